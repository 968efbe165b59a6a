#include "smath.h"

#include "report.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

report sarins_report(char *msg, size_t len)
{
    report r = {0, msg, msg == NULL ? 0 : len};
    if (r.len > 0)
        msg[0] = '\0';
    return r;
}

int sarins_fail(report *r, int code, const char *fmt, ...)
{
    if (r->code)
        return r->code;
    r->code = code;
    if (r->len > 0) {
        va_list ap;
        va_start(ap, fmt);
        int n = vsnprintf(r->msg, r->len, fmt, ap);
        va_end(ap);
        if (n < 0) /* an encoding error: no reason rather than a partial one */
            r->msg[0] = '\0';
    }
    return r->code;
}

void sarins_format_number(char *buf, size_t len, double x)
{
    char s[48];
    if (len == 0)
        return;
    if (isnan(x)) {
        snprintf(buf, len, "nan");
        return;
    }
    if (isinf(x)) {
        snprintf(buf, len, x > 0 ? "inf" : "-inf");
        return;
    }
    int p = 1;
    for (; p < 17; p++) { /* the shortest precision that reads back as x */
        if (snprintf(s, sizeof s, "%.*g", p, x) < 0)
            break;
        if (strtod(s, NULL) == x)
            break;
    }
    if (snprintf(s, sizeof s, "%.*g", p, x) < 0) {
        snprintf(buf, len, "?");
        return;
    }
    const char *e = strchr(s, 'e');
    if (e != NULL) { /* repr writes 1e+02 as 100.0: positional up to 1e16 */
        int exp10 = atoi(e + 1);
        if (exp10 >= 0 && exp10 < 16 && snprintf(s, sizeof s, "%.*g", exp10 + 1, x) < 0) {
            snprintf(buf, len, "?");
            return;
        }
    }
    /* a whole number: repr adds ".0" */
    snprintf(buf, len, "%s%s", s, strpbrk(s, ".e") == NULL ? ".0" : "");
}

void sarins_join(char *buf, size_t len, const char *a, const char *b, const char *c, const char *d)
{
    const char *parts[4] = {a, b, c, d};
    size_t used = strlen(buf);
    for (int i = 0; i < 4 && used + 1 < len; i++) {
        size_t n = strlen(parts[i]);
        if (n > len - 1 - used)
            n = len - 1 - used;
        memcpy(buf + used, parts[i], n);
        used += n;
        buf[used] = '\0';
    }
}

void sarins_say(char *msg, size_t size, const char *text)
{
    if (msg == NULL || size == 0)
        return;
    msg[0] = '\0';
    sarins_join(msg, size, text, "", "", "");
}
