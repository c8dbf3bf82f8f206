/* The evaluations' working memory (problem.h): fit_problem_evaluate runs
 * on the solver's threads, several blocks at once (never one block twice
 * at once), hundreds of times a solve, so its memory comes from a pool
 * that fit_problem_finish makes, not from malloc. An evaluation takes a
 * free buffer (an atomic flag), grows it if the problem has outgrown it
 * (the pixel footprints add pairs after fit_problem_finish) and gives it
 * back; when every buffer of the pool is taken it makes one of its own.
 * For src/fit/problem/ alone. */
#ifndef CLAYFIT_FIT_PROBLEM_SCRATCH_H
#define CLAYFIT_FIT_PROBLEM_SCRATCH_H

#include <stdatomic.h>

#include "problem.h"

struct fit_scratch {
  atomic_int taken;
  int own;                                       /* not the pool's: freed after use */
  size_t pairs, jacobian_pairs, columns, images; /* what the arrays have room for */
  double *f;                                     /* 3 × pairs: the model's values */
  double *grad;                                  /* 3 × dim × jacobian_pairs: their gradients */
  int *place;        /* columns: each unknown's place among the block's */
  int *gain_column;  /* 3 × columns: where each channel's log gain goes */
  double *gain_sign; /* 3 × columns */
  double *log_e;     /* images: the exposures at x */
  double *log_b;     /* 3 × images: the white balance at x */
  /* the lights' gains inside the sums (fit_groups.slot_light): */
  double *light_w;   /* 3 × pairs: the pairs' weights times their light's gain (f's allocation) */
  size_t light_room; /* light_d's and light_i's parts have room for this many */
  double *light_d, *log_g, *minus, *slot_gain; /* log g per light; −1s; each slot's g */
  int *light_i, *light_place, *last_places, *slot_entry, *entry_light;
  /* each light's place in the block (−1: none); the places of every
   * light's but the last's (its log gain is minus their sum); the image's
   * slots' entries among its lights, and each entry's light */
};

/* A free scratch of the pool, or one of its own (NULL: no memory). */
fit_scratch *fit_scratch_take(const fit_problem *p);
void fit_scratch_give(fit_scratch *s);

/* Room in the scratch for an evaluation of `pairs` pairs, with the
 * Jacobian or not (the arrays' contents are not kept). 0: no memory. */
int fit_scratch_fit(fit_scratch *s, const fit_problem *p, size_t pairs, int jacobian);

#endif /* CLAYFIT_FIT_PROBLEM_SCRATCH_H */
