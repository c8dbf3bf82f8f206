/* One model fitted to a population of a capture's observations: the
 * whole of cf_fit_run (fit.c), on a subset, for the model choice. Private
 * to src/fit. */
#ifndef CLAYFIT_FIT_RUN_H
#define CLAYFIT_FIT_RUN_H

#include "clayfit/fit.h"
#include "fit_problem.h"

/* `tolerance`: the relative change of the cost at which the solves on the
 * population stop (0: the solver's 1e-10; the model choice's candidates
 * need less, FIT_CANDIDATE_TOLERANCE). */
cf_status fit_run_population(const cf_capture *capture, const fit_population *population,
                             const cf_fit_options *o, double tolerance, cf_fit_result *r,
                             cf_error *err);

/* Append a warning to the result (dropped beyond CF_FIT_MAX_WARNINGS). */
void fit_add_warning(cf_fit_result *r, const char *format, ...)
    __attribute__((format(printf, 2, 3)));

#endif /* CLAYFIT_FIT_RUN_H */
