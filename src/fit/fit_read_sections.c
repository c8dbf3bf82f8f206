/* fit.json's sections read back (fit_read_internal.h): the capture, the
 * derived values, the scale, correlations, held parameters, noise and loss,
 * residuals, light gains, the solver, the starts, timing and footprints. */
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

/* capture.path is relative to fit.json's folder; a fit.json written before
 * that rule has it relative to the folder where clayfit fit ran, taken as
 * written (relative to the current folder) when only that exists. */
static cf_status locate_capture(const char *written, const char *fit_path, const json_at *at,
                                cf_fit_file *f, cf_error *err) {
  if (strlen(written) >= sizeof f->capture_written)
    return json_fail(at, err, CF_ERANGE, "the path is longer than %zu bytes",
                     sizeof f->capture_written - 1);
  memcpy(f->capture_written, written, strlen(written) + 1);
  char folder[4096];
  TRY(cf_path_dirname(fit_path, folder, sizeof folder, err));
  TRY(cf_path_join(folder, written, f->capture_path, sizeof f->capture_path, err));
  f->capture_found = cf_path_exists(f->capture_path);
  if (!f->capture_found && written[0] != '/' && cf_path_exists(written)) {
    memcpy(f->capture_path, written, strlen(written) + 1);
    f->capture_found = 1;
  }
  return CF_OK;
}

cf_status fit_read_capture(const json_t *root, const json_at *at, const char *fit_path,
                           cf_fit_file *f, cf_error *err) {
  const json_t *obj;
  TRY(json_get_object(root, at, "capture", 1, &obj, NULL, err));
  json_at here = json_member_at(at, "capture");
  static const char *const known[] = {"path",       "name",      "images", "observations",
                                      "radiometry", "reference", NULL};
  TRY(json_check_keys(obj, &here, known, err));
  const char *path;
  TRY(json_get_string(obj, &here, "path", 1, &path, NULL, err));
  json_at p = json_member_at(&here, "path");
  TRY(locate_capture(path, fit_path, &p, f, err));
  TRY(fit_read_text(obj, &here, "name", f->capture_name, sizeof f->capture_name, err));
  TRY(fit_read_count(obj, &here, "images", &f->capture_images, err));
  TRY(fit_read_count(obj, &here, "observations", &f->capture_observations, err));
  static const char *const radiometry[] = {"absolute", "relative", "from_reference", NULL};
  int r;
  TRY(json_get_choice(obj, &here, "radiometry", 1, radiometry, &r, NULL, err));
  snprintf(f->radiometry, sizeof f->radiometry, "%s", radiometry[r]);
  const json_t *ref;
  int found = 0;
  TRY(json_get_object(obj, &here, "reference", 0, &ref, &found, err));
  if (found != (r == 2)) {
    return json_fail(&here, err, CF_EPARSE,
                     "'reference' must be present exactly when the radiometry is from_reference");
  }
  if (found) {
    json_at rh = json_member_at(&here, "reference");
    static const char *const rkeys[] = {"scale", "spread", "pixels", NULL};
    TRY(json_check_keys(ref, &rh, rkeys, err));
    double x;
    long long n;
    TRY(json_get_number(ref, &rh, "scale", 1, 1e-300, HUGE_NUMBER, &x, NULL, err));
    TRY(fit_read_nonneg(ref, &rh, "spread", &x, err));
    TRY(json_get_integer(ref, &rh, "pixels", 1, 16, (long long)1 << 53, &n, NULL, err));
  }
  return CF_OK;
}

cf_status fit_read_derived(const json_t *root, const json_at *at, cf_fit_file *f, cf_error *err) {
  const json_t *obj;
  TRY(fit_read_member(root, at, "derived", &obj, err));
  json_at here = json_member_at(at, "derived");
  f->density = NAN;
  for (int c = 0; c < 3; ++c) f->absorption[c] = NAN;
  if (json_is_null(obj)) {
    if (cf_model_info_get(f->result.model)->ggx_twin == CF_MODEL_CLAY)
      return json_fail(&here, err, CF_EPARSE,
                       "models M4 and M4T need the film's density and absorption");
    return CF_OK;
  }
  if (!json_is_object(obj))
    return json_fail(&here, err, CF_EPARSE, "expected an object or null, got %s",
                     json_type_name(obj));
  if (cf_model_info_get(f->result.model)->ggx_twin != CF_MODEL_CLAY)
    return json_fail(&here, err, CF_EPARSE, "must be null for a model other than M4 and M4T");
  static const char *const known[] = {"density", "convention", "absorption", NULL};
  TRY(json_check_keys(obj, &here, known, err));
  TRY(fit_read_nonneg(obj, &here, "density", &f->density, err));
  TRY(fit_read_text(obj, &here, "convention", f->density_convention, sizeof f->density_convention,
                    err));
  const json_t *absorption;
  TRY(fit_read_member(obj, &here, "absorption", &absorption, err));
  if (json_is_string(absorption)) return CF_OK; /* undefined: τ = 0 */
  return json_get_numbers(obj, &here, "absorption", 1, 3, 0.0, HUGE_NUMBER, f->absorption, NULL,
                          err);
}

cf_status fit_read_scale(const json_t *root, const json_at *at, cf_fit_result *r, cf_error *err) {
  const json_t *obj;
  TRY(json_get_object(root, at, "scale", 1, &obj, NULL, err));
  json_at here = json_member_at(at, "scale");
  static const char *const known[] = {"value", "sd", "fitted", NULL};
  TRY(json_check_keys(obj, &here, known, err));
  TRY(json_get_number(obj, &here, "value", 1, 1e-300, HUGE_NUMBER, &r->scale, NULL, err));
  TRY(fit_read_nonneg(obj, &here, "sd", &r->scale_sd, err));
  return json_get_bool(obj, &here, "fitted", 1, &r->scale_fitted, NULL, err);
}

static cf_status slot_from_name(cf_model_id model, const json_t *value, const json_at *at,
                                int *slot, cf_error *err) {
  const char *text;
  TRY(json_as_string(value, at, &text, err));
  const cf_model_info *m = cf_model_info_get(model);
  for (int k = 0; k < m->dim; ++k) {
    char name[48];
    if (strcmp(cf_model_slot_name(model, k, name, sizeof name), text) == 0) {
      *slot = k;
      return CF_OK;
    }
  }
  return json_fail(at, err, CF_EPARSE, "'%s' is not a slot of model %s", text, m->code);
}

cf_status fit_read_correlation(const json_t *root, const json_at *at, cf_fit_result *r,
                               cf_error *err) {
  const json_t *obj, *names, *matrix;
  TRY(json_get_object(root, at, "correlation", 1, &obj, NULL, err));
  json_at here = json_member_at(at, "correlation");
  static const char *const known[] = {"parameters", "matrix", NULL};
  TRY(json_check_keys(obj, &here, known, err));
  TRY(json_get_array(obj, &here, "parameters", 1, &names, NULL, err));
  TRY(json_get_array(obj, &here, "matrix", 1, &matrix, NULL, err));
  json_at nh = json_member_at(&here, "parameters"), mh = json_member_at(&here, "matrix");
  size_t n = json_array_size(names);
  if (n > (size_t)cf_model_info_get(r->model)->dim)
    return json_fail(&nh, err, CF_EPARSE, "more slots (%zu) than the model has", n);
  if (json_array_size(matrix) != n)
    return json_fail(&mh, err, CF_EPARSE, "expected %zu rows, got %zu", n, json_array_size(matrix));
  r->free_count = (int)n;
  for (size_t a = 0; a < n; ++a) {
    json_at element = json_element_at(&nh, a);
    TRY(slot_from_name(r->model, json_array_get(names, a), &element, &r->free_slots[a], err));
    for (size_t b = 0; b < a; ++b)
      if (r->free_slots[b] == r->free_slots[a])
        return json_fail(&element, err, CF_EPARSE, "the slot is listed twice");
    json_at row_at = json_element_at(&mh, a);
    const json_t *row = json_array_get(matrix, a);
    if (!json_is_array(row) || json_array_size(row) != n)
      return json_fail(&row_at, err, CF_EPARSE, "expected an array of %zu numbers", n);
    for (size_t b = 0; b < n; ++b) {
      json_at cell = json_element_at(&row_at, b);
      TRY(json_as_number(json_array_get(row, b), &cell, -1.000001, 1.000001,
                         &r->correlation[a * n + b], err));
    }
  }
  return CF_OK;
}

/* held, not_constrained, at_bound: their types (the statuses are read from
 * params). */
cf_status fit_read_held(const json_t *root, const json_at *at, cf_fit_result *r, cf_error *err) {
  const json_t *held;
  TRY(json_get_array(root, at, "held", 1, &held, NULL, err));
  json_at hh = json_member_at(at, "held");
  for (size_t i = 0; i < json_array_size(held); ++i) {
    json_at e = json_element_at(&hh, i);
    const json_t *item = json_array_get(held, i);
    if (!json_is_object(item))
      return json_fail(&e, err, CF_EPARSE, "expected an object, got %s", json_type_name(item));
    static const char *const known[] = {"name", "value", "why", NULL};
    TRY(json_check_keys(item, &e, known, err));
    int slot;
    double value;
    cf_param_status why;
    const json_t *name;
    TRY(fit_read_member(item, &e, "name", &name, err));
    json_at nh = json_member_at(&e, "name");
    TRY(slot_from_name(r->model, name, &nh, &slot, err));
    TRY(json_get_number(item, &e, "value", 1, -HUGE_NUMBER, HUGE_NUMBER, &value, NULL, err));
    const json_t *w;
    TRY(fit_read_member(item, &e, "why", &w, err));
    json_at wh = json_member_at(&e, "why");
    TRY(fit_read_status_name(w, &wh, &why, err));
  }
  const char *lists[] = {"not_constrained", "at_bound"};
  for (int l = 0; l < 2; ++l) {
    const json_t *array;
    TRY(json_get_array(root, at, lists[l], 1, &array, NULL, err));
    json_at lh = json_member_at(at, lists[l]);
    for (size_t i = 0; i < json_array_size(array); ++i) {
      json_at e = json_element_at(&lh, i);
      int slot;
      TRY(slot_from_name(r->model, json_array_get(array, i), &e, &slot, err));
    }
  }
  return CF_OK;
}

cf_status fit_read_loss(const json_t *obj, const json_at *at, char *type, size_t size,
                        double *scale, cf_error *err) {
  static const char *const known[] = {"type", "scale_sigma", NULL};
  TRY(json_check_keys(obj, at, known, err));
  static const char *const types[] = {"none", "huber", "cauchy", NULL};
  int t;
  TRY(json_get_choice(obj, at, "type", 1, types, &t, NULL, err));
  if (type) snprintf(type, size, "%s", types[t]);
  return json_get_number(obj, at, "scale_sigma", 1, 1e-300, HUGE_NUMBER, scale, NULL, err);
}

cf_status fit_read_noise_loss(const json_t *root, const json_at *at, cf_fit_file *f,
                              cf_error *err) {
  const json_t *obj;
  TRY(json_get_object(root, at, "noise", 1, &obj, NULL, err));
  json_at here = json_member_at(at, "noise");
  static const char *const known[] = {"model", "sigma", NULL};
  TRY(json_check_keys(obj, &here, known, err));
  static const char *const models[] = {"capture", "estimated from the residuals", NULL};
  int m;
  TRY(json_get_choice(obj, &here, "model", 1, models, &m, NULL, err));
  TRY(fit_read_nonneg(obj, &here, "sigma", &f->result.sigma, err));
  TRY(json_get_object(root, at, "loss", 1, &obj, NULL, err));
  here = json_member_at(at, "loss");
  return fit_read_loss(obj, &here, f->loss, sizeof f->loss, &f->loss_scale, err);
}

cf_status fit_read_residuals(const json_t *root, const json_at *at, cf_fit_result *r,
                             cf_error *err) {
  const json_t *obj, *per_image, *cores, *rest;
  TRY(json_get_object(root, at, "residuals", 1, &obj, NULL, err));
  json_at here = json_member_at(at, "residuals");
  static const char *const known[] = {"count",         "censored",  "rejected",        "rmse",
                                      "relative_rmse", "per_image", "highlight_cores", NULL};
  TRY(json_check_keys(obj, &here, known, err));
  TRY(fit_read_count(obj, &here, "count", &r->residuals, err));
  TRY(fit_read_count(obj, &here, "censored", &r->censored, err));
  TRY(fit_read_count(obj, &here, "rejected", &r->rejected, err));
  TRY(fit_read_nonneg(obj, &here, "rmse", &r->rmse, err));
  TRY(fit_read_nonneg(obj, &here, "relative_rmse", &r->relative_rmse, err));
  TRY(json_get_array(obj, &here, "per_image", 1, &per_image, NULL, err));
  json_at ph = json_member_at(&here, "per_image");
  size_t n = json_array_size(per_image);
  r->images = n;
  r->exposures = calloc(n ? n : 1, sizeof *r->exposures);
  r->image_rmse = calloc(n ? n : 1, sizeof *r->image_rmse);
  r->image_relative_rmse = calloc(n ? n : 1, sizeof *r->image_relative_rmse);
  r->exposure_sd = calloc(n ? n : 1, sizeof *r->exposure_sd); /* 0 in older files */
  r->white_balance = malloc(3 * (n ? n : 1) * sizeof *r->white_balance);
  r->white_balance_sd = calloc(3 * (n ? n : 1), sizeof *r->white_balance_sd);
  if (!r->exposures || !r->image_rmse || !r->image_relative_rmse || !r->exposure_sd ||
      !r->white_balance || !r->white_balance_sd)
    return cf_error_set(err, CF_ENOMEM, "%s: out of memory for %zu images", here.file, n);
  for (size_t k = 0; k < n; ++k) {
    json_at e = json_element_at(&ph, k);
    const json_t *item = json_array_get(per_image, k);
    if (!json_is_object(item))
      return json_fail(&e, err, CF_EPARSE, "expected an object, got %s", json_type_name(item));
    static const char *const ikeys[] = {
        "name",        "rmse",          "relative_rmse",    "exposure", "not_radiance",
        "exposure_sd", "white_balance", "white_balance_sd", NULL};
    TRY(json_check_keys(item, &e, ikeys, err));
    const char *name;
    TRY(json_get_string(item, &e, "name", 1, &name, NULL, err));
    TRY(fit_read_nonneg(item, &e, "rmse", &r->image_rmse[k], err));
    TRY(fit_read_nonneg(item, &e, "relative_rmse", &r->image_relative_rmse[k], err));
    TRY(json_get_number(item, &e, "exposure", 1, 1e-300, HUGE_NUMBER, &r->exposures[k], NULL, err));
    TRY(json_get_number(item, &e, "exposure_sd", 0, 0.0, HUGE_NUMBER, &r->exposure_sd[k], NULL,
                        err));
    int balanced = 0; /* (1 each when absent: not fitted) */
    r->white_balance[3 * k] = r->white_balance[3 * k + 1] = r->white_balance[3 * k + 2] = 1.0;
    TRY(json_get_numbers(item, &e, "white_balance", 0, 3, 1e-300, HUGE_NUMBER,
                         r->white_balance + 3 * k, &balanced, err));
    TRY(json_get_numbers(item, &e, "white_balance_sd", balanced, 3, 0.0, HUGE_NUMBER,
                         r->white_balance_sd + 3 * k, NULL, err));
    r->white_balance_fitted |= balanced;
  }
  TRY(json_get_object(obj, &here, "highlight_cores", 1, &cores, NULL, err));
  json_at ch = json_member_at(&here, "highlight_cores");
  static const char *const ckeys[] = {"radius_px", "count",   "rmse", "relative_rmse",
                                      "rest",      "meaning", NULL};
  TRY(json_check_keys(cores, &ch, ckeys, err));
  double radius;
  const char *meaning;
  TRY(json_get_number(cores, &ch, "radius_px", 1, 1e-300, HUGE_NUMBER, &radius, NULL, err));
  TRY(fit_read_count(cores, &ch, "count", &r->core_residuals, err));
  TRY(fit_read_nonneg(cores, &ch, "rmse", &r->core_rmse, err));
  TRY(fit_read_nonneg(cores, &ch, "relative_rmse", &r->core_relative_rmse, err));
  TRY(json_get_string(cores, &ch, "meaning", 1, &meaning, NULL, err));
  TRY(json_get_object(cores, &ch, "rest", 1, &rest, NULL, err));
  json_at rh = json_member_at(&ch, "rest");
  static const char *const rkeys[] = {"count", "rmse", "relative_rmse", NULL};
  TRY(json_check_keys(rest, &rh, rkeys, err));
  size_t rest_count;
  TRY(fit_read_count(rest, &rh, "count", &rest_count, err));
  TRY(fit_read_nonneg(rest, &rh, "rmse", &r->rest_rmse, err));
  return fit_read_nonneg(rest, &rh, "relative_rmse", &r->rest_relative_rmse, err);
}

/* The gains per light (light_gains; absent: none), each light's name,
 * gain and sd. */
cf_status fit_read_light_gains(const json_t *root, const json_at *at, cf_fit_result *r,
                               cf_error *err) {
  const json_t *lights;
  int found = 0;
  TRY(json_get_array(root, at, "light_gains", 0, &lights, &found, err));
  if (!found) return CF_OK;
  json_at here = json_member_at(at, "light_gains");
  size_t n = json_array_size(lights);
  if (n < 2) return json_fail(&here, err, CF_EPARSE, "needs 2 lights or more, has %zu", n);
  r->light_gains = malloc(n * sizeof *r->light_gains);
  r->light_gains_sd = malloc(n * sizeof *r->light_gains_sd);
  r->light_names = malloc(n * sizeof *r->light_names);
  if (!r->light_gains || !r->light_gains_sd || !r->light_names)
    return cf_error_set(err, CF_ENOMEM, "%s: out of memory for %zu lights", here.file, n);
  r->light_count = n;
  static const char *const keys[] = {"light", "gain", "sd", NULL};
  for (size_t l = 0; l < n; ++l) {
    json_at e = json_element_at(&here, l);
    const json_t *item = json_array_get(lights, l);
    if (!json_is_object(item))
      return json_fail(&e, err, CF_EPARSE, "expected an object, got %s", json_type_name(item));
    TRY(json_check_keys(item, &e, keys, err));
    TRY(fit_read_text(item, &e, "light", r->light_names[l], sizeof r->light_names[l], err));
    TRY(json_get_number(item, &e, "gain", 1, 1e-300, HUGE_NUMBER, &r->light_gains[l], NULL, err));
    TRY(fit_read_nonneg(item, &e, "sd", &r->light_gains_sd[l], err));
  }
  return CF_OK;
}

cf_status fit_read_solver(const json_t *root, const json_at *at, cf_fit_result *r, cf_error *err) {
  const json_t *obj;
  TRY(json_get_object(root, at, "solver", 1, &obj, NULL, err));
  json_at here = json_member_at(at, "solver");
  static const char *const known[] = {"iterations", "solves", "termination", "seconds",
                                      "final_cost", "trace",  NULL};
  TRY(json_check_keys(obj, &here, known, err));
  const json_t *trace;
  int has_trace = 0;
  TRY(json_get_array(obj, &here, "trace", 0, &trace, &has_trace, err));
  r->trace_count = 0;
  if (has_trace) { /* the convergence trace: at most CF_FIT_MAX_TRACE costs */
    json_at tat = json_member_at(&here, "trace");
    if (json_array_size(trace) > CF_FIT_MAX_TRACE)
      return json_fail(&tat, err, CF_EPARSE, "%zu costs; at most %d", json_array_size(trace),
                       CF_FIT_MAX_TRACE);
    for (size_t i = 0; i < json_array_size(trace); ++i) {
      json_at eat = json_element_at(&tat, i);
      TRY(json_as_number(json_array_get(trace, i), &eat, 0.0, 1e300, &r->trace[i], err));
      r->trace_count = (int)i + 1;
    }
  }
  TRY(fit_read_int(obj, &here, "iterations", 0, 1 << 30, &r->iterations, err));
  TRY(fit_read_int(obj, &here, "solves", 0, 1 << 30, &r->solves, err));
  TRY(fit_read_text(obj, &here, "termination", r->termination, sizeof r->termination, err));
  TRY(fit_read_nonneg(obj, &here, "seconds", &r->solve_seconds, err));
  return fit_read_nonneg(obj, &here, "final_cost", &r->cost, err);
}

cf_status fit_read_starts(const json_t *root, const json_at *at, cf_fit_result *r, cf_error *err) {
  const json_t *starts;
  TRY(json_get_array(root, at, "starts", 1, &starts, NULL, err));
  json_at sh = json_member_at(at, "starts");
  size_t n = json_array_size(starts);
  if (n > CF_FIT_MAX_STARTS)
    return json_fail(&sh, err, CF_ERANGE, "%zu starts, at most %d", n, CF_FIT_MAX_STARTS);
  r->starts = (int)n;
  for (size_t i = 0; i < n; ++i) {
    json_at e = json_element_at(&sh, i);
    const json_t *item = json_array_get(starts, i), *values;
    if (!json_is_object(item))
      return json_fail(&e, err, CF_EPARSE, "expected an object, got %s", json_type_name(item));
    static const char *const known[] = {"start", "end", "cost", "iterations", "stopped", NULL};
    TRY(json_check_keys(item, &e, known, err));
    cf_fit_start *s = &r->start[i];
    TRY(json_get_object(item, &e, "start", 1, &values, NULL, err));
    json_at vh = json_member_at(&e, "start");
    TRY(fit_read_values_by_name(values, &vh, r->model, s->start, err));
    TRY(json_get_object(item, &e, "end", 1, &values, NULL, err));
    vh = json_member_at(&e, "end");
    TRY(fit_read_values_by_name(values, &vh, r->model, s->end, err));
    TRY(json_get_number(item, &e, "cost", 1, -HUGE_NUMBER, HUGE_NUMBER, &s->cost, NULL, err));
    TRY(fit_read_int(item, &e, "iterations", 0, 1 << 30, &s->iterations, err));
    TRY(json_get_bool(item, &e, "stopped", 1, &s->stopped, NULL, err));
  }
  TRY(fit_read_int(root, at, "best_start", 0, n ? (int)n - 1 : 0, &r->best_start, err));
  const json_t *warnings;
  TRY(json_get_array(root, at, "warnings", 1, &warnings, NULL, err));
  json_at wh = json_member_at(at, "warnings");
  n = json_array_size(warnings);
  if (n > CF_FIT_MAX_WARNINGS)
    return json_fail(&wh, err, CF_ERANGE, "%zu warnings, at most %d", n, CF_FIT_MAX_WARNINGS);
  r->warning_count = (int)n;
  for (size_t i = 0; i < n; ++i) {
    json_at e = json_element_at(&wh, i);
    const char *text;
    TRY(json_as_string(json_array_get(warnings, i), &e, &text, err));
    if (strlen(text) >= sizeof r->warnings[i])
      return json_fail(&e, err, CF_ERANGE, "the warning is longer than %zu bytes",
                       sizeof r->warnings[i] - 1);
    memcpy(r->warnings[i], text, strlen(text) + 1);
  }
  return CF_OK;
}

cf_status fit_read_timing(const json_t *root, const json_at *at, cf_fit_result *r, cf_error *err) {
  const json_t *obj, *stages;
  TRY(json_get_object(root, at, "timing", 1, &obj, NULL, err));
  json_at here = json_member_at(at, "timing");
  static const char *const known[] = {"load_s", "fit_s", "total_s", "stages", "choice_s", NULL};
  TRY(json_check_keys(obj, &here, known, err));
  double x;
  TRY(fit_read_nonneg(obj, &here, "load_s", &x, err));
  TRY(fit_read_nonneg(obj, &here, "fit_s", &x, err));
  TRY(fit_read_nonneg(obj, &here, "total_s", &x, err));
  TRY(fit_read_nonneg(obj, &here, "choice_s", &x, err));
  TRY(json_get_object(obj, &here, "stages", 1, &stages, NULL, err));
  json_at sh = json_member_at(&here, "stages");
  const char *names[CF_FIT_STAGE_COUNT + 1];
  for (int i = 0; i < CF_FIT_STAGE_COUNT; ++i) names[i] = cf_fit_stage_name((cf_fit_stage)i);
  names[CF_FIT_STAGE_COUNT] = NULL;
  TRY(json_check_keys(stages, &sh, names, err));
  for (int i = 0; i < CF_FIT_STAGE_COUNT; ++i)
    TRY(fit_read_nonneg(stages, &sh, names[i], &r->stage_seconds[i], err));
  return CF_OK;
}

cf_status fit_read_footprint(const json_t *root, const json_at *at, cf_fit_file *f, cf_error *err) {
  const json_t *obj;
  TRY(json_get_object(root, at, "footprint", 1, &obj, NULL, err));
  json_at here = json_member_at(at, "footprint");
  static const char *const known[] = {
      "mode",    "samples_per_side",     "tolerance", "observations",
      "samples", "max_samples_per_side", "meaning",   NULL};
  TRY(json_check_keys(obj, &here, known, err));
  static const char *const modes[] = {"auto", "centre", "fixed", NULL};
  int mode, per_side;
  TRY(json_get_choice(obj, &here, "mode", 1, modes, &mode, NULL, err));
  TRY(fit_read_int(obj, &here, "samples_per_side", 0, CF_FIT_FOOTPRINT_MAX_SAMPLES, &per_side,
                   err));
  if ((mode == 2) != (per_side >= 2)) {
    json_at p = json_member_at(&here, "samples_per_side");
    return json_fail(&p, err, CF_EPARSE, "%d: expected 2 to %d with mode fixed, else 0", per_side,
                     CF_FIT_FOOTPRINT_MAX_SAMPLES);
  }
  f->footprint = mode == 0 ? 0 : mode == 1 ? 1 : per_side;
  TRY(json_get_number(obj, &here, "tolerance", 1, 1e-300, HUGE_NUMBER, &f->footprint_tolerance,
                      NULL, err));
  TRY(fit_read_count(obj, &here, "observations", &f->result.footprint_observations, err));
  TRY(fit_read_count(obj, &here, "samples", &f->result.footprint_samples, err));
  TRY(fit_read_int(obj, &here, "max_samples_per_side", 1, 1 << 20, &f->result.footprint_max, err));
  const char *meaning;
  return json_get_string(obj, &here, "meaning", 1, &meaning, NULL, err);
}

/* A response written before the curve (clayfit 0.x up to issue 17): one
 * exponent γ with its sd, the power x^γ, which is the curve with every
 * slope γ and every covariance entry sd² (docs/fitting.md). */