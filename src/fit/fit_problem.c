/* The fit's least-squares problem (fit_problem.h). */
#include "fit_problem.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lsq/parallel.h"
#include "order_statistics.h"

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
  double threshold = fit_kth_smallest(sorted, n, n - n / 16);
  size_t specular = 0;
  for (size_t i = 0; i < n; ++i) specular += score[i] >= threshold;
  /* per stratum: how many to take, every stride-th */
  size_t want[2] = {target / 4, target - target / 4}, size[2] = {specular, n - specular};
  size_t stride[2], taken[2] = {0, 0}, seen[2] = {0, 0};
  for (int t = 0; t < 2; ++t) {
    stride[t] = want[t] > 0 && size[t] > want[t] ? size[t] / want[t] : 1;
  }
  size_t m = 0;
  for (size_t i = 0; i < n && m < capacity; ++i) {
    int t = score[i] >= threshold ? 0 : 1;
    if (seen[t]++ % stride[t] != 0 || taken[t] >= want[t] + 1) continue;
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
  p->response = 1.0;
  p->block_size = BLOCK_SIZE;
  p->threads = threads > 1 ? threads : 1;
  cf_model_default_params(model, p->params);
  size_t pairs = p->count * (size_t)p->lights;
  p->slots = pairs;
  p->geometry = malloc(pairs * sizeof *p->geometry);
  p->weight = malloc(3 * pairs * sizeof *p->weight);
  p->inv_sigma = malloc(3 * p->count * sizeof *p->inv_sigma);
  p->log_exposures = calloc(p->images, sizeof *p->log_exposures);
  p->y = malloc(3 * (p->count ? p->count : 1) * sizeof *p->y);
  p->image = malloc((p->count ? p->count : 1) * sizeof *p->image);
  p->flags = malloc(p->count ? p->count : 1);
  if (!p->geometry || !p->weight || !p->inv_sigma || !p->log_exposures || !p->y || !p->image ||
      !p->flags) {
    fit_problem_release(p);
    return cf_error_set(err, CF_ENOMEM, "out of memory for %zu observations", p->count);
  }
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

void fit_problem_release(fit_problem *p) {
  free(p->geometry);
  free(p->weight);
  free(p->inv_sigma);
  free(p->log_exposures);
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

/* 1/σ of the noise model at the values mu (3 per observation used: the
 * measurements or the predictions): the variance read² + shot · max(μ, 0),
 * floored at its smallest positive value over them (a dark pixel with no
 * read noise would otherwise weigh infinitely). */
static void noise_inv_sigma(fit_problem *p, double read, double shot, const double *mu) {
  size_t n = 3 * p->count;
  double floor = read > 0.0 ? read * read : HUGE_VAL;
  for (size_t i = 0; read == 0.0 && i < n; ++i)
    if (shot * mu[i] > 0.0) floor = fmin(floor, shot * mu[i]);
  for (size_t i = 0; i < n; ++i)
    p->inv_sigma[i] = 1.0 / sqrt(fmax(read * read + shot * fmax(mu[i], 0.0), floor));
}

void fit_problem_set_sigma(fit_problem *p, const cf_capture *capture, double sigma) {
  double read, shot;
  int noise = capture_noise(capture, &read, &shot);
  p->sigma = noise ? 0.0 : sigma;
  /* one σ for all, or the measurements, turned in place into the noise
   * model's 1/σ */
  for (size_t i = 0; i < 3 * p->count; ++i)
    p->inv_sigma[i] = noise ? p->y[i] : 1.0 / sqrt(sigma * sigma);
  if (noise) noise_inv_sigma(p, read, shot, p->inv_sigma);
}

cf_status fit_problem_reweight(fit_problem *p, const cf_capture *capture, cf_error *err) {
  double read, shot;
  if (!capture_noise(capture, &read, &shot)) return CF_OK;
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
  p->response_on = p->response != 1.0;
  memset(p->at_bound, 0, sizeof p->at_bound);
}

static void add_unknown(fit_problem *p, fit_unknown_kind kind, int slot, double lo, double hi) {
  int i = p->num_unknowns++;
  p->unknowns[i] = (fit_unknown){kind, slot};
  p->lower[i] = lo;
  p->upper[i] = hi;
}

void fit_problem_free_slot(fit_problem *p, int slot) {
  const cf_model_info *m = cf_model_info_get(p->model);
  for (int j = m->param_count - 1; j >= 0; --j)
    if (slot >= m->offsets[j]) {
      const cf_param_info *info = cf_param_info_get(m->params[j]);
      if (info->id == CF_PARAM_ALBEDO) {
        add_unknown(p, FIT_LOG_SLOT, slot, log(fmax(info->lower, FIT_ALBEDO_FLOOR)),
                    log(info->upper));
        return;
      }
      if (info->id == CF_PARAM_DIFFUSE_ROUGHNESS) {
        add_unknown(p, FIT_SQUARE_SLOT, slot, info->lower * info->lower, info->upper * info->upper);
        return;
      }
      add_unknown(p, FIT_MODEL_SLOT, slot, info->lower, info->upper);
      return;
    }
}

void fit_problem_free_scale(fit_problem *p) {
  add_unknown(p, FIT_LOG_SCALE, 0, -HUGE_VAL, HUGE_VAL);
}

void fit_problem_free_response(fit_problem *p) {
  add_unknown(p, FIT_RESPONSE, 0, FIT_RESPONSE_LOWER, FIT_RESPONSE_UPPER);
  p->response_on = 1;
}

void fit_problem_free_exposures(fit_problem *p) {
  for (size_t k = 0; k + 1 < p->images; ++k)
    add_unknown(p, FIT_LOG_EXPOSURE, (int)k, -HUGE_VAL, HUGE_VAL);
}

/* The blocks and their columns: the model's, the scale's and the
 * response's in every block; an exposure's where its image is (every
 * exposure where the last image is). */
cf_status fit_problem_finish(fit_problem *p, cf_error *err) {
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
    for (size_t i = begin; i < end; ++i) seen[p->image[i]] = 1;
    int has_last = seen[p->last_image];
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
      if (unk->kind != FIT_LOG_EXPOSURE || has_last || seen[unk->slot]) p->block_column[k++] = u;
    }
    p->block_column_begin[b + 1] = k;
    for (size_t i = begin; i < end; ++i) seen[p->image[i]] = 0;
  }
  free(seen);
  return failed ? cf_error_set(err, CF_ENOMEM, "out of memory for the residual blocks") : CF_OK;
}

void fit_problem_get_x(const fit_problem *p, double *x) {
  for (int i = 0; i < p->num_unknowns; ++i) {
    const fit_unknown *u = &p->unknowns[i];
    x[i] = u->kind == FIT_MODEL_SLOT    ? p->params[u->slot]
           : u->kind == FIT_LOG_SLOT    ? log(p->params[u->slot])
           : u->kind == FIT_SQUARE_SLOT ? p->params[u->slot] * p->params[u->slot]
           : u->kind == FIT_LOG_SCALE   ? p->log_scale
           : u->kind == FIT_RESPONSE    ? p->response
                                        : p->log_exposures[u->slot];
  }
}

/* The values x stands for: params, log s, log e_k (the last image's from
 * the others). */
static void values_at(const fit_problem *p, const double *x, double *params, double *log_scale,
                      double *response, double *log_exposures) {
  memcpy(params, p->params, sizeof p->params);
  *log_scale = p->log_scale;
  *response = p->response;
  if (log_exposures) memcpy(log_exposures, p->log_exposures, p->images * sizeof *log_exposures);
  int exposures_free = 0;
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
      *response = x[i];
    else if (log_exposures)
      log_exposures[u->slot] = x[i], exposures_free = 1;
  }
  if (exposures_free) {
    double sum = 0.0;
    for (size_t k = 0; k + 1 < p->images; ++k) sum += log_exposures[k];
    log_exposures[p->last_image] = -sum;
  }
}

void fit_problem_set_x(fit_problem *p, const double *x) {
  double params[CF_MAX_DIM], log_scale, response;
  values_at(p, x, params, &log_scale, &response, p->log_exposures);
  memcpy(p->params, params, sizeof params);
  p->log_scale = log_scale;
  p->response = response;
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

/* ---- residuals ---- */

/* The channel a model slot moves: c for component c of an RGB parameter,
 * −1 (all three) for a scalar one. */
static int slot_channel(cf_model_id model, int slot) {
  const cf_model_info *m = cf_model_info_get(model);
  for (int j = m->param_count - 1; j >= 0; --j)
    if (slot >= m->offsets[j])
      return cf_param_info_get(m->params[j])->components == 3 ? slot - m->offsets[j] : -1;
  return -1;
}

/* The normal equations of one channel's rows of one image, in a small
 * dense layout: the model unknowns that move the channel, then the log
 * gain (the scale's and the image's exposure's derivative, which are the
 * same), then the response. Rows add here without indirection; the sums go
 * to the block's columns when the image changes (fit_problem_evaluate). */
enum { LOCAL_MAX = CF_MAX_DIM + 2 };
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
 * image, to minus every exposure's). */
typedef struct local_map {
  int column[LOCAL_MAX];
  int gain; /* the log gain's local index, or −1 */
  const int *gain_column;
  const double *gain_sign;
  int gain_count;
} local_map;

static int local_targets(const local_map *map, int i, const int **column, const double **sign) {
  static const double one = 1.0;
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

int fit_problem_evaluate(void *user, const double *x, size_t block, double *cost, double *jtj,
                         double *jtu) {
  const fit_problem *p = user;
  size_t begin = block * p->block_size;
  size_t n = p->count - begin < p->block_size ? p->count - begin : p->block_size;
  size_t first_pair, last_pair;
  fit_problem_slot_range(p, begin, &first_pair);
  last_pair = first_pair;
  if (n > 0) last_pair = fit_problem_slot_range(p, begin + n - 1, &last_pair) + last_pair;
  size_t pairs = last_pair - first_pair;
  const int dim = p->dim, unknowns = p->num_unknowns;
  const int *columns = NULL;
  int k = 0;
  double params[CF_MAX_DIM], log_scale, response;
  double *log_e = malloc(p->images * sizeof *log_e);
  double *f = malloc(3 * pairs * sizeof *f);
  double *grad = jtj ? malloc(3 * (size_t)dim * pairs * sizeof *grad) : NULL;
  /* each unknown's place among the block's k columns; where the log gain
   * goes for the current image */
  int *place = jtj ? malloc(((size_t)unknowns + 1) * sizeof *place) : NULL;
  int *gain_column = jtj ? malloc(((size_t)unknowns + 1) * sizeof *gain_column) : NULL;
  double *gain_sign = jtj ? malloc(((size_t)unknowns + 1) * sizeof *gain_sign) : NULL;
  local_normal local[3];
  local_map map[3];
  int ok = log_e && f && (!jtj || (grad && place && gain_column && gain_sign));
  if (ok && jtj) {
    columns = p->block_column + p->block_column_begin[block];
    k = (int)(p->block_column_begin[block + 1] - p->block_column_begin[block]);
    for (int u = 0; u < unknowns; ++u) place[u] = -1;
    for (int c = 0; c < k; ++c) place[columns[c]] = c;
    memset(jtj, 0, (size_t)k * (size_t)k * sizeof *jtj);
    memset(jtu, 0, (size_t)k * sizeof *jtu);
  }
  /* per channel, the model unknowns that move it, their slots and
   * d param / d x (1, ρ for log ρ, 1/(2σ) for σ²); the scale's, the
   * response's and the exposures' unknowns */
  int channel_u[3][CF_MAX_DIM], channel_slot[3][CF_MAX_DIM], channel_count[3] = {0, 0, 0};
  double channel_factor[3][CF_MAX_DIM];
  int scale_u = -1, response_u = -1, exposures = 0;
  int *exposure_u = p->images > 0 ? malloc(p->images * sizeof *exposure_u) : NULL;
  ok = ok && exposure_u;
  if (ok) {
    values_at(p, x, params, &log_scale, &response, log_e);
    /* σ² unknowns: evaluate at σ >= 1e-6, so that ∂f/∂σ² = (∂f/∂σ)/(2σ)
     * has no 0/0 (f depends on σ through σ² only, and differs from its
     * value at σ = 0 by about 1e-13 relative there) */
    for (size_t i = 0; i < p->images; ++i) exposure_u[i] = -1;
    for (int u = 0; u < unknowns; ++u) {
      const fit_unknown *unk = &p->unknowns[u];
      if (unk->kind == FIT_SQUARE_SLOT) params[unk->slot] = fmax(params[unk->slot], 1e-6);
      if (unk->kind == FIT_LOG_SCALE)
        scale_u = u;
      else if (unk->kind == FIT_RESPONSE)
        response_u = u;
      else if (unk->kind == FIT_LOG_EXPOSURE)
        exposure_u[unk->slot] = u, exposures = 1;
    }
    for (int u = 0; u < unknowns; ++u) {
      const fit_unknown *unk = &p->unknowns[u];
      if (unk->kind != FIT_MODEL_SLOT && unk->kind != FIT_LOG_SLOT && unk->kind != FIT_SQUARE_SLOT)
        continue;
      double factor = unk->kind == FIT_LOG_SLOT      ? params[unk->slot]
                      : unk->kind == FIT_SQUARE_SLOT ? 0.5 / params[unk->slot]
                                                     : 1.0;
      int moves = slot_channel(p->model, unk->slot);
      for (int c = 0; c < 3; ++c) {
        if (moves >= 0 && moves != c) continue;
        int q = channel_count[c]++;
        channel_u[c][q] = u;
        channel_slot[c][q] = unk->slot;
        channel_factor[c][q] = factor;
      }
    }
    for (int c = 0; jtj && c < 3; ++c) { /* each channel's local layout */
      memset(&local[c], 0, sizeof local[c]);
      local_map *lm = &map[c];
      int size = channel_count[c];
      for (int q = 0; q < size; ++q) lm->column[q] = place[channel_u[c][q]];
      lm->gain = scale_u >= 0 || exposures ? size++ : -1;
      if (response_u >= 0) lm->column[size++] = place[response_u];
      lm->gain_column = gain_column;
      lm->gain_sign = gain_sign;
      lm->gain_count = 0;
      local[c].size = size;
    }
    ok = cf_eval_batch(p->model, params, pairs, p->geometry + first_pair, f, grad) == CF_OK;
  }
  double total = 0.0; /* Σ w ρ */
  uint32_t gain_image = UINT32_MAX;
  double gain = 0.0;
  for (size_t i = 0; ok && i < n; ++i) {
    size_t row = begin + i;
    const double *y = p->y + 3 * row;
    uint32_t image = p->image[row];
    if (image != gain_image) {
      gain = exp(log_scale + log_e[image]);
      if (jtj) { /* the last image's sums, and where this image's log gain goes */
        int count = 0;
        for (int c = 0; c < 3 && gain_image != UINT32_MAX; ++c)
          local_flush(&local[c], &map[c], k, jtj, jtu);
        if (scale_u >= 0) gain_column[count] = place[scale_u], gain_sign[count++] = 1.0;
        if (exposures && image == p->last_image) { /* log e_last = −Σ of the others */
          for (size_t e = 0; e + 1 < p->images; ++e)
            if (exposure_u[e] >= 0)
              gain_column[count] = place[exposure_u[e]], gain_sign[count++] = -1.0;
        } else if (exposures && exposure_u[image] >= 0) {
          gain_column[count] = place[exposure_u[image]], gain_sign[count++] = 1.0;
        }
        for (int c = 0; c < 3; ++c) map[c].gain_count = count;
      }
      gain_image = image;
    }
    size_t first;
    size_t slots = fit_problem_slot_range(p, row, &first);
    const double *w = p->weight + 3 * first;
    first -= first_pair; /* into f and grad */
    for (int c = 0; c < 3; ++c) {
      /* the prediction and its gradient in the model's slots: with one
       * slot, the evaluator's gradient scaled (no accumulator to zero: a
       * zeroed array here cost a fifth of this function in stores) */
      double model_value = 0.0, sum[CF_MAX_DIM], weight_one = 0.0;
      const double *dmodel = sum;
      if (slots == 1) {
        weight_one = w[c];
        model_value = weight_one * f[3 * first + (size_t)c];
        if (grad) dmodel = grad + (3 * first + (size_t)c) * (size_t)dim;
      } else {
        weight_one = 1.0;
        for (int s = 0; s < dim; ++s) sum[s] = 0.0;
        for (size_t j = 0; j < slots; ++j) {
          size_t pair = first + j;
          double wj = w[3 * j + (size_t)c];
          if (wj == 0.0) continue;
          model_value += wj * f[3 * pair + (size_t)c];
          if (!grad) continue;
          const double *g = grad + (3 * pair + (size_t)c) * (size_t)dim;
          for (int s = 0; s < dim; ++s) sum[s] += wj * g[s];
        }
      }
      /* with a response exponent, (gain · model)^γ and its chain factor
       * γ (gain · model)^(γ − 1) (0 where the linear value is not positive:
       * no light, no prediction) */
      double linear = gain * model_value, prediction = linear, chain = 1.0, log_linear = 0.0;
      if (p->response_on) {
        prediction = linear > 0.0 ? pow(linear, response) : 0.0;
        chain = linear > 0.0 ? response * prediction / linear : 0.0;
        log_linear = linear > 0.0 ? log(linear) : 0.0;
      }
      double inv_sigma = p->inv_sigma[3 * row + (size_t)c];
      double r = (prediction - y[c]) * inv_sigma;
      /* a clipped channel only counts while the model predicts less */
      int censored = fit_problem_censored_at(p, row, c, prediction, y[c]);
      if (censored) r = 0.0;
      double rho1, root = p->sample_root ? p->sample_root[row] : 1.0;
      double rho = robust(p, r * r, &rho1);
      total += root * root * rho;
      if (!isfinite(rho)) ok = 0;
      if (!jtj || censored) continue; /* a censored residual's row is 0 */
      /* the row of J: u = √w √ρ' r and its derivatives */
      /* (ρ' = 1 without a loss and inside Huber's core: no square root,
       * a tenth of an M2 pass) */
      double scale = root * (rho1 == 1.0 ? 1.0 : sqrt(rho1)) * inv_sigma;
      double u = scale * (prediction - y[c]);
      double model_scale = scale * chain * gain * weight_one, v[LOCAL_MAX];
      int m = 0;
      for (int q = 0; q < channel_count[c]; ++q)
        v[m++] = model_scale * dmodel[channel_slot[c][q]] * channel_factor[c][q];
      /* ∂ prediction / ∂ log gain = γ · prediction = chain · linear */
      if (map[c].gain >= 0) v[m++] = scale * chain * linear;
      if (response_u >= 0) v[m++] = scale * prediction * log_linear;
      local_add(&local[c], v, u);
    }
  }
  if (ok && jtj) { /* the last image's sums; a non-finite entry fails the block */
    for (int c = 0; c < 3 && gain_image != UINT32_MAX; ++c)
      local_flush(&local[c], &map[c], k, jtj, jtu);
    for (int a = 0; a < k; ++a)
      ok = ok && isfinite(jtu[a]) && isfinite(jtj[(size_t)a * (size_t)k + (size_t)a]);
  }
  *cost = 0.5 * total;
  free(exposure_u);
  free(log_e);
  free(f);
  free(grad);
  free(place);
  free(gain_column);
  free(gain_sign);
  return ok && isfinite(*cost);
}

int fit_problem_block_columns(void *user, size_t block, const int **columns) {
  const fit_problem *p = user;
  *columns = p->block_column + p->block_column_begin[block];
  return (int)(p->block_column_begin[block + 1] - p->block_column_begin[block]);
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
  double *f = malloc(3 * (pairs ? pairs : 1) * sizeof *f);
  if (!f) {
    job->failed = 1;
    return;
  }
  cf_eval_batch(p->model, p->params, pairs, p->geometry + first_pair, f, NULL);
  uint32_t gain_image = UINT32_MAX;
  double gain = 0.0;
  for (size_t i = begin; i < end; ++i) {
    size_t first;
    size_t slots = fit_problem_slot_range(p, i, &first);
    if (p->image[i] != gain_image) {
      gain_image = p->image[i];
      gain = exp(p->log_scale + p->log_exposures[gain_image]);
    }
    for (int c = 0; c < 3; ++c) {
      double value = 0.0;
      for (size_t pair = first; pair < first + slots; ++pair)
        value += p->weight[3 * pair + (size_t)c] * f[3 * (pair - first_pair) + (size_t)c];
      double linear = gain * value;
      job->prediction[3 * i + (size_t)c] =
          p->response_on ? (linear > 0.0 ? pow(linear, p->response) : 0.0) : linear;
      job->measured[3 * i + (size_t)c] = p->y[3 * i + (size_t)c];
    }
  }
  free(f);
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
