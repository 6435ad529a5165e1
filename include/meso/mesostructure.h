/* meso mesostructure sources: height fields and solids.
 *
 * Height field (docs/design.md): h(u, v) in [0, 1]; 1 lies on the mesh, 0 at -depth. Stored as a
 * grid of width x height texels, row 0 at the top of the image (v = 1 - (j+0.5)/H), sampled
 * bilinearly between texel centres with repeat or clamp-to-edge wrapping.
 *
 * Solid (non-height-field): a signed distance over texture space (u, v, w), u and v tiled with
 * period 1, w = 0 at the mesh (top) and w = 1 at -depth (bottom). Negative inside the
 * material. Distances are in texture-space units (one tile = 1 in u and v, the shell's depth
 * = 1 in w), exact or a lower bound, so sphere tracing is safe. Outside the slab 0 <= w <= 1
 * the solid is empty.
 *
 * Procedural sources are deterministic (same parameters, same values on every machine) and
 * tileable. Height fields from procedures are rasterised at `resolution` texels a side; the
 * solids are evaluated analytically.
 *
 * Threads: sampling and evaluation are pure and thread-safe; create/destroy are not shared.
 */
#ifndef MESO_MESOSTRUCTURE_H
#define MESO_MESOSTRUCTURE_H

#include "meso/core.h"
#include "meso/image.h"
#include "meso/math.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- Height fields ------------------------------------------------------------------------ */

typedef struct meso_heightfield {
    int width, height;
    float *heights; /* width * height, row 0 at the top; owned */
    meso_wrap wrap;
    uint64_t hash; /* of the texels and wrap: bake caches are keyed by it */
} meso_heightfield;

typedef enum meso_heightfield_kind {
    MESO_HEIGHTFIELD_DEFAULT = 0, /* bricks */
    MESO_HEIGHTFIELD_BRICKS,      /* running-bond bricks with mortar grooves and bevelled edges */
    MESO_HEIGHTFIELD_BUMPS,       /* a grid of smooth round bumps */
    MESO_HEIGHTFIELD_WEAVE,       /* over-under woven strips */
    MESO_HEIGHTFIELD_TILES,       /* square tiles with grout, slightly uneven tops */
    MESO_HEIGHTFIELD_BARK,        /* tree bark: plates along v between wandering furrows,
                                     cracked across, fibrous tops */
} meso_heightfield_kind;

/* The largest procedural resolution: its square is the image limit MESO_IMAGE_MAX_PIXELS. */
#define MESO_HEIGHTFIELD_MAX_RESOLUTION 8192

/* Zero fields take the defaults of meso_heightfield_desc_defaults(). */
typedef struct meso_heightfield_desc {
    meso_heightfield_kind kind;
    int resolution;    /* texels a side (512) */
    int rows, columns; /* repeats per tile: bricks 4 x 2, bumps 4 x 4, weave 4 x 4, tiles 4 x 4,
                          bark 3 x 6 (rows: cracks along v; columns: plates around u) */
    float gap;         /* mortar / groove / grout width as a fraction of a cell (0.08; bark's
                          furrows 0.3) */
    float bevel;       /* rounded edge width, fraction of a cell (0.04) */
    float roughness;   /* amplitude of deterministic noise on tops, in height units (0.0) */
    uint32_t seed;     /* noise seed (1) */
    meso_wrap wrap;    /* default repeat */
} meso_heightfield_desc;

meso_heightfield_desc meso_heightfield_desc_defaults(const meso_heightfield_desc *desc);
bool meso_heightfield_kind_from_name(const char *name, meso_heightfield_kind *out_kind);
const char *meso_heightfield_kind_name(meso_heightfield_kind kind);

/* A procedural height field; optionally a matching colour map (RGB, linear) in *out_color,
 * e.g. red bricks and grey mortar (out_color may be NULL). */
meso_result meso_heightfield_create_procedural(meso_context *ctx, const meso_heightfield_desc *desc,
                                               meso_heightfield **out_heightfield,
                                               meso_image **out_color);
/* A height field from an image (values as loaded, in [0,1], clamped): a grey image's grey, an
 * RGB or RGBA image's luminance 0.2126 R + 0.7152 G + 0.0722 B of the stored values (no sRGB
 * decoding); alpha is ignored. */
meso_result meso_heightfield_create_from_image(meso_context *ctx, const meso_image *image,
                                               meso_wrap wrap, meso_heightfield **out_heightfield);
/* A constant height field (tests and degenerate cases). */
meso_result meso_heightfield_create_constant(meso_context *ctx, int width, int height, float value,
                                             meso_heightfield **out_heightfield);
/* Loads a PNG as meso_heightfield_create_from_image reads it. Errors name the file; a constant
 * map loads, with a warning naming the file ("the height map is constant"). */
meso_result meso_heightfield_load_png(meso_context *ctx, const char *path, meso_wrap wrap,
                                      meso_heightfield **out_heightfield);
void meso_heightfield_destroy(meso_heightfield *heightfield);
/* Recompute the hash after writing texels by hand. */
void meso_heightfield_update_hash(meso_heightfield *heightfield);

/* The texel (i, j) with wrapping applied to out-of-range indices. */
static inline float meso_heightfield_texel(const meso_heightfield *hf, int i, int j) {
    if (hf->wrap == MESO_WRAP_CLAMP) {
        i = i < 0 ? 0 : (i >= hf->width ? hf->width - 1 : i);
        j = j < 0 ? 0 : (j >= hf->height ? hf->height - 1 : j);
    } else {
        i %= hf->width;
        j %= hf->height;
        i += i < 0 ? hf->width : 0;
        j += j < 0 ? hf->height : 0;
    }
    return hf->heights[(size_t)j * (size_t)hf->width + (size_t)i];
}

/* The two texel indices around a sample, i and i + 1, wrapped to [0, n). Most lookups fall
 * inside the map, so that case costs a compare instead of the two integer divisions of
 * meso_heightfield_texel: the hot loops of every technique sample through here. */
static inline void meso_heightfield_wrap_pair(meso_wrap wrap, int i, int n, int *out_i0,
                                              int *out_i1) {
    if ((unsigned)i < (unsigned)(n - 1)) {
        *out_i0 = i;
        *out_i1 = i + 1;
    } else if (wrap == MESO_WRAP_CLAMP) {
        *out_i0 = i < 0 ? 0 : (i >= n ? n - 1 : i);
        *out_i1 = i + 1 < 0 ? 0 : (i + 1 >= n ? n - 1 : i + 1);
    } else {
        int w = i % n;
        w += w < 0 ? n : 0;
        *out_i0 = w;
        *out_i1 = w + 1 == n ? 0 : w + 1;
    }
}

/* h(u, v): bilinear between texel centres (docs/design.md). */
static inline float meso_heightfield_sample(const meso_heightfield *hf, float u, float v) {
    float x = u * (float)hf->width - 0.5f;
    float y = (1.0f - v) * (float)hf->height - 0.5f;
    float fx = floorf(x), fy = floorf(y);
    float tx = x - fx, ty = y - fy;
    int i0, i1, j0, j1;
    meso_heightfield_wrap_pair(hf->wrap, (int)fx, hf->width, &i0, &i1);
    meso_heightfield_wrap_pair(hf->wrap, (int)fy, hf->height, &j0, &j1);
    const float *row0 = hf->heights + (size_t)j0 * (size_t)hf->width;
    const float *row1 = hf->heights + (size_t)j1 * (size_t)hf->width;
    float h00 = row0[i0], h10 = row0[i1], h01 = row1[i0], h11 = row1[i1];
    float top = h00 + (h10 - h00) * tx, bottom = h01 + (h11 - h01) * tx;
    return top + (bottom - top) * ty;
}

/* The gradient (dh/du, dh/dv) every technique and the reference shade with: central
 * differences of the bilinear surface one texel apart. */
static inline meso_vec2 meso_heightfield_gradient(const meso_heightfield *hf, float u, float v) {
    float du = 1.0f / (float)hf->width, dv = 1.0f / (float)hf->height;
    float hu = (meso_heightfield_sample(hf, u + du, v) - meso_heightfield_sample(hf, u - du, v)) /
               (2.0f * du);
    float hv = (meso_heightfield_sample(hf, u, v + dv) - meso_heightfield_sample(hf, u, v - dv)) /
               (2.0f * dv);
    return (meso_vec2){hu, hv};
}

/* ---- Solids ------------------------------------------------------------------------------- */

typedef enum meso_solid_kind {
    MESO_SOLID_DEFAULT = 0, /* weave */
    MESO_SOLID_WEAVE,       /* interlaced threads with gaps between them */
    MESO_SOLID_CHAIN,       /* interlocking torus links */
    MESO_SOLID_GRID,        /* a lattice of bars with holes */
    MESO_SOLID_SQUAMA,      /* overlapping scales */
    MESO_SOLID_HELIX,       /* a double helix of threads */
    MESO_SOLID_SLAB,        /* solid below w = 1 - thickness: the height field h = thickness */
    MESO_SOLID_MESH,        /* a closed tile mesh (meso_solid_create_from_triangles) */
} meso_solid_kind;

typedef struct meso_solid_desc {
    meso_solid_kind kind;
    int count;       /* repeats per tile along u (and v where it applies): weave 2, chain 2,
                        grid 4, squama 4, helix 2, slab 1 */
    float thickness; /* thread / bar / link radius as a fraction of a cell (kind's default) */
} meso_solid_desc;

typedef struct meso_solid meso_solid;

meso_solid_desc meso_solid_desc_defaults(const meso_solid_desc *desc);
bool meso_solid_kind_from_name(const char *name, meso_solid_kind *out_kind);
const char *meso_solid_kind_name(meso_solid_kind kind);

meso_result meso_solid_create_procedural(meso_context *ctx, const meso_solid_desc *desc,
                                         meso_solid **out_solid);
/* A solid from a closed triangle mesh of one tile (docs/design.md: x, y -> u, v, periodic: the
 * mesh may cross the tile's border and continues in the neighbouring tiles; z -> 1 - w, its
 * top at z = 1 on the mesh), converted once to signed distances on a grid of `resolution`^3
 * nodes (0: 96) with Embree: the sign by ray parity along z, the magnitude by closest-point
 * queries. meso_solid_distance then interpolates the grid trilinearly (scaled so it stays a
 * distance bound). `name` (the file) names the mesh in messages.
 * Returns MESO_OK; MESO_ERROR_FORMAT naming `name` when the mesh is empty, not closed (an edge
 * with one triangle), not manifold (an edge with three or more), inconsistently oriented, or
 * has vertices outside 0 <= z <= 1; MESO_ERROR_LIMIT (resolution outside 8..256);
 * MESO_ERROR_OUT_OF_MEMORY; MESO_ERROR_INTERNAL (Embree failed).
 * Threads: uses every worker of ctx; the grid is independent of the thread count. */
meso_result meso_solid_create_from_triangles(meso_context *ctx, const meso_vec3 *positions,
                                             size_t num_vertices, const uint32_t *indices,
                                             size_t num_triangles, const char *name, int resolution,
                                             meso_solid **out_solid);
/* A solid from a whole model for a relief impostor (Policarpo & Oliveira 2006 §4): positions
 * already in the unit box (the caller maps the model's bounds there), not periodic, clamped
 * at the box, and not required to be closed: a node is inside when it lies behind the face
 * nearest to it (the teapot's patches leave seams and holes that ray parity cannot cross).
 * Same results otherwise as meso_solid_create_from_triangles. */
meso_result meso_solid_create_from_model(meso_context *ctx, const meso_vec3 *positions,
                                         size_t num_vertices, const uint32_t *indices,
                                         size_t num_triangles, const char *name, int resolution,
                                         meso_solid **out_solid);
/* False for a model's solid (clamped at the box), true for tiles and procedural solids. */
bool meso_solid_is_periodic(const meso_solid *solid);
/* A model's solid keeps the model's own triangles in texture space (u, v, w), w = 0 at the
 * box's top: the object an impostor stands for, which the reference traces. Borrowed views,
 * valid until the solid is destroyed. Returns false, with every output NULL or 0, for tiles
 * and procedural solids (and a NULL solid). Pure; thread-safe. */
bool meso_solid_model_view(const meso_solid *solid, const meso_vec3 **out_uvw,
                           size_t *out_num_vertices, const uint32_t **out_indices,
                           size_t *out_num_triangles);
void meso_solid_destroy(meso_solid *solid);
/* The parameters the solid was made with (defaults filled in). */
meso_solid_desc meso_solid_get_desc(const meso_solid *solid);
/* A hash of the parameters, for bake caches. */
uint64_t meso_solid_hash(const meso_solid *solid);

/* Signed distance at (u, v, w); u, v taken modulo 1. Pure, thread-safe. */
float meso_solid_distance(const meso_solid *solid, meso_vec3 uvw);
/* The gradient of the distance (not normalised), by central differences of step 1e-3 unless
 * the kind has an analytic one. Points outward. */
meso_vec3 meso_solid_gradient(const meso_solid *solid, meso_vec3 uvw);

/* The constants meso_solid_distance computes with, for ports of it to other languages (the GL
 * back end's shaders/meso_solid.glsl): cell-space terms of the procedural kinds
 * (mesostructure_solid.c) and, for MESO_SOLID_MESH, the distance grid it interpolates. A
 * borrowed view, valid while the solid lives. Pure. */
typedef struct meso_solid_shape {
    meso_solid_desc desc;     /* defaults filled in */
    float depth_cells, scale; /* the slab in cells; 1 / (lipschitz max(count, depth_cells)) */
    float cap;                /* bound on the omitted repeats */
    float amplitude;          /* weave */
    float major, half_length; /* chain (major: helix too) */
    float tilt_cos, tilt_sin, radius; /* squama */
    const float *grid; /* MESO_SOLID_MESH: n^3 samples, (k n + j) n + i; NULL otherwise */
    int grid_side;     /* n */
    bool grid_clamped; /* a model's grid (nodes at i / (n - 1), clamped) */
} meso_solid_shape;
meso_solid_shape meso_solid_get_shape(const meso_solid *solid);

/* A scalar field over texture space, negative inside; must be periodic in u and v (period 1). */
typedef float (*meso_scalar_field_fn)(void *user, meso_vec3 uvw);

#ifdef __cplusplus
}
#endif
#endif
