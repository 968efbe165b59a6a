/* Lumped thermal model: see thermal.h.  The evaluation order follows
 * sarins_fmu/thermal.py's former compiled loops term by term, so results
 * are the same bit for bit. */

#include "smath.h"

#include "thermal.h"

double sarins_thermal_exact_step(double x, double amb0, double amb1, double dt, double heat, double tau) {
    /* the input amb + dT, linear over the step at the ambient's slope */
    double slope = dt > 0 ? (amb1 - amb0) / dt : 0.0;
    return sarins_first_order_step(x, amb0 + heat, slope, dt, tau, sm_exp(-dt / tau));
}

void sarins_thermal_exact_steps(int64_t n_steps, const double *h, const double *amb, int64_t n_sensors,
                                const double *heat, const double *tau, const double *temp0, double *out) {
    for (int64_t j = 0; j < n_sensors; j++) {
        double x = temp0[j];
        for (int64_t k = 0; k < n_steps; k++) {
            x = sarins_thermal_exact_step(x, amb[k], amb[k + 1], h[k], heat[j], tau[j]);
            out[k * n_sensors + j] = x;
        }
    }
}

void sarins_thermal_steps(double t0, double h, double k0, double amb0, int64_t n_steps, const double *amb_end,
                          int64_t n_sensors, const double *heat, const double *tau, double *temperature,
                          double *out) {
    for (int64_t j = 0; j < n_sensors; j++) {
        double x = temperature[j];
        double a_prev = amb0;
        double t_prev = t0 + k0 * h;
        for (int64_t k = 0; k < n_steps; k++) {
            /* interval end t_k = t0 + (k0 + k + 1) h, the step length its difference to the previous end */
            double t_k = t0 + (k0 + (double)k + 1.0) * h;
            x = sarins_thermal_exact_step(x, a_prev, amb_end[k], t_k - t_prev, heat[j], tau[j]);
            out[k * n_sensors + j] = x;
            a_prev = amb_end[k];
            t_prev = t_k;
        }
        temperature[j] = x;
    }
}

void sarins_die_temperatures(int64_t n_steps, int64_t n_sensors, const double *reported0, const double *reported,
                             double h, const double *tau, double *die, double *out) {
    for (int64_t j = 0; j < n_sensors; j++) {
        double prev = reported0[j];
        for (int64_t k = 0; k < n_steps; k++) {
            double rep = reported[k * n_sensors + j];
            if (tau[j] > 0.0) {
                /* the input T_rep, linear over the interval */
                die[j] = sarins_first_order_step(die[j], prev, (rep - prev) / h, h, tau[j], sm_exp(-h / tau[j]));
            } else {
                die[j] = rep;
            }
            out[k * n_sensors + j] = die[j];
            prev = rep;
        }
    }
}
