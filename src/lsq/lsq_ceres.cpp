// The Ceres adapter behind lsq.h: one ceres::CostFunction per residual
// block, each a thin shell over the C callback, Levenberg-Marquardt with
// dense normal equations (few parameters, many residuals), bounds as Ceres
// bounds, ceres::Covariance for the uncertainty. No exception crosses the
// C boundary.
#include <ceres/ceres.h>
#include <glog/logging.h>

#include <algorithm>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <memory>
#include <mutex>
#include <new>
#include <thread>
#include <vector>

#include "lsq.h"

namespace {

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
// Ceres evaluates a block from one thread at a time.
struct BlockCache {
  BlockEvaluation slot[2];
  unsigned long clock = 0;
  // new points Ceres asked the cost at since its last Jacobian (BlockCost)
  int trials = 0;

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
    if (!problem->evaluate(problem->user, point, block, &e.cost,
                           want_normal ? e.jtj.data() : nullptr,
                           want_normal ? e.jtu.data() : nullptr))
      return nullptr;
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

// One residual block of the C problem, compressed (lsq.h): k + 1
// residuals (c, d) with the Jacobian (R; 0) in the block's k columns, from
// the block's normal equations.
//
// Evaluating the cost alone also computes the normal equations (for k up
// to SPECULATE_COLUMNS), kept with x: Ceres evaluates the cost at a
// candidate (twice: its projected line search tries the full step first)
// and, when it accepts the step, the Jacobian at the same point, which is
// then free. A Jacobian pass costs about 1.5 cost passes, so an accepted
// step costs 1.5 passes instead of 2.5, a rejected one 1.5 instead of 1.
// Only the first SPECULATE_TRIALS new points after a Jacobian, though (a
// candidate, and the next after a rejected one): the rest are the
// projected line search's trials along a step that left the box, up to
// 20, whose normal equations are seldom asked for.
constexpr int SPECULATE_COLUMNS = 128, SPECULATE_TRIALS = 2;

class BlockCost final : public ceres::CostFunction {
 public:
  BlockCost(const cf_lsq_problem *problem, size_t block, BlockCache *cache)
      : problem_(problem), block_(block), cache_(cache) {
    const int *columns = nullptr;
    const int k = problem->block_columns(problem->user, block, &columns);
    columns_.assign(columns, columns + k);
    set_num_residuals(k + 1);
    mutable_parameter_block_sizes()->push_back(problem->num_params);
  }

  bool Evaluate(double const *const *parameters, double *residuals,
                double **jacobians) const override {
    double *jacobian = jacobians != nullptr ? jacobians[0] : nullptr;
    const int n = problem_->num_params, k = static_cast<int>(columns_.size());
    const double *x = parameters[0];
    if (jacobian == nullptr) {  // the cost alone: (0, …, 0, √(2C))
      const bool speculate = k <= SPECULATE_COLUMNS && cache_->trials < SPECULATE_TRIALS;
      const BlockEvaluation *e = cache_->at(problem_, block_, k, x, speculate);
      if (e == nullptr) return false;
      if (e->uses == 0) ++cache_->trials;  // evaluated here: a new point
      std::fill(residuals, residuals + k, 0.0);
      residuals[k] = std::sqrt(2.0 * e->cost);
      return true;
    }
    const BlockEvaluation *e = cache_->at(problem_, block_, k, x, true);
    if (e == nullptr) return false;
    cache_->trials = 0;
    const double cost = e->cost;
    const std::vector<double> &jtj_storage = e->jtj, &jtu_storage = e->jtu;
    using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    Eigen::Map<const RowMajor> jtj(jtj_storage.data(), k, k);
    Eigen::Map<const Eigen::VectorXd> jtu(jtu_storage.data(), k);
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(jtj);
    if (eigen.info() != Eigen::Success) return false;
    const double largest = std::max(0.0, eigen.eigenvalues().maxCoeff());
    double projected = 0.0;
    std::fill(jacobian, jacobian + static_cast<size_t>(k + 1) * n, 0.0);
    for (int i = 0; i < k; ++i) {
      const double lambda = eigen.eigenvalues()(i);
      residuals[i] = 0.0;
      if (!(lambda > 1e-14 * largest)) continue;  // a direction the block does not see
      const double root = std::sqrt(lambda);
      residuals[i] = eigen.eigenvectors().col(i).dot(jtu) / root;
      projected += residuals[i] * residuals[i];
      for (int c = 0; c < k; ++c)
        jacobian[static_cast<size_t>(i) * n + columns_[c]] = root * eigen.eigenvectors()(c, i);
    }
    residuals[k] = std::sqrt(std::max(0.0, 2.0 * cost - projected));
    return true;
  }

 private:
  const cf_lsq_problem *problem_;
  size_t block_;
  BlockCache *cache_;
  std::vector<int> columns_;
};

// r = R (x − x0): a residual block whose Jacobian is the factor R.
class FactorCost final : public ceres::CostFunction {
 public:
  FactorCost(int n, const double *r, const double *x0) : n_(n), r_(r), x0_(x0) {
    set_num_residuals(n);
    mutable_parameter_block_sizes()->push_back(n);
  }

  bool Evaluate(double const *const *parameters, double *residuals,
                double **jacobians) const override {
    for (int i = 0; i < n_; ++i) {
      residuals[i] = 0.0;
      for (int j = 0; j < n_; ++j) residuals[i] += r_[i * n_ + j] * (parameters[0][j] - x0_[j]);
    }
    if (jacobians != nullptr && jacobians[0] != nullptr)
      std::memcpy(jacobians[0], r_, sizeof(double) * static_cast<size_t>(n_) * n_);
    return true;
  }

 private:
  int n_;
  const double *r_;
  const double *x0_;
};

void quiet_glog() {
  // Ceres reports through glog; the fit reports rank deficiency itself
  // (once, whichever of the solves running side by side comes first)
  static std::once_flag once;
  std::call_once(once, [] { FLAGS_minloglevel = google::GLOG_FATAL; });
}

void copy_termination(const ceres::Solver::Summary &s, cf_lsq_summary *out) {
  std::snprintf(out->termination, sizeof out->termination, "%s",
                ceres::TerminationTypeToString(s.termination_type));
}

}  // namespace

namespace {

// f(t) for t = 0 … count − 1 at once: t = 0 on this thread, each other on
// one of its own. False when an f(t) returned false or threw, or a thread
// could not be started (those started are joined first: a joinable
// std::thread destroyed would end the process).
template <class F>
bool in_threads(size_t count, F f) {
  std::vector<char> ok(count, 1);
  auto guarded = [&](size_t t) noexcept {
    try {
      ok[t] = f(t);
    } catch (...) {
      ok[t] = 0;
    }
  };
  std::vector<std::thread> pool;
  bool started = true;
  try {
    for (size_t t = 1; t < count; ++t) pool.emplace_back(guarded, t);
  } catch (...) {
    started = false;
  }
  if (started) guarded(0);
  for (auto &thread : pool) thread.join();
  return started && std::all_of(ok.begin(), ok.end(), [](char o) { return o != 0; });
}

// cf_lsq_normal_equations, from the blocks' caches where they hold x
// (caches: one per block, or nullptr).
int normal_equations(const cf_lsq_problem *problem, int threads, std::vector<BlockCache> *caches,
                     double *jtj, double *jtu, double *cost) {
  const int n = problem->num_params;
  const size_t count = static_cast<size_t>(std::max(1, threads));
  std::vector<std::vector<double>> sum_jtj(count), sum_jtu(count);
  std::vector<double> sum_cost(count, 0.0);
  const bool ok = in_threads(count, [&](size_t t) {
    BlockCache scratch;
    if (jtj) sum_jtj[t].assign(static_cast<size_t>(n) * n, 0.0);
    sum_jtu[t].assign(n, 0.0);
    for (size_t b = t; b < problem->num_blocks; b += count) {
      const int *columns = nullptr;
      const int k = problem->block_columns(problem->user, b, &columns);
      scratch.clear();  // it held another block
      BlockCache &cache = caches != nullptr ? (*caches)[b] : scratch;
      const BlockEvaluation *e = cache.at(problem, b, k, problem->x, true);
      if (e == nullptr) return false;
      sum_cost[t] += e->cost;
      for (int a = 0; a < k; ++a) {
        sum_jtu[t][columns[a]] += e->jtu[a];
        if (!jtj) continue;
        for (int c = 0; c < k; ++c)
          sum_jtj[t][static_cast<size_t>(columns[a]) * n + columns[c]] +=
              e->jtj[static_cast<size_t>(a) * k + c];
      }
    }
    return true;
  });
  if (!ok) return 0;
  if (jtj) std::fill(jtj, jtj + static_cast<size_t>(n) * n, 0.0);
  if (jtu) std::fill(jtu, jtu + n, 0.0);
  *cost = 0.0;
  for (size_t t = 0; t < count; ++t) {
    *cost += sum_cost[t];
    for (int a = 0; a < n; ++a) {
      if (jtu) jtu[a] += sum_jtu[t][a];
      if (jtj)
        for (int c = 0; c < n; ++c)
          jtj[static_cast<size_t>(a) * n + c] += sum_jtj[t][static_cast<size_t>(a) * n + c];
    }
  }
  return 1;
}

}  // namespace

extern "C" int cf_lsq_normal_equations(const cf_lsq_problem *problem, int threads, double *jtj,
                                       double *jtu, double *cost) {
  try {
    return normal_equations(problem, threads, nullptr, jtj, jtu, cost);
  } catch (...) {  // out of memory for the sums: nothing crosses into C
    return 0;
  }
}

extern "C" cf_status cf_lsq_covariance(int n, const double *jtj, double *covariance,
                                       int *rank_deficient, cf_error *err) {
  try {
    quiet_glog();
    Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> a(
        jtj, n, n);
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(a);
    if (eigen.info() != Eigen::Success)
      return cf_error_set(err, CF_ENUMERIC, "the normal matrix could not be decomposed");
    // R = Λ^(1/2) Vᵀ, row-major
    std::vector<double> r(static_cast<size_t>(n) * n), x(n, 0.0), x0(n, 0.0);
    for (int i = 0; i < n; ++i) {
      double root = std::sqrt(std::max(0.0, eigen.eigenvalues()(i)));
      for (int j = 0; j < n; ++j)
        r[static_cast<size_t>(i) * n + j] = root * eigen.eigenvectors()(j, i);
    }
    ceres::Problem problem;
    problem.AddResidualBlock(new FactorCost(n, r.data(), x0.data()), nullptr, x.data());
    ceres::Covariance::Options options;
    options.algorithm_type = ceres::DENSE_SVD;
    options.min_reciprocal_condition_number = 1e-12;
    ceres::Covariance covariance_problem(options);
    std::vector<std::pair<const double *, const double *>> blocks{{x.data(), x.data()}};
    if (!covariance_problem.Compute(blocks, &problem)) {
      if (rank_deficient) *rank_deficient = 1;
      return CF_OK;
    }
    if (rank_deficient) *rank_deficient = 0;
    covariance_problem.GetCovarianceBlock(x.data(), x.data(), covariance);
    return CF_OK;
  } catch (const std::bad_alloc &) {
    return cf_error_set(err, CF_ENOMEM, "out of memory for the covariance");
  } catch (const std::exception &e) {
    return cf_error_set(err, CF_ENUMERIC, "the covariance failed: %s", e.what());
  } catch (...) {
    return cf_error_set(err, CF_ENUMERIC, "the covariance failed");
  }
}

extern "C" void cf_lsq_default_options(cf_lsq_options *options) {
  options->max_iterations = 100;
  options->threads = 2;
  options->function_tolerance = 1e-10;
  options->gradient_tolerance = 1e-12;
  options->parameter_tolerance = 1e-10;
  options->line_search_tolerance = 1e-3;
  options->min_relative_decrease = 1e-3;
  options->initial_radius = 1e4;
  options->newton_start = 0;
  options->stop = nullptr;
  options->stop_user = nullptr;
  options->final_jtj = nullptr;
}

namespace {

// Stops the solve when a free parameter has sat at a bound for two
// iterations in a row (Ceres clips steps at the box, so "at" is exact), or
// is closing in on one with poor steps (closing_in): the projected line
// search shortens every step that the bound would clip, and the parameter
// never lands on it (measured: an Oren-Nayar σ²
// from 3e-4 to 2e-6 in 30 iterations, each with a fifth of the predicted
// decrease). Such a parameter is pinned at the bound, and the Newton test
// at the end of the round (pinned_at_bounds) frees it again when its
// minimum is inside.
class BoundWatcher final : public ceres::IterationCallback {
 public:
  // A parameter is pinned for closing in at most twice a solve: when the
  // Newton step frees it twice, it is believed, and the poor steps are left
  // to converge as they can.
  static constexpr int MAX_CLOSINGS = 2;

  BoundWatcher(const cf_lsq_problem *problem, const cf_lsq_options *options,
               const std::vector<int> &active, const std::vector<int> &closings)
      : problem_(problem),
        options_(options),
        active_(active),
        closings_(closings),
        closed_(active.size(), 0),
        streak_(active.size(), 0),
        hit_(active.size(), 0),
        approach_(active.size(), 0),
        distance_(active.size(), 0.0),
        near_(active.size(), 0) {}

  ceres::CallbackReturnType operator()(const ceres::IterationSummary &it) override {
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
      int side = side_of(i);
      streak_[i] = side != 0 ? streak_[i] + 1 : 0;
      if (streak_[i] >= 2) hit_[i] = side, stop = true;
      if (it.step_is_successful && it.iteration > 0 && side == 0 &&
          closing_in(i, it.relative_decrease) && closings_[i] < MAX_CLOSINGS)
        hit_[i] = near_[i], closed_[i] = 1, stop = true;
    }
    return stop ? ceres::SOLVER_TERMINATE_SUCCESSFULLY : ceres::SOLVER_CONTINUE;
  }

  // Is parameter i closing in on a bound the steps cannot reach: 10 %
  // closer on each of three successful steps in a row, each with less than
  // half the decrease its model predicted, and now within 1 % of the range?
  // (A parameter that converges to a point near a bound slows down; one
  // whose minimum is at the bound, with steps the bound clips and the line
  // search shortens, keeps closing in at a constant rate with poor steps.)
  bool closing_in(size_t i, double relative_decrease) {
    const double lower = problem_->lower[i], upper = problem_->upper[i], x = problem_->x[i];
    if (!std::isfinite(lower) || !std::isfinite(upper)) return false;
    const int near = x - lower <= upper - x ? -1 : 1;
    const double distance = near < 0 ? x - lower : upper - x;
    const bool closer =
        near == near_[i] && distance <= 0.9 * distance_[i] && relative_decrease < 0.5;
    approach_[i] = closer ? approach_[i] + 1 : 0;
    near_[i] = near;
    distance_[i] = distance;
    return approach_[i] >= 3 && distance < 0.01 * (upper - lower);
  }

  int side_of(size_t i) const {
    double x = problem_->x[i];
    if (x <= problem_->lower[i]) return -1;
    if (x >= problem_->upper[i]) return 1;
    return 0;
  }
  const std::vector<int> &hit() const {
    return hit_;
  }
  bool stopped() const {
    return stopped_;
  }
  // 1 for a parameter pinned for closing in on its bound
  const std::vector<int> &closed() const {
    return closed_;
  }
  // x before the last successful step (empty when there was none)
  const std::vector<double> &previous() const {
    return previous_;
  }
  bool any_hit() const {
    return std::any_of(hit_.begin(), hit_.end(), [](int h) { return h != 0; });
  }

 private:
  const cf_lsq_problem *problem_;
  const cf_lsq_options *options_;
  const std::vector<int> &active_;
  const std::vector<int> &closings_;  // times each was pinned for closing in
  std::vector<int> closed_;
  bool stopped_ = false;
  std::vector<int> streak_, hit_;
  std::vector<int> approach_;     // successful steps in a row that came closer
  std::vector<double> distance_;  // to the nearest bound, at the last successful step
  std::vector<int> near_;         // which bound that is
  std::vector<double> previous_, current_;
};

// The cost's gradient Jᵀu at problem->x.
bool gradient_at(const cf_lsq_problem *problem, int threads, std::vector<double> *gradient) {
  gradient->assign(problem->num_params, 0.0);
  double cost;
  return cf_lsq_normal_equations(problem, threads, nullptr, gradient->data(), &cost) != 0;
}

// The Gauss-Newton step of the parameters not pinned (pinned[i] == 0) with
// the pinned ones held: solves JᵀJ d = −g over the free ones (jtj n × n,
// row-major), with a ridge of 1e-12 of the largest curvature so that a
// direction no data see does not take the step to infinity. free_index
// gets the free parameters, step their components, in that order.
void reduced_newton_step(const std::vector<double> &jtj, const std::vector<double> &g,
                         const std::vector<int> &pinned, std::vector<int> *free_index,
                         Eigen::VectorXd *step) {
  const int n = static_cast<int>(g.size());
  free_index->clear();
  for (int i = 0; i < n; ++i)
    if (pinned[i] == 0) free_index->push_back(i);
  const int m = static_cast<int>(free_index->size());
  Eigen::MatrixXd h(m, m);
  Eigen::VectorXd rhs(m);
  double largest = 0.0;
  for (int a = 0; a < m; ++a) {
    rhs(a) = -g[(*free_index)[a]];
    for (int b = 0; b < m; ++b)
      h(a, b) = jtj[static_cast<size_t>((*free_index)[a]) * n + (*free_index)[b]];
    largest = std::max(largest, h(a, a));
  }
  h.diagonal().array() += 1e-12 * std::max(largest, 1e-300);
  *step = m > 0 ? Eigen::VectorXd(h.ldlt().solve(rhs)) : Eigen::VectorXd();
}

// Which parameters at a bound (side: −1, +1; 0 for one inside the box)
// stay pinned there. One that hit the bound on its way, the first time in
// a solve, by its gradient: pinned when it points out of the box, freed
// when it points in (far from the minimum the Gauss-Newton step is no
// guide: a start whose optical depth hit 0 on its way stayed there, 2 %
// above the true minimum). One freed before, or pinned for closing in with
// poor steps (by_newton), by the Gauss-Newton step of the problem with it
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
  if (!normal_equations(problem, threads, caches, jtj.data(), g.data(), &cost)) return false;
  pinned->assign(n, 0);
  for (int i = 0; i < n; ++i)  // the gradient's decisions (descent is −g)
    if (side[i] != 0 && !by_newton[i] && side[i] * -g[i] > 0.0) (*pinned)[i] = side[i];
  std::vector<int> free_index;
  Eigen::VectorXd step;
  for (;;) {
    reduced_newton_step(jtj, g, *pinned, &free_index, &step);
    const int m = static_cast<int>(free_index.size());
    if (m == 0) return true;
    bool changed = false;
    for (int a = 0; a < m; ++a) {
      const int i = free_index[a];
      if (side[i] != 0 && by_newton[i] && side[i] * step(a) > 0.0)
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
// step's minimum within a Δχ² of 20).
constexpr double NEWTON_START_DECREMENT = 10.0;

bool newton_pins(cf_lsq_problem *problem, int threads, std::vector<BlockCache> *caches,
                 std::vector<int> *active) {
  const int n = problem->num_params;
  std::vector<double> jtj(static_cast<size_t>(n) * n), g(n);
  double cost;
  if (!normal_equations(problem, threads, caches, jtj.data(), g.data(), &cost)) return false;
  std::vector<int> free_index;
  Eigen::VectorXd step;
  for (bool first = true;;) {
    reduced_newton_step(jtj, g, *active, &free_index, &step);
    const int m = static_cast<int>(free_index.size());
    if (m == 0) break;
    // far from the minimum the quadratic model is no guide (DiLiGenT's
    // refinement started 10⁴ σ² above it, and the step sent every albedo
    // to 20 and the film's roughness below its floor): pins only within
    // NEWTON_START_DECREMENT of the unconstrained step's minimum
    double decrement = 0.0;
    for (int a = 0; a < m; ++a) decrement -= 0.5 * g[free_index[a]] * step(a);
    if (first && !(decrement < NEWTON_START_DECREMENT)) return true;
    first = false;
    bool changed = false;
    for (int a = 0; a < m; ++a) {
      const int i = free_index[a];
      const double target = problem->x[i] + step(a);
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

// The total cost at x (NaN when a block cannot be evaluated there), the
// blocks shared among `threads` threads.
double cost_at(const cf_lsq_problem *problem, const double *x, int threads) {
  const size_t count = static_cast<size_t>(std::max(1, threads));
  std::vector<double> partial(count, 0.0);
  const bool ok = in_threads(count, [&](size_t t) {
    for (size_t b = t; b < problem->num_blocks; b += count) {
      double cost;
      if (!problem->evaluate(problem->user, x, b, &cost, nullptr, nullptr)) cost = NAN;
      partial[t] += cost;
    }
    return true;
  });
  double total = 0.0;
  for (double p : partial) total += p;
  return ok ? total : NAN;
}

// Did the chunk's successful steps decrease the cost by more than their
// model predicted (mean ratio above 1.25)? Gauss-Newton then takes steps
// too short along a direction where the residuals' own curvature cancels
// part of JᵀJ (a fit with large systematic residuals), and converges
// linearly, slowly.
bool under_stepping(const ceres::Solver::Summary &summary) {
  double sum = 0.0;
  int count = 0;
  for (const auto &it : summary.iterations)
    if (it.iteration > 0 && it.step_is_successful) sum += it.relative_decrease, ++count;
  return count >= 3 && sum / count > 1.25;
}

// Where a line search along the last step d of a chunk starts: the
// minimum of the cost along d if it is a parabola, t* = 1 / (2 − ρ) for
// the step's ratio ρ of actual to predicted decrease (the model's
// curvature along d is then 1 / (2 − ρ) times the cost's), rounded down
// to a power of 2 in [2, 32]. (DiLiGenT's chunks end with ρ from 1.8 to
// 1.96, t* from 5 to 25: doubling from 2 took up to six cost passes.)
double first_trial(const ceres::Solver::Summary &summary) {
  double ratio = 1.0;
  for (const auto &it : summary.iterations)
    if (it.iteration > 0 && it.step_is_successful) ratio = it.relative_decrease;
  const double target = ratio < 2.0 ? 1.0 / (2.0 - ratio) : 64.0;
  double t = 2.0;
  while (t * 2.0 <= std::min(target, 32.0)) t *= 2.0;
  return t;
}

// A line search along the last Gauss-Newton step d = x − x0: the costs at
// x0 + t d for t = first, 2 first, 4 first, … (clipped into the box, t at
// most 64) while they decrease, or, when the first is already higher,
// first / 2, first / 4, … down to 2 until one is lower; then the vertex of
// the parabola through the best and its neighbours. Returns whether x
// moved (to a lower cost).
bool extrapolate(cf_lsq_problem *problem, const std::vector<double> &x0, double cost, double first,
                 int threads, double tolerance) {
  const int n = problem->num_params;
  const bool trace = std::getenv("CLAYFIT_LSQ_TRACE") != nullptr;
  std::vector<double> trial(n), best(problem->x, problem->x + n);
  auto point = [&](double t) {
    for (int i = 0; i < n; ++i)
      trial[i] =
          std::min(problem->upper[i], std::max(problem->lower[i], x0[i] + t * (best[i] - x0[i])));
  };
  const std::vector<double> x1(best);
  double t_prev = 1.0, c_prev = cost, t_best = 1.0, c_best = cost, t_next = 0.0, c_next = NAN;
  bool back = false;  // the first trial was higher: halving toward 1
  for (double t = first;;) {
    point(t);
    double c = cost_at(problem, trial.data(), threads);
    if (trace) std::printf("line search t = %g: cost %.9e (from %.9e)\n", t, c, cost);
    if (c < c_best) {
      t_prev = t_best, c_prev = c_best, t_best = t, c_best = c;
      if (back || t * 2.0 > 64.0) break;  // (back: the next is known, higher)
      t *= 2.0;
      continue;
    }
    t_next = t, c_next = c;
    if (t_best != 1.0 || t <= 2.0) break;
    back = true;
    t *= 0.5;
  }
  best = x1;  // point() steps from x0 along x1 − x0
  if (t_best == 1.0 || !(c_best < cost - tolerance)) return false;
  std::vector<double> at_best(n);
  point(t_best);
  at_best = trial;
  if (std::isfinite(c_next)) {  // the parabola through (t_prev, t_best, t_next)
    double a = t_prev, b = t_best, c = t_next, fa = c_prev, fb = c_best, fc = c_next;
    double num = (b - a) * (b - a) * (fb - fc) - (b - c) * (b - c) * (fb - fa);
    double den = (b - a) * (fb - fc) - (b - c) * (fb - fa);
    if (den != 0.0) {
      double t = b - 0.5 * num / den;
      if (t > a && t < c) {
        point(t);
        double ct = cost_at(problem, trial.data(), threads);
        if (trace) std::printf("line search t = %g (parabola): cost %.9e\n", t, ct);
        if (ct < c_best) c_best = ct, at_best = trial;
      }
    }
  }
  std::copy(at_best.begin(), at_best.end(), problem->x);
  return true;
}

// One Ceres solve with the parameters flagged in `active` held.
void solve_once(cf_lsq_problem *problem, const cf_lsq_options *options,
                const std::vector<int> &active, int max_iterations, double radius,
                std::vector<BlockCache> *caches, BoundWatcher *watcher,
                ceres::Solver::Summary *summary) {
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  problem_options.manifold_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem ceres_problem(problem_options);
  ceres_problem.AddParameterBlock(problem->x, problem->num_params);
  for (size_t b = 0; b < problem->num_blocks; ++b)
    ceres_problem.AddResidualBlock(new BlockCost(problem, b, &(*caches)[b]), nullptr, problem->x);
  for (int i = 0; i < problem->num_params; ++i) {
    if (std::isfinite(problem->lower[i]))
      ceres_problem.SetParameterLowerBound(problem->x, i, problem->lower[i]);
    if (std::isfinite(problem->upper[i]))
      ceres_problem.SetParameterUpperBound(problem->x, i, problem->upper[i]);
  }
  std::vector<int> held;
  for (int i = 0; i < problem->num_params; ++i)
    if (active[i] != 0) held.push_back(i);
  if (static_cast<int>(held.size()) == problem->num_params)
    ceres_problem.SetParameterBlockConstant(problem->x);
  else if (!held.empty())
    ceres_problem.SetManifold(problem->x, new ceres::SubsetManifold(problem->num_params, held));
  ceres::Solver::Options solver_options;
  solver_options.minimizer_type = ceres::TRUST_REGION;
  solver_options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  solver_options.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  solver_options.max_num_iterations = max_iterations;
  // the trust region where the last chunk left it: restarting at Ceres'
  // 1e4 damps the weak directions again every chunk (measured: 16
  // iterations where 10 do)
  solver_options.initial_trust_region_radius = radius;
  // Ceres' projected line search along a step at the box (bounds) needs
  // the cost alone with quadratic interpolation; cubic evaluates the
  // Jacobian at every trial (a whole extra pass per iteration)
  solver_options.line_search_interpolation_type = ceres::QUADRATIC;
  solver_options.min_relative_decrease = options->min_relative_decrease;
  solver_options.num_threads = options->threads;
  solver_options.function_tolerance = options->function_tolerance;
  solver_options.gradient_tolerance = options->gradient_tolerance;
  solver_options.parameter_tolerance = options->parameter_tolerance;
  solver_options.update_state_every_iteration = true;  // the watcher reads x
  solver_options.callbacks.push_back(watcher);
  // CLAYFIT_LSQ_TRACE=1: Ceres' per-iteration lines on stdout, to study
  // convergence
  const bool trace = std::getenv("CLAYFIT_LSQ_TRACE") != nullptr;
  solver_options.logging_type = trace ? ceres::PER_MINIMIZER_ITERATION : ceres::SILENT;
  solver_options.minimizer_progress_to_stdout = trace;
  ceres::Solve(solver_options, &ceres_problem, summary);
}

}  // namespace

extern "C" cf_status cf_lsq_solve(cf_lsq_problem *problem, const cf_lsq_options *options,
                                  cf_lsq_summary *summary, cf_error *err) {
  constexpr int MAX_ROUNDS = 8, CHUNK = 8, MAX_EXTRAPOLATIONS = 50;
  try {
    quiet_glog();
    const int n = problem->num_params;
    std::vector<int> active(n, 0);
    for (int i = 0; i < n; ++i)  // a start at a bound starts pinned there
      active[i] = problem->x[i] <= problem->lower[i]   ? -1
                  : problem->x[i] >= problem->upper[i] ? 1
                                                       : 0;
    std::vector<double> gradient;
    ceres::Solver::Summary ceres_summary;
    int iterations = 0, trace_count = 0;
    double seconds = 0.0, initial_cost = 0.0;
    std::vector<double> x0(n);
    int extrapolations = 0;
    double radius = options->initial_radius > 0.0 ? options->initial_radius : 1e4;
    std::vector<BlockCache> caches(problem->num_blocks);
    std::vector<int> freed(n, 0);  // freed from a bound once in this solve
    std::vector<int> closings(n, 0);
    std::vector<int> by_start(n, 0);  // pinned by the Newton step at the start
    if (options->newton_start) {
      std::vector<int> before = active;
      // (normal equations that cannot be evaluated: no pins, and the
      // solve meets them itself)
      if (!newton_pins(problem, options->threads, &caches, &active)) active = before;
      for (int i = 0; i < n; ++i) by_start[i] = active[i] != 0 && before[i] == 0;
    }
    summary->stopped = 0;
    for (int round = 0; round < MAX_ROUNDS;) {
      BoundWatcher watcher(problem, options, active, closings);
      int budget = std::max(1, std::min(CHUNK, options->max_iterations - iterations));
      std::copy(problem->x, problem->x + n, x0.begin());
      solve_once(problem, options, active, budget, radius, &caches, &watcher, &ceres_summary);
      if (std::getenv("CLAYFIT_LSQ_TRACE") != nullptr) {
        std::printf("chunk of solve: round %d, %s\n", round, ceres_summary.message.c_str());
        if (std::getenv("CLAYFIT_LSQ_TRACE")[0] == '2' &&
            gradient_at(problem, options->threads, &gradient))
          for (int i = 0; i < n; ++i)
            std::printf("  x[%d] = %.9g in [%g, %g], gradient %.4g, active %d\n", i, problem->x[i],
                        problem->lower[i], problem->upper[i], gradient[i], active[i]);
      }
      if (!ceres_summary.iterations.empty())
        radius = ceres_summary.iterations.back().trust_region_radius;
      if (round == 0 && extrapolations == 0 && iterations == 0)
        initial_cost = ceres_summary.initial_cost;
      for (size_t i = 0; i < ceres_summary.iterations.size(); ++i) {  // the trace
        const ceres::IterationSummary &it = ceres_summary.iterations[i];
        bool first = i == 0 && iterations == 0 && round == 0 && extrapolations == 0;
        if ((first || (i > 0 && it.step_is_successful)) && trace_count < CF_LSQ_TRACE)
          summary->trace[trace_count++] = it.cost;
      }
      iterations += std::max(0, static_cast<int>(ceres_summary.iterations.size()) - 1);
      seconds += ceres_summary.total_time_in_seconds;
      if (ceres_summary.termination_type == ceres::FAILURE) break;
      if (watcher.stopped()) {
        summary->stopped = 1;
        break;
      }
      // a chunk ended, or the solve converged: with steps too short, a line
      // search along the last one, and on
      const bool chunk_ended = ceres_summary.termination_type == ceres::NO_CONVERGENCE;
      if (!watcher.any_hit() && iterations < options->max_iterations &&
          (chunk_ended || ceres_summary.termination_type == ceres::CONVERGENCE)) {
        bool moved = under_stepping(ceres_summary) && !watcher.previous().empty() &&
                     extrapolate(problem, watcher.previous(), ceres_summary.final_cost,
                                 first_trial(ceres_summary), options->threads,
                                 options->line_search_tolerance);
        extrapolations += moved;
        if (chunk_ended || (moved && extrapolations < MAX_EXTRAPOLATIONS)) continue;
      }
      ++round;
      if (watcher.any_hit()) {  // pin and solve the rest
        for (int i = 0; i < n; ++i) {
          if (watcher.hit()[i] == 0) continue;
          closings[i] += watcher.closed()[i];
          active[i] = watcher.hit()[i];
          problem->x[i] = active[i] < 0 ? problem->lower[i] : problem->upper[i];
        }
        if (iterations < options->max_iterations) continue;
      }
      // the end of a solve: which parameters at a bound stay there
      // (none at a bound: nothing to decide, and no pass for the gradient)
      std::vector<int> side(n);
      bool any_at_bound = false;
      for (int i = 0; i < n; ++i) {
        side[i] = watcher.side_of(static_cast<size_t>(i));
        any_at_bound |= side[i] != 0;
      }
      if (!any_at_bound) break;
      std::vector<int> pinned;
      std::vector<int> by_newton(n);  // freed once, or pinned for closing in
      for (int i = 0; i < n; ++i) by_newton[i] = freed[i] || closings[i] > 0 || by_start[i];
      if (!pinned_at_bounds(problem, options->threads, &caches, side, by_newton, &pinned)) break;
      bool released = false;
      for (int i = 0; i < n; ++i) {
        if (active[i] != 0 && pinned[i] == 0) released = true, freed[i] = 1;
        active[i] = pinned[i];
      }
      if (!released || iterations >= options->max_iterations) break;
    }
    if (problem->at_bound != nullptr) std::copy(active.begin(), active.end(), problem->at_bound);
    summary->final_normal = 0;
    if (options->final_jtj != nullptr && ceres_summary.termination_type != ceres::FAILURE) {
      double cost;  // (the blocks' kept evaluations at x, or a pass)
      summary->final_normal =
          normal_equations(problem, options->threads, &caches, options->final_jtj, nullptr, &cost);
    }
    summary->initial_cost = initial_cost;
    summary->final_cost = ceres_summary.final_cost;
    summary->iterations = iterations;
    summary->trace_count = trace_count;
    summary->converged = ceres_summary.termination_type == ceres::CONVERGENCE;
    summary->seconds = seconds;
    summary->final_radius = radius;
    copy_termination(ceres_summary, summary);
    if (ceres_summary.termination_type == ceres::FAILURE)
      return cf_error_set(err, CF_ENUMERIC, "the solver failed: %s", ceres_summary.message.c_str());
    return CF_OK;
  } catch (const std::bad_alloc &) {
    return cf_error_set(err, CF_ENOMEM, "out of memory in the solver");
  } catch (const std::exception &e) {
    return cf_error_set(err, CF_ENUMERIC, "the solver failed: %s", e.what());
  } catch (...) {
    return cf_error_set(err, CF_ENUMERIC, "the solver failed");
  }
}
