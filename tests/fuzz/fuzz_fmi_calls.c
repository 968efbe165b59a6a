/* libFuzzer harness of FMI call sequences on the native glue (fmus/c/fmi2_glue.c or, with -DFMI3,
 * fmi3_glue.c, over glue_core.c), linked with one native FMU's sources/ (the glue, model.c, variables.h, the
 * core).  The input is a program: each operation is one byte (its code modulo N_OPS) and the argument bytes
 * it reads; missing bytes read as 0.  The operations act on one instance at a time, in any order and any state:
 * instantiate (good or odd arguments: NULL/empty/long name, wrong/NULL/empty GUID, missing, bad or relative
 * resource location, no logger, Model Exchange, event mode), free it, set up / enter / exit initialisation
 * (start and stop times odd too), enter / exit (re)configuration mode (FMI 3.0), doStep (the current point
 * or off it, NaN, negative; steps from a table of 0, negative, NaN, inf, tiny, off-grid, 1e300), terminate,
 * reset, get and set of every type (valid value references, foreign ones and FMI 3.0's time; counts 0 .. 4096;
 * FMI 3.0 nValues right or wrong; values NaN, inf, huge, start, strings empty / 4095 / 4096 / 5000 bytes,
 * NULL, bytes of the input), FMU state get / set / free / size / serialize / deserialize (valid states,
 * NULL, freed, foreign; buffers exact, short or long; blobs valid, one byte changed, truncated or from the
 * input), debug logging, the unsupported calls, and calls on a NULL instance.
 *
 * Findings: any sanitizer report (leaks included: everything is freed at the end of an input), a hang
 * (libFuzzer -timeout), and abort() on a broken invariant:
 * - OK from a call in a state where the standard forbids it, by the harness's own tracking of the state
 *   (FMI 2.0 section 4.2.4, FMI 3.0 section 4.2.1; a call returning Error leaves the instance where only
 *   Get*, SetFMUstate to a state saved before, Reset and FreeInstance may follow, FMI 2.0 section 2.1.3 /
 *   FMI 3.0 section 2.2.4): EnterInitializationMode outside Instantiated, ExitInitializationMode outside
 *   Initialization Mode, DoStep outside Step Mode (stepComplete), Terminate before initialisation, after it
 *   or after an error, Set* after Terminate or an error, GetFMUstate after an error, SetupExperiment (2.0)
 *   after instantiation;
 * - OK from a get or set naming a value reference the model does not have, or of another type, or (3.0) an
 *   nValues other than the values those references hold;
 * - a non-finite Real output after a doStep that returned OK; a String longer than its buffer.
 *
 * Build (from an FMU's sources/ folder):
 *   clang -std=c11 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all [-DFMI3] -I. \
 *       tests/fuzz/fuzz_fmi_calls.c *.c -o fuzz_calls
 *   ./fuzz_calls -max_total_time=60 -timeout=20 tests/fuzz/corpus_fmi_calls
 * A model that needs files is given them like fuzz_fmu_state.c: SARINS_FUZZ_RESOURCES (the unzipped
 * resources folder) and SARINS_FUZZ_PARAMS ("name=value" lines set after a good instantiation).  Without
 * libFuzzer, -DSARINS_FUZZ_MAIN makes `fuzz_calls FILE...` run the harness once on each file
 * (tests/test_fuzz_fmi_calls.py replays the corpus and tests/fuzz/regressions/calls_*.bin so).
 */
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "model.h"
#include "variables.h"

#define MAXN 4096                    /* value references in one call */
#define MAXV (2 * 100000 + MAXN)     /* values in one call (two arrays of the largest length and scalars) */
#define SLOTS 4                      /* FMU states held */
#define BLOBS 3                      /* serialized states held */

/* what the harness believes the instance's state is (T_UNKNOWN: nothing is asserted until a call fixes it) */
enum { T_NONE, T_INST, T_INIT, T_STEP, T_FAILED, T_TERM, T_ERR, T_CONF, T_RECONF, T_UNKNOWN };

typedef struct {
    const uint8_t *p;
    size_t n;
} input;

static unsigned u8(input *in)
{
    if (in->n == 0)
        return 0;
    in->n--;
    return *in->p++;
}

static uint64_t bytes(input *in, int k)
{
    uint64_t x = 0;
    for (int j = 0; j < k; j++)
        x |= (uint64_t)u8(in) << (8 * j);
    return x;
}

static void check(int ok, const char *what)
{
    if (!ok) {
        fprintf(stderr, "fuzz_fmi_calls: invariant broken: %s\n", what);
        abort();
    }
}

/* ------------------------------------------------------------------ the table */

static const sarins_var *var_by_vr(unsigned vr)
{
    for (size_t k = 0; k < SARINS_TABLE.n_vars; k++)
        if (SARINS_TABLE.vars[k].vr == vr)
            return &SARINS_TABLE.vars[k];
    return NULL;
}

static unsigned time_vr(void) /* FMI 3.0: the glue's time variable, one past the last value reference */
{
    unsigned m = 0;
    for (size_t k = 0; k < SARINS_TABLE.n_vars; k++)
        if (SARINS_TABLE.vars[k].vr + 1 > m)
            m = SARINS_TABLE.vars[k].vr + 1;
    return m;
}

/* a value reference: a variable of the table (most often), FMI 3.0's time, or any number */
static unsigned pick_vr(input *in)
{
    unsigned b = u8(in);
    if (b < 200 && SARINS_TABLE.n_vars > 0)
        return SARINS_TABLE.vars[(b + 200 * u8(in)) % SARINS_TABLE.n_vars].vr;
    if (b < 220)
        return time_vr();
    if (b < 240)
        return time_vr() + 1 + (b - 220);
    return (unsigned)bytes(in, 4);
}

static double pick_real(input *in, const sarins_var *v)
{
    static const double table[] = {0.0, -0.0, 1.0, -1.0, NAN, INFINITY, -INFINITY, DBL_MAX, -DBL_MAX, 5e-324,
                                   1e-300, 0.5, 0.01, 100.0, 1e6, 1e12, 3.5, 0.4925, 1e300, -1e300};
    unsigned b = u8(in) % 22;
    if (b < 20)
        return table[b];
    if (b == 20)
        return v != NULL && v->type == SARINS_REAL ? v->start_real : 2.0;
    uint64_t x = bytes(in, 8);
    double d;
    memcpy(&d, &x, sizeof d);
    return d;
}

static int pick_int(input *in, const sarins_var *v)
{
    static const int table[] = {0, 1, -1, 2, 3, 5, 10, 100, 100000, 100001, INT_MAX, INT_MIN};
    unsigned b = u8(in) % 14;
    if (b < 12)
        return table[b];
    if (b == 12)
        return v != NULL ? v->start_int : 4;
    return (int)(uint32_t)bytes(in, 4);
}

static uint64_t pick_u64(input *in)
{
    static const uint64_t table[] = {0, 1, 2, 3, 7, 100, 100000, 100001, UINT64_MAX, (1ULL << 32) + 2};
    unsigned b = u8(in) % 11;
    return b < 10 ? table[b] : bytes(in, 8);
}

static char long_a[5001], fits[SARINS_STRING_MAX], one_over[SARINS_STRING_MAX + 1];

/* a String value (NULL too); raw bytes of the input go into buf (NUL-terminated) */
static const char *pick_string(input *in, const sarins_var *v, char *buf, size_t cap)
{
    static const char *const table[] = {"", "x", "hot", "cold", "input", "static", "none", "z", "x,y,z", "-1",
                                        "nan", "/nonexistent/file.bin", "0 10 1 0 0 0 0 0; 10 20 0 1 0 0 0 0",
                                        "10 20; 5 1"};
    unsigned b = u8(in) % 19;
    if (b < 14)
        return table[b];
    switch (b) {
    case 14:
        return v != NULL && v->start_string != NULL ? v->start_string : "";
    case 15:
        return long_a;
    case 16:
        return fits;
    case 17:
        return one_over;
    default: {
        size_t n = u8(in) % (cap - 1);
        size_t k = 0;
        while (k < n && in->n > 0)
            buf[k++] = (char)u8(in);
        buf[k] = '\0';
        return buf;
    }
    }
}

/* ------------------------------------------------------------ the FMI version */

#ifdef FMI3
#include "fmi3Functions.h"
typedef fmi3Instance inst;
typedef fmi3FMUState fstate;
typedef fmi3Status status;
#define OK fmi3OK
#define WARNING fmi3Warning
#define DISCARD fmi3Discard
#define ERROR fmi3Error
#else
#include "fmi2Functions.h"
typedef fmi2Component inst;
typedef fmi2FMUstate fstate;
typedef fmi2Status status;
#define OK fmi2OK
#define WARNING fmi2Warning
#define DISCARD fmi2Discard
#define ERROR fmi2Error
#endif

typedef struct {
    inst c;
    int t;                 /* T_* */
    fstate slot[SLOTS];    /* FMU states this instance issued (or NULL) */
    int slot_t[SLOTS];     /* the tracked state each was taken in */
    fstate freed;          /* a state freed earlier (a dangling pointer: must be refused, never read) */
    unsigned char *blob[BLOBS];
    size_t blob_n[BLOBS];
    int blob_t[BLOBS];
    char sbuf[MAXN > 8 ? 8 : MAXN][300];
} world;

static unsigned vrs[MAXN];
static double reals[MAXV];
static int ints[MAXN];
static uint64_t u64s[MAXN];
static const char *strs[MAXN];
#ifdef FMI3
static fmi3Boolean bools[MAXN];
#else
static fmi2Boolean bools[MAXN];
#endif
static unsigned char foreign[512]; /* a "state" the FMU never issued */

static void logger_check(const char *message)
{
    check(message != NULL && strlen(message) < 1u << 20, "a log message is NULL or unterminated");
}

#ifdef FMI3
static void logger(fmi3InstanceEnvironment env, fmi3Status s, fmi3String category, fmi3String message)
{
    (void)env; (void)s; (void)category;
    logger_check(message);
}
#else
static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status s, fmi2String category,
                   fmi2String message, ...)
{
    (void)env; (void)name; (void)s; (void)category;
    logger_check(message);
}
static const fmi2CallbackFunctions CALLBACKS = {logger, calloc, free, NULL, NULL};
static const fmi2CallbackFunctions NO_LOGGER = {NULL, calloc, free, NULL, NULL};
#endif

/* the tracked state after a call on an instance that returned rc; `ok_to` the state an OK leads to */
static void after(world *w, status rc, int ok_to)
{
    if (rc == ERROR || rc > ERROR)
        w->t = T_ERR;
    else if ((rc == OK || rc == WARNING) && ok_to != -1)
        w->t = ok_to;
}

/* OK (or Warning) from a call the tracked state forbids: a finding */
static void forbid(const world *w, status rc, int bad_states, const char *what)
{
    if (w->t != T_UNKNOWN && (rc == OK || rc == WARNING) && (bad_states & (1 << w->t)))
        check(0, what);
}
#define B(x) (1 << (x))

/* ------------------------------------------------------------------ operations */

static const char *resources(int uri)
{
    static char buf[4200];
    const char *dir = getenv("SARINS_FUZZ_RESOURCES");
    if (dir == NULL || dir[0] == '\0')
        return NULL;
    snprintf(buf, sizeof buf, "%s%s", uri ? "file://" : "", dir);
    return buf;
}

static void clear_slots(world *w)
{
    for (int k = 0; k < SLOTS; k++) {
        if (w->slot[k] != NULL)
            w->freed = w->slot[k]; /* freed with the instance */
        w->slot[k] = NULL;
    }
}

static void free_instance(world *w)
{
    if (w->c != NULL) {
#ifdef FMI3
        fmi3FreeInstance(w->c);
#else
        fmi2FreeInstance(w->c);
#endif
    }
    w->c = NULL;
    w->t = T_NONE;
    clear_slots(w);
}

static int set_params(world *w);

static void op_instantiate(world *w, input *in)
{
    free_instance(w);
    unsigned a = u8(in), f = u8(in);
    static char long_name[6000];
    if (long_name[0] == '\0')
        memset(long_name, 'n', sizeof long_name - 1);
    const char *names[4] = {"fuzz", NULL, "", long_name};
    const char *guids[4] = {SARINS_TABLE.guid, "{00000000-0000-0000-0000-000000000000}", NULL, ""};
    char raw[300];
    const char *res;
    switch ((a >> 5) & 7) {
    case 0: res = resources(
#ifdef FMI3
                  0
#else
                  1
#endif
                  ); break;
    case 1: res = NULL; break;
    case 2: res = ""; break;
#ifdef FMI3
    case 3: res = "/nonexistent/resources"; break;
    case 4: res = "file:///tmp"; break;
#else
    case 3: res = "file:///nonexistent/resources"; break;
    case 4: res = "http://host/resources"; break;
#endif
    case 5: res = "resources"; break;
    default: res = pick_string(in, NULL, raw, sizeof raw); break;
    }
    const char *name = names[a & 3], *guid = guids[(a >> 2) & 3];
    int logging = f & 1;
#ifdef FMI3
    int event = (f & 2) != 0 && (f & 4) != 0, no_logger = (f & 8) != 0;
    fmi3ValueReference required[1] = {0};
    w->c = fmi3InstantiateCoSimulation(name, guid, res, fmi3False, logging ? fmi3True : fmi3False,
                                       event ? fmi3True : fmi3False, fmi3False, required, (f & 16) && (f & 32),
                                       NULL, no_logger ? NULL : logger, NULL);
    int good = !event && !((f & 16) && (f & 32));
#else
    fmi2Type type = (f & 2) && (f & 4) ? fmi2ModelExchange : fmi2CoSimulation;
    const fmi2CallbackFunctions *cb = (f & 24) == 24 ? NULL : (f & 8) ? &NO_LOGGER : &CALLBACKS;
    w->c = fmi2Instantiate(name, type, guid, res, cb, fmi2False, logging ? fmi2True : fmi2False);
    int good = type == fmi2CoSimulation;
#endif
    if (w->c != NULL) {
        check(good || (a & 0x1C) == 0, "an instance from a wrong, NULL or empty token, or for another interface");
        w->t = T_INST;
        if (((a >> 5) & 7) == 0 && !(f & 64))
            set_params(w);
    }
}

/* SARINS_FUZZ_PARAMS, like fuzz_fmu_state.c; a refusal is the model's business (tracked) */
static int set_params(world *w)
{
    const char *p = getenv("SARINS_FUZZ_PARAMS");
    while (p != NULL && *p != '\0') {
        const char *end = strchr(p, '\n'), *eq = strchr(p, '=');
        size_t n = end ? (size_t)(end - p) : strlen(p);
        char line[4200];
        if (eq == NULL || eq > p + n || n >= sizeof line)
            return 1;
        memcpy(line, p, n);
        line[n] = '\0';
        line[eq - p] = '\0';
        const char *value = line + (eq - p) + 1;
        for (size_t v = 0; v < SARINS_TABLE.n_vars; v++) {
            const sarins_var *var = &SARINS_TABLE.vars[v];
            if (strcmp(var->name, line) != 0 || var->type != SARINS_STRING)
                continue;
            unsigned vr = var->vr;
#ifdef FMI3
            after(w, fmi3SetString(w->c, &vr, 1, &value, 1), -1);
#else
            after(w, fmi2SetString(w->c, &vr, 1, &value), -1);
#endif
        }
        p = end ? end + 1 : p + n;
    }
    return 0;
}

static double pick_time(input *in, double now)
{
    static const double table[] = {0.0, 1.0, -1.0, 1e6, NAN, INFINITY, 1e300, -1e300, 0.5, 1e-3};
    unsigned b = u8(in) % 14;
    if (b < 10)
        return table[b];
    return b == 10 ? now : b == 11 ? now + 1e-12 : b == 12 ? now + 1e-3 : now - 1.0;
}

static double pick_step(input *in)
{
    static const double table[] = {1.0, 0.01, 0.1, 0.005, 0.0123, 0.25, 1.5, 10.0, 2.0, 0.0, -1.0, NAN,
                                   INFINITY, -INFINITY, 5e-324, 1e-9, 1e-3, 1e20, 1e300, -0.0};
    return table[u8(in) % 20];
}

/* the current communication point as the FMU reports it (only asked in Step Mode), else 0 */
static double now(world *w)
{
    double t = 0.0;
    if (w->c == NULL || w->t != T_STEP)
        return t;
#ifdef FMI3
    unsigned vr = time_vr();
    status rc = fmi3GetFloat64(w->c, &vr, 1, &t, 1);
#else
    status rc = fmi2GetRealStatus(w->c, fmi2LastSuccessfulTime, &t);
#endif
    check(rc == OK, "the current time is not readable in Step Mode");
    return t;
}

static void check_outputs(world *w)
{
    for (size_t k = 0; k < SARINS_TABLE.n_vars; k++) {
        const sarins_var *v = &SARINS_TABLE.vars[k];
        if (v->type != SARINS_REAL || v->causality != SARINS_OUTPUT || v->dim >= 0)
            continue;
        unsigned vr = v->vr;
        double x = 0.0;
#ifdef FMI3
        status rc = fmi3GetFloat64(w->c, &vr, 1, &x, 1);
#else
        status rc = fmi2GetReal(w->c, &vr, 1, &x);
#endif
        check(rc == OK, "a scalar output is not readable after an OK doStep");
        check(x - x == 0.0, "a non-finite output after an OK doStep");
    }
}

static void op_do_step(world *w, input *in)
{
    double t = pick_time(in, now(w)), h = pick_step(in);
    if (w->c == NULL)
        return;
#ifdef FMI3
    fmi3Boolean event, term, early;
    fmi3Float64 last;
    status rc = fmi3DoStep(w->c, t, h, fmi3False, &event, &term, &early, &last);
#else
    status rc = fmi2DoStep(w->c, t, h, fmi2False);
#endif
    forbid(w, rc, ~B(T_STEP), "doStep OK outside Step Mode");
    if (rc == OK) {
        check(h > 0.0 && t == t && h == h, "doStep OK with a step that is not positive or a NaN time");
        check_outputs(w);
    }
#ifdef FMI3
    after(w, rc, -1);
    if (rc == DISCARD)
        w->t = T_UNKNOWN;
#else
    after(w, rc, -1);
    if (rc == DISCARD)
        w->t = T_FAILED;
#endif
}

/* the values the value references vrs[0 .. n-1] hold: -1 if one is not a variable of `type` (FMI 3.0: an Int32
 * or a UInt64 as `structural` says; the time a Float64 to get, never to set), -2 if one is an array (its length
 * is not predicted) */
static long expected_values(size_t n, int type, int structural, int set)
{
    long total = 0;
    int arrays = 0;
    for (size_t k = 0; k < n; k++) {
        const sarins_var *v = var_by_vr(vrs[k]);
#ifdef FMI3
        if (v == NULL && vrs[k] == time_vr() && type == SARINS_REAL && !set) {
            total++;
            continue;
        }
        if (v == NULL || v->type != type
            || (type == SARINS_INTEGER && (v->causality == SARINS_STRUCTURAL_PARAMETER) != structural))
            return -1;
        if (v->dim >= 0)
            arrays = 1;
        else
            total++;
#else
        (void)structural;
        (void)set;
        if (v == NULL || v->type != type || v->dim >= 0) /* FMI 2.0 has no array variables */
            return -1;
        total++;
#endif
    }
    return arrays ? -2 : total;
}

/* value references for one call: a count and up to 8 chosen ones, repeated up to the count */
static size_t pick_vrs(input *in)
{
    static const size_t counts[] = {1, 1, 1, 2, 3, 0, 8, MAXN};
    unsigned b = u8(in);
    size_t n = b < 248 ? counts[b % 8] : SARINS_TABLE.n_vars;
    size_t chosen = n < 8 ? n : 8;
    for (size_t k = 0; k < chosen; k++)
        vrs[k] = pick_vr(in);
    for (size_t k = chosen; k < n; k++)
        vrs[k] = vrs[k % chosen];
    return n;
}

#ifdef FMI3
/* FMI 3.0 nValues: usually the number of references (right for scalars), sometimes off */
static size_t pick_nvalues(input *in, size_t n)
{
    unsigned b = u8(in) % 8;
    size_t m = b < 5 ? n : b == 5 ? n + 1 : b == 6 ? 0 : 200000;
    return m > MAXV ? MAXV : m;
}
#endif

enum { GET_R, GET_I, GET_B, GET_S, SET_R, SET_I, SET_B, SET_S, GET_U, SET_U };

static void op_values(world *w, input *in, int kind)
{
    size_t n = pick_vrs(in);
#ifdef FMI3
    size_t nv = pick_nvalues(in, n);
#endif
    int type = kind == GET_R || kind == SET_R ? SARINS_REAL : kind == GET_B || kind == SET_B ? SARINS_BOOLEAN
             : kind == GET_S || kind == SET_S ? SARINS_STRING : SARINS_INTEGER;
    int structural = kind == GET_U || kind == SET_U;
    int set = kind == SET_R || kind == SET_I || kind == SET_B || kind == SET_S || kind == SET_U;
    for (size_t k = 0; k < n && k < 8; k++) {
        const sarins_var *v = var_by_vr(vrs[k]);
        reals[k] = pick_real(in, v);
        ints[k] = pick_int(in, v);
        u64s[k] = pick_u64(in);
        bools[k] = (u8(in) & 1) != 0;
        strs[k] = pick_string(in, v, w->sbuf[k], sizeof w->sbuf[k]);
    }
    for (size_t k = 8; k < n; k++) {
        reals[k] = reals[k % 8];
        ints[k] = ints[k % 8];
        u64s[k] = u64s[k % 8];
        bools[k] = bools[k % 8];
        strs[k] = strs[k % 8];
    }
    if (w->c == NULL)
        return;
    status rc;
#ifdef FMI3
    fmi3Instance c = w->c;
    switch (kind) {
    case GET_R: rc = fmi3GetFloat64(c, vrs, n, reals, nv); break;
    case GET_I: rc = fmi3GetInt32(c, vrs, n, ints, nv); break;
    case GET_B: rc = fmi3GetBoolean(c, vrs, n, bools, nv); break;
    case GET_S: rc = fmi3GetString(c, vrs, n, strs, nv); break;
    case GET_U: rc = fmi3GetUInt64(c, vrs, n, u64s, nv); break;
    case SET_R: rc = fmi3SetFloat64(c, vrs, n, reals, nv); break;
    case SET_I: rc = fmi3SetInt32(c, vrs, n, ints, nv); break;
    case SET_B: rc = fmi3SetBoolean(c, vrs, n, bools, nv); break;
    case SET_S: rc = fmi3SetString(c, vrs, n, strs, nv); break;
    default: rc = fmi3SetUInt64(c, vrs, n, u64s, nv); break;
    }
#else
    fmi2Component c = w->c;
    switch (kind) {
    case GET_R: rc = fmi2GetReal(c, vrs, n, reals); break;
    case GET_I: case GET_U: rc = fmi2GetInteger(c, vrs, n, ints); break;
    case GET_B: rc = fmi2GetBoolean(c, vrs, n, bools); break;
    case GET_S: rc = fmi2GetString(c, vrs, n, strs); break;
    case SET_R: rc = fmi2SetReal(c, vrs, n, reals); break;
    case SET_I: case SET_U: rc = fmi2SetInteger(c, vrs, n, ints); break;
    case SET_B: rc = fmi2SetBoolean(c, vrs, n, bools); break;
    default: rc = fmi2SetString(c, vrs, n, strs); break;
    }
#endif
    if (rc == OK || rc == WARNING) {
        long e = expected_values(n, type, structural, set);
        if (e == -1)
            for (size_t k = 0; k < n && k < 8; k++)
                fprintf(stderr, "operation %d: value reference %u\n", kind, vrs[k]);
        check(e != -1, "a get or set OK with an unknown value reference or one of another type");
#ifdef FMI3
        check(e == -2 || (size_t)e == nv, "a get or set OK with nValues other than the values referenced");
#endif
        if (kind == GET_S)
            for (size_t k = 0; k < n; k++)
                check(strs[k] != NULL && strlen(strs[k]) < SARINS_STRING_MAX, "a String longer than its buffer");
        if (set)
            forbid(w, rc, B(T_TERM) | B(T_ERR), "a set OK after terminate or an error");
    }
    after(w, rc, -1);
}

static int pick_slot(input *in)
{
    return (int)(u8(in) % SLOTS);
}

static void op_get_state(world *w, input *in)
{
    int k = pick_slot(in);
    if (w->c == NULL)
        return;
#ifdef FMI3
    status rc = fmi3GetFMUState(w->c, &w->slot[k]);
#else
    status rc = fmi2GetFMUstate(w->c, &w->slot[k]);
#endif
    forbid(w, rc, B(T_ERR), "GetFMUstate OK after an error");
    if (rc == OK || rc == WARNING)
        w->slot_t[k] = w->t;
    after(w, rc, -1);
}

/* a state argument: a slot's (maybe NULL), a freed one or one never issued */
static fstate pick_state(world *w, input *in, int *tracked)
{
    unsigned b = u8(in) % 8;
    *tracked = T_UNKNOWN;
    if (b < SLOTS) {
        *tracked = w->slot_t[b];
        return w->slot[b];
    }
    if (b == 4)
        return w->freed;
    if (b == 5)
        return (fstate)foreign;
    if (b == 6)
        return (fstate)(void *)((unsigned char *)foreign + 1);
    return NULL;
}

static void op_set_state(world *w, input *in)
{
    int tracked;
    fstate s = pick_state(w, in, &tracked);
    if (w->c == NULL)
        return;
#ifdef FMI3
    status rc = fmi3SetFMUState(w->c, s);
#else
    status rc = fmi2SetFMUstate(w->c, s);
#endif
    after(w, rc, tracked);
}

static void op_free_state(world *w, input *in)
{
    unsigned b = u8(in) % 8;
    if (w->c == NULL)
        return;
    fstate other = b == 4 ? w->freed : b == 5 ? (fstate)foreign : NULL;
    fstate *p = b < SLOTS ? &w->slot[b] : &other;
    fstate before = *p;
#ifdef FMI3
    status rc = b == 7 ? fmi3FreeFMUState(w->c, NULL) : fmi3FreeFMUState(w->c, p);
#else
    status rc = b == 7 ? fmi2FreeFMUstate(w->c, NULL) : fmi2FreeFMUstate(w->c, p);
#endif
    if ((rc == OK || rc == WARNING) && b < SLOTS && before != NULL) {
        check(w->slot[b] == NULL, "FreeFMUstate OK left the state pointer set");
        w->freed = before;
    }
    after(w, rc, -1);
}

static void op_serialize(world *w, input *in)
{
    int tracked;
    fstate s = pick_state(w, in, &tracked);
    int k = (int)(u8(in) % BLOBS);
    unsigned how = u8(in) % 4;
    if (w->c == NULL)
        return;
    size_t n = 0;
#ifdef FMI3
    status rc = fmi3SerializedFMUStateSize(w->c, s, how == 3 ? NULL : &n);
#else
    status rc = fmi2SerializedFMUstateSize(w->c, s, how == 3 ? NULL : &n);
#endif
    after(w, rc, -1);
    if (rc != OK || n > (1u << 26))
        return;
    size_t cap = how == 1 ? n - (n > 0) : how == 2 ? n + 7 : n;
    unsigned char *buf = malloc(cap + 1);
    check(buf != NULL, "out of memory in the harness");
#ifdef FMI3
    rc = fmi3SerializeFMUState(w->c, s, buf, cap);
#else
    rc = fmi2SerializeFMUstate(w->c, s, (fmi2Byte *)buf, cap);
#endif
    after(w, rc, -1);
    if (rc == OK && cap >= n) {
        free(w->blob[k]);
        w->blob[k] = buf;
        w->blob_n[k] = n; /* the state is n bytes whatever the buffer */
        w->blob_t[k] = tracked;
    } else {
        check(rc != OK, "SerializeFMUstate OK into a buffer shorter than the state's size");
        free(buf);
    }
}

static void op_deserialize(world *w, input *in)
{
    int k = (int)(u8(in) % BLOBS), slot = pick_slot(in);
    unsigned how = u8(in) % 6, at = (unsigned)bytes(in, 2);
    static unsigned char tmp[1 << 16];
    const unsigned char *src = w->blob[k];
    size_t n = w->blob_n[k];
    int tracked = w->blob_t[k];
    if (how == 1 && n > 0) { /* one byte changed (the checksum must catch it) */
        memcpy(tmp, src, n < sizeof tmp ? n : sizeof tmp);
        n = n < sizeof tmp ? n : sizeof tmp;
        tmp[at % n] ^= (unsigned char)(1 + u8(in) % 255);
        src = tmp;
        tracked = T_UNKNOWN;
    } else if (how == 2 && n > 0) { /* truncated */
        n = at % n;
        tracked = T_UNKNOWN;
    } else if (how == 3) { /* bytes of the input */
        n = u8(in);
        n = n < in->n ? n : in->n;
        memcpy(tmp, in->p, n);
        in->p += n;
        in->n -= n;
        src = tmp;
        tracked = T_UNKNOWN;
    } else if (how == 4) {
        src = NULL;
    }
    if (w->c == NULL)
        return;
    fstate *into = how == 5 ? NULL : &w->slot[slot];
#ifdef FMI3
    status rc = fmi3DeserializeFMUState(w->c, src, n, into);
#else
    status rc = fmi2DeSerializeFMUstate(w->c, (const fmi2Byte *)src, n, into);
#endif
    if (rc == OK || rc == WARNING)
        w->slot_t[slot] = tracked;
    after(w, rc, -1);
}

static void op_debug_logging(world *w, input *in)
{
    unsigned b = u8(in);
    const char *cats[3];
    char raw[64];
    size_t n = b % 4;
    for (size_t k = 0; k < 3; k++)
        cats[k] = SARINS_TABLE.n_categories > 0 && (u8(in) & 1) ? SARINS_TABLE.categories[k % SARINS_TABLE.n_categories]
                                                                 : pick_string(in, NULL, raw, sizeof raw);
    if (w->c == NULL)
        return;
#ifdef FMI3
    status rc = fmi3SetDebugLogging(w->c, (b & 4) != 0, n, (b & 8) ? NULL : cats);
#else
    status rc = fmi2SetDebugLogging(w->c, (b & 4) ? fmi2True : fmi2False, n, (b & 8) ? NULL : cats);
#endif
    after(w, rc, -1);
}

static void op_lifecycle(world *w, input *in, int which)
{
    double start = pick_time(in, 0.0), stop = pick_time(in, 0.0);
    unsigned stop_defined = u8(in) & 1;
    if (w->c == NULL)
        return;
    status rc;
    switch (which) {
    case 0: /* enter initialisation */
#ifdef FMI3
        rc = fmi3EnterInitializationMode(w->c, fmi3False, 0.0, start, stop_defined ? fmi3True : fmi3False, stop);
#else
        rc = fmi2EnterInitializationMode(w->c);
#endif
        forbid(w, rc, ~B(T_INST), "EnterInitializationMode OK outside Instantiated");
        after(w, rc, T_INIT);
        break;
    case 1:
#ifdef FMI3
        rc = fmi3ExitInitializationMode(w->c);
#else
        rc = fmi2ExitInitializationMode(w->c);
#endif
        forbid(w, rc, ~B(T_INIT), "ExitInitializationMode OK outside Initialization Mode");
        after(w, rc, T_STEP);
        break;
    case 2:
#ifdef FMI3
        rc = fmi3Terminate(w->c);
#else
        rc = fmi2Terminate(w->c);
#endif
        forbid(w, rc, B(T_INST) | B(T_TERM) | B(T_ERR) | B(T_CONF) | B(T_RECONF), "Terminate OK before "
               "initialisation, after terminate or after an error");
        after(w, rc, T_TERM);
        break;
    case 3:
#ifdef FMI3
        rc = fmi3Reset(w->c);
#else
        rc = fmi2Reset(w->c);
#endif
        after(w, rc, T_INST);
        break;
    case 4: /* FMI 2.0: set up the experiment; FMI 3.0: enter (re)configuration mode */
#ifdef FMI3
        rc = fmi3EnterConfigurationMode(w->c);
        forbid(w, rc, ~(B(T_INST) | B(T_STEP)), "EnterConfigurationMode OK outside Instantiated and Step Mode");
        after(w, rc, w->t == T_INST ? T_CONF : w->t == T_STEP ? T_RECONF : T_UNKNOWN);
#else
        rc = fmi2SetupExperiment(w->c, fmi2False, 0.0, start, stop_defined ? fmi2True : fmi2False, stop);
        forbid(w, rc, ~B(T_INST), "SetupExperiment OK after instantiation");
        after(w, rc, -1);
#endif
        break;
    default:
#ifdef FMI3
        rc = fmi3ExitConfigurationMode(w->c);
        forbid(w, rc, ~(B(T_CONF) | B(T_RECONF)), "ExitConfigurationMode OK outside Configuration Mode");
        after(w, rc, w->t == T_CONF ? T_INST : w->t == T_RECONF ? T_STEP : T_UNKNOWN);
#else
        {
            double x = 0.0;
            fmi2Boolean yes = fmi2True;
            fmi2Status st;
            unsigned kind = u8(in) % 5;
            rc = kind == 0 ? fmi2GetRealStatus(w->c, fmi2LastSuccessfulTime, &x)
               : kind == 1 ? fmi2GetBooleanStatus(w->c, fmi2Terminated, &yes)
               : kind == 2 ? fmi2GetStatus(w->c, fmi2DoStepStatus, &st)
               : kind == 3 ? fmi2CancelStep(w->c) : fmi2GetRealStatus(w->c, fmi2LastSuccessfulTime, NULL);
            after(w, rc, -1);
        }
#endif
        break;
    }
}

/* the calls this FMU does not support, and calls on a NULL instance: an error, never a crash */
static void op_odd(world *w, input *in)
{
    unsigned b = u8(in) % 8;
    inst c = (b & 1) ? NULL : w->c;
    unsigned vr = pick_vr(in);
    double x = 0.0;
    status rc;
#ifdef FMI3
    fmi3Float32 f = 0.0f;
    switch (b >> 1) {
    case 0: rc = fmi3GetFloat32(c, &vr, 1, &f, 1); break;
    case 1: rc = fmi3GetFloat64(c, &vr, 1, &x, 1); break;
    case 2: rc = fmi3DoStep(c, 0.0, 1.0, fmi3False, NULL, NULL, NULL, NULL); break;
    default: rc = fmi3EnterStepMode(c); break;
    }
#else
    fmi2Real dv = 0.0;
    switch (b >> 1) {
    case 0: rc = fmi2GetDirectionalDerivative(c, &vr, 1, &vr, 1, &dv, &x); break;
    case 1: rc = fmi2GetReal(c, &vr, 1, &x); break;
    case 2: rc = fmi2DoStep(c, 0.0, 1.0, fmi2False); break;
    default: rc = fmi2SetRealInputDerivatives(c, &vr, 1, (const fmi2Integer[]){1}, &dv); break;
    }
#endif
    if (c == NULL) {
        check(rc == ERROR || rc > ERROR, "a call on a NULL instance did not return Error");
        return;
    }
    if ((b >> 1) == 1 && rc == OK) {
        vrs[0] = vr;
        long e = expected_values(1, SARINS_REAL, 0, 0);
        check(e == 1 || e == -2, "a get OK with an unknown value reference");
    }
    after(w, rc, -1);
}

#define N_OPS 22

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static world w0;
    world *w = &w0;
    memset(w, 0, sizeof *w);
    if (long_a[0] == '\0') {
        memset(long_a, 'a', sizeof long_a - 1);
        memset(fits, 'b', sizeof fits - 1);
        memset(one_over, 'c', sizeof one_over - 1);
    }
    input in = {data, size};
    int ops = 0;
    while (in.n > 0 && ops++ < 400) {
        switch (u8(&in) % N_OPS) {
        case 0: op_instantiate(w, &in); break;
        case 1: free_instance(w); break;
        case 2: op_lifecycle(w, &in, 4); break;
        case 3: op_lifecycle(w, &in, 0); break;
        case 4: op_lifecycle(w, &in, 1); break;
        case 5: op_do_step(w, &in); break;
        case 6: op_lifecycle(w, &in, 2); break;
        case 7: op_lifecycle(w, &in, 3); break;
        case 8: op_values(w, &in, GET_R); break;
        case 9: op_values(w, &in, GET_I); break;
        case 10: op_values(w, &in, GET_B); break;
        case 11: op_values(w, &in, GET_S); break;
        case 12: op_values(w, &in, SET_R); break;
        case 13: op_values(w, &in, (u8(&in) & 1) ? SET_U : SET_I); break;
        case 14: op_values(w, &in, (u8(&in) & 1) ? SET_B : GET_U); break;
        case 15: op_values(w, &in, SET_S); break;
        case 16: op_get_state(w, &in); break;
        case 17: op_set_state(w, &in); break;
        case 18: op_free_state(w, &in); break;
        case 19: op_serialize(w, &in); break;
        case 20: op_deserialize(w, &in); break;
        default:
            if (u8(&in) & 1)
                op_debug_logging(w, &in);
            else if (u8(&in) & 1)
                op_lifecycle(w, &in, 5);
            else
                op_odd(w, &in);
            break;
        }
    }
    free_instance(w);
    for (int k = 0; k < BLOBS; k++)
        free(w->blob[k]);
    return 0;
}

#ifdef SARINS_FUZZ_MAIN
int main(int argc, char **argv)
{
    static unsigned char buf[1 << 20];
    for (int k = 1; k < argc; k++) {
        FILE *f = fopen(argv[k], "rb");
        if (f == NULL)
            return 2;
        size_t n = fread(buf, 1, sizeof buf, f);
        fclose(f);
        LLVMFuzzerTestOneInput(buf, n);
    }
    printf("ran %d inputs\n", argc - 1);
    return 0;
}
#endif
