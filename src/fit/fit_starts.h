/* The deterministic starts of the multi-start (include/clayfit/fit.h):
 * the closed-form albedo, then a small grid over roughness and F0 (and for
 * M4 both orderings of its two lobes: a sharp film over a rough base and
 * the reverse). Private to src/fit. */
#ifndef CLAYFIT_FIT_STARTS_H
#define CLAYFIT_FIT_STARTS_H

#include "clayfit/model.h"

/* Fill starts (at most max) for `model` from the base vector (albedo
 * estimated, held slots set); slots with held[k] keep base[k]. For M3 and
 * M4, `warm` (may be NULL) is the fitted M2 (ρ, σ, r, F0): the starts then
 * build on it, for M4 in both orderings of its lobes (M2's lobe as the
 * film over bases of several roughnesses, or as the base under a sharp or a
 * rough film). Returns the count. */
int fit_starts(cf_model_id model, const double *base, const int *held, const double *warm,
               double (*starts)[CF_MAX_DIM], int max);

#endif /* CLAYFIT_FIT_STARTS_H */
