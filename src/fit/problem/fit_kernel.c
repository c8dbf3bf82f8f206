/* A block's cost and the normal equations of its Gauss-Newton model, and
 * the scores of groups of observations (fit_problem.h): the residual and
 * normal-equation kernel. Per row and channel it takes the derivatives of
 * the prediction that the kinds of unknowns need (kind.h's handles) and
 * adds them into the channel's local sums (fit_local.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fit_local.h"
#include "fit_loss.h"
#include "fit_row.h"
#include "fit_scratch.h"
#include "lsq/lsq.h"

/* The channel a model slot moves: c for component c of an RGB parameter,
 * −1 (all three) for a scalar one. */
static int slot_channel(cf_model_id model, int slot) {
  int component;
  const cf_param_info *info = cf_model_slot_param(model, slot, &component);
  return info && info->components == 3 ? component : -1;
}

/* An evaluation of a block at x: what holds over its rows. */
typedef struct block_eval {
  const fit_problem *p;
  fit_scratch *s;
  size_t first_pair; /* the block's first pair, where f and grad start */
  double *f, *grad;  /* the model's values and gradients (grad NULL: cost alone) */
  fit_values v;      /* the values at x (arrays in s) */
  /* per channel, the model unknowns that move it, their slots and
   * d param / d x (the kind's chain factor) */
  int channel_u[3][CF_MAX_DIM], channel_slot[3][CF_MAX_DIM], channel_count[3];
  double channel_factor[3][CF_MAX_DIM];
  const fit_run *gain_run[FIT_MAX_RUNS]; /* the runs taking the log gain's derivative */
  int gain_runs;
  int response_u[CF_RESPONSE_MODEL_KNOTS]; /* each slope's unknown, or −1 */
  int response_free;                        /* any slope free */
  const fit_run *light_run;                 /* the lights' gains free (NULL: not) */
  int light_on; /* the lights' gains apply (fit_problem.light_gains_on) */
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

/* A model kind's run into the channels' entries. */
static void model_entries(block_eval *e, const fit_run *run) {
  const fit_problem *p = e->p;
  for (int u = run->first; u < run->first + run->count; ++u) {
    int slot = p->unknowns.unknown[u].slot;
    double factor = run->kind->chain ? run->kind->chain(p, &e->v, slot) : 1.0;
    int moves = slot_channel(p->model, slot);
    for (int c = 0; c < 3; ++c) {
      if (moves >= 0 && moves != c) continue;
      int q = e->channel_count[c]++;
      e->channel_u[c][q] = u;
      e->channel_slot[c][q] = slot;
      e->channel_factor[c][q] = factor;
    }
  }
}

/* The values x stands for (the kinds' set over the current values), and
 * the unknowns' roles by their kinds' handles. */
static void unknowns_at(block_eval *e, const double *x) {
  const fit_problem *p = e->p;
  const fit_values *now = &p->values;
  e->v = (fit_values){.log_scale = now->log_scale,
                      .log_exposures = e->s->log_e,
                      .log_balance = e->s->log_b,
                      .log_light = e->s->log_g};
  memcpy(e->v.params, now->params, sizeof now->params);
  memcpy(e->v.response, now->response, sizeof now->response);
  memcpy(e->v.log_exposures, now->log_exposures, p->groups.images * sizeof *now->log_exposures);
  memcpy(e->v.log_balance, now->log_balance, 3 * p->groups.images * sizeof *now->log_balance);
  memcpy(e->v.log_light, now->log_light, p->groups.light_count * sizeof *now->log_light);
  if (x) fit_unknowns_values_at(p, x, &e->v);
  e->gain_runs = 0;
  e->response_free = 0;
  e->light_run = NULL;
  e->light_on = p->light_gains_on;
  for (int j = 0; j < CF_RESPONSE_MODEL_KNOTS; ++j) e->response_u[j] = -1;
  for (int c = 0; c < 3; ++c) e->channel_count[c] = 0;
  for (int r = 0; r < p->unknowns.runs; ++r) {
    const fit_run *run = &p->unknowns.run[r];
    switch (run->kind->handle) {
      case FIT_HANDLE_MODEL:
        model_entries(e, run);
        break;
      case FIT_HANDLE_GAIN:
        e->gain_run[e->gain_runs++] = run;
        break;
      case FIT_HANDLE_SLOPE:
        for (int u = run->first; u < run->first + run->count; ++u)
          e->response_u[p->unknowns.unknown[u].slot] = u, e->response_free = 1;
        break;
      case FIT_HANDLE_LIGHT:
        e->light_run = run;
        break;
    }
  }
}

/* Where the lights' gains go in the block: each light's place (−1: none;
 * the last light has no unknown), and for the last light's, minus every
 * other light's. */
static void light_layout(const block_eval *e, const int *place) {
  const fit_problem *p = e->p;
  fit_scratch *s = e->s;
  for (size_t l = 0; e->light_run && l < p->groups.light_count; ++l) {
    int u = (int)l < e->light_run->count ? e->light_run->first + (int)l : -1;
    s->light_place[l] = u >= 0 ? place[u] : -1;
    if (l + 1 < p->groups.light_count) s->last_places[l] = s->light_place[l], s->minus[l] = -1.0;
  }
}

/* The block's columns (each unknown's place among them), jtj and jtu
 * zeroed, and each channel's local layout: its model unknowns, the log
 * gain, the response. */
static void normal_layout(const block_eval *e, size_t block, block_normal *n) {
  const fit_problem *p = e->p;
  int *place = e->s->place;
  const int *columns = p->blocks.column + p->blocks.column_begin[block];
  n->k = (int)(p->blocks.column_begin[block + 1] - p->blocks.column_begin[block]);
  for (int u = 0; u < p->unknowns.num; ++u) place[u] = -1;
  for (int c = 0; c < n->k; ++c) place[columns[c]] = c;
  memset(n->jtj, 0, (size_t)n->k * (size_t)n->k * sizeof *n->jtj);
  memset(n->jtu, 0, (size_t)n->k * sizeof *n->jtu);
  for (int c = 0; c < 3; ++c) {
    memset(&n->local[c], 0, sizeof n->local[c]);
    local_map *lm = &n->map[c];
    int size = e->channel_count[c];
    for (int q = 0; q < size; ++q) lm->column[q] = place[e->channel_u[c][q]];
    lm->gain = e->gain_runs > 0 ? size++ : -1;
    for (int j = 0; j < CF_RESPONSE_MODEL_KNOTS; ++j)
      if (e->response_u[j] >= 0) lm->column[size++] = place[e->response_u[j]];
    size_t stride = (size_t)p->unknowns.num + 1; /* (fit_scratch_fit's columns) */
    lm->gain_column = e->s->gain_column + (size_t)c * stride;
    lm->gain_sign = e->s->gain_sign + (size_t)c * stride;
    lm->gain_count = 0;
    n->local[c].size = lm->light_first = size; /* (the image's lights after: next_image) */
    lm->light_entries = 0;
    lm->s = e->s;
    lm->last_light = p->groups.light_count - 1;
    lm->last_count = p->groups.light_count > 0 ? (int)p->groups.light_count - 1 : 0;
  }
  light_layout(e, place);
}

/* Image `image`'s lights as local entries: slot_entry[j] (lights; −1: no
 * light) and entry_light[q]; returns their count (at most FIT_IMAGE_LIGHTS,
 * which the check before the fit enforces). */
static int image_entries(const fit_problem *p, uint32_t image, int *slot_entry, int *entry_light) {
  const long *id = p->groups.slot_light + (size_t)image * (size_t)p->rows.lights;
  int count = 0;
  for (int j = 0; j < p->rows.lights; ++j) {
    slot_entry[j] = -1;
    for (int q = 0; q < count && id[j] >= 0 && slot_entry[j] < 0; ++q)
      if (entry_light[q] == id[j]) slot_entry[j] = q;
    if (id[j] >= 0 && slot_entry[j] < 0 && count < FIT_IMAGE_LIGHTS)
      entry_light[count] = (int)id[j], slot_entry[j] = count++;
  }
  return count;
}

/* The rows of a new image begin: the last image's sums into jtj and jtu
 * (unless there was none), where this image's log gain goes in each
 * channel (the gain kinds' targets), and its lights' entries. */
static void next_image(const block_eval *e, block_normal *n, int had_image, uint32_t image) {
  const fit_problem *p = e->p;
  for (int c = 0; c < 3 && had_image; ++c)
    local_flush(&n->local[c], &n->map[c], n->k, n->jtj, n->jtu);
  size_t stride = (size_t)p->unknowns.num + 1; /* each channel's (normal_layout) */
  for (int c = 0; c < 3; ++c) {
    int *column = e->s->gain_column + (size_t)c * stride, count = 0;
    double *sign = e->s->gain_sign + (size_t)c * stride;
    for (int r = 0; r < e->gain_runs; ++r)
      count += e->gain_run[r]->kind->gain_targets(p, e->gain_run[r], e->s->place, image, c,
                                                  column + count, sign + count);
    n->map[c].gain_count = count;
  }
  int entries = e->light_run ? image_entries(p, image, e->s->slot_entry, e->s->entry_light) : 0;
  for (int c = 0; c < 3; ++c)
    n->map[c].light_entries = entries, n->local[c].size = n->map[c].light_first + entries;
}

/* Channel c's derivatives in the image's lights' log gains into v: ∂μ/∂
 * log g_l = factor · Σ over light l's pairs of w f (factor: R' s e_k b_kc
 * times the row's scale; w with the gains: fit_light_weighted). Returns
 * their count. */
static int light_rows(const block_eval *e, const local_map *map, int c, size_t first, size_t slots,
                      const double *w, double factor, double *v) {
  double share[FIT_IMAGE_LIGHTS] = {0.0};
  for (size_t j = 0; j < slots; ++j) {
    int q = e->s->slot_entry[j % (size_t)e->p->rows.lights];
    if (q >= 0) share[q] += w[3 * j + (size_t)c] * e->f[3 * (first + j) + (size_t)c];
  }
  for (int q = 0; q < map->light_entries; ++q) v[q] = factor * share[q];
  return map->light_entries;
}

/* Row `row`'s channel c with its row v of J and residual u (channel_row)
 * into its group's score: −v u, each local index to its columns. */
static void score_add(const fit_problem *p, block_normal *n, size_t row, int c, const double *v,
                      double u) {
  double *score = n->score + n->group[row] * (size_t)p->unknowns.num;
  for (int i = 0; i < n->local[c].size; ++i) {
    const int *column;
    const double *sign;
    int count = local_targets(&n->map[c], i, &column, &sign);
    for (int t = 0; t < count; ++t) score[n->columns[column[t]]] -= sign[t] * v[i] * u;
  }
}

/* Row `row`'s channel c's row v of J (its local entries: the model's, the
 * log gain's, the slopes', the lights'), from its scale (√w √ρ' σ⁻¹ times
 * the censored slope), ∂μ/∂linear (chain), its gain and linear value, the
 * model's gradient and the slopes' derivatives. Returns the count. */
static int jacobian_row(const block_eval *e, const block_normal *n, int c, size_t first,
                        size_t slots, const double *w, double scale, double chain, double gain,
                        double linear, const double *dmodel, double weight_one,
                        const double *dslope, double *v) {
  double model_scale = scale * chain * gain * weight_one;
  int m = 0;
  for (int q = 0; q < e->channel_count[c]; ++q)
    v[m++] = model_scale * dmodel[e->channel_slot[c][q]] * e->channel_factor[c][q];
  /* ∂ prediction / ∂ log gain = R'(linear) · linear = chain · linear */
  if (n->map[c].gain >= 0) v[m++] = scale * chain * linear;
  for (int j = 0; j < CF_RESPONSE_MODEL_KNOTS; ++j)
    if (e->response_u[j] >= 0) v[m++] = scale * dslope[j];
  if (n->map[c].light_entries)
    m += light_rows(e, &n->map[c], c, first, slots, w, scale * chain * gain, v + m);
  return m;
}

/* Channel c of row `row` (its `slots` pairs from `first` in f and grad,
 * weighed by w; its image's gain): its share w ρ >= 0 of the cost
 * (returned; not finite with ρ), and with the normal equations (n) its row
 * of J and u = √w √ρ' r into the channel's local sums. */
static double channel_row(const block_eval *e, block_normal *n, size_t row, int c, size_t first,
                          size_t slots, const double *w, double gain) {
  const fit_problem *p = e->p;
  double sum[CF_MAX_DIM], weight_one;
  const double *dmodel;
  double model =
      fit_model_value(w, e->f, e->grad, p->dim, first, slots, c, sum, &dmodel, &weight_one);
  double linear = gain * model, chain = 1.0, dslope[CF_RESPONSE_MODEL_KNOTS];
  double prediction =
      fit_predict_channel(p->response_on, e->v.response, linear, n ? &chain : NULL, dslope);
  double y = p->rows.y[3 * row + (size_t)c], inv_sigma = p->rows.inv_sigma[3 * row + (size_t)c];
  double r = (prediction - y) * inv_sigma;
  /* a clipped channel says only that the true value is at least y, its
   * clip level: the censored likelihood's residual and slope (53) */
  int clipped = p->rows.flags[row] >> c & 1u;
  double slope = 1.0;
  if (clipped) r = fit_censored_residual(r, &slope);
  int censored = clipped && slope == 0.0;
  double rho1, root = p->rows.sample_root ? p->rows.sample_root[row] : 1.0;
  double rho = fit_robust(p, r * r, &rho1), share = root * root * rho;
  if (!n || censored) return share; /* a censored residual's row is 0 */
  /* (ρ' = 1 without a loss and inside Huber's core: no square root, a
   * tenth of an M2 pass) */
  double scale = root * (rho1 == 1.0 ? 1.0 : sqrt(rho1)) * inv_sigma;
  double u = clipped ? scale / inv_sigma * r : scale * (prediction - y), v[LOCAL_MAX];
  scale *= slope;
  jacobian_row(e, n, c, first, slots, w, scale, chain, gain, linear, dmodel, weight_one, dslope,
               v);
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
    uint32_t image = p->rows.image[row];
    if (image != gain_image) {
      for (int c = 0; c < 3; ++c)
        gain[c] = fit_image_gain(e->v.log_scale, e->v.log_exposures[image] +
                                                     e->v.log_balance[3 * image + (uint32_t)c]);
      if (e->light_on) fit_image_slot_gains(p, e->v.log_light, image, e->s->slot_gain);
      if (n) next_image(e, n, gain_image != UINT32_MAX, image);
      gain_image = image;
    }
    size_t first;
    size_t slots = fit_rows_slot_range(&p->rows, row, &first);
    const double *w = p->rows.weight + 3 * first;
    first -= e->first_pair; /* into f and grad */
    if (e->light_on)
      w = fit_light_weighted(p, e->s->slot_gain, w, slots, e->s->light_w + 3 * first);
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
  *begin = block * p->blocks.size;
  *n = p->rows.count - *begin < p->blocks.size ? p->rows.count - *begin : p->blocks.size;
  fit_rows_slot_range(&p->rows, *begin, first_pair);
  if (*n == 0) return 0;
  size_t last_pair;
  size_t last_slots = fit_rows_slot_range(&p->rows, *begin + *n - 1, &last_pair);
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
    double r = w * (e->v.response[j + 1] - e->v.response[j]);
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
  e.s = fit_scratch_take(e.p);
  if (!e.s || !fit_scratch_fit(e.s, e.p, pairs, jtj != NULL)) {
    fit_scratch_give(e.s);
    return CF_LSQ_FAILED;
  }
  e.f = e.s->f;
  e.grad = jtj ? e.s->grad : NULL;
  unknowns_at(&e, x);
  block_normal normal = {.jtj = jtj, .jtu = jtu}, *n = jtj ? &normal : NULL;
  if (n) normal_layout(&e, block, n);
  double total = 0.0; /* Σ w ρ */
  int finite = cf_eval_batch(e.p->model, e.v.params, pairs, e.p->rows.geometry + e.first_pair,
                             e.s->f, e.grad) == CF_OK;
  /* (the cost alone in a call of its own: the compiler makes it a copy
   * without the Jacobian's branches; its pass about 4 % faster, measured) */
  if (finite)
    finite = n ? evaluate_rows(&e, n, begin, count, &total)
               : evaluate_rows(&e, NULL, begin, count, &total);
  if (finite && block == 0 && e.response_free) total += response_prior(&e, n);
  *cost = 0.5 * total;
  fit_scratch_give(e.s);
  return finite && isfinite(*cost) ? CF_LSQ_EVALUATED : CF_LSQ_NOT_FINITE;
}

int fit_problem_cost(const fit_problem *p, double *cost) {
  *cost = 0.0;
  for (size_t b = 0; b < p->blocks.count; ++b) {
    double block_cost;
    if (fit_problem_evaluate((void *)p, NULL, b, &block_cost, NULL, NULL) != CF_LSQ_EVALUATED)
      return 0;
    *cost += block_cost;
  }
  return 1;
}

cf_status fit_problem_group_scores(const fit_problem *p, const size_t *group, double *score,
                                   cf_error *err) {
  size_t k = (size_t)p->unknowns.num;
  double *x = malloc((k ? k : 1) * sizeof *x), *jtj = malloc((k ? k * k : 1) * sizeof *jtj);
  double *jtu = malloc((k ? k : 1) * sizeof *jtu), total;
  block_eval e = {.p = p, .s = fit_scratch_take(p)};
  cf_status s = x && jtj && jtu && e.s ? CF_OK : cf_error_set(err, CF_ENOMEM, "out of memory");
  if (s == CF_OK) fit_problem_get_x(p, x);
  /* (the local sums stay 0: jtj and jtu are where evaluate_rows flushes them) */
  block_normal n = {.jtj = jtj, .jtu = jtu, .score = score, .group = group};
  for (size_t b = 0; s == CF_OK && b < p->blocks.count; ++b) {
    size_t begin, count;
    size_t pairs = block_pairs(p, b, &begin, &count, &e.first_pair);
    if (!fit_scratch_fit(e.s, p, pairs, 1)) {
      s = cf_error_set(err, CF_ENOMEM, "out of memory");
      break;
    }
    e.f = e.s->f;
    e.grad = e.s->grad;
    unknowns_at(&e, x);
    normal_layout(&e, b, &n);
    n.columns = p->blocks.column + p->blocks.column_begin[b];
    if (cf_eval_batch(p->model, e.v.params, pairs, p->rows.geometry + e.first_pair, e.f, e.grad) !=
            CF_OK ||
        !evaluate_rows(&e, &n, begin, count, &total))
      s = cf_error_set(err, CF_ENUMERIC, "the fit's Jacobian is not finite at its values");
  }
  fit_scratch_give(e.s);
  free(x);
  free(jtj);
  free(jtu);
  return s;
}
