/* Binary model files of the trained networks (identifiers, compensators): the one reader of the core.
 *
 * A small self-describing little-endian container, written by the Python trainer
 * (sarins_fmu/identify/netfile.py) and read here without any library.  Layout (every integer unsigned
 * little-endian, every offset a multiple of 8):
 *
 *   offset  bytes  field
 *   0       8      magic "SARNET\0\1"
 *   8       4      format version (SARINS_NETFILE_VERSION)
 *   12      4      model kind (SARINS_NET_KIND_*)
 *   16      8      total size of the file in bytes, checksum included
 *   24      4      number of arrays (1 .. SARINS_NETFILE_MAX_ARRAYS)
 *   28      4      reserved, 0
 *   32      ...    the arrays, one after the other, each:
 *                    32 bytes  name: ASCII [a-z0-9_.], NUL-padded, at least one NUL, unique in the file
 *                    4 bytes   ndim (0 .. 2; 0 is a scalar of one element)
 *                    4 bytes   reserved, 0
 *                    8 bytes   dim 0 (1 when ndim < 1)
 *                    8 bytes   dim 1 (1 when ndim < 2)
 *                    8 * dim0 * dim1 bytes  float64 IEEE 754 little-endian, row-major
 *   total-8 8      checksum: FNV-1a 64 of bytes [0, total - 8)
 *
 * Every byte is checked against the buffer: the declared total must equal the buffer's length and lie
 * within SARINS_NETFILE_MAX_BYTES, every array must fit before the checksum, the arrays must end exactly
 * at it, and every element count within SARINS_NETFILE_MAX_ELEMENTS.  A file is read by
 * sarins_netfile_read_path (it refuses a file whose size exceeds the budget before allocating) or parsed
 * from memory by sarins_netfile_parse.  Errors: a non-zero SARINS_NETFILE_* code and a one-line reason in
 * msg (msg_len bytes, always terminated; msg may be NULL).  No globals; reentrant.
 */
#ifndef SARINS_NETFILE_H
#define SARINS_NETFILE_H

#include <stddef.h>
#include <stdint.h>

#define SARINS_NETFILE_VERSION 1u
#define SARINS_NETFILE_HEADER 32u            /* bytes before the first array */
#define SARINS_NETFILE_ARRAY_HEADER 56u      /* bytes of an array's header */
#define SARINS_NETFILE_NAME 32u              /* bytes of an array's name field */
#define SARINS_NETFILE_MAX_ARRAYS 64u        /* most arrays in one file */
#define SARINS_NETFILE_MAX_BYTES ((uint64_t)64 << 20) /* largest file: 64 MiB */
#define SARINS_NETFILE_MAX_ELEMENTS ((uint64_t)1 << 23) /* most float64 in one array */

/* model kinds (the Python writer's names in brackets) */
enum {
    SARINS_NET_KIND_AXIAL_RBF = 1,   /* seed 000 axial drift identifier [axial_rbf] */
    SARINS_NET_KIND_TRADITIONAL = 2, /* seed 003 compensators [traditional, rbf, grnn, lstm, gru, lstm3, gru3] */
    SARINS_NET_KIND_RBF = 3,
    SARINS_NET_KIND_GRNN = 4,
    SARINS_NET_KIND_LSTM = 5,
    SARINS_NET_KIND_GRU = 6,
    SARINS_NET_KIND_LSTM3 = 7,
    SARINS_NET_KIND_GRU3 = 8,
    SARINS_NET_KIND_RLS = 9          /* seed 002 forgetting-factor RLS of the azimuth drift model [rls] (rls.h) */
};
#define SARINS_NET_KIND_LAST 9

enum {
    SARINS_NETFILE_OK = 0,
    SARINS_NETFILE_IO = 1,       /* cannot open or read the file */
    SARINS_NETFILE_TOO_BIG = 2,  /* over a size budget */
    SARINS_NETFILE_FORMAT = 3,   /* not this format, truncated, inconsistent or corrupt */
    SARINS_NETFILE_MEMORY = 4,   /* out of memory */
    SARINS_NETFILE_CONTENT = 5   /* a well-formed file whose arrays do not make the model asked for */
};

typedef struct {
    char name[SARINS_NETFILE_NAME + 1]; /* NUL-terminated */
    uint32_t ndim;
    uint64_t dim[2];   /* 1 for the absent dimensions */
    uint64_t count;    /* dim[0] * dim[1] */
    size_t offset;     /* of the first element in the buffer */
} sarins_netfile_array;

typedef struct {
    uint32_t version;
    uint32_t kind;
    uint32_t n_arrays;
    sarins_netfile_array arrays[SARINS_NETFILE_MAX_ARRAYS];
    const unsigned char *buf; /* the parsed buffer (not owned) */
    size_t size;
} sarins_netfile;

/* FNV-1a 64 of n bytes. */
uint64_t sarins_netfile_checksum(const unsigned char *p, size_t n);

/* Parse buf[n] into *out (which points into buf: keep buf alive while using it). */
int sarins_netfile_parse(const unsigned char *buf, size_t n, sarins_netfile *out, char *msg, size_t msg_len);

/* Read the file at path into a new buffer (*buf, *n; free() it), refusing before allocating a file larger
 * than SARINS_NETFILE_MAX_BYTES. */
int sarins_netfile_read_path(const char *path, unsigned char **buf, size_t *n, char *msg, size_t msg_len);

/* The array named name, or NULL. */
const sarins_netfile_array *sarins_netfile_find(const sarins_netfile *f, const char *name);

/* Element i (< a->count) of array a, decoded from little-endian. */
double sarins_netfile_value(const sarins_netfile *f, const sarins_netfile_array *a, uint64_t i);

#endif
