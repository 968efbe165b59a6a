/* Time-correlated sensor errors (sarins_fmu/imu_correlated.py): thermal
 * gradient, play-operator hysteresis, flicker (sum of F Gauss-Markov terms),
 * rate random walk, turn-on bias.
 *
 * Per output interval k and sensor j (gyro x, y, z, accel x, y, z; rad/s or
 * m/s^2), with T the die temperature at the interval midpoint (degC) and
 * Tdot its rate over the interval (degC/s):
 *     b  += c_g Tdot + c_h (T - P_w[T]) / w + x_flicker + x_rrw + b_on
 *     sf += s_g Tdot
 */
#ifndef SARINS_CORRELATED_H
#define SARINS_CORRELATED_H

#include <stdint.h>

#include "rng.h"

/* Add the terms of K intervals of length h (s) to the (K, 3) gyro and
 * accelerometer bias and scale-factor arrays, in place.
 *
 * die0[6]: die temperatures at the start, die (K, 6) at the interval ends
 * (degC); corr_par (8, 6): die time constant, c_grad, s_grad, c_hyst,
 * w_hyst, rrw, turn-on bias, turn-on std; corr_state (3, 6): die, play
 * operator, x_rrw (play and x_rrw updated); phi[F] flicker decays per
 * interval, q (F, 6) their std, x_flicker (F, 6) their states (updated).
 * Driving noise, drawn interval by interval: flicker_rng 6 F numbers
 * (sensor-major: sensor j's F terms, then sensor j + 1's), rrw_rng 6; NULL
 * for a stream whose terms are all zero (no draw, no noise). */
void sarins_correlated_terms(int64_t n_steps, const double *die0, const double *die, double h,
                             const double *corr_par, double *corr_state, int64_t n_flicker, const double *phi,
                             const double *q, double *x_flicker, SarinsRng *flicker_rng, SarinsRng *rrw_rng,
                             double *g_bias, double *g_sf, double *a_bias, double *a_sf);

#endif
