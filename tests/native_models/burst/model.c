/* Burst: the test model of the glue's FMI 3.0 arrays (declared in tests/native_models/burst_slave.py).
 * Over the step [t, t + h] split into n = n_sub intervals: samples[k] = slope * (t + (k + 1) h / n) + u,
 * y = samples[n - 1], wsum = sum of the array input w, steps += 1. */
#include <math.h>

#include "model.h"
#include "variables.h"

typedef struct {
    int steps;
} burst_state;

static void write_outputs(sarins_ctx *c, double t, double h)
{
    int n = c->i[SARINS_I_n_sub];
    double slope = c->r[SARINS_R_slope], u = c->r[SARINS_R_u], sum = 0.0;
    for (int k = 0; k < n; k++) {
        c->a[SARINS_A_samples][k] = slope * (t + (k + 1) * h / n) + u;
        sum += c->a[SARINS_A_w][k];
    }
    c->r[SARINS_R_y] = c->a[SARINS_A_samples][n - 1];
    c->r[SARINS_R_wsum] = sum;
    c->i[SARINS_I_steps] = ((burst_state *)c->state)->steps;
}

static int burst_initialize(sarins_ctx *c)
{
    if (!isfinite(c->r[SARINS_R_slope])) {
        sarins_log(c, SARINS_ERROR, "parameter slope = %g must be finite", c->r[SARINS_R_slope]);
        return SARINS_ERROR;
    }
    ((burst_state *)c->state)->steps = 0;
    write_outputs(c, c->start_time, 0.0);
    return SARINS_OK;
}

static int burst_do_step(sarins_ctx *c, double t, double h)
{
    if (!isfinite(c->r[SARINS_R_u])) {
        sarins_log(c, SARINS_DISCARD, "input u = %g is not finite", c->r[SARINS_R_u]);
        return SARINS_DISCARD;
    }
    ((burst_state *)c->state)->steps++;
    write_outputs(c, t, h);
    return SARINS_OK;
}

static void burst_release(sarins_ctx *c) { c->work = NULL; }

const sarins_model sarins_model_desc = {
    .table = &SARINS_TABLE,
    .state_size = sizeof(burst_state),
    .state_version = 1,
    .initialize = burst_initialize,
    .do_step = burst_do_step,
    .release = burst_release,
};
