/* The camera response curve (include/clayfit/response_model.h, docs/model.md
 * §5.4). */
#include "clayfit/response_model.h"

#include <math.h>

enum { K = CF_RESPONSE_MODEL_KNOTS };

/* The knots' spacing in log x: a factor 3 (1.6 stops; two stops left 3.3 % on sRGB's
 * decoding, docs/model.md §5.4). */
static double knot_step(void) {
  return log(3.0);
}

double cf_response_model_knot(int j) {
  return exp(-knot_step() * (double)j);
}

static double slope_of(const double *a, int j) {
  return a ? a[j] : 1.0;
}

double cf_response_model_basis(const double *a, double x, double *phi) {
  double t = log(x), L = knot_step();
  for (int j = 0; j < K; ++j) phi[j] = 0.0;
  if (t >= 0.0) { /* above the top knot: h_0 = 1 */
    phi[0] = t;
    return slope_of(a, 0);
  }
  /* ∫_t^0 h_j in units of L: the whole segments between knots give half
   * to each of their two hats, the last partial one its trapezoids */
  double u = -t / L, whole = floor(u);
  int full = whole < (double)(K - 1) ? (int)whole : K - 1;
  for (int s = 0; s < full; ++s) {
    phi[s] += 0.5;
    phi[s + 1] += 0.5;
  }
  double slope;
  if (full < K - 1) {
    double f = u - whole;
    phi[full] += f - 0.5 * f * f;
    phi[full + 1] += 0.5 * f * f;
    slope = (1.0 - f) * slope_of(a, full) + f * slope_of(a, full + 1);
  } else { /* below the last knot: h_{K−1} = 1 */
    phi[K - 1] += u - (double)(K - 1);
    slope = slope_of(a, K - 1);
  }
  for (int j = 0; j < K; ++j) phi[j] *= -L; /* Φ_j(t) = −∫_t^0 h_j */
  return slope;
}

double cf_response_model_value(const double *a, double x, double *dx, double *da) {
  if (!(x > 0.0)) {
    if (dx) *dx = 0.0;
    for (int j = 0; da && j < K; ++j) da[j] = 0.0;
    return 0.0;
  }
  double phi[K], log_r = 0.0;
  double slope = cf_response_model_basis(a, x, phi);
  for (int j = 0; j < K; ++j) log_r += a[j] * phi[j];
  double r = exp(log_r);
  if (dx) *dx = r * slope / x;
  for (int j = 0; da && j < K; ++j) da[j] = r * phi[j];
  return r;
}

/* log x at log R = log_y: g(t) = log R is increasing and quadratic
 * between knots, so each piece is solved exactly. */
static double inverse_log(const double *a, double log_y) {
  if (log_y >= 0.0) return log_y / a[0];
  double L = knot_step(), g = 0.0; /* g at knot i */
  for (int i = 0; i + 1 < K; ++i) {
    double next = g - 0.5 * L * (a[i] + a[i + 1]);
    if (log_y >= next) { /* between knots i and i + 1: t = t_i − L f */
      double c = (g - log_y) / L, delta = a[i + 1] - a[i];
      /* (Δ/2) f² + a_i f − c = 0, its root in [0, 1] without cancellation */
      double f = 2.0 * c / (a[i] + sqrt(fmax(0.0, a[i] * a[i] + 2.0 * delta * c)));
      return -L * ((double)i + f);
    }
    g = next;
  }
  return -L * (double)(K - 1) - (g - log_y) / a[K - 1];
}

double cf_response_model_inverse(const double *a, const double *covariance, double y,
                                 double *sd_log_x) {
  double x = exp(inverse_log(a, log(y)));
  if (sd_log_x) {
    double phi[K], var = 0.0;
    double slope = cf_response_model_basis(a, x, phi);
    for (int i = 0; covariance && i < K; ++i)
      for (int j = 0; j < K; ++j) var += phi[i] * covariance[i * K + j] * phi[j];
    *sd_log_x = sqrt(fmax(0.0, var)) / slope;
  }
  return x;
}

int cf_response_model_is_power(const double *a) {
  for (int j = 1; j < K; ++j)
    if (a[j] != a[0]) return 0;
  return 1;
}
