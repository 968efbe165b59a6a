/* AidedINS FMU (native): strapdown INS + 15-state error-state Kalman filter aided by GNSS fixes, zero-velocity
 * and zero-angular-rate updates at stops, a wheel odometer and the non-holonomic constraint; optional states
 * (parameters state_*: scale factors, lever arm, the receiver's Gauss-Markov errors; eskf.h) on request.
 *
 * The declaration (variables, descriptions, the timing contract) is fmus/aided_ins_slave.py; the filter is
 * the C core's (sarins_fmu/core/eskf.h: sarins_eskf_predict, sarins_eskf_aid, sarins_eskf_gnss), the kernels
 * sarins_fmu.aided.navigate runs in process (sarins_eskf_run, every aiding): fed the same increments, the same
 * per-step aiding rows and the fixes at the steps after which navigate applies them, the outputs equal its
 * rows bit for bit.  doStep(t, h) integrates the increments of [t, t + h], applies the interval's aiding row
 * (eskf.h's order: ZUPT, ZARU, odometer and / or NHC) built from the inputs zupt, zupt_v_*, zaru, odo_valid,
 * odo_speed, nhc, nhc_v_*, then a new valid fix.  With zupt_source = 1 the stops come from the IMU's statistics:
 * the core's detector (zvd.h, window zvd_window samples ending at the interval, threshold zvd_gamma, noise
 * densities zvd_vrw, zvd_arw) sees each interval's increments once and in order (causal: its decision for an
 * interval uses that interval and the zvd_window - 1 before it, as sarins_fmu.zero_velocity.detect), and the
 * ZUPT / ZARU are applied where the input zupt / zaru is 1 and the detector says still:
 * navigate(..., zupt_detect="imu") on the same increments.  Units: rad, m, m/s, rad/s, m/s^2, s.
 */
#include "smath.h"

#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "eskf.h"
#include "model.h"
#include "nav3.h"
#include "variables.h"
#include "zvd.h"

#define STEP_TOL 1e-9 /* relative: the communication step equals the filter's step */
#define NO_TAG -1.0e9  /* s: increment_end_time unconnected (fmus.slave_support.NO_TAG): untagged mode */
#define MAX_INC 4      /* time-tagged mode: intervals that may wait */
#define MAX_FIX 8      /* time-tagged mode: fixes that may wait */
#define FIX_ROW 8      /* valid (0/1), fix_time (s), lat, lon (rad), h (m), v E N U (m/s) */
#define INC_ROW (6 + SARINS_ESKF_AID) /* dtheta (3, rad), dv (3, m/s), aiding row (eskf.h) of one interval */

/* What changes during a run (plain data: the FMU state copies it). */
typedef struct {
    sarins_eskf eskf;
    int64_t last_count; /* fix_count input of the last applied / seen fix */
    int64_t used;       /* valid fixes applied */
    /* time-tagged mode: interval i ends at start + (i + 1) h */
    double inc[MAX_INC][INC_ROW]; /* waiting increments and aiding rows (ring) of intervals done .. done + n_inc - 1 */
    int64_t inc_first, n_inc; /* ring position and length */
    int64_t done;             /* intervals integrated */
    double fix[MAX_FIX][FIX_ROW]; /* waiting fixes (ring), in time order */
    int64_t fix_first, n_fix;
    int64_t zupt_source; /* 0: the inputs zupt, zaru; 1: and the detector's decision */
    sarins_zvd zvd;      /* the stillness detector (zupt_source 1) */
} ai_state;

/* 1 when st can be run, else 0 with the reason in msg. */
static int ai_state_ok(const ai_state *st, char *msg, size_t size)
{
    int ok = st->last_count >= 0 && st->used >= 0 && st->eskf.steps >= 0 && st->eskf.since_cov >= 0
             && st->eskf.config[SARINS_ESKF_STEP] > 0.0 && st->inc_first >= 0 && st->inc_first < MAX_INC
             && st->n_inc >= 0 && st->n_inc <= MAX_INC && st->fix_first >= 0 && st->fix_first < MAX_FIX
             && st->n_fix >= 0 && st->n_fix <= MAX_FIX && st->done >= 0;
    if (!ok)
        snprintf(msg, size, "AidedINS state: a count or the step is out of range");
    return ok;
}

static void publish(sarins_ctx *c, const ai_state *st)
{
    const sarins_eskf *e = &st->eskf;
    double *r = c->r;
    double val[9];
    sarins_nav3_row(e->q, e->v, e->pos, val);
    const int nav[9] = {SARINS_R_lat, SARINS_R_lon, SARINS_R_height, SARINS_R_v_e, SARINS_R_v_n, SARINS_R_v_u,
                        SARINS_R_yaw, SARINS_R_pitch, SARINS_R_roll};
    for (int i = 0; i < 9; i++)
        r[nav[i]] = val[i];
    const int bias[6] = {SARINS_R_bias_g_x, SARINS_R_bias_g_y, SARINS_R_bias_g_z, SARINS_R_bias_a_x,
                         SARINS_R_bias_a_y, SARINS_R_bias_a_z};
    for (int i = 0; i < 3; i++) {
        r[bias[i]] = e->bg[i];
        r[bias[3 + i]] = e->ba[i];
    }
    const int sig[9] = {SARINS_R_sigma_pos_e, SARINS_R_sigma_pos_n, SARINS_R_sigma_pos_u, SARINS_R_sigma_vel_e,
                        SARINS_R_sigma_vel_n, SARINS_R_sigma_vel_u, SARINS_R_sigma_att_e, SARINS_R_sigma_att_n,
                        SARINS_R_sigma_att_u};
    for (int i = 0; i < 9; i++) {
        double p = e->p[i * e->n + i];
        r[sig[i]] = p > 0.0 ? sm_sqrt(p) : 0.0;
    }
    const int est[15] = {SARINS_R_scale_g_x, SARINS_R_scale_g_y, SARINS_R_scale_g_z, SARINS_R_scale_a_x,
                         SARINS_R_scale_a_y, SARINS_R_scale_a_z, SARINS_R_lever_est_x, SARINS_R_lever_est_y,
                         SARINS_R_lever_est_z, SARINS_R_gnss_pos_gm_e, SARINS_R_gnss_pos_gm_n, SARINS_R_gnss_pos_gm_u,
                         SARINS_R_gnss_vel_gm_e, SARINS_R_gnss_vel_gm_n, SARINS_R_gnss_vel_gm_u};
    const double *blocks[5] = {e->sg, e->sa, e->lever, e->gm_r, e->gm_v};
    const int64_t first[5] = {e->i_sg, e->i_sa, e->i_lever, e->i_gm_r, e->i_gm_v};
    for (int b = 0; b < 5; b++)
        for (int i = 0; i < 3; i++)
            r[est[3 * b + i]] = first[b] >= 0 ? blocks[b][i] : 0.0;
    c->i[SARINS_I_fixes_used] = (int)st->used;
}

/* The optional states' options (eskf.h SARINS_ESKF_OPT) from the parameters state_* and their priors: 0, or
 * SARINS_ERROR with the parameter named. */
static int state_options(sarins_ctx *c, double *opt)
{
    const double *r = c->r;
    static const char *const switch_names[4] = {"state_scale_factors", "state_lever_arm", "state_gnss_pos_gm",
                                                "state_gnss_vel_gm"};
    const int switches[4] = {SARINS_I_state_scale_factors, SARINS_I_state_lever_arm, SARINS_I_state_gnss_pos_gm,
                             SARINS_I_state_gnss_vel_gm};
    const int bits[4] = {SARINS_ESKF_SF, SARINS_ESKF_LEVER, SARINS_ESKF_GNSS_POS_GM, SARINS_ESKF_GNSS_VEL_GM};
    int mask = 0;
    for (int i = 0; i < 4; i++) {
        int v = c->i[switches[i]];
        if (v != 0 && v != 1) {
            sarins_log(c, SARINS_ERROR, "parameter %s = %d must be 0 or 1", switch_names[i], v);
            return SARINS_ERROR;
        }
        mask |= v ? bits[i] : 0;
    }
    static const char *const names[SARINS_ESKF_OPT - 1] = {
        "gyro_sf0_std", "accel_sf0_std", "sf_tau", "lever0_std", "gnss_pos_gm_std_e", "gnss_pos_gm_std_n",
        "gnss_pos_gm_std_u", "gnss_pos_gm_tau", "gnss_vel_gm_std_e", "gnss_vel_gm_std_n", "gnss_vel_gm_std_u",
        "gnss_vel_gm_tau"};
    const int slots[SARINS_ESKF_OPT - 1] = {
        SARINS_R_gyro_sf0_std, SARINS_R_accel_sf0_std, SARINS_R_sf_tau, SARINS_R_lever0_std,
        SARINS_R_gnss_pos_gm_std_e, SARINS_R_gnss_pos_gm_std_n, SARINS_R_gnss_pos_gm_std_u, SARINS_R_gnss_pos_gm_tau,
        SARINS_R_gnss_vel_gm_std_e, SARINS_R_gnss_vel_gm_std_n, SARINS_R_gnss_vel_gm_std_u, SARINS_R_gnss_vel_gm_tau};
    opt[SARINS_ESKF_STATES] = (double)mask;
    for (int i = 0; i < SARINS_ESKF_OPT - 1; i++) {
        double v = r[slots[i]];
        int k = i + 1; /* its index in opt */
        /* the priors of navigate's FilterSettings positive, the Gauss-Markov times positive, sf_tau and the
         * receiver's stds >= 0 */
        int positive = k == SARINS_ESKF_GYRO_SF0_STD || k == SARINS_ESKF_ACCEL_SF0_STD || k == SARINS_ESKF_LEVER0_STD
                       || k == SARINS_ESKF_GNSS_POS_GM_TAU || k == SARINS_ESKF_GNSS_VEL_GM_TAU;
        if (!isfinite(v) || (positive ? !(v > 0.0) : v < 0.0)) {
            sarins_log(c, SARINS_ERROR, "parameter %s = %.17g must be %s", names[i], v,
                       positive ? "positive" : "finite and >= 0");
            return SARINS_ERROR;
        }
        opt[k] = v;
    }
    return SARINS_OK;
}

static int ai_initialize(sarins_ctx *c)
{
    const double *r = c->r;
    double config[SARINS_ESKF_CONFIG] = {
        r[SARINS_R_step], r[SARINS_R_arw], r[SARINS_R_vrw], r[SARINS_R_gyro_rw], r[SARINS_R_accel_rw],
        r[SARINS_R_pos0_std], r[SARINS_R_vel0_std], r[SARINS_R_tilt0_std], r[SARINS_R_heading0_std],
        r[SARINS_R_gyro_bias0_std], r[SARINS_R_accel_bias0_std], r[SARINS_R_lever_x], r[SARINS_R_lever_y],
        r[SARINS_R_lever_z], r[SARINS_R_latency], r[SARINS_R_zupt_std], r[SARINS_R_cov_every], r[SARINS_R_nhc_std],
        r[SARINS_R_odo_std], r[SARINS_R_zaru_std]};
    static const char *const names[SARINS_ESKF_CONFIG] = {
        "step", "arw", "vrw", "gyro_rw", "accel_rw", "pos0_std", "vel0_std", "tilt0_std", "heading0_std",
        "gyro_bias0_std", "accel_bias0_std", "lever_x", "lever_y", "lever_z", "latency", "zupt_std", "cov_every",
        "nhc_std", "odo_std", "zaru_std"};
    for (int i = 0; i < SARINS_ESKF_CONFIG; i++) {
        int lever = i >= SARINS_ESKF_LEVER_X && i <= SARINS_ESKF_LEVER_Z;
        int positive = i == SARINS_ESKF_STEP || i == SARINS_ESKF_ZUPT_STD || i == SARINS_ESKF_NHC_STD
                       || i == SARINS_ESKF_ODO_STD || i == SARINS_ESKF_ZARU_STD;
        int whole = i == SARINS_ESKF_COV_EVERY;
        if (!isfinite(config[i]) || (positive && !(config[i] > 0.0)) || (!lever && config[i] < 0.0)
            || (whole && !(config[i] >= 1.0 && config[i] <= 1000.0 && sm_floor(config[i]) == config[i]))) {
            sarins_log(c, SARINS_ERROR, "parameter %s = %.17g must be %s", names[i], config[i],
                       lever ? "finite" : whole ? "a whole number 1 .. 1000" : positive ? "positive" : "finite and >= 0");
            return SARINS_ERROR;
        }
    }
    const char *std_names[6] = {"gnss_pos_std_e", "gnss_pos_std_n", "gnss_pos_std_u", "gnss_vel_std_e",
                                "gnss_vel_std_n", "gnss_vel_std_u"};
    const int std_slots[6] = {SARINS_R_gnss_pos_std_e, SARINS_R_gnss_pos_std_n, SARINS_R_gnss_pos_std_u,
                              SARINS_R_gnss_vel_std_e, SARINS_R_gnss_vel_std_n, SARINS_R_gnss_vel_std_u};
    for (int i = 0; i < 6; i++)
        if (!(isfinite(r[std_slots[i]]) && r[std_slots[i]] > 0.0)) {
            sarins_log(c, SARINS_ERROR, "parameter %s = %.17g must be positive", std_names[i], r[std_slots[i]]);
            return SARINS_ERROR;
        }
    if (c->i[SARINS_I_use_velocity] != 0 && c->i[SARINS_I_use_velocity] != 1) {
        sarins_log(c, SARINS_ERROR, "parameter use_velocity = %d must be 0 or 1", c->i[SARINS_I_use_velocity]);
        return SARINS_ERROR;
    }
    double nav0[9] = {r[SARINS_R_lat0], r[SARINS_R_lon0], r[SARINS_R_height0], r[SARINS_R_v_e0], r[SARINS_R_v_n0],
                      r[SARINS_R_v_u0], r[SARINS_R_yaw0], r[SARINS_R_pitch0], r[SARINS_R_roll0]};
    static const char *const nav_names[9] = {"lat0", "lon0", "height0", "v_e0", "v_n0", "v_u0", "yaw0", "pitch0",
                                             "roll0"};
    for (int i = 0; i < 9; i++)
        if (!isfinite(nav0[i]) || (i == 0 && sm_fabs(nav0[0]) > 89.9 * (3.141592653589793 / 180.0))) {
            sarins_log(c, SARINS_ERROR, "parameter %s = %.17g must be finite%s", nav_names[i], nav0[i],
                       i == 0 ? " and within +-89.9 deg" : "");
            return SARINS_ERROR;
        }
    double opt[SARINS_ESKF_OPT];
    if (state_options(c, opt) != SARINS_OK)
        return SARINS_ERROR;
    int source = c->i[SARINS_I_zupt_source], window = c->i[SARINS_I_zvd_window];
    if (source != 0 && source != 1) {
        sarins_log(c, SARINS_ERROR, "parameter zupt_source = %d must be 0 (the inputs zupt, zaru) or 1 (detected from "
                   "the increments)", source);
        return SARINS_ERROR;
    }
    double zvd[SARINS_ZVD_CONFIG] = {(double)window, r[SARINS_R_step], r[SARINS_R_zvd_vrw], r[SARINS_R_zvd_arw],
                                     r[SARINS_R_zvd_gamma]};
    if (source == 1) {
        if (window < 2 || window > SARINS_ZVD_MAX_WINDOW) {
            sarins_log(c, SARINS_ERROR, "parameter zvd_window = %d must be 2 .. " SARINS_ZVD_STR(SARINS_ZVD_MAX_WINDOW)
                       " samples (zupt_source 1)", window);
            return SARINS_ERROR;
        }
        static const char *const zvd_names[3] = {"zvd_vrw", "zvd_arw", "zvd_gamma"};
        for (int i = 0; i < 3; i++)
            if (!(isfinite(zvd[SARINS_ZVD_VRW + i]) && zvd[SARINS_ZVD_VRW + i] > 0.0)) {
                sarins_log(c, SARINS_ERROR, "parameter %s = %.17g must be positive (zupt_source 1)", zvd_names[i],
                           zvd[SARINS_ZVD_VRW + i]);
                return SARINS_ERROR;
            }
    }
    ai_state *st = c->state;
    memset(st, 0, sizeof *st);
    char msg[256];
    st->zupt_source = source;
    if (source == 1 && sarins_zvd_init(&st->zvd, zvd, msg, sizeof msg)) {
        sarins_log(c, SARINS_ERROR, "parameters (zvd_window, step, zvd_vrw, zvd_arw, zvd_gamma): %s", msg);
        return SARINS_ERROR;
    }
    if (sarins_eskf_init_states(&st->eskf, config, opt, nav0, msg, sizeof msg)) {
        sarins_log(c, SARINS_ERROR, "parameters (lat0 .. roll0, filter settings): %s", msg);
        return SARINS_ERROR;
    }
    publish(c, st);
    c->r[SARINS_R_nav_time] = c->start_time;
    return SARINS_OK;
}

static const double *std_of(const sarins_ctx *c, double *std)
{
    const double *r = c->r;
    const int slots[6] = {SARINS_R_gnss_pos_std_e, SARINS_R_gnss_pos_std_n, SARINS_R_gnss_pos_std_u,
                          SARINS_R_gnss_vel_std_e, SARINS_R_gnss_vel_std_n, SARINS_R_gnss_vel_std_u};
    for (int i = 0; i < 6; i++)
        std[i] = r[slots[i]];
    return std;
}

/* The index of the interval after which navigate applies a fix valid at time (aided.fix_rows):
 * ceil((time - start + latency) / h - 1e-9) - 1. */
static double fix_index(const sarins_ctx *c, const ai_state *st, double time)
{
    const double *cf = st->eskf.config;
    return sm_ceil((time - c->start_time + cf[SARINS_ESKF_LATENCY]) / cf[SARINS_ESKF_STEP] - 1e-9) - 1.0;
}

/* One aiding input: a flag (0/1) and the measured values (m/s) the core reads when it is 1, at their
 * columns of the aiding row (eskf.h sarins_eskf_aid). */
typedef struct {
    const char *flag_name;
    int flag_slot, flag_column;
    int n;
    const char *names[3];
    int slots[3], columns[3];
} aid_input;

static const aid_input AID_INPUTS[] = {
    {"zupt", SARINS_I_zupt, 0, 3, {"zupt_v_e", "zupt_v_n", "zupt_v_u"},
     {SARINS_R_zupt_v_e, SARINS_R_zupt_v_n, SARINS_R_zupt_v_u}, {1, 2, 3}},
    {"odo_valid", SARINS_I_odo_valid, 4, 1, {"odo_speed", NULL, NULL}, {SARINS_R_odo_speed, 0, 0}, {5, 0, 0}},
    {"nhc", SARINS_I_nhc, 6, 2, {"nhc_v_x", "nhc_v_z", NULL}, {SARINS_R_nhc_v_x, SARINS_R_nhc_v_z, 0}, {7, 8, 0}},
    {"zaru", SARINS_I_zaru, 9, 0, {NULL, NULL, NULL}, {0, 0, 0}, {0, 0, 0}},
};

/* The interval's aiding row (SARINS_ESKF_AID, eskf.h sarins_eskf_aid) from the inputs: each flag 0 or 1,
 * the values of a set flag finite (those of a clear flag are not read: 0 in the row).  0, or -1 with the
 * error logged. */
static int aid_row(sarins_ctx *c, double t, double *aid)
{
    for (int j = 0; j < SARINS_ESKF_AID; j++)
        aid[j] = 0.0;
    for (size_t k = 0; k < sizeof AID_INPUTS / sizeof AID_INPUTS[0]; k++) {
        const aid_input *a = &AID_INPUTS[k];
        int flag = c->i[a->flag_slot];
        if (flag != 0 && flag != 1) {
            sarins_log(c, SARINS_ERROR, "ValueError: input %s = %d at t = %.17g s must be 0 or 1", a->flag_name, flag,
                       t);
            return -1;
        }
        if (!flag)
            continue;
        aid[a->flag_column] = 1.0;
        for (int j = 0; j < a->n; j++) {
            double v = c->r[a->slots[j]];
            if (!isfinite(v)) {
                sarins_log(c, SARINS_ERROR, "ValueError: input %s = %.17g at t = %.17g s is not finite (%s is 1)",
                           a->names[j], v, t, a->flag_name);
                return -1;
            }
            aid[a->columns[j]] = v;
        }
    }
    return 0;
}

/* zupt_source 1: the detector sees the interval's increments; the ZUPT and ZARU flags of its aiding row stay 1 only
 * where the detector says still (a cleared ZUPT's values zeroed, as aid_row leaves a clear flag's).  0, or -1 with
 * the error logged (a non-finite increment, checked before). */
static int detect(sarins_ctx *c, ai_state *st, const double *dtheta, const double *dv, double *aid)
{
    if (st->zupt_source != 1)
        return 0;
    double stat;
    int still = sarins_zvd_push(&st->zvd, dtheta, dv, &stat);
    if (still < 0) {
        sarins_log(c, SARINS_ERROR, "ValueError: the zero-velocity detector's increments are not finite");
        return -1;
    }
    if (!still) {
        for (int j = 0; j < 4; j++)
            aid[j] = 0.0;
        aid[9] = 0.0;
    }
    return 0;
}

/* Time-tagged mode (model.h's do_step, the declaration's contract): queue the inputs, integrate what is due. */
static int tagged_step(sarins_ctx *c, ai_state *st, double t)
{
    const double *r = c->r;
    double h = st->eskf.config[SARINS_ESKF_STEP];
    double tag = r[SARINS_R_increment_end_time];
    double index = sm_floor((tag - c->start_time) / h + 0.5), point = c->start_time + index * h;
    if (!(isfinite(tag) && index >= 0.0 && index < 9007199254740992.0)
        || sm_fabs(tag - point) > STEP_TOL * (sm_fabs(point) + h)) {
        sarins_log(c, SARINS_ERROR, "ValueError: increment_end_time %.17g s is not a communication point", tag);
        return SARINS_ERROR;
    }
    int64_t received = st->done + st->n_inc; /* intervals received: the next one ends at start + (received + 1) h */
    int64_t m = (int64_t)index;
    if (m == received + 1) {
        if (st->n_inc == MAX_INC) {
            sarins_log(c, SARINS_ERROR, "ValueError: more than %d intervals wait for fix_horizon at t = %.17g s "
                       "(is the receiver's fix_horizon connected?)", MAX_INC, t);
            return SARINS_ERROR;
        }
        double *slot = st->inc[(st->inc_first + st->n_inc) % MAX_INC];
        const int in[6] = {SARINS_R_dtheta_x, SARINS_R_dtheta_y, SARINS_R_dtheta_z, SARINS_R_dv_x, SARINS_R_dv_y,
                           SARINS_R_dv_z};
        for (int i = 0; i < 6; i++) {
            slot[i] = r[in[i]];
            if (!isfinite(slot[i])) {
                sarins_log(c, SARINS_ERROR, "ValueError: an increment input at t = %.17g s is not finite", t);
                return SARINS_ERROR;
            }
        }
        if (aid_row(c, t, slot + 6) < 0 || detect(c, st, slot, slot + 3, slot + 6) < 0)
            return SARINS_ERROR;
        st->n_inc += 1;
    } else if (m != received) {
        sarins_log(c, SARINS_ERROR, "ValueError: increment_end_time %.17g s: the interval ending at %.17g s was "
                   "expected", tag, c->start_time + (double)(received + 1) * h);
        return SARINS_ERROR;
    }
    int64_t count = c->i[SARINS_I_fix_count];
    if (count > st->last_count) {
        if (st->n_fix == MAX_FIX) {
            sarins_log(c, SARINS_ERROR, "ValueError: more than %d fixes wait at t = %.17g s", MAX_FIX, t);
            return SARINS_ERROR;
        }
        double row[FIX_ROW] = {c->i[SARINS_I_fix_valid] != 0, r[SARINS_R_fix_time], r[SARINS_R_fix_lat],
                               r[SARINS_R_fix_lon], r[SARINS_R_fix_height], r[SARINS_R_fix_v_e], r[SARINS_R_fix_v_n],
                               r[SARINS_R_fix_v_u]};
        for (int i = 1; i < FIX_ROW; i++)
            if (!isfinite(row[i])) {
                sarins_log(c, SARINS_ERROR, "ValueError: a fix input at t = %.17g s is not finite", t);
                return SARINS_ERROR;
            }
        if (fix_index(c, st, row[1]) < (double)st->done) {
            sarins_log(c, SARINS_ERROR, "ValueError: the fix valid at %.17g s came after its interval was integrated "
                       "(fix_horizon said it was in)", row[1]);
            return SARINS_ERROR;
        }
        memcpy(st->fix[(st->fix_first + st->n_fix) % MAX_FIX], row, sizeof row);
        st->n_fix += 1;
        st->last_count = count;
    }
    double horizon = r[SARINS_R_fix_horizon], latency = st->eskf.config[SARINS_ESKF_LATENCY];
    if (isnan(horizon)) {
        sarins_log(c, SARINS_ERROR, "ValueError: fix_horizon at t = %.17g s is not a number", t);
        return SARINS_ERROR;
    }
    double std[6];
    std_of(c, std);
    while (st->n_inc > 0) {
        double end = c->start_time + (double)(st->done + 1) * h; /* of the interval to integrate */
        if (!(horizon >= end - latency - STEP_TOL * (sm_fabs(end) + h)))
            break; /* a fix applied after it may still come */
        const double *inc = st->inc[st->inc_first];
        sarins_eskf_predict(&st->eskf, inc, inc + 3);
        sarins_eskf_aid(&st->eskf, inc, inc + 6);
        while (st->n_fix > 0 && fix_index(c, st, st->fix[st->fix_first][1]) <= (double)st->done) {
            const double *f = st->fix[st->fix_first];
            if (f[0] != 0.0) {
                sarins_eskf_gnss(&st->eskf, f + 2, f + 5, std, c->i[SARINS_I_use_velocity]);
                st->used += 1;
            }
            st->fix_first = (st->fix_first + 1) % MAX_FIX;
            st->n_fix -= 1;
        }
        st->inc_first = (st->inc_first + 1) % MAX_INC;
        st->n_inc -= 1;
        st->done += 1;
    }
    publish(c, st);
    c->r[SARINS_R_nav_time] = c->start_time + (double)st->done * h;
    return SARINS_OK;
}

static int ai_do_step(sarins_ctx *c, double t, double h)
{
    ai_state *st = c->state;
    char msg[256];
    if (!ai_state_ok(st, msg, sizeof msg)) {
        sarins_log(c, SARINS_ERROR, "%s", msg);
        return SARINS_ERROR;
    }
    double step = st->eskf.config[SARINS_ESKF_STEP];
    if (sm_fabs(h - step) > STEP_TOL * step) {
        sarins_log(c, SARINS_ERROR, "ValueError: communication step %.17g s differs from parameter step %.17g s", h,
                   step);
        return SARINS_ERROR;
    }
    if (c->r[SARINS_R_increment_end_time] != NO_TAG)
        return tagged_step(c, st, t);
    const double *r = c->r;
    double dtheta[3] = {r[SARINS_R_dtheta_x], r[SARINS_R_dtheta_y], r[SARINS_R_dtheta_z]};
    double dv[3] = {r[SARINS_R_dv_x], r[SARINS_R_dv_y], r[SARINS_R_dv_z]};
    double pos[3] = {r[SARINS_R_fix_lat], r[SARINS_R_fix_lon], r[SARINS_R_fix_height]};
    double vel[3] = {r[SARINS_R_fix_v_e], r[SARINS_R_fix_v_n], r[SARINS_R_fix_v_u]};
    for (int i = 0; i < 3; i++)
        if (!isfinite(dtheta[i]) || !isfinite(dv[i])) {
            sarins_log(c, SARINS_ERROR, "ValueError: an increment input at t = %.17g s is not finite", t);
            return SARINS_ERROR;
        }
    double aid[SARINS_ESKF_AID];
    if (aid_row(c, t, aid) < 0 || detect(c, st, dtheta, dv, aid) < 0)
        return SARINS_ERROR;
    int64_t count = c->i[SARINS_I_fix_count];
    int fresh = count > st->last_count && c->i[SARINS_I_fix_valid] != 0;
    if (fresh)
        for (int i = 0; i < 3; i++)
            if (!isfinite(pos[i]) || !isfinite(vel[i])) {
                sarins_log(c, SARINS_ERROR, "ValueError: a fix input at t = %.17g s is not finite", t);
                return SARINS_ERROR;
            }
    sarins_eskf_predict(&st->eskf, dtheta, dv);
    sarins_eskf_aid(&st->eskf, dtheta, aid);
    if (fresh) {
        double std[6] = {r[SARINS_R_gnss_pos_std_e], r[SARINS_R_gnss_pos_std_n], r[SARINS_R_gnss_pos_std_u],
                         r[SARINS_R_gnss_vel_std_e], r[SARINS_R_gnss_vel_std_n], r[SARINS_R_gnss_vel_std_u]};
        sarins_eskf_gnss(&st->eskf, pos, vel, std, c->i[SARINS_I_use_velocity]);
        st->used += 1;
    }
    if (count > st->last_count)
        st->last_count = count;
    publish(c, st);
    c->r[SARINS_R_nav_time] = t + h;
    return SARINS_OK;
}

static void ai_release(sarins_ctx *c)
{
    c->work = NULL;
}

/* A state handed to the FMU (model.h "State validation"): every field within what do_step relies on. */
static int ai_check_state(const sarins_ctx *c, int running)
{
    (void)running;
    const ai_state *st = c->state;
    const sarins_eskf *e = &st->eskf;
    const long long big = 1LL << 53;
    int ok = sarins_state_int(c, "last_count", st->last_count, 0, big) && sarins_state_int(c, "used", st->used, 0, big)
             && sarins_state_int(c, "eskf.steps", e->steps, 0, big)
             && sarins_state_int(c, "eskf.since_cov", e->since_cov, 0, 1000)
             && sarins_state_real(c, "eskf.step", e->config[SARINS_ESKF_STEP], 1e-300, 1e300)
             && sarins_state_real(c, "eskf.cov_every", e->config[SARINS_ESKF_COV_EVERY], 1.0, 1000.0)
             && sarins_state_finite(c, "eskf.config", e->config, SARINS_ESKF_CONFIG)
             && sarins_state_finite(c, "eskf.q", e->q, 4) && sarins_state_finite(c, "eskf.v", e->v, 3)
             && sarins_state_finite(c, "eskf.pos", e->pos, 3) && sarins_state_finite(c, "eskf.bg", e->bg, 3)
             && sarins_state_finite(c, "eskf.ba", e->ba, 3)
             && sarins_state_finite(c, "eskf.w_ib", e->w_ib, 3) && sarins_state_finite(c, "eskf.f_n", e->f_n, 3)
             && sarins_state_int(c, "inc_first", st->inc_first, 0, MAX_INC - 1)
             && sarins_state_int(c, "n_inc", st->n_inc, 0, MAX_INC) && sarins_state_int(c, "done", st->done, 0, big)
             && sarins_state_int(c, "fix_first", st->fix_first, 0, MAX_FIX - 1)
             && sarins_state_int(c, "n_fix", st->n_fix, 0, MAX_FIX)
             && sarins_state_finite(c, "inc", &st->inc[0][0], INC_ROW * MAX_INC)
             && sarins_state_finite(c, "fix", &st->fix[0][0], FIX_ROW * MAX_FIX);
    char msg[256];
    if (ok && sarins_eskf_check(e, msg, sizeof msg)) { /* options, layout, P, x and the optional blocks */
        sarins_log(c, SARINS_ERROR, "FMU state: eskf: %s", msg);
        ok = 0;
    }
    ok = ok && sarins_state_int(c, "zupt_source", st->zupt_source, 0, 1);
    if (ok && st->zupt_source == 1 && sarins_zvd_check(&st->zvd, msg, sizeof msg)) {
        sarins_log(c, SARINS_ERROR, "FMU state: %s", msg);
        ok = 0;
    }
    if (ok && st->zupt_source == 1 && !(st->zvd.step == e->config[SARINS_ESKF_STEP])) {
        sarins_log(c, SARINS_ERROR, "FMU state: the zero-velocity detector's step differs from the filter's");
        ok = 0;
    }
    for (int i = 0; ok && i < MAX_INC; i++) /* the aiding flags aid_row writes */
        for (size_t k = 0; ok && k < sizeof AID_INPUTS / sizeof AID_INPUTS[0]; k++)
            ok = sarins_state_real(c, "inc (an aiding flag)", st->inc[i][6 + AID_INPUTS[k].flag_column], 0.0, 1.0);
    return ok ? SARINS_OK : SARINS_ERROR;
}

const sarins_model sarins_model_desc = {
    .table = &SARINS_TABLE,
    .state_size = sizeof(ai_state),
    .state_version = 6, /* 4: the ring's rows carry the aiding row (ZUPT, odometer, NHC, ZARU); 5: the filter's
                         * optional states (eskf.h: n x n P, options, their estimates); 6: the stillness detector
                         * (zupt_source, zvd) */
    .initialize = ai_initialize,
    .do_step = ai_do_step,
    .release = ai_release,
    .check_state = ai_check_state,
};
