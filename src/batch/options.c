/* A manifest entry's options into each model's cf_fit_options through the
 * fit layer's cf_fit_model_options and cf_fit_ladder_options, which build
 * clayfit fit's too: clayfit fit's defaults, then the entry's threads,
 * fit_exposures, budget and holds, so that an entry and a direct `clayfit
 * fit` with the same options and --threads give the same fit to the bit. */
#include <string.h>

#include "clayfit/batch.h"

cf_status cf_batch_fit_options(const cf_batch_entry *e, int threads, int *automatic,
                               cf_model_id *model, cf_fit_options ladder[CF_MODEL_COUNT],
                               cf_error *err) {
  cf_fit_options settings;
  cf_fit_default_options(&settings, CF_MODEL_LAMBERT);
  settings.threads = threads;
  settings.fit_exposures = e->fit_exposures;
  if (e->budget_given) settings.budget = e->budget;
  *automatic = strcmp(e->model, "auto") == 0;
  *model = CF_MODEL_CLAY;
  cf_status s = CF_OK;
  if (*automatic) {
    s = cf_fit_ladder_options(&settings, e->hold, e->hold_count, NULL, 0, ladder, err);
    for (int m = 0; s == CF_OK && m < CF_MODEL_COUNT; ++m)
      s = cf_fit_check_options(&ladder[m], err);
    return s;
  }
  s = cf_model_find(e->model, model, err);
  if (s == CF_OK)
    s = cf_fit_model_options(*model, &settings, e->hold, e->hold_count, NULL, 0, NULL,
                             &ladder[*model], err);
  return s == CF_OK ? cf_fit_check_options(&ladder[*model], err) : s;
}
