/* The Turntable FMU's compiled doStep (constant ambient temperature).
 *
 * int sarins_turntable_fmu_step(int64_t *table, int64_t rows, double *buffer, int64_t n, double t, double h)
 * writes the gimbal state at t + h (angles rad, rates rad/s, accelerations
 * rad/s^2), the constant ambient temperature (degC) and its rate (0) and
 * motion_time = t + h (s) to the slave's Real buffer and returns 0, or
 * returns 1 without having changed anything (another step size, a varying
 * ambient, a bad table): the Python do_step then runs.
 *
 * Table rows (fmus.compiled_steps.turntable_context): the schedule's
 * breakpoint tables 0 times (M+1), 1 angle_bp (M+1,A), 2 rate_bp (M+1,A),
 * 3 accel (M,A), 4 angle0 (A), 5 rate0 (A) (see turntable.h), 6 io
 * (SARINS_TT_IO): expected step, gimbals A (<= 3), constant ambient (1/0),
 * its value, slots of angle_1..3, rate_1..3, accel_1..3, ambient_temp,
 * ambient_temp_rate, motion_time.
 */
#ifndef SARINS_TURNTABLE_FMU_STEP_H
#define SARINS_TURNTABLE_FMU_STEP_H

#include <stdint.h>

#define SARINS_TT_IO 16
#define SARINS_TT_TABLE_ROWS 7

int sarins_turntable_fmu_step(int64_t *table, int64_t rows, double *buffer, int64_t n, double t, double h);

#endif
