/* Pixel footprints (docs/model.md §5.6): an M2 sphere about 120
 * pixels across with roughness 0.08 (α = 0.0064: the highlight's lobe is
 * narrower than a pixel, across which the normal turns by about 0.017 rad),
 * noise-free.
 *   same integration  rendered with 4 × 4 samples per pixel and fitted with
 *                     4 × 4 (--footprint 4): every parameter recovered to
 *                     1e-4 of max(|truth|, range width), as test_fit_recovery
 *                     asks of pixel-centre captures;
 *   adaptive          rendered with 16 × 16 samples (close to the exact
 *                     integral) and fitted with the default adaptive
 *                     footprint: within 1e-3, and at least 5 times closer
 *                     than the pixel-centre fit, whose bias is what the
 *                     integration removes. */
#include <math.h>
#include <stdio.h>

#include "fit_support.h"
#include "support/check.h"

CHECK_MAIN_STATE;

static const double truth[CF_MAX_DIM] = {0.6, 0.4, 0.3, 0.3, 0.08, 0.05};

/* Fit with the footprint `footprint` (cf_fit_options); the worst error
 * over the parameters, or NaN on an error (CHECKed). */
static double worst_error(const char *name, cf_capture *capture, int footprint) {
  const cf_model_info *m = cf_model_info_get(CF_MODEL_DIELECTRIC);
  cf_fit_options o;
  fit_test_fit_options(&o, CF_MODEL_DIELECTRIC, footprint);
  cf_fit_result r;
  cf_error err = {0};
  cf_status s = cf_fit_run(capture, &o, &r, &err);
  CHECK(s == CF_OK, "%s: %s", name, err.message);
  if (s != CF_OK) return NAN;
  double worst = 0.0;
  int worst_slot = 0;
  for (int k = 0; k < m->dim; ++k) {
    double error = cf_model_slot_error(CF_MODEL_DIELECTRIC, k, r.params[k], truth[k]);
    CHECK(isfinite(error), "%s: slot %d = %g", name, k, r.params[k]);
    if (error > worst) worst = error, worst_slot = k;
  }
  char slot[48];
  printf(
      "%-22s footprint %-6s: worst error %.3g (%s = %.7g, truth %.7g); %zu observations "
      "integrated, %zu samples, S up to %d; relative RMSE %.3g; %.2f s\n",
      name,
      footprint == 0   ? "auto"
      : footprint == 1 ? "centre"
                       : "fixed",
      worst, cf_model_slot_name(CF_MODEL_DIELECTRIC, worst_slot, slot, sizeof slot),
      r.params[worst_slot], truth[worst_slot], r.footprint_observations, r.footprint_samples,
      r.footprint_max, r.relative_rmse,
      r.stage_seconds[0] + r.stage_seconds[1] + r.stage_seconds[2] + r.stage_seconds[3]);
  if (footprint == 0)
    CHECK(r.footprint_max > 1 && r.footprint_observations > 0 &&
              r.footprint_observations < cf_capture_observations(capture)->count / 2,
          "%s: adaptive integration of %zu of %zu observations, S up to %d", name,
          r.footprint_observations, cf_capture_observations(capture)->count, r.footprint_max);
  cf_fit_result_free(&r);
  return worst;
}

static cf_capture *render(const char *dir, const char *name, int supersample) {
  cf_synth_options so;
  fit_test_synth_options(&so, CF_MODEL_DIELECTRIC, truth);
  so.read_noise = so.shot_noise = 0.0;
  so.supersample = supersample;
  return fit_test_capture(dir, name, &so);
}

int main(void) {
  char dir[64];
  if (!fit_test_make_dir(dir, sizeof dir)) return 1;
  cf_capture *four = render(dir, "s4", 4);
  if (four) {
    double same = worst_error("rendered 4x4", four, 4);
    CHECK(same <= 1e-4, "the same integration: worst error %.3g > 1e-4", same);
    double centre = worst_error("rendered 4x4", four, 1);
    CHECK(centre > 1e-3, "pixel centres should be biased here: worst error %.3g", centre);
    cf_capture_free(four);
  }
  cf_capture *fine = render(dir, "s16", 16);
  if (fine) {
    double adaptive = worst_error("rendered 16x16", fine, 0);
    double centre = worst_error("rendered 16x16", fine, 1);
    CHECK(adaptive <= 1e-3, "adaptive: worst error %.3g > 1e-3", adaptive);
    CHECK(5.0 * adaptive < centre, "adaptive %.3g is not 5 times better than centres %.3g",
          adaptive, centre);
    cf_capture_free(fine);
  }
  fit_test_remove_dir(dir);
  return check_finish("test_fit_footprint");
}
