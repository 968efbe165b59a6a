/* Seed 002's land vehicle: drives, turns and stops on a level road, with the body's pitch and roll sway and
 * vibration while it moves (sarins_fmu.vehicle, the VehicleMotion FMU).
 *
 * Units SI (rad, rad/s, rad/s^2, m, m/s, m/s^2, s).  Frames: navigation frame n = local-level ENU at the
 * vehicle; body frame right-front-up; the vehicle's attitude is yaw psi (heading, counter-clockwise from
 * north), pitch theta, roll phi with mat_nv = Rz(psi) Rx(theta) Ry(phi).
 *
 * Legs (after lead_time s at rest):
 *   stop  SECONDS         brake to rest at `brake` m/s^2, then stand still; SECONDS in total;
 *   drive SECONDS SPEED   accelerate (brake) towards SPEED m/s at `accel` (`brake`), then hold; SECONDS in total;
 *   turn  ANGLE           change heading by ANGLE rad (positive left) with a trapezoidal yaw-rate profile
 *                         (peak yaw_rate, acceleration yaw_accel, phases whole grid steps), keeping the speed.
 * A ramp from v0 to v1 takes n = max(1, ceil(|v1 - v0| / (a h) - 1e-9)) steps of (v1 - v0) / (n h); a leg
 * lasts max(n, round(SECONDS / h)) steps.  The legs become segments (n steps of constant longitudinal and
 * yaw acceleration): a lead segment, <= 3 per leg, a last step at rest; then the vehicle stays parked.
 *
 * Motion on the grid t_k = k h (from the trajectory's start).  Over step k the longitudinal acceleration a_k
 * and yaw acceleration alpha_k are constant:
 *     s_{k+1} = s_k + a_k h (the segment's target speed at its last step, exactly),
 *     r_{k+1} = r_k + alpha_k h (0 at a turn's end, exactly),  psi_{k+1} = psi_k + r_k h + alpha_k h^2 / 2.
 * Body pitch/roll rates (j = pitch, roll) on the grid, linear in between:
 *     q_j(t) = [A_j w_s cos(w_s t + p_j0) + B sum_i w_i cos(w_i t + p_ji)] s(t) / s_ref,
 * w_s = 2 pi / sway_period, w_i = 2 pi vibration_hz[i], A = (sway_pitch, sway_roll), B = vibration; phases
 * p_ji = 2 pi u, u the uniforms of stream SARINS_VEHICLE_STREAM of seed (rng.h), in the order p_00 p_01 p_02
 * p_03 p_10 .. p_13.  Angular acceleration over step k: (q_{k+1} - q_k) / h; angle
 *     theta_{k+1} = theta_k + q_k h + acc_k h^2 / 2.
 * Velocity v = s (-sin psi, cos psi, 0); the step's mean velocity is Simpson's (v_k + 4 v_mid + v_{k+1}) / 6
 * with v_mid from s and psi at mid-step (exact: linear / quadratic in the step).  Position (height 0):
 *     L_{k+1} = L_k + vbar_N h / R_M(L'),  L' = L_k + vbar_N h / (2 R_M(L_k))   (midpoint rule)
 *     lambda_{k+1} = lambda_k + vbar_E h / (R_N(Lm) cos Lm),  Lm = (L_k + L_{k+1}) / 2.
 * Moving-base outputs held over step k (exact for the IMU): the inertial rate of n,
 *     w_it = w_ie + w_en,  w_ie = Omega (0, cos Lm, sin Lm),  w_en = (-vbar_N / R_M, vbar_E / R_N, vbar_E tan Lm / R_N),
 * and the specific force  f = (v_{k+1} - v_k) / h + (2 w_ie + w_en) x vbar - g^n,  g^n = (0, 0, -g(Lm, 0)).
 *
 * Use: sarins_vehicle_params_default, set fields; sarins_vehicle_segments (checks every parameter and leg,
 * writes <= 3 n_legs + 2 segments); sarins_vehicle_start; then sarins_vehicle_step once per grid step.
 * Nothing allocates, no globals, reentrant.  Errors: a non-zero code and a one-line reason in msg naming the
 * parameter (as sarins_fmu.vehicle and the FMU name it). */
#ifndef SARINS_VEHICLE_H
#define SARINS_VEHICLE_H

#include <stddef.h>
#include <stdint.h>

#define SARINS_VEHICLE_STREAM 61     /* rng.h stream id of the body phases */
#define SARINS_VEHICLE_N_VIBRATION 3 /* vibration frequencies */
#define SARINS_VEHICLE_BAD_PARAM 1   /* return code: a parameter or leg is out of range (msg says which) */
#define SARINS_VEHICLE_CAPACITY 3    /* return code: the caller's segment array is too small */
#define SARINS_VEHICLE_PART_MAX 256  /* bytes of one leg's text in sarins_vehicle_parse_legs */

enum { SARINS_LEG_STOP = 0, SARINS_LEG_DRIVE = 1, SARINS_LEG_TURN = 2 };

typedef struct {
    int kind;       /* SARINS_LEG_* */
    double seconds; /* stop, drive: duration, s, > 0; turn: the angle in degrees as written (not read) */
    double value;   /* drive: speed, m/s, >= 0; turn: heading change, rad (degrees * (pi / 180)), positive left */
} sarins_leg;

typedef struct {
    double lat0, lon0;  /* start position, rad (|lat0| <= 89.9 deg) */
    double heading0;    /* start heading, CCW from north, rad */
    double step;        /* grid h (= the IMU's output interval), s, > 0 */
    double lead_time;   /* at rest before the first leg, s, >= 0 */
    double accel;       /* m/s^2, > 0: longitudinal acceleration */
    double brake;       /* m/s^2, > 0: braking deceleration */
    double yaw_rate;    /* rad/s, > 0: peak turn rate */
    double yaw_accel;   /* rad/s^2, > 0 */
    double sway_pitch, sway_roll;  /* rad, >= 0: sway amplitudes at reference_speed */
    double sway_period;            /* s, > 0 */
    double vibration;              /* rad, >= 0: vibration amplitude per frequency at reference_speed */
    double vibration_hz[SARINS_VEHICLE_N_VIBRATION]; /* Hz, > 0 */
    double reference_speed;        /* m/s, > 0 */
    uint64_t seed;                 /* of the body phases */
} sarins_vehicle_params;

typedef struct {
    int64_t n;          /* grid steps, >= 1 */
    double accel;       /* longitudinal acceleration, m/s^2 */
    double yaw_accel;   /* rad/s^2 */
    double end_speed;   /* speed at the segment's end, m/s */
    int end_turn;       /* 1: the yaw rate is 0 at the segment's end (a turn's last phase) */
} sarins_vehicle_segment;

/* The stream's state at grid point k (plain data; the FMU state).  Values at t_k = k h. */
typedef struct {
    double phase[2][1 + SARINS_VEHICLE_N_VIBRATION]; /* rad */
    double w_sway, w_vib[SARINS_VEHICLE_N_VIBRATION]; /* rad/s */
    double amplitude[2], vibration, reference_speed, step;
    int64_t k;          /* grid point */
    int64_t segment;    /* current segment (n_segments: parked) */
    int64_t in_segment; /* steps of it done */
    double speed, yaw_rate, yaw, pitch, roll, lat, lon;
} sarins_vehicle;

/* Everything about the step that starts at t_k (what the VehicleMotion FMU publishes at t_k). */
enum {
    SARINS_VEH_YAW, SARINS_VEH_PITCH, SARINS_VEH_ROLL,                /* rad */
    SARINS_VEH_YAW_RATE, SARINS_VEH_PITCH_RATE, SARINS_VEH_ROLL_RATE, /* rad/s */
    SARINS_VEH_YAW_ACC, SARINS_VEH_PITCH_ACC, SARINS_VEH_ROLL_ACC,    /* rad/s^2, over the step */
    SARINS_VEH_W_E, SARINS_VEH_W_N, SARINS_VEH_W_U,                   /* w_it over the step, rad/s */
    SARINS_VEH_F_E, SARINS_VEH_F_N, SARINS_VEH_F_U,                   /* specific force over the step, m/s^2 */
    SARINS_VEH_LAT, SARINS_VEH_LON,                                   /* rad */
    SARINS_VEH_V_E, SARINS_VEH_V_N, SARINS_VEH_SPEED,                 /* m/s */
    SARINS_VEH_N_OUT
};

/* Defaults (sarins_fmu.vehicle.DriveSettings and BodyMotion, our choice): accel 1, brake 1.5 m/s^2, yaw
 * rate 6 deg/s, yaw accel 3 deg/s^2, sway 0.5 deg pitch and 0.3 deg roll over 20 s, vibration 0.05 deg at
 * 0.13, 0.29, 0.41 Hz, reference speed 10 m/s, step 1 s, seed 0; position and heading 0. */
void sarins_vehicle_params_default(sarins_vehicle_params *p);

/* Check p and the legs, and write their segments into segs (capacity cap; segs may be NULL to count only):
 * *n_segments segments, *n_steps grid steps in all.  Returns 0, SARINS_VEHICLE_BAD_PARAM or
 * SARINS_VEHICLE_CAPACITY with the reason in msg. */
int sarins_vehicle_segments(const sarins_vehicle_params *p, const sarins_leg *legs, int64_t n_legs,
                            sarins_vehicle_segment *segs, int64_t cap, int64_t *n_segments, int64_t *n_steps,
                            char *msg, size_t msg_len);

/* The state at t = 0 (p checked by sarins_vehicle_segments). */
void sarins_vehicle_start(sarins_vehicle *v, const sarins_vehicle_params *p);

/* Write the step that starts at the current grid point into out[SARINS_VEH_N_OUT] and move v to the next
 * one.  After the segments the vehicle keeps its speed with no acceleration (parked after a final stop). */
void sarins_vehicle_step(sarins_vehicle *v, const sarins_vehicle_segment *segs, int64_t n_segments, double *out);

/* 1 while the stream's state is valid: position, speed and angles finite, |lat| <= 89.9 deg (the ENU
 * mechanisation's range); 0 once a drive has left it (reason in msg). */
int sarins_vehicle_valid(const sarins_vehicle *v, char *msg, size_t msg_len);

/* 1 when v can be stepped over these segments (a state from outside, e.g. a deserialized FMU state): the
 * grid point k >= 0, the segment index in [0, n_segments] and the steps done in it below its length, the
 * step and the body constants positive and finite; else 0 with the reason in msg.  Then
 * sarins_vehicle_valid for the motion itself. */
int sarins_vehicle_state_ok(const sarins_vehicle *v, const sarins_vehicle_segment *segs, int64_t n_segments,
                            char *msg, size_t msg_len);

/* Parse "drive 300 10; turn 90; stop 1800" (degrees for turns; ';'-separated, blanks around) into legs
 * (capacity cap; turn angles written in rad).  Returns the number of legs, or -1 with the reason in msg. */
int64_t sarins_vehicle_parse_legs(const char *text, sarins_leg *legs, int64_t cap, char *msg, size_t msg_len);

/* Binding helper: check, segment and run the whole trajectory: out (n_rows, SARINS_VEH_N_OUT), row k the
 * step from t_k (k = 0 .. n_rows - 1).  segs: caller's scratch of cap segments.  Returns as
 * sarins_vehicle_segments (with out NULL only counts: *n_steps), or SARINS_VEHICLE_BAD_PARAM when the drive
 * leaves the valid range (sarins_vehicle_valid). */
int sarins_vehicle_run(const sarins_vehicle_params *p, const sarins_leg *legs, int64_t n_legs,
                       sarins_vehicle_segment *segs, int64_t cap, int64_t n_rows, double *out, int64_t *n_steps,
                       char *msg, size_t msg_len);

#endif
