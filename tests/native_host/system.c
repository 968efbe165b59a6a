/* A native FMI 2.0 co-simulation master for the tests: several FMUs, fixed
 * step, Gauss-Seidel in the order given, no Python in the process.
 *
 * usage: system PLAN_FILE
 * PLAN_FILE lines (whitespace separated, one item per line):
 *   steps N STEP_SIZE
 *   fmu UNZIPPED_DIR MODEL_IDENTIFIER GUID          (index = order of appearance)
 *   real FMU VR VALUE | int FMU VR VALUE | string FMU VR TEXT   (start values)
 *   link SRC_FMU SRC_VR DST_FMU DST_VR              (Real output -> Real input)
 *   print FMU VR                                    (Real printed after the last step)
 *   latency WARMUP                                  (real-time profile, below)
 *   paced                                           (with latency: one step per period)
 * Inputs are set from their sources before each FMU leaves initialisation and
 * before each FMU's doStep.  Prints "STATUS <fmu> <function> <status>" for
 * every non-OK call, "VALUE <fmu> <vr> <value>" and "DONE <steps>"; exits 0
 * when the run completed, 1 when a call failed, 2 on a usage/loading error.
 *
 * Real-time profile (plan item "latency WARMUP"): after initialisation the
 * chain makes WARMUP untimed steps, then the N steps of "steps", each timed
 * with clock_gettime(CLOCK_MONOTONIC) (one chain step: the link gets/sets and
 * every FMU's doStep) into an array allocated and touched before the warm-up.
 * When the process carries the allocation counter (LD_PRELOAD of
 * alloc_counter.so), it is zeroed after the warm-up and read after every
 * timed step; the last reading is taken before fmi2Terminate.  Prints
 *   ALLOC_STEP <step> <allocs> <frees> <mmaps> <munmaps>   (each timed step that
 *       called the heap or mmap, first MAX_ALLOC_LINES of them; step counted from 0
 *       after the warm-up, values of that step alone)
 *   LATENCY steps=N warmup=K step_s=H p50_ns=.. p99_ns=.. p999_ns=.. max_ns=..
 *       jitter=p99.9/p50 counter=1|0 allocs=.. frees=.. mmaps=.. munmaps=.. alloc_steps=..
 *       max_quiet_ns=.. max_alloc_ns=..
 *       paced=0|1 wake_p50_ns=.. wake_p99_ns=.. wake_max_ns=.. overruns=..
 * (counts -1 without the counter; percentiles by nearest rank; max_quiet_ns is the
 * slowest step that made no heap or mmap call, max_alloc_ns the slowest that did,
 * -1 when there is none).  With "paced", timed step k starts at its deadline
 * (clock_nanosleep, absolute, one communication step apart, timer slack 1 ns;
 * normal scheduling policy, memory not locked): wake_* is how late
 * it started, overruns counts the steps that ended after the next deadline
 * (-1 when not paced).  Without it the steps follow each other at once.
 */
#define _GNU_SOURCE /* RTLD_DEFAULT, clock_gettime */
#include <dlfcn.h>
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <time.h>

#include "fmi2Functions.h"

#define MAXF 8
#define MAXL 64
#define ALLOC_COUNTER_N 4
#define MAX_ALLOC_LINES 1000

typedef void alloc_reset_fn(void);
typedef void alloc_get_fn(unsigned long long out[ALLOC_COUNTER_N]);

typedef struct {
    void *lib;
    fmi2Component c;
    fmi2InstantiateTYPE *instantiate;
    fmi2SetupExperimentTYPE *setup;
    fmi2EnterInitializationModeTYPE *enter;
    fmi2ExitInitializationModeTYPE *exit_;
    fmi2DoStepTYPE *step;
    fmi2TerminateTYPE *terminate;
    fmi2FreeInstanceTYPE *free_;
    fmi2SetRealTYPE *setReal;
    fmi2GetRealTYPE *getReal;
    fmi2SetIntegerTYPE *setInteger;
    fmi2SetStringTYPE *setString;
} Fmu;

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env;
    if (status == fmi2OK) return;
    va_list ap;
    va_start(ap, message);
    printf("LOG %s %d %s: ", name ? name : "", (int)status, category ? category : "");
    vprintf(message, ap);
    printf("\n");
    va_end(ap);
}

static int check(int k, const char *fn, fmi2Status st) {
    if (st != fmi2OK) {
        printf("STATUS %d %s %d\n", k, fn, (int)st);
        return 0;
    }
    return 1;
}

/* FMU k's connected inputs from their sources' current outputs (link rows: source, vr, target, vr). */
static int pass_inputs(Fmu *f, int k, int link[][4], int nl) {
    int ok = 1;
    for (int l = 0; ok && l < nl; l++)
        if (link[l][2] == k) {
            fmi2ValueReference src = (fmi2ValueReference)link[l][1], dst = (fmi2ValueReference)link[l][3];
            fmi2Real v;
            ok = check(link[l][0], "fmi2GetReal", f[link[l][0]].getReal(f[link[l][0]].c, &src, 1, &v)) &&
                 check(k, "fmi2SetReal", f[k].setReal(f[k].c, &dst, 1, &v));
        }
    return ok;
}

/* One Gauss-Seidel step of the chain at time t: each FMU's inputs from their sources, then its doStep. */
static int chain_step(Fmu *f, int nf, int link[][4], int nl, double t, double h) {
    int ok = 1;
    for (int k = 0; ok && k < nf; k++)
        ok = pass_inputs(f, k, link, nl) && check(k, "fmi2DoStep", f[k].step(f[k].c, t, h, fmi2True));
    return ok;
}

static long long now_ns(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (long long)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

static int cmp_ll(const void *a, const void *b) {
    long long x = *(const long long *)a, y = *(const long long *)b;
    return (x > y) - (x < y);
}

/* Nearest-rank percentile q (0 < q <= 1) of sorted[0..n). */
static long long percentile(const long long *sorted, long n, double q) {
    long rank = (long)((double)n * q + 0.999999999);
    if (rank < 1) rank = 1;
    return sorted[(rank > n ? n : rank) - 1];
}

typedef struct {
    long long *lat;                         /* ns, per timed step */
    long long *wake;                        /* ns after the step's deadline it started (paced) */
    unsigned long long (*seen)[ALLOC_COUNTER_N]; /* counter readings after each step */
    long overruns;                          /* paced steps that ended after the next deadline */
} Samples;

/* Sleep until the CLOCK_MONOTONIC time deadline_ns (returns at once when it has passed). */
static void sleep_until(long long deadline_ns) {
    struct timespec ts = {(time_t)(deadline_ns / 1000000000LL), (long)(deadline_ns % 1000000000LL)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) == EINTR) {
    }
}

/* STEPS timed chain steps from step index n0; paced: step k starts at its deadline, one period apart. */
static int timed_steps(Fmu *f, int nf, int link[][4], int nl, long n0, long steps, double h, int paced,
                       alloc_get_fn *get, Samples *s, long *done) {
    int ok = 1;
    long long period = (long long)(h * 1e9 + 0.5), first = now_ns() + period;
    if (paced && prctl(PR_SET_TIMERSLACK, 1UL) != 0) /* wake at the deadline, not up to 50 us after it */
        perror("latency: prctl(PR_SET_TIMERSLACK) failed, default timer slack kept");
    for (long k = 0; ok && k < steps; k++, (*done)++) {
        long long deadline = first + k * period, t0;
        if (paced) {
            sleep_until(deadline);
            t0 = now_ns();
            s->wake[k] = t0 - deadline;
        } else {
            t0 = now_ns();
        }
        ok = chain_step(f, nf, link, nl, (double)(n0 + k) * h, h);
        long long t1 = now_ns();
        s->lat[k] = t1 - t0;
        if (paced && t1 > deadline + period) s->overruns++;
        if (get) get(s->seen[k]);
    }
    return ok;
}

/* Prints the ALLOC_STEP lines; returns the number of steps with heap or mmap calls (-1 without the
 * counter) and sets the slowest of them and the slowest of the others (-1 when there is none). */
static long alloc_steps_report(const Samples *s, long steps, int counted, long long *max_quiet,
                               long long *max_alloc) {
    long n = 0;
    *max_quiet = *max_alloc = -1;
    for (long k = 0; k < steps; k++) {
        unsigned long long d[ALLOC_COUNTER_N] = {0};
        for (int j = 0; counted && j < ALLOC_COUNTER_N; j++) d[j] = s->seen[k][j] - (k ? s->seen[k - 1][j] : 0);
        if (d[0] + d[1] + d[2] + d[3] == 0) {
            if (s->lat[k] > *max_quiet) *max_quiet = s->lat[k];
            continue;
        }
        if (s->lat[k] > *max_alloc) *max_alloc = s->lat[k];
        if (n++ < MAX_ALLOC_LINES) printf("ALLOC_STEP %ld %llu %llu %llu %llu\n", k, d[0], d[1], d[2], d[3]);
    }
    return counted ? n : -1;
}

/* The LATENCY line (sorts the samples). */
static void latency_report(Samples *s, long steps, long warmup, double h, int paced, int counted,
                           const unsigned long long total[ALLOC_COUNTER_N]) {
    long long max_quiet, max_alloc;
    long alloc_steps = alloc_steps_report(s, steps, counted, &max_quiet, &max_alloc);
    qsort(s->lat, (size_t)steps, sizeof *s->lat, cmp_ll);
    long long p50 = percentile(s->lat, steps, 0.50), p99 = percentile(s->lat, steps, 0.99);
    long long p999 = percentile(s->lat, steps, 0.999), max = s->lat[steps - 1];
    long long w50 = -1, w99 = -1, wmax = -1;
    if (paced) {
        qsort(s->wake, (size_t)steps, sizeof *s->wake, cmp_ll);
        w50 = percentile(s->wake, steps, 0.50), w99 = percentile(s->wake, steps, 0.99), wmax = s->wake[steps - 1];
    }
    long long c[ALLOC_COUNTER_N];
    for (int j = 0; j < ALLOC_COUNTER_N; j++) c[j] = counted ? (long long)total[j] : -1;
    printf("LATENCY steps=%ld warmup=%ld step_s=%.17g p50_ns=%lld p99_ns=%lld p999_ns=%lld max_ns=%lld "
           "jitter=%.6g counter=%d allocs=%lld frees=%lld mmaps=%lld munmaps=%lld alloc_steps=%ld "
           "max_quiet_ns=%lld max_alloc_ns=%lld paced=%d wake_p50_ns=%lld wake_p99_ns=%lld wake_max_ns=%lld "
           "overruns=%ld\n",
           steps, warmup, h, p50, p99, p999, max, p50 > 0 ? (double)p999 / (double)p50 : 0.0, counted, c[0], c[1],
           c[2], c[3], alloc_steps, max_quiet, max_alloc, paced, w50, w99, wmax, paced ? s->overruns : -1L);
}

/* The real-time profile: WARMUP untimed steps, then STEPS timed ones (see the header). */
static int profile(Fmu *f, int nf, int link[][4], int nl, long warmup, long steps, double h, int paced,
                   long *done) {
    alloc_reset_fn *reset = (alloc_reset_fn *)dlsym(RTLD_DEFAULT, "alloc_counter_reset");
    alloc_get_fn *get = (alloc_get_fn *)dlsym(RTLD_DEFAULT, "alloc_counter_get");
    int counted = reset != NULL && get != NULL;
    if (steps < 1) {
        fprintf(stderr, "latency: steps must be >= 1\n");
        return 0;
    }
    Samples s = {malloc((size_t)steps * sizeof *s.lat), malloc((size_t)steps * sizeof *s.wake),
                 malloc((size_t)steps * sizeof *s.seen), 0};
    int ok = s.lat && s.wake && s.seen;
    if (!ok) {
        fprintf(stderr, "latency: cannot allocate %ld samples\n", steps);
    } else {
        memset(s.lat, 0, (size_t)steps * sizeof *s.lat); /* touch every page before timing */
        memset(s.wake, 0, (size_t)steps * sizeof *s.wake);
        memset(s.seen, 0, (size_t)steps * sizeof *s.seen);
        for (long n = 0; ok && n < warmup; n++, (*done)++) ok = chain_step(f, nf, link, nl, (double)n * h, h);
        if (ok && counted) reset();
        ok = ok && timed_steps(f, nf, link, nl, warmup, steps, h, paced, counted ? get : NULL, &s, done);
        unsigned long long total[ALLOC_COUNTER_N] = {0};
        if (counted) get(total); /* before fmi2Terminate (the caller's next call) */
        if (ok) latency_report(&s, steps, warmup, h, paced, counted, total);
    }
    free(s.lat);
    free(s.wake);
    free(s.seen);
    return ok;
}

int main(int argc, char **argv) {
    if (argc != 2) {
        fprintf(stderr, "usage: system PLAN_FILE\n");
        return 2;
    }
    FILE *plan = fopen(argv[1], "r");
    if (!plan) {
        perror(argv[1]);
        return 2;
    }
    Fmu f[MAXF];
    int nf = 0, nl = 0, np = 0;
    int link[MAXL][4], printed[MAXL][2];
    long steps = 0, warmup = -1;
    int paced = 0;
    double h = 1.0;
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    char kind[32];
    while (fscanf(plan, "%31s", kind) == 1) {
        if (strcmp(kind, "steps") == 0) {
            if (fscanf(plan, "%ld %lf", &steps, &h) != 2) return 2;
        } else if (strcmp(kind, "fmu") == 0) {
            char dir[2048], model[256], guid[256], path[4096], uri[4096], name[32];
            if (nf == MAXF || fscanf(plan, "%2047s %255s %255s", dir, model, guid) != 3) return 2;
            Fmu *u = &f[nf];
            snprintf(path, sizeof path, "%s/binaries/linux64/%s.so", dir, model);
            u->lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
            if (!u->lib) {
                fprintf(stderr, "%s\n", dlerror());
                return 2;
            }
            u->instantiate = (fmi2InstantiateTYPE *)dlsym(u->lib, "fmi2Instantiate");
            u->setup = (fmi2SetupExperimentTYPE *)dlsym(u->lib, "fmi2SetupExperiment");
            u->enter = (fmi2EnterInitializationModeTYPE *)dlsym(u->lib, "fmi2EnterInitializationMode");
            u->exit_ = (fmi2ExitInitializationModeTYPE *)dlsym(u->lib, "fmi2ExitInitializationMode");
            u->step = (fmi2DoStepTYPE *)dlsym(u->lib, "fmi2DoStep");
            u->terminate = (fmi2TerminateTYPE *)dlsym(u->lib, "fmi2Terminate");
            u->free_ = (fmi2FreeInstanceTYPE *)dlsym(u->lib, "fmi2FreeInstance");
            u->setReal = (fmi2SetRealTYPE *)dlsym(u->lib, "fmi2SetReal");
            u->getReal = (fmi2GetRealTYPE *)dlsym(u->lib, "fmi2GetReal");
            u->setInteger = (fmi2SetIntegerTYPE *)dlsym(u->lib, "fmi2SetInteger");
            u->setString = (fmi2SetStringTYPE *)dlsym(u->lib, "fmi2SetString");
            snprintf(uri, sizeof uri, "file://%s/resources", dir);
            snprintf(name, sizeof name, "fmu%d", nf);
            u->c = u->instantiate(name, fmi2CoSimulation, guid, uri, &cb, fmi2False, fmi2False);
            if (!u->c) {
                printf("STATUS %d fmi2Instantiate NULL\n", nf);
                return 1;
            }
            if (!check(nf, "fmi2SetupExperiment", u->setup(u->c, fmi2False, 0.0, 0.0, fmi2False, 0.0))) return 1;
            nf++;
        } else if (strcmp(kind, "real") == 0 || strcmp(kind, "int") == 0 || strcmp(kind, "string") == 0) {
            int k;
            unsigned vr;
            char text[1024];
            if (fscanf(plan, "%d %u %1023s", &k, &vr, text) != 3 || k >= nf) return 2;
            fmi2ValueReference r = vr;
            fmi2Status st;
            if (kind[0] == 'r') {
                fmi2Real v = atof(text);
                st = f[k].setReal(f[k].c, &r, 1, &v);
            } else if (kind[0] == 'i') {
                fmi2Integer v = atoi(text);
                st = f[k].setInteger(f[k].c, &r, 1, &v);
            } else {
                fmi2String v = text;
                st = f[k].setString(f[k].c, &r, 1, &v);
            }
            if (!check(k, "fmi2Set", st)) return 1;
        } else if (strcmp(kind, "link") == 0) {
            if (nl == MAXL || fscanf(plan, "%d %d %d %d", &link[nl][0], &link[nl][1], &link[nl][2], &link[nl][3]) != 4)
                return 2;
            nl++;
        } else if (strcmp(kind, "latency") == 0) {
            if (fscanf(plan, "%ld", &warmup) != 1 || warmup < 0) return 2;
        } else if (strcmp(kind, "paced") == 0) {
            paced = 1;
        } else if (strcmp(kind, "print") == 0) {
            if (np == MAXL || fscanf(plan, "%d %d", &printed[np][0], &printed[np][1]) != 2) return 2;
            np++;
        } else {
            fprintf(stderr, "unknown plan item %s\n", kind);
            return 2;
        }
    }
    fclose(plan);
    for (int k = 0; k < nf; k++)
        if (!check(k, "fmi2EnterInitializationMode", f[k].enter(f[k].c))) return 1;
    int ok = 1;
    for (int k = 0; ok && k < nf; k++)
        ok = pass_inputs(f, k, link, nl) && check(k, "fmi2ExitInitializationMode", f[k].exit_(f[k].c));
    long done = 0;
    if (warmup < 0) {
        for (long n = 0; ok && n < steps; n++, done++) ok = chain_step(f, nf, link, nl, n * h, h);
    } else {
        ok = ok && profile(f, nf, link, nl, warmup, steps, h, paced, &done);
    }
    for (int p = 0; ok && p < np; p++) {
        fmi2ValueReference vr = (fmi2ValueReference)printed[p][1];
        fmi2Real v;
        ok = check(printed[p][0], "fmi2GetReal", f[printed[p][0]].getReal(f[printed[p][0]].c, &vr, 1, &v));
        if (ok) printf("VALUE %d %d %.17g\n", printed[p][0], printed[p][1], v);
    }
    for (int k = 0; k < nf; k++) {
        if (ok) check(k, "fmi2Terminate", f[k].terminate(f[k].c));
        f[k].free_(f[k].c);
    }
    printf("DONE %ld\n", done);
    return ok ? 0 : 1;
}
