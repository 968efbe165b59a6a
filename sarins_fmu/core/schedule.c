/* Turntable schedules generated from parameters (schedule.h). */
#include "smath.h"

#include "schedule.h"
#include "report.h"

#include <ctype.h>
#include <string.h>

#define PI 3.14159265358979323846
#define DEG_TO_RAD (PI / 180.0)
#define QUARTER (0.5 * PI)   /* a quarter turn, rad */
#define MAX_STEPS 9007199254740992.0 /* 2^53: grid steps are counted exactly in a double */
#define MAX_TRACK 4          /* segments of a track's repeating pattern */

static const double RATE_TEST_MAGNITUDES_DPS[SARINS_RATE_TEST_N_MAGNITUDES] = {
    1.0, 2.0, 3.0, 5.0, 10.0, 20.0, 30.0, 50.0, 100.0, 150.0, 200.0};

enum { NONE, CONTINUOUS, FORWARD_REVERSE, FOUR_POSITION, DUAL_AXIS, RATE_TABLE_3AXIS, TUMBLE_24, RATE_TEST,
       N_SCHEMES };

static const char *const SCHEME_NAMES[N_SCHEMES] = {
    "none", "continuous", "forward-reverse", "four-position", "dual-axis", "rate-table-3axis", "tumble-24",
    "rate-test"};

static const char *const CHAINS[N_SCHEMES] = {"z", "z", "z", "z", "y,z", "z,x,y", "z,x,y", "z,x,y"};

static int scheme_index(const char *name)
{
    if (name == NULL)
        return -1;
    for (int i = 0; i < N_SCHEMES; i++)
        if (strcmp(name, SCHEME_NAMES[i]) == 0)
            return i;
    return -1;
}

const char *sarins_scheme_gimbal_axes(const char *scheme)
{
    int i = scheme_index(scheme);
    return i < 0 ? NULL : CHAINS[i];
}

void sarins_rate_test_magnitudes_dps(double *out)
{
    for (int i = 0; i < SARINS_RATE_TEST_N_MAGNITUDES; i++)
        out[i] = RATE_TEST_MAGNITUDES_DPS[i];
}

void sarins_schedule_params_default(sarins_schedule_params *p)
{
    memset(p, 0, sizeof *p);
    p->scheme = "forward-reverse";
    p->duration = 100 * 3600.0;
    p->rate = 6.0 * DEG_TO_RAD;
    p->accel = 6.0 * DEG_TO_RAD;
    p->dwell = 0.0;
    p->revolutions = 1.0;
    p->align_time = 4 * 3600.0;
    p->align_dwell = 300.0;
    p->grid = 1.0;
    p->outer_rate = 6.0 * DEG_TO_RAD;
    p->outer_accel = 6.0 * DEG_TO_RAD;
    p->table_inner_rate = 1.0 * DEG_TO_RAD;
    p->table_middle_rate = 10.0 * DEG_TO_RAD;
    p->table_outer_rate = 100.0 * DEG_TO_RAD;
    p->table_inner_accel = 0.01 * DEG_TO_RAD;
    p->table_middle_accel = 0.1 * DEG_TO_RAD;
    p->table_outer_accel = 1.0 * DEG_TO_RAD;
    p->warmup = 600.0;
    p->test_rates = NULL;
    p->n_test_rates = 0;
    p->test_axes = NULL;
    p->test_min_duration = 0.0;
    p->test_rate_tol = 1e-3;
}

/* ------------------------------------------------------------------ checks */

/* kinds of quantity, for the unit in messages */
enum { SECONDS, ANGLE_RATE, ANGLE_ACCEL, PLAIN };

static int check(report *r, const char *name, double v, int positive, int kind)
{
    if (r->code)
        return r->code;
    char num[40], deg[40];
    sarins_format_number(num, sizeof num, v);
    const char *unit = kind == SECONDS ? " s" : kind == ANGLE_RATE ? " rad/s" : kind == ANGLE_ACCEL ? " rad/s^2" : "";
    const char *deg_unit = kind == ANGLE_RATE ? " deg/s" : " deg/s^2";
    deg[0] = '\0';
    if (kind == ANGLE_RATE || kind == ANGLE_ACCEL) {
        char d[40];
        sarins_format_number(d, sizeof d, v / DEG_TO_RAD);
        sarins_join(deg, sizeof deg, " (", d, deg_unit, ")");
    }
    if (!isfinite(v))
        return sarins_fail(r, SARINS_SCHEDULE_BAD_PARAM, "%s must be finite, got %s%s%s", name, num, unit, deg);
    if (v < 0 || (positive && v == 0))
        return sarins_fail(r, SARINS_SCHEDULE_BAD_PARAM, "%s must be %s, got %s%s%s", name,
                           positive ? "positive" : "non-negative", num, unit, deg);
    return 0;
}

/* Whole grid steps covering duration (0 for 0), as a double: max(0, ceil(duration / grid - 1e-9)). */
static double ceil_steps(report *r, double duration, double grid)
{
    double n = sm_ceil(duration / grid - 1e-9);
    if (!(n <= MAX_STEPS)) {
        sarins_fail(r, SARINS_SCHEDULE_TOO_BIG, "a span of %.9g s is more than 2^53 steps of the %.9g s grid",
                    duration, grid);
        return 0.0;
    }
    return n > 0.0 ? n : 0.0;
}

/* duration rounded up to whole steps of grid (at least one step), s */
static double ceil_to_grid(report *r, double duration, double grid)
{
    double n = ceil_steps(r, duration, grid);
    return (n >= 1.0 ? n : 1.0) * grid;
}

/* x rounded half to even, checked to be a whole number of at most 2^53 */
static double round_steps(report *r, double x)
{
    double n = sm_nearbyint(x);
    if (!(sm_fabs(n) <= MAX_STEPS)) {
        sarins_fail(r, SARINS_SCHEDULE_TOO_BIG, "%.9g grid steps are more than 2^53", x);
        return 0.0;
    }
    return n;
}

/* ------------------------------------------------------------------ moves */

/* Rest-to-rest move through angle (rad): up to 3 segments (duration s, accel rad/s^2) in dur, acc; returns
 * their number.  rate_max, accel_max and grid are positive. */
static int move(report *r, double angle, double rate_max, double accel_max, double grid, double *dur,
                double *acc)
{
    if (angle == 0.0)
        return 0;
    double sign = angle > 0 ? 1.0 : -1.0;
    angle = sm_fabs(angle);
    double t_acc = ceil_to_grid(r, rate_max / accel_max, grid), t_cruise;
    if (rate_max * t_acc >= angle) { /* triangular profile: no cruise phase */
        t_acc = ceil_to_grid(r, sm_sqrt(angle / accel_max), grid);
        t_cruise = 0.0;
    } else {
        t_cruise = ceil_to_grid(r, angle / rate_max - t_acc, grid);
    }
    /* area of the trapezoid = angle */
    double rate = angle / (t_acc + t_cruise);
    double a = rate / t_acc;
    int n = 0;
    dur[n] = t_acc;
    acc[n++] = sign * a;
    if (t_cruise > 0) {
        dur[n] = t_cruise;
        acc[n++] = 0.0;
    }
    dur[n] = t_acc;
    acc[n++] = -sign * a;
    return n;
}

int sarins_move_segments(double angle, double rate_max, double accel_max, double grid, double *duration,
                         double *seg_accel, int64_t *n, char *msg, size_t msg_len)
{
    report r = sarins_report(msg, msg_len);
    *n = 0;
    if (angle == 0.0) /* no move, whatever the rest */
        return 0;
    if (!(isfinite(angle) && isfinite(rate_max) && isfinite(accel_max) && isfinite(grid)))
        return sarins_fail(&r, SARINS_SCHEDULE_BAD_PARAM, "angle, rate, acceleration and grid must be finite");
    if (!(rate_max > 0 && accel_max > 0 && grid > 0))
        return sarins_fail(&r, SARINS_SCHEDULE_BAD_PARAM, "rate, acceleration and grid must be positive");
    int k = move(&r, angle, rate_max, accel_max, grid, duration, seg_accel);
    if (r.code)
        return r.code;
    *n = k;
    return 0;
}

/* ------------------------------------------------------------------ output */

/* Collects segments (a duration or a number of grid steps, and the accelerations of the n_axes gimbals)
 * into the breakpoint tables, or only counts them (s == NULL or its arrays NULL).  Two forms:
 *   steps (the rate-table profiles and dual-axis): durations are whole grid steps, equal consecutive
 *       accelerations merge, times[m] = grid * N_m (N_m steps so far), and each segment's acceleration is
 *       scaled by n grid / (times[m+1] - times[m]) so its rate change is exactly accel * n * grid;
 *   seconds (single-axis): durations are s, times are their running sum, nothing merges. */
typedef struct {
    report *r;
    sarins_schedule *s;      /* NULL: count only */
    int64_t n_axes;
    int steps;               /* 1: the steps form, 0: the seconds form */
    double grid;
    int pending;             /* a segment waits to be merged with the next one (steps form) */
    double pend_n;           /* its steps */
    double pend_acc[SARINS_SCHEDULE_MAX_AXES];
    int64_t n_seg;           /* segments written (or counted) */
    double now;              /* steps form: grid steps so far (merged or pending) */
    double written_steps;    /* steps form: steps in written segments */
    double t_sum;            /* seconds form: running sum of durations, s */
    double t_last;           /* time of the last breakpoint written, s */
    int64_t n_windows;
} sink;

static void write_segment(sink *k, double length, const double *acc)
{
    report *r = k->r;
    if (r->code)
        return;
    if (k->n_seg + 2 > SARINS_SCHEDULE_MAX_BREAKPOINTS) {
        sarins_fail(r, SARINS_SCHEDULE_TOO_BIG,
                    "the schedule needs more than %lld breakpoints: shorten the duration or coarsen the grid",
                    (long long)SARINS_SCHEDULE_MAX_BREAKPOINTS);
        return;
    }
    double t1;
    if (k->steps) {
        k->written_steps += length;
        /* times = grid * cumsum(n) */
        t1 = k->grid * k->written_steps;
    } else {
        /* times = cumsum(durations) */
        k->t_sum = (k->n_seg == 0) ? length : k->t_sum + length;
        t1 = 0.0 + k->t_sum;
    }
    if (!(t1 > k->t_last)) {
        sarins_fail(r, SARINS_SCHEDULE_BAD_PARAM,
                    "breakpoint times must be strictly increasing (a segment of %.9g s vanishes at t = %.9g s)",
                    length, k->t_last);
        return;
    }
    sarins_schedule *s = k->s;
    if (s != NULL && s->times != NULL) {
        if (k->n_seg + 2 > s->capacity) {
            sarins_fail(r, SARINS_SCHEDULE_CAPACITY, "the schedule has more than the %lld breakpoints allocated",
                        (long long)s->capacity);
            return;
        }
        s->times[k->n_seg + 1] = t1;
        double *a = s->accel + k->n_axes * k->n_seg;
        /* n_axes is 1 .. 3 by construction; the explicit bound lets GCC -O3 -march=native (znver) see that acc's
         * row is never read past its end, which it otherwise reports as maybe-uninitialized */
        const int64_t n_axes = k->n_axes < SARINS_SCHEDULE_MAX_AXES ? k->n_axes : SARINS_SCHEDULE_MAX_AXES;
        if (k->steps) {
            /* accel * (n grid) / diff(times) */
            double ratio = (length * k->grid) / (t1 - k->t_last);
            for (int64_t j = 0; j < n_axes; j++)
                a[j] = acc[j] * ratio;
        } else {
            for (int64_t j = 0; j < n_axes; j++)
                a[j] = acc[j];
        }
    }
    k->t_last = t1;
    k->n_seg++;
}

static int same(const double *a, const double *b, int64_t n)
{
    for (int64_t j = 0; j < n; j++)
        if (!(a[j] == b[j]))
            return 0;
    return 1;
}

/* The steps form: n grid steps at acc (merged with the previous segment when equal). */
static void emit_steps(sink *k, double n, const double *acc)
{
    if (k->r->code || n <= 0)
        return;
    k->now += n;
    if (k->pending && same(k->pend_acc, acc, k->n_axes)) {
        k->pend_n += n;
        return;
    }
    if (k->pending)
        write_segment(k, k->pend_n, k->pend_acc);
    k->pending = 1;
    k->pend_n = n;
    for (int64_t j = 0; j < k->n_axes; j++)
        k->pend_acc[j] = acc[j];
}

static void rest(sink *k, double n)
{
    static const double zeros[SARINS_SCHEDULE_MAX_AXES] = {0.0};
    emit_steps(k, n, zeros);
}

/* The seconds form: one gimbal (single-axis). */
static void emit_seconds(sink *k, double duration, double acc)
{
    const double a[SARINS_SCHEDULE_MAX_AXES] = {acc}; /* n_axes is 1 here; a whole row keeps GCC -O3 quiet */
    write_segment(k, duration, a);
}

static void push_window(sink *k, const sarins_schedule_window *w)
{
    if (k->r->code)
        return;
    sarins_schedule *s = k->s;
    if (s != NULL && s->windows != NULL) {
        if (k->n_windows >= s->window_capacity) {
            sarins_fail(k->r, SARINS_SCHEDULE_CAPACITY, "the schedule has more than the %lld windows allocated",
                        (long long)s->window_capacity);
            return;
        }
        s->windows[k->n_windows] = *w;
    }
    k->n_windows++;
}

/* A gimbal's part in a block of simultaneous motion: a pattern of up to MAX_TRACK segments (grid steps,
 * accel) repeated `repeat` times. */
typedef struct {
    int n;
    double steps[MAX_TRACK];
    double acc[MAX_TRACK];
    double repeat;
} track;

/* Runs the tracks of the gimbals (NULL or an empty track: the gimbal rests) simultaneously from now; the
 * block lasts as long as the longest track, a gimbal whose track is shorter has zero acceleration
 * afterwards.  A new segment starts wherever any track's segment ends. */
static void parallel(sink *k, const track *const *tracks)
{
    int idx[SARINS_SCHEDULE_MAX_AXES];
    double rep[SARINS_SCHEDULE_MAX_AXES], left[SARINS_SCHEDULE_MAX_AXES];
    int active[SARINS_SCHEDULE_MAX_AXES];
    /* position each track on its first non-empty segment */
    for (int64_t j = 0; j < k->n_axes; j++) {
        const track *t = tracks[j];
        active[j] = 0;
        if (t == NULL || t->n == 0 || !(t->repeat >= 1))
            continue;
        idx[j] = -1;
        rep[j] = 0;
        left[j] = 0;
        active[j] = 1;
        for (;;) { /* advance to the next segment of positive length */
            if (++idx[j] == t->n) {
                idx[j] = 0;
                if (++rep[j] >= t->repeat) {
                    active[j] = 0;
                    break;
                }
            }
            if (t->steps[idx[j]] > 0) {
                left[j] = t->steps[idx[j]];
                break;
            }
        }
    }
    while (!k->r->code) {
        double d = 0.0;
        int any = 0;
        for (int64_t j = 0; j < k->n_axes; j++)
            if (active[j] && (!any || left[j] < d)) {
                d = left[j];
                any = 1;
            }
        if (!any)
            return;
        double acc[SARINS_SCHEDULE_MAX_AXES];
        for (int64_t j = 0; j < k->n_axes; j++)
            acc[j] = active[j] ? tracks[j]->acc[idx[j]] : 0.0;
        emit_steps(k, d, acc);
        for (int64_t j = 0; j < k->n_axes; j++) {
            if (!active[j] || (left[j] -= d) > 0)
                continue;
            const track *t = tracks[j];
            for (;;) {
                if (++idx[j] == t->n) {
                    idx[j] = 0;
                    if (++rep[j] >= t->repeat) {
                        active[j] = 0;
                        break;
                    }
                }
                if (t->steps[idx[j]] > 0) {
                    left[j] = t->steps[idx[j]];
                    break;
                }
            }
        }
    }
}

/* A move as a track of whole grid steps (round(duration / grid)). */
static void move_track(report *r, track *t, double angle, double rate, double acc, double grid)
{
    double dur[3], a[3];
    int n = move(r, angle, rate, acc, grid, dur, a);
    t->n = 0;
    t->repeat = 1;
    for (int i = 0; i < n; i++) {
        t->steps[t->n] = round_steps(r, dur[i] / grid);
        t->acc[t->n++] = a[i];
    }
}

/* One gimbal moves alone (the others rest). */
static void move_alone(sink *k, int64_t gimbal, double angle, double rate, double acc, double grid)
{
    track t;
    const track *tracks[SARINS_SCHEDULE_MAX_AXES] = {NULL, NULL, NULL};
    move_track(k->r, &t, angle, rate, acc, grid);
    tracks[gimbal] = &t;
    parallel(k, tracks);
}

/* Ends the steps form: the pending segment, or one rest step if there was no motion at all. */
static void finish_steps(sink *k)
{
    if (k->pending)
        write_segment(k, k->pend_n, k->pend_acc);
    k->pending = 0;
    if (k->n_seg == 0) {
        static const double zeros[SARINS_SCHEDULE_MAX_AXES] = {0.0};
        write_segment(k, 1.0, zeros);
    }
}

/* ------------------------------------------------------------------ single-axis schemes (seed 000) */

static const double INDEX_MOVES[4] = {PI, -0.5 * PI, PI, -1.5 * PI}; /* four-position indexing, rad */

static void single_axis(const sarins_schedule_params *p, int scheme, sink *k)
{
    report *r = k->r;
    double rate = p->rate, acc = p->accel, grid = p->grid;
    check(r, "duration", p->duration, 1, SECONDS);
    check(r, "grid", grid, 1, SECONDS);
    check(r, "rate", rate, 0, ANGLE_RATE);
    check(r, "accel", acc, 0, ANGLE_ACCEL);
    check(r, "dwell", p->dwell, 0, SECONDS);
    check(r, "align_time", p->align_time, 0, SECONDS);
    check(r, "align_dwell", p->align_dwell, 0, SECONDS);
    if (r->code)
        return;
    double dur[3], a[3];
    if (p->align_time > 0) {
        if (!(rate > 0 && acc > 0)) {
            sarins_fail(r, SARINS_SCHEDULE_BAD_PARAM, "rate, acceleration and grid must be positive");
            return;
        }
        double t_align = round_steps(r, p->align_time / grid) * grid;
        double dwell_align = p->align_dwell > 0 ? ceil_to_grid(r, p->align_dwell, grid) : 0.0;
        double t_used = 0.0;
        for (int64_t i = 0; !r->code; i++) { /* whole moves (with their dwell) that fit in the alignment */
            int n = move(r, INDEX_MOVES[i % 4], rate, acc, grid, dur, a);
            double length = 0.0;
            for (int m = 0; m < n; m++)
                length += dur[m];
            if (dwell_align > 0)
                length += dwell_align;
            if (t_used + length > t_align + 1e-9)
                break;
            for (int m = 0; m < n; m++)
                emit_seconds(k, dur[m], a[m]);
            if (dwell_align > 0)
                emit_seconds(k, dwell_align, 0.0);
            t_used += length;
        }
        if (t_align - t_used > 1e-9)
            emit_seconds(k, t_align - t_used, 0.0);
    }
    if (r->code)
        return;
    double t_nav = p->duration - (k->n_seg ? k->t_sum : 0.0);
    if (!(t_nav >= grid))
        t_nav = grid;
    if (scheme == NONE) {
        emit_seconds(k, ceil_to_grid(r, t_nav, grid), 0.0);
        return;
    }
    if (rate <= 0 || acc <= 0) {
        sarins_fail(r, SARINS_SCHEDULE_BAD_PARAM, "rate and accel must be positive for a rotating scheme");
        return;
    }
    if (scheme == CONTINUOUS) {
        double t_acc = ceil_to_grid(r, rate / acc, grid);
        emit_seconds(k, t_acc, rate / t_acc);
        return;
    }
    double dwell = p->dwell > 0 ? ceil_to_grid(r, p->dwell, grid) : 0.0;
    double cycle[4];
    int n_moves;
    if (scheme == FORWARD_REVERSE) {
        double rev = p->revolutions;
        if (!(rev >= 1 && sm_floor(rev) == rev && isfinite(rev))) { /* 0 turns: a cycle of no time, never ending */
            char num[40];
            sarins_format_number(num, sizeof num, rev);
            sarins_fail(r, SARINS_SCHEDULE_BAD_PARAM, "revolutions must be a positive whole number, got %s", num);
            return;
        }
        cycle[0] = 2.0 * PI * rev;
        cycle[1] = -2.0 * PI * rev;
        n_moves = 2;
    } else {
        for (int i = 0; i < 4; i++)
            cycle[i] = INDEX_MOVES[i];
        n_moves = 4;
    }
    double t = 0.0;
    while (t < t_nav && !r->code) {
        for (int i = 0; i < n_moves; i++) {
            int n = move(r, cycle[i], rate, acc, grid, dur, a);
            for (int m = 0; m < n; m++) {
                emit_seconds(k, dur[m], a[m]);
                t += dur[m];
            }
            if (dwell > 0) {
                emit_seconds(k, dwell, 0.0);
                t += dwell;
            }
        }
    }
}

/* ------------------------------------------------------------------ dual-axis scheme (seed 002) */

static void dual_axis(const sarins_schedule_params *p, sink *k)
{
    enum { OUTER, INNER };
    report *r = k->r;
    double grid = p->grid;
    check(r, "duration", p->duration, 1, SECONDS);
    check(r, "grid", grid, 1, SECONDS);
    check(r, "rate", p->rate, 1, ANGLE_RATE);
    check(r, "accel", p->accel, 1, ANGLE_ACCEL);
    check(r, "outer_rate", p->outer_rate, 1, ANGLE_RATE);
    check(r, "outer_accel", p->outer_accel, 1, ANGLE_ACCEL);
    check(r, "dwell", p->dwell, 0, SECONDS);
    check(r, "align_time", p->align_time, 0, SECONDS);
    check(r, "align_dwell", p->align_dwell, 0, SECONDS);
    if (r->code)
        return;
    double n_dwell = ceil_steps(r, p->dwell, grid);
    double n_align_dwell = ceil_steps(r, p->align_dwell, grid);
    if (p->align_time > 0) {
        /* four-position indexing of the inner gimbal filling n_align steps with whole moves, padded with rest */
        double n_align = round_steps(r, p->align_time / grid), used = 0.0;
        double acc[2] = {0.0, 0.0};
        for (int64_t i = 0; n_align > 0 && !r->code; i++) {
            track t;
            move_track(r, &t, INDEX_MOVES[i % 4], p->rate, p->accel, grid);
            double length = 0.0;
            for (int m = 0; m < t.n; m++)
                length += t.steps[m];
            length += n_align_dwell;
            if (used + length > n_align)
                break;
            for (int m = 0; m < t.n; m++) {
                acc[INNER] = t.acc[m];
                emit_steps(k, t.steps[m], acc);
            }
            rest(k, n_align_dwell);
            used += length;
        }
        if (n_align > used)
            rest(k, n_align - used);
    }
    double n_end = ceil_steps(r, p->duration, grid);
    do {
        for (int f = 0; f < 2; f++) {
            for (int i = 0; i < 2; i++) {
                move_alone(k, INNER, i == 0 ? 2.0 * PI : -2.0 * PI, p->rate, p->accel, grid);
                rest(k, n_dwell);
            }
            move_alone(k, OUTER, f == 0 ? PI : -PI, p->outer_rate, p->outer_accel, grid);
            rest(k, n_dwell);
        }
    } while (k->now < n_end && !r->code);
}

/* ------------------------------------------------------------------ seed 003's three-axis rate table */

enum { OUTER3, MIDDLE3, INNER3 };

static void rate_table_3axis(const sarins_schedule_params *p, sink *k)
{
    report *r = k->r;
    double grid = p->grid;
    check(r, "duration", p->duration, 1, SECONDS);
    check(r, "grid", grid, 1, SECONDS);
    check(r, "warmup", p->warmup, 0, SECONDS);
    if (r->code)
        return;
    double n_warm = ceil_steps(r, p->warmup, grid);
    double n_duration = ceil_steps(r, p->duration, grid);
    double n_motion = n_duration - n_warm;
    if (!(n_motion >= 1))
        n_motion = 1;
    const double rates[3] = {p->table_outer_rate, p->table_middle_rate, p->table_inner_rate};
    const double accels[3] = {p->table_outer_accel, p->table_middle_accel, p->table_inner_accel};
    static const char *const rate_names[3] = {"table_outer_rate", "table_middle_rate", "table_inner_rate"};
    static const char *const accel_names[3] = {"table_outer_accel", "table_middle_accel", "table_inner_accel"};
    track tracks[3];
    const track *use[3] = {NULL, NULL, NULL};
    for (int j = 0; j < 3; j++) {
        check(r, rate_names[j], rates[j], 0, ANGLE_RATE);
        check(r, accel_names[j], accels[j], 1, ANGLE_ACCEL);
        if (r->code)
            return;
        if (rates[j] == 0.0)
            continue;
        double q = ceil_steps(r, rates[j] / accels[j], grid); /* quarter period, grid steps */
        if (q < 1)
            q = 1;
        double a = rates[j] / (q * grid);
        /* accel +a for T_q, -a for 2 T_q, +a for T_q: rate 0 -> +max -> -max -> 0, angle back to its start */
        track *t = &tracks[j];
        *t = (track){3, {q, 2 * q, q}, {a, -a, a}, sm_ceil(n_motion / (4 * q))};
        use[j] = t;
    }
    rest(k, n_warm);
    parallel(k, use);
    if (k->now < n_duration) /* every gimbal still (all rates 0) */
        rest(k, n_duration - k->now);
}

/* ------------------------------------------------------------------ 24-position tumble */

static void tumble_24(const sarins_schedule_params *p, sink *k)
{
    static const struct { int up, mid, in; } ORIENT[6] = {
        {SARINS_UP_PZ, 0, 0}, {SARINS_UP_PX, 0, -1}, {SARINS_UP_MZ, 0, -2},
        {SARINS_UP_MX, 0, -3}, {SARINS_UP_PY, 1, -3}, {SARINS_UP_MY, -1, -3}};
    static const int HEADINGS[2][4] = {{0, 1, 2, 3}, {3, 2, 1, 0}};
    report *r = k->r;
    double grid = p->grid, rate = p->rate, acc = p->accel;
    check(r, "grid", grid, 1, SECONDS);
    check(r, "dwell", p->dwell, 1, SECONDS);
    check(r, "rate", rate, 1, ANGLE_RATE);
    check(r, "accel", acc, 1, ANGLE_ACCEL);
    if (r->code)
        return;
    double n_dwell = ceil_steps(r, p->dwell, grid);
    int q[3] = {0, 0, 0}; /* gimbal angles in quarter turns: outer, middle, inner */
    for (int i = 0; i < 6 && !r->code; i++) {
        track t[3];
        const track *use[3] = {NULL, NULL, NULL};
        const int target[3] = {0, ORIENT[i].mid, ORIENT[i].in};
        for (int j = 1; j < 3; j++)
            if (target[j] != q[j]) {
                move_track(r, &t[j], (target[j] - q[j]) * QUARTER, rate, acc, grid);
                use[j] = &t[j];
            }
        parallel(k, use);
        q[1] = ORIENT[i].mid;
        q[2] = ORIENT[i].in;
        for (int h = 0; h < 4; h++) {
            int heading = HEADINGS[i % 2][h];
            if (heading != q[0]) {
                move_alone(k, OUTER3, (heading - q[0]) * QUARTER, rate, acc, grid);
                q[0] = heading;
            }
            double start = k->now;
            rest(k, n_dwell);
            sarins_schedule_window w;
            memset(&w, 0, sizeof w);
            w.start = start * grid;
            w.end = k->now * grid;
            w.up = ORIENT[i].up;
            w.heading = (q[0] % 4) * QUARTER;
            for (int j = 0; j < 3; j++)
                w.angles[j] = (double)q[j] * QUARTER;
            push_window(k, &w);
        }
    }
}

/* ------------------------------------------------------------------ rate test */

/* Smallest k revolutions in n grid steps with 2 pi k / (n grid) within rate_tol of |rate|, k >= 1 and
 * n grid >= min_duration. */
static void whole_revolutions(report *r, double rate, double grid, double min_duration, double rate_tol,
                              double *k_out, double *n_out)
{
    double steps_per_rev = 2 * PI / (sm_fabs(rate) * grid);
    double k_min = sm_ceil(min_duration * sm_fabs(rate) / (2 * PI) - 1e-9);
    if (!(k_min >= 1))
        k_min = 1;
    for (double k = k_min; k < k_min + 100000; k++) {
        double n = sm_nearbyint(k * steps_per_rev);
        if (!(n <= MAX_STEPS) || !(k <= MAX_STEPS)) {
            sarins_fail(r, SARINS_SCHEDULE_TOO_BIG, "a rate-test window at %.9g deg/s is more than 2^53 grid steps",
                        sm_fabs(rate) / DEG_TO_RAD);
            return;
        }
        if (!(n >= 1.0))
            n = 1.0;
        if (sm_fabs(k * steps_per_rev / n - 1.0) <= rate_tol && n * grid >= min_duration - 1e-9) {
            *k_out = k;
            *n_out = n;
            return;
        }
    }
    char g[40], tol[40];
    sarins_format_number(g, sizeof g, grid);
    sarins_format_number(tol, sizeof tol, rate_tol);
    sarins_fail(r, SARINS_SCHEDULE_BAD_PARAM,
                "cannot fit whole revolutions at %.9g deg/s on a %s s grid within a relative rate change of %s; "
                "use a finer grid or a larger rate_tol", sm_fabs(rate) / DEG_TO_RAD, g, tol);
}

/* (middle, inner) quarter turns that point each body axis up: Rx(m) Ry(i) e_axis = +z */
static const int UP_QUARTERS[6][2] = {{0, -1}, {0, 1}, {1, 0}, {-1, 0}, {0, 0}, {0, 2}}; /* +x -x +y -y +z -z */

/* The next axis name of a comma-separated list: *code, and the position after it; 0 at the end. */
static int next_axis(report *r, const char **pos, int *code)
{
    const char *s = *pos;
    if (*s == '\0')
        return 0;
    const char *end = strchr(s, ',');
    if (end == NULL)
        end = s + strlen(s);
    *pos = (*end == ',') ? end + 1 : end;
    while (s < end && isspace((unsigned char)*s))
        s++;
    const char *e = end;
    while (e > s && isspace((unsigned char)e[-1]))
        e--;
    char key[3] = {0, 0, 0};
    size_t len = (size_t)(e - s);
    if (len == 1 || (len == 2 && (s[0] == '+' || s[0] == '-'))) {
        key[0] = len == 1 ? '+' : s[0];
        key[1] = (char)tolower((unsigned char)s[len - 1]);
        if (key[1] >= 'x' && key[1] <= 'z') {
            *code = 2 * (key[1] - 'x') + (key[0] == '-');
            return 1;
        }
    }
    sarins_fail(r, SARINS_SCHEDULE_BAD_PARAM,
                "unknown body axis '%.*s' in axis_up; choose from x, y, z, +x, ..., -z", (int)(len > 40 ? 40 : len), s);
    return 0;
}

static void rate_test(const sarins_schedule_params *p, sink *k)
{
    report *r = k->r;
    double grid = p->grid, acc = p->accel, pos_rate = p->rate;
    check(r, "grid", grid, 1, SECONDS);
    check(r, "accel", acc, 1, ANGLE_ACCEL);
    check(r, "rate", pos_rate, 1, ANGLE_RATE);
    check(r, "dwell", p->dwell, 0, SECONDS);
    check(r, "test_min_duration", p->test_min_duration, 0, SECONDS);
    check(r, "test_rate_tol", p->test_rate_tol, 1, PLAIN);
    if (r->code)
        return;
    double n_settle = ceil_steps(r, p->dwell, grid);
    double min_duration = p->test_min_duration, rate_tol = p->test_rate_tol;
    if (rate_tol > 0.1) {
        char num[40];
        sarins_format_number(num, sizeof num, rate_tol);
        sarins_fail(r, SARINS_SCHEDULE_BAD_PARAM, "test_rate_tol must be at most 0.1, got %s", num);
        return;
    }
    int64_t n_rates = p->test_rates == NULL ? 2 * SARINS_RATE_TEST_N_MAGNITUDES : p->n_test_rates;
    if (n_rates < 1) {
        sarins_fail(r, SARINS_SCHEDULE_BAD_PARAM, "test_rates must not be empty");
        return;
    }
    /* rate i: the given one, or magnitude i / 2 with the sign + for even i, - for odd i */
#define NOMINAL(i) (p->test_rates != NULL ? p->test_rates[i] \
                    : ((i) % 2 ? -1.0 : 1.0) * RATE_TEST_MAGNITUDES_DPS[(i) / 2] * DEG_TO_RAD)
    for (int64_t i = 0; i < n_rates; i++) {
        double w = NOMINAL(i);
        if (!isfinite(w) || w == 0) {
            char num[40];
            sarins_format_number(num, sizeof num, w);
            sarins_fail(r, SARINS_SCHEDULE_BAD_PARAM, "test_rates must be finite and non-zero, got %s rad/s", num);
            return;
        }
    }
    const char *axes = p->test_axes == NULL ? "x,y,z" : p->test_axes;
    int code, n_axes = 0;
    for (const char *pos = axes; next_axis(r, &pos, &code);)
        n_axes++;
    if (r->code)
        return;
    if (n_axes == 0) {
        sarins_fail(r, SARINS_SCHEDULE_BAD_PARAM, "test_axes must name at least one body axis");
        return;
    }
    double k_rev, n_rev;
    for (int64_t i = 0; i < n_rates && !r->code; i++) /* every rate fits before anything moves */
        whole_revolutions(r, NOMINAL(i), grid, min_duration, rate_tol, &k_rev, &n_rev);
    int q_mid = 0, q_in = 0;
    for (const char *pos = axes; !r->code && next_axis(r, &pos, &code);) {
        int target_mid = UP_QUARTERS[code][0], target_in = UP_QUARTERS[code][1];
        track t[3];
        const track *use[3] = {NULL, NULL, NULL};
        if (target_mid != q_mid) {
            move_track(r, &t[MIDDLE3], (target_mid - q_mid) * QUARTER, pos_rate, acc, grid);
            use[MIDDLE3] = &t[MIDDLE3];
        }
        if (target_in != q_in) {
            move_track(r, &t[INNER3], (target_in - q_in) * QUARTER, pos_rate, acc, grid);
            use[INNER3] = &t[INNER3];
        }
        parallel(k, use);
        q_mid = target_mid;
        q_in = target_in;
        for (int64_t i = 0; i < n_rates && !r->code; i++) {
            double w_nominal = NOMINAL(i);
            whole_revolutions(r, w_nominal, grid, min_duration, rate_tol, &k_rev, &n_rev);
            double w = sm_copysign(2 * PI * k_rev / (n_rev * grid), w_nominal);
            double q = ceil_steps(r, sm_fabs(w) / acc, grid);
            if (q < 1)
                q = 1;
            double a = w / (q * grid);
            double start = k->now + q + n_settle;
            /* spin up, settle and the window at constant rate, spin down */
            track spin = {3, {q, n_settle + n_rev, q}, {a, 0.0, -a}, 1};
            const track *outer[3] = {&spin, NULL, NULL};
            parallel(k, outer);
            sarins_schedule_window win;
            memset(&win, 0, sizeof win);
            win.start = start * grid;
            win.end = (start + n_rev) * grid;
            win.up = code;
            win.rate = w;
            win.rate_nominal = w_nominal;
            win.revolutions = (int64_t)k_rev;
            win.angles[0] = 0.0;
            win.angles[1] = q_mid * QUARTER;
            win.angles[2] = q_in * QUARTER;
            push_window(k, &win);
        }
    }
#undef NOMINAL
}

/* ------------------------------------------------------------------ entry points */

void sarins_schedule_integrate(int64_t n_times, int64_t n_axes, const double *times, const double *accel,
                               const double *angle0, const double *rate0, double *angle_bp, double *rate_bp)
{
    for (int64_t j = 0; j < n_axes; j++) {
        double rate_sum = 0.0, angle_sum = 0.0; /* running sums, in order, each from its first term */
        rate_bp[j] = rate0[j] + 0.0;
        angle_bp[j] = angle0[j] + 0.0;
        for (int64_t m = 0; m + 1 < n_times; m++) {
            double dt = times[m + 1] - times[m], a = accel[n_axes * m + j];
            /* rate_bp[m+1] = rate0 + sum accel dt */
            double d_rate = a * dt;
            rate_sum = m ? rate_sum + d_rate : d_rate;
            /* angle_bp[m+1] = angle0 + sum (rate_bp dt + accel dt^2 / 2) */
            double d_angle = rate_bp[n_axes * m + j] * dt + 0.5 * a * (dt * dt);
            angle_sum = m ? angle_sum + d_angle : d_angle;
            rate_bp[n_axes * (m + 1) + j] = rate0[j] + rate_sum;
            angle_bp[n_axes * (m + 1) + j] = angle0[j] + angle_sum;
        }
    }
}

static int generate(const sarins_schedule_params *p, sarins_schedule *s, report *r, int64_t *n_times,
                    int64_t *n_axes, int64_t *n_windows)
{
    int scheme = scheme_index(p->scheme);
    if (scheme < 0) {
        char names[160] = "";
        for (int i = 0; i < N_SCHEMES; i++)
            sarins_join(names, sizeof names, names[0] ? ", " : "", SCHEME_NAMES[i], "", "");
        return sarins_fail(r, SARINS_SCHEDULE_BAD_PARAM, "unknown scheme '%.60s'; choose one of %s",
                           p->scheme == NULL ? "(null)" : p->scheme, names);
    }
    sink k;
    memset(&k, 0, sizeof k);
    k.r = r;
    k.s = s;
    k.grid = p->grid;
    k.n_axes = scheme <= FOUR_POSITION ? 1 : scheme == DUAL_AXIS ? 2 : 3;
    k.steps = scheme > FOUR_POSITION;
    if (s != NULL && s->times != NULL) {
        if (s->capacity < 2 || s->angle_bp == NULL || s->rate_bp == NULL || s->accel == NULL)
            return sarins_fail(r, SARINS_SCHEDULE_CAPACITY,
                               "the schedule's arrays are missing or hold fewer than 2 breakpoints");
        s->times[0] = 0.0;
    }
    switch (scheme) {
    case DUAL_AXIS:
        dual_axis(p, &k);
        break;
    case RATE_TABLE_3AXIS:
        rate_table_3axis(p, &k);
        break;
    case TUMBLE_24:
        tumble_24(p, &k);
        break;
    case RATE_TEST:
        rate_test(p, &k);
        break;
    default:
        single_axis(p, scheme, &k);
    }
    if (k.steps)
        finish_steps(&k);
    if (r->code)
        return r->code;
    *n_times = k.n_seg + 1;
    *n_axes = k.n_axes;
    *n_windows = k.n_windows;
    if (s != NULL) {
        static const double AXES[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
        const char *chain = CHAINS[scheme];
        for (int64_t j = 0; j < k.n_axes; j++) {
            int c = chain[2 * j] - 'x';
            for (int i = 0; i < 3; i++)
                s->axes[j][i] = AXES[c][i];
            s->angle0[j] = 0.0;
            s->rate0[j] = 0.0;
        }
        memcpy(s->gimbal_axes, chain, strlen(chain) + 1); /* at most "z,x,y" */
        s->n_times = *n_times;
        s->n_axes = *n_axes;
        s->n_windows = *n_windows;
        if (s->times != NULL)
            sarins_schedule_integrate(s->n_times, s->n_axes, s->times, s->accel, s->angle0, s->rate0,
                                      s->angle_bp, s->rate_bp);
    }
    return 0;
}

int sarins_schedule_size(const sarins_schedule_params *p, int64_t *n_times, int64_t *n_axes, int64_t *n_windows,
                         char *msg, size_t msg_len)
{
    report r = sarins_report(msg, msg_len);
    int64_t nt = 0, na = 0, nw = 0;
    int code = generate(p, NULL, &r, &nt, &na, &nw);
    if (n_times != NULL)
        *n_times = nt;
    if (n_axes != NULL)
        *n_axes = na;
    if (n_windows != NULL)
        *n_windows = nw;
    return code;
}

int sarins_schedule_build(const sarins_schedule_params *p, sarins_schedule *s, char *msg, size_t msg_len)
{
    report r = sarins_report(msg, msg_len);
    int64_t nt = 0, na = 0, nw = 0;
    if (s->windows == NULL)
        s->window_capacity = 0;
    return generate(p, s, &r, &nt, &na, &nw);
}
