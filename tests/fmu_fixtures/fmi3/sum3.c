/* Sum3: integrates an array of n sub-step samples; scalar pass-throughs of three types.
 *
 * doStep(t, h): integral += (h / n) * sum(u) (the rectangle rule over n equal
 * sub-intervals; u is held over the step), then scaled = k * mean(u), m_out = m,
 * flag_out = flag, v_sum[j] = sum over k of v[k][j] (v an [n, 2] array) (direct
 * feedthrough); k is a Float32.  n is a structural parameter (1..FIXTURE_DIM_MAX).
 */
#include "fixture3.h"

typedef struct {
    fmi3UInt64 n;
    fmi3Float64 u[FIXTURE_DIM_MAX];  /* m */
    fmi3Float32 k;                   /* mm */
    fmi3Int32 m;
    fmi3Boolean flag;
    fmi3Float64 integral;            /* m.s */
    fmi3Float64 scaled;              /* m.mm */
    fmi3Int32 m_out;
    fmi3Boolean flag_out;
    fmi3Float64 v[FIXTURE_DIM_MAX][2];
    fmi3Float64 v_sum[2];
} Sum;

const char *const MODEL_TOKEN = "{5d0b9a7e-61c4-4f2a-8e3d-2c9f1a6b7e05}";
const VarInfo MODEL_VARIABLES[] = {
    {1, T_UINT64, R_STRUCTURAL, offsetof(Sum, n), 0, 0},
    {2, T_FLOAT64, R_INPUT, offsetof(Sum, u), DIM_STRUCTURAL, 0},
    {3, T_FLOAT32, R_INPUT, offsetof(Sum, k), 0, 0},
    {4, T_INT32, R_INPUT, offsetof(Sum, m), 0, 0},
    {5, T_BOOLEAN, R_INPUT, offsetof(Sum, flag), 0, 0},
    {6, T_FLOAT64, R_OUTPUT, offsetof(Sum, integral), 0, 0},
    {7, T_FLOAT64, R_OUTPUT, offsetof(Sum, scaled), 0, 0},
    {8, T_INT32, R_OUTPUT, offsetof(Sum, m_out), 0, 0},
    {9, T_BOOLEAN, R_OUTPUT, offsetof(Sum, flag_out), 0, 0},
    {10, T_FLOAT64, R_INPUT, offsetof(Sum, v), DIM_STRUCTURAL, 2},
    {11, T_FLOAT64, R_OUTPUT, offsetof(Sum, v_sum), 2, 0},
};
const size_t MODEL_VARIABLE_COUNT = sizeof MODEL_VARIABLES / sizeof MODEL_VARIABLES[0];

size_t model_size(void) { return sizeof(Sum); }

void model_defaults(void *model)
{
    Sum *s = model;
    s->n = 4;
    s->k = 1.0f;
}

size_t model_dim(const void *model) { return (size_t)((const Sum *)model)->n; }

const char *model_check(const void *model)
{
    const Sum *s = model;
    return s->n < 1 || s->n > FIXTURE_DIM_MAX ? "n must be in 1..64" : NULL;
}

static void feedthrough(Sum *s)
{
    double total = 0.0;
    for (size_t i = 0; i < s->n; i++) total += s->u[i];
    s->scaled = s->k * total / (double)s->n;
    s->m_out = s->m;
    s->flag_out = s->flag;
    s->v_sum[0] = s->v_sum[1] = 0.0;
    for (size_t i = 0; i < s->n; i++) {
        s->v_sum[0] += s->v[i][0];
        s->v_sum[1] += s->v[i][1];
    }
}

void model_start(void *model, double time)
{
    Sum *s = model;
    (void)time;
    s->integral = 0.0;
    feedthrough(s);
}

int model_step(void *model, double time, double step)
{
    Sum *s = model;
    double total = 0.0;
    (void)time;
    for (size_t i = 0; i < s->n; i++) total += s->u[i];
    s->integral += step / (double)s->n * total;
    feedthrough(s);
    return 0;
}
