/* The fit's least-squares problem as a whole (fit_problem.h): made from a
 * capture's observations, forked for the multi-start, freed, read. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "problem.h"

cf_status fit_values_alloc(fit_values *v, size_t images, size_t lights, cf_error *err) {
  v->log_exposures = calloc(images ? images : 1, sizeof *v->log_exposures);
  v->log_balance = calloc(3 * (images ? images : 1), sizeof *v->log_balance);
  v->log_light = calloc(lights ? lights : 1, sizeof *v->log_light);
  if (v->log_exposures && v->log_balance && v->log_light) return CF_OK;
  fit_values_free(v);
  return cf_error_set(err, CF_ENOMEM, "out of memory for the gains of %zu images", images);
}

void fit_values_free(fit_values *v) {
  free(v->log_exposures);
  free(v->log_balance);
  free(v->log_light);
  v->log_exposures = v->log_balance = v->log_light = NULL;
}

/* The values of `from` into `to` (both sized for p's images and lights). */
static void copy_values(const fit_problem *p, fit_values *to, const fit_values *from) {
  size_t images = p->groups.images;
  memcpy(to->params, from->params, sizeof to->params);
  to->log_scale = from->log_scale;
  memcpy(to->response, from->response, sizeof to->response);
  memcpy(to->log_exposures, from->log_exposures, images * sizeof *to->log_exposures);
  memcpy(to->log_balance, from->log_balance, 3 * images * sizeof *to->log_balance);
  memcpy(to->log_light, from->log_light, p->groups.light_count * sizeof *to->log_light);
}

cf_status fit_values_save(const fit_problem *p, fit_values *copy, cf_error *err) {
  cf_status s = fit_values_alloc(copy, p->groups.images, p->groups.light_count, err);
  if (s == CF_OK) copy_values(p, copy, &p->values);
  return s;
}

void fit_values_restore(fit_problem *p, const fit_values *copy) {
  copy_values(p, &p->values, copy);
}

void fit_problem_copy_values(fit_problem *to, const fit_problem *from) {
  copy_values(from, &to->values, &from->values);
}

cf_status fit_problem_new(fit_problem **out, const cf_capture *capture, cf_model_id model,
                          const uint32_t *index, size_t count, int threads, cf_error *err) {
  fit_problem *p = *out = calloc(1, sizeof *p);
  if (!p) return cf_error_set(err, CF_ENOMEM, "out of memory");
  p->capture = capture;
  p->obs = cf_capture_observations(capture);
  p->model = model;
  p->dim = cf_model_info_get(model)->dim;
  p->threads = threads > 1 ? threads : 1;
  p->loss = CF_LOSS_NONE;
  p->blocks.size = FIT_BLOCK_SIZE;
  cf_model_default_params(model, p->values.params);
  fit_response_identity(p->values.response);
  cf_status s = fit_rows_init(&p->rows, p->obs, index, count, p->threads, err);
  if (s == CF_OK) s = fit_groups_init(&p->groups, capture, p->obs->lights, err);
  if (s == CF_OK) s = fit_values_alloc(&p->values, p->groups.images, p->groups.light_count, err);
  if (s != CF_OK) {
    fit_problem_free(p);
    *out = NULL;
    return s;
  }
  fit_problem_group_gains(p, 0); /* a gain per image, when free */
  fit_problem_set_sigma(p, 1.0);
  return CF_OK;
}

void fit_problem_free(fit_problem *p) {
  if (!p) return;
  fit_values_free(&p->values);
  if (p->origin) { /* a fork: its at_bound alone is its own */
    free(p->unknowns.at_bound);
    free(p);
    return;
  }
  fit_rows_release(&p->rows);
  fit_groups_release(&p->groups);
  fit_unknowns_release(&p->unknowns);
  free(p->blocks.column_begin);
  free(p->blocks.column);
  fit_scratch_pool_free(&p->scratch);
  free(p);
}

cf_status fit_problem_fork(const fit_problem *p, fit_problem **out, cf_error *err) {
  fit_problem *fork = *out = malloc(sizeof *fork);
  if (!fork) return cf_error_set(err, CF_ENOMEM, "out of memory");
  *fork = *p;
  fork->origin = p;
  fork->radius = 0.0;
  memset(&fork->tally, 0, sizeof fork->tally);
  fork->values.log_exposures = fork->values.log_balance = fork->values.log_light = NULL;
  size_t n = p->unknowns.num ? (size_t)p->unknowns.num : 1;
  fork->unknowns.at_bound = calloc(n, sizeof *fork->unknowns.at_bound);
  cf_status s = fork->unknowns.at_bound
                    ? fit_values_save(p, &fork->values, err)
                    : cf_error_set(err, CF_ENOMEM, "out of memory");
  if (s != CF_OK) {
    fit_problem_free(fork);
    *out = NULL;
  }
  return s;
}

cf_model_id fit_problem_model(const fit_problem *p) {
  return p->model;
}

int fit_problem_dim(const fit_problem *p) {
  return p->dim;
}

const cf_capture *fit_problem_capture(const fit_problem *p) {
  return p->capture;
}

size_t fit_problem_count(const fit_problem *p) {
  return p->rows.count;
}

size_t fit_problem_images(const fit_problem *p) {
  return p->groups.images;
}

size_t fit_problem_observation(const fit_problem *p, size_t i) {
  return fit_rows_observation(&p->rows, i);
}

uint32_t fit_problem_image(const fit_problem *p, size_t i) {
  return p->rows.image[i];
}

const double *fit_problem_measured(const fit_problem *p) {
  return p->rows.y;
}

const double *fit_problem_inv_sigma(const fit_problem *p) {
  return p->rows.inv_sigma;
}

const double *fit_problem_sample_roots(const fit_problem *p) {
  return p->rows.sample_root;
}

const fit_values *fit_problem_read_values(const fit_problem *p) {
  return &p->values;
}

fit_values *fit_problem_values(fit_problem *p) {
  return &p->values;
}

int fit_problem_response_on(const fit_problem *p) {
  return p->response_on;
}

const fit_groups *fit_problem_groups(const fit_problem *p) {
  return &p->groups;
}

double fit_problem_sigma(const fit_problem *p) {
  return p->rows.sigma;
}

void fit_problem_set_loss(fit_problem *p, cf_loss loss, double scale) {
  p->loss = loss;
  p->loss_scale = scale;
}

cf_status fit_problem_set_sample_weights(fit_problem *p, const double *weight, cf_error *err) {
  fit_rows *r = &p->rows;
  free(r->sample_root);
  r->sample_root = malloc((r->count ? r->count : 1) * sizeof *r->sample_root);
  if (!r->sample_root) return cf_error_set(err, CF_ENOMEM, "out of memory");
  for (size_t i = 0; i < r->count; ++i) r->sample_root[i] = sqrt(weight[i]);
  return CF_OK;
}

void fit_problem_set_measured(fit_problem *p, const double *y, const uint8_t *flags) {
  fit_rows *r = &p->rows;
  for (size_t i = 0; i < r->count; ++i) {
    size_t k = fit_rows_observation(r, i);
    for (int c = 0; c < 3; ++c) r->y[3 * i + (size_t)c] = y[3 * k + (size_t)c];
    r->flags[i] = flags[k];
  }
}

size_t fit_problem_pairs(const fit_problem *p, size_t i, const cf_geometry **geometry,
                         const double **weight) {
  size_t first, slots = fit_rows_slot_range(&p->rows, i, &first);
  *geometry = p->rows.geometry + first;
  *weight = p->rows.weight + 3 * first;
  return slots;
}

int fit_problem_unknown_count(const fit_problem *p) {
  return p->unknowns.num;
}

fit_unknown fit_problem_unknown(const fit_problem *p, int u) {
  return p->unknowns.unknown[u];
}

int fit_problem_has_kind(const fit_problem *p, const fit_kind *kind) {
  return fit_unknowns_run(&p->unknowns, kind) != NULL;
}

double fit_problem_lower(const fit_problem *p, int u) {
  return p->unknowns.lower[u];
}

double fit_problem_upper(const fit_problem *p, int u) {
  return p->unknowns.upper[u];
}

int *fit_problem_at_bound(fit_problem *p) {
  return p->unknowns.at_bound;
}

const int *fit_problem_read_at_bound(const fit_problem *p) {
  return p->unknowns.at_bound;
}

size_t fit_problem_block_count(const fit_problem *p) {
  return p->blocks.count;
}

int fit_problem_block_columns(void *user, size_t block, const int **columns) {
  const fit_problem *p = user;
  *columns = p->blocks.column + p->blocks.column_begin[block];
  return (int)(p->blocks.column_begin[block + 1] - p->blocks.column_begin[block]);
}

fit_solve_settings *fit_problem_settings(fit_problem *p) {
  return &p->settings;
}

void fit_problem_forget_radius(fit_problem *p) {
  p->radius = 0.0;
}

const fit_tally *fit_problem_tally(const fit_problem *p) {
  return &p->tally;
}
