/* Turntable schedules generated from parameters (sarins_fmu/turntable):
 * the single-axis RINS schemes, the dual-axis scheme, and seed 003's
 * three-axis rate table (dynamic sweep), 24-position tumble and rate test.
 *
 * Units: rad, rad/s, rad/s^2, s.  Frames: gimbal j turns by theta_j about
 * axes[j], a unit vector in its parent frame (outer gimbal first, the parent
 * of gimbal 0 is the base frame t, the innermost gimbal carries the IMU,
 * frame b):  mat_tb = R(axes[0], theta_0) ... R(axes[A-1], theta_{A-1}).
 * Chains: single-axis schemes "z"; "dual-axis" "y,z" (outer about the base's
 * front y, inner about the outer frame's z); "rate-table-3axis", "tumble-24"
 * and "rate-test" "z,x,y" (outer about the base vertical z, middle about x,
 * inner about y).  Every schedule starts at rest at angle 0 at t = 0.
 *
 * Output: the breakpoint tables of a piecewise-constant-acceleration motion
 * (as sarins_fmu.turntable.GimbalSchedule.tables(), read by
 * sarins_turntable_state in turntable.h): times (M+1) strictly increasing,
 * angle_bp and rate_bp (M+1, A) the state at each breakpoint, accel (M, A)
 * the acceleration on [times[m], times[m+1]), angle0 and rate0 (A) the
 * state at times[0].  Arrays are row-major float64.  Every breakpoint lies
 * on the grid (k * grid, k integer); after the last one the gimbals keep
 * their final rate.
 *
 * Use: sarins_schedule_params_default, set the fields, sarins_schedule_size
 * (validates and counts), allocate, sarins_schedule_build (writes).  The
 * builder allocates nothing, keeps no globals and is reentrant; its output
 * is bit-identical to the former Python generator.  Errors: a non-zero code
 * and a one-line reason written to msg (msg_len bytes, always terminated;
 * msg may be NULL), e.g. "grid must be positive, got 0.0 s".
 *
 * Sources: schedule.c, ambient.c and report.c (the reasons); the schedule is
 * evaluated by turntable.c (sarins_turntable_state).
 */
#ifndef SARINS_SCHEDULE_H
#define SARINS_SCHEDULE_H

#include <stddef.h>
#include <stdint.h>

/* return codes */
#define SARINS_SCHEDULE_OK 0
#define SARINS_SCHEDULE_BAD_PARAM 1  /* a parameter is out of range (msg names it) */
#define SARINS_SCHEDULE_TOO_BIG 2    /* more than SARINS_SCHEDULE_MAX_BREAKPOINTS or 2^53 grid steps */
#define SARINS_SCHEDULE_CAPACITY 3   /* the caller's arrays are smaller than sarins_schedule_size said */

#define SARINS_SCHEDULE_MAX_AXES 3                  /* gimbals of the generated chains */
#define SARINS_SCHEDULE_MAX_BREAKPOINTS ((int64_t)1 << 23)  /* largest schedule generated, breakpoints */
#define SARINS_RATE_TEST_N_MAGNITUDES 11            /* default rate-test magnitudes (each rate +/-) */

/* Body axis codes (the axis that points up in a tumble position or a rate-test window). */
enum { SARINS_UP_PX = 0, SARINS_UP_MX, SARINS_UP_PY, SARINS_UP_MY, SARINS_UP_PZ, SARINS_UP_MZ };

/* Parameters of one schedule (the Turntable FMU's parameters, SI).  Only the
 * fields the scheme uses are read and checked:
 *   single-axis ("none", "continuous", "forward-reverse", "four-position"):
 *       duration, rate, accel, dwell, revolutions (forward-reverse), align_time, align_dwell, grid;
 *   "dual-axis": duration, rate/accel (inner), outer_rate/outer_accel, dwell, align_time, align_dwell, grid;
 *   "rate-table-3axis": duration, table_*_rate/accel, grid, warmup;
 *   "tumble-24": dwell (at each position), rate/accel (of the moves), grid;
 *   "rate-test": accel (spin-up and positioning), rate (positioning), dwell (settling at constant rate before
 *       each window), grid, test_rates, test_axes, test_min_duration, test_rate_tol. */
typedef struct {
    const char *scheme;      /* "none", "continuous", "forward-reverse", "four-position", "dual-axis",
                                "rate-table-3axis", "tumble-24", "rate-test" */
    double duration;         /* length the schedule must cover, s, > 0 (the pattern repeats) */
    double rate;             /* peak rate of the (inner) gimbal's moves, rad/s, >= 0 (> 0 when rotating) */
    double accel;            /* acceleration of those moves, rad/s^2, >= 0 (> 0 when rotating) */
    double dwell;            /* stop at each position or reversal, s, >= 0 (rounded up to the grid) */
    double revolutions;      /* forward-reverse: turns each way, a whole number >= 1 */
    double align_time;       /* initial four-position indexing (alignment), s, >= 0 (0: none) */
    double align_dwell;      /* stop at each alignment position, s, >= 0 */
    double grid;             /* time grid on which the acceleration may change, s, > 0 */
    double outer_rate;       /* dual-axis: outer flip peak rate, rad/s, > 0 */
    double outer_accel;      /* dual-axis: outer flip acceleration, rad/s^2, > 0 */
    double table_inner_rate, table_middle_rate, table_outer_rate;    /* rate-table-3axis: rate amplitude, rad/s,
                                                                        >= 0 (0: that gimbal stays still) */
    double table_inner_accel, table_middle_accel, table_outer_accel; /* rate-table-3axis: rad/s^2, > 0 */
    double warmup;           /* rate-table-3axis: static warm-up, s, >= 0 (rounded up to the grid) */
    const double *test_rates; /* rate-test: nominal outer rates, rad/s, finite, non-zero (sign: sense about the
                                 base up axis); NULL: the default +-{1, 2, 3, 5, 10, 20, 30, 50, 100, 150, 200}
                                 deg/s, each positive then negative */
    int64_t n_test_rates;    /* entries of test_rates (>= 1 when test_rates is not NULL) */
    const char *test_axes;   /* rate-test: body axes pointed up in turn, comma-separated, "x" means "+x",
                                case and blanks ignored, e.g. "x,y,z" or "-y, X"; NULL: "x,y,z" */
    double test_min_duration; /* rate-test: shortest window, s, >= 0 (0: one revolution) */
    double test_rate_tol;    /* rate-test: largest relative change of a rate to fit whole revolutions on the grid,
                                in (0, 0.1] */
} sarins_schedule_params;

/* One dwell window of "tumble-24" (24 rows) or measurement window of
 * "rate-test" (axes x rates rows), in time order. */
typedef struct {
    double start, end;       /* s, on the grid: tumble: the table is at rest on [start, end]; rate test: the outer
                                gimbal turns at `rate` on [start, end] through `revolutions` whole turns */
    double angles[3];        /* gimbal angles (outer, middle, inner), rad: tumble: held in the window; rate test:
                                middle and inner (outer 0: it turns) */
    double heading;          /* tumble: outer angle mod 2 pi, rad; rate test: 0 */
    double rate;             /* rate test: outer rate in the window, rad/s (2 pi k / (n grid), signed); tumble: 0 */
    double rate_nominal;     /* rate test: the requested rate, rad/s; tumble: 0 */
    int64_t revolutions;     /* rate test: k; tumble: 0 */
    int64_t up;              /* body axis pointing up, SARINS_UP_PX .. SARINS_UP_MZ */
} sarins_schedule_window;

/* A built schedule.  The caller sets the array pointers and capacities; the
 * builder writes the rest. */
typedef struct {
    int64_t capacity;        /* caller: rows of times, angle_bp, rate_bp (>= n_times of the size query) */
    double *times;           /* caller: [capacity] */
    double *angle_bp;        /* caller: [capacity * n_axes] (n_axes of the size query, <= 3) */
    double *rate_bp;         /* caller: [capacity * n_axes] */
    double *accel;           /* caller: [(capacity - 1) * n_axes] */
    int64_t window_capacity; /* caller: rows of windows (0 and windows NULL: windows not written) */
    sarins_schedule_window *windows; /* caller: [window_capacity] or NULL */
    int64_t n_times;         /* breakpoints M + 1 (>= 2) */
    int64_t n_axes;          /* gimbals A (1, 2 or 3) */
    int64_t n_windows;       /* windows of the scheme (0 except tumble-24 and rate-test), written or not */
    double angle0[SARINS_SCHEDULE_MAX_AXES]; /* angles at times[0], rad (0) */
    double rate0[SARINS_SCHEDULE_MAX_AXES];  /* rates at times[0], rad/s (0) */
    double axes[SARINS_SCHEDULE_MAX_AXES][3]; /* unit gimbal axes in the parent frame, outer first */
    char gimbal_axes[8];     /* the chain as axis letters, outer first: "z", "y,z" or "z,x,y" */
} sarins_schedule;

/* The Turntable FMU's default parameters: "forward-reverse" at 6 deg/s and 6
 * deg/s^2, dwell 0, 1 revolution, align_time 4 h, align_dwell 300 s, grid 1
 * s, duration 100 h, outer 6 deg/s and 6 deg/s^2, table rates (inner,
 * middle, outer) 1, 10, 100 deg/s and accelerations 0.01, 0.1, 1 deg/s^2,
 * warmup 600 s, rate test: default rates, axes "x,y,z", min duration 0,
 * rate_tol 1e-3. */
void sarins_schedule_params_default(sarins_schedule_params *p);

/* Checks p and counts the schedule: *n_times breakpoints, *n_axes gimbals,
 * *n_windows windows (any of the three may be NULL).  Returns a code. */
int sarins_schedule_size(const sarins_schedule_params *p, int64_t *n_times, int64_t *n_axes, int64_t *n_windows,
                         char *msg, size_t msg_len);

/* Checks p and writes the schedule into s (see sarins_schedule).  Returns a
 * code; SARINS_SCHEDULE_CAPACITY if s->capacity (or a non-zero
 * s->window_capacity) is smaller than needed.  On an error the contents of
 * s are unspecified. */
int sarins_schedule_build(const sarins_schedule_params *p, sarins_schedule *s, char *msg, size_t msg_len);

/* Gimbal chain of a scheme as axis letters ("z", "y,z", "z,x,y"), or NULL
 * for an unknown scheme. */
const char *sarins_scheme_gimbal_axes(const char *scheme);

/* Segments of a trapezoidal-rate move through angle (rad) from rest to rest
 * at peak rate rate_max (rad/s) and acceleration accel_max (rad/s^2): the
 * acceleration and cruise phases are whole multiples of grid (s) (at least
 * one step each phase present); the peak rate is lowered (never raised) so
 * the move covers angle exactly.  Writes *n segments (0 for angle 0, else 2
 * or 3) to duration[3] (s) and seg_accel[3] (rad/s^2).  Returns a code
 * (rate_max, accel_max and grid must be positive and everything finite). */
int sarins_move_segments(double angle, double rate_max, double accel_max, double grid, double *duration,
                         double *seg_accel, int64_t *n, char *msg, size_t msg_len);

/* State at each breakpoint of a schedule given by its times (M+1), accel
 * (M, A), angle0 and rate0 (A):
 *   rate_bp[m] = rate0 + sum_{i<m} accel[i] dt_i,
 *   angle_bp[m] = angle0 + sum_{i<m} (rate_bp[i] dt_i + accel[i] dt_i^2 / 2),  dt_i = times[i+1] - times[i]
 * (sums accumulated in order).  Writes angle_bp, rate_bp (M+1, A). */
void sarins_schedule_integrate(int64_t n_times, int64_t n_axes, const double *times, const double *accel,
                               const double *angle0, const double *rate0, double *angle_bp, double *rate_bp);

/* Seed 003's default rate-test magnitudes (deg/s, ascending), written to
 * out[SARINS_RATE_TEST_N_MAGNITUDES]. */
void sarins_rate_test_magnitudes_dps(double *out);

#endif
