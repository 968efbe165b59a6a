/* 15-state error-state Kalman filter (up to 30 with the optional states at the end of this comment) for
 * loosely coupled GNSS / INS with zero-velocity updates, closed loop (the estimated errors are fed back into
 * the INS after every update).
 *
 * The INS is nav3.h's mechanization on the increments compensated with the estimated biases,
 *     dtheta_c = dtheta - b_g h,   dv_c = dv - b_a h.
 * Error state (ENU, metres and radians), true = computed - error for dr, dv and phi:
 *     x = [dr (E N U, m), dv (E N U, m/s), phi (E N U, rad), db_g (body, rad/s), db_a (body, m/s^2)]
 * with mat_nb,computed = (I - [phi x]) mat_nb,true; the bias blocks are the corrections the estimates
 * lack, true = estimate + db (b_g,true = b_g + db_g, b_a,true = b_a + db_a): the compensated increments
 * then carry -db (dtheta_c / h = w_ib,true - db_g + noise), which is what the dynamics below
 * (phi' = ... - mat_nb db_g), the GNSS velocity row (-mat_nb [l x]) and the feedback b += db use.
 * Continuous error model (Titterton & Weston 2004, ch. 12; Groves 2013, ch. 14, local-navigation-frame
 * form; R = sqrt(R_M R_N) + h for the gravity gradient):
 *     dr'  = dv
 *     dv'  = f^n x phi - (2 omega_ie^n + omega_en^n) x dv + mat_nb db_a + (0, 0, 2 g / R dr_U)
 *     phi' = -omega_in^n x phi + d omega_en^n(dv) - mat_nb db_g
 *     d omega_en^n(dv) = (-dv_N / (R_M + h), dv_E / (R_N + h), dv_E tan L / (R_N + h))
 *     db_g' = w_bg,  db_a' = w_ba  (random walks)
 * and white noises: angle random walk arw (rad/sqrt(s)) on phi, velocity random walk vrw
 * (m/s/sqrt(s)) on dv, bias random walks.  Every cov_every IMU steps (T = cov_every h):
 *     Phi = I + F T + (F T)^2 / 2,   P = Phi P Phi' + Q,   Q = diag(0, vrw^2, arw^2, rw_g^2, rw_a^2) T
 * (F at the current state).  Updates are scalar and sequential (diagonal R), in Joseph form,
 *     k = P h' / (h P h' + r),   P = (I - k h) P (I - k h)' + k r k',
 * the Joseph form evaluated expanded, P - k a' - a k' + (h a + r) k k' with a = P h' (the same
 * expression for any gain, O(n^2) instead of two n^3 products), then P is symmetrized (the numerical safeguard: symmetry and, by Joseph's form, positive
 * semi-definiteness are kept to rounding).  After a set of updates the state feeds back: position
 * (metres to lat, lon, h), velocity, attitude q_nb <- q(phi) q_nb, biases b += db; x is reset to 0.
 *
 * GNSS position (antenna at lever arm l, body m; fix valid L = `latency` s before it is applied, the
 * INS taken back to the fix's time with a = f^n + g^n - (2 omega_ie^n + omega_en^n) x v from the last
 * step: r(t - L) = r - v L + a L^2 / 2, v(t - L) = v - a L):
 *     z = r_ins(t - L) + mat_nb l - r_gnss (ENU m),  H = [I, 0, [(mat_nb l) x], 0, 0]
 * GNSS velocity:  z = v_ins(t - L) + mat_nb (omega_nb^b x l) - v_gnss,
 *     H = [0, I, [(mat_nb (omega_nb^b x l)) x], -mat_nb [l x], 0]
 * ZUPT:  z = v_ins - v_meas (v_meas: zero plus the stop's jitter),  H = [0, I, 0, 0, 0].
 * ZARU (zero angular rate at a stop): the body stands still on the Earth, so its true rate is the Earth's,
 *     w_ib,true = mat_bn,true omega_ie^n,   omega_ie^n = (0, Omega cos L, Omega sin L)  (ENU).
 * The measured rate is the step's compensated increment over h, w_ib = (dtheta - b_g h) / h (the bias as it
 * stands when the update runs: a ZUPT fed back before it counts), and with the gyro error model
 * dtheta = dtheta_true + b_g,true h + arw sqrt(h) n and b_g,true = b_g + db_g:
 *     w_ib = w_ib,true + db_g + n_w,   n_w white with std arw / sqrt(h) per step.
 * The predicted rate uses the computed attitude, mat_bn = mat_bn,true (I - [phi x])' = mat_bn,true (I + [phi x]):
 *     mat_bn omega_ie^n = mat_bn,true omega_ie^n + mat_bn [phi x] omega_ie^n
 *                       = mat_bn,true omega_ie^n - mat_bn [omega_ie^n x] phi.
 * So  z = w_ib - mat_bn omega_ie^n = mat_bn [omega_ie^n x] phi + db_g + n_w,
 *     H = [0, 0, mat_bn [omega_ie^n x], I, 0]  (row i: row i of mat_bn [omega_ie^n x], e_i),
 * three scalar updates with std config ZARU_STD (rad/s).  (omega_ie^n at the computed latitude: its
 * position derivative, Omega / R per metre ~ 1e-11 rad/s/m, is left out.)  One update per stationary
 * step with the step's own rate, not one with the mean rate of the stop: for a constant bias both carry
 * the same information (N updates of variance r = arw^2 / h, or one of r / N: information N h / arw^2
 * = T / arw^2 over a stop of T s, whatever h), and per step needs no accumulator in the struct and follows
 * a bias estimate that moves during the stop.  ZARU_STD = arw / sqrt(h) is the gyro's own white rate noise
 * per step (the vehicle's rate jitter at a stop adds to it).  The same gyro noise drives phi (the ARW in
 * Q); the filter treats the two as independent: phi enters z only through |omega_ie| ~ 7e-5 rad/s, so
 * the neglected correlation is of relative size Omega h.
 * Body-frame velocity (odometer: forward axis y, measured speed; non-holonomic constraint: axes x
 * and z, measured 0 plus the vehicle's jitter), v^b = mat_bn v^n, for each axis i used:
 *     z_i = (mat_bn v^n)_i - meas_i,   H_i = [0, (mat_bn)_i, -(mat_bn [v^n x])_i, 0, 0]
 * (the odometer at the IMU, no scale-factor state: a scale-factor error is not estimated).
 * The struct holds no pointer and allocates nothing: copying it copies the filter.
 *
 * Optional states (sarins_eskf_init_states, options SARINS_ESKF_OPT below; all off = the 15 states above, the
 * same numbers bit for bit).  They follow the 15 in this order, each block present only when its bit is set
 * in option STATES, so the dimension n is 15 .. SARINS_ESKF_NMAX (30) and P is n x n (row-major, stride n):
 *   bit 1 (SARINS_ESKF_SF): ds_g (body, 1 = 1e6 ppm), ds_a (body, 1), the gyro and accelerometer scale-factor
 *       errors, true = estimate + ds.  Measured dtheta = (1 + s_g) dtheta_true + b_g h + noise per axis (same for
 *       dv with s_a, b_a); compensated  dtheta_c = (dtheta - b_g h) / (1 + s_g),  dv_c = (dv - b_a h) / (1 + s_a),
 *       so w_c = w_true + db_g + diag(w_ib) ds_g to first order, and
 *           phi' = ... - mat_nb diag(w_ib) ds_g,   dv' = ... + mat_nb diag(f^b) ds_a
 *       (w_ib, f^b the last compensated rate and specific force, body).  Random constants (option SF_TAU 0) or
 *       first-order Gauss-Markov, ds' = -ds / tau + w with Q = 2 sigma^2 / tau (sigma = SF0 std); prior std
 *       GYRO_SF0_STD, ACCEL_SF0_STD (1).  ZARU: w_ib carries diag(w_ib) ds_g too, H columns
 *       (mat_bn omega_ie^n)_i (the true rate at rest: the measured rate in H would share z's noise and pull ds_g).
 *   bit 2 (SARINS_ESKF_LEVER): dl (body right-front-up, m), the antenna lever arm's error, true = estimate + dl
 *       (the estimate starts at config LEVER_X..Z); random constant, prior std LEVER0_STD (m).  In the GNSS rows
 *       position  H_dl = -mat_nb,   velocity  H_dl = -mat_nb [omega_nb^b x]
 *       (r_gnss = r + mat_nb,true l_true, v_gnss = v + mat_nb,true (omega_nb^b x l_true)).
 *   bit 4 (SARINS_ESKF_GNSS_POS_GM): e_r (ENU m), the receiver's first-order Gauss-Markov position error,
 *       r_gnss = r_true + mat_nb l + e_r + white;  e_r' = -e_r / tau_r + w, Q = 2 sigma_r^2 / tau_r per axis
 *       (GNSS_POS_GM_STD E N U m, GNSS_POS_GM_TAU s, also the prior).  Not an INS correction: its estimate
 *       ê_r is kept (decayed by Phi's diagonal 1 - T / tau + (T / tau)^2 / 2 at each propagation), the
 *       predicted fix is r_ins + mat_nb l + ê_r and H_e = -I (true = estimate + de).
 *   bit 8 (SARINS_ESKF_GNSS_VEL_GM): e_v (ENU m/s), the same for the fix's velocity (GNSS_VEL_GM_STD, _TAU).
 * With GNSS Gauss-Markov states the fixes' std (sarins_eskf_gnss std, the fix rows) should be the white part
 * only.  Feedback adds the estimated errors to the estimates (s_g, s_a, l, ê_r, ê_v) and resets x.
 */
#ifndef SARINS_ESKF_H
#define SARINS_ESKF_H

#include <stddef.h>
#include <stdint.h>

#define SARINS_ESKF_N 15    /* the base states; n = N + the optional blocks' */
#define SARINS_ESKF_NMAX 30 /* the largest n: every optional block */
/* settings (SI) */
enum {
    SARINS_ESKF_STEP, SARINS_ESKF_ARW, SARINS_ESKF_VRW, SARINS_ESKF_GYRO_RW, SARINS_ESKF_ACCEL_RW,
    SARINS_ESKF_POS0_STD, SARINS_ESKF_VEL0_STD, SARINS_ESKF_TILT0_STD, SARINS_ESKF_HEADING0_STD,
    SARINS_ESKF_GYRO_BIAS0_STD, SARINS_ESKF_ACCEL_BIAS0_STD, SARINS_ESKF_LEVER_X, SARINS_ESKF_LEVER_Y,
    SARINS_ESKF_LEVER_Z, SARINS_ESKF_LATENCY, SARINS_ESKF_ZUPT_STD, SARINS_ESKF_COV_EVERY, SARINS_ESKF_NHC_STD,
    SARINS_ESKF_ODO_STD, SARINS_ESKF_ZARU_STD, SARINS_ESKF_CONFIG
};
/* options of the optional states (sarins_eskf_init_states; SI, the header's model): STATES a bit set (a whole
 * number 0 .. 15) of the blocks below; scale-factor prior stds (1) and correlation time (s, 0: random
 * constants); lever-arm prior std (m); the receiver's Gauss-Markov position std E N U (m) and correlation
 * time (s), velocity std E N U (m/s) and correlation time (s).  A std must be >= 0, a used tau > 0. */
enum {
    SARINS_ESKF_STATES, SARINS_ESKF_GYRO_SF0_STD, SARINS_ESKF_ACCEL_SF0_STD, SARINS_ESKF_SF_TAU,
    SARINS_ESKF_LEVER0_STD, SARINS_ESKF_GNSS_POS_GM_STD, SARINS_ESKF_GNSS_POS_GM_TAU = SARINS_ESKF_GNSS_POS_GM_STD + 3,
    SARINS_ESKF_GNSS_VEL_GM_STD, SARINS_ESKF_GNSS_VEL_GM_TAU = SARINS_ESKF_GNSS_VEL_GM_STD + 3, SARINS_ESKF_OPT
};
enum { SARINS_ESKF_SF = 1, SARINS_ESKF_LEVER = 2, SARINS_ESKF_GNSS_POS_GM = 4, SARINS_ESKF_GNSS_VEL_GM = 8 };
/* output row (15 states): nav row (9: lat, lon, h, v E N U, yaw, pitch, roll), b_g (3), b_a (3), P (15 x 15);
 * the short row has P's diagonal (15) in place of P.  With n states: nav (9), b_g, b_a, the optional blocks'
 * estimates in the state's order (s_g, s_a, l, ê_r, ê_v as present: n - 15), then P (n x n) or its diagonal
 * (n): n + n^2 or 2 n numbers (sarins_eskf_row_size). */
#define SARINS_ESKF_ROW (9 + 6 + SARINS_ESKF_N * SARINS_ESKF_N)
#define SARINS_ESKF_ROW_DIAG (9 + 6 + SARINS_ESKF_N)
#define SARINS_ESKF_AID 10 /* aid row of sarins_eskf_run (columns below) */
#define SARINS_ESKF_GNSS 11 /* fix row of sarins_eskf_run: step index, valid, lat, lon (rad), h (m),
                               v E N U (m/s), position std E N U (m) */

typedef struct {
    double config[SARINS_ESKF_CONFIG];
    double q[4], v[3], pos[3]; /* INS state: q_nb [w x y z], ENU m/s, lat lon rad h m */
    double bg[3], ba[3];       /* estimated biases, body rad/s, m/s^2 */
    double p[SARINS_ESKF_NMAX * SARINS_ESKF_NMAX]; /* n x n, row-major, stride n */
    double x[SARINS_ESKF_NMAX]; /* error state between an update and its feedback (0 otherwise) */
    double w_ib[3];            /* last compensated angular rate, body rad/s */
    double f_n[3];             /* last specific force, nav m/s^2 (for F) */
    int64_t steps, since_cov;
    double opt[SARINS_ESKF_OPT]; /* options of the optional states (all 0: none) */
    double f_b[3];             /* last compensated specific force, body m/s^2 (scale-factor rows of F) */
    double sg[3], sa[3];       /* scale-factor estimates, body (1) */
    double lever[3];           /* antenna lever-arm estimate, body m (config LEVER_X..Z at the start) */
    double gm_r[3], gm_v[3];   /* receiver Gauss-Markov error estimates, ENU m and m/s */
    int64_t n;                 /* states: 15 .. SARINS_ESKF_NMAX */
    int64_t i_sg, i_sa, i_lever, i_gm_r, i_gm_v; /* first index of each optional block, -1 when absent */
} sarins_eskf;

/* Initialise from config and the start nav row (9); 0, or 1 with a reason in msg. */
int sarins_eskf_init(sarins_eskf *s, const double *config, const double *nav0, char *msg, size_t size);

/* Initialise with the optional states of opt (SARINS_ESKF_OPT, NULL: none); 0, or 1 with a reason in msg.
 * sarins_eskf_init is this with opt NULL. */
int sarins_eskf_init_states(sarins_eskf *s, const double *config, const double *opt, const double *nav0, char *msg,
                            size_t size);

/* The state dimension n of s; the width of sarins_eskf_run's output rows (full_cov != 0: n + n^2, else 2 n). */
int64_t sarins_eskf_dim(const sarins_eskf *s);
int64_t sarins_eskf_row_size(const sarins_eskf *s, int full_cov);

/* 0 when s is a state sarins_eskf_init_states and the steps can make as far as the layout goes (options
 * valid, n and the block indices those of the options' bits, the state finite), else 1 with msg. */
int sarins_eskf_check(const sarins_eskf *s, char *msg, size_t size);

/* One IMU step (dtheta, dv body rad, m/s): mechanization + covariance propagation. */
void sarins_eskf_predict(sarins_eskf *s, const double *dtheta, const double *dv);

/* GNSS update from a fix pos (lat, lon rad, h m), vel (E N U m/s) with std (6: position E N U m,
 * velocity E N U m/s); use_vel 0 skips velocity.  Feeds back.  Returns the normalized innovation
 * squared summed over the scalar updates (for consistency checks). */
double sarins_eskf_gnss(sarins_eskf *s, const double *pos, const double *vel, const double *std, int use_vel);

/* Zero-velocity update from the velocity measured at a stop v_meas (3, ENU m/s: zero plus the stop's
 * jitter; three scalar updates with std config ZUPT_STD) and feedback. */
void sarins_eskf_zupt(sarins_eskf *s, const double *v_meas);

/* Zero-angular-rate update at a stop from the step's raw angle increment dtheta (3, body rad: the one
 * sarins_eskf_predict just integrated), compensated with the current gyro bias estimate; three scalar
 * updates with std config ZARU_STD (rad/s), then feedback. */
void sarins_eskf_zaru(sarins_eskf *s, const double *dtheta);

/* Body-frame velocity update on the axes with use[i] != 0 (meas (3) m/s, std (3) m/s), then feedback. */
void sarins_eskf_body_velocity(sarins_eskf *s, const double *meas, const int *use, const double *std);

/* The per-step aiding after one sarins_eskf_predict(s, dtheta, dv), by one aid row a (SARINS_ESKF_AID)
 * = [zupt flag, zupt measured v E N U (m/s), odometer flag, odometer speed (m/s, forward body y), NHC flag,
 * NHC measured body v_x, v_z (m/s: zero plus the vehicle's jitter), zaru flag] (a flag is applied when
 * != 0; a value is read only when its flag is set): a ZUPT, then a ZARU (from the step's raw dtheta (3,
 * body rad)), then one body-velocity update on the odometer's and / or the NHC's axes (std config
 * ODO_STD, NHC_STD).  Each applied update feeds back.  The inputs must be finite. */
void sarins_eskf_aid(sarins_eskf *s, const double *dtheta, const double *a);

/* K steps: predict with dtheta, dv (K, 3); after step k, sarins_eskf_aid with the row aid[k] of aid
 * (K, SARINS_ESKF_AID) (columns above); then the fixes
 * whose step index (gnss row column 0, the step after which the fix is applied) equals k, in order:
 * rows (m, 11) = step index, valid, lat, lon, h, v E N U, std E N U (position m), and vel_std (3)
 * shared by all fixes.  Writes out rows after every out_every-th step (n_out = K / out_every rows):
 * sarins_eskf_row_size(s, full_cov) numbers each (SARINS_ESKF_ROW with full_cov != 0, else SARINS_ESKF_ROW_DIAG,
 * P's diagonal only, for the 15 states).  Returns 0, or 1
 * (nothing changed) for a non-finite input or fix rows not in step order. */
int sarins_eskf_run(sarins_eskf *s, int64_t k, const double *dtheta, const double *dv, const double *aid, int64_t m,
                    const double *gnss, const double *vel_std, int use_vel, int64_t out_every, int full_cov, double *out);

int64_t sarins_eskf_size(void);

#endif
