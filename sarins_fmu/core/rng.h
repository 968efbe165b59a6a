/* Seeded random streams of the C core: uniform and standard normal draws.
 *
 * Generator: SplitMix64 (G. L. Steele, D. Lea, C. H. Flood, "Fast splittable
 * pseudorandom number generators", OOPSLA 2014), written as a counter-based
 * generator.  Draw i (i = 1, 2, ...) of a stream with key K and odd
 * increment G is
 *     x_i = mix(K + i G)                       (all arithmetic mod 2^64)
 *     mix(z): z = (z ^ z >> 30) * 0xbf58476d1ce4e5b9;
 *             z = (z ^ z >> 27) * 0x94d049bb133111eb;  z ^ z >> 31
 * (mix is Stafford's "variant 13" 64-bit finaliser, a bijection).  Since G is
 * odd, i -> K + i G visits every 64-bit value once: the period of a stream is
 * 2^64 draws.  The state of a stream is (K, G, i) and the spare normal of
 * the last polar pair, so a run continued in pieces of any length draws the
 * same numbers as one run, and the state is a few words (saved with the
 * component, no hidden state anywhere: no globals, reentrant).
 *
 * Streams: one per purpose and seed.  From a 64-bit seed s and a stream id n
 *     a = mix(s + phi),   b = mix(a ^ mix((n + 1) phi)),
 *     K = b,   G = gamma(mix(b + phi))
 * with phi = 0x9e3779b97f4a7c15 (2^64 / golden ratio) and gamma(z) the
 * increment chooser of java.util.SplittableRandom: z | 1, and z ^
 * 0xaaaaaaaaaaaaaaaa when z ^ (z >> 1) has fewer than 24 one bits (an
 * increment with few bit transitions makes a poor Weyl sequence).  Streams
 * of different (s, n) differ in key and increment: they are different
 * sequences, not shifted copies of one.
 *
 * Uniform: u = (x >> 11) 2^-53 in [0, 1), 53 random bits.
 * Normal: Marsaglia's polar method (Marsaglia & Bray, SIAM Review 6(3),
 * 1964): v1, v2 = 2u - 1 from two draws, s = v1^2 + v2^2, rejected unless
 * 0 < s < 1 (accepted with probability pi/4); then v1 f and v2 f with
 * f = sqrt(-2 ln s / s) are two independent N(0, 1) values: the first is
 * returned, the second kept as the spare for the next call.
 */
#ifndef SARINS_RNG_H
#define SARINS_RNG_H

#include "smath.h"
#include <stdint.h>

typedef struct {
    uint64_t key;   /* K: start of the Weyl sequence */
    uint64_t gamma; /* G: odd increment */
    uint64_t count; /* i: 64-bit draws made so far */
    double spare;   /* the second normal of the last polar pair */
    int has_spare;  /* 1 when spare is unused */
} SarinsRng;

/* Words of a stream's state packed into float64 (sarins_rng_pack): key and
 * increment as 32-bit halves (high, low), the draw count (exact below 2^53),
 * the spare normal, the spare flag, and the stream id (for reading). */
#define SARINS_RNG_WORDS 8

/* mix(z), the finaliser above */
static inline uint64_t sarins_rng_mix(uint64_t z) {
    z = (z ^ (z >> 30)) * UINT64_C(0xbf58476d1ce4e5b9);
    z = (z ^ (z >> 27)) * UINT64_C(0x94d049bb133111eb);
    return z ^ (z >> 31);
}

/* the next 64-bit draw x_i */
static inline uint64_t sarins_rng_next(SarinsRng *r) {
    r->count += 1;
    return sarins_rng_mix(r->key + r->count * r->gamma);
}

/* uniform in [0, 1) */
static inline double sarins_rng_uniform(SarinsRng *r) { return (double)(sarins_rng_next(r) >> 11) / 9007199254740992.0; }

/* standard normal N(0, 1), polar method */
static inline double sarins_rng_normal(SarinsRng *r) {
    if (r->has_spare) {
        r->has_spare = 0;
        return r->spare;
    }
    double v1, v2, s;
    do {
        v1 = 2.0 * sarins_rng_uniform(r) - 1.0;
        v2 = 2.0 * sarins_rng_uniform(r) - 1.0;
        s = v1 * v1 + v2 * v2;
    } while (s >= 1.0 || s == 0.0);
    double f = sm_sqrt(-2.0 * sm_log(s) / s);
    r->spare = v2 * f;
    r->has_spare = 1;
    return v1 * f;
}

/* The stream n of seed s, at its start (no draw made). */
/* 1 when r is a state a stream can be in (a state check after a deserialisation): an even increment
 * repeats its draws within 2^63 of them, 0 repeats one, which the polar method may reject for ever. */
static inline int sarins_rng_valid(const SarinsRng *r) {
    return (r->gamma & 1u) && (r->has_spare == 0 || r->has_spare == 1) && isfinite(r->spare);
}

void sarins_rng_stream(SarinsRng *r, uint64_t seed, uint64_t stream);

/* State <-> SARINS_RNG_WORDS float64 words (stream: the id recorded in the
 * last word).  unpack returns 0 and leaves r untouched when the words are
 * not a packed state (halves outside [0, 2^32) or not whole, an even
 * increment, a count outside [0, 2^53), a non-finite spare, a flag not 0/1). */
void sarins_rng_pack(const SarinsRng *r, uint64_t stream, double *words);
int sarins_rng_unpack(const double *words, SarinsRng *r);

/* Binding helpers (tests, one-off draws): n standard normals (normals) or
 * uniforms in [0, 1) (uniforms) from the start of stream `stream` of `seed`. */
void sarins_rng_normals(uint64_t seed, uint64_t stream, int64_t n, double *out);
void sarins_rng_uniforms(uint64_t seed, uint64_t stream, int64_t n, double *out);

/* The packed state of stream `stream` of `seed` at its start. */
void sarins_rng_start(uint64_t seed, uint64_t stream, double *words);

/* Continue a packed stream state: n standard normals into out, the state
 * words updated.  Returns 0, or 1 (nothing drawn) when the words are not a
 * packed state. */
int sarins_rng_fill_normals(double *words, int64_t n, double *out);

#endif
