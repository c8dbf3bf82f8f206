/* The names of fit.h's enumerations and the release of a result: what
 * reading fit.json back needs of the fit layer. Here, in the library
 * clayfit_fit_read, rather than beside the solver, so that reading a
 * fit.json does not link Ceres (src/fit/CMakeLists.txt). */
#include <stdlib.h>

#include "clayfit/fit.h"

const char *cf_fit_stage_name(cf_fit_stage stage) {
  switch (stage) {
    case CF_FIT_STAGE_START:
      return "start";
    case CF_FIT_STAGE_REFINE:
      return "refine";
    case CF_FIT_STAGE_SOLVE:
      return "solve";
    case CF_FIT_STAGE_STATISTICS:
      return "statistics";
    case CF_FIT_STAGE_COUNT:
      break;
  }
  return "unknown";
}

const char *cf_param_status_name(cf_param_status status) {
  switch (status) {
    case CF_PARAM_FITTED:
      return "fitted";
    case CF_PARAM_HELD:
      return "held";
    case CF_PARAM_HELD_FOR_SCALE:
      return "held: sets the absolute scale";
    case CF_PARAM_UNCONSTRAINED:
      return "not constrained by this capture";
    case CF_PARAM_AT_BOUND:
      return "fitted: at a bound of its range";
  }
  return "unknown";
}

void cf_fit_result_free(cf_fit_result *result) {
  free(result->exposures);
  free(result->exposure_sd);
  free(result->white_balance);
  free(result->white_balance_sd);
  result->exposure_sd = result->white_balance = result->white_balance_sd = NULL;
  free(result->light_gains);
  free(result->light_gains_sd);
  free(result->light_names);
  result->light_gains = result->light_gains_sd = NULL;
  result->light_names = NULL;
  result->light_count = 0;
  free(result->image_rmse);
  free(result->image_relative_rmse);
  result->exposures = result->image_rmse = result->image_relative_rmse = NULL;
}

const char *cf_sampling_name(cf_sampling sampling) {
  switch (sampling) {
    case CF_SAMPLING_UNIFORM:
      return "uniform";
    case CF_SAMPLING_STRATIFIED:
      return "stratified";
    case CF_SAMPLING_IMPORTANCE:
      return "importance";
    case CF_SAMPLING_COUNT:
      break;
  }
  return "unknown";
}
