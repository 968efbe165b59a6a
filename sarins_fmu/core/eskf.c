#include "smath.h"
#include "report.h"
#include "eskf.h"

#include "earth.h"
#include "ins.h"
#include "matrix.h"
#include "nav3.h"
#include "rotations.h"

#define NMAX SARINS_ESKF_NMAX
#define IDX(i, j) ((i) * n + (j)) /* P and F: n x n, stride n (n in scope) */

int64_t sarins_eskf_size(void) { return (int64_t)sizeof(sarins_eskf); }

int64_t sarins_eskf_dim(const sarins_eskf *s) { return s->n; }

int64_t sarins_eskf_row_size(const sarins_eskf *s, int full_cov) { return full_cov ? s->n + s->n * s->n : 2 * s->n; }

/* The layout of a STATES bit set: n and the blocks' first indices (-1 when absent). */
static int64_t layout(int mask, int64_t *i_sg, int64_t *i_sa, int64_t *i_lever, int64_t *i_gm_r, int64_t *i_gm_v)
{
    int64_t n = SARINS_ESKF_N;
    *i_sg = *i_sa = *i_lever = *i_gm_r = *i_gm_v = -1;
    if (mask & SARINS_ESKF_SF) {
        *i_sg = n;
        *i_sa = n + 3;
        n += 6;
    }
    if (mask & SARINS_ESKF_LEVER) {
        *i_lever = n;
        n += 3;
    }
    if (mask & SARINS_ESKF_GNSS_POS_GM) {
        *i_gm_r = n;
        n += 3;
    }
    if (mask & SARINS_ESKF_GNSS_VEL_GM) {
        *i_gm_v = n;
        n += 3;
    }
    return n;
}

/* 1 when opt holds (finite, STATES a bit set 0 .. 15, stds >= 0, a used tau > 0), else 0 with msg. */
static int options_ok(const double *opt, char *msg, size_t size)
{
    for (int i = 0; i < SARINS_ESKF_OPT; i++)
        if (!isfinite(opt[i])) {
            sarins_say(msg, size, "a filter state option is not finite");
            return 0;
        }
    double m = opt[SARINS_ESKF_STATES];
    if (!(m >= 0.0 && m <= 15.0 && sm_floor(m) == m)) {
        sarins_say(msg, size, "the optional states must be a bit set 0 .. 15 (1 scale factors, 2 lever arm, "
                              "4 GNSS position Gauss-Markov, 8 GNSS velocity Gauss-Markov)");
        return 0;
    }
    for (int i = SARINS_ESKF_GYRO_SF0_STD; i < SARINS_ESKF_OPT; i++)
        if (opt[i] < 0.0) {
            sarins_say(msg, size, "an optional state's std or correlation time is negative");
            return 0;
        }
    int mask = (int)m;
    if (((mask & SARINS_ESKF_GNSS_POS_GM) && !(opt[SARINS_ESKF_GNSS_POS_GM_TAU] > 0.0)) ||
        ((mask & SARINS_ESKF_GNSS_VEL_GM) && !(opt[SARINS_ESKF_GNSS_VEL_GM_TAU] > 0.0))) {
        sarins_say(msg, size, "a GNSS Gauss-Markov correlation time must be positive");
        return 0;
    }
    return 1;
}

int sarins_eskf_init(sarins_eskf *s, const double *config, const double *nav0, char *msg, size_t size)
{
    return sarins_eskf_init_states(s, config, NULL, nav0, msg, size);
}

int sarins_eskf_init_states(sarins_eskf *s, const double *config, const double *opt, const double *nav0, char *msg,
                            size_t size)
{
    if (opt != NULL && !options_ok(opt, msg, size))
        return 1;
    for (int i = 0; i < SARINS_ESKF_CONFIG; i++)
        if (!isfinite(config[i])) {
            sarins_say(msg, size, "a filter setting is not finite");
            return 1;
        }
    for (int i = 0; i < 9; i++)
        if (!isfinite(nav0[i])) {
            sarins_say(msg, size, "the start state is not finite");
            return 1;
        }
    if (!(config[SARINS_ESKF_STEP] > 0.0)) {
        sarins_say(msg, size, "the IMU step must be positive");
        return 1;
    }
    for (int i = SARINS_ESKF_ARW; i <= SARINS_ESKF_ACCEL_BIAS0_STD; i++)
        if (config[i] < 0.0) {
            sarins_say(msg, size, "a filter standard deviation is negative");
            return 1;
        }
    if (!(config[SARINS_ESKF_ZUPT_STD] > 0.0) || !(config[SARINS_ESKF_NHC_STD] > 0.0) ||
        !(config[SARINS_ESKF_ODO_STD] > 0.0) || !(config[SARINS_ESKF_ZARU_STD] > 0.0) ||
        config[SARINS_ESKF_LATENCY] < 0.0) {
        sarins_say(msg, size, "the ZUPT, ZARU, NHC and odometer stds must be positive and the latency not negative");
        return 1;
    }
    if (!(config[SARINS_ESKF_COV_EVERY] >= 1.0 && config[SARINS_ESKF_COV_EVERY] <= 1000.0 &&
          sm_floor(config[SARINS_ESKF_COV_EVERY]) == config[SARINS_ESKF_COV_EVERY])) {
        sarins_say(msg, size, "cov_every must be a whole number 1 .. 1000");
        return 1;
    }
    if (sm_fabs(nav0[0]) > 89.9 * (3.141592653589793 / 180.0)) {
        sarins_say(msg, size, "the start latitude is outside +-89.9 deg");
        return 1;
    }
    for (size_t i = 0; i < sizeof *s; i++)
        ((unsigned char *)s)[i] = 0;
    for (int i = 0; i < SARINS_ESKF_CONFIG; i++)
        s->config[i] = config[i];
    if (opt != NULL)
        for (int i = 0; i < SARINS_ESKF_OPT; i++)
            s->opt[i] = opt[i];
    const int64_t n = layout((int)s->opt[SARINS_ESKF_STATES], &s->i_sg, &s->i_sa, &s->i_lever, &s->i_gm_r, &s->i_gm_v);
    s->n = n;
    for (int i = 0; i < 3; i++)
        s->lever[i] = config[SARINS_ESKF_LEVER_X + i];
    double mat[9];
    sarins_euler_to_mat(nav0[6], nav0[7], nav0[8], mat);
    sarins_mat_to_quat(mat, s->q);
    for (int i = 0; i < 3; i++) {
        s->pos[i] = nav0[i];
        s->v[i] = nav0[3 + i];
    }
    const double *c = config;
    double d[NMAX] = {c[SARINS_ESKF_POS0_STD], c[SARINS_ESKF_POS0_STD], c[SARINS_ESKF_POS0_STD],
                   c[SARINS_ESKF_VEL0_STD], c[SARINS_ESKF_VEL0_STD], c[SARINS_ESKF_VEL0_STD],
                   c[SARINS_ESKF_TILT0_STD], c[SARINS_ESKF_TILT0_STD], c[SARINS_ESKF_HEADING0_STD],
                   c[SARINS_ESKF_GYRO_BIAS0_STD], c[SARINS_ESKF_GYRO_BIAS0_STD], c[SARINS_ESKF_GYRO_BIAS0_STD],
                   c[SARINS_ESKF_ACCEL_BIAS0_STD], c[SARINS_ESKF_ACCEL_BIAS0_STD], c[SARINS_ESKF_ACCEL_BIAS0_STD]};
    const double *o = s->opt;
    for (int i = 0; i < 3; i++) {
        if (s->i_sg >= 0) {
            d[s->i_sg + i] = o[SARINS_ESKF_GYRO_SF0_STD];
            d[s->i_sa + i] = o[SARINS_ESKF_ACCEL_SF0_STD];
        }
        if (s->i_lever >= 0)
            d[s->i_lever + i] = o[SARINS_ESKF_LEVER0_STD];
        if (s->i_gm_r >= 0)
            d[s->i_gm_r + i] = o[SARINS_ESKF_GNSS_POS_GM_STD + i];
        if (s->i_gm_v >= 0)
            d[s->i_gm_v + i] = o[SARINS_ESKF_GNSS_VEL_GM_STD + i];
    }
    for (int i = 0; i < n; i++)
        s->p[IDX(i, i)] = d[i] * d[i];
    return 0;
}

int sarins_eskf_check(const sarins_eskf *s, char *msg, size_t size)
{
    if (!options_ok(s->opt, msg, size))
        return 1;
    int64_t ix[5];
    int64_t n = layout((int)s->opt[SARINS_ESKF_STATES], ix, ix + 1, ix + 2, ix + 3, ix + 4);
    if (s->n != n || s->i_sg != ix[0] || s->i_sa != ix[1] || s->i_lever != ix[2] || s->i_gm_r != ix[3] ||
        s->i_gm_v != ix[4]) {
        sarins_say(msg, size, "the filter's state dimension or block indices are not those of its options");
        return 1;
    }
    const double *v[7] = {s->f_b, s->sg, s->sa, s->lever, s->gm_r, s->gm_v, s->x};
    for (int k = 0; k < 7; k++)
        for (int i = 0; i < (k == 6 ? n : 3); i++)
            if (!isfinite(v[k][i])) {
                sarins_say(msg, size, "a filter state value is not finite");
                return 1;
            }
    for (int64_t i = 0; i < n * n; i++)
        if (!isfinite(s->p[i])) {
            sarins_say(msg, size, "the filter's covariance is not finite");
            return 1;
        }
    for (int i = 0; i < 3; i++)
        if (!(s->sg[i] > -0.5 && s->sa[i] > -0.5)) {
            sarins_say(msg, size, "a scale-factor estimate is at or below -0.5");
            return 1;
        }
    return 0;
}

/* error-state dynamics matrix F (N x N) at the current state */
static void dynamics(const sarins_eskf *s, double *f)
{
    const int64_t n = s->n;
    for (int64_t i = 0; i < n * n; i++)
        f[i] = 0.0;
    double rm, rn, sl, cl, m[9];
    sarins_earth_radii(s->pos[0], &rm, &rn);
    sm_sincos(s->pos[0], &sl, &cl);
    double rmh = rm + s->pos[2], rnh = rn + s->pos[2];
    double w_ie[3] = {0.0, SARINS_EARTH_RATE * cl, SARINS_EARTH_RATE * sl};
    double w_en[3] = {-s->v[1] / rmh, s->v[0] / rnh, s->v[0] * sl / (cl * rnh)};
    sarins_quat_to_mat(s->q, m);
    const double *fn = s->f_n;
    double w2[3], wi[3];
    for (int i = 0; i < 3; i++) {
        w2[i] = 2.0 * w_ie[i] + w_en[i];
        wi[i] = w_ie[i] + w_en[i];
        f[IDX(i, 3 + i)] = 1.0; /* dr' = dv */
    }
    /* dv' = [f x] phi - [(2 w_ie + w_en) x] dv + mat_nb db_a + (0, 0, 2 g / R dr_U) */
    double fx[9] = {0.0, -fn[2], fn[1], fn[2], 0.0, -fn[0], -fn[1], fn[0], 0.0};
    double wx2[9] = {0.0, -w2[2], w2[1], w2[2], 0.0, -w2[0], -w2[1], w2[0], 0.0};
    double wxi[9] = {0.0, -wi[2], wi[1], wi[2], 0.0, -wi[0], -wi[1], wi[0], 0.0};
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            f[IDX(3 + i, 6 + j)] = fx[3 * i + j];
            f[IDX(3 + i, 3 + j)] = -wx2[3 * i + j];
            f[IDX(3 + i, 12 + j)] = m[3 * i + j];
            f[IDX(6 + i, 6 + j)] = -wxi[3 * i + j]; /* phi' = -[w_in x] phi ... */
            f[IDX(6 + i, 9 + j)] = -m[3 * i + j];   /* ... - mat_nb db_g */
        }
    double r = sm_sqrt(rm * rn) + s->pos[2];
    f[IDX(5, 2)] = 2.0 * sarins_earth_gravity(s->pos[0], s->pos[2]) / r;
    /* d omega_en (dv) */
    f[IDX(6, 4)] = -1.0 / rmh;
    f[IDX(7, 3)] = 1.0 / rnh;
    f[IDX(8, 3)] = sl / (cl * rnh);
    const double *o = s->opt;
    for (int i = 0; i < 3; i++) {
        if (s->i_sg >= 0)
            for (int j = 0; j < 3; j++) {
                f[IDX(6 + i, s->i_sg + j)] = -m[3 * i + j] * s->w_ib[j]; /* phi' = ... - mat_nb diag(w_ib) ds_g */
                f[IDX(3 + i, s->i_sa + j)] = m[3 * i + j] * s->f_b[j];   /* dv' = ... + mat_nb diag(f^b) ds_a */
            }
        if (s->i_sg >= 0 && o[SARINS_ESKF_SF_TAU] > 0.0) {
            f[IDX(s->i_sg + i, s->i_sg + i)] = -1.0 / o[SARINS_ESKF_SF_TAU];
            f[IDX(s->i_sa + i, s->i_sa + i)] = -1.0 / o[SARINS_ESKF_SF_TAU];
        }
        if (s->i_gm_r >= 0)
            f[IDX(s->i_gm_r + i, s->i_gm_r + i)] = -1.0 / o[SARINS_ESKF_GNSS_POS_GM_TAU];
        if (s->i_gm_v >= 0)
            f[IDX(s->i_gm_v + i, s->i_gm_v + i)] = -1.0 / o[SARINS_ESKF_GNSS_VEL_GM_TAU];
    }
}

/* Scratch matrices of propagate_cov: n rows padded to W columns (the padding held at 0), so a row's
 * loop has a length the compiler vectorizes without a remainder (lane by lane, the same operations).
 * W = 16 for n <= 16 (the 15 states), 32 beyond (the sums of the first 16 columns do not see W). */
#define W 32
typedef struct {
    double r[NMAX][W];
} mat_w;

/* c = a b (N x N in rows of W), skipping the zero entries of a: for a finite b the same as sarins_matmul
 * bit for bit (each c_ij still sums a_ik b_kj over ascending k from +0.0, and adding an exact zero
 * product never changes such a sum); F and Phi are sparse (zero bias rows, few nonzeros elsewhere). */
#if defined(__GNUC__) && defined(__x86_64__) && defined(__ELF__) && defined(__GLIBC__) && defined(__has_attribute)
#if __has_attribute(target_clones)
#define ESKF_CLONES __attribute__((target_clones("avx2", "default")))
#endif
#endif
#ifndef ESKF_CLONES
#define ESKF_CLONES
#endif
#if defined(__GNUC__)
#define ESKF_INLINE __attribute__((always_inline)) inline
#else
#define ESKF_INLINE inline
#endif
/* n states; called with n = SARINS_ESKF_N as a constant for the 15 states (the loops then have the fixed trip
 * counts they had before the optional states), else with s->n: the same operations in the same order */
static ESKF_INLINE void mul_skip_zeros_n(const int64_t n, const mat_w *a, const mat_w *b, mat_w *c)
{
    for (int i = 0; i < n; i++) {
        int ks[NMAX], nz = 0; /* the columns of a's row i that are not 0, ascending */
        for (int k = 0; k < n; k++) { /* without a branch: the pattern changes along the row */
            ks[nz] = k;
            nz += a->r[i][k] != 0.0;
        }
        double lo[8] = {0.0}, hi[8] = {0.0}; /* columns 0-7 and 8-15: sums that stay in registers */
        for (int t = 0; t < nz; t++) {
            double aik = a->r[i][ks[t]];
            const double *bk = b->r[ks[t]];
            for (int l = 0; l < 8; l++)
                lo[l] += aik * bk[l];
            for (int l = 0; l < 8; l++)
                hi[l] += aik * bk[8 + l];
        }
        for (int l = 0; l < 8; l++) {
            c->r[i][l] = lo[l];
            c->r[i][8 + l] = hi[l];
        }
        if (n > 16) { /* columns 16-31, the same sums */
            double lo2[8] = {0.0}, hi2[8] = {0.0};
            for (int t = 0; t < nz; t++) {
                double aik = a->r[i][ks[t]];
                const double *bk = b->r[ks[t]] + 16;
                for (int l = 0; l < 8; l++)
                    lo2[l] += aik * bk[l];
                for (int l = 0; l < 8; l++)
                    hi2[l] += aik * bk[8 + l];
            }
            for (int l = 0; l < 8; l++) {
                c->r[i][16 + l] = lo2[l];
                c->r[i][24 + l] = hi2[l];
            }
        }
    }
}

ESKF_CLONES static void mul_skip_zeros(int64_t n, const mat_w *a, const mat_w *b, mat_w *c)
{
    if (n == SARINS_ESKF_N)
        mul_skip_zeros_n(SARINS_ESKF_N, a, b, c);
    else
        mul_skip_zeros_n(n, a, b, c);
}

/* Rows n .. NMAX-1 of the work matrices below are never written and never read (mul_skip_zeros reads row k of
 * its second factor only for the nonzero columns k < n of a row of its first); gcc 12 at -O2 for mingw-w64 and
 * aarch64 (without the target clones) cannot see that and warns maybe-uninitialized. Zeroing them would cost
 * 40 KB of stores per propagation, so the warning is silenced for this function only. */
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
static void propagate_cov(sarins_eskf *s, double t)
{
    const int64_t n = s->n;
    const int w = n > 16 ? 32 : 16; /* the columns mul_skip_zeros writes */
    double f[NMAX * NMAX];
    mat_w a, a2, phi, m1, m2;
    dynamics(s, f);
    for (int i = 0; i < n; i++) {
        for (int j = 0; j < n; j++) {
            a.r[i][j] = f[IDX(i, j)] * t;
            m2.r[i][j] = s->p[IDX(i, j)];
        }
        for (int j = (int)n; j < w; j++)
            a.r[i][j] = m2.r[i][j] = 0.0;
    }
    mul_skip_zeros(n, &a, &a, &a2); /* (F T)^2 */
    for (int i = 0; i < n; i++)
        for (int j = 0; j < w; j++)
            phi.r[i][j] = (i == j ? 1.0 : 0.0) + a.r[i][j] + 0.5 * a2.r[i][j];
    /* P = Phi P Phi' + Q, as Phi (Phi P)': the transpose of Phi P Phi' with the same products in the same
     * order (P is written transposed, which the symmetrization below does not see) */
    mul_skip_zeros(n, &phi, &m2, &m1); /* Phi P */
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++)
            m2.r[j][i] = m1.r[i][j];
    mul_skip_zeros(n, &phi, &m2, &m1);
    const double *c = s->config, *o = s->opt;
    /* white-noise densities^2 of each block of 3: the 5 base blocks, then the optional ones (Gauss-Markov:
     * 2 sigma^2 / tau; random constants 0) */
    double q2[NMAX];
    double q[5] = {0.0, c[SARINS_ESKF_VRW], c[SARINS_ESKF_ARW], c[SARINS_ESKF_GYRO_RW], c[SARINS_ESKF_ACCEL_RW]};
    for (int i = 0; i < SARINS_ESKF_N; i++)
        q2[i] = q[i / 3] * q[i / 3];
    for (int i = SARINS_ESKF_N; i < n; i++)
        q2[i] = 0.0;
    double sf_tau = o[SARINS_ESKF_SF_TAU];
    for (int i = 0; i < 3; i++) {
        if (s->i_sg >= 0 && sf_tau > 0.0) {
            q2[s->i_sg + i] = 2.0 * o[SARINS_ESKF_GYRO_SF0_STD] * o[SARINS_ESKF_GYRO_SF0_STD] / sf_tau;
            q2[s->i_sa + i] = 2.0 * o[SARINS_ESKF_ACCEL_SF0_STD] * o[SARINS_ESKF_ACCEL_SF0_STD] / sf_tau;
        }
        if (s->i_gm_r >= 0) {
            double sd = o[SARINS_ESKF_GNSS_POS_GM_STD + i], tau = o[SARINS_ESKF_GNSS_POS_GM_TAU];
            q2[s->i_gm_r + i] = 2.0 * sd * sd / tau;
        }
        if (s->i_gm_v >= 0) {
            double sd = o[SARINS_ESKF_GNSS_VEL_GM_STD + i], tau = o[SARINS_ESKF_GNSS_VEL_GM_TAU];
            q2[s->i_gm_v + i] = 2.0 * sd * sd / tau;
        }
    }
    for (int i = 0; i < n; i++) {
        for (int j = 0; j < n; j++)
            s->p[IDX(i, j)] = m1.r[i][j];
        s->p[IDX(i, i)] += q2[i] * t;
    }
    sarins_symmetrize((int)n, s->p);
    /* the Gauss-Markov estimates that are not fed into the INS decay as Phi's diagonal says */
    for (int i = 0; i < 3; i++) {
        if (s->i_sg >= 0 && sf_tau > 0.0) {
            s->sg[i] *= phi.r[s->i_sg + i][s->i_sg + i];
            s->sa[i] *= phi.r[s->i_sa + i][s->i_sa + i];
        }
        if (s->i_gm_r >= 0)
            s->gm_r[i] *= phi.r[s->i_gm_r + i][s->i_gm_r + i];
        if (s->i_gm_v >= 0)
            s->gm_v[i] *= phi.r[s->i_gm_v + i][s->i_gm_v + i];
    }
}
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif

void sarins_eskf_predict(sarins_eskf *s, const double *dtheta, const double *dv)
{
    double h = s->config[SARINS_ESKF_STEP], dt[3], dvc[3], dvn[3];
    for (int i = 0; i < 3; i++) {
        dt[i] = dtheta[i] - s->bg[i] * h;
        dvc[i] = dv[i] - s->ba[i] * h;
        if (s->i_sg >= 0) { /* (x - b h) / (1 + s) */
            dt[i] /= 1.0 + s->sg[i];
            dvc[i] /= 1.0 + s->sa[i];
        }
        s->w_ib[i] = dt[i] / h;
        s->f_b[i] = dvc[i] / h;
    }
    sarins_nav3_step_dvn(s->q, s->v, s->pos, dt, dvc, h, dvn);
    for (int i = 0; i < 3; i++) /* specific force in n at the start of the step: mat_nb,k-1 dv_c / h */
        s->f_n[i] = dvn[i] / h;
    s->steps += 1;
    s->since_cov += 1;
    if ((double)s->since_cov >= s->config[SARINS_ESKF_COV_EVERY]) {
        propagate_cov(s, (double)s->since_cov * h);
        s->since_cov = 0;
    }
}

/* scalar Joseph update with row hrow (N), innovation z (computed - measured), variance r; returns z^2 / s */
static ESKF_INLINE double scalar_update_n(sarins_eskf *s, const double *hrow, double z, double r, const int64_t n)
{
    double ph[NMAX], k[NMAX], sv = r;
    for (int i = 0; i < n; i++) {
        double acc = 0.0;
        for (int j = 0; j < n; j++)
            acc += s->p[IDX(i, j)] * hrow[j];
        ph[i] = acc;
    }
    for (int i = 0; i < n; i++)
        sv += hrow[i] * ph[i];
    double innov = z;
    for (int i = 0; i < n; i++)
        innov -= hrow[i] * s->x[i];
    for (int i = 0; i < n; i++)
        k[i] = ph[i] / sv;
    for (int i = 0; i < n; i++)
        s->x[i] += k[i] * innov;
    /* Joseph: P = (I - k h) P (I - k h)' + k r k', expanded with a = P h' (= ph):
     *     P = P - k a' - a k' + (h a + r) k k'     (valid for any gain k; O(n^2)) */
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++)
            s->p[IDX(i, j)] += (sv * k[i] * k[j] - k[i] * ph[j]) - ph[i] * k[j];
    sarins_symmetrize((int)n, s->p);
    return innov * innov / sv;
}

static double scalar_update(sarins_eskf *s, const double *hrow, double z, double r)
{ /* n a constant for the 15 states (see mul_skip_zeros_n) */
    return s->n == SARINS_ESKF_N ? scalar_update_n(s, hrow, z, r, SARINS_ESKF_N) : scalar_update_n(s, hrow, z, r, s->n);
}

/* zero a measurement row of the n states */
static void clear_row(const sarins_eskf *s, double *hrow)
{
    for (int j = 0; j < s->n; j++)
        hrow[j] = 0.0;
}

static void feedback(sarins_eskf *s)
{
    double rm, rn;
    sarins_earth_radii(s->pos[0], &rm, &rn);
    double *x = s->x;
    s->pos[0] -= x[1] / (rm + s->pos[2]);
    s->pos[1] -= x[0] / ((rn + s->pos[2]) * sm_cos(s->pos[0]));
    s->pos[2] -= x[2];
    for (int i = 0; i < 3; i++) {
        s->v[i] -= x[3 + i];
        s->bg[i] += x[9 + i];
        s->ba[i] += x[12 + i];
        if (s->i_sg >= 0) {
            s->sg[i] += x[s->i_sg + i];
            s->sa[i] += x[s->i_sa + i];
        }
        if (s->i_lever >= 0)
            s->lever[i] += x[s->i_lever + i];
        if (s->i_gm_r >= 0)
            s->gm_r[i] += x[s->i_gm_r + i];
        if (s->i_gm_v >= 0)
            s->gm_v[i] += x[s->i_gm_v + i];
    }
    /* mat_true = (I + [phi x]) mat_computed: q_nb <- q(phi) q_nb */
    double qp[4], qn[4];
    sarins_rotvec_to_quat(x + 6, qp);
    sarins_quat_mult(qp, s->q, qn);
    double n = sm_sqrt(qn[0] * qn[0] + qn[1] * qn[1] + qn[2] * qn[2] + qn[3] * qn[3]);
    for (int i = 0; i < 4; i++)
        s->q[i] = qn[i] / n;
    for (int i = 0; i < s->n; i++)
        x[i] = 0.0;
}

static void cross_matrix_row(const double *a, int row, double *out3)
{ /* row `row` of [a x] */
    double k[9] = {0.0, -a[2], a[1], a[2], 0.0, -a[0], -a[1], a[0], 0.0};
    for (int j = 0; j < 3; j++)
        out3[j] = k[3 * row + j];
}

double sarins_eskf_gnss(sarins_eskf *s, const double *pos, const double *vel, const double *std, int use_vel)
{
    const double *lever = s->lever;
    double lat = s->config[SARINS_ESKF_LATENCY];
    double m[9], rm, rn, sl, cl;
    sarins_quat_to_mat(s->q, m);
    sarins_earth_radii(s->pos[0], &rm, &rn);
    sm_sincos(s->pos[0], &sl, &cl);
    double rmh = rm + s->pos[2], rnh = rn + s->pos[2];
    double ln[3], w_nb[3], wl[3], vl[3];
    double w_in[3] = {-s->v[1] / rmh, SARINS_EARTH_RATE * cl + s->v[0] / rnh,
                      SARINS_EARTH_RATE * sl + s->v[0] * sl / (cl * rnh)};
    for (int i = 0; i < 3; i++) {
        ln[i] = m[3 * i] * lever[0] + m[3 * i + 1] * lever[1] + m[3 * i + 2] * lever[2];
        w_nb[i] = s->w_ib[i] - (m[i] * w_in[0] + m[3 + i] * w_in[1] + m[6 + i] * w_in[2]);
    }
    wl[0] = w_nb[1] * lever[2] - w_nb[2] * lever[1];
    wl[1] = w_nb[2] * lever[0] - w_nb[0] * lever[2];
    wl[2] = w_nb[0] * lever[1] - w_nb[1] * lever[0];
    for (int i = 0; i < 3; i++)
        vl[i] = m[3 * i] * wl[0] + m[3 * i + 1] * wl[1] + m[3 * i + 2] * wl[2];
    /* the INS taken back to the fix's time: acceleration a = f^n + g^n - (2 w_ie + w_en) x v (from the last
     * step's specific force), r(t - L) = r - v L + a L^2 / 2, v(t - L) = v - a L */
    double w2[3] = {w_in[0], w_in[1] + SARINS_EARTH_RATE * cl, w_in[2] + SARINS_EARTH_RATE * sl};
    const double *v = s->v;
    double acc[3] = {s->f_n[0] - (w2[1] * v[2] - w2[2] * v[1]), s->f_n[1] - (w2[2] * v[0] - w2[0] * v[2]),
                     s->f_n[2] - (w2[0] * v[1] - w2[1] * v[0]) - sarins_earth_gravity(s->pos[0], s->pos[2])};
    double back[3], vback[3];
    for (int i = 0; i < 3; i++) {
        back[i] = -v[i] * lat + 0.5 * acc[i] * lat * lat;
        vback[i] = -acc[i] * lat;
    }
    /* position innovation, ENU m: r_ins(t - L) + mat_nb l - r_gnss */
    double z[3] = {(s->pos[1] - pos[1]) * rnh * cl + ln[0] + back[0],
                   (s->pos[0] - pos[0]) * rmh + ln[1] + back[1],
                   (s->pos[2] - pos[2]) + ln[2] + back[2]};
    double nis = 0.0, hrow[NMAX];
    for (int i = 0; i < 3; i++) {
        clear_row(s, hrow);
        hrow[i] = 1.0;
        cross_matrix_row(ln, i, hrow + 6); /* [(mat_nb l) x] */
        if (s->i_lever >= 0) /* -mat_nb, row i */
            for (int j = 0; j < 3; j++)
                hrow[s->i_lever + j] = -m[3 * i + j];
        if (s->i_gm_r >= 0) { /* the predicted fix carries the receiver's error estimate; H = -I */
            z[i] += s->gm_r[i];
            hrow[s->i_gm_r + i] = -1.0;
        }
        nis += scalar_update(s, hrow, z[i], std[i] * std[i]);
    }
    if (use_vel) {
        double lx[9] = {0.0, -lever[2], lever[1], lever[2], 0.0, -lever[0], -lever[1], lever[0], 0.0};
        double wx[9] = {0.0, -w_nb[2], w_nb[1], w_nb[2], 0.0, -w_nb[0], -w_nb[1], w_nb[0], 0.0};
        for (int i = 0; i < 3; i++) {
            clear_row(s, hrow);
            hrow[3 + i] = 1.0;
            cross_matrix_row(vl, i, hrow + 6);
            for (int j = 0; j < 3; j++) /* -mat_nb [l x], row i */
                hrow[9 + j] = -(m[3 * i] * lx[j] + m[3 * i + 1] * lx[3 + j] + m[3 * i + 2] * lx[6 + j]);
            if (s->i_lever >= 0) /* -mat_nb [omega_nb^b x], row i */
                for (int j = 0; j < 3; j++)
                    hrow[s->i_lever + j] = -(m[3 * i] * wx[j] + m[3 * i + 1] * wx[3 + j] + m[3 * i + 2] * wx[6 + j]);
            double zi = s->v[i] + vback[i] + vl[i] - vel[i];
            if (s->i_gm_v >= 0) {
                zi += s->gm_v[i];
                hrow[s->i_gm_v + i] = -1.0;
            }
            nis += scalar_update(s, hrow, zi, std[3 + i] * std[3 + i]);
        }
    }
    feedback(s);
    return nis;
}

void sarins_eskf_zupt(sarins_eskf *s, const double *v_meas)
{
    double hrow[NMAX], r = s->config[SARINS_ESKF_ZUPT_STD] * s->config[SARINS_ESKF_ZUPT_STD];
    for (int i = 0; i < 3; i++) {
        clear_row(s, hrow);
        hrow[3 + i] = 1.0;
        scalar_update(s, hrow, s->v[i] - v_meas[i], r);
    }
    feedback(s);
}

void sarins_eskf_zaru(sarins_eskf *s, const double *dtheta)
{
    double h = s->config[SARINS_ESKF_STEP], r = s->config[SARINS_ESKF_ZARU_STD] * s->config[SARINS_ESKF_ZARU_STD];
    double m[9], sl, cl, hrow[NMAX];
    sarins_quat_to_mat(s->q, m);
    sm_sincos(s->pos[0], &sl, &cl);
    double w_ie[3] = {0.0, SARINS_EARTH_RATE * cl, SARINS_EARTH_RATE * sl};
    double wx[9] = {0.0, -w_ie[2], w_ie[1], w_ie[2], 0.0, -w_ie[0], -w_ie[1], w_ie[0], 0.0};
    for (int i = 0; i < 3; i++) {
        clear_row(s, hrow);
        double pred = 0.0; /* (mat_bn omega_ie^n)_i, row i of mat_bn = column i of mat_nb */
        for (int j = 0; j < 3; j++) {
            pred += m[3 * j + i] * w_ie[j];
            hrow[6 + j] = m[i] * wx[j] + m[3 + i] * wx[3 + j] + m[6 + i] * wx[6 + j]; /* (mat_bn [w_ie x])_ij */
        }
        hrow[9 + i] = 1.0; /* w_ib carries +db_g (the bias block: true = estimate + db) */
        double w = (dtheta[i] - s->bg[i] * h) / h;
        if (s->i_sg >= 0) { /* the compensated rate (predict's) carries diag(w_ib) ds_g too */
            w = (dtheta[i] - s->bg[i] * h) / (1.0 + s->sg[i]) / h;
            hrow[s->i_sg + i] = pred; /* the true rate at rest (the measured w would correlate H with z's noise) */
        }
        scalar_update(s, hrow, w - pred, r);
    }
    feedback(s);
}

void sarins_eskf_body_velocity(sarins_eskf *s, const double *meas, const int *use, const double *std)
{
    double m[9], hrow[NMAX];
    sarins_quat_to_mat(s->q, m);
    const double *v = s->v;
    double vx[9] = {0.0, -v[2], v[1], v[2], 0.0, -v[0], -v[1], v[0], 0.0};
    for (int i = 0; i < 3; i++) {
        if (!use[i])
            continue;
        clear_row(s, hrow);
        double vb = 0.0;
        for (int j = 0; j < 3; j++) { /* row i of mat_bn = column i of mat_nb */
            vb += m[3 * j + i] * v[j];
            hrow[3 + j] = m[3 * j + i];
            hrow[6 + j] = -(m[i] * vx[j] + m[3 + i] * vx[3 + j] + m[6 + i] * vx[6 + j]);
        }
        scalar_update(s, hrow, vb - meas[i], std[i] * std[i]);
    }
    feedback(s);
}

void sarins_eskf_aid(sarins_eskf *s, const double *dtheta, const double *a)
{
    if (a[0] != 0.0)
        sarins_eskf_zupt(s, a + 1);
    if (a[9] != 0.0)
        sarins_eskf_zaru(s, dtheta);
    if (a[4] != 0.0 || a[6] != 0.0) {
        /* body x: NHC, y: odometer (forward), z: NHC */
        double meas[3] = {a[7], a[5], a[8]};
        int use[3] = {a[6] != 0.0, a[4] != 0.0, a[6] != 0.0};
        double nhc = s->config[SARINS_ESKF_NHC_STD];
        double std[3] = {nhc, s->config[SARINS_ESKF_ODO_STD], nhc};
        sarins_eskf_body_velocity(s, meas, use, std);
    }
}

/* an output row: nav (9), b_g, b_a, then P (full_cov) or its diagonal */
static void write_row(const sarins_eskf *s, int full_cov, double *row)
{
    sarins_nav3_row(s->q, s->v, s->pos, row);
    for (int i = 0; i < 3; i++) {
        row[9 + i] = s->bg[i];
        row[12 + i] = s->ba[i];
    }
    const int64_t n = s->n;
    int64_t at = 15; /* the optional blocks' estimates, in the state's order */
    const double *est[5] = {s->sg, s->sa, s->lever, s->gm_r, s->gm_v};
    const int64_t first[5] = {s->i_sg, s->i_sa, s->i_lever, s->i_gm_r, s->i_gm_v};
    for (int b = 0; b < 5; b++)
        if (first[b] >= 0)
            for (int i = 0; i < 3; i++)
                row[at++] = est[b][i];
    if (full_cov)
        for (int64_t i = 0; i < n * n; i++)
            row[at + i] = s->p[i];
    else
        for (int i = 0; i < n; i++)
            row[at + i] = s->p[IDX(i, i)];
}

int sarins_eskf_run(sarins_eskf *s, int64_t k, const double *dtheta, const double *dv, const double *aid, int64_t m,
                    const double *gnss, const double *vel_std, int use_vel, int64_t out_every, int full_cov, double *out)
{
    int64_t width = sarins_eskf_row_size(s, full_cov);
    if (out_every < 1 || k < 0 || m < 0)
        return 1;
    for (int64_t i = 0; i < 3 * k; i++)
        if (!isfinite(dtheta[i]) || !isfinite(dv[i]))
            return 1;
    for (int64_t i = 0; i < SARINS_ESKF_AID * k; i++)
        if (!isfinite(aid[i]))
            return 1;
    for (int64_t j = 0; j < m * SARINS_ESKF_GNSS; j++)
        if (!isfinite(gnss[j]))
            return 1;
    for (int64_t j = 1; j < m; j++)
        if (gnss[j * SARINS_ESKF_GNSS] < gnss[(j - 1) * SARINS_ESKF_GNSS])
            return 1;
    for (int i = 0; i < 3; i++)
        if (!isfinite(vel_std[i]) || !(vel_std[i] > 0.0))
            return 1;
    int64_t g = 0;
    while (g < m && gnss[g * SARINS_ESKF_GNSS] < 0.0) /* fixes before this run: skipped */
        g++;
    for (int64_t i = 0; i < k; i++) {
        sarins_eskf_predict(s, dtheta + 3 * i, dv + 3 * i);
        sarins_eskf_aid(s, dtheta + 3 * i, aid + SARINS_ESKF_AID * i);
        for (; g < m && gnss[g * SARINS_ESKF_GNSS] <= (double)i; g++) {
            const double *r = gnss + g * SARINS_ESKF_GNSS;
            if (r[0] < (double)i || r[1] == 0.0)
                continue;
            double std[6] = {r[8], r[9], r[10], vel_std[0], vel_std[1], vel_std[2]};
            sarins_eskf_gnss(s, r + 2, r + 5, std, use_vel);
        }
        if ((i + 1) % out_every == 0)
            write_row(s, full_cov, out + width * ((i + 1) / out_every - 1));
    }
    return 0;
}
