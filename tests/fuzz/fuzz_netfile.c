/* libFuzzer harness of the binary model file reader and the model builders (sarins_fmu/core/netfile.c,
 * netmodel.c): any bytes are parsed; a file that parses is built into an axial identifier and a
 * compensator, each evaluated once, then released.  Nothing may crash, leak or read outside the buffer.
 *
 * Build and run (from the repository root; seeds: any *.bin model files, e.g. an FMU's resources):
 * (FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION skips the checksum so that mutations reach the arrays):
 *   clang -std=c11 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined \
 *       -DFUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION \
 *       -Isarins_fmu/core tests/fuzz/fuzz_netfile.c sarins_fmu/core/netfile.c sarins_fmu/core/netmodel.c \
 * sarins_fmu/core/nets.c sarins_fmu/core/smath.c -o /tmp/fuzz_netfile
 *   /tmp/fuzz_netfile -max_total_time=60 -max_len=65536 CORPUS_DIR
 */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "netfile.h"
#include "netmodel.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    sarins_netfile f;
    char msg[256];
    if (sarins_netfile_parse(data, size, &f, msg, sizeof msg) != SARINS_NETFILE_OK)
        return 0;
    sarins_axial a;
    if (sarins_axial_build(&a, &f, msg, sizeof msg) == SARINS_NETFILE_OK) {
        double drift = 0.0;
        (void)sarins_axial_drift(&a, 1e-5, 20.0, 3.0, &drift);
    }
    sarins_axial_release(&a);
    sarins_comp c;
    if (sarins_comp_build(&c, &f, msg, sizeof msg) == SARINS_NETFILE_OK) {
        static const double x[SARINS_COMP_N_IN] = {0.01, -0.02, 0.03, 0.1, -0.2, 9.8, 25.0};
        double state[SARINS_COMP_MAX_STATE], y[SARINS_COMP_N_OUT];
        memset(state, 0, sizeof state);
        (void)sarins_comp_run(&c, state, 1, x, y, NULL);
        sarins_comp_release(&c);
    }
    return 0;
}
