/* Writes the seed corpus of fuzz_image (scripts/fuzz.sh, and the test
 * fuzz_inputs_image): tiny images in every format and sample type clayfit
 * writes (cf_image_write), each as one seed file DIR/NAME: the selector
 * byte of fuzz_image.cpp (the extension's index), then the file's bytes.
 * DIR is made if needed.
 *   make_image_seeds DIR */
#ifndef _DEFAULT_SOURCE
#define _DEFAULT_SOURCE
#endif
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "clayfit/image.h"
#include "core/file.h"

/* fuzz_image.cpp's extensions, in the order of its selector byte. */
static const char *const extensions[6] = {"png", "exr", "tif", "jpg", "hdr", "pfm"};

typedef struct seed {
  int extension; /* index into extensions */
  int bits, channels, width, height, with_info, special;
} seed;

static void fill(cf_image *image, int special) {
  size_t n = (size_t)image->width * (size_t)image->height * (size_t)image->channels;
  for (size_t i = 0; i < n; ++i) image->pixels[i] = (float)((i * 37) % 101) / 100.0f;
  if (special) { /* float formats: a negative value, a large one, a NaN */
    image->pixels[0] = -0.5f;
    image->pixels[1] = 1e30f;
    image->pixels[n - 1] = NAN;
  }
}

static int write_seed(const char *dir, const seed *s, cf_error *err) {
  char image_path[4096], seed_path[4096];
  snprintf(image_path, sizeof image_path, "%s/image.%s", dir, extensions[s->extension]);
  snprintf(seed_path, sizeof seed_path, "%s/%s-%d-%dx%dx%d%s%s", dir, extensions[s->extension],
           s->bits, s->width, s->height, s->channels, s->with_info ? "-exif" : "",
           s->special ? "-special" : "");
  cf_image image = {0};
  if (cf_image_alloc(&image, s->width, s->height, s->channels, err) != CF_OK) return 1;
  fill(&image, s->special);
  cf_image_info info = {"", 0, 0, 1.0 / 125.0, 5.6, 200.0};
  cf_status status = s->with_info
                         ? cf_image_write_with_info(image_path, &image, s->bits, &info, err)
                         : cf_image_write(image_path, &image, s->bits, err);
  cf_image_free(&image);
  char *bytes = NULL;
  size_t size = 0;
  if (status == CF_OK) status = cf_read_file(image_path, 1 << 20, &bytes, &size, err);
  remove(image_path);
  if (status != CF_OK) return 1;
  FILE *file = fopen(seed_path, "wb");
  int ok = file && fputc(s->extension, file) != EOF && fwrite(bytes, 1, size, file) == size;
  ok = file && fclose(file) == 0 && ok;
  free(bytes);
  if (!ok) cf_error_set(err, CF_EIO, "%s: could not write", seed_path);
  return !ok;
}

int main(int argc, char **argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: make_image_seeds DIR\n");
    return 2;
  }
  static const seed seeds[] = {
      {0, 8, 1, 3, 2, 0, 0},  {0, 8, 2, 2, 2, 0, 0},  {0, 8, 3, 4, 3, 0, 0},
      {0, 16, 3, 3, 2, 0, 0}, {0, 16, 4, 2, 3, 0, 0}, {1, 16, 3, 3, 2, 0, 0},
      {1, 32, 1, 2, 2, 0, 1}, {1, 32, 4, 3, 2, 1, 0}, {1, 16, 3, 4, 1, 0, 1},
      {2, 8, 3, 3, 2, 1, 0},  {2, 16, 1, 2, 2, 0, 0}, {2, 16, 4, 3, 3, 0, 0},
      {3, 8, 3, 8, 8, 1, 0},  {3, 8, 1, 4, 4, 0, 0},  {4, 32, 3, 3, 2, 0, 0},
      {5, 32, 3, 3, 2, 0, 1}, {5, 32, 1, 2, 3, 0, 0},
  };
  mkdir(argv[1], 0777); /* or it exists: the seeds' writes say */
  /* a format that cannot be written only loses its seeds (the writers have
   * their own tests); no seed at all is a failure */
  size_t written = 0;
  for (size_t k = 0; k < sizeof seeds / sizeof seeds[0]; ++k) {
    cf_error err = {0};
    if (write_seed(argv[1], &seeds[k], &err) == 0)
      ++written;
    else
      fprintf(stderr, "make_image_seeds: skipped: %s\n", err.message);
  }
  return written ? 0 : 1;
}
