/* Forgetting-factor recursive least squares of the azimuth gyro drift's quadratic temperature model
 * (seed 002 eqs 7-18; the Python face is sarins_fmu/identify/rls.py, ForgettingRLS).
 *
 * Model eps(T) = a T^2 + b T + c = h(T)' x, h(T) = [T^2, T, 1], x = [a, b, c]: temperatures in degC, the
 * drift in any unit (rad/s inside the library), a, b, c in that unit per degC^2, per degC and plain.  P is
 * the inverse of the weighted information (sum_i w_i h_i h_i')^-1, 3 x 3 row-major, symmetric.  Times in s.
 * An update at time t forgets the old information by lam = lambda^((t - t_prev) / m) (eq. 15; m = 0: by
 * lambda whatever the gap) and then (eqs 16-18)
 *     K = P h / (lam + h' P h);  x = x + K (z - h' x);  P = (P - K (P h)') / lam,  P symmetrized.
 *
 * Functions that can fail return SARINS_RLS_OK or SARINS_RLS_BAD with a one-line reason in msg (size
 * bytes; msg may be NULL) and leave their outputs unchanged.  libm: pow, sqrt.
 */
#ifndef SARINS_RLS_H
#define SARINS_RLS_H

#include <stddef.h>
#include <stdint.h>

#define SARINS_RLS_OK 0
#define SARINS_RLS_BAD 1
#define SARINS_RLS_PRIOR_NODES 11 /* calibration temperatures of a prior (prior_covariance) */

/* The whole RLS state (plain data: copying the bytes copies the state). */
typedef struct {
    double x[3];              /* [a, b, c] */
    double p[9];              /* inverse weighted information, symmetric */
    double time;              /* s, of the last update (or of the initial model) */
    double forgetting_factor; /* lambda in (0, 1], per time scale */
    double time_scale;        /* m, s (> 0); 0: forget by lambda at every update */
    int64_t n_updates;        /* updates since the initial model */
} sarins_rls;

/* eps(T) = (a T + b) T + c of coef = [a, b, c] at t (degC). */
double sarins_drift_model_value(const double *coef, double t);

/* lambda^(dt / m), or lambda when time_scale is 0 (dt >= 0, s). */
double sarins_rls_factor(double forgetting_factor, double dt, double time_scale);

/* One step of eqs 16-18 on x (3) and p (3 x 3) in place: regressor h (3), measurement z, forgetting lam. */
void sarins_rls_gain_step(double *x, double *p, const double *h, double z, double lam);

/* Refuses a covariance that is not finite, not symmetric (|p_ij - p_ji| > 1e-9 |p_ji|) or not positive
 * definite (a Cholesky pivot <= 0), with the reason. */
int sarins_rls_check_covariance(const double *p, char *msg, size_t size);

/* Checks the forgetting settings: lambda in (0, 1], time_scale > 0 and finite, or 0 (per update). */
int sarins_rls_check_settings(double forgetting_factor, double time_scale, char *msg, size_t size);

/* A state from parameters x (3, finite), covariance p (checked, then symmetrized), time (s, finite) and
 * the forgetting settings; n_updates = 0. */
int sarins_rls_init(sarins_rls *s, const double *x, const double *p, double time, double forgetting_factor,
                    double time_scale, char *msg, size_t size);

/* Adds the measurement (temperature degC, drift, time s) taken no earlier than s->time; refused (state
 * unchanged) if the result would not be finite or P's diagonal not positive (an overflow). */
int sarins_rls_update(sarins_rls *s, double temperature, double drift, double time, char *msg, size_t size);

/* P0 of an initial model worth `points` calibration points spread evenly over t_min .. t_max degC:
 * (sum_i w h_i h_i')^-1 with SARINS_RLS_PRIOR_NODES nodes t_i = t_min + i (t_max - t_min) / 10 (the last
 * t_max) of weight w = points / 11, symmetrized.  Needs points > 0, t_max > t_min, all finite, and an
 * invertible information matrix. */
int sarins_rls_prior_covariance(double points, double t_min, double t_max, double *p0, char *msg, size_t size);

/* The RLS model file: a binary model file (netfile.h, the core's one container reader) of kind
 * SARINS_NET_KIND_RLS, written by sarins_fmu.identify.rls.ForgettingRLS.export_binary, with exactly these
 * float64 arrays: parameters (3), covariance (3 x 3), and the scalars time (s), n_updates (a whole number
 * 0 .. 2^53), forgetting_factor and time_scale (s; 0: forget per update).  At most SARINS_RLS_FILE_MAX
 * bytes (the kind's budget, below the container's).  The state is checked like sarins_rls_init's
 * arguments. */
#define SARINS_RLS_FILE_MAX 4096

/* The state in the n bytes of an RLS model file. */
int sarins_rls_from_model(const unsigned char *buf, size_t n, sarins_rls *s, char *msg, size_t size);

/* The state in the RLS model file at path (read into a buffer of SARINS_RLS_FILE_MAX bytes on the stack: a
 * longer file is refused without reading it all; nothing is allocated). */
int sarins_rls_load_file(const char *path, sarins_rls *s, char *msg, size_t size);

/* Every field of a state within the invariants the functions above keep (finite values, an exactly
 * symmetric covariance with a positive diagonal, valid settings, n_updates >= 0): for a state that arrived
 * from outside (an FMU state). */
int sarins_rls_check(const sarins_rls *s, char *msg, size_t size);

/* sizeof(sarins_rls) and the byte offsets of x, p, time, forgetting_factor, time_scale, n_updates in
 * offsets[0..5] (for the Python binding). */
int64_t sarins_rls_layout(int64_t *offsets);

#endif
