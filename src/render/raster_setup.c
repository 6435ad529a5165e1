/* Rasterizer front half: vertex transform, clipping, triangle setup and binning into tiles.
 *
 * Exactness: vertices snap to 1/256 sample and edge functions are evaluated in 64-bit integers,
 * so two triangles sharing an edge compute the same edge with opposite signs and the top-left
 * rule gives every sample centre on it to exactly one of them. Clipping keeps that property:
 * the point where a shared edge crosses a clip plane is computed from the edge's inside vertex
 * toward its outside vertex in both triangles, so it is bit-identical.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "raster_internal.h"
#include "render_simd.h"

#if defined(__SSE2__) && defined(__x86_64__)
#include <emmintrin.h>
#include "meso/runtime.h"
#endif

#define MAX_POLYGON 9          /* 3 vertices + one per clip plane (5) + 1 */
#define RESERVE_FIRST_ITEMS 64 /* first capacity of a chunk's growing arrays */

typedef struct clip_vertex {
    double x, y, z, w;
    double bary[3]; /* weights of the source triangle's vertices */
} clip_vertex;

/* ---- Clipping ----------------------------------------------------------------------------- */

/* Signed distance of v to clip plane `plane` (>= 0 inside): 0 near, 1-4 the guard band. */
static double plane_distance(const clip_vertex *v, int plane, double z_near, double guard) {
    switch (plane) {
    case 0:
        return z_near < 0.0 ? v->z + v->w : v->w - z_near; /* z_near < 0: z_ndc >= -1 */
    case 1:
        return guard * v->w - v->x;
    case 2:
        return guard * v->w + v->x;
    case 3:
        return guard * v->w - v->y;
    default:
        return guard * v->w + v->y;
    }
}

/* The point where edge (in, out) crosses the plane, always computed from the inside vertex so
 * that both triangles sharing the edge get the same bits. */
static clip_vertex intersect(const clip_vertex *in, double d_in, const clip_vertex *out,
                             double d_out) {
    double t = d_in / (d_in - d_out);
    clip_vertex r;
    r.x = in->x + t * (out->x - in->x);
    r.y = in->y + t * (out->y - in->y);
    r.z = in->z + t * (out->z - in->z);
    r.w = in->w + t * (out->w - in->w);
    for (int i = 0; i < 3; i++) r.bary[i] = in->bary[i] + t * (out->bary[i] - in->bary[i]);
    return r;
}

/* Sutherland-Hodgman against one plane; returns the new vertex count. */
static int clip_polygon(const clip_vertex *in, int n, clip_vertex *out, int plane, double z_near,
                        double guard) {
    int m = 0;
    for (int i = 0; i < n; i++) {
        const clip_vertex *a = &in[i], *b = &in[(i + 1) % n];
        double da = plane_distance(a, plane, z_near, guard);
        double db = plane_distance(b, plane, z_near, guard);
        if (da >= 0.0) out[m++] = *a;
        if ((da >= 0.0) != (db >= 0.0)) {
            out[m++] = da >= 0.0 ? intersect(a, da, b, db) : intersect(b, db, a, da);
        }
    }
    return m;
}

/* ---- Setup -------------------------------------------------------------------------------- */

static inline int32_t ceil_div_subpixel(int64_t n) {
    return (int32_t)(-((-n) >> RASTER_SUBPIXEL_BITS));
}
static inline int32_t floor_div_subpixel(int64_t n) { return (int32_t)(n >> RASTER_SUBPIXEL_BITS); }

/* llrint without the library call it compiles to (errno rules keep GCC from inlining it):
 * cvtsd2si rounds in the current mode as llrint does, and gives the same INT64_MIN for what is
 * out of range. Six a snapped triangle, a million triangles a frame. */
static inline int64_t round_to_int64(double x) {
#if defined(__SSE2__) && defined(__x86_64__)
    return _mm_cvtsd_si64(_mm_set_sd(x));
#else
    return llrint(x);
#endif
}

/* A triangle snapped to the fixed-point grid, before any per-triangle setup. */
typedef struct snapped_triangle {
    int64_t X[3], Y[3]; /* counter-clockwise on screen (vertices 1 and 2 swapped if `swap`) */
    int32_t bx0, bx1, by0, by1;
    bool swap;
} snapped_triangle;

/* The samples whose centres lie in the snapped triangle's bounding box, clamped to the target;
 * false when there are none. Sample i has its centre at 256 i + 128. */
static bool sample_box(const raster_setup_desc *desc, snapped_triangle *s) {
    const int64_t *X = s->X, *Y = s->Y;
    int64_t min_x = X[0], max_x = X[0], min_y = Y[0], max_y = Y[0];
    for (int k = 1; k < 3; k++) {
        min_x = X[k] < min_x ? X[k] : min_x;
        max_x = X[k] > max_x ? X[k] : max_x;
        min_y = Y[k] < min_y ? Y[k] : min_y;
        max_y = Y[k] > max_y ? Y[k] : max_y;
    }
    int32_t bx0 = ceil_div_subpixel(min_x - RASTER_SUBPIXEL_ONE / 2);
    int32_t bx1 = floor_div_subpixel(max_x - RASTER_SUBPIXEL_ONE / 2);
    int32_t by0 = ceil_div_subpixel(min_y - RASTER_SUBPIXEL_ONE / 2);
    int32_t by1 = floor_div_subpixel(max_y - RASTER_SUBPIXEL_ONE / 2);
    bx0 = bx0 < 0 ? 0 : bx0;
    by0 = by0 < 0 ? 0 : by0;
    bx1 = bx1 > desc->width - 1 ? desc->width - 1 : bx1;
    by1 = by1 > desc->height - 1 ? desc->height - 1 : by1;
    if (bx0 > bx1 || by0 > by1) return false;
    s->bx0 = bx0, s->bx1 = bx1, s->by0 = by0, s->by1 = by1;
    return true;
}

/* Orient the snapped triangle counter-clockwise on screen (y down); false when its area is zero
 * or it is a back face to cull. */
static bool orient_triangle(bool cull_back, snapped_triangle *s) {
    int64_t *X = s->X, *Y = s->Y;
    int64_t area = (X[1] - X[0]) * (Y[2] - Y[0]) - (Y[1] - Y[0]) * (X[2] - X[0]);
    if (area == 0) return false;
    /* Counter-clockwise from outside in the world is clockwise on screen (y down): area < 0. */
    if (area > 0 && cull_back) return false;
    s->swap = area < 0;
    if (s->swap) { /* make the edge functions positive inside */
        int64_t t = X[1];
        X[1] = X[2];
        X[2] = t;
        t = Y[1];
        Y[1] = Y[2];
        Y[2] = t;
    }
    return true;
}

/* Whether the oriented triangle covers a sample centre of its sample box when that box is at
 * most 2 x 2 samples (true for larger boxes): the edge functions and the top-left rule of
 * setup_triangle at each centre, evaluated as cover_triangle evaluates them (raster_tiles.c),
 * so a triangle this rejects would have covered no sample. Most triangles of a displaced mesh
 * are smaller than a sample, and many of those whose box holds a centre miss it
 * (docs/rasterizer.md). */
static bool covers_small_box(const snapped_triangle *s) {
    if (s->bx1 - s->bx0 > 1 || s->by1 - s->by0 > 1) return true;
    const int64_t half = RASTER_SUBPIXEL_ONE / 2;
    const int64_t *X = s->X, *Y = s->Y;
    for (int corner = 0; corner < 4; corner++) {
        int64_t px = ((int64_t)(corner & 1 ? s->bx1 : s->bx0) << RASTER_SUBPIXEL_BITS) + half;
        int64_t py = ((int64_t)(corner & 2 ? s->by1 : s->by0) << RASTER_SUBPIXEL_BITS) + half;
        bool inside = true;
#pragma GCC unroll 3
        for (int k = 0; k < 3; k++) {
            int a = (k + 1) % 3, b = (k + 2) % 3;
            int32_t ea = (int32_t)(-(Y[b] - Y[a])), eb = (int32_t)(X[b] - X[a]);
            int32_t bias = (ea > 0 || (ea == 0 && eb > 0)) ? 0 : -1;
            inside &=
                (int64_t)ea * (px - (int32_t)X[a]) + (int64_t)eb * (py - (int32_t)Y[a]) + bias >= 0;
        }
        if (inside) return true;
    }
    return false;
}

/* Snap the vertices (clip x, y, w) to 1/256 sample and find the sample centres the bounding box
 * holds; false when there are none, the area is zero or a culled back face. This is the whole
 * cost of many triangles of a displaced mesh (they cover no sample centre, docs/performance.md),
 * so it runs before the edge functions and the planes are built and before the chunk grows.
 * The 8-wide path (setup_source_triangles8) computes the same integers. */
static bool snap_triangle(const raster_setup_desc *desc, bool cull_back, const clip_vertex *v[3],
                          snapped_triangle *s) {
    double W = (double)desc->width, H = (double)desc->height;
    for (int k = 0; k < 3; k++) {
        if (!(v[k]->w > 0.0)) return false; /* only for projections with w <= 0 in front */
        double inv_w = 1.0 / v[k]->w;
        double sx = (v[k]->x * inv_w * 0.5 + 0.5) * W;
        double sy = (0.5 - 0.5 * v[k]->y * inv_w) * H;
        s->X[k] = round_to_int64(sx * RASTER_SUBPIXEL_ONE);
        s->Y[k] = round_to_int64(sy * RASTER_SUBPIXEL_ONE);
    }
    /* the box does not depend on the orientation: test the cheaper rejection first */
    return sample_box(desc, s) && orient_triangle(cull_back, s) &&
           (!desc->drop_uncovered || covers_small_box(s));
}

/* Set up one (possibly clipped) triangle that snap_triangle kept. */
static void setup_triangle(const raster_setup_desc *desc, const snapped_triangle *s,
                           const clip_vertex *vin[3], uint32_t triangle, raster_triangle *out) {
    const clip_vertex *v[3] = {vin[0], s->swap ? vin[2] : vin[1], s->swap ? vin[1] : vin[2]};
    const int64_t *X = s->X, *Y = s->Y;
    int32_t bx0 = s->bx0, bx1 = s->bx1, by0 = s->by0, by1 = s->by1;
    out->min_x = bx0, out->max_x = bx1, out->min_y = by0, out->max_y = by1;
    out->triangle = triangle;
    /* The loops over the three edges unrolled: their % 3 indexing and loop counters were a
     * quarter of this function's instructions. */
#pragma GCC unroll 3
    for (int k = 0; k < 3; k++) {
        out->x[k] = (int32_t)X[k];
        out->y[k] = (int32_t)Y[k];
        int a = (k + 1) % 3, b = (k + 2) % 3;
        /* E_k(p) = (b - a) x (p - a): a = dE/dx, b = dE/dy */
        int32_t ea = (int32_t)(-(Y[b] - Y[a]));
        int32_t eb = (int32_t)(X[b] - X[a]);
        out->edge_a[k] = ea;
        out->edge_b[k] = eb;
        /* Top-left rule (y down): a left edge has the inside to its right (dE/dx > 0), a top
         * edge is horizontal with the inside below it (dE/dy > 0). */
        out->bias[k] = (ea > 0 || (ea == 0 && eb > 0)) ? 0 : -1;
    }

    /* Planes of lambda_k / w_k in sample units around the bounding box centre, in double. */
    double rx = 0.5 * (double)(bx0 + bx1 + 1), ry = 0.5 * (double)(by0 + by1 + 1);
    double px[3], py[3];
#pragma GCC unroll 3
    for (int k = 0; k < 3; k++) {
        px[k] = (double)X[k] / RASTER_SUBPIXEL_ONE;
        py[k] = (double)Y[k] / RASTER_SUBPIXEL_ONE;
    }
    double area_d = (px[1] - px[0]) * (py[2] - py[0]) - (py[1] - py[0]) * (px[2] - px[0]);
    double la[3], lb[3], lc[3];
#pragma GCC unroll 3
    for (int k = 0; k < 3; k++) {
        int a = (k + 1) % 3, b = (k + 2) % 3;
        double inv = 1.0 / (area_d * v[k]->w);
        la[k] = -(py[b] - py[a]) * inv;
        lb[k] = (px[b] - px[a]) * inv;
        lc[k] = ((px[b] - px[a]) * (ry - py[a]) - (py[b] - py[a]) * (rx - px[a])) * inv;
    }
#pragma GCC unroll 3
    for (int i = 0; i < 3; i++) {
        double ga = 0.0, gb = 0.0, gc = 0.0;
#pragma GCC unroll 3
        for (int k = 0; k < 3; k++) {
            ga += v[k]->bary[i] * la[k];
            gb += v[k]->bary[i] * lb[k];
            gc += v[k]->bary[i] * lc[k];
        }
        out->ga[i] = (float)ga;
        out->gb[i] = (float)gb;
        out->gc[i] = (float)gc;
    }
    out->ref_x = (float)rx;
    out->ref_y = (float)ry;
    if (desc->depth_plane) {
        double za = 0.0, zb = 0.0, zc = 0.0;
        for (int k = 0; k < 3; k++) {
            double z = v[k]->z / v[k]->w * 0.5 + 0.5;
            /* la, lb, lc above are divided by w_k; undo that for the screen-linear z */
            za += la[k] * v[k]->w * z;
            zb += lb[k] * v[k]->w * z;
            zc += lc[k] * v[k]->w * z;
        }
        out->za = (float)za, out->zb = (float)zb, out->zc = (float)zc;
    } else {
        out->za = out->zb = out->zc = 0.0f;
    }
}

static bool reserve(void **data, size_t *capacity, size_t needed, size_t item) {
    if (needed <= *capacity) return true;
    size_t cap = *capacity ? *capacity : RESERVE_FIRST_ITEMS;
    while (cap < needed) cap *= 2;
    void *p = realloc(*data, cap * item);
    if (!p) return false;
    *data = p;
    *capacity = cap;
    return true;
}

/* Whether the triangle (world positions) faces away from the eye by more than
 * RASTER_BACK_FACE_MARGIN: the rasterizer would cull it (a triangle counter-clockwise from
 * outside is front-facing exactly when the eye lies on its outer side, for any part of it in
 * front of the eye), and this costs a cross and a dot product instead of three vertex transforms
 * and the snapping. The margin leaves triangles near edge-on, where snapping to 1/256 sample
 * could turn the screen orientation, to the exact test. NaNs compare false: not culled here. */
static bool faces_away(const raster_bins *bins, meso_vec3 p0, meso_vec3 p1, meso_vec3 p2) {
    meso_vec3 n = meso_vec3_cross(meso_vec3_sub(p1, p0), meso_vec3_sub(p2, p0));
    meso_vec3 to_eye = meso_vec3_sub(bins->eye, p0);
    float d = meso_vec3_dot(n, to_eye);
    if (!(d < 0.0f)) return false;
    float scale = meso_vec3_dot(n, n) * meso_vec3_dot(to_eye, to_eye);
    return d * d > RASTER_BACK_FACE_MARGIN * RASTER_BACK_FACE_MARGIN * scale;
}

/* Set up one triangle (or a piece of a clipped one) into the chunk when it covers a sample. */
static void emit_triangle(const raster_setup_desc *desc, bool cull_back, const clip_vertex *tri[3],
                          uint32_t t, raster_chunk *chunk) {
    snapped_triangle st;
    if (!snap_triangle(desc, cull_back, tri, &st)) return;
    if (!reserve((void **)&chunk->triangles, &chunk->capacity, chunk->num_triangles + 1,
                 sizeof(raster_triangle))) {
        chunk->failed = true;
        return;
    }
    setup_triangle(desc, &st, tri, t, &chunk->triangles[chunk->num_triangles++]);
}

/* Reject, clip and set up source triangle t from its clip-space vertices; appends 0..6
 * triangles to the chunk. */
static void setup_clip_triangle(const raster_bins *bins, bool cull_back, const meso_vec4 c[3],
                                uint32_t t, raster_chunk *chunk) {
    const raster_setup_desc *desc = &bins->desc;
    /* x * 0 is NaN exactly when x is infinite or NaN, and a NaN survives the sum: one
     * branch for the twelve coordinates (a million-triangle mesh runs this twice a frame) */
    float poison = 0.0f;
    for (int k = 0; k < 3; k++)
        poison += (c[k].x * 0.0f + c[k].y * 0.0f) + (c[k].z * 0.0f + c[k].w * 0.0f);
    if (poison != poison) return;
    /* Trivial reject: all three outside one plane of the view frustum (no sample centre lies
     * on or beyond x = +-w or y = +-w). */
    if (c[0].x > c[0].w && c[1].x > c[1].w && c[2].x > c[2].w) return;
    if (c[0].x < -c[0].w && c[1].x < -c[1].w && c[2].x < -c[2].w) return;
    if (c[0].y > c[0].w && c[1].y > c[1].w && c[2].y > c[2].w) return;
    if (c[0].y < -c[0].w && c[1].y < -c[1].w && c[2].y < -c[2].w) return;
    /* The near plane: clip w >= z_near, or z_ndc >= -1 for depth maps (any projection). */
    float zn = desc->clip_z ? -1.0f : desc->z_near;
    float nd[3];
    for (int k = 0; k < 3; k++) nd[k] = desc->clip_z ? c[k].z + c[k].w : c[k].w - zn;
    if (nd[0] < 0.0f && nd[1] < 0.0f && nd[2] < 0.0f) return;

    float g = bins->guard;
    bool inside = true;
    for (int k = 0; k < 3; k++) { /* without branches: almost every triangle is inside */
        inside &= (nd[k] >= 0.0f) & (c[k].w > 0.0f) & (fabsf(c[k].x) <= g * c[k].w) &
                  (fabsf(c[k].y) <= g * c[k].w);
    }
    clip_vertex poly[2][MAX_POLYGON];
    for (int k = 0; k < 3; k++)
        poly[0][k] = (clip_vertex){c[k].x, c[k].y, c[k].z, c[k].w, {k == 0, k == 1, k == 2}};
    if (inside) { /* the common case */
        const clip_vertex *tri[3] = {&poly[0][0], &poly[0][1], &poly[0][2]};
        emit_triangle(desc, cull_back, tri, t, chunk);
        return;
    }
    int n = 3, cur = 0;
    for (int plane = 0; plane < 5 && n >= 3; plane++) {
        n = clip_polygon(poly[cur], n, poly[cur ^ 1], plane, zn, g);
        cur ^= 1;
    }
    for (int k = 1; k + 1 < n; k++) {
        const clip_vertex *tri[3] = {&poly[cur][0], &poly[cur][k], &poly[cur][k + 1]};
        emit_triangle(desc, cull_back, tri, t, chunk);
        if (chunk->failed) return;
    }
}

/* Set up source triangle t alone (the tail of a chunk, and the reference the 8-wide path is
 * tested against). */
static void setup_source_triangle(const raster_bins *bins, const raster_mesh *rm, uint32_t t,
                                  raster_chunk *chunk) {
    const raster_setup_desc *desc = &bins->desc;
    const uint32_t *idx = rm->mesh->indices + 3 * (size_t)t;
    bool cull_back = desc->cull_back && !rm->both_faces;
    meso_vec3 p[3] = {rm->mesh->positions[idx[0]], rm->mesh->positions[idx[1]],
                      rm->mesh->positions[idx[2]]};
    if (cull_back && bins->has_eye && faces_away(bins, p[0], p[1], p[2])) return;
    /* Vertices are transformed here, per triangle: a vertex shared by several triangles is
     * transformed several times (always to the same bits), which costs less than a separate
     * parallel pass and its barrier. */
    meso_vec4 c[3];
    for (int k = 0; k < 3; k++)
        c[k] = meso_mat4_mul_vec4(desc->view_projection, (meso_vec4){p[k].x, p[k].y, p[k].z, 1.0f});
    setup_clip_triangle(bins, cull_back, c, t, chunk);
}

/* ---- Eight source triangles at a time ----------------------------------------------------- */

/* With AVX2 only: compiled for SSE2 (a portable build's baseline), the 8-wide code costs more
 * instructions than the one-triangle path (docs/rasterizer.md):
 * no 64-bit or 32-bit lane minimum, no packed double rounding, every vector split in pairs. */
#if defined(__AVX2__)

typedef float v4f __attribute__((vector_size(16)));
typedef double v4d __attribute__((vector_size(32)));

static inline v8f v8_abs(v8f x) { return (v8f)((v8i)x & v8i_splat(0x7fffffff)); }
static inline v8i v8i_min(v8i a, v8i b) {
    v8i m = a < b;
    return (a & m) | (b & ~m);
}
static inline v8i v8i_max(v8i a, v8i b) {
    v8i m = a > b;
    return (a & m) | (b & ~m);
}

/* Lanes 4 h .. 4 h + 3 of x in double. */
static inline v4d v4d_half(v8f x, int h) {
    v4f q = {x[4 * h], x[4 * h + 1], x[4 * h + 2], x[4 * h + 3]};
    return __builtin_convertvector(q, v4d);
}

/* round_to_int64 of eight doubles that lie well inside the int32 range (the snapped coordinates
 * of triangles inside the guard band: below 2^27): cvtpd2dq rounds in the current mode as
 * cvtsd2si does, so the integers are the same. */
static inline v8i round8(v4d lo, v4d hi) {
    __m128i a = _mm256_cvtpd_epi32((__m256d)lo), b = _mm256_cvtpd_epi32((__m256d)hi);
    return (v8i)_mm256_set_m128i(b, a);
}

/* faces_away for eight triangles, with the same operations in the same order. */
static inline v8i faces_away8(meso_vec3 eye, const v8f px[3], const v8f py[3], const v8f pz[3]) {
    v8f ax = px[1] - px[0], ay = py[1] - py[0], az = pz[1] - pz[0];
    v8f bx = px[2] - px[0], by = py[2] - py[0], bz = pz[2] - pz[0];
    v8f nx = ay * bz - az * by, ny = az * bx - ax * bz, nz = ax * by - ay * bx;
    v8f ex = eye.x - px[0], ey = eye.y - py[0], ez = eye.z - pz[0];
    v8f d = nx * ex + ny * ey + nz * ez;
    v8f scale = (nx * nx + ny * ny + nz * nz) * (ex * ex + ey * ey + ez * ez);
    return (d < 0.0f) & (d * d > RASTER_BACK_FACE_MARGIN * RASTER_BACK_FACE_MARGIN * scale);
}

/* snap_triangle's projection and snapping of one vertex of eight triangles. */
static inline void snap8(v8f x, v8f y, v8f w, double width, double height, v8i *out_x, v8i *out_y) {
    v4d sx[2], sy[2];
    for (int h = 0; h < 2; h++) {
        v4d inv_w = 1.0 / v4d_half(w, h);
        sx[h] = (v4d_half(x, h) * inv_w * 0.5 + 0.5) * width * (double)RASTER_SUBPIXEL_ONE;
        sy[h] = (0.5 - 0.5 * v4d_half(y, h) * inv_w) * height * (double)RASTER_SUBPIXEL_ONE;
    }
    *out_x = round8(sx[0], sx[1]);
    *out_y = round8(sy[0], sy[1]);
}

typedef int32_t v4i __attribute__((vector_size(16)));
typedef int64_t v4l __attribute__((vector_size(32)));
typedef uint64_t v4lu __attribute__((vector_size(32)));

static inline v4l v4l_half(v8i x, int h) {
    v4i q = {x[4 * h], x[4 * h + 1], x[4 * h + 2], x[4 * h + 3]};
    return __builtin_convertvector(q, v4l);
}
/* Lanes 4 h .. 4 h + 3 of integer x in double. */
static inline v4d v4d_half_int(v8i x, int h) {
    v4i q = {x[4 * h], x[4 * h + 1], x[4 * h + 2], x[4 * h + 3]};
    return __builtin_convertvector(q, v4d);
}
static inline int v4l_mask_bits(v4l mask) { return _mm256_movemask_pd((__m256d)mask); }
/* a * b of 64-bit lanes holding sign-extended 32-bit integers (vpmuldq: no 64-bit product
 * emulated from three). */
static inline v4l mul_wide(v4l a, v4l b) { return (v4l)_mm256_mul_epi32((__m256i)a, (__m256i)b); }
static inline v8i v8i_select(v8i mask, v8i a, v8i b) { return (a & mask) | (b & ~mask); }

/* Eight unclipped triangles that passed the sample-box test, set up as setup_triangle would:
 * the fields, lane by lane, in `out` (raster_triangle's layout transposed). */
typedef struct triangles8 {
    v8i x[3], y[3], edge_a[3], edge_b[3], bias[3];
    v8f ref_x, ref_y, ga[3], gb[3], gc[3], za, zb, zc;
    int kept;       /* lanes kept by the orientation (area and back-face) test */
    int one_by_one; /* lanes whose planes are not finite: left to setup_triangle */
} triangles8;

/* orient_triangle and setup_triangle for the lanes of `lanes`, eight wide, to the same bits:
 * the area in 64-bit integers, the planes in double with the same operations in the same
 * order. Unclipped, vertex k's barycentrics are e_k, so setup_triangle's sums
 * 0 + b_0 l_0 + b_1 l_1 + b_2 l_2 are the one term l_k plus zeros: l_k + 0, bit for bit, when
 * l_k is finite (a NaN or infinite l_k would spread through the zero products: such lanes,
 * slivers spanning the guard band, go to setup_triangle). */
static void setup_triangles8(const raster_setup_desc *desc, bool cull_back, const v8i X[3],
                             const v8i Y[3], v8i bx0, v8i bx1, v8i by0, v8i by1, const v8f cz[3],
                             const v8f cw[3], int lanes, triangles8 *out) {
    int neg = 0, zero = 0, pos = 0;
    v8i dx1 = X[1] - X[0], dy2 = Y[2] - Y[0], dy1 = Y[1] - Y[0], dx2 = X[2] - X[0];
    for (int h = 0; h < 2; h++) {
        v4l area = v4l_half(dx1, h) * v4l_half(dy2, h) - v4l_half(dy1, h) * v4l_half(dx2, h);
        neg |= v4l_mask_bits(area < 0) << 4 * h;
        zero |= v4l_mask_bits(area == 0) << 4 * h;
        pos |= v4l_mask_bits(area > 0) << 4 * h;
    }
    out->kept = lanes & ~zero & ~(cull_back ? pos : 0);
    out->one_by_one = 0;
    if (!out->kept) return;
    v8i swap = v8_mask_from_bits(neg);
    /* counter-clockwise on screen: vertices 1 and 2 swapped where the area is negative */
    v8i x[3] = {X[0], v8i_select(swap, X[2], X[1]), v8i_select(swap, X[1], X[2])};
    v8i y[3] = {Y[0], v8i_select(swap, Y[2], Y[1]), v8i_select(swap, Y[1], Y[2])};
    v8f w[3] = {cw[0], v8_select(swap, cw[2], cw[1]), v8_select(swap, cw[1], cw[2])};
    v8f z[3] = {cz[0], v8_select(swap, cz[2], cz[1]), v8_select(swap, cz[1], cz[2])};
#pragma GCC unroll 3
    for (int k = 0; k < 3; k++) {
        int a = (k + 1) % 3, b = (k + 2) % 3;
        out->x[k] = x[k], out->y[k] = y[k];
        v8i ea = -(y[b] - y[a]), eb = x[b] - x[a];
        out->edge_a[k] = ea, out->edge_b[k] = eb;
        out->bias[k] = ~((ea > 0) | ((ea == 0) & (eb > 0)));
    }
    /* covers_small_box, eight wide */
    if (desc->drop_uncovered) {
        v8i wide = bx1 - bx0, tall = by1 - by0; /* 0 or 1 in a small box */
        int small_bits = out->kept & v8_mask_bits((wide <= 1) & (tall <= 1));
        if (small_bits) {
            const int32_t half = RASTER_SUBPIXEL_ONE / 2;
            v8i px = (bx0 << RASTER_SUBPIXEL_BITS) + half,
                py = (by0 << RASTER_SUBPIXEL_BITS) + half;
            int covered = 0;
            for (int h = 0; h < 2; h++) {
                /* the edge functions at the box's four corners (the same centre twice in a
                 * box one sample wide or tall): at (bx0, by0) and one sample step on */
                v4l step_x = v4l_half(wide == 1, h), step_y = v4l_half(tall == 1, h); /* masks */
                v4l neg00 = {0, 0, 0, 0}, neg10 = neg00, neg01 = neg00, neg11 = neg00;
#pragma GCC unroll 3
                for (int k = 0; k < 3; k++) {
                    int a = (k + 1) % 3;
                    v4l ea = v4l_half(out->edge_a[k], h), eb = v4l_half(out->edge_b[k], h);
                    v4l e00 = mul_wide(ea, v4l_half(px - x[a], h)) +
                              mul_wide(eb, v4l_half(py - y[a], h)) + v4l_half(out->bias[k], h);
                    /* one sample on: the step times 256, shifted as unsigned (defined for a
                     * negative step, and no 64-bit lane product) */
                    v4l dx = (v4l)((v4lu)ea << RASTER_SUBPIXEL_BITS) & step_x;
                    v4l dy = (v4l)((v4lu)eb << RASTER_SUBPIXEL_BITS) & step_y;
                    neg00 |= e00, neg10 |= e00 + dx, neg01 |= e00 + dy, neg11 |= e00 + dx + dy;
                }
                int miss = v4l_mask_bits(neg00 < 0) & v4l_mask_bits(neg10 < 0) &
                           v4l_mask_bits(neg01 < 0) & v4l_mask_bits(neg11 < 0);
                covered |= (~miss & 15) << 4 * h;
            }
            out->kept &= ~(small_bits & ~covered);
            if (!out->kept) return;
        }
    }
    v8i ref2_x = bx0 + bx1 + 1, ref2_y = by0 + by1 + 1;
    v8f non_finite = v8_splat(0.0f);
    for (int h = 0; h < 2; h++) {
        v4d rx = 0.5 * v4d_half_int(ref2_x, h), ry = 0.5 * v4d_half_int(ref2_y, h);
        v4d px[3], py[3], wd[3];
        for (int k = 0; k < 3; k++) {
            px[k] = v4d_half_int(x[k], h) / (double)RASTER_SUBPIXEL_ONE;
            py[k] = v4d_half_int(y[k], h) / (double)RASTER_SUBPIXEL_ONE;
            wd[k] = v4d_half(w[k], h);
        }
        v4d area_d = (px[1] - px[0]) * (py[2] - py[0]) - (py[1] - py[0]) * (px[2] - px[0]);
        v4d la[3], lb[3], lc[3], bad = {0.0, 0.0, 0.0, 0.0};
#pragma GCC unroll 3
        for (int k = 0; k < 3; k++) {
            int a = (k + 1) % 3, b = (k + 2) % 3;
            v4d inv = 1.0 / (area_d * wd[k]);
            la[k] = -(py[b] - py[a]) * inv;
            lb[k] = (px[b] - px[a]) * inv;
            lc[k] = ((px[b] - px[a]) * (ry - py[a]) - (py[b] - py[a]) * (rx - px[a])) * inv;
            bad += (la[k] * 0.0 + lb[k] * 0.0) + lc[k] * 0.0; /* NaN where one is not finite */
        }
        v4f bad_f = __builtin_convertvector(bad, v4f);
        for (int j = 0; j < 4; j++) non_finite[4 * h + j] = bad_f[j];
        /* source barycentric i is vertex k's of the oriented triangle: k = i, or 1 and 2
         * exchanged where swapped */
        v4l swap_h = v4l_half(swap, h);
        v4d g_a[3] = {la[0], (v4d)(((v4l)la[2] & swap_h) | ((v4l)la[1] & ~swap_h)),
                      (v4d)(((v4l)la[1] & swap_h) | ((v4l)la[2] & ~swap_h))};
        v4d g_b[3] = {lb[0], (v4d)(((v4l)lb[2] & swap_h) | ((v4l)lb[1] & ~swap_h)),
                      (v4d)(((v4l)lb[1] & swap_h) | ((v4l)lb[2] & ~swap_h))};
        v4d g_c[3] = {lc[0], (v4d)(((v4l)lc[2] & swap_h) | ((v4l)lc[1] & ~swap_h)),
                      (v4d)(((v4l)lc[1] & swap_h) | ((v4l)lc[2] & ~swap_h))};
        for (int i = 0; i < 3; i++) {
            v4f qa = __builtin_convertvector(g_a[i] + 0.0, v4f);
            v4f qb = __builtin_convertvector(g_b[i] + 0.0, v4f);
            v4f qc = __builtin_convertvector(g_c[i] + 0.0, v4f);
            for (int j = 0; j < 4; j++) {
                out->ga[i][4 * h + j] = qa[j];
                out->gb[i][4 * h + j] = qb[j];
                out->gc[i][4 * h + j] = qc[j];
            }
        }
        v4f qx = __builtin_convertvector(rx, v4f), qy = __builtin_convertvector(ry, v4f);
        v4f qza = {0.0f, 0.0f, 0.0f, 0.0f}, qzb = qza, qzc = qza;
        if (desc->depth_plane) {
            v4d za = {0.0, 0.0, 0.0, 0.0}, zb = za, zc = za;
            for (int k = 0; k < 3; k++) {
                v4d zk = v4d_half(z[k], h) / wd[k] * 0.5 + 0.5;
                za += la[k] * wd[k] * zk;
                zb += lb[k] * wd[k] * zk;
                zc += lc[k] * wd[k] * zk;
            }
            qza = __builtin_convertvector(za, v4f);
            qzb = __builtin_convertvector(zb, v4f);
            qzc = __builtin_convertvector(zc, v4f);
        }
        for (int j = 0; j < 4; j++) {
            out->ref_x[4 * h + j] = qx[j], out->ref_y[4 * h + j] = qy[j];
            out->za[4 * h + j] = qza[j], out->zb[4 * h + j] = qzb[j], out->zc[4 * h + j] = qzc[j];
        }
    }
    out->one_by_one = out->kept & v8_mask_bits(non_finite != non_finite);
}

/* Lane j of the eight triangles into `o`. */
static void store_triangle8(const triangles8 *s, int j, int32_t bx0, int32_t bx1, int32_t by0,
                            int32_t by1, uint32_t triangle, raster_triangle *o) {
#pragma GCC unroll 3
    for (int k = 0; k < 3; k++) {
        o->x[k] = s->x[k][j], o->y[k] = s->y[k][j];
        o->edge_a[k] = s->edge_a[k][j], o->edge_b[k] = s->edge_b[k][j];
        o->bias[k] = s->bias[k][j];
        o->ga[k] = s->ga[k][j], o->gb[k] = s->gb[k][j], o->gc[k] = s->gc[k][j];
    }
    o->min_x = bx0, o->max_x = bx1, o->min_y = by0, o->max_y = by1;
    o->ref_x = s->ref_x[j], o->ref_y = s->ref_y[j];
    o->za = s->za[j], o->zb = s->zb[j], o->zc = s->zc[j];
    o->triangle = triangle;
}

/* Source triangles t .. t + 7: the world-space back-face test, the vertex transform, the poison
 * and frustum rejects and, for the triangles that need no clipping, the snap and the sample-box
 * test, eight lanes wide with the very operations of the one-triangle path in the same order
 * (and no fused multiply-add: -ffp-contract=off), so every bit and integer is the same. Most
 * triangles of a displaced mesh end there. The others are set up one by one in source order —
 * the survivors by setup_triangle, the rare ones that need clipping by the one-triangle path —
 * so the chunk holds the same triangles in the same order. */
static void setup_source_triangles8(const raster_bins *bins, const raster_mesh *rm, uint32_t t,
                                    raster_chunk *chunk) {
    const raster_setup_desc *desc = &bins->desc;
    const meso_mesh *mesh = rm->mesh;
    bool cull_back = desc->cull_back && !rm->both_faces;
    v8f px[3], py[3], pz[3];
    const uint32_t *idx = mesh->indices + 3 * (size_t)t;
#pragma GCC unroll 8
    for (int j = 0; j < V8_LANES; j++) {
#pragma GCC unroll 3
        for (int k = 0; k < 3; k++) {
            meso_vec3 p = mesh->positions[idx[3 * j + k]];
            px[k][j] = p.x, py[k][j] = p.y, pz[k][j] = p.z;
        }
    }
    v8i dropped = v8i_splat(0);
    if (cull_back && bins->has_eye) dropped = faces_away8(bins->eye, px, py, pz);
    const float *m = desc->view_projection.m;
    v8f cx[3], cy[3], cz[3], cw[3];
    for (int k = 0; k < 3; k++) { /* meso_mat4_mul_vec4 with w = 1 */
        cx[k] = m[0] * px[k] + m[4] * py[k] + m[8] * pz[k] + m[12] * 1.0f;
        cy[k] = m[1] * px[k] + m[5] * py[k] + m[9] * pz[k] + m[13] * 1.0f;
        cz[k] = m[2] * px[k] + m[6] * py[k] + m[10] * pz[k] + m[14] * 1.0f;
        cw[k] = m[3] * px[k] + m[7] * py[k] + m[11] * pz[k] + m[15] * 1.0f;
    }
    v8f poison = v8_splat(0.0f);
    for (int k = 0; k < 3; k++)
        poison += (cx[k] * 0.0f + cy[k] * 0.0f) + (cz[k] * 0.0f + cw[k] * 0.0f);
    dropped |= poison != poison;
    dropped |= (cx[0] > cw[0]) & (cx[1] > cw[1]) & (cx[2] > cw[2]);
    dropped |= (cx[0] < -cw[0]) & (cx[1] < -cw[1]) & (cx[2] < -cw[2]);
    dropped |= (cy[0] > cw[0]) & (cy[1] > cw[1]) & (cy[2] > cw[2]);
    dropped |= (cy[0] < -cw[0]) & (cy[1] < -cw[1]) & (cy[2] < -cw[2]);
    float zn = desc->clip_z ? -1.0f : desc->z_near;
    v8f nd[3];
    for (int k = 0; k < 3; k++) nd[k] = desc->clip_z ? cz[k] + cw[k] : cw[k] - zn;
    dropped |= (nd[0] < 0.0f) & (nd[1] < 0.0f) & (nd[2] < 0.0f);
    v8f g = v8_splat(bins->guard);
    v8i inside = ~dropped;
    for (int k = 0; k < 3; k++) {
        inside &= (nd[k] >= 0.0f) & (cw[k] > 0.0f) & (v8_abs(cx[k]) <= g * cw[k]) &
                  (v8_abs(cy[k]) <= g * cw[k]);
    }
    int clip_bits = v8_mask_bits(~dropped & ~inside);
    int keep_bits = 0;
    v8i X[3], Y[3], bx0, bx1, by0, by1;
    if (v8_any(inside)) {
        for (int k = 0; k < 3; k++)
            snap8(cx[k], cy[k], cw[k], (double)desc->width, (double)desc->height, &X[k], &Y[k]);
        /* sample_box: sample i has its centre at 256 i + 128 */
        const int32_t half = RASTER_SUBPIXEL_ONE / 2;
        bx0 = -(-(v8i_min(X[0], v8i_min(X[1], X[2])) - half) >> RASTER_SUBPIXEL_BITS);
        bx1 = (v8i_max(X[0], v8i_max(X[1], X[2])) - half) >> RASTER_SUBPIXEL_BITS;
        by0 = -(-(v8i_min(Y[0], v8i_min(Y[1], Y[2])) - half) >> RASTER_SUBPIXEL_BITS);
        by1 = (v8i_max(Y[0], v8i_max(Y[1], Y[2])) - half) >> RASTER_SUBPIXEL_BITS;
        bx0 = v8i_max(bx0, v8i_splat(0));
        by0 = v8i_max(by0, v8i_splat(0));
        bx1 = v8i_min(bx1, v8i_splat(desc->width - 1));
        by1 = v8i_min(by1, v8i_splat(desc->height - 1));
        keep_bits = v8_mask_bits(inside & (bx0 <= bx1) & (by0 <= by1));
    }
    triangles8 set;
    set.kept = set.one_by_one = 0;
    if (keep_bits)
        setup_triangles8(desc, cull_back, X, Y, bx0, bx1, by0, by1, cz, cw, keep_bits, &set);
    /* The survivors and the triangles to clip, in source order. */
    for (int todo = set.kept | clip_bits; todo; todo &= todo - 1) {
        int j = __builtin_ctz((unsigned)todo);
        uint32_t tj = t + (uint32_t)j;
        if (clip_bits >> j & 1) {
            meso_vec4 c[3];
            for (int k = 0; k < 3; k++) c[k] = (meso_vec4){cx[k][j], cy[k][j], cz[k][j], cw[k][j]};
            setup_clip_triangle(bins, cull_back, c, tj, chunk);
            if (chunk->failed) return;
            continue;
        }
        if (!reserve((void **)&chunk->triangles, &chunk->capacity, chunk->num_triangles + 1,
                     sizeof(raster_triangle))) {
            chunk->failed = true;
            return;
        }
        raster_triangle *o = &chunk->triangles[chunk->num_triangles++];
        if (!(set.one_by_one >> j & 1)) {
            store_triangle8(&set, j, bx0[j], bx1[j], by0[j], by1[j], tj, o);
            continue;
        }
        snapped_triangle st = {.X = {X[0][j], X[1][j], X[2][j]},
                               .Y = {Y[0][j], Y[1][j], Y[2][j]},
                               .bx0 = bx0[j],
                               .bx1 = bx1[j],
                               .by0 = by0[j],
                               .by1 = by1[j]};
        orient_triangle(cull_back, &st); /* kept: setup_triangles8 found it so */
        clip_vertex v[3];
        for (int k = 0; k < 3; k++)
            v[k] = (clip_vertex){cx[k][j], cy[k][j], cz[k][j], cw[k][j], {k == 0, k == 1, k == 2}};
        const clip_vertex *tri[3] = {&v[0], &v[1], &v[2]};
        setup_triangle(desc, &st, tri, tj, o);
    }
}

#endif /* __AVX2__ */

/* The tiles a triangle's sample box touches, inclusive. The box is clamped to the target, so
 * its bounds are not negative and divide as unsigned (a shift, no rounding toward zero). */
typedef struct tile_range {
    uint32_t x0, x1, y0, y1;
} tile_range;
static inline tile_range triangle_tiles(const raster_triangle *tri) {
    return (tile_range){
        (uint32_t)tri->min_x / RASTER_TILE_SIZE, (uint32_t)tri->max_x / RASTER_TILE_SIZE,
        (uint32_t)tri->min_y / RASTER_TILE_SIZE, (uint32_t)tri->max_y / RASTER_TILE_SIZE};
}

/* Set up the chunk's source triangles and bin them into tiles. */
static void process_chunk(const raster_bins *bins, raster_chunk *chunk) {
    const raster_mesh *rm = &bins->meshes[chunk->mesh];
    chunk->num_triangles = 0;
    chunk->num_entries = 0;
    chunk->failed = false;
    uint32_t t = chunk->first, end = chunk->first + chunk->count;
#if defined(__AVX2__)
    if (!bins->desc.one_at_a_time) {
        for (; t + V8_LANES <= end; t += V8_LANES) {
            setup_source_triangles8(bins, rm, t, chunk);
            if (chunk->failed) return;
        }
    }
#endif
    for (; t < end; t++) {
        setup_source_triangle(bins, rm, t, chunk);
        if (chunk->failed) return;
    }
    /* Bin: count per tile, prefix sums, fill in triangle order. */
    size_t num_tiles = (size_t)bins->tiles_x * (size_t)bins->tiles_y;
    if (!reserve((void **)&chunk->tile_start, &chunk->tile_start_capacity, num_tiles + 1,
                 sizeof(uint32_t))) {
        chunk->failed = true;
        return;
    }
    uint32_t *start = chunk->tile_start;
    uint32_t tiles_x = (uint32_t)bins->tiles_x;
    memset(start, 0, (num_tiles + 1) * sizeof(uint32_t));
    size_t total = 0;
    for (size_t i = 0; i < chunk->num_triangles; i++) {
        tile_range r = triangle_tiles(&chunk->triangles[i]);
        if (r.x0 == r.x1 && r.y0 == r.y1) { /* most triangles: one tile */
            start[r.y0 * tiles_x + r.x0 + 1]++;
            total++;
            continue;
        }
        for (uint32_t ty = r.y0; ty <= r.y1; ty++)
            for (uint32_t tx = r.x0; tx <= r.x1; tx++) start[ty * tiles_x + tx + 1]++;
        total += (size_t)(r.x1 - r.x0 + 1) * (size_t)(r.y1 - r.y0 + 1);
    }
    if (total > UINT32_MAX ||
        !reserve((void **)&chunk->entries, &chunk->entries_capacity, total, sizeof(uint32_t))) {
        chunk->failed = true;
        return;
    }
    for (size_t i = 0; i < num_tiles; i++) start[i + 1] += start[i];
    /* start[tile] is now the first slot of `tile`; fill using start[tile] as a cursor and
     * shift back afterwards. */
    for (size_t i = 0; i < chunk->num_triangles; i++) {
        tile_range r = triangle_tiles(&chunk->triangles[i]);
        if (r.x0 == r.x1 && r.y0 == r.y1) {
            chunk->entries[start[r.y0 * tiles_x + r.x0]++] = (uint32_t)i;
            continue;
        }
        for (uint32_t ty = r.y0; ty <= r.y1; ty++)
            for (uint32_t tx = r.x0; tx <= r.x1; tx++)
                chunk->entries[start[ty * tiles_x + tx]++] = (uint32_t)i;
    }
    for (size_t i = num_tiles; i > 0; i--) start[i] = start[i - 1];
    start[0] = 0;
    chunk->num_entries = total;
}

static void setup_chunk(void *user, size_t job, int thread_index) {
    (void)thread_index;
    raster_bins *bins = user;
    /* Work on a copy: neighbouring chunks share cache lines and are set up by other threads
     * at the same time (no false sharing on every triangle). */
    raster_chunk local = bins->chunks[job];
    process_chunk(bins, &local);
    bins->chunks[job] = local;
}

/* Triangles a chunk of a mesh of num_triangles: `base`, or more for meshes of more than
 * RASTER_CHUNKS_PER_MESH chunks. Every chunk costs a pass over the tile table when it is binned
 * and every tile a look at every chunk when it is drawn; for the million triangles of a
 * displaced mesh those passes cost more than the triangles' own setup. Depends on the mesh
 * only, never the thread count, and a tile meets its triangles in the same order whatever
 * the chunking, so the images are the same. */
static size_t mesh_chunk_size(size_t num_triangles, size_t base) {
    size_t spread = (num_triangles + RASTER_CHUNKS_PER_MESH - 1) / RASTER_CHUNKS_PER_MESH;
    return spread > base ? spread : base;
}

/* The eye of a perspective view_projection: the point whose clip x, y and w are all 0 (rows 0, 1
 * and 3 of the matrix as planes), by Cramer's rule in double. False for an orthographic
 * projection (w does not depend on the point) or a singular one. */
static bool projection_eye(meso_mat4 m, meso_vec3 *out_eye) {
    double r[3][4];
    const int rows[3] = {0, 1, 3};
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 4; j++) r[i][j] = (double)m.m[4 * j + rows[i]];
    double det = r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1]) -
                 r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0]) +
                 r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0]);
    double wlen = fabs(r[2][0]) + fabs(r[2][1]) + fabs(r[2][2]);
    if (!(wlen > 0.0) || !(fabs(det) > 1e-12 * wlen) || !isfinite(det)) return false;
    double e[3];
    for (int c = 0; c < 3; c++) { /* replace column c by -r[.][3] */
        double a[3][3];
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) a[i][j] = j == c ? -r[i][3] : r[i][j];
        e[c] = (a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
                a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0])) /
               det;
    }
    if (!isfinite(e[0]) || !isfinite(e[1]) || !isfinite(e[2])) return false;
    *out_eye = (meso_vec3){(float)e[0], (float)e[1], (float)e[2]};
    return true;
}

meso_result raster_bins_build(meso_context *ctx, raster_bins *bins, const meso_mesh *const *meshes,
                              const bool *both_faces, int num_meshes,
                              const raster_setup_desc *desc) {
    if (desc->width <= 0 || desc->height <= 0 || desc->width > RASTER_MAX_TARGET_SIDE ||
        desc->height > RASTER_MAX_TARGET_SIDE) {
        return meso_log_error(ctx, MESO_ERROR_LIMIT,
                              "render: target of %d x %d samples exceeds the limit %d a side",
                              desc->width, desc->height, RASTER_MAX_TARGET_SIDE);
    }
    bins->desc = *desc;
    bins->tiles_x = (desc->width + RASTER_TILE_SIZE - 1) / RASTER_TILE_SIZE;
    bins->tiles_y = (desc->height + RASTER_TILE_SIZE - 1) / RASTER_TILE_SIZE;
    int side = desc->width > desc->height ? desc->width : desc->height;
    bins->guard = (float)(2.0 * RASTER_GUARD_SAMPLES / (double)side);
    bins->has_eye = desc->cull_back && projection_eye(desc->view_projection, &bins->eye);

    /* Meshes. */
    if (num_meshes > bins->meshes_capacity) {
        raster_mesh *m = realloc(bins->meshes, (size_t)num_meshes * sizeof(*m));
        if (!m) goto oom;
        bins->meshes = m;
        bins->meshes_capacity = num_meshes;
    }
    bins->num_meshes = num_meshes;
    /* Chunks of a fixed size for a given target (never the thread count). Large targets get
     * larger chunks so that the per-chunk tile tables (4 bytes a tile) stay within about
     * 32 bytes a triangle. */
    size_t num_tiles = (size_t)bins->tiles_x * (size_t)bins->tiles_y;
    size_t chunk_size = RASTER_CHUNK_TRIANGLES *
                        (num_tiles > RASTER_CHUNK_TILES ? num_tiles / RASTER_CHUNK_TILES : 1);
    size_t chunks = 0;
    for (int m = 0; m < num_meshes; m++) {
        bins->meshes[m].mesh = meshes[m];
        bins->meshes[m].both_faces = both_faces && both_faces[m];
        size_t nt = meshes[m] ? meshes[m]->num_triangles : 0;
        size_t size = mesh_chunk_size(nt, chunk_size);
        chunks += (nt + size - 1) / size;
    }

    /* Chunks of source triangles, in object order. */
    if (chunks > bins->chunks_capacity) {
        raster_chunk *c = realloc(bins->chunks, chunks * sizeof(*c));
        if (!c) goto oom;
        memset(c + bins->chunks_capacity, 0, (chunks - bins->chunks_capacity) * sizeof(*c));
        bins->chunks = c;
        bins->chunks_capacity = chunks;
    }
    bins->num_chunks = chunks;
    size_t next = 0;
    for (int m = 0; m < num_meshes; m++) {
        size_t nt = meshes[m] ? meshes[m]->num_triangles : 0;
        size_t size = mesh_chunk_size(nt, chunk_size);
        for (size_t first = 0; first < nt; first += size) {
            raster_chunk *c = &bins->chunks[next++];
            c->mesh = m;
            c->first = (uint32_t)first;
            c->count = (uint32_t)(nt - first < size ? nt - first : size);
        }
    }
    meso_parallel_for(ctx, chunks, setup_chunk, bins);
    for (size_t i = 0; i < chunks; i++) {
        if (bins->chunks[i].failed) goto oom;
    }
    return MESO_OK;
oom:
    bins->num_chunks = 0;
    return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY,
                          "render: out of memory setting up triangles");
}

void raster_bins_release(raster_bins *bins) {
    free(bins->meshes);
    for (size_t i = 0; i < bins->chunks_capacity; i++) {
        free(bins->chunks[i].triangles);
        free(bins->chunks[i].tile_start);
        free(bins->chunks[i].entries);
    }
    free(bins->chunks);
    memset(bins, 0, sizeof(*bins));
}
