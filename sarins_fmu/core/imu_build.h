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

/* Check the parameters bounded by the minor-loop rate internal_rate (Hz, > 0): -1 when they hold, else the
 * index of the first at fault with *reason (static text).  A gyro bias b (rad/s) turns the body by
 * b / internal_rate rad per minor step; the minor step's rotation vector is unique only below pi rad, and
 * half of that is left to the table's and the other error terms' rates: |b| <= (pi / 2) internal_rate
 * (measured: 1e3 rad/s at 200 Hz, 5 rad per step, turns the increments NaN within three steps). */
int64_t sarins_imu_check_rate_params(const double *par, double internal_rate, const char **reason);

/* Fill the constant arrays of the IMU table (imu.h rows CONSTS, SENSOR_PAR, COEF, TRIAD, MATS, CORR_PAR
 * rows 0-5 and 7, PHI, Q, DYN_PAR; the PHI/Q/X_FLICKER rows must have sarins_imu_flicker_count rows) from par,
 * checked first: t0 the start time (s), h the output interval (s, > 0), n_sub minor steps per interval
 * (1 to SARINS_IMU_MAX_SUB);
 * the azimuth-drift coefficients aged by age (s; 0: not aged) with the AGEING stream of seed when an
 * ageing std is not zero.  The table's AXES and BASE rows are the caller's.  Returns SARINS_IMU_OK or
 * SARINS_IMU_BAD_TABLE (a bad parameter vector, h or n_sub, or a table of other shapes; nothing written). */
int sarins_imu_build(const int64_t *table, int64_t rows, const double *par, double t0, double h, int64_t n_sub,
                     double age, uint64_t seed);

/* Start a run of a built table: clock (0, ambient0), reported temperatures ambient0 (+ the self-heating
 * when hot), the die at them, the play operators relaxed, the z gyro's block node and play operator
 * (state row 2, sarins_imu_axial_thermal_terms) at its temperature, the rate random walks and the flicker
 * states at 0, the output dynamics (DYN_STATE, dynamics.h) at rest, then sarins_imu_seed(seed).  ambient0 degC, finite and above -273.15 (else SARINS_IMU_BAD_TABLE,
 * nothing written). */
int sarins_imu_start(const int64_t *table, int64_t rows, double ambient0, int hot, uint64_t seed);

#endif
