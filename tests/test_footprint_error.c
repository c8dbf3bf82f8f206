/* The pixel-footprint rule of include/clayfit/model.h: cf_footprint_samples
 * picks the fewest samples whose error bound (cf_footprint_error) is within
 * the tolerance, below the cap; the Gauss-Legendre pairs' bound falls as
 * 1/P⁴; cf_footprint_offset's points are a composite two-point
 * Gauss-Legendre rule (exact for cubics on every panel); the degenerate
 * cases return what the header says. */
#include <math.h>

#include "clayfit/model.h"
#include "support/check.h"

CHECK_MAIN_STATE;

enum { MAX = 16 };

static void check_choice(double w, double delta, double theta, double tol, int *capped) {
  int n = cf_footprint_samples(w, delta, theta, tol, MAX);
  CHECK(n == 1 || (n >= 2 && n <= MAX && n % 2 == 0), "n = %d", n);
  if (n == MAX) {
    ++*capped;
    return;
  }
  double at_n = cf_footprint_error(w, delta, theta, n);
  CHECK(at_n <= tol * (1.0 + 1e-12), "w %g delta %g theta %g tol %g: n %d errs %g", w, delta, theta,
        tol, n, at_n);
  if (n >= 2)
    CHECK(cf_footprint_error(w, delta, theta, 1) > tol,
          "w %g delta %g theta %g tol %g: the "
          "centre is enough, not %d",
          w, delta, theta, tol, n);
  if (n >= 4)
    CHECK(cf_footprint_error(w, delta, theta, n - 2) > tol,
          "w %g delta %g theta %g tol %g: %d is enough (%g)", w, delta, theta, tol, n - 2,
          cf_footprint_error(w, delta, theta, n - 2));
}

int main(void) {
  static const double widths[] = {1e-4, 1e-3, 0.01, 0.05, 0.2};
  static const double deltas[] = {1e-4, 1e-3, 5e-3, 0.02};
  static const double thetas[] = {0.0, 1e-3, 0.01, 0.1, 0.5};
  static const double tolerances[] = {1e-4, 2e-3, 0.02, 0.1};
  int cases = 0, capped = 0, paired = 0;
  for (size_t a = 0; a < sizeof widths / sizeof *widths; ++a)
    for (size_t b = 0; b < sizeof deltas / sizeof *deltas; ++b)
      for (size_t c = 0; c < sizeof thetas / sizeof *thetas; ++c)
        for (size_t d = 0; d < sizeof tolerances / sizeof *tolerances; ++d) {
          double w = widths[a], delta = deltas[b], theta = thetas[c];
          check_choice(w, delta, theta, tolerances[d], &capped);
          int n = cf_footprint_samples(w, delta, theta, tolerances[d], MAX);
          paired += n > 1 && n < MAX;
          ++cases;
          double two = cf_footprint_error(w, delta, theta, 2);
          CHECK(fabs(cf_footprint_error(w, delta, theta, 6) * 81.0 - two) <= 1e-12 * two,
                "1/P^4: %g against %g", cf_footprint_error(w, delta, theta, 6) * 81.0, two);
        }
  CHECK(capped > 0 && paired > 0 && capped + paired < cases,
        "capped %d, paired %d of %d: the grid should reach the centre, pairs and the cap", capped,
        paired, cases);
  /* where the lobe is as wide as the turn, the pairs need 8 where the
   * centre's rule would need 29 (the header's example) */
  CHECK(cf_footprint_samples(0.01, 0.01, 0.0, 2e-3, 64) == 8, "8 samples, not %d",
        cf_footprint_samples(0.01, 0.01, 0.0, 2e-3, 64));

  /* the points: symmetric, inside the pixel, and exact for a cubic */
  for (int n = 2; n <= MAX; n += 2) {
    double mean = 0.0;
    for (int j = 0; j < n; ++j) {
      double x = cf_footprint_offset(n, j);
      CHECK(fabs(x) < 0.5, "n %d: offset %d = %g", n, j, x);
      CHECK(fabs(x + cf_footprint_offset(n, n - 1 - j)) < 1e-15, "n %d: not symmetric at %d", n, j);
      mean += (x * x * x + 3.0 * x * x - x + 1.0) / n;
    }
    CHECK(fabs(mean - 1.25) < 1e-14, "n %d: the mean of a cubic %.17g, not 1.25", n, mean);
  }
  CHECK(cf_footprint_offset(1, 0) == 0.0, "one sample: the centre");
  CHECK(isnan(cf_footprint_offset(3, 0)) && isnan(cf_footprint_offset(4, 4)) &&
            isnan(cf_footprint_offset(2, -1)),
        "odd counts and indices outside [0, n) have no offset");
  CHECK(isnan(cf_footprint_error(0.01, 0.01, 0.0, 3)), "an odd count has no bound");
  CHECK(cf_footprint_error(0.01, 0.0, 0.1, 1) == 0.0, "no turn: no error");
  CHECK(cf_footprint_error(INFINITY, 0.01, 0.1, 1) == 0.0, "no lobe: no error");
  CHECK(isinf(cf_footprint_error(0.0, 0.01, 0.0, 4)), "a delta lobe at the centre: unbounded");
  CHECK(cf_footprint_samples(0.0, 0.01, 0.0, 1e-3, 15) == 14, "a delta lobe: the even cap, not %d",
        cf_footprint_samples(0.0, 0.01, 0.0, 1e-3, 15));
  CHECK(cf_footprint_samples(0.0, 0.01, 0.0, 1e-3, 1) == 1, "a cap of 1: the centre");
  return check_finish("footprint error");
}
