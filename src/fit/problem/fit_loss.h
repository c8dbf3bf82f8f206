/* What a residual costs (fit_problem.h): the robust loss, inline for the
 * kernel's rows. For src/fit/problem/ alone. */
#ifndef CLAYFIT_FIT_PROBLEM_LOSS_H
#define CLAYFIT_FIT_PROBLEM_LOSS_H

#include <math.h>

#include "problem.h"

/* ρ(s) of s = r² in units of σ (Huber, Cauchy, or s itself), and ρ'(s).
 * The solver's model of a residual is the reweighted one, √ρ' r with the
 * Jacobian √ρ' ∂r (iteratively reweighted least squares: its gradient is
 * that of ½ ρ, its Gauss-Newton matrix Σ ρ' JᵀJ), while the cost is ½ ρ
 * itself (lsq.h). Ceres' LossFunction would do the same per residual
 * block, but a block here holds a thousand observations. */
static inline double fit_robust(const fit_problem *p, double s, double *rho1) {
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

/* Is channel c of used observation `row` censored (fit_problem_censored)? */
static inline int fit_censored_at(const fit_problem *p, size_t row, int c, double prediction,
                                  double measured) {
  return (p->rows.flags[row] >> c & 1u) && prediction >= measured;
}

#endif /* CLAYFIT_FIT_PROBLEM_LOSS_H */
