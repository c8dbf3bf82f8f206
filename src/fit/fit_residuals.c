/* Residual statistics of a fit and σ from its residuals
 * (fit_residuals.h). */
#include "fit_residuals.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/memory.h"
#include "core/order_statistics.h"
#include "fit_plan.h"

/* Per image, the observation with the brightest measurement (−1: none). */
static cf_status brightest(const fit_problem *p, const double *measured, long **best,
                           cf_error *err) {
  size_t images = fit_problem_images(p);
  double *level = malloc((images ? images : 1) * sizeof *level);
  *best = malloc((images ? images : 1) * sizeof **best);
  if (!level || !*best) {
    free(level);
    return cf_error_set(err, CF_ENOMEM, "out of memory");
  }
  for (size_t k = 0; k < images; ++k) level[k] = -HUGE_VAL, (*best)[k] = -1;
  for (size_t i = 0; i < fit_problem_count(p); ++i) {
    uint32_t image = fit_problem_image(p, i);
    double y = measured[3 * i] + measured[3 * i + 1] + measured[3 * i + 2];
    if (y > level[image]) level[image] = y, (*best)[image] = (long)i;
  }
  free(level);
  return CF_OK;
}

/* Weighted sums of squared residuals and measurements, the weights' sum
 * and the count (a pixel budget's weights make the sums estimates of
 * every observation's; without one every weight is 1). */
typedef struct sums {
  double e2, y2, w;
  size_t n;
} sums;

static void add(sums *s, double e, double y, double w) {
  s->e2 += w * e * e;
  s->y2 += w * y * y;
  s->w += w;
  ++s->n;
}

static double rms(const sums *s) {
  return s->w > 0.0 ? sqrt(s->e2 / s->w) : 0.0;
}
static double relative(const sums *s) {
  return s->y2 > 0.0 ? sqrt(s->e2 / s->y2) : 0.0;
}

cf_status fit_statistics(fit_problem *p, const cf_fit_options *o, cf_fit_result *r, cf_error *err) {
  size_t count = fit_problem_count(p), n = 3 * count, images = fit_problem_images(p);
  const cf_observations *obs = cf_capture_observations(fit_problem_capture(p));
  const double *inv_sigma = fit_problem_inv_sigma(p), *root = fit_problem_sample_roots(p);
  double *prediction = malloc((n ? n : 1) * sizeof *prediction);
  double *measured = malloc((n ? n : 1) * sizeof *measured);
  sums *per_image = calloc(images ? images : 1, sizeof *per_image);
  long *best = NULL;
  r->image_rmse = calloc(images ? images : 1, sizeof *r->image_rmse);
  r->image_relative_rmse = calloc(images ? images : 1, sizeof *r->image_relative_rmse);
  cf_status s = prediction && measured && per_image && r->image_rmse && r->image_relative_rmse
                    ? fit_problem_predict(p, prediction, measured, err)
                    : cf_error_set(err, CF_ENOMEM, "out of memory");
  if (s == CF_OK) s = brightest(p, measured, &best, err);
  sums total = {0}, core = {0}, rest = {0};
  const double radius2 = CF_FIT_CORE_RADIUS_PX * CF_FIT_CORE_RADIUS_PX;
  for (size_t i = 0; s == CF_OK && i < count; ++i) {
    size_t k = fit_problem_observation(p, i);
    uint32_t image = obs->image[k];
    size_t b = (size_t)best[image]; /* the image has an observation: this one */
    size_t kb = fit_problem_observation(p, b);
    double dx = (double)obs->pixel[2 * k] - (double)obs->pixel[2 * kb];
    double dy = (double)obs->pixel[2 * k + 1] - (double)obs->pixel[2 * kb + 1];
    int in_core = dx * dx + dy * dy <= radius2;
    double w = root ? root[i] * root[i] : 1.0;
    for (int c = 0; c < 3; ++c) {
      size_t at = 3 * i + (size_t)c;
      double e = prediction[at] - measured[at];
      if (fit_problem_censored(p, at, prediction[at], measured[at])) {
        ++r->censored; /* predicted at or above the clip level: no residual */
        continue;
      }
      if (o->loss != CF_LOSS_NONE && fabs(e) * inv_sigma[at] > o->loss_scale) ++r->rejected;
      add(&total, e, measured[at], w);
      add(&per_image[image], e, measured[at], w);
      add(in_core ? &core : &rest, e, measured[at], w);
    }
  }
  if (s == CF_OK) {
    r->residuals = total.n;
    r->rmse = rms(&total);
    r->relative_rmse = relative(&total);
    r->core_residuals = core.n;
    r->core_rmse = rms(&core);
    r->core_relative_rmse = relative(&core);
    r->rest_rmse = rms(&rest);
    r->rest_relative_rmse = relative(&rest);
    for (size_t k = 0; k < images; ++k) {
      r->image_rmse[k] = rms(&per_image[k]);
      r->image_relative_rmse[k] = relative(&per_image[k]);
    }
  }
  free(prediction);
  free(measured);
  free(per_image);
  free(best);
  return s;
}

/* σ = 1.4826 × the median absolute residual (a robust estimate), over the
 * uncensored residuals at the current values; a sample's weights weigh
 * the median. With σ through the curve, τ: the residuals divided by
 * R'(x) at the prediction. */
cf_status fit_estimate_sigma(fit_problem *p, double *sigma, cf_error *err) {
  size_t n = 3 * fit_problem_count(p);
  const double *root = fit_problem_sample_roots(p);
  double *prediction = malloc((n ? n : 1) * sizeof *prediction);
  double *measured = malloc((n ? n : 1) * sizeof *measured);
  cf_status s = prediction && measured ? fit_problem_predict(p, prediction, measured, err)
                                       : cf_error_set(err, CF_ENOMEM, "out of memory");
  size_t m = 0;
  int through = fit_problem_sigma_through_curve(p);
  for (size_t i = 0; s == CF_OK && i < n; ++i) {
    double e = prediction[i] - measured[i];
    if (fit_problem_censored(p, i, prediction[i], measured[i])) continue;
    if (through) e /= fit_problem_curve_slope(p, prediction[i]);
    double w = root ? root[i / 3] * root[i / 3] : 1.0;
    prediction[m] = fabs(e);
    measured[m++] = w; /* the weight (m <= i: nothing unread is overwritten) */
  }
  double median = 0.0;
  if (s == CF_OK && m > 0) {
    if (!root)
      median = order_kth_smallest(prediction, m, m / 2);
    else if (!order_weighted_median(prediction, measured, m, &median))
      s = cf_error_set(err, CF_ENOMEM, "out of memory");
  }
  /* (1e-12: a positive σ for a fit that is exact to rounding, not a trade) */
  if (s == CF_OK) *sigma = median > 0.0 ? 1.4826 * median : 1e-12;
  free(prediction);
  free(measured);
  return s;
}

/* A fit's values (parameters, scale, response, exposures, white balance,
 * lights' gains) into v. */
static void values_of_fit(const fit_problem *p, const cf_fit_result *fit, fit_values *v) {
  const fit_groups *g = fit_problem_groups(p);
  memcpy(v->params, fit->params, sizeof v->params);
  v->log_scale = log(fit->scale);
  if (fit->response_fitted) memcpy(v->response, fit->response, sizeof v->response);
  for (size_t k = 0; k < g->images && fit->exposures; ++k)
    v->log_exposures[k] = log(fit->exposures[k]);
  for (size_t i = 0; i < 3 * g->images && fit->white_balance; ++i)
    v->log_balance[i] = log(fit->white_balance[i]);
  for (size_t l = 0; l < g->light_count && fit->light_gains && fit->light_count == g->light_count;
       ++l)
    v->log_light[l] = log(fit->light_gains[l]);
}

/* The problem over a population at a fit's values, nothing free, its
 * footprints integrated as o says and σ from the noise model at the
 * prediction, or `sigma` for all (τ through the curve at the prediction:
 * fit_problem_set_sigma). On failure *p is NULL. */
static cf_status problem_at_fit(fit_problem **p, const cf_capture *capture,
                                const fit_population *population, const cf_fit_result *fit,
                                double sigma, const cf_fit_options *o, cf_error *err) {
  cf_status s = fit_problem_new(p, capture, fit->model, population->index, population->count,
                                fit_threads(o), err);
  if (s != CF_OK) return s;
  values_of_fit(*p, fit, fit_problem_values(*p));
  fit_problem_set_loss(*p, o->loss, o->loss_scale);
  fit_problem_clear_unknowns(*p);
  s = fit_problem_finish(*p, err);
  if (s == CF_OK) s = fit_footprint_update(*p, o, NULL, err);
  if (s == CF_OK && !fit_capture_has_noise(capture)) fit_problem_set_sigma(*p, sigma);
  if (s == CF_OK) /* (without a noise model a no-op unless σ goes through the curve) */
    s = fit_problem_reweight(*p, err);
  if (s != CF_OK) {
    fit_problem_free(*p);
    *p = NULL;
  }
  return s;
}

cf_status fit_sum_log_sigma(const fit_problem *p, double *sum, cf_error *err) {
  size_t n = 3 * fit_problem_count(p);
  const double *root = fit_problem_sample_roots(p), *inv_sigma = fit_problem_inv_sigma(p);
  double *prediction = malloc((n ? n : 1) * sizeof *prediction);
  double *measured = malloc((n ? n : 1) * sizeof *measured);
  cf_status s = prediction && measured ? fit_problem_predict(p, prediction, measured, err)
                                       : cf_error_set(err, CF_ENOMEM, "out of memory");
  *sum = 0.0;
  for (size_t i = 0; s == CF_OK && i < n; ++i) {
    if (fit_problem_censored(p, i, prediction[i], measured[i])) continue;
    double w = root ? root[i / 3] * root[i / 3] : 1.0;
    *sum -= w * log(inv_sigma[i]);
  }
  free(prediction);
  free(measured);
  return s;
}

/* The fit's gains per light (if any) into stats (allocated). */
static cf_status copy_light_gains(const cf_fit_result *fit, cf_fit_result *stats, cf_error *err) {
  size_t n = fit->light_count;
  if (n == 0 || !fit->light_gains || !fit->light_gains_sd || !fit->light_names) return CF_OK;
  stats->light_gains = malloc(n * sizeof *stats->light_gains);
  stats->light_gains_sd = malloc(n * sizeof *stats->light_gains_sd);
  stats->light_names = malloc(n * sizeof *stats->light_names);
  if (!stats->light_gains || !stats->light_gains_sd || !stats->light_names)
    return cf_error_set(err, CF_ENOMEM, "out of memory");
  memcpy(stats->light_gains, fit->light_gains, n * sizeof *stats->light_gains);
  memcpy(stats->light_gains_sd, fit->light_gains_sd, n * sizeof *stats->light_gains_sd);
  memcpy(stats->light_names, fit->light_names, n * sizeof *stats->light_names);
  stats->light_count = n;
  return CF_OK;
}

cf_status fit_score_at(const cf_capture *capture, const fit_population *population,
                       const cf_fit_result *fit, double sigma, const cf_fit_options *o,
                       double *cost, double *log_sigma, cf_fit_result *stats, cf_error *err) {
  *stats = *fit;
  stats->exposures = stats->image_rmse = stats->image_relative_rmse = NULL;
  stats->exposure_sd = stats->white_balance = stats->white_balance_sd = NULL; /* (copied below) */
  stats->light_gains = stats->light_gains_sd = NULL, stats->light_names = NULL;
  stats->light_count = 0; /* (copied below) */
  stats->residuals = stats->censored = stats->rejected = 0;
  *cost = 0.0;
  fit_problem *p;
  cf_status s = problem_at_fit(&p, capture, population, fit, sigma, o, err);
  if (s != CF_OK) return s;
  if (!fit_problem_cost(p, cost))
    s = cf_error_set(err, CF_ENUMERIC, "the %s fit cannot be evaluated on these observations",
                     cf_model_info_get(fit->model)->code);
  if (log_sigma) *log_sigma = 0.0;
  if (s == CF_OK && log_sigma && fit->response_fitted &&
      (fit_capture_has_noise(capture) || fit_problem_sigma_through_curve(p)))
    s = fit_sum_log_sigma(p, log_sigma, err);
  if (s == CF_OK) s = fit_statistics(p, o, stats, err);
  if (s == CF_OK && fit->exposures) {
    stats->exposures = malloc(fit->images * sizeof *stats->exposures);
    if (stats->exposures)
      memcpy(stats->exposures, fit->exposures, fit->images * sizeof *fit->exposures);
    else
      s = cf_error_set(err, CF_ENOMEM, "out of memory");
  }
  double **own[3] = {&stats->exposure_sd, &stats->white_balance, &stats->white_balance_sd};
  const double *its[3] = {fit->exposure_sd, fit->white_balance, fit->white_balance_sd};
  for (int a = 0; s == CF_OK && a < 3; ++a) { /* the fit's per-image arrays, copied */
    size_t count = (a == 0 ? 1 : 3) * fit->images;
    if (!its[a]) continue;
    *own[a] = malloc((count ? count : 1) * sizeof **own[a]);
    if (*own[a])
      memcpy(*own[a], its[a], count * sizeof **own[a]);
    else
      s = cf_error_set(err, CF_ENOMEM, "out of memory");
  }
  if (s == CF_OK) s = copy_light_gains(fit, stats, err);
  fit_problem_free(p);
  if (s != CF_OK) cf_fit_result_free(stats);
  return s;
}

cf_status cf_fit_predict(const cf_capture *capture, const cf_fit_result *fit,
                         const cf_fit_options *options, double *prediction, double *sigma,
                         cf_error *err) {
  fit_problem *p;
  fit_population all = {NULL, cf_capture_observations(capture)->count, NULL};
  cf_status s =
      problem_at_fit(&p, capture, &all, fit, fit->sigma > 0.0 ? fit->sigma : 1.0, options, err);
  if (s != CF_OK) return s;
  size_t n = 3 * fit_problem_count(p);
  const double *inv_sigma = fit_problem_inv_sigma(p);
  double *measured = cf_malloc_large((n ? n : 1) * sizeof *measured);
  s = measured ? fit_problem_predict(p, prediction, measured, err)
               : cf_error_set(err, CF_ENOMEM, "out of memory");
  for (size_t i = 0; s == CF_OK && sigma && i < n; ++i) sigma[i] = 1.0 / inv_sigma[i];
  free(measured);
  fit_problem_free(p);
  return s;
}

cf_status cf_fit_evaluate(const cf_capture *capture, const cf_fit_result *fit,
                          const unsigned char *use_image, const cf_fit_options *options,
                          cf_fit_result *stats, cf_error *err) {
  memset(stats, 0, sizeof *stats);
  fit_population population;
  uint32_t *index;
  double cost;
  cf_status s = fit_population_of_images(capture, use_image, &population, &index, err);
  if (s == CF_OK)
    s = fit_score_at(capture, &population, fit, fit->sigma > 0.0 ? fit->sigma : 1.0, options, &cost,
                     NULL, stats, err);
  free(index);
  return s;
}
