/* The response curve's shape when the tone curve is unknown: the curve
 * freed on a subsample from a few starting shapes, the most likely going
 * on to the full solve (docs/fitting.md "Response curve"). Private to
 * src/fit. */
#ifndef CLAYFIT_FIT_RESPONSE_STARTS_H
#define CLAYFIT_FIT_RESPONSE_STARTS_H

#include "clayfit/capture.h"
#include "clayfit/fit.h"
#include "fit_plan.h"
#include "fit_sample.h"
#include "fit_problem.h"

/* With an unknown tone curve (unless o->no_response_starts): from the
 * refined (params, log_scale) under the identity, the material and the
 * curve solved on a subsample from each starting shape (the given start's
 * curve in `response` too, with o->use_start), and the values of the
 * lowest negative log-likelihood into params, log_scale and response
 * (CF_RESPONSE_MODEL_KNOTS slopes). sigma: the one σ without a noise
 * model. Otherwise nothing changes. */
cf_status fit_response_starts(const cf_capture *capture, const fit_population *population,
                              const cf_fit_options *o, const fit_plan *plan, double sigma,
                              double *params, double *log_scale, double *response, cf_error *err);

#endif /* CLAYFIT_FIT_RESPONSE_STARTS_H */
