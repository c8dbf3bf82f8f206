/* Eigenvalues and eigenvectors of a small symmetric matrix (cyclic Jacobi
 * rotations; Golub & Van Loan, §8.5). Private to src/fit. */
#ifndef CLAYFIT_FIT_SYMMETRIC_EIGEN_H
#define CLAYFIT_FIT_SYMMETRIC_EIGEN_H

/* a: n × n symmetric, row-major (destroyed). values[i] and the column i of
 * vectors (n × n, row-major) are the i-th eigenpair, unordered. */
void symmetric_eigen(double *a, int n, double *values, double *vectors);

#endif /* CLAYFIT_FIT_SYMMETRIC_EIGEN_H */
