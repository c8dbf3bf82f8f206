/* clayfit's side of the peers benchmark (clayfit-peers): the common
 * problem solved through the fit's own C path (fit_problem.h over lsq.h),
 * the C evaluator's predictions for checking the peers' models and costs,
 * and the evaluator floor. Private to bench/peers. */
#ifndef CLAYFIT_BENCH_PEERS_CLAYFIT_H
#define CLAYFIT_BENCH_PEERS_CLAYFIT_H

#include <stddef.h>
#include <stdint.h>

#include "clayfit/capture.h"
#include "clayfit/model.h"
#include "clayfit/status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct peers_clayfit_result {
  double params[CF_MAX_DIM]; /* the solution */
  double cost;               /* ½ Σ r² (the solver's) */
  int iterations;            /* Levenberg-Marquardt iterations (lsq.h) */
  double seconds;            /* wall: problem set-up and solve */
  double solve_seconds;      /* wall: the solve alone */
  char termination[64];
  double pass_seconds;        /* one cf_eval_batch pass, value + gradient, over
                                 every (observation, light) pair (the best of
                                 several) */
  size_t pairs;               /* those pairs */
  double normal_pass_seconds; /* one pass of the fit's callback (lsq.h)
                                 over every block, value and normal
                                 equations JᵀJ, Jᵀr, on one thread (the
                                 best of several): the evaluator and the
                                 sums the solver needs */
} peers_clayfit_result;

/* Solve the common problem: the `count` observations of index, unweighted
 * least squares on linear RGB (no loss, σ = 1, no censoring, scale and
 * exposures held at 1), every model slot free within docs/model.md §1.6's bounds,
 * Levenberg-Marquardt from start (cf_lsq_default_options' tolerances). */
cf_status peers_clayfit_run(const cf_capture *capture, cf_model_id model, const uint32_t *index,
                            size_t count, const double *start, int threads, int max_iterations,
                            peers_clayfit_result *result, cf_error *err);

/* The C evaluator's prediction Σ_j f E_j c_i,j and the measurement of the
 * `count` observations of index at params: 3 × count each. */
cf_status peers_predict(const cf_capture *capture, cf_model_id model, const uint32_t *index,
                        size_t count, const double *params, double *prediction, double *measured,
                        cf_error *err);

/* Wall-clock seconds (monotonic). */
double peers_now(void);

#ifdef __cplusplus
}
#endif

#endif /* CLAYFIT_BENCH_PEERS_CLAYFIT_H */
