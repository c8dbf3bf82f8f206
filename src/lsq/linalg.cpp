// Dense symmetric linear algebra by Eigen (linalg.h). No exception crosses
// the C boundary.
#include "linalg.h"

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
