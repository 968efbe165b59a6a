/* libFuzzer harness of the native glue's FMU-state reader (fmus/c/glue_core.c: DeSerializeFMUstate, then
 * SetFMUstate and steps from the state), FMI 2.0 or 3.0 (-DFMI3), linked with one native FMU's sources/
 * (the glue, model.c, variables.h, the core).  Findings: any sanitizer report, or a state the FMU accepted
 * from which a step returns OK with a non-finite output (abort()).
 *
 * Build (from an FMU's sources/ folder; FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION skips the state checksum so
 * that mutations reach the fields behind it):
 *   clang -std=c11 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all \
 *       -DFUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION [-DFMI3] -I. tests/fuzz/fuzz_fmu_state.c *.c -o fuzz_state
 *   ./fuzz_state -max_total_time=60 CORPUS_DIR
 * A model that needs files (a model file in resources/, a log): the environment names them, read at every
 * instantiation: SARINS_FUZZ_RESOURCES the FMU's unzipped resources folder (an absolute path; FMI 2.0 gets it
 * as a file: URI), SARINS_FUZZ_PARAMS lines "name=value" set (by the variable's type) before initialisation.
 * Seeds: states of the model itself; without libFuzzer add -DSARINS_FUZZ_MAIN: `fuzz_state --seeds DIR`
 * writes them (after initialisation, after 3 and 20 steps of 1 s), `fuzz_state FILE...` runs the harness
 * once on each file.  tests/test_fuzz_fmu_state.py does both.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "model.h"
#include "variables.h"

/* the resources folder (SARINS_FUZZ_RESOURCES) as FMI 2.0's file: URI (uri = 1) or FMI 3.0's path, or NULL */
static const char *resources(int uri)
{
    static char buf[4200];
    const char *dir = getenv("SARINS_FUZZ_RESOURCES");
    if (dir == NULL || dir[0] == '\0')
        return NULL;
    snprintf(buf, sizeof buf, "%s%s", uri ? "file://" : "", dir);
    return buf;
}

#ifdef FMI3
#include "fmi3Functions.h"
typedef fmi3Instance inst;
typedef fmi3FMUState fstate;
static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message)
{
    (void)env; (void)status; (void)category; (void)message;
}
#define SETR(c, vr, x) fmi3SetFloat64((c), &(vr), 1, &(x), 1)
#define SETI(c, vr, x) fmi3SetInt32((c), &(vr), 1, &(x), 1)
#define SETB(c, vr, x) fmi3SetBoolean((c), &(vr), 1, &(x), 1)
#define SETS(c, vr, x) fmi3SetString((c), &(vr), 1, &(x), 1)
typedef fmi3Int32 int_t;
typedef fmi3Boolean bool_t;
static int set_params(inst c);
static inst start(void)
{
    inst c = fmi3InstantiateCoSimulation("fuzz", SARINS_TABLE.guid, resources(0), fmi3False, fmi3False, fmi3False,
                                         fmi3False, NULL, 0, NULL, logger, NULL);
    if (c == NULL || set_params(c) != 0 || fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0) != fmi3OK
        || fmi3ExitInitializationMode(c) != fmi3OK)
        abort(); /* the model's defaults must run */
    return c;
}
#define DESER(c, d, n, s) fmi3DeserializeFMUState((c), (const fmi3Byte *)(d), (n), (s))
#define SET(c, s) fmi3SetFMUState((c), (s))
#define GET(c, s) fmi3GetFMUState((c), (s))
#define FREE(c, s) fmi3FreeFMUState((c), (s))
#define SIZE(c, s, n) fmi3SerializedFMUStateSize((c), (s), (n))
#define SER(c, s, b, n) fmi3SerializeFMUState((c), (s), (fmi3Byte *)(b), (n))
#define STEP(c, t, h) fmi3DoStep((c), (t), (h), fmi3True, &event, &terminate, &early, &last)
#define STEP_DECL fmi3Boolean event, terminate, early; fmi3Float64 last
#define GETR(c, vr, x) fmi3GetFloat64((c), &(vr), 1, &(x), 1)
#define FREE_INSTANCE(c) fmi3FreeInstance(c)
#else
#include "fmi2Functions.h"
typedef fmi2Component inst;
typedef fmi2FMUstate fstate;
static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...)
{
    (void)env; (void)name; (void)status; (void)category; (void)message;
}
static const fmi2CallbackFunctions CALLBACKS = {logger, calloc, free, NULL, NULL};
#define SETR(c, vr, x) fmi2SetReal((c), &(vr), 1, &(x))
#define SETI(c, vr, x) fmi2SetInteger((c), &(vr), 1, &(x))
#define SETB(c, vr, x) fmi2SetBoolean((c), &(vr), 1, &(x))
#define SETS(c, vr, x) fmi2SetString((c), &(vr), 1, &(x))
typedef fmi2Integer int_t;
typedef fmi2Boolean bool_t;
static int set_params(inst c);
static inst start(void)
{
    inst c = fmi2Instantiate("fuzz", fmi2CoSimulation, SARINS_TABLE.guid, resources(1), &CALLBACKS, fmi2False,
                             fmi2False);
    if (c == NULL || set_params(c) != 0 || fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK
        || fmi2EnterInitializationMode(c) != fmi2OK || fmi2ExitInitializationMode(c) != fmi2OK)
        abort();
    return c;
}
#define DESER(c, d, n, s) fmi2DeSerializeFMUstate((c), (const fmi2Byte *)(d), (n), (s))
#define SET(c, s) fmi2SetFMUstate((c), (s))
#define GET(c, s) fmi2GetFMUstate((c), (s))
#define FREE(c, s) fmi2FreeFMUstate((c), (s))
#define SIZE(c, s, n) fmi2SerializedFMUstateSize((c), (s), (n))
#define SER(c, s, b, n) fmi2SerializeFMUstate((c), (s), (fmi2Byte *)(b), (n))
#define STEP(c, t, h) fmi2DoStep((c), (t), (h), fmi2True)
#define STEP_DECL (void)0
#define GETR(c, vr, x) fmi2GetReal((c), &(vr), 1, &(x))
#define FREE_INSTANCE(c) fmi2FreeInstance(c)
#endif

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* SARINS_FUZZ_PARAMS: "name=value" lines, each set by its variable's type; 0, or 1 on an unknown name or a
 * refused value */
static int set_params(inst c)
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
        const sarins_var *var = NULL;
        for (size_t v = 0; v < SARINS_TABLE.n_vars && var == NULL; v++)
            if (strcmp(SARINS_TABLE.vars[v].name, line) == 0)
                var = &SARINS_TABLE.vars[v];
        if (var == NULL)
            return 1;
        unsigned vr = var->vr;
        double r = strtod(value, NULL);
        int_t i = (int_t)strtol(value, NULL, 10);
        bool_t b = (bool_t)(strtol(value, NULL, 10) != 0);
        int rc = var->type == SARINS_REAL ? (int)SETR(c, vr, r) : var->type == SARINS_INTEGER ? (int)SETI(c, vr, i)
               : var->type == SARINS_BOOLEAN ? (int)SETB(c, vr, b) : (int)SETS(c, vr, value);
        if (rc != 0)
            return 1;
        p = end ? end + 1 : p + n;
    }
    return 0;
}

/* the blob's next communication point (payload offset 8) or its start time, so that steps can continue */
static double blob_time(const uint8_t *data, size_t size)
{
    double t = 0.0;
    if (size >= 104 + 24) {
        int32_t have_time;
        memcpy(&have_time, data + 104 + 4, 4);
        memcpy(&t, data + 104 + (have_time ? 8 : 16), 8);
    }
    return t;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    inst c = start();
    fstate s = NULL;
    STEP_DECL;
    if (DESER(c, data, size, &s) == 0) {
        if (SET(c, s) == 0) {
            double t = blob_time(data, size);
            for (int k = 0; k < 3; k++, t += 1.0) {
                if (STEP(c, t, 1.0) != 0)
                    break;
                for (size_t v = 0; v < SARINS_TABLE.n_vars; v++) {
                    const sarins_var *var = &SARINS_TABLE.vars[v];
                    double x = 0.0;
                    if (var->type == SARINS_REAL && var->causality == SARINS_OUTPUT && var->dim < 0
                        && GETR(c, var->vr, x) == 0 && !(x - x == 0.0))
                        abort(); /* a non-finite output returned with OK */
                }
            }
        }
        FREE(c, &s);
    }
    FREE_INSTANCE(c);
    return 0;
}

#ifdef SARINS_FUZZ_MAIN
static int write_seed(inst c, const char *dir, int k)
{
    fstate s = NULL;
    size_t n = 0;
    static unsigned char buf[1 << 22];
    if (GET(c, &s) != 0 || SIZE(c, s, &n) != 0 || n > sizeof buf || SER(c, s, buf, n) != 0)
        return 2;
    FREE(c, &s);
    char path[4096];
    snprintf(path, sizeof path, "%s/seed%d", dir, k);
    FILE *f = fopen(path, "wb");
    if (f == NULL || fwrite(buf, 1, n, f) != n)
        return 2;
    fclose(f);
    return 0;
}

int main(int argc, char **argv)
{
    if (argc == 3 && strcmp(argv[1], "--seeds") == 0) {
        inst c = start();
        STEP_DECL;
        int rc = write_seed(c, argv[2], 0);
        for (int k = 0; k < 20 && rc == 0; k++) {
            if (STEP(c, (double)k, 1.0) > 1)
                break; /* a model that needs inputs: the states before */
            if (k == 2 || k == 19)
                rc = write_seed(c, argv[2], k + 1);
        }
        FREE_INSTANCE(c);
        return rc;
    }
    static unsigned char buf[1 << 22];
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
