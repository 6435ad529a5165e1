/* vdm: view-dependent displacement mapping (Wang et al. 2003, §3.2 and Fig. 6): per fragment
 * the view direction in the local frame and the curvature along it select the baked distance
 * d(x, y, theta, phi, c) to the mesostructure; no intersection -> discard (silhouette); the
 * real texture coordinate T' = T - d V_xy; shadows by a second lookup along the light (flat
 * surface approximation, §3.2); shading at T' with the height field's normal.
 * The map is baked (src/bake/bake_vdm.c) and cached. docs/techniques/vdm.md. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#if defined(__F16C__)
#include <immintrin.h>
#endif

#include "meso/bake_vdm.h"
#include "meso/bake_vdm_lanes.h"
#include "meso/runtime.h"
#include "render_internal.h"
#include "render_simd.h"

#define MAX_LEVELS MESO_VDM_MAX_LEVELS

typedef struct vdm_state {
    meso_vdm *vdm;
    meso_vdm_view view;
    bool raw; /* "compressed" 0: the 5D table itself */
    bool shadows, silhouettes, curvature;
    bool nearest_silhouette; /* theta_MVM of the nearest texel (§3.2) or interpolated */
    int num_eigen;           /* k used at render time (<= the bake's) */
    int num_mvm;
    int refine_steps;  /* 0: the paper's interpolated d; else refine_hit with this many steps */
    int shadow_steps;  /* blocked_before's probes where the light's corners disagree */
    float depth_tiles; /* shell depth in tiles (the bake's "depth") */
    float tile_world;  /* world length of one tile: curvature and offsets */
    float shadow_bias; /* shell depths */
    bool clamp;
    /* The compressed data re-laid for 8-wide loads (§3.3 reconstruction as dot products,
     * meso_vdm_lanes): eigen_t [column][lanes] (E_VDM transposed, zero past k),
     * mvm_t [c][lanes] (E_MVM transposed, zero past m); lanes = max(k, m) rounded up to 8. */
    int lanes;
    float *eigen_t, *mvm_t;
    /* §4: "VDM as a texture map is easily anti-aliased by mip-mapping": d = sum W E is linear
     * in W, so box-filtering W over (x, y) filters the reconstructed table exactly. Level 0 is
     * W itself; the others are used when minified (and far less memory traffic: speed on busy
     * textures). */
    bool mipmap;
    int num_levels;
    int level_width[MAX_LEVELS], level_height[MAX_LEVELS];
    uint16_t *level_weights[MAX_LEVELS]; /* half floats: half the memory traffic */
} vdm_state;

#define MAX_CHUNKS (MESO_VDM_MAX_EIGEN / 8)

static inline v8f load8(const float *p) {
    v8f v;
    memcpy(&v, p, sizeof(v));
    return v;
}
/* 8 half floats to floats (F16C when the CPU has it). */
static inline v8f load8h(const uint16_t *p) {
#if defined(__F16C__)
    __m256 v = _mm256_cvtph_ps(_mm_loadu_si128((const __m128i *)p));
    v8f out;
    memcpy(&out, &v, sizeof(out));
    return out;
#else
    v8f out;
    for (int i = 0; i < 8; i++) out[i] = meso_half_to_float(p[i]);
    return out;
#endif
}
static inline float sum8(v8f v) {
    return ((v[0] + v[1]) + (v[2] + v[3])) + ((v[4] + v[5]) + (v[6] + v[7]));
}
/* sum8 of each of eight vectors, lane k holding v[k]'s: the same additions in the same order
 * (AVX: horizontal adds pair neighbours as sum8 does), so the same bits. */
static inline v8f sum8_each(const v8f v[8]) {
#if defined(__AVX__)
    __m256 h01 = _mm256_hadd_ps((__m256)v[0], (__m256)v[1]);
    __m256 h23 = _mm256_hadd_ps((__m256)v[2], (__m256)v[3]);
    __m256 h45 = _mm256_hadd_ps((__m256)v[4], (__m256)v[5]);
    __m256 h67 = _mm256_hadd_ps((__m256)v[6], (__m256)v[7]);
    /* lanes 0-3: (v0 + v1) + (v2 + v3) of v[0..3], lanes 4-7: (v4 + v5) + (v6 + v7) */
    __m256 g0 = _mm256_hadd_ps(h01, h23), g1 = _mm256_hadd_ps(h45, h67);
    __m256 lo = _mm256_permute2f128_ps(g0, g1, 0x20), hi = _mm256_permute2f128_ps(g0, g1, 0x31);
    return (v8f)_mm256_add_ps(lo, hi);
#else
    v8f out;
    for (int k = 0; k < 8; k++) out[k] = sum8(v[k]);
    return out;
#endif
}

typedef struct vdm_options {
    bool compressed, shadows, silhouettes, curvature, silhouette_filter, mipmap;
    int eigenfunctions, mvm_eigenfunctions, resolution, num_theta, num_phi, num_curvatures;
    int refine_steps, shadow_steps;
    float shadow_bias;
} vdm_options;

static const meso_technique_option vdm_option_table[] = {
    MESO_OPTION_ROW(MESO_OPTION_BOOL, compressed, 0, 1, 1,
                    "0: render from the raw 5D table (bakes and caches it)", vdm_options,
                    compressed),
    MESO_OPTION_ROW(MESO_OPTION_INT, eigenfunctions, 1, MESO_VDM_MAX_EIGEN, 8,
                    "VDM eigenfunctions used (bakes at least 8)", vdm_options, eigenfunctions),
    MESO_OPTION_ROW(MESO_OPTION_INT, mvm_eigenfunctions, 1, MESO_VDM_MAX_EIGEN, 4,
                    "MVM eigenfunctions used (bakes at least 4)", vdm_options, mvm_eigenfunctions),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, shadows, 0, 1, 1, "shadows along each light (§3.2)",
                    vdm_options, shadows),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, silhouettes, 0, 1, 1, "discard where theta_V > theta_MVM",
                    vdm_options, silhouettes),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, curvature, 0, 1, 1,
                    "0: curvature 0 everywhere (the paper's planar case)", vdm_options, curvature),
    MESO_OPTION_ROW(MESO_OPTION_INT, resolution, 8, MESO_VDM_MAX_SIDE, 128,
                    "bake: texels a side (256 and 512 measured in docs/techniques/vdm.md)",
                    vdm_options, resolution),
    MESO_OPTION_ROW(MESO_OPTION_INT, num_theta, 2, MESO_VDM_MAX_THETA, 32,
                    "bake: polar view angles", vdm_options, num_theta),
    MESO_OPTION_ROW(MESO_OPTION_INT, num_phi, 1, MESO_VDM_MAX_PHI, 8, "bake: azimuthal view angles",
                    vdm_options, num_phi),
    MESO_OPTION_ROW(MESO_OPTION_INT, num_curvatures, 1, MESO_VDM_MAX_CURVATURES, 16,
                    "bake: curvatures", vdm_options, num_curvatures),
    MESO_OPTION_ROW(MESO_OPTION_FLOAT, shadow_bias, -1.0, 10.0, -1.0,
                    "lit when d_L >= h sec theta_L - bias (1 + h sec theta_L); -1: 0.05, or 0.2 "
                    "with refine_steps 0",
                    vdm_options, shadow_bias),
    MESO_OPTION_ROW(MESO_OPTION_INT, refine_steps, 0, 16, 3,
                    "regula-falsi steps of the hit refined on the height field; 0: the paper's "
                    "interpolated d",
                    vdm_options, refine_steps),
    MESO_OPTION_ROW(MESO_OPTION_INT, shadow_steps, 1, 256, 16,
                    "probes along the light ray where the table is ambiguous (an occluder's edge)",
                    vdm_options, shadow_steps),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, silhouette_filter, 0, 1, 0,
                    "0: theta_MVM of the nearest texel (paper); 1: interpolated", vdm_options,
                    silhouette_filter),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, mipmap, 0, 1, 1,
                    "mip level of W from the pixel's footprint in texels", vdm_options, mipmap),
};

static void vdm_release(void *state) {
    vdm_state *s = state;
    if (!s) return;
    meso_vdm_destroy(s->vdm);
    for (int l = 0; l < s->num_levels; l++) free(s->level_weights[l]);
    free(s->eigen_t);
    free(s->mvm_t);
    free(s);
}

/* The compressed arrays laid out for the 8-wide lookups (meso_vdm_lanes, shared with the GL
 * back end), moved into the state. */
static meso_result relayout(meso_context *ctx, const meso_object *object, vdm_state *s) {
    meso_vdm_lanes l;
    meso_result r =
        meso_vdm_lanes_init(ctx, &s->view, s->num_eigen, s->num_mvm, s->mipmap, object->name, &l);
    if (r != MESO_OK) return r;
    s->lanes = l.lanes;
    s->num_levels = l.num_levels;
    for (int i = 0; i < l.num_levels; i++) {
        s->level_width[i] = l.level_width[i];
        s->level_height[i] = l.level_height[i];
        s->level_weights[i] = l.level_weights[i];
    }
    s->eigen_t = l.eigen_t;
    s->mvm_t = l.mvm_t;
    return MESO_OK;
}

static meso_result vdm_prepare(meso_context *ctx, const meso_scene *scene,
                               const meso_object *object, void **out_state) {
    *out_state = NULL;
    vdm_options options;
    meso_result r =
        meso_technique_options_read(ctx, scene, object, &meso_technique_vdm.info, &options);
    if (r != MESO_OK) return r;
    const meso_mesostructure *ms = &object->mesostructure;
    if (ms->kind != MESO_MESOSTRUCTURE_HEIGHT_FIELD || !ms->height_field)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: technique vdm needs a height field", object->name);
    if (!object->mesh->uvs)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: technique vdm needs texture coordinates", object->name);
    int compressed, eigen, mvm, shadows, silhouettes, curvature, resolution, num_theta, num_phi,
        num_curvatures, silhouette_filter, mipmap, refine_steps, shadow_steps;
    compressed = options.compressed;
    eigen = options.eigenfunctions;
    mvm = options.mvm_eigenfunctions;
    shadows = options.shadows;
    silhouettes = options.silhouettes;
    curvature = options.curvature;
    silhouette_filter = options.silhouette_filter;
    mipmap = options.mipmap;
    resolution = options.resolution;
    num_theta = options.num_theta;
    num_phi = options.num_phi;
    num_curvatures = options.num_curvatures;
    refine_steps = options.refine_steps;
    shadow_steps = options.shadow_steps;
    /* Interpolated d errs by a good part of a shell depth at jumps; refined, by far less. */
    double bias =
        options.shadow_bias >= 0.0f ? options.shadow_bias : (refine_steps > 0 ? 0.05 : 0.2);
    float tile = meso_mesh_tile_length(object->mesh);
    if (!(tile > 0.0f))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: vdm: the texture coordinates cover no area", object->name);
    float depth_tiles = ms->depth / tile;
    if (!(depth_tiles > 0.0f && depth_tiles <= 16.0f))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: mesostructure.depth: %g is %g tiles; vdm needs (0, 16]",
                              object->name, ms->depth, depth_tiles);
    vdm_state *s = calloc(1, sizeof(*s));
    if (!s) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", object->name);
    /* The bake keeps at least the paper's 8 + 4 eigenfunctions, so renders with fewer (Fig. 8)
     * share one cached bake. */
    meso_vdm_desc desc = {.heightfield = ms->height_field,
                          .depth = depth_tiles,
                          .width = resolution,
                          .height = resolution,
                          .num_theta = num_theta,
                          .num_phi = num_phi,
                          .num_curvatures = num_curvatures,
                          .vdm_eigenfunctions = eigen > 8 ? eigen : 8,
                          .mvm_eigenfunctions = mvm > 4 ? mvm : 4,
                          .keep_raw = !compressed};
    int rank = num_theta * num_curvatures + num_curvatures;
    int rows = resolution * resolution * num_phi;
    rank = rank < rows ? rank : rows;
    if (desc.vdm_eigenfunctions > rank) desc.vdm_eigenfunctions = rank;
    if (desc.mvm_eigenfunctions > rank) desc.mvm_eigenfunctions = rank;
    if (eigen > rank || mvm > rank) {
        vdm_release(s);
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: technique_options.eigenfunctions: at most %d for this table",
                              object->name, rank);
    }
    r = meso_vdm_bake_cached(ctx, &desc, &s->vdm);
    if (r != MESO_OK) {
        vdm_release(s);
        return r;
    }
    s->view = meso_vdm_get_view(s->vdm);
    s->raw = !compressed && s->view.raw;
    s->shadows = shadows;
    s->silhouettes = silhouettes;
    s->curvature = curvature;
    s->nearest_silhouette = silhouette_filter == 0;
    s->mipmap = mipmap;
    s->num_eigen = eigen;
    s->num_mvm = mvm;
    s->refine_steps = refine_steps;
    s->shadow_steps = shadow_steps;
    s->depth_tiles = depth_tiles;
    s->tile_world = tile;
    s->shadow_bias = (float)bias;
    s->clamp = ms->height_field->wrap == MESO_WRAP_CLAMP;
    if (!s->raw && (r = relayout(ctx, object, s)) != MESO_OK) {
        vdm_release(s);
        return r;
    }
    *out_state = s;
    return MESO_OK;
}

/* ---- Lookups (multilinear over x, y, phi, theta, c; §4: "interpolated") ------------------- */

typedef struct texel_axes {
    meso_axis x, y, phi;
} texel_axes;

/* meso_axis_wrap, with a mask instead of the integer division where n is a power of two (the
 * same index: i % n made non-negative is i & (n - 1) in two's complement). */
static inline meso_axis axis_wrap(float x, int n) {
    if (n & (n - 1)) return meso_axis_wrap(x, n);
    float f = floorf(x);
    int i = (int)f & (n - 1);
    return (meso_axis){i, (i + 1) & (n - 1), x - f};
}

static inline texel_axes texel_axes_of(const vdm_state *s, meso_vec2 uv, float phi, int width,
                                       int height) {
    const meso_vdm_view *v = &s->view;
    float x = uv.x * (float)width - 0.5f, y = (1.0f - uv.y) * (float)height - 0.5f;
    texel_axes a;
    if (s->clamp) {
        a.x = meso_axis_clamp(x, width);
        a.y = meso_axis_clamp(y, height);
    } else {
        a.x = axis_wrap(x, width);
        a.y = axis_wrap(y, height);
    }
    a.phi = axis_wrap(phi * (float)v->num_phi / (2.0f * MESO_PI), v->num_phi);
    return a;
}

static inline size_t row_of(const meso_vdm_view *v, int ix, int iy, int ip) {
    return ((size_t)iy * (size_t)v->width + (size_t)ix) * (size_t)v->num_phi + (size_t)ip;
}
static inline size_t level_row(int width, int num_phi, int ix, int iy, int ip) {
    return ((size_t)iy * (size_t)width + (size_t)ix) * (size_t)num_phi + (size_t)ip;
}

/* The curvature and theta axes as 4 (column, weight) pairs of the VDM part. */
typedef struct column_set {
    int col[4];
    float w[4];
    meso_axis c;
} column_set;

static inline column_set columns_of(const meso_vdm_view *v, float theta, float c) {
    meso_axis t =
        meso_axis_clamp(theta * (float)v->num_theta / (0.5f * MESO_PI) - 0.5f, v->num_theta);
    float cn = v->num_curvatures > 1
                   ? (c - v->curvature_min) / (v->curvature_max - v->curvature_min) *
                         (float)(v->num_curvatures - 1)
                   : 0.0f;
    meso_axis ca = meso_axis_clamp(cn, v->num_curvatures);
    column_set cs = {
        {ca.i0 * v->num_theta + t.i0, ca.i0 * v->num_theta + t.i1, ca.i1 * v->num_theta + t.i0,
         ca.i1 * v->num_theta + t.i1},
        {(1.0f - ca.w) * (1.0f - t.w), (1.0f - ca.w) * t.w, ca.w * (1.0f - t.w), ca.w * t.w},
        ca};
    return cs;
}

/* d in shell depths at (uv, theta, phi, c) (§3.3: sum_i W^i(x, y, phi) E^i(theta, c)),
 * trilinear over (x, y, phi) and bilinear over (theta, c). out_corners (NULL or 8 values)
 * receives d at the 8 (x, y, phi) corners, the candidates refine_hit chooses from. Also
 * theta_MVM from the nearest texel (§3.2: "its nearest sample value in texture space for
 * silhouette determination"), linear in phi and c. */
static inline float lookup(const vdm_state *s, meso_vec2 uv, float theta, float phi, float c,
                           int level, float *out_max_theta, float *out_corners) {
    const meso_vdm_view *v = &s->view;
    level = s->raw ? 0 : level;
    int lw = s->raw ? v->width : s->level_width[level];
    int lh = s->raw ? v->height : s->level_height[level];
    texel_axes a = texel_axes_of(s, uv, phi, lw, lh);
    column_set cs = columns_of(v, theta, c);
    int nearest_x = a.x.w < 0.5f ? a.x.i0 : a.x.i1, nearest_y = a.y.w < 0.5f ? a.y.i0 : a.y.i1;
    bool nearest = s->nearest_silhouette;
    int mvm_base = v->num_theta * v->num_curvatures;
    if (s->raw) {
        int columns = v->raw_columns;
        float d = 0.0f;
        for (int corner = 0; corner < 8; corner++) {
            float w = (corner & 1 ? a.x.w : 1.0f - a.x.w) * (corner & 2 ? a.y.w : 1.0f - a.y.w) *
                      (corner & 4 ? a.phi.w : 1.0f - a.phi.w);
            if (w == 0.0f && !out_corners) continue;
            const float *row =
                v->raw + row_of(v, corner & 1 ? a.x.i1 : a.x.i0, corner & 2 ? a.y.i1 : a.y.i0,
                                corner & 4 ? a.phi.i1 : a.phi.i0) *
                             columns;
            float corner_d = cs.w[0] * row[cs.col[0]] + cs.w[1] * row[cs.col[1]] +
                             cs.w[2] * row[cs.col[2]] + cs.w[3] * row[cs.col[3]];
            if (out_corners) out_corners[corner] = corner_d;
            d += w * corner_d;
        }
        if (out_max_theta && !nearest) {
            float m = 0.0f;
            for (int corner = 0; corner < 8; corner++) {
                float w = (corner & 1 ? a.x.w : 1.0f - a.x.w) *
                          (corner & 2 ? a.y.w : 1.0f - a.y.w) *
                          (corner & 4 ? a.phi.w : 1.0f - a.phi.w);
                if (w == 0.0f) continue;
                const float *row =
                    v->raw + row_of(v, corner & 1 ? a.x.i1 : a.x.i0, corner & 2 ? a.y.i1 : a.y.i0,
                                    corner & 4 ? a.phi.i1 : a.phi.i0) *
                                 columns;
                m += w *
                     (row[mvm_base + cs.c.i0] * (1.0f - cs.c.w) + row[mvm_base + cs.c.i1] * cs.c.w);
            }
            *out_max_theta = m;
        } else if (out_max_theta) {
            float m = 0.0f;
            for (int q = 0; q < 2; q++) {
                const float *row =
                    v->raw + row_of(v, nearest_x, nearest_y, q ? a.phi.i1 : a.phi.i0) * columns;
                float wq = q ? a.phi.w : 1.0f - a.phi.w;
                m += wq *
                     (row[mvm_base + cs.c.i0] * (1.0f - cs.c.w) + row[mvm_base + cs.c.i1] * cs.c.w);
            }
            *out_max_theta = m;
        }
        return d;
    }
    /* §3.3: d = sum_i W^i E^i_VDM: W trilinear over (x, y, phi), E bilinear over (theta, c) */
    int lanes = s->lanes, chunks = lanes / 8;
    const uint16_t *weights = s->level_weights[level];
    v8f e[MAX_CHUNKS]; /* E^i(theta, c), bilinear */
    for (int j = 0; j < chunks; j++)
        e[j] = cs.w[0] * load8(s->eigen_t + (size_t)cs.col[0] * lanes + 8 * j) +
               cs.w[1] * load8(s->eigen_t + (size_t)cs.col[1] * lanes + 8 * j) +
               cs.w[2] * load8(s->eigen_t + (size_t)cs.col[2] * lanes + 8 * j) +
               cs.w[3] * load8(s->eigen_t + (size_t)cs.col[3] * lanes + 8 * j);
    /* W interpolated, for theta_MVM between the texels (silhouette_filter 1) */
    bool mix_w = out_max_theta && !nearest;
    v8f w[MAX_CHUNKS];
    if (mix_w)
        for (int j = 0; j < chunks; j++) w[j] = (v8f){0};
    float wx[2] = {1.0f - a.x.w, a.x.w}, wy[2] = {1.0f - a.y.w, a.y.w};
    float wp[2] = {1.0f - a.phi.w, a.phi.w};
    /* a corner's row: ((iy lw + ix) num_phi + ip) lanes, as level_row */
    size_t np = (size_t)v->num_phi, lws = (size_t)lw;
    size_t y0 = (size_t)a.y.i0 * lws, y1 = (size_t)a.y.i1 * lws;
    size_t x0 = (size_t)a.x.i0, x1 = (size_t)a.x.i1;
    const size_t xy[4] = {(y0 + x0) * np, (y0 + x1) * np, (y1 + x0) * np, (y1 + x1) * np};
    const size_t rp[2] = {(size_t)a.phi.i0, (size_t)a.phi.i1};
    /* the corners' weights wx wy wp, corner k at (x k & 1, y k >> 1 & 1, phi k >> 2) */
    v8f cw = (v8f){wx[0], wx[1], wx[0], wx[1], wx[0], wx[1], wx[0], wx[1]} *
             (v8f){wy[0], wy[0], wy[1], wy[1], wy[0], wy[0], wy[1], wy[1]} *
             (v8f){wp[0], wp[0], wp[0], wp[0], wp[1], wp[1], wp[1], wp[1]};
    /* corners of weight 0 are skipped unless their d is asked for */
    int used = out_corners ? 0xff : v8_mask_bits(cw != 0.0f);
    v8f dot[8];
#pragma GCC unroll 8
    for (int corner = 0; corner < 8; corner++) {
        dot[corner] = (v8f){0};
        if (!(used >> corner & 1)) continue;
        const uint16_t *row = weights + (xy[corner & 3] + rp[corner >> 2]) * (size_t)lanes;
        if (chunks == 1 && !mix_w) { /* the paper's 8 eigenfunctions */
            dot[corner] += load8h(row) * e[0];
            continue;
        }
        for (int j = 0; j < chunks; j++) {
            v8f wj = load8h(row + 8 * j);
            dot[corner] += wj * e[j];
            if (mix_w) w[j] += cw[corner] * wj;
        }
    }
    /* every corner's sum8 at once */
    v8f corner_d = sum8_each(dot), weighted = cw * corner_d;
    float d = 0.0f;
#pragma GCC unroll 8
    for (int corner = 0; corner < 8; corner++)
        if (used >> corner & 1) d += weighted[corner];
    if (out_corners) memcpy(out_corners, &corner_d, sizeof corner_d);
    if (out_max_theta) {
        /* theta_MVM = sum_i W^i E^i_MVM(c), with W interpolated or of the nearest texel */
        if (nearest) {
            const uint16_t *r0 =
                weights + level_row(lw, v->num_phi, nearest_x, nearest_y, a.phi.i0) * lanes;
            const uint16_t *r1 =
                weights + level_row(lw, v->num_phi, nearest_x, nearest_y, a.phi.i1) * lanes;
            for (int j = 0; j < chunks; j++)
                w[j] = wp[0] * load8h(r0 + 8 * j) + wp[1] * load8h(r1 + 8 * j);
        }
        v8f m = {0};
        for (int j = 0; j < chunks; j++) {
            v8f e_mvm = (1.0f - cs.c.w) * load8(s->mvm_t + (size_t)cs.c.i0 * lanes + 8 * j) +
                        cs.c.w * load8(s->mvm_t + (size_t)cs.c.i1 * lanes + 8 * j);
            m += w[j] * e_mvm;
        }
        *out_max_theta = sum8(m);
    }
    (void)mvm_base;
    return d;
}

/* Beyond the paper: the hit chosen among the 8 (x, y, phi) corner samples of the table, then
 * refined on the height field. d(x, y, phi) jumps where the view ray grazes past a bump
 * (from the bump's near side to the ground behind it), so the paper's interpolated d lands
 * between the two surfaces -- on the hidden far side of the bump, lit from the wrong side:
 * with 8 azimuths 45 degrees apart, and asymmetric maps seen off the axes, most of a cone's
 * outline is such a jump (docs/techniques/vdm.md, "Hit refinement"). Each corner d is a distance
 * the ray may have at this pixel; along the pixel's own ray (bake space, unit vb, d in shell
 * depths) a point d is below the height field when r(d) = d vb.z - (1 - h(T - d depth_tiles vb.xy))
 * >= 0. The first corner with r >= 0 brackets the first crossing after the last one with r < 0 (0
 * is above the surface unless the mesostructure touches it); `steps` of the Illinois regula falsi
 * close in. Where the 8 corners agree the table is smooth and d is used as the paper does: no
 * height samples. When the ray is above the surface at every corner, returns past_every_corner
 * (NAN: the largest corner, the nearest to where the hit must be). */
/* The 8 corner values, clamped to >= 0 and sorted ascending; false when they agree within 1/50
 * shell depth (the table is smooth there: its interpolated d is used as the paper does). */
static inline bool sorted_corners(const float in[8], float out[8]) {
    v8f c;
    memcpy(&c, in, sizeof c);
    /* the table's corners are finite: fminf and fmaxf are plain comparisons there */
    float lo = c[0], hi = c[0];
    for (int i = 1; i < 8; i++) {
        lo = c[i] < lo ? c[i] : lo;
        hi = c[i] > hi ? c[i] : hi;
    }
    if ((hi > 0.0f ? hi : 0.0f) - (lo > 0.0f ? lo : 0.0f) < 0.02f) return false; /* most pixels */
    /* clamped to >= 0 (no -0 left, no NaN) and sorted by a bitonic network: the values in
     * ascending order, as any sort gives them */
    v8f x = v8_select(c > 0.0f, c, v8_splat(0.0f));
    /* each stage: lane i meets lane i ^ j and keeps the larger where its mask is set */
#define SORT_STAGE(p0, p1, p2, p3, p4, p5, p6, p7, m0, m1, m2, m3, m4, m5, m6, m7)                 \
    do {                                                                                           \
        v8f other = __builtin_shufflevector(x, x, p0, p1, p2, p3, p4, p5, p6, p7);                 \
        x = v8_select((v8i){m0, m1, m2, m3, m4, m5, m6, m7}, v8_max(x, other), v8_min(x, other));  \
    } while (0)
    SORT_STAGE(1, 0, 3, 2, 5, 4, 7, 6, 0, -1, -1, 0, 0, -1, -1, 0);
    SORT_STAGE(2, 3, 0, 1, 6, 7, 4, 5, 0, 0, -1, -1, -1, -1, 0, 0);
    SORT_STAGE(1, 0, 3, 2, 5, 4, 7, 6, 0, -1, 0, -1, -1, 0, -1, 0);
    SORT_STAGE(4, 5, 6, 7, 0, 1, 2, 3, 0, 0, 0, 0, -1, -1, -1, -1);
    SORT_STAGE(2, 3, 0, 1, 6, 7, 4, 5, 0, 0, -1, -1, 0, 0, -1, -1);
    SORT_STAGE(1, 0, 3, 2, 5, 4, 7, 6, 0, -1, 0, -1, 0, -1, 0, -1);
#undef SORT_STAGE
    memcpy(out, &x, sizeof x);
    return out[7] - out[0] >= 0.02f;
}

/* One side's texel pair of meso_heightfield_wrap_pair for eight lanes: the same indices. */
static inline void wrap_pair8(meso_wrap wrap, v8i i, int n, v8i *out_i0, v8i *out_i1) {
    v8i i1 = i + 1;
    /* (unsigned)i < n - 1: inside, the pair i, i + 1 */
    int outside = v8_mask_bits((i < 0) | (i >= v8i_splat(n - 1)));
    if (outside && wrap == MESO_WRAP_CLAMP) {
        v8i zero = v8i_splat(0), last = v8i_splat(n - 1);
        i = (v8i)v8_select(i < zero, (v8f)zero, v8_select(i > last, (v8f)last, (v8f)i));
        i1 = (v8i)v8_select(i1 < zero, (v8f)zero, v8_select(i1 > last, (v8f)last, (v8f)i1));
    } else if (outside && (n & (n - 1)) == 0) { /* i % n, made non-negative, is i & (n - 1) */
        i &= n - 1;
        i1 = (i + 1) & (n - 1);
    } else if (outside) {
        for (int k = 0; k < 8; k++) {
            if (!(outside >> k & 1)) continue;
            int w = i[k] % n;
            w += w < 0 ? n : 0;
            i[k] = w;
            i1[k] = w + 1 == n ? 0 : w + 1;
        }
    }
    *out_i0 = i, *out_i1 = i1;
}

/* meso_heightfield_sample at eight (u, v) at once, with the same operations in the same order
 * per lane, so the same bits. */
static inline v8f heightfield_sample8(const meso_heightfield *hf, v8f u, v8f v) {
    if ((size_t)hf->width * (size_t)hf->height > (size_t)INT32_MAX) { /* 32-bit gathers */
        v8f h;
        for (int k = 0; k < 8; k++) h[k] = meso_heightfield_sample(hf, u[k], v[k]);
        return h;
    }
    v8f x = u * (float)hf->width - 0.5f;
    v8f y = (1.0f - v) * (float)hf->height - 0.5f;
    v8f fx = v8_floor(x), fy = v8_floor(y);
    v8f tx = x - fx, ty = y - fy;
    v8i i0, i1, j0, j1;
    wrap_pair8(hf->wrap, __builtin_convertvector(fx, v8i), hf->width, &i0, &i1);
    wrap_pair8(hf->wrap, __builtin_convertvector(fy, v8i), hf->height, &j0, &j1);
    v8i row0 = j0 * hf->width, row1 = j1 * hf->width;
    v8f h00 = v8_gather(hf->heights, row0 + i0), h10 = v8_gather(hf->heights, row0 + i1);
    v8f h01 = v8_gather(hf->heights, row1 + i0), h11 = v8_gather(hf->heights, row1 + i1);
    v8f top = h00 + (h10 - h00) * tx, bottom = h01 + (h11 - h01) * tx;
    return top + (bottom - top) * ty;
}

/* r(t) of refine_hit: >= 0 where the point t shell depths along the ray is below the surface. */
#define RESIDUAL(t)                                                                                \
    ((t)*vb.z - (1.0f - meso_heightfield_sample(hf, uv.x - (t)*step_u, uv.y - (t)*step_v)))
/* RESIDUAL at eight t at once (the same bits per lane). */
#define RESIDUAL8(t)                                                                               \
    ((t)*vb.z - (1.0f - heightfield_sample8(hf, uv.x - (t)*step_u, uv.y - (t)*step_v)))

static float refine_hit(const meso_heightfield *hf, meso_vec2 uv, meso_vec3 vb, float depth_tiles,
                        const float corners_in[8], float d, int steps, float past_every_corner) {
    float corners[8];
    if (!sorted_corners(corners_in, corners)) return d;
    float step_u = depth_tiles * vb.x, step_v = depth_tiles * vb.y;
    /* The probes in their order, each taken while every one before it was above the surface:
     * t = 0, then from each corner beyond the last probe back to it in 1 to 4 parts (half-way
     * first where the gap is wide: a thin tip the ray clips between two corners' distances
     * would otherwise be stepped over), then, above the surface at every candidate, 4 steps
     * further on. They are evaluated eight at a time up to the first below the surface: the
     * same probes and the same first one as probing one by one. */
    float probe[1 + 8 * 4 + 4];
    int num_probes = 0;
    float last = 0.0f;
    probe[num_probes++] = 0.0f;
    for (int i = 0; i < 8; i++) {
        if (corners[i] <= last) continue;
        float start = last, gap = corners[i] - last;
        int inner = gap > 0.3f ? 3 : (gap > 0.2f ? 2 : (gap > 0.1f ? 1 : 0));
        for (int k = 1; k <= inner + 1; k++)
            last = probe[num_probes++] = start + gap * (float)k / (float)(inner + 1);
    }
    float stride = fmaxf(corners[7] - corners[0], 0.125f);
    for (int k = 1; k <= 4; k++) probe[num_probes++] = corners[7] + stride * (float)k;
    float residual[8], r_prev = 0.0f;
    int first = -1, base = 0;
    for (; base < num_probes && first < 0; base += 8) {
        v8f t;
        for (int k = 0; k < 8; k++) t[k] = probe[base + k < num_probes ? base + k : base];
        v8f r = RESIDUAL8(t);
        int valid = num_probes - base >= 8 ? 0xff : (1 << (num_probes - base)) - 1;
        int below = v8_mask_bits(r >= 0.0f) & valid;
        memcpy(residual, &r, sizeof residual);
        if (below)
            first = base + __builtin_ctz((unsigned)below);
        else
            r_prev = residual[7];
    }
    if (first == 0) return 0.0f; /* below the surface where the ray enters */
    if (first < 0) return isnan(past_every_corner) ? corners[7] : past_every_corner;
    float hi = probe[first], r_hi = residual[first - (base - 8)];
    float lo = probe[first - 1];
    float r_lo = first - 1 >= base - 8 ? residual[first - 1 - (base - 8)] : r_prev;
    int side = 0;
    for (int k = 0; k < steps; k++) {
        float x = lo + (hi - lo) * r_lo / (r_lo - r_hi);
        float r = RESIDUAL(x);
        if (r >= 0.0f) {
            hi = x;
            r_hi = r;
            if (side > 0) r_lo *= 0.5f; /* Illinois: the stale end keeps moving */
            side = 1;
        } else {
            lo = x;
            r_lo = r;
            if (side < 0) r_hi *= 0.5f;
            side = -1;
        }
    }
    return lo + (hi - lo) * r_lo / (r_lo - r_hi);
}

/* The shadow counterpart of refine_hit: is the light ray, entering the shell at uv (P'') along
 * the unit bake-space direction vb toward P', below the height field anywhere before `limit`
 * shell depths? Where the 8 corners agree, the table decides as §3.2 says (d_L < limit).
 * Where they disagree the light ray grazes an occluder's edge: one corner's ray (a texel
 * away, up to 22 degrees off in phi) hits it and the next misses, and no corner says where
 * along the pixel's own ray the occluder lies -- choosing among them (refine_hit's way) or
 * probing at and between them missed most of a cone's shadow edge under a low light
 * (truth scene cones-uv-scale). So there `steps` uniform probes along the ray decide, as
 * relief's shadow search does. */
static bool blocked_before(const meso_heightfield *hf, meso_vec2 uv, meso_vec3 vb,
                           float depth_tiles, const float corners_in[8], float d, float limit,
                           int steps) {
    float corners[8];
    if (!sorted_corners(corners_in, corners)) return d < limit;
    float step_u = depth_tiles * vb.x, step_v = depth_tiles * vb.y;
    /* whether any probe is below: eight probes at a time */
    const v8f lane = {0, 1, 2, 3, 4, 5, 6, 7};
    for (int k = 1; k <= steps; k += 8) {
        v8f t = limit * ((float)k + lane) / (float)steps;
        int valid = steps - k + 1 >= 8 ? 0xff : (1 << (steps - k + 1)) - 1;
        if (v8_mask_bits(RESIDUAL8(t) > 0.0f) & valid) return true;
    }
    return false;
}
#undef RESIDUAL
#undef RESIDUAL8

/* VDM §3.2: c_V = (c_max (V.C_max)^2 + c_min (V.C_min)^2) / (1 - (V.N)^2) at one vertex. */
static inline float curvature_along(const meso_mesh *mesh, uint32_t vertex, meso_vec3 eye) {
    meso_vec3 view = meso_vec3_normalize(meso_vec3_sub(eye, mesh->positions[vertex]));
    float vn = meso_vec3_dot(view, mesh->normals[vertex]);
    float a = meso_vec3_dot(view, mesh->curvature_dir_max[vertex]);
    float b = meso_vec3_dot(view, mesh->curvature_dir_min[vertex]);
    float denominator = 1.0f - vn * vn;
    if (denominator < 1e-6f) /* V along N: every direction is equally likely; the mean */
        return 0.5f * (mesh->curvature_max[vertex] + mesh->curvature_min[vertex]);
    return (mesh->curvature_max[vertex] * a * a + mesh->curvature_min[vertex] * b * b) /
           denominator;
}

/* h(u, v) and its gradient as meso_heightfield_sample / meso_heightfield_gradient compute
 * them (bilinear between texel centres; central differences one texel apart), from one 4 x 4
 * block of texels whose wrapped indices are found once: the five bilinear samples share their
 * fractions. */
static inline float height_and_gradient(const meso_heightfield *hf, meso_vec2 uv,
                                        meso_vec2 *out_gradient) {
    float x = uv.x * (float)hf->width - 0.5f, y = (1.0f - uv.y) * (float)hf->height - 0.5f;
    float fx = floorf(x), fy = floorf(y), tx = x - fx, ty = y - fy;
    int i = (int)fx, j = (int)fy;
    int cols[4], rows[4];
    for (int k = 0; k < 4; k++) {
        int c = i - 1 + k, r = j - 1 + k;
        if (hf->wrap == MESO_WRAP_CLAMP) {
            c = c < 0 ? 0 : (c >= hf->width ? hf->width - 1 : c);
            r = r < 0 ? 0 : (r >= hf->height ? hf->height - 1 : r);
        } else {
            c %= hf->width;
            c += c < 0 ? hf->width : 0;
            r %= hf->height;
            r += r < 0 ? hf->height : 0;
        }
        cols[k] = c;
        rows[k] = r;
    }
    float t[4][4];
    for (int r = 0; r < 4; r++)
        for (int c = 0; c < 4; c++)
            t[r][c] = hf->heights[(size_t)rows[r] * (size_t)hf->width + (size_t)cols[c]];
#define BILERP(r, c)                                                                               \
    ((t[r][c] + (t[r][(c) + 1] - t[r][c]) * tx) +                                                  \
     ((t[(r) + 1][c] + (t[(r) + 1][(c) + 1] - t[(r) + 1][c]) * tx) -                               \
      (t[r][c] + (t[r][(c) + 1] - t[r][c]) * tx)) *                                                \
         ty)
    float h = BILERP(1, 1);
    float right = BILERP(1, 2), left = BILERP(1, 0);
    float up = BILERP(0, 1), down = BILERP(2, 1); /* +v is one row up */
#undef BILERP
    out_gradient->x = (right - left) * 0.5f * (float)hf->width;
    out_gradient->y = (up - down) * 0.5f * (float)hf->height;
    return h;
}

/* A world direction in the bake's texture space (u, v, depth; see vdm_shade), unit. */
static inline meso_vec3 to_bake_space(meso_vec3 dir, meso_vec3 t, meso_vec3 b, meso_vec3 n,
                                      float scale_u, float scale_v, float scale_depth) {
    return meso_vec3_normalize((meso_vec3){meso_vec3_dot(dir, t) / scale_u,
                                           meso_vec3_dot(dir, b) / scale_v,
                                           meso_vec3_dot(dir, n) / scale_depth});
}

/* World length of one texture unit along the tangent-plane direction (hx, hy). */
static inline float horizontal_scale(float hx, float hy, float scale_u, float scale_v) {
    float x = hx / scale_u, y = hy / scale_v;
    return sqrtf((hx * hx + hy * hy) / (x * x + y * y));
}

static void vdm_shade(const void *state, const meso_frame *frame, const meso_object *object,
                      meso_fragment *fragments, size_t count) {
    const vdm_state *s = state;
    const meso_scene *scene = frame->scene;
    const meso_mesh *mesh = object->mesh;
    const meso_heightfield *hf = object->mesostructure.height_field;
    float depth_world = object->mesostructure.depth, depth_tiles = s->depth_tiles;
    float theta_step = (0.5f * MESO_PI) / (float)s->view.num_theta;
    bool has_curvature = s->curvature && mesh->curvature_max && mesh->curvature_min &&
                         mesh->curvature_dir_max && mesh->curvature_dir_min;
    /* shading runs 8-wide over a chunk once its fragments know P', N' and T' */
    enum { CHUNK = 64 };
    float chunk_visibility[CHUNK * MESO_SCENE_MAX_LIGHTS];
    int num_lights = scene->num_lights;
    uint32_t cached_triangle = UINT32_MAX;
    float vertex_c[3] = {0.0f, 0.0f, 0.0f};
    for (size_t start = 0; start < count; start += CHUNK) {
        size_t end = start + CHUNK < count ? start + CHUNK : count;
        for (size_t fi = start; fi < end; fi++) {
            meso_fragment *f = &fragments[fi];
            float *visibility = chunk_visibility + (fi - start) * (size_t)num_lights;
            for (int li = 0; li < num_lights; li++) visibility[li] = 1.0f;
            meso_vec3 n = f->normal;
            /* the local frame of §3.2: the normal and the texture directions */
            meso_vec3 t =
                meso_vec3_normalize(meso_vec3_madd(f->tangent, n, -meso_vec3_dot(n, f->tangent)));
            meso_vec3 b = meso_vec3_madd(f->bitangent, n, -meso_vec3_dot(n, f->bitangent));
            b = meso_vec3_normalize(meso_vec3_madd(b, t, -meso_vec3_dot(t, b)));
            meso_vec3 view = meso_vec3_normalize(meso_vec3_sub(frame->eye, f->position));
            if (meso_vec3_dot(view, n) <= 1e-4f) { /* grazing or from behind the base surface */
                f->discard = true;
                continue;
            }
            /* The bake's space is texture space: u, v in tiles and depth in tiles of the average
             * scale (depth_tiles = depth / tile_world). Map V there with the local dP/du, dP/dv,
             * which also covers textures stretched differently in u and v (sphere poles, teapot)
             * where §3.2 assumes a locally uniform scale. */
            float scale_u = meso_vec3_length(f->tangent), scale_v = meso_vec3_length(f->bitangent);
            if (!(scale_u > 0.0f && scale_v > 0.0f)) {
                f->discard = true;
                continue;
            }
            meso_vec3 vb = to_bake_space(view, t, b, n, scale_u, scale_v, s->tile_world);
            float theta = acosf(fminf(vb.z, 1.0f)), phi = atan2f(vb.y, vb.x);
            float c = 0.0f, c_world = 0.0f;
            if (has_curvature) {
                /* per vertex, then interpolated (§3.2); a triangle's fragments are consecutive */
                if (f->triangle != cached_triangle) {
                    const uint32_t *tri = mesh->indices + 3 * (size_t)f->triangle;
                    for (int k = 0; k < 3; k++)
                        vertex_c[k] = curvature_along(mesh, tri[k], frame->eye);
                    cached_triangle = f->triangle;
                }
                c = f->b0 * vertex_c[0] + f->b1 * vertex_c[1] + f->b2 * vertex_c[2];
                c_world = c;
                /* world 1/length -> bake space: y = x^2 c / 2 scaled by 1/s_h across and 1/s
                 * down gives c s_h^2 / s, s_h the world length of one bake unit along V_xy */
                float hx = meso_vec3_dot(view, t), hy = meso_vec3_dot(view, b);
                float world_per_unit = hx * hx + hy * hy > 1e-12f
                                           ? horizontal_scale(hx, hy, scale_u, scale_v)
                                           : s->tile_world;
                c *= world_per_unit * world_per_unit / s->tile_world;
            }
            float max_theta = 0.5f * MESO_PI;
            int level = 0;
            if (s->num_levels > 1) {
                /* texels under the pixel: its world size at this depth over the texel's */
                float footprint = meso_vec3_length(frame->pixel_right) * f->depth;
                float rho = footprint * sqrtf((float)s->view.width * (float)s->view.height /
                                              (scale_u * scale_v));
                while (rho >= 2.0f && level + 1 < s->num_levels) {
                    rho *= 0.5f;
                    level++;
                }
            }
            float corners[8];
            float d = lookup(s, f->uv, theta, phi, c, level, s->silhouettes ? &max_theta : NULL,
                             s->refine_steps > 0 ? corners : NULL);
            /* Silhouette determination (§3.2): d = -1, i.e. theta beyond theta_MVM (§3.3); the
             * half step puts the boundary between the last valid sample and the first invalid. */
            if (s->silhouettes && theta > max_theta + 0.5f * theta_step) {
                f->discard = true;
                continue;
            }
            if (s->refine_steps > 0)
                d = refine_hit(hf, f->uv, vb, depth_tiles, corners, d, s->refine_steps, NAN);
            d = d > 0.0f ? d : 0.0f;
            /* Real texture coordinate (§3.2): T' = T - d V_xy (V toward the eye), in tiles. */
            float offset = d * depth_tiles;
            meso_vec2 uv = {f->uv.x - offset * vb.x, f->uv.y - offset * vb.y};
            meso_vec2 gradient;
            float h = height_and_gradient(hf, uv, &gradient);
            float below = (1.0f - h) * depth_world;
            meso_vec3 position = meso_vec3_madd(f->position, t, -offset * vb.x * scale_u);
            position = meso_vec3_madd(position, b, -offset * vb.y * scale_v);
            position = meso_vec3_madd(position, n, -below);
            /* Beyond the paper: the normal of the curved mesh at the hit, not at the entry (the
             * surface has turned by c_V per world unit of the way along V_xy; relief's
             * relief_curve_normal8 does the same with its quadric). The turn is applied to the
             * displaced normal: turning N before meso_displaced_normal is lost where the
             * gradient is 0, since that normal is then T x B whatever N is. */
            meso_vec3 along = meso_vec3_sub(meso_vec3_madd(position, n, below), f->position);
            meso_vec3 normal = meso_vec3_normalize(meso_vec3_madd(
                meso_displaced_normal(n, f->tangent, f->bitangent, depth_world, gradient), along,
                c_world));

            /* Shadow determination (§3.2, Fig. 5), flat-surface approximation, c_L ignored as in
             * the paper: P'' = T' + h tan(theta_L) L; lit when d_L reaches P' (h sec(theta_L)). */
            for (int li = 0; li < num_lights && s->shadows; li++) {
                meso_vec3 l = meso_light_direction(&scene->lights[li], position);
                if (meso_vec3_dot(l, n) <= 1e-4f) {
                    visibility[li] = 0.0f; /* below the reference surface's horizon */
                    continue;
                }
                if (meso_vec3_dot(l, normal) <= 0.0f) continue; /* unlit anyway: skip the lookup */
                meso_vec3 lb = to_bake_space(l, t, b, n, scale_u, scale_v, s->tile_world);
                float lz = lb.z;
                float depth_below = 1.0f - h; /* shell depths */
                if (depth_below <= 0.0f) continue;
                float reach = depth_below * depth_tiles / lz; /* P' to P'' along L, bake units */
                meso_vec2 uv_light = {uv.x + reach * lb.x, uv.y + reach * lb.y};
                float theta_l = acosf(fminf(lz, 1.0f)), phi_l = atan2f(lb.y, lb.x);
                float max_theta_l = 0.5f * MESO_PI;
                float light_corners[8];
                float d_l = lookup(s, uv_light, theta_l, phi_l, 0.0f, level, &max_theta_l,
                                   s->refine_steps > 0 ? light_corners : NULL);
                if (theta_l > max_theta_l + 0.5f * theta_step) continue; /* the ray meets nothing */
                float expected = depth_below / lz;
                float limit = expected - s->shadow_bias * (1.0f + expected);
                bool blocked = s->refine_steps > 0
                                   ? blocked_before(hf, uv_light, lb, depth_tiles, light_corners,
                                                    d_l, limit, s->shadow_steps)
                                   : d_l < limit;
                if (blocked) visibility[li] = 0.0f;
            }
            float out_depth = meso_vec3_dot(meso_vec3_sub(position, frame->eye), frame->forward);
            f->out_depth = out_depth > f->depth ? out_depth : f->depth;
            f->position = position;
            f->normal = normal;
            f->uv = uv;
        }
        meso_shade_fragments(frame, object, fragments + start, end - start, chunk_visibility);
    }
}

static size_t vdm_memory(const void *state) {
    const vdm_state *s = state;
    if (!s) return 0;
    const meso_vdm_view *v = &s->view;
    size_t rows = (size_t)v->width * v->height * v->num_phi;
    size_t bytes = sizeof(float) * (rows * (size_t)v->num_weights +
                                    (size_t)v->num_vdm * v->num_theta * v->num_curvatures +
                                    (size_t)v->num_mvm * v->num_curvatures);
    if (v->raw) bytes += sizeof(float) * rows * (size_t)v->raw_columns;
    for (int l = 0; l < s->num_levels; l++)
        bytes += sizeof(uint16_t) * (size_t)s->lanes * s->level_width[l] * s->level_height[l] *
                 (size_t)v->num_phi;
    if (s->eigen_t)
        bytes += sizeof(float) * (size_t)s->lanes *
                 ((size_t)v->num_theta * v->num_curvatures + (size_t)v->num_curvatures);
    return bytes;
}

const meso_technique meso_technique_vdm = {
    .info = {.name = "vdm",
             .summary = "view-dependent displacement map: silhouettes, occlusion, shadows (SVD)",
             .paper = "Wang et al. 2003, View-Dependent Displacement Mapping, §3",
             .kind = MESO_TECHNIQUE_PER_PIXEL,
             .accepts = MESO_TECHNIQUE_ACCEPTS_HEIGHT_FIELD,
             .options = vdm_option_table,
             .num_options = MESO_OPTION_COUNT(vdm_option_table)},
    .prepare = vdm_prepare,
    .release = vdm_release,
    .shade = vdm_shade,
    .memory = vdm_memory,
};
