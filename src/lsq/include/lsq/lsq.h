/* Bounded non-linear least squares through Ceres (lsq_ceres.cpp), behind a
 * C interface: the fit layer describes a problem of one parameter vector
 * and many residual blocks, each evaluated by a C callback, and gets back
 * the minimiser, Ceres' summary and, on request, the covariance
 * (ceres::Covariance). This is the only place that includes Ceres. Private
 * to the layers above src/lsq (capture's sphere fit, fit). */
#ifndef CLAYFIT_LSQ_LSQ_H
#define CLAYFIT_LSQ_LSQ_H

#include <stddef.h>

#include "clayfit/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Residual block `block` at parameters x: its cost (always) and, when jtj
 * is not NULL, the normal equations of its Gauss-Newton model over the
 * block's k columns (block_columns, in that order): jtj = JᵀJ (k × k,
 * row-major, symmetric) and jtu = Jᵀu (k), where u are the model's
 * residuals and J their Jacobian. Without a robust loss u is the residual
 * vector and cost = ½|u|²; with one, u = √ρ' r and cost = ½ Σ ρ(r²) (the
 * reweighted model, whose curvature is right in the loss's tails, where
 * √ρ-transformed residuals would halve it); either way |u|² <= 2 cost.
 * The callback accumulates JᵀJ as it evaluates, over each residual's
 * nonzero entries only, and never forms J: that is the whole price of a
 * Jacobian beyond the model's own gradient. Returns CF_LSQ_EVALUATED, or
 * CF_LSQ_NOT_FINITE when the block is not finite there (the solver then
 * rejects the step), or CF_LSQ_FAILED when it could not be computed at
 * all (out of memory: the solve ends with CF_ENOMEM). Called from several
 * threads at once, never for the same block at the same time. */
enum { CF_LSQ_FAILED = -1, CF_LSQ_NOT_FINITE = 0, CF_LSQ_EVALUATED = 1 };
typedef int (*cf_lsq_evaluate)(void *user, const double *x, size_t block, double *cost, double *jtj,
                               double *jtu);

typedef struct cf_lsq_problem {
  int num_params;
  double *x;                   /* in: the start; out: the solution */
  const double *lower, *upper; /* per parameter; ±HUGE_VAL for none */
  size_t num_blocks;
  cf_lsq_evaluate evaluate;
  /* the columns (parameters) block `block`'s Jacobian can be nonzero in
   * (structurally, at any x), ascending: *columns points to them (owned
   * by the caller); returns their number */
  int (*block_columns)(void *user, size_t block, const int **columns);
  void *user;
  /* out (num_params, optional): −1 or +1 for a parameter that ends at its
   * lower or upper bound with the cost's gradient pointing out of the box
   * (a constrained minimum: the data prefer a value at or beyond it), 0
   * otherwise */
  int *at_bound;
} cf_lsq_problem;

typedef struct cf_lsq_options {
  int max_iterations;
  int threads;
  double function_tolerance, gradient_tolerance, parameter_tolerance;
  /* a step is taken when it lowers the cost by at least this fraction of
   * the decrease its quadratic model predicts (Ceres'
   * min_relative_decrease, 1e-3); below, the trust region shrinks faster */
  double min_relative_decrease;
  /* a line search that lowers the cost by less than this is not worth
   * another solve (the fit's costs are in units of σ²: 1e-3 is a change
   * of χ² by 0.002) */
  double line_search_tolerance;
  /* the Levenberg-Marquardt trust region to start from (Ceres' 1e4 by
   * default): a solve near where another ended starts from its final
   * radius, not damping the ill-conditioned directions all over again */
  double initial_radius;
  /* nonzero for a solve that may start near a minimum (a refinement of
   * an earlier solve's end): when the Gauss-Newton step from the start
   * predicts a decrease below 10 (in the cost's units), a parameter it
   * takes beyond a bound by more than its distance inside starts pinned
   * there, and the Newton test at the end of the solve frees it when its
   * minimum is inside (default 0: no such pins) */
  int newton_start;
  /* optional: called after every successful iteration with x and the
   * cost; nonzero ends the solve there (a multi-start's start that has
   * reached another's minimum) */
  int (*stop)(void *user, const double *x, double cost);
  void *stop_user;
  /* optional (num_params², row-major): the normal equations JᵀJ over
   * every parameter at the solution, from the evaluations the solve kept
   * (one pass less than cf_lsq_normal_equations after it; the summary's
   * final_normal says they were written) */
  double *final_jtj;
  /* optional: called with one line of text for every iteration of Ceres
   * and every decision of the solve around it (to study convergence;
   * clayfit fit --trace) */
  void (*trace)(void *user, const char *line);
  void *trace_user;
} cf_lsq_options;

void cf_lsq_default_options(cf_lsq_options *options);

enum { CF_LSQ_TRACE = 256 };

/* How a solve ended. */
typedef enum cf_lsq_termination {
  CF_LSQ_END_CONVERGED,         /* a tolerance was met (Ceres' CONVERGENCE) */
  CF_LSQ_END_OUT_OF_ITERATIONS, /* max_iterations reached (NO_CONVERGENCE) */
  CF_LSQ_END_STOPPED,           /* options->stop ended it (USER_SUCCESS) */
  CF_LSQ_END_FAILED             /* the solve failed (FAILURE) */
} cf_lsq_termination;

/* The name fit.json records for a termination: Ceres' own. */
const char *cf_lsq_termination_name(cf_lsq_termination termination);

typedef struct cf_lsq_summary {
  double initial_cost, final_cost; /* ½ Σ r² */
  /* the cost at the start and after every successful iteration (the
   * first CF_LSQ_TRACE) */
  double trace[CF_LSQ_TRACE];
  int trace_count;
  int iterations;
  int converged;             /* Ceres' CONVERGENCE */
  cf_lsq_termination ending; /* cf_lsq_termination_name: fit.json's word */
  double seconds;
  double final_radius; /* the trust region at the end */
  int stopped;         /* options->stop ended it */
  int final_normal;    /* options->final_jtj holds JᵀJ at the solution */
} cf_lsq_summary;

/* Solve (Levenberg-Marquardt, dense normal equations) with an active set
 * for the bounds.
 *
 * Block compression. A block whose model has m residuals u with Jacobian
 * J (m × k in its k nonzero columns) and cost C, given as JᵀJ and Jᵀu by
 * the callback, is handed to Ceres as
 * k + 1 residuals
 *   ρ = (c, d),  c = Λ^(−1/2) Vᵀ Jᵀu,  d = sqrt(2C − |c|²),
 * with the Jacobian (R; 0), R = Λ^(1/2) Vᵀ, where JᵀJ = V Λ Vᵀ. Then
 * ½|ρ|² = C, RᵀR = JᵀJ and Rᵀc = Jᵀu (c is u projected on the range of
 * J, so |c|² <= |u|² <= 2C for Huber and Cauchy): the cost, the gradient
 * and the Gauss-Newton matrix are exactly the block's, so Levenberg-
 * Marquardt takes the same steps, while Ceres holds (k + 1) × n numbers
 * per block instead of m × n (for a million observations, 14 thousand
 * rows instead of 3.6 million). Eigenvalues below 1e-14 of the largest
 * are dropped (a block that does not see a parameter). Evaluations of the
 * cost alone return (0, …, 0, √(2C)). A block whose JᵀJ is nearly
 * singular loses digits in c (the sphere fit with a block per view: the
 * cost off by 1e-11 relative, the solve 5e-8 radii short of the minimum):
 * group the residuals so that each block sees its parameters well.
 *
 * The active set. Ceres clips a step at the box, but its model of the
 * cost change does not see the clipping: once a parameter sits at a bound
 * its gradient pushes against, every step's ratio of actual to predicted
 * decrease is small, the trust region shrinks, and the solver crawls (100
 * iterations that move nothing, measured on an Oren-Nayar σ at 0). So a
 * parameter that starts at a bound, or stays at one for two iterations, is
 * pinned there (held through a ceres::SubsetManifold) and the rest solved
 * again; at the end a pinned parameter whose gradient points back into the
 * box is released and the solve repeated (at most a few rounds).
 *
 * The solve runs in chunks of 8 iterations with a line search along the
 * last step between them where the steps kept more than their model
 * promised. What each of these devices buys, measured, is in
 * docs/solver.md. Returns CF_ENOMEM when a block's evaluation failed
 * (CF_LSQ_FAILED), CF_ENUMERIC when Ceres failed. */
cf_status cf_lsq_solve(cf_lsq_problem *problem, const cf_lsq_options *options,
                       cf_lsq_summary *summary, cf_error *err);

/* The normal equations summed over every block at problem->x (blocks
 * shared among `threads` threads): jtj = JᵀJ (num_params², row-major) and
 * jtu = Jᵀu (num_params; the cost's gradient), either may be NULL, and
 * *cost. Returns what the blocks returned: CF_LSQ_EVALUATED, or
 * CF_LSQ_NOT_FINITE or CF_LSQ_FAILED for the first that did not. */
int cf_lsq_normal_equations(const cf_lsq_problem *problem, int threads, double *jtj, double *jtu,
                            double *cost);

/* How much a Gauss-Newton step from here could still lower the cost: the
 * decrement ½ gᵀ H⁺ g over the parameters not pinned (pinned[i] == 0;
 * pinned may be NULL), H their block of jtj (n², row-major) and H⁺ its
 * pseudo-inverse, eigenvalues below 1e-12 of the largest dropped (a
 * direction no data see). In the cost's units; HUGE_VAL when it cannot be
 * computed. */
double cf_lsq_newton_decrement(int n, const double *jtj, const double *g, const int *pinned);

/* The covariance (JᵀJ)⁻¹ = V Λ⁻¹ Vᵀ (n², row-major) of a least-squares
 * solution from its normal matrix jtj = JᵀJ = V Λ Vᵀ (n², row-major): the
 * covariance depends on J only through JᵀJ, so a solution with millions
 * of residuals costs an n × n eigen-decomposition instead of an SVD of J.
 * *rank_deficient is set (covariance untouched) when JᵀJ is singular to
 * within a reciprocal condition number of 1e-12 (the test
 * ceres::Covariance makes with DENSE_SVD). */
cf_status cf_lsq_covariance(int n, const double *jtj, double *covariance, int *rank_deficient,
                            cf_error *err);

#ifdef __cplusplus
}
#endif

#endif /* CLAYFIT_LSQ_LSQ_H */
