/* The start of a fit that needs no guess: the closed-form albedo of the
 * least specular observations, then the deterministic multi-start
 * (fit_starts.h) run to convergence on a subsample; M3 and M4 build their
 * starts on a fitted M2. Private to src/fit. */
#ifndef CLAYFIT_FIT_MULTISTART_H
#define CLAYFIT_FIT_MULTISTART_H

#include "clayfit/capture.h"
#include "clayfit/fit.h"
#include "fit_plan.h"
#include "fit_sample.h"

/* Runs the starts on a subsample of the population (recorded in r->start;
 * the best is r->best_start) and returns the best start's values, its log
 * scale, and σ estimated from its residuals (used when the capture has no
 * noise model). */
cf_status fit_multistart(const cf_capture *capture, const fit_population *population,
                         const cf_fit_options *o, const fit_plan *plan, cf_fit_result *r,
                         double *best_params, double *best_log_scale, double *sigma, cf_error *err);

/* The base start: the closed-form albedo of the least specular half of
 * the problem's observations (and, with a free scale, the scale that puts
 * it inside [0, 1]), every other slot at its default or held value. */
void fit_base_start(const fit_problem *p, const fit_plan *plan, const cf_fit_options *o,
                    double *params, double *log_scale);

/* σ estimated from the residuals at a given start (the start given in the
 * options instead of the multi-start), on a subsample of the population. */
cf_status fit_start_sigma(const cf_capture *capture, const fit_population *population,
                          const cf_fit_options *o, const double *params, double log_scale,
                          double *sigma, cf_error *err);

/* Did a start end far from the best (more than 5 % of a parameter's
 * range) within the noise of its cost (Δcost < 1 in units of σ², that is
 * Δχ² < 2)? Starts stopped at an earlier minimum do not count. */
int fit_ambiguous(const cf_fit_result *r, cf_model_id model, double sigma2);

#endif /* CLAYFIT_FIT_MULTISTART_H */
