/* lsq.h's line search after a chunk of under-stepping iterations (private
 * to src/fit): where the Gauss-Newton matrix overstates the cost's
 * curvature, the steps keep a fixed share of the way and their ratio of
 * actual to predicted decrease stays near 2; the search along the last
 * step then starts at the 1-D minimum that ratio implies instead of
 * doubling from 2.
 *
 * The problem: C(x) = ½ a (x − 1)² with a = 4 in one block, whose normal
 * equations report the true gradient a (x − 1) but the curvature K a
 * (K = 10: a Gauss-Newton matrix ten times the cost's, as from large
 * systematic residuals). From x = 0 each step covers 1/K of the way; its
 * ratio is 2 − 1/K = 1.9 and the minimum along it is K = 10 steps out.
 * With a wall, ½ W (x − w)² beyond x = w, the first trial lands past it
 * and the search halves back toward the last point. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "lsq/lsq.h"
#include "support/check.h"

CHECK_MAIN_STATE;

enum { K = 10 };

typedef struct toy {
  double a, wall, w; /* the wall's curvature (0: none) and place */
  int cost_only;     /* evaluations without the normal equations: the search's */
} toy;

static int toy_evaluate(void *user, const double *x, size_t block, double *cost, double *jtj,
                        double *jtu) {
  toy *data = user;
  (void)block;
  double d = x[0] - 1.0, e = x[0] > data->w ? x[0] - data->w : 0.0;
  *cost = 0.5 * data->a * d * d + 0.5 * data->wall * e * e;
  if (jtj) { /* (the wall's curvature as it is) */
    jtj[0] = K * data->a + (e > 0.0 ? data->wall : 0.0);
    jtu[0] = data->a * d + data->wall * e;
  } else {
    ++data->cost_only;
  }
  return 1;
}

static int toy_columns(void *user, size_t block, const int **columns) {
  static const int one[1] = {0};
  (void)user;
  (void)block;
  *columns = one;
  return 1;
}

/* Solve from x = 0; the end in x. */
static cf_lsq_summary solve(toy *data, double *x) {
  static const double lower[1] = {-10.0}, upper[1] = {10.0};
  int at_bound[1];
  x[0] = 0.0;
  cf_lsq_problem problem = {1, x, lower, upper, 1, toy_evaluate, toy_columns, data, at_bound};
  cf_lsq_options options;
  cf_lsq_default_options(&options);
  options.threads = 1;
  cf_lsq_summary summary;
  memset(&summary, 0, sizeof summary);
  cf_error err = {0};
  cf_status st = cf_lsq_solve(&problem, &options, &summary, &err);
  CHECK(st == CF_OK, "solve: %s", err.message);
  return summary;
}

int main(void) {
  double x[1];
  toy data = {4.0, 0.0, 0.0, 0};
  cf_lsq_summary summary = solve(&data, x);
  CHECK(fabs(x[0] - 1.0) <= 1e-6, "the minimum: x = %.12g, expected 1", x[0]);
  /* without a search, 0.9^k of the way left after k steps: about 100
   * iterations to the tolerance; with it, one chunk of 8 */
  CHECK(summary.iterations <= 9, "%d iterations, expected a chunk of 8 and the search",
        summary.iterations);
  /* the first trial at t = 8 (t* = 10 rounded down to a power of 2), 16
   * higher, then the parabola through 1, 8, 16: three cost passes, where
   * doubling from 2 took five (2, 4, 8, 16 and the parabola) */
  CHECK(data.cost_only >= 1 && data.cost_only <= 3, "%d cost passes in the search, expected 3",
        data.cost_only);
  printf("no wall: %d iterations, %d cost passes in the line search, x = %.12g\n",
         summary.iterations, data.cost_only, x[0]);

  /* a wall at 0.65 (after 8 steps x = 0.57, t = 8 reaches 0.90): the
   * minimum of the cost with it, (a + W w) / (a + W) */
  toy walled = {4.0, 4000.0, 0.65, 0};
  summary = solve(&walled, x);
  double expected = (walled.a + walled.wall * walled.w) / (walled.a + walled.wall);
  CHECK(fabs(x[0] - expected) <= 1e-6, "with the wall: x = %.12g, expected %.12g", x[0], expected);
  /* t = 8 and 4 beyond the wall, 2 lower, the parabola through 1, 2, 4 */
  CHECK(walled.cost_only >= 4 && walled.cost_only <= 8,
        "with the wall: %d cost passes in the line searches, expected 4 in the first",
        walled.cost_only);
  printf("the wall: %d iterations, %d cost passes in the line searches, x = %.12g\n",
         summary.iterations, walled.cost_only, x[0]);
  return check_finish("test_lsq_extrapolate");
}
