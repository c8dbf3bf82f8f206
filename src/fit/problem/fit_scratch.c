/* The evaluations' working memory (fit_scratch.h). */
#include "fit_scratch.h"

#include <stdlib.h>
#include <string.h>

/* Buffers in a problem's pool: more than the solver's threads ever take
 * at once (an evaluation beyond takes one of its own). */
enum { SCRATCH_POOL = 16 }; /* the threads' cap (MOST_THREADS): a derivation */

static void free_arrays(fit_scratch *s) {
  free(s->f);
  free(s->grad);
  free(s->place);
  free(s->gain_column);
  free(s->gain_sign);
  free(s->log_e);
  free(s->log_b);
  free(s->light_d);
  free(s->light_i);
}

/* Room in the scratch's light arrays for the problem's lights. */
static int fit_lights(fit_scratch *s, const fit_problem *p) {
  size_t room = p->groups.light_count + (size_t)p->rows.lights + 1;
  if (room <= s->light_room) return 1;
  free(s->light_d);
  free(s->light_i);
  s->light_d = malloc(3 * room * sizeof *s->light_d);
  s->light_i = malloc(4 * room * sizeof *s->light_i);
  s->light_room = s->light_d && s->light_i ? room : 0;
  if (!s->light_room) return 0;
  s->log_g = s->light_d, s->minus = s->light_d + room, s->slot_gain = s->light_d + 2 * room;
  s->light_place = s->light_i, s->last_places = s->light_i + room;
  s->slot_entry = s->light_i + 2 * room, s->entry_light = s->light_i + 3 * room;
  return 1;
}

/* Room for the values' arrays of the problem's images. */
static int fit_images(fit_scratch *s, const fit_problem *p) {
  size_t images = p->groups.images ? p->groups.images : 1;
  if (images <= s->images) return 1;
  free(s->log_e);
  free(s->log_b);
  s->log_e = malloc(images * sizeof *s->log_e);
  s->log_b = malloc(3 * images * sizeof *s->log_b);
  s->images = s->log_e && s->log_b ? images : 0;
  return s->images != 0;
}

/* Room for the Jacobian's arrays: gradients and the block's columns. */
static int fit_jacobian(fit_scratch *s, const fit_problem *p, size_t pairs) {
  size_t columns = (size_t)p->unknowns.num + 1;
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

int fit_scratch_fit(fit_scratch *s, const fit_problem *p, size_t pairs, int jacobian) {
  pairs = pairs ? pairs : 1;
  if (!fit_images(s, p)) return 0;
  if (pairs > s->pairs) {
    free(s->f);
    s->f = malloc(6 * pairs * sizeof *s->f); /* (then light_w) */
    s->pairs = s->f ? pairs : 0;
    if (!s->f) return 0;
    s->light_w = s->f + 3 * pairs;
  }
  if (!fit_lights(s, p)) return 0;
  return !jacobian || fit_jacobian(s, p, pairs);
}

fit_scratch *fit_scratch_take(const fit_problem *p) {
  const fit_scratch_pool *pool = &p->scratch;
  for (int i = 0; i < pool->count; ++i) {
    int expected = 0;
    if (atomic_compare_exchange_strong(&pool->scratch[i].taken, &expected, 1))
      return &pool->scratch[i];
  }
  fit_scratch *own = calloc(1, sizeof *own);
  if (own) own->own = 1;
  return own;
}

void fit_scratch_give(fit_scratch *s) {
  if (!s) return;
  if (!s->own) {
    atomic_store(&s->taken, 0);
    return;
  }
  free_arrays(s);
  free(s);
}

int fit_scratch_pool_make(fit_scratch_pool *pool) {
  if (pool->scratch) return 1;
  pool->scratch = calloc(SCRATCH_POOL, sizeof *pool->scratch);
  if (!pool->scratch) return 0;
  for (int i = 0; i < SCRATCH_POOL; ++i) atomic_init(&pool->scratch[i].taken, 0);
  pool->count = SCRATCH_POOL;
  return 1;
}

void fit_scratch_pool_free(fit_scratch_pool *pool) {
  for (int i = 0; i < pool->count; ++i) free_arrays(&pool->scratch[i]);
  free(pool->scratch);
  pool->scratch = NULL;
  pool->count = 0;
}
