/* meso isosurfaces: the surface of a solid mesostructure extracted in texture space.
 *
 * Overview
 *   The reference tracer needs a solid's surface as real triangles. This bake samples
 *   the solid's signed distance on a regular grid over one tile (u, v in [0,1], w in [0,1])
 *   and extracts the zero level set by dual contouring (Ju et al. 2002): one vertex per cell
 *   the surface crosses, where the planes through its edges' zero crossings (found on the field
 *   itself, with the field's normal there) meet in the least-squares sense, kept inside the
 *   cell -- so a box's edges and corners are kept, not cut off as the crossings' mean (surface
 *   nets) cut them -- and one quad (two triangles) per grid edge that changes sign, through the
 *   vertices of the four cells around it, so the surface is watertight by construction. The grid is
 * periodic in u and v; the quads along u = 0 and v = 0 use vertices of the cells just below
 * (positions < 0), which are the last cells' vertices moved by exactly -1, so copies of the tile
 * laid side by side share those vertices bit for bit and join without a gap. The slab 0 <= w <= 1
 * is closed: the field is taken as max(distance, -w, w - 1) and one padding node layer is sampled
 * above and below, so the surface caps the solid exactly at w = 0 and w = 1.
 *
 * Output
 *   An indexed triangle mesh in texture space (positions are (u, v, w)), triangles grouped by
 *   the grid column (cell i along u, cell j along v) that owns them: the triangles of
 *   column c = j * resolution_u + i are column_offsets[c] .. column_offsets[c + 1] - 1. A
 *   triangle lies within the column's cell grown by one cell on every side, u in
 *   [(i-1)/ru, (i+1)/ru] and v in [(j-1)/rv, (j+1)/rv], so positions may be slightly below 0.
 *   Triangles face outward (their geometric normal points toward positive distance). Each
 *   quad of the net is two consecutive triangles of its column, (v0, v1, v2) and (v0, v2, v3),
 *   so triangle counts per column are even.
 *
 * Usage
 *   meso_isosurface *iso = NULL;
 *   meso_isosurface_bake(ctx, solid, &(meso_isosurface_desc){0}, &iso);  // 128 x 128 x 32
 *   ...
 *   meso_isosurface_destroy(iso);
 *
 * Limits: each resolution in [2, MESO_ISOSURFACE_MAX_RESOLUTION], and at most
 * MESO_ISOSURFACE_MAX_NODES grid nodes, checked before allocating (MESO_ERROR_LIMIT).
 * Threads: uses every worker of ctx; output independent of the thread count.
 */
#ifndef MESO_BAKE_ISOSURFACE_H
#define MESO_BAKE_ISOSURFACE_H

#include "meso/core.h"
#include "meso/math.h"
#include "meso/mesostructure.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MESO_ISOSURFACE_MAX_RESOLUTION 1024
#define MESO_ISOSURFACE_MAX_NODES (1u << 25)

/* Zero fields take the defaults: 128 x 128 x 32 cells per tile. */
typedef struct meso_isosurface_desc {
    int resolution_u, resolution_v, resolution_w;
} meso_isosurface_desc;

typedef struct meso_isosurface {
    int resolution_u, resolution_v, resolution_w;
    size_t num_vertices, num_triangles;
    meso_vec3 *positions;     /* (u, v, w) */
    uint32_t *indices;        /* 3 per triangle */
    uint32_t *column_offsets; /* resolution_u * resolution_v + 1 entries */
} meso_isosurface;

/* The desc with zero fields replaced by the defaults. Pure. */
meso_isosurface_desc meso_isosurface_desc_defaults(const meso_isosurface_desc *desc);

/* Extract the surface of `solid` (meso_solid_distance). desc may be NULL.
 * out_isosurface: on MESO_OK a new mesh owned by the caller (meso_isosurface_destroy).
 * Returns MESO_OK, MESO_ERROR_INVALID_ARGUMENT (NULL solid), MESO_ERROR_LIMIT (resolution,
 * naming the field), MESO_ERROR_OUT_OF_MEMORY. */
meso_result meso_isosurface_bake(meso_context *ctx, const meso_solid *solid,
                                 const meso_isosurface_desc *desc,
                                 meso_isosurface **out_isosurface);

/* The same for any periodic field (tests build a slab or a sphere with it). `field` is called
 * from several threads at once and must be pure. */
meso_result meso_isosurface_bake_function(meso_context *ctx, meso_scalar_field_fn field, void *user,
                                          const meso_isosurface_desc *desc,
                                          meso_isosurface **out_isosurface);

/* Free; NULL does nothing. */
void meso_isosurface_destroy(meso_isosurface *isosurface);

#ifdef __cplusplus
}
#endif
#endif
