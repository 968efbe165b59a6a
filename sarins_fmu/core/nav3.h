/* Full three-dimensional strapdown mechanization (ENU, height included) for aided navigation.
 *
 * One major-loop step from the IMU increments over [t_{k-1}, t_k] (dtheta rad, the body rotation
 * vector; dv m/s, the specific-force increment in the body frame at t_{k-1}; the contract of
 * ins.h and traj.h), h s.  Earth rate, transport rate, gravity and the Coriolis velocity are taken
 * at the middle of the step, found by two passes (the first at the start state, the second at the
 * mean of the start and the first pass's end: a second-order predictor-corrector; Savage,
 * Strapdown Analytics 2000, ch. 7):
 *     zeta  = (omega_ie^n + omega_en^n)(mid) h
 *     v_k   = v_{k-1} + (I - [zeta x]/2) mat_nb(k-1) dv + (g^n - (2 omega_ie^n + omega_en^n) x v)(mid) h
 *     h_k   = h_{k-1} + (v_U,k-1 + v_U,k) h / 2
 *     L_k   = L_{k-1} + (v_N,k-1 + v_N,k) h / (2 (R_M(mid) + h(mid)))
 *     lon_k = lon_{k-1} + (v_E,k-1 + v_E,k) h / (2 (R_N(mid) + h(mid)) cos L(mid))
 *     q_nb,k = q(-zeta) * q_nb,k-1 * q(dtheta)
 * Unlike ins.h's mechanization the vertical channel is free (unstable without aiding: its error
 * grows with time constant sqrt(R / 2 g), about 570 s).
 * State arrays: q (4) q_nb [w x y z], v (3) ENU m/s, pos (3) lat, lon rad, height m.
 */
#ifndef SARINS_NAV3_H
#define SARINS_NAV3_H

#include <stdint.h>

#define SARINS_NAV3_ROW 9 /* lat, lon (rad), h (m), v E N U (m/s), yaw, pitch, roll (rad) */

/* One step in place. */
void sarins_nav3_step(double *q, double *v, double *pos, const double *dtheta, const double *dv, double h);

/* The same step, also giving dv_n (3) = mat_nb,k-1 dv (m/s, ENU: the specific-force increment resolved
 * at the start of the step, as the velocity update uses it). */
void sarins_nav3_step_dvn(double *q, double *v, double *pos, const double *dtheta, const double *dv, double h,
                          double *dv_n);

/* K steps in place; writes out (K, 9) after each step.  Within the call the position sums are
 * compensated (Kahan), so rounding does not accumulate over the K steps.  Returns 0, or 1 (nothing changed) when an
 * increment is not finite or h is not positive. */
int sarins_nav3_steps(int64_t k, double *q, double *v, double *pos, const double *dtheta, const double *dv,
                      double h, double *out);

/* Output row (9) of a state. */
void sarins_nav3_row(const double *q, const double *v, const double *pos, double *row);

/* yaw, pitch, roll (rad) of mat_nb = Rz(yaw) Rx(pitch) Ry(roll) (3,3) row-major */
void sarins_mat_to_euler(const double *mat, double *ypr);

#endif
