/* Seed 002's land vehicle (vehicle.h). */
#include "smath.h"
#include <stdlib.h>
#include <string.h>

#include "earth.h"
#include "report.h"
#include "rng.h"
#include "schedule.h"
#include "vehicle.h"

#define PI 3.14159265358979323846
#define DEG (PI / 180.0)
#define MAX_STEPS 9007199254740992.0 /* 2^53 grid steps */

void sarins_vehicle_params_default(sarins_vehicle_params *p)
{
    memset(p, 0, sizeof *p);
    p->step = 1.0;
    p->accel = 1.0;
    p->brake = 1.5;
    p->yaw_rate = 6.0 * DEG;
    p->yaw_accel = 3.0 * DEG;
    p->sway_pitch = 0.5 * DEG;
    p->sway_roll = 0.3 * DEG;
    p->sway_period = 20.0;
    p->vibration = 0.05 * DEG;
    p->vibration_hz[0] = 0.13;
    p->vibration_hz[1] = 0.29;
    p->vibration_hz[2] = 0.41;
    p->reference_speed = 10.0;
}

static int check_params(const sarins_vehicle_params *p, report *r)
{
    const char *finite_names[] = {"lat0", "lon0", "heading0", "step", "lead_time"};
    const double finite_values[] = {p->lat0, p->lon0, p->heading0, p->step, p->lead_time};
    for (int i = 0; i < 5; i++)
        if (!isfinite(finite_values[i]))
            return sarins_fail(r, SARINS_VEHICLE_BAD_PARAM, "%s must be finite", finite_names[i]);
    if (sm_fabs(p->lat0) > 89.9 * DEG)
        return sarins_fail(r, SARINS_VEHICLE_BAD_PARAM, "lat0: latitude outside +-89.9 deg");
    if (!(p->step > 0))
        return sarins_fail(r, SARINS_VEHICLE_BAD_PARAM, "step must be positive");
    if (!(p->lead_time >= 0))
        return sarins_fail(r, SARINS_VEHICLE_BAD_PARAM, "lead_time must be >= 0");
    const char *pos_names[] = {"accel", "brake", "yaw_rate", "yaw_accel", "sway_period", "reference_speed"};
    const double pos_values[] = {p->accel, p->brake, p->yaw_rate, p->yaw_accel, p->sway_period, p->reference_speed};
    for (int i = 0; i < 6; i++)
        if (!(isfinite(pos_values[i]) && pos_values[i] > 0))
            return sarins_fail(r, SARINS_VEHICLE_BAD_PARAM, "%s must be a positive number", pos_names[i]);
    const char *nn_names[] = {"sway_pitch", "sway_roll", "vibration"};
    const double nn_values[] = {p->sway_pitch, p->sway_roll, p->vibration};
    for (int i = 0; i < 3; i++)
        if (!(isfinite(nn_values[i]) && nn_values[i] >= 0))
            return sarins_fail(r, SARINS_VEHICLE_BAD_PARAM, "body motion %s must be a non-negative number",
                               nn_names[i]);
    for (int i = 0; i < SARINS_VEHICLE_N_VIBRATION; i++)
        if (!(isfinite(p->vibration_hz[i]) && p->vibration_hz[i] > 0))
            return sarins_fail(r, SARINS_VEHICLE_BAD_PARAM, "vibration frequencies must be positive");
    if (!(p->lead_time / p->step < MAX_STEPS))
        return sarins_fail(r, SARINS_VEHICLE_BAD_PARAM, "lead_time is too long for the grid");
    return 0;
}

/* Appends a segment (or counts it when segs is NULL). */
static int add(report *r, sarins_vehicle_segment *segs, int64_t cap, int64_t *n, int64_t steps, double accel,
               double yaw_accel, double end_speed, int end_turn)
{
    if (steps <= 0)
        return 0;
    if (segs != NULL) {
        if (*n >= cap)
            return sarins_fail(r, SARINS_VEHICLE_CAPACITY, "more than %lld segments", (long long)cap);
        sarins_vehicle_segment *s = &segs[*n];
        s->n = steps;
        s->accel = accel;
        s->yaw_accel = yaw_accel;
        s->end_speed = end_speed;
        s->end_turn = end_turn;
    }
    *n += 1;
    return 0;
}

/* Segments of a turn through angle (rad) at speed. */
static int turn(report *r, const sarins_vehicle_params *p, double angle, double speed,
                sarins_vehicle_segment *segs, int64_t cap, int64_t *n, int64_t *steps)
{
    if (!isfinite(angle))
        return sarins_fail(r, SARINS_VEHICLE_BAD_PARAM, "turn angle must be finite");
    if (angle == 0.0)
        return 0;
    if (speed <= 0)
        return sarins_fail(r, SARINS_VEHICLE_BAD_PARAM, "a turn needs a moving vehicle (drive first)");
    double dur[3], acc[3];
    int64_t m = 0;
    char why[160];
    if (sarins_move_segments(angle, p->yaw_rate, p->yaw_accel, p->step, dur, acc, &m, why, sizeof why))
        return sarins_fail(r, SARINS_VEHICLE_BAD_PARAM, "turn: %s", why);
    for (int64_t i = 0; i < m; i++) {
        int64_t k = (int64_t)sm_round(dur[i] / p->step);
        if (add(r, segs, cap, n, k, 0.0, acc[i], speed, i == m - 1))
            return r->code;
        *steps += k;
    }
    return 0;
}

int sarins_vehicle_segments(const sarins_vehicle_params *p, const sarins_leg *legs, int64_t n_legs,
                            sarins_vehicle_segment *segs, int64_t cap, int64_t *n_segments, int64_t *n_steps,
                            char *msg, size_t msg_len)
{
    report r = sarins_report(msg, msg_len);
    int64_t n = 0, steps = 0;
    *n_segments = 0;
    *n_steps = 0;
    if (check_params(p, &r))
        return r.code;
    if (n_legs < 0 || (n_legs > 0 && legs == NULL))
        return sarins_fail(&r, SARINS_VEHICLE_BAD_PARAM, "no legs");
    int64_t lead = (int64_t)sm_round(p->lead_time / p->step);
    if (add(&r, segs, cap, &n, lead, 0.0, 0.0, 0.0, 0))
        return r.code;
    steps += lead;
    double speed = 0.0;
    for (int64_t i = 0; i < n_legs; i++) {
        const sarins_leg *leg = &legs[i];
        if (leg->kind == SARINS_LEG_TURN) {
            if (turn(&r, p, leg->value, speed, segs, cap, &n, &steps))
                return r.code;
            continue;
        }
        if (leg->kind != SARINS_LEG_STOP && leg->kind != SARINS_LEG_DRIVE)
            return sarins_fail(&r, SARINS_VEHICLE_BAD_PARAM, "unknown leg kind %d; choose stop, drive or turn",
                               leg->kind);
        if (!(isfinite(leg->seconds) && leg->seconds > 0 && leg->seconds / p->step < MAX_STEPS))
            return sarins_fail(&r, SARINS_VEHICLE_BAD_PARAM, "leg duration must be positive, got %.17g",
                               leg->seconds);
        double target = leg->kind == SARINS_LEG_STOP ? 0.0 : leg->value;
        if (!(isfinite(target) && target >= 0))
            return sarins_fail(&r, SARINS_VEHICLE_BAD_PARAM, "drive speed must be >= 0 m/s, got %.17g", target);
        int64_t n_ramp = 0;
        double a = 0.0;
        if (target != speed) { /* whole steps taking the speed to the target exactly */
            double rate = target < speed ? p->brake : p->accel;
            double k = sm_ceil(sm_fabs(target - speed) / (rate * p->step) - 1e-9);
            if (!(k < MAX_STEPS))
                return sarins_fail(&r, SARINS_VEHICLE_BAD_PARAM, "drive speed %.17g m/s is out of reach", target);
            n_ramp = k < 1.0 ? 1 : (int64_t)k;
            a = (target - speed) / ((double)n_ramp * p->step);
        }
        int64_t n_total = (int64_t)sm_round(leg->seconds / p->step);
        if (n_total < n_ramp)
            n_total = n_ramp;
        if (add(&r, segs, cap, &n, n_ramp, a, 0.0, target, 0) ||
            add(&r, segs, cap, &n, n_total - n_ramp, 0.0, 0.0, target, 0))
            return r.code;
        steps += n_total;
        speed = target;
    }
    if (add(&r, segs, cap, &n, 1, 0.0, 0.0, speed, 0)) /* a last step at rest (or cruising) */
        return r.code;
    steps += 1;
    if (!((double)steps < MAX_STEPS))
        return sarins_fail(&r, SARINS_VEHICLE_BAD_PARAM, "the legs are too long for the grid");
    *n_segments = n;
    *n_steps = steps;
    return 0;
}

void sarins_vehicle_start(sarins_vehicle *v, const sarins_vehicle_params *p)
{
    memset(v, 0, sizeof *v);
    SarinsRng rng;
    sarins_rng_stream(&rng, p->seed, SARINS_VEHICLE_STREAM);
    for (int j = 0; j < 2; j++)
        for (int i = 0; i <= SARINS_VEHICLE_N_VIBRATION; i++)
            v->phase[j][i] = 2.0 * PI * sarins_rng_uniform(&rng);
    v->w_sway = 2.0 * PI / p->sway_period;
    for (int i = 0; i < SARINS_VEHICLE_N_VIBRATION; i++)
        v->w_vib[i] = 2.0 * PI * p->vibration_hz[i];
    v->amplitude[0] = p->sway_pitch;
    v->amplitude[1] = p->sway_roll;
    v->vibration = p->vibration;
    v->reference_speed = p->reference_speed;
    v->step = p->step;
    v->yaw = p->heading0;
    v->lat = p->lat0;
    v->lon = p->lon0;
}

/* Body pitch (j = 0) or roll (1) rate, rad/s, at time t (s) and speed (m/s). */
static double body_rate(const sarins_vehicle *v, int j, double t, double speed)
{
    if (speed == 0.0)
        return 0.0;
    /* q = [A w_s cos(w_s t + p_0) + B sum w_i cos(w_i t + p_i)] s / s_ref */
    double q = v->amplitude[j] * v->w_sway * sm_cos(v->w_sway * t + v->phase[j][0]);
    for (int i = 0; i < SARINS_VEHICLE_N_VIBRATION; i++)
        q += v->vibration * v->w_vib[i] * sm_cos(v->w_vib[i] * t + v->phase[j][i + 1]);
    return q * (speed / v->reference_speed);
}

/* v^n = s (-sin psi, cos psi, 0): east, north */
static void velocity(double speed, double yaw, double *ve, double *vn)
{
    double s, c;
    sm_sincos(yaw, &s, &c);
    *ve = -speed * s;
    *vn = speed * c;
}

void sarins_vehicle_step(sarins_vehicle *v, const sarins_vehicle_segment *segs, int64_t n_segments, double *out)
{
    const double h = v->step;
    const sarins_vehicle_segment *seg = v->segment < n_segments ? &segs[v->segment] : NULL;
    double a = seg ? seg->accel : 0.0, alpha = seg ? seg->yaw_accel : 0.0;
    int last = seg != NULL && v->in_segment + 1 == seg->n;
    /* next grid point: s, r, psi */
    double speed1 = last ? seg->end_speed : v->speed + a * h;
    double yaw_rate1 = (last && seg->end_turn) ? 0.0 : v->yaw_rate + alpha * h;
    double yaw1 = v->yaw + v->yaw_rate * h + 0.5 * alpha * (h * h);
    /* body rates at t_k and t_{k+1}, acceleration between */
    double t0 = (double)v->k * h, t1 = (double)(v->k + 1) * h;
    double q0[2], q1[2], qa[2];
    for (int j = 0; j < 2; j++) {
        q0[j] = body_rate(v, j, t0, v->speed);
        q1[j] = body_rate(v, j, t1, speed1);
        qa[j] = (q1[j] - q0[j]) / h;
    }
    /* Simpson mean velocity over the step */
    double speed_mid = v->speed + 0.5 * a * h;
    double yaw_mid = v->yaw + 0.5 * v->yaw_rate * h + 0.125 * alpha * (h * h);
    double ve0, vn0, vem, vnm, ve1, vn1;
    velocity(v->speed, v->yaw, &ve0, &vn0);
    velocity(speed_mid, yaw_mid, &vem, &vnm);
    velocity(speed1, yaw1, &ve1, &vn1);
    double ve = (ve0 + 4.0 * vem + ve1) / 6.0, vn = (vn0 + 4.0 * vnm + vn1) / 6.0;
    /* position: midpoint rule in latitude */
    double rm, rn;
    sarins_earth_radii(v->lat, &rm, &rn);
    double lat_p = v->lat + 0.5 * vn * h / rm;
    sarins_earth_radii(lat_p, &rm, &rn);
    double lat1 = v->lat + vn * h / rm;
    double lat_m = 0.5 * (v->lat + lat1);
    sarins_earth_radii(lat_m, &rm, &rn);
    double sl, cl;
    sm_sincos(lat_m, &sl, &cl);
    double lon1 = v->lon + ve * h / (rn * cl);
    /* w_ie, w_en, g at mid-step */
    double wie[3] = {0.0, SARINS_EARTH_RATE * cl, SARINS_EARTH_RATE * sl};
    double wen[3] = {-vn / rm, ve / rn, ve * (sl / cl) / rn};
    double g = sarins_earth_gravity(lat_m, 0.0);
    /* f = dv/h + (2 w_ie + w_en) x vbar - g^n, vbar = (ve, vn, 0) */
    double c[3] = {2.0 * wie[0] + wen[0], 2.0 * wie[1] + wen[1], 2.0 * wie[2] + wen[2]};
    out[SARINS_VEH_YAW] = v->yaw;
    out[SARINS_VEH_PITCH] = v->pitch;
    out[SARINS_VEH_ROLL] = v->roll;
    out[SARINS_VEH_YAW_RATE] = v->yaw_rate;
    out[SARINS_VEH_PITCH_RATE] = q0[0];
    out[SARINS_VEH_ROLL_RATE] = q0[1];
    out[SARINS_VEH_YAW_ACC] = alpha;
    out[SARINS_VEH_PITCH_ACC] = qa[0];
    out[SARINS_VEH_ROLL_ACC] = qa[1];
    for (int i = 0; i < 3; i++)
        out[SARINS_VEH_W_E + i] = wie[i] + wen[i];
    out[SARINS_VEH_F_E] = (ve1 - ve0) / h - c[2] * vn;
    out[SARINS_VEH_F_N] = (vn1 - vn0) / h + c[2] * ve;
    out[SARINS_VEH_F_U] = (c[0] * vn - c[1] * ve) + g;
    out[SARINS_VEH_LAT] = v->lat;
    out[SARINS_VEH_LON] = v->lon;
    out[SARINS_VEH_V_E] = ve0;
    out[SARINS_VEH_V_N] = vn0;
    out[SARINS_VEH_SPEED] = v->speed;
    /* move to t_{k+1}: theta += q h + acc h^2 / 2 */
    v->pitch += q0[0] * h + 0.5 * qa[0] * (h * h);
    v->roll += q0[1] * h + 0.5 * qa[1] * (h * h);
    v->speed = speed1;
    v->yaw_rate = yaw_rate1;
    v->yaw = yaw1;
    v->lat = lat1;
    v->lon = lon1;
    v->k += 1;
    if (seg != NULL) {
        v->in_segment += 1;
        if (last) {
            v->segment += 1;
            v->in_segment = 0;
        }
    }
}

int sarins_vehicle_valid(const sarins_vehicle *v, char *msg, size_t msg_len)
{
    report r = sarins_report(msg, msg_len);
    if (!(isfinite(v->lat) && isfinite(v->lon) && isfinite(v->speed) && isfinite(v->yaw) && isfinite(v->pitch)
          && isfinite(v->roll) && isfinite(v->yaw_rate))) {
        sarins_fail(&r, SARINS_VEHICLE_BAD_PARAM, "the drive's state is not finite at t = %.17g s",
                    (double)v->k * v->step);
        return 0;
    }
    if (sm_fabs(v->lat) > 89.9 * DEG) {
        sarins_fail(&r, SARINS_VEHICLE_BAD_PARAM, "the legs drive beyond +-89.9 deg latitude (%.9g deg at t = %.17g s)",
                    v->lat / DEG, (double)v->k * v->step);
        return 0;
    }
    return 1;
}

int sarins_vehicle_state_ok(const sarins_vehicle *v, const sarins_vehicle_segment *segs, int64_t n_segments,
                            char *msg, size_t msg_len)
{
    report r = sarins_report(msg, msg_len);
    if (!(v->k >= 0 && v->segment >= 0 && v->segment <= n_segments && v->in_segment >= 0
          && (v->segment == n_segments ? v->in_segment == 0 : v->in_segment < segs[v->segment].n))) {
        sarins_fail(&r, SARINS_VEHICLE_BAD_PARAM, "vehicle state: grid point %lld, segment %lld of %lld, step %lld "
                    "in it: out of range", (long long)v->k, (long long)v->segment, (long long)n_segments,
                    (long long)v->in_segment);
        return 0;
    }
    double consts[] = {v->step, v->reference_speed, v->w_sway, v->w_vib[0], v->w_vib[1], v->w_vib[2]};
    for (size_t i = 0; i < sizeof consts / sizeof consts[0]; i++)
        if (!(isfinite(consts[i]) && consts[i] > 0)) {
            sarins_fail(&r, SARINS_VEHICLE_BAD_PARAM, "vehicle state: a grid or body constant is not positive");
            return 0;
        }
    for (int j = 0; j < 2; j++)
        for (int i = 0; i <= SARINS_VEHICLE_N_VIBRATION; i++)
            if (!(isfinite(v->phase[j][i]) && isfinite(v->amplitude[j]) && isfinite(v->vibration))) {
                sarins_fail(&r, SARINS_VEHICLE_BAD_PARAM, "vehicle state: a body phase or amplitude is not finite");
                return 0;
            }
    return 1;
}

static const char *skip_blanks(const char *s)
{
    while (*s == ' ' || *s == '\t' || *s == '\n' || *s == '\r')
        s++;
    return s;
}

/* One leg "kind n1 [n2]" in [s, end): 0 or -1 with the reason. */
static int parse_leg(report *r, const char *s, const char *end, sarins_leg *leg)
{
    char part[SARINS_VEHICLE_PART_MAX];
    size_t len = (size_t)(end - s);
    while (len > 0 && (s[len - 1] == ' ' || s[len - 1] == '\t' || s[len - 1] == '\n' || s[len - 1] == '\r'))
        len--;
    if (len >= sizeof part)
        return sarins_fail(r, 1, "leg '%.40s...' is too long", s);
    memcpy(part, s, len);
    part[len] = '\0';
    const char *p = part;
    size_t kind_len = strcspn(p, " \t\r\n");
    int want;
    if (kind_len == 5 && strncmp(p, "drive", 5) == 0) {
        leg->kind = SARINS_LEG_DRIVE;
        want = 2;
    } else if (kind_len == 4 && strncmp(p, "turn", 4) == 0) {
        leg->kind = SARINS_LEG_TURN;
        want = 1;
    } else if (kind_len == 4 && strncmp(p, "stop", 4) == 0) {
        leg->kind = SARINS_LEG_STOP;
        want = 1;
    } else {
        return sarins_fail(r, 1, "leg '%s': use 'drive SECONDS SPEED', 'turn DEGREES' or 'stop SECONDS'", part);
    }
    double x[3];
    int got = 0;
    p = skip_blanks(p + kind_len);
    while (*p != '\0') {
        char *stop;
        double value = strtod(p, &stop);
        if (stop == p || !(*stop == '\0' || *stop == ' ' || *stop == '\t' || *stop == '\r' || *stop == '\n'))
            return sarins_fail(r, 1, "leg '%s': numbers expected after '%.*s'", part, (int)kind_len, part);
        if (got == 3)
            break;
        x[got++] = value;
        p = skip_blanks(stop);
    }
    if (got != want)
        return sarins_fail(r, 1, "leg '%s': use 'drive SECONDS SPEED', 'turn DEGREES' or 'stop SECONDS'", part);
    if (leg->kind == SARINS_LEG_TURN) {
        leg->seconds = x[0];
        leg->value = x[0] * DEG;
    } else {
        leg->seconds = x[0];
        leg->value = leg->kind == SARINS_LEG_DRIVE ? x[1] : 0.0;
    }
    return 0;
}

int64_t sarins_vehicle_parse_legs(const char *text, sarins_leg *legs, int64_t cap, char *msg, size_t msg_len)
{
    report r = sarins_report(msg, msg_len);
    int64_t n = 0;
    if (text == NULL) {
        sarins_fail(&r, 1, "legs is empty");
        return -1;
    }
    const char *s = text;
    for (;;) {
        const char *end = strchr(s, ';');
        if (end == NULL)
            end = s + strlen(s);
        s = skip_blanks(s);
        if (s < end) {
            if (n >= cap) {
                sarins_fail(&r, 1, "more than %lld legs", (long long)cap);
                return -1;
            }
            if (parse_leg(&r, s, end, &legs[n]))
                return -1;
            n++;
        }
        if (*end == '\0')
            break;
        s = end + 1;
    }
    if (n == 0) {
        sarins_fail(&r, 1, "legs is empty");
        return -1;
    }
    return n;
}

int sarins_vehicle_run(const sarins_vehicle_params *p, const sarins_leg *legs, int64_t n_legs,
                       sarins_vehicle_segment *segs, int64_t cap, int64_t n_rows, double *out, int64_t *n_steps,
                       char *msg, size_t msg_len)
{
    int64_t n_segments = 0;
    int code = sarins_vehicle_segments(p, legs, n_legs, out == NULL ? NULL : segs, cap, &n_segments, n_steps, msg,
                                       msg_len);
    if (code || out == NULL)
        return code;
    sarins_vehicle v;
    sarins_vehicle_start(&v, p);
    for (int64_t k = 0; k < n_rows; k++) {
        sarins_vehicle_step(&v, segs, n_segments, out + (size_t)k * SARINS_VEH_N_OUT);
        if (!sarins_vehicle_valid(&v, msg, msg_len))
            return SARINS_VEHICLE_BAD_PARAM;
    }
    return 0;
}
