/* Rasterizer back half: per-tile coverage, early depth test, fragment batches handed to the
 * technique, depth-tested write-back, wireframe overlay, and the supersampling resolve.
 *
 * Every tile is one job. It clears its own part of the target, then walks the chunks in order
 * and, in each, the triangles binned to it in order; fragments are shaded one batch per
 * (object, tile), split where a triangle repeats a sample of the batch. No job reads what
 * another writes, so the bytes never depend on the number of threads or the schedule.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "raster_internal.h"
#include "render_simd.h"

#define TILE_SAMPLES (RASTER_TILE_SIZE * RASTER_TILE_SIZE)
_Static_assert(TILE_SAMPLES <= MESO_FRAGMENT_BLOCK_CAPACITY, "a batch holds a whole tile");
/* Wireframe: an edge sample is drawn when its depth is within this slack of the buffer's (the
 * edge lies on the surface the buffer holds, up to rounding of two different evaluations). */
#define WIRE_DEPTH_RELATIVE_SLACK 1.001f
#define WIRE_DEPTH_ABSOLUTE_SLACK 1e-4f
/* Wire colour: black, or white where the image's luma (Rec. 709 weights) is below this, low
 * enough that the switch hides in the darkest regions. */
#define WIRE_DARK_LUMA 0.03f

typedef struct draw_job {
    raster_pass *pass;
    const meso_frame *frame;
    const raster_object *objects;
    bool wireframe;
    float *color, *coverage, *depth;
} draw_job;

/* Attributes of a source triangle's three vertices. */
typedef struct vertex_attributes {
    meso_vec3 n[3], t[3], b[3];
    meso_vec2 uv[3];
    bool has_tangents, has_uvs;
} vertex_attributes;

static void load_attributes(const meso_mesh *mesh, uint32_t triangle, vertex_attributes *a) {
    const uint32_t *idx = mesh->indices + 3 * (size_t)triangle;
    a->has_tangents = mesh->tangents && mesh->bitangents;
    a->has_uvs = mesh->uvs != NULL;
    for (int k = 0; k < 3; k++) {
        a->n[k] = mesh->normals ? mesh->normals[idx[k]] : (meso_vec3){0.0f, 0.0f, 0.0f};
        if (a->has_tangents) {
            a->t[k] = mesh->tangents[idx[k]];
            a->b[k] = mesh->bitangents[idx[k]];
        }
        if (a->has_uvs) a->uv[k] = mesh->uvs[idx[k]];
    }
}

#define LANES V8_LANES
#define splat v8_splat

/* Fill the inputs and preset the outputs of n fragments from their sample positions and view
 * depths, 8 at a time (GCC vector extensions), into lanes first..first+n-1 of the block. The
 * inputs are padded to whole groups of 8 (cover_triangle), so up to 7 lanes past first+n are
 * written too; the next triangle's fill or flush_batch's padding writes over them. */
static void fill_fragments(const raster_triangle *tri, const meso_frame *frame,
                           const vertex_attributes *va, size_t n, const int32_t *xs,
                           const int32_t *ys, const float *depths, meso_fragment_block *block,
                           size_t first) {
    const v8f ga0 = splat(tri->ga[0]), ga1 = splat(tri->ga[1]), ga2 = splat(tri->ga[2]);
    const v8f gb0 = splat(tri->gb[0]), gb1 = splat(tri->gb[1]), gb2 = splat(tri->gb[2]);
    const v8f gc0 = splat(tri->gc[0]), gc1 = splat(tri->gc[1]), gc2 = splat(tri->gc[2]);
    const v8f ref_x = splat(tri->ref_x), ref_y = splat(tri->ref_y);
    const v8i triangle = v8i_splat((int32_t)tri->triangle);
    const v8f zero = splat(0.0f);
    const uint64_t no_discard = 0;
#define STORE(array, value) memcpy(block->array + at, &(value), sizeof(v8f))
    for (size_t i = 0; i < n; i += LANES) {
        size_t at = first + i;
        v8i ix, iy;
        v8f d;
        /* the arrays are padded to whole groups of 8 by the caller */
        memcpy(&ix, xs + i, sizeof(ix));
        memcpy(&iy, ys + i, sizeof(iy));
        memcpy(&d, depths + i, sizeof(d));
        v8f sx = __builtin_convertvector(ix, v8f) + splat(0.5f);
        v8f sy = __builtin_convertvector(iy, v8f) + splat(0.5f);
        v8f fx = sx - ref_x, fy = sy - ref_y;
        v8f b0 = (gc0 + gb0 * fy + ga0 * fx) * d;
        v8f b1 = (gc1 + gb1 * fy + ga1 * fx) * d;
        v8f b2 = (gc2 + gb2 * fy + ga2 * fx) * d;
        STORE(x, sx), STORE(y, sy), STORE(triangle, triangle);
        STORE(b0, b0), STORE(b1, b1), STORE(b2, b2);
        /* On the camera ray through the sample centre: the same ray the reference traces
         * (meso_frame_ray_direction). */
        v8f dx = splat(frame->corner.x) +
                 (splat(frame->pixel_right.x) * sx + splat(frame->pixel_down.x) * sy);
        v8f dy = splat(frame->corner.y) +
                 (splat(frame->pixel_right.y) * sx + splat(frame->pixel_down.y) * sy);
        v8f dz = splat(frame->corner.z) +
                 (splat(frame->pixel_right.z) * sx + splat(frame->pixel_down.z) * sy);
        v8f px = splat(frame->eye.x) + dx * d, py = splat(frame->eye.y) + dy * d;
        v8f pz = splat(frame->eye.z) + dz * d;
        STORE(px, px), STORE(py, py), STORE(pz, pz);
#define INTERP(arr, c) (splat(arr[0].c) * b0 + splat(arr[1].c) * b1 + splat(arr[2].c) * b2)
        v8f nx = INTERP(va->n, x), ny = INTERP(va->n, y), nz = INTERP(va->n, z);
        v8f len2 = nx * nx + ny * ny + nz * nz;
        v8f inv = v8_select(len2 > splat(0.0f), splat(1.0f) / v8_sqrt(len2), splat(1.0f));
        nx *= inv, ny *= inv, nz *= inv;
        STORE(nx, nx), STORE(ny, ny), STORE(nz, nz);
        if (va->has_tangents) {
            v8f tx = INTERP(va->t, x), ty = INTERP(va->t, y), tz = INTERP(va->t, z);
            v8f bx = INTERP(va->b, x), by = INTERP(va->b, y), bz = INTERP(va->b, z);
            STORE(tx, tx), STORE(ty, ty), STORE(tz, tz);
            STORE(bx, bx), STORE(by, by), STORE(bz, bz);
        } else {
            STORE(tx, zero), STORE(ty, zero), STORE(tz, zero);
            STORE(bx, zero), STORE(by, zero), STORE(bz, zero);
        }
        if (va->has_uvs) {
            v8f u = INTERP(va->uv, x), v = INTERP(va->uv, y);
            STORE(u, u), STORE(v, v);
        } else {
            STORE(u, zero), STORE(v, zero);
        }
#undef INTERP
        STORE(depth, d), STORE(out_depth, d);
        STORE(r, zero), STORE(g, zero), STORE(b, zero);
        memcpy(block->discard + at, &no_discard, sizeof(no_discard));
    }
#undef STORE
}

/* The samples of one triangle that pass coverage and the early depth test, before their
 * attributes are filled: sample position, view depth, tile-buffer index. Padded by one group of
 * 8 for the vector fill. */
typedef struct covered_samples {
    int32_t x[TILE_SAMPLES + LANES], y[TILE_SAMPLES + LANES];
    float depth[TILE_SAMPLES + LANES];
} covered_samples;

/* Covered samples of `tri` inside [x0, x1] x [y0, y1] that pass the depth test go to `out` and
 * their tile-buffer indices to `pixels`; returns how many. Coverage and the depth test compact
 * their survivors without branches (small triangles make those branches unpredictable). */
static size_t cover_triangle(const raster_triangle *tri, int x0, int y0, int x1, int y1, int tx0,
                             int ty0, const float *depth, covered_samples *out, uint32_t *pixels) {
    const int64_t half = RASTER_SUBPIXEL_ONE / 2;
    int64_t px = ((int64_t)x0 << RASTER_SUBPIXEL_BITS) + half;
    int64_t py = ((int64_t)y0 << RASTER_SUBPIXEL_BITS) + half;
    int64_t row[3], step_x[3], step_y[3];
    for (int k = 0; k < 3; k++) {
        int a = (k + 1) % 3;
        row[k] = (int64_t)tri->edge_a[k] * (px - tri->x[a]) +
                 (int64_t)tri->edge_b[k] * (py - tri->y[a]) + tri->bias[k];
        step_x[k] = (int64_t)tri->edge_a[k] * RASTER_SUBPIXEL_ONE;
        step_y[k] = (int64_t)tri->edge_b[k] * RASTER_SUBPIXEL_ONE;
    }
    const v8f ga0 = splat(tri->ga[0]), ga1 = splat(tri->ga[1]), ga2 = splat(tri->ga[2]);
    const v8f ref_x = splat(tri->ref_x);
    /* padded by one group of 8, and every entry a sample of the row, so that whole groups of
     * candidates read valid depths */
    int candidates[RASTER_TILE_SIZE + LANES];
    for (int i = 0; i < RASTER_TILE_SIZE + LANES; i++) candidates[i] = x0;
    size_t n = 0;
    for (int y = y0; y <= y1; y++) {
        int64_t e0 = row[0], e1 = row[1], e2 = row[2];
        /* The edge functions are linear along the row: their signs at both ends accept or
         * reject the whole row at once (most rows of a large triangle). */
        int64_t span = x1 - x0;
        int64_t f0 = e0 + step_x[0] * span, f1 = e1 + step_x[1] * span, f2 = e2 + step_x[2] * span;
        row[0] += step_y[0], row[1] += step_y[1], row[2] += step_y[2];
        if ((e0 & f0) < 0 || (e1 & f1) < 0 || (e2 & f2) < 0) continue; /* outside one edge */
        int m = 0;
        if ((e0 | e1 | e2 | f0 | f1 | f2) >= 0) { /* inside all three */
            for (int x = x0; x <= x1; x++) candidates[m++] = x;
        } else {
            for (int x = x0; x <= x1; x++, e0 += step_x[0], e1 += step_x[1], e2 += step_x[2]) {
                candidates[m] = x;
                m += (e0 | e1 | e2) >= 0;
            }
            if (!m) continue;
        }
        float fy = (float)y + 0.5f - tri->ref_y;
        v8f cy0 = splat(tri->gc[0] + tri->gb[0] * fy), cy1 = splat(tri->gc[1] + tri->gb[1] * fy);
        v8f cy2 = splat(tri->gc[2] + tri->gb[2] * fy);
        /* depth: the tile's own buffer, RASTER_TILE_SIZE a row, origin (tx0, ty0) */
        const float *zrow = depth + (y - ty0) * RASTER_TILE_SIZE;
        uint32_t base = (uint32_t)((y - ty0) * RASTER_TILE_SIZE);
        /* The depths of eight candidates at a time: one vector division instead of eight. */
        for (int first = 0; first < m; first += LANES) {
            v8i x, column;
            memcpy(&x, candidates + first, sizeof(x));
            column = x - v8i_splat(tx0);
            v8f fx = (__builtin_convertvector(x, v8f) + splat(0.5f)) - ref_x;
            v8f inv_depth = (cy0 + ga0 * fx) + (cy1 + ga1 * fx) + (cy2 + ga2 * fx);
            v8f d = splat(1.0f) / inv_depth;
            /* kept when in front of the camera and nearer than the buffer; a NaN fails both */
            int keep = v8_mask_bits((inv_depth > splat(0.0f)) & (d < v8_gather(zrow, column)));
            int lanes = m - first < LANES ? m - first : LANES;
            if (lanes == LANES && keep == 0xff) { /* all eight kept (inside large triangles) */
                v8i pixel = v8i_splat((int32_t)base) + column;
                memcpy(pixels + n, &pixel, sizeof pixel);
                memcpy(out->depth + n, &d, sizeof d);
                memcpy(out->x + n, &x, sizeof x);
                v8i row_y = v8i_splat(y);
                memcpy(out->y + n, &row_y, sizeof row_y);
                n += LANES;
                continue;
            }
            for (int k = 0; k < lanes; k++) { /* compacted without branches */
                pixels[n] = base + (uint32_t)column[k];
                out->depth[n] = d[k];
                out->x[n] = x[k];
                out->y[n] = y;
                n += (size_t)(keep >> k & 1);
            }
        }
    }
    if (!n) return 0;
    for (size_t i = n; i % LANES; i++) { /* unused lanes repeat the last fragment */
        out->x[i] = out->x[n - 1], out->y[i] = out->y[n - 1], out->depth[i] = out->depth[n - 1];
    }
    return n;
}

/* Mark the samples of the triangle's edges inside the tile (1-sample lines, sampled at the
 * centres along the major axis) that are not behind the depth buffer. */
static void mark_edges(const raster_triangle *tri, int tx0, int ty0, int tx1, int ty1,
                       const float *depth, uint8_t *wire) {
    for (int k = 0; k < 3; k++) {
        int a = k, b = (k + 1) % 3;
        float ax = (float)tri->x[a] / RASTER_SUBPIXEL_ONE,
              ay = (float)tri->y[a] / RASTER_SUBPIXEL_ONE;
        float bx = (float)tri->x[b] / RASTER_SUBPIXEL_ONE,
              by = (float)tri->y[b] / RASTER_SUBPIXEL_ONE;
        float dx = bx - ax, dy = by - ay;
        bool along_x = fabsf(dx) >= fabsf(dy);
        float lo = along_x ? fminf(ax, bx) : fminf(ay, by);
        float hi = along_x ? fmaxf(ax, bx) : fmaxf(ay, by);
        int i0 = (int)ceilf(lo - 0.5f), i1 = (int)floorf(hi - 0.5f);
        int clip0 = along_x ? tx0 : ty0, clip1 = along_x ? tx1 : ty1;
        i0 = i0 < clip0 ? clip0 : i0;
        i1 = i1 > clip1 ? clip1 : i1;
        for (int i = i0; i <= i1; i++) {
            float c = (float)i + 0.5f;
            float x, y;
            if (along_x) {
                x = c;
                y = dx != 0.0f ? ay + (c - ax) / dx * dy : ay;
            } else {
                y = c;
                x = dy != 0.0f ? ax + (c - ay) / dy * dx : ax;
            }
            int px = along_x ? i : (int)floorf(x), py = along_x ? (int)floorf(y) : i;
            if (px < tx0 || px > tx1 || py < ty0 || py > ty1) continue;
            float fx = x - tri->ref_x, fy = y - tri->ref_y;
            float inv_depth = 0.0f;
            for (int j = 0; j < 3; j++) inv_depth += tri->gc[j] + tri->ga[j] * fx + tri->gb[j] * fy;
            if (!(inv_depth > 0.0f)) continue;
            float d = 1.0f / inv_depth;
            float z = depth[(py - ty0) * RASTER_TILE_SIZE + (px - tx0)];
            if (d <= z * WIRE_DEPTH_RELATIVE_SLACK + WIRE_DEPTH_ABSOLUTE_SLACK || !isfinite(z))
                wire[(py - ty0) * RASTER_TILE_SIZE + (px - tx0)] = 1;
        }
    }
}

/* Copy n floats to the target. Plain stores (memcpy), not non-temporal ones: with the tile
 * pass in the AVX2 copy, _mm256_stream_ps made an empty 512^2 frame 0.27-0.33 ms against
 * 0.15-0.24 ms for memcpy (meso bench, 5 interleaved runs, issue 16; docs/performance.md): the
 * next frame and the image conversion read the target back from the cache. */
static inline void copy_floats(float *dst, const float *src, size_t n) {
    memcpy(dst, src, n * sizeof(float));
}

/* Fragments of one object in one tile waiting to be shaded; no two share a sample. */
typedef struct tile_batch {
    const raster_object *object;
    const meso_frame *frame;
    meso_fragment_block *block;
    meso_fragment *scratch; /* the adapter's fragments (render_fragments.c) */
    uint32_t *pixels;       /* tile-buffer index of each fragment */
    uint8_t *pending;       /* per tile sample: 1 while a fragment of the batch covers it */
    float *color, *coverage, *depth; /* the tile's buffers */
    size_t count;
    uint64_t shaded; /* fragments shaded in the tile so far */
} tile_batch;

/* Shade the batch and write the fragments that stay in front; empty the batch. */
static void flush_batch(tile_batch *b) {
    if (!b->count) return;
    const raster_object *obj = b->object;
    meso_fragment_block *block = b->block;
    block->count = b->count;
    /* each triangle's fill pads its own last group; the block's last group is padded here */
    meso_fragment_block_pad(block);
    meso_technique_shade_block(obj->technique, obj->state, b->frame, obj->object, block,
                               b->scratch);
    float *depth = b->depth, *coverage = b->coverage, *color = b->color;
    const uint32_t *pixels = b->pixels;
    size_t count = b->count;
    /* The batch never repeats a sample, so the depths it tests against can be read eight at a
     * time before any is written. */
    for (size_t first = 0; first < count; first += LANES) {
        int lanes = count - first < LANES ? (int)(count - first) : LANES;
        int live = (1 << lanes) - 1;
        v8i pix;
        memcpy(&pix, pixels + first, sizeof pix);
        pix = pix & (v8i)v8_mask_from_bits(live); /* the entries past count are stale */
        v8f z, old = v8_gather(depth, pix);
        memcpy(&z, block->out_depth + first, sizeof z);
        /* behind, or NaN: nothing drawn */
        for (int keep = v8_mask_bits(z < old) & live; keep; keep &= keep - 1) {
            int k = __builtin_ctz((unsigned)keep);
            size_t i = first + (size_t)k;
            if (block->discard[i]) continue; /* discarded: nothing drawn */
            uint32_t p = (uint32_t)pix[k];
            depth[p] = z[k];
            coverage[p] = 1.0f;
            color[3 * p + 0] = block->r[i];
            color[3 * p + 1] = block->g[i];
            color[3 * p + 2] = block->b[i];
        }
    }
    /* release the batch's samples: the whole mask at once when the batch is a large part of
     * the tile */
    if (count * 8 > TILE_SAMPLES)
        memset(b->pending, 0, TILE_SAMPLES);
    else
        for (size_t i = 0; i < count; i++) b->pending[pixels[i]] = 0;
    b->shaded += b->count;
    b->count = 0;
}

static void draw_tile(void *user, size_t job, int thread_index) {
    const draw_job *dj = user;
    raster_pass *pass = dj->pass;
    const raster_bins *bins = &pass->bins;
    const meso_frame *frame = dj->frame;
    raster_thread_scratch *scratch = &pass->threads[thread_index];
    int tile = (int)job;
    int tx0 = (tile % bins->tiles_x) * RASTER_TILE_SIZE;
    int ty0 = (tile / bins->tiles_x) * RASTER_TILE_SIZE;
    int tx1 = tx0 + RASTER_TILE_SIZE - 1, ty1 = ty0 + RASTER_TILE_SIZE - 1;
    tx1 = tx1 > frame->width - 1 ? frame->width - 1 : tx1;
    ty1 = ty1 > frame->height - 1 ? frame->height - 1 : ty1;
    const size_t width = (size_t)frame->width;
    size_t tw = (size_t)(tx1 - tx0 + 1);
    meso_progress_advance(frame->progress, tw * (size_t)(ty1 - ty0 + 1));
    bool empty = true;
    for (size_t c = 0; c < bins->num_chunks && empty; c++) {
        size_t count;
        raster_chunk_tile(&bins->chunks[c], tile, &count);
        empty = count == 0;
    }
    if (empty) { /* background straight into the target */
        for (int y = ty0; y <= ty1; y++) {
            size_t p = (size_t)y * width + (size_t)tx0;
            copy_floats(dj->color + 3 * p, pass->clear_color, 3 * tw);
            copy_floats(dj->coverage + p, pass->clear_coverage, tw);
            copy_floats(dj->depth + p, pass->clear_depth, tw);
        }
        pass->tile_fragments[tile] = 0;
        return;
    }
    /* The tile renders into the thread's own small buffers (they stay in cache) and is copied
     * out once at the end: every target sample is written exactly once a frame. */
    float *color = scratch->color, *coverage = scratch->coverage, *depth = scratch->depth;
    memcpy(color, pass->clear_color, 3 * TILE_SAMPLES * sizeof(float));
    memcpy(coverage, pass->clear_coverage, TILE_SAMPLES * sizeof(float));
    memcpy(depth, pass->clear_depth, TILE_SAMPLES * sizeof(float));
    /* One batch per (object, tile): the fragments of consecutive triangles of one object
     * gather until the object changes or a triangle covers a sample already in the batch.
     * Flushing on such a repeat before its depth test keeps every early depth test exactly
     * as it was with a batch per triangle: a sample not in the batch holds its final depth,
     * and write-back only lowers depths, so a sample rejected against the batch's older
     * depth would be rejected against the newer one too. The same fragments are shaded and
     * written, hence the same bytes. */
    tile_batch batch = {.block = scratch->block,
                        .scratch = scratch->fragments,
                        .pixels = scratch->pixels,
                        .pending = scratch->pending,
                        .color = color,
                        .coverage = coverage,
                        .depth = depth,
                        .frame = frame};
    covered_samples *covered = scratch->covered;
    for (size_t c = 0; c < bins->num_chunks; c++) {
        const raster_chunk *chunk = &bins->chunks[c];
        size_t count;
        const uint32_t *list = raster_chunk_tile(chunk, tile, &count);
        if (!count) continue;
        const raster_object *obj = &dj->objects[chunk->mesh];
        if (obj != batch.object) flush_batch(&batch);
        batch.object = obj;
        const meso_mesh *mesh = bins->meshes[chunk->mesh].mesh;
        for (size_t e = 0; e < count; e++) {
            const raster_triangle *tri = &chunk->triangles[list[e]];
            int x0 = tri->min_x > tx0 ? tri->min_x : tx0, x1 = tri->max_x < tx1 ? tri->max_x : tx1;
            int y0 = tri->min_y > ty0 ? tri->min_y : ty0, y1 = tri->max_y < ty1 ? tri->max_y : ty1;
            if (x0 > x1 || y0 > y1) continue;
            uint32_t *pixels = batch.pixels + batch.count;
            size_t n = cover_triangle(tri, x0, y0, x1, y1, tx0, ty0, depth, covered, pixels);
            if (!n) continue;
            uint8_t repeats = 0;
            for (size_t i = 0; i < n; i++) { /* a triangle covers a sample once */
                repeats |= batch.pending[pixels[i]];
                batch.pending[pixels[i]] = 1;
            }
            if (repeats) { /* test again against the depths the batch writes */
                for (size_t i = 0; i < n; i++) batch.pending[pixels[i]] = 0;
                flush_batch(&batch);
                pixels = batch.pixels;
                n = cover_triangle(tri, x0, y0, x1, y1, tx0, ty0, depth, covered, pixels);
                for (size_t i = 0; i < n; i++) batch.pending[pixels[i]] = 1;
                if (!n) continue;
            }
            vertex_attributes va;
            load_attributes(mesh, tri->triangle, &va);
            fill_fragments(tri, frame, &va, n, covered->x, covered->y, covered->depth, batch.block,
                           batch.count);
            batch.count += n;
        }
    }
    flush_batch(&batch);
    uint64_t fragments = batch.shaded;
    pass->tile_fragments[tile] = fragments;

    if (dj->wireframe) {
        uint8_t *wire = scratch->wire;
        memset(wire, 0, TILE_SAMPLES);
        for (size_t c = 0; c < bins->num_chunks; c++) {
            const raster_chunk *chunk = &bins->chunks[c];
            size_t count;
            const uint32_t *list = raster_chunk_tile(chunk, tile, &count);
            for (size_t e = 0; e < count; e++)
                mark_edges(&chunk->triangles[list[e]], tx0, ty0, tx1, ty1, depth, wire);
        }
        /* A contrasting colour: black lines, white ones where the image is nearly black. */
        for (int i = 0; i < TILE_SAMPLES; i++) {
            if (!wire[i]) continue;
            float *rgb = color + 3 * i;
            float luma = 0.2126f * rgb[0] + 0.7152f * rgb[1] + 0.0722f * rgb[2];
            float v = luma > WIRE_DARK_LUMA ? 0.0f : 1.0f;
            rgb[0] = rgb[1] = rgb[2] = v;
        }
    }

    for (int y = ty0; y <= ty1; y++) {
        size_t p = (size_t)y * width + (size_t)tx0;
        size_t l = (size_t)(y - ty0) * RASTER_TILE_SIZE;
        copy_floats(dj->color + 3 * p, color + 3 * l, 3 * tw);
        copy_floats(dj->coverage + p, coverage + l, tw);
        copy_floats(dj->depth + p, depth + l, tw);
    }
}

static meso_result reserve_threads(meso_context *ctx, raster_pass *pass) {
    int threads = meso_context_num_threads(ctx);
    if (threads <= pass->num_threads) return MESO_OK;
    raster_thread_scratch *t = realloc(pass->threads, (size_t)threads * sizeof(*t));
    if (!t) goto oom;
    pass->threads = t;
    for (int i = pass->num_threads; i < threads; i++) {
        t[i].block = aligned_alloc(32, sizeof(meso_fragment_block));
        t[i].fragments = malloc(TILE_SAMPLES * sizeof(meso_fragment));
        /* a triangle's samples are tested before the check for repeats: up to a tile's
         * worth past a full batch, plus the branch-free compaction's one extra write */
        t[i].pixels = malloc((2 * TILE_SAMPLES + 1) * sizeof(uint32_t));
        t[i].wire = malloc(TILE_SAMPLES);
        t[i].pending = calloc(TILE_SAMPLES, 1);
        t[i].covered = malloc(sizeof(covered_samples));
        t[i].color = malloc(3 * TILE_SAMPLES * sizeof(float));
        t[i].coverage = malloc(TILE_SAMPLES * sizeof(float));
        t[i].depth = malloc(TILE_SAMPLES * sizeof(float));
        if (!t[i].block || !t[i].fragments || !t[i].pixels || !t[i].wire || !t[i].color ||
            !t[i].coverage || !t[i].depth || !t[i].pending || !t[i].covered) {
            free(t[i].block);
            free(t[i].pending);
            free(t[i].covered);
            free(t[i].fragments);
            free(t[i].pixels);
            free(t[i].wire);
            free(t[i].color);
            free(t[i].coverage);
            free(t[i].depth);
            goto oom;
        }
        pass->num_threads = i + 1;
    }
    return MESO_OK;
oom:
    return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY,
                          "render: out of memory for fragment batches");
}

meso_result raster_draw(meso_context *ctx, raster_pass *pass, const meso_frame *frame,
                        const raster_object *objects, const meso_mesh *const *meshes,
                        int num_objects, bool wireframe, float *color, float *coverage,
                        float *depth, uint64_t *out_triangles, uint64_t *out_fragments) {
    *out_triangles = 0;
    *out_fragments = 0;
    raster_setup_desc desc = {.view_projection = frame->view_projection,
                              .width = frame->width,
                              .height = frame->height,
                              .z_near = frame->z_near,
                              .cull_back = true};
    if (num_objects > pass->both_faces_capacity) {
        bool *b = realloc(pass->both_faces, (size_t)num_objects * sizeof(*b));
        if (!b) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "render: out of memory");
        pass->both_faces = b;
        pass->both_faces_capacity = num_objects;
    }
    for (int i = 0; i < num_objects; i++)
        pass->both_faces[i] = objects[i].technique && objects[i].technique->both_faces;
    meso_result r =
        raster_bins_build(ctx, &pass->bins, meshes, pass->both_faces, num_objects, &desc);
    if (r != MESO_OK) return r;
    if ((r = reserve_threads(ctx, pass)) != MESO_OK) return r;
    size_t num_tiles = (size_t)pass->bins.tiles_x * (size_t)pass->bins.tiles_y;
    if (num_tiles > pass->tile_fragments_capacity) {
        uint64_t *f = realloc(pass->tile_fragments, num_tiles * sizeof(*f));
        if (!f) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "render: out of memory");
        pass->tile_fragments = f;
        pass->tile_fragments_capacity = num_tiles;
    }
    meso_vec3 bg = frame->scene->background;
    for (int i = 0; i < TILE_SAMPLES; i++) {
        pass->clear_color[3 * i + 0] = bg.x;
        pass->clear_color[3 * i + 1] = bg.y;
        pass->clear_color[3 * i + 2] = bg.z;
        pass->clear_coverage[i] = 0.0f;
        pass->clear_depth[i] = INFINITY;
    }
    draw_job dj = {pass, frame, objects, wireframe, color, coverage, depth};
    meso_parallel_for(ctx, num_tiles, draw_tile, &dj);
    uint64_t frags = 0, tris = 0;
    for (size_t i = 0; i < num_tiles; i++) frags += pass->tile_fragments[i];
    for (size_t c = 0; c < pass->bins.num_chunks; c++) tris += pass->bins.chunks[c].num_triangles;
    *out_triangles = tris;
    *out_fragments = frags;
    return MESO_OK;
}

void raster_pass_release(raster_pass *pass) {
    raster_bins_release(&pass->bins);
    for (int i = 0; i < pass->num_threads; i++) {
        free(pass->threads[i].block);
        free(pass->threads[i].fragments);
        free(pass->threads[i].pixels);
        free(pass->threads[i].wire);
        free(pass->threads[i].pending);
        free(pass->threads[i].covered);
        free(pass->threads[i].color);
        free(pass->threads[i].coverage);
        free(pass->threads[i].depth);
    }
    free(pass->threads);
    free(pass->tile_fragments);
    free(pass->both_faces);
    memset(pass, 0, sizeof(*pass));
}

/* ---- Supersampling resolve ---------------------------------------------------------------- */

typedef struct resolve_job {
    int n, width, height;
    const float *sc, *scov, *sd;
    float *color, *coverage, *depth;
} resolve_job;

#define RESOLVE_ROWS 16

static void resolve_rows(void *user, size_t job, int thread_index) {
    (void)thread_index;
    const resolve_job *r = user;
    int n = r->n;
    size_t sw = (size_t)r->width * (size_t)n;
    float inv = 1.0f / (float)(n * n);
    int y_end = (int)(job + 1) * RESOLVE_ROWS;
    y_end = y_end > r->height ? r->height : y_end;
    for (int y = (int)job * RESOLVE_ROWS; y < y_end; y++) {
        for (int x = 0; x < r->width; x++) {
            float c0 = 0.0f, c1 = 0.0f, c2 = 0.0f, cov = 0.0f, d = INFINITY;
            for (int j = 0; j < n; j++) {
                size_t s = ((size_t)y * (size_t)n + (size_t)j) * sw + (size_t)x * (size_t)n;
                for (int i = 0; i < n; i++, s++) {
                    c0 += r->sc[3 * s + 0];
                    c1 += r->sc[3 * s + 1];
                    c2 += r->sc[3 * s + 2];
                    cov += r->scov[s];
                    d = r->sd[s] < d ? r->sd[s] : d;
                }
            }
            size_t p = (size_t)y * (size_t)r->width + (size_t)x;
            r->color[3 * p + 0] = c0 * inv;
            r->color[3 * p + 1] = c1 * inv;
            r->color[3 * p + 2] = c2 * inv;
            r->coverage[p] = cov * inv;
            r->depth[p] = d;
        }
    }
}

void raster_resolve(meso_context *ctx, int n, int width, int height, const float *sample_color,
                    const float *sample_coverage, const float *sample_depth, float *color,
                    float *coverage, float *depth) {
    resolve_job r = {n,     width,    height, sample_color, sample_coverage, sample_depth,
                     color, coverage, depth};
    meso_parallel_for(ctx, ((size_t)height + RESOLVE_ROWS - 1) / RESOLVE_ROWS, resolve_rows, &r);
}
