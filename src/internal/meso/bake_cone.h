/* meso cone map: a conservative cone a cell of a periodic height field, for exact empty-space
 * skipping along rays (after Dummer 2006, "Cone step mapping": the widest cone above a point
 * that no part of the surface enters).
 *
 * Cells are the level-0 cells of the min-max pyramid (bake_minmax.h): cell (i, j) is the
 * bilinear patch between the texel centres (i, j) .. (i + 1, j + 1) in texel-centre coordinates.
 * For each cell the map holds its highest point `top` (the pyramid's level-0 max) and a slope
 * `slope` >= 0 such that the bilinear surface everywhere satisfies
 *
 *     h(q) <= top + slope * dist(q, cell)
 *
 * where dist is the L1 (|dx| + |dy|) distance in texels from q to the cell's square, taken on
 * the torus the repeating field tiles. A point above the cell at height z > top therefore sees
 * no surface within L1 distance (z - top) / slope: a ray may step that far (less its own descent)
 * without missing a hit. The L1 distance makes the bound exact for the bilinear surface: it is
 * affine over every patch (concave where the torus folds), so a bound that holds at the texel
 * centres holds between them; a Euclidean or Chebyshev distance would not.
 *
 * The slope is the largest ratio (h - top) / dist over the texels higher than the cell's top
 * within MESO_CONE_RADIUS (L1), or (field's highest - top) / (MESO_CONE_RADIUS + 1) if that is
 * larger (it bounds every farther texel), rounded up to a float. The search is pruned with the
 * pyramid: a block of texels no higher than the cell's top, farther than the radius, or whose
 * highest texel over its least distance cannot raise the slope found so far, is not opened.
 * 512 x 512 bricks: about 0.1 s on 2 cores (docs/techniques/relief_exact.md).
 *
 * Usage
 *   meso_minmax_pyramid *p = NULL;  meso_cone_map *c = NULL;
 *   meso_minmax_pyramid_bake(ctx, heightfield, &p);
 *   meso_cone_map_bake(ctx, heightfield, p, &c);
 *   float top = c->cells[2 * (j * c->width + i)], slope = c->cells[2 * (j * c->width + i) + 1];
 *   meso_cone_map_destroy(c);
 *
 * Threads: the bake uses every worker of ctx (parallel over rows of cells; byte-identical for any
 * thread count); the map is read-only afterwards and may be shared by any number of threads.
 */
#ifndef MESO_BAKE_CONE_H
#define MESO_BAKE_CONE_H

#include "meso/bake_minmax.h"
#include "meso/core.h"
#include "meso/mesostructure.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MESO_CONE_KIND "cone"
#define MESO_CONE_KIND_VERSION 1u

/* The radius (L1, texels) searched exactly; the field's highest texel bounds the rest. */
#define MESO_CONE_RADIUS 16

typedef struct meso_cone_map {
    int width, height; /* cells: the height field's texels */
    float *cells;      /* owned: width * height pairs (top, slope), row 0 at the top */
    uint64_t source_hash;
} meso_cone_map;

/* Bake the cone map of `heightfield` (MESO_WRAP_REPEAT or DEFAULT) from its pyramid `pyramid`
 * (meso_minmax_pyramid_bake of the same field).
 * out_map      On MESO_OK a new map owned by the caller (meso_cone_map_destroy); NULL otherwise.
 * Returns      MESO_OK, MESO_ERROR_INVALID_ARGUMENT (NULL or empty field, a clamped field, a
 *              pyramid of another field), MESO_ERROR_OUT_OF_MEMORY.
 * Threads      Uses every worker of ctx; safe on different contexts at once. */
meso_result meso_cone_map_bake(meso_context *ctx, const meso_heightfield *heightfield,
                               const meso_minmax_pyramid *pyramid, meso_cone_map **out_map);

/* meso_cone_map_bake through the bake cache (bake_cache: kind "cone", keyed by the field's hash and
 * the radius): a cached map is loaded instead of baked, a new one stored (a failure to store is
 * a warning). Same results, errors and threads as meso_cone_map_bake; an unusable entry is baked
 * again with a warning. */
meso_result meso_cone_map_bake_cached(meso_context *ctx, const meso_heightfield *heightfield,
                                      const meso_minmax_pyramid *pyramid, meso_cone_map **out_map);

/* Bytes held by the map (0 for NULL). */
size_t meso_cone_map_memory(const meso_cone_map *map);

/* NULL does nothing. */
void meso_cone_map_destroy(meso_cone_map *map);

#ifdef __cplusplus
}
#endif

#endif
