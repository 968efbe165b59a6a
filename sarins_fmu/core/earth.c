#include "smath.h"

#include "earth.h"


void sarins_earth_constants(double *out)
{
    out[0] = SARINS_EARTH_A;
    out[1] = SARINS_EARTH_F;
    out[2] = SARINS_EARTH_E2;
    out[3] = SARINS_EARTH_B;
    out[4] = SARINS_EARTH_RATE;
    out[5] = SARINS_EARTH_GM;
    out[6] = SARINS_EARTH_GAMMA_E;
    out[7] = SARINS_EARTH_GAMMA_P;
    out[8] = SARINS_EARTH_K_SOMIGLIANA;
    out[9] = SARINS_EARTH_M;
}

void sarins_earth_radii(double lat, double *r_meridian, double *r_prime_vertical)
{
    sarins_earth_radii_sin(sm_sin(lat), r_meridian, r_prime_vertical);
}

void sarins_earth_radii_sin(double s, double *r_meridian, double *r_prime_vertical)
{
    double s2 = s * s;
    /* w = sqrt(1 - e^2 sin^2 L) */
    double w = sm_sqrt(1.0 - SARINS_EARTH_E2 * s2);
    /* R_M = a (1 - e^2) / w^3 ; R_N = a / w */
    *r_meridian = SARINS_EARTH_A * (1.0 - SARINS_EARTH_E2) / (w * (w * w));
    *r_prime_vertical = SARINS_EARTH_A / w;
}

double sarins_earth_gravity(double lat, double height)
{
    return sarins_earth_gravity_sin(sm_sin(lat), height);
}

double sarins_earth_gravity_sin(double s, double height)
{
    double s2 = s * s;
    /* g0 = gamma_e (1 + k sin^2 L) / sqrt(1 - e^2 sin^2 L) */
    double g0 = SARINS_EARTH_GAMMA_E * (1.0 + SARINS_EARTH_K_SOMIGLIANA * s2) / sm_sqrt(1.0 - SARINS_EARTH_E2 * s2);
    /* g = g0 [1 - 2/a (1 + f + m - 2 f sin^2 L) h + 3 h^2 / a^2] */
    return g0 * (1.0 - 2.0 / SARINS_EARTH_A * (1.0 + SARINS_EARTH_F + SARINS_EARTH_M - 2.0 * SARINS_EARTH_F * s2) * height
                 + 3.0 * (height * height) / (SARINS_EARTH_A * SARINS_EARTH_A));
}

void sarins_earth_radii_n(int64_t n, const double *lat, double *r_meridian, double *r_prime_vertical)
{
    for (int64_t k = 0; k < n; k++)
        sarins_earth_radii(lat[k], &r_meridian[k], &r_prime_vertical[k]);
}

void sarins_earth_gravity_n(int64_t n, const double *lat, const double *height, double *gravity)
{
    for (int64_t k = 0; k < n; k++)
        gravity[k] = sarins_earth_gravity(lat[k], height[k]);
}
