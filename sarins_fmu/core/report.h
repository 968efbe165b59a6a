/* Error reports of the profile builders (schedule.c, ambient.c): a code and a one-line reason written into
 * the caller's buffer; numbers in the reasons are written as Python's repr writes them. */
#ifndef SARINS_REPORT_H
#define SARINS_REPORT_H

#include <stddef.h>

typedef struct {
    int code;    /* 0 until the first failure */
    char *msg;   /* caller's buffer, or NULL */
    size_t len;  /* its size, bytes */
} report;

/* A report writing into msg (len bytes; msg may be NULL), cleared to "". */
report sarins_report(char *msg, size_t len);

/* Records a failure (the first one only: later calls keep its code and reason); returns r->code. */
int sarins_fail(report *r, int code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* x as Python's repr(float) writes it: the shortest digits that read back as x, "100.0", "1e-05", "nan". */
void sarins_format_number(char *buf, size_t len, double x);

/* Copies text into msg (size bytes, truncated and terminated); nothing when msg is NULL or size 0. */
void sarins_say(char *msg, size_t size, const char *text);

/* Appends a, b, c and d to the string in buf (len bytes, truncated and terminated). */
void sarins_join(char *buf, size_t len, const char *a, const char *b, const char *c, const char *d);

#endif
