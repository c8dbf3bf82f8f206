/* Dense symmetric linear algebra for the layers above, by Eigen (which
 * Ceres brings): the one eigen-decomposition and the one Cholesky
 * factorisation of the project. Matrices are row-major, n × n. Private to
 * the layers above src/lsq. */
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

#ifdef __cplusplus
}
#endif

#endif /* CLAYFIT_LSQ_LINALG_H */
