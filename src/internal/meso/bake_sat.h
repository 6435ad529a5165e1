/* meso summed-area table of a height field (Crow 1984).
 *
 * Overview
 *   The table gives the sum (and so the average) of the heights over any axis-aligned box of
 *   texels in constant time. Doggett & Hirche 2000 ("Local Area Average Height Test") use it
 *   to compare the average height around an edge's end points with the average around its
 *   midpoint, which detects low-frequency surface change the normal test misses.
 *
 * Usage
 *   meso_sat *sat = NULL;
 *   if (meso_sat_bake(ctx, heightfield, &sat) != MESO_OK) return ...;
 *   float a = meso_sat_box_average(sat, u, v, 4.0f);  // mean height over a 9 x 9 texel box
 *   meso_sat_destroy(sat);
 *
 * Conventions
 *   Texel (i, j) is column i, row j with row 0 at the top, as in meso_heightfield. Boxes are
 *   half-open: [i0, i1) x [j0, j1). With MESO_WRAP_REPEAT the height field is extended
 *   periodically, so a box may cross the border or be larger than the field; with
 *   MESO_WRAP_CLAMP a box is clipped to the field and the average is taken over the texels left.
 *   Sums are kept in double precision: a sum over 2^24 texels of [0,1] values keeps ~1e-9
 *   relative error, far below a height quantum.
 *
 * Limits
 *   MESO_SAT_MAX_TEXELS texels (width * height), checked before allocating.
 *
 * Ownership and threads
 *   meso_sat_bake returns a new table owned by the caller (meso_sat_destroy; NULL is fine).
 *   Queries are pure and thread-safe.
 */
#ifndef MESO_BAKE_SAT_H
#define MESO_BAKE_SAT_H

#include "meso/core.h"
#include "meso/mesostructure.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MESO_SAT_MAX_TEXELS (1u << 24) /* 4096 x 4096: 128 MiB of doubles */

typedef struct meso_sat {
    int width, height; /* of the height field */
    meso_wrap wrap;    /* REPEAT or CLAMP (DEFAULT is stored as REPEAT) */
    /* (width + 1) * (height + 1) prefix sums: sums[j * (width + 1) + i] is the sum of the
     * texels (x, y) with x < i and y < j. Owned. */
    double *sums;
} meso_sat;

/* Build the summed-area table of `heightfield` (its wrap mode is kept).
 * Returns MESO_OK, MESO_ERROR_INVALID_ARGUMENT (NULL or empty field), MESO_ERROR_LIMIT (more
 * than MESO_SAT_MAX_TEXELS texels, before allocating), MESO_ERROR_OUT_OF_MEMORY; *out_sat is
 * NULL on failure. Single-threaded (linear time). */
meso_result meso_sat_bake(meso_context *ctx, const meso_heightfield *heightfield,
                          meso_sat **out_sat);
void meso_sat_destroy(meso_sat *sat);

/* Sum of the texels in [i0, i1) x [j0, j1) with the table's wrap mode (see above); 0 for an
 * empty box. Pure. */
double meso_sat_box_sum(const meso_sat *sat, int i0, int j0, int i1, int j1);

/* Number of texels meso_sat_box_sum adds for that box (the clipped area with CLAMP). Pure. */
double meso_sat_box_count(const meso_sat *sat, int i0, int j0, int i1, int j1);

/* Mean height over the box of texels whose centres lie within `radius` texels (Chebyshev) of
 * the point (u, v) of texture space, at least the one texel nearest to it. Pure. */
float meso_sat_box_average(const meso_sat *sat, float u, float v, float radius);

#ifdef __cplusplus
}
#endif
#endif
