/* What a residual weighs and costs (fit_problem.h): σ of every residual
 * (the capture's noise model, or one σ, carried through the response
 * curve), the robust loss and the censored likelihood of a clipped
 * channel (fit_loss.h inlines the loss for the kernel). */
#include <math.h>
#include <stdlib.h>

#include "fit_loss.h"

/* Does the capture give a noise model with some noise in it? */
static int capture_noise(const cf_capture *capture, double *read, double *shot) {
  cf_capture_summary summary;
  cf_capture_summarize(capture, &summary);
  *read = summary.noise_read;
  *shot = summary.noise_shot;
  return summary.has_noise && (summary.noise_read > 0.0 || summary.noise_shot > 0.0);
}

int fit_capture_has_noise(const cf_capture *capture) {
  double read, shot;
  return capture_noise(capture, &read, &shot);
}

/* The noise model's variance at a decoded value μ: read² + shot · max(μ, 0);
 * with a response curve the sensor's noise, before the curve, carried
 * through it (docs/model.md §6.2): R'(x)² (read² + shot · x) at
 * x = R⁻¹(μ), R' taken at x >= the last knot (where 8-bit photos end;
 * R' finite and positive there). With the identity curve the same as
 * without one. */
static double noise_variance(const fit_problem *p, double read, double shot, double mu) {
  if (!p->response_on) return read * read + shot * fmax(mu, 0.0);
  const double *response = p->values.response;
  double x = mu > 0.0 ? cf_response_model_inverse(response, NULL, mu, NULL) : 0.0, slope;
  cf_response_model_value(response, fmax(x, cf_response_model_knot(CF_RESPONSE_MODEL_KNOTS - 1)),
                          &slope, NULL);
  return slope * slope * (read * read + shot * x);
}

/* 1/σ of the noise model at the values mu (3 per observation used: the
 * measurements or the predictions; mu may be rows.inv_sigma itself), read
 * noise `read` and shot noise `shot` (with a response curve on: through
 * the curve), the variance floored at its smallest positive value over
 * them: a dark pixel with no read noise would otherwise weigh infinitely. */
static void noise_inv_sigma(fit_problem *p, double read, double shot, const double *mu) {
  size_t n = 3 * p->rows.count;
  double *inv_sigma = p->rows.inv_sigma, floor = HUGE_VAL;
  for (size_t i = 0; i < n; ++i) {
    double v = noise_variance(p, read, shot, mu[i]);
    inv_sigma[i] = v; /* (after mu[i] is read: in place) */
    if (v > 0.0) floor = fmin(floor, v);
  }
  for (size_t i = 0; i < n; ++i) inv_sigma[i] = 1.0 / sqrt(fmax(inv_sigma[i], floor));
}

int fit_problem_sigma_through_curve(const fit_problem *p) {
  return p->rows.sigma > 0.0 && p->response_on;
}

double fit_problem_curve_slope(const fit_problem *p, double mu) {
  return sqrt(noise_variance(p, 1.0, 0.0, mu));
}

void fit_problem_set_sigma(fit_problem *p, double sigma) {
  double read, shot;
  int noise = capture_noise(p->capture, &read, &shot);
  fit_rows *r = &p->rows;
  r->sigma = noise ? 0.0 : sigma;
  int through = fit_problem_sigma_through_curve(p);
  /* one σ for all, or the measurements, turned in place into the noise
   * model's 1/σ (or τ R'(x)'s: a read noise τ alone) */
  for (size_t i = 0; i < 3 * r->count; ++i)
    r->inv_sigma[i] = noise || through ? r->y[i] : 1.0 / sqrt(sigma * sigma);
  if (noise) noise_inv_sigma(p, read, shot, r->inv_sigma);
  if (through) noise_inv_sigma(p, sigma, 0.0, r->inv_sigma);
}

cf_status fit_problem_reweight(fit_problem *p, cf_error *err) {
  double read, shot;
  if (!capture_noise(p->capture, &read, &shot)) {
    if (!fit_problem_sigma_through_curve(p)) return CF_OK;
    read = p->rows.sigma; /* τ R'(x): a read noise τ alone */
    shot = 0.0;
  }
  size_t n = 3 * p->rows.count;
  double *prediction = malloc((n ? n : 1) * sizeof *prediction);
  double *measured = malloc((n ? n : 1) * sizeof *measured);
  cf_status s = prediction && measured ? fit_problem_predict(p, prediction, measured, err)
                                       : cf_error_set(err, CF_ENOMEM, "out of memory");
  if (s == CF_OK) noise_inv_sigma(p, read, shot, prediction);
  free(prediction);
  free(measured);
  return s;
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
