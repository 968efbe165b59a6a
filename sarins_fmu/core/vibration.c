#include "smath.h"
#include "report.h"
#include "aid_noise.h"
#include "vibration.h"

static int settings_ok(double accel_rms, double rate_rms, double step, char *msg, size_t size)
{
    if (!(isfinite(accel_rms) && accel_rms >= 0.0 && isfinite(rate_rms) && rate_rms >= 0.0)) {
        sarins_say(msg, size, "the vibration's rms values must be finite and >= 0");
        return 0;
    }
    if (!(isfinite(step) && step > 0.0)) {
        sarins_say(msg, size, "the vibration's step is not positive and finite");
        return 0;
    }
    return 1;
}

/* the jitter of one point: six draws, scaled, times the moving flag */
static void draw(sarins_vibration *s, int moving, double *u, double *theta)
{
    double n[SARINS_VIBRATION_DRAWS];
    for (int i = 0; i < SARINS_VIBRATION_DRAWS; i++)
        n[i] = sarins_rng_normal(&s->rng);
    const double m = (double)moving, r2 = sm_sqrt(2.0);
    const double cu = s->accel_rms * s->step / r2, ct = s->rate_rms * s->step / r2;
    for (int i = 0; i < 3; i++) {
        u[i] = (n[i] * cu) * m;
        theta[i] = (n[3 + i] * ct) * m;
    }
}

int sarins_vibration_init(sarins_vibration *s, double accel_rms, double rate_rms, double step, uint64_t seed,
                          int moving0, char *msg, size_t size)
{
    if (!settings_ok(accel_rms, rate_rms, step, msg, size))
        return 1;
    s->accel_rms = accel_rms;
    s->rate_rms = rate_rms;
    s->step = step;
    s->steps = 0;
    sarins_rng_stream(&s->rng, seed, SARINS_VIBRATION_STREAM);
    draw(s, moving0 != 0, s->u, s->theta);
    return 0;
}

void sarins_vibration_step(sarins_vibration *s, int moving, double *dtheta, double *dv)
{
    double u[3], theta[3];
    draw(s, moving != 0, u, theta);
    for (int i = 0; i < 3; i++) {
        dtheta[i] = theta[i] - s->theta[i];
        dv[i] = u[i] - s->u[i];
        s->theta[i] = theta[i];
        s->u[i] = u[i];
    }
    s->steps += 1;
}

int sarins_vibration_run(double accel_rms, double rate_rms, double step, uint64_t seed, int64_t n, const double *v,
                         double *dtheta, double *dv)
{
    char msg[8];
    sarins_vibration s;
    if (n < 0)
        return 1;
    for (int64_t k = 0; k < 3 * (n + 1); k++)
        if (!isfinite(v[k]))
            return 1;
    if (sarins_vibration_init(&s, accel_rms, rate_rms, step, seed, sarins_aid_moving(v), msg, sizeof msg))
        return 1;
    for (int64_t k = 0; k < n; k++)
        sarins_vibration_step(&s, sarins_aid_moving(v + 3 * (k + 1)), dtheta + 3 * k, dv + 3 * k);
    return 0;
}

int sarins_vibration_check(const sarins_vibration *s, char *msg, size_t size)
{
    if (!settings_ok(s->accel_rms, s->rate_rms, s->step, msg, size))
        return 1;
    for (int i = 0; i < 3; i++)
        if (!isfinite(s->u[i]) || !isfinite(s->theta[i])) {
            sarins_say(msg, size, "the vibration's jitter is not finite");
            return 1;
        }
    if (!sarins_rng_valid(&s->rng)) {
        sarins_say(msg, size, "the vibration's random stream is not one the vibration makes");
        return 1;
    }
    if (s->steps < 0) {
        sarins_say(msg, size, "the vibration's step count is negative");
        return 1;
    }
    return 0;
}
