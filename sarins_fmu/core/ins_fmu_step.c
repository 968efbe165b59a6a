#include "smath.h"

#include "ins_fmu_step.h"

#include <stdio.h>
#include <string.h>

#include "rotations.h"

#define CAP SARINS_INS_COMP_QUEUE

/* snprintf into msg when there is one */
#define REASON(...)                                  \
    do {                                             \
        if (msg != NULL && size > 0)                 \
            snprintf(msg, size, __VA_ARGS__);        \
    } while (0)

/* Two time tags name the same communication point (to SARINS_INS_TAG_TOL of a step h). */
static int same_time(double a, double b, double h) { return sm_fabs(a - b) <= SARINS_INS_TAG_TOL * h; }

static const sarins_ins_comp_pair *queued(const sarins_ins_comp *c, int64_t i)
{
    return &c->pending[(c->first + i) % CAP];
}

static int same_value(const double *a, const double *b) { return a[0] == b[0] && a[1] == b[1] && a[2] == b[2]; }

/* What an input pair does to the queue for the interval starting at nav_start (computed first, applied
 * by comp_apply only when the whole step goes ahead). */
typedef struct {
    int differs;       /* the pair is not the one seen last */
    int64_t keep;      /* queued pairs kept (the others start at or after the new pair's apply_from) */
    int push;          /* the new pair is queued */
    int64_t take;      /* pairs (of the kept + the new one) that take over, in order */
    double current[3]; /* the value in force for the interval */
} comp_plan;

static int comp_plan_for(const sarins_ins_comp *c, const double *value, double apply_from, double nav_start,
                         double tol, comp_plan *p, char *msg, size_t size)
{
    if (!(isfinite(value[0]) && isfinite(value[1]) && isfinite(value[2]) && isfinite(apply_from))) {
        REASON("an axial_drift_correction input or axial_drift_apply_from is not finite");
        return SARINS_INS_BAD_STEP;
    }
    p->differs = !(same_value(value, c->seen.value) && apply_from == c->seen.apply_from);
    p->keep = c->count;
    p->push = 0;
    if (p->differs) {
        if (c->started && apply_from < nav_start - tol) {
            REASON("axial drift compensation %.6g rad/s to apply from nav time %.9g s arrived when the INS "
                   "integrates the interval starting at %.9g s (make the sender's latency longer)",
                   value[0], apply_from, nav_start);
            return SARINS_INS_BAD_STEP;
        }
        /* a pair replaces the queued ones that would start at or after its own apply_from */
        while (p->keep > 0 && queued(c, p->keep - 1)->apply_from >= apply_from - tol)
            p->keep--;
        /* ... and is queued unless it equals the value it would follow */
        const double *last = (p->keep > 0) ? queued(c, p->keep - 1)->value : c->current;
        p->push = !same_value(value, last);
        if (p->keep + p->push > CAP) {
            REASON("more than %d axial drift compensations wait to apply (a sender changes its value every step "
                   "with a latency of more than %d steps)", CAP, CAP);
            return SARINS_INS_BAD_STEP;
        }
    }
    /* the queued pairs whose apply_from the interval's start has reached take over, in order */
    const double *current = c->current;
    int64_t total = p->keep + p->push;
    p->take = 0;
    while (p->take < total) {
        const double *v = (p->take < p->keep) ? queued(c, p->take)->value : value;
        double from = (p->take < p->keep) ? queued(c, p->take)->apply_from : apply_from;
        if (!(nav_start >= from - tol))
            break;
        current = v;
        p->take++;
    }
    for (int i = 0; i < 3; i++)
        p->current[i] = current[i];
    return SARINS_INS_OK;
}

static void comp_apply(sarins_ins_comp *c, const comp_plan *p, const double *value, double apply_from)
{
    if (p->differs) {
        c->count = p->keep;
        for (int i = 0; i < 3; i++)
            c->seen.value[i] = value[i];
        c->seen.apply_from = apply_from;
        if (p->push) {
            sarins_ins_comp_pair *slot = &c->pending[(c->first + c->count) % CAP];
            for (int i = 0; i < 3; i++)
                slot->value[i] = value[i];
            slot->apply_from = apply_from;
            c->count++;
        }
    }
    c->started = 1;
    c->first = (c->first + p->take) % CAP;
    c->count -= p->take;
    for (int i = 0; i < 3; i++)
        c->current[i] = p->current[i];
}

void sarins_ins_comp_init(sarins_ins_comp *c, const double *value, double apply_from)
{
    memset(c, 0, sizeof *c);
    for (int i = 0; i < 3; i++)
        c->seen.value[i] = c->pending[0].value[i] = value[i];
    c->seen.apply_from = c->pending[0].apply_from = apply_from;
    c->count = 1;
}

int sarins_ins_comp_value_at(sarins_ins_comp *c, const double *value, double apply_from, double nav_start,
                             double tol, double *current, char *msg, size_t size)
{
    comp_plan plan;
    int status = comp_plan_for(c, value, apply_from, nav_start, tol, &plan, msg, size);
    if (status != SARINS_INS_OK)
        return status;
    comp_apply(c, &plan, value, apply_from);
    for (int i = 0; i < 3; i++)
        current[i] = c->current[i];
    return SARINS_INS_OK;
}

/* lat, lon, height of the start, nav_time, solution_time and, navigating from the start, the attitude */
static void publish_start(sarins_ins_fmu *f)
{
    const double *c = f->config;
    f->out[SARINS_INS_OUT_LAT] = c[SARINS_INS_LAT];
    f->out[SARINS_INS_OUT_LON] = c[SARINS_INS_LON];
    f->out[SARINS_INS_OUT_HEIGHT] = c[SARINS_INS_HEIGHT];
    f->out[SARINS_INS_OUT_NAV_TIME] = -c[SARINS_INS_ALIGN_TIME];
    f->out[SARINS_INS_OUT_SOLUTION_TIME] = f->start_time;
    if (c[SARINS_INS_ALIGN_TIME] == 0.0) {
        f->out[SARINS_INS_OUT_YAW] = f->attitude0[0];
        f->out[SARINS_INS_OUT_PITCH] = f->attitude0[1];
        f->out[SARINS_INS_OUT_ROLL] = f->attitude0[2];
        f->phase = 2;
    }
}

void sarins_ins_fmu_setup(sarins_ins_fmu *f, const double *config, const double *attitude0, double start_time)
{
    memset(f, 0, sizeof *f);
    for (int i = 0; i < SARINS_INS_CONFIG; i++)
        f->config[i] = config[i];
    for (int i = 0; i < 3; i++)
        f->attitude0[i] = attitude0[i];
    f->start_time = start_time;
    publish_start(f);
}

int sarins_ins_fmu_start(sarins_ins_fmu *f, const double *in, char *msg, size_t size)
{
    double config[SARINS_INS_CONFIG];
    for (int i = 0; i < SARINS_INS_CONFIG; i++)
        config[i] = f->config[i];
    config[SARINS_INS_STEP] = 1.0;
    int status = sarins_ins_config_check(config, msg, size);
    if (status != SARINS_INS_OK)
        return status;
    publish_start(f);
    f->out[SARINS_INS_OUT_TEMP_ALIGN_START] = in[SARINS_INS_IN_TEMP_GYRO_Z];
    f->out[SARINS_INS_OUT_TEMP_AZIMUTH_GYRO] = in[SARINS_INS_IN_TEMP_GYRO_Z];
    sarins_ins_comp_init(&f->comp, in + SARINS_INS_IN_CORRECTION_C, in[SARINS_INS_IN_APPLY_FROM]);
    return SARINS_INS_OK;
}

/* The INS of the first doStep (step h) into ins. */
static int first_ins(const sarins_ins_fmu *f, double h, sarins_ins *ins, char *msg, size_t size)
{
    double config[SARINS_INS_CONFIG], mat_nb0[9];
    for (int i = 0; i < SARINS_INS_CONFIG; i++)
        config[i] = f->config[i];
    config[SARINS_INS_STEP] = h;
    sarins_euler_to_mat(f->attitude0[0], f->attitude0[1], f->attitude0[2], mat_nb0);
    return sarins_ins_init(ins, config, mat_nb0, msg, size);
}

/* The outputs after a step that wrote the navigation row row (T the interval's gyro temperature, degC). */
static void publish(sarins_ins_fmu *f, const double *row, double temp)
{
    const sarins_ins *s = &f->ins;
    double err[4];
    for (int i = 0; i < SARINS_INS_ROW; i++)
        f->out[SARINS_INS_OUT_LAT + i] = row[i];
    sarins_ins_position_error(s, 1, row, err);
    for (int i = 0; i < 4; i++)
        f->out[SARINS_INS_OUT_LAT_ERROR + i] = err[i];
    f->out[SARINS_INS_OUT_POSITION_ERROR] = sm_hypot(err[2], err[3]);
    f->phase = sarins_ins_phase(s);
    double time = (double)s->steps * s->config[SARINS_INS_STEP]; /* since the start, s */
    double nav_time = time - s->config[SARINS_INS_ALIGN_TIME];
    f->out[SARINS_INS_OUT_NAV_TIME] = nav_time;
    f->out[SARINS_INS_OUT_SOLUTION_TIME] = f->start_time + time;
    f->out[SARINS_INS_OUT_GYRO_DRIFT_EST_X] = s->gyro_comp[0];
    f->out[SARINS_INS_OUT_GYRO_DRIFT_EST_Y] = s->gyro_comp[1];
    f->out[SARINS_INS_OUT_ACCEL_BIAS_EST_X] = s->accel_comp[0];
    f->out[SARINS_INS_OUT_ACCEL_BIAS_EST_Y] = s->accel_comp[1];
    f->out[SARINS_INS_OUT_TEMP_AZIMUTH_GYRO] = temp;
    if (f->phase != 2 || sm_fabs(nav_time) < 0.5 * f->step) { /* aligning, or the first navigation point */
        f->out[SARINS_INS_OUT_TEMP_ALIGN_END] = temp;
        f->out[SARINS_INS_OUT_TEMP_CHANGE_ALIGN] = temp - f->out[SARINS_INS_OUT_TEMP_ALIGN_START];
    }
}

int sarins_ins_fmu_do_step(sarins_ins_fmu *f, const double *in, double t, double h, char *msg, size_t size)
{
    (void)t; /* the interval is named by the increments' time tag */
    if (!(h > 0.0 && isfinite(h))) {
        REASON("communication step %.17g must be positive and finite", h);
        return SARINS_INS_BAD_STEP;
    }
    if (f->step != 0.0 && sm_fabs(h - f->step) > 1e-9 * f->step) {
        REASON("communication step changed from %.17g s to %.17g s; this FMU needs a fixed step", f->step, h);
        return SARINS_INS_BAD_STEP;
    }
    sarins_ins first;
    const sarins_ins *ins = &f->ins;
    if (!f->running) {
        int status = first_ins(f, h, &first, msg, size);
        if (status != SARINS_INS_OK)
            return status;
        ins = &first;
    }
    for (int i = 0; i <= SARINS_INS_IN_TEMP_GYRO_Z; i++)
        if (!isfinite(in[i])) {
            REASON("increments, increment_end_time or temp_gyro_z contain NaN or infinity");
            return SARINS_INS_BAD_STEP;
        }
    double tag = in[SARINS_INS_IN_INCREMENT_END_TIME], temp = in[SARINS_INS_IN_TEMP_GYRO_Z];
    double done = f->start_time + (double)ins->steps * h; /* end of the last interval integrated */
    int waiting = same_time(tag, done, h) && ins->steps == 0; /* no increments yet (Jacobi's first step) */
    comp_plan plan;
    double correction = 0.0;
    if (!waiting) {
        if (!same_time(tag, done + h, h)) {
            REASON("increments tagged increment_end_time=%.9g s %s: the INS has integrated up to %.9g s and needs "
                   "the interval ending at %.9g s", tag,
                   same_time(tag, done, h) ? "were already integrated" : "would skip an interval", done, done + h);
            return SARINS_INS_BAD_STEP;
        }
        double nav_start = (double)ins->steps * h - ins->config[SARINS_INS_ALIGN_TIME]; /* the interval's start */
        int status = comp_plan_for(&f->comp, in + SARINS_INS_IN_CORRECTION_C, in[SARINS_INS_IN_APPLY_FROM],
                                   nav_start, SARINS_INS_TAG_TOL * h, &plan, msg, size);
        if (status != SARINS_INS_OK)
            return status;
        /* eps(T) = (a T + b) T + c */
        correction = (plan.current[2] * temp + plan.current[1]) * temp + plan.current[0];
        if (!isfinite(correction)) {
            REASON("axial correction contains NaN or infinity");
            return SARINS_INS_BAD_STEP;
        }
    }
    /* every check passed: from here on the step happens */
    f->step = h;
    if (!f->running) {
        f->ins = first;
        f->running = 1;
    }
    if (waiting)
        return SARINS_INS_OK;
    comp_apply(&f->comp, &plan, in + SARINS_INS_IN_CORRECTION_C, in[SARINS_INS_IN_APPLY_FROM]);
    if (f->ins.steps == 0)
        f->out[SARINS_INS_OUT_TEMP_ALIGN_START] = temp; /* at the end of the first interval */
    double row[SARINS_INS_ROW];
    int status = sarins_ins_steps(&f->ins, 1, in + SARINS_INS_IN_DTHETA_X, in + SARINS_INS_IN_DV_X, &correction,
                                  row, NULL);
    if (status != SARINS_INS_OK) { /* unreachable: every input was checked finite above */
        REASON("the INS refused finite increments (internal error)");
        return status;
    }
    publish(f, row, temp);
    return SARINS_INS_OK;
}

int64_t sarins_ins_fmu_layout(int64_t *offsets)
{
    offsets[0] = (int64_t)offsetof(sarins_ins_fmu, out);
    offsets[1] = (int64_t)offsetof(sarins_ins_fmu, phase);
    offsets[2] = (int64_t)offsetof(sarins_ins_fmu, ins);
    offsets[3] = (int64_t)offsetof(sarins_ins_fmu, comp);
    offsets[4] = (int64_t)(offsetof(sarins_ins_fmu, comp) + offsetof(sarins_ins_comp, count));
    return (int64_t)sizeof(sarins_ins_fmu);
}
