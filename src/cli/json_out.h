/* Small helpers over jansson for the CLI's JSON output. */
#ifndef CLAYFIT_CLI_JSON_OUT_H
#define CLAYFIT_CLI_JSON_OUT_H

#include <jansson.h>
#include <stdio.h>

/* A JSON array of n doubles. Non-finite values become null. */
json_t *json_doubles(const double *x, int n);

/* Write a JSON document with 17 significant digits and a final newline;
 * 0 on success. Takes ownership of doc. */
int json_print(FILE *out, json_t *doc);

#endif /* CLAYFIT_CLI_JSON_OUT_H */
