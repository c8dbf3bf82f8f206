/* clayfit's side of the peers benchmark (peers_clayfit.h). */
#include "peers_clayfit.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fit_plan.h"
#include "problem/problem.h"
#include "lsq/lsq.h"

double peers_now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* The problem over the observations, unweighted: σ = 1 for every residual
 * whatever the capture's noise model says, no loss. */
static cf_status common_problem(fit_problem **out, const cf_capture *capture, cf_model_id model,
                                const uint32_t *index, size_t count, const double *params,
                                int free_all, cf_error *err) {
  cf_status s = fit_problem_new(out, capture, model, index, count, 1, err);
  if (s != CF_OK) return s;
  fit_problem *p = *out;
  for (size_t i = 0; i < 3 * p->rows.count; ++i) p->rows.inv_sigma[i] = 1.0;
  p->rows.sigma = 1.0;
  p->loss = CF_LOSS_NONE;
  memcpy(p->values.params, params, sizeof(double) * (size_t)p->dim);
  fit_problem_clear_unknowns(p);
  if (free_all)
    for (int k = 0; k < p->dim; ++k) fit_problem_free_slot(p, k);
  s = fit_problem_finish(p, err);
  if (s != CF_OK) {
    fit_problem_free(p);
    *out = NULL;
  }
  return s;
}

cf_status peers_clayfit_run(const cf_capture *capture, cf_model_id model, const uint32_t *index,
                            size_t count, const double *start, int threads, int max_iterations,
                            peers_clayfit_result *result, cf_error *err) {
  memset(result, 0, sizeof *result);
  double t0 = peers_now();
  fit_problem *p;
  cf_status s = common_problem(&p, capture, model, index, count, start, 1, err);
  if (s != CF_OK) return s;
  cf_fit_options o;
  cf_fit_default_options(&o, model);
  o.threads = threads;
  o.loss = CF_LOSS_NONE;
  cf_lsq_summary summary;
  double t1 = peers_now();
  s = fit_solve(p, &o, max_iterations, &summary, err);
  double t2 = peers_now();
  if (s == CF_OK) {
    memcpy(result->params, p->values.params, sizeof(double) * (size_t)p->dim);
    result->cost = summary.final_cost;
    result->iterations = summary.iterations;
    result->seconds = t2 - t0;
    result->solve_seconds = t2 - t1;
    snprintf(result->termination, sizeof result->termination, "%s",
             cf_lsq_termination_name(summary.ending));
    /* the floor: one value + gradient pass over every pair */
    result->pairs = p->rows.slots;
    double *f = malloc(3 * p->rows.slots * sizeof *f);
    double *grad = malloc(3 * (size_t)p->dim * p->rows.slots * sizeof *grad);
    if (!f || !grad) s = cf_error_set(err, CF_ENOMEM, "out of memory for the floor's pass");
    result->pass_seconds = HUGE_VAL;
    for (int rep = 0; s == CF_OK && rep < 5; ++rep) {
      double a = peers_now();
      s = cf_eval_batch(model, p->values.params, p->rows.slots, p->rows.geometry, f, grad);
      double b = peers_now();
      result->pass_seconds = fmin(result->pass_seconds, b - a);
    }
    if (s != CF_OK && err->message[0] == '\0') cf_error_set(err, s, "cf_eval_batch failed");
    free(f);
    free(grad);
    /* the callback's pass: value and normal equations, block by block */
    size_t k = (size_t)p->unknowns.num;
    double *x = malloc((k ? k : 1) * sizeof *x), *jtj = malloc((k ? k * k : 1) * sizeof *jtj);
    double *jtu = malloc((k ? k : 1) * sizeof *jtu);
    if (s == CF_OK && (!x || !jtj || !jtu)) s = cf_error_set(err, CF_ENOMEM, "out of memory");
    if (s == CF_OK) fit_problem_get_x(p, x);
    result->normal_pass_seconds = HUGE_VAL;
    for (int rep = 0; s == CF_OK && rep < 5; ++rep) {
      double a = peers_now(), cost;
      for (size_t b = 0; s == CF_OK && b < p->blocks.count; ++b) {
        int evaluated = fit_problem_evaluate(p, x, b, &cost, jtj, jtu);
        if (evaluated == CF_LSQ_FAILED)
          s = cf_error_set(err, CF_ENOMEM, "out of memory evaluating block %zu", b);
        else if (evaluated != CF_LSQ_EVALUATED)
          s = cf_error_set(err, CF_ENUMERIC, "the callback failed on block %zu", b);
      }
      result->normal_pass_seconds = fmin(result->normal_pass_seconds, peers_now() - a);
    }
    free(x);
    free(jtj);
    free(jtu);
  }
  fit_problem_free(p);
  return s;
}

cf_status peers_predict(const cf_capture *capture, cf_model_id model, const uint32_t *index,
                        size_t count, const double *params, double *prediction, double *measured,
                        cf_error *err) {
  fit_problem *p;
  cf_status s = common_problem(&p, capture, model, index, count, params, 0, err);
  if (s != CF_OK) return s;
  s = fit_problem_predict(p, prediction, measured, err);
  fit_problem_free(p);
  return s;
}
