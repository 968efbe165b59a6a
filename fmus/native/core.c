/* sarins FMI 2.0 core: hosts a pythonfmu slave class through the Python C API.
 *
 * Loaded by the shim (<model>.so) with RTLD_NOW | RTLD_NODELETE once a Python
 * runtime is in the process's global scope; this object is compiled against
 * the Python headers of the build interpreter and not linked to libpython.
 *
 * Contract kept here (FMI 2.0, co-simulation):
 * - the state machine of FMI 2.0 section 4.2.4 (calls out of order -> fmi2Error
 *   with a logged message, the instance then in the error state);
 * - value references and types checked against the slave's variable table;
 *   fmi2Set* checks causality/variability against the current state;
 * - a Python exception -> fmi2Error with the exception logged; never fmi2Fatal;
 * - non-finite Real outputs are never returned with fmi2OK;
 * - messages reach the host's logger: status >= fmi2Discard always, others
 *   when debug logging is on for their category (loggingOn at instantiation
 *   switches every category on; fmi2SetDebugLogging changes them);
 * - Py_Finalize is never called (the interpreter outlives every instance).
 * Reals that the slave keeps in a float64 buffer are read and written here
 * without entering Python.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <pthread.h>
#include <stdint.h>

#include "sarins_fmi.h"
#include "sarins_uri.h"

#define EXPORT __attribute__((visibility("default")))

enum { S_INSTANTIATED = 1, S_INIT = 2, S_STEP_COMPLETE = 4, S_STEP_FAILED = 8, S_TERMINATED = 16,
       S_ERROR = 32 };
enum { T_REAL = 0, T_INTEGER = 1, T_BOOLEAN = 2, T_STRING = 3 };
enum { C_PARAMETER = 0, C_CALCULATED_PARAMETER = 1, C_INPUT = 2, C_OUTPUT = 3, C_LOCAL = 4, C_INDEPENDENT = 5 };
enum { V_CONSTANT = 0, V_FIXED = 1, V_TUNABLE = 2, V_DISCRETE = 3, V_CONTINUOUS = 4 };

static const char *TYPE_NAMES[] = {"Real", "Integer", "Boolean", "String"};
static const char *CAUSALITY_NAMES[] = {"parameter", "calculatedParameter", "input", "output", "local",
                                        "independent"};
static const char *VARIABILITY_NAMES[] = {"constant", "fixed", "tunable", "discrete", "continuous"};

typedef struct {
    char *name;
    fmi2CallbackLogger logger;
    fmi2ComponentEnvironment env;
    int state;
    int ncat;
    char **cat;
    int *cat_on;
    /* Python objects (owned) */
    PyObject *bridge_inst, *describe, *slave, *log_queue, *str_hold;
    PyObject *m_do_step, *m_get_real, *m_set_real, *m_get_integer, *m_set_integer, *m_get_boolean,
        *m_set_boolean, *m_get_string, *m_set_string, *m_setup, *m_enter, *m_exit, *m_terminate;
    /* variable table, indexed by value reference */
    long nvr;
    signed char *vtype, *caus, *varb;
    int *slot;
    char **vname;
    /* float64 buffer of the slave's Reals */
    Py_buffer view;
    int have_view;
    double *buf;
    int nout;
    int *out_vr;
    /* time */
    int have_time;
    double t_next;
    double t_start; /* fmi2SetupExperiment's start time (0 until it is called): the first step starts there */
} Inst;

static pthread_mutex_t setup_lock = PTHREAD_MUTEX_INITIALIZER;

/* ---------------------------------------------------------------- logging */

static int category_index(const Inst *in, const char *name) {
    for (int i = 0; i < in->ncat; i++)
        if (strcmp(in->cat[i], name) == 0) return i;
    return -1;
}

static int category_on(const Inst *in, const char *category) {
    int all = category_index(in, "logAll");
    if (all >= 0 && in->cat_on[all]) return 1;
    int i = category ? category_index(in, category) : -1;
    if (i >= 0) return in->cat_on[i];
    for (int k = 0; k < in->ncat; k++)
        if (in->cat_on[k]) return 1;
    return 0;
}

static void emit(const Inst *in, const char *name, fmi2Status status, const char *category, const char *text) {
    if (in->logger == NULL) return;
    if (status < fmi2Discard && !category_on(in, category)) return;
    in->logger(in->env, name ? name : "", status, category ? category : "logAll", "%s", text);
}

static const char *status_category(fmi2Status status) {
    switch (status) {
    case fmi2Warning: return "logStatusWarning";
    case fmi2Discard: return "logStatusDiscard";
    case fmi2Error: return "logStatusError";
    case fmi2Fatal: return "logStatusFatal";
    default: return "logAll";
    }
}

static void logf_(const Inst *in, fmi2Status status, const char *fmt, ...) {
    char text[2048];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    emit(in, in->name, status, status_category(status), text);
}

static const char *state_name(int s) {
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
static fmi2Status fail(Inst *in, const char *fmt, ...) {
    char text[2048];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    emit(in, in->name, fmi2Error, "logStatusError", text);
    in->state = S_ERROR;
    return fmi2Error;
}

static fmi2Status bad_state(Inst *in, const char *fn) {
    if (in->state == S_ERROR) {
        logf_(in, fmi2Error, "%s: not allowed after an earlier error (state 'error'); call fmi2Reset or "
              "fmi2FreeInstance", fn);
        return fmi2Error;
    }
    return fail(in, "%s: not allowed in state '%s' (FMI 2.0 section 4.2.4)", fn, state_name(in->state));
}

#define REQUIRE(in, fn, allowed)                                                                      \
    do {                                                                                              \
        if ((in) == NULL) return fmi2Error;                                                          \
        if (!((in)->state & (allowed))) return bad_state((in), (fn));                                 \
    } while (0)

/* Hand the slave's queued log messages to the host; returns the highest status among them. */
static fmi2Status drain(Inst *in) {
    fmi2Status worst = fmi2OK;
    if (in->log_queue == NULL || !PyList_Check(in->log_queue)) return worst;
    Py_ssize_t n = PyList_GET_SIZE(in->log_queue);
    if (n == 0) return worst;
    for (Py_ssize_t i = 0; i < n; i++) {
        PyObject *msg = PyList_GET_ITEM(in->log_queue, i);
        PyObject *st = PyObject_GetAttrString(msg, "status");
        PyObject *cat = PyObject_GetAttrString(msg, "category");
        PyObject *text = PyObject_GetAttrString(msg, "msg");
        long status = st ? PyLong_AsLong(st) : fmi2Error;
        if (status < fmi2OK || status > fmi2Fatal) status = fmi2Error;
        const char *c = (cat && PyUnicode_Check(cat)) ? PyUnicode_AsUTF8(cat) : NULL;
        PyObject *s = text ? PyObject_Str(text) : NULL;
        const char *t = s ? PyUnicode_AsUTF8(s) : NULL;
        PyErr_Clear();
        emit(in, in->name, (fmi2Status)status, c ? c : status_category((fmi2Status)status),
             t ? t : "(unprintable message)");
        if (status > worst) worst = (fmi2Status)status;
        Py_XDECREF(st);
        Py_XDECREF(cat);
        Py_XDECREF(text);
        Py_XDECREF(s);
    }
    PyList_SetSlice(in->log_queue, 0, n, NULL);
    PyErr_Clear();
    return worst;
}

/* The pending Python exception -> logged fmi2Error (instance to the error state). */
static fmi2Status py_fail(Inst *in, const char *fn) {
    PyObject *type, *value, *tb;
    PyErr_Fetch(&type, &value, &tb);
    PyErr_NormalizeException(&type, &value, &tb);
    if (value != NULL && tb != NULL) PyException_SetTraceback(value, tb);
    const char *text = NULL;
    PyObject *d = NULL;
    if (in->describe != NULL && value != NULL) d = PyObject_CallOneArg(in->describe, value);
    if (d == NULL) {
        PyErr_Clear();
        d = value ? PyObject_Str(value) : NULL;
    }
    if (d != NULL) text = PyUnicode_AsUTF8(d);
    PyErr_Clear();
    drain(in);
    fmi2Status st = fail(in, "%s: %s", fn, text ? text : "Python error (no message)");
    Py_XDECREF(d);
    Py_XDECREF(type);
    Py_XDECREF(value);
    Py_XDECREF(tb);
    return st;
}

/* Status of a call that returned normally: the highest status the slave logged
 * during it (fmi2Discard counts only for fmi2DoStep, fmi2Fatal as fmi2Error). */
static fmi2Status after_call(Inst *in, int is_step) {
    fmi2Status logged = drain(in);
    if (logged >= fmi2Error) {
        in->state = S_ERROR;
        return fmi2Error;
    }
    if (logged == fmi2Discard && !is_step) logged = fmi2Warning;
    return logged;
}

/* ------------------------------------------------------------- instances */

static void clear_slave(Inst *in) {
    if (in->have_view) {
        PyBuffer_Release(&in->view);
        in->have_view = 0;
    }
    in->buf = NULL;
    Py_CLEAR(in->m_do_step); Py_CLEAR(in->m_get_real); Py_CLEAR(in->m_set_real);
    Py_CLEAR(in->m_get_integer); Py_CLEAR(in->m_set_integer); Py_CLEAR(in->m_get_boolean);
    Py_CLEAR(in->m_set_boolean); Py_CLEAR(in->m_get_string); Py_CLEAR(in->m_set_string);
    Py_CLEAR(in->m_setup); Py_CLEAR(in->m_enter); Py_CLEAR(in->m_exit); Py_CLEAR(in->m_terminate);
    Py_CLEAR(in->slave);
    Py_CLEAR(in->log_queue);
    Py_CLEAR(in->str_hold);
    for (long i = 0; i < in->nvr; i++) free(in->vname ? in->vname[i] : NULL);
    free(in->vtype); free(in->caus); free(in->varb); free(in->slot); free(in->vname); free(in->out_vr);
    in->vtype = in->caus = in->varb = NULL;
    in->slot = NULL; in->vname = NULL; in->out_vr = NULL;
    in->nvr = 0; in->nout = 0;
    for (int i = 0; i < in->ncat; i++) free(in->cat[i]);
    free(in->cat);
    in->cat = NULL;
    in->ncat = 0;
    /* keep cat_on's meaning: rebuilt by load_slave */
}

static PyObject *method(PyObject *obj, const char *name) {
    PyObject *m = PyObject_GetAttrString(obj, name);
    return m;
}

/* Read the bridge instance's slave, table, categories and buffer (GIL held). */
static int load_slave(Inst *in, int logging_on) {
    PyObject *table = NULL, *cats = NULL, *buffer = NULL, *slots = NULL;
    int ok = 0;
    in->slave = PyObject_GetAttrString(in->bridge_inst, "slave");
    in->log_queue = PyObject_GetAttrString(in->bridge_inst, "log_queue");
    table = PyObject_GetAttrString(in->bridge_inst, "table");
    cats = PyObject_GetAttrString(in->bridge_inst, "categories");
    buffer = PyObject_GetAttrString(in->bridge_inst, "buffer");
    slots = PyObject_GetAttrString(in->bridge_inst, "slots");
    if (!in->slave || !in->log_queue || !table || !cats || !buffer || !slots) goto done;
    if (!PyList_Check(table) || !PyList_Check(cats) || !PyList_Check(slots)) {
        PyErr_SetString(PyExc_TypeError, "bridge returned malformed tables");
        goto done;
    }
    Py_ssize_t n = PyList_GET_SIZE(table);
    long maxvr = -1;
    for (Py_ssize_t i = 0; i < n; i++) {
        PyObject *row = PyList_GET_ITEM(table, i);
        if (!PyTuple_Check(row) || PyTuple_GET_SIZE(row) != 5) {
            PyErr_SetString(PyExc_TypeError, "bridge variable table: a row is not a 5-tuple");
            goto done;
        }
        long vr = PyLong_AsLong(PyTuple_GET_ITEM(row, 0));
        if (vr == -1 && PyErr_Occurred()) goto done; /* checked here: the next call must not run with it set */
        if (vr < 0 || vr > INT_MAX - 1) {
            PyErr_Format(PyExc_ValueError, "bridge variable table: value reference %ld out of range", vr);
            goto done;
        }
        if (vr > maxvr) maxvr = vr;
    }
    in->nvr = maxvr + 1;
    size_t m = in->nvr > 0 ? (size_t)in->nvr : 1;
    in->vtype = malloc(m); in->caus = malloc(m); in->varb = malloc(m);
    in->slot = malloc(m * sizeof(int)); in->vname = calloc(m, sizeof(char *));
    in->out_vr = malloc(m * sizeof(int));
    if (!in->vtype || !in->caus || !in->varb || !in->slot || !in->vname || !in->out_vr) {
        PyErr_NoMemory();
        goto done;
    }
    memset(in->vtype, -1, m);
    for (size_t i = 0; i < m; i++) in->slot[i] = -1;
    for (Py_ssize_t i = 0; i < n; i++) {
        PyObject *row = PyList_GET_ITEM(table, i); /* a 5-tuple (first pass) */
        long field[4];
        for (int j = 0; j < 4; j++) {
            field[j] = PyLong_AsLong(PyTuple_GET_ITEM(row, j));
            if (field[j] == -1 && PyErr_Occurred()) goto done;
        }
        long vr = field[0], t = field[1], c = field[2], v = field[3];
        const char *name = PyUnicode_AsUTF8(PyTuple_GET_ITEM(row, 4));
        if (!name) goto done;
        if (t < 0 || t > 3 || c < 0 || c > 5 || v < 0 || v > 4) {
            PyErr_Format(PyExc_ValueError, "bridge variable table: bad row for %s", name);
            goto done;
        }
        if (in->vtype[vr] >= 0) { /* refused: aliases are not supported, and the first name would leak */
            PyErr_Format(PyExc_ValueError, "bridge variable table: value reference %ld given to both %s and %s", vr,
                         in->vname[vr], name);
            goto done;
        }
        char *copy = strdup(name);
        if (!copy) {
            PyErr_NoMemory();
            goto done;
        }
        in->vtype[vr] = (signed char)t; in->caus[vr] = (signed char)c; in->varb[vr] = (signed char)v;
        in->vname[vr] = copy;
    }
    Py_ssize_t ncat = PyList_GET_SIZE(cats);
    if (ncat > 1024) {
        PyErr_SetString(PyExc_ValueError, "bridge: more than 1024 log categories");
        goto done;
    }
    free(in->cat_on);
    in->cat_on = NULL;
    in->cat = calloc(ncat ? (size_t)ncat : 1, sizeof(char *));
    in->cat_on = calloc(ncat ? (size_t)ncat : 1, sizeof(int));
    if (!in->cat || !in->cat_on) {
        PyErr_NoMemory();
        goto done;
    }
    for (Py_ssize_t i = 0; i < ncat; i++) {
        const char *c = PyUnicode_AsUTF8(PyList_GET_ITEM(cats, i));
        if (!c) goto done;
        char *copy = strdup(c);
        if (!copy) {
            PyErr_NoMemory();
            goto done;
        }
        in->cat[i] = copy;
        in->cat_on[i] = logging_on;
        in->ncat = (int)i + 1; /* clear_slave frees what was copied so far */
    }
    if (buffer != Py_None) {
        if (PyObject_GetBuffer(buffer, &in->view, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0)
            goto done;
        in->have_view = 1;
        if (in->view.itemsize != 8 || in->view.format == NULL || strcmp(in->view.format, "d") != 0) {
            PyErr_SetString(PyExc_TypeError, "the slave's Real buffer is not float64");
            goto done;
        }
        in->buf = (double *)in->view.buf;
        Py_ssize_t len = in->view.len / 8;
        for (Py_ssize_t i = 0; i < PyList_GET_SIZE(slots); i++) {
            PyObject *pair = PyList_GET_ITEM(slots, i);
            long vr = PyLong_AsLong(PyTuple_GetItem(pair, 0));
            long s = PyLong_AsLong(PyTuple_GetItem(pair, 1));
            if (PyErr_Occurred()) goto done;
            if (vr < 0 || vr >= in->nvr || in->vtype[vr] != T_REAL || s < 0 || s >= len) {
                PyErr_SetString(PyExc_ValueError, "bad Real buffer slot");
                goto done;
            }
            in->slot[vr] = (int)s;
        }
    }
    in->nout = 0;
    for (long vr = 0; vr < in->nvr; vr++)
        if (in->vtype[vr] == T_REAL && in->caus[vr] == C_OUTPUT && in->slot[vr] >= 0) in->out_vr[in->nout++] = (int)vr;
    in->str_hold = PyList_New(0);
    if (!(in->m_do_step = method(in->slave, "do_step")) || !(in->m_get_real = method(in->slave, "get_real")) ||
        !(in->m_set_real = method(in->slave, "set_real")) ||
        !(in->m_get_integer = method(in->slave, "get_integer")) ||
        !(in->m_set_integer = method(in->slave, "set_integer")) ||
        !(in->m_get_boolean = method(in->slave, "get_boolean")) ||
        !(in->m_set_boolean = method(in->slave, "set_boolean")) ||
        !(in->m_get_string = method(in->slave, "get_string")) ||
        !(in->m_set_string = method(in->slave, "set_string")) ||
        !(in->m_setup = method(in->slave, "setup_experiment")) ||
        !(in->m_enter = method(in->slave, "enter_initialization_mode")) ||
        !(in->m_exit = method(in->slave, "exit_initialization_mode")) ||
        !(in->m_terminate = method(in->slave, "terminate")) || !in->str_hold)
        goto done;
    ok = 1;
done:
    Py_XDECREF(table);
    Py_XDECREF(cats);
    Py_XDECREF(buffer);
    Py_XDECREF(slots);
    return ok;
}

static unsigned long long fnv1a(const char *s, size_t n) {
    unsigned long long h = 1469598103934665603ULL;
    for (size_t i = 0; i < n; i++) {
        h ^= (unsigned char)s[i];
        h *= 1099511628211ULL;
    }
    return h;
}

/* Import resources/_fmi_bridge.py under a name derived from its content (GIL held). */
static PyObject *import_bridge(const char *resources) {
    char path[4096];
    int len = snprintf(path, sizeof path, "%s/_fmi_bridge.py", resources);
    if (len < 0 || (size_t)len >= sizeof path) {
        PyErr_Format(PyExc_OSError, "the path of %s/_fmi_bridge.py is too long (%zu bytes at most)", resources,
                     sizeof path - 1);
        return NULL;
    }
    FILE *f = fopen(path, "rb");
    if (!f) {
        PyErr_Format(PyExc_FileNotFoundError, "cannot open %s", path);
        return NULL;
    }
    long size = fseek(f, 0, SEEK_END) == 0 ? ftell(f) : -1;
    if (size < 0 || size > (1L << 24) || fseek(f, 0, SEEK_SET) != 0) {
        fclose(f);
        PyErr_Format(PyExc_OSError, "cannot read %s: %s", path, size < 0 ? "cannot tell its size" : "over 16 MiB");
        return NULL;
    }
    char *src = malloc((size_t)size + 1);
    if (!src || fread(src, 1, (size_t)size, f) != (size_t)size) {
        fclose(f);
        free(src);
        PyErr_Format(PyExc_OSError, "cannot read %s", path);
        return NULL;
    }
    fclose(f);
    src[size] = '\0';
    char name[64];
    len = snprintf(name, sizeof name, "_sarins_fmi_bridge_%016llx", fnv1a(src, (size_t)size));
    if (len < 0 || (size_t)len >= sizeof name) { /* cannot happen (35 characters); checked all the same */
        free(src);
        PyErr_SetString(PyExc_OSError, "bridge module name truncated");
        return NULL;
    }
    PyObject *modules = PyImport_GetModuleDict();
    PyObject *mod = PyDict_GetItemString(modules, name);
    if (mod != NULL) {
        free(src);
        Py_INCREF(mod);
        return mod;
    }
    PyObject *code = Py_CompileString(src, path, Py_file_input);
    free(src);
    if (!code) return NULL;
    mod = PyImport_ExecCodeModuleEx(name, code, path);
    Py_DECREF(code);
    return mod;
}

static void free_inst(Inst *in) {
    if (!in) return;
    free(in->name);
    free(in->cat_on);
    free(in);
}

static fmi2Component core_instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String guid,
                                      fmi2String resourceLocation, const fmi2CallbackFunctions *functions,
                                      fmi2Boolean visible, fmi2Boolean loggingOn) {
    Inst *in = calloc(1, sizeof(Inst));
    if (!in) return NULL;
    in->name = strdup(instanceName ? instanceName : "");
    if (!in->name) {
        free(in);
        if (functions && functions->logger)
            functions->logger(functions->componentEnvironment, instanceName ? instanceName : "", fmi2Error,
                              "logStatusError", "fmi2Instantiate: out of memory");
        return NULL;
    }
    if (functions) {
        in->logger = functions->logger;
        in->env = functions->componentEnvironment;
    }
    in->ncat = 0;
    if (!instanceName || !instanceName[0]) {
        logf_(in, fmi2Error, "fmi2Instantiate: the instance name must not be empty");
        free_inst(in);
        return NULL;
    }
    if (fmuType != fmi2CoSimulation) {
        logf_(in, fmi2Error, "fmi2Instantiate: this FMU supports co-simulation only (fmuType %d)", (int)fmuType);
        free_inst(in);
        return NULL;
    }
    char resources[4096];
    int uri = sarins_uri_to_path(resourceLocation, resources, sizeof resources);
    if (uri != SARINS_URI_OK) {
        logf_(in, fmi2Error, "fmi2Instantiate: fmuResourceLocation %.1000s: %s",
              resourceLocation ? resourceLocation : "(null)", sarins_uri_error(uri));
        free_inst(in);
        return NULL;
    }
    PyGILState_STATE g = PyGILState_Ensure();
    PyObject *bridge = import_bridge(resources);
    PyObject *create = bridge ? PyObject_GetAttrString(bridge, "create") : NULL;
    in->describe = bridge ? PyObject_GetAttrString(bridge, "describe") : NULL;
    Py_XDECREF(bridge);
    if (create) {
        in->bridge_inst = PyObject_CallFunction(create, "ssOs", resources, instanceName,
                                                visible ? Py_True : Py_False, guid ? guid : "");
        Py_DECREF(create);
    }
    if (!in->bridge_inst || !load_slave(in, loggingOn ? 1 : 0)) {
        py_fail(in, "fmi2Instantiate");
        clear_slave(in);
        Py_CLEAR(in->bridge_inst);
        Py_CLEAR(in->describe);
        PyGILState_Release(g);
        free_inst(in);
        return NULL;
    }
    fmi2Status st = drain(in);
    PyGILState_Release(g);
    (void)st;
    in->state = S_INSTANTIATED;
    return (fmi2Component)in;
}

static void core_free(fmi2Component c) {
    Inst *in = (Inst *)c;
    if (!in) return;
    PyGILState_STATE g = PyGILState_Ensure();
    drain(in);
    clear_slave(in);
    Py_CLEAR(in->bridge_inst);
    Py_CLEAR(in->describe);
    PyGILState_Release(g);
    free_inst(in);
}

static fmi2Status core_set_debug_logging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cats[]) {
    Inst *in = (Inst *)c;
    if (!in) return fmi2Error;
    if (n > 0 && cats == NULL) return fail(in, "fmi2SetDebugLogging: categories is NULL");
    if (n == 0) {
        for (int i = 0; i < in->ncat; i++) in->cat_on[i] = on ? 1 : 0;
        return fmi2OK;
    }
    fmi2Status st = fmi2OK;
    for (size_t k = 0; k < n; k++) {
        int i = cats[k] ? category_index(in, cats[k]) : -1;
        if (i < 0) {
            logf_(in, fmi2Warning, "fmi2SetDebugLogging: unknown log category %s", cats[k] ? cats[k] : "(null)");
            st = fmi2Warning;
        } else {
            in->cat_on[i] = on ? 1 : 0;
        }
    }
    return st;
}

static fmi2Status call_noarg(Inst *in, PyObject *m, const char *fn) {
    PyGILState_STATE g = PyGILState_Ensure();
    PyObject *r = PyObject_CallNoArgs(m);
    fmi2Status st;
    if (!r) st = py_fail(in, fn);
    else {
        Py_DECREF(r);
        st = after_call(in, 0);
    }
    PyGILState_Release(g);
    return st;
}

static fmi2Status core_setup_experiment(fmi2Component c, fmi2Boolean tolDefined, fmi2Real tol, fmi2Real t0,
                                        fmi2Boolean stopDefined, fmi2Real t1) {
    Inst *in = (Inst *)c;
    REQUIRE(in, "fmi2SetupExperiment", S_INSTANTIATED);
    if (!isfinite(t0)) return fail(in, "fmi2SetupExperiment: start time %g is not finite", t0);
    if (stopDefined && !(t1 >= t0)) return fail(in, "fmi2SetupExperiment: stop time %g before start %g", t1, t0);
    (void)tolDefined; (void)tol;
    PyGILState_STATE g = PyGILState_Ensure();
    PyObject *r = PyObject_CallFunction(in->m_setup, "dOO", t0, (PyObject *)Py_None, (PyObject *)Py_None);
    fmi2Status st;
    if (!r) st = py_fail(in, "fmi2SetupExperiment");
    else {
        Py_DECREF(r);
        st = after_call(in, 0);
        if (st <= fmi2Warning) in->t_start = t0;
    }
    PyGILState_Release(g);
    return st;
}

static fmi2Status core_enter_init(fmi2Component c) {
    Inst *in = (Inst *)c;
    REQUIRE(in, "fmi2EnterInitializationMode", S_INSTANTIATED);
    fmi2Status st = call_noarg(in, in->m_enter, "fmi2EnterInitializationMode");
    if (st <= fmi2Warning) in->state = S_INIT;
    return st;
}

/* Buffered Real outputs must be finite (GIL not needed). */
static fmi2Status check_outputs(Inst *in, const char *fn) {
    for (int k = 0; k < in->nout; k++) {
        int vr = in->out_vr[k];
        double v = in->buf[in->slot[vr]];
        if (!isfinite(v))
            return fail(in, "%s: output %s = %g is not finite", fn, in->vname[vr], v);
    }
    return fmi2OK;
}

static fmi2Status core_exit_init(fmi2Component c) {
    Inst *in = (Inst *)c;
    REQUIRE(in, "fmi2ExitInitializationMode", S_INIT);
    fmi2Status st = call_noarg(in, in->m_exit, "fmi2ExitInitializationMode");
    if (st > fmi2Warning) return st;
    if (check_outputs(in, "fmi2ExitInitializationMode") != fmi2OK) return fmi2Error;
    in->state = S_STEP_COMPLETE;
    in->have_time = 0;
    return st;
}

static fmi2Status core_terminate(fmi2Component c) {
    Inst *in = (Inst *)c;
    REQUIRE(in, "fmi2Terminate", S_STEP_COMPLETE | S_STEP_FAILED);
    fmi2Status st = call_noarg(in, in->m_terminate, "fmi2Terminate");
    if (st <= fmi2Warning) in->state = S_TERMINATED;
    return st;
}

static fmi2Status core_reset(fmi2Component c) {
    Inst *in = (Inst *)c;
    REQUIRE(in, "fmi2Reset", S_INSTANTIATED | S_INIT | S_STEP_COMPLETE | S_STEP_FAILED | S_TERMINATED | S_ERROR);
    int logging = 0;
    for (int i = 0; i < in->ncat; i++) logging |= in->cat_on[i];
    int *saved = NULL;
    char **saved_names = NULL;
    int nsaved = in->ncat > 0 ? in->ncat : 0;
    if (nsaved > 0) {
        saved = malloc((size_t)nsaved * sizeof(int));
        saved_names = malloc((size_t)nsaved * sizeof(char *));
        if (!saved || !saved_names) nsaved = 0; /* out of memory: the settings are not kept */
        for (int i = 0; i < nsaved; i++) {
            saved[i] = in->cat_on[i];
            saved_names[i] = strdup(in->cat[i]);
            if (!saved_names[i]) { /* keep those copied so far */
                nsaved = i;
                break;
            }
        }
    }
    PyGILState_STATE g = PyGILState_Ensure();
    drain(in);
    clear_slave(in);
    PyObject *r = PyObject_CallMethod(in->bridge_inst, "reset", NULL);
    fmi2Status st;
    if (!r || !load_slave(in, logging)) {
        Py_XDECREF(r);
        st = py_fail(in, "fmi2Reset");
    } else {
        Py_DECREF(r);
        for (int i = 0; i < nsaved; i++) { /* debug-logging settings survive a reset */
            int k = category_index(in, saved_names[i]);
            if (k >= 0) in->cat_on[k] = saved[i];
        }
        st = after_call(in, 0);
        if (st <= fmi2Warning) {
            in->state = S_INSTANTIATED;
            in->have_time = 0;
            in->t_start = 0.0; /* the slave is new: back to the default start time */
        }
    }
    PyGILState_Release(g);
    for (int i = 0; i < nsaved; i++) free(saved_names[i]);
    free(saved);
    free(saved_names);
    return st;
}

/* --------------------------------------------------------- get and set */

#define GET_STATES (S_INSTANTIATED | S_INIT | S_STEP_COMPLETE | S_STEP_FAILED | S_TERMINATED | S_ERROR)
#define SET_STATES (S_INSTANTIATED | S_INIT | S_STEP_COMPLETE)

/* Check one value reference for type (and, for a set, causality/variability in this state). */
static fmi2Status check_vr(Inst *in, const char *fn, fmi2ValueReference vr, int type, int setting) {
    if ((long)vr >= in->nvr || in->vtype[vr] < 0)
        return fail(in, "%s: unknown value reference %u", fn, (unsigned)vr);
    if (in->vtype[vr] != type)
        return fail(in, "%s: %s (value reference %u) is a%s %s, not a%s %s", fn, in->vname[vr], (unsigned)vr,
                    in->vtype[vr] == T_INTEGER ? "n" : "", TYPE_NAMES[(int)in->vtype[vr]],
                    type == T_INTEGER ? "n" : "", TYPE_NAMES[type]);
    if (!setting) return fmi2OK;
    int c = in->caus[vr], v = in->varb[vr], ok;
    if (v == V_CONSTANT) ok = 0;
    else if (in->state == S_INSTANTIATED || in->state == S_INIT) ok = (c == C_PARAMETER || c == C_INPUT);
    else ok = (c == C_INPUT || (c == C_PARAMETER && v == V_TUNABLE));
    if (!ok)
        return fail(in, "%s: %s (value reference %u, causality %s, variability %s) cannot be set in state '%s'",
                    fn, in->vname[vr], (unsigned)vr, CAUSALITY_NAMES[c], VARIABILITY_NAMES[v],
                    state_name(in->state));
    return fmi2OK;
}

static fmi2Status check_args(Inst *in, const char *fn, const fmi2ValueReference vr[], size_t nvr,
                             const void *values, int type, int setting) {
    if (nvr == 0) return fmi2OK;
    if (vr == NULL || values == NULL) return fail(in, "%s: NULL value reference or value array", fn);
    for (size_t i = 0; i < nvr; i++)
        if (check_vr(in, fn, vr[i], type, setting) != fmi2OK) return fmi2Error;
    return fmi2OK;
}

static PyObject *vr_list(const fmi2ValueReference vr[], size_t nvr, const size_t *idx, size_t n) {
    PyObject *l = PyList_New((Py_ssize_t)n);
    if (!l) return NULL;
    for (size_t k = 0; k < n; k++) PyList_SET_ITEM(l, (Py_ssize_t)k, PyLong_FromUnsignedLong(vr[idx ? idx[k] : k]));
    (void)nvr;
    return l;
}

/* Call getter(list of vrs) -> Python list of len n, or NULL with an exception set. */
static PyObject *py_get(PyObject *getter, const fmi2ValueReference vr[], size_t nvr, const size_t *idx, size_t n) {
    PyObject *l = vr_list(vr, nvr, idx, n);
    if (!l) return NULL;
    PyObject *r = PyObject_CallOneArg(getter, l);
    Py_DECREF(l);
    if (!r) return NULL;
    PyObject *seq = PySequence_Fast(r, "getter must return a sequence");
    Py_DECREF(r);
    if (!seq) return NULL;
    if ((size_t)PySequence_Fast_GET_SIZE(seq) != n) {
        Py_DECREF(seq);
        PyErr_SetString(PyExc_ValueError, "getter returned the wrong number of values");
        return NULL;
    }
    return seq;
}

static fmi2Status core_get_real(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    Inst *in = (Inst *)c;
    REQUIRE(in, "fmi2GetReal", GET_STATES);
    if (check_args(in, "fmi2GetReal", vr, nvr, value, T_REAL, 0) != fmi2OK) return fmi2Error;
    size_t nslow = 0;
    for (size_t i = 0; i < nvr; i++) {
        int s = in->slot[vr[i]];
        if (s >= 0) value[i] = in->buf[s];
        else nslow++;
    }
    fmi2Status st = fmi2OK;
    if (nslow > 0) {
        size_t *idx = malloc(nslow * sizeof(size_t));
        if (!idx) return fail(in, "fmi2GetReal: out of memory");
        size_t k = 0;
        for (size_t i = 0; i < nvr; i++)
            if (in->slot[vr[i]] < 0) idx[k++] = i;
        PyGILState_STATE g = PyGILState_Ensure();
        PyObject *seq = py_get(in->m_get_real, vr, nvr, idx, nslow);
        if (!seq) st = py_fail(in, "fmi2GetReal");
        else {
            for (k = 0; k < nslow; k++) value[idx[k]] = PyFloat_AsDouble(PySequence_Fast_GET_ITEM(seq, k));
            Py_DECREF(seq);
            st = PyErr_Occurred() ? py_fail(in, "fmi2GetReal") : after_call(in, 0);
        }
        PyGILState_Release(g);
        free(idx);
        if (st > fmi2Warning) return st;
    }
    for (size_t i = 0; i < nvr; i++)
        if (in->caus[vr[i]] == C_OUTPUT && !isfinite(value[i]))
            return fail(in, "fmi2GetReal: output %s = %g is not finite", in->vname[vr[i]], value[i]);
    return st;
}

static fmi2Status core_set_real(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    Inst *in = (Inst *)c;
    REQUIRE(in, "fmi2SetReal", SET_STATES);
    if (check_args(in, "fmi2SetReal", vr, nvr, value, T_REAL, 1) != fmi2OK) return fmi2Error;
    size_t nslow = 0;
    for (size_t i = 0; i < nvr; i++) {
        int s = in->slot[vr[i]];
        if (s >= 0) in->buf[s] = value[i];
        else nslow++;
    }
    if (nslow == 0) return fmi2OK;
    PyGILState_STATE g = PyGILState_Ensure();
    PyObject *vrs = PyList_New((Py_ssize_t)nslow), *vals = PyList_New((Py_ssize_t)nslow);
    fmi2Status st;
    if (!vrs || !vals) st = py_fail(in, "fmi2SetReal");
    else {
        Py_ssize_t k = 0;
        for (size_t i = 0; i < nvr; i++)
            if (in->slot[vr[i]] < 0) {
                PyList_SET_ITEM(vrs, k, PyLong_FromUnsignedLong(vr[i]));
                PyList_SET_ITEM(vals, k, PyFloat_FromDouble(value[i]));
                k++;
            }
        PyObject *r = PyObject_CallFunctionObjArgs(in->m_set_real, vrs, vals, NULL);
        if (!r) st = py_fail(in, "fmi2SetReal");
        else {
            Py_DECREF(r);
            st = after_call(in, 0);
        }
    }
    Py_XDECREF(vrs);
    Py_XDECREF(vals);
    PyGILState_Release(g);
    return st;
}

static fmi2Status core_get_integer(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    Inst *in = (Inst *)c;
    REQUIRE(in, "fmi2GetInteger", GET_STATES);
    if (check_args(in, "fmi2GetInteger", vr, nvr, value, T_INTEGER, 0) != fmi2OK) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    PyGILState_STATE g = PyGILState_Ensure();
    fmi2Status st = fmi2OK;
    PyObject *seq = py_get(in->m_get_integer, vr, nvr, NULL, nvr);
    if (!seq) st = py_fail(in, "fmi2GetInteger");
    else {
        for (size_t i = 0; i < nvr && st == fmi2OK; i++) {
            long long v = PyLong_AsLongLong(PySequence_Fast_GET_ITEM(seq, (Py_ssize_t)i));
            if (PyErr_Occurred()) st = py_fail(in, "fmi2GetInteger");
            else if (v < -2147483647LL - 1 || v > 2147483647LL)
                st = fail(in, "fmi2GetInteger: %s = %lld does not fit fmi2Integer", in->vname[vr[i]], v);
            else value[i] = (fmi2Integer)v;
        }
        Py_DECREF(seq);
        if (st == fmi2OK) st = after_call(in, 0);
    }
    PyGILState_Release(g);
    return st;
}

static fmi2Status core_get_boolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    Inst *in = (Inst *)c;
    REQUIRE(in, "fmi2GetBoolean", GET_STATES);
    if (check_args(in, "fmi2GetBoolean", vr, nvr, value, T_BOOLEAN, 0) != fmi2OK) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    PyGILState_STATE g = PyGILState_Ensure();
    fmi2Status st = fmi2OK;
    PyObject *seq = py_get(in->m_get_boolean, vr, nvr, NULL, nvr);
    if (!seq) st = py_fail(in, "fmi2GetBoolean");
    else {
        for (size_t i = 0; i < nvr && st == fmi2OK; i++) {
            int v = PyObject_IsTrue(PySequence_Fast_GET_ITEM(seq, (Py_ssize_t)i));
            if (v < 0) st = py_fail(in, "fmi2GetBoolean");
            else value[i] = v ? fmi2True : fmi2False;
        }
        Py_DECREF(seq);
        if (st == fmi2OK) st = after_call(in, 0);
    }
    PyGILState_Release(g);
    return st;
}

static fmi2Status core_get_string(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    Inst *in = (Inst *)c;
    REQUIRE(in, "fmi2GetString", GET_STATES);
    if (check_args(in, "fmi2GetString", vr, nvr, value, T_STRING, 0) != fmi2OK) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    PyGILState_STATE g = PyGILState_Ensure();
    fmi2Status st = fmi2OK;
    PyObject *seq = py_get(in->m_get_string, vr, nvr, NULL, nvr);
    PyObject *hold = PyList_New(0);
    if (!seq || !hold) st = py_fail(in, "fmi2GetString");
    else {
        for (size_t i = 0; i < nvr && st == fmi2OK; i++) {
            PyObject *s = PyObject_Str(PySequence_Fast_GET_ITEM(seq, (Py_ssize_t)i));
            PyObject *b = s ? PyUnicode_AsUTF8String(s) : NULL;
            Py_XDECREF(s);
            if (!b || PyList_Append(hold, b) < 0) st = py_fail(in, "fmi2GetString");
            else value[i] = PyBytes_AS_STRING(b);
            Py_XDECREF(b); /* the list keeps it alive */
        }
        if (st == fmi2OK) {
            Py_XSETREF(in->str_hold, hold); /* strings stay valid until the next fmi2GetString */
            hold = NULL;
            st = after_call(in, 0);
        }
    }
    Py_XDECREF(seq);
    Py_XDECREF(hold);
    PyGILState_Release(g);
    return st;
}

/* set_*(list of vrs, list of values) with values built by make(i) */
typedef PyObject *(*maker)(const void *values, size_t i);
static PyObject *make_int(const void *v, size_t i) { return PyLong_FromLong(((const fmi2Integer *)v)[i]); }
static PyObject *make_bool(const void *v, size_t i) { return PyBool_FromLong(((const fmi2Boolean *)v)[i]); }
static PyObject *make_str(const void *v, size_t i) {
    const char *s = ((const fmi2String *)v)[i];
    if (!s) {
        PyErr_SetString(PyExc_ValueError, "NULL string value");
        return NULL;
    }
    return PyUnicode_FromString(s);
}

static fmi2Status py_set(Inst *in, const char *fn, PyObject *setter, const fmi2ValueReference vr[], size_t nvr,
                         const void *values, maker make) {
    if (nvr == 0) return fmi2OK;
    PyGILState_STATE g = PyGILState_Ensure();
    fmi2Status st;
    PyObject *vrs = vr_list(vr, nvr, NULL, nvr), *vals = PyList_New((Py_ssize_t)nvr);
    int ok = vrs && vals;
    for (size_t i = 0; ok && i < nvr; i++) {
        PyObject *v = make(values, i);
        if (!v) ok = 0;
        else PyList_SET_ITEM(vals, (Py_ssize_t)i, v);
    }
    PyObject *r = ok ? PyObject_CallFunctionObjArgs(setter, vrs, vals, NULL) : NULL;
    if (!r) st = py_fail(in, fn);
    else {
        Py_DECREF(r);
        st = after_call(in, 0);
    }
    Py_XDECREF(vrs);
    Py_XDECREF(vals);
    PyGILState_Release(g);
    return st;
}

static fmi2Status core_set_integer(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                   const fmi2Integer value[]) {
    Inst *in = (Inst *)c;
    REQUIRE(in, "fmi2SetInteger", SET_STATES);
    if (check_args(in, "fmi2SetInteger", vr, nvr, value, T_INTEGER, 1) != fmi2OK) return fmi2Error;
    return py_set(in, "fmi2SetInteger", in->m_set_integer, vr, nvr, value, make_int);
}

static fmi2Status core_set_boolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                   const fmi2Boolean value[]) {
    Inst *in = (Inst *)c;
    REQUIRE(in, "fmi2SetBoolean", SET_STATES);
    if (check_args(in, "fmi2SetBoolean", vr, nvr, value, T_BOOLEAN, 1) != fmi2OK) return fmi2Error;
    return py_set(in, "fmi2SetBoolean", in->m_set_boolean, vr, nvr, value, make_bool);
}

static fmi2Status core_set_string(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                  const fmi2String value[]) {
    Inst *in = (Inst *)c;
    REQUIRE(in, "fmi2SetString", SET_STATES);
    if (check_args(in, "fmi2SetString", vr, nvr, value, T_STRING, 1) != fmi2OK) return fmi2Error;
    return py_set(in, "fmi2SetString", in->m_set_string, vr, nvr, value, make_str);
}

/* ---------------------------------------------------------------- step */

static fmi2Status core_do_step(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSetPrior) {
    Inst *in = (Inst *)c;
    (void)noSetPrior;
    REQUIRE(in, "fmi2DoStep", S_STEP_COMPLETE);
    if (!isfinite(t)) return fail(in, "fmi2DoStep: communication point %g is not finite", t);
    if (!(h > 0.0) || !isfinite(h))
        return fail(in, "fmi2DoStep: communication step size %g must be positive and finite", h);
    if (in->have_time && fabs(t - in->t_next) > 1e-9 * fmax(1.0, fabs(in->t_next)))
        return fail(in, "fmi2DoStep: communication point %.17g does not continue the previous step, which "
                    "ended at %.17g", t, in->t_next);
    if (!in->have_time && fabs(t - in->t_start) > 1e-9 * fmax(1.0, fabs(in->t_start)))
        return fail(in, "fmi2DoStep: the first communication point %.17g is not the start time %.17g "
                    "(fmi2SetupExperiment)", t, in->t_start);
    fmi2Status st;
    PyGILState_STATE g = PyGILState_Ensure();
    PyObject *args[2] = {PyFloat_FromDouble(t), PyFloat_FromDouble(h)};
    PyObject *r = (args[0] && args[1]) ? PyObject_Vectorcall(in->m_do_step, args, 2, NULL) : NULL;
    Py_XDECREF(args[0]);
    Py_XDECREF(args[1]);
    if (!r) st = py_fail(in, "fmi2DoStep");
    else {
        int ok = PyObject_IsTrue(r);
        Py_DECREF(r);
        if (ok < 0) st = py_fail(in, "fmi2DoStep");
        else {
            st = (in->log_queue && PyList_GET_SIZE(in->log_queue)) ? after_call(in, 1) : fmi2OK;
            if (!ok && st < fmi2Discard) {
                st = fmi2Discard;
                logf_(in, fmi2Discard, "fmi2DoStep: the slave refused the step at t = %.17g", t);
            }
        }
    }
    PyGILState_Release(g);
    if (st == fmi2Discard) {
        in->state = S_STEP_FAILED;
        return st;
    }
    if (st > fmi2Discard) return st;
    if (check_outputs(in, "fmi2DoStep") != fmi2OK) return fmi2Error;
    in->have_time = 1;
    in->t_next = t + h;
    return st;
}

static fmi2Status core_cancel_step(fmi2Component c) {
    Inst *in = (Inst *)c;
    if (!in) return fmi2Error;
    return fail(in, "fmi2CancelStep: no asynchronous step is in progress (this FMU steps synchronously)");
}

static fmi2Status core_get_status(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    Inst *in = (Inst *)c;
    REQUIRE(in, "fmi2GetStatus", S_STEP_COMPLETE | S_STEP_FAILED | S_TERMINATED);
    (void)s; (void)value;
    return fmi2Discard; /* only meaningful for asynchronous steps */
}

static fmi2Status core_get_real_status(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    Inst *in = (Inst *)c;
    REQUIRE(in, "fmi2GetRealStatus", S_STEP_COMPLETE | S_STEP_FAILED | S_TERMINATED);
    if (s == fmi2LastSuccessfulTime && value) {
        *value = in->have_time ? in->t_next : 0.0;
        return fmi2OK;
    }
    return fmi2Discard;
}

static fmi2Status core_get_integer_status(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    Inst *in = (Inst *)c;
    REQUIRE(in, "fmi2GetIntegerStatus", S_STEP_COMPLETE | S_STEP_FAILED | S_TERMINATED);
    (void)s; (void)value;
    return fmi2Discard;
}

static fmi2Status core_get_boolean_status(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    Inst *in = (Inst *)c;
    REQUIRE(in, "fmi2GetBooleanStatus", S_STEP_COMPLETE | S_STEP_FAILED | S_TERMINATED);
    if (s == fmi2Terminated && value) {
        *value = fmi2False; /* the slave never asks to end the simulation */
        return fmi2OK;
    }
    return fmi2Discard;
}

static fmi2Status core_get_string_status(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    Inst *in = (Inst *)c;
    REQUIRE(in, "fmi2GetStringStatus", S_STEP_COMPLETE | S_STEP_FAILED | S_TERMINATED);
    (void)s; (void)value;
    return fmi2Discard;
}

/* ------------------------------------------- capabilities this FMU lacks */

static fmi2Status unsupported(fmi2Component c, const char *fn, const char *why) {
    Inst *in = (Inst *)c;
    if (!in) return fmi2Error;
    return fail(in, "%s: not supported (%s)", fn, why);
}

static fmi2Status core_get_state(fmi2Component c, fmi2FMUstate *s) {
    (void)s;
    return unsupported(c, "fmi2GetFMUstate", "canGetAndSetFMUstate is false");
}
static fmi2Status core_set_state(fmi2Component c, fmi2FMUstate s) {
    (void)s;
    return unsupported(c, "fmi2SetFMUstate", "canGetAndSetFMUstate is false");
}
static fmi2Status core_free_state(fmi2Component c, fmi2FMUstate *s) {
    (void)s;
    return unsupported(c, "fmi2FreeFMUstate", "canGetAndSetFMUstate is false");
}
static fmi2Status core_state_size(fmi2Component c, fmi2FMUstate s, size_t *n) {
    (void)s; (void)n;
    return unsupported(c, "fmi2SerializedFMUstateSize", "canSerializeFMUstate is false");
}
static fmi2Status core_serialize(fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t n) {
    (void)s; (void)b; (void)n;
    return unsupported(c, "fmi2SerializeFMUstate", "canSerializeFMUstate is false");
}
static fmi2Status core_deserialize(fmi2Component c, const fmi2Byte b[], size_t n, fmi2FMUstate *s) {
    (void)s; (void)b; (void)n;
    return unsupported(c, "fmi2DeSerializeFMUstate", "canSerializeFMUstate is false");
}
static fmi2Status core_directional(fmi2Component c, const fmi2ValueReference u[], size_t nu,
                                   const fmi2ValueReference z[], size_t nz, const fmi2Real dv[], fmi2Real dz[]) {
    (void)u; (void)nu; (void)z; (void)nz; (void)dv; (void)dz;
    return unsupported(c, "fmi2GetDirectionalDerivative", "providesDirectionalDerivative is false");
}
static fmi2Status core_set_input_derivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                            const fmi2Integer order[], const fmi2Real v[]) {
    (void)vr; (void)n; (void)order; (void)v;
    return unsupported(c, "fmi2SetRealInputDerivatives", "canInterpolateInputs is false");
}
static fmi2Status core_get_output_derivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                             const fmi2Integer order[], fmi2Real v[]) {
    (void)vr; (void)n; (void)order; (void)v;
    return unsupported(c, "fmi2GetRealOutputDerivatives", "maxOutputDerivativeOrder is 0");
}

/* -------------------------------------------------------------- runtime */

static int core_setup(const char *program, char *err, size_t errlen) {
    pthread_mutex_lock(&setup_lock);
    int rc = 0;
    if (!Py_IsInitialized()) {
        PyConfig config;
        PyConfig_InitPythonConfig(&config);
        config.install_signal_handlers = 0; /* the host owns SIGINT */
        config.parse_argv = 0;
        PyStatus status = PyStatus_Ok();
        if (program && program[0]) status = PyConfig_SetBytesString(&config, &config.program_name, program);
        if (!PyStatus_Exception(status)) status = Py_InitializeFromConfig(&config);
        PyConfig_Clear(&config);
        if (PyStatus_Exception(status)) {
            snprintf(err, errlen, "cannot initialise Python (program %s): %s", program ? program : "(default)",
                     status.err_msg ? status.err_msg : "unknown error");
            rc = 1;
        } else {
            PyEval_SaveThread(); /* every entry point takes the GIL with PyGILState_Ensure */
        }
    }
    pthread_mutex_unlock(&setup_lock);
    return rc;
}

static const sarins_core_api API = {
    SARINS_CORE_ABI, core_setup, core_instantiate, core_free, core_set_debug_logging, core_setup_experiment,
    core_enter_init, core_exit_init, core_terminate, core_reset, core_get_real, core_get_integer,
    core_get_boolean, core_get_string, core_set_real, core_set_integer, core_set_boolean, core_set_string,
    core_get_state, core_set_state, core_free_state, core_state_size, core_serialize, core_deserialize,
    core_directional, core_set_input_derivatives, core_get_output_derivatives, core_do_step, core_cancel_step,
    core_get_status, core_get_real_status, core_get_integer_status, core_get_boolean_status,
    core_get_string_status};

EXPORT const sarins_core_api *sarins_fmi_core_api(void) { return &API; }
