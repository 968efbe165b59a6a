/* fmuResourceLocation (a file: URI) -> local path: the one parser of the shim and the core.
 *
 * Accepted (RFC 8089): file:///p, file://localhost/p (host case-insensitive), file:/p.  Refused:
 * any other scheme, any other host (file://otherhost/p names a file on another machine), a '%' not
 * followed by two hex digits, an escape decoding to NUL, a path that is not absolute, and a path
 * that does not fit in the caller's buffer (an error, never a silently shortened path).  Trailing
 * slashes are dropped (but "/" stays).  Header-only so that both objects and the test driver
 * (tests/test_native_uri.py) compile the same code.
 */
#ifndef SARINS_URI_H
#define SARINS_URI_H

#include <stddef.h>
#include <string.h>

enum {
    SARINS_URI_OK = 0,
    SARINS_URI_NULL = 1,        /* no URI given */
    SARINS_URI_SCHEME = 2,      /* not a file: URI */
    SARINS_URI_HOST = 3,        /* a host other than localhost or empty */
    SARINS_URI_ESCAPE = 4,      /* '%' not followed by two hex digits, or %00 */
    SARINS_URI_TOO_LONG = 5,    /* the path does not fit in the buffer */
    SARINS_URI_EMPTY = 6        /* no path */
};

static inline const char *sarins_uri_error(int code) {
    switch (code) {
    case SARINS_URI_OK: return "ok";
    case SARINS_URI_NULL: return "no fmuResourceLocation given";
    case SARINS_URI_SCHEME: return "not a file: URI";
    case SARINS_URI_HOST: return "a file: URI naming another host (only localhost or an empty host)";
    case SARINS_URI_ESCAPE: return "a bad percent escape (% must be followed by two hex digits, not %00)";
    case SARINS_URI_TOO_LONG: return "a path too long for this FMU's buffer";
    case SARINS_URI_EMPTY: return "no path in the URI";
    default: return "unknown error";
    }
}

static inline int sarins_hex_digit(char c) {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

static inline int sarins_ascii_ieq(const char *a, const char *b, size_t n) {
    for (size_t i = 0; i < n; i++) {
        char x = a[i], y = b[i];
        if (x >= 'A' && x <= 'Z') x = (char)(x - 'A' + 'a');
        if (y >= 'A' && y <= 'Z') y = (char)(y - 'A' + 'a');
        if (x != y || x == '\0') return 0;
    }
    return 1;
}

/* Decode uri into out (outlen bytes, NUL included); returns SARINS_URI_OK or an error code, out then "". */
static inline int sarins_uri_to_path(const char *uri, char *out, size_t outlen) {
    if (out != NULL && outlen > 0) out[0] = '\0';
    if (uri == NULL) return SARINS_URI_NULL;
    if (out == NULL || outlen == 0) return SARINS_URI_TOO_LONG;
    if (!sarins_ascii_ieq(uri, "file:", 5)) return SARINS_URI_SCHEME;
    const char *p = uri + 5;
    if (p[0] == '/' && p[1] == '/') { /* an authority: empty or localhost */
        p += 2;
        size_t host = strcspn(p, "/");
        if (!(host == 0 || (host == 9 && sarins_ascii_ieq(p, "localhost", 9)))) return SARINS_URI_HOST;
        p += host;
    }
    if (p[0] != '/') return p[0] ? SARINS_URI_SCHEME : SARINS_URI_EMPTY;
    size_t k = 0;
    for (; *p; p++) {
        char c = *p;
        if (c == '%') {
            int hi = sarins_hex_digit(p[1]), lo = hi < 0 ? -1 : sarins_hex_digit(p[2]);
            if (hi < 0 || lo < 0 || (hi == 0 && lo == 0)) {
                out[0] = '\0';
                return SARINS_URI_ESCAPE;
            }
            c = (char)(hi * 16 + lo);
            p += 2;
        }
        if (k + 1 >= outlen) {
            out[0] = '\0';
            return SARINS_URI_TOO_LONG;
        }
        out[k++] = c;
    }
    out[k] = '\0';
    while (k > 1 && out[k - 1] == '/') out[--k] = '\0';
#ifdef _WIN32
    /* file:///C:/dir names the Windows path C:/dir (RFC 8089 E.2): drop the slash before a drive letter */
    if (k >= 3 && out[0] == '/' && ((out[1] >= 'A' && out[1] <= 'Z') || (out[1] >= 'a' && out[1] <= 'z'))
        && out[2] == ':' && (out[3] == '/' || out[3] == '\\' || out[3] == '\0'))
        memmove(out, out + 1, k);
#endif
    return SARINS_URI_OK;
}

#endif
