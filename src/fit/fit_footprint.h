/* Pixel footprints in the fit (docs/model.md §5.6): a pixel
 * measures the mean of the reflected radiance over its footprint, which
 * the value at the pixel centre misses where a lobe is narrower than the
 * pixel (a sharp highlight on a sphere a few hundred pixels across). Such
 * observations get S × S samples over the pixel, each a point of the
 * footprint with its own normal, view and lights (cf_capture_footprint_at),
 * weighted 1/S²: the Gauss-Legendre pairs of cf_footprint_samples (auto),
 * or a fixed S's centred grid (the box filter `clayfit synth` renders
 * with).
 * Private to src/fit. */
#ifndef CLAYFIT_FIT_FOOTPRINT_H
#define CLAYFIT_FIT_FOOTPRINT_H

#include "clayfit/capture.h"
#include "clayfit/fit.h"
#include "fit_problem.h"

/* Choose S for every observation of the problem at its current parameters
 * (options->footprint: adaptive, centres only, or S for all) and, where
 * that differs from what the problem has, rebuild its pairs. Adaptive S
 * only grows from one call to the next (a lobe that narrows during the
 * fit gets more samples; one that widens keeps them), so repeated calls
 * settle. *changed (optional) is set when the pairs were rebuilt. */
cf_status fit_footprint_update(fit_problem *p, const cf_capture *capture,
                               const cf_fit_options *options, int *changed, cf_error *err);

/* What the problem integrates: observations with S >= 2, Σ S² over them,
 * the largest S. */
void fit_footprint_tally(const fit_problem *p, size_t *observations, size_t *samples, int *largest);

#endif /* CLAYFIT_FIT_FOOTPRINT_H */
