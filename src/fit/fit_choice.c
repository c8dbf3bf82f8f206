/* The choice of the model (clayfit fit --model auto; include/clayfit/fit.h
 * states the rule): every candidate fitted to the training part of a
 * sample, scored by BIC on it and by the RMS without the robust loss on
 * the held-out part, decided by the walk up the ladder, the held-out guard
 * and the physical reading, and the chosen one fitted to every observation
 * from its candidate fit. */
#include "fit_choice.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clayfit/model.h"
#include "core/clock.h"
#include "fit_gains.h"
#include "fit_outcome.h"
#include "fit_plan.h"
#include "fit_problem.h"
#include "fit_residuals.h"
#include "fit_run.h"
#include "core/parallel.h"

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
  /* a guard: 16 observations are 48 residuals, above M4T's 12 unknowns; every fourth held out */
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

/* A candidate's solves stop when a step changes the cost by less than
 * this, relative (the fit's own: 1e-10): about 0.1 σ² on DiLiGenT's
 * training part (10⁵), where the choice's margins are a BIC of 10 (a cost
 * of 5) and 1 % of the held-out error. Measured there: 0.84× the CPU time
 * of the whole fit, the same choice, held-out errors within 0.06 %. */
#define FIT_CANDIDATE_TOLERANCE 1e-6

/* The candidates, simplest first. A new rung is one line here: its place
 * in the walk, and `physical` for a single tailed lobe (M2T) that is the
 * simpler reading of M4's stacked lobes. */
static const fit_choice_rung rungs[] = {
    {CF_MODEL_LAMBERT, 0},           {CF_MODEL_OREN_NAYAR, 0}, {CF_MODEL_DIELECTRIC, 0},
    {CF_MODEL_DIELECTRIC_TAILED, 1}, {CF_MODEL_CLEARCOAT, 0},  {CF_MODEL_CLAY, 0},
    {CF_MODEL_CLAY_TAILED, 0},
};

const fit_choice_rung *fit_choice_rungs(int *count) {
  *count = (int)(sizeof rungs / sizeof rungs[0]);
  return rungs;
}

/* Fit every candidate to the training part: side by side, each on one
 * thread, when the options give two threads or more (the candidates are
 * independent; a fit's result does not depend on its threads beyond the
 * order of its sums). Each tailed twin starts from its GGX twin's fit with
 * the tail at GGX's 2, so that it starts where its twin ended and can only
 * do better (from its own multi-start, M4T ended 12 % above M4's BIC on
 * DiLiGenT, short of its minimum): it runs right after its twin, in the
 * same work item; but the richest model's twin, whose own twin finishes
 * last, runs alone afterwards on every thread (DiLiGenT: M4T then takes
 * 0.12 s instead of 0.21 s, the choice 1.3 s instead of 1.4 s). */
typedef struct candidate_work {
  const cf_capture *capture;
  const cf_fit_options *options;
  const fit_population *train;
  cf_fit_choice *choice;
  int side_by_side;
  int order[CF_FIT_MAX_CANDIDATES]; /* each work item's candidate */
  int then[CF_FIT_MAX_CANDIDATES];  /* and the one after it in the item, or −1 */
} candidate_work;

/* The candidate of `choice` that fits `model`, or NULL. */
static const cf_fit_candidate *candidate_of(const cf_fit_choice *choice, cf_model_id model) {
  for (int i = 0; i < choice->count; ++i)
    if (choice->candidate[i].model == model) return &choice->candidate[i];
  return NULL;
}

static void fit_one_candidate(candidate_work *w, int k) {
  cf_fit_candidate *c = &w->choice->candidate[k];
  const cf_model_info *info = cf_model_info_get(c->model);
  cf_fit_options o = w->options[c->model];
  o.model = c->model;
  o.progress = NULL;
  o.jpeg_plain = 1;         /* the candidates are scored on the photos as they are */
  o.no_response_starts = 1; /* (the chosen model's fit tries the curve's shapes once) */
  if (w->side_by_side) o.threads = 1;
  const cf_fit_candidate *twin =
      info->tail_slot >= 0 ? candidate_of(w->choice, info->ggx_twin) : NULL;
  if (twin && twin->ok && !o.use_start) {
    o.use_start = 1;
    memcpy(o.start, twin->fit.params, sizeof o.start);
    o.start[info->tail_slot] = o.hold[info->tail_slot] ? o.hold_value[info->tail_slot] : 2.0;
    o.start_scale = twin->fit.scale;
    memcpy(o.start_response, twin->fit.response, sizeof o.start_response);
  }
  cf_error err = {0};
  double clock = cf_now_seconds();
  cf_status s =
      fit_run_population(w->capture, w->train, &o, FIT_CANDIDATE_TOLERANCE, &c->fit, &err);
  c->seconds = cf_now_seconds() - clock;
  c->ok = s == CF_OK;
  if (!c->ok) snprintf(c->note, sizeof c->note, "not a candidate: %.200s", err.message);
}

static void fit_candidate_item(void *user, int i) {
  candidate_work *w = user;
  fit_one_candidate(w, w->order[i]);
  if (w->then[i] >= 0) fit_one_candidate(w, w->then[i]);
}

/* The candidate whose model is `model`'s tailed twin, or −1. */
static int tailed_twin_of(const cf_fit_choice *choice, cf_model_id model) {
  for (int i = 0; i < choice->count; ++i) {
    const cf_model_info *info = cf_model_info_get(choice->candidate[i].model);
    if (info->tail_slot >= 0 && info->ggx_twin == model) return i;
  }
  return -1;
}

static void fit_candidates(const cf_capture *capture, const cf_fit_options options[],
                           const fit_population *train, cf_fit_choice *choice) {
  const cf_fit_options *first = &options[0];
  int threads = fit_threads(first);
  const fit_choice_rung *r = fit_choice_rungs(&choice->count);
  for (int i = 0; i < choice->count; ++i) {
    choice->candidate[i].model = r[i].model;
    choice->candidate[i].physical = r[i].physical;
  }
  candidate_work work = {capture, options, train, choice, threads >= 2, {0}, {0}};
  if (first->progress)
    first->progress(first->progress_user, "choosing the model", 0, (size_t)choice->count);
  int n = 0, last = -1;
  for (int i = choice->count - 1; i >= 0; --i) { /* the richest, slowest first */
    if (cf_model_info_get(choice->candidate[i].model)->tail_slot >= 0) continue;
    int twin = tailed_twin_of(choice, choice->candidate[i].model);
    if (n == 0) last = twin;
    work.order[n] = i;
    work.then[n] = n == 0 ? -1 : twin; /* the first's twin runs last */
    ++n;
  }
  cf_parallel_for(n, threads, fit_candidate_item, &work);
  if (last >= 0) {
    work.side_by_side = 0;
    work.order[0] = last;
    work.then[0] = -1;
    cf_parallel_for(1, threads, fit_candidate_item, &work);
  }
  if (first->progress)
    first->progress(first->progress_user, "choosing the model", (size_t)choice->count,
                    (size_t)choice->count);
}

/* One candidate's scores on the training and held-out parts. */
typedef struct score_work {
  const cf_capture *capture;
  const fit_population *train, *test;
  cf_fit_choice *choice;
  cf_fit_options train_options; /* BIC: the fits' own loss */
  cf_fit_options test_options;  /* held out: no robust loss */
  cf_status status[CF_FIT_MAX_CANDIDATES];
  cf_error err[CF_FIT_MAX_CANDIDATES];
} score_work;

static void score_candidate(void *user, int i) {
  score_work *w = user;
  cf_fit_candidate *c = &w->choice->candidate[i];
  cf_error *err = &w->err[i];
  w->status[i] = CF_OK;
  if (!c->ok) return; /* not a candidate: nothing to score */
  double train_cost, test_cost, train_log_sigma, test_log_sigma;
  cf_fit_result on_train, on_test;
  cf_status s = fit_score_at(w->capture, w->train, &c->fit, w->choice->sigma, &w->train_options,
                             &train_cost, &train_log_sigma, &on_train, err);
  if (s == CF_OK) {
    cf_fit_result_free(&on_train);
    s = fit_score_at(w->capture, w->test, &c->fit, w->choice->sigma, &w->test_options, &test_cost,
                     &test_log_sigma, &on_test, err);
  }
  w->status[i] = s;
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

/* BIC (the fits' own loss: what they minimised) and the held-out RMS
 * (no robust loss: what they predict) at the common σ, the candidates
 * side by side; the first failure in ladder order is the
 * one reported. */
static cf_status score_candidates(const cf_capture *capture, const fit_population *train,
                                  const fit_population *test, int threads, cf_fit_choice *choice,
                                  cf_error *err) {
  int has_noise = fit_capture_has_noise(capture);
  choice->sigma = 0.0;
  for (int i = 0; i < choice->count && !has_noise; ++i) {
    const cf_fit_candidate *c = &choice->candidate[i];
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
  cf_fit_default_options(&w->train_options, CF_MODEL_LAMBERT);
  w->train_options.loss = choice->loss;
  w->train_options.loss_scale = choice->loss_scale;
  w->train_options.threads = threads >= 2 ? 1 : threads; /* each candidate on one thread */
  w->test_options = w->train_options;
  w->test_options.loss = CF_LOSS_NONE;
  cf_parallel_for(choice->count, threads, score_candidate, w);
  cf_status s = CF_OK;
  for (int i = 0; i < choice->count && s == CF_OK; ++i)
    if (w->status[i] != CF_OK) {
      s = w->status[i];
      *err = w->err[i];
    }
  free(w);
  return s;
}

/* ---- the decision ---- */

static const char *code_of(const cf_fit_candidate *c) {
  return cf_model_info_get(c->model)->code;
}

/* 1. Up the ladder: a richer model replaces the choice only when clearly
 * better on both scores. */
static int walk_ladder(cf_fit_choice *choice) {
  int best = -1;
  for (int i = 0; i < choice->count; ++i) {
    cf_fit_candidate *c = &choice->candidate[i];
    if (!c->ok) continue;
    if (best < 0) {
      best = i;
      snprintf(c->note, sizeof c->note, "the simplest model that could be fitted");
      continue;
    }
    const cf_fit_candidate *b = &choice->candidate[best];
    double dbic = b->bic - c->bic;
    double gain = 1.0 - c->heldout_score / b->heldout_score;
    if (dbic > choice->bic_margin && gain > choice->heldout_margin) {
      snprintf(c->note, sizeof c->note,
               "clearly better than %s: BIC lower by %.4g, held-out error lower by %.3g %%",
               code_of(b), dbic, 100.0 * gain);
      best = i;
    } else {
      snprintf(c->note, sizeof c->note,
               "not clearly better than %s: BIC lower by %.4g (needs > %g), held-out error lower "
               "by %.3g %% (needs > %g %%)",
               code_of(b), dbic, choice->bic_margin, 100.0 * gain, 100.0 * choice->heldout_margin);
    }
  }
  return best;
}

/* 2. The guard: never a held-out error more than heldout_guard above the
 * lowest, unless the BIC says so. */
static int guard_heldout(cf_fit_choice *choice, int best) {
  double lowest = INFINITY;
  for (int i = 0; i < choice->count; ++i)
    if (choice->candidate[i].ok && choice->candidate[i].heldout_score < lowest)
      lowest = choice->candidate[i].heldout_score;
  cf_fit_candidate *b = &choice->candidate[best];
  double limit = (1.0 + choice->heldout_guard) * lowest;
  if (!(b->heldout_score > limit)) return best;
  int a = 0; /* the simplest within the guard (the lowest is) */
  while (!choice->candidate[a].ok || !(choice->candidate[a].heldout_score <= limit)) ++a;
  cf_fit_candidate *c = &choice->candidate[a];
  double above = 100.0 * (b->heldout_score / c->heldout_score - 1.0);
  double dbic = c->bic - b->bic;
  char walk[320]; /* the walk's note of the one that loses */
  if (dbic > choice->bic_margin) {
    snprintf(walk, sizeof walk, "%s", b->note);
    snprintf(b->note, sizeof b->note,
             "kept although its held-out error is %.3g %% above %s's (more than %g %%): its BIC "
             "is lower by %.4g (more than %g: strong evidence from the training part); %.120s",
             above, code_of(c), 100.0 * choice->heldout_guard, dbic, choice->bic_margin, walk);
    return best;
  }
  snprintf(walk, sizeof walk, "%s", c->note);
  snprintf(c->note, sizeof c->note,
           "chosen over %s, whose held-out error is %.3g %% above this one's (more than %g %%) "
           "and whose BIC is not lower by more than %g (by %.4g); %.120s",
           code_of(b), above, 100.0 * choice->heldout_guard, choice->bic_margin, dbic, walk);
  return a;
}

int fit_choice_stacked_lobes(const cf_fit_result *fit, char *why, size_t size) {
  int rough, f0;
  const cf_param_info *info;
  cf_error ignored = {0};
  if (cf_model_param_find(fit->model, "film_roughness", &rough, &info, &ignored) != CF_OK ||
      cf_model_param_find(fit->model, "film_f0", &f0, &info, &ignored) != CF_OK)
    return 0;
  int held = fit->status[f0] == CF_PARAM_HELD || fit->status[f0] == CF_PARAM_HELD_FOR_SCALE;
  int too_rough = fit->params[rough] > CF_FIT_FILM_MAX_ROUGHNESS;
  int too_bright = !held && fit->params[f0] > CF_FIT_FILM_MAX_F0;
  if (why && too_rough && too_bright)
    snprintf(why, size, "film roughness %.3g > %g and film F0 %.3g > %g", fit->params[rough],
             CF_FIT_FILM_MAX_ROUGHNESS, fit->params[f0], CF_FIT_FILM_MAX_F0);
  else if (why && too_rough)
    snprintf(why, size, "film roughness %.3g > %g (no liquid film is that rough)",
             fit->params[rough], CF_FIT_FILM_MAX_ROUGHNESS);
  else if (why && too_bright)
    snprintf(why, size, "film F0 %.3g > %g (water 0.02, oil 0.035)", fit->params[f0],
             CF_FIT_FILM_MAX_F0);
  return too_rough || too_bright;
}

/* 3. A model whose film is a second lobe gives way to the simpler
 * physical reading (the first candidate marked so) when that one does as
 * well within the margins. */
static int prefer_physical(cf_fit_choice *choice, int best) {
  cf_fit_candidate *b = &choice->candidate[best];
  char why[160];
  if (!fit_choice_stacked_lobes(&b->fit, why, sizeof why)) return best;
  for (int i = 0; i < choice->count; ++i) {
    cf_fit_candidate *c = &choice->candidate[i];
    if (i == best || !c->ok || !c->physical) continue;
    double above = c->heldout_score / b->heldout_score - 1.0, dbic = c->bic - b->bic;
    if (above > choice->heldout_margin || dbic > choice->bic_margin) continue;
    snprintf(c->note, sizeof c->note,
             "the simpler physical reading: %s's film is a second lobe (%s), and this does as "
             "well within the margins (held-out error %+.3g %%, BIC %+.4g)",
             code_of(b), why, 100.0 * above, dbic);
    return i;
  }
  return best;
}

/* A tailed choice: what GGX's lobe would cost, from its GGX twin's row
 * (the held-out RMS without the loss; no extra fit). */
static void state_ggx_cost(cf_fit_choice *choice, const cf_fit_candidate *chosen) {
  choice->ggx_cost = NAN;
  const cf_model_info *info = cf_model_info_get(chosen->model);
  const cf_fit_candidate *twin = info->tail_slot >= 0 ? candidate_of(choice, info->ggx_twin) : NULL;
  if (!twin || !twin->ok || !(chosen->heldout_score > 0.0)) return;
  choice->ggx_cost = twin->heldout_score / chosen->heldout_score - 1.0;
  snprintf(choice->ggx_cost_text, sizeof choice->ggx_cost_text,
           "GGX would cost %.3g %%: %s, the same model with GGX's lobe, predicts the held-out "
           "part with a %.3g %% %s RMS",
           100.0 * choice->ggx_cost, cf_model_info_get(twin->model)->code,
           100.0 * fabs(choice->ggx_cost), choice->ggx_cost >= 0.0 ? "larger" : "smaller");
}

void fit_choice_decide(cf_fit_choice *choice) {
  int best = walk_ladder(choice);
  if (best < 0) return;
  best = guard_heldout(choice, best);
  best = prefer_physical(choice, best);
  for (int i = 0; i < choice->count; ++i) choice->candidate[i].chosen = i == best;
  choice->chosen = choice->candidate[best].model;
  state_ggx_cost(choice, &choice->candidate[best]);
}

const cf_fit_candidate *cf_fit_choice_chosen(const cf_fit_choice *choice) {
  for (int i = 0; i < choice->count; ++i)
    if (choice->candidate[i].chosen) return &choice->candidate[i];
  return NULL;
}

int cf_fit_reading(const cf_fit_result *result, char *text, size_t size) {
  char why[160];
  if (!fit_choice_stacked_lobes(result, why, sizeof why)) return 0;
  const char *code = cf_model_info_get(result->model)->code;
  snprintf(text, size, "%s's film parameters describe a second specular lobe, not a film: %s", code,
           why);
  return 1;
}

/* What the chosen fit's parameters mean where not what they are named
 * after (rule 3's output). */
static void state_reading(cf_fit_choice *choice, const cf_fit_result *result) {
  cf_fit_reading(result, choice->reading, sizeof choice->reading);
}

/* The candidates fitted on a training split and scored on held-out
 * images, and the rule's choice (choice->chosen). */
static cf_status choose(const cf_capture *capture, const cf_fit_options options[CF_MODEL_COUNT],
                        cf_fit_choice *choice, cf_error *err) {
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
  if (s == CF_OK) fit_choice_decide(choice);
  split_free(&split);
  choice->seconds = cf_now_seconds() - clock;
  return s;
}

/* The chosen model on every observation (the budget's, drawn before, when
 * its options draw the same), from its candidate fit. */
static cf_status fit_chosen(const cf_capture *capture, const cf_fit_options options[CF_MODEL_COUNT],
                            const fit_budget *budget, cf_fit_choice *choice,
                            cf_fit_result *result, cf_error *err) {
  const cf_fit_candidate *c = cf_fit_choice_chosen(choice);
  cf_fit_options o = options[c->model];
  o.model = c->model;
  o.use_start = 1;
  memcpy(o.start, c->fit.params, sizeof o.start);
  o.start_scale = c->fit.scale;
  memcpy(o.start_response, c->fit.response, sizeof o.start_response);
  cf_status s = fit_budget_same(&o, &options[CF_MODEL_LAMBERT])
                    ? fit_run_budget(capture, budget, &o, result, err)
                    : cf_fit_run(capture, &o, result, err);
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
  state_reading(choice, result);
  return CF_OK;
}

cf_status cf_fit_auto(const cf_capture *capture, const cf_fit_options options[CF_MODEL_COUNT],
                      cf_fit_choice *choice, cf_fit_result *result, cf_error *err) {
  memset(choice, 0, sizeof *choice);
  memset(result, 0, sizeof *result);
  choice->automatic = 1;
  choice->bic_margin = CF_FIT_CHOICE_BIC_MARGIN;
  choice->heldout_margin = CF_FIT_CHOICE_HELDOUT_MARGIN;
  choice->heldout_guard = CF_FIT_CHOICE_HELDOUT_GUARD;
  choice->loss = options[0].loss;
  choice->loss_scale = options[0].loss_scale;
  if (cf_capture_observations(capture)->count == 0)
    return cf_error_set(err, CF_EINVAL, "the capture has no observations to fit");
  /* the pixel budget, drawn once; the gains told from the material before
   * any fit (the albedo's trade, which every model of the ladder has:
   * M0's) */
  fit_budget budget;
  cf_status s = fit_budget_for(capture, &options[CF_MODEL_LAMBERT], &budget, err);
  if (s == CF_OK) s = fit_check_gains(capture, &options[CF_MODEL_LAMBERT], &budget, err);
  if (s == CF_OK) s = choose(capture, options, choice, err);
  if (s == CF_OK) s = fit_chosen(capture, options, &budget, choice, result, err);
  fit_budget_free(&budget);
  if (s == CF_OK && (s = fit_check_constrained(result, err)) != CF_OK)
    cf_fit_result_free(result);
  return s;
}

void cf_fit_choice_free(cf_fit_choice *choice) {
  for (int i = 0; i < choice->count; ++i)
    if (choice->candidate[i].ok) cf_fit_result_free(&choice->candidate[i].fit);
  choice->count = 0;
}
