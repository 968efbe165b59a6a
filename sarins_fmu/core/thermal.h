/* Lumped thermal model of the IMU (sarins_fmu/thermal.py).
 *
 * Each sensor j (gyro x, y, z, accelerometer x, y, z) is a first-order
 * lumped body heated by the electronics and coupled to the ambient:
 *     dT_j/dt = (T_amb(t) + dT_self_j - T_j) / tau_j
 * with the ambient linear over each step, integrated exactly.  The sensing
 * die lags the reported temperature through a second first-order stage
 *     dT_die_j/dt = (T_j - T_die_j) / tau_die_j.
 * Temperatures in degC, times in s.  Arrays are row-major float64:
 * (K, S) means K rows (steps) of S sensors.
 */
#ifndef SARINS_THERMAL_H
#define SARINS_THERMAL_H

#include <stdint.h>

#define SARINS_FIRST_ORDER_SERIES 1.4901161193847656e-08 /* 2^-26: dt / tau below it takes the series */

/* The exact end value of a first-order lag dy/dt = (u(t) - y) / tau over a step of length dt >= 0 (s) with
 * the input linear from u0 at slope (unit/s), decay = exp(-dt / tau) given:
 *     y <- decay y + (u0 - slope tau)(1 - decay) + slope dt.
 * That form's rounding error is about eps |slope| tau (1 - decay carries a relative error eps / w, w = dt / tau,
 * times slope tau): at most 2^-26 |slope dt| while w >= 2^-26 (1.5e-8 of the input's change over the step), but
 * unbounded beyond (at tau = 1e300 s a 480 degC ambient step moved the sensor by 480 degC).  For w < 2^-26 the
 * value comes from its series, y + (u0 - y)(w - w^2 / 2) + slope dt w (1/2 - w / 6) (the terms left out are
 * below eps); the form above is kept elsewhere so that every result before this branch is the same bits. */
static inline double sarins_first_order_step(double y, double u0, double slope, double dt, double tau, double decay)
{
    double w = dt / tau;
    if (w < SARINS_FIRST_ORDER_SERIES)
        return y + (u0 - y) * (w - 0.5 * w * w) + slope * dt * w * (0.5 - w / 6.0);
    return decay * y + (u0 - slope * tau) * (1.0 - decay) + slope * dt;
}

/* One exact step of length dt >= 0 (s) from temperature x (degC), ambient
 * linear from amb0 to amb1 (degC), self-heating heat (degC), time constant
 * tau (s); returns the temperature at the step end (degC). */
double sarins_thermal_exact_step(double x, double amb0, double amb1, double dt, double heat, double tau);

/* Exact steps of lengths h[K] (s) with the ambient amb[K + 1] (degC) at the
 * step ends (amb[0] at the start), from temp0[S]; out (K, S) receives the
 * temperatures at the step ends. */
void sarins_thermal_exact_steps(int64_t n_steps, const double *h, const double *amb, int64_t n_sensors,
                                const double *heat, const double *tau, const double *temp0, double *out);

/* Exact steps over K intervals of the grid t0 + k h (s), from interval k0 on:
 * interval ends t0 + (k0 + k + 1) h; ambient amb0 at the start and
 * amb_end[K] at the ends (degC).  temperature[S] is advanced in place; out
 * (K, S) receives the temperatures at the ends. */
void sarins_thermal_steps(double t0, double h, double k0, double amb0, int64_t n_steps, const double *amb_end,
                          int64_t n_sensors, const double *heat, const double *tau, double *temperature,
                          double *out);

/* Die temperatures at the ends of K output intervals of length h (s):
 * reported0[S] at the start of the first interval, reported (K, S) at the
 * ends (taken linear over each interval), tau[S] die time constants (s; 0
 * passes the reported temperature through); die[S] holds the die
 * temperatures at the start and is advanced in place; out (K, S). */
void sarins_die_temperatures(int64_t n_steps, int64_t n_sensors, const double *reported0, const double *reported,
                             double h, const double *tau, double *die, double *out);

#endif
