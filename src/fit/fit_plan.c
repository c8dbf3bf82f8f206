/* What a fit frees and holds, and the solver calls of every stage
 * (fit_plan.h). */
#include "fit_plan.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lsq/lsq.h"

/* The interface F0 that fixes the absolute scale of a capture whose lights
 * are known only up to a factor (docs/model.md §5.5), or −1. */
int fit_scale_slot(cf_model_id model) {
  const cf_model_info *info = cf_model_info_get(model);
  if (!info) return -1;
  switch (info->ggx_twin) { /* a tailed twin's vector starts with its twin's */
    case CF_MODEL_DIELECTRIC:
      return CF_DIELECTRIC_F0;
    case CF_MODEL_CLEARCOAT:
      return CF_CLEARCOAT_F0;
    case CF_MODEL_CLAY:
      return CF_CLAY_FILM_F0;
    default:
      return -1;
  }
}

cf_status fit_plan_for(const cf_capture *capture, const cf_fit_options *o, fit_plan *plan) {
  const cf_model_info *m = cf_model_info_get(o->model);
  cf_capture_summary summary;
  cf_capture_summarize(capture, &summary);
  memset(plan, 0, sizeof *plan);
  for (int k = 0; k < m->dim; ++k) plan->status[k] = o->hold[k] ? CF_PARAM_HELD : CF_PARAM_FITTED;
  int sk = fit_scale_slot(o->model);
  /* an unknown tone curve leaves the level unmeasured too: the curve's
   * stretch R(x/k) trades with every lobe's level (docs/model.md §5.4) */
  if ((summary.radiometry_relative || summary.tone_curve_unknown) && sk >= 0) {
    /* the scale is fitted, fixed by the interface F0 (held, 0.04 unless the
     * user says otherwise) */
    plan->scale = 1;
    if (!o->free[sk] && !o->hold[sk]) plan->status[sk] = CF_PARAM_HELD_FOR_SCALE;
  }
  plan->exposures = cf_capture_image_count(capture) > 1 ? o->fit_exposures : CF_GAINS_NONE;
  return CF_OK;
}

cf_status fit_declare(fit_problem *p, const fit_plan *plan, cf_error *err) {
  fit_problem_clear_unknowns(p);
  p->radius = 0.0; /* other unknowns, another minimum: Ceres' initial trust region */
  for (int k = 0; k < p->dim; ++k)
    if (plan->status[k] == CF_PARAM_FITTED) fit_problem_free_slot(p, k);
  if (plan->scale) fit_problem_free_scale(p);
  /* a gain per light: per image's group where each image has one light,
   * else inside the sums (fit_problem_free_light_gains) */
  if (plan->exposures == CF_GAINS_PER_LIGHT && p->several_lights) {
    fit_problem_free_light_gains(p);
  } else if (plan->exposures) {
    fit_problem_group_gains(p, plan->exposures == CF_GAINS_PER_LIGHT);
    fit_problem_free_exposures(p);
  }
  if (plan->exposures == CF_GAINS_PER_IMAGE_RGB) fit_problem_free_balance(p);
  if (plan->response) fit_problem_free_response(p);
  return fit_problem_finish(p, err);
}

/* A trust region carried to the next solve is at most this wide: a step
 * that fails there shrinks it by 2, 4, 8, … (a cost pass each), so from
 * here a few failures reach any useful radius. */
#define MAX_CARRIED_RADIUS 1e10

int fit_threads(const cf_fit_options *o) {
  return o->threads > 0 ? o->threads : 2;
}

void fit_lsq_problem(fit_problem *p, double *x, cf_lsq_problem *problem) {
  *problem = (cf_lsq_problem){
      p->num_unknowns,           x, p->lower,   p->upper, p->num_blocks, fit_problem_evaluate,
      fit_problem_block_columns, p, p->at_bound};
}

cf_status fit_solve(fit_problem *p, const cf_fit_options *o, int max_iterations,
                    cf_lsq_summary *summary, cf_error *err) {
  return fit_solve_normal(p, o, max_iterations, summary, NULL, err);
}

/* The problem as lsq.h sees it at the current values, in a new x (freed
 * by the caller). */
static cf_status lsq_problem_here(fit_problem *p, double **x, cf_lsq_problem *problem,
                                  cf_error *err) {
  *x = malloc((p->num_unknowns ? (size_t)p->num_unknowns : 1) * sizeof **x);
  if (!*x) return cf_error_set(err, CF_ENOMEM, "out of memory for %d unknowns", p->num_unknowns);
  fit_problem_get_x(p, *x);
  fit_lsq_problem(p, *x, problem);
  return CF_OK;
}

cf_status fit_solve_normal(fit_problem *p, const cf_fit_options *o, int max_iterations,
                           cf_lsq_summary *summary, double *jtj, cf_error *err) {
  double *x;
  cf_lsq_problem problem;
  cf_status here = lsq_problem_here(p, &x, &problem, err);
  if (here != CF_OK) return here;
  cf_lsq_options options;
  cf_lsq_default_options(&options);
  options.max_iterations = max_iterations;
  options.threads = fit_threads(o);
  if (p->radius > 0.0) options.initial_radius = p->radius;
  if (p->function_tolerance > 0.0) options.function_tolerance = p->function_tolerance;
  if (p->min_relative_decrease > 0.0) options.min_relative_decrease = p->min_relative_decrease;
  options.newton_start = p->newton_start;
  options.stop = p->stop;
  options.stop_user = p->stop_user;
  options.final_jtj = jtj;
  options.trace = o->trace;
  options.trace_user = o->trace_user;
  cf_status s = cf_lsq_solve(&problem, &options, summary, err);
  if (s == CF_OK) p->radius = fmin(summary->final_radius, MAX_CARRIED_RADIUS);
  if (s == CF_OK) fit_problem_set_x(p, x);
  free(x);
  if (s == CF_OK) {
    ++p->solves;
    p->iterations += summary->iterations;
    for (int i = 0; i < summary->trace_count && p->trace_count < CF_FIT_MAX_TRACE; ++i)
      p->trace[p->trace_count++] = summary->trace[i];
    p->solver_seconds += summary->seconds;
  }
  if (s == CF_OK && jtj && !summary->final_normal) /* (could not be evaluated there) */
    s = fit_normal_equations(p, fit_threads(o), jtj, NULL, NULL, err);
  return s;
}

cf_status fit_normal_equations(fit_problem *p, int threads, double *jtj, double *jtu, double *cost,
                               cf_error *err) {
  double total, *x;
  cf_lsq_problem problem;
  cf_status here = lsq_problem_here(p, &x, &problem, err);
  if (here != CF_OK) return here;
  int evaluated = cf_lsq_normal_equations(&problem, threads, jtj, jtu, &total);
  free(x);
  if (evaluated == CF_LSQ_FAILED)
    return cf_error_set(err, CF_ENOMEM, "out of memory evaluating the fit at its current values");
  if (evaluated != CF_LSQ_EVALUATED)
    return cf_error_set(err, CF_ENUMERIC, "the fit is not finite at its current values");
  if (cost) *cost = total;
  return CF_OK;
}

cf_status fit_newton_decrement(fit_problem *p, const cf_fit_options *o, double *decrement,
                               cf_error *err) {
  int n = p->num_unknowns;
  *decrement = HUGE_VAL;
  if (n > FIT_DECREMENT_MOST) return CF_OK;
  double jtj[FIT_DECREMENT_MOST * FIT_DECREMENT_MOST], g[FIT_DECREMENT_MOST];
  cf_status s = fit_normal_equations(p, fit_threads(o), jtj, g, NULL, err);
  if (s == CF_OK) *decrement = fit_newton_decrement_from(p, jtj, g);
  return s;
}

int fit_pins_hold(const fit_problem *p, const double *g) {
  for (int u = 0; u < p->num_unknowns; ++u)
    if (p->at_bound[u] != 0 && !(p->at_bound[u] * -g[u] > 0.0)) return 0;
  return 1;
}

double fit_newton_decrement_from(const fit_problem *p, const double *jtj, const double *g) {
  if (p->num_unknowns > FIT_DECREMENT_MOST) return HUGE_VAL;
  return cf_lsq_newton_decrement(p->num_unknowns, jtj, g, p->at_bound);
}

/* With a noise model (or σ through the curve), σ from the prediction
 * (fit_problem_reweight) and solve again, to the fixed point (the
 * largest change in a model slot below 1e-7 of its range's width, or
 * `rounds` rounds); without one, one solve. */
cf_status fit_solve_reweighted(fit_problem *p, const cf_capture *capture, const cf_fit_options *o,
                               int rounds, cf_lsq_summary *summary, int *weights_current,
                               cf_error *err) {
  if (weights_current) *weights_current = 0;
  if (!fit_capture_has_noise(capture) && !fit_problem_sigma_through_curve(p))
    return fit_solve(p, o, o->max_iterations, summary, err);
  cf_status s = CF_OK;
  for (int round = 0; s == CF_OK && round < rounds; ++round) {
    double before[CF_MAX_DIM], decrement = HUGE_VAL;
    memcpy(before, p->params, sizeof before);
    s = fit_problem_reweight(p, capture, err);
    /* after the first solve, new weights that move nothing end it */
    if (s == CF_OK && round > 0) s = fit_newton_decrement(p, o, &decrement, err);
    if (s == CF_OK && decrement < FIT_RESOLVE_DECREMENT) {
      if (weights_current) *weights_current = 1; /* from these values: nothing moved since */
      break;
    }
    if (s == CF_OK) s = fit_solve(p, o, o->max_iterations, summary, err);
    double change = 0.0;
    for (int k = 0; k < p->dim; ++k)
      change = fmax(change, fabs(p->params[k] - before[k]) / fit_slot_width(p, k));
    if (change < 1e-7) break;
  }
  return s;
}

/* The width of a model slot's range. */
double fit_slot_width(const fit_problem *p, int slot) {
  const cf_param_info *info = cf_model_slot_param(p->model, slot, NULL);
  return info ? info->upper - info->lower : 1.0;
}

void fit_progress(const cf_fit_options *o, const char *stage, size_t done, size_t total) {
  if (o->progress) o->progress(o->progress_user, stage, done, total);
}
