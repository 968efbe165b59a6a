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
 * to 17 in the order SARINS_IMU_CONSTS .. SARINS_IMU_PERIODIC.  Every random
 * number is drawn here, inside the step, from the streams of rng.h whose
 * states the table holds; sarins_imu_seed starts them from the IMU seed.
 *
 * Periodic disturbance (SARINS_IMU_PERIODIC (3, 6): amplitude a (rad/s,
 * m/s^2), frequency f (Hz, 0 < f <= n_sub / (2 h) when a > 0) and phase phi
 * (rad, drawn at seeding) of gyro x y z, accel x y z): the sensor's output
 * rate carries a sin(2 pi f t + phi), t the time since the IMU's start; its
 * exact integral over each output interval [k h, (k + 1) h],
 *     (a / (pi f)) sin(pi f h) sin(2 pi f (k + 1/2) h + phi),
 * is added to the increments after the output dynamics (so the Allan
 * variance of the rate is a^2 sin^4(pi f tau) / (pi f tau)^2 exactly at
 * every tau = m h).
 */
#ifndef SARINS_IMU_H
#define SARINS_IMU_H

#include <stdint.h>

#include "rng.h"
#include "workers.h"

enum {
    SARINS_IMU_CONSTS, SARINS_IMU_CLOCK, SARINS_IMU_SENSOR_PAR, SARINS_IMU_STATE, SARINS_IMU_COEF,
    SARINS_IMU_TRIAD, SARINS_IMU_MATS, SARINS_IMU_AXES, SARINS_IMU_BASE, SARINS_IMU_RNG, SARINS_IMU_CORR_PAR,
    SARINS_IMU_CORR_STATE, SARINS_IMU_PHI, SARINS_IMU_Q, SARINS_IMU_X_FLICKER, SARINS_IMU_DYN_PAR, SARINS_IMU_DYN_STATE,
    SARINS_IMU_PERIODIC, SARINS_IMU_N_ARRAYS
};

/* The IMU's random streams (rng.h), one per purpose, all from the IMU seed;
 * their states are the rows of the SARINS_IMU_RNG array, in this order.
 * Draws per output interval, in this order within each stream:
 *   WHITE    6: angle / velocity random walk, gyro x y z, accel x y z (when
 *            a random walk is not zero);
 *   GM       6 at seeding (the stationary start), then 6 per interval (when
 *            a Gauss-Markov std is not zero);
 *   FLICKER  6 F at seeding (stationary start, term-major), then 6 F per
 *            interval (sensor-major) when a flicker term is not zero and the
 *            correlated terms are on;
 *   RRW      6 per interval (rate random walk, when not zero and on);
 *   TURN_ON  6 at seeding (the turn-on bias);
 *   AGEING   3 per ageing step (sarins_imu_aged_poly), drawn at construction;
 *   PERIODIC 6 uniform at seeding (the periodic terms' phases, gyro x y z,
 *            accel x y z, drawn whatever the amplitudes); not kept in the
 *            table (no later draw), so it is not a row of SARINS_IMU_RNG. */
enum {
    SARINS_IMU_STREAM_WHITE, SARINS_IMU_STREAM_GM, SARINS_IMU_STREAM_FLICKER, SARINS_IMU_STREAM_RRW,
    SARINS_IMU_STREAM_TURN_ON, SARINS_IMU_STREAM_AGEING, SARINS_IMU_N_STREAMS
};
#define SARINS_IMU_STREAM_PERIODIC SARINS_IMU_N_STREAMS /* stream id 6: seeding only (above) */

/* return codes of the table functions */
#define SARINS_IMU_OK 0
#define SARINS_IMU_BAD_TABLE 1  /* a missing row, an array of the wrong shape or a stream state that is not one */

#define SARINS_IMU_MAX_AXES 8   /* gimbals the one-interval step accepts */
#define SARINS_IMU_LANES 4      /* intervals the minor loop evaluates side by side */
#define SARINS_IMU_N_CONSTS 13  /* length of the consts row (sarins_fmu/imu_step.py) */
#define SARINS_IMU_MAX_SUB 1073741824 /* minor steps per output interval (2^30; an int64 loop count, exact in a double) */

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
 * width (rad/s); g_sens (3, 3) g-sensitivity (rad/s per m/s^2).
 *
 * Runs of SARINS_IMU_LANES intervals are evaluated side by side in SIMD
 * lanes (each lane does the scalar formulas' operations in the same order);
 * the remainder, and every interval of more than SARINS_IMU_MAX_AXES
 * gimbals, one at a time (then the terms of SARINS_IMU_LANES consecutive
 * minor steps that do not depend on the attitude and velocity sums side by
 * side).  The results do not depend on the split. */
void sarins_imu_increments(int64_t k0, int64_t k1, int64_t n_axes, const double *axes, const double *angle0,
                           const double *rate0, const double *accel, const double *w_t, const double *f_t,
                           double h, int64_t n_sub, const double *g_sf, const double *g_mis,
                           const double *g_bias, const double *g_quad, const double *g_lowrate,
                           const double *g_lowrate_width, const double *g_sens, const double *a_sf,
                           const double *a_mis, const double *a_bias, const double *a_quad, double *dtheta,
                           double *dv);

/* sarins_imu_increments one interval at a time, without interval lanes
 * (the reference those lanes are tested against; the same results). */
void sarins_imu_increments_scalar(int64_t k0, int64_t k1, int64_t n_axes, const double *axes, const double *angle0,
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
 * gm[6] Gauss-Markov states (updated), gm_phi[6], gm_std[6]; gm_rng the
 * stream of their driving noise (6 draws per interval), or NULL for none
 * (every gm_std zero). */
void sarins_imu_interval_terms(int64_t n_steps, const double *temp0, const double *temps, double h,
                               const double *coef, const double *drift_poly, double drift_dtdt, double *gm,
                               const double *gm_phi, const double *gm_std, SarinsRng *gm_rng,
                               double *g_bias, double *g_sf, double *a_bias, double *a_sf);

/* Azimuth-gyro thermal terms beyond eps(T) and d dT/dt, added to the z-gyro
 * bias of K intervals of length h (s):
 *   gradient    k_g G,  G = T - T_b the difference between the z-gyro node and
 *               its block node, dT_b/dt = (T - T_b) / tau_b (exact for T
 *               linear over each interval; G is the mean of its values at the
 *               interval's start and end; tau_b = 0: no block lag, G = 0);
 *   hysteresis  H (T_m - P) / w,  P_k = max(T_m - w, min(T_m + w, P_{k-1})) the
 *               play operator of width w (degC, > 0) on the interval-mean
 *               temperature T_m, then relaxed towards T_m,
 *               P <- T_m + (P - T_m) exp(-h / tau_r) (tau_r = 0: no relaxation).
 * Heating by more than w puts the term on its +H branch, cooling on its -H
 * branch; at rest it decays as exp(-t / tau_r).
 * temp0: z temperature at the start (degC); temps[k * t_stride] at the ends;
 * par[5] = k_g (rad/s/degC), tau_b (s), H (rad/s), w (degC), tau_r (s);
 * state[2] = T_b, P (degC), advanced in place; bias[k * b_stride] += the terms
 * (rad/s).  Nothing happens when k_g and H are both 0. */
void sarins_imu_axial_thermal_terms(int64_t n_steps, double temp0, const double *temps, int64_t t_stride, double h,
                                    const double *par, double *state, double *bias, int64_t b_stride);

/* Advance the thermal and error states of the IMU table over K intervals:
 * amb_end[K] ambient at the interval ends (degC, checked by the caller);
 * temps (K, 6) out: reported temperatures at the ends; die (K, 6) scratch;
 * g_bias, g_sf, a_bias, a_sf (K, 3) out.  Draws the GM, FLICKER and RRW
 * streams' numbers of K intervals but leaves the clock:
 * sarins_imu_white_noise moves it on.
 * Returns SARINS_IMU_OK, or an error code without touching any state. */
int sarins_imu_advance(const int64_t *table, int64_t rows, int64_t n_steps, const double *amb_end, double *temps,
                       double *die, double *g_bias, double *g_sf, double *a_bias, double *a_sf);

/* The output dynamics of dynamics.h (size effect, rate hysteresis, output
 * filter) on K intervals' dtheta, dv (K, 3), in place, with temps (K, 6) the
 * reported temperatures at the interval ends; does nothing when the table's
 * dynamics parameters are all 0.  No random draws. */
int sarins_imu_dynamics(const int64_t *table, int64_t rows, int64_t n_steps, const double *temps, double *dtheta,
                        double *dv);

/* Add the output terms that do not pass through the output dynamics to K
 * intervals' dtheta, dv (K, 3): the periodic disturbance (its exact integral
 * over each interval, see SARINS_IMU_PERIODIC above; nothing when every
 * amplitude is 0) and the angle / velocity random walk (exact variance
 * rw^2 h, from the WHITE stream); then move the clock on by K intervals. */
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
 * dv[3], temps[6] out. */
int sarins_imu_one_interval(const int64_t *table, int64_t rows, const double *angle0, const double *rate0,
                            const double *accel, double amb_end, double *dtheta, double *dv, double *temps);

/* Start the random streams of the table from seed (a restart of the IMU):
 * every stream at its start, then the draws made at power-up: the
 * Gauss-Markov states' stationary start (state row 1 = N(0, gm_std^2)), the
 * flicker terms' (x_flicker = N(0, q^2)), the turn-on bias (corr_par row 6
 * = N(0, std^2) with corr_par row 7 the std), the periodic terms' phases
 * (periodic row 2, uniform on [0, 2 pi) from the PERIODIC stream).  The
 * other states are the caller's (reset before this call). */
int sarins_imu_seed(const int64_t *table, int64_t rows, uint64_t seed);

/* The turn-on bias an IMU with seed draws at power-up: out[j] = std[j] w_j,
 * w the first 6 draws of the TURN_ON stream (gyro x y z rad/s, accel m/s^2). */
void sarins_imu_turn_on(uint64_t seed, const double *std, double *out);

/* Ageing of the azimuth-drift coefficients (a, b, c): first-order Markov
 * m_{k+1} = d_k m_k + sigma sqrt(1 - d_k^2) w_k, d_k = exp(-(t_k - t_{k-1}) / tau),
 * m_0 = 0 at t_0 = 0, w from the AGEING stream of seed (3 per step, a b c);
 * out (K, 3) = poly + m_k at the K increasing ages t (s). */
void sarins_imu_aged_poly(uint64_t seed, int64_t n, const double *t, const double *poly, const double *sigma,
                          double tau, double *out);

/* The IMUThermal FMU's step (fmus/c/imu_thermal/model.c): table
 * rows 0-17 the IMU state, 18 the io row, 19 the held motion set, 20 the
 * held vehicle set; buf[n] the FMU's Real values; t, h the communication
 * point and step (s).  Returns 0 when it did the step, 1 when it changed
 * nothing (the caller then finds and reports the reason). */
int sarins_imu_fmu_step(int64_t *table, int64_t rows, double *buf, int64_t n, double t, double h);

/* The same step split into k_sub > 1 output intervals of h / k_sub each (the table built with that interval
 * and internal_rate h / k_sub minor steps per interval), as if the FMU stepped at h / k_sub: every
 * sub-interval's thermal and error terms, minor loop, output dynamics and random walk (sarins_imu_steps),
 * its start-of-interval motion the step's motion set carried forward with its constant accelerations
 * (theta0 + (rate0 + accel tau / 2) tau, rate0 + accel tau), the base rates and forces held, the ambient
 * linear.  dtheta, dv (k_sub, 3) and temps (k_sub, 6) out: each sub-interval's increments (body axes at its
 * start) and temperatures at its end; buf's increments are their sums (in order, no coning or sculling
 * across sub-intervals) and its temperatures the last sub-interval's.  scratch: SARINS_IMU_SUB_SCRATCH
 * doubles.  Returns 0 when it did the step, 1 when it changed nothing (also for a table built with
 * another interval than h / k_sub). */
int sarins_imu_fmu_step_sub(int64_t *table, int64_t rows, double *buf, int64_t n, double t, double h,
                            int64_t k_sub, double *dtheta, double *dv, double *temps, double *scratch);
#define SARINS_IMU_SUB_SCRATCH(k_sub, n_axes) ((k_sub) * (3 * (n_axes) + 7 + 18))

/* sarins_imu_fmu_step_sub with the motion of every sub-interval given (k_sub >= 1, static base): motion
 * (k_sub, 3 A + 2), row k the start of sub-interval k as a step of h / k_sub would read it: the A gimbal
 * angles (rad), rates (rad/s), accelerations holding over it (rad/s^2), the ambient (degC) and its slope
 * (degC/s); the set is tagged by buf's motion_time and the table's held row holds k_sub (3 A + 2) values.
 * Sub-interval k's ambient at its end is ambient + slope h / k_sub.  pool: NULL (the caller's thread) or
 * workers running the sub-intervals' minor loops side by side (the same bits).  dtheta, dv, temps, scratch
 * as sarins_imu_fmu_step_sub.  Returns 0 when it did the step, 1 when it changed nothing. */
int sarins_imu_fmu_step_given(int64_t *table, int64_t rows, double *buf, int64_t n, double t, double h,
                              int64_t k_sub, const double *motion, double *dtheta, double *dv, double *temps,
                              double *scratch, sarins_workers *pool);

/* The io row of sarins_imu_fmu_step: the expected step (s), the start time (s), the gimbal count A (1-3),
 * the buf slots of motion_time, ambient_temp, ambient_temp_rate, angle_1..3, rate_1..3, accel_1..3, the 12
 * outputs (dtheta x y z, dv x y z, the six temperatures), increment_end_time; moving base (1/0), the slots of
 * base_motion_time and of the SARINS_IMU_VEHICLE_SET vehicle inputs (yaw, pitch, roll; their rates; their
 * accelerations; base rate e n u; base force e n u).  A held set is [kept (0/1), tag, values...]. */
#define SARINS_IMU_VEHICLE_SET 15
#define SARINS_IMU_NO_TAG (-1.0e9) /* start value of a time-tag input: not connected */
#define SARINS_IMU_TAG_TOL 1e-6    /* of a step: two time tags closer than this name the same point */
enum { SARINS_IMU_IO_STEP = 0, SARINS_IMU_IO_START = 1, SARINS_IMU_IO_GIMBALS = 2, SARINS_IMU_IO_MOTION_TIME = 3,
       SARINS_IMU_IO_AMBIENT = 4, SARINS_IMU_IO_MOTION = 6, SARINS_IMU_IO_OUT = 15, SARINS_IMU_IO_END_TIME = 27,
       SARINS_IMU_IO_VEHICLE = 28, SARINS_IMU_IO_SIZE = SARINS_IMU_IO_VEHICLE + 2 + SARINS_IMU_VEHICLE_SET };

#endif
