/* The jitter of the zero-velocity (ZUPT) and non-holonomic (NHC) pseudo-measurements, and the stillness of a
 * trajectory step: the per-step aiding rows of sarins_eskf_aid (eskf.h) that the TrajectoryIMU FMU outputs and
 * sarins_fmu.aided.navigate(..., imu_stream="core") applies.
 *
 * A trajectory has no side-slip or bounce, so the pseudo-measurements carry simulated white jitter of the std
 * the filter assumes.  Over IMU step k (the interval [t_k, t_k+1]), with z, w the flags (0 or 1) and
 * n_k1 .. n_k5 ~ N(0, 1):
 *     zupt velocity (E, N, U, m/s)      = (z zupt_std) n_k1, (z zupt_std) n_k2, (z zupt_std) n_k3
 *     nhc velocity (body x, z, m/s)     = (w nhc_std) n_k4, (w nhc_std) n_k5
 * The draws come from the core's stream SARINS_AID_NOISE_STREAM of the seed (rng.h): exactly five normals per
 * step in that order, whether or not a flag is set, so the values of step k depend only on (seed, k), and a
 * run made in pieces (the FMU, one step at a time) draws the numbers of one batch run bit for bit.
 *
 * Stillness: step k is still when the speed |v^n| (ENU, m/s, the norm sqrt((v_E^2 + v_N^2) + v_U^2)) at both
 * of its ends is below SARINS_AID_STILL_SPEED: the steps a zero-velocity update is true on
 * (sarins_fmu.trajectory.Truth.stationary).
 */
#ifndef SARINS_AID_NOISE_H
#define SARINS_AID_NOISE_H

#include <stddef.h>
#include <stdint.h>

#include "rng.h"

#define SARINS_AID_NOISE_STREAM 33  /* stream id (gnss.h uses 30, odo.h 31, aided_imu.h 32) */
#define SARINS_AID_NOISE_DRAWS 5    /* normals drawn per step */
#define SARINS_AID_STILL_SPEED 1e-9 /* m/s: below it at both ends of a step the vehicle stands still */

typedef struct {
    double zupt_std; /* m/s, per ENU axis */
    double nhc_std;  /* m/s, body x and z */
    SarinsRng rng;
    int64_t steps;   /* steps drawn */
} sarins_aid_noise;

/* Initialise: the stds (finite, >= 0) and the seed.  0, or 1 with a reason in msg. */
int sarins_aid_noise_init(sarins_aid_noise *s, double zupt_std, double nhc_std, uint64_t seed, char *msg,
                          size_t size);

/* One step: draws five normals; out (5) = ZUPT velocity E, N, U, NHC velocity body x, z for the flags zupt and
 * nhc (0 or 1; a value of a flag 0 is zero, with the sign of its draw). */
void sarins_aid_noise_step(sarins_aid_noise *s, int zupt, int nhc, double *out);

/* n steps: flags zupt (n) and nhc (n) (0 or 1), out (n, 5).  0, or 1 (nothing written) for a std that is not
 * finite and >= 0 or a flag other than 0 or 1. */
int sarins_aid_noise_run(double zupt_std, double nhc_std, uint64_t seed, int64_t n, const int32_t *zupt,
                         const int32_t *nhc, double *out);

/* 0 when s is a state init and step make (stds finite >= 0, a valid stream, steps >= 0), else 1 with msg. */
int sarins_aid_noise_check(const sarins_aid_noise *s, char *msg, size_t size);

/* 1 when the step between the velocities v0 and v1 (3 each, ENU m/s) is still, else 0. */
int sarins_aid_still(const double *v0, const double *v1);

/* 1 when the vehicle moves at the velocity v (3, ENU m/s): its speed is not below SARINS_AID_STILL_SPEED (the
 * points sarins_fmu.zero_velocity.moving_points marks; vibration.h adds its jitter there). */
int sarins_aid_moving(const double *v);

/* The stillness of n steps from n + 1 velocities v (n + 1, 3): out (n) 0 / 1. */
void sarins_aid_still_n(int64_t n, const double *v, int32_t *out);

#endif
