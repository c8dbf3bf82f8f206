/* The uncertainty of a fit (fit_uncertainty.h). */
#include "fit_uncertainty.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fit_plan.h"
#include "lsq/linalg.h"
#include "lsq/lsq.h"

/* A model slot's standard deviation from its unknown's variance:
 * dρ = ρ d log ρ; dσ = dσ² / (2σ), and at σ = 0, where σ = √σ² is not
 * differentiable, the half-width √sd(σ²) (σ² <= sd(σ²) within one sd). */
double fit_slot_sd(const fit_problem *p, const fit_unknown *unk, double variance) {
  double sd = sqrt(fmax(0.0, variance)), x = p->params[unk->slot];
  if (unk->kind == FIT_LOG_SLOT) return x * sd;
  if (unk->kind == FIT_SQUARE_SLOT) return x > 0.5 * sqrt(sd) ? sd / (2.0 * x) : sqrt(sd);
  return sd;
}

/* The model slots' block of JᵀJ, each column scaled to its range's width
 * (∂/∂ρ = ∂/∂log ρ / ρ). */
static int scaled_model_block(const fit_problem *p, const double *jtj, int *slots, double *h) {
  int n = p->num_unknowns, m = 0;
  int map[CF_MAX_DIM];
  double width[CF_MAX_DIM];
  for (int u = 0; u < n && m < CF_MAX_DIM; ++u) {
    const fit_unknown *unk = &p->unknowns[u];
    if (!fit_unknown_is_model(unk->kind) || p->at_bound[u]) continue;
    map[m] = u;
    slots[m] = unk->slot;
    width[m] = unk->kind == FIT_LOG_SLOT ? fit_slot_width(p, unk->slot) / p->params[unk->slot]
                                         : p->upper[u] - p->lower[u];
    ++m;
  }
  for (int a = 0; a < m; ++a)
    for (int c = 0; c < m; ++c) h[a * m + c] = jtj[map[a] * n + map[c]] * width[a] * width[c];
  return m;
}

/* The covariance of the unknowns not at a bound (those at one are held
 * there: their rows and columns are 0). */
cf_status fit_free_covariance(const fit_problem *p, const double *jtj, double *covariance,
                              int *rank_deficient, cf_error *err) {
  int n = p->num_unknowns, m = 0;
  int *map = malloc((size_t)n * sizeof *map);
  double *sub = malloc((size_t)n * (size_t)n * sizeof *sub);
  double *sub_covariance = malloc((size_t)n * (size_t)n * sizeof *sub_covariance);
  cf_status s =
      map && sub && sub_covariance ? CF_OK : cf_error_set(err, CF_ENOMEM, "out of memory");
  for (int u = 0; s == CF_OK && u < n; ++u)
    if (!p->at_bound[u]) map[m++] = u;
  for (int a = 0; s == CF_OK && a < m; ++a)
    for (int b = 0; b < m; ++b) sub[a * m + b] = jtj[map[a] * n + map[b]];
  *rank_deficient = 0;
  if (s == CF_OK && m > 0) s = cf_lsq_covariance(m, sub, sub_covariance, rank_deficient, err);
  if (s == CF_OK) {
    memset(covariance, 0, (size_t)n * (size_t)n * sizeof *covariance);
    for (int a = 0; !*rank_deficient && a < m; ++a)
      for (int b = 0; b < m; ++b) covariance[map[a] * n + map[b]] = sub_covariance[a * m + b];
  }
  free(map);
  free(sub);
  free(sub_covariance);
  return s;
}

cf_status fit_sample_covariance(fit_problem *p, int threads, double *covariance, cf_error *err) {
  if (!p->sample_root) return CF_OK;
  size_t n = (size_t)p->num_unknowns;
  double *roots = malloc((p->count ? p->count : 1) * sizeof *roots);
  double *b = malloc(n * n * sizeof *b), *bc = malloc(n * n * sizeof *bc);
  cf_status s = roots && b && bc ? CF_OK : cf_error_set(err, CF_ENOMEM, "out of memory");
  if (s == CF_OK) { /* B: each row weighed by w instead of √w */
    memcpy(roots, p->sample_root, p->count * sizeof *roots);
    for (size_t i = 0; i < p->count; ++i) p->sample_root[i] = roots[i] * roots[i];
    s = fit_normal_equations(p, threads, b, NULL, NULL, err);
    memcpy(p->sample_root, roots, p->count * sizeof *roots);
  }
  if (s == CF_OK) { /* A⁻¹ B A⁻¹ (A⁻¹ is 0 on the rows and columns at a bound) */
    for (size_t i = 0; i < n; ++i)
      for (size_t j = 0; j < n; ++j) {
        double sum = 0.0;
        for (size_t k = 0; k < n; ++k) sum += b[i * n + k] * covariance[k * n + j];
        bc[i * n + j] = sum;
      }
    for (size_t i = 0; i < n; ++i)
      for (size_t j = 0; j < n; ++j) {
        double sum = 0.0;
        for (size_t k = 0; k < n; ++k) sum += covariance[i * n + k] * bc[k * n + j];
        b[i * n + j] = sum;
      }
    for (size_t i = 0; i < n; ++i) /* symmetric to the last bit */
      for (size_t j = 0; j < n; ++j) covariance[i * n + j] = 0.5 * (b[i * n + j] + b[j * n + i]);
  }
  free(roots);
  free(b);
  free(bc);
  return s;
}

/* Mark the model slots that no observation moves: a column of the
 * Jacobian that is exactly 0 (the ones merely small are the eigenvalues'
 * and the hidden base's to judge). A slot at a bound too: the solver's
 * active set can hold one there that the data never touched (an albedo
 * started at its floor in a channel no light has), and it is not
 * "fitted". */
static int mark_unmoved(const fit_problem *p, const double *jtj, fit_plan *plan) {
  int found = 0;
  for (int u = 0; u < p->num_unknowns; ++u)
    if (fit_unknown_is_model(p->unknowns[u].kind) &&
        !(jtj[(size_t)u * (size_t)p->num_unknowns + (size_t)u] > 0.0)) {
      plan->status[p->unknowns[u].slot] = CF_PARAM_UNCONSTRAINED;
      found = 1;
    }
  return found;
}

/* Mark the model slots the capture does not constrain: those no
 * observation moves, those that carry the eigenvectors of the
 * (width-scaled) normal matrix whose eigenvalues are negligible, or whose
 * standard deviation exceeds half their range. */
cf_status fit_find_unconstrained(fit_problem *p, const double *jtj, const double *covariance,
                                 int rank_deficient, fit_plan *plan, int *found, cf_error *err) {
  *found = mark_unmoved(p, jtj, plan);
  if (*found) return CF_OK;
  if (covariance && !rank_deficient) {
    for (int u = 0; u < p->num_unknowns; ++u) {
      const fit_unknown *unk = &p->unknowns[u];
      if (!fit_unknown_is_model(unk->kind) || p->at_bound[u]) continue;
      double sd = fit_slot_sd(p, unk, covariance[u * p->num_unknowns + u]);
      if (sd > 0.5 * fit_slot_width(p, unk->slot)) {
        plan->status[p->unknowns[u].slot] = CF_PARAM_UNCONSTRAINED;
        *found = 1;
      }
    }
    return CF_OK;
  }
  int slots[CF_MAX_DIM];
  double h[CF_MAX_DIM * CF_MAX_DIM], values[CF_MAX_DIM], vectors[CF_MAX_DIM * CF_MAX_DIM];
  int m = scaled_model_block(p, jtj, slots, h);
  if (m == 0) return CF_OK;
  if (!cf_symmetric_eigen(m, h, values, vectors))
    return cf_error_set(err, CF_ENUMERIC, "the normal matrix of the model's slots is not finite");
  double largest = 0.0;
  for (int i = 0; i < m; ++i) largest = fmax(largest, values[i]);
  int weakest = 0;
  for (int i = 0; i < m; ++i) {
    if (values[i] < values[weakest]) weakest = i;
    if (values[i] > 1e-10 * largest) continue;
    for (int k = 0; k < m; ++k)
      if (fabs(vectors[k * m + i]) > 0.3) {
        plan->status[slots[k]] = CF_PARAM_UNCONSTRAINED;
        *found = 1;
      }
  }
  if (!*found) { /* the solver saw a deficiency: name the weakest direction's largest part */
    int best = 0;
    for (int k = 1; k < m; ++k)
      if (fabs(vectors[k * m + weakest]) > fabs(vectors[best * m + weakest])) best = k;
    plan->status[slots[best]] = CF_PARAM_UNCONSTRAINED;
    *found = 1;
  }
  return CF_OK;
}
