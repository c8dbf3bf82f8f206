/* libFuzzer target for the text files of a capture (built and run by
 * scripts/fuzz.sh): the image list ("images": {"list": ...}, read by
 * capture_spec.c) and the per-image light directions and intensities
 * (DiLiGenT's light_directions.txt and light_intensities.txt, read by
 * capture_lights.c). The bytes are split at the lines "%%" into the list,
 * the directions and the intensities; a fixed capture.json names the three
 * files, and the capture's lights are loaded from them (capture_load_lights
 * on a capture holding only the spec: no image is read). Besides crashes
 * and sanitizer reports, a broken promise aborts: a failure names the file;
 * a success gives every image one directional light with a unit direction
 * and a finite, non-negative irradiance. */
#ifndef _DEFAULT_SOURCE
#define _DEFAULT_SOURCE
#endif
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "capture/capture_internal.h"
#include "fuzz_files.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static const char capture_json[] =
    "{\"clayfit_capture\": 1, \"camera\": {\"type\": \"orthographic\"},"
    " \"images\": {\"list\": \"list.txt\"}, \"colour\": {\"encoding\": \"linear\"},"
    " \"geometry\": {\"type\": \"sphere_from_silhouettes\"},"
    " \"lights\": [{\"type\": \"directional_per_image\", \"directions\": \"directions.txt\","
    " \"intensities\": \"intensities.txt\"}]}";

/* The next part of data: up to the line "%%" (exclusive) or the end. */
static size_t next_part(const uint8_t *data, size_t size, size_t *skip) {
  for (size_t i = 0; i + 2 <= size; ++i)
    if ((i == 0 || data[i - 1] == '\n') && data[i] == '%' && data[i + 1] == '%' &&
        (i + 2 == size || data[i + 2] == '\n')) {
      *skip = i + 2 < size ? 3 : 2;
      return i;
    }
  *skip = 0;
  return size;
}

static int names_a_file(const char *message) {
  return strstr(message, "list.txt") || strstr(message, "directions.txt") ||
         strstr(message, "intensities.txt") || strstr(message, "out of memory");
}

static void check_lights(const cf_capture *c) {
  fuzz_require(c->max_lights == 1 && c->lights && c->light_counts, "one light slot per image", "");
  for (size_t k = 0; k < c->spec.num_images; ++k) {
    const cf_light *l = &c->lights[k];
    double n = sqrt(l->direction[0] * l->direction[0] + l->direction[1] * l->direction[1] +
                    l->direction[2] * l->direction[2]);
    fuzz_require(c->light_counts[k] == 1 && l->kind == CF_LIGHT_DIRECTIONAL,
                 "one directional light per image", "");
    fuzz_require(fabs(n - 1.0) < 1e-9, "a unit light direction", "");
    for (int ch = 0; ch < 3; ++ch)
      fuzz_require(isfinite(l->intensity[ch]) && l->intensity[ch] >= 0.0,
                   "a finite, non-negative irradiance", "");
  }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  static const char *const names[3] = {"list.txt", "directions.txt", "intensities.txt"};
  char path[4096];
  size_t offset = 0;
  for (int k = 0; k < 3; ++k) {
    size_t skip, n = next_part(data + offset, size - offset, &skip);
    fuzz_write(names[k], data + offset, n, path);
    offset += n + skip;
  }
  fuzz_write_text("capture.json", capture_json, path);

  cf_capture capture;
  memset(&capture, 0, sizeof capture);
  cf_error err = {0};
  cf_status s = cf_capture_spec_read(path, &capture.spec, &err);
  if (s == CF_OK) {
    capture.images = calloc(capture.spec.num_images, sizeof *capture.images);
    fuzz_require(capture.images != NULL, "memory for the images", "");
    s = capture_load_lights(&capture, &err);
    if (s == CF_OK) check_lights(&capture);
  }
  if (s != CF_OK)
    fuzz_require(err.status == s && names_a_file(err.message), "a failure names the file",
                 err.message);
  free(capture.lights);
  free(capture.light_counts);
  free(capture.images);
  for (size_t i = 0; i < capture.num_warnings; ++i) free(capture.warnings[i]);
  free(capture.warnings);
  cf_capture_spec_free(&capture.spec);
  return 0;
}
