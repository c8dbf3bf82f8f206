/* Wall time for stage timings and benchmarks: seconds on the monotonic
 * clock (POSIX clock_gettime; the includer defines _POSIX_C_SOURCE).
 * Header-only. */
#ifndef CLAYFIT_CORE_CLOCK_H
#define CLAYFIT_CORE_CLOCK_H

#include <time.h>

static inline double cf_now_seconds(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

#endif /* CLAYFIT_CORE_CLOCK_H */
