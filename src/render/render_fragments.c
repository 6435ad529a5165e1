/* Fragments in structure-of-arrays blocks (render_internal.h, meso_fragment_block) and the
 * adapters between blocks and meso_fragment arrays: techniques written per fragment are shaded
 * from the rasterizer's blocks, and techniques written per block from hand-built fragments. */
#include <stdlib.h>
#include <string.h>

#include "render_internal.h"

void meso_fragment_block_get(const meso_fragment_block *b, size_t i, meso_fragment *f) {
    f->x = b->x[i], f->y = b->y[i];
    f->triangle = b->triangle[i];
    f->b0 = b->b0[i], f->b1 = b->b1[i], f->b2 = b->b2[i];
    f->position = (meso_vec3){b->px[i], b->py[i], b->pz[i]};
    f->normal = (meso_vec3){b->nx[i], b->ny[i], b->nz[i]};
    f->tangent = (meso_vec3){b->tx[i], b->ty[i], b->tz[i]};
    f->bitangent = (meso_vec3){b->bx[i], b->by[i], b->bz[i]};
    f->uv = (meso_vec2){b->u[i], b->v[i]};
    f->duv_dx = (meso_vec2){b->dudx[i], b->dvdx[i]};
    f->duv_dy = (meso_vec2){b->dudy[i], b->dvdy[i]};
    f->depth = b->depth[i];
    f->color = (meso_vec3){b->r[i], b->g[i], b->b[i]};
    f->out_depth = b->out_depth[i];
    f->discard = b->discard[i] != 0;
}

void meso_fragment_block_set(meso_fragment_block *b, size_t i, const meso_fragment *f) {
    b->x[i] = f->x, b->y[i] = f->y;
    b->triangle[i] = f->triangle;
    b->b0[i] = f->b0, b->b1[i] = f->b1, b->b2[i] = f->b2;
    b->px[i] = f->position.x, b->py[i] = f->position.y, b->pz[i] = f->position.z;
    b->nx[i] = f->normal.x, b->ny[i] = f->normal.y, b->nz[i] = f->normal.z;
    b->tx[i] = f->tangent.x, b->ty[i] = f->tangent.y, b->tz[i] = f->tangent.z;
    b->bx[i] = f->bitangent.x, b->by[i] = f->bitangent.y, b->bz[i] = f->bitangent.z;
    b->u[i] = f->uv.x, b->v[i] = f->uv.y;
    b->dudx[i] = f->duv_dx.x, b->dvdx[i] = f->duv_dx.y;
    b->dudy[i] = f->duv_dy.x, b->dvdy[i] = f->duv_dy.y;
    b->depth[i] = f->depth;
    b->r[i] = f->color.x, b->g[i] = f->color.y, b->b[i] = f->color.z;
    b->out_depth[i] = f->out_depth;
    b->discard[i] = f->discard ? 1 : 0;
}

void meso_fragment_block_pad(meso_fragment_block *b) {
    if (!b->count) return;
    meso_fragment last;
    meso_fragment_block_get(b, b->count - 1, &last);
    for (size_t i = b->count; i % 8; i++) meso_fragment_block_set(b, i, &last);
}

void meso_technique_shade_block(const meso_technique *t, const void *state, const meso_frame *frame,
                                const meso_object *object, meso_fragment_block *block,
                                meso_fragment *scratch) {
    if (t->shade_block) {
        t->shade_block(state, frame, object, block);
        return;
    }
    /* The adapter: the same fragments, in the same order, as one batch (so a technique sees
     * exactly the batches it saw before blocks existed), then the outputs back. */
    size_t count = block->count;
    for (size_t i = 0; i < count; i++) meso_fragment_block_get(block, i, &scratch[i]);
    t->shade(state, frame, object, scratch, count);
    for (size_t i = 0; i < count; i++) {
        const meso_fragment *f = &scratch[i];
        block->r[i] = f->color.x, block->g[i] = f->color.y, block->b[i] = f->color.z;
        block->out_depth[i] = f->out_depth;
        block->discard[i] = f->discard ? 1 : 0;
    }
}

meso_result meso_technique_shade(const meso_technique *t, const void *state,
                                 const meso_frame *frame, const meso_object *object,
                                 meso_fragment *fragments, size_t count) {
    if (!t->shade_block) {
        t->shade(state, frame, object, fragments, count);
        return MESO_OK;
    }
    meso_fragment_block *block = aligned_alloc(32, sizeof *block);
    if (!block) return MESO_ERROR_OUT_OF_MEMORY;
    for (size_t first = 0; first < count; first += MESO_FRAGMENT_BLOCK_CAPACITY) {
        size_t n = count - first < MESO_FRAGMENT_BLOCK_CAPACITY ? count - first
                                                                : MESO_FRAGMENT_BLOCK_CAPACITY;
        block->count = n;
        for (size_t i = 0; i < n; i++) meso_fragment_block_set(block, i, &fragments[first + i]);
        meso_fragment_block_pad(block);
        t->shade_block(state, frame, object, block);
        for (size_t i = 0; i < n; i++) {
            meso_fragment *f = &fragments[first + i];
            f->color = (meso_vec3){block->r[i], block->g[i], block->b[i]};
            f->out_depth = block->out_depth[i];
            f->discard = block->discard[i] != 0;
        }
    }
    free(block);
    return MESO_OK;
}
