#include "smath.h"

#include "ins.h"

#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "earth.h"
#include "filter.h"
#include "rotations.h"

/* q /= |q| */
static void normalize_into(const double *qn, double *q)
{
    double norm = sm_sqrt(qn[0] * qn[0] + qn[1] * qn[1] + qn[2] * qn[2] + qn[3] * qn[3]);
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
    double w_c = SARINS_EARTH_RATE * sm_cos(lat), w_s = SARINS_EARTH_RATE * sm_sin(lat);
    double ve = v[0], vn = v[1];
    /* omega_en^n = (-v_N / (R_M + h), v_E / (R_N + h), v_E tan L / (R_N + h)) */
    double en_x = -vn / (r_m + hgt);
    double en_y = ve / (r_n + hgt);
    double en_z = ve * sm_tan(lat) / (r_n + hgt);
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
        pos[1] = pos[1] + 0.5 * (v_old0 + v[0]) * h / ((r_n + hgt) * sm_cos(lat_mid));
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
    row[7] = sm_asin(s);
    /* roll = atan2(-C_20, C_22) ; yaw = atan2(-C_01, C_11) */
    row[8] = sm_atan2(-c[6], c[8]);
    row[6] = sm_atan2(-c[1], c[4]);
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
    double w_c = SARINS_EARTH_RATE * sm_cos(lat), w_s = SARINS_EARTH_RATE * sm_sin(lat);
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
        f[N * 2 + 3] = sm_tan(lat) / (r_n + pos[2]);
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

/* ---------------------------------------------------------------- the whole INS */

static const char *const CONFIG_NAMES[SARINS_INS_CONFIG] = {
    "lat", "lon", "height", "align_time", "coarse_time", "step", "arw", "vrw", "drift_rw", "bias_rw",
    "velocity_meas_std", "tilt0_std", "heading0_std", "velocity0_std", "drift0_std", "bias0_std"};

/* round half to even, as Python's round() */
static double round_even(double x)
{
    double r = sm_floor(x), d = x - r;
    if (d > 0.5 || (d == 0.5 && sm_fmod(r, 2.0) != 0.0))
        r += 1.0;
    return r;
}

/* a b + c d + e f as a fused multiply-add chain (the rounding of the BLAS products this replaced) */
static double dot3(double a, double b, double c, double d, double e, double f)
{
    return sm_fma(e, f, sm_fma(c, d, a * b));
}

/* c = a b, 3x3 row-major, each entry a dot3 */
static void mat3_mult(const double *a, const double *b, double *c)
{
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            c[3 * i + j] = dot3(a[3 * i], b[j], a[3 * i + 1], b[3 + j], a[3 * i + 2], b[6 + j]);
}

static double norm3(const double *a) { return sm_sqrt(dot3(a[0], a[0], a[1], a[1], a[2], a[2])); }

/* c = a x b (each component a product difference, not fused) */
static void cross3(const double *a, const double *b, double *c)
{
    double p0 = a[1] * b[2], p1 = a[2] * b[0], p2 = a[0] * b[1];
    double m0 = a[2] * b[1], m1 = a[0] * b[2], m2 = a[1] * b[0];
    c[0] = p0 - m0;
    c[1] = p1 - m1;
    c[2] = p2 - m2;
}

int sarins_ins_config_check(const double *c, char *msg, size_t size)
{
    char scratch[8];
    if (msg == NULL || size == 0) {
        msg = scratch;
        size = sizeof scratch;
    }
    for (int i = 0; i < SARINS_INS_STEP + 1; i++)
        if (!isfinite(c[i])) {
            snprintf(msg, size, "INS %s must be finite", CONFIG_NAMES[i]);
            return SARINS_INS_BAD_CONFIG;
        }
    for (int i = SARINS_INS_FILTER_FIRST; i < SARINS_INS_CONFIG; i++)
        if (!(isfinite(c[i]) && c[i] > 0.0)) {
            snprintf(msg, size, "alignment filter %s must be positive and finite, got %.17g", CONFIG_NAMES[i], c[i]);
            return SARINS_INS_BAD_CONFIG;
        }
    double align = c[SARINS_INS_ALIGN_TIME], coarse = c[SARINS_INS_COARSE_TIME], step = c[SARINS_INS_STEP];
    if (sm_fabs(c[SARINS_INS_LAT]) > SARINS_INS_LAT_LIMIT) {
        snprintf(msg, size, "latitude %.6g deg is outside +-89.9 deg", c[SARINS_INS_LAT] * (180.0 / SARINS_INS_PI));
        return SARINS_INS_BAD_CONFIG;
    }
    if (step <= 0.0) {
        snprintf(msg, size, "INS step must be positive, got %.17g", step);
        return SARINS_INS_BAD_CONFIG;
    }
    if (align < 0.0 || coarse < 0.0) {
        snprintf(msg, size, "alignment durations must be non-negative");
        return SARINS_INS_BAD_CONFIG;
    }
    if (0.0 < align && align < coarse + 2.0 * step) {
        snprintf(msg, size, "align_time must exceed coarse_time (or be 0 for a given initial attitude)");
        return SARINS_INS_BAD_CONFIG;
    }
    if (coarse > 0.0 && round_even(coarse / step) < 2.0) {
        snprintf(msg, size, "coarse_time must span at least two steps");
        return SARINS_INS_BAD_CONFIG;
    }
    if (round_even(align / step) > 9.0e15) {
        snprintf(msg, size, "align_time spans more steps than a step counter holds");
        return SARINS_INS_BAD_CONFIG;
    }
    return SARINS_INS_OK;
}

void sarins_mat_to_quat(const double *m, double *q)
{
    double tr = (m[0] + m[4]) + m[8];
    double cands[4] = {tr, m[0], m[4], m[8]};
    int i = 0;
    for (int j = 1; j < 4; j++) /* the first largest */
        if (cands[j] > cands[i])
            i = j;
    double r[4];
    if (i == 0) {
        double w = 0.5 * sm_sqrt(1.0 + tr);
        r[0] = w;
        r[1] = (m[7] - m[5]) / (4.0 * w);
        r[2] = (m[2] - m[6]) / (4.0 * w);
        r[3] = (m[3] - m[1]) / (4.0 * w);
    } else if (i == 1) {
        double x = 0.5 * sm_sqrt((1.0 + 2.0 * m[0]) - tr);
        r[0] = (m[7] - m[5]) / (4.0 * x);
        r[1] = x;
        r[2] = (m[1] + m[3]) / (4.0 * x);
        r[3] = (m[2] + m[6]) / (4.0 * x);
    } else if (i == 2) {
        double y = 0.5 * sm_sqrt((1.0 + 2.0 * m[4]) - tr);
        r[0] = (m[2] - m[6]) / (4.0 * y);
        r[1] = (m[1] + m[3]) / (4.0 * y);
        r[2] = y;
        r[3] = (m[5] + m[7]) / (4.0 * y);
    } else {
        double z = 0.5 * sm_sqrt((1.0 + 2.0 * m[8]) - tr);
        r[0] = (m[3] - m[1]) / (4.0 * z);
        r[1] = (m[2] + m[6]) / (4.0 * z);
        r[2] = (m[5] + m[7]) / (4.0 * z);
        r[3] = z;
    }
    double norm = sm_sqrt(sm_fma(r[3], r[3], sm_fma(r[2], r[2], sm_fma(r[1], r[1], r[0] * r[0]))));
    double sign = (r[0] >= 0.0) ? 1.0 : -1.0;
    for (int j = 0; j < 4; j++)
        q[j] = r[j] / norm * sign;
}

void sarins_ins_reset(sarins_ins *s)
{
    const double *c = s->config;
    s->steps = 0;
    s->pos[0] = c[SARINS_INS_LAT];
    s->pos[1] = c[SARINS_INS_LON];
    s->pos[2] = c[SARINS_INS_HEIGHT];
    for (int i = 0; i < 4; i++) {
        s->q[i] = s->q0[i];
        s->q_b0b[i] = (i == 0) ? 1.0 : 0.0;
    }
    for (int i = 0; i < 3; i++)
        s->v[i] = s->gyro_comp[i] = s->accel_comp[i] = s->v_b0[i] = s->v_b0_half[i] = 0.0;
    /* P0 = diag(tilt, tilt, heading, v, v, drift, drift, bias, bias)^2 ; Q = diag(arw x3, vrw x2,
     * drift_rw x2, bias_rw x2)^2 */
    const int p0_index[SARINS_INS_ALIGN_STATES] = {
        SARINS_INS_TILT0_STD, SARINS_INS_TILT0_STD, SARINS_INS_HEADING0_STD, SARINS_INS_VELOCITY0_STD,
        SARINS_INS_VELOCITY0_STD, SARINS_INS_DRIFT0_STD, SARINS_INS_DRIFT0_STD, SARINS_INS_BIAS0_STD,
        SARINS_INS_BIAS0_STD};
    const int q_index[SARINS_INS_ALIGN_STATES] = {
        SARINS_INS_ARW, SARINS_INS_ARW, SARINS_INS_ARW, SARINS_INS_VRW, SARINS_INS_VRW, SARINS_INS_DRIFT_RW,
        SARINS_INS_DRIFT_RW, SARINS_INS_BIAS_RW, SARINS_INS_BIAS_RW};
    enum { N = SARINS_INS_ALIGN_STATES };
    for (int i = 0; i < N; i++) {
        s->x[i] = 0.0;
        for (int j = 0; j < N; j++)
            s->p[N * i + j] = 0.0;
        double sd = c[p0_index[i]], qd = c[q_index[i]];
        s->p[N * i + i] = sd * sd;
        s->q_diag[i] = qd * qd;
    }
}

int sarins_ins_init(sarins_ins *s, const double *config, const double *mat_nb0, char *msg, size_t size)
{
    int status = sarins_ins_config_check(config, msg, size);
    if (status != SARINS_INS_OK)
        return status;
    double align = config[SARINS_INS_ALIGN_TIME], step = config[SARINS_INS_STEP];
    double q0[4] = {1.0, 0.0, 0.0, 0.0};
    if (align == 0.0) {
        if (mat_nb0 == NULL) {
            if (msg != NULL && size > 0)
                snprintf(msg, size, "align_time = 0 needs an initial attitude");
            return SARINS_INS_BAD_CONFIG;
        }
        for (int i = 0; i < 9; i++)
            if (!isfinite(mat_nb0[i])) {
                if (msg != NULL && size > 0)
                    snprintf(msg, size, "the initial attitude is not finite");
                return SARINS_INS_BAD_CONFIG;
            }
        sarins_mat_to_quat(mat_nb0, q0);
    }
    memset(s, 0, sizeof *s);
    for (int i = 0; i < SARINS_INS_CONFIG; i++)
        s->config[i] = config[i];
    for (int i = 0; i < 4; i++)
        s->q0[i] = q0[i];
    s->n_coarse = (align > 0.0) ? (int64_t)round_even(config[SARINS_INS_COARSE_TIME] / step) : 0;
    s->n_align = (int64_t)round_even(align / step);
    sarins_ins_reset(s);
    return SARINS_INS_OK;
}

int sarins_ins_phase(const sarins_ins *s)
{
    if (s->steps < s->n_coarse)
        return 0;
    return (s->steps < s->n_align) ? 1 : 2;
}

/* int_0^t mat_n0n(s) (0, 0, g) ds for a static point (see the header), m/s */
static void gravity_integral_n0(double lat, double height, double t, double *out)
{
    double u[3] = {0.0, sm_cos(lat), sm_sin(lat)};
    double k[9] = {0.0, -u[2], u[1], u[2], 0.0, -u[0], -u[1], u[0], 0.0};
    double w = SARINS_EARTH_RATE;
    double f[3] = {0.0, 0.0, sarins_earth_gravity(lat, height)};
    double kk[9], m[9];
    mat3_mult(k, k, kk);
    double c1 = (1.0 - sm_cos(w * t)) / w, c2 = t - sm_sin(w * t) / w;
    for (int i = 0; i < 9; i++)
        m[i] = (t * ((i % 4 == 0) ? 1.0 : 0.0) + c1 * k[i]) + c2 * kk[i];
    for (int i = 0; i < 3; i++)
        out[i] = dot3(m[3 * i], f[0], m[3 * i + 1], f[1], m[3 * i + 2], f[2]);
}

/* frame [x y z] (columns, row-major) of the vector pair (a, b): x = a/|a|, y = a x b/|a x b|, z = x x y */
static void triad_frame(const double *a, const double *b, double *frame)
{
    double x[3], y[3], z[3];
    double na = norm3(a);
    for (int i = 0; i < 3; i++)
        x[i] = a[i] / na;
    cross3(a, b, y);
    double ny = norm3(y);
    for (int i = 0; i < 3; i++)
        y[i] /= ny;
    cross3(x, y, z);
    for (int i = 0; i < 3; i++) {
        frame[3 * i] = x[i];
        frame[3 * i + 1] = y[i];
        frame[3 * i + 2] = z[i];
    }
}

/* End of the coarse alignment: q_nb from the TRIAD of (V_n0, V_b0) at T/2 and T (see the header). */
static void finish_coarse(sarins_ins *s)
{
    const double *c = s->config;
    double step = c[SARINS_INS_STEP], lat = c[SARINS_INS_LAT], height = c[SARINS_INS_HEIGHT];
    double t_half = (double)(s->n_coarse / 2) * step, t_end = (double)s->n_coarse * step;
    double r1[3], r2[3], fr[9], fb[9], fbt[9], mat_n0b0[9];
    gravity_integral_n0(lat, height, t_half, r1);
    gravity_integral_n0(lat, height, t_end, r2);
    triad_frame(r1, r2, fr);
    triad_frame(s->v_b0_half, s->v_b0, fb);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            fbt[3 * i + j] = fb[3 * j + i];
    /* mat_n0b0 = F_r F_b' */
    mat3_mult(fr, fbt, mat_n0b0);
    /* mat_nb(T) = mat_nn0(T) mat_n0b0 mat_b0b(T); n has turned by -omega_ie^n T wrt n0 (static) */
    double minus_zeta[3] = {-(0.0 * t_end), -((SARINS_EARTH_RATE * sm_cos(lat)) * t_end),
                            -((SARINS_EARTH_RATE * sm_sin(lat)) * t_end)};
    double qz[4], mat_nn0[9], mat_b0b[9], tmp[9], mat_nb[9];
    sarins_rotvec_to_quat(minus_zeta, qz);
    sarins_quat_to_mat(qz, mat_nn0);
    sarins_quat_to_mat(s->q_b0b, mat_b0b);
    mat3_mult(mat_nn0, mat_n0b0, tmp);
    mat3_mult(tmp, mat_b0b, mat_nb);
    sarins_mat_to_quat(mat_nb, s->q);
}

static int all_finite(int64_t n, const double *a)
{
    for (int64_t i = 0; i < n; i++)
        if (!isfinite(a[i]))
            return 0;
    return 1;
}

int sarins_ins_steps(sarins_ins *s, int64_t k, const double *dtheta, const double *dv, const double *axial_corr,
                     double *out, double *p_diag)
{
    if (k < 0 || !all_finite(3 * k, dtheta) || !all_finite(3 * k, dv) || !all_finite(k, axial_corr))
        return SARINS_INS_BAD_INPUT;
    double step = s->config[SARINS_INS_STEP];
    double row[SARINS_INS_ROW];
    int64_t i = 0;
    while (i < k) {
        int64_t m;
        int phase = sarins_ins_phase(s);
        if (phase == 0) {
            m = s->n_coarse - s->steps;
            m = (m < k - i) ? m : k - i;
            for (int64_t j = 0; j < m; j++) {
                double v_b0[3];
                sarins_ins_coarse_steps(1, s->q_b0b, s->v_b0, dtheta + 3 * (i + j), dv + 3 * (i + j), v_b0);
                if (s->steps + j + 1 == s->n_coarse / 2)
                    for (int d = 0; d < 3; d++)
                        s->v_b0_half[d] = v_b0[d];
            }
            if (s->steps + m == s->n_coarse)
                finish_coarse(s);
        } else if (phase == 1) {
            m = s->n_align - s->steps;
            m = (m < k - i) ? m : k - i;
            double r_var = s->config[SARINS_INS_VELOCITY_MEAS_STD] * s->config[SARINS_INS_VELOCITY_MEAS_STD];
            if (p_diag != NULL) { /* the whole run at once, the P diagonal into its rows */
                sarins_ins_align_steps(m, s->q, s->v, s->pos, dtheta + 3 * i, dv + 3 * i, step, s->gyro_comp,
                                       s->accel_comp, s->x, s->p, s->q_diag, r_var,
                                       p_diag + SARINS_INS_ALIGN_STATES * i);
            } else { /* step by step into a scratch row */
                for (int64_t j = 0; j < m; j++) {
                    double hist[SARINS_INS_ALIGN_STATES];
                    sarins_ins_align_steps(1, s->q, s->v, s->pos, dtheta + 3 * (i + j), dv + 3 * (i + j), step,
                                           s->gyro_comp, s->accel_comp, s->x, s->p, s->q_diag, r_var, hist);
                }
            }
            if (s->steps + m == s->n_align)
                s->v[0] = s->v[1] = s->v[2] = 0.0; /* known static start for navigation */
        } else {
            m = k - i;
            sarins_ins_nav_steps(m, s->q, s->v, s->pos, dtheta + 3 * i, dv + 3 * i, step, s->gyro_comp,
                                 s->accel_comp, axial_corr + i, out + SARINS_INS_ROW * i);
        }
        if (phase != 2) {
            sarins_ins_held_row(s->q, s->pos, row);
            for (int64_t j = 0; j < m; j++)
                for (int d = 0; d < SARINS_INS_ROW; d++)
                    out[SARINS_INS_ROW * (i + j) + d] = row[d];
        }
        s->steps += m;
        i += m;
    }
    return SARINS_INS_OK;
}

void sarins_ins_position_error(const sarins_ins *s, int64_t k, const double *rows, double *err)
{
    const double *c = s->config;
    double r_m, r_n;
    sarins_earth_radii(c[SARINS_INS_LAT], &r_m, &r_n);
    double north_scale = r_m + c[SARINS_INS_HEIGHT], east_scale = r_n + c[SARINS_INS_HEIGHT];
    double cos_lat = sm_cos(c[SARINS_INS_LAT]);
    for (int64_t i = 0; i < k; i++) {
        double dlat = rows[SARINS_INS_ROW * i] - c[SARINS_INS_LAT];
        double dlon = rows[SARINS_INS_ROW * i + 1] - c[SARINS_INS_LON];
        err[4 * i] = dlat;
        err[4 * i + 1] = dlon;
        err[4 * i + 2] = dlat * north_scale;
        err[4 * i + 3] = dlon * east_scale * cos_lat;
    }
}

int64_t sarins_ins_layout(int64_t *offsets)
{
    const size_t fields[] = {offsetof(sarins_ins, q),      offsetof(sarins_ins, v),
                             offsetof(sarins_ins, pos),    offsetof(sarins_ins, gyro_comp),
                             offsetof(sarins_ins, accel_comp), offsetof(sarins_ins, x),
                             offsetof(sarins_ins, p),      offsetof(sarins_ins, q_diag),
                             offsetof(sarins_ins, steps),  offsetof(sarins_ins, n_coarse),
                             offsetof(sarins_ins, n_align), offsetof(sarins_ins, config)};
    for (size_t i = 0; i < sizeof fields / sizeof fields[0]; i++)
        offsets[i] = (int64_t)fields[i];
    return (int64_t)sizeof(sarins_ins);
}
