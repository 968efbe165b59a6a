/* libFuzzer harness of the fmuResourceLocation parser (fmus/c/sarins_uri.h, sarins_uri_to_path: what every
 * native FMU's glue runs on the URI a host hands it) on arbitrary bytes.  The first byte picks the output
 * buffer length (0..254, or 4096 for 255); the rest, NUL-terminated, is the URI.  The buffer is allocated
 * to exactly that length, so that AddressSanitizer sees any write past it.  Findings: any sanitizer report,
 * or a broken invariant (abort()):
 *   - the output is NUL-terminated within the buffer (whenever the buffer has a byte);
 *   - SARINS_URI_OK implies an absolute path: it starts with '/' (built with -D_WIN32: '/' or a drive
 *     letter and ':');
 *   - any error implies the output is "".
 *
 *   clang -std=c11 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all -Ifmus/c \
 *       tests/fuzz/fuzz_uri.c -o /tmp/fuzz_uri           (and again with -D_WIN32: the drive-letter branch)
 *   /tmp/fuzz_uri -max_len=4096 -max_total_time=60 tests/fuzz/corpus_uri
 * Without libFuzzer (gcc -fsanitize=address,undefined), add -DSARINS_FUZZ_MAIN: the program then runs the
 * harness on each file named on its command line.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sarins_uri.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static int is_letter(char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z'); }

static int absolute(const char *path)
{
    if (path[0] == '/') return 1;
#ifdef _WIN32
    if (is_letter(path[0]) && path[1] == ':') return 1;
#else
    (void)is_letter;
#endif
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1) return 0;
    size_t outlen = data[0] == 255 ? 4096 : data[0];
    char *uri = malloc(size);             /* size - 1 bytes of URI and its NUL */
    char *out = malloc(outlen ? outlen : 1);
    if (uri == NULL || out == NULL) {
        free(uri);
        free(out);
        return 0;
    }
    memcpy(uri, data + 1, size - 1);
    uri[size - 1] = '\0';
    memset(out, 'x', outlen ? outlen : 1);
    int code = sarins_uri_to_path(uri, out, outlen);
    if (outlen > 0) {
        if (memchr(out, '\0', outlen) == NULL) abort();
        if (code == SARINS_URI_OK && !absolute(out)) abort();
        if (code != SARINS_URI_OK && out[0] != '\0') abort();
    } else if (code == SARINS_URI_OK) {
        abort();                          /* no byte for even the NUL: never OK */
    }
    if (code < SARINS_URI_OK || code > SARINS_URI_EMPTY) abort();
    free(uri);
    free(out);
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
