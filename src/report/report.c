/* The residual report of a fit (include/clayfit/report.h). */
#include <stdio.h>
#include <stdlib.h>

#include "core/file.h"
#include "report_internal.h"

cf_status cf_report_write(const cf_capture *capture, const cf_fit_file *fit, const char *dir,
                          const cf_report_options *options, cf_error *err) {
  const char *fit_path = options && options->fit_path ? options->fit_path : "fit.json";
  const char *version = options && options->version ? options->version : "";
  char sub[4096];
  cf_status s = cf_make_dirs(dir, err);
  snprintf(sub, sizeof sub, "%s/images", dir);
  if (s == CF_OK) s = cf_make_dirs(sub, err);
  snprintf(sub, sizeof sub, "%s/plots", dir);
  if (s == CF_OK) s = cf_make_dirs(sub, err);
  if (s != CF_OK) return s;
  report_data d;
  if (options && options->progress) options->progress(options->progress_user, "predicting", 0, 1);
  s = report_data_build(&d, capture, fit, fit_path, err);
  if (s != CF_OK) return s;
  char(*files)[3][64] = calloc(d.images ? d.images : 1, sizeof *files);
  if (!files) s = cf_error_set(err, CF_ENOMEM, "out of memory");
  for (size_t k = 0; s == CF_OK && k < d.images; ++k) {
    if (options && options->progress)
      options->progress(options->progress_user, "writing images", k, d.images);
    s = report_image(&d, k, dir, files[k], err);
  }
  if (s == CF_OK && options && options->progress)
    options->progress(options->progress_user, "writing images", d.images, d.images);
  if (s == CF_OK) s = report_write_plots(&d, dir, err);
  if (s == CF_OK) s = report_write_json(&d, dir, fit_path, version, files, err);
  if (s == CF_OK) s = report_write_html(&d, dir, fit_path, version, files, err);
  free(files);
  report_data_free(&d);
  return s;
}
