// Dense symmetric linear algebra by Eigen (linalg.h). No exception crosses
// the C boundary.
#include "lsq/linalg.h"

#include <Eigen/Dense>

#include <cmath>

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
