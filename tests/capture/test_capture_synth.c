/* The capture pipeline end to end on a synthetic capture: clayfit synth
 * renders an exact scene (float EXR, no noise, one sample per pixel), the
 * capture loader reads it back through COLMAP's text model, OpenImageIO,
 * the sphere and the flash, and every observation must equal docs/model.md's
 * image formation (5) L = f(n, l, v) E c_i at its pixel centre. This checks the
 * poses, the camera model, the ray-sphere geometry, the flash's position,
 * the decoding and the lights all at once. Then, with 3 x 3 samples per
 * pixel, the observations differ from the centre value only by the
 * footprint's averaging (reported). */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clayfit/capture.h"
#include "clayfit/synth.h"
#include "support/check.h"

CHECK_MAIN_STATE;

typedef struct comparison {
  size_t observations, lit;
  double worst_relative, mean_relative;
} comparison;

/* Compare each observation with f E c_i at its pixel centre. */
static comparison compare(const cf_capture *capture, const cf_synth_options *o) {
  const cf_observations *obs = cf_capture_observations(capture);
  comparison r = {obs->count, 0, 0.0, 0.0};
  for (size_t i = 0; i < obs->count; ++i) {
    const double *n = obs->normal + 3 * i, *v = obs->view + 3 * i;
    const double *l = obs->light_dir + 3 * i, *e = obs->irradiance + 3 * i;
    double f[3], cos_i = n[0] * l[0] + n[1] * l[1] + n[2] * l[2];
    cf_eval(o->model, o->params, n, l, v, f, NULL);
    r.lit += cos_i > 0.0;
    for (int c = 0; c < 3; ++c) {
      double predicted = cos_i > 0.0 ? f[c] * e[c] * cos_i : 0.0;
      double relative = fabs(obs->rgb[3 * i + c] - predicted) / fmax(predicted, 1e-3);
      r.worst_relative = fmax(r.worst_relative, relative);
      r.mean_relative += relative / (3.0 * (double)obs->count);
    }
  }
  return r;
}

static void check_geometry(const cf_capture *capture) {
  const cf_observations *obs = cf_capture_observations(capture);
  double worst_unit = 0.0;
  size_t facing = 0;
  for (size_t i = 0; i < obs->count; ++i) {
    const double *n = obs->normal + 3 * i, *v = obs->view + 3 * i;
    worst_unit = fmax(worst_unit, fabs(sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) - 1.0));
    worst_unit = fmax(worst_unit, fabs(sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) - 1.0));
    facing += n[0] * v[0] + n[1] * v[1] + n[2] * v[2] > 0.0;
  }
  CHECK(worst_unit < 1e-12, "normals and views are unit vectors (worst %.3g)", worst_unit);
  CHECK(facing == obs->count, "%zu of %zu observations face the camera", facing, obs->count);
  /* each image's adjacent_turn: the largest angle between the normals of
   * horizontally adjacent pixels, here by acos */
  size_t images = cf_capture_image_count(capture);
  double largest[4] = {0.0, 0.0, 0.0, 0.0};
  for (size_t i = 0; i + 1 < obs->count && images <= 4; ++i) {
    if (obs->image[i] != obs->image[i + 1] || obs->pixel[2 * i + 1] != obs->pixel[2 * i + 3] ||
        obs->pixel[2 * i + 2] != obs->pixel[2 * i] + 1.0f)
      continue;
    const double *a = obs->normal + 3 * i, *b = a + 3;
    double turn = acos(fmin(1.0, a[0] * b[0] + a[1] * b[1] + a[2] * b[2]));
    largest[obs->image[i]] = fmax(largest[obs->image[i]], turn);
  }
  for (size_t k = 0; k < images && images <= 4; ++k) {
    double turn = cf_capture_image_at(capture, k)->adjacent_turn;
    CHECK(largest[k] > 0.0 && fabs(turn - largest[k]) < 1e-6 * largest[k],
          "image %zu: adjacent_turn %.9g, the largest turn between adjacent normals %.9g", k, turn,
          largest[k]);
  }
}

static int run(const char *dir, int supersample, comparison *result) {
  cf_synth_options o;
  cf_synth_default_options(&o);
  o.images = 4;
  o.width = 200;
  o.height = 150;
  o.focal_px = 240.0;
  o.format = CF_SYNTH_EXR;
  o.read_noise = o.shot_noise = 0.0;
  o.supersample = supersample;
  /* a wet clay with a broad base lobe and a distinct film */
  double *p = o.params;
  p[CF_CLAY_ALBEDO + 0] = 0.7, p[CF_CLAY_ALBEDO + 1] = 0.45, p[CF_CLAY_ALBEDO + 2] = 0.3;
  p[CF_CLAY_DIFFUSE_ROUGHNESS] = 0.3;
  p[CF_CLAY_FILM_ROUGHNESS] = 0.35, p[CF_CLAY_FILM_F0] = 0.03;
  p[CF_CLAY_OPTICAL_DEPTH + 0] = 0.1, p[CF_CLAY_OPTICAL_DEPTH + 1] = 0.3;
  p[CF_CLAY_OPTICAL_DEPTH + 2] = 0.6;
  p[CF_CLAY_BASE_ROUGHNESS] = 0.6, p[CF_CLAY_BASE_F0] = 0.01;
  cf_error err = {0};
  CHECK(cf_synth_write(dir, &o, &err) == CF_OK, "synth: %s", err.message);
  if (err.status != CF_OK) return 0;
  char path[4096];
  snprintf(path, sizeof path, "%s/capture.json", dir);
  cf_capture *capture = NULL;
  CHECK(cf_capture_load(path, NULL, &capture, &err) == CF_OK, "load: %s", err.message);
  if (!capture) return 0;
  *result = compare(capture, &o);
  check_geometry(capture);
  /* every image sees the whole sphere: a disc of radius f tan(asin(1/5)) */
  double radius_px = o.focal_px * tan(asin(1.0 / o.distance));
  for (size_t k = 0; k < cf_capture_image_count(capture); ++k) {
    const cf_capture_image *im = cf_capture_image_at(capture, k);
    double expected = 3.14159265358979 * radius_px * radius_px;
    CHECK(fabs((double)im->sphere_pixels - expected) < 0.02 * expected,
          "image %zu: %zu sphere pixels, expected about %.0f", k, im->sphere_pixels, expected);
    CHECK(im->observations < im->sphere_pixels && im->observations > 0.85 * im->sphere_pixels,
          "image %zu: %zu observations of %zu sphere pixels (the 2 px margin)", k, im->observations,
          im->sphere_pixels);
    CHECK(im->clipped == 0, "image %zu: float images have no clip level", k);
  }
  cf_capture_free(capture);
  return 1;
}

int main(void) {
  char dir1[] = "/tmp/clayfit-synth-XXXXXX", dir3[] = "/tmp/clayfit-synth-XXXXXX";
  if (!mkdtemp(dir1) || !mkdtemp(dir3)) {
    perror("mkdtemp");
    return 1;
  }
  comparison one = {0}, three = {0};
  if (run(dir1, 1, &one)) {
    printf(
        "1 sample per pixel: %zu observations (%zu lit); worst relative difference from "
        "f E c_i at the pixel centre %.3g, mean %.3g\n",
        one.observations, one.lit, one.worst_relative, one.mean_relative);
    /* float32 storage: 6e-8 relative */
    CHECK(one.worst_relative < 1e-6, "observations equal the image formation (worst %.3g)",
          one.worst_relative);
    CHECK(one.lit == one.observations, "the flash lights every visible point");
  }
  if (run(dir3, 3, &three)) {
    printf(
        "3 x 3 samples per pixel: worst relative difference from the centre value %.3g, "
        "mean %.3g (the footprint's averaging)\n",
        three.worst_relative, three.mean_relative);
    CHECK(three.mean_relative < 0.01 && three.worst_relative > one.worst_relative,
          "supersampling changes values a little (mean %.3g)", three.mean_relative);
  }
  char command[8300];
  snprintf(command, sizeof command, "rm -rf '%s' '%s'", dir1, dir3);
  if (system(command) != 0) fprintf(stderr, "could not remove %s, %s\n", dir1, dir3);
  return check_finish("test_capture_synth");
}
