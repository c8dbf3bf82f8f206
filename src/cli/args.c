#include "args.h"

#include <stdio.h>

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

cf_status cli_parse_number(const char *text, const char *what, double *out, cf_error *err) {
  char *end = NULL;
  errno = 0;
  double x = strtod(text, &end);
  if (end == text || *end != '\0')
    return cf_error_set(err, CF_EINVAL, "%s: '%s' is not a number", what, text);
  if (!isfinite(x) || errno == ERANGE)
    return cf_error_set(err, CF_EINVAL, "%s: '%s' is not a finite number", what, text);
  *out = x;
  return CF_OK;
}

cf_status cli_parse_list(const char *text, const char *what, int count, double *out,
                         cf_error *err) {
  char buffer[512];
  if (strlen(text) >= sizeof buffer)
    return cf_error_set(err, CF_EINVAL, "%s: value too long", what);
  strcpy(buffer, text);
  int n = 0;
  char *cursor = buffer;
  for (;;) {
    char *comma = strchr(cursor, ',');
    if (comma) *comma = '\0';
    if (n == count)
      return cf_error_set(err, CF_EINVAL, "%s: '%s' has more than %d numbers", what, text, count);
    cf_status s = cli_parse_number(cursor, what, &out[n], err);
    if (s != CF_OK) return s;
    ++n;
    if (!comma) break;
    cursor = comma + 1;
  }
  if (n != count)
    return cf_error_set(err, CF_EINVAL, "%s: '%s' has %d number%s, expected %d", what, text, n,
                        n == 1 ? "" : "s", count);
  return CF_OK;
}

cf_status cli_parse_direction(const char *text, const char *what, double out[3], cf_error *err) {
  cf_status s = cli_parse_list(text, what, 3, out, err);
  if (s != CF_OK) return s;
  /* scale by the largest component first, so that no square overflows */
  double largest = fmax(fabs(out[0]), fmax(fabs(out[1]), fabs(out[2])));
  if (largest == 0.0)
    return cf_error_set(err, CF_EINVAL,
                        "%s: '%s' has zero length; a direction needs a "
                        "non-zero length",
                        what, text);
  for (int k = 0; k < 3; ++k) out[k] /= largest;
  double length = sqrt(out[0] * out[0] + out[1] * out[1] + out[2] * out[2]);
  for (int k = 0; k < 3; ++k) out[k] /= length;
  return CF_OK;
}

cf_status cli_parse_count(const char *text, const char *what, long min, long max, long *out,
                          cf_error *err) {
  char *end = NULL;
  errno = 0;
  long x = strtol(text, &end, 10);
  if (end == text || *end != '\0' || errno == ERANGE)
    return cf_error_set(err, CF_EINVAL, "%s: '%s' is not an integer", what, text);
  if (x < min || x > max)
    return cf_error_set(err, CF_ERANGE, "%s: %ld is outside [%ld, %ld]", what, x, min, max);
  *out = x;
  return CF_OK;
}

/* Apply one "name=value" assignment to the parameter vector. */
cf_status cli_apply_param(cf_model_id model, const char *flag, const char *assignment,
                          double *params, int *given, cf_error *err) {
  const char *equals = strchr(assignment, '=');
  if (!equals || equals == assignment)
    return cf_error_set(err, CF_EINVAL,
                        "%s '%s': expected name=value (for example "
                        "albedo=0.8,0.5,0.3 or roughness=0.4)",
                        flag, assignment);
  char name[64];
  size_t length = (size_t)(equals - assignment);
  if (length >= sizeof name)
    return cf_error_set(err, CF_EINVAL, "%s '%s': name too long", flag, assignment);
  memcpy(name, assignment, length);
  name[length] = '\0';

  int slot = 0;
  const cf_param_info *info = NULL;
  cf_status s = cf_model_param_find(model, name, &slot, &info, err);
  if (s != CF_OK) return s;
  if (given[slot]) return cf_error_set(err, CF_EINVAL, "%s %s is given twice", flag, name);

  char what[96];
  snprintf(what, sizeof what, "%s %s", flag, name);
  const char *value = equals + 1;
  double x[3] = {0.0, 0.0, 0.0};
  if (info->components == 3 && strchr(value, ',')) {
    s = cli_parse_list(value, what, 3, x, err);
  } else {
    s = cli_parse_number(value, what, &x[0], err);
    x[1] = x[2] = x[0];
  }
  if (s != CF_OK) return s;
  for (int c = 0; c < info->components; ++c) {
    params[slot + c] = x[c];
    given[slot + c] = 1;
  }
  return CF_OK;
}
