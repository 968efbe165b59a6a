/* DriftModelUpdater FMU (native): seed 002's online update of the azimuth drift model, eps(T) = a T^2 +
 * b T + c, at the vehicle's stops (Fig. 2).
 *
 * The declaration (variables, descriptions, the timing contract) is fmus/drift_model_updater_slave.py.
 * The physics is the C core's, the code the library runs in process: Fig. 2's row logic (online.h), the
 * stop Kalman filter (stop_filter.h, filter.h) and the forgetting-factor RLS with its prior and its
 * binary model file (rls.h over the core's model-file reader netfile.h).  This file pairs the time-tagged inputs into rows (the INS row
 * tagged solution_time, else nav_time, with the vehicle speed tagged speed_time from the last 8 kept) and
 * publishes the outputs.  Units: s, m/s, rad, rad/s, degC.
 *
 * Everything that changes during a run is the state struct below (plain bytes, no pointer); the model
 * file is read at initialisation only and its model kept in the state, so do_step does no I/O and
 * nothing allocates at all.  libm: fabs (and through the core: pow, sqrt, sin, cos, tan).
 */
#include "smath.h"

#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "model.h"
#include "online.h"
#include "report.h"
#include "rls.h"
#include "stop_filter.h"
#include "variables.h"

#define DAY 86400.0     /* s */
#define NO_TAG -1.0e9   /* s: a time-tag input that is not connected (start value) */
#define TAG_TOL 1e-6    /* of a step: two time tags closer than this name the same communication point */
#define STEP_TOL 1e-9   /* relative: a communication step equal to the first one */
#define HISTORY 8       /* vehicle speeds kept to pair with the INS rows */
#define NAVIGATE 2      /* StrapdownINS phase in navigation */
#define MSG 512

/* What changes during a run. */
typedef struct {
    sarins_rls rls;              /* the model and its inverse information */
    sarins_rls initial;          /* the model at initialisation (the first step's rebuild starts from it) */
    sarins_stop_kf kf;           /* the stop filter (its step is the communication step) */
    sarins_online upd;           /* Fig. 2's stop flag and finished-stop record */
    double start_time;           /* s */
    double step;                 /* s, the communication step; 0 before the first doStep */
    double last_tag;             /* s, the tag of the last row processed (when have_last_tag) */
    int64_t have_last_tag;       /* 0 or 1 */
    int64_t n_speeds;            /* speeds kept, 0 .. HISTORY, oldest first */
    double speed_tag[HISTORY];   /* s, their speed_time tags, increasing */
    double speed[HISTORY];       /* m/s */
} dmu_state;

static const unsigned P_SLOTS[6] = {SARINS_R_p_aa, SARINS_R_p_ab, SARINS_R_p_ac, SARINS_R_p_bb, SARINS_R_p_bc,
                                    SARINS_R_p_cc};
static const int P_INDEX[6] = {0, 1, 2, 4, 5, 8}; /* (0,0) (0,1) (0,2) (1,1) (1,2) (2,2) of the 3 x 3 P */

static int same_time(double a, double b, double step) { return sm_fabs(a - b) <= TAG_TOL * step; }

/* ------------------------------------------------------------------------------------------ parameters */

typedef struct {
    const char *name;
    unsigned slot;
} named;

/* The slave's checks, in its order and with its messages' meaning. */
static int check_parameters(const sarins_ctx *c)
{
    static const named FINITE[] = {
        {"a0", SARINS_R_a0}, {"b0", SARINS_R_b0}, {"c0", SARINS_R_c0}, {"prior_points", SARINS_R_prior_points},
        {"prior_t_min", SARINS_R_prior_t_min}, {"prior_t_max", SARINS_R_prior_t_max},
        {"start_day", SARINS_R_start_day}, {"forgetting_factor", SARINS_R_forgetting_factor},
        {"forgetting_time_scale", SARINS_R_forgetting_time_scale}, {"time_threshold", SARINS_R_time_threshold},
        {"speed_threshold", SARINS_R_speed_threshold}, {"kf_arw", SARINS_R_kf_arw}, {"kf_vrw", SARINS_R_kf_vrw},
        {"kf_velocity_meas_std", SARINS_R_kf_velocity_meas_std}, {"kf_heading0_std", SARINS_R_kf_heading0_std},
        {"latency", SARINS_R_latency}};
    static const named POSITIVE[] = {
        {"prior_points", SARINS_R_prior_points}, {"forgetting_factor", SARINS_R_forgetting_factor},
        {"forgetting_time_scale", SARINS_R_forgetting_time_scale}, {"time_threshold", SARINS_R_time_threshold},
        {"speed_threshold", SARINS_R_speed_threshold}, {"kf_arw", SARINS_R_kf_arw}, {"kf_vrw", SARINS_R_kf_vrw},
        {"kf_velocity_meas_std", SARINS_R_kf_velocity_meas_std}, {"kf_heading0_std", SARINS_R_kf_heading0_std}};
    static const named NON_NEGATIVE[] = {{"start_day", SARINS_R_start_day}, {"latency", SARINS_R_latency}};
    const double *r = c->r;
    for (size_t k = 0; k < sizeof FINITE / sizeof FINITE[0]; k++)
        if (!isfinite(r[FINITE[k].slot])) {
            sarins_log(c, SARINS_ERROR, "parameter %s = %g is not a finite number", FINITE[k].name, r[FINITE[k].slot]);
            return SARINS_ERROR;
        }
    for (size_t k = 0; k < sizeof POSITIVE / sizeof POSITIVE[0]; k++)
        if (!(r[POSITIVE[k].slot] > 0.0)) {
            sarins_log(c, SARINS_ERROR, "parameter %s = %.17g must be positive", POSITIVE[k].name,
                       r[POSITIVE[k].slot]);
            return SARINS_ERROR;
        }
    for (size_t k = 0; k < sizeof NON_NEGATIVE / sizeof NON_NEGATIVE[0]; k++)
        if (!(r[NON_NEGATIVE[k].slot] >= 0.0)) {
            sarins_log(c, SARINS_ERROR, "parameter %s = %.17g must not be negative", NON_NEGATIVE[k].name,
                       r[NON_NEGATIVE[k].slot]);
            return SARINS_ERROR;
        }
    if (!(r[SARINS_R_prior_t_max] > r[SARINS_R_prior_t_min])) {
        sarins_log(c, SARINS_ERROR, "parameter prior_t_max = %.17g degC must exceed prior_t_min = %.17g degC",
                   r[SARINS_R_prior_t_max], r[SARINS_R_prior_t_min]);
        return SARINS_ERROR;
    }
    if (!(r[SARINS_R_forgetting_factor] <= 1.0)) {
        sarins_log(c, SARINS_ERROR, "parameter forgetting_factor = %.17g must be in (0, 1]",
                   r[SARINS_R_forgetting_factor]);
        return SARINS_ERROR;
    }
    return SARINS_OK;
}

/* The stop filter's settings: the defaults with the four the FMU takes as parameters. */
static void filter_settings(const sarins_ctx *c, double *settings)
{
    sarins_stop_settings_default(settings);
    settings[SARINS_STOP_ARW] = c->r[SARINS_R_kf_arw];
    settings[SARINS_STOP_VRW] = c->r[SARINS_R_kf_vrw];
    settings[SARINS_STOP_VELOCITY_MEAS_STD] = c->r[SARINS_R_kf_velocity_meas_std];
    settings[SARINS_STOP_HEADING0_STD] = c->r[SARINS_R_kf_heading0_std];
}

/* The initial model: the RLS state in model_file, else a0, b0, c0 worth prior_points calibration points. */
static int initial_model(const sarins_ctx *c, sarins_rls *rls)
{
    char msg[MSG];
    const double lam = c->r[SARINS_R_forgetting_factor], m = c->r[SARINS_R_forgetting_time_scale];
    const char *path = c->s[SARINS_S_model_file];
    if (path[0] == '\0') {
        double p0[9];
        const double x0[3] = {c->r[SARINS_R_a0], c->r[SARINS_R_b0], c->r[SARINS_R_c0]};
        if (sarins_rls_prior_covariance(c->r[SARINS_R_prior_points], c->r[SARINS_R_prior_t_min],
                                        c->r[SARINS_R_prior_t_max], p0, msg, sizeof msg) != SARINS_RLS_OK
            || sarins_rls_init(rls, x0, p0, 0.0, lam, m, msg, sizeof msg) != SARINS_RLS_OK) {
            sarins_log(c, SARINS_ERROR, "parameters a0, b0, c0, prior_points, prior_t_min, prior_t_max: %s", msg);
            return SARINS_ERROR;
        }
        return SARINS_OK;
    }
    if (sarins_rls_load_file(path, rls, msg, sizeof msg) != SARINS_RLS_OK) {
        sarins_log(c, SARINS_ERROR, "parameter model_file = '%s': model file '%s': %s", path, path, msg);
        return SARINS_ERROR;
    }
    if (rls->forgetting_factor != lam || rls->time_scale != m) {
        char file_lam[40], file_m[48], par_lam[40], par_m[40];
        sarins_format_number(file_lam, sizeof file_lam, rls->forgetting_factor);
        if (rls->time_scale == 0.0) {
            snprintf(file_m, sizeof file_m, "update (no time scale)");
        } else {
            sarins_format_number(file_m, sizeof file_m - 2, rls->time_scale);
            strcat(file_m, " s");
        }
        sarins_format_number(par_lam, sizeof par_lam, lam);
        sarins_format_number(par_m, sizeof par_m, m);
        sarins_log(c, SARINS_ERROR, "model_file %s has forgetting factor %s per %s; the parameters say %s per %s s",
                   path, file_lam, file_m, par_lam, par_m);
        return SARINS_ERROR;
    }
    return SARINS_OK;
}

/* The filter at the lat input with step dt and Fig. 2's thresholds (the model is set by the caller). */
static int build_updater(const sarins_ctx *c, dmu_state *s, double dt)
{
    char msg[MSG];
    double settings[SARINS_STOP_N_SETTINGS];
    filter_settings(c, settings);
    if (sarins_stop_kf_init(&s->kf, settings, c->r[SARINS_R_lat], dt, msg, sizeof msg) != SARINS_STOP_OK) {
        sarins_log(c, SARINS_ERROR, "input lat or the stop filter's settings: %s", msg);
        return SARINS_ERROR;
    }
    if (sarins_online_init(&s->upd, c->r[SARINS_R_time_threshold], c->r[SARINS_R_speed_threshold], msg, sizeof msg)
        != SARINS_ONLINE_OK) {
        sarins_log(c, SARINS_ERROR, "%s", msg);
        return SARINS_ERROR;
    }
    return SARINS_OK;
}

/* ------------------------------------------------------------------------------------------ outputs */

static int saturated(int64_t n) { return n > INT32_MAX ? INT32_MAX : (int)n; }

static void publish(sarins_ctx *c, const dmu_state *s, double compensation, double apply_from)
{
    double *r = c->r;
    for (int i = 0; i < 3; i++)
        r[(i == 0) ? SARINS_R_drift_a : (i == 1) ? SARINS_R_drift_b : SARINS_R_drift_c] = s->rls.x[i];
    for (int k = 0; k < 6; k++)
        r[P_SLOTS[k]] = s->rls.p[P_INDEX[k]];
    r[SARINS_R_model_time] = s->rls.time;
    r[SARINS_R_compensation_drift] = compensation;
    r[SARINS_R_apply_from] = apply_from;
    c->i[SARINS_I_stopped] = (int)s->upd.stopped;
    r[SARINS_R_stop_timer] = sarins_online_timer(&s->upd, &s->kf);
    r[SARINS_R_drift_estimate] = s->upd.stopped ? sarins_stop_kf_drift_estimate(&s->kf) : 0.0;
    r[SARINS_R_drift_estimate_std] = s->upd.stopped ? sarins_stop_kf_drift_std(&s->kf) : 0.0;
    c->i[SARINS_I_n_updates] = saturated(s->upd.n_updates);
    c->i[SARINS_I_n_resets] = saturated(s->upd.n_resets);
    if (s->upd.n_updates > 0) {
        r[SARINS_R_last_update_temp] = s->upd.last_update.temperature;
        r[SARINS_R_last_update_drift] = s->upd.last_update.drift;
    }
    if (s->upd.n_updates > 0 || s->upd.n_resets > 0) {
        const sarins_online_event *e = &s->upd.last;
        r[SARINS_R_last_stop_time] = e->time;
        r[SARINS_R_last_stop_duration] = e->duration;
        r[SARINS_R_last_stop_temp] = e->temperature;
        r[SARINS_R_last_stop_drift] = e->drift;
        r[SARINS_R_last_stop_drift_std] = e->drift_std;
        c->i[SARINS_I_last_stop_used] = (int)e->used;
    }
}

/* ------------------------------------------------------------------------------------------ speeds */

/* Keep (tag, speed) (a repeated tag, e.g. Jacobi's first step, is ignored; the oldest leaves when full). */
static int push_speed(const sarins_ctx *c, dmu_state *s, double tag, double speed, double step)
{
    if (!isfinite(tag)) {
        sarins_log(c, SARINS_ERROR, "speed_time is not finite");
        return SARINS_ERROR;
    }
    if (s->n_speeds > 0) {
        double last = s->speed_tag[s->n_speeds - 1];
        if (same_time(tag, last, step))
            return SARINS_OK;
        if (tag < last) {
            sarins_log(c, SARINS_ERROR, "speed_time went back from %.9g s to %.9g s", last, tag);
            return SARINS_ERROR;
        }
    }
    if (s->n_speeds == HISTORY) {
        memmove(s->speed_tag, s->speed_tag + 1, (HISTORY - 1) * sizeof(double));
        memmove(s->speed, s->speed + 1, (HISTORY - 1) * sizeof(double));
        s->n_speeds--;
    }
    s->speed_tag[s->n_speeds] = tag;
    s->speed[s->n_speeds] = speed;
    s->n_speeds++;
    return SARINS_OK;
}

/* The speed tagged tag (the newest of the same time). */
static int speed_at(const sarins_ctx *c, const dmu_state *s, double tag, double step, double *speed)
{
    for (int64_t k = s->n_speeds - 1; k >= 0; k--)
        if (same_time(s->speed_tag[k], tag, step)) {
            *speed = s->speed[k];
            return SARINS_OK;
        }
    char kept[96];
    if (s->n_speeds > 0)
        snprintf(kept, sizeof kept, "%.9g .. %.9g s", s->speed_tag[0], s->speed_tag[s->n_speeds - 1]);
    else
        snprintf(kept, sizeof kept, "none");
    sarins_log(c, SARINS_ERROR, "no vehicle_speed tagged speed_time=%.9g s to pair with (kept: %s; the vehicle_speed "
               "must arrive no later than, and at most %d steps before, the input it is paired with)", tag, kept,
               HISTORY - 1);
    return SARINS_ERROR;
}

/* ------------------------------------------------------------------------------------------ state check */

static int state_fail(const sarins_ctx *c, const char *what, const char *why)
{
    sarins_log(c, SARINS_ERROR, "the model state is not valid (%s%s%s)", what, why[0] ? ": " : "", why);
    return SARINS_ERROR;
}

static int same_rls_settings(const sarins_rls *a, const sarins_rls *b)
{
    return a->forgetting_factor == b->forgetting_factor && a->time_scale == b->time_scale;
}

/* Every field of the state within the invariants this model keeps after initialisation: the core
 * structs (their own checks), settings equal to the parameters, the filter's step equal to the
 * communication step (1 s before the first), a valid tag, the speed history's count within its buffer,
 * its tags finite and increasing, its unused slots zero.  For a state that arrived from outside (a
 * restored or deserialised FMU state). */
static int check_state(const sarins_ctx *c, const dmu_state *s)
{
    char msg[MSG];
    double settings[SARINS_STOP_N_SETTINGS];
    if (sarins_rls_check(&s->rls, msg, sizeof msg) != SARINS_RLS_OK)
        return state_fail(c, "model", msg);
    if (sarins_rls_check(&s->initial, msg, sizeof msg) != SARINS_RLS_OK)
        return state_fail(c, "initial model", msg);
    if (!same_rls_settings(&s->rls, &s->initial) || s->rls.forgetting_factor != c->r[SARINS_R_forgetting_factor]
        || s->rls.time_scale != c->r[SARINS_R_forgetting_time_scale])
        return state_fail(c, "forgetting settings differ from the parameters", "");
    if (sarins_stop_kf_check(&s->kf, msg, sizeof msg) != SARINS_STOP_OK)
        return state_fail(c, "stop filter", msg);
    if (!isfinite(s->kf.temperature_sum))
        return state_fail(c, "stop filter temperature sum not finite", "");
    filter_settings(c, settings);
    if (memcmp(settings, s->kf.settings, sizeof settings) != 0)
        return state_fail(c, "stop filter settings differ from the parameters", "");
    if (sarins_online_check(&s->upd, msg, sizeof msg) != SARINS_ONLINE_OK)
        return state_fail(c, "updater", msg);
    if (s->upd.time_threshold != c->r[SARINS_R_time_threshold]
        || s->upd.speed_threshold != c->r[SARINS_R_speed_threshold])
        return state_fail(c, "thresholds differ from the parameters", "");
    if (!s->upd.stopped && s->kf.n != 0)
        return state_fail(c, "rows recorded outside a stop", "");
    if (!isfinite(s->start_time) || !isfinite(s->step) || s->step < 0.0)
        return state_fail(c, "start time or step not valid", "");
    if (s->kf.dt != (s->step > 0.0 ? s->step : 1.0))
        return state_fail(c, "stop filter step differs from the communication step", "");
    if ((s->have_last_tag != 0 && s->have_last_tag != 1) || !isfinite(s->last_tag)
        || (!s->have_last_tag && s->last_tag != 0.0))
        return state_fail(c, "last row tag not valid", "");
    if (s->n_speeds < 0 || s->n_speeds > HISTORY)
        return state_fail(c, "speed history count out of its buffer", "");
    for (int64_t k = 0; k < HISTORY; k++) {
        if (k >= s->n_speeds) {
            if (s->speed_tag[k] != 0.0 || s->speed[k] != 0.0)
                return state_fail(c, "speed history unused slot not zero", "");
            continue;
        }
        if (!isfinite(s->speed_tag[k]) || !isfinite(s->speed[k]) || (k > 0 && !(s->speed_tag[k] > s->speed_tag[k - 1])))
            return state_fail(c, "speed history not finite or not increasing", "");
    }
    return SARINS_OK;
}

/* ------------------------------------------------------------------------------------------ callbacks */

static int initialize(sarins_ctx *c)
{
    dmu_state *s = (dmu_state *)c->state;
    dmu_state fresh;
    memset(&fresh, 0, sizeof fresh);
    if (check_parameters(c) != SARINS_OK) /* quiet (Initialization Mode): no output, nothing logged */
        return SARINS_ERROR;
    if (initial_model(c, &fresh.initial) != SARINS_OK || build_updater(c, &fresh, 1.0) != SARINS_OK)
        return SARINS_ERROR;
    fresh.rls = fresh.initial;
    fresh.start_time = c->start_time;
    if (!c->quiet && c->r[SARINS_R_speed_time] != NO_TAG
        && push_speed(c, &fresh, c->r[SARINS_R_speed_time], c->r[SARINS_R_vehicle_speed], 1.0) != SARINS_OK)
        return SARINS_ERROR;
    *s = fresh;
    publish(c, s, sarins_drift_model_value(s->rls.x, c->r[SARINS_R_temp_gyro_z]), NO_TAG);
    return SARINS_OK;
}

/* The first step fixes the step; the filter's interval is the communication step (rebuilt from the
 * initial model when it differs from the 1 s of initialisation). */
static int check_step(sarins_ctx *c, dmu_state *s, double h)
{
    if (s->step > 0.0) {
        if (sm_fabs(h - s->step) > STEP_TOL * s->step) {
            sarins_log(c, SARINS_ERROR, "communication step changed from %.17g s to %.17g s; this FMU needs a fixed "
                       "step", s->step, h);
            return SARINS_ERROR;
        }
        return SARINS_OK;
    }
    if (h != s->kf.dt) {
        if (build_updater(c, s, h) != SARINS_OK)
            return SARINS_ERROR; /* nothing changed: the filter's settings are checked before it is written */
        s->rls = s->initial;
    }
    s->step = h;
    return SARINS_OK;
}

/* The tag of the INS row to process now; *fresh = 0 if it is no new row. */
static int row_tag(const sarins_ctx *c, const dmu_state *s, double h, double *tag, int *fresh)
{
    int tagged = c->r[SARINS_R_solution_time] != NO_TAG;
    *tag = tagged ? c->r[SARINS_R_solution_time] : c->r[SARINS_R_nav_time];
    *fresh = 0;
    if (!isfinite(*tag)) {
        sarins_log(c, SARINS_ERROR, "the INS row's tag (solution_time) is not finite");
        return SARINS_ERROR;
    }
    if (tagged && *tag <= s->start_time + TAG_TOL * h)
        return SARINS_OK; /* the INS's initial outputs: no interval integrated yet */
    if (s->have_last_tag && same_time(*tag, s->last_tag, h))
        return SARINS_OK; /* the same row again (Jacobi's first steps) */
    int have_expected = tagged || s->have_last_tag;
    double expected = s->have_last_tag ? s->last_tag + h : s->start_time + h;
    if (have_expected && !same_time(*tag, expected, h)) {
        sarins_log(c, SARINS_ERROR, "INS row tagged %s=%.9g s where the row at %.9g s was due: rows must follow each "
                   "other one step apart (none skipped or repeated)", tagged ? "solution_time" : "nav_time", *tag,
                   expected);
        return SARINS_ERROR;
    }
    *fresh = 1;
    return SARINS_OK;
}

static int do_step(sarins_ctx *c, double t, double h)
{
    (void)t;
    dmu_state *s = (dmu_state *)c->state;
    const double *r = c->r;
    char msg[MSG];
    if (check_state(c, s) != SARINS_OK || check_step(c, s, h) != SARINS_OK)
        return SARINS_ERROR;
    static const unsigned INPUTS[9] = {SARINS_R_v_e, SARINS_R_v_n, SARINS_R_yaw, SARINS_R_pitch, SARINS_R_roll,
                                       SARINS_R_temp_gyro_z, SARINS_R_vehicle_speed, SARINS_R_lat, SARINS_R_nav_time};
    for (int k = 0; k < 9; k++)
        if (!isfinite(r[INPUTS[k]])) {
            sarins_log(c, SARINS_ERROR, "an input (velocity, attitude, temperature, speed or nav_time) is NaN or "
                       "infinite");
            return SARINS_ERROR;
        }
    int speed_tagged = r[SARINS_R_speed_time] != NO_TAG;
    if (speed_tagged) {
        if (r[SARINS_R_solution_time] == NO_TAG) {
            sarins_log(c, SARINS_ERROR, "vehicle_speed is tagged (speed_time is connected) but the INS rows are not: "
                       "connect the INS's solution_time to pair each row with the speed of its time");
            return SARINS_ERROR;
        }
        if (push_speed(c, s, r[SARINS_R_speed_time], r[SARINS_R_vehicle_speed], h) != SARINS_OK)
            return SARINS_ERROR;
    }
    double tag, speed = r[SARINS_R_vehicle_speed];
    int fresh;
    if (row_tag(c, s, h, &tag, &fresh) != SARINS_OK)
        return SARINS_ERROR;
    if (!fresh)
        return SARINS_OK; /* no new INS row: nothing changes */
    if (speed_tagged && speed_at(c, s, tag, h, &speed) != SARINS_OK)
        return SARINS_ERROR;
    s->last_tag = tag;
    s->have_last_tag = 1;
    const double time = r[SARINS_R_start_day] * DAY + r[SARINS_R_nav_time];
    const double velocity[2] = {r[SARINS_R_v_e], r[SARINS_R_v_n]};
    const double attitude[3] = {r[SARINS_R_yaw], r[SARINS_R_pitch], r[SARINS_R_roll]};
    const unsigned char active = c->i[SARINS_I_ins_phase] == NAVIGATE && r[SARINS_R_nav_time] >= 0.0;
    double comp;
    sarins_online_event event;
    int64_t n_events;
    if (sarins_online_rows(&s->upd, &s->rls, &s->kf, 1, &time, &speed, velocity, attitude, &r[SARINS_R_temp_gyro_z],
                           &r[SARINS_R_lat], &active, &comp, &event, 1, &n_events, msg, sizeof msg)
        != SARINS_ONLINE_OK) {
        sarins_log(c, SARINS_ERROR, "%s", msg);
        return SARINS_ERROR;
    }
    c->r[SARINS_R_row_time] = tag;
    publish(c, s, comp, r[SARINS_R_nav_time] + r[SARINS_R_latency]);
    return SARINS_OK;
}

static void release(sarins_ctx *c) { c->work = NULL; /* nothing allocated: the state struct is all */ }

/* Every field of the state within what do_step relies on (model.h, State validation): the RLS models, the
 * stop filter and the stop record by the core's own checks, then the glue's own fields. */
static int dmu_check_state(const sarins_ctx *c, int running)
{
    const dmu_state *s = c->state;
    char msg[MSG];
    if (running) {
        if (sarins_rls_check(&s->rls, msg, sizeof msg) != SARINS_RLS_OK
            || sarins_rls_check(&s->initial, msg, sizeof msg) != SARINS_RLS_OK
            || sarins_stop_kf_check(&s->kf, msg, sizeof msg) != 0
            || sarins_online_check(&s->upd, msg, sizeof msg) != 0) {
            sarins_log(c, SARINS_ERROR, "the state's model or filter: %s", msg);
            return SARINS_ERROR;
        }
    }
    if (!sarins_state_real(c, "start_time", s->start_time, -1e300, 1e300)
        || !sarins_state_real(c, "step", s->step, 0.0, 1e300)
        || !sarins_state_int(c, "have_last_tag", s->have_last_tag, 0, 1)
        || (s->have_last_tag && !sarins_state_real(c, "last_tag", s->last_tag, -1e300, 1e300))
        || !sarins_state_int(c, "n_speeds", s->n_speeds, 0, HISTORY)
        || !sarins_state_finite(c, "speed_tag", s->speed_tag, (size_t)s->n_speeds)
        || !sarins_state_finite(c, "speed", s->speed, (size_t)s->n_speeds))
        return SARINS_ERROR;
    return SARINS_OK;
}

const sarins_model sarins_model_desc = {
    .table = &SARINS_TABLE,
    .state_size = sizeof(dmu_state),
    .state_version = 1,
    .check_state = dmu_check_state,
    .initialize = initialize,
    .do_step = do_step,
    .release = release,
    .terminate = NULL,
    .work_state_size = NULL,
    .save_work_state = NULL,
    .load_work_state = NULL,
};
