/* Dense symmetric linear algebra for the layers above, by Eigen (which
 * Ceres brings): the one eigen-decomposition and the one Cholesky
 * factorisation of the project. Matrices are row-major, n × n. lsq's
 * interface to the layers above (src/lsq/include). */
#ifndef CLAYFIT_LSQ_LINALG_H
#define CLAYFIT_LSQ_LINALG_H

#include "clayfit/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The eigenvalues of the symmetric a (ascending) into values (n) and,
 * unless vectors is NULL, the unit eigenvectors as the columns of vectors
 * (n × n, row-major): a = V diag(values) Vᵀ. Returns 0 when a is not
 * finite or the decomposition fails (out of memory included). */
int cf_symmetric_eigen(int n, const double *a, double *values, double *vectors);

/* Solves a x = b for a symmetric positive definite a by Cholesky (LLᵀ).
 * Returns 0 when a is not positive definite (a pivot at or below zero) or
 * not finite. */
int cf_cholesky_solve(int n, const double *a, const double *b, double *x);

/* The covariance of the last g unknowns of the symmetric normal matrix a
 * (n × n, row-major) with the first n − g profiled out: the inverse of
 * the Schur complement a_gg − a_gmᵀ a_mm⁺ a_mg, where a_mm⁺ is the
 * pseudo-inverse of the first unknowns' block (each column scaled to a
 * unit diagonal; eigenvalues below 1e-10 of the largest dropped: those
 * directions are not constrained and are held, not traded against the
 * last g). Into covariance (g × g) when it is regular; else returns 0 and
 * writes the Schur complement's weakest direction (a unit vector of g,
 * its eigenvalue at or below 1e-10 of the largest, or a zero diagonal)
 * into weakest. Returns −1 when a is not finite or out of memory. */
int cf_schur_covariance(int n, int g, const double *a, double *covariance, double *weakest);

/* The sandwich covariance: b ← a b a (a and b symmetric, n × n, row-major;
 * a is the inverse normal matrix, b the scores' outer products), made
 * symmetric to the last bit (a NaN in a or b spreads as in the product).
 * Returns 0 when out of memory (b untouched). */
int cf_sandwich(int n, const double *a, double *b);

#ifdef __cplusplus
}
#endif

#endif /* CLAYFIT_LSQ_LINALG_H */
