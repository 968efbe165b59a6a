/* Turntable FMU (native): gimbal angles, rates and accelerations of a rotation scheme, and the ambient.
 *
 * The declaration (variables, descriptions, the timing contract) is fmus/turntable_slave.py; the schedule
 * and the chamber profile are built by the C core (sarins_fmu/core/schedule.h, ambient.h) and evaluated by
 * sarins_turntable_state (turntable.h), the functions the library runs in process.  The outputs describe
 * the motion segment that starts at motion_time: the state at motion_time and the acceleration holding from
 * there; ambient_temp at motion_time and its slope over [motion_time, motion_time + h] (before the first
 * step over [start, start + grid]).  Units: rad, rad/s, rad/s^2, s, degC, degC/s.
 *
 * Sub-intervals (n_sub = K, default 1).  The *_sub arrays (FMI 3.0 outputs, c->a in both versions) hold
 * the outputs this turntable with n_sub = 1 stepped at s = h / K shows at each communication point of the
 * coming step: element 0 at motion_time, element k >= 1 at (start + (m - 1) s) + s, m the index of that
 * point on the grid of s (a master's begin + j s, then the turntable's t + s), each with the ambient's slope
 * over [time, time + s].  The breakpoints of the schedule need only lie on the grid of s.  The scalars are
 * element 0's but for ambient_temp_rate, still the slope over the whole step (element 0's when K = 1).
 * Before the first step s is taken as grid.  The FMI 2.0 variant, which has no arrays, refuses K > 1.
 */
#include "smath.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ambient.h"
#include "model.h"
#include "schedule.h"
#include "turntable.h"
#include "variables.h"

#define DEG_TO_RAD (3.14159265358979323846 / 180.0)
#define INT32_LIMIT 2147483647
#define STEP_TOL 1e-9   /* relative: a communication step equal to the first one */
#define GRID_TOL 1e-9   /* relative: a breakpoint on the grid of the communication step */

/* What changes during a run (plain bytes: the FMU state copies it). */
typedef struct {
    double step; /* s, the communication step, fixed by the first fmi2DoStep */
    int have_step;
} tt_state;

/* What the parameters give (built at initialisation, not part of the FMU state). */
typedef struct {
    sarins_schedule schedule;
    sarins_ambient ambient;
    double *buffer; /* one allocation: the schedule's tables, then the chamber profile */
} tt_work;

/* The library's schedule takes deg-based values (rate_dps = rate / DEG_TO_RAD) and converts them back with
 * * DEG_TO_RAD; the same two roundings here keep the FMU bit-identical with in-process runs. */
static double via_deg(double x) { return (x / DEG_TO_RAD) * DEG_TO_RAD; }

static int refuse(sarins_ctx *c, const char *fmt, const char *name, double value)
{
    sarins_log(c, SARINS_ERROR, fmt, name, value);
    return SARINS_ERROR;
}

/* n_sub in 1 .. max_dim; above 1 only where the arrays are visible (FMI 3.0). */
static int check_n_sub(const sarins_ctx *c)
{
    int n_sub = c->i[SARINS_I_n_sub];
    if (n_sub < 1 || n_sub > SARINS_TABLE.max_dim) {
        sarins_log(c, SARINS_ERROR, "parameter n_sub = %d must be an integer in [1, %d]", n_sub,
                   SARINS_TABLE.max_dim);
        return SARINS_ERROR;
    }
    if (n_sub > 1 && !sarins_arrays_visible(c)) {
        sarins_log(c, SARINS_ERROR, "parameter n_sub = %d describes the sub-intervals in the *_sub array outputs, "
                   "which only the FMI 3.0 variant of this FMU has; use 1 here", n_sub);
        return SARINS_ERROR;
    }
    return SARINS_OK;
}

/* Every parameter check of the Python slave, in its order and with its messages' meaning; then n_sub. */
static int check_parameters(sarins_ctx *c)
{
    static const struct { const char *name; int slot; } finite[] = {
        {"rate", SARINS_R_rate}, {"accel", SARINS_R_accel}, {"dwell", SARINS_R_dwell},
        {"align_time", SARINS_R_align_time}, {"align_dwell", SARINS_R_align_dwell}, {"grid", SARINS_R_grid},
        {"duration", SARINS_R_duration}, {"ambient_mean", SARINS_R_ambient_mean},
        {"ambient_amplitude", SARINS_R_ambient_amplitude}, {"ambient_period", SARINS_R_ambient_period},
        {"outer_rate", SARINS_R_outer_rate}, {"outer_accel", SARINS_R_outer_accel}, {"warmup", SARINS_R_warmup},
        {"chamber_low", SARINS_R_chamber_low}, {"chamber_high", SARINS_R_chamber_high},
        {"chamber_ramp", SARINS_R_chamber_ramp}, {"chamber_hold", SARINS_R_chamber_hold},
        {"chamber_step", SARINS_R_chamber_step}, {"chamber_step_hold", SARINS_R_chamber_step_hold},
        {"table_inner_rate", SARINS_R_table_inner_rate}, {"table_inner_accel", SARINS_R_table_inner_accel},
        {"table_middle_rate", SARINS_R_table_middle_rate}, {"table_middle_accel", SARINS_R_table_middle_accel},
        {"table_outer_rate", SARINS_R_table_outer_rate}, {"table_outer_accel", SARINS_R_table_outer_accel},
    };
    static const struct { const char *name; int slot; } positive[] = {
        {"grid", SARINS_R_grid}, {"duration", SARINS_R_duration}, {"ambient_period", SARINS_R_ambient_period},
    };
    static const struct { const char *name; int slot; } non_negative[] = {
        {"rate", SARINS_R_rate}, {"accel", SARINS_R_accel}, {"dwell", SARINS_R_dwell},
        {"align_time", SARINS_R_align_time}, {"align_dwell", SARINS_R_align_dwell},
        {"outer_rate", SARINS_R_outer_rate}, {"outer_accel", SARINS_R_outer_accel}, {"warmup", SARINS_R_warmup},
        {"chamber_hold", SARINS_R_chamber_hold}, {"chamber_step", SARINS_R_chamber_step},
        {"chamber_step_hold", SARINS_R_chamber_step_hold}, {"ambient_amplitude", SARINS_R_ambient_amplitude},
    };
    const double *r = c->r;
    for (size_t k = 0; k < sizeof finite / sizeof finite[0]; k++)
        if (!isfinite(r[finite[k].slot]))
            return refuse(c, "parameter %s = %g is not a finite number", finite[k].name, r[finite[k].slot]);
    for (size_t k = 0; k < sizeof positive / sizeof positive[0]; k++)
        if (!(r[positive[k].slot] > 0.0))
            return refuse(c, "parameter %s = %.17g must be positive", positive[k].name, r[positive[k].slot]);
    for (size_t k = 0; k < sizeof non_negative / sizeof non_negative[0]; k++)
        if (!(r[non_negative[k].slot] >= 0.0))
            return refuse(c, "parameter %s = %.17g must not be negative", non_negative[k].name,
                          r[non_negative[k].slot]);
    if (!(r[SARINS_R_chamber_ramp] > 0.0))
        return refuse(c, "parameter %s = %.17g degC/s must be positive", "chamber_ramp", r[SARINS_R_chamber_ramp]);
    const char *first = c->s[SARINS_S_chamber_first];
    if (strcmp(first, "low") != 0 && strcmp(first, "high") != 0) {
        sarins_log(c, SARINS_ERROR, "parameter chamber_first must be 'low' or 'high', got '%s'", first);
        return SARINS_ERROR;
    }
    if (c->i[SARINS_I_revolutions] < 1) {
        sarins_log(c, SARINS_ERROR, "parameter revolutions = %d must be an integer in [1, %d]",
                   c->i[SARINS_I_revolutions], INT32_LIMIT);
        return SARINS_ERROR;
    }
    return check_n_sub(c);
}

static void schedule_params(const sarins_ctx *c, sarins_schedule_params *p)
{
    const double *r = c->r;
    sarins_schedule_params_default(p);
    p->scheme = c->s[SARINS_S_scheme];
    p->duration = r[SARINS_R_duration];
    p->rate = via_deg(r[SARINS_R_rate]);
    p->accel = via_deg(r[SARINS_R_accel]);
    p->dwell = r[SARINS_R_dwell];
    p->revolutions = (double)c->i[SARINS_I_revolutions];
    p->align_time = r[SARINS_R_align_time];
    p->align_dwell = r[SARINS_R_align_dwell];
    p->grid = r[SARINS_R_grid];
    p->outer_rate = via_deg(r[SARINS_R_outer_rate]);
    p->outer_accel = via_deg(r[SARINS_R_outer_accel]);
    p->table_inner_rate = via_deg(r[SARINS_R_table_inner_rate]);
    p->table_middle_rate = via_deg(r[SARINS_R_table_middle_rate]);
    p->table_outer_rate = via_deg(r[SARINS_R_table_outer_rate]);
    p->table_inner_accel = via_deg(r[SARINS_R_table_inner_accel]);
    p->table_middle_accel = via_deg(r[SARINS_R_table_middle_accel]);
    p->table_outer_accel = via_deg(r[SARINS_R_table_outer_accel]);
    p->warmup = r[SARINS_R_warmup];
}

/* The library's chamber_profile takes ramp in degC/min and holds in min: the same roundings here. */
static void chamber_params(const sarins_ctx *c, sarins_chamber_params *p)
{
    const double *r = c->r;
    sarins_chamber_params_default(p);
    p->duration = r[SARINS_R_duration];
    p->low = r[SARINS_R_chamber_low];
    p->high = r[SARINS_R_chamber_high];
    p->ramp = (r[SARINS_R_chamber_ramp] * 60.0) / 60.0;
    p->hold = (r[SARINS_R_chamber_hold] / 60.0) * 60.0;
    p->start = r[SARINS_R_ambient_mean];
    p->delay = 0.0;
    p->first = c->s[SARINS_S_chamber_first];
    p->step = r[SARINS_R_chamber_step];
    p->step_hold = (r[SARINS_R_chamber_step_hold] / 60.0) * 60.0;
}

/* The outputs at one time, in the order of OUT_SLOTS and SUB_ARRAYS. */
enum { N_OUT = 11, OUT_AMBIENT = 9, OUT_AMBIENT_RATE = 10 };
static const int OUT_SLOTS[N_OUT] = {
    SARINS_R_angle_1, SARINS_R_angle_2, SARINS_R_angle_3, SARINS_R_rate_1, SARINS_R_rate_2, SARINS_R_rate_3,
    SARINS_R_accel_1, SARINS_R_accel_2, SARINS_R_accel_3, SARINS_R_ambient_temp, SARINS_R_ambient_temp_rate};
static const int SUB_ARRAYS[N_OUT] = {
    SARINS_A_angle_1_sub, SARINS_A_angle_2_sub, SARINS_A_angle_3_sub, SARINS_A_rate_1_sub, SARINS_A_rate_2_sub,
    SARINS_A_rate_3_sub, SARINS_A_accel_1_sub, SARINS_A_accel_2_sub, SARINS_A_accel_3_sub,
    SARINS_A_ambient_temp_sub, SARINS_A_ambient_temp_rate_sub};

/* The outputs at `time` (s) into out: gimbal angles, rates and the acceleration holding from there (0
 * beyond the gimbals in use), the ambient and its slope over [time, time + span]. */
static int motion_at(const sarins_ctx *c, const tt_work *w, double time, double span, double out[N_OUT])
{
    const sarins_schedule *s = &w->schedule;
    double angle[SARINS_SCHEDULE_MAX_AXES], rate[SARINS_SCHEDULE_MAX_AXES], acc[SARINS_SCHEDULE_MAX_AXES];
    if (!isfinite(time)) {
        sarins_log(c, SARINS_ERROR, "ValueError: time must be finite (motion time %g)", time);
        return SARINS_ERROR;
    }
    char msg[256];
    if (sarins_ambient_segment(&w->ambient, time, span, &out[OUT_AMBIENT], &out[OUT_AMBIENT_RATE], msg,
                               sizeof msg) != SARINS_SCHEDULE_OK) {
        sarins_log(c, SARINS_ERROR, "ValueError: %s", msg);
        return SARINS_ERROR;
    }
    sarins_turntable_state(1, &time, s->n_times, s->n_axes, s->times, s->angle_bp, s->rate_bp, s->accel,
                           s->angle0, s->rate0, angle, rate, acc);
    for (int64_t j = 0; j < SARINS_SCHEDULE_MAX_AXES; j++) {
        int used = j < s->n_axes;
        out[j] = used ? angle[j] : 0.0;
        out[3 + j] = used ? rate[j] : 0.0;
        out[6 + j] = used ? acc[j] : 0.0;
    }
    return SARINS_OK;
}

/* Scalar outputs at `time` (s), the ambient's slope over [time, time + span]. */
static int publish(sarins_ctx *c, const tt_work *w, double time, double span)
{
    double out[N_OUT];
    if (motion_at(c, w, time, span, out) != SARINS_OK)
        return SARINS_ERROR;
    for (int i = 0; i < N_OUT; i++)
        c->r[OUT_SLOTS[i]] = out[i];
    c->r[SARINS_R_motion_time] = time;
    return SARINS_OK;
}

/* The *_sub arrays: element 0 at `first` (the scalars' motion_time), element k >= 1 at the communication
 * point (start + (index + k - 1) sub) + sub of a turntable stepped at sub (s) from start; each slope over
 * sub.  With one element and sub the span of the scalars, the arrays are the scalars. */
static int publish_sub(sarins_ctx *c, const tt_work *w, double first, double index, double sub)
{
    int n_sub = c->i[SARINS_I_n_sub];
    for (int k = 0; k < n_sub; k++) {
        double time = k == 0 ? first : (c->start_time + (index + (double)k - 1.0) * sub) + sub;
        double out[N_OUT];
        if (motion_at(c, w, time, sub, out) != SARINS_OK)
            return SARINS_ERROR;
        for (int i = 0; i < N_OUT; i++)
            c->a[SUB_ARRAYS[i]][k] = out[i];
    }
    return SARINS_OK;
}

static void tt_release(sarins_ctx *c)
{
    tt_work *w = c->work;
    if (w != NULL) {
        free(w->buffer);
        free(w);
    }
    c->work = NULL;
}

/* Build the schedule and the ambient into a fresh tt_work; SARINS_ERROR with a logged reason. */
static int build(sarins_ctx *c, tt_work **out)
{
    sarins_schedule_params sp;
    sarins_chamber_params cp;
    schedule_params(c, &sp);
    chamber_params(c, &cp);
    char msg[512];
    int64_t n_times = 0, n_axes = 0, n_points = 0;
    if (sarins_schedule_size(&sp, &n_times, &n_axes, NULL, msg, sizeof msg) != SARINS_SCHEDULE_OK) {
        sarins_log(c, SARINS_ERROR, "parameter scheme = '%s' with its motion parameters: %s", sp.scheme, msg);
        return SARINS_ERROR;
    }
    const char *mode = c->s[SARINS_S_ambient_mode];
    int chamber = strcmp(mode, "chamber") == 0;
    if (!chamber && strcmp(mode, "sinusoid") != 0) {
        sarins_log(c, SARINS_ERROR, "parameter ambient_mode = '%s': ambient_mode must be 'sinusoid' or 'chamber'",
                   mode);
        return SARINS_ERROR;
    }
    if (chamber && sarins_chamber_size(&cp, &n_points, msg, sizeof msg) != SARINS_SCHEDULE_OK) {
        sarins_log(c, SARINS_ERROR, "parameter ambient_mode = 'chamber': %s", msg);
        return SARINS_ERROR;
    }
    /* times (M+1), angle_bp and rate_bp (M+1, A), accel (M, A), then the profile's times and temperatures */
    size_t m1 = (size_t)n_times, a = (size_t)n_axes;
    size_t count = m1 + 2 * m1 * a + (m1 - 1) * a + 2 * (size_t)n_points;
    tt_work *w = calloc(1, sizeof *w);
    double *buffer = w ? malloc(count * sizeof(double)) : NULL;
    if (buffer == NULL) {
        free(w);
        sarins_log(c, SARINS_ERROR, "out of memory for a schedule of %lld breakpoints", (long long)n_times);
        return SARINS_ERROR;
    }
    w->buffer = buffer;
    sarins_schedule *s = &w->schedule;
    s->capacity = n_times;
    s->times = buffer;
    s->angle_bp = s->times + m1;
    s->rate_bp = s->angle_bp + m1 * a;
    s->accel = s->rate_bp + m1 * a;
    s->window_capacity = 0;
    s->windows = NULL;
    int code = sarins_schedule_build(&sp, s, msg, sizeof msg);
    if (code == SARINS_SCHEDULE_OK && s->n_axes != n_axes) {
        code = SARINS_SCHEDULE_CAPACITY;
        snprintf(msg, sizeof msg, "the schedule has %lld gimbals, its size query said %lld", (long long)s->n_axes,
                 (long long)n_axes);
    }
    if (code != SARINS_SCHEDULE_OK) {
        sarins_log(c, SARINS_ERROR, "parameter scheme = '%s' with its motion parameters: %s", sp.scheme, msg);
        tt_release(&(sarins_ctx){.work = w});
        return SARINS_ERROR;
    }
    sarins_ambient *amb = &w->ambient;
    amb->mean = c->r[SARINS_R_ambient_mean];
    if (chamber) {
        double *times = s->accel + (m1 - 1) * a, *temps = times + n_points;
        int64_t written = 0;
        if (sarins_chamber_build(&cp, n_points, times, temps, &written, msg, sizeof msg) != SARINS_SCHEDULE_OK) {
            sarins_log(c, SARINS_ERROR, "parameter ambient_mode = 'chamber': %s", msg);
            tt_release(&(sarins_ctx){.work = w});
            return SARINS_ERROR;
        }
        amb->n_profile = written;
        amb->profile_times = times;
        amb->profile_temps = temps;
    } else {
        amb->amplitude = c->r[SARINS_R_ambient_amplitude];
        amb->period = c->r[SARINS_R_ambient_period];
    }
    *out = w;
    return SARINS_OK;
}

static int tt_initialize(sarins_ctx *c)
{
    int status = check_parameters(c);
    if (status != SARINS_OK)
        return status;
    tt_work *w = NULL;
    status = build(c, &w);
    if (status != SARINS_OK)
        return status;
    c->work = w;
    memset(c->state, 0, sizeof(tt_state));
    c->i[SARINS_I_n_gimbals] = (int)w->schedule.n_axes;
    double grid = c->r[SARINS_R_grid];
    if (publish(c, w, c->start_time, grid) != SARINS_OK)
        return SARINS_ERROR;
    return publish_sub(c, w, c->start_time, 0.0, grid);
}

/* Every breakpoint on the grid of the sub-interval h / n_sub (from t = 0), as the IMU needs to rebuild the
 * motion inside a (sub-)interval exactly. */
static int check_grid(sarins_ctx *c, const sarins_schedule *s, double h, int n_sub)
{
    double step = n_sub > 1 ? h / (double)n_sub : h;
    for (int64_t m = 0; m < s->n_times; m++) {
        double n = s->times[m] / step;
        if (sm_fabs(n - sm_nearbyint(n)) <= GRID_TOL * sm_fmax(1.0, sm_fabs(n)))
            continue;
        if (n_sub > 1)
            sarins_log(c, SARINS_ERROR, "ValueError: turntable breakpoint at t=%.9g s is not on the output grid of "
                       "step %.17g s / n_sub %d = %.17g s: the IMU cannot rebuild the motion inside a sub-interval "
                       "exactly", s->times[m], h, n_sub, step);
        else
            sarins_log(c, SARINS_ERROR, "ValueError: turntable breakpoint at t=%.9g s is not on the output grid of "
                       "step %.17g s: the IMU cannot rebuild the motion inside a step exactly", s->times[m], step);
        return SARINS_ERROR;
    }
    return SARINS_OK;
}

static int tt_do_step(sarins_ctx *c, double t, double h)
{
    tt_work *w = c->work;
    tt_state *st = c->state;
    int n_sub = c->i[SARINS_I_n_sub];
    if (!st->have_step) {
        if (check_grid(c, &w->schedule, h, n_sub) != SARINS_OK)
            return SARINS_ERROR;
        double grid = c->r[SARINS_R_grid];
        if (n_sub > 1 && sm_fabs(h / (double)n_sub - grid) > STEP_TOL * grid) {
            /* the arrays of initialisation (read by a Gauss-Seidel IMU in its first step) are laid out on grid */
            sarins_log(c, SARINS_ERROR, "ValueError: step %.17g s / n_sub %d = %.17g s must equal grid = %.17g s "
                       "(the sub-intervals of the arrays at initialisation are grid long)", h, n_sub,
                       h / (double)n_sub, grid);
            return SARINS_ERROR;
        }
    } else if (sm_fabs(h - st->step) > STEP_TOL * st->step) {
        sarins_log(c, SARINS_ERROR, "ValueError: communication step changed from %.17g s to %.17g s; this FMU needs a "
                   "fixed step", st->step, h);
        return SARINS_ERROR;
    }
    st->step = h; /* the step as given (the library's check_step keeps the latest) */
    st->have_step = 1;
    if (publish(c, w, t + h, h) != SARINS_OK)
        return SARINS_ERROR;
    if (n_sub == 1)
        return publish_sub(c, w, t + h, 0.0, h);
    /* the coming step's first sub-interval is number (i + 1) n_sub on the grid of h / n_sub, t = start + i h */
    double index = (sm_nearbyint((t - c->start_time) / h) + 1.0) * (double)n_sub;
    return publish_sub(c, w, t + h, index, h / (double)n_sub);
}

/* Every field of the state within what do_step relies on (model.h, State validation). */
static int tt_check_state(const sarins_ctx *c, int running)
{
    const tt_state *s = c->state;
    (void)running;
    /* the communication step: 0 before the first step, positive after */
    if (!sarins_state_int(c, "have_step", s->have_step, 0, 1)
        || !sarins_state_real(c, "step", s->step, s->have_step ? 1e-300 : 0.0, s->have_step ? 1e300 : 0.0))
        return SARINS_ERROR;
    return SARINS_OK;
}

const sarins_model sarins_model_desc = {
    .table = &SARINS_TABLE,
    .state_size = sizeof(tt_state),
    .state_version = 1,
    .check_state = tt_check_state,
    .initialize = tt_initialize,
    .do_step = tt_do_step,
    .release = tt_release,
};
