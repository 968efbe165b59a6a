/* Inference kernels of the trained networks: RBF (seed 000 eqs (1)-(2), seed 003), dense GRNN (seed 003
 * eqs (3)-(6)), LSTM and GRU cells (seed 003 eqs (7)-(10)) and the triad calibration inverse (seed 003
 * eqs (1)-(2)).  The Python library calls them through ctypes (sarins_fmu/core/nets.py) and the FMUs link
 * them, so both compute the same numbers bit for bit.  Training stays in Python.
 *
 * Units: whatever the model was trained on; the kernels are unit-free (a standardised input z is
 * dimensionless).  Arrays are row-major float64.  No allocation, no globals, reentrant; the exponential and
 * the hyperbolic tangent are evaluated in nets.c's two math helpers only.
 */
#ifndef SARINS_NETS_H
#define SARINS_NETS_H

#include <stdint.h>

#define SARINS_RNN_MAX_HIDDEN 256 /* most units of a recurrent layer */
#define SARINS_RNN_MAX_LAYERS 3   /* most stacked recurrent layers */
#define SARINS_RNN_MAX_STREAMS 8  /* most series one call of sarins_rnn_step_streams advances */
#define SARINS_RNN_MAX_IO 64      /* most inputs / outputs of a recurrent network */
#define SARINS_NET_MAX_INPUTS 64  /* most inputs d of an RBF or GRNN row */

enum { SARINS_RNN_LSTM = 0, SARINS_RNN_GRU = 1 };

/* Gaussian RBF network with m outputs:
 *   y_o = sum_j w[j][o] exp(-ln2 |z(x) - zc_j|^2 / spread^2) + bias_o,  z(x) = (x - mean) / scale,
 * zc the standardised centres (sarins_standardize of the centres).  The sum runs over j = 0 .. k-1 in order. */
typedef struct {
    int64_t d, k, m;
    const double *mean, *scale; /* [d] */
    const double *zc;           /* [k][d] */
    const double *w;            /* [k][m] */
    const double *bias;         /* [m] */
    double spread;              /* > 0, standardised units */
} sarins_rbf;

/* Dense GRNN (Nadaraya-Watson) with m outputs: P_j = exp(-(D_j^2 - min D^2) / (2 sigma^2)),
 * y_o = sum_j y[j][o] P_j / sum_j P_j over every pattern, D_j = |z(x) - zt_j| (the largest weight is 1). */
typedef struct {
    int64_t d, n, m;
    const double *mean, *scale; /* [d] */
    const double *zt;           /* [n][d] standardised patterns */
    const double *y;            /* [n][m] */
    double sigma;               /* > 0, standardised units */
} sarins_grnn;

/* Stacked LSTM or GRU (PyTorch layout and gate order: LSTM i f g o, GRU r z n) with a linear output.
 * Layer l: w_ih [G h][n_in or h], w_hh [G h][h], b_ih, b_hh [G h]; w_out [n_out][h], b_out [n_out].  The kernel
 * reads w_ih and w_hh transposed: w_ih [n_in or h][G h], w_hh [h][G h] (sarins_rnn_transpose; the sums are those
 * of PyTorch's layout, in the same order, bit for bit). */
typedef struct {
    int cell; /* SARINS_RNN_LSTM or SARINS_RNN_GRU */
    int layers;
    int64_t hidden, n_in, n_out;
    const double *w_ih[SARINS_RNN_MAX_LAYERS], *w_hh[SARINS_RNN_MAX_LAYERS];
    const double *b_ih[SARINS_RNN_MAX_LAYERS], *b_hh[SARINS_RNN_MAX_LAYERS];
    const double *w_out, *b_out;
} sarins_rnn;

/* z[n][d] = (x[n][d] - mean) / scale (z may be x). */
void sarins_standardize(int64_t n, int64_t d, const double *x, const double *mean, const double *scale, double *z);

/* RBF outputs y[n][m] of the inputs x[n][d]. */
void sarins_rbf_eval(const sarins_rbf *net, int64_t n, const double *x, double *y);

/* GRNN outputs y[n][m] of the inputs x[n][d]; scratch holds net->n doubles. */
void sarins_grnn_eval(const sarins_grnn *net, int64_t n, const double *x, double *y, double *scratch);

/* Candidates gathered for sarins_grnn_eval_gathered (cand[0 .. n_cand-1]: pattern indices, ascending, in
 * [0, net->n)): scratch[2 n_cand .. 2 n_cand + d n_cand - 1] the candidates' standardised patterns by
 * coordinate, zt[cand[k]][i] at 2 n_cand + i n_cand + k (so that the distances run in SIMD lanes), then n_cand m
 * doubles their targets y[cand[k]][m] (scratch holds sarins_grnn_block_scratch(net, n_cand) doubles; the first
 * 2 n_cand are sarins_grnn_eval_gathered's work space). */
void sarins_grnn_gather(const sarins_grnn *net, int64_t n_cand, const int64_t *cand, double *scratch);

/* Truncated GRNN (exact to a bound): the output y[m] of one input x[d] over the n_cand candidate patterns
 * sarins_grnn_gather put in scratch, keeping the terms whose weight relative to the largest candidate's,
 * P_j / max P = exp(-(D_j^2 - min D^2) / (2 sigma^2)), is at least exp(log_cut).  The kept terms are those of
 * sarins_grnn_eval in the same order, so with every pattern a candidate and nothing cut the result is the dense one
 * bit for bit.  The candidates must hold the query's nearest pattern and every pattern above the cut
 * (sarins_fmu/identify/grnn.py finds them with a k-d tree; the error bound is derived there).  Returns the number
 * of kept terms (no candidate: y is NaN, 0 returned). */
int64_t sarins_grnn_eval_gathered(const sarins_grnn *net, const double *x, int64_t n_cand, double log_cut, double *y,
                                  double *scratch);

/* Doubles of scratch sarins_grnn_gather and sarins_grnn_eval_gathered need for n_cand candidates: n_cand (2 + d + m)
 * (per query, the candidates' distances then kept weights, and the kept candidates' numbers). */
static inline int64_t sarins_grnn_block_scratch(const sarins_grnn *net, int64_t n_cand)
{
    return n_cand * (2 + net->d + net->m);
}

/* sarins_grnn_eval_gathered for the rows row_ptr[b] .. row_ptr[b+1]-1 of x[][d] and y[][m], block b's
 * candidates cand[cand_ptr[b] .. cand_ptr[b+1]-1] (gathered once per block); scratch holds
 * sarins_grnn_block_scratch of the largest block's candidate count; kept[row] (may be NULL) receives each row's
 * kept terms. */
void sarins_grnn_eval_blocks(const sarins_grnn *net, int64_t n_blocks, const int64_t *row_ptr,
                             const int64_t *cand_ptr, const int64_t *cand, double log_cut, const double *x, double *y,
                             double *scratch, int64_t *kept);

/* Doubles of a network's state: h then c, each [layers][hidden] (c unused by the GRU). */
int64_t sarins_rnn_state_size(const sarins_rnn *net);

/* dst[cols][rows] = src[rows][cols] (the layout of sarins_rnn's w_ih, w_hh; dst and src must not overlap). */
void sarins_rnn_transpose(int64_t rows, int64_t cols, const double *src, double *dst);

/* One time step: input x[n_in], state advanced in place, output y[n_out]. */
void sarins_rnn_step(const sarins_rnn *net, double *state, const double *x, double *y);

/* One time step of n_streams (1 .. SARINS_RNN_MAX_STREAMS) independent series side by side: inputs x[s][n_in],
 * states state[s][sarins_rnn_state_size] advanced in place, outputs y[s][n_out]; each stream's numbers are those
 * of sarins_rnn_step bit for bit (the streams share each block of weights while it is in cache); work holds
 * sarins_rnn_streams_work(net, n_streams) doubles. */
void sarins_rnn_step_streams(const sarins_rnn *net, int64_t n_streams, double *state, const double *x, double *y,
                             double *work);

/* Doubles of sarins_rnn_step_streams' work: 2 n_streams G hidden (G = 4 for the LSTM, 3 for the GRU). */
static inline int64_t sarins_rnn_streams_work(const sarins_rnn *net, int64_t n_streams)
{
    return 2 * n_streams * (net->cell == SARINS_RNN_LSTM ? 4 : 3) * net->hidden;
}

/* u[n][3] = K^-1 (y[n][3] - b), K (3 x 3, row-major) by LU with partial pivoting.  Returns 0, or 1 when K is
 * singular (u untouched). */
int sarins_triad_compensate(const double *k, const double *b, int64_t n, const double *y, double *u);

/* Flat-argument forms for the ctypes binding (the same computations). */
void sarins_rbf_predict(int64_t d, int64_t k, int64_t m, const double *mean, const double *scale, const double *zc,
                        const double *w, const double *bias, double spread, int64_t n, const double *x, double *y);
void sarins_grnn_predict(int64_t d, int64_t n_patterns, int64_t m, const double *mean, const double *scale,
                         const double *zt, const double *yt, double sigma, int64_t n, const double *x, double *y,
                         double *scratch);
void sarins_grnn_predict_blocks(int64_t d, int64_t n_patterns, int64_t m, const double *mean, const double *scale,
                                const double *zt, const double *yt, double sigma, int64_t n_blocks,
                                const int64_t *row_ptr, const int64_t *cand_ptr, const int64_t *cand, double log_cut,
                                const double *x, double *y, double *scratch, int64_t *kept);

#endif
