/* The StrapdownINS FMU's compiled doStep (fine alignment and navigation).
 *
 * int sarins_ins_fmu_step(int64_t *table, int64_t rows, double *buffer, int64_t n, double t, double h)
 * does one whole fmi2DoStep(t, h) of the slave (fmus/strapdown_ins_slave.py)
 * on its Real buffer (n doubles) and returns 0, or returns 1 without having
 * changed anything when it cannot (coarse alignment, the first step, the last
 * fine-alignment step, a new or queued drift compensation, any input or tag
 * the Python do_step would refuse or handle): the Python do_step then runs.
 *
 * Table rows (fmus.compiled_steps.ins_context): 0 q (4), 1 v (3), 2 pos (3),
 * 3 gyro_comp (3), 4 accel_comp (3), 5 steps done (1), 6 io (SARINS_INS_IO),
 * 7 the Compensation state (9), 8 x (9), 9 P (9,9), 10 q_diag (9),
 * 11 P-diagonal history (M,9).
 *
 * io row: expected step, start time, align time, steps of the alignment;
 * slots of the 12 inputs (dtheta_xyz, dv_xyz, increment_end_time,
 * temp_gyro_z, axial_drift_correction c, b, a, axial_drift_apply_from), the
 * 9 navigation outputs, the 5 error outputs, the 4 estimates, the 6 time and
 * temperature outputs (nav_time, temp_azimuth_gyro, temp_align_start,
 * temp_align_end, temp_change_align, solution_time); lat0, lon0 (rad),
 * R_M + h0, R_N + h0 (m), cos(lat0); steps of the coarse alignment, the
 * filter's velocity measurement variance (m/s)^2; the time-tag tolerance
 * (fraction of a step).
 */
#ifndef SARINS_INS_FMU_STEP_H
#define SARINS_INS_FMU_STEP_H

#include <stdint.h>

#define SARINS_INS_IN 4
#define SARINS_INS_N_IN 12
#define SARINS_INS_NAV (SARINS_INS_IN + SARINS_INS_N_IN)
#define SARINS_INS_ERR (SARINS_INS_NAV + 9)
#define SARINS_INS_EST (SARINS_INS_ERR + 5)
#define SARINS_INS_TEMP (SARINS_INS_EST + 4)
#define SARINS_INS_SITE (SARINS_INS_TEMP + 6)
#define SARINS_INS_FILTER (SARINS_INS_SITE + 5)
#define SARINS_INS_TAG_TOL (SARINS_INS_FILTER + 2)
#define SARINS_INS_IO (SARINS_INS_TAG_TOL + 1)
#define SARINS_INS_TABLE_ROWS 12

/* Length of the io row (the binding checks its layout against it). */
int64_t sarins_ins_fmu_io_size(void);

int sarins_ins_fmu_step(int64_t *table, int64_t rows, double *buffer, int64_t n, double t, double h);

#endif
