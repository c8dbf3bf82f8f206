/* The camera response curve's slopes as unknowns (kind.h), for photos
 * whose tone curve is unknown: the prediction is R(s e_k Σ f E c_i)
 * (clayfit/response_model.h, docs/model.md §5.4). Its smoothness prior
 * is the kernel's (fit_kernel.c, response_prior). */
#include "problem.h"

void fit_problem_free_response(fit_problem *p) {
  for (int j = 0; j < CF_RESPONSE_MODEL_KNOTS; ++j)
    fit_unknowns_add(p, &fit_kind_response, j, CF_RESPONSE_MODEL_SLOPE_LOWER,
                     CF_RESPONSE_MODEL_SLOPE_UPPER);
  p->response_on = 1;
}

void fit_response_identity(double *slopes) {
  for (int j = 0; j < CF_RESPONSE_MODEL_KNOTS; ++j) slopes[j] = 1.0;
}

int fit_response_is_identity(const double *slopes) {
  for (int j = 0; j < CF_RESPONSE_MODEL_KNOTS; ++j)
    if (slopes[j] != 1.0) return 0;
  return 1;
}

static double get(const fit_problem *p, const fit_values *v, int slot) {
  (void)p;
  return v->response[slot];
}

static void set(const fit_problem *p, const double *x, const fit_unknown *u, int count,
                fit_values *v) {
  (void)p;
  for (int i = 0; i < count; ++i) v->response[u[i].slot] = x[i];
}

const fit_kind fit_kind_response = {
    .name = "response slope", .handle = FIT_HANDLE_SLOPE, .get = get, .set = set};
