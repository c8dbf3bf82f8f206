/* report.json (data_schema/report.schema.json). */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "core/json_reader.h"
#include "report_internal.h"

static json_t *parameters_json(const cf_fit_result *r, json_t **unconstrained) {
  const cf_model_info *m = cf_model_info_get(r->model);
  json_t *list = json_array();
  *unconstrained = json_array();
  for (int j = 0; j < m->param_count; ++j) {
    const cf_param_info *info = cf_param_info_get(m->params[j]);
    for (int c = 0; c < info->components; ++c) {
      int k = m->offsets[j] + c;
      char name[48];
      cf_model_slot_name(r->model, k, name, sizeof name);
      json_array_append_new(
          list, json_pack("{s:s, s:f, s:o, s:s, s:s}", "name", name, "value", r->params[k], "sd",
                          json_real_or_null(r->sd[k]), "unit", info->unit, "status",
                          cf_param_status_name(r->status[k])));
      if (r->status[k] == CF_PARAM_UNCONSTRAINED)
        json_array_append_new(*unconstrained, json_string(name));
    }
  }
  return list;
}

cf_status report_write_json(const report_data *d, const char *dir, const char *fit_path,
                            const char *version, char (*image_files)[3][64], cf_error *err) {
  const cf_fit_result *r = &d->fit->result;
  const cf_model_info *m = cf_model_info_get(r->model);
  json_t *images = json_array(), *plots = json_object(), *unconstrained;
  size_t censored = 0, rejected = 0, beyond = 0, used = 0;
  double sum2 = 0.0;
  for (size_t i = 0; i < d->count; ++i) {
    censored += (d->mark[i] & REPORT_CENSORED) != 0;
    rejected += (d->mark[i] & REPORT_REJECTED) != 0;
    if (!isfinite(d->residual[i])) continue;
    ++used;
    sum2 += (double)d->residual[i] * d->residual[i];
    beyond += fabs(d->residual[i]) > CF_REPORT_SIGMA_RANGE;
  }
  for (size_t k = 0; k < d->images; ++k) {
    const cf_capture_image *im = cf_capture_image_at(d->capture, k);
    json_array_append_new(
        images,
        json_pack("{s:o, s:s, s:s, s:s, s:I, s:I, s:I, s:I, s:I, s:f, s:o, s:o}", "name",
                  json_text(im->name), "photo", image_files[k][0], "render", image_files[k][1],
                  "residual", image_files[k][2], "observations", (json_int_t)d->observations[k],
                  "censored", (json_int_t)d->censored[k], "rejected", (json_int_t)d->rejected[k],
                  "rejected_largest_region", (json_int_t)d->rejected_region[k],
                  "not_radiance", (json_int_t)im->not_radiance, "rms_sigma", d->rms_sigma[k],
                  "rmse", json_real_or_null(r->image_rmse ? r->image_rmse[k] : NAN),
                  "relative_rmse",
                  json_real_or_null(r->image_relative_rmse ? r->image_relative_rmse[k] : NAN)));
  }
  for (int p = 0; p < REPORT_PLOT_COUNT; ++p)
    json_object_set_new(plots, report_plots[p].key, json_string(report_plots[p].file));
  if (d->fit->result.response_fitted)
    json_object_set_new(plots, report_response_plot_info.key,
                        json_string(report_response_plot_info.file));
  char created[32];
  time_t now = time(NULL);
  struct tm utc;
  gmtime_r(&now, &utc);
  strftime(created, sizeof created, "%Y-%m-%dT%H:%M:%SZ", &utc);
  json_t *params = parameters_json(r, &unconstrained);
  json_t *doc = json_pack(
      "{s:i, s:s, s:s, s:o, s:s, s:{s:o, s:s}, s:{s:s, s:s}, s:o, s:o, s:f, "
      "s:{s:I, s:I, s:I, s:I, s:f, s:f}, s:o, s:o}",
      "clayfit_report", 1, "clayfit_version", version, "created", created, "fit",
      json_text(fit_path), "page", "index.html", "capture", "path", json_text(d->capture_path),
      "name", d->fit->capture_name, "model", "code", m->code, "name", m->name, "parameters", params,
      "not_constrained", unconstrained, "sigma_range", CF_REPORT_SIGMA_RANGE, "residuals", "count",
      (json_int_t)used, "censored", (json_int_t)censored, "rejected", (json_int_t)rejected,
      "beyond_sigma_range", (json_int_t)beyond, "rms_sigma", used ? sqrt(sum2 / (double)used) : 0.0,
      "loss_scale_sigma", isfinite(d->loss_scale) ? d->loss_scale : 0.0, "images", images, "plots",
      plots);
  if (!doc) return cf_error_set(err, CF_ENOMEM, "could not build report.json");
  json_object_set_new(json_object_get(doc, "residuals"), "rejected_largest_region_share",
                      json_real_or_null(report_rejected_share(d, 0)));
  json_object_set_new(json_object_get(doc, "residuals"), "rejected_clustered_share",
                      json_real_or_null(report_rejected_share(d, 1)));
  json_t *capture = json_object_get(doc, "capture");
  if (strcmp(d->capture_path, d->fit->capture_path) != 0)
    json_object_set_new(capture, "fit_capture", json_text(d->fit->capture_path));
  if (d->capture_check[0]) json_object_set_new(capture, "check", json_string(d->capture_check));
  char path[4096];
  snprintf(path, sizeof path, "%s/report.json", dir);
  cf_status s = json_write_file(doc, path, JSON_INDENT(2) | JSON_REAL_PRECISION(10), err);
  json_decref(doc);
  return s;
}
