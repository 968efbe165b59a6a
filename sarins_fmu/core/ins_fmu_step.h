/* The StrapdownINS FMU's step on one state struct: time-tag checks, the
 * azimuth drift compensation queue and its temperature model, the INS
 * (ins.h) and the outputs.  The native FMU (fmus/c/strapdown_ins/model.c)
 * and the in-process slave (fmus/strapdown_ins_slave.py) call these functions;
 * the struct holds no pointer, so copying its bytes copies the FMU's state.
 *
 * Contract (standard FMI timing, explicit time-tagged latency): the inputs
 * of doStep(t, h) are the IMU's increments of the interval ending at
 * increment_end_time, with the azimuth gyro temperature there.  Each step
 * integrates the interval the tag names, exactly once and in order: the
 * next interval of the grid start_time + k h; a tag equal to the start time
 * before the first interval (Jacobi's first step) waits; a repeated or
 * skipped interval is an error.  Tags equal to TAG_TOL of a step.
 *
 * Azimuth drift compensation (rad/s): eps(T) = (a T + b) T + c with
 * (c, b, a) the inputs axial_drift_correction(_b, _a) (rad/s, rad/s/degC,
 * rad/s/degC^2) and T = temp_gyro_z (degC) of the interval; it is
 * subtracted from the z gyro in every navigation interval that starts at
 * nav time >= its apply_from (input axial_drift_apply_from, s).  Queue
 * semantics: an input pair (value, apply_from) that differs from the last
 * one seen is queued and takes over for the intervals starting at or after
 * its apply_from; it replaces the queued pairs that would start at or after
 * its own apply_from; a value equal to the one it would follow (the last
 * queued, else the one in force) is not queued; a pair whose apply_from lies
 * before the interval about to be integrated is an error (after the first
 * step).  At most SARINS_INS_COMP_QUEUE pairs wait at once (more: an error).
 *
 * Every function that can fail returns SARINS_INS_OK or an error code with
 * a one-line reason in msg (size bytes; msg may be NULL) and then leaves
 * the struct unchanged.
 */
#ifndef SARINS_INS_FMU_STEP_H
#define SARINS_INS_FMU_STEP_H

#include <stddef.h>
#include <stdint.h>

#include "ins.h"

#define SARINS_INS_TAG_TOL 1e-6   /* of a step: two time tags closer than this name the same point */
#define SARINS_INS_COMP_QUEUE 256 /* compensation pairs that may wait at once */
#define SARINS_INS_BAD_STEP 3     /* a refused doStep (message written, nothing changed) */

/* Inputs, in this order (units: rad, m/s, s, degC, rad/s per degC^n). */
enum {
    SARINS_INS_IN_DTHETA_X, SARINS_INS_IN_DTHETA_Y, SARINS_INS_IN_DTHETA_Z,
    SARINS_INS_IN_DV_X, SARINS_INS_IN_DV_Y, SARINS_INS_IN_DV_Z,
    SARINS_INS_IN_INCREMENT_END_TIME, SARINS_INS_IN_TEMP_GYRO_Z,
    SARINS_INS_IN_CORRECTION_C, SARINS_INS_IN_CORRECTION_B, SARINS_INS_IN_CORRECTION_A,
    SARINS_INS_IN_APPLY_FROM, SARINS_INS_N_IN
};

/* Real outputs, in this order: lat, lon (rad), height (m), v_e, v_n, v_u (m/s), yaw, pitch, roll (rad);
 * lat_error, lon_error (rad), north_error, east_error, position_error (m) wrt the start; nav_time (s,
 * negative while aligning); gyro_drift_est_x, _y (rad/s), accel_bias_est_x, _y (m/s^2); temp_align_start,
 * temp_align_end, temp_change_align, temp_azimuth_gyro (degC); solution_time (s, the simulation time the
 * navigation outputs refer to). */
enum {
    SARINS_INS_OUT_LAT, SARINS_INS_OUT_LON, SARINS_INS_OUT_HEIGHT, SARINS_INS_OUT_V_E, SARINS_INS_OUT_V_N,
    SARINS_INS_OUT_V_U, SARINS_INS_OUT_YAW, SARINS_INS_OUT_PITCH, SARINS_INS_OUT_ROLL,
    SARINS_INS_OUT_LAT_ERROR, SARINS_INS_OUT_LON_ERROR, SARINS_INS_OUT_NORTH_ERROR, SARINS_INS_OUT_EAST_ERROR,
    SARINS_INS_OUT_POSITION_ERROR, SARINS_INS_OUT_NAV_TIME, SARINS_INS_OUT_GYRO_DRIFT_EST_X,
    SARINS_INS_OUT_GYRO_DRIFT_EST_Y, SARINS_INS_OUT_ACCEL_BIAS_EST_X, SARINS_INS_OUT_ACCEL_BIAS_EST_Y,
    SARINS_INS_OUT_TEMP_ALIGN_START, SARINS_INS_OUT_TEMP_ALIGN_END, SARINS_INS_OUT_TEMP_CHANGE_ALIGN,
    SARINS_INS_OUT_TEMP_AZIMUTH_GYRO, SARINS_INS_OUT_SOLUTION_TIME, SARINS_INS_N_OUT
};

/* One compensation: value (c, b, a) and the nav time it applies from (s). */
typedef struct {
    double value[3];
    double apply_from;
} sarins_ins_comp_pair;

typedef struct {
    sarins_ins_comp_pair seen;                          /* the last input pair */
    double current[3];                                  /* the value in force */
    sarins_ins_comp_pair pending[SARINS_INS_COMP_QUEUE]; /* ring buffer of the queued pairs */
    int64_t first, count;                               /* its first slot and length */
    int64_t started;                                    /* 1 after the first interval */
} sarins_ins_comp;

/* Start a queue with the pair (value, apply_from) queued and 0 in force. */
void sarins_ins_comp_init(sarins_ins_comp *c, const double *value, double apply_from);

/* The compensation in force (current, 3 values) for the interval starting at nav time nav_start (s),
 * given the input pair (value, apply_from); tol (s) is the time-tag tolerance.  The queue is updated
 * only on success (SARINS_INS_OK); else SARINS_INS_BAD_STEP with the reason. */
int sarins_ins_comp_value_at(sarins_ins_comp *c, const double *value, double apply_from, double nav_start,
                             double tol, double *current, char *msg, size_t size);

typedef struct {
    double config[SARINS_INS_CONFIG]; /* the INS settings (ins.h; the step is the first doStep's) */
    double attitude0[3];              /* yaw0, pitch0, roll0 (rad): the start attitude when align_time = 0 */
    double start_time;                /* s, the simulation time of the start */
    double step;                      /* s, the communication step (0 before the first doStep) */
    int64_t running;                  /* 1 once the INS is initialised (first doStep) */
    int64_t phase;                    /* output: 0 coarse alignment, 1 fine alignment, 2 navigation */
    double out[SARINS_INS_N_OUT];     /* the Real outputs */
    sarins_ins ins;
    sarins_ins_comp comp;
} sarins_ins_fmu;

/* Set the settings (config: ins.h layout, its step ignored; attitude0: yaw0, pitch0, roll0 rad) and the
 * start time (s), and publish the start outputs: lat, lon, height of the start, nav_time = -align_time,
 * solution_time = start_time, and with align_time = 0 the attitude and phase 2; every other output 0.
 * No check (Initialization Mode: the parameters may still change). */
void sarins_ins_fmu_setup(sarins_ins_fmu *f, const double *config, const double *attitude0, double start_time);

/* Leave Initialization Mode: check the settings (with a 1 s step, as the first doStep will with its own),
 * publish the start outputs again, take the temperature input as temp_align_start and
 * temp_azimuth_gyro, and start the compensation queue with the input pair.  in: SARINS_INS_N_IN inputs. */
int sarins_ins_fmu_start(sarins_ins_fmu *f, const double *in, char *msg, size_t size);

/* doStep(t, h) with the inputs in (SARINS_INS_N_IN values, read at the call): see the contract above.
 * Returns SARINS_INS_OK (outputs updated; a waiting first step changes none) or an error code. */
int sarins_ins_fmu_do_step(sarins_ins_fmu *f, const double *in, double t, double h, char *msg, size_t size);

/* sizeof(sarins_ins_fmu), and the byte offsets of its out, phase, ins and comp members and of the queue's
 * count in offsets[0..4]. */
int64_t sarins_ins_fmu_layout(int64_t *offsets);

#endif
