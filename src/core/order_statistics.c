/* Order statistics (order_statistics.h). */
#include "core/order_statistics.h"

#include <stdlib.h>

double order_kth_smallest(double *a, size_t n, size_t k) {
  /* quickselect with a three-way partition: [lo, lt) < pivot,
   * [lt, gt] = pivot, (gt, hi] > pivot */
  ptrdiff_t lo = 0, hi = (ptrdiff_t)n - 1, target = (ptrdiff_t)k;
  while (lo < hi) {
    double pivot = a[lo + (hi - lo) / 2];
    ptrdiff_t lt = lo, i = lo, gt = hi;
    while (i <= gt) {
      double t = a[i];
      if (t < pivot) {
        a[i++] = a[lt];
        a[lt++] = t;
      } else if (t > pivot) {
        a[i] = a[gt];
        a[gt--] = t;
      } else {
        ++i;
      }
    }
    if (target < lt)
      hi = lt - 1;
    else if (target > gt)
      lo = gt + 1;
    else
      return pivot;
  }
  return a[target];
}

double order_median(double *a, size_t n) {
  double upper = order_kth_smallest(a, n, n / 2);
  if (n % 2) return upper;
  double lower = a[0]; /* the largest of a[0..n/2), all <= upper after the selection */
  for (size_t i = 1; i < n / 2; ++i)
    if (a[i] > lower) lower = a[i];
  return 0.5 * (lower + upper);
}

typedef struct weighted {
  double value, weight;
} weighted;

static int by_value(const void *a, const void *b) {
  double x = ((const weighted *)a)->value, y = ((const weighted *)b)->value;
  return (x > y) - (x < y);
}

int order_weighted_median(const double *values, const double *weights, size_t n, double *median) {
  weighted *pairs = malloc((n ? n : 1) * sizeof *pairs);
  if (!pairs) return 0;
  double total = 0.0;
  for (size_t i = 0; i < n; ++i) {
    pairs[i] = (weighted){values[i], weights[i]};
    total += weights[i];
  }
  qsort(pairs, n, sizeof *pairs, by_value);
  double below = 0.0;
  *median = n ? pairs[n - 1].value : 0.0;
  for (size_t i = 0; i < n; ++i) {
    below += pairs[i].weight;
    if (below >= 0.5 * total) {
      *median = pairs[i].value;
      break;
    }
  }
  free(pairs);
  return 1;
}
