/* The stop Kalman filter of seed 002 as one state struct: its settings, its state and covariance, and
 * what it keeps of the stop (the Python face is sarins_fmu/kalman.py, StopKalmanFilter).
 *
 * The filter step itself is sarins_stop_filter_steps (filter.h: 11 states phi_E, phi_N, phi_U, dv_E,
 * dv_N, eps_x, eps_y, eps_z, nabla_x, nabla_y, d_lat; measurement z = INS east/north velocity at rest).
 * This file adds its initial covariance P0 = diag(std^2) and continuous process noise q = diag(noise^2)
 * from the settings, the reset at the start of a stop, and the stop's record: rows since the reset, the
 * running sums (added row by row) of the azimuth drift compensation the INS applied and of the azimuth
 * gyro temperature, from which the stop's drift measurement eps_U = mean compensation + eps_z estimate
 * and its temperature T_gz follow.
 *
 * Units: rad, rad/s, m/s, m/s^2, m, s, degC.  Functions that can fail return SARINS_STOP_OK or
 * SARINS_STOP_BAD with a one-line reason in msg (size bytes; msg may be NULL).  libm: sqrt (and what
 * sarins_stop_filter_steps uses: sin, cos, tan, sqrt).
 */
#ifndef SARINS_STOP_FILTER_H
#define SARINS_STOP_FILTER_H

#include <stddef.h>
#include <stdint.h>

#include "filter.h"

#define SARINS_STOP_OK 0
#define SARINS_STOP_BAD 1
#define SARINS_STOP_LAT_LIMIT (89.9 * (3.141592653589793 / 180.0)) /* rad: the largest latitude, 89.9 deg */

/* Settings, in this order (the fields of sarins_fmu.kalman.StopFilterSettings): arw rad/sqrt(s), vrw
 * m/s/sqrt(s), drift_rw rad/s/sqrt(s), bias_rw m/s^2/sqrt(s), velocity_meas_std m/s, tilt0_std rad,
 * heading0_std rad, velocity0_std m/s, drift0_std rad/s, azimuth_drift0_std rad/s, bias0_std m/s^2,
 * position0_std m.  Every one positive and finite. */
enum {
    SARINS_STOP_ARW, SARINS_STOP_VRW, SARINS_STOP_DRIFT_RW, SARINS_STOP_BIAS_RW, SARINS_STOP_VELOCITY_MEAS_STD,
    SARINS_STOP_TILT0_STD, SARINS_STOP_HEADING0_STD, SARINS_STOP_VELOCITY0_STD, SARINS_STOP_DRIFT0_STD,
    SARINS_STOP_AZIMUTH_DRIFT0_STD, SARINS_STOP_BIAS0_STD, SARINS_STOP_POSITION0_STD, SARINS_STOP_N_SETTINGS
};

typedef struct {
    double settings[SARINS_STOP_N_SETTINGS];
    double lat;                           /* rad, of the stop */
    double dt;                            /* s, the measurement interval */
    double q[SARINS_STOP_STATES];         /* continuous process-noise densities (settings squared) */
    double r_var;                         /* velocity measurement variance, (m/s)^2 */
    double x[SARINS_STOP_STATES];         /* state estimate */
    double p[SARINS_STOP_STATES * SARINS_STOP_STATES]; /* its covariance, row-major */
    int64_t n;                            /* rows since the reset */
    double correction_sum;                /* rad/s: sum of the compensations of those rows */
    double temperature_sum;               /* degC: sum of their temperatures (NaN if one was not given) */
} sarins_stop_kf;

/* The default settings (StopFilterSettings()): written into settings (SARINS_STOP_N_SETTINGS values). */
void sarins_stop_settings_default(double *settings);

/* Checks settings (SARINS_STOP_N_SETTINGS values), a latitude (finite, within +-89.9 deg) and a step. */
int sarins_stop_check_settings(const double *settings, char *msg, size_t size);
int sarins_stop_check_lat_dt(double lat, double dt, char *msg, size_t size);

/* A filter with these settings at latitude lat (rad) and step dt (s), reset. */
int sarins_stop_kf_init(sarins_stop_kf *kf, const double *settings, double lat, double dt, char *msg,
                        size_t size);

/* A new stop at latitude lat (rad; checked, kept on failure): state 0, covariance P0, record cleared. */
int sarins_stop_kf_reset(sarins_stop_kf *kf, double lat, char *msg, size_t size);

/* K rows of the stop: velocity_en (K,2) m/s and attitude (K,3) yaw, pitch, roll rad of the INS at the end
 * of each step, correction (K) rad/s the azimuth drift the INS subtracted, temperature (K) degC (may be
 * NaN: then the mean temperature is NaN).  Refused, with nothing changed, if a velocity, attitude or
 * correction is not finite.  out (K,2), may be NULL: the eps_z estimate and its standard deviation after
 * each row, rad/s. */
int sarins_stop_kf_steps(sarins_stop_kf *kf, int64_t k, const double *velocity_en, const double *attitude,
                         const double *correction, const double *temperature, double *out, char *msg,
                         size_t size);

double sarins_stop_kf_elapsed(const sarins_stop_kf *kf);        /* s: n dt */
double sarins_stop_kf_residual(const sarins_stop_kf *kf);       /* rad/s: the eps_z estimate */
double sarins_stop_kf_drift_std(const sarins_stop_kf *kf);      /* rad/s: its filter standard deviation */
double sarins_stop_kf_drift_estimate(const sarins_stop_kf *kf); /* rad/s: mean correction + eps_z (0 + eps_z
                                                                 * before the first row) */
double sarins_stop_kf_mean_temperature(const sarins_stop_kf *kf); /* degC, NaN before the first row */

/* Every field within the invariants the functions above keep (settings valid, q and r_var their squares,
 * latitude and step valid, x and p finite with p's diagonal >= 0, n >= 0, correction_sum finite,
 * temperature_sum finite or NaN): for a state that arrived from outside. */
int sarins_stop_kf_check(const sarins_stop_kf *kf, char *msg, size_t size);

/* sizeof(sarins_stop_kf) and the byte offsets of settings, lat, dt, x, p, n, correction_sum,
 * temperature_sum in offsets[0..7] (for the Python binding). */
int64_t sarins_stop_kf_layout(int64_t *offsets);

#endif
