#if defined(_MSC_VER) && !defined(_CRT_SECURE_NO_WARNINGS)
#define _CRT_SECURE_NO_WARNINGS /* fopen and fread are the portable C11 calls; MSVC's /W4 would flag them */
#endif
/* Binary model files: the container reader (netfile.h has the layout). */
#include "smath.h"

#include "netfile.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const unsigned char MAGIC[8] = {'S', 'A', 'R', 'N', 'E', 'T', 0, 1};

static int fail(char *msg, size_t msg_len, int code, const char *fmt, ...)
{
    if (msg != NULL && msg_len > 0) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(msg, msg_len, fmt, ap);
        va_end(ap);
    }
    return code;
}

static uint32_t get_u32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static uint64_t get_u64(const unsigned char *p)
{
    return (uint64_t)get_u32(p) | (uint64_t)get_u32(p + 4) << 32;
}

uint64_t sarins_netfile_checksum(const unsigned char *p, size_t n)
{
    uint64_t h = 0xcbf29ce484222325u; /* FNV-1a 64 offset basis */
    for (size_t i = 0; i < n; i++) {
        h ^= p[i];
        h *= 0x100000001b3u; /* FNV 64 prime */
    }
    return h;
}

static int name_char(unsigned char ch)
{
    return (ch >= 'a' && ch <= 'z') || (ch >= '0' && ch <= '9') || ch == '_' || ch == '.';
}

/* The array header at buf[pos]: name, shape, element count and offset; pos advanced past its data. */
static int parse_array(const unsigned char *buf, size_t end, size_t *pos, sarins_netfile_array *a, uint32_t k,
                       char *msg, size_t msg_len)
{
    if (end - *pos < SARINS_NETFILE_ARRAY_HEADER)
        return fail(msg, msg_len, SARINS_NETFILE_FORMAT, "array %u: its header runs past the end of the data",
                    (unsigned)k);
    const unsigned char *h = buf + *pos;
    size_t len = 0;
    while (len < SARINS_NETFILE_NAME && h[len] != 0)
        len++;
    if (len == 0 || len == SARINS_NETFILE_NAME)
        return fail(msg, msg_len, SARINS_NETFILE_FORMAT, "array %u: its name is empty or not terminated",
                    (unsigned)k);
    for (size_t i = 0; i < SARINS_NETFILE_NAME; i++)
        if (i < len ? !name_char(h[i]) : h[i] != 0)
            return fail(msg, msg_len, SARINS_NETFILE_FORMAT, "array %u: its name has a byte outside [a-z0-9_.] "
                        "or garbage after the terminator", (unsigned)k);
    memcpy(a->name, h, len);
    a->name[len] = '\0';
    a->ndim = get_u32(h + 32);
    if (a->ndim > 2 || get_u32(h + 36) != 0)
        return fail(msg, msg_len, SARINS_NETFILE_FORMAT, "array %s: ndim %u (0 .. 2) or a non-zero reserved field",
                    a->name, (unsigned)a->ndim);
    a->dim[0] = get_u64(h + 40);
    a->dim[1] = get_u64(h + 48);
    for (uint32_t d = a->ndim; d < 2; d++)
        if (a->dim[d] != 1)
            return fail(msg, msg_len, SARINS_NETFILE_FORMAT, "array %s: an absent dimension must be 1", a->name);
    if (a->dim[0] > SARINS_NETFILE_MAX_ELEMENTS || a->dim[1] > SARINS_NETFILE_MAX_ELEMENTS
        || (a->dim[1] != 0 && a->dim[0] > SARINS_NETFILE_MAX_ELEMENTS / a->dim[1]))
        return fail(msg, msg_len, SARINS_NETFILE_TOO_BIG, "array %s: shape (%llu, %llu) is over the budget of %llu "
                    "elements", a->name, (unsigned long long)a->dim[0], (unsigned long long)a->dim[1],
                    (unsigned long long)SARINS_NETFILE_MAX_ELEMENTS);
    a->count = a->dim[0] * a->dim[1];
    *pos += SARINS_NETFILE_ARRAY_HEADER;
    if ((uint64_t)(end - *pos) / 8u < a->count)
        return fail(msg, msg_len, SARINS_NETFILE_FORMAT, "array %s: %llu elements run past the end of the data",
                    a->name, (unsigned long long)a->count);
    a->offset = *pos;
    *pos += (size_t)a->count * 8u;
    return SARINS_NETFILE_OK;
}

int sarins_netfile_parse(const unsigned char *buf, size_t n, sarins_netfile *out, char *msg, size_t msg_len)
{
    if (msg != NULL && msg_len > 0)
        msg[0] = '\0';
    if (buf == NULL || out == NULL)
        return fail(msg, msg_len, SARINS_NETFILE_FORMAT, "no data");
    memset(out, 0, sizeof *out);
    if (n < SARINS_NETFILE_HEADER + 8u || memcmp(buf, MAGIC, sizeof MAGIC) != 0)
        return fail(msg, msg_len, SARINS_NETFILE_FORMAT, "not a sarins binary model file (wrong magic or shorter "
                    "than a header: %llu bytes)", (unsigned long long)n);
    out->version = get_u32(buf + 8);
    if (out->version != SARINS_NETFILE_VERSION)
        return fail(msg, msg_len, SARINS_NETFILE_FORMAT, "format version %u, this reader knows %u",
                    (unsigned)out->version, (unsigned)SARINS_NETFILE_VERSION);
    out->kind = get_u32(buf + 12);
    uint64_t total = get_u64(buf + 16);
    if (total > SARINS_NETFILE_MAX_BYTES)
        return fail(msg, msg_len, SARINS_NETFILE_TOO_BIG, "declared size %llu bytes is over the budget of %llu",
                    (unsigned long long)total, (unsigned long long)SARINS_NETFILE_MAX_BYTES);
    if (total != (uint64_t)n)
        return fail(msg, msg_len, SARINS_NETFILE_FORMAT, "declared size %llu bytes, the data has %llu (truncated or "
                    "padded)", (unsigned long long)total, (unsigned long long)n);
    uint64_t stored = get_u64(buf + n - 8);
#ifndef FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION /* libFuzzer builds: let mutated files reach the arrays */
    if (sarins_netfile_checksum(buf, n - 8) != stored)
        return fail(msg, msg_len, SARINS_NETFILE_FORMAT, "checksum mismatch (the file is corrupt)");
#else
    (void)stored;
#endif
    out->n_arrays = get_u32(buf + 24);
    if (out->n_arrays == 0 || out->n_arrays > SARINS_NETFILE_MAX_ARRAYS || get_u32(buf + 28) != 0)
        return fail(msg, msg_len, SARINS_NETFILE_FORMAT, "%u arrays (1 .. %u) or a non-zero reserved field",
                    (unsigned)out->n_arrays, (unsigned)SARINS_NETFILE_MAX_ARRAYS);
    size_t pos = SARINS_NETFILE_HEADER, end = n - 8;
    for (uint32_t k = 0; k < out->n_arrays; k++) {
        int code = parse_array(buf, end, &pos, &out->arrays[k], k, msg, msg_len);
        if (code != SARINS_NETFILE_OK)
            return code;
        for (uint32_t j = 0; j < k; j++)
            if (strcmp(out->arrays[j].name, out->arrays[k].name) == 0)
                return fail(msg, msg_len, SARINS_NETFILE_FORMAT, "array %s appears twice", out->arrays[k].name);
    }
    if (pos != end)
        return fail(msg, msg_len, SARINS_NETFILE_FORMAT, "%llu stray bytes after the last array",
                    (unsigned long long)(end - pos));
    out->buf = buf;
    out->size = n;
    return SARINS_NETFILE_OK;
}

int sarins_netfile_read_path(const char *path, unsigned char **buf, size_t *n, char *msg, size_t msg_len)
{
    if (msg != NULL && msg_len > 0)
        msg[0] = '\0';
    *buf = NULL;
    *n = 0;
    FILE *fp = path != NULL ? fopen(path, "rb") : NULL;
    if (fp == NULL)
        return fail(msg, msg_len, SARINS_NETFILE_IO, "cannot open the file");
    unsigned char head[SARINS_NETFILE_HEADER];
    size_t got = fread(head, 1, sizeof head, fp);
    if (got < 24 || memcmp(head, MAGIC, sizeof MAGIC) != 0) {
        fclose(fp);
        return fail(msg, msg_len, SARINS_NETFILE_FORMAT, "not a sarins binary model file (wrong magic or shorter "
                    "than a header: %llu bytes)", (unsigned long long)got);
    }
    uint64_t total = get_u64(head + 16);
    if (total > SARINS_NETFILE_MAX_BYTES || total < SARINS_NETFILE_HEADER + 8u) {
        fclose(fp);
        if (total > SARINS_NETFILE_MAX_BYTES)
            return fail(msg, msg_len, SARINS_NETFILE_TOO_BIG, "declared size %llu bytes is over the budget of %llu",
                        (unsigned long long)total, (unsigned long long)SARINS_NETFILE_MAX_BYTES);
        return fail(msg, msg_len, SARINS_NETFILE_FORMAT, "declared size %llu bytes is smaller than a header",
                    (unsigned long long)total);
    }
    /* one byte more than declared: a longer file is seen as such, never silently cut */
    unsigned char *data = malloc((size_t)total + 1u);
    if (data == NULL) {
        fclose(fp);
        return fail(msg, msg_len, SARINS_NETFILE_MEMORY, "out of memory for %llu bytes", (unsigned long long)total);
    }
    memcpy(data, head, got);
    size_t size = got;
    if (got == sizeof head)
        size += fread(data + got, 1, (size_t)total + 1u - got, fp);
    int read_error = ferror(fp);
    fclose(fp);
    if (read_error) {
        free(data);
        return fail(msg, msg_len, SARINS_NETFILE_IO, "read error");
    }
    if (size != total) {
        free(data);
        return fail(msg, msg_len, SARINS_NETFILE_FORMAT, "declared size %llu bytes, the file has %s%llu",
                    (unsigned long long)total, size > total ? "more than " : "", (unsigned long long)size);
    }
    *buf = data;
    *n = size;
    return SARINS_NETFILE_OK;
}

const sarins_netfile_array *sarins_netfile_find(const sarins_netfile *f, const char *name)
{
    for (uint32_t k = 0; k < f->n_arrays; k++)
        if (strcmp(f->arrays[k].name, name) == 0)
            return &f->arrays[k];
    return NULL;
}

double sarins_netfile_value(const sarins_netfile *f, const sarins_netfile_array *a, uint64_t i)
{
    uint64_t bits = get_u64(f->buf + a->offset + (size_t)i * 8u);
    double v;
    memcpy(&v, &bits, sizeof v);
    return v;
}
