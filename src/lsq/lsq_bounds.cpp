// Bounds as an active set (lsq_bounds.h).
#include "lsq_bounds.h"

#include <cmath>

namespace lsq {

ceres::CallbackReturnType BoundWatcher::operator()(const ceres::IterationSummary &it) {
  trace(options_, "iteration %d: cost %.9e, change %.3e, ratio %.3g, radius %.3g, step %.3g%s",
        it.iteration, it.cost, it.cost_change, it.relative_decrease, it.trust_region_radius,
        it.step_norm, it.step_is_successful ? "" : " (rejected)");
  if (it.step_is_successful || it.iteration == 0) {
    previous_ = current_;
    current_.assign(problem_->x, problem_->x + problem_->num_params);
  }
  if (it.step_is_successful && it.iteration > 0 && options_->stop != nullptr &&
      options_->stop(options_->stop_user, problem_->x, it.cost)) {
    stopped_ = true;
    return ceres::SOLVER_TERMINATE_SUCCESSFULLY;
  }
  bool stop = false;
  for (size_t i = 0; i < active_.size(); ++i) {
    if (active_[i] != 0) continue;
    const int side = side_of(i);
    streak_[i] = side != 0 ? streak_[i] + 1 : 0;
    if (streak_[i] >= 2) hit_[i] = side, stop = true;  // the active set: docs/solver.md; 2 not varied
    if (it.step_is_successful && it.iteration > 0 && side == 0 &&
        closing_in(i, it.relative_decrease) && closings_[i] < MAX_CLOSINGS)
      hit_[i] = near_[i], closed_[i] = 1, stop = true;
  }
  return stop ? ceres::SOLVER_TERMINATE_SUCCESSFULLY : ceres::SOLVER_CONTINUE;
}

// Is parameter i closing in on a bound the steps cannot reach: 10 % closer
// on each of three successful steps in a row, each with less than half the
// decrease its model predicted, and now within 1 % of the range? (One that
// converges to a point near a bound slows down; one whose minimum is at
// the bound, with steps the bound clips and Ceres' projected line search
// shortens, keeps closing in at a constant rate with poor steps: an
// Oren-Nayar σ² from 3e-4 to 2e-6 in 30 iterations, each with a fifth of
// the predicted decrease.)
bool BoundWatcher::closing_in(size_t i, double relative_decrease) {
  const double lower = problem_->lower[i], upper = problem_->upper[i], x = problem_->x[i];
  if (!std::isfinite(lower) || !std::isfinite(upper)) return false;
  const int near = x - lower <= upper - x ? -1 : 1;
  const double distance = near < 0 ? x - lower : upper - x;
  const bool closer = near == near_[i] && distance <= 0.9 * distance_[i] && relative_decrease < 0.5;
  approach_[i] = closer ? approach_[i] + 1 : 0;
  near_[i] = near;
  distance_[i] = distance;
  return approach_[i] >= 3 && distance < 0.01 * (upper - lower);
}

// Which parameters at a bound (side: −1, +1; 0 for one inside the box)
// stay pinned there. One that hit the bound on its way, the first time in
// a solve, by its gradient: pinned when it points out of the box, freed
// when it points in (far from the minimum the Gauss-Newton step is no
// guide: a start whose optical depth hit 0 on its way stayed there, 2 %
// above the true minimum). One freed before, or pinned for closing in with
// poor steps or up front (by_newton), by the Gauss-Newton step of the problem with it
// free: pinned when the step, which the other parameters' change drags,
// moves it further out, even with a gradient that points in (measured: an
// Oren-Nayar σ² at 0, freed by its gradient and pushed back by every step,
// 45 iterations of creeping; DiLiGenT's optical depths, 89 iterations for
// 18). The outward ones are pinned and the step solved again for the
// rest, until none goes out. pinned[i] is side or 0. Returns false when
// the normal equations cannot be evaluated.
bool pinned_at_bounds(const cf_lsq_problem *problem, int threads, std::vector<BlockCache> *caches,
                      const std::vector<int> &side, const std::vector<int> &by_newton,
                      std::vector<int> *pinned) {
  const int n = problem->num_params;
  std::vector<double> jtj(static_cast<size_t>(n) * n), g(n);
  double cost;
  if (normal_equations(problem, threads, caches, jtj.data(), g.data(), &cost) != CF_LSQ_EVALUATED)
    return false;
  pinned->assign(n, 0);
  for (int i = 0; i < n; ++i)  // the gradient's decisions (descent is −g)
    if (side[i] != 0 && !by_newton[i] && side[i] * -g[i] > 0.0) (*pinned)[i] = side[i];
  std::vector<int> free_index;
  std::vector<double> step;
  for (;;) {
    reduced_newton_step(n, jtj.data(), g.data(), pinned->data(), &free_index, &step);
    const int m = static_cast<int>(free_index.size());
    if (m == 0) return true;
    bool changed = false;
    for (int a = 0; a < m; ++a) {
      const int i = free_index[a];
      if (side[i] != 0 && by_newton[i] && side[i] * step[a] > 0.0)
        (*pinned)[i] = side[i], changed = true;
    }
    if (!changed) return true;
  }
}

// A solve near a minimum (cf_lsq_options.newton_start): the parameters
// whose Gauss-Newton step from x, with the others free, leaves the box
// are pinned at that bound (active), and the step solved again for the
// rest, until none leaves; x is moved onto the pinned bounds. (A parameter
// whose minimum is at a bound otherwise creeps there with steps the bound
// clips: the 8-image synthetic capture's σ², 0.0048 where the subsample's
// minimum was, took 7 of the fit's 9 iterations to reach 0.) Returns
// false when the normal equations cannot be evaluated.
//
// Only where the step's predicted decrease is below
// NEWTON_START_DECREMENT, in the cost's units (the fit's are σ²: the
// step's minimum within a Δχ² of 20). (Without these pins the 8-image
// capture's fit on every observation took 13 iterations instead of 3,
// 1.23x the wall time; docs/solver.md, "up-front pins".)
constexpr double NEWTON_START_DECREMENT = 10.0;

bool newton_pins(cf_lsq_problem *problem, int threads, std::vector<BlockCache> *caches,
                 std::vector<int> *active) {
  const int n = problem->num_params;
  std::vector<double> jtj(static_cast<size_t>(n) * n), g(n);
  double cost;
  if (normal_equations(problem, threads, caches, jtj.data(), g.data(), &cost) != CF_LSQ_EVALUATED)
    return false;
  std::vector<int> free_index;
  std::vector<double> step;
  for (bool first = true;;) {
    const double decrement =
        reduced_newton_step(n, jtj.data(), g.data(), active->data(), &free_index, &step);
    const int m = static_cast<int>(free_index.size());
    if (m == 0) break;
    // far from the minimum the quadratic model is no guide (DiLiGenT's
    // refinement started 10⁴ σ² above it, and the step sent every albedo
    // to 20 and the film's roughness below its floor): pins only within
    // NEWTON_START_DECREMENT of the unconstrained step's minimum
    if (first && !(decrement < NEWTON_START_DECREMENT)) return true;
    first = false;
    bool changed = false;
    for (int a = 0; a < m; ++a) {
      const int i = free_index[a];
      const double target = problem->x[i] + step[a];
      if (!std::isfinite(target)) continue;
      // beyond the bound by at least the distance inside it: a step that
      // only just leaves can be the quadratic model's error (the
      // 16-image capture's σ², 0.041 with a step of −0.058, has its
      // minimum at 0.0059)
      const double x = problem->x[i], lower = problem->lower[i], upper = problem->upper[i];
      if (target < lower - (x - lower)) (*active)[i] = -1, changed = true;
      if (target > upper + (upper - x)) (*active)[i] = 1, changed = true;
    }
    if (!changed) break;
  }
  for (int i = 0; i < n; ++i)
    if ((*active)[i] != 0) problem->x[i] = (*active)[i] < 0 ? problem->lower[i] : problem->upper[i];
  return true;
}

}  // namespace lsq

extern "C" double cf_lsq_newton_decrement(int n, const double *jtj, const double *g,
                                          const int *pinned) {
  try {
    std::vector<int> free_index;
    std::vector<double> step;
    return lsq::reduced_newton_step(n, jtj, g, pinned, &free_index, &step);
  } catch (...) {  // out of memory: nothing known, nothing settled
    return HUGE_VAL;
  }
}
