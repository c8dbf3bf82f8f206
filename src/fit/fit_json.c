/* fit.json (data_schema/fit.schema.json): a fit's result as a file. */
#include "clayfit/fit_file.h"

#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "core/file.h"
#include "core/json_reader.h"
#include "fit_jpeg.h"

static json_t *numbers(const double *x, int n) {
  json_t *array = json_array();
  for (int i = 0; i < n; ++i) json_array_append_new(array, json_real(x[i]));
  return array;
}

/* A parameter's value, or its three channels. */
static json_t *value_of(const double *x, int components) {
  return components == 3 ? numbers(x, 3) : json_real(x[0]);
}

static json_t *sd_of(const double *sd, int components) {
  if (components == 1) return json_real_or_null(sd[0]);
  json_t *array = json_array();
  for (int c = 0; c < components; ++c) json_array_append_new(array, json_real_or_null(sd[c]));
  return array;
}

/* A parameter's status: one string, or one per channel where they differ. */
static json_t *status_of(const cf_param_status *status, int components) {
  int same = 1;
  for (int c = 1; c < components; ++c) same &= status[c] == status[0];
  if (same) return json_string(cf_param_status_name(status[0]));
  json_t *array = json_array();
  for (int c = 0; c < components; ++c)
    json_array_append_new(array, json_string(cf_param_status_name(status[c])));
  return array;
}

static json_t *params_json(const cf_fit_result *r) {
  const cf_model_info *m = cf_model_info_get(r->model);
  json_t *params = json_object();
  for (int j = 0; j < m->param_count; ++j) {
    const cf_param_info *info = cf_param_info_get(m->params[j]);
    int k = m->offsets[j];
    json_object_set_new(params, info->name,
                        json_pack("{s:o, s:o, s:s, s:o, s:f, s:f, s:s}", "value",
                                  value_of(r->params + k, info->components), "sd",
                                  sd_of(r->sd + k, info->components), "unit", info->unit, "status",
                                  status_of(r->status + k, info->components), "lower", info->lower,
                                  "upper", info->upper, "meaning", info->meaning));
  }
  return params;
}

/* Density and absorption of M4's film under docs/model.md §3.6's convention: only
 * their product τ is observable. */
static json_t *derived_json(const cf_fit_result *r, double density) {
  if (cf_model_info_get(r->model)->ggx_twin != CF_MODEL_CLAY) return json_null(); /* M4, M4T */
  const double *tau = r->params + CF_CLAY_OPTICAL_DEPTH;
  double mean = (tau[0] + tau[1] + tau[2]) / 3.0;
  double absorption[3];
  const char *convention;
  double d;
  if (isfinite(density)) {
    d = density;
    convention = "density (film thickness) given by the user; absorption = tau / density";
  } else {
    d = mean / 0.8;
    convention =
        "the photos determine only tau = absorption x density; by the convention of "
        "docs/model.md §3.6 "
        "the mean absorption over the channels is 0.8, so density = mean(tau) / 0.8";
  }
  for (int c = 0; c < 3; ++c) absorption[c] = d > 0.0 ? tau[c] / d : NAN;
  json_t *out = json_pack("{s:f, s:s}", "density", d, "convention", convention);
  if (d > 0.0)
    json_object_set_new(out, "absorption", numbers(absorption, 3));
  else
    json_object_set_new(out, "absorption", json_string("undefined: the optical depth is 0"));
  return out;
}

static json_t *correlation_json(const cf_fit_result *r) {
  json_t *names = json_array(), *matrix = json_array();
  for (int a = 0; a < r->free_count; ++a) {
    char name[48];
    json_array_append_new(
        names, json_string(cf_model_slot_name(r->model, r->free_slots[a], name, sizeof name)));
    json_array_append_new(matrix, numbers(r->correlation + a * r->free_count, r->free_count));
  }
  return json_pack("{s:o, s:o}", "parameters", names, "matrix", matrix);
}

/* Per slot (an RGB parameter's channels may differ): what was held and
 * why, the slots the capture does not constrain, the slots at a bound. */
static json_t *held_json(const cf_fit_result *r, json_t **unconstrained, json_t **at_bound) {
  const cf_model_info *m = cf_model_info_get(r->model);
  json_t *held = json_array();
  *unconstrained = json_array();
  *at_bound = json_array();
  for (int k = 0; k < m->dim; ++k) {
    char name[48];
    cf_model_slot_name(r->model, k, name, sizeof name);
    if (r->status[k] == CF_PARAM_FITTED) continue;
    if (r->status[k] == CF_PARAM_AT_BOUND) {
      json_array_append_new(*at_bound, json_string(name));
      continue;
    }
    json_array_append_new(held, json_pack("{s:s, s:f, s:s}", "name", name, "value", r->params[k],
                                          "why", cf_param_status_name(r->status[k])));
    if (r->status[k] == CF_PARAM_UNCONSTRAINED)
      json_array_append_new(*unconstrained, json_string(name));
  }
  return held;
}

static json_t *params_by_name(cf_model_id model, const double *x) {
  const cf_model_info *m = cf_model_info_get(model);
  json_t *out = json_object();
  for (int j = 0; j < m->param_count; ++j) {
    const cf_param_info *info = cf_param_info_get(m->params[j]);
    json_object_set_new(out, info->name, value_of(x + m->offsets[j], info->components));
  }
  return out;
}

static const char *const loss_names[] = {"none", "huber", "cauchy"};

/* The model choice: the rule, and every candidate's figures. */
static json_t *choice_json(const cf_fit_choice *choice, const cf_fit_result *result) {
  if (!choice) {
    json_t *forced = json_pack("{s:s, s:s, s:[]}", "mode", "forced", "chosen",
                               cf_model_info_get(result->model)->code, "candidates");
    char reading[320];
    if (cf_fit_reading(result, reading, sizeof reading))
      json_object_set_new(forced, "reading", json_string(reading));
    return forced;
  }
  json_t *candidates = json_array();
  for (int m = 0; m < choice->count; ++m) {
    const cf_fit_candidate *c = &choice->candidate[m];
    const char *code = cf_model_info_get(c->model)->code;
    json_t *entry;
    if (!c->ok) {
      entry = json_pack("{s:s, s:b, s:b, s:f, s:s}", "model", code, "ok", 0, "chosen", 0, "seconds",
                        c->seconds, "note", c->note);
    } else {
      entry = json_pack(
          "{s:s, s:b, s:b, s:o, s:i, s:I, s:f, s:f, s:I, s:o, s:o, s:o, s:f, s:f, s:f, s:s}",
          "model", code, "ok", 1, "chosen", c->chosen, "params", params_json(&c->fit), "unknowns",
          c->parameters, "residuals", (json_int_t)c->residuals, "cost", c->cost, "bic", c->bic,
          "heldout_residuals", (json_int_t)c->heldout_residuals, "heldout_score",
          json_real_or_null(c->heldout_score), "heldout_rmse", json_real_or_null(c->heldout_rmse),
          "heldout_relative_rmse", json_real_or_null(c->heldout_relative_rmse), "train_rmse",
          c->fit.rmse, "train_relative_rmse", c->fit.relative_rmse, "seconds", c->seconds, "note",
          c->note);
    }
    json_array_append_new(candidates, entry);
  }
  json_t *out = json_pack(
      "{s:s, s:s, s:I, s:I, s:s, s:f, s:{s:s, s:f}, s:f, s:f, s:f, s:f, s:s, s:o}", "mode",
      "auto", "chosen", cf_model_info_get(choice->chosen)->code, "train_observations",
      (json_int_t)choice->train_observations, "heldout_observations",
      (json_int_t)choice->heldout_observations, "heldout", choice->heldout, "sigma", choice->sigma,
      "loss", "type", loss_names[choice->loss], "scale_sigma", choice->loss_scale, "bic_margin",
      choice->bic_margin, "heldout_margin", choice->heldout_margin, "heldout_guard",
      choice->heldout_guard, "seconds", choice->seconds, "rule",
      "each model fitted to the training part; BIC = 2 cost + unknowns ln(residuals) there, "
      "cost = 1/2 sum rho(r^2) at the common sigma (the fits' loss); heldout_score = "
      "sqrt(mean r^2) on the held-out part, in sigma, without the robust loss (censored "
      "channels as in the fit); 1. going up the ladder a richer model replaces the choice only "
      "when its BIC is lower by more than bic_margin and its held-out score lower by more than "
      "heldout_margin (relative); 2. a choice whose held-out score is more than heldout_guard "
      "(relative) above the lowest gives way to the simplest candidate within heldout_guard of "
      "the lowest, unless its BIC is lower than that one's by more than bic_margin; 3. a choice "
      "whose film is a second lobe gives way to a candidate that is the simpler physical "
      "reading when that one does as well within the margins; the chosen candidate's note "
      "says why",
      "candidates", candidates);
  if (choice->reading[0]) json_object_set_new(out, "reading", json_string(choice->reading));
  if (choice->ggx_cost_text[0])
    json_object_set_new(out, "ggx_cost",
                        json_pack("{s:f, s:s}", "heldout_increase", choice->ggx_cost, "meaning",
                                  choice->ggx_cost_text));
  return out;
}

/* How the pixel footprints were integrated (cf_fit_options.footprint). */
/* The pixel budget's sample, or null (every observation). */
static json_t *sample_json(const cf_fit_result *r) {
  if (r->sample_count == 0) return json_null();
  return json_pack(
      "{s:s, s:I, s:I, s:s}", "sampling", cf_sampling_name(r->sampling), "observations",
      (json_int_t)r->sample_count, "population", (json_int_t)r->population_count, "meaning",
      "the fit used a pixel budget: `observations` of the `population` in use, drawn by "
      "`sampling`, each weighed by the inverse of its chance of being drawn; the standard "
      "deviations are the sample's (the sandwich A^-1 B A^-1 of the weighted fit), and the "
      "residual statistics are estimates for every observation from the weighted sample "
      "(their counts are the sample's); clayfit report evaluates every observation");
}

static json_t *footprint_json(const cf_fit_report *rep) {
  const cf_fit_result *r = rep->result;
  const char *mode = rep->footprint == 0 ? "auto" : rep->footprint == 1 ? "centre" : "fixed";
  return json_pack("{s:s, s:i, s:f, s:I, s:I, s:i, s:s}", "mode", mode, "samples_per_side",
                   rep->footprint >= 2 ? rep->footprint : 0, "tolerance", rep->footprint_tolerance,
                   "observations", (json_int_t)r->footprint_observations, "samples",
                   (json_int_t)r->footprint_samples, "max_samples_per_side", r->footprint_max,
                   "meaning",
                   "observations integrated over their pixel with S x S samples (S >= 2) "
                   "where a lobe is narrower than the pixel, the samples over them, and the "
                   "largest S; the others are evaluated at the pixel centre");
}

static json_t *per_image_json(const cf_fit_report *rep) {
  const cf_fit_result *r = rep->result;
  json_t *per_image = json_array();
  for (size_t k = 0; k < r->images; ++k) {
    json_t *image = json_pack(
        "{s:s, s:f, s:f, s:f, s:I}", "name", cf_capture_image_at(rep->capture, k)->name, "rmse",
        r->image_rmse[k], "relative_rmse", r->image_relative_rmse[k], "exposure", r->exposures[k],
        "not_radiance", (json_int_t)cf_capture_image_at(rep->capture, k)->not_radiance);
    if (r->exposure_sd) json_object_set_new(image, "exposure_sd", json_real(r->exposure_sd[k]));
    if (r->white_balance_fitted && r->white_balance && r->white_balance_sd) {
      json_object_set_new(image, "white_balance", numbers(r->white_balance + 3 * k, 3));
      json_object_set_new(image, "white_balance_sd", numbers(r->white_balance_sd + 3 * k, 3));
    }
    json_array_append_new(per_image, image);
  }
  return per_image;
}

/* The gains per light inside the sums (docs/fitting.md), when fitted. */
static json_t *light_gains_json(const cf_fit_result *r) {
  json_t *lights = json_array();
  for (size_t l = 0; l < r->light_count; ++l)
    json_array_append_new(lights, json_pack("{s:s, s:f, s:f}", "light", r->light_names[l], "gain",
                                            r->light_gains[l], "sd", r->light_gains_sd[l]));
  return lights;
}

static json_t *starts_json(const cf_fit_result *r) {
  json_t *starts = json_array();
  for (int i = 0; i < r->starts; ++i)
    json_array_append_new(
        starts,
        json_pack("{s:o, s:o, s:f, s:i, s:b}", "start", params_by_name(r->model, r->start[i].start),
                  "end", params_by_name(r->model, r->start[i].end), "cost", r->start[i].cost,
                  "iterations", r->start[i].iterations, "stopped", r->start[i].stopped));
  return starts;
}

static json_t *stages_json(const cf_fit_result *r) {
  json_t *stages = json_object();
  for (int i = 0; i < CF_FIT_STAGE_COUNT; ++i)
    json_object_set_new(stages, cf_fit_stage_name((cf_fit_stage)i), json_real(r->stage_seconds[i]));
  return stages;
}

static json_t *warnings_json(const cf_fit_result *r) {
  json_t *warnings = json_array();
  for (int i = 0; i < r->warning_count; ++i)
    json_array_append_new(warnings, json_string(r->warnings[i]));
  return warnings;
}

static json_t *cores_json(const cf_fit_result *r) {
  return json_pack(
      "{s:f, s:I, s:f, s:f, s:{s:I, s:f, s:f}, s:s}", "radius_px", CF_FIT_CORE_RADIUS_PX, "count",
      (json_int_t)r->core_residuals, "rmse", r->core_rmse, "relative_rmse", r->core_relative_rmse,
      "rest", "count", (json_int_t)(r->residuals - r->core_residuals), "rmse", r->rest_rmse,
      "relative_rmse", r->rest_relative_rmse, "meaning",
      "residuals within radius_px of each image's brightest observation (the highlight's core, "
      "where the lobe's shape shows) and of all the others");
}

/* The response curve (docs/model.md §5.4): its model, slopes with their
 * sds and covariance, and the curve sampled every quarter stop of the
 * decoded value from 2^−8 to 1, each with the linear value R⁻¹(y) and its
 * sd (docs/fitting.md "Response curve"). */
enum { CURVE_SAMPLES = 33 };
static json_t *response_json(const cf_fit_result *r) {
  enum { K = CF_RESPONSE_MODEL_KNOTS };
  double knots[K], sd[K];
  json_t *covariance = json_array(), *curve = json_array();
  for (int j = 0; j < K; ++j) {
    knots[j] = cf_response_model_knot(j);
    sd[j] = sqrt(fmax(0.0, r->response_covariance[j * K + j]));
    json_array_append_new(covariance, numbers(r->response_covariance + j * K, K));
  }
  for (int i = 0; i < CURVE_SAMPLES; ++i) {
    double y = exp2(-8.0 + 0.25 * i), sd_log;
    double x = cf_response_model_inverse(r->response, r->response_covariance, y, &sd_log);
    json_array_append_new(
        curve, json_pack("{s:f, s:f, s:f}", "decoded", y, "linear", x, "linear_sd", x * sd_log));
  }
  return json_pack(
      "{s:b, s:s, s:o, s:o, s:o, s:o, s:o, s:s}", "fitted", r->response_fitted, "model",
      CF_RESPONSE_MODEL_NAME, "knots", numbers(knots, K), "slopes", numbers(r->response, K),
      "slopes_sd", numbers(sd, K), "covariance", covariance, "curve", curve, "meaning",
      "the camera response R: the decoded photo values are modelled as R(scale x exposure x "
      "radiance), log R a function of log x whose slope is linear between the knots (x = 1, "
      "1/3, 1/9, ...; the slopes given) and constant beyond, R(1) = 1; fitted when the capture "
      "says the tone curve is unknown, else the identity (every slope 1). The curve gives, for "
      "decoded "
      "values y, the linear value x = R^-1(y) and its sd from the slopes' covariance");
}

/* JPEG's coding error as the fit modelled it (fit_jpeg.h). */
static json_t *jpeg_coding_json(const cf_fit_result *r) {
  return json_pack(
      "{s:i, s:i, s:f, s:[f, f, f], s:s}", "images", r->jpeg_images, "draws", FIT_JPEG_DRAWS,
      "bias_rms_codes", r->jpeg_bias_rms, "bias_mean_codes", r->jpeg_bias_mean[0],
      r->jpeg_bias_mean[1], r->jpeg_bias_mean[2], "meaning",
      "the JPEG images' codec error, modelled: the photo with the fitted prediction on the "
      "sphere (plus draws of the noise model) coded and decoded at each file's own quality and "
      "chroma subsampling; the mean change at each observed pixel was taken out of the "
      "measurements before the last solve. Its rms over the observed pixels and channels, and "
      "its mean per channel, in codes of 1/255 (docs/model.md 6.2)");
}

/* The sections after the first json_pack (its format has room for no more). */
static void add_later_sections(json_t *doc, const cf_fit_report *rep,
                               const cf_capture_summary *summary) {
  const cf_fit_result *r = rep->result;
  /* the formulas the values belong to (docs/model.md, top) */
  json_object_set_new(doc, "model_version", json_integer(CF_MODEL_VERSION));
  if (summary->radiometry_from_reference) /* the capture's scale from its reference */
    json_object_set_new(
        json_object_get(doc, "capture"), "reference",
        json_pack("{s:f, s:f, s:I}", "scale", summary->reference_scale, "spread",
                  summary->reference_spread, "pixels", (json_int_t)summary->reference_pixels));
  json_object_set_new(doc, "choice", choice_json(rep->choice, r));
  json_object_set_new(json_object_get(doc, "timing"), "choice_s",
                      json_real(rep->choice ? rep->choice->seconds : 0.0));
  json_object_set_new(doc, "footprint", footprint_json(rep));
  json_object_set_new(doc, "sample", sample_json(r));
  json_object_set_new(json_object_get(doc, "solver"), "trace", numbers(r->trace, r->trace_count));
  json_object_set_new(doc, "response", response_json(r));
  if (r->jpeg_images > 0) json_object_set_new(doc, "jpeg_coding", jpeg_coding_json(r));
  if (r->light_count > 0 && r->light_gains && r->light_gains_sd && r->light_names)
    json_object_set_new(doc, "light_gains", light_gains_json(r));
}

/* The capture's path relative to the folder of fit.json (data_schema/
 * fit.schema.json, capture.path), so that report and export find it from
 * any folder. */
static cf_status capture_path_from(const char *fit_path, const char *capture_path, char *out,
                                   size_t size, cf_error *err) {
  char folder[4096];
  cf_status s = cf_path_dirname(fit_path, folder, sizeof folder, err);
  if (s == CF_OK) s = cf_path_relative(folder, capture_path, out, size, err);
  return s;
}

cf_status cf_fit_write_json(const char *path, const cf_fit_report *rep, cf_error *err) {
  const cf_fit_result *r = rep->result;
  const cf_model_info *m = cf_model_info_get(r->model);
  char capture_path[4096];
  cf_status s = capture_path_from(path, rep->capture_path, capture_path, sizeof capture_path, err);
  if (s != CF_OK) return s;
  cf_capture_summary summary;
  cf_capture_summarize(rep->capture, &summary);
  const cf_observations *obs = cf_capture_observations(rep->capture);
  char created[32];
  time_t now = time(NULL);
  struct tm utc;
  gmtime_r(&now, &utc);
  strftime(created, sizeof created, "%Y-%m-%dT%H:%M:%SZ", &utc);

  json_t *unconstrained, *at_bound;
  json_t *held = held_json(r, &unconstrained, &at_bound);
  json_t *doc = json_pack(
      "{s:i, s:s, s:s, s:{s:s, s:s, s:I, s:I, s:s}, s:{s:s, s:s}, s:o, s:o, s:{s:f, s:f, s:b}, "
      "s:o, s:o, s:o, s:o, s:{s:s, s:f}, s:{s:s, s:f}, s:{s:I, s:I, s:I, s:f, s:f, s:o, s:o}, "
      "s:{s:i, s:i, s:s, s:f, s:f}, s:o, s:i, s:o, s:{s:f, s:f, s:f, s:o}}",
      "clayfit_fit", 1, "clayfit_version", rep->version, "created", created, "capture", "path",
      capture_path, "name", summary.name, "images", (json_int_t)r->images, "observations",
      (json_int_t)obs->count, "radiometry",
      summary.radiometry_from_reference ? "from_reference"
      : summary.radiometry_relative     ? "relative"
                                        : "absolute",
      "model", "code", m->code, "name", m->name, "params", params_json(r), "derived",
      derived_json(r, rep->density), "scale", "value", r->scale, "sd", r->scale_sd, "fitted",
      r->scale_fitted, "correlation", correlation_json(r), "held", held, "not_constrained",
      unconstrained, "at_bound", at_bound, "noise", "model",
      r->sigma > 0.0 ? "estimated from the residuals" : "capture", "sigma", r->sigma, "loss",
      "type", loss_names[rep->loss], "scale_sigma", rep->loss_scale, "residuals", "count",
      (json_int_t)r->residuals, "censored", (json_int_t)r->censored, "rejected",
      (json_int_t)r->rejected, "rmse", r->rmse, "relative_rmse", r->relative_rmse, "per_image",
      per_image_json(rep), "highlight_cores", cores_json(r), "solver", "iterations", r->iterations,
      "solves", r->solves, "termination", r->termination, "seconds", r->solve_seconds, "final_cost",
      r->cost, "starts", starts_json(r), "best_start", r->best_start, "warnings", warnings_json(r),
      "timing", "load_s", rep->load_seconds, "fit_s", rep->fit_seconds, "total_s",
      rep->load_seconds + rep->fit_seconds, "stages", stages_json(r));
  if (!doc) return cf_error_set(err, CF_ENOMEM, "could not build fit.json");
  add_later_sections(doc, rep, &summary);
  cf_status written = json_write_file(doc, path, JSON_INDENT(2) | JSON_REAL_PRECISION(17), err);
  json_decref(doc);
  return written;
}
