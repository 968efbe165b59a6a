/* Time-correlated sensor errors: see correlated.h.  The evaluation order of
 * every expression follows the former compiled loop of
 * sarins_fmu/imu_correlated.py; the loop runs interval by interval (each
 * sensor's chain is independent of the others), so that the driving noise
 * is drawn in interval order whatever the batch length. */
#include "smath.h"

#include <stddef.h>

#include "correlated.h"

/* Python's max(a, b) and min(a, b): the first argument unless the second compares greater (smaller) */
static double py_max(double a, double b) { return b > a ? b : a; }
static double py_min(double a, double b) { return b < a ? b : a; }

void sarins_correlated_terms(int64_t n_steps, const double *die0, const double *die, double h,
                             const double *corr_par, double *corr_state, int64_t n_flicker, const double *phi,
                             const double *q, double *x_flicker, SarinsRng *flicker_rng, SarinsRng *rrw_rng,
                             double *g_bias, double *g_sf, double *a_bias, double *a_sf) {
    const double *c_grad = corr_par + 6, *s_grad = corr_par + 12, *c_hyst = corr_par + 18;
    const double *w_hyst = corr_par + 24, *rrw = corr_par + 30, *turn_on = corr_par + 36;
    double *play = corr_state + 6, *x_rrw = corr_state + 12;
    double sqrt_h = sm_sqrt(h);
    double prev[6];
    for (int64_t j = 0; j < 6; j++) prev[j] = die0[j];
    for (int64_t k = 0; k < n_steps; k++) {
        for (int64_t j = 0; j < 6; j++) {
            double *bias_out = j < 3 ? g_bias : a_bias;
            double *sf_out = j < 3 ? g_sf : a_sf;
            int64_t col = j % 3;
            double now = die[k * 6 + j];
            double mid = 0.5 * (prev[j] + now);
            double rate = (now - prev[j]) / h;
            /* play operator P_k = max(T_k - w, min(T_k + w, P_{k-1})) */
            play[j] = py_max(mid - w_hyst[j], py_min(mid + w_hyst[j], play[j]));
            double flick = 0.0;
            for (int64_t i = 0; i < n_flicker; i++) {
                double w = flicker_rng != NULL ? sarins_rng_normal(flicker_rng) : 0.0;
                /* exact Gauss-Markov step x <- phi x + q sqrt(1 - phi^2) w */
                x_flicker[i * 6 + j] = phi[i] * x_flicker[i * 6 + j] + q[i * 6 + j] * sm_sqrt(1.0 - phi[i] * phi[i]) * w;
                flick += x_flicker[i * 6 + j];
            }
            /* rate random walk x <- x + K sqrt(h) w */
            x_rrw[j] += rrw[j] * sqrt_h * (rrw_rng != NULL ? sarins_rng_normal(rrw_rng) : 0.0);
            double bias = c_grad[j] * rate + c_hyst[j] * (mid - play[j]) / w_hyst[j] + flick + x_rrw[j] + turn_on[j];
            bias_out[k * 3 + col] += bias;
            sf_out[k * 3 + col] += s_grad[j] * rate;
            prev[j] = now;
        }
    }
}
