/* Worker threads splitting a range with the caller (workers.h). */
#if !defined(_WIN32)
#define _POSIX_C_SOURCE 200809L /* pthreads under -std=c11 */
#endif
#include "smath.h"

#include <stdlib.h>

#include "workers.h"

#if defined(_WIN32)
#include <windows.h>
typedef HANDLE sw_thread;
typedef CRITICAL_SECTION sw_mutex;
typedef CONDITION_VARIABLE sw_cond;
#else
#include <pthread.h>
#include <unistd.h> /* sysconf */
typedef pthread_t sw_thread;
typedef pthread_mutex_t sw_mutex;
typedef pthread_cond_t sw_cond;
/* A sanitizer's runtime intercepts the pthread functions under their plain names: no versions, no weak refs */
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define SW_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define SW_SANITIZED 1
#endif
#endif
#if defined(__linux__) && defined(__GLIBC__) && !defined(SW_SANITIZED)
/* Weak: absent (NULL) in a glibc before 2.34 that has not loaded libpthread; then no thread is started. */
#pragma weak pthread_create
#pragma weak pthread_join
#pragma weak pthread_mutex_init
#pragma weak pthread_mutex_destroy
#pragma weak pthread_mutex_lock
#pragma weak pthread_mutex_unlock
#pragma weak pthread_cond_init
#pragma weak pthread_cond_destroy
#pragma weak pthread_cond_wait
#pragma weak pthread_cond_broadcast
#pragma weak pthread_cond_signal
/* glibc's oldest versions of the functions that moved into libc in 2.34 (a new default version there) */
#if defined(__x86_64__)
#define SW_OLD "GLIBC_2.2.5"
#define SW_COND "GLIBC_2.3.2" /* the condition variables' current ABI */
#elif defined(__aarch64__)
#define SW_OLD "GLIBC_2.17"
#define SW_COND "GLIBC_2.17"
#endif
#if defined(SW_OLD)
__asm__(".symver pthread_create,pthread_create@" SW_OLD);
__asm__(".symver pthread_join,pthread_join@" SW_OLD);
__asm__(".symver pthread_mutex_init,pthread_mutex_init@" SW_OLD);
__asm__(".symver pthread_mutex_destroy,pthread_mutex_destroy@" SW_OLD);
__asm__(".symver pthread_mutex_lock,pthread_mutex_lock@" SW_OLD);
__asm__(".symver pthread_mutex_unlock,pthread_mutex_unlock@" SW_OLD);
__asm__(".symver pthread_cond_init,pthread_cond_init@" SW_COND);
__asm__(".symver pthread_cond_destroy,pthread_cond_destroy@" SW_COND);
__asm__(".symver pthread_cond_wait,pthread_cond_wait@" SW_COND);
__asm__(".symver pthread_cond_broadcast,pthread_cond_broadcast@" SW_COND);
__asm__(".symver pthread_cond_signal,pthread_cond_signal@" SW_COND);
#endif
#define SW_HAVE_THREADS() (pthread_create != NULL && pthread_join != NULL && pthread_mutex_init != NULL \
    && pthread_mutex_destroy != NULL && pthread_mutex_lock != NULL && pthread_mutex_unlock != NULL \
    && pthread_cond_init != NULL && pthread_cond_destroy != NULL && pthread_cond_wait != NULL \
    && pthread_cond_broadcast != NULL && pthread_cond_signal != NULL)
#endif
#endif
#if !defined(SW_HAVE_THREADS)
#define SW_HAVE_THREADS() 1
#endif

/* Atomic reads and writes of the counters a waiting thread polls before it sleeps (the mutex still orders
 * everything else). */
#if defined(_MSC_VER)
#include <intrin.h>
static uint64_t load(const volatile uint64_t *x)
{
    return (uint64_t)InterlockedCompareExchange64((volatile LONG64 *)x, 0, 0);
}
static void store(volatile uint64_t *x, uint64_t v) { InterlockedExchange64((volatile LONG64 *)x, (LONG64)v); }
static void relax(void) { YieldProcessor(); }
#else
static uint64_t load(const volatile uint64_t *x) { return __atomic_load_n(x, __ATOMIC_ACQUIRE); }
static void store(volatile uint64_t *x, uint64_t v) { __atomic_store_n(x, v, __ATOMIC_RELEASE); }
#if defined(__x86_64__) || defined(__i386__)
static void relax(void) { __builtin_ia32_pause(); }
#elif defined(__aarch64__)
static void relax(void) { __asm__ __volatile__("yield"); }
#else
static void relax(void) {}
#endif
#endif

/* Polls of a counter before a thread sleeps on the condition variable: a step's next run (or the end of the
 * other chunks) usually comes within tens of microseconds, sooner than a sleeping thread wakes up.  None when
 * the set has more threads than the machine has processors (a polling thread would hold one a worker needs). */
#define SPINS 2000

#if defined(_WIN32)
static int processors(void)
{
    SYSTEM_INFO info;
    GetSystemInfo(&info);
    return (int)info.dwNumberOfProcessors;
}
#else
static int processors(void) { return (int)sysconf(_SC_NPROCESSORS_ONLN); }
#endif

typedef struct {
    sarins_workers *set;
    int index; /* the chunk this thread runs: 1 .. threads - 1 */
} sw_slot;

struct sarins_workers {
    int threads;          /* in use, the caller's included */
    int spins;            /* polls before sleeping: SPINS, or 0 when threads > processors */
    int mutex_ready, go_ready, done_ready;
    sw_mutex mutex;
    sw_cond go, done;     /* a run posted / every chunk done */
    volatile uint64_t generation; /* runs posted so far */
    volatile uint64_t pending;    /* worker chunks of the current run not done */
    volatile uint64_t quit;
    sarins_workers_fn fn;
    void *arg;
    int64_t n;
    sw_thread thread[SARINS_WORKERS_MAX];
    sw_slot slot[SARINS_WORKERS_MAX];
};

#if defined(_WIN32)
static int mutex_init(sw_mutex *m) { InitializeCriticalSection(m); return 1; }
static void mutex_destroy(sw_mutex *m) { DeleteCriticalSection(m); }
static void lock(sw_mutex *m) { EnterCriticalSection(m); }
static void unlock(sw_mutex *m) { LeaveCriticalSection(m); }
static int cond_init(sw_cond *c) { InitializeConditionVariable(c); return 1; }
static void cond_destroy(sw_cond *c) { (void)c; }
static void cond_wait(sw_cond *c, sw_mutex *m) { SleepConditionVariableCS(c, m, INFINITE); }
static void cond_broadcast(sw_cond *c) { WakeAllConditionVariable(c); }
static void cond_signal(sw_cond *c) { WakeConditionVariable(c); }
#else
static int mutex_init(sw_mutex *m) { return pthread_mutex_init(m, NULL) == 0; }
static void mutex_destroy(sw_mutex *m) { pthread_mutex_destroy(m); }
static void lock(sw_mutex *m) { pthread_mutex_lock(m); }
static void unlock(sw_mutex *m) { pthread_mutex_unlock(m); }
static int cond_init(sw_cond *c) { return pthread_cond_init(c, NULL) == 0; }
static void cond_destroy(sw_cond *c) { pthread_cond_destroy(c); }
static void cond_wait(sw_cond *c, sw_mutex *m) { pthread_cond_wait(c, m); }
static void cond_broadcast(sw_cond *c) { pthread_cond_broadcast(c); }
static void cond_signal(sw_cond *c) { pthread_cond_signal(c); }
#endif

/* Chunk i of [0, n) among t: [n i / t, n (i + 1) / t) (n < 2^62 so the products do not overflow). */
static void run_chunk(sarins_workers_fn fn, void *arg, int64_t n, int i, int t)
{
    int64_t k0 = n / t * i + n % t * i / t, k1 = n / t * (i + 1) + n % t * (i + 1) / t;
    if (k1 > k0)
        fn(arg, k0, k1);
}

static void work_loop(sw_slot *slot)
{
    sarins_workers *w = slot->set;
    uint64_t seen = 0;
    for (;;) {
        for (int i = 0; i < w->spins && load(&w->generation) == seen && !load(&w->quit); i++)
            relax();
        lock(&w->mutex);
        while (load(&w->generation) == seen && !load(&w->quit))
            cond_wait(&w->go, &w->mutex);
        if (load(&w->quit))
            break;
        seen = load(&w->generation);
        sarins_workers_fn fn = w->fn;
        void *arg = w->arg;
        int64_t n = w->n;
        int threads = w->threads;
        unlock(&w->mutex);
        run_chunk(fn, arg, n, slot->index, threads);
        lock(&w->mutex);
        uint64_t left = load(&w->pending) - 1;
        store(&w->pending, left);
        if (left == 0)
            cond_signal(&w->done);
        unlock(&w->mutex);
    }
    unlock(&w->mutex);
}

#if defined(_WIN32)
static DWORD WINAPI thread_main(LPVOID p) { work_loop(p); return 0; }
static int spawn(sw_thread *t, sw_slot *slot)
{
    *t = CreateThread(NULL, 0, thread_main, slot, 0, NULL);
    return *t != NULL;
}
static void join(sw_thread t) { WaitForSingleObject(t, INFINITE); CloseHandle(t); }
#else
static void *thread_main(void *p) { work_loop(p); return NULL; }
static int spawn(sw_thread *t, sw_slot *slot) { return pthread_create(t, NULL, thread_main, slot) == 0; }
static void join(sw_thread t) { pthread_join(t, NULL); }
#endif

sarins_workers *sarins_workers_start(int n_threads, int *started)
{
    if (started != NULL)
        *started = 0;
    if (n_threads < 1 || n_threads > SARINS_WORKERS_MAX)
        return NULL;
    sarins_workers *w = calloc(1, sizeof *w);
    if (w == NULL)
        return NULL;
    w->threads = 1;
    w->spins = n_threads <= processors() ? SPINS : 0;
    if (n_threads > 1 && SW_HAVE_THREADS()) {
        w->mutex_ready = mutex_init(&w->mutex);
        w->go_ready = w->mutex_ready && cond_init(&w->go);
        w->done_ready = w->go_ready && cond_init(&w->done);
        /* threads - 1 is read by the running workers only after a run is posted: set it before any runs */
        for (int i = 1; w->done_ready && i < n_threads; i++) {
            w->slot[i].set = w;
            w->slot[i].index = i;
            if (!spawn(&w->thread[i], &w->slot[i]))
                break;
            w->threads = i + 1;
        }
    }
    if (started != NULL)
        *started = w->threads;
    return w;
}

void sarins_workers_run(sarins_workers *w, sarins_workers_fn fn, void *arg, int64_t n)
{
    if (n < 1)
        return;
    if (w == NULL || w->threads == 1) {
        fn(arg, 0, n);
        return;
    }
    lock(&w->mutex);
    w->fn = fn;
    w->arg = arg;
    w->n = n;
    store(&w->pending, (uint64_t)(w->threads - 1));
    store(&w->generation, load(&w->generation) + 1);
    cond_broadcast(&w->go);
    unlock(&w->mutex);
    run_chunk(fn, arg, n, 0, w->threads);
    for (int i = 0; i < w->spins && load(&w->pending) > 0; i++)
        relax();
    lock(&w->mutex);
    while (load(&w->pending) > 0)
        cond_wait(&w->done, &w->mutex);
    unlock(&w->mutex);
}

void sarins_workers_stop(sarins_workers *w)
{
    if (w == NULL)
        return;
    if (w->threads > 1) {
        lock(&w->mutex);
        store(&w->quit, 1);
        cond_broadcast(&w->go);
        unlock(&w->mutex);
        for (int i = 1; i < w->threads; i++)
            join(w->thread[i]);
    }
    if (w->done_ready)
        cond_destroy(&w->done);
    if (w->go_ready)
        cond_destroy(&w->go);
    if (w->mutex_ready)
        mutex_destroy(&w->mutex);
    free(w);
}
