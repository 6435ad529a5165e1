/* Private interface of the rasterizer (raster_setup.c, raster_tiles.c, raster_depth_map.c):
 * triangle setup, binning into screen tiles, and the per-tile passes.
 *
 * Pipeline (docs/rasterizer.md):
 *   1. setup, parallel over fixed chunks of RASTER_CHUNK_TRIANGLES triangles: vertices to clip
 *      space, trivial frustum reject, clipping at the near plane (and a guard band far outside
 *      the screen), projection, snapping to 1/256 sample, back-face culling, edge functions with
 * the top-left rule, perspective barycentric planes; then each chunk bins its triangles into
 * RASTER_TILE_SIZE tiles;
 *   2. tiles, parallel: each tile walks the chunks in order and their triangles in order, so the
 *      output never depends on the number of threads.
 */
#ifndef MESO_RASTER_INTERNAL_H
#define MESO_RASTER_INTERNAL_H

#include "render_internal.h"

#define RASTER_TILE_SIZE 32 /* samples a side of a screen tile */
#define RASTER_CHUNK_TRIANGLES                                                                     \
    256                            /* source triangles per setup chunk (times num_tiles /          \
                                      RASTER_CHUNK_TILES above that many tiles) */
#define RASTER_CHUNKS_PER_MESH 128 /* chunks grow beyond this many a mesh (raster_setup.c) */
#define RASTER_CHUNK_TILES                                                                         \
    2048                       /* tiles above which chunks grow: a chunk's tile table (4 bytes a   \
                                  tile) stays within ~32 bytes a triangle */
#define RASTER_SUBPIXEL_BITS 8 /* vertices snap to 1/256 sample */
#define RASTER_SUBPIXEL_ONE (1 << RASTER_SUBPIXEL_BITS)
#define RASTER_GUARD_SAMPLES 262144.0 /* |screen coordinate| bound after guard-band clipping */
#define RASTER_MAX_TARGET_SIDE 65536  /* samples a side of a raster target */
/* Back faces are dropped before their vertices are transformed when the sine of the angle past
 * edge-on exceeds this (raster_setup.c, faces_away); nearer edge-on the snapped screen
 * orientation decides, as for every other triangle. */
#define RASTER_BACK_FACE_MARGIN 0.01f

/* One triangle ready to rasterize (a source triangle, or a piece of one after clipping). */
typedef struct raster_triangle {
    int32_t x[3], y[3]; /* vertices, fixed point (1/256 sample), y down, counter-clockwise
                           in these coordinates so that the edge functions are >= 0 inside */
    int32_t edge_a[3];  /* edge k (opposite vertex k): E = a (px - x[k+1]) + b (py - y[k+1]) */
    int32_t edge_b[3];
    int32_t bias[3];                    /* top-left rule: 0 for top/left edges, -1 otherwise */
    int32_t min_x, min_y, max_x, max_y; /* samples whose centre may be covered, clamped to the
                                           target, inclusive */
    float ref_x, ref_y;                 /* reference point of the planes below (sample units) */
    /* g_i(x, y) = gc[i] + ga[i] (x - ref_x) + gb[i] (y - ref_y): the source triangle's
     * barycentric i divided by clip w. sum g_i = 1 / view depth; b_i = g_i / sum g. */
    float ga[3], gb[3], gc[3];
    /* z_ndc * 0.5 + 0.5, linear in screen space (depth maps only) */
    float za, zb, zc;
    uint32_t triangle; /* source triangle index in the mesh */
} raster_triangle;

/* The geometry of one object for the binning pass. */
typedef struct raster_mesh {
    const meso_mesh *mesh;
    bool both_faces; /* drawn from both sides even when the pass culls back faces */
} raster_mesh;

typedef struct raster_chunk {
    int mesh;              /* index into the raster_mesh array */
    uint32_t first, count; /* source triangles [first, first + count) */
    raster_triangle *triangles;
    size_t num_triangles, capacity;
    uint32_t *tile_start; /* num_tiles + 1 offsets into entries */
    size_t tile_start_capacity;
    uint32_t *entries; /* indices into triangles, grouped by tile, in triangle order */
    size_t num_entries, entries_capacity;
    bool failed; /* out of memory in the chunk job */
} raster_chunk;

typedef struct raster_setup_desc {
    meso_mat4 view_projection;
    int width, height;   /* target, samples */
    float z_near;        /* clip at clip w >= z_near */
    bool clip_z;         /* instead clip at z_ndc >= -1 (depth maps: any projection) */
    bool cull_back;      /* drop triangles facing away (clockwise on screen from outside) */
    bool depth_plane;    /* fill za/zb/zc */
    bool one_at_a_time;  /* tests: set up source triangles one by one, the reference of the
                            8-wide path (the same triangles, raster_setup.c) */
    bool drop_uncovered; /* drop a triangle whose sample box (at most 2 x 2 samples) holds no
                            sample centre it covers: it draws nothing, only a wireframe shows it */
} raster_setup_desc;

/* Scratch reused from frame to frame: buffers only grow. */
typedef struct raster_bins {
    raster_setup_desc desc;
    int tiles_x, tiles_y;
    raster_mesh *meshes;
    int num_meshes, meshes_capacity;
    raster_chunk *chunks;
    size_t num_chunks, chunks_capacity;
    float guard;   /* |x|, |y| <= guard * w keeps screen coordinates bounded */
    meso_vec3 eye; /* of a perspective view_projection, when has_eye (back faces culled early) */
    bool has_eye;
} raster_bins;

/* Transform, clip, set up and bin `num_meshes` meshes; both_faces (NULL: none) marks meshes
 * whose back faces are kept although desc culls them. Returns MESO_OK or
 * MESO_ERROR_OUT_OF_MEMORY / MESO_ERROR_LIMIT (logged). */
meso_result raster_bins_build(meso_context *ctx, raster_bins *bins, const meso_mesh *const *meshes,
                              const bool *both_faces, int num_meshes,
                              const raster_setup_desc *desc);
void raster_bins_release(raster_bins *bins);

/* The triangles (as indices into chunk->triangles) of `tile` in chunk `chunk`. */
static inline const uint32_t *raster_chunk_tile(const raster_chunk *chunk, int tile,
                                                size_t *out_count) {
    *out_count = chunk->tile_start[tile + 1] - chunk->tile_start[tile];
    /* an empty chunk has no entries array: no offset from NULL (undefined behaviour) */
    return *out_count ? chunk->entries + chunk->tile_start[tile] : NULL;
}

/* ---- Colour pass (raster_tiles.c) --------------------------------------------------------- */

typedef struct raster_object {
    const meso_object *object;
    const meso_technique *technique;
    const void *state;
} raster_object;

typedef struct covered_samples covered_samples;

typedef struct raster_thread_scratch {
    meso_fragment_block *block; /* the batch: a batch never repeats a sample */
    meso_fragment *fragments;   /* RASTER_TILE_SIZE^2, for techniques without shade_block */
    uint32_t *pixels;           /* tile-buffer index of each fragment (2 x tile + 8) */
    uint8_t *pending;           /* RASTER_TILE_SIZE^2: samples held by the batch (zeroed) */
    covered_samples *covered;   /* one triangle's samples before their attributes */
    uint8_t *wire;              /* RASTER_TILE_SIZE^2 wireframe mask */
    float *color, *depth;       /* the tile being drawn, RASTER_TILE_SIZE a row (no coverage: the
                                 * depths below +inf, raster_tiles.c) */
} raster_thread_scratch;

typedef struct raster_pass {
    raster_bins bins;
    raster_thread_scratch *threads;
    int num_threads;
    uint64_t *tile_fragments; /* per tile */
    bool *both_faces;         /* per object: its technique draws back faces */
    int both_faces_capacity;
    /* one tile of background, coverage 0 and depth +inf, to clear from */
    float clear_color[3 * RASTER_TILE_SIZE * RASTER_TILE_SIZE];
    float clear_coverage[RASTER_TILE_SIZE * RASTER_TILE_SIZE];
    float clear_depth[RASTER_TILE_SIZE * RASTER_TILE_SIZE];
    size_t tile_fragments_capacity;
} raster_pass;

/* Rasterize and shade the objects (already binned in pass->bins with the frame's
 * view_projection) into the target arrays of frame->width x frame->height samples. Clears
 * them first (background, coverage 0, depth +inf). */
meso_result raster_draw(meso_context *ctx, raster_pass *pass, const meso_frame *frame,
                        const raster_object *objects, const meso_mesh *const *meshes,
                        int num_objects, bool wireframe, float *color, float *coverage,
                        float *depth, uint64_t *out_triangles, uint64_t *out_fragments);
void raster_pass_release(raster_pass *pass);

#if MESO_HAS_AVX2_TECHNIQUES
/* raster_tiles.c compiled for AVX2 + FMA + F16C like the techniques (CMakeLists.txt): the same
 * bits; render_renderer.c calls them when meso_technique_isa() is "avx2". */
meso_result raster_draw_avx2(meso_context *ctx, raster_pass *pass, const meso_frame *frame,
                             const raster_object *objects, const meso_mesh *const *meshes,
                             int num_objects, bool wireframe, float *color, float *coverage,
                             float *depth, uint64_t *out_triangles, uint64_t *out_fragments);
void raster_resolve_avx2(meso_context *ctx, int n, int width, int height, const float *sample_color,
                         const float *sample_coverage, const float *sample_depth, float *color,
                         float *coverage, float *depth);
/* raster_setup.c's AVX2 copy (8 source triangles at a time); raster_draw_avx2 calls it, and
 * meso_raster_depth_map when meso_technique_isa() is "avx2". Its bins are released by either
 * copy's raster_bins_release. */
meso_result raster_bins_build_avx2(meso_context *ctx, raster_bins *bins,
                                   const meso_mesh *const *meshes, const bool *both_faces,
                                   int num_meshes, const raster_setup_desc *desc);
#endif

/* A 64-byte aligned array of floats for render targets (free() releases it); NULL when out of
 * memory. */
float *meso_render_alloc_floats(size_t count);

/* Box-filter n x n samples per pixel: colour mean, coverage mean, depth minimum. */
void raster_resolve(meso_context *ctx, int n, int width, int height, const float *sample_color,
                    const float *sample_coverage, const float *sample_depth, float *color,
                    float *coverage, float *depth);

#endif
