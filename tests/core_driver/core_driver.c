/* Deterministic workload through the C core's public functions, for the
 * cross-platform comparison of tests/test_core_win64.py (linux64 gcc + glibc
 * against win64 mingw-w64 under wine).
 *
 * Every input is made inside the driver from a fixed 64-bit LCG or from
 * closed-form polynomials (IEEE basic operations only, no libc RNG, no libm),
 * so the two builds start from bit-identical inputs.  Each output is printed
 * as "<group> <16 hex digits of its IEEE-754 bit pattern>", one per line; the
 * hex is formatted here (no printf of floating point, whose rounding differs
 * between C runtimes).
 *
 * Groups whose kernels use only + - * / and sqrt get libm-free inputs, so
 * any difference there is a compiler or ABI fault, not libm.  The chain
 * groups (thermal, imu_increments, ins_*, stop_filter) use sin, cos, tan,
 * exp, asin, atan2 and are compared with a bound.
 *
 * Units as in the core's headers: rad, rad/s, m/s, m/s^2, s, degC.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sarins_core.h"

#define K 400        /* output intervals of the IMU workload */
#define H 0.005      /* interval, s (200 Hz) */
#define N_SUB 8      /* minor steps per interval */
#define N_AXES 2     /* gimbals: outer about z, inner about x */
#define N_SEG 5      /* turntable schedule segments */
#define N_FLICKER 3  /* flicker Gauss-Markov terms */
#define CORR_STRIDE (6 * N_FLICKER + 6)
#define K_ALIGN 200  /* intervals of fine alignment; the rest navigate */
#define K_NAV (K - K_ALIGN)

typedef struct {
    uint64_t s;
} Lcg;

/* Knuth's MMIX LCG; 53 high bits as a uniform number in [0, 1). */
static double uniform(Lcg *g)
{
    g->s = g->s * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(g->s >> 11) * (1.0 / 9007199254740992.0);
}

/* Approximately standard normal: sum of 12 uniforms less 6 (no libm). */
static double normal(Lcg *g)
{
    double sum = 0.0;
    for (int i = 0; i < 12; i++)
        sum += uniform(g);
    return sum - 6.0;
}

/* uniform in [lo, hi) */
static double between(Lcg *g, double lo, double hi)
{
    return lo + (hi - lo) * uniform(g);
}

static void emit(const char *group, const double *x, int64_t n)
{
    static const char digits[] = "0123456789abcdef";
    for (int64_t i = 0; i < n; i++) {
        uint64_t bits;
        char hex[17];
        memcpy(&bits, &x[i], sizeof bits);
        for (int d = 15; d >= 0; d--) {
            hex[d] = digits[bits & 0xFu];
            bits >>= 4;
        }
        hex[16] = '\0';
        printf("%s %s\n", group, hex);
    }
}

/* Every array of the workload, allocated once (no globals, nothing on a small stack). */
typedef struct {
    /* turntable */
    double times[N_SEG + 1], angle_bp[(N_SEG + 1) * N_AXES], rate_bp[(N_SEG + 1) * N_AXES];
    double seg_acc[N_SEG * N_AXES], tt_t[K];
    double angle0[K * N_AXES], rate0[K * N_AXES], accel[K * N_AXES];
    /* moving base */
    double w_t[K * 3], f_t[K * 3];
    /* thermal chain */
    double amb_end[K], temps[K * 6], die[K * 6];
    /* interval terms and correlated terms (libm-free temperatures) */
    double temps_iso[K * 6], die_iso[K * 6];
    double g_bias[K * 3], g_sf[K * 3], a_bias[K * 3], a_sf[K * 3];
    /* increments */
    double dtheta[K * 3], dv[K * 3];
    /* INS */
    double coarse_hist[K * 3], align_hist[K_ALIGN * 9], nav_out[K_NAV * 9], axial[K_NAV];
    double vel_en[K_NAV * 2], att[K_NAV * 3], stop_out[K_NAV * 2];
    double p_align[9 * 9], p_stop[11 * 11];
} Work;

/* Schedule of N_SEG segments with piecewise-constant accelerations; breakpoint states integrated here. */
static void turntable(Work *w)
{
    static const double times[N_SEG + 1] = {0.0, 0.25, 0.6, 1.05, 1.5, 2.1};
    static const double acc[N_SEG * N_AXES] = {3.0, -1.5, 0.0, 2.0, -4.0, 0.5, 1.0, -2.5, 0.0, 1.25};
    double angle0[N_AXES] = {0.3, -0.2}, rate0[N_AXES] = {0.5, 0.25};
    memcpy(w->times, times, sizeof times);
    memcpy(w->seg_acc, acc, sizeof acc);
    for (int j = 0; j < N_AXES; j++) {
        w->angle_bp[j] = angle0[j];
        w->rate_bp[j] = rate0[j];
    }
    for (int s = 0; s < N_SEG; s++) {
        double d = times[s + 1] - times[s];
        for (int j = 0; j < N_AXES; j++) {
            double a = acc[N_AXES * s + j], r = w->rate_bp[N_AXES * s + j];
            w->rate_bp[N_AXES * (s + 1) + j] = r + a * d;
            w->angle_bp[N_AXES * (s + 1) + j] = w->angle_bp[N_AXES * s + j] + r * d + 0.5 * a * d * d;
        }
    }
    /* interval starts, plus one time before the schedule */
    for (int k = 0; k < K; k++)
        w->tt_t[k] = (double)k * H;
    w->tt_t[0] = -0.05;
    sarins_turntable_state(K, w->tt_t, N_SEG + 1, N_AXES, w->times, w->angle_bp, w->rate_bp, w->seg_acc, angle0,
                           rate0, w->angle0, w->rate0, w->accel);
    w->tt_t[0] = 0.0;
    sarins_turntable_state(1, w->tt_t, N_SEG + 1, N_AXES, w->times, w->angle_bp, w->rate_bp, w->seg_acc, angle0,
                           rate0, w->angle0, w->rate0, w->accel);
    emit("turntable", w->angle0, K * N_AXES);
    emit("turntable", w->rate0, K * N_AXES);
    emit("turntable", w->accel, K * N_AXES);
}

/* Moving base: Earth rate at latitude ~0.6 rad plus a slow vehicle turn, specific force with a manoeuvre (polynomials). */
static void moving_base(Work *w, Lcg *g)
{
    for (int k = 0; k < K; k++) {
        double t = (double)k * H;
        w->w_t[3 * k] = 2e-3 * t - 1e-3 * t * t + 1e-6 * normal(g);
        w->w_t[3 * k + 1] = 5.9e-5 + 3e-3 * t * (1.0 - 0.3 * t);
        w->w_t[3 * k + 2] = 4.1e-5 + 0.02 * t * t * (2.0 - t);
        w->f_t[3 * k] = 0.4 * t * (2.0 - t) + 1e-3 * normal(g);
        w->f_t[3 * k + 1] = -0.3 + 0.25 * t;
        w->f_t[3 * k + 2] = 9.80 + 0.05 * t * t + 1e-3 * normal(g);
    }
}

static void earth_and_rotations(Lcg *g)
{
    double c[SARINS_EARTH_N_CONSTANTS];
    sarins_earth_constants(c);
    emit("earth", c, SARINS_EARTH_N_CONSTANTS);
    double lat[7] = {-1.5, -0.9, -0.2, 0.0, 0.35, 0.61, 1.45}, h[7] = {0, 10, -30, 200, 1500, 8000, 50};
    double rm[7], rn[7], grav[7];
    sarins_earth_radii_n(7, lat, rm, rn);
    sarins_earth_gravity_n(7, lat, h, grav);
    emit("earth", rm, 7);
    emit("earth", rn, 7);
    emit("earth", grav, 7);

    enum { NR = 16 };
    double phi[NR * 3], q[NR * 4], q2[NR * 4], qq[NR * 4], mat[NR * 9], mq[NR * 9], ypr[NR * 3], me[NR * 9];
    for (int i = 0; i < NR * 3; i++) {
        /* angles from 1e-10 (the series branch) to ~3 rad */
        double scale = i < 6 ? 1e-10 : (i < 12 ? 1e-4 : 1.0);
        phi[i] = scale * between(g, -1.7, 1.7);
        ypr[i] = between(g, -3.0, 3.0);
    }
    for (int i = 0; i < NR; i++)
        ypr[3 * i + 1] *= 0.5;
    sarins_rotvec_to_mat_n(NR, phi, mat);
    sarins_rotvec_to_quat_n(NR, phi, q);
    for (int i = 0; i < NR * 4; i++)
        q2[i] = q[(i + 4) % (NR * 4)];
    sarins_quat_mult_n(NR, q, q2, qq);
    sarins_quat_to_mat_n(NR, qq, mq);
    sarins_euler_to_mat_n(NR, ypr, me);
    emit("rotations", mat, NR * 9);
    emit("rotations", q, NR * 4);
    emit("rotations", qq, NR * 4);
    emit("rotations", mq, NR * 9);
    emit("rotations", me, NR * 9);
}

/* Ambient ramp, exact thermal steps, die temperatures (exp). */
static void thermal(Work *w)
{
    double heat[6] = {4.0, 4.5, 5.0, 2.0, 2.5, 3.0}, tau[6] = {60.0, 75.0, 90.0, 40.0, 45.0, 50.0};
    double tau_die[6] = {5.0, 0.0, 7.5, 2.0, 3.0, 1.5};
    double temp[6] = {20.0, 20.5, 21.0, 19.5, 19.0, 18.5}, temp0[6], die[6];
    memcpy(temp0, temp, sizeof temp);
    memcpy(die, temp, sizeof temp);
    for (int k = 0; k < K; k++) {
        double t = (double)(k + 1) * H;
        w->amb_end[k] = 20.0 + 30.0 * t - 4.0 * t * t;
    }
    double step = sarins_thermal_exact_step(20.0, 20.0, 26.0, 1.7, 3.0, 45.0);
    emit("thermal", &step, 1);
    sarins_thermal_steps(0.0, H, 0.0, 20.0, K, w->amb_end, 6, heat, tau, temp, w->temps);
    sarins_die_temperatures(K, 6, temp0, w->temps, H, tau_die, die, w->die);
    emit("thermal", w->temps, K * 6);
    emit("thermal", temp, 6);
    emit("thermal", w->die, K * 6);
    emit("thermal", die, 6);
}

/* Bias, scale factor, Gauss-Markov, drift model, correlated terms: libm-free inputs (sqrt is exact). */
static void error_terms(Work *w, Lcg *g)
{
    double temp0[6], die0[6];
    for (int j = 0; j < 6; j++) {
        temp0[j] = 20.0 + 0.5 * (double)j;
        die0[j] = temp0[j] - 0.1;
    }
    for (int k = 0; k < K; k++) {
        double t = (double)(k + 1) * H;
        for (int j = 0; j < 6; j++) {
            w->temps_iso[6 * k + j] = temp0[j] + (3.0 + 0.2 * (double)j) * t - 0.7 * t * t + 1e-3 * normal(g);
            w->die_iso[6 * k + j] = w->temps_iso[6 * k + j] - 0.1 + 0.05 * t;
        }
    }
    /* coef (10, 3): gyro bias (rad/s), tc1, tc2, sf, sf tc; then the same for the accelerometers (m/s^2) */
    double coef[30];
    for (int r = 0; r < 10; r++)
        for (int i = 0; i < 3; i++) {
            static const double mag[5] = {5e-6, 2e-8, 1e-9, 3e-5, 1e-7};
            double m = mag[r % 5] * (r < 5 ? 1.0 : 200.0);
            coef[3 * r + i] = m * between(g, -1.0, 1.0);
        }
    double drift_poly[3] = {1e-11, -2e-10, 3e-9}, drift_dtdt = 4e-7;
    double gm[6] = {1e-7, -2e-7, 3e-7, 1e-4, -2e-4, 3e-4};
    double gm_phi[6] = {0.999, 0.998, 0.9995, 0.99, 0.995, 0.997};
    double gm_std[6] = {1e-7, 2e-7, 1.5e-7, 5e-5, 6e-5, 7e-5};
    /* the Gauss-Markov and correlated-term normals come from the core's seeded streams (polar method: log) */
    SarinsRng gm_rng, flicker_rng, rrw_rng;
    sarins_rng_stream(&gm_rng, 20261202u, 1u);
    sarins_rng_stream(&flicker_rng, 20261202u, 2u);
    sarins_rng_stream(&rrw_rng, 20261202u, 3u);
    sarins_imu_interval_terms(K, temp0, w->temps_iso, H, coef, drift_poly, drift_dtdt, gm, gm_phi, gm_std,
                              &gm_rng, w->g_bias, w->g_sf, w->a_bias, w->a_sf);
    emit("interval_terms", w->g_bias, K * 3);
    emit("interval_terms", w->g_sf, K * 3);
    emit("interval_terms", w->a_bias, K * 3);
    emit("interval_terms", w->a_sf, K * 3);
    emit("interval_terms", gm, 6);

    /* corr_par (7, 6): die tau, c_grad, s_grad, c_hyst, w_hyst, rrw, turn-on */
    double corr_par[42], corr_state[18], phi[N_FLICKER] = {0.9, 0.99, 0.999};
    double q[N_FLICKER * 6], x_flicker[N_FLICKER * 6];
    static const double par_mag[7] = {3.0, 1e-7, 1e-6, 2e-7, 0.3, 1e-8, 1e-6};
    for (int r = 0; r < 7; r++)
        for (int j = 0; j < 6; j++) {
            double m = par_mag[r] * ((r > 0 && r != 4 && j >= 3) ? 100.0 : 1.0);
            corr_par[6 * r + j] = (r == 0 || r == 4) ? m * between(g, 0.5, 1.5) : m * between(g, -1.0, 1.0);
        }
    for (int j = 0; j < 6; j++) {
        corr_state[j] = die0[j];
        corr_state[6 + j] = die0[j] + 0.05;
        corr_state[12 + j] = 1e-8 * normal(g);
    }
    for (int i = 0; i < N_FLICKER * 6; i++) {
        q[i] = (i % 6 < 3 ? 1e-7 : 1e-5) * between(g, 0.5, 1.5);
        x_flicker[i] = q[i] * normal(g);
    }
    sarins_correlated_terms(K, die0, w->die_iso, H, corr_par, corr_state, N_FLICKER, phi, q, x_flicker,
                            &flicker_rng, &rrw_rng, w->g_bias, w->g_sf, w->a_bias, w->a_sf);
    emit("correlated", w->g_bias, K * 3);
    emit("correlated", w->g_sf, K * 3);
    emit("correlated", w->a_bias, K * 3);
    emit("correlated", w->a_sf, K * 3);
    emit("correlated", corr_state, 18);
    emit("correlated", x_flicker, N_FLICKER * 6);

    /* Kalman steps on libm-free matrices: propagate + Joseph update, 11 states */
    double x[11], p[121], phi_m[121], q_diag[11], c[121];
    for (int i = 0; i < 11; i++) {
        x[i] = 1e-3 * normal(g);
        q_diag[i] = 1e-9 * between(g, 0.5, 2.0);
        for (int j = 0; j < 11; j++) {
            phi_m[11 * i + j] = (i == j ? 1.0 : 0.0) + 1e-3 * between(g, -1.0, 1.0);
            p[11 * i + j] = (i == j ? 1e-2 : 0.0);
        }
    }
    for (int s = 0; s < 50; s++) {
        sarins_filter_propagate(11, x, p, phi_m, q_diag, H);
        sarins_filter_velocity_update(11, x, p, 1e-4, 1e-2 * normal(g), 1e-2 * normal(g));
    }
    sarins_matmul(11, phi_m, p, c);
    emit("filter", x, 11);
    emit("filter", p, 121);
    emit("filter", c, 121);
}

/* Minor loop of the turning 2-axis table on the moving base, every error term non-zero. */
static void increments(Work *w)
{
    double axes[N_AXES * 3] = {0.0, 0.0, 1.0, 1.0, 0.0, 0.0};
    double g_mis[9] = {0.0, 2e-5, -1e-5, 3e-5, 0.0, 1.5e-5, -2.5e-5, 1e-5, 0.0};
    double a_mis[9] = {0.0, -4e-5, 2e-5, 1e-5, 0.0, -3e-5, 2.5e-5, 3.5e-5, 0.0};
    double g_quad[3] = {1e-6, -2e-6, 1.5e-6}, a_quad[3] = {2e-5, 1e-5, -3e-5};
    double g_lowrate[3] = {1e-3, 2e-3, -1.5e-3}, g_width[3] = {1e-4, 2e-4, 1.5e-4};
    double g_sens[9] = {1e-7, 2e-8, -3e-8, 1.5e-8, -1e-7, 2.5e-8, -2e-8, 3e-8, 1.2e-7};
    sarins_imu_increments(0, K, N_AXES, axes, w->angle0, w->rate0, w->accel, w->w_t, w->f_t, H, N_SUB, w->g_sf,
                          g_mis, w->g_bias, g_quad, g_lowrate, g_width, g_sens, w->a_sf, a_mis, w->a_bias, a_quad,
                          w->dtheta, w->dv);
    emit("imu_increments", w->dtheta, K * 3);
    emit("imu_increments", w->dv, K * 3);
    double truth[6], tau = 0.0031;
    sarins_imu_truth(N_AXES, axes, w->angle0 + 2 * 17, w->rate0 + 2 * 17, w->accel + 2 * 17, tau, w->w_t + 51,
                     w->f_t + 51, truth);
    emit("imu_increments", truth, 6);
}

/* Coarse accumulators, fine alignment, free navigation and the stop filter over the increments. */
static void ins(Work *w)
{
    double q_b0b[4] = {1.0, 0.0, 0.0, 0.0}, v_b0[3] = {0.0, 0.0, 0.0};
    sarins_ins_coarse_steps(K, q_b0b, v_b0, w->dtheta, w->dv, w->coarse_hist);
    emit("ins_coarse", w->coarse_hist, K * 3);
    emit("ins_coarse", q_b0b, 4);

    double phi0[3] = {0.01, -0.02, 0.3}, q[4], v[3] = {0.0, 0.0, 0.0}, pos[3] = {0.6, 2.0, 50.0};
    sarins_rotvec_to_quat(phi0, q);
    double gyro_comp[3] = {0.0, 0.0, 0.0}, accel_comp[3] = {0.0, 0.0, 0.0}, x[9] = {0.0};
    double q_diag[9] = {1e-12, 1e-12, 1e-12, 1e-6, 1e-6, 1e-16, 1e-16, 1e-10, 1e-10};
    static const double p0[9] = {1e-4, 1e-4, 1e-2, 1e-2, 1e-2, 1e-12, 1e-12, 1e-6, 1e-6};
    memset(w->p_align, 0, sizeof w->p_align);
    for (int i = 0; i < 9; i++)
        w->p_align[9 * i + i] = p0[i];
    sarins_ins_align_steps(K_ALIGN, q, v, pos, w->dtheta, w->dv, H, gyro_comp, accel_comp, x, w->p_align, q_diag,
                           1e-4, w->align_hist);
    double row[9];
    sarins_ins_held_row(q, pos, row);
    emit("ins_align", w->align_hist, K_ALIGN * 9);
    emit("ins_align", w->p_align, 81);
    emit("ins_align", q, 4);
    emit("ins_align", v, 3);
    emit("ins_align", gyro_comp, 3);
    emit("ins_align", accel_comp, 3);
    emit("ins_align", row, 9);

    for (int s = 0; s < K_NAV; s++)
        w->axial[s] = 1e-7 * (double)s / (double)K_NAV;
    sarins_ins_nav_steps(K_NAV, q, v, pos, w->dtheta + 3 * K_ALIGN, w->dv + 3 * K_ALIGN, H, gyro_comp, accel_comp,
                         w->axial, w->nav_out);
    emit("ins_nav", w->nav_out, K_NAV * 9);
    emit("ins_nav", q, 4);

    for (int s = 0; s < K_NAV; s++) {
        w->vel_en[2 * s] = w->nav_out[9 * s + 3];
        w->vel_en[2 * s + 1] = w->nav_out[9 * s + 4];
        for (int j = 0; j < 3; j++)
            w->att[3 * s + j] = w->nav_out[9 * s + 6 + j];
    }
    double xs[11] = {0.0}, qs[11];
    memset(w->p_stop, 0, sizeof w->p_stop);
    for (int i = 0; i < 11; i++) {
        qs[i] = i < 3 ? 1e-12 : (i < 5 ? 1e-6 : (i < 8 ? 1e-16 : (i < 10 ? 1e-10 : 1e-14)));
        w->p_stop[11 * i + i] = i < 3 ? 1e-4 : (i < 5 ? 1e-2 : (i < 8 ? 1e-12 : (i < 10 ? 1e-6 : 1e-10)));
    }
    sarins_stop_filter_steps(K_NAV, xs, w->p_stop, w->vel_en, w->att, 0.6, H, qs, 1e-4, w->stop_out);
    emit("stop_filter", w->stop_out, K_NAV * 2);
    emit("stop_filter", xs, 11);
    emit("stop_filter", w->p_stop, 121);
}

int main(void)
{
    if (sarins_core_abi() != SARINS_CORE_ABI) {
        fprintf(stderr, "core_driver: core ABI %d, driver built for %d\n", sarins_core_abi(), SARINS_CORE_ABI);
        return 1;
    }
    Work *w = calloc(1, sizeof *w);
    if (w == NULL) {
        fprintf(stderr, "core_driver: out of memory\n");
        return 1;
    }
    Lcg g = {0x5A121A5ULL};
    turntable(w);
    moving_base(w, &g);
    earth_and_rotations(&g);
    thermal(w);
    error_terms(w, &g);
    increments(w);
    ins(w);
    free(w);
    if (fflush(stdout) != 0) {
        fprintf(stderr, "core_driver: cannot write the output\n");
        return 1;
    }
    return 0;
}
