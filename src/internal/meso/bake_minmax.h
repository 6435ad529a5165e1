/* meso min-max pyramid: a maximum (and minimum) mip pyramid of a height field, for exact
 * hierarchical ray tracing of the bilinear surface (Tevs, Ihrke, Seidel 2008, "Maximum mipmaps
 * for fast, accurate, and scalable dynamic height field rendering").
 *
 * Cells live in texel-centre coordinates x = u * width - 0.5, y = (1 - v) * height - 0.5 (row 0
 * at the top, as the height field). Level 0 has width x height cells; cell (i, j) is the
 * bilinear patch between the texel centres (i, j), (i+1, j), (i, j+1), (i+1, j+1) (indices
 * wrapped as the height field wraps), so its max / min are the max / min of those four texels
 * and bound the bilinear surface over the cell exactly. Level L cell (i, j) covers the level
 * L-1 cells (2i..2i+1, 2j..2j+1) (those that exist): ceil(w / 2) x ceil(h / 2) cells a level,
 * down to a last level of 1 x 1 that bounds the whole tile.
 *
 * Usage
 *   meso_minmax_pyramid *p = NULL;
 *   meso_minmax_pyramid_bake(ctx, heightfield, &p);
 *   float top = p->levels[p->num_levels - 1].max[0];   // max height of the whole field
 *   meso_minmax_pyramid_destroy(p);
 *
 * Threads: the bake uses every worker of ctx (parallel over rows, byte-identical for any thread
 * count); the pyramid is read-only afterwards and may be shared by any number of threads.
 */
#ifndef MESO_BAKE_MINMAX_H
#define MESO_BAKE_MINMAX_H

#include "meso/core.h"
#include "meso/mesostructure.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MESO_MINMAX_MAX_LEVELS 32
/* Largest height field side accepted (checked before allocating). */
#define MESO_MINMAX_MAX_SIDE 32768

typedef struct meso_minmax_level {
    int width, height; /* cells */
    float *max;        /* width * height, row 0 at the top; points into the pyramid's block */
    float *min;
} meso_minmax_level;

typedef struct meso_minmax_pyramid {
    int num_levels; /* 1 + ceil(log2(max(width, height))) */
    meso_wrap wrap; /* of the source */
    uint64_t source_hash;
    meso_minmax_level levels[MESO_MINMAX_MAX_LEVELS];
    float *block; /* owned: every level's max then min */
    size_t block_floats;
} meso_minmax_pyramid;

/* Bake the pyramid of `heightfield`.
 * out_pyramid  On MESO_OK a new pyramid owned by the caller (meso_minmax_pyramid_destroy);
 *              NULL otherwise.
 * Returns      MESO_OK, MESO_ERROR_INVALID_ARGUMENT (NULL or empty field, naming it),
 *              MESO_ERROR_LIMIT (a side above MESO_MINMAX_MAX_SIDE), MESO_ERROR_OUT_OF_MEMORY.
 * Threads      Uses every worker of ctx; safe on different contexts at once. */
meso_result meso_minmax_pyramid_bake(meso_context *ctx, const meso_heightfield *heightfield,
                                     meso_minmax_pyramid **out_pyramid);
/* Bytes held by the pyramid (0 for NULL). */
size_t meso_minmax_pyramid_memory(const meso_minmax_pyramid *pyramid);
/* NULL does nothing. */
void meso_minmax_pyramid_destroy(meso_minmax_pyramid *pyramid);

#ifdef __cplusplus
}
#endif
#endif
