/* Test cases shared by the evaluator tests: random in-range parameters,
 * random and grazing directions, the grid of hard cases, and a finite-
 * difference gradient following docs/model.md §4 (the properties every
 * model must satisfy). */
#ifndef CLAYFIT_TEST_CASES_H
#define CLAYFIT_TEST_CASES_H

#include <stddef.h>

#include "clayfit/model.h"
#include "core/rng.h"

/* Uniform in-range parameters; with probability p_bound each parameter
 * sits exactly at one of its bounds instead. */
void random_params(cf_rng *rng, cf_model_id model, double p_bound, double *params);

/* A random observation: random unit normal, l and v on its hemisphere;
 * with probability p_grazing one or both cosines are made tiny
 * (10^-1 .. 10^-12), with probability p_equal l = v. */
void random_directions(cf_rng *rng, double p_grazing, double p_equal, double n[3], double l[3],
                       double v[3]);

/* Directions from cosines and azimuths about n = (0, 0, 1), exact for
 * tiny cosines (sin θ = sqrt((1 − c)(1 + c))). */
void direction_from(double c, double phi, double out[3]);

/* The hard-case grid of geometries: cosines {1, 0.5, 1e-3, 1e-8, 1e-150,
 * 1e-300, 0} on either side, azimuths with l = v, l mirrored about n and
 * a perpendicular pair, l + v = 0 at the horizon, in the z-up frame and in
 * a tilted frame. Returns the count written (at most max). */
size_t hard_geometries(double (*n)[3], double (*l)[3], double (*v)[3], size_t max);

/* Parameter sets on the corners of the range: every parameter at lower,
 * upper or default (RGB ones equal in all channels), plus optical_depth
 * 1e3 for M4. Calls visit(params, user) for each; returns the count. */
long for_each_extreme_params(cf_model_id model, void (*visit)(const double *params, void *user),
                             void *user);

/* The finite difference of docs/model.md (34) of f_c in parameter k: step
 * h = 1e-6 max(|x|, 1), central inside the range, one-sided (second
 * order) where a step would leave it. *one_sided tells which was used.
 * quotient[c] = max over the stencil's points x_j of |f(x_j) − f(x)| / h:
 * the scale of change the stencil sees. It equals |∂f/∂x| where f is
 * smooth and stays meaningful where the derivative vanishes but higher
 * ones do not (σ = 0 at grazing: f = A + B(σ) x, B ≈ 5σ², x up to 1e150). */
void finite_difference(cf_model_id model, const double *params, int k, const double n[3],
                       const double l[3], const double v[3], double g_fd[3], double quotient[3],
                       int *one_sided);

#endif /* CLAYFIT_TEST_CASES_H */
