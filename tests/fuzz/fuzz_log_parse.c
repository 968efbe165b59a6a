/* libFuzzer harness of the text-log block parser (sarins_fmu/core/log_parse.c, sarins_log_parse_block: what
 * sarins_fmu.imu_log runs on every block of sample lines) on arbitrary bytes.  The first byte picks the number
 * of columns (1..8), the line end (LF/CRLF) and the line limit; the rest is the block.  Findings: any sanitizer
 * report, or more rows than the buffer holds (abort()).
 *
 *   clang -std=c11 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all -Isarins_fmu/core \
 *       tests/fuzz/fuzz_log_parse.c sarins_fmu/core/log_parse.c -o /tmp/fuzz_log_parse
 *   /tmp/fuzz_log_parse -max_len=4096 -max_total_time=60
 * Without libFuzzer (gcc -fsanitize=address,undefined), add -DSARINS_FUZZ_MAIN: the program then runs the
 * harness on each file named on its command line.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "log_parse.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1) return 0;
    int32_t n_cols = 1 + (data[0] & 7);
    int32_t crlf = (data[0] >> 3) & 1;
    int32_t max_line = (data[0] >> 4) * 64;
    int64_t len = (int64_t)size - 1;
    int64_t cap = len / (2 * n_cols) + 1;
    double *out = malloc((size_t)(cap * n_cols) * sizeof *out);
    if (out == NULL) return 0;
    int64_t rows = sarins_log_parse_block((const char *)data + 1, len, n_cols, crlf, max_line, out, cap);
    free(out);
    if (rows > cap) abort();
    return 0;
}

#ifdef SARINS_FUZZ_MAIN
int main(int argc, char **argv)
{
    for (int i = 1; i < argc; i++) {
        FILE *f = fopen(argv[i], "rb");
        if (f == NULL) continue;
        static uint8_t buf[1 << 16];
        size_t n = fread(buf, 1, sizeof buf, f);
        fclose(f);
        LLVMFuzzerTestOneInput(buf, n);
    }
    return 0;
}
#endif
