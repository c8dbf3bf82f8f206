/* The fit's least-squares problem (fit_problem.h). */
#include "fit_problem.h"

#include <limits.h>
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "core/order_statistics.h"
#include "lsq/lsq.h"
#include "core/parallel.h"

enum { BLOCK_SIZE = 1024 };

/* Problems of fewer observations are built on one thread. */
enum { INIT_PARALLEL_MIN = 65536 };

static size_t observation(const fit_problem *p, size_t i) {
  return p->index ? p->index[i] : i;
}

void fit_sample_free(fit_sample *sample) {
  free(sample->index);
  free(sample->weight);
  memset(sample, 0, sizeof *sample);
}

cf_status fit_sample_draw(const cf_observations *obs, const fit_population *from, size_t target,
                          fit_sample *sample, cf_error *err) {
  memset(sample, 0, sizeof *sample);
  size_t n = from->count;
  size_t capacity = n <= target ? n : target + 2;
  sample->index = malloc((capacity ? capacity : 1) * sizeof *sample->index);
  sample->weight = malloc((capacity ? capacity : 1) * sizeof *sample->weight);
  double *score = n > target ? malloc(n * sizeof *score) : NULL;
  double *sorted = n > target ? malloc(n * sizeof *sorted) : NULL;
  if (!sample->index || !sample->weight || (n > target && (!score || !sorted))) {
    free(score);
    free(sorted);
    fit_sample_free(sample);
    return cf_error_set(err, CF_ENOMEM, "out of memory for a sample of %zu observations", target);
  }
  if (n <= target) { /* the whole population */
    for (size_t i = 0; i < n; ++i) {
      sample->index[i] = from->index ? from->index[i] : (uint32_t)i;
      sample->weight[i] = 1.0;
    }
    sample->count = n;
    return CF_OK;
  }
  for (size_t i = 0; i < n; ++i)
    score[i] = sorted[i] = cf_observation_specularity(obs, from->index ? from->index[i] : i);
  double threshold = order_kth_smallest(sorted, n, n - n / 16);
  size_t specular = 0;
  for (size_t i = 0; i < n; ++i) specular += score[i] >= threshold;
  /* per stratum: how many to take, spread evenly over it */
  size_t want[2] = {target / 4, target - target / 4}, size[2] = {specular, n - specular};
  size_t taken[2] = {0, 0}, spread[2] = {0, 0};
  size_t m = 0;
  for (size_t i = 0; i < n && m < capacity; ++i) {
    int t = score[i] >= threshold ? 0 : 1;
    if (!fit_spread_take(&spread[t], want[t], size[t])) continue;
    sample->index[m] = from->index ? from->index[i] : (uint32_t)i;
    sample->weight[m] = (double)t; /* the stratum, for now */
    ++taken[t];
    ++m;
  }
  for (size_t i = 0; i < m; ++i) {
    int t = (int)sample->weight[i];
    sample->weight[i] = (double)size[t] / (double)taken[t];
  }
  sample->count = m;
  free(score);
  free(sorted);
  return CF_OK;
}

cf_status fit_problem_set_sample_weights(fit_problem *p, const double *weight, cf_error *err) {
  free(p->sample_root);
  p->sample_root = malloc((p->count ? p->count : 1) * sizeof *p->sample_root);
  if (!p->sample_root) return cf_error_set(err, CF_ENOMEM, "out of memory");
  for (size_t i = 0; i < p->count; ++i) p->sample_root[i] = sqrt(weight[i]);
  return CF_OK;
}

/* Observations [begin, end) of fit_problem_init: measurements, images,
 * flags, and their pairs' geometry and weights. */
typedef struct init_job {
  fit_problem *p;
  int parts;
} init_job;

static void init_part(void *user, int part) {
  const init_job *job = user;
  fit_problem *p = job->p;
  const cf_observations *o = p->obs;
  size_t begin, end;
  cf_part_range(p->count, job->parts, part, &begin, &end);
  for (size_t i = begin; i < end; ++i) {
    size_t k = observation(p, i), slot = k * (size_t)p->lights, pair = i * (size_t)p->lights;
    for (int c = 0; c < 3; ++c) p->y[3 * i + (size_t)c] = o->rgb[3 * k + (size_t)c];
    p->image[i] = o->image[k];
    p->flags[i] = o->flags[k];
    fit_pairs_at(p->lights, o->normal + 3 * k, o->view + 3 * k, o->light_dir + 3 * slot,
                 o->irradiance + 3 * slot, 1.0, p->geometry + pair, p->weight + 3 * pair);
  }
}

/* The capture's lights (cf_capture_light_ids) into p: slot_light,
 * light_count, log_light (0), image_lights, several_lights and
 * light_of_image. 0: no memory. */
static int problem_lights(fit_problem *p, const cf_capture *capture) {
  size_t lights = (size_t)p->lights, images = p->images ? p->images : 1;
  p->slot_light = malloc(images * (lights ? lights : 1) * sizeof *p->slot_light);
  if (!p->slot_light) return 0;
  p->light_count = cf_capture_light_ids(capture, p->slot_light);
  p->log_light = calloc(p->light_count ? p->light_count : 1, sizeof *p->log_light);
  long *first = malloc((p->light_count ? p->light_count : 1) * sizeof *first);
  if (!p->log_light || !first) return free(first), 0;
  for (size_t l = 0; l < p->light_count; ++l) first[l] = -1;
  for (size_t k = 0; k < p->images; ++k) {
    const long *id = p->slot_light + k * lights;
    int distinct = 0;
    long only = -1;
    for (size_t j = 0; j < lights; ++j) {
      int seen = id[j] < 0;
      for (size_t i = 0; i < j && !seen; ++i) seen = id[i] == id[j];
      if (!seen) distinct += 1, only = id[j];
    }
    if (distinct == 1 && first[only] < 0) first[only] = (long)k;
    p->light_of_image[k] = distinct == 1 ? first[only] : -1;
    p->image_lights = distinct > p->image_lights ? distinct : p->image_lights;
  }
  p->several_lights = p->image_lights > 1;
  free(first);
  return 1;
}

cf_status fit_problem_init(fit_problem *p, const cf_capture *capture, cf_model_id model,
                           const uint32_t *index, size_t count, int threads, cf_error *err) {
  memset(p, 0, sizeof *p);
  p->obs = cf_capture_observations(capture);
  p->model = model;
  p->dim = cf_model_info_get(model)->dim;
  p->lights = p->obs->lights;
  p->index = index;
  p->count = index ? count : p->obs->count;
  p->images = cf_capture_image_count(capture);
  p->last_image = (uint32_t)(p->images - 1);
  p->loss = CF_LOSS_NONE;
  p->loss_scale = 3.0;
  fit_response_identity(p->response);
  p->block_size = BLOCK_SIZE;
  p->threads = threads > 1 ? threads : 1;
  cf_model_default_params(model, p->params);
  size_t pairs = p->count * (size_t)p->lights;
  p->slots = pairs;
  p->geometry = malloc(pairs * sizeof *p->geometry);
  p->weight = malloc(3 * pairs * sizeof *p->weight);
  p->inv_sigma = malloc(3 * p->count * sizeof *p->inv_sigma);
  p->log_exposures = calloc(p->images, sizeof *p->log_exposures);
  p->log_balance = calloc(3 * (p->images ? p->images : 1), sizeof *p->log_balance);
  p->gain_group = malloc((p->images ? p->images : 1) * sizeof *p->gain_group);
  p->group_image = malloc((p->images ? p->images : 1) * sizeof *p->group_image);
  p->light_of_image = malloc((p->images ? p->images : 1) * sizeof *p->light_of_image);
  p->y = malloc(3 * (p->count ? p->count : 1) * sizeof *p->y);
  p->image = malloc((p->count ? p->count : 1) * sizeof *p->image);
  p->flags = malloc(p->count ? p->count : 1);
  if (!p->geometry || !p->weight || !p->inv_sigma || !p->log_exposures || !p->y || !p->image ||
      !p->flags || !p->gain_group || !p->group_image || !p->light_of_image || !p->log_balance ||
      !problem_lights(p, capture)) {
    fit_problem_release(p);
    return cf_error_set(err, CF_ENOMEM, "out of memory for %zu observations", p->count);
  }
  fit_problem_group_gains(p, 0); /* a gain per image, when free */
  /* the geometry of every (observation, light) pair, and E c_i (in parts
   * on the threads: for DiLiGenT's 1.4 M observations, 0.25 s on one) */
  init_job job = {p, p->threads > 1 && p->count >= INIT_PARALLEL_MIN ? 4 * p->threads : 1};
  cf_parallel_for(job.parts, p->threads, init_part, &job);
  fit_problem_set_sigma(p, capture, 1.0);
  return CF_OK;
}

void fit_pairs_at(int lights, const double n[3], const double v[3], const double *light_dir,
                  const double *irradiance, double scale, cf_geometry *geometry, double *weight) {
  for (int j = 0; j < lights; ++j) {
    const double *l = light_dir + 3 * j, *e = irradiance + 3 * j;
    geometry[j] = cf_geometry_from_directions(n, l, v);
    double cos_i = cf_geometry_is_lit(&geometry[j]) ? geometry[j].cos_i : 0.0;
    for (int c = 0; c < 3; ++c) weight[3 * j + c] = scale * e[c] * cos_i;
  }
}

/* ---- the evaluations' scratch ----
 * fit_problem_evaluate runs on the solver's threads, several blocks at
 * once (never one block twice at once), hundreds of times a solve: its
 * working memory comes from a pool that fit_problem_finish makes, not
 * from malloc. An evaluation takes a free buffer (an atomic flag), grows
 * it if the problem has outgrown it (the pixel footprints add pairs after
 * fit_problem_finish) and gives it back; when every buffer of the pool is
 * taken it makes one of its own. */
enum { SCRATCH_POOL = 16 };

typedef struct fit_scratch {
  atomic_int taken;
  int own;                                       /* not the pool's: freed after use */
  size_t pairs, jacobian_pairs, columns, images; /* what the arrays have room for */
  double *f;                                     /* 3 × pairs: the model's values */
  double *grad;                                  /* 3 × dim × jacobian_pairs: their gradients */
  int *place;        /* columns: each unknown's place among the block's */
  int *gain_column;  /* 3 × columns: where each channel's log gain goes */
  double *gain_sign; /* 3 × columns */
  double *log_e;     /* images */
  int *exposure_u;   /* images: gain group g's unknown, or −1 */
  double *log_b;     /* 3 × images: the white balance */
  int *balance_u;    /* 2 × images: image k's red and blue balance's unknowns, or −1 */
  /* the lights' gains inside the sums (fit_problem.slot_light): */
  double *light_w;   /* 3 × pairs: the pairs' weights times their light's gain (f's allocation) */
  size_t light_room; /* light_d's and light_i's parts have room for this many */
  double *light_d, *log_g, *minus, *slot_gain; /* log g per light; −1s; each slot's g */
  int *light_i, *light_u, *light_place, *last_places, *slot_entry, *entry_light;
  /* each light's unknown (−1: none) and its place in the block; the places
   * of every light's but the last's (its log gain is minus their sum); the
   * image's slots' entries among its lights, and each entry's light */
} fit_scratch;

static void scratch_free_arrays(fit_scratch *s) {
  free(s->f);
  free(s->grad);
  free(s->place);
  free(s->gain_column);
  free(s->gain_sign);
  free(s->log_e);
  free(s->exposure_u);
  free(s->log_b);
  free(s->balance_u);
  free(s->light_d);
  free(s->light_i);
}

/* Room in the scratch's light arrays for the problem's lights. */
static int scratch_lights(fit_scratch *s, const fit_problem *p) {
  size_t room = p->light_count + (size_t)p->lights + 1;
  if (room <= s->light_room) return 1;
  free(s->light_d);
  free(s->light_i);
  s->light_d = malloc(3 * room * sizeof *s->light_d);
  s->light_i = malloc(5 * room * sizeof *s->light_i);
  s->light_room = s->light_d && s->light_i ? room : 0;
  if (!s->light_room) return 0;
  s->log_g = s->light_d, s->minus = s->light_d + room, s->slot_gain = s->light_d + 2 * room;
  s->light_u = s->light_i, s->light_place = s->light_i + room;
  s->last_places = s->light_i + 2 * room, s->slot_entry = s->light_i + 3 * room;
  s->entry_light = s->light_i + 4 * room;
  return 1;
}

/* Room in the scratch for an evaluation of `pairs` pairs, with the
 * Jacobian or not (the arrays' contents are not kept). */
static int scratch_fit(fit_scratch *s, const fit_problem *p, size_t pairs, int jacobian) {
  size_t images = p->images ? p->images : 1, columns = (size_t)p->num_unknowns + 1;
  pairs = pairs ? pairs : 1;
  if (images > s->images) {
    free(s->log_e);
    free(s->exposure_u);
    free(s->log_b);
    free(s->balance_u);
    s->log_e = malloc(images * sizeof *s->log_e);
    s->exposure_u = malloc(images * sizeof *s->exposure_u);
    s->log_b = malloc(3 * images * sizeof *s->log_b);
    s->balance_u = malloc(2 * images * sizeof *s->balance_u);
    s->images = s->log_e && s->exposure_u && s->log_b && s->balance_u ? images : 0;
    if (!s->images) return 0;
  }
  if (pairs > s->pairs) {
    free(s->f);
    s->f = malloc(6 * pairs * sizeof *s->f); /* (then light_w) */
    s->pairs = s->f ? pairs : 0;
    if (!s->f) return 0;
    s->light_w = s->f + 3 * pairs;
  }
  if (!scratch_lights(s, p)) return 0;
  if (!jacobian) return 1;
  if (pairs > s->jacobian_pairs) {
    free(s->grad);
    s->grad = malloc(3 * (size_t)p->dim * pairs * sizeof *s->grad);
    s->jacobian_pairs = s->grad ? pairs : 0;
    if (!s->grad) return 0;
  }
  if (columns > s->columns) {
    free(s->place);
    free(s->gain_column);
    free(s->gain_sign);
    s->place = malloc(columns * sizeof *s->place);
    s->gain_column = malloc(3 * columns * sizeof *s->gain_column);
    s->gain_sign = malloc(3 * columns * sizeof *s->gain_sign);
    s->columns = s->place && s->gain_column && s->gain_sign ? columns : 0;
    if (!s->columns) return 0;
  }
  return 1;
}

/* A free scratch of the pool, or one of its own (NULL: no memory). */
static fit_scratch *scratch_take(const fit_problem *p) {
  for (int i = 0; i < p->scratch_count; ++i) {
    int expected = 0;
    if (atomic_compare_exchange_strong(&p->scratch[i].taken, &expected, 1)) return &p->scratch[i];
  }
  fit_scratch *own = calloc(1, sizeof *own);
  if (own) own->own = 1;
  return own;
}

static void scratch_give(fit_scratch *s) {
  if (!s) return;
  if (!s->own) {
    atomic_store(&s->taken, 0);
    return;
  }
  scratch_free_arrays(s);
  free(s);
}

/* The pool (fit_problem_finish), once per problem. */
static int scratch_pool_make(fit_problem *p) {
  if (p->scratch) return 1;
  p->scratch = calloc(SCRATCH_POOL, sizeof *p->scratch);
  if (!p->scratch) return 0;
  for (int i = 0; i < SCRATCH_POOL; ++i) atomic_init(&p->scratch[i].taken, 0);
  p->scratch_count = SCRATCH_POOL;
  return 1;
}

static void scratch_pool_free(fit_problem *p) {
  for (int i = 0; i < p->scratch_count; ++i) scratch_free_arrays(&p->scratch[i]);
  free(p->scratch);
  p->scratch = NULL;
  p->scratch_count = 0;
}

void fit_problem_release(fit_problem *p) {
  free(p->geometry);
  free(p->weight);
  free(p->inv_sigma);
  free(p->log_exposures);
  free(p->gain_group);
  free(p->log_balance);
  free(p->group_image);
  free(p->light_of_image);
  free(p->slot_light);
  free(p->log_light);
  free(p->block_column_begin);
  free(p->block_column);
  free(p->sample_root);
  free(p->slot_begin);
  free(p->samples);
  free(p->turn_bound);
  free(p->pixel_turn);
  free(p->y);
  free(p->image);
  free(p->flags);
  free(p->unknowns);
  free(p->lower);
  free(p->upper);
  free(p->at_bound);
  scratch_pool_free(p);
  memset(p, 0, sizeof *p);
}

/* Does the capture give a noise model with some noise in it? */
static int capture_noise(const cf_capture *capture, double *read, double *shot) {
  cf_capture_summary summary;
  cf_capture_summarize(capture, &summary);
  *read = summary.noise_read;
  *shot = summary.noise_shot;
  return summary.has_noise && (summary.noise_read > 0.0 || summary.noise_shot > 0.0);
}

int fit_capture_has_noise(const cf_capture *capture) {
  double read, shot;
  return capture_noise(capture, &read, &shot);
}

/* The noise model's variance at a decoded value μ: read² + shot · max(μ, 0);
 * with a response curve the sensor's noise, before the curve, carried
 * through it (docs/model.md §6.2): R'(x)² (read² + shot · x) at
 * x = R⁻¹(μ), R' taken at x >= the last knot (where 8-bit photos end;
 * R' finite and positive there). With the identity curve the same as
 * without one. */
static double noise_variance(const fit_problem *p, double read, double shot, double mu) {
  if (!p->response_on) return read * read + shot * fmax(mu, 0.0);
  double x = mu > 0.0 ? cf_response_model_inverse(p->response, NULL, mu, NULL) : 0.0, slope;
  cf_response_model_value(p->response, fmax(x, cf_response_model_knot(CF_RESPONSE_MODEL_KNOTS - 1)),
                          &slope, NULL);
  return slope * slope * (read * read + shot * x);
}

/* 1/σ of the noise model at the values mu (3 per observation used: the
 * measurements or the predictions; mu may be p->inv_sigma itself),
 * the variance floored at its smallest positive value over them (a dark
 * pixel with no read noise would otherwise weigh infinitely). */
static void noise_inv_sigma(fit_problem *p, double read, double shot, const double *mu) {
  size_t n = 3 * p->count;
  double floor = HUGE_VAL;
  for (size_t i = 0; i < n; ++i) {
    double v = noise_variance(p, read, shot, mu[i]);
    p->inv_sigma[i] = v; /* (after mu[i] is read: in place) */
    if (v > 0.0) floor = fmin(floor, v);
  }
  for (size_t i = 0; i < n; ++i) p->inv_sigma[i] = 1.0 / sqrt(fmax(p->inv_sigma[i], floor));
}

int fit_problem_sigma_through_curve(const fit_problem *p) {
  return p->sigma > 0.0 && p->response_on;
}

double fit_problem_curve_slope(const fit_problem *p, double mu) {
  return sqrt(noise_variance(p, 1.0, 0.0, mu));
}

void fit_problem_set_sigma(fit_problem *p, const cf_capture *capture, double sigma) {
  double read, shot;
  int noise = capture_noise(capture, &read, &shot);
  p->sigma = noise ? 0.0 : sigma;
  int through = fit_problem_sigma_through_curve(p);
  /* one σ for all, or the measurements, turned in place into the noise
   * model's 1/σ (or τ R'(x)'s: a read noise τ alone) */
  for (size_t i = 0; i < 3 * p->count; ++i)
    p->inv_sigma[i] = noise || through ? p->y[i] : 1.0 / sqrt(sigma * sigma);
  if (noise) noise_inv_sigma(p, read, shot, p->inv_sigma);
  if (through) noise_inv_sigma(p, sigma, 0.0, p->inv_sigma);
}

cf_status fit_problem_reweight(fit_problem *p, const cf_capture *capture, cf_error *err) {
  double read, shot;
  if (!capture_noise(capture, &read, &shot)) {
    if (!fit_problem_sigma_through_curve(p)) return CF_OK;
    read = p->sigma; /* τ R'(x): a read noise τ alone */
    shot = 0.0;
  }
  size_t n = 3 * p->count;
  double *prediction = malloc(n * sizeof *prediction), *measured = malloc(n * sizeof *measured);
  cf_status s = prediction && measured ? fit_problem_predict(p, prediction, measured, err)
                                       : cf_error_set(err, CF_ENOMEM, "out of memory");
  if (s == CF_OK) noise_inv_sigma(p, read, shot, prediction);
  free(prediction);
  free(measured);
  return s;
}

/* ---- unknowns ---- */

void fit_problem_clear_unknowns(fit_problem *p) {
  p->num_unknowns = 0;
  p->unknowns_failed = 0;
  p->response_on = !fit_response_is_identity(p->response);
  p->light_gains_on = 0;
  for (size_t l = 0; l < p->light_count; ++l) p->light_gains_on |= p->log_light[l] != 0.0;
}

/* Room for `capacity` unknowns in the unknowns' arrays (kept as they are). */
static int grow_unknowns(fit_problem *p, int capacity) {
  size_t n = (size_t)capacity;
  fit_unknown *unknowns = realloc(p->unknowns, n * sizeof *unknowns);
  if (unknowns) p->unknowns = unknowns;
  double *lower = realloc(p->lower, n * sizeof *lower);
  if (lower) p->lower = lower;
  double *upper = realloc(p->upper, n * sizeof *upper);
  if (upper) p->upper = upper;
  int *at_bound = realloc(p->at_bound, n * sizeof *at_bound);
  if (at_bound) p->at_bound = at_bound;
  if (!unknowns || !lower || !upper || !at_bound) return 0;
  p->unknown_capacity = capacity;
  return 1;
}

static void add_unknown(fit_problem *p, fit_unknown_kind kind, int slot, double lo, double hi) {
  if (p->unknowns_failed) return;
  if (p->num_unknowns == p->unknown_capacity &&
      (p->num_unknowns > INT_MAX / 2 - 16 || !grow_unknowns(p, 2 * p->num_unknowns + 16))) {
    p->unknowns_failed = 1; /* fit_problem_finish reports it */
    return;
  }
  int i = p->num_unknowns++;
  p->unknowns[i] = (fit_unknown){kind, slot};
  p->lower[i] = lo;
  p->upper[i] = hi;
  p->at_bound[i] = 0;
}

void fit_problem_free_slot(fit_problem *p, int slot) {
  const cf_param_info *info = cf_model_slot_param(p->model, slot, NULL);
  if (!info) return;
  if (info->id == CF_PARAM_ALBEDO)
    add_unknown(p, FIT_LOG_SLOT, slot, log(fmax(info->lower, FIT_ALBEDO_FLOOR)), log(info->upper));
  else if (info->id == CF_PARAM_DIFFUSE_ROUGHNESS)
    add_unknown(p, FIT_SQUARE_SLOT, slot, info->lower * info->lower, info->upper * info->upper);
  else
    add_unknown(p, FIT_MODEL_SLOT, slot, info->lower, info->upper);
}

void fit_problem_free_scale(fit_problem *p) {
  add_unknown(p, FIT_LOG_SCALE, 0, -HUGE_VAL, HUGE_VAL);
}

void fit_problem_free_response(fit_problem *p) {
  for (int j = 0; j < CF_RESPONSE_MODEL_KNOTS; ++j)
    add_unknown(p, FIT_RESPONSE, j, CF_RESPONSE_MODEL_SLOPE_LOWER, CF_RESPONSE_MODEL_SLOPE_UPPER);
  p->response_on = 1;
}

void fit_problem_copy_values(fit_problem *to, const fit_problem *from) {
  memcpy(to->params, from->params, sizeof to->params);
  to->log_scale = from->log_scale;
  memcpy(to->response, from->response, sizeof to->response);
  memcpy(to->log_exposures, from->log_exposures, from->images * sizeof *to->log_exposures);
  memcpy(to->log_balance, from->log_balance, 3 * from->images * sizeof *to->log_balance);
  memcpy(to->log_light, from->log_light, from->light_count * sizeof *to->log_light);
}

void fit_response_identity(double *slopes) {
  for (int j = 0; j < CF_RESPONSE_MODEL_KNOTS; ++j) slopes[j] = 1.0;
}

int fit_response_is_identity(const double *slopes) {
  for (int j = 0; j < CF_RESPONSE_MODEL_KNOTS; ++j)
    if (slopes[j] != 1.0) return 0;
  return 1;
}

void fit_problem_group_gains(fit_problem *p, int per_light) {
  p->gain_groups = 0;
  for (size_t k = 0; k < p->images; ++k) {
    long light = per_light ? p->light_of_image[k] : -1;
    size_t g = p->gain_groups;
    if (light >= 0 && (size_t)light < k) g = p->gain_group[light]; /* (light: its first image) */
    if (g == p->gain_groups) p->group_image[p->gain_groups++] = (uint32_t)k;
    p->gain_group[k] = (uint32_t)g;
  }
}

void fit_problem_free_exposures(fit_problem *p) {
  for (size_t g = 0; g + 1 < p->gain_groups; ++g) /* (contiguous, in the groups' order) */
    add_unknown(p, FIT_LOG_EXPOSURE, (int)g, -HUGE_VAL, HUGE_VAL);
}

void fit_problem_free_light_gains(fit_problem *p) {
  for (size_t l = 0; l + 1 < p->light_count; ++l) /* (contiguous, in the lights' order) */
    add_unknown(p, FIT_LOG_LIGHT, (int)l, -HUGE_VAL, HUGE_VAL);
  p->light_gains_on = p->light_count > 1;
}

void fit_problem_free_balance(fit_problem *p) {
  for (size_t k = 0; k + 1 < p->images; ++k)
    for (int j = 0; j < 2; ++j)
      add_unknown(p, FIT_LOG_BALANCE, (int)(2 * k) + j, -HUGE_VAL, HUGE_VAL);
}

/* The blocks and their columns: the model's, the scale's, the
 * response's and the lights' gains in every block (a capture has few
 * lights); a gain's where its group's images are (every
 * gain where the last group's are), a white balance's where its image is
 * (every one where the last image is). */
cf_status fit_problem_finish(fit_problem *p, cf_error *err) {
  if (p->unknowns_failed)
    return cf_error_set(err, CF_ENOMEM, "out of memory for the fit's unknowns (%d and more)",
                        p->num_unknowns);
  p->num_blocks = (p->count + p->block_size - 1) / p->block_size;
  free(p->block_column_begin);
  free(p->block_column);
  p->block_column = NULL;
  p->block_column_begin = malloc((p->num_blocks + 1) * sizeof *p->block_column_begin);
  unsigned char *seen = calloc(p->images ? p->images : 1, 1);
  size_t capacity = 0;
  int failed = !p->block_column_begin || !seen;
  if (!failed) p->block_column_begin[0] = 0;
  for (size_t b = 0; !failed && b < p->num_blocks; ++b) {
    size_t begin = b * p->block_size;
    size_t end = p->count - begin < p->block_size ? p->count : begin + p->block_size;
    for (size_t i = begin; i < end; ++i) /* (bit 0: a group's images, 1: an image) */
      seen[p->gain_group[p->image[i]]] |= 1, seen[p->image[i]] |= 2;
    int has_last = p->gain_groups > 0 && (seen[p->gain_groups - 1] & 1);
    int has_last_image = p->images > 0 && (seen[p->images - 1] & 2);
    size_t k = p->block_column_begin[b];
    if (k + (size_t)p->num_unknowns + 1 > capacity) { /* room for this block's */
      capacity = 2 * (k + (size_t)p->num_unknowns + 1);
      int *grown = realloc(p->block_column, capacity * sizeof *grown);
      if (!grown) {
        failed = 1;
        break;
      }
      p->block_column = grown;
    }
    for (int u = 0; u < p->num_unknowns; ++u) {
      const fit_unknown *unk = &p->unknowns[u];
      int in_block = unk->kind == FIT_LOG_EXPOSURE   ? has_last || (seen[unk->slot] & 1)
                     : unk->kind == FIT_LOG_BALANCE ? has_last_image || (seen[unk->slot / 2] & 2)
                                                    : 1;
      if (in_block) p->block_column[k++] = u;
    }
    p->block_column_begin[b + 1] = k;
    for (size_t i = begin; i < end; ++i) seen[p->gain_group[p->image[i]]] = seen[p->image[i]] = 0;
  }
  free(seen);
  if (failed || !scratch_pool_make(p))
    return cf_error_set(err, CF_ENOMEM, "out of memory for the residual blocks");
  return CF_OK;
}

void fit_problem_get_x(const fit_problem *p, double *x) {
  for (int i = 0; i < p->num_unknowns; ++i) {
    const fit_unknown *u = &p->unknowns[i];
    x[i] = u->kind == FIT_MODEL_SLOT    ? p->params[u->slot]
           : u->kind == FIT_LOG_SLOT    ? log(p->params[u->slot])
           : u->kind == FIT_SQUARE_SLOT ? p->params[u->slot] * p->params[u->slot]
           : u->kind == FIT_LOG_SCALE   ? p->log_scale
           : u->kind == FIT_RESPONSE    ? p->response[u->slot]
           : u->kind == FIT_LOG_BALANCE ? p->log_balance[3 * (u->slot / 2) + 2 * (u->slot % 2)]
           : u->kind == FIT_LOG_LIGHT   ? p->log_light[u->slot]
                                        : p->log_exposures[p->group_image[u->slot]];
  }
}

/* The white balance x stands for (its unknowns from x[first]: image k's
 * red and blue at 2k, 2k + 1; the last image's minus the others' sum). */
static void balance_at(const fit_problem *p, const double *x, int first, double *log_balance) {
  double sum[2] = {0.0, 0.0};
  for (size_t k = 0; k + 1 < p->images; ++k)
    for (int j = 0; j < 2; ++j)
      sum[j] += log_balance[3 * k + 2 * (size_t)j] = x[first + 2 * (int)k + j];
  log_balance[3 * (p->images - 1)] = -sum[0];
  log_balance[3 * (p->images - 1) + 2] = -sum[1];
}

/* The lights' log gains x stands for (from x[first]; the last light's
 * minus the others' sum), into log_light (light_count). */
static void light_gains_at(const fit_problem *p, const double *x, int first, double *log_light) {
  double sum = 0.0;
  for (size_t l = 0; l + 1 < p->light_count; ++l) sum += log_light[l] = x[first + (int)l];
  log_light[p->light_count - 1] = -sum;
}

/* The values x stands for: params, log s, the response's slopes, log e_k
 * of every image (its gain group's; the last group's from the others),
 * the white balance (3 × images; NULL: not wanted) and the lights' log
 * gains (light_count; NULL: not wanted). */
static void values_at(const fit_problem *p, const double *x, double *params, double *log_scale,
                      double *response, double *log_exposures, double *log_balance,
                      double *log_light) {
  memcpy(params, p->params, sizeof p->params);
  *log_scale = p->log_scale;
  memcpy(response, p->response, sizeof p->response);
  if (log_exposures) memcpy(log_exposures, p->log_exposures, p->images * sizeof *log_exposures);
  if (log_balance) memcpy(log_balance, p->log_balance, 3 * p->images * sizeof *log_balance);
  if (log_light) memcpy(log_light, p->log_light, p->light_count * sizeof *log_light);
  int first_gain = -1, first_balance = -1, first_light = -1;
  for (int i = 0; i < p->num_unknowns; ++i) {
    const fit_unknown *u = &p->unknowns[i];
    if (u->kind == FIT_MODEL_SLOT)
      params[u->slot] = x[i];
    else if (u->kind == FIT_LOG_SLOT)
      params[u->slot] = exp(x[i]);
    else if (u->kind == FIT_SQUARE_SLOT)
      params[u->slot] = sqrt(fmax(x[i], 0.0));
    else if (u->kind == FIT_LOG_SCALE)
      *log_scale = x[i];
    else if (u->kind == FIT_RESPONSE)
      response[u->slot] = x[i];
    else if (u->kind == FIT_LOG_BALANCE && first_balance < 0)
      first_balance = i; /* contiguous, image k's red and blue at 2k, 2k + 1 */
    else if (u->kind == FIT_LOG_EXPOSURE && first_gain < 0)
      first_gain = i; /* the gains' unknowns: contiguous, group g at first_gain + g */
    else if (u->kind == FIT_LOG_LIGHT && first_light < 0)
      first_light = i; /* contiguous, light l at first_light + l */
  }
  if (first_light >= 0 && log_light) light_gains_at(p, x, first_light, log_light);
  if (first_balance >= 0 && log_balance) balance_at(p, x, first_balance, log_balance);
  if (first_gain >= 0 && log_exposures) {
    double sum = 0.0;
    for (size_t g = 0; g + 1 < p->gain_groups; ++g) sum += x[first_gain + (int)g];
    for (size_t k = 0; k < p->images; ++k)
      log_exposures[k] = p->gain_group[k] + 1 == p->gain_groups
                             ? -sum
                             : x[first_gain + (int)p->gain_group[k]];
  }
}

void fit_problem_set_x(fit_problem *p, const double *x) {
  double params[CF_MAX_DIM], log_scale, response[CF_RESPONSE_MODEL_KNOTS];
  values_at(p, x, params, &log_scale, response, p->log_exposures, p->log_balance, p->log_light);
  memcpy(p->params, params, sizeof params);
  p->log_scale = log_scale;
  memcpy(p->response, response, sizeof response);
}

/* ---- the loss, per scalar residual ----
 * ρ(s) of s = r² in units of σ (Huber, Cauchy, or s itself), and ρ'(s).
 * The solver's model of a residual is the reweighted one, √ρ' r with the
 * Jacobian √ρ' ∂r (iteratively reweighted least squares: its gradient is
 * that of ½ ρ, its Gauss-Newton matrix Σ ρ' JᵀJ), while the cost is ½ ρ
 * itself (lsq.h). Ceres' LossFunction would do the same per residual
 * block, but a block here holds a thousand observations. */
static double robust(const fit_problem *p, double s, double *rho1) {
  double k2 = p->loss_scale * p->loss_scale;
  switch (p->loss) {
    case CF_LOSS_HUBER:
      if (s <= k2) break;
      *rho1 = p->loss_scale / sqrt(s);
      return 2.0 * p->loss_scale * sqrt(s) - k2;
    case CF_LOSS_CAUCHY:
      *rho1 = 1.0 / (1.0 + s / k2);
      return k2 * log1p(s / k2);
    case CF_LOSS_NONE:
    default:
      break;
  }
  *rho1 = 1.0;
  return s;
}

double fit_problem_loss_weight(const fit_problem *p, double s) {
  double rho1 = 1.0;
  robust(p, s, &rho1);
  return rho1;
}

double fit_problem_censored_residual(double z, double *slope) {
  /* beyond 30, 1 − Φ(z) is below 1e-197 (t² would underflow) */
  if (!(z < 30.0)) {
    *slope = 0.0;
    return 0.0;
  }
  if (z < -37.0) { /* erfc underflows: Φ(z) = φ(z)/(−z) (1 − 1/z² + 3/z⁴ − …) */
    double w = 1.0 / (z * z), series = 1.0 - w + 3.0 * w * w;
    double t = -sqrt(z * z + 2.0 * log(-z) + 1.8378770664093453 - 2.0 * log(series));
    double dseries = (2.0 * w - 12.0 * w * w) / z; /* d series / dz */
    *slope = (z + 1.0 / z - dseries / series) / t;
    return t;
  }
  double tail = 0.5 * erfc(z / sqrt(2.0)); /* 1 − Φ(z) */
  double phi_cdf = 0.5 * erfc(-z / sqrt(2.0));
  double cost = -2.0 * (z > 0.0 ? log1p(-tail) : log(phi_cdf));
  if (!(cost > 0.0)) {
    *slope = 0.0;
    return 0.0;
  }
  double t = sqrt(cost), density = 0.3989422804014327 * exp(-0.5 * z * z); /* φ(z) */
  *slope = density / (phi_cdf * t);
  return -t;
}

/* ---- residuals ---- */

/* The channel a model slot moves: c for component c of an RGB parameter,
 * −1 (all three) for a scalar one. */
static int slot_channel(cf_model_id model, int slot) {
  int component;
  const cf_param_info *info = cf_model_slot_param(model, slot, &component);
  return info && info->components == 3 ? component : -1;
}

/* The normal equations of one channel's rows of one image, in a small
 * dense layout: the model unknowns that move the channel, then the log
 * gain (the scale's and the image's exposure's derivative, which are the
 * same), then the response. Rows add here without indirection; the sums go
 * to the block's columns when the image changes (fit_problem_evaluate). */
enum { LOCAL_MAX = CF_MAX_DIM + 1 + CF_RESPONSE_MODEL_KNOTS + FIT_IMAGE_LIGHTS };
typedef struct local_normal {
  int size;
  double a[LOCAL_MAX][LOCAL_MAX]; /* lower triangle */
  double b[LOCAL_MAX];
} local_normal;

static inline void local_add_sized(local_normal *n, const double *v, double u, int size) {
  for (int i = 0; i < size; ++i) {
    double vi = v[i];
    n->b[i] += vi * u;
    for (int j = 0; j <= i; ++j) n->a[i][j] += vi * v[j];
  }
}

/* One row into the sums; the common sizes with their size a constant, so
 * that the compiler unrolls the loops (a fifth of the evaluation was this
 * triangle, with its bound unknown). */
static void local_add(local_normal *n, const double *v, double u) {
  switch (n->size) {
    case 2:
      local_add_sized(n, v, u, 2);
      break;
    case 3:
      local_add_sized(n, v, u, 3);
      break;
    case 4:
      local_add_sized(n, v, u, 4);
      break;
    case 5:
      local_add_sized(n, v, u, 5);
      break;
    case 6:
      local_add_sized(n, v, u, 6);
      break;
    case 7:
      local_add_sized(n, v, u, 7);
      break;
    case 8:
      local_add_sized(n, v, u, 8);
      break;
    case 9:
      local_add_sized(n, v, u, 9);
      break;
    default:
      local_add_sized(n, v, u, n->size);
      break;
  }
}

/* Where the local indices go: one column each, but the log gain's, which
 * goes to the scale's and the image's exposure's columns (or, for the last
 * image, to minus every exposure's), and the image's lights' (the last
 * light's to minus every other light's). */
typedef struct local_map {
  int column[LOCAL_MAX];
  int gain; /* the log gain's local index, or −1 */
  const int *gain_column;
  const double *gain_sign;
  int gain_count;
  /* the image's lights' gains: local indices light_first … + light_entries */
  int light_first, light_entries, last_count;
  const fit_scratch *s;
  size_t last_light;
} local_map;

static int local_targets(const local_map *map, int i, const int **column, const double **sign) {
  static const double one = 1.0;
  if (i >= map->light_first && i < map->light_first + map->light_entries) {
    int l = map->s->entry_light[i - map->light_first];
    *column = (size_t)l == map->last_light ? map->s->last_places : &map->s->light_place[l];
    *sign = (size_t)l == map->last_light ? map->s->minus : &one;
    return (size_t)l == map->last_light ? map->last_count : 1;
  }
  if (i == map->gain) {
    *column = map->gain_column;
    *sign = map->gain_sign;
    return map->gain_count;
  }
  *column = &map->column[i];
  *sign = &one;
  return 1;
}

/* The local sums into the block's k × k jtj (both triangles) and jtu, then
 * zeroed. */
static void local_flush(local_normal *n, const local_map *map, int k, double *jtj, double *jtu) {
  for (int i = 0; i < n->size; ++i) {
    const int *ci, *cj;
    const double *si, *sj;
    int count_i = local_targets(map, i, &ci, &si);
    for (int x = 0; x < count_i; ++x) jtu[ci[x]] += si[x] * n->b[i];
    for (int j = 0; j <= i; ++j) {
      double value = n->a[i][j];
      if (value == 0.0) continue;
      int count_j = local_targets(map, j, &cj, &sj);
      for (int x = 0; x < count_i; ++x)
        for (int y = 0; y < count_j; ++y) {
          double v = si[x] * sj[y] * value;
          jtj[(size_t)ci[x] * (size_t)k + (size_t)cj[y]] += v;
          if (i != j) jtj[(size_t)cj[y] * (size_t)k + (size_t)ci[x]] += v;
        }
    }
  }
  int size = n->size;
  memset(n, 0, sizeof *n);
  n->size = size;
}

/* ---- the prediction (fit_problem_evaluate and fit_problem_predict) ---- */

/* The gain s e_k of image k's observations. */
static double image_gain(double log_scale, double log_exposure) {
  return exp(log_scale + log_exposure);
}

/* The model's value Σ_m w_m Σ_j E f c_i (docs/model.md (40)) of channel c
 * of an observation over its `slots` pairs, from `first` in f (3 per pair;
 * w: the pairs' weights, 3 per pair), and with grad (3 × dim per pair;
 * NULL: none) its gradient in the model's slots: *dmodel, times
 * *weight_one. With one slot that is the evaluator's gradient itself,
 * scaled later (no accumulator to zero: a zeroed array here cost a fifth
 * of the evaluation in stores); else the weighted sum, in sum (dim). */
static double model_value(const double *w, const double *f, const double *grad, int dim,
                          size_t first, size_t slots, int c, double *sum, const double **dmodel,
                          double *weight_one) {
  *dmodel = sum;
  if (slots == 1) {
    *weight_one = w[c];
    if (grad) *dmodel = grad + (3 * first + (size_t)c) * (size_t)dim;
    return *weight_one * f[3 * first + (size_t)c];
  }
  *weight_one = 1.0;
  double value = 0.0;
  if (grad)
    for (int s = 0; s < dim; ++s) sum[s] = 0.0;
  for (size_t j = 0; j < slots; ++j) {
    size_t pair = first + j;
    double wj = w[3 * j + (size_t)c];
    if (wj == 0.0) continue;
    value += wj * f[3 * pair + (size_t)c];
    if (!grad) continue;
    const double *g = grad + (3 * pair + (size_t)c) * (size_t)dim;
    for (int s = 0; s < dim; ++s) sum[s] += wj * g[s];
  }
  return value;
}

/* Image `image`'s slots' gains g_l (slot_gain, lights; 1 for a slot
 * without light) from the lights' log gains. */
static void image_slot_gains(const fit_problem *p, const double *log_g, uint32_t image,
                             double *slot_gain) {
  const long *id = p->slot_light + (size_t)image * (size_t)p->lights;
  for (int j = 0; j < p->lights; ++j) slot_gain[j] = id[j] < 0 ? 1.0 : exp(log_g[id[j]]);
}

/* An observation's pair weights (w, 3 per pair) times their lights' gains,
 * into out; pair j is light slot j mod lights (fit_problem.slot_begin). */
static const double *light_weighted(const fit_problem *p, const double *slot_gain, const double *w,
                                    size_t slots, double *out) {
  for (size_t j = 0; j < slots; ++j) {
    double g = slot_gain[j % (size_t)p->lights];
    for (int c = 0; c < 3; ++c) out[3 * j + (size_t)c] = g * w[3 * j + (size_t)c];
  }
  return out;
}

/* Image `image`'s lights as local entries: slot_entry[j] (lights; −1: no
 * light) and entry_light[q]; returns their count (at most FIT_IMAGE_LIGHTS,
 * which the check before the fit enforces). */
static int image_entries(const fit_problem *p, uint32_t image, int *slot_entry, int *entry_light) {
  const long *id = p->slot_light + (size_t)image * (size_t)p->lights;
  int count = 0;
  for (int j = 0; j < p->lights; ++j) {
    slot_entry[j] = -1;
    for (int q = 0; q < count && id[j] >= 0 && slot_entry[j] < 0; ++q)
      if (entry_light[q] == id[j]) slot_entry[j] = q;
    if (id[j] >= 0 && slot_entry[j] < 0 && count < FIT_IMAGE_LIGHTS)
      entry_light[count] = (int)id[j], slot_entry[j] = count++;
  }
  return count;
}

/* The prediction μ of a channel from its linear value, gain · model
 * (docs/model.md (40)): the linear value itself, or with a response
 * curve, R(linear) (0 where the linear value is not positive: no light,
 * no prediction). With chain non-NULL, also ∂μ/∂linear (1 without a
 * response) and, with a response, in dslope ∂μ/∂a_j (CF_RESPONSE_MODEL_KNOTS;
 * untouched without one: no slope is free then). */
static double predict_channel(int response_on, const double *response, double linear, double *chain,
                              double *dslope) {
  if (chain) *chain = 1.0;
  if (!response_on) return linear;
  return cf_response_model_value(response, linear, chain, dslope);
}

/* ---- one block's cost and normal equations (fit_problem_evaluate) ---- */

/* An evaluation of a block at x: what holds over its rows. */
typedef struct block_eval {
  const fit_problem *p;
  fit_scratch *s;
  size_t first_pair; /* the block's first pair, where f and grad start */
  double *f, *grad;  /* the model's values and gradients (grad NULL: cost alone) */
  double params[CF_MAX_DIM], log_scale, response[CF_RESPONSE_MODEL_KNOTS];
  /* per channel, the model unknowns that move it, their slots and
   * d param / d x (1, ρ for log ρ, 1/(2σ) for σ²) */
  int channel_u[3][CF_MAX_DIM], channel_slot[3][CF_MAX_DIM], channel_count[3];
  double channel_factor[3][CF_MAX_DIM];
  /* the scale's and the response's slopes' unknowns, or −1 */
  int scale_u, response_u[CF_RESPONSE_MODEL_KNOTS];
  int response_free;       /* any slope free */
  int exposures;           /* any exposure free (s->exposure_u: whose) */
  int balance;             /* any white balance free (s->balance_u: whose) */
  int light_on;            /* the lights' gains apply (fit_problem.light_gains_on) */
  int light_free;          /* any light's gain free (s->light_u: whose) */
} block_eval;

/* The normal equations of a block over its k columns, and each channel's
 * local sums (local_normal). Apart from block_eval: stores into the sums
 * then cannot touch what the rows read. */
typedef struct block_normal {
  double *jtj, *jtu;
  int k;
  local_normal local[3];
  local_map map[3];
  /* fit_problem_group_scores: each row's −Jᵀu into its group's score
   * (score[group[row] × unknowns + u]) instead of the sums (NULL: the sums) */
  double *score;
  const size_t *group;
  const int *columns; /* the block's columns' unknowns */
} block_normal;

/* The values x stands for (values_at; σ² unknowns evaluated at σ >= 1e-6,
 * so that ∂f/∂σ² = (∂f/∂σ)/(2σ) has no 0/0: f depends on σ through σ²
 * only, and differs from its value at σ = 0 by about 1e-13 relative
 * there), and the unknowns' roles: the scale's, the response's, each
 * image's exposure's, and per channel the model's. */
static void unknowns_at(block_eval *e, const double *x) {
  const fit_problem *p = e->p;
  values_at(p, x, e->params, &e->log_scale, e->response, e->s->log_e, e->s->log_b, e->s->log_g);
  e->scale_u = -1;
  e->response_free = 0;
  for (int j = 0; j < CF_RESPONSE_MODEL_KNOTS; ++j) e->response_u[j] = -1;
  e->exposures = e->balance = 0;
  for (size_t i = 0; i < p->images; ++i) e->s->exposure_u[i] = -1;
  for (size_t i = 0; i < 2 * p->images; ++i) e->s->balance_u[i] = -1;
  for (size_t l = 0; l < p->light_count; ++l) e->s->light_u[l] = -1;
  e->light_on = p->light_gains_on, e->light_free = 0;
  for (int u = 0; u < p->num_unknowns; ++u) {
    const fit_unknown *unk = &p->unknowns[u];
    if (unk->kind == FIT_SQUARE_SLOT) e->params[unk->slot] = fmax(e->params[unk->slot], 1e-6);
    if (unk->kind == FIT_LOG_SCALE)
      e->scale_u = u;
    else if (unk->kind == FIT_RESPONSE)
      e->response_u[unk->slot] = u, e->response_free = 1;
    else if (unk->kind == FIT_LOG_EXPOSURE)
      e->s->exposure_u[unk->slot] = u, e->exposures = 1;
    else if (unk->kind == FIT_LOG_BALANCE)
      e->s->balance_u[unk->slot] = u, e->balance = 1;
    else if (unk->kind == FIT_LOG_LIGHT)
      e->s->light_u[unk->slot] = u, e->light_free = 1;
  }
  for (int c = 0; c < 3; ++c) e->channel_count[c] = 0;
  for (int u = 0; u < p->num_unknowns; ++u) {
    const fit_unknown *unk = &p->unknowns[u];
    if (!fit_unknown_is_model(unk->kind)) continue;
    double factor = unk->kind == FIT_LOG_SLOT      ? e->params[unk->slot]
                    : unk->kind == FIT_SQUARE_SLOT ? 0.5 / e->params[unk->slot]
                                                   : 1.0;
    int moves = slot_channel(p->model, unk->slot);
    for (int c = 0; c < 3; ++c) {
      if (moves >= 0 && moves != c) continue;
      int q = e->channel_count[c]++;
      e->channel_u[c][q] = u;
      e->channel_slot[c][q] = unk->slot;
      e->channel_factor[c][q] = factor;
    }
  }
}

/* The block's columns (each unknown's place among them), jtj and jtu
 * zeroed, and each channel's local layout: its model unknowns, the log
 * gain, the response. */
static void normal_layout(const block_eval *e, size_t block, block_normal *n) {
  const fit_problem *p = e->p;
  int *place = e->s->place;
  const int *columns = p->block_column + p->block_column_begin[block];
  n->k = (int)(p->block_column_begin[block + 1] - p->block_column_begin[block]);
  for (int u = 0; u < p->num_unknowns; ++u) place[u] = -1;
  for (int c = 0; c < n->k; ++c) place[columns[c]] = c;
  memset(n->jtj, 0, (size_t)n->k * (size_t)n->k * sizeof *n->jtj);
  memset(n->jtu, 0, (size_t)n->k * sizeof *n->jtu);
  for (int c = 0; c < 3; ++c) {
    memset(&n->local[c], 0, sizeof n->local[c]);
    local_map *lm = &n->map[c];
    int size = e->channel_count[c];
    for (int q = 0; q < size; ++q) lm->column[q] = place[e->channel_u[c][q]];
    lm->gain = e->scale_u >= 0 || e->exposures || e->balance ? size++ : -1;
    for (int j = 0; j < CF_RESPONSE_MODEL_KNOTS; ++j)
      if (e->response_u[j] >= 0) lm->column[size++] = place[e->response_u[j]];
    size_t stride = (size_t)p->num_unknowns + 1; /* (scratch_fit's columns) */
    lm->gain_column = e->s->gain_column + (size_t)c * stride;
    lm->gain_sign = e->s->gain_sign + (size_t)c * stride;
    lm->gain_count = 0;
    n->local[c].size = lm->light_first = size; /* (the image's lights after: next_image) */
    lm->light_entries = 0;
    lm->s = e->s;
    lm->last_light = p->light_count - 1;
    lm->last_count = p->light_count > 0 ? (int)p->light_count - 1 : 0;
  }
  for (size_t l = 0; e->light_free && l < p->light_count; ++l) {
    int u = e->s->light_u[l];
    e->s->light_place[l] = u >= 0 ? place[u] : -1;
    if (l + 1 < p->light_count) e->s->last_places[l] = e->s->light_place[l], e->s->minus[l] = -1.0;
  }
}

/* Red's (c 0) and blue's (c 2) white balance of `image` among channel
 * c's log gain columns after `count` (for the last image, minus every
 * other image's); returns the new count. */
static int balance_columns(const block_eval *e, uint32_t image, int c, int *column, double *sign,
                           int count) {
  const fit_problem *p = e->p;
  const int *place = e->s->place, *balance_u = e->s->balance_u;
  if (!e->balance || c == 1) return count;
  int j = c / 2;
  if (image + 1 == p->images) {
    for (size_t k = 0; k + 1 < p->images; ++k)
      if (balance_u[2 * k + (size_t)j] >= 0)
        column[count] = place[balance_u[2 * k + (size_t)j]], sign[count++] = -1.0;
  } else if (balance_u[2 * image + (uint32_t)j] >= 0) {
    column[count] = place[balance_u[2 * image + (uint32_t)j]], sign[count++] = 1.0;
  }
  return count;
}

/* The rows of a new image begin: the last image's sums into jtj and jtu
 * (unless there was none), and where this image's log gain goes: the
 * scale's column and its gain group's (for the last group, minus every
 * other group's: log e_last = −Σ of the others, docs/model.md (41)), and
 * in red and blue its white balance's. */
static void next_image(const block_eval *e, block_normal *n, int had_image, uint32_t image) {
  const fit_problem *p = e->p;
  uint32_t group = p->gain_group[image];
  const int *place = e->s->place, *exposure_u = e->s->exposure_u;
  size_t stride = (size_t)p->num_unknowns + 1; /* each channel's (normal_layout) */
  int *gain_column = e->s->gain_column, count = 0;
  double *gain_sign = e->s->gain_sign;
  for (int c = 0; c < 3 && had_image; ++c)
    local_flush(&n->local[c], &n->map[c], n->k, n->jtj, n->jtu);
  if (e->scale_u >= 0) gain_column[count] = place[e->scale_u], gain_sign[count++] = 1.0;
  if (e->exposures && group + 1 == p->gain_groups) {
    for (size_t g = 0; g + 1 < p->gain_groups; ++g)
      if (exposure_u[g] >= 0) gain_column[count] = place[exposure_u[g]], gain_sign[count++] = -1.0;
  } else if (e->exposures && exposure_u[group] >= 0) {
    gain_column[count] = place[exposure_u[group]], gain_sign[count++] = 1.0;
  }
  for (int c = 0; c < 3; ++c) { /* the same in every channel, but the balance */
    int *column = gain_column + (size_t)c * stride;
    double *sign = gain_sign + (size_t)c * stride;
    if (c > 0) {
      memcpy(column, gain_column, (size_t)count * sizeof *column);
      memcpy(sign, gain_sign, (size_t)count * sizeof *sign);
    }
    n->map[c].gain_count = balance_columns(e, image, c, column, sign, count);
  }
  int entries = e->light_free ? image_entries(p, image, e->s->slot_entry, e->s->entry_light) : 0;
  for (int c = 0; c < 3; ++c)
    n->map[c].light_entries = entries, n->local[c].size = n->map[c].light_first + entries;
}

/* Channel c's derivatives in the image's lights' log gains into v: ∂μ/∂
 * log g_l = factor · Σ over light l's pairs of w f (factor: R' s e_k b_kc
 * times the row's scale; w with the gains: light_weighted). Returns
 * their count. */
static int light_rows(const block_eval *e, const local_map *map, int c, size_t first, size_t slots,
                      const double *w, double factor, double *v) {
  double share[FIT_IMAGE_LIGHTS] = {0.0};
  for (size_t j = 0; j < slots; ++j) {
    int q = e->s->slot_entry[j % (size_t)e->p->lights];
    if (q >= 0) share[q] += w[3 * j + (size_t)c] * e->f[3 * (first + j) + (size_t)c];
  }
  for (int q = 0; q < map->light_entries; ++q) v[q] = factor * share[q];
  return map->light_entries;
}

/* Row `row`'s channel c with its row v of J and residual u (channel_row)
 * into its group's score: −v u, each local index to its columns. */
static void score_add(const fit_problem *p, block_normal *n, size_t row, int c, const double *v,
                      double u) {
  double *score = n->score + n->group[row] * (size_t)p->num_unknowns;
  for (int i = 0; i < n->local[c].size; ++i) {
    const int *column;
    const double *sign;
    int count = local_targets(&n->map[c], i, &column, &sign);
    for (int t = 0; t < count; ++t) score[n->columns[column[t]]] -= sign[t] * v[i] * u;
  }
}

/* Channel c of row `row` (its `slots` pairs from `first` in f and grad,
 * weighed by w; its image's gain): its share w ρ >= 0 of the cost
 * (returned; not finite with ρ), and with the normal equations (n) its row of J,
 * u = √w √ρ' r and its derivatives, into the channel's local sums. */
static double channel_row(const block_eval *e, block_normal *n, size_t row, int c, size_t first,
                          size_t slots, const double *w, double gain) {
  const fit_problem *p = e->p;
  double sum[CF_MAX_DIM], weight_one;
  const double *dmodel;
  double model = model_value(w, e->f, e->grad, p->dim, first, slots, c, sum, &dmodel, &weight_one);
  double linear = gain * model, chain = 1.0, dslope[CF_RESPONSE_MODEL_KNOTS];
  double prediction =
      predict_channel(p->response_on, e->response, linear, n ? &chain : NULL, dslope);
  double y = p->y[3 * row + (size_t)c], inv_sigma = p->inv_sigma[3 * row + (size_t)c];
  double r = (prediction - y) * inv_sigma;
  /* a clipped channel says only that the true value is at least y, its
   * clip level: the censored likelihood's residual and slope (53) */
  int clipped = p->flags[row] >> c & 1u;
  double slope = 1.0;
  if (clipped) r = fit_problem_censored_residual(r, &slope);
  int censored = clipped && slope == 0.0;
  double rho1, root = p->sample_root ? p->sample_root[row] : 1.0;
  double rho = robust(p, r * r, &rho1), share = root * root * rho;
  if (!n || censored) return share; /* a censored residual's row is 0 */
  /* (ρ' = 1 without a loss and inside Huber's core: no square root, a
   * tenth of an M2 pass) */
  double scale = root * (rho1 == 1.0 ? 1.0 : sqrt(rho1)) * inv_sigma;
  double u = clipped ? scale / inv_sigma * r : scale * (prediction - y);
  scale *= slope;
  double model_scale = scale * chain * gain * weight_one, v[LOCAL_MAX];
  int m = 0;
  for (int q = 0; q < e->channel_count[c]; ++q)
    v[m++] = model_scale * dmodel[e->channel_slot[c][q]] * e->channel_factor[c][q];
  /* ∂ prediction / ∂ log gain = R'(linear) · linear = chain · linear */
  if (n->map[c].gain >= 0) v[m++] = scale * chain * linear;
  for (int j = 0; j < CF_RESPONSE_MODEL_KNOTS; ++j)
    if (e->response_u[j] >= 0) v[m++] = scale * dslope[j];
  if (n->map[c].light_entries)
    m += light_rows(e, &n->map[c], c, first, slots, w, scale * chain * gain, v + m);
  if (n->score)
    score_add(p, n, row, c, v, u);
  else
    local_add(&n->local[c], v, u);
  return share;
}

/* The block's rows [begin, begin + count), image by image: their cost
 * Σ w ρ into *total, and with the normal equations (n), the last image's
 * sums flushed and every diagonal entry checked. Returns 0 when something
 * is not finite. */
static int evaluate_rows(const block_eval *e, block_normal *n, size_t begin, size_t count,
                         double *total) {
  const fit_problem *p = e->p;
  uint32_t gain_image = UINT32_MAX;
  double gain[3] = {0.0, 0.0, 0.0}, sum = 0.0;
  int finite = 1;
  for (size_t i = 0; finite && i < count; ++i) {
    size_t row = begin + i;
    uint32_t image = p->image[row];
    if (image != gain_image) {
      for (int c = 0; c < 3; ++c)
        gain[c] = image_gain(e->log_scale, e->s->log_e[image] + e->s->log_b[3 * image + c]);
      if (e->light_on) image_slot_gains(p, e->s->log_g, image, e->s->slot_gain);
      if (n) next_image(e, n, gain_image != UINT32_MAX, image);
      gain_image = image;
    }
    size_t first;
    size_t slots = fit_problem_slot_range(p, row, &first);
    const double *w = p->weight + 3 * first;
    first -= e->first_pair; /* into f and grad */
    if (e->light_on) w = light_weighted(p, e->s->slot_gain, w, slots, e->s->light_w + 3 * first);
    for (int c = 0; c < 3; ++c) sum += channel_row(e, n, row, c, first, slots, w, gain[c]);
    finite = isfinite(sum); /* the shares are >= 0: one not finite leaves the sum so */
  }
  *total = sum;
  if (!finite || !n) return finite;
  for (int c = 0; c < 3 && gain_image != UINT32_MAX; ++c)
    local_flush(&n->local[c], &n->map[c], n->k, n->jtj, n->jtu);
  for (int a = 0; a < n->k; ++a)
    finite =
        finite && isfinite(n->jtu[a]) && isfinite(n->jtj[(size_t)a * (size_t)n->k + (size_t)a]);
  return finite;
}

/* Block b's observations: the first, *begin, and their count, *n; and
 * their pairs: the first, *first_pair, and their count (returned). */
static size_t block_pairs(const fit_problem *p, size_t block, size_t *begin, size_t *n,
                          size_t *first_pair) {
  *begin = block * p->block_size;
  *n = p->count - *begin < p->block_size ? p->count - *begin : p->block_size;
  fit_problem_slot_range(p, *begin, first_pair);
  if (*n == 0) return 0;
  size_t last_pair;
  size_t last_slots = fit_problem_slot_range(p, *begin + *n - 1, &last_pair);
  return last_pair + last_slots - *first_pair;
}

/* The response's smoothness prior (docs/model.md §5.4): the residuals
 * (a_{j+1} − a_j) / FIT_RESPONSE_PRIOR_SD of neighbouring free slopes,
 * their squares' sum returned and, with n, their rows in its normal
 * equations. It holds a slope whose knot no observation reaches to its
 * neighbour's; a power has none. */
static double response_prior(const block_eval *e, block_normal *n) {
  const int *place = e->s->place;
  double w = 1.0 / FIT_RESPONSE_PRIOR_SD, sum = 0.0;
  for (int j = 0; j + 1 < CF_RESPONSE_MODEL_KNOTS; ++j) {
    if (e->response_u[j] < 0 || e->response_u[j + 1] < 0) continue;
    double r = w * (e->response[j + 1] - e->response[j]);
    sum += r * r;
    if (!n) continue;
    size_t a = (size_t)place[e->response_u[j]], b = (size_t)place[e->response_u[j + 1]];
    size_t k = (size_t)n->k;
    n->jtu[a] -= w * r;
    n->jtu[b] += w * r;
    n->jtj[a * k + a] += w * w;
    n->jtj[b * k + b] += w * w;
    n->jtj[a * k + b] -= w * w;
    n->jtj[b * k + a] -= w * w;
  }
  return sum;
}

int fit_problem_evaluate(void *user, const double *x, size_t block, double *cost, double *jtj,
                         double *jtu) {
  block_eval e;
  e.p = user;
  size_t begin, count;
  size_t pairs = block_pairs(e.p, block, &begin, &count, &e.first_pair);
  e.s = scratch_take(e.p);
  if (!e.s || !scratch_fit(e.s, e.p, pairs, jtj != NULL)) {
    scratch_give(e.s);
    return CF_LSQ_FAILED;
  }
  e.f = e.s->f;
  e.grad = jtj ? e.s->grad : NULL;
  unknowns_at(&e, x);
  block_normal normal = {.jtj = jtj, .jtu = jtu}, *n = jtj ? &normal : NULL;
  if (n) normal_layout(&e, block, n);
  double total = 0.0; /* Σ w ρ */
  int finite = cf_eval_batch(e.p->model, e.params, pairs, e.p->geometry + e.first_pair, e.s->f,
                             e.grad) == CF_OK;
  /* (the cost alone in a call of its own: the compiler makes it a copy
   * without the Jacobian's branches; its pass about 4 % faster, measured) */
  if (finite)
    finite = n ? evaluate_rows(&e, n, begin, count, &total)
               : evaluate_rows(&e, NULL, begin, count, &total);
  if (finite && block == 0 && e.response_free) total += response_prior(&e, n);
  *cost = 0.5 * total;
  scratch_give(e.s);
  return finite && isfinite(*cost) ? CF_LSQ_EVALUATED : CF_LSQ_NOT_FINITE;
}

int fit_problem_block_columns(void *user, size_t block, const int **columns) {
  const fit_problem *p = user;
  *columns = p->block_column + p->block_column_begin[block];
  return (int)(p->block_column_begin[block + 1] - p->block_column_begin[block]);
}

cf_status fit_problem_group_scores(const fit_problem *p, const size_t *group, double *score,
                                   cf_error *err) {
  size_t k = (size_t)p->num_unknowns;
  double *x = malloc((k ? k : 1) * sizeof *x), *jtj = malloc((k ? k * k : 1) * sizeof *jtj);
  double *jtu = malloc((k ? k : 1) * sizeof *jtu), total;
  block_eval e = {.p = p, .s = scratch_take(p)};
  cf_status s = x && jtj && jtu && e.s ? CF_OK : cf_error_set(err, CF_ENOMEM, "out of memory");
  if (s == CF_OK) fit_problem_get_x(p, x);
  /* (the local sums stay 0: jtj and jtu are where evaluate_rows flushes them) */
  block_normal n = {.jtj = jtj, .jtu = jtu, .score = score, .group = group};
  for (size_t b = 0; s == CF_OK && b < p->num_blocks; ++b) {
    size_t begin, count;
    size_t pairs = block_pairs(p, b, &begin, &count, &e.first_pair);
    if (!scratch_fit(e.s, p, pairs, 1)) {
      s = cf_error_set(err, CF_ENOMEM, "out of memory");
      break;
    }
    e.f = e.s->f;
    e.grad = e.s->grad;
    unknowns_at(&e, x);
    normal_layout(&e, b, &n);
    n.columns = p->block_column + p->block_column_begin[b];
    if (cf_eval_batch(p->model, e.params, pairs, p->geometry + e.first_pair, e.f, e.grad) !=
            CF_OK ||
        !evaluate_rows(&e, &n, begin, count, &total))
      s = cf_error_set(err, CF_ENUMERIC, "the fit's Jacobian is not finite at its values");
  }
  scratch_give(e.s);
  free(x);
  free(jtj);
  free(jtu);
  return s;
}

/* A range of rows' predictions (fit_problem_predict), on one thread. */
typedef struct predict_job {
  const fit_problem *p;
  double *prediction, *measured;
  size_t rows_per_part;
  int failed;
} predict_job;

static void predict_part(void *user, int part) {
  predict_job *job = user;
  const fit_problem *p = job->p;
  size_t begin = (size_t)part * job->rows_per_part;
  size_t end = begin + job->rows_per_part < p->count ? begin + job->rows_per_part : p->count;
  if (begin >= end) return;
  size_t first_pair, last_pair;
  fit_problem_slot_range(p, begin, &first_pair);
  size_t last_slots = fit_problem_slot_range(p, end - 1, &last_pair);
  size_t pairs = last_pair + last_slots - first_pair;
  fit_scratch *s = scratch_take(p);
  if (!s || !scratch_fit(s, p, pairs, 0)) {
    scratch_give(s);
    job->failed = 1;
    return;
  }
  cf_eval_batch(p->model, p->params, pairs, p->geometry + first_pair, s->f, NULL);
  uint32_t gain_image = UINT32_MAX;
  double gain[3] = {0.0, 0.0, 0.0};
  for (size_t i = begin; i < end; ++i) {
    size_t first;
    size_t slots = fit_problem_slot_range(p, i, &first);
    if (p->image[i] != gain_image) {
      gain_image = p->image[i];
      for (int c = 0; c < 3; ++c)
        gain[c] = image_gain(p->log_scale, p->log_exposures[gain_image] +
                                               p->log_balance[3 * (size_t)gain_image + (size_t)c]);
      if (p->light_gains_on) image_slot_gains(p, p->log_light, gain_image, s->slot_gain);
    }
    const double *w = p->weight + 3 * first;
    if (p->light_gains_on)
      w = light_weighted(p, s->slot_gain, w, slots, s->light_w + 3 * (first - first_pair));
    for (int c = 0; c < 3; ++c) {
      const double *dmodel;
      double weight_one;
      double model = model_value(w, s->f, NULL, p->dim, first - first_pair, slots, c, NULL, &dmodel,
                                 &weight_one);
      job->prediction[3 * i + (size_t)c] =
          predict_channel(p->response_on, p->response, gain[c] * model, NULL, NULL);
      job->measured[3 * i + (size_t)c] = p->y[3 * i + (size_t)c];
    }
  }
  scratch_give(s);
}

cf_status fit_problem_predict(const fit_problem *p, double *prediction, double *measured,
                              cf_error *err) {
  /* parts of whole blocks, one per thread, for a population worth it */
  int parts = p->threads > 1 && p->count >= 4 * (size_t)p->block_size ? p->threads : 1;
  size_t blocks = (p->count + p->block_size - 1) / p->block_size;
  predict_job job = {p, prediction, measured,
                     ((blocks + (size_t)parts - 1) / (size_t)parts) * p->block_size, 0};
  if (job.rows_per_part == 0) job.rows_per_part = 1;
  cf_parallel_for(parts, parts, predict_part, &job);
  return job.failed ? cf_error_set(err, CF_ENOMEM, "out of memory") : CF_OK;
}

cf_status fit_problem_init_sample(fit_problem *p, fit_sample *sample, const cf_capture *capture,
                                  cf_model_id model, const fit_population *population,
                                  size_t target, cf_error *err) {
  cf_status s = fit_sample_draw(cf_capture_observations(capture), population, target, sample, err);
  if (s != CF_OK) return s;
  s = fit_problem_init(p, capture, model, sample->index, sample->count, 1, err);
  if (s != CF_OK) {
    fit_sample_free(sample);
    return s;
  }
  s = fit_problem_set_sample_weights(p, sample->weight, err);
  if (s != CF_OK) {
    fit_problem_release(p);
    fit_sample_free(sample);
  }
  return s;
}

cf_status fit_population_of_images(const cf_capture *capture, const unsigned char *use_image,
                                   fit_population *population, uint32_t **index, cf_error *err) {
  const cf_observations *obs = cf_capture_observations(capture);
  *index = NULL;
  population->index = NULL;
  population->count = obs->count;
  population->weight = NULL;
  if (!use_image) return CF_OK;
  *index = malloc((obs->count ? obs->count : 1) * sizeof **index);
  if (!*index) return cf_error_set(err, CF_ENOMEM, "out of memory");
  size_t n = 0;
  for (size_t i = 0; i < obs->count; ++i)
    if (use_image[obs->image[i]]) (*index)[n++] = (uint32_t)i;
  population->index = *index;
  population->count = n;
  if (n == 0) return cf_error_set(err, CF_EINVAL, "the images chosen have no observations");
  return CF_OK;
}
