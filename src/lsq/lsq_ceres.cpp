// The Ceres adapter behind lsq.h: Levenberg-Marquardt with dense normal
// equations (few parameters, many residuals) over the compressed residual
// blocks (lsq_blocks.h), bounds as Ceres bounds with an active set on top
// (lsq_bounds.h), in chunks with a line search between them
// (lsq_line_search.h); the covariance from the normal matrix's
// eigen-decomposition. What each device buys, measured, is in
// docs/solver.md. No exception crosses the C boundary.
#include <ceres/manifold.h>
#include <ceres/problem.h>
#include <ceres/solver.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <new>
#include <vector>

#include "lsq/lsq.h"
#include "lsq_blocks.h"
#include "lsq_bounds.h"
#include "lsq_line_search.h"

namespace {

using lsq::BlockCache;
using lsq::BoundWatcher;

// A solve runs in chunks of CHUNK iterations, each a ceres::Solve that
// carries the last one's trust region, with a line search between chunks
// whose steps kept more than their model promised (lsq_line_search.h).
// Without the chunks the search comes only at the end: DiLiGenT's forced M4
// fit took 54 iterations instead of 24, its every-observation fit 1.33x the
// CPU time (docs/solver.md, "chunks").
constexpr int CHUNK = 8;
// Rounds of pinning and freeing at the bounds, and line searches, at most.
// MAX_ROUNDS (fd063f4, not measured) ends 228 of 7565 solves in the fit tests, 218 of them
// multi-start starts; at 100, 10 of 31 screened fits move, 2 to another minimum
// (studies/2026-12-07-tuned-constants.md). MAX_EXTRAPOLATIONS is a bound: 5 at most there.
constexpr int MAX_ROUNDS = 8, MAX_EXTRAPOLATIONS = 50;
// Ceres' floor of the trust region (Solver::Options::min_trust_region_radius):
// a radius below it is convergence, and a solve cannot start from it.
constexpr double MIN_RADIUS = 1e-32;
// The trust region a round that freed a parameter at most starts from
// (Ceres' default start): the radius carried from a converged round (up
// to 1e14) makes the first steps with the freed ones Gauss-Newton steps
// the box shortens, each keeping 0.2 % of its promised decrease while Ceres
// halves the radius (DiLiGenT's M4 candidate: 28 such steps, 7 of them
// rejected, from 4e14 down to 4e3).
constexpr double RELEASE_RADIUS = 1e4;

// One ceres::Solve of at most max_iterations over the blocks (caches: one
// per block) with the parameters flagged in `active` held, from the trust
// region `radius`.
void solve_chunk(cf_lsq_problem *problem, const cf_lsq_options *options,
                 const std::vector<int> &active, int max_iterations, double radius,
                 std::vector<BlockCache> *caches, BoundWatcher *watcher,
                 ceres::Solver::Summary *summary) {
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  problem_options.manifold_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem ceres_problem(problem_options);
  ceres_problem.AddParameterBlock(problem->x, problem->num_params);
  for (size_t b = 0; b < problem->num_blocks; ++b)
    ceres_problem.AddResidualBlock(lsq::new_block_cost(problem, b, &(*caches)[b]), nullptr,
                                   problem->x);
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
  // the trust region where the last chunk (or, cf_lsq_options.
  // initial_radius, the last solve) left it: Ceres' 1e4 damps the weak
  // directions again every time (the 16-image capture's fit on the
  // default budget 17 iterations instead of 10, 1.21x the CPU time;
  // docs/solver.md, "radius")
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
  solver_options.callbacks.push_back(watcher);         // (it traces every iteration)
  // Ceres' own reports, per solve: none (the solve traces its iterations
  // through cf_lsq_options.trace). glog's process-wide level is left to the
  // host: clayfit keeps glog's default, under which Ceres printed nothing in
  // the fit's tests (hard cases and ambiguous fits included) nor in
  // `clayfit fit` on nine captures (DiLiGenT, gains, M4T; 2026-12-07)
  solver_options.logging_type = ceres::SILENT;
  solver_options.minimizer_progress_to_stdout = false;
  ceres::Solve(solver_options, &ceres_problem, summary);
}

// How a solve ended, from its last chunk: converged when that did, else
// out of iterations (the iterations or the rounds of pins ran out).
cf_lsq_termination ending_of(const ceres::Solver::Summary &last, bool stopped) {
  if (last.termination_type == ceres::FAILURE) return CF_LSQ_END_FAILED;
  if (stopped) return CF_LSQ_END_STOPPED;
  if (last.termination_type == ceres::CONVERGENCE) return CF_LSQ_END_CONVERGED;
  return CF_LSQ_END_OUT_OF_ITERATIONS;
}

// One cf_lsq_solve: its state across chunks and rounds, and its steps.
class Solve {
 public:
  Solve(cf_lsq_problem *problem, const cf_lsq_options *options, cf_lsq_summary *summary)
      : p_(problem),
        o_(options),
        s_(summary),
        n_(problem->num_params),
        active_(n_, 0),
        freed_(n_, 0),
        closings_(n_, 0),
        by_start_(n_, 0),
        x0_(n_),
        caches_(problem->num_blocks),
        radius_(options->initial_radius > 0.0 ? std::max(options->initial_radius, MIN_RADIUS)
                                              : 1e4) {}

  cf_status run(cf_error *err) {
    pin_at_start();
    s_->stopped = 0;
    for (int round = 0; round < MAX_ROUNDS;) {
      BoundWatcher watcher(p_, o_, active_, closings_);
      chunk(round, &watcher);
      if (last_.termination_type == ceres::FAILURE) break;
      if (watcher.stopped()) {
        s_->stopped = 1;
        break;
      }
      if (search_along_last_step(watcher)) continue;
      ++round;
      if (watcher.any_hit()) {  // pin and solve the rest
        pin_hits(watcher);
        if (iterations_ < o_->max_iterations) continue;
      }
      if (!release_at_end(watcher) || iterations_ >= o_->max_iterations) break;
    }
    return finish(err);
  }

 private:
  // A start at a bound starts pinned there; with newton_start, so does a
  // parameter the Gauss-Newton step from the start takes out of the box
  // (lsq_bounds.h).
  void pin_at_start() {
    for (int i = 0; i < n_; ++i)
      active_[i] = p_->x[i] <= p_->lower[i] ? -1 : p_->x[i] >= p_->upper[i] ? 1 : 0;
    if (!o_->newton_start) return;
    std::vector<int> before = active_;
    // (normal equations that cannot be evaluated: no pins, and the solve
    // meets them itself)
    if (!lsq::newton_pins(p_, o_->threads, &caches_, &active_)) active_ = before;
    for (int i = 0; i < n_; ++i) by_start_[i] = active_[i] != 0 && before[i] == 0;
  }

  // One chunk, and its iterations into the summary's counts and trace.
  void chunk(int round, BoundWatcher *watcher) {
    const int budget = std::max(1, std::min(CHUNK, o_->max_iterations - iterations_));
    std::copy(p_->x, p_->x + n_, x0_.begin());
    solve_chunk(p_, o_, active_, budget, radius_, &caches_, watcher, &last_);
    lsq::trace(o_, "chunk of solve: round %d, %s", round, last_.message.c_str());
    if (!last_.iterations.empty()) radius_ = last_.iterations.back().trust_region_radius;
    // Ceres tests the iteration cap before the radius: a chunk can end out
    // of iterations with the radius already below the floor, which is
    // convergence (and which the next chunk would refuse as its start)
    if (radius_ < MIN_RADIUS) {
      last_.termination_type = ceres::CONVERGENCE;
      radius_ = MIN_RADIUS;
    }
    const bool first_chunk = chunks_++ == 0;
    if (first_chunk) s_->initial_cost = last_.initial_cost;
    for (size_t i = 0; i < last_.iterations.size(); ++i) {
      const ceres::IterationSummary &it = last_.iterations[i];
      if (((i == 0 && first_chunk) || (i > 0 && it.step_is_successful)) &&
          trace_count_ < CF_LSQ_TRACE)
        s_->trace[trace_count_++] = it.cost;
    }
    iterations_ += std::max(0, static_cast<int>(last_.iterations.size()) - 1);
    seconds_ += last_.total_time_in_seconds;
  }

  // After a chunk that ended (or converged) with no parameter at a bound:
  // with steps too short, a line search along the last one. True when the
  // solve goes on with another chunk.
  bool search_along_last_step(const BoundWatcher &watcher) {
    const bool chunk_ended = last_.termination_type == ceres::NO_CONVERGENCE;
    if (watcher.any_hit() || iterations_ >= o_->max_iterations ||
        !(chunk_ended || last_.termination_type == ceres::CONVERGENCE))
      return false;
    const bool moved =
        lsq::under_stepping(last_) && !watcher.previous().empty() &&
        lsq::extrapolate(p_, o_, watcher.previous(), last_.final_cost, lsq::first_trial(last_));
    extrapolations_ += moved;
    return chunk_ended || (moved && extrapolations_ < MAX_EXTRAPOLATIONS);
  }

  // The parameters the watcher stopped the chunk for, pinned at their
  // bounds.
  void pin_hits(const BoundWatcher &watcher) {
    for (int i = 0; i < n_; ++i) {
      if (watcher.hit()[i] == 0) continue;
      closings_[i] += watcher.closed()[i];
      active_[i] = watcher.hit()[i];
      p_->x[i] = active_[i] < 0 ? p_->lower[i] : p_->upper[i];
    }
  }

  // The end of a round: which parameters at a bound stay there
  // (lsq::pinned_at_bounds). True when one was released, and the solve
  // goes on.
  bool release_at_end(const BoundWatcher &watcher) {
    std::vector<int> side(n_);
    bool any_at_bound = false;
    for (int i = 0; i < n_; ++i) {
      side[i] = watcher.side_of(static_cast<size_t>(i));
      any_at_bound |= side[i] != 0;
    }
    if (!any_at_bound) return false;         // nothing to decide, no pass for the gradient
    std::vector<int> pinned, by_newton(n_);  // freed once, pinned for closing in or up front
    for (int i = 0; i < n_; ++i) by_newton[i] = freed_[i] || closings_[i] > 0 || by_start_[i];
    if (!lsq::pinned_at_bounds(p_, o_->threads, &caches_, side, by_newton, &pinned)) return false;
    bool released = false;
    for (int i = 0; i < n_; ++i) {
      if (active_[i] != 0 && pinned[i] == 0) released = true, freed_[i] = 1;
      active_[i] = pinned[i];
    }
    if (released) radius_ = std::min(radius_, RELEASE_RADIUS);
    return released;
  }

  cf_status finish(cf_error *err) {
    if (p_->at_bound != nullptr) std::copy(active_.begin(), active_.end(), p_->at_bound);
    s_->final_normal = 0;
    if (o_->final_jtj != nullptr && last_.termination_type != ceres::FAILURE) {
      double cost;  // (the blocks' kept evaluations at x, or a pass)
      s_->final_normal = lsq::normal_equations(p_, o_->threads, &caches_, o_->final_jtj, nullptr,
                                               &cost) == CF_LSQ_EVALUATED;
    }
    s_->final_cost = last_.final_cost;
    s_->iterations = iterations_;
    s_->trace_count = trace_count_;
    s_->ending = ending_of(last_, s_->stopped != 0);
    s_->converged = s_->ending == CF_LSQ_END_CONVERGED;
    s_->seconds = seconds_;
    s_->final_radius = radius_;
    if (std::any_of(caches_.begin(), caches_.end(), [](const BlockCache &c) { return c.failed; }))
      return cf_error_set(err, CF_ENOMEM, "out of memory evaluating the residuals");
    if (s_->ending == CF_LSQ_END_FAILED)
      return cf_error_set(err, CF_ENUMERIC, "the solver failed: %s", last_.message.c_str());
    return CF_OK;
  }

  cf_lsq_problem *p_;
  const cf_lsq_options *o_;
  cf_lsq_summary *s_;
  const int n_;
  std::vector<int> active_;    // −1/+1: pinned at the lower/upper bound
  std::vector<int> freed_;     // freed from a bound once in this solve
  std::vector<int> closings_;  // times pinned for closing in
  std::vector<int> by_start_;  // pinned by the Newton step at the start
  std::vector<double> x0_;
  std::vector<BlockCache> caches_;
  ceres::Solver::Summary last_;
  double radius_, seconds_ = 0.0;
  int iterations_ = 0, trace_count_ = 0, extrapolations_ = 0, chunks_ = 0;
};

}  // namespace

extern "C" cf_status cf_lsq_solve(cf_lsq_problem *problem, const cf_lsq_options *options,
                                  cf_lsq_summary *summary, cf_error *err) {
  try {
    Solve solve(problem, options, summary);
    return solve.run(err);
  } catch (const std::bad_alloc &) {
    return cf_error_set(err, CF_ENOMEM, "out of memory in the solver");
  } catch (const std::exception &e) {
    return cf_error_set(err, CF_ENUMERIC, "the solver failed: %s", e.what());
  } catch (...) {
    return cf_error_set(err, CF_ENUMERIC, "the solver failed");
  }
}

extern "C" const char *cf_lsq_termination_name(cf_lsq_termination termination) {
  switch (termination) {
    case CF_LSQ_END_CONVERGED:
      return "CONVERGENCE";
    case CF_LSQ_END_OUT_OF_ITERATIONS:
      return "NO_CONVERGENCE";
    case CF_LSQ_END_STOPPED:
      return "USER_SUCCESS";
    default:
      return "FAILURE";
  }
}


extern "C" void cf_lsq_default_options(cf_lsq_options *options) {
  options->max_iterations = 100;  // the fit passes its own (cf_fit_options.max_iterations)
  options->threads = 2;
  // the function tolerance stops the fit's solves: at Ceres' 1e-6, 28 of 29 screened fits move
  // (4 hold another slot, the rest up to 4.9 sd); the gradient and parameter tolerances at
  // Ceres' 1e-10 and 1e-8 move none of the 29 (bench/peers uses these too); the line
  // search's 1e-3 is fd063f4's: at 5e-4 1 of 10 fits moves (0.02 sd), at 2e-3 none (the study)
  options->function_tolerance = 1e-10;
  options->gradient_tolerance = 1e-12;
  options->parameter_tolerance = 1e-10;
  options->line_search_tolerance = 1e-3;
  options->min_relative_decrease = 1e-3;  // Ceres' default
  options->initial_radius = 1e4;          // Ceres' default
  options->newton_start = 0;
  options->stop = nullptr;
  options->stop_user = nullptr;
  options->final_jtj = nullptr;
  options->trace = nullptr;
  options->trace_user = nullptr;
}
