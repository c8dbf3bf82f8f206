/* fit.json's response curve, JPEG coding, sample and model choice read
 * back (fit_read_internal.h). */
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

static cf_status read_response_exponent(const json_t *obj, const json_at *here, cf_fit_result *r,
                                        cf_error *err) {
  static const char *const known[] = {"value", "sd", "fitted", "meaning", NULL};
  TRY(json_check_keys(obj, here, known, err));
  double gamma, sd;
  TRY(json_get_number(obj, here, "value", 1, 0.25, 4.0, &gamma, NULL, err));
  TRY(fit_read_nonneg(obj, here, "sd", &sd, err));
  for (int i = 0; i < CF_RESPONSE_MODEL_KNOTS; ++i) {
    r->response[i] = gamma;
    for (int j = 0; j < CF_RESPONSE_MODEL_KNOTS; ++j)
      r->response_covariance[i * CF_RESPONSE_MODEL_KNOTS + j] = sd * sd;
  }
  return CF_OK;
}

/* The slopes' covariance: K rows of K finite numbers, a diagonal >= 0. */
static cf_status read_response_covariance(const json_t *obj, const json_at *here, cf_fit_result *r,
                                          cf_error *err) {
  enum { K = CF_RESPONSE_MODEL_KNOTS };
  const json_t *rows;
  TRY(json_get_array(obj, here, "covariance", 1, &rows, NULL, err));
  json_at at = json_member_at(here, "covariance");
  if (json_array_size(rows) != K)
    return json_fail(&at, err, CF_EPARSE, "expected %d rows, got %zu", K, json_array_size(rows));
  for (size_t a = 0; a < K; ++a) {
    json_at row_at = json_element_at(&at, a);
    const json_t *row = json_array_get(rows, a);
    if (!json_is_array(row) || json_array_size(row) != K)
      return json_fail(&row_at, err, CF_EPARSE, "expected an array of %d numbers", K);
    for (size_t b = 0; b < K; ++b) {
      json_at cell = json_element_at(&row_at, b);
      TRY(json_as_number(json_array_get(row, b), &cell, a == b ? 0.0 : -HUGE_NUMBER, HUGE_NUMBER,
                         &r->response_covariance[a * K + b], err));
    }
  }
  return CF_OK;
}

/* The response curve: its model (the one this clayfit fits, at its
 * knots), slopes and covariance; the sds and the sampled curve follow from
 * them and are checked for their shape only. */
static cf_status read_response_curve(const json_t *obj, const json_at *here, cf_fit_result *r,
                                     cf_error *err) {
  enum { K = CF_RESPONSE_MODEL_KNOTS };
  static const char *const known[] = {"fitted",     "model", "knots",   "slopes", "slopes_sd",
                                      "covariance", "curve", "meaning", NULL};
  TRY(json_check_keys(obj, here, known, err));
  static const char *const models[] = {CF_RESPONSE_MODEL_NAME, NULL};
  int model;
  TRY(json_get_choice(obj, here, "model", 1, models, &model, NULL, err));
  double knots[K], sd[K];
  TRY(json_get_numbers(obj, here, "knots", 1, K, 0.0, 1.0, knots, NULL, err));
  for (int j = 0; j < K; ++j)
    if (fabs(knots[j] - cf_response_model_knot(j)) > 1e-12) {
      json_at at = json_member_at(here, "knots");
      return json_fail(&at, err, CF_EPARSE, "knot %d is %.17g, not this model's %.17g", j, knots[j],
                       cf_response_model_knot(j));
    }
  TRY(json_get_numbers(obj, here, "slopes", 1, K, CF_RESPONSE_MODEL_SLOPE_LOWER,
                       CF_RESPONSE_MODEL_SLOPE_UPPER, r->response, NULL, err));
  TRY(json_get_numbers(obj, here, "slopes_sd", 1, K, 0.0, HUGE_NUMBER, sd, NULL, err));
  TRY(read_response_covariance(obj, here, r, err));
  const json_t *curve;
  return json_get_array(obj, here, "curve", 1, &curve, NULL, err);
}

cf_status fit_read_response(const json_t *root, const json_at *at, cf_fit_result *r,
                            cf_error *err) {
  const json_t *obj;
  TRY(json_get_object(root, at, "response", 1, &obj, NULL, err));
  json_at here = json_member_at(at, "response");
  int is_curve = json_object_get(obj, "slopes") != NULL;
  TRY(is_curve ? read_response_curve(obj, &here, r, err)
               : read_response_exponent(obj, &here, r, err));
  TRY(json_get_bool(obj, &here, "fitted", 1, &r->response_fitted, NULL, err));
  const char *meaning;
  return json_get_string(obj, &here, "meaning", 1, &meaning, NULL, err);
}

/* The pixel budget's sample, or null. */
/* The optional JPEG coding block (fit_json.c's jpeg_coding_json). */
cf_status fit_read_jpeg_coding(const json_t *root, const json_at *at, cf_fit_result *r,
                               cf_error *err) {
  const json_t *obj;
  int found;
  TRY(json_get_object(root, at, "jpeg_coding", 0, &obj, &found, err));
  if (!found) return CF_OK;
  json_at here = json_member_at(at, "jpeg_coding");
  static const char *const known[] = {"images",          "draws",   "bias_rms_codes",
                                      "bias_mean_codes", "meaning", NULL};
  TRY(json_check_keys(obj, &here, known, err));
  int draws;
  TRY(fit_read_int(obj, &here, "images", 1, 1 << 30, &r->jpeg_images, err));
  TRY(fit_read_int(obj, &here, "draws", 1, 1 << 20, &draws, err));
  TRY(json_get_number(obj, &here, "bias_rms_codes", 1, 0.0, 255.0, &r->jpeg_bias_rms, NULL, err));
  TRY(json_get_numbers(obj, &here, "bias_mean_codes", 1, 3, -255.0, 255.0, r->jpeg_bias_mean, NULL,
                       err));
  const char *meaning;
  return json_get_string(obj, &here, "meaning", 1, &meaning, NULL, err);
}

cf_status fit_read_sample(const json_t *root, const json_at *at, cf_fit_result *r, cf_error *err) {
  const json_t *obj;
  TRY(fit_read_member(root, at, "sample", &obj, err));
  json_at here = json_member_at(at, "sample");
  if (json_is_null(obj)) return CF_OK;
  if (!json_is_object(obj))
    return json_fail(&here, err, CF_EPARSE, "expected an object or null, got %s",
                     json_type_name(obj));
  static const char *const known[] = {"sampling", "observations", "population", "meaning", NULL};
  TRY(json_check_keys(obj, &here, known, err));
  static const char *const samplings[] = {"uniform", "stratified", "importance", NULL};
  int sampling;
  TRY(json_get_choice(obj, &here, "sampling", 1, samplings, &sampling, NULL, err));
  r->sampling = (cf_sampling)sampling;
  TRY(fit_read_count(obj, &here, "observations", &r->sample_count, err));
  TRY(fit_read_count(obj, &here, "population", &r->population_count, err));
  if (r->sample_count == 0 || r->sample_count >= r->population_count) {
    json_at e = json_member_at(&here, "observations");
    return json_fail(&e, err, CF_EPARSE, "%zu: expected 1 to %zu (below the population)",
                     r->sample_count, r->population_count > 0 ? r->population_count - 1 : 0);
  }
  const char *meaning;
  return json_get_string(obj, &here, "meaning", 1, &meaning, NULL, err);
}

/* One candidate of an automatic choice. */
static cf_status read_candidate(const json_t *item, const json_at *e, cf_error *err) {
  if (!json_is_object(item))
    return json_fail(e, err, CF_EPARSE, "expected an object, got %s", json_type_name(item));
  cf_model_id model;
  const char *const *codes = cf_model_codes();
  int code, ok, chosen;
  TRY(json_get_choice(item, e, "model", 1, codes, &code, NULL, err));
  model = (cf_model_id)code;
  TRY(json_get_bool(item, e, "ok", 1, &ok, NULL, err));
  TRY(json_get_bool(item, e, "chosen", 1, &chosen, NULL, err));
  double x;
  const char *note;
  TRY(fit_read_nonneg(item, e, "seconds", &x, err));
  TRY(json_get_string(item, e, "note", 1, &note, NULL, err));
  if (!ok) {
    static const char *const known[] = {"model", "ok", "chosen", "seconds", "note", NULL};
    TRY(json_check_keys(item, e, known, err));
    if (chosen) return json_fail(e, err, CF_EPARSE, "a failed candidate cannot be chosen");
    return CF_OK;
  }
  static const char *const known[] = {"model",
                                      "ok",
                                      "chosen",
                                      "params",
                                      "unknowns",
                                      "residuals",
                                      "cost",
                                      "bic",
                                      "heldout_residuals",
                                      "heldout_score",
                                      "heldout_rmse",
                                      "heldout_relative_rmse",
                                      "train_rmse",
                                      "train_relative_rmse",
                                      "seconds",
                                      "note",
                                      NULL};
  TRY(json_check_keys(item, e, known, err));
  const json_t *params;
  TRY(json_get_object(item, e, "params", 1, &params, NULL, err));
  json_at ph = json_member_at(e, "params");
  double values[CF_MAX_DIM], sd[CF_MAX_DIM];
  cf_param_status status[CF_MAX_DIM];
  TRY(fit_read_params(params, &ph, model, values, sd, status, err));
  size_t n;
  TRY(fit_read_count(item, e, "unknowns", &n, err));
  TRY(fit_read_count(item, e, "residuals", &n, err));
  TRY(fit_read_nonneg(item, e, "cost", &x, err));
  TRY(json_get_number(item, e, "bic", 1, -HUGE_NUMBER, HUGE_NUMBER, &x, NULL, err));
  TRY(fit_read_count(item, e, "heldout_residuals", &n, err));
  const char *nullable[] = {"heldout_score", "heldout_rmse", "heldout_relative_rmse"};
  for (int i = 0; i < 3; ++i) {
    const json_t *v;
    TRY(fit_read_member(item, e, nullable[i], &v, err));
    if (!json_is_null(v)) TRY(fit_read_nonneg(item, e, nullable[i], &x, err));
  }
  TRY(fit_read_nonneg(item, e, "train_rmse", &x, err));
  return fit_read_nonneg(item, e, "train_relative_rmse", &x, err);
}

cf_status fit_read_choice(const json_t *root, const json_at *at, cf_model_id model, cf_error *err) {
  const json_t *obj, *candidates;
  TRY(json_get_object(root, at, "choice", 1, &obj, NULL, err));
  json_at here = json_member_at(at, "choice");
  static const char *const modes[] = {"forced", "auto", NULL};
  const char *const *codes = cf_model_codes();
  int mode, chosen;
  TRY(json_get_choice(obj, &here, "mode", 1, modes, &mode, NULL, err));
  TRY(json_get_choice(obj, &here, "chosen", 1, codes, &chosen, NULL, err));
  if ((cf_model_id)chosen != model)
    return json_fail(&here, err, CF_EPARSE, "chosen %s is not the model %s", codes[chosen],
                     cf_model_info_get(model)->code);
  TRY(json_get_array(obj, &here, "candidates", 1, &candidates, NULL, err));
  json_at ch = json_member_at(&here, "candidates");
  if (mode == 0) {
    static const char *const known[] = {"mode", "chosen", "candidates", "reading", NULL};
    TRY(json_check_keys(obj, &here, known, err));
    if (json_array_size(candidates))
      return json_fail(&ch, err, CF_EPARSE, "a forced model has no candidates");
    const char *text; /* an M4 whose film is a lobe (issue 18; optional) */
    TRY(json_get_string(obj, &here, "reading", 0, &text, NULL, err));
    return CF_OK;
  }
  static const char *const known[] = {"mode",
                                      "chosen",
                                      "train_observations",
                                      "heldout_observations",
                                      "heldout",
                                      "sigma",
                                      "loss",
                                      "bic_margin",
                                      "heldout_margin",
                                      "heldout_guard",
                                      "seconds",
                                      "rule",
                                      "reading",
                                      "ggx_cost",
                                      "candidates",
                                      NULL};
  TRY(json_check_keys(obj, &here, known, err));
  size_t n;
  double x;
  const char *text;
  const json_t *loss;
  TRY(fit_read_count(obj, &here, "train_observations", &n, err));
  TRY(fit_read_count(obj, &here, "heldout_observations", &n, err));
  TRY(json_get_string(obj, &here, "heldout", 1, &text, NULL, err));
  TRY(fit_read_nonneg(obj, &here, "sigma", &x, err));
  TRY(json_get_object(obj, &here, "loss", 1, &loss, NULL, err));
  json_at lh = json_member_at(&here, "loss");
  TRY(fit_read_loss(loss, &lh, NULL, 0, &x, err));
  TRY(json_get_number(obj, &here, "bic_margin", 1, -HUGE_NUMBER, HUGE_NUMBER, &x, NULL, err));
  TRY(json_get_number(obj, &here, "heldout_margin", 1, -HUGE_NUMBER, HUGE_NUMBER, &x, NULL, err));
  /* (the guard and the reading since issue 18: optional in older files) */
  TRY(json_get_number(obj, &here, "heldout_guard", 0, -HUGE_NUMBER, HUGE_NUMBER, &x, NULL, err));
  TRY(fit_read_nonneg(obj, &here, "seconds", &x, err));
  TRY(json_get_string(obj, &here, "rule", 1, &text, NULL, err));
  TRY(json_get_string(obj, &here, "reading", 0, &text, NULL, err));
  const json_t *ggx_cost; /* a tailed choice only */
  int has_cost;
  TRY(json_get_object(obj, &here, "ggx_cost", 0, &ggx_cost, &has_cost, err));
  if (has_cost) {
    json_at gh = json_member_at(&here, "ggx_cost");
    static const char *const cost_keys[] = {"heldout_increase", "meaning", NULL};
    TRY(json_check_keys(ggx_cost, &gh, cost_keys, err));
    TRY(json_get_number(ggx_cost, &gh, "heldout_increase", 1, -1.0, HUGE_NUMBER, &x, NULL, err));
    TRY(json_get_string(ggx_cost, &gh, "meaning", 1, &text, NULL, err));
  }
  n = json_array_size(candidates);
  if (n < 1 || n > CF_MODEL_COUNT)
    return json_fail(&ch, err, CF_EPARSE, "expected 1 to %d candidates, got %zu", CF_MODEL_COUNT,
                     n);
  for (size_t i = 0; i < n; ++i) {
    json_at e = json_element_at(&ch, i);
    TRY(read_candidate(json_array_get(candidates, i), &e, err));
  }
  return CF_OK;
}

/* model_version: absent in files written before it existed (version 1,
 * Schlick's Fresnel); a version this clayfit does not know is refused. */