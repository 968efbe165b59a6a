/* Kalman-filter steps shared by the INS fine alignment and the stop filter.
 *
 * Both filters measure z = (v_E, v_N), m/s, the states 3 and 4 (Titterton &
 * Weston ch. 13; seed 002 eqs 4-6), and propagate with a transition matrix
 * Phi built by the caller.  The update uses the Joseph form.  Matrices are
 * n x n row-major with 5 <= n <= SARINS_FILTER_MAX_STATES (for another n
 * nothing is done); x and P are updated in place.
 */
#ifndef SARINS_FILTER_H
#define SARINS_FILTER_H

#include <stdint.h>

#include "matrix.h" /* sarins_matmul and the other small-matrix helpers */

#define SARINS_FILTER_MAX_STATES 11

/* x = Phi x ; P = Phi P Phi' + diag(q) dt   (q: continuous noise densities, dt s) */
void sarins_filter_propagate(int n, double *x, double *p, const double *phi, const double *q_diag, double dt);

/* z = (z_east, z_north) measures x[3], x[4] with variance r_var (m/s)^2:
 * K = P H' (H P H' + R)^-1 ; x += K (z - H x) ; P = (I - K H) P (I - K H)' + K R K' */
void sarins_filter_velocity_update(int n, double *x, double *p, double r_var, double z_east, double z_north);

/* Static-base stop filter of seed 002 (sarins_fmu.kalman) over K measurements,
 * 11 states x = [phi_E, phi_N, phi_U, dv_E, dv_N, eps_x, eps_y, eps_z,
 * nabla_x, nabla_y, d_lat] (rad, m/s, rad/s, m/s^2, rad), open loop:
 *     phi'   = phi x omega_ie^n + d omega_en^n(dv) + d omega_ie^n(d_lat) - mat_nb eps
 *     dv'    = f^n x phi - 2 omega_ie^n x dv + mat_nb nabla,  f^n = (0, 0, g)
 *     d_lat' = dv_N / R_M
 * with mat_nb from the INS attitude (K,3) yaw, pitch, roll (rad) of each
 * step, Phi = I + F dt + (F dt)^2/2 + (F dt)^3/6, measurement velocity_en
 * (K,2) m/s with variance r_var.  lat rad, dt s, q_diag (11) continuous
 * noise densities.  x (11), p (11,11) in place; out (K,2): the eps_z
 * estimate and its standard deviation after each step, rad/s. */
#define SARINS_STOP_STATES 11
#define SARINS_STOP_EPS_Z 7
void sarins_stop_filter_steps(int64_t k, double *x, double *p, const double *velocity_en, const double *attitude,
                              double lat, double dt, const double *q_diag, double r_var, double *out);

#endif
