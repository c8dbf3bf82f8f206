// clayfit-peers' Ceres contestants: the idiomatic layout, one residual
// block per observation, with AutoDiffCostFunction and
// NumericDiffCostFunction (CENTRAL) over the templated model (jet_model.h)
// and with the C evaluator's analytic derivatives (ObservationAnalytic).
#include <ceres/ceres.h>
#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "jet_model.h"
#include "peers.h"
#include "peers_clayfit.h"

namespace peers {
namespace {

using clayfit_jet::Vec3;

// Observation i's prediction Σ_j f E_j c_i,j (3 channels) at p.
template <typename T>
void Predict(const Data &d, size_t i, const T *p, T out[3]) {
  const double *n = &d.n[3 * i], *v = &d.v[3 * i];
  out[0] = out[1] = out[2] = T(0.0);
  for (int j = 0; j < d.lights; ++j) {
    const double *l = &d.l[3 * (i * d.lights + j)], *e = &d.e[3 * (i * d.lights + j)];
    const Vec3<double> nn{n[0], n[1], n[2]}, ll{l[0], l[1], l[2]}, vv{v[0], v[1], v[2]};
    const double c_i = clayfit_jet::Dot(nn, ll);
    if (!(c_i > 0.0) || (e[0] == 0.0 && e[1] == 0.0 && e[2] == 0.0)) continue;
    T f[3] = {T(0.0), T(0.0), T(0.0)};
    clayfit_jet::Eval(d.model, p, nn, ll, vv, f);
    for (int c = 0; c < 3; ++c) out[c] += f[c] * (e[c] * c_i);
  }
}

// One observation's three residuals: the idiomatic Ceres residual block.
struct ObservationResidual {
  const Data *data;
  size_t i;
  template <typename T>
  bool operator()(const T *p, T *r) const {
    T pred[3];
    Predict(*data, i, p, pred);
    for (int c = 0; c < 3; ++c) r[c] = pred[c] - data->y[3 * i + c];
    return true;
  }
};

// One observation's three residuals with the C evaluator's analytic
// derivatives: the idiomatic Ceres layout (one residual block per
// observation, Ceres forming J) around clayfit's own model, so that the
// only difference from clayfit is the layout of the problem (clayfit hands
// Ceres each block of a thousand observations compressed to its normal
// equations, src/lsq/include/lsq/lsq.h).
class ObservationAnalytic final : public ceres::CostFunction {
 public:
  ObservationAnalytic(const Data *d, size_t i) : d_(d), i_(i) {
    set_num_residuals(3);
    mutable_parameter_block_sizes()->push_back(d->dim);
  }
  bool Evaluate(double const *const *parameters, double *residuals,
                double **jacobians) const override {
    const Data &d = *d_;
    const double *n = &d.n[3 * i_], *v = &d.v[3 * i_], *p = parameters[0];
    double *jacobian = jacobians != nullptr ? jacobians[0] : nullptr;
    for (int c = 0; c < 3; ++c) residuals[c] = -d.y[3 * i_ + c];
    if (jacobian != nullptr) std::fill(jacobian, jacobian + 3 * d.dim, 0.0);
    // (on the stack: Ceres calls this for every observation of every pass)
    double grad[3 * CF_MAX_DIM];
    for (int j = 0; j < d.lights; ++j) {
      const double *l = &d.l[3 * (i_ * d.lights + j)], *e = &d.e[3 * (i_ * d.lights + j)];
      const double c_i = n[0] * l[0] + n[1] * l[1] + n[2] * l[2];
      if (!(c_i > 0.0) || (e[0] == 0.0 && e[1] == 0.0 && e[2] == 0.0)) continue;
      double f[3];
      if (cf_eval(d.model, p, n, l, v, f, jacobian != nullptr ? grad : nullptr) != CF_OK)
        return false;
      for (int c = 0; c < 3; ++c) {
        residuals[c] += f[c] * (e[c] * c_i);
        if (jacobian == nullptr) continue;
        for (int k = 0; k < d.dim; ++k)
          jacobian[c * d.dim + k] += grad[c * d.dim + k] * (e[c] * c_i);
      }
    }
    return true;
  }

 private:
  const Data *d_;
  size_t i_;
};

void QuietGlog() {
  static bool done = false;
  if (!done) {
    google::InitGoogleLogging("clayfit-peers");
    FLAGS_minloglevel = google::GLOG_WARNING;
    done = true;
  }
}

template <int Dim, Derivatives How>
ceres::CostFunction *MakeCost(const Data *d, size_t i) {
  if constexpr (How == Derivatives::kAnalytic)
    return new ObservationAnalytic(d, i);
  else if constexpr (How == Derivatives::kNumeric)
    return new ceres::NumericDiffCostFunction<ObservationResidual, ceres::CENTRAL, 3, Dim>(
        new ObservationResidual{d, i});
  else
    return new ceres::AutoDiffCostFunction<ObservationResidual, 3, Dim>(
        new ObservationResidual{d, i});
}

template <int Dim, Derivatives How>
void SolveCeres(const Data &d, const std::vector<double> &start, const Options &o, Outcome *out) {
  QuietGlog();
  double t0 = peers_now();
  std::vector<double> x = start;
  ceres::Problem problem;
  for (size_t i = 0; i < d.count; ++i)
    problem.AddResidualBlock(MakeCost<Dim, How>(&d, i), nullptr, x.data());
  for (int k = 0; k < Dim; ++k) {
    problem.SetParameterLowerBound(x.data(), k, d.lower[k]);
    problem.SetParameterUpperBound(x.data(), k, d.upper[k]);
  }
  ceres::Solver::Options so;
  so.minimizer_type = ceres::TRUST_REGION;
  so.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  so.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  so.num_threads = o.threads;
  so.max_num_iterations = o.max_iterations;
  so.function_tolerance = 1e-10;  // cf_lsq_default_options'
  so.gradient_tolerance = 1e-12;
  so.parameter_tolerance = 1e-10;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  double t1 = peers_now();
  ceres::Solve(so, &problem, &summary);
  double t2 = peers_now();
  out->ran = true;
  out->seconds = t2 - t0;
  out->solve_seconds = t2 - t1;
  out->solver_cost = summary.final_cost;
  out->iterations = std::max(0, static_cast<int>(summary.iterations.size()) - 1);
  out->note = ceres::TerminationTypeToString(summary.termination_type);
  out->params = x;
}

template <int Dim>
void SolveCeresHow(const Data &d, const std::vector<double> &start, const Options &o,
                   Derivatives how, Outcome *out) {
  switch (how) {
    case Derivatives::kAuto:
      return SolveCeres<Dim, Derivatives::kAuto>(d, start, o, out);
    case Derivatives::kNumeric:
      return SolveCeres<Dim, Derivatives::kNumeric>(d, start, o, out);
    case Derivatives::kAnalytic:
      return SolveCeres<Dim, Derivatives::kAnalytic>(d, start, o, out);
  }
}

// Relative difference of a prediction from the C evaluator's, against the
// larger of its own size and 1e-6 of the largest prediction (a grazing
// pixel's prediction near 0 has no relative digits to compare).
double RelativeDifference(double a, double c, double scale) {
  return std::fabs(a - c) / std::max(std::fabs(c), 1e-6 * scale);
}

double LargestAbs(const std::vector<double> &v) {
  double m = 0.0;
  for (double x : v) m = std::max(m, std::fabs(x));
  return m;
}

}  // namespace

void SolveCeresFor(const Data &d, const std::vector<double> &start, const Options &o,
                   Derivatives how, Outcome *out) {
  if (d.model == CF_MODEL_DIELECTRIC)
    SolveCeresHow<CF_DIELECTRIC_DIM>(d, start, o, how, out);
  else
    SolveCeresHow<CF_CLAY_DIM>(d, start, o, how, out);
}

double TemplatedModelError(const Data &d, const double *params, const std::vector<double> &pred_c) {
  const double scale = LargestAbs(pred_c);
  double worst = 0.0;
  for (size_t i = 0; i < d.count; ++i) {
    double p[3];
    Predict(d, i, params, p);
    for (int c = 0; c < 3; ++c)
      worst = std::max(worst, RelativeDifference(p[c], pred_c[3 * i + c], scale));
  }
  return worst;
}

}  // namespace peers
