/* libFuzzer harness of the IMULog FMU's log reader (fmus/c/imu_log/model.c: read_file, the format and header
 * checks, the block parser and its strtod fallback, the sample checks), FMI 2.0, linked with the FMU's sources/.
 * Each input is written as the log file (path: $FUZZ_LOG_PATH, else fuzz_imu_log.csv in the working folder),
 * the FMU is instantiated with log_file set to it and initialised; when that succeeds it is stepped with the
 * log's own interval over the whole log and one step past it.  Findings: any sanitizer report, a log the FMU
 * accepted whose log_step is not positive and finite, or a step returning OK with a non-finite output
 * (abort()).
 *
 * Build (from the IMULog FMU's sources/ folder):
 *   clang -std=c11 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all -I. \
 *       tests/fuzz/fuzz_imu_log_file.c *.c -o fuzz_log_file
 *   ./fuzz_log_file -max_total_time=60 -max_len=8192 CORPUS_DIR
 * Without libFuzzer (any C11 compiler) add -DSARINS_FUZZ_MAIN: `fuzz_log_file FILE...` runs the harness once
 * on each file and prints ACCEPTED or REFUSED with its name.  tests/test_fuzz_imu_log_file.py does both.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "model.h"
#include "variables.h"

#define MAX_STEPS 4096 /* steps run on an accepted log (a longer log is played this far) */
#define MAX_OUT 64     /* Real outputs read after each step */

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...)
{
    (void)env; (void)name; (void)status; (void)category; (void)message;
}
static const fmi2CallbackFunctions CALLBACKS = {logger, calloc, free, NULL, NULL};

static fmi2ValueReference vr_of(const char *name)
{
    for (size_t k = 0; k < SARINS_TABLE.n_vars; k++)
        if (strcmp(SARINS_TABLE.vars[k].name, name) == 0)
            return SARINS_TABLE.vars[k].vr;
    abort(); /* the harness and the FMU disagree */
}

static const char *log_path(void)
{
    const char *path = getenv("FUZZ_LOG_PATH");
    return path != NULL && path[0] != '\0' ? path : "fuzz_imu_log.csv";
}

/* Step the accepted log through its end and one step past it; abort() on an OK step with a non-finite output. */
static void play(fmi2Component c)
{
    fmi2ValueReference vr_h = vr_of("log_step");
    fmi2Real h = 0.0;
    if (fmi2GetReal(c, &vr_h, 1, &h) != fmi2OK || !(h > 0.0 && h < 1e300))
        abort();
    fmi2ValueReference outs[MAX_OUT];
    size_t n_out = 0;
    for (size_t k = 0; k < SARINS_TABLE.n_vars && n_out < MAX_OUT; k++)
        if (SARINS_TABLE.vars[k].type == SARINS_REAL && SARINS_TABLE.vars[k].causality == SARINS_OUTPUT)
            outs[n_out++] = SARINS_TABLE.vars[k].vr;
    fmi2Real values[MAX_OUT];
    for (int k = 0; k < MAX_STEPS; k++) {
        fmi2Status status = fmi2DoStep(c, (double)k * h, h, fmi2True);
        if (status != fmi2OK)
            return; /* past the end of the log: an error naming it */
        if (fmi2GetReal(c, outs, n_out, values) != fmi2OK)
            abort();
        for (size_t j = 0; j < n_out; j++)
            if (!(values[j] - values[j] == 0.0))
                abort();
    }
}

/* 1 when the FMU accepted the log (and it was played), else 0. */
static int run_one(const uint8_t *data, size_t size)
{
    const char *path = log_path();
    FILE *f = fopen(path, "wb");
    if (f == NULL)
        abort();
    if (size > 0 && fwrite(data, 1, size, f) != size)
        abort();
    if (fclose(f) != 0)
        abort();
    fmi2Component c = fmi2Instantiate("fuzz", fmi2CoSimulation, SARINS_TABLE.guid, NULL, &CALLBACKS, fmi2False,
                                      fmi2False);
    if (c == NULL)
        abort();
    fmi2ValueReference vr_file = vr_of("log_file");
    fmi2String value = path;
    if (fmi2SetString(c, &vr_file, 1, &value) != fmi2OK
        || fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK)
        abort();
    int accepted = fmi2EnterInitializationMode(c) == fmi2OK && fmi2ExitInitializationMode(c) == fmi2OK;
    if (accepted)
        play(c);
    fmi2FreeInstance(c);
    return accepted;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    (void)run_one(data, size);
    return 0;
}

#ifdef SARINS_FUZZ_MAIN
int main(int argc, char **argv)
{
    for (int k = 1; k < argc; k++) {
        FILE *f = fopen(argv[k], "rb");
        if (f == NULL) {
            fprintf(stderr, "cannot open %s\n", argv[k]);
            return 2;
        }
        static uint8_t buf[1 << 20];
        size_t n = fread(buf, 1, sizeof buf, f);
        fclose(f);
        printf("%s %s\n", run_one(buf, n) ? "ACCEPTED" : "REFUSED", argv[k]);
    }
    return 0;
}
#endif
