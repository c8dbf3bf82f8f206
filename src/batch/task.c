/* One entry of a batch, in this process: the capture loaded, fitted,
 * fit.json, every preset, the report and thumbnail.png written into the
 * task's own folder, then entry.json (with each step's time), and the
 * folder renamed into place. A failure the capture causes leaves
 * failed.json (its reason and the task's log) as the entry instead; a
 * failure while running (out of memory, disk full) keeps a fitted entry. */
#define _DEFAULT_SOURCE /* gmtime_r, getrusage */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "batch_internal.h"
#include "clayfit/capture.h"
#include "clayfit/fit_file.h"
#include "clayfit/report.h"
#include "clayfit/thumbnail.h"
#include "core/clock.h"
#include "core/file.h"
#include "core/json_reader.h"

typedef struct task {
  const cf_batch_entry *entry;
  const char *library;
  const char *viewer_bundle; /* the report's three.js bundle, or NULL */
  char tmp[4096];
  char key[CF_BATCH_KEY_SIZE];
  char model[16];
  json_t *log; /* array of lines */
  char started[32];
  double start_wall;
  double seconds[5]; /* wall time of each step (task_step), for entry.json */
} task;

/* The steps a task times (entry.json's "timing"). */
typedef enum task_step { STEP_LOAD, STEP_FIT, STEP_PRESETS, STEP_REPORT, STEP_THUMBNAIL } task_step;
static const char *const step_names[] = {"load", "fit", "presets", "report", "thumbnail"};

static void task_log(task *t, const char *format, ...) {
  char line[1200];
  va_list args;
  va_start(args, format);
  vsnprintf(line, sizeof line, format, args);
  va_end(args);
  json_array_append_new(t->log, json_text(line));
}

static void utc_now(char out[32]) {
  time_t now = time(NULL);
  struct tm tm;
  gmtime_r(&now, &tm);
  strftime(out, 32, "%Y-%m-%dT%H:%M:%SZ", &tm);
}

static double cpu_seconds(void) {
  struct rusage u;
  if (getrusage(RUSAGE_SELF, &u) != 0) return 0.0;
  return (double)u.ru_utime.tv_sec + 1e-6 * (double)u.ru_utime.tv_usec + (double)u.ru_stime.tv_sec +
         1e-6 * (double)u.ru_stime.tv_usec;
}

/* "<tmp>/<file>" */
static cf_status in_tmp(const task *t, const char *file, char *out, size_t size, cf_error *err) {
  return cf_path_join(t->tmp, file, out, size, err);
}

/* What fit.json, the presets and the report name as the fit: its place in
 * the library once the entry is in place, not the task's folder. */
static void fit_label(const task *t, char *out, size_t size) {
  snprintf(out, size, "%s/fit.json", t->entry->name);
}

static cf_status load(task *t, cf_capture **capture, cf_error *err) {
  task_log(t, "loading %s", t->entry->capture);
  cf_capture_options options = {NULL, NULL, 0};
  cf_status s = cf_capture_load(t->entry->capture, &options, capture, err);
  if (s != CF_OK) return s;
  cf_capture_summary summary;
  cf_capture_summarize(*capture, &summary);
  for (size_t i = 0; i < summary.warnings; ++i)
    task_log(t, "warning: %s", cf_capture_warning(*capture, i));
  return CF_OK;
}

static cf_status fit(task *t, const cf_capture *capture, int threads, cf_error *err) {
  int automatic = 0;
  cf_model_id model = CF_MODEL_CLAY;
  cf_fit_options ladder[CF_MODEL_COUNT];
  cf_status s = cf_batch_fit_options(t->entry, threads, &automatic, &model, ladder, err);
  if (s != CF_OK) return s;
  task_log(t, "fitting (model %s, %d threads)", t->entry->model, threads);
  double start = cf_now_seconds();
  cf_fit_result result;
  cf_fit_choice choice;
  s = automatic ? cf_fit_auto(capture, ladder, &choice, &result, err)
                : cf_fit_run(capture, &ladder[model], &result, err);
  if (s != CF_OK) return s;
  const cf_fit_options *o = &ladder[automatic ? choice.chosen : model];
  char path[4096];
  s = in_tmp(t, "fit.json", path, sizeof path, err);
  if (s == CF_OK) {
    cf_fit_report report = {capture,
                            t->entry->capture,
                            &result,
                            automatic ? &choice : NULL,
                            CLAYFIT_VERSION,
                            o->loss,
                            o->loss_scale,
                            o->density,
                            t->start_wall ? start - t->start_wall : 0.0,
                            cf_now_seconds() - start,
                            o->footprint,
                            o->footprint_tolerance};
    s = cf_fit_write_json(path, &report, err);
  }
  snprintf(t->model, sizeof t->model, "%s", cf_model_info_get(result.model)->code);
  for (int i = 0; i < result.warning_count; ++i) task_log(t, "warning: %s", result.warnings[i]);
  task_log(t, "model %s, relative RMSE %.4g %%", t->model, 100.0 * result.relative_rmse);
  if (automatic) cf_fit_choice_free(&choice);
  cf_fit_result_free(&result);
  return s;
}

static cf_status presets(task *t, const cf_fit_file *file, cf_error *err) {
  char dir[4096], path[4096], label[4096];
  fit_label(t, label, sizeof label);
  cf_status s = in_tmp(t, "presets", dir, sizeof dir, err);
  if (s == CF_OK) s = cf_make_dirs(dir, err);
  for (int f = 0; s == CF_OK && f < CF_EXPORT_FORMAT_COUNT; ++f) {
    cf_export_warnings warnings = {0};
    s = cf_path_join(dir, batch_preset_file((cf_export_format)f), path, sizeof path, err);
    if (s == CF_OK) s = cf_export_write(file, label, (cf_export_format)f, path, &warnings, err);
    for (int i = 0; i < warnings.count; ++i)
      task_log(t, "%s: warning: %s", cf_export_format_name((cf_export_format)f), warnings.text[i]);
  }
  return s;
}

static cf_status report(task *t, const cf_capture *capture, const cf_fit_file *file,
                        cf_error *err) {
  char dir[4096], label[4096];
  fit_label(t, label, sizeof label);
  cf_status s = in_tmp(t, "report", dir, sizeof dir, err);
  cf_report_options options = {label, CLAYFIT_VERSION, NULL, NULL, t->entry->capture,
                               "",    t->viewer_bundle};
  if (s == CF_OK) s = cf_report_write(capture, file, dir, &options, err);
  return s;
}

/* The fitted sphere under the standard light (docs/report.md), from the
 * fit as fit.json has it, so that it equals what `clayfit library compare`
 * renders from the same file. */
static cf_status thumbnail(task *t, const cf_fit_file *file, cf_error *err) {
  char path[4096];
  cf_status s = in_tmp(t, "thumbnail.png", path, sizeof path, err);
  if (s == CF_OK) s = cf_report_write_thumbnail(&file->result, NULL, path, err);
  return s;
}

/* Add the wall time since *mark to step's, and reset the mark. */
static void timed(task *t, task_step step, double *mark) {
  double now = cf_now_seconds();
  t->seconds[step] += now - *mark;
  *mark = now;
}

/* The fit, the presets, the report and the thumbnail, into the task's
 * folder; *failed the step that failed. */
static cf_status work(task *t, int threads, task_step *failed, cf_error *err) {
  cf_capture *capture = NULL;
  double mark = cf_now_seconds();
  cf_status s = load(t, &capture, err);
  timed(t, STEP_LOAD, &mark);
  *failed = s == CF_OK ? STEP_FIT : STEP_LOAD;
  if (s == CF_OK) s = fit(t, capture, threads, err);
  char path[4096];
  cf_fit_file file;
  int read = 0;
  if (s == CF_OK) s = in_tmp(t, "fit.json", path, sizeof path, err);
  if (s == CF_OK) s = cf_fit_file_read(path, &file, err), read = s == CF_OK;
  timed(t, STEP_FIT, &mark);
  if (s == CF_OK) *failed = STEP_PRESETS, s = presets(t, &file, err);
  timed(t, STEP_PRESETS, &mark);
  if (s == CF_OK) task_log(t, "writing the report");
  if (s == CF_OK) *failed = STEP_REPORT, s = report(t, capture, &file, err);
  timed(t, STEP_REPORT, &mark);
  if (s == CF_OK) *failed = STEP_THUMBNAIL, s = thumbnail(t, &file, err);
  timed(t, STEP_THUMBNAIL, &mark);
  if (read) cf_fit_file_free(&file);
  cf_capture_free(capture);
  return s;
}

/* 1 when a step's failure is the capture's, as the command that runs the
 * step alone exits 2 for it (src/cli): clayfit fit loading (all but out of
 * memory) and fitting (invalid or out of range), clayfit export (all but
 * I/O and memory), clayfit report and its thumbnail (invalid). Else it is
 * a failure while running: out of memory, disk full, an I/O error. */
static int input_fault(task_step step, cf_status s) {
  if (step == STEP_LOAD) return s != CF_ENOMEM;
  if (step == STEP_FIT) return s == CF_EINVAL || s == CF_ERANGE;
  if (step == STEP_PRESETS) return s != CF_EIO && s != CF_ENOMEM;
  return s == CF_EINVAL; /* the report, the thumbnail */
}

static json_t *timing_of(const task *t) {
  json_t *timing = json_object();
  for (int i = 0; timing && i < (int)(sizeof step_names / sizeof *step_names); ++i)
    json_object_set_new(timing, step_names[i], json_real(t->seconds[i]));
  return timing;
}

/* entry.json, or failed.json (with the reason, and "retry" when the
 * failure is not the capture's), into the task's folder. */
static cf_status record(task *t, int threads, double cpu0, const char *reason, int retry,
                        cf_error *err) {
  char host[256], ended[32], path[4096];
  batch_host_name(host, sizeof host);
  utc_now(ended);
  json_t *doc = json_pack(
      "{s:s, s:s, s:s, s:o, s:o, s:s, s:s, s:o, s:s, s:s, s:f, s:f, s:i, s:I}", "name",
      t->entry->name, "key", t->key, "capture", t->entry->capture, "options",
      batch_object_or_empty(t->entry->options), "tags", batch_object_or_empty(t->entry->tags),
      "clayfit_version", CLAYFIT_VERSION, "build", cf_batch_build_id(), "host", json_text(host),
      "started", t->started, "ended", ended, "wall_seconds", cf_now_seconds() - t->start_wall,
      "cpu_seconds", cpu_seconds() - cpu0, "threads", threads, "pid", (json_int_t)getpid());
  if (!doc) return cf_error_set(err, CF_ENOMEM, "out of memory");
  json_object_set_new(doc, "timing", timing_of(t));
  if (reason) {
    json_object_set_new(doc, "reason", json_text(reason));
    json_object_set(doc, "log", t->log);
    if (retry) json_object_set_new(doc, "retry", json_true());
  } else {
    json_object_set_new(doc, "model", json_string(t->model));
  }
  cf_status s = in_tmp(t, reason ? "failed.json" : "entry.json", path, sizeof path, err);
  if (s == CF_OK) s = json_write_file(doc, path, JSON_INDENT(2), err);
  json_decref(doc);
  return s;
}

/* The task's folder emptied for failed.json. */
static cf_status fresh_tmp(const task *t, cf_error *err) {
  if (batch_remove_tree(t->tmp) != 0)
    return cf_error_set(err, CF_EIO, "%s: cannot remove the task's folder", t->tmp);
  return cf_make_dirs(t->tmp, err);
}

/* A failure while running with a fitted entry in place: the entry kept
 * whole, the task's folder removed, err saying so. */
static cf_status keep_entry(task *t, cf_status status, cf_error *err) {
  batch_remove_tree(t->tmp);
  cf_error why = *err;
  return cf_error_set(err, status,
                      "%s (a failure while running, not the capture's: the earlier entry is kept)",
                      why.message);
}

cf_status cf_batch_task_run(const cf_batch_manifest *m, size_t index, const char *library,
                            const cf_batch_task_options *options, cf_batch_fault *fault,
                            cf_error *err) {
  *fault = CF_BATCH_FAULT_RUN;
  if (index >= m->count)
    return cf_error_set(err, CF_ERANGE, "task %zu: the manifest has %zu captures", index, m->count);
  task t = {.entry = &m->entries[index],
            .library = library,
            .viewer_bundle = options->viewer_bundle,
            .log = json_array()};
  if (!t.log) return cf_error_set(err, CF_ENOMEM, "out of memory");
  t.start_wall = cf_now_seconds();
  double cpu0 = cpu_seconds();
  utc_now(t.started);
  cf_status s = cf_batch_entry_key(t.entry, t.key, err);
  if (s == CF_OK) s = batch_tmp_path(library, t.entry->name, getpid(), t.tmp, sizeof t.tmp, err);
  if (s == CF_OK) s = fresh_tmp(&t, err);
  if (s != CF_OK) {
    json_decref(t.log);
    return s;
  }
  task_step step = STEP_LOAD;
  cf_status status = work(&t, options->threads, &step, err);
  int input = status != CF_OK && input_fault(step, status);
  char have[CF_BATCH_KEY_SIZE];
  if (status != CF_OK && !input &&
      cf_batch_entry_state(library, t.entry->name, have) == CF_BATCH_FITTED) {
    json_decref(t.log);
    return keep_entry(&t, status, err);
  }
  cf_error task_error = *err;
  if (status != CF_OK) {
    task_log(&t, "error: %s", err->message);
    s = fresh_tmp(&t, err);
  }
  if (s == CF_OK)
    s = record(&t, options->threads, cpu0, status == CF_OK ? NULL : task_error.message, !input,
               err);
  if (s == CF_OK) s = batch_replace_entry(library, t.entry->name, t.tmp, err);
  if (s != CF_OK) batch_remove_tree(t.tmp);
  json_decref(t.log);
  if (s != CF_OK && status != CF_OK) {
    cf_error why = *err;
    cf_error_set(err, CF_EIO, "%s; then the entry could not be recorded: %s", task_error.message,
                 why.message);
  }
  if (s != CF_OK) return CF_EIO; /* the library not written: a failure while running */
  *fault = status == CF_OK ? CF_BATCH_FAULT_NONE
           : input         ? CF_BATCH_FAULT_INPUT
                           : CF_BATCH_FAULT_RUN;
  if (status != CF_OK) *err = task_error;
  return status;
}
