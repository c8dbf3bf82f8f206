/* clayfit: fit.json (data_schema/fit.schema.json), a fit as a file.
 *
 * Reading it back (cf_fit_file_read) is the library clayfit_fit_read, which
 * needs core, model and Jansson only: clayfit export links it and not the
 * solver (Ceres). Writing it (cf_fit_write_json) summarises the capture and
 * the fit, and is the fit layer's (clayfit_fit).
 *
 * fit.json names its capture by capture.path, relative to the folder of
 * fit.json (so that the two can be read from anywhere and moved together).
 * A fit.json written before that rule has the path relative to the folder
 * where clayfit fit ran; the reader still finds it there, relative to the
 * current folder, when that is the only place it exists. */
#ifndef CLAYFIT_FIT_FILE_H
#define CLAYFIT_FIT_FILE_H

#include "clayfit/capture.h"
#include "clayfit/fit.h"
#include "clayfit/status.h"

#ifdef __cplusplus
extern "C" {
#endif

struct json_t; /* Jansson's */

/* ---- writing (clayfit_fit) ---- */

typedef struct cf_fit_report {
  const cf_capture *capture;
  const char *capture_path; /* as opened: relative to the current folder, or absolute;
                               written relative to fit.json's folder */
  const cf_fit_result *result;
  const cf_fit_choice *choice; /* NULL: the model was forced (--model M) */
  const char *version;
  cf_loss loss;
  double loss_scale;
  double density; /* NaN: the convention of docs/model.md §3.6 */
  double load_seconds, fit_seconds;
  int footprint;              /* cf_fit_options.footprint */
  double footprint_tolerance; /* cf_fit_options.footprint_tolerance */
} cf_fit_report;

/* Write fit.json at path. The folders of path and of the capture must
 * exist (the capture's path is made relative to the first through both
 * real paths). */
cf_status cf_fit_write_json(const char *path, const cf_fit_report *report, cf_error *err);

/* ---- reading back (clayfit_fit_read: for clayfit export and report) ---- */

typedef struct cf_fit_file {
  cf_fit_result result; /* model, params, sd (NaN for null), status, scale/scale_sd/scale_fitted,
                           response/response_sd/response_fitted, sigma, images, exposures
                           (owned), rmse, relative_rmse, residual counts, image_rmse and
                           image_relative_rmse (owned): as far as fit.json holds them */
  char clayfit_version[32], created[32];
  int model_version;          /* model_version: the formulas the values were fitted with
                                 (CF_MODEL_VERSION; 1, Schlick's Fresnel, when absent) */
  char capture_path[4096];    /* the capture to open: capture.path joined to fit.json's folder
                                 (absolute: as it is); for a fit.json written before that rule,
                                 capture.path as written (relative to the current folder) when
                                 only that exists. When neither exists: joined to fit.json's
                                 folder, and capture_found is 0 */
  char capture_written[4096]; /* capture.path as fit.json has it */
  int capture_found;          /* 1 if a file exists at capture_path */
  char capture_name[256];
  char radiometry[32];  /* "absolute", "relative" or "from_reference" */
  double density;       /* derived.density (NaN when derived is null) */
  double absorption[3]; /* NaN where undefined */
  char density_convention[512];
  char loss[16];     /* loss.type */
  double loss_scale; /* loss.scale_sigma */
  int footprint;     /* cf_fit_options.footprint: 0 auto, 1 centre, S fixed */
  double footprint_tolerance;
  size_t capture_images, capture_observations; /* capture.images, capture.observations */
  struct json_t *document; /* fit.json as read and checked (owned; freed by cf_fit_file_free):
                              what the report shows beyond the fields above (the choice's
                              candidates, the starts, the solver's trace, the timings, the
                              images' names), so that fit.json is parsed once, under the cap */
} cf_fit_file;

/* The most bytes cf_fit_file_read accepts, checked before anything is
 * allocated. A fit of 1,040 images writes 181 KB (123 bytes an image);
 * parsing costs up to 45 times the size (8 MiB of "[]," took 363 MB with
 * Jansson 2.14, where the earlier 256 MiB cap allowed 11 GB). */
#define CF_FIT_FILE_MAX_SIZE ((size_t)8 << 20)

/* One line for a command to print as a warning when the file's values were
 * fitted with an older model version (docs/model.md, "Changes from version
 * 1"); NULL when they belong to this one (CF_MODEL_VERSION). */
const char *cf_fit_file_version_warning(const cf_fit_file *file);

/* Read fit.json back (untrusted: at most CF_FIT_FILE_MAX_SIZE bytes, every
 * field type- and range-checked, errors name the file and the JSON path). A
 * capture that is not found is not an error here (export does not need it):
 * see cf_fit_file_check_capture. */
cf_status cf_fit_file_read(const char *path, cf_fit_file *file, cf_error *err);
void cf_fit_file_free(cf_fit_file *file);

/* CF_OK when the capture of a fit.json read from fit_path was found, else
 * CF_ENOTFOUND with a message naming every place it was looked for. */
cf_status cf_fit_file_check_capture(const cf_fit_file *file, const char *fit_path, cf_error *err);

#ifdef __cplusplus
}
#endif

#endif /* CLAYFIT_FIT_FILE_H */
