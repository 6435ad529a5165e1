/* Private to the mesostructure module: integer hash noise shared by the procedural sources.
 *
 * Everything here is integer arithmetic or plain float math on fixed inputs, so procedural
 * height fields and solids are the same bytes on every machine and thread count (no rand()).
 */
#ifndef MESO_MESOSTRUCTURE_INTERNAL_H
#define MESO_MESOSTRUCTURE_INTERNAL_H

#include <math.h>
#include <stdint.h>

#include "meso/mesostructure.h"

/* A solid: a procedural kind's parameters, or a tile mesh's distance grid. */
struct meso_solid {
    meso_solid_desc desc;
    float depth_cells; /* slab thickness in cell units */
    float scale;       /* 1 / (lipschitz * max(count, depth_cells)) */
    float cap;         /* bound on omitted repeats, cell units */
    /* kind-specific shape parameters, cell units */
    float amplitude;          /* weave: undulation of the thread centres */
    float major;              /* chain: link half-width (stadium radius); helix: helix radius */
    float half_length;        /* chain: half the straight part of a link */
    float tilt_cos, tilt_sin; /* squama */
    float radius;             /* squama: scale radius */
    /* MESO_SOLID_MESH: signed distance samples of a tile mesh (mesostructure_tile_mesh.c) */
    float *grid;       /* n^3 nodes, index (k n + j) n + i at (i/n, j/n, k/(n-1)) in (u, v, w) */
    int grid_side;     /* n */
    bool grid_clamped; /* a model (impostor): not periodic, nodes at i / (n - 1) in u and v */
    uint64_t grid_hash;
    char grid_name[256];
    /* a model's own triangles in (u, v, w): the object an impostor stands for, which the
     * reference traces (meso_solid_model_view); NULL for tiles and procedural solids */
    meso_vec3 *model_uvw;
    uint32_t *model_indices;
    size_t model_num_vertices, model_num_triangles;
};

/* The distance of a tile-mesh solid at (u, v, w): trilinear in the grid (u, v periodic). */
float meso_solid_grid_distance(const meso_solid *solid, meso_vec3 uvw);

/* A 32-bit avalanche mix (the MurmurHash3 finaliser's shift-multiply rounds). */
static inline uint32_t mix32(uint32_t x) {
    x ^= x >> 16;
    x *= 0x85ebca6bu;
    x ^= x >> 13;
    x *= 0xc2b2ae35u;
    x ^= x >> 16;
    return x;
}

/* A hash of two lattice indices and a seed. */
static inline uint32_t hash_cell(int i, int j, uint32_t seed) {
    uint32_t h = mix32(seed * 0x9e3779b9u + 0x632be5abu);
    h = mix32(h ^ ((uint32_t)i * 0x27d4eb2du));
    h = mix32(h ^ ((uint32_t)j * 0x165667b1u));
    return h;
}

/* A value in [0, 1) from a hash (24 bits: exact in float). */
static inline float hash_unit(uint32_t h) { return (float)(h >> 8) * (1.0f / 16777216.0f); }

/* i modulo n in [0, n) for any sign of i. */
static inline int wrap_index(int i, int n) {
    int r = i % n;
    return r < 0 ? r + n : r;
}

/* Value noise in [0, 1] with period (period_x, period_y) lattice cells: lattice values are
 * hashed from indices taken modulo the period, so noise over a tile continues across its
 * border. Quintic fade: C2 continuous, so height-field gradients have no creases. */
static inline float periodic_value_noise(float x, float y, int period_x, int period_y,
                                         uint32_t seed) {
    float fx = floorf(x), fy = floorf(y);
    int i = (int)fx, j = (int)fy;
    float tx = x - fx, ty = y - fy;
    tx = tx * tx * tx * (tx * (tx * 6.0f - 15.0f) + 10.0f);
    ty = ty * ty * ty * (ty * (ty * 6.0f - 15.0f) + 10.0f);
    int i0 = wrap_index(i, period_x), i1 = wrap_index(i + 1, period_x);
    int j0 = wrap_index(j, period_y), j1 = wrap_index(j + 1, period_y);
    float a = hash_unit(hash_cell(i0, j0, seed)), b = hash_unit(hash_cell(i1, j0, seed));
    float c = hash_unit(hash_cell(i0, j1, seed)), d = hash_unit(hash_cell(i1, j1, seed));
    float top = a + (b - a) * tx, bottom = c + (d - c) * tx;
    return top + (bottom - top) * ty;
}

/* Three octaves of periodic value noise over the unit tile, in [-1, 1] (approximately zero
 * mean). base_period lattice cells per tile at the first octave. */
static inline float periodic_fbm(float u, float v, int base_period, uint32_t seed) {
    float sum = 0.0f, amplitude = 0.5f, norm = 0.0f;
    int period = base_period;
    for (int octave = 0; octave < 3; octave++) {
        float n = periodic_value_noise(u * (float)period, v * (float)period, period, period,
                                       seed + 101u * (uint32_t)octave);
        sum += amplitude * (2.0f * n - 1.0f);
        norm += amplitude;
        amplitude *= 0.5f;
        period *= 2;
    }
    return sum / norm;
}

/* A zeroed height field (texels all 0, hash not set) with its size checked against the image
 * limits before allocating; errors name `name`. */
meso_result meso_heightfield_alloc(meso_context *ctx, const char *name, int width, int height,
                                   meso_wrap wrap, meso_heightfield **out_heightfield);

/* u - floor(u): the position inside the unit tile. */
static inline float fract_tile(float u) { return u - floorf(u); }

#endif
