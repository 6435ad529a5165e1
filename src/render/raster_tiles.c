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
#include "meso/runtime.h"

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

static void load_attributes(const meso_mesh *mesh, uint32_t triangle, bool tangents,
                            vertex_attributes *a) {
    const uint32_t *idx = mesh->indices + 3 * (size_t)triangle;
    a->has_tangents = tangents && mesh->tangents && mesh->bitangents;
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

/* The footprint of a triangle's samples (meso_fragment.duv_dx, duv_dy). With g_i the planes of
 * raster_triangle (b_i = g_i d, d = 1 / sum g the view depth), db_i/dx = d (ga_i - b_i sum ga),
 * so du/dx = d (sum u_i ga_i - u sum ga), and likewise for v and y: exact for the
 * perspective-correct interpolation, per sample. */
typedef struct uv_footprint_planes {
    float ua, ub, va, vb, sa, sb;
} uv_footprint_planes;

static inline uv_footprint_planes footprint_planes(const raster_triangle *tri,
                                                   const vertex_attributes *va) {
    uv_footprint_planes p;
    p.ua = va->uv[0].x * tri->ga[0] + va->uv[1].x * tri->ga[1] + va->uv[2].x * tri->ga[2];
    p.ub = va->uv[0].x * tri->gb[0] + va->uv[1].x * tri->gb[1] + va->uv[2].x * tri->gb[2];
    p.va = va->uv[0].y * tri->ga[0] + va->uv[1].y * tri->ga[1] + va->uv[2].y * tri->ga[2];
    p.vb = va->uv[0].y * tri->gb[0] + va->uv[1].y * tri->gb[1] + va->uv[2].y * tri->gb[2];
    p.sa = tri->ga[0] + tri->ga[1] + tri->ga[2];
    p.sb = tri->gb[0] + tri->gb[1] + tri->gb[2];
    return p;
}

/* fill_fragments_skipping of one fragment, lane `at` of the block only, with the very
 * operations of a lane of the vector code in their order (so the same bits). The lanes after it
 * are written by the next triangle's fill or by flush_batch's padding. */
static inline __attribute__((always_inline)) void
fill_one_skipping(const raster_triangle *tri, const meso_frame *frame, const vertex_attributes *va,
                  unsigned skip, int32_t ix, int32_t iy, float d, meso_fragment_block *block,
                  size_t at) {
    float sx = (float)ix + 0.5f, sy = (float)iy + 0.5f;
    float fx = sx - tri->ref_x, fy = sy - tri->ref_y;
    float b0 = (tri->gc[0] + tri->gb[0] * fy + tri->ga[0] * fx) * d;
    float b1 = (tri->gc[1] + tri->gb[1] * fy + tri->ga[1] * fx) * d;
    float b2 = (tri->gc[2] + tri->gb[2] * fy + tri->ga[2] * fx) * d;
    if (!(skip & MESO_FRAGMENT_SKIP_SAMPLE)) block->x[at] = sx, block->y[at] = sy;
    if (!(skip & MESO_FRAGMENT_SKIP_TRIANGLE)) block->triangle[at] = tri->triangle;
    if (!(skip & MESO_FRAGMENT_SKIP_BARYCENTRICS))
        block->b0[at] = b0, block->b1[at] = b1, block->b2[at] = b2;
    float dx = frame->corner.x + (frame->pixel_right.x * sx + frame->pixel_down.x * sy);
    float dy = frame->corner.y + (frame->pixel_right.y * sx + frame->pixel_down.y * sy);
    float dz = frame->corner.z + (frame->pixel_right.z * sx + frame->pixel_down.z * sy);
    block->px[at] = frame->eye.x + dx * d, block->py[at] = frame->eye.y + dy * d;
    block->pz[at] = frame->eye.z + dz * d;
#define INTERP(arr, c) (arr[0].c * b0 + arr[1].c * b1 + arr[2].c * b2)
    float nx = INTERP(va->n, x), ny = INTERP(va->n, y), nz = INTERP(va->n, z);
    float len2 = nx * nx + ny * ny + nz * nz;
    float inv = len2 > 0.0f ? 1.0f / sqrtf(len2) : 1.0f;
    block->nx[at] = nx * inv, block->ny[at] = ny * inv, block->nz[at] = nz * inv;
    if (va->has_tangents) {
        block->tx[at] = INTERP(va->t, x), block->ty[at] = INTERP(va->t, y);
        block->tz[at] = INTERP(va->t, z);
        block->bx[at] = INTERP(va->b, x), block->by[at] = INTERP(va->b, y);
        block->bz[at] = INTERP(va->b, z);
    } else if (!(skip & MESO_FRAGMENT_SKIP_TANGENTS)) {
        block->tx[at] = block->ty[at] = block->tz[at] = 0.0f;
        block->bx[at] = block->by[at] = block->bz[at] = 0.0f;
    }
    block->u[at] = va->has_uvs ? INTERP(va->uv, x) : 0.0f;
    block->v[at] = va->has_uvs ? INTERP(va->uv, y) : 0.0f;
#undef INTERP
    if (frame->filter) {
        uv_footprint_planes fp = va->has_uvs ? footprint_planes(tri, va) : (uv_footprint_planes){0};
        float u = block->u[at], v = block->v[at];
        block->dudx[at] = d * (fp.ua - u * fp.sa), block->dudy[at] = d * (fp.ub - u * fp.sb);
        block->dvdx[at] = d * (fp.va - v * fp.sa), block->dvdy[at] = d * (fp.vb - v * fp.sb);
    }
    block->depth[at] = d, block->out_depth[at] = d;
    if (!(skip & MESO_FRAGMENT_SKIP_COLOR_PRESET))
        block->r[at] = block->g[at] = block->b[at] = 0.0f;
    block->discard[at] = 0;
}

/* Fill the inputs and preset the outputs of n fragments from their sample positions and view
 * depths, 8 at a time (GCC vector extensions), into lanes first..first+n-1 of the block, but for
 * the fields in `skip` (MESO_FRAGMENT_SKIP_*: the technique never reads them). The
 * inputs are padded to whole groups of 8 (cover_triangle), so up to 7 lanes past first+n are
 * written too; the next triangle's fill or flush_batch's padding writes over them. */
static inline __attribute__((always_inline)) void
fill_fragments_skipping(const raster_triangle *tri, const meso_frame *frame,
                        const vertex_attributes *va, unsigned skip, size_t n, const int32_t *xs,
                        const int32_t *ys, const float *depths, meso_fragment_block *block,
                        size_t first) {
    if (n == 1) { /* most triangles of a displaced mesh: one lane, not a group of eight */
        fill_one_skipping(tri, frame, va, skip, xs[0], ys[0], depths[0], block, first);
        return;
    }
    const v8f ga0 = splat(tri->ga[0]), ga1 = splat(tri->ga[1]), ga2 = splat(tri->ga[2]);
    const v8f gb0 = splat(tri->gb[0]), gb1 = splat(tri->gb[1]), gb2 = splat(tri->gb[2]);
    const v8f gc0 = splat(tri->gc[0]), gc1 = splat(tri->gc[1]), gc2 = splat(tri->gc[2]);
    const v8f ref_x = splat(tri->ref_x), ref_y = splat(tri->ref_y);
    const v8i triangle = v8i_splat((int32_t)tri->triangle);
    const v8f zero = splat(0.0f);
    const uint64_t no_discard = 0;
    const bool footprint = frame->filter;
    const uv_footprint_planes fp =
        footprint && va->has_uvs ? footprint_planes(tri, va) : (uv_footprint_planes){0};
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
        if (!(skip & MESO_FRAGMENT_SKIP_SAMPLE)) STORE(x, sx), STORE(y, sy);
        if (!(skip & MESO_FRAGMENT_SKIP_TRIANGLE)) STORE(triangle, triangle);
        if (!(skip & MESO_FRAGMENT_SKIP_BARYCENTRICS)) STORE(b0, b0), STORE(b1, b1), STORE(b2, b2);
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
        } else if (!(skip & MESO_FRAGMENT_SKIP_TANGENTS)) {
            STORE(tx, zero), STORE(ty, zero), STORE(tz, zero);
            STORE(bx, zero), STORE(by, zero), STORE(bz, zero);
        }
        if (va->has_uvs) {
            v8f u = INTERP(va->uv, x), v = INTERP(va->uv, y);
            STORE(u, u), STORE(v, v);
            if (footprint) {
                v8f dudx = d * (splat(fp.ua) - u * splat(fp.sa));
                v8f dudy = d * (splat(fp.ub) - u * splat(fp.sb));
                v8f dvdx = d * (splat(fp.va) - v * splat(fp.sa));
                v8f dvdy = d * (splat(fp.vb) - v * splat(fp.sb));
                STORE(dudx, dudx), STORE(dudy, dudy), STORE(dvdx, dvdx), STORE(dvdy, dvdy);
            }
        } else {
            STORE(u, zero), STORE(v, zero);
            if (footprint)
                STORE(dudx, zero), STORE(dudy, zero), STORE(dvdx, zero), STORE(dvdy, zero);
        }
#undef INTERP
        STORE(depth, d), STORE(out_depth, d);
        if (!(skip & MESO_FRAGMENT_SKIP_COLOR_PRESET))
            STORE(r, zero), STORE(g, zero), STORE(b, zero);
        memcpy(block->discard + at, &no_discard, sizeof(no_discard));
    }
#undef STORE
}

/* fill_fragments_skipping with the skips of flat, bump, parallax and displacement as constants:
 * a test of `skip` a group cost as much as the stores it saved. */
#define FILL_SHADING_ONLY                                                                          \
    (MESO_FRAGMENT_SKIP_SAMPLE | MESO_FRAGMENT_SKIP_TRIANGLE | MESO_FRAGMENT_SKIP_BARYCENTRICS |   \
     MESO_FRAGMENT_SKIP_COLOR_PRESET)
static void fill_fragments(const raster_triangle *tri, const meso_frame *frame,
                           const vertex_attributes *va, unsigned skip, size_t n, const int32_t *xs,
                           const int32_t *ys, const float *depths, meso_fragment_block *block,
                           size_t first) {
    if (skip == FILL_SHADING_ONLY)
        fill_fragments_skipping(tri, frame, va, FILL_SHADING_ONLY, n, xs, ys, depths, block, first);
    else if (skip == (FILL_SHADING_ONLY | MESO_FRAGMENT_SKIP_TANGENTS))
        fill_fragments_skipping(tri, frame, va, FILL_SHADING_ONLY | MESO_FRAGMENT_SKIP_TANGENTS, n,
                                xs, ys, depths, block, first);
    else if (skip == (FILL_SHADING_ONLY & ~MESO_FRAGMENT_SKIP_TRIANGLE)) /* displacement */
        fill_fragments_skipping(tri, frame, va, FILL_SHADING_ONLY & ~MESO_FRAGMENT_SKIP_TRIANGLE, n,
                                xs, ys, depths, block, first);
    else if (skip == 0)
        fill_fragments_skipping(tri, frame, va, 0, n, xs, ys, depths, block, first);
    else
        fill_fragments_skipping(tri, frame, va, skip, n, xs, ys, depths, block, first);
}

/* The samples of one triangle that pass coverage and the early depth test, before their
 * attributes are filled: sample position, view depth, tile-buffer index. Padded by one group of
 * 8 for the vector fill. */
typedef struct covered_samples {
    int32_t x[TILE_SAMPLES + LANES], y[TILE_SAMPLES + LANES];
    float depth[TILE_SAMPLES + LANES];
} covered_samples;

/* Four 64-bit edge-function values. */
typedef int64_t v4l __attribute__((vector_size(32)));

/* Bit k set when lane k of lo (k < 4) or hi (k >= 4) is negative. */
static inline int negative_bits(v4l lo, v4l hi) {
#if defined(__AVX__)
    return _mm256_movemask_pd((__m256d)lo) | _mm256_movemask_pd((__m256d)hi) << 4;
#else
    int bits = 0;
    for (int k = 0; k < 4; k++) bits |= (lo[k] < 0) << k | (hi[k] < 0) << (k + 4);
    return bits;
#endif
}

#if defined(__AVX2__)
/* For each 8-bit lane mask, the indices of its set lanes in order, 4 bits each from the low
 * end (the rest 0): the permutation that packs the kept lanes of a group to its front. */
static const uint32_t kept_lanes[256] = {
    0x00000000, 0x00000000, 0x00000001, 0x00000010, 0x00000002, 0x00000020, 0x00000021, 0x00000210,
    0x00000003, 0x00000030, 0x00000031, 0x00000310, 0x00000032, 0x00000320, 0x00000321, 0x00003210,
    0x00000004, 0x00000040, 0x00000041, 0x00000410, 0x00000042, 0x00000420, 0x00000421, 0x00004210,
    0x00000043, 0x00000430, 0x00000431, 0x00004310, 0x00000432, 0x00004320, 0x00004321, 0x00043210,
    0x00000005, 0x00000050, 0x00000051, 0x00000510, 0x00000052, 0x00000520, 0x00000521, 0x00005210,
    0x00000053, 0x00000530, 0x00000531, 0x00005310, 0x00000532, 0x00005320, 0x00005321, 0x00053210,
    0x00000054, 0x00000540, 0x00000541, 0x00005410, 0x00000542, 0x00005420, 0x00005421, 0x00054210,
    0x00000543, 0x00005430, 0x00005431, 0x00054310, 0x00005432, 0x00054320, 0x00054321, 0x00543210,
    0x00000006, 0x00000060, 0x00000061, 0x00000610, 0x00000062, 0x00000620, 0x00000621, 0x00006210,
    0x00000063, 0x00000630, 0x00000631, 0x00006310, 0x00000632, 0x00006320, 0x00006321, 0x00063210,
    0x00000064, 0x00000640, 0x00000641, 0x00006410, 0x00000642, 0x00006420, 0x00006421, 0x00064210,
    0x00000643, 0x00006430, 0x00006431, 0x00064310, 0x00006432, 0x00064320, 0x00064321, 0x00643210,
    0x00000065, 0x00000650, 0x00000651, 0x00006510, 0x00000652, 0x00006520, 0x00006521, 0x00065210,
    0x00000653, 0x00006530, 0x00006531, 0x00065310, 0x00006532, 0x00065320, 0x00065321, 0x00653210,
    0x00000654, 0x00006540, 0x00006541, 0x00065410, 0x00006542, 0x00065420, 0x00065421, 0x00654210,
    0x00006543, 0x00065430, 0x00065431, 0x00654310, 0x00065432, 0x00654320, 0x00654321, 0x06543210,
    0x00000007, 0x00000070, 0x00000071, 0x00000710, 0x00000072, 0x00000720, 0x00000721, 0x00007210,
    0x00000073, 0x00000730, 0x00000731, 0x00007310, 0x00000732, 0x00007320, 0x00007321, 0x00073210,
    0x00000074, 0x00000740, 0x00000741, 0x00007410, 0x00000742, 0x00007420, 0x00007421, 0x00074210,
    0x00000743, 0x00007430, 0x00007431, 0x00074310, 0x00007432, 0x00074320, 0x00074321, 0x00743210,
    0x00000075, 0x00000750, 0x00000751, 0x00007510, 0x00000752, 0x00007520, 0x00007521, 0x00075210,
    0x00000753, 0x00007530, 0x00007531, 0x00075310, 0x00007532, 0x00075320, 0x00075321, 0x00753210,
    0x00000754, 0x00007540, 0x00007541, 0x00075410, 0x00007542, 0x00075420, 0x00075421, 0x00754210,
    0x00007543, 0x00075430, 0x00075431, 0x00754310, 0x00075432, 0x00754320, 0x00754321, 0x07543210,
    0x00000076, 0x00000760, 0x00000761, 0x00007610, 0x00000762, 0x00007620, 0x00007621, 0x00076210,
    0x00000763, 0x00007630, 0x00007631, 0x00076310, 0x00007632, 0x00076320, 0x00076321, 0x00763210,
    0x00000764, 0x00007640, 0x00007641, 0x00076410, 0x00007642, 0x00076420, 0x00076421, 0x00764210,
    0x00007643, 0x00076430, 0x00076431, 0x00764310, 0x00076432, 0x00764320, 0x00764321, 0x07643210,
    0x00000765, 0x00007650, 0x00007651, 0x00076510, 0x00007652, 0x00076520, 0x00076521, 0x00765210,
    0x00007653, 0x00076530, 0x00076531, 0x00765310, 0x00076532, 0x00765320, 0x00765321, 0x07653210,
    0x00007654, 0x00076540, 0x00076541, 0x00765410, 0x00076542, 0x00765420, 0x00765421, 0x07654210,
    0x00076543, 0x00765430, 0x00765431, 0x07654310, 0x00765432, 0x07654320, 0x07654321, 0x76543210,
};
#endif

/* Append the lanes of (pixel, depth, x) set in `keep` to pixels and out from index n, row y,
 * in lane order; returns the new count. Writes 8 entries from n whatever `keep` is (the arrays
 * are padded by a group). */
static inline size_t append_kept(int keep, v8i pixel, v8f d, v8i x, int y, uint32_t *pixels,
                                 covered_samples *out, size_t n) {
    v8i row_y = v8i_splat(y);
#if defined(__AVX2__)
    const v8i nibble = {0, 4, 8, 12, 16, 20, 24, 28};
    v8i order = (v8i_splat((int32_t)kept_lanes[keep]) >> nibble) & v8i_splat(7);
    pixel = (v8i)_mm256_permutevar8x32_epi32((__m256i)pixel, (__m256i)order);
    d = (v8f)_mm256_permutevar8x32_ps((__m256)d, (__m256i)order);
    x = (v8i)_mm256_permutevar8x32_epi32((__m256i)x, (__m256i)order);
    memcpy(pixels + n, &pixel, sizeof pixel);
    memcpy(out->depth + n, &d, sizeof d);
    memcpy(out->x + n, &x, sizeof x);
    memcpy(out->y + n, &row_y, sizeof row_y);
    return n + (size_t)__builtin_popcount((unsigned)keep);
#else
    for (int k = 0; k < LANES; k++) { /* compacted without branches */
        pixels[n] = (uint32_t)pixel[k];
        out->depth[n] = d[k];
        out->x[n] = x[k];
        out->y[n] = row_y[k];
        n += (size_t)(keep >> k & 1);
    }
    return n;
#endif
}

/* Covered samples of `tri` inside [x0, x1] x [y0, y1] that pass the depth test go to `out` and
 * their tile-buffer indices to `pixels`; returns how many. Coverage and the depth test run on
 * eight samples of a row at a time and compact their survivors without branches (small
 * triangles make those branches unpredictable). */
static size_t cover_triangle(const raster_triangle *tri, int x0, int y0, int x1, int y1, int tx0,
                             int ty0, const float *depth, covered_samples *out, uint32_t *pixels) {
    const int64_t half = RASTER_SUBPIXEL_ONE / 2;
    int64_t px = ((int64_t)x0 << RASTER_SUBPIXEL_BITS) + half;
    int64_t py = ((int64_t)y0 << RASTER_SUBPIXEL_BITS) + half;
    int64_t row[3], step_x[3], step_y[3];
    /* the edge functions of samples x .. x + 7 of a row: E(x) + offsets, exact in 64 bits */
    v4l offset_lo[3], offset_hi[3];
    int64_t step_group[3];
    /* unrolled: the loop's (k + 1) % 3 and its indexing were a tenth of the coverage of a
     * sphere's small triangles */
#pragma GCC unroll 3
    for (int k = 0; k < 3; k++) {
        int a = (k + 1) % 3;
        row[k] = (int64_t)tri->edge_a[k] * (px - tri->x[a]) +
                 (int64_t)tri->edge_b[k] * (py - tri->y[a]) + tri->bias[k];
        step_x[k] = (int64_t)tri->edge_a[k] * RASTER_SUBPIXEL_ONE;
        step_y[k] = (int64_t)tri->edge_b[k] * RASTER_SUBPIXEL_ONE;
        int64_t s = step_x[k];
        offset_lo[k] = (v4l){0, s, 2 * s, 3 * s};
        offset_hi[k] = offset_lo[k] + 4 * s; /* one vector add instead of four lane inserts */
        step_group[k] = 8 * s;
    }
    const v8f ga0 = splat(tri->ga[0]), ga1 = splat(tri->ga[1]), ga2 = splat(tri->ga[2]);
    const v8f ref_x = splat(tri->ref_x);
    const v8i lane = {0, 1, 2, 3, 4, 5, 6, 7};
    size_t n = 0;
    for (int y = y0; y <= y1; y++) {
        int64_t e0 = row[0], e1 = row[1], e2 = row[2];
        /* The edge functions are linear along the row: their signs at both ends accept or
         * reject the whole row at once (most rows of a large triangle). */
        int64_t span = x1 - x0;
        int64_t f0 = e0 + step_x[0] * span, f1 = e1 + step_x[1] * span, f2 = e2 + step_x[2] * span;
        row[0] += step_y[0], row[1] += step_y[1], row[2] += step_y[2];
        if ((e0 & f0) < 0 || (e1 & f1) < 0 || (e2 & f2) < 0) continue; /* outside one edge */
        bool inside = (e0 | e1 | e2 | f0 | f1 | f2) >= 0;              /* inside all three */
        float fy = (float)y + 0.5f - tri->ref_y;
        v8f cy0 = splat(tri->gc[0] + tri->gb[0] * fy), cy1 = splat(tri->gc[1] + tri->gb[1] * fy);
        v8f cy2 = splat(tri->gc[2] + tri->gb[2] * fy);
        /* depth: the tile's own buffer, RASTER_TILE_SIZE a row, origin (tx0, ty0) */
        const float *zrow = depth + (y - ty0) * RASTER_TILE_SIZE;
        uint32_t base = (uint32_t)((y - ty0) * RASTER_TILE_SIZE);
        for (int first = x0; first <= x1; first += LANES) {
            int lanes = x1 - first + 1 < LANES ? x1 - first + 1 : LANES;
            int covered = (1 << lanes) - 1;
            if (!inside) {
                v4l lo0 = (v4l){e0, e0, e0, e0} + offset_lo[0];
                v4l hi0 = (v4l){e0, e0, e0, e0} + offset_hi[0];
                v4l lo1 = (v4l){e1, e1, e1, e1} + offset_lo[1];
                v4l hi1 = (v4l){e1, e1, e1, e1} + offset_hi[1];
                v4l lo2 = (v4l){e2, e2, e2, e2} + offset_lo[2];
                v4l hi2 = (v4l){e2, e2, e2, e2} + offset_hi[2];
                covered &= ~negative_bits(lo0 | lo1 | lo2, hi0 | hi1 | hi2);
                e0 += step_group[0], e1 += step_group[1], e2 += step_group[2];
                if (!covered) continue;
            }
            /* lanes past x1 repeat x1: a sample of the row, so the depth read stays inside */
            v8i x = v8i_splat(first) + lane;
            x = (v8i)v8_select(x > v8i_splat(x1), (v8f)v8i_splat(x1), (v8f)x);
            v8i column = x - v8i_splat(tx0);
            v8f fx = (__builtin_convertvector(x, v8f) + splat(0.5f)) - ref_x;
            /* The depths of eight samples at a time: one vector division instead of eight. */
            v8f inv_depth = (cy0 + ga0 * fx) + (cy1 + ga1 * fx) + (cy2 + ga2 * fx);
            v8f d = splat(1.0f) / inv_depth;
            /* kept when in front of the camera and nearer than the buffer; a NaN fails both */
            int keep =
                v8_mask_bits((inv_depth > splat(0.0f)) & (d < v8_gather(zrow, column))) & covered;
            n = append_kept(keep, v8i_splat((int32_t)base) + column, d, x, y, pixels, out, n);
        }
    }
    if (!n) return 0;
    /* unused lanes of the last group repeat the last fragment (the arrays hold a group more) */
    v8i last_x = v8i_splat(out->x[n - 1]), last_y = v8i_splat(out->y[n - 1]);
    v8f last_depth = splat(out->depth[n - 1]);
    memcpy(out->x + n, &last_x, sizeof last_x);
    memcpy(out->y + n, &last_y, sizeof last_y);
    memcpy(out->depth + n, &last_depth, sizeof last_depth);
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
 * pass in the AVX2 copy, _mm256_stream_ps made an empty frame slower than memcpy (meso bench,
 * interleaved runs): the next frame and the image conversion read the target back from the cache.
 */
static inline void copy_floats(float *dst, const float *src, size_t n) {
#if defined(__AVX__)
    /* Inline 32-byte moves: rows of a tile are 128-384 bytes, where the library call's
     * dispatch and the PLT cost as much as the copy (perf). */
    size_t i = 0;
    for (; i + 8 <= n; i += 8) _mm256_storeu_ps(dst + i, _mm256_loadu_ps(src + i));
    for (; i < n; i++) dst[i] = src[i];
#else
    memcpy(dst, src, n * sizeof(float));
#endif
}

/* The tile's coverage from its depths: a sample is written exactly when its depth becomes less
 * than the clear's +inf (the test is "nearer than the buffer", a NaN never passes), so the
 * coverage is 1 exactly where the depth is below +inf. Worked out in the copy-out instead of a
 * cleared coverage buffer and a store a fragment. */
static inline void copy_coverage(float *dst, const float *depth, size_t n) {
    size_t i = 0;
    for (; i + LANES <= n; i += LANES) {
        v8f d;
        memcpy(&d, depth + i, sizeof d);
        v8f c = v8_select(d < splat(INFINITY), splat(1.0f), splat(0.0f));
        memcpy(dst + i, &c, sizeof c);
    }
    for (; i < n; i++) dst[i] = depth[i] < INFINITY ? 1.0f : 0.0f;
}

/* r0 g0 b0 r1 g1 b1 ... r7 g7 b7 in out[0..2]. */
static inline void interleave3(v8f r, v8f g, v8f b, v8f out[3]) {
    typedef float v16f __attribute__((vector_size(64)));
    v16f rg = __builtin_shufflevector(r, g, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
    v16f bb = __builtin_shufflevector(b, b, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
    /* indices 0-7: r, 8-15: g, 16-23: b */
    out[0] = __builtin_shufflevector(rg, bb, 0, 8, 16, 1, 9, 17, 2, 10);
    out[1] = __builtin_shufflevector(rg, bb, 18, 3, 11, 19, 4, 12, 20, 5);
    out[2] = __builtin_shufflevector(rg, bb, 13, 21, 6, 14, 22, 7, 15, 23);
}

/* Fragments of one object in one tile waiting to be shaded; no two share a sample. */
typedef struct tile_batch {
    const raster_object *object;
    const meso_frame *frame;
    meso_fragment_block *block;
    meso_fragment *scratch; /* the adapter's fragments (render_fragments.c) */
    uint32_t *pixels;       /* tile-buffer index of each fragment */
    /* per tile sample: 1 while a fragment of the batch covers it, for the batch's first
     * `marked` fragments: the first triangle's samples are marked only when a second triangle
     * joins the batch (in most tiles of a large triangle none does) */
    uint8_t *pending;
    float *color, *depth; /* the tile's buffers (coverage: where depth < +inf, copy_coverage) */
    size_t count, marked;
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
    float *depth = b->depth, *color = b->color;
    const uint32_t *pixels = b->pixels;
    size_t count = b->count;
    const v8i consecutive = {0, 1, 2, 3, 4, 5, 6, 7};
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
        uint64_t discards;
        memcpy(&discards, block->discard + first, sizeof discards);
        /* Eight fragments on consecutive samples of a row (inside large triangles), all in
         * front and none discarded: written with vector stores, the colours interleaved by
         * shuffles; the same values as the loop below. */
        if (live == 0xff && !discards && v8_mask_bits(z < old) == 0xff &&
            v8_mask_bits(pix == v8i_splat(pix[0]) + consecutive) == 0xff) {
            uint32_t p = (uint32_t)pix[0];
            v8f r, g, bl, rgb[3];
            memcpy(&r, block->r + first, sizeof r);
            memcpy(&g, block->g + first, sizeof g);
            memcpy(&bl, block->b + first, sizeof bl);
            interleave3(r, g, bl, rgb);
            memcpy(depth + p, &z, sizeof z);
            memcpy(color + 3 * p, rgb, sizeof rgb);
            continue;
        }
        /* behind, or NaN: nothing drawn */
        for (int keep = v8_mask_bits(z < old) & live; keep; keep &= keep - 1) {
            int k = __builtin_ctz((unsigned)keep);
            size_t i = first + (size_t)k;
            if (block->discard[i]) continue; /* discarded: nothing drawn */
            uint32_t p = (uint32_t)pix[k];
            depth[p] = z[k];
            color[3 * p + 0] = block->r[i];
            color[3 * p + 1] = block->g[i];
            color[3 * p + 2] = block->b[i];
        }
    }
    /* release the batch's samples: the whole mask at once when the batch is a large part of
     * the tile */
    if (b->marked * 8 > TILE_SAMPLES)
        memset(b->pending, 0, TILE_SAMPLES);
    else
        for (size_t i = 0; i < b->marked; i++) b->pending[pixels[i]] = 0;
    b->shaded += b->count;
    b->count = 0;
    b->marked = 0;
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
    float *color = scratch->color, *depth = scratch->depth;
    memcpy(color, pass->clear_color, 3 * TILE_SAMPLES * sizeof(float));
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
        /* the adapter copies every field; the shading model reads the tangents for a normal
         * map */
        unsigned skip = obj->technique->shade_block ? obj->technique->skip_fields : 0;
        if (obj->object->material.normal_map) skip &= ~MESO_FRAGMENT_SKIP_TANGENTS;
        const meso_mesh *mesh = bins->meshes[chunk->mesh].mesh;
        for (size_t e = 0; e < count; e++) {
            const raster_triangle *tri = &chunk->triangles[list[e]];
            int x0 = tri->min_x > tx0 ? tri->min_x : tx0, x1 = tri->max_x < tx1 ? tri->max_x : tx1;
            int y0 = tri->min_y > ty0 ? tri->min_y : ty0, y1 = tri->max_y < ty1 ? tri->max_y : ty1;
            if (x0 > x1 || y0 > y1) continue;
            uint32_t *pixels = batch.pixels + batch.count;
            size_t n = cover_triangle(tri, x0, y0, x1, y1, tx0, ty0, depth, covered, pixels);
            if (!n) continue;
            if (batch.count) { /* the batch's first triangle repeats nothing */
                for (size_t i = batch.marked; i < batch.count; i++)
                    batch.pending[batch.pixels[i]] = 1;
                batch.marked = batch.count;
                uint8_t repeats = 0;
                for (size_t i = 0; i < n; i++) { /* a triangle covers a sample once */
                    repeats |= batch.pending[pixels[i]];
                    batch.pending[pixels[i]] = 1;
                }
                batch.marked += n;
                if (repeats) { /* test again against the depths the batch writes */
                    for (size_t i = 0; i < n; i++) batch.pending[pixels[i]] = 0;
                    batch.marked -= n;
                    flush_batch(&batch);
                    pixels = batch.pixels;
                    n = cover_triangle(tri, x0, y0, x1, y1, tx0, ty0, depth, covered, pixels);
                    if (!n) continue;
                }
            }
            vertex_attributes va;
            load_attributes(mesh, tri->triangle, !(skip & MESO_FRAGMENT_SKIP_TANGENTS), &va);
            fill_fragments(tri, frame, &va, skip, n, covered->x, covered->y, covered->depth,
                           batch.block, batch.count);
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
        copy_coverage(dj->coverage + p, depth + l, tw);
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
        /* the footprint arrays stay 0 in frames without filtering, which never write them */
        if (t[i].block) memset(t[i].block, 0, sizeof(meso_fragment_block));
        t[i].fragments = malloc(TILE_SAMPLES * sizeof(meso_fragment));
        /* a triangle's samples are tested before the check for repeats: up to a tile's
         * worth past a full batch, plus the compaction's writes of a whole group */
        t[i].pixels = malloc((2 * TILE_SAMPLES + LANES) * sizeof(uint32_t));
        t[i].wire = malloc(TILE_SAMPLES);
        t[i].pending = calloc(TILE_SAMPLES, 1);
        t[i].covered = malloc(sizeof(covered_samples));
        t[i].color = malloc(3 * TILE_SAMPLES * sizeof(float));
        t[i].depth = malloc(TILE_SAMPLES * sizeof(float));
        if (!t[i].block || !t[i].fragments || !t[i].pixels || !t[i].wire || !t[i].color ||
            !t[i].depth || !t[i].pending || !t[i].covered) {
            free(t[i].block);
            free(t[i].pending);
            free(t[i].covered);
            free(t[i].fragments);
            free(t[i].pixels);
            free(t[i].wire);
            free(t[i].color);
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
                              .cull_back = true,
                              /* the wireframe draws the edges of triangles covering nothing */
                              .drop_uncovered = !wireframe};
    if (num_objects > pass->both_faces_capacity) {
        bool *b = realloc(pass->both_faces, (size_t)num_objects * sizeof(*b));
        if (!b) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "render: out of memory");
        pass->both_faces = b;
        pass->both_faces_capacity = num_objects;
    }
    for (int i = 0; i < num_objects; i++)
        pass->both_faces[i] =
            objects[i].technique && (objects[i].technique->both_faces ||
                                     (objects[i].technique->state_both_faces &&
                                      objects[i].technique->state_both_faces(objects[i].state)));
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
