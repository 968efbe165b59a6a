/* The IMU: see imu.h.  The evaluation order of every expression follows the
 * former numba kernels (sarins_fmu/imu_kernel.py, imu_step.py) term by term,
 * so the results are the same bit for bit. */
#include "smath.h"

#include <stdint.h>
#include <string.h>

#include "correlated.h"
#include "dynamics.h"
#include "imu.h"
#include "imu_build.h"
#include "thermal.h"
#include "workers.h"

#define PI 3.14159265358979323846

/* ------------------------------------------------------------ minor loop */

/* v <- R(a, theta)^T v = cos v - sin (a x v) + (1 - cos)(a.v) a, with c = cos theta, s = sin theta */
static void rot_t(double ax, double ay, double az, double c, double s, double v[3]) {
    double cx = ay * v[2] - az * v[1];
    double cy = az * v[0] - ax * v[2];
    double cz = ax * v[1] - ay * v[0];
    double d = (1.0 - c) * (ax * v[0] + ay * v[1] + az * v[2]);
    v[0] = c * v[0] - s * cx + d * ax;
    v[1] = c * v[1] - s * cy + d * ay;
    v[2] = c * v[2] - s * cz + d * az;
}

void sarins_imu_truth(int64_t n_axes, const double *axes, const double *angle0, const double *rate0,
                      const double *accel, double tau, const double *w_t, const double *f_t, double *out) {
    double w[3] = {w_t[0], w_t[1], w_t[2]};
    double f[3] = {f_t[0], f_t[1], f_t[2]};
    double s[3] = {0.0, 0.0, 0.0}; /* omega_tb resolved in the current gimbal frame */
    for (int64_t j = 0; j < n_axes; j++) {
        /* theta = theta0 + (rate0 + accel tau / 2) tau, thetadot = rate0 + accel tau */
        double th = angle0[j] + (rate0[j] + 0.5 * accel[j] * tau) * tau;
        double thd = rate0[j] + accel[j] * tau;
        double c, sn;
        sm_sincos(th, &sn, &c);
        double ax = axes[3 * j], ay = axes[3 * j + 1], az = axes[3 * j + 2];
        rot_t(ax, ay, az, c, sn, w);
        rot_t(ax, ay, az, c, sn, f);
        rot_t(ax, ay, az, c, sn, s);
        s[0] += thd * ax;
        s[1] += thd * ay;
        s[2] += thd * az;
    }
    /* omega_ib_b = mat_bt omega_it_t + omega_tb_b, f_b = mat_bt f_t */
    out[0] = w[0] + s[0];
    out[1] = w[1] + s[1];
    out[2] = w[2] + s[2];
    out[3] = f[0];
    out[4] = f[1];
    out[5] = f[2];
}

/* An interval's outputs from its composed quaternion q (changed) and velocity increment v: dtheta_k[3] the
 * rotation vector of q, its sign fixed so that the angle is in [0, pi] (2 atan2(|u|, w) u / |u|); dv_k[3] = v. */
static void finish(double q[4], const double v[3], double *dtheta_k, double *dv_k) {
    if (q[0] < 0.0) {
        for (int a = 0; a < 4; a++) q[a] = -q[a];
    }
    double vn = sm_sqrt(q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    double scale = vn > 1e-300 ? 2.0 * sm_atan2(vn, q[0]) / vn : 2.0;
    dtheta_k[0] = q[1] * scale;
    dtheta_k[1] = q[2] * scale;
    dtheta_k[2] = q[3] * scale;
    dv_k[0] = v[0];
    dv_k[1] = v[1];
    dv_k[2] = v[2];
}

/* The minor loop evaluates SARINS_IMU_LANES values side by side (struct of arrays, one element per lane):
 * LANES intervals of a batch (interval_lanes), or LANES consecutive minor steps of one interval (interval:
 * the terms that do not depend on the loop's serial state, i.e. all but the quaternion and the velocity
 * sum).  Every lane does the operations of the one-value formulas in the same order, so the results do not
 * depend on the layout, bit for bit, and equal those of the scalar formulas (sarins_imu_truth); the loops
 * over lanes carry no dependence, so the compiler evaluates them in SIMD registers.  The math calls (sincos,
 * exp, atan2) stay one per value. */
#define LANES SARINS_IMU_LANES
typedef double Lanes[LANES];
/* Lane arrays are passed as Lanes * even where a function only reads them (its comment names its outputs):
 * ISO C before C23 does not convert double (*)[N] to const double (*)[N] implicitly (-Wpedantic; MSVC C4090). */

/* With GCC or clang on x86-64 glibc, the lane functions are also compiled for AVX2 (four lanes in one register)
 * and the loader picks the variant the CPU runs; elsewhere the one portable build (SSE2 on x86-64).  Both do
 * the same IEEE operations (no contraction: -ffp-contract=off), so the results are the same. */
#if defined(__GNUC__) && defined(__x86_64__) && defined(__ELF__) && defined(__GLIBC__) && defined(__has_attribute)
#if __has_attribute(target_clones)
#define LANE_CLONES __attribute__((target_clones("avx2", "default")))
#define LANE_INLINE __attribute__((always_inline)) inline /* into each variant (GCC inlines no plain callee) */
#endif
#endif
#ifndef LANE_CLONES
#define LANE_CLONES
#define LANE_INLINE inline
#endif

/* The error terms of the minor loop that are the same for every interval of a batch. */
typedef struct {
    const double *g_mis, *g_quad, *g_lowrate, *g_width, *g_sens, *a_mis, *a_quad; /* as sarins_imu_increments */
    int lowrate; /* g_lowrate is not zero */
} Fixed;

static Fixed fixed_terms(const double *g_mis, const double *g_quad, const double *g_lowrate, const double *g_width,
                         const double *g_sens, const double *a_mis, const double *a_quad) {
    Fixed fx = {g_mis, g_quad, g_lowrate, g_width, g_sens, a_mis, a_quad,
                g_lowrate[0] != 0.0 || g_lowrate[1] != 0.0 || g_lowrate[2] != 0.0};
    return fx;
}

/* (x, y, z) <- R(a, theta)^T (x, y, z): rot_t on one lane's vector */
static LANE_INLINE void rot_t_lane(double ax, double ay, double az, double c, double s, double *x, double *y,
                                   double *z) {
    double v0 = *x, v1 = *y, v2 = *z;
    double cx = ay * v2 - az * v1;
    double cy = az * v0 - ax * v2;
    double cz = ax * v1 - ay * v0;
    double d = (1.0 - c) * (ax * v0 + ay * v1 + az * v2);
    *x = c * v0 - s * cx + d * ax;
    *y = c * v1 - s * cy + d * ay;
    *z = c * v2 - s * cz + d * az;
}

/* Gimbal j of the truth: w, f, s (v[0..8] lanes) turned by R^T as rot_t turns them, then s += thetadot a; the
 * gimbal state ang, rat, acc and the time tau (s) since the interval start per lane.  Lanes from n_valid on
 * hold no value: their cos, sin taken as 1, 0.  first: s is still the zero vector
 * (+0.0 each), taken as literals rather than stored (a store of zeros becomes a memset, a slow rep stos here). */
/* sn, c = sin, cos of the first n_valid lanes of th; the other lanes get 0, 1 (th's unused lanes are overwritten). */
static LANE_INLINE void lanes_sincos(Lanes th, int n_valid, Lanes sn, Lanes c) {
#if LANES == 4
    for (int l = n_valid; l < LANES; l++) th[l] = 1.0; /* no value: an ordinary argument, result unused */
    sm_sincos4(th, sn, c);
    for (int l = n_valid; l < LANES; l++) {
        c[l] = 1.0;
        sn[l] = 0.0;
    }
#else
    for (int l = 0; l < LANES; l++) {
        if (l < n_valid) {
            sm_sincos(th[l], &sn[l], &c[l]);
        } else {
            c[l] = 1.0;
            sn[l] = 0.0;
        }
    }
#endif
}

static LANE_INLINE void gimbal_lanes(int first, const double *restrict axis, const double *restrict ang,
                                     const double *restrict rat, const double *restrict acc,
                                     const double *restrict tau, int n_valid, Lanes *restrict v) {
    Lanes th, thd, c, sn;
    for (int l = 0; l < LANES; l++) {
        th[l] = ang[l] + (rat[l] + 0.5 * acc[l] * tau[l]) * tau[l];
        thd[l] = rat[l] + acc[l] * tau[l];
    }
    lanes_sincos(th, n_valid, sn, c);
    double ax = axis[0], ay = axis[1], az = axis[2];
    for (int l = 0; l < LANES; l++) {
        double s0 = first ? 0.0 : v[6][l], s1 = first ? 0.0 : v[7][l], s2 = first ? 0.0 : v[8][l];
        rot_t_lane(ax, ay, az, c[l], sn[l], &v[0][l], &v[1][l], &v[2][l]);
        rot_t_lane(ax, ay, az, c[l], sn[l], &v[3][l], &v[4][l], &v[5][l]);
        rot_t_lane(ax, ay, az, c[l], sn[l], &s0, &s1, &s2);
        v[6][l] = s0 + thd[l] * ax;
        v[7][l] = s1 + thd[l] * ay;
        v[8][l] = s2 + thd[l] * az;
    }
}

/* The truth's start: w_t, f_t [3] lanes into v (w, f, s); s zero only without a gimbal (else gimbal 0 sets it). */
static LANE_INLINE void truth_start(int64_t n_axes, Lanes *restrict w_t, Lanes *restrict f_t, Lanes *restrict v) {
    for (int a = 0; a < 3; a++) {
        for (int l = 0; l < LANES; l++) {
            v[a][l] = w_t[a][l];
            v[3 + a][l] = f_t[a][l];
        }
    }
    if (n_axes < 1) { /* no gimbal (the binding refuses it): s stays zero */
        for (int a = 6; a < 9; a++) {
            for (int l = 0; l < LANES; l++) v[a][l] = 0.0;
        }
    }
}

/* The truth's end: out [6] lanes = (w + s, f), sarins_imu_truth's out. */
static LANE_INLINE void truth_end(Lanes *restrict v, Lanes *restrict out) {
    for (int a = 0; a < 3; a++) {
        for (int l = 0; l < LANES; l++) {
            out[a][l] = v[a][l] + v[6 + a][l];
            out[3 + a][l] = v[3 + a][l];
        }
    }
}

/* sarins_imu_truth of LANES intervals at one time tau: gimbal states ang, rat, acc [A] lanes; w_t, f_t [3]
 * lanes; out [6] lanes. */
static LANE_INLINE void truth_lanes(int64_t n_axes, const double *restrict axes, Lanes *restrict ang,
                                    Lanes *restrict rat, Lanes *restrict acc, double tau, Lanes *restrict w_t,
                                    Lanes *restrict f_t, Lanes *restrict out) {
    Lanes v[9], taus; /* w, f, s (omega_tb in the current gimbal frame) */
    for (int l = 0; l < LANES; l++) taus[l] = tau;
    truth_start(n_axes, w_t, f_t, v);
    for (int64_t j = 0; j < n_axes; j++) {
        if (j == 0) {
            gimbal_lanes(1, axes, ang[0], rat[0], acc[0], taus, LANES, v);
        } else {
            gimbal_lanes(0, axes + 3 * j, ang[j], rat[j], acc[j], taus, LANES, v);
        }
    }
    truth_end(v, out);
}

/* The compensated increments of a minor step of length dt per lane from the truth t0, t1 [6] lanes at its
 * ends: trapezoid increments u (force), e (rate); da = (I + diag(gsf) + M_g) e + gb dt + q_g e|e| / dt + G u
 * + k e exp(-(e / (w dt))^2) (low rate; no exp for the lanes from n_valid on), dvm = (I + diag(asf) + M_a) u
 * + ab dt + q_a u|u| / dt; gsf, gb, asf, ab [3] lanes: the interval's scale factors and biases. */
static LANE_INLINE void minor_terms(Lanes *restrict t0, Lanes *restrict t1, double dt, int n_valid,
                                    const Fixed *restrict fx, Lanes *restrict gsf, Lanes *restrict gb,
                                    Lanes *restrict asf, Lanes *restrict ab, Lanes *restrict da, Lanes *restrict dvm) {
    const double *g_sens = fx->g_sens, *g_mis = fx->g_mis, *g_quad = fx->g_quad, *a_mis = fx->a_mis;
    const double *a_quad = fx->a_quad;
    Lanes u[3], e[3], g[3], x[3];
    for (int a = 0; a < 3; a++) {
        for (int l = 0; l < LANES; l++) {
            u[a][l] = 0.5 * (t0[3 + a][l] + t1[3 + a][l]) * dt;
            e[a][l] = 0.5 * (t0[a][l] + t1[a][l]) * dt;
        }
    }
    for (int a = 0; a < 3; a++) { /* g-sensitivity G u */
        for (int l = 0; l < LANES; l++)
            g[a][l] = g_sens[3 * a] * u[0][l] + g_sens[3 * a + 1] * u[1][l] + g_sens[3 * a + 2] * u[2][l];
    }
    if (fx->lowrate) { /* the exp calls of the three axes together: one wait for their results */
        for (int a = 0; a < 3; a++) {
            for (int l = 0; l < LANES; l++) {
                double r = e[a][l] / (dt * fx->g_width[a]);
                x[a][l] = -(r * r);
            }
        }
        for (int a = 0; a < 3; a++) {
            for (int l = 0; l < LANES; l++) x[a][l] = l < n_valid ? sm_exp(x[a][l]) : 0.0;
        }
        for (int a = 0; a < 3; a++) {
            for (int l = 0; l < LANES; l++) g[a][l] += fx->g_lowrate[a] * e[a][l] * x[a][l];
        }
    }
    for (int l = 0; l < LANES; l++) {
        double d0 = e[0][l], d1 = e[1][l], d2 = e[2][l];
        double da0 = d0 * (1.0 + gsf[0][l]) + g_mis[1] * d1 + g_mis[2] * d2 + gb[0][l] * dt
                     + g_quad[0] * d0 * sm_fabs(d0) / dt;
        double da1 = d1 * (1.0 + gsf[1][l]) + g_mis[3] * d0 + g_mis[5] * d2 + gb[1][l] * dt
                     + g_quad[1] * d1 * sm_fabs(d1) / dt;
        double da2 = d2 * (1.0 + gsf[2][l]) + g_mis[6] * d0 + g_mis[7] * d1 + gb[2][l] * dt
                     + g_quad[2] * d2 * sm_fabs(d2) / dt;
        da[0][l] = da0 + g[0][l];
        da[1][l] = da1 + g[1][l];
        da[2][l] = da2 + g[2][l];
        double u0 = u[0][l], u1 = u[1][l], u2 = u[2][l];
        dvm[0][l] = u0 * (1.0 + asf[0][l]) + a_mis[1] * u1 + a_mis[2] * u2 + ab[0][l] * dt
                    + a_quad[0] * u0 * sm_fabs(u0) / dt;
        dvm[1][l] = u1 * (1.0 + asf[1][l]) + a_mis[3] * u0 + a_mis[5] * u2 + ab[1][l] * dt
                    + a_quad[1] * u1 * sm_fabs(u1) / dt;
        dvm[2][l] = u2 * (1.0 + asf[2][l]) + a_mis[6] * u0 + a_mis[7] * u1 + ab[2][l] * dt
                    + a_quad[2] * u2 * sm_fabs(u2) / dt;
    }
}

/* A minor step's terms from its increments da, dvm and the previous step's pa, pv: sv[3] its velocity in
 * b(m-1), dnu + dalpha x dnu / 2 + (dalpha_prev x dnu + dnu_prev x dalpha) / 12 (sculling); p[3] its
 * coning-corrected rotation vector, dalpha + dalpha_prev x dalpha / 12; *c, *s: cos(|p|/2) and
 * sin(|p|/2) / |p| by their series to |p|^4. */
static LANE_INLINE void scull_cone(double da0, double da1, double da2, double dv0, double dv1, double dv2,
                                   double pa0, double pa1, double pa2, double pv0, double pv1, double pv2,
                                   double *restrict sv, double *restrict p, double *restrict c, double *restrict s) {
    sv[0] = dv0 + 0.5 * (da1 * dv2 - da2 * dv1) + ((pa1 * dv2 - pa2 * dv1) + (pv1 * da2 - pv2 * da1)) / 12.0;
    sv[1] = dv1 + 0.5 * (da2 * dv0 - da0 * dv2) + ((pa2 * dv0 - pa0 * dv2) + (pv2 * da0 - pv0 * da2)) / 12.0;
    sv[2] = dv2 + 0.5 * (da0 * dv1 - da1 * dv0) + ((pa0 * dv1 - pa1 * dv0) + (pv0 * da1 - pv1 * da0)) / 12.0;
    p[0] = da0 + (pa1 * da2 - pa2 * da1) / 12.0;
    p[1] = da1 + (pa2 * da0 - pa0 * da2) / 12.0;
    p[2] = da2 + (pa0 * da1 - pa1 * da0) / 12.0;
    double th2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
    *c = 1.0 - th2 / 8.0 + th2 * th2 / 384.0;
    *s = 0.5 - th2 / 48.0 + th2 * th2 / 3840.0;
}

/* The serial part of a minor step: v += q sv q* (the step's velocity into b(k-1)); q <- q * [c, s p]. */
/* n = q * (c, s p): one minor step's quaternion update (p the unit rotation axis, c, s the half angle's cos, sin). */
static LANE_INLINE void q_rotate(double q0, double q1, double q2, double q3, double p0, double p1, double p2,
                                 double c, double s, double *restrict n) {
    n[0] = q0 * c - s * (q1 * p0 + q2 * p1 + q3 * p2);
    n[1] = q0 * s * p0 + q1 * c + s * (q2 * p2 - q3 * p1);
    n[2] = q0 * s * p1 + q2 * c + s * (q3 * p0 - q1 * p2);
    n[3] = q0 * s * p2 + q3 * c + s * (q1 * p1 - q2 * p0);
}

/* o = sv rotated by q (sv + 2 q0 (qv x sv) + 2 qv x (qv x sv), the q_step velocity term). */
static LANE_INLINE void v_rotate(double q0, double q1, double q2, double q3, double s0, double s1, double s2,
                                 double *restrict o) {
    double cx = q2 * s2 - q3 * s1, cy = q3 * s0 - q1 * s2, cz = q1 * s1 - q2 * s0;
    o[0] = s0 + 2.0 * (q0 * cx + q2 * cz - q3 * cy);
    o[1] = s1 + 2.0 * (q0 * cy + q3 * cx - q1 * cz);
    o[2] = s2 + 2.0 * (q0 * cz + q1 * cy - q2 * cx);
}

static LANE_INLINE void q_step(double *restrict q, double *restrict v, const double *restrict sv,
                               const double *restrict p, double c, double s) {
    double o[3];
    v_rotate(q[0], q[1], q[2], q[3], sv[0], sv[1], sv[2], o);
    v[0] += o[0];
    v[1] += o[1];
    v[2] += o[2];
    q_rotate(q[0], q[1], q[2], q[3], p[0], p[1], p[2], c, s, q);
}

/* ---------------------------------------------- one interval, minor steps in lanes */

/* Minor steps per block of interval(): the lane phase fills a block's terms, the serial phase reads them. */
#define BLOCK 64
_Static_assert(BLOCK % LANES == 0, "a block holds whole lane groups");

/* A gimbal whose rate and acceleration are both zero (either sign) is still: theta = theta0 + (rate0 + accel
 * tau / 2) tau and thetadot = rate0 + accel tau are then the same bits at every tau > 0 (each product a zero
 * whose sign does not depend on tau), so its cos and sin are taken once per interval, at tau = dt. */
typedef struct {
    int still;
    double c, s, thd; /* cos theta, sin theta, thetadot at every minor time when still */
} Gimbal;

/* One interval's inputs to the minor loop and what is the same at all its minor steps (arguments of
 * interval()).  Gimbal 0 turns the interval's w_t, f_t and s = +0: the parts of rot_t that do not depend
 * on the angle (a x v, a . v) are taken once, with rot_t's operations. */
typedef struct {
    int64_t n_axes;
    const double *axes, *ang, *rat, *acc;
    double dt;
    Fixed fx;
    double v0[9], cr[9], dot[3]; /* w_t, f_t, +0 (3 each); their a x v; their a . v (gimbal 0's axis a) */
    double opg[3], gbdt[3], opa[3], abdt[3], wdt[3]; /* 1 + gsf, gb dt, 1 + asf, ab dt, dt w (low-rate width) */
    int quad; /* a quadratic coefficient is not zero; else its term q e|e| / dt is +-0 and the division is left
                 out (a zero divided by dt > 0 keeps its sign) */
    Gimbal g[SARINS_IMU_MAX_AXES]; /* gimbals from MAX_AXES on are taken as moving */
} Minor;

/* What the lane phase carries from one block to the next: the truth t at the last minor time done, that
 * step's increments d = (da, dvm) (zero before the first step). */
typedef struct {
    double t[6], d[6];
} Carry;

/* The serial phase's inputs of BLOCK minor steps (scull_cone's outputs), one column per step; qh: the
 * quaternion before each step, vt: each step's velocity term (filled by the serial phase). */
typedef struct {
    double sv[3][BLOCK], p[3][BLOCK], c[BLOCK], s[BLOCK], qh[4][BLOCK], vt[3][BLOCK];
} Block;

/* The lane phase's intermediate rows over a block: the truth at minor times i0 .. i0 + nb and the increments
 * da (rows 0-2), dvm (rows 3-5) of minor steps i0 .. i0 + nb (column 0: the carry; columns past nb: lanes that
 * hold no time, written and unused). */
typedef struct {
    double t[6][BLOCK + 1], d[6][BLOCK + 1];
} Stage;

/* cos, sin of gimbal j's angle and its rate at the LANES times tau (gimbal_lanes' values: lanes from n_valid on
 * hold no time, their cos, sin taken as 1, 0). */
static LANE_INLINE void gimbal_angle(const Minor *restrict in, int64_t j, const double *restrict tau, int n_valid,
                                     double *restrict c, double *restrict sn, double *restrict thd) {
    if (j < SARINS_IMU_MAX_AXES && in->g[j].still) {
        for (int l = 0; l < LANES; l++) {
            c[l] = in->g[j].c;
            sn[l] = in->g[j].s;
            thd[l] = in->g[j].thd;
        }
        return;
    }
    double ang = in->ang[j], rat = in->rat[j], acc = in->acc[j];
    Lanes th;
    for (int l = 0; l < LANES; l++) {
        th[l] = ang + (rat + 0.5 * acc * tau[l]) * tau[l];
        thd[l] = rat + acc * tau[l];
    }
    lanes_sincos(th, n_valid, sn, c);
}

/* truth_end of v (w, f, s) [9] lanes into columns col .. col + LANES - 1 of st->t */
static LANE_INLINE void truth_out(Lanes *restrict v, Stage *restrict st, int col) {
    double *o0 = st->t[0] + col, *o1 = st->t[1] + col, *o2 = st->t[2] + col;
    double *o3 = st->t[3] + col, *o4 = st->t[4] + col, *o5 = st->t[5] + col;
    for (int l = 0; l < LANES; l++) {
        o0[l] = v[0][l] + v[6][l];
        o1[l] = v[1][l] + v[7][l];
        o2[l] = v[2][l] + v[8][l];
        o3[l] = v[3][l];
        o4[l] = v[4][l];
        o5[l] = v[5][l];
    }
}

/* sarins_imu_truth of the interval at LANES times tau (lanes from n_valid on hold no time) into columns
 * col .. col + LANES - 1 of st->t.  Gimbal 0 from the interval's constants (Minor), the others as gimbal_lanes
 * turns them; the same operations on the same values as sarins_imu_truth. */
static LANE_INLINE void truth_steps(const Minor *restrict in, const double *restrict tau, int n_valid,
                                    Stage *restrict st, int col) {
    Lanes v[9], c, sn, thd; /* w, f, s (omega_tb in the current gimbal frame) */
    const double *a = in->axes, *x0 = in->v0, *cr = in->cr, *dot = in->dot;
    if (in->n_axes < 1) { /* no gimbal (the binding refuses it): w_t, f_t and s = +0 as they are */
        for (int r = 0; r < 9; r++) {
            for (int l = 0; l < LANES; l++) v[r][l] = x0[r];
        }
        truth_out(v, st, col);
        return;
    }
    gimbal_angle(in, 0, tau, n_valid, c, sn, thd);
    for (int l = 0; l < LANES; l++) { /* w, f, s: rot_t with a x v and a . v the interval's */
        double omc = 1.0 - c[l], dw = omc * dot[0], df = omc * dot[1], ds = omc * dot[2];
        v[0][l] = c[l] * x0[0] - sn[l] * cr[0] + dw * a[0];
        v[1][l] = c[l] * x0[1] - sn[l] * cr[1] + dw * a[1];
        v[2][l] = c[l] * x0[2] - sn[l] * cr[2] + dw * a[2];
        v[3][l] = c[l] * x0[3] - sn[l] * cr[3] + df * a[0];
        v[4][l] = c[l] * x0[4] - sn[l] * cr[4] + df * a[1];
        v[5][l] = c[l] * x0[5] - sn[l] * cr[5] + df * a[2];
        v[6][l] = (c[l] * x0[6] - sn[l] * cr[6] + ds * a[0]) + thd[l] * a[0];
        v[7][l] = (c[l] * x0[7] - sn[l] * cr[7] + ds * a[1]) + thd[l] * a[1];
        v[8][l] = (c[l] * x0[8] - sn[l] * cr[8] + ds * a[2]) + thd[l] * a[2];
    }
    for (int64_t j = 1; j < in->n_axes; j++) {
        gimbal_angle(in, j, tau, n_valid, c, sn, thd);
        double ax = a[3 * j], ay = a[3 * j + 1], az = a[3 * j + 2];
        for (int l = 0; l < LANES; l++) {
            rot_t_lane(ax, ay, az, c[l], sn[l], &v[0][l], &v[1][l], &v[2][l]);
            rot_t_lane(ax, ay, az, c[l], sn[l], &v[3][l], &v[4][l], &v[5][l]);
            rot_t_lane(ax, ay, az, c[l], sn[l], &v[6][l], &v[7][l], &v[8][l]);
            v[6][l] += thd[l] * ax;
            v[7][l] += thd[l] * ay;
            v[8][l] += thd[l] * az;
        }
    }
    truth_out(v, st, col);
}

/* minor_terms of one interval for the LANES steps ending at columns col + 1 .. col + LANES of st->t, into the
 * same columns of st->d; its constants taken from Minor (the same values, the same operations). */
static LANE_INLINE void step_terms(Stage *restrict st, int col, const Minor *restrict in, int n_valid) {
    const Fixed *fx = &in->fx;
    const double *g_sens = fx->g_sens, *g_mis = fx->g_mis, *g_quad = fx->g_quad, *a_mis = fx->a_mis;
    const double *a_quad = fx->a_quad;
    double dt = in->dt;
    Lanes u[3], e[3], g[3], x[3];
    for (int a = 0; a < 3; a++) {
        const double *f = st->t[3 + a] + col, *w = st->t[a] + col;
        for (int l = 0; l < LANES; l++) {
            u[a][l] = 0.5 * (f[l] + f[l + 1]) * dt;
            e[a][l] = 0.5 * (w[l] + w[l + 1]) * dt;
        }
    }
    for (int a = 0; a < 3; a++) { /* g-sensitivity G u */
        for (int l = 0; l < LANES; l++)
            g[a][l] = g_sens[3 * a] * u[0][l] + g_sens[3 * a + 1] * u[1][l] + g_sens[3 * a + 2] * u[2][l];
    }
    if (fx->lowrate) {
        for (int a = 0; a < 3; a++) {
            for (int l = 0; l < LANES; l++) {
                double r = e[a][l] / in->wdt[a];
                x[a][l] = -(r * r);
            }
        }
        for (int a = 0; a < 3; a++) {
            for (int l = 0; l < LANES; l++) x[a][l] = l < n_valid ? sm_exp(x[a][l]) : 0.0;
        }
        for (int a = 0; a < 3; a++) {
            for (int l = 0; l < LANES; l++) g[a][l] += fx->g_lowrate[a] * e[a][l] * x[a][l];
        }
    }
    Lanes qg[3], qa[3]; /* q e|e| / dt, q u|u| / dt */
    for (int a = 0; a < 3; a++) {
        for (int l = 0; l < LANES; l++) {
            qg[a][l] = g_quad[a] * e[a][l] * sm_fabs(e[a][l]);
            qa[a][l] = a_quad[a] * u[a][l] * sm_fabs(u[a][l]);
        }
    }
    if (in->quad) {
        for (int a = 0; a < 3; a++) {
            for (int l = 0; l < LANES; l++) {
                qg[a][l] = qg[a][l] / dt;
                qa[a][l] = qa[a][l] / dt;
            }
        }
    }
    const double *opg = in->opg, *gbdt = in->gbdt, *opa = in->opa, *abdt = in->abdt;
    double *da0 = st->d[0] + col + 1, *da1 = st->d[1] + col + 1, *da2 = st->d[2] + col + 1;
    double *dv0 = st->d[3] + col + 1, *dv1 = st->d[4] + col + 1, *dv2 = st->d[5] + col + 1;
    for (int l = 0; l < LANES; l++) {
        double d0 = e[0][l], d1 = e[1][l], d2 = e[2][l];
        da0[l] = (d0 * opg[0] + g_mis[1] * d1 + g_mis[2] * d2 + gbdt[0] + qg[0][l]) + g[0][l];
        da1[l] = (d1 * opg[1] + g_mis[3] * d0 + g_mis[5] * d2 + gbdt[1] + qg[1][l]) + g[1][l];
        da2[l] = (d2 * opg[2] + g_mis[6] * d0 + g_mis[7] * d1 + gbdt[2] + qg[2][l]) + g[2][l];
        double u0 = u[0][l], u1 = u[1][l], u2 = u[2][l];
        dv0[l] = u0 * opa[0] + a_mis[1] * u1 + a_mis[2] * u2 + abdt[0] + qa[0][l];
        dv1[l] = u1 * opa[1] + a_mis[3] * u0 + a_mis[5] * u2 + abdt[1] + qa[1][l];
        dv2[l] = u2 * opa[2] + a_mis[6] * u0 + a_mis[7] * u1 + abdt[2] + qa[2][l];
    }
}

/* Steps j0 .. j1 - 1 of block b's quaternion chain (q_step's quaternion part): q = (q0, q1, q2, q3) through
 * them, the quaternion before each step kept in b->qh. */
static LANE_INLINE void q_steps(Block *restrict b, int j0, int j1, double *restrict q) {
    double q0 = q[0], q1 = q[1], q2 = q[2], q3 = q[3];
    for (int j = j0; j < j1; j++) {
        b->qh[0][j] = q0;
        b->qh[1][j] = q1;
        b->qh[2][j] = q2;
        b->qh[3][j] = q3;
        double n[4];
        q_rotate(q0, q1, q2, q3, b->p[0][j], b->p[1][j], b->p[2][j], b->c[j], b->s[j], n);
        q0 = n[0];
        q1 = n[1];
        q2 = n[2];
        q3 = n[3];
    }
    q[0] = q0;
    q[1] = q1;
    q[2] = q2;
    q[3] = q3;
}

/* The lane phase of minor steps i0 + 1 .. i0 + nb (1 <= nb <= BLOCK) of one interval, LANES steps side by
 * side, in three passes over the block (short loop bodies, whose groups the CPU overlaps): the truth at the
 * step ends, the increments, the sculling and coning terms, into out.  The truth pass also takes the
 * previous block's quaternion chain (prev, prev_nb steps; none when prev is NULL) LANES steps a group: a
 * serial chain of short latency-bound steps beside independent work, which the CPU runs side by side. */
LANE_CLONES static void minor_block(const Minor *restrict in, int64_t i0, int nb, Carry *restrict carry,
                                    Block *restrict out, Block *restrict prev, int prev_nb, double *restrict q) {
    Stage st;
    double dt = in->dt;
    for (int a = 0; a < 6; a++) {
        st.t[a][0] = carry->t[a];
        st.d[a][0] = carry->d[a];
    }
    if (prev == NULL) prev_nb = 0;
    int done = 0; /* steps of prev taken */
    for (int j0 = 0; j0 < nb; j0 += LANES) {
        int n_valid = nb - j0 < LANES ? nb - j0 : LANES;
        Lanes tau;
        for (int l = 0; l < LANES; l++) tau[l] = (double)(i0 + j0 + l + 1) * dt;
        truth_steps(in, tau, n_valid, &st, j0 + 1);
        if (done < prev_nb) {
            int upto = done + LANES < prev_nb ? done + LANES : prev_nb;
            q_steps(prev, done, upto, q);
            done = upto;
        }
    }
    if (done < prev_nb) q_steps(prev, done, prev_nb, q);
    for (int j0 = 0; j0 < nb; j0 += LANES) step_terms(&st, j0, in, nb - j0 < LANES ? nb - j0 : LANES);
    for (int j0 = 0; j0 < nb; j0 += LANES) {
        /* the group's columns (indices from pointers: with -fwrapv, j0 + l may not be consecutive) */
        const double *pa0 = st.d[0] + j0, *pa1 = st.d[1] + j0, *pa2 = st.d[2] + j0;
        const double *pv0 = st.d[3] + j0, *pv1 = st.d[4] + j0, *pv2 = st.d[5] + j0;
        double *sv0 = out->sv[0] + j0, *sv1 = out->sv[1] + j0, *sv2 = out->sv[2] + j0;
        double *p0 = out->p[0] + j0, *p1 = out->p[1] + j0, *p2 = out->p[2] + j0;
        double *c = out->c + j0, *s = out->s + j0;
        for (int l = 0; l < LANES; l++) {
            double sv[3], p[3];
            scull_cone(pa0[l + 1], pa1[l + 1], pa2[l + 1], pv0[l + 1], pv1[l + 1], pv2[l + 1], pa0[l], pa1[l],
                       pa2[l], pv0[l], pv1[l], pv2[l], sv, p, &c[l], &s[l]);
            sv0[l] = sv[0]; /* written out, as in interval_lanes */
            sv1[l] = sv[1];
            sv2[l] = sv[2];
            p0[l] = p[0];
            p1[l] = p[1];
            p2[l] = p[2];
        }
    }
    for (int a = 0; a < 6; a++) {
        carry->t[a] = st.t[a][nb];
        carry->d[a] = st.d[a][nb];
    }
}

/* The velocity terms of steps j0 .. j1 - 1 of the block: q_step's, from the quaternion before each step (qh)
 * and its sv. */
static LANE_INLINE void v_range(Block *restrict b, int j0, int j1) {
    const double *Q0 = b->qh[0], *Q1 = b->qh[1], *Q2 = b->qh[2], *Q3 = b->qh[3];
    const double *S0 = b->sv[0], *S1 = b->sv[1], *S2 = b->sv[2];
    double *o0 = b->vt[0], *o1 = b->vt[1], *o2 = b->vt[2];
    for (int j = j0; j < j1; j++) {
        double o[3];
        v_rotate(Q0[j], Q1[j], Q2[j], Q3[j], S0[j], S1[j], S2[j], o);
        o0[j] = o[0];
        o1[j] = o[1];
        o2[j] = o[2];
    }
}

/* The velocity terms of nb steps of the block, LANES steps side by side. */
LANE_CLONES static void v_terms(Block *restrict b, int nb) {
    int j = 0;
    for (; j + LANES <= nb; j += LANES) v_range(b, j, j + LANES);
    v_range(b, j, nb);
}

/* The velocity part of the serial phase of nb minor steps (their quaternions before each step in qh): the
 * velocity terms (v_terms), summed into v in order. */
static void velocity_block(Block *restrict b, int nb, double *restrict v) {
    v_terms(b, nb);
    for (int a = 0; a < 3; a++) {
        double x = v[a];
        for (int j = 0; j < nb; j++) x += b->vt[a][j];
        v[a] = x;
    }
}

/* Minor's gimbal and per-interval terms (see Minor). */
static void minor_setup(Minor *in, const double *w_t, const double *f_t, const double *gsf, const double *gb,
                        const double *asf, const double *ab) {
    const double *a = in->axes, *g_quad = in->fx.g_quad, *a_quad = in->fx.a_quad;
    double dt = in->dt;
    for (int i = 0; i < 3; i++) {
        in->v0[i] = w_t[i];
        in->v0[3 + i] = f_t[i];
        in->v0[6 + i] = 0.0;
        in->opg[i] = 1.0 + gsf[i];
        in->gbdt[i] = gb[i] * dt;
        in->opa[i] = 1.0 + asf[i];
        in->abdt[i] = ab[i] * dt;
        in->wdt[i] = dt * in->fx.g_width[i];
    }
    for (int r = 0; r < 3; r++) { /* rot_t's a x v and a . v */
        const double *x = in->v0 + 3 * r;
        in->cr[3 * r] = a[1] * x[2] - a[2] * x[1];
        in->cr[3 * r + 1] = a[2] * x[0] - a[0] * x[2];
        in->cr[3 * r + 2] = a[0] * x[1] - a[1] * x[0];
        in->dot[r] = a[0] * x[0] + a[1] * x[1] + a[2] * x[2];
    }
    in->quad = 0;
    for (int i = 0; i < 3; i++) in->quad |= g_quad[i] != 0.0 || a_quad[i] != 0.0;
    for (int64_t j = 0; j < in->n_axes && j < SARINS_IMU_MAX_AXES; j++) {
        Gimbal *g = &in->g[j];
        g->still = in->rat[j] == 0.0 && in->acc[j] == 0.0;
        if (g->still) {
            double th = in->ang[j] + (in->rat[j] + 0.5 * in->acc[j] * dt) * dt;
            g->thd = in->rat[j] + in->acc[j] * dt;
            sm_sincos(th, &g->s, &g->c);
        }
    }
}

/* Minor loop of output interval k; writes dtheta[k], dv[k].  Blocks of BLOCK minor steps: the lane phase
 * (minor_block, which also takes the previous block's quaternion chain), then the velocity sums of the
 * previous block (velocity_block); the quaternion q_{b(k-1) b(m)} and the velocity
 * increment in b(k-1) are the only state the steps pass on. */
static void interval(int64_t k, int64_t n_axes, const double *axes, const double *angle0, const double *rate0,
                     const double *accel, const double *w_t, const double *f_t, double h, int64_t n_sub,
                     const double *g_sf, const double *g_mis, const double *g_bias, const double *g_quad,
                     const double *g_lowrate, const double *g_width, const double *g_sens, const double *a_sf,
                     const double *a_mis, const double *a_bias, const double *a_quad, double *dtheta,
                     double *dv) {
    Minor in;
    in.n_axes = n_axes;
    in.axes = axes;
    in.ang = angle0 + k * n_axes;
    in.rat = rate0 + k * n_axes;
    in.acc = accel + k * n_axes;
    in.dt = h / (double)n_sub;
    in.fx = fixed_terms(g_mis, g_quad, g_lowrate, g_width, g_sens, a_mis, a_quad);
    minor_setup(&in, w_t + 3 * k, f_t + 3 * k, g_sf + 3 * k, g_bias + 3 * k, a_sf + 3 * k, a_bias + 3 * k);
    Carry carry = {{0.0}, {0.0}};
    sarins_imu_truth(n_axes, axes, in.ang, in.rat, in.acc, 0.0, w_t + 3 * k, f_t + 3 * k, carry.t);
    double q[4] = {1.0, 0.0, 0.0, 0.0}, v[3] = {0.0, 0.0, 0.0};
    Block blocks[2], *prev = NULL; /* the block filled before this one, its quaternion chain still to take */
    int prev_nb = 0;
    for (int64_t i0 = 0; i0 < n_sub; i0 += BLOCK) {
        int nb = n_sub - i0 < BLOCK ? (int)(n_sub - i0) : BLOCK;
        Block *cur = &blocks[(i0 / BLOCK) & 1];
        minor_block(&in, i0, nb, &carry, cur, prev, prev_nb, q);
        if (prev != NULL) velocity_block(prev, prev_nb, v);
        prev = cur;
        prev_nb = nb;
    }
    if (prev != NULL) { /* the last block's chain (none when n_sub is 0) */
        q_steps(prev, 0, prev_nb, q);
        velocity_block(prev, prev_nb, v);
    }
    finish(q, v, dtheta + 3 * k, dv + 3 * k);
}

/* ------------------------------------------------- intervals in lanes */

/* rows k0..k0+LANES-1 of the (K, cols) array x into lanes, column-major */
static void load_lanes(const double *x, int64_t k0, int64_t cols, Lanes *out) {
    for (int64_t c = 0; c < cols; c++) {
        for (int l = 0; l < LANES; l++) out[c][l] = x[(k0 + l) * cols + c];
    }
}

/* The minor loops of intervals k0..k0+LANES-1 (n_axes <= SARINS_IMU_MAX_AXES); arguments as interval(). */
LANE_CLONES static void interval_lanes(int64_t k0, int64_t n_axes, const double *axes, const double *angle0,
                           const double *rate0, const double *accel, const double *w_t, const double *f_t, double h,
                           int64_t n_sub, const double *g_sf, const double *g_mis, const double *g_bias,
                           const double *g_quad, const double *g_lowrate, const double *g_width,
                           const double *g_sens, const double *a_sf, const double *a_mis, const double *a_bias,
                           const double *a_quad, double *dtheta, double *dv) {
    Lanes ang[SARINS_IMU_MAX_AXES], rat[SARINS_IMU_MAX_AXES], acc[SARINS_IMU_MAX_AXES];
    Lanes wk[3], fk[3], gsf[3], gb[3], asf[3], ab[3];
    load_lanes(angle0, k0, n_axes, ang);
    load_lanes(rate0, k0, n_axes, rat);
    load_lanes(accel, k0, n_axes, acc);
    load_lanes(w_t, k0, 3, wk);
    load_lanes(f_t, k0, 3, fk);
    load_lanes(g_sf, k0, 3, gsf);
    load_lanes(g_bias, k0, 3, gb);
    load_lanes(a_sf, k0, 3, asf);
    load_lanes(a_bias, k0, 3, ab);
    Fixed fx = fixed_terms(g_mis, g_quad, g_lowrate, g_width, g_sens, a_mis, a_quad);
    double dt = h / (double)n_sub;
    Lanes t0[6] = {{0.0}}, t1[6]; /* t0 set at i = 0 (initialised: GCC -O3 cannot see it and warns) */
    Lanes q[4], v[3], pa[3], pv[3]; /* as in interval(): pa, pv the previous step's increments */
    for (int l = 0; l < LANES; l++) {
        q[0][l] = 1.0;
        q[1][l] = q[2][l] = q[3][l] = 0.0;
        v[0][l] = v[1][l] = v[2][l] = 0.0;
        pa[0][l] = pa[1][l] = pa[2][l] = 0.0;
        pv[0][l] = pv[1][l] = pv[2][l] = 0.0;
    }
    for (int64_t i = 0; i <= n_sub; i++) { /* one call site of truth_lanes, inlined into each variant */
        truth_lanes(n_axes, axes, ang, rat, acc, (double)i * dt, wk, fk, t1);
        if (i == 0) {
            memcpy(t0, t1, sizeof t0);
            continue;
        }
        Lanes da[3], dvm[3];
        minor_terms(t0, t1, dt, LANES, &fx, gsf, gb, asf, ab, da, dvm);
        for (int l = 0; l < LANES; l++) {
            double sv[3], p[3], c, s;
            scull_cone(da[0][l], da[1][l], da[2][l], dvm[0][l], dvm[1][l], dvm[2][l], pa[0][l], pa[1][l],
                       pa[2][l], pv[0][l], pv[1][l], pv[2][l], sv, p, &c, &s);
            double ql[4] = {q[0][l], q[1][l], q[2][l], q[3][l]}, vl[3] = {v[0][l], v[1][l], v[2][l]};
            q_step(ql, vl, sv, p, c, s);
            q[0][l] = ql[0]; /* written out: a loop over the components here keeps GCC from vectorising */
            q[1][l] = ql[1];
            q[2][l] = ql[2];
            q[3][l] = ql[3];
            v[0][l] = vl[0];
            v[1][l] = vl[1];
            v[2][l] = vl[2];
            pa[0][l] = da[0][l];
            pa[1][l] = da[1][l];
            pa[2][l] = da[2][l];
            pv[0][l] = dvm[0][l];
            pv[1][l] = dvm[1][l];
            pv[2][l] = dvm[2][l];
        }
        memcpy(t0, t1, sizeof t0);
    }
    for (int l = 0; l < LANES; l++) {
        double ql[4] = {q[0][l], q[1][l], q[2][l], q[3][l]}, vl[3] = {v[0][l], v[1][l], v[2][l]};
        finish(ql, vl, dtheta + 3 * (k0 + l), dv + 3 * (k0 + l));
    }
}

void sarins_imu_increments_scalar(int64_t k0, int64_t k1, int64_t n_axes, const double *axes, const double *angle0,
                                  const double *rate0, const double *accel, const double *w_t, const double *f_t,
                                  double h, int64_t n_sub, const double *g_sf, const double *g_mis,
                                  const double *g_bias, const double *g_quad, const double *g_lowrate,
                                  const double *g_lowrate_width, const double *g_sens, const double *a_sf,
                                  const double *a_mis, const double *a_bias, const double *a_quad, double *dtheta,
                                  double *dv) {
    for (int64_t k = k0; k < k1; k++) {
        interval(k, n_axes, axes, angle0, rate0, accel, w_t, f_t, h, n_sub, g_sf, g_mis, g_bias, g_quad,
                 g_lowrate, g_lowrate_width, g_sens, a_sf, a_mis, a_bias, a_quad, dtheta, dv);
    }
}

void sarins_imu_increments(int64_t k0, int64_t k1, int64_t n_axes, const double *axes, const double *angle0,
                           const double *rate0, const double *accel, const double *w_t, const double *f_t,
                           double h, int64_t n_sub, const double *g_sf, const double *g_mis,
                           const double *g_bias, const double *g_quad, const double *g_lowrate,
                           const double *g_lowrate_width, const double *g_sens, const double *a_sf,
                           const double *a_mis, const double *a_bias, const double *a_quad, double *dtheta,
                           double *dv) {
    if (n_axes <= SARINS_IMU_MAX_AXES) {
        for (; k0 + LANES <= k1; k0 += LANES) {
            interval_lanes(k0, n_axes, axes, angle0, rate0, accel, w_t, f_t, h, n_sub, g_sf, g_mis, g_bias, g_quad,
                           g_lowrate, g_lowrate_width, g_sens, a_sf, a_mis, a_bias, a_quad, dtheta, dv);
        }
    }
    for (int64_t k = k0; k < k1; k++) { /* the remainder (or every interval of more than MAX_AXES gimbals) */
        interval(k, n_axes, axes, angle0, rate0, accel, w_t, f_t, h, n_sub, g_sf, g_mis, g_bias, g_quad,
                 g_lowrate, g_lowrate_width, g_sens, a_sf, a_mis, a_bias, a_quad, dtheta, dv);
    }
}

/* ------------------------------------------------------ interval terms */

void sarins_imu_interval_terms(int64_t n_steps, const double *temp0, const double *temps, double h,
                               const double *coef, const double *drift_poly, double drift_dtdt, double *gm,
                               const double *gm_phi, const double *gm_std, SarinsRng *gm_rng,
                               double *g_bias, double *g_sf, double *a_bias, double *a_sf) {
    double prev[6];
    memcpy(prev, temp0, sizeof prev);
    for (int64_t k = 0; k < n_steps; k++) {
        const double *now = temps + 6 * k;
        for (int j = 0; j < 6; j++) {
            /* Gauss-Markov exact step x_k = phi x_{k-1} + std sqrt(1 - phi^2) w_k */
            double w = gm_rng != NULL ? sarins_rng_normal(gm_rng) : 0.0;
            gm[j] = gm_phi[j] * gm[j] + gm_std[j] * sm_sqrt(1.0 - gm_phi[j] * gm_phi[j]) * w;
        }
        for (int t = 0; t < 2; t++) {
            for (int i = 0; i < 3; i++) {
                int s = 3 * t + i;
                const double *c = coef + 15 * t + i; /* rows 5t..5t+4, column i */
                double mid = 0.5 * (prev[s] + now[s]);
                double d = mid - SARINS_IMU_T_REF;
                /* b(T) = bias + tc1 (T - T_ref) + tc2 (T - T_ref)^2 + GM; sf(T) = sf + sf_tc (T - T_ref) */
                double bias = c[0] + c[3] * d + c[6] * d * d + gm[s];
                double sf = c[9] + c[12] * d;
                if (t == 0) {
                    if (i == 2) { /* azimuth drift model eps(T) = (a T + b) T + c, plus d dT/dt */
                        bias += (drift_poly[0] * mid + drift_poly[1]) * mid + drift_poly[2];
                        bias += drift_dtdt * (now[s] - prev[s]) / h;
                    }
                    g_bias[3 * k + i] = bias;
                    g_sf[3 * k + i] = sf;
                } else {
                    a_bias[3 * k + i] = bias;
                    a_sf[3 * k + i] = sf;
                }
            }
        }
        memcpy(prev, now, sizeof prev);
    }
}

/* ------------------------------------------ azimuth-gyro thermal terms */

void sarins_imu_axial_thermal_terms(int64_t n_steps, double temp0, const double *temps, int64_t t_stride, double h,
                                    const double *par, double *state, double *bias, int64_t b_stride) {
    double k_grad = par[0], tau_b = par[1], hyst = par[2], width = par[3], tau_r = par[4];
    if (k_grad == 0.0 && hyst == 0.0) return;
    double e_b = tau_b > 0.0 ? sm_exp(-h / tau_b) : 0.0;
    double e_r = tau_r > 0.0 ? sm_exp(-h / tau_r) : 1.0;
    double prev = temp0;
    for (int64_t k = 0; k < n_steps; k++) {
        double now = temps[k * t_stride];
        double grad0 = prev - state[0];
        if (tau_b > 0.0) { /* the input T, linear over the interval */
            state[0] = sarins_first_order_step(state[0], prev, (now - prev) / h, h, tau_b, e_b);
        } else {
            state[0] = now;
        }
        double grad = 0.5 * (grad0 + (now - state[0]));
        double mid = 0.5 * (prev + now);
        double play = sm_fmax(mid - width, sm_fmin(mid + width, state[1]));
        state[1] = mid + (play - mid) * e_r;
        bias[k * b_stride] += k_grad * grad + hyst * (mid - state[1]) / width;
        prev = now;
    }
}

/* ------------------------------------------------------ the state table */

typedef struct {
    double *consts, *clock, *sensor_par, *state, *coef, *triad, *mats, *axes, *base, *rng, *corr_par, *corr_state,
        *phi, *q, *x_flicker, *dyn_par, *dyn_state, *periodic;
    int64_t n_axes, n_flicker;
    SarinsRng streams[SARINS_IMU_N_STREAMS]; /* the RNG rows unpacked (imu_view), kept equal to them */
    int have_streams;
} ImuView;

static double *table_array(const int64_t *table, int64_t i) { return (double *)(intptr_t)table[3 * i]; }

static int has_shape(const int64_t *table, int64_t i, int64_t rows, int64_t cols) {
    return table[3 * i + 1] == rows && table[3 * i + 2] == cols && (rows == 0 || table[3 * i] != 0);
}

/* The IMU arrays of table rows 0..17 with their shapes checked; 0 when they fit. */
static int imu_shapes(const int64_t *table, int64_t rows, ImuView *v) {
    v->have_streams = 0;
    if (table == NULL || rows < SARINS_IMU_N_ARRAYS) return SARINS_IMU_BAD_TABLE;
    v->n_axes = table[3 * SARINS_IMU_AXES + 1];
    v->n_flicker = table[3 * SARINS_IMU_PHI + 1];
    if (!(has_shape(table, SARINS_IMU_CONSTS, SARINS_IMU_N_CONSTS, 1) && has_shape(table, SARINS_IMU_CLOCK, 2, 1)
          && has_shape(table, SARINS_IMU_SENSOR_PAR, 4, 6) && has_shape(table, SARINS_IMU_STATE, 3, 6)
          && has_shape(table, SARINS_IMU_COEF, 10, 3) && has_shape(table, SARINS_IMU_TRIAD, 7, 3)
          && has_shape(table, SARINS_IMU_MATS, 9, 3) && v->n_axes >= 1
          && has_shape(table, SARINS_IMU_AXES, v->n_axes, 3) && has_shape(table, SARINS_IMU_BASE, 2, 3)
          && has_shape(table, SARINS_IMU_RNG, SARINS_IMU_N_STREAMS, SARINS_RNG_WORDS)
          && has_shape(table, SARINS_IMU_CORR_PAR, 8, 6) && has_shape(table, SARINS_IMU_CORR_STATE, 3, 6)
          && v->n_flicker >= 0 && has_shape(table, SARINS_IMU_PHI, v->n_flicker, 1)
          && has_shape(table, SARINS_IMU_Q, v->n_flicker, 6) && has_shape(table, SARINS_IMU_X_FLICKER, v->n_flicker, 6)
          && has_shape(table, SARINS_IMU_DYN_PAR, SARINS_DYN_PAR_ROWS, 6)
          && has_shape(table, SARINS_IMU_DYN_STATE, SARINS_DYN_STATE_ROWS, 6)
          && has_shape(table, SARINS_IMU_PERIODIC, 3, 6)))
        return SARINS_IMU_BAD_TABLE;
    v->consts = table_array(table, SARINS_IMU_CONSTS);
    v->clock = table_array(table, SARINS_IMU_CLOCK);
    v->sensor_par = table_array(table, SARINS_IMU_SENSOR_PAR);
    v->state = table_array(table, SARINS_IMU_STATE);
    v->coef = table_array(table, SARINS_IMU_COEF);
    v->triad = table_array(table, SARINS_IMU_TRIAD);
    v->mats = table_array(table, SARINS_IMU_MATS);
    v->axes = table_array(table, SARINS_IMU_AXES);
    v->base = table_array(table, SARINS_IMU_BASE);
    v->rng = table_array(table, SARINS_IMU_RNG);
    v->corr_par = table_array(table, SARINS_IMU_CORR_PAR);
    v->corr_state = table_array(table, SARINS_IMU_CORR_STATE);
    v->phi = table_array(table, SARINS_IMU_PHI);
    v->q = table_array(table, SARINS_IMU_Q);
    v->x_flicker = table_array(table, SARINS_IMU_X_FLICKER);
    v->dyn_par = table_array(table, SARINS_IMU_DYN_PAR);
    v->dyn_state = table_array(table, SARINS_IMU_DYN_STATE);
    v->periodic = table_array(table, SARINS_IMU_PERIODIC);
    /* consts: t0, h, drift_dtdt, die_lag, correlated_active, n_sub, (spare), (spare), the five parameters of
     * sarins_imu_axial_thermal_terms (block and relaxation times >= 0, width > 0) */
    if (!(v->consts[1] > 0.0 && v->consts[5] >= 1.0 && v->consts[5] <= (double)SARINS_IMU_MAX_SUB
          && v->consts[5] == sm_nearbyint(v->consts[5]) && v->consts[9] >= 0.0 && v->consts[11] > 0.0
          && v->consts[12] >= 0.0))
        return SARINS_IMU_BAD_TABLE;
    /* periodic: amplitudes >= 0, frequencies in [0, n_sub / (2 h)], phases finite (a handed-back state too) */
    for (int j = 0; j < 6; j++) {
        double a = v->periodic[j], f = v->periodic[6 + j], phase = v->periodic[12 + j];
        if (!(a >= 0.0 && a < INFINITY && f >= 0.0 && f * v->consts[1] <= 0.5 * v->consts[5] && isfinite(phase)))
            return SARINS_IMU_BAD_TABLE;
    }
    return SARINS_IMU_OK;
}

/* imu_shapes, and every stream state checked, so that no later load fails after a state has changed. */
static int imu_view(const int64_t *table, int64_t rows, ImuView *v) {
    int status = imu_shapes(table, rows, v);
    if (status != SARINS_IMU_OK) return status;
    for (int s = 0; s < SARINS_IMU_N_STREAMS; s++) {
        if (!sarins_rng_unpack(v->rng + SARINS_RNG_WORDS * s, &v->streams[s])) return SARINS_IMU_BAD_TABLE;
    }
    v->have_streams = 1;
    return SARINS_IMU_OK;
}

/* 1 when any of x[0..n) is not zero */
static int any_nonzero(const double *x, int64_t n) {
    for (int64_t i = 0; i < n; i++) {
        if (x[i] != 0.0) return 1;
    }
    return 0;
}

/* The stream of the table's RNG row `stream` into r; 0 when the row is not a stream state. */
static int load_stream(const ImuView *v, int stream, SarinsRng *r) {
    if (v->have_streams) {
        *r = v->streams[stream];
        return 1;
    }
    return sarins_rng_unpack(v->rng + SARINS_RNG_WORDS * stream, r);
}

static void store_stream(ImuView *v, int stream, const SarinsRng *r) {
    sarins_rng_pack(r, (uint64_t)stream, v->rng + SARINS_RNG_WORDS * stream);
    if (v->have_streams) v->streams[stream] = *r;
}

/* The table functions below check the table once (imu_view) and then work on the view: a table that passed
 * stays valid through a step (the streams are stored packed as sarins_rng_pack writes them). */

static int advance_view(ImuView *v, int64_t n_steps, const double *amb_end, double *temps, double *die,
                        double *g_bias, double *g_sf, double *a_bias, double *a_sf) {
    SarinsRng gm_rng, flicker_rng, rrw_rng;
    if (!(load_stream(v, SARINS_IMU_STREAM_GM, &gm_rng) && load_stream(v, SARINS_IMU_STREAM_FLICKER, &flicker_rng)
          && load_stream(v, SARINS_IMU_STREAM_RRW, &rrw_rng)))
        return SARINS_IMU_BAD_TABLE;
    int gm_on = any_nonzero(v->sensor_par + 18, 6);
    int flicker_on = any_nonzero(v->q, 6 * v->n_flicker), rrw_on = any_nonzero(v->corr_par + 30, 6);
    double h = v->consts[1];
    double *temperature = v->state; /* reported temperatures, row 0 */
    double start[6];
    memcpy(start, temperature, sizeof start);
    sarins_thermal_steps(v->consts[0], h, v->clock[0], v->clock[1], n_steps, amb_end, 6, v->sensor_par,
                         v->sensor_par + 6, temperature, temps);
    v->clock[1] = amb_end[n_steps - 1];
    const double *die0 = start, *die_t = temps;
    double die_start[6];
    if (v->consts[3] != 0.0) { /* the errors follow the die, which lags the reported temperature */
        double *die_now = v->corr_state; /* row 0 */
        memcpy(die_start, die_now, sizeof die_start);
        sarins_die_temperatures(n_steps, 6, start, temps, h, v->corr_par, die_now, die);
        die0 = die_start;
        die_t = die;
    }
    sarins_imu_interval_terms(n_steps, die0, die_t, h, v->coef, v->triad, v->consts[2], v->state + 6,
                              v->sensor_par + 12, v->sensor_par + 18, gm_on ? &gm_rng : NULL, g_bias, g_sf, a_bias,
                              a_sf);
    store_stream(v, SARINS_IMU_STREAM_GM, &gm_rng);
    sarins_imu_axial_thermal_terms(n_steps, die0[2], die_t + 2, 6, h, v->consts + 8, v->state + 12, g_bias + 2, 3);
    if (v->consts[4] != 0.0) {
        sarins_correlated_terms(n_steps, die0, die_t, h, v->corr_par, v->corr_state, v->n_flicker, v->phi, v->q,
                                v->x_flicker, flicker_on ? &flicker_rng : NULL, rrw_on ? &rrw_rng : NULL, g_bias,
                                g_sf, a_bias, a_sf);
        store_stream(v, SARINS_IMU_STREAM_FLICKER, &flicker_rng);
        store_stream(v, SARINS_IMU_STREAM_RRW, &rrw_rng);
    }
    return SARINS_IMU_OK;
}

int sarins_imu_advance(const int64_t *table, int64_t rows, int64_t n_steps, const double *amb_end, double *temps,
                       double *die, double *g_bias, double *g_sf, double *a_bias, double *a_sf) {
    ImuView v;
    int status = imu_view(table, rows, &v);
    if (status != SARINS_IMU_OK) return status;
    if (n_steps < 1) return SARINS_IMU_BAD_TABLE;
    return advance_view(&v, n_steps, amb_end, temps, die, g_bias, g_sf, a_bias, a_sf);
}

static void dynamics_view(ImuView *v, int64_t n_steps, const double *temps, double *dtheta, double *dv) {
    if (sarins_dynamics_active(v->dyn_par))
        sarins_dynamics_apply(n_steps, v->consts[1], temps, v->dyn_par, v->dyn_state, SARINS_IMU_T_REF, dtheta, dv);
}

int sarins_imu_dynamics(const int64_t *table, int64_t rows, int64_t n_steps, const double *temps, double *dtheta,
                        double *dv) {
    ImuView v;
    int status = imu_view(table, rows, &v);
    if (status != SARINS_IMU_OK) return status;
    if (n_steps < 0) return SARINS_IMU_BAD_TABLE;
    dynamics_view(&v, n_steps, temps, dtheta, dv);
    return SARINS_IMU_OK;
}

/* The periodic disturbance's exact integral over K intervals from the clock's (periodic row of imu.h) added to
 * dtheta (gyro columns 0-2) and dv (accel 3-5). */
static void periodic_view(const ImuView *v, int64_t n_steps, double *dtheta, double *dv) {
    const double *amp = v->periodic, *freq = v->periodic + 6, *phase = v->periodic + 12;
    double h = v->consts[1], k0 = v->clock[0];
    for (int j = 0; j < 6; j++) {
        if (amp[j] == 0.0) continue;
        double *out = j < 3 ? dtheta + j : dv + (j - 3);
        /* integral of a sin(2 pi f t + phi) over [k h, (k + 1) h] = (a / (pi f)) sin(pi f h) sin(2 pi f (k + 1/2) h
           + phi); the cycles f h (k + 1/2) reduced to [0, 1) before the 2 pi */
        double fh = freq[j] * h;
        double gain = amp[j] * sm_sin(PI * fh) / (PI * freq[j]);
        for (int64_t k = 0; k < n_steps; k++) {
            double cycles = fh * (k0 + (double)k + 0.5);
            out[3 * k] += gain * sm_sin(2.0 * PI * (cycles - sm_floor(cycles)) + phase[j]);
        }
    }
}

static int white_noise_view(ImuView *v, int64_t n_steps, double *dtheta, double *dv) {
    periodic_view(v, n_steps, dtheta, dv);
    SarinsRng rng;
    if (!load_stream(v, SARINS_IMU_STREAM_WHITE, &rng)) return SARINS_IMU_BAD_TABLE;
    double sqrt_h = sm_sqrt(v->consts[1]);
    const double *rw_g = v->triad + 15, *rw_a = v->triad + 18; /* triad rows 5 and 6 */
    if (any_nonzero(rw_g, 6)) { /* rows 5 and 6 are adjacent */
        for (int64_t k = 0; k < n_steps; k++) {
            double w[6];
            for (int i = 0; i < 6; i++) w[i] = sarins_rng_normal(&rng);
            for (int i = 0; i < 3; i++) {
                /* N(0, rw^2 h): the random walk integrated over the interval */
                dtheta[3 * k + i] += w[i] * sqrt_h * rw_g[i];
                dv[3 * k + i] += w[3 + i] * sqrt_h * rw_a[i];
            }
        }
        store_stream(v, SARINS_IMU_STREAM_WHITE, &rng);
    }
    v->clock[0] += (double)n_steps;
    return SARINS_IMU_OK;
}

int sarins_imu_white_noise(const int64_t *table, int64_t rows, int64_t n_steps, double *dtheta, double *dv) {
    ImuView v;
    int status = imu_view(table, rows, &v);
    if (status != SARINS_IMU_OK) return status;
    if (n_steps < 0) return SARINS_IMU_BAD_TABLE;
    return white_noise_view(&v, n_steps, dtheta, dv);
}

/* The arguments of sarins_imu_increments for one batch, run in chunks by the workers. */
typedef struct {
    const ImuView *v;
    const double *angle0, *rate0, *accel, *w_t, *f_t, *g_sf, *g_bias, *a_sf, *a_bias;
    double *dtheta, *dv;
} IncrementsJob;

static void increments_chunk(void *arg, int64_t k0, int64_t k1) {
    const IncrementsJob *j = arg;
    const ImuView *v = j->v;
    /* triad rows: drift poly, gyro quadratic, low-rate gain, low-rate width, accel quadratic, random walks;
       mats rows: gyro misalignment, g-sensitivity, accel misalignment */
    sarins_imu_increments(k0, k1, v->n_axes, v->axes, j->angle0, j->rate0, j->accel, j->w_t, j->f_t, v->consts[1],
                          (int64_t)v->consts[5], j->g_sf, v->mats, j->g_bias, v->triad + 3, v->triad + 6,
                          v->triad + 9, v->mats + 9, j->a_sf, v->mats + 18, j->a_bias, v->triad + 12, j->dtheta,
                          j->dv);
}

/* n_steps intervals: advance, the minor loops (on the workers' threads when pool is not NULL: the intervals
 * are independent, so the same bits), output dynamics, white noise. */
static int steps_view(ImuView *v, int64_t n_steps, const double *angle0, const double *rate0,
                      const double *accel, const double *w_t, const double *f_t, const double *amb_end,
                      double *dtheta, double *dv, double *temps, double *work, sarins_workers *pool) {
    double *g_bias = work, *g_sf = work + 3 * n_steps, *a_bias = work + 6 * n_steps, *a_sf = work + 9 * n_steps;
    int status = advance_view(v, n_steps, amb_end, temps, work + 12 * n_steps, g_bias, g_sf, a_bias, a_sf);
    if (status != SARINS_IMU_OK) return status;
    IncrementsJob job = {v, angle0, rate0, accel, w_t, f_t, g_sf, g_bias, a_sf, a_bias, dtheta, dv};
    sarins_workers_run(pool, increments_chunk, &job, n_steps);
    dynamics_view(v, n_steps, temps, dtheta, dv);
    return white_noise_view(v, n_steps, dtheta, dv);
}

int sarins_imu_steps(const int64_t *table, int64_t rows, int64_t n_steps, const double *angle0,
                     const double *rate0, const double *accel, const double *w_t, const double *f_t,
                     const double *amb_end, double *dtheta, double *dv, double *temps, double *work) {
    ImuView v;
    int status = imu_view(table, rows, &v);
    if (status != SARINS_IMU_OK) return status;
    if (n_steps < 1) return SARINS_IMU_BAD_TABLE;
    return steps_view(&v, n_steps, angle0, rate0, accel, w_t, f_t, amb_end, dtheta, dv, temps, work, NULL);
}

/* One interval with the base motion of the view's base row (sarins_imu_one_interval). */
static int one_interval_view(ImuView *v, const double *angle0, const double *rate0, const double *accel,
                             double amb_end, double *dtheta, double *dv, double *temps) {
    double work[18];
    return steps_view(v, 1, angle0, rate0, accel, v->base, v->base + 3, &amb_end, dtheta, dv, temps, work,
                      NULL);
}

int sarins_imu_one_interval(const int64_t *table, int64_t rows, const double *angle0, const double *rate0,
                            const double *accel, double amb_end, double *dtheta, double *dv, double *temps) {
    ImuView v;
    int status = imu_view(table, rows, &v);
    if (status != SARINS_IMU_OK) return status;
    return one_interval_view(&v, angle0, rate0, accel, amb_end, dtheta, dv, temps);
}

/* ------------------------------------------------------ seeding and ageing */

void sarins_imu_turn_on(uint64_t seed, const double *std, double *out) {
    SarinsRng r;
    sarins_rng_stream(&r, seed, SARINS_IMU_STREAM_TURN_ON);
    for (int j = 0; j < 6; j++) out[j] = std[j] * sarins_rng_normal(&r);
}

int sarins_imu_seed(const int64_t *table, int64_t rows, uint64_t seed) {
    ImuView v;
    int status = imu_shapes(table, rows, &v); /* the stream states are written here */
    if (status != SARINS_IMU_OK) return status;
    for (int s = 0; s < SARINS_IMU_N_STREAMS; s++) {
        SarinsRng r;
        sarins_rng_stream(&r, seed, (uint64_t)s);
        if (s == SARINS_IMU_STREAM_GM) { /* stationary start of the Gauss-Markov biases */
            const double *gm_std = v.sensor_par + 18;
            for (int j = 0; j < 6; j++) v.state[6 + j] = gm_std[j] * sarins_rng_normal(&r);
        } else if (s == SARINS_IMU_STREAM_FLICKER) { /* stationary start of the flicker terms */
            for (int64_t i = 0; i < 6 * v.n_flicker; i++) v.x_flicker[i] = v.q[i] * sarins_rng_normal(&r);
        }
        store_stream(&v, s, &r);
    }
    SarinsRng r; /* the periodic terms' phases, uniform on [0, 2 pi): a stream of their own, drawn here only */
    sarins_rng_stream(&r, seed, SARINS_IMU_STREAM_PERIODIC);
    for (int j = 0; j < 6; j++) v.periodic[12 + j] = 2.0 * PI * sarins_rng_uniform(&r);
    sarins_imu_turn_on(seed, v.corr_par + 42, v.corr_par + 36);
    return SARINS_IMU_OK;
}

void sarins_imu_aged_poly(uint64_t seed, int64_t n, const double *t, const double *poly, const double *sigma,
                          double tau, double *out) {
    SarinsRng r;
    sarins_rng_stream(&r, seed, SARINS_IMU_STREAM_AGEING);
    double m[3] = {0.0, 0.0, 0.0}, prev = 0.0;
    for (int64_t k = 0; k < n; k++) {
        double d = sm_exp(-(t[k] - prev) / tau);
        for (int i = 0; i < 3; i++) {
            /* m <- d m + sigma sqrt(1 - d^2) w */
            m[i] = d * m[i] + sigma[i] * sm_sqrt(1.0 - d * d) * sarins_rng_normal(&r);
            out[3 * k + i] = poly[i] + m[i];
        }
        prev = t[k];
    }
}

/* ------------------------------------------------------ the FMU's step */

#define TAG_TOL SARINS_IMU_TAG_TOL
#define NO_TAG SARINS_IMU_NO_TAG
#define VEHICLE_SET SARINS_IMU_VEHICLE_SET
enum { IO_STEP = SARINS_IMU_IO_STEP, IO_START = SARINS_IMU_IO_START, IO_GIMBALS = SARINS_IMU_IO_GIMBALS,
       IO_MOTION_TIME = SARINS_IMU_IO_MOTION_TIME, IO_AMBIENT = SARINS_IMU_IO_AMBIENT, IO_MOTION = SARINS_IMU_IO_MOTION,
       IO_OUT = SARINS_IMU_IO_OUT, IO_END_TIME = SARINS_IMU_IO_END_TIME, IO_VEHICLE = SARINS_IMU_IO_VEHICLE,
       IO_SIZE = SARINS_IMU_IO_SIZE };

static int same_time(double a, double b, double step) { return sm_fabs(a - b) <= TAG_TOL * step; }

/* Buffer index of a slot (a float64 holding an index), or -1 outside buf[0..n). */
static int64_t slot_index(double slot, int64_t n) {
    if (!(slot >= 0.0 && slot < (double)n)) return -1;
    return (int64_t)slot;
}

/* out[i] = buf[slots[i]]; 0 if a slot is out of range or a value not finite. */
static int read_slots(const double *buf, int64_t n, const double *slots, int count, double *out) {
    for (int i = 0; i < count; i++) {
        int64_t at = slot_index(slots[i], n);
        if (at < 0) return 0;
        out[i] = buf[at];
        if (!isfinite(out[i])) return 0;
    }
    return 1;
}

/* The set tagged t among the current one and the held one (held = [kept, tag, values...]) into chosen;
 * 0 when neither is. */
static int choose(const double *held, const double *current, int count, double tag, double t, double h,
                  double *chosen) {
    if (same_time(tag, t, h)) {
        memcpy(chosen, current, (size_t)count * sizeof *chosen);
        return 1;
    }
    if (held[0] != 0.0 && same_time(held[1], t, h)) {
        memcpy(chosen, held + 2, (size_t)count * sizeof *chosen);
        return 1;
    }
    return 0;
}

static void keep(double *held, const double *current, int count, double tag) {
    memcpy(held + 2, current, (size_t)count * sizeof *held);
    held[1] = tag;
    held[0] = 1.0;
}

/* Sub-interval k's start-of-interval motion (k_sub > 1): the set of the step start carried forward with its
 * acceleration, theta = theta0 + (rate0 + accel tau / 2) tau, rate = rate0 + accel tau (sarins_imu_truth's
 * law, tau = k h_sub); the base row held; the ambient linear. */
static void sub_motion(int64_t k_sub, int m, double h_sub, double motion[3][SARINS_IMU_MAX_AXES], const double *base,
                       double amb0, double amb_rate, double *scratch) {
    double *angle0 = scratch, *rate0 = angle0 + k_sub * m, *accel = rate0 + k_sub * m;
    double *w_t = accel + k_sub * m, *f_t = w_t + 3 * k_sub, *amb_end = f_t + 3 * k_sub;
    for (int64_t k = 0; k < k_sub; k++) {
        double tau = (double)k * h_sub;
        for (int j = 0; j < m; j++) {
            double a0 = motion[0][j], r0 = motion[1][j], acc = motion[2][j];
            angle0[k * m + j] = a0 + (r0 + 0.5 * acc * tau) * tau;
            rate0[k * m + j] = r0 + acc * tau;
            accel[k * m + j] = acc;
        }
        memcpy(w_t + 3 * k, base, 3 * sizeof *w_t);
        memcpy(f_t + 3 * k, base + 3, 3 * sizeof *f_t);
        amb_end[k] = amb0 + amb_rate * ((double)(k + 1) * h_sub);
    }
}

/* The step's outputs into buf: the increments the sums of the k_sub sub-intervals', in order (no coning or
 * sculling across them), the temperatures the last one's, the end time t + h. */
static void write_outputs(double *buf, const double *io, double t, double h, int64_t k_sub, const double *dtheta,
                          const double *dv, const double *temps) {
    for (int i = 0; i < 3; i++) {
        double sum_theta = k_sub == 1 ? dtheta[i] : 0.0, sum_v = k_sub == 1 ? dv[i] : 0.0;
        for (int64_t k = 0; k_sub > 1 && k < k_sub; k++) {
            sum_theta += dtheta[3 * k + i];
            sum_v += dv[3 * k + i];
        }
        buf[(int64_t)io[IO_OUT + i]] = sum_theta;
        buf[(int64_t)io[IO_OUT + 3 + i]] = sum_v;
    }
    for (int i = 0; i < 6; i++) buf[(int64_t)io[IO_OUT + 6 + i]] = temps[6 * (k_sub - 1) + i];
    buf[(int64_t)io[IO_END_TIME]] = t + h;
}

/* Sub-interval k's start-of-interval motion given by the set (k_sub rows of count = 3 na + 2 values: angles,
 * rates, accelerations, ambient, its slope); the base row held; the ambient at each end as a step of h_sub
 * would take it (ambient + slope h_sub).  Scratch laid out as sub_motion's; 0 when an ambient end is out of
 * range. */
static int given_motion(int64_t k_sub, int na, double h_sub, const double *set, const double *base,
                        double *scratch) {
    int count = 3 * na + 2;
    double *angle0 = scratch, *rate0 = angle0 + k_sub * na, *accel = rate0 + k_sub * na;
    double *w_t = accel + k_sub * na, *f_t = w_t + 3 * k_sub, *amb_end = f_t + 3 * k_sub;
    for (int64_t k = 0; k < k_sub; k++) {
        const double *row = set + k * count;
        memcpy(angle0 + k * na, row, (size_t)na * sizeof *angle0);
        memcpy(rate0 + k * na, row + na, (size_t)na * sizeof *rate0);
        memcpy(accel + k * na, row + 2 * na, (size_t)na * sizeof *accel);
        memcpy(w_t + 3 * k, base, 3 * sizeof *w_t);
        memcpy(f_t + 3 * k, base + 3, 3 * sizeof *f_t);
        amb_end[k] = row[3 * na] + row[3 * na + 1] * h_sub;
        if (!(amb_end[k] >= -273.15 && amb_end[k] <= SARINS_IMU_AMBIENT_MAX)) return 0; /* imu_build.h */
    }
    return 1;
}

/* The set tagged t (the given one or the held one) for the given-motion step; NULL when neither is. */
static const double *given_set(const double *held, const double *given, int64_t size, int fixed, double tag,
                               double t, double h) {
    for (int64_t i = 0; i < size; i++) {
        if (!isfinite(given[i])) return NULL;
    }
    if (fixed || same_time(tag, t, h)) return given;
    if (held[0] != 0.0 && same_time(held[1], t, h)) return held + 2;
    return NULL;
}

/* The FMU step of sarins_imu_fmu_step (k_sub = 1, the arguments after it unused), of sarins_imu_fmu_step_sub
 * (k_sub > 1, given NULL) or of sarins_imu_fmu_step_given (k_sub >= 1, given the motion of every
 * sub-interval); pool NULL or the workers of the minor loops. */
static int fmu_step(int64_t *table, int64_t rows, double *buf, int64_t n, double t, double h, int64_t k_sub,
                    const double *given, double *sub_dtheta, double *sub_dv, double *sub_temps, double *scratch,
                    sarins_workers *pool) {
    ImuView v;
    if (buf == NULL || rows < SARINS_IMU_N_ARRAYS + 3 || imu_view(table, rows, &v) != SARINS_IMU_OK) return 1;
    if (!has_shape(table, SARINS_IMU_N_ARRAYS, IO_SIZE, 1)) return 1;
    const double *io = table_array(table, SARINS_IMU_N_ARRAYS);
    double *held = table_array(table, SARINS_IMU_N_ARRAYS + 1);
    double *v_held = table_array(table, SARINS_IMU_N_ARRAYS + 2);
    const double *consts = v.consts, *clock = v.clock;
    if (!(sm_fabs(h - io[IO_STEP]) <= 1e-9 * io[IO_STEP])) return 1;
    if (!same_time(consts[0] + clock[0] * consts[1] + io[IO_START], t, h)) return 1;
    if (k_sub < 1 || (k_sub > 1 && !(sm_fabs(consts[1] * (double)k_sub - h) <= 1e-9 * h))) return 1;
    if (!(io[IO_GIMBALS] >= 1.0 && io[IO_GIMBALS] <= 3.0)) return 1;
    int na = (int)io[IO_GIMBALS];
    int count = 3 * na + 2;
    int64_t set_size = given != NULL ? k_sub * count : count;
    int moving = io[IO_VEHICLE] != 0.0;
    int m = moving ? na + 3 : na; /* the vehicle's attitude gimbals carry the table's */
    if (!has_shape(table, SARINS_IMU_N_ARRAYS + 1, set_size + 2, 1) || v.n_axes != m
        || (moving && (given != NULL || !has_shape(table, SARINS_IMU_N_ARRAYS + 2, VEHICLE_SET + 2, 1))))
        return 1;
    for (int i = IO_OUT; i <= IO_END_TIME; i++) {
        if (slot_index(io[i], n) < 0) return 1;
    }
    int64_t tag_at = slot_index(io[IO_MOTION_TIME], n);
    if (tag_at < 0) return 1;
    double tag = buf[tag_at];
    if (!isfinite(tag)) return 1;
    int fixed = tag == NO_TAG && held[0] != 0.0 && held[1] == NO_TAG; /* no turntable connected */
    if (given != NULL) {
        const double *set = given_set(held, given, set_size, fixed, tag, t, h);
        if (set == NULL || !given_motion(k_sub, na, consts[1], set, v.base, scratch)) return 1;
        /* every check passed: from here on the step happens */
        if (!fixed) keep(held, given, (int)set_size, tag);
        double *angle0 = scratch, *amb = scratch + 3 * k_sub * na + 6 * k_sub;
        if (steps_view(&v, k_sub, angle0, angle0 + k_sub * na, angle0 + 2 * k_sub * na, angle0 + 3 * k_sub * na,
                       angle0 + 3 * k_sub * na + 3 * k_sub, amb, sub_dtheta, sub_dv, sub_temps, amb + k_sub, pool)
            != SARINS_IMU_OK)
            return 1; /* not reached: the table and its stream states were checked above */
        write_outputs(buf, io, t, h, k_sub, sub_dtheta, sub_dv, sub_temps);
        return 0;
    }
    double slots[11], current[11], chosen[11];
    for (int k = 0; k < 3; k++) memcpy(slots + k * na, io + IO_MOTION + 3 * k, (size_t)na * sizeof *slots);
    slots[3 * na] = io[IO_AMBIENT];
    slots[3 * na + 1] = io[IO_AMBIENT + 1];
    if (!read_slots(buf, n, slots, count, current)) return 1;
    if (fixed) {
        memcpy(chosen, current, (size_t)count * sizeof *chosen);
    } else if (!choose(held, current, count, tag, t, h, chosen)) {
        return 1;
    }
    double vehicle[VEHICLE_SET], v_chosen[VEHICLE_SET], v_tag = 0.0;
    if (moving) {
        int64_t v_tag_at = slot_index(io[IO_VEHICLE + 1], n);
        if (v_tag_at < 0) return 1;
        v_tag = buf[v_tag_at];
        if (!(read_slots(buf, n, io + IO_VEHICLE + 2, VEHICLE_SET, vehicle) && isfinite(v_tag))) return 1;
        if (!choose(v_held, vehicle, VEHICLE_SET, v_tag, t, h, v_chosen)) return 1;
    }
    /* ambient linear over the step: its value at the end */
    double amb_end = chosen[3 * na] + chosen[3 * na + 1] * h;
    if (!(amb_end >= -273.15 && amb_end <= SARINS_IMU_AMBIENT_MAX)) return 1; /* imu_build.h */
    /* every check passed: from here on the step happens */
    if (!fixed) keep(held, current, count, tag);
    double motion[3][SARINS_IMU_MAX_AXES];
    for (int k = 0; k < 3; k++) {
        if (moving) memcpy(motion[k], v_chosen + 3 * k, 3 * sizeof **motion);
        memcpy(motion[k] + (m - na), chosen + k * na, (size_t)na * sizeof **motion);
    }
    if (moving) {
        keep(v_held, vehicle, VEHICLE_SET, v_tag);
        memcpy(v.base, v_chosen + 9, 3 * sizeof *v.base);
        memcpy(v.base + 3, v_chosen + 12, 3 * sizeof *v.base);
    }
    if (k_sub == 1) {
        double dtheta[3], dv[3], temps[6];
        if (one_interval_view(&v, motion[0], motion[1], motion[2], amb_end, dtheta, dv, temps) != SARINS_IMU_OK)
            return 1; /* not reached: the table and its stream states were checked above */
        write_outputs(buf, io, t, h, 1, dtheta, dv, temps);
        return 0;
    }
    sub_motion(k_sub, m, consts[1], motion, v.base, chosen[3 * na], chosen[3 * na + 1], scratch);
    double *angle0 = scratch, *amb = scratch + 3 * k_sub * m + 6 * k_sub;
    if (steps_view(&v, k_sub, angle0, angle0 + k_sub * m, angle0 + 2 * k_sub * m, angle0 + 3 * k_sub * m,
                   angle0 + 3 * k_sub * m + 3 * k_sub, amb, sub_dtheta, sub_dv, sub_temps, amb + k_sub, pool)
        != SARINS_IMU_OK)
        return 1; /* not reached, as above */
    write_outputs(buf, io, t, h, k_sub, sub_dtheta, sub_dv, sub_temps);
    return 0;
}

int sarins_imu_fmu_step(int64_t *table, int64_t rows, double *buf, int64_t n, double t, double h) {
    return fmu_step(table, rows, buf, n, t, h, 1, NULL, NULL, NULL, NULL, NULL, NULL);
}

int sarins_imu_fmu_step_sub(int64_t *table, int64_t rows, double *buf, int64_t n, double t, double h,
                            int64_t k_sub, double *dtheta, double *dv, double *temps, double *scratch) {
    if (k_sub < 2 || dtheta == NULL || dv == NULL || temps == NULL || scratch == NULL) return 1;
    return fmu_step(table, rows, buf, n, t, h, k_sub, NULL, dtheta, dv, temps, scratch, NULL);
}

int sarins_imu_fmu_step_given(int64_t *table, int64_t rows, double *buf, int64_t n, double t, double h,
                              int64_t k_sub, const double *motion, double *dtheta, double *dv, double *temps,
                              double *scratch, sarins_workers *pool) {
    if (k_sub < 1 || motion == NULL || dtheta == NULL || dv == NULL || temps == NULL || scratch == NULL) return 1;
    return fmu_step(table, rows, buf, n, t, h, k_sub, motion, dtheta, dv, temps, scratch, pool);
}
