/* The response curve's shape from a few starts (fit_response_starts.h).
 *
 * From the identity alone the full solve found a second minimum on linear
 * 8-bit JPEGs declared sRGB or gamma 1.8 (the curve's top slope at its
 * bound 0.1, the scale 0.61, the albedo 4-6 % low: 24-25 sd; relative
 * RMSE 5.63 % against 4.39 %). Each start here is a hypothesis about the
 * camera: the declared encoding is its curve (the identity), or it is one
 * of the common curves (cf_response) read through the declared decoding. */
#include "fit_response_starts.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "clayfit/image.h"
#include "clayfit/response_model.h"
#include "fit_residuals.h"
#include "fit_sample.h"

enum {
  K = CF_RESPONSE_MODEL_KNOTS,
  START_TARGET = 6000, /* observations a start is solved on (7426efe: h13's choice) */
  START_ROUNDS = 2     /* reweighted solves a stage (7426efe; 1: 1 of 10 fits moves, 4: none) */
};

/* The mean log of the subsample's positive measurements: the level at
 * which a start's curve meets the identity (through the scale). */
static double mean_log_level(const fit_problem *p) {
  const double *y = fit_problem_measured(p);
  double sum = 0.0;
  size_t n = 0;
  for (size_t i = 0; i < 3 * fit_problem_count(p); ++i)
    if (y[i] > 0.0) sum += log(y[i]), ++n;
  return n ? sum / (double)n : log(0.25); /* (no positive measurement: any level) */
}

/* The knots' log-log slopes of R = the declared decoding of camera curve
 * `camera`'s codes (within the slopes' bounds). */
static void camera_slopes(const cf_capture_summary *about, cf_response camera, double *slopes) {
  const double h = 0.05; /* in log x: a central difference, against knots log 3 = 1.1 apart */
  for (int j = 0; j < K; ++j) {
    double x = cf_response_model_knot(j);
    double up = cf_transfer_to_linear((cf_transfer)about->transfer, about->transfer_gamma,
                                      cf_response_encode(camera, x * exp(h)));
    double down = cf_transfer_to_linear((cf_transfer)about->transfer, about->transfer_gamma,
                                        cf_response_encode(camera, x * exp(-h)));
    double slope = log(up / down) / (2.0 * h);
    slopes[j] = fmin(CF_RESPONSE_MODEL_SLOPE_UPPER, fmax(CF_RESPONSE_MODEL_SLOPE_LOWER, slope));
  }
}

/* Two curves the same start (slopes within 0.1 at every knot: 7426efe; 0.05, 0.2 move no fit)? */
static int same_start(const double *a, const double *b) {
  for (int j = 0; j < K; ++j)
    if (fabs(a[j] - b[j]) > 0.1) return 0;
  return 1;
}

/* The starting shapes: the given curve (the model choice's, or NULL),
 * the identity, then the declared decoding of each common camera curve's
 * codes, each shape once. Returns how many. */
static int start_shapes(const cf_capture_summary *about, const double *given, double starts[][K]) {
  int count = 0;
  if (given) memcpy(starts[count++], given, sizeof starts[0]);
  fit_response_identity(starts[count]);
  count += !(given && same_start(starts[0], starts[count]));
  for (int c = 0; c < CF_RESPONSE_COUNT; ++c) {
    camera_slopes(about, (cf_response)c, starts[count]);
    int seen = 0;
    for (int k = 0; k < count; ++k) seen |= same_start(starts[k], starts[count]);
    if (!seen) ++count;
  }
  return count;
}

/* The negative log-likelihood at the problem's values, σ from the
 * prediction through its curve: the cost (the loss, the censored
 * channels, the prior) plus Σ w log σ. The cost alone does not compare
 * curves, whose slopes scale σ: on linear JPEGs declared sRGB it ranked
 * a curve flat at the top (cost 6470) above the right one (26359). */
static cf_status neg_log_likelihood(fit_problem *p, int threads, double *nll, cf_error *err) {
  size_t n = (size_t)fit_problem_unknown_count(p);
  double *jtj = malloc((n * n + n + 1) * sizeof *jtj), cost = 0.0, logs = 0.0;
  cf_status s = jtj ? fit_problem_reweight(p, err) : cf_error_set(err, CF_ENOMEM, "out of memory");
  if (s == CF_OK) s = fit_normal_equations(p, threads, jtj, jtj + n * n, &cost, err);
  if (s == CF_OK) s = fit_sum_log_sigma(p, &logs, err);
  free(jtj);
  *nll = cost + logs;
  return s;
}

/* What every start shares, and the most likely values yet. */
typedef struct start_run {
  const cf_capture *capture;
  const cf_fit_options *o;
  fit_problem *sub;
  double sigma, level; /* the one σ; mean_log_level */
  double best, best_params[CF_MAX_DIM], best_log_scale, best_response[K];
} start_run;

/* A reweighted solve of the subsample with the plan's unknowns. */
static cf_status solve_start(start_run *run, const fit_plan *plan, cf_error *err) {
  cf_status s = fit_declare_robust(run->sub, plan, run->o, run->sigma, err);
  if (s != CF_OK) return s;
  cf_lsq_summary summary;
  return fit_solve_reweighted(run->sub, run->o, START_ROUNDS, &summary, NULL, err);
}

/* The subsample's values kept when they are the most likely yet. */
static cf_status consider(start_run *run, cf_error *err) {
  double nll;
  cf_status s = neg_log_likelihood(run->sub, fit_threads(run->o), &nll, err);
  if (s != CF_OK || !(nll < run->best)) return s;
  const fit_values *v = fit_problem_read_values(run->sub);
  run->best = nll;
  memcpy(run->best_params, v->params, sizeof run->best_params);
  run->best_log_scale = v->log_scale;
  memcpy(run->best_response, v->response, sizeof run->best_response);
  return CF_OK;
}

/* One start: the curve `slopes`, meeting the identity's values at the
 * mean level through the scale when it is free; the material solved with
 * that curve held, then with it free (freed at once, the top slope fell
 * to its bound from x^1.8 on linear JPEGs declared gamma 1.8). Both ends
 * are considered: the solves weigh by σ from the curve but drop log σ
 * (an estimating equation, not the likelihood): on a model choice's
 * training subsample (17,334 observations) of linear JPEGs declared
 * linear, freeing the true curve raised the negative log-likelihood from
 * -226481 to -217664 (the top slope at its bound). */
/* The log scale by which a curve's values meet the identity's at the
 * level (the scale of the identity's values is the starts' reference). */
static double meet_shift(double level, const double *slopes) {
  return log(cf_response_model_inverse(slopes, NULL, exp(level), NULL)) - level;
}

static cf_status one_start(start_run *run, const fit_plan *plan, const double *slopes,
                           const double *params, double log_scale, cf_error *err) {
  fit_values *v = fit_problem_values(run->sub);
  memcpy(v->params, params, sizeof v->params);
  memcpy(v->response, slopes, sizeof v->response);
  v->log_scale = log_scale + (plan->scale ? meet_shift(run->level, slopes) : 0.0);
  fit_plan held = *plan;
  held.response = 0;
  cf_status s = solve_start(run, &held, err);
  if (s == CF_OK) s = consider(run, err);
  if (s == CF_OK) s = solve_start(run, plan, err);
  if (s == CF_OK) s = consider(run, err);
  return s;
}

cf_status fit_response_starts(const cf_capture *capture, const fit_population *population,
                              const cf_fit_options *o, const fit_plan *plan, double sigma,
                              double *params, double *log_scale, double *response, cf_error *err) {
  cf_capture_summary about;
  cf_capture_summarize(capture, &about);
  if (!about.tone_curve_unknown || o->no_response_starts) return CF_OK;
  start_run run = {.capture = capture, .o = o, .sigma = sigma, .best = HUGE_VAL};
  fit_sample sample;
  cf_status s =
      fit_sample_problem(&run.sub, &sample, capture, o->model, population, START_TARGET, err);
  if (s != CF_OK) return s;
  fit_plan free_curve = *plan;
  free_curve.response = 1;
  run.level = mean_log_level(run.sub);
  /* a given start's curve (the model choice's candidate's) is one of the
   * shapes; the refined values are the identity's either way */
  const double *given = o->use_start ? response : NULL;
  double shapes[2 + CF_RESPONSE_COUNT][K];
  int starts = start_shapes(&about, given, shapes);
  for (int k = 0; s == CF_OK && k < starts; ++k)
    s = one_start(&run, &free_curve, shapes[k], params, *log_scale, err);
  if (s == CF_OK && run.best < HUGE_VAL) {
    memcpy(params, run.best_params, sizeof run.best_params);
    *log_scale = run.best_log_scale;
    memcpy(response, run.best_response, sizeof run.best_response);
  }
  fit_problem_free(run.sub);
  fit_sample_free(&sample);
  return s;
}
