/* log_parse.c: see log_parse.h. */
#include "smath.h" /* first: the floating-point contract, each operation rounded as written; no -ffast-math */
#include "log_parse.h"

#include <stddef.h>

/* 10^0 .. 10^22: every one exact in binary64 */
static const double POW10[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
                                 1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
#define MAX_EXACT_MANTISSA 9007199254740992ULL /* 2^53 */
#define MAX_DIGITS 15                           /* significant digits kept below 2^53 */

static int is_blank(char c) { return c == ' ' || c == '\t'; }

/* One field p[0..n) -> *value; 0 if not in the fast form (see the header). */
static int parse_field(const char *p, int64_t n, double *value) {
    int64_t i = 0;
    while (i < n && is_blank(p[i])) i++;
    while (n > i && is_blank(p[n - 1])) n--;
    if (i == n) return 0;
    int negative = 0;
    if (p[i] == '+' || p[i] == '-') negative = p[i++] == '-';
    uint64_t mantissa = 0;
    int digits = 0, seen = 0;
    int64_t scale = 0; /* value = mantissa * 10^(scale + exponent) */
    while (i < n && p[i] >= '0' && p[i] <= '9') {
        seen = 1;
        if (mantissa == 0 && p[i] == '0') { i++; continue; }
        if (++digits > MAX_DIGITS) return 0;
        mantissa = mantissa * 10u + (uint64_t)(p[i++] - '0');
    }
    if (i < n && p[i] == '.') {
        i++;
        while (i < n && p[i] >= '0' && p[i] <= '9') {
            seen = 1;
            scale--;
            if (mantissa == 0 && p[i] == '0') { i++; continue; }
            if (++digits > MAX_DIGITS) return 0;
            mantissa = mantissa * 10u + (uint64_t)(p[i++] - '0');
        }
    }
    if (!seen) return 0;
    if (i < n && (p[i] == 'e' || p[i] == 'E')) {
        i++;
        int eneg = 0;
        if (i < n && (p[i] == '+' || p[i] == '-')) eneg = p[i++] == '-';
        int64_t exponent = 0;
        int edigits = 0;
        while (i < n && p[i] >= '0' && p[i] <= '9') {
            if (exponent < 100000) exponent = exponent * 10 + (p[i] - '0');
            i++;
            edigits++;
        }
        if (!edigits) return 0;
        scale += eneg ? -exponent : exponent;
    }
    if (i != n) return 0;
    if (mantissa > MAX_EXACT_MANTISSA) return 0;
    double m = (double)mantissa; /* exact: mantissa <= 2^53 */
    double v;
    if (mantissa == 0) {
        v = 0.0;
    } else if (scale >= 0 && scale <= 22) {
        v = m * POW10[scale]; /* both exact: one correctly rounded product */
    } else if (scale < 0 && scale >= -22) {
        v = m / POW10[-scale]; /* both exact: one correctly rounded quotient */
    } else {
        return 0;
    }
    *value = negative ? -v : v;
    return 1;
}

int64_t sarins_log_parse_block(const char *buf, int64_t len, int32_t n_cols, int32_t crlf, int32_t max_line,
                               double *out, int64_t cap_rows) {
    if (buf == NULL || out == NULL || len < 0 || n_cols < 1 || max_line < 0 || cap_rows < 0) return SARINS_LOG_NOT_TAKEN;
    int64_t rows = 0, start = 0;
    while (start < len) {
        int64_t end = start;
        while (end < len && buf[end] != '\n') end++;
        int has_eol = end < len;
        int64_t body_end = end;
        if (has_eol && crlf) {
            if (body_end == start || buf[body_end - 1] != '\r') return SARINS_LOG_NOT_TAKEN; /* LF among CRLF */
            body_end--;
        }
        if (body_end - start > max_line) return SARINS_LOG_NOT_TAKEN;
        if (buf[start] == '#') return SARINS_LOG_NOT_TAKEN;
        if (rows >= cap_rows) return SARINS_LOG_NOT_TAKEN;
        double *row = out + rows * n_cols;
        int32_t col = 0;
        int64_t f = start;
        for (int64_t i = start; i <= body_end; i++) {
            if (i < body_end && buf[i] == '\r') return SARINS_LOG_NOT_TAKEN; /* CR inside, or CRLF among LF */
            if (i == body_end || buf[i] == ',') {
                if (col >= n_cols || !parse_field(buf + f, i - f, &row[col])) return SARINS_LOG_NOT_TAKEN;
                col++;
                f = i + 1;
            }
        }
        if (col != n_cols) return SARINS_LOG_NOT_TAKEN;
        rows++;
        start = end + 1;
    }
    return rows;
}
