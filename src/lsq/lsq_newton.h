// The reduced Gauss-Newton step of the bounds' active set (defined in
// linalg.cpp, with the project's other Eigen decompositions). Private to
// src/lsq.
#ifndef CLAYFIT_LSQ_NEWTON_H
#define CLAYFIT_LSQ_NEWTON_H

#include <vector>

namespace lsq {

// The Gauss-Newton step over the parameters not pinned (pinned[i] != 0;
// pinned may be null) of the normal equations jtj (n × n, row-major) and
// gradient g: free_index gets the free parameters, step their components,
// in that order; returns the decrement ½ gᵀ H⁺ g (0 when nothing is
// free, HUGE_VAL when H cannot be decomposed). Throws std::bad_alloc.
double reduced_newton_step(int n, const double *jtj, const double *g, const int *pinned,
                           std::vector<int> *free_index, std::vector<double> *step);

}  // namespace lsq

#endif  // CLAYFIT_LSQ_NEWTON_H
