// The residual blocks as Ceres sees them (lsq_blocks.h).
#include "lsq_blocks.h"

#include <cmath>
#include <cstdarg>
#include <cstdio>

#include <Eigen/Core>

#include "lsq/linalg.h"

namespace lsq {

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
// 20, whose normal equations are seldom asked for. (Without it DiLiGenT's
// fit on every observation took 1.18x the wall time, the same 17
// iterations; docs/solver.md, "speculation".)
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
    // JᵀJ = S⁻¹ M S⁻¹ with M of unit diagonal (S = diag(JᵀJ)^(−1/2); 1 for
    // a column of 0), and M's eigenvalues cut: a direction is dropped for
    // what the block sees of it, not for its scale (block 0 holds the
    // response's prior, in its own units, beside data in σ's: at σ 5e-9,
    // a noise-free EXR capture's, the prior fell below 1e-14 of the data
    // and its slope drifted)
    Eigen::VectorXd unit(k);
    for (int c = 0; c < k; ++c) {
      const double d = jtj(c, c);
      unit(c) = d > 0.0 && std::isfinite(d) ? 1.0 / std::sqrt(d) : 1.0;
    }
    std::vector<double> scaled(static_cast<size_t>(k) * k), values(k), vectors(scaled.size());
    for (int r = 0; r < k; ++r)
      for (int c = 0; c < k; ++c)
        scaled[static_cast<size_t>(r) * k + c] = unit(r) * jtj(r, c) * unit(c);  // as Eigen's D J D
    if (!cf_symmetric_eigen(k, scaled.data(), values.data(), vectors.data())) return false;
    const Eigen::MatrixXd v = Eigen::Map<const RowMajor>(vectors.data(), k, k);
    const Eigen::VectorXd scaled_jtu = unit.cwiseProduct(jtu);
    const double largest = std::max(0.0, *std::max_element(values.begin(), values.end()));
    double projected = 0.0;
    std::fill(jacobian, jacobian + static_cast<size_t>(k + 1) * n, 0.0);
    for (int i = 0; i < k; ++i) {
      const double lambda = values[i];
      residuals[i] = 0.0;
      if (!(lambda > 1e-14 * largest)) continue;  // a direction the block does not see
      const double root = std::sqrt(lambda);
      residuals[i] = v.col(i).dot(scaled_jtu) / root;
      projected += residuals[i] * residuals[i];
      for (int c = 0; c < k; ++c)
        jacobian[static_cast<size_t>(i) * n + columns_[c]] =
            root * v(c, i) / unit(c);
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

ceres::CostFunction *new_block_cost(const cf_lsq_problem *problem, size_t block,
                                    BlockCache *cache) {
  return new BlockCost(problem, block, cache);
}

// cf_lsq_normal_equations, from the blocks' caches where they hold x
// (caches: one per block, or nullptr).
int normal_equations(const cf_lsq_problem *problem, int threads, std::vector<BlockCache> *caches,
                     double *jtj, double *jtu, double *cost) {
  const int n = problem->num_params;
  const size_t count = static_cast<size_t>(std::max(1, threads));
  std::vector<std::vector<double>> sum_jtj(count), sum_jtu(count);
  std::vector<double> sum_cost(count, 0.0);
  std::vector<char> failed(count, 0);
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
      if (e == nullptr) {
        failed[t] = cache.failed;
        return false;
      }
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
  if (!ok)
    return std::any_of(failed.begin(), failed.end(), [](char f) { return f != 0; })
               ? CF_LSQ_FAILED
               : CF_LSQ_NOT_FINITE;
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
  return CF_LSQ_EVALUATED;
}

// The total cost at x (NaN when a block cannot be evaluated there), the
// blocks shared among `threads` threads.
double cost_at(const cf_lsq_problem *problem, const double *x, int threads) {
  const size_t count = static_cast<size_t>(std::max(1, threads));
  std::vector<double> partial(count, 0.0);
  const bool ok = in_threads(count, [&](size_t t) {
    for (size_t b = t; b < problem->num_blocks; b += count) {
      double cost;
      if (problem->evaluate(problem->user, x, b, &cost, nullptr, nullptr) != CF_LSQ_EVALUATED)
        cost = NAN;
      partial[t] += cost;
    }
    return true;
  });
  double total = 0.0;
  for (double p : partial) total += p;
  return ok ? total : NAN;
}

void trace(const cf_lsq_options *options, const char *format, ...) {
  if (options->trace == nullptr) return;
  char line[256];
  va_list args;
  va_start(args, format);
  std::vsnprintf(line, sizeof line, format, args);
  va_end(args);
  options->trace(options->trace_user, line);
}

}  // namespace lsq

extern "C" int cf_lsq_normal_equations(const cf_lsq_problem *problem, int threads, double *jtj,
                                       double *jtu, double *cost) {
  try {
    return lsq::normal_equations(problem, threads, nullptr, jtj, jtu, cost);
  } catch (...) {  // out of memory for the sums: nothing crosses into C
    return CF_LSQ_FAILED;
  }
}
