/* Rotation helpers: rotation vectors, quaternions, Euler angles.
 *
 * Matrices are 3x3 row-major double[9]; a DCM mat_xy projects frame y onto
 * the axes of frame x.  Quaternions are scalar-first [w x y z] and name the
 * same transformation as the DCM of the same name.  A rotation vector phi
 * (rad) maps to exp([phi x]) (Rodrigues).  Euler angles (rad) follow the
 * seeds' ENU / right-front-up convention: mat_nb = Rz(yaw) Rx(pitch) Ry(roll),
 * yaw positive counter-clockwise about up.
 */
#ifndef SARINS_ROTATIONS_H
#define SARINS_ROTATIONS_H

#include <stdint.h>

/* mat = exp([phi x]) = I + sin(th)/th [phi x] + (1 - cos(th))/th^2 [phi x]^2, th = |phi| */
void sarins_rotvec_to_mat(const double *phi, double *mat);
/* q = [cos(th/2), sin(th/2)/th phi] */
void sarins_rotvec_to_quat(const double *phi, double *q);
/* out = p * q (Hamilton product); out may not alias p or q */
void sarins_quat_mult(const double *p, const double *q, double *out);
/* DCM of a unit quaternion */
void sarins_quat_to_mat(const double *q, double *mat);
/* mat_nb = Rz(yaw) Rx(pitch) Ry(roll) */
void sarins_euler_to_mat(double yaw, double pitch, double roll, double *mat);

/* Batched over n items (phi (n,3), q (n,4), mat (n,9), angles (n,3)), for the Python binding. */
void sarins_rotvec_to_mat_n(int64_t n, const double *phi, double *mat);
void sarins_rotvec_to_quat_n(int64_t n, const double *phi, double *q);
void sarins_quat_mult_n(int64_t n, const double *p, const double *q, double *out);
void sarins_quat_to_mat_n(int64_t n, const double *q, double *mat);
void sarins_euler_to_mat_n(int64_t n, const double *yaw_pitch_roll, double *mat);

#endif
