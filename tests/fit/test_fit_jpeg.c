/* JPEG captures end to end: synth writes 8-bit JPEGs (quality 90, 4:2:0)
 * whose EXIF exposure time, ISO and f-number vary per image, with the
 * photos scaled to match, and a capture that says "exposure": "exif";
 * M2 fitted to it.
 *
 * Without arguments (label fit): one capture. The capture's exposures are
 * the EXIF's (truth.json's e_k); the fitted material is within 2 sd of the
 * truth; the same photos declared without exposures fit clearly worse
 * (the EXIF path carries weight).
 *
 * With "sweep" (label slow): SEEDS captures, each with its own noise seed
 * and image size (so that the JPEG block grid falls differently on the
 * sphere: with one size every seed repeats the same coding errors), and
 * the fraction of (value − truth) / sd within ±2 over every fitted slot.
 * JPEG's errors are correlated within its blocks, so the sds come from the
 * tile sandwich (fit_tile_covariance); before it (clip level 1, margin 2,
 * sds from JᵀJ) 7 of 60 (12 %) were within 2 sd (docs/model.md).
 * "sweep-large" does the same at 320 × 240, a sphere of about 80 px, where
 * the codec's own bias is larger than the sds: without its model
 * (--jpeg-plain, fit_jpeg.h) 38–55 % were within 2 sd. */
#define _POSIX_C_SOURCE 200809L
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fit_support.h"
#include "support/check.h"

CHECK_MAIN_STATE;

enum { SEEDS = 24, LARGE_SEEDS = 12 };

/* albedo, diffuse roughness, roughness, F0 */
static const double truth[CF_MAX_DIM] = {0.6, 0.4, 0.3, 0.3, 0.3, 0.05};

static void jpeg_options(cf_synth_options *so, int seed, int width, int height) {
  fit_test_synth_options(so, CF_MODEL_DIELECTRIC, truth);
  so->images = 4;
  so->width = width + 2 * (seed % 8);
  so->height = height + 2 * (seed % 5);
  so->focal_px = 1.2 * so->width;
  so->format = CF_SYNTH_JPEG;
  so->exif_exposures = 1;
  so->seed = (uint64_t)seed;
}

/* Fit M2 to folder/capture.json (plain: the JPEG coding not modelled); 1
 * on success. */
static int fit_folder(const char *folder, int plain, cf_fit_result *r) {
  cf_capture *capture = fit_test_load(folder);
  if (!capture) return 0;
  cf_fit_options o;
  fit_test_fit_options(&o, CF_MODEL_DIELECTRIC, 1);
  o.jpeg_plain = plain;
  cf_error err = {0};
  cf_status s = cf_fit_run(capture, &o, r, &err);
  CHECK(s == CF_OK, "%s: %s", folder, err.message);
  cf_capture_free(capture);
  return s == CF_OK;
}

/* Slots within 2 sd of the truth (every slot fitted, sd > 0). */
static int within_two_sd(const cf_fit_result *r, const char *what, int *cases) {
  const cf_model_info *m = cf_model_info_get(CF_MODEL_DIELECTRIC);
  int inside = 0;
  for (int k = 0; k < m->dim; ++k) {
    char name[48];
    cf_model_slot_name(CF_MODEL_DIELECTRIC, k, name, sizeof name);
    CHECK(r->status[k] == CF_PARAM_FITTED && r->sd[k] > 0.0, "%s %s: %s, sd %g", what, name,
          cf_param_status_name(r->status[k]), r->sd[k]);
    double z = (r->params[k] - truth[k]) / r->sd[k];
    printf("  %s %-18s %.5f ± %.5f (truth %.3f, z %+.2f)\n", what, name, r->params[k], r->sd[k],
           truth[k], z);
    inside += fabs(z) <= 2.0;
  }
  *cases = m->dim;
  return inside;
}

/* The capture's exposures are those of the EXIF (truth.json's). */
static void check_exposures(const char *folder) {
  char path[600];
  snprintf(path, sizeof path, "%s/truth.json", folder);
  json_error_t error;
  json_t *doc = json_load_file(path, 0, &error);
  CHECK(doc != NULL, "%s: %s", path, error.text);
  cf_capture *capture = fit_test_load(folder);
  const json_t *exposures = json_object_get(doc, "exposures");
  for (size_t k = 0; capture && k < cf_capture_image_count(capture); ++k) {
    double loaded = cf_capture_image_at(capture, k)->exposure;
    double expected = json_real_value(json_array_get(exposures, k));
    CHECK(fabs(loaded / expected - 1.0) < 1e-5 && fabs(expected - 1.0) > 0.05,
          "image %zu: exposure %.6f from EXIF, truth %.6f", k, loaded, expected);
  }
  cf_capture_free(capture);
  json_decref(doc);
}

/* A JPEG whose mask leaves it no observation: the capture warns, and the
 * fit models the coding of the other images (it failed: "the images
 * chosen have no observations"). */
static void check_empty_image(const char *dir) {
  cf_synth_options so;
  jpeg_options(&so, 2, 160, 120);
  so.write_masks = 1;
  char folder[512], path[600];
  if (!fit_test_render(dir, "empty", &so, folder, sizeof folder)) return;
  snprintf(path, sizeof path, "%s/masks/000.jpg", folder);
  cf_image blank = {0};
  cf_error err = {0};
  cf_status s = cf_image_alloc(&blank, so.width, so.height, 1, &err);
  if (s == CF_OK) s = cf_image_write(path, &blank, 8, &err);
  cf_image_free(&blank);
  CHECK(s == CF_OK, "%s", err.message);
  cf_fit_result r;
  if (s == CF_OK && fit_folder(folder, 0, &r)) {
    CHECK(r.jpeg_images == 3, "the coding modelled in %d images, 3 with observations",
          r.jpeg_images);
    cf_fit_result_free(&r);
  }
}

static int end_to_end(const char *dir) {
  cf_synth_options so;
  jpeg_options(&so, 1, 160, 120);
  char folder[512];
  if (!fit_test_render(dir, "jpeg", &so, folder, sizeof folder)) return 1;
  check_exposures(folder);
  cf_fit_result r, none;
  int cases = 0;
  if (fit_folder(folder, 0, &r)) {
    int inside = within_two_sd(&r, "exif", &cases);
    CHECK(inside == cases, "%d of %d slots within 2 sd of the truth", inside, cases);
    /* the tables of quality 90 were found, the codec's error modelled */
    const cf_capture_image *image = NULL;
    cf_capture *capture = fit_test_load(folder);
    if (capture) image = cf_capture_image_at(capture, 0);
    CHECK(image && image->jpeg_quality == 90 && image->jpeg_exact &&
              image->jpeg_chroma == CF_CHROMA_420,
          "the JPEG's coding: quality %d (exact %d), chroma %d", image ? image->jpeg_quality : -1,
          image ? image->jpeg_exact : -1, image ? image->jpeg_chroma : -1);
    cf_capture_free(capture);
    printf("JPEG coding modelled in %d images: bias rms %.3f codes, mean %+.3f %+.3f %+.3f\n",
           r.jpeg_images, r.jpeg_bias_rms, r.jpeg_bias_mean[0], r.jpeg_bias_mean[1],
           r.jpeg_bias_mean[2]);
    CHECK(r.jpeg_images == 4 && r.jpeg_bias_rms > 0.0 && r.jpeg_bias_rms < 5.0,
          "the JPEG coding modelled in %d images, bias rms %g codes", r.jpeg_images,
          r.jpeg_bias_rms);
    printf("relative RMSE %.4f with the EXIF exposures\n", r.relative_rmse);
    /* the same photos without their exposures */
    if (fit_test_edit_text(folder, "capture.json", "\"exif\"", "\"none\"") &&
        fit_folder(folder, 0, &none)) {
      printf("relative RMSE %.4f without them\n", none.relative_rmse);
      CHECK(none.relative_rmse > 3.0 * r.relative_rmse,
            "ignoring the EXIF exposures costs: relative RMSE %.4f against %.4f",
            none.relative_rmse, r.relative_rmse);
      cf_fit_result_free(&none);
    }
    cf_fit_result_free(&r);
  }
  check_empty_image(dir);
  return check_finish("test_fit_jpeg");
}

/* The 2-sd coverage of `seeds` captures of about width × height, fitted
 * with the JPEG coding modelled or (plain) not, into *rate; the number of
 * fits. */
static int coverage(const char *dir, int seeds, int width, int height, int plain, double *rate) {
  int inside = 0, cases = 0, fits = 0;
  for (int seed = 1; seed <= seeds; ++seed) {
    cf_synth_options so;
    jpeg_options(&so, seed, width, height);
    char name[32], folder[512], what[32];
    snprintf(name, sizeof name, "seed%d", seed);
    snprintf(what, sizeof what, "seed %2d", seed);
    cf_fit_result r;
    if (!fit_test_render(dir, name, &so, folder, sizeof folder) || !fit_folder(folder, plain, &r))
      continue;
    int n = 0;
    inside += within_two_sd(&r, what, &n);
    cases += n;
    ++fits;
    cf_fit_result_free(&r);
    fit_test_remove_dir(folder);
  }
  *rate = cases ? (double)inside / cases : 0.0;
  printf(
      "JPEG (quality 90, 4:2:0, EXIF exposures, about %d x %d, coding %s), %d fits of M2: %d "
      "of %d slots within 2 sd (%.1f %%, nominal 95.4 %%)\n",
      width, height, plain ? "not modelled" : "modelled", fits, inside, cases, 100.0 * *rate);
  return fits;
}

static int sweep(const char *dir, int large) {
  int seeds = large ? LARGE_SEEDS : SEEDS;
  double rate, plain_rate = 0.0;
  int fits =
      large ? coverage(dir, seeds, 320, 240, 0, &rate) : coverage(dir, seeds, 160, 120, 0, &rate);
  CHECK(fits == seeds, "only %d of %d fits", fits, seeds);
  CHECK(rate >= 0.8, "2-sd coverage %.3f is below 0.8: the JPEG sds are too small", rate);
  CHECK(rate < 1.0, "every slot within 2 sd: the sds may be too large");
  if (large) { /* what the model of the coding is for */
    coverage(dir, seeds, 320, 240, 1, &plain_rate);
    CHECK(plain_rate < rate, "coverage %.3f without the coding's model, %.3f with it", plain_rate,
          rate);
  } else { /* printed, for docs/model.md's table */
    coverage(dir, seeds, 160, 120, 1, &plain_rate);
  }
  return check_finish(large ? "test_fit_jpeg sweep-large" : "test_fit_jpeg sweep");
}

int main(int argc, char **argv) {
  char dir[64];
  if (!fit_test_make_dir(dir, sizeof dir)) return 1;
  int status = argc > 1 && strcmp(argv[1], "sweep") == 0         ? sweep(dir, 0)
               : argc > 1 && strcmp(argv[1], "sweep-large") == 0 ? sweep(dir, 1)
                                                                 : end_to_end(dir);
  fit_test_remove_dir(dir);
  return status;
}
