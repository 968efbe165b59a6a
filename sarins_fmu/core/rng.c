/* Seeded random streams: see rng.h. */
#include "smath.h"

#include <stdint.h>

#include "rng.h"

#define PHI UINT64_C(0x9e3779b97f4a7c15)
#define TWO32 4294967296.0
#define TWO53 9007199254740992.0

/* one bits of z */
static int bit_count(uint64_t z) {
    int n = 0;
    for (; z != 0; z &= z - 1) n++;
    return n;
}

/* an odd increment with enough bit transitions (rng.h) */
static uint64_t choose_gamma(uint64_t z) {
    z |= 1u;
    if (bit_count(z ^ (z >> 1)) < 24) z ^= UINT64_C(0xaaaaaaaaaaaaaaaa);
    return z;
}

void sarins_rng_stream(SarinsRng *r, uint64_t seed, uint64_t stream) {
    uint64_t a = sarins_rng_mix(seed + PHI);
    uint64_t b = sarins_rng_mix(a ^ sarins_rng_mix((stream + 1u) * PHI));
    r->key = b;
    r->gamma = choose_gamma(sarins_rng_mix(b + PHI));
    r->count = 0;
    r->spare = 0.0;
    r->has_spare = 0;
}

void sarins_rng_pack(const SarinsRng *r, uint64_t stream, double *words) {
    words[0] = (double)(r->key >> 32);
    words[1] = (double)(r->key & UINT64_C(0xffffffff));
    words[2] = (double)(r->gamma >> 32);
    words[3] = (double)(r->gamma & UINT64_C(0xffffffff));
    words[4] = (double)r->count;
    words[5] = r->spare;
    words[6] = r->has_spare ? 1.0 : 0.0;
    words[7] = (double)stream;
}

/* a whole number in [0, limit) */
static int whole_below(double x, double limit) { return x >= 0.0 && x < limit && sm_floor(x) == x; }

int sarins_rng_unpack(const double *words, SarinsRng *r) {
    for (int i = 0; i < 4; i++) {
        if (!whole_below(words[i], TWO32)) return 0;
    }
    uint64_t gamma = ((uint64_t)words[2] << 32) | (uint64_t)words[3];
    if (!(gamma & 1u) || !whole_below(words[4], TWO53) || !isfinite(words[5])
        || !(words[6] == 0.0 || words[6] == 1.0))
        return 0;
    r->key = ((uint64_t)words[0] << 32) | (uint64_t)words[1];
    r->gamma = gamma;
    r->count = (uint64_t)words[4];
    r->spare = words[5];
    r->has_spare = words[6] == 1.0;
    return 1;
}

void sarins_rng_normals(uint64_t seed, uint64_t stream, int64_t n, double *out) {
    SarinsRng r;
    sarins_rng_stream(&r, seed, stream);
    for (int64_t i = 0; i < n; i++) out[i] = sarins_rng_normal(&r);
}

void sarins_rng_uniforms(uint64_t seed, uint64_t stream, int64_t n, double *out) {
    SarinsRng r;
    sarins_rng_stream(&r, seed, stream);
    for (int64_t i = 0; i < n; i++) out[i] = sarins_rng_uniform(&r);
}

void sarins_rng_start(uint64_t seed, uint64_t stream, double *words) {
    SarinsRng r;
    sarins_rng_stream(&r, seed, stream);
    sarins_rng_pack(&r, stream, words);
}

int sarins_rng_fill_normals(double *words, int64_t n, double *out) {
    SarinsRng r;
    if (!sarins_rng_unpack(words, &r)) return 1;
    for (int64_t i = 0; i < n; i++) out[i] = sarins_rng_normal(&r);
    double stream = words[7]; /* kept as it was */
    sarins_rng_pack(&r, 0u, words);
    words[7] = stream;
    return 0;
}
