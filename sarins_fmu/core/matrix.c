#include "smath.h"

#include "matrix.h"


void sarins_matmul(int n, const double *a, const double *b, double *c)
{
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            double s = 0.0;
            for (int k = 0; k < n; k++)
                s += a[n * i + k] * b[n * k + j];
            c[n * i + j] = s;
        }
}

void sarins_matmul_bt(int n, const double *a, const double *b, double *c)
{
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            double s = 0.0;
            for (int k = 0; k < n; k++)
                s += a[n * i + k] * b[n * j + k];
            c[n * i + j] = s;
        }
}

void sarins_matvec(int n, const double *a, const double *x, double *y)
{
    for (int i = 0; i < n; i++) {
        double s = 0.0;
        for (int k = 0; k < n; k++)
            s += a[n * i + k] * x[k];
        y[i] = s;
    }
}

void sarins_symmetrize(int n, double *a)
{
    for (int i = 0; i < n; i++)
        for (int j = i + 1; j < n; j++) {
            double m = 0.5 * (a[n * i + j] + a[n * j + i]);
            a[n * i + j] = m;
            a[n * j + i] = m;
        }
}

int sarins_cholesky(int n, const double *a, double *l)
{
    if (n < 1 || n > SARINS_MATRIX_MAX)
        return -1;
    for (int i = 0; i < n * n; i++)
        l[i] = 0.0;
    for (int j = 0; j < n; j++) {
        /* l_jj = sqrt(a_jj - sum_k<j l_jk^2) */
        double d = a[n * j + j];
        for (int k = 0; k < j; k++)
            d -= l[n * j + k] * l[n * j + k];
        if (!(d > 0.0) || !isfinite(d))
            return -1;
        double ljj = sm_sqrt(d);
        l[n * j + j] = ljj;
        /* l_ij = (a_ij - sum_k<j l_ik l_jk) / l_jj, i > j */
        for (int i = j + 1; i < n; i++) {
            double s = a[n * i + j];
            for (int k = 0; k < j; k++)
                s -= l[n * i + k] * l[n * j + k];
            l[n * i + j] = s / ljj;
        }
    }
    return 0;
}

int sarins_spd_inverse(int n, const double *a, double *inv)
{
    double l[SARINS_MATRIX_MAX * SARINS_MATRIX_MAX], m[SARINS_MATRIX_MAX * SARINS_MATRIX_MAX];
    if (sarins_cholesky(n, a, l) != 0)
        return -1;
    /* m = l^-1 (lower triangular), column by column by forward substitution of l m = I */
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            if (i < j) {
                m[n * i + j] = 0.0;
                continue;
            }
            double s = (i == j) ? 1.0 : 0.0;
            for (int k = j; k < i; k++)
                s -= l[n * i + k] * m[n * k + j];
            m[n * i + j] = s / l[n * i + i];
        }
    /* inv = m' m: inv_ij = sum_k>=max(i,j) m_ki m_kj, written to both triangles */
    for (int i = 0; i < n; i++)
        for (int j = i; j < n; j++) {
            double s = 0.0;
            for (int k = j; k < n; k++)
                s += m[n * k + i] * m[n * k + j];
            inv[n * i + j] = s;
            inv[n * j + i] = s;
        }
    for (int i = 0; i < n * n; i++)
        if (!isfinite(inv[i]))
            return -1;
    return 0;
}
