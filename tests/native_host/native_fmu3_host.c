/* A portable FMI 3.0 co-simulation host for the native FMUs (fmus/c): Linux (dlopen) and Windows
 * (LoadLibrary; built with mingw-w64 and run under wine).  No Python anywhere.  The FMI 3.0 sibling of
 * native_fmu_host.c, with arrays.
 *
 * usage: native_fmu3_host BINARY TOKEN STEPS STEP_SIZE [ops...]
 *   uVR=VALUE                        a structural parameter (UInt64), set in Configuration Mode
 *   rVR=VALUE  iVR=VALUE  sVR=TEXT   Float64 / Int32 / String, set in Instantiated
 *   out=VR,VR,...  nout=N            Float64 outputs (arrays whole) giving N values in all, printed after
 *                                    initialisation and after every step as "OUT k <16 hex digits per value>"
 *   in=VR,VR,...  nin=N  rows=FILE   Float64 inputs (arrays whole, N values in all) set before every step:
 *                                    FILE holds float64 values, native byte order, row k (N values) for the
 *                                    step from k steps done to k + 1
 *   res=PATH                         fmi3InstantiateCoSimulation's resourcePath (default NULL)
 *   roundtrip=K                      after K steps: fmi3GetFMUState, the remaining steps (printed), then
 *                                    fmi3SetFMUState and the same steps again, printed as "AGAIN k ..."
 * Every call that does not return fmi3OK prints "STATUS <function> <status>", the logger's messages print
 * "LOG ...".  Exit 0 when the sequence ran (whatever the statuses), 2 on a usage or loading error.
 */
#if !defined(_WIN32)
#define _GNU_SOURCE
#endif
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "host_common.h"

#define MAX_VR 64

typedef struct {
    fmi3InstantiateCoSimulationTYPE *instantiate;
    fmi3EnterConfigurationModeTYPE *enter_config;
    fmi3ExitConfigurationModeTYPE *exit_config;
    fmi3EnterInitializationModeTYPE *enter;
    fmi3ExitInitializationModeTYPE *exit_init;
    fmi3DoStepTYPE *step;
    fmi3TerminateTYPE *terminate;
    fmi3FreeInstanceTYPE *free_instance;
    fmi3SetFloat64TYPE *set_float64;
    fmi3SetInt32TYPE *set_int32;
    fmi3SetUInt64TYPE *set_uint64;
    fmi3SetStringTYPE *set_string;
    fmi3GetFloat64TYPE *get_float64;
    fmi3GetFMUStateTYPE *get_state;
    fmi3SetFMUStateTYPE *set_state;
    fmi3FreeFMUStateTYPE *free_state;
} api_t;

typedef struct {
    fmi3ValueReference vr[MAX_VR];
    size_t n_vr, n_values;
} vr_list;

static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message)
{
    (void)env;
    printf("LOG %d %s: %s\n", (int)status, category ? category : "", message ? message : "");
    fflush(stdout);
}

static int report(const char *fn, fmi3Status st)
{
    if (st != fmi3OK)
        printf("STATUS %s %d\n", fn, (int)st);
    fflush(stdout);
    return st == fmi3OK;
}

static vr_list outs, ins;
static double *out_values;  /* outs.n_values */
static double *in_rows;     /* (n_in_rows, ins.n_values), from rows=FILE */
static long n_in_rows;

static int print_outputs(const api_t *f, fmi3Instance c, const char *tag, long k)
{
    if (outs.n_vr == 0)
        return 1;
    if (!report("fmi3GetFloat64", f->get_float64(c, outs.vr, outs.n_vr, out_values, outs.n_values)))
        return 0;
    host_print_bits(tag, k, out_values, outs.n_values);
    return 1;
}

static int steps(const api_t *f, fmi3Instance c, long k0, long n, double h, const char *tag)
{
    for (long k = k0; k < k0 + n; k++) {
        if (ins.n_vr > 0 && !(k < n_in_rows && report("fmi3SetFloat64", f->set_float64(c, ins.vr, ins.n_vr,
                                                      in_rows + (size_t)k * ins.n_values, ins.n_values))))
            return 0;
        fmi3Boolean event = fmi3False, stop = fmi3False, early = fmi3False;
        fmi3Float64 last = 0.0;
        if (!report("fmi3DoStep", f->step(c, (double)k * h, h, fmi3False, &event, &stop, &early, &last)))
            return 0;
        if (!print_outputs(f, c, tag, k + 1))
            return 0;
    }
    return 1;
}

int main(int argc, char **argv)
{
    if (argc < 5) {
        fprintf(stderr, "usage: native_fmu3_host BINARY TOKEN STEPS STEP_SIZE [ops...]\n");
        return 2;
    }
    const char *binary = argv[1], *token = argv[2];
    long n_steps = atol(argv[3]);
    double h = atof(argv[4]);
    lib_t lib = lib_open(binary);
    if (!lib) {
        fprintf(stderr, "cannot load %s\n", binary);
        return 2;
    }
    api_t f;
    const host_symbol syms[] = {
        {(void **)&f.instantiate, "fmi3InstantiateCoSimulation"},
        {(void **)&f.enter_config, "fmi3EnterConfigurationMode"},
        {(void **)&f.exit_config, "fmi3ExitConfigurationMode"},
        {(void **)&f.enter, "fmi3EnterInitializationMode"}, {(void **)&f.exit_init, "fmi3ExitInitializationMode"},
        {(void **)&f.step, "fmi3DoStep"}, {(void **)&f.terminate, "fmi3Terminate"},
        {(void **)&f.free_instance, "fmi3FreeInstance"}, {(void **)&f.set_float64, "fmi3SetFloat64"},
        {(void **)&f.set_int32, "fmi3SetInt32"}, {(void **)&f.set_uint64, "fmi3SetUInt64"},
        {(void **)&f.set_string, "fmi3SetString"}, {(void **)&f.get_float64, "fmi3GetFloat64"},
        {(void **)&f.get_state, "fmi3GetFMUState"}, {(void **)&f.set_state, "fmi3SetFMUState"},
        {(void **)&f.free_state, "fmi3FreeFMUState"},
    };
    if (!host_resolve(lib, syms, sizeof syms / sizeof syms[0]))
        return 2;
    long roundtrip = -1;
    const char *rows = NULL, *resources = NULL;
    for (int k = 5; k < argc; k++) {
        if (strncmp(argv[k], "out=", 4) == 0)
            host_parse_vrs(argv[k] + 4, outs.vr, &outs.n_vr, MAX_VR);
        else if (strncmp(argv[k], "in=", 3) == 0)
            host_parse_vrs(argv[k] + 3, ins.vr, &ins.n_vr, MAX_VR);
        else if (strncmp(argv[k], "nout=", 5) == 0)
            outs.n_values = (size_t)atol(argv[k] + 5);
        else if (strncmp(argv[k], "nin=", 4) == 0)
            ins.n_values = (size_t)atol(argv[k] + 4);
        else if (strncmp(argv[k], "rows=", 5) == 0)
            rows = argv[k] + 5;
        else if (strncmp(argv[k], "roundtrip=", 10) == 0)
            roundtrip = atol(argv[k] + 10);
        else if (strncmp(argv[k], "res=", 4) == 0)
            resources = argv[k] + 4;
    }
    if ((outs.n_vr > 0 && outs.n_values < outs.n_vr) || (ins.n_vr > 0 && (ins.n_values < ins.n_vr || !rows))) {
        fprintf(stderr, "out= needs nout=, in= needs nin= and rows=\n");
        return 2;
    }
    out_values = calloc(outs.n_values + 1, sizeof *out_values);
    if (out_values == NULL || (rows != NULL && !host_read_doubles(rows, &in_rows, &n_in_rows))) {
        fprintf(stderr, "cannot allocate or read %s\n", rows ? rows : "the outputs");
        return 2;
    }
    if (ins.n_vr > 0)
        n_in_rows /= (long)ins.n_values;
    fmi3Instance c = f.instantiate("host", token, resources, fmi3False, fmi3False, fmi3False, fmi3False, NULL, 0, NULL,
                                   logger, NULL);
    if (!c) {
        printf("STATUS fmi3InstantiateCoSimulation NULL\n");
        return 0;
    }
    int ok = 1, configure = 0;
    for (int k = 5; k < argc; k++)
        configure |= argv[k][0] == 'u' && strchr(argv[k], '=') != NULL;
    if (configure) {
        ok = report("fmi3EnterConfigurationMode", f.enter_config(c));
        for (int k = 5; ok && k < argc; k++) {
            char *eq = strchr(argv[k], '=');
            if (argv[k][0] != 'u' || !eq)
                continue;
            fmi3ValueReference vr = (fmi3ValueReference)strtoul(argv[k] + 1, NULL, 10);
            fmi3UInt64 v = strtoull(eq + 1, NULL, 10);
            ok = report("fmi3SetUInt64", f.set_uint64(c, &vr, 1, &v, 1));
        }
        ok = ok && report("fmi3ExitConfigurationMode", f.exit_config(c));
    }
    for (int k = 5; ok && k < argc; k++) {
        char *op = argv[k], *eq = strchr(op, '=');
        if (!eq || !(op[0] == 'r' || op[0] == 'i' || op[0] == 's') || !(op[1] >= '0' && op[1] <= '9'))
            continue;
        fmi3ValueReference vr = (fmi3ValueReference)strtoul(op + 1, NULL, 10);
        if (op[0] == 'r') {
            fmi3Float64 v = atof(eq + 1);
            ok = report("fmi3SetFloat64", f.set_float64(c, &vr, 1, &v, 1));
        } else if (op[0] == 'i') {
            fmi3Int32 v = atoi(eq + 1);
            ok = report("fmi3SetInt32", f.set_int32(c, &vr, 1, &v, 1));
        } else {
            fmi3String v = eq + 1;
            ok = report("fmi3SetString", f.set_string(c, &vr, 1, &v, 1));
        }
    }
    ok = ok && report("fmi3EnterInitializationMode", f.enter(c, fmi3False, 0.0, 0.0, fmi3False, 0.0));
    ok = ok && report("fmi3ExitInitializationMode", f.exit_init(c));
    ok = ok && print_outputs(&f, c, "OUT", 0);
    if (ok && roundtrip >= 0 && roundtrip <= n_steps) {
        fmi3FMUState s = NULL;
        ok = steps(&f, c, 0, roundtrip, h, "OUT");
        ok = ok && report("fmi3GetFMUState", f.get_state(c, &s));
        ok = ok && steps(&f, c, roundtrip, n_steps - roundtrip, h, "OUT");
        ok = ok && report("fmi3SetFMUState", f.set_state(c, s));
        ok = ok && steps(&f, c, roundtrip, n_steps - roundtrip, h, "AGAIN");
        if (s != NULL)
            report("fmi3FreeFMUState", f.free_state(c, &s));
    } else if (ok) {
        ok = steps(&f, c, 0, n_steps, h, "OUT");
    }
    if (ok)
        report("fmi3Terminate", f.terminate(c));
    f.free_instance(c);
    free(out_values);
    free(in_rows);
    printf("DONE %d\n", ok);
    return 0;
}
