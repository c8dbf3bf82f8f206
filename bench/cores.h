/* What the highlight-cores program's files share (bench/cores.c: the
 * photos' pictures, the noise floor and the driver; bench/cores_psf.c: the
 * cores' profiles, shifts and the point-spread-function test). */
#ifndef CLAYFIT_BENCH_CORES_H
#define CLAYFIT_BENCH_CORES_H

#include <stddef.h>

#include "clayfit/capture.h"

enum { WIN = 5, HALF = 2, NP = 6 }; /* the noise window and its quadratic */
enum { CORE_R = 3, RING_R = 12, KERNEL_R = 15, PATCH_R = RING_R + KERNEL_R };

typedef struct image_data {
  int w, h;
  float *y[3], *p[3];  /* photo and prediction (NaN: not an observation) */
  unsigned char *clip; /* per pixel: clipped channels (bits) */
  int bx, by;          /* the brightest observation's pixel */
} image_data;

typedef struct all {
  const cf_capture *capture;
  const cf_observations *o;
  double *pred;
  size_t images;
  size_t *first, *last;
} all;

typedef struct sums {
  double e2, y2;
} sums;

typedef struct set {
  image_data *img;
  size_t count;
} set;

/* Is (x, y) within r pixels of the image's brightest observation? */
int is_core(const image_data *d, int x, int y, double r);

/* cores_psf.c: each prints its table. */
void profile(const set *s);
void core_radii(const set *s);
void core_grid(const set *s, size_t k);
void shift_test(const set *s);
void radial_and_star(const set *s);
void psf_test(set *s, int streak);

#endif /* CLAYFIT_BENCH_CORES_H */
