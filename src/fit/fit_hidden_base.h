/* M4's base when the photos do not show it (a film so absorbing that the
 * clay under it is hidden): a likelihood-ratio test of the base against
 * the film alone, so that a base the data cannot see is reported as not
 * constrained instead of as a faint lobe that fits the noise. Private to
 * src/fit. */
#ifndef CLAYFIT_FIT_HIDDEN_BASE_H
#define CLAYFIT_FIT_HIDDEN_BASE_H

#include "clayfit/fit.h"
#include "fit_plan.h"
#include "fit_problem.h"

/* The outcome of the test. */
typedef struct fit_hidden_base {
  int tested;     /* 0: not M4, no free base slot, or the base plainly
                     visible (skipped) */
  int hidden;     /* the film alone explains the photos: adopted */
  int slots;      /* k: the base's free slots */
  double gain;    /* χ²(film alone) − χ²(with the base), at the same σ */
  double price;   /* k ln n, BIC's price of those slots */
  double visible; /* χ² of the base's whole contribution at the fit */
} fit_hidden_base;

/* For M4 with free base slots (albedo, σ, τ, r2, F0_2), after a solve
 * whose final cost is `cost` (½ χ² at the problem's current σ):
 *   1. the base's whole contribution at the fit, χ² of the model minus its
 *      top specular alone (the reduction of docs/model.md §4.5 at τ >= 400); above 100 per
 *      residual the film alone cannot explain the photos: skipped;
 *   2. else the film alone is fitted (τ held at its upper bound, where the
 *      film hides the base; the base's other slots held at their defaults)
 *      and compared by BIC: when its χ² is higher by less than k ln n, the
 *      base is not seen: the plan marks the base's slots not constrained
 *      and the problem keeps the film-alone solution (declared by the
 *      plan). Otherwise the problem is restored as it was (re-declared).
 * *out says what happened. */
cf_status fit_test_hidden_base(fit_problem *p, fit_plan *plan, const cf_fit_options *o, double cost,
                               fit_hidden_base *out, cf_error *err);

#endif /* CLAYFIT_FIT_HIDDEN_BASE_H */
