/* Strapdown INS major loop (ENU), its fine-alignment filter and the
 * inertial-frame coarse-alignment accumulators.
 *
 * Major-loop update from the compensated increments (phi, dv_b) over
 * [t_{k-1}, t_k] (Savage, Strapdown Analytics 2000, ch. 7; Titterton &
 * Weston 2004, ch. 11):
 *
 *     zeta   = (omega_ie^n + omega_en^n) h                   nav-frame rotation
 *     dv_n   = (I - [zeta x]/2) mat_nb(k-1) dv_b             specific-force part
 *     v_k    = v_{k-1} + dv_n + (g^n - (2 omega_ie^n + omega_en^n) x v_{k-1}) h
 *     q_nb,k = q(-zeta) * q_nb,k-1 * q(phi)
 *     L, lambda advance with the trapezoidal mean velocity.
 *
 * Earth and transport rate and Coriolis are evaluated at the start of the
 * step.  The vertical channel is held (height fixed, v_U = 0).
 *
 * State arrays are updated in place: q (4) = q_nb [w x y z], v (3) ENU m/s,
 * pos (3) = [lat rad, lon rad, height m].  Increments dtheta (K,3) rad and
 * dv (K,3) m/s are body-frame (right-front-up), row-major.  Output rows
 * (K,9): lat, lon, height, v_E, v_N, v_U, yaw, pitch, roll (rad, m, m/s),
 * with mat_nb = Rz(yaw) Rx(pitch) Ry(roll).
 */
#ifndef SARINS_INS_H
#define SARINS_INS_H

#include <stddef.h>
#include <stdint.h>

#define SARINS_INS_ROW 9           /* columns of an output row */
#define SARINS_INS_ALIGN_STATES 9  /* fine-alignment filter states */

/* Free navigation over K steps of h s.  gyro_comp (3) rad/s and accel_comp
 * (3) m/s^2 are subtracted from the increments (alignment estimates);
 * axial_corr (K) rad/s is subtracted from the z angle increment.  Writes
 * out (K,9). */
void sarins_ins_nav_steps(int64_t k, double *q, double *v, double *pos, const double *dtheta, const double *dv,
                          double h, const double *gyro_comp, const double *accel_comp, const double *axial_corr,
                          double *out);

/* Output row of the alignment phases: pos, zero velocity, the attitude of q. */
void sarins_ins_held_row(const double *q, const double *pos, double *row);

/* Fine alignment on a static base over K steps: mechanization with the
 * position held + 9-state closed-loop Kalman filter,
 *     x = [phi_E, phi_N, phi_U, dv_E, dv_N, eps_x, eps_y, nabla_x, nabla_y]
 * (mat_computed = (I - [phi x]) mat_true; body-frame horizontal gyro drifts
 * rad/s and accelerometer biases m/s^2), error model (Titterton & Weston
 * eqs 12.6-12.7, ENU, static, position known)
 *     phi' = phi x omega_ie^n + d omega_en^n(dv) - mat_nb eps
 *     dv'  = f^n x phi - 2 omega_ie^n x dv + mat_nb nabla
 * measurement: the computed v_E, v_N (true velocity zero, variance r_var).
 * After each update attitude and velocity are corrected, the drift and bias
 * estimates are added to gyro_comp / accel_comp and x is reset.  x (9),
 * p (9,9), q_diag (9) continuous noise densities.  Writes the P diagonal
 * after each step to hist (K,9). */
void sarins_ins_align_steps(int64_t k, double *q, double *v, double *pos, const double *dtheta, const double *dv,
                            double h, double *gyro_comp, double *accel_comp, double *x, double *p,
                            const double *q_diag, double r_var, double *hist);

/* Inertial-frame coarse alignment accumulators over K steps (in place):
 *     v_b0 += mat_b0b dv ;  q_b0b = q_b0b * q(dtheta)
 * Writes v_b0 after each step to hist (K,3). */
void sarins_ins_coarse_steps(int64_t k, double *q_b0b, double *v_b0, const double *dtheta, const double *dv,
                             double *hist);

/* ------------------------------------------------------------------------
 * The whole INS on one state struct: coarse alignment, fine alignment,
 * navigation (sarins_fmu.ins.StrapdownINS is its Python face).
 *
 * 1. Coarse alignment (coarse_time, n_coarse steps), analytic in the
 *    inertial frame, valid on a rotating turntable: the body attitude wrt
 *    the initial body frame b0 is integrated from the angle increments and
 *    the specific force accumulated in b0, V_b0(t) = int mat_b0b f_b dt.  In
 *    n0 (the navigation frame at the start, frozen in inertial space) the
 *    same integral of the static specific force (0, 0, g) is, with u the
 *    Earth-rate axis (0, cos L, sin L), K = [u x] and W the Earth rate,
 *        V_n0(t) = (t I + (1 - cos W t)/W K + (t - sin(W t)/W) K^2) (0, 0, g);
 *    the pairs at T/2 and T give mat_n0b0 by the double-vector (TRIAD)
 *    construction, and mat_nb(T) = q(-omega_ie^n T) mat_n0b0 mat_b0b(T).
 * 2. Fine alignment (until align_time, n_align steps in all):
 *    sarins_ins_align_steps; at its last step the velocity is set to 0
 *    (the known static start).
 * 3. Navigation: sarins_ins_nav_steps from the known start position with
 *    the alignment's drift and bias estimates compensated.
 * align_time = 0: navigation from the given attitude at once.
 *
 * The struct holds no pointer: copying its bytes copies the INS (FMU state).
 */

/* Settings of sarins_ins_init: a flat array of SARINS_INS_CONFIG doubles in this order (SI units):
 * start latitude, longitude (rad), height (m); align_time, coarse_time, step (s); then the fine-alignment
 * filter of sarins_fmu.ins.AlignmentFilter: arw (rad/sqrt(s)), vrw (m/s/sqrt(s)), drift_rw
 * (rad/s/sqrt(s)), bias_rw (m/s^2/sqrt(s)), velocity_meas_std (m/s), tilt0_std, heading0_std (rad),
 * velocity0_std (m/s), drift0_std (rad/s), bias0_std (m/s^2). */
enum {
    SARINS_INS_LAT, SARINS_INS_LON, SARINS_INS_HEIGHT, SARINS_INS_ALIGN_TIME, SARINS_INS_COARSE_TIME,
    SARINS_INS_STEP, SARINS_INS_ARW, SARINS_INS_VRW, SARINS_INS_DRIFT_RW, SARINS_INS_BIAS_RW,
    SARINS_INS_VELOCITY_MEAS_STD, SARINS_INS_TILT0_STD, SARINS_INS_HEADING0_STD, SARINS_INS_VELOCITY0_STD,
    SARINS_INS_DRIFT0_STD, SARINS_INS_BIAS0_STD, SARINS_INS_CONFIG
};
#define SARINS_INS_FILTER_FIRST SARINS_INS_ARW

/* return codes */
#define SARINS_INS_OK 0
#define SARINS_INS_BAD_CONFIG 1 /* a setting out of range (message written) */
#define SARINS_INS_BAD_INPUT 2  /* an increment or a correction is not finite (nothing changed) */

/* Latitude limit of the start, rad (89.9 deg: the navigation frame is singular at the poles). */
#define SARINS_INS_PI 3.141592653589793
#define SARINS_INS_LAT_LIMIT (89.9 * (SARINS_INS_PI / 180.0))

typedef struct {
    double config[SARINS_INS_CONFIG]; /* the settings (layout above) */
    double q0[4];                     /* q_nb at the start, [w x y z] (identity when aligning) */
    int64_t n_coarse, n_align;        /* steps of the coarse alignment and of the whole alignment */
    int64_t steps;                    /* major-loop steps integrated */
    double q[4];                      /* q_nb [w x y z] */
    double v[3];                      /* ENU velocity, m/s */
    double pos[3];                    /* lat rad, lon rad, height m */
    double gyro_comp[3];              /* gyro drift estimate subtracted, body, rad/s */
    double accel_comp[3];             /* accelerometer bias estimate subtracted, body, m/s^2 */
    double x[SARINS_INS_ALIGN_STATES];                           /* filter state (0 between steps) */
    double p[SARINS_INS_ALIGN_STATES * SARINS_INS_ALIGN_STATES]; /* filter covariance */
    double q_diag[SARINS_INS_ALIGN_STATES];                      /* continuous noise densities */
    double q_b0b[4];                  /* coarse alignment: body attitude wrt b0 */
    double v_b0[3];                   /* coarse alignment: int mat_b0b f_b dt, m/s */
    double v_b0_half[3];              /* v_b0 after n_coarse / 2 steps */
} sarins_ins;

/* Check a settings array (the checks of sarins_fmu.ins.InsConfig and AlignmentFilter); returns
 * SARINS_INS_OK or SARINS_INS_BAD_CONFIG with a one-line reason in msg (size bytes, may be NULL). */
int sarins_ins_config_check(const double *config, char *msg, size_t size);

/* Initialise s from config; mat_nb0 (3,3) row-major is the start attitude, required when align_time
 * is 0 and ignored otherwise (may be NULL then).  Returns SARINS_INS_OK or SARINS_INS_BAD_CONFIG
 * (s untouched, reason in msg). */
int sarins_ins_init(sarins_ins *s, const double *config, const double *mat_nb0, char *msg, size_t size);

/* Back to the state right after sarins_ins_init. */
void sarins_ins_reset(sarins_ins *s);

/* Phase after the steps done: 0 coarse alignment, 1 fine alignment, 2 navigation. */
int sarins_ins_phase(const sarins_ins *s);

/* Advance over K major-loop steps, across the phases.  dtheta, dv (K,3) rad, m/s body-frame
 * increments; axial_corr (K) rad/s subtracted from the z gyro while navigating.  Writes out (K,9)
 * (the rows of sarins_ins_nav_steps; the rows of an alignment phase hold the start position, zero
 * velocity and the attitude at the end of that phase's run of rows within this call) and, if p_diag
 * is not NULL, the P diagonal after each fine-alignment step to its row of p_diag (K,9) (other rows
 * untouched).  Returns SARINS_INS_OK, or SARINS_INS_BAD_INPUT without changing anything when an input
 * is not finite. */
int sarins_ins_steps(sarins_ins *s, int64_t k, const double *dtheta, const double *dv, const double *axial_corr,
                     double *out, double *p_diag);

/* Errors of K output rows (K,9) wrt the known start: err (K,4) = dlat, dlon (rad), north, east (m),
 *     north = dlat (R_M + h0),   east = dlon (R_N + h0) cos L0. */
void sarins_ins_position_error(const sarins_ins *s, int64_t k, const double *rows, double *err);

/* Unit quaternion [w x y z] of a DCM (3,3) row-major (Shepperd's method; the 4-norm as a fused
 * multiply-add chain). */
void sarins_mat_to_quat(const double *mat, double *q);

/* Byte offsets of the fields a binding exposes, in this order: q, v, pos, gyro_comp, accel_comp, x,
 * p, q_diag, steps, n_coarse, n_align, config; returns sizeof(sarins_ins). */
int64_t sarins_ins_layout(int64_t *offsets);

#endif
