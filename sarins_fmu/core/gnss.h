/* GNSS receiver model: position and velocity fixes with white and first-order Gauss-Markov errors
 * per axis, an antenna lever arm, outage windows; seeded.
 *
 * At each fix epoch t_j (the caller gives the truth there: rows lat, lon rad, h m, v E N U m/s,
 * yaw, pitch, roll rad, and omega_ib^b rad/s), for each ENU axis i of position (m) and velocity (m/s)
 *     e_i(t_j) = sigma_w,i w_j + b_i(t_j)
 *     b_i(t_j) = exp(-dt/tau) b_i(t_{j-1}) + sigma_gm,i sqrt(1 - exp(-2 dt/tau)) u_j   (dt = t_j - t_{j-1})
 * w, u independent N(0, 1); b starts from its stationary law N(0, sigma_gm^2), so
 *     Var e = sigma_w^2 + sigma_gm^2,   Cov(e(t), e(t + s)) = sigma_gm^2 exp(-|s| / tau)  (s != 0).
 * The antenna sits at the lever arm l (body, right-front-up, m):
 *     r_ant^n = r^n + mat_nb l,   v_ant^n = v^n + mat_nb (omega_nb^b x l),
 *     omega_nb^b = omega_ib^b - mat_bn (omega_ie^n + omega_en^n).
 * Position errors are added in metres (north / (R_M + h) to latitude, east / ((R_N + h) cos L) to
 * longitude).  Inside an outage window [start, end) no fix is given (valid = 0); the error
 * processes keep running.  Latency is not applied here: a fix valid at t_j reaches the user at
 * t_j + latency (the caller's schedule, sarins_fmu.gnss).
 */
#ifndef SARINS_GNSS_H
#define SARINS_GNSS_H

#include <stddef.h>
#include <stdint.h>

#include "rng.h"

/* settings (SI): lever arm (3, m); position white std E N U (m); position GM std E N U (m); position GM
 * correlation time (s); velocity white std E N U (m/s); velocity GM std E N U (m/s); velocity GM
 * correlation time (s) */
enum {
    SARINS_GNSS_LEVER_X, SARINS_GNSS_LEVER_Y, SARINS_GNSS_LEVER_Z,
    SARINS_GNSS_POS_WHITE_E, SARINS_GNSS_POS_WHITE_N, SARINS_GNSS_POS_WHITE_U,
    SARINS_GNSS_POS_GM_E, SARINS_GNSS_POS_GM_N, SARINS_GNSS_POS_GM_U, SARINS_GNSS_POS_TAU,
    SARINS_GNSS_VEL_WHITE_E, SARINS_GNSS_VEL_WHITE_N, SARINS_GNSS_VEL_WHITE_U,
    SARINS_GNSS_VEL_GM_E, SARINS_GNSS_VEL_GM_N, SARINS_GNSS_VEL_GM_U, SARINS_GNSS_VEL_TAU,
    SARINS_GNSS_CONFIG
};
#define SARINS_GNSS_OUT 7 /* fix row: valid (1/0), lat, lon (rad), h (m), v E N U (m/s) */

typedef struct {
    double config[SARINS_GNSS_CONFIG];
    SarinsRng rng;
    double b[6];      /* GM states: position E N U (m), velocity E N U (m/s) */
    double last_time; /* time of the last epoch, s */
    int64_t epochs;   /* epochs generated */
} sarins_gnss;

/* Initialise from config with seed; 0, or 1 with a reason in msg for a negative or non-finite
 * standard deviation or lever arm, or a correlation time not positive. */
int sarins_gnss_init(sarins_gnss *s, const double *config, uint64_t seed, char *msg, size_t size);

/* n epochs at increasing times time (n), truth (n, 9) and omega_ib (n, 3) there, n_out outage windows
 * outages (n_out, 2) [start, end) s; writes out (n, 7).  Returns 0, or 1 (nothing changed) for
 * times not increasing after the last epoch or a non-finite input. */
int sarins_gnss_fixes(sarins_gnss *s, int64_t n, const double *time, const double *truth, const double *omega_ib,
                      int64_t n_out, const double *outages, double *out);

/* 0 when s is a state sarins_gnss_init and sarins_gnss_fixes can make (settings as init checks them, an odd
 * random-stream increment, finite correlated errors and epoch time, epochs >= 0), else 1 with a reason in msg
 * (for a state a host hands back: FMU state). */
int sarins_gnss_check(const sarins_gnss *s, char *msg, size_t size);

/* sizeof(sarins_gnss), for a binding that holds the struct in its own buffer */
int64_t sarins_gnss_size(void);

#endif
