/* Small dense matrices shared by the core's estimators (the INS alignment filter, the stop filter, the
 * forgetting-factor RLS and any other filter of the core).
 *
 * Matrices are row-major double arrays, n x n unless stated, 1 <= n <= SARINS_MATRIX_MAX.  Every sum runs
 * over its index in ascending order from 0.0, so the results do not depend on the compiler (with the
 * core's -ffp-contract=off) and the Python binding reproduces them bit for bit.  No allocation, no
 * libm except sqrt (Cholesky).  Outputs must not alias inputs unless stated.
 */
#ifndef SARINS_MATRIX_H
#define SARINS_MATRIX_H

#define SARINS_MATRIX_MAX 32 /* largest n of the functions that need scratch space */

/* c = a b */
void sarins_matmul(int n, const double *a, const double *b, double *c);

/* c = a b' */
void sarins_matmul_bt(int n, const double *a, const double *b, double *c);

/* y = a x (a n x n, x and y n) */
void sarins_matvec(int n, const double *a, const double *x, double *y);

/* a = (a + a') / 2 in place: entry (i, j) and (j, i) both become 0.5 * (a_ij + a_ji) */
void sarins_symmetrize(int n, double *a);

/* Cholesky factor of a symmetric matrix (only its lower triangle is read): a = l l', l lower triangular
 * (its upper triangle set to 0).  Returns 0, or -1 when a is not positive definite (a pivot is not > 0 or
 * not finite; l is then unspecified) or n is out of range. */
int sarins_cholesky(int n, const double *a, double *l);

/* inv = a^-1 of a symmetric positive definite matrix, from its Cholesky factor: inv = l^-T l^-1, written
 * symmetric.  Returns 0, or -1 (inv unspecified) when a is not positive definite or n is out of range. */
int sarins_spd_inverse(int n, const double *a, double *inv);

#endif
