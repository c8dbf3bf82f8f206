/* The model choice's decision on the candidates' figures (cf_fit_auto
 * fits and scores them; include/clayfit/fit.h states the rule). Private to
 * src/fit; separate so that tests can check the rule on figures made by
 * hand. */
#ifndef CLAYFIT_FIT_CHOICE_H
#define CLAYFIT_FIT_CHOICE_H

#include <stddef.h>

#include "clayfit/fit.h"

/* One candidate of the choice. `physical`: the rung is the simpler
 * physical reading of a richer rung whose film is a second lobe (a single
 * tailed lobe, M2T once it exists); it wins over such a model when it does
 * as well within the margins. */
typedef struct fit_choice_rung {
  cf_model_id model;
  int physical;
} fit_choice_rung;

/* The candidates in the order the walk goes up the ladder (simplest
 * first); *count receives their number. */
const fit_choice_rung *fit_choice_rungs(int *count);

/* Decide on choice->candidate[0 .. count − 1] (model, ok, physical, bic,
 * heldout_score filled; margins set): the walk up the ladder, the held-out
 * guard, the physical reading; sets choice->chosen, the candidates'
 * `chosen` and notes. At least one candidate must be ok. */
void fit_choice_decide(cf_fit_choice *choice);

/* 1 when the fit has a film (film_roughness and film_f0) that is not a
 * film: film roughness above CF_FIT_FILM_MAX_ROUGHNESS, or a fitted film
 * F0 above CF_FIT_FILM_MAX_F0; why (if not NULL) receives the values in
 * words. */
int fit_choice_stacked_lobes(const cf_fit_result *fit, char *why, size_t size);

#endif /* CLAYFIT_FIT_CHOICE_H */
