/* The result of a fit from its solved problem: the values of every kind
 * of unknown with their standard deviations and correlations, the
 * solver's summary, and the warnings the result calls for. Private to
 * src/fit. */
#ifndef CLAYFIT_FIT_OUTCOME_H
#define CLAYFIT_FIT_OUTCOME_H

#include "clayfit/fit.h"
#include "fit_plan.h"
#include "fit_problem.h"

/* Into r: the problem's values, their sds from `covariance` (of its
 * unknowns, n²), the plan's statuses, the summary of the last solve
 * (sampled: the fit ran on a pixel budget's sample), the footprints, the
 * multi-start's ambiguity (σ² the starts' costs are in) and the
 * warnings. */
cf_status fit_outcome(const fit_problem *p, const fit_plan *plan, const double *covariance,
                      const cf_lsq_summary *summary, const cf_fit_options *o, int sampled,
                      double sigma2, cf_fit_result *r, cf_error *err);

/* CF_EINVAL "nothing to fit" when the result has no parameter the capture
 * constrains (none fitted, some not constrained), whatever the reason. */
cf_status fit_check_constrained(const cf_fit_result *r, cf_error *err);

/* Append a warning to the result (dropped beyond CF_FIT_MAX_WARNINGS). */
void fit_add_warning(cf_fit_result *r, const char *format, ...)
    __attribute__((format(printf, 2, 3)));

#endif /* CLAYFIT_FIT_OUTCOME_H */
