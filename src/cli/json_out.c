#include "json_out.h"

#include <math.h>

json_t *json_doubles(const double *x, int n) {
  json_t *array = json_array();
  for (int k = 0; k < n; ++k)
    json_array_append_new(array, isfinite(x[k]) ? json_real(x[k]) : json_null());
  return array;
}

int json_print(FILE *out, json_t *doc) {
  int status = json_dumpf(doc, out, JSON_INDENT(2) | JSON_REAL_PRECISION(17));
  json_decref(doc);
  if (status == 0 && fputc('\n', out) == EOF) status = -1;
  return status;
}
