/* The problem's solves through lsq.h (fit_problem.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lsq/lsq.h"
#include "problem.h"

/* A trust region carried to the next solve is at most this wide: a step
 * that fails there shrinks it by 2, 4, 8, … (a cost pass each), so from
 * here a few failures reach any useful radius. */
#define MAX_CARRIED_RADIUS 1e10 /* 7057c3b (docs/solver.md); 1e8: 1 of 10 fits moves 2e-6 sd */

int fit_threads(const cf_fit_options *o) {
  return o->threads > 0 ? o->threads : 2;
}

void fit_lsq_problem(fit_problem *p, double *x, cf_lsq_problem *problem) {
  const fit_unknowns *u = &p->unknowns;
  *problem = (cf_lsq_problem){u->num,         x,   u->lower,   u->upper, p->blocks.count,
                              fit_problem_evaluate, fit_problem_block_columns, p, u->at_bound};
}

/* The problem as lsq.h sees it at the current values, in a new x (freed
 * by the caller). */
static cf_status lsq_problem_here(fit_problem *p, double **x, cf_lsq_problem *problem,
                                  cf_error *err) {
  int n = p->unknowns.num;
  *x = malloc((n ? (size_t)n : 1) * sizeof **x);
  if (!*x) return cf_error_set(err, CF_ENOMEM, "out of memory for %d unknowns", n);
  fit_problem_get_x(p, *x);
  fit_lsq_problem(p, *x, problem);
  return CF_OK;
}

cf_status fit_solve(fit_problem *p, const cf_fit_options *o, int max_iterations,
                    cf_lsq_summary *summary, cf_error *err) {
  return fit_solve_normal(p, o, max_iterations, summary, NULL, err);
}

/* lsq.h's options for a solve of p. */
static void solve_options(const fit_problem *p, const cf_fit_options *o, int max_iterations,
                          double *jtj, cf_lsq_options *options) {
  const fit_solve_settings *set = &p->settings;
  cf_lsq_default_options(options);
  options->max_iterations = max_iterations;
  options->threads = fit_threads(o);
  if (p->radius > 0.0) options->initial_radius = p->radius;
  if (set->function_tolerance > 0.0) options->function_tolerance = set->function_tolerance;
  if (set->min_relative_decrease > 0.0)
    options->min_relative_decrease = set->min_relative_decrease;
  options->newton_start = set->newton_start;
  options->stop = set->stop;
  options->stop_user = set->stop_user;
  options->final_jtj = jtj;
  options->trace = o->trace;
  options->trace_user = o->trace_user;
}

/* A solve's iterations, trace and time into the problem's tally. */
static void tally(fit_problem *p, const cf_lsq_summary *summary) {
  fit_tally *t = &p->tally;
  ++t->solves;
  t->iterations += summary->iterations;
  for (int i = 0; i < summary->trace_count && t->trace_count < CF_FIT_MAX_TRACE; ++i)
    t->trace[t->trace_count++] = summary->trace[i];
  t->seconds += summary->seconds;
}

cf_status fit_solve_normal(fit_problem *p, const cf_fit_options *o, int max_iterations,
                           cf_lsq_summary *summary, double *jtj, cf_error *err) {
  double *x;
  cf_lsq_problem problem;
  cf_status here = lsq_problem_here(p, &x, &problem, err);
  if (here != CF_OK) return here;
  cf_lsq_options options;
  solve_options(p, o, max_iterations, jtj, &options);
  cf_status s = cf_lsq_solve(&problem, &options, summary, err);
  if (s == CF_OK) {
    p->radius = fmin(summary->final_radius, MAX_CARRIED_RADIUS);
    fit_problem_set_x(p, x);
    tally(p, summary);
  }
  free(x);
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

cf_status fit_sample_information(fit_problem *p, int threads, double *b, cf_error *err) {
  double *root = p->rows.sample_root, *square = malloc((p->rows.count ? p->rows.count : 1) *
                                                       sizeof *square);
  if (!square) return cf_error_set(err, CF_ENOMEM, "out of memory");
  for (size_t i = 0; root && i < p->rows.count; ++i) square[i] = root[i] * root[i];
  p->rows.sample_root = root ? square : NULL; /* each row weighed by w instead of √w */
  cf_status s = fit_normal_equations(p, threads, b, NULL, NULL, err);
  p->rows.sample_root = root;
  free(square);
  return s;
}

cf_status fit_newton_decrement(fit_problem *p, const cf_fit_options *o, double *decrement,
                               cf_error *err) {
  int n = p->unknowns.num;
  *decrement = HUGE_VAL;
  if (n > FIT_DECREMENT_MOST) return CF_OK;
  double jtj[FIT_DECREMENT_MOST * FIT_DECREMENT_MOST], g[FIT_DECREMENT_MOST];
  cf_status s = fit_normal_equations(p, fit_threads(o), jtj, g, NULL, err);
  if (s == CF_OK) *decrement = fit_newton_decrement_from(p, jtj, g);
  return s;
}

int fit_pins_hold(const fit_problem *p, const double *g) {
  const int *at_bound = p->unknowns.at_bound;
  for (int u = 0; u < p->unknowns.num; ++u)
    if (at_bound[u] != 0 && !(at_bound[u] * -g[u] > 0.0)) return 0;
  return 1;
}

double fit_newton_decrement_from(const fit_problem *p, const double *jtj, const double *g) {
  if (p->unknowns.num > FIT_DECREMENT_MOST) return HUGE_VAL;
  return cf_lsq_newton_decrement(p->unknowns.num, jtj, g, p->unknowns.at_bound);
}

double fit_slot_width(cf_model_id model, int slot) {
  const cf_param_info *info = cf_model_slot_param(model, slot, NULL);
  return info ? info->upper - info->lower : 1.0;
}

/* With a noise model (or σ through the curve), σ from the prediction
 * (fit_problem_reweight) and solve again, to the fixed point (the
 * largest change in a model slot below 1e-7 of its range's width, or
 * `rounds` rounds); without one, one solve. */
cf_status fit_solve_reweighted(fit_problem *p, const cf_fit_options *o, int rounds,
                               cf_lsq_summary *summary, int *weights_current, cf_error *err) {
  if (weights_current) *weights_current = 0;
  if (!fit_capture_has_noise(p->capture) && !fit_problem_sigma_through_curve(p))
    return fit_solve(p, o, o->max_iterations, summary, err);
  cf_status s = CF_OK;
  for (int round = 0; s == CF_OK && round < rounds; ++round) {
    double before[CF_MAX_DIM], decrement = HUGE_VAL;
    memcpy(before, p->values.params, sizeof before);
    s = fit_problem_reweight(p, err);
    /* after the first solve, new weights that move nothing end it */
    if (s == CF_OK && round > 0) s = fit_newton_decrement(p, o, &decrement, err);
    if (s == CF_OK && decrement < FIT_RESOLVE_DECREMENT) {
      if (weights_current) *weights_current = 1; /* from these values: nothing moved since */
      break;
    }
    if (s == CF_OK) s = fit_solve(p, o, o->max_iterations, summary, err);
    double change = 0.0;
    for (int k = 0; k < p->dim; ++k)
      change = fmax(change, fabs(p->values.params[k] - before[k]) / fit_slot_width(p->model, k));
    if (change < 1e-7) break; /* fd063f4; 1e-8 or 1e-6: 10 of 10 screened fits identical */
  }
  return s;
}
