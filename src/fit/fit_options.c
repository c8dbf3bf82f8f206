/* A fit's options built from the settings every model shares and the
 * parameters held or freed by name: one place for clayfit fit (its
 * --hold and --free) and clayfit batch (a manifest's "hold"), so that the
 * same options give the same fit to the bit. */
#include <string.h>

#include "clayfit/fit.h"

/* One hold into o (given[] marks the slots held so far). */
static cf_status apply_hold(cf_fit_options *o, const cf_fit_hold *h, int slot,
                            const cf_param_info *info, int *given, cf_error *err) {
  if (given[slot]) return cf_error_set(err, CF_EINVAL, "--hold %s is given twice", h->name);
  if (h->count != 1 && h->count != info->components)
    return cf_error_set(err, CF_EINVAL, "--hold %s: expected %s, got %d numbers", h->name,
                        info->components == 1 ? "one number" : "one number or r,g,b",
                        h->count);
  for (int c = 0; c < info->components; ++c) {
    o->hold_value[slot + c] = h->value[h->count == 1 ? 0 : c];
    given[slot + c] = 1;
  }
  return CF_OK;
}

static cf_status apply_holds(cf_fit_options *o, const cf_fit_hold *holds, int hold_count,
                             int *known, cf_error *err) {
  int given[CF_MAX_DIM] = {0};
  cf_status s = CF_OK;
  for (int i = 0; s == CF_OK && i < hold_count; ++i) {
    int slot = 0;
    const cf_param_info *info = NULL;
    s = cf_model_param_find(o->model, holds[i].name, &slot, &info, err);
    if (known && s == CF_ENOTFOUND) {
      s = CF_OK;
      continue;
    }
    if (known && s == CF_OK) known[i] = 1;
    if (s == CF_OK) s = apply_hold(o, &holds[i], slot, info, given, err);
  }
  for (int k = 0; k < CF_MAX_DIM; ++k) o->hold[k] = given[k];
  return s;
}

static cf_status apply_frees(cf_fit_options *o, const char *const *frees, int free_count,
                             int *known, cf_error *err) {
  for (int i = 0; i < free_count; ++i) {
    int slot = 0;
    const cf_param_info *info = NULL;
    cf_status s = cf_model_param_find(o->model, frees[i], &slot, &info, err);
    if (known && s == CF_ENOTFOUND) continue;
    if (s != CF_OK) return s;
    if (known) known[i] = 1;
    for (int c = 0; c < info->components; ++c) {
      if (o->hold[slot + c])
        return cf_error_set(err, CF_EINVAL, "%s is both held and freed", info->name);
      o->free[slot + c] = 1;
    }
  }
  return CF_OK;
}

cf_status cf_fit_model_options(cf_model_id model, const cf_fit_options *settings,
                               const cf_fit_hold *holds, int hold_count,
                               const char *const *frees, int free_count, int *known,
                               cf_fit_options *o, cf_error *err) {
  cf_fit_default_options(o, model);
  o->loss = settings->loss;
  o->loss_scale = settings->loss_scale;
  o->fit_exposures = settings->fit_exposures;
  o->jpeg_plain = settings->jpeg_plain;
  o->multistart = settings->multistart;
  o->max_iterations = settings->max_iterations;
  o->threads = settings->threads;
  o->density = settings->density;
  o->footprint = settings->footprint;
  o->footprint_tolerance = settings->footprint_tolerance;
  o->budget = settings->budget;
  o->sampling = settings->sampling;
  cf_status s = apply_holds(o, holds, hold_count, known, err);
  if (s == CF_OK) s = apply_frees(o, frees, free_count, known ? known + hold_count : NULL, err);
  return s;
}

cf_status cf_fit_ladder_options(const cf_fit_options *settings, const cf_fit_hold *holds,
                                int hold_count, const char *const *frees, int free_count,
                                cf_fit_options ladder[CF_MODEL_COUNT], cf_error *err) {
  int known[2 * CF_FIT_MAX_NAMED] = {0};
  if (hold_count > CF_FIT_MAX_NAMED || free_count > CF_FIT_MAX_NAMED)
    return cf_error_set(err, CF_ERANGE, "more than %d --hold or --free", CF_FIT_MAX_NAMED);
  cf_status s = CF_OK;
  for (int m = 0; s == CF_OK && m < CF_MODEL_COUNT; ++m)
    s = cf_fit_model_options((cf_model_id)m, settings, holds, hold_count, frees, free_count,
                             known, &ladder[m], err);
  for (int i = 0; s == CF_OK && i < hold_count + free_count; ++i) {
    if (known[i]) continue;
    int hold = i < hold_count;
    s = cf_error_set(err, CF_ENOTFOUND,
                     "%s %s: no model of the ladder has a parameter of that name (see clayfit "
                     "models)",
                     hold ? "--hold" : "--free", hold ? holds[i].name : frees[i - hold_count]);
  }
  return s;
}
