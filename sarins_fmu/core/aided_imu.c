#include "smath.h"
#include "report.h"
#include "aided_imu.h"

/* 1 when the settings and step hold, else 0 with msg. */
static int settings_ok(const double *config, double step, char *msg, size_t size)
{
    for (int i = 0; i < SARINS_AIDED_IMU_CONFIG; i++)
        if (!(isfinite(config[i]) && config[i] >= 0.0)) {
            sarins_say(msg, size, "an IMU noise setting is not a finite number >= 0");
            return 0;
        }
    if (!(isfinite(step) && step > 0.0)) {
        sarins_say(msg, size, "the IMU step is not positive and finite");
        return 0;
    }
    return 1;
}

int sarins_aided_imu_init(sarins_aided_imu *s, const double *config, double step, uint64_t seed, char *msg,
                          size_t size)
{
    if (!settings_ok(config, step, msg, size))
        return 1;
    for (int i = 0; i < SARINS_AIDED_IMU_CONFIG; i++)
        s->config[i] = config[i];
    s->step = step;
    s->sqrt_h = sm_sqrt(step);
    s->steps = 0;
    sarins_rng_stream(&s->rng, seed, SARINS_AIDED_IMU_STREAM);
    for (int i = 0; i < 6; i++) /* b_0 = bias_std n */
        s->bias[i] = config[i < 3 ? SARINS_AIDED_IMU_GYRO_BIAS_STD : SARINS_AIDED_IMU_ACCEL_BIAS_STD]
                     * sarins_rng_normal(&s->rng);
    return 0;
}

void sarins_aided_imu_step(sarins_aided_imu *s, const double *dtheta_true, const double *dv_true, double *dtheta,
                           double *dv, double *bias)
{
    const double h = s->step, sh = s->sqrt_h;
    const double arw = s->config[SARINS_AIDED_IMU_ARW], vrw = s->config[SARINS_AIDED_IMU_VRW];
    double white[6], b[6];
    for (int i = 0; i < 6; i++) {
        white[i] = sh * sarins_rng_normal(&s->rng);
        b[i] = s->bias[i];
    }
    for (int i = 0; i < 3; i++) {
        /* dtheta = dtheta_true + b_g h + arw sqrt(h) n;  dv = dv_true + b_a h + vrw sqrt(h) n */
        dtheta[i] = dtheta_true[i] + b[i] * h + arw * white[i];
        dv[i] = dv_true[i] + b[3 + i] * h + vrw * white[3 + i];
    }
    for (int i = 0; i < 6; i++) /* b_{k+1} = b_k + rw sqrt(h) n */
        s->bias[i] += s->config[i < 3 ? SARINS_AIDED_IMU_GYRO_RW : SARINS_AIDED_IMU_ACCEL_RW]
                      * (sh * sarins_rng_normal(&s->rng));
    if (bias != NULL)
        for (int i = 0; i < 6; i++)
            bias[i] = b[i];
    s->steps += 1;
}

int sarins_aided_imu_run(const double *config, double step, uint64_t seed, int64_t n, const double *dtheta_true,
                         const double *dv_true, double *dtheta, double *dv, double *bias)
{
    sarins_aided_imu s;
    if (n < 0 || sarins_aided_imu_init(&s, config, step, seed, NULL, 0))
        return 1;
    for (int64_t k = 0; k < n; k++)
        sarins_aided_imu_step(&s, dtheta_true + 3 * k, dv_true + 3 * k, dtheta + 3 * k, dv + 3 * k, bias + 6 * k);
    return 0;
}

int sarins_aided_imu_check(const sarins_aided_imu *s, char *msg, size_t size)
{
    if (!settings_ok(s->config, s->step, msg, size))
        return 1;
    if (!(s->sqrt_h == sm_sqrt(s->step))) {
        sarins_say(msg, size, "the IMU step's square root is not the step's");
        return 1;
    }
    for (int i = 0; i < 6; i++)
        if (!isfinite(s->bias[i])) {
            sarins_say(msg, size, "an IMU bias is not finite");
            return 1;
        }
    if (!sarins_rng_valid(&s->rng)) {
        sarins_say(msg, size, "the IMU random stream is not one the IMU makes");
        return 1;
    }
    if (s->steps < 0) {
        sarins_say(msg, size, "the IMU step count is negative");
        return 1;
    }
    return 0;
}
