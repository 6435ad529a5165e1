/* meso multilayer relief maps (Policarpo & Oliveira 2006, §3): for every texel, the depths at
 * which a ray cast straight down through the texel centre (along +w, from the mesh at w = 0 to
 * the shell's bottom at w = 1) enters and leaves the solid, and the surface normal there.
 *
 * Overview
 *   The paper stores four depths per texel in the RGBA channels of one texture (unused
 *   channels = 1.0, its Fig. 5) and the x and y of the four unit normals in two more, z being
 *   reconstructed. A texel of the map here holds `num_layers` depths (4, or 8 = two groups of
 *   four, beyond the paper) sorted nearest first: entries at even layers, exits at odd ones,
 *   so a ray at depth d is inside the solid iff an odd number of the texel's depths are <= d
 *   (§3.1). A height field is one layer: its depth 1 - h, exit at the floor.
 *   Normals are unit vectors in texture space with z toward the top of the shell:
 *   (n_u, n_v, -n_w) of the solid's outward normal (n_u, n_v, n_w). Entries face up (z >= 0),
 *   exits down (z <= 0), so z is reconstructed as +-sqrt(max(0, 1 - x^2 - y^2)) by the layer's
 *   parity (meso_layers_normal).
 *
 * Layout
 *   depth, normal_x, normal_y: width * height * num_layers floats, texel-major (the layers of a
 *   texel are consecutive, like the paper's RGBA texels), row 0 at the top: texel (i, j) is
 *   u = (i + 0.5) / width, v = 1 - (j + 0.5) / height (docs/design.md). count: layers per texel.
 *   With format U8 the values are rounded to 8 bits (depth d -> round(255 d), normal
 *   component n -> round(127.5 (n + 1))) and held as the floats those bytes decode to, so a
 *   map read back from a file is bit-identical to the one baked.
 *
 * Usage
 *   meso_layers *map = NULL;
 *   meso_layers_desc desc = {.solid = solid, .num_layers = 8};
 *   if (meso_layers_bake_cached(ctx, &desc, &map) == MESO_OK) {
 *       float d = map->depth[((size_t)j * map->width + i) * map->num_layers + k];
 *       meso_layers_save(ctx, map, "weave.mesobake");
 *       meso_layers_destroy(map);
 *   }
 *
 * Limits: sides 1..MESO_LAYERS_MAX_SIDE, num_layers 4 or 8; a loaded file is validated
 * (shapes, value ranges, sorted depths, counts) before anything is allocated for it.
 * Threads: the bake uses every worker of ctx, parallel over rows; output independent of the
 * thread count. A map is read-only afterwards.
 */
#ifndef MESO_BAKE_LAYERS_H
#define MESO_BAKE_LAYERS_H

#include "meso/bake_file.h"
#include "meso/core.h"
#include "meso/mesostructure.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MESO_LAYERS_KIND "relief_layers"
#define MESO_LAYERS_KIND_VERSION 1u
#define MESO_LAYERS_MAX 8
#define MESO_LAYERS_MAX_SIDE 8192
/* The paper's maps: three RGBA8 textures of 256 x 256 (§5), 786432 bytes. */
#define MESO_LAYERS_PAPER_BYTES 786432u

typedef enum meso_layers_format {
    MESO_LAYERS_FORMAT_DEFAULT = 0, /* U8 */
    MESO_LAYERS_FORMAT_U8,          /* 8 bits per value, as the paper's RGBA8 textures */
    MESO_LAYERS_FORMAT_F32,         /* float */
} meso_layers_format;

/* Exactly one source: a solid, a height field, or a scalar field (negative inside, periodic in
 * u and v, 1-Lipschitz in (u, v, w): it is sphere traced). Zero fields take the defaults of
 * meso_layers_desc_defaults. */
typedef struct meso_layers_desc {
    const meso_solid *solid;
    const meso_heightfield *heightfield;
    meso_scalar_field_fn field;
    void *field_user;
    uint64_t field_hash; /* identifies `field` in the cache key */
    int width, height;   /* texels: 256 x 256; a height field's own size */
    int num_layers;      /* 4 (the paper) or 8 */
    meso_layers_format format;
} meso_layers_desc;

typedef struct meso_layers {
    int width, height, num_layers;
    meso_layers_format format;
    meso_wrap wrap;
    bool from_heightfield; /* one layer over a solid floor (the shell's bottom is hit) */
    uint64_t source_hash;
    int max_count;            /* most layers a texel holds */
    int max_crossings;        /* most surface crossings found in a texel before clipping */
    uint64_t clipped_texels;  /* texels with more crossings than num_layers (deeper dropped) */
    uint64_t clipped_at_four; /* texels with more than 4 crossings: what the paper's limit clips */
    double bake_seconds;      /* 0 when loaded */
    float *depth;             /* see Layout; unused = 1.0 */
    float *normal_x, *normal_y;
    uint8_t *count;
} meso_layers;

/* desc with zero fields replaced by the defaults (desc may be NULL). Pure. */
meso_layers_desc meso_layers_desc_defaults(const meso_layers_desc *desc);

/* Bake the map of desc's source (§3, the paper's ray-casting plugin of §5 done by sphere
 * tracing the solid's distance bound down every texel centre, each crossing refined by
 * bisection, the normal from the distance's gradient).
 * out_map  On MESO_OK a new map owned by the caller (meso_layers_destroy); NULL otherwise.
 * Returns  MESO_OK, MESO_ERROR_INVALID_ARGUMENT (no or two sources, bad field: the message
 *          names it, "relief_layers: num_layers: ..."), MESO_ERROR_LIMIT,
 *          MESO_ERROR_OUT_OF_MEMORY.
 * Threads  Uses every worker of ctx; safe on different contexts at once. */
meso_result meso_layers_bake(meso_context *ctx, const meso_layers_desc *desc,
                             meso_layers **out_map);
/* The cache key of desc (source hash and every parameter). Pure. */
uint64_t meso_layers_cache_key(const meso_layers_desc *desc);
/* meso_layers_bake through the bake cache (bake_file.h): a valid cached entry is loaded, else
 * the map is baked and stored. Same results as meso_layers_bake. */
meso_result meso_layers_bake_cached(meso_context *ctx, const meso_layers_desc *desc,
                                    meso_layers **out_map);

/* Save as a .mesobake of kind "relief_layers" (docs/bake-format.md), atomically; U8 maps are
 * stored as bytes. Returns MESO_OK, MESO_ERROR_IO naming the file. */
meso_result meso_layers_save(meso_context *ctx, const meso_layers *map, const char *path);
/* Load a map saved by meso_layers_save: MESO_ERROR_FORMAT naming the file and what is wrong
 * for another kind, missing or misshapen arrays, depths outside [0, 1] or unsorted, normals
 * outside [-1, 1], counts above num_layers. */
meso_result meso_layers_load(meso_context *ctx, const char *path, meso_layers **out_map);
/* The same from a bake file already read; `name` is used in messages. */
meso_result meso_layers_from_bake_file(meso_context *ctx, const meso_bake_file *bake,
                                       const char *name, meso_layers **out_map);

/* The map of the same solid seen from the bottom of the shell (w' = 1 - w: depths 1 - d in
 * reverse order, entries and exits swapped), for back faces and the back views of relief
 * impostors (§4). Height-field maps are refused (MESO_ERROR_INVALID_ARGUMENT): their floor is
 * solid. out_map: a new map owned by the caller. */
meso_result meso_layers_mirror(meso_context *ctx, const meso_layers *map, meso_layers **out_map);
/* Unit normal of layer k of texel (i, j), z reconstructed with the layer's sign. Pure. */
meso_vec3 meso_layers_normal(const meso_layers *map, int i, int j, int k);
/* Bytes of the map as stored (1 or 4 per value, 3 values and a count per layer slot). */
size_t meso_layers_file_bytes(const meso_layers *map);
/* Bytes held in memory. */
size_t meso_layers_memory(const meso_layers *map);
/* A text report for `meso info` (sizes beside the paper's, clipping); 0 when bake is not a
 * layers bake. Writes at most size bytes (NUL included); returns the length needed. */
size_t meso_layers_describe(const meso_bake_file *bake, char *buffer, size_t size);
/* NULL does nothing. */
void meso_layers_destroy(meso_layers *map);

#ifdef __cplusplus
}
#endif
#endif
