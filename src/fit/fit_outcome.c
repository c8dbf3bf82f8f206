/* The result of a fit from its solved problem (fit_outcome.h): the values
 * of every kind of unknown with their standard deviations, the solver's
 * summary and the warnings the result calls for. */
#include "fit_outcome.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fit_gains.h"
#include "fit_multistart.h"
#include "fit_uncertainty.h"

void fit_add_warning(cf_fit_result *r, const char *format, ...) {
  if (r->warning_count == CF_FIT_MAX_WARNINGS) return;
  va_list args;
  va_start(args, format);
  vsnprintf(r->warnings[r->warning_count++], sizeof r->warnings[0], format, args);
  va_end(args);
}

/* The response's covariance: the row of its unknown u (a slope) against
 * the other slopes'. */
static void response_covariance(const fit_problem *p, const double *covariance, int u,
                                cf_fit_result *r) {
  int n = fit_problem_unknown_count(p), a = fit_problem_unknown(p, u).slot;
  for (int v = 0; v < n; ++v) {
    fit_unknown other = fit_problem_unknown(p, v);
    if (other.kind == &fit_kind_response)
      r->response_covariance[a * CF_RESPONSE_MODEL_KNOTS + other.slot] = covariance[u * n + v];
  }
}

/* The model's free slots: each one's sd (or its status at a bound), and
 * the correlation of those with an sd. */
static void material_of(const fit_problem *p, const double *covariance, cf_fit_result *r) {
  const int *at_bound = fit_problem_read_at_bound(p);
  int n = fit_problem_unknown_count(p), map[CF_MAX_DIM];
  r->free_count = 0;
  for (int u = 0; u < n; ++u) {
    fit_unknown unk = fit_problem_unknown(p, u);
    if (unk.kind != &fit_kind_material) continue;
    if (at_bound[u]) {
      r->status[unk.slot] = CF_PARAM_AT_BOUND;
      r->sd[unk.slot] = NAN;
      continue;
    }
    r->sd[unk.slot] = fit_slot_sd(p, unk.slot, covariance[u * n + u]);
    map[r->free_count] = u;
    r->free_slots[r->free_count++] = unk.slot;
  }
  for (int a = 0; a < r->free_count; ++a)
    for (int b = 0; b < r->free_count; ++b) {
      double va = covariance[map[a] * n + map[a]], vb = covariance[map[b] * n + map[b]];
      r->correlation[a * r->free_count + b] =
          va > 0.0 && vb > 0.0 ? covariance[map[a] * n + map[b]] / sqrt(va * vb) : (a == b);
    }
}

/* The values of every kind and their sds from the solved problem and its
 * covariance. */
static cf_status fill_values(const fit_problem *p, const fit_plan *plan, const double *covariance,
                             cf_fit_result *r, cf_error *err) {
  const fit_values *v = fit_problem_read_values(p);
  int n = fit_problem_unknown_count(p);
  memcpy(r->params, v->params, sizeof v->params);
  for (int k = 0; k < fit_problem_dim(p); ++k) r->status[k] = plan->status[k];
  r->free_unknowns = n;
  for (int u = 0; u < n; ++u) {
    const fit_kind *kind = fit_problem_unknown(p, u).kind;
    if (kind == &fit_kind_scale) /* d s = s d log s */
      r->scale_sd = exp(v->log_scale) * sqrt(fmax(0.0, covariance[u * n + u]));
    else if (kind == &fit_kind_response)
      response_covariance(p, covariance, u, r);
  }
  material_of(p, covariance, r);
  memcpy(r->response, v->response, sizeof r->response);
  r->response_fitted = plan->response;
  r->scale = exp(v->log_scale);
  r->scale_fitted = plan->scale;
  r->images = fit_problem_images(p);
  r->exposures = malloc(r->images * sizeof *r->exposures);
  r->exposure_sd = malloc(r->images * sizeof *r->exposure_sd);
  if (!r->exposures || !r->exposure_sd) return cf_error_set(err, CF_ENOMEM, "out of memory");
  for (size_t k = 0; k < r->images; ++k) r->exposures[k] = exp(v->log_exposures[k]);
  fit_gains_sd(p, covariance, r->exposure_sd);
  cf_status s =
      fit_balance_of(p, plan->exposures == CF_GAINS_PER_IMAGE_RGB, covariance, r, err);
  if (s == CF_OK) s = fit_light_gains_of(p, covariance, r, err);
  return s;
}

/* Photo values that cannot be radiance, left out when the capture was
 * loaded: a warning in the fit's own list when they are more than a trace
 * in some image (the capture's warnings say where). */
static void warn_not_radiance(const cf_capture *capture, cf_fit_result *r) {
  size_t total = 0, images = 0, worst = 0;
  double worst_share = 0.0;
  for (size_t k = 0; k < cf_capture_image_count(capture); ++k) {
    const cf_capture_image *image = cf_capture_image_at(capture, k);
    double share = (double)image->not_radiance /
                   fmax(1.0, (double)(image->observations + image->not_radiance));
    total += image->not_radiance;
    if (share <= CF_NOT_RADIANCE_TRACE) continue;
    ++images;
    if (share > worst_share) worst_share = share, worst = k;
  }
  if (images > 0)
    fit_add_warning(r,
                    "%zu pixels on the sphere hold values that cannot be radiance and were left "
                    "out, more than a trace in %zu of the %zu images (most: %.32s, %.2g %%); "
                    "see residuals.per_image[].not_radiance",
                    total, images, cf_capture_image_count(capture),
                    cf_capture_image_at(capture, worst)->name, 100.0 * worst_share);
}

/* The solver's summary: the problem's tally and the last solve's end. */
static void solver_summary(const fit_problem *p, const cf_lsq_summary *summary,
                           const cf_fit_options *o, int sampled, cf_fit_result *r) {
  const fit_tally *t = fit_problem_tally(p);
  r->cost = summary->final_cost;
  r->iterations = t->iterations;
  r->solves = t->solves;
  memcpy(r->trace, t->trace, (size_t)t->trace_count * sizeof *t->trace);
  r->trace_count = t->trace_count;
  const char *termination = cf_lsq_termination_name(summary->ending);
  snprintf(r->termination, sizeof r->termination, "%s", termination);
  r->solve_seconds = t->seconds;
  if (summary->ending == CF_LSQ_END_OUT_OF_ITERATIONS)
    fit_add_warning(r,
                    "the last solve ended without converging (%s after its %d iterations "
                    "at most): the values may be short of the minimum; raise "
                    "--max-iterations%s",
                    termination, o->max_iterations,
                    sampled ? ", or the pixel budget (a small sample may not show the "
                              "highlight well enough to fit it)"
                            : "");
}

/* What the capture's radiometry leaves to the result's reader. */
static void warn_units(const cf_capture *capture, cf_model_id model, cf_fit_result *r) {
  cf_capture_summary about;
  cf_capture_summarize(capture, &about);
  if (about.radiometry_relative && fit_scale_slot(model) < 0)
    fit_add_warning(r,
                    "the capture's radiometry is relative and %s has no interface F0 to "
                    "fix the scale: its albedo is in the lights' relative units",
                    cf_model_info_get(model)->code);
  else if (about.tone_curve_unknown && fit_scale_slot(model) < 0)
    fit_add_warning(r,
                    "the photos' tone curve is unknown and %s has no interface F0 to fix "
                    "the level: its albedo trades with the response curve's stretch and is "
                    "in relative units",
                    cf_model_info_get(model)->code);
}

cf_status fit_outcome(const fit_problem *p, const fit_plan *plan, const double *covariance,
                      const cf_lsq_summary *summary, const cf_fit_options *o, int sampled,
                      double sigma2, cf_fit_result *r, cf_error *err) {
  cf_status s = fill_values(p, plan, covariance, r, err);
  if (s != CF_OK) return s;
  solver_summary(p, summary, o, sampled, r);
  fit_footprint_tally(p, &r->footprint_observations, &r->footprint_samples, &r->footprint_max);
  r->ambiguous = fit_ambiguous(r, o->model, sigma2);
  if (r->ambiguous)
    fit_add_warning(r,
                    "on the multi-start's subsample two starts far apart ended within "
                    "the noise of each other (see starts); the fit on all observations "
                    "went on from the best: see its sd and correlations");
  warn_not_radiance(fit_problem_capture(p), r);
  warn_units(fit_problem_capture(p), o->model, r);
  return CF_OK;
}

cf_status fit_check_constrained(const cf_fit_result *r, cf_error *err) {
  const cf_model_info *model = cf_model_info_get(r->model);
  int fitted = 0, unconstrained = 0;
  for (int k = 0; k < model->dim; ++k) {
    fitted += r->status[k] == CF_PARAM_FITTED || r->status[k] == CF_PARAM_AT_BOUND;
    unconstrained += r->status[k] == CF_PARAM_UNCONSTRAINED;
  }
  if (fitted > 0 || unconstrained == 0) return CF_OK;
  return cf_error_set(err, CF_EINVAL,
                      "nothing to fit: the capture constrains none of %s's parameters (each "
                      "one's sd exceeds half its range, or no observation moves it): the lights "
                      "are too weak, or the lit values too few or too noisy, to move any value "
                      "beyond the noise",
                      model->code);
}
