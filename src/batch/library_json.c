/* LIBRARY/library.json (data_schema/library.schema.json): one record per
 * manifest entry, from what its folder holds. */
#include <stdio.h>
#include <string.h>

#include "batch_internal.h"
#include "clayfit/fit_file.h"
#include "core/file.h"
#include "core/json_reader.h"

static const char *state_name(cf_batch_state state) {
  return state == CF_BATCH_FITTED ? "fitted" : state == CF_BATCH_FAILED ? "failed" : "missing";
}

/* "<name>/<file>", a path relative to the library. */
static json_t *entry_path(const char *name, const char *file) {
  char path[4096];
  snprintf(path, sizeof path, "%s/%s", name, file);
  return json_string(path);
}

static json_t *preset_paths(const char *name) {
  json_t *presets = json_object();
  char file[128];
  for (int f = 0; presets && f < CF_EXPORT_FORMAT_COUNT; ++f) {
    snprintf(file, sizeof file, "presets/%s", batch_preset_file((cf_export_format)f));
    json_object_set_new(presets, cf_export_format_name((cf_export_format)f),
                        entry_path(name, file));
  }
  return presets;
}

/* value, sd and status of each parameter, as fit.json has them. */
static json_t *params_of(const json_t *fit_params) {
  json_t *params = json_object();
  const char *key;
  json_t *value;
  json_object_foreach((json_t *)fit_params, key, value) {
    json_t *p = json_object();
    json_object_set(p, "value", json_object_get(value, "value"));
    json_object_set(p, "sd", json_object_get(value, "sd"));
    json_object_set(p, "status", json_object_get(value, "status"));
    json_object_set_new(params, key, p);
  }
  return params;
}

/* The fitted entry's model, parameters and RMSE from its fit.json. */
static cf_status add_fit(json_t *record, const char *library, const char *name, cf_error *err) {
  char path[4096];
  snprintf(path, sizeof path, "%s/%s/fit.json", library, name);
  cf_fit_file fit;
  cf_status s = cf_fit_file_read(path, &fit, err);
  if (s != CF_OK) return s;
  const json_t *model = json_object_get(fit.document, "model");
  json_object_set(record, "model", json_object_get(model, "code"));
  json_object_set_new(record, "params", params_of(json_object_get(fit.document, "params")));
  json_object_set_new(record, "relative_rmse", json_real(fit.result.relative_rmse));
  json_t *paths = json_object_get(record, "paths");
  json_object_set_new(paths, "fit", entry_path(name, "fit.json"));
  json_object_set_new(paths, "report", entry_path(name, "report/index.html"));
  json_object_set_new(paths, "presets", preset_paths(name));
  json_object_set_new(paths, "entry", entry_path(name, "entry.json"));
  cf_fit_file_free(&fit);
  return CF_OK;
}

static json_t *null_paths(void) {
  return json_pack("{s:n, s:n, s:n, s:n, s:n}", "fit", "report", "presets", "entry", "failed");
}

static cf_status entry_record(const char *library, const cf_batch_entry *e, json_t **out,
                              cf_error *err) {
  char key[CF_BATCH_KEY_SIZE], reason[1024];
  cf_batch_state state = cf_batch_entry_state(library, e->name, key);
  json_t *r = json_pack("{s:s, s:o, s:s, s:o, s:n, s:n, s:n, s:n, s:o, s:n}", "name", e->name,
                        "tags", batch_object_or_empty(e->tags), "state", state_name(state),
                        "key", key[0] ? json_string(key) : json_null(), "model", "params",
                        "relative_rmse", "reason", "paths", null_paths(), "thumbnail");
  if (!r) return cf_error_set(err, CF_ENOMEM, "out of memory");
  cf_status s = CF_OK;
  if (state == CF_BATCH_FITTED) s = add_fit(r, library, e->name, err);
  if (state == CF_BATCH_FAILED) {
    cf_batch_failed_reason(library, e->name, reason, sizeof reason);
    json_object_set_new(r, "reason", json_text(reason));
    json_object_set_new(json_object_get(r, "paths"), "failed", entry_path(e->name, "failed.json"));
  }
  if (s != CF_OK) json_decref(r);
  *out = s == CF_OK ? r : NULL;
  return s;
}

cf_status cf_batch_library_write(const char *library, const cf_batch_manifest *m,
                                 cf_error *err) {
  json_t *entries = json_array();
  json_t *root = json_pack("{s:i, s:s, s:s, s:o}", "clayfit_library", 1, "clayfit_version",
                           CLAYFIT_VERSION, "build", cf_batch_build_id(), "entries", entries);
  if (!root) return cf_error_set(err, CF_ENOMEM, "out of memory");
  cf_status s = CF_OK;
  for (size_t i = 0; s == CF_OK && i < m->count; ++i) {
    json_t *record = NULL;
    s = entry_record(library, &m->entries[i], &record, err);
    if (s == CF_OK) json_array_append_new(entries, record);
  }
  char path[4096];
  if (s == CF_OK) s = cf_path_join(library, "library.json", path, sizeof path, err);
  if (s == CF_OK) s = json_write_file(root, path, JSON_INDENT(2) | JSON_REAL_PRECISION(17), err);
  json_decref(root);
  return s;
}
