/* TrajectoryIMU FMU (native): a vehicle's truth from segments and the aided runs' IMU along it.
 *
 * The declaration (variables, descriptions, the timing contract) is fmus/trajectory_imu_slave.py; the
 * motion is the C core's traj.h (sarins_traj_begin/_row/_step, the kernel of sarins_traj_run that
 * sarins_fmu.trajectory.generate runs in process) and the IMU errors its aided_imu.h (the stream
 * sarins_fmu.aided.corrupt draws), so after doStep(t_k, h) the outputs are the truth row k + 1 and the
 * measured increments of step k of the in-process run bit for bit.  With odo_rate_hz > 0 a wheel odometer
 * (odo.h, seed odo_seed) reads the forward speed of truth row k + 1 after every (1 / (odo_rate_hz h))-th step,
 * the readings sarins_fmu.aided.per_step_aiding draws for navigate's odometer aiding.  With zupt_enable /
 * nhc_enable the ZUPT and NHC aiding rows of step k (aid_noise.h: the still decision from truth rows k and k + 1,
 * five normals per step from stream 33 of jitter_seed), the rows per_step_aiding(..., stream="core") gives;
 * zupt_enable 2 outputs the ZUPT jitter on every step (zupt still the truth's flag): the values for the stops a
 * detector downstream declares (AidedINS zupt_source 1, per_step_aiding's rows with stops from the IMU).
 * With vib_accel_rms or vib_rate_rms > 0 the vehicle's vibration while moving (vibration.h, stream 34 of seed) is
 * added to the increments: navigate(..., imu_stream="core", vibration=Vibration(vib_accel_rms, vib_rate_rms)).
 * Units: rad, m, m/s, rad/s, s.
 */
#include "smath.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "aid_noise.h"
#include "aided_imu.h"
#include "model.h"
#include "odo.h"
#include "traj.h"
#include "vibration.h"
#include "variables.h"

#define TAG_TOL 1e-9                      /* relative to the step: two times name the same grid point */
#define MAX_SEGMENTS (SARINS_STRING_MAX / 8) /* "1 0 0 0;" is the shortest row: no more rows fit the string */

/* What changes during a run (plain data: the FMU state copies it). */
typedef struct {
    sarins_traj traj;     /* the motion at the next grid point */
    sarins_aided_imu imu; /* the IMU's errors */
    int64_t k;            /* steps done */
    sarins_odo odo;       /* the odometer's errors */
    int64_t odo_every;    /* steps per odometer reading; 0: no odometer */
    sarins_aid_noise jitter; /* the ZUPT and NHC jitter */
    int32_t zupt_on, nhc_on; /* zupt_enable, nhc_enable */
    sarins_vibration vib;    /* the vehicle's vibration while moving */
    int32_t vib_on;          /* vib_accel_rms or vib_rate_rms > 0 */
} ti_state;

/* What the parameters give (built at initialisation, not part of the FMU state). */
typedef struct {
    double seg[SARINS_TRAJ_SEG * MAX_SEGMENTS];
    int64_t n_seg, n_steps;
} ti_work;

static void ti_release(sarins_ctx *c)
{
    free(c->work);
    c->work = NULL;
}

/* "steps accel yaw_rate pitch_rate; ..." into w; SARINS_ERROR with a logged reason. */
static int parse_segments(sarins_ctx *c, ti_work *w)
{
    const char *p = c->s[SARINS_S_segments];
    w->n_seg = 0;
    w->n_steps = 0;
    for (;;) {
        while (*p == ' ' || *p == ';')
            p++;
        if (*p == '\0')
            break;
        if (w->n_seg == MAX_SEGMENTS) {
            sarins_log(c, SARINS_ERROR, "parameter segments: more than %d rows", MAX_SEGMENTS);
            return SARINS_ERROR;
        }
        double *row = w->seg + SARINS_TRAJ_SEG * w->n_seg;
        for (int j = 0; j < SARINS_TRAJ_SEG; j++) {
            char *stop;
            row[j] = strtod(p, &stop);
            int end = *stop == '\0' || *stop == ';' || *stop == ' ';
            if (stop == p || !end || !isfinite(row[j])) {
                sarins_log(c, SARINS_ERROR, "parameter segments: row %d is not four finite numbers 'steps accel "
                           "yaw_rate pitch_rate'", (int)w->n_seg + 1);
                return SARINS_ERROR;
            }
            p = stop;
            while (*p == ' ')
                p++;
            if (j < SARINS_TRAJ_SEG - 1 && (*p == ';' || *p == '\0')) {
                sarins_log(c, SARINS_ERROR, "parameter segments: row %d has fewer than four numbers",
                           (int)w->n_seg + 1);
                return SARINS_ERROR;
            }
        }
        if (!(row[0] >= 0.0 && row[0] <= 1e12 && sm_floor(row[0]) == row[0])) {
            sarins_log(c, SARINS_ERROR, "parameter segments: row %d's steps %.17g is not a whole number 0 .. 1e12",
                       (int)w->n_seg + 1, row[0]);
            return SARINS_ERROR;
        }
        if (*p != '\0' && *p != ';') {
            sarins_log(c, SARINS_ERROR, "parameter segments: row %d has more than four numbers", (int)w->n_seg + 1);
            return SARINS_ERROR;
        }
        w->n_steps += (int64_t)row[0];
        w->n_seg += 1;
    }
    if (w->n_seg == 0 || w->n_steps < 1) {
        sarins_log(c, SARINS_ERROR, "parameter segments: no step (give at least one row with steps >= 1)");
        return SARINS_ERROR;
    }
    return SARINS_OK;
}

/* The truth at the next grid point into the outputs (and row, SARINS_TRAJ_ROW). */
static void publish(sarins_ctx *c, const ti_work *w, const ti_state *st, double time, double *row)
{
    sarins_traj_row(&st->traj, w->seg, row);
    double *r = c->r;
    const int slots[12] = {SARINS_R_lat, SARINS_R_lon, SARINS_R_height, SARINS_R_v_e, SARINS_R_v_n, SARINS_R_v_u,
                           SARINS_R_yaw, SARINS_R_pitch, SARINS_R_roll, SARINS_R_omega_ib_x, SARINS_R_omega_ib_y,
                           SARINS_R_omega_ib_z};
    for (int i = 0; i < 12; i++)
        r[slots[i]] = row[i];
    r[SARINS_R_truth_time] = time;
}

static int ti_initialize(sarins_ctx *c)
{
    const double *r = c->r;
    double step = r[SARINS_R_step];
    if (!(isfinite(step) && step > 0.0 && step <= 1.0)) {
        sarins_log(c, SARINS_ERROR, "parameter step = %.17g must be within 0 .. 1 s (exclusive of 0)", step);
        return SARINS_ERROR;
    }
    int substeps = c->i[SARINS_I_substeps];
    if (substeps < 1 || substeps > 1000) {
        sarins_log(c, SARINS_ERROR, "parameter substeps = %d must be 1 .. 1000", substeps);
        return SARINS_ERROR;
    }
    if (c->i[SARINS_I_seed] < 0) {
        sarins_log(c, SARINS_ERROR, "parameter seed = %d must be >= 0", c->i[SARINS_I_seed]);
        return SARINS_ERROR;
    }
    double start[SARINS_TRAJ_START] = {r[SARINS_R_lat0], r[SARINS_R_lon0], r[SARINS_R_height0], r[SARINS_R_speed0],
                                       r[SARINS_R_yaw0], r[SARINS_R_pitch0]};
    static const char *const start_names[SARINS_TRAJ_START] = {"lat0", "lon0", "height0", "speed0", "yaw0", "pitch0"};
    const double deg = 3.141592653589793 / 180.0;
    for (int i = 0; i < SARINS_TRAJ_START; i++) {
        double lim = i == SARINS_TRAJ_LAT ? 89.9 * deg : i == SARINS_TRAJ_PITCH ? 89.0 * deg : 1e300;
        if (!isfinite(start[i]) || sm_fabs(start[i]) >= lim || (i == SARINS_TRAJ_SPEED && start[i] < 0.0)) {
            sarins_log(c, SARINS_ERROR, "parameter %s = %.17g must be finite%s", start_names[i], start[i],
                       i == SARINS_TRAJ_LAT ? " and within +-89.9 deg" : i == SARINS_TRAJ_PITCH ? " and within +-89 deg"
                       : i == SARINS_TRAJ_SPEED ? " and >= 0" : "");
            return SARINS_ERROR;
        }
    }
    double noise[SARINS_AIDED_IMU_CONFIG] = {r[SARINS_R_arw], r[SARINS_R_vrw], r[SARINS_R_gyro_bias_std],
                                             r[SARINS_R_accel_bias_std], r[SARINS_R_gyro_rw], r[SARINS_R_accel_rw]};
    static const char *const noise_names[SARINS_AIDED_IMU_CONFIG] = {"arw", "vrw", "gyro_bias_std", "accel_bias_std",
                                                                     "gyro_rw", "accel_rw"};
    for (int i = 0; i < SARINS_AIDED_IMU_CONFIG; i++)
        if (!(isfinite(noise[i]) && noise[i] >= 0.0)) {
            sarins_log(c, SARINS_ERROR, "parameter %s = %.17g must be finite and >= 0", noise_names[i], noise[i]);
            return SARINS_ERROR;
        }
    double odo_rate = r[SARINS_R_odo_rate_hz], odo_every = 0.0;
    if (!(isfinite(odo_rate) && odo_rate >= 0.0)) {
        sarins_log(c, SARINS_ERROR, "parameter odo_rate_hz = %.17g must be finite and >= 0 (0: no odometer)",
                   odo_rate);
        return SARINS_ERROR;
    }
    if (odo_rate > 0.0) { /* a reading every 1 / (rate h) steps: a whole number >= 1 */
        odo_every = sm_floor(1.0 / (odo_rate * step) + 0.5);
        if (!(odo_every >= 1.0 && odo_every < 9007199254740992.0
              && sm_fabs(1.0 / (odo_rate * step) - odo_every) <= TAG_TOL * odo_every)) {
            sarins_log(c, SARINS_ERROR, "parameter odo_rate_hz = %.17g: 1 / (odo_rate_hz step) = %.17g must be a "
                       "whole number >= 1 (steps per reading)", odo_rate, 1.0 / (odo_rate * step));
            return SARINS_ERROR;
        }
    }
    if (c->i[SARINS_I_odo_seed] < 0) {
        sarins_log(c, SARINS_ERROR, "parameter odo_seed = %d must be >= 0", c->i[SARINS_I_odo_seed]);
        return SARINS_ERROR;
    }
    static const char *const flag_names[2] = {"zupt_enable", "nhc_enable"};
    const int flags[2] = {c->i[SARINS_I_zupt_enable], c->i[SARINS_I_nhc_enable]};
    for (int i = 0; i < 2; i++)
        if (flags[i] != 0 && flags[i] != 1 && !(i == 0 && flags[i] == 2)) {
            sarins_log(c, SARINS_ERROR, "parameter %s = %d must be 0 or 1%s", flag_names[i], flags[i],
                       i == 0 ? " (or 2: the jitter on every step)" : "");
            return SARINS_ERROR;
        }
    static const char *const std_names[2] = {"zupt_std", "nhc_std"};
    const double stds[2] = {r[SARINS_R_zupt_std], r[SARINS_R_nhc_std]};
    for (int i = 0; i < 2; i++)
        if (!(isfinite(stds[i]) && stds[i] >= 0.0)) {
            sarins_log(c, SARINS_ERROR, "parameter %s = %.17g must be finite and >= 0", std_names[i], stds[i]);
            return SARINS_ERROR;
        }
    static const char *const vib_names[2] = {"vib_accel_rms", "vib_rate_rms"};
    const double vib[2] = {r[SARINS_R_vib_accel_rms], r[SARINS_R_vib_rate_rms]};
    for (int i = 0; i < 2; i++)
        if (!(isfinite(vib[i]) && vib[i] >= 0.0)) {
            sarins_log(c, SARINS_ERROR, "parameter %s = %.17g must be finite and >= 0 (0: no vibration)", vib_names[i],
                       vib[i]);
            return SARINS_ERROR;
        }
    if (c->i[SARINS_I_jitter_seed] < 0) {
        sarins_log(c, SARINS_ERROR, "parameter jitter_seed = %d must be >= 0", c->i[SARINS_I_jitter_seed]);
        return SARINS_ERROR;
    }
    ti_work *w = calloc(1, sizeof *w);
    if (w == NULL) {
        sarins_log(c, SARINS_ERROR, "out of memory for the trajectory's segments");
        return SARINS_ERROR;
    }
    ti_state *st = c->state;
    memset(st, 0, sizeof *st);
    char msg[256];
    if (parse_segments(c, w) != SARINS_OK) {
        free(w);
        return SARINS_ERROR;
    }
    if (sarins_traj_begin(&st->traj, w->n_seg, w->seg, start, step, substeps) != SARINS_TRAJ_OK) {
        sarins_log(c, SARINS_ERROR, "parameters segments, lat0 .. pitch0: the trajectory leaves the valid range "
                   "(negative speed, |pitch| >= 89 deg)");
        free(w);
        return SARINS_ERROR;
    }
    if (sarins_aided_imu_init(&st->imu, noise, step, (uint64_t)c->i[SARINS_I_seed], msg, sizeof msg)) {
        sarins_log(c, SARINS_ERROR, "parameters (arw .. accel_rw, step): %s", msg);
        free(w);
        return SARINS_ERROR;
    }
    double odo[SARINS_ODO_CONFIG] = {r[SARINS_R_odo_scale_factor], r[SARINS_R_odo_noise_std],
                                     r[SARINS_R_odo_resolution]};
    if (sarins_odo_init(&st->odo, odo, (uint64_t)c->i[SARINS_I_odo_seed], msg, sizeof msg)) {
        sarins_log(c, SARINS_ERROR, "parameters (odo_scale_factor, odo_noise_std, odo_resolution): %s", msg);
        free(w);
        return SARINS_ERROR;
    }
    st->odo_every = (int64_t)odo_every;
    if (sarins_aid_noise_init(&st->jitter, stds[0], stds[1], (uint64_t)c->i[SARINS_I_jitter_seed], msg,
                              sizeof msg)) {
        sarins_log(c, SARINS_ERROR, "parameters (zupt_std, nhc_std): %s", msg);
        free(w);
        return SARINS_ERROR;
    }
    st->zupt_on = flags[0];
    st->nhc_on = flags[1];
    c->work = w;
    double row[SARINS_TRAJ_ROW];
    publish(c, w, st, c->start_time, row);
    st->vib_on = vib[0] > 0.0 || vib[1] > 0.0;
    if (sarins_vibration_init(&st->vib, vib[0], vib[1], step, (uint64_t)c->i[SARINS_I_seed], sarins_aid_moving(row + 3),
                              msg, sizeof msg)) {
        sarins_log(c, SARINS_ERROR, "parameters (vib_accel_rms, vib_rate_rms, step): %s", msg);
        ti_release(c);
        return SARINS_ERROR;
    }
    double *out = c->r;
    const int zero[12] = {SARINS_R_dtheta_x, SARINS_R_dtheta_y, SARINS_R_dtheta_z, SARINS_R_dv_x, SARINS_R_dv_y,
                          SARINS_R_dv_z, SARINS_R_true_bias_g_x, SARINS_R_true_bias_g_y, SARINS_R_true_bias_g_z,
                          SARINS_R_true_bias_a_x, SARINS_R_true_bias_a_y, SARINS_R_true_bias_a_z};
    for (int i = 0; i < 12; i++)
        out[zero[i]] = 0.0;
    out[SARINS_R_increment_end_time] = c->start_time;
    out[SARINS_R_odo_speed] = 0.0;
    c->i[SARINS_I_odo_valid] = 0;
    const int aid[5] = {SARINS_R_zupt_v_e, SARINS_R_zupt_v_n, SARINS_R_zupt_v_u, SARINS_R_nhc_v_x, SARINS_R_nhc_v_z};
    for (int i = 0; i < 5; i++)
        out[aid[i]] = 0.0;
    c->i[SARINS_I_zupt] = 0;
    c->i[SARINS_I_nhc] = 0;
    return SARINS_OK;
}

static int ti_do_step(sarins_ctx *c, double t, double h)
{
    const ti_work *w = c->work;
    ti_state *st = c->state;
    double step = st->imu.step;
    if (st->traj.n_seg != w->n_seg || st->traj.seg >= w->n_seg
        || st->traj.i > (int64_t)w->seg[SARINS_TRAJ_SEG * st->traj.seg] || st->k > w->n_steps) { /* a set state */
        sarins_log(c, SARINS_ERROR, "TrajectoryIMU state: the segment position does not fit the segments");
        return SARINS_ERROR;
    }
    if (sm_fabs(h - step) > TAG_TOL * step) {
        sarins_log(c, SARINS_ERROR, "ValueError: communication step %.17g s differs from parameter step %.17g s", h,
                   step);
        return SARINS_ERROR;
    }
    double expected = c->start_time + (double)st->k * step;
    if (sm_fabs(t - expected) > TAG_TOL * (sm_fabs(expected) + step)) {
        sarins_log(c, SARINS_ERROR, "ValueError: time %.17g s is not the next communication point %.17g s", t, expected);
        return SARINS_ERROR;
    }
    if (sarins_traj_done(&st->traj, w->seg)) {
        sarins_log(c, SARINS_ERROR, "ValueError: time %.17g s is past the trajectory's end (%lld steps of %.17g s)", t,
                   (long long)w->n_steps, step);
        return SARINS_ERROR;
    }
    double dtheta_true[3], dv_true[3], dtheta[3], dv[3], bias[6];
    sarins_traj next = st->traj;
    if (sarins_traj_step(&next, w->seg, dtheta_true, dv_true) != SARINS_TRAJ_OK) {
        sarins_log(c, SARINS_ERROR, "ValueError: the trajectory leaves the valid range in the step from %.17g s "
                   "(negative speed, |pitch| >= 89 deg or |latitude| >= 89.9 deg)", t);
        return SARINS_ERROR;
    }
    double speed = 0.0, reading = 0.0, row[SARINS_TRAJ_ROW], row0[SARINS_TRAJ_ROW];
    sarins_traj_row(&st->traj, w->seg, row0); /* the truth at t: the step's start, for the still decision */
    int odo_due = st->odo_every > 0 && (st->k + 1) % st->odo_every == 0;
    if (odo_due) { /* the forward speed at the step's end */
        sarins_traj_row(&next, w->seg, row);
        speed = sarins_odo_forward_speed(row + 3, row + 6);
        sarins_odo probe = st->odo;
        if (sarins_odo_speeds(&probe, 1, &speed, &reading)) {
            sarins_log(c, SARINS_ERROR, "ValueError: the forward speed at %.17g s is not finite", t + h);
            return SARINS_ERROR;
        }
        st->odo = probe;
    }
    st->traj = next;
    sarins_aided_imu_step(&st->imu, dtheta_true, dv_true, dtheta, dv, bias);
    st->k += 1;
    double time = c->start_time + (double)st->k * step;
    publish(c, w, st, time, row);
    double *r = c->r;
    c->i[SARINS_I_odo_valid] = odo_due;
    if (odo_due)
        r[SARINS_R_odo_speed] = reading;
    /* ZUPT / NHC rows of the step: still from the velocities at t and t + h; five draws whatever the flags */
    int still = sarins_aid_still(row0 + 3, row + 3), zupt = st->zupt_on && still, nhc = st->nhc_on && !still;
    double jitter[SARINS_AID_NOISE_DRAWS]; /* zupt_enable 2: the ZUPT jitter on every step (a detector's stops) */
    sarins_aid_noise_step(&st->jitter, st->zupt_on == 2 ? 1 : zupt, nhc, jitter);
    const int aid[5] = {SARINS_R_zupt_v_e, SARINS_R_zupt_v_n, SARINS_R_zupt_v_u, SARINS_R_nhc_v_x, SARINS_R_nhc_v_z};
    for (int i = 0; i < 5; i++)
        r[aid[i]] = jitter[i];
    c->i[SARINS_I_zupt] = zupt;
    c->i[SARINS_I_nhc] = nhc;
    if (st->vib_on) { /* the vibration's increments to the step's end point: dtheta + vib, as navigate adds them */
        double vib_theta[3], vib_v[3];
        sarins_vibration_step(&st->vib, sarins_aid_moving(row + 3), vib_theta, vib_v);
        for (int i = 0; i < 3; i++) {
            dtheta[i] = dtheta[i] + vib_theta[i];
            dv[i] = dv[i] + vib_v[i];
        }
    }
    const int inc[6] = {SARINS_R_dtheta_x, SARINS_R_dtheta_y, SARINS_R_dtheta_z, SARINS_R_dv_x, SARINS_R_dv_y,
                        SARINS_R_dv_z};
    const int bs[6] = {SARINS_R_true_bias_g_x, SARINS_R_true_bias_g_y, SARINS_R_true_bias_g_z,
                       SARINS_R_true_bias_a_x, SARINS_R_true_bias_a_y, SARINS_R_true_bias_a_z};
    for (int i = 0; i < 3; i++) {
        r[inc[i]] = dtheta[i];
        r[inc[3 + i]] = dv[i];
    }
    for (int i = 0; i < 6; i++)
        r[bs[i]] = bias[i];
    r[SARINS_R_increment_end_time] = time;
    return SARINS_OK;
}

/* A state handed to the FMU (model.h "State validation"): every field within what do_step relies on (the
 * segment position against the segments is checked by do_step, which has them). */
static int ti_check_state(const sarins_ctx *c, int running)
{
    const ti_state *st = c->state;
    const sarins_traj *s = &st->traj;
    const long long big = 1LL << 53;
    if (!running)
        return SARINS_OK;
    int ok = sarins_state_int(c, "k", st->k, 0, big) && sarins_state_int(c, "traj.n_seg", s->n_seg, 1, MAX_SEGMENTS)
             && sarins_state_int(c, "traj.seg", s->seg, 0, s->n_seg - 1) && sarins_state_int(c, "traj.i", s->i, 0, big)
             && sarins_state_int(c, "traj.substeps", s->substeps, 1, 1000)
             && sarins_state_real(c, "traj.step", s->step, 1e-300, 1.0)
             && sarins_state_finite(c, "traj.state0", s->state0, 3) && sarins_state_finite(c, "traj.pos", s->pos, 3)
             && sarins_state_finite(c, "traj.pos_c", s->pos_c, 3)
             && sarins_state_real(c, "traj.lat", s->pos[0], -1.5690509975429023, 1.5690509975429023);
    char msg[160];
    if (ok && sarins_aided_imu_check(&st->imu, msg, sizeof msg)) {
        sarins_log(c, SARINS_ERROR, "the state's %s", msg);
        ok = 0;
    }
    if (ok && !(st->imu.step == s->step)) {
        sarins_log(c, SARINS_ERROR, "the state's IMU step differs from the trajectory's");
        ok = 0;
    }
    ok = ok && sarins_state_int(c, "odo_every", st->odo_every, 0, big);
    if (ok && sarins_odo_check(&st->odo, msg, sizeof msg)) {
        sarins_log(c, SARINS_ERROR, "the state's %s", msg);
        ok = 0;
    }
    ok = ok && sarins_state_int(c, "zupt_on", st->zupt_on, 0, 2) && sarins_state_int(c, "nhc_on", st->nhc_on, 0, 1);
    if (ok && sarins_aid_noise_check(&st->jitter, msg, sizeof msg)) {
        sarins_log(c, SARINS_ERROR, "the state's %s", msg);
        ok = 0;
    }
    ok = ok && sarins_state_int(c, "vib_on", st->vib_on, 0, 1);
    if (ok && sarins_vibration_check(&st->vib, msg, sizeof msg)) {
        sarins_log(c, SARINS_ERROR, "the state's %s", msg);
        ok = 0;
    }
    if (ok && !(st->vib.step == s->step)) {
        sarins_log(c, SARINS_ERROR, "the state's vibration step differs from the trajectory's");
        ok = 0;
    }
    return ok ? SARINS_OK : SARINS_ERROR;
}

const sarins_model sarins_model_desc = {
    .table = &SARINS_TABLE,
    .state_size = sizeof(ti_state),
    .state_version = 4, /* 2: the odometer (odo, odo_every); 3: the ZUPT / NHC jitter (jitter, zupt_on, nhc_on);
                         * 4: the vibration (vib, vib_on), zupt_on 2 */
    .initialize = ti_initialize,
    .do_step = ti_do_step,
    .release = ti_release,
    .check_state = ti_check_state,
};
