/* An environment light in a capture file: a small equirectangular EXR with
 * a bright patch and two negative values, reduced to K directional
 * lights: every observation carries K light slots, the lights' irradiance
 * adds up to the map's Σ L dω, and the negative values are clamped to 0
 * with a warning naming the file. The same map with a NaN is refused,
 * naming the file, the texel and the channel. With the real HDRIs (../shared/data/hdri,
 * when present), their known negative values are reported likewise. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clayfit/capture.h"
#include "core/file.h"
#include "ortho_scene.h"
#include "support/check.h"

CHECK_MAIN_STATE;

enum { MAP_W = 64, MAP_H = 32, K = 8 };
static char dir[] = "/tmp/clayfit-environment-XXXXXX";

static void write_capture(const char *map, int count) {
  char path[4096];
  snprintf(path, sizeof path, "%s/capture.json", dir);
  FILE *f = fopen(path, "w");
  if (!f) return;
  fprintf(f,
          "{\"clayfit_capture\": 1, \"camera\": {\"type\": \"orthographic\"},"
          " \"images\": {\"files\": [\"photo.exr\"]}, \"colour\": {\"encoding\": \"linear\"},"
          " \"geometry\": {\"type\": \"normal_map\", \"file\": \"normals.exr\"},"
          " \"lights\": [{\"type\": \"environment\", \"file\": \"%s\", \"count\": %d}]}",
          map, count);
  fclose(f);
}

static cf_capture *load(void) {
  char path[4096];
  snprintf(path, sizeof path, "%s/capture.json", dir);
  cf_capture *capture = NULL;
  cf_error err = {0};
  CHECK(cf_capture_load(path, NULL, &capture, &err) == CF_OK, "%s", err.message);
  return capture;
}

/* Σ over the lights of one observation's irradiance, per channel. */
static void light_total(const cf_observations *o, double total[3]) {
  total[0] = total[1] = total[2] = 0.0;
  for (int j = 0; j < o->lights; ++j)
    for (int c = 0; c < 3; ++c) total[c] += o->irradiance[3 * j + c];
}

int main(int argc, char **argv) {
  if (!mkdtemp(dir)) {
    perror("mkdtemp");
    return 1;
  }
  cf_image normals = {0}, photo = {0}, map = {0};
  cf_error err = {0};
  const double up[3] = {0.0, 0.0, 1.0};
  CHECK(cf_image_alloc(&normals, ORTHO_SIZE, ORTHO_SIZE, 3, &err) == CF_OK, "alloc");
  CHECK(cf_image_alloc(&photo, ORTHO_SIZE, ORTHO_SIZE, 3, &err) == CF_OK, "alloc");
  CHECK(cf_image_alloc(&map, MAP_W, MAP_H, 3, &err) == CF_OK, "alloc");
  ortho_scene(&normals, &photo, up);
  /* a dim sky, a bright patch, two negative values; the map's
   * Σ L dω with dω = (2π/W)(π/H) sin θ */
  double expected[3] = {0.0, 0.0, 0.0};
  for (int y = 0; y < MAP_H; ++y)
    for (int x = 0; x < MAP_W; ++x) {
      float *p = map.pixels + 3 * (y * MAP_W + x);
      double value = (x >= 10 && x < 13 && y >= 8 && y < 10) ? 50.0 : 0.2;
      for (int c = 0; c < 3; ++c) p[c] = (float)value;
      double theta = 3.14159265358979 * (y + 0.5) / MAP_H;
      double d_omega = (2.0 * 3.14159265358979 / MAP_W) * (3.14159265358979 / MAP_H) * sin(theta);
      for (int c = 0; c < 3; ++c)
        expected[c] += (x == 40 && y == 20) || (x == 41 && y == 20) ? 0.0 : p[c] * d_omega;
    }
  map.pixels[3 * (20 * MAP_W + 40)] = -7.0f;
  map.pixels[3 * (20 * MAP_W + 41) + 1] = -0.5f;
  /* the clamped pixels count 0 in their bad channel only */
  {
    double theta = 3.14159265358979 * 20.5 / MAP_H;
    double d_omega = (2.0 * 3.14159265358979 / MAP_W) * (3.14159265358979 / MAP_H) * sin(theta);
    expected[1] += 0.2 * d_omega, expected[2] += 0.2 * d_omega; /* pixel 40: r clamped */
    expected[0] += 0.2 * d_omega, expected[2] += 0.2 * d_omega; /* pixel 41: g clamped */
  }
  char path[4096];
  snprintf(path, sizeof path, "%s/normals.exr", dir);
  CHECK(cf_image_write(path, &normals, 32, &err) == CF_OK, "%s", err.message);
  snprintf(path, sizeof path, "%s/photo.exr", dir);
  CHECK(cf_image_write(path, &photo, 32, &err) == CF_OK, "%s", err.message);
  snprintf(path, sizeof path, "%s/sky.exr", dir);
  CHECK(cf_image_write(path, &map, 32, &err) == CF_OK, "%s", err.message);
  map.pixels[3 * (21 * MAP_W + 5) + 2] = strtof("nan", NULL);
  snprintf(path, sizeof path, "%s/nan.exr", dir);
  CHECK(cf_image_write(path, &map, 32, &err) == CF_OK, "%s", err.message);
  cf_image_free(&normals);
  cf_image_free(&photo);
  cf_image_free(&map);

  write_capture("sky.exr", K);
  cf_capture *capture = load();
  if (capture) {
    const cf_observations *o = cf_capture_observations(capture);
    double total[3];
    light_total(o, total);
    printf("%d lights from the map: irradiance %.6g %.6g %.6g, the map's %.6g %.6g %.6g\n",
           o->lights, total[0], total[1], total[2], expected[0], expected[1], expected[2]);
    CHECK(o->lights == K && o->count > 0, "K light slots per observation: %d", o->lights);
    for (int c = 0; c < 3; ++c)
      CHECK(fabs(total[c] - expected[c]) < 1e-6 * expected[c], "channel %d total", c);
    const char *warning = cf_capture_warning(capture, 0);
    printf("warning: %s\n", warning ? warning : "(none)");
    CHECK(warning && strstr(warning, "sky.exr") && strstr(warning, "2 negative values clamped"),
          "the clamped values are reported");
    cf_capture_free(capture);
  }
  /* a NaN: refused, not clamped */
  write_capture("nan.exr", K);
  {
    snprintf(path, sizeof path, "%s/capture.json", dir);
    cf_capture *refused = NULL;
    cf_status s = cf_capture_load(path, NULL, &refused, &err);
    printf("with a NaN: %s\n", err.message);
    CHECK(s == CF_EINVAL && strstr(err.message, "nan.exr: environment map: 1 non-finite value") &&
              strstr(err.message, "NaN at texel (5, 21)") && strstr(err.message, "channel 2 (B)"),
          "a NaN in the map is refused: %s", err.message);
    cf_capture_free(refused);
  }

  /* the real HDRIs, when present */
  /* the capture file names the maps; relative paths there start from its
   * own folder, so make the data folder absolute */
  char shared_buffer[4096] = "";
  const char *shared = argc > 1 && realpath(argv[1], shared_buffer) ? shared_buffer : "/absent";
  static const char *const names[] = {"studio", "city", "sunset", "forest"};
  for (int i = 0; i < 4; ++i) {
    char hdri[4096];
    snprintf(hdri, sizeof hdri, "%s/hdri/%s.exr", shared, names[i]);
    if (!cf_path_exists(hdri)) {
      printf("%s is absent: skipped\n", hdri);
      continue;
    }
    write_capture(hdri, 32);
    capture = load();
    if (!capture) continue;
    const char *warning = cf_capture_warning(capture, 0);
    printf("%s with 32 lights: %s\n", names[i], warning ? warning + strlen(shared) : "no warning");
    CHECK(cf_capture_observations(capture)->lights == 32, "32 lights");
    CHECK(warning && strstr(warning, "clamped to 0"), "the map's negative values are reported");
    cf_capture_free(capture);
  }
  char command[4200];
  snprintf(command, sizeof command, "rm -rf '%s'", dir);
  if (system(command) != 0) fprintf(stderr, "could not remove %s\n", dir);
  return check_finish("test_capture_environment");
}
