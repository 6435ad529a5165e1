/* The radiance transfer volume, uncompressed and view-independent (include/meso/bake_rtv.h;
 * GDM paper §3.2). Two passes over the voxels: direct transfer with the mesostructure's
 * shadowing, then one bounce gathered from the first pass where rays meet the mesostructure. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake_internal.h"
#include "meso/bake_rtv.h"

typedef struct rtv_job {
    meso_rtv_desc desc;
    const meso_vec3 *direction; /* the fixed directions, tangent frame (z up) */
    float direction_weight;     /* 4 pi / directions */
    float step;                 /* march step, world units (a tile is 1) */
    const float *first;         /* the first pass (second pass only) */
    float *out;
} rtv_job;

/* Texture space (u, v, w) to world-like space: a tile 1 wide, the shell `aspect` deep, z up. A
 * unit world direction d moves (u, v, w) by (d.x, d.y, -d.z / aspect). */
static bool occupied(const meso_rtv_desc *d, meso_vec3 uvw) {
    if (uvw.z >= 1.0f) return true; /* below the shell's bottom: solid */
    if (d->heightfield) return uvw.z >= 1.0f - meso_heightfield_sample(d->heightfield, uvw.x, uvw.y);
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

/* March from p along the world direction w; true when it escapes (leaves through the top or
 * travels max_tiles), else *out_hit is the first occupied point. */
static bool escapes(const rtv_job *rj, meso_vec3 p, meso_vec3 w, meso_vec3 *out_hit) {
    const meso_rtv_desc *d = &rj->desc;
    meso_vec3 move = {w.x, w.y, -w.z / d->aspect};
    /* no step crosses more than an eighth of a layer of the shell */
    float step = rj->step;
    if (fabsf(move.z) * step > 0.125f / (float)d->layers) step = 0.125f / (float)d->layers / fabsf(move.z);
    float horizontal = sqrtf(w.x * w.x + w.y * w.y);
    int steps = horizontal > 0.0f ? (int)ceilf(d->max_tiles / (horizontal * step)) : 1 << 20;
    if (steps > 1 << 20) steps = 1 << 20;
    for (int s = 1; s <= steps; s++) {
        meso_vec3 q = meso_vec3_madd(p, move, step * (float)s);
        if (q.z < 0.0f) return true;
        if (occupied(d, q)) {
            *out_hit = q;
            return false;
        }
    }
    return true;
}

/* The first pass's coefficients at (u, v, w): trilinear, periodic in u and v. */
static void lookup(const meso_rtv *rtv, const float *table, meso_vec3 uvw, float out[MESO_SH_COUNT]) {
    float x = (uvw.x - floorf(uvw.x)) * (float)rtv->width - 0.5f;
    float v = uvw.y - floorf(uvw.y);
    float y = (1.0f - v) * (float)rtv->height - 0.5f;
    float z = meso_clampf(uvw.z, 0.0f, 1.0f) * (float)(rtv->layers - 1);
    float fx = floorf(x), fy = floorf(y), fz = floorf(z);
    float tx = x - fx, ty = y - fy, tz = z - fz;
    int i0 = ((int)fx % rtv->width + rtv->width) % rtv->width, i1 = (i0 + 1) % rtv->width;
    int j0 = ((int)fy % rtv->height + rtv->height) % rtv->height, j1 = (j0 + 1) % rtv->height;
    int l0 = (int)fz, l1 = l0 + 1 < rtv->layers ? l0 + 1 : l0;
    memset(out, 0, MESO_SH_COUNT * sizeof(float));
    const int is[2] = {i0, i1}, js[2] = {j0, j1}, ls[2] = {l0, l1};
    const float wx[2] = {1.0f - tx, tx}, wy[2] = {1.0f - ty, ty}, wz[2] = {1.0f - tz, tz};
    for (int a = 0; a < 2; a++)
        for (int b = 0; b < 2; b++)
            for (int c = 0; c < 2; c++) {
                float weight = wx[a] * wy[b] * wz[c];
                const float *t = table + (((size_t)ls[c] * (size_t)rtv->height + (size_t)js[b]) *
                                              (size_t)rtv->width + (size_t)is[a]) * MESO_SH_COUNT;
                for (int k = 0; k < MESO_SH_COUNT; k++) out[k] += weight * t[k];
            }
}

typedef struct pass_job {
    const rtv_job *rj;
    const meso_rtv *rtv; /* its size; the first pass' table in rj->first */
} pass_job;

/* One row of voxels (layer l, row j) per job: disjoint output, any thread count. */
static void bake_row(void *user, size_t job, int thread_index) {
    (void)thread_index;
    const pass_job *pj = user;
    const rtv_job *rj = pj->rj;
    const meso_rtv_desc *d = &rj->desc;
    int l = (int)(job / (size_t)d->height), j = (int)(job % (size_t)d->height);
    for (int i = 0; i < d->width; i++) {
        meso_vec3 c = {((float)i + 0.5f) / (float)d->width, 1.0f - ((float)j + 0.5f) / (float)d->height,
                       (float)l / (float)(d->layers - 1)};
        meso_vec3 p, n;
        surface_at(d, c, &p, &n);
        /* start just off the surface, on its open side */
        p = meso_vec3_madd(p, (meso_vec3){n.x, n.y, -n.z / d->aspect}, 0.5f * rj->step);
        float *out = rj->out + (((size_t)l * (size_t)d->height + (size_t)j) * (size_t)d->width +
                                (size_t)i) * MESO_SH_COUNT;
        memset(out, 0, MESO_SH_COUNT * sizeof(float));
        for (int k = 0; k < d->directions; k++) {
            meso_vec3 w = rj->direction[k];
            float cosine = meso_vec3_dot(n, w);
            if (cosine <= 0.0f) continue;
            meso_vec3 hit;
            bool open = escapes(rj, p, w, &hit);
            float scale = rj->direction_weight * cosine * (float)M_1_PI;
            float basis[MESO_SH_COUNT];
            if (!rj->first) { /* first pass: light arriving unblocked */
                if (!open) continue;
                meso_sh_basis(w, basis);
                for (int m = 0; m < MESO_SH_COUNT; m++) out[m] += scale * basis[m];
            } else if (open) { /* second pass: the first pass' direct part again */
                meso_sh_basis(w, basis);
                for (int m = 0; m < MESO_SH_COUNT; m++) out[m] += scale * basis[m];
            } else { /* ... plus the light the blocking point reflects */
                lookup(pj->rtv, rj->first, hit, basis);
                for (int m = 0; m < MESO_SH_COUNT; m++) out[m] += scale * d->albedo * basis[m];
            }
        }
    }
}

meso_result meso_bake_rtv(meso_context *ctx, const meso_rtv_desc *desc, meso_rtv **out_rtv) {
    *out_rtv = NULL;
    meso_rtv_desc d = desc ? *desc : (meso_rtv_desc){0};
    if (!d.width) d.width = 32;
    if (!d.height) d.height = 32;
    if (!d.layers) d.layers = 8;
    if (!d.directions) d.directions = 256;
    if (d.albedo == 0.0f) d.albedo = 0.7f;
    if (d.max_tiles == 0.0f) d.max_tiles = 2.0f;
    if (!d.heightfield == !d.solid)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "rtv: needs exactly one of a height field and a solid");
    if (!(d.aspect > 0.0f && d.aspect <= 100.0f))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "rtv: aspect: %g is not in (0, 100]",
                              (double)d.aspect);
    if (d.width < 1 || d.height < 1 || d.layers < 2 || d.width > 4096 || d.height > 4096 ||
        d.layers > 4096)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "rtv: %d x %d x %d voxels: each side in [1, 4096], layers >= 2",
                              d.width, d.height, d.layers);
    if (d.directions < 16 || d.directions > 65536)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "rtv: directions: %d is not in [16, 65536]", d.directions);
    if (!(d.albedo <= 1.0f) || !(d.max_tiles > 0.0f && d.max_tiles <= 64.0f))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "rtv: albedo must be at most 1 and max_tiles in (0, 64]");
    uint64_t voxels = (uint64_t)d.width * (uint64_t)d.height * (uint64_t)d.layers;
    if (voxels > MESO_RTV_MAX_VOXELS)
        return meso_log_error(ctx, MESO_ERROR_LIMIT, "rtv: %llu voxels exceed the limit of %llu",
                              (unsigned long long)voxels, (unsigned long long)MESO_RTV_MAX_VOXELS);
    bool bounce = d.albedo > 0.0f;
    meso_result r = meso_memory_check(ctx, "rtv", voxels * MESO_SH_COUNT * sizeof(float) *
                                                      (bounce ? 2u : 1u));
    if (r != MESO_OK) return r;
    double start = meso_time_seconds();
    meso_rtv *rtv = calloc(1, sizeof *rtv);
    float *first = NULL;
    meso_vec3 *direction = malloc((size_t)d.directions * sizeof *direction);
    if (rtv) rtv->coefficients = malloc((size_t)voxels * MESO_SH_COUNT * sizeof(float));
    if (bounce) first = malloc((size_t)voxels * MESO_SH_COUNT * sizeof(float));
    if (!rtv || !rtv->coefficients || !direction || (bounce && !first)) {
        free(first);
        free(direction);
        meso_rtv_destroy(rtv);
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "rtv: %llu voxels",
                              (unsigned long long)voxels);
    }
    rtv->width = d.width, rtv->height = d.height, rtv->layers = d.layers;
    for (int k = 0; k < d.directions; k++) {
        double z = 1.0 - (2.0 * k + 1.0) / d.directions, s = sqrt(fmax(0.0, 1.0 - z * z));
        double phi = 2.399963229728653 * k;
        direction[k] = (meso_vec3){(float)(s * cos(phi)), (float)(s * sin(phi)), (float)z};
    }
    /* march steps of half a texel of the source (solids: of a 256 grid) */
    int texels = d.heightfield ? (d.heightfield->width > d.heightfield->height ? d.heightfield->width
                                                                              : d.heightfield->height)
                               : 256;
    rtv_job rj = {d, direction, (float)(4.0 * M_PI / d.directions), 0.5f / (float)texels, NULL,
                  bounce ? first : rtv->coefficients};
    pass_job pj = {&rj, rtv};
    size_t rows = (size_t)d.layers * (size_t)d.height;
    meso_parallel_for(ctx, rows, bake_row, &pj);
    if (bounce) {
        rj.first = first;
        rj.out = rtv->coefficients;
        meso_parallel_for(ctx, rows, bake_row, &pj);
    }
    free(first);
    free(direction);
    rtv->bake_seconds = meso_time_seconds() - start;
    *out_rtv = rtv;
    return MESO_OK;
}

void meso_rtv_destroy(meso_rtv *rtv) {
    if (!rtv) return;
    free(rtv->coefficients);
    free(rtv);
}

void meso_rtv_evaluate(const meso_rtv *rtv, meso_vec3 uvw, const float radiance[3][MESO_SH_COUNT],
                       float out_rgb[3]) {
    float t[MESO_SH_COUNT];
    lookup(rtv, rtv->coefficients, uvw, t);
    for (int c = 0; c < 3; c++) {
        float sum = 0.0f;
        for (int k = 0; k < MESO_SH_COUNT; k++) sum += t[k] * radiance[c][k];
        out_rgb[c] = sum > 0.0f ? sum : 0.0f;
    }
}
