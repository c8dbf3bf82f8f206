/* fit.json (data_schema/fit.schema.json): what a fit wrote down. Private
 * to src/fit and the CLI. */
#ifndef CLAYFIT_FIT_JSON_H
#define CLAYFIT_FIT_JSON_H

#include "clayfit/capture.h"
#include "clayfit/fit.h"

typedef struct cf_fit_report {
  const cf_capture *capture;
  const char *capture_path;
  const cf_fit_result *result;
  const cf_fit_choice *choice; /* NULL: the model was forced (--model M) */
  const char *version;
  cf_loss loss;
  double loss_scale;
  double density; /* NaN: MODEL.md's convention */
  double load_seconds, fit_seconds;
  int footprint;              /* cf_fit_options.footprint */
  double footprint_tolerance; /* cf_fit_options.footprint_tolerance */
} cf_fit_report;

cf_status cf_fit_write_json(const char *path, const cf_fit_report *report, cf_error *err);

#endif /* CLAYFIT_FIT_JSON_H */
