/* Heap allocation counter for the native test hosts, loaded with LD_PRELOAD.
 *
 * build: cc -O2 -shared -fPIC -o alloc_counter.so alloc_counter.c -ldl
 * run:   LD_PRELOAD=./alloc_counter.so ./system plan.txt
 *
 * Wraps malloc, calloc, realloc, free, posix_memalign, aligned_alloc, memalign,
 * valloc and pvalloc (forwarded to the next definition found by
 * dlsym(RTLD_NEXT)), and mmap / munmap called through their public symbols
 * (glibc's malloc maps its large blocks internally, which this does not see;
 * CPython's small-object allocator takes its 1 MiB arenas with mmap, which it
 * does see).  Every call is counted in an atomic counter, from any thread.
 *
 * The host finds the counters with dlsym(RTLD_DEFAULT, ...) (absent without
 * the preload, so the host runs without it too):
 *   void alloc_counter_reset(void);               zero every counter
 *   void alloc_counter_get(unsigned long long c[ALLOC_COUNTER_N]);
 *        c[0] allocations: malloc, calloc, realloc, posix_memalign,
 *             aligned_alloc, memalign, valloc, pvalloc (failed ones too)
 *        c[1] frees of a non-NULL pointer
 *        c[2] mmap calls, c[3] munmap calls
 *
 * dlsym itself may call calloc (glibc's dlerror buffer) before the real calloc
 * is known: while the symbols are being resolved, allocations are served from
 * a small static buffer, never freed (free ignores pointers into it).
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/types.h>

#define ALLOC_COUNTER_N 4

typedef void *(*malloc_fn)(size_t);
typedef void *(*calloc_fn)(size_t, size_t);
typedef void *(*realloc_fn)(void *, size_t);
typedef void (*free_fn)(void *);
typedef int (*posix_memalign_fn)(void **, size_t, size_t);
typedef void *(*aligned_alloc_fn)(size_t, size_t);
typedef void *(*mmap_fn)(void *, size_t, int, int, int, off_t);
typedef int (*munmap_fn)(void *, size_t);

static atomic_ullong counts[ALLOC_COUNTER_N];
static malloc_fn real_malloc;
static calloc_fn real_calloc;
static realloc_fn real_realloc;
static free_fn real_free;
static posix_memalign_fn real_posix_memalign;
static aligned_alloc_fn real_aligned_alloc, real_memalign;
static malloc_fn real_valloc, real_pvalloc;
static mmap_fn real_mmap;
static munmap_fn real_munmap;
static atomic_int resolving; /* 1 while dlsym runs: serve allocations from boot */
static atomic_int resolved;

#define BOOT_SIZE 16384
static _Alignas(max_align_t) unsigned char boot[BOOT_SIZE];
static atomic_size_t boot_used;

static void *boot_alloc(size_t n) {
    size_t need = (n + sizeof(max_align_t) - 1) / sizeof(max_align_t) * sizeof(max_align_t);
    size_t at = atomic_fetch_add(&boot_used, need);
    if (at + need > BOOT_SIZE) return NULL;
    return boot + at; /* static storage: already zero, as calloc needs */
}

static int in_boot(const void *p) {
    uintptr_t a = (uintptr_t)p, b = (uintptr_t)boot;
    return a >= b && a < b + BOOT_SIZE;
}

static void resolve(void) {
    if (atomic_load(&resolved) || atomic_exchange(&resolving, 1)) return;
    real_malloc = (malloc_fn)dlsym(RTLD_NEXT, "malloc");
    real_calloc = (calloc_fn)dlsym(RTLD_NEXT, "calloc");
    real_realloc = (realloc_fn)dlsym(RTLD_NEXT, "realloc");
    real_free = (free_fn)dlsym(RTLD_NEXT, "free");
    real_posix_memalign = (posix_memalign_fn)dlsym(RTLD_NEXT, "posix_memalign");
    real_aligned_alloc = (aligned_alloc_fn)dlsym(RTLD_NEXT, "aligned_alloc");
    real_memalign = (aligned_alloc_fn)dlsym(RTLD_NEXT, "memalign");
    real_valloc = (malloc_fn)dlsym(RTLD_NEXT, "valloc");
    real_pvalloc = (malloc_fn)dlsym(RTLD_NEXT, "pvalloc");
    real_mmap = (mmap_fn)dlsym(RTLD_NEXT, "mmap");
    real_munmap = (munmap_fn)dlsym(RTLD_NEXT, "munmap");
    atomic_store(&resolving, 0);
    atomic_store(&resolved, 1);
}

static void count(int which) { atomic_fetch_add_explicit(&counts[which], 1, memory_order_relaxed); }

void alloc_counter_reset(void) {
    for (int k = 0; k < ALLOC_COUNTER_N; k++) atomic_store(&counts[k], 0);
}

void alloc_counter_get(unsigned long long out[ALLOC_COUNTER_N]) {
    for (int k = 0; k < ALLOC_COUNTER_N; k++) out[k] = atomic_load(&counts[k]);
}

void *malloc(size_t n) {
    if (atomic_load(&resolving)) return boot_alloc(n);
    resolve();
    count(0);
    return real_malloc ? real_malloc(n) : NULL;
}

void *calloc(size_t m, size_t n) {
    if (atomic_load(&resolving)) return n && m > SIZE_MAX / n ? NULL : boot_alloc(m * n);
    resolve();
    count(0);
    return real_calloc ? real_calloc(m, n) : NULL;
}

void *realloc(void *p, size_t n) {
    if (atomic_load(&resolving)) return NULL; /* dlsym never grows a block */
    if (in_boot(p)) { /* a boot block grown later: move it to the real heap (it is never freed) */
        size_t left = (size_t)(boot + BOOT_SIZE - (unsigned char *)p);
        void *q = malloc(n);
        if (q) memcpy(q, p, n < left ? n : left);
        return q;
    }
    resolve();
    count(0);
    return real_realloc ? real_realloc(p, n) : NULL;
}

void free(void *p) {
    if (!p || in_boot(p)) return;
    resolve();
    count(1);
    if (real_free) real_free(p);
}

int posix_memalign(void **out, size_t align, size_t n) {
    resolve();
    count(0);
    return real_posix_memalign ? real_posix_memalign(out, align, n) : ENOMEM;
}

void *aligned_alloc(size_t align, size_t n) {
    resolve();
    count(0);
    return real_aligned_alloc ? real_aligned_alloc(align, n) : NULL;
}

void *memalign(size_t align, size_t n) {
    resolve();
    count(0);
    return real_memalign ? real_memalign(align, n) : NULL;
}

void *valloc(size_t n) {
    resolve();
    count(0);
    return real_valloc ? real_valloc(n) : NULL;
}

void *pvalloc(size_t n) {
    resolve();
    count(0);
    return real_pvalloc ? real_pvalloc(n) : NULL;
}

void *mmap(void *addr, size_t n, int prot, int flags, int fd, off_t off) {
    resolve();
    count(2);
    if (!real_mmap) {
        errno = ENOMEM;
        return MAP_FAILED;
    }
    return real_mmap(addr, n, prot, flags, fd, off);
}

int munmap(void *addr, size_t n) {
    resolve();
    count(3);
    if (!real_munmap) {
        errno = EINVAL;
        return -1;
    }
    return real_munmap(addr, n);
}
