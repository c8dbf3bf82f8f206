/* What a fit frees and holds: the plan, and its unknowns declared on a
 * problem (fit_problem.h). Private to src/fit. */
#ifndef CLAYFIT_FIT_PLAN_H
#define CLAYFIT_FIT_PLAN_H

#include <stddef.h>

#include "clayfit/capture.h"
#include "clayfit/fit.h"
#include "fit_problem.h"

/* What is free: per model slot its status (CF_PARAM_FITTED: free), and
 * whether the global scale and the exposures are. */
typedef struct fit_plan {
  cf_param_status status[CF_MAX_DIM];
  int scale;
  int exposures; /* CF_GAINS_*: the gains free, per image or light, or RGB */
  int response; /* the response curve (an unknown tone curve) */
} fit_plan;

/* The interface F0 that fixes the absolute scale of a capture whose lights
 * are known only up to a factor (docs/model.md §5.5), or −1
 * for a model without one. */
int fit_scale_slot(cf_model_id model);

/* The value that slot is held at for the scale unless the user holds
 * another (docs/model.md (42): F0 = 0.04, an uncoated dielectric of IOR 1.5). */
#define FIT_SCALE_F0 0.04

/* The plan for the options' model on this capture. */
cf_status fit_plan_for(const cf_capture *capture, const cf_fit_options *o, fit_plan *plan);

/* Declare the plan's unknowns on the problem. */
cf_status fit_declare(fit_problem *p, const fit_plan *plan, cf_error *err);

/* ... for a robust solve: then `sigma` for every residual (unless the
 * capture has a noise model; through the curve when the response is on)
 * and the options' loss. */
cf_status fit_declare_robust(fit_problem *p, const fit_plan *plan, const cf_fit_options *o,
                             double sigma, cf_error *err);

void fit_progress(const cf_fit_options *o, const char *stage, size_t done, size_t total);

#endif /* CLAYFIT_FIT_PLAN_H */
