/* Order statistics for the fit: the k-th smallest of an array, and a
 * weighted median. Private to src/fit. */
#ifndef CLAYFIT_FIT_ORDER_STATISTICS_H
#define CLAYFIT_FIT_ORDER_STATISTICS_H

#include <stddef.h>

/* The k-th smallest of a[0..n) (0-based; a is reordered), n > 0, k < n. */
double fit_kth_smallest(double *a, size_t n, size_t k);

/* The smallest value with at least half the total weight at or below it;
 * returns 0 when out of memory. */
int fit_weighted_median(const double *values, const double *weights, size_t n, double *median);

#endif /* CLAYFIT_FIT_ORDER_STATISTICS_H */
