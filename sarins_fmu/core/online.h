/* Online update of the azimuth drift model at vehicle stops (seed 002, Fig. 2), row by row: the Python
 * face is sarins_fmu/identify/online.py (OnlineDriftUpdater), the FMU fmus/c/drift_model_updater.
 *
 * Each row is one INS output (its time, the vehicle speed, the INS east/north velocity and attitude, the
 * azimuth gyro temperature, the latitude and whether the INS navigates).  The vehicle is stopped at a
 * row when |speed| < speed_threshold and the INS navigates.  Per row:
 *   1. moving and a stop was being estimated: the stop ends at this row's time; if its estimation time
 *      reached time_threshold (- 1e-9 s) the pair (mean gyro temperature, drift estimate) updates the
 *      RLS model (rls.h), else the stop is discarded; either way an event is recorded;
 *   2. the compensation drift of the row is the current model at its temperature;
 *   3. stopped: at the first row of a stop the filter (stop_filter.h) is reset at the row's latitude;
 *      the row is one filter step with the row's compensation as the correction the INS applied.
 * Units: s, m/s, rad, rad/s, degC.  Functions that can fail return SARINS_ONLINE_OK or SARINS_ONLINE_BAD
 * with a one-line reason in msg (size bytes; msg may be NULL).  libm: through rls.h and stop_filter.h.
 */
#ifndef SARINS_ONLINE_H
#define SARINS_ONLINE_H

#include <stddef.h>
#include <stdint.h>

#include "rls.h"
#include "stop_filter.h"

#define SARINS_ONLINE_OK 0
#define SARINS_ONLINE_BAD 1
#define SARINS_ONLINE_TIME_TOL 1e-9 /* s: a stop this much shorter than time_threshold still counts */
#define SARINS_ONLINE_MAX_COUNT ((int64_t)1 << 53) /* event counts a state may hold (whole float64 values) */

/* A finished stop. */
typedef struct {
    double time;        /* s, the row at which the vehicle moved off */
    double duration;    /* s, its estimation time */
    double temperature; /* degC, mean azimuth gyro temperature (T_gz) */
    double drift;       /* rad/s, the drift estimate eps_U */
    double drift_std;   /* rad/s, its filter standard deviation */
    int64_t used;       /* 1: it updated the model; 0: discarded as too short */
} sarins_online_event;

typedef struct {
    double time_threshold;           /* s, the shortest stop that updates the model (> 0) */
    double speed_threshold;          /* m/s, below it the vehicle is stopped (> 0) */
    int64_t stopped;                 /* 1 while a stop is being estimated */
    int64_t n_updates, n_resets;     /* stops that updated the model / were discarded, since init */
    sarins_online_event last;        /* the last finished stop (when n_updates + n_resets > 0) */
    sarins_online_event last_update; /* the last one that updated the model (when n_updates > 0) */
} sarins_online;

/* Thresholds (positive, finite), not stopped, no events. */
int sarins_online_init(sarins_online *u, double time_threshold, double speed_threshold, char *msg, size_t size);

/* The vehicle moves off at time (s): if a stop is being estimated, end it (step 1 above), reset the filter
 * at its latitude and write the event into *event (may be NULL); *finished = 1 then, else 0.  A failed
 * model update (a time before the model's) is refused with nothing changed. */
int sarins_online_finish(sarins_online *u, sarins_rls *rls, sarins_stop_kf *kf, double time,
                         sarins_online_event *event, int *finished, char *msg, size_t size);

/* K rows: time (K) s, speed (K) m/s, velocity_en (K,2) m/s, attitude (K,3) rad, temperature (K) degC,
 * lat (K) rad or NULL (the filter keeps its latitude), active (K) 0/1 or NULL (all navigating).
 * Writes comp (K), the compensation drift of each row, rad/s, and the finished stops into events (at most
 * max_events; more is refused before any row runs when K could exceed it: pass max_events >= K / 2 + 1),
 * their number into *n_events.  The times, speeds and temperatures are checked finite first (refused with
 * nothing changed); a row refused later (a latitude out of range at a stop's start, a non-finite INS output
 * or compensation while stopped, a failed update) stops the call there, the rows before it processed
 * (*n_events and comp written for them). */
int sarins_online_rows(sarins_online *u, sarins_rls *rls, sarins_stop_kf *kf, int64_t k, const double *time,
                       const double *speed, const double *velocity_en, const double *attitude,
                       const double *temperature, const double *lat, const unsigned char *active, double *comp,
                       sarins_online_event *events, int64_t max_events, int64_t *n_events, char *msg, size_t size);

/* s: the estimation time of the current stop (0 when moving). */
double sarins_online_timer(const sarins_online *u, const sarins_stop_kf *kf);

/* Every field within its invariants (thresholds positive and finite, stopped 0/1, counts >= 0, events
 * finite with used 0/1 and non-negative durations): for a state that arrived from outside. */
int sarins_online_check(const sarins_online *u, char *msg, size_t size);

/* sizeof(sarins_online) and sizeof(sarins_online_event), and the byte offsets of stopped, n_updates,
 * n_resets, last, last_update in offsets[0..4] (for the Python binding). */
int64_t sarins_online_layout(int64_t *event_size, int64_t *offsets);

#endif
