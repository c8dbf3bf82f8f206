/* The model's slots as unknowns (kind.h): each as it is, as its logarithm
 * (the albedo) or as its square (the Oren-Nayar σ): fit_slot_form_of. */
#include <math.h>

#include "problem.h"

fit_slot_form fit_slot_form_of(cf_model_id model, int slot) {
  const cf_param_info *info = cf_model_slot_param(model, slot, NULL);
  if (info && info->id == CF_PARAM_ALBEDO) return FIT_SLOT_LOG;
  if (info && info->id == CF_PARAM_DIFFUSE_ROUGHNESS) return FIT_SLOT_SQUARE;
  return FIT_SLOT_PLAIN;
}

void fit_problem_free_slot(fit_problem *p, int slot) {
  const cf_param_info *info = cf_model_slot_param(p->model, slot, NULL);
  if (!info) return;
  switch (fit_slot_form_of(p->model, slot)) {
    case FIT_SLOT_LOG:
      fit_unknowns_add(p, &fit_kind_material, slot, log(fmax(info->lower, FIT_ALBEDO_FLOOR)),
                       log(info->upper));
      break;
    case FIT_SLOT_SQUARE:
      fit_unknowns_add(p, &fit_kind_material, slot, info->lower * info->lower,
                       info->upper * info->upper);
      break;
    case FIT_SLOT_PLAIN:
    default:
      fit_unknowns_add(p, &fit_kind_material, slot, info->lower, info->upper);
      break;
  }
}

static double get(const fit_problem *p, const fit_values *v, int slot) {
  double value = v->params[slot];
  switch (fit_slot_form_of(p->model, slot)) {
    case FIT_SLOT_LOG:
      return log(value);
    case FIT_SLOT_SQUARE:
      return value * value;
    case FIT_SLOT_PLAIN:
    default:
      return value;
  }
}

static void set(const fit_problem *p, const double *x, const fit_unknown *u, int count,
                fit_values *v) {
  for (int i = 0; i < count; ++i) {
    int slot = u[i].slot;
    fit_slot_form form = fit_slot_form_of(p->model, slot);
    v->params[slot] = form == FIT_SLOT_LOG      ? exp(x[i])
                      : form == FIT_SLOT_SQUARE ? sqrt(fmax(x[i], 0.0))
                                                : x[i];
  }
}

/* d param / d x: 1, ρ for log ρ, 1/(2σ) for σ²; σ² unknowns are evaluated
 * at σ >= 1e-6 (so that ∂f/∂σ² = (∂f/∂σ)/(2σ) has no 0/0: f depends on
 * σ through σ² only, and differs from its value at σ = 0 by about 1e-13
 * relative there). */
static double chain(const fit_problem *p, fit_values *v, int slot) {
  switch (fit_slot_form_of(p->model, slot)) {
    case FIT_SLOT_LOG:
      return v->params[slot];
    case FIT_SLOT_SQUARE:
      v->params[slot] = fmax(v->params[slot], 1e-6);
      return 0.5 / v->params[slot];
    case FIT_SLOT_PLAIN:
    default:
      return 1.0;
  }
}

const fit_kind fit_kind_material = {
    .name = "material", .handle = FIT_HANDLE_MODEL, .get = get, .set = set, .chain = chain};
