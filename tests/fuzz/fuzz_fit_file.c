/* libFuzzer target for reading fit.json back (cf_fit_file_read, the
 * clayfit_fit_read library that clayfit export and report read it with;
 * built and run by scripts/fuzz.sh): the bytes are a fit.json in a scratch
 * folder. Besides crashes and sanitizer reports, a broken promise aborts: a
 * failure names the file; a success holds a known model, finite values in
 * every slot, counts within their arrays and terminated strings. */
#ifndef _DEFAULT_SOURCE
#define _DEFAULT_SOURCE
#endif
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "clayfit/fit_file.h"
#include "clayfit/model.h"
#include "fuzz_files.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static int terminated(const char *text, size_t size) {
  return memchr(text, '\0', size) != NULL;
}

static void check_result(const cf_fit_result *r) {
  const cf_model_info *info = cf_model_info_get(r->model);
  fuzz_require(info != NULL, "a known model", "");
  for (int k = 0; k < info->dim; ++k) fuzz_require(isfinite(r->params[k]), "finite parameters", "");
  fuzz_require(r->free_count >= 0 && r->free_count <= info->dim, "free slots within the model", "");
  for (int k = 0; k < r->free_count; ++k)
    fuzz_require(r->free_slots[k] >= 0 && r->free_slots[k] < info->dim, "a free slot in range", "");
  fuzz_require(r->trace_count >= 0 && r->trace_count <= CF_FIT_MAX_TRACE, "a trace in its array",
               "");
  fuzz_require(r->starts >= 0 && r->starts <= CF_FIT_MAX_STARTS, "starts in their array", "");
  fuzz_require(r->warning_count >= 0 && r->warning_count <= CF_FIT_MAX_WARNINGS,
               "warnings in their array", "");
  for (int k = 0; k < r->warning_count; ++k)
    fuzz_require(terminated(r->warnings[k], sizeof r->warnings[k]), "a terminated warning", "");
  fuzz_require(terminated(r->termination, sizeof r->termination), "a terminated termination", "");
  fuzz_require(isfinite(r->scale) && r->scale > 0.0, "a finite, positive scale", "");
}

static void check_file(const cf_fit_file *f) {
  check_result(&f->result);
  fuzz_require(terminated(f->clayfit_version, sizeof f->clayfit_version) &&
                   terminated(f->created, sizeof f->created) &&
                   terminated(f->capture_path, sizeof f->capture_path) &&
                   terminated(f->capture_written, sizeof f->capture_written) &&
                   terminated(f->capture_name, sizeof f->capture_name) &&
                   terminated(f->radiometry, sizeof f->radiometry) &&
                   terminated(f->density_convention, sizeof f->density_convention) &&
                   terminated(f->loss, sizeof f->loss),
               "terminated strings", "");
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char path[4096];
  fuzz_write("fit.json", data, size, path);
  cf_fit_file file;
  cf_error err = {0};
  cf_status s = cf_fit_file_read(path, &file, &err);
  if (s != CF_OK) {
    fuzz_require(err.status == s && strstr(err.message, "fit.json") != NULL,
                 "a failure names the file", err.message);
    return 0;
  }
  check_file(&file);
  cf_error capture_err = {0};
  if (cf_fit_file_check_capture(&file, path, &capture_err) != CF_OK)
    fuzz_require(strstr(capture_err.message, "fit.json") != NULL,
                 "a missing capture names fit.json", capture_err.message);
  cf_fit_file_free(&file);
  return 0;
}
