/* The shared shading model (render_internal.h, meso_shade_point) eight points at a time, for
 * techniques that already hold their normals and texture coordinates in vectors
 * (render_simd.h). Shading lane by lane through meso_shade_point ran the whole eight-wide
 * model for one point: two thirds of parallax mapping's frame. */
#ifndef MESO_RENDER_SHADING_H
#define MESO_RENDER_SHADING_H

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

/* visibility[i] = 1 in every lane for the scene's lights. */
static inline void meso_shade_batch_all_visible(meso_shade_batch *in, const meso_frame *frame) {
    for (int i = 0; i < frame->scene->num_lights; i++) in->visibility[i] = v8_splat(1.0f);
}

#endif
