/* A fixed set of worker threads that split a range of independent items with the calling thread.
 *
 * sarins_workers_run(w, fn, arg, n) cuts [0, n) into w's thread count of contiguous chunks, chunk i the
 * items [n i / T, n (i + 1) / T); the caller runs chunk 0 and the workers the others, and the call returns
 * when every chunk is done.  Each item must depend on nothing another chunk writes: then the results are
 * those of fn(arg, 0, n) on one thread, bit for bit, whatever the thread count.
 *
 * The threads are created by sarins_workers_start and joined by sarins_workers_stop; nothing is allocated
 * in between.  POSIX threads (pthreads) or the Windows API.  On Linux the pthread functions are weak
 * references bound to glibc's oldest symbol versions (x86-64 GLIBC_2.2.5, aarch64 GLIBC_2.17): a library
 * using this file loads on glibc 2.17, and where the process has no thread functions (glibc before 2.34
 * without libpthread loaded) sarins_workers_start starts no thread and every run is serial, with the
 * same results.  No globals.
 */
#ifndef SARINS_WORKERS_H
#define SARINS_WORKERS_H

#include <stdint.h>

#define SARINS_WORKERS_MAX 64 /* threads of one set, the caller's included */

typedef struct sarins_workers sarins_workers;

/* Items [k0, k1) of a run; arg is the run's argument. */
typedef void (*sarins_workers_fn)(void *arg, int64_t k0, int64_t k1);

/* A set of n_threads threads, the caller's included (1 .. SARINS_WORKERS_MAX; 1 starts none): the set, or
 * NULL when out of memory or n_threads is out of range.  *started gets the number of threads in use
 * (the caller's included), which is smaller than n_threads when the system refused a thread or has no
 * thread functions. */
sarins_workers *sarins_workers_start(int n_threads, int *started);

/* fn over [0, n) on the set's threads (see the top); w NULL runs fn(arg, 0, n) on the caller. */
void sarins_workers_run(sarins_workers *w, sarins_workers_fn fn, void *arg, int64_t n);

/* Join the threads and free the set (NULL: nothing). */
void sarins_workers_stop(sarins_workers *w);

#endif
