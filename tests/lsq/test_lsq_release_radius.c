/* The trust region a round that frees a parameter from its bound starts
 * from (lsq_ceres.cpp, RELEASE_RADIUS): at most Ceres' default 1e4, not
 * the radius carried from the round before, which grows to 1e14 where
 * that round converged. (With the carried one, DiLiGenT's M4 candidate
 * took 35 box-shortened steps while Ceres halved 4e14 down; docs/solver.md,
 * "The carried trust region stops at a release".)
 *
 * The problem: C(x) = ½ (x₀ − 0.5)² + ½ (x₁ − 2)² in one block, x₀ in
 * [0, 1] starting at its upper bound (pinned there), x₁ free, from a
 * carried radius of 1e14. The first round solves x₁; at its end the
 * gradient points x₀ into the box and frees it; the next round solves x₀.
 * Its steps are exact (ratio 1: the radius triples at each), so the
 * radius at the end is the release's start times a few threes. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "lsq/lsq.h"
#include "support/check.h"

CHECK_MAIN_STATE;

static int quad_evaluate(void *user, const double *x, size_t block, double *cost, double *jtj,
                         double *jtu) {
  static const double m[2] = {0.5, 2.0};
  (void)user;
  (void)block;
  *cost = 0.0;
  for (int i = 0; i < 2; ++i) *cost += 0.5 * (x[i] - m[i]) * (x[i] - m[i]);
  if (jtj) {
    jtj[0] = 1.0, jtj[1] = 0.0, jtj[2] = 0.0, jtj[3] = 1.0;
    jtu[0] = x[0] - m[0], jtu[1] = x[1] - m[1];
  }
  return 1;
}

static int quad_columns(void *user, size_t block, const int **columns) {
  static const int both[2] = {0, 1};
  (void)user;
  (void)block;
  *columns = both;
  return 2;
}

int main(void) {
  static const double lower[2] = {0.0, -10.0}, upper[2] = {1.0, 10.0};
  double x[2] = {1.0, 0.0};
  int at_bound[2];
  cf_lsq_problem problem = {2, x, lower, upper, 1, quad_evaluate, quad_columns, NULL, at_bound};
  cf_lsq_options options;
  cf_lsq_default_options(&options);
  options.threads = 1;
  options.initial_radius = 1e14;
  cf_lsq_summary summary;
  memset(&summary, 0, sizeof summary);
  cf_error err = {0};
  cf_status st = cf_lsq_solve(&problem, &options, &summary, &err);
  CHECK(st == CF_OK, "solve: %s", err.message);
  CHECK(fabs(x[0] - 0.5) <= 1e-6 && fabs(x[1] - 2.0) <= 1e-6,
        "the minimum: x = (%.12g, %.12g), expected (0.5, 2)", x[0], x[1]);
  CHECK(at_bound[0] == 0, "x0 still pinned at its bound (%d)", at_bound[0]);
  /* from 1e4, a few exact steps: below 1e8; carried, at least 1e14 */
  CHECK(summary.final_radius <= 1e8, "the radius at the end %.3g: the release did not reset it",
        summary.final_radius);
  printf("%d iterations, final radius %.3g\n", summary.iterations, summary.final_radius);
  return check_finish("test_lsq_release_radius");
}
