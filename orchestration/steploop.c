/* The master's inner loop in C (orchestration/steploop.py is its Python side).
 *
 * Runs a block of fixed-size communication steps of a prepared plan: a list of operations on loaded
 * FMI 2.0 / 3.0 co-simulation FMUs (getters, setters, doStep, unit maps, casts between C types), the
 * same calls in the same order as the Python loop of orchestration/master.py, through the FMUs' own
 * C functions (function pointers taken from the libraries the master loaded).  It knows nothing of the
 * FMUs it runs.  After each step it records a row when one is due (one getter call per block of
 * values, writing straight into the recorder's storage) and checks the FMI 3.0 terminate flags.
 *
 * It returns to Python after the block, at the first failing call, at a terminate request or at a
 * failing record, so that interrupts, progress and error reports stay in Python.  No allocation, no
 * globals: every buffer belongs to the caller.  With a `seconds` array it also sums the wall time of
 * each operation and of recording (a profile of where a step goes; off by default).  Times are computed as the Python loop does
 * (t = begin + j h, the end of the last step of a segment is the segment's end), so both loops give
 * the same numbers bit for bit.
 */
#if !defined(_WIN32)
#define _POSIX_C_SOURCE 199309L /* clock_gettime */
#endif
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#if defined(_WIN32)
#include <windows.h>
#else
#include <time.h>
#endif

#if defined(_WIN32)
#define SL_EXPORT __declspec(dllexport)
#else
#define SL_EXPORT __attribute__((visibility("default")))
#endif

#define SL_ABI 1

/* operation kinds */
enum {
    OP_VALUES2 = 0, /* fmi2Get / fmi2Set: fn(instance, vrs, nvr, values) */
    OP_VALUES3 = 1, /* fmi3Get / fmi3Set: fn(instance, vrs, nvr, values, nValues) */
    OP_STEP2 = 2,   /* fmi2DoStep(instance, t, h, noSetFMUStatePriorToCurrentPoint = 1) */
    OP_STEP3 = 3,   /* fmi3DoStep(instance, t, h, true, &event, &terminate, &early, &lastTime) */
    OP_MAP = 4,     /* values[k] = values[k] * factor[k], then + offset[k] (unit conversions) */
    OP_CAST = 5     /* dst[k] = (dst type) src[k] */
};

/* element types of OP_MAP and OP_CAST buffers */
enum { T_F64 = 0, T_F32, T_I8, T_U8, T_I16, T_U16, T_I32, T_U32, T_I64, T_U64, T_BOOL };

typedef void (*sl_any_fn)(void); /* a function pointer of any type (ISO C: cast back before calling) */
typedef int (*values2_fn)(void *, const unsigned *, size_t, void *);
typedef int (*values3_fn)(void *, const unsigned *, size_t, void *, size_t);
typedef int (*step2_fn)(void *, double, double, int);
typedef int (*step3_fn)(void *, double, double, bool, bool *, bool *, bool *, double *);

typedef struct {
    int32_t kind;
    int32_t type;        /* OP_MAP: the buffer's type; OP_CAST: the source's type */
    int32_t type_to;     /* OP_CAST: the target's type */
    int32_t pad;
    sl_any_fn fn;        /* the FMI function */
    void *instance;      /* its fmi2Component / fmi3Instance */
    const unsigned *vrs; /* value references */
    uint64_t nvr;
    void *values;        /* OP_VALUES*: the value buffer; OP_MAP: the buffer; OP_CAST: the source */
    uint64_t n_values;   /* elements (FMI 3.0 nValues; OP_MAP/OP_CAST: their count) */
    const double *factor, *offset; /* OP_MAP */
    void *target;        /* OP_CAST: the target buffer */
    bool *event, *terminate, *early; /* OP_STEP3: its output flags */
    double *last_time;   /* OP_STEP3 */
} sl_op;

typedef struct {
    int32_t fmi3;        /* 1: fn takes nValues */
    int32_t pad;
    sl_any_fn fn;        /* the getter */
    void *instance;
    const unsigned *vrs;
    uint64_t nvr;
    uint64_t n_values;
    unsigned char *base; /* the block's storage, row 0 */
    uint64_t row_bytes;
} sl_record;

typedef struct {
    /* in: the segment and the block of steps to run */
    double begin, h, end; /* the segment: t_j = begin + j h, its last step ends at end */
    int64_t j0, count;     /* steps j0 .. j0 + count - 1 of the segment */
    int64_t seg_count;     /* steps in the segment */
    /* in/out: counters shared with the Python loop */
    int64_t done;          /* steps done in the run */
    int64_t total;         /* steps planned in the run */
    int64_t every;         /* record every this many steps */
    int64_t next_record;   /* the value of done at which the next row is due */
    int64_t rows;          /* rows recorded (the recorder's count) */
    int64_t capacity;      /* rows the storage holds */
    double *times;         /* the recorder's time column */
    /* out */
    int32_t outcome;       /* see SL_* below */
    int32_t status;        /* the failing call's status */
    int64_t where;         /* the failing op, record block or terminating step op */
    double t_fail;         /* the communication point of the failure */
    double t_end;          /* end time of the last step done */
    double *seconds;       /* NULL, or n_ops + 1 sums: wall seconds spent in each op and in recording */
} sl_run_state;

enum { SL_DONE = 0, SL_CALL_FAILED = 1, SL_TERMINATED = 2, SL_RECORD_FAILED = 3, SL_FULL = 4,
       SL_BAD_OP = 5 };

#define FMI_WARNING 1

/* wall clock, s (profiling only) */
static double now(void)
{
#if defined(_WIN32)
    LARGE_INTEGER count, frequency;
    QueryPerformanceCounter(&count);
    QueryPerformanceFrequency(&frequency);
    return (double)count.QuadPart / (double)frequency.QuadPart;
#else
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
#endif
}

SL_EXPORT int sl_abi(void) { return SL_ABI; }

static double load(const void *p, int32_t type, size_t k)
{
    switch (type) {
    case T_F64: return ((const double *)p)[k];
    case T_F32: return (double)((const float *)p)[k];
    default: return 0.0;
    }
}

static int map_values(const sl_op *op)
{
    size_t n = (size_t)op->n_values;
    if (op->type == T_F64) {
        double *v = (double *)op->values;
        for (size_t k = 0; k < n; k++) {
            double x = v[k] * op->factor[k]; /* two roundings, as numpy's multiply then add */
            v[k] = x + op->offset[k];
        }
        return 0;
    }
    if (op->type == T_F32) {
        float *v = (float *)op->values;
        for (size_t k = 0; k < n; k++) {
            v[k] = (float)((double)v[k] * op->factor[k]);
            v[k] = (float)((double)v[k] + op->offset[k]);
        }
        return 0;
    }
    return -1;
}

/* One element as a signed or unsigned 64-bit integer (integer and boolean families). */
static int64_t load_int(const void *p, int32_t type, size_t k)
{
    switch (type) {
    case T_I8: return ((const int8_t *)p)[k];
    case T_U8: return ((const uint8_t *)p)[k];
    case T_I16: return ((const int16_t *)p)[k];
    case T_U16: return ((const uint16_t *)p)[k];
    case T_I32: return ((const int32_t *)p)[k];
    case T_U32: return ((const uint32_t *)p)[k];
    case T_I64: return ((const int64_t *)p)[k];
    case T_U64: return (int64_t)((const uint64_t *)p)[k];
    case T_BOOL: return ((const bool *)p)[k] ? 1 : 0;
    default: return 0;
    }
}

static void store_int(void *p, int32_t type, size_t k, int64_t v, int from_bool_family)
{
    switch (type) {
    case T_I8: ((int8_t *)p)[k] = (int8_t)v; break;
    case T_U8: ((uint8_t *)p)[k] = (uint8_t)v; break;
    case T_I16: ((int16_t *)p)[k] = (int16_t)v; break;
    case T_U16: ((uint16_t *)p)[k] = (uint16_t)v; break;
    case T_I32: ((int32_t *)p)[k] = from_bool_family ? (v != 0) : (int32_t)v; break;
    case T_U32: ((uint32_t *)p)[k] = (uint32_t)v; break;
    case T_I64: ((int64_t *)p)[k] = v; break;
    case T_U64: ((uint64_t *)p)[k] = (uint64_t)v; break;
    case T_BOOL: ((bool *)p)[k] = v != 0; break;
    default: break;
    }
}

static int is_float(int32_t type) { return type == T_F64 || type == T_F32; }

/* numpy's copyto(casting="unsafe") between two buffers of one family */
static int cast_values(const sl_op *op)
{
    size_t n = (size_t)op->n_values;
    if (is_float(op->type) != is_float(op->type_to) || op->type < T_F64 || op->type > T_BOOL
        || op->type_to < T_F64 || op->type_to > T_BOOL)
        return -1;
    if (is_float(op->type)) {
        for (size_t k = 0; k < n; k++) {
            double v = load(op->values, op->type, k);
            if (op->type_to == T_F64)
                ((double *)op->target)[k] = v;
            else
                ((float *)op->target)[k] = (float)v;
        }
        return 0;
    }
    int boolean = op->type == T_BOOL || op->type_to == T_BOOL;
    for (size_t k = 0; k < n; k++)
        store_int(op->target, op->type_to, k, load_int(op->values, op->type, k), boolean);
    return 0;
}

/* One operation; its FMI status (0 for maps and casts; > FMI_WARNING stops the run). */
static int run_op(const sl_op *op, double t, double h)
{
    switch (op->kind) {
    case OP_VALUES2:
        return ((values2_fn)op->fn)(op->instance, op->vrs, (size_t)op->nvr, op->values);
    case OP_VALUES3:
        return ((values3_fn)op->fn)(op->instance, op->vrs, (size_t)op->nvr, op->values, (size_t)op->n_values);
    case OP_STEP2:
        return ((step2_fn)op->fn)(op->instance, t, h, 1);
    case OP_STEP3:
        return ((step3_fn)op->fn)(op->instance, t, h, true, op->event, op->terminate, op->early,
                                  op->last_time);
    case OP_MAP:
        return map_values(op) == 0 ? 0 : -1;
    case OP_CAST:
        return cast_values(op) == 0 ? 0 : -1;
    default:
        return -1;
    }
}

static int record_row(const sl_record *rec, size_t n_rec, sl_run_state *s, double t_end)
{
    int64_t row = s->rows;
    if (row >= s->capacity) {
        s->outcome = SL_FULL;
        return 0;
    }
    s->times[row] = t_end;
    for (size_t b = 0; b < n_rec; b++) {
        const sl_record *r = &rec[b];
        void *at = r->base + (size_t)row * (size_t)r->row_bytes;
        int st = r->fmi3 ? ((values3_fn)r->fn)(r->instance, r->vrs, (size_t)r->nvr, at, (size_t)r->n_values)
                         : ((values2_fn)r->fn)(r->instance, r->vrs, (size_t)r->nvr, at);
        if (st > FMI_WARNING) {
            s->outcome = SL_RECORD_FAILED;
            s->status = st;
            s->where = (int64_t)b;
            s->t_fail = t_end;
            return 0;
        }
    }
    s->rows = row + 1;
    return 1;
}

/* Run s->count steps (or fewer: see the outcome).  Returns the outcome. */
SL_EXPORT int sl_run(const sl_op *ops, uint64_t n_ops, const sl_record *rec, uint64_t n_rec, sl_run_state *s)
{
    s->outcome = SL_DONE;
    if (ops == NULL || s == NULL || (n_rec > 0 && rec == NULL) || s->every < 1)
        return s ? (s->outcome = SL_BAD_OP) : SL_BAD_OP;
    for (int64_t j = s->j0; j < s->j0 + s->count; j++) {
        double t = s->begin + (double)j * s->h;
        for (uint64_t k = 0; k < n_ops; k++) {
            double t0 = s->seconds != NULL ? now() : 0.0;
            int st = run_op(&ops[k], t, s->h);
            if (s->seconds != NULL)
                s->seconds[k] += now() - t0;
            if (st > FMI_WARNING || st < 0) {
                s->outcome = st < 0 ? SL_BAD_OP : SL_CALL_FAILED;
                s->status = st;
                s->where = (int64_t)k;
                s->t_fail = t;
                return s->outcome;
            }
        }
        s->done++;
        double t_end = j == s->seg_count - 1 ? s->end : s->begin + (double)(j + 1) * s->h;
        s->t_end = t_end;
        for (uint64_t k = 0; k < n_ops; k++)
            if (ops[k].kind == OP_STEP3 && *ops[k].terminate) {
                s->outcome = SL_TERMINATED;
                s->where = (int64_t)k;
                return s->outcome;
            }
        if (s->done == s->next_record) {
            double t0 = s->seconds != NULL ? now() : 0.0;
            int recorded = record_row(rec, (size_t)n_rec, s, t_end);
            if (s->seconds != NULL)
                s->seconds[n_ops] += now() - t0;
            if (!recorded)
                return s->outcome;
            s->next_record = s->next_record + s->every < s->total ? s->next_record + s->every : s->total;
        }
    }
    return s->outcome;
}
