/* Truth motion of a vehicle from segments, and the ideal IMU's increments along it.
 *
 * A trajectory is a chain of segments on the IMU's output grid (step h, s).  Within segment j,
 * tau the time since its start, the speed s, the heading (yaw, CCW from north) psi and the pitch
 * (flight-path angle, the body's pitch; roll is 0, no side-slip) are
 *     s = s_j + a_j tau,   psi = psi_j + r_j tau,   theta = theta_j + q_j tau
 * (a_j m/s^2, r_j yaw rate rad/s, q_j pitch rate rad/s), continuous across segments, so velocity
 * and attitude are continuous and the accelerations and rates change only on the grid.  Frames:
 * navigation ENU, body right-front-up, mat_nb = Rz(psi) Rx(theta), so
 *     v^n = s u,   u = (-sin psi cos theta, cos psi cos theta, sin theta)
 *     omega_nb^b = (q, r sin theta, r cos theta)
 * and, with omega_in^n = omega_ie^n + omega_en^n and g^n = (0, 0, -g(L, h)) (earth.h),
 *     omega_ib^b = omega_nb^b + mat_bn omega_in^n
 *     f^b       = mat_bn (dv^n/dt + (2 omega_ie^n + omega_en^n) x v^n - g^n)
 *     L' = v_N / (R_M + h),   lambda' = v_E / ((R_N + h) cos L),   h' = v_U.
 * Position, the body attitude wrt inertial space over each IMU interval (q' = q (0, omega_ib^b) / 2)
 * and the specific-force increment dv = int mat_{b(k-1) b(t)} f^b dt are integrated together by
 * classical Runge-Kutta (4th order) on `substeps` sub-intervals of each step; the angle increment
 * is the rotation vector of q at the end of the step (coning included).  These are the increments
 * of the project's IMU contract (ins.h): dtheta the body rotation over the step, dv in the body
 * frame at the start of the step.
 */
#ifndef SARINS_TRAJ_H
#define SARINS_TRAJ_H

#include <stdint.h>

#define SARINS_TRAJ_SEG 4  /* segment row: steps (integer-valued), accel m/s^2, yaw rate rad/s, pitch rate rad/s */
#define SARINS_TRAJ_ROW 15 /* truth row: lat, lon (rad), h (m), v E N U (m/s), yaw, pitch, roll (rad),
                              omega_ib^b (rad/s, 3), f^b (m/s^2, 3) */
/* start array: lat, lon (rad), height (m), speed (m/s), yaw, pitch (rad) */
enum { SARINS_TRAJ_LAT, SARINS_TRAJ_LON, SARINS_TRAJ_HEIGHT, SARINS_TRAJ_SPEED, SARINS_TRAJ_YAW,
       SARINS_TRAJ_PITCH, SARINS_TRAJ_START };

#define SARINS_TRAJ_OK 0
#define SARINS_TRAJ_BAD 1 /* a bad argument: nothing written beyond the rows done */

/* Run n_seg segments (seg (n_seg, 4)) from start (6) with IMU step h s and `substeps` RK4
 * sub-intervals per step; k_total = the sum of the segments' steps.  Writes truth (k_total + 1, 15)
 * (row k at t = k h; its rate and specific force are those at t = k h on the segment that starts
 * there, the last row's on the last segment) and dtheta, dv (k_total, 3).  Returns SARINS_TRAJ_BAD
 * when a count is not a non-negative integer, the counts do not add up to k_total, h or substeps is
 * not positive, the speed turns negative, |pitch| reaches 89 deg or the latitude 89.9 deg, or a
 * value is not finite. */
int sarins_traj_run(int64_t n_seg, const double *seg, const double *start, double h, int64_t substeps,
                    int64_t k_total, double *truth, double *dtheta, double *dv);

/* The same run one step at a time (the TrajectoryIMU FMU): the state between steps, plain data. */
typedef struct {
    double state0[3]; /* speed (m/s), yaw, pitch (rad) at the start of the current segment */
    double pos[3];    /* lat, lon (rad), h (m) at the start of the next step */
    double pos_c[3];  /* Kahan compensation of pos */
    double step;      /* h, s */
    int64_t substeps; /* RK4 sub-intervals per step */
    int64_t seg;      /* current segment */
    int64_t i;        /* steps done in it */
    int64_t n_seg;    /* segments */
} sarins_traj;

/* Start a stepwise run of n_seg segments seg (n_seg, 4) (checked as sarins_traj_run checks them, except the
 * total) from start (6).  SARINS_TRAJ_OK or SARINS_TRAJ_BAD. */
int sarins_traj_begin(sarins_traj *s, int64_t n_seg, const double *seg, const double *start, double h,
                      int64_t substeps);

/* The truth row (15) at the start of the next step (t = k h): sarins_traj_run's row k. */
void sarins_traj_row(const sarins_traj *s, const double *seg, double *row);

/* One step of the segments s was begun with: dtheta, dv (3 each) over it, s advanced to its end.  Returns
 * SARINS_TRAJ_OK, or SARINS_TRAJ_BAD (s unchanged but for a partly written dtheta, dv) when the segments
 * are used up or the motion leaves the range sarins_traj_run checks. */
int sarins_traj_step(sarins_traj *s, const double *seg, double *dtheta, double *dv);

/* 1 when every segment's steps are done. */
int sarins_traj_done(const sarins_traj *s, const double *seg);

/* Rotation vector of a unit quaternion [w x y z] (the shorter rotation). */
void sarins_quat_to_rotvec(const double *q, double *phi);

#endif
