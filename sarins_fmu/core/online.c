#include "smath.h"

#include "online.h"

#include <stddef.h>

#include "report.h"

int sarins_online_init(sarins_online *u, double time_threshold, double speed_threshold, char *msg, size_t size)
{
    report r = sarins_report(msg, size);
    const double values[2] = {time_threshold, speed_threshold};
    const char *const names[2] = {"time_threshold", "speed_threshold"};
    for (int i = 0; i < 2; i++)
        if (!(isfinite(values[i]) && values[i] > 0.0)) {
            char text[40];
            sarins_format_number(text, sizeof text, values[i]);
            return sarins_fail(&r, SARINS_ONLINE_BAD, "%s must be positive and finite, got %s", names[i], text);
        }
    const sarins_online_event none = {0.0, 0.0, 0.0, 0.0, 0.0, 0};
    u->time_threshold = time_threshold;
    u->speed_threshold = speed_threshold;
    u->stopped = 0;
    u->n_updates = 0;
    u->n_resets = 0;
    u->last = none;
    u->last_update = none;
    return SARINS_ONLINE_OK;
}

int sarins_online_finish(sarins_online *u, sarins_rls *rls, sarins_stop_kf *kf, double time,
                         sarins_online_event *event, int *finished, char *msg, size_t size)
{
    *finished = 0;
    if (!u->stopped)
        return SARINS_ONLINE_OK;
    sarins_online_event e;
    e.time = time;
    e.duration = sarins_stop_kf_elapsed(kf);
    e.temperature = sarins_stop_kf_mean_temperature(kf);
    e.drift = sarins_stop_kf_drift_estimate(kf);
    e.drift_std = sarins_stop_kf_drift_std(kf);
    e.used = e.duration >= u->time_threshold - SARINS_ONLINE_TIME_TOL;
    if (e.used && sarins_rls_update(rls, e.temperature, e.drift, time, msg, size) != SARINS_RLS_OK)
        return SARINS_ONLINE_BAD;
    if (e.used) {
        u->n_updates += 1;
        u->last_update = e;
    } else {
        u->n_resets += 1;
    }
    u->last = e;
    /* the stop's latitude was checked at its reset: this reset cannot fail */
    (void)sarins_stop_kf_reset(kf, kf->lat, NULL, 0);
    u->stopped = 0;
    if (event != NULL)
        *event = e;
    *finished = 1;
    return SARINS_ONLINE_OK;
}

int sarins_online_rows(sarins_online *u, sarins_rls *rls, sarins_stop_kf *kf, int64_t k, const double *time,
                       const double *speed, const double *velocity_en, const double *attitude,
                       const double *temperature, const double *lat, const unsigned char *active, double *comp,
                       sarins_online_event *events, int64_t max_events, int64_t *n_events, char *msg, size_t size)
{
    report r = sarins_report(msg, size);
    *n_events = 0;
    if (k < 0 || max_events < 0 || (k > 0 && max_events < k / 2 + 1))
        return sarins_fail(&r, SARINS_ONLINE_BAD, "rows (%lld) or room for events (%lld) out of range",
                           (long long)k, (long long)max_events);
    static const char *const NAMES[3] = {"time", "speed", "temperature"};
    const double *columns[3] = {time, speed, temperature};
    for (int c = 0; c < 3; c++)
        for (int64_t s = 0; s < k; s++)
            if (!isfinite(columns[c][s]))
                return sarins_fail(&r, SARINS_ONLINE_BAD, "%s contains NaN or infinity", NAMES[c]);
    for (int64_t s = 0; s < k; s++) {
        int still = sm_fabs(speed[s]) < u->speed_threshold && (active == NULL || active[s]);
        if (!still && u->stopped) {
            int finished;
            if (sarins_online_finish(u, rls, kf, time[s], events + *n_events, &finished, msg, size)
                != SARINS_ONLINE_OK)
                return SARINS_ONLINE_BAD;
            *n_events += finished;
        }
        comp[s] = sarins_drift_model_value(rls->x, temperature[s]);
        if (!still)
            continue;
        if (!u->stopped) { /* a stop begins: reset the filter, start the timer */
            if (sarins_stop_kf_reset(kf, lat == NULL ? kf->lat : lat[s], msg, size) != SARINS_STOP_OK)
                return SARINS_ONLINE_BAD;
            u->stopped = 1;
        }
        if (sarins_stop_kf_steps(kf, 1, velocity_en + 2 * s, attitude + 3 * s, comp + s, temperature + s, NULL, msg,
                                 size) != SARINS_STOP_OK)
            return SARINS_ONLINE_BAD;
    }
    return SARINS_ONLINE_OK;
}

double sarins_online_timer(const sarins_online *u, const sarins_stop_kf *kf)
{
    return u->stopped ? sarins_stop_kf_elapsed(kf) : 0.0;
}

static int event_ok(const sarins_online_event *e)
{
    return isfinite(e->time) && isfinite(e->duration) && e->duration >= 0.0 && isfinite(e->temperature)
           && isfinite(e->drift) && isfinite(e->drift_std) && e->drift_std >= 0.0 && (e->used == 0 || e->used == 1);
}

int sarins_online_check(const sarins_online *u, char *msg, size_t size)
{
    report r = sarins_report(msg, size);
    if (!(isfinite(u->time_threshold) && u->time_threshold > 0.0 && isfinite(u->speed_threshold)
          && u->speed_threshold > 0.0))
        return sarins_fail(&r, SARINS_ONLINE_BAD, "updater thresholds not positive and finite");
    if (u->stopped != 0 && u->stopped != 1)
        return sarins_fail(&r, SARINS_ONLINE_BAD, "updater stop flag not 0 or 1");
    if (u->n_updates < 0 || u->n_resets < 0 || u->n_updates > SARINS_ONLINE_MAX_COUNT
        || u->n_resets > SARINS_ONLINE_MAX_COUNT)
        return sarins_fail(&r, SARINS_ONLINE_BAD, "updater event counts not 0 .. 2^53");
    if (!event_ok(&u->last) || !event_ok(&u->last_update))
        return sarins_fail(&r, SARINS_ONLINE_BAD, "updater event record not finite or not valid");
    return SARINS_ONLINE_OK;
}

int64_t sarins_online_layout(int64_t *event_size, int64_t *offsets)
{
    *event_size = (int64_t)sizeof(sarins_online_event);
    offsets[0] = (int64_t)offsetof(sarins_online, stopped);
    offsets[1] = (int64_t)offsetof(sarins_online, n_updates);
    offsets[2] = (int64_t)offsetof(sarins_online, n_resets);
    offsets[3] = (int64_t)offsetof(sarins_online, last);
    offsets[4] = (int64_t)offsetof(sarins_online, last_update);
    return (int64_t)sizeof(sarins_online);
}
