/* smath: the core's own portable, deterministic math functions (no libm).
 *
 * Every C file of the core and of the native FMUs includes this header FIRST (before any other
 * header and any code) and calls these functions instead of <math.h>'s: the results are then the same
 * bits on every platform, compiler and compile line (gcc, clang, mingw-w64, MSVC; x86-64, aarch64;
 * -O0 .. -O3, -march=native, -std=c11 or gnu11), and a binary needs no libm (no GLIBC_2.29 exp/log/pow,
 * no GLIBC_2.35 hypot).  Only the classification macros of <math.h> (isfinite, isnan, isinf, signbit,
 * NAN, INFINITY, HUGE_VAL) may still be used.
 *
 * The header also fixes the floating-point contract of the file that includes it: no contraction of
 * a * b + c into a fused multiply-add (C's FP_CONTRACT OFF; gcc ignores that pragma, hence its own),
 * so that every expression rounds each operation as written.  It refuses to compile with -ffast-math
 * (which breaks IEEE semantics) and where double expressions are evaluated in a wider format
 * (FLT_EVAL_METHOD != 0: 32-bit x86 without SSE2).
 *
 * Accuracy (measured against mpmath by benchmarks/smath_accuracy.py): sqrt, fma, fabs, floor, ceil,
 * trunc, round, nearbyint, fmod, fmin, fmax, copysign exact (correctly rounded); the others below
 * one ulp, stated at each.  Special values (+-0, +-inf, NaN, subnormals) follow C's Annex F; errno
 * is never set.
 */
#ifndef SARINS_SMATH_H
#define SARINS_SMATH_H

#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#elif defined(__GNUC__)
#pragma GCC optimize("fp-contract=off")
#elif defined(_MSC_VER)
#pragma fp_contract(off)
#else
#pragma STDC FP_CONTRACT OFF
#endif

#if defined(__FAST_MATH__)
#error "sarins core: -ffast-math / -Ofast change the results; compile without them"
#endif

#include <float.h>
#include <stdint.h>
#include <math.h> /* isfinite, isnan, isinf, signbit, NAN, INFINITY, HUGE_VAL only */

/* 16 (ISO/IEC TS 18661-3): only _Float16 is widened, to float; float and double as with 0 (gcc in GNU mode
   with -march=native on a CPU with AVX512-FP16). */
#if defined(FLT_EVAL_METHOD) && FLT_EVAL_METHOD != 0 && FLT_EVAL_METHOD != -1 && FLT_EVAL_METHOD != 16
#error "sarins core: needs double expressions evaluated in double (FLT_EVAL_METHOD 0); on 32-bit x86 add -msse2 -mfpmath=sse"
#endif

/* exact (correctly rounded, as IEEE 754 requires of these) */
double sm_sqrt(double x);
double sm_fma(double a, double b, double c); /* a b + c rounded once */
/* fabs, copysign, fmin, fmax: inline (they sit in SIMD loops; a call would stop the vectorizer) */
typedef union {
    double d;
    uint64_t u;
} sm_bits64;

static inline double sm_fabs(double x)
{
#if defined(__GNUC__)
    return __builtin_fabs(x); /* a bit operation, never a call */
#else
    sm_bits64 b;
    b.d = x;
    b.u &= 0x7fffffffffffffffull;
    return b.d;
#endif
}

static inline double sm_copysign(double x, double y)
{
#if defined(__GNUC__)
    return __builtin_copysign(x, y);
#else
    sm_bits64 a, b;
    a.d = x;
    b.d = y;
    a.u = (a.u & 0x7fffffffffffffffull) | (b.u & 0x8000000000000000ull);
    return a.d;
#endif
}

static inline double sm_fmin(double x, double y) /* a NaN argument gives the other */
{
    return isnan(x) ? y : isnan(y) ? x : x < y ? x : y;
}

static inline double sm_fmax(double x, double y)
{
    return isnan(x) ? y : isnan(y) ? x : x > y ? x : y;
}

double sm_floor(double x);
double sm_ceil(double x);
double sm_trunc(double x);
double sm_round(double x);     /* halfway cases away from zero */
double sm_nearbyint(double x); /* halfway cases to even (the default rounding mode) */
double sm_fmod(double x, double y);

/* below one ulp (the largest error measured is stated in benchmarks/smath_accuracy.py's table) */
double sm_sin(double x); /* any finite x: exact range reduction by pi/2 */
double sm_cos(double x);
void sm_sincos(double x, double *s, double *c); /* *s = sm_sin(x), *c = sm_cos(x), one reduction */
void sm_sincos4(const double *x, double *s, double *c); /* sm_sincos of x[0..3], in SIMD lanes where it can */
double sm_tan(double x);
double sm_exp(double x);
double sm_exp10(double x); /* 10^x */
double sm_log(double x);
double sm_log10(double x);
double sm_atan(double x);
double sm_atan2(double y, double x);
double sm_asin(double x);
double sm_acos(double x);
double sm_hypot(double x, double y);
double sm_tanh(double x);
double sm_pow(double x, double y); /* the special cases of C's Annex F */

/* tanh of x[0..n-1] into y (y may be x), below 3 ulp (not sm_tanh's bits): branch-free, in SIMD lanes where it
 * can (the same bits in every lane and on every platform); the recurrent networks' gates (nets.c) */
void sm_tanh_lanes(int64_t n, const double *x, double *y);

/* sm_exp of x[0..n-1] into y (y may be x), the same bits: in SIMD lanes where it can (the GRNN kernels) */
void sm_exp_lanes(int64_t n, const double *x, double *y);

/* Every function above over n arguments, for the tests and benchmarks (through the Python binding):
 * func is the index of the function in SARINS_SMATH_NAMES (x, y, z: first, second, third argument, NULL
 * where unused); out[n] the results (sincos, sincos4: out[2n], sin then cos of each x; tanhv: sm_tanh_lanes; expv: sm_exp_lanes; soft_sqrt, soft_fma: the
 * software versions of sm_sqrt and sm_fma, which use the hardware instruction where there is one).  Returns 0, or -1 for an unknown func
 * or n < 0. */
#define SARINS_SMATH_NAMES                                                                                  \
    "sqrt fma fabs copysign fmin fmax floor ceil trunc round nearbyint fmod sin cos sincos tan exp exp10 "  \
    "log log10 atan atan2 asin acos hypot soft_sqrt soft_fma sincos4 tanh pow tanhv expv"
int sarins_smath_eval(int func, int64_t n, const double *x, const double *y, const double *z, double *out);

#endif
