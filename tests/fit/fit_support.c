/* What the fit's tests share (fit_support.h). */
#define _POSIX_C_SOURCE 200809L
#include "fit_support.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "support/check.h"

void fit_test_synth_options(cf_synth_options *o, cf_model_id model, const double *params) {
  cf_synth_default_options(o);
  o->model = model;
  memcpy(o->params, params, sizeof o->params);
  o->images = 8;
  o->width = 240;
  o->height = 180;
  o->focal_px = 290.0;
  o->format = CF_SYNTH_EXR;
  o->supersample = 1;
}

int fit_test_make_dir(char *dir, size_t size) {
  snprintf(dir, size, "/tmp/clayfit-fit-test-XXXXXX");
  if (mkdtemp(dir)) return 1;
  perror("mkdtemp");
  return 0;
}

void fit_test_remove_dir(const char *dir) {
  char command[600];
  snprintf(command, sizeof command, "rm -rf '%s'", dir);
  if (system(command) != 0) fprintf(stderr, "could not remove %s\n", dir);
}

cf_capture *fit_test_capture(const char *dir, const char *name, const cf_synth_options *o) {
  char folder[512], path[600];
  snprintf(folder, sizeof folder, "%s/%s", dir, name);
  cf_error err = {0};
  cf_status s = cf_synth_write(folder, o, &err);
  CHECK(s == CF_OK, "%s: synth: %s", name, err.message);
  if (s != CF_OK) return NULL;
  snprintf(path, sizeof path, "%s/capture.json", folder);
  cf_capture *capture = NULL;
  s = cf_capture_load(path, NULL, &capture, &err);
  CHECK(s == CF_OK, "%s: load: %s", name, err.message);
  return s == CF_OK ? capture : NULL;
}

double fit_test_error(cf_model_id model, int k, double fitted, double truth) {
  const cf_model_info *m = cf_model_info_get(model);
  const cf_param_info *info = NULL;
  for (int j = 0; j < m->param_count; ++j)
    if (k >= m->offsets[j]) info = cf_param_info_get(m->params[j]);
  return fabs(fitted - truth) / fmax(fabs(truth), info->upper - info->lower);
}
