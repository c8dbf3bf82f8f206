/* src/lsq's C interface, on problems small enough to know the answer:
 *   - a block that fails to evaluate (CF_LSQ_FAILED: out of memory) ends the
 *     solve with CF_ENOMEM, while one that is not finite only rejects the
 *     step (the solve goes on and converges);
 *   - a trust region that collapses below Ceres' floor as a chunk of the
 *     solve ends is convergence, not a failed next chunk;
 *   - the trace callback hears every iteration, and nothing is printed;
 *   - the termination: converged, out of iterations, stopped;
 *   - the covariance (JᵀJ)⁻¹ of a known matrix, and a singular one flagged;
 *   - the Newton decrement ½ gᵀ H⁺ g with and without pinned parameters,
 *     and a direction no data see dropped;
 *   - a block whose directions differ in scale by 1e19 (a fit's data at a
 *     tiny σ beside the response's prior in one block) solved in both;
 *   - Eigen's eigen-decomposition and Cholesky behind linalg.h, and the
 *     Schur complement the gains' check uses (cf_schur_covariance). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "lsq/linalg.h"
#include "lsq/lsq.h"
#include "support/check.h"

CHECK_MAIN_STATE;

/* C(x) = ½ Σ_i a_i (x_i − m_i)² in one block of two parameters; where x₀
 * passes `poison`, the block answers `poisoned` (not finite, or failed). */
typedef struct quad {
  double a[2], m[2];
  double poison;
  int poisoned;
} quad;

static int quad_evaluate(void *user, const double *x, size_t block, double *cost, double *jtj,
                         double *jtu) {
  const quad *q = user;
  (void)block;
  if (x[0] > q->poison) return q->poisoned;
  *cost = 0.0;
  for (int i = 0; i < 2; ++i) *cost += 0.5 * q->a[i] * (x[i] - q->m[i]) * (x[i] - q->m[i]);
  if (jtj) {
    jtj[0] = q->a[0], jtj[1] = 0.0, jtj[2] = 0.0, jtj[3] = q->a[1];
    for (int i = 0; i < 2; ++i) jtu[i] = q->a[i] * (x[i] - q->m[i]);
  }
  return CF_LSQ_EVALUATED;
}

static int quad_columns(void *user, size_t block, const int **columns) {
  static const int both[2] = {0, 1};
  (void)user;
  (void)block;
  *columns = both;
  return 2;
}

typedef struct lines {
  int count, iterations;
} lines;

static void count_line(void *user, const char *line) {
  lines *l = user;
  ++l->count;
  l->iterations += strncmp(line, "iteration ", 10) == 0;
}

static int stop_at_once(void *user, const double *x, double cost) {
  (void)user, (void)x, (void)cost;
  return 1;
}

static cf_status solve(quad *q, double *x, cf_lsq_options *options, cf_lsq_summary *summary,
                       cf_error *err) {
  static const double lower[2] = {-100.0, -100.0}, upper[2] = {100.0, 100.0};
  x[0] = 0.0, x[1] = 0.0;
  cf_lsq_problem problem = {2, x, lower, upper, 1, quad_evaluate, quad_columns, q, NULL};
  memset(summary, 0, sizeof *summary);
  return cf_lsq_solve(&problem, options, summary, err);
}

static void test_solve(void) {
  quad q = {{1.0, 4.0}, {3.0, -2.0}, HUGE_VAL, CF_LSQ_EVALUATED};
  double x[2];
  cf_lsq_options options;
  cf_lsq_default_options(&options);
  options.threads = 1;
  lines heard = {0, 0};
  options.trace = count_line;
  options.trace_user = &heard;
  cf_lsq_summary summary;
  cf_error err = {0};
  CHECK(solve(&q, x, &options, &summary, &err) == CF_OK, "solve: %s", err.message);
  CHECK(fabs(x[0] - 3.0) < 1e-8 && fabs(x[1] + 2.0) < 1e-8, "minimum (%g, %g)", x[0], x[1]);
  CHECK(summary.ending == CF_LSQ_END_CONVERGED && summary.converged, "ending %d", summary.ending);
  CHECK(strcmp(cf_lsq_termination_name(summary.ending), "CONVERGENCE") == 0, "name");
  CHECK(heard.iterations >= summary.iterations + 1, "trace heard %d iteration lines for %d",
        heard.iterations, summary.iterations);

  /* not finite past x₀ = 1: the steps there are rejected and the solve
   * ends where it could go, without an error */
  q.poison = 1.0, q.poisoned = CF_LSQ_NOT_FINITE;
  options.trace = NULL;
  cf_status s = solve(&q, x, &options, &summary, &err);
  CHECK(s == CF_OK, "not finite: status %d (%s)", s, err.message);
  CHECK(x[0] <= 1.0 && x[0] > 0.0 && x[1] < 0.0, "not finite: ended at (%g, %g)", x[0], x[1]);

  /* failed past x₀ = 1: the solve ends with CF_ENOMEM, not a rejected step */
  q.poisoned = CF_LSQ_FAILED;
  s = solve(&q, x, &options, &summary, &err);
  CHECK(s == CF_ENOMEM, "failed evaluation: status %d, expected CF_ENOMEM (%s)", s, err.message);

  q.poison = HUGE_VAL;
  options.max_iterations = 1;
  q.a[0] = 1e-6; /* a valley the first step cannot cross */
  s = solve(&q, x, &options, &summary, &err);
  CHECK(s == CF_OK && summary.ending == CF_LSQ_END_OUT_OF_ITERATIONS,
        "one iteration: status %d, ending %d", s, summary.ending);
  CHECK(strcmp(cf_lsq_termination_name(summary.ending), "NO_CONVERGENCE") == 0, "name");

  options.max_iterations = 100;
  options.stop = stop_at_once;
  s = solve(&q, x, &options, &summary, &err);
  CHECK(s == CF_OK && summary.ending == CF_LSQ_END_STOPPED && summary.stopped,
        "stopped: status %d, ending %d", s, summary.ending);
}

/* C(x) = ½ (x − m)ᵀ A (x − m), A = [[1e20, 1e9], [1e9, 16]]: well
 * conditioned at a unit diagonal (correlation 0.025), but its small
 * eigenvalue is 1.6e-19 of the large one. Compressed on the eigenvalues
 * of A itself (cut at 1e-14 of the largest), x₁'s direction was dropped
 * and x₁ stayed where it started (noise-free fits with a response
 * curve: its prior in block 0 beside data at σ 5e-9). */
static int scaled_evaluate(void *user, const double *x, size_t block, double *cost, double *jtj,
                           double *jtu) {
  static const double a[4] = {1e20, 1e9, 1e9, 16.0}, m[2] = {3.0, -2.0};
  (void)user, (void)block;
  double d[2] = {x[0] - m[0], x[1] - m[1]};
  double ad[2] = {a[0] * d[0] + a[1] * d[1], a[2] * d[0] + a[3] * d[1]};
  *cost = 0.5 * (d[0] * ad[0] + d[1] * ad[1]);
  if (jtj) {
    memcpy(jtj, a, sizeof a);
    jtu[0] = ad[0], jtu[1] = ad[1];
  }
  return CF_LSQ_EVALUATED;
}

static void test_scales(void) {
  static const double lower[2] = {-100.0, -100.0}, upper[2] = {100.0, 100.0};
  double x[2] = {0.0, 0.0};
  cf_lsq_problem problem = {2, x, lower, upper, 1, scaled_evaluate, quad_columns, NULL, NULL};
  cf_lsq_options options;
  cf_lsq_default_options(&options);
  options.threads = 1;
  cf_lsq_summary summary;
  cf_error err = {0};
  CHECK(cf_lsq_solve(&problem, &options, &summary, &err) == CF_OK, "solve: %s", err.message);
  CHECK(fabs(x[0] - 3.0) < 1e-8 && fabs(x[1] + 2.0) < 1e-6,
        "scales 1e19 apart: minimum (3, -2), found (%.12g, %.12g)", x[0], x[1]);
}

/* Every step rejected (not finite anywhere but at the start): the trust
 * region shrinks to Ceres' floor, 1e-32. Whatever the iteration cap and the
 * start radius, the solve ends there converged; where the floor fell on the
 * end of a chunk, the next chunk started below it and Ceres refused it
 * ("Invalid configuration", 156 of these 1 140 solves, before the fix). */
static int nowhere_evaluate(void *user, const double *x, size_t block, double *cost, double *jtj,
                            double *jtu) {
  (void)user, (void)block;
  if (x[0] != 0.0) return CF_LSQ_NOT_FINITE;
  *cost = 0.5;
  if (jtj) jtj[0] = 1.0, jtu[0] = -1.0;
  return CF_LSQ_EVALUATED;
}

static int one_column(void *user, size_t block, const int **columns) {
  static const int first[1] = {0};
  (void)user, (void)block;
  *columns = first;
  return 1;
}

static void test_collapsed_radius(void) {
  int failed = 0, converged = 0, solves = 0;
  for (int cap = 1; cap <= 60; ++cap)
    for (int e = -6; e <= 12; ++e, ++solves) {
      double x[1] = {0.0};
      static const double lower[1] = {-1e3}, upper[1] = {1e3};
      cf_lsq_problem problem = {1, x, lower, upper, 1, nowhere_evaluate, one_column, NULL, NULL};
      cf_lsq_options options;
      cf_lsq_default_options(&options);
      options.threads = 1, options.max_iterations = cap, options.initial_radius = pow(10.0, e);
      options.function_tolerance = options.gradient_tolerance = options.parameter_tolerance = 0.0;
      cf_lsq_summary summary;
      cf_error err = {0};
      failed += cf_lsq_solve(&problem, &options, &summary, &err) != CF_OK;
      converged += summary.ending == CF_LSQ_END_CONVERGED;
    }
  CHECK(failed == 0, "%d of %d solves failed when the trust region collapsed", failed, solves);
  CHECK(converged > 0, "no solve converged on the collapsed trust region");
}

static void test_covariance(void) {
  /* [[4, 1], [1, 3]]⁻¹ = [[3, −1], [−1, 4]] / 11 */
  const double jtj[4] = {4.0, 1.0, 1.0, 3.0}, want[4] = {3.0 / 11, -1.0 / 11, -1.0 / 11, 4.0 / 11};
  double covariance[4];
  int rank_deficient = -1;
  cf_error err = {0};
  CHECK(cf_lsq_covariance(2, jtj, covariance, &rank_deficient, &err) == CF_OK, "%s", err.message);
  CHECK(rank_deficient == 0, "full rank flagged deficient");
  for (int i = 0; i < 4; ++i)
    CHECK(fabs(covariance[i] - want[i]) < 1e-14, "covariance[%d] = %.17g, expected %.17g", i,
          covariance[i], want[i]);
  /* eigenvalues 2 and 2e-13: below 1e-12 of the largest */
  const double singular[4] = {1.0, 1.0 - 2e-13, 1.0 - 2e-13, 1.0};
  CHECK(cf_lsq_covariance(2, singular, covariance, &rank_deficient, &err) == CF_OK, "singular");
  CHECK(rank_deficient == 1, "a singular matrix not flagged");
}

static void test_decrement(void) {
  /* H = diag(2, 8), g = (2, 4): ½ (2²/2 + 4²/8) = 2 */
  const double h[4] = {2.0, 0.0, 0.0, 8.0}, g[2] = {2.0, 4.0};
  double d = cf_lsq_newton_decrement(2, h, g, NULL);
  CHECK(fabs(d - 2.0) < 1e-14, "decrement %.17g, expected 2", d);
  const int pinned[2] = {0, -1}; /* the second held: ½ 2²/2 = 1 */
  d = cf_lsq_newton_decrement(2, h, g, pinned);
  CHECK(fabs(d - 1.0) < 1e-14, "decrement with a pin %.17g, expected 1", d);
  const double blind[4] = {2.0, 0.0, 0.0, 0.0}; /* no data see the second */
  d = cf_lsq_newton_decrement(2, blind, g, NULL);
  CHECK(fabs(d - 1.0) < 1e-14, "decrement with an unseen direction %.17g, expected 1", d);
}

static void test_linalg(void) {
  const double a[9] = {4.0, 1.0, 0.0, 1.0, 3.0, 1.0, 0.0, 1.0, 2.0};
  double values[3], vectors[9];
  CHECK(cf_symmetric_eigen(3, a, values, vectors), "eigen");
  CHECK(values[0] <= values[1] && values[1] <= values[2], "ascending");
  for (int k = 0; k < 3; ++k) /* a v = λ v */
    for (int i = 0; i < 3; ++i) {
      double av = 0.0;
      for (int j = 0; j < 3; ++j) av += a[3 * i + j] * vectors[3 * j + k];
      CHECK(fabs(av - values[k] * vectors[3 * i + k]) < 1e-13, "eigenpair %d row %d", k, i);
    }
  const double b[3] = {1.0, 2.0, 3.0};
  double x[3];
  CHECK(cf_cholesky_solve(3, a, b, x), "cholesky");
  for (int i = 0; i < 3; ++i) {
    double ax = 0.0;
    for (int j = 0; j < 3; ++j) ax += a[3 * i + j] * x[j];
    CHECK(fabs(ax - b[i]) < 1e-13, "a x = b, row %d: %.17g", i, ax);
  }
  const double indefinite[4] = {1.0, 2.0, 2.0, 1.0};
  CHECK(!cf_cholesky_solve(2, indefinite, b, x), "an indefinite matrix factored");
  const double not_finite[4] = {1.0, NAN, NAN, 1.0};
  CHECK(!cf_symmetric_eigen(2, not_finite, values, NULL), "NaN decomposed");
}

/* cf_schur_covariance: the last g unknowns' covariance with the first
 * profiled out; a direction of the first block that nothing constrains
 * dropped, not traded; a gain that only trades with the first: singular. */
static void test_schur(void) {
  /* D − bᵀ b / 4 = [[2.75, 0.5], [0.5, 4]], its inverse [[4, −0.5], [−0.5, 2.75]] / 10.75 */
  const double a[9] = {4.0, 1.0, 2.0, 1.0, 3.0, 1.0, 2.0, 1.0, 5.0};
  const double want[4] = {4.0 / 10.75, -0.5 / 10.75, -0.5 / 10.75, 2.75 / 10.75};
  double covariance[4], weakest[2];
  CHECK(cf_schur_covariance(3, 2, a, covariance, weakest) == 1, "regular");
  for (int i = 0; i < 4; ++i)
    CHECK(fabs(covariance[i] - want[i]) < 1e-12, "covariance[%d] %g, want %g", i, covariance[i],
          want[i]);
  const double free_first[9] = {0.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 3.0};
  CHECK(cf_schur_covariance(3, 2, free_first, covariance, weakest) == 1 &&
            fabs(covariance[0] - 0.5) < 1e-12 && fabs(covariance[3] - 1.0 / 3.0) < 1e-12,
        "an unconstrained first unknown dropped: %g %g", covariance[0], covariance[3]);
  /* the first gain's column is the first unknown's: it only trades with it */
  const double trades[9] = {1.0, 1.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 2.0};
  CHECK(cf_schur_covariance(3, 2, trades, covariance, weakest) == 0 &&
            fabs(fabs(weakest[0]) - 1.0) < 1e-9 && fabs(weakest[1]) < 1e-9,
        "a gain that trades: singular, weakest (%g, %g)", weakest[0], weakest[1]);
  /* the same trade between two gains and the first unknown, no zero diagonal */
  const double pair[9] = {2.0, 1.0, 1.0, 1.0, 1.0, 0.0, 1.0, 0.0, 1.0};
  CHECK(cf_schur_covariance(3, 2, pair, covariance, weakest) == 0 &&
            fabs(fabs(weakest[0]) - fabs(weakest[1])) < 1e-9,
        "two gains against one unknown: singular, weakest (%g, %g)", weakest[0], weakest[1]);
  const double not_finite[9] = {1.0, NAN, 0.0, NAN, 1.0, 0.0, 0.0, 0.0, 1.0};
  CHECK(cf_schur_covariance(3, 2, not_finite, covariance, weakest) == -1, "NaN");
}

int main(void) {
  test_schur();
  test_solve();
  test_collapsed_radius();
  test_scales();
  test_covariance();
  test_decrement();
  test_linalg();
  return check_finish("test_lsq_layer");
}
