/* The shading model every technique and the reference share (docs/design.md, "Shading"). */
#include <math.h>

#include "render_environment.h"
#include "render_filter.h"
#include "render_shading.h"
#include "meso/texture.h"

static inline v8i sel_i(v8i mask, v8i a, v8i b) { return (a & mask) | (b & ~mask); }

/* base[index[k]] and base[index[k] + 1] per lane, the codes of a texel and its right neighbour:
 * v8_load_pairs (one 8-byte load a lane; before, two 64-bit gathers of four lanes each); the
 * same codes. */
static inline void load_code_pairs(const int32_t *base, v8i index, v8i *left, v8i *right) {
    v8f l, r;
    v8_load_pairs((const float *)(const void *)base, index, &l, &r);
    *left = (v8i)l, *right = (v8i)r;
}

/* The colour map at eight uvs: bilinear between texel centres at level 0 with the texture's
 * wrap (the arithmetic of meso_texture_sample(t, uv, 0, MESO_FILTER_BILINEAR): uv reduced to
 * [0, 1) for repeat, x = u W - 0.5, y = (1 - v) H - 0.5), 0 for a non-finite uv. */
/* Inlined: a call and its prologue cost a noticeable share of the lookup's instructions. */
static inline __attribute__((always_inline)) void sample_color_map(const meso_texture *t,
                                                                   const float *srgb8_table, v8f u,
                                                                   v8f v, v8f *out_r, v8f *out_g,
                                                                   v8f *out_b) {
    const meso_image *level = t->levels[0];
    int w = level->width, h = level->height;
    v8i finite = ((u - u) == v8_splat(0.0f)) & ((v - v) == v8_splat(0.0f));
    u = v8_select(finite, u, v8_splat(0.0f));
    v = v8_select(finite, v, v8_splat(0.0f));
    bool clamp = t->wrap == MESO_WRAP_CLAMP;
    if (!clamp) {
        u -= v8_floor(u);
        v -= v8_floor(v);
    }
    v8f x = u * v8_splat((float)w) - v8_splat(0.5f);
    v8f y = (v8_splat(1.0f) - v) * v8_splat((float)h) - v8_splat(0.5f);
    v8f fx = v8_floor(x), fy = v8_floor(y);
    v8f tx = x - fx, ty = y - fy;
    /* clamp mode: far-out coordinates are clamped before the conversion to int */
    fx = v8_select(fx < v8_splat(-1.0f), v8_splat(-1.0f), fx);
    fy = v8_select(fy < v8_splat(-1.0f), v8_splat(-1.0f), fy);
    fx = v8_select(fx > v8_splat((float)w), v8_splat((float)w), fx);
    fy = v8_select(fy > v8_splat((float)h), v8_splat((float)h), fy);
    v8i i0 = __builtin_convertvector(fx, v8i), j0 = __builtin_convertvector(fy, v8i);
    v8i i1 = i0 + 1, j1 = j0 + 1;
    v8i wv = {w, w, w, w, w, w, w, w}, hv = {h, h, h, h, h, h, h, h};
    v8i zero = {0, 0, 0, 0, 0, 0, 0, 0};
    if (clamp) {
        i0 = sel_i(i0 < zero, zero, i0), j0 = sel_i(j0 < zero, zero, j0);
        i1 = sel_i(i1 >= wv, wv - 1, i1), j1 = sel_i(j1 >= hv, hv - 1, j1);
        i0 = sel_i(i0 >= wv, wv - 1, i0), j0 = sel_i(j0 >= hv, hv - 1, j0);
    } else { /* after the reduction i0 >= -1 and i1 <= w */
        i0 = sel_i(i0 < zero, i0 + wv, i0), j0 = sel_i(j0 < zero, j0 + hv, j0);
        i1 = sel_i(i1 >= wv, i1 - wv, i1), j1 = sel_i(j1 >= hv, j1 - hv, j1);
    }
    v8i row0 = j0 * wv, row1 = j1 * wv;
    v8f ar, ag, ab, br, bg, bb, cr, cg, cb, dr, dg, db;
    if (t->srgb8) {
        /* 8-bit sRGB decoded in the lookup, as GPUs do: 4 gathers from a quarter of the
         * float level's bytes, then 12 from the 1 KB decode table (stays in L1) */
        const int32_t *codes = (const int32_t *)t->srgb8;
        const float *table = srgb8_table;
        v8i a, b, c, d;
        if (v8_mask_bits(i1 == i0 + 1) == 0xff) {
            /* each texel's right neighbour is the next code of its row (every lane but at a
             * wrap or clamp column): both from one 64-bit gather */
            load_code_pairs(codes, row0 + i0, &a, &b);
            load_code_pairs(codes, row1 + i0, &c, &d);
        } else {
            a = v8i_gather(codes, row0 + i0), b = v8i_gather(codes, row0 + i1);
            c = v8i_gather(codes, row1 + i0), d = v8i_gather(codes, row1 + i1);
        }
        v8i byte = v8i_splat(255);
#define DECODE(code, shift) v8_gather(table, ((code) >> (shift)) & byte)
        ar = DECODE(a, 0), ag = DECODE(a, 8), ab = DECODE(a, 16);
        br = DECODE(b, 0), bg = DECODE(b, 8), bb = DECODE(b, 16);
        cr = DECODE(c, 0), cg = DECODE(c, 8), cb = DECODE(c, 16);
        dr = DECODE(d, 0), dg = DECODE(d, 8), db = DECODE(d, 16);
#undef DECODE
    } else {
        /* In range in every lane (a non-finite uv became 0 above), so all eight lanes load:
         * twelve gathers beat 96 scalar loads into vector lanes. */
        v8i a = (row0 + i0) * 4, b = (row0 + i1) * 4, c = (row1 + i0) * 4, d = (row1 + i1) * 4;
        const float *p = level->pixels;
        ar = v8_gather(p, a), ag = v8_gather(p + 1, a), ab = v8_gather(p + 2, a);
        br = v8_gather(p, b), bg = v8_gather(p + 1, b), bb = v8_gather(p + 2, b);
        cr = v8_gather(p, c), cg = v8_gather(p + 1, c), cb = v8_gather(p + 2, c);
        dr = v8_gather(p, d), dg = v8_gather(p + 1, d), db = v8_gather(p + 2, d);
    }
    v8f top, bottom;
    top = ar + (br - ar) * tx, bottom = cr + (dr - cr) * tx;
    *out_r = v8_select(finite, top + (bottom - top) * ty, v8_splat(0.0f));
    top = ag + (bg - ag) * tx, bottom = cg + (dg - cg) * tx;
    *out_g = v8_select(finite, top + (bottom - top) * ty, v8_splat(0.0f));
    top = ab + (bb - ab) * tx, bottom = cb + (db - cb) * tx;
    *out_b = v8_select(finite, top + (bottom - top) * ty, v8_splat(0.0f));
}

/* A map at eight uvs: with a footprint (fp not NULL, the frame filters) and a mip chain,
 * filtered by it (render_filter.h); else, or where every lane's footprint lies within a texel,
 * sample_color_map's level-0 lookup. The mean of a normal map's texels is renormalised after
 * (apply_normal_map), the usual mip-mapped normal map. */
static inline __attribute__((always_inline)) void sample_map(const meso_texture *t,
                                                             const float *srgb8_table,
                                                             const meso_footprint8 *fp, v8f u,
                                                             v8f v, v8f *r, v8f *g, v8f *b) {
    meso_filter_levels levels;
    meso_filter_taps plan;
    if (fp && meso_filter_levels_init(&levels, t) && meso_filter_plan(&levels, fp, &plan))
        meso_filter_sample8(&levels, t->wrap == MESO_WRAP_CLAMP, &plan, u, v, r, g, b);
    else
        sample_color_map(t, srgb8_table, u, v, r, g, b);
}

/* ---- Eight points at a time ----------------------------------------------------------------
 * meso_shade_point, meso_shade_fragments and meso_shade_batch8 all run this one function (one
 * lane or eight), so a technique that shades a batch and the reference that shades single
 * points get the same bits. GCC vector extensions: 8 floats a vector. */
#define LANES V8_LANES

#define splat v8_splat
#define select_v v8_select
static inline v8f rsqrt_safe(v8f len2, v8i *nonzero) {
    *nonzero = len2 > splat(0.0f);
    return splat(1.0f) / v8_sqrt(len2);
}

/* The normal map's normal (docs/scene-format.md, "normal_map"): the texel (r, g, b) at uv (level
 * 0, bilinear, the colour map's wrap) read as x = 2r - 1, y = 2g - 1 (1 - 2g for the DirectX
 * convention), z = 2b - 1 in the frame (T', B', N') of the surface being shaded: N' the normal
 * the technique computed (in->n), T' the base tangent dP/du made orthogonal to N', B' the base
 * bitangent dP/dv made orthogonal to N' and T' (Gram-Schmidt, so B' keeps the side of dP/dv:
 * mirrored uvs stay right). n = normalize(T' x + B' y + N' z); the normal stays N' where the
 * frame is degenerate (no uvs, T or B along N') or uv is not finite. */
static void apply_normal_map(const meso_material *m, const meso_shade_batch *in,
                             const meso_footprint8 *fp, v8f *nx, v8f *ny, v8f *nz) {
    v8f r, g, b;
    sample_map(m->normal_map, meso_srgb8_table(), fp, in->u, in->v, &r, &g, &b);
    v8f x = r * splat(2.0f) - splat(1.0f), y = g * splat(2.0f) - splat(1.0f);
    v8f z = b * splat(2.0f) - splat(1.0f);
    if (m->normal_map_directx) y = -y;
    v8f Nx = *nx, Ny = *ny, Nz = *nz;
    v8f d = Nx * in->tx + Ny * in->ty + Nz * in->tz;
    v8f tx = in->tx - Nx * d, ty = in->ty - Ny * d, tz = in->tz - Nz * d;
    v8f t2 = tx * tx + ty * ty + tz * tz;
    v8i ok = t2 > splat(0.0f);
    t2 = select_v(ok, t2, splat(1.0f));
    d = Nx * in->bx + Ny * in->by + Nz * in->bz;
    v8f bx = in->bx - Nx * d, by = in->by - Ny * d, bz = in->bz - Nz * d;
    d = (tx * bx + ty * by + tz * bz) / t2;
    bx -= tx * d, by -= ty * d, bz -= tz * d;
    v8f b2 = bx * bx + by * by + bz * bz;
    ok &= b2 > splat(0.0f);
    b2 = select_v(ok, b2, splat(1.0f));
    v8f ti = splat(1.0f) / v8_sqrt(t2), bi = splat(1.0f) / v8_sqrt(b2);
    v8f px = tx * ti * x + bx * bi * y + Nx * z;
    v8f py = ty * ti * x + by * bi * y + Ny * z;
    v8f pz = tz * ti * x + bz * bi * y + Nz * z;
    v8f p2 = px * px + py * py + pz * pz;
    /* a non-finite uv or frame fails one of these (NaN compares false) */
    ok &= (p2 > splat(0.0f)) & (p2 < splat(INFINITY)) & ((in->u - in->u) == splat(0.0f)) &
          ((in->v - in->v) == splat(0.0f));
    v8f pi = splat(1.0f) / v8_sqrt(select_v(ok, p2, splat(1.0f)));
    *nx = select_v(ok, px * pi, Nx);
    *ny = select_v(ok, py * pi, Ny);
    *nz = select_v(ok, pz * pi, Nz);
}

/* What the shading of one object in one frame reads whatever the point: worked out once a call
 * of meso_shade_batches_to_block instead of once a group of eight (with the call, a
 * tenth of flat's shading). */
typedef struct shade_constants {
    const meso_frame *frame;
    const meso_object *object;
    const float *srgb8_table; /* the colour map's decode table, when it has codes */
    bool has_specular, integer_power;
} shade_constants;

static void shade_constants_init(shade_constants *c, const meso_frame *frame,
                                 const meso_object *object) {
    const meso_material *m = &object->material;
    c->frame = frame;
    c->object = object;
    c->srgb8_table = m->color_map && m->color_map->srgb8 ? meso_srgb8_table() : NULL;
    c->has_specular = m->specular.x > 0.0f || m->specular.y > 0.0f || m->specular.z > 0.0f;
    c->integer_power = c->has_specular && m->shininess >= 0.0f && m->shininess <= 4096.0f &&
                       m->shininess == floorf(m->shininess);
}

/* colour = albedo map(uv) (ambient + sum_i c_i max(0, N.L_i) v_i) + sum_i spec c_i (N.H_i)^s v_i
 * (docs/design.md); with an environment, ambient + E(N) / pi (render_environment.h), specular only
 * where N.L_i > 0 and N.H_i > 0. */
static inline __attribute__((always_inline)) void shade8(const shade_constants *c,
                                                         const meso_shade_batch *in,
                                                         const meso_footprint8 *fp, int lanes,
                                                         v8f *out_r, v8f *out_g, v8f *out_b) {
    const meso_frame *frame = c->frame;
    const meso_scene *scene = frame->scene;
    const meso_material *m = &c->object->material;
    v8f br = splat(m->albedo.x), bg = splat(m->albedo.y), bb = splat(m->albedo.z);
    if (m->color_map) {
        /* Without filtering: level 0, bilinear, in every technique and the reference, so
         * images compare pixel by pixel with the papers' point-sampled ones. With it: by the
         * base uv's footprint, the same in every technique (the rasterizer's) and the
         * reference (its ray differentials). */
        v8f tr, tg, tb;
        sample_map(m->color_map, c->srgb8_table, fp, in->u, in->v, &tr, &tg, &tb);
        br *= tr, bg *= tg, bb *= tb;
    }
    v8f nx = in->nx, ny = in->ny, nz = in->nz;
    if (m->normal_map) apply_normal_map(m, in, fp, &nx, &ny, &nz);
    bool has_specular = c->has_specular;
    v8f vx = splat(0.0f), vy = splat(0.0f), vz = splat(0.0f);
    v8i nonzero;
    if (has_specular) {
        vx = splat(frame->eye.x) - in->px, vy = splat(frame->eye.y) - in->py;
        vz = splat(frame->eye.z) - in->pz;
        v8f inv = rsqrt_safe(vx * vx + vy * vy + vz * vz, &nonzero);
        vx = select_v(nonzero, vx * inv, vx), vy = select_v(nonzero, vy * inv, vy);
        vz = select_v(nonzero, vz * inv, vz);
    }
    v8f dr = splat(scene->ambient.x), dg = splat(scene->ambient.y), db = splat(scene->ambient.z);
    if (scene->environment)
        meso_environment_ambient8(scene->environment, nx, ny, nz, &dr, &dg, &db);
    v8f sr = splat(0.0f), sg = splat(0.0f), sb = splat(0.0f);
    bool integer_power = c->integer_power;
    for (int li = 0; li < scene->num_lights; li++) {
        const meso_light *light = &scene->lights[li];
        v8f lx, ly, lz;
        if (light->type == MESO_LIGHT_DIRECTIONAL) {
            lx = splat(light->direction.x), ly = splat(light->direction.y);
            lz = splat(light->direction.z);
        } else {
            lx = splat(light->position.x) - in->px, ly = splat(light->position.y) - in->py;
            lz = splat(light->position.z) - in->pz;
            v8f inv = rsqrt_safe(lx * lx + ly * ly + lz * lz, &nonzero);
            lx = select_v(nonzero, lx * inv, lx), ly = select_v(nonzero, ly * inv, ly);
            lz = select_v(nonzero, lz * inv, lz);
        }
        v8f ndl = nx * lx + ny * ly + nz * lz;
        v8f vis = in->visibility[li];
        v8i lit = (ndl > splat(0.0f)) & (vis > splat(0.0f));
        if (!v8_any(lit)) continue;
        v8f w = ndl * vis;
        dr += select_v(lit, splat(light->color.x) * w, splat(0.0f));
        dg += select_v(lit, splat(light->color.y) * w, splat(0.0f));
        db += select_v(lit, splat(light->color.z) * w, splat(0.0f));
        if (!has_specular) continue;
        /* Blinn-Phong, only where the light reaches the front of the surface */
        v8f hx = lx + vx, hy = ly + vy, hz = lz + vz;
        v8f inv = rsqrt_safe(hx * hx + hy * hy + hz * hz, &nonzero);
        hx = select_v(nonzero, hx * inv, hx), hy = select_v(nonzero, hy * inv, hy);
        hz = select_v(nonzero, hz * inv, hz);
        v8f ndh = nx * hx + ny * hy + nz * hz;
        v8i on = lit & (ndh > splat(0.0f));
        v8f p;
        if (integer_power) { /* exact repeated squaring: the usual 8, 32, 64... */
            unsigned e = (unsigned)m->shininess;
            v8f x = ndh;
            p = splat(1.0f);
            while (e) {
                if (e & 1u) p *= x;
                x *= x;
                e >>= 1;
            }
        } else {
            for (int i = 0; i < LANES; i++) p[i] = i < lanes ? powf(ndh[i], m->shininess) : 0.0f;
        }
        v8f sv = select_v(on, p * vis, splat(0.0f));
        sr += splat(light->color.x * m->specular.x) * sv;
        sg += splat(light->color.y * m->specular.y) * sv;
        sb += splat(light->color.z * m->specular.z) * sv;
    }
    *out_r = br * dr + sr;
    *out_g = bg * dg + sg;
    *out_b = bb * db + sb;
}

void meso_shade_batch8(const meso_frame *frame, const meso_object *object,
                       const meso_shade_batch *in, int lanes, v8f *out_r, v8f *out_g, v8f *out_b) {
    shade_constants c;
    shade_constants_init(&c, frame, object);
    shade8(&c, in, NULL, lanes, out_r, out_g, out_b);
}

void meso_shade_batch8_fragments(const meso_frame *frame, const meso_object *object,
                                 const meso_shade_batch *in, const meso_fragment *fragments,
                                 int lanes, v8f *out_r, v8f *out_g, v8f *out_b) {
    shade_constants c;
    shade_constants_init(&c, frame, object);
    meso_footprint8 fp;
    if (frame->filter)
        for (int i = 0; i < LANES; i++) {
            const meso_fragment *f = &fragments[i < lanes ? i : lanes - 1];
            fp.dudx[i] = f->duv_dx.x, fp.dvdx[i] = f->duv_dx.y;
            fp.dudy[i] = f->duv_dy.x, fp.dvdy[i] = f->duv_dy.y;
        }
    shade8(&c, in, frame->filter ? &fp : NULL, lanes, out_r, out_g, out_b);
}

void meso_shade_batches_to_block(const meso_frame *frame, const meso_object *object,
                                 const meso_shade_batch *in, size_t num_groups,
                                 meso_fragment_block *b, size_t first) {
    shade_constants c;
    shade_constants_init(&c, frame, object);
    meso_footprint8 fp;
    for (size_t g = 0; g < num_groups; g++, first += LANES) {
        int lanes = b->count - first < LANES ? (int)(b->count - first) : LANES;
        v8f r, gr, bl;
        /* the batches are the block's lanes, whose footprints the rasterizer filled */
        if (frame->filter) meso_footprint8_from_block(&fp, b, first);
        shade8(&c, &in[g], frame->filter ? &fp : NULL, lanes, &r, &gr, &bl);
        meso_block_store(b->r, first, r);
        meso_block_store(b->g, first, gr);
        meso_block_store(b->b, first, bl);
    }
}

void meso_shade_block(const meso_frame *frame, const meso_object *object, meso_fragment_block *b) {
    shade_constants c;
    shade_constants_init(&c, frame, object);
    /* the tangents are read (and filled by the rasterizer for a technique that skips them)
     * only for a normal map */
    bool tangents = object->material.normal_map != NULL;
    meso_shade_batch in;
    meso_footprint8 fp;
    meso_shade_batch_all_visible(&in, frame); /* once, not once a group */
    for (size_t first = 0; first < b->count; first += LANES) {
        meso_shade_batch_from_block(&in, b, first, tangents);
        if (frame->filter) meso_footprint8_from_block(&fp, b, first);
        int lanes = b->count - first < LANES ? (int)(b->count - first) : LANES;
        v8f r, g, bl;
        shade8(&c, &in, frame->filter ? &fp : NULL, lanes, &r, &g, &bl);
        meso_block_store(b->r, first, r);
        meso_block_store(b->g, first, g);
        meso_block_store(b->b, first, bl);
    }
}

meso_vec3 meso_shade_point(const meso_frame *frame, const meso_object *object, meso_vec3 position,
                           meso_vec3 normal, meso_vec2 uv, const float *visibility) {
    meso_vec3 zero = {0.0f, 0.0f, 0.0f};
    return meso_shade_point_tb(frame, object, position, normal, zero, zero, uv, visibility);
}

meso_vec3 meso_shade_point_tb(const meso_frame *frame, const meso_object *object,
                              meso_vec3 position, meso_vec3 normal, meso_vec3 tangent,
                              meso_vec3 bitangent, meso_vec2 uv, const float *visibility) {
    meso_vec2 point = {0.0f, 0.0f};
    return meso_shade_point_footprint(frame, object, position, normal, tangent, bitangent, uv,
                                      point, point, visibility);
}

meso_vec3 meso_shade_point_footprint(const meso_frame *frame, const meso_object *object,
                                     meso_vec3 position, meso_vec3 normal, meso_vec3 tangent,
                                     meso_vec3 bitangent, meso_vec2 uv, meso_vec2 duv_dx,
                                     meso_vec2 duv_dy, const float *visibility) {
    meso_shade_batch in;
    in.px = splat(position.x), in.py = splat(position.y), in.pz = splat(position.z);
    in.nx = splat(normal.x), in.ny = splat(normal.y), in.nz = splat(normal.z);
    in.u = splat(uv.x), in.v = splat(uv.y);
    in.tx = splat(tangent.x), in.ty = splat(tangent.y), in.tz = splat(tangent.z);
    in.bx = splat(bitangent.x), in.by = splat(bitangent.y), in.bz = splat(bitangent.z);
    for (int i = 0; i < frame->scene->num_lights; i++)
        in.visibility[i] = splat(visibility ? visibility[i] : 1.0f);
    meso_footprint8 fp = {splat(duv_dx.x), splat(duv_dx.y), splat(duv_dy.x), splat(duv_dy.y)};
    shade_constants c;
    shade_constants_init(&c, frame, object);
    v8f r, g, b;
    shade8(&c, &in, frame->filter ? &fp : NULL, 1, &r, &g, &b);
    return (meso_vec3){r[0], g[0], b[0]};
}

void meso_shade_fragments(const meso_frame *frame, const meso_object *object,
                          meso_fragment *fragments, size_t count, const float *visibility) {
    int num_lights = frame->scene->num_lights;
    shade_constants c;
    shade_constants_init(&c, frame, object);
    for (size_t first = 0; first < count; first += LANES) {
        int lanes = count - first < LANES ? (int)(count - first) : LANES;
        meso_shade_batch in;
        meso_footprint8 fp;
        if (!visibility) meso_shade_batch_all_visible(&in, frame);
        for (int i = 0; i < LANES; i++) {
            /* unused lanes repeat the last fragment: finite inputs, results ignored */
            size_t k = first + (size_t)(i < lanes ? i : lanes - 1);
            const meso_fragment *f = &fragments[k];
            in.px[i] = f->position.x, in.py[i] = f->position.y, in.pz[i] = f->position.z;
            in.nx[i] = f->normal.x, in.ny[i] = f->normal.y, in.nz[i] = f->normal.z;
            in.u[i] = f->uv.x, in.v[i] = f->uv.y;
            in.tx[i] = f->tangent.x, in.ty[i] = f->tangent.y, in.tz[i] = f->tangent.z;
            in.bx[i] = f->bitangent.x, in.by[i] = f->bitangent.y, in.bz[i] = f->bitangent.z;
            fp.dudx[i] = f->duv_dx.x, fp.dvdx[i] = f->duv_dx.y;
            fp.dudy[i] = f->duv_dy.x, fp.dvdy[i] = f->duv_dy.y;
            for (int li = 0; visibility && li < num_lights; li++)
                in.visibility[li][i] = visibility[k * (size_t)num_lights + li];
        }
        v8f r, g, b;
        shade8(&c, &in, frame->filter ? &fp : NULL, lanes, &r, &g, &b);
        for (int i = 0; i < lanes; i++)
            fragments[first + (size_t)i].color = (meso_vec3){r[i], g[i], b[i]};
    }
}
