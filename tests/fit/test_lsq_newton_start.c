/* lsq.h's newton_start (private to src/fit): a solve that starts near a
 * minimum at a bound pins the parameter there up front, and reaches the
 * same minimum as without it in no more iterations; a start far from the
 * minimum (the step's predicted decrease of 10 or more) and a minimum just
 * inside the bound are solved exactly as without it.
 *
 * The problem: m(t) = q (1 − ½ t s / (s + 0.33)) on 400 points t in
 * [0, 1), s in [0, 1.44] (an Oren-Nayar σ²'s saturation, nonlinear near
 * its floor), q free, residuals (m − y)/0.2. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "lsq/lsq.h"
#include "support/check.h"

CHECK_MAIN_STATE;

enum { POINTS = 400 };

typedef struct toy {
  double y[POINTS];
} toy;

static double toy_model(double s, double q, double t, double *ds, double *dq) {
  double sat = s / (s + 0.33);
  *dq = 1.0 - 0.5 * t * sat;
  *ds = -0.5 * q * t * 0.33 / ((s + 0.33) * (s + 0.33));
  return q * *dq;
}

static int toy_evaluate(void *user, const double *x, size_t block, double *cost, double *jtj,
                        double *jtu) {
  const toy *data = user;
  (void)block;
  double c = 0.0, a00 = 0.0, a01 = 0.0, a11 = 0.0, b0 = 0.0, b1 = 0.0;
  for (int j = 0; j < POINTS; ++j) {
    double t = (double)j / POINTS, ds, dq;
    double r = (toy_model(x[0], x[1], t, &ds, &dq) - data->y[j]) / 0.2;
    ds /= 0.2;
    dq /= 0.2;
    c += 0.5 * r * r;
    a00 += ds * ds, a01 += ds * dq, a11 += dq * dq, b0 += ds * r, b1 += dq * r;
  }
  *cost = c;
  if (jtj) {
    jtj[0] = a00, jtj[1] = jtj[2] = a01, jtj[3] = a11;
    jtu[0] = b0, jtu[1] = b1;
  }
  return isfinite(c);
}

static int toy_columns(void *user, size_t block, const int **columns) {
  static const int both[2] = {0, 1};
  (void)user;
  (void)block;
  *columns = both;
  return 2;
}

/* Solve from (s, q) with newton_start on or off; the end in x. */
static cf_lsq_summary solve(toy *data, double s, double q, int newton_start, double x[2],
                            int at_bound[2]) {
  static const double lower[2] = {0.0, -HUGE_VAL}, upper[2] = {1.44, HUGE_VAL};
  x[0] = s;
  x[1] = q;
  cf_lsq_problem problem = {2, x, lower, upper, 1, toy_evaluate, toy_columns, data, at_bound};
  cf_lsq_options options;
  cf_lsq_default_options(&options);
  options.threads = 1;
  options.newton_start = newton_start;
  cf_lsq_summary summary;
  memset(&summary, 0, sizeof summary);
  cf_error err = {0};
  cf_status st = cf_lsq_solve(&problem, &options, &summary, &err);
  CHECK(st == CF_OK, "solve from (%g, %g): %s", s, q, err.message);
  return summary;
}

static void make_data(toy *data, double s) {
  for (int j = 0; j < POINTS; ++j) {
    double ds, dq;
    data->y[j] = toy_model(s, 1.0, (double)j / POINTS, &ds, &dq);
  }
}

int main(void) {
  static toy data;
  double x0[2], x1[2];
  int b0[2], b1[2];

  /* the data want s = −0.02: the minimum is at the bound s = 0 */
  make_data(&data, -0.02);
  cf_lsq_summary off = solve(&data, 0.005, 1.0, 0, x0, b0);
  cf_lsq_summary on = solve(&data, 0.005, 1.0, 1, x1, b1);
  CHECK(x1[0] == 0.0 && b1[0] == -1, "near: s = %g, at_bound %d; expected 0, -1", x1[0], b1[0]);
  CHECK(x0[0] == 0.0 && b0[0] == -1, "near, without: s = %g, at_bound %d", x0[0], b0[0]);
  CHECK(fabs(on.final_cost - off.final_cost) <= 1e-9 * off.final_cost + 1e-12,
        "near: cost %.12g with the pins, %.12g without", on.final_cost, off.final_cost);
  CHECK(fabs(x1[1] - x0[1]) <= 1e-8, "near: q %.12g with, %.12g without", x1[1], x0[1]);
  CHECK(on.iterations <= off.iterations, "near: %d iterations with the pins, %d without",
        on.iterations, off.iterations);
  printf("near: %d iterations with the pins, %d without\n", on.iterations, off.iterations);

  /* far from the minimum (q off by 2: the step's decrease is thousands):
   * no pins, the same solve */
  off = solve(&data, 0.3, 3.0, 0, x0, b0);
  on = solve(&data, 0.3, 3.0, 1, x1, b1);
  CHECK(on.iterations == off.iterations && on.final_cost == off.final_cost && x1[0] == x0[0],
        "far: %d iterations and cost %.12g with, %d and %.12g without", on.iterations,
        on.final_cost, off.iterations, off.final_cost);

  /* a minimum just inside, s = 0.01, from s = 0.03: found with or without */
  make_data(&data, 0.01);
  off = solve(&data, 0.03, 1.0, 0, x0, b0);
  on = solve(&data, 0.03, 1.0, 1, x1, b1);
  CHECK(fabs(x1[0] - 0.01) <= 1e-6 && b1[0] == 0, "inside: s = %.9g, at_bound %d with the pins",
        x1[0], b1[0]);
  CHECK(fabs(x0[0] - 0.01) <= 1e-6, "inside: s = %.9g without", x0[0]);
  printf("inside: %d iterations with the pins, %d without\n", on.iterations, off.iterations);
  return check_finish("test_lsq_newton_start");
}
