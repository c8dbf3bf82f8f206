// The residual blocks as Ceres sees them (lsq_blocks.cpp): each block of
// the C problem compressed to k + 1 residuals from its normal equations
// (lsq.h), its last evaluations kept, and passes over every block on the
// solve's threads. Private to src/lsq.
#ifndef CLAYFIT_LSQ_BLOCKS_H
#define CLAYFIT_LSQ_BLOCKS_H

#include <ceres/cost_function.h>

#include <algorithm>
#include <cstddef>
#include <vector>

#include "core/parallel.h"
#include "lsq/lsq.h"

namespace lsq {

// One evaluation of a block: x, its cost and, when `normal`, its normal
// equations over the block's k columns.
struct BlockEvaluation {
  bool valid = false, normal = false;
  int uses = 0;             // requests it served after its own
  unsigned long stamp = 0;  // the cache's clock at its last use
  std::vector<double> x, jtj, jtu;
  double cost = 0.0;
};

// The last two evaluations of one block. One solve keeps one cache per
// block across its chunks, so that a chunk's first Jacobian, the Newton
// test of the bounds and a Jacobian after a cost at the same point are not
// evaluated again. Two, because Ceres evaluates a candidate before it
// decides on it: a solve that ends on the function tolerance ends where it
// was before its last candidate (one pass at the end of every such solve,
// measured, with one). A new evaluation replaces one that served nothing
// after its own (a rejected candidate), else the one used least recently.
// Ceres evaluates a block from one thread at a time. (Without the cache the
// 16-image capture's fit on the default budget took 1.20x the wall time;
// docs/solver.md, "evaluation cache".)
struct BlockCache {
  BlockEvaluation slot[2];
  unsigned long clock = 0;
  // new points Ceres asked the cost at since its last Jacobian (BlockCost)
  int trials = 0;
  bool failed = false;  // an evaluation returned CF_LSQ_FAILED

  // The block at `point`, from the cache or evaluated into it (the normal
  // equations too when `want_normal`); nullptr when it cannot be
  // evaluated.
  const BlockEvaluation *at(const cf_lsq_problem *problem, size_t block, int k, const double *point,
                            bool want_normal) {
    const int n = problem->num_params;
    ++clock;
    for (BlockEvaluation &e : slot)
      if (e.valid && (e.normal || !want_normal) && std::equal(point, point + n, e.x.begin())) {
        ++e.uses;
        e.stamp = clock;
        return &e;
      }
    BlockEvaluation &e = replaced();
    e.valid = false;
    if (want_normal) {
      e.jtj.resize(static_cast<size_t>(k) * k);
      e.jtu.resize(k);
    }
    const int result = problem->evaluate(problem->user, point, block, &e.cost,
                                         want_normal ? e.jtj.data() : nullptr,
                                         want_normal ? e.jtu.data() : nullptr);
    if (result != CF_LSQ_EVALUATED) {
      failed |= result == CF_LSQ_FAILED;
      return nullptr;
    }
    e.x.assign(point, point + n);
    e.normal = want_normal;
    e.valid = true;
    e.uses = 0;
    e.stamp = clock;
    return &e;
  }

  void clear() {
    slot[0].valid = slot[1].valid = false;
  }

 private:
  BlockEvaluation &replaced() {
    for (BlockEvaluation &e : slot)
      if (!e.valid) return e;
    const bool idle0 = slot[0].uses == 0, idle1 = slot[1].uses == 0;
    if (idle0 != idle1) return idle0 ? slot[0] : slot[1];
    return slot[0].stamp <= slot[1].stamp ? slot[0] : slot[1];
  }
};

// Block `block` of the problem as a ceres::CostFunction over all
// num_params parameters, its evaluations through `cache`.
ceres::CostFunction *new_block_cost(const cf_lsq_problem *problem, size_t block, BlockCache *cache);

// f(t) for t = 0 … count − 1, side by side on count threads
// (cf_parallel_for). False when an f(t) returned false or threw.
template <class F>
bool in_threads(size_t count, F f) {
  struct Job {
    F *f;
    std::vector<char> ok;
  } job{&f, std::vector<char>(count, 1)};
  cf_parallel_for(
      static_cast<int>(count), static_cast<int>(count),
      [](void *user, int t) {
        Job *j = static_cast<Job *>(user);
        try {
          j->ok[t] = (*j->f)(static_cast<size_t>(t));
        } catch (...) {
          j->ok[t] = 0;
        }
      },
      &job);
  return std::all_of(job.ok.begin(), job.ok.end(), [](char o) { return o != 0; });
}

// cf_lsq_normal_equations, from the blocks' caches where they hold x
// (caches: one per block, or nullptr).
int normal_equations(const cf_lsq_problem *problem, int threads, std::vector<BlockCache> *caches,
                     double *jtj, double *jtu, double *cost);

// The total cost at x (NaN when a block cannot be evaluated there), the
// blocks shared among `threads` threads.
double cost_at(const cf_lsq_problem *problem, const double *x, int threads);

// One line of the solve's trace (cf_lsq_options.trace), printf-style.
void trace(const cf_lsq_options *options, const char *format, ...)
    __attribute__((format(printf, 2, 3)));

}  // namespace lsq

#endif  // CLAYFIT_LSQ_BLOCKS_H
