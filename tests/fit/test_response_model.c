/* The fitted camera response curve (include/clayfit/response_model.h):
 *   - R is strictly increasing, positive, R(1) = 1 and R(0) = 0 for slopes
 *     anywhere in their box (random and at the corners);
 *   - every slope 1 is the identity and every slope γ the power x^γ, to
 *     rounding (the old response exponent is a special case);
 *   - dR/dx and ∂R/∂a_j agree with central differences;
 *   - the inverse undoes R, and its sd of log x agrees with the delta
 *     method by finite differences;
 *   - the curve reaches sRGB's encoding within 0.1 % of full scale at the
 *     slopes a least-squares fit finds (docs/fitting.md), which the model's
 *     knots were chosen for. */
#include <math.h>
#include <stdlib.h>

#include "clayfit/image.h"
#include "clayfit/response_model.h"
#include "support/check.h"

CHECK_MAIN_STATE;

enum { K = CF_RESPONSE_MODEL_KNOTS };

static double uniform(unsigned *state) {
  *state = *state * 1664525u + 1013904223u;
  return (double)(*state >> 8) / (double)(1u << 24);
}

/* Slopes drawn log-uniformly in the box, or (corner >= 0) at the box's
 * corner with bits `corner`. */
static void draw_slopes(unsigned *state, int corner, double *a) {
  double lo = log(CF_RESPONSE_MODEL_SLOPE_LOWER), hi = log(CF_RESPONSE_MODEL_SLOPE_UPPER);
  for (int j = 0; j < K; ++j)
    a[j] = corner >= 0 ? exp((corner >> j & 1) ? hi : lo) : exp(lo + (hi - lo) * uniform(state));
}

static void test_monotone(void) {
  unsigned state = 17u;
  for (int trial = 0; trial < 200 + (1 << K); ++trial) {
    double a[K];
    draw_slopes(&state, trial < (1 << K) ? trial : -1, a);
    double last = 0.0;
    int increasing = 1;
    for (int i = 0; i <= 400; ++i) { /* x from 2^−14 to 2^3: past both ends */
      double x = exp2(-14.0 + 17.0 * i / 400.0), dx;
      double r = cf_response_model_value(a, x, &dx, NULL);
      increasing &= r > last && dx > 0.0 && isfinite(r);
      last = r;
    }
    CHECK(increasing, "trial %d: not strictly increasing", trial);
    CHECK(fabs(cf_response_model_value(a, 1.0, NULL, NULL) - 1.0) < 1e-15, "trial %d: R(1)", trial);
    CHECK(cf_response_model_value(a, 0.0, NULL, NULL) == 0.0, "R(0)");
    CHECK(cf_response_model_value(a, -0.1, NULL, NULL) == 0.0, "R(-0.1)");
  }
}

static void test_special_cases(void) {
  const double gammas[] = {1.0, 0.45, 1.0 / 2.2, 1.5, 2.2, 0.25, 4.0};
  for (size_t g = 0; g < sizeof gammas / sizeof gammas[0]; ++g) {
    double a[K], worst = 0.0;
    for (int j = 0; j < K; ++j) a[j] = gammas[g];
    CHECK(cf_response_model_is_power(a), "is_power");
    for (int i = 0; i <= 300; ++i) {
      double x = exp2(-12.0 + 14.0 * i / 300.0);
      double r = cf_response_model_value(a, x, NULL, NULL);
      worst = fmax(worst, fabs(r / pow(x, gammas[g]) - 1.0));
    }
    CHECK(worst < 1e-13, "every slope %g: off the power by %.3g relative", gammas[g], worst);
  }
  double b[K] = {1, 1, 1, 1, 1, 1.01};
  CHECK(!cf_response_model_is_power(b), "is_power of a curve");
}

static void test_derivatives(void) {
  unsigned state = 5u;
  double worst_x = 0.0, worst_a = 0.0;
  for (int trial = 0; trial < 100; ++trial) {
    double a[K];
    draw_slopes(&state, -1, a);
    for (int j = 0; j < K; ++j) a[j] = fmin(a[j], 3.0); /* keep R within doubles at 2^−12 */
    for (int i = 0; i < 40; ++i) {
      double x = exp2(-12.0 + 14.0 * uniform(&state)), dx, da[K];
      double r = cf_response_model_value(a, x, &dx, da);
      double h = 1e-6 * x;
      double fd = (cf_response_model_value(a, x + h, NULL, NULL) -
                   cf_response_model_value(a, x - h, NULL, NULL)) /
                  (2.0 * h);
      worst_x = fmax(worst_x, fabs(fd - dx) / (fabs(dx) + 1e-300));
      for (int j = 0; j < K; ++j) {
        double up[K], down[K];
        for (int q = 0; q < K; ++q) up[q] = down[q] = a[q];
        up[j] += 1e-6;
        down[j] -= 1e-6;
        double fa = (cf_response_model_value(up, x, NULL, NULL) -
                     cf_response_model_value(down, x, NULL, NULL)) /
                    2e-6;
        worst_a = fmax(worst_a, fabs(fa - da[j]) / (r + 1e-300));
      }
    }
  }
  CHECK(worst_x < 1e-6, "dR/dx off its central difference by %.3g relative", worst_x);
  CHECK(worst_a < 1e-7, "dR/da off its central difference by %.3g of R", worst_a);
}

static void test_inverse(void) {
  unsigned state = 9u;
  double worst = 0.0, worst_sd = 0.0;
  for (int trial = 0; trial < 100; ++trial) {
    double a[K], covariance[K * K];
    draw_slopes(&state, -1, a);
    for (int j = 0; j < K; ++j) a[j] = fmin(a[j], 3.0);
    for (int i = 0; i < K; ++i) /* a covariance: diagonal, correlated neighbours */
      for (int j = 0; j < K; ++j)
        covariance[i * K + j] = i == j ? 1e-4 * (1 + i) : abs(i - j) == 1 ? 2e-5 : 0.0;
    for (int i = 0; i < 30; ++i) {
      double y = exp2(-8.0 + 9.0 * uniform(&state)), sd;
      double x = cf_response_model_inverse(a, covariance, y, &sd);
      worst = fmax(worst, fabs(cf_response_model_value(a, x, NULL, NULL) / y - 1.0));
      /* the delta method by hand: ∂ log x / ∂a_j by central differences */
      double g[K], var = 0.0;
      for (int j = 0; j < K; ++j) {
        double up[K], down[K];
        for (int q = 0; q < K; ++q) up[q] = down[q] = a[q];
        up[j] += 1e-6;
        down[j] -= 1e-6;
        g[j] = (log(cf_response_model_inverse(up, NULL, y, NULL)) -
                log(cf_response_model_inverse(down, NULL, y, NULL))) /
               2e-6;
      }
      for (int p = 0; p < K; ++p)
        for (int q = 0; q < K; ++q) var += g[p] * covariance[p * K + q] * g[q];
      worst_sd = fmax(worst_sd, fabs(sqrt(var) - sd) / (sd + 1e-6)); /* (sd → 0 at y = 1) */
    }
  }
  CHECK(worst < 1e-12, "R(R^-1(y)) off y by %.3g relative", worst);
  CHECK(worst_sd < 1e-5, "sd(log x) off the delta method by %.3g relative", worst_sd);
  double identity[K] = {1, 1, 1, 1, 1, 1};
  CHECK(fabs(cf_response_model_inverse(identity, NULL, 0.3, NULL) - 0.3) < 1e-15, "identity");
}

/* sRGB's encoding from a small least-squares fit of the slopes
 * (linear least squares on log R, which is linear in them) over x in
 * [1/256, 1]. */
static void test_represents_srgb(void) {
  enum { N = 200 };
  double ata[K * K] = {0}, atb[K] = {0};
  for (int i = 0; i < N; ++i) {
    double x = exp2(-8.0 * i / (N - 1)), phi[K];
    cf_response_model_basis(NULL, x, phi);
    double target = log(cf_linear_to_srgb(x));
    for (int p = 0; p < K; ++p) {
      atb[p] += phi[p] * target;
      for (int q = 0; q < K; ++q) ata[p * K + q] += phi[p] * phi[q];
    }
  }
  for (int c = 0; c < K; ++c) /* Gauss-Jordan on the normal equations */
    for (int r = 0; r < K; ++r) {
      if (r == c) continue;
      double f = ata[r * K + c] / ata[c * K + c];
      for (int q = 0; q < K; ++q) ata[r * K + q] -= f * ata[c * K + q];
      atb[r] -= f * atb[c];
    }
  double a[K], worst = 0.0;
  for (int j = 0; j < K; ++j) a[j] = atb[j] / ata[j * K + j];
  for (int i = 0; i < N; ++i) {
    double x = exp2(-8.0 * i / (N - 1));
    worst = fmax(worst, fabs(cf_response_model_value(a, x, NULL, NULL) - cf_linear_to_srgb(x)));
  }
  CHECK(worst < 1e-3, "sRGB off by %.3g of full scale at its best slopes", worst);
}

int main(void) {
  test_monotone();
  test_special_cases();
  test_derivatives();
  test_inverse();
  test_represents_srgb();
  return check_finish("test_response_model");
}
