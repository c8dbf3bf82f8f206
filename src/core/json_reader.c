/* Strict JSON reading with path-based errors (json_reader.h). */
#include "core/json_reader.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/file.h"
#include "core/text_escape.h"

void json_at_path(const json_at *at, char *out, size_t size) {
  /* collect the chain root-first */
  const json_at *chain[64];
  int depth = 0;
  for (const json_at *p = at; p && depth < 64; p = p->parent)
    if (p->parent) chain[depth++] = p; /* the root has no name */
  size_t used = 0;
  out[0] = '\0';
  for (int i = depth - 1; i >= 0 && used < size; --i) {
    int n = chain[i]->key
                ? snprintf(out + used, size - used, "%s%s", used ? "." : "", chain[i]->key)
                : snprintf(out + used, size - used, "[%zu]", chain[i]->index);
    if (n > 0) used += (size_t)n;
  }
  if (!out[0]) snprintf(out, size, "(top level)");
}

cf_status json_fail(const json_at *at, cf_error *err, cf_status status, const char *format, ...) {
  char message[CF_ERROR_MESSAGE_SIZE], path[512];
  va_list args;
  va_start(args, format);
  vsnprintf(message, sizeof message, format, args);
  va_end(args);
  json_at_path(at, path, sizeof path);
  return cf_error_set(err, status, "%s: %s: %s", at->file, path, message);
}

cf_status json_load_object(const char *path, size_t max_size, json_t **root, cf_error *err) {
  char *text = NULL;
  size_t size = 0;
  cf_status s = cf_read_file(path, max_size, &text, &size, err);
  if (s != CF_OK) return s;
  json_error_t error;
  *root = json_loadb(text, size, JSON_REJECT_DUPLICATES, &error);
  free(text);
  /* Jansson 2.14 leaves the error empty when an allocation fails */
  if (!*root && (json_error_code(&error) == json_error_out_of_memory || !error.text[0]))
    return cf_error_set(err, CF_ENOMEM, "%s: out of memory while parsing its %zu bytes of JSON",
                        path, size);
  if (!*root && json_error_code(&error) == json_error_null_character)
    return cf_error_set(err, CF_EPARSE, "%s:%d:%d: a string holds \\u0000 (NUL): not accepted",
                        path, error.line, error.column);
  if (!*root)
    return cf_error_set(err, CF_EPARSE, "%s:%d:%d: invalid JSON: %s", path, error.line,
                        error.column, error.text);
  if (!json_is_object(*root)) {
    const char *type = json_type_name(*root);
    json_decref(*root);
    *root = NULL;
    return cf_error_set(err, CF_EPARSE, "%s: the top level must be an object, not %s", path, type);
  }
  return CF_OK;
}

json_at json_member_at(const json_at *parent, const char *key) {
  return (json_at){parent->file, parent, key, 0};
}

json_at json_element_at(const json_at *parent, size_t index) {
  return (json_at){parent->file, parent, NULL, index};
}

const char *json_type_name(const json_t *value) {
  switch (json_typeof(value)) {
    case JSON_OBJECT:
      return "an object";
    case JSON_ARRAY:
      return "an array";
    case JSON_STRING:
      return "a string";
    case JSON_INTEGER:
    case JSON_REAL:
      return "a number";
    case JSON_TRUE:
    case JSON_FALSE:
      return "a boolean";
    case JSON_NULL:
      return "null";
  }
  return "an unknown value";
}

cf_status json_check_keys(const json_t *object, const json_at *at, const char *const *known,
                          cf_error *err) {
  const char *key;
  json_t *value;
  json_object_foreach((json_t *)object, key, value) {
    int ok = 0;
    for (const char *const *k = known; *k; ++k) ok |= strcmp(key, *k) == 0;
    if (ok) continue;
    char list[512] = "";
    size_t used = 0;
    for (const char *const *k = known; *k && used < sizeof list; ++k) {
      int n = snprintf(list + used, sizeof list - used, "%s%s", k == known ? "" : ", ", *k);
      if (n > 0) used += (size_t)n;
    }
    return json_fail(at, err, CF_EPARSE, "unknown key '%s' (the keys here are: %s)", key, list);
  }
  return CF_OK;
}

/* The member, or NULL (with the missing-member error when required). */
static cf_status member(const json_t *object, const json_at *at, const char *key, int required,
                        const json_t **value, int *found, cf_error *err) {
  *value = json_object_get(object, key);
  if (found) *found = *value != NULL;
  if (!*value && required) return json_fail(at, err, CF_EPARSE, "missing required key '%s'", key);
  return CF_OK;
}

static cf_status expect(const json_t *value, const json_at *at, int ok, const char *what,
                        cf_error *err) {
  if (ok) return CF_OK;
  return json_fail(at, err, CF_EPARSE, "expected %s, got %s", what, json_type_name(value));
}

#define JSON_GETTER_PROLOGUE                                           \
  const json_t *value;                                                 \
  cf_status s = member(object, at, key, required, &value, found, err); \
  if (s != CF_OK || !value) return s;                                  \
  json_at here = json_member_at(at, key);

cf_status json_get_object(const json_t *object, const json_at *at, const char *key, int required,
                          const json_t **out, int *found, cf_error *err) {
  JSON_GETTER_PROLOGUE
  s = expect(value, &here, json_is_object(value), "an object", err);
  if (s == CF_OK) *out = value;
  return s;
}

cf_status json_get_array(const json_t *object, const json_at *at, const char *key, int required,
                         const json_t **out, int *found, cf_error *err) {
  JSON_GETTER_PROLOGUE
  s = expect(value, &here, json_is_array(value), "an array", err);
  if (s == CF_OK) *out = value;
  return s;
}

cf_status json_as_string(const json_t *value, const json_at *at, const char **out, cf_error *err) {
  cf_status s = expect(value, at, json_is_string(value), "a string", err);
  if (s != CF_OK) return s;
  if (strlen(json_string_value(value)) != json_string_length(value))
    return json_fail(at, err, CF_EPARSE, "the string contains a NUL character");
  *out = json_string_value(value);
  return CF_OK;
}

cf_status json_get_string(const json_t *object, const json_at *at, const char *key, int required,
                          const char **out, int *found, cf_error *err) {
  JSON_GETTER_PROLOGUE
  return json_as_string(value, &here, out, err);
}

cf_status json_as_number(const json_t *value, const json_at *at, double lo, double hi, double *out,
                         cf_error *err) {
  cf_status s = expect(value, at, json_is_number(value), "a number", err);
  if (s != CF_OK) return s;
  double x = json_number_value(value);
  if (!isfinite(x)) return json_fail(at, err, CF_EPARSE, "the number must be finite");
  if (x >= lo && x <= hi) {
    *out = x;
    return CF_OK;
  }
  /* the open-ended ranges in words, for a value on the wrong side of 0;
   * beyond their real ends (1e300), the real range */
  if (hi >= 1e300 && lo > 0.0 && lo <= 1e-300 && x <= 0.0)
    return json_fail(at, err, CF_ERANGE, "%.17g must be greater than 0", x);
  if (hi >= 1e300 && lo == 0.0 && x < 0.0)
    return json_fail(at, err, CF_ERANGE, "%.17g must be 0 or greater", x);
  return json_fail(at, err, CF_ERANGE, "%.17g is outside [%g, %g]", x, lo, hi);
}

cf_status json_get_number(const json_t *object, const json_at *at, const char *key, int required,
                          double lo, double hi, double *out, int *found, cf_error *err) {
  JSON_GETTER_PROLOGUE
  return json_as_number(value, &here, lo, hi, out, err);
}

cf_status json_get_integer(const json_t *object, const json_at *at, const char *key, int required,
                           long long lo, long long hi, long long *out, int *found, cf_error *err) {
  JSON_GETTER_PROLOGUE
  s = expect(value, &here, json_is_integer(value), "an integer", err);
  if (s != CF_OK) return s;
  long long x = json_integer_value(value);
  if (x < lo || x > hi)
    return json_fail(&here, err, CF_ERANGE, "%lld is outside [%lld, %lld]", x, lo, hi);
  *out = x;
  return CF_OK;
}

cf_status json_get_bool(const json_t *object, const json_at *at, const char *key, int required,
                        int *out, int *found, cf_error *err) {
  JSON_GETTER_PROLOGUE
  s = expect(value, &here, json_is_boolean(value), "true or false", err);
  if (s == CF_OK) *out = json_is_true(value);
  return s;
}

cf_status json_get_numbers(const json_t *object, const json_at *at, const char *key, int required,
                           size_t n, double lo, double hi, double *out, int *found, cf_error *err) {
  JSON_GETTER_PROLOGUE
  s = expect(value, &here, json_is_array(value), "an array of numbers", err);
  if (s != CF_OK) return s;
  if (json_array_size(value) != n)
    return json_fail(&here, err, CF_EPARSE, "expected %zu numbers, got %zu", n,
                     json_array_size(value));
  for (size_t i = 0; i < n; ++i) {
    json_at element = json_element_at(&here, i);
    s = json_as_number(json_array_get(value, i), &element, lo, hi, &out[i], err);
    if (s != CF_OK) return s;
  }
  return CF_OK;
}

cf_status json_get_choice(const json_t *object, const json_at *at, const char *key, int required,
                          const char *const *choices, int *out, int *found, cf_error *err) {
  JSON_GETTER_PROLOGUE
  const char *text;
  s = json_as_string(value, &here, &text, err);
  if (s != CF_OK) return s;
  char list[256] = "";
  size_t used = 0;
  for (int i = 0; choices[i]; ++i) {
    if (strcmp(text, choices[i]) == 0) {
      *out = i;
      return CF_OK;
    }
    int n = snprintf(list + used, sizeof list - used, "%s'%s'", i ? ", " : "", choices[i]);
    if (n > 0 && used + (size_t)n < sizeof list) used += (size_t)n;
  }
  return json_fail(&here, err, CF_EPARSE, "'%s' is not one of %s", text, list);
}

cf_status json_write_file(const json_t *doc, const char *path, size_t flags, cf_error *err) {
  char *text = doc ? json_dumps(doc, flags) : NULL;
  if (!text) return cf_error_set(err, CF_ENOMEM, "%s: out of memory for the JSON text", path);
  cf_status s = cf_write_file(path, text, strlen(text), err);
  free(text);
  return s;
}

json_t *json_text(const char *text) {
  char *valid = text_escape_alloc(text_escape_utf8, text);
  json_t *string = valid ? json_string(valid) : NULL;
  free(valid);
  return string;
}

json_t *json_real_or_null(double x) {
  return isfinite(x) ? json_real(x) : json_null();
}
