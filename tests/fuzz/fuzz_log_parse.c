/* libFuzzer harness of the text-log block parser (sarins_fmu/core/log_parse.c, sarins_log_parse_block: what
 * sarins_fmu.imu_log runs on every block of sample lines) on arbitrary bytes.  The first byte picks the number
 * of columns (1..8), the line end (LF/CRLF) and the line limit; the rest is the block.  Findings: any sanitizer
 * report, more rows than the buffer holds, or a taken block with a value that is not the correctly rounded
 * double of its field (abort()).  The reference is slow and exact, independent of the parser: the field's
 * decimal digits as a big integer D 10^q, compared with big integers against the two midpoints between the
 * returned double and its neighbours (ties to even); no strtod.
 *
 *   clang -std=c11 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all -Isarins_fmu/core \
 *       tests/fuzz/fuzz_log_parse.c sarins_fmu/core/log_parse.c -o /tmp/fuzz_log_parse
 *   /tmp/fuzz_log_parse -max_len=4096 -max_total_time=60 tests/fuzz/corpus_log_parse
 * Without libFuzzer (gcc -fsanitize=address,undefined), add -DSARINS_FUZZ_MAIN: the program then runs the
 * harness on each file named on its command line.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include <string.h>

#include "log_parse.h"

/* ---------------------------------------------------------------- the exact reference: big unsigned integers */

#define BN_LIMBS 192 /* 6144 bits: 10^60 5^420 2^1600 fits */

typedef struct {
    uint32_t d[BN_LIMBS]; /* least significant first */
    int n;                /* limbs in use; 0 for zero */
} bignum;

static void bn_set(bignum *b, uint64_t v) {
    b->n = 0;
    while (v) {
        b->d[b->n++] = (uint32_t)v;
        v >>= 32;
    }
}

static void bn_mul_add(bignum *b, uint32_t m, uint32_t a) { /* b = b m + a */
    uint64_t carry = a;
    for (int i = 0; i < b->n; i++) {
        uint64_t t = (uint64_t)b->d[i] * m + carry;
        b->d[i] = (uint32_t)t;
        carry = t >> 32;
    }
    if (carry) {
        if (b->n == BN_LIMBS) abort();
        b->d[b->n++] = (uint32_t)carry;
    }
}

static void bn_shl(bignum *b, int s) {
    if (b->n == 0) return;
    int limbs = s / 32, bits = s % 32;
    if (b->n + limbs + 1 > BN_LIMBS) abort();
    uint32_t top = 0;
    b->d[b->n] = 0;
    for (int i = b->n; i >= 0; i--) {
        uint32_t lo = i > 0 ? b->d[i - 1] : 0;
        uint32_t v = bits ? (b->d[i] << bits) | (lo >> (32 - bits)) : b->d[i];
        if (i == b->n) top = v;
        b->d[i + limbs] = v;
    }
    for (int i = 0; i < limbs; i++) b->d[i] = 0;
    b->n += limbs + (top != 0);
}

static int bn_cmp(const bignum *a, const bignum *b) {
    if (a->n != b->n) return a->n < b->n ? -1 : 1;
    for (int i = a->n - 1; i >= 0; i--)
        if (a->d[i] != b->d[i]) return a->d[i] < b->d[i] ? -1 : 1;
    return 0;
}

/* sign of D 10^q - C 2^j (D > 0 from its decimal digits, C > 0) */
static int cmp_decimal(const char *digits, int nd, int q, uint64_t c, int j) {
    static bignum lhs, rhs; /* static: 768 bytes each, off the fuzzer's stack */
    bn_set(&lhs, 0);
    for (int i = 0; i < nd; i++) {
        if (lhs.n == 0) bn_set(&lhs, (uint64_t)(digits[i] - '0'));
        else bn_mul_add(&lhs, 10, (uint32_t)(digits[i] - '0'));
    }
    bn_set(&rhs, c);
    for (int i = 0; i < (q > 0 ? q : -q); i++) bn_mul_add(q > 0 ? &lhs : &rhs, 5, 0); /* D 5^q 2^q vs C 2^j */
    if (q > j) bn_shl(&lhs, q - j);
    else bn_shl(&rhs, j - q);
    return bn_cmp(&lhs, &rhs);
}

/* 1 when v is float()'s value of the field f[0..n) (blanks around, [+-], digits, '.', exponent) */
static int exact_reference(const char *f, int64_t n, double v) {
    int64_t i = 0;
    while (i < n && (f[i] == ' ' || f[i] == '\t')) i++;
    while (n > i && (f[n - 1] == ' ' || f[n - 1] == '\t')) n--;
    int negative = 0;
    if (i < n && (f[i] == '+' || f[i] == '-')) negative = f[i++] == '-';
    static char digits[4096];
    int nd = 0, q = 0, seen = 0;
    for (int frac = 0; i < n && ((f[i] >= '0' && f[i] <= '9') || (f[i] == '.' && !frac)); i++) {
        if (f[i] == '.') {
            frac = 1;
            continue;
        }
        seen = 1;
        if (nd || f[i] != '0') digits[nd++] = f[i];
        q -= frac;
    }
    if (!seen) return 0;
    if (i < n && (f[i] == 'e' || f[i] == 'E')) {
        i++;
        int eneg = 0, e = 0, ed = 0;
        if (i < n && (f[i] == '+' || f[i] == '-')) eneg = f[i++] == '-';
        for (; i < n && f[i] >= '0' && f[i] <= '9'; i++, ed++)
            if (e < 100000) e = e * 10 + (f[i] - '0');
        if (!ed) return 0;
        q += eneg ? -e : e;
    }
    if (i != n || nd > 60) return 0;
    if ((signbit(v) != 0) != negative || isnan(v) || isinf(v)) return 0;
    double a = negative ? -v : v;
    if (nd == 0) return a == 0.0;
    if (q + nd > 330) return 0; /* >= 10^329: would overflow */
    if (q + nd < -400) return a == 0.0; /* < 10^-400 */
    uint64_t bits;
    memcpy(&bits, &a, sizeof bits);
    int field = (int)(bits >> 52);
    uint64_t m = bits & ((UINT64_C(1) << 52) - 1u);
    int k = -1074;
    if (field) {
        m |= UINT64_C(1) << 52;
        k = field - 1075;
    }
    int even = !(m & 1u);
    /* above the lower midpoint (m - 1/2) 2^k, or (m - 1/4) 2^k below a power of two; at it only when even */
    int low = m == 0 ? 1 /* zero: no lower bound */
              : (m == UINT64_C(1) << 52 && field > 1) ? cmp_decimal(digits, nd, q, 4 * m - 1, k - 2)
                                                      : cmp_decimal(digits, nd, q, 2 * m - 1, k - 1);
    int high = cmp_decimal(digits, nd, q, 2 * m + 1, k - 1); /* below the upper midpoint (m + 1/2) 2^k */
    return (low > 0 || (low == 0 && even)) && (high < 0 || (high == 0 && even));
}

/* every field of a taken block against the reference */
static void check_values(const char *buf, int64_t len, int32_t n_cols, int32_t crlf, const double *out, int64_t rows) {
    int64_t row = 0, start = 0;
    while (start < len) {
        int64_t end = start;
        while (end < len && buf[end] != '\n') end++;
        int64_t body = end < len && crlf ? end - 1 : end;
        int32_t col = 0;
        for (int64_t i = start, f = start; i <= body; i++) {
            if (i == body || buf[i] == ',') {
                if (row >= rows || !exact_reference(buf + f, i - f, out[row * n_cols + col])) abort();
                col++;
                f = i + 1;
            }
        }
        row++;
        start = end + 1;
    }
    if (row != rows) abort();
}

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
    if (rows > cap) abort();
    if (rows >= 0) check_values((const char *)data + 1, len, n_cols, crlf, out, rows);
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
