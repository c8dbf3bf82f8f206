// Bounds as an active set (lsq_bounds.cpp): Ceres clips a step at the box
// but its model of the cost change does not see the clipping, so a
// parameter whose minimum is at a bound crawls there with poor steps. The
// solve pins such a parameter at the bound (held through a
// ceres::SubsetManifold) and solves the rest, and frees it again when the
// Gauss-Newton step from the end of a round points back into the box.
// Private to src/lsq.
#ifndef CLAYFIT_LSQ_BOUNDS_H
#define CLAYFIT_LSQ_BOUNDS_H

#include <ceres/iteration_callback.h>
#include <ceres/manifold.h>

#include <vector>

#include "lsq/lsq.h"
#include "lsq_blocks.h"
#include "lsq_newton.h"

namespace lsq {

// Watches a chunk's iterations (a ceres::IterationCallback): traces each,
// stops the chunk when options->stop says so, and when a free parameter
// has sat at a bound for two iterations in a row (Ceres clips steps at the
// box, so "at" is exact) or is closing in on one with poor steps
// (closing_in); the solve then pins it there (hit()) and solves the rest.
// Without the pins the 8-image capture's fit on 10 000 observations took
// 500 iterations instead of 13 (2.5x the CPU time), and DiLiGenT's fit on
// every observation ended at 42 % error instead of 8.5 %; without the pins
// for closing in, DiLiGenT's fit on 3·10⁴ uniform observations took 147
// iterations instead of 65 (1.18x the wall time) and ended 0.5 % higher
// (docs/solver.md, "active set").
class BoundWatcher final : public ceres::IterationCallback {
 public:
  // A parameter is pinned for closing in at most twice a solve: when the
  // Newton step frees it twice, it is believed, and the poor steps are left
  // to converge as they can.
  static constexpr int MAX_CLOSINGS = 2;  // 0aac5d5 (DiLiGenT 89 iterations -> 18); 2 not measured

  // closings: the times each parameter was pinned for closing in so far
  BoundWatcher(const cf_lsq_problem *problem, const cf_lsq_options *options,
               const std::vector<int> &active, const std::vector<int> &closings)
      : problem_(problem),
        options_(options),
        active_(active),
        closings_(closings),
        streak_(active.size(), 0),
        hit_(active.size(), 0),
        closed_(active.size(), 0),
        approach_(active.size(), 0),
        near_(active.size(), 0),
        distance_(active.size(), 0.0) {}

  ceres::CallbackReturnType operator()(const ceres::IterationSummary &it) override;

  // −1 or +1 for a parameter at its lower or upper bound, 0 inside
  int side_of(size_t i) const {
    const double x = problem_->x[i];
    if (x <= problem_->lower[i]) return -1;
    if (x >= problem_->upper[i]) return 1;
    return 0;
  }
  // the side each parameter the chunk was stopped for sits at (0: none)
  const std::vector<int> &hit() const {
    return hit_;
  }
  bool any_hit() const {
    return std::any_of(hit_.begin(), hit_.end(), [](int h) { return h != 0; });
  }
  // 1 for a parameter pinned for closing in on its bound
  const std::vector<int> &closed() const {
    return closed_;
  }
  // options->stop ended the chunk
  bool stopped() const {
    return stopped_;
  }
  // x before the last successful step (empty when there was none)
  const std::vector<double> &previous() const {
    return previous_;
  }

 private:
  bool closing_in(size_t i, double relative_decrease);

  const cf_lsq_problem *problem_;
  const cf_lsq_options *options_;
  const std::vector<int> &active_, &closings_;
  std::vector<int> streak_, hit_, closed_;
  std::vector<int> approach_;     // successful steps in a row that came closer
  std::vector<int> near_;         // the bound it came closer to
  std::vector<double> distance_;  // to that bound, at the last successful step
  bool stopped_ = false;
  std::vector<double> previous_, current_;
};

// Which parameters at a bound (side: −1, +1; 0 for one inside the box)
// stay pinned there at the end of a round (lsq_bounds.cpp). Returns false
// when the normal equations cannot be evaluated.
bool pinned_at_bounds(const cf_lsq_problem *problem, int threads, std::vector<BlockCache> *caches,
                      const std::vector<int> &side, const std::vector<int> &by_newton,
                      std::vector<int> *pinned);

// The up-front pins of a solve near a minimum (cf_lsq_options.newton_start,
// lsq_bounds.cpp). Returns false when the normal equations cannot be
// evaluated.
bool newton_pins(cf_lsq_problem *problem, int threads, std::vector<BlockCache> *caches,
                 std::vector<int> *active);

}  // namespace lsq

#endif  // CLAYFIT_LSQ_BOUNDS_H
