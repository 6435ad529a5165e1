/* gdm under global illumination: the RTV . incident radiance dot product at the GDM hit
 * (gdm_gi.h; GDM paper §3.2, §4.2; docs/techniques/gdm-gi.md). */
#include "gdm_gi.h"

#include <stdlib.h>
#include <string.h>

#include "meso/bake_rtv.h"
#include "meso/runtime.h"
#include "meso/prism.h"
#include "render_environment.h"
#include "render_gi.h"

/* GI_MAX_EIGEN: gdm's option gi_eigen is at most the 32 views of the default RTV */
/* GI_INSIDE_DIRECTIONS: the sky's directions over the sphere for a hit seen from inside */
enum { GI_BATCH = 64, GI_CHANNELS = 3, GI_MAX_EIGEN = 32, GI_INSIDE_DIRECTIONS = 64 };

struct gdm_gi {
    meso_rtv *rtv;
    const meso_mesh *mesh;
    const meso_environment *environment;
    /* per vertex: 3 x 16 incident radiance in the vertex's frame (kept for the interior's
     * radiance; NULL without an interior) */
    float *radiance;
    /* the same per vertex as 16 x 4: coefficient i's three channels side by side (lane 3 0),
     * so that a hit's colour sums 16 four-lane products with no shuffles */
    float *radiance4;
    meso_vec3 *tangents; /* per vertex: the frame's unit T (meso_gi_vertex_tangent) */
    /* the RTV's arrays voxel-major and view-major, [voxel][k][16] and [view][k][16]: a hit
     * reads 8 + 4 runs of 16 k floats instead of 16 x (8 + 4) scattered ones (bake_rtv.h
     * keeps them coefficient-major, as §4.1's SVD produces them), and an eigenfunction's 16
     * coefficients fill two vectors (evaluate's sums over the eigenfunctions, 16 at once) */
    float *weights, *eigen;
    int stride; /* 16 k */
    int chunks; /* 8-float chunks of a row read: 2 a used eigenfunction (gdm_gi_desc.used_eigen) */
    /* this frame's scene and frame with the environment removed (the direct part: constant
     * ambient, lights, specular), and with ambient 1 and nothing else (the albedo) */
    meso_scene direct_scene, albedo_scene;
    meso_frame direct_frame, albedo_frame;
    /* gdm's shadows through the shell (NULL: none), the directions a hit seen from inside
     * looks for the sky along, and the sky's radiance there times 4 / GI_INSIDE_DIRECTIONS
     * (the quadrature weight 4 pi / n over pi: E / pi) */
    const gdm_shell *shell;
    meso_vec3 albedo; /* the material's (the inside's interreflection) */
    /* a solid whose shell lets light through (open_fraction > 0): per vertex the 16
     * coefficients of the directions below the tangent plane that meet the base mesh, and the
     * interior's radiance this frame (render_gi.h); NULL and 0 otherwise */
    float *interior;
    float open_fraction;
    meso_vec3 interior_radiance;
    /* the lights interior_radiance was computed for (num_lights -1: none yet) */
    meso_light interior_lights[MESO_SCENE_MAX_LIGHTS];
    int interior_num_lights;
    meso_vec3 inside_direction[GI_INSIDE_DIRECTIONS];
    meso_vec3 inside_radiance[GI_INSIDE_DIRECTIONS];
};

static meso_result pack_rtv(meso_context *ctx, gdm_gi *gi, const char *name) {
    const meso_rtv *rtv = gi->rtv;
    size_t k = (size_t)rtv->num_eigen, stride = MESO_SH_COUNT * k;
    size_t voxels = (size_t)rtv->width * (size_t)rtv->height * (size_t)rtv->layers;
    size_t views = (size_t)rtv->num_theta * (size_t)rtv->num_phi;
    if (k > GI_MAX_EIGEN)
        return meso_log_error(ctx, MESO_ERROR_LIMIT, "%s: gdm gi: %zu eigenfunctions, at most %d",
                              name, k, (int)GI_MAX_EIGEN);
    gi->stride = (int)stride;
    gi->weights = malloc(voxels * stride * sizeof(float));
    gi->eigen = malloc(views * stride * sizeof(float));
    if (!gi->weights || !gi->eigen)
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: gdm gi: RTV", name);
    for (size_t i = 0; i < MESO_SH_COUNT; i++)
        for (size_t e = 0; e < k; e++) {
            for (size_t c = 0; c < voxels; c++)
                gi->weights[c * stride + e * MESO_SH_COUNT + i] =
                    rtv->weights[(i * voxels + c) * k + e];
            for (size_t v = 0; v < views; v++)
                gi->eigen[v * stride + e * MESO_SH_COUNT + i] = rtv->eigen[(i * k + e) * views + v];
        }
    return MESO_OK;
}

/* Four float lanes: one hit's three colour channels side by side (lane 3 unused). */
typedef float gi_v4f __attribute__((vector_size(16)));

enum { GI_LANES4 = 4, GI_RADIANCE4 = MESO_SH_COUNT * GI_LANES4 };

/* acc[j] += weight x row[8 j .. 8 j + 7] for the chunks of a packed row, each lane as the
 * scalar multiply-add (-ffp-contract=off: no fused rounding). Inline, so that the default
 * chunk count (16 x 4 eigenfunctions / 8) unrolls into registers. */
static inline void accumulate_rows(v8f *acc, const float *row, float weight, int chunks) {
    v8f cw = v8_splat(weight);
#pragma GCC unroll 8
    for (int j = 0; j < chunks; j++) {
        v8f x;
        memcpy(&x, row + 8 * j, sizeof x);
        acc[j] += cw * x;
    }
}

/* W and E interpolated at the cell (8 voxel corners, 4 views), chunk by chunk in the corners'
 * order. */
static inline void interpolate_rows(const gdm_gi *gi, const meso_rtv_cell *cell, v8f *w, v8f *e,
                                    int chunks) {
#pragma GCC unroll 8
    for (int j = 0; j < chunks; j++) w[j] = e[j] = v8_splat(0.0f);
#pragma GCC unroll 8
    for (int c = 0; c < 8; c++)
        accumulate_rows(w, gi->weights + cell->corner[c] * (size_t)gi->stride,
                        cell->corner_weight[c], chunks);
#pragma GCC unroll 4
    for (int v = 0; v < 4; v++)
        accumulate_rows(e, gi->eigen + (size_t)cell->view_index[v] * (size_t)gi->stride,
                        cell->view_weight[v], chunks);
}

/* The transfer vector at the cell, coefficients 0-7 and 8-15: coefficient i's is the sum over
 * the eigenfunctions q of W E, in q's order from 0 -- the sum the coefficient-major layout made
 * one coefficient at a time, here for 16 coefficients at once (the same additions per
 * coefficient, so the same bits). Inline, so that with the default chunk count W and E stay in
 * registers. */
static inline void transfer(const gdm_gi *gi, const meso_rtv_cell *cell, int chunks, v8f *out_lo,
                            v8f *out_hi) {
    enum { MAX_CHUNKS = MESO_SH_COUNT * GI_MAX_EIGEN / 8 };
    v8f w[MAX_CHUNKS], e[MAX_CHUNKS];
    interpolate_rows(gi, cell, w, e, chunks);
    v8f f_lo = v8_splat(0.0f), f_hi = v8_splat(0.0f);
#pragma GCC unroll 4
    for (int q = 0; 2 * q < chunks; q++) {
        f_lo += w[2 * q] * e[2 * q];
        f_hi += w[2 * q + 1] * e[2 * q + 1];
    }
    *out_lo = f_lo, *out_hi = f_hi;
}

/* meso_rtv_evaluate on the packed arrays: the same sums in another order, 8 wide (16 k is a
 * multiple of 8; transfer above); the colour is the sum over i in i's order, the three
 * channels in the lanes of one vector (radiance as radiance4 holds it: one load a
 * coefficient). */
static void evaluate(const gdm_gi *gi, meso_vec3 uvw, meso_vec3 view,
                     const gi_v4f radiance[MESO_SH_COUNT], float out_rgb[3]) {
    enum { CHUNKS_3 = MESO_SH_COUNT * 3 / 8, CHUNKS_4 = MESO_SH_COUNT * 4 / 8 };
    meso_rtv_cell cell;
    meso_rtv_cell_at(gi->rtv, uvw, view, &cell);
    int chunks = gi->chunks;
    v8f f_lo, f_hi;
    if (chunks == CHUNKS_3) /* the default 3 eigenfunctions, unrolled */
        transfer(gi, &cell, CHUNKS_3, &f_lo, &f_hi);
    else if (chunks == CHUNKS_4) /* the bake's default 4 */
        transfer(gi, &cell, CHUNKS_4, &f_lo, &f_hi);
    else
        transfer(gi, &cell, chunks, &f_lo, &f_hi);
    float f[MESO_SH_COUNT];
    memcpy(f, &f_lo, sizeof f_lo);
    memcpy(f + 8, &f_hi, sizeof f_hi);
    gi_v4f rgb = {0.0f, 0.0f, 0.0f, 0.0f};
#pragma GCC unroll 16
    for (int i = 0; i < MESO_SH_COUNT; i++) rgb += (gi_v4f){f[i], f[i], f[i], f[i]} * radiance[i];
    for (int c = 0; c < GI_CHANNELS; c++) out_rgb[c] = rgb[c] > 0.0f ? rgb[c] : 0.0f;
}

/* out = b0 a + b1 b + b2 c over n floats (a multiple of 8), 8 at a time: each element the
 * same sum as the scalar one, so the same bits. */
static inline void blend3(const float *a, const float *b, const float *c, float b0, float b1,
                          float b2, float *out, int n) {
    v8f w0 = v8_splat(b0), w1 = v8_splat(b1), w2 = v8_splat(b2);
#pragma GCC unroll 8
    for (int j = 0; j < n; j += 8) {
        v8f x, y, z;
        memcpy(&x, a + j, sizeof x);
        memcpy(&y, b + j, sizeof y);
        memcpy(&z, c + j, sizeof z);
        v8f r = w0 * x + w1 * y + w2 * z;
        memcpy(out + j, &r, sizeof r);
    }
}

/* meso_gi_radiance_interpolate (render_gi.h) on radiance4's layout. */
static inline void radiance_interpolate(const float *radiance4, uint32_t i0, uint32_t i1,
                                        uint32_t i2, float b0, float b1, float b2,
                                        gi_v4f out[MESO_SH_COUNT]) {
    blend3(radiance4 + (size_t)i0 * GI_RADIANCE4, radiance4 + (size_t)i1 * GI_RADIANCE4,
           radiance4 + (size_t)i2 * GI_RADIANCE4, b0, b1, b2, (float *)out, GI_RADIANCE4);
}

/* meso_gi_radiance_add_interior (render_gi.h) on radiance4's layout: coefficient i's m the
 * same sum, each channel the same l[c] m added. */
static inline void radiance_add_interior(const float *interior, uint32_t i0, uint32_t i1,
                                         uint32_t i2, float b0, float b1, float b2,
                                         meso_vec3 interior_radiance,
                                         gi_v4f radiance[MESO_SH_COUNT]) {
    float m[MESO_SH_COUNT];
    blend3(interior + (size_t)i0 * MESO_SH_COUNT, interior + (size_t)i1 * MESO_SH_COUNT,
           interior + (size_t)i2 * MESO_SH_COUNT, b0, b1, b2, m, MESO_SH_COUNT);
    gi_v4f l = {interior_radiance.x, interior_radiance.y, interior_radiance.z, 0.0f};
#pragma GCC unroll 16
    for (int i = 0; i < MESO_SH_COUNT; i++) radiance[i] += l * (gi_v4f){m[i], m[i], m[i], m[i]};
}

meso_result gdm_gi_create(meso_context *ctx, const meso_scene *scene, const meso_object *object,
                          const gdm_gi_desc *desc, gdm_gi **out_gi) {
    *out_gi = NULL;
    const meso_mesostructure *ms = &object->mesostructure;
    const meso_mesh *mesh = object->mesh;
    gdm_gi *gi = calloc(1, sizeof *gi);
    if (!gi) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: gdm gi", object->name);
    gi->mesh = mesh;
    gi->environment = scene->environment;
    meso_result r;
    gi->tangents = malloc((mesh->num_vertices ? mesh->num_vertices : 1) * sizeof *gi->tangents);
    if (!gi->tangents) {
        r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: gdm gi", object->name);
        goto fail;
    }
    for (size_t v = 0; v < mesh->num_vertices; v++)
        gi->tangents[v] = meso_gi_vertex_tangent(mesh, v);
    /* the shell's aspect as the reference's rtv mode takes it: the same cached bake */
    meso_rtv_desc rtv_desc = {
        .heightfield = ms->kind == MESO_MESOSTRUCTURE_HEIGHT_FIELD ? ms->height_field : NULL,
        .solid = ms->kind == MESO_MESOSTRUCTURE_SOLID ? ms->solid : NULL,
        .aspect = meso_gi_shell_aspect(object),
        .width = desc->resolution,
        .height = desc->resolution,
        .layers = desc->layers,
        .eigen = desc->eigen};
    if ((r = meso_rtv_bake_cached(ctx, &rtv_desc, &gi->rtv)) != MESO_OK) goto fail;
    if ((r = pack_rtv(ctx, gi, object->name)) != MESO_OK) goto fail;
    gi->chunks = gi->stride / 8;
    if (desc->used_eigen > 0 && desc->used_eigen < gi->rtv->num_eigen)
        gi->chunks = 2 * desc->used_eigen;
    gi->open_fraction = meso_gi_open_fraction(ms);
    gi->interior_num_lights = -1;
    r = gi->open_fraction > 0.0f
            ? meso_gi_vertex_radiance_through_shell(ctx, mesh, scene->environment, NULL,
                                                    &gi->radiance, &gi->interior)
            : meso_gi_vertex_radiance(ctx, mesh, scene->environment, NULL, &gi->radiance);
    if (r != MESO_OK) goto fail;
    gi->radiance4 =
        calloc(mesh->num_vertices ? mesh->num_vertices * GI_RADIANCE4 : 1, sizeof *gi->radiance4);
    if (!gi->radiance4) {
        r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: gdm gi", object->name);
        goto fail;
    }
    for (size_t v = 0; v < mesh->num_vertices; v++)
        for (int c = 0; c < GI_CHANNELS; c++)
            for (int i = 0; i < MESO_SH_COUNT; i++)
                gi->radiance4[v * GI_RADIANCE4 + (size_t)i * GI_LANES4 + (size_t)c] =
                    gi->radiance[(v * GI_CHANNELS + (size_t)c) * MESO_SH_COUNT + (size_t)i];
    if (!gi->interior) { /* the 3 x 16 layout is read only for the interior's radiance */
        free(gi->radiance);
        gi->radiance = NULL;
    }
    gi->shell = desc->shell;
    gi->albedo = object->material.albedo;
    for (int k = 0; k < GI_INSIDE_DIRECTIONS; k++) {
        meso_vec3 d = meso_gi_fibonacci_direction(k, GI_INSIDE_DIRECTIONS);
        float l[GI_CHANNELS];
        for (int c = 0; c < GI_CHANNELS; c++) /* clamped as the per-vertex transfer's */
            l[c] = fmaxf(0.0f, meso_sh_evaluate(scene->environment->sh[c], d)) * 4.0f /
                   (float)GI_INSIDE_DIRECTIONS;
        gi->inside_direction[k] = d;
        gi->inside_radiance[k] = (meso_vec3){l[0], l[1], l[2]};
    }
    *out_gi = gi;
    return MESO_OK;
fail:
    gdm_gi_destroy(gi);
    return r;
}

void gdm_gi_destroy(gdm_gi *gi) {
    if (!gi) return;
    meso_rtv_destroy(gi->rtv);
    free(gi->radiance);
    free(gi->radiance4);
    free(gi->interior);
    free(gi->tangents);
    free(gi->weights);
    free(gi->eigen);
    free(gi);
}

size_t gdm_gi_memory(const gdm_gi *gi) {
    if (!gi) return 0;
    return 2 * (size_t)gi->rtv->compressed_bytes + /* the RTV and its packed copy */
           gi->mesh->num_vertices *
               ((GI_LANES4 + (gi->interior ? GI_CHANNELS + 1 : 0)) * MESO_SH_COUNT * sizeof(float) +
                sizeof(meso_vec3));
}

void gdm_gi_begin_frame(gdm_gi *gi, const meso_frame *frame) {
    gi->direct_scene = *frame->scene;
    gi->direct_scene.environment = NULL;
    gi->direct_frame = *frame;
    gi->direct_frame.scene = &gi->direct_scene;
    gi->albedo_scene = gi->direct_scene;
    gi->albedo_scene.num_lights = 0;
    gi->albedo_scene.ambient = (meso_vec3){1.0f, 1.0f, 1.0f};
    gi->albedo_frame = *frame;
    gi->albedo_frame.scene = &gi->albedo_scene;
    const meso_scene *scene = frame->scene;
    size_t light_bytes = (size_t)scene->num_lights * sizeof *scene->lights;
    if (gi->interior && (scene->num_lights != gi->interior_num_lights ||
                         memcmp(scene->lights, gi->interior_lights, light_bytes) != 0)) {
        /* the lights moved (the viewer): a pass over the mesh, not every frame */
        gi->interior_radiance =
            meso_gi_interior_radiance(gi->mesh, gi->radiance, scene, gi->albedo, gi->open_fraction);
        memcpy(gi->interior_lights, scene->lights, light_bytes);
        gi->interior_num_lights = scene->num_lights;
    }
}

/* The sky's irradiance over pi at a hit seen from inside the base mesh, shadowed by the shell:
 * the environment's radiance over fixed directions of the normal's hemisphere, each kept
 * when gdm's walk through the shell (gdm_shell_shadow.h) lets it in -- through the holes of
 * the near wall, over a rim. The light the inside's walls bounce (the truth has it; without
 * it the holes measured too dark) enters through Jimenez et al. 2016's multi-bounce fit of
 * the visible fraction x for albedo a ("Practical Real-Time Strategies for Accurate Indirect
 * Occlusion", GTAO): max(x, ((p x + q) x + r) x), the surfaces around taken as lit alike. */
static void inside_sky(const gdm_gi *gi, const meso_fragment *f, const gdm_gi_hit *hit,
                       meso_vec3 albedo, float out_rgb[3]) {
    size_t prism = gdm_shell_prism_index(gi->shell, hit->prism);
    meso_vec3 seen = {0.0f, 0.0f, 0.0f}, all = seen;
    for (int k = 0; k < GI_INSIDE_DIRECTIONS; k++) {
        float cosine = meso_vec3_dot(f->normal, gi->inside_direction[k]);
        if (cosine <= 0.0f) continue;
        all = meso_vec3_madd(all, gi->inside_radiance[k], cosine);
        if (gdm_shell_light_visible(gi->shell, prism, hit->uvw, gi->inside_direction[k], false,
                                    false))
            seen = meso_vec3_madd(seen, gi->inside_radiance[k], cosine);
    }
    const float *a = &albedo.x, *s = &seen.x, *u = &all.x;
    for (int c = 0; c < 3; c++) {
        float x = u[c] > 0.0f ? s[c] / u[c] : 1.0f;
        float p = 2.0404f * a[c] - 0.3324f, q = -4.7951f * a[c] + 0.6417f;
        float r = 2.7552f * a[c] + 0.6903f;
        out_rgb[c] = u[c] * fmaxf(x, ((x * p + q) * x + r) * x);
    }
}

/* RTV(uvw, view) . L per unit albedo at one hit: L interpolated from the prism's vertices at
 * the hit's (u, v), the view in the interpolated tangent frame (as the vertices' frames,
 * render_gi_transfer.c, and the reference's rtv mode).
 *
 * A hit seen from below its base surface (the far wall of a woven teapot seen from inside
 * through the near wall's holes) faces the light from below the tangent plane: with an open
 * shell (gi->interior), the environment and the interior's radiance the vertices hold; with
 * gi_inside_sky, the sky through the shell; otherwise (a height field's closed shell: the
 * model has no light there) the shading model's unshadowed SH ambient at the hit's normal
 * (gi off's term). Returns false for such a hit. */
static bool reflected_at(const gdm_gi *gi, const meso_frame *frame, const meso_fragment *f,
                         const gdm_gi_hit *hit, float out_rgb[3]) {
    const meso_mesh *mesh = gi->mesh;
    const uint32_t *v = hit->prism->vertices;
    float b[3];
    meso_prism_weights(hit->prism, (meso_vec2){hit->uvw.x, hit->uvw.y}, b);
    gi_v4f radiance[MESO_SH_COUNT];
    radiance_interpolate(gi->radiance4, v[0], v[1], v[2], b[0], b[1], b[2], radiance);
    if (gi->interior) /* plus the interior's light from below the tangent plane */
        radiance_add_interior(gi->interior, v[0], v[1], v[2], b[0], b[1], b[2],
                              gi->interior_radiance, radiance);
    meso_vec3 n = meso_vec3_normalize(meso_vec3_barycentric(
        mesh->normals[v[0]], mesh->normals[v[1]], mesh->normals[v[2]], b[0], b[1], b[2]));
    meso_vec3 t = meso_vec3_barycentric(gi->tangents[v[0]], gi->tangents[v[1]], gi->tangents[v[2]],
                                        b[0], b[1], b[2]);
    t = meso_vec3_normalize(meso_vec3_sub(t, meso_vec3_scale(n, meso_vec3_dot(n, t))));
    meso_vec3 bt = meso_vec3_cross(n, t);
    meso_vec3 toward = meso_vec3_normalize(meso_vec3_sub(frame->eye, f->position));
    meso_vec3 view = {meso_vec3_dot(toward, t), meso_vec3_dot(toward, bt),
                      meso_vec3_dot(toward, n)};
    if (view.z < 0.0f && gi->shell) {
        inside_sky(gi, f, hit, gi->albedo, out_rgb);
        return false;
    }
    if (view.z < 0.0f && gi->interior) {
        float channels[GI_CHANNELS][MESO_SH_COUNT];
        for (int c = 0; c < GI_CHANNELS; c++)
            for (int i = 0; i < MESO_SH_COUNT; i++) channels[c][i] = radiance[i][c];
        meso_gi_reflected_from_below((const float(*)[MESO_SH_COUNT])channels, out_rgb);
        return false;
    }
    if (view.z < 0.0f) {
        v8f r = v8_splat(0.0f), g = r, bl = r;
        meso_environment_ambient8(gi->environment, v8_splat(f->normal.x), v8_splat(f->normal.y),
                                  v8_splat(f->normal.z), &r, &g, &bl);
        out_rgb[0] = r[0], out_rgb[1] = g[0], out_rgb[2] = bl[0];
        return false;
    }
    evaluate(gi, hit->uvw, view, radiance, out_rgb);
    return true;
}

void gdm_gi_shade(const gdm_gi *gi, const meso_frame *frame, const meso_object *object,
                  meso_fragment *fragments, size_t count, const float *visibility,
                  const gdm_gi_hit *hits) {
    int num_lights = gi->direct_scene.num_lights;
    const meso_material *m = &object->material;
    for (size_t start = 0; start < count; start += GI_BATCH) {
        size_t n = count - start < GI_BATCH ? count - start : GI_BATCH;
        meso_fragment *batch = fragments + start;
        meso_vec3 reflected[GI_BATCH];
        for (size_t i = 0; i < n; i++) {
            float rgb[3];
            reflected_at(gi, frame, &batch[i], &hits[start + i], rgb);
            reflected[i] = (meso_vec3){rgb[0], rgb[1], rgb[2]};
        }
        /* the albedo: the shading model's own (albedo x colour map) with ambient 1 alone */
        if (m->color_map) {
            meso_shade_fragments(&gi->albedo_frame, object, batch, n, NULL);
            for (size_t i = 0; i < n; i++)
                reflected[i] = meso_vec3_mul(reflected[i], batch[i].color);
        } else {
            for (size_t i = 0; i < n; i++) reflected[i] = meso_vec3_mul(reflected[i], m->albedo);
        }
        meso_shade_fragments(&gi->direct_frame, object, batch, n,
                             visibility ? visibility + start * (size_t)num_lights : NULL);
        for (size_t i = 0; i < n; i++) batch[i].color = meso_vec3_add(batch[i].color, reflected[i]);
    }
}
