/* The camera response model a fit recovers when a capture's tone curve is
 * unknown (docs/model.md §5.4; the true curves synth renders through are
 * cf_response, image.h): R maps the model's linear value x (the gain
 * times the reflectance model) to the decoded photo value y.
 *
 * R is a log-log slope spline: log R is a function of t = log x whose
 * slope is piecewise linear in t through K knots at x = 1, 1/3, 1/9, ...
 * (t_j = −j log 3), constant beyond the first and the last knot, with the
 * knots' slopes a_j > 0 as parameters:
 *
 *   log R(x) = Σ_j a_j Φ_j(log x),   Φ_j(t) = ∫_0^t h_j(τ) dτ,
 *
 * h_j the hat functions of the knots (Σ_j h_j = 1). Monotone for any
 * a_j > 0 (d log R / d log x = Σ a_j h_j > 0), R(0) = 0 and R(1) = 1 (the
 * gauge: the scale s absorbs the level), a power x^γ exactly when every
 * a_j = γ (the identity when every a_j = 1). Pure C and libm. */
#ifndef CLAYFIT_RESPONSE_MODEL_H
#define CLAYFIT_RESPONSE_MODEL_H

#ifdef __cplusplus
extern "C" {
#endif

/* The knots: x = 3^−j, j = 0 … CF_RESPONSE_MODEL_KNOTS − 1 (1 down to 1/243,
 * where 8-bit photos end). Six knots 1.6 stops apart: with five 2 stops
 * apart sRGB's decoding (linear photos declared sRGB) was off by 3.3 %
 * relative at best, with six by 0.4 %. */
#define CF_RESPONSE_MODEL_KNOTS 6
/* The slopes' range: from a curve far flatter than sRGB's (sRGB's slope
 * is 0.44 at the top) to a toe far steeper than a filmic curve's; > 0
 * keeps R strictly increasing. */
#define CF_RESPONSE_MODEL_SLOPE_LOWER 0.1
#define CF_RESPONSE_MODEL_SLOPE_UPPER 10.0
/* The name fit.json gives the model. */
#define CF_RESPONSE_MODEL_NAME "log_log_slope_spline"

/* Knot j's linear value 3^−j. */
double cf_response_model_knot(int j);

/* Φ_j(log x) for every knot into phi (CF_RESPONSE_MODEL_KNOTS): ∂ log R / ∂a_j.
 * Returns the slope Σ a_j h_j(log x) = d log R / d log x at x (a NULL:
 * every a_j = 1). x > 0. */
double cf_response_model_basis(const double *a, double x, double *phi);

/* R(x) for slopes a; with dx non-NULL also dR/dx, with da non-NULL
 * ∂R/∂a_j (CF_RESPONSE_MODEL_KNOTS). R = 0 (and its derivatives 0) where
 * x <= 0: no light, no value. */
double cf_response_model_value(const double *a, double x, double *dx, double *da);

/* The x with R(x) = y (y > 0), and with sd_log_x non-NULL the standard
 * deviation of log x at that y given the slopes' covariance (K × K,
 * row-major; NULL: 0): d log x = −Σ Φ_j da_j / slope. */
double cf_response_model_inverse(const double *a, const double *covariance, double y,
                                 double *sd_log_x);

/* Is the curve a power (every slope the same)? */
int cf_response_model_is_power(const double *a);

#ifdef __cplusplus
}
#endif

#endif /* CLAYFIT_RESPONSE_MODEL_H */
