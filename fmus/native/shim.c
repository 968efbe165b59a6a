/* sarins FMI 2.0 loader shim: <modelIdentifier>.so.
 *
 * Exports the FMI 2.0 co-simulation functions and references no Python
 * symbol, so any host can load it.  The first fmi2Instantiate makes a CPython
 * runtime available and loads the core (<modelIdentifier>_pycore.so, same
 * folder) that hosts the Python slave; every call is forwarded to the core.
 *
 * Runtime search order (the first that applies wins):
 *  0. the host process already runs CPython (e.g. FMPy): use it;
 *  1. $SARINS_FMU_PYTHON: a python executable, or a libpython .so;
 *  2. the interpreter recorded at build time (resources/sarins_fmi_runtime.txt);
 *  3. python3.X, then python3, on $PATH whose version is the build's X;
 *  4. libpython3.X.so.1.0 from the system library path;
 * otherwise fmi2Instantiate logs why and returns NULL.  The runtime's
 * major.minor must equal the build's.  Python is never finalised.
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <limits.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "fmi2Functions.h"
#include "sarins_fmi.h"
#include "sarins_uri.h"

static const sarins_core_api *api = NULL;
static pthread_mutex_t load_lock = PTHREAD_MUTEX_INITIALIZER;

typedef struct {
    char version[16];     /* "3.11" */
    char executable[PATH_MAX];
    char libpython[PATH_MAX];
    char prefix[PATH_MAX];
} runtime_info;

static int is_file(const char *p) {
    struct stat st;
    return p && p[0] && stat(p, &st) == 0 && S_ISREG(st.st_mode);
}

static void append(char *buf, size_t len, const char *fmt, ...) {
    size_t used = strlen(buf);
    if (used + 1 >= len) return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf + used, len - used, fmt, ap);
    va_end(ap);
}

static void read_runtime(const char *resources, runtime_info *ri) {
    memset(ri, 0, sizeof *ri);
    char path[PATH_MAX + 64];
    snprintf(path, sizeof path, "%s/sarins_fmi_runtime.txt", resources);
    FILE *f = fopen(path, "r");
    if (!f) return;
    char line[PATH_MAX + 64];
    while (fgets(line, sizeof line, f)) {
        line[strcspn(line, "\r\n")] = '\0';
        char *eq = strchr(line, '=');
        if (!eq) continue;
        *eq = '\0';
        const char *v = eq + 1;
        if (strcmp(line, "version") == 0) snprintf(ri->version, sizeof ri->version, "%s", v);
        else if (strcmp(line, "executable") == 0) snprintf(ri->executable, sizeof ri->executable, "%s", v);
        else if (strcmp(line, "libpython") == 0) snprintf(ri->libpython, sizeof ri->libpython, "%s", v);
        else if (strcmp(line, "prefix") == 0) snprintf(ri->prefix, sizeof ri->prefix, "%s", v);
    }
    fclose(f);
}

/* "3.11.7 (main, ...)" starts with version "3.11" followed by a non-digit */
static int version_matches(const char *full, const char *want) {
    size_t n = strlen(want);
    return full && strncmp(full, want, n) == 0 && (full[n] < '0' || full[n] > '9');
}

/* Ask a python executable for its version, executable and shared libpython. */
static int query_python(const char *exe, char *version, size_t vlen, char *real_exe, char *lib, char *why,
                        size_t wlen) {
    if (strchr(exe, '\'')) {
        append(why, wlen, "; %s: quote in path", exe);
        return 0;
    }
    char cmd[PATH_MAX + 512];
    snprintf(cmd, sizeof cmd,
             "'%s' -c 'import sys,sysconfig as s,os;print(\"%%d.%%d\" %% sys.version_info[:2]);"
             "print(sys.executable);d=s.get_config_var(\"LIBDIR\") or \"\";"
             "c=[os.path.join(d,n) for n in (s.get_config_var(\"INSTSONAME\"),s.get_config_var(\"LDLIBRARY\")) if n];"
             "print(([p for p in c if p.endswith(\".so\") or \".so.\" in p and os.path.isfile(p)]+[\"\"])[0])' "
             "2>/dev/null",
             exe);
    FILE *p = popen(cmd, "r");
    if (!p) {
        append(why, wlen, "; %s: cannot run", exe);
        return 0;
    }
    char lines[3][PATH_MAX];
    int n = 0;
    while (n < 3 && fgets(lines[n], PATH_MAX, p)) {
        lines[n][strcspn(lines[n], "\r\n")] = '\0';
        n++;
    }
    int rc = pclose(p);
    if (n < 3 || rc != 0) {
        append(why, wlen, "; %s: not a working python", exe);
        return 0;
    }
    snprintf(version, vlen, "%.15s", lines[0]);
    snprintf(real_exe, PATH_MAX, "%s", lines[1]);
    snprintf(lib, PATH_MAX, "%s", lines[2]);
    if (!is_file(lib)) {
        append(why, wlen, "; %s (%s) has no shared libpython", exe, version);
        return 0;
    }
    return 1;
}

/* The python executable belonging to a libpython (for sys.prefix), or "". */
static void program_of_lib(const char *lib, const char *version, char *program) {
    char dir[PATH_MAX];
    program[0] = '\0';
    snprintf(dir, sizeof dir, "%s", lib);
    for (int up = 0; up < 4; up++) {
        char *slash = strrchr(dir, '/');
        if (!slash || slash == dir) return;
        *slash = '\0';
        char probe[PATH_MAX + 64];
        snprintf(probe, sizeof probe, "%s/lib/python%s/os.py", dir, version);
        if (is_file(probe)) {
            snprintf(probe, sizeof probe, "%s/bin/python%s", dir, version);
            if (is_file(probe)) snprintf(program, PATH_MAX, "%.4000s", probe);
            return;
        }
    }
}

/* Pick a libpython and the matching executable; 1 on success. */
static int find_python(const runtime_info *ri, char *lib, char *program, char *why, size_t wlen) {
    char version[32], exe[PATH_MAX];
    const char *env = getenv("SARINS_FMU_PYTHON");
    if (env && env[0]) {
        if (strstr(env, ".so")) {
            if (is_file(env)) {
                snprintf(lib, PATH_MAX, "%s", env);
                program_of_lib(lib, ri->version, program);
                return 1;
            }
            append(why, wlen, "; SARINS_FMU_PYTHON=%s: no such file", env);
        } else if (query_python(env, version, sizeof version, exe, lib, why, wlen)) {
            if (strcmp(version, ri->version) == 0) {
                snprintf(program, PATH_MAX, "%s", exe);
                return 1;
            }
            append(why, wlen, "; SARINS_FMU_PYTHON=%s is Python %s", env, version);
        }
    }
    if (is_file(ri->libpython)) {
        snprintf(lib, PATH_MAX, "%s", ri->libpython);
        if (is_file(ri->executable)) snprintf(program, PATH_MAX, "%s", ri->executable);
        else program_of_lib(lib, ri->version, program);
        return 1;
    }
    append(why, wlen, "; recorded runtime %s: not found", ri->libpython[0] ? ri->libpython : "(none)");
    const char *path = getenv("PATH");
    char names[2][32];
    snprintf(names[0], sizeof names[0], "python%s", ri->version);
    snprintf(names[1], sizeof names[1], "python3");
    for (int k = 0; k < 2 && path; k++) {
        const char *p = path;
        while (*p) {
            size_t n = strcspn(p, ":");
            char cand[PATH_MAX + 64];
            snprintf(cand, sizeof cand, "%.*s/%s", (int)(n ? n : 1), n ? p : ".", names[k]);
            if (access(cand, X_OK) == 0 && query_python(cand, version, sizeof version, exe, lib, why, wlen)) {
                if (strcmp(version, ri->version) == 0) {
                    snprintf(program, PATH_MAX, "%s", exe);
                    return 1;
                }
                append(why, wlen, "; %s is Python %s", cand, version);
            }
            p += n;
            if (*p == ':') p++;
        }
    }
    char soname[64];
    snprintf(soname, sizeof soname, "libpython%s.so.1.0", ri->version);
    void *h = dlopen(soname, RTLD_NOW | RTLD_GLOBAL);
    if (h) {
        void *sym = dlsym(h, "Py_IsInitialized");
        Dl_info info;
        if (sym && dladdr(sym, &info) && info.dli_fname) {
            snprintf(lib, PATH_MAX, "%s", info.dli_fname);
            program_of_lib(lib, ri->version, program);
            return 1;
        }
    }
    append(why, wlen, "; %s: not on the library path", soname);
    return 0;
}

static void report(const fmi2CallbackFunctions *functions, fmi2String name, const char *msg) {
    if (functions && functions->logger)
        functions->logger(functions->componentEnvironment, name ? name : "", fmi2Error, "logStatusError", "%s", msg);
    else
        fprintf(stderr, "[%s] fmi2Instantiate: %s\n", name ? name : "", msg);
}

static int load_core(const char *resources, char *err, size_t errlen) {
    Dl_info self;
    /* function and object pointers convert through uintptr_t (POSIX; ISO C has no direct conversion) */
    if (!dladdr((void *)(uintptr_t)&load_core, &self) || !self.dli_fname) {
        snprintf(err, errlen, "cannot locate this FMU's binary");
        return 0;
    }
    char core[PATH_MAX];
    snprintf(core, sizeof core, "%s", self.dli_fname);
    size_t n = strlen(core);
    if (n > 3 && strcmp(core + n - 3, ".so") == 0) core[n - 3] = '\0';
    strncat(core, "_pycore.so", sizeof core - strlen(core) - 1);

    runtime_info ri;
    read_runtime(resources, &ri);
    if (!ri.version[0]) {
        snprintf(err, errlen, "%s/sarins_fmi_runtime.txt is missing or has no version", resources);
        return 0;
    }
    char lib[PATH_MAX] = "", program[PATH_MAX] = "";
    int (*initialized)(void) = (int (*)(void))(uintptr_t)dlsym(RTLD_DEFAULT, "Py_IsInitialized");
    if (!initialized) {
        char why[4096] = "";
        if (!find_python(&ri, lib, program, why, sizeof why)) {
            snprintf(err, errlen,
                     "no CPython %s runtime found (this FMU needs CPython %s with numpy; set SARINS_FMU_PYTHON to "
                     "a python%s executable or its libpython .so)%s",
                     ri.version, ri.version, ri.version, why);
            return 0;
        }
        if (!dlopen(lib, RTLD_NOW | RTLD_GLOBAL)) {
            snprintf(err, errlen, "cannot load %s: %s", lib, dlerror());
            return 0;
        }
    } else if (!initialized()) {
        program_of_lib(ri.libpython, ri.version, program); /* libpython present but idle: start it */
        if (is_file(ri.executable)) snprintf(program, sizeof program, "%s", ri.executable);
    }
    const char *(*get_version)(void) = (const char *(*)(void))(uintptr_t)dlsym(RTLD_DEFAULT, "Py_GetVersion");
    const char *running = get_version ? get_version() : NULL;
    if (!version_matches(running, ri.version)) {
        snprintf(err, errlen, "this FMU was built for CPython %s but the process runs CPython %s", ri.version,
                 running ? running : "(unknown)");
        return 0;
    }
    void *h = dlopen(core, RTLD_NOW | RTLD_NODELETE); /* never unloaded: Python objects may point into it */
    if (!h) {
        snprintf(err, errlen, "cannot load %s: %s", core, dlerror());
        return 0;
    }
    sarins_core_entry entry = (sarins_core_entry)(uintptr_t)dlsym(h, SARINS_CORE_ENTRY);
    const sarins_core_api *a = entry ? entry() : NULL;
    if (!a || a->abi != SARINS_CORE_ABI) {
        snprintf(err, errlen, "%s is not a matching sarins FMI core", core);
        return 0;
    }
    if (a->setup(program[0] ? program : NULL, err, errlen) != 0) return 0;
    api = a;
    return 1;
}

/* The core's table once loaded (NULL before), read under load_lock like every access to api. */
static const sarins_core_api *loaded_api(void) {
    pthread_mutex_lock(&load_lock);
    const sarins_core_api *a = api;
    pthread_mutex_unlock(&load_lock);
    return a;
}

FMI2_Export const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
FMI2_Export const char *fmi2GetVersion(void) { return fmi2Version; }

FMI2_Export fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String resources,
                                          const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                                          fmi2Boolean loggingOn) {
    char err[8192] = "";
    pthread_mutex_lock(&load_lock);
    if (api == NULL) {
        char path[PATH_MAX];
        int uri = sarins_uri_to_path(resources, path, sizeof path);
        if (uri != SARINS_URI_OK)
            snprintf(err, sizeof err, "fmuResourceLocation %.4000s: %s", resources ? resources : "(null)",
                     sarins_uri_error(uri));
        else
            load_core(path, err, sizeof err);
    }
    const sarins_core_api *a = api;
    pthread_mutex_unlock(&load_lock);
    if (a == NULL) {
        report(functions, name, err);
        return NULL;
    }
    return a->instantiate(name, type, guid, resources, functions, visible, loggingOn);
}

#define FWD(call)                                          \
    do {                                                   \
        const sarins_core_api *a_ = loaded_api();          \
        return (c && a_) ? a_->call : fmi2Error;           \
    } while (0)

FMI2_Export void fmi2FreeInstance(fmi2Component c) {
    const sarins_core_api *a = loaded_api();
    if (c && a) a->freeInstance(c);
}
FMI2_Export fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cats[]) {
    FWD(setDebugLogging(c, on, n, cats));
}
FMI2_Export fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolDefined, fmi2Real tol, fmi2Real t0,
                                           fmi2Boolean stopDefined, fmi2Real t1) {
    FWD(setupExperiment(c, tolDefined, tol, t0, stopDefined, t1));
}
FMI2_Export fmi2Status fmi2EnterInitializationMode(fmi2Component c) { FWD(enterInitializationMode(c)); }
FMI2_Export fmi2Status fmi2ExitInitializationMode(fmi2Component c) { FWD(exitInitializationMode(c)); }
FMI2_Export fmi2Status fmi2Terminate(fmi2Component c) { FWD(terminate(c)); }
FMI2_Export fmi2Status fmi2Reset(fmi2Component c) { FWD(reset(c)); }
FMI2_Export fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real v[]) {
    FWD(getReal(c, vr, n, v));
}
FMI2_Export fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer v[]) {
    FWD(getInteger(c, vr, n, v));
}
FMI2_Export fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Boolean v[]) {
    FWD(getBoolean(c, vr, n, v));
}
FMI2_Export fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2String v[]) {
    FWD(getString(c, vr, n, v));
}
FMI2_Export fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real v[]) {
    FWD(setReal(c, vr, n, v));
}
FMI2_Export fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                      const fmi2Integer v[]) {
    FWD(setInteger(c, vr, n, v));
}
FMI2_Export fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                      const fmi2Boolean v[]) {
    FWD(setBoolean(c, vr, n, v));
}
FMI2_Export fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2String v[]) {
    FWD(setString(c, vr, n, v));
}
FMI2_Export fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s) { FWD(getFMUstate(c, s)); }
FMI2_Export fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s) { FWD(setFMUstate(c, s)); }
FMI2_Export fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s) { FWD(freeFMUstate(c, s)); }
FMI2_Export fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *n) {
    FWD(serializedFMUstateSize(c, s, n));
}
FMI2_Export fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t n) {
    FWD(serializeFMUstate(c, s, b, n));
}
FMI2_Export fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte b[], size_t n, fmi2FMUstate *s) {
    FWD(deSerializeFMUstate(c, b, n, s));
}
FMI2_Export fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu,
                                                    const fmi2ValueReference z[], size_t nz, const fmi2Real dv[],
                                                    fmi2Real dz[]) {
    FWD(getDirectionalDerivative(c, u, nu, z, nz, dv, dz));
}
FMI2_Export fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                                   const fmi2Integer order[], const fmi2Real v[]) {
    FWD(setRealInputDerivatives(c, vr, n, order, v));
}
FMI2_Export fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                                    const fmi2Integer order[], fmi2Real v[]) {
    FWD(getRealOutputDerivatives(c, vr, n, order, v));
}
FMI2_Export fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSetPrior) {
    FWD(doStep(c, t, h, noSetPrior));
}
FMI2_Export fmi2Status fmi2CancelStep(fmi2Component c) { FWD(cancelStep(c)); }
FMI2_Export fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *v) {
    FWD(getStatus(c, s, v));
}
FMI2_Export fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *v) {
    FWD(getRealStatus(c, s, v));
}
FMI2_Export fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *v) {
    FWD(getIntegerStatus(c, s, v));
}
FMI2_Export fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *v) {
    FWD(getBooleanStatus(c, s, v));
}
FMI2_Export fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *v) {
    FWD(getStringStatus(c, s, v));
}
