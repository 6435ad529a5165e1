/* The radiance transfer volume (include/meso/bake_rtv.h; GDM paper §3.2, §4.1). Passes over
 * the voxels: direct transfer with the mesostructure's shadowing at each voxel's nearest
 * surface point; one bounce gathered from it where rays meet the mesostructure; the table per
 * view (the surface point each view shows); the SVD of each coefficient's table. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <stdio.h>

#include "bake_internal.h"
#include "meso/bake_cache.h"
#include "meso/bake_rtv.h"
#include "meso/runtime.h"

typedef struct rtv_job {
    meso_rtv_desc desc;
    const meso_vec3 *direction; /* the fixed directions, tangent frame (z up) */
    float direction_weight;     /* 4 pi / directions */
    float step;                 /* march step, world units (a tile is 1) */
    const float *first;         /* the first pass (second pass only) */
    float *out;
    meso_vec3 *surface_point;  /* per voxel: the nearest surface point (u, v, w) ... */
    meso_vec3 *surface_normal; /* ... and its unit normal, tangent frame */
} rtv_job;

/* Texture space (u, v, w) to world-like space: a tile 1 wide, the shell `aspect` deep, z up. A
 * unit world direction d moves (u, v, w) by (d.x, d.y, -d.z / aspect). */
static bool occupied(const meso_rtv_desc *d, meso_vec3 uvw) {
    /* below the shell's bottom: a height field's floor; a solid's shell is open there (its
     * holes let the light from below the tangent plane through: render_gi.h) */
    if (uvw.z >= 1.0f) return !d->solid;
    if (d->heightfield)
        return uvw.z >= 1.0f - meso_heightfield_sample(d->heightfield, uvw.x, uvw.y);
    return meso_solid_distance(d->solid, uvw) <= 0.0f;
}

/* The surface point nearest the voxel centre c and its unit normal in the tangent frame. */
static void surface_at(const meso_rtv_desc *d, meso_vec3 c, meso_vec3 *out_p, meso_vec3 *out_n) {
    if (d->heightfield) {
        float h = meso_heightfield_sample(d->heightfield, c.x, c.y);
        meso_vec2 g = meso_heightfield_gradient(d->heightfield, c.x, c.y);
        *out_p = (meso_vec3){c.x, c.y, 1.0f - h};
        /* the surface z(u, v) = (h - 1) aspect: normal (-dz/du, -dz/dv, 1) */
        *out_n = meso_vec3_normalize((meso_vec3){-d->aspect * g.x, -d->aspect * g.y, 1.0f});
        return;
    }
    float dist = meso_solid_distance(d->solid, c);
    meso_vec3 g = meso_solid_gradient(d->solid, c);
    float g2 = meso_vec3_dot(g, g);
    *out_p = g2 > 0.0f ? meso_vec3_madd(c, g, -dist / g2) : c;
    meso_vec3 gp = meso_solid_gradient(d->solid, *out_p);
    /* d/dz = -(1 / aspect) d/dw */
    meso_vec3 n = {gp.x, gp.y, -gp.z / d->aspect};
    *out_n = meso_vec3_length(n) > 0.0f ? meso_vec3_normalize(n) : (meso_vec3){0, 0, 1};
}

/* The step (world length) and step count of a march along the world direction w, which moves
 * (u, v, w) by `move` per unit length: no step crosses more than an eighth of a layer of the
 * shell, and the march ends after max_tiles tiles sideways. */
static int march_steps(const rtv_job *rj, meso_vec3 w, meso_vec3 move, float *out_step) {
    const meso_rtv_desc *d = &rj->desc;
    float step = rj->step;
    if (fabsf(move.z) * step > 0.125f / (float)d->layers)
        step = 0.125f / (float)d->layers / fabsf(move.z);
    float horizontal = sqrtf(w.x * w.x + w.y * w.y);
    /* in float first: a nearly vertical ray would overflow an int */
    float steps = horizontal > 0.0f ? ceilf(d->max_tiles / (horizontal * step)) : (float)(1 << 20);
    *out_step = step;
    return steps < (float)(1 << 20) ? (int)steps : 1 << 20;
}

/* March from p along the world direction w; true when it escapes (leaves through the top or
 * travels max_tiles), else *out_hit is the first occupied point. */
static bool escapes(const rtv_job *rj, meso_vec3 p, meso_vec3 w, meso_vec3 *out_hit) {
    const meso_rtv_desc *d = &rj->desc;
    meso_vec3 move = {w.x, w.y, -w.z / d->aspect};
    float step;
    int steps = march_steps(rj, w, move, &step);
    for (int s = 1; s <= steps; s++) {
        meso_vec3 q = meso_vec3_madd(p, move, step * (float)s);
        if (q.z < 0.0f || (q.z > 1.0f && d->solid)) return true;
        if (occupied(d, q)) {
            *out_hit = q;
            return false;
        }
    }
    return true;
}

typedef struct pass_job {
    const rtv_job *rj;
    const meso_rtv *rtv; /* its size; the first pass' table in rj->first */
} pass_job;

/* A corner voxel answers for a surface point when its own nearest surface point is the same
 * surface: within this many voxels of it, with normals less than 60 degrees apart. */
#define SAME_SURFACE_VOXELS 1.5f
#define SAME_SURFACE_COSINE 0.5f

/* Wrapped difference of two periodic coordinates, in (-0.5, 0.5]. */
static float periodic_difference(float a, float b) {
    float d = a - b;
    return d - roundf(d);
}

/* A periodic lattice index and the next one: ((i % n) + n) % n and (that + 1) % n. A texture
 * coordinate's fraction times n, less half a cell, floors to i in [-1, n - 1] (the fraction
 * may round up to 1), where comparisons give the same indices as the divisions; anything else
 * (a NaN's conversion) takes the divisions. A hit's cell took six integer divisions, slow on
 * any x86. */
static inline void wrap_index(int i, int n, int *out_i0, int *out_i1) {
    int i0 = i >= 0 && i < n ? i : (i == -1 ? n - 1 : (i % n + n) % n);
    *out_i0 = i0;
    *out_i1 = i0 + 1 < n ? i0 + 1 : (i0 + 1) % n;
}

/* The 8 voxels around uvw (indices into [layers][height][width]) and their trilinear weights,
 * periodic in u and v: meso_rtv_cell_at's voxel half. Corner c's bits choose the upper voxel
 * in x, y, z; its weight is (x factor * y factor) * z factor. */
static void voxel_corners(const meso_rtv *rtv, meso_vec3 uvw, size_t corner[8], float weight[8]) {
    float x = (uvw.x - floorf(uvw.x)) * (float)rtv->width - 0.5f;
    float y = (1.0f - (uvw.y - floorf(uvw.y))) * (float)rtv->height - 0.5f;
    float z = meso_clampf(uvw.z, 0.0f, 1.0f) * (float)(rtv->layers - 1);
    float fx = floorf(x), fy = floorf(y), fz = floorf(z);
    int i0, i1, j0, j1;
    wrap_index((int)fx, rtv->width, &i0, &i1);
    wrap_index((int)fy, rtv->height, &j0, &j1);
    int l0 = (int)fz < rtv->layers - 1 ? (int)fz : rtv->layers - 1;
    int l1 = l0 + 1 < rtv->layers ? l0 + 1 : l0;
    float ax0 = 1.0f - (x - fx), ax1 = x - fx, ay0 = 1.0f - (y - fy), ay1 = y - fy;
    float az0 = 1.0f - (z - fz), az1 = z - fz;
    size_t w = (size_t)rtv->width, plane = (size_t)rtv->height * w;
    size_t c00 = (size_t)j0 * w + (size_t)i0, c10 = (size_t)j0 * w + (size_t)i1;
    size_t c01 = (size_t)j1 * w + (size_t)i0, c11 = (size_t)j1 * w + (size_t)i1;
    size_t lo = (size_t)l0 * plane, hi = (size_t)l1 * plane;
    corner[0] = lo + c00, corner[1] = lo + c10, corner[2] = lo + c01, corner[3] = lo + c11;
    corner[4] = hi + c00, corner[5] = hi + c10, corner[6] = hi + c01, corner[7] = hi + c11;
    float xy00 = ax0 * ay0, xy10 = ax1 * ay0, xy01 = ax0 * ay1, xy11 = ax1 * ay1;
    weight[0] = xy00 * az0, weight[1] = xy10 * az0, weight[2] = xy01 * az0;
    weight[3] = xy11 * az0, weight[4] = xy00 * az1, weight[5] = xy10 * az1;
    weight[6] = xy01 * az1, weight[7] = xy11 * az1;
}

/* A table's coefficients at the surface point nearest q: trilinear over the voxels, periodic in
 * u and v, counting only the corners whose nearest surface point is the same surface (above).
 * Without that test a point on top of a thin feature (a thread lying on another) blends in the
 * voxels inside the feature that answer for its underside, and the top comes out dark along
 * every edge. Where no corner passes, the nearest corner of the same orientation answers, and
 * where none faces the same way, all eight as before. A height field's voxels all answer for
 * the surface point of their column, one surface: every corner counts. */
static void surface_lookup(const rtv_job *rj, const meso_rtv *rtv, const float *table, meso_vec3 q,
                           float out[MESO_SH_COUNT]) {
    const meso_rtv_desc *d = &rj->desc;
    meso_vec3 at, normal;
    surface_at(d, q, &at, &normal);
    size_t voxel[8];
    float weight[8], same[8];
    voxel_corners(rtv, at, voxel, weight);
    int nearest = -1;
    float nearest_distance2 = INFINITY, kept = 0.0f;
    for (int c = 0; c < 8; c++) {
        same[c] = weight[c];
        if (!d->solid) continue;
        meso_vec3 sp = rj->surface_point[voxel[c]];
        float du = periodic_difference(sp.x, at.x) * (float)rtv->width;
        float dv = periodic_difference(sp.y, at.y) * (float)rtv->height;
        float dw = (sp.z - at.z) * (float)(rtv->layers - 1);
        float distance2 = du * du + dv * dv + dw * dw;
        bool facing = meso_vec3_dot(rj->surface_normal[voxel[c]], normal) >= SAME_SURFACE_COSINE;
        if (facing && distance2 < nearest_distance2) nearest = c, nearest_distance2 = distance2;
        if (!facing || distance2 > SAME_SURFACE_VOXELS * SAME_SURFACE_VOXELS) same[c] = 0.0f;
    }
    for (int c = 0; c < 8; c++) kept += same[c];
    if (!(kept > 1e-3f)) { /* either way the weights sum to 1 */
        for (int c = 0; c < 8; c++) same[c] = nearest < 0 ? weight[c] : (float)(c == nearest);
        kept = 1.0f;
    }
    memset(out, 0, MESO_SH_COUNT * sizeof(float));
    for (int c = 0; c < 8; c++) {
        if (same[c] == 0.0f) continue;
        const float *t = table + voxel[c] * MESO_SH_COUNT;
        for (int k = 0; k < MESO_SH_COUNT; k++) out[k] += same[c] / kept * t[k];
    }
}

/* The response at the surface point p with unit normal n (tangent frame): the light arriving
 * unblocked and, with the first pass' table `first`, the light the blocking points reflect. */
static void response_at(const rtv_job *rj, const meso_rtv *rtv, const float *first, meso_vec3 p,
                        meso_vec3 n, float out[MESO_SH_COUNT]) {
    const meso_rtv_desc *d = &rj->desc;
    /* start just off the surface, on its open side; where the field's projection left the
     * point inside (two features in contact), a few more half steps out */
    meso_vec3 out_of_surface = {n.x, n.y, -n.z / d->aspect};
    p = meso_vec3_madd(p, out_of_surface, 0.5f * rj->step);
    for (int k = 0; k < 8 && occupied(d, p); k++)
        p = meso_vec3_madd(p, out_of_surface, 0.5f * rj->step);
    memset(out, 0, MESO_SH_COUNT * sizeof(float));
    for (int k = 0; k < d->directions; k++) {
        meso_vec3 w = rj->direction[k];
        float cosine = meso_vec3_dot(n, w);
        if (cosine <= 0.0f) continue;
        meso_vec3 hit;
        bool open = escapes(rj, p, w, &hit);
        if (!open && !first) continue;
        float scale = rj->direction_weight * cosine * MESO_INV_PI;
        float basis[MESO_SH_COUNT];
        if (open) {
            meso_sh_basis(w, basis);
        } else { /* the light the blocking point reflects */
            surface_lookup(rj, rtv, first, hit, basis);
            scale *= d->albedo;
        }
        for (int m = 0; m < MESO_SH_COUNT; m++) out[m] += scale * basis[m];
    }
}

/* One row of voxels (layer l, row j) per job: disjoint output, any thread count. The first
 * pass also finds each voxel's nearest surface point and normal, which the second pass' and
 * the per-view table's lookups compare. */
static void bake_row(void *user, size_t job, int thread_index) {
    (void)thread_index;
    const pass_job *pj = user;
    const rtv_job *rj = pj->rj;
    const meso_rtv_desc *d = &rj->desc;
    int l = (int)(job / (size_t)d->height), j = (int)(job % (size_t)d->height);
    for (int i = 0; i < d->width; i++) {
        size_t voxel = ((size_t)l * (size_t)d->height + (size_t)j) * (size_t)d->width + (size_t)i;
        if (!rj->first) {
            meso_vec3 c = {((float)i + 0.5f) / (float)d->width,
                           1.0f - ((float)j + 0.5f) / (float)d->height,
                           (float)l / (float)(d->layers - 1)};
            surface_at(d, c, &rj->surface_point[voxel], &rj->surface_normal[voxel]);
        }
        response_at(rj, pj->rtv, rj->first, rj->surface_point[voxel], rj->surface_normal[voxel],
                    rj->out + voxel * MESO_SH_COUNT);
    }
}

/* The unit view direction (tangent frame, toward the viewer) of view (t, p). */
static meso_vec3 view_direction(const meso_rtv *rtv, int t, int p) {
    float theta = ((float)t + 0.5f) * 0.5f * MESO_PI / (float)rtv->num_theta;
    float phi = (float)p * 2.0f * MESO_PI / (float)rtv->num_phi;
    return (meso_vec3){sinf(theta) * cosf(phi), sinf(theta) * sinf(phi), cosf(theta)};
}

typedef struct view_job {
    const rtv_job *rj;
    const meso_rtv *rtv; /* sizes and the nearest-surface table */
    float *raw;          /* [voxel][view][16] */
} view_job;

/* The surface point the view ray through c shows (see bake_rtv.h): followed back out of the
 * solid, or on into it; c itself when neither happens within max_tiles. */
static meso_vec3 seen_point(const rtv_job *rj, meso_vec3 c, meso_vec3 view) {
    const meso_rtv_desc *d = &rj->desc;
    bool inside = occupied(d, c);
    /* inside: toward the viewer (+view); outside: along the ray (-view) */
    float sign = inside ? 1.0f : -1.0f;
    meso_vec3 move = {sign * view.x, sign * view.y, -sign * view.z / d->aspect};
    float step;
    int steps = march_steps(rj, view, move, &step);
    for (int s = 1; s <= steps; s++) {
        meso_vec3 q = meso_vec3_madd(c, move, step * (float)s);
        if (q.z < 0.0f || q.z > 1.0f) break;
        if (occupied(d, q) != inside) return q;
    }
    return c;
}

static void view_row(void *user, size_t job, int thread_index) {
    (void)thread_index;
    const view_job *vj = user;
    const meso_rtv *rtv = vj->rtv;
    int l = (int)(job / (size_t)rtv->height), j = (int)(job % (size_t)rtv->height);
    int views = rtv->num_theta * rtv->num_phi;
    for (int i = 0; i < rtv->width; i++) {
        meso_vec3 c = {((float)i + 0.5f) / (float)rtv->width,
                       1.0f - ((float)j + 0.5f) / (float)rtv->height,
                       (float)l / (float)(rtv->layers - 1)};
        size_t voxel =
            ((size_t)l * (size_t)rtv->height + (size_t)j) * (size_t)rtv->width + (size_t)i;
        for (int t = 0; t < rtv->num_theta; t++)
            for (int p = 0; p < rtv->num_phi; p++) {
                meso_vec3 q = seen_point(vj->rj, c, view_direction(rtv, t, p));
                surface_lookup(vj->rj, rtv, rtv->coefficients, q,
                               vj->raw + (voxel * (size_t)views + (size_t)(t * rtv->num_phi + p)) *
                                             MESO_SH_COUNT);
            }
    }
}

typedef struct svd_source {
    const float *raw;
    int views, coefficient;
} svd_source;

/* Rows of coefficient i's table: raw[voxel][view][i]. */
static void fill_rows(void *user, size_t first, size_t count, float *out) {
    const svd_source *src = user;
    for (size_t r = 0; r < count; r++)
        for (int v = 0; v < src->views; v++)
            out[r * (size_t)src->views + (size_t)v] =
                src->raw[((first + r) * (size_t)src->views + (size_t)v) * MESO_SH_COUNT +
                         (size_t)src->coefficient];
}

/* The per-view table and its SVD, coefficient by coefficient (§4.1); fills weights, eigen,
 * rmse and the sizes. */
static meso_result compress(meso_context *ctx, const rtv_job *rj, meso_rtv *rtv) {
    int views = rtv->num_theta * rtv->num_phi, k = rtv->num_eigen;
    size_t voxels = (size_t)rtv->width * (size_t)rtv->height * (size_t)rtv->layers;
    float *raw = malloc(voxels * (size_t)views * MESO_SH_COUNT * sizeof(float));
    float *singular = malloc((size_t)views * sizeof(float));
    float *vectors = malloc((size_t)views * (size_t)views * sizeof(float));
    rtv->weights = malloc((size_t)MESO_SH_COUNT * voxels * (size_t)k * sizeof(float));
    rtv->eigen = malloc((size_t)MESO_SH_COUNT * (size_t)k * (size_t)views * sizeof(float));
    meso_result r = MESO_OK;
    if (!raw || !singular || !vectors || !rtv->weights || !rtv->eigen) {
        r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "rtv: %zu voxels x %d views", voxels,
                           views);
        goto done;
    }
    view_job vj = {rj, rtv, raw};
    meso_parallel_for(ctx, (size_t)rtv->layers * (size_t)rtv->height, view_row, &vj);
    double tail[MESO_RTV_RMSE_COUNT] = {0}; /* sum over coefficients of s_j^2, j >= k */
    for (int i = 0; i < MESO_SH_COUNT && r == MESO_OK; i++) {
        svd_source src = {raw, views, i};
        meso_bake_rows rows = {.rows = voxels, .columns = views, .fill = fill_rows, .user = &src};
        r = meso_bake_svd_streamed(ctx, "rtv", &rows, k, singular, vectors,
                                   rtv->weights + (size_t)i * voxels * (size_t)k, NULL);
        if (r != MESO_OK) break;
        for (int e = 0; e < k; e++)
            for (int v = 0; v < views; v++)
                rtv->eigen[((size_t)i * (size_t)k + (size_t)e) * (size_t)views + (size_t)v] =
                    vectors[(size_t)v * (size_t)views + (size_t)e];
        for (int kept = 1; kept <= MESO_RTV_RMSE_COUNT; kept++)
            for (int j = kept; j < views; j++) tail[kept - 1] += (double)singular[j] * singular[j];
    }
    double entries = (double)MESO_SH_COUNT * (double)voxels * (double)views;
    for (int e = 0; e < MESO_RTV_RMSE_COUNT; e++) rtv->rmse[e] = (float)sqrt(tail[e] / entries);
    rtv->raw_bytes = (uint64_t)entries * sizeof(float);
    rtv->compressed_bytes = (uint64_t)MESO_SH_COUNT * ((uint64_t)voxels + (uint64_t)views) *
                            (uint64_t)k * sizeof(float);
done:
    free(vectors);
    free(singular);
    free(raw);
    return r;
}

meso_result meso_rtv_bake(meso_context *ctx, const meso_rtv_desc *desc, meso_rtv **out_rtv) {
    *out_rtv = NULL;
    meso_rtv_desc d = desc ? *desc : (meso_rtv_desc){0};
    if (!d.width) d.width = 32;
    if (!d.height) d.height = 32;
    if (!d.layers) d.layers = 8;
    if (!d.directions) d.directions = 256;
    if (d.albedo == 0.0f) d.albedo = 0.7f;
    if (d.max_tiles == 0.0f) d.max_tiles = 2.0f;
    if (!d.num_theta) d.num_theta = 4;
    if (!d.num_phi) d.num_phi = 8;
    if (!d.eigen) d.eigen = 4;
    if (!d.heightfield == !d.solid)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "rtv: needs exactly one of a height field and a solid");
    if (!(d.aspect > 0.0f && d.aspect <= 100.0f))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "rtv: aspect: %g is not in (0, 100]", (double)d.aspect);
    if (d.width < 1 || d.height < 1 || d.layers < 2 || d.width > 4096 || d.height > 4096 ||
        d.layers > 4096)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "rtv: %d x %d x %d voxels: each side in [1, 4096], layers >= 2",
                              d.width, d.height, d.layers);
    if (d.directions < 16 || d.directions > 65536)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "rtv: directions: %d is not in [16, 65536]", d.directions);
    if (d.num_theta < 1 || d.num_phi < 1 || d.num_theta * d.num_phi > 4096 || d.eigen < 1 ||
        d.eigen > d.num_theta * d.num_phi)
        return meso_log_error(
            ctx, MESO_ERROR_INVALID_ARGUMENT,
            "rtv: %d x %d views (at most 4096) with %d eigenfunctions (1 .. views)", d.num_theta,
            d.num_phi, d.eigen);
    if (!(d.albedo <= 1.0f) || !(d.max_tiles > 0.0f && d.max_tiles <= 64.0f))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "rtv: albedo must be at most 1 and max_tiles in (0, 64]");
    uint64_t voxels = (uint64_t)d.width * (uint64_t)d.height * (uint64_t)d.layers;
    if (voxels > MESO_RTV_MAX_VOXELS)
        return meso_log_error(ctx, MESO_ERROR_LIMIT, "rtv: %llu voxels exceed the limit of %llu",
                              (unsigned long long)voxels, (unsigned long long)MESO_RTV_MAX_VOXELS);
    bool bounce = d.albedo > 0.0f;
    uint64_t views = (uint64_t)d.num_theta * (uint64_t)d.num_phi;
    meso_result r = meso_memory_check(
        ctx, "rtv",
        voxels * (MESO_SH_COUNT * sizeof(float) * ((bounce ? 2u : 1u) + views + d.eigen) +
                  2 * sizeof(meso_vec3)));
    if (r != MESO_OK) return r;
    double start = meso_time_seconds();
    meso_rtv *rtv = calloc(1, sizeof *rtv);
    float *first = NULL;
    meso_vec3 *direction = malloc((size_t)d.directions * sizeof *direction);
    meso_vec3 *surface_point = malloc((size_t)voxels * sizeof *surface_point);
    meso_vec3 *surface_normal = malloc((size_t)voxels * sizeof *surface_normal);
    if (rtv) rtv->coefficients = malloc((size_t)voxels * MESO_SH_COUNT * sizeof(float));
    if (bounce) first = malloc((size_t)voxels * MESO_SH_COUNT * sizeof(float));
    if (!rtv || !rtv->coefficients || !direction || !surface_point || !surface_normal ||
        (bounce && !first)) {
        free(first);
        free(direction);
        free(surface_point);
        free(surface_normal);
        meso_rtv_destroy(rtv);
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "rtv: %llu voxels",
                              (unsigned long long)voxels);
    }
    rtv->width = d.width, rtv->height = d.height, rtv->layers = d.layers;
    rtv->num_theta = d.num_theta, rtv->num_phi = d.num_phi, rtv->num_eigen = d.eigen;
    for (int k = 0; k < d.directions; k++) {
        double z = 1.0 - (2.0 * k + 1.0) / d.directions, s = sqrt(fmax(0.0, 1.0 - z * z));
        double phi = 2.399963229728653 * k;
        direction[k] = (meso_vec3){(float)(s * cos(phi)), (float)(s * sin(phi)), (float)z};
    }
    /* march steps of half a texel of the source (solids: of a 256 grid) */
    int texels = d.heightfield
                     ? (d.heightfield->width > d.heightfield->height ? d.heightfield->width
                                                                     : d.heightfield->height)
                     : 256;
    rtv_job rj = {d,
                  direction,
                  (float)(4.0 * MESO_PI_D / d.directions),
                  0.5f / (float)texels,
                  NULL,
                  bounce ? first : rtv->coefficients,
                  surface_point,
                  surface_normal};
    pass_job pj = {&rj, rtv};
    size_t rows = (size_t)d.layers * (size_t)d.height;
    meso_parallel_for(ctx, rows, bake_row, &pj);
    if (bounce) {
        rj.first = first;
        rj.out = rtv->coefficients;
        meso_parallel_for(ctx, rows, bake_row, &pj);
    }
    free(first);
    r = compress(ctx, &rj, rtv);
    free(direction);
    free(surface_point);
    free(surface_normal);
    if (r != MESO_OK) {
        meso_rtv_destroy(rtv);
        return r;
    }
    rtv->bake_seconds = meso_time_seconds() - start;
    *out_rtv = rtv;
    return MESO_OK;
}

void meso_rtv_destroy(meso_rtv *rtv) {
    if (!rtv) return;
    free(rtv->coefficients);
    free(rtv->weights);
    free(rtv->eigen);
    free(rtv);
}

/* ---- Evaluation --------------------------------------------------------------------------- */

void meso_rtv_cell_at(const meso_rtv *rtv, meso_vec3 uvw, meso_vec3 view, meso_rtv_cell *out) {
    voxel_corners(rtv, uvw, out->corner, out->corner_weight);
    float theta = acosf(meso_clampf(view.z, 0.0f, 1.0f));
    float t = meso_clampf(theta / (0.5f * MESO_PI) * (float)rtv->num_theta - 0.5f, 0.0f,
                          (float)(rtv->num_theta - 1));
    float phi = atan2f(view.y, view.x);
    float p = (phi < 0.0f ? phi + 2.0f * MESO_PI : phi) / (2.0f * MESO_PI) * (float)rtv->num_phi;
    int t0 = (int)t, t1 = t0 + 1 < rtv->num_theta ? t0 + 1 : t0;
    /* (int)p % num_phi and the next without divisions: p lies in [0, num_phi] (num_phi where
     * phi + 2 pi rounds to 2 pi); a NaN's conversion takes the division as before */
    int ip = (int)p, n = rtv->num_phi;
    int p0 = ip >= 0 && ip < n ? ip : (ip == n ? 0 : ip % n);
    int p1 = p0 + 1 < n ? p0 + 1 : (p0 + 1) % n;
    float tt = t - (float)t0, tp = p - floorf(p);
    out->view_index[0] = t0 * rtv->num_phi + p0, out->view_index[1] = t0 * rtv->num_phi + p1;
    out->view_index[2] = t1 * rtv->num_phi + p0, out->view_index[3] = t1 * rtv->num_phi + p1;
    out->view_weight[0] = (1 - tt) * (1 - tp), out->view_weight[1] = (1 - tt) * tp;
    out->view_weight[2] = tt * (1 - tp), out->view_weight[3] = tt * tp;
}

void meso_rtv_evaluate(const meso_rtv *rtv, meso_vec3 uvw, meso_vec3 view,
                       const float radiance[3][MESO_SH_COUNT], float out_rgb[3]) {
    int k = rtv->num_eigen, views = rtv->num_theta * rtv->num_phi;
    size_t voxels = (size_t)rtv->width * (size_t)rtv->height * (size_t)rtv->layers;
    meso_rtv_cell cell;
    meso_rtv_cell_at(rtv, uvw, view, &cell);
    const size_t *corner = cell.corner;
    const float *corner_weight = cell.corner_weight, *view_weight = cell.view_weight;
    const int *view_index = cell.view_index;
    out_rgb[0] = out_rgb[1] = out_rgb[2] = 0.0f;
    for (int i = 0; i < MESO_SH_COUNT; i++) {
        float f = 0.0f;
        for (int e = 0; e < k; e++) {
            const float *w = rtv->weights + (size_t)i * voxels * (size_t)k;
            float weight = 0.0f;
            for (int c = 0; c < 8; c++)
                weight += corner_weight[c] * w[corner[c] * (size_t)k + (size_t)e];
            const float *eig = rtv->eigen + ((size_t)i * (size_t)k + (size_t)e) * (size_t)views;
            float value = 0.0f;
            for (int v = 0; v < 4; v++) value += view_weight[v] * eig[view_index[v]];
            f += weight * value;
        }
        for (int c = 0; c < 3; c++) out_rgb[c] += f * radiance[c][i];
    }
    for (int c = 0; c < 3; c++) out_rgb[c] = out_rgb[c] > 0.0f ? out_rgb[c] : 0.0f;
}

/* ---- Files -------------------------------------------------------------------------------- */

/* The bake file of an RTV; it borrows the RTV's arrays and `shape` (5 values). */
static meso_bake_file to_bake_file(const meso_rtv *rtv, int32_t shape[5]) {
    uint64_t voxels = (uint64_t)rtv->width * (uint64_t)rtv->height * (uint64_t)rtv->layers;
    uint64_t views = (uint64_t)rtv->num_theta * (uint64_t)rtv->num_phi;
    shape[0] = rtv->width, shape[1] = rtv->height, shape[2] = rtv->layers;
    shape[3] = rtv->num_theta, shape[4] = rtv->num_phi;
    meso_bake_file bake = {.kind = MESO_RTV_KIND,
                           .kind_version = MESO_RTV_KIND_VERSION,
                           .params_json = "{}",
                           .num_arrays = 4};
    bake.arrays[0] = (meso_bake_array){
        .name = "shape", .type = MESO_BAKE_I32, .num_dims = 1, .dims = {5}, .data = shape};
    bake.arrays[1] = (meso_bake_array){.name = "weights",
                                       .type = MESO_BAKE_F32,
                                       .num_dims = 3,
                                       .dims = {MESO_SH_COUNT, voxels, (uint64_t)rtv->num_eigen},
                                       .data = rtv->weights};
    bake.arrays[2] = (meso_bake_array){.name = "eigen",
                                       .type = MESO_BAKE_F32,
                                       .num_dims = 3,
                                       .dims = {MESO_SH_COUNT, (uint64_t)rtv->num_eigen, views},
                                       .data = rtv->eigen};
    bake.arrays[3] = (meso_bake_array){.name = "rmse",
                                       .type = MESO_BAKE_F32,
                                       .num_dims = 1,
                                       .dims = {MESO_RTV_RMSE_COUNT},
                                       .data = (void *)rtv->rmse};
    return bake;
}

meso_result meso_rtv_save(meso_context *ctx, const meso_rtv *rtv, const char *path) {
    int32_t shape[5];
    meso_bake_file bake = to_bake_file(rtv, shape);
    return meso_bake_file_save(ctx, &bake, path);
}

/* The array `name` with `type` and `num_dims`, or NULL after logging what is wrong. */
static const meso_bake_array *expect_array(meso_context *ctx, const meso_bake_file *bake,
                                           const char *path, const char *name, meso_bake_type type,
                                           int num_dims) {
    const meso_bake_array *a = meso_bake_file_find(bake, name);
    if (!a || a->type != type || a->num_dims != num_dims) {
        meso_log_error(ctx, MESO_ERROR_FORMAT,
                       "%s: rtv: array \"%s\" is missing or not %d-D of "
                       "the right type",
                       path, name, num_dims);
        return NULL;
    }
    return a;
}

meso_result meso_rtv_from_bake_file(meso_context *ctx, const meso_bake_file *bake, const char *path,
                                    meso_rtv **out_rtv) {
    *out_rtv = NULL;
    meso_result r = MESO_OK;
    meso_rtv *rtv = NULL;
    /* version 1 files hold the same arrays (baked before the same-surface lookup) */
    if (strcmp(bake->kind, MESO_RTV_KIND) != 0 || bake->kind_version < 1 ||
        bake->kind_version > MESO_RTV_KIND_VERSION) {
        r = meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: not an rtv bake (kind \"%s\" version %u)",
                           path, bake->kind, (unsigned)bake->kind_version);
        goto done;
    }
    const meso_bake_array *shape = expect_array(ctx, bake, path, "shape", MESO_BAKE_I32, 1);
    const meso_bake_array *weights = expect_array(ctx, bake, path, "weights", MESO_BAKE_F32, 3);
    const meso_bake_array *eigen = expect_array(ctx, bake, path, "eigen", MESO_BAKE_F32, 3);
    const meso_bake_array *rmse = expect_array(ctx, bake, path, "rmse", MESO_BAKE_F32, 1);
    if (!shape || !weights || !eigen || !rmse) {
        r = MESO_ERROR_FORMAT;
        goto done;
    }
    const int32_t *s = shape->data;
    uint64_t voxels = 0, views = 0;
    bool sizes = shape->dims[0] == 5 && rmse->dims[0] == MESO_RTV_RMSE_COUNT;
    for (int k = 0; sizes && k < 5; k++) sizes = s[k] >= 1 && s[k] <= 4096;
    if (sizes) {
        voxels = (uint64_t)s[0] * (uint64_t)s[1] * (uint64_t)s[2];
        views = (uint64_t)s[3] * (uint64_t)s[4];
        sizes = s[2] >= 2 && voxels <= MESO_RTV_MAX_VOXELS && views <= 4096 &&
                weights->dims[0] == MESO_SH_COUNT && weights->dims[1] == voxels &&
                weights->dims[2] >= 1 && weights->dims[2] <= views &&
                eigen->dims[0] == MESO_SH_COUNT && eigen->dims[1] == weights->dims[2] &&
                eigen->dims[2] == views;
    }
    if (!sizes) {
        r = meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: rtv: the arrays' sizes do not agree", path);
        goto done;
    }
    if ((r = meso_bake_array_check_values(ctx, path, weights, -1e6, 1e6)) ||
        (r = meso_bake_array_check_values(ctx, path, eigen, -1e6, 1e6)) ||
        (r = meso_bake_array_check_values(ctx, path, rmse, 0.0, 1e6)))
        goto done;
    rtv = calloc(1, sizeof *rtv);
    size_t weight_bytes = (size_t)meso_bake_array_count(weights) * sizeof(float);
    size_t eigen_bytes = (size_t)meso_bake_array_count(eigen) * sizeof(float);
    if (rtv) rtv->weights = malloc(weight_bytes), rtv->eigen = malloc(eigen_bytes);
    if (!rtv || !rtv->weights || !rtv->eigen) {
        r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", path);
        goto done;
    }
    memcpy(rtv->weights, weights->data, weight_bytes);
    memcpy(rtv->eigen, eigen->data, eigen_bytes);
    memcpy(rtv->rmse, rmse->data, sizeof rtv->rmse);
    rtv->width = s[0], rtv->height = s[1], rtv->layers = s[2];
    rtv->num_theta = s[3], rtv->num_phi = s[4], rtv->num_eigen = (int)weights->dims[2];
    rtv->raw_bytes = (uint64_t)MESO_SH_COUNT * voxels * views * sizeof(float);
    rtv->compressed_bytes = (uint64_t)(weight_bytes + eigen_bytes);
    *out_rtv = rtv;
    rtv = NULL;
done:
    meso_rtv_destroy(rtv);
    return r;
}

/* The cache key: the source's hash and every field that changes the table. */
static uint64_t cache_key(const meso_rtv_desc *d, uint64_t source_hash) {
    float fields[6] = {d->aspect,        (float)d->width,      (float)d->height,
                       (float)d->layers, (float)d->directions, d->albedo};
    float more[4] = {d->max_tiles, (float)d->num_theta, (float)d->num_phi, (float)d->eigen};
    uint64_t key = meso_hash64(&source_hash, sizeof source_hash, MESO_HASH_SEED);
    key = meso_hash64(fields, sizeof fields, key);
    return meso_hash64(more, sizeof more, key);
}

/* The steps of meso_bake_cache_run for an rtv; desc: the caller's meso_rtv_desc. */
static meso_result rtv_from_file(meso_context *ctx, const meso_bake_file *bake, const char *where,
                                 const void *desc, void *out) {
    (void)desc;
    return meso_rtv_from_bake_file(ctx, bake, where, out);
}

static meso_result rtv_bake(meso_context *ctx, const void *desc, void *out) {
    return meso_rtv_bake(ctx, desc, out);
}

static meso_result rtv_store(meso_context *ctx, const meso_cached_bake *entry, const void *out) {
    int32_t shape[5];
    meso_bake_file bake = to_bake_file(*(meso_rtv *const *)out, shape);
    bake.source_hash = entry->source_hash;
    return meso_bake_cache_save(ctx, &bake, entry->key);
}

meso_result meso_rtv_load(meso_context *ctx, const char *path, meso_rtv **out_rtv) {
    *out_rtv = NULL;
    return meso_bake_load_with(ctx, path, rtv_from_file, NULL, out_rtv);
}

meso_result meso_rtv_bake_cached(meso_context *ctx, const meso_rtv_desc *desc, meso_rtv **out_rtv) {
    *out_rtv = NULL;
    meso_rtv_desc d = desc ? *desc : (meso_rtv_desc){0};
    uint64_t source = d.heightfield ? d.heightfield->hash : d.solid ? meso_solid_hash(d.solid) : 0;
    meso_cached_bake entry = {MESO_RTV_KIND, MESO_RTV_KIND_VERSION,
                              "rtv",         cache_key(&d, source),
                              source,        &d,
                              rtv_from_file, rtv_bake,
                              rtv_store};
    return meso_bake_cache_run(ctx, &entry, out_rtv);
}

size_t meso_rtv_describe(const meso_bake_file *bake, char *buffer, size_t size) {
    if (!bake || strcmp(bake->kind, MESO_RTV_KIND) != 0) return 0;
    const meso_bake_array *shape = meso_bake_file_find(bake, "shape");
    const meso_bake_array *weights = meso_bake_file_find(bake, "weights");
    const meso_bake_array *rmse = meso_bake_file_find(bake, "rmse");
    const meso_bake_array *eigen = meso_bake_file_find(bake, "eigen");
    if (!shape || shape->type != MESO_BAKE_I32 || shape->num_dims != 1 || shape->dims[0] != 5 ||
        !rmse || rmse->type != MESO_BAKE_F32 || rmse->num_dims != 1 ||
        rmse->dims[0] != MESO_RTV_RMSE_COUNT || !weights || weights->num_dims != 3 || !eigen ||
        eigen->num_dims != 3)
        return 0;
    const int32_t *s = shape->data;
    const float *e = rmse->data;
    uint64_t voxels = weights->dims[1], views = eigen->dims[2];
    double raw = (double)MESO_SH_COUNT * (double)voxels * (double)views * 4.0;
    double compressed =
        4.0 * (double)(meso_bake_array_count(weights) + meso_bake_array_count(eigen));
    int n = snprintf(buffer, size,
                     "rtv: %dx%dx%d voxels, %dx%d views, %llu eigenfunctions a coefficient; raw "
                     "%.2f MB, compressed %.2f MB\nRMSE with k eigenfunctions, k = 1..16:",
                     s[0], s[1], s[2], s[3], s[4], (unsigned long long)weights->dims[2], raw / 1e6,
                     compressed / 1e6);
    for (int k = 0; k < MESO_RTV_RMSE_COUNT && n >= 0; k++) {
        int m = snprintf(buffer && (size_t)n < size ? buffer + n : NULL,
                         buffer && (size_t)n < size ? size - (size_t)n : 0, " %.4g", (double)e[k]);
        n = m < 0 ? m : n + m;
    }
    if (n >= 0) {
        int m = snprintf(buffer && (size_t)n < size ? buffer + n : NULL,
                         buffer && (size_t)n < size ? size - (size_t)n : 0, "\n");
        n = m < 0 ? m : n + m;
    }
    return n > 0 ? (size_t)n : 0;
}
