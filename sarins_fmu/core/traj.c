#include "smath.h"
#include "traj.h"

#include "earth.h"
#include "rotations.h"

#define DEG (3.141592653589793 / 180.0)

typedef struct { /* kinematics at one instant */
    double v[3], vdot[3], w_nb[3], mat_nb[9];
} kin;

static void kinematics(const double *seg0, const double *rates, double tau, kin *k)
{
    double s = seg0[0] + rates[0] * tau, psi = seg0[1] + rates[1] * tau, th = seg0[2] + rates[2] * tau;
    double sp, cp, st, ct;
    sm_sincos(psi, &sp, &cp);
    sm_sincos(th, &st, &ct);
    double u[3] = {-sp * ct, cp * ct, st};
    double u_psi[3] = {-cp * ct, -sp * ct, 0.0}, u_th[3] = {sp * st, -cp * st, ct};
    for (int i = 0; i < 3; i++) {
        k->v[i] = s * u[i];
        /* dv/dt = a u + s (du/dpsi r + du/dtheta q) */
        k->vdot[i] = rates[0] * u[i] + s * (u_psi[i] * rates[1] + u_th[i] * rates[2]);
    }
    k->w_nb[0] = rates[2];
    k->w_nb[1] = rates[1] * st;
    k->w_nb[2] = rates[1] * ct;
    sarins_euler_to_mat(psi, th, 0.0, k->mat_nb);
}

/* Body rate wrt inertial space and specific force, body frame, at position pos for kinematics k;
 * dpos = (L', lambda', h'). */
static void imu_truth(const kin *k, const double *pos, double *w_ib, double *f_b, double *dpos)
{
    double rm, rn, sl, cl;
    sarins_earth_radii(pos[0], &rm, &rn);
    sm_sincos(pos[0], &sl, &cl);
    double rmh = rm + pos[2], rnh = rn + pos[2];
    double w_ie[3] = {0.0, SARINS_EARTH_RATE * cl, SARINS_EARTH_RATE * sl};
    double w_en[3] = {-k->v[1] / rmh, k->v[0] / rnh, k->v[0] * sl / (cl * rnh)};
    double w2[3] = {2.0 * w_ie[0] + w_en[0], 2.0 * w_ie[1] + w_en[1], 2.0 * w_ie[2] + w_en[2]};
    /* f^n = dv/dt + (2 w_ie + w_en) x v - g^n,  g^n = (0, 0, -g) */
    double f_n[3] = {k->vdot[0] + (w2[1] * k->v[2] - w2[2] * k->v[1]),
                     k->vdot[1] + (w2[2] * k->v[0] - w2[0] * k->v[2]),
                     k->vdot[2] + (w2[0] * k->v[1] - w2[1] * k->v[0]) + sarins_earth_gravity(pos[0], pos[2])};
    const double *m = k->mat_nb;
    for (int i = 0; i < 3; i++) { /* mat_bn = mat_nb^T */
        double w_in = w_ie[0] + w_en[0], w_in1 = w_ie[1] + w_en[1], w_in2 = w_ie[2] + w_en[2];
        w_ib[i] = k->w_nb[i] + (m[i] * w_in + m[3 + i] * w_in1 + m[6 + i] * w_in2);
        f_b[i] = m[i] * f_n[0] + m[3 + i] * f_n[1] + m[6 + i] * f_n[2];
    }
    dpos[0] = k->v[1] / rmh;
    dpos[1] = k->v[0] / (rnh * cl);
    dpos[2] = k->v[2];
}

/* derivative of y = [pos - pos0 (3), q_{b(k-1) b} (4), dv (3)] at time tau of the segment */
static void deriv(const double *seg0, const double *rates, double tau, const double *pos0, const double *y,
                  double *dy)
{
    kin k;
    double w[3], f[3], c[9];
    double pos[3] = {pos0[0] + y[0], pos0[1] + y[1], pos0[2] + y[2]};
    kinematics(seg0, rates, tau, &k);
    imu_truth(&k, pos, w, f, dy);
    const double *q = y + 3;
    /* q' = q (0, w) / 2 */
    double wq[4] = {0.0, w[0], w[1], w[2]}, qd[4];
    sarins_quat_mult(q, wq, qd);
    for (int i = 0; i < 4; i++)
        dy[3 + i] = 0.5 * qd[i];
    /* dv' = mat(q) f */
    sarins_quat_to_mat(q, c);
    for (int i = 0; i < 3; i++)
        dy[7 + i] = c[3 * i] * f[0] + c[3 * i + 1] * f[1] + c[3 * i + 2] * f[2];
}

void sarins_quat_to_rotvec(const double *q, double *phi)
{
    double w = q[0], x = q[1], y = q[2], z = q[3];
    if (w < 0.0) { /* the shorter rotation */
        w = -w, x = -x, y = -y, z = -z;
    }
    double n = sm_sqrt(x * x + y * y + z * z);
    double scale;
    if (n < 1e-6 * w) { /* 2 atan(n / w) / n = (2 / w) (1 - r^2 / 3 + r^4 / 5), r = n / w */
        double r2 = (n / w) * (n / w);
        scale = (2.0 / w) * (1.0 - r2 / 3.0 + r2 * r2 / 5.0);
    } else {
        scale = 2.0 * sm_atan2(n, w) / n;
    }
    phi[0] = scale * x;
    phi[1] = scale * y;
    phi[2] = scale * z;
}

static void truth_row(const double *seg0, const double *rates, double tau, const double *pos, double *row)
{
    kin k;
    double dpos[3];
    kinematics(seg0, rates, tau, &k);
    row[0] = pos[0], row[1] = pos[1], row[2] = pos[2];
    row[3] = k.v[0], row[4] = k.v[1], row[5] = k.v[2];
    double psi = seg0[1] + rates[1] * tau;
    row[6] = sm_atan2(sm_sin(psi), sm_cos(psi)); /* wrapped to (-pi, pi] */
    row[7] = seg0[2] + rates[2] * tau;
    row[8] = 0.0;
    imu_truth(&k, pos, row + 9, row + 12, dpos);
}

/* Checks of the segment table and start (as sarins_traj_run states them); the total number of steps in
 * *total.  1 when they hold. */
static int segments_ok(int64_t n_seg, const double *seg, const double *start, double h, int64_t substeps,
                       int64_t *total)
{
    if (n_seg < 1 || substeps < 1 || !(h > 0.0) || !isfinite(h))
        return 0;
    *total = 0;
    for (int64_t j = 0; j < n_seg; j++) {
        const double *r = seg + SARINS_TRAJ_SEG * j;
        if (!(r[0] >= 0.0 && r[0] <= 1e15 && sm_floor(r[0]) == r[0]) || !isfinite(r[1]) || !isfinite(r[2]) ||
            !isfinite(r[3]))
            return 0;
        *total += (int64_t)r[0];
    }
    for (int i = 0; i < SARINS_TRAJ_START; i++)
        if (!isfinite(start[i]))
            return 0;
    return 1;
}

/* Move past finished segments: state0 advanced by each finished segment's rates over its duration
 * (speed, |pitch| checked), stopping at the last segment.  SARINS_TRAJ_BAD when the speed turns negative
 * or |pitch| reaches 89 deg. */
static int settle(sarins_traj *s, const double *seg)
{
    for (;;) {
        const double *r = seg + SARINS_TRAJ_SEG * s->seg;
        int64_t n = (int64_t)r[0];
        if (s->i < n)
            return SARINS_TRAJ_OK;
        double tau_end = (double)n * s->step;
        double end[3] = {s->state0[0] + r[1] * tau_end, s->state0[1] + r[2] * tau_end, s->state0[2] + r[3] * tau_end};
        if (end[0] < -1e-9 || sm_fabs(end[2]) >= 89.0 * DEG)
            return SARINS_TRAJ_BAD;
        if (s->seg == s->n_seg - 1)
            return SARINS_TRAJ_OK; /* done: the last row is on the last segment at its end */
        if (end[0] < 1e-12)
            end[0] = 0.0;
        for (int c = 0; c < 3; c++)
            s->state0[c] = end[c];
        s->seg += 1;
        s->i = 0;
    }
}

int sarins_traj_begin(sarins_traj *s, int64_t n_seg, const double *seg, const double *start, double h,
                      int64_t substeps)
{
    int64_t total;
    if (!segments_ok(n_seg, seg, start, h, substeps, &total))
        return SARINS_TRAJ_BAD;
    s->state0[0] = start[SARINS_TRAJ_SPEED];
    s->state0[1] = start[SARINS_TRAJ_YAW];
    s->state0[2] = start[SARINS_TRAJ_PITCH];
    s->pos[0] = start[SARINS_TRAJ_LAT];
    s->pos[1] = start[SARINS_TRAJ_LON];
    s->pos[2] = start[SARINS_TRAJ_HEIGHT];
    s->pos_c[0] = s->pos_c[1] = s->pos_c[2] = 0.0;
    s->step = h;
    s->substeps = substeps;
    s->seg = 0;
    s->i = 0;
    s->n_seg = n_seg;
    return settle(s, seg);
}

int sarins_traj_done(const sarins_traj *s, const double *seg)
{
    return s->seg == s->n_seg - 1 && s->i >= (int64_t)seg[SARINS_TRAJ_SEG * s->seg];
}

void sarins_traj_row(const sarins_traj *s, const double *seg, double *row)
{
    const double *r = seg + SARINS_TRAJ_SEG * s->seg;
    const double rates[3] = {r[1], r[2], r[3]};
    truth_row(s->state0, rates, (double)s->i * s->step, s->pos, row);
}

int sarins_traj_step(sarins_traj *s, const double *seg, double *dtheta, double *dv)
{
    if (sarins_traj_done(s, seg))
        return SARINS_TRAJ_BAD;
    const double *r = seg + SARINS_TRAJ_SEG * s->seg;
    const double rates[3] = {r[1], r[2], r[3]};
    const double h = s->step, dt = h / (double)s->substeps, tau0 = (double)s->i * h;
    double y[10] = {0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
    for (int64_t m = 0; m < s->substeps; m++) {
        double t = tau0 + (double)m * dt, k1[10], k2[10], k3[10], k4[10], yt[10];
        /* classical RK4: y += dt (k1 + 2 k2 + 2 k3 + k4) / 6 */
        deriv(s->state0, rates, t, s->pos, y, k1);
        for (int c = 0; c < 10; c++) yt[c] = y[c] + 0.5 * dt * k1[c];
        deriv(s->state0, rates, t + 0.5 * dt, s->pos, yt, k2);
        for (int c = 0; c < 10; c++) yt[c] = y[c] + 0.5 * dt * k2[c];
        deriv(s->state0, rates, t + 0.5 * dt, s->pos, yt, k3);
        for (int c = 0; c < 10; c++) yt[c] = y[c] + dt * k3[c];
        deriv(s->state0, rates, t + dt, s->pos, yt, k4);
        for (int c = 0; c < 10; c++) y[c] += dt * (k1[c] + 2.0 * k2[c] + 2.0 * k3[c] + k4[c]) / 6.0;
    }
    double qn = sm_sqrt(y[3] * y[3] + y[4] * y[4] + y[5] * y[5] + y[6] * y[6]);
    double q[4] = {y[3] / qn, y[4] / qn, y[5] / qn, y[6] / qn};
    sarins_quat_to_rotvec(q, dtheta);
    sarins_traj next = *s;
    for (int c = 0; c < 3; c++) {
        dv[c] = y[7 + c];
        /* pos += y, compensated (Kahan) so that rounding does not accumulate over the steps */
        double add = y[c] - next.pos_c[c], sum = next.pos[c] + add;
        next.pos_c[c] = (sum - next.pos[c]) - add;
        next.pos[c] = sum;
    }
    if (!isfinite(next.pos[0]) || sm_fabs(next.pos[0]) >= 89.9 * DEG)
        return SARINS_TRAJ_BAD;
    next.i += 1;
    if (settle(&next, seg) != SARINS_TRAJ_OK)
        return SARINS_TRAJ_BAD;
    *s = next;
    return SARINS_TRAJ_OK;
}

int sarins_traj_run(int64_t n_seg, const double *seg, const double *start, double h, int64_t substeps,
                    int64_t k_total, double *truth, double *dtheta, double *dv)
{
    int64_t total;
    if (k_total < 1 || !segments_ok(n_seg, seg, start, h, substeps, &total) || total != k_total)
        return SARINS_TRAJ_BAD;
    sarins_traj s;
    if (sarins_traj_begin(&s, n_seg, seg, start, h, substeps) != SARINS_TRAJ_OK)
        return SARINS_TRAJ_BAD;
    for (int64_t row = 0; row < k_total; row++) {
        sarins_traj_row(&s, seg, truth + SARINS_TRAJ_ROW * row);
        if (sarins_traj_step(&s, seg, dtheta + 3 * row, dv + 3 * row) != SARINS_TRAJ_OK)
            return SARINS_TRAJ_BAD;
    }
    sarins_traj_row(&s, seg, truth + SARINS_TRAJ_ROW * k_total);
    return SARINS_TRAJ_OK;
}
