/* cf_fit_file_read: a fit written by cf_fit_write_json and read back gives
 * the same values (M4 with per-channel statuses, a null standard deviation
 * at a bound, an unconstrained slot; M0 with derived null); a broken
 * fit.json is refused with the file and the JSON path in the message. The
 * capture is recorded relative to fit.json's folder and found from there;
 * an older fit.json's path, relative to the current folder, still is. The
 * response curve's slopes and covariance read back as written; an older
 * fit.json's response exponent γ reads as the curve with every slope γ. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <jansson.h>

#include "clayfit/fit.h"
#include "clayfit/fit_file.h"
#include "core/file.h"
#include "fit/fit_support.h"
#include "support/check.h"

CHECK_MAIN_STATE;

static int same(double a, double b) {
  return a == b || (isnan(a) && isnan(b));
}

/* A hand-made result of `model` over the capture's images. */
static void make_result(cf_fit_result *r, cf_model_id model, size_t images) {
  memset(r, 0, sizeof *r);
  const cf_model_info *m = cf_model_info_get(model);
  r->model = model;
  cf_model_default_params(model, r->params);
  for (int k = 0; k < m->dim; ++k) {
    double step = 0.001 * (k + 1) / 3.0; /* not round numbers, in range */
    r->params[k] += r->params[k] + step <= 1.0 ? step : -step;
    r->sd[k] = 1e-3 / (k + 1);
    r->status[k] = CF_PARAM_FITTED;
  }
  if (model == CF_MODEL_CLAY) {
    r->params[CF_CLAY_OPTICAL_DEPTH + 2] = 0.0; /* at its lower bound */
    r->sd[CF_CLAY_OPTICAL_DEPTH + 2] = NAN;
    r->status[CF_CLAY_OPTICAL_DEPTH + 2] = CF_PARAM_AT_BOUND;
    r->params[CF_CLAY_BASE_F0] = 0.004;
    r->sd[CF_CLAY_BASE_F0] = 0.0;
    r->status[CF_CLAY_BASE_F0] = CF_PARAM_UNCONSTRAINED;
    r->sd[CF_CLAY_FILM_F0] = 0.0;
    r->status[CF_CLAY_FILM_F0] = CF_PARAM_HELD_FOR_SCALE;
  }
  for (int k = 0; k < m->dim; ++k)
    if (r->status[k] == CF_PARAM_FITTED) r->free_slots[r->free_count++] = k;
  for (int a = 0; a < r->free_count; ++a)
    for (int b = 0; b < r->free_count; ++b)
      r->correlation[a * r->free_count + b] = a == b ? 1.0 : 0.01 * (a - b);
  r->scale = 1.25;
  r->scale_sd = 0.003;
  r->scale_fitted = 1;
  const double slopes[CF_RESPONSE_MODEL_KNOTS] = {0.45, 0.5, 0.6, 0.8, 1.0, 1.1};
  for (int i = 0; i < CF_RESPONSE_MODEL_KNOTS; ++i) {
    r->response[i] = slopes[i];
    for (int j = 0; j < CF_RESPONSE_MODEL_KNOTS; ++j)
      r->response_covariance[i * CF_RESPONSE_MODEL_KNOTS + j] =
          i == j ? 1e-4 * (i + 1) : -1e-6 * (i + j);
  }
  r->response_fitted = 1;
  r->images = images;
  r->exposures = calloc(images, sizeof(double));
  r->image_rmse = calloc(images, sizeof(double));
  r->image_relative_rmse = calloc(images, sizeof(double));
  for (size_t k = 0; k < images; ++k) {
    r->exposures[k] = 1.0 + 0.1 * (double)k;
    r->image_rmse[k] = 0.01 / (double)(k + 1);
    r->image_relative_rmse[k] = 0.02 / (double)(k + 1);
  }
  r->sigma = 0.0123;
  r->residuals = 3000;
  r->censored = 7;
  r->rejected = 11;
  r->rmse = 0.0042;
  r->relative_rmse = 0.031;
  r->core_residuals = 90;
  r->core_rmse = 0.1;
  r->core_relative_rmse = 0.2;
  r->rest_rmse = 0.003;
  r->rest_relative_rmse = 0.02;
  r->cost = 123.5;
  r->iterations = 17;
  r->solves = 2;
  snprintf(r->termination, sizeof r->termination, "CONVERGENCE");
  r->starts = 2;
  for (int i = 0; i < 2; ++i) {
    memcpy(r->start[i].start, r->params, sizeof r->params);
    memcpy(r->start[i].end, r->params, sizeof r->params);
    r->start[i].start[0] = 0.1 * (i + 1);
    r->start[i].cost = 10.0 + i;
    r->start[i].iterations = 5 + i;
    r->start[i].stopped = i;
  }
  r->best_start = 1;
  r->footprint_observations = 40;
  r->footprint_samples = 640;
  r->footprint_max = 4;
  if (model == CF_MODEL_CLAY) { /* a pixel budget (the others: none, "sample": null) */
    r->sample_count = 1000;
    r->population_count = 9000;
    r->sampling = CF_SAMPLING_STRATIFIED;
  }
  r->warning_count = 1;
  snprintf(r->warnings[0], sizeof r->warnings[0], "a warning");
}

static void round_trip(const cf_capture *capture, const char *dir, cf_model_id model) {
  const cf_model_info *m = cf_model_info_get(model);
  cf_fit_result r;
  make_result(&r, model, cf_capture_image_count(capture));
  char path[600];
  snprintf(path, sizeof path, "%s/%s.fit.json", dir, m->code);
  char capture_path[600];
  snprintf(capture_path, sizeof capture_path, "%s/capture/capture.json", dir);
  cf_fit_report rep = {capture, capture_path, &r,  NULL, "9.9.9", CF_LOSS_CAUCHY,
                       2.5,     NAN,          1.0, 2.0,  3,       0.004};
  cf_error err = {0};
  CHECK(cf_fit_write_json(path, &rep, &err) == CF_OK, "%s", err.message);
  cf_fit_file f;
  cf_status s = cf_fit_file_read(path, &f, &err);
  CHECK(s == CF_OK, "%s: %s", m->code, err.message);
  if (s != CF_OK) {
    cf_fit_result_free(&r);
    return;
  }
  const cf_fit_result *g = &f.result;
  CHECK(g->model == model, "%s: model %d", m->code, (int)g->model);
  for (int k = 0; k < m->dim; ++k) {
    CHECK(g->params[k] == r.params[k], "%s: params[%d] %.17g != %.17g", m->code, k, g->params[k],
          r.params[k]);
    CHECK(same(g->sd[k], r.sd[k]), "%s: sd[%d] %.17g != %.17g", m->code, k, g->sd[k], r.sd[k]);
    CHECK(g->status[k] == r.status[k], "%s: status[%d] %d != %d", m->code, k, (int)g->status[k],
          (int)r.status[k]);
  }
  CHECK(g->free_count == r.free_count, "%s: free_count", m->code);
  for (int a = 0; a < r.free_count * r.free_count; ++a)
    CHECK(g->correlation[a] == r.correlation[a], "%s: correlation[%d]", m->code, a);
  for (int a = 0; a < r.free_count; ++a) CHECK(g->free_slots[a] == r.free_slots[a], "free_slots");
  CHECK(g->scale == r.scale && g->scale_sd == r.scale_sd && g->scale_fitted == 1, "scale");
  CHECK(memcmp(g->response, r.response, sizeof r.response) == 0 &&
            memcmp(g->response_covariance, r.response_covariance, sizeof r.response_covariance) ==
                0 &&
            g->response_fitted == 1,
        "response");
  CHECK(g->images == r.images, "images %zu", g->images);
  for (size_t k = 0; k < r.images && k < g->images; ++k)
    CHECK(g->exposures[k] == r.exposures[k] && g->image_rmse[k] == r.image_rmse[k] &&
              g->image_relative_rmse[k] == r.image_relative_rmse[k],
          "image %zu", k);
  CHECK(g->sigma == r.sigma && g->rmse == r.rmse && g->relative_rmse == r.relative_rmse, "rmse");
  CHECK(g->residuals == 3000 && g->censored == 7 && g->rejected == 11, "counts");
  CHECK(g->core_residuals == 90 && g->core_rmse == 0.1 && g->rest_rmse == 0.003, "cores");
  CHECK(g->cost == 123.5 && g->iterations == 17 && g->solves == 2, "solver");
  CHECK(strcmp(g->termination, "CONVERGENCE") == 0, "termination");
  CHECK(g->starts == 2 && g->best_start == 1, "starts");
  CHECK(g->start[0].start[0] == 0.1 && g->start[1].cost == 11.0, "start values");
  CHECK(g->start[0].stopped == 0 && g->start[1].stopped == 1, "start stopped");
  CHECK(g->warning_count == 1 && strcmp(g->warnings[0], "a warning") == 0, "warnings");
  CHECK(g->footprint_observations == 40 && g->footprint_samples == 640 && g->footprint_max == 4,
        "footprint counts");
  CHECK(f.footprint == 3 && f.footprint_tolerance == 0.004, "footprint %d", f.footprint);
  CHECK(g->sample_count == r.sample_count && g->population_count == r.population_count &&
            (r.sample_count == 0 || g->sampling == r.sampling),
        "%s: sample %zu of %zu", m->code, g->sample_count, g->population_count);
  CHECK(strcmp(f.clayfit_version, "9.9.9") == 0, "version '%s'", f.clayfit_version);
  CHECK(strlen(f.created) == 20, "created '%s'", f.created);
  CHECK(strcmp(f.capture_written, "capture/capture.json") == 0, "capture.path '%s'",
        f.capture_written);
  CHECK(strcmp(f.capture_path, capture_path) == 0 && f.capture_found, "capture_path '%s'",
        f.capture_path);
  CHECK(strcmp(f.radiometry, "absolute") == 0, "radiometry '%s'", f.radiometry);
  CHECK(strcmp(f.loss, "cauchy") == 0 && f.loss_scale == 2.5, "loss '%s'", f.loss);
  if (cf_model_info_get(model)->ggx_twin == CF_MODEL_CLAY) { /* M4, M4T */
    const double *tau = r.params + CF_CLAY_OPTICAL_DEPTH;
    double d = (tau[0] + tau[1] + tau[2]) / 3.0 / 0.8;
    CHECK(fabs(f.density - d) <= 1e-15 * d, "density %.17g", f.density);
    CHECK(fabs(f.absorption[0] - tau[0] / d) < 1e-14 && fabs(f.absorption[2] - tau[2] / d) < 1e-14,
          "absorption");
    CHECK(strstr(f.density_convention, "0.8") != NULL, "convention");
  } else {
    CHECK(isnan(f.density) && isnan(f.absorption[0]), "derived null");
  }
  cf_fit_file_free(&f);
  CHECK(f.result.exposures == NULL, "freed");
  cf_fit_result_free(&r);
}

/* Replace `from` by `to` in the file, write it to `out`. */
static int edit(const char *in, const char *out, const char *from, const char *to) {
  FILE *file = fopen(in, "rb");
  if (!file) return 0;
  static char text[1 << 20];
  size_t n = fread(text, 1, sizeof text - 1, file);
  fclose(file);
  text[n] = '\0';
  char *at = strstr(text, from);
  if (!at) return 0;
  file = fopen(out, "wb");
  if (!file) return 0;
  fwrite(text, 1, (size_t)(at - text), file);
  fputs(to, file);
  fputs(at + strlen(from), file);
  fclose(file);
  return 1;
}

static void refused(const char *dir, const char *from, const char *to, const char *message) {
  char in[600], out[600];
  snprintf(in, sizeof in, "%s/M4.fit.json", dir);
  snprintf(out, sizeof out, "%s/bad.fit.json", dir);
  CHECK(edit(in, out, from, to), "could not edit '%s'", from);
  cf_fit_file f;
  cf_error err = {0};
  cf_status s = cf_fit_file_read(out, &f, &err);
  CHECK(s != CF_OK, "'%s' -> '%s' accepted", from, to);
  CHECK(strstr(err.message, message) != NULL && strstr(err.message, "bad.fit.json") != NULL,
        "'%s' -> '%s': message '%s' lacks '%s'", from, to, err.message, message);
}

/* cf_path_relative between real folders. */
static void relative_paths(const char *dir) {
  char from[600], target[600], out[600];
  cf_error err = {0};
  snprintf(from, sizeof from, "%s/old", dir);
  snprintf(target, sizeof target, "%s/capture/capture.json", dir);
  CHECK(cf_path_relative(from, target, out, sizeof out, &err) == CF_OK &&
            strcmp(out, "../capture/capture.json") == 0,
        "'%s' %s", out, err.message);
  CHECK(cf_path_relative(dir, target, out, sizeof out, &err) == CF_OK &&
            strcmp(out, "capture/capture.json") == 0,
        "'%s' %s", out, err.message);
  snprintf(from, sizeof from, "%s/old/", dir);
  CHECK(cf_path_relative(from, target, out, sizeof out, &err) == CF_OK &&
            strcmp(out, "../capture/capture.json") == 0,
        "trailing slash: '%s' %s", out, err.message);
  CHECK(cf_path_relative("/", target, out, sizeof out, &err) == CF_OK && out[0] != '/' &&
            strstr(out, "capture/capture.json") != NULL,
        "from /: '%s' %s", out, err.message);
  snprintf(target, sizeof target, "%s/capturex/capture.json", dir);
  CHECK(cf_path_relative(dir, target, out, sizeof out, &err) == CF_ENOTFOUND,
        "a missing folder: '%s'", out);
}

/* A fit.json as clayfit wrote it before capture.path was relative to its
 * folder: the path relative to the folder clayfit fit ran in (dir). Found
 * there when the current folder is that one; otherwise not found, and the
 * message names both places. */
static void older_fit(const char *dir) {
  char in[600], out[600], cwd[4096];
  snprintf(in, sizeof in, "%s/M2.fit.json", dir);
  snprintf(out, sizeof out, "%s/old/fit.json", dir);
  CHECK(edit(in, out, "\"clayfit_fit\": 1", "\"clayfit_fit\": 1"), "could not copy %s", in);
  CHECK(getcwd(cwd, sizeof cwd) != NULL, "getcwd");
  cf_fit_file f;
  cf_error err = {0};
  CHECK(chdir(dir) == 0, "chdir %s", dir);
  CHECK(cf_fit_file_read(out, &f, &err) == CF_OK, "%s", err.message);
  CHECK(f.capture_found && strcmp(f.capture_path, "capture/capture.json") == 0,
        "from the fit's folder: '%s'", f.capture_path);
  CHECK(cf_fit_file_check_capture(&f, out, &err) == CF_OK, "%s", err.message);
  cf_fit_file_free(&f);
  CHECK(chdir("/") == 0, "chdir /");
  CHECK(cf_fit_file_read(out, &f, &err) == CF_OK, "%s", err.message);
  char expected[700];
  snprintf(expected, sizeof expected, "%s/old/capture/capture.json", dir);
  CHECK(!f.capture_found && strcmp(f.capture_path, expected) == 0, "elsewhere: '%s'",
        f.capture_path);
  CHECK(cf_fit_file_check_capture(&f, out, &err) == CF_ENOTFOUND &&
            strstr(err.message, expected) != NULL &&
            strstr(err.message, "nor at capture/capture.json (relative to the current folder") !=
                NULL,
        "message '%s'", err.message);
  cf_fit_file_free(&f);
  CHECK(chdir(cwd) == 0, "chdir %s", cwd);
}

/* fit.json's response as clayfit wrote it before the curve: one exponent
 * γ ± sd, read as the curve with every slope γ and every covariance entry
 * sd² (the power x^γ, its sd fully correlated across the knots). */
static void older_response(const char *dir) {
  char in[600], out[600];
  snprintf(in, sizeof in, "%s/M2.fit.json", dir);
  snprintf(out, sizeof out, "%s/old_response.fit.json", dir);
  json_t *root = json_load_file(in, 0, NULL);
  CHECK(root != NULL, "could not load %s", in);
  if (!root) return;
  json_object_set_new(root, "response",
                      json_pack("{s:f, s:f, s:b, s:s}", "value", 1.5, "sd", 0.002, "fitted", 1,
                                "meaning", "the response exponent"));
  CHECK(json_dump_file(root, out, JSON_REAL_PRECISION(17)) == 0, "could not write %s", out);
  json_decref(root);
  cf_fit_file f;
  cf_error err = {0};
  CHECK(cf_fit_file_read(out, &f, &err) == CF_OK, "%s", err.message);
  int power = f.result.response_fitted == 1;
  for (int i = 0; i < CF_RESPONSE_MODEL_KNOTS; ++i) {
    power = power && f.result.response[i] == 1.5;
    for (int j = 0; j < CF_RESPONSE_MODEL_KNOTS; ++j)
      power = power && fabs(f.result.response_covariance[i * CF_RESPONSE_MODEL_KNOTS + j] -
                            0.002 * 0.002) < 1e-18;
  }
  CHECK(power, "the exponent 1.5 +- 0.002 did not read as the power curve");
  cf_fit_file_free(&f);
}

int main(void) {
  char dir[64];
  if (!fit_test_make_dir(dir, sizeof dir)) return 1;
  cf_synth_options o;
  double params[CF_MAX_DIM];
  cf_model_default_params(CF_MODEL_LAMBERT, params);
  fit_test_synth_options(&o, CF_MODEL_LAMBERT, params);
  o.images = 2;
  o.width = 80;
  o.height = 60;
  o.focal_px = 100.0;
  cf_capture *capture = fit_test_capture(dir, "capture", &o);
  if (!capture) return check_finish("test_fit_read");
  for (int m = 0; m < CF_MODEL_COUNT; ++m) round_trip(capture, dir, (cf_model_id)m);
  cf_capture_free(capture);
  char old[600];
  snprintf(old, sizeof old, "%s/old", dir);
  CHECK(mkdir(old, 0777) == 0, "mkdir %s", old);
  relative_paths(dir);
  older_fit(dir);
  older_response(dir);

  refused(dir, "\"clayfit_fit\": 1", "\"clayfit_fit\": \"1\"", "clayfit_fit: expected an integer");
  refused(dir, "\"scale\": {", "\"scale\": {\"bogus\": 1, ", "scale: unknown key 'bogus'");
  refused(dir, "\"code\": \"M4\"", "\"code\": \"M7\"", "model.code: 'M7' is not one of");
  refused(dir, "\"status\": \"held: sets the absolute scale\"", "\"status\": \"guessed\"",
          "params.film_f0.status: 'guessed' is not a parameter status");
  refused(dir, "\"unit\": \"rad\"", "\"unit\": \"deg\"", "params.diffuse_roughness.unit");
  refused(dir, "\"exposure\": 1.0", "\"exposure\": -1", "residuals.per_image[0].exposure");
  refused(dir, "\"value\": 1.25", "\"value\": \"x\"", "scale.value: expected a number");
  refused(dir, "\"sampling\": \"stratified\"", "\"sampling\": \"random\"",
          "sample.sampling: 'random' is not one of");
  refused(dir, "\"observations\": 1000", "\"observations\": 9000",
          "sample.observations: 9000: expected 1 to 8999");
  refused(dir, "\"model\": \"log_log_slope_spline\"", "\"model\": \"emor\"",
          "response.model: 'emor' is not one of");
  refused(dir, "\"slopes\": [\n      0.45", "\"slopes\": [\n      0.05", "response.slopes");
  refused(dir, "\"knots\": [\n      1.0", "\"knots\": [\n      0.5",
          "response.knots: knot 0 is 0.5");
  cf_fit_file f;
  cf_error err = {0};
  CHECK(cf_fit_file_read("/no/such/fit.json", &f, &err) == CF_ENOTFOUND, "missing file: %s",
        err.message);
  fit_test_remove_dir(dir);
  return check_finish("test_fit_read");
}
