#include "smath.h"
#include "report.h"
#include "aid_noise.h"

static int stds_ok(double zupt_std, double nhc_std, char *msg, size_t size)
{
    if (!(isfinite(zupt_std) && zupt_std >= 0.0 && isfinite(nhc_std) && nhc_std >= 0.0)) {
        sarins_say(msg, size, "the ZUPT and NHC jitter stds must be finite and >= 0");
        return 0;
    }
    return 1;
}

int sarins_aid_noise_init(sarins_aid_noise *s, double zupt_std, double nhc_std, uint64_t seed, char *msg,
                          size_t size)
{
    if (!stds_ok(zupt_std, nhc_std, msg, size))
        return 1;
    s->zupt_std = zupt_std;
    s->nhc_std = nhc_std;
    s->steps = 0;
    sarins_rng_stream(&s->rng, seed, SARINS_AID_NOISE_STREAM);
    return 0;
}

void sarins_aid_noise_step(sarins_aid_noise *s, int zupt, int nhc, double *out)
{
    double n[SARINS_AID_NOISE_DRAWS];
    for (int i = 0; i < SARINS_AID_NOISE_DRAWS; i++)
        n[i] = sarins_rng_normal(&s->rng);
    const double a = (double)zupt * s->zupt_std, b = (double)nhc * s->nhc_std;
    for (int i = 0; i < 3; i++)
        out[i] = a * n[i];
    out[3] = b * n[3];
    out[4] = b * n[4];
    s->steps += 1;
}

int sarins_aid_noise_run(double zupt_std, double nhc_std, uint64_t seed, int64_t n, const int32_t *zupt,
                         const int32_t *nhc, double *out)
{
    char msg[8];
    sarins_aid_noise s;
    for (int64_t k = 0; k < n; k++)
        if ((zupt[k] != 0 && zupt[k] != 1) || (nhc[k] != 0 && nhc[k] != 1))
            return 1;
    if (sarins_aid_noise_init(&s, zupt_std, nhc_std, seed, msg, sizeof msg))
        return 1;
    for (int64_t k = 0; k < n; k++)
        sarins_aid_noise_step(&s, zupt[k], nhc[k], out + SARINS_AID_NOISE_DRAWS * k);
    return 0;
}

int sarins_aid_noise_check(const sarins_aid_noise *s, char *msg, size_t size)
{
    if (!stds_ok(s->zupt_std, s->nhc_std, msg, size))
        return 1;
    if (!sarins_rng_valid(&s->rng)) {
        sarins_say(msg, size, "aiding jitter's random stream is not one the jitter makes");
        return 1;
    }
    if (s->steps < 0) {
        sarins_say(msg, size, "aiding jitter's step count is negative");
        return 1;
    }
    return 0;
}

static double speed(const double *v)
{
    double sum = v[0] * v[0];
    sum += v[1] * v[1];
    sum += v[2] * v[2];
    return sm_sqrt(sum);
}

int sarins_aid_still(const double *v0, const double *v1)
{
    return speed(v0) < SARINS_AID_STILL_SPEED && speed(v1) < SARINS_AID_STILL_SPEED;
}

int sarins_aid_moving(const double *v)
{
    return !(speed(v) < SARINS_AID_STILL_SPEED);
}

void sarins_aid_still_n(int64_t n, const double *v, int32_t *out)
{
    for (int64_t k = 0; k < n; k++)
        out[k] = sarins_aid_still(v + 3 * k, v + 3 * (k + 1));
}
