/* The gdm technique's 8-wide lookup of a compressed GDM (private to src/techniques and
 * its test): the same d as meso_gdm_lookup (bake_gdm.h: axes, interpolation over x, y, z,
 * theta and phi, §4.1's d = sum_i W_i(x, y, phi) E_i(z, theta)), from a copy of the view laid
 * out for vector loads: W padded to whole groups of 8 eigen-maps a row, E transposed so that
 * one (z, theta) column's k values are adjacent. The W of the 8 (x, y, phi) corners are
 * blended first and dotted once with the blended E: 8 + 4 vector multiply-adds and one
 * horizontal sum instead of 8 x (4 + 1) k scalar ones. */
#ifndef MESO_GDM_LOOKUP_H
#define MESO_GDM_LOOKUP_H

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "meso/bake_gdm.h"
#include "render_simd.h"

#define GDM_LOOKUP_MAX_CHUNKS (MESO_GDM_MAX_EIGEN / 8)

typedef struct gdm_lookup_table {
    int width, height, layers, num_theta, num_phi;
    int num_eigen;  /* k used (<= the map's) */
    int chunks;     /* groups of 8 eigen-maps */
    float *weights; /* [height][width][num_phi][8 chunks], zero past k */
    float *eigen;   /* [layers][num_theta][8 chunks]: E transposed, zero past k */
} gdm_lookup_table;

/* Lay out the view's first num_eigen eigen-maps (0 or more than stored: all). false when out
 * of memory. */
static inline bool gdm_lookup_table_init(gdm_lookup_table *t, const meso_gdm_view *v,
                                         int num_eigen) {
    memset(t, 0, sizeof *t);
    int k = num_eigen <= 0 || num_eigen > v->num_eigen ? v->num_eigen : num_eigen;
    t->width = v->width, t->height = v->height, t->layers = v->layers;
    t->num_theta = v->num_theta, t->num_phi = v->num_phi;
    t->num_eigen = k;
    t->chunks = (k + 7) / 8;
    int lanes = 8 * t->chunks;
    size_t rows = (size_t)v->width * (size_t)v->height * (size_t)v->num_phi;
    size_t columns = (size_t)v->layers * (size_t)v->num_theta;
    t->weights = calloc(rows * (size_t)lanes, sizeof(float));
    t->eigen = calloc(columns * (size_t)lanes, sizeof(float));
    if (!t->weights || !t->eigen) return false;
    for (size_t r = 0; r < rows; r++)
        memcpy(t->weights + r * (size_t)lanes, v->weights + r * (size_t)v->num_eigen,
               sizeof(float) * (size_t)k);
    for (int e = 0; e < k; e++)
        for (size_t c = 0; c < columns; c++)
            t->eigen[c * (size_t)lanes + (size_t)e] = v->eigen[(size_t)e * columns + c];
    return true;
}

static inline void gdm_lookup_table_deinit(gdm_lookup_table *t) {
    free(t->weights);
    free(t->eigen);
    memset(t, 0, sizeof *t);
}

static inline size_t gdm_lookup_table_bytes(const gdm_lookup_table *t) {
    size_t lanes = 8 * (size_t)t->chunks;
    return ((size_t)t->width * t->height * t->num_phi + (size_t)t->layers * t->num_theta) * lanes *
           sizeof(float);
}

/* fminf and fmaxf with libm's results, NaNs included (glibc's x86-64 minss/maxss: the second
 * operand when equal, the other operand when one is a NaN; of two zeros C allows either),
 * inline: without -ffinite-math-only the compiler calls libm for them, 5 instructions and a
 * call each, and the hot paths call them millions of times a frame. */
static inline float gdm_fminf(float a, float b) { return a < b || b != b ? a : b; }
static inline float gdm_fmaxf(float a, float b) { return a > b || b != b ? a : b; }

static inline float gdm_tile_fraction(float x) {
    if (!isfinite(x)) return 0.0f;
    float f = x - floorf(x);
    return f < 1.0f ? f : 0.0f;
}

static inline v8f gdm_load8(const float *p) {
    v8f v;
    memcpy(&v, p, sizeof v);
    return v;
}

/* atan2(y, x) in [-pi, pi] without libm's call: the quotient of the smaller by the larger
 * magnitude in [0, 1], reduced once more past tan(pi/8) by atan(a) = pi/4 + atan((a - 1) /
 * (a + 1)), then Cephes' atanf polynomial. Within 3e-7 rad of the exact atan2 (atan2f's own
 * float result: 2.5e-7; test_technique_gdm), a millionth of one of the table's direction cells
 * (pi/16 in theta); acosf and atan2f were a quarter of the lookup's instructions. */
static inline float gdm_atan2(float y, float x) {
    const float pi = 3.14159265358979323846f;
    float ax = fabsf(x), ay = fabsf(y);
    float big = ax > ay ? ax : ay, small = ax > ay ? ay : ax;
    float a = big > 0.0f ? small / big : 0.0f;
    float base = 0.0f;
    if (a > 0.41421356237309505f) { /* tan(pi/8) */
        base = 0.25f * pi;
        a = (a - 1.0f) / (a + 1.0f);
    }
    float z = a * a;
    float r = base + ((((8.05374449538e-2f * z - 1.38776856032e-1f) * z + 1.99777106478e-1f) * z -
                       3.33329491539e-1f) *
                          z * a +
                      a);
    if (ay > ax) r = 0.5f * pi - r;
    if (x < 0.0f) r = pi - r;
    return y < 0.0f ? -r : r;
}

/* meso_axis_wrap(x, n) (math.h), with a mask instead of the remainder where n is a power of
 * two (the default table's 64 x 64 voxels and 32 azimuths): i & (n - 1) is the wrapped index
 * for every int i. Three integer divisions a lookup fewer, the same axis. */
static inline meso_axis gdm_axis_wrap(float x, int n) {
    if (n & (n - 1)) return meso_axis_wrap(x, n);
    float f = floorf(x);
    int i = (int)f & (n - 1);
    return (meso_axis){i, (i + 1) & (n - 1), x - f};
}

/* d at uvw along the unit (u, v, w) direction: meso_gdm_lookup's value (compressed, k of the
 * table) up to the order of the additions. Pure. */
static inline float gdm_lookup8(const gdm_lookup_table *t, meso_vec3 uvw, meso_vec3 direction) {
    const float two_pi = 6.28318530717958647692f, pi = 3.14159265358979323846f;
    float u = gdm_tile_fraction(uvw.x), v = gdm_tile_fraction(uvw.y);
    float w = isfinite(uvw.z) ? gdm_fminf(gdm_fmaxf(uvw.z, 0.0f), 1.0f) : 0.0f;
    meso_axis ax = gdm_axis_wrap(u * (float)t->width - 0.5f, t->width);
    meso_axis ay = gdm_axis_wrap((1.0f - v) * (float)t->height - 0.5f, t->height);
    meso_axis az = meso_axis_clamp(w * (float)(t->layers - 1), t->layers);
    float length = meso_vec3_length(direction);
    bool valid = length > 0.0f && isfinite(length);
    /* theta = acos(-z / |direction|) = atan2(|(x, y)|, -z), phi = atan2(y, x) */
    float across = sqrtf(direction.x * direction.x + direction.y * direction.y);
    float theta = valid ? gdm_atan2(across, -direction.z) : 0.0f;
    float phi = valid ? gdm_atan2(direction.y, direction.x) : 0.0f;
    if (phi < 0.0f) phi += two_pi;
    meso_axis at = meso_axis_clamp(theta * (float)t->num_theta / pi - 0.5f, t->num_theta);
    meso_axis ap = gdm_axis_wrap(phi * (float)t->num_phi / two_pi, t->num_phi);
    int lanes = 8 * t->chunks;
    /* E(z, theta), bilinear */
    const float *e00 = t->eigen + ((size_t)az.i0 * t->num_theta + (size_t)at.i0) * lanes;
    const float *e01 = t->eigen + ((size_t)az.i0 * t->num_theta + (size_t)at.i1) * lanes;
    const float *e10 = t->eigen + ((size_t)az.i1 * t->num_theta + (size_t)at.i0) * lanes;
    const float *e11 = t->eigen + ((size_t)az.i1 * t->num_theta + (size_t)at.i1) * lanes;
    float c00 = (1.0f - az.w) * (1.0f - at.w), c01 = (1.0f - az.w) * at.w;
    float c10 = az.w * (1.0f - at.w), c11 = az.w * at.w;
    /* W(x, y, phi), trilinear */
    int ix[2] = {ax.i0, ax.i1}, iy[2] = {ay.i0, ay.i1}, ip[2] = {ap.i0, ap.i1};
    float wx[2] = {1.0f - ax.w, ax.w}, wy[2] = {1.0f - ay.w, ay.w}, wp[2] = {1.0f - ap.w, ap.w};
    /* corner c = (x bit 0, y bit 1, phi bit 2): its weight (wx wy) wp and its row, with the
     * (x, y) parts made once for the two phi corners */
    float cw[8];
    const float *rows[8];
#pragma GCC unroll 4
    for (int xy = 0; xy < 4; xy++) {
        float wxy = wx[xy & 1] * wy[xy >> 1];
        size_t cell =
            ((size_t)iy[xy >> 1] * (size_t)t->width + (size_t)ix[xy & 1]) * (size_t)t->num_phi;
        for (int p = 0; p < 2; p++) {
            cw[xy + 4 * p] = wxy * wp[p];
            rows[xy + 4 * p] = t->weights + (cell + (size_t)ip[p]) * (size_t)lanes;
        }
    }
    float d = 0.0f;
    for (int chunk = 0; chunk < t->chunks; chunk++) {
        size_t o = 8 * (size_t)chunk;
        v8f e = v8_splat(c00) * gdm_load8(e00 + o) + v8_splat(c01) * gdm_load8(e01 + o) +
                v8_splat(c10) * gdm_load8(e10 + o) + v8_splat(c11) * gdm_load8(e11 + o);
        v8f wsum = v8_splat(0.0f);
#pragma GCC unroll 8
        for (int corner = 0; corner < 8; corner++)
            wsum += v8_splat(cw[corner]) * gdm_load8(rows[corner] + o);
        v8f p = wsum * e;
        d += ((p[0] + p[1]) + (p[2] + p[3])) + ((p[4] + p[5]) + (p[6] + p[7]));
    }
    return d;
}

#endif
