/* A minimal native FMI 2.0 co-simulation host for the tests: no Python in it.
 *
 * usage: host UNZIPPED_DIR MODEL_IDENTIFIER GUID STEPS [STEP_SIZE] [ops...]
 *   ops before initialisation:  rVR=VALUE  iVR=VALUE  sVR=TEXT
 *   probes after initialisation: probe-real=VR  probe-int=VR (get with that vr/type)
 *   after the last step:         final-real=VR (prints "VALUE VR %.17g")
 *   time-tagged Real input:      tagVR=OFFSET (set to t + OFFSET before every doStep(t, h))
 *   timestamp:                   time-at=K (prints "STAMP K <unix time, s>" after the K-th doStep)
 *
 * Runs instantiate -> setupExperiment -> set -> enter/exit initialisation ->
 * STEPS doSteps -> terminate -> free, prints "<function> <status>" for every
 * call that does not return fmi2OK and the logger's messages, and exits 0 when
 * the sequence ran (whatever the statuses), 2 on a usage or loading error.
 */
#include <dlfcn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmi2Functions.h"

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env;
    va_list ap;
    va_start(ap, message);
    printf("LOG %s %d %s: ", name ? name : "", (int)status, category ? category : "");
    vprintf(message, ap);
    printf("\n");
    va_end(ap);
    fflush(stdout);
}

#define LOAD(name)                                                                 \
    name##TYPE *name = (name##TYPE *)dlsym(lib, #name);                            \
    if (!name) {                                                                   \
        fprintf(stderr, "missing symbol %s\n", #name);                              \
        return 2;                                                                  \
    }

static int is_op(const char *op, const char *prefix) { return strncmp(op, prefix, strlen(prefix)) == 0; }

static void stamp(long k) {
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    printf("STAMP %ld %.6f\n", k, (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec);
    fflush(stdout);
}

/* Before doStep(t, h): every tagVR=OFFSET input gets t + OFFSET. */
static fmi2Status set_tags(fmi2SetRealTYPE *set_real, fmi2Component c, int argc, char **argv, int first_op,
                           double t) {
    for (int k = first_op; k < argc; k++) {
        char *eq = strchr(argv[k], '=');
        if (!is_op(argv[k], "tag") || !eq) continue;
        fmi2ValueReference vr = (fmi2ValueReference)strtoul(argv[k] + 3, NULL, 10);
        fmi2Real v = t + atof(eq + 1);
        fmi2Status st = set_real(c, &vr, 1, &v);
        if (st != fmi2OK) return st;
    }
    return fmi2OK;
}

static int report(const char *fn, fmi2Status st) {
    if (st != fmi2OK) printf("STATUS %s %d\n", fn, (int)st);
    fflush(stdout);
    return st;
}

int main(int argc, char **argv) {
    if (argc < 5) {
        fprintf(stderr, "usage: host DIR MODEL_IDENTIFIER GUID STEPS [STEP_SIZE] [ops...]\n");
        return 2;
    }
    const char *dir = argv[1], *model = argv[2], *guid = argv[3];
    long steps = atol(argv[4]);
    double h = 1.0;
    int first_op = 5;
    if (argc > 5 && argv[5][0] >= '0' && argv[5][0] <= '9') {
        h = atof(argv[5]);
        first_op = 6;
    }
    char path[4096], uri[4200];
    snprintf(path, sizeof path, "%s/binaries/linux64/%s.so", dir, model);
    void *lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "cannot load %s: %s\n", path, dlerror());
        return 2;
    }
    LOAD(fmi2Instantiate) LOAD(fmi2SetupExperiment) LOAD(fmi2EnterInitializationMode)
    LOAD(fmi2ExitInitializationMode) LOAD(fmi2DoStep) LOAD(fmi2Terminate) LOAD(fmi2FreeInstance)
    LOAD(fmi2SetReal) LOAD(fmi2SetInteger) LOAD(fmi2SetString) LOAD(fmi2GetReal) LOAD(fmi2GetInteger)
    snprintf(uri, sizeof uri, "file://%s/resources", dir);
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    fmi2Component c = fmi2Instantiate("host", fmi2CoSimulation, guid, uri, &cb, fmi2False, fmi2True);
    if (!c) {
        printf("STATUS fmi2Instantiate NULL\n");
        return 0;
    }
    report("fmi2SetupExperiment", fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    for (int k = first_op; k < argc; k++) {
        char *op = argv[k], *eq = strchr(op, '=');
        if (!eq || strncmp(op, "probe-", 6) == 0 || strncmp(op, "final-", 6) == 0) continue;
        fmi2ValueReference vr = (fmi2ValueReference)strtoul(op + 1, NULL, 10);
        if (op[0] == 'r') {
            fmi2Real v = atof(eq + 1);
            report("fmi2SetReal", fmi2SetReal(c, &vr, 1, &v));
        } else if (op[0] == 'i') {
            fmi2Integer v = atoi(eq + 1);
            report("fmi2SetInteger", fmi2SetInteger(c, &vr, 1, &v));
        } else if (op[0] == 's') {
            fmi2String v = eq + 1;
            report("fmi2SetString", fmi2SetString(c, &vr, 1, &v));
        }
    }
    int ok = report("fmi2EnterInitializationMode", fmi2EnterInitializationMode(c)) == fmi2OK;
    ok = ok && report("fmi2ExitInitializationMode", fmi2ExitInitializationMode(c)) == fmi2OK;
    for (int k = first_op; ok && k < argc; k++) {
        fmi2ValueReference vr;
        if (strncmp(argv[k], "probe-real=", 11) == 0) {
            vr = (fmi2ValueReference)strtoul(argv[k] + 11, NULL, 10);
            fmi2Real v;
            ok = report("fmi2GetReal", fmi2GetReal(c, &vr, 1, &v)) == fmi2OK;
        } else if (strncmp(argv[k], "probe-int=", 10) == 0) {
            vr = (fmi2ValueReference)strtoul(argv[k] + 10, NULL, 10);
            fmi2Integer v;
            ok = report("fmi2GetInteger", fmi2GetInteger(c, &vr, 1, &v)) == fmi2OK;
        }
    }
    long done = 0;
    for (long n = 0; ok && n < steps; n++, done++) {
        ok = report("fmi2SetReal", set_tags(fmi2SetReal, c, argc, argv, first_op, n * h)) == fmi2OK;
        ok = ok && report("fmi2DoStep", fmi2DoStep(c, n * h, h, fmi2True)) == fmi2OK;
        for (int k = first_op; ok && k < argc; k++)
            if (is_op(argv[k], "time-at=") && atol(argv[k] + 8) == n + 1) stamp(n + 1);
    }
    for (int k = first_op; ok && k < argc; k++) {
        if (strncmp(argv[k], "final-real=", 11) != 0) continue;
        fmi2ValueReference vr = (fmi2ValueReference)strtoul(argv[k] + 11, NULL, 10);
        fmi2Real v;
        ok = report("fmi2GetReal", fmi2GetReal(c, &vr, 1, &v)) == fmi2OK;
        if (ok) printf("VALUE %u %.17g\n", (unsigned)vr, v);
    }
    if (ok) report("fmi2Terminate", fmi2Terminate(c));
    fmi2FreeInstance(c);
    printf("DONE %ld\n", done);
    return 0;
}
