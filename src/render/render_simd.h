/* Eight-lane float vectors (GCC vector extensions) for the rasterizer's fragment fill, the
 * shading and the relief family's searches: the same source compiles to AVX on x86-64 and to
 * pairs of SSE/NEON ops elsewhere. */
#ifndef MESO_RENDER_SIMD_H
#define MESO_RENDER_SIMD_H

#include <math.h>
#include <stdint.h>
#if defined(__AVX__)
#include <immintrin.h>
#endif

#include "meso/geom.h"

typedef float v8f __attribute__((vector_size(32)));
typedef int32_t v8i __attribute__((vector_size(32)));
#define V8_LANES 8

static inline v8f v8_splat(float x) { return (v8f){x, x, x, x, x, x, x, x}; }
static inline v8i v8i_splat(int32_t x) { return (v8i){x, x, x, x, x, x, x, x}; }

/* mask ? a : b per lane (mask lanes all ones or all zeros, as vector comparisons give). */
static inline v8f v8_select(v8i mask, v8f a, v8f b) {
    return (v8f)(((v8i)a & mask) | ((v8i)b & ~mask));
}

/* Correctly rounded square root per lane (IEEE, like sqrtf), without errno handling. */
static inline v8f v8_sqrt(v8f x) {
#if defined(__AVX__)
    return (v8f)_mm256_sqrt_ps((__m256)x);
#else
    v8f r;
    for (int i = 0; i < V8_LANES; i++) r[i] = __builtin_sqrtf(x[i] < 0.0f ? NAN : x[i]);
    return r;
#endif
}

/* floor per lane. */
static inline v8f v8_floor(v8f x) {
#if defined(__AVX__)
    return (v8f)_mm256_floor_ps((__m256)x);
#else
    v8f r;
    for (int i = 0; i < V8_LANES; i++) r[i] = floorf(x[i]);
    return r;
#endif
}

static inline v8f v8_min(v8f a, v8f b) { return v8_select(a < b, a, b); }
static inline v8f v8_max(v8f a, v8f b) { return v8_select(a > b, a, b); }

/* Lane k's mask as bit k, and back. */
static inline int v8_mask_bits(v8i mask) {
#if defined(__AVX__)
    return _mm256_movemask_ps((__m256)mask);
#else
    int bits = 0;
    for (int k = 0; k < V8_LANES; ++k) bits |= (mask[k] != 0) << k;
    return bits;
#endif
}
static inline v8i v8_mask_from_bits(int bits) {
    const v8i lane_bit = {1, 2, 4, 8, 16, 32, 64, 128};
    return (v8i_splat(bits) & lane_bit) != 0;
}

/* base[index[k]] per lane. */
static inline v8f v8_gather(const float *base, v8i index) {
#if defined(__AVX2__)
    return (v8f)_mm256_i32gather_ps(base, (__m256i)index, 4);
#else
    v8f r;
    for (int k = 0; k < V8_LANES; ++k) r[k] = base[index[k]];
    return r;
#endif
}

/* base[index[k]] per lane, 32-bit integers. */
static inline v8i v8i_gather(const int32_t *base, v8i index) {
#if defined(__AVX2__)
    return (v8i)_mm256_i32gather_epi32((const int *)base, (__m256i)index, 4);
#else
    v8i r;
    for (int k = 0; k < V8_LANES; ++k) r[k] = base[index[k]];
    return r;
#endif
}

/* base[index[k]] in *left and base[index[k] + 1] in *right per lane (any 32-bit values, as
 * float bits), by one 8-byte load a lane instead of gathers: on an AVX-512 machine
 * the gathers of a lookup outside a dependent chain cost more time than the loads, the index
 * extraction and the shuffles together (more instructions, though: callgrind counts a gather
 * as one). */
static inline void v8_load_pairs(const float *base, v8i index, v8f *left, v8f *right) {
#if defined(__AVX2__)
    /* pairs of lanes k, k + 1 in the low half, of k + 4, k + 5 in the high one: one shuffle
     * then picks every lane's first element, another its second */
    __m256 pairs[2];
#pragma GCC unroll 2
    for (int k = 0; k < 2; k++) {
        __m128 lo =
            _mm_loadl_pi(_mm_setzero_ps(), (const __m64 *)(const void *)(base + index[2 * k]));
        lo = _mm_loadh_pi(lo, (const __m64 *)(const void *)(base + index[2 * k + 1]));
        __m128 hi =
            _mm_loadl_pi(_mm_setzero_ps(), (const __m64 *)(const void *)(base + index[2 * k + 4]));
        hi = _mm_loadh_pi(hi, (const __m64 *)(const void *)(base + index[2 * k + 5]));
        pairs[k] = _mm256_insertf128_ps(_mm256_castps128_ps256(lo), hi, 1);
    }
    *left = (v8f)_mm256_shuffle_ps(pairs[0], pairs[1], 0x88);
    *right = (v8f)_mm256_shuffle_ps(pairs[0], pairs[1], 0xdd);
#else
    for (int k = 0; k < V8_LANES; ++k)
        (*left)[k] = base[index[k]], (*right)[k] = base[index[k] + 1];
#endif
}

static inline int v8_any(v8i mask) {
    return ((mask[0] | mask[1]) | (mask[2] | mask[3])) |
           ((mask[4] | mask[5]) | (mask[6] | mask[7]));
}

/* Eight 3-vectors as vectors of their components. */
typedef struct v8vec3 {
    v8f x, y, z;
} v8vec3;

static inline v8f v8_dot(v8vec3 a, v8vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline v8vec3 v8_cross(v8vec3 a, v8vec3 b) {
    return (v8vec3){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
static inline v8vec3 v8_madd(v8vec3 a, v8vec3 b, v8f s) {
    return (v8vec3){a.x + b.x * s, a.y + b.y * s, a.z + b.z * s};
}
static inline v8vec3 v8_splat3(meso_vec3 a) {
    return (v8vec3){v8_splat(a.x), v8_splat(a.y), v8_splat(a.z)};
}

#endif
