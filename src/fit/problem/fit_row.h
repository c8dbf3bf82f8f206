/* One row's prediction, the pieces the kernel (fit_kernel.c) and the
 * predictions (fit_predict.c) share: docs/model.md (40),
 * μ = R(s e_k b_kc Σ_m w_m Σ_j g_l(j) f E_j c_i). Inline: they run for
 * every observation of every evaluation. For src/fit/problem/ alone. */
#ifndef CLAYFIT_FIT_PROBLEM_ROW_H
#define CLAYFIT_FIT_PROBLEM_ROW_H

#include <math.h>

#include "problem.h"

/* The gain s e_k of image k's observations (with its balance b_kc). */
static inline double fit_image_gain(double log_scale, double log_exposure) {
  return exp(log_scale + log_exposure);
}

/* The model's value Σ_m w_m Σ_j E f c_i (docs/model.md (40)) of channel c
 * of an observation over its `slots` pairs, from `first` in f (3 per pair;
 * w: the pairs' weights, 3 per pair), and with grad (3 × dim per pair;
 * NULL: none) its gradient in the model's slots: *dmodel, times
 * *weight_one. With one slot that is the evaluator's gradient itself,
 * scaled later (no accumulator to zero: a zeroed array here cost a fifth
 * of the evaluation in stores); else the weighted sum, in sum (dim). */
static inline double fit_model_value(const double *w, const double *f, const double *grad,
                                     int dim, size_t first, size_t slots, int c, double *sum,
                                     const double **dmodel, double *weight_one) {
  *dmodel = sum;
  if (slots == 1) {
    *weight_one = w[c];
    if (grad) *dmodel = grad + (3 * first + (size_t)c) * (size_t)dim;
    return *weight_one * f[3 * first + (size_t)c];
  }
  *weight_one = 1.0;
  double value = 0.0;
  if (grad)
    for (int s = 0; s < dim; ++s) sum[s] = 0.0;
  for (size_t j = 0; j < slots; ++j) {
    size_t pair = first + j;
    double wj = w[3 * j + (size_t)c];
    if (wj == 0.0) continue;
    value += wj * f[3 * pair + (size_t)c];
    if (!grad) continue;
    const double *g = grad + (3 * pair + (size_t)c) * (size_t)dim;
    for (int s = 0; s < dim; ++s) sum[s] += wj * g[s];
  }
  return value;
}

/* Image `image`'s slots' gains g_l (slot_gain, lights; 1 for a slot
 * without light) from the lights' log gains. */
static inline void fit_image_slot_gains(const fit_problem *p, const double *log_g, uint32_t image,
                                        double *slot_gain) {
  const long *id = p->groups.slot_light + (size_t)image * (size_t)p->rows.lights;
  for (int j = 0; j < p->rows.lights; ++j) slot_gain[j] = id[j] < 0 ? 1.0 : exp(log_g[id[j]]);
}

/* An observation's pair weights (w, 3 per pair) times their lights' gains,
 * into out; pair j is light slot j mod lights (fit_rows.slot_begin). */
static inline const double *fit_light_weighted(const fit_problem *p, const double *slot_gain,
                                               const double *w, size_t slots, double *out) {
  for (size_t j = 0; j < slots; ++j) {
    double g = slot_gain[j % (size_t)p->rows.lights];
    for (int c = 0; c < 3; ++c) out[3 * j + (size_t)c] = g * w[3 * j + (size_t)c];
  }
  return out;
}

/* The prediction μ of a channel from its linear value, gain · model
 * (docs/model.md (40)): the linear value itself, or with a response
 * curve, R(linear) (0 where the linear value is not positive: no light,
 * no prediction). With chain non-NULL, also ∂μ/∂linear (1 without a
 * response) and, with a response, in dslope ∂μ/∂a_j (CF_RESPONSE_MODEL_KNOTS;
 * untouched without one: no slope is free then). */
static inline double fit_predict_channel(int response_on, const double *response, double linear,
                                         double *chain, double *dslope) {
  if (chain) *chain = 1.0;
  if (!response_on) return linear;
  return cf_response_model_value(response, linear, chain, dslope);
}

#endif /* CLAYFIT_FIT_PROBLEM_ROW_H */
