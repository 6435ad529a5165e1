/* Shared by the per-pixel height-field techniques (parallax, horizon, relief, relief_exact):
 * the view ray in the object's texture space, a padded copy of the height field with an
 * 8-wide bilinear sampler, the option reader, and the relief family's silhouette (per-vertex
 * quadric), depth correction, self-shadow and shading code.
 *
 * Texture space of a fragment. With T = dP/du, B = dP/dv and N unit at the fragment, the view
 * vector V = P - eye (unnormalised) is written V = du T + dv B + dn N (dual basis). Along the
 * ray P + t V (t >= 0 from the base mesh), the texture coordinates are uv + t (du, dv) and the
 * depth below the base surface in shell units (d = 1 - h, d = 0 at the mesh, docs/design.md) is
 *     d(t) = t (a - b t),   a = -dn / depth,   b = (qa x^2 + qb y^2) / depth
 * where (x, y) = (V.normalize(T), V.normalize(B)) and (qa, qb) the per-vertex quadric
 * interpolated at the fragment (Oliveira & Policarpo 2005, summarised in Policarpo & Oliveira
 * 2006 §2.1): on a curved mesh the surface falls away below the tangent plane by qa x^2 + qb y^2,
 * so d counts from the curved surface and a ray whose d returns to 0 leaves the shell (a
 * silhouette). b = 0 without silhouettes (the flat relief of Policarpo et al. 2005).
 * The ray hits the height field at the first t with d(t) >= 1 - h(uv(t)).
 *
 * Everything is in texel-centre coordinates for sampling: x = u W - 0.5, y = (1 - v) H - 0.5.
 */
#ifndef MESO_RELIEF_COMMON_H
#define MESO_RELIEF_COMMON_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "meso/bake_minmax.h"
#include "meso/runtime.h"
#include "render_shading.h"

#define RELIEF_LANES V8_LANES
/* Groups of eight a technique hands meso_shade_batches_to_block at once: the shading's
 * per-object constants once a call (8 KB of inputs on the stack). */
#define RELIEF_SHADE_GROUPS 8

/* ---- The height field, padded ------------------------------------------------------------- */

/* A (W + 1) x (H + 1) copy of the height field whose last row and column repeat the wrapped
 * first ones (or the clamped last ones), so a bilinear lookup reads four texels without
 * wrapping indices in the inner loop. */
typedef struct relief_heights {
    const meso_heightfield *source;
    int width, height, stride;
    bool clamp;
    float *padded;
} relief_heights;

static inline meso_result relief_heights_init(meso_context *ctx, const meso_object *object,
                                              relief_heights *out) {
    const meso_heightfield *hf = object->mesostructure.height_field;
    memset(out, 0, sizeof *out);
    if (!hf || hf->width <= 0 || hf->height <= 0)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: mesostructure: a height field is required", object->name);
    if (hf->width >= (1 << 15) || hf->height >= (1 << 15))
        return meso_log_error(ctx, MESO_ERROR_LIMIT,
                              "%s: mesostructure: %d x %d exceeds 32767 texels a side",
                              object->name, hf->width, hf->height);
    size_t n = (size_t)(hf->width + 1) * (size_t)(hf->height + 1);
    out->padded = malloc(n * sizeof(float));
    if (!out->padded)
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", object->name);
    out->source = hf;
    out->width = hf->width;
    out->height = hf->height;
    out->stride = hf->width + 1;
    out->clamp = hf->wrap == MESO_WRAP_CLAMP;
    for (int j = 0; j <= hf->height; ++j)
        for (int i = 0; i <= hf->width; ++i)
            out->padded[(size_t)j * (size_t)out->stride + (size_t)i] =
                meso_heightfield_texel(hf, i, j);
    return MESO_OK;
}

static inline void relief_heights_deinit(relief_heights *h) {
    free(h->padded);
    h->padded = NULL;
}

static inline size_t relief_heights_memory(const relief_heights *h) {
    return (size_t)(h->width + 1) * (size_t)(h->height + 1) * sizeof(float);
}

/* base[index[k]] and base[index[k] + 1] per lane: with AVX2 as two 64-bit gathers of four
 * lanes each (a texel and its right neighbour are adjacent in a row), half the elements of
 * two 32-bit gathers, which is what a gather costs; the same floats, so the same results. */
static inline void relief_gather_pairs8(const float *base, v8i index, v8f *left, v8f *right) {
#if defined(__AVX2__)
    /* lanes 0, 1, 4, 5 in the first gather, 2, 3, 6, 7 in the second: the shuffles below
     * then put every lane back in its place */
    __m256i order = _mm256_permute4x64_epi64((__m256i)index, 0xd8);
    const long long *pairs = (const long long *)(const void *)base;
    __m256 a = _mm256_castsi256_ps(_mm256_i32gather_epi64(pairs, _mm256_castsi256_si128(order), 4));
    __m256 b =
        _mm256_castsi256_ps(_mm256_i32gather_epi64(pairs, _mm256_extracti128_si256(order, 1), 4));
    *left = (v8f)_mm256_shuffle_ps(a, b, 0x88);
    *right = (v8f)_mm256_shuffle_ps(a, b, 0xdd);
#else
    *left = v8_gather(base, index);
    *right = v8_gather(base + 1, index);
#endif
}

/* The texel (i, j) below texel-centre coordinates (x, y) and the fractions (tx, ty) inside it,
 * with the height field's wrap: what relief_sample8 interpolates between. */
static inline void relief_texel8(const relief_heights *m, v8f x, v8f y, v8i *out_i, v8i *out_j,
                                 v8f *out_tx, v8f *out_ty) {
    float fw = (float)m->width, fh = (float)m->height;
    if (m->clamp) {
        x = v8_min(v8_max(x, v8_splat(0.0f)), v8_splat(fw - 1.0f));
        y = v8_min(v8_max(y, v8_splat(0.0f)), v8_splat(fh - 1.0f));
    } else {
        x -= fw * v8_floor(x * (1.0f / fw));
        y -= fh * v8_floor(y * (1.0f / fh));
    }
    v8i i = __builtin_convertvector(x, v8i), j = __builtin_convertvector(y, v8i);
    v8i wmax = v8i_splat(m->width - 1), hmax = v8i_splat(m->height - 1);
    i = (v8i)v8_select(i > wmax, (v8f)wmax, (v8f)i);
    j = (v8i)v8_select(j > hmax, (v8f)hmax, (v8f)j);
    *out_tx = x - __builtin_convertvector(i, v8f), *out_ty = y - __builtin_convertvector(j, v8f);
    *out_i = i, *out_j = j;
}

/* relief_texel8's texel as an index into the padded rows (its top-left of the four). */
static inline v8i relief_texel_index8(const relief_heights *m, v8f x, v8f y, v8f *out_tx,
                                      v8f *out_ty) {
    v8i i, j;
    relief_texel8(m, x, y, &i, &j, out_tx, out_ty);
    return j * m->stride + i;
}

/* The bilinear blend of relief_sample8: h00, h10 on row j, h01, h11 on row j + 1. */
static inline v8f relief_bilinear8(v8f h00, v8f h10, v8f h01, v8f h11, v8f tx, v8f ty) {
    v8f top = h00 + (h10 - h00) * tx, bottom = h01 + (h11 - h01) * tx;
    return top + (bottom - top) * ty;
}

/* h at texel-centre coordinates (x, y), the bilinear surface of meso_heightfield_sample, eight
 * lookups at once; the hot loop of every search (4 gathers of 8 texels). */
static inline v8f relief_sample8(const relief_heights *m, v8f x, v8f y) {
    v8f tx, ty;
    v8i index = relief_texel_index8(m, x, y, &tx, &ty);
    v8f h00, h10, h01, h11;
    relief_gather_pairs8(m->padded, index, &h00, &h10);
    relief_gather_pairs8(m->padded + m->stride, index, &h01, &h11);
    return relief_bilinear8(h00, h10, h01, h11, tx, ty);
}

#if defined(__AVX2__)
/* base[index[k] + c] for c = 0..3 in out[c], per lane: one 16-byte load a lane and a
 * transpose, no gather. */
static inline void relief_load_quads8(const float *base, v8i index, v8f out[4]) {
    __m256 q[4];
    /* unrolled: as a loop GCC kept q on the stack */
#pragma GCC unroll 4
    for (int k = 0; k < 4; k++) {
        __m128 lo = _mm_loadu_ps(base + index[k]), hi = _mm_loadu_ps(base + index[k + 4]);
        q[k] = _mm256_insertf128_ps(_mm256_castps128_ps256(lo), hi, 1);
    }
    /* q[k]: lane k's four texels, then lane k + 4's */
    __m256 t0 = _mm256_unpacklo_ps(q[0], q[1]), t1 = _mm256_unpackhi_ps(q[0], q[1]);
    __m256 t2 = _mm256_unpacklo_ps(q[2], q[3]), t3 = _mm256_unpackhi_ps(q[2], q[3]);
    out[0] = (v8f)_mm256_shuffle_ps(t0, t2, 0x44), out[1] = (v8f)_mm256_shuffle_ps(t0, t2, 0xee);
    out[2] = (v8f)_mm256_shuffle_ps(t1, t3, 0x44), out[3] = (v8f)_mm256_shuffle_ps(t1, t3, 0xee);
}
#endif

/* relief_sample8 with the texel pairs read by loads (v8_load_pairs), not gathers: the same
 * texels, so the same bits. For a lookup outside a search's dependent chain, where the loads
 * cost less time than the gathers (parallax's unshifted depth); inside a chain the
 * index extraction would lengthen it (not measured). */
static inline v8f relief_sample8_loads(const relief_heights *m, v8f x, v8f y) {
    v8f tx, ty;
    v8i index = relief_texel_index8(m, x, y, &tx, &ty);
    v8f h00, h10, h01, h11;
    v8_load_pairs(m->padded, index, &h00, &h10);
    v8_load_pairs(m->padded + m->stride, index, &h01, &h11);
    return relief_bilinear8(h00, h10, h01, h11, tx, ty);
}

/* relief_sample8 at (x + 1, y) in *right and (x - 1, y) in *left, with the same bits. Both read
 * rows j and j + 1; where every lane's two texel pairs are the four texels from i - 1 on (no
 * wrap between them), AVX2 reads them with one 16-byte load a lane and row instead of two
 * gathers a sample and row (the gathers were most of bump's frame). */
static inline void relief_sample8_beside(const relief_heights *m, v8f x, v8f y, v8f *right,
                                         v8f *left) {
#if defined(__AVX2__)
    v8i ir, jr, il, jl;
    v8f txr, tyr, txl, tyl;
    relief_texel8(m, x + 1.0f, y, &ir, &jr, &txr, &tyr);
    relief_texel8(m, x - 1.0f, y, &il, &jl, &txl, &tyl);
    /* the padded rows hold columns 0..width: il + 3 <= width */
    if (v8_mask_bits((ir == il + 2) & (il <= v8i_splat(m->width - 3)) & (jr == jl)) == 0xff) {
        v8i index = jl * m->stride + il;
        v8f row0[4], row1[4];
        relief_load_quads8(m->padded, index, row0);
        relief_load_quads8(m->padded + m->stride, index, row1);
        *right = relief_bilinear8(row0[2], row0[3], row1[2], row1[3], txr, tyr);
        *left = relief_bilinear8(row0[0], row0[1], row1[0], row1[1], txl, tyl);
        return;
    }
#endif
    *right = relief_sample8(m, x + 1.0f, y);
    *left = relief_sample8(m, x - 1.0f, y);
}

/* ---- The view ray in texture space -------------------------------------------------------- */

/* Write a world direction D in the fragment's frame: D = cu T + cv B + cn N. False when the
 * frame is degenerate (no UVs). */
static inline bool relief_frame_solve(const meso_fragment *f, meso_vec3 dir, float *cu, float *cv,
                                      float *cn) {
    meso_vec3 bn = meso_vec3_cross(f->bitangent, f->normal);
    meso_vec3 nt = meso_vec3_cross(f->normal, f->tangent);
    meso_vec3 tb = meso_vec3_cross(f->tangent, f->bitangent);
    float det = meso_vec3_dot(f->tangent, bn);
    if (!(fabsf(det) > 1e-20f)) return false;
    float inv = 1.0f / det;
    *cu = meso_vec3_dot(dir, bn) * inv;
    *cv = meso_vec3_dot(dir, nt) * inv;
    *cn = meso_vec3_dot(dir, tb) * inv;
    return true;
}

/* The quadric (a, b) at the fragment: per-vertex values interpolated by its barycentrics. */
static inline meso_vec2 relief_fragment_quadric(const meso_object *object, const meso_fragment *f) {
    const meso_mesh *mesh = object->mesh;
    if (!mesh || !mesh->quadrics || f->triangle >= mesh->num_triangles)
        return (meso_vec2){0.0f, 0.0f};
    const uint32_t *t = mesh->indices + 3 * (size_t)f->triangle;
    return meso_vec2_barycentric(mesh->quadrics[t[0]], mesh->quadrics[t[1]], mesh->quadrics[t[2]],
                                 f->b0, f->b1, f->b2);
}

/* The quadrics (relief_fragment_quadric) of the first `count` fragments of an array, or of
 * lanes first..first+count-1 of a block; the other lanes 0. False when the mesh has none. */
static inline bool relief_quadrics8(const meso_object *object, const meso_fragment *f,
                                    const meso_fragment_block *block, size_t first, int count,
                                    v8f *qa, v8f *qb) {
    const meso_mesh *mesh = object->mesh;
    *qa = v8_splat(0.0f), *qb = v8_splat(0.0f);
    if (!mesh || !mesh->quadrics) return false;
    if (block && mesh->num_triangles < (1u << 29)) {
        /* eight lanes by gathers: meso_vec2_barycentric's products and sums in its order, so
         * the same floats */
        v8i triangle;
        memcpy(&triangle, block->triangle + first, sizeof triangle);
        v8i ok = v8_mask_from_bits((1 << count) - 1) & (triangle >= 0) &
                 (triangle < v8i_splat((int32_t)mesh->num_triangles));
        v8i corner = (v8i)v8_select(ok, (v8f)(triangle * 3), (v8f)v8i_splat(0));
        const int32_t *indices = (const int32_t *)(const void *)mesh->indices;
        const float *q = (const float *)(const void *)mesh->quadrics;
        v8i i0 = v8i_gather(indices, corner) * 2, i1 = v8i_gather(indices, corner + 1) * 2;
        v8i i2 = v8i_gather(indices, corner + 2) * 2;
        v8f b0 = meso_block_load(block->b0, first), b1 = meso_block_load(block->b1, first);
        v8f b2 = meso_block_load(block->b2, first);
        v8f x = v8_gather(q, i0) * b0 + v8_gather(q, i1) * b1 + v8_gather(q, i2) * b2;
        v8f y = v8_gather(q, i0 + 1) * b0 + v8_gather(q, i1 + 1) * b1 + v8_gather(q, i2 + 1) * b2;
        *qa = v8_select(ok, x, v8_splat(0.0f));
        *qb = v8_select(ok, y, v8_splat(0.0f));
        return true;
    }
    for (int k = 0; k < count; ++k) {
        meso_vec2 q;
        if (f) {
            q = relief_fragment_quadric(object, &f[k]);
        } else {
            size_t i = first + (size_t)k;
            uint32_t triangle = block->triangle[i];
            if (triangle >= mesh->num_triangles) continue;
            const uint32_t *t = mesh->indices + 3 * (size_t)triangle;
            q = meso_vec2_barycentric(mesh->quadrics[t[0]], mesh->quadrics[t[1]],
                                      mesh->quadrics[t[2]], block->b0[i], block->b1[i],
                                      block->b2[i]);
        }
        (*qa)[k] = q.x;
        (*qb)[k] = q.y;
    }
    return true;
}

/* A batch of up to 8 rays as vectors; lanes >= count are inactive (t_end = 0, found). */
typedef struct relief_batch {
    int count;
    v8f x0, y0, xd, yd, a, b, t_end;
    v8f qa, qb; /* the quadric at each fragment (0 without silhouettes): shadows use it too */
    /* curved_uv only (else 0): at depth d the texture coordinates advance 1 / (1 - lateral d)
     * times faster than on the mesh (relief_lateral_scale) */
    v8f lateral;
    int flat_bits;  /* lanes whose hit is t = 0 without a search */
    int floor_bits; /* lanes whose search ends on the floor */
} relief_batch;

/* The inside test of a search (relief_search8_core): at texel-centre positions (x, y) and
 * depths d (shell units) of eight lanes, the mask of lanes at or below the surface and in
 * *out_f a signed distance to it (>= 0 inside, < 0 outside) whose root the secant step finds.
 * A height field's is relief_height_inside8; relief_layers' counts a multilayer map's layers. */
typedef v8i (*relief_inside8_fn)(const void *field, v8f x, v8f y, v8f d, v8f *out_f);

/* A height field's inside test: below the surface where d >= 1 - h, f = d + h - 1. */
__attribute__((always_inline)) static inline v8i relief_height_inside8(const void *field, v8f x,
                                                                       v8f y, v8f d, v8f *out_f) {
    v8f f = d + relief_sample8(field, x, y) - 1.0f;
    *out_f = f;
    return f >= 0.0f;
}

/* The factor on the tangent-plane texture offset of a ray point at depth d (curved_uv). */
static inline v8f relief_lateral_scale(const relief_batch *b, v8f d) {
    return 1.0f / (1.0f - b->lateral * v8_max(d, v8_splat(0.0f)));
}

/* Relief mapping's search (Policarpo et al. 2005, as in Policarpo & Oliveira 2006 §2.1 and
 * Appendix A; for a multilayer map the same Algorithms 1 and 2 of §3.1 with its inside test):
 * `linear_steps` uniform steps along the ray until the first sample inside, then
 * `binary_steps` halvings of that bracket, then one secant step between the bracket's ends
 * (exact where the surface is planar, e.g. h constant). For `count` (1 or 2) batches: writes t
 * of the hit per lane and the bits of the lanes that hit (the others left the shell:
 * silhouette). `curved`: the texture walk scaled by the curvature (relief_lateral_scale);
 * `floor_solid`: the last linear step counts as inside on the lanes whose ray ends on the
 * shell's floor (a height field's floor is solid). */
__attribute__((always_inline)) static inline void
relief_search8_core(const void *field, relief_inside8_fn inside, bool curved, bool floor_solid,
                    const relief_batch *batches, int count, int linear_steps, int binary_steps,
                    v8f *out_t, int *out_hit) {
    /* Two batches are stepped in turn: a binary step's lookup depends on the one before, so
     * one batch alone waits on each gather; interleaved, the processor overlaps the two
     * chains. Each batch's arithmetic is unchanged, so are its results. */
    v8i lanes[2], floor_mask[2], found[2];
    v8f t_lo[2], t_hi[2], f_lo[2], f_hi[2], t_prev[2], f_prev[2];
    int all[2];
    for (int g = 0; g < count; ++g) {
        const relief_batch *batch = &batches[g];
        all[g] = (1 << batch->count) - 1;
        lanes[g] = v8_mask_from_bits(all[g]);
        floor_mask[g] = v8_mask_from_bits(floor_solid ? batch->floor_bits : 0);
        /* t = 0: a texel at full height is hit where the ray enters (h = 1: exactly the
         * mesh). */
        v8f f;
        v8i in = inside(field, batch->x0, batch->y0, v8_splat(0.0f), &f);
        found[g] = (in | v8_mask_from_bits(batch->flat_bits)) & lanes[g];
        t_lo[g] = v8_splat(0.0f), t_hi[g] = v8_splat(0.0f), f_lo[g] = v8_splat(-1.0f);
        f_hi[g] = f;
        t_prev[g] = v8_splat(0.0f), f_prev[g] = f;
    }
    v8f inv_n = v8_splat(1.0f / (float)linear_steps);
    for (int k = 1; k <= linear_steps; ++k) {
        int busy = 0;
        for (int g = 0; g < count; ++g) {
            if (v8_mask_bits(found[g]) == all[g]) continue;
            busy = 1;
            const relief_batch *batch = &batches[g];
            v8f t = batch->t_end * ((float)k * inv_n);
            v8f d = t * (batch->a - batch->b * t);
            v8f tt = curved ? t * relief_lateral_scale(batch, d) : t;
            v8f f;
            v8i below =
                inside(field, batch->x0 + batch->xd * tt, batch->y0 + batch->yd * tt, d, &f);
            if (k == linear_steps) below |= floor_mask[g]; /* d = 1 there, whatever rounding */
            v8i fresh = below & ~found[g] & lanes[g];
            t_lo[g] = v8_select(fresh, t_prev[g], t_lo[g]);
            f_lo[g] = v8_select(fresh, f_prev[g], f_lo[g]);
            t_hi[g] = v8_select(fresh, t, t_hi[g]);
            f_hi[g] = v8_select(fresh, v8_max(f, v8_splat(0.0f)), f_hi[g]);
            found[g] |= fresh;
            t_prev[g] = t;
            f_prev[g] = f;
        }
        if (!busy) break;
    }
    /* Binary search inside [t_lo, t_hi] (lanes hit at t = 0 have an empty bracket, which a
     * step leaves as it is: a batch with no other lane needs none). */
    bool bracket[2] = {false, false};
    for (int g = 0; g < count; ++g) bracket[g] = v8_mask_bits(t_hi[g] > t_lo[g]) != 0;
    for (int k = 0; k < binary_steps; ++k) {
        for (int g = 0; g < count; ++g) {
            if (!bracket[g]) continue;
            const relief_batch *batch = &batches[g];
            v8f t = (t_lo[g] + t_hi[g]) * 0.5f;
            v8f d = t * (batch->a - batch->b * t);
            v8f tt = curved ? t * relief_lateral_scale(batch, d) : t;
            v8f f;
            v8i below =
                inside(field, batch->x0 + batch->xd * tt, batch->y0 + batch->yd * tt, d, &f);
            t_hi[g] = v8_select(below, t, t_hi[g]);
            f_hi[g] = v8_select(below, f, f_hi[g]);
            t_lo[g] = v8_select(below, t_lo[g], t);
            f_lo[g] = v8_select(below, f_lo[g], f);
        }
    }
    for (int g = 0; g < count; ++g) {
        /* Secant between the bracket's ends: f_lo <= 0 <= f_hi, so w lies in [0, 1] (the clamp
         * only turns -0 into 0, which moves no t). */
        v8f span = f_hi[g] - f_lo[g];
        v8f w = v8_select(span > 1e-12f, -f_lo[g] / v8_max(span, v8_splat(1e-12f)), v8_splat(1.0f));
        w = v8_min(v8_max(w, v8_splat(0.0f)), v8_splat(1.0f));
        v8f t = t_lo[g] + (t_hi[g] - t_lo[g]) * w;
        out_t[g] = v8_select(t_hi[g] <= t_lo[g], t_hi[g], t);
        out_hit[g] = v8_mask_bits(found[g]) & all[g];
    }
}

/* relief_search8_core for one or two batches with `count` a constant, which unrolls the loops
 * over the batches: their state stays in registers. */
__attribute__((always_inline)) static inline void
relief_search8_batches(const void *field, relief_inside8_fn inside, bool curved, bool floor_solid,
                       const relief_batch *batches, int count, int linear_steps, int binary_steps,
                       v8f *out_t, int *out_hit) {
    if (count == 2)
        relief_search8_core(field, inside, curved, floor_solid, batches, 2, linear_steps,
                            binary_steps, out_t, out_hit);
    else
        relief_search8_core(field, inside, curved, floor_solid, batches, 1, linear_steps,
                            binary_steps, out_t, out_hit);
}

/* relief's search on a height field. */
static inline void relief_search8x2(const relief_heights *m, const relief_batch *batches, int count,
                                    int linear_steps, int binary_steps, v8f *out_t, int *out_hit) {
    /* The wrap as a constant (a copy of the map whose `clamp` the compiler sees): the samples
     * skip its test. */
    relief_heights fixed = *m;
    if (m->clamp) {
        fixed.clamp = true;
        relief_search8_batches(&fixed, relief_height_inside8, false, true, batches, count,
                               linear_steps, binary_steps, out_t, out_hit);
    } else {
        fixed.clamp = false;
        relief_search8_batches(&fixed, relief_height_inside8, false, true, batches, count,
                               linear_steps, binary_steps, out_t, out_hit);
    }
}

/* relief_search8x2 on one batch: writes t of the hit per lane, returns the bits of the lanes
 * that hit. */
static inline int relief_search8(const relief_heights *m, const relief_batch *batch,
                                 int linear_steps, int binary_steps, v8f *out_t) {
    int hit;
    relief_search8x2(m, batch, 1, linear_steps, binary_steps, out_t, &hit);
    return hit;
}

/* ---- Shadows ------------------------------------------------------------------------------ */

/* Light rays from the hits of one batch toward one light, in texel-centre coordinates: from
 * (x, y, d) at s = 0 to (x + xd, y + yd, 0) at s = 1, where the ray leaves the shell. The
 * depth along the way is d (1 - s) + bulge s (1 - s): on a curved mesh (the quadric of the
 * view rays, above) the surface falls away from a rising light ray, which so leaves the
 * shell sooner and, between its ends, lies deeper than the straight line (bulge >= 0 when
 * convex); flat: bulge = 0. */
typedef struct relief_shadow_batch {
    int count;
    v8f x, y, d, xd, yd, bulge;
    int active_bits; /* lanes that need a search (lit lanes at d = 0 and dark ones do not) */
} relief_shadow_batch;

/* Depth bias of the shadow test, in shell units: the hit lies on the surface (up to the
 * search's error), and a light ray leaving it must not find it again. */
#define RELIEF_SHADOW_BIAS 0.004f

/* Self-shadowing by a second linear search toward the light (Policarpo & Oliveira 2006 §2.1;
 * for a multilayer map §3.1, last paragraphs, with its inside test): blocked where a sample lies
 * inside by more than the bias. Returns the bits of blocked lanes. */
__attribute__((always_inline)) static inline int relief_shadow_walk8(const void *field,
                                                                     relief_inside8_fn inside,
                                                                     const relief_shadow_batch *s,
                                                                     int steps) {
    int blocked = 0, pending = s->active_bits;
    float inv = 1.0f / (float)steps;
    /* Sample k = steps is on the mesh (d = 0): nothing is above it. */
    for (int k = 1; k < steps && pending; ++k) {
        float frac = (float)k * inv;
        v8f f;
        inside(field, s->x + s->xd * frac, s->y + s->yd * frac,
               (s->d + s->bulge * frac) * (1.0f - frac), &f);
        int bits = v8_mask_bits(f > RELIEF_SHADOW_BIAS) & pending;
        blocked |= bits;
        pending &= ~bits;
    }
    return blocked;
}

/* relief's shadow search on a height field. */
static inline int relief_shadow_search8(const relief_heights *m, const relief_shadow_batch *s,
                                        int steps) {
    relief_heights fixed = *m; /* the wrap as a constant, as in relief_search8x2 */
    if (m->clamp) {
        fixed.clamp = true;
        return relief_shadow_walk8(&fixed, relief_height_inside8, s, steps);
    }
    fixed.clamp = false;
    return relief_shadow_walk8(&fixed, relief_height_inside8, s, steps);
}

/* The maximum mip-map of a height field (Tevs et al. 2008) with per-level tables for lookups
 * of eight lanes at once, each at its own level. */
typedef struct relief_maxmip {
    const meso_minmax_pyramid *pyramid;
    int32_t offset[MESO_MINMAX_MAX_LEVELS]; /* of each level's max array in pyramid->block */
    int32_t width[MESO_MINMAX_MAX_LEVELS], height[MESO_MINMAX_MAX_LEVELS];
    bool power_of_two; /* both sides */
} relief_maxmip;

static inline void relief_maxmip_init(const meso_minmax_pyramid *p, relief_maxmip *out) {
    memset(out, 0, sizeof *out);
    out->pyramid = p;
    for (int l = 0; l < p->num_levels; ++l) {
        out->offset[l] = (int32_t)(p->levels[l].max - p->block);
        out->width[l] = p->levels[l].width;
        out->height[l] = p->levels[l].height;
    }
    int w = p->levels[0].width, h = p->levels[0].height;
    out->power_of_two = (w & (w - 1)) == 0 && (h & (h - 1)) == 0;
}

/* The highest height of the bilinear surface over eight texel-centre boxes [x0, x1] x [y0, y1]
 * (unwrapped coordinates, x0 <= x1): a box's level-0 cells (cell i spans texel centres
 * i..i+1) lie in at most 2 x 2 cells of the first level whose cells are longer than the box.
 * Boxes as long as the field, and on wrapped fields whose sides are not powers of two boxes
 * that cross the tile's seam (their coarser cells do not tile the repeats), get the whole
 * field's maximum. The boxes are widened by a margin far above the rounding of a sample's
 * position (relief_sample8's wrap, the step's product), so every texel a sample inside reads
 * is bounded. */
static inline v8f relief_box_max8(const relief_maxmip *mm, const relief_heights *m, v8f x0, v8f x1,
                                  v8f y0, v8f y1) {
    const meso_minmax_pyramid *p = mm->pyramid;
    int top = p->num_levels - 1, w = m->width, h = m->height;
    float fw = (float)w, fh = (float)h;
    v8f ex = 0.01f + 1e-5f * v8_max(v8_max(x0, -x0), v8_max(x1, -x1));
    v8f ey = 0.01f + 1e-5f * v8_max(v8_max(y0, -y0), v8_max(y1, -y1));
    x0 -= ex, x1 += ex, y0 -= ey, y1 += ey;
    v8i ok = (x1 - x0 < fw) & (y1 - y0 < fh); /* NaN: not ok */
    /* keep the unused lanes' conversions in range */
    x0 = v8_select(ok, x0, v8_splat(0.0f)), x1 = v8_select(ok, x1, v8_splat(0.0f));
    y0 = v8_select(ok, y0, v8_splat(0.0f)), y1 = v8_select(ok, y1, v8_splat(0.0f));
    v8i wmax = v8i_splat(w - 1), hmax = v8i_splat(h - 1), zero = v8i_splat(0);
    v8i i0, i1, j0, j1;
    if (m->clamp) { /* relief_sample8 clamps positions to [0, side - 1] */
        v8f lo = v8_splat(0.0f), wm = v8_splat(fw - 1.0f), hm = v8_splat(fh - 1.0f);
        i0 = __builtin_convertvector(v8_min(v8_max(x0, lo), wm), v8i);
        i1 = __builtin_convertvector(v8_min(v8_max(x1, lo), wm), v8i);
        j0 = __builtin_convertvector(v8_min(v8_max(y0, lo), hm), v8i);
        j1 = __builtin_convertvector(v8_min(v8_max(y1, lo), hm), v8i);
    } else {
        /* the first cell wrapped into the tile (exact for power-of-two sides; otherwise at
         * worst a tile off, which the seam test below sends to the field's maximum), the
         * last one as many cells on, unwrapped */
        v8f fx0 = v8_floor(x0), fy0 = v8_floor(y0);
        v8f wx = fx0 - fw * v8_floor(x0 * (1.0f / fw)), wy = fy0 - fh * v8_floor(y0 * (1.0f / fh));
        i0 = __builtin_convertvector(wx, v8i), j0 = __builtin_convertvector(wy, v8i);
        i1 = i0 + __builtin_convertvector(v8_floor(x1) - fx0, v8i);
        j1 = j0 + __builtin_convertvector(v8_floor(y1) - fy0, v8i);
        /* i0 = -1 only for a box starting within the margin of the seam: cell 0 holds it */
        i0 = (v8i)v8_select(i0 < zero, (v8f)zero, (v8f)i0);
        j0 = (v8i)v8_select(j0 < zero, (v8f)zero, (v8f)j0);
        if (!mm->power_of_two) {
            ok &= (i0 <= wmax) & (j0 <= hmax) & (i1 <= wmax) & (j1 <= hmax);
        }
    }
    v8i span_x = i1 - i0, span_y = j1 - j0;
    if (!m->clamp && mm->power_of_two) i1 &= wmax, j1 &= hmax; /* every level tiles repeats */
    v8i span = (v8i)v8_select(span_x > span_y, (v8f)span_x, (v8f)span_y);
    /* the first level with cells longer than span: floor(log2 span) + 1, from the exponent */
    v8i level = ((v8i) __builtin_convertvector(span, v8f) >> 23) - 126;
    level = (v8i)v8_select(span == zero, (v8f)zero, (v8f)level);
    level = (v8i)v8_select(level > v8i_splat(top), (v8f)v8i_splat(top), (v8f)level);
    level = (v8i)v8_select(ok, (v8f)level, (v8f)v8i_splat(top));
    v8i lw = v8i_gather(mm->width, level), lh = v8i_gather(mm->height, level);
    v8i base = v8i_gather(mm->offset, level);
    v8i ci0 = i0 >> level, ci1 = i1 >> level, cj0 = j0 >> level, cj1 = j1 >> level;
    v8i lwm = lw - 1, lhm = lh - 1;
    ci0 = (v8i)v8_select(ci0 > lwm, (v8f)lwm, (v8f)ci0);
    ci1 = (v8i)v8_select(ci1 > lwm, (v8f)lwm, (v8f)ci1);
    cj0 = (v8i)v8_select(cj0 > lhm, (v8f)lhm, (v8f)cj0);
    cj1 = (v8i)v8_select(cj1 > lhm, (v8f)lhm, (v8f)cj1);
    v8i r0 = base + cj0 * lw, r1 = base + cj1 * lw;
    v8f a = v8_max(v8_gather(p->block, r0 + ci0), v8_gather(p->block, r0 + ci1));
    v8f b = v8_max(v8_gather(p->block, r1 + ci0), v8_gather(p->block, r1 + ci1));
    return v8_max(a, b);
}

/* The lanes of a shadow batch in which no sample of relief_shadow_search8 can find the light
 * blocked, proved without sampling: every sample's depth is at most the light ray's deepest
 * point dmax (of d (1 - s) + bulge s (1 - s) over s in [0, 1]) and its height at most the
 * maximum mip-map's bound over the ray's footprint, so f <= dmax + hmax - 1; where that stays
 * below the bias (less a margin for the samples' float rounding) the search would find
 * nothing. The search is skipped for these lanes, not changed: the same result. Most hits on
 * a raised surface (a brick's top) end here after a few reads instead of `steps` bilinear
 * samples. */
static inline int relief_shadow_clear8(const relief_maxmip *mm, const relief_heights *m,
                                       const relief_shadow_batch *s) {
    v8f xe = s->x + s->xd, ye = s->y + s->yd;
    v8f hmax = relief_box_max8(mm, m, v8_min(s->x, xe), v8_max(s->x, xe), v8_min(s->y, ye),
                               v8_max(s->y, ye));
    v8f d = s->d, b = s->bulge;
    v8i vertex = b > d; /* the parabola's vertex (b - d) / 2b inside (0, 1) */
    v8f dmax =
        v8_select(vertex, d + (b - d) * (b - d) / (4.0f * v8_select(vertex, b, v8_splat(1.0f))), d);
    return v8_mask_bits(dmax + hmax - 1.0f < RELIEF_SHADOW_BIAS - 1e-5f) & s->active_bits;
}

/* ---- Eight fragments as vectors ---------------------------------------------------------- */

/* Up to eight fragments in structure-of-arrays form with their texture-space frame: the dual
 * basis (B x N, N x T, T x B) / det writes a world direction D as (du, dv, dn) with
 * D = du T + dv B + dn N by three dot products (relief_frame_solve, eight at once). Lanes past
 * `count` repeat lane 0, so every lane holds finite values. */
typedef struct relief_lanes {
    int count;
    v8vec3 position, normal, tangent, bitangent, view;
    v8vec3 bn, nt, tb; /* dual basis, divided by det */
    v8f u, v, depth;
    int frame_bits; /* lanes whose frame is not degenerate */
} relief_lanes;

/* The view vector and the dual basis of loaded lanes (relief_lanes). */
static inline void relief_lanes_basis(relief_lanes *l, const meso_frame *frame) {
    int count = l->count;
    v8vec3 eye = v8_splat3(frame->eye);
    l->view = (v8vec3){l->position.x - eye.x, l->position.y - eye.y, l->position.z - eye.z};
    v8vec3 bn = v8_cross(l->bitangent, l->normal), nt = v8_cross(l->normal, l->tangent);
    v8vec3 tb = v8_cross(l->tangent, l->bitangent);
    v8f det = v8_dot(l->tangent, bn);
    v8i ok = (det > 1e-20f) | (det < -1e-20f);
    l->frame_bits = v8_mask_bits(ok) & ((1 << count) - 1);
    v8f inv = v8_select(ok, 1.0f / v8_select(ok, det, v8_splat(1.0f)), v8_splat(0.0f));
    l->bn = (v8vec3){bn.x * inv, bn.y * inv, bn.z * inv};
    l->nt = (v8vec3){nt.x * inv, nt.y * inv, nt.z * inv};
    l->tb = (v8vec3){tb.x * inv, tb.y * inv, tb.z * inv};
}

static inline void relief_lanes_load(relief_lanes *l, const meso_frame *frame,
                                     const meso_fragment *f, int count) {
    l->count = count;
    for (int k = 0; k < RELIEF_LANES; ++k) {
        const meso_fragment *g = &f[k < count ? k : 0];
        l->position.x[k] = g->position.x;
        l->position.y[k] = g->position.y;
        l->position.z[k] = g->position.z;
        l->normal.x[k] = g->normal.x;
        l->normal.y[k] = g->normal.y;
        l->normal.z[k] = g->normal.z;
        l->tangent.x[k] = g->tangent.x;
        l->tangent.y[k] = g->tangent.y;
        l->tangent.z[k] = g->tangent.z;
        l->bitangent.x[k] = g->bitangent.x;
        l->bitangent.y[k] = g->bitangent.y;
        l->bitangent.z[k] = g->bitangent.z;
        l->u[k] = g->uv.x;
        l->v[k] = g->uv.y;
        l->depth[k] = g->depth;
    }
    relief_lanes_basis(l, frame);
}

/* relief_lanes_load from lanes first..first+7 of a block (render_internal.h): the same values,
 * read as vectors; the block's padding lanes repeat its last fragment instead of lane 0. */
static inline void relief_lanes_load_block(relief_lanes *l, const meso_frame *frame,
                                           const meso_fragment_block *b, size_t first) {
    l->count = b->count - first < RELIEF_LANES ? (int)(b->count - first) : RELIEF_LANES;
    l->position = (v8vec3){meso_block_load(b->px, first), meso_block_load(b->py, first),
                           meso_block_load(b->pz, first)};
    l->normal = (v8vec3){meso_block_load(b->nx, first), meso_block_load(b->ny, first),
                         meso_block_load(b->nz, first)};
    l->tangent = (v8vec3){meso_block_load(b->tx, first), meso_block_load(b->ty, first),
                          meso_block_load(b->tz, first)};
    l->bitangent = (v8vec3){meso_block_load(b->bx, first), meso_block_load(b->by, first),
                            meso_block_load(b->bz, first)};
    l->u = meso_block_load(b->u, first), l->v = meso_block_load(b->v, first);
    l->depth = meso_block_load(b->depth, first);
    relief_lanes_basis(l, frame);
}

/* The view vector along the fragments' unit tangent and bitangent, which the silhouettes' ray
 * (relief_batch_setup), the turn of the normal (relief_curve_normal8) and every light's shadow
 * ray read: worked out once a group of eight, not once a use (the same operations, so the same
 * bits). */
typedef struct relief_axes {
    v8f tl, bl; /* |T|, |B| */
    v8f vt, vb; /* V.T, V.B */
    v8f x, y;   /* V.T / |T|, V.B / |B| (0 where the length is 0) */
} relief_axes;

static inline void relief_axes_init(const relief_lanes *l, relief_axes *a) {
    v8f zero = v8_splat(0.0f);
    a->tl = v8_sqrt(v8_dot(l->tangent, l->tangent));
    a->bl = v8_sqrt(v8_dot(l->bitangent, l->bitangent));
    a->vt = v8_dot(l->view, l->tangent);
    a->vb = v8_dot(l->view, l->bitangent);
    a->x = v8_select(a->tl > 0.0f, a->vt / a->tl, zero);
    a->y = v8_select(a->bl > 0.0f, a->vb / a->bl, zero);
}

/* Texel-centre coordinates of the fragments' uv. */
static inline void relief_lanes_texel(const relief_heights *m, const relief_lanes *l, v8f *x,
                                      v8f *y) {
    *x = l->u * (float)m->width - 0.5f;
    *y = (1.0f - l->v) * (float)m->height - 0.5f;
}

/* The gradient (dh/du, dh/dv) at texel-centre coordinates: meso_heightfield_gradient's
 * central differences one texel apart, eight at once. */
static inline void relief_gradient8(const relief_heights *m, v8f x, v8f y, v8f *gu, v8f *gv) {
#if defined(__AVX2__)
    /* The four samples read texels of the 4 x 4 block from (i - 1, j - 1): (x +- 1, y) rows j
     * and j + 1, (x, y - 1) rows j - 1 and j, (x, y + 1) rows j + 1 and j + 2, every one in the
     * columns i - 1 .. i + 2. Where no lane wraps inside that block, four 16-byte loads a lane
     * read it all instead of two quad loads and eight pair gathers; the same texels and
     * fractions, so the same bits (the gathers were a fifth of parallax's time). */
    v8i ir, jr, il, jl, iu, ju, id, jd;
    v8f txr, tyr, txl, tyl, txu, tyu, txd, tyd;
    relief_texel8(m, x + 1.0f, y, &ir, &jr, &txr, &tyr);
    relief_texel8(m, x - 1.0f, y, &il, &jl, &txl, &tyl);
    relief_texel8(m, x, y - 1.0f, &iu, &ju, &txu, &tyu);
    relief_texel8(m, x, y + 1.0f, &id, &jd, &txd, &tyd);
    v8i column = il + 1;
    /* the padded field holds columns and rows 0..width and 0..height */
    v8i inside =
        (il <= v8i_splat(m->width - 3)) & (jl >= v8i_splat(1)) & (jl <= v8i_splat(m->height - 2));
    v8i unwrapped = (ir == il + 2) & (jr == jl) & (iu == column) & (id == column) & (ju == jl - 1) &
                    (jd == jl + 1);
    if (v8_mask_bits(inside & unwrapped) == 0xff) {
        v8i index = (jl - 1) * m->stride + il;
        v8f above[4], row0[4], row1[4], below[4];
        relief_load_quads8(m->padded, index, above);
        relief_load_quads8(m->padded + m->stride, index, row0);
        relief_load_quads8(m->padded + 2 * m->stride, index, row1);
        relief_load_quads8(m->padded + 3 * m->stride, index, below);
        v8f right = relief_bilinear8(row0[2], row0[3], row1[2], row1[3], txr, tyr);
        v8f left = relief_bilinear8(row0[0], row0[1], row1[0], row1[1], txl, tyl);
        v8f up = relief_bilinear8(above[1], above[2], row0[1], row0[2], txu, tyu);
        v8f down = relief_bilinear8(row1[1], row1[2], below[1], below[2], txd, tyd);
        *gu = (right - left) * (0.5f * (float)m->width);
        *gv = (up - down) * (0.5f * (float)m->height);
        return;
    }
#endif
    v8f right, left;
    relief_sample8_beside(m, x, y, &right, &left);
    *gu = (right - left) * (0.5f * (float)m->width);
    *gv = (relief_sample8(m, x, y - 1.0f) - relief_sample8(m, x, y + 1.0f)) *
          (0.5f * (float)m->height);
}

/* meso_displaced_normal eight at once: normalize(cross(T + depth h_u N, B + depth h_v N)),
 * turned to N's side. A zero gradient keeps the interpolated normal itself, so a flat field
 * draws exactly the `flat` image. */
static inline v8vec3 relief_normal8(const relief_lanes *l, float depth, v8f gu, v8f gv) {
    v8vec3 du = v8_madd(l->tangent, l->normal, gu * depth);
    v8vec3 dv = v8_madd(l->bitangent, l->normal, gv * depth);
    v8vec3 n = v8_cross(du, dv);
    v8f len2 = v8_dot(n, n);
    v8i ok = (len2 > 1e-30f) & (len2 < 1e30f);
    v8f inv = 1.0f / v8_sqrt(v8_select(ok, len2, v8_splat(1.0f)));
    inv = v8_select(v8_dot(n, l->normal) < 0.0f, -inv, inv);
    v8i keep = ~ok | ((gu == 0.0f) & (gv == 0.0f));
    return (v8vec3){v8_select(keep, l->normal.x, n.x * inv),
                    v8_select(keep, l->normal.y, n.y * inv),
                    v8_select(keep, l->normal.z, n.z * inv)};
}

/* relief_bump_loaded_lanes but for the lights' visibility, which a caller shading every light
 * visible sets once for all its groups. */
static inline void relief_bump_inputs(const relief_heights *m, float depth, const relief_lanes *l,
                                      v8f *x, v8f *y, meso_shade_batch *in) {
    v8f gu, gv;
    relief_lanes_texel(m, l, x, y);
    relief_gradient8(m, *x, *y, &gu, &gv);
    v8vec3 normal = relief_normal8(l, depth, gu, gv);
    /* field by field: a compound literal would also zero the 16 lights' visibility (a
     * 512-byte memset a group) that meso_shade_batch_all_visible sets for the scene's lights */
    in->px = l->position.x, in->py = l->position.y, in->pz = l->position.z;
    in->nx = normal.x, in->ny = normal.y, in->nz = normal.z;
    in->u = l->u, in->v = l->v;
    in->tx = l->tangent.x, in->ty = l->tangent.y, in->tz = l->tangent.z;
    in->bx = l->bitangent.x, in->by = l->bitangent.y, in->bz = l->bitangent.z;
}

/* relief_bump_lanes on lanes already loaded (relief_lanes_load, relief_lanes_load_block). */
static inline void relief_bump_loaded_lanes(const relief_heights *m, const meso_frame *frame,
                                            float depth, const relief_lanes *l, v8f *x, v8f *y,
                                            meso_shade_batch *in) {
    relief_bump_inputs(m, depth, l, x, y, in);
    meso_shade_batch_all_visible(in, frame);
}

/* Up to eight fragments with the bump-mapped normal at their own uv (Blinn 1978; no shift):
 * lanes loaded, texel-centre coordinates in *x, *y, and the shading inputs in *in with every
 * light visible. bump draws this as is; horizon adds its visibility. */
static inline void relief_bump_lanes(const relief_heights *m, const meso_frame *frame,
                                     const meso_fragment *f, int count, float depth,
                                     relief_lanes *l, v8f *x, v8f *y, meso_shade_batch *in) {
    relief_lanes_load(l, frame, f, count);
    relief_bump_loaded_lanes(m, frame, depth, l, x, y, in);
}

/* Shade the lanes of `in` and write the colours of the first `count` fragments. */
static inline void relief_shade_store(const meso_frame *frame, const meso_object *object,
                                      const meso_shade_batch *in, meso_fragment *f, int count) {
    v8f r, g, b;
    meso_shade_batch8_fragments(frame, object, in, f, count, &r, &g, &b);
    for (int k = 0; k < count; ++k) f[k].color = (meso_vec3){r[k], g[k], b[k]};
}

/* The displaced normal n, found in the frame of the fragment where the ray entered, carried
 * to the hit t V away on the curved mesh: the quadric surface -(qa x^2 + qb y^2) has the
 * normal N + 2 qa x T^ + 2 qb y B^ (unnormalised) at (x, y), so every normal there is turned
 * by the rotation that takes N to it (small angle: n + (N_hit - N), renormalised). Flat
 * meshes (q = 0) keep n. Without it a sphere is shaded as if every hit faced the entry's
 * way: a uniform error over its lit side (docs/techniques/relief.md). */
static inline v8vec3 relief_curve_normal8(const relief_lanes *l, const relief_axes *axes,
                                          const relief_batch *batch, v8f t, v8vec3 n) {
    v8f tl = axes->tl, bl = axes->bl;
    v8f zero = v8_splat(0.0f);
    v8f it = v8_select(tl > 0.0f, 1.0f / v8_select(tl > 0.0f, tl, v8_splat(1.0f)), zero);
    v8f ib = v8_select(bl > 0.0f, 1.0f / v8_select(bl > 0.0f, bl, v8_splat(1.0f)), zero);
    /* (x, y) of the hit from the entry, world units along T^ and B^; the turn 2 q (x, y) */
    v8f sx = 2.0f * batch->qa * t * axes->vt * it * it;
    v8f sy = 2.0f * batch->qb * t * axes->vb * ib * ib;
    v8vec3 turned = {n.x + l->tangent.x * sx + l->bitangent.x * sy,
                     n.y + l->tangent.y * sx + l->bitangent.y * sy,
                     n.z + l->tangent.z * sx + l->bitangent.z * sy};
    v8f inv = 1.0f / v8_sqrt(v8_max(v8_dot(turned, turned), v8_splat(1e-30f)));
    return (v8vec3){turned.x * inv, turned.y * inv, turned.z * inv};
}

/* ---- The relief family's fragment loop ---------------------------------------------------- */

/* The tracer of one variant: its search for the view rays and its shadow test, each given
 * `count` (1 or 2) batches of eight rays at once, so a tracer whose steps are chains of
 * dependent operations can interleave two batches. */
typedef struct relief_tracer {
    const void *user;
    /* Per batch: t of the hit per lane and the bits of lanes that hit. */
    void (*search)(const void *user, const relief_batch *batches, int count, v8f *out_t,
                   int *out_hit);
    /* Per batch: the bits of blocked lanes (batches may have no active lane). */
    void (*shadow)(const void *user, const relief_shadow_batch *batches, int count,
                   int *out_blocked);
    /* Optional (NULL: the height field's gradient, relief_normal8): the unit world normal at
     * the hits (hx, hy) in texel-centre coordinates, depth hd, ray parameter t, of one batch.
     * relief_layers reads its baked layer normals here (Policarpo & Oliveira 2006 §3). */
    void (*normal)(const void *user, const relief_lanes *lanes, const relief_batch *batch, v8f t,
                   v8f hx, v8f hy, v8f hd, float depth, v8vec3 *out_normal);
} relief_tracer;

/* Fill the domain (geom.h, meso_mesh_uv_domain: the UV box's sides that are open borders, where
 * a ray leaves the shell and a hit past them is a miss, not the next tile of a repeating map). */
static inline meso_result relief_domain_init(meso_context *ctx, const meso_object *object,
                                             meso_uv_domain *out) {
    *out = (meso_uv_domain){0};
    if (!object->mesh || meso_mesh_uv_domain(object->mesh, out)) return MESO_OK;
    return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", object->name);
}

/* The lanes whose texture point (u, v) lies inside the domain's open sides. */
static inline int relief_domain_inside8(const meso_uv_domain *d, v8f u, v8f v) {
    v8i in = v8_mask_from_bits(0xff);
    if (d->sides & MESO_UV_DOMAIN_U_MIN) in &= u >= d->u_min;
    if (d->sides & MESO_UV_DOMAIN_U_MAX) in &= u <= d->u_max;
    if (d->sides & MESO_UV_DOMAIN_V_MIN) in &= v >= d->v_min;
    if (d->sides & MESO_UV_DOMAIN_V_MAX) in &= v <= d->v_max;
    return v8_mask_bits(in);
}

typedef struct relief_params {
    bool shadows, silhouettes;
    /* Beyond the papers (relief_layers): on a curved mesh the shell at depth w is a smaller
     * (convex) or larger copy of the surface, so a ray's texture coordinates advance faster
     * there than the tangent-plane walk says: by 1 / (1 - kappa w depth) with kappa the
     * curvature along the ray (twice the quadric, Oliveira & Policarpo 2005), averaged from 0
     * to the ray's depth d as 1 / (1 - kappa d depth / 2). */
    bool curved_uv;
    meso_uv_domain domain; /* hits past its open sides miss */
} relief_params;

/* The view rays of eight fragments (see the top of this file). */
static inline void relief_batch_setup(const relief_heights *m, const meso_object *object,
                                      const meso_fragment *f, const meso_fragment_block *block,
                                      size_t first, const relief_lanes *l, const relief_axes *axes,
                                      bool silhouettes, bool curved_uv, relief_batch *batch,
                                      v8f *out_du, v8f *out_dv) {
    float depth = object->mesostructure.depth;
    int all = (1 << l->count) - 1;
    v8f cu = v8_dot(l->view, l->bn), cv = v8_dot(l->view, l->nt), cn = v8_dot(l->view, l->tb);
    int enter = depth > 0.0f ? v8_mask_bits(cn < 0.0f) & l->frame_bits : 0;
    v8i on = v8_mask_from_bits(enter);
    v8f zero = v8_splat(0.0f);
    /* every field is set below; these stay 0 without silhouettes (a memset of the whole
     * batch cost more than the rest of the setup's stores) */
    batch->qa = zero, batch->qb = zero, batch->b = zero, batch->lateral = zero;
    batch->count = l->count;
    relief_lanes_texel(m, l, &batch->x0, &batch->y0);
    cu = v8_select(on, cu, zero);
    cv = v8_select(on, cv, zero);
    batch->xd = cu * (float)m->width;
    batch->yd = -cv * (float)m->height;
    float inv_depth = depth > 0.0f ? 1.0f / depth : 0.0f;
    batch->a = v8_select(on, -cn * inv_depth, zero);
    v8f qa, qb;
    if (silhouettes && relief_quadrics8(object, f, block, first, l->count, &qa, &qb)) {
        batch->qa = qa;
        batch->qb = qb;
        v8f x = axes->x, y = axes->y;
        batch->b = v8_select(on, (qa * x * x + qb * y * y) * inv_depth, zero);
        if (curved_uv) { /* kappa depth / 2 along the ray, kept below 0.9 (relief_params) */
            v8f r2 = x * x + y * y;
            v8f lateral = (qa * x * x + qb * y * y) * depth / v8_max(r2, v8_splat(1e-30f));
            lateral = v8_min(v8_max(lateral, v8_splat(-0.9f)), v8_splat(0.9f));
            batch->lateral = v8_select(on & (r2 > 0.0f), lateral, zero);
        }
    }
    /* d(t) = 1 at the smaller root of b t^2 - a t + 1 = 0 (stable for b -> 0); without a real
     * root the convex shell is left at t = a / b. */
    v8f disc = batch->a * batch->a - 4.0f * batch->b;
    v8i floor_mask = disc >= 0.0f;
    v8f t_floor = 2.0f / (batch->a + v8_sqrt(v8_max(disc, zero)));
    v8f t_exit = batch->a / v8_select(floor_mask, v8_splat(1.0f), batch->b);
    batch->t_end = v8_select(on, v8_select(floor_mask, t_floor, t_exit), zero);
    batch->floor_bits = v8_mask_bits(floor_mask) & enter;
    batch->flat_bits = all & ~enter;
    *out_du = cu;
    *out_dv = cv;
}

/* The colours of RELIEF_SHADE_GROUPS groups of a block at once (the shading's per-object
 * constants once a call, not once a group): in[g] holds lanes first + 8g.., hit[g] the bits of
 * its lanes that hit. The lanes that did not hit keep the colour they had, as the array path
 * leaves a discarded fragment's. */
static inline void relief_shade_groups_to_block(const meso_frame *frame, const meso_object *object,
                                                const meso_shade_batch *in, const int *hit,
                                                size_t groups, meso_fragment_block *block,
                                                size_t first) {
    v8f keep[RELIEF_SHADE_GROUPS][3];
    for (size_t g = 0; g < groups; ++g) {
        if (hit[g] == 0xff) continue;
        size_t at = first + g * RELIEF_LANES;
        keep[g][0] = meso_block_load(block->r, at), keep[g][1] = meso_block_load(block->g, at);
        keep[g][2] = meso_block_load(block->b, at);
    }
    meso_shade_batches_to_block(frame, object, in, groups, block, first);
    for (size_t g = 0; g < groups; ++g) {
        if (hit[g] == 0xff) continue;
        size_t at = first + g * RELIEF_LANES;
        v8i on = v8_mask_from_bits(hit[g]);
        meso_block_store(block->r, at, v8_select(on, meso_block_load(block->r, at), keep[g][0]));
        meso_block_store(block->g, at, v8_select(on, meso_block_load(block->g, at), keep[g][1]));
        meso_block_store(block->b, at, v8_select(on, meso_block_load(block->b, at), keep[g][2]));
    }
}

/* Shade `count` fragments with a tracer, sixteen at a time (m: the map's size in texels for
 * the texel-centre coordinates, and the heights unless the tracer has its own normal) as two
 * batches of eight: view rays, hits, depth correction, the displaced normal at the hit,
 * self-shadows per light, the shading model. The fragments are an array (`fragments`) or a
 * block (`block`, the other NULL): the same lanes and arithmetic either way, so the same
 * images; a block saves the adapter's copies and reads the lanes as vectors. */
__attribute__((always_inline)) static inline void
relief_shade_core(const relief_heights *m, const relief_tracer *tracer, relief_params params,
                  const meso_frame *frame, const meso_object *object, meso_fragment *fragments,
                  meso_fragment_block *block, size_t count) {
    const meso_scene *scene = frame->scene;
    int num_lights =
        scene->num_lights < MESO_SCENE_MAX_LIGHTS ? scene->num_lights : MESO_SCENE_MAX_LIGHTS;
    float depth = object->mesostructure.depth;
    /* a block's shading inputs, shaded RELIEF_SHADE_GROUPS groups a call */
    _Static_assert(RELIEF_SHADE_GROUPS % 2 == 0, "whole pairs of groups");
    meso_shade_batch pending[RELIEF_SHADE_GROUPS];
    int pending_hit[RELIEF_SHADE_GROUPS];
    size_t pending_groups = 0, pending_first = 0;
    for (size_t start = 0; start < count; start += 2 * RELIEF_LANES) {
        if (block && pending_groups == RELIEF_SHADE_GROUPS) {
            relief_shade_groups_to_block(frame, object, pending, pending_hit, pending_groups, block,
                                         pending_first);
            pending_groups = 0;
        }
        if (!pending_groups) pending_first = start;
        relief_lanes l[2];
        relief_axes axes[2];
        relief_batch batch[2];
        v8f du[2], dv[2], t[2], hx[2], hy[2], hd[2], out_depth[2], hit_u[2], hit_v[2];
        v8vec3 hit_pos[2], normal[2];
        int hit[2], n[2], groups = 0;
        for (int g = 0; g < 2; ++g) {
            size_t first = start + (size_t)g * RELIEF_LANES;
            if (first >= count) break;
            n[g] = count - first < RELIEF_LANES ? (int)(count - first) : RELIEF_LANES;
            if (block)
                relief_lanes_load_block(&l[g], frame, block, first);
            else
                relief_lanes_load(&l[g], frame, fragments + first, n[g]);
            if (params.silhouettes || params.shadows) relief_axes_init(&l[g], &axes[g]);
            relief_batch_setup(m, object, block ? NULL : fragments + first, block, first, &l[g],
                               &axes[g], params.silhouettes, params.curved_uv, &batch[g], &du[g],
                               &dv[g]);
            groups = g + 1;
        }
        tracer->search(tracer->user, batch, groups, t, hit);
        for (int g = 0; g < groups; ++g) {
            /* The hits in texel space, their depth d and the gradient there. */
            hd[g] = v8_max(t[g] * (batch[g].a - batch[g].b * t[g]), v8_splat(0.0f));
            v8f tt = params.curved_uv ? t[g] * relief_lateral_scale(&batch[g], hd[g]) : t[g];
            hx[g] = batch[g].x0 + batch[g].xd * tt;
            hy[g] = batch[g].y0 + batch[g].yd * tt;
            hit_pos[g] = v8_madd(l[g].position, l[g].view, t[g]);
            hit_u[g] = l[g].u + du[g] * tt;
            hit_v[g] = l[g].v + dv[g] * tt;
            if (params.domain.sides)
                hit[g] &= relief_domain_inside8(&params.domain, hit_u[g], hit_v[g]);
            out_depth[g] = l[g].depth * (1.0f + t[g]); /* dot(P + t V - eye, forward) */
            if (tracer->normal) {
                tracer->normal(tracer->user, &l[g], &batch[g], t[g], hx[g], hy[g], hd[g], depth,
                               &normal[g]);
            } else {
                v8f gu, gv;
                relief_gradient8(m, hx[g], hy[g], &gu, &gv);
                normal[g] = relief_normal8(&l[g], depth, gu, gv);
            }
            if (params.silhouettes)
                normal[g] = relief_curve_normal8(&l[g], &axes[g], &batch[g], t[g], normal[g]);
        }
        meso_shade_batch local[2];
        meso_shade_batch *in = block ? pending + pending_groups : local;
        for (int li = 0; li < num_lights; ++li) {
            relief_shadow_batch sb[2];
            int dark[2] = {0, 0}, any = 0;
            for (int g = 0; g < groups; ++g) {
                sb[g].count = n[g];
                if (!params.shadows || !hit[g]) {
                    memset(&sb[g], 0, sizeof sb[g]); /* no lane active */
                    sb[g].count = n[g];
                    continue;
                }
                const meso_light *light = &scene->lights[li];
                v8vec3 L;
                if (light->type == MESO_LIGHT_DIRECTIONAL) {
                    L = v8_splat3(light->direction);
                } else {
                    v8vec3 p = v8_splat3(light->position);
                    L = (v8vec3){p.x - hit_pos[g].x, p.y - hit_pos[g].y, p.z - hit_pos[g].z};
                    v8f inv = 1.0f / v8_sqrt(v8_max(v8_dot(L, L), v8_splat(1e-30f)));
                    L = (v8vec3){L.x * inv, L.y * inv, L.z * inv};
                }
                v8f lu = v8_dot(L, l[g].bn), lv = v8_dot(L, l[g].nt), ln = v8_dot(L, l[g].tb);
                /* The light ray leaves the shell where d(s) = hd - (ln s + q s^2) / depth
                 * reaches 0 (s in world units along L, q = qa xL^2 + qb yL^2 the quadric
                 * along L, as the view rays' b): s_out = 2 hd depth / (ln + sqrt(ln^2 +
                 * 4 q hd depth)). On a convex mesh that can be so even for a light a little
                 * below the tangent plane (the band past the terminator the truth still
                 * lights); without a real positive root the surface itself blocks the light. */
                v8f tl = axes[g].tl, bl = axes[g].bl;
                v8f xl = v8_select(tl > 0.0f, v8_dot(L, l[g].tangent) / tl, v8_splat(0.0f));
                v8f yl = v8_select(bl > 0.0f, v8_dot(L, l[g].bitangent) / bl, v8_splat(0.0f));
                v8f q = batch[g].qa * xl * xl + batch[g].qb * yl * yl;
                /* The light's elevation over the tangent plane at the hit, not at the entry:
                 * the hit lies t V away, where the curved surface has turned by 2 q. */
                v8f xv = axes[g].x, yv = axes[g].y;
                ln += 2.0f * t[g] * (batch[g].qa * xv * xl + batch[g].qb * yv * yl);
                v8f reach = hd[g] * depth;
                v8f disc = ln * ln + 4.0f * q * reach;
                v8f denominator = ln + v8_sqrt(v8_max(disc, v8_splat(0.0f)));
                v8i leaves = (disc >= 0.0f) & (denominator > 0.0f);
                /* hit at the top (hd = 0): lit exactly when the light is above the plane */
                v8i top = hd[g] <= 0.0f;
                leaves = (leaves & ~top) | ((ln > 0.0f) & top);
                int up = v8_mask_bits(leaves) & l[g].frame_bits;
                dark[g] = hit[g] & ~up;
                sb[g].active_bits = hit[g] & up & v8_mask_bits(hd[g] > 0.0f);
                v8f s = 2.0f * reach / v8_select(leaves, denominator, v8_splat(1.0f));
                sb[g].x = hx[g];
                sb[g].y = hy[g];
                sb[g].d = hd[g];
                sb[g].bulge = v8_select(leaves, q * s * s / depth, v8_splat(0.0f));
                sb[g].xd = lu * s * (float)m->width;
                sb[g].yd = -lv * s * (float)m->height;
                any |= sb[g].active_bits;
            }
            if (any) {
                int blocked[2] = {0, 0};
                tracer->shadow(tracer->user, sb, groups, blocked);
                for (int g = 0; g < groups; ++g) dark[g] |= blocked[g] & sb[g].active_bits;
            }
            for (int g = 0; g < groups; ++g)
                in[g].visibility[li] =
                    v8_select(v8_mask_from_bits(dark[g]), v8_splat(0.0f), v8_splat(1.0f));
        }
        for (int g = 0; g < groups; ++g) {
            size_t first = start + (size_t)g * RELIEF_LANES;
            in[g].px = hit_pos[g].x, in[g].py = hit_pos[g].y, in[g].pz = hit_pos[g].z;
            in[g].nx = normal[g].x, in[g].ny = normal[g].y, in[g].nz = normal[g].z;
            in[g].u = hit_u[g], in[g].v = hit_v[g];
            in[g].tx = l[g].tangent.x, in[g].ty = l[g].tangent.y, in[g].tz = l[g].tangent.z;
            in[g].bx = l[g].bitangent.x, in[g].by = l[g].bitangent.y;
            in[g].bz = l[g].bitangent.z;
            if (block) { /* the colours when the pending groups are shaded */
                pending_hit[pending_groups++] = hit[g];
                if (hit[g] == 0xff) { /* eight fragments, none discarded */
                    meso_block_store(block->out_depth, first, out_depth[g]);
                    continue;
                }
                for (int k = 0; k < n[g]; ++k) {
                    size_t i = first + (size_t)k;
                    if (!(hit[g] >> k & 1)) /* the ray left the curved shell */
                        block->discard[i] = 1;
                    else
                        block->out_depth[i] = out_depth[g][k];
                }
                continue;
            }
            v8f r, gr, b;
            meso_shade_batch8_fragments(frame, object, &in[g], fragments + first, n[g], &r, &gr,
                                        &b);
            for (int k = 0; k < n[g]; ++k) {
                bool discard = !(hit[g] >> k & 1); /* the ray left the curved shell */
                meso_fragment *f = fragments + first + (size_t)k;
                if (discard) {
                    f->discard = true;
                    continue;
                }
                f->out_depth = out_depth[g][k];
                f->color = (meso_vec3){r[k], gr[k], b[k]};
            }
        }
    }
    if (block && pending_groups)
        relief_shade_groups_to_block(frame, object, pending, pending_hit, pending_groups, block,
                                     pending_first);
}

static inline void relief_shade_fragments(const relief_heights *m, const relief_tracer *tracer,
                                          relief_params params, const meso_frame *frame,
                                          const meso_object *object, meso_fragment *fragments,
                                          size_t count) {
    relief_shade_core(m, tracer, params, frame, object, fragments, NULL, count);
}

/* relief_shade_fragments on a block (render_internal.h's shade_block). */
static inline void relief_shade_block(const relief_heights *m, const relief_tracer *tracer,
                                      relief_params params, const meso_frame *frame,
                                      const meso_object *object, meso_fragment_block *block) {
    relief_shade_core(m, tracer, params, frame, object, NULL, block, block->count);
}

#endif
