/* What a fit frees and holds, and the solver calls every stage of the fit
 * makes (lsq.h over fit_problem.h). Private to src/fit. */
#ifndef CLAYFIT_FIT_PLAN_H
#define CLAYFIT_FIT_PLAN_H

#include <stddef.h>

#include "clayfit/capture.h"
#include "clayfit/fit.h"
#include "fit_problem.h"
#include "lsq/lsq.h"

/* What is free: per model slot its status (CF_PARAM_FITTED: free), and
 * whether the global scale and the exposures are. */
typedef struct fit_plan {
  cf_param_status status[CF_MAX_DIM];
  int scale;
  int exposures; /* CF_GAINS_*: the gains free, per image or light, or RGB */
  int response; /* the response curve (an unknown tone curve) */
} fit_plan;

/* The interface F0 that fixes the absolute scale of a capture whose lights
 * are known only up to a factor (docs/model.md §5.5), or −1
 * for a model without one. */
int fit_scale_slot(cf_model_id model);

/* The value that slot is held at for the scale unless the user holds
 * another (docs/model.md (42): F0 = 0.04, an uncoated dielectric of IOR 1.5). */
#define FIT_SCALE_F0 0.04

/* The plan for the options' model on this capture. */
cf_status fit_plan_for(const cf_capture *capture, const cf_fit_options *o, fit_plan *plan);

/* Declare the plan's unknowns on the problem. */
cf_status fit_declare(fit_problem *p, const fit_plan *plan, cf_error *err);

/* The solver threads the options ask for (2 when they say none). */
int fit_threads(const cf_fit_options *o);

/* The problem as lsq.h sees it, over the unknowns x (num_unknowns; the
 * caller fills them, fit_problem_get_x). */
void fit_lsq_problem(fit_problem *p, double *x, cf_lsq_problem *problem);

/* Solve the problem from its current values (lsq.h); the solution becomes
 * the current values, p->at_bound says which unknowns ended at a bound. */
cf_status fit_solve(fit_problem *p, const cf_fit_options *o, int max_iterations,
                    cf_lsq_summary *summary, cf_error *err);

/* fit_solve, then the normal equations at the solution over every unknown
 * into jtj (n², as fit_normal_equations), mostly from the evaluations the
 * solve kept. */
cf_status fit_solve_normal(fit_problem *p, const cf_fit_options *o, int max_iterations,
                           cf_lsq_summary *summary, double *jtj, cf_error *err);

/* The normal equations at the current values, over every unknown: JᵀJ
 * (n², row-major) and, unless jtu is NULL, Jᵀu (n), and unless cost is
 * NULL the cost, one pass over the observations on `threads` threads. */
cf_status fit_normal_equations(fit_problem *p, int threads, double *jtj, double *jtu, double *cost,
                               cf_error *err);

/* The most unknowns for which a Newton decrement is computed (beyond, it
 * is not worth it: HUGE_VAL). */
enum { FIT_DECREMENT_MOST = 64 };

/* How much a solve from the current values could still lower the cost:
 * the Gauss-Newton decrement ½ gᵀ H⁻¹ g over the unknowns not pinned at a
 * bound (in the cost's units, σ²: 1e-3 is a move of 0.045 standard
 * deviations along the worst direction). *decrement is HUGE_VAL where it
 * is not worth computing (more than FIT_DECREMENT_MOST unknowns). */
cf_status fit_newton_decrement(fit_problem *p, const cf_fit_options *o, double *decrement,
                               cf_error *err);

/* The same from the normal equations at the current values (jtj, g =
 * Jᵀu, fit_normal_equations), without a pass; HUGE_VAL beyond
 * FIT_DECREMENT_MOST unknowns. */
double fit_newton_decrement_from(const fit_problem *p, const double *jtj, const double *g);

/* Do the unknowns pinned at a bound (p->at_bound) stay there by the
 * gradient g at the current values: does descent (−g) point out of the
 * box for each? */
int fit_pins_hold(const fit_problem *p, const double *g);

/* Below this decrement a change of the problem (new weights, new pixel
 * footprints) is not solved again. */
#define FIT_RESOLVE_DECREMENT 1e-3

/* With a noise model, σ from the prediction (fit_problem_reweight) and
 * solve again, to the fixed point or `rounds` rounds; without one, one
 * solve. *weights_current (optional) is 1 when it ended with the weights
 * of the current values (new weights that moved nothing), else 0. */
cf_status fit_solve_reweighted(fit_problem *p, const cf_capture *capture, const cf_fit_options *o,
                               int rounds, cf_lsq_summary *summary, int *weights_current,
                               cf_error *err);

/* The width of a model slot's range. */
double fit_slot_width(const fit_problem *p, int slot);

void fit_progress(const cf_fit_options *o, const char *stage, size_t done, size_t total);

#endif /* CLAYFIT_FIT_PLAN_H */
