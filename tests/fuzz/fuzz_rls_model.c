/* libFuzzer harness: the binary model-file reader (sarins_fmu/core/modelfile.c) and the RLS model-file
 * reader on top of it (sarins_fmu/core/rls.c, sarins_rls_from_model: what the DriftModelUpdater FMU runs on
 * its model_file), on arbitrary bytes.
 *
 * Each input is read twice: as it is, and as a copy whose total-size field and checksum are rewritten to
 * match (so the fuzzer reaches the header fields, the entries and the RLS checks behind the checksum).
 * Findings: any sanitizer report, or an accepted file whose parsed view points outside the input or whose
 * RLS state fails the core's own state check (abort()).
 *
 * Build and run with libFuzzer (clang), from the repository root:
 *   clang -std=c11 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all -Isarins_fmu/core \
 *       tests/fuzz/fuzz_rls_model.c sarins_fmu/core/modelfile.c sarins_fmu/core/rls.c \
 *       sarins_fmu/core/matrix.c sarins_fmu/core/report.c -lm -o fuzz_rls_model
 *   ./fuzz_rls_model -max_len=8192 -max_total_time=60 CORPUS_DIR
 * A seed corpus: files written by ForgettingRLS.save('x.smf') (tests/test_fuzz_model_file.py writes some).
 * Without libFuzzer (any C11 compiler, e.g. gcc with -fsanitize=address,undefined), add -DSARINS_FUZZ_MAIN:
 * the program then runs the harness once on each file named on its command line.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "modelfile.h"
#include "rls.h"

#define MAX_INPUT 8192

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void put_u32(unsigned char *p, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

static void read_one(const unsigned char *data, size_t size)
{
    static sarins_mf mf; /* 4 KiB: not on the fuzzer's stack */
    char msg[512];
    if (sarins_mf_parse(data, size, NULL, &mf, msg, sizeof msg) == SARINS_MF_OK) {
        if (mf.n_entries < 1 || mf.n_entries > SARINS_MF_MAX_ENTRIES)
            abort();
        volatile double sink = 0.0;
        for (uint32_t k = 0; k < mf.n_entries; k++) {
            const sarins_mf_entry *e = &mf.entries[k];
            if (e->offset < SARINS_MF_HEADER || e->offset > size || e->count > (size - e->offset) / 8)
                abort(); /* an accepted view must lie inside the input */
            for (uint64_t i = 0; i < e->count; i++)
                sink += e->dtype == SARINS_MF_I64 ? (double)sarins_mf_i64(data, e, i) : sarins_mf_f64(data, e, i);
            if (sarins_mf_find(&mf, e->name) != e)
                abort();
        }
        (void)sink;
    }
    sarins_rls s;
    if (sarins_rls_from_model(data, size, &s, msg, sizeof msg) == SARINS_RLS_OK) {
        if (sarins_rls_check(&s, msg, sizeof msg) != SARINS_RLS_OK)
            abort(); /* an accepted model must be a valid state */
        (void)sarins_rls_update(&s, 25.0, 1e-8, s.time + 86400.0, msg, sizeof msg);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static unsigned char copy[MAX_INPUT];
    read_one(data, size);
    if (size >= SARINS_MF_MIN_SIZE && size <= MAX_INPUT) {
        memcpy(copy, data, size);
        uint64_t total = (uint64_t)size;
        for (int i = 0; i < 8; i++)
            copy[72 + i] = (unsigned char)(total >> (8 * i));
        put_u32(copy + size - 4, sarins_mf_crc32(copy, size - 4));
        read_one(copy, size);
    }
    return 0;
}

#ifdef SARINS_FUZZ_MAIN
int main(int argc, char **argv)
{
    static unsigned char buf[MAX_INPUT + 1];
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
