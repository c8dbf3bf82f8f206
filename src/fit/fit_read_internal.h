/* fit.json's readers shared by fit_read.c, fit_read_sections.c and
 * fit_read_choice.c: members by type and range, parameters, and one reader
 * per section of the file. Private to clayfit_fit_read. */
#ifndef CLAYFIT_FIT_READ_INTERNAL_H
#define CLAYFIT_FIT_READ_INTERNAL_H

#include <jansson.h>

#include "clayfit/fit_file.h"
#include "core/json_reader.h"

#define HUGE_NUMBER 1e308

/* Shorthands: every call names the object, its location and the key. */
#define TRY(call)               \
  do {                          \
    cf_status s_ = (call);      \
    if (s_ != CF_OK) return s_; \
  } while (0)

/* A string member copied into a fixed buffer; too long is an error, not a
 * silent truncation. */
cf_status fit_read_text(const json_t *obj, const json_at *at, const char *key, char *out,
                        size_t size, cf_error *err);

cf_status fit_read_count(const json_t *obj, const json_at *at, const char *key, size_t *out,
                         cf_error *err);

cf_status fit_read_int(const json_t *obj, const json_at *at, const char *key, int lo, int hi,
                       int *out, cf_error *err);

cf_status fit_read_nonneg(const json_t *obj, const json_at *at, const char *key, double *out,
                          cf_error *err);

cf_status fit_read_member(const json_t *obj, const json_at *at, const char *key, const json_t **out,
                          cf_error *err);

cf_status fit_read_status_name(const json_t *value, const json_at *at, cf_param_status *out,
                               cf_error *err);

/* `params`: every parameter of the model, nothing else. */
cf_status fit_read_params(const json_t *obj, const json_at *at, cf_model_id model, double *params,
                          double *sd, cf_param_status *status, cf_error *err);

/* Parameters by name (a start and where it ended): every one of the model. */
cf_status fit_read_values_by_name(const json_t *obj, const json_at *at, cf_model_id model,
                                  double *params, cf_error *err);

cf_status fit_read_capture(const json_t *root, const json_at *at, const char *fit_path,
                           cf_fit_file *f, cf_error *err);

cf_status fit_read_derived(const json_t *root, const json_at *at, cf_fit_file *f, cf_error *err);

cf_status fit_read_scale(const json_t *root, const json_at *at, cf_fit_result *r, cf_error *err);

cf_status fit_read_correlation(const json_t *root, const json_at *at, cf_fit_result *r,
                               cf_error *err);

/* held, not_constrained, at_bound: their types (the statuses are read from
 * params). */
cf_status fit_read_held(const json_t *root, const json_at *at, cf_fit_result *r, cf_error *err);

cf_status fit_read_loss(const json_t *obj, const json_at *at, char *type, size_t size,
                        double *scale, cf_error *err);

cf_status fit_read_noise_loss(const json_t *root, const json_at *at, cf_fit_file *f, cf_error *err);

cf_status fit_read_residuals(const json_t *root, const json_at *at, cf_fit_result *r,
                             cf_error *err);

/* The gains per light (light_gains; absent: none), each light's name,
 * gain and sd. */
cf_status fit_read_light_gains(const json_t *root, const json_at *at, cf_fit_result *r,
                               cf_error *err);

cf_status fit_read_solver(const json_t *root, const json_at *at, cf_fit_result *r, cf_error *err);

cf_status fit_read_starts(const json_t *root, const json_at *at, cf_fit_result *r, cf_error *err);

cf_status fit_read_timing(const json_t *root, const json_at *at, cf_fit_result *r, cf_error *err);

cf_status fit_read_footprint(const json_t *root, const json_at *at, cf_fit_file *f, cf_error *err);

cf_status fit_read_response(const json_t *root, const json_at *at, cf_fit_result *r, cf_error *err);

/* The optional JPEG coding block (fit_json.c's jpeg_coding_json). */
cf_status fit_read_jpeg_coding(const json_t *root, const json_at *at, cf_fit_result *r,
                               cf_error *err);

cf_status fit_read_sample(const json_t *root, const json_at *at, cf_fit_result *r, cf_error *err);

cf_status fit_read_choice(const json_t *root, const json_at *at, cf_model_id model, cf_error *err);

#endif /* CLAYFIT_FIT_READ_INTERNAL_H */
