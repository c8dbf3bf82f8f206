/* The parts of the fit's least-squares problem (fit_problem.h), for the
 * files of src/fit/problem/ alone (and white-box tests):
 *   fit_rows.c      the observations used: measurements, pairs, σ, weights
 *   fit_groups.c    the capture's images and lights as the gains group them
 *   fit_noise.c     what a residual weighs and costs: σ from the noise model
 *                   (through the curve), the robust loss (fit_loss.h), censoring
 *   fit_unknowns.c  what x holds: the unknowns, their runs, the blocks' columns
 *   fit_kind_*.c    one kind of unknown each (kind.h)
 *   fit_scratch.c   the evaluations' working memory
 *   fit_kernel.c    a block's cost and normal equations; group scores
 *   fit_predict.c   the prediction of every observation
 *   fit_solve.c     the solves through lsq.h
 *   fit_footprint.c pixel footprints: each observation's pairs over its pixel
 *   fit_problem.c   the problem as a whole: made, forked, freed; what the
 *                   stages read of it and set on it (fit_problem.h) */
#ifndef CLAYFIT_FIT_PROBLEM_PARTS_H
#define CLAYFIT_FIT_PROBLEM_PARTS_H

#include "fit_problem.h"
#include "kind.h"

/* ---- the observations used (fit_rows.c) ---- */
typedef struct fit_rows {
  size_t count;          /* observations used (all, or a subsample) */
  const uint32_t *index; /* the observations used (NULL: all, in order) */
  /* their measurements, images and clip flags, copied in the problem's
   * order: the solver reads them at every evaluation, and a subsample's
   * index jumps through the capture's arrays (a cache miss per
   * observation: 70 % of a subsample's evaluation time, measured) */
  double *y;       /* 3 × count */
  uint32_t *image; /* count */
  uint8_t *flags;  /* count */
  /* the (observation, light) pairs: observation i's are the slots
   * [slot_begin[i], slot_begin[i + 1]), or, with slot_begin NULL, the
   * `lights` slots from i × lights. An observation integrated over its
   * pixel's footprint has S² × lights slots, one per sample and light,
   * each weighted 1/S². */
  int lights;
  size_t *slot_begin;    /* count + 1, or NULL */
  size_t slots;          /* in all */
  cf_geometry *geometry; /* slots */
  double *weight;        /* slots × 3: E_c c_i (0 when unlit), over S² */
  int *samples;          /* count: S of each observation, or NULL (all 1) */
  /* what the footprints measure once (fit_footprint.c; they do not depend
   * on the parameters): per image a bound on the normal's turn across a
   * pixel, and per observation its turn (NaN until measured); NULL before */
  double *turn_bound, *pixel_turn;
  double *inv_sigma;   /* count × 3; from the noise model, or 1/σ */
  double *sample_root; /* count: √(sample weight), or NULL (all 1) */
  double sigma;        /* one σ for all (no noise model), else 0 */
} fit_rows;

/* The rows of `count` observations (index: which; NULL: all) with their
 * pairs' geometry at the pixel centres, built on `threads` threads. */
cf_status fit_rows_init(fit_rows *rows, const cf_observations *obs, const uint32_t *index,
                        size_t count, int threads, cf_error *err);
void fit_rows_release(fit_rows *rows);

/* Observation i's index among the capture's. */
static inline size_t fit_rows_observation(const fit_rows *rows, size_t i) {
  return rows->index ? rows->index[i] : i;
}

/* The slots of observation i (of those used): *first and the count. */
static inline size_t fit_rows_slot_range(const fit_rows *rows, size_t i, size_t *first) {
  if (!rows->slot_begin) {
    *first = i * (size_t)rows->lights;
    return (size_t)rows->lights;
  }
  *first = rows->slot_begin[i];
  return rows->slot_begin[i + 1] - rows->slot_begin[i];
}

/* The pairs of one surface point with each of `lights` lights: their
 * geometry and weights scale · E_c c_i (0 where unlit), into geometry
 * (lights) and weight (3 × lights). */
void fit_pairs_at(int lights, const double n[3], const double v[3], const double *light_dir,
                  const double *irradiance, double scale, cf_geometry *geometry, double *weight);

/* ---- the capture's images and lights (fit_groups.c) ---- */
cf_status fit_groups_init(fit_groups *groups, const cf_capture *capture, int lights,
                          cf_error *err);
void fit_groups_release(fit_groups *groups);

/* ---- the unknowns declared (fit_unknowns.c) ---- */

/* A run of unknowns of one kind: x[first .. first + count). A kind's
 * unknowns are declared together, so each kind has one run at most. */
struct fit_run {
  const fit_kind *kind;
  int first, count;
};

enum { FIT_MAX_RUNS = 8 }; /* above the 6 kinds of unknown (fit_problem.h): a derivation */

typedef struct fit_unknowns {
  /* num of them, in arrays that grow as unknowns are declared (capacity) */
  int num, capacity;
  fit_unknown *unknown;
  double *lower, *upper;
  int *at_bound; /* after a solve (fit_problem_at_bound) */
  int failed;    /* a declaration found no memory (fit_problem_finish says so) */
  fit_run run[FIT_MAX_RUNS];
  int runs;
} fit_unknowns;

/* Declare one unknown of `kind` (after those declared, in the kind's
 * run) with its bounds. */
void fit_unknowns_add(fit_problem *p, const fit_kind *kind, int slot, double lo, double hi);
void fit_unknowns_release(fit_unknowns *u);
/* The run of `kind` (NULL: none declared). */
const fit_run *fit_unknowns_run(const fit_unknowns *u, const fit_kind *kind);
/* The values x stands for, into v (which holds the values of what is not
 * free), kind by kind. */
void fit_unknowns_values_at(const fit_problem *p, const double *x, fit_values *v);

/* The residual blocks: `size` observations each (FIT_BLOCK_SIZE; the
 * blocks are the solver's units of work on its threads and of its
 * compressed normal equations, lsq.h); block b's columns
 * (the unknowns its Jacobian can be nonzero in, ascending) are
 * column[column_begin[b] ... column_begin[b + 1]). */
enum { FIT_BLOCK_SIZE = 1024 }; /* fd063f4: threads' and cache's unit; time not measured (study) */
typedef struct fit_blocks {
  size_t size, count;
  size_t *column_begin;
  int *column;
} fit_blocks;

/* ---- the evaluations' working memory (fit_scratch.c) ---- */
typedef struct fit_scratch fit_scratch;
typedef struct fit_scratch_pool {
  fit_scratch *scratch;
  int count;
} fit_scratch_pool;

/* ---- the problem ---- */
struct fit_problem {
  const cf_capture *capture;
  const cf_observations *obs;
  cf_model_id model;
  int dim;
  /* threads for work over every observation (predictions, footprints;
   * fit_problem_new's: a problem solved beside others keeps to one) */
  int threads;
  fit_rows rows;
  fit_groups groups;
  fit_values values;
  /* what the values switch on: R applies (it is free, or not the
   * identity); the lights' gains apply (they are free, or not all 1) */
  int response_on, light_gains_on;
  fit_unknowns unknowns;
  fit_blocks blocks;
  cf_loss loss;
  double loss_scale; /* in σ */
  fit_solve_settings settings;
  /* the trust region the last solve ended with, where the next starts
   * (lsq.h); 0 (Ceres' initial one) before the first solve and after
   * every declaration */
  double radius;
  fit_tally tally;
  fit_scratch_pool scratch;
  /* a fork's origin, whose rows, groups, unknowns' declaration, blocks
   * and scratch it shares (fit_problem_fork); NULL: owns them */
  const fit_problem *origin;
};

/* The values' arrays for the problem's images and lights (zeroed). */
cf_status fit_values_alloc(fit_values *v, size_t images, size_t lights, cf_error *err);

/* ---- scratch (fit_scratch.c) ---- */

/* The pool (fit_problem_finish), once per problem; and freed. */
int fit_scratch_pool_make(fit_scratch_pool *pool);
void fit_scratch_pool_free(fit_scratch_pool *pool);

#endif /* CLAYFIT_FIT_PROBLEM_PARTS_H */
