#include "smath.h"

#include "rotations.h"


void sarins_rotvec_to_mat(const double *phi, double *mat)
{
    double theta2 = phi[0] * phi[0] + phi[1] * phi[1] + phi[2] * phi[2];
    double theta = sm_sqrt(theta2);
    double a, b;
    if (theta < 1e-8) { /* series: sin(th)/th ~ 1 - th^2/6, (1 - cos th)/th^2 ~ 1/2 - th^2/24 */
        a = 1.0 - theta2 / 6.0;
        b = 0.5 - theta2 / 24.0;
    } else {
        a = sm_sin(theta) / theta;
        b = (1.0 - sm_cos(theta)) / theta2;
    }
    double k[9] = {0.0, -phi[2], phi[1], phi[2], 0.0, -phi[0], -phi[1], phi[0], 0.0};
    /* mat = I + a K + b K K */
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double kk = k[3 * i] * k[j] + k[3 * i + 1] * k[3 + j] + k[3 * i + 2] * k[6 + j];
            mat[3 * i + j] = ((i == j) ? 1.0 : 0.0) + a * k[3 * i + j] + b * kk;
        }
}

void sarins_rotvec_to_quat(const double *phi, double *q)
{
    double theta2 = phi[0] * phi[0] + phi[1] * phi[1] + phi[2] * phi[2];
    double theta = sm_sqrt(theta2);
    double s, c;
    if (theta < 1e-8) { /* series: sin(th/2)/th ~ 1/2 - th^2/48, cos(th/2) ~ 1 - th^2/8 */
        s = 0.5 - theta2 / 48.0;
        c = 1.0 - theta2 / 8.0;
    } else {
        double sh;
        sm_sincos(0.5 * theta, &sh, &c); /* one range reduction; the bits of sm_sin, sm_cos */
        s = sh / theta;
    }
    q[0] = c;
    q[1] = s * phi[0];
    q[2] = s * phi[1];
    q[3] = s * phi[2];
}

void sarins_quat_mult(const double *p, const double *q, double *out)
{
    out[0] = p[0] * q[0] - p[1] * q[1] - p[2] * q[2] - p[3] * q[3];
    out[1] = p[0] * q[1] + p[1] * q[0] + p[2] * q[3] - p[3] * q[2];
    out[2] = p[0] * q[2] - p[1] * q[3] + p[2] * q[0] + p[3] * q[1];
    out[3] = p[0] * q[3] + p[1] * q[2] - p[2] * q[1] + p[3] * q[0];
}

void sarins_quat_to_mat(const double *q, double *mat)
{
    double w = q[0], x = q[1], y = q[2], z = q[3];
    mat[0] = w * w + x * x - y * y - z * z;
    mat[1] = 2 * (x * y - w * z);
    mat[2] = 2 * (x * z + w * y);
    mat[3] = 2 * (x * y + w * z);
    mat[4] = w * w - x * x + y * y - z * z;
    mat[5] = 2 * (y * z - w * x);
    mat[6] = 2 * (x * z - w * y);
    mat[7] = 2 * (y * z + w * x);
    mat[8] = w * w - x * x - y * y + z * z;
}

void sarins_euler_to_mat(double yaw, double pitch, double roll, double *mat)
{
    double cy, sy, cp, sp, cr, sr; /* one range reduction per angle; the bits of sm_sin, sm_cos */
    sm_sincos(yaw, &sy, &cy);
    sm_sincos(pitch, &sp, &cp);
    sm_sincos(roll, &sr, &cr);
    /* Rz(yaw) Rx(pitch) Ry(roll), written out */
    mat[0] = cy * cr - sy * sp * sr;
    mat[1] = -sy * cp;
    mat[2] = cy * sr + sy * sp * cr;
    mat[3] = sy * cr + cy * sp * sr;
    mat[4] = cy * cp;
    mat[5] = sy * sr - cy * sp * cr;
    mat[6] = -cp * sr;
    mat[7] = sp;
    mat[8] = cp * cr;
}

void sarins_rotvec_to_mat_n(int64_t n, const double *phi, double *mat)
{
    for (int64_t k = 0; k < n; k++)
        sarins_rotvec_to_mat(phi + 3 * k, mat + 9 * k);
}

void sarins_rotvec_to_quat_n(int64_t n, const double *phi, double *q)
{
    for (int64_t k = 0; k < n; k++)
        sarins_rotvec_to_quat(phi + 3 * k, q + 4 * k);
}

void sarins_quat_mult_n(int64_t n, const double *p, const double *q, double *out)
{
    for (int64_t k = 0; k < n; k++)
        sarins_quat_mult(p + 4 * k, q + 4 * k, out + 4 * k);
}

void sarins_quat_to_mat_n(int64_t n, const double *q, double *mat)
{
    for (int64_t k = 0; k < n; k++)
        sarins_quat_to_mat(q + 4 * k, mat + 9 * k);
}

void sarins_euler_to_mat_n(int64_t n, const double *yaw_pitch_roll, double *mat)
{
    for (int64_t k = 0; k < n; k++)
        sarins_euler_to_mat(yaw_pitch_roll[3 * k], yaw_pitch_roll[3 * k + 1], yaw_pitch_roll[3 * k + 2], mat + 9 * k);
}
