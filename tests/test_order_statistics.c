/* The order statistics every layer uses (src/core/include/core/order_statistics.h),
 * against a full sort: the k-th smallest for every k of random arrays
 * with many ties and with none, the median of odd and even counts, and the
 * weighted median against its definition. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/order_statistics.h"
#include "core/rng.h"

static int by_value(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

static int failures = 0;

static void expect(int ok, const char *what, size_t n, size_t k) {
  if (ok) return;
  ++failures;
  if (failures <= 10) printf("FAIL: %s (n %zu, k %zu)\n", what, n, k);
}

/* values[0..n): with ties (levels > 0: that many distinct values) or not */
static void fill(cf_rng *rng, double *values, size_t n, int levels) {
  for (size_t i = 0; i < n; ++i) {
    double u = cf_rng_uniform(rng);
    values[i] = levels > 0 ? (double)(int)(u * levels) : u - 0.5;
  }
}

static void check_array(cf_rng *rng, size_t n, int levels) {
  double *values = malloc(n * sizeof *values), *sorted = malloc(n * sizeof *sorted),
         *work = malloc(n * sizeof *work);
  fill(rng, values, n, levels);
  memcpy(sorted, values, n * sizeof *values);
  qsort(sorted, n, sizeof *sorted, by_value);
  for (size_t k = 0; k < n; ++k) {
    memcpy(work, values, n * sizeof *values);
    double kth = order_kth_smallest(work, n, k);
    expect(kth == sorted[k], "k-th smallest equals the sorted array's", n, k);
    int partitioned = 1; /* after the selection: a[0..k) <= a[k] <= a(k..n) */
    for (size_t i = 0; i < n; ++i) partitioned &= i < k ? work[i] <= kth : work[i] >= kth;
    expect(partitioned, "the array is partitioned about k", n, k);
  }
  memcpy(work, values, n * sizeof *values);
  double median = n % 2 ? sorted[n / 2] : 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]);
  expect(order_median(work, n) == median, "median equals the sorted array's", n, n / 2);
  double *weights = malloc(n * sizeof *weights), total = 0.0, wm = 0.0;
  for (size_t i = 0; i < n; ++i) total += weights[i] = cf_rng_uniform(rng);
  expect(order_weighted_median(values, weights, n, &wm), "weighted median allocates", n, 0);
  double at_or_below = 0.0, below = 0.0; /* the definition: the smallest value with half */
  for (size_t i = 0; i < n; ++i) {
    at_or_below += values[i] <= wm ? weights[i] : 0.0;
    below += values[i] < wm ? weights[i] : 0.0;
  }
  expect(at_or_below >= 0.5 * total && below < 0.5 * total, "weighted median's definition", n, 0);
  free(values), free(sorted), free(work), free(weights);
}

int main(void) {
  cf_rng rng = cf_rng_seed(20261126);
  static const size_t sizes[] = {1, 2, 3, 4, 5, 8, 17, 64, 101, 1000};
  size_t arrays = 0;
  for (size_t s = 0; s < sizeof sizes / sizeof *sizes; ++s)
    for (int levels = 0; levels <= 8; levels += 2)
      for (int repeat = 0; repeat < 20; ++repeat, ++arrays) check_array(&rng, sizes[s], levels);
  printf("%zu arrays, %d failures\n", arrays, failures);
  return failures ? 1 : 0;
}
