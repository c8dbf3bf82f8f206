/* A calibration check of the reported uncertainty: M2 fitted to noisy
 * synthetic captures (the default noise, which the capture file states)
 * over SEEDS seeds; every fitted parameter should fall within two reported
 * standard deviations of the truth in about 95 % of cases. The observed
 * rate is printed, with the same for one σ (about 68 %). The cases within
 * a seed are correlated, so the rate's spread is wider than a binomial's:
 * the test asserts 0.88 <= rate and that not every case falls inside (a
 * reported σ far too large would pass a one-sided check).
 *
 * With arguments BUDGET SAMPLING the fits use that pixel budget, drawn
 * uniform, stratified or importance: the same coverage must then hold for
 * the sample's standard deviations (the sandwich of the weighted fit). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fit_support.h"
#include "support/check.h"

CHECK_MAIN_STATE;

enum { SEEDS = 24 };

static const double truth[CF_MAX_DIM] = {0.6, 0.4, 0.3, 0.3, 0.3, 0.05};

int main(int argc, char **argv) {
  size_t budget = 0;
  cf_sampling sampling = CF_SAMPLING_STRATIFIED;
  if (argc == 3) {
    budget = (size_t)strtoul(argv[1], NULL, 10);
    int found = 0;
    for (int k = 0; k < CF_SAMPLING_COUNT; ++k)
      if (strcmp(argv[2], cf_sampling_name((cf_sampling)k)) == 0)
        sampling = (cf_sampling)k, found = 1;
    if (budget == 0 || !found) {
      fprintf(stderr, "usage: test_fit_calibration [BUDGET uniform|stratified|importance]\n");
      return 2;
    }
  }
  char dir[64];
  if (!fit_test_make_dir(dir, sizeof dir)) return 1;
  const cf_model_info *m = cf_model_info_get(CF_MODEL_DIELECTRIC);
  int within1[CF_MAX_DIM] = {0}, within2[CF_MAX_DIM] = {0}, fits = 0;
  double z2[CF_MAX_DIM] = {0}, worst_ratio = 0.0;
  for (int seed = 1; seed <= SEEDS; ++seed) {
    cf_synth_options so;
    fit_test_synth_options(&so, CF_MODEL_DIELECTRIC, truth);
    so.images = 4;
    so.width = 160;
    so.height = 120;
    so.focal_px = 220.0;
    so.seed = (uint64_t)seed;
    char name[32];
    snprintf(name, sizeof name, "seed%d", seed);
    cf_capture *capture = fit_test_capture(dir, name, &so);
    if (!capture) continue;
    cf_fit_options o;
    fit_test_fit_options(&o, CF_MODEL_DIELECTRIC, 1);
    o.budget = budget;
    o.sampling = sampling;
    cf_fit_result r;
    cf_error err = {0};
    cf_status s = cf_fit_run(capture, &o, &r, &err);
    CHECK(s == CF_OK, "seed %d: %s", seed, err.message);
    if (s == CF_OK && budget > 0)
      CHECK(r.sample_count > 0 && r.sample_count <= budget + 2 &&
                r.population_count > 4 * r.sample_count,
            "seed %d: a budget of %zu drew %zu of %zu observations", seed, budget, r.sample_count,
            r.population_count);
    if (s == CF_OK && budget > 0) { /* the weighted sample's RMSE estimates every one's */
      cf_fit_result all;
      cf_status e = cf_fit_evaluate(capture, &r, NULL, &o, &all, &err);
      CHECK(e == CF_OK, "seed %d: %s", seed, err.message);
      if (e == CF_OK) {
        double ratio = r.relative_rmse / all.relative_rmse;
        worst_ratio = fmax(worst_ratio, fabs(log(ratio)));
        CHECK(fabs(ratio - 1.0) < 0.1, "seed %d: relative RMSE %.4g estimated, %.4g on all", seed,
              r.relative_rmse, all.relative_rmse);
        cf_fit_result_free(&all);
      }
    }
    if (s == CF_OK) {
      ++fits;
      for (int k = 0; k < m->dim; ++k) {
        CHECK(r.status[k] == CF_PARAM_FITTED && r.sd[k] > 0.0, "seed %d slot %d: %s, sd %g", seed,
              k, cf_param_status_name(r.status[k]), r.sd[k]);
        double z = (r.params[k] - truth[k]) / r.sd[k];
        within1[k] += fabs(z) <= 1.0;
        within2[k] += fabs(z) <= 2.0;
        z2[k] += z * z;
      }
      cf_fit_result_free(&r);
    }
    cf_capture_free(capture);
    fit_test_remove_dir(dir);
    if (!fit_test_make_dir(dir, sizeof dir)) return 1;
  }
  fit_test_remove_dir(dir);
  int total1 = 0, total2 = 0;
  printf("%d fits of M2 (4 images of 160 x 120, default noise", fits);
  if (budget > 0) printf("; a budget of %zu observations, %s", budget, cf_sampling_name(sampling));
  printf("), per parameter:\n");
  for (int k = 0; k < m->dim; ++k) {
    char name[48];
    printf("  %-18s within 1 sd %2d/%d, within 2 sd %2d/%d, rms z %.3f\n",
           cf_model_slot_name(CF_MODEL_DIELECTRIC, k, name, sizeof name), within1[k], fits,
           within2[k], fits, fits ? sqrt(z2[k] / fits) : NAN);
    total1 += within1[k];
    total2 += within2[k];
  }
  int cases = fits * m->dim;
  double rate1 = cases ? (double)total1 / cases : 0.0, rate2 = cases ? (double)total2 / cases : 0.0;
  printf(
      "observed coverage: %.1f %% within 1 sd (nominal 68.3 %%), %.1f %% within 2 sd "
      "(nominal 95.4 %%), over %d cases\n",
      100.0 * rate1, 100.0 * rate2, cases);
  if (budget > 0)
    printf(
        "relative RMSE estimated from the sample against every observation's: within a "
        "factor %.4f\n",
        exp(worst_ratio));
  CHECK(fits >= 20, "only %d fits", fits);
  CHECK(rate2 >= 0.88, "2-sd coverage %.3f is below 0.88: the reported sd is too small", rate2);
  CHECK(rate2 < 1.0 || cases < 60, "every case within 2 sd: the reported sd may be too large");
  CHECK(rate1 >= 0.5 && rate1 <= 0.85, "1-sd coverage %.3f is far from 0.683", rate1);
  return check_finish("test_fit_calibration");
}
