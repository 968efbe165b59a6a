/* Trained models built from a binary model file (netfile.h): the seed 000 axial drift identifier and the
 * seed 003 IMU compensators.  Shared by the RBFIdentifier and IMUCompensator FMUs and by the Python library
 * (sarins_fmu/core/nets.py hands the same file bytes to the same builders), so the in-process and the
 * co-simulated evaluations are one computation.
 *
 * Build (allocates: one block for every array the model keeps, freed by the release function) only at
 * initialisation; evaluation never allocates.  Every array of the file is checked for its shape and for
 * finite values (scales, spreads and smoothing factors positive) before use; errors return a non-zero code
 * (SARINS_NETFILE_CONTENT, _MEMORY, _TOO_BIG) and a one-line reason.
 *
 * Axial identifier (kind SARINS_NET_KIND_AXIAL_RBF), arrays: mean, scale [d], centers [k][d] (the inputs'
 * units), weights [k][1] (deg/h), bias [1] (deg/h), spread [] (standardised units), inputs [d] (codes
 * SARINS_AXIAL_IN_*), local_lat_deg [] (deg).  Inputs from the INS: latitude error (rad), azimuth gyro
 * temperature and its change over the alignment (degC); output: the axial gyro drift (deg/h).
 *
 * Compensator (kinds TRADITIONAL .. GRU3) maps x = (Wx, Wy, Wz, Ax, Ay, Az, T) (rad/s, m/s^2, degC) to
 * y = (wx, wy, wz, ax, ay, az) (rad/s, m/s^2).  traditional: gyro_bias, accel_bias [3], gyro_matrix,
 * accel_matrix [3][3], y = K^-1 (W - b) per triad.  The networks give the standardised correction z and
 * y = x[0..5] + z target_scale + target_mean (target_mean, target_scale [6]): rbf net.mean, net.scale [7],
 * net.centers [k][7], net.weights [k][6], net.bias [6], net.spread []; grnn net.mean, net.scale [7],
 * net.x_train [n][7], net.y_train [n][6], net.sigma []; lstm, gru (1 layer), lstm3, gru3 (3 layers):
 * input_mean, input_scale [7] (z_in = (x - mean) / scale), memory [] (1: the state is carried from sample
 * to sample, 0: every sample from a zero state), per layer l net.w_ih, net.w_hh, net.b_ih, net.b_hh (layer
 * 0) and net.w_ih_l<l>, ... (layers 1, 2), net.w_out [6][h], net.b_out [6] (PyTorch layout, nets.h).
 */
#ifndef SARINS_NETMODEL_H
#define SARINS_NETMODEL_H

#include <stddef.h>
#include <stdint.h>

#include "netfile.h"
#include "nets.h"

#define SARINS_COMP_N_IN 7
#define SARINS_COMP_N_OUT 6
#define SARINS_COMP_MAX_STATE (2 * SARINS_RNN_MAX_LAYERS * SARINS_RNN_MAX_HIDDEN) /* doubles */

enum { SARINS_AXIAL_IN_LAT_ERROR_DEG = 0, SARINS_AXIAL_IN_LAT_DEG = 1, SARINS_AXIAL_IN_TEMP_C = 2,
       SARINS_AXIAL_IN_TEMP_CHANGE_C = 3 };
#define SARINS_AXIAL_MAX_INPUTS 4

/* evaluation statuses */
enum { SARINS_NET_OK = 0, SARINS_NET_INPUT = 1 /* a used input is not finite */,
       SARINS_NET_OUTPUT = 2 /* the result is not finite */, SARINS_NET_SINGULAR = 3 /* a singular K */,
       SARINS_NET_KIND = 4 /* the call needs another kind of model */ };

typedef struct {
    sarins_rbf rbf;
    int n_inputs;
    int inputs[SARINS_AXIAL_MAX_INPUTS]; /* SARINS_AXIAL_IN_* per network input */
    double local_lat_deg;                /* deg: the training site */
    double *block;                       /* owned */
} sarins_axial;

typedef struct {
    uint32_t kind; /* SARINS_NET_KIND_TRADITIONAL .. _GRU3 */
    int memory;
    double gyro_k[9], gyro_b[3], accel_k[9], accel_b[3];
    double in_mean[SARINS_COMP_N_IN], in_scale[SARINS_COMP_N_IN];
    double target_mean[SARINS_COMP_N_OUT], target_scale[SARINS_COMP_N_OUT];
    sarins_rbf rbf;
    sarins_grnn grnn;
    sarins_rnn rnn;
    double *block;   /* owned: every array of the model */
    double *scratch; /* owned: GRNN pattern distances [n] (used when the caller gives none) */
} sarins_comp;

int sarins_axial_build(sarins_axial *a, const sarins_netfile *f, char *msg, size_t msg_len);
void sarins_axial_release(sarins_axial *a);
/* drift (deg/h) from the latitude error (rad) and the temperatures (degC; only those the model uses must be
 * finite); SARINS_NET_* status. */
int sarins_axial_drift(const sarins_axial *a, double lat_error, double temp_c, double temp_change_c,
                       double *drift_dph);

int sarins_comp_build(sarins_comp *c, const sarins_netfile *f, char *msg, size_t msg_len);
void sarins_comp_release(sarins_comp *c);
/* doubles of the state a caller keeps between samples (0: none; at most SARINS_COMP_MAX_STATE) */
int64_t sarins_comp_state_size(const sarins_comp *c);
/* doubles of the scratch a GRNN needs per evaluation (0 for the other kinds) */
int64_t sarins_comp_scratch_size(const sarins_comp *c);

/* Doubles of sarins_comp_run_grnn_blocks' scratch per candidate of the largest block (2 + d + 6; 0 when c is
 * not a GRNN). */
int64_t sarins_comp_grnn_per_candidate(const sarins_comp *c);

/* compensate n time-ordered samples x[n][7] -> y[n][6], the recurrent state advanced in place (zero it to
 * start a series); scratch: sarins_comp_scratch_size doubles of the caller's, or NULL to use the model's own
 * (then one evaluation at a time per model; with the caller's, the model is only read and several threads
 * may share it).  SARINS_NET_* status (x non-finite: SARINS_NET_INPUT, nothing written for that row on). */
int sarins_comp_run(const sarins_comp *c, double *state, int64_t n, const double *x, double *y, double *scratch);

/* Doubles of sarins_comp_run_streams' work for n_streams series (0 when c is not recurrent). */
int64_t sarins_comp_streams_work(const sarins_comp *c, int64_t n_streams);

/* sarins_comp_run of n_streams (1 .. SARINS_RNN_MAX_STREAMS) independent series of a recurrent compensator side by
 * side, n samples each: x[s][n][7] -> y[s][n][6], states[s][sarins_comp_state_size] advanced in place; each
 * series' numbers are sarins_comp_run's bit for bit (the in-process batch evaluation: the series share the
 * weights while they are in cache).  work: sarins_comp_streams_work doubles.  SARINS_NET_* status
 * (SARINS_NET_KIND when c is not recurrent or n_streams is out of range; x non-finite: SARINS_NET_INPUT). */
int sarins_comp_run_streams(const sarins_comp *c, int64_t n_streams, double *states, int64_t n, const double *x,
                            double *y, double *work);

/* The truncated GRNN (sarins_grnn_eval_blocks, nets.h) of a GRNN compensator over the rows x[n][7] -> y[n][6],
 * row_ptr, cand_ptr, cand, log_cut, kept as there; scratch holds the largest block's candidate count times
 * (2 + d + 6) doubles, d the GRNN's inputs (sarins_grnn_block_scratch, nets.h).  The
 * in-process batch evaluation (the IMUCompensator FMU runs the dense sarins_comp_run).  SARINS_NET_* status
 * (SARINS_NET_KIND when c is not a GRNN). */
int sarins_comp_run_grnn_blocks(const sarins_comp *c, int64_t n_blocks, const int64_t *row_ptr,
                                const int64_t *cand_ptr, const int64_t *cand, double log_cut, const double *x,
                                double *y, double *scratch, int64_t *kept);

/* Handles for the ctypes binding: parse + build from bytes (NULL with a reason on failure), free. */
sarins_axial *sarins_axial_open(const unsigned char *buf, size_t n, char *msg, size_t msg_len);
void sarins_axial_close(sarins_axial *a);
sarins_comp *sarins_comp_open(const unsigned char *buf, size_t n, char *msg, size_t msg_len);
void sarins_comp_close(sarins_comp *c);
int sarins_comp_kind(const sarins_comp *c);

#endif
