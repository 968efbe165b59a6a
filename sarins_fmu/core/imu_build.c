/* The IMU built from its flat parameters: see imu_build.h.  Every expression follows the former Python
 * construction (sarins_fmu/imu.py IMU._allocate, imu_correlated.CorrelatedErrors) term by term. */
#include "smath.h"

#include <float.h>
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
/* sensor j's periodic amplitude and frequency (imu_params.h: per triad amplitude x y z, frequency x y z) */
#define PERIODIC_AMPLITUDE(j) (SARINS_IMU_P_GYRO_PERIODIC_AMPLITUDE_X + 6 * ((j) / 3) + (j) % 3)
#define PERIODIC_FREQUENCY(j) (SARINS_IMU_P_GYRO_PERIODIC_FREQUENCY_X + 6 * ((j) / 3) + (j) % 3)

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
        {SARINS_IMU_P_GYRO_PERIODIC_AMPLITUDE_X, 3, 1, NON_NEGATIVE, "must be non-negative"},
        {SARINS_IMU_P_ACCEL_PERIODIC_AMPLITUDE_X, 3, 1, NON_NEGATIVE, "must be non-negative"},
        {SARINS_IMU_P_GYRO_PERIODIC_FREQUENCY_X, 3, 1, NON_NEGATIVE, "must be non-negative"},
        {SARINS_IMU_P_ACCEL_PERIODIC_FREQUENCY_X, 3, 1, NON_NEGATIVE, "must be non-negative"},
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
    /* a periodic term with an amplitude needs a frequency (0 Hz would be a constant bias: that is bias) */
    for (int j = 0; j < 6; j++) {
        if (par[PERIODIC_AMPLITUDE(j)] > 0.0 && !(par[PERIODIC_FREQUENCY(j)] > 0.0)) {
            *reason = "must be positive where the periodic amplitude is not zero";
            return PERIODIC_FREQUENCY(j);
        }
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

double sarins_imu_max_rate(double internal_rate) {
    return sm_fmin(PI / 8.0 * internal_rate, SARINS_IMU_GYRO_FULL_SCALE);
}

/* ------------------------------------------------ derived bounds (imu_build.h sarins_imu_param_bound) */

#define MAX_TERMS 24
#define LOWER_BOUND SARINS_IMU_LOWER_BOUND
#define SQRT3 1.7320508075688772

/* A sum of error terms sum_k scale_k |par[index_k]| that must stay within capacity. */
typedef struct {
    double capacity;
    int n;
    int index[MAX_TERMS];
    double scale[MAX_TERMS];
    const char *reason;
} Sum;

static void term(Sum *s, int index, double scale) {
    s->index[s->n] = index;
    s->scale[s->n] = scale;
    s->n++;
}

/* The largest temperature rate of sensor j (degC/s): a change of at most TEMP_SPAN, at the rate of the
 * first-order model, (target - T) / tau <= SPAN / tau, and over at least one minor step (the die follows
 * the reported temperature, so its rate is no larger). */
static double temp_rate(const double *par, double internal_rate, int j) {
    double tau = par[SP(SARINS_IMU_P_TIME_CONSTANT_GYRO_X, j)];
    return SARINS_IMU_TEMP_SPAN / sm_fmax(tau, 1.0 / internal_rate);
}

/* sigma multiple of the flicker terms' sum: SIGMAS x F x the unit std sqrt(ln(tau_1 / tau_0) / pi) of each of
 * the F terms (imu_build.c, the flicker terms) */
static double flicker_scale(const double *par) {
    double lo = par[SARINS_IMU_P_FLICKER_TAU_MIN], hi = par[SARINS_IMU_P_FLICKER_TAU_MAX];
    int64_t n = sarins_imu_flicker_count(lo, hi);
    if (n < 2) return SARINS_IMU_SIGMAS * 49.0; /* an invalid band (refused by sarins_imu_check_params) */
    double step = (sm_log10(hi) - sm_log10(lo)) / (double)(n - 1);
    return SARINS_IMU_SIGMAS * (double)n * sm_sqrt(step * sm_log(10.0) / PI);
}

/* The rules of the sign and additive sums of sensor j, naming its time constant (dT/dt_max) */
#define SIGN_RULE(what, sensor, lowrate)                                                                       \
    "the sensed " what " does not flip its sign (and stays within 2 x the true " what "): |sf| + |sf_tc| 975 "  \
    "degC + |sf_dtdt| dT/dt_max + |misalignment row| + " lowrate "|quadratic| full scale <= 1 (imu.h step 3), "  \
    "dT/dt_max = 1773.15 degC / max(time_constant_" sensor ", 1 / internal_rate)"
#define GYRO_ADD_RULE(sensor)                                                                                  \
    "a minor step's rotation stays below pi rad: the gyro's additive terms at 975 degC from 25, |T| <= 1000 "   \
    "degC, dT/dt_max = 1773.15 degC / max(time_constant_" sensor ", 1 / internal_rate) and 8 sigma <= 3 pi/4 x " \
    "internal_rate (imu_build.h)"
#define ACCEL_ADD_RULE(sensor)                                                                                 \
    "the accelerometer's additive terms at 975 degC from 25, dT/dt_max = 1773.15 degC / max(time_constant_"     \
    sensor ", 1 / internal_rate) and 8 sigma <= 1e6 x full scale (100 g)"
static const char *const SIGN_REASON[6] = {
    SIGN_RULE("rate", "gyro_x", "|lowrate_gain| + "), SIGN_RULE("rate", "gyro_y", "|lowrate_gain| + "),
    SIGN_RULE("rate", "gyro_z", "|lowrate_gain| + "), SIGN_RULE("force", "accel_x", ""),
    SIGN_RULE("force", "accel_y", ""),                SIGN_RULE("force", "accel_z", "")};
static const char *const ADD_REASON[6] = {GYRO_ADD_RULE("gyro_x"),   GYRO_ADD_RULE("gyro_y"),
                                          GYRO_ADD_RULE("gyro_z"),   ACCEL_ADD_RULE("accel_x"),
                                          ACCEL_ADD_RULE("accel_y"), ACCEL_ADD_RULE("accel_z")};

/* The sums of sensor j (gyro x y z, accel x y z): sign, additive, white noise, rate hysteresis and its
 * temperature coefficient; n written to *count. */
static int sensor_sums(const double *par, double f, int j, Sum *out) {
    int t = j / 3, i = j % 3;
    double full = t == 0 ? sarins_imu_max_rate(f) : SARINS_IMU_ACCEL_FULL_SCALE;
    double e = SARINS_IMU_TEMP_EXCURSION, rate = temp_rate(par, f, j);
    int mis = t == 0 ? SARINS_IMU_P_GYRO_MISALIGNMENT_XY : SARINS_IMU_P_ACCEL_MISALIGNMENT_XY;
    int n = 0;
    Sum *s = &out[n++];
    *s = (Sum){1.0, 0, {0}, {0}, SIGN_REASON[j]};
    term(s, TP(SARINS_IMU_P_GYRO_SCALE_FACTOR_X, t, i), 1.0);
    term(s, TP(SARINS_IMU_P_GYRO_SCALE_FACTOR_TC_X, t, i), e);
    term(s, TP(SARINS_IMU_P_GYRO_SCALE_FACTOR_DTDT_X, t, i), rate);
    for (int k = 0; k < 6; k++) {
        if (MISALIGNMENT[k][0] == i) term(s, mis + k, 1.0);
    }
    if (t == 0) term(s, LOWRATE_GAIN[i], 1.0);
    term(s, TP(SARINS_IMU_P_GYRO_QUADRATIC_X, t, i), full);
    if (t == 0) {
        s = &out[n++];
        *s = (Sum){0.5 * PI * f, 0, {0}, {0}, "must be at most pi/2 rad per minor step in magnitude "
                   "(|bias| <= pi/2 x internal_rate)"};
        term(s, TP(SARINS_IMU_P_GYRO_BIAS_X, t, i), 1.0);
    }
    s = &out[n++];
    *s = (Sum){t == 0 ? 0.75 * PI * f : SARINS_IMU_OUTPUT_MARGIN * full, 0, {0}, {0}, ADD_REASON[j]};
    static const int UNIT[] = {SARINS_IMU_P_GYRO_BIAS_X, SARINS_IMU_P_GYRO_HYSTERESIS_X};
    static const int SIGMA[] = {SARINS_IMU_P_GYRO_BIAS_INSTABILITY_X, SARINS_IMU_P_GYRO_TURN_ON_BIAS_X};
    for (int k = 0; k < 2; k++) term(s, TP(UNIT[k], t, i), 1.0);
    for (int k = 0; k < 2; k++) term(s, TP(SIGMA[k], t, i), SARINS_IMU_SIGMAS);
    term(s, TP(SARINS_IMU_P_GYRO_BIAS_TC1_X, t, i), e);
    term(s, TP(SARINS_IMU_P_GYRO_BIAS_TC2_X, t, i), e * e);
    term(s, TP(SARINS_IMU_P_GYRO_BIAS_DTDT_X, t, i), rate);
    term(s, TP(SARINS_IMU_P_GYRO_FLICKER_X, t, i), flicker_scale(par));
    term(s, TP(SARINS_IMU_P_GYRO_RATE_RANDOM_WALK_X, t, i), SARINS_IMU_SIGMAS * sm_sqrt(SARINS_IMU_RRW_TIME));
    term(s, PERIODIC_AMPLITUDE(j), 1.0); /* |A sin(2 pi f t + phi)| <= A */
    if (t == 0) {
        for (int c = 0; c < 3; c++) term(s, SARINS_IMU_P_G_SENSITIVITY_XX + 3 * i + c, SARINS_IMU_ACCEL_FULL_SCALE);
    }
    if (j == 2) { /* eps(T) = (a T + b) T + c and the azimuth gyro's thermal terms */
        double ta = SARINS_IMU_TEMP_ABS;
        const double powers[3] = {ta * ta, ta, 1.0};
        for (int k = 0; k < 3; k++) {
            term(s, DRIFT[k], powers[k]);
            term(s, AGING[k], SARINS_IMU_SIGMAS * powers[k]);
        }
        term(s, SARINS_IMU_P_AXIAL_DRIFT_DTDT, rate);
        term(s, SARINS_IMU_P_AXIAL_DRIFT_GRAD, SARINS_IMU_TEMP_SPAN);
        term(s, SARINS_IMU_P_AXIAL_HYSTERESIS, 1.0);
    }
    s = &out[n++];
    *s = (Sum){SARINS_IMU_OUTPUT_MARGIN * full, 0, {0}, {0}, "one output sample's noise std, random_walk "
               "sqrt(internal_rate), <= 1e6 x full scale"};
    term(s, TP(SARINS_IMU_P_GYRO_RANDOM_WALK_X, t, i), sm_sqrt(f));
    s = &out[n++]; /* before the amplitude, whose scale holds it */
    *s = (Sum){SARINS_IMU_OUTPUT_MARGIN, 0, {0}, {0}, "the rate hysteresis gain changes by at most 1e6 over the "
               "temperatures: |rate_hysteresis_tc| 975 degC <= 1e6 (dynamics.h)"};
    term(s, TP(SARINS_IMU_P_GYRO_RATE_HYSTERESIS_TC_X, t, i), e);
    double tc = par[TP(SARINS_IMU_P_GYRO_RATE_HYSTERESIS_TC_X, t, i)];
    s = &out[n++];
    *s = (Sum){SARINS_IMU_OUTPUT_MARGIN * full, 0, {0}, {0}, "the rate hysteresis at 975 degC from 25, |c| "
               "(1 + |rate_hysteresis_tc| 975 degC), <= 1e6 x full scale (dynamics.h)"};
    term(s, TP(SARINS_IMU_P_GYRO_RATE_HYSTERESIS_X, t, i), 1.0 + sm_fabs(tc) * e);
    if (t == 1) { /* accelerometer i's lever arm: the size effect at the largest measured rate */
        s = &out[n++];
        *s = (Sum){SARINS_IMU_OUTPUT_MARGIN * full, 0, {0}, {0}, "the size effect at pi rad per minor step on "
                   "each axis, |r| (3 pi^2 + 2 sqrt(3) pi) internal_rate^2, <= 1e6 x full scale (dynamics.h)"};
        for (int c = 0; c < 3; c++)
            term(s, SARINS_IMU_P_ACCEL_LEVER_ARM_XX + 3 * i + c, (3.0 * PI * PI + 2.0 * SQRT3 * PI) * f * f);
    }
    /* the sensor's thermal and die time constants: slope x tau in the exact steps (thermal.h) finite */
    static const int TIMES[2] = {SARINS_IMU_P_TIME_CONSTANT_GYRO_X, SARINS_IMU_P_DIE_TIME_CONSTANT_GYRO_X};
    for (int k = 0; k < 2; k++) {
        s = &out[n++];
        *s = (Sum){0.25 * DBL_MAX, 0, {0}, {0}, "the exact thermal step's slope x time constant stays finite: "
                   "1773.15 degC x internal_rate x tau <= DBL_MAX / 4 (thermal.h)"};
        term(s, SP(TIMES[k], j), SARINS_IMU_TEMP_SPAN * f);
    }
    return n;
}

#define MAX_SUMS (6 * 9 + 1)

/* Every sum of the parameter vector at the minor-loop rate f; their count. */
static int all_sums(const double *par, double f, Sum *sums) {
    int n = 0;
    for (int j = 0; j < 6; j++) n += sensor_sums(par, f, j, sums + n);
    Sum *s = &sums[n++];
    *s = (Sum){0.25 * DBL_MAX, 0, {0}, {0}, "the exact thermal step's slope x time constant stays finite: "
               "1773.15 degC x internal_rate x tau <= DBL_MAX / 4 (thermal.h)"};
    term(s, SARINS_IMU_P_AXIAL_BLOCK_TIME_CONSTANT, SARINS_IMU_TEMP_SPAN * f);
    return n;
}

/* The bound of term k of sum s: (capacity - the other terms) / its scale, at least 0. */
static double term_bound(const Sum *s, const double *par, int k) {
    double others = 0.0;
    for (int m = 0; m < s->n; m++) {
        if (m != k) others += s->scale[m] * sm_fabs(par[s->index[m]]);
    }
    double room = (s->capacity - others) / s->scale[k];
    return room > 0.0 ? room : 0.0;
}

int sarins_imu_param_bound(const double *par, double internal_rate, int64_t i, double *bound, const char **reason) {
    Sum sums[MAX_SUMS];
    int n = all_sums(par, internal_rate, sums), found = 0;
    for (int r = 0; r < n; r++) {
        for (int k = 0; k < sums[r].n; k++) {
            if (sums[r].index[k] != i) continue;
            double b = term_bound(&sums[r], par, k);
            if (!found || b < *bound) {
                *bound = b;
                *reason = sums[r].reason;
            }
            found = 1;
        }
    }
    return found;
}

int64_t sarins_imu_check_rate_params(const double *par, double internal_rate, double *bound, const char **reason) {
    /* a lower bound: the low-rate term divides the minor increment e by dt w (imu.c minor_terms); dt w must be
       a normal double, else e / (dt w) is 0/0 (NaN) for e = 0 (measured: lowrate_width 5e-324 at 200 Hz) */
    for (int i = 0; i < 3; i++) {
        if (!(par[LOWRATE_WIDTH[i]] / internal_rate >= DBL_MIN)) {
            *bound = DBL_MIN * internal_rate;
            *reason = LOWER_BOUND "the minor step dt = 1 / internal_rate times lowrate_width must be a normal "
                      "double (>= DBL_MIN), else e / (dt w) in the low-rate term is 0/0 (imu.c minor_terms)";
            return LOWRATE_WIDTH[i];
        }
    }
    Sum sums[MAX_SUMS];
    int n = all_sums(par, internal_rate, sums);
    for (int r = 0; r < n; r++) {
        /* the largest term: over the capacity exactly when the sum is (to rounding) */
        const Sum *s = &sums[r];
        int top = 0;
        for (int k = 1; k < s->n; k++) {
            if (s->scale[k] * sm_fabs(par[s->index[k]]) > s->scale[top] * sm_fabs(par[s->index[top]])) top = k;
        }
        double b = term_bound(s, par, top);
        if (!(sm_fabs(par[s->index[top]]) <= b)) {
            *bound = b;
            *reason = s->reason;
            return s->index[top];
        }
    }
    return -1;
}

int64_t sarins_imu_check_periodic_params(const double *par, double internal_rate, const char **reason) {
    for (int j = 0; j < 6; j++) { /* f <= internal_rate / 2 */
        if (!(par[PERIODIC_FREQUENCY(j)] <= 0.5 * internal_rate)) {
            *reason = "must be at most the Nyquist frequency of the minor loop, internal_rate / 2";
            return PERIODIC_FREQUENCY(j);
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
        *dyn_par, *dyn_state, *periodic;
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
    a->periodic = row_array(table, SARINS_IMU_PERIODIC, 3, 6);
    double *all[] = {a->consts, a->clock, a->sensor_par, a->state, a->coef, a->triad, a->mats, a->corr_par,
                     a->corr_state, a->phi, a->q, a->x_flicker, a->dyn_par, a->dyn_state, a->periodic};
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
    double bound;
    if (par == NULL || sarins_imu_check_params(par, &reason) >= 0) return SARINS_IMU_BAD_TABLE;
    if (!(h > 0.0 && h < INFINITY && n_sub >= 1 && n_sub <= SARINS_IMU_MAX_SUB && isfinite(t0) && age >= 0.0 && age < INFINITY))
        return SARINS_IMU_BAD_TABLE;
    if (sarins_imu_check_rate_params(par, (double)n_sub / h, &bound, &reason) >= 0) return SARINS_IMU_BAD_TABLE;
    if (sarins_imu_check_periodic_params(par, (double)n_sub / h, &reason) >= 0) return SARINS_IMU_BAD_TABLE;
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
    /* periodic: amplitude, frequency (row 2, the phase, is drawn at seeding) */
    for (int j = 0; j < 6; j++) {
        a.periodic[j] = par[PERIODIC_AMPLITUDE(j)];
        a.periodic[6 + j] = par[PERIODIC_FREQUENCY(j)];
    }
    return SARINS_IMU_OK;
}

int sarins_imu_start(const int64_t *table, int64_t rows, double ambient0, int hot, uint64_t seed) {
    if (table == NULL || rows < SARINS_IMU_N_ARRAYS || !(ambient0 >= -273.15 && ambient0 <= SARINS_IMU_AMBIENT_MAX))
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
