/* IMUCompensator FMU (native): a trained seed 003 compensator between IMUThermal and the INS.
 *
 * The declaration (variables, the time-tag contract) is fmus/imu_compensator_slave.py.  The model is read
 * at initialisation from a binary model file (sarins_fmu/core/netfile.h): model_file when given, else
 * resources/compensator.bin, and evaluated by the C core's sarins_comp_run (netmodel.h), the function the
 * library's compensators call in process.  The model sees x = (dtheta / h, dv / h, mean of the six
 * temperatures) in rad/s, m/s^2, degC and its outputs times h are the compensated increments (rad, m/s).
 *
 * Held between steps (the FMU state, plain bytes): the communication step, the last time tag and the
 * recurrent state (zero at initialisation).  The model in c->work depends on the parameters only.
 */
#include "smath.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "model.h"
#include "netfile.h"
#include "netmodel.h"
#include "variables.h"

#define MODEL_IN_RESOURCES "compensator.bin"
#define NO_TAG (-1.0e9) /* s: start value of raw_increment_end_time, not connected (fmus/slave_support.py) */
#define STEP_TOL 1e-9   /* relative: a communication step equal to the first one */
#define TAG_TOL 1e-6    /* of a step: two time tags closer than this name the same communication point */
#define PATH_MAX_BYTES 4096

typedef struct {
    double step;     /* s, fixed by the first doStep */
    double last_tag; /* s, end of the last interval compensated */
    int have_step;
    int have_last;
    double rnn[SARINS_COMP_MAX_STATE]; /* recurrent state (sarins_comp_state_size doubles used) */
} ic_state;

static const int RAW[6] = {SARINS_R_raw_dtheta_x, SARINS_R_raw_dtheta_y, SARINS_R_raw_dtheta_z,
                           SARINS_R_raw_dv_x, SARINS_R_raw_dv_y, SARINS_R_raw_dv_z};
static const int OUT[6] = {SARINS_R_dtheta_x, SARINS_R_dtheta_y, SARINS_R_dtheta_z,
                           SARINS_R_dv_x, SARINS_R_dv_y, SARINS_R_dv_z};
static const int TEMPS[6] = {SARINS_R_temp_gyro_x, SARINS_R_temp_gyro_y, SARINS_R_temp_gyro_z,
                             SARINS_R_temp_accel_x, SARINS_R_temp_accel_y, SARINS_R_temp_accel_z};

static void ic_release(sarins_ctx *c)
{
    sarins_comp *m = c->work;
    if (m != NULL) {
        sarins_comp_release(m);
        free(m);
    }
    c->work = NULL;
}

static int load(sarins_ctx *c)
{
    char path[PATH_MAX_BYTES], msg[512];
    const char *file = c->s[SARINS_S_model_file];
    if (file[0] != '\0') {
        snprintf(path, sizeof path, "%s", file);
    } else if (c->resources == NULL) {
        sarins_log(c, SARINS_ERROR, "no model_file given and the FMU has no resources folder (%s)",
                   c->resources_problem ? c->resources_problem : "unknown");
        return SARINS_ERROR;
    } else if ((size_t)snprintf(path, sizeof path, "%s/%s", c->resources, MODEL_IN_RESOURCES) >= sizeof path) {
        sarins_log(c, SARINS_ERROR, "the resources path is too long");
        return SARINS_ERROR;
    }
    unsigned char *buf = NULL;
    size_t n = 0;
    sarins_netfile f;
    sarins_comp *m = NULL;
    int code = sarins_netfile_read_path(path, &buf, &n, msg, sizeof msg);
    if (code == SARINS_NETFILE_OK)
        code = sarins_netfile_parse(buf, n, &f, msg, sizeof msg);
    if (code == SARINS_NETFILE_OK) {
        m = malloc(sizeof *m);
        code = m == NULL ? SARINS_NETFILE_MEMORY : sarins_comp_build(m, &f, msg, sizeof msg);
        if (m == NULL)
            snprintf(msg, sizeof msg, "out of memory");
    }
    free(buf);
    if (code != SARINS_NETFILE_OK) {
        free(m); /* sarins_comp_build released what it allocated */
        sarins_log(c, SARINS_ERROR, "model file '%s': %s", path, msg);
        return SARINS_ERROR;
    }
    c->work = m;
    return SARINS_OK;
}

static void publish_start(sarins_ctx *c)
{
    c->r[SARINS_R_increment_end_time] = c->start_time; /* no increments yet */
    c->r[SARINS_R_temp_azimuth_gyro] = c->r[SARINS_R_temp_gyro_z];
}

static int ic_initialize(sarins_ctx *c)
{
    memset(c->state, 0, sizeof(ic_state));
    publish_start(c);
    if (c->quiet)
        return SARINS_OK; /* the model is read when initialisation ends */
    if (load(c) != SARINS_OK)
        return SARINS_ERROR;
    const sarins_comp *m = c->work;
    c->i[SARINS_I_model_kind] = (int)m->kind - SARINS_NET_KIND_TRADITIONAL; /* index in compensators.KINDS */
    return SARINS_OK;
}

/* End time of the interval to compensate now (*end), 0 if no new one arrived; -1 on a bad tag (logged). */
static int interval(sarins_ctx *c, ic_state *st, double t, double h, double *end)
{
    double tag = c->r[SARINS_R_raw_increment_end_time];
    if (tag == NO_TAG) {
        *end = t + h; /* untagged: the current step's increments */
        return 1;
    }
    if (!isfinite(tag)) {
        sarins_log(c, SARINS_ERROR, "ValueError: raw_increment_end_time is not finite");
        return -1;
    }
    if (tag <= c->start_time + 1e-6 * h || (st->have_last && sm_fabs(tag - st->last_tag) <= TAG_TOL * h))
        return 0;
    double expected = (st->have_last ? st->last_tag : c->start_time) + h;
    if (!(sm_fabs(tag - expected) <= TAG_TOL * h)) {
        sarins_log(c, SARINS_ERROR, "ValueError: raw increments tagged raw_increment_end_time=%.9g s where the "
                   "interval ending at %.9g s was due (each interval once, in order)", tag, expected);
        return -1;
    }
    st->last_tag = tag;
    st->have_last = 1;
    *end = tag;
    return 1;
}

static int ic_do_step(sarins_ctx *c, double t, double h)
{
    ic_state *st = c->state;
    sarins_comp *m = c->work;
    if (m == NULL) {
        sarins_log(c, SARINS_ERROR, "no model loaded");
        return SARINS_ERROR;
    }
    if (st->have_step && sm_fabs(h - st->step) > STEP_TOL * st->step) {
        sarins_log(c, SARINS_ERROR, "ValueError: communication step changed from %.17g s to %.17g s; this FMU needs a "
                   "fixed step", st->step, h);
        return SARINS_ERROR;
    }
    st->step = h;
    st->have_step = 1;
    double end = 0.0;
    int got = interval(c, st, t, h, &end);
    if (got <= 0)
        return got < 0 ? SARINS_ERROR : SARINS_OK;
    double x[SARINS_COMP_N_IN], y[SARINS_COMP_N_OUT], sum = 0.0;
    for (int i = 0; i < 6; i++)
        x[i] = c->r[RAW[i]] / h; /* mean rate, mean specific force */
    for (int i = 0; i < 6; i++)
        sum += c->r[TEMPS[i]];
    x[6] = sum / 6.0;
    int status = sarins_comp_run(m, st->rnn, 1, x, y, NULL);
    if (status == SARINS_NET_INPUT) {
        sarins_log(c, SARINS_ERROR, "ValueError: non-finite IMU input at t=%.9g s", t);
        return SARINS_ERROR;
    }
    if (status != SARINS_NET_OK) {
        sarins_log(c, SARINS_ERROR, "ValueError: %s at t=%.9g s", status == SARINS_NET_SINGULAR ?
                   "a calibration matrix is singular" : "the compensated output is not finite", t);
        return SARINS_ERROR;
    }
    for (int i = 0; i < 6; i++)
        c->r[OUT[i]] = y[i] * h;
    c->r[SARINS_R_temperature] = x[6];
    c->r[SARINS_R_increment_end_time] = end;
    c->r[SARINS_R_temp_azimuth_gyro] = c->r[SARINS_R_temp_gyro_z];
    return SARINS_OK;
}

/* Every field of the state within what do_step relies on (model.h, State validation). */
static int ic_check_state(const sarins_ctx *c, int running)
{
    const ic_state *s = c->state;
    (void)running;
    /* the communication step: 0 before the first step, positive after */
    if (!sarins_state_int(c, "have_step", s->have_step, 0, 1)
        || !sarins_state_real(c, "step", s->step, s->have_step ? 1e-300 : 0.0, s->have_step ? 1e300 : 0.0))
        return SARINS_ERROR;
    if (!sarins_state_int(c, "have_last", s->have_last, 0, 1)
        || (s->have_last && !sarins_state_real(c, "last_tag", s->last_tag, -1e300, 1e300))
        || !sarins_state_finite(c, "rnn", s->rnn, SARINS_COMP_MAX_STATE))
        return SARINS_ERROR;
    return SARINS_OK;
}

const sarins_model sarins_model_desc = {
    .table = &SARINS_TABLE,
    .state_size = sizeof(ic_state),
    .state_version = 1,
    .check_state = ic_check_state,
    .initialize = ic_initialize,
    .do_step = ic_do_step,
    .release = ic_release,
};
