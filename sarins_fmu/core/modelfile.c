#if defined(_MSC_VER) && !defined(_CRT_SECURE_NO_WARNINGS)
#define _CRT_SECURE_NO_WARNINGS /* fopen and fread are the portable C11 calls; MSVC's /W4 would flag them */
#endif
#include "modelfile.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "report.h"

static const unsigned char MAGIC[8] = {'S', 'A', 'R', 'I', 'N', 'S', 'M', 'F'};

uint32_t sarins_mf_crc32(const unsigned char *data, size_t n)
{
    uint32_t crc = 0xFFFFFFFFu;
    for (size_t i = 0; i < n; i++) {
        crc ^= data[i];
        for (int b = 0; b < 8; b++)
            crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
    }
    return crc ^ 0xFFFFFFFFu;
}

static uint32_t get_u32(const unsigned char *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static uint64_t get_u64(const unsigned char *p) { return (uint64_t)get_u32(p) | ((uint64_t)get_u32(p + 4) << 32); }

/* A NUL-terminated string of at most len - 1 characters accepted by ok(), the rest of the field NUL. */
static int text_field(const unsigned char *p, size_t len, int (*ok)(unsigned char c, size_t i), char *out)
{
    size_t end = 0;
    while (end < len && p[end] != 0) {
        if (!ok(p[end], end))
            return 0;
        end++;
    }
    if (end == 0 || end == len)
        return 0;
    for (size_t i = end; i < len; i++)
        if (p[i] != 0)
            return 0;
    memcpy(out, p, end + 1);
    return 1;
}

static int kind_char(unsigned char c, size_t i)
{
    (void)i;
    return c >= 0x20 && c <= 0x7e;
}

static int name_char(unsigned char c, size_t i)
{
    int letter = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z');
    return i == 0 ? letter : (letter || (c >= '0' && c <= '9') || c == '_' || c == '.');
}

/* One entry's header at buf + at (the caller checked that SARINS_MF_ENTRY_HEADER bytes follow before the
 * checksum); fills e and returns the offset after its data, or 0 with the reason. */
static uint64_t parse_entry(const unsigned char *buf, uint64_t at, uint64_t end, sarins_mf_entry *e, report *r,
                            unsigned index)
{
    const unsigned char *p = buf + at;
    if (!text_field(p, SARINS_MF_NAME, name_char, e->name)) {
        sarins_fail(r, SARINS_MF_BAD, "entry %u: the name is not [A-Za-z][A-Za-z0-9_.]* NUL-terminated and "
                                      "NUL-padded in %d bytes", index + 1, SARINS_MF_NAME);
        return 0;
    }
    e->dtype = get_u32(p + 32);
    e->ndim = get_u32(p + 36);
    e->dims[0] = get_u32(p + 40);
    e->dims[1] = get_u32(p + 44);
    if (e->dtype > SARINS_MF_I64) {
        sarins_fail(r, SARINS_MF_BAD, "entry '%s': unknown dtype %lu", e->name, (unsigned long)e->dtype);
        return 0;
    }
    if (e->ndim > 2 || (e->dtype == SARINS_MF_NULL && e->ndim != 0)) {
        sarins_fail(r, SARINS_MF_BAD, "entry '%s': rank %lu not allowed", e->name, (unsigned long)e->ndim);
        return 0;
    }
    uint64_t count = e->dtype == SARINS_MF_NULL ? 0 : 1;
    for (uint32_t d = 0; d < 2; d++) {
        if (d < e->ndim ? e->dims[d] == 0 : e->dims[d] != 0) {
            sarins_fail(r, SARINS_MF_BAD, "entry '%s': dimension %lu is %lu", e->name, (unsigned long)d + 1,
                        (unsigned long)e->dims[d]);
            return 0;
        }
        if (d < e->ndim)
            count *= e->dims[d]; /* < 2^64: two factors below 2^32 */
    }
    uint64_t data = at + SARINS_MF_ENTRY_HEADER;
    if (count > (end - data) / 8) {
        sarins_fail(r, SARINS_MF_BAD, "entry '%s': %llu values run past the end of the file", e->name,
                    (unsigned long long)count);
        return 0;
    }
    e->count = count;
    e->offset = data;
    if (e->dtype == SARINS_MF_F64)
        for (uint64_t i = 0; i < count; i++)
            if (!isfinite(sarins_mf_f64(buf, e, i))) {
                sarins_fail(r, SARINS_MF_BAD, "entry '%s' holds NaN or infinity", e->name);
                return 0;
            }
    return data + 8 * count;
}

int sarins_mf_parse(const unsigned char *buf, size_t n, const char *kind, sarins_mf *mf, char *msg, size_t size)
{
    report r = sarins_report(msg, size);
    if (buf == NULL || n < sizeof MAGIC || memcmp(buf, MAGIC, sizeof MAGIC) != 0)
        return sarins_fail(&r, SARINS_MF_BAD, "not a binary model file (no SARINSMF magic; write one with the "
                                              "library's save(path.smf))");
    if (n < SARINS_MF_MIN_SIZE)
        return sarins_fail(&r, SARINS_MF_BAD, "%llu bytes: too short for a model file (at least %d)",
                           (unsigned long long)n, SARINS_MF_MIN_SIZE);
    uint32_t version = get_u32(buf + 8);
    if (version != SARINS_MF_VERSION)
        return sarins_fail(&r, SARINS_MF_BAD, "container version %lu not supported (readable: %d)",
                           (unsigned long)version, SARINS_MF_VERSION);
    uint64_t total = get_u64(buf + 72);
    if (total != (uint64_t)n)
        return sarins_fail(&r, SARINS_MF_BAD, "the header says %llu bytes, the file has %llu (truncated or "
                                              "extended)", (unsigned long long)total, (unsigned long long)n);
    uint32_t crc = get_u32(buf + n - 4);
    if (crc != sarins_mf_crc32(buf, n - 4))
        return sarins_fail(&r, SARINS_MF_BAD, "checksum mismatch (the file is corrupt)");
    uint32_t count = get_u32(buf + 12);
    if (count < 1 || count > SARINS_MF_MAX_ENTRIES)
        return sarins_fail(&r, SARINS_MF_BAD, "%lu entries (1 .. %d allowed)", (unsigned long)count,
                           SARINS_MF_MAX_ENTRIES);
    if (!text_field(buf + 16, SARINS_MF_KIND, kind_char, mf->kind))
        return sarins_fail(&r, SARINS_MF_BAD, "the kind tag is not printable ASCII NUL-terminated and NUL-padded "
                                              "in %d bytes", SARINS_MF_KIND);
    if (kind != NULL && strcmp(mf->kind, kind) != 0)
        return sarins_fail(&r, SARINS_MF_BAD, "format tag is '%s', expected '%s'", mf->kind, kind);
    mf->kind_version = get_u32(buf + 64);
    if (mf->kind_version < 1)
        return sarins_fail(&r, SARINS_MF_BAD, "format version 0 not allowed");
    if (get_u32(buf + 68) != 0)
        return sarins_fail(&r, SARINS_MF_BAD, "reserved flags are not 0");
    uint64_t end = (uint64_t)n - 4, at = SARINS_MF_HEADER;
    for (uint32_t k = 0; k < count; k++) {
        if (end - at < SARINS_MF_ENTRY_HEADER)
            return sarins_fail(&r, SARINS_MF_BAD, "entry %lu of %lu runs past the end of the file",
                               (unsigned long)k + 1, (unsigned long)count);
        at = parse_entry(buf, at, end, &mf->entries[k], &r, k);
        if (at == 0)
            return SARINS_MF_BAD;
        for (uint32_t j = 0; j < k; j++)
            if (strcmp(mf->entries[j].name, mf->entries[k].name) == 0)
                return sarins_fail(&r, SARINS_MF_BAD, "entry '%s' appears twice", mf->entries[k].name);
    }
    if (at != end)
        return sarins_fail(&r, SARINS_MF_BAD, "%llu bytes after the last entry", (unsigned long long)(end - at));
    mf->n_entries = count;
    return SARINS_MF_OK;
}

const sarins_mf_entry *sarins_mf_find(const sarins_mf *mf, const char *name)
{
    for (uint32_t k = 0; k < mf->n_entries && k < SARINS_MF_MAX_ENTRIES; k++)
        if (strcmp(mf->entries[k].name, name) == 0)
            return &mf->entries[k];
    return NULL;
}

double sarins_mf_f64(const unsigned char *buf, const sarins_mf_entry *e, uint64_t i)
{
    uint64_t bits = get_u64(buf + e->offset + 8 * i);
    double x;
    memcpy(&x, &bits, sizeof x);
    return x;
}

int64_t sarins_mf_i64(const unsigned char *buf, const sarins_mf_entry *e, uint64_t i)
{
    uint64_t bits = get_u64(buf + e->offset + 8 * i);
    int64_t x;
    memcpy(&x, &bits, sizeof x);
    return x;
}

int sarins_mf_read_file(const char *path, unsigned char *buf, size_t cap, size_t *n, char *msg, size_t size)
{
    report r = sarins_report(msg, size);
    *n = 0;
    if (path == NULL || path[0] == '\0')
        return sarins_fail(&r, SARINS_MF_BAD, "no file named");
    FILE *f = fopen(path, "rb");
    if (f == NULL)
        return sarins_fail(&r, SARINS_MF_BAD, "no such file or it cannot be opened");
    size_t got = 0;
    while (got < cap) {
        size_t k = fread(buf + got, 1, cap - got, f);
        if (k == 0)
            break;
        got += k;
    }
    int failed = ferror(f);
    int more = 0;
    if (!failed && got == cap) { /* one byte more: over the budget */
        unsigned char extra;
        more = fread(&extra, 1, 1, f) == 1;
        failed = ferror(f);
    }
    fclose(f);
    if (failed)
        return sarins_fail(&r, SARINS_MF_BAD, "cannot be read (a directory, or a read error)");
    if (more)
        return sarins_fail(&r, SARINS_MF_BAD, "larger than the %llu bytes a model file of this kind may have",
                           (unsigned long long)cap);
    *n = got;
    return SARINS_MF_OK;
}

int64_t sarins_mf_layout(int64_t *entry_size)
{
    *entry_size = (int64_t)sizeof(sarins_mf_entry);
    return (int64_t)sizeof(sarins_mf);
}
