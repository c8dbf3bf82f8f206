/* clayfit library compare (include/clayfit/library.h): two entries of a
 * library, their parameters side by side and the difference of their
 * renders under the standard light. Here in the batch layer, not the
 * report's, because it reads the library's layout (library.json, the
 * entries' folders), which is the batch layer's; the renders come from the
 * report layer below (cf_report_render_sphere, the thumbnail's scene). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "batch_internal.h"
#include "clayfit/fit_file.h"
#include "clayfit/library.h"
#include "clayfit/thumbnail.h"
#include "core/file.h"
#include "core/json_reader.h"

/* library.json's cap: about 2 KB an entry, so 100,000 entries fit. */
#define LIBRARY_JSON_MAX_SIZE ((size_t)256 << 20)

/* The record of `name` in library.json's entries (NULL when not listed). */
static const json_t *find_record(const json_t *entries, const char *name) {
  size_t i;
  json_t *record;
  json_array_foreach(entries, i, record) {
    const char *n = json_string_value(json_object_get(record, "name"));
    if (n && strcmp(n, name) == 0) return record;
  }
  return NULL;
}

/* The record of a fitted entry, or CF_EINVAL naming why there is none. */
static cf_status fitted_record(const char *library, const json_t *root, const char *name,
                               cf_error *err) {
  const json_t *entries = json_object_get(root, "entries");
  if (json_integer_value(json_object_get(root, "clayfit_library")) != 1 ||
      !json_is_array(entries))
    return cf_error_set(err, CF_EINVAL, "%s: not a clayfit library (library.json is not one "
                        "clayfit batch wrote)", library);
  const json_t *record = find_record(entries, name);
  if (!record)
    return cf_error_set(err, CF_EINVAL, "%s: no entry '%s' in the library", library, name);
  const char *state = json_string_value(json_object_get(record, "state"));
  if (state && strcmp(state, "failed") == 0) {
    const char *reason = json_string_value(json_object_get(record, "reason"));
    return cf_error_set(err, CF_EINVAL, "%s: entry '%s' failed: %s", library, name,
                        reason ? reason : "(no reason recorded)");
  }
  if (!state || strcmp(state, "fitted") != 0)
    return cf_error_set(err, CF_EINVAL, "%s: entry '%s' is not fitted (its task died or did "
                        "not run)", library, name);
  return CF_OK;
}

static cf_status entry_from_fit(const char *library, const char *name, cf_library_entry *entry,
                                cf_error *err) {
  char folder[4096], path[4096];
  cf_status s = cf_path_join(library, name, folder, sizeof folder, err);
  if (s == CF_OK) s = cf_path_join(folder, "fit.json", path, sizeof path, err);
  cf_fit_file fit;
  if (s == CF_OK) s = cf_fit_file_read(path, &fit, err);
  if (s != CF_OK) return s;
  const cf_model_info *info = cf_model_info_get(fit.result.model);
  snprintf(entry->name, sizeof entry->name, "%s", name);
  entry->model = fit.result.model;
  for (int k = 0; k < info->dim; ++k) {
    entry->params[k] = fit.result.params[k];
    entry->sd[k] = fit.result.sd[k];
  }
  entry->relative_rmse = fit.result.relative_rmse;
  cf_fit_file_free(&fit);
  return CF_OK;
}

cf_status cf_library_entry_read(const char *library, const char *name, cf_library_entry *entry,
                                cf_error *err) {
  memset(entry, 0, sizeof *entry);
  if (!cf_batch_name_valid(name))
    return cf_error_set(err, CF_EINVAL, "%s: '%s' is not an entry name", library, name);
  char path[4096];
  json_t *root = NULL;
  cf_status s = cf_path_join(library, "library.json", path, sizeof path, err);
  if (s == CF_OK && json_load_object(path, LIBRARY_JSON_MAX_SIZE, &root, err) != CF_OK) {
    char why[sizeof err->message];
    snprintf(why, sizeof why, "%s", err->message);
    s = cf_error_set(err, CF_EINVAL, "%s: not a clayfit library (%s)", library, why);
  }
  if (s == CF_OK) s = fitted_record(library, root, name, err);
  json_decref(root);
  if (s == CF_OK) s = entry_from_fit(library, name, entry, err);
  return s;
}

/* ---- the parameters ---- */

static double sd_or_zero(double sd) { return isfinite(sd) ? sd : 0.0; }

static double z_score(double a, double sd_a, double b, double sd_b) {
  double sd = sqrt(sd_or_zero(sd_a) * sd_or_zero(sd_a) + sd_or_zero(sd_b) * sd_or_zero(sd_b));
  if (sd > 0.0) return (a - b) / sd;
  return a == b ? 0.0 : NAN;
}

/* The slot of parameter id in a model, -1 when the model lacks it. */
static int slot_of(cf_model_id model, cf_param_id id) {
  const cf_model_info *info = cf_model_info_get(model);
  for (int i = 0; i < info->param_count; ++i)
    if (info->params[i] == id) return info->offsets[i];
  return -1;
}

/* Every component of parameter id: from A and B where their models have it. */
static void add_param(cf_library_comparison *c, cf_param_id id) {
  const cf_param_info *p = cf_param_info_get(id);
  int slot_a = slot_of(c->a.model, id), slot_b = slot_of(c->b.model, id);
  for (int k = 0; k < p->components && c->count < CF_LIBRARY_MAX_DIFFS; ++k) {
    cf_library_param_diff *d = &c->diffs[c->count++];
    *d = (cf_library_param_diff){p->name, k, p->components, slot_a >= 0, slot_b >= 0,
                                 NAN, NAN, NAN, NAN, NAN};
    if (d->in_a) d->a = c->a.params[slot_a + k], d->sd_a = c->a.sd[slot_a + k];
    if (d->in_b) d->b = c->b.params[slot_b + k], d->sd_b = c->b.sd[slot_b + k];
    if (d->in_a && d->in_b) d->z = z_score(d->a, d->sd_a, d->b, d->sd_b);
  }
}

static void compare_params(cf_library_comparison *c) {
  const cf_model_info *a = cf_model_info_get(c->a.model), *b = cf_model_info_get(c->b.model);
  for (int i = 0; i < a->param_count; ++i) add_param(c, a->params[i]);
  for (int i = 0; i < b->param_count; ++i)
    if (slot_of(c->a.model, b->params[i]) < 0) add_param(c, b->params[i]);
}

/* ---- the renders ---- */

static cf_status render(const cf_library_entry *e, cf_image *out, cf_error *err) {
  cf_sphere_view view;
  cf_sphere_view_default(&view);
  return cf_sphere_render(e->model, e->params, &view, out, err);
}

static cf_status difference(cf_library_comparison *c, cf_error *err) {
  const cf_image *a = &c->render_a, *b = &c->render_b;
  cf_status s = cf_image_alloc(&c->difference, a->width, a->height, a->channels, err);
  if (s != CF_OK) return s;
  size_t n = (size_t)a->width * (size_t)a->height * (size_t)a->channels;
  double sum = 0.0, max = 0.0;
  for (size_t i = 0; i < n; ++i) {
    double d = (double)a->pixels[i] - (double)b->pixels[i];
    c->difference.pixels[i] = (float)d;
    sum += d * d;
    max = fabs(d) > max ? fabs(d) : max;
  }
  c->max_abs_difference = max;
  c->rms_difference = sqrt(sum / (double)n);
  return CF_OK;
}

cf_status cf_library_compare(const char *library, const char *a, const char *b,
                             cf_library_comparison *out, cf_error *err) {
  memset(out, 0, sizeof *out);
  cf_status s = cf_library_entry_read(library, a, &out->a, err);
  if (s == CF_OK) s = cf_library_entry_read(library, b, &out->b, err);
  if (s == CF_OK) compare_params(out);
  if (s == CF_OK) s = render(&out->a, &out->render_a, err);
  if (s == CF_OK) s = render(&out->b, &out->render_b, err);
  if (s == CF_OK) s = difference(out, err);
  if (s != CF_OK) cf_library_comparison_free(out);
  return s;
}

void cf_library_comparison_free(cf_library_comparison *c) {
  cf_image_free(&c->render_a);
  cf_image_free(&c->render_b);
  cf_image_free(&c->difference);
}

double cf_library_difference_scale(const cf_library_comparison *c) {
  return c->max_abs_difference;
}
