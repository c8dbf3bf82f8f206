/* LIBRARY/library.json (data_schema/library.schema.json): one record per
 * manifest entry, from what its folder holds; then LIBRARY/index.html, the
 * gallery (docs/batch.md, "The gallery"), a card per record built from the
 * same records, so that the two cannot disagree. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "batch_internal.h"
#include "clayfit/fit_file.h"
#include "clayfit/gallery.h"
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
  /* An entry fitted before thumbnails existed has none (until re-fitted). */
  struct stat st;
  snprintf(path, sizeof path, "%s/%s/thumbnail.png", library, name);
  if (stat(path, &st) == 0 && S_ISREG(st.st_mode))
    json_object_set_new(record, "thumbnail", entry_path(name, "thumbnail.png"));
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

/* ---- the gallery, from library.json's records ---- */

/* What a card points to besides the record's own strings (the manifest
 * caps the tags, a model has at most CF_MAX_DIM parameters). */
typedef struct card_storage {
  cf_gallery_tag tags[CF_BATCH_MAX_TAGS];
  cf_gallery_param params[CF_MAX_DIM];
} card_storage;

static const char *string_or_null(const json_t *object, const char *key) {
  return json_string_value(json_object_get(object, key));
}

/* Component i of a value or sd (a number, or an array of 3); NaN for
 * null. */
static double component(const json_t *v, int i) {
  if (json_is_array(v)) v = json_array_get(v, (size_t)i);
  return json_is_number(v) ? json_number_value(v) : NAN;
}

/* The card's parameters from the record's: value and sd as library.json
 * has them, the unit from the model's table. */
static size_t card_params(const json_t *record, cf_gallery_param *out) {
  cf_model_id model;
  cf_error ignored = {0};
  const char *code = string_or_null(record, "model");
  if (!code || cf_model_find(code, &model, &ignored) != CF_OK) return 0;
  size_t count = 0;
  const char *name;
  json_t *p;
  json_object_foreach(json_object_get(record, "params"), name, p) {
    int slot;
    const cf_param_info *info;
    if (count == CF_MAX_DIM ||
        cf_model_param_find(model, name, &slot, &info, &ignored) != CF_OK)
      continue;
    cf_gallery_param *g = &out[count++];
    *g = (cf_gallery_param){name, info->components, {0}, {0}, info->unit};
    for (int c = 0; c < info->components; ++c) {
      g->value[c] = component(json_object_get(p, "value"), c);
      g->sd[c] = component(json_object_get(p, "sd"), c);
      if (!(g->sd[c] > 0.0)) g->sd[c] = NAN; /* held or at a bound: none, as the gallery's */
    }
  }
  return count;
}

static void card_of(const json_t *record, card_storage *storage, cf_gallery_entry *card) {
  const char *state = string_or_null(record, "state");
  const json_t *paths = json_object_get(record, "paths");
  const json_t *rmse = json_object_get(record, "relative_rmse");
  size_t tags = 0;
  const char *key;
  json_t *value;
  json_object_foreach(json_object_get(record, "tags"), key, value) {
    if (tags < CF_BATCH_MAX_TAGS)
      storage->tags[tags++] = (cf_gallery_tag){key, json_string_value(value)};
  }
  int fitted = strcmp(state, "fitted") == 0, failed = strcmp(state, "failed") == 0;
  *card = (cf_gallery_entry){
      .name = string_or_null(record, "name"),
      .tags = storage->tags,
      .tag_count = tags,
      .state = fitted ? CF_GALLERY_FITTED : failed ? CF_GALLERY_FAILED : CF_GALLERY_MISSING,
      .model = string_or_null(record, "model"),
      .params = storage->params,
      .param_count = fitted ? card_params(record, storage->params) : 0,
      .relative_rmse = json_is_number(rmse) ? json_number_value(rmse) : NAN,
      .thumbnail = string_or_null(record, "thumbnail"),
      .report = string_or_null(paths, fitted ? "report" : "failed"),
      .reason = string_or_null(record, "reason")};
}

/* The page's title: the library folder's name. */
static void gallery_title(const char *library, char *out, size_t size) {
  size_t n = strlen(library);
  while (n > 1 && library[n - 1] == '/') --n;
  size_t start = n;
  while (start > 0 && library[start - 1] != '/') --start;
  snprintf(out, size, "clayfit library %.*s", (int)(n - start), library + start);
}

static cf_status write_gallery(const char *library, const json_t *entries, cf_error *err) {
  size_t count = json_array_size(entries);
  card_storage *storage = calloc(count ? count : 1, sizeof *storage);
  cf_gallery_entry *cards = calloc(count ? count : 1, sizeof *cards);
  cf_status s = storage && cards ? CF_OK : cf_error_set(err, CF_ENOMEM, "out of memory");
  for (size_t i = 0; s == CF_OK && i < count; ++i)
    card_of(json_array_get(entries, i), &storage[i], &cards[i]);
  char path[4096], title[512];
  gallery_title(library, title, sizeof title);
  if (s == CF_OK) s = cf_path_join(library, "index.html", path, sizeof path, err);
  if (s == CF_OK) s = cf_report_write_gallery(cards, count, title, path, err);
  free(cards);
  free(storage);
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
  if (s == CF_OK) s = write_gallery(library, entries, err);
  json_decref(root);
  return s;
}
