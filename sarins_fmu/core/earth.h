/* WGS-84 Earth model: radii of curvature, normal gravity, Earth rate.
 *
 * Angles rad, lengths m, rates rad/s, accelerations m/s^2.  Navigation
 * frame ENU.  References: NIMA TR8350.2 (WGS-84), Titterton & Weston (2004)
 * ch. 3, Savage, Strapdown Analytics (2000) ch. 5.
 *
 * The constants are the one definition of the project: the Python module
 * sarins_fmu.earth reads them from sarins_earth_constants().
 */
#ifndef SARINS_EARTH_H
#define SARINS_EARTH_H

#include <stdint.h>

#define SARINS_EARTH_A 6378137.0                 /* semi-major axis, m */
#define SARINS_EARTH_F (1.0 / 298.257223563)     /* flattening */
#define SARINS_EARTH_E2 (SARINS_EARTH_F * (2.0 - SARINS_EARTH_F)) /* first eccentricity squared */
#define SARINS_EARTH_B (SARINS_EARTH_A * (1.0 - SARINS_EARTH_F))  /* semi-minor axis, m */
#define SARINS_EARTH_RATE 7.2921151467e-5        /* Earth rotation rate, rad/s */
#define SARINS_EARTH_GM 3.986004418e14           /* gravitational constant x Earth mass, m^3/s^2 */
#define SARINS_EARTH_GAMMA_E 9.7803253359        /* normal gravity at the equator, m/s^2 */
#define SARINS_EARTH_GAMMA_P 9.8321849378        /* normal gravity at the poles, m/s^2 */
/* Somigliana's k = b gamma_p / (a gamma_e) - 1 */
#define SARINS_EARTH_K_SOMIGLIANA \
    (SARINS_EARTH_B * SARINS_EARTH_GAMMA_P / (SARINS_EARTH_A * SARINS_EARTH_GAMMA_E) - 1.0)
/* geodetic parameter m = w^2 a^2 b / GM of the normal field */
#define SARINS_EARTH_M \
    (SARINS_EARTH_RATE * SARINS_EARTH_RATE * (SARINS_EARTH_A * SARINS_EARTH_A) * SARINS_EARTH_B / SARINS_EARTH_GM)

#define SARINS_EARTH_N_CONSTANTS 10

/* out[10] = A, F, E2, B, RATE, GM, GAMMA_E, GAMMA_P, K_SOMIGLIANA, M (units as above). */
void sarins_earth_constants(double *out);

/* Meridian and prime-vertical radii at geodetic latitude lat (rad), m:
 * R_M = a (1 - e^2) / (1 - e^2 sin^2 L)^(3/2), R_N = a / sqrt(1 - e^2 sin^2 L). */
void sarins_earth_radii(double lat, double *r_meridian, double *r_prime_vertical);

/* Normal gravity magnitude (gravitation + centrifugal), m/s^2, at latitude
 * lat (rad) and height (m): Somigliana on the ellipsoid with the
 * second-order free-air correction (TR8350.2 eq. 4-3). */
double sarins_earth_gravity(double lat, double height);

/* The same two from sin_lat = sm_sin(lat) (bit for bit the values above; for a caller that has the
 * sine already, e.g. from sm_sincos). */
void sarins_earth_radii_sin(double sin_lat, double *r_meridian, double *r_prime_vertical);
double sarins_earth_gravity_sin(double sin_lat, double height);

/* Element-wise over n points (the Python binding's vectorised calls). */
void sarins_earth_radii_n(int64_t n, const double *lat, double *r_meridian, double *r_prime_vertical);
void sarins_earth_gravity_n(int64_t n, const double *lat, const double *height, double *gravity);

#endif
