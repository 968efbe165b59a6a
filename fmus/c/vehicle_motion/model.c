/* VehicleMotion FMU (native): seed 002's land vehicle (drives, turns, stops, body sway and vibration) as
 * the moving-base inputs of IMUThermal.
 *
 * The declaration (variables, descriptions, the timing contract) is fmus/vehicle_motion_slave.py; the
 * trajectory is the C core's (sarins_fmu/core/vehicle.h), the same stream sarins_fmu.vehicle runs in
 * process, so the outputs at grid point k are row k of VehicleTrajectory.rows bit for bit.  The core
 * checks every parameter and leg; this file maps the FMU's variables onto it and reports.  The outputs
 * describe the step that starts at base_motion_time (the start time at initialisation, t + h after
 * doStep(t, h)).  Units: rad, rad/s, rad/s^2, m/s, m/s^2, s.
 */
#include "smath.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "model.h"
#include "variables.h"
#include "vehicle.h"

#define TAG_TOL 1e-9                /* relative to the grid: two time tags name the same point */
#define MAX_LEGS (SARINS_STRING_MAX / 2) /* "stop 1;" is the shortest leg: fewer legs fit into the string */
#define STOPPED_SPEED 1e-6          /* m/s: at rest below this */

/* What changes during a run (plain data: the FMU state copies it). */
typedef struct {
    sarins_vehicle vehicle; /* the stream at the next grid point to publish */
    double step;            /* s, the communication step, fixed by the first doStep */
    int have_step;
} vm_state;

/* What the parameters give (built at initialisation, not part of the FMU state). */
typedef struct {
    sarins_vehicle_params params;
    sarins_vehicle_segment segments[3 * MAX_LEGS + 2];
    sarins_leg legs[MAX_LEGS]; /* the parsed legs string (scratch of build) */
    int64_t n_segments, n_steps;
    double end_speed; /* m/s, after the last leg */
} vm_work;

static void vm_release(sarins_ctx *c)
{
    free(c->work);
    c->work = NULL;
}

/* The core's parameters from the FMU's variables; SARINS_ERROR with a logged reason. */
static int build(sarins_ctx *c, vm_work *w)
{
    const double *r = c->r;
    sarins_vehicle_params *p = &w->params;
    sarins_vehicle_params_default(p);
    p->lat0 = r[SARINS_R_lat0];
    p->lon0 = r[SARINS_R_lon0];
    p->heading0 = r[SARINS_R_heading0];
    p->step = r[SARINS_R_grid];
    p->lead_time = r[SARINS_R_lead_time];
    p->sway_pitch = r[SARINS_R_sway_pitch];
    p->sway_roll = r[SARINS_R_sway_roll];
    p->sway_period = r[SARINS_R_sway_period];
    p->vibration = r[SARINS_R_vibration];
    p->reference_speed = r[SARINS_R_reference_speed];
    if (c->i[SARINS_I_body_seed] < 0) {
        sarins_log(c, SARINS_ERROR, "parameter body_seed = %d must be >= 0", c->i[SARINS_I_body_seed]);
        return SARINS_ERROR;
    }
    p->seed = (uint64_t)c->i[SARINS_I_body_seed];
    char msg[512];
    int64_t n_legs = sarins_vehicle_parse_legs(c->s[SARINS_S_legs], w->legs, MAX_LEGS, msg, sizeof msg);
    if (n_legs < 0) {
        sarins_log(c, SARINS_ERROR, "parameter legs: %s", msg);
        return SARINS_ERROR;
    }
    int code = sarins_vehicle_segments(p, w->legs, n_legs, w->segments, 3 * MAX_LEGS + 2, &w->n_segments,
                                       &w->n_steps, msg, sizeof msg);
    if (code) {
        sarins_log(c, SARINS_ERROR, "parameters (grid = step, legs = '%s'): %s", c->s[SARINS_S_legs], msg);
        return SARINS_ERROR;
    }
    w->end_speed = w->segments[w->n_segments - 1].end_speed;
    return SARINS_OK;
}

/* Write the step that starts at the stream's grid point and move the stream on. */
static void publish(sarins_ctx *c, const vm_work *w, vm_state *st, double time)
{
    double out[SARINS_VEH_N_OUT];
    sarins_vehicle_step(&st->vehicle, w->segments, w->n_segments, out);
    double *r = c->r;
    r[SARINS_R_vehicle_yaw] = out[SARINS_VEH_YAW];
    r[SARINS_R_vehicle_pitch] = out[SARINS_VEH_PITCH];
    r[SARINS_R_vehicle_roll] = out[SARINS_VEH_ROLL];
    r[SARINS_R_vehicle_yaw_rate] = out[SARINS_VEH_YAW_RATE];
    r[SARINS_R_vehicle_pitch_rate] = out[SARINS_VEH_PITCH_RATE];
    r[SARINS_R_vehicle_roll_rate] = out[SARINS_VEH_ROLL_RATE];
    r[SARINS_R_vehicle_yaw_accel] = out[SARINS_VEH_YAW_ACC];
    r[SARINS_R_vehicle_pitch_accel] = out[SARINS_VEH_PITCH_ACC];
    r[SARINS_R_vehicle_roll_accel] = out[SARINS_VEH_ROLL_ACC];
    r[SARINS_R_base_rate_e] = out[SARINS_VEH_W_E];
    r[SARINS_R_base_rate_n] = out[SARINS_VEH_W_N];
    r[SARINS_R_base_rate_u] = out[SARINS_VEH_W_U];
    r[SARINS_R_base_force_e] = out[SARINS_VEH_F_E];
    r[SARINS_R_base_force_n] = out[SARINS_VEH_F_N];
    r[SARINS_R_base_force_u] = out[SARINS_VEH_F_U];
    r[SARINS_R_lat] = out[SARINS_VEH_LAT];
    r[SARINS_R_lon] = out[SARINS_VEH_LON];
    r[SARINS_R_v_e] = out[SARINS_VEH_V_E];
    r[SARINS_R_v_n] = out[SARINS_VEH_V_N];
    r[SARINS_R_speed] = out[SARINS_VEH_SPEED];
    r[SARINS_R_base_motion_time] = time;
    c->i[SARINS_I_stopped] = !(out[SARINS_VEH_SPEED] > STOPPED_SPEED);
}

static int vm_initialize(sarins_ctx *c)
{
    vm_work *w = calloc(1, sizeof *w);
    if (w == NULL) {
        sarins_log(c, SARINS_ERROR, "out of memory for the vehicle's segments");
        return SARINS_ERROR;
    }
    if (build(c, w) != SARINS_OK) {
        free(w);
        return SARINS_ERROR;
    }
    c->work = w;
    vm_state *st = c->state;
    memset(st, 0, sizeof *st);
    sarins_vehicle_start(&st->vehicle, &w->params);
    publish(c, w, st, c->start_time);
    return SARINS_OK;
}

static int vm_do_step(sarins_ctx *c, double t, double h)
{
    vm_work *w = c->work;
    vm_state *st = c->state;
    double grid = w->params.step, time = t + h;
    char msg[256];
    if (!sarins_vehicle_state_ok(&st->vehicle, w->segments, w->n_segments, msg, sizeof msg)) { /* a set state */
        sarins_log(c, SARINS_ERROR, "%s", msg);
        return SARINS_ERROR;
    }
    if (st->have_step && sm_fabs(h - st->step) > 1e-9 * st->step) {
        sarins_log(c, SARINS_ERROR, "ValueError: communication step changed from %.17g s to %.17g s; this FMU needs "
                   "a fixed step", st->step, h);
        return SARINS_ERROR;
    }
    st->step = h;
    st->have_step = 1;
    if (sm_fabs(h - grid) > TAG_TOL * h) {
        sarins_log(c, SARINS_ERROR, "ValueError: communication step %.17g s differs from the vehicle grid %.17g s",
                   h, grid);
        return SARINS_ERROR;
    }
    int64_t k = st->vehicle.k;
    if (sm_fabs((double)k * grid + c->start_time - time) > TAG_TOL * grid) {
        sarins_log(c, SARINS_ERROR, "ValueError: time %.9g s is not on the vehicle's grid of %.17g s", time, grid);
        return SARINS_ERROR;
    }
    if (k > w->n_steps && w->end_speed != 0.0) { /* the state at the drive's end is published, not a step after */
        sarins_log(c, SARINS_ERROR, "ValueError: time %.9g s is beyond the drive and the legs do not end with a stop",
                   time);
        return SARINS_ERROR;
    }
    if (!sarins_vehicle_valid(&st->vehicle, msg, sizeof msg)) { /* the next step would start outside */
        sarins_log(c, SARINS_ERROR, "ValueError: %s", msg);
        return SARINS_ERROR;
    }
    publish(c, w, st, time);
    return SARINS_OK;
}

/* The fields of the state do_step indexes or divides by, within their buffers and finite (model.h, State
 * validation); the segment index against the segment buffer (the parameters' count is in the work). */
static int vm_check_state(const sarins_ctx *c, int running)
{
    const vm_state *st = c->state;
    const sarins_vehicle *v = &st->vehicle;
    (void)running;
    if (!sarins_state_int(c, "have_step", st->have_step, 0, 1)
        || !sarins_state_real(c, "step", st->step, st->have_step ? 1e-300 : 0.0, st->have_step ? 1e300 : 0.0)
        || !sarins_state_int(c, "vehicle.segment", v->segment, 0, 3 * MAX_LEGS + 2)
        || !sarins_state_int(c, "vehicle.k", v->k, 0, INT64_MAX)
        || !sarins_state_int(c, "vehicle.in_segment", v->in_segment, 0, INT64_MAX)
        || !sarins_state_finite(c, "vehicle.phase", &v->phase[0][0], 2 * (1 + SARINS_VEHICLE_N_VIBRATION))
        || !sarins_state_finite(c, "vehicle.speed", &v->speed, 1) || !sarins_state_finite(c, "vehicle.yaw", &v->yaw, 1)
        || !sarins_state_finite(c, "vehicle.lat", &v->lat, 1) || !sarins_state_finite(c, "vehicle.lon", &v->lon, 1))
        return SARINS_ERROR;
    return SARINS_OK;
}

const sarins_model sarins_model_desc = {
    .table = &SARINS_TABLE,
    .state_size = sizeof(vm_state),
    .state_version = 1,
    .initialize = vm_initialize,
    .do_step = vm_do_step,
    .release = vm_release,
    .check_state = vm_check_state,
};
