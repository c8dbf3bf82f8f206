/* Parsing of command-line values, with messages that say which option and
 * what was expected. */
#ifndef CLAYFIT_CLI_ARGS_H
#define CLAYFIT_CLI_ARGS_H

#include "clayfit/model.h"
#include "clayfit/status.h"

/* A finite number; the whole text must be consumed. */
cf_status cli_parse_number(const char *text, const char *what, double *out, cf_error *err);

/* A comma-separated list of exactly `count` finite numbers. */
cf_status cli_parse_list(const char *text, const char *what, int count, double *out, cf_error *err);

/* A direction "x,y,z": finite, non-zero length, returned normalised. */
cf_status cli_parse_direction(const char *text, const char *what, double out[3], cf_error *err);

/* A positive integer. */
cf_status cli_parse_count(const char *text, const char *what, long min, long max, long *out,
                          cf_error *err);

/* Apply one --param "name=value" to a model's parameter vector: an RGB
 * parameter takes "r,g,b" or one number for all three. given[] marks the
 * slots set so far (a parameter given twice is an error). The range is
 * not checked here (cf_params_check). */
cf_status cli_apply_param(cf_model_id model, const char *flag, const char *assignment,
                          double *params, int *given,
                          cf_error *err);

#endif /* CLAYFIT_CLI_ARGS_H */
