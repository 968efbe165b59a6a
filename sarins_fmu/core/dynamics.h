/* Sensor dynamics with memory at the output rate (sarins_fmu/imu_dynamics.py):
 * accelerometer size effect, rate hysteresis with relaxation, output low-pass
 * filter.  Applied to the interval means of the six channels after the minor
 * loop's deterministic errors and before the white noise (the datasheets'
 * random walks are specified at the output).
 *
 * Per output interval k of length h (s), channel j (gyro x, y, z in rad/s,
 * accel x, y, z in m/s^2), x_j = dtheta_j / h or dv_j / h:
 *   1. size effect (accelerometers): accel j sits at r_j (m) from the gyro
 *      triad's reference point and measures
 *        x_j += e_j . (alpha x r_j + omega x (omega x r_j)),
 *      omega the interval's gyro means (before the terms below),
 *      alpha = (omega_k - omega_{k-1}) / h (0 in the first interval);
 *   2. hysteresis with relaxation: a play operator of half-width w_j (input
 *      units) on x_j whose state relaxes towards x_j with time constant tau_r,
 *        P <- x + (P - x) exp(-h / tau_r)   (tau_r = 0: no relaxation),
 *        P <- max(x - w, min(x + w, P)),
 *        x += c_j (1 + k_j (T - T_ref)) (x - P) / w,
 *      T the channel's reported temperature at the interval end (degC): a
 *      sweep faster than w / tau_r runs on the +-c branches, a slower one on
 *      a loop c r tau_r / w wide, a held input decays as exp(-t / tau_r);
 *   3. output low-pass: y <- y + a (x - y), x = y, a = h / (h + tau_f): the
 *      first-order recursive filter whose group delay at low frequency is
 *      (1 - a) h / a = tau_f at any output interval (tau_f = 0: none).
 * The first interval starts every state at rest on its input.
 */
#ifndef SARINS_DYNAMICS_H
#define SARINS_DYNAMICS_H

#include <stdint.h>

#define SARINS_DYN_PAR_ROWS 8   /* tau_f, c, w, tau_r, k_T, r_x, r_y, r_z (rows of 6 channels) */
#define SARINS_DYN_STATE_ROWS 4 /* filter output, play operator, previous gyro mean, started (1/0) */

/* 1 when any term of par (SARINS_DYN_PAR_ROWS, 6) is switched on. */
int sarins_dynamics_active(const double *par);

/* Apply the terms to K intervals' dtheta, dv (K, 3) in place; temps (K, 6)
 * reported temperatures at the interval ends (degC); par, state as above
 * (state advanced in place); t_ref the temperature coefficient's reference. */
void sarins_dynamics_apply(int64_t n_steps, double h, const double *temps, const double *par, double *state,
                           double t_ref, double *dtheta, double *dv);

#endif
