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

int fit_test_render(const char *dir, const char *name, const cf_synth_options *o, char *folder,
                    size_t size) {
  snprintf(folder, size, "%s/%s", dir, name);
  cf_error err = {0};
  cf_status s = cf_synth_write(folder, o, &err);
  CHECK(s == CF_OK, "%s: synth: %s", name, err.message);
  return s == CF_OK;
}

cf_capture *fit_test_load(const char *folder) {
  char path[600];
  snprintf(path, sizeof path, "%s/capture.json", folder);
  cf_capture *capture = NULL;
  cf_error err = {0};
  cf_status s = cf_capture_load(path, NULL, &capture, &err);
  CHECK(s == CF_OK, "%s: load: %s", folder, err.message);
  return s == CF_OK ? capture : NULL;
}

cf_capture *fit_test_capture(const char *dir, const char *name, const cf_synth_options *o) {
  char folder[512];
  return fit_test_render(dir, name, o, folder, sizeof folder) ? fit_test_load(folder) : NULL;
}

int fit_test_edit_images(const char *folder, const char *sub, int images, int bits,
                         fit_test_image_edit edit, void *user) {
  for (int k = 0; k < images; ++k) {
    char path[600];
    snprintf(path, sizeof path, "%s/%s/%03d.exr", folder, sub, k);
    cf_image image = {0};
    cf_error err = {0};
    cf_status s = cf_image_read(path, &image, NULL, &err);
    if (s == CF_OK) {
      edit(&image, k, user);
      s = cf_image_write(path, &image, bits, &err);
    }
    cf_image_free(&image);
    CHECK(s == CF_OK, "%s", err.message);
    if (s != CF_OK) return 0;
  }
  return 1;
}

int fit_test_edit_text(const char *folder, const char *file, const char *from, const char *to) {
  char path[600];
  snprintf(path, sizeof path, "%s/%s", folder, file);
  FILE *f = fopen(path, "rb");
  char text[1 << 16];
  size_t n = f ? fread(text, 1, sizeof text - 1, f) : 0;
  if (f) fclose(f);
  text[n] = '\0';
  char *at = strstr(text, from);
  CHECK(at != NULL && n < sizeof text - 1, "%s: '%s' not found", path, from);
  if (!at) return 0;
  f = fopen(path, "wb");
  int ok = f && fwrite(text, 1, (size_t)(at - text), f) == (size_t)(at - text) &&
           fputs(to, f) >= 0 && fputs(at + strlen(from), f) >= 0;
  if (f) ok &= fclose(f) == 0;
  CHECK(ok, "%s: could not write", path);
  return ok;
}

void fit_test_fit_options(cf_fit_options *o, cf_model_id model, int supersample) {
  cf_fit_default_options(o, model);
  o->footprint = supersample;
}
