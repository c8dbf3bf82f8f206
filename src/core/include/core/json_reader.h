/* Strict reading of JSON input files over Jansson: every value is checked
 * for its type (and numbers for finiteness and range) as it is read, every
 * object for keys it does not know (a typo must not be ignored silently),
 * and every error names the file and the JSON path of the value
 * ("capture.json: lights[2].intensity[1]: expected a number, got a
 * string"). Parse errors name the line and column. In core (it needs only
 * Jansson) so that every layer reads its files with it: src/capture the
 * capture files, src/fit fit.json, src/export the json presets. An interface
 * of core to the layers above (src/core/include), never part of the public
 * headers. */
#ifndef CLAYFIT_CORE_JSON_READER_H
#define CLAYFIT_CORE_JSON_READER_H

#include <jansson.h>
#include <stddef.h>

#include "clayfit/status.h"

/* The document written to `path` with Jansson's `flags` through
 * cf_write_file: whole or not at all, errors with the system's reason. The
 * one way clayfit writes a JSON file. */
cf_status json_write_file(const json_t *doc, const char *path, size_t flags, cf_error *err);

/* A JSON string of untrusted text (a path, a name from a capture), which
 * may not be UTF-8 as Jansson requires: each byte of invalid UTF-8 becomes
 * U+FFFD (text_escape_utf8). NULL text is "". NULL if out of memory. */
json_t *json_text(const char *text);

/* x as a JSON number, or null where it is not finite (JSON has no NaN or
 * infinity: an undefined sd, an RMSE not computed). */
json_t *json_real_or_null(double x);

/* Where a value is: the file and its JSON path. Nodes chain on the stack. */
typedef struct json_at {
  const char *file;
  const struct json_at *parent;
  const char *key; /* member name, or NULL for an array element */
  size_t index;    /* array index when key is NULL */
} json_at;

/* The path of a location as text ("lights[2].intensity"). */
void json_at_path(const json_at *at, char *out, size_t size);

/* Set err to "<file>: <path>: <message>" and return status. */
cf_status json_fail(const json_at *at, cf_error *err, cf_status status, const char *format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

/* Load a JSON file (at most max_size bytes), rejecting duplicate keys; the
 * root must be an object. Parse errors give line and column. */
cf_status json_load_object(const char *path, size_t max_size, json_t **root, cf_error *err);

/* Child locations. */
json_at json_member_at(const json_at *parent, const char *key);
json_at json_element_at(const json_at *parent, size_t index);

/* CF_EPARSE if `object` has a key not in the NULL-terminated `known` list;
 * the message lists the known keys. */
cf_status json_check_keys(const json_t *object, const json_at *at, const char *const *known,
                          cf_error *err);

/* Typed getters for member `key` of `object` (at `at`). When the member is
 * absent: with required, CF_EPARSE ("missing"); otherwise CF_OK with *found
 * = 0 and the output untouched (found may be NULL for required members). */
cf_status json_get_object(const json_t *object, const json_at *at, const char *key, int required,
                          const json_t **out, int *found, cf_error *err);
cf_status json_get_array(const json_t *object, const json_at *at, const char *key, int required,
                         const json_t **out, int *found, cf_error *err);
cf_status json_get_string(const json_t *object, const json_at *at, const char *key, int required,
                          const char **out, int *found, cf_error *err);
/* A finite number in [lo, hi]. */
cf_status json_get_number(const json_t *object, const json_at *at, const char *key, int required,
                          double lo, double hi, double *out, int *found, cf_error *err);
/* An integer in [lo, hi]. */
cf_status json_get_integer(const json_t *object, const json_at *at, const char *key, int required,
                           long long lo, long long hi, long long *out, int *found, cf_error *err);
cf_status json_get_bool(const json_t *object, const json_at *at, const char *key, int required,
                        int *out, int *found, cf_error *err);
/* An array of exactly n finite numbers in [lo, hi]. */
cf_status json_get_numbers(const json_t *object, const json_at *at, const char *key, int required,
                           size_t n, double lo, double hi, double *out, int *found, cf_error *err);
/* A string that must be one of the NULL-terminated `choices`; *out is its
 * index. */
cf_status json_get_choice(const json_t *object, const json_at *at, const char *key, int required,
                          const char *const *choices, int *out, int *found, cf_error *err);

/* The value as a number array element etc., for arrays walked by hand. */
cf_status json_as_number(const json_t *value, const json_at *at, double lo, double hi, double *out,
                         cf_error *err);
cf_status json_as_string(const json_t *value, const json_at *at, const char **out, cf_error *err);

/* "a string", "an object", ... for messages. */
const char *json_type_name(const json_t *value);

#endif /* CLAYFIT_CORE_JSON_READER_H */
