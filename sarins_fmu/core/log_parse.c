/* log_parse.c: see log_parse.h. */
#include "smath.h" /* first: the floating-point contract, each operation rounded as written; no -ffast-math */
#include "log_parse.h"

#include <stddef.h>
#include <string.h> /* memchr */

#include "log_parse_tables.h"

/* 10^0 .. 10^22: every one exact in binary64 */
static const double POW10[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
                                 1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
#define MAX_EXACT_MANTISSA 9007199254740992ULL /* 2^53 */
#define MAX_DIGITS 19                           /* significant digits held by a uint64_t: 10^19 - 1 < 2^64 */

/* a b = *hi 2^64 + *lo, exactly */
#if defined(__SIZEOF_INT128__) && !defined(SARINS_LOG_PARSE_PORTABLE)
__extension__ typedef unsigned __int128 lp_u128;
static void mul_64x64(uint64_t a, uint64_t b, uint64_t *hi, uint64_t *lo) {
    lp_u128 p = (lp_u128)a * b;
    *hi = (uint64_t)(p >> 64);
    *lo = (uint64_t)p;
}
#else
static void mul_64x64(uint64_t a, uint64_t b, uint64_t *hi, uint64_t *lo) {
    uint64_t a0 = a & 0xffffffffu, a1 = a >> 32, b0 = b & 0xffffffffu, b1 = b >> 32;
    uint64_t p00 = a0 * b0, p01 = a0 * b1, p10 = a1 * b0, p11 = a1 * b1;
    uint64_t mid = (p00 >> 32) + (p01 & 0xffffffffu) + (p10 & 0xffffffffu); /* < 3 2^32 */
    *lo = (mid << 32) | (p00 & 0xffffffffu);
    *hi = p11 + (p01 >> 32) + (p10 >> 32) + (mid >> 32);
}
#endif

/* leading zero bits of x != 0 */
static int clz64(uint64_t x) {
#if defined(__GNUC__) && !defined(SARINS_LOG_PARSE_PORTABLE)
    return __builtin_clzll(x);
#else
    int n = 0;
    while (!(x & 0x8000000000000000u)) {
        x <<= 1;
        n++;
    }
    return n;
#endif
}

/* The double nearest N 2^E, ties to even (IEEE round to nearest, subnormals included), as its bits in *bits;
 * 0 when it overflows.  N = n[2] 2^128 + n[1] 2^64 + n[0] with 2^190 <= N < 2^192.  The kept bits m are those
 * of N from bit `shift` up: shift = bitlength(N) - 53 for a normal result, or the shift that puts the last
 * kept bit at 2^-1074 (subnormal), whichever is larger; shift >= 137, so m, the rounding bit and part of the
 * rest lie in n[2]. */
static int round_n_192(const uint64_t n[3], int32_t e2, uint64_t *bits) {
    int32_t len = 192 - clz64(n[2]);
    int32_t shift = len - 53;
    if (shift < -1074 - e2) shift = -1074 - e2;
    int32_t s = shift - 128; /* >= 9 */
    uint64_t m, half, rest;
    if (s > 64) { /* N < 2^(shift - 1): below half the smallest step, rounds to zero */
        m = 0;
        half = 0;
        rest = 0;
    } else if (s == 64) {
        m = 0;
        half = n[2] >> 63;
        rest = (n[2] << 1) | n[1] | n[0];
    } else {
        m = n[2] >> s;
        half = (n[2] >> (s - 1)) & 1u;
        rest = (n[2] & ((UINT64_C(1) << (s - 1)) - 1u)) | n[1] | n[0];
    }
    if (half && (rest || (m & 1u))) m++;
    int32_t be = e2 + shift + 52; /* the value is m 2^(be - 52); normal: 2^52 <= m < 2^53 */
    if (m == UINT64_C(1) << 53) {
        m >>= 1;
        be++;
    }
    if (be > 1023) return 0;
    /* normal: biased exponent be + 1023 and m's leading bit (2^52) adds the one; subnormal: be = -1022, m < 2^52
     * (m = 2^52 is the smallest normal, encoded the same way) */
    *bits = ((uint64_t)(be + 1022) << 52) + m;
    return 1;
}

/* 1 when N + w rounds to the same double as N (bits), N = n[2] n[1] n[0] as in round_n_192, w < 2^64 */
static int same_rounding(const uint64_t n[3], uint64_t w, int32_t e2, uint64_t bits) {
    uint64_t u[3];
    u[0] = n[0] + w;
    u[1] = n[1] + (u[0] < w);
    u[2] = n[2] + (u[1] < n[1]); /* N + w < 2^192 (N <= (2^64 - 1)(2^128 - 1)) */
    /* the usual case: the same top word and a nonzero rest below it at both ends (N + w can clear n[1] n[0] only
     * by a carry into n[2]), so the same kept bits, rounding bit and sticky bit */
    if (u[2] == n[2] && (n[1] | n[0])) return 1;
    uint64_t upper;
    return round_n_192(u, e2, &upper) && upper == bits;
}

/* w 10^q correctly rounded in *bits when q < 0 and 5^-q divides w: then w 10^q = (w / 5^-q) 2^q exactly, an
 * integer below 2^64 times a power of two (the exact ties between two doubles are all of this kind).  0 if not. */
static int exact_quotient(uint64_t w, int64_t q, uint64_t *bits) {
    if (q >= 0 || q < -27) return 0; /* 5^28 > 2^64 > w */
    uint64_t p = 1;
    for (int64_t k = 0; k < -q; k++) p *= 5u;
    if (w % p) return 0;
    uint64_t v = w / p;
    int l = clz64(v);
    uint64_t n[3] = {0, 0, v << l}; /* 2^191 <= N = (v 2^l) 2^128 < 2^192 */
    return round_n_192(n, (int32_t)q - l - 128, bits);
}

/* w 10^q correctly rounded (w != 0 and POW5_MIN_Q <= q <= POW5_MAX_Q), or 0 when the product cannot decide it
 * or the result overflows (the caller then parses the block its own way).
 *
 * With l = clz(w), w' = w 2^l (2^63 <= w' < 2^64) and 5^q = A 2^e(q), T(q) <= A < T(q) + 1 (the table):
 * w 10^q = X 2^(e(q) + q - l) with X = w' A in [w' T, w' T + w') -- exactly w' T when T(q) is exact.  Rounding
 * is monotone, so when the 192-bit integers N = w' T and N + w' round to the same double, so does X (the
 * idea of Eisel and Lemire's algorithm, with the full 192-bit product; the interval is 2^-126 of N wide, so
 * the two differ only for X within that of a rounding boundary).  A decimal of <= 19 digits gets that close only
 * as an exact tie between two doubles, with q < 0: exact_quotient() rounds it; anything else left is 0. */
static int decimal_to_double(uint64_t w, int64_t q, double *value) {
    int l = clz64(w);
    uint64_t wn = w << l;
    const uint64_t *t = POW5_128[q - POW5_MIN_Q];
    int32_t e2 = (int32_t)POW5_EXP2[q - POW5_MIN_Q] + (int32_t)q - l;
    uint64_t hh, hl, lh, ll;
    mul_64x64(wn, t[0], &hh, &hl);
    mul_64x64(wn, t[1], &lh, &ll);
    uint64_t n[3];
    n[0] = ll;
    n[1] = hl + lh;
    n[2] = hh + (n[1] < hl);
    uint64_t bits;
    if (!round_n_192(n, e2, &bits)) return 0;
    if ((q < 0 || q > POW5_EXACT_MAX_Q) && !same_rounding(n, wn, e2, bits) && !exact_quotient(w, q, &bits)) return 0;
    sm_bits64 b;
    b.u = bits;
    *value = b.d;
    return 1;
}

static int is_blank(char c) { return c == ' ' || c == '\t'; }

static int is_digit(char c) { return (unsigned)(c - '0') < 10u; }

/* w 10^q (sign apart) -> *value; 0 if not taken (see the header). */
static int to_double(uint64_t w, int64_t q, double *value) {
    if (w == 0) {
        *value = 0.0;
    } else if (w <= MAX_EXACT_MANTISSA && q >= 0 && q <= 22) {
        *value = (double)w * POW10[q]; /* both exact: one correctly rounded product (Clinger) */
    } else if (w <= MAX_EXACT_MANTISSA && q < 0 && q >= -22) {
        *value = (double)w / POW10[-q]; /* both exact: one correctly rounded quotient */
    } else if (q < POW5_MIN_Q) {
        *value = 0.0; /* w 10^q < 2^64 10^-343 < 2^-1075, half the smallest subnormal: rounds to zero */
    } else if (q > POW5_MAX_Q) {
        return 0; /* >= 10^309: overflows */
    } else {
        return decimal_to_double(w, q, value);
    }
    return 1;
}

/* The field that starts at p[i] and ends before p[end] at the latest: [blanks][+-]digits[.digits][(e|E)[+-]digits]
 * [blanks] (or .digits) -> *value.  Returns the index after it (its trailing blanks), where the caller expects
 * a comma or the line's end; -1 if no number in the fast form starts there. */
static int64_t parse_field(const char *p, int64_t i, int64_t end, double *value) {
    while (i < end && is_blank(p[i])) i++;
    int negative = 0;
    if (i < end && (p[i] == '+' || p[i] == '-')) negative = p[i++] == '-';
    uint64_t w = 0; /* the significant digits; wraps only when there are more than 19, refused below */
    int64_t digits = 0, scale = 0; /* value = w 10^(scale + exponent) */
    int64_t z = i;
    while (i < end && p[i] == '0') i++; /* leading zeros */
    int seen = i > z;
    int64_t d0 = i;
    while (i < end && is_digit(p[i])) w = w * 10u + (uint64_t)(p[i++] - '0');
    digits = i - d0;
    seen |= digits > 0;
    if (i < end && p[i] == '.') {
        i++;
        if (digits == 0) { /* 0.000ddd: zeros after the point are not significant either */
            z = i;
            while (i < end && p[i] == '0') i++;
            scale -= i - z;
            seen |= i > z;
        }
        int64_t f0 = i;
        while (i < end && is_digit(p[i])) w = w * 10u + (uint64_t)(p[i++] - '0');
        digits += i - f0;
        scale -= i - f0;
        seen |= i > f0;
    }
    if (!seen || digits > MAX_DIGITS) return -1;
    if (i < end && (p[i] == 'e' || p[i] == 'E')) {
        i++;
        int eneg = 0;
        if (i < end && (p[i] == '+' || p[i] == '-')) eneg = p[i++] == '-';
        int64_t exponent = 0;
        int64_t e0 = i;
        while (i < end && is_digit(p[i])) {
            if (exponent < 100000) exponent = exponent * 10 + (p[i] - '0');
            i++;
        }
        if (i == e0) return -1;
        scale += eneg ? -exponent : exponent;
    }
    while (i < end && is_blank(p[i])) i++;
    double v;
    if (!to_double(w, scale, &v)) return -1;
    *value = negative ? -v : v;
    return i;
}

int64_t sarins_log_parse_block(const char *buf, int64_t len, int32_t n_cols, int32_t crlf, int32_t max_line,
                               double *out, int64_t cap_rows) {
    if (buf == NULL || out == NULL || len < 0 || n_cols < 1 || max_line < 0 || cap_rows < 0) return SARINS_LOG_NOT_TAKEN;
    int64_t rows = 0, start = 0;
    while (start < len) {
        const char *nl = memchr(buf + start, '\n', (size_t)(len - start));
        int64_t end = nl != NULL ? nl - buf : len;
        int64_t body_end = end;
        if (nl != NULL && crlf) {
            if (body_end == start || buf[body_end - 1] != '\r') return SARINS_LOG_NOT_TAKEN; /* LF among CRLF */
            body_end--;
        }
        if (body_end - start > max_line) return SARINS_LOG_NOT_TAKEN;
        if (rows >= cap_rows) return SARINS_LOG_NOT_TAKEN;
        double *row = out + rows * n_cols;
        int64_t i = start;
        for (int32_t col = 0; col < n_cols; col++) {
            /* a '#', a CR inside the line (or CRLF among LF) and a missing or extra field all stop a field */
            i = parse_field(buf, i, body_end, &row[col]);
            if (i < 0) return SARINS_LOG_NOT_TAKEN;
            if (col + 1 < n_cols) {
                if (i == body_end || buf[i] != ',') return SARINS_LOG_NOT_TAKEN;
                i++;
            }
        }
        if (i != body_end) return SARINS_LOG_NOT_TAKEN;
        rows++;
        start = end + 1;
    }
    return rows;
}
