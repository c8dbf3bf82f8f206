/* What a residual costs: the robust loss and the censored likelihood of a
 * clipped channel (fit_problem.h, fit_loss.h). */
#include "fit_loss.h"

void fit_problem_set_loss(fit_problem *p, cf_loss loss, double scale) {
  p->loss = loss;
  p->loss_scale = scale;
}

double fit_problem_loss_weight(const fit_problem *p, double s) {
  double rho1 = 1.0;
  fit_robust(p, s, &rho1);
  return rho1;
}

int fit_problem_censored(const fit_problem *p, size_t i, double prediction, double measured) {
  return fit_censored_at(p, i / 3, (int)(i % 3), prediction, measured);
}

double fit_censored_residual(double z, double *slope) {
  /* beyond 30, 1 − Φ(z) is below 1e-197 (t² would underflow) */
  if (!(z < 30.0)) {
    *slope = 0.0;
    return 0.0;
  }
  if (z < -37.0) { /* erfc underflows: Φ(z) = φ(z)/(−z) (1 − 1/z² + 3/z⁴ − …) */
    double w = 1.0 / (z * z), series = 1.0 - w + 3.0 * w * w;
    double t = -sqrt(z * z + 2.0 * log(-z) + 1.8378770664093453 - 2.0 * log(series));
    double dseries = (2.0 * w - 12.0 * w * w) / z; /* d series / dz */
    *slope = (z + 1.0 / z - dseries / series) / t;
    return t;
  }
  double tail = 0.5 * erfc(z / sqrt(2.0)); /* 1 − Φ(z) */
  double phi_cdf = 0.5 * erfc(-z / sqrt(2.0));
  double cost = -2.0 * (z > 0.0 ? log1p(-tail) : log(phi_cdf));
  if (!(cost > 0.0)) {
    *slope = 0.0;
    return 0.0;
  }
  double t = sqrt(cost), density = 0.3989422804014327 * exp(-0.5 * z * z); /* φ(z) */
  *slope = density / (phi_cdf * t);
  return -t;
}
