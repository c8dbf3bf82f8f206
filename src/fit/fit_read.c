/* Reading fit.json (data_schema/fit.schema.json) back: for clayfit export
 * and clayfit report (include/clayfit/fit_file.h). The file is untrusted:
 * every field is checked for its type and range with core's strict JSON
 * reader, every object for unknown keys, and every error names the file and
 * JSON path. This file holds the shared readers (members, parameters, the
 * model) and the whole file's reading; fit_read_sections.c the fit's
 * sections, fit_read_choice.c the response curve, the JPEG coding, the
 * sample and the model choice. */
#include <jansson.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clayfit/fit_file.h"
#include "core/file.h"
#include "core/json_reader.h"
#include "fit_read_internal.h"

/* A string member copied into a fixed buffer; too long is an error, not a
 * silent truncation. */
cf_status fit_read_text(const json_t *obj, const json_at *at, const char *key, char *out,
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

cf_status fit_read_count(const json_t *obj, const json_at *at, const char *key, size_t *out,
                         cf_error *err) {
  long long x;
  TRY(json_get_integer(obj, at, key, 1, 0, (long long)1 << 53, &x, NULL, err));
  *out = (size_t)x;
  return CF_OK;
}

cf_status fit_read_int(const json_t *obj, const json_at *at, const char *key, int lo, int hi,
                       int *out, cf_error *err) {
  long long x;
  TRY(json_get_integer(obj, at, key, 1, lo, hi, &x, NULL, err));
  *out = (int)x;
  return CF_OK;
}

cf_status fit_read_nonneg(const json_t *obj, const json_at *at, const char *key, double *out,
                          cf_error *err) {
  return json_get_number(obj, at, key, 1, 0.0, HUGE_NUMBER, out, NULL, err);
}

cf_status fit_read_member(const json_t *obj, const json_at *at, const char *key, const json_t **out,
                          cf_error *err) {
  *out = json_object_get(obj, key);
  if (!*out) return json_fail(at, err, CF_EPARSE, "missing required key '%s'", key);
  return CF_OK;
}

/* ---- parameters ---- */

cf_status fit_read_status_name(const json_t *value, const json_at *at, cf_param_status *out,
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
  TRY(fit_read_member(obj, at, "sd", &value, err));
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
  TRY(fit_read_member(obj, at, "status", &value, err));
  json_at here = json_member_at(at, "status");
  if (json_is_string(value)) {
    TRY(fit_read_status_name(value, &here, &out[0], err));
    for (int c = 1; c < components; ++c) out[c] = out[0];
    return CF_OK;
  }
  if (components != 3 || !json_is_array(value) || json_array_size(value) != 3)
    return json_fail(&here, err, CF_EPARSE, "expected a status name%s, got %s",
                     components == 3 ? " or an array of 3" : "", json_type_name(value));
  for (size_t c = 0; c < 3; ++c) {
    json_at element = json_element_at(&here, c);
    TRY(fit_read_status_name(json_array_get(value, c), &element, &out[c], err));
  }
  return CF_OK;
}

/* `params`: every parameter of the model, nothing else. */
cf_status fit_read_params(const json_t *obj, const json_at *at, cf_model_id model, double *params,
                          double *sd, cf_param_status *status, cf_error *err) {
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
cf_status fit_read_values_by_name(const json_t *obj, const json_at *at, cf_model_id model,
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
  static const char *const known[] = {
      "clayfit_fit", "clayfit_version", "model_version", "created",
      "capture",     "model",           "params",        "derived",
      "scale",       "correlation",     "held",          "not_constrained",
      "at_bound",    "noise",           "loss",          "residuals",
      "solver",      "starts",          "best_start",    "warnings",
      "timing",      "choice",          "footprint",     "response",
      "sample",      "light_gains",     "jpeg_coding",   NULL};
  TRY(json_check_keys(root, &at, known, err));
  long long layout;
  TRY(json_get_integer(root, &at, "clayfit_fit", 1, 1, 1, &layout, NULL, err));
  TRY(fit_read_text(root, &at, "clayfit_version", f->clayfit_version, sizeof f->clayfit_version,
                    err));
  TRY(read_model_version(root, &at, path, &f->model_version, err));
  TRY(fit_read_text(root, &at, "created", f->created, sizeof f->created, err));
  TRY(fit_read_capture(root, &at, path, f, err));
  cf_fit_result *r = &f->result;
  TRY(read_model(root, &at, "model", &r->model, err));
  const json_t *params;
  TRY(json_get_object(root, &at, "params", 1, &params, NULL, err));
  json_at ph = json_member_at(&at, "params");
  TRY(fit_read_params(params, &ph, r->model, r->params, r->sd, r->status, err));
  TRY(fit_read_derived(root, &at, f, err));
  TRY(fit_read_scale(root, &at, r, err));
  TRY(fit_read_correlation(root, &at, r, err));
  TRY(fit_read_held(root, &at, r, err));
  TRY(fit_read_noise_loss(root, &at, f, err));
  TRY(fit_read_residuals(root, &at, r, err));
  TRY(fit_read_light_gains(root, &at, r, err));
  TRY(fit_read_solver(root, &at, r, err));
  TRY(fit_read_starts(root, &at, r, err));
  TRY(fit_read_timing(root, &at, r, err));
  TRY(fit_read_choice(root, &at, r->model, err));
  TRY(fit_read_footprint(root, &at, f, err));
  TRY(fit_read_sample(root, &at, r, err));
  TRY(fit_read_jpeg_coding(root, &at, r, err));
  return fit_read_response(root, &at, r, err);
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
