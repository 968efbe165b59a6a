#include "smath.h"
#include "report.h"
#include "odo.h"
#include "rotations.h"


static int settings_ok(const double *config, char *msg, size_t size)
{
    for (int i = 0; i < SARINS_ODO_CONFIG; i++)
        if (!isfinite(config[i])) {
            sarins_say(msg, size, "an odometer setting is not finite");
            return 0;
        }
    if (config[SARINS_ODO_NOISE_STD] < 0.0 || config[SARINS_ODO_RESOLUTION] < 0.0) {
        sarins_say(msg, size, "the odometer noise std and resolution must not be negative");
        return 0;
    }
    if (sm_fabs(config[SARINS_ODO_SCALE_FACTOR]) >= 0.5) {
        sarins_say(msg, size, "the odometer scale-factor error must be within +-0.5");
        return 0;
    }
    return 1;
}

int sarins_odo_init(sarins_odo *s, const double *config, uint64_t seed, char *msg, size_t size)
{
    if (!settings_ok(config, msg, size))
        return 1;
    for (int i = 0; i < SARINS_ODO_CONFIG; i++)
        s->config[i] = config[i];
    sarins_rng_stream(&s->rng, seed, 31);
    return 0;
}

int sarins_odo_speeds(sarins_odo *s, int64_t n, const double *speed, double *out)
{
    for (int64_t i = 0; i < n; i++)
        if (!isfinite(speed[i]))
            return 1;
    double sf = s->config[SARINS_ODO_SCALE_FACTOR], sigma = s->config[SARINS_ODO_NOISE_STD];
    double res = s->config[SARINS_ODO_RESOLUTION];
    for (int64_t i = 0; i < n; i++) {
        double x = (1.0 + sf) * speed[i] + sigma * sarins_rng_normal(&s->rng);
        out[i] = res > 0.0 ? res * sm_nearbyint(x / res) : x;
    }
    return 0;
}

int sarins_odo_check(const sarins_odo *s, char *msg, size_t size)
{
    if (!settings_ok(s->config, msg, size))
        return 1;
    if (!sarins_rng_valid(&s->rng)) {
        sarins_say(msg, size, "the odometer's random stream is not one the odometer makes");
        return 1;
    }
    return 0;
}

double sarins_odo_forward_speed(const double *v_n, const double *ypr)
{
    double m[9];
    sarins_euler_to_mat(ypr[0], ypr[1], ypr[2], m);
    /* s = (mat_bn v^n)_y: column y of mat_nb . v^n */
    double speed = m[1] * v_n[0];
    speed += m[4] * v_n[1];
    speed += m[7] * v_n[2];
    return speed;
}

void sarins_odo_forward_speed_n(int64_t n, const double *v_n, const double *ypr, double *out)
{
    for (int64_t i = 0; i < n; i++)
        out[i] = sarins_odo_forward_speed(v_n + 3 * i, ypr + 3 * i);
}

int64_t sarins_odo_size(void) { return (int64_t)sizeof(sarins_odo); }
