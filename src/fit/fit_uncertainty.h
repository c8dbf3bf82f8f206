/* The uncertainty of a fit: from the normal matrix JᵀJ at the solution
 * (fit_normal_equations), the covariance of the unknowns not at a bound
 * (ceres::Covariance, lsq.h) and the model slots the capture does not
 * constrain. Private to src/fit. */
#ifndef CLAYFIT_FIT_UNCERTAINTY_H
#define CLAYFIT_FIT_UNCERTAINTY_H

#include "fit_plan.h"
#include "fit_problem.h"

/* A model slot's standard deviation from its unknown's variance:
 * dρ = ρ d log ρ; dσ = dσ² / (2σ), and near σ = 0, where σ = √σ² is not
 * differentiable, the half-width √sd(σ²). */
double fit_slot_sd(const fit_problem *p, int slot, double variance);

/* The covariance of the unknowns not at a bound (those at one: rows and
 * columns 0); *rank_deficient when JᵀJ is singular there. */
cf_status fit_free_covariance(const fit_problem *p, const double *jtj, double *covariance,
                              int *rank_deficient, cf_error *err);

/* A pixel budget's covariance (sample weights set; nothing to do
 * otherwise). The weighted fit's normal matrix A = Σ w JᵀJ, w the
 * inverse of an observation's chance of being drawn, estimates the
 * information of every observation, which the sample does not hold; the
 * estimate's covariance is the sandwich A⁻¹ B A⁻¹ with B = Σ w² JᵀJ (the
 * residuals of unit variance; the robust loss's weights as in A). With one
 * weight N/n for all it is the sample's own (Σ JᵀJ)⁻¹. `covariance` holds
 * A⁻¹ (fit_free_covariance) on entry and the sandwich on return. */
cf_status fit_sample_covariance(fit_problem *p, int threads, double *covariance, cf_error *err);

/* Mark in the plan the model slots the capture does not constrain: those
 * carrying the eigenvectors of the range-scaled normal matrix with
 * negligible eigenvalues, or whose standard deviation exceeds half their
 * range. *found says whether there were any. */
cf_status fit_find_unconstrained(fit_problem *p, const double *jtj, const double *covariance,
                                 int rank_deficient, fit_plan *plan, int *found, cf_error *err);

/* The covariance when residuals are correlated within tile_px × tile_px
 * squares of pixels (a JPEG's blocks): the cluster-robust sandwich
 * A⁻¹ B A⁻¹ with B = Σ_tiles g_t g_tᵀ, g_t the tile's part in the score
 * (its residuals in units of σ, weighed as the normal equations weigh
 * them, times ∂μ/∂x from the analytic Jacobian, fit_problem_group_scores).
 * Independent residuals of variance σ² give B ≈ A. `covariance` holds A⁻¹
 * (fit_free_covariance) on entry and the sandwich on return (*applied 1),
 * or is left as it was when the observations fall in fewer than
 * FIT_TILES_PER_UNKNOWN tiles per unknown (*applied 0). */
cf_status fit_tile_covariance(const fit_problem *p, int tile_px, double *covariance, int *applied,
                              cf_error *err);
#define FIT_TILES_PER_UNKNOWN 4 /* 69a8156: B of rank n needs n tiles; 2, 8 move no fit (study) */

/* The tiles of a JPEG capture: its 4:2:0 coding unit, 16 × 16 pixels. */
#define FIT_JPEG_TILE_PX 16

#endif /* CLAYFIT_FIT_UNCERTAINTY_H */
