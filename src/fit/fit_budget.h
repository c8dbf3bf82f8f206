/* A pixel budget (cf_fit_options.budget): the observations of the fit on
 * every observation drawn by a sampling strategy, each weighed by the
 * inverse of its chance to be drawn. Private to src/fit. */
#ifndef CLAYFIT_FIT_BUDGET_H
#define CLAYFIT_FIT_BUDGET_H

#include "clayfit/fit.h"
#include "fit_problem.h"

/* About `budget` observations of the population by `sampling` into
 * sample (weights: the population's over the sample's share, per
 * stratum); the population whole, weights 1, when it has no more. */
cf_status fit_budget_draw(const cf_observations *obs, const fit_population *from, size_t budget,
                          cf_sampling sampling, fit_sample *sample, cf_error *err);

#endif /* CLAYFIT_FIT_BUDGET_H */
