/* Filtering by pixel footprint: the maps read at the mip level that matches how many texels a
 * sample covers, instead of level 0 at the sample's centre (docs/techniques.md, "Filtering").
 *
 * The footprint is the change of the base uv from one sample to the next to the right
 * (duv/dx) and down (duv/dy), which the rasterizer derives exactly from its perspective planes
 * (raster_tiles.c) and the reference from ray differentials at its primary hits (Igehy 1999,
 * "Tracing ray differentials", §3). In texels these two vectors span the sample's footprint, an
 * ellipse-like parallelogram; a lookup takes taps = ceil(major / minor) (at most
 * MESO_FILTER_MAX_TAPS) trilinear probes spread evenly along the major axis, each at the level
 * log2(major / taps), box-weighted: the anisotropic filter of graphics hardware (the
 * "footprint assembly" of Schilling, Knittel and Strasser 1996, "Texram: a smart memory for
 * texturing", §4), a cheap stand-in for a full EWA filter (Heckbert 1989 §3.5.8). A footprint
 * of at most one texel reads level 0 bilinearly with exactly the unfiltered lookup's arithmetic,
 * so close-up pixels keep their bits.
 */
#ifndef MESO_RENDER_FILTER_H
#define MESO_RENDER_FILTER_H

#include <string.h>

#include "render_internal.h"
#include "render_simd.h"
#include "meso/texture.h"

/* Taps along the major axis: more sharpen footprints longer than 8:1 (a floor at a grazing
 * angle) at the cost of a lookup each; beyond 8 the level rises instead (blurring across the
 * minor axis), as GPUs do past their maximum anisotropy. */
#define MESO_FILTER_MAX_TAPS 8

/* The footprints of eight lanes: duv/dx = (dudx, dvdx), duv/dy = (dudy, dvdy), in uv units
 * (uv_scale applied) per sample. Zero: a point. */
typedef struct meso_footprint8 {
    v8f dudx, dvdx, dudy, dvdy;
} meso_footprint8;

/* Lanes first..first+7 of a block's footprint arrays. */
static inline void meso_footprint8_from_block(meso_footprint8 *fp, const meso_fragment_block *b,
                                              size_t first) {
    memcpy(&fp->dudx, b->dudx + first, sizeof(v8f));
    memcpy(&fp->dvdx, b->dvdx + first, sizeof(v8f));
    memcpy(&fp->dudy, b->dudy + first, sizeof(v8f));
    memcpy(&fp->dvdy, b->dvdy + first, sizeof(v8f));
}

/* A texture's levels as the lookups index them: sizes and offsets into mip_chain. */
typedef struct meso_filter_levels {
    const float *chain;
    int num_levels;
    int32_t width[MESO_TEXTURE_MAX_LEVELS], height[MESO_TEXTURE_MAX_LEVELS];
    int32_t offset[MESO_TEXTURE_MAX_LEVELS];
    float width0, height0;
} meso_filter_levels;

/* false when the texture has no chain (no mips): it is then read unfiltered. */
static inline bool meso_filter_levels_init(meso_filter_levels *l, const meso_texture *t) {
    l->chain = t ? t->mip_chain : NULL;
    if (!l->chain) return false;
    l->num_levels = t->num_levels;
    for (int k = 0; k < MESO_TEXTURE_MAX_LEVELS; k++) {
        int use = k < t->num_levels ? k : t->num_levels - 1;
        l->width[k] = t->levels[use]->width, l->height[k] = t->levels[use]->height;
        l->offset[k] = t->mip_offset[use];
    }
    l->width0 = (float)l->width[0], l->height0 = (float)l->height[0];
    return true;
}

/* log2(x) for x > 0 finite, to about 0.01: exponent plus a quadratic in the mantissa that is
 * exact at its ends, so the level is continuous and increasing in the footprint (what the blend
 * between levels needs; its exact value does not matter). */
static inline v8f meso_filter_log2(v8f x) {
    v8i bits = (v8i)x;
    v8f e = __builtin_convertvector(((bits >> 23) & 255) - 127, v8f);
    v8i mb = (bits & 0x007fffff) | 0x3f800000;
    v8f t = (v8f)mb - v8_splat(1.0f);
    return e + t * (v8_splat(1.3465f) - v8_splat(0.3465f) * t);
}

/* Where a footprint-filtered lookup reads: per lane, the number of taps, the step between taps
 * in uv (along the major axis), the two levels and the blend between them. */
typedef struct meso_filter_taps {
    v8f count; /* taps, 1..MESO_FILTER_MAX_TAPS, as a float */
    v8f step_u, step_v;
    v8i level;      /* the finer level */
    v8f blend;      /* weight of level + 1 */
    int max_count;  /* the most taps of any lane */
    bool any_blend; /* some lane reads level + 1 */
} meso_filter_taps;

/* false when every lane's footprint lies within one texel of level 0 (read it unfiltered);
 * else the taps of each lane (lanes within one texel: one tap at level 0). */
static inline bool meso_filter_plan(const meso_filter_levels *l, const meso_footprint8 *fp,
                                    meso_filter_taps *out) {
    v8f ax = fp->dudx * l->width0, ay = fp->dvdx * l->height0;
    v8f bx = fp->dudy * l->width0, by = fp->dvdy * l->height0;
    v8f la = ax * ax + ay * ay, lb = bx * bx + by * by;
    v8i finite = (la < v8_splat(INFINITY)) & (lb < v8_splat(INFINITY));
    la = v8_select(finite, la, v8_splat(0.0f)), lb = v8_select(finite, lb, v8_splat(0.0f));
    v8i x_major = la >= lb;
    v8f major2 = v8_select(x_major, la, lb), minor2 = v8_select(x_major, lb, la);
    v8i wide = major2 > v8_splat(1.0f);
    if (!v8_any(wide)) return false;
    /* taps = ceil(major / minor), from the squared ratio without a division by zero; a ratio
     * within 1 % of a whole number counts as it, so a round footprint that rounding made a
     * hair longer one way takes one tap, not two half a texel apart */
    v8f ratio = v8_sqrt(major2 / v8_select(minor2 > v8_splat(1e-20f), minor2, v8_splat(1e-20f))) -
                v8_splat(0.01f);
    v8f count = v8_floor(ratio);
    count = v8_select(count < ratio, count + v8_splat(1.0f), count);
    count = v8_select(count > v8_splat((float)MESO_FILTER_MAX_TAPS),
                      v8_splat((float)MESO_FILTER_MAX_TAPS), count);
    count = v8_select(wide & (count > v8_splat(1.0f)), count, v8_splat(1.0f));
    /* lod = log2(major / taps), at least 0 */
    v8f lod = v8_splat(0.5f) * meso_filter_log2(v8_select(wide, major2, v8_splat(1.0f))) -
              meso_filter_log2(count);
    float max_lod = (float)(l->num_levels - 1);
    lod = v8_select(lod > v8_splat(0.0f), lod, v8_splat(0.0f));
    lod = v8_select(lod < v8_splat(max_lod), lod, v8_splat(max_lod));
    v8f level = v8_floor(lod);
    out->level = __builtin_convertvector(level, v8i);
    out->blend = lod - level;
    out->any_blend = v8_any(out->blend > v8_splat(0.0f));
    out->count = count;
    v8f inv = v8_splat(1.0f) / count;
    out->step_u = v8_select(x_major, fp->dudx, fp->dudy) * inv;
    out->step_v = v8_select(x_major, fp->dvdx, fp->dvdy) * inv;
    out->step_u = v8_select(finite & wide, out->step_u, v8_splat(0.0f));
    out->step_v = v8_select(finite & wide, out->step_v, v8_splat(0.0f));
    int most = 1;
    for (int k = 0; k < V8_LANES; k++)
        if ((int)count[k] > most) most = (int)count[k];
    out->max_count = most;
    return true;
}

/* Bilinear between texel centres at each lane's own level of the chain, with the texture's wrap:
 * per lane the arithmetic of the shading's level-0 lookup (render_shading.c,
 * sample_color_map), so level 0 gives its bits; 0 for a non-finite uv. */
static inline __attribute__((always_inline)) void meso_filter_bilinear8(const meso_filter_levels *l,
                                                                        bool clamp, v8i level,
                                                                        v8f u, v8f v, v8f *r,
                                                                        v8f *g, v8f *b) {
    v8i finite = ((u - u) == v8_splat(0.0f)) & ((v - v) == v8_splat(0.0f));
    u = v8_select(finite, u, v8_splat(0.0f));
    v = v8_select(finite, v, v8_splat(0.0f));
    if (!clamp) {
        u -= v8_floor(u);
        v -= v8_floor(v);
    }
    v8i wv = v8i_gather(l->width, level), hv = v8i_gather(l->height, level);
    v8i offset = v8i_gather(l->offset, level);
    v8f wf = __builtin_convertvector(wv, v8f), hf = __builtin_convertvector(hv, v8f);
    v8f x = u * wf - v8_splat(0.5f);
    v8f y = (v8_splat(1.0f) - v) * hf - v8_splat(0.5f);
    v8f fx = v8_floor(x), fy = v8_floor(y);
    v8f tx = x - fx, ty = y - fy;
    fx = v8_select(fx < v8_splat(-1.0f), v8_splat(-1.0f), fx);
    fy = v8_select(fy < v8_splat(-1.0f), v8_splat(-1.0f), fy);
    fx = v8_select(fx > wf, wf, fx);
    fy = v8_select(fy > hf, hf, fy);
    v8i i0 = __builtin_convertvector(fx, v8i), j0 = __builtin_convertvector(fy, v8i);
    v8i i1 = i0 + 1, j1 = j0 + 1;
    v8i zero = v8i_splat(0);
#define SEL(m, a, c) (((a) & (m)) | ((c) & ~(m)))
    if (clamp) {
        i0 = SEL(i0 < zero, zero, i0), j0 = SEL(j0 < zero, zero, j0);
        i1 = SEL(i1 >= wv, wv - 1, i1), j1 = SEL(j1 >= hv, hv - 1, j1);
        i0 = SEL(i0 >= wv, wv - 1, i0), j0 = SEL(j0 >= hv, hv - 1, j0);
    } else {
        i0 = SEL(i0 < zero, i0 + wv, i0), j0 = SEL(j0 < zero, j0 + hv, j0);
        i1 = SEL(i1 >= wv, i1 - wv, i1), j1 = SEL(j1 >= hv, j1 - hv, j1);
    }
#undef SEL
    v8i row0 = j0 * wv, row1 = j1 * wv;
    v8i ia = offset + (row0 + i0) * 4, ib = offset + (row0 + i1) * 4;
    v8i ic = offset + (row1 + i0) * 4, id = offset + (row1 + i1) * 4;
    const float *p = l->chain;
    v8f ar = v8_gather(p, ia), ag = v8_gather(p + 1, ia), ab = v8_gather(p + 2, ia);
    v8f br = v8_gather(p, ib), bg = v8_gather(p + 1, ib), bb = v8_gather(p + 2, ib);
    v8f cr = v8_gather(p, ic), cg = v8_gather(p + 1, ic), cb = v8_gather(p + 2, ic);
    v8f dr = v8_gather(p, id), dg = v8_gather(p + 1, id), db = v8_gather(p + 2, id);
    v8f top, bottom;
    top = ar + (br - ar) * tx, bottom = cr + (dr - cr) * tx;
    *r = v8_select(finite, top + (bottom - top) * ty, v8_splat(0.0f));
    top = ag + (bg - ag) * tx, bottom = cg + (dg - cg) * tx;
    *g = v8_select(finite, top + (bottom - top) * ty, v8_splat(0.0f));
    top = ab + (bb - ab) * tx, bottom = cb + (db - cb) * tx;
    *b = v8_select(finite, top + (bottom - top) * ty, v8_splat(0.0f));
}

/* The footprint-filtered RGB at eight uvs, by a plan of meso_filter_plan: the mean of each
 * lane's taps u + (k + 1/2 - taps/2) step, each trilinear between its two levels. One tap with
 * no blend is the bilinear lookup at the level, bit for bit. */
static inline void meso_filter_sample8(const meso_filter_levels *l, bool clamp,
                                       const meso_filter_taps *plan, v8f u, v8f v, v8f *out_r,
                                       v8f *out_g, v8f *out_b) {
    v8f sr = v8_splat(0.0f), sg = v8_splat(0.0f), sb = v8_splat(0.0f);
    v8i coarser = plan->level + 1;
    coarser = (coarser & (coarser < l->num_levels)) | ((plan->level) & ~(coarser < l->num_levels));
    v8f half = v8_splat(0.5f) * plan->count;
    for (int k = 0; k < plan->max_count; k++) {
        v8f offset = v8_splat((float)k + 0.5f) - half;
        v8i active = v8_splat((float)k) < plan->count;
        v8f tu = v8_select(active, u + offset * plan->step_u, u);
        v8f tv = v8_select(active, v + offset * plan->step_v, v);
        v8f r, g, b;
        meso_filter_bilinear8(l, clamp, plan->level, tu, tv, &r, &g, &b);
        if (plan->any_blend) {
            v8f r1, g1, b1;
            meso_filter_bilinear8(l, clamp, coarser, tu, tv, &r1, &g1, &b1);
            r += (r1 - r) * plan->blend, g += (g1 - g) * plan->blend, b += (b1 - b) * plan->blend;
        }
        sr += v8_select(active, r, v8_splat(0.0f));
        sg += v8_select(active, g, v8_splat(0.0f));
        sb += v8_select(active, b, v8_splat(0.0f));
    }
    v8f inv = v8_splat(1.0f) / plan->count;
    *out_r = sr * inv, *out_g = sg * inv, *out_b = sb * inv;
}

#endif
