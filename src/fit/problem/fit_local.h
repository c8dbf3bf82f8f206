/* The normal equations of one channel's rows of one image, in a small
 * dense layout (the kernel's, fit_kernel.c): the model unknowns that move
 * the channel, then the log gain (the scale's, the image's exposure's and
 * balance's derivative, which are the same), then the response's slopes,
 * then the image's lights' gains. Rows add here without indirection; the
 * sums go to the block's columns when the image changes (local_flush).
 * For src/fit/problem/ alone. */
#ifndef CLAYFIT_FIT_PROBLEM_LOCAL_H
#define CLAYFIT_FIT_PROBLEM_LOCAL_H

#include <string.h>

#include "fit_scratch.h"

enum { LOCAL_MAX = CF_MAX_DIM + 1 + CF_RESPONSE_MODEL_KNOTS + FIT_IMAGE_LIGHTS };

typedef struct local_normal {
  int size;
  double a[LOCAL_MAX][LOCAL_MAX]; /* lower triangle */
  double b[LOCAL_MAX];
} local_normal;

static inline void local_add_sized(local_normal *n, const double *v, double u, int size) {
  for (int i = 0; i < size; ++i) {
    double vi = v[i];
    n->b[i] += vi * u;
    for (int j = 0; j <= i; ++j) n->a[i][j] += vi * v[j];
  }
}

/* One row into the sums; the common sizes with their size a constant, so
 * that the compiler unrolls the loops (a fifth of the evaluation was this
 * triangle, with its bound unknown). */
static inline void local_add(local_normal *n, const double *v, double u) {
  switch (n->size) {
    case 2:
      local_add_sized(n, v, u, 2);
      break;
    case 3:
      local_add_sized(n, v, u, 3);
      break;
    case 4:
      local_add_sized(n, v, u, 4);
      break;
    case 5:
      local_add_sized(n, v, u, 5);
      break;
    case 6:
      local_add_sized(n, v, u, 6);
      break;
    case 7:
      local_add_sized(n, v, u, 7);
      break;
    case 8:
      local_add_sized(n, v, u, 8);
      break;
    case 9:
      local_add_sized(n, v, u, 9);
      break;
    default:
      local_add_sized(n, v, u, n->size);
      break;
  }
}

/* Where the local indices go: one column each, but the log gain's, which
 * goes to the gains' columns (scale, the image's exposure and balance;
 * for the last image, minus every other one's), and the image's lights'
 * (the last light's to minus every other light's). */
typedef struct local_map {
  int column[LOCAL_MAX];
  int gain; /* the log gain's local index, or −1 */
  const int *gain_column;
  const double *gain_sign;
  int gain_count;
  /* the image's lights' gains: local indices light_first … + light_entries */
  int light_first, light_entries, last_count;
  const fit_scratch *s;
  size_t last_light;
} local_map;

static inline int local_targets(const local_map *map, int i, const int **column,
                                const double **sign) {
  static const double one = 1.0;
  if (i >= map->light_first && i < map->light_first + map->light_entries) {
    int l = map->s->entry_light[i - map->light_first];
    *column = (size_t)l == map->last_light ? map->s->last_places : &map->s->light_place[l];
    *sign = (size_t)l == map->last_light ? map->s->minus : &one;
    return (size_t)l == map->last_light ? map->last_count : 1;
  }
  if (i == map->gain) {
    *column = map->gain_column;
    *sign = map->gain_sign;
    return map->gain_count;
  }
  *column = &map->column[i];
  *sign = &one;
  return 1;
}

/* The local sums into the block's k × k jtj (both triangles) and jtu, then
 * zeroed. */
static inline void local_flush(local_normal *n, const local_map *map, int k, double *jtj,
                               double *jtu) {
  for (int i = 0; i < n->size; ++i) {
    const int *ci, *cj;
    const double *si, *sj;
    int count_i = local_targets(map, i, &ci, &si);
    for (int x = 0; x < count_i; ++x) jtu[ci[x]] += si[x] * n->b[i];
    for (int j = 0; j <= i; ++j) {
      double value = n->a[i][j];
      if (value == 0.0) continue;
      int count_j = local_targets(map, j, &cj, &sj);
      for (int x = 0; x < count_i; ++x)
        for (int y = 0; y < count_j; ++y) {
          double v = si[x] * sj[y] * value;
          jtj[(size_t)ci[x] * (size_t)k + (size_t)cj[y]] += v;
          if (i != j) jtj[(size_t)cj[y] * (size_t)k + (size_t)ci[x]] += v;
        }
    }
  }
  int size = n->size;
  memset(n, 0, sizeof *n);
  n->size = size;
}

#endif /* CLAYFIT_FIT_PROBLEM_LOCAL_H */
