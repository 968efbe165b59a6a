/* Errors of the aided runs' IMU (sarins_fmu.aided.ImuNoise), added to ideal increments step by step.
 *
 * Per axis, over IMU step k of length h (s), with n ~ N(0, 1) independent draws:
 *     dtheta_k = dtheta_true,k + b_g,k h + arw (sqrt(h) n)       (rad; arw rad/sqrt(s))
 *     dv_k     = dv_true,k     + b_a,k h + vrw (sqrt(h) n)       (m/s; vrw m/s/sqrt(s))
 *     b_{k+1}  = b_k + rw (sqrt(h) n)                            (gyro_rw rad/s/sqrt(s), accel_rw m/s^2/sqrt(s))
 *     b_0      = bias_std n                                      (per-seed constant part, rad/s, m/s^2)
 * Draws come from the core's stream SARINS_AIDED_IMU_STREAM of the seed (rng.h): six for b_0 (gyro x y z,
 * accelerometer x y z) at initialisation, then per step six white (gyro, accelerometer) and six walk
 * draws, in that order.  A run made in pieces of any length (the FMU, one step at a time) draws the same
 * numbers as one batch run (the in-process path), so both give the same increments bit for bit.
 * Body frame right-front-up; SI units.
 */
#ifndef SARINS_AIDED_IMU_H
#define SARINS_AIDED_IMU_H

#include <stddef.h>
#include <stdint.h>

#include "rng.h"

#define SARINS_AIDED_IMU_STREAM 32 /* stream id of the aided IMU's errors (gnss.h uses 30, odo.h 31) */

/* noise settings (SI), in this order */
enum { SARINS_AIDED_IMU_ARW, SARINS_AIDED_IMU_VRW, SARINS_AIDED_IMU_GYRO_BIAS_STD, SARINS_AIDED_IMU_ACCEL_BIAS_STD,
       SARINS_AIDED_IMU_GYRO_RW, SARINS_AIDED_IMU_ACCEL_RW, SARINS_AIDED_IMU_CONFIG };

typedef struct {
    double config[SARINS_AIDED_IMU_CONFIG];
    double step;    /* h, s */
    double sqrt_h;  /* sqrt(h) */
    double bias[6]; /* b_k: gyro x y z (rad/s), accelerometer x y z (m/s^2), the bias of the next step */
    SarinsRng rng;
    int64_t steps;  /* steps made */
} sarins_aided_imu;

/* Initialise for step h (s) and seed; draws b_0.  0, or 1 with a reason in msg for a setting that is not a
 * finite number >= 0 or a step that is not positive and finite. */
int sarins_aided_imu_init(sarins_aided_imu *s, const double *config, double step, uint64_t seed, char *msg,
                          size_t size);

/* One step: the ideal increments dtheta_true, dv_true (3 each) in, the measured ones out (3 each, may be
 * the same arrays); bias (6, may be NULL) receives b_k, the biases over this step. */
void sarins_aided_imu_step(sarins_aided_imu *s, const double *dtheta_true, const double *dv_true, double *dtheta,
                           double *dv, double *bias);

/* n steps of the ideal increments (n, 3) each: measured increments (n, 3) and biases (n, 6).  0, or 1 as
 * sarins_aided_imu_init (nothing written). */
int sarins_aided_imu_run(const double *config, double step, uint64_t seed, int64_t n, const double *dtheta_true,
                         const double *dv_true, double *dtheta, double *dv, double *bias);

/* 0 when s is a state init and step can make (settings, step, a finite bias, an odd random-stream
 * increment, a spare flag 0/1 and a finite spare, steps >= 0), else 1 with a reason in msg. */
int sarins_aided_imu_check(const sarins_aided_imu *s, char *msg, size_t size);

#endif
