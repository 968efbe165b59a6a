/* A portable FMI 2.0 co-simulation host for the native FMUs (fmus/c): Linux (dlopen) and Windows
 * (LoadLibrary; built with mingw-w64 and run under wine).  No Python anywhere.
 *
 * usage: native_fmu_host BINARY GUID STEPS STEP_SIZE [ops...]
 *   rVR=VALUE  iVR=VALUE  sVR=TEXT   set before initialisation
 *   out=VR,VR,...                    Real outputs printed after initialisation and after every step as
 *                                    "OUT k <16 hex digits per value>" (k = steps done; the bit patterns)
 *   roundtrip=K                      after K steps: fmi2GetFMUstate, the remaining steps (printed), then
 *                                    fmi2SetFMUstate and the same steps again, printed as "AGAIN k ..."
 *   save=FILE                        after the last step: serialize the FMU state into FILE
 *   load=FILE                        after initialisation: deserialize FILE and set it, then step on from
 *                                    the time it holds (fmi2GetRealStatus fmi2LastSuccessfulTime)
 *   in=VR,VR,...                     Real inputs set before every fmi2DoStep from rows=FILE
 *   rows=FILE                        float64 values, native byte order, one row of len(in) values per step:
 *                                    row k is set before the step from k steps done to k + 1
 *   res=URI                          fmi2Instantiate's fmuResourceLocation (default file:///nonexistent)
 *   allocs                           print "ALLOCS n" = heap allocations counted (tests/native_host/
 *                                    alloc_counter.c, LD_PRELOAD) from after fmi2ExitInitializationMode to
 *                                    before fmi2Terminate (Linux only; "ALLOCS none" without the counter)
 * Every call that does not return fmi2OK prints "STATUS <function> <status>", the logger's messages print
 * "LOG ...".  Exit 0 when the sequence ran (whatever the statuses), 2 on a usage or loading error.
 */
#if !defined(_WIN32)
#define _GNU_SOURCE
#endif
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "host_common.h"

typedef struct {
    fmi2InstantiateTYPE *instantiate;
    fmi2SetupExperimentTYPE *setup;
    fmi2EnterInitializationModeTYPE *enter;
    fmi2ExitInitializationModeTYPE *exit_init;
    fmi2DoStepTYPE *step;
    fmi2TerminateTYPE *terminate;
    fmi2FreeInstanceTYPE *free_instance;
    fmi2SetRealTYPE *set_real;
    fmi2SetIntegerTYPE *set_integer;
    fmi2SetStringTYPE *set_string;
    fmi2GetRealTYPE *get_real;
    fmi2GetRealStatusTYPE *real_status;
    fmi2GetFMUstateTYPE *get_state;
    fmi2SetFMUstateTYPE *set_state;
    fmi2FreeFMUstateTYPE *free_state;
    fmi2SerializedFMUstateSizeTYPE *state_size;
    fmi2SerializeFMUstateTYPE *serialize;
    fmi2DeSerializeFMUstateTYPE *deserialize;
} api_t;

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...)
{
    (void)env;
    va_list ap;
    va_start(ap, message);
    printf("LOG %s %d %s: ", name ? name : "", (int)status, category ? category : "");
    vprintf(message, ap);
    printf("\n");
    va_end(ap);
    fflush(stdout);
}

static int report(const char *fn, fmi2Status st)
{
    if (st != fmi2OK)
        printf("STATUS %s %d\n", fn, (int)st);
    fflush(stdout);
    return st == fmi2OK;
}

static fmi2ValueReference outs[256];
static size_t n_outs;

static int print_outputs(const api_t *f, fmi2Component c, const char *tag, long k)
{
    fmi2Real v[256];
    if (n_outs == 0)
        return 1;
    if (!report("fmi2GetReal", f->get_real(c, outs, n_outs, v)))
        return 0;
    host_print_bits(tag, k, v, n_outs);
    return 1;
}

static fmi2ValueReference ins[256];
static size_t n_ins;
static double *in_rows; /* (rows, n_ins), from rows=FILE */
static long n_in_rows;

static int steps(const api_t *f, fmi2Component c, double t0, long k0, long n, double h, const char *tag)
{
    for (long k = 0; k < n; k++) {
        if (n_ins > 0 && !(k0 + k < n_in_rows
                           && report("fmi2SetReal", f->set_real(c, ins, n_ins, in_rows + (size_t)(k0 + k) * n_ins))))
            return 0;
        if (!report("fmi2DoStep", f->step(c, t0 + (double)k * h, h, fmi2False)))
            return 0;
        if (!print_outputs(f, c, tag, k0 + k + 1))
            return 0;
    }
    return 1;
}

typedef void (*counter_get_t)(unsigned long long *);
typedef void (*counter_reset_t)(void);

int main(int argc, char **argv)
{
    if (argc < 5) {
        fprintf(stderr, "usage: native_fmu_host BINARY GUID STEPS STEP_SIZE [ops...]\n");
        return 2;
    }
    const char *binary = argv[1], *guid = argv[2];
    long n_steps = atol(argv[3]);
    double h = atof(argv[4]);
    lib_t lib = lib_open(binary);
    if (!lib) {
        fprintf(stderr, "cannot load %s\n", binary);
        return 2;
    }
    api_t f;
    const host_symbol syms[] = {
        {(void **)&f.instantiate, "fmi2Instantiate"}, {(void **)&f.setup, "fmi2SetupExperiment"},
        {(void **)&f.enter, "fmi2EnterInitializationMode"}, {(void **)&f.exit_init, "fmi2ExitInitializationMode"},
        {(void **)&f.step, "fmi2DoStep"}, {(void **)&f.terminate, "fmi2Terminate"},
        {(void **)&f.free_instance, "fmi2FreeInstance"}, {(void **)&f.set_real, "fmi2SetReal"},
        {(void **)&f.set_integer, "fmi2SetInteger"}, {(void **)&f.set_string, "fmi2SetString"},
        {(void **)&f.get_real, "fmi2GetReal"}, {(void **)&f.real_status, "fmi2GetRealStatus"},
        {(void **)&f.get_state, "fmi2GetFMUstate"}, {(void **)&f.set_state, "fmi2SetFMUstate"},
        {(void **)&f.free_state, "fmi2FreeFMUstate"}, {(void **)&f.state_size, "fmi2SerializedFMUstateSize"},
        {(void **)&f.serialize, "fmi2SerializeFMUstate"}, {(void **)&f.deserialize, "fmi2DeSerializeFMUstate"},
    };
    if (!host_resolve(lib, syms, sizeof syms / sizeof syms[0]))
        return 2;
    long roundtrip = -1;
    const char *save = NULL, *load = NULL, *resources = "file:///nonexistent";
    int allocs = 0;
    for (int k = 5; k < argc; k++) {
        if (strncmp(argv[k], "out=", 4) == 0) {
            host_parse_vrs(argv[k] + 4, outs, &n_outs, 256);
        } else if (strncmp(argv[k], "in=", 3) == 0) {
            host_parse_vrs(argv[k] + 3, ins, &n_ins, 256);
        } else if (strncmp(argv[k], "rows=", 5) == 0) {
            if (!host_read_doubles(argv[k] + 5, &in_rows, &n_in_rows)) {
                fprintf(stderr, "cannot read %s\n", argv[k] + 5);
                return 2;
            }
        } else if (strncmp(argv[k], "roundtrip=", 10) == 0) {
            roundtrip = atol(argv[k] + 10);
        } else if (strncmp(argv[k], "save=", 5) == 0) {
            save = argv[k] + 5;
        } else if (strncmp(argv[k], "load=", 5) == 0) {
            load = argv[k] + 5;
        } else if (strncmp(argv[k], "res=", 4) == 0) {
            resources = argv[k] + 4;
        } else if (strcmp(argv[k], "allocs") == 0) {
            allocs = 1;
        }
    }
    if (n_ins > 0)
        n_in_rows /= (long)n_ins;
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    fmi2Component c = f.instantiate("host", fmi2CoSimulation, guid, resources, &cb, fmi2False, fmi2False);
    if (!c) {
        printf("STATUS fmi2Instantiate NULL\n");
        return 0;
    }
    int ok = report("fmi2SetupExperiment", f.setup(c, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    for (int k = 5; ok && k < argc; k++) {
        char *op = argv[k], *eq = strchr(op, '=');
        if (!eq || !(op[0] == 'r' || op[0] == 'i' || op[0] == 's') || !(op[1] >= '0' && op[1] <= '9'))
            continue;
        fmi2ValueReference vr = (fmi2ValueReference)strtoul(op + 1, NULL, 10);
        if (op[0] == 'r') {
            fmi2Real v = atof(eq + 1);
            ok = report("fmi2SetReal", f.set_real(c, &vr, 1, &v));
        } else if (op[0] == 'i') {
            fmi2Integer v = atoi(eq + 1);
            ok = report("fmi2SetInteger", f.set_integer(c, &vr, 1, &v));
        } else {
            fmi2String v = eq + 1;
            ok = report("fmi2SetString", f.set_string(c, &vr, 1, &v));
        }
    }
    ok = ok && report("fmi2EnterInitializationMode", f.enter(c));
    ok = ok && report("fmi2ExitInitializationMode", f.exit_init(c));
    ok = ok && print_outputs(&f, c, "OUT", 0);
    long k0 = 0;
    if (ok && load != NULL) {
        FILE *in = fopen(load, "rb");
        static fmi2Byte blob[1 << 20];
        size_t n = in ? fread(blob, 1, sizeof blob, in) : 0;
        if (in)
            fclose(in);
        fmi2FMUstate s = NULL;
        ok = report("fmi2DeSerializeFMUstate", f.deserialize(c, blob, n, &s));
        ok = ok && report("fmi2SetFMUstate", f.set_state(c, s));
        if (s != NULL)
            report("fmi2FreeFMUstate", f.free_state(c, &s));
        fmi2Real t = 0.0;
        ok = ok && report("fmi2GetRealStatus", f.real_status(c, fmi2LastSuccessfulTime, &t));
        k0 = (long)(t / h + 0.5);
        ok = ok && print_outputs(&f, c, "LOADED", k0);
    }
    counter_get_t counter_get = NULL;
    counter_reset_t counter_reset = NULL;
#if !defined(_WIN32)
    counter_get = (counter_get_t)(uintptr_t)dlsym(RTLD_DEFAULT, "alloc_counter_get");
    counter_reset = (counter_reset_t)(uintptr_t)dlsym(RTLD_DEFAULT, "alloc_counter_reset");
#endif
    if (allocs && counter_reset)
        counter_reset();
    double t0 = (double)k0 * h;
    if (ok && roundtrip >= 0 && roundtrip <= n_steps) {
        fmi2FMUstate s = NULL;
        ok = steps(&f, c, t0, k0, roundtrip, h, "OUT");
        ok = ok && report("fmi2GetFMUstate", f.get_state(c, &s));
        ok = ok && steps(&f, c, t0 + (double)roundtrip * h, k0 + roundtrip, n_steps - roundtrip, h, "OUT");
        ok = ok && report("fmi2SetFMUstate", f.set_state(c, s));
        ok = ok && steps(&f, c, t0 + (double)roundtrip * h, k0 + roundtrip, n_steps - roundtrip, h, "AGAIN");
        if (s != NULL)
            report("fmi2FreeFMUstate", f.free_state(c, &s));
    } else if (ok) {
        ok = steps(&f, c, t0, k0, n_steps, h, "OUT");
    }
    if (allocs) {
        if (counter_get) {
            unsigned long long counts[4];
            counter_get(counts);
            printf("ALLOCS %llu\n", counts[0]);
        } else {
            printf("ALLOCS none\n");
        }
    }
    if (ok && save != NULL) {
        fmi2FMUstate s = NULL;
        size_t n = 0;
        static fmi2Byte blob[1 << 20];
        ok = report("fmi2GetFMUstate", f.get_state(c, &s));
        ok = ok && report("fmi2SerializedFMUstateSize", f.state_size(c, s, &n));
        ok = ok && (n <= sizeof blob) && report("fmi2SerializeFMUstate", f.serialize(c, s, blob, n));
        FILE *out = ok ? fopen(save, "wb") : NULL;
        ok = out != NULL && fwrite(blob, 1, n, out) == n;
        if (out)
            fclose(out);
        if (s != NULL)
            report("fmi2FreeFMUstate", f.free_state(c, &s));
    }
    if (ok)
        report("fmi2Terminate", f.terminate(c));
    f.free_instance(c);
    free(in_rows);
    printf("DONE %d\n", ok);
    return 0;
}
