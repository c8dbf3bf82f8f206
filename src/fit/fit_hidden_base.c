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
  size_t n = 3 * fit_problem_count(p);
  const double *root = fit_problem_sample_roots(p), *inv_sigma = fit_problem_inv_sigma(p);
  double *full = malloc((n ? n : 1) * sizeof *full), *top = malloc((n ? n : 1) * sizeof *top);
  double *measured = malloc((n ? n : 1) * sizeof *measured);
  cf_status s = full && top && measured ? fit_problem_predict(p, full, measured, err)
                                        : cf_error_set(err, CF_ENOMEM, "out of memory");
  double saved[3], *params = fit_problem_values(p)->params;
  memcpy(saved, params + CF_CLAY_OPTICAL_DEPTH, sizeof saved);
  /* τ = 400, 50 × its bound: e^(−τ P) < 1e-173, the base's light gone (a derivation) */
  for (int c = 0; c < 3; ++c) params[CF_CLAY_OPTICAL_DEPTH + c] = 400.0;
  if (s == CF_OK) s = fit_problem_predict(p, top, measured, err);
  memcpy(params + CF_CLAY_OPTICAL_DEPTH, saved, sizeof saved);
  *chi2 = 0.0;
  for (size_t i = 0; s == CF_OK && i < n; ++i) {
    if (fit_problem_censored(p, i, full[i], measured[i])) continue;
    double d = (full[i] - top[i]) * inv_sigma[i] * (root ? root[i / 3] : 1.0);
    *chi2 += d * d;
  }
  free(full);
  free(top);
  free(measured);
  return s;
}

/* The film alone: the base's free slots held (τ at its upper bound,
 * where the film hides the base; the others at their defaults), into
 * `alone` and p's values. */
static void hide_base(fit_problem *p, const fit_plan *plan, fit_plan *alone) {
  double defaults[CF_MAX_DIM], *params = fit_problem_values(p)->params;
  cf_model_default_params(fit_problem_model(p), defaults);
  double tau_upper = cf_param_info_get(CF_PARAM_OPTICAL_DEPTH)->upper;
  *alone = *plan;
  for (int k = 0; k < CF_CLAY_DIM; ++k) {
    if (!is_base_slot(k) || !is_free(plan->status[k])) continue;
    alone->status[k] = CF_PARAM_UNCONSTRAINED;
    params[k] = k >= CF_CLAY_OPTICAL_DEPTH && k < CF_CLAY_OPTICAL_DEPTH + 3 ? tau_upper : defaults[k];
  }
}

/* The film alone, fitted and compared by BIC with the fit of cost `cost`:
 * adopted (its plan into *plan) when the base is not seen, else the
 * problem back where the test began (its values and pins). */
static cf_status compare_film_alone(fit_problem *p, fit_plan *plan, const cf_fit_options *o,
                                    double cost, fit_hidden_base *out, cf_error *err) {
  size_t unknowns = (size_t)fit_problem_unknown_count(p);
  int *at_bound = malloc((unknowns ? unknowns : 1) * sizeof *at_bound);
  fit_values saved = {0};
  cf_status s = at_bound ? fit_values_save(p, &saved, err)
                         : cf_error_set(err, CF_ENOMEM, "out of memory");
  if (s != CF_OK) {
    free(at_bound);
    return s;
  }
  memcpy(at_bound, fit_problem_read_at_bound(p), unknowns * sizeof *at_bound);
  fit_plan alone;
  hide_base(p, plan, &alone);
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
    fit_values_restore(p, &saved);
    cf_status restored = fit_declare(p, plan, err);
    if (restored == CF_OK) memcpy(fit_problem_at_bound(p), at_bound, unknowns * sizeof *at_bound);
    if (s == CF_OK) s = restored;
  }
  free(at_bound);
  fit_values_free(&saved);
  return s;
}

cf_status fit_test_hidden_base(fit_problem *p, fit_plan *plan, const cf_fit_options *o, double cost,
                               fit_hidden_base *out, cf_error *err) {
  memset(out, 0, sizeof *out);
  /* M4 and M4T (whose vector starts with M4's) */
  if (cf_model_info_get(fit_problem_model(p))->ggx_twin != CF_MODEL_CLAY) return CF_OK;
  for (int k = 0; k < CF_CLAY_DIM; ++k) out->slots += is_base_slot(k) && is_free(plan->status[k]);
  if (out->slots == 0) return CF_OK;
  size_t n = 3 * fit_problem_count(p);
  cf_status s = base_contribution(p, &out->visible, err);
  /* 100 σ² a residual: plainly visible (9156243; 2 of 161 test fits below; 50, 200: none moves) */
  if (s != CF_OK || out->visible > 100.0 * (double)n) return s;
  out->tested = 1;
  out->price = out->slots * log((double)n);
  return compare_film_alone(p, plan, o, cost, out, err);
}
