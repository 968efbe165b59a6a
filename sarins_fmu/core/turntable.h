/* Gimbal-chain motion truth of a piecewise-constant-acceleration schedule.
 *
 * Angles rad, rates rad/s, accelerations rad/s^2, times s.  A schedule of
 * A gimbals and M segments is given by its breakpoint tables (as
 * sarins_fmu.turntable.GimbalSchedule.tables()): times (M+1) strictly
 * increasing; angle_bp, rate_bp (M+1, A) the state at each breakpoint;
 * accel (M, A) the acceleration on [times[m], times[m+1]); angle0, rate0 (A)
 * the state at times[0].  Arrays are row-major.
 */
#ifndef SARINS_TURNTABLE_H
#define SARINS_TURNTABLE_H

#include <stdint.h>

/* State at the n times t (any order):
 *   before times[0]:  angle = angle0 + rate0 (t - t0), rate = rate0, acc = 0;
 *   in segment s:     tau = t - times[s], a = accel[s] (0 after the last breakpoint),
 *                     angle = angle_bp[s] + rate_bp[s] tau + a tau^2 / 2, rate = rate_bp[s] + a tau.
 * The acceleration written is the one holding on [t, next breakpoint).
 * Writes angle, rate, acc (n, A). */
void sarins_turntable_state(int64_t n, const double *t, int64_t n_times, int64_t n_axes, const double *times,
                            const double *angle_bp, const double *rate_bp, const double *accel,
                            const double *angle0, const double *rate0, double *angle, double *rate, double *acc);

#endif
