/* Reading fit.json (data_schema/fit.schema.json) back: for clayfit export
 * and clayfit report (include/clayfit/fit_file.h). The file is untrusted:
 * every field is checked for its type and range with core's strict JSON
 * reader, every object for unknown keys, and every error names the file and
 * JSON path. */
#include <jansson.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clayfit/fit_file.h"
#include "core/file.h"
#include "core/json_reader.h"

#define HUGE_NUMBER 1e308

/* Shorthands: every call names the object, its location and the key. */
#define TRY(call)               \
  do {                          \
    cf_status s_ = (call);      \
    if (s_ != CF_OK) return s_; \
  } while (0)

/* A string member copied into a fixed buffer; too long is an error, not a
 * silent truncation. */
static cf_status get_text(const json_t *obj, const json_at *at, const char *key, char *out,
                          size_t size, cf_error *err) {
  const char *text;
  TRY(json_get_string(obj, at, key, 1, &text, NULL, err));
  if (strlen(text) >= size) {
    json_at here = json_member_at(at, key);
    return json_fail(&here, err, CF_ERANGE, "the string is longer than %zu bytes", size - 1);
  }
  memcpy(out, text, strlen(text) + 1);
  return CF_OK;
}

static cf_status get_count(const json_t *obj, const json_at *at, const char *key, size_t *out,
                           cf_error *err) {
  long long x;
  TRY(json_get_integer(obj, at, key, 1, 0, (long long)1 << 53, &x, NULL, err));
  *out = (size_t)x;
  return CF_OK;
}

static cf_status get_int(const json_t *obj, const json_at *at, const char *key, int lo, int hi,
                         int *out, cf_error *err) {
  long long x;
  TRY(json_get_integer(obj, at, key, 1, lo, hi, &x, NULL, err));
  *out = (int)x;
  return CF_OK;
}

static cf_status get_nonneg(const json_t *obj, const json_at *at, const char *key, double *out,
                            cf_error *err) {
  return json_get_number(obj, at, key, 1, 0.0, HUGE_NUMBER, out, NULL, err);
}

static cf_status get_member(const json_t *obj, const json_at *at, const char *key,
                            const json_t **out, cf_error *err) {
  *out = json_object_get(obj, key);
  if (!*out) return json_fail(at, err, CF_EPARSE, "missing required key '%s'", key);
  return CF_OK;
}

/* ---- parameters ---- */

static cf_status status_from_name(const json_t *value, const json_at *at, cf_param_status *out,
                                  cf_error *err) {
  const char *text;
  TRY(json_as_string(value, at, &text, err));
  const cf_param_status all[] = {CF_PARAM_FITTED, CF_PARAM_HELD, CF_PARAM_HELD_FOR_SCALE,
                                 CF_PARAM_UNCONSTRAINED, CF_PARAM_AT_BOUND};
  for (size_t i = 0; i < sizeof all / sizeof all[0]; ++i)
    if (strcmp(text, cf_param_status_name(all[i])) == 0) {
      *out = all[i];
      return CF_OK;
    }
  return json_fail(at, err, CF_EPARSE,
                   "'%s' is not a parameter status ('fitted', 'held', 'held: sets the absolute "
                   "scale', 'not constrained by this capture', 'fitted: at a bound of its range')",
                   text);
}

/* One number, or [r, g, b] for an RGB parameter, within [lo, hi]. */
static cf_status get_value(const json_t *obj, const json_at *at, const char *key, int components,
                           double lo, double hi, double *out, cf_error *err) {
  if (components == 3) return json_get_numbers(obj, at, key, 1, 3, lo, hi, out, NULL, err);
  return json_get_number(obj, at, key, 1, lo, hi, out, NULL, err);
}

/* A standard deviation: a number >= 0, or null (NaN); per channel for RGB. */
static cf_status sd_as(const json_t *value, const json_at *at, double *out, cf_error *err) {
  if (json_is_null(value)) {
    *out = NAN;
    return CF_OK;
  }
  return json_as_number(value, at, 0.0, HUGE_NUMBER, out, err);
}

static cf_status get_sd(const json_t *obj, const json_at *at, int components, double *out,
                        cf_error *err) {
  const json_t *value;
  TRY(get_member(obj, at, "sd", &value, err));
  json_at here = json_member_at(at, "sd");
  if (components == 1) return sd_as(value, &here, out, err);
  if (!json_is_array(value) || json_array_size(value) != 3)
    return json_fail(&here, err, CF_EPARSE, "expected an array of 3 numbers or nulls, got %s",
                     json_type_name(value));
  for (size_t c = 0; c < 3; ++c) {
    json_at element = json_element_at(&here, c);
    TRY(sd_as(json_array_get(value, c), &element, &out[c], err));
  }
  return CF_OK;
}

static cf_status get_status(const json_t *obj, const json_at *at, int components,
                            cf_param_status *out, cf_error *err) {
  const json_t *value;
  TRY(get_member(obj, at, "status", &value, err));
  json_at here = json_member_at(at, "status");
  if (json_is_string(value)) {
    TRY(status_from_name(value, &here, &out[0], err));
    for (int c = 1; c < components; ++c) out[c] = out[0];
    return CF_OK;
  }
  if (components != 3 || !json_is_array(value) || json_array_size(value) != 3)
    return json_fail(&here, err, CF_EPARSE, "expected a status name%s, got %s",
                     components == 3 ? " or an array of 3" : "", json_type_name(value));
  for (size_t c = 0; c < 3; ++c) {
    json_at element = json_element_at(&here, c);
    TRY(status_from_name(json_array_get(value, c), &element, &out[c], err));
  }
  return CF_OK;
}

/* `params`: every parameter of the model, nothing else. */
static cf_status read_params(const json_t *obj, const json_at *at, cf_model_id model,
                             double *params, double *sd, cf_param_status *status, cf_error *err) {
  const cf_model_info *m = cf_model_info_get(model);
  const char *key;
  json_t *value;
  json_object_foreach((json_t *)obj, key, value) {
    int slot;
    cf_error ignored = {0};
    if (cf_model_param_find(model, key, &slot, NULL, &ignored) != CF_OK) {
      json_at here = json_member_at(at, key);
      return json_fail(&here, err, CF_EPARSE, "model %s (%s) has no parameter '%s'", m->code,
                       m->name, key);
    }
  }
  for (int j = 0; j < m->param_count; ++j) {
    const cf_param_info *info = cf_param_info_get(m->params[j]);
    int k = m->offsets[j];
    const json_t *p;
    TRY(json_get_object(obj, at, info->name, 1, &p, NULL, err));
    json_at here = json_member_at(at, info->name);
    static const char *const known[] = {"value", "sd",    "unit",    "status",
                                        "lower", "upper", "meaning", NULL};
    TRY(json_check_keys(p, &here, known, err));
    TRY(get_value(p, &here, "value", info->components, info->lower, info->upper, params + k, err));
    if (sd) TRY(get_sd(p, &here, info->components, sd + k, err));
    if (status) TRY(get_status(p, &here, info->components, status + k, err));
    const char *unit;
    double bound;
    TRY(json_get_string(p, &here, "unit", 1, &unit, NULL, err));
    if (strcmp(unit, info->unit) != 0) {
      json_at u = json_member_at(&here, "unit");
      return json_fail(&u, err, CF_EPARSE, "'%s' is not the unit of %s ('%s')", unit, info->name,
                       info->unit);
    }
    TRY(json_get_number(p, &here, "lower", 1, -HUGE_NUMBER, HUGE_NUMBER, &bound, NULL, err));
    TRY(json_get_number(p, &here, "upper", 1, -HUGE_NUMBER, HUGE_NUMBER, &bound, NULL, err));
    const char *meaning;
    TRY(json_get_string(p, &here, "meaning", 1, &meaning, NULL, err));
  }
  return CF_OK;
}

/* Parameters by name (a start and where it ended): every one of the model. */
static cf_status read_values_by_name(const json_t *obj, const json_at *at, cf_model_id model,
                                     double *params, cf_error *err) {
  const cf_model_info *m = cf_model_info_get(model);
  if (json_object_size(obj) != (size_t)m->param_count)
    return json_fail(at, err, CF_EPARSE, "expected the %d parameters of model %s, got %zu keys",
                     m->param_count, m->code, json_object_size(obj));
  for (int j = 0; j < m->param_count; ++j) {
    const cf_param_info *info = cf_param_info_get(m->params[j]);
    TRY(get_value(obj, at, info->name, info->components, -HUGE_NUMBER, HUGE_NUMBER,
                  params + m->offsets[j], err));
  }
  return CF_OK;
}

static cf_status read_model(const json_t *root, const json_at *at, const char *key,
                            cf_model_id *model, cf_error *err) {
  const json_t *obj;
  TRY(json_get_object(root, at, key, 1, &obj, NULL, err));
  json_at here = json_member_at(at, key);
  static const char *const known[] = {"code", "name", NULL};
  TRY(json_check_keys(obj, &here, known, err));
  const char *const *codes = cf_model_codes(), *const *names = cf_model_names();
  int code, name;
  TRY(json_get_choice(obj, &here, "code", 1, codes, &code, NULL, err));
  TRY(json_get_choice(obj, &here, "name", 1, names, &name, NULL, err));
  const cf_model_info *m = cf_model_info_get((cf_model_id)code);
  if (!m || strcmp(m->code, codes[code]) != 0 || strcmp(m->name, names[name]) != 0)
    return json_fail(&here, err, CF_EPARSE, "model code %s and name %s do not agree", codes[code],
                     names[name]);
  *model = m->id;
  return CF_OK;
}

/* ---- the sections ---- */

/* capture.path is relative to fit.json's folder; a fit.json written before
 * that rule has it relative to the folder where clayfit fit ran, taken as
 * written (relative to the current folder) when only that exists. */
static cf_status locate_capture(const char *written, const char *fit_path, const json_at *at,
                                cf_fit_file *f, cf_error *err) {
  if (strlen(written) >= sizeof f->capture_written)
    return json_fail(at, err, CF_ERANGE, "the path is longer than %zu bytes",
                     sizeof f->capture_written - 1);
  memcpy(f->capture_written, written, strlen(written) + 1);
  char folder[4096];
  TRY(cf_path_dirname(fit_path, folder, sizeof folder, err));
  TRY(cf_path_join(folder, written, f->capture_path, sizeof f->capture_path, err));
  f->capture_found = cf_path_exists(f->capture_path);
  if (!f->capture_found && written[0] != '/' && cf_path_exists(written)) {
    memcpy(f->capture_path, written, strlen(written) + 1);
    f->capture_found = 1;
  }
  return CF_OK;
}

static cf_status read_capture(const json_t *root, const json_at *at, const char *fit_path,
                              cf_fit_file *f, cf_error *err) {
  const json_t *obj;
  TRY(json_get_object(root, at, "capture", 1, &obj, NULL, err));
  json_at here = json_member_at(at, "capture");
  static const char *const known[] = {"path",       "name",      "images", "observations",
                                      "radiometry", "reference", NULL};
  TRY(json_check_keys(obj, &here, known, err));
  const char *path;
  TRY(json_get_string(obj, &here, "path", 1, &path, NULL, err));
  json_at p = json_member_at(&here, "path");
  TRY(locate_capture(path, fit_path, &p, f, err));
  TRY(get_text(obj, &here, "name", f->capture_name, sizeof f->capture_name, err));
  TRY(get_count(obj, &here, "images", &f->capture_images, err));
  TRY(get_count(obj, &here, "observations", &f->capture_observations, err));
  static const char *const radiometry[] = {"absolute", "relative", "from_reference", NULL};
  int r;
  TRY(json_get_choice(obj, &here, "radiometry", 1, radiometry, &r, NULL, err));
  snprintf(f->radiometry, sizeof f->radiometry, "%s", radiometry[r]);
  const json_t *ref;
  int found = 0;
  TRY(json_get_object(obj, &here, "reference", 0, &ref, &found, err));
  if (found != (r == 2)) {
    return json_fail(&here, err, CF_EPARSE,
                     "'reference' must be present exactly when the radiometry is from_reference");
  }
  if (found) {
    json_at rh = json_member_at(&here, "reference");
    static const char *const rkeys[] = {"scale", "spread", "pixels", NULL};
    TRY(json_check_keys(ref, &rh, rkeys, err));
    double x;
    long long n;
    TRY(json_get_number(ref, &rh, "scale", 1, 1e-300, HUGE_NUMBER, &x, NULL, err));
    TRY(get_nonneg(ref, &rh, "spread", &x, err));
    TRY(json_get_integer(ref, &rh, "pixels", 1, 16, (long long)1 << 53, &n, NULL, err));
  }
  return CF_OK;
}

static cf_status read_derived(const json_t *root, const json_at *at, cf_fit_file *f,
                              cf_error *err) {
  const json_t *obj;
  TRY(get_member(root, at, "derived", &obj, err));
  json_at here = json_member_at(at, "derived");
  f->density = NAN;
  for (int c = 0; c < 3; ++c) f->absorption[c] = NAN;
  if (json_is_null(obj)) {
    if (cf_model_info_get(f->result.model)->ggx_twin == CF_MODEL_CLAY)
      return json_fail(&here, err, CF_EPARSE,
                       "models M4 and M4T need the film's density and absorption");
    return CF_OK;
  }
  if (!json_is_object(obj))
    return json_fail(&here, err, CF_EPARSE, "expected an object or null, got %s",
                     json_type_name(obj));
  if (cf_model_info_get(f->result.model)->ggx_twin != CF_MODEL_CLAY)
    return json_fail(&here, err, CF_EPARSE, "must be null for a model other than M4 and M4T");
  static const char *const known[] = {"density", "convention", "absorption", NULL};
  TRY(json_check_keys(obj, &here, known, err));
  TRY(get_nonneg(obj, &here, "density", &f->density, err));
  TRY(get_text(obj, &here, "convention", f->density_convention, sizeof f->density_convention, err));
  const json_t *absorption;
  TRY(get_member(obj, &here, "absorption", &absorption, err));
  if (json_is_string(absorption)) return CF_OK; /* undefined: τ = 0 */
  return json_get_numbers(obj, &here, "absorption", 1, 3, 0.0, HUGE_NUMBER, f->absorption, NULL,
                          err);
}

static cf_status read_scale(const json_t *root, const json_at *at, cf_fit_result *r,
                            cf_error *err) {
  const json_t *obj;
  TRY(json_get_object(root, at, "scale", 1, &obj, NULL, err));
  json_at here = json_member_at(at, "scale");
  static const char *const known[] = {"value", "sd", "fitted", NULL};
  TRY(json_check_keys(obj, &here, known, err));
  TRY(json_get_number(obj, &here, "value", 1, 1e-300, HUGE_NUMBER, &r->scale, NULL, err));
  TRY(get_nonneg(obj, &here, "sd", &r->scale_sd, err));
  return json_get_bool(obj, &here, "fitted", 1, &r->scale_fitted, NULL, err);
}

static cf_status slot_from_name(cf_model_id model, const json_t *value, const json_at *at,
                                int *slot, cf_error *err) {
  const char *text;
  TRY(json_as_string(value, at, &text, err));
  const cf_model_info *m = cf_model_info_get(model);
  for (int k = 0; k < m->dim; ++k) {
    char name[48];
    if (strcmp(cf_model_slot_name(model, k, name, sizeof name), text) == 0) {
      *slot = k;
      return CF_OK;
    }
  }
  return json_fail(at, err, CF_EPARSE, "'%s' is not a slot of model %s", text, m->code);
}

static cf_status read_correlation(const json_t *root, const json_at *at, cf_fit_result *r,
                                  cf_error *err) {
  const json_t *obj, *names, *matrix;
  TRY(json_get_object(root, at, "correlation", 1, &obj, NULL, err));
  json_at here = json_member_at(at, "correlation");
  static const char *const known[] = {"parameters", "matrix", NULL};
  TRY(json_check_keys(obj, &here, known, err));
  TRY(json_get_array(obj, &here, "parameters", 1, &names, NULL, err));
  TRY(json_get_array(obj, &here, "matrix", 1, &matrix, NULL, err));
  json_at nh = json_member_at(&here, "parameters"), mh = json_member_at(&here, "matrix");
  size_t n = json_array_size(names);
  if (n > (size_t)cf_model_info_get(r->model)->dim)
    return json_fail(&nh, err, CF_EPARSE, "more slots (%zu) than the model has", n);
  if (json_array_size(matrix) != n)
    return json_fail(&mh, err, CF_EPARSE, "expected %zu rows, got %zu", n, json_array_size(matrix));
  r->free_count = (int)n;
  for (size_t a = 0; a < n; ++a) {
    json_at element = json_element_at(&nh, a);
    TRY(slot_from_name(r->model, json_array_get(names, a), &element, &r->free_slots[a], err));
    for (size_t b = 0; b < a; ++b)
      if (r->free_slots[b] == r->free_slots[a])
        return json_fail(&element, err, CF_EPARSE, "the slot is listed twice");
    json_at row_at = json_element_at(&mh, a);
    const json_t *row = json_array_get(matrix, a);
    if (!json_is_array(row) || json_array_size(row) != n)
      return json_fail(&row_at, err, CF_EPARSE, "expected an array of %zu numbers", n);
    for (size_t b = 0; b < n; ++b) {
      json_at cell = json_element_at(&row_at, b);
      TRY(json_as_number(json_array_get(row, b), &cell, -1.000001, 1.000001,
                         &r->correlation[a * n + b], err));
    }
  }
  return CF_OK;
}

/* held, not_constrained, at_bound: their types (the statuses are read from
 * params). */
static cf_status read_held(const json_t *root, const json_at *at, cf_fit_result *r, cf_error *err) {
  const json_t *held;
  TRY(json_get_array(root, at, "held", 1, &held, NULL, err));
  json_at hh = json_member_at(at, "held");
  for (size_t i = 0; i < json_array_size(held); ++i) {
    json_at e = json_element_at(&hh, i);
    const json_t *item = json_array_get(held, i);
    if (!json_is_object(item))
      return json_fail(&e, err, CF_EPARSE, "expected an object, got %s", json_type_name(item));
    static const char *const known[] = {"name", "value", "why", NULL};
    TRY(json_check_keys(item, &e, known, err));
    int slot;
    double value;
    cf_param_status why;
    const json_t *name;
    TRY(get_member(item, &e, "name", &name, err));
    json_at nh = json_member_at(&e, "name");
    TRY(slot_from_name(r->model, name, &nh, &slot, err));
    TRY(json_get_number(item, &e, "value", 1, -HUGE_NUMBER, HUGE_NUMBER, &value, NULL, err));
    const json_t *w;
    TRY(get_member(item, &e, "why", &w, err));
    json_at wh = json_member_at(&e, "why");
    TRY(status_from_name(w, &wh, &why, err));
  }
  const char *lists[] = {"not_constrained", "at_bound"};
  for (int l = 0; l < 2; ++l) {
    const json_t *array;
    TRY(json_get_array(root, at, lists[l], 1, &array, NULL, err));
    json_at lh = json_member_at(at, lists[l]);
    for (size_t i = 0; i < json_array_size(array); ++i) {
      json_at e = json_element_at(&lh, i);
      int slot;
      TRY(slot_from_name(r->model, json_array_get(array, i), &e, &slot, err));
    }
  }
  return CF_OK;
}

static cf_status read_loss(const json_t *obj, const json_at *at, char *type, size_t size,
                           double *scale, cf_error *err) {
  static const char *const known[] = {"type", "scale_sigma", NULL};
  TRY(json_check_keys(obj, at, known, err));
  static const char *const types[] = {"none", "huber", "cauchy", NULL};
  int t;
  TRY(json_get_choice(obj, at, "type", 1, types, &t, NULL, err));
  if (type) snprintf(type, size, "%s", types[t]);
  return json_get_number(obj, at, "scale_sigma", 1, 1e-300, HUGE_NUMBER, scale, NULL, err);
}

static cf_status read_noise_loss(const json_t *root, const json_at *at, cf_fit_file *f,
                                 cf_error *err) {
  const json_t *obj;
  TRY(json_get_object(root, at, "noise", 1, &obj, NULL, err));
  json_at here = json_member_at(at, "noise");
  static const char *const known[] = {"model", "sigma", NULL};
  TRY(json_check_keys(obj, &here, known, err));
  static const char *const models[] = {"capture", "estimated from the residuals", NULL};
  int m;
  TRY(json_get_choice(obj, &here, "model", 1, models, &m, NULL, err));
  TRY(get_nonneg(obj, &here, "sigma", &f->result.sigma, err));
  TRY(json_get_object(root, at, "loss", 1, &obj, NULL, err));
  here = json_member_at(at, "loss");
  return read_loss(obj, &here, f->loss, sizeof f->loss, &f->loss_scale, err);
}

static cf_status read_residuals(const json_t *root, const json_at *at, cf_fit_result *r,
                                cf_error *err) {
  const json_t *obj, *per_image, *cores, *rest;
  TRY(json_get_object(root, at, "residuals", 1, &obj, NULL, err));
  json_at here = json_member_at(at, "residuals");
  static const char *const known[] = {"count",         "censored",  "rejected",        "rmse",
                                      "relative_rmse", "per_image", "highlight_cores", NULL};
  TRY(json_check_keys(obj, &here, known, err));
  TRY(get_count(obj, &here, "count", &r->residuals, err));
  TRY(get_count(obj, &here, "censored", &r->censored, err));
  TRY(get_count(obj, &here, "rejected", &r->rejected, err));
  TRY(get_nonneg(obj, &here, "rmse", &r->rmse, err));
  TRY(get_nonneg(obj, &here, "relative_rmse", &r->relative_rmse, err));
  TRY(json_get_array(obj, &here, "per_image", 1, &per_image, NULL, err));
  json_at ph = json_member_at(&here, "per_image");
  size_t n = json_array_size(per_image);
  r->images = n;
  r->exposures = calloc(n ? n : 1, sizeof *r->exposures);
  r->image_rmse = calloc(n ? n : 1, sizeof *r->image_rmse);
  r->image_relative_rmse = calloc(n ? n : 1, sizeof *r->image_relative_rmse);
  r->exposure_sd = calloc(n ? n : 1, sizeof *r->exposure_sd); /* 0 in older files */
  r->white_balance = malloc(3 * (n ? n : 1) * sizeof *r->white_balance);
  r->white_balance_sd = calloc(3 * (n ? n : 1), sizeof *r->white_balance_sd);
  if (!r->exposures || !r->image_rmse || !r->image_relative_rmse || !r->exposure_sd ||
      !r->white_balance || !r->white_balance_sd)
    return cf_error_set(err, CF_ENOMEM, "%s: out of memory for %zu images", here.file, n);
  for (size_t k = 0; k < n; ++k) {
    json_at e = json_element_at(&ph, k);
    const json_t *item = json_array_get(per_image, k);
    if (!json_is_object(item))
      return json_fail(&e, err, CF_EPARSE, "expected an object, got %s", json_type_name(item));
    static const char *const ikeys[] = {
        "name",        "rmse",          "relative_rmse",    "exposure", "not_radiance",
        "exposure_sd", "white_balance", "white_balance_sd", NULL};
    TRY(json_check_keys(item, &e, ikeys, err));
    const char *name;
    TRY(json_get_string(item, &e, "name", 1, &name, NULL, err));
    TRY(get_nonneg(item, &e, "rmse", &r->image_rmse[k], err));
    TRY(get_nonneg(item, &e, "relative_rmse", &r->image_relative_rmse[k], err));
    TRY(json_get_number(item, &e, "exposure", 1, 1e-300, HUGE_NUMBER, &r->exposures[k], NULL, err));
    TRY(json_get_number(item, &e, "exposure_sd", 0, 0.0, HUGE_NUMBER, &r->exposure_sd[k], NULL,
                        err));
    int balanced = 0; /* (1 each when absent: not fitted) */
    r->white_balance[3 * k] = r->white_balance[3 * k + 1] = r->white_balance[3 * k + 2] = 1.0;
    TRY(json_get_numbers(item, &e, "white_balance", 0, 3, 1e-300, HUGE_NUMBER,
                         r->white_balance + 3 * k, &balanced, err));
    TRY(json_get_numbers(item, &e, "white_balance_sd", balanced, 3, 0.0, HUGE_NUMBER,
                         r->white_balance_sd + 3 * k, NULL, err));
    r->white_balance_fitted |= balanced;
  }
  TRY(json_get_object(obj, &here, "highlight_cores", 1, &cores, NULL, err));
  json_at ch = json_member_at(&here, "highlight_cores");
  static const char *const ckeys[] = {"radius_px", "count",   "rmse", "relative_rmse",
                                      "rest",      "meaning", NULL};
  TRY(json_check_keys(cores, &ch, ckeys, err));
  double radius;
  const char *meaning;
  TRY(json_get_number(cores, &ch, "radius_px", 1, 1e-300, HUGE_NUMBER, &radius, NULL, err));
  TRY(get_count(cores, &ch, "count", &r->core_residuals, err));
  TRY(get_nonneg(cores, &ch, "rmse", &r->core_rmse, err));
  TRY(get_nonneg(cores, &ch, "relative_rmse", &r->core_relative_rmse, err));
  TRY(json_get_string(cores, &ch, "meaning", 1, &meaning, NULL, err));
  TRY(json_get_object(cores, &ch, "rest", 1, &rest, NULL, err));
  json_at rh = json_member_at(&ch, "rest");
  static const char *const rkeys[] = {"count", "rmse", "relative_rmse", NULL};
  TRY(json_check_keys(rest, &rh, rkeys, err));
  size_t rest_count;
  TRY(get_count(rest, &rh, "count", &rest_count, err));
  TRY(get_nonneg(rest, &rh, "rmse", &r->rest_rmse, err));
  return get_nonneg(rest, &rh, "relative_rmse", &r->rest_relative_rmse, err);
}

/* The gains per light (light_gains; absent: none), each light's name,
 * gain and sd. */
static cf_status read_light_gains(const json_t *root, const json_at *at, cf_fit_result *r,
                                  cf_error *err) {
  const json_t *lights;
  int found = 0;
  TRY(json_get_array(root, at, "light_gains", 0, &lights, &found, err));
  if (!found) return CF_OK;
  json_at here = json_member_at(at, "light_gains");
  size_t n = json_array_size(lights);
  if (n < 2) return json_fail(&here, err, CF_EPARSE, "needs 2 lights or more, has %zu", n);
  r->light_gains = malloc(n * sizeof *r->light_gains);
  r->light_gains_sd = malloc(n * sizeof *r->light_gains_sd);
  r->light_names = malloc(n * sizeof *r->light_names);
  if (!r->light_gains || !r->light_gains_sd || !r->light_names)
    return cf_error_set(err, CF_ENOMEM, "%s: out of memory for %zu lights", here.file, n);
  r->light_count = n;
  static const char *const keys[] = {"light", "gain", "sd", NULL};
  for (size_t l = 0; l < n; ++l) {
    json_at e = json_element_at(&here, l);
    const json_t *item = json_array_get(lights, l);
    if (!json_is_object(item))
      return json_fail(&e, err, CF_EPARSE, "expected an object, got %s", json_type_name(item));
    TRY(json_check_keys(item, &e, keys, err));
    TRY(get_text(item, &e, "light", r->light_names[l], sizeof r->light_names[l], err));
    TRY(json_get_number(item, &e, "gain", 1, 1e-300, HUGE_NUMBER, &r->light_gains[l], NULL, err));
    TRY(get_nonneg(item, &e, "sd", &r->light_gains_sd[l], err));
  }
  return CF_OK;
}

static cf_status read_solver(const json_t *root, const json_at *at, cf_fit_result *r,
                             cf_error *err) {
  const json_t *obj;
  TRY(json_get_object(root, at, "solver", 1, &obj, NULL, err));
  json_at here = json_member_at(at, "solver");
  static const char *const known[] = {"iterations", "solves", "termination", "seconds",
                                      "final_cost", "trace",  NULL};
  TRY(json_check_keys(obj, &here, known, err));
  const json_t *trace;
  int has_trace = 0;
  TRY(json_get_array(obj, &here, "trace", 0, &trace, &has_trace, err));
  r->trace_count = 0;
  if (has_trace) { /* the convergence trace: at most CF_FIT_MAX_TRACE costs */
    json_at tat = json_member_at(&here, "trace");
    if (json_array_size(trace) > CF_FIT_MAX_TRACE)
      return json_fail(&tat, err, CF_EPARSE, "%zu costs; at most %d", json_array_size(trace),
                       CF_FIT_MAX_TRACE);
    for (size_t i = 0; i < json_array_size(trace); ++i) {
      json_at eat = json_element_at(&tat, i);
      TRY(json_as_number(json_array_get(trace, i), &eat, 0.0, 1e300, &r->trace[i], err));
      r->trace_count = (int)i + 1;
    }
  }
  TRY(get_int(obj, &here, "iterations", 0, 1 << 30, &r->iterations, err));
  TRY(get_int(obj, &here, "solves", 0, 1 << 30, &r->solves, err));
  TRY(get_text(obj, &here, "termination", r->termination, sizeof r->termination, err));
  TRY(get_nonneg(obj, &here, "seconds", &r->solve_seconds, err));
  return get_nonneg(obj, &here, "final_cost", &r->cost, err);
}

static cf_status read_starts(const json_t *root, const json_at *at, cf_fit_result *r,
                             cf_error *err) {
  const json_t *starts;
  TRY(json_get_array(root, at, "starts", 1, &starts, NULL, err));
  json_at sh = json_member_at(at, "starts");
  size_t n = json_array_size(starts);
  if (n > CF_FIT_MAX_STARTS)
    return json_fail(&sh, err, CF_ERANGE, "%zu starts, at most %d", n, CF_FIT_MAX_STARTS);
  r->starts = (int)n;
  for (size_t i = 0; i < n; ++i) {
    json_at e = json_element_at(&sh, i);
    const json_t *item = json_array_get(starts, i), *values;
    if (!json_is_object(item))
      return json_fail(&e, err, CF_EPARSE, "expected an object, got %s", json_type_name(item));
    static const char *const known[] = {"start", "end", "cost", "iterations", "stopped", NULL};
    TRY(json_check_keys(item, &e, known, err));
    cf_fit_start *s = &r->start[i];
    TRY(json_get_object(item, &e, "start", 1, &values, NULL, err));
    json_at vh = json_member_at(&e, "start");
    TRY(read_values_by_name(values, &vh, r->model, s->start, err));
    TRY(json_get_object(item, &e, "end", 1, &values, NULL, err));
    vh = json_member_at(&e, "end");
    TRY(read_values_by_name(values, &vh, r->model, s->end, err));
    TRY(json_get_number(item, &e, "cost", 1, -HUGE_NUMBER, HUGE_NUMBER, &s->cost, NULL, err));
    TRY(get_int(item, &e, "iterations", 0, 1 << 30, &s->iterations, err));
    TRY(json_get_bool(item, &e, "stopped", 1, &s->stopped, NULL, err));
  }
  TRY(get_int(root, at, "best_start", 0, n ? (int)n - 1 : 0, &r->best_start, err));
  const json_t *warnings;
  TRY(json_get_array(root, at, "warnings", 1, &warnings, NULL, err));
  json_at wh = json_member_at(at, "warnings");
  n = json_array_size(warnings);
  if (n > CF_FIT_MAX_WARNINGS)
    return json_fail(&wh, err, CF_ERANGE, "%zu warnings, at most %d", n, CF_FIT_MAX_WARNINGS);
  r->warning_count = (int)n;
  for (size_t i = 0; i < n; ++i) {
    json_at e = json_element_at(&wh, i);
    const char *text;
    TRY(json_as_string(json_array_get(warnings, i), &e, &text, err));
    if (strlen(text) >= sizeof r->warnings[i])
      return json_fail(&e, err, CF_ERANGE, "the warning is longer than %zu bytes",
                       sizeof r->warnings[i] - 1);
    memcpy(r->warnings[i], text, strlen(text) + 1);
  }
  return CF_OK;
}

static cf_status read_timing(const json_t *root, const json_at *at, cf_fit_result *r,
                             cf_error *err) {
  const json_t *obj, *stages;
  TRY(json_get_object(root, at, "timing", 1, &obj, NULL, err));
  json_at here = json_member_at(at, "timing");
  static const char *const known[] = {"load_s", "fit_s", "total_s", "stages", "choice_s", NULL};
  TRY(json_check_keys(obj, &here, known, err));
  double x;
  TRY(get_nonneg(obj, &here, "load_s", &x, err));
  TRY(get_nonneg(obj, &here, "fit_s", &x, err));
  TRY(get_nonneg(obj, &here, "total_s", &x, err));
  TRY(get_nonneg(obj, &here, "choice_s", &x, err));
  TRY(json_get_object(obj, &here, "stages", 1, &stages, NULL, err));
  json_at sh = json_member_at(&here, "stages");
  const char *names[CF_FIT_STAGE_COUNT + 1];
  for (int i = 0; i < CF_FIT_STAGE_COUNT; ++i) names[i] = cf_fit_stage_name((cf_fit_stage)i);
  names[CF_FIT_STAGE_COUNT] = NULL;
  TRY(json_check_keys(stages, &sh, names, err));
  for (int i = 0; i < CF_FIT_STAGE_COUNT; ++i)
    TRY(get_nonneg(stages, &sh, names[i], &r->stage_seconds[i], err));
  return CF_OK;
}

static cf_status read_footprint(const json_t *root, const json_at *at, cf_fit_file *f,
                                cf_error *err) {
  const json_t *obj;
  TRY(json_get_object(root, at, "footprint", 1, &obj, NULL, err));
  json_at here = json_member_at(at, "footprint");
  static const char *const known[] = {
      "mode",    "samples_per_side",     "tolerance", "observations",
      "samples", "max_samples_per_side", "meaning",   NULL};
  TRY(json_check_keys(obj, &here, known, err));
  static const char *const modes[] = {"auto", "centre", "fixed", NULL};
  int mode, per_side;
  TRY(json_get_choice(obj, &here, "mode", 1, modes, &mode, NULL, err));
  TRY(get_int(obj, &here, "samples_per_side", 0, CF_FIT_FOOTPRINT_MAX_SAMPLES, &per_side, err));
  if ((mode == 2) != (per_side >= 2)) {
    json_at p = json_member_at(&here, "samples_per_side");
    return json_fail(&p, err, CF_EPARSE, "%d: expected 2 to %d with mode fixed, else 0", per_side,
                     CF_FIT_FOOTPRINT_MAX_SAMPLES);
  }
  f->footprint = mode == 0 ? 0 : mode == 1 ? 1 : per_side;
  TRY(json_get_number(obj, &here, "tolerance", 1, 1e-300, HUGE_NUMBER, &f->footprint_tolerance,
                      NULL, err));
  TRY(get_count(obj, &here, "observations", &f->result.footprint_observations, err));
  TRY(get_count(obj, &here, "samples", &f->result.footprint_samples, err));
  TRY(get_int(obj, &here, "max_samples_per_side", 1, 1 << 20, &f->result.footprint_max, err));
  const char *meaning;
  return json_get_string(obj, &here, "meaning", 1, &meaning, NULL, err);
}

/* A response written before the curve (clayfit 0.x up to issue 17): one
 * exponent γ with its sd, the power x^γ, which is the curve with every
 * slope γ and every covariance entry sd² (docs/fitting.md). */
static cf_status read_response_exponent(const json_t *obj, const json_at *here, cf_fit_result *r,
                                        cf_error *err) {
  static const char *const known[] = {"value", "sd", "fitted", "meaning", NULL};
  TRY(json_check_keys(obj, here, known, err));
  double gamma, sd;
  TRY(json_get_number(obj, here, "value", 1, 0.25, 4.0, &gamma, NULL, err));
  TRY(get_nonneg(obj, here, "sd", &sd, err));
  for (int i = 0; i < CF_RESPONSE_MODEL_KNOTS; ++i) {
    r->response[i] = gamma;
    for (int j = 0; j < CF_RESPONSE_MODEL_KNOTS; ++j)
      r->response_covariance[i * CF_RESPONSE_MODEL_KNOTS + j] = sd * sd;
  }
  return CF_OK;
}

/* The slopes' covariance: K rows of K finite numbers, a diagonal >= 0. */
static cf_status read_response_covariance(const json_t *obj, const json_at *here, cf_fit_result *r,
                                          cf_error *err) {
  enum { K = CF_RESPONSE_MODEL_KNOTS };
  const json_t *rows;
  TRY(json_get_array(obj, here, "covariance", 1, &rows, NULL, err));
  json_at at = json_member_at(here, "covariance");
  if (json_array_size(rows) != K)
    return json_fail(&at, err, CF_EPARSE, "expected %d rows, got %zu", K, json_array_size(rows));
  for (size_t a = 0; a < K; ++a) {
    json_at row_at = json_element_at(&at, a);
    const json_t *row = json_array_get(rows, a);
    if (!json_is_array(row) || json_array_size(row) != K)
      return json_fail(&row_at, err, CF_EPARSE, "expected an array of %d numbers", K);
    for (size_t b = 0; b < K; ++b) {
      json_at cell = json_element_at(&row_at, b);
      TRY(json_as_number(json_array_get(row, b), &cell, a == b ? 0.0 : -HUGE_NUMBER, HUGE_NUMBER,
                         &r->response_covariance[a * K + b], err));
    }
  }
  return CF_OK;
}

/* The response curve: its model (the one this clayfit fits, at its
 * knots), slopes and covariance; the sds and the sampled curve follow from
 * them and are checked for their shape only. */
static cf_status read_response_curve(const json_t *obj, const json_at *here, cf_fit_result *r,
                                     cf_error *err) {
  enum { K = CF_RESPONSE_MODEL_KNOTS };
  static const char *const known[] = {"fitted",     "model", "knots",   "slopes", "slopes_sd",
                                      "covariance", "curve", "meaning", NULL};
  TRY(json_check_keys(obj, here, known, err));
  static const char *const models[] = {CF_RESPONSE_MODEL_NAME, NULL};
  int model;
  TRY(json_get_choice(obj, here, "model", 1, models, &model, NULL, err));
  double knots[K], sd[K];
  TRY(json_get_numbers(obj, here, "knots", 1, K, 0.0, 1.0, knots, NULL, err));
  for (int j = 0; j < K; ++j)
    if (fabs(knots[j] - cf_response_model_knot(j)) > 1e-12) {
      json_at at = json_member_at(here, "knots");
      return json_fail(&at, err, CF_EPARSE, "knot %d is %.17g, not this model's %.17g", j, knots[j],
                       cf_response_model_knot(j));
    }
  TRY(json_get_numbers(obj, here, "slopes", 1, K, CF_RESPONSE_MODEL_SLOPE_LOWER,
                       CF_RESPONSE_MODEL_SLOPE_UPPER, r->response, NULL, err));
  TRY(json_get_numbers(obj, here, "slopes_sd", 1, K, 0.0, HUGE_NUMBER, sd, NULL, err));
  TRY(read_response_covariance(obj, here, r, err));
  const json_t *curve;
  return json_get_array(obj, here, "curve", 1, &curve, NULL, err);
}

static cf_status read_response(const json_t *root, const json_at *at, cf_fit_result *r,
                               cf_error *err) {
  const json_t *obj;
  TRY(json_get_object(root, at, "response", 1, &obj, NULL, err));
  json_at here = json_member_at(at, "response");
  int is_curve = json_object_get(obj, "slopes") != NULL;
  TRY(is_curve ? read_response_curve(obj, &here, r, err)
               : read_response_exponent(obj, &here, r, err));
  TRY(json_get_bool(obj, &here, "fitted", 1, &r->response_fitted, NULL, err));
  const char *meaning;
  return json_get_string(obj, &here, "meaning", 1, &meaning, NULL, err);
}

/* The pixel budget's sample, or null. */
/* The optional JPEG coding block (fit_json.c's jpeg_coding_json). */
static cf_status read_jpeg_coding(const json_t *root, const json_at *at, cf_fit_result *r,
                                  cf_error *err) {
  const json_t *obj;
  int found;
  TRY(json_get_object(root, at, "jpeg_coding", 0, &obj, &found, err));
  if (!found) return CF_OK;
  json_at here = json_member_at(at, "jpeg_coding");
  static const char *const known[] = {"images",          "draws",   "bias_rms_codes",
                                      "bias_mean_codes", "meaning", NULL};
  TRY(json_check_keys(obj, &here, known, err));
  int draws;
  TRY(get_int(obj, &here, "images", 1, 1 << 30, &r->jpeg_images, err));
  TRY(get_int(obj, &here, "draws", 1, 1 << 20, &draws, err));
  TRY(json_get_number(obj, &here, "bias_rms_codes", 1, 0.0, 255.0, &r->jpeg_bias_rms, NULL, err));
  TRY(json_get_numbers(obj, &here, "bias_mean_codes", 1, 3, -255.0, 255.0, r->jpeg_bias_mean, NULL,
                       err));
  const char *meaning;
  return json_get_string(obj, &here, "meaning", 1, &meaning, NULL, err);
}

static cf_status read_sample(const json_t *root, const json_at *at, cf_fit_result *r,
                             cf_error *err) {
  const json_t *obj;
  TRY(get_member(root, at, "sample", &obj, err));
  json_at here = json_member_at(at, "sample");
  if (json_is_null(obj)) return CF_OK;
  if (!json_is_object(obj))
    return json_fail(&here, err, CF_EPARSE, "expected an object or null, got %s",
                     json_type_name(obj));
  static const char *const known[] = {"sampling", "observations", "population", "meaning", NULL};
  TRY(json_check_keys(obj, &here, known, err));
  static const char *const samplings[] = {"uniform", "stratified", "importance", NULL};
  int sampling;
  TRY(json_get_choice(obj, &here, "sampling", 1, samplings, &sampling, NULL, err));
  r->sampling = (cf_sampling)sampling;
  TRY(get_count(obj, &here, "observations", &r->sample_count, err));
  TRY(get_count(obj, &here, "population", &r->population_count, err));
  if (r->sample_count == 0 || r->sample_count >= r->population_count) {
    json_at e = json_member_at(&here, "observations");
    return json_fail(&e, err, CF_EPARSE, "%zu: expected 1 to %zu (below the population)",
                     r->sample_count, r->population_count > 0 ? r->population_count - 1 : 0);
  }
  const char *meaning;
  return json_get_string(obj, &here, "meaning", 1, &meaning, NULL, err);
}

/* One candidate of an automatic choice. */
static cf_status read_candidate(const json_t *item, const json_at *e, cf_error *err) {
  if (!json_is_object(item))
    return json_fail(e, err, CF_EPARSE, "expected an object, got %s", json_type_name(item));
  cf_model_id model;
  const char *const *codes = cf_model_codes();
  int code, ok, chosen;
  TRY(json_get_choice(item, e, "model", 1, codes, &code, NULL, err));
  model = (cf_model_id)code;
  TRY(json_get_bool(item, e, "ok", 1, &ok, NULL, err));
  TRY(json_get_bool(item, e, "chosen", 1, &chosen, NULL, err));
  double x;
  const char *note;
  TRY(get_nonneg(item, e, "seconds", &x, err));
  TRY(json_get_string(item, e, "note", 1, &note, NULL, err));
  if (!ok) {
    static const char *const known[] = {"model", "ok", "chosen", "seconds", "note", NULL};
    TRY(json_check_keys(item, e, known, err));
    if (chosen) return json_fail(e, err, CF_EPARSE, "a failed candidate cannot be chosen");
    return CF_OK;
  }
  static const char *const known[] = {"model",
                                      "ok",
                                      "chosen",
                                      "params",
                                      "unknowns",
                                      "residuals",
                                      "cost",
                                      "bic",
                                      "heldout_residuals",
                                      "heldout_score",
                                      "heldout_rmse",
                                      "heldout_relative_rmse",
                                      "train_rmse",
                                      "train_relative_rmse",
                                      "seconds",
                                      "note",
                                      NULL};
  TRY(json_check_keys(item, e, known, err));
  const json_t *params;
  TRY(json_get_object(item, e, "params", 1, &params, NULL, err));
  json_at ph = json_member_at(e, "params");
  double values[CF_MAX_DIM], sd[CF_MAX_DIM];
  cf_param_status status[CF_MAX_DIM];
  TRY(read_params(params, &ph, model, values, sd, status, err));
  size_t n;
  TRY(get_count(item, e, "unknowns", &n, err));
  TRY(get_count(item, e, "residuals", &n, err));
  TRY(get_nonneg(item, e, "cost", &x, err));
  TRY(json_get_number(item, e, "bic", 1, -HUGE_NUMBER, HUGE_NUMBER, &x, NULL, err));
  TRY(get_count(item, e, "heldout_residuals", &n, err));
  const char *nullable[] = {"heldout_score", "heldout_rmse", "heldout_relative_rmse"};
  for (int i = 0; i < 3; ++i) {
    const json_t *v;
    TRY(get_member(item, e, nullable[i], &v, err));
    if (!json_is_null(v)) TRY(get_nonneg(item, e, nullable[i], &x, err));
  }
  TRY(get_nonneg(item, e, "train_rmse", &x, err));
  return get_nonneg(item, e, "train_relative_rmse", &x, err);
}

static cf_status read_choice(const json_t *root, const json_at *at, cf_model_id model,
                             cf_error *err) {
  const json_t *obj, *candidates;
  TRY(json_get_object(root, at, "choice", 1, &obj, NULL, err));
  json_at here = json_member_at(at, "choice");
  static const char *const modes[] = {"forced", "auto", NULL};
  const char *const *codes = cf_model_codes();
  int mode, chosen;
  TRY(json_get_choice(obj, &here, "mode", 1, modes, &mode, NULL, err));
  TRY(json_get_choice(obj, &here, "chosen", 1, codes, &chosen, NULL, err));
  if ((cf_model_id)chosen != model)
    return json_fail(&here, err, CF_EPARSE, "chosen %s is not the model %s", codes[chosen],
                     cf_model_info_get(model)->code);
  TRY(json_get_array(obj, &here, "candidates", 1, &candidates, NULL, err));
  json_at ch = json_member_at(&here, "candidates");
  if (mode == 0) {
    static const char *const known[] = {"mode", "chosen", "candidates", "reading", NULL};
    TRY(json_check_keys(obj, &here, known, err));
    if (json_array_size(candidates))
      return json_fail(&ch, err, CF_EPARSE, "a forced model has no candidates");
    const char *text; /* an M4 whose film is a lobe (issue 18; optional) */
    TRY(json_get_string(obj, &here, "reading", 0, &text, NULL, err));
    return CF_OK;
  }
  static const char *const known[] = {"mode",
                                      "chosen",
                                      "train_observations",
                                      "heldout_observations",
                                      "heldout",
                                      "sigma",
                                      "loss",
                                      "bic_margin",
                                      "heldout_margin",
                                      "heldout_guard",
                                      "seconds",
                                      "rule",
                                      "reading",
                                      "ggx_cost",
                                      "candidates",
                                      NULL};
  TRY(json_check_keys(obj, &here, known, err));
  size_t n;
  double x;
  const char *text;
  const json_t *loss;
  TRY(get_count(obj, &here, "train_observations", &n, err));
  TRY(get_count(obj, &here, "heldout_observations", &n, err));
  TRY(json_get_string(obj, &here, "heldout", 1, &text, NULL, err));
  TRY(get_nonneg(obj, &here, "sigma", &x, err));
  TRY(json_get_object(obj, &here, "loss", 1, &loss, NULL, err));
  json_at lh = json_member_at(&here, "loss");
  TRY(read_loss(loss, &lh, NULL, 0, &x, err));
  TRY(json_get_number(obj, &here, "bic_margin", 1, -HUGE_NUMBER, HUGE_NUMBER, &x, NULL, err));
  TRY(json_get_number(obj, &here, "heldout_margin", 1, -HUGE_NUMBER, HUGE_NUMBER, &x, NULL, err));
  /* (the guard and the reading since issue 18: optional in older files) */
  TRY(json_get_number(obj, &here, "heldout_guard", 0, -HUGE_NUMBER, HUGE_NUMBER, &x, NULL, err));
  TRY(get_nonneg(obj, &here, "seconds", &x, err));
  TRY(json_get_string(obj, &here, "rule", 1, &text, NULL, err));
  TRY(json_get_string(obj, &here, "reading", 0, &text, NULL, err));
  const json_t *ggx_cost; /* a tailed choice only */
  int has_cost;
  TRY(json_get_object(obj, &here, "ggx_cost", 0, &ggx_cost, &has_cost, err));
  if (has_cost) {
    json_at gh = json_member_at(&here, "ggx_cost");
    static const char *const cost_keys[] = {"heldout_increase", "meaning", NULL};
    TRY(json_check_keys(ggx_cost, &gh, cost_keys, err));
    TRY(json_get_number(ggx_cost, &gh, "heldout_increase", 1, -1.0, HUGE_NUMBER, &x, NULL, err));
    TRY(json_get_string(ggx_cost, &gh, "meaning", 1, &text, NULL, err));
  }
  n = json_array_size(candidates);
  if (n < 1 || n > CF_MODEL_COUNT)
    return json_fail(&ch, err, CF_EPARSE, "expected 1 to %d candidates, got %zu", CF_MODEL_COUNT,
                     n);
  for (size_t i = 0; i < n; ++i) {
    json_at e = json_element_at(&ch, i);
    TRY(read_candidate(json_array_get(candidates, i), &e, err));
  }
  return CF_OK;
}

/* model_version: absent in files written before it existed (version 1,
 * Schlick's Fresnel); a version this clayfit does not know is refused. */
static cf_status read_model_version(const json_t *root, const json_at *at, const char *path,
                                    int *version, cf_error *err) {
  long long v = 1;
  int found = 0;
  TRY(json_get_integer(root, at, "model_version", 0, LLONG_MIN, LLONG_MAX, &v, &found, err));
  if (found && (v < 1 || v > CF_MODEL_VERSION))
    return cf_error_set(err, CF_EPARSE,
                        "%s: model_version: unknown model version %lld (this clayfit knows "
                        "versions 1 to %d; was the file written by a newer clayfit?)",
                        path, v, CF_MODEL_VERSION);
  *version = (int)v;
  return CF_OK;
}

static cf_status read_root(const json_t *root, const char *path, cf_fit_file *f, cf_error *err) {
  json_at at = {path, NULL, NULL, 0};
  static const char *const known[] = {"clayfit_fit",
                                      "clayfit_version",
                                      "model_version",
                                      "created",
                                      "capture",
                                      "model",
                                      "params",
                                      "derived",
                                      "scale",
                                      "correlation",
                                      "held",
                                      "not_constrained",
                                      "at_bound",
                                      "noise",
                                      "loss",
                                      "residuals",
                                      "solver",
                                      "starts",
                                      "best_start",
                                      "warnings",
                                      "timing",
                                      "choice",
                                      "footprint",
                                      "response",
                                      "sample",
                                      "light_gains",
                                      "jpeg_coding",
                                      NULL};
  TRY(json_check_keys(root, &at, known, err));
  long long layout;
  TRY(json_get_integer(root, &at, "clayfit_fit", 1, 1, 1, &layout, NULL, err));
  TRY(get_text(root, &at, "clayfit_version", f->clayfit_version, sizeof f->clayfit_version, err));
  TRY(read_model_version(root, &at, path, &f->model_version, err));
  TRY(get_text(root, &at, "created", f->created, sizeof f->created, err));
  TRY(read_capture(root, &at, path, f, err));
  cf_fit_result *r = &f->result;
  TRY(read_model(root, &at, "model", &r->model, err));
  const json_t *params;
  TRY(json_get_object(root, &at, "params", 1, &params, NULL, err));
  json_at ph = json_member_at(&at, "params");
  TRY(read_params(params, &ph, r->model, r->params, r->sd, r->status, err));
  TRY(read_derived(root, &at, f, err));
  TRY(read_scale(root, &at, r, err));
  TRY(read_correlation(root, &at, r, err));
  TRY(read_held(root, &at, r, err));
  TRY(read_noise_loss(root, &at, f, err));
  TRY(read_residuals(root, &at, r, err));
  TRY(read_light_gains(root, &at, r, err));
  TRY(read_solver(root, &at, r, err));
  TRY(read_starts(root, &at, r, err));
  TRY(read_timing(root, &at, r, err));
  TRY(read_choice(root, &at, r->model, err));
  TRY(read_footprint(root, &at, f, err));
  TRY(read_sample(root, &at, r, err));
  TRY(read_jpeg_coding(root, &at, r, err));
  return read_response(root, &at, r, err);
}

const char *cf_fit_file_version_warning(const cf_fit_file *file) {
  if (file->model_version >= CF_MODEL_VERSION) return NULL;
  return "the values were fitted with model version 1 (Schlick's Fresnel); this clayfit "
         "evaluates them with version 2's exact dielectric Fresnel (docs/model.md), which "
         "differs at grazing angles: refit for exact values";
}

cf_status cf_fit_file_read(const char *path, cf_fit_file *file, cf_error *err) {
  memset(file, 0, sizeof *file);
  file->density = NAN;
  for (int c = 0; c < 3; ++c) file->absorption[c] = NAN;
  for (int k = 0; k < CF_MAX_DIM; ++k) file->result.sd[k] = NAN;
  json_t *root = NULL;
  cf_status s = json_load_object(path, CF_FIT_FILE_MAX_SIZE, &root, err);
  if (s != CF_OK) return s;
  file->document = root;
  s = read_root(root, path, file, err);
  if (s != CF_OK) cf_fit_file_free(file);
  return s;
}

cf_status cf_fit_file_check_capture(const cf_fit_file *file, const char *fit_path, cf_error *err) {
  if (file->capture_found) return CF_OK;
  if (file->capture_written[0] == '/')
    return cf_error_set(err, CF_ENOTFOUND, "%s: capture.path: no capture at %s", fit_path,
                        file->capture_path);
  return cf_error_set(err, CF_ENOTFOUND,
                      "%s: capture.path '%s': no capture at %s (relative to the folder of "
                      "fit.json) nor at %s (relative to the current folder, where a fit.json "
                      "written by an earlier clayfit has it)",
                      fit_path, file->capture_written, file->capture_path, file->capture_written);
}

void cf_fit_file_free(cf_fit_file *file) {
  if (!file) return;
  cf_fit_result_free(&file->result);
  if (file->document) json_decref(file->document);
  file->document = NULL;
}
