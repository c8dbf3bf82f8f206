/* The fit's least-squares problem, as the fit's stages see it: the
 * observations a fit uses (their measurements, the pairs of each
 * observation's surface point with the lights, σ of every residual), the
 * unknowns the solver's x holds, one file per kind of unknown, the
 * current values of every kind, the residuals and their Jacobian a block
 * of observations at a time, and the solves through lsq.h.
 *
 * The problem is opaque: its parts live in src/fit/problem/ (problem.h
 * there is their own header), and the stages use the functions below.
 * Private to src/fit. */
#ifndef CLAYFIT_FIT_PROBLEM_H
#define CLAYFIT_FIT_PROBLEM_H

#include <stddef.h>
#include <stdint.h>

#include "clayfit/capture.h"
#include "clayfit/fit.h"
#include "clayfit/model.h"
#include "clayfit/response_model.h"
#include "lsq/lsq.h"

typedef struct fit_problem fit_problem;

/* ---- the current values of every kind of unknown ----
 * What the unknowns start from, and what the rest are held at. Each kind
 * of unknown (problem/kind.h) keeps its values here. */
typedef struct fit_values {
  double params[CF_MAX_DIM]; /* the model's */
  double log_scale;          /* log s */
  double response[CF_RESPONSE_MODEL_KNOTS]; /* R's slopes (all 1: linear) */
  double *log_exposures; /* images: log e of each image (its gain group's) */
  double *log_balance;   /* 3 × images: log b per image and channel (green's 0) */
  double *log_light;     /* lights: log g of each light inside its images' sums */
} fit_values;

/* A copy of p's values (its arrays owned: fit_values_free), and back. */
cf_status fit_values_save(const fit_problem *p, fit_values *copy, cf_error *err);
void fit_values_restore(fit_problem *p, const fit_values *copy);
void fit_values_free(fit_values *v);

/* ---- the problem ---- */

/* The problem over `count` observations of the capture (index: which;
 * NULL: all, in order), their pairs' geometry built on `threads` threads,
 * which predictions and footprints use from then on; nothing free yet.
 * On failure *p is NULL. */
cf_status fit_problem_new(fit_problem **p, const cf_capture *capture, cf_model_id model,
                          const uint32_t *index, size_t count, int threads, cf_error *err);
void fit_problem_free(fit_problem *p);

/* A problem that shares p's observations and unknowns (which its solves
 * only read) and has values, a trust region and tallies of its own, at
 * p's values: a start of the multi-start, solved beside others. It must
 * be freed before p. */
cf_status fit_problem_fork(const fit_problem *p, fit_problem **fork, cf_error *err);

/* Weigh each used observation's cost by weight[i] (a sample's weights,
 * count of them; copied). Without it every weight is 1. */
cf_status fit_problem_set_sample_weights(fit_problem *p, const double *weight, cf_error *err);

cf_model_id fit_problem_model(const fit_problem *p);
int fit_problem_dim(const fit_problem *p);
const cf_capture *fit_problem_capture(const fit_problem *p);
/* The observations used, and the capture's images. */
size_t fit_problem_count(const fit_problem *p);
size_t fit_problem_images(const fit_problem *p);
/* Used observation i's index among the capture's, and its image. */
size_t fit_problem_observation(const fit_problem *p, size_t i);
uint32_t fit_problem_image(const fit_problem *p, size_t i);
/* The measurements of the used observations (3 × count, in the problem's
 * order), and 1/σ of every residual (3 × count). */
const double *fit_problem_measured(const fit_problem *p);
const double *fit_problem_inv_sigma(const fit_problem *p);
/* √(sample weight) of every used observation (count), or NULL: all 1. */
const double *fit_problem_sample_roots(const fit_problem *p);
/* Observation i's pairs with the lights (its `slots` pairs: geometry and
 * weights E_c c_i, 3 each); returns their count. */
size_t fit_problem_pairs(const fit_problem *p, size_t i, const cf_geometry **geometry,
                         const double **weight);
/* Replace the measurements and clip flags of the used observations with
 * those of the capture's observations `y` (3 per observation) and `flags`
 * (JPEG's coding error taken out, fit_jpeg.h). */
void fit_problem_set_measured(fit_problem *p, const double *y, const uint8_t *flags);

/* The current values (read, or to change). */
const fit_values *fit_problem_read_values(const fit_problem *p);
fit_values *fit_problem_values(fit_problem *p);
/* Does the response curve apply (it is free, or not the identity)? */
int fit_problem_response_on(const fit_problem *p);
/* The current values of `from` into `to`, a problem over the same capture
 * (its images and lights; another set of observations);
 * fit_problem_clear_unknowns then sets what they switch on. */
void fit_problem_copy_values(fit_problem *to, const fit_problem *from);

/* ---- the capture's images and lights, as the gains group them ---- */

typedef struct fit_groups {
  size_t images;
  /* the gains' groups (--fit-exposures): image k's gain is its group's,
   * group[k] (per image the group is k; per light the images one light
   * lights alone share it, fit_problem_group_gains), count in all, the
   * first image of each group in group_image; light_of_image[k] is the
   * first image of image k's only light (−1: it has none or several) */
  uint32_t *group, *group_image;
  size_t count;
  long *light_of_image;
  /* the capture's lights (cf_capture_light_ids): image k's slot j is light
   * slot_light[k × lights + j] (−1: none), lights in all (light_count);
   * an image has at most image_lights of them; several_lights: some image
   * has two or more */
  int lights;
  long *slot_light;
  size_t light_count;
  int image_lights, several_lights;
} fit_groups;

const fit_groups *fit_problem_groups(const fit_problem *p);

/* ---- the unknowns ---- */

/* A kind of unknown (problem/kind.h): one file each. */
typedef struct fit_kind fit_kind;
extern const fit_kind fit_kind_material; /* the model's slots (problem/fit_kind_material.c) */
extern const fit_kind fit_kind_scale;    /* log s (problem/fit_kind_gains.c) */
extern const fit_kind fit_kind_exposure; /* log e of each gain group but the last */
extern const fit_kind fit_kind_balance;  /* log b of each image's red and blue but the last's */
extern const fit_kind fit_kind_light;    /* log g of each light but the last (problem/fit_kind_light.c) */
extern const fit_kind fit_kind_response; /* the response curve's slopes (problem/fit_kind_response.c) */

/* What the solver's x[u] is: its kind and, within the kind, which value
 * (a model slot, a gain group, image k's red 2k or blue 2k + 1, a light,
 * a knot). */
typedef struct fit_unknown {
  const fit_kind *kind;
  int slot;
} fit_unknown;

/* How a model slot is fitted: as it is, as its logarithm (the albedo:
 * ρ > 0 for any real clay; the bound ρ <= 1 becomes log ρ <= 0 and ρ >= 0
 * becomes ρ >= FIT_ALBEDO_FLOOR: no capture tells 1e-6 from 0, and a
 * hidden base must not drive log ρ to −∞; a flash capture sees the film's
 * diffuse light nearly straight on, so it determines ρ e^(−τ P) with P
 * hardly varying: a curved valley in (ρ, τ), straight in (log ρ, τ), where
 * the solver needs 3 to 5 times fewer iterations), or as its square (the
 * Oren-Nayar σ, whose derivative vanishes at σ = 0, docs/model.md §6.6: f
 * depends on σ only through σ²). */
typedef enum fit_slot_form { FIT_SLOT_PLAIN, FIT_SLOT_LOG, FIT_SLOT_SQUARE } fit_slot_form;
#define FIT_ALBEDO_FLOOR 1e-6
fit_slot_form fit_slot_form_of(cf_model_id model, int slot);

int fit_problem_unknown_count(const fit_problem *p);
fit_unknown fit_problem_unknown(const fit_problem *p, int u);
/* Is some unknown of this kind free? */
int fit_problem_has_kind(const fit_problem *p, const fit_kind *kind);
double fit_problem_lower(const fit_problem *p, int u);
double fit_problem_upper(const fit_problem *p, int u);
/* After a solve: −1/+1 for an unknown held at its lower/upper bound by
 * the data (lsq.h), else 0; all (num unknowns), to read or to restore. */
int *fit_problem_at_bound(fit_problem *p);
const int *fit_problem_read_at_bound(const fit_problem *p);

/* Declare the unknowns (in this order: model slots, the scale, the
 * lights' gains or the exposures and the white balance, the response)
 * and the blocks; fit_problem_finish after the last. The unknowns' arrays
 * grow as they are declared; when that fails (out of memory)
 * fit_problem_finish returns CF_ENOMEM. */
void fit_problem_clear_unknowns(fit_problem *p);
void fit_problem_free_slot(fit_problem *p, int slot);
void fit_problem_free_scale(fit_problem *p);
/* The gains' groups for fit_problem_free_exposures: one per image, or
 * (per_light) one per light, the images one light lights alone sharing
 * it (an image of no single light keeps a group of its own). */
void fit_problem_group_gains(fit_problem *p, int per_light);
void fit_problem_free_exposures(fit_problem *p);
/* A gain per light inside each image's sum over its lights (where an
 * image has several): light_count − 1 free log gains, the last light's
 * minus their sum. At most FIT_IMAGE_LIGHTS lights an image (the check
 * before the fit refuses more: cf_fit_check_gains). */
#define FIT_IMAGE_LIGHTS 8 /* a capacity (arrays on the stack), not a trade */
void fit_problem_free_light_gains(fit_problem *p);
/* The white balance free: the red and blue gains of every image against
 * its green, their mean log over the images 0 per channel (a gain per
 * image, fit_problem_free_exposures, gives the green's). */
void fit_problem_free_balance(fit_problem *p);
void fit_problem_free_response(fit_problem *p);
cf_status fit_problem_finish(fit_problem *p, cf_error *err);

/* The response's slopes all 1 (linear); is it the identity? */
void fit_response_identity(double *slopes);
int fit_response_is_identity(const double *slopes);

/* x from the problem's current values, and the current values from x. */
void fit_problem_get_x(const fit_problem *p, double *x);
void fit_problem_set_x(fit_problem *p, const double *x);

/* ---- the noise model and the loss ---- */

/* Does the capture give a noise model with some noise (read or shot > 0)? */
int fit_capture_has_noise(const cf_capture *capture);

/* σ for every residual: the capture's noise model if it has one with some
 * noise (at the measurements; with a response curve on, the sensor's
 * noise carried through the curve: docs/model.md (50a)), else one σ (> 0)
 * for all. */
void fit_problem_set_sigma(fit_problem *p, double sigma);
/* The one σ (fit_problem_set_sigma's; 0 with a noise model). */
double fit_problem_sigma(const fit_problem *p);

/* Without a noise model but with a response curve on, the one σ is τ in
 * linear units, carried through the curve: σ = τ R'(x) at x = R⁻¹(μ), μ
 * the measurement (fit_problem_set_sigma) or the prediction
 * (fit_problem_reweight), so that declaring another encoding changes
 * only the units (docs/model.md (52a)). Is that the case for p? */
int fit_problem_sigma_through_curve(const fit_problem *p);

/* R'(x) at x = R⁻¹(mu), as the noise model takes it (1 without a curve). */
double fit_problem_curve_slope(const fit_problem *p, double mu);

/* σ from the noise model at the current prediction instead of the
 * measurement (iteratively reweighted least squares): weights computed
 * from y correlate with y's own noise and bias the fit by about −shot per
 * pixel, which the ill-conditioned directions (ρ against τ in a flash
 * capture) amplify; at the fixed point of prediction-based weights the
 * quasi-score Σ (y − μ)/v(μ) ∂μ is 0, which is unbiased. No-op without a
 * noise model, unless σ goes through the curve. */
cf_status fit_problem_reweight(fit_problem *p, cf_error *err);

/* The robust loss: which, and its scale in σ (none until set). */
void fit_problem_set_loss(fit_problem *p, cf_loss loss, double scale);
/* The robust loss's weight ρ'(s) of a residual whose square in units of σ
 * is s (1 without a loss, or inside Huber's threshold). */
double fit_problem_loss_weight(const fit_problem *p, double s);

/* Is residual i (observation i / 3 of those used, channel i % 3)
 * censored: a clipped channel whose prediction is at or above what was
 * seen (the true value is at least that, so no residual)? */
int fit_problem_censored(const fit_problem *p, size_t i, double prediction, double measured);

/* A clipped channel's residual in units of σ under the censored likelihood
 * (docs/model.md (53)): with z = (μ − y)/σ, y the clip level, the channel
 * has probability Φ(z) and the residual is t = −√(−2 log Φ(z)) (t² is its
 * cost; t ≈ z for z ≪ 0, t → 0 for z ≫ 0). *slope = dt/dz (> 0; 0 where
 * t is 0 to rounding: the channel is then censored outright). */
double fit_censored_residual(double z, double *slope);

/* The smoothness prior on the response (docs/model.md §5.4): the slopes
 * of neighbouring knots differ by about this much at most. */
#define FIT_RESPONSE_PRIOR_SD 0.25 /* sRGB's slope changes by 0.2 at most between knots */

/* ---- the residuals and their Jacobian ---- */

/* lsq.h's callback: the cost of block `block` at x, and the normal
 * equations of its Gauss-Newton model (reweighted by the loss) over the
 * block's columns. Returns CF_LSQ_EVALUATED, CF_LSQ_NOT_FINITE, or
 * CF_LSQ_FAILED when it found no memory. Safe to call from several
 * threads at once for different blocks. */
int fit_problem_evaluate(void *user, const double *x, size_t block, double *cost, double *jtj,
                         double *jtu);
/* lsq.h's block_columns: the unknowns block `block` depends on. */
int fit_problem_block_columns(void *user, size_t block, const int **columns);
size_t fit_problem_block_count(const fit_problem *p);
/* The cost at the current values, block by block (nothing free: x
 * unused). Returns 0 when some block cannot be evaluated. */
int fit_problem_cost(const fit_problem *p, double *cost);

/* The score of groups of observations at the current values: score[g ×
 * num_unknowns + u] += Σ ψ ∂μ/∂x_u over the channels of the observations
 * i with group[i] = g, with ψ = w ρ'(e²) e / σ, e = (y − μ)/σ (a clipped
 * channel's e and slope from the censored likelihood; 0 where censored
 * outright): each row's −Jᵀu, from the analytic Jacobian, without the
 * response's prior. */
cf_status fit_problem_group_scores(const fit_problem *p, const size_t *group, double *score,
                                   cf_error *err);

/* The prediction (with scale and exposures) and the measurement of every
 * used observation and channel at the current values: 3 × count each. */
cf_status fit_problem_predict(const fit_problem *p, double *prediction, double *measured,
                              cf_error *err);

/* ---- solving (problem/fit_solve.c) ---- */

/* How the problem's solves run (lsq.h's options; 0: its defaults). */
typedef struct fit_solve_settings {
  double function_tolerance, min_relative_decrease;
  int newton_start; /* the solves start near a minimum */
  /* optional: ends a solve early (lsq.h's cf_lsq_options.stop) */
  int (*stop)(void *user, const double *x, double cost);
  void *stop_user;
} fit_solve_settings;
fit_solve_settings *fit_problem_settings(fit_problem *p);
/* The next solve starts with Ceres' initial trust region, not where the
 * last ended (a start far from the last one's end). */
void fit_problem_forget_radius(fit_problem *p);

/* What the problem's solves did, in all. */
typedef struct fit_tally {
  int solves, iterations;
  double trace[CF_FIT_MAX_TRACE]; /* the costs of the iterations, in order */
  int trace_count;
  double seconds;
} fit_tally;
const fit_tally *fit_problem_tally(const fit_problem *p);

/* The problem as lsq.h sees it, over the unknowns x (num unknowns; the
 * caller fills them, fit_problem_get_x). */
void fit_lsq_problem(fit_problem *p, double *x, cf_lsq_problem *problem);

/* Solve the problem from its current values (lsq.h); the solution becomes
 * the current values, fit_problem_at_bound says which unknowns ended at a
 * bound. */
cf_status fit_solve(fit_problem *p, const cf_fit_options *o, int max_iterations,
                    cf_lsq_summary *summary, cf_error *err);

/* fit_solve, then the normal equations at the solution over every unknown
 * into jtj (n², as fit_normal_equations), mostly from the evaluations the
 * solve kept. */
cf_status fit_solve_normal(fit_problem *p, const cf_fit_options *o, int max_iterations,
                           cf_lsq_summary *summary, double *jtj, cf_error *err);

/* The normal equations at the current values, over every unknown: JᵀJ
 * (n², row-major) and, unless jtu is NULL, Jᵀu (n), and unless cost is
 * NULL the cost, one pass over the observations on `threads` threads. */
cf_status fit_normal_equations(fit_problem *p, int threads, double *jtj, double *jtu, double *cost,
                               cf_error *err);

/* The same with every row weighed by its sample weight w instead of √w
 * (B = Σ w² JᵀJ of a pixel budget's sandwich, fit_uncertainty.h). */
cf_status fit_sample_information(fit_problem *p, int threads, double *b, cf_error *err);

/* The most unknowns for which a Newton decrement is computed (beyond, it
 * is not worth it: HUGE_VAL). */
enum { FIT_DECREMENT_MOST = 64 }; /* 763ea94 named it; not measured */

/* How much a solve from the current values could still lower the cost:
 * the Gauss-Newton decrement ½ gᵀ H⁻¹ g over the unknowns not pinned at a
 * bound (in the cost's units, σ²: 1e-3 is a move of 0.045 standard
 * deviations along the worst direction). *decrement is HUGE_VAL where it
 * is not worth computing (more than FIT_DECREMENT_MOST unknowns). */
cf_status fit_newton_decrement(fit_problem *p, const cf_fit_options *o, double *decrement,
                               cf_error *err);

/* The same from the normal equations at the current values (jtj, g =
 * Jᵀu, fit_normal_equations), without a pass; HUGE_VAL beyond
 * FIT_DECREMENT_MOST unknowns. */
double fit_newton_decrement_from(const fit_problem *p, const double *jtj, const double *g);

/* Do the unknowns pinned at a bound stay there by the gradient g at the
 * current values: does descent (−g) point out of the box for each? */
int fit_pins_hold(const fit_problem *p, const double *g);

/* Below this decrement a change of the problem (new weights, new pixel
 * footprints) is not solved again. */
#define FIT_RESOLVE_DECREMENT 1e-3 /* a917abb: the demo's fit 4 solves -> 2, 9.7 -> 7.7 s */

/* With a noise model, σ from the prediction (fit_problem_reweight) and
 * solve again, to the fixed point or `rounds` rounds; without one, one
 * solve. *weights_current (optional) is 1 when it ended with the weights
 * of the current values (new weights that moved nothing), else 0. */
cf_status fit_solve_reweighted(fit_problem *p, const cf_fit_options *o, int rounds,
                               cf_lsq_summary *summary, int *weights_current, cf_error *err);

/* The solver threads the options ask for (2 when they say none). */
int fit_threads(const cf_fit_options *o);

/* The width of a model slot's range. */
double fit_slot_width(cf_model_id model, int slot);

/* ---- pixel footprints (problem/fit_footprint.c) ----
 * A pixel measures the mean of the reflected radiance over its footprint,
 * which the value at the pixel centre misses where a lobe is narrower than
 * the pixel (docs/model.md §5.6). Such observations get S × S samples over
 * the pixel, each a point of the footprint with its own normal, view and
 * lights (cf_capture_footprint_at), weighted 1/S²: the Gauss-Legendre
 * pairs of cf_footprint_samples (auto), or a fixed S's centred grid (the
 * box filter `clayfit synth` renders with). */

/* Choose S for every observation at the current parameters
 * (options->footprint: adaptive, centres only, or S for all) and, where
 * that differs from what the problem has, rebuild its pairs. Adaptive S
 * only grows from one call to the next (a lobe that narrows during the
 * fit gets more samples; one that widens keeps them), so repeated calls
 * settle. *changed (optional) is set when the pairs were rebuilt. */
cf_status fit_footprint_update(fit_problem *p, const cf_fit_options *options, int *changed,
                               cf_error *err);

/* What the problem integrates: observations with S >= 2, Σ S² over them,
 * the largest S. */
void fit_footprint_tally(const fit_problem *p, size_t *observations, size_t *samples, int *largest);

#endif /* CLAYFIT_FIT_PROBLEM_H */
