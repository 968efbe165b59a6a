#include "smath.h"

#include "filter.h"


#include "earth.h"
#include "matrix.h"
#include "rotations.h"

#define MAXN SARINS_FILTER_MAX_STATES

void sarins_filter_propagate(int n, double *x, double *p, const double *phi, const double *q_diag, double dt)
{
    double xn[MAXN], tmp[MAXN * MAXN];
    if (n < 1 || n > MAXN)
        return; /* callers pass their fixed state count (9 or 11) */
    /* x = Phi x */
    for (int i = 0; i < n; i++) {
        double s = 0.0;
        for (int k = 0; k < n; k++)
            s += phi[n * i + k] * x[k];
        xn[i] = s;
    }
    for (int i = 0; i < n; i++)
        x[i] = xn[i];
    /* P = (Phi P) Phi' + diag(q) dt */
    sarins_matmul(n, phi, p, tmp);
    sarins_matmul_bt(n, tmp, phi, p);
    for (int i = 0; i < n; i++)
        p[n * i + i] += q_diag[i] * dt;
}

/* sum_k (I - K H)_ik b[k * stride] over k in {i, 3, 4} ascending, with ikh_i = ((I - K H)_i3, (I - K H)_i4) */
static double ikh_row_dot(int i, const double *ikh_i, const double *b, int stride)
{
    double s = 0.0;
    if (i < 3)
        s += 1.0 * b[i * stride];
    s += ikh_i[0] * b[3 * stride];
    s += ikh_i[1] * b[4 * stride];
    if (i > 4)
        s += 1.0 * b[i * stride];
    return s;
}

void sarins_filter_velocity_update(int n, double *x, double *p, double r_var, double z_east, double z_north)
{
    double gain[MAXN][2], ikh[MAXN][2], tmp[MAXN * MAXN];
    if (n < 5 || n > MAXN)
        return; /* callers pass their fixed state count (9 or 11) */
    /* S = H P H' + R, H selecting states 3 and 4 */
    double s00 = p[n * 3 + 3] + r_var, s01 = p[n * 3 + 4];
    double s10 = p[n * 4 + 3], s11 = p[n * 4 + 4] + r_var;
    /* S^-1 = [s11 -s01; -s10 s00] / det */
    double det = s00 * s11 - s01 * s10;
    double i00 = s11 / det, i01 = -s01 / det, i10 = -s10 / det, i11 = s00 / det;
    /* K = (P H') S^-1, P H' = columns 3 and 4 of P */
    for (int i = 0; i < n; i++) {
        gain[i][0] = p[n * i + 3] * i00 + p[n * i + 4] * i10;
        gain[i][1] = p[n * i + 3] * i01 + p[n * i + 4] * i11;
    }
    /* x += K (z - H x) */
    double innov0 = z_east - x[3], innov1 = z_north - x[4];
    for (int i = 0; i < n; i++)
        x[i] += gain[i][0] * innov0 + gain[i][1] * innov1;
    /* I - K H: the identity with columns 3 and 4 less K; its other entries are exact zeros, so the
     * products below sum only over k in {i, 3, 4} (ascending), which is the full index-ordered sum
     * without its zero terms */
    for (int i = 0; i < n; i++) {
        ikh[i][0] = ((i == 3) ? 1.0 : 0.0) - gain[i][0];
        ikh[i][1] = ((i == 4) ? 1.0 : 0.0) - gain[i][1];
    }
    /* tmp = (I - K H) P */
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++)
            tmp[n * i + j] = ikh_row_dot(i, ikh[i], p + j, n);
    /* P = tmp (I - K H)' + r K K' */
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++)
            p[n * i + j] = ikh_row_dot(j, ikh[j], tmp + n * i, 1);
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++)
            p[n * i + j] += r_var * (gain[i][0] * gain[j][0] + gain[i][1] * gain[j][1]);
}

void sarins_stop_filter_steps(int64_t k, double *x, double *p, const double *velocity_en, const double *attitude,
                              double lat, double dt, const double *q_diag, double r_var, double *out)
{
    enum { N = SARINS_STOP_STATES };
    double f[N * N] = {0.0}, fh[N * N], fh2[N * N], fh3[N * N], phi_m[N * N], c[9];
    double r_m, r_n;
    sarins_earth_radii(lat, &r_m, &r_n);
    double w_c = SARINS_EARTH_RATE * sm_cos(lat), w_s = SARINS_EARTH_RATE * sm_sin(lat);
    double g = sarins_earth_gravity(lat, 0.0);
    /* continuous-time F, static base (the attitude columns are set per step) */
    f[N * 0 + 1] = w_s;
    f[N * 0 + 2] = -w_c;
    f[N * 0 + 4] = -1.0 / r_m;
    f[N * 1 + 0] = -w_s;
    f[N * 1 + 3] = 1.0 / r_n;
    f[N * 2 + 0] = w_c;
    f[N * 2 + 3] = sm_tan(lat) / r_n;
    f[N * 3 + 1] = -g;
    f[N * 3 + 4] = 2.0 * w_s;
    f[N * 4 + 0] = g;
    f[N * 4 + 3] = -2.0 * w_s;
    /* north position error: d_lat' = dv_N / R_M; d omega_ie^n = W (0, -sin L, cos L) d_lat */
    f[N * 10 + 4] = 1.0 / r_m;
    f[N * 1 + 10] = -w_s;
    f[N * 2 + 10] = w_c;
    for (int64_t s = 0; s < k; s++) {
        sarins_euler_to_mat(attitude[3 * s], attitude[3 * s + 1], attitude[3 * s + 2], c);
        for (int i = 0; i < 3; i++) { /* - mat_nb eps */
            f[N * i + 5] = -c[3 * i];
            f[N * i + 6] = -c[3 * i + 1];
            f[N * i + 7] = -c[3 * i + 2];
        }
        for (int i = 0; i < 2; i++) { /* + mat_nb nabla */
            f[N * (3 + i) + 8] = c[3 * i];
            f[N * (3 + i) + 9] = c[3 * i + 1];
        }
        /* Phi = I + F dt + (F dt)^2 / 2 + (F dt)^3 / 6 */
        for (int i = 0; i < N * N; i++)
            fh[i] = f[i] * dt;
        sarins_matmul(N, fh, fh, fh2);
        sarins_matmul(N, fh2, fh, fh3);
        for (int i = 0; i < N; i++)
            for (int j = 0; j < N; j++)
                phi_m[N * i + j] = ((i == j) ? 1.0 : 0.0) + fh[N * i + j] + 0.5 * fh2[N * i + j] + fh3[N * i + j] / 6.0;
        sarins_filter_propagate(N, x, p, phi_m, q_diag, dt);
        sarins_filter_velocity_update(N, x, p, r_var, velocity_en[2 * s], velocity_en[2 * s + 1]);
        out[2 * s] = x[SARINS_STOP_EPS_Z];
        out[2 * s + 1] = sm_sqrt(p[N * SARINS_STOP_EPS_Z + SARINS_STOP_EPS_Z]);
    }
}
