/* M4's base when the photos do not show it (fit_hidden_base.h). */
#include "fit_hidden_base.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The slots of M4's base: albedo, σ, τ, r2, F0_2. */
static int is_base_slot(int k) {
  return k < CF_CLAY_FILM_ROUGHNESS || (k >= CF_CLAY_OPTICAL_DEPTH && k <= CF_CLAY_BASE_F0);
}

static int is_free(cf_param_status status) {
  return status == CF_PARAM_FITTED || status == CF_PARAM_AT_BOUND;
}

/* χ² of the base's whole contribution at the current values: the model
 * against its top specular alone. */
static cf_status base_contribution(fit_problem *p, double *chi2, cf_error *err) {
  size_t n = 3 * p->count;
  double *full = malloc(n * sizeof *full), *top = malloc(n * sizeof *top);
  double *measured = malloc(n * sizeof *measured);
  cf_status s = full && top && measured ? fit_problem_predict(p, full, measured, err)
                                        : cf_error_set(err, CF_ENOMEM, "out of memory");
  double saved[3];
  memcpy(saved, p->params + CF_CLAY_OPTICAL_DEPTH, sizeof saved);
  for (int c = 0; c < 3; ++c) p->params[CF_CLAY_OPTICAL_DEPTH + c] = 400.0;
  if (s == CF_OK) s = fit_problem_predict(p, top, measured, err);
  memcpy(p->params + CF_CLAY_OPTICAL_DEPTH, saved, sizeof saved);
  *chi2 = 0.0;
  for (size_t i = 0; s == CF_OK && i < n; ++i) {
    if (fit_problem_censored(p, i, full[i], measured[i])) continue;
    double root = p->sample_root ? p->sample_root[i / 3] : 1.0;
    double d = (full[i] - top[i]) * p->inv_sigma[i] * root;
    *chi2 += d * d;
  }
  free(full);
  free(top);
  free(measured);
  return s;
}

cf_status fit_test_hidden_base(fit_problem *p, fit_plan *plan, const cf_fit_options *o, double cost,
                               fit_hidden_base *out, cf_error *err) {
  memset(out, 0, sizeof *out);
  /* M4 and M4T (whose vector starts with M4's) */
  if (cf_model_info_get(p->model)->ggx_twin != CF_MODEL_CLAY) return CF_OK;
  for (int k = 0; k < CF_CLAY_DIM; ++k) out->slots += is_base_slot(k) && is_free(plan->status[k]);
  if (out->slots == 0) return CF_OK;
  size_t n = 3 * p->count;
  cf_status s = base_contribution(p, &out->visible, err);
  if (s != CF_OK || out->visible > 100.0 * (double)n) return s;
  out->tested = 1;
  out->price = out->slots * log((double)n);

  /* the film alone: the base hidden under τ at its bound */
  double params[CF_MAX_DIM], log_scale = p->log_scale, response[CF_RESPONSE_MODEL_KNOTS];
  memcpy(response, p->response, sizeof response);
  size_t unknowns = (size_t)p->num_unknowns;
  memcpy(params, p->params, sizeof params);
  int *at_bound = malloc((unknowns ? unknowns : 1) * sizeof *at_bound);
  double *log_exposures = malloc((p->images ? p->images : 1) * sizeof *log_exposures);
  double *log_balance = malloc(3 * (p->images ? p->images : 1) * sizeof *log_balance);
  double *log_light = malloc((p->light_count ? p->light_count : 1) * sizeof *log_light);
  if (!at_bound || !log_exposures || !log_balance || !log_light) {
    free(at_bound);
    free(log_exposures);
    free(log_balance);
    free(log_light);
    return cf_error_set(err, CF_ENOMEM, "out of memory");
  }
  memcpy(at_bound, p->at_bound, unknowns * sizeof *at_bound);
  memcpy(log_exposures, p->log_exposures, p->images * sizeof *log_exposures);
  memcpy(log_balance, p->log_balance, 3 * p->images * sizeof *log_balance);
  memcpy(log_light, p->log_light, p->light_count * sizeof *log_light);
  fit_plan alone = *plan;
  double defaults[CF_MAX_DIM];
  cf_model_default_params(p->model, defaults);
  double tau_upper = cf_param_info_get(CF_PARAM_OPTICAL_DEPTH)->upper;
  for (int k = 0; k < CF_CLAY_DIM; ++k) {
    if (!is_base_slot(k) || !is_free(plan->status[k])) continue;
    alone.status[k] = CF_PARAM_UNCONSTRAINED;
    p->params[k] =
        k >= CF_CLAY_OPTICAL_DEPTH && k < CF_CLAY_OPTICAL_DEPTH + 3 ? tau_upper : defaults[k];
  }
  cf_lsq_summary summary;
  s = fit_declare(p, &alone, err);
  if (s == CF_OK) s = fit_solve(p, o, o->max_iterations, &summary, err);
  if (s == CF_OK) {
    out->gain = 2.0 * (summary.final_cost - cost);
    out->hidden = out->gain < out->price;
  }
  if (s == CF_OK && out->hidden) {
    *plan = alone;
  } else { /* the base stays: back to where the test began */
    memcpy(p->params, params, sizeof params);
    p->log_scale = log_scale;
    memcpy(p->response, response, sizeof response);
    memcpy(p->log_exposures, log_exposures, p->images * sizeof *log_exposures);
    memcpy(p->log_balance, log_balance, 3 * p->images * sizeof *log_balance);
    memcpy(p->log_light, log_light, p->light_count * sizeof *log_light);
    cf_status restored = fit_declare(p, plan, err);
    if (restored == CF_OK) memcpy(p->at_bound, at_bound, unknowns * sizeof *at_bound);
    if (s == CF_OK) s = restored;
  }
  free(at_bound);
  free(log_exposures);
  free(log_balance);
  free(log_light);
  return s;
}
