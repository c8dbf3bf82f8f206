/* The report's 8-bit sRGB encoding from its table (report_images.c)
 * against the direct way through the PNG writer: cf_linear_to_srgb of the
 * value clamped to [0, 1], written with cf_image_write and read back. At
 * every step of the encoding (the least value of each code and the float
 * below it), at values outside [0, 1] and NaN, and at a million floats in
 * [0, 1] spread over their bit patterns. Usage: test_report_srgb DIR */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "clayfit/image.h"
#include "report_internal.h"

enum { WIDTH = 1000, HEIGHT = 336 }; /* 1008000 values */

static float float_of(uint32_t bits) {
  float x;
  memcpy(&x, &bits, sizeof x);
  return x;
}

/* The values: every step and the float below it, the odd ones, then
 * pseudorandom bit patterns of floats in [0, 1]. */
static void fill(const report_srgb *t, float *x, size_t n) {
  static const float odd[] = {0.0f, -0.0f, -1.0f, 1.0f, 1.5f, 1e30f, -1e-30f, 1e-45f, 0.5f};
  size_t m = 0;
  for (int q = 1; q < 256; ++q) {
    x[m++] = t->threshold[q];
    x[m++] = nextafterf(t->threshold[q], 0.0f);
  }
  for (size_t k = 0; k < sizeof odd / sizeof *odd; ++k) x[m++] = odd[k];
  x[m++] = NAN;
  x[m++] = INFINITY;
  x[m++] = -INFINITY;
  uint64_t state = 0x9e3779b97f4a7c15u;
  while (m < n) {
    state = state * 6364136223846793005u + 1442695040888963407u;
    x[m++] = float_of((uint32_t)(state >> 33) % 0x3f800001u); /* 0 .. 1.0f */
  }
}

int main(int argc, char **argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: test_report_srgb DIR\n");
    return 2;
  }
  mkdir(argv[1], 0777);
  report_srgb t;
  report_srgb_init(&t);
  int failures = 0;
  for (int q = 1; q < 256; ++q)
    if (!(t.threshold[q] > t.threshold[q - 1])) {
      fprintf(stderr, "FAIL: step %d at %a is not above step %d at %a\n", q, t.threshold[q],
              q - 1, t.threshold[q - 1]);
      ++failures;
    }
  cf_image direct, table, a, b;
  cf_error err = {0};
  if (cf_image_alloc(&direct, WIDTH, HEIGHT, 3, &err) != CF_OK ||
      cf_image_alloc(&table, WIDTH, HEIGHT, 3, &err) != CF_OK) {
    fprintf(stderr, "FAIL: %s\n", err.message);
    return 1;
  }
  size_t n = 3 * (size_t)WIDTH * HEIGHT;
  float *x = malloc(n * sizeof *x);
  if (!x) return 1;
  fill(&t, x, n);
  for (size_t i = 0; i < n; ++i) {
    direct.pixels[i] = (float)cf_linear_to_srgb(fmin(1.0, fmax(0.0, x[i])));
    table.pixels[i] = (float)report_srgb_encode(&t, x[i]) / 255.0f;
  }
  char path_a[4200], path_b[4200];
  snprintf(path_a, sizeof path_a, "%s/direct.png", argv[1]);
  snprintf(path_b, sizeof path_b, "%s/table.png", argv[1]);
  if (cf_image_write(path_a, &direct, 8, &err) != CF_OK ||
      cf_image_write(path_b, &table, 8, &err) != CF_OK ||
      cf_image_read(path_a, &a, NULL, &err) != CF_OK ||
      cf_image_read(path_b, &b, NULL, &err) != CF_OK) {
    fprintf(stderr, "FAIL: %s\n", err.message);
    return 1;
  }
  size_t differ = 0;
  for (size_t i = 0; i < n; ++i)
    if (a.pixels[i] != b.pixels[i]) {
      if (differ++ < 10)
        fprintf(stderr, "FAIL: %a is stored as %.0f directly and %.0f from the table\n", x[i],
                255.0f * a.pixels[i], 255.0f * b.pixels[i]);
    }
  printf("%zu values (every step of the encoding, and each float below it): %zu differ\n", n,
         differ);
  failures += differ != 0;
  free(x);
  cf_image_free(&direct);
  cf_image_free(&table);
  cf_image_free(&a);
  cf_image_free(&b);
  return failures ? 1 : 0;
}
