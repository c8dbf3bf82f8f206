/* clayfit: fitting a model of the ladder to a capture's observations.
 *
 * The parameters that minimise
 *   Σ_i,c ρ( r_ic² ),  r_ic = (s · e_k · Σ_j f_c(n_i, l_ij, v_i) E_ijc c_i,ij − y_ic) / σ_ic
 * over the observations i and channels c, where
 *   f        the model's BRDF (include/clayfit/model.h),
 *   E, c_i   each light's irradiance and cosine, y the measured radiance,
 *   e_k      the image's exposure when fitted (their mean log is 0; the
 *            capture's own exposures are already divided out of y),
 *   s        the global scale when the radiometry is relative,
 *   σ        the noise: sqrt(read² + shot · max(y, 0)) when the capture
 *            gives it, else one σ for all estimated from the residuals,
 *   ρ        Huber (default), Cauchy, or the identity, in units of σ.
 * A clipped channel is censored: it only counts while the model predicts
 * less than the clip level (the true value is at least what was seen).
 * Bounds are the ranges of docs/model.md §1.6, enforced by the solver (Ceres, Levenberg-
 * Marquardt); nothing is clamped. */
#ifndef CLAYFIT_FIT_H
#define CLAYFIT_FIT_H

#include <stddef.h>

#include "clayfit/capture.h"
#include "clayfit/model.h"
#include "clayfit/response_model.h"
#include "clayfit/status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum cf_loss { CF_LOSS_NONE, CF_LOSS_HUBER, CF_LOSS_CAUCHY } cf_loss;

/* How a pixel budget draws the observations of the fit on every
 * observation (cf_fit_options.budget); each drawn observation is weighed
 * by the inverse of its chance to be drawn (Horvitz-Thompson), so that the
 * sample's cost estimates the population's. */
typedef enum cf_sampling {
  CF_SAMPLING_UNIFORM,    /* every k-th observation */
  CF_SAMPLING_STRATIFIED, /* by half-angle: the 1/16 of the observations
                             nearest a highlight get a quarter of the
                             budget, the rest three quarters */
  CF_SAMPLING_IMPORTANCE, /* the highlights (the 1/16 nearest) and the
                             silhouette region (n·v < 0.3) kept whole up to
                             half the budget, the rest uniform */
  CF_SAMPLING_COUNT
} cf_sampling;

const char *cf_sampling_name(cf_sampling sampling);

/* Why a parameter has the value it has. */
typedef enum cf_param_status {
  CF_PARAM_FITTED,          /* estimated from the capture */
  CF_PARAM_HELD,            /* held by the user (--hold) */
  CF_PARAM_HELD_FOR_SCALE,  /* held because it sets the absolute scale of a
                               capture with relative radiometry */
  CF_PARAM_UNCONSTRAINED,   /* not constrained by this capture: held at its
                               default */
  CF_PARAM_AT_BOUND         /* fitted, and the data put it at a bound of its
                               range (they prefer a value at or beyond it):
                               no standard deviation (NaN) */
} cf_param_status;

/* What cf_fit_options.fit_exposures frees (docs/fitting.md, Exposures):
 * nothing, a gain per image (its exposure), or a gain per light
 * (cf_capture_light_ids): with one light an image, shared by the images
 * that light lights (as in DiLiGenT, the same unknowns as per image), else
 * inside each image's sum over its lights (cf_fit_result.light_gains), or an
 * RGB gain per image (a white balance: the per-image gain, green's, and
 * red's and blue's against it, each with its mean log over the images 0). */
/* Room for a light's name in cf_fit_result.light_names. */
#define CF_FIT_LIGHT_NAME 96
enum { CF_GAINS_NONE = 0, CF_GAINS_PER_IMAGE = 1, CF_GAINS_PER_LIGHT = 2, CF_GAINS_PER_IMAGE_RGB = 3 };

typedef struct cf_fit_options {
  cf_model_id model;
  /* per slot: hold[k] = 1 holds params[k] at hold_value[k] (the user's
   * --hold), free[k] = 1 frees a slot that would be held for the scale */
  int hold[CF_MAX_DIM];
  double hold_value[CF_MAX_DIM];
  int free[CF_MAX_DIM];
  cf_loss loss;
  double loss_scale;      /* in σ; default 3 */
  int fit_exposures;      /* CF_GAINS_*: 0, or fit a gain e_k per image, or
                             one per light (their mean log fixed at 0) */
  int multistart;         /* 1 (default): the deterministic multi-start */
  int use_start;          /* 1: start from `start` (and `start_scale`)
                             instead of the multi-start, for example from
                             the model choice's fit on a subsample */
  double start[CF_MAX_DIM];
  double start_scale;
  /* the response curve's slopes to start from (each 0: 1), with use_start */
  double start_response[CF_RESPONSE_MODEL_KNOTS];
  int max_iterations;     /* per start; default 100 */
  int threads;            /* Ceres' threads; default 2 */
  const unsigned char *use_image; /* NULL: every image; else fit only the
                             observations of images k with use_image[k]
                             (for example to predict held-out lights) */
  /* the pixel footprint (docs/model.md §5.6): 0 (the default)
   * integrates an observation over its pixel with S × S samples (Gauss-
   * Legendre pairs, cf_footprint_offset) where a lobe is narrower than the
   * pixel (cf_footprint_samples at the fit's parameters, to a relative
   * error of footprint_tolerance, S at most CF_FIT_FOOTPRINT_MAX_SAMPLES);
   * 1 evaluates pixel centres only; S >= 2 samples every observation on
   * an S × S centred grid (as `clayfit synth --supersample S` renders) */
  int footprint;
  double footprint_tolerance; /* default 2e-3 */
  /* a pixel budget: the fit on every observation uses at most `budget` of
   * them drawn by `sampling` (0: all; default CF_FIT_DEFAULT_BUDGET,
   * stratified); the starts and the model choice use their own subsamples
   * anyway */
  size_t budget;
  cf_sampling sampling;
  int no_response_starts; /* 1: an unknown tone curve's shape only from the
                             start's (the model choice's candidates; by
                             default the fit also tries the common camera
                             curves' shapes, fit_response_starts.h) */
  int jpeg_plain;          /* 1: leave JPEG's coding error out of the model
                             (default 0: JPEG photos whose quality their
                             tables give are compared with the prediction
                             as their codec codes it, docs/model.md §6.2) */
  double density;         /* the film's known thickness for the report of
                             density and absorption; NaN: the convention
                             (mean absorption 0.8) */
  cf_progress_fn progress;
  void *progress_user;
  /* optional: one line of text for every iteration of every solve and
   * every decision of the solver around Ceres (clayfit fit --trace), to
   * study convergence; called from the fit's threads, one solve at a time
   * per model */
  void (*trace)(void *user, const char *line);
  void *trace_user;
} cf_fit_options;

/* The default pixel budget: 10⁵ observations, stratified by half-angle.
 * Measured (clayfit bench fit, docs/benchmarks.md): on the synthetic captures and on
 * DiLiGenT the relative RMSE over every observation stays within 1 % of
 * the fit to all of them (10⁴ failed on DiLiGenT: too few highlight
 * pixels), at a half to a third of the time; the standard deviations are
 * the sample's (larger by about √(observations / 10⁵)). */
#define CF_FIT_DEFAULT_BUDGET 100000

void cf_fit_default_options(cf_fit_options *options, cf_model_id model);

/* A parameter held by name (clayfit fit --hold, a batch manifest's
 * "hold"): count 1 (that value in every component) or the parameter's
 * components (3: r, g, b). */
typedef struct cf_fit_hold {
  const char *name;
  int count;
  double value[3];
} cf_fit_hold;

enum { CF_FIT_MAX_NAMED = 64 }; /* holds, and frees, at most */

/* The options of `model`: its defaults, with the settings every model
 * shares taken from `settings` (loss, loss_scale, fit_exposures,
 * jpeg_plain, multistart, max_iterations, threads, density, footprint,
 * footprint_tolerance, budget, sampling), then the holds and the frees
 * (parameter names; a free fits what would be held for the scale). With
 * known (the model choice: one flag per hold, then per free), a name the
 * model lacks is skipped and its flag set for names it has; without, it
 * is CF_ENOTFOUND. A parameter held twice, or held and freed: CF_EINVAL.
 * The one way clayfit fit and clayfit batch build a fit's options. */
cf_status cf_fit_model_options(cf_model_id model, const cf_fit_options *settings,
                               const cf_fit_hold *holds, int hold_count,
                               const char *const *frees, int free_count, int *known,
                               cf_fit_options *options, cf_error *err);

/* Every model's options for the model choice (--model auto): a hold or a
 * free applies to the models that have the parameter and must name one
 * that some model has (CF_ENOTFOUND). */
cf_status cf_fit_ladder_options(const cf_fit_options *settings, const cf_fit_hold *holds,
                                int hold_count, const char *const *frees, int free_count,
                                cf_fit_options ladder[CF_MODEL_COUNT], cf_error *err);

/* One start of the multi-start and where it ended. */
typedef struct cf_fit_start {
  double start[CF_MAX_DIM], end[CF_MAX_DIM];
  double cost; /* ½ Σ ρ at the end */
  int iterations;
  int stopped; /* 1: stopped where an earlier start's minimum was (within
                  1 % of every range, or within the noise of it) */
} cf_fit_start;

enum {
  CF_FIT_MAX_STARTS = 32,
  CF_FIT_MAX_WARNINGS = 8,
  CF_FIT_FOOTPRINT_MAX_SAMPLES = 16,
  CF_FIT_MAX_TRACE = 512
};
#define CF_FIT_CORE_RADIUS_PX 3.0

/* The stages of a fit, for their wall times. */
typedef enum cf_fit_stage {
  CF_FIT_STAGE_START,      /* closed-form albedo and the multi-start */
  CF_FIT_STAGE_REFINE,     /* the best start on a larger subsample */
  CF_FIT_STAGE_SOLVE,      /* every observation: weights, robust loss,
                              unconstrained parameters held */
  CF_FIT_STAGE_STATISTICS, /* residual statistics */
  CF_FIT_STAGE_COUNT
} cf_fit_stage;

const char *cf_fit_stage_name(cf_fit_stage stage);

typedef struct cf_fit_result {
  cf_model_id model;
  double params[CF_MAX_DIM]; /* the fitted (or held) values */
  double sd[CF_MAX_DIM];     /* standard deviations; 0 where not fitted */
  cf_param_status status[CF_MAX_DIM];
  int free_count;            /* fitted slots, in slot order */
  int free_slots[CF_MAX_DIM];
  double correlation[CF_MAX_DIM * CF_MAX_DIM]; /* free_count² */
  double scale, scale_sd;    /* the global scale s (1 for absolute radiometry) */
  int scale_fitted;
  /* the camera response R of photos whose tone curve the capture says is
   * unknown (clayfit/response_model.h): the prediction is R(s e_k Σ f E c_i)
   * in the decoded values. Its slopes at the knots and their covariance
   * (K × K, row-major; 0 where a slope ended at a bound); all slopes 1 and
   * not fitted when the tone curve is known */
  double response[CF_RESPONSE_MODEL_KNOTS];
  double response_covariance[CF_RESPONSE_MODEL_KNOTS * CF_RESPONSE_MODEL_KNOTS];
  int response_fitted;
  size_t images;
  double *exposures;         /* e_k per image (1 unless fitted), owned */
  double *exposure_sd;       /* their sd per image (0 unless fitted), owned */
  /* the white balance b_kc per image and channel (3 × images; green's 1;
   * red's and blue's 1 unless CF_GAINS_PER_IMAGE_RGB) and their sd: channel
   * c of image k has the gain s e_k b_kc; owned, NULL in older files */
  double *white_balance, *white_balance_sd;
  int white_balance_fitted;
  /* the gains per light inside each image's sum over its lights
   * (CF_GAINS_PER_LIGHT where an image has several lights; docs/fitting.md):
   * light_count lights (0 otherwise), each's gain g_l (their mean log is
   * 0), its sd and its name (cf_capture_light_name); owned, NULL without */
  size_t light_count;
  double *light_gains, *light_gains_sd;
  char (*light_names)[CF_FIT_LIGHT_NAME];
  double sigma;              /* σ when estimated from the residuals, else 0;
                              * with a fitted response curve τ, in linear
                              * units: σ = τ R'(x) (docs/model.md (52a)) */

  /* the pixel budget the fit used: sample_count observations drawn by
   * `sampling` from the population_count in use (sample_count 0: every
   * observation, no budget) */
  size_t sample_count, population_count;
  cf_sampling sampling;

  /* residuals over every observation and channel, unweighted, radiance
   * units; relative = RMSE / RMS of the measurements. With a pixel
   * budget: estimated from the sample, each residual weighed by its
   * observation's weight (the counts are the sample's) */
  size_t residuals, censored, rejected; /* rejected: |r| beyond the loss scale */
  double rmse, relative_rmse;
  double *image_rmse, *image_relative_rmse; /* per image, owned */
  double cost;               /* ½ Σ ρ(r²) at the end, in units of σ² */
  int iterations;            /* Levenberg-Marquardt iterations on every
                                observation (all solves of that stage) */
  int solves;                /* Ceres solves of that stage */
  char termination[64];      /* of the last one */
  double solve_seconds;      /* Ceres' time in them */
  /* the convergence trace: the cost (½ Σ ρ, σ units) at the start and
   * after each successful iteration of those solves, in order (the weights
   * change between solves, so it steps there) */
  double trace[CF_FIT_MAX_TRACE];
  int trace_count;
  double stage_seconds[CF_FIT_STAGE_COUNT]; /* wall time of each stage */

  /* the footprint integration of the fit on every observation */
  size_t footprint_observations; /* integrated with S >= 2 */
  size_t footprint_samples;      /* Σ S² over those */
  int footprint_max;             /* the largest S (1: pixel centres only) */

  int free_unknowns;         /* everything estimated: model slots (fitted or
                                at a bound), scale, exposures */

  int starts;                /* 0 when the fit began at options.start */
  cf_fit_start start[CF_FIT_MAX_STARTS];
  int best_start;
  int ambiguous;             /* two distant starts ended within the noise */

  /* the highlight cores: the observations within CF_FIT_CORE_RADIUS_PX of
   * each image's brightest observation (where a lobe's shape shows), and
   * the rest */
  size_t core_residuals;
  double core_rmse, core_relative_rmse, rest_rmse, rest_relative_rmse;

  /* JPEG's coding error, modelled (0 images: not): the codec's mean change
   * of the predicted photos where they were compared, in codes of 1/255:
   * its rms over the channels and its mean per channel */
  int jpeg_images;
  double jpeg_bias_rms, jpeg_bias_mean[3];

  int warning_count;
  char warnings[CF_FIT_MAX_WARNINGS][256];
} cf_fit_result;

/* ---- the choice of the model (clayfit fit --model auto) ----
 *
 * Every candidate (the ladder M0 → M4, simplest first: fit_choice.c's
 * table of rungs) is fitted to the training part of a sample of the
 * observations (at most CF_FIT_CHOICE_SAMPLE, spread evenly), with the
 * fit's own loss, and judged two ways:
 *   BIC      2 C + k ln n on the training part, C = ½ Σ ρ(r²) (the fits'
 *            loss: what they minimised) at one σ for all candidates (the
 *            capture's noise model, or the smallest σ the candidates
 *            estimated), k the unknowns fitted, n the residuals;
 *   held out the RMS √(mean r²) (in units of σ) on the held-out part,
 *            without the robust loss (censored channels as the objective
 *            has them), so that no model can improve it by calling a whole
 *            highlight an outlier:
 *            every fourth image (with four or more images and no exposures
 *            fitted; with a light per image, as in DiLiGenT, these are
 *            held-out lights), else the last image, else every fourth
 *            observation.
 * The decision (fit_choice.c):
 *   1. the walk: going up the ladder, a richer model replaces the current
 *      choice only when clearly better on both: BIC lower by more than
 *      bic_margin (10: "very strong" evidence, Kass & Raftery 1995) and
 *      the held-out RMS lower by more than heldout_margin (1 %: a model
 *      error of about a seventh of the noise);
 *   2. the guard: a choice whose held-out RMS is more than heldout_guard
 *      (10 %) above the lowest is replaced by the simplest candidate
 *      within 10 % of the lowest, unless its BIC is lower than that one's
 *      by more than bic_margin (the note then says so);
 *   3. the physical reading: a choice whose film is a second lobe
 *      (cf_fit_choice.reading) gives way to a candidate marked as the
 *      simpler physical reading (a single tailed lobe) when that one does
 *      as well within the margins (held-out RMS at most heldout_margin
 *      above, BIC at most bic_margin above).
 * The chosen model is then fitted to every observation, starting from its
 * candidate fit. */
/* 3·10⁴: on the demo capture and DiLiGenT the same choices as 6·10⁴, the
 * margins still far beyond the thresholds (BIC M3 → M4 by 6300 and 38600),
 * in 1.1 s and 2.3 s instead of 2.0 s and 3.9 s */
#define CF_FIT_CHOICE_SAMPLE 30000
#define CF_FIT_CHOICE_BIC_MARGIN 10.0
#define CF_FIT_CHOICE_HELDOUT_MARGIN 0.01
#define CF_FIT_CHOICE_HELDOUT_GUARD 0.10
/* A film that is not a film: rougher than any liquid film's surface
 * (DiLiGenT's M4 puts 0.87 there, as a second lobe), or an F0 twice oil's
 * 0.035 (water 0.02; η ≈ 1.72, beyond any water or oil film) */
#define CF_FIT_FILM_MAX_ROUGHNESS 0.7
#define CF_FIT_FILM_MAX_F0 0.07

enum { CF_FIT_MAX_CANDIDATES = CF_MODEL_COUNT };

typedef struct cf_fit_candidate {
  cf_model_id model;
  int ok;                  /* 0: the fit failed (why: note) */
  int physical;            /* 1: the simpler physical reading of a model
                              whose film is a second lobe (rule 3) */
  cf_fit_result fit;       /* on the training part (owns its arrays) */
  int parameters;          /* k */
  size_t residuals;        /* n, training */
  double cost, bic;        /* training, ½ Σ ρ(r²) at the common σ (with a
                              fitted response and a noise model, each its
                              own σ, the BIC with 2 Σ log σ: docs/model.md
                              §6.8) */
  size_t heldout_residuals;
  double heldout_score;    /* √(mean r²) without the loss, σ units (with a fitted response
                              and a noise model, times σ's geometric mean) */
  double heldout_rmse, heldout_relative_rmse; /* plain, radiance units */
  double seconds;
  int chosen;
  char note[320];          /* how it compared, and why it was chosen */
} cf_fit_candidate;

typedef struct cf_fit_choice {
  int automatic;           /* 0: the model was forced (--model M) */
  cf_model_id chosen;
  int count;
  cf_fit_candidate candidate[CF_FIT_MAX_CANDIDATES]; /* in ladder order */
  size_t train_observations, heldout_observations;
  char heldout[256];       /* what was held out */
  double sigma;            /* the common σ (0: the capture's noise model) */
  cf_loss loss;            /* the loss of the candidates' fits and BIC
                              (the first model's; the held-out RMS has none) */
  double loss_scale;
  double bic_margin, heldout_margin, heldout_guard;
  char reading[320];       /* what the chosen model's parameters mean where
                              they are not what they are named after ("M4's
                              film parameters describe a second lobe, not a
                              film: ..."); empty if nothing to say */
  double ggx_cost;         /* a tailed choice (M2T, M4T): its GGX twin's
                              held-out RMS over its own, minus 1 (NaN for
                              a GGX choice), and the sentence that says so */
  char ggx_cost_text[200];
  double seconds;          /* wall time of the choice (the candidates' fits
                              and scores) */
} cf_fit_choice;

/* What a fit's parameters mean where they are not what they are named after
 * (an M4 or M4T whose film is a second lobe, cf_fit_choice.reading; also for
 * a forced model): 1 and the sentence in text, else 0. */
int cf_fit_reading(const cf_fit_result *result, char *text, size_t size);

/* The candidate of the chosen model (NULL if none). */
const cf_fit_candidate *cf_fit_choice_chosen(const cf_fit_choice *choice);

/* Choose the model (options[m] for model m: each candidate's holds) and fit
 * it to every observation: result is the chosen model's fit. Free both
 * with cf_fit_choice_free and cf_fit_result_free. */
cf_status cf_fit_auto(const cf_capture *capture, const cf_fit_options options[CF_MODEL_COUNT],
                      cf_fit_choice *choice, cf_fit_result *result, cf_error *err);
void cf_fit_choice_free(cf_fit_choice *choice);

/* Options that no capture could make right, before any work: a held
 * value outside its parameter's range (the message names the parameter,
 * the value and the range), a start out of range, a footprint tolerance
 * outside (0, 1). CF_ERANGE or CF_EINVAL. */
cf_status cf_fit_check_options(const cf_fit_options *options, cf_error *err);

/* With options->fit_exposures, can the capture tell each image's gain
 * from the material? At the base start (the closed-form albedo, the
 * defaults) on the fit's sample, the normal equations of the options'
 * model, the scale and the gains, with the material and the scale
 * profiled out (a Schur complement): CF_EINVAL naming the images when
 * that block is singular or a gain's predicted sd is above 10 %. CF_OK
 * without fitted exposures. cf_fit_auto and cf_fit_run (without a start
 * of their own) call it before any fit. */
cf_status cf_fit_check_gains(const cf_capture *capture, const cf_fit_options *options,
                             cf_error *err);

/* Fit one model to a loaded capture. The result owns its per-image arrays
 * (cf_fit_result_free). */
cf_status cf_fit_run(const cf_capture *capture, const cf_fit_options *options,
                     cf_fit_result *result, cf_error *err);
void cf_fit_result_free(cf_fit_result *result);

/* A fit's residual statistics (at its parameters, scale and exposures)
 * on the observations of the images with use_image[k] (NULL: all): the
 * residual counts, RMSE and relative RMSE, the highlight cores and the rest,
 * per image (0 for an image not used), into *stats, whose other fields are
 * copied from fit (cf_fit_result_free). */
cf_status cf_fit_evaluate(const cf_capture *capture, const cf_fit_result *fit,
                          const unsigned char *use_image, const cf_fit_options *options,
                          cf_fit_result *stats, cf_error *err);

/* A fit's prediction of every observation of the capture (3 per
 * observation, in cf_observations' order and units: radiance divided by the
 * image's exposure), integrating the pixel footprints as options say, with
 * the fit's scale, exposures and response; and, when sigma is not NULL,
 * the noise σ of each (the capture's noise model at the prediction, or the
 * fit's estimated σ). */
cf_status cf_fit_predict(const cf_capture *capture, const cf_fit_result *fit,
                         const cf_fit_options *options, double *prediction, double *sigma,
                         cf_error *err);

const char *cf_param_status_name(cf_param_status status);

/* fit.json, written and read back: include/clayfit/fit_file.h */

#ifdef __cplusplus
}
#endif

#endif /* CLAYFIT_FIT_H */
