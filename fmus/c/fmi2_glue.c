/* FMI 2.0 co-simulation in C for one native model (fmus/c/<model>/model.c, interface in model.h).
 *
 * Contract (the one fmus/native/core.c keeps for the Python-hosted FMUs):
 * - the state machine of FMI 2.0 section 4.2.4: a call out of order returns fmi2Error with a logged
 *   message and puts the instance in the error state, which only fmi2Reset or fmi2FreeInstance leave;
 * - value references and types are checked against the model's variable table; fmi2Set* checks
 *   causality/variability against the current state;
 * - bad input gives fmi2Error with a logged reason, never fmi2Fatal, never a crash;
 * - parameters are checked at fmi2ExitInitializationMode (the model's initialize());
 * - a Real output that is not finite is never returned with fmi2OK (checked after every callback);
 * - the first fmi2DoStep starts at fmi2SetupExperiment's start time (0 without it), each next one where
 *   the previous ended;
 * - messages reach the host's logger: status >= fmi2Discard always, others when debug logging is on for
 *   their category (loggingOn at instantiation switches every category on; fmi2SetDebugLogging changes them).
 * FMU state (canGetAndSetFMUstate, canSerializeFMUstate): a state is one self-describing blob, the same
 * bytes in memory and serialized: header (magic, format version, the model's state version, byte order,
 * GUID, payload size, FNV-1a checksum of the payload) and payload (FMI state, time, every value, the model's
 * plain-bytes state, its work state).  A wrong, truncated or foreign blob is refused with fmi2Error.
 * Memory: fmi2Instantiate allocates the instance; the model allocates in initialize(); after that nothing
 * allocates except the FMU-state calls (fmi2GetFMUstate and fmi2DeSerializeFMUstate allocate the blob,
 * fmi2SetFMUstate may rebuild the model's work from restored parameters).  No globals.
 */
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "model.h"

enum { S_INSTANTIATED = 1, S_INIT = 2, S_STEP_COMPLETE = 4, S_STEP_FAILED = 8, S_TERMINATED = 16, S_ERROR = 32 };
#define ANY_STATE (S_INSTANTIATED | S_INIT | S_STEP_COMPLETE | S_STEP_FAILED | S_TERMINATED | S_ERROR)
#define GET_STATES ANY_STATE
#define SET_STATES (S_INSTANTIATED | S_INIT | S_STEP_COMPLETE)
#define FMU_STATE_STATES (S_INSTANTIATED | S_INIT | S_STEP_COMPLETE | S_STEP_FAILED | S_TERMINATED)
#define RUN_STATES (S_STEP_COMPLETE | S_STEP_FAILED | S_TERMINATED)

static const char *const TYPE_NAMES[] = {"Real", "Integer", "Boolean", "String"};
static const char *const CAUSALITY_NAMES[] = {"parameter", "calculatedParameter", "input", "output", "local",
                                              "independent"};
static const char *const VARIABILITY_NAMES[] = {"constant", "fixed", "tunable", "discrete", "continuous"};

struct sarins_glue {
    const sarins_model *model;
    const sarins_table *table;
    char *name;
    fmi2CallbackLogger logger;
    fmi2ComponentEnvironment env;
    int state;
    int *cat_on;
    const sarins_var **by_vr; /* value reference -> variable (NULL: none) */
    size_t n_vr;
    unsigned char *values; /* the value arrays, one block: r, i, b, s */
    unsigned char *built;  /* the value block as initialize() last saw it (its parameters built c->work) */
    size_t values_size;
    double built_start;
    int have_built;
    sarins_ctx ctx;
    int have_time;
    double t_next;
    unsigned long problems; /* messages logged with status >= Discard (so a failure is never silent) */
};

/* ---------------------------------------------------------------- logging */

static int category_index(const sarins_glue *g, const char *name)
{
    for (size_t i = 0; i < g->table->n_categories; i++)
        if (strcmp(g->table->categories[i], name) == 0)
            return (int)i;
    return -1;
}

static int category_on(const sarins_glue *g, const char *category)
{
    int all = category_index(g, "logAll");
    if (all >= 0 && g->cat_on[all])
        return 1;
    int i = category ? category_index(g, category) : -1;
    if (i >= 0)
        return g->cat_on[i];
    for (size_t k = 0; k < g->table->n_categories; k++)
        if (g->cat_on[k])
            return 1;
    return 0;
}

static const char *status_category(int status)
{
    switch (status) {
    case fmi2Warning: return "logStatusWarning";
    case fmi2Discard: return "logStatusDiscard";
    case fmi2Error: return "logStatusError";
    case fmi2Fatal: return "logStatusFatal";
    default: return "logAll";
    }
}

static void vlog(sarins_glue *g, int status, const char *fmt, va_list ap)
{
    if (status >= fmi2Discard)
        g->problems++;
    const char *category = status_category(status);
    if (g->logger == NULL || (status < fmi2Discard && !category_on(g, category)))
        return;
    char text[2048];
    vsnprintf(text, sizeof text, fmt, ap);
    g->logger(g->env, g->name, (fmi2Status)status, category, "%s", text);
}

void sarins_log(const sarins_ctx *c, int status, const char *fmt, ...)
{
    if (c == NULL || c->glue == NULL || c->quiet)
        return;
    va_list ap;
    va_start(ap, fmt);
    vlog(c->glue, status, fmt, ap);
    va_end(ap);
}

static void logf_(sarins_glue *g, int status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static void logf_(sarins_glue *g, int status, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vlog(g, status, fmt, ap);
    va_end(ap);
}

static const char *state_name(int s)
{
    switch (s) {
    case S_INSTANTIATED: return "instantiated";
    case S_INIT: return "initializationMode";
    case S_STEP_COMPLETE: return "stepComplete";
    case S_STEP_FAILED: return "stepFailed";
    case S_TERMINATED: return "terminated";
    case S_ERROR: return "error";
    default: return "unknown";
    }
}

/* Log an error, put the instance in the error state, return fmi2Error. */
static fmi2Status fail(sarins_glue *g, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
static fmi2Status fail(sarins_glue *g, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vlog(g, fmi2Error, fmt, ap);
    va_end(ap);
    g->state = S_ERROR;
    return fmi2Error;
}

static fmi2Status bad_state(sarins_glue *g, const char *fn)
{
    if (g->state == S_ERROR) {
        logf_(g, fmi2Error, "%s: not allowed after an earlier error (state 'error'); call fmi2Reset or "
              "fmi2FreeInstance", fn);
        return fmi2Error;
    }
    return fail(g, "%s: not allowed in state '%s' (FMI 2.0 section 4.2.4)", fn, state_name(g->state));
}

#define REQUIRE(g, fn, allowed)                                                                              \
    do {                                                                                                     \
        if ((g) == NULL)                                                                                     \
            return fmi2Error;                                                                                \
        if (!((g)->state & (allowed)))                                                                       \
            return bad_state((g), (fn));                                                                     \
    } while (0)

/* A model callback's status as the call's: a failure the model did not explain gets a generic reason. */
static fmi2Status model_status(sarins_glue *g, int status, unsigned long problems_before, const char *fn)
{
    if (status == SARINS_OK || status == SARINS_WARNING)
        return (fmi2Status)status;
    if (status == SARINS_DISCARD) {
        if (g->problems == problems_before)
            logf_(g, fmi2Discard, "%s: the model refused the call", fn);
        return fmi2Discard;
    }
    if (g->problems == problems_before)
        return fail(g, "%s: the model failed (status %d)", fn, status);
    g->state = S_ERROR;
    return fmi2Error;
}

/* ------------------------------------------------------------- values */

static size_t off_int(const sarins_table *t) { return t->n_real * sizeof(double); }
static size_t off_bool(const sarins_table *t) { return off_int(t) + t->n_integer * sizeof(int); }
static size_t off_string(const sarins_table *t) { return off_bool(t) + t->n_boolean * sizeof(int); }
static size_t off_set(const sarins_table *t) { return off_string(t) + t->n_string * SARINS_STRING_MAX; }
static size_t values_size(const sarins_table *t) { return off_set(t) + t->n_vars; } /* + one set flag per vr */

static void point_ctx(sarins_glue *g)
{
    const sarins_table *t = g->table;
    g->ctx.r = (double *)(void *)g->values;
    g->ctx.i = (int *)(void *)(g->values + off_int(t));
    g->ctx.b = (int *)(void *)(g->values + off_bool(t));
    g->ctx.s = (char(*)[SARINS_STRING_MAX])(void *)(g->values + off_string(t));
    g->ctx.set = g->values + off_set(t);
}

static void set_start_values(sarins_glue *g)
{
    memset(g->values, 0, g->values_size);
    for (size_t k = 0; k < g->table->n_vars; k++) {
        const sarins_var *v = &g->table->vars[k];
        switch (v->type) {
        case SARINS_REAL: g->ctx.r[v->slot] = v->start_real; break;
        case SARINS_INTEGER: g->ctx.i[v->slot] = v->start_int; break;
        case SARINS_BOOLEAN: g->ctx.b[v->slot] = v->start_int ? 1 : 0; break;
        default:
            if (v->start_string != NULL)
                snprintf(g->ctx.s[v->slot], SARINS_STRING_MAX, "%s", v->start_string);
            break;
        }
    }
}

/* Every Real output finite, else fmi2Error naming it. */
static fmi2Status check_outputs(sarins_glue *g, const char *fn)
{
    for (size_t k = 0; k < g->table->n_vars; k++) {
        const sarins_var *v = &g->table->vars[k];
        if (v->type == SARINS_REAL && v->causality == SARINS_OUTPUT && !isfinite(g->ctx.r[v->slot]))
            return fail(g, "%s: output %s = %g is not finite", fn, v->name, g->ctx.r[v->slot]);
    }
    return fmi2OK;
}

static void release_work(sarins_glue *g)
{
    g->model->release(&g->ctx);
    g->ctx.work = NULL;
    g->have_built = 0;
}

/* initialize() from the current values; on success remember the parameters it was given. */
static int run_initialize(sarins_glue *g, int quiet)
{
    release_work(g);
    g->ctx.quiet = quiet;
    int status = g->model->initialize(&g->ctx);
    g->ctx.quiet = 0;
    if (status == SARINS_OK || status == SARINS_WARNING) {
        memcpy(g->built, g->values, g->values_size);
        g->built_start = g->ctx.start_time;
        g->have_built = 1;
    } else {
        release_work(g);
    }
    return status;
}

/* ------------------------------------------------------------- instances */

static void free_glue(sarins_glue *g)
{
    if (g == NULL)
        return;
    if (g->model != NULL && g->ctx.work != NULL)
        g->model->release(&g->ctx);
    free(g->ctx.state);
    free(g->values);
    free(g->built);
    free((void *)g->by_vr);
    free(g->cat_on);
    free(g->name);
    free(g);
}

static char *copy_string(const char *s)
{
    size_t n = strlen(s) + 1;
    char *c = malloc(n);
    if (c != NULL)
        memcpy(c, s, n);
    return c;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn)
{
    (void)fmuResourceLocation; /* a native model needs no resources */
    (void)visible;
    const sarins_model *m = &sarins_model_desc;
    const sarins_table *t = m->table;
    sarins_glue *g = calloc(1, sizeof *g);
    if (g == NULL) {
        if (functions && functions->logger)
            functions->logger(functions->componentEnvironment, instanceName ? instanceName : "", fmi2Error,
                              "logStatusError", "fmi2Instantiate: out of memory");
        return NULL;
    }
    g->model = m;
    g->table = t;
    g->ctx.glue = g;
    if (functions != NULL) {
        g->logger = functions->logger;
        g->env = functions->componentEnvironment;
    }
    g->name = copy_string(instanceName ? instanceName : "");
    g->cat_on = calloc(t->n_categories ? t->n_categories : 1, sizeof(int));
    unsigned max_vr = 0;
    for (size_t k = 0; k < t->n_vars; k++)
        if (t->vars[k].vr > max_vr)
            max_vr = t->vars[k].vr;
    g->n_vr = t->n_vars ? (size_t)max_vr + 1 : 0;
    g->by_vr = calloc(g->n_vr ? g->n_vr : 1, sizeof(const sarins_var *));
    g->values_size = values_size(t);
    g->values = calloc(g->values_size ? g->values_size : 1, 1);
    g->built = calloc(g->values_size ? g->values_size : 1, 1);
    g->ctx.state = calloc(m->state_size ? m->state_size : 1, 1);
    if (!g->name || !g->cat_on || !g->by_vr || !g->values || !g->built || !g->ctx.state) {
        if (g->logger)
            g->logger(g->env, instanceName ? instanceName : "", fmi2Error, "logStatusError",
                      "fmi2Instantiate: out of memory");
        free_glue(g);
        return NULL;
    }
    for (size_t i = 0; i < t->n_categories; i++)
        g->cat_on[i] = loggingOn ? 1 : 0;
    if (!instanceName || !instanceName[0]) {
        logf_(g, fmi2Error, "fmi2Instantiate: the instance name must not be empty");
        free_glue(g);
        return NULL;
    }
    if (fmuType != fmi2CoSimulation) {
        logf_(g, fmi2Error, "fmi2Instantiate: this FMU supports co-simulation only (fmuType %d)", (int)fmuType);
        free_glue(g);
        return NULL;
    }
    if (fmuGUID == NULL || strcmp(fmuGUID, t->guid) != 0) {
        logf_(g, fmi2Error, "fmi2Instantiate: GUID '%.100s' does not match this FMU's '%s' (modelDescription.xml "
              "of another FMU?)", fmuGUID ? fmuGUID : "(null)", t->guid);
        free_glue(g);
        return NULL;
    }
    for (size_t k = 0; k < t->n_vars; k++) {
        const sarins_var *v = &t->vars[k];
        g->by_vr[v->vr] = v;
    }
    point_ctx(g);
    set_start_values(g);
    g->state = S_INSTANTIATED;
    return (fmi2Component)g;
}

void fmi2FreeInstance(fmi2Component c)
{
    free_glue((sarins_glue *)c);
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t n, const fmi2String categories[])
{
    sarins_glue *g = (sarins_glue *)c;
    if (g == NULL)
        return fmi2Error;
    if (n > 0 && categories == NULL)
        return fail(g, "fmi2SetDebugLogging: categories is NULL");
    if (n == 0) {
        for (size_t i = 0; i < g->table->n_categories; i++)
            g->cat_on[i] = loggingOn ? 1 : 0;
        return fmi2OK;
    }
    fmi2Status st = fmi2OK;
    for (size_t k = 0; k < n; k++) {
        int i = categories[k] ? category_index(g, categories[k]) : -1;
        if (i < 0) {
            logf_(g, fmi2Warning, "fmi2SetDebugLogging: unknown log category %s",
                  categories[k] ? categories[k] : "(null)");
            st = fmi2Warning;
        } else {
            g->cat_on[i] = loggingOn ? 1 : 0;
        }
    }
    return st;
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2SetupExperiment", S_INSTANTIATED);
    (void)toleranceDefined;
    (void)tolerance;
    if (!isfinite(startTime))
        return fail(g, "fmi2SetupExperiment: start time %g is not finite", startTime);
    if (stopTimeDefined && !(stopTime >= startTime))
        return fail(g, "fmi2SetupExperiment: stop time %g before start %g", stopTime, startTime);
    g->ctx.start_time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2EnterInitializationMode", S_INSTANTIATED);
    /* outputs during initialisation; a bad parameter is reported at fmi2ExitInitializationMode */
    (void)run_initialize(g, 1);
    g->state = S_INIT;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2ExitInitializationMode", S_INIT);
    unsigned long before = g->problems;
    fmi2Status st = model_status(g, run_initialize(g, 0), before, "fmi2ExitInitializationMode");
    if (st > fmi2Warning) {
        g->state = S_ERROR;
        return fmi2Error;
    }
    if (check_outputs(g, "fmi2ExitInitializationMode") != fmi2OK)
        return fmi2Error;
    g->state = S_STEP_COMPLETE;
    g->have_time = 0;
    return st;
}

fmi2Status fmi2Terminate(fmi2Component c)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2Terminate", S_STEP_COMPLETE | S_STEP_FAILED);
    if (g->model->terminate != NULL)
        g->model->terminate(&g->ctx);
    g->state = S_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2Reset", ANY_STATE);
    release_work(g);
    memset(g->ctx.state, 0, g->model->state_size ? g->model->state_size : 1);
    set_start_values(g);
    g->ctx.start_time = 0.0;
    g->have_time = 0;
    g->t_next = 0.0;
    g->state = S_INSTANTIATED; /* debug-logging settings survive a reset */
    return fmi2OK;
}

/* --------------------------------------------------------- get and set */

/* One value reference: known, of this type, and (setting) settable in this state. */
static const sarins_var *check_vr(sarins_glue *g, const char *fn, fmi2ValueReference vr, int type, int setting)
{
    const sarins_var *v = (size_t)vr < g->n_vr ? g->by_vr[vr] : NULL;
    if (v == NULL) {
        fail(g, "%s: unknown value reference %u", fn, (unsigned)vr);
        return NULL;
    }
    if (v->type != type) {
        fail(g, "%s: %s (value reference %u) is a%s %s, not a%s %s", fn, v->name, (unsigned)vr,
             v->type == SARINS_INTEGER ? "n" : "", TYPE_NAMES[v->type], type == SARINS_INTEGER ? "n" : "",
             TYPE_NAMES[type]);
        return NULL;
    }
    if (!setting)
        return v;
    int ok;
    if (v->variability == SARINS_CONSTANT)
        ok = 0;
    else if (g->state == S_INSTANTIATED || g->state == S_INIT)
        ok = (v->causality == SARINS_PARAMETER || v->causality == SARINS_INPUT);
    else
        ok = (v->causality == SARINS_INPUT || (v->causality == SARINS_PARAMETER && v->variability == SARINS_TUNABLE));
    if (!ok) {
        fail(g, "%s: %s (value reference %u, causality %s, variability %s) cannot be set in state '%s'", fn,
             v->name, (unsigned)vr, CAUSALITY_NAMES[v->causality], VARIABILITY_NAMES[v->variability],
             state_name(g->state));
        return NULL;
    }
    return v;
}

/* Every value reference checked before any value moves (a refused call changes nothing). */
static int check_args(sarins_glue *g, const char *fn, const fmi2ValueReference vr[], size_t n, const void *values,
                      int type, int setting)
{
    if (n == 0)
        return 1;
    if (vr == NULL || values == NULL) {
        fail(g, "%s: NULL value reference or value array", fn);
        return 0;
    }
    for (size_t k = 0; k < n; k++)
        if (check_vr(g, fn, vr[k], type, setting) == NULL)
            return 0;
    return 1;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[])
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2GetReal", GET_STATES);
    if (!check_args(g, "fmi2GetReal", vr, nvr, value, SARINS_REAL, 0))
        return fmi2Error;
    for (size_t k = 0; k < nvr; k++) {
        const sarins_var *v = g->by_vr[vr[k]];
        value[k] = g->ctx.r[v->slot];
        if (v->causality == SARINS_OUTPUT && !isfinite(value[k]))
            return fail(g, "fmi2GetReal: output %s = %g is not finite", v->name, value[k]);
    }
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[])
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2GetInteger", GET_STATES);
    if (!check_args(g, "fmi2GetInteger", vr, nvr, value, SARINS_INTEGER, 0))
        return fmi2Error;
    for (size_t k = 0; k < nvr; k++)
        value[k] = g->ctx.i[g->by_vr[vr[k]]->slot];
    return fmi2OK;
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[])
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2GetBoolean", GET_STATES);
    if (!check_args(g, "fmi2GetBoolean", vr, nvr, value, SARINS_BOOLEAN, 0))
        return fmi2Error;
    for (size_t k = 0; k < nvr; k++)
        value[k] = g->ctx.b[g->by_vr[vr[k]]->slot] ? fmi2True : fmi2False;
    return fmi2OK;
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[])
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2GetString", GET_STATES);
    if (!check_args(g, "fmi2GetString", vr, nvr, value, SARINS_STRING, 0))
        return fmi2Error;
    for (size_t k = 0; k < nvr; k++)
        value[k] = g->ctx.s[g->by_vr[vr[k]]->slot]; /* valid until the value changes or the instance is freed */
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[])
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2SetReal", SET_STATES);
    if (!check_args(g, "fmi2SetReal", vr, nvr, value, SARINS_REAL, 1))
        return fmi2Error;
    for (size_t k = 0; k < nvr; k++) {
        g->ctx.r[g->by_vr[vr[k]]->slot] = value[k];
        g->ctx.set[g->by_vr[vr[k]] - g->table->vars] = 1; /* its row = its vr (native_fmu.py) */
    }
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[])
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2SetInteger", SET_STATES);
    if (!check_args(g, "fmi2SetInteger", vr, nvr, value, SARINS_INTEGER, 1))
        return fmi2Error;
    for (size_t k = 0; k < nvr; k++) {
        g->ctx.i[g->by_vr[vr[k]]->slot] = value[k];
        g->ctx.set[g->by_vr[vr[k]] - g->table->vars] = 1; /* its row = its vr (native_fmu.py) */
    }
    return fmi2OK;
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[])
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2SetBoolean", SET_STATES);
    if (!check_args(g, "fmi2SetBoolean", vr, nvr, value, SARINS_BOOLEAN, 1))
        return fmi2Error;
    for (size_t k = 0; k < nvr; k++) {
        g->ctx.b[g->by_vr[vr[k]]->slot] = value[k] ? 1 : 0;
        g->ctx.set[g->by_vr[vr[k]] - g->table->vars] = 1; /* its row = its vr (native_fmu.py) */
    }
    return fmi2OK;
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[])
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2SetString", SET_STATES);
    if (!check_args(g, "fmi2SetString", vr, nvr, value, SARINS_STRING, 1))
        return fmi2Error;
    for (size_t k = 0; k < nvr; k++) {
        const sarins_var *v = g->by_vr[vr[k]];
        if (value[k] == NULL)
            return fail(g, "fmi2SetString: NULL value for %s", v->name);
        if (strlen(value[k]) >= SARINS_STRING_MAX)
            return fail(g, "fmi2SetString: the value of %s is %llu bytes long, at most %d are allowed", v->name,
                        (unsigned long long)strlen(value[k]), SARINS_STRING_MAX - 1);
    }
    for (size_t k = 0; k < nvr; k++) {
        snprintf(g->ctx.s[g->by_vr[vr[k]]->slot], SARINS_STRING_MAX, "%s", value[k]);
        g->ctx.set[g->by_vr[vr[k]] - g->table->vars] = 1; /* its row = its vr (native_fmu.py) */
    }
    return fmi2OK;
}

/* ---------------------------------------------------------------- step */

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    sarins_glue *g = (sarins_glue *)c;
    (void)noSetFMUStatePriorToCurrentPoint;
    REQUIRE(g, "fmi2DoStep", S_STEP_COMPLETE);
    if (!isfinite(t))
        return fail(g, "fmi2DoStep: communication point %g is not finite", t);
    if (!(h > 0.0) || !isfinite(h))
        return fail(g, "fmi2DoStep: communication step size %g must be positive and finite", h);
    if (g->have_time && fabs(t - g->t_next) > 1e-9 * fmax(1.0, fabs(g->t_next)))
        return fail(g, "fmi2DoStep: communication point %.17g does not continue the previous step, which ended at "
                    "%.17g", t, g->t_next);
    double start = g->ctx.start_time;
    if (!g->have_time && fabs(t - start) > 1e-9 * fmax(1.0, fabs(start)))
        return fail(g, "fmi2DoStep: the first communication point %.17g is not the start time %.17g "
                    "(fmi2SetupExperiment)", t, start);
    unsigned long before = g->problems;
    fmi2Status st = model_status(g, g->model->do_step(&g->ctx, t, h), before, "fmi2DoStep");
    if (st == fmi2Discard) {
        g->state = S_STEP_FAILED;
        return st;
    }
    if (st > fmi2Discard)
        return st;
    if (check_outputs(g, "fmi2DoStep") != fmi2OK)
        return fmi2Error;
    g->have_time = 1;
    g->t_next = t + h;
    return st;
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    sarins_glue *g = (sarins_glue *)c;
    if (g == NULL)
        return fmi2Error;
    return fail(g, "fmi2CancelStep: no asynchronous step is in progress (this FMU steps synchronously)");
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2GetStatus", RUN_STATES);
    (void)s;
    (void)value;
    return fmi2Discard; /* only meaningful for asynchronous steps */
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2GetRealStatus", RUN_STATES);
    if (s == fmi2LastSuccessfulTime && value != NULL) {
        *value = g->have_time ? g->t_next : g->ctx.start_time;
        return fmi2OK;
    }
    return fmi2Discard;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2GetIntegerStatus", RUN_STATES);
    (void)s;
    (void)value;
    return fmi2Discard;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2GetBooleanStatus", RUN_STATES);
    if (s == fmi2Terminated && value != NULL) {
        *value = fmi2False; /* the model never asks to end the simulation */
        return fmi2OK;
    }
    return fmi2Discard;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2GetStringStatus", RUN_STATES);
    (void)s;
    (void)value;
    return fmi2Discard;
}

/* ------------------------------------------------------------ FMU state */

#define STATE_MAGIC "SARINSst"
#define STATE_FORMAT 1u
#define BYTE_ORDER_MARK 0x01020304u
#define GUID_BYTES 64
/* header: magic 8, format 4, model state version 4, byte-order mark 4, string size 4, GUID 64,
 * payload size 8, checksum 8 */
#define HEADER_BYTES (8 + 4 + 4 + 4 + 4 + GUID_BYTES + 8 + 8)
#define OFF_PAYLOAD_SIZE (8 + 4 + 4 + 4 + 4 + GUID_BYTES)
#define OFF_CHECKSUM (OFF_PAYLOAD_SIZE + 8)
/* payload: FMI state 4, have_time 4, t_next 8, start_time 8, n_real/n_integer/n_boolean/n_string 4 x 8,
 * value block, model state size 8, model state, work-state size 8, work state */
#define FIXED_PAYLOAD (4 + 4 + 8 + 8 + 4 * 8)

typedef struct {
    size_t size;           /* bytes of data */
    unsigned char data[]; /* header + payload */
} fmu_state;

static uint64_t fnv1a(const unsigned char *p, size_t n)
{
    uint64_t h = 1469598103934665603ULL;
    for (size_t i = 0; i < n; i++) {
        h ^= p[i];
        h *= 1099511628211ULL;
    }
    return h;
}

static unsigned char *put(unsigned char *p, const void *v, size_t n)
{
    if (n > 0)
        memcpy(p, v, n);
    return p + n;
}

static const unsigned char *get(const unsigned char *p, void *v, size_t n)
{
    if (n > 0)
        memcpy(v, p, n);
    return p + n;
}

static int post_init(int state) { return (state & RUN_STATES) != 0; }

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2GetFMUstate", FMU_STATE_STATES);
    if (FMUstate == NULL)
        return fail(g, "fmi2GetFMUstate: FMUstate is NULL");
    const sarins_model *m = g->model;
    uint64_t work_n = 0;
    if (post_init(g->state) && m->work_state_size != NULL && g->ctx.work != NULL)
        work_n = (uint64_t)m->work_state_size(&g->ctx);
    uint64_t payload = FIXED_PAYLOAD + g->values_size + 8 + m->state_size + 8 + work_n;
    size_t total = HEADER_BYTES + (size_t)payload;
    /* an existing state of this model is overwritten in place when it has the size (FMI 2.0 allows reuse) */
    fmu_state *s = (fmu_state *)*FMUstate;
    if (s == NULL || s->size != total) {
        fmu_state *fresh = malloc(sizeof(fmu_state) + total);
        if (fresh == NULL)
            return fail(g, "fmi2GetFMUstate: out of memory (%llu bytes)", (unsigned long long)total);
        free(s);
        s = fresh;
        s->size = total;
    }
    unsigned char *p = s->data;
    uint32_t u32;
    char guid[GUID_BYTES] = {0};
    snprintf(guid, sizeof guid, "%s", g->table->guid);
    p = put(p, STATE_MAGIC, 8);
    u32 = STATE_FORMAT;
    p = put(p, &u32, 4);
    u32 = m->state_version;
    p = put(p, &u32, 4);
    u32 = BYTE_ORDER_MARK;
    p = put(p, &u32, 4);
    u32 = SARINS_STRING_MAX;
    p = put(p, &u32, 4);
    p = put(p, guid, GUID_BYTES);
    p = put(p, &payload, 8);
    p += 8; /* checksum, below */
    unsigned char *body = p;
    int32_t state = g->state, have_time = g->have_time;
    uint64_t counts[4] = {g->table->n_real, g->table->n_integer, g->table->n_boolean, g->table->n_string};
    uint64_t state_n = m->state_size;
    p = put(p, &state, 4);
    p = put(p, &have_time, 4);
    p = put(p, &g->t_next, 8);
    p = put(p, &g->ctx.start_time, 8);
    p = put(p, counts, sizeof counts);
    p = put(p, g->values, g->values_size);
    p = put(p, &state_n, 8);
    p = put(p, g->ctx.state, m->state_size);
    p = put(p, &work_n, 8);
    if (work_n > 0)
        m->save_work_state(&g->ctx, p);
    uint64_t sum = fnv1a(body, (size_t)payload);
    memcpy(s->data + OFF_CHECKSUM, &sum, 8);
    *FMUstate = (fmi2FMUstate)s;
    return fmi2OK;
}

/* NULL if the blob of n bytes is a state of this model in this format, else the reason. */
static const char *refuse_blob(const sarins_glue *g, const unsigned char *b, size_t n)
{
    if (n < HEADER_BYTES)
        return "shorter than the header (truncated?)";
    if (memcmp(b, STATE_MAGIC, 8) != 0)
        return "not an FMU state of this FMU (bad magic)";
    uint32_t format, version, bom, smax;
    memcpy(&format, b + 8, 4);
    memcpy(&version, b + 12, 4);
    memcpy(&bom, b + 16, 4);
    memcpy(&smax, b + 20, 4);
    if (bom != BYTE_ORDER_MARK)
        return "written on a machine of another byte order";
    if (format != STATE_FORMAT || smax != SARINS_STRING_MAX)
        return "written in another state format";
    char guid[GUID_BYTES + 1] = {0};
    memcpy(guid, b + 24, GUID_BYTES);
    if (strcmp(guid, g->table->guid) != 0)
        return "written by another FMU (GUID differs)";
    if (version != g->model->state_version)
        return "written by another version of this model (state version differs)";
    uint64_t payload, sum;
    memcpy(&payload, b + OFF_PAYLOAD_SIZE, 8);
    memcpy(&sum, b + OFF_CHECKSUM, 8);
    if (payload != (uint64_t)(n - HEADER_BYTES))
        return "its size does not match its header (truncated?)";
    if (fnv1a(b + HEADER_BYTES, (size_t)payload) != sum)
        return "its checksum does not match (corrupted)";
    uint64_t fixed = FIXED_PAYLOAD + g->values_size + 8 + g->model->state_size + 8;
    if (payload < fixed)
        return "its payload is too short for this model";
    const unsigned char *p = b + HEADER_BYTES;
    int32_t state;
    uint64_t counts[4], state_n, work_n;
    memcpy(&state, p, 4);
    memcpy(counts, p + 24, sizeof counts);
    memcpy(&state_n, p + FIXED_PAYLOAD + g->values_size, 8);
    memcpy(&work_n, p + FIXED_PAYLOAD + g->values_size + 8 + g->model->state_size, 8);
    if (counts[0] != g->table->n_real || counts[1] != g->table->n_integer || counts[2] != g->table->n_boolean
        || counts[3] != g->table->n_string || state_n != g->model->state_size)
        return "its variables or model state do not fit this model";
    if (payload != fixed + work_n)
        return "its work-state size does not match its payload";
    if (!(state == S_INSTANTIATED || state == S_INIT || post_init(state)))
        return "it holds an unknown FMI state";
    if (work_n > 0 && (!post_init(state) || g->model->load_work_state == NULL))
        return "it holds a work state this model does not take";
    return NULL;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2SetFMUstate", FMU_STATE_STATES);
    const fmu_state *s = (const fmu_state *)FMUstate;
    if (s == NULL)
        return fail(g, "fmi2SetFMUstate: FMUstate is NULL");
    const char *why = refuse_blob(g, s->data, s->size);
    if (why != NULL)
        return fail(g, "fmi2SetFMUstate: the state is refused: %s", why);
    const sarins_model *m = g->model;
    const unsigned char *p = s->data + HEADER_BYTES;
    int32_t state, have_time;
    double t_next, start_time;
    uint64_t work_n;
    p = get(p, &state, 4);
    p = get(p, &have_time, 4);
    p = get(p, &t_next, 8);
    p = get(p, &start_time, 8);
    p += 4 * 8;
    const unsigned char *values = p;
    const unsigned char *model_state = values + g->values_size + 8;
    memcpy(&work_n, model_state + m->state_size, 8);
    const unsigned char *work = model_state + m->state_size + 8;
    if (post_init(state)) {
        /* c->work must come from the restored parameters: rebuild it unless it already does */
        int same = g->have_built && g->built_start == start_time;
        for (size_t k = 0; same && k < g->table->n_vars; k++) {
            const sarins_var *v = &g->table->vars[k];
            if (v->causality != SARINS_PARAMETER)
                continue;
            size_t off, n;
            switch (v->type) {
            case SARINS_REAL: off = v->slot * sizeof(double); n = sizeof(double); break;
            case SARINS_INTEGER: off = off_int(g->table) + v->slot * sizeof(int); n = sizeof(int); break;
            case SARINS_BOOLEAN: off = off_bool(g->table) + v->slot * sizeof(int); n = sizeof(int); break;
            default: off = off_string(g->table) + v->slot * (size_t)SARINS_STRING_MAX; n = SARINS_STRING_MAX; break;
            }
            same = memcmp(g->built + off, values + off, n) == 0
                   && g->built[off_set(g->table) + k] == values[off_set(g->table) + k]; /* its set flag */
        }
        if (!same) {
            memcpy(g->values, values, g->values_size);
            g->ctx.start_time = start_time;
            unsigned long before = g->problems;
            if (model_status(g, run_initialize(g, 0), before, "fmi2SetFMUstate") > fmi2Warning)
                return fail(g, "fmi2SetFMUstate: the model could not be rebuilt from the state's parameters");
        }
        uint64_t need = (m->work_state_size != NULL && g->ctx.work != NULL) ? m->work_state_size(&g->ctx) : 0;
        if (need != work_n)
            return fail(g, "fmi2SetFMUstate: the state's work state has %llu bytes, the model has %llu",
                        (unsigned long long)work_n, (unsigned long long)need);
    } else {
        release_work(g); /* before initialisation the model holds nothing */
    }
    memcpy(g->values, values, g->values_size);
    memcpy(g->ctx.state, model_state, m->state_size);
    g->ctx.start_time = start_time;
    g->have_time = have_time ? 1 : 0;
    g->t_next = t_next;
    if (work_n > 0) {
        unsigned long before = g->problems;
        if (model_status(g, m->load_work_state(&g->ctx, work, (size_t)work_n), before, "fmi2SetFMUstate")
            > fmi2Warning)
            return fmi2Error;
    }
    g->state = state;
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2FreeFMUstate", ANY_STATE);
    if (FMUstate == NULL)
        return fail(g, "fmi2FreeFMUstate: FMUstate is NULL");
    free(*FMUstate);
    *FMUstate = NULL;
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2SerializedFMUstateSize", ANY_STATE);
    if (FMUstate == NULL || size == NULL)
        return fail(g, "fmi2SerializedFMUstateSize: FMUstate or size is NULL");
    *size = ((const fmu_state *)FMUstate)->size;
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[], size_t size)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2SerializeFMUstate", ANY_STATE);
    const fmu_state *s = (const fmu_state *)FMUstate;
    if (s == NULL || serializedState == NULL)
        return fail(g, "fmi2SerializeFMUstate: FMUstate or serializedState is NULL");
    if (size < s->size)
        return fail(g, "fmi2SerializeFMUstate: %llu bytes given, the state needs %llu (fmi2SerializedFMUstateSize)",
                    (unsigned long long)size, (unsigned long long)s->size);
    memcpy(serializedState, s->data, s->size);
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2DeSerializeFMUstate", ANY_STATE);
    if (serializedState == NULL || FMUstate == NULL)
        return fail(g, "fmi2DeSerializeFMUstate: serializedState or FMUstate is NULL");
    const char *why = refuse_blob(g, (const unsigned char *)serializedState, size);
    if (why != NULL)
        return fail(g, "fmi2DeSerializeFMUstate: the serialized state is refused: %s", why);
    fmu_state *s = malloc(sizeof(fmu_state) + size);
    if (s == NULL)
        return fail(g, "fmi2DeSerializeFMUstate: out of memory (%llu bytes)", (unsigned long long)size);
    s->size = size;
    memcpy(s->data, serializedState, size);
    *FMUstate = (fmi2FMUstate)s;
    return fmi2OK;
}

/* ------------------------------------------- capabilities this FMU lacks */

static fmi2Status unsupported(fmi2Component c, const char *fn, const char *why)
{
    sarins_glue *g = (sarins_glue *)c;
    if (g == NULL)
        return fmi2Error;
    return fail(g, "%s: not supported (%s)", fn, why);
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown[], size_t nUnknown,
                                        const fmi2ValueReference vKnown[], size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[])
{
    (void)vUnknown; (void)nUnknown; (void)vKnown; (void)nKnown; (void)dvKnown; (void)dvUnknown;
    return unsupported(c, "fmi2GetDirectionalDerivative", "providesDirectionalDerivative is false");
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    (void)vr; (void)nvr; (void)order; (void)value;
    return unsupported(c, "fmi2SetRealInputDerivatives", "canInterpolateInputs is false");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[])
{
    (void)vr; (void)nvr; (void)order; (void)value;
    return unsupported(c, "fmi2GetRealOutputDerivatives", "maxOutputDerivativeOrder is 0");
}
