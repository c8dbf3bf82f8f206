/* Fixtures for the "accepted but wrong" tests (issue 16, items 7 and 8;
 * tests/fit/unusable.cmake runs `clayfit fit` on each): in DIR, the issue's
 * capture (`clayfit synth --images 4 --size 160x120 --format exr`: M4,
 * noise) once as rendered and once per case, each changed in one way:
 *   zero_intensity   the flash's intensity 0 0 0
 *   light_inside     a point light inside the sphere instead of the flash
 *   flash_inside     the flash 4.5 in front of the camera: 0.5 from the
 *                    sphere's centre
 *   black_level      colour.black_level 1
 *   blue_unlit       the flash's intensity 39.27 39.27 0: no data move the
 *                    blue albedo
 *   negative_patch   a 10 x 10 pixel patch of -0.5 on the sphere in 000.exr
 *                    (100 of 17 376 observations: 0.58 %)
 *   huge_patch       the same patch at 1e38
 *   patch_no_noise_model  the patch in a capture without a noise model (the
 *                    noise's scale then comes from the image)
 * usage: make_unusable_captures DIR */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clayfit/image.h"
#include "clayfit/synth.h"
#include "core/file.h"

static int fail(const char *what, const cf_error *err) {
  fprintf(stderr, "make_unusable_captures: %s: %s\n", what, err ? err->message : "");
  return 1;
}

static int synth(const char *root, const char *name, char *out, size_t size) {
  snprintf(out, size, "%s/%s", root, name);
  cf_synth_options o;
  cf_synth_default_options(&o);
  o.images = 4;
  o.width = 160;
  o.height = 120;
  o.focal_px = 192.0; /* synth's default: 1.2 times the width */
  o.format = CF_SYNTH_EXR;
  cf_error err = {0};
  return cf_synth_write(out, &o, &err) == CF_OK ? 0 : fail(name, &err);
}

/* In DIR/capture.json, replace the JSON value that follows `key` (an
 * array or an object, up to its matching bracket; or a string) by `to`;
 * with_key: the key as well. */
static int replace(const char *dir, const char *key, const char *to, int with_key) {
  char path[4096], *text = NULL;
  size_t size = 0;
  cf_error err = {0};
  snprintf(path, sizeof path, "%s/capture.json", dir);
  if (cf_read_file(path, 1 << 24, &text, &size, &err) != CF_OK) return fail(path, &err);
  char *at = strstr(text, key), *end = NULL, *start = at;
  if (at) at += strlen(key);
  while (at && *at == ' ') ++at;
  if (at && *at == '"') {
    end = strchr(at + 1, '"');
    if (end) ++end;
  } else if (at && (*at == '[' || *at == '{')) {
    int depth = 0;
    for (end = at; *end; ++end) {
      depth += *end == '[' || *end == '{';
      depth -= *end == ']' || *end == '}';
      if (depth == 0) break;
    }
    if (*end) ++end;
  }
  if (!at || !end) {
    free(text);
    return fail(key, NULL);
  }
  if (!with_key) start = at;
  size_t head = (size_t)(start - text), tail = size - (size_t)(end - text), middle = strlen(to);
  char *edited = malloc(head + middle + tail + 1);
  if (!edited) {
    free(text);
    return fail("out of memory", NULL);
  }
  memcpy(edited, text, head);
  memcpy(edited + head, to, middle);
  memcpy(edited + head + middle, end, tail);
  cf_status s = cf_write_file(path, edited, head + middle + tail, &err);
  free(text);
  free(edited);
  return s == CF_OK ? 0 : fail(path, &err);
}

static int replace_value(const char *dir, const char *key, const char *to) {
  return replace(dir, key, to, 0);
}

/* Set a 10 x 10 pixel patch of 000.exr (on the sphere: its centre is at
 * about (80, 60), radius 38 px) to `value` in every channel. */
static int patch(const char *dir, float value) {
  char path[4200];
  cf_image image = {0};
  cf_error err = {0};
  snprintf(path, sizeof path, "%s/images/000.exr", dir);
  if (cf_image_read(path, &image, NULL, &err) != CF_OK) return fail(path, &err);
  for (int y = 50; y < 60; ++y)
    for (int x = 70; x < 80; ++x)
      for (int c = 0; c < image.channels; ++c)
        image.pixels[((size_t)y * (size_t)image.width + (size_t)x) * (size_t)image.channels +
                     (size_t)c] = value;
  cf_status s = cf_image_write(path, &image, 32, &err);
  cf_image_free(&image);
  return s == CF_OK ? 0 : fail(path, &err);
}

int main(int argc, char **argv) {
  if (argc != 2) return 2;
  const char *root = argv[1];
  cf_error err = {0};
  char command[4200], dir[4096];
  snprintf(command, sizeof command, "rm -rf '%s'", root); /* start from nothing */
  if (system(command) != 0 || cf_make_dirs(root, &err) != CF_OK) return fail(root, &err);

  if (synth(root, "rendered", dir, sizeof dir)) return 1;
  if (synth(root, "zero_intensity", dir, sizeof dir) ||
      replace_value(dir, "\"intensity\":", "[0, 0, 0]"))
    return 1;
  if (synth(root, "light_inside", dir, sizeof dir) ||
      replace_value(
          dir, "\"lights\":",
          "[{\"type\": \"point\", \"position\": [0, 0, 0.2], \"intensity\": [40, 40, 40]}]"))
    return 1;
  if (synth(root, "flash_inside", dir, sizeof dir) ||
      replace_value(dir, "\"offset\":", "[0, 0, 4.5]"))
    return 1;
  if (synth(root, "black_level", dir, sizeof dir) ||
      replace_value(dir, "\"colour\":", "{\"encoding\": \"linear\", \"black_level\": 1}"))
    return 1;
  if (synth(root, "blue_unlit", dir, sizeof dir) ||
      replace_value(dir, "\"intensity\":", "[39.27, 39.27, 0]"))
    return 1;
  if (synth(root, "negative_patch", dir, sizeof dir) || patch(dir, -0.5f)) return 1;
  if (synth(root, "huge_patch", dir, sizeof dir) || patch(dir, 1e38f)) return 1;
  if (synth(root, "patch_no_noise_model", dir, sizeof dir) || patch(dir, -0.5f) ||
      replace(dir, ",\n  \"noise\":", "", 1))
    return 1;
  printf("make_unusable_captures: 9 captures in %s\n", root);
  return 0;
}
