/* The FMI-version-independent part of the native glue: see glue_core.h.
 *
 * FMU state blob: header (magic, format version, the model's state version, byte order, string size, GUID,
 * payload size, FNV-1a checksum of the payload) and payload (FMI state, time, every value, the model's
 * plain-bytes state, its work state).  A wrong, truncated or foreign blob is refused with a logged reason.
 * Memory: sg_init allocates the instance; the model allocates in initialize(); after that nothing allocates
 * except the FMU-state calls (sg_get_state and sg_deserialize allocate the blob, sg_set_state may rebuild
 * the model's work from restored parameters).  No globals.
 */
#include "smath.h"

#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "glue_core.h"
#include "sarins_uri.h"

static const char *const TYPE_NAMES[] = {"Real", "Integer", "Boolean", "String"};
static const char *const CAUSALITY_NAMES[] = {"parameter", "calculatedParameter", "input", "output", "local",
                                              "independent", "structuralParameter"};
static const char *const VARIABILITY_NAMES[] = {"constant", "fixed", "tunable", "discrete", "continuous"};

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
    case SARINS_WARNING: return "logStatusWarning";
    case SARINS_DISCARD: return "logStatusDiscard";
    case SARINS_ERROR: return "logStatusError";
    case SARINS_ERROR + 1: return "logStatusFatal";
    default: return "logAll";
    }
}

static void vlog(sarins_glue *g, int status, const char *fmt, va_list ap)
{
    if (status >= SARINS_DISCARD)
        g->problems++;
    const char *category = status_category(status);
    if (g->emit == NULL || (status < SARINS_DISCARD && (g->cat_on == NULL || !category_on(g, category))))
        return;
    char text[2048];
    vsnprintf(text, sizeof text, fmt, ap);
    g->emit(g, status, category, text);
}

int sarins_arrays_visible(const sarins_ctx *c)
{
    return c != NULL && c->glue != NULL && c->glue->arrays_visible;
}

int sarins_check_sub_switch(const sarins_ctx *c, const char *name, int value, const char *zero)
{
    if (value != 0 && value != 1) {
        sarins_log(c, SARINS_ERROR, "parameter %s = %d must be 0 (%s) or 1 (the *_sub arrays)", name, value, zero);
        return SARINS_ERROR;
    }
    if (value == 1 && !sarins_arrays_visible(c)) {
        sarins_log(c, SARINS_ERROR, "parameter %s = 1 needs the *_sub array inputs, which only the FMI 3.0 variant "
                   "of this FMU has; use 0 here", name);
        return SARINS_ERROR;
    }
    return SARINS_OK;
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

int sarins_state_real(const sarins_ctx *c, const char *field, double x, double lo, double hi)
{
    if (isfinite(x) && x >= lo && x <= hi)
        return 1;
    sarins_log(c, SARINS_ERROR, "the state's %s = %g is not finite and in %g .. %g", field, x, lo, hi);
    return 0;
}

int sarins_state_int(const sarins_ctx *c, const char *field, long long x, long long lo, long long hi)
{
    if (x >= lo && x <= hi)
        return 1;
    sarins_log(c, SARINS_ERROR, "the state's %s = %lld is not in %lld .. %lld", field, x, lo, hi);
    return 0;
}

int sarins_state_finite(const sarins_ctx *c, const char *field, const double *x, size_t n)
{
    for (size_t k = 0; k < n; k++)
        if (!isfinite(x[k])) {
            sarins_log(c, SARINS_ERROR, "the state's %s[%llu] = %g is not finite", field, (unsigned long long)k, x[k]);
            return 0;
        }
    return 1;
}

void sg_log(sarins_glue *g, int status, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vlog(g, status, fmt, ap);
    va_end(ap);
}

int sg_fail(sarins_glue *g, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vlog(g, SARINS_ERROR, fmt, ap);
    va_end(ap);
    g->state = S_ERROR;
    return SARINS_ERROR;
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
    case S_CONFIG: return "configurationMode";
    case S_RECONFIG: return "reconfigurationMode";
    default: return "unknown";
    }
}

int sg_bad_state(sarins_glue *g, const char *fn)
{
    if (g->state == S_ERROR) {
        sg_log(g, SARINS_ERROR, "%s: not allowed after an earlier error (state 'error'); call %sReset, "
               "%sFreeInstance, or set an FMU state saved before the error", fn, g->prefix, g->prefix);
        return SARINS_ERROR;
    }
    return sg_fail(g, "%s: not allowed in state '%s' (%s)", fn, state_name(g->state), g->standard);
}

int sg_set_debug_logging(sarins_glue *g, int on, size_t n, const char *const categories[], const char *fn)
{
    if (g == NULL)
        return SARINS_ERROR;
    if (n > 0 && categories == NULL)
        return sg_fail(g, "%s: categories is NULL", fn);
    if (n == 0) {
        for (size_t i = 0; i < g->table->n_categories; i++)
            g->cat_on[i] = on ? 1 : 0;
        return SARINS_OK;
    }
    int st = SARINS_OK;
    for (size_t k = 0; k < n; k++) {
        int i = categories[k] ? category_index(g, categories[k]) : -1;
        if (i < 0) {
            sg_log(g, SARINS_WARNING, "%s: unknown log category %s", fn, categories[k] ? categories[k] : "(null)");
            st = SARINS_WARNING;
        } else {
            g->cat_on[i] = on ? 1 : 0;
        }
    }
    return st;
}

/* A model callback's status as the call's: a failure the model did not explain gets a generic reason. */
int sg_model_status(sarins_glue *g, int status, unsigned long problems_before, const char *fn)
{
    if (status == SARINS_OK || status == SARINS_WARNING)
        return status;
    if (status == SARINS_DISCARD) {
        if (g->problems == problems_before)
            sg_log(g, SARINS_DISCARD, "%s: the model refused the call", fn);
        return SARINS_DISCARD;
    }
    if (g->problems == problems_before)
        return sg_fail(g, "%s: the model failed (status %d)", fn, status);
    g->state = S_ERROR;
    return SARINS_ERROR;
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
        if (v->dim >= 0)
            continue; /* an array: its slot is in c->a, zeroed when it is sized */
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

/* Every Real output finite, else SARINS_ERROR naming it. */
int sg_check_outputs(sarins_glue *g, const char *fn)
{
    for (size_t k = 0; k < g->n_outputs; k++) {
        const sarins_var *v = g->outputs[k];
        if (v->dim < 0 && !isfinite(g->ctx.r[v->slot]))
            return sg_fail(g, "%s: output %s = %g is not finite", fn, v->name, g->ctx.r[v->slot]);
        for (size_t e = 0; v->dim >= 0 && e < sg_length(g, v); e++)
            if (!isfinite(g->ctx.a[v->slot][e]))
                return sg_fail(g, "%s: output %s[%llu] = %g is not finite", fn, v->name, (unsigned long long)e + 1,
                               g->ctx.a[v->slot][e]);
    }
    return SARINS_OK;
}

size_t sg_length(const sarins_glue *g, const sarins_var *v)
{
    return v->dim < 0 ? 1 : g->array_len[v->slot];
}

/* the structural parameter (an Integer) in Integer slot dim, or NULL */
static const sarins_var *dimension_var(const sarins_table *t, int dim)
{
    for (size_t k = 0; k < t->n_vars; k++)
        if (t->vars[k].type == SARINS_INTEGER && (int)t->vars[k].slot == dim)
            return &t->vars[k];
    return NULL;
}

int sg_array_usable(sarins_glue *g, const char *fn, const sarins_var *v)
{
    if (v->dim < 0 || (g->ctx.i[v->dim] >= 0 && (size_t)g->ctx.i[v->dim] == g->array_len[v->slot]))
        return 1;
    const sarins_var *n = dimension_var(g->table, v->dim);
    sg_fail(g, "%s: %s has %llu elements; the structural parameter %s = %d takes effect only when %s leaves "
            "Configuration Mode with it accepted (1 .. %d)", fn, v->name, (unsigned long long)g->array_len[v->slot],
            n ? n->name : "?", g->ctx.i[v->dim], g->prefix, g->table->max_dim);
    return 0;
}

/* NULL if every structural parameter sizing an array is in 1 .. max_dim, else the first bad one */
static const sarins_var *bad_dimension(const sarins_table *t, const int *ints)
{
    for (size_t k = 0; k < t->n_vars; k++) {
        const sarins_var *v = &t->vars[k];
        if (v->dim >= 0 && (ints[v->dim] < 1 || ints[v->dim] > t->max_dim))
            return v;
    }
    return NULL;
}

int sg_size_arrays(sarins_glue *g, const char *fn)
{
    const sarins_table *t = g->table;
    if (t->n_array == 0)
        return SARINS_OK;
    const sarins_var *bad = bad_dimension(t, g->ctx.i);
    if (bad != NULL) {
        const sarins_var *n = dimension_var(t, bad->dim);
        return sg_fail(g, "%s: structural parameter %s = %d (the length of %s) must be in 1 .. %d", fn,
                       n ? n->name : "?", g->ctx.i[bad->dim], bad->name, t->max_dim);
    }
    size_t total = 0;
    for (size_t k = 0; k < t->n_vars; k++)
        if (t->vars[k].dim >= 0)
            total += (size_t)g->ctx.i[t->vars[k].dim];
    if (total != g->array_doubles || g->array_block == NULL) {
        double *block = calloc(total, sizeof(double));
        if (block == NULL)
            return sg_fail(g, "%s: out of memory (%llu array elements)", fn, (unsigned long long)total);
        free(g->array_block);
        g->array_block = block;
        g->array_doubles = total;
    } /* same lengths: the values stay (inputs set before initialisation) */
    size_t at = 0;
    for (size_t k = 0; k < t->n_vars; k++) {
        const sarins_var *v = &t->vars[k];
        if (v->dim >= 0) {
            g->ctx.a[v->slot] = g->array_block + at;
            g->array_len[v->slot] = (size_t)g->ctx.i[v->dim];
            at += g->array_len[v->slot];
        }
    }
    return SARINS_OK;
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
    if (g->table->n_array > 0) {
        int saved = g->state;
        if (quiet && bad_dimension(g->table, g->ctx.i) != NULL)
            return SARINS_ERROR; /* reported when initialisation mode ends */
        if (sg_size_arrays(g, "initialize") != SARINS_OK) {
            g->state = saved; /* the caller decides; the reason is logged */
            return SARINS_ERROR;
        }
    }
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

sarins_glue *sg_alloc(size_t size)
{
    sarins_glue *g = calloc(1, size < sizeof *g ? sizeof *g : size);
    if (g != NULL) {
        g->model = &sarins_model_desc;
        g->table = g->model->table;
        g->ctx.glue = g;
        g->time_vr = SG_NO_TIME_VR;
        g->prefix = "fmi";
        g->standard = "FMI";
    }
    return g;
}

void sg_free(sarins_glue *g)
{
    if (g == NULL)
        return;
    if (g->ctx.work != NULL)
        g->model->release(&g->ctx);
    sg_free_states(g); /* the states the host did not free die with the instance */
    free(g->ctx.state);
    free(g->ctx.a);
    free(g->array_len);
    free(g->array_block);
    free(g->values);
    free(g->built);
    free((void *)g->by_vr);
    free((void *)g->outputs);
    free(g->cat_on);
    free(g->name);
    free(g->resources);
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

#define SG_PATH_MAX 4096 /* bytes of a resources path, NUL included */

int sg_set_resources(sarins_glue *g, const char *location, int is_uri)
{
    g->ctx.resources = NULL;
    if (location == NULL || location[0] == '\0') {
        g->ctx.resources_problem = "the host gave no resource location";
        return 1;
    }
    char *path = malloc(SG_PATH_MAX);
    if (path == NULL) {
        sg_log(g, SARINS_ERROR, "out of memory");
        return 0;
    }
    if (is_uri) {
        int code = sarins_uri_to_path(location, path, SG_PATH_MAX);
        if (code != SARINS_URI_OK) {
            free(path);
            g->ctx.resources_problem = sarins_uri_error(code);
            return 1;
        }
    } else {
        size_t n = strlen(location);
        if (n >= SG_PATH_MAX) {
            free(path);
            g->ctx.resources_problem = "the resource path is too long for this FMU's buffer";
            return 1;
        }
        memcpy(path, location, n + 1);
        while (n > 1 && (path[n - 1] == '/' || path[n - 1] == '\\'))
            path[--n] = '\0'; /* no trailing separator */
    }
    g->resources = path;
    g->ctx.resources = path;
    g->ctx.resources_problem = NULL;
    return 1;
}

int sg_init(sarins_glue *g, const char *instance_name, const char *token, int logging_on, const char *fn)
{
    const sarins_table *t = g->table;
    g->name = copy_string(instance_name ? instance_name : "");
    g->cat_on = calloc(t->n_categories ? t->n_categories : 1, sizeof(int));
    unsigned max_vr = 0;
    for (size_t k = 0; k < t->n_vars; k++)
        if (t->vars[k].vr > max_vr)
            max_vr = t->vars[k].vr;
    g->n_vr = t->n_vars ? (size_t)max_vr + 1 : 0;
    g->by_vr = calloc(g->n_vr ? g->n_vr : 1, sizeof(const sarins_var *));
    g->outputs = calloc(t->n_vars ? t->n_vars : 1, sizeof(const sarins_var *));
    g->values_size = values_size(t);
    g->values = calloc(g->values_size ? g->values_size : 1, 1);
    g->built = calloc(g->values_size ? g->values_size : 1, 1);
    g->ctx.state = calloc(g->model->state_size ? g->model->state_size : 1, 1);
    g->ctx.a = calloc(t->n_array ? t->n_array : 1, sizeof(double *));
    g->array_len = calloc(t->n_array ? t->n_array : 1, sizeof(size_t));
    if (!g->name || !g->cat_on || !g->by_vr || !g->outputs || !g->values || !g->built || !g->ctx.state || !g->ctx.a
        || !g->array_len) {
        if (g->emit)
            g->emit(g, SARINS_ERROR, "logStatusError", "out of memory");
        return 0;
    }
    for (size_t i = 0; i < t->n_categories; i++)
        g->cat_on[i] = logging_on ? 1 : 0;
    if (!instance_name || !instance_name[0]) {
        sg_log(g, SARINS_ERROR, "%s: the instance name must not be empty", fn);
        return 0;
    }
    if (token == NULL || strcmp(token, t->guid) != 0) {
        sg_log(g, SARINS_ERROR, "%s: GUID '%.100s' does not match this FMU's '%s' (modelDescription.xml of another "
               "FMU?)", fn, token ? token : "(null)", t->guid);
        return 0;
    }
    for (size_t k = 0; k < t->n_vars; k++) {
        g->by_vr[t->vars[k].vr] = &t->vars[k];
        if (t->vars[k].type == SARINS_REAL && t->vars[k].causality == SARINS_OUTPUT)
            g->outputs[g->n_outputs++] = &t->vars[k];
    }
    point_ctx(g);
    set_start_values(g);
    g->state = S_INSTANTIATED;
    if (sg_size_arrays(g, fn) != SARINS_OK)
        return 0; /* the declared start values are out of range: a build fault, logged */
    return 1;
}

/* ------------------------------------------------------------- lifecycle */

void sg_enter_init(sarins_glue *g)
{
    /* outputs during initialisation; a bad parameter is reported at the exit of initialisation mode */
    (void)run_initialize(g, 1);
    g->state = S_INIT;
}

int sg_exit_init(sarins_glue *g, const char *fn)
{
    unsigned long before = g->problems;
    int st = sg_model_status(g, run_initialize(g, 0), before, fn);
    if (st > SARINS_WARNING) {
        g->state = S_ERROR;
        return SARINS_ERROR;
    }
    if (sg_check_outputs(g, fn) != SARINS_OK)
        return SARINS_ERROR;
    g->state = S_STEP_COMPLETE;
    g->have_time = 0;
    return st;
}

void sg_terminate(sarins_glue *g)
{
    if (g->model->terminate != NULL)
        g->model->terminate(&g->ctx);
    g->state = S_TERMINATED;
}

void sg_reset(sarins_glue *g)
{
    release_work(g);
    memset(g->ctx.state, 0, g->model->state_size ? g->model->state_size : 1);
    set_start_values(g);
    g->ctx.start_time = 0.0;
    g->have_time = 0;
    g->t_next = 0.0;
    g->state = S_INSTANTIATED; /* debug-logging settings survive a reset */
    (void)sg_size_arrays(g, "reset"); /* start values: in range (checked at instantiation) */
    if (g->array_block != NULL)
        memset(g->array_block, 0, g->array_doubles * sizeof(double));
}

double sg_time(const sarins_glue *g) { return g->have_time ? g->t_next : g->ctx.start_time; }

int sg_do_step(sarins_glue *g, double t, double h, const char *fn)
{
    if (!isfinite(t))
        return sg_fail(g, "%s: communication point %g is not finite", fn, t);
    if (!(h > 0.0) || !isfinite(h))
        return sg_fail(g, "%s: communication step size %g must be positive and finite", fn, h);
    if (g->have_time && sm_fabs(t - g->t_next) > 1e-9 * sm_fmax(1.0, sm_fabs(g->t_next)))
        return sg_fail(g, "%s: communication point %.17g does not continue the previous step, which ended at "
                       "%.17g", fn, t, g->t_next);
    double start = g->ctx.start_time;
    if (!g->have_time && sm_fabs(t - start) > 1e-9 * sm_fmax(1.0, sm_fabs(start)))
        return sg_fail(g, "%s: the first communication point %.17g is not the start time %.17g", fn, t, start);
    unsigned long before = g->problems;
    int st = sg_model_status(g, g->model->do_step(&g->ctx, t, h), before, fn);
    if (st == SARINS_DISCARD) {
        g->state = S_STEP_FAILED;
        return st;
    }
    if (st > SARINS_DISCARD)
        return st;
    if (sg_check_outputs(g, fn) != SARINS_OK)
        return SARINS_ERROR;
    g->have_time = 1;
    g->t_next = t + h;
    return st;
}

/* --------------------------------------------------------- get and set */

int sg_settable_default(const sarins_glue *g, const sarins_var *v)
{
    if (v->variability == SARINS_CONSTANT)
        return 0;
    int parameter = v->causality == SARINS_PARAMETER || v->causality == SARINS_STRUCTURAL_PARAMETER;
    if (g->state == S_INSTANTIATED || g->state == S_INIT)
        return parameter || v->causality == SARINS_INPUT;
    return v->causality == SARINS_INPUT || (parameter && v->variability == SARINS_TUNABLE);
}

/* 1 when vr is FMI 3.0's time variable (FMI 2.0 has none: no value reference is time there, not even
 * SG_NO_TIME_VR) */
static int is_time(const sarins_glue *g, unsigned vr)
{
    return g->time_vr != SG_NO_TIME_VR && vr == g->time_vr;
}

/* One value reference: known, of this type, and (settable given) settable in this state. */
static const sarins_var *check_vr(sarins_glue *g, const char *fn, unsigned vr, int type, sg_settable_fn settable)
{
    if (is_time(g, vr)) {
        if (type != SARINS_REAL)
            sg_fail(g, "%s: time (value reference %u) is a Float64", fn, vr);
        else if (settable != NULL)
            sg_fail(g, "%s: time (value reference %u) is the independent variable and cannot be set", fn, vr);
        return NULL;
    }
    const sarins_var *v = (size_t)vr < g->n_vr ? g->by_vr[vr] : NULL;
    if (v != NULL && v->dim >= 0 && !g->arrays_visible)
        v = NULL; /* arrays are FMI 3.0 only */
    if (v == NULL) {
        sg_fail(g, "%s: unknown value reference %u", fn, vr);
        return NULL;
    }
    if (!sg_array_usable(g, fn, v))
        return NULL;
    if (v->type != type) {
        sg_fail(g, "%s: %s (value reference %u) is a%s %s, not a%s %s", fn, v->name, vr,
                v->type == SARINS_INTEGER ? "n" : "", TYPE_NAMES[v->type], type == SARINS_INTEGER ? "n" : "",
                TYPE_NAMES[type]);
        return NULL;
    }
    if (settable != NULL && !settable(g, v)) {
        sg_fail(g, "%s: %s (value reference %u, causality %s, variability %s) cannot be set in state '%s'", fn,
                v->name, vr, CAUSALITY_NAMES[v->causality], VARIABILITY_NAMES[v->variability],
                state_name(g->state));
        return NULL;
    }
    return v;
}

int sg_check_args(sarins_glue *g, const char *fn, const unsigned vr[], size_t n, const void *values, int type,
                  sg_settable_fn settable)
{
    if (n == 0)
        return 1;
    if (vr == NULL || values == NULL) {
        sg_fail(g, "%s: NULL value reference or value array", fn);
        return 0;
    }
    for (size_t k = 0; k < n; k++)
        if (!(type == SARINS_REAL && settable == NULL && is_time(g, vr[k]))
            && check_vr(g, fn, vr[k], type, settable) == NULL)
            return 0;
    return 1;
}

int sg_check_count(sarins_glue *g, const char *fn, const unsigned vr[], size_t n, size_t n_values)
{
    size_t want = 0;
    for (size_t k = 0; k < n && vr != NULL; k++) {
        const sarins_var *v = (size_t)vr[k] < g->n_vr ? g->by_vr[vr[k]] : NULL;
        if (v != NULL && v->dim >= 0 && g->arrays_visible && !sg_array_usable(g, fn, v))
            return 0;
        want += (v != NULL && v->dim >= 0 && g->arrays_visible) ? sg_length(g, v) : 1;
    }
    if (n_values != want) {
        sg_fail(g, "%s: %llu values for value references holding %llu", fn, (unsigned long long)n_values,
                (unsigned long long)want);
        return 0;
    }
    return 1;
}

int sg_get_real(sarins_glue *g, const char *fn, const unsigned vr[], size_t n, double value[])
{
    if (!sg_check_args(g, fn, vr, n, value, SARINS_REAL, NULL))
        return SARINS_ERROR;
    size_t at = 0; /* arrays: the values of one variable follow each other */
    for (size_t k = 0; k < n; k++) {
        if (is_time(g, vr[k])) {
            value[at++] = sg_time(g);
            continue;
        }
        const sarins_var *v = g->by_vr[vr[k]];
        if (v->dim >= 0) {
            size_t n_el = sg_length(g, v);
            memcpy(value + at, g->ctx.a[v->slot], n_el * sizeof(double));
            for (size_t e = 0; e < n_el; e++)
                if (v->causality == SARINS_OUTPUT && !isfinite(value[at + e]))
                    return sg_fail(g, "%s: output %s[%llu] = %g is not finite", fn, v->name,
                                   (unsigned long long)e + 1, value[at + e]);
            at += n_el;
            continue;
        }
        value[at] = g->ctx.r[v->slot];
        if (v->causality == SARINS_OUTPUT && !isfinite(value[at]))
            return sg_fail(g, "%s: output %s = %g is not finite", fn, v->name, value[at]);
        at++;
    }
    return SARINS_OK;
}

int sg_get_int(sarins_glue *g, const char *fn, const unsigned vr[], size_t n, int value[])
{
    if (!sg_check_args(g, fn, vr, n, value, SARINS_INTEGER, NULL))
        return SARINS_ERROR;
    for (size_t k = 0; k < n; k++)
        value[k] = g->ctx.i[g->by_vr[vr[k]]->slot];
    return SARINS_OK;
}

int sg_get_string(sarins_glue *g, const char *fn, const unsigned vr[], size_t n, const char *value[])
{
    if (!sg_check_args(g, fn, vr, n, value, SARINS_STRING, NULL))
        return SARINS_ERROR;
    for (size_t k = 0; k < n; k++)
        value[k] = g->ctx.s[g->by_vr[vr[k]]->slot]; /* valid until the value changes or the instance is freed */
    return SARINS_OK;
}

int sg_set_real(sarins_glue *g, const char *fn, const unsigned vr[], size_t n, const double value[],
                sg_settable_fn settable)
{
    if (!sg_check_args(g, fn, vr, n, value, SARINS_REAL, settable))
        return SARINS_ERROR;
    size_t at = 0;
    for (size_t k = 0; k < n; k++) {
        const sarins_var *v = g->by_vr[vr[k]];
        if (v->dim >= 0) {
            memcpy(g->ctx.a[v->slot], value + at, sg_length(g, v) * sizeof(double));
            at += sg_length(g, v);
        } else {
            g->ctx.r[v->slot] = value[at++];
        }
        g->ctx.set[g->by_vr[vr[k]] - g->table->vars] = 1; /* its row = its vr (native_fmu.py) */
    }
    return SARINS_OK;
}

int sg_set_int(sarins_glue *g, const char *fn, const unsigned vr[], size_t n, const int value[],
               sg_settable_fn settable)
{
    if (!sg_check_args(g, fn, vr, n, value, SARINS_INTEGER, settable))
        return SARINS_ERROR;
    for (size_t k = 0; k < n; k++) {
        g->ctx.i[g->by_vr[vr[k]]->slot] = value[k];
        g->ctx.set[g->by_vr[vr[k]] - g->table->vars] = 1; /* its row = its vr (native_fmu.py) */
    }
    return SARINS_OK;
}

int sg_set_string(sarins_glue *g, const char *fn, const unsigned vr[], size_t n, const char *const value[],
                  sg_settable_fn settable)
{
    if (!sg_check_args(g, fn, vr, n, value, SARINS_STRING, settable))
        return SARINS_ERROR;
    for (size_t k = 0; k < n; k++) {
        const sarins_var *v = g->by_vr[vr[k]];
        if (value[k] == NULL)
            return sg_fail(g, "%s: NULL value for %s", fn, v->name);
        if (strlen(value[k]) >= SARINS_STRING_MAX)
            return sg_fail(g, "%s: the value of %s is %llu bytes long, at most %d are allowed", fn, v->name,
                           (unsigned long long)strlen(value[k]), SARINS_STRING_MAX - 1);
    }
    for (size_t k = 0; k < n; k++) {
        snprintf(g->ctx.s[g->by_vr[vr[k]]->slot], SARINS_STRING_MAX, "%s", value[k]);
        g->ctx.set[g->by_vr[vr[k]] - g->table->vars] = 1; /* its row = its vr (native_fmu.py) */
    }
    return SARINS_OK;
}

/* ------------------------------------------------------------ FMU state */

#define STATE_MAGIC "SARINSst"
#define STATE_FORMAT 2u /* 2: the arrays after the work state */
#define BYTE_ORDER_MARK 0x01020304u
#define GUID_BYTES 64
/* header: magic 8, format 4, model state version 4, byte-order mark 4, string size 4, GUID 64,
 * payload size 8, checksum 8 */
#define HEADER_BYTES (8 + 4 + 4 + 4 + 4 + GUID_BYTES + 8 + 8)
#define OFF_PAYLOAD_SIZE (8 + 4 + 4 + 4 + 4 + GUID_BYTES)
#define OFF_CHECKSUM (OFF_PAYLOAD_SIZE + 8)
/* payload: FMI state 4, have_time 4, t_next 8, start_time 8, n_real/n_integer/n_boolean/n_string 4 x 8,
 * value block, model state size 8, model state, work-state size 8, work state, array elements 8, arrays */
#define FIXED_PAYLOAD (4 + 4 + 8 + 8 + 4 * 8)

/* In memory a state is its size and its bytes.  The instance keeps the address of every state it issued
 * (sg_get_state, sg_deserialize) and has not freed: a pointer is recognised by comparing addresses only, so
 * a freed, foreign (another instance's) or made-up pointer is refused without reading through it. */
typedef struct fmu_state {
    size_t size;          /* bytes of data */
    unsigned char data[]; /* header + payload: the serialized bytes */
} fmu_state;

/* the index of p among the instance's live states, or -1 */
static long state_index(const sarins_glue *g, const void *p)
{
    for (size_t k = 0; k < g->n_states; k++)
        if (g->states[k] == p)
            return (long)k;
    return -1;
}

static const char *not_a_state(const sarins_glue *g, const void *p)
{
    if (p == NULL)
        return "FMUState is NULL";
    if (state_index(g, p) < 0)
        return "FMUState is not a live FMU state of this instance (freed, another instance's, or not one)";
    return NULL;
}

/* remember s as issued; 0 (nothing changed) when out of memory */
static int remember_state(sarins_glue *g, fmu_state *s)
{
    if (g->n_states == g->cap_states) {
        size_t cap = g->cap_states ? 2 * g->cap_states : 8;
        void **more = realloc(g->states, cap * sizeof *more);
        if (more == NULL)
            return 0;
        g->states = more;
        g->cap_states = cap;
    }
    g->states[g->n_states++] = s;
    return 1;
}

static void forget_state(sarins_glue *g, const void *s)
{
    long k = state_index(g, s);
    if (k >= 0)
        g->states[k] = g->states[--g->n_states];
}

void sg_free_states(sarins_glue *g)
{
    for (size_t k = 0; k < g->n_states; k++)
        free(g->states[k]);
    free(g->states);
    g->states = NULL;
    g->n_states = g->cap_states = 0;
}

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

int sg_get_state(sarins_glue *g, void **FMUstate, const char *fn)
{
    if (g->model->no_fmu_state)
        return sg_fail(g, "%s: not supported (canGetAndSetFMUstate is false)", fn);
    if (FMUstate == NULL)
        return sg_fail(g, "%s: FMUstate is NULL", fn);
    const sarins_model *m = g->model;
    uint64_t work_n = 0;
    if (post_init(g->state) && m->work_state_size != NULL && g->ctx.work != NULL)
        work_n = (uint64_t)m->work_state_size(&g->ctx);
    uint64_t array_n = g->array_doubles;
    uint64_t payload = FIXED_PAYLOAD + g->values_size + 8 + m->state_size + 8 + work_n + 8 + 8 * array_n;
    size_t total = HEADER_BYTES + (size_t)payload;
    /* an existing state of this model is overwritten in place when it has the size (FMI 2.0 allows reuse) */
    fmu_state *s = (fmu_state *)*FMUstate;
    if (s != NULL && not_a_state(g, s) != NULL)
        return sg_fail(g, "%s: *FMUState is not NULL and %s", fn, not_a_state(g, s));
    if (s == NULL || s->size != total) {
        fmu_state *fresh = malloc(sizeof(fmu_state) + total);
        if (fresh == NULL || !remember_state(g, fresh)) {
            free(fresh);
            return sg_fail(g, "%s: out of memory (%llu bytes)", fn, (unsigned long long)total);
        }
        if (s != NULL) {
            forget_state(g, s);
            free(s);
        }
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
    p += work_n;
    p = put(p, &array_n, 8);
    p = put(p, g->array_block, 8 * (size_t)array_n);
    uint64_t sum = fnv1a(body, (size_t)payload);
    memcpy(s->data + OFF_CHECKSUM, &sum, 8);
    *FMUstate = s;
    return SARINS_OK;
}

/* NULL if the blob of n bytes is a state of this model in this format, else the reason. */
/* NULL if the glue's fields and the model's state in a structurally valid payload keep their invariants, else
 * the reason (the model's own reason is logged by its check_state).  Allocates two scratch copies. */
static const char *refuse_fields(sarins_glue *g, const unsigned char *p)
{
    int32_t state, have_time;
    double t_next, start_time;
    memcpy(&state, p, 4);
    memcpy(&have_time, p + 4, 4);
    memcpy(&t_next, p + 8, 8);
    memcpy(&start_time, p + 16, 8);
    if (have_time != 0 && have_time != 1)
        return "its have_time flag is neither 0 nor 1";
    if (!isfinite(t_next) || !isfinite(start_time))
        return "its communication point or start time is not finite";
    if (have_time && !(t_next > start_time))
        return "its next communication point is not after its start time";
    const sarins_table *t = g->table;
    const sarins_model *m = g->model;
    unsigned char *values = malloc(g->values_size ? g->values_size : 1);
    void *mstate = malloc(m->state_size ? m->state_size : 1);
    const char *why = NULL;
    if (values == NULL || mstate == NULL) {
        why = "out of memory while checking it";
        goto done;
    }
    memcpy(values, p + FIXED_PAYLOAD, g->values_size);
    memcpy(mstate, p + FIXED_PAYLOAD + g->values_size + 8, m->state_size);
    sarins_ctx c = g->ctx; /* the instance's view, pointed at the copies; no work, no arrays */
    c.r = (double *)(void *)values;
    c.i = (int *)(void *)(values + off_int(t));
    c.b = (int *)(void *)(values + off_bool(t));
    c.s = (char(*)[SARINS_STRING_MAX])(void *)(values + off_string(t));
    c.set = values + off_set(t);
    c.state = mstate;
    c.work = NULL;
    c.a = NULL;
    c.start_time = start_time;
    c.quiet = 0;
    for (size_t k = 0; k < t->n_boolean && why == NULL; k++)
        if (c.b[k] != 0 && c.b[k] != 1)
            why = "a Boolean in it is neither 0 nor 1";
    for (size_t k = 0; k < t->n_string && why == NULL; k++)
        if (memchr(c.s[k], '\0', SARINS_STRING_MAX) == NULL)
            why = "a String in it is not terminated";
    for (size_t k = 0; k < t->n_vars && why == NULL; k++)
        if (c.set[k] > 1)
            why = "a set flag in it is neither 0 nor 1";
    for (size_t k = 0; k < g->n_outputs && why == NULL && post_init(state); k++)
        if (g->outputs[k]->dim < 0 && !isfinite(c.r[g->outputs[k]->slot]))
            why = "an output in it is not finite";
    if (why == NULL && m->check_state != NULL && m->check_state(&c, post_init(state)) != SARINS_OK)
        why = "the model's state in it breaks the model's invariants";
done:
    free(values);
    free(mstate);
    return why;
}

static const char *refuse_blob(sarins_glue *g, const unsigned char *b, size_t n)
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
#ifndef FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION /* a fuzzer's mutations reach the fields behind it */
    if (fnv1a(b + HEADER_BYTES, (size_t)payload) != sum)
        return "its checksum does not match (corrupted)";
#else
    (void)sum;
#endif
    uint64_t fixed = FIXED_PAYLOAD + g->values_size + 8 + g->model->state_size + 8 + 8;
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
    if (work_n > payload - fixed) /* payload >= fixed: no wrap-around (fixed + work_n could wrap) */
        return "its work-state size does not match its payload";
    uint64_t array_n, want = 0;
    memcpy(&array_n, p + fixed - 8 + work_n, 8);
    for (size_t k = 0; k < g->table->n_vars; k++) {
        const sarins_var *v = &g->table->vars[k];
        if (v->dim < 0)
            continue;
        int d; /* the blob's value of the structural parameter */
        memcpy(&d, p + FIXED_PAYLOAD + off_int(g->table) + (size_t)v->dim * sizeof(int), sizeof d);
        if (d < 1 || d > g->table->max_dim)
            return "a structural parameter in it is out of range";
        want += (uint64_t)d;
    }
    if (array_n != want || array_n > (payload - fixed - work_n) / 8 || payload != fixed + work_n + 8 * array_n)
        return "its arrays do not match its structural parameters or its payload";
    if (!(state == S_INSTANTIATED || state == S_INIT || post_init(state)))
        return "it holds an unknown FMI state";
    if (work_n > 0 && (!post_init(state) || g->model->load_work_state == NULL))
        return "it holds a work state this model does not take";
    return refuse_fields(g, p);
}

int sg_set_state(sarins_glue *g, const void *FMUstate, const char *fn)
{
    if (g->model->no_fmu_state)
        return sg_fail(g, "%s: not supported (canGetAndSetFMUstate is false)", fn);
    const fmu_state *s = (const fmu_state *)FMUstate;
    if (not_a_state(g, s) != NULL)
        return sg_fail(g, "%s: %s", fn, not_a_state(g, s));
    const char *why = refuse_blob(g, s->data, s->size);
    if (why != NULL)
        return sg_fail(g, "%s: the state is refused: %s", fn, why);
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
        /* after an error the model's work is rebuilt whatever the parameters (recovery starts clean) */
        int same = g->state != S_ERROR && g->have_built && g->built_start == start_time;
        for (size_t k = 0; same && k < g->table->n_vars; k++) {
            const sarins_var *v = &g->table->vars[k];
            if (v->causality != SARINS_PARAMETER && v->causality != SARINS_STRUCTURAL_PARAMETER)
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
            if (sg_model_status(g, run_initialize(g, 0), before, fn) > SARINS_WARNING)
                return sg_fail(g, "%s: the model could not be rebuilt from the state's parameters", fn);
        }
        uint64_t need = (m->work_state_size != NULL && g->ctx.work != NULL) ? m->work_state_size(&g->ctx) : 0;
        if (need != work_n)
            return sg_fail(g, "%s: the state's work state has %llu bytes, the model has %llu", fn,
                           (unsigned long long)work_n, (unsigned long long)need);
    } else {
        release_work(g); /* before initialisation the model holds nothing */
    }
    memcpy(g->values, values, g->values_size);
    if (sg_size_arrays(g, fn) != SARINS_OK) /* checked in refuse_blob: only out of memory */
        return SARINS_ERROR;
    if (g->array_doubles > 0)
        memcpy(g->array_block, work + work_n + 8, 8 * g->array_doubles);
    memcpy(g->ctx.state, model_state, m->state_size);
    g->ctx.start_time = start_time;
    g->have_time = have_time ? 1 : 0;
    g->t_next = t_next;
    if (work_n > 0) {
        unsigned long before = g->problems;
        if (sg_model_status(g, m->load_work_state(&g->ctx, work, (size_t)work_n), before, fn) > SARINS_WARNING)
            return SARINS_ERROR;
    }
    g->state = state;
    return SARINS_OK;
}

int sg_free_state(sarins_glue *g, void **FMUstate, const char *fn)
{
    if (FMUstate == NULL)
        return sg_fail(g, "%s: FMUstate is NULL", fn);
    if (state_index(g, FMUstate) >= 0) /* the state itself, not the address of the variable holding it */
        return sg_fail(g, "%s: the argument is the FMU state itself; pass the address of the variable that holds "
                       "it", fn);
    fmu_state *s = (fmu_state *)*FMUstate;
    if (s == NULL)
        return SARINS_OK;
    if (not_a_state(g, s) != NULL)
        return sg_fail(g, "%s: %s", fn, not_a_state(g, s));
    forget_state(g, s);
    free(s);
    *FMUstate = NULL;
    return SARINS_OK;
}

int sg_state_size(sarins_glue *g, const void *FMUstate, size_t *size, const char *fn)
{
    if (size == NULL || not_a_state(g, FMUstate) != NULL)
        return sg_fail(g, "%s: %s", fn, size == NULL ? "size is NULL" : not_a_state(g, FMUstate));
    *size = ((const fmu_state *)FMUstate)->size;
    return SARINS_OK;
}

int sg_serialize(sarins_glue *g, const void *FMUstate, unsigned char *dst, size_t size, const char *fn)
{
    const fmu_state *s = (const fmu_state *)FMUstate;
    if (dst == NULL || not_a_state(g, s) != NULL)
        return sg_fail(g, "%s: %s", fn, dst == NULL ? "serializedState is NULL" : not_a_state(g, s));
    if (size < s->size)
        return sg_fail(g, "%s: %llu bytes given, the state needs %llu (%sSerializedFMUstateSize)", fn,
                       (unsigned long long)size, (unsigned long long)s->size, g->prefix);
    memcpy(dst, s->data, s->size);
    return SARINS_OK;
}

int sg_deserialize(sarins_glue *g, const unsigned char *src, size_t size, void **FMUstate, const char *fn)
{
    if (g->model->no_fmu_state)
        return sg_fail(g, "%s: not supported (canGetAndSetFMUstate is false)", fn);
    if (src == NULL || FMUstate == NULL)
        return sg_fail(g, "%s: serializedState or FMUstate is NULL", fn);
    const char *why = refuse_blob(g, src, size);
    if (why != NULL)
        return sg_fail(g, "%s: the serialized state is refused: %s", fn, why);
    fmu_state *s = malloc(sizeof(fmu_state) + size);
    if (s == NULL || !remember_state(g, s)) {
        free(s);
        return sg_fail(g, "%s: out of memory (%llu bytes)", fn, (unsigned long long)size);
    }
    s->size = size;
    memcpy(s->data, src, size);
    *FMUstate = s;
    return SARINS_OK;
}
