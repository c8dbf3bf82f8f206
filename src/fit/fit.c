/* Fitting one model to a capture (include/clayfit/fit.h):
 *   1. the plan: what is free (the model's parameters but those held by
 *      the user, or, for relative radiometry, the interface F0 that sets
 *      the scale; the global scale; the exposures) (fit_plan.c);
 *   2. the closed-form albedo from the least specular observations, then
 *      the deterministic multi-start on a subsample (fit_multistart.c);
 *   3. the best start refined on a larger subsample (with an unknown tone
 *      curve, then the curve's shape from a few starts,
 *      fit_response_starts.c), then on every observation, with the
 *      robust loss and, for a noise model, weights from the prediction to
 *      their fixed point;
 *   4. the covariance; parameters the capture does not constrain are held
 *      at their defaults, named, and the fit repeated (fit_uncertainty.c);
 *   5. the result (fit_outcome.c) and residual statistics
 *      (fit_residuals.c). */
#include "clayfit/fit.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/clock.h"
#include "fit_gains.h"
#include "fit_hidden_base.h"
#include "fit_jpeg.h"
#include "fit_multistart.h"
#include "fit_outcome.h"
#include "fit_plan.h"
#include "fit_problem.h"
#include "fit_residuals.h"
#include "fit_response_starts.h"
#include "fit_run.h"
#include "fit_sample.h"
#include "fit_uncertainty.h"

/* The best start refines on about REFINE_TARGET observations before all of
 * them (each stage starts closer, where iterations cost more). The loops'
 * bounds: rounds used counted over the fit tests' fits (studies/2026-12-07-tuned-constants.md). */
enum {
  REFINE_TARGET = 40000,        /* without it: 10 of 29 fits move, M4 on every obs. 2.15x CPU */
  MAX_UNCONSTRAINED_ROUNDS = 4, /* a bound: 2 rounds at most in 915 fits */
  REWEIGHT_ROUNDS = 4,          /* ends 14 of 810 reweighted solves (fd063f4; not measured) */
  FOOTPRINT_ROUNDS = 3,         /* a bound: never a third round in the fit tests */
  TAU_ROUNDS = 4                /* sigma_through_curve; a bound: τ settles in 3 rounds at most */
};

void cf_fit_default_options(cf_fit_options *o, cf_model_id model) {
  memset(o, 0, sizeof *o);
  o->model = model;
  o->loss = CF_LOSS_HUBER; /* without a loss test_fit_hard_cases' outliers fail */
  o->loss_scale = 3.0; /* Gaussian noise passes 3 σ in 0.27 % of residuals (2 σ: 4.6 %) */
  o->multistart = 1;
  o->max_iterations = 100; /* reached by 14 of 2878 solves in the fit tests (they warn) */
  o->threads = 2;
  o->density = NAN;
  o->footprint = 0;
  o->footprint_tolerance = 2e-3; /* 1e-3: 1.44x CPU on DiLiGenT; 4e-3: a choice M2 -> M3 */
  o->budget = CF_FIT_DEFAULT_BUDGET;
  o->sampling = CF_SAMPLING_STRATIFIED;
}

/* Relative radiometry fixes the scale by holding the interface F0 (0.04
 * unless the user holds another value). When that needs an albedo above
 * its bound 1 (an albedo channel ends at the bound), the assumption is
 * inconsistent with the data; the scale then comes from the albedo
 * instead: the brightest channel at the bound is held at 1 and the F0
 * fitted. Returns 1 when it switched (with a warning). */
static int scale_from_albedo(fit_problem *p, const cf_fit_options *o, fit_plan *plan,
                             cf_fit_result *r) {
  cf_model_id model = fit_problem_model(p);
  int sk = fit_scale_slot(model);
  if (!plan->scale || sk < 0 || plan->status[sk] != CF_PARAM_HELD_FOR_SCALE || o->hold[sk])
    return 0;
  const int *at_bound = fit_problem_read_at_bound(p);
  int albedo = -1;
  for (int u = 0; u < fit_problem_unknown_count(p); ++u) {
    fit_unknown unk = fit_problem_unknown(p, u);
    if (unk.kind == &fit_kind_material && fit_slot_form_of(model, unk.slot) == FIT_SLOT_LOG &&
        at_bound[u] > 0)
      albedo = unk.slot;
  }
  if (albedo < 0) return 0;
  char name[48];
  plan->status[albedo] = CF_PARAM_HELD_FOR_SCALE;
  plan->status[sk] = CF_PARAM_FITTED;
  fit_add_warning(r,
                  "relative radiometry: with the interface F0 held at %g the albedo would exceed "
                  "1, so the scale comes from the albedo instead (%s held at 1, F0 fitted); "
                  "hold F0 (--hold) to choose another assumption",
                  fit_problem_read_values(p)->params[sk],
                  cf_model_slot_name(model, albedo, name, sizeof name));
  return 1;
}

/* Is the problem, solved before and changed since only by new weights or
 * pixel footprints, still at its minimum: the Gauss-Newton decrement
 * below FIT_RESOLVE_DECREMENT and every pinned unknown still held at its
 * bound by the gradient? Then a solve would only confirm it (measured:
 * 0.14-0.17 s of the 16-image capture's 2.2 s solve stage). *settled
 * says so; the pass's normal equations (jtj, every unknown) and cost
 * (summary->final_cost, at the current weights) serve in its place. */
static cf_status settled_at_minimum(fit_problem *p, const cf_fit_options *o, double *jtj,
                                    cf_lsq_summary *summary, int *settled, cf_error *err) {
  *settled = 0;
  if (fit_problem_tally(p)->solves == 0 || fit_problem_unknown_count(p) > FIT_DECREMENT_MOST)
    return CF_OK;
  double g[FIT_DECREMENT_MOST], cost;
  cf_status s = fit_normal_equations(p, fit_threads(o), jtj, g, &cost, err);
  if (s != CF_OK) return s;
  *settled = fit_newton_decrement_from(p, jtj, g) < FIT_RESOLVE_DECREMENT && fit_pins_hold(p, g);
  if (*settled) summary->final_cost = cost;
  return CF_OK;
}

/* Solve the plan's unknowns with reweighting and, once, switch the
 * scale's assumption if the albedo says so (*switched) and solve again. */
static cf_status solve_switching(fit_problem *p, const cf_fit_options *o, fit_plan *plan,
                                 cf_fit_result *r, int *switched, cf_error *err) {
  cf_lsq_summary summary;
  cf_status s = fit_solve_reweighted(p, o, REWEIGHT_ROUNDS, &summary, NULL, err);
  if (s != CF_OK || *switched || !scale_from_albedo(p, o, plan, r)) return s;
  *switched = 1;
  s = fit_declare(p, plan, err);
  if (s == CF_OK) s = fit_solve_reweighted(p, o, REWEIGHT_ROUNDS, &summary, NULL, err);
  return s;
}

/* Refine (params, log_scale) on a subsample of about `target` observations
 * of the population (nothing to do when it has fewer than twice as many):
 * robust loss, and weights from the prediction with a noise model. */
static cf_status refine_on_subsample(const cf_capture *capture, const fit_population *population,
                                     const cf_fit_options *o, fit_plan *plan, size_t target,
                                     double sigma, double *params, double *log_scale,
                                     cf_fit_result *r, int *switched, cf_error *err) {
  if (population->count < 2 * target) return CF_OK;
  fit_sample sample;
  fit_problem *sub;
  cf_status s = fit_sample_problem(&sub, &sample, capture, o->model, population, target, err);
  if (s != CF_OK) return s;
  s = fit_declare_robust(sub, plan, o, sigma, err);
  fit_values *v = fit_problem_values(sub);
  if (s == CF_OK) {
    memcpy(v->params, params, sizeof v->params);
    v->log_scale = *log_scale;
    fit_problem_settings(sub)->newton_start = 1; /* from the best start's minimum */
    s = solve_switching(sub, o, plan, r, switched, err);
  }
  if (s == CF_OK) {
    memcpy(params, v->params, sizeof v->params);
    *log_scale = v->log_scale;
  }
  fit_problem_free(sub);
  fit_sample_free(&sample);
  return s;
}

cf_status cf_fit_check_options(const cf_fit_options *o, cf_error *err) {
  const cf_model_info *m = cf_model_info_get(o->model);
  if (!m) return cf_error_set(err, CF_EINVAL, "invalid model id %d", (int)o->model);
  for (int k = 0; k < m->dim; ++k) {
    const cf_param_info *info = cf_model_slot_param(o->model, k, NULL);
    char name[48];
    cf_model_slot_name(o->model, k, name, sizeof name);
    if (o->hold[k] && (!(o->hold_value[k] >= info->lower) || !(o->hold_value[k] <= info->upper)))
      return cf_error_set(err, CF_ERANGE, "--hold %s=%g is outside its range [%g, %g]", name,
                          o->hold_value[k], info->lower, info->upper);
    if (o->use_start && (!(o->start[k] >= info->lower) || !(o->start[k] <= info->upper)))
      return cf_error_set(err, CF_ERANGE, "the start's %s = %g is outside its range [%g, %g]", name,
                          o->start[k], info->lower, info->upper);
  }
  if (!(o->footprint_tolerance > 0.0 && o->footprint_tolerance < 1.0))
    return cf_error_set(err, CF_ERANGE, "the footprint tolerance %g is not in (0, 1)",
                        o->footprint_tolerance);
  if (o->use_start && !(o->start_scale > 0.0 && isfinite(o->start_scale)))
    return cf_error_set(err, CF_ERANGE, "the start's scale %g is not a positive number",
                        o->start_scale);
  return CF_OK;
}

/* One run of fit_run_population: what its steps share. */
typedef struct fit_run {
  const cf_capture *capture;
  const fit_population *population;
  const cf_fit_options *o;
  double tolerance; /* the solves' (0: the solver's) */
  cf_fit_result *r;
  fit_plan plan;
  fit_problem *p; /* over the whole population */
  cf_lsq_summary summary;
  double sigma; /* one σ for all (no noise model) */
  int has_noise, switched;
  /* the normal equations and the covariance of the unknowns (n² each,
   * room for `normal_capacity` entries) */
  double *jtj, *covariance;
  size_t normal_capacity;
} fit_run;

/* Room in run->jtj and run->covariance for the unknowns declared now. */
static cf_status normal_room(fit_run *run, cf_error *err) {
  size_t n = (size_t)fit_problem_unknown_count(run->p), need = n > 0 ? n * n : 1;
  if (need <= run->normal_capacity) return CF_OK;
  free(run->jtj);
  free(run->covariance);
  run->jtj = malloc(need * sizeof *run->jtj);
  run->covariance = malloc(need * sizeof *run->covariance);
  run->normal_capacity = run->jtj && run->covariance ? need : 0;
  if (!run->normal_capacity)
    return cf_error_set(err, CF_ENOMEM, "out of memory for the normal equations of %zu unknowns",
                        n);
  return CF_OK;
}

/* 2. The start: the multi-start, or the one given (with the response
 * slopes it gives; 1 otherwise). */
static cf_status find_start(fit_run *run, double *params, double *log_scale, double *response,
                            cf_error *err) {
  const cf_fit_options *o = run->o;
  *log_scale = 0.0;
  fit_response_identity(response);
  if (!o->use_start)
    return fit_multistart(run->capture, run->population, o, &run->plan, run->r, params, log_scale,
                          &run->sigma, err);
  memcpy(params, o->start, sizeof o->start);
  for (int k = 0; k < cf_model_info_get(o->model)->dim; ++k)
    if (o->hold[k]) params[k] = o->hold_value[k];
  int sk = fit_scale_slot(o->model); /* the scale's assumption, not the start's F0 */
  if (sk >= 0 && run->plan.status[sk] == CF_PARAM_HELD_FOR_SCALE && !o->hold[sk])
    params[sk] = FIT_SCALE_F0;
  *log_scale = run->plan.scale ? log(o->start_scale) : 0.0;
  for (int j = 0; j < CF_RESPONSE_MODEL_KNOTS; ++j)
    response[j] = o->start_response[j] > 0.0 ? o->start_response[j] : 1.0;
  return fit_start_sigma(run->capture, run->population, o, params, *log_scale, &run->sigma, err);
}

/* The problem over the whole population from the refined values: σ, the
 * robust loss, the response curve when the tone curve is unknown. */
static cf_status full_problem(fit_run *run, const double *params, double log_scale,
                              const double *response, cf_error *err) {
  const cf_fit_options *o = run->o;
  cf_status s = fit_problem_new(&run->p, run->capture, o->model, run->population->index,
                                run->population->count, fit_threads(o), err);
  if (s != CF_OK) return s;
  fit_problem *p = run->p;
  if (run->population->weight) s = fit_problem_set_sample_weights(p, run->population->weight, err);
  fit_values *v = fit_problem_values(p);
  memcpy(v->params, params, sizeof v->params);
  v->log_scale = log_scale;
  /* (the trust region starts anew, not where the refinement's ended: that
   * one ends with Gauss-Newton steps, a radius of 1e10 and more, but every
   * observation and their pixel footprints move the minimum; on DiLiGenT,
   * default budget, the undamped steps then kept 1 % of their promise for
   * 29 iterations while the radius halved, 48 iterations in all where 24
   * reach the same cost) */
  fit_problem_settings(p)->function_tolerance = run->tolerance;
  fit_problem_settings(p)->newton_start = 1; /* from the refinement's (or the best start's) minimum */
  /* an unknown tone curve: the response curve is fitted from here on
   * (the starts and the subsample assume a linear response) */
  cf_capture_summary about;
  cf_capture_summarize(run->capture, &about);
  run->plan.response = about.tone_curve_unknown;
  if (run->plan.response) memcpy(v->response, response, sizeof v->response);
  if (s == CF_OK) s = fit_declare_robust(p, &run->plan, o, run->sigma, err);
  run->has_noise = fit_capture_has_noise(run->capture);
  if (!run->has_noise) run->r->sigma = run->sigma;
  return s;
}

/* Without a noise model, with a response curve: τ, the one σ in linear
 * units (σ = τ R'(x)), from the residuals at the curve, solved for and
 * estimated again until τ moves by less than 1 % (TAU_ROUNDS at most).
 * The start's σ assumed a linear response (on 8-bit sRGB photos declared
 * linear, twice the sRGB declaration's, and so was the albedo's sd), and
 * a τ from a solve at a wrong one (the model choice's final run starts
 * from its candidate's curve and that σ) came out 14 % high
 * (docs/fitting.md "Response curve"). run->sigma stays the start's: the
 * starts' costs, which fit_ambiguous weighs, are in its units. */
static cf_status sigma_through_curve(fit_run *run, cf_error *err) {
  fit_problem *p = run->p;
  double tau = run->sigma, before;
  /* (no floor: at a noise-free float capture's τ, 5e-9, the response's
   * prior is 1e-20 of the data, and still counts: the blocks and the
   * covariance judge rank at a unit diagonal, lsq_blocks.cpp and
   * fit_free_covariance) */
  cf_status s = fit_estimate_sigma(p, &tau, err); /* at the start's curve */
  for (int round = 0; s == CF_OK && round < TAU_ROUNDS; ++round) {
    fit_problem_set_sigma(p, tau);
    s = fit_problem_reweight(p, err);
    if (s == CF_OK) s = fit_solve(p, run->o, run->o->max_iterations, &run->summary, err);
    before = tau;
    if (s == CF_OK) s = fit_estimate_sigma(p, &tau, err);
    if (s != CF_OK || fabs(tau - before) < 0.01 * before) break; /* 1 %: 3ff77a2 */
  }
  if (s == CF_OK) {
    fit_problem_set_sigma(p, tau);
    run->r->sigma = tau;
  }
  return s;
}

/* The pixel footprints at the refined values, which are near the end (the
 * solves below then see them from the start, and the rounds after them
 * seldom change anything); with a noise model, weights from the
 * prediction to their fixed point; then the footprints where a lobe is
 * narrower than a pixel, at the parameters found, until the samples
 * settle. */
static cf_status settle_weights_and_footprints(fit_run *run, cf_error *err) {
  fit_problem *p = run->p;
  const cf_fit_options *o = run->o;
  cf_status s = fit_footprint_update(p, o, NULL, err);
  int weights_current = 0, vary = run->has_noise || fit_problem_sigma_through_curve(p);
  if (s == CF_OK && !run->has_noise && vary) s = sigma_through_curve(run, err);
  if (s == CF_OK && vary)
    s = fit_solve_reweighted(p, o, REWEIGHT_ROUNDS, &run->summary, &weights_current, err);
  if (s == CF_OK && vary && !weights_current) s = fit_problem_reweight(p, err);
  for (int round = 0; s == CF_OK && round < FOOTPRINT_ROUNDS; ++round) {
    int changed = 0;
    s = fit_footprint_update(p, o, &changed, err);
    if (s != CF_OK || !changed) break;
    fit_progress(o, "integrating pixel footprints", (size_t)round, FOOTPRINT_ROUNDS);
    double decrement; /* samples that move nothing need no solve */
    s = fit_newton_decrement(p, o, &decrement, err);
    if (s != CF_OK || decrement < FIT_RESOLVE_DECREMENT) break;
    s = fit_solve(p, o, o->max_iterations, &run->summary, err);
    if (s == CF_OK && vary) s = fit_problem_reweight(p, err);
  }
  return s;
}

/* Does the capture hold a JPEG? Its errors are correlated within the
 * codec's blocks. */
static int capture_has_jpeg(const cf_capture *capture) {
  for (size_t k = 0; k < cf_capture_image_count(capture); ++k)
    if (cf_capture_image_at(capture, k)->jpeg) return 1;
  return 0;
}

/* One round of step 4: solve (unless the first finds the problem settled),
 * switch the scale's assumption if the albedo says so, and the
 * covariance, into run->jtj and run->covariance, with *rank_deficient. */
static cf_status solve_with_covariance(fit_run *run, int round, int *rank_deficient,
                                       cf_error *err) {
  fit_problem *p = run->p;
  const cf_fit_options *o = run->o;
  int settled = 0; /* (jtj then holds the normal equations at the solution) */
  cf_status s = normal_room(run, err);
  if (s == CF_OK && round == 0)
    s = settled_at_minimum(p, o, run->jtj, &run->summary, &settled, err);
  if (s == CF_OK && !settled)
    s = fit_solve_normal(p, o, o->max_iterations, &run->summary, run->jtj, err);
  if (s == CF_OK && !run->switched && scale_from_albedo(p, o, &run->plan, run->r)) {
    run->switched = 1;
    s = fit_declare(p, &run->plan, err);
    if (s == CF_OK) s = normal_room(run, err);
    if (s == CF_OK) s = fit_solve_normal(p, o, o->max_iterations, &run->summary, run->jtj, err);
  }
  if (s == CF_OK) s = fit_free_covariance(p, run->jtj, run->covariance, rank_deficient, err);
  int tiles = 0; /* JPEG: the tiles' sandwich (a sample's too) */
  if (s == CF_OK && !*rank_deficient && capture_has_jpeg(run->capture))
    s = fit_tile_covariance(p, FIT_JPEG_TILE_PX, run->covariance, &tiles, err);
  if (s == CF_OK && !*rank_deficient && !tiles)
    s = fit_sample_covariance(p, fit_threads(o), run->covariance, err);
  return s;
}

/* M4: is the base seen at all? Once, after a round that found everything
 * constrained; *again when the base is hidden (solve again, and the
 * covariance of the film alone). */
static cf_status test_hidden_base(fit_run *run, fit_hidden_base *hidden, int *again,
                                  cf_error *err) {
  cf_status s = fit_test_hidden_base(run->p, &run->plan, run->o, run->summary.final_cost, hidden,
                                     err);
  hidden->tested = 1;
  *again = s == CF_OK && hidden->hidden;
  if (*again)
    fit_add_warning(run->r,
                    "the photos do not show the base under the film: the film alone explains "
                    "them (chi2 higher by %.3g with the base hidden, against BIC's price %.3g "
                    "of its %d parameters), so the base's parameters are not constrained: "
                    "held at their defaults, the optical depth at its upper bound (the data "
                    "say only that the film hides the base)",
                    hidden->gain, hidden->price, hidden->slots);
  return s;
}

/* 4. Robust solves until every free parameter is constrained: those the
 * capture does not constrain held at their defaults, and for M4 the base
 * under the film hidden when the photos do not show it. */
static cf_status solve_until_constrained(fit_run *run, cf_error *err) {
  fit_problem *p = run->p;
  const cf_fit_options *o = run->o;
  cf_status s = CF_OK;
  int rank_deficient = 0;
  fit_hidden_base hidden = {0};
  for (int round = 0; s == CF_OK && round < MAX_UNCONSTRAINED_ROUNDS; ++round) {
    fit_progress(o, "solving", (size_t)round, MAX_UNCONSTRAINED_ROUNDS);
    s = solve_with_covariance(run, round, &rank_deficient, err);
    int found = 0, again = 0;
    if (s == CF_OK)
      s = fit_find_unconstrained(p, run->jtj, run->covariance, rank_deficient, &run->plan, &found,
                                 err);
    if (s == CF_OK && !found && !hidden.tested && !rank_deficient)
      s = test_hidden_base(run, &hidden, &again, err);
    if (again) continue;
    if (s != CF_OK || !found) break;
    double defaults[CF_MAX_DIM], *params = fit_problem_values(p)->params;
    cf_model_default_params(o->model, defaults);
    for (int k = 0; k < fit_problem_dim(p); ++k) /* held at the default */
      if (run->plan.status[k] == CF_PARAM_UNCONSTRAINED) params[k] = defaults[k];
    s = fit_declare(p, &run->plan, err);
  }
  if (s == CF_OK && rank_deficient)
    s = cf_error_set(err, CF_ENUMERIC,
                     "the capture does not constrain the fit even with the unconstrained "
                     "parameters held");
  fit_progress(o, "solving", MAX_UNCONSTRAINED_ROUNDS, MAX_UNCONSTRAINED_ROUNDS);
  return s;
}

/* Steps 3 (on every observation) to 5, from the refined values; JPEG
 * photos are then compared with the prediction as their codec codes it,
 * the codec's error taken at the solution (fit_jpeg.h), and solved again,
 * once: further rounds, each taking the error at the last round's
 * solution, drifted along the response curve's valley with the level
 * (6 captures with an unknown curve at 320 × 240: 2-sd coverage 63 %
 * after up to 4 rounds, 83 % after one; with a known curve a second round
 * moved nothing by more than 0.13 sd). */
static cf_status solve_population(fit_run *run, const double *params, double log_scale,
                                  const double *response, cf_error *err) {
  cf_status s = full_problem(run, params, log_scale, response, err);
  if (s == CF_OK) s = settle_weights_and_footprints(run, err);
  if (s == CF_OK) s = solve_until_constrained(run, err);
  if (s == CF_OK && !run->o->jpeg_plain && fit_jpeg_modelled(run->capture)) {
    s = fit_jpeg_correct(run->p, run->capture, run->o, run->r, err);
    if (s == CF_OK) s = solve_until_constrained(run, err);
  }
  if (s == CF_OK)
    s = fit_outcome(run->p, &run->plan, run->covariance, &run->summary, run->o,
                    run->population->weight != NULL,
                    run->has_noise ? 1.0 : run->sigma * run->sigma, run->r, err);
  return s;
}

/* 2. the start; 3. a larger subsample, then the whole population, timed
 * by stage. */
static cf_status run_stages(fit_run *run, cf_error *err) {
  const cf_fit_options *o = run->o;
  cf_fit_result *r = run->r;
  double params[CF_MAX_DIM], log_scale, response[CF_RESPONSE_MODEL_KNOTS];
  double clock = cf_now_seconds(), then;
  cf_status s = find_start(run, params, &log_scale, response, err);
  if (s != CF_OK) return s;
  r->stage_seconds[CF_FIT_STAGE_START] = (then = cf_now_seconds()) - clock;
  clock = then;
  /* a given start is already a fit (the model choice's, on about 22 000
   * observations): refining it on 40 000 first saves the full solve nothing
   * (DiLiGenT: 43 + 27 iterations against 26, the same minimum within 0.05
   * sd, 10 % less CPU) */
  if (!o->use_start)
    s = refine_on_subsample(run->capture, run->population, o, &run->plan, REFINE_TARGET,
                            run->sigma, params, &log_scale, r, &run->switched, err);
  if (s == CF_OK) /* an unknown tone curve: the curve's shape from a few starts */
    s = fit_response_starts(run->capture, run->population, o, &run->plan, run->sigma, params,
                            &log_scale, response, err);
  if (s != CF_OK) return s;
  r->stage_seconds[CF_FIT_STAGE_REFINE] = (then = cf_now_seconds()) - clock;
  clock = then;
  s = solve_population(run, params, log_scale, response, err);
  r->stage_seconds[CF_FIT_STAGE_SOLVE] = (then = cf_now_seconds()) - clock;
  clock = then;
  if (s == CF_OK) s = fit_statistics(run->p, o, r, err);
  r->stage_seconds[CF_FIT_STAGE_STATISTICS] = cf_now_seconds() - clock;
  return s;
}

cf_status fit_run_population(const cf_capture *capture, const fit_population *population,
                             const cf_fit_options *o, double tolerance, cf_fit_result *r,
                             cf_error *err) {
  memset(r, 0, sizeof *r);
  r->model = o->model;
  cf_status s = cf_fit_check_options(o, err);
  if (s != CF_OK) return s;
  fit_run run = {.capture = capture,
                 .population = population,
                 .o = o,
                 .tolerance = tolerance,
                 .r = r,
                 .sigma = 1.0};
  fit_plan_for(capture, o, &run.plan);
  if (cf_capture_observations(capture)->count == 0 || population->count == 0)
    return cf_error_set(err, CF_EINVAL, "the capture has no observations to fit");
  s = run_stages(&run, err);
  free(run.jtj);
  free(run.covariance);
  fit_problem_free(run.p);
  if (s != CF_OK) cf_fit_result_free(r);
  return s;
}

cf_status fit_run_budget(const cf_capture *capture, const fit_budget *budget,
                         const cf_fit_options *o, cf_fit_result *r, cf_error *err) {
  cf_status s = fit_run_population(capture, &budget->population, o, 0.0, r, err);
  if (s == CF_OK && budget->sample.weight) {
    r->sample_count = budget->sample.count;
    r->population_count = budget->in_use;
    r->sampling = o->sampling;
  }
  return s;
}

cf_status cf_fit_run(const cf_capture *capture, const cf_fit_options *o, cf_fit_result *r,
                     cf_error *err) {
  memset(r, 0, sizeof *r);
  fit_budget budget;
  cf_status s = fit_budget_for(capture, o, &budget, err);
  /* (a start of its own: cf_fit_auto's chosen model, checked before) */
  if (s == CF_OK && !o->use_start) s = fit_check_gains(capture, o, &budget, err);
  if (s == CF_OK) s = fit_run_budget(capture, &budget, o, r, err);
  fit_budget_free(&budget);
  if (s == CF_OK && (s = fit_check_constrained(r, err)) != CF_OK) cf_fit_result_free(r);
  return s;
}
