/* Trained models built from a binary model file (netmodel.h). */
#include "smath.h"

#include "netmodel.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define ANY (-1)

static int fail(char *msg, size_t msg_len, int code, const char *fmt, ...)
{
    if (msg != NULL && msg_len > 0) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(msg, msg_len, fmt, ap);
        va_end(ap);
    }
    return code;
}

enum { FINITE = 0, POSITIVE = 1 };

/* The array `name` with ndim dimensions of sizes d0, d1 (ANY: any size; *n0 gets dim 0), every
 * element finite (POSITIVE: and > 0); NULL with a reason in msg. */
static const sarins_netfile_array *want(const sarins_netfile *f, const char *name, uint32_t ndim, int64_t d0,
                                        int64_t d1, int rule, int64_t *n0, char *msg, size_t msg_len)
{
    const sarins_netfile_array *a = sarins_netfile_find(f, name);
    if (a == NULL) {
        fail(msg, msg_len, 0, "the model lacks the array '%s'", name);
        return NULL;
    }
    int64_t want0 = ndim >= 1 ? d0 : 1, want1 = ndim >= 2 ? d1 : 1;
    if (a->ndim != ndim || (want0 != ANY && a->dim[0] != (uint64_t)want0)
        || (want1 != ANY && a->dim[1] != (uint64_t)want1)) {
        fail(msg, msg_len, 0, "array '%s' has ndim %u and shape (%llu, %llu), expected ndim %u and (%lld, %lld) "
             "(-1: any)", name, (unsigned)a->ndim, (unsigned long long)a->dim[0], (unsigned long long)a->dim[1],
             (unsigned)ndim, (long long)want0, (long long)want1);
        return NULL;
    }
    for (uint64_t i = 0; i < a->count; i++) {
        double v = sarins_netfile_value(f, a, i);
        if (!isfinite(v) || (rule == POSITIVE && !(v > 0.0))) {
            fail(msg, msg_len, 0, "array '%s' element %llu is %.17g (%s)", name, (unsigned long long)i, v,
                 rule == POSITIVE ? "must be positive and finite" : "must be finite");
            return NULL;
        }
    }
    if (n0 != NULL)
        *n0 = (int64_t)a->dim[0];
    return a;
}

static void copy(const sarins_netfile *f, const sarins_netfile_array *a, double *dst)
{
    for (uint64_t i = 0; i < a->count; i++)
        dst[i] = sarins_netfile_value(f, a, i);
}

static double scalar(const sarins_netfile *f, const sarins_netfile_array *a) { return sarins_netfile_value(f, a, 0); }

/* ---------------------------------------------------------------- RBF (axial and compensator) */

/* The RBF network under `prefix` (d inputs, m outputs; weights [k][m]); net arrays point into a new block
 * (*block, freed by the caller). */
static int build_rbf(sarins_rbf *net, double **block, const sarins_netfile *f, const char *prefix, int64_t d,
                     int64_t m, char *msg, size_t msg_len)
{
    char name[4][48];
    static const char *const parts[4] = {"mean", "scale", "centers", "weights"};
    for (int i = 0; i < 4; i++)
        snprintf(name[i], sizeof name[i], "%s%s", prefix, parts[i]);
    char bname[48], sname[48];
    snprintf(bname, sizeof bname, "%sbias", prefix);
    snprintf(sname, sizeof sname, "%sspread", prefix);
    int64_t k = 0;
    const sarins_netfile_array *mean = want(f, name[0], 1, d, 1, FINITE, NULL, msg, msg_len);
    const sarins_netfile_array *scale = mean ? want(f, name[1], 1, d, 1, POSITIVE, NULL, msg, msg_len) : NULL;
    const sarins_netfile_array *centers = scale ? want(f, name[2], 2, ANY, d, FINITE, &k, msg, msg_len) : NULL;
    const sarins_netfile_array *w = centers ? want(f, name[3], 2, k, m, FINITE, NULL, msg, msg_len) : NULL;
    const sarins_netfile_array *bias = w ? want(f, bname, 1, m, 1, FINITE, NULL, msg, msg_len) : NULL;
    const sarins_netfile_array *spread = bias ? want(f, sname, 0, 1, 1, POSITIVE, NULL, msg, msg_len) : NULL;
    if (spread == NULL)
        return SARINS_NETFILE_CONTENT;
    size_t total = (size_t)(2 * d + k * d + k * m + m);
    double *b = malloc((total ? total : 1) * sizeof(double));
    if (b == NULL)
        return fail(msg, msg_len, SARINS_NETFILE_MEMORY, "out of memory for an RBF network of %lld centres",
                    (long long)k);
    double *p = b;
    net->d = d, net->k = k, net->m = m;
    copy(f, mean, p), net->mean = p, p += d;
    copy(f, scale, p), net->scale = p, p += d;
    copy(f, centers, p);
    sarins_standardize(k, d, p, net->mean, net->scale, p); /* the centres in standardised units */
    net->zc = p, p += k * d;
    copy(f, w, p), net->w = p, p += k * m;
    copy(f, bias, p), net->bias = p;
    net->spread = scalar(f, spread);
    *block = b;
    return SARINS_NETFILE_OK;
}

/* ---------------------------------------------------------------- axial identifier */

int sarins_axial_build(sarins_axial *a, const sarins_netfile *f, char *msg, size_t msg_len)
{
    memset(a, 0, sizeof *a);
    if (f->kind != SARINS_NET_KIND_AXIAL_RBF)
        return fail(msg, msg_len, SARINS_NETFILE_CONTENT, "model kind %u is not an axial drift identifier (%d)",
                    (unsigned)f->kind, SARINS_NET_KIND_AXIAL_RBF);
    int64_t d = 0;
    const sarins_netfile_array *inputs = want(f, "inputs", 1, ANY, 1, FINITE, &d, msg, msg_len);
    if (inputs == NULL)
        return SARINS_NETFILE_CONTENT;
    if (d < 1 || d > SARINS_AXIAL_MAX_INPUTS)
        return fail(msg, msg_len, SARINS_NETFILE_CONTENT, "%lld inputs (1 .. %d)", (long long)d,
                    SARINS_AXIAL_MAX_INPUTS);
    for (int64_t i = 0; i < d; i++) {
        double code = sarins_netfile_value(f, inputs, (uint64_t)i);
        if (!(code == 0.0 || code == 1.0 || code == 2.0 || code == 3.0))
            return fail(msg, msg_len, SARINS_NETFILE_CONTENT, "input %lld has code %.17g (0 lat_error_deg, 1 "
                        "lat_deg, 2 temp_c, 3 temp_change_c)", (long long)i, code);
        a->inputs[i] = (int)code;
    }
    a->n_inputs = (int)d;
    const sarins_netfile_array *lat = want(f, "local_lat_deg", 0, 1, 1, FINITE, NULL, msg, msg_len);
    if (lat == NULL)
        return SARINS_NETFILE_CONTENT;
    a->local_lat_deg = scalar(f, lat);
    if (!(sm_fabs(a->local_lat_deg) <= 90.0))
        return fail(msg, msg_len, SARINS_NETFILE_CONTENT, "local_lat_deg %.17g is not a latitude within +-90 deg",
                    a->local_lat_deg);
    return build_rbf(&a->rbf, &a->block, f, "", d, 1, msg, msg_len);
}

void sarins_axial_release(sarins_axial *a)
{
    if (a != NULL) {
        free(a->block);
        a->block = NULL;
    }
}

#define RAD_TO_DEG (180.0 / 3.141592653589793) /* deg per rad, as sarins_fmu.units.RAD_TO_DEG */

int sarins_axial_drift(const sarins_axial *a, double lat_error, double temp_c, double temp_change_c,
                       double *drift_dph)
{
    double lat_error_deg = lat_error * RAD_TO_DEG;
    const double values[SARINS_AXIAL_MAX_INPUTS] = {lat_error_deg, a->local_lat_deg + lat_error_deg, temp_c,
                                                    temp_change_c};
    double row[SARINS_AXIAL_MAX_INPUTS];
    for (int i = 0; i < a->n_inputs; i++) {
        row[i] = values[a->inputs[i]];
        if (!isfinite(row[i]))
            return SARINS_NET_INPUT;
    }
    sarins_rbf_eval(&a->rbf, 1, row, drift_dph);
    return isfinite(*drift_dph) ? SARINS_NET_OK : SARINS_NET_OUTPUT;
}

/* ---------------------------------------------------------------- compensators */

static int build_traditional(sarins_comp *c, const sarins_netfile *f, char *msg, size_t msg_len)
{
    const sarins_netfile_array *a;
    static const char *const names[4] = {"gyro_bias", "gyro_matrix", "accel_bias", "accel_matrix"};
    double *dst[4] = {c->gyro_b, c->gyro_k, c->accel_b, c->accel_k};
    for (int i = 0; i < 4; i++) {
        a = want(f, names[i], i % 2 ? 2 : 1, 3, 3, FINITE, NULL, msg, msg_len);
        if (a == NULL)
            return SARINS_NETFILE_CONTENT;
        copy(f, a, dst[i]);
    }
    return SARINS_NETFILE_OK;
}

static int load_fixed(const sarins_netfile *f, const char *name, int64_t n, int rule, double *dst, char *msg,
                      size_t msg_len)
{
    const sarins_netfile_array *a = want(f, name, 1, n, 1, rule, NULL, msg, msg_len);
    if (a == NULL)
        return SARINS_NETFILE_CONTENT;
    copy(f, a, dst);
    return SARINS_NETFILE_OK;
}

static int build_grnn(sarins_comp *c, const sarins_netfile *f, char *msg, size_t msg_len)
{
    const int64_t d = SARINS_COMP_N_IN, m = SARINS_COMP_N_OUT;
    int64_t n = 0;
    const sarins_netfile_array *mean = want(f, "net.mean", 1, d, 1, FINITE, NULL, msg, msg_len);
    const sarins_netfile_array *scale = mean ? want(f, "net.scale", 1, d, 1, POSITIVE, NULL, msg, msg_len) : NULL;
    const sarins_netfile_array *x = scale ? want(f, "net.x_train", 2, ANY, d, FINITE, &n, msg, msg_len) : NULL;
    const sarins_netfile_array *y = x ? want(f, "net.y_train", 2, n, m, FINITE, NULL, msg, msg_len) : NULL;
    const sarins_netfile_array *sigma = y ? want(f, "net.sigma", 0, 1, 1, POSITIVE, NULL, msg, msg_len) : NULL;
    if (sigma == NULL)
        return SARINS_NETFILE_CONTENT;
    if (n < 1)
        return fail(msg, msg_len, SARINS_NETFILE_CONTENT, "a GRNN needs at least one pattern");
    double *b = malloc((size_t)(2 * d + n * d + n * m + n) * sizeof(double));
    if (b == NULL)
        return fail(msg, msg_len, SARINS_NETFILE_MEMORY, "out of memory for a GRNN of %lld patterns", (long long)n);
    sarins_grnn *g = &c->grnn;
    double *p = b;
    g->d = d, g->n = n, g->m = m;
    copy(f, mean, p), g->mean = p, p += d;
    copy(f, scale, p), g->scale = p, p += d;
    copy(f, x, p);
    sarins_standardize(n, d, p, g->mean, g->scale, p);
    g->zt = p, p += n * d;
    copy(f, y, p), g->y = p, p += n * m;
    c->scratch = p;
    g->sigma = scalar(f, sigma);
    c->block = b;
    return SARINS_NETFILE_OK;
}

static int build_rnn(sarins_comp *c, const sarins_netfile *f, char *msg, size_t msg_len)
{
    sarins_rnn *r = &c->rnn;
    int lstm = c->kind == SARINS_NET_KIND_LSTM || c->kind == SARINS_NET_KIND_LSTM3;
    r->cell = lstm ? SARINS_RNN_LSTM : SARINS_RNN_GRU;
    r->layers = (c->kind == SARINS_NET_KIND_LSTM3 || c->kind == SARINS_NET_KIND_GRU3) ? 3 : 1;
    r->n_in = SARINS_COMP_N_IN;
    r->n_out = SARINS_COMP_N_OUT;
    const int64_t g = lstm ? 4 : 3;
    int64_t gh = 0;
    const sarins_netfile_array *whh0 = want(f, "net.w_hh", 2, ANY, ANY, FINITE, &gh, msg, msg_len);
    if (whh0 == NULL)
        return SARINS_NETFILE_CONTENT;
    const int64_t h = (int64_t)whh0->dim[1];
    if (h < 1 || h > SARINS_RNN_MAX_HIDDEN || gh != g * h)
        return fail(msg, msg_len, SARINS_NETFILE_CONTENT, "net.w_hh has shape (%lld, %lld): expected (%lld h, h) "
                    "with 1 <= h <= %d", (long long)gh, (long long)h, (long long)g, SARINS_RNN_MAX_HIDDEN);
    r->hidden = h;
    char extra[48];
    snprintf(extra, sizeof extra, "net.w_ih_l%d", r->layers);
    if (sarins_netfile_find(f, extra) != NULL)
        return fail(msg, msg_len, SARINS_NETFILE_CONTENT, "the file holds more than the %d recurrent layer(s) of "
                    "its kind", r->layers);
    const sarins_netfile_array *arr[SARINS_RNN_MAX_LAYERS][4];
    size_t total = 0;
    for (int l = 0; l < r->layers; l++) {
        static const char *const base[4] = {"net.w_ih", "net.w_hh", "net.b_ih", "net.b_hh"};
        for (int q = 0; q < 4; q++) {
            char name[48];
            if (l == 0)
                snprintf(name, sizeof name, "%s", base[q]);
            else
                snprintf(name, sizeof name, "%s_l%d", base[q], l);
            int64_t cols = q == 0 ? (l == 0 ? r->n_in : h) : h;
            arr[l][q] = q < 2 ? want(f, name, 2, g * h, cols, FINITE, NULL, msg, msg_len)
                              : want(f, name, 1, g * h, 1, FINITE, NULL, msg, msg_len);
            if (arr[l][q] == NULL)
                return SARINS_NETFILE_CONTENT;
            total += (size_t)arr[l][q]->count;
        }
    }
    const sarins_netfile_array *wout = want(f, "net.w_out", 2, r->n_out, h, FINITE, NULL, msg, msg_len);
    const sarins_netfile_array *bout = wout ? want(f, "net.b_out", 1, r->n_out, 1, FINITE, NULL, msg, msg_len)
                                            : NULL;
    const sarins_netfile_array *memory = bout ? want(f, "memory", 0, 1, 1, FINITE, NULL, msg, msg_len) : NULL;
    if (memory == NULL)
        return SARINS_NETFILE_CONTENT;
    double mem = scalar(f, memory);
    if (mem != 0.0 && mem != 1.0)
        return fail(msg, msg_len, SARINS_NETFILE_CONTENT, "memory is %.17g (0 or 1)", mem);
    c->memory = mem == 1.0;
    int status = load_fixed(f, "input_mean", SARINS_COMP_N_IN, FINITE, c->in_mean, msg, msg_len);
    if (status == SARINS_NETFILE_OK)
        status = load_fixed(f, "input_scale", SARINS_COMP_N_IN, POSITIVE, c->in_scale, msg, msg_len);
    if (status != SARINS_NETFILE_OK)
        return status;
    total += (size_t)(wout->count + bout->count);
    /* + one scratch matrix for the transposition of the largest weight (G h x max(n_in, h)) */
    const int64_t widest = r->n_in > h ? r->n_in : h;
    double *b = malloc((total + (size_t)(g * h * widest)) * sizeof(double));
    if (b == NULL)
        return fail(msg, msg_len, SARINS_NETFILE_MEMORY, "out of memory for a recurrent network of %lld units",
                    (long long)h);
    double *p = b;
    for (int l = 0; l < r->layers; l++) {
        const double **dst[4] = {&r->w_ih[l], &r->w_hh[l], &r->b_ih[l], &r->b_hh[l]};
        for (int q = 0; q < 4; q++) {
            copy(f, arr[l][q], p);
            *dst[q] = p;
            p += arr[l][q]->count;
        }
    }
    copy(f, wout, p), r->w_out = p, p += wout->count;
    copy(f, bout, p), r->b_out = p, p += bout->count;
    for (int l = 0; l < r->layers; l++) /* the kernel's layout: w_ih, w_hh transposed (nets.h) */
        for (int q = 0; q < 2; q++) {
            double *w = (double *)(q == 0 ? r->w_ih[l] : r->w_hh[l]);
            int64_t cols = q == 0 ? (l == 0 ? r->n_in : h) : h;
            memcpy(p, w, (size_t)(g * h * cols) * sizeof(double));
            sarins_rnn_transpose(g * h, cols, p, w);
        }
    c->block = b;
    return SARINS_NETFILE_OK;
}

int sarins_comp_build(sarins_comp *c, const sarins_netfile *f, char *msg, size_t msg_len)
{
    memset(c, 0, sizeof *c);
    c->kind = f->kind;
    if (f->kind < SARINS_NET_KIND_TRADITIONAL || f->kind > SARINS_NET_KIND_GRU3)
        return fail(msg, msg_len, SARINS_NETFILE_CONTENT, "model kind %u is not a compensator (%d .. %d)",
                    (unsigned)f->kind, SARINS_NET_KIND_TRADITIONAL, SARINS_NET_KIND_GRU3);
    if (f->kind == SARINS_NET_KIND_TRADITIONAL)
        return build_traditional(c, f, msg, msg_len);
    int status = load_fixed(f, "target_mean", SARINS_COMP_N_OUT, FINITE, c->target_mean, msg, msg_len);
    if (status == SARINS_NETFILE_OK)
        status = load_fixed(f, "target_scale", SARINS_COMP_N_OUT, POSITIVE, c->target_scale, msg, msg_len);
    if (status != SARINS_NETFILE_OK)
        return status;
    if (f->kind == SARINS_NET_KIND_RBF)
        status = build_rbf(&c->rbf, &c->block, f, "net.", SARINS_COMP_N_IN, SARINS_COMP_N_OUT, msg, msg_len);
    else if (f->kind == SARINS_NET_KIND_GRNN)
        status = build_grnn(c, f, msg, msg_len);
    else
        status = build_rnn(c, f, msg, msg_len);
    if (status != SARINS_NETFILE_OK)
        sarins_comp_release(c);
    return status;
}

void sarins_comp_release(sarins_comp *c)
{
    if (c != NULL) {
        free(c->block);
        c->block = NULL;
        c->scratch = NULL;
    }
}

int64_t sarins_comp_state_size(const sarins_comp *c)
{
    return c->kind >= SARINS_NET_KIND_LSTM ? sarins_rnn_state_size(&c->rnn) : 0;
}

int64_t sarins_comp_scratch_size(const sarins_comp *c) { return c->kind == SARINS_NET_KIND_GRNN ? c->grnn.n : 0; }

int64_t sarins_comp_grnn_per_candidate(const sarins_comp *c)
{
    return c->kind == SARINS_NET_KIND_GRNN ? sarins_grnn_block_scratch(&c->grnn, 1) : 0;
}

static int inputs_finite(const double *x)
{
    for (int i = 0; i < SARINS_COMP_N_IN; i++)
        if (!isfinite(x[i]))
            return 0;
    return 1;
}

/* a network's standardised correction z -> y = x + z s + m (the correction undone), checked finite */
static int comp_finish(const sarins_comp *c, const double *x, const double *z, double *y)
{
    for (int o = 0; o < SARINS_COMP_N_OUT; o++)
        y[o] = x[o] + z[o] * c->target_scale[o] + c->target_mean[o];
    for (int o = 0; o < SARINS_COMP_N_OUT; o++)
        if (!isfinite(y[o]))
            return SARINS_NET_OUTPUT;
    return SARINS_NET_OK;
}

/* one sample: x[7] -> y[6] */
static int comp_one(const sarins_comp *c, double *state, const double *x, double *y, double *scratch)
{
    if (!inputs_finite(x))
        return SARINS_NET_INPUT;
    double z[SARINS_COMP_N_OUT];
    switch (c->kind) {
    case SARINS_NET_KIND_TRADITIONAL:
        if (sarins_triad_compensate(c->gyro_k, c->gyro_b, 1, x, y) != 0
            || sarins_triad_compensate(c->accel_k, c->accel_b, 1, x + 3, y + 3) != 0)
            return SARINS_NET_SINGULAR;
        for (int o = 0; o < SARINS_COMP_N_OUT; o++)
            if (!isfinite(y[o]))
                return SARINS_NET_OUTPUT;
        return SARINS_NET_OK;
    case SARINS_NET_KIND_RBF:
        sarins_rbf_eval(&c->rbf, 1, x, z);
        break;
    case SARINS_NET_KIND_GRNN:
        sarins_grnn_eval(&c->grnn, 1, x, z, scratch);
        break;
    default: {
        double zin[SARINS_COMP_N_IN];
        if (!c->memory)
            memset(state, 0, (size_t)sarins_rnn_state_size(&c->rnn) * sizeof(double));
        sarins_standardize(1, SARINS_COMP_N_IN, x, c->in_mean, c->in_scale, zin);
        sarins_rnn_step(&c->rnn, state, zin, z);
    }
    }
    return comp_finish(c, x, z, y);
}

int sarins_comp_run_grnn_blocks(const sarins_comp *c, int64_t n_blocks, const int64_t *row_ptr,
                                const int64_t *cand_ptr, const int64_t *cand, double log_cut, const double *x,
                                double *y, double *scratch, int64_t *kept)
{
    if (c->kind != SARINS_NET_KIND_GRNN)
        return SARINS_NET_KIND;
    double z[SARINS_COMP_N_OUT];
    for (int64_t b = 0; b < n_blocks; b++) {
        int64_t n_cand = cand_ptr[b + 1] - cand_ptr[b];
        sarins_grnn_gather(&c->grnn, n_cand, cand + cand_ptr[b], scratch);
        for (int64_t r = row_ptr[b]; r < row_ptr[b + 1]; r++) {
            const double *xr = x + r * SARINS_COMP_N_IN;
            if (!inputs_finite(xr))
                return SARINS_NET_INPUT;
            int64_t k = sarins_grnn_eval_gathered(&c->grnn, xr, n_cand, log_cut, z, scratch);
            if (kept != NULL)
                kept[r] = k;
            int status = comp_finish(c, xr, z, y + r * SARINS_COMP_N_OUT);
            if (status != SARINS_NET_OK)
                return status;
        }
    }
    return SARINS_NET_OK;
}

int sarins_comp_run(const sarins_comp *c, double *state, int64_t n, const double *x, double *y, double *scratch)
{
    if (scratch == NULL)
        scratch = c->scratch;
    for (int64_t i = 0; i < n; i++) {
        int status = comp_one(c, state, x + i * SARINS_COMP_N_IN, y + i * SARINS_COMP_N_OUT, scratch);
        if (status != SARINS_NET_OK)
            return status;
    }
    return SARINS_NET_OK;
}

int64_t sarins_comp_streams_work(const sarins_comp *c, int64_t n_streams)
{
    if (c->kind < SARINS_NET_KIND_LSTM)
        return 0;
    return n_streams * (SARINS_COMP_N_IN + SARINS_COMP_N_OUT) + sarins_rnn_streams_work(&c->rnn, n_streams);
}

int sarins_comp_run_streams(const sarins_comp *c, int64_t n_streams, double *states, int64_t n, const double *x,
                            double *y, double *work)
{
    if (c->kind < SARINS_NET_KIND_LSTM || n_streams < 1 || n_streams > SARINS_RNN_MAX_STREAMS)
        return SARINS_NET_KIND;
    const int64_t size = sarins_rnn_state_size(&c->rnn);
    double *zin = work, *z = work + n_streams * SARINS_COMP_N_IN, *rest = z + n_streams * SARINS_COMP_N_OUT;
    for (int64_t i = 0; i < n; i++) {
        for (int64_t s = 0; s < n_streams; s++) {
            const double *xs = x + (s * n + i) * SARINS_COMP_N_IN;
            if (!inputs_finite(xs))
                return SARINS_NET_INPUT;
            if (!c->memory)
                memset(states + s * size, 0, (size_t)size * sizeof(double));
            sarins_standardize(1, SARINS_COMP_N_IN, xs, c->in_mean, c->in_scale, zin + s * SARINS_COMP_N_IN);
        }
        sarins_rnn_step_streams(&c->rnn, n_streams, states, zin, z, rest);
        for (int64_t s = 0; s < n_streams; s++) {
            int status = comp_finish(c, x + (s * n + i) * SARINS_COMP_N_IN, z + s * SARINS_COMP_N_OUT,
                                     y + (s * n + i) * SARINS_COMP_N_OUT);
            if (status != SARINS_NET_OK)
                return status;
        }
    }
    return SARINS_NET_OK;
}

/* ---------------------------------------------------------------- handles (ctypes binding) */

sarins_axial *sarins_axial_open(const unsigned char *buf, size_t n, char *msg, size_t msg_len)
{
    sarins_netfile f;
    if (sarins_netfile_parse(buf, n, &f, msg, msg_len) != SARINS_NETFILE_OK)
        return NULL;
    sarins_axial *a = malloc(sizeof *a);
    if (a == NULL) {
        fail(msg, msg_len, 0, "out of memory");
        return NULL;
    }
    if (sarins_axial_build(a, &f, msg, msg_len) != SARINS_NETFILE_OK) {
        sarins_axial_release(a);
        free(a);
        return NULL;
    }
    return a;
}

void sarins_axial_close(sarins_axial *a)
{
    sarins_axial_release(a);
    free(a);
}

sarins_comp *sarins_comp_open(const unsigned char *buf, size_t n, char *msg, size_t msg_len)
{
    sarins_netfile f;
    if (sarins_netfile_parse(buf, n, &f, msg, msg_len) != SARINS_NETFILE_OK)
        return NULL;
    sarins_comp *c = malloc(sizeof *c);
    if (c == NULL) {
        fail(msg, msg_len, 0, "out of memory");
        return NULL;
    }
    if (sarins_comp_build(c, &f, msg, msg_len) != SARINS_NETFILE_OK) {
        free(c);
        return NULL;
    }
    return c;
}

void sarins_comp_close(sarins_comp *c)
{
    sarins_comp_release(c);
    free(c);
}

int sarins_comp_kind(const sarins_comp *c) { return (int)c->kind; }
