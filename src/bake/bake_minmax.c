/* The min-max (maximum mip-map) pyramid of a height field: Tevs, Ihrke, Seidel 2008, "Maximum
 * mipmaps for fast, accurate, and scalable dynamic height field rendering" (I3D), §3. Level 0
 * bounds each bilinear patch by its four corner texels, so the bound is exact for the bilinear
 * surface meso samples (docs/design.md: bilinear between texel centres). See bake_minmax.h. */
#include <stdlib.h>
#include <string.h>

#include "meso/bake_minmax.h"
#include "meso/runtime.h"

#define SERIAL_BELOW_CELLS (256 * 256)

typedef struct minmax_job {
    const meso_heightfield *heightfield;
    meso_minmax_level *level;       /* the level written */
    const meso_minmax_level *child; /* the finer level read (NULL for level 0) */
} minmax_job;

/* Rows are independent jobs writing disjoint memory: byte-identical for any thread count. */
static void bake_level0_row(void *user, size_t job, int thread_index) {
    (void)thread_index;
    const minmax_job *w = user;
    const meso_heightfield *hf = w->heightfield;
    int j = (int)job, width = w->level->width;
    float *max_row = w->level->max + (size_t)j * (size_t)width;
    float *min_row = w->level->min + (size_t)j * (size_t)width;
    for (int i = 0; i < width; ++i) {
        float a = meso_heightfield_texel(hf, i, j), b = meso_heightfield_texel(hf, i + 1, j);
        float c = meso_heightfield_texel(hf, i, j + 1),
              d = meso_heightfield_texel(hf, i + 1, j + 1);
        float hi = a > b ? a : b, lo = a < b ? a : b;
        hi = c > hi ? c : hi;
        lo = c < lo ? c : lo;
        hi = d > hi ? d : hi;
        lo = d < lo ? d : lo;
        max_row[i] = hi;
        min_row[i] = lo;
    }
}

static void bake_parent_row(void *user, size_t job, int thread_index) {
    (void)thread_index;
    const minmax_job *w = user;
    const meso_minmax_level *c = w->child;
    int j = (int)job, width = w->level->width;
    float *max_row = w->level->max + (size_t)j * (size_t)width;
    float *min_row = w->level->min + (size_t)j * (size_t)width;
    for (int i = 0; i < width; ++i) {
        float hi = -INFINITY, lo = INFINITY;
        for (int dj = 0; dj < 2; ++dj) {
            int cj = 2 * j + dj;
            if (cj >= c->height) break;
            for (int di = 0; di < 2; ++di) {
                int ci = 2 * i + di;
                if (ci >= c->width) break;
                size_t k = (size_t)cj * (size_t)c->width + (size_t)ci;
                hi = c->max[k] > hi ? c->max[k] : hi;
                lo = c->min[k] < lo ? c->min[k] : lo;
            }
        }
        max_row[i] = hi;
        min_row[i] = lo;
    }
}

meso_result meso_minmax_pyramid_bake(meso_context *ctx, const meso_heightfield *heightfield,
                                     meso_minmax_pyramid **out_pyramid) {
    meso_minmax_pyramid *p = NULL;
    *out_pyramid = NULL;
    if (!heightfield || !heightfield->heights || heightfield->width <= 0 ||
        heightfield->height <= 0)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "minmax: heightfield: missing or empty");
    if (heightfield->width > MESO_MINMAX_MAX_SIDE || heightfield->height > MESO_MINMAX_MAX_SIDE)
        return meso_log_error(ctx, MESO_ERROR_LIMIT,
                              "minmax: heightfield: %d x %d exceeds the limit %d a side",
                              heightfield->width, heightfield->height, MESO_MINMAX_MAX_SIDE);
    p = calloc(1, sizeof *p);
    if (!p) goto oom;
    p->wrap = heightfield->wrap;
    p->source_hash = heightfield->hash;
    int w = heightfield->width, h = heightfield->height;
    size_t total = 0;
    for (;;) {
        meso_minmax_level *l = &p->levels[p->num_levels++];
        l->width = w;
        l->height = h;
        total += (size_t)w * (size_t)h;
        if (w == 1 && h == 1) break;
        w = (w + 1) / 2;
        h = (h + 1) / 2;
    }
    p->block_floats = 2 * total;
    p->block = malloc(p->block_floats * sizeof(float));
    if (!p->block) goto oom;
    size_t offset = 0;
    for (int l = 0; l < p->num_levels; ++l) {
        size_t n = (size_t)p->levels[l].width * (size_t)p->levels[l].height;
        p->levels[l].max = p->block + offset;
        p->levels[l].min = p->block + total + offset;
        offset += n;
    }
    for (int l = 0; l < p->num_levels; ++l) {
        minmax_job job = {heightfield, &p->levels[l], l ? &p->levels[l - 1] : NULL};
        meso_job_fn fn = l ? bake_parent_row : bake_level0_row;
        /* Small levels run on the calling thread: a parallel loop's start and end cost more
         * than their few rows (the same rows either way: byte-identical). */
        if ((size_t)p->levels[l].width * (size_t)p->levels[l].height >= SERIAL_BELOW_CELLS)
            meso_parallel_for(ctx, (size_t)p->levels[l].height, fn, &job);
        else
            for (int j = 0; j < p->levels[l].height; ++j) fn(&job, (size_t)j, 0);
    }
    *out_pyramid = p;
    return MESO_OK;
oom:
    meso_minmax_pyramid_destroy(p);
    return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "minmax: out of memory for %d x %d",
                          heightfield->width, heightfield->height);
}

size_t meso_minmax_pyramid_memory(const meso_minmax_pyramid *pyramid) {
    return pyramid ? pyramid->block_floats * sizeof(float) + sizeof *pyramid : 0;
}

void meso_minmax_pyramid_destroy(meso_minmax_pyramid *pyramid) {
    if (!pyramid) return;
    free(pyramid->block);
    free(pyramid);
}
