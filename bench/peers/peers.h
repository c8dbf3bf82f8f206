// clayfit-peers' common problem (peers.cpp) and its contestants beside
// clayfit: Ceres over the templated model or the C evaluator
// (peers_ceres.cpp) and SciPy's least_squares (peers_scipy.cpp).
#ifndef CLAYFIT_BENCH_PEERS_H
#define CLAYFIT_BENCH_PEERS_H

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

extern "C" {
#include "clayfit/model.h"
}

namespace peers {

constexpr double kCostTolerance = 1e-6;    // |cost − clayfit's| / clayfit's
constexpr double kModelTolerance = 1e-10;  // relative, of the prediction

struct Options {
  std::string capture, json, python = "/usr/bin/python3", script, work = "/tmp", truth;
  double perturb = 0.05;
  cf_model_id model = CF_MODEL_DIELECTRIC;
  size_t max_obs = 0;
  int threads = 2, max_iterations = 100;
  bool autodiff = true, numeric = true, analytic = true, scipy = true, check = false;
};

// The common problem's data, one observation after another.
struct Data {
  cf_model_id model;
  int dim = 0, lights = 0;
  size_t count = 0;
  std::vector<uint32_t> index;
  std::vector<double> n, v, l, e, y;  // 3, 3, 3 L, 3 L, 3 per observation
  std::vector<double> lower, upper;
};

struct Outcome {
  std::string name;
  bool ran = false, skipped = false;
  std::string note;
  double seconds = 0.0, solve_seconds = 0.0, cost = NAN, solver_cost = NAN;
  int iterations = 0, evaluations = -1, jacobians = -1;
  double model_error = 0.0;  // worst relative difference from the C evaluator
  bool model_ok = true;
  std::vector<double> params;
};

enum class Derivatives { kAuto, kNumeric, kAnalytic };

// Ceres (peers_ceres.cpp): one residual block per observation, derivatives
// by how, from start, within the bounds; its outcome in *out.
void SolveCeresFor(const Data &d, const std::vector<double> &start, const Options &o,
                   Derivatives how, Outcome *out);

// The templated model's (the Ceres peers') worst relative difference from
// the C evaluator's prediction pred_c at params (peers_ceres.cpp).
double TemplatedModelError(const Data &d, const double *params, const std::vector<double> &pred_c);

// SciPy's least_squares through scripts/peer_scipy.py (peers_scipy.cpp).
void SolveScipy(const Data &d, const std::vector<double> &start, const std::vector<double> &pred_c,
                const Options &o, Outcome *out);

// A JSON array of doubles, every digit kept.
std::string JsonArray(const std::vector<double> &a);

}  // namespace peers

#endif  // CLAYFIT_BENCH_PEERS_H
