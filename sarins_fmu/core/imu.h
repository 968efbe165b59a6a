/* The IMU: 200 Hz minor loop, interval error terms, state advance and the
 * IMUThermal FMU's step (sarins_fmu/imu.py, sarins_fmu/imu_step.py).
 *
 * Frames: t is the turntable base frame (a static base: level, yawed in the
 * ENU navigation frame; a moving base: the local-level ENU frame at the
 * vehicle), b the body (sensor) frame carried by A gimbals; gimbal j turns
 * by theta_j about axes[j] (a unit vector in its parent frame, outer first).
 * Units: rad, rad/s, rad/s^2, m/s, m/s^2, s, degC.  Arrays are row-major
 * float64; (K, 3) means one row per output interval.
 *
 * Minor loop of one output interval k of length h, split into n_sub minor
 * steps dt = h / n_sub:
 *   1. true motion: gimbal angle quadratic and rate linear in time,
 *        omega_ib_b = mat_bt omega_it_t + omega_tb_b,   f_b = mat_bt f_t;
 *   2. trapezoid increments over each minor step (exact for the gimbal
 *      rates, linear in time);
 *   3. deterministic sensor errors on the minor increments,
 *        x_meas = (I + diag(sf) + M) x + b dt + q x|x| / dt  (+ G f dt and
 *        the low-rate nonlinearity k x exp(-(x / (w dt))^2) for the gyros);
 *   4. two-sample coning and sculling (Savage, Strapdown Analytics 2000,
 *      sec. 7.1.1.1 and eq. 7.2.2.2-22, minor-step form), the rotations
 *      composed in a quaternion; the outputs are the interval's rotation
 *      vector dtheta (rad) and velocity increment dv (m/s), resolved in the
 *      body frame at the interval start.
 *
 * The IMU's state (sarins_fmu/imu_step.py docstring) reaches C as an array
 * table: int64 rows (address, rows, columns), one per float64 array, rows 0
 * to 18 in the order SARINS_IMU_CONSTS .. SARINS_IMU_DYN_STATE.
 */
#ifndef SARINS_IMU_H
#define SARINS_IMU_H

#include <stdint.h>

enum {
    SARINS_IMU_CONSTS, SARINS_IMU_CLOCK, SARINS_IMU_SENSOR_PAR, SARINS_IMU_STATE, SARINS_IMU_COEF,
    SARINS_IMU_TRIAD, SARINS_IMU_MATS, SARINS_IMU_AXES, SARINS_IMU_BASE, SARINS_IMU_GM_BLOCK,
    SARINS_IMU_WHITE_BLOCK, SARINS_IMU_CORR_PAR, SARINS_IMU_CORR_STATE, SARINS_IMU_PHI, SARINS_IMU_Q,
    SARINS_IMU_X_FLICKER, SARINS_IMU_CORR_BLOCK, SARINS_IMU_DYN_PAR, SARINS_IMU_DYN_STATE, SARINS_IMU_N_ARRAYS
};

/* return codes of the table functions */
#define SARINS_IMU_OK 0
#define SARINS_IMU_BAD_TABLE 1  /* a missing row or an array of the wrong shape */
#define SARINS_IMU_NO_ROWS 2    /* the random blocks hold fewer unused rows than intervals asked for */

#define SARINS_IMU_MAX_AXES 8   /* gimbals the one-interval step accepts */

/* Reference temperature of the linear/quadratic coefficients, degC. */
#define SARINS_IMU_T_REF 25.0

/* True omega_ib_b (out[0..2], rad/s) and f_b (out[3..5], m/s^2) at time tau
 * (s) into an interval whose gimbal state at its start is angle0, rate0,
 * accel [A] (rad, rad/s, rad/s^2); w_t, f_t [3]: the base frame's inertial
 * rate and specific force resolved in t; axes (A, 3). */
void sarins_imu_truth(int64_t n_axes, const double *axes, const double *angle0, const double *rate0,
                      const double *accel, double tau, const double *w_t, const double *f_t, double *out);

/* Minor loop of the output intervals k0 <= k < k1 of a batch (writes rows
 * k0..k1-1 of dtheta, dv (K, 3)).  Intervals are independent: disjoint
 * ranges may run in parallel threads.
 *
 * axes (A, 3); angle0, rate0, accel (K, A) gimbal state at each interval
 * start; w_t, f_t (K, 3) base inertial rate (rad/s) and specific force
 * (m/s^2) resolved in t, held over each interval; h interval (s); n_sub
 * minor steps per interval; g_sf, a_sf (K, 3) scale-factor errors; g_mis,
 * a_mis (3, 3) misalignment (rad, diagonal unused); g_bias, a_bias (K, 3)
 * biases (rad/s, m/s^2); g_quad, a_quad [3] coefficients of x|x| (s/rad,
 * s^2/m); g_lowrate, g_lowrate_width [3] low-rate nonlinearity gain and
 * width (rad/s); g_sens (3, 3) g-sensitivity (rad/s per m/s^2). */
void sarins_imu_increments(int64_t k0, int64_t k1, int64_t n_axes, const double *axes, const double *angle0,
                           const double *rate0, const double *accel, const double *w_t, const double *f_t,
                           double h, int64_t n_sub, const double *g_sf, const double *g_mis,
                           const double *g_bias, const double *g_quad, const double *g_lowrate,
                           const double *g_lowrate_width, const double *g_sens, const double *a_sf,
                           const double *a_mis, const double *a_bias, const double *a_quad, double *dtheta,
                           double *dv);

/* Biases (rad/s, m/s^2) and scale-factor errors held over each of K
 * intervals of length h (s), written to the (K, 3) outputs.  temp0[6] and
 * temps (K, 6): (die) temperatures at the start and the interval ends
 * (degC); coef (10, 3): per triad (gyro rows 0-4, accel rows 5-9) bias,
 * tc1, tc2, scale factor, sf tc about SARINS_IMU_T_REF; drift_poly[3] the
 * azimuth drift eps(T) = (a T + b) T + c (rad/s); drift_dtdt (rad/degC);
 * gm[6] Gauss-Markov states (updated), gm_phi[6], gm_std[6], gm_noise (K, 6). */
void sarins_imu_interval_terms(int64_t n_steps, const double *temp0, const double *temps, double h,
                               const double *coef, const double *drift_poly, double drift_dtdt, double *gm,
                               const double *gm_phi, const double *gm_std, const double *gm_noise,
                               double *g_bias, double *g_sf, double *a_bias, double *a_sf);

/* Advance the thermal and error states of the IMU table over K intervals:
 * amb_end[K] ambient at the interval ends (degC, checked by the caller);
 * temps (K, 6) out: reported temperatures at the ends; die (K, 6) scratch;
 * g_bias, g_sf, a_bias, a_sf (K, 3) out.  Consumes K rows of the random
 * blocks but leaves the clock: sarins_imu_white_noise moves it on.
 * Returns SARINS_IMU_OK, or an error code without touching any state. */
int sarins_imu_advance(const int64_t *table, int64_t rows, int64_t n_steps, const double *amb_end, double *temps,
                       double *die, double *g_bias, double *g_sf, double *a_bias, double *a_sf);

/* The output dynamics of dynamics.h (size effect, rate hysteresis, output
 * filter) on K intervals' dtheta, dv (K, 3), in place, with temps (K, 6) the
 * reported temperatures at the interval ends; does nothing when the table's
 * dynamics parameters are all 0. */
int sarins_imu_dynamics(const int64_t *table, int64_t rows, int64_t n_steps, const double *temps, double *dtheta,
                        double *dv);

/* Add the angle / velocity random walk (exact variance rw^2 h) to K
 * intervals' dtheta, dv (K, 3) and move the clock on by K intervals. */
int sarins_imu_white_noise(const int64_t *table, int64_t rows, int64_t n_steps, double *dtheta, double *dv);

/* K intervals on the calling thread: sarins_imu_advance, the minor loop over
 * all K, sarins_imu_dynamics, sarins_imu_white_noise.  angle0, rate0, accel (K, A); w_t, f_t
 * (K, 3); amb_end[K] (degC, checked by the caller); dtheta, dv (K, 3) and
 * temps (K, 6) out; work (K, 18) scratch. */
int sarins_imu_steps(const int64_t *table, int64_t rows, int64_t n_steps, const double *angle0,
                     const double *rate0, const double *accel, const double *w_t, const double *f_t,
                     const double *amb_end, double *dtheta, double *dv, double *temps, double *work);

/* One output interval with the base motion of the table's base row:
 * angle0, rate0, accel [A]; amb_end ambient at its end (degC); dtheta[3],
 * dv[3], temps[6] out.  The random blocks must hold one unused row. */
int sarins_imu_one_interval(const int64_t *table, int64_t rows, const double *angle0, const double *rate0,
                            const double *accel, double amb_end, double *dtheta, double *dv, double *temps);

/* The IMUThermal FMU's step (fmus/compiled_steps.py, imu_context): table
 * rows 0-18 the IMU state, 19 the io row, 20 the held motion set, 21 the
 * held vehicle set; buf[n] the slave's Real buffer; t, h the communication
 * point and step (s).  Returns 0 when it did the step, 1 when it changed
 * nothing (the Python do_step then runs and reports any error). */
int sarins_imu_fmu_step(int64_t *table, int64_t rows, double *buf, int64_t n, double t, double h);

#endif
