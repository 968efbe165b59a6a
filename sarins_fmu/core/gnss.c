#include "smath.h"
#include "report.h"
#include "gnss.h"

#include "earth.h"
#include "rotations.h"

/* 1 when config holds (finite, standard deviations >= 0, correlation times > 0), else 0 with msg. */
static int config_ok(const double *config, char *msg, size_t size)
{
    for (int i = 0; i < SARINS_GNSS_CONFIG; i++)
        if (!isfinite(config[i])) {
            sarins_say(msg, size, "a GNSS setting is not finite");
            return 0;
        }
    for (int i = SARINS_GNSS_POS_WHITE_E; i < SARINS_GNSS_CONFIG; i++)
        if (config[i] < 0.0) {
            sarins_say(msg, size, "a GNSS standard deviation is negative");
            return 0;
        }
    if (!(config[SARINS_GNSS_POS_TAU] > 0.0) || !(config[SARINS_GNSS_VEL_TAU] > 0.0)) {
        sarins_say(msg, size, "a GNSS correlation time is not positive");
        return 0;
    }
    return 1;
}

int sarins_gnss_init(sarins_gnss *s, const double *config, uint64_t seed, char *msg, size_t size)
{
    if (!config_ok(config, msg, size))
        return 1;
    for (int i = 0; i < SARINS_GNSS_CONFIG; i++)
        s->config[i] = config[i];
    sarins_rng_stream(&s->rng, seed, 30);
    s->epochs = 0;
    s->last_time = 0.0;
    for (int i = 0; i < 6; i++) /* stationary start: b ~ N(0, sigma_gm^2) */
        s->b[i] = config[(i < 3 ? SARINS_GNSS_POS_GM_E : SARINS_GNSS_VEL_GM_E) + i % 3] * sarins_rng_normal(&s->rng);
    return 0;
}

static void antenna(const double *lever, const double *row, const double *w_ib, double *pos, double *vel)
{
    double m[9], rm, rn, sl, cl;
    sarins_euler_to_mat(row[6], row[7], row[8], m);
    sarins_earth_radii(row[0], &rm, &rn);
    sm_sincos(row[0], &sl, &cl);
    double rmh = rm + row[2], rnh = rn + row[2];
    double w_in[3] = {-row[4] / rmh, SARINS_EARTH_RATE * cl + row[3] / rnh,
                      SARINS_EARTH_RATE * sl + row[3] * sl / (cl * rnh)};
    double w_nb[3], c[3], ln[3], vn[3];
    for (int i = 0; i < 3; i++) /* omega_nb^b = omega_ib^b - mat_bn omega_in^n */
        w_nb[i] = w_ib[i] - (m[i] * w_in[0] + m[3 + i] * w_in[1] + m[6 + i] * w_in[2]);
    c[0] = w_nb[1] * lever[2] - w_nb[2] * lever[1];
    c[1] = w_nb[2] * lever[0] - w_nb[0] * lever[2];
    c[2] = w_nb[0] * lever[1] - w_nb[1] * lever[0];
    for (int i = 0; i < 3; i++) {
        ln[i] = m[3 * i] * lever[0] + m[3 * i + 1] * lever[1] + m[3 * i + 2] * lever[2];
        vn[i] = m[3 * i] * c[0] + m[3 * i + 1] * c[1] + m[3 * i + 2] * c[2];
        vel[i] = row[3 + i] + vn[i];
    }
    pos[0] = row[0] + ln[1] / rmh;
    pos[1] = row[1] + ln[0] / (rnh * cl);
    pos[2] = row[2] + ln[2];
}

int sarins_gnss_fixes(sarins_gnss *s, int64_t n, const double *time, const double *truth, const double *omega_ib,
                      int64_t n_out, const double *outages, double *out)
{
    double prev = s->last_time;
    for (int64_t j = 0; j < n; j++) {
        if (!isfinite(time[j]) || (s->epochs + j > 0 && !(time[j] > prev)))
            return 1;
        prev = time[j];
        for (int c = 0; c < 9; c++)
            if (!isfinite(truth[9 * j + c]))
                return 1;
        for (int c = 0; c < 3; c++)
            if (!isfinite(omega_ib[3 * j + c]))
                return 1;
    }
    for (int64_t i = 0; i < 2 * n_out; i++)
        if (!isfinite(outages[i]))
            return 1;
    const double *cf = s->config;
    for (int64_t j = 0; j < n; j++) {
        if (s->epochs > 0) { /* b = exp(-dt/tau) b + sigma sqrt(1 - exp(-2 dt/tau)) u */
            double dt = time[j] - s->last_time;
            for (int i = 0; i < 6; i++) {
                double tau = cf[i < 3 ? SARINS_GNSS_POS_TAU : SARINS_GNSS_VEL_TAU];
                double sigma = cf[(i < 3 ? SARINS_GNSS_POS_GM_E : SARINS_GNSS_VEL_GM_E) + i % 3];
                double a = sm_exp(-dt / tau);
                s->b[i] = a * s->b[i] + sigma * sm_sqrt(1.0 - a * a) * sarins_rng_normal(&s->rng);
            }
        }
        s->last_time = time[j];
        s->epochs += 1;
        double e[6];
        for (int i = 0; i < 6; i++)
            e[i] = cf[(i < 3 ? SARINS_GNSS_POS_WHITE_E : SARINS_GNSS_VEL_WHITE_E) + i % 3] * sarins_rng_normal(&s->rng)
                   + s->b[i];
        const double *row = truth + 9 * j;
        double *o = out + SARINS_GNSS_OUT * j;
        double pos[3], vel[3], rm, rn;
        antenna(cf + SARINS_GNSS_LEVER_X, row, omega_ib + 3 * j, pos, vel);
        sarins_earth_radii(pos[0], &rm, &rn);
        o[1] = pos[0] + e[1] / (rm + pos[2]);
        o[2] = pos[1] + e[0] / ((rn + pos[2]) * sm_cos(pos[0]));
        o[3] = pos[2] + e[2];
        for (int i = 0; i < 3; i++)
            o[4 + i] = vel[i] + e[3 + i];
        int valid = 1;
        for (int64_t w = 0; w < n_out; w++)
            if (time[j] >= outages[2 * w] && time[j] < outages[2 * w + 1])
                valid = 0;
        o[0] = valid ? 1.0 : 0.0;
    }
    return 0;
}

int64_t sarins_gnss_size(void) { return (int64_t)sizeof(sarins_gnss); }

int sarins_gnss_check(const sarins_gnss *s, char *msg, size_t size)
{
    if (!config_ok(s->config, msg, size))
        return 1;
    if (!sarins_rng_valid(&s->rng)) {
        sarins_say(msg, size, "the GNSS random stream is not one the receiver makes");
        return 1;
    }
    for (int i = 0; i < 6; i++)
        if (!isfinite(s->b[i])) {
            sarins_say(msg, size, "a GNSS correlated error is not finite");
            return 1;
        }
    if (!isfinite(s->last_time) || s->epochs < 0) {
        sarins_say(msg, size, "the GNSS epoch clock is out of range");
        return 1;
    }
    return 0;
}
