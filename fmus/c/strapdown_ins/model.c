/* StrapdownINS as a native model for the shared FMI 2.0 glue (fmus/c/model.h).
 *
 * Thin: the parameter checks of the slave (fmus/strapdown_ins_slave.py, the
 * one declaration of the variables) with logged reasons, then the C core's
 * StrapdownINS FMU step (sarins_fmu/core/ins_fmu_step.h: time tags, the
 * drift compensation queue, alignment and navigation), whose state struct
 * is this model's whole state (plain bytes, no pointer).  Units and frames
 * as in the core's headers: rad, m, m/s, s, degC, ENU.
 *
 * Sub-interval inputs (FMI 3.0, sub_inputs = 1): a step of size h integrates
 * the n_sub sub-intervals of the *_sub arrays one by one, each a core step
 * of h / n_sub with its own increments, gyro_z temperature and time tag
 * (increment_end_time - (n_sub - 1 - k) h / n_sub): the same calls, in the
 * same order, as an INS stepped at h / n_sub with the scalar inputs.
 */
#include "smath.h"

#include <stdio.h>

#include "ins_fmu_step.h"
#include "model.h"
#include "variables.h"

#define PI 3.141592653589793
#define DEG (PI / 180.0)

/* The filter parameters kf_<name>, in the order of the core's settings array (ins.h). */
static const unsigned FILTER_SLOTS[SARINS_INS_CONFIG - SARINS_INS_FILTER_FIRST] = {
    SARINS_R_kf_arw, SARINS_R_kf_vrw, SARINS_R_kf_drift_rw, SARINS_R_kf_bias_rw, SARINS_R_kf_velocity_meas_std,
    SARINS_R_kf_tilt0_std, SARINS_R_kf_heading0_std, SARINS_R_kf_velocity0_std, SARINS_R_kf_drift0_std,
    SARINS_R_kf_bias0_std};
static const char *const FILTER_NAMES[SARINS_INS_CONFIG - SARINS_INS_FILTER_FIRST] = {
    "kf_arw", "kf_vrw", "kf_drift_rw", "kf_bias_rw", "kf_velocity_meas_std", "kf_tilt0_std", "kf_heading0_std",
    "kf_velocity0_std", "kf_drift0_std", "kf_bias0_std"};

/* The core's inputs, in its order (ins_fmu_step.h). */
static const unsigned INPUT_SLOTS[SARINS_INS_N_IN] = {
    SARINS_R_dtheta_x, SARINS_R_dtheta_y, SARINS_R_dtheta_z, SARINS_R_dv_x, SARINS_R_dv_y, SARINS_R_dv_z,
    SARINS_R_increment_end_time, SARINS_R_temp_gyro_z, SARINS_R_axial_drift_correction,
    SARINS_R_axial_drift_correction_b, SARINS_R_axial_drift_correction_a, SARINS_R_axial_drift_apply_from};

/* The core's Real outputs, in its order. */
static const unsigned OUTPUT_SLOTS[SARINS_INS_N_OUT] = {
    SARINS_R_lat, SARINS_R_lon, SARINS_R_height, SARINS_R_v_e, SARINS_R_v_n, SARINS_R_v_u, SARINS_R_yaw,
    SARINS_R_pitch, SARINS_R_roll, SARINS_R_lat_error, SARINS_R_lon_error, SARINS_R_north_error,
    SARINS_R_east_error, SARINS_R_position_error, SARINS_R_nav_time, SARINS_R_gyro_drift_est_x,
    SARINS_R_gyro_drift_est_y, SARINS_R_accel_bias_est_x, SARINS_R_accel_bias_est_y, SARINS_R_temp_align_start,
    SARINS_R_temp_align_end, SARINS_R_temp_change_align, SARINS_R_temp_azimuth_gyro, SARINS_R_solution_time};

/* the sub-interval arrays, in the order of the core's first six inputs, then temp_gyro_z */
static const int SUB_ARRAYS[7] = {SARINS_A_dtheta_x_sub, SARINS_A_dtheta_y_sub, SARINS_A_dtheta_z_sub,
                                  SARINS_A_dv_x_sub, SARINS_A_dv_y_sub, SARINS_A_dv_z_sub,
                                  SARINS_A_temp_gyro_z_sub};

static void read_inputs(const sarins_ctx *c, double *in)
{
    for (int i = 0; i < SARINS_INS_N_IN; i++)
        in[i] = c->r[INPUT_SLOTS[i]];
}

static void write_outputs(sarins_ctx *c, const sarins_ins_fmu *f)
{
    for (int i = 0; i < SARINS_INS_N_OUT; i++)
        c->r[OUTPUT_SLOTS[i]] = f->out[i];
    c->i[SARINS_I_phase] = (int)f->phase;
}

/* The core's settings array from the parameters (its step is set by the first doStep). */
static void read_config(const sarins_ctx *c, double *config)
{
    config[SARINS_INS_LAT] = c->r[SARINS_R_lat0];
    config[SARINS_INS_LON] = c->r[SARINS_R_lon0];
    config[SARINS_INS_HEIGHT] = c->r[SARINS_R_height0];
    config[SARINS_INS_ALIGN_TIME] = c->r[SARINS_R_align_time];
    config[SARINS_INS_COARSE_TIME] = c->r[SARINS_R_coarse_time];
    config[SARINS_INS_STEP] = 1.0;
    for (int i = 0; i < SARINS_INS_CONFIG - SARINS_INS_FILTER_FIRST; i++)
        config[SARINS_INS_FILTER_FIRST + i] = c->r[FILTER_SLOTS[i]];
}

static int refuse(const sarins_ctx *c, const char *name, double value, const char *what)
{
    sarins_log(c, SARINS_ERROR, "parameter %s = %.17g %s", name, value, what);
    return SARINS_ERROR;
}

/* A parameter within [low, high] (SI), reported in degrees. */
static int check_range_deg(const sarins_ctx *c, const char *name, double value, double low, double high)
{
    if (isfinite(value) && low <= value && value <= high)
        return SARINS_OK;
    sarins_log(c, SARINS_ERROR, "parameter %s = %.9g deg is outside [%.9g, %.9g] deg", name, value / DEG,
               low / DEG, high / DEG);
    return SARINS_ERROR;
}

/* The slave's parameter checks, in its order. */
static int check_parameters(const sarins_ctx *c)
{
    static const char *const ATTITUDE[3] = {"yaw0", "pitch0", "roll0"};
    const double attitude[3] = {c->r[SARINS_R_yaw0], c->r[SARINS_R_pitch0], c->r[SARINS_R_roll0]};
    for (int i = 0; i < 3; i++)
        if (!isfinite(attitude[i]))
            return refuse(c, ATTITUDE[i], attitude[i], "is not a finite number");
    if (check_range_deg(c, "pitch0", attitude[1], -0.5 * PI, 0.5 * PI) != SARINS_OK)
        return SARINS_ERROR;
    static const char *const SITE[5] = {"lat0", "lon0", "height0", "align_time", "coarse_time"};
    double config[SARINS_INS_CONFIG];
    read_config(c, config);
    for (int i = 0; i < 5; i++)
        if (!isfinite(config[i]))
            return refuse(c, SITE[i], config[i], "is not a finite number");
    for (int i = 0; i < SARINS_INS_CONFIG - SARINS_INS_FILTER_FIRST; i++)
        if (!isfinite(config[SARINS_INS_FILTER_FIRST + i]))
            return refuse(c, FILTER_NAMES[i], config[SARINS_INS_FILTER_FIRST + i], "is not a finite number");
    for (int i = 0; i < SARINS_INS_CONFIG - SARINS_INS_FILTER_FIRST; i++)
        if (!(config[SARINS_INS_FILTER_FIRST + i] > 0.0))
            return refuse(c, FILTER_NAMES[i], config[SARINS_INS_FILTER_FIRST + i], "must be positive");
    for (int i = SARINS_INS_ALIGN_TIME; i <= SARINS_INS_COARSE_TIME; i++)
        if (!(config[i] >= 0.0))
            return refuse(c, SITE[i], config[i], "must not be negative");
    if (check_range_deg(c, "lat0", config[SARINS_INS_LAT], -SARINS_INS_LAT_LIMIT, SARINS_INS_LAT_LIMIT) != SARINS_OK)
        return SARINS_ERROR;
    if (c->i[SARINS_I_n_sub] < 1 || c->i[SARINS_I_n_sub] > SARINS_TABLE.max_dim) {
        sarins_log(c, SARINS_ERROR, "parameter n_sub = %d must be an integer in [1, %d]", c->i[SARINS_I_n_sub],
                   SARINS_TABLE.max_dim);
        return SARINS_ERROR;
    }
    return sarins_check_sub_switch(c, "sub_inputs", c->i[SARINS_I_sub_inputs], "scalar increments");
}

static int initialize(sarins_ctx *c)
{
    sarins_ins_fmu *f = (sarins_ins_fmu *)c->state;
    if (!c->quiet && check_parameters(c) != SARINS_OK)
        return SARINS_ERROR;
    double config[SARINS_INS_CONFIG];
    read_config(c, config);
    const double attitude[3] = {c->r[SARINS_R_yaw0], c->r[SARINS_R_pitch0], c->r[SARINS_R_roll0]};
    sarins_ins_fmu_setup(f, config, attitude, c->start_time);
    if (!c->quiet) {
        char msg[512];
        double in[SARINS_INS_N_IN];
        read_inputs(c, in);
        if (sarins_ins_fmu_start(f, in, msg, sizeof msg) != SARINS_INS_OK) {
            sarins_log(c, SARINS_ERROR, "%s", msg);
            return SARINS_ERROR;
        }
    }
    write_outputs(c, f);
    return SARINS_OK;
}

/* sub_inputs = 1: the n_sub sub-intervals of the arrays, one core step of h / n_sub each (see the top). */
static int do_sub_steps(sarins_ctx *c, sarins_ins_fmu *f, double *in, double t, double h)
{
    int n = c->i[SARINS_I_n_sub];
    double h_sub = h / (double)n, tag = in[SARINS_INS_IN_INCREMENT_END_TIME];
    char msg[512];
    for (int j = 0; j < 7; j++)
        for (int k = 0; k < n; k++)
            if (!isfinite(c->a[SUB_ARRAYS[j]][k])) {
                sarins_log(c, SARINS_ERROR, "the *_sub array inputs contain NaN or infinity (element %d)", k + 1);
                return SARINS_ERROR;
            }
    /* the start time as the tag before anything was integrated: Jacobi's first step, nothing to do yet */
    if (!(f->running && f->ins.steps > 0) && sm_fabs(tag - f->start_time) <= SARINS_INS_TAG_TOL * h_sub) {
        if (sarins_ins_fmu_do_step(f, in, t, h_sub, msg, sizeof msg) != SARINS_INS_OK) {
            sarins_log(c, SARINS_ERROR, "%s", msg);
            return SARINS_ERROR;
        }
        return SARINS_OK;
    }
    for (int k = 0; k < n; k++) {
        for (int j = 0; j < 6; j++)
            in[j] = c->a[SUB_ARRAYS[j]][k];
        in[SARINS_INS_IN_TEMP_GYRO_Z] = c->a[SARINS_A_temp_gyro_z_sub][k];
        in[SARINS_INS_IN_INCREMENT_END_TIME] = k == n - 1 ? tag : tag - (double)(n - 1 - k) * h_sub;
        if (sarins_ins_fmu_do_step(f, in, t + (double)k * h_sub, h_sub, msg, sizeof msg) != SARINS_INS_OK) {
            sarins_log(c, SARINS_ERROR, "sub-interval %d of %d: %s", k + 1, n, msg);
            return SARINS_ERROR;
        }
    }
    return SARINS_OK;
}

static int do_step(sarins_ctx *c, double t, double h)
{
    sarins_ins_fmu *f = (sarins_ins_fmu *)c->state;
    char msg[512];
    double in[SARINS_INS_N_IN];
    read_inputs(c, in);
    if (c->i[SARINS_I_sub_inputs] == 1) {
        int status = do_sub_steps(c, f, in, t, h);
        if (status == SARINS_OK)
            write_outputs(c, f);
        return status;
    }
    if (sarins_ins_fmu_do_step(f, in, t, h, msg, sizeof msg) != SARINS_INS_OK) {
        sarins_log(c, SARINS_ERROR, "%s", msg);
        return SARINS_ERROR;
    }
    write_outputs(c, f);
    return SARINS_OK;
}

static void release(sarins_ctx *c) { c->work = NULL; /* nothing allocated: the state struct is all */ }

/* Every field of the state within what do_step relies on (model.h, State validation): the phase, the
 * compensation queue's ring indices within its buffer, the step, every number finite. */
static int ins_check_state(const sarins_ctx *c, int running)
{
    const sarins_ins_fmu *f = c->state;
    const sarins_ins *s = &f->ins;
    const sarins_ins_comp *q = &f->comp;
    (void)running;
    if (!sarins_state_int(c, "running", f->running, 0, 1) || !sarins_state_int(c, "phase", f->phase, 0, 2)
        || !sarins_state_real(c, "step", f->step, f->running ? 1e-300 : 0.0, f->running ? 1e300 : 1e300)
        || !sarins_state_real(c, "start_time", f->start_time, -1e300, 1e300)
        || !sarins_state_int(c, "comp.first", q->first, 0, SARINS_INS_COMP_QUEUE - 1)
        || !sarins_state_int(c, "comp.count", q->count, 0, SARINS_INS_COMP_QUEUE)
        || !sarins_state_int(c, "comp.started", q->started, 0, 1)
        || !sarins_state_finite(c, "config", f->config, SARINS_INS_CONFIG)
        || !sarins_state_finite(c, "attitude0", f->attitude0, 3)
        || !sarins_state_finite(c, "out", f->out, SARINS_INS_N_OUT)
        || !sarins_state_finite(c, "comp.seen.value", q->seen.value, 3)
        || !sarins_state_finite(c, "comp.current", q->current, 3)
        || !sarins_state_int(c, "ins.steps", s->steps, 0, INT64_MAX)
        || !sarins_state_int(c, "ins.n_coarse", s->n_coarse, 0, INT64_MAX)
        || !sarins_state_int(c, "ins.n_align", s->n_align, 0, INT64_MAX)
        || !sarins_state_finite(c, "ins.config", s->config, SARINS_INS_CONFIG)
        || !sarins_state_finite(c, "ins.q0", s->q0, 4) || !sarins_state_finite(c, "ins.q", s->q, 4)
        || !sarins_state_finite(c, "ins.v", s->v, 3)
        || !sarins_state_real(c, "ins.pos[0] (latitude)", s->pos[0], -PI / 2, PI / 2)
        || !sarins_state_finite(c, "ins.pos", s->pos, 3)
        || !sarins_state_finite(c, "ins.gyro_comp", s->gyro_comp, 3)
        || !sarins_state_finite(c, "ins.accel_comp", s->accel_comp, 3)
        || !sarins_state_finite(c, "ins.x", s->x, SARINS_INS_ALIGN_STATES)
        || !sarins_state_finite(c, "ins.p", s->p, SARINS_INS_ALIGN_STATES * SARINS_INS_ALIGN_STATES)
        || !sarins_state_finite(c, "ins.q_diag", s->q_diag, SARINS_INS_ALIGN_STATES)
        || !sarins_state_finite(c, "ins.q_b0b", s->q_b0b, 4) || !sarins_state_finite(c, "ins.v_b0", s->v_b0, 3)
        || !sarins_state_finite(c, "ins.v_b0_half", s->v_b0_half, 3))
        return SARINS_ERROR;
    for (int64_t k = 0; k < q->count; k++) {
        const sarins_ins_comp_pair *pair = &q->pending[(q->first + k) % SARINS_INS_COMP_QUEUE];
        if (!sarins_state_finite(c, "comp.pending.value", pair->value, 3)
            || !sarins_state_finite(c, "comp.pending.apply_from", &pair->apply_from, 1))
            return SARINS_ERROR;
    }
    return SARINS_OK;
}

const sarins_model sarins_model_desc = {
    .table = &SARINS_TABLE,
    .state_size = sizeof(sarins_ins_fmu),
    .state_version = 1,
    .check_state = ins_check_state,
    .initialize = initialize,
    .do_step = do_step,
    .release = release,
    .terminate = NULL,
    .work_state_size = NULL,
    .save_work_state = NULL,
    .load_work_state = NULL,
};
