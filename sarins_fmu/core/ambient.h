/* Ambient (thermal chamber) temperature around the IMU (sarins_fmu/thermal.py:
 * Ambient, ambient_segment, chamber_profile, chamber_cycle_time).
 *
 * Temperatures degC, times s, rates degC/s.  Either a formula,
 *     T_amb(t) = mean + amplitude sin(2 pi t / period + phase) + slope t,
 * or a piecewise-linear profile (times strictly increasing, held at both
 * ends; as numpy.interp), e.g. the chamber profile built here.  The
 * functions allocate nothing, keep no globals and are reentrant.  Errors:
 * a non-zero code (SARINS_SCHEDULE_* of schedule.h) and a one-line reason
 * written to msg (msg_len bytes, always terminated; msg may be NULL).
 */
#ifndef SARINS_AMBIENT_H
#define SARINS_AMBIENT_H

#include <stddef.h>
#include <stdint.h>

#define SARINS_CHAMBER_MAX_POINTS ((int64_t)1 << 23) /* largest chamber profile generated, breakpoints */

typedef struct {
    double mean;           /* degC */
    double amplitude;      /* degC */
    double period;         /* s (> 0 when amplitude is not 0) */
    double phase;          /* rad */
    double slope;          /* linear drift, degC/s */
    int64_t n_profile;     /* > 0: the profile below replaces the formula */
    const double *profile_times; /* [n_profile] s, strictly increasing */
    const double *profile_temps; /* [n_profile] degC */
} sarins_ambient;

/* T_amb at time t (s), degC (the formula is skipped, giving mean, when
 * amplitude and slope are both 0). */
double sarins_ambient_at(const sarins_ambient *a, double t);

/* T_amb at the n times t, written to out[n]. */
void sarins_ambient_values(const sarins_ambient *a, int64_t n, const double *t, double *out);

/* The ambient as an IMU sees it over a step [t, t + span]: *value = T_amb(t)
 * and *slope = (T_amb(t + span) - T_amb(t)) / span (degC, degC/s).
 * Returns a code (span must be positive and finite). */
int sarins_ambient_segment(const sarins_ambient *a, double t, double span, double *value, double *slope,
                           char *msg, size_t msg_len);

/* Thermal-chamber programme (seed 003's dynamic calibration):
 *     start for `delay` s, ramp to the first end, hold, ramp to the other end, hold, ...
 * at |dT/dt| = ramp, cut at `duration` (the last value interpolated).  With
 * step > 0 every ramp between the ends also stops for step_hold at each
 * `step` from the end it leaves (the first ramp from `start` has no stops). */
typedef struct {
    double duration;       /* length to cover, s, > 0 */
    double low, high;      /* cold and hot set points, degC, -273.15 < low < high */
    double ramp;           /* ramp rate magnitude, degC/s, > 0 */
    double hold;           /* hold at each end, s, >= 0 */
    double start;          /* temperature at t = 0, degC */
    double delay;          /* hold at start before the first ramp, s, >= 0 */
    const char *first;     /* end the first ramp goes to: "low" or "high" */
    double step;           /* spacing of the intermediate stops, degC, >= 0 (0: none) */
    double step_hold;      /* length of each intermediate stop, s, >= 0 */
} sarins_chamber_params;

/* Defaults of the Turntable FMU: duration 100 h, low -25, high 40 degC,
 * ramp 1 degC/min, hold 30 min, start 20 degC, delay 0, first "low", no
 * intermediate stops. */
void sarins_chamber_params_default(sarins_chamber_params *p);

/* Checks p and counts the profile's breakpoints (*n_points, >= 2). */
int sarins_chamber_size(const sarins_chamber_params *p, int64_t *n_points, char *msg, size_t msg_len);

/* Checks p and writes the profile: times[*n_points] (s, strictly increasing
 * from 0 to duration) and temps[*n_points] (degC); capacity is the length
 * of both arrays (SARINS_SCHEDULE_CAPACITY if below what sarins_chamber_size
 * gives).  Feed them to sarins_ambient as its profile. */
int sarins_chamber_build(const sarins_chamber_params *p, int64_t capacity, double *times, double *temps,
                         int64_t *n_points, char *msg, size_t msg_len);

/* Length of one cycle of the programme, end -> other end -> end, holds and
 * intermediate stops included, s (p->duration, start, delay, first unused). */
int sarins_chamber_cycle_time(const sarins_chamber_params *p, double *cycle, char *msg, size_t msg_len);

#endif
