/* Order statistics: the k-th smallest of an array, the median and a
 * weighted median; one place for every layer (the capture's bright levels
 * and silhouette threshold, the fit's robust scales and budgets, the
 * report's white points). Internal to clayfit (src/). Pure C. */
#ifndef CLAYFIT_CORE_ORDER_STATISTICS_H
#define CLAYFIT_CORE_ORDER_STATISTICS_H

#include <stddef.h>

/* The k-th smallest of a[0..n) (0-based; a is reordered), n > 0, k < n. */
double order_kth_smallest(double *a, size_t n, size_t k);

/* The median of a[0..n), n > 0 (a is reordered): the middle value, or for
 * even n the mean of the two middle ones. */
double order_median(double *a, size_t n);

/* The smallest value with at least half the total weight at or below it;
 * returns 0 when out of memory. */
int order_weighted_median(const double *values, const double *weights, size_t n, double *median);

#endif /* CLAYFIT_CORE_ORDER_STATISTICS_H */
