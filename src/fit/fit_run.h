/* One model fitted to a population of a capture's observations: the
 * whole of cf_fit_run (fit.c), on a subset, for the model choice. Private
 * to src/fit. */
#ifndef CLAYFIT_FIT_RUN_H
#define CLAYFIT_FIT_RUN_H

#include "clayfit/fit.h"
#include "fit_outcome.h"
#include "fit_sample.h"

/* `tolerance`: the relative change of the cost at which the solves on the
 * population stop (0: the solver's 1e-10; the model choice's candidates
 * need less, FIT_CANDIDATE_TOLERANCE). */
cf_status fit_run_population(const cf_capture *capture, const fit_population *population,
                             const cf_fit_options *o, double tolerance, cf_fit_result *r,
                             cf_error *err);

/* cf_fit_run on a budget drawn before (fit_budget_for, with the same
 * sampling options: fit_budget_same), the gains checked before. */
cf_status fit_run_budget(const cf_capture *capture, const fit_budget *budget,
                         const cf_fit_options *o, cf_fit_result *r, cf_error *err);

#endif /* CLAYFIT_FIT_RUN_H */
