#include "smath.h"
#include "nav3.h"

#include "earth.h"
#include "rotations.h"

void sarins_mat_to_euler(const double *m, double *ypr)
{
    ypr[0] = sm_atan2(-m[1], m[4]);
    ypr[1] = sm_atan2(m[7], sm_hypot(m[1], m[4]));
    ypr[2] = sm_atan2(-m[6], m[8]);
}

void sarins_nav3_row(const double *q, const double *v, const double *pos, double *row)
{
    double mat[9];
    sarins_quat_to_mat(q, mat);
    for (int i = 0; i < 3; i++) {
        row[i] = pos[i];
        row[3 + i] = v[i];
    }
    sarins_mat_to_euler(mat, row + 6);
}

/* the new state from the start (v; q_dt = q_nb,k-1 * q(dtheta), dvn0 = mat_nb,k-1 dv, the same in
 * both passes) with the rates taken at (v_mid, pos_mid) */
static void advance(const double *q_dt, const double *dvn0, const double *v, const double *v_mid, const double *pos_mid,
                    double h, double *q1, double *v1, double *dpos)
{
    double rm, rn, sl, cl;
    sm_sincos(pos_mid[0], &sl, &cl);
    sarins_earth_radii_sin(sl, &rm, &rn);
    double rmh = rm + pos_mid[2], rnh = rn + pos_mid[2];
    double w_ie[3] = {0.0, SARINS_EARTH_RATE * cl, SARINS_EARTH_RATE * sl};
    double w_en[3] = {-v_mid[1] / rmh, v_mid[0] / rnh, v_mid[0] * sl / (cl * rnh)};
    double zeta[3], w2[3];
    for (int i = 0; i < 3; i++) {
        zeta[i] = (w_ie[i] + w_en[i]) * h;
        w2[i] = 2.0 * w_ie[i] + w_en[i];
    }
    /* (I - [zeta x]/2) dvn0 = dvn0 - zeta x dvn0 / 2 */
    double cz[3] = {zeta[1] * dvn0[2] - zeta[2] * dvn0[1], zeta[2] * dvn0[0] - zeta[0] * dvn0[2],
                    zeta[0] * dvn0[1] - zeta[1] * dvn0[0]};
    double cor[3] = {w2[1] * v_mid[2] - w2[2] * v_mid[1], w2[2] * v_mid[0] - w2[0] * v_mid[2],
                     w2[0] * v_mid[1] - w2[1] * v_mid[0]};
    double g = sarins_earth_gravity_sin(sl, pos_mid[2]);
    for (int i = 0; i < 3; i++)
        v1[i] = v[i] + (dvn0[i] - 0.5 * cz[i]) - cor[i] * h;
    v1[2] -= g * h;
    dpos[2] = 0.5 * (v[2] + v1[2]) * h;
    dpos[0] = 0.5 * (v[1] + v1[1]) * h / rmh;
    dpos[1] = 0.5 * (v[0] + v1[0]) * h / (rnh * cl);
    /* q_nb,k = q(-zeta) * q_nb,k-1 * q(dtheta) */
    double mz[3] = {-zeta[0], -zeta[1], -zeta[2]}, qz[4];
    sarins_rotvec_to_quat(mz, qz);
    sarins_quat_mult(qz, q_dt, q1);
    double n = sm_sqrt(q1[0] * q1[0] + q1[1] * q1[1] + q1[2] * q1[2] + q1[3] * q1[3]);
    for (int i = 0; i < 4; i++)
        q1[i] /= n;
}

/* one step: q and v in place, the position change in dpos (pos untouched), dvn0 = mat_nb,k-1 dv */
static void step_delta(double *q, double *v, const double *pos, const double *dtheta, const double *dv, double h,
                       double *dpos, double *dvn0)
{
    double q1[4], v1[3], vm[3], pm[3], c[9], qt[4], q_dt[4];
    sarins_quat_to_mat(q, c);
    for (int i = 0; i < 3; i++)
        dvn0[i] = c[3 * i] * dv[0] + c[3 * i + 1] * dv[1] + c[3 * i + 2] * dv[2];
    sarins_rotvec_to_quat(dtheta, qt);
    sarins_quat_mult(q, qt, q_dt);
    advance(q_dt, dvn0, v, v, pos, h, q1, v1, dpos); /* pass 1: rates at the start */
    for (int i = 0; i < 3; i++) {
        vm[i] = 0.5 * (v[i] + v1[i]);
        pm[i] = 0.5 * (pos[i] + (pos[i] + dpos[i]));
    }
    advance(q_dt, dvn0, v, vm, pm, h, q1, v1, dpos); /* pass 2: rates at the middle */
    for (int i = 0; i < 4; i++)
        q[i] = q1[i];
    for (int i = 0; i < 3; i++)
        v[i] = v1[i];
}

void sarins_nav3_step_dvn(double *q, double *v, double *pos, const double *dtheta, const double *dv, double h,
                          double *dv_n)
{
    double dpos[3];
    step_delta(q, v, pos, dtheta, dv, h, dpos, dv_n);
    for (int i = 0; i < 3; i++)
        pos[i] += dpos[i];
}

void sarins_nav3_step(double *q, double *v, double *pos, const double *dtheta, const double *dv, double h)
{
    double dv_n[3];
    sarins_nav3_step_dvn(q, v, pos, dtheta, dv, h, dv_n);
}

int sarins_nav3_steps(int64_t k, double *q, double *v, double *pos, const double *dtheta, const double *dv,
                      double h, double *out)
{
    if (!(h > 0.0) || h - h != 0.0)
        return 1;
    for (int64_t i = 0; i < 3 * k; i++)
        if (dtheta[i] - dtheta[i] != 0.0 || dv[i] - dv[i] != 0.0)
            return 1;
    double lo[3] = {0.0, 0.0, 0.0}; /* Kahan compensation of the position sums within this call */
    for (int64_t i = 0; i < k; i++) {
        double dpos[3], dvn0[3];
        step_delta(q, v, pos, dtheta + 3 * i, dv + 3 * i, h, dpos, dvn0);
        for (int c = 0; c < 3; c++) {
            double add = dpos[c] - lo[c], sum = pos[c] + add;
            lo[c] = (sum - pos[c]) - add;
            pos[c] = sum;
        }
        sarins_nav3_row(q, v, pos, out + SARINS_NAV3_ROW * i);
    }
    return 0;
}
