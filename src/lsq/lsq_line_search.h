// A line search between chunks of a solve (lsq_line_search.cpp). Where
// the residuals are large and systematic (a real capture the model does not
// explain to the noise), their own curvature cancels part of JᵀJ along some
// direction: Gauss-Newton's steps are too short there, each keeping more
// than its model promised, and Levenberg-Marquardt converges linearly. A
// search along the last step finds the minimum along it in a few cost
// passes. (Without it DiLiGenT's forced M4 fit took 54 iterations instead
// of 24, 1.25x the wall time; docs/solver.md, "line search".) Private to
// src/lsq.
#ifndef CLAYFIT_LSQ_LINE_SEARCH_H
#define CLAYFIT_LSQ_LINE_SEARCH_H

#include <ceres/solver.h>

#include <vector>

#include "lsq/lsq.h"

namespace lsq {

// Did the chunk's successful steps decrease the cost by more than their
// model predicted (mean ratio of actual to predicted above 1.25)?
bool under_stepping(const ceres::Solver::Summary &summary);

// Where the search along the chunk's last step starts (a power of 2).
double first_trial(const ceres::Solver::Summary &summary);

// A line search along the last step d = x − x0; returns whether x moved
// (to a lower cost by more than options->line_search_tolerance).
bool extrapolate(cf_lsq_problem *problem, const cf_lsq_options *options,
                 const std::vector<double> &x0, double cost, double first);

}  // namespace lsq

#endif  // CLAYFIT_LSQ_LINE_SEARCH_H
