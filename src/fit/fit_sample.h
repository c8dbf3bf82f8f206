/* The observations a fit uses: a population (the capture's, or those of
 * some images), a weighted sample of it, and the pixel budget's sample
 * (cf_fit_options.budget). One sampler: observations in strata, each
 * stratum taken evenly (fit_spread_take), each drawn observation weighed
 * by its stratum's size over its sample's, so that a sample's cost
 * estimates the population's without bias (a Horvitz-Thompson estimate).
 * Private to src/fit. */
#ifndef CLAYFIT_FIT_SAMPLE_H
#define CLAYFIT_FIT_SAMPLE_H

#include <stddef.h>
#include <stdint.h>

#include "clayfit/capture.h"
#include "clayfit/fit.h"
#include "fit_problem.h"

/* The observations a fit uses: all of the capture's (index NULL; count is
 * then the capture's) or the `count` listed in index, each weighed by
 * weight[i] (a pixel budget's sample; NULL: 1). */
typedef struct fit_population {
  const uint32_t *index;
  size_t count;
  const double *weight;
} fit_population;

typedef struct fit_sample {
  uint32_t *index;
  double *weight;
  size_t count;
} fit_sample;

/* The observations of the images with use_image[k] (NULL: all, index
 * NULL); *index is owned (free). */
cf_status fit_population_of_images(const cf_capture *capture, const unsigned char *use_image,
                                   fit_population *population, uint32_t **index, cf_error *err);

/* A weighted sample of about `target` observations of the population,
 * for the stages that work on a subsample (the highlights' stratum, the
 * 1/16 of the population whose half vector comes nearest the normal for
 * any light, gets a quarter, one at least: rare in a photo, they fix the
 * lobes). A
 * population no larger than the target is taken whole, with weights 1. */
cf_status fit_sample_draw(const cf_observations *obs, const fit_population *from, size_t target,
                          fit_sample *sample, cf_error *err);
void fit_sample_free(fit_sample *sample);

/* About `budget` observations of the population by `sampling` (uniform;
 * stratified: fit_sample_draw; importance: the highlights and the
 * silhouette region, n·v < 0.3, up to half the budget, the rest
 * uniform); the population whole, weights 1, when it has no more. */
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

/* The population a fit's options use (their images), and the pixel
 * budget's sample of it when the budget is below its size (drawn image by
 * image when per-image gains are free): drawn once, for the check of the
 * gains before the fit and for the fit. */
typedef struct fit_budget {
  fit_population population; /* what the fit uses: the sample's, or all of the images' */
  size_t in_use;             /* the observations of the images */
  fit_sample sample;         /* the budget's draw (weight NULL: none) */
  uint32_t *index;           /* the images' observations (owned) */
} fit_budget;

cf_status fit_budget_for(const cf_capture *capture, const cf_fit_options *o, fit_budget *budget,
                         cf_error *err);
void fit_budget_free(fit_budget *budget);
/* Do two options draw the same budget (images, budget, sampling, gains)? */
int fit_budget_same(const cf_fit_options *a, const cf_fit_options *b);

/* A weighted sample of about `target` observations of the population
 * (fit_sample_draw) and the problem over it with the sample's weights, on
 * one thread. On failure nothing is left to free; else free both. */
cf_status fit_sample_problem(fit_problem **p, fit_sample *sample, const cf_capture *capture,
                             cf_model_id model, const fit_population *population, size_t target,
                             cf_error *err);

/* An even spread (Bresenham's): of `size` items met one by one, take
 * `want` (all when want >= size) spaced evenly over the whole run, the
 * last item included; *acc starts at 0. A whole stride (every
 * (size / want)-th, stopped at `want`) left the end out: on DiLiGenT the
 * last two images of 96, whose free exposures then had no observation. */
static inline int fit_spread_take(size_t *acc, size_t want, size_t size) {
  if (want >= size) return 1;
  *acc += want;
  if (*acc < size) return 0;
  *acc -= size;
  return 1;
}

#endif /* CLAYFIT_FIT_SAMPLE_H */
