/* What a fit frees and holds (fit_plan.h). */
#include "fit_plan.h"

#include <string.h>

/* The interface F0 that fixes the absolute scale of a capture whose lights
 * are known only up to a factor (docs/model.md §5.5), or −1. */
int fit_scale_slot(cf_model_id model) {
  const cf_model_info *info = cf_model_info_get(model);
  if (!info) return -1;
  switch (info->ggx_twin) { /* a tailed twin's vector starts with its twin's */
    case CF_MODEL_DIELECTRIC:
      return CF_DIELECTRIC_F0;
    case CF_MODEL_CLEARCOAT:
      return CF_CLEARCOAT_F0;
    case CF_MODEL_CLAY:
      return CF_CLAY_FILM_F0;
    default:
      return -1;
  }
}

cf_status fit_plan_for(const cf_capture *capture, const cf_fit_options *o, fit_plan *plan) {
  const cf_model_info *m = cf_model_info_get(o->model);
  cf_capture_summary summary;
  cf_capture_summarize(capture, &summary);
  memset(plan, 0, sizeof *plan);
  for (int k = 0; k < m->dim; ++k) plan->status[k] = o->hold[k] ? CF_PARAM_HELD : CF_PARAM_FITTED;
  int sk = fit_scale_slot(o->model);
  /* an unknown tone curve leaves the level unmeasured too: the curve's
   * stretch R(x/k) trades with every lobe's level (docs/model.md §5.4) */
  if ((summary.radiometry_relative || summary.tone_curve_unknown) && sk >= 0) {
    /* the scale is fitted, fixed by the interface F0 (held, 0.04 unless the
     * user says otherwise) */
    plan->scale = 1;
    if (!o->free[sk] && !o->hold[sk]) plan->status[sk] = CF_PARAM_HELD_FOR_SCALE;
  }
  plan->exposures = cf_capture_image_count(capture) > 1 ? o->fit_exposures : CF_GAINS_NONE;
  return CF_OK;
}

cf_status fit_declare(fit_problem *p, const fit_plan *plan, cf_error *err) {
  fit_problem_clear_unknowns(p); /* (and the trust region: Ceres' initial one) */
  for (int k = 0; k < fit_problem_dim(p); ++k)
    if (plan->status[k] == CF_PARAM_FITTED) fit_problem_free_slot(p, k);
  if (plan->scale) fit_problem_free_scale(p);
  /* a gain per light: per image's group where each image has one light,
   * else inside the sums (fit_problem_free_light_gains) */
  if (plan->exposures == CF_GAINS_PER_LIGHT && fit_problem_groups(p)->several_lights) {
    fit_problem_free_light_gains(p);
  } else if (plan->exposures) {
    fit_problem_group_gains(p, plan->exposures == CF_GAINS_PER_LIGHT);
    fit_problem_free_exposures(p);
  }
  if (plan->exposures == CF_GAINS_PER_IMAGE_RGB) fit_problem_free_balance(p);
  if (plan->response) fit_problem_free_response(p);
  return fit_problem_finish(p, err);
}

cf_status fit_declare_robust(fit_problem *p, const fit_plan *plan, const cf_fit_options *o,
                             double sigma, cf_error *err) {
  cf_status s = fit_declare(p, plan, err);
  if (s != CF_OK) return s;
  if (!fit_capture_has_noise(fit_problem_capture(p))) fit_problem_set_sigma(p, sigma);
  fit_problem_set_loss(p, o->loss, o->loss_scale);
  return CF_OK;
}

void fit_progress(const cf_fit_options *o, const char *stage, size_t done, size_t total) {
  if (o->progress) o->progress(o->progress_user, stage, done, total);
}
