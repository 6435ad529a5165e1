/* Depth-only rasterization for shadow maps (meso_raster_depth_map, render_internal.h): the same
 * setup, fill rule, clipping and tiles as the colour pass, both faces, z_ndc * 0.5 + 0.5. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "raster_internal.h"
#include "meso/runtime.h"

typedef struct depth_job {
    const raster_bins *bins;
    float *depth;
} depth_job;

/* z_ndc * 0.5 + 0.5 of one triangle into the depth target over the samples [x0, x1] x [y0, y1]
 * (inside the triangle's sample box and the tile). A sample is covered when its three edge
 * functions are >= 0 (the colour pass's test, in the same 64-bit integers). Along a row each
 * edge function is linear in x, so the covered samples of a row are one run: the row stops at
 * the first uncovered sample after a covered one (the same samples as testing all of them). */
static void depth_triangle(const raster_triangle *tri, int x0, int x1, int y0, int y1, float *depth,
                           int width) {
    const int64_t half = RASTER_SUBPIXEL_ONE / 2;
    int64_t px = ((int64_t)x0 << RASTER_SUBPIXEL_BITS) + half;
    int64_t py = ((int64_t)y0 << RASTER_SUBPIXEL_BITS) + half;
    /* edge k runs from vertex k + 1: E_k = a_k (px - x[k+1]) + b_k (py - y[k+1]) + bias_k */
    int64_t row0 = (int64_t)tri->edge_a[0] * (px - tri->x[1]) +
                   (int64_t)tri->edge_b[0] * (py - tri->y[1]) + tri->bias[0];
    int64_t row1 = (int64_t)tri->edge_a[1] * (px - tri->x[2]) +
                   (int64_t)tri->edge_b[1] * (py - tri->y[2]) + tri->bias[1];
    int64_t row2 = (int64_t)tri->edge_a[2] * (px - tri->x[0]) +
                   (int64_t)tri->edge_b[2] * (py - tri->y[0]) + tri->bias[2];
    int64_t sx0 = (int64_t)tri->edge_a[0] * RASTER_SUBPIXEL_ONE;
    int64_t sx1 = (int64_t)tri->edge_a[1] * RASTER_SUBPIXEL_ONE;
    int64_t sx2 = (int64_t)tri->edge_a[2] * RASTER_SUBPIXEL_ONE;
    int64_t sy0 = (int64_t)tri->edge_b[0] * RASTER_SUBPIXEL_ONE;
    int64_t sy1 = (int64_t)tri->edge_b[1] * RASTER_SUBPIXEL_ONE;
    int64_t sy2 = (int64_t)tri->edge_b[2] * RASTER_SUBPIXEL_ONE;
    for (int y = y0; y <= y1; y++, row0 += sy0, row1 += sy1, row2 += sy2) {
        int64_t e0 = row0, e1 = row1, e2 = row2;
        float fy = (float)y + 0.5f - tri->ref_y;
        float *out = depth + (size_t)y * (size_t)width;
        int x = x0;
        for (; x <= x1 && (e0 | e1 | e2) < 0; x++) e0 += sx0, e1 += sx1, e2 += sx2;
        for (; x <= x1 && (e0 | e1 | e2) >= 0; x++, e0 += sx0, e1 += sx1, e2 += sx2) {
            float z = tri->zc + tri->za * ((float)x + 0.5f - tri->ref_x) + tri->zb * fy;
            if (z < out[x]) out[x] = z;
        }
    }
}

static void depth_tile(void *user, size_t job, int thread_index) {
    (void)thread_index;
    const depth_job *dj = user;
    const raster_bins *bins = dj->bins;
    int width = bins->desc.width, height = bins->desc.height;
    int tile = (int)job;
    int tx0 = (tile % bins->tiles_x) * RASTER_TILE_SIZE;
    int ty0 = (tile / bins->tiles_x) * RASTER_TILE_SIZE;
    int tx1 = tx0 + RASTER_TILE_SIZE - 1, ty1 = ty0 + RASTER_TILE_SIZE - 1;
    tx1 = tx1 > width - 1 ? width - 1 : tx1;
    ty1 = ty1 > height - 1 ? height - 1 : ty1;
    /* a row of the tile cleared from one of +inf (one copy instead of a store a sample) */
    float clear[RASTER_TILE_SIZE];
    for (int i = 0; i < RASTER_TILE_SIZE; i++) clear[i] = INFINITY;
    size_t row_bytes = (size_t)(tx1 - tx0 + 1) * sizeof(float);
    for (int y = ty0; y <= ty1; y++)
        memcpy(dj->depth + (size_t)y * (size_t)width + (size_t)tx0, clear, row_bytes);
    for (size_t c = 0; c < bins->num_chunks; c++) {
        const raster_chunk *chunk = &bins->chunks[c];
        size_t count;
        const uint32_t *list = raster_chunk_tile(chunk, tile, &count);
        for (size_t e = 0; e < count; e++) {
            const raster_triangle *tri = &chunk->triangles[list[e]];
            int x0 = tri->min_x > tx0 ? tri->min_x : tx0, x1 = tri->max_x < tx1 ? tri->max_x : tx1;
            int y0 = tri->min_y > ty0 ? tri->min_y : ty0, y1 = tri->max_y < ty1 ? tri->max_y : ty1;
            if (x0 > x1 || y0 > y1) continue;
            depth_triangle(tri, x0, x1, y0, y1, dj->depth, width);
        }
    }
}

struct meso_raster_depth_scratch {
    raster_bins bins;
};

size_t meso_raster_depth_scratch_memory(const meso_raster_depth_scratch *scratch) {
    if (!scratch) return 0;
    const raster_bins *bins = &scratch->bins;
    size_t bytes = sizeof(*scratch) + (size_t)bins->meshes_capacity * sizeof(raster_mesh) +
                   bins->chunks_capacity * sizeof(raster_chunk);
    for (size_t i = 0; i < bins->chunks_capacity; i++) {
        const raster_chunk *c = &bins->chunks[i];
        bytes += c->capacity * sizeof(raster_triangle) +
                 (c->tile_start_capacity + c->entries_capacity) * sizeof(uint32_t);
    }
    return bytes;
}

void meso_raster_depth_scratch_destroy(meso_raster_depth_scratch *scratch) {
    if (!scratch) return;
    raster_bins_release(&scratch->bins);
    free(scratch);
}

meso_result meso_raster_depth_map(meso_context *ctx, meso_raster_depth_scratch **scratch,
                                  const meso_mesh *mesh, meso_mat4 view_projection, int width,
                                  int height, float *depth) {
    if (!mesh || !depth || width <= 0 || height <= 0) {
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "depth map: invalid arguments (%d x %d)", width, height);
    }
    meso_raster_depth_scratch local;
    memset(&local, 0, sizeof(local));
    meso_raster_depth_scratch *kept = &local;
    if (scratch) {
        if (!*scratch) {
            *scratch = calloc(1, sizeof(**scratch));
            if (!*scratch)
                return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "depth map: scratch");
        }
        kept = *scratch;
    }
    raster_bins *bins = &kept->bins;
    raster_setup_desc desc = {.view_projection = view_projection,
                              .width = width,
                              .height = height,
                              .clip_z = true,
                              .cull_back = false,
                              .depth_plane = true,
                              .drop_uncovered = true};
    const meso_mesh *meshes[1] = {mesh};
#if MESO_HAS_AVX2_TECHNIQUES
    /* the setup's AVX2 copy where the techniques run theirs: 8 triangles at a time */
    meso_result r = (strcmp(meso_technique_isa(), "avx2") == 0
                         ? raster_bins_build_avx2
                         : raster_bins_build)(ctx, bins, meshes, NULL, 1, &desc);
#else
    meso_result r = raster_bins_build(ctx, bins, meshes, NULL, 1, &desc);
#endif
    if (r == MESO_OK) {
        depth_job dj = {bins, depth};
        meso_parallel_for(ctx, (size_t)bins->tiles_x * (size_t)bins->tiles_y, depth_tile, &dj);
    }
    if (kept == &local) raster_bins_release(bins);
    return r;
}
