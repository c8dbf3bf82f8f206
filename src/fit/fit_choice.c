/* The choice of the model (clayfit fit --model auto; include/clayfit/fit.h
 * states the rule): every model of the ladder fitted to the training part
 * of a sample, scored by BIC on it and by the robust RMS on the held-out
 * part, the simplest model kept unless a richer one is clearly better on
 * both, and the chosen one fitted to every observation from its candidate
 * fit. */
#include "clayfit/fit.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/clock.h"
#include "lsq/parallel.h"
#include "fit_plan.h"
#include "fit_problem.h"
#include "fit_residuals.h"
#include "fit_run.h"

/* The sample (every stride-th observation, at most CF_FIT_CHOICE_SAMPLE)
 * split into a training and a held-out part; `heldout` says how. */
typedef struct choice_split {
  uint32_t *train, *test;
  size_t train_count, test_count;
} choice_split;

static cf_status split_sample(const cf_capture *capture, const unsigned char *use_image,
                              int exposures_fitted, choice_split *split, char *heldout,
                              size_t heldout_size, cf_error *err) {
  const cf_observations *obs = cf_capture_observations(capture);
  size_t images = cf_capture_image_count(capture);
  size_t stride = (obs->count + CF_FIT_CHOICE_SAMPLE - 1) / CF_FIT_CHOICE_SAMPLE;
  if (stride == 0) stride = 1;
  size_t n = (obs->count + stride - 1) / stride;
  memset(split, 0, sizeof *split);
  split->train = malloc((n ? n : 1) * sizeof *split->train);
  split->test = malloc((n ? n : 1) * sizeof *split->test);
  if (!split->train || !split->test) return cf_error_set(err, CF_ENOMEM, "out of memory");
  /* held-out images need their exposures known: with fitted exposures
   * (or one image) observations are held out instead */
  int by_image = !exposures_fitted && images >= 2;
  if (by_image && images >= 4)
    snprintf(heldout, heldout_size, "every fourth image (images 4, 8, ...; %zu of %zu)", images / 4,
             images);
  else if (by_image)
    snprintf(heldout, heldout_size, "the last image (%zu of %zu)", images, images);
  else
    snprintf(heldout, heldout_size, "every fourth observation of the sample%s",
             exposures_fitted ? " (the exposures are fitted, so no image is held out)" : "");
  for (size_t j = 0, i = 0; i < obs->count; i += stride, ++j) {
    size_t k = obs->image[i];
    if (use_image && !use_image[k]) continue;
    int test = !by_image ? j % 4 == 3 : images >= 4 ? k % 4 == 3 : k == images - 1;
    if (test)
      split->test[split->test_count++] = (uint32_t)i;
    else
      split->train[split->train_count++] = (uint32_t)i;
  }
  if (split->train_count < 16 || split->test_count < 4)
    return cf_error_set(err, CF_EINVAL,
                        "too few observations to choose the model (%zu for training, %zu held "
                        "out): give --model",
                        split->train_count, split->test_count);
  return CF_OK;
}

static void split_free(choice_split *split) {
  free(split->train);
  free(split->test);
}

/* Fit every candidate to the training part: side by side, each on one
 * thread, when the options give two threads or more (the candidates are
 * independent; a fit's result does not depend on its threads beyond the
 * order of its sums). */
typedef struct candidate_work {
  const cf_capture *capture;
  const cf_fit_options *options;
  const fit_population *train;
  cf_fit_choice *choice;
  int side_by_side;
} candidate_work;

static void fit_candidate(void *user, int i) {
  candidate_work *w = user;
  int m = CF_MODEL_COUNT - 1 - i; /* the richest, slowest first */
  cf_fit_candidate *c = &w->choice->candidate[m];
  c->model = (cf_model_id)m;
  cf_fit_options o = w->options[m];
  o.model = (cf_model_id)m;
  o.progress = NULL;
  o.jpeg_plain = 1;         /* the candidates are scored on the photos as they are */
  o.no_response_starts = 1; /* (the chosen model's fit tries the curve's shapes once) */
  if (w->side_by_side) o.threads = 1;
  cf_error err = {0};
  double clock = cf_now_seconds();
  cf_status s = fit_run_population(w->capture, w->train, &o, &c->fit, &err);
  c->seconds = cf_now_seconds() - clock;
  c->ok = s == CF_OK;
  if (!c->ok) snprintf(c->note, sizeof c->note, "not a candidate: %.200s", err.message);
}

static void fit_candidates(const cf_capture *capture, const cf_fit_options options[],
                           const fit_population *train, cf_fit_choice *choice) {
  const cf_fit_options *first = &options[0];
  int threads = fit_threads(first);
  candidate_work work = {capture, options, train, choice, threads >= 2};
  if (first->progress)
    first->progress(first->progress_user, "choosing the model", 0, CF_MODEL_COUNT);
  cf_parallel_for(CF_MODEL_COUNT, threads, fit_candidate, &work);
  if (first->progress)
    first->progress(first->progress_user, "choosing the model", CF_MODEL_COUNT, CF_MODEL_COUNT);
  choice->count = CF_MODEL_COUNT;
}

/* One candidate's scores on the training and held-out parts. */
typedef struct score_work {
  const cf_capture *capture;
  const fit_population *train, *test;
  cf_fit_choice *choice;
  cf_fit_options options; /* the loss of the scores */
  cf_status status[CF_MODEL_COUNT];
  cf_error err[CF_MODEL_COUNT];
} score_work;

static void score_candidate(void *user, int m) {
  score_work *w = user;
  cf_fit_candidate *c = &w->choice->candidate[m];
  cf_error *err = &w->err[m];
  w->status[m] = CF_OK;
  if (!c->ok) return; /* not a candidate: nothing to score */
  double train_cost, test_cost, train_log_sigma, test_log_sigma;
  cf_fit_result on_train, on_test;
  cf_status s = fit_score_at(w->capture, w->train, &c->fit, w->choice->sigma, &w->options,
                             &train_cost, &train_log_sigma, &on_train, err);
  if (s == CF_OK) {
    cf_fit_result_free(&on_train);
    s = fit_score_at(w->capture, w->test, &c->fit, w->choice->sigma, &w->options, &test_cost,
                     &test_log_sigma, &on_test, err);
  }
  w->status[m] = s;
  if (s != CF_OK) return;
  size_t train_n = on_train.residuals + on_train.censored;
  c->heldout_residuals = on_test.residuals + on_test.censored;
  c->parameters = c->fit.free_unknowns;
  c->residuals = train_n;
  c->cost = train_cost;
  /* −2 log L with the Gaussian's 2 Σ log σ where σ depends on the fit (a
   * fitted response curve carries the noise model: fit_score_at), else
   * 0; the held-out RMS then times σ's geometric mean, so that a curve
   * cannot lower either score by stretching σ (docs/fitting.md "Response
   * curve") */
  c->bic = 2.0 * train_cost + 2.0 * train_log_sigma + c->parameters * log((double)train_n);
  c->heldout_score = sqrt(2.0 * test_cost / (double)c->heldout_residuals);
  if (test_log_sigma != 0.0 && on_test.residuals)
    c->heldout_score *= exp(test_log_sigma / (double)on_test.residuals);
  c->heldout_rmse = on_test.residuals ? on_test.rmse : NAN;
  c->heldout_relative_rmse = on_test.relative_rmse;
  cf_fit_result_free(&on_test);
}

/* BIC and the held-out scores at the common σ, the candidates side by
 * side; the first failure in ladder order is the one reported. */
static cf_status score_candidates(const cf_capture *capture, const fit_population *train,
                                  const fit_population *test, int threads, cf_fit_choice *choice,
                                  cf_error *err) {
  int has_noise = fit_capture_has_noise(capture);
  choice->sigma = 0.0;
  for (int m = 0; m < choice->count && !has_noise; ++m) {
    const cf_fit_candidate *c = &choice->candidate[m];
    if (c->ok && c->fit.sigma > 0.0 && (choice->sigma == 0.0 || c->fit.sigma < choice->sigma))
      choice->sigma = c->fit.sigma;
  }
  if (!has_noise && !(choice->sigma > 0.0))
    return cf_error_set(err, CF_ENUMERIC, "no model of the ladder could be fitted to choose from");
  score_work *w = calloc(1, sizeof *w);
  if (!w) return cf_error_set(err, CF_ENOMEM, "out of memory");
  w->capture = capture;
  w->train = train;
  w->test = test;
  w->choice = choice;
  cf_fit_default_options(&w->options, CF_MODEL_LAMBERT);
  w->options.loss = choice->loss;
  w->options.loss_scale = choice->loss_scale;
  w->options.threads = threads >= 2 ? 1 : threads; /* each candidate on one thread */
  cf_parallel_for(choice->count, threads, score_candidate, w);
  cf_status s = CF_OK;
  for (int m = 0; m < choice->count && s == CF_OK; ++m)
    if (w->status[m] != CF_OK) {
      s = w->status[m];
      *err = w->err[m];
    }
  free(w);
  return s;
}

/* Up the ladder: a richer model replaces the choice only when clearly
 * better on both scores. */
static void walk_ladder(cf_fit_choice *choice) {
  int best = -1;
  for (int m = 0; m < choice->count; ++m) {
    cf_fit_candidate *c = &choice->candidate[m];
    if (!c->ok) continue;
    if (best < 0) {
      best = m;
      snprintf(c->note, sizeof c->note, "the simplest model that could be fitted");
      continue;
    }
    const cf_fit_candidate *b = &choice->candidate[best];
    const char *code = cf_model_info_get(b->model)->code;
    double dbic = b->bic - c->bic;
    double gain = 1.0 - c->heldout_score / b->heldout_score;
    int better_bic = dbic > choice->bic_margin;
    int better_test = gain > choice->heldout_margin;
    if (better_bic && better_test) {
      snprintf(c->note, sizeof c->note,
               "clearly better than %s: BIC lower by %.4g, held-out error lower by %.3g %%", code,
               dbic, 100.0 * gain);
      best = m;
    } else {
      snprintf(c->note, sizeof c->note,
               "not clearly better than %s: BIC lower by %.4g (needs > %g), held-out error lower "
               "by %.3g %% (needs > %g %%)",
               code, dbic, choice->bic_margin, 100.0 * gain, 100.0 * choice->heldout_margin);
    }
  }
  choice->chosen = (cf_model_id)best;
  choice->candidate[best].chosen = 1;
}

cf_status cf_fit_auto(const cf_capture *capture, const cf_fit_options options[CF_MODEL_COUNT],
                      cf_fit_choice *choice, cf_fit_result *result, cf_error *err) {
  memset(choice, 0, sizeof *choice);
  memset(result, 0, sizeof *result);
  choice->automatic = 1;
  choice->bic_margin = CF_FIT_CHOICE_BIC_MARGIN;
  choice->heldout_margin = CF_FIT_CHOICE_HELDOUT_MARGIN;
  choice->loss = options[0].loss;
  choice->loss_scale = options[0].loss_scale;
  if (cf_capture_observations(capture)->count == 0)
    return cf_error_set(err, CF_EINVAL, "the capture has no observations to fit");
  /* the gains told from the material before any fit (the albedo's trade,
   * which every model of the ladder has: M0's) */
  cf_status gains = cf_fit_check_gains(capture, &options[CF_MODEL_LAMBERT], err);
  if (gains != CF_OK) return gains;
  double clock = cf_now_seconds();
  int exposures = 0;
  for (int m = 0; m < CF_MODEL_COUNT; ++m) exposures |= options[m].fit_exposures;
  choice_split split;
  cf_status s = split_sample(capture, options[0].use_image, exposures, &split, choice->heldout,
                             sizeof choice->heldout, err);
  fit_population train = {split.train, split.train_count, NULL},
                 test = {split.test, split.test_count, NULL};
  choice->train_observations = split.train_count;
  choice->heldout_observations = split.test_count;
  if (s == CF_OK) {
    fit_candidates(capture, options, &train, choice);
    s = score_candidates(capture, &train, &test, fit_threads(&options[0]), choice, err);
  }
  if (s == CF_OK) walk_ladder(choice);
  split_free(&split);
  choice->seconds = cf_now_seconds() - clock;
  if (s != CF_OK) return s;

  /* the chosen model on every observation, from its candidate fit */
  const cf_fit_candidate *c = &choice->candidate[choice->chosen];
  cf_fit_options o = options[choice->chosen];
  o.model = choice->chosen;
  o.use_start = 1;
  memcpy(o.start, c->fit.params, sizeof o.start);
  o.start_scale = c->fit.scale;
  memcpy(o.start_response, c->fit.response, sizeof o.start_response);
  s = cf_fit_run(capture, &o, result, err);
  if (s != CF_OK) return s;
  result->starts = c->fit.starts;
  memcpy(result->start, c->fit.start, sizeof result->start);
  result->best_start = c->fit.best_start;
  result->ambiguous = c->fit.ambiguous;
  for (int i = 0; i < c->fit.warning_count; ++i) {
    int dup = 0;
    for (int j = 0; j < result->warning_count; ++j)
      dup |= !strcmp(result->warnings[j], c->fit.warnings[i]);
    if (!dup) fit_add_warning(result, "%s", c->fit.warnings[i]);
  }
  return CF_OK;
}

void cf_fit_choice_free(cf_fit_choice *choice) {
  for (int m = 0; m < choice->count; ++m)
    if (choice->candidate[m].ok) cf_fit_result_free(&choice->candidate[m].fit);
  choice->count = 0;
}
