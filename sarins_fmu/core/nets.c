/* Inference kernels of the trained networks (nets.h). */
#include "smath.h"

#include "nets.h"

#include <string.h>

/* The lane kernels (affine_t, sq_dists below): GCC or clang four-lane vectors, each lane the scalar operation
 * (SSE2's and AVX's mulpd and addpd round as mulsd and addsd, and fp-contract is off, smath.h), compiled for
 * AVX2 too where the loader can pick it, as smath.c's lane functions; other compilers: the scalar loops. */
#if defined(__GNUC__) && defined(__x86_64__) && defined(__ELF__) && defined(__GLIBC__) && defined(__has_attribute)
#if __has_attribute(target_clones)
#define NET_CLONES __attribute__((target_clones("avx2", "default")))
#endif
#endif
#ifndef NET_CLONES
#define NET_CLONES
#endif
#if defined(__GNUC__) || defined(__clang__)
typedef double net_v4 __attribute__((vector_size(32)));
#endif

/* ln 2 as the double nearest to it (numpy's log(2.0)) */
#define NET_LN2 0x1.62e42fefa39efp-1

/* the networks' transcendental functions: the core's own (smath.h): sm_exp for the RBF and GRNN kernels
 * (sm_exp_lanes, the same bits over SIMD lanes, for the truncated GRNN's kept terms), sm_tanh_lanes (below
 * 3 ulp, branch-free over SIMD lanes) for the recurrent gates */
static double net_exp(double x) { return sm_exp(x); }

void sarins_standardize(int64_t n, int64_t d, const double *x, const double *mean, const double *scale, double *z)
{
    for (int64_t i = 0; i < n; i++)
        for (int64_t j = 0; j < d; j++)
            z[i * d + j] = (x[i * d + j] - mean[j]) / scale[j];
}

/* |a - b|^2 over d coordinates, summed in order */
static double sq_dist(int64_t d, const double *a, const double *b)
{
    double s = 0.0;
    for (int64_t i = 0; i < d; i++) {
        double t = a[i] - b[i];
        s += t * t;
    }
    return s;
}

void sarins_rbf_eval(const sarins_rbf *net, int64_t n, const double *x, double *y)
{
    const int64_t d = net->d, m = net->m;
    /* a = exp(-(b dist)^2), b = sqrt(ln 2) / spread: the neuron answers 0.5 at distance spread */
    const double factor = -NET_LN2 / (net->spread * net->spread);
    double z[SARINS_NET_MAX_INPUTS];
    for (int64_t r = 0; r < n; r++) {
        double *out = y + r * m;
        sarins_standardize(1, d, x + r * d, net->mean, net->scale, z);
        for (int64_t o = 0; o < m; o++)
            out[o] = 0.0;
        for (int64_t j = 0; j < net->k; j++) {
            double phi = net_exp(sq_dist(d, z, net->zc + j * d) * factor);
            for (int64_t o = 0; o < m; o++)
                out[o] += phi * net->w[j * m + o];
        }
        for (int64_t o = 0; o < m; o++)
            out[o] = out[o] + net->bias[o];
    }
}

void sarins_grnn_eval(const sarins_grnn *net, int64_t n, const double *x, double *y, double *scratch)
{
    const int64_t d = net->d, m = net->m;
    const double inv_two_var = 1.0 / (2.0 * (net->sigma * net->sigma));
    double z[SARINS_NET_MAX_INPUTS];
    for (int64_t r = 0; r < n; r++) {
        double *out = y + r * m;
        sarins_standardize(1, d, x + r * d, net->mean, net->scale, z);
        double d2_min = INFINITY;
        for (int64_t j = 0; j < net->n; j++) {
            scratch[j] = sq_dist(d, z, net->zt + j * d);
            if (scratch[j] < d2_min)
                d2_min = scratch[j];
        }
        /* P_j / max_j P_j = exp(-(D_j^2 - min D^2) / (2 sigma^2)), eq. (3) shifted: S_D >= 1 */
        double s_d = 0.0;
        for (int64_t o = 0; o < m; o++)
            out[o] = 0.0;
        for (int64_t j = 0; j < net->n; j++) {
            double p = net_exp((d2_min - scratch[j]) * inv_two_var);
            s_d += p;
            for (int64_t o = 0; o < m; o++)
                out[o] += net->y[j * m + o] * p; /* S_j, eq. (5) */
        }
        for (int64_t o = 0; o < m; o++)
            out[o] = out[o] / s_d; /* eq. (6) */
    }
}

void sarins_grnn_gather(const sarins_grnn *net, int64_t n_cand, const int64_t *cand, double *scratch)
{
    const int64_t d = net->d, m = net->m;
    double *zb = scratch + 2 * n_cand, *yb = zb + n_cand * d;
    for (int64_t k = 0; k < n_cand; k++) {
        const double *zk = net->zt + cand[k] * d;
        for (int64_t i = 0; i < d; i++)
            zb[i * n_cand + k] = zk[i];
        memcpy(yb + k * m, net->y + cand[k] * m, (size_t)m * sizeof(double));
    }
}

/* d2[k] = sq_dist(z, candidate k) for the n candidates stored by coordinate (zb[i n + k]), the same sums in
 * the same order (four candidates in the four lanes of a vector); returns the smallest d2[k] (INFINITY if
 * none or all NaN, as the dense loop's d2 < d2_min; the d2 are >= +0, so the minimum's bits are unique) */
NET_CLONES static double sq_dists(int64_t d, int64_t n, const double *z, const double *zb, double *d2)
{
    double d2_min = INFINITY;
    int64_t k = 0;
#if defined(__GNUC__) || defined(__clang__)
    typedef int64_t net_v4i __attribute__((vector_size(32)));
    net_v4 lo = {INFINITY, INFINITY, INFINITY, INFINITY};
    for (; k + 4 <= n; k += 4) {
        net_v4 s = {0.0, 0.0, 0.0, 0.0}, c;
        for (int64_t i = 0; i < d; i++) {
            const net_v4 zi = {z[i], z[i], z[i], z[i]};
            memcpy(&c, zb + i * n + k, sizeof c);
            net_v4 t = zi - c;
            s += t * t;
        }
        memcpy(d2 + k, &s, sizeof s);
        net_v4i lt = (net_v4i)(s < lo);
        lo = (net_v4)((lt & (net_v4i)s) | (~lt & (net_v4i)lo));
    }
    for (int l = 0; l < 4; l++)
        if (lo[l] < d2_min)
            d2_min = lo[l];
#endif
    for (; k < n; k++) {
        double s = 0.0;
        for (int64_t i = 0; i < d; i++) {
            double t = z[i] - zb[i * n + k];
            s += t * t;
        }
        d2[k] = s;
        if (s < d2_min)
            d2_min = s;
    }
    return d2_min;
}

int64_t sarins_grnn_eval_gathered(const sarins_grnn *net, const double *x, int64_t n_cand, double log_cut, double *y,
                                  double *scratch)
{
    const int64_t d = net->d, m = net->m;
    const double inv_two_var = 1.0 / (2.0 * (net->sigma * net->sigma));
    const double *zb = scratch + 2 * n_cand, *yb = zb + n_cand * d;
    double *w = scratch, *idx = scratch + n_cand;
    double z[SARINS_NET_MAX_INPUTS];
    sarins_standardize(1, d, x, net->mean, net->scale, z);
    double d2_min = sq_dists(d, n_cand, z, zb, w);
    /* the dense sum's terms (sarins_grnn_eval), in the same pattern order, those below the cut left out:
     * the exponents of the kept ones packed to the front of w (in place: kept <= k), their candidate numbers
     * in idx, without branches (each written, the count advanced by the test) */
    int64_t kept = 0;
    for (int64_t k = 0; k < n_cand; k++) {
        double e = (d2_min - w[k]) * inv_two_var; /* ln(P_j / max P) */
        w[kept] = e;
        idx[kept] = (double)k;
        kept += !(e < log_cut);
    }
    sm_exp_lanes(kept, w, w); /* sm_exp's bits, as net_exp */
    double s_d = 0.0;
    if (m == 6) { /* the compensator's outputs: the seven sums kept in registers (summed in y they go through
                   * memory at every term, y possibly aliasing the scratch), the same additions in the same order */
        double y0 = 0.0, y1 = 0.0, y2 = 0.0, y3 = 0.0, y4 = 0.0, y5 = 0.0;
        for (int64_t j = 0; j < kept; j++) {
            const double p = w[j], *yk = yb + (int64_t)idx[j] * 6;
            s_d += p;
            y0 += yk[0] * p;
            y1 += yk[1] * p;
            y2 += yk[2] * p;
            y3 += yk[3] * p;
            y4 += yk[4] * p;
            y5 += yk[5] * p;
        }
        y[0] = y0 / s_d;
        y[1] = y1 / s_d;
        y[2] = y2 / s_d;
        y[3] = y3 / s_d;
        y[4] = y4 / s_d;
        y[5] = y5 / s_d;
        return kept;
    }
    for (int64_t o = 0; o < m; o++)
        y[o] = 0.0;
    for (int64_t j = 0; j < kept; j++) {
        const double p = w[j], *yk = yb + (int64_t)idx[j] * m;
        s_d += p;
        for (int64_t o = 0; o < m; o++)
            y[o] += yk[o] * p;
    }
    for (int64_t o = 0; o < m; o++)
        y[o] = y[o] / s_d; /* no candidate: 0 / 0, NaN */
    return kept;
}

void sarins_grnn_eval_blocks(const sarins_grnn *net, int64_t n_blocks, const int64_t *row_ptr,
                             const int64_t *cand_ptr, const int64_t *cand, double log_cut, const double *x, double *y,
                             double *scratch, int64_t *kept)
{
    for (int64_t b = 0; b < n_blocks; b++) {
        int64_t n_cand = cand_ptr[b + 1] - cand_ptr[b];
        sarins_grnn_gather(net, n_cand, cand + cand_ptr[b], scratch);
        for (int64_t r = row_ptr[b]; r < row_ptr[b + 1]; r++) {
            int64_t k = sarins_grnn_eval_gathered(net, x + r * net->d, n_cand, log_cut, y + r * net->m, scratch);
            if (kept != NULL)
                kept[r] = k;
        }
    }
}

void sarins_rnn_transpose(int64_t rows, int64_t cols, const double *src, double *dst)
{
    for (int64_t i = 0; i < rows; i++)
        for (int64_t j = 0; j < cols; j++)
            dst[j * rows + i] = src[i * cols + j];
}

int64_t sarins_rnn_state_size(const sarins_rnn *net) { return 2 * (int64_t)net->layers * net->hidden; }

/* g[rows] = w[rows][cols] v[cols] + b, each row summed in order j = 0 .. cols-1 (four rows at a time: four
 * independent sums, each in the same order, so the result does not depend on the blocking) */
static void affine(int64_t rows, int64_t cols, const double *w, const double *v, const double *b, double *g)
{
    int64_t i = 0;
    for (; i + 4 <= rows; i += 4) {
        const double *w0 = w + i * cols, *w1 = w0 + cols, *w2 = w1 + cols, *w3 = w2 + cols;
        double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
        for (int64_t j = 0; j < cols; j++) {
            s0 += v[j] * w0[j];
            s1 += v[j] * w1[j];
            s2 += v[j] * w2[j];
            s3 += v[j] * w3[j];
        }
        g[i] = s0 + b[i];
        g[i + 1] = s1 + b[i + 1];
        g[i + 2] = s2 + b[i + 2];
        g[i + 3] = s3 + b[i + 3];
    }
    for (; i < rows; i++) {
        double s = 0.0;
        for (int64_t j = 0; j < cols; j++)
            s += v[j] * w[i * cols + j];
        g[i] = s + b[i];
    }
}

/* g[rows] = W v + b with W given transposed, wt[cols][rows] (wt[j][i] = W[i][j]), for n_streams vectors v (the
 * s-th at v + s v_stride, its result at g + s g_stride; skip[s] != 0 (skip may be NULL): stream s left out):
 * each g[i] is summed from 0.0 in order j = 0 .. cols-1 and then b[i] added, exactly as affine does, so the
 * result is the same bit for bit; 32 rows at a time in registers (with GCC or clang as eight four-lane vectors,
 * each lane the scalar operation: SSE2's and AVX's mulpd and addpd round as mulsd and addsd, and fp-contract is
 * off, smath.h; compiled for AVX2 too where the loader can pick it, as smath.c's lane functions).  The streams
 * take each block of rows in turn, so a block's weights (32 cols doubles) are read from memory once for all
 * of them and from the first level of cache for the others. */

NET_CLONES static void affine_t(int64_t rows, int64_t cols, const double *wt, int64_t n_streams, const double *v,
                                int64_t v_stride, const double *b, double *g, int64_t g_stride,
                                const unsigned char *skip)
{
    int64_t i = 0;
#if defined(__GNUC__) || defined(__clang__)
    for (; i + 32 <= rows; i += 32) { /* eight independent sums in flight: the adds' latency hidden */
        for (int64_t s = 0; s < n_streams; s++) {
            if (skip != NULL && skip[s])
                continue;
            const double *vs = v + s * v_stride;
            net_v4 s0 = {0.0, 0.0, 0.0, 0.0}, s1 = s0, s2 = s0, s3 = s0, s4 = s0, s5 = s0, s6 = s0, s7 = s0;
            for (int64_t j = 0; j < cols; j++) {
                const net_v4 vj = {vs[j], vs[j], vs[j], vs[j]};
                const double *col = wt + j * rows + i;
                net_v4 w0, w1, w2, w3, w4, w5, w6, w7;
                memcpy(&w0, col, sizeof w0);
                memcpy(&w1, col + 4, sizeof w1);
                memcpy(&w2, col + 8, sizeof w2);
                memcpy(&w3, col + 12, sizeof w3);
                memcpy(&w4, col + 16, sizeof w4);
                memcpy(&w5, col + 20, sizeof w5);
                memcpy(&w6, col + 24, sizeof w6);
                memcpy(&w7, col + 28, sizeof w7);
                s0 += vj * w0;
                s1 += vj * w1;
                s2 += vj * w2;
                s3 += vj * w3;
                s4 += vj * w4;
                s5 += vj * w5;
                s6 += vj * w6;
                s7 += vj * w7;
            }
            net_v4 acc[8] = {s0, s1, s2, s3, s4, s5, s6, s7}, bias;
            double *gs = g + s * g_stride;
            for (int q = 0; q < 8; q++) {
                memcpy(&bias, b + i + 4 * q, sizeof bias);
                acc[q] += bias;
                memcpy(gs + i + 4 * q, &acc[q], sizeof bias);
            }
        }
    }
    for (; i + 4 <= rows; i += 4) {
        for (int64_t s = 0; s < n_streams; s++) {
            if (skip != NULL && skip[s])
                continue;
            const double *vs = v + s * v_stride;
            net_v4 s0 = {0.0, 0.0, 0.0, 0.0}, w0;
            for (int64_t j = 0; j < cols; j++) {
                const net_v4 vj = {vs[j], vs[j], vs[j], vs[j]};
                memcpy(&w0, wt + j * rows + i, sizeof w0);
                s0 += vj * w0;
            }
            memcpy(&w0, b + i, sizeof w0);
            s0 += w0;
            memcpy(g + s * g_stride + i, &s0, sizeof s0);
        }
    }
#endif
    for (; i < rows; i++) {
        for (int64_t s = 0; s < n_streams; s++) {
            if (skip != NULL && skip[s])
                continue;
            const double *vs = v + s * v_stride;
            double sum = 0.0;
            for (int64_t j = 0; j < cols; j++)
                sum += vs[j] * wt[j * rows + i];
            g[s * g_stride + i] = sum + b[i];
        }
    }
}

/* 1 if every v[k] == 0 (either sign): then every product v[k] w (w finite) is +-0 and a sum of them from
 * 0.0 is +0 exactly (round to nearest: +0 + -0 = +0) */
static int all_zero(int64_t n, const double *v)
{
    for (int64_t k = 0; k < n; k++)
        if (v[k] != 0.0)
            return 0;
    return 1;
}

/* The gates of one layer of one stream from gi = W_ih in + b_ih and gh = W_hh h + b_hh (both [G hid], used as
 * work space): hidden h[hid] and cell c[hid] advanced in place. */
static void rnn_gates(const sarins_rnn *net, double *gi, double *gh, double *h, double *c)
{
    const int64_t hid = net->hidden;
    /* the gate nonlinearities over all lanes at once (sm_tanh_lanes: SIMD, the same bits in every lane), in place
     * in gi and gh: the logistic function as 0.5 (1 + tanh(x / 2)): exact in form, no overflow of exp(-x) */
    if (net->cell == SARINS_RNN_LSTM) {
        for (int64_t k = 0; k < 4 * hid; k++) {
            double s = gi[k] + gh[k];
            gi[k] = k >= 2 * hid && k < 3 * hid ? s : 0.5 * s; /* g: tanh; i, f, o: sigmoid */
        }
        sm_tanh_lanes(4 * hid, gi, gh); /* gh: the tanh of every gate's argument */
        for (int64_t k = 0; k < hid; k++) {
            double i = 0.5 * (1.0 + gh[k]);
            double f = 0.5 * (1.0 + gh[hid + k]);
            double gg = gh[2 * hid + k];
            c[k] = f * c[k] + i * gg; /* c_t = f c_{t-1} + i g */
        }
        sm_tanh_lanes(hid, c, gi); /* gi[0 .. hid-1]: tanh(c_t) */
        for (int64_t k = 0; k < hid; k++) {
            double o = 0.5 * (1.0 + gh[3 * hid + k]);
            h[k] = o * gi[k]; /* h_t = o tanh(c_t) */
        }
        return;
    }
    for (int64_t k = 0; k < 2 * hid; k++)
        gi[k] = 0.5 * (gi[k] + gh[k]); /* r, z: sigmoid, eqs (7), (8) */
    sm_tanh_lanes(2 * hid, gi, gi);
    for (int64_t k = 0; k < hid; k++) {
        double r = 0.5 * (1.0 + gi[k]);
        gh[k] = gi[2 * hid + k] + r * gh[2 * hid + k]; /* (k < hid: reads only what it has not written) */
    }
    sm_tanh_lanes(hid, gh, gh); /* the candidate, eq. (9) */
    for (int64_t k = 0; k < hid; k++) {
        double z = 0.5 * (1.0 + gi[hid + k]);
        h[k] = (1.0 - z) * gh[k] + z * h[k]; /* eq. (10) */
    }
}

/* Layer l of every stream: input in + s in_stride [n_in], state + s state_size advanced in place; gi, gh:
 * n_streams G hid doubles each. */
static void rnn_layer(const sarins_rnn *net, int l, int64_t n_streams, const double *in, int64_t in_stride,
                      int64_t n_in, double *state, int64_t state_size, double *gi, double *gh)
{
    const int64_t hid = net->hidden, rows = (net->cell == SARINS_RNN_LSTM ? 4 : 3) * hid;
    unsigned char zero[SARINS_RNN_MAX_STREAMS];
    double *h = state + l * hid, *c = state + ((int64_t)net->layers + l) * hid;
    affine_t(rows, n_in, net->w_ih[l], n_streams, in, in_stride, net->b_ih[l], gi, rows, NULL);
    for (int64_t s = 0; s < n_streams; s++) {
        /* a zero state (a series' start, a memoryless control): the sums are exactly +0 */
        zero[s] = (unsigned char)all_zero(hid, h + s * state_size);
        if (zero[s])
            for (int64_t k = 0; k < rows; k++)
                gh[s * rows + k] = 0.0 + net->b_hh[l][k]; /* what affine_t gives: 0.0 + (+-0) ... = +0, then + b */
    }
    affine_t(rows, hid, net->w_hh[l], n_streams, h, state_size, net->b_hh[l], gh, rows, zero);
    for (int64_t s = 0; s < n_streams; s++)
        rnn_gates(net, gi + s * rows, gh + s * rows, h + s * state_size, c + s * state_size);
}

void sarins_rnn_step_streams(const sarins_rnn *net, int64_t n_streams, double *state, const double *x, double *y,
                             double *work)
{
    const int64_t hid = net->hidden, size = sarins_rnn_state_size(net);
    double *gi = work, *gh = work + n_streams * (net->cell == SARINS_RNN_LSTM ? 4 : 3) * hid;
    const double *in = x;
    int64_t n_in = net->n_in, in_stride = net->n_in;
    for (int l = 0; l < net->layers; l++) {
        rnn_layer(net, l, n_streams, in, in_stride, n_in, state, size, gi, gh);
        in = state + l * hid;
        n_in = hid;
        in_stride = size;
    }
    for (int64_t s = 0; s < n_streams; s++)
        affine(net->n_out, hid, net->w_out, in + s * size, net->b_out, y + s * net->n_out);
}

void sarins_rnn_step(const sarins_rnn *net, double *state, const double *x, double *y)
{
    double work[2 * 4 * SARINS_RNN_MAX_HIDDEN];
    sarins_rnn_step_streams(net, 1, state, x, y, work);
}

int sarins_triad_compensate(const double *k, const double *b, int64_t n, const double *y, double *u)
{
    /* P K = L U with partial pivoting; L unit lower (below the diagonal of a), U on and above it */
    double a[9];
    int perm[3] = {0, 1, 2};
    memcpy(a, k, sizeof a);
    for (int col = 0; col < 3; col++) {
        int p = col;
        for (int r = col + 1; r < 3; r++)
            if (sm_fabs(a[r * 3 + col]) > sm_fabs(a[p * 3 + col]))
                p = r;
        if (!(a[p * 3 + col] != 0.0) || !isfinite(a[p * 3 + col]))
            return 1;
        if (p != col) {
            for (int j = 0; j < 3; j++) {
                double t = a[col * 3 + j];
                a[col * 3 + j] = a[p * 3 + j];
                a[p * 3 + j] = t;
            }
            int t = perm[col];
            perm[col] = perm[p];
            perm[p] = t;
        }
        for (int r = col + 1; r < 3; r++) {
            double f = a[r * 3 + col] / a[col * 3 + col];
            a[r * 3 + col] = f;
            for (int j = col + 1; j < 3; j++)
                a[r * 3 + j] -= f * a[col * 3 + j];
        }
    }
    for (int64_t i = 0; i < n; i++) {
        double r[3], v[3];
        for (int j = 0; j < 3; j++)
            r[j] = y[i * 3 + j] - b[j];
        for (int j = 0; j < 3; j++) { /* L v = P r */
            v[j] = r[perm[j]];
            for (int q = 0; q < j; q++)
                v[j] -= a[j * 3 + q] * v[q];
        }
        for (int j = 2; j >= 0; j--) { /* U u = v */
            for (int q = j + 1; q < 3; q++)
                v[j] -= a[j * 3 + q] * v[q];
            v[j] = v[j] / a[j * 3 + j];
        }
        memcpy(u + i * 3, v, sizeof v);
    }
    return 0;
}

void sarins_rbf_predict(int64_t d, int64_t k, int64_t m, const double *mean, const double *scale, const double *zc,
                        const double *w, const double *bias, double spread, int64_t n, const double *x, double *y)
{
    const sarins_rbf net = {d, k, m, mean, scale, zc, w, bias, spread};
    sarins_rbf_eval(&net, n, x, y);
}

void sarins_grnn_predict(int64_t d, int64_t n_patterns, int64_t m, const double *mean, const double *scale,
                         const double *zt, const double *yt, double sigma, int64_t n, const double *x, double *y,
                         double *scratch)
{
    const sarins_grnn net = {d, n_patterns, m, mean, scale, zt, yt, sigma};
    sarins_grnn_eval(&net, n, x, y, scratch);
}

void sarins_grnn_predict_blocks(int64_t d, int64_t n_patterns, int64_t m, const double *mean, const double *scale,
                                const double *zt, const double *yt, double sigma, int64_t n_blocks,
                                const int64_t *row_ptr, const int64_t *cand_ptr, const int64_t *cand, double log_cut,
                                const double *x, double *y, double *scratch, int64_t *kept)
{
    const sarins_grnn net = {d, n_patterns, m, mean, scale, zt, yt, sigma};
    sarins_grnn_eval_blocks(&net, n_blocks, row_ptr, cand_ptr, cand, log_cut, x, y, scratch, kept);
}
