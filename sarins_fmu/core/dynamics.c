/* Sensor dynamics with memory at the output rate: see dynamics.h. */

#include "smath.h"

#include "dynamics.h"

enum { P_TAU_F, P_HYST, P_WIDTH, P_TAU_R, P_HYST_TC, P_ARM };
enum { S_FILTER, S_PLAY, S_OMEGA, S_STARTED };

int sarins_dynamics_active(const double *par) {
    for (int j = 0; j < 6; j++) {
        if (par[6 * P_TAU_F + j] != 0.0 || par[6 * P_HYST + j] != 0.0) return 1;
        for (int a = 0; a < 3; a++) {
            if (par[6 * (P_ARM + a) + j] != 0.0) return 1;
        }
    }
    return 0;
}

/* e_j . (alpha x r + omega x (omega x r)) for accelerometer j at r */
static double size_effect(int j, const double *alpha, const double *omega, const double *r) {
    double wr[3] = {omega[1] * r[2] - omega[2] * r[1], omega[2] * r[0] - omega[0] * r[2],
                    omega[0] * r[1] - omega[1] * r[0]};
    double ar[3] = {alpha[1] * r[2] - alpha[2] * r[1], alpha[2] * r[0] - alpha[0] * r[2],
                    alpha[0] * r[1] - alpha[1] * r[0]};
    double cen[3] = {omega[1] * wr[2] - omega[2] * wr[1], omega[2] * wr[0] - omega[0] * wr[2],
                     omega[0] * wr[1] - omega[1] * wr[0]};
    return ar[j] + cen[j];
}

void sarins_dynamics_apply(int64_t n_steps, double h, const double *temps, const double *par, double *state,
                           double t_ref, double *dtheta, double *dv) {
    double *filt = state + 6 * S_FILTER, *play = state + 6 * S_PLAY, *prev = state + 6 * S_OMEGA;
    double *started = state + 6 * S_STARTED;
    double a_f[6], decay_r[6];
    for (int j = 0; j < 6; j++) {
        double tau_f = par[6 * P_TAU_F + j], tau_r = par[6 * P_TAU_R + j];
        a_f[j] = h / (h + tau_f); /* low-frequency group delay (1 - a) h / a = tau_f exactly */
        decay_r[j] = tau_r > 0.0 ? sm_exp(-h / tau_r) : 1.0;
    }
    for (int64_t k = 0; k < n_steps; k++) {
        double x[6], omega[3], alpha[3];
        for (int a = 0; a < 3; a++) {
            x[a] = dtheta[3 * k + a] / h;
            x[3 + a] = dv[3 * k + a] / h;
            omega[a] = x[a];
        }
        int first = started[0] == 0.0;
        for (int a = 0; a < 3; a++) alpha[a] = first ? 0.0 : (omega[a] - prev[a]) / h;
        for (int j = 0; j < 3; j++) {
            const double r[3] = {par[6 * P_ARM + 3 + j], par[6 * (P_ARM + 1) + 3 + j], par[6 * (P_ARM + 2) + 3 + j]};
            x[3 + j] += size_effect(j, alpha, omega, r);
        }
        for (int j = 0; j < 6; j++) {
            double c = par[6 * P_HYST + j], w = par[6 * P_WIDTH + j];
            if (c != 0.0 && w > 0.0) {
                if (first) play[j] = x[j];
                play[j] = x[j] + (play[j] - x[j]) * decay_r[j];
                play[j] = sm_fmax(x[j] - w, sm_fmin(x[j] + w, play[j]));
                double gain = 1.0 + par[6 * P_HYST_TC + j] * (temps[6 * k + j] - t_ref);
                x[j] += c * gain * (x[j] - play[j]) / w;
            }
            if (par[6 * P_TAU_F + j] > 0.0) {
                if (first) filt[j] = x[j];
                filt[j] += a_f[j] * (x[j] - filt[j]);
                x[j] = filt[j];
            }
        }
        for (int a = 0; a < 3; a++) {
            prev[a] = omega[a];
            dtheta[3 * k + a] = x[a] * h;
            dv[3 * k + a] = x[3 + a] * h;
        }
        for (int j = 0; j < 6; j++) started[j] = 1.0;
    }
}
