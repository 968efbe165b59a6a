/* GNSSReceiver FMU (native): GNSS position/velocity fixes of the antenna from the true motion.
 *
 * The declaration (variables, descriptions, the timing contract) is fmus/gnss_receiver_slave.py; the error
 * model is the C core's (sarins_fmu/core/gnss.h), the same stream sarins_fmu.gnss.simulate runs in process,
 * so the fix of epoch m equals row m of its GNSSFixes bit for bit when the inputs are the same truth.  Fix
 * epochs are the communication points t_k = start + k h with k a positive multiple of every = 1 / (rate h);
 * doStep(t_k, h) computes the fix valid at t_k from the inputs set for t_k and publishes it after the step.
 * Units: rad, m, m/s, rad/s, s.
 */
#include "smath.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gnss.h"
#include "model.h"
#include "variables.h"

#define MAX_OUTAGES 16
#define GRID_TOL 1e-9 /* relative: a fix interval within this of a whole number of steps is one */
#define NO_TAG -1.0e9  /* s: truth_time unconnected (fmus.slave_support.NO_TAG): the truth is at t */

/* What changes during a run, and the parsed parameters it runs with (plain data: the FMU state copies it). */
typedef struct {
    sarins_gnss gnss;                   /* the receiver's error processes */
    double outages[2 * MAX_OUTAGES];    /* [start, end) s */
    int64_t n_outages;
    int64_t k;                          /* steps done: the next doStep starts at start + k h */
    int64_t every;                      /* steps per fix, fixed by the first doStep (0 before) */
    double step;                        /* s, the communication step, fixed by the first doStep */
    int64_t truth_next;                 /* time-tagged truth: index of the next communication point to take */
} gr_state;

/* 1 when st can be run (counts and sizes in range), else 0 with the reason in msg. */
static int gr_state_ok(const gr_state *st, char *msg, size_t size)
{
    const char *why = NULL;
    if (st->n_outages < 0 || st->n_outages > MAX_OUTAGES)
        why = "outage count out of range";
    else if (st->k < 0 || st->every < 0 || st->gnss.epochs < 0 || st->truth_next < 0)
        why = "step or epoch count out of range";
    else if (st->every > 0 && !(st->step > 0.0))
        why = "step out of range";
    if (why == NULL)
        return 1;
    snprintf(msg, size, "GNSS receiver state: %s", why);
    return 0;
}

/* "start:end;start:end" into st->outages; SARINS_ERROR with a logged reason. */
static int parse_outages(sarins_ctx *c, gr_state *st)
{
    const char *p = c->s[SARINS_S_outages];
    st->n_outages = 0;
    for (;;) {
        while (*p == ' ' || *p == ';')
            p++;
        if (*p == '\0')
            return SARINS_OK;
        if (st->n_outages == MAX_OUTAGES) {
            sarins_log(c, SARINS_ERROR, "parameter outages = '%s': more than %d windows", c->s[SARINS_S_outages],
                       MAX_OUTAGES);
            return SARINS_ERROR;
        }
        char *stop;
        double a = strtod(p, &stop);
        int ok = stop != p && *stop == ':';
        double b = ok ? strtod(stop + 1, &stop) : 0.0;
        ok = ok && (*stop == '\0' || *stop == ';' || *stop == ' ') && isfinite(a) && isfinite(b) && a >= 0.0
             && a < b;
        if (!ok) {
            sarins_log(c, SARINS_ERROR, "parameter outages = '%s': window %d is not 'start:end' with 0 <= start < "
                       "end (s)", c->s[SARINS_S_outages], (int)st->n_outages + 1);
            return SARINS_ERROR;
        }
        st->outages[2 * st->n_outages] = a;
        st->outages[2 * st->n_outages + 1] = b;
        st->n_outages++;
        p = stop;
    }
}

static void publish_empty(sarins_ctx *c)
{
    double *r = c->r;
    r[SARINS_R_fix_lat] = r[SARINS_R_fix_lon] = r[SARINS_R_fix_height] = 0.0;
    r[SARINS_R_fix_v_e] = r[SARINS_R_fix_v_n] = r[SARINS_R_fix_v_u] = 0.0;
    r[SARINS_R_fix_time] = c->start_time;
    c->i[SARINS_I_fix_valid] = 0;
    c->i[SARINS_I_fix_count] = 0;
    r[SARINS_R_fix_horizon] = NO_TAG;
}

static int gr_initialize(sarins_ctx *c)
{
    const double *r = c->r;
    double rate = r[SARINS_R_rate_hz];
    if (!(isfinite(rate) && rate >= 1.0 && rate <= 20.0)) {
        sarins_log(c, SARINS_ERROR, "parameter rate_hz = %.17g must be within 1 .. 20 Hz", rate);
        return SARINS_ERROR;
    }
    if (c->i[SARINS_I_seed] < 0) {
        sarins_log(c, SARINS_ERROR, "parameter seed = %d must be >= 0", c->i[SARINS_I_seed]);
        return SARINS_ERROR;
    }
    double config[SARINS_GNSS_CONFIG] = {
        r[SARINS_R_lever_x], r[SARINS_R_lever_y], r[SARINS_R_lever_z],
        r[SARINS_R_pos_white_e], r[SARINS_R_pos_white_n], r[SARINS_R_pos_white_u],
        r[SARINS_R_pos_gm_e], r[SARINS_R_pos_gm_n], r[SARINS_R_pos_gm_u], r[SARINS_R_pos_gm_tau],
        r[SARINS_R_vel_white_e], r[SARINS_R_vel_white_n], r[SARINS_R_vel_white_u],
        r[SARINS_R_vel_gm_e], r[SARINS_R_vel_gm_n], r[SARINS_R_vel_gm_u], r[SARINS_R_vel_gm_tau]};
    static const char *const names[SARINS_GNSS_CONFIG] = {
        "lever_x", "lever_y", "lever_z", "pos_white_e", "pos_white_n", "pos_white_u", "pos_gm_e", "pos_gm_n",
        "pos_gm_u", "pos_gm_tau", "vel_white_e", "vel_white_n", "vel_white_u", "vel_gm_e", "vel_gm_n", "vel_gm_u",
        "vel_gm_tau"};
    for (int i = 0; i < SARINS_GNSS_CONFIG; i++) {
        int tau = i == SARINS_GNSS_POS_TAU || i == SARINS_GNSS_VEL_TAU, lever = i <= SARINS_GNSS_LEVER_Z;
        if (!isfinite(config[i]) || (tau && !(config[i] > 0.0)) || (!tau && !lever && config[i] < 0.0)) {
            sarins_log(c, SARINS_ERROR, "parameter %s = %.17g must be %s", names[i], config[i],
                       tau ? "a positive time (s)" : lever ? "finite (m)" : "a finite standard deviation >= 0");
            return SARINS_ERROR;
        }
    }
    gr_state *st = c->state;
    memset(st, 0, sizeof *st);
    char msg[256];
    if (sarins_gnss_init(&st->gnss, config, (uint64_t)c->i[SARINS_I_seed], msg, sizeof msg)) {
        sarins_log(c, SARINS_ERROR, "parameters (lever_*, pos_*, vel_*): %s", msg);
        return SARINS_ERROR;
    }
    if (parse_outages(c, st) != SARINS_OK)
        return SARINS_ERROR;
    publish_empty(c);
    return SARINS_OK;
}

/* Fix the step on the first doStep: every = 1 / (rate h), a whole number >= 1. */
static int fix_step(sarins_ctx *c, gr_state *st, double h)
{
    double rate = c->r[SARINS_R_rate_hz];
    double every = 1.0 / (rate * h); /* inf for a step so small that rate * h underflows */
    if (1.0 / rate < h * (1.0 - GRID_TOL)) {
        sarins_log(c, SARINS_ERROR, "ValueError: GNSS rate %.17g Hz is above the step rate %.17g Hz", rate, 1.0 / h);
        return SARINS_ERROR;
    }
    if (!(every < 9007199254740992.0)) { /* 2^53 steps per fix: beyond any whole number a double holds */
        sarins_log(c, SARINS_ERROR, "ValueError: GNSS interval %.17g s is not a whole number of steps (%.17g s)",
                   1.0 / rate, h);
        return SARINS_ERROR;
    }
    int64_t n = (int64_t)(every + 0.5);
    if (n < 1 || sm_fabs((double)n * h * rate - 1.0) > GRID_TOL) {
        sarins_log(c, SARINS_ERROR, "ValueError: GNSS interval %.17g s is not a whole number of steps (%.17g s)",
                   1.0 / rate, h);
        return SARINS_ERROR;
    }
    st->every = n;
    st->step = h;
    return SARINS_OK;
}

static int gr_do_step(sarins_ctx *c, double t, double h)
{
    gr_state *st = c->state;
    char msg[256];
    if (!gr_state_ok(st, msg, sizeof msg)) { /* a set state */
        sarins_log(c, SARINS_ERROR, "%s", msg);
        return SARINS_ERROR;
    }
    if (st->every == 0 && fix_step(c, st, h) != SARINS_OK)
        return SARINS_ERROR;
    if (sm_fabs(h - st->step) > GRID_TOL * st->step) {
        sarins_log(c, SARINS_ERROR, "ValueError: communication step changed from %.17g s to %.17g s; this FMU needs "
                   "a fixed step", st->step, h);
        return SARINS_ERROR;
    }
    double epoch = c->start_time + (double)st->k * st->step;
    if (sm_fabs(t - epoch) > GRID_TOL * (sm_fabs(epoch) + st->step)) {
        sarins_log(c, SARINS_ERROR, "ValueError: time %.17g s is not the next communication point %.17g s", t, epoch);
        return SARINS_ERROR;
    }
    int64_t m = st->k; /* the communication point whose truth the inputs are */
    int take = 1;
    double tag = c->r[SARINS_R_truth_time];
    if (tag != NO_TAG) {
        double index = sm_floor((tag - c->start_time) / st->step + 0.5);
        double point = c->start_time + index * st->step;
        if (!(isfinite(tag) && index >= 0.0 && index < 9007199254740992.0)
            || sm_fabs(tag - point) > GRID_TOL * (sm_fabs(point) + st->step)) {
            sarins_log(c, SARINS_ERROR, "ValueError: truth_time %.17g s is not a communication point", tag);
            return SARINS_ERROR;
        }
        m = (int64_t)index;
        /* the next point in order; the first may be point 1 (Gauss-Seidel: point 0, no epoch, is never seen) */
        take = m == st->truth_next || (st->truth_next == 0 && m == 1);
        if (!take && m != st->truth_next - 1) {
            sarins_log(c, SARINS_ERROR, "ValueError: truth_time %.17g s: the truth of %.17g s was expected next", tag,
                       c->start_time + (double)st->truth_next * st->step);
            return SARINS_ERROR;
        }
        if (take)
            epoch = c->start_time + (double)m * st->step;
    }
    if (take && m > 0 && m % st->every == 0) {
        const double *r = c->r;
        double truth[9] = {r[SARINS_R_lat], r[SARINS_R_lon], r[SARINS_R_height], r[SARINS_R_v_e], r[SARINS_R_v_n],
                           r[SARINS_R_v_u], r[SARINS_R_yaw], r[SARINS_R_pitch], r[SARINS_R_roll]};
        double omega[3] = {r[SARINS_R_omega_ib_x], r[SARINS_R_omega_ib_y], r[SARINS_R_omega_ib_z]};
        double out[SARINS_GNSS_OUT];
        if (sarins_gnss_fixes(&st->gnss, 1, &epoch, truth, omega, st->n_outages, st->outages, out)) {
            sarins_log(c, SARINS_ERROR, "ValueError: a truth input at %.17g s is not finite", t);
            return SARINS_ERROR;
        }
        double *w = c->r;
        c->i[SARINS_I_fix_valid] = out[0] > 0.5;
        w[SARINS_R_fix_lat] = out[1];
        w[SARINS_R_fix_lon] = out[2];
        w[SARINS_R_fix_height] = out[3];
        w[SARINS_R_fix_v_e] = out[4];
        w[SARINS_R_fix_v_n] = out[5];
        w[SARINS_R_fix_v_u] = out[6];
        w[SARINS_R_fix_time] = epoch;
        c->i[SARINS_I_fix_count] += 1;
    }
    if (take) {
        c->r[SARINS_R_fix_horizon] = c->start_time + (double)m * st->step;
        st->truth_next = m + 1;
    }
    st->k += 1;
    return SARINS_OK;
}

static void gr_release(sarins_ctx *c)
{
    free(c->work);
    c->work = NULL;
}

/* A state handed to the FMU (model.h "State validation"): every field within what do_step relies on. */
static int gr_check_state(const sarins_ctx *c, int running)
{
    const gr_state *st = c->state;
    const long long big = 1LL << 53;
    int ok = sarins_state_int(c, "n_outages", st->n_outages, 0, MAX_OUTAGES)
             && sarins_state_int(c, "k", st->k, 0, big) && sarins_state_int(c, "truth_next", st->truth_next, 0, big) && sarins_state_int(c, "every", st->every, 0, big)
             && sarins_state_int(c, "gnss.epochs", st->gnss.epochs, 0, big)
             && sarins_state_finite(c, "gnss.b", st->gnss.b, 6)
             && sarins_state_finite(c, "gnss.config", st->gnss.config, SARINS_GNSS_CONFIG)
             && sarins_state_finite(c, "gnss.last_time", &st->gnss.last_time, 1)
             && sarins_state_finite(c, "outages", st->outages, (size_t)(2 * st->n_outages))
             && (st->every == 0 ? sarins_state_real(c, "step", st->step, 0.0, 0.0)
                                : sarins_state_real(c, "step", st->step, 1e-300, 1e300));
    char msg[160];
    if (ok && running && sarins_gnss_check(&st->gnss, msg, sizeof msg)) { /* the receiver's own invariants */
        sarins_log(c, SARINS_ERROR, "the state's %s", msg);
        ok = 0;
    }
    return ok ? SARINS_OK : SARINS_ERROR;
}

const sarins_model sarins_model_desc = {
    .table = &SARINS_TABLE,
    .state_size = sizeof(gr_state),
    .state_version = 2,
    .initialize = gr_initialize,
    .do_step = gr_do_step,
    .release = gr_release,
    .check_state = gr_check_state,
};
