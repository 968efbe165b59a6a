#include "smath.h"

#include "stop_filter.h"

#include <stddef.h>

#include "earth.h"
#include "report.h"

enum { N = SARINS_STOP_STATES };

static const char *const NAMES[SARINS_STOP_N_SETTINGS] = {
    "arw", "vrw", "drift_rw", "bias_rw", "velocity_meas_std", "tilt0_std", "heading0_std", "velocity0_std",
    "drift0_std", "azimuth_drift0_std", "bias0_std", "position0_std"};

/* the unit constants of sarins_fmu/units.py, written as it writes them (the same roundings) */
#define DEG_TO_RAD (3.141592653589793 / 180.0)
#define DPH_TO_RPS (DEG_TO_RAD / 3600.0)
#define UG_TO_MPS2 (1e-6 * 9.80665)
#define ARCSEC_TO_RAD (DEG_TO_RAD / 3600.0)

void sarins_stop_settings_default(double *s)
{
    s[SARINS_STOP_ARW] = 0.0005 * DEG_TO_RAD / 60.0;
    s[SARINS_STOP_VRW] = 5.0 * UG_TO_MPS2;
    s[SARINS_STOP_DRIFT_RW] = 1e-7 * DPH_TO_RPS;
    s[SARINS_STOP_BIAS_RW] = 1e-3 * UG_TO_MPS2;
    s[SARINS_STOP_VELOCITY_MEAS_STD] = 1e-3;
    s[SARINS_STOP_TILT0_STD] = 30.0 * ARCSEC_TO_RAD;
    s[SARINS_STOP_HEADING0_STD] = 0.1 * DEG_TO_RAD;
    s[SARINS_STOP_VELOCITY0_STD] = 1.0;
    s[SARINS_STOP_DRIFT0_STD] = 0.01 * DPH_TO_RPS;
    s[SARINS_STOP_AZIMUTH_DRIFT0_STD] = 0.02 * DPH_TO_RPS;
    s[SARINS_STOP_BIAS0_STD] = 100.0 * UG_TO_MPS2;
    s[SARINS_STOP_POSITION0_STD] = 10.0;
}

int sarins_stop_check_settings(const double *settings, char *msg, size_t size)
{
    report r = sarins_report(msg, size);
    for (int i = 0; i < SARINS_STOP_N_SETTINGS; i++)
        if (!(isfinite(settings[i]) && settings[i] > 0.0)) {
            char text[40];
            sarins_format_number(text, sizeof text, settings[i]);
            return sarins_fail(&r, SARINS_STOP_BAD, "stop filter %s must be positive and finite, got %s", NAMES[i],
                               text);
        }
    return SARINS_STOP_OK;
}

int sarins_stop_check_lat_dt(double lat, double dt, char *msg, size_t size)
{
    report r = sarins_report(msg, size);
    char text[40];
    if (!(isfinite(lat) && sm_fabs(lat) <= SARINS_STOP_LAT_LIMIT)) {
        sarins_format_number(text, sizeof text, lat);
        return sarins_fail(&r, SARINS_STOP_BAD, "latitude must be finite and within +-89.9 deg, got %s rad", text);
    }
    if (!(isfinite(dt) && dt > 0.0)) {
        sarins_format_number(text, sizeof text, dt);
        return sarins_fail(&r, SARINS_STOP_BAD, "filter step must be positive, got %s", text);
    }
    return SARINS_STOP_OK;
}

/* q = (arw, arw, arw, vrw, vrw, drift_rw x 3, bias_rw x 2, 0)^2 */
static void process_noise(const double *s, double *q)
{
    const double noise[N] = {s[SARINS_STOP_ARW], s[SARINS_STOP_ARW], s[SARINS_STOP_ARW], s[SARINS_STOP_VRW],
                             s[SARINS_STOP_VRW], s[SARINS_STOP_DRIFT_RW], s[SARINS_STOP_DRIFT_RW],
                             s[SARINS_STOP_DRIFT_RW], s[SARINS_STOP_BIAS_RW], s[SARINS_STOP_BIAS_RW], 0.0};
    for (int i = 0; i < N; i++)
        q[i] = noise[i] * noise[i];
}

int sarins_stop_kf_init(sarins_stop_kf *kf, const double *settings, double lat, double dt, char *msg, size_t size)
{
    if (sarins_stop_check_settings(settings, msg, size) != SARINS_STOP_OK
        || sarins_stop_check_lat_dt(lat, dt, msg, size) != SARINS_STOP_OK)
        return SARINS_STOP_BAD;
    for (int i = 0; i < SARINS_STOP_N_SETTINGS; i++)
        kf->settings[i] = settings[i];
    kf->dt = dt;
    process_noise(settings, kf->q);
    kf->r_var = settings[SARINS_STOP_VELOCITY_MEAS_STD] * settings[SARINS_STOP_VELOCITY_MEAS_STD];
    return sarins_stop_kf_reset(kf, lat, msg, size);
}

int sarins_stop_kf_reset(sarins_stop_kf *kf, double lat, char *msg, size_t size)
{
    if (sarins_stop_check_lat_dt(lat, kf->dt, msg, size) != SARINS_STOP_OK)
        return SARINS_STOP_BAD;
    const double *s = kf->settings;
    /* P0 = diag(std^2), the north position error as a latitude error (rad) */
    const double std[N] = {s[SARINS_STOP_TILT0_STD], s[SARINS_STOP_TILT0_STD], s[SARINS_STOP_HEADING0_STD],
                           s[SARINS_STOP_VELOCITY0_STD], s[SARINS_STOP_VELOCITY0_STD], s[SARINS_STOP_DRIFT0_STD],
                           s[SARINS_STOP_DRIFT0_STD], s[SARINS_STOP_AZIMUTH_DRIFT0_STD], s[SARINS_STOP_BIAS0_STD],
                           s[SARINS_STOP_BIAS0_STD], s[SARINS_STOP_POSITION0_STD] / SARINS_EARTH_A};
    kf->lat = lat;
    for (int i = 0; i < N; i++) {
        kf->x[i] = 0.0;
        for (int j = 0; j < N; j++)
            kf->p[N * i + j] = (i == j) ? std[i] * std[i] : 0.0;
    }
    kf->n = 0;
    kf->correction_sum = 0.0;
    kf->temperature_sum = 0.0;
    return SARINS_STOP_OK;
}

int sarins_stop_kf_steps(sarins_stop_kf *kf, int64_t k, const double *velocity_en, const double *attitude,
                         const double *correction, const double *temperature, double *out, char *msg, size_t size)
{
    report r = sarins_report(msg, size);
    if (k < 0)
        return sarins_fail(&r, SARINS_STOP_BAD, "a negative number of rows");
    for (int64_t s = 0; s < k; s++)
        if (!(isfinite(velocity_en[2 * s]) && isfinite(velocity_en[2 * s + 1]) && isfinite(attitude[3 * s])
              && isfinite(attitude[3 * s + 1]) && isfinite(attitude[3 * s + 2]) && isfinite(correction[s])))
            return sarins_fail(&r, SARINS_STOP_BAD, "INS outputs contain NaN or infinity");
    if (out != NULL) {
        sarins_stop_filter_steps(k, kf->x, kf->p, velocity_en, attitude, kf->lat, kf->dt, kf->q, kf->r_var, out);
    } else {
        double row[2];
        for (int64_t s = 0; s < k; s++)
            sarins_stop_filter_steps(1, kf->x, kf->p, velocity_en + 2 * s, attitude + 3 * s, kf->lat, kf->dt,
                                     kf->q, kf->r_var, row);
    }
    /* running sums added row by row: a stop fed in blocks or one row at a time gives the same bits */
    for (int64_t s = 0; s < k; s++) {
        kf->correction_sum += correction[s];
        kf->temperature_sum += temperature[s];
    }
    kf->n += k;
    return SARINS_STOP_OK;
}

double sarins_stop_kf_elapsed(const sarins_stop_kf *kf) { return (double)kf->n * kf->dt; }

double sarins_stop_kf_residual(const sarins_stop_kf *kf) { return kf->x[SARINS_STOP_EPS_Z]; }

double sarins_stop_kf_drift_std(const sarins_stop_kf *kf)
{
    return sm_sqrt(kf->p[N * SARINS_STOP_EPS_Z + SARINS_STOP_EPS_Z]);
}

double sarins_stop_kf_drift_estimate(const sarins_stop_kf *kf)
{
    double mean_correction = kf->n ? kf->correction_sum / (double)kf->n : 0.0;
    return mean_correction + kf->x[SARINS_STOP_EPS_Z];
}

double sarins_stop_kf_mean_temperature(const sarins_stop_kf *kf)
{
    return kf->n ? kf->temperature_sum / (double)kf->n : NAN;
}

int sarins_stop_kf_check(const sarins_stop_kf *kf, char *msg, size_t size)
{
    report r = sarins_report(msg, size);
    double q[N];
    if (sarins_stop_check_settings(kf->settings, msg, size) != SARINS_STOP_OK
        || sarins_stop_check_lat_dt(kf->lat, kf->dt, msg, size) != SARINS_STOP_OK)
        return SARINS_STOP_BAD;
    process_noise(kf->settings, q);
    for (int i = 0; i < N; i++)
        if (kf->q[i] != q[i])
            return sarins_fail(&r, SARINS_STOP_BAD, "stop filter process noise differs from its settings");
    if (kf->r_var != kf->settings[SARINS_STOP_VELOCITY_MEAS_STD] * kf->settings[SARINS_STOP_VELOCITY_MEAS_STD])
        return sarins_fail(&r, SARINS_STOP_BAD, "stop filter measurement noise differs from its settings");
    for (int i = 0; i < N; i++)
        if (!isfinite(kf->x[i]))
            return sarins_fail(&r, SARINS_STOP_BAD, "stop filter state not finite");
    for (int i = 0; i < N * N; i++)
        if (!isfinite(kf->p[i]))
            return sarins_fail(&r, SARINS_STOP_BAD, "stop filter covariance not finite");
    for (int i = 0; i < N; i++)
        if (!(kf->p[N * i + i] >= 0.0))
            return sarins_fail(&r, SARINS_STOP_BAD, "stop filter covariance diagonal negative");
    if (kf->n < 0)
        return sarins_fail(&r, SARINS_STOP_BAD, "stop filter row count negative");
    if (!isfinite(kf->correction_sum) || isinf(kf->temperature_sum))
        return sarins_fail(&r, SARINS_STOP_BAD, "stop filter sums not finite");
    return SARINS_STOP_OK;
}

int64_t sarins_stop_kf_layout(int64_t *offsets)
{
    offsets[0] = (int64_t)offsetof(sarins_stop_kf, settings);
    offsets[1] = (int64_t)offsetof(sarins_stop_kf, lat);
    offsets[2] = (int64_t)offsetof(sarins_stop_kf, dt);
    offsets[3] = (int64_t)offsetof(sarins_stop_kf, x);
    offsets[4] = (int64_t)offsetof(sarins_stop_kf, p);
    offsets[5] = (int64_t)offsetof(sarins_stop_kf, n);
    offsets[6] = (int64_t)offsetof(sarins_stop_kf, correction_sum);
    offsets[7] = (int64_t)offsetof(sarins_stop_kf, temperature_sum);
    return (int64_t)sizeof(sarins_stop_kf);
}
