/* A kind of unknown of the fit (fit_problem.h): what the solver's x holds
 * for it, where its values live (fit_values), which residual blocks
 * depend on it, and which derivative of the prediction it takes. One file
 * each:
 *   fit_kind_material.c  the model's slots (plain, log ρ, σ²)
 *   fit_kind_gains.c     the scale, the exposures, the white balance
 *   fit_kind_light.c     the lights' gains inside each image's sum
 *   fit_kind_response.c  the response curve's slopes
 * A new kind (the sphere, light directions, the floor, texels) is a new
 * file: its struct fit_kind, its fit_problem_free_* declaration, its
 * values in fit_values, and, when its derivative is not one of the
 * handles below, that derivative in the kernel (fit_kernel.c).
 * For src/fit/problem/ alone. */
#ifndef CLAYFIT_FIT_PROBLEM_KIND_H
#define CLAYFIT_FIT_PROBLEM_KIND_H

#include <stddef.h>
#include <stdint.h>

#include "fit_problem.h"

typedef struct fit_run fit_run;

/* The derivative of a channel's prediction μ that a kind's unknowns take
 * (the kernel computes each once per row, fit_kernel.c): */
typedef enum fit_handle {
  FIT_HANDLE_MODEL, /* ∂μ/∂ params[slot], times the kind's chain factor */
  FIT_HANDLE_GAIN,  /* ∂μ/∂ log(the gain of the row's image and channel) */
  FIT_HANDLE_SLOPE, /* ∂μ/∂ a_slot, the response's slope at knot slot */
  FIT_HANDLE_LIGHT  /* ∂μ/∂ log g_l of each light in the row's image's sum */
} fit_handle;

struct fit_kind {
  const char *name;
  fit_handle handle;
  /* x of the unknown `slot` from the values v */
  double (*get)(const fit_problem *p, const fit_values *v, int slot);
  /* the values x stands for: the kind's run of `count` unknowns, slots
   * u[0 .. count), is x[0 .. count); into v, which holds the values of
   * everything else */
  void (*set)(const fit_problem *p, const double *x, const fit_unknown *u, int count,
              fit_values *v);
  /* the block's columns: which of the run's unknowns (first .. + count)
   * rows [begin, end) depend on, appended to column (ascending); returns
   * how many. `mark` has room for a byte per image, all 0 (left so).
   * NULL: every one, in every block */
  int (*columns)(const fit_problem *p, size_t begin, size_t end, int first, int count,
                 unsigned char *mark, int *column);
  /* FIT_HANDLE_MODEL: d params[slot] / d x at the values v (NULL: 1),
   * params[slot] first moved where the evaluation takes it, if anywhere */
  double (*chain)(const fit_problem *p, fit_values *v, int slot);
  /* FIT_HANDLE_GAIN: the columns through which the run's unknowns take
   * the derivative in the log gain of image `image`'s channel c:
   * place[u] is unknown u's column in the block (−1: not in it); each
   * target's column and sign (the last group's or image's gain is minus
   * the others') appended at column/sign; returns how many */
  int (*gain_targets)(const fit_problem *p, const fit_run *run, const int *place, uint32_t image,
                      int c, int *column, double *sign);
};

#endif /* CLAYFIT_FIT_PROBLEM_KIND_H */
