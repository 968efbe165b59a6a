#include "ins.h"

#include <math.h>

#include "earth.h"
#include "filter.h"
#include "rotations.h"

/* q /= |q| */
static void normalize_into(const double *qn, double *q)
{
    double norm = sqrt(qn[0] * qn[0] + qn[1] * qn[1] + qn[2] * qn[2] + qn[3] * qn[3]);
    for (int i = 0; i < 4; i++)
        q[i] = qn[i] / norm;
}

/* One major-loop step (see ins.h); the position moves only if move_position. */
static void mech_step(double *q, double *v, double *pos, const double *phi, const double *dv_b, double h,
                      int move_position)
{
    double lat = pos[0], hgt = pos[2];
    double r_m, r_n;
    sarins_earth_radii(lat, &r_m, &r_n);
    double w_c = SARINS_EARTH_RATE * cos(lat), w_s = SARINS_EARTH_RATE * sin(lat);
    double ve = v[0], vn = v[1];
    /* omega_en^n = (-v_N / (R_M + h), v_E / (R_N + h), v_E tan L / (R_N + h)) */
    double en_x = -vn / (r_m + hgt);
    double en_y = ve / (r_n + hgt);
    double en_z = ve * tan(lat) / (r_n + hgt);
    /* zeta = (omega_ie^n + omega_en^n) h */
    double zeta[3] = {en_x * h, (w_c + en_y) * h, (w_s + en_z) * h};
    double c[9], u[3];
    sarins_quat_to_mat(q, c);
    /* u = mat_nb dv_b */
    for (int i = 0; i < 3; i++)
        u[i] = c[3 * i] * dv_b[0] + c[3 * i + 1] * dv_b[1] + c[3 * i + 2] * dv_b[2];
    /* dv_n = (I - [zeta x]/2) u */
    double dvn[3] = {u[0] - 0.5 * (zeta[1] * u[2] - zeta[2] * u[1]),
                     u[1] - 0.5 * (zeta[2] * u[0] - zeta[0] * u[2]),
                     u[2] - 0.5 * (zeta[0] * u[1] - zeta[1] * u[0])};
    /* Coriolis: v -= (2 omega_ie^n + omega_en^n) x v h */
    double ox = en_x, oy = 2.0 * w_c + en_y, oz = 2.0 * w_s + en_z;
    double v_old0 = v[0], v_old1 = v[1];
    v[0] = v[0] + dvn[0] - (oy * v[2] - oz * v[1]) * h;
    v[1] = v[1] + dvn[1] - (oz * v_old0 - ox * v[2]) * h;
    v[2] = 0.0; /* vertical channel held */
    if (move_position) {
        /* L += mean v_N h / (R_M + h) ; lambda += mean v_E h / ((R_N + h) cos L_mid) */
        pos[0] = lat + 0.5 * (v_old1 + v[1]) * h / (r_m + hgt);
        double lat_mid = 0.5 * (lat + pos[0]);
        pos[1] = pos[1] + 0.5 * (v_old0 + v[0]) * h / ((r_n + hgt) * cos(lat_mid));
    }
    /* q_nb = q(-zeta) * q_nb * q(phi), normalised */
    double minus_zeta[3] = {-zeta[0], -zeta[1], -zeta[2]};
    double qz[4], qphi[4], tmp[4], qn[4];
    sarins_rotvec_to_quat(minus_zeta, qz);
    sarins_rotvec_to_quat(phi, qphi);
    sarins_quat_mult(qz, q, tmp);
    sarins_quat_mult(tmp, qphi, qn);
    normalize_into(qn, q);
}

/* Output row from the state: position, velocity, yaw/pitch/roll of q. */
static void record(const double *q, const double *v, const double *pos, double *row)
{
    double c[9];
    row[0] = pos[0];
    row[1] = pos[1];
    row[2] = pos[2];
    row[3] = v[0];
    row[4] = v[1];
    row[5] = v[2];
    sarins_quat_to_mat(q, c);
    /* pitch = asin(C_21) clipped to [-1, 1] as Python's min(1, max(-1, x)) */
    double s = (c[7] > -1.0) ? c[7] : -1.0;
    s = (s < 1.0) ? s : 1.0;
    row[7] = asin(s);
    /* roll = atan2(-C_20, C_22) ; yaw = atan2(-C_01, C_11) */
    row[8] = atan2(-c[6], c[8]);
    row[6] = atan2(-c[1], c[4]);
}

void sarins_ins_held_row(const double *q, const double *pos, double *row)
{
    const double zero[3] = {0.0, 0.0, 0.0};
    record(q, zero, pos, row);
}

void sarins_ins_nav_steps(int64_t k, double *q, double *v, double *pos, const double *dtheta, const double *dv,
                          double h, const double *gyro_comp, const double *accel_comp, const double *axial_corr,
                          double *out)
{
    double phi[3], u[3];
    for (int64_t s = 0; s < k; s++) {
        for (int j = 0; j < 3; j++) {
            phi[j] = dtheta[3 * s + j] - gyro_comp[j] * h;
            u[j] = dv[3 * s + j] - accel_comp[j] * h;
        }
        phi[2] -= axial_corr[s] * h;
        mech_step(q, v, pos, phi, u, h, 1);
        record(q, v, pos, out + SARINS_INS_ROW * s);
    }
}

void sarins_ins_align_steps(int64_t k, double *q, double *v, double *pos, const double *dtheta, const double *dv,
                            double h, double *gyro_comp, double *accel_comp, double *x, double *p,
                            const double *q_diag, double r_var, double *hist)
{
    enum { N = SARINS_INS_ALIGN_STATES };
    double phi[3], u[3], c0[9], c1[9], c[9];
    double f[N * N] = {0.0}, fh[N * N], fh2[N * N], phi_m[N * N];
    double lat = pos[0];
    double r_m, r_n;
    sarins_earth_radii(lat, &r_m, &r_n);
    double w_c = SARINS_EARTH_RATE * cos(lat), w_s = SARINS_EARTH_RATE * sin(lat);
    double g = sarins_earth_gravity(lat, pos[2]);
    for (int64_t s = 0; s < k; s++) {
        for (int j = 0; j < 3; j++) {
            phi[j] = dtheta[3 * s + j] - gyro_comp[j] * h;
            u[j] = dv[3 * s + j] - accel_comp[j] * h;
        }
        sarins_quat_to_mat(q, c0);
        mech_step(q, v, pos, phi, u, h, 0);
        /* sensor errors act over the whole step: mid-step attitude (2nd order) */
        sarins_quat_to_mat(q, c1);
        for (int i = 0; i < 9; i++)
            c[i] = 0.5 * (c0[i] + c1[i]);
        /* continuous-time F (static base) */
        f[N * 0 + 1] = w_s;
        f[N * 0 + 2] = -w_c;
        f[N * 0 + 4] = -1.0 / (r_m + pos[2]);
        f[N * 1 + 0] = -w_s;
        f[N * 1 + 3] = 1.0 / (r_n + pos[2]);
        f[N * 2 + 0] = w_c;
        f[N * 2 + 3] = tan(lat) / (r_n + pos[2]);
        f[N * 3 + 1] = -g;
        f[N * 3 + 4] = 2.0 * w_s;
        f[N * 4 + 0] = g;
        f[N * 4 + 3] = -2.0 * w_s;
        for (int i = 0; i < 3; i++) { /* phi' = ... - mat_nb eps */
            f[N * i + 5] = -c[3 * i];
            f[N * i + 6] = -c[3 * i + 1];
        }
        for (int i = 0; i < 2; i++) { /* dv' = ... + mat_nb nabla */
            f[N * (3 + i) + 7] = c[3 * i];
            f[N * (3 + i) + 8] = c[3 * i + 1];
        }
        /* Phi = I + F h + (F h)^2 / 2 */
        for (int i = 0; i < N * N; i++)
            fh[i] = f[i] * h;
        sarins_matmul(N, fh, fh, fh2);
        for (int i = 0; i < N; i++)
            for (int j = 0; j < N; j++)
                phi_m[N * i + j] = ((i == j) ? 1.0 : 0.0) + fh[N * i + j] + 0.5 * fh2[N * i + j];
        sarins_filter_propagate(N, x, p, phi_m, q_diag, h);
        sarins_filter_velocity_update(N, x, p, r_var, v[0], v[1]);
        /* closed-loop feedback: q_true = q(phi) * q_computed */
        double qphi[4], qn[4];
        sarins_rotvec_to_quat(x, qphi);
        sarins_quat_mult(qphi, q, qn);
        normalize_into(qn, q);
        v[0] -= x[3];
        v[1] -= x[4];
        gyro_comp[0] += x[5];
        gyro_comp[1] += x[6];
        accel_comp[0] += x[7];
        accel_comp[1] += x[8];
        for (int i = 0; i < N; i++) {
            x[i] = 0.0;
            hist[N * s + i] = p[N * i + i];
        }
    }
}

void sarins_ins_coarse_steps(int64_t k, double *q_b0b, double *v_b0, const double *dtheta, const double *dv,
                             double *hist)
{
    double c[9], qd[4], qn[4];
    for (int64_t s = 0; s < k; s++) {
        const double *d = dv + 3 * s;
        sarins_quat_to_mat(q_b0b, c);
        /* v_b0 += mat_b0b dv */
        for (int i = 0; i < 3; i++)
            v_b0[i] += c[3 * i] * d[0] + c[3 * i + 1] * d[1] + c[3 * i + 2] * d[2];
        /* q_b0b = q_b0b * q(dtheta), normalised */
        sarins_rotvec_to_quat(dtheta + 3 * s, qd);
        sarins_quat_mult(q_b0b, qd, qn);
        normalize_into(qn, q_b0b);
        for (int i = 0; i < 3; i++)
            hist[3 * s + i] = v_b0[i];
    }
}
