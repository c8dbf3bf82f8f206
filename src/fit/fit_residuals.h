/* The residuals of a fit: statistics over every observation and per
 * image, and σ from the residuals. Private to src/fit. */
#ifndef CLAYFIT_FIT_RESIDUALS_H
#define CLAYFIT_FIT_RESIDUALS_H

#include <stddef.h>

#include "clayfit/capture.h"
#include "clayfit/fit.h"
#include "fit_problem.h"
#include "fit_sample.h"

/* RMSE, relative RMSE, censored and rejected counts, per image, at the
 * current values, into r (which then owns its per-image arrays). A pixel
 * budget's sample weighs each residual by its observation's weight, so
 * the RMSEs estimate those of every observation; the counts are the
 * sample's. */
cf_status fit_statistics(fit_problem *p, const cf_fit_options *o, cf_fit_result *r, cf_error *err);

/* σ = 1.4826 × the median absolute residual (a robust estimate) over the
 * uncensored residuals at the current values. */
cf_status fit_estimate_sigma(fit_problem *p, double *sigma, cf_error *err);

/* A fit (its parameters, scale and exposures) on a population of the
 * capture's observations: its cost ½ Σ ρ(r²), r in units of σ (the model
 * choice's training cost and held-out score), and its residual statistics
 * there (fit_statistics) into *stats, whose other fields are copied from
 * fit and which owns its per-image arrays (cf_fit_result_free). With the
 * capture's noise model σ comes from the prediction (as in the fit);
 * without one, it is `sigma` for every residual. With log_sigma non-NULL,
 * also Σ w log σ over the uncensored residuals when σ depends on the fit
 * beyond its prediction (the noise model carried through a fitted
 * response curve: the Gaussian likelihood's −Σ log σ then differs between
 * fits), else 0. */
cf_status fit_score_at(const cf_capture *capture, const fit_population *population,
                       const cf_fit_result *fit, double sigma, const cf_fit_options *o,
                       double *cost, double *log_sigma, cf_fit_result *stats, cf_error *err);

/* Σ w log σ over p's uncensored residuals at its current values and σ
 * (fit_score_at's log_sigma; the response's starts, fit_response_starts.c). */
cf_status fit_sum_log_sigma(const fit_problem *p, double *sum, cf_error *err);

#endif /* CLAYFIT_FIT_RESIDUALS_H */
