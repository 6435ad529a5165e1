/* The cone map of a periodic height field (bake_cone.h): per level-0 cell the highest corner
 * and a slope s with h(q) <= top + s * L1-distance(q, cell) over the whole torus, after Dummer
 * 2006, "Cone step mapping" (conservative cones): the largest ratio (h - top) / distance over the
 * texels within MESO_CONE_RADIUS that are higher than the cell's top, or the field's highest over
 * MESO_CONE_RADIUS + 1 if that is more, found by a branch and bound over the min-max pyramid
 * (bake_minmax.h) that opens a block only if its highest texel at its least distance could raise
 * the slope found so far. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake_internal.h"
#include "meso/bake_cache.h"
#include "meso/bake_cone.h"
#include "meso/bake_file.h"
#include "meso/bake_minmax.h"
#include "meso/runtime.h"

/* A depth-first walk holds at most 3 siblings a level plus the node opened. */
#define STACK_NODES (4 * MESO_MINMAX_MAX_LEVELS)

typedef struct cone_job {
    const meso_heightfield *heightfield;
    const meso_minmax_pyramid *pyramid;
    meso_cone_map *map;
} cone_job;

typedef struct cone_node {
    int level, i, j;
    double bound; /* the largest ratio a texel of the node could have */
} cone_node;

/* The distance in texels between the integer intervals [p0, p0 + 1] and [q0, q1] on a circle of
 * `period` texels (both given in [0, period]). */
static inline int circle_gap(int p0, int q0, int q1, int period) {
    int best = period;
    for (int k = -1; k <= 1; ++k) {
        int a = q0 + k * period - (p0 + 1), b = p0 - (q1 + k * period);
        int g = a > b ? a : b;
        g = g > 0 ? g : 0;
        best = g < best ? g : best;
    }
    return best;
}

/* The largest (h - top) / distance over the texels of level-0 cell (a, b) higher than top. */
static double leaf_ratio(const meso_heightfield *hf, int ci, int cj, int a, int b, float top) {
    double best = 0.0;
    for (int dj = 0; dj < 2; ++dj) {
        for (int di = 0; di < 2; ++di) {
            int x = a + di, y = b + dj; /* in [0, width], [0, height]: texel width is texel 0 */
            float h =
                hf->heights[(size_t)(y % hf->height) * (size_t)hf->width + (size_t)(x % hf->width)];
            if (!(h > top)) continue;
            int d = circle_gap(ci, x, x, hf->width) + circle_gap(cj, y, y, hf->height);
            /* d >= 1: the cell's own corners are no higher than its top */
            double ratio = ((double)h - (double)top) / (double)d;
            best = ratio > best ? ratio : best;
        }
    }
    return best;
}

/* The bound of level-l cell (i, j) seen from level-0 cell (ci, cj) with top `top`: 0 when it
 * cannot hold a texel higher than top, INFINITY when it touches the cell. */
static double node_bound(const meso_minmax_pyramid *p, int level, int i, int j, int ci, int cj,
                         float top) {
    const meso_minmax_level *lv = &p->levels[level];
    float hi = lv->max[(size_t)j * (size_t)lv->width + (size_t)i];
    if (!(hi > top)) return 0.0;
    int w = p->levels[0].width, h = p->levels[0].height;
    int x0 = i << level, x1 = (i + 1) << level, y0 = j << level, y1 = (j + 1) << level;
    x1 = x1 < w ? x1 : w;
    y1 = y1 < h ? y1 : h;
    int d = circle_gap(ci, x0, x1, w) + circle_gap(cj, y0, y1, h);
    if (d > MESO_CONE_RADIUS) return 0.0; /* the start slope bounds it */
    return d > 0 ? ((double)hi - (double)top) / (double)d : INFINITY;
}

static float cell_slope(const meso_heightfield *hf, const meso_minmax_pyramid *p, int ci, int cj,
                        float top) {
    int root = p->num_levels - 1;
    if (!(p->levels[root].max[0] > top)) return 0.0f; /* nothing in the field is higher */
    cone_node stack[STACK_NODES];
    int n = 0;
    stack[n++] = (cone_node){root, 0, 0, INFINITY};
    /* Beyond MESO_CONE_RADIUS texels (L1) no texel can rise faster than the field's highest over
     * that distance: the search starts from that slope and opens only nearer blocks. */
    double best = ((double)p->levels[root].max[0] - (double)top) / (double)(MESO_CONE_RADIUS + 1);
    while (n > 0) {
        cone_node node = stack[--n];
        if (!(node.bound > best)) continue;
        if (node.level == 0) {
            double r = leaf_ratio(hf, ci, cj, node.i, node.j, top);
            best = r > best ? r : best;
            continue;
        }
        /* the children, pushed in increasing bound so the most promising is opened first */
        const meso_minmax_level *child = &p->levels[node.level - 1];
        cone_node kids[4];
        int m = 0;
        for (int dj = 0; dj < 2; ++dj) {
            for (int di = 0; di < 2; ++di) {
                int i = 2 * node.i + di, j = 2 * node.j + dj;
                if (i >= child->width || j >= child->height) continue;
                double b = node_bound(p, node.level - 1, i, j, ci, cj, top);
                if (!(b > best)) continue;
                int k = m++;
                for (; k > 0 && kids[k - 1].bound > b; --k) kids[k] = kids[k - 1];
                kids[k] = (cone_node){node.level - 1, i, j, b};
            }
        }
        for (int k = 0; k < m; ++k) stack[n++] = kids[k];
    }
    /* rounded up: the bound must hold for the float the tracer reads */
    float s = (float)best;
    if ((double)s < best) s = nextafterf(s, INFINITY);
    return s;
}

/* Rows of cells are independent jobs writing disjoint memory: byte-identical for any thread
 * count. */
static void bake_cone_row(void *user, size_t job, int thread_index) {
    (void)thread_index;
    const cone_job *w = user;
    const meso_minmax_level *l0 = &w->pyramid->levels[0];
    int j = (int)job;
    float *row = w->map->cells + 2 * (size_t)j * (size_t)w->map->width;
    for (int i = 0; i < w->map->width; ++i) {
        float top = l0->max[(size_t)j * (size_t)l0->width + (size_t)i];
        row[2 * i] = top;
        row[2 * i + 1] = cell_slope(w->heightfield, w->pyramid, i, j, top);
    }
}

meso_result meso_cone_map_bake(meso_context *ctx, const meso_heightfield *heightfield,
                               const meso_minmax_pyramid *pyramid, meso_cone_map **out_map) {
    *out_map = NULL;
    if (!heightfield || !heightfield->heights || heightfield->width <= 0 ||
        heightfield->height <= 0)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "cone: heightfield: missing or empty");
    if (heightfield->wrap == MESO_WRAP_CLAMP)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "cone: heightfield: clamped to its edges (the map needs a "
                              "repeating field)");
    if (!pyramid || pyramid->num_levels < 1 || pyramid->levels[0].width != heightfield->width ||
        pyramid->levels[0].height != heightfield->height ||
        pyramid->source_hash != heightfield->hash)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "cone: pyramid: missing or baked from another height field");
    meso_cone_map *map = calloc(1, sizeof *map);
    if (!map) goto oom;
    map->width = heightfield->width;
    map->height = heightfield->height;
    map->source_hash = heightfield->hash;
    map->cells = malloc(2 * (size_t)map->width * (size_t)map->height * sizeof(float));
    if (!map->cells) goto oom;
    cone_job job = {heightfield, pyramid, map};
    meso_parallel_for(ctx, (size_t)map->height, bake_cone_row, &job);
    *out_map = map;
    return MESO_OK;
oom:
    meso_cone_map_destroy(map);
    return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "cone: out of memory for %d x %d",
                          heightfield->width, heightfield->height);
}

/* The cache entry's key: the field, the radius and the cell layout (the version). */
static uint64_t cone_cache_key(uint64_t source_hash) {
    int32_t fields[2] = {MESO_CONE_RADIUS, MESO_CONE_KIND_VERSION};
    uint64_t key = meso_hash64(&source_hash, sizeof source_hash, MESO_HASH_SEED);
    return meso_hash64(fields, sizeof fields, key);
}

/* A cache entry's cells into a new map; MESO_ERROR_FORMAT (logged) if it does not fit. */
static meso_result cone_from_bake_file(meso_context *ctx, const meso_bake_file *bake,
                                       const meso_heightfield *heightfield,
                                       meso_cone_map **out_map) {
    const meso_bake_array *cells = meso_bake_file_find(bake, "cells");
    if (!cells || cells->type != MESO_BAKE_F32 || cells->num_dims != 3 ||
        cells->dims[0] != (uint64_t)heightfield->height ||
        cells->dims[1] != (uint64_t)heightfield->width || cells->dims[2] != 2)
        return meso_log_error(ctx, MESO_ERROR_FORMAT,
                              "cone cache entry: array \"cells\" missing "
                              "or not %d x %d x 2 floats",
                              heightfield->height, heightfield->width);
    meso_result r = meso_bake_array_check_values(ctx, "cone cache entry", cells, -1e30, 1e30);
    if (r != MESO_OK) return r;
    const float *values = cells->data;
    for (size_t k = 1; k < 2 * (size_t)heightfield->width * (size_t)heightfield->height; k += 2)
        if (!(values[k] >= 0.0f)) /* a negative slope would let a ray step through the surface */
            return meso_log_error(ctx, MESO_ERROR_FORMAT,
                                  "cone cache entry: array \"cells\": slope %zu is %g, not >= 0",
                                  k / 2, (double)values[k]);
    meso_cone_map *map = calloc(1, sizeof *map);
    size_t bytes = 2 * (size_t)heightfield->width * (size_t)heightfield->height * sizeof(float);
    if (!map || !(map->cells = malloc(bytes))) {
        free(map);
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "cone: out of memory");
    }
    map->width = heightfield->width;
    map->height = heightfield->height;
    map->source_hash = heightfield->hash;
    memcpy(map->cells, cells->data, bytes);
    *out_map = map;
    return MESO_OK;
}

/* The steps of meso_bake_cache_run for a cone map; desc: a cone_source. */
typedef struct cone_source {
    const meso_heightfield *heightfield;
    const meso_minmax_pyramid *pyramid;
} cone_source;

static meso_result cone_from_file(meso_context *ctx, const meso_bake_file *bake, const char *where,
                                  const void *desc, void *out) {
    (void)where;
    return cone_from_bake_file(ctx, bake, ((const cone_source *)desc)->heightfield, out);
}

static meso_result cone_bake(meso_context *ctx, const void *desc, void *out) {
    const cone_source *source = desc;
    return meso_cone_map_bake(ctx, source->heightfield, source->pyramid, out);
}

static meso_result cone_store(meso_context *ctx, const meso_cached_bake *entry, const void *out) {
    const meso_cone_map *map = *(meso_cone_map *const *)out;
    meso_bake_file bake = {.kind = MESO_CONE_KIND,
                           .kind_version = MESO_CONE_KIND_VERSION,
                           .source_hash = entry->source_hash,
                           .params_json = "{}",
                           .num_arrays = 1};
    bake.arrays[0] = (meso_bake_array){.name = "cells",
                                       .type = MESO_BAKE_F32,
                                       .num_dims = 3,
                                       .dims = {(uint64_t)map->height, (uint64_t)map->width, 2},
                                       .data = map->cells};
    return meso_bake_cache_save(ctx, &bake, entry->key);
}

meso_result meso_cone_map_bake_cached(meso_context *ctx, const meso_heightfield *heightfield,
                                      const meso_minmax_pyramid *pyramid, meso_cone_map **out_map) {
    *out_map = NULL;
    if (!heightfield) return meso_cone_map_bake(ctx, heightfield, pyramid, out_map);
    cone_source source = {heightfield, pyramid};
    meso_cached_bake entry = {MESO_CONE_KIND,
                              MESO_CONE_KIND_VERSION,
                              "cone",
                              cone_cache_key(heightfield->hash),
                              heightfield->hash,
                              &source,
                              cone_from_file,
                              cone_bake,
                              cone_store};
    return meso_bake_cache_run(ctx, &entry, out_map);
}

size_t meso_cone_map_memory(const meso_cone_map *map) {
    return map ? 2 * (size_t)map->width * (size_t)map->height * sizeof(float) + sizeof *map : 0;
}

void meso_cone_map_destroy(meso_cone_map *map) {
    if (!map) return;
    free(map->cells);
    free(map);
}
