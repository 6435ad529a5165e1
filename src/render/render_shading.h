/* The shared shading model (render_internal.h, meso_shade_point) eight points at a time, for
 * techniques that already hold their normals and texture coordinates in vectors
 * (render_simd.h). Shading lane by lane through meso_shade_point ran the whole eight-wide
 * model for one point: two thirds of parallax mapping's frame. */
#ifndef MESO_RENDER_SHADING_H
#define MESO_RENDER_SHADING_H

#include <string.h>

#include "render_internal.h"
#include "render_simd.h"

typedef struct meso_shade_batch {
    v8f px, py, pz; /* position, world space */
    v8f nx, ny, nz; /* unit normal */
    v8f u, v;       /* colour-map coordinates */
    /* the base surface's tangent (dP/du) and bitangent (dP/dv), any length: read only for an
     * object with a normal map (render_shading.c, apply_normal_map) */
    v8f tx, ty, tz, bx, by, bz;
    /* visibility[i]: light i's visibility per lane (1: every light visible), the first
     * scene->num_lights entries are read */
    v8f visibility[MESO_SCENE_MAX_LIGHTS];
} meso_shade_batch;

/* Lanes 0..lanes-1 (1-8) of out = meso_shade_point of the matching lanes of `in`, with the same
 * bits; the other lanes of `in` must hold finite values (e.g. repeat lane 0), the other lanes
 * of out are undefined. Pure, thread-safe. */
void meso_shade_batch8(const meso_frame *frame, const meso_object *object,
                       const meso_shade_batch *in, int lanes, v8f *out_r, v8f *out_g, v8f *out_b);

/* meso_shade_batch8 for lanes that are fragments[0..lanes-1]: with frame->filter the maps are
 * read by the fragments' footprints (meso_fragment.duv_dx, duv_dy). */
void meso_shade_batch8_fragments(const meso_frame *frame, const meso_object *object,
                                 const meso_shade_batch *in, const meso_fragment *fragments,
                                 int lanes, v8f *out_r, v8f *out_g, v8f *out_b);

/* visibility[i] = 1 in every lane for the scene's lights. */
static inline void meso_shade_batch_all_visible(meso_shade_batch *in, const meso_frame *frame) {
    for (int i = 0; i < frame->scene->num_lights; i++) in->visibility[i] = v8_splat(1.0f);
}

/* Lanes first..first+7 of a block's array (first a multiple of 8: aligned, inside the padding). */
static inline v8f meso_block_load(const float *array, size_t first) {
    v8f r;
    memcpy(&r, array + first, sizeof r);
    return r;
}
static inline void meso_block_store(float *array, size_t first, v8f value) {
    memcpy(array + first, &value, sizeof value);
}

/* The shading inputs of lanes first..first+7 of a block as they are (position, normal, uv, and
 * with `tangents` the tangent and bitangent, which only a normal map reads); not the lights'
 * visibility, which a caller shading every light visible sets once
 * (meso_shade_batch_all_visible) for all its groups. */
static inline void meso_shade_batch_from_block(meso_shade_batch *in, const meso_fragment_block *b,
                                               size_t first, bool tangents) {
    in->px = meso_block_load(b->px, first), in->py = meso_block_load(b->py, first);
    in->pz = meso_block_load(b->pz, first);
    in->nx = meso_block_load(b->nx, first), in->ny = meso_block_load(b->ny, first);
    in->nz = meso_block_load(b->nz, first);
    in->u = meso_block_load(b->u, first), in->v = meso_block_load(b->v, first);
    if (tangents) {
        in->tx = meso_block_load(b->tx, first), in->ty = meso_block_load(b->ty, first);
        in->tz = meso_block_load(b->tz, first);
        in->bx = meso_block_load(b->bx, first), in->by = meso_block_load(b->by, first);
        in->bz = meso_block_load(b->bz, first);
    }
}

/* Shade the lanes of num_groups groups of eight into the block's colours: in[k] holds lanes
 * first + 8k .. first + 8k + 7 (first a multiple of 8; lanes past count: padding), as
 * meso_shade_batch8 does, the per-object constants worked out once a call. With
 * frame->filter the maps are read by the block's footprints of those lanes. */
void meso_shade_batches_to_block(const meso_frame *frame, const meso_object *object,
                                 const meso_shade_batch *in, size_t num_groups,
                                 meso_fragment_block *b, size_t first);

/* Shade lanes first..first+7 of `in` into the block's colours (lanes past count: padding). */
static inline void meso_shade_batch_to_block(const meso_frame *frame, const meso_object *object,
                                             const meso_shade_batch *in, meso_fragment_block *b,
                                             size_t first) {
    meso_shade_batches_to_block(frame, object, in, 1, b, first);
}

/* meso_shade_fragments for a block, every light visible: the colour of each fragment from its
 * own position, normal, uv, tangent and bitangent, with the same bits. The per-object constants
 * are worked out once a block. */
void meso_shade_block(const meso_frame *frame, const meso_object *object, meso_fragment_block *b);

#endif
