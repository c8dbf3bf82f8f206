/* The lights' gains inside each image's sum over its lights (kind.h;
 * --fit-gains per-light where an image has several lights): the
 * prediction is R(s e_k Σ_j g_l(j) f E_j c_j). Their mean log over the
 * lights is 0: the last light's is minus the sum of the others'. The
 * kernel takes their derivative per light of the row's image
 * (fit_kernel.c, FIT_HANDLE_LIGHT). */
#include <math.h>

#include "problem.h"

void fit_problem_free_light_gains(fit_problem *p) {
  for (size_t l = 0; l + 1 < p->groups.light_count; ++l) /* (contiguous, in the lights' order) */
    fit_unknowns_add(p, &fit_kind_light, (int)l, -HUGE_VAL, HUGE_VAL);
  p->light_gains_on = p->groups.light_count > 1;
}

static double get(const fit_problem *p, const fit_values *v, int slot) {
  (void)p;
  return v->log_light[slot];
}

static void set(const fit_problem *p, const double *x, const fit_unknown *u, int count,
                fit_values *v) {
  (void)u, (void)count;
  double sum = 0.0;
  for (size_t l = 0; l + 1 < p->groups.light_count; ++l) sum += v->log_light[l] = x[l];
  v->log_light[p->groups.light_count - 1] = -sum;
}

const fit_kind fit_kind_light = {
    .name = "light gain", .handle = FIT_HANDLE_LIGHT, .get = get, .set = set};
