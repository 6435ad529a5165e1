/* displace_shade (displace_common.c) eight fragments at a time, straight from the rasterizer's
 * blocks (render_internal.h, meso_fragment_block): the height field's gradient, the displaced
 * normal, the face normal, the shadow maps' 2 x 2 percentage-closer lookup and the shading
 * model, each lane with the scalar code's operations in its order (-ffp-contract=off), so the
 * bits are the same. Through the per-fragment adapter every fragment would be copied out of the
 * block and back, its gradient and shadow lookup taken one at a time, and the shading model's
 * inputs gathered again from the copies: a large part of a displacement frame.
 *
 * Static inline, for the technique files: a portable build compiles them twice (baseline and
 * AVX2, CMakeLists.txt), so this code runs on single AVX instructions where the CPU has them. */
#ifndef MESO_DISPLACE_SHADE8_H
#define MESO_DISPLACE_SHADE8_H

#include "displace_common.h"
#include "render_shading.h"
#include "render_simd.h"

/* Groups of eight shaded by one call of the shading model (its per-object constants once). */
#define DISPLACE_SHADE_GROUPS 8

/* base[index[k]] per lane by eight scalar loads. Not the AVX2 gather (v8_gather): on an AMD
 * EPYC the gathers made a one-thread displacement frame slower than these loads (meso bench),
 * although callgrind counts a gather as one instruction. */
static inline v8f displace_gather8(const float *base, v8i index) {
    v8f r;
    for (int k = 0; k < V8_LANES; ++k) r[k] = base[index[k]];
    return r;
}
static inline v8i displace_gather8i(const uint32_t *base, v8i index) {
    v8i r;
    for (int k = 0; k < V8_LANES; ++k) r[k] = (int32_t)base[index[k]];
    return r;
}

/* Finite in every component (a NaN or an infinity times 0 is NaN). */
static inline v8i displace_finite8(v8vec3 a) {
    return (a.x * 0.0f == 0.0f) & (a.y * 0.0f == 0.0f) & (a.z * 0.0f == 0.0f);
}

/* One bilinear sample of the height field at texel-centre coordinates (x, y) per lane:
 * meso_heightfield_sample after its texel coordinates, with meso_heightfield_wrap_pair. */
static inline v8f displace_sample8(const meso_heightfield *hf, v8f x, v8f y) {
    v8f fx = v8_floor(x), fy = v8_floor(y);
    v8f tx = x - fx, ty = y - fy;
    v8i ix = __builtin_convertvector(fx, v8i), iy = __builtin_convertvector(fy, v8i);
    v8i i0 = ix, i1 = ix + 1, j0 = iy, j1 = iy + 1;
    /* inside the field (the common case): the texel and its right and lower neighbours */
    v8i inside = ((ix >= 0) & (ix < hf->width - 1)) & ((iy >= 0) & (iy < hf->height - 1));
    if (v8_mask_bits(inside) != 0xff) {
        for (int k = 0; k < V8_LANES; k++) {
            int a0, a1, b0, b1;
            meso_heightfield_wrap_pair(hf->wrap, ix[k], hf->width, &a0, &a1);
            meso_heightfield_wrap_pair(hf->wrap, iy[k], hf->height, &b0, &b1);
            i0[k] = a0, i1[k] = a1, j0[k] = b0, j1[k] = b1;
        }
    }
    v8i row0 = j0 * hf->width, row1 = j1 * hf->width;
    v8f h00 = displace_gather8(hf->heights, row0 + i0),
        h10 = displace_gather8(hf->heights, row0 + i1);
    v8f h01 = displace_gather8(hf->heights, row1 + i0),
        h11 = displace_gather8(hf->heights, row1 + i1);
    v8f top = h00 + (h10 - h00) * tx, bottom = h01 + (h11 - h01) * tx;
    return top + (bottom - top) * ty;
}

/* displace_gradient per lane: central differences one texel apart at the texture uv (u, v
 * modulo 1 with repeat wrapping), as displace_heightfield_gradient computes them. */
static inline void displace_gradient8(const displace_surface *surface, v8f u, v8f v, v8f *out_gu,
                                      v8f *out_gv) {
    const meso_heightfield *hf = surface->heightfield;
    if (surface->repeat) u = u - v8_floor(u), v = v - v8_floor(v);
    float du = 1.0f / (float)hf->width, dv = 1.0f / (float)hf->height;
    float w = (float)hf->width, h = (float)hf->height;
    v8f x_right = (u + du) * w - 0.5f, x_left = (u - du) * w - 0.5f, x_mid = u * w - 0.5f;
    v8f y_mid = (1.0f - v) * h - 0.5f;
    v8f y_up = (1.0f - (v + dv)) * h - 0.5f, y_down = (1.0f - (v - dv)) * h - 0.5f;
    v8f right = displace_sample8(hf, x_right, y_mid), left = displace_sample8(hf, x_left, y_mid);
    v8f up = displace_sample8(hf, x_mid, y_up), down = displace_sample8(hf, x_mid, y_down);
    *out_gu = (right - left) / (2.0f * du);
    *out_gv = (up - down) / (2.0f * dv);
}

/* meso_displaced_normal per lane, then displace_shade's choice: the displaced normal where it
 * is non-zero and finite, the interpolated one elsewhere. */
static inline v8vec3 displace_normal8(v8vec3 n, v8vec3 t, v8vec3 b, float depth, v8f gu, v8f gv) {
    v8f su = depth * gu, sv = depth * gv;
    v8vec3 du = {t.x + n.x * su, t.y + n.y * su, t.z + n.z * su};
    v8vec3 dv = {b.x + n.x * sv, b.y + n.y * sv, b.z + n.z * sv};
    v8vec3 c = {du.y * dv.z - du.z * dv.y, du.z * dv.x - du.x * dv.z, du.x * dv.y - du.y * dv.x};
    v8f len2 = v8_dot(c, c);
    v8i ok = (len2 > 0.0f) & (len2 < INFINITY);
    v8f inv = 1.0f / v8_sqrt(v8_select(ok, len2, v8_splat(1.0f)));
    v8vec3 s = {c.x * inv, c.y * inv, c.z * inv};
    v8i flip = v8_dot(s, n) < 0.0f;
    s = (v8vec3){v8_select(flip, -s.x, s.x), v8_select(flip, -s.y, s.y),
                 v8_select(flip, -s.z, s.z)};
    s = (v8vec3){v8_select(ok, s.x, n.x), v8_select(ok, s.y, n.y), v8_select(ok, s.z, n.z)};
    v8i use = (v8_dot(s, s) > 0.0f) & displace_finite8(s);
    return (v8vec3){v8_select(use, s.x, n.x), v8_select(use, s.y, n.y), v8_select(use, s.z, n.z)};
}

/* The unit face normal of each lane's triangle of `mesh` (positions gathered by index), or
 * `fallback` where the triangle is degenerate or out of range: displace_shade's face. */
static inline v8vec3 displace_face8(const meso_mesh *mesh, const uint32_t *triangle,
                                    v8vec3 fallback) {
    v8i t;
    memcpy(&t, triangle, sizeof t);
    v8i valid = v8i_splat(0);
    if (mesh) {
        /* an unsigned comparison: triangle < num_triangles (at most 2^26, MESO_MESH_MAX) */
        valid =
            (t >= 0) & (t < (int32_t)(mesh->num_triangles < (size_t)INT32_MAX ? mesh->num_triangles
                                                                              : (size_t)INT32_MAX));
    }
    if (!v8_any(valid)) return fallback;
    v8i corner = (v8i)v8_select(valid, (v8f)(t * 3), (v8f)v8i_splat(0));
    const float *p = (const float *)mesh->positions;
    v8i v0 = displace_gather8i(mesh->indices, corner) * 3;
    v8i v1 = displace_gather8i(mesh->indices, corner + 1) * 3;
    v8i v2 = displace_gather8i(mesh->indices, corner + 2) * 3;
    v8vec3 p0 = {displace_gather8(p, v0), displace_gather8(p, v0 + 1), displace_gather8(p, v0 + 2)};
    v8vec3 a = {displace_gather8(p, v1) - p0.x, displace_gather8(p, v1 + 1) - p0.y,
                displace_gather8(p, v1 + 2) - p0.z};
    v8vec3 b = {displace_gather8(p, v2) - p0.x, displace_gather8(p, v2 + 1) - p0.y,
                displace_gather8(p, v2 + 2) - p0.z};
    v8vec3 e = {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
    v8f len2 = v8_dot(e, e);
    v8i have = valid & (len2 > 0.0f);
    /* meso_vec3_normalize: e * (1 / sqrt(len2)) */
    v8f inv = 1.0f / v8_sqrt(v8_select(have, len2, v8_splat(1.0f)));
    return (v8vec3){v8_select(have, e.x * inv, fallback.x), v8_select(have, e.y * inv, fallback.y),
                    v8_select(have, e.z * inv, fallback.z)};
}

/* lit_tap per lane: 1 where z is not behind the map's depth at texel (i, j) clamped. */
static inline v8f displace_lit8(const float *depth, int size, v8i i, v8i j, v8f z) {
    v8i zero = v8i_splat(0), last = v8i_splat(size - 1);
    i = (v8i)v8_select(i < zero, (v8f)zero, (v8f)v8_select(i >= size, (v8f)last, (v8f)i));
    j = (v8i)v8_select(j < zero, (v8f)zero, (v8f)v8_select(j >= size, (v8f)last, (v8f)j));
    v8f d = displace_gather8(depth, j * size + i);
    return v8_select(z <= d, v8_splat(1.0f), v8_splat(0.0f));
}

/* displace_shadows_visibility of light l per lane (1 where the light casts no map, faces away
 * from the shading normal or the point falls outside its map). */
static inline v8f displace_visibility8(const displace_shadows *shadows, const meso_scene *scene,
                                       int l, v8vec3 position, v8vec3 normal, v8vec3 face) {
    v8f one = v8_splat(1.0f);
    if (l >= shadows->num_lights || !shadows->lights[l].active) return one;
    const displace_light_map *map = &shadows->lights[l];
    const meso_light *light = &scene->lights[l];
    v8vec3 to_light, from = {0};
    if (light->type == MESO_LIGHT_DIRECTIONAL) {
        to_light = (v8vec3){v8_splat(light->direction.x), v8_splat(light->direction.y),
                            v8_splat(light->direction.z)};
    } else { /* meso_vec3_normalize(light - position) */
        from = (v8vec3){light->position.x - position.x, light->position.y - position.y,
                        light->position.z - position.z};
        v8f len2 = v8_dot(from, from);
        v8i positive = len2 > 0.0f;
        v8f inv = 1.0f / v8_sqrt(v8_select(positive, len2, one));
        to_light = (v8vec3){v8_select(positive, from.x * inv, from.x),
                            v8_select(positive, from.y * inv, from.y),
                            v8_select(positive, from.z * inv, from.z)};
    }
    /* looked up unless facing away (a NaN is looked up, as the scalar `<= 0` test lets it) */
    v8i look = ~(v8_dot(normal, to_light) <= 0.0f);
    if (!v8_any(look)) return one;
    /* slope-scaled bias (displace_shadows_visibility) */
    v8f c = v8_dot(face, to_light);
    c = v8_select(c < 0.0f, -c, c); /* fabsf: -0 and 0 give the same below */
    c = v8_select(c < 0.1f, v8_splat(0.1f), c);
    v8f s2 = 1.0f - c * c;
    s2 = v8_select(s2 > 0.0f, s2, v8_splat(0.0f)); /* fmaxf(0, x): 0 for a NaN too */
    v8f slope = v8_sqrt(s2) / c;
    v8f texel = v8_splat(map->texel_size);
    if (light->type != MESO_LIGHT_DIRECTIONAL) texel = texel * v8_sqrt(v8_dot(from, from));
    v8f offset = shadows->options.bias * texel * (1.0f + slope);
    v8vec3 p = {position.x + to_light.x * offset, position.y + to_light.y * offset,
                position.z + to_light.z * offset};
    const float *m = map->view_projection.m;
    v8f cx = m[0] * p.x + m[4] * p.y + m[8] * p.z + m[12] * 1.0f;
    v8f cy = m[1] * p.x + m[5] * p.y + m[9] * p.z + m[13] * 1.0f;
    v8f cz = m[2] * p.x + m[6] * p.y + m[10] * p.z + m[14] * 1.0f;
    v8f cw = m[3] * p.x + m[7] * p.y + m[11] * p.z + m[15] * 1.0f;
    look &= cw > 0.0f;
    v8f nx = cx / cw, ny = cy / cw, nz = cz / cw;
    look &= (nx >= -1.0f) & (nx <= 1.0f) & (ny >= -1.0f) & (ny <= 1.0f);
    if (!v8_any(look)) return one;
    v8f z = nz * 0.5f + 0.5f;
    int size = shadows->options.size;
    v8f x = (nx * 0.5f + 0.5f) * (float)size - 0.5f;
    v8f y = (0.5f - ny * 0.5f) * (float)size - 0.5f;
    /* lanes not looked up read texel 0 (any finite coordinate) and are replaced by 1 */
    x = v8_select(look, x, v8_splat(0.0f)), y = v8_select(look, y, v8_splat(0.0f));
    v8f lit;
    if (shadows->options.pcf) {
        v8f fx = v8_floor(x), fy = v8_floor(y);
        v8i i = __builtin_convertvector(fx, v8i), j = __builtin_convertvector(fy, v8i);
        v8f tx = x - fx, ty = y - fy;
        v8f top = displace_lit8(map->depth, size, i, j, z) * (1.0f - tx) +
                  displace_lit8(map->depth, size, i + 1, j, z) * tx;
        v8f bottom = displace_lit8(map->depth, size, i, j + 1, z) * (1.0f - tx) +
                     displace_lit8(map->depth, size, i + 1, j + 1, z) * tx;
        lit = top * (1.0f - ty) + bottom * ty;
    } else {
        v8i i = __builtin_convertvector(v8_floor(x + 0.5f), v8i);
        v8i j = __builtin_convertvector(v8_floor(y + 0.5f), v8i);
        lit = displace_lit8(map->depth, size, i, j, z);
    }
    return v8_select(look, lit, one);
}

/* displace_shade for a block: the same colours, bit for bit. The block must carry the
 * position, normal, tangent, bitangent, uv and triangle of each fragment (not the sample, the
 * barycentrics or the colour preset). */
static inline void displace_shade_block(const displace_surface *surface,
                                        const displace_shadows *shadows, const meso_mesh *mesh,
                                        const meso_frame *frame, meso_fragment_block *block) {
    const meso_object *object = surface->object;
    int num_lights = frame->scene->num_lights;
    meso_shade_batch in[DISPLACE_SHADE_GROUPS];
    for (size_t first = 0; first < block->count; first += DISPLACE_SHADE_GROUPS * V8_LANES) {
        size_t groups = 0;
        for (size_t at = first; at < block->count && groups < DISPLACE_SHADE_GROUPS;
             at += V8_LANES, groups++) {
            meso_shade_batch *b = &in[groups];
            v8vec3 position = {meso_block_load(block->px, at), meso_block_load(block->py, at),
                               meso_block_load(block->pz, at)};
            v8vec3 base = {meso_block_load(block->nx, at), meso_block_load(block->ny, at),
                           meso_block_load(block->nz, at)};
            v8vec3 t = {meso_block_load(block->tx, at), meso_block_load(block->ty, at),
                        meso_block_load(block->tz, at)};
            v8vec3 bt = {meso_block_load(block->bx, at), meso_block_load(block->by, at),
                         meso_block_load(block->bz, at)};
            v8f u = meso_block_load(block->u, at), v = meso_block_load(block->v, at);
            v8vec3 normal = base;
            if (surface->heightfield) {
                /* the bump-map operation on the interpolated BASE frame (displace_shade) */
                v8f gu, gv;
                displace_gradient8(surface, u, v, &gu, &gv);
                normal = displace_normal8(base, t, bt, surface->depth, gu, gv);
            }
            if (shadows->num_lights > 0) {
                v8vec3 face = displace_face8(mesh, block->triangle + at, base);
                for (int l = 0; l < num_lights; l++)
                    b->visibility[l] =
                        displace_visibility8(shadows, frame->scene, l, position, normal, face);
                if (surface->both_faces) { /* displace_back_face, per lane */
                    v8vec3 eye = {v8_splat(frame->eye.x), v8_splat(frame->eye.y),
                                  v8_splat(frame->eye.z)};
                    v8vec3 to = {position.x - eye.x, position.y - eye.y, position.z - eye.z};
                    v8i back =
                        v8_dot(to, face) > v8_sqrt(v8_dot(to, to)) * DISPLACE_BACK_FACE_MARGIN;
                    for (int l = 0; l < num_lights; l++)
                        b->visibility[l] = v8_select(back, v8_splat(0.0f), b->visibility[l]);
                }
            } else {
                meso_shade_batch_all_visible(b, frame);
            }
            b->px = position.x, b->py = position.y, b->pz = position.z;
            b->nx = normal.x, b->ny = normal.y, b->nz = normal.z;
            b->u = u, b->v = v;
            b->tx = t.x, b->ty = t.y, b->tz = t.z;
            b->bx = bt.x, b->by = bt.y, b->bz = bt.z;
        }
        meso_shade_batches_to_block(frame, object, in, groups, block, first);
    }
}

#endif
