/* Burst3: n samples of y(t) = slope * t over each communication step.
 *
 * After doStep(t, h): samples[k] = slope * (t + (k + 1) h / n), k = 0..n-1 (the values
 * at the ends of the n equal sub-intervals), ends = {samples[0], samples[n-1]},
 * pairs[k] = {t + (k + 1) h / n, samples[k]} (a [n, 2] array), y = slope * (t + h),
 * count = steps taken.  At the start time t0 every sample is
 * slope * t0.  n is a structural parameter (1..FIXTURE_DIM_MAX).  With stop_after > 0
 * the step that makes count reach stop_after sets terminateSimulation.  label is a String
 * parameter nothing uses (it is read back as set).
 */
#include <string.h>

#include "fixture3.h"

typedef struct {
    fmi3UInt64 n;
    fmi3Float64 slope;                     /* m/s */
    fmi3Float64 samples[FIXTURE_DIM_MAX];  /* m */
    fmi3Float64 ends[2];                   /* m */
    fmi3Float64 pairs[FIXTURE_DIM_MAX][2]; /* (s, m) */
    fmi3Float64 y;                         /* m */
    fmi3Int32 count;
    fmi3Int32 stop_after;
    char label[FIXTURE_STRING_MAX];
} Burst;

const char *const MODEL_TOKEN = "{8c1e2f36-3b0a-4d5e-9a61-b3a7f0c2d413}";
const VarInfo MODEL_VARIABLES[] = {
    {1, T_UINT64, R_STRUCTURAL, offsetof(Burst, n), 0, 0},
    {2, T_FLOAT64, R_PARAMETER, offsetof(Burst, slope), 0, 0},
    {3, T_FLOAT64, R_OUTPUT, offsetof(Burst, samples), DIM_STRUCTURAL, 0},
    {4, T_FLOAT64, R_OUTPUT, offsetof(Burst, ends), 2, 0},
    {5, T_FLOAT64, R_OUTPUT, offsetof(Burst, y), 0, 0},
    {6, T_INT32, R_OUTPUT, offsetof(Burst, count), 0, 0},
    {7, T_INT32, R_PARAMETER, offsetof(Burst, stop_after), 0, 0},
    {9, T_FLOAT64, R_OUTPUT, offsetof(Burst, pairs), DIM_STRUCTURAL, 2},
    {8, T_STRING, R_PARAMETER, offsetof(Burst, label), 0, 0},
};
const size_t MODEL_VARIABLE_COUNT = sizeof MODEL_VARIABLES / sizeof MODEL_VARIABLES[0];

size_t model_size(void) { return sizeof(Burst); }

void model_defaults(void *model)
{
    Burst *b = model;
    b->n = 4;
    b->slope = 1.0;
    memcpy(b->label, "burst", sizeof "burst");
}

size_t model_dim(const void *model) { return (size_t)((const Burst *)model)->n; }

const char *model_check(const void *model)
{
    const Burst *b = model;
    if (b->n < 1 || b->n > FIXTURE_DIM_MAX) return "n must be in 1..64";
    if (!(b->slope == b->slope)) return "slope must be a number";
    return NULL;
}

void model_start(void *model, double time)
{
    Burst *b = model;
    for (size_t k = 0; k < b->n; k++) {
        b->samples[k] = b->slope * time;
        b->pairs[k][0] = time;
        b->pairs[k][1] = b->samples[k];
    }
    b->ends[0] = b->ends[1] = b->y = b->slope * time;
    b->count = 0;
}

int model_step(void *model, double time, double step)
{
    Burst *b = model;
    for (size_t k = 0; k < b->n; k++) {
        b->pairs[k][0] = time + (double)(k + 1) * step / (double)b->n;
        b->samples[k] = b->slope * b->pairs[k][0];
        b->pairs[k][1] = b->samples[k];
    }
    b->ends[0] = b->samples[0];
    b->ends[1] = b->samples[b->n - 1];
    b->y = b->slope * (time + step);
    b->count++;
    return b->stop_after > 0 && b->count >= b->stop_after;
}
