/* On noise-free synthetic captures (clayfit synth: float EXR, true poses
 * and sphere, one sample per pixel as the fit assumes) of every model of
 * the ladder, with parameters inside their ranges (optical depth below 1,
 * roughness where the highlight spans a few pixels), the fit from its
 * default start recovers every parameter to within 1e-4 of
 * max(|truth|, the range's width). */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "clayfit/capture.h"
#include "clayfit/fit.h"
#include "fit_support.h"
#include "support/check.h"

CHECK_MAIN_STATE;

static const double tolerance = 1e-4;

typedef struct truth_case {
  cf_model_id model;
  double params[CF_MAX_DIM];
} truth_case;

static const truth_case cases[] = {
    {CF_MODEL_LAMBERT, {0.7, 0.45, 0.3}},
    {CF_MODEL_OREN_NAYAR, {0.7, 0.45, 0.3, 0.4}},
    {CF_MODEL_DIELECTRIC, {0.6, 0.4, 0.3, 0.3, 0.3, 0.05}},
    {CF_MODEL_CLEARCOAT, {0.6, 0.4, 0.3, 0.3, 0.45, 0.04, 0.6, 0.5}},
    {CF_MODEL_CLAY, {0.7, 0.45, 0.3, 0.3, 0.2, 0.03, 0.1, 0.3, 0.6, 0.6, 0.01}},
    {CF_MODEL_DIELECTRIC_TAILED, {0.6, 0.4, 0.3, 0.3, 0.3, 0.05, 1.8}},
    {CF_MODEL_CLAY_TAILED, {0.7, 0.45, 0.3, 0.3, 0.2, 0.03, 0.1, 0.3, 0.6, 0.6, 0.01, 3.0}},
};

static double elapsed(const struct timespec *t0) {
  struct timespec t1;
  clock_gettime(CLOCK_MONOTONIC, &t1);
  return (double)(t1.tv_sec - t0->tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0->tv_nsec);
}

static void recover(const truth_case *c, const char *dir) {
  const cf_model_info *m = cf_model_info_get(c->model);
  cf_synth_options o;
  fit_test_synth_options(&o, c->model, c->params);
  o.read_noise = o.shot_noise = 0.0;
  cf_capture *capture = fit_test_capture(dir, m->code, &o);
  if (!capture) return;
  cf_error err = {0};
  cf_fit_options options;
  fit_test_fit_options(&options, c->model, o.supersample);
  cf_fit_result r;
  struct timespec t0;
  clock_gettime(CLOCK_MONOTONIC, &t0);
  cf_status s = cf_fit_run(capture, &options, &r, &err);
  double seconds = elapsed(&t0);
  CHECK(s == CF_OK, "%s fit: %s", m->code, err.message);
  if (s == CF_OK) {
    double worst = 0.0;
    int worst_slot = 0;
    for (int j = 0; j < m->param_count; ++j) {
      const cf_param_info *info = cf_param_info_get(m->params[j]);
      for (int k = m->offsets[j]; k < m->offsets[j] + info->components; ++k) {
        double error = cf_model_slot_error(c->model, k, r.params[k], c->params[k]);
        char name[48];
        CHECK(error <= tolerance && r.status[k] == CF_PARAM_FITTED,
              "%s %s: fitted %.9g, truth %.9g (error %.3g of its scale; %s)", m->code,
              cf_model_slot_name(c->model, k, name, sizeof name), r.params[k], c->params[k], error,
              cf_param_status_name(r.status[k]));
        if (error > worst) worst = error, worst_slot = k;
      }
    }
    char name[48];
    printf("%s %-10s: %zu observations, %d starts, fit in %.2f s; worst error %.3g of "
           "max(|truth|, range) (%s), relative RMSE %.3g\n",
           m->code, m->name, cf_capture_observations(capture)->count, r.starts, seconds, worst,
           cf_model_slot_name(c->model, worst_slot, name, sizeof name), r.relative_rmse);
    cf_fit_result_free(&r);
  }
  cf_capture_free(capture);
}

int main(void) {
  char dir[64];
  if (!fit_test_make_dir(dir, sizeof dir)) return 1;
  printf("tolerance: %.0e of max(|truth|, range width)\n", tolerance);
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) recover(&cases[i], dir);
  fit_test_remove_dir(dir);
  return check_finish("test_fit_recovery");
}
