// Dense symmetric linear algebra by Eigen (linalg.h), and the solver's own
// (cf_lsq_covariance, lsq.h; the reduced Newton step, lsq_newton.h): the
// project's Eigen decompositions in one file, compiled once (four files
// each instantiating them took half the demo's build). No exception
// crosses the C boundary.
#include "lsq/linalg.h"
#include "lsq/lsq.h"
#include "lsq_newton.h"

#include <Eigen/Dense>

#include <cmath>
#include <new>
#include <vector>

namespace {

using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

bool all_finite(int n, const double *a) {
  for (long i = 0; i < static_cast<long>(n) * n; ++i)
    if (!std::isfinite(a[i])) return false;
  return true;
}

}  // namespace

extern "C" int cf_symmetric_eigen(int n, const double *a, double *values, double *vectors) {
  if (n <= 0 || !all_finite(n, a)) return 0;
  try {
    Eigen::Map<const RowMajor> m(a, n, n);
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(
        m, vectors != nullptr ? Eigen::ComputeEigenvectors : Eigen::EigenvaluesOnly);
    if (eigen.info() != Eigen::Success) return 0;
    Eigen::Map<Eigen::VectorXd>(values, n) = eigen.eigenvalues();
    if (vectors != nullptr) Eigen::Map<RowMajor>(vectors, n, n) = eigen.eigenvectors();
    return 1;
  } catch (...) {
    return 0;
  }
}

extern "C" int cf_cholesky_solve(int n, const double *a, const double *b, double *x) {
  if (n <= 0 || !all_finite(n, a)) return 0;
  try {
    Eigen::Map<const RowMajor> m(a, n, n);
    Eigen::LLT<Eigen::MatrixXd> llt(m);
    if (llt.info() != Eigen::Success) return 0;
    Eigen::Map<Eigen::VectorXd>(x, n) = llt.solve(Eigen::Map<const Eigen::VectorXd>(b, n));
    for (int i = 0; i < n; ++i)
      if (!std::isfinite(x[i])) return 0;
    return 1;
  } catch (...) {
    return 0;
  }
}

namespace {

// 1/√diag (0 where the diagonal is not positive), for a unit diagonal.
Eigen::VectorXd unit_diagonal_scale(const Eigen::MatrixXd &a) {
  Eigen::VectorXd scale(a.rows());
  for (Eigen::Index i = 0; i < a.rows(); ++i)
    scale(i) = a(i, i) > 0.0 ? 1.0 / std::sqrt(a(i, i)) : 0.0;
  return scale;
}

// The pseudo-inverse of the symmetric a, scaled to a unit diagonal, its
// eigenvalues below `relative` of the largest dropped.
Eigen::MatrixXd scaled_pseudo_inverse(const Eigen::MatrixXd &a, double relative) {
  const Eigen::VectorXd scale = unit_diagonal_scale(a);
  const Eigen::MatrixXd scaled = scale.asDiagonal() * a * scale.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(scaled);
  const Eigen::VectorXd &values = eigen.eigenvalues();
  const double largest = values.size() > 0 ? values(values.size() - 1) : 0.0;
  Eigen::VectorXd inverse(values.size());
  for (Eigen::Index i = 0; i < values.size(); ++i)
    inverse(i) = largest > 0.0 && values(i) > relative * largest ? 1.0 / values(i) : 0.0;
  const Eigen::MatrixXd &v = eigen.eigenvectors();
  return scale.asDiagonal() * (v * inverse.asDiagonal() * v.transpose()) * scale.asDiagonal();
}

}  // namespace

extern "C" int cf_schur_covariance(int n, int g, const double *a, double *covariance,
                                   double *weakest) {
  if (n <= 0 || g <= 0 || g > n || !all_finite(n, a)) return -1;
  constexpr double relative = 1e-10;  // 69a8156; 1e-12, 1e-8: no screened fit moves (study)
  try {
    const int m = n - g;
    Eigen::Map<const RowMajor> full(a, n, n);
    Eigen::MatrixXd schur = full.bottomRightCorner(g, g);
    if (m > 0) {
      const Eigen::MatrixXd b = full.topRightCorner(m, g);
      schur -= b.transpose() * scaled_pseudo_inverse(full.topLeftCorner(m, m), relative) * b;
    }
    schur = 0.5 * (schur + schur.transpose()).eval();
    Eigen::Map<Eigen::VectorXd> weak(weakest, g);
    for (int i = 0; i < g; ++i)  // a gain no observation moves
      if (!(schur(i, i) > 0.0)) {
        weak.setZero();
        weak(i) = 1.0;
        return 0;
      }
    const Eigen::VectorXd scale = unit_diagonal_scale(schur);
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(scale.asDiagonal() * schur *
                                                         scale.asDiagonal());
    if (eigen.info() != Eigen::Success) return -1;
    const Eigen::VectorXd &values = eigen.eigenvalues();  // ascending
    if (!(values(0) > relative * values(g - 1))) {
      weak = (scale.asDiagonal() * eigen.eigenvectors().col(0)).normalized();
      return 0;
    }
    const Eigen::MatrixXd &v = eigen.eigenvectors();
    Eigen::Map<RowMajor>(covariance, g, g) =
        scale.asDiagonal() * (v * values.cwiseInverse().asDiagonal() * v.transpose()) *
        scale.asDiagonal();
    return 1;
  } catch (...) {
    return -1;
  }
}

extern "C" int cf_sandwich(int n, const double *a, double *b) {
  if (n <= 0) return 0;
  try {
    Eigen::Map<const RowMajor> inverse(a, n, n);
    Eigen::Map<RowMajor> scores(b, n, n);
    RowMajor product = inverse * scores * inverse;
    scores = 0.5 * (product + product.transpose());
    return 1;
  } catch (...) {
    return 0;
  }
}

extern "C" cf_status cf_lsq_covariance(int n, const double *jtj, double *covariance,
                                       int *rank_deficient, cf_error *err) {
  try {
    using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    Eigen::Map<const RowMajor> a(jtj, n, n);
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(a);
    if (eigen.info() != Eigen::Success)
      return cf_error_set(err, CF_ENUMERIC, "the normal matrix could not be decomposed");
    // singular when the smallest eigenvalue is below 1e-12 of the largest:
    // ceres::Covariance's DENSE_SVD test on J, whose singular values are
    // their square roots (min_reciprocal_condition_number 1e-12)
    const Eigen::VectorXd &values = eigen.eigenvalues();  // ascending
    const double largest = values(n - 1);
    if (!(largest > 0.0) || !(values(0) >= 1e-12 * largest)) {
      if (rank_deficient) *rank_deficient = 1;
      return CF_OK;
    }
    if (rank_deficient) *rank_deficient = 0;
    const Eigen::MatrixXd &v = eigen.eigenvectors();  // (JᵀJ)⁻¹ = V Λ⁻¹ Vᵀ
    Eigen::Map<RowMajor>(covariance, n, n) = v * values.cwiseInverse().asDiagonal() * v.transpose();
    return CF_OK;
  } catch (const std::bad_alloc &) {
    return cf_error_set(err, CF_ENOMEM, "out of memory for the covariance");
  } catch (...) {
    return cf_error_set(err, CF_ENUMERIC, "the covariance failed");
  }
}

namespace lsq {

// The Gauss-Newton step of the parameters not pinned (pinned[i] == 0)
// with the pinned ones held: d = −H⁺ g over the free ones, H their block
// of jtj (n × n, row-major), H⁺ its pseudo-inverse V Λ⁺ Vᵀ with
// eigenvalues below 1e-12 of the largest dropped (a direction no data see
// takes no step). free_index gets the free parameters, step their
// components, in that order; returns the decrement ½ gᵀ H⁺ g, the cost
// the quadratic model says the step removes (0 when nothing is free).
double reduced_newton_step(int n, const double *jtj, const double *g, const int *pinned,
                           std::vector<int> *free_index, std::vector<double> *step) {
  free_index->clear();
  for (int i = 0; i < n; ++i)
    if (pinned == nullptr || pinned[i] == 0) free_index->push_back(i);
  const int m = static_cast<int>(free_index->size());
  step->assign(m, 0.0);
  if (m == 0) return 0.0;
  Eigen::MatrixXd h(m, m);
  Eigen::VectorXd minus_g(m);
  for (int a = 0; a < m; ++a) {
    minus_g(a) = -g[(*free_index)[a]];
    for (int b = 0; b < m; ++b)
      h(a, b) = jtj[static_cast<size_t>((*free_index)[a]) * n + (*free_index)[b]];
  }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(h);
  if (eigen.info() != Eigen::Success) return HUGE_VAL;
  const Eigen::VectorXd &values = eigen.eigenvalues();  // ascending
  const Eigen::MatrixXd &v = eigen.eigenvectors();
  const Eigen::VectorXd projection = v.transpose() * minus_g;
  Eigen::VectorXd scaled = Eigen::VectorXd::Zero(m);
  double decrement = 0.0;
  for (int i = 0; i < m; ++i) {
    if (!(values(i) > 1e-12 * values(m - 1))) continue;
    scaled(i) = projection(i) / values(i);
    decrement += 0.5 * projection(i) * scaled(i);
  }
  Eigen::Map<Eigen::VectorXd>(step->data(), m) = v * scaled;
  return decrement;
}

}  // namespace lsq
