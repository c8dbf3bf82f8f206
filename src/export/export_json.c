/* The json preset (data_schema/preset.schema.json): lossless. The model
 * and every parameter with its unit, standard deviation, status and range,
 * the film's density and absorption, the fit's figures and provenance. And
 * its reader, for clayfit eval --preset. */
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "core/json_reader.h"
#include "export_internal.h"

static json_t *numbers(const double *x, int n) {
  json_t *array = json_array();
  for (int i = 0; i < n; ++i) json_array_append_new(array, json_real(x[i]));
  return array;
}

static json_t *param_json(const cf_fit_result *r, const cf_param_info *info, int k) {
  json_t *value, *sd, *status;
  if (info->components == 3) {
    value = numbers(r->params + k, 3);
    sd = json_array();
    for (int c = 0; c < 3; ++c) json_array_append_new(sd, json_real_or_null(r->sd[k + c]));
    int same = r->status[k] == r->status[k + 1] && r->status[k] == r->status[k + 2];
    if (same) {
      status = json_string(cf_param_status_name(r->status[k]));
    } else {
      status = json_array();
      for (int c = 0; c < 3; ++c)
        json_array_append_new(status, json_string(cf_param_status_name(r->status[k + c])));
    }
  } else {
    value = json_real(r->params[k]);
    sd = json_real_or_null(r->sd[k]);
    status = json_string(cf_param_status_name(r->status[k]));
  }
  return json_pack("{s:o, s:o, s:s, s:o, s:f, s:f, s:s}", "value", value, "sd", sd, "unit",
                   info->unit, "status", status, "lower", info->lower, "upper", info->upper,
                   "meaning", info->meaning);
}

/* The fit's response curve: its model's name, slopes and their sds
 * (clayfit/response_model.h). */
static json_t *response_json(const cf_fit_result *r) {
  enum { K = CF_RESPONSE_MODEL_KNOTS };
  double sd[K];
  for (int j = 0; j < K; ++j) sd[j] = sqrt(fmax(0.0, r->response_covariance[j * (K + 1)]));
  return json_pack("{s:s, s:o, s:o, s:b}", "model", CF_RESPONSE_MODEL_NAME, "slopes",
                   numbers(r->response, K), "slopes_sd", numbers(sd, K), "fitted",
                   r->response_fitted);
}

cf_status export_json(const cf_fit_file *fit, const char *fit_path, const char *path,
                      preset_notes *notes, cf_error *err) {
  (void)notes; /* lossless: nothing to note */
  const cf_fit_result *r = &fit->result;
  const cf_model_info *m = cf_model_info_get(r->model);
  json_t *params = json_object();
  for (int j = 0; j < m->param_count; ++j) {
    const cf_param_info *info = cf_param_info_get(m->params[j]);
    json_object_set_new(params, info->name, param_json(r, info, m->offsets[j]));
  }
  json_t *derived = json_null();
  if (m->ggx_twin == CF_MODEL_CLAY) /* M4, M4T */
    derived = json_pack("{s:f, s:o, s:s}", "density", fit->density, "absorption",
                        isfinite(fit->absorption[0]) ? numbers(fit->absorption, 3) : json_null(),
                        "convention", fit->density_convention);
  char exported[32];
  time_t now = time(NULL);
  struct tm utc;
  gmtime_r(&now, &utc);
  strftime(exported, sizeof exported, "%Y-%m-%dT%H:%M:%SZ", &utc);
  /* The paths come from the command line and may not be UTF-8 (json_text);
   * the strings read from fit.json are UTF-8 already. json_pack takes the
   * "o" values, also when it fails. */
  json_t *doc = json_pack(
      "{s:i, s:{s:s, s:s}, s:o, s:o, s:{s:s, s:s, s:s, s:s, s:s}, "
      "s:{s:f, s:f, s:I, s:{s:f, s:f, s:b}, s:o, s:{s:s, s:f}}, "
      "s:{s:s, s:s, s:o, s:s, s:s, s:{s:o, s:s, s:s}}}",
      "clayfit_preset", 1, "model", "code", m->code, "name", m->name, "params", params, "derived",
      derived, "conventions", "brdf",
      "f(l, v) per linear-RGB channel in 1/sr (not f cos), as clayfit eval prints it", "roughness",
      "perceptual: the GGX width is alpha = r^2", "f0",
      "normal-incidence reflectance; eta = (1 + sqrt(F0)) / (1 - sqrt(F0))", "base_f0",
      "M4: reflectance of the film-to-clay interface, relative to the film", "model",
      "docs/model.md of clayfit " CLAYFIT_EXPORT_VERSION, "fit", "rmse", r->rmse, "relative_rmse",
      r->relative_rmse, "residuals", (json_int_t)r->residuals, "scale", "value", r->scale, "sd",
      r->scale_sd, "fitted", r->scale_fitted, "response", response_json(r), "loss", "type",
      fit->loss, "scale_sigma", fit->loss_scale, "provenance", "clayfit_version",
      CLAYFIT_EXPORT_VERSION, "exported", exported, "fit_file", json_text(fit_path),
      "fit_clayfit_version", fit->clayfit_version, "fit_created", fit->created, "capture", "path",
      json_text(fit->capture_path), "name", fit->capture_name, "radiometry", fit->radiometry);
  if (!doc) return cf_error_set(err, CF_ENOMEM, "%s: could not build the preset", path);
  /* the model version the values were fitted with (docs/model.md, top) */
  json_object_set_new(json_object_get(doc, "conventions"), "model_version",
                      json_integer(fit->model_version));
  cf_status s = json_write_file(doc, path, JSON_INDENT(2) | JSON_REAL_PRECISION(17), err);
  json_decref(doc);
  return s;
}

/* ---- reading a preset back ---- */

#define TRY(call)               \
  do {                          \
    cf_status s_ = (call);      \
    if (s_ != CF_OK) return s_; \
  } while (0)

static cf_status read_sd(const json_t *value, const json_at *at, int components, cf_error *err) {
  if (components == 3 && json_is_array(value) && json_array_size(value) == 3) {
    for (size_t c = 0; c < 3; ++c) {
      json_at e = json_element_at(at, c);
      TRY(read_sd(json_array_get(value, c), &e, 1, err));
    }
    return CF_OK;
  }
  if (json_is_null(value)) return CF_OK;
  double x;
  return json_as_number(value, at, 0.0, 1e308, &x, err);
}

static cf_status read_preset(const json_t *root, const char *path, cf_model_id *model,
                             double *params, cf_error *err) {
  json_at at = {path, NULL, NULL, 0};
  static const char *const known[] = {"clayfit_preset", "model", "params",     "derived",
                                      "conventions",    "fit",   "provenance", NULL};
  TRY(json_check_keys(root, &at, known, err));
  long long layout;
  TRY(json_get_integer(root, &at, "clayfit_preset", 1, 1, 1, &layout, NULL, err));
  const json_t *obj;
  TRY(json_get_object(root, &at, "model", 1, &obj, NULL, err));
  json_at mh = json_member_at(&at, "model");
  static const char *const mkeys[] = {"code", "name", NULL};
  TRY(json_check_keys(obj, &mh, mkeys, err));
  const char *const *codes = cf_model_codes(), *const *names = cf_model_names();
  int code, name;
  TRY(json_get_choice(obj, &mh, "code", 1, codes, &code, NULL, err));
  TRY(json_get_choice(obj, &mh, "name", 1, names, &name, NULL, err));
  if (code != name)
    return json_fail(&mh, err, CF_EPARSE, "code %s and name %s are not the same model", codes[code],
                     names[name]);
  *model = (cf_model_id)code;
  const cf_model_info *m = cf_model_info_get(*model);
  TRY(json_get_object(root, &at, "params", 1, &obj, NULL, err));
  json_at ph = json_member_at(&at, "params");
  const char *key;
  json_t *value;
  json_object_foreach((json_t *)obj, key, value) {
    int slot;
    cf_error ignored = {0};
    if (cf_model_param_find(*model, key, &slot, NULL, &ignored) != CF_OK) {
      json_at here = json_member_at(&ph, key);
      return json_fail(&here, err, CF_EPARSE, "model %s (%s) has no parameter '%s'", m->code,
                       m->name, key);
    }
  }
  for (int j = 0; j < m->param_count; ++j) {
    const cf_param_info *info = cf_param_info_get(m->params[j]);
    const json_t *p;
    TRY(json_get_object(obj, &ph, info->name, 1, &p, NULL, err));
    json_at here = json_member_at(&ph, info->name);
    static const char *const pkeys[] = {"value", "sd",    "unit",    "status",
                                        "lower", "upper", "meaning", NULL};
    TRY(json_check_keys(p, &here, pkeys, err));
    double *x = params + m->offsets[j];
    if (info->components == 3)
      TRY(json_get_numbers(p, &here, "value", 1, 3, info->lower, info->upper, x, NULL, err));
    else
      TRY(json_get_number(p, &here, "value", 1, info->lower, info->upper, x, NULL, err));
    const json_t *sd = json_object_get(p, "sd");
    if (sd) {
      json_at sh = json_member_at(&here, "sd");
      TRY(read_sd(sd, &sh, info->components, err));
    }
    const char *unit;
    int found;
    TRY(json_get_string(p, &here, "unit", 0, &unit, &found, err));
    if (found && strcmp(unit, info->unit) != 0) {
      json_at u = json_member_at(&here, "unit");
      return json_fail(&u, err, CF_EPARSE, "'%s' is not the unit of %s ('%s')", unit, info->name,
                       info->unit);
    }
  }
  return CF_OK;
}

cf_status cf_export_preset_read(const char *path, cf_model_id *model, double params[CF_MAX_DIM],
                                cf_error *err) {
  json_t *root = NULL;
  cf_status s = json_load_object(path, (size_t)16 << 20, &root, err);
  if (s != CF_OK) return s;
  double x[CF_MAX_DIM] = {0};
  cf_model_id m = CF_MODEL_LAMBERT;
  s = read_preset(root, path, &m, x, err);
  json_decref(root);
  if (s != CF_OK) return s;
  *model = m;
  memcpy(params, x, sizeof x);
  return CF_OK;
}
