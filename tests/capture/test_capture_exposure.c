/* colour.exposure "exif": two photos of one scene, the second exposed twice
 * as long (EXIF) and so twice as bright, must give the same radiance once
 * decoded, with exposures e_k = 1/√2 and √2 (their geometric mean is the
 * reference, 1); a photo without EXIF is refused, naming the file. An
 * orthographic capture with a normal map and a directional light keeps the
 * scene exact. The photos are 8-bit sRGB JPEGs, as cameras write them (and
 * the one format whose EXIF OpenImageIO 2.4 writes whole: its TIFF and EXR
 * writers drop the ISO), so the comparison allows for JPEG's loss. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clayfit/capture.h"
#include "clayfit/image.h"
#include "ortho_scene.h"
#include "support/check.h"

CHECK_MAIN_STATE;

enum { SIZE = ORTHO_SIZE };
static char dir[] = "/tmp/clayfit-exposure-XXXXXX";

static void write_scene(void) {
  cf_image normals = {0}, photo = {0};
  cf_error err = {0};
  CHECK(cf_image_alloc(&normals, SIZE, SIZE, 3, &err) == CF_OK, "%s", err.message);
  CHECK(cf_image_alloc(&photo, SIZE, SIZE, 3, &err) == CF_OK, "%s", err.message);
  const double l[3] = {0.3, 0.2, 0.93};
  ortho_scene(&normals, &photo, l);
  char path[256];
  snprintf(path, sizeof path, "%s/normals.exr", dir);
  CHECK(cf_image_write(path, &normals, 32, &err) == CF_OK, "%s", err.message);
  /* a: 1/100 s; b: 1/50 s and twice the radiance; c: no EXIF */
  cf_image encoded = {0};
  CHECK(cf_image_alloc(&encoded, SIZE, SIZE, 3, &err) == CF_OK, "%s", err.message);
  cf_image_info info = {"", 8, 0, 0.01, 4.0, 100.0};
  const char *names[3] = {"a.jpg", "c.jpg", "b.jpg"};
  for (int k = 0; k < 3; ++k) {
    double gain = k == 2 ? 2.0 : 1.0;
    for (size_t i = 0; i < 3 * SIZE * SIZE; ++i)
      encoded.pixels[i] = (float)cf_linear_to_srgb(gain * photo.pixels[i]);
    info.exposure_time = 0.01 * gain;
    snprintf(path, sizeof path, "%s/%s", dir, names[k]);
    cf_status s = k == 1 ? cf_image_write(path, &encoded, 8, &err)
                         : cf_image_write_with_info(path, &encoded, 8, &info, &err);
    CHECK(s == CF_OK, "%s", err.message);
  }
  cf_image_free(&encoded);
  cf_image_free(&normals);
  cf_image_free(&photo);
}

static void write_capture(const char *name, const char *files) {
  char path[256];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE *f = fopen(path, "w");
  if (!f) return;
  fprintf(f,
          "{\"clayfit_capture\": 1, \"camera\": {\"type\": \"orthographic\"},"
          " \"images\": {\"files\": [%s]},"
          " \"colour\": {\"encoding\": \"srgb\", \"exposure\": \"exif\"},"
          " \"geometry\": {\"type\": \"normal_map\", \"file\": \"normals.exr\", \"margin_px\": 1},"
          " \"lights\": [{\"type\": \"directional\", \"direction\": [0.3, 0.2, 0.93],"
          " \"irradiance\": [1, 1, 1]}]}",
          files);
  fclose(f);
}

int main(void) {
  if (!mkdtemp(dir)) {
    perror("mkdtemp");
    return 1;
  }
  write_scene();
  write_capture("pair.json", "\"a.jpg\", \"b.jpg\"");
  write_capture("no_exif.json", "\"a.jpg\", \"c.jpg\"");
  char path[256];
  cf_error err = {0};
  cf_capture *capture = NULL;
  snprintf(path, sizeof path, "%s/pair.json", dir);
  CHECK(cf_capture_load(path, NULL, &capture, &err) == CF_OK, "%s", err.message);
  if (capture) {
    double ea = cf_capture_image_at(capture, 0)->exposure;
    double eb = cf_capture_image_at(capture, 1)->exposure;
    printf("exposures from EXIF (1/100 s and 1/50 s, f/4, ISO 100): %.6f and %.6f\n", ea, eb);
    CHECK(fabs(ea - sqrt(0.5)) < 1e-3 && fabs(eb - sqrt(2.0)) < 1e-3,
          "e = 1/sqrt 2 and sqrt 2 (EXIF stores the time as a fraction)");
    const cf_observations *o = cf_capture_observations(capture);
    size_t half = o->count / 2;
    CHECK(o->count % 2 == 0 && half > 500, "both images give the same pixels: %zu", o->count);
    double sum_a = 0.0, sum_b = 0.0;
    for (size_t i = 0; i < half; ++i)
      for (int c = 0; c < 3; ++c) {
        sum_a += o->rgb[3 * i + c];
        sum_b += o->rgb[3 * (half + i) + c];
      }
    double ratio = sum_b / sum_a;
    printf(
        "the two photos after decoding: mean radiance ratio %.5f (1 when the exposures are "
        "right, 2 or 0.5 when not)\n",
        ratio);
    CHECK(fabs(ratio - 1.0) < 0.01, "the same radiance from both photos (ratio %.5f)", ratio);
    cf_capture_free(capture);
  }
  snprintf(path, sizeof path, "%s/no_exif.json", dir);
  CHECK(cf_capture_load(path, NULL, &capture, &err) == CF_ENOTFOUND, "no EXIF refused");
  CHECK(strstr(err.message, "c.jpg") && strstr(err.message, "exposure time"), "message: %s",
        err.message);
  printf("without EXIF: %s\n", strstr(err.message, "c.jpg") ? strstr(err.message, "c.jpg") : "");
  char command[300];
  snprintf(command, sizeof command, "rm -rf '%s'", dir);
  if (system(command) != 0) fprintf(stderr, "could not remove %s\n", dir);
  return check_finish("test_capture_exposure");
}
