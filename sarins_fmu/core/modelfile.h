/* The binary model file ("SARINSMF"): named numeric arrays with a kind tag, read without any library.
 *
 * Written by the Python library (sarins_fmu/identify/modelfile.py, suffix .smf) for models that a native
 * FMU reads at initialisation; read here, by the FMUs and, through ctypes, by the library itself (one
 * reader).  Every multi-byte field is little-endian.  Layout:
 *
 *   offset size  field
 *   0      8     magic "SARINSMF"
 *   8      4     u32 container version (1)
 *   12     4     u32 entry count, 1 .. SARINS_MF_MAX_ENTRIES
 *   16     48    kind: printable ASCII (0x20..0x7e), NUL-terminated, the rest NUL ("sarins_fmu.identify.rls")
 *   64     4     u32 kind version (>= 1; its meaning belongs to the kind)
 *   68     4     u32 flags, 0
 *   72     8     u64 total size of the file in bytes
 *   80           the entries, one after the other, each:
 *                  32 bytes  name: [A-Za-z][A-Za-z0-9_.]*, NUL-terminated, the rest NUL; names unique
 *                  4  bytes  u32 dtype: 0 null (no data: a missing optional value), 1 float64, 2 int64
 *                  4  bytes  u32 ndim: 0 (a scalar), 1 or 2 (null: 0)
 *                  8  bytes  u32 dims[2]: the used ones >= 1, the others 0
 *                  8 x count bytes of data, count = the product of the used dims (a scalar 1, null 0);
 *                  float64 values finite (IEEE 754 binary64 bit patterns), int64 two's complement
 *   size-4 4     u32 CRC-32 (IEEE 802.3, zlib's crc32) of every byte before it
 *
 * Every byte is checked: the magic, versions, flags, reserved and padding bytes, names and kind
 * (characters, termination, zero padding), dtypes, ranks, dims, sizes (the total size field equals the
 * buffer length, each entry's data lies inside it, nothing is left over), finiteness and the checksum.
 * Budgets: the caller's buffer size (each model kind has its own: SARINS_RLS_FILE_MAX for the RLS),
 * SARINS_MF_MAX_ENTRIES entries, dims below 2^32.  Parsing allocates nothing; the parsed view refers to the
 * caller's buffer by offsets.  Functions return SARINS_MF_OK or SARINS_MF_BAD with a one-line reason in
 * msg (size bytes; msg may be NULL).
 */
#ifndef SARINS_MODELFILE_H
#define SARINS_MODELFILE_H

#include <stddef.h>
#include <stdint.h>

#define SARINS_MF_OK 0
#define SARINS_MF_BAD 1
#define SARINS_MF_VERSION 1
#define SARINS_MF_HEADER 80      /* bytes before the first entry */
#define SARINS_MF_ENTRY_HEADER 48 /* bytes of an entry before its data */
#define SARINS_MF_NAME 32        /* bytes of an entry name, NUL included */
#define SARINS_MF_KIND 48        /* bytes of the kind tag, NUL included */
#define SARINS_MF_MAX_ENTRIES 64
#define SARINS_MF_MIN_SIZE (SARINS_MF_HEADER + SARINS_MF_ENTRY_HEADER + 4)

enum { SARINS_MF_NULL = 0, SARINS_MF_F64 = 1, SARINS_MF_I64 = 2 };

typedef struct {
    char name[SARINS_MF_NAME];
    uint32_t dtype, ndim;
    uint32_t dims[2];
    uint64_t count;  /* elements */
    uint64_t offset; /* byte offset of the first element in the buffer */
} sarins_mf_entry;

typedef struct {
    char kind[SARINS_MF_KIND];
    uint32_t kind_version;
    uint32_t n_entries;
    sarins_mf_entry entries[SARINS_MF_MAX_ENTRIES];
} sarins_mf;

/* CRC-32 (IEEE, reflected, init and final xor 0xFFFFFFFF) of n bytes: zlib.crc32(bytes). */
uint32_t sarins_mf_crc32(const unsigned char *data, size_t n);

/* Parse n bytes into *mf (see the layout above).  kind: the tag the caller expects (NULL: any). */
int sarins_mf_parse(const unsigned char *buf, size_t n, const char *kind, sarins_mf *mf, char *msg, size_t size);

/* The entry called name, or NULL. */
const sarins_mf_entry *sarins_mf_find(const sarins_mf *mf, const char *name);

/* Element i of a float64 entry (the caller has checked the dtype and i < count). */
double sarins_mf_f64(const unsigned char *buf, const sarins_mf_entry *e, uint64_t i);

/* Element i of an int64 entry (the caller has checked the dtype and i < count). */
int64_t sarins_mf_i64(const unsigned char *buf, const sarins_mf_entry *e, uint64_t i);

/* Read the regular file at path into buf (cap bytes, the kind's budget): *n its size.  A file larger than
 * cap, a missing or unreadable path, a directory, or a read error is refused with the reason. */
int sarins_mf_read_file(const char *path, unsigned char *buf, size_t cap, size_t *n, char *msg, size_t size);

/* sizeof(sarins_mf) and sizeof(sarins_mf_entry) (for the Python binding). */
int64_t sarins_mf_layout(int64_t *entry_size);

#endif
