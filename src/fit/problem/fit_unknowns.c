/* What the solver's x holds: the unknowns declared, kind by kind, their
 * bounds, x to and from the values, and the residual blocks' columns
 * (problem.h, fit_unknowns). */
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "problem.h"

void fit_problem_clear_unknowns(fit_problem *p) {
  fit_unknowns *u = &p->unknowns;
  u->num = 0;
  u->failed = 0;
  u->runs = 0;
  p->radius = 0.0; /* other unknowns, another minimum: Ceres' initial trust region */
  p->response_on = !fit_response_is_identity(p->values.response);
  p->light_gains_on = 0;
  for (size_t l = 0; l < p->groups.light_count; ++l) p->light_gains_on |= p->values.log_light[l] != 0.0;
}

/* Room for `capacity` unknowns in the unknowns' arrays (kept as they are). */
static int grow(fit_unknowns *u, int capacity) {
  size_t n = (size_t)capacity;
  fit_unknown *unknown = realloc(u->unknown, n * sizeof *unknown);
  if (unknown) u->unknown = unknown;
  double *lower = realloc(u->lower, n * sizeof *lower);
  if (lower) u->lower = lower;
  double *upper = realloc(u->upper, n * sizeof *upper);
  if (upper) u->upper = upper;
  int *at_bound = realloc(u->at_bound, n * sizeof *at_bound);
  if (at_bound) u->at_bound = at_bound;
  if (!unknown || !lower || !upper || !at_bound) return 0;
  u->capacity = capacity;
  return 1;
}

/* The run that unknown `i` of `kind` joins: the last one when it is the
 * kind's, else a new one (NULL: no room, or the kind's run is over). */
static fit_run *run_for(fit_unknowns *u, const fit_kind *kind, int i) {
  if (u->runs > 0 && u->run[u->runs - 1].kind == kind) return &u->run[u->runs - 1];
  if (u->runs == FIT_MAX_RUNS || fit_unknowns_run(u, kind)) return NULL;
  u->run[u->runs] = (fit_run){kind, i, 0};
  return &u->run[u->runs++];
}

void fit_unknowns_add(fit_problem *p, const fit_kind *kind, int slot, double lo, double hi) {
  fit_unknowns *u = &p->unknowns;
  if (u->failed) return;
  if (u->num == u->capacity && (u->num > INT_MAX / 2 - 16 || !grow(u, 2 * u->num + 16))) {
    u->failed = 1; /* fit_problem_finish reports it */
    return;
  }
  fit_run *run = run_for(u, kind, u->num);
  if (!run) {
    u->failed = 1;
    return;
  }
  ++run->count;
  int i = u->num++;
  u->unknown[i] = (fit_unknown){kind, slot};
  u->lower[i] = lo;
  u->upper[i] = hi;
  u->at_bound[i] = 0;
}

void fit_unknowns_release(fit_unknowns *u) {
  free(u->unknown);
  free(u->lower);
  free(u->upper);
  free(u->at_bound);
  memset(u, 0, sizeof *u);
}

const fit_run *fit_unknowns_run(const fit_unknowns *u, const fit_kind *kind) {
  for (int r = 0; r < u->runs; ++r)
    if (u->run[r].kind == kind) return &u->run[r];
  return NULL;
}

/* Block b's columns, kind by kind, at column (room for every unknown);
 * returns how many. */
static int block_columns(const fit_problem *p, size_t b, unsigned char *mark, int *column) {
  const fit_unknowns *u = &p->unknowns;
  size_t begin = b * p->blocks.size;
  size_t end = p->rows.count - begin < p->blocks.size ? p->rows.count : begin + p->blocks.size;
  int k = 0;
  for (int r = 0; r < u->runs; ++r) {
    const fit_run *run = &u->run[r];
    if (run->kind->columns) {
      k += run->kind->columns(p, begin, end, run->first, run->count, mark, column + k);
      continue;
    }
    for (int i = 0; i < run->count; ++i) column[k++] = run->first + i;
  }
  return k;
}

/* The blocks and their columns, the kinds' columns in each. */
static int make_blocks(fit_problem *p) {
  fit_blocks *b = &p->blocks;
  int n = p->unknowns.num;
  b->count = (p->rows.count + b->size - 1) / b->size;
  free(b->column_begin);
  free(b->column);
  b->column = NULL;
  b->column_begin = malloc((b->count + 1) * sizeof *b->column_begin);
  unsigned char *mark = calloc(p->groups.images ? p->groups.images : 1, 1);
  size_t capacity = 0;
  int ok = b->column_begin && mark;
  if (ok) b->column_begin[0] = 0;
  for (size_t block = 0; ok && block < b->count; ++block) {
    size_t k = b->column_begin[block];
    if (k + (size_t)n + 1 > capacity) { /* room for this block's */
      capacity = 2 * (k + (size_t)n + 1);
      int *grown = realloc(b->column, capacity * sizeof *grown);
      if (!grown) {
        ok = 0;
        break;
      }
      b->column = grown;
    }
    b->column_begin[block + 1] = k + (size_t)block_columns(p, block, mark, b->column + k);
  }
  free(mark);
  return ok;
}

cf_status fit_problem_finish(fit_problem *p, cf_error *err) {
  if (p->unknowns.failed)
    return cf_error_set(err, CF_ENOMEM, "out of memory for the fit's unknowns (%d and more)",
                        p->unknowns.num);
  if (!make_blocks(p) || !fit_scratch_pool_make(&p->scratch))
    return cf_error_set(err, CF_ENOMEM, "out of memory for the residual blocks");
  return CF_OK;
}

void fit_problem_get_x(const fit_problem *p, double *x) {
  const fit_unknowns *u = &p->unknowns;
  for (int i = 0; i < u->num; ++i) x[i] = u->unknown[i].kind->get(p, &p->values, u->unknown[i].slot);
}

void fit_unknowns_values_at(const fit_problem *p, const double *x, fit_values *v) {
  const fit_unknowns *u = &p->unknowns;
  for (int r = 0; r < u->runs; ++r) {
    const fit_run *run = &u->run[r];
    run->kind->set(p, x + run->first, u->unknown + run->first, run->count, v);
  }
}

void fit_problem_set_x(fit_problem *p, const double *x) {
  fit_unknowns_values_at(p, x, &p->values); /* (the arrays in place) */
}

