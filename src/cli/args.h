/* Parsing of command-line values, with messages that say which option and
 * what was expected. */
#ifndef CLAYFIT_CLI_ARGS_H
#define CLAYFIT_CLI_ARGS_H

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

#endif /* CLAYFIT_CLI_ARGS_H */
