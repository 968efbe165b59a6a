/* Strapdown INS major loop (ENU), its fine-alignment filter and the
 * inertial-frame coarse-alignment accumulators.
 *
 * Major-loop update from the compensated increments (phi, dv_b) over
 * [t_{k-1}, t_k] (Savage, Strapdown Analytics 2000, ch. 7; Titterton &
 * Weston 2004, ch. 11):
 *
 *     zeta   = (omega_ie^n + omega_en^n) h                   nav-frame rotation
 *     dv_n   = (I - [zeta x]/2) mat_nb(k-1) dv_b             specific-force part
 *     v_k    = v_{k-1} + dv_n + (g^n - (2 omega_ie^n + omega_en^n) x v_{k-1}) h
 *     q_nb,k = q(-zeta) * q_nb,k-1 * q(phi)
 *     L, lambda advance with the trapezoidal mean velocity.
 *
 * Earth and transport rate and Coriolis are evaluated at the start of the
 * step.  The vertical channel is held (height fixed, v_U = 0).
 *
 * State arrays are updated in place: q (4) = q_nb [w x y z], v (3) ENU m/s,
 * pos (3) = [lat rad, lon rad, height m].  Increments dtheta (K,3) rad and
 * dv (K,3) m/s are body-frame (right-front-up), row-major.  Output rows
 * (K,9): lat, lon, height, v_E, v_N, v_U, yaw, pitch, roll (rad, m, m/s),
 * with mat_nb = Rz(yaw) Rx(pitch) Ry(roll).
 */
#ifndef SARINS_INS_H
#define SARINS_INS_H

#include <stdint.h>

#define SARINS_INS_ROW 9           /* columns of an output row */
#define SARINS_INS_ALIGN_STATES 9  /* fine-alignment filter states */

/* Free navigation over K steps of h s.  gyro_comp (3) rad/s and accel_comp
 * (3) m/s^2 are subtracted from the increments (alignment estimates);
 * axial_corr (K) rad/s is subtracted from the z angle increment.  Writes
 * out (K,9). */
void sarins_ins_nav_steps(int64_t k, double *q, double *v, double *pos, const double *dtheta, const double *dv,
                          double h, const double *gyro_comp, const double *accel_comp, const double *axial_corr,
                          double *out);

/* Output row of the alignment phases: pos, zero velocity, the attitude of q. */
void sarins_ins_held_row(const double *q, const double *pos, double *row);

/* Fine alignment on a static base over K steps: mechanization with the
 * position held + 9-state closed-loop Kalman filter,
 *     x = [phi_E, phi_N, phi_U, dv_E, dv_N, eps_x, eps_y, nabla_x, nabla_y]
 * (mat_computed = (I - [phi x]) mat_true; body-frame horizontal gyro drifts
 * rad/s and accelerometer biases m/s^2), error model (Titterton & Weston
 * eqs 12.6-12.7, ENU, static, position known)
 *     phi' = phi x omega_ie^n + d omega_en^n(dv) - mat_nb eps
 *     dv'  = f^n x phi - 2 omega_ie^n x dv + mat_nb nabla
 * measurement: the computed v_E, v_N (true velocity zero, variance r_var).
 * After each update attitude and velocity are corrected, the drift and bias
 * estimates are added to gyro_comp / accel_comp and x is reset.  x (9),
 * p (9,9), q_diag (9) continuous noise densities.  Writes the P diagonal
 * after each step to hist (K,9). */
void sarins_ins_align_steps(int64_t k, double *q, double *v, double *pos, const double *dtheta, const double *dv,
                            double h, double *gyro_comp, double *accel_comp, double *x, double *p,
                            const double *q_diag, double r_var, double *hist);

/* Inertial-frame coarse alignment accumulators over K steps (in place):
 *     v_b0 += mat_b0b dv ;  q_b0b = q_b0b * q(dtheta)
 * Writes v_b0 after each step to hist (K,3). */
void sarins_ins_coarse_steps(int64_t k, double *q_b0b, double *v_b0, const double *dtheta, const double *dv,
                             double *hist);

#endif
