/* Fixtures for the capture's bad-input tests: in DIR, one small synthetic
 * capture per case, each broken in one way (tests/capture/capture.cmake
 * runs `clayfit inspect` on each and checks the message and exit status):
 *   missing_image     an image file deleted
 *   wrong_size        an image replaced by one of another size
 *   truncated_bin     the model in binary, images.bin cut short
 *   unknown_camera    cameras.txt names a camera model COLMAP lacks
 *   nan_exr           a NaN in one image
 *   wrong_type        the capture file: lights is an object
 *   missing_field     the capture file: the colour block deleted
 *   unseen_sphere     the sphere behind every camera
 *   missing_mask      one mask for every image, its file absent
 *   mask_size         one mask for every image, of another size
 * usage: make_bad_captures DIR */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clayfit/colmap.h"
#include "clayfit/image.h"
#include "clayfit/synth.h"
#include "core/file.h"

static int fail(const char *what, const cf_error *err) {
  fprintf(stderr, "make_bad_captures: %s: %s\n", what, err ? err->message : "");
  return 1;
}

static int synth(const char *dir, const char *name, char *out, size_t size) {
  snprintf(out, size, "%s/%s", dir, name);
  cf_synth_options o;
  cf_synth_default_options(&o);
  o.images = 2;
  o.width = 96;
  o.height = 72;
  o.focal_px = 115.2;
  o.format = CF_SYNTH_EXR;
  o.supersample = 1;
  cf_error err = {0};
  return cf_synth_write(out, &o, &err) == CF_OK ? 0 : fail(name, &err);
}

/* Replace `from` by `to` once in a text file. */
static int edit(const char *dir, const char *file, const char *from, const char *to) {
  char path[4096], *text = NULL;
  size_t size = 0;
  cf_error err = {0};
  snprintf(path, sizeof path, "%s/%s", dir, file);
  if (cf_read_file(path, 1 << 24, &text, &size, &err) != CF_OK) return fail(path, &err);
  char *at = strstr(text, from);
  if (!at) {
    free(text);
    return fail(path, NULL);
  }
  FILE *f = fopen(path, "w");
  if (!f) {
    free(text);
    return fail(path, NULL);
  }
  fwrite(text, 1, (size_t)(at - text), f);
  fputs(to, f);
  fputs(at + strlen(from), f);
  fclose(f);
  free(text);
  return 0;
}

int main(int argc, char **argv) {
  if (argc != 2) return 2;
  const char *root = argv[1];
  cf_error err = {0};
  char command[4200];
  snprintf(command, sizeof command, "rm -rf '%s'", root); /* start from nothing */
  if (system(command) != 0 || cf_make_dirs(root, &err) != CF_OK) return fail(root, &err);
  char dir[4096], path[4200];

  if (synth(root, "missing_image", dir, sizeof dir)) return 1;
  snprintf(path, sizeof path, "%s/images/001.exr", dir);
  if (remove(path) != 0) return fail(path, NULL);

  if (synth(root, "wrong_size", dir, sizeof dir)) return 1;
  cf_image small = {0};
  snprintf(path, sizeof path, "%s/images/001.exr", dir);
  if (cf_image_alloc(&small, 80, 60, 3, &err) != CF_OK || cf_image_write(path, &small, 32, &err))
    return fail(path, &err);
  cf_image_free(&small);

  if (synth(root, "truncated_bin", dir, sizeof dir)) return 1;
  cf_colmap_model model = {0};
  snprintf(path, sizeof path, "%s/sparse/0", dir);
  if (cf_colmap_read(path, 1, &model, &err) != CF_OK || cf_colmap_write_binary(path, &model, &err))
    return fail(path, &err);
  cf_colmap_model_free(&model);
  char *bin = NULL;
  size_t size = 0;
  snprintf(path, sizeof path, "%s/sparse/0/images.bin", dir);
  if (cf_read_file(path, 1 << 20, &bin, &size, &err) != CF_OK ||
      cf_write_file(path, bin, size / 2, &err) != CF_OK)
    return fail(path, &err);
  free(bin);

  if (synth(root, "unknown_camera", dir, sizeof dir)) return 1;
  if (edit(dir, "sparse/0/cameras.txt", " PINHOLE ", " PINHOLE_WITH_WOBBLE ")) return 1;

  if (synth(root, "nan_exr", dir, sizeof dir)) return 1;
  cf_image image = {0};
  snprintf(path, sizeof path, "%s/images/000.exr", dir);
  if (cf_image_read(path, &image, NULL, &err) != CF_OK) return fail(path, &err);
  image.pixels[3 * (10 * 96 + 20) + 1] = strtof("nan", NULL);
  if (cf_image_write(path, &image, 32, &err) != CF_OK) return fail(path, &err);
  cf_image_free(&image);

  if (synth(root, "wrong_type", dir, sizeof dir)) return 1;
  if (edit(dir, "capture.json", "\"lights\": [", "\"lights\": {\"x\": [")) return 1;
  if (edit(dir, "capture.json", "  ],\n  \"noise\"", "  ]},\n  \"noise\"")) return 1;

  if (synth(root, "missing_field", dir, sizeof dir)) return 1;
  if (edit(dir, "capture.json", "  \"colour\": {\n    \"encoding\": \"linear\"\n  },\n", ""))
    return 1;

  if (synth(root, "unseen_sphere", dir, sizeof dir)) return 1;
  if (edit(dir, "capture.json", "\"center\": [\n      0.0,\n      0.0,\n      0.0",
           "\"center\": [\n      0.0,\n      0.0,\n      -40.0"))
    return 1;
  if (synth(root, "missing_mask", dir, sizeof dir)) return 1;
  if (edit(dir, "capture.json", "\"directory\": \"images\",",
           "\"directory\": \"images\", \"mask\": \"nope.png\","))
    return 1;

  if (synth(root, "mask_size", dir, sizeof dir)) return 1;
  if (edit(dir, "capture.json", "\"directory\": \"images\",",
           "\"directory\": \"images\", \"mask\": \"mask.png\","))
    return 1;
  cf_image mask = {0};
  snprintf(path, sizeof path, "%s/mask.png", dir);
  if (cf_image_alloc(&mask, 80, 60, 1, &err) != CF_OK || cf_image_write(path, &mask, 8, &err))
    return fail(path, &err);
  cf_image_free(&mask);
  printf("make_bad_captures: 10 broken captures in %s\n", root);
  return 0;
}
