/* The fit's least-squares problem (include/clayfit/fit.h) over a capture's
 * observations: the geometry of every (observation, light) pair computed
 * once, the map from the solver's vector x to the model's parameters, the
 * exposures and the scale, and the residuals of a block of observations
 * with their Jacobian. Private to src/fit. */
#ifndef CLAYFIT_FIT_PROBLEM_H
#define CLAYFIT_FIT_PROBLEM_H

#include <stddef.h>
#include <stdint.h>

#include "clayfit/capture.h"
#include "clayfit/fit.h"
#include "clayfit/model.h"
#include "clayfit/response_model.h"

/* What the solver's entry x[i] is. Model slots are fitted as they are,
 * but the albedo, fitted as its logarithm (ρ > 0 for any real clay; the
 * bound ρ <= 1 becomes log ρ <= 0, and ρ >= 0 becomes ρ >= FIT_ALBEDO_FLOOR:
 * no capture tells an albedo of 1e-6 from 0, and a hidden base must not
 * drive log ρ to −∞), and σ, fitted as σ² (bounds squared). */
#define FIT_ALBEDO_FLOOR 1e-6
typedef enum fit_unknown_kind {
  FIT_MODEL_SLOT,  /* params[slot] */
  FIT_SQUARE_SLOT, /* params[slot]²: the Oren-Nayar σ, whose derivative
                     vanishes at σ = 0 (docs/model.md §6.6); f depends
                     on σ only through σ² */
  FIT_LOG_SLOT,    /* log params[slot]: the albedo. A flash capture sees the
                      film's diffuse light nearly straight on, so it
                      determines ρ e^(−τ P) with P hardly varying: a curved
                      valley in (ρ, τ), straight in (log ρ, τ), where the
                      solver needs 3 to 5 times fewer iterations. */
  FIT_LOG_SCALE,   /* log s */
  FIT_RESPONSE,    /* the response curve's slope a_slot at knot `slot`
                      (clayfit/response_model.h), for photos whose tone
                      curve is unknown: the prediction is R(s e_k Σ f E c_i) */
  FIT_LOG_EXPOSURE, /* log e of gain group `slot`, the gain of its images
                       (fit_problem.gain_group; per image, the group is
                       the image); the last group's is minus the sum of the
                       others: their mean log is 0 */
  FIT_LOG_BALANCE,  /* log b of image slot / 2's red (slot even) or blue
                       gain against its green (--fit-gains per-image-rgb);
                       the last image's is minus the sum of the others' */
  FIT_LOG_LIGHT     /* log g of light `slot` (fit_problem.slot_light), inside
                       the sum over an image's lights (--fit-gains per-light
                       where an image has several): the prediction is
                       R(s e_k Σ_j g_l(j) f E_j c_j); the last light's is
                       minus the sum of the others': their mean log is 0 */
} fit_unknown_kind;

/* Is an unknown one of the model's slots (not the scale, an exposure or
 * the response)? */
static inline int fit_unknown_is_model(fit_unknown_kind kind) {
  return kind == FIT_MODEL_SLOT || kind == FIT_SQUARE_SLOT || kind == FIT_LOG_SLOT;
}

typedef struct fit_unknown {
  fit_unknown_kind kind;
  int slot;
} fit_unknown;

typedef struct fit_problem {
  const cf_observations *obs;
  cf_model_id model;
  int dim, lights;
  size_t count;          /* observations used (all, or a subsample) */
  const uint32_t *index; /* the observations used (NULL: all, in order) */
  /* the used observations' measurements, images and flags, copied in the
   * problem's order: the solver reads them at every evaluation, and a
   * subsample's index jumps through the capture's arrays (a cache miss per
   * observation: 70 % of a subsample's evaluation time, measured) */
  double *y;       /* 3 × count */
  uint32_t *image; /* count */
  uint8_t *flags;  /* count */
  /* the (observation, light) pairs: observation i's are the slots
   * [slot_begin[i], slot_begin[i + 1]), or, with slot_begin NULL, the
   * `lights` slots from i × lights. An observation integrated over its
   * pixel's footprint (fit_footprint.h) has S² × lights slots, one per
   * sample and light, each weighted 1/S². */
  size_t *slot_begin;    /* count + 1, or NULL */
  size_t slots;          /* in all */
  cf_geometry *geometry; /* slots */
  double *weight;        /* slots × 3: E_c c_i (0 when unlit), over S² */
  int *samples;          /* count: S of each observation, or NULL (all 1) */
  /* what the footprints measure once (fit_footprint.c; they do not depend
   * on the parameters): per image a bound on the normal's turn across a
   * pixel, and per observation its turn (NaN until measured); NULL before */
  double *turn_bound, *pixel_turn;
  double *inv_sigma;   /* count × 3; from the noise model, or 1 */
  double *sample_root; /* count: √(sample weight), or NULL (all 1) */
  double sigma;        /* one σ for all (no noise model), else 0 */
  size_t images;
  uint32_t last_image; /* images − 1 */

  /* current values: what the unknowns start from and what the others are
   * held at */
  double params[CF_MAX_DIM];
  double log_scale;
  double response[CF_RESPONSE_MODEL_KNOTS]; /* R's slopes (all 1: linear) */
  int response_on;       /* apply R (it is free, or not the identity) */
  double *log_exposures; /* images */
  /* the gains' groups (--fit-exposures): image k's gain is its group's,
   * gain_group[k] (images; per image the group is k, per light the images
   * one light lights alone, fit_problem_group_gains), gain_groups in all,
   * the first image of each group in group_image; light_of_image[k] is
   * the first image of image k's only light (−1: it has none or several) */
  uint32_t *gain_group, *group_image;
  size_t gain_groups;
  long *light_of_image;
  /* the capture's lights (cf_capture_light_ids): image k's slot j is light
   * slot_light[k × lights + j] (−1: none), light_count in all; an image
   * has at most image_lights of them, several_lights: some image has
   * two or more. Their gains g_l inside each image's sum, as log g_l
   * (light_count; 0: 1), apply with light_gains_on (they are free, or
   * not all 1) */
  long *slot_light;
  size_t light_count;
  int image_lights, several_lights, light_gains_on;
  double *log_light;
  /* the white balance per image and channel: log b, 3 × images (green's
   * 0; all 0 unless fitted, fit_problem_free_balance); channel c of image
   * k has the gain s e_k b_kc */
  double *log_balance;
  /* the unknowns declared (fit_problem_clear_unknowns, _free_*), their
   * bounds and, after a solve, at_bound: −1/+1 for an unknown held at its
   * lower/upper bound by the data (lsq.h), else 0; num_unknowns each, in
   * arrays that grow as unknowns are declared (unknown_capacity) */
  int num_unknowns, unknown_capacity;
  fit_unknown *unknowns;
  double *lower, *upper;
  int *at_bound;
  int unknowns_failed;            /* a declaration found no memory (fit_problem_finish says so) */
  int solves, iterations;         /* tallies of fit_solve on this problem */
  double trace[CF_FIT_MAX_TRACE]; /* the costs of its solves' iterations, in order */
  int trace_count;
  double solver_seconds;
  /* the trust region the last solve ended with, where the next starts
   * (lsq.h); 0 (Ceres' initial one) before the first solve and after
   * every fit_declare */
  double radius;
  /* the solves' relative function tolerance and least relative decrease
   * of a step (0: lsq.h's defaults) */
  double function_tolerance, min_relative_decrease;
  int newton_start; /* lsq.h's: the solves start near a minimum */
  /* threads for work over every observation (fit_problem_predict, the
   * pixel footprints; fit_problem_init's: a problem solved beside others
   * keeps to one) */
  int threads;
  /* optional: ends a solve early (lsq.h's cf_lsq_options.stop) */
  int (*stop)(void *user, const double *x, double cost);
  void *stop_user;
  cf_loss loss;
  double loss_scale; /* in σ */
  size_t block_size; /* observations per residual block */
  size_t num_blocks;
  /* block b's columns (the unknowns its Jacobian can be nonzero in,
   * ascending): block_column[block_column_begin[b] ...
   * block_column_begin[b + 1]) */
  size_t *block_column_begin;
  int *block_column;
  /* fit_problem_evaluate's working memory: a pool of scratch buffers that
   * concurrent evaluations take (fit_problem.c), made by
   * fit_problem_finish, grown to the problem as it grows */
  struct fit_scratch *scratch;
  int scratch_count;
} fit_problem;

/* The pairs of one surface point with each of `lights` lights: their
 * geometry and weights scale · E_c c_i (0 where unlit), into geometry
 * (lights) and weight (3 × lights). */
void fit_pairs_at(int lights, const double n[3], const double v[3], const double *light_dir,
                  const double *irradiance, double scale, cf_geometry *geometry, double *weight);

/* The observations a fit uses: all of the capture's (index NULL; count is
 * then the capture's) or the `count` listed in index, each weighed by
 * weight[i] (a pixel budget's sample, fit_budget.h; NULL: 1). */
typedef struct fit_population {
  const uint32_t *index;
  size_t count;
  const double *weight;
} fit_population;

/* A weighted sample of a population, for the stages that work on a
 * subsample: about `target` observations in two strata, taken evenly
 * (fit_spread_take) from each. The specular stratum is the 1/16 of the
 * population whose half vector comes nearest the normal (for any light):
 * it holds the highlights, rare in a photo but what fixes the lobes, and
 * gets a quarter of the sample. The rest gets the other three quarters.
 * Each observation's weight is its stratum's size over its sample's, so
 * that the sample's cost estimates the population's without bias (a
 * Horvitz-Thompson estimate). A population no larger than the target is
 * taken whole, with weights 1. */
typedef struct fit_sample {
  uint32_t *index;
  double *weight;
  size_t count;
} fit_sample;

/* The observations of the images with use_image[k] (NULL: all, index
 * NULL); *index is owned (free). */
cf_status fit_population_of_images(const cf_capture *capture, const unsigned char *use_image,
                                   fit_population *population, uint32_t **index, cf_error *err);

cf_status fit_sample_draw(const cf_observations *obs, const fit_population *from, size_t target,
                          fit_sample *sample, cf_error *err);

/* An even spread (Bresenham's): of `size` items met one by one, take
 * `want` (all when want >= size) spaced evenly over the whole run, the
 * last item included; *acc starts at 0. A whole stride (every
 * (size / want)-th, stopped at `want`) left the end out: on DiLiGenT the
 * last two images of 96, whose free exposures then had no observation. */
static inline int fit_spread_take(size_t *acc, size_t want, size_t size) {
  if (want >= size) return 1;
  *acc += want;
  if (*acc < size) return 0;
  *acc -= size;
  return 1;
}
void fit_sample_free(fit_sample *sample);

/* Set up the problem for all observations (index NULL) or the `count`
 * listed in index; nothing is free yet (fit_problem_free_slot etc.). */
/* Weigh each used observation's cost by weight[i] (a sample's weights;
 * copied). Without it every weight is 1. */
cf_status fit_problem_set_sample_weights(fit_problem *p, const double *weight, cf_error *err);

/* The problem over `count` observations of the capture (index: which;
 * NULL: all, in order), their pairs' geometry built on `threads` threads,
 * which predictions and footprints use from then on (p->threads). */
cf_status fit_problem_init(fit_problem *p, const cf_capture *capture, cf_model_id model,
                           const uint32_t *index, size_t count, int threads, cf_error *err);

/* A weighted sample of about `target` observations of the population
 * (fit_sample_draw) and the problem over it with the sample's weights.
 * On failure nothing is left to free; else release both. */
cf_status fit_problem_init_sample(fit_problem *p, fit_sample *sample, const cf_capture *capture,
                                  cf_model_id model, const fit_population *population,
                                  size_t target, cf_error *err);
void fit_problem_release(fit_problem *p);

/* Does the capture give a noise model with some noise (read or shot > 0)? */
int fit_capture_has_noise(const cf_capture *capture);

/* σ for every residual: the capture's noise model if it has one with some
 * noise (at the measurements; with a response curve on, the sensor's
 * noise carried through the curve: docs/model.md (50a)), else one σ (> 0)
 * for all. */
void fit_problem_set_sigma(fit_problem *p, const cf_capture *capture, double sigma);

/* Without a noise model but with a response curve on, the one σ is τ in
 * linear units, carried through the curve: σ = τ R'(x) at x = R⁻¹(μ), μ
 * the measurement (fit_problem_set_sigma) or the prediction
 * (fit_problem_reweight), so that declaring another encoding changes
 * only the units (docs/model.md (52a)). Is that the case for p? */
int fit_problem_sigma_through_curve(const fit_problem *p);

/* R'(x) at x = R⁻¹(mu), as the noise model takes it (1 without a curve). */
double fit_problem_curve_slope(const fit_problem *p, double mu);

/* Declare the unknowns (in this order: model slots, the scale, the
 * exposures) and the blocks; call after the last. The unknowns'
 * arrays grow as they are declared; when that fails (out of memory)
 * fit_problem_finish returns CF_ENOMEM. */
void fit_problem_clear_unknowns(fit_problem *p);
void fit_problem_free_slot(fit_problem *p, int slot);
void fit_problem_free_scale(fit_problem *p);
void fit_problem_free_exposures(fit_problem *p);
/* The gains' groups for fit_problem_free_exposures: one per image, or
 * (per_light) one per light, the images one light lights alone sharing
 * it (an image of no single light, light_of_image −1, keeps a group of
 * its own). */
void fit_problem_group_gains(fit_problem *p, int per_light);
/* A gain per light inside each image's sum over its lights (where an
 * image has several): light_count − 1 free log gains, the last light's
 * minus their sum. At most FIT_IMAGE_LIGHTS lights an image (the check
 * before the fit refuses more: cf_fit_check_gains). */
#define FIT_IMAGE_LIGHTS 8
void fit_problem_free_light_gains(fit_problem *p);
/* The white balance free: the red and blue gains of every image against
 * its green, their mean log over the images 0 per channel (a gain per
 * image, fit_problem_free_exposures, gives the green's). */
void fit_problem_free_balance(fit_problem *p);
void fit_problem_free_response(fit_problem *p);

/* The current values (parameters, scale, response, the gains, the white
 * balance, the lights' gains) of `from` into `to`, a problem over the
 * same capture (its images and lights; another set of observations);
 * fit_problem_clear_unknowns then sets what they switch on. */
void fit_problem_copy_values(fit_problem *to, const fit_problem *from);

/* The response's slopes all 1 (linear); is it the identity? */
void fit_response_identity(double *slopes);
int fit_response_is_identity(const double *slopes);
/* The smoothness prior on the response (docs/model.md §5.4): the slopes
 * of neighbouring knots differ by about this much at most. */
#define FIT_RESPONSE_PRIOR_SD 0.25
cf_status fit_problem_finish(fit_problem *p, cf_error *err);

/* σ from the noise model at the current prediction instead of the
 * measurement (iteratively reweighted least squares): weights computed
 * from y correlate with y's own noise and bias the fit by about −shot per
 * pixel, which the ill-conditioned directions (ρ against τ in a flash
 * capture) amplify; at the fixed point of prediction-based weights the
 * quasi-score Σ (y − μ)/v(μ) ∂μ is 0, which is unbiased. No-op without a
 * noise model, unless σ goes through the curve. */
cf_status fit_problem_reweight(fit_problem *p, const cf_capture *capture, cf_error *err);

/* x from the problem's current values, and the current values from x. */
void fit_problem_get_x(const fit_problem *p, double *x);
void fit_problem_set_x(fit_problem *p, const double *x);

/* lsq.h's callback: the cost of block `block` at x, and the normal
 * equations of its Gauss-Newton model (reweighted by the loss) over the
 * block's columns. Returns CF_LSQ_EVALUATED, CF_LSQ_NOT_FINITE, or
 * CF_LSQ_FAILED when it found no memory. Safe to call from several
 * threads at once for different blocks. */
int fit_problem_evaluate(void *user, const double *x, size_t block, double *cost, double *jtj,
                         double *jtu);

/* The score of groups of observations at the current values: score[g ×
 * num_unknowns + u] += Σ ψ ∂μ/∂x_u over the channels of the observations
 * i with group[i] = g, with ψ = w ρ'(e²) e / σ, e = (y − μ)/σ (a clipped
 * channel's e and slope from the censored likelihood; 0 where censored
 * outright): each row's −Jᵀu, from the analytic Jacobian, without the
 * response's prior. */
cf_status fit_problem_group_scores(const fit_problem *p, const size_t *group, double *score,
                                   cf_error *err);

/* lsq.h's block_columns: the unknowns block `block` depends on (every
 * model slot, the scale, the response and the lights' gains; the gains of its images' groups,
 * all of them when it holds an image of the last group, whose log gain is
 * minus their sum; the same for the white balance by image). */
int fit_problem_block_columns(void *user, size_t block, const int **columns);

/* The slots of observation i (of those used): *first and the count. */
static inline size_t fit_problem_slot_range(const fit_problem *p, size_t i, size_t *first) {
  if (!p->slot_begin) {
    *first = i * (size_t)p->lights;
    return (size_t)p->lights;
  }
  *first = p->slot_begin[i];
  return p->slot_begin[i + 1] - p->slot_begin[i];
}

/* Is residual i (observation i / 3 of those used, channel i % 3; or
 * observation `row`, channel c) censored: a clipped channel whose
 * prediction is at or above what was seen (the true value is at least
 * that, so no residual)? */
static inline int fit_problem_censored_at(const fit_problem *p, size_t row, int c,
                                          double prediction, double measured) {
  return (p->flags[row] >> c & 1u) && prediction >= measured;
}

static inline int fit_problem_censored(const fit_problem *p, size_t i, double prediction,
                                       double measured) {
  return fit_problem_censored_at(p, i / 3, (int)(i % 3), prediction, measured);
}

/* A clipped channel's residual in units of σ under the censored likelihood
 * (docs/model.md (53)): with z = (μ − y)/σ, y the clip level, the channel
 * has probability Φ(z) and the residual is t = −√(−2 log Φ(z)) (t² is its
 * cost; t ≈ z for z ≪ 0, t → 0 for z ≫ 0). *slope = dt/dz (> 0; 0 where
 * t is 0 to rounding: the channel is then censored outright). */
double fit_problem_censored_residual(double z, double *slope);

/* The robust loss's weight ρ'(s) of a residual whose square in units of σ
 * is s (1 without a loss, or inside Huber's threshold). */
double fit_problem_loss_weight(const fit_problem *p, double s);

/* The prediction (with scale and exposures) and the measurement of every
 * used observation and channel at the current values: 3 × count each. */
cf_status fit_problem_predict(const fit_problem *p, double *prediction, double *measured,
                              cf_error *err);

#endif /* CLAYFIT_FIT_PROBLEM_H */
