/* Odometer (wheel-speed sensor) model: forward speed with scale-factor error, white noise and
 * quantisation; seeded.
 *
 *     s_meas = q(res, (1 + sf) s_true + sigma n),   q(res, x) = res * round_half_even(x / res) (res > 0),
 *                                                   q(0, x) = x
 * s_true the true forward speed (m/s, body axis y at the odometer), sf the scale-factor error, sigma
 * the white-noise std (m/s), res the speed resolution (m/s; a wheel encoder's distance per pulse over
 * the sampling interval).  Quantisation adds variance res^2 / 12.
 */
#ifndef SARINS_ODO_H
#define SARINS_ODO_H

#include <stddef.h>
#include <stdint.h>

#include "rng.h"

enum { SARINS_ODO_SCALE_FACTOR, SARINS_ODO_NOISE_STD, SARINS_ODO_RESOLUTION, SARINS_ODO_CONFIG };

typedef struct {
    double config[SARINS_ODO_CONFIG];
    SarinsRng rng;
} sarins_odo;

/* 0, or 1 with a reason in msg (a negative std or resolution, |sf| >= 0.5, a non-finite value). */
int sarins_odo_init(sarins_odo *s, const double *config, uint64_t seed, char *msg, size_t size);

/* n measurements of the true speeds speed (n) into out (n); 1 (nothing drawn) for a non-finite speed. */
int sarins_odo_speeds(sarins_odo *s, int64_t n, const double *speed, double *out);

/* Forward speed (m/s, body y) of a velocity v_n (3, ENU m/s) seen from the attitude ypr (3: yaw, pitch, roll,
 * rad; rotations.h mat_nb = Rz(yaw) Rx(pitch) Ry(roll)):
 *     s = (mat_bn v^n)_y = sum_i (mat_nb)_iy v^n_i  (the odometer's true speed, summed in the order i = E, N, U). */
double sarins_odo_forward_speed(const double *v_n, const double *ypr);

/* The same over n rows: v_n (n, 3), ypr (n, 3), out (n). */
void sarins_odo_forward_speed_n(int64_t n, const double *v_n, const double *ypr, double *out);

/* 0 when s is a state sarins_odo_init makes (settings in range, its random stream valid), else 1 with a
 * reason in msg. */
int sarins_odo_check(const sarins_odo *s, char *msg, size_t size);

int64_t sarins_odo_size(void);

#endif
