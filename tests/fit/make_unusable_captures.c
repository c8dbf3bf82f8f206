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
 *   bright_patch     the patch at 1e6 in each of the four images (issue 30,
 *                    item 6): 2.3 % of each image's pixels on the sphere,
 *                    3.3 times what any material can reflect under the flash
 *                    there (with the margin), far below 1e9 times the bright
 *                    level
 *   faint_flash      the flash's intensity 1e-12 (issue 30, item 7)
 *   faintest_flash   the flash's intensity 1e-300
 *   environment      lit by a uniform map of radiance 0.5 (environment.exr,
 *                    64 x 32) instead of the flash, as rendered
 *   faint_environment  the same, the map's texels then set to 1e-44
 *   dark             rendered under a flash of intensity 1e-12: the photos
 *                    hold only the noise, and so does the model's brightest
 *   faintest_relative  the flash's intensity 1e-300, radiometry relative
 *                    (the scale free: no bound from the lights at loading)
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

/* ROOT/NAME from the options, lit by `environment` (a map's path)
 * instead of the flash when not NULL, the flash's intensity `flash` when
 * not 0. */
static int synth_lit(const char *root, const char *name, const char *environment, double flash,
                     char *out, size_t size) {
  snprintf(out, size, "%s/%s", root, name);
  cf_synth_options o;
  cf_synth_default_options(&o);
  o.images = 4;
  o.width = 160;
  o.height = 120;
  o.focal_px = 192.0; /* synth's default: 1.2 times the width */
  o.format = CF_SYNTH_EXR;
  if (environment) o.environment = environment, o.environment_lights = 64;
  o.flash_intensity = flash;
  cf_error err = {0};
  return cf_synth_write(out, &o, &err) == CF_OK ? 0 : fail(name, &err);
}

static int synth(const char *root, const char *name, char *out, size_t size) {
  return synth_lit(root, name, NULL, 0.0, out, size);
}

/* A 64 x 32 float map of `value` in every channel at `path`. */
static int uniform_map(const char *path, float value) {
  cf_image map = {0};
  cf_error err = {0};
  if (cf_image_alloc(&map, 64, 32, 3, &err) != CF_OK) return fail(path, &err);
  for (size_t i = 0; i < (size_t)64 * 32 * 3; ++i) map.pixels[i] = value;
  cf_status s = cf_image_write(path, &map, 32, &err);
  cf_image_free(&map);
  return s == CF_OK ? 0 : fail(path, &err);
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

/* Set a 10 x 10 pixel patch of image `name` (on the sphere: its centre is
 * at about (80, 60), radius 38 px) to `value` in every channel. */
static int patch_image(const char *dir, const char *name, float value) {
  char path[4200];
  cf_image image = {0};
  cf_error err = {0};
  snprintf(path, sizeof path, "%s/images/%s", dir, name);
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

static int patch(const char *dir, float value) {
  return patch_image(dir, "000.exr", value);
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
  if (synth(root, "bright_patch", dir, sizeof dir) || patch_image(dir, "000.exr", 1e6f) ||
      patch_image(dir, "001.exr", 1e6f) || patch_image(dir, "002.exr", 1e6f) ||
      patch_image(dir, "003.exr", 1e6f))
    return 1;
  if (synth(root, "faint_flash", dir, sizeof dir) ||
      replace_value(dir, "\"intensity\":", "[1e-12, 1e-12, 1e-12]"))
    return 1;
  if (synth(root, "faintest_flash", dir, sizeof dir) ||
      replace_value(dir, "\"intensity\":", "[1e-300, 1e-300, 1e-300]"))
    return 1;
  char map[4200];
  snprintf(map, sizeof map, "%s/environment.exr", root);
  if (uniform_map(map, 0.5f) || synth_lit(root, "environment", map, 0.0, dir, sizeof dir) ||
      synth_lit(root, "faint_environment", map, 0.0, dir, sizeof dir))
    return 1;
  snprintf(map, sizeof map, "%s/faint_environment/environment.exr", root);
  if (uniform_map(map, 1e-44f) || replace_value(dir, "\"file\":", "\"environment.exr\"")) return 1;
  if (synth_lit(root, "dark", NULL, 1e-12, dir, sizeof dir)) return 1;
  if (synth(root, "faintest_relative", dir, sizeof dir) ||
      replace_value(dir, "\"intensity\":", "[1e-300, 1e-300, 1e-300]") ||
      replace_value(dir, "\"radiometry\":", "\"relative\""))
    return 1;
  printf("make_unusable_captures: 16 captures in %s\n", root);
  return 0;
}
