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

/* The fewest observations a free per-image gain gets in a budget's sample
 * (all its image has when fewer). Measured on DiLiGenT (96 images, M4,
 * --fit-exposures, default budget): about 1,040 per image give gains
 * with sd at most 0.16 % that agree with the all-pixel fit's within
 * 0.17 %; the sd grows as 1/√n, so 1,000 keeps that, far below the 10 %
 * at which the gains are refused (cf_fit_check_gains). */
#define FIT_GAIN_FLOOR 1000

/* fit_budget_draw image by image, for free per-image gains: each image's
 * observations drawn apart, to its share of the budget (budget × its share
 * of the population) but at least `floor`, so that every gain has its own
 * observations however many images share the budget (the sample may then
 * exceed it: images × floor at most beyond). `from` is unweighted. */
cf_status fit_budget_draw_images(const cf_observations *obs, const fit_population *from,
                                 size_t images, size_t budget, size_t floor, cf_sampling sampling,
                                 fit_sample *sample, cf_error *err);

#endif /* CLAYFIT_FIT_BUDGET_H */
