/* Ambient temperature and the thermal chamber's programme (ambient.h). */
#include "smath.h"

#include "ambient.h"
#include "report.h"
#include "schedule.h"

#include <string.h>

#define PI 3.14159265358979323846

/* Linear interpolation in a strictly increasing table, held at both ends (numpy.interp's arithmetic). */
static double interp(double x, int64_t n, const double *xp, const double *fp)
{
    if (isnan(x))
        return x;
    if (x < xp[0])
        return fp[0];
    if (x >= xp[n - 1]) /* also a table of one point */
        return fp[n - 1];
    int64_t lo = 0, hi = n - 1; /* xp[lo] <= x < xp[hi] */
    while (hi - lo > 1) {
        int64_t mid = lo + (hi - lo) / 2;
        if (xp[mid] <= x)
            lo = mid;
        else
            hi = mid;
    }
    if (xp[lo] == x)
        return fp[lo];
    double slope = (fp[lo + 1] - fp[lo]) / (xp[lo + 1] - xp[lo]);
    double y = slope * (x - xp[lo]) + fp[lo];
    if (isnan(y)) { /* nan one way: try the other */
        y = slope * (x - xp[lo + 1]) + fp[lo + 1];
        if (isnan(y) && fp[lo] == fp[lo + 1])
            y = fp[lo];
    }
    return y;
}

double sarins_ambient_at(const sarins_ambient *a, double t)
{
    if (a->n_profile > 0)
        return interp(t, a->n_profile, a->profile_times, a->profile_temps);
    if (a->amplitude == 0.0 && a->slope == 0.0)
        return a->mean;
    /* T = mean + amplitude sin(2 pi t / period + phase) + slope t */
    return a->mean + a->amplitude * sm_sin(2 * PI * t / a->period + a->phase) + a->slope * t;
}

void sarins_ambient_values(const sarins_ambient *a, int64_t n, const double *t, double *out)
{
    for (int64_t i = 0; i < n; i++)
        out[i] = sarins_ambient_at(a, t[i]);
}

int sarins_ambient_segment(const sarins_ambient *a, double t, double span, double *value, double *slope,
                           char *msg, size_t msg_len)
{
    report r = sarins_report(msg, msg_len);
    if (!(span > 0 && isfinite(span))) {
        char num[40];
        sarins_format_number(num, sizeof num, span);
        return sarins_fail(&r, SARINS_SCHEDULE_BAD_PARAM, "span must be positive and finite, got %s", num);
    }
    double a0 = sarins_ambient_at(a, t);
    *value = a0;
    /* slope of the ambient sampled on a grid of span s, linear in between */
    *slope = (sarins_ambient_at(a, t + span) - a0) / span;
    return 0;
}

/* ------------------------------------------------------------------ chamber */

void sarins_chamber_params_default(sarins_chamber_params *p)
{
    memset(p, 0, sizeof *p);
    p->duration = 100 * 3600.0;
    p->low = -25.0;
    p->high = 40.0;
    p->ramp = 1.0 / 60.0;
    p->hold = 30.0 * 60.0;
    p->start = 20.0;
    p->delay = 0.0;
    p->first = "low";
    p->step = 0.0;
    p->step_hold = 0.0;
}

static int check(report *r, const char *name, double v, int positive, const char *unit)
{
    if (r->code)
        return r->code;
    char num[40];
    sarins_format_number(num, sizeof num, v);
    if (!isfinite(v))
        return sarins_fail(r, SARINS_SCHEDULE_BAD_PARAM, "%s must be finite, got %s%s", name, num, unit);
    if (v < 0 || (positive && v == 0))
        return sarins_fail(r, SARINS_SCHEDULE_BAD_PARAM, "%s must be %s, got %s%s", name,
                           positive ? "positive" : "non-negative", num, unit);
    return 0;
}

static int check_chamber(const sarins_chamber_params *p, report *r)
{
    check(r, "duration", p->duration, 1, " s");
    check(r, "ramp", p->ramp, 1, " degC/s");
    check(r, "hold", p->hold, 0, " s");
    check(r, "delay", p->delay, 0, " s");
    const char *names[3] = {"low", "high", "start"};
    const double values[3] = {p->low, p->high, p->start};
    for (int i = 0; i < 3 && !r->code; i++)
        if (!isfinite(values[i])) {
            char num[40];
            sarins_format_number(num, sizeof num, values[i]);
            sarins_fail(r, SARINS_SCHEDULE_BAD_PARAM, "%s must be finite, got %s degC", names[i], num);
        }
    if (r->code)
        return r->code;
    char lo[40], hi[40];
    sarins_format_number(lo, sizeof lo, p->low);
    sarins_format_number(hi, sizeof hi, p->high);
    if (!(p->low < p->high))
        return sarins_fail(r, SARINS_SCHEDULE_BAD_PARAM, "low must be below high, got %s and %s degC", lo, hi);
    if (p->low <= -273.15)
        return sarins_fail(r, SARINS_SCHEDULE_BAD_PARAM, "low must be above absolute zero, got %s degC", lo);
    if (p->first == NULL || (strcmp(p->first, "low") != 0 && strcmp(p->first, "high") != 0))
        return sarins_fail(r, SARINS_SCHEDULE_BAD_PARAM, "first must be 'low' or 'high', got '%.40s'",
                           p->first == NULL ? "(null)" : p->first);
    check(r, "step", p->step, 0, " degC");
    check(r, "step_hold", p->step_hold, 0, " s");
    return r->code;
}

/* Intermediate set points every `step` from one end towards the other, both ends excluded. */
static double n_stops(double from, double to, double step)
{
    if (step <= 0)
        return 0.0;
    double n = sm_ceil(sm_fabs(to - from) / step - 1e-9) - 1;
    return n > 0 ? n : 0.0;
}

/* Builds (or only counts, times NULL) the programme's breakpoints before `duration` and the cut point. */
typedef struct {
    report *r;
    double duration;
    int64_t capacity;
    double *times, *temps;
    double t_last, v_last;   /* the last breakpoint of the uncut programme */
    int64_t n_made;          /* breakpoints of the uncut programme so far */
    int64_t n_kept;          /* of them before `duration` (written) */
    int done;                /* the cut point is written */
} chamber;

static void put(chamber *c, double t, double v)
{
    if (c->r->code)
        return;
    if (c->times != NULL) {
        if (c->n_kept >= c->capacity) {
            sarins_fail(c->r, SARINS_SCHEDULE_CAPACITY, "the chamber profile has more than the %lld points allocated",
                        (long long)c->capacity);
            return;
        }
        c->times[c->n_kept] = t;
        c->temps[c->n_kept] = v;
    }
    c->n_kept++;
}

/* The next breakpoint (t, v), if later than the last one. */
static void to(chamber *c, double t, double v)
{
    if (!(t > c->t_last) || c->r->code)
        return;
    if (++c->n_made > SARINS_CHAMBER_MAX_POINTS) {
        sarins_fail(c->r, SARINS_SCHEDULE_TOO_BIG,
                    "the chamber profile needs more than %lld points: shorten the duration or widen the steps",
                    (long long)SARINS_CHAMBER_MAX_POINTS);
        return;
    }
    if (!c->done) {
        if (t < c->duration) {
            put(c, t, v);
        } else { /* the cut: the value at `duration`, interpolated */
            double xp[2] = {c->t_last, t}, fp[2] = {c->v_last, v};
            put(c, c->duration, interp(c->duration, 2, xp, fp));
            c->done = 1;
        }
    }
    c->t_last = t;
    c->v_last = v;
}

static void ramp_to(chamber *c, const sarins_chamber_params *p, double target, double from, double to_end,
                    double stops)
{
    for (double i = 0; i < stops && !c->r->code; i++) {
        double point = from + sm_copysign(p->step * (i + 1), to_end - from);
        to(c, c->t_last + sm_fabs(point - c->v_last) / p->ramp, point);
        to(c, c->t_last + p->step_hold, point);
    }
    to(c, c->t_last + sm_fabs(target - c->v_last) / p->ramp, target);
}

static int chamber_run(const sarins_chamber_params *p, report *r, int64_t capacity, double *times, double *temps,
                       int64_t *n_points)
{
    *n_points = 0;
    if (check_chamber(p, r))
        return r->code;
    chamber c;
    memset(&c, 0, sizeof c);
    c.r = r;
    c.duration = p->duration;
    c.capacity = capacity;
    c.times = times;
    c.temps = temps;
    c.n_made = 1;
    put(&c, 0.0, p->start);
    c.t_last = 0.0;
    c.v_last = p->start;
    to(&c, p->delay, p->start);
    double target = strcmp(p->first, "low") == 0 ? p->low : p->high;
    double from = 0.0, to_end = 0.0, stops = 0.0; /* the first ramp, from start, has no stops */
    int idle = 0; /* iterations in a row that added no breakpoint */
    while (c.t_last < p->duration && !r->code) {
        double before = c.t_last;
        ramp_to(&c, p, target, from, to_end, stops);
        to(&c, c.t_last + p->hold, target);
        from = target;
        to_end = p->low + p->high - target;
        stops = n_stops(from, to_end, p->step);
        target = target == p->low ? p->high : p->low;
        idle = c.t_last > before ? 0 : idle + 1;
        if (idle >= 3) /* the state repeats every 2 iterations: stuck for ever */
            sarins_fail(r, SARINS_SCHEDULE_TOO_BIG,
                        "the chamber programme does not advance at t = %.9g s: the ramps and holds are too short "
                        "for that time", before);
    }
    if (r->code)
        return r->code;
    *n_points = c.n_kept;
    return 0;
}

int sarins_chamber_size(const sarins_chamber_params *p, int64_t *n_points, char *msg, size_t msg_len)
{
    report r = sarins_report(msg, msg_len);
    return chamber_run(p, &r, 0, NULL, NULL, n_points);
}

int sarins_chamber_build(const sarins_chamber_params *p, int64_t capacity, double *times, double *temps,
                         int64_t *n_points, char *msg, size_t msg_len)
{
    report r = sarins_report(msg, msg_len);
    if (times == NULL || temps == NULL || capacity < 2) {
        *n_points = 0;
        return sarins_fail(&r, SARINS_SCHEDULE_CAPACITY, "the chamber profile's arrays are missing or too short");
    }
    return chamber_run(p, &r, capacity, times, temps, n_points);
}

int sarins_chamber_cycle_time(const sarins_chamber_params *p, double *cycle, char *msg, size_t msg_len)
{
    report r = sarins_report(msg, msg_len);
    check(&r, "ramp", p->ramp, 1, " degC/s");
    check(&r, "step", p->step, 0, " degC");
    check(&r, "hold", p->hold, 0, " s");
    check(&r, "step_hold", p->step_hold, 0, " s");
    if (r.code)
        return r.code;
    /* 2 (ramp end to end + hold + stops) */
    *cycle = 2.0 * ((p->high - p->low) / p->ramp + p->hold + n_stops(p->low, p->high, p->step) * p->step_hold);
    return 0;
}
