/* libFuzzer harness of the RLS model-file reader (sarins_fmu/core/rls.c, sarins_rls_from_model: what the
 * DriftModelUpdater FMU runs on its model_file) over the core's binary model file container
 * (sarins_fmu/core/netfile.c), on arbitrary bytes.  Findings: any sanitizer report, or an accepted file
 * whose RLS state fails the core's own state check, or an accepted update that leaves a state failing it
 * (abort()).
 *
 * Build and run with libFuzzer (clang), from the repository root
 * (FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION skips the container's checksum so that mutations reach the arrays):
 *   clang -std=c11 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all \
 *       -DFUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION -Isarins_fmu/core tests/fuzz/fuzz_rls_model.c \
 *       sarins_fmu/core/rls.c sarins_fmu/core/netfile.c sarins_fmu/core/matrix.c sarins_fmu/core/report.c \
 *       sarins_fmu/core/smath.c -o /tmp/fuzz_rls_model
 *   /tmp/fuzz_rls_model -max_len=8192 -max_total_time=60 CORPUS_DIR
 * Seeds: files written by ForgettingRLS.export_binary (tests/test_fuzz_model_file.py writes some).  Without
 * libFuzzer (any C11 compiler, e.g. gcc -fsanitize=address,undefined), add -DSARINS_FUZZ_MAIN: the program
 * then runs the harness once on each file named on its command line.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "rls.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char msg[512];
    sarins_rls s;
    if (sarins_rls_from_model(data, size, &s, msg, sizeof msg) != SARINS_RLS_OK)
        return 0;
    if (sarins_rls_check(&s, msg, sizeof msg) != SARINS_RLS_OK)
        abort(); /* an accepted model must be a valid state */
    if (sarins_rls_update(&s, 25.0, 1e-8, s.time + 86400.0, msg, sizeof msg) == SARINS_RLS_OK
        && sarins_rls_check(&s, msg, sizeof msg) != SARINS_RLS_OK)
        abort(); /* an update the core accepts keeps a valid state */
    return 0;
}

#ifdef SARINS_FUZZ_MAIN
int main(int argc, char **argv)
{
    static unsigned char buf[SARINS_RLS_FILE_MAX * 2];
    for (int k = 1; k < argc; k++) {
        FILE *f = fopen(argv[k], "rb");
        if (f == NULL) {
            fprintf(stderr, "cannot open %s\n", argv[k]);
            return 2;
        }
        size_t n = fread(buf, 1, sizeof buf, f);
        fclose(f);
        LLVMFuzzerTestOneInput(buf, n);
    }
    printf("ran %d inputs\n", argc - 1);
    return 0;
}
#endif
