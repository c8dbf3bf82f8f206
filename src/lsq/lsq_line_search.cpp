// A line search between chunks of a solve (lsq_line_search.h).
#include "lsq_line_search.h"

#include <algorithm>
#include <cmath>

#include "lsq_blocks.h"

namespace lsq {

bool under_stepping(const ceres::Solver::Summary &summary) {
  double sum = 0.0;
  int count = 0;
  for (const auto &it : summary.iterations)
    if (it.iteration > 0 && it.step_is_successful) sum += it.relative_decrease, ++count;
  return count >= 3 && sum / count > 1.25;  // fd063f4; 1.1, 1.5, 2, 5: fits move ≤ 0.06 sd (study)
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
bool extrapolate(cf_lsq_problem *problem, const cf_lsq_options *options,
                 const std::vector<double> &x0, double cost, double first) {
  const int n = problem->num_params, threads = options->threads;
  const double tolerance = options->line_search_tolerance;
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
    trace(options, "line search t = %g: cost %.9e (from %.9e)", t, c, cost);
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
        trace(options, "line search t = %g (parabola): cost %.9e", t, ct);
        if (ct < c_best) c_best = ct, at_best = trial;
      }
    }
  }
  std::copy(at_best.begin(), at_best.end(), problem->x);
  return true;
}

}  // namespace lsq
