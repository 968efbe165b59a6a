/* The IMU built from its flat parameters: see imu_build.h.  Every expression follows the former Python
 * construction (sarins_fmu/imu.py IMU._allocate, imu_correlated.CorrelatedErrors) term by term. */
#include "smath.h"

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "dynamics.h"
#include "imu.h"
#include "imu_build.h"
#include "imu_params.h"

#define PI 3.14159265358979323846

/* index of triad t's (0 gyro, 1 accel) parameter whose gyro x index is gyro_x, axis i */
#define TRIAD_STRIDE (SARINS_IMU_P_ACCEL_BIAS_X - SARINS_IMU_P_GYRO_BIAS_X)
#define TP(gyro_x, t, i) ((gyro_x) + (t)*TRIAD_STRIDE + (i))
/* sensor j's (gyro x y z, accel x y z) thermal parameter whose gyro x index is first */
#define SP(first, j) ((first) + 3 * (j))

static const int MISALIGNMENT[6][2] = {{0, 1}, {0, 2}, {1, 0}, {1, 2}, {2, 0}, {2, 1}}; /* xy xz yx yz zx zy */
static const int LOWRATE_GAIN[3] = {SARINS_IMU_P_LOWRATE_GAIN_X, SARINS_IMU_P_LOWRATE_GAIN_Y,
                                    SARINS_IMU_P_LOWRATE_GAIN_Z};
static const int LOWRATE_WIDTH[3] = {SARINS_IMU_P_LOWRATE_WIDTH_X, SARINS_IMU_P_LOWRATE_WIDTH_Y,
                                     SARINS_IMU_P_LOWRATE_WIDTH_Z};
static const int DRIFT[3] = {SARINS_IMU_P_AXIAL_DRIFT_A, SARINS_IMU_P_AXIAL_DRIFT_B, SARINS_IMU_P_AXIAL_DRIFT_C};
static const int AGING[3] = {SARINS_IMU_P_AGING_SIGMA_A, SARINS_IMU_P_AGING_SIGMA_B, SARINS_IMU_P_AGING_SIGMA_C};

int64_t sarins_imu_flicker_count(double tau_min, double tau_max) {
    if (!(tau_min > 0.0 && tau_min < tau_max && tau_max < INFINITY)) return 0;
    double n = sm_ceil(SARINS_IMU_FLICKER_PER_DECADE * sm_log10(tau_max / tau_min)) + 1.0;
    return n > 2.0 ? (int64_t)n : 2;
}

void sarins_imu_flicker_taus(double tau_min, double tau_max, int64_t n, double *taus) {
    /* 10^(log10 tau_min + i step), step = (log10 tau_max - log10 tau_min) / (F - 1): numpy.geomspace's sum */
    double low = sm_log10(tau_min), step = (sm_log10(tau_max) - low) / (double)(n - 1);
    for (int64_t i = 0; i < n; i++) taus[i] = sm_exp10((double)i * step + low);
    taus[0] = tau_min;
    taus[n - 1] = tau_max;
}

/* the first index in first + (0..count) * stride whose value breaks the rule, else -1 */
enum { NON_NEGATIVE, POSITIVE };
static int64_t first_bad(const double *par, int first, int count, int stride, int rule) {
    for (int k = 0; k < count; k++) {
        double x = par[first + k * stride];
        if (rule == NON_NEGATIVE ? !(x >= 0.0) : !(x > 0.0)) return first + k * stride;
    }
    return -1;
}

int64_t sarins_imu_check_params(const double *par, const char **reason) {
    for (int64_t i = 0; i < SARINS_IMU_N_PARAMS; i++) {
        if (!isfinite(par[i])) {
            *reason = "must be finite";
            return i;
        }
    }
    static const struct {
        int first, count, stride, rule;
        const char *reason;
    } RULES[] = {
        {SARINS_IMU_P_GYRO_RANDOM_WALK_X, 3, 1, NON_NEGATIVE, "must be non-negative"},
        {SARINS_IMU_P_ACCEL_RANDOM_WALK_X, 3, 1, NON_NEGATIVE, "must be non-negative"},
        {SARINS_IMU_P_GYRO_BIAS_INSTABILITY_X, 3, 1, NON_NEGATIVE, "must be non-negative"},
        {SARINS_IMU_P_ACCEL_BIAS_INSTABILITY_X, 3, 1, NON_NEGATIVE, "must be non-negative"},
        {SARINS_IMU_P_GYRO_BIAS_CORR_TIME_X, 3, 1, POSITIVE, "must be positive"},
        {SARINS_IMU_P_ACCEL_BIAS_CORR_TIME_X, 3, 1, POSITIVE, "must be positive"},
        {SARINS_IMU_P_GYRO_HYSTERESIS_WIDTH_X, 3, 1, POSITIVE, "must be positive"},
        {SARINS_IMU_P_ACCEL_HYSTERESIS_WIDTH_X, 3, 1, POSITIVE, "must be positive"},
        {SARINS_IMU_P_GYRO_FLICKER_X, 3, 1, NON_NEGATIVE, "must be non-negative"},
        {SARINS_IMU_P_ACCEL_FLICKER_X, 3, 1, NON_NEGATIVE, "must be non-negative"},
        {SARINS_IMU_P_GYRO_RATE_RANDOM_WALK_X, 3, 1, NON_NEGATIVE, "must be non-negative"},
        {SARINS_IMU_P_ACCEL_RATE_RANDOM_WALK_X, 3, 1, NON_NEGATIVE, "must be non-negative"},
        {SARINS_IMU_P_GYRO_TURN_ON_BIAS_X, 3, 1, NON_NEGATIVE, "must be non-negative"},
        {SARINS_IMU_P_ACCEL_TURN_ON_BIAS_X, 3, 1, NON_NEGATIVE, "must be non-negative"},
        {SARINS_IMU_P_GYRO_FILTER_TIME_CONSTANT_X, 3, 1, NON_NEGATIVE, "must be non-negative"},
        {SARINS_IMU_P_ACCEL_FILTER_TIME_CONSTANT_X, 3, 1, NON_NEGATIVE, "must be non-negative"},
        {SARINS_IMU_P_GYRO_RATE_HYSTERESIS_WIDTH_X, 3, 1, POSITIVE, "must be positive"},
        {SARINS_IMU_P_ACCEL_RATE_HYSTERESIS_WIDTH_X, 3, 1, POSITIVE, "must be positive"},
        {SARINS_IMU_P_GYRO_RATE_HYSTERESIS_TIME_X, 3, 1, NON_NEGATIVE, "must be non-negative"},
        {SARINS_IMU_P_ACCEL_RATE_HYSTERESIS_TIME_X, 3, 1, NON_NEGATIVE, "must be non-negative"},
        {SARINS_IMU_P_LOWRATE_WIDTH_X, 3, 2, POSITIVE, "must be positive"},
        {SARINS_IMU_P_AGING_CORR_TIME, 1, 1, POSITIVE, "must be positive"},
        {SARINS_IMU_P_FLICKER_TAU_MIN, 1, 1, POSITIVE, "must be positive"},
        {SARINS_IMU_P_TIME_CONSTANT_GYRO_X, 6, 3, POSITIVE, "must be positive"},
        {SARINS_IMU_P_DIE_TIME_CONSTANT_GYRO_X, 6, 3, NON_NEGATIVE, "must be non-negative"},
        {SARINS_IMU_P_AXIAL_BLOCK_TIME_CONSTANT, 1, 1, NON_NEGATIVE, "must be non-negative"},
        {SARINS_IMU_P_AXIAL_HYSTERESIS_WIDTH, 1, 1, POSITIVE, "must be positive"},
        {SARINS_IMU_P_AXIAL_HYSTERESIS_RELAX_TIME, 1, 1, NON_NEGATIVE, "must be non-negative"},
    };
    for (size_t r = 0; r < sizeof RULES / sizeof RULES[0]; r++) {
        int64_t bad = first_bad(par, RULES[r].first, RULES[r].count, RULES[r].stride, RULES[r].rule);
        if (bad >= 0) {
            *reason = RULES[r].reason;
            return bad;
        }
    }
    if (!(par[SARINS_IMU_P_FLICKER_TAU_MAX] > par[SARINS_IMU_P_FLICKER_TAU_MIN])) {
        *reason = "must exceed flicker_tau_min";
        return SARINS_IMU_P_FLICKER_TAU_MAX;
    }
    /* The flicker band [tau_min, tau_max] is synthesised by Gauss-Markov terms whose decay factors
     * exp(-h/tau) act on one double-precision state: a band wider than 1/DBL_EPSILON = 2^52 (15.7 decades)
     * holds terms whose contributions differ by less than an ulp of the largest, and its term count
     * (SARINS_IMU_FLICKER_PER_DECADE per decade) would grow without bound (tau_min = 5e-324 makes the ratio
     * infinite).  So tau_max / tau_min <= 2^52, which also keeps the count <= 3 x 16 + 1 = 49 terms. */
    if (!(par[SARINS_IMU_P_FLICKER_TAU_MAX] / par[SARINS_IMU_P_FLICKER_TAU_MIN] <= SARINS_IMU_FLICKER_MAX_RATIO)) {
        *reason = "must be at least flicker_tau_max / 2^52 (a flicker band of at most 15.7 decades)";
        return SARINS_IMU_P_FLICKER_TAU_MIN;
    }
    /* a sensor's self-heating rise above the ambient (degC), within the limit the IMUThermal FMU already
     * applied (now checked here once, for the library too: a rise of 1e308 degC made the first step NaN) */
    for (int j = 0; j < 6; j++) {
        int k = SP(SARINS_IMU_P_SELF_HEATING_GYRO_X, j);
        if (!(sm_fabs(par[k]) <= SARINS_IMU_SELF_HEATING_LIMIT)) {
            *reason = "must lie within +-500 degC";
            return k;
        }
    }
    return -1;
}

int64_t sarins_imu_check_rate_params(const double *par, double internal_rate, const char **reason) {
    double limit = 0.5 * PI * internal_rate; /* rad/s: a quarter turn per minor step (imu_build.h) */
    for (int i = 0; i < 3; i++) {
        int k = SARINS_IMU_P_GYRO_BIAS_X + i;
        if (!(sm_fabs(par[k]) <= limit)) {
            *reason = "must be at most pi/2 rad per minor step in magnitude (|bias| <= pi/2 x internal_rate)";
            return k;
        }
    }
    return -1;
}

/* the float64 array of table row i if its shape is (rows, cols), else NULL */
static double *row_array(const int64_t *table, int64_t i, int64_t rows, int64_t cols) {
    if (table[3 * i + 1] != rows || table[3 * i + 2] != cols) return NULL;
    return rows == 0 ? (double *)(intptr_t)1 : (double *)(intptr_t)table[3 * i];
}

typedef struct {
    double *consts, *clock, *sensor_par, *state, *coef, *triad, *mats, *corr_par, *corr_state, *phi, *q, *x_flicker,
        *dyn_par, *dyn_state;
} Arrays;

static int arrays_of(const int64_t *table, int64_t rows, int64_t n_flicker, Arrays *a) {
    if (table == NULL || rows < SARINS_IMU_N_ARRAYS) return 0;
    a->consts = row_array(table, SARINS_IMU_CONSTS, SARINS_IMU_N_CONSTS, 1);
    a->clock = row_array(table, SARINS_IMU_CLOCK, 2, 1);
    a->sensor_par = row_array(table, SARINS_IMU_SENSOR_PAR, 4, 6);
    a->state = row_array(table, SARINS_IMU_STATE, 3, 6);
    a->coef = row_array(table, SARINS_IMU_COEF, 10, 3);
    a->triad = row_array(table, SARINS_IMU_TRIAD, 7, 3);
    a->mats = row_array(table, SARINS_IMU_MATS, 9, 3);
    a->corr_par = row_array(table, SARINS_IMU_CORR_PAR, 8, 6);
    a->corr_state = row_array(table, SARINS_IMU_CORR_STATE, 3, 6);
    a->phi = row_array(table, SARINS_IMU_PHI, n_flicker, 1);
    a->q = row_array(table, SARINS_IMU_Q, n_flicker, 6);
    a->x_flicker = row_array(table, SARINS_IMU_X_FLICKER, n_flicker, 6);
    a->dyn_par = row_array(table, SARINS_IMU_DYN_PAR, SARINS_DYN_PAR_ROWS, 6);
    a->dyn_state = row_array(table, SARINS_IMU_DYN_STATE, SARINS_DYN_STATE_ROWS, 6);
    double *all[] = {a->consts, a->clock, a->sensor_par, a->state, a->coef, a->triad, a->mats, a->corr_par,
                     a->corr_state, a->phi, a->q, a->x_flicker, a->dyn_par, a->dyn_state};
    for (size_t i = 0; i < sizeof all / sizeof all[0]; i++) {
        if (all[i] == NULL) return 0;
    }
    return 1;
}

/* 1 when any of the n values from first on (stride) is not zero */
static int any_set(const double *par, int first, int count, int stride) {
    for (int k = 0; k < count; k++) {
        if (par[first + k * stride] != 0.0) return 1;
    }
    return 0;
}

int sarins_imu_build(const int64_t *table, int64_t rows, const double *par, double t0, double h, int64_t n_sub,
                     double age, uint64_t seed) {
    const char *reason;
    if (par == NULL || sarins_imu_check_params(par, &reason) >= 0) return SARINS_IMU_BAD_TABLE;
    if (!(h > 0.0 && h < INFINITY && n_sub >= 1 && n_sub <= SARINS_IMU_MAX_SUB && isfinite(t0) && age >= 0.0 && age < INFINITY))
        return SARINS_IMU_BAD_TABLE;
    int64_t n_flicker = sarins_imu_flicker_count(par[SARINS_IMU_P_FLICKER_TAU_MIN], par[SARINS_IMU_P_FLICKER_TAU_MAX]);
    Arrays a;
    if (!arrays_of(table, rows, n_flicker, &a)) return SARINS_IMU_BAD_TABLE;
    int die_lag = 0;
    for (int j = 0; j < 6; j++) die_lag |= par[SP(SARINS_IMU_P_DIE_TIME_CONSTANT_GYRO_X, j)] > 0.0;
    int active = die_lag;
    static const int CORRELATED[] = {SARINS_IMU_P_GYRO_BIAS_DTDT_X, SARINS_IMU_P_GYRO_SCALE_FACTOR_DTDT_X,
                                     SARINS_IMU_P_GYRO_HYSTERESIS_X, SARINS_IMU_P_GYRO_FLICKER_X,
                                     SARINS_IMU_P_GYRO_RATE_RANDOM_WALK_X, SARINS_IMU_P_GYRO_TURN_ON_BIAS_X};
    for (size_t k = 0; k < sizeof CORRELATED / sizeof CORRELATED[0]; k++) {
        active |= any_set(par, CORRELATED[k], 3, 1) || any_set(par, CORRELATED[k] + TRIAD_STRIDE, 3, 1);
    }
    /* consts: t0, h, drift_dtdt, die_lag, correlated_active, n_sub, (spare), (spare), the five parameters of
       sarins_imu_axial_thermal_terms (gradient coefficient, block time constant, hysteresis, its width and
       relaxation time) */
    double consts[SARINS_IMU_N_CONSTS] = {t0, h, par[SARINS_IMU_P_AXIAL_DRIFT_DTDT], die_lag, active, (double)n_sub,
                                          0.0, 0.0, par[SARINS_IMU_P_AXIAL_DRIFT_GRAD],
                                          par[SARINS_IMU_P_AXIAL_BLOCK_TIME_CONSTANT], par[SARINS_IMU_P_AXIAL_HYSTERESIS],
                                          par[SARINS_IMU_P_AXIAL_HYSTERESIS_WIDTH],
                                          par[SARINS_IMU_P_AXIAL_HYSTERESIS_RELAX_TIME]};
    memcpy(a.consts, consts, sizeof consts);
    for (int j = 0; j < 6; j++) {
        int t = j / 3, i = j % 3;
        a.sensor_par[j] = par[SP(SARINS_IMU_P_SELF_HEATING_GYRO_X, j)];
        a.sensor_par[6 + j] = par[SP(SARINS_IMU_P_TIME_CONSTANT_GYRO_X, j)];
        a.sensor_par[12 + j] = sm_exp(-h / par[TP(SARINS_IMU_P_GYRO_BIAS_CORR_TIME_X, t, i)]);
        a.sensor_par[18 + j] = par[TP(SARINS_IMU_P_GYRO_BIAS_INSTABILITY_X, t, i)];
    }
    /* coef: per triad bias, tc1, tc2, scale factor, sf_tc */
    static const int COEF[5] = {SARINS_IMU_P_GYRO_BIAS_X, SARINS_IMU_P_GYRO_BIAS_TC1_X, SARINS_IMU_P_GYRO_BIAS_TC2_X,
                                SARINS_IMU_P_GYRO_SCALE_FACTOR_X, SARINS_IMU_P_GYRO_SCALE_FACTOR_TC_X};
    for (int t = 0; t < 2; t++) {
        for (int r = 0; r < 5; r++) {
            for (int i = 0; i < 3; i++) a.coef[15 * t + 3 * r + i] = par[TP(COEF[r], t, i)];
        }
    }
    /* triad: drift poly (aged), gyro quadratic, low-rate gain, low-rate width, accel quadratic, random walks */
    double poly[3], sigma[3];
    int aged = 0;
    for (int i = 0; i < 3; i++) {
        poly[i] = par[DRIFT[i]];
        sigma[i] = par[AGING[i]];
        aged |= sigma[i] > 0.0;
    }
    if (age > 0.0 && aged) {
        sarins_imu_aged_poly(seed, 1, &age, poly, sigma, par[SARINS_IMU_P_AGING_CORR_TIME], a.triad);
    } else {
        memcpy(a.triad, poly, sizeof poly);
    }
    for (int i = 0; i < 3; i++) {
        a.triad[3 + i] = par[TP(SARINS_IMU_P_GYRO_QUADRATIC_X, 0, i)];
        a.triad[6 + i] = par[LOWRATE_GAIN[i]];
        a.triad[9 + i] = par[LOWRATE_WIDTH[i]];
        a.triad[12 + i] = par[TP(SARINS_IMU_P_GYRO_QUADRATIC_X, 1, i)];
        a.triad[15 + i] = par[TP(SARINS_IMU_P_GYRO_RANDOM_WALK_X, 0, i)];
        a.triad[18 + i] = par[TP(SARINS_IMU_P_GYRO_RANDOM_WALK_X, 1, i)];
    }
    /* mats: gyro misalignment, g-sensitivity, accel misalignment (diagonals 0) */
    memset(a.mats, 0, 27 * sizeof *a.mats);
    for (int k = 0; k < 6; k++) {
        int i = MISALIGNMENT[k][0], j = MISALIGNMENT[k][1];
        a.mats[3 * i + j] = par[SARINS_IMU_P_GYRO_MISALIGNMENT_XY + k];
        a.mats[18 + 3 * i + j] = par[SARINS_IMU_P_ACCEL_MISALIGNMENT_XY + k];
    }
    for (int k = 0; k < 9; k++) a.mats[9 + k] = par[SARINS_IMU_P_G_SENSITIVITY_XX + k];
    /* corr_par: die time constant, c_grad, s_grad, c_hyst, w_hyst, rrw, (turn-on bias: drawn at seeding),
       turn-on std */
    static const int CORR[6] = {-1, SARINS_IMU_P_GYRO_BIAS_DTDT_X, SARINS_IMU_P_GYRO_SCALE_FACTOR_DTDT_X,
                                SARINS_IMU_P_GYRO_HYSTERESIS_X, SARINS_IMU_P_GYRO_HYSTERESIS_WIDTH_X,
                                SARINS_IMU_P_GYRO_RATE_RANDOM_WALK_X};
    for (int j = 0; j < 6; j++) {
        int t = j / 3, i = j % 3;
        a.corr_par[j] = par[SP(SARINS_IMU_P_DIE_TIME_CONSTANT_GYRO_X, j)];
        for (int r = 1; r < 6; r++) a.corr_par[6 * r + j] = par[TP(CORR[r], t, i)];
        a.corr_par[36 + j] = 0.0;
        a.corr_par[42 + j] = par[TP(SARINS_IMU_P_GYRO_TURN_ON_BIAS_X, t, i)];
    }
    /* flicker terms: phi_i = exp(-h / tau_i), q = B sqrt(ln(tau_1 / tau_0) / pi) (imu_correlated.py) */
    sarins_imu_flicker_taus(par[SARINS_IMU_P_FLICKER_TAU_MIN], par[SARINS_IMU_P_FLICKER_TAU_MAX], n_flicker, a.phi);
    double unit_std = 1.0 * sm_sqrt(sm_log(a.phi[1] / a.phi[0]) / PI);
    for (int64_t k = 0; k < n_flicker; k++) {
        a.phi[k] = sm_exp(-h / a.phi[k]);
        for (int j = 0; j < 6; j++) {
            a.q[6 * k + j] = unit_std * par[TP(SARINS_IMU_P_GYRO_FLICKER_X, j / 3, j % 3)];
        }
    }
    /* dyn_par (dynamics.h): filter time constant, rate hysteresis amplitude, width, relaxation time,
       temperature coefficient; rows 5-7 component a of each accelerometer's lever arm (gyro columns 0) */
    static const int DYN[5] = {SARINS_IMU_P_GYRO_FILTER_TIME_CONSTANT_X, SARINS_IMU_P_GYRO_RATE_HYSTERESIS_X,
                               SARINS_IMU_P_GYRO_RATE_HYSTERESIS_WIDTH_X, SARINS_IMU_P_GYRO_RATE_HYSTERESIS_TIME_X,
                               SARINS_IMU_P_GYRO_RATE_HYSTERESIS_TC_X};
    memset(a.dyn_par, 0, SARINS_DYN_PAR_ROWS * 6 * sizeof *a.dyn_par);
    for (int j = 0; j < 6; j++) {
        for (int r = 0; r < 5; r++) a.dyn_par[6 * r + j] = par[TP(DYN[r], j / 3, j % 3)];
    }
    for (int i = 0; i < 3; i++) {
        for (int c = 0; c < 3; c++) a.dyn_par[6 * (5 + c) + 3 + i] = par[SARINS_IMU_P_ACCEL_LEVER_ARM_XX + 3 * i + c];
    }
    return SARINS_IMU_OK;
}

int sarins_imu_start(const int64_t *table, int64_t rows, double ambient0, int hot, uint64_t seed) {
    if (table == NULL || rows < SARINS_IMU_N_ARRAYS || !(isfinite(ambient0) && ambient0 >= -273.15))
        return SARINS_IMU_BAD_TABLE;
    Arrays a;
    if (!arrays_of(table, rows, table[3 * SARINS_IMU_PHI + 1], &a)) return SARINS_IMU_BAD_TABLE;
    a.clock[0] = 0.0;
    a.clock[1] = ambient0;
    for (int j = 0; j < 6; j++) {
        double temperature = hot ? ambient0 + a.sensor_par[j] : ambient0 + 0.0;
        a.state[j] = temperature;
        a.corr_state[j] = temperature;      /* die */
        a.corr_state[6 + j] = temperature;  /* play operator, relaxed */
        a.corr_state[12 + j] = 0.0;         /* rate random walk */
        a.state[12 + j] = 0.0;
    }
    /* the z gyro's block node and play operator at its temperature: no gradient, the loop at 0 */
    a.state[12] = a.state[13] = a.state[2];
    /* the output dynamics at rest: each state starts on its first input */
    memset(a.dyn_state, 0, SARINS_DYN_STATE_ROWS * 6 * sizeof *a.dyn_state);
    return sarins_imu_seed(table, rows, seed); /* the GM and flicker states, the turn-on bias */
}
