/* The IMU built from its flat parameters (imu_params.h; sarins_fmu/imu_params.py), in C: the parameter
 * checks of sarins_fmu.imu.ImuModel / TriadErrors / sarins_fmu.thermal.ThermalParams, the constant
 * arrays of the IMU table (imu.h, sarins_fmu/imu_step.py) and the start of a run.  The Python IMU and a
 * native FMU build the same table with these functions.
 *
 * Units: SI as in imu_params.h (rad, rad/s, m/s^2, s, degC). */
#ifndef SARINS_IMU_BUILD_H
#define SARINS_IMU_BUILD_H

#include <stdint.h>

#include "imu_params.h"

#define SARINS_IMU_FLICKER_PER_DECADE 3 /* Gauss-Markov terms per decade of the flicker synthesis */
#define SARINS_IMU_FLICKER_MAX_RATIO 4503599627370496.0 /* 2^52 = 1/DBL_EPSILON: widest flicker band tau_max/tau_min */
#define SARINS_IMU_SELF_HEATING_LIMIT 500.0 /* degC: a sensor's self-heating rise above the ambient, in magnitude */
#define SARINS_IMU_DAY 86400.0         /* s */

/* The envelope the parameter bounds are derived for (sarins_imu_param_bound):
 *   ambient      -273.15 .. SARINS_IMU_AMBIENT_MAX degC (a higher ambient is refused by the step);
 *   temperatures a sensor or its die reaches: the ambient plus a self-heating within
 *                +-SARINS_IMU_SELF_HEATING_LIMIT (the thermal model's exact step stays between its start and
 *                ambient + self-heating), so T in [-773.15, 1000] degC: |T| <= SARINS_IMU_TEMP_ABS,
 *                |T - SARINS_IMU_T_REF| <= SARINS_IMU_TEMP_EXCURSION, a change of at most SARINS_IMU_TEMP_SPAN;
 *   rates        sarins_imu_max_rate(internal_rate) per body axis (the gyro's full scale, <= pi/8 rad per minor step);
 *   forces       SARINS_IMU_ACCEL_FULL_SCALE per body axis (the accelerometer's full scale). */
#define SARINS_IMU_AMBIENT_MAX 500.0      /* degC: the highest ambient the IMU accepts */
#define SARINS_IMU_TEMP_ABS 1000.0        /* degC: AMBIENT_MAX + SELF_HEATING_LIMIT */
#define SARINS_IMU_TEMP_EXCURSION 975.0   /* degC: TEMP_ABS - T_REF (> T_REF - (-273.15 - 500)) */
#define SARINS_IMU_TEMP_SPAN 1773.15      /* degC: TEMP_ABS - (-273.15 - SELF_HEATING_LIMIT) */
#define SARINS_IMU_ACCEL_FULL_SCALE 980.665 /* m/s^2: 100 g */
#define SARINS_IMU_GYRO_FULL_SCALE 100.0  /* rad/s (5730 deg/s, above any MEMS range): the rate cap at high internal rates */
#define SARINS_IMU_OUTPUT_MARGIN 1e6      /* an error term that only adds to the outputs: at most this x full scale */
#define SARINS_IMU_SIGMAS 8.0             /* a random term's excursion: this many standard deviations */
#define SARINS_IMU_RRW_TIME (365.0 * SARINS_IMU_DAY) /* s: a rate random walk's excursion over a year's run */

/* Number of flicker terms F for the band [tau_min, tau_max] (s): max(2, ceil(3 log10(tau_max /
 * tau_min)) + 1); 0 when the band is not 0 < tau_min < tau_max < inf. */
int64_t sarins_imu_flicker_count(double tau_min, double tau_max);

/* The F correlation times (s), log-spaced from tau_min to tau_max (both exactly): tau_i =
 * 10^(log10 tau_min + i (log10 tau_max - log10 tau_min) / (F - 1)). */
void sarins_imu_flicker_taus(double tau_min, double tau_max, int64_t n, double *taus);

/* Check a parameter vector par[SARINS_IMU_N_PARAMS]: -1 when it is a valid IMU model, else the index of
 * the first parameter at fault, with *reason the rule it breaks ("must be finite", "must be positive",
 * ...; static text). */
int64_t sarins_imu_check_params(const double *par, const char **reason);

/* The largest body rate per axis the model supports at the minor-loop rate internal_rate (Hz), rad/s: pi/8 rad
 * per minor step, (pi / 8) internal_rate, at most SARINS_IMU_GYRO_FULL_SCALE (the gyro's full scale; the error
 * terms take the rest of the pi rad a minor step's rotation vector may turn, sarins_imu_param_bound). */
double sarins_imu_max_rate(double internal_rate);

/* The bound on |par[i]| that the parameter checks apply at the minor-loop rate internal_rate (Hz, > 0), the
 * other parameters as in par (checked by sarins_imu_check_params first): 1 with *bound (>= 0, in the unit of
 * the parameter) and *reason (static text: the rule it comes from), or 0 when par[i] has no magnitude bound.
 * Every bound keeps a sum of error terms, each at its largest over the envelope above, within a capacity:
 *   sign      per sensor, |sf| + |sf_tc| E + |sf_dtdt| R + |misalignment row| + |lowrate_gain| + |quadratic| S
 *             <= 1 (imu.h step 3: the sensed x is (1 + those) x, so its sign does not flip and it stays within
 *             2 x the true value; E the temperature excursion, R = SPAN / max(time constant, 1 / internal_rate)
 *             the largest temperature rate, S the full scale);
 *   gyro bias |bias| <= (pi / 2) internal_rate: a quarter turn per minor step (measured: 1e3 rad/s at 200 Hz,
 *             5 rad per step, turned the increments NaN within three steps);
 *   gyro sum  per gyro, the additive terms (bias, tc1 E, tc2 E^2, bias_dtdt R, hysteresis, g-sensitivity row x
 *             the accelerometer full scale, 8 sigma of the Gauss-Markov, flicker, turn-on, a year's rate
 *             random walk, the periodic amplitude; the z gyro also a TEMP_ABS^2 + b TEMP_ABS + c (imu.h eps(T)),
 *             8 sigma of their ageing, axial_drift_dtdt R, axial_drift_grad SPAN, axial_hysteresis) <= (3 pi / 4)
 *             internal_rate: with the true rate (pi / 8 per step) times at most 2, a minor step's rotation
 *             vector stays below pi rad, where it is unique and the coning series (imu.c scull_cone) keeps the
 *             quaternion's norm (measured: 5 rad per step overflows it within a second);
 *   accel sum per accelerometer, the same additive terms <= OUTPUT_MARGIN x ACCEL_FULL_SCALE;
 *   outputs   random walk sqrt(internal_rate) (the std of one sample) and rate hysteresis (1 + |tc| E) <=
 *             OUTPUT_MARGIN x full scale; |rate_hysteresis_tc| E <= OUTPUT_MARGIN; the lever arm row sum x
 *             (3 pi^2 + 2 sqrt(3) pi) internal_rate^2 (the size effect at the largest measured rate and
 *             angular acceleration, dynamics.h) <= OUTPUT_MARGIN x ACCEL_FULL_SCALE;
 *   times     a time constant tau (thermal, die, block) with SPAN internal_rate tau <= DBL_MAX / 4: the exact
 *             step's slope x tau (thermal.h) stays finite. */
int sarins_imu_param_bound(const double *par, double internal_rate, int64_t i, double *bound, const char **reason);

/* Check the bounds of sarins_imu_param_bound at the minor-loop rate internal_rate (Hz, > 0): -1 when they
 * hold, else the index of the parameter at fault (of a sum that exceeds its capacity: its largest term),
 * with *bound its bound and *reason the rule (static text).  A reason that starts with SARINS_IMU_LOWER_BOUND
 * makes *bound a lower bound on the value (lowrate_width >= DBL_MIN internal_rate). */
#define SARINS_IMU_LOWER_BOUND "at least: "
int64_t sarins_imu_check_rate_params(const double *par, double internal_rate, double *bound, const char **reason);

/* Check the periodic terms' frequencies against the minor-loop rate internal_rate (Hz, > 0): -1 when they hold,
 * else the index of the first at fault with *reason (static text).  A frequency f (Hz) is at most the minor
 * loop's Nyquist frequency, f <= internal_rate / 2: the sensor's own sampling resolves it.  The output interval
 * may be longer (f above its Nyquist frequency): the increments are the sinusoid's exact integrals over it,
 * which is what an integrating sensor outputs (their sequence aliases, as a real unit's does). */
int64_t sarins_imu_check_periodic_params(const double *par, double internal_rate, const char **reason);

/* Fill the constant arrays of the IMU table (imu.h rows CONSTS, SENSOR_PAR, COEF, TRIAD, MATS, CORR_PAR
 * rows 0-5 and 7, PHI, Q, DYN_PAR, PERIODIC rows 0-1; the PHI/Q/X_FLICKER rows must have
 * sarins_imu_flicker_count rows) from par, checked first (sarins_imu_check_params and
 * sarins_imu_check_periodic_params at n_sub / h): t0 the start time (s), h the output interval (s, > 0), n_sub minor
 * steps per interval (1 to SARINS_IMU_MAX_SUB);
 * the azimuth-drift coefficients aged by age (s; 0: not aged) with the AGEING stream of seed when an
 * ageing std is not zero.  The table's AXES and BASE rows are the caller's.  Returns SARINS_IMU_OK or
 * SARINS_IMU_BAD_TABLE (a bad parameter vector, h or n_sub, or a table of other shapes; nothing written). */
int sarins_imu_build(const int64_t *table, int64_t rows, const double *par, double t0, double h, int64_t n_sub,
                     double age, uint64_t seed);

/* Start a run of a built table: clock (0, ambient0), reported temperatures ambient0 (+ the self-heating
 * when hot), the die at them, the play operators relaxed, the z gyro's block node and play operator
 * (state row 2, sarins_imu_axial_thermal_terms) at its temperature, the rate random walks and the flicker
 * states at 0, the output dynamics (DYN_STATE, dynamics.h) at rest, then sarins_imu_seed(seed) (which also
 * draws the periodic terms' phases).  ambient0 degC, finite and above -273.15 (else SARINS_IMU_BAD_TABLE,
 * nothing written). */
int sarins_imu_start(const int64_t *table, int64_t rows, double ambient0, int hot, uint64_t seed);

#endif
