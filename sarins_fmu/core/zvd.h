/* Zero-velocity / zero-angular-rate detector: a chi-square test of "standing still" over a sliding
 * window of IMU increments (body frame, SI).
 *
 * Sample k of step h (s): specific force f_k = dv_k / h (m/s^2), angular rate w_k = dtheta_k / h
 * (rad/s).  Window W_k = {k-N+1 .. k}, its means fbar, wbar.  Statistic
 *
 *     T_k = sum_{j in W_k} |f_j - fbar|^2 / sigma_f^2 + |w_j - wbar|^2 / sigma_w^2,
 *     sigma_f = vrw / sqrt(h),  sigma_w = arw / sqrt(h)
 *
 * (vrw m/s/sqrt(s), arw rad/sqrt(s): the IMU's white-noise densities; sigma_f, sigma_w the per-axis
 * std of one sample).  Standing still, the true specific force (gravity) and rate (the Earth's) and
 * the biases are constant over the window and the noise is white Gaussian, so each sum is a sample
 * variance: T_k ~ chi-square(6 (N - 1)) whatever gravity, Earth rate and the biases are.  The window
 * is declared stationary when T_k <= gamma; gamma = the (1 - alpha) quantile of chi-square(6 (N - 1))
 * (computed by the caller) makes alpha the probability that a stationary window is declared moving.
 * Motion is seen through the variance it adds (vibration, changing acceleration or rate); a motion
 * whose specific force and rate are constant over the window (a smooth straight cruise) passes the
 * test like a stop.
 *
 * The window lives in the struct (at most SARINS_ZVD_MAX_WINDOW samples): nothing is allocated.  Each
 * sample recomputes the window's means and squared deviations in two passes (O(N), no running sums
 * that drift over long runs).
 */
#ifndef SARINS_ZVD_H
#define SARINS_ZVD_H

#include <stddef.h>
#include <stdint.h>

#define SARINS_ZVD_MAX_WINDOW 4096 /* samples */
#define SARINS_ZVD_STR2(x) #x
#define SARINS_ZVD_STR(x) SARINS_ZVD_STR2(x)

enum { SARINS_ZVD_WINDOW, SARINS_ZVD_STEP, SARINS_ZVD_VRW, SARINS_ZVD_ARW, SARINS_ZVD_GAMMA, SARINS_ZVD_CONFIG };

typedef struct {
    int64_t window;              /* N, samples */
    double inv_var_f, inv_var_w; /* 1 / sigma_f^2 (s^4/m^2), 1 / sigma_w^2 (s^2/rad^2) */
    double step, gamma;          /* h (s), threshold */
    int64_t count;               /* samples pushed so far */
    double f[SARINS_ZVD_MAX_WINDOW][3], w[SARINS_ZVD_MAX_WINDOW][3]; /* ring buffers, m/s^2 and rad/s */
} sarins_zvd;

/* 0, or 1 with a reason in msg: config = [window N (2 .. SARINS_ZVD_MAX_WINDOW, whole), step h > 0 (s),
 * vrw > 0 (m/s/sqrt(s)), arw > 0 (rad/sqrt(s)), gamma > 0]. */
int sarins_zvd_init(sarins_zvd *s, const double *config, char *msg, size_t size);

/* One sample (dtheta rad, dv m/s over the step): *stat = T_k (or -1 while fewer than N samples were
 * pushed); returns 1 (stationary), 0 (moving or window not full) or -1 for a non-finite sample
 * (nothing pushed). */
int sarins_zvd_push(sarins_zvd *s, const double *dtheta, const double *dv, double *stat);

/* n samples, dtheta and dv (n, 3): stat (n) and flag (n) as sarins_zvd_push gives them (flag 1.0 or 0.0);
 * returns 0, or 1 at the first non-finite sample (the outputs before it written). */
int sarins_zvd_run(sarins_zvd *s, int64_t n, const double *dtheta, const double *dv, double *stat, double *flag);

int64_t sarins_zvd_size(void);

/* 0 when s is a state init and push make (window 2 .. SARINS_ZVD_MAX_WINDOW, positive finite step, inverse
 * variances and threshold, count >= 0, the window's samples finite), else 1 with a reason in msg. */
int sarins_zvd_check(const sarins_zvd *s, char *msg, size_t size);

#endif
