/* The path-traced reference: the truth under an environment and with
 * interreflection, over the same micro-geometry the direct-light reference traces.
 *
 * A pixel is the direct-light reference's colour (the shared shading model with hard shadows:
 * ambient, the scene's lights, specular; without the environment's unshadowed SH term, which
 * the sampled environment light replaces) plus the light the surface reflects from the
 * environment and from other surfaces, which the model treats as Lambertian with its diffuse
 * albedo (albedo x colour map):
 *     L(x) = shade(x) + albedo(x) / pi * E(x),   E(x) = integral L_in(w) max(0, n.w) dw,
 * where L_in is the environment's radiance where the ray w escapes and, where it hits a surface
 * y, y's radiance albedo(y) (ambient + sum of lights n.l visible + E(y) / pi), up to `bounces`
 * surfaces deep (0: no interreflection, the environment's direct light only). Specular is
 * reflected from the scene's lights only, as in the direct model.
 *
 * E is estimated with one sample of each of two strategies combined by the balance heuristic
 * (Veach & Guibas 1995, multiple importance sampling): a direction drawn from the environment's
 * luminance (its importance sampling, meso_environment_sample) with a shadow ray, and a
 * cosine-weighted direction about the normal, which continues the path where it hits a
 * surface. The camera ray goes through the pixel centre as in every other renderer, so
 * coverage and depth are the direct reference's exactly; only the lighting is sampled.
 *
 * Determinism: sample s of pixel p draws its numbers from a generator seeded by (p, s) alone,
 * and a pixel's samples are summed in order, so the image is the same for any thread count.
 * Progress: samples are taken in passes of PASS_SAMPLES over every 16 x 16 tile; the progress
 * counts tiles x passes and a cancel stops at the next tile.
 */
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "meso/bake_rtv.h"
#include "meso/runtime.h"
#include "reference_internal.h"
#include "render_gi.h"

enum { PASS_SAMPLES = 4 };

/* ---- Random numbers ----------------------------------------------------------------------- */

/* SplitMix64 (Steele, Lea & Flood 2014): a counter through a strong mixer, so nearby seeds
 * give independent streams. */
typedef struct path_random {
    uint64_t state;
} path_random;

static uint64_t random_next64(path_random *r) {
    uint64_t z = (r->state += UINT64_C(0x9E3779B97F4A7C15));
    z = (z ^ (z >> 30)) * UINT64_C(0xBF58476D1CE4E5B9);
    z = (z ^ (z >> 27)) * UINT64_C(0x94D049BB133111EB);
    return z ^ (z >> 31);
}

/* Uniform in [0, 1): the top 24 bits, exactly representable. */
static float random_next(path_random *r) { return (float)(random_next64(r) >> 40) * 0x1p-24f; }

static path_random random_for(size_t pixel, int sample) {
    path_random r = {((uint64_t)pixel << 24) ^ (uint64_t)sample};
    random_next64(&r); /* one step, so that seeds differing in few bits start far apart */
    return r;
}

/* ---- Directions --------------------------------------------------------------------------- */

/* A cosine-weighted direction about the unit n (Malley's method: a uniform point of the disc
 * lifted to the hemisphere); its density is max(0, n.w) / pi. */
static meso_vec3 cosine_direction(meso_vec3 n, float u1, float u2) {
    /* an orthonormal basis around n without a branch on n's size (Duff et al. 2017) */
    float sign = copysignf(1.0f, n.z);
    float a = -1.0f / (sign + n.z), b = n.x * n.y * a;
    meso_vec3 t = {1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x};
    meso_vec3 s = {b, sign + n.y * n.y * a, -n.y};
    float r = sqrtf(u1), phi = 2.0f * MESO_PI * u2;
    float x = r * cosf(phi), y = r * sinf(phi), z = sqrtf(fmaxf(0.0f, 1.0f - u1));
    return meso_vec3_normalize(meso_vec3_add(
        meso_vec3_add(meso_vec3_scale(t, x), meso_vec3_scale(s, y)), meso_vec3_scale(n, z)));
}

/* ---- Light transport ---------------------------------------------------------------------- */

typedef struct path_job {
    const meso_reference *reference;
    const meso_frame *frame;
    meso_frame albedo_frame; /* the frame with no lights and ambient 1: shading gives albedo */
    meso_scene albedo_scene;
    /* the frame without the environment's unshadowed SH term (render_environment.h), which
     * the sampled light replaces: the direct part of a pixel */
    meso_frame direct_frame;
    meso_scene direct_scene;
    const meso_environment *environment; /* NULL: none */
    int samples, bounces;
    int pass; /* the pass running: samples [pass * PASS_SAMPLES, ...) */
    int tiles_x;
    float *color, *coverage, *depth;
    double *reflected; /* per pixel, RGB: the sum over samples of albedo E / pi */
    /* RTV mode (option `rtv`): per object, its RTV and per-vertex incident radiance (NULL for
     * objects without mesostructure, which keep the SH ambient of the shading model) */
    meso_rtv **rtvs;
    float **vertex_radiance;
    /* per object, for a solid whose shell lets light through: the vertices' coefficients of
     * the directions into the base mesh and the interior's radiance (render_gi.h); NULL */
    float **vertex_interior;
    meso_vec3 *interior_radiance;
    meso_progress *progress;
    atomic_bool cancelled;
} path_job;

/* The shading model's diffuse albedo at a hit (albedo x colour map, exactly as it shades). */
static meso_vec3 albedo_at(const path_job *pj, const reference_hit *hit) {
    return reference_shade_hit(&pj->albedo_frame, hit, NULL);
}

/* The shading normal on the ray's side: interpolated normals may face away from the
 * triangle the ray hit; light then arrives on the side the ray came from. */
static meso_vec3 facing_normal(const reference_hit *hit) {
    return meso_vec3_dot(hit->normal, hit->geometric_normal) < 0.0f ? meso_vec3_negate(hit->normal)
                                                                    : hit->normal;
}

static meso_vec3 surface_radiance(const path_job *pj, const reference_hit *hit, int bounces_left,
                                  path_random *random);

/* One estimate of the irradiance E at a hit (see the top of the file). */
static meso_vec3 irradiance(const path_job *pj, const reference_hit *hit, int bounces_left,
                            path_random *random) {
    const meso_environment *env = pj->environment;
    meso_vec3 n = facing_normal(hit), ng = hit->geometric_normal;
    meso_vec3 e = {0, 0, 0};
    /* the environment's importance: directions toward its bright texels */
    float u1 = random_next(random), u2 = random_next(random);
    if (env) {
        float pdf_light = 0.0f;
        meso_vec3 w = meso_environment_sample(env, u1, u2, &pdf_light);
        float cosine = meso_vec3_dot(n, w);
        struct RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        if (cosine > 0.0f && meso_vec3_dot(ng, w) > 0.0f &&
            reference_unoccluded(pj->reference->scene, &context, hit->origin, w, INFINITY)) {
            float pdf_cosine = cosine * MESO_INV_PI;
            float weight = pdf_light / (pdf_light + pdf_cosine);
            e = meso_vec3_madd(e, meso_environment_radiance(env, w), cosine / pdf_light * weight);
        }
    }
    /* cosine-weighted: the environment where the ray escapes, the surface where it hits */
    float u3 = random_next(random), u4 = random_next(random);
    meso_vec3 w = cosine_direction(n, u3, u4);
    float cosine = meso_vec3_dot(n, w);
    if (!(cosine > 0.0f && meso_vec3_dot(ng, w) > 0.0f)) return e;
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    reference_hit next;
    if (!reference_trace(pj->reference, &context, hit->origin, w, 0.0f, &next)) {
        if (env) {
            float pdf_cosine = cosine * MESO_INV_PI;
            float weight = pdf_cosine / (pdf_cosine + meso_environment_pdf(env, w));
            /* L cos / pdf_cosine = L pi */
            e = meso_vec3_madd(e, meso_environment_radiance(env, w), MESO_PI * weight);
        }
    } else if (bounces_left > 0) {
        e = meso_vec3_madd(e, surface_radiance(pj, &next, bounces_left - 1, random), MESO_PI);
    }
    return e;
}

/* The radiance a surface point seen by a bounce ray reflects (diffusely) toward it. */
static meso_vec3 surface_radiance(const path_job *pj, const reference_hit *hit, int bounces_left,
                                  path_random *random) {
    const meso_scene *scene = pj->frame->scene;
    meso_vec3 n = facing_normal(hit);
    float visibility[MESO_SCENE_MAX_LIGHTS];
    reference_light_visibility(pj->reference, hit->origin, hit->position, visibility);
    meso_vec3 direct = scene->ambient;
    for (int l = 0; l < scene->num_lights; l++) {
        float cosine = meso_vec3_dot(n, meso_light_direction(&scene->lights[l], hit->position));
        if (cosine > 0.0f && visibility[l] > 0.0f)
            direct = meso_vec3_madd(direct, scene->lights[l].color, cosine * visibility[l]);
    }
    meso_vec3 e = irradiance(pj, hit, bounces_left, random);
    return meso_vec3_mul(albedo_at(pj, hit), meso_vec3_madd(direct, e, MESO_INV_PI));
}

/* ---- The RTV mode: GDM-GI's shading at the true hit (docs/techniques/gdm-gi.md) ------------ */

/* What the environment adds at a hit through the RTV: albedo x RTV(uvw, view) . L, L the
 * object's per-vertex incident radiance interpolated over the base triangle; objects without
 * mesostructure get the shading model's SH ambient (the frame's own shading). */
static meso_vec3 rtv_reflected(const path_job *pj, const meso_frame *frame,
                               const reference_hit *hit) {
    int o = (int)(hit->ref - pj->reference->objects);
    const meso_mesh *mesh = hit->ref->object->mesh;
    meso_vec3 albedo = albedo_at(pj, hit);
    if (!pj->rtvs[o]) {
        meso_vec3 full = reference_shade_hit(frame, hit, NULL);
        meso_vec3 none = reference_shade_hit(&pj->direct_frame, hit, NULL);
        return meso_vec3_sub(full, none);
    }
    const uint32_t *tri = mesh->indices + 3 * hit->base.triangle;
    const float *b = hit->base.weights;
    float radiance[3][MESO_SH_COUNT];
    meso_gi_radiance_interpolate(pj->vertex_radiance[o], tri[0], tri[1], tri[2], b[0], b[1], b[2],
                                 radiance);
    const float *interior = pj->vertex_interior[o];
    if (interior) /* as gdm's: gdm_gi.c */
        meso_gi_radiance_add_interior(interior, tri[0], tri[1], tri[2], b[0], b[1], b[2],
                                      pj->interior_radiance[o], radiance);
    /* the tangent frame as the vertices' (render_gi_transfer.c): T made orthogonal to N */
    meso_vec3 n = meso_vec3_normalize(meso_vec3_barycentric(
        mesh->normals[tri[0]], mesh->normals[tri[1]], mesh->normals[tri[2]], b[0], b[1], b[2]));
    meso_vec3 t = mesh->tangents
                      ? meso_vec3_barycentric(mesh->tangents[tri[0]], mesh->tangents[tri[1]],
                                              mesh->tangents[tri[2]], b[0], b[1], b[2])
                      : (meso_vec3){1, 0, 0};
    t = meso_vec3_normalize(meso_vec3_sub(t, meso_vec3_scale(n, meso_vec3_dot(n, t))));
    meso_vec3 bt = meso_vec3_cross(n, t);
    meso_vec3 v = meso_vec3_normalize(meso_vec3_sub(frame->eye, hit->position));
    meso_vec3 view = {meso_vec3_dot(v, t), meso_vec3_dot(v, bt), meso_vec3_dot(v, n)};
    float rgb[3];
    if (view.z < 0.0f && interior) /* seen from inside: the light from below (gdm_gi.c) */
        meso_gi_reflected_from_below((const float(*)[MESO_SH_COUNT])radiance, rgb);
    else
        meso_rtv_evaluate(pj->rtvs[o], (meso_vec3){hit->uv.x, hit->uv.y, hit->base.w}, view,
                          radiance, rgb);
    return meso_vec3_mul(albedo, (meso_vec3){rgb[0], rgb[1], rgb[2]});
}

/* Bake (through the cache) every object's RTV and per-vertex radiance. */
static meso_result prepare_rtv(meso_context *ctx, path_job *pj) {
    const meso_reference *reference = pj->reference;
    const meso_scene *scene = pj->frame->scene;
    if (!scene->environment)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: reference: rtv needs the scene's environment", scene->path);
    int n = reference->num_objects;
    pj->rtvs = calloc((size_t)n, sizeof *pj->rtvs);
    pj->vertex_radiance = calloc((size_t)n, sizeof *pj->vertex_radiance);
    pj->vertex_interior = calloc((size_t)n, sizeof *pj->vertex_interior);
    pj->interior_radiance = calloc((size_t)n, sizeof *pj->interior_radiance);
    if (!pj->rtvs || !pj->vertex_radiance || !pj->vertex_interior || !pj->interior_radiance)
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "reference: rtv");
    for (int o = 0; o < n; o++) {
        const meso_object *object = reference->objects[o].object;
        if (!object || object->mesostructure.kind == MESO_MESOSTRUCTURE_NONE) continue;
        const meso_mesostructure *ms = &object->mesostructure;
        meso_rtv_desc desc = {
            .heightfield = ms->kind == MESO_MESOSTRUCTURE_HEIGHT_FIELD ? ms->height_field : NULL,
            .solid = ms->kind == MESO_MESOSTRUCTURE_SOLID ? ms->solid : NULL,
            .aspect = meso_gi_shell_aspect(object)};
        meso_result r = meso_rtv_bake_cached(ctx, &desc, &pj->rtvs[o]);
        float open_fraction = meso_gi_open_fraction(ms);
        if (r == MESO_OK && open_fraction > 0.0f)
            r = meso_gi_vertex_radiance_through_shell(ctx, object->mesh, scene->environment, NULL,
                                                      &pj->vertex_radiance[o],
                                                      &pj->vertex_interior[o]);
        else if (r == MESO_OK)
            r = meso_gi_vertex_radiance(ctx, object->mesh, scene->environment, NULL,
                                        &pj->vertex_radiance[o]);
        if (r != MESO_OK) return r;
        if (pj->vertex_interior[o])
            pj->interior_radiance[o] =
                meso_gi_interior_radiance(object->mesh, pj->vertex_radiance[o], scene,
                                          object->material.albedo, open_fraction);
    }
    return MESO_OK;
}

static void release_rtv(path_job *pj, int n) {
    for (int o = 0; pj->rtvs && o < n; o++) meso_rtv_destroy(pj->rtvs[o]);
    for (int o = 0; pj->vertex_radiance && o < n; o++) free(pj->vertex_radiance[o]);
    for (int o = 0; pj->vertex_interior && o < n; o++) free(pj->vertex_interior[o]);
    free(pj->vertex_interior);
    free(pj->interior_radiance);
    free(pj->rtvs);
    free(pj->vertex_radiance);
}

static void path_tile(void *user, size_t job, int thread_index) {
    (void)thread_index;
    path_job *pj = user;
    if (atomic_load_explicit(&pj->cancelled, memory_order_relaxed)) return;
    const meso_reference *reference = pj->reference;
    const meso_frame *frame = pj->frame;
    int x0, y0, x1, y1;
    reference_tile_bounds(job, pj->tiles_x, frame->width, frame->height, &x0, &y0, &x1, &y1);
    int first = pj->pass * PASS_SAMPLES;
    int last = first + PASS_SAMPLES < pj->samples ? first + PASS_SAMPLES : pj->samples;
    struct RTCIntersectContext primary;
    rtcInitIntersectContext(&primary);
    primary.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    for (int j = y0; j < y1; j++)
        for (int i = x0; i < x1; i++) {
            size_t pixel = (size_t)j * (size_t)frame->width + (size_t)i;
            reference_hit hit;
            bool found;
            if (pj->pass == 0) {
                /* the direct reference's sample, without the environment's SH term */
                found = reference_direct_sample(reference, &pj->direct_frame, &primary, i, j,
                                                pj->color, pj->coverage, pj->depth, &hit);
            } else {
                meso_vec3 dir = meso_frame_ray_direction(frame, (float)i + 0.5f, (float)j + 0.5f);
                found = reference_trace(reference, &primary, frame->eye, dir, frame->z_near, &hit);
            }
            if (!found) continue;
            meso_vec3 albedo = albedo_at(pj, &hit);
            double *sum = pj->reflected + 3 * pixel;
            if (pj->rtvs) {
                meso_vec3 reflected = rtv_reflected(pj, frame, &hit);
                sum[0] += reflected.x, sum[1] += reflected.y, sum[2] += reflected.z;
                continue;
            }
            for (int s = first; s < last; s++) {
                path_random random = random_for(pixel, s);
                meso_vec3 e = irradiance(pj, &hit, pj->bounces, &random);
                meso_vec3 reflected = meso_vec3_scale(meso_vec3_mul(albedo, e), MESO_INV_PI);
                sum[0] += reflected.x, sum[1] += reflected.y, sum[2] += reflected.z;
            }
        }
    if (last == pj->samples)
        meso_progress_advance(frame->progress, (uint64_t)(x1 - x0) * (uint64_t)(y1 - y0));
    if (meso_progress_advance(pj->progress, 1)) atomic_store(&pj->cancelled, true);
}

meso_result reference_path_render(meso_context *ctx, const meso_reference *reference,
                                  const meso_frame *frame, float *color, float *coverage,
                                  float *depth) {
    size_t pixels = (size_t)frame->width * (size_t)frame->height;
    meso_result r =
        meso_memory_check(ctx, "reference: path tracing", (uint64_t)pixels * 3 * sizeof(double));
    if (r != MESO_OK) return r;
    path_job *pj = calloc(1, sizeof *pj);
    double *reflected = calloc(pixels * 3, sizeof(double));
    if (!pj || !reflected) {
        free(pj);
        free(reflected);
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "reference: path tracing: %zu pixels",
                              pixels);
    }
    pj->reference = reference;
    pj->frame = frame;
    pj->albedo_scene = *frame->scene;
    pj->albedo_scene.num_lights = 0;
    pj->albedo_scene.ambient = (meso_vec3){1.0f, 1.0f, 1.0f};
    pj->albedo_scene.environment = NULL;
    pj->direct_scene = *frame->scene;
    pj->direct_scene.environment = NULL;
    pj->direct_frame = *frame;
    pj->direct_frame.scene = &pj->direct_scene;
    pj->albedo_frame = *frame;
    pj->albedo_frame.scene = &pj->albedo_scene;
    pj->environment = frame->scene->environment;
    pj->samples = reference->path_rtv ? 1 : reference->path_samples;
    pj->bounces = reference->path_bounces;
    if (reference->path_rtv && (r = prepare_rtv(ctx, pj)) != MESO_OK) {
        release_rtv(pj, reference->num_objects);
        free(reflected);
        free(pj);
        return r;
    }
    pj->tiles_x = (frame->width + REFERENCE_TILE - 1) / REFERENCE_TILE;
    pj->color = color, pj->coverage = coverage, pj->depth = depth;
    pj->reflected = reflected;
    atomic_init(&pj->cancelled, false);
    size_t tiles =
        (size_t)pj->tiles_x * (size_t)((frame->height + REFERENCE_TILE - 1) / REFERENCE_TILE);
    int passes = (pj->samples + PASS_SAMPLES - 1) / PASS_SAMPLES;
    double start = meso_time_seconds();
    pj->progress = meso_progress_begin(ctx, "reference: path trace", tiles * (size_t)passes);
    for (pj->pass = 0; pj->pass < passes && !atomic_load(&pj->cancelled); pj->pass++)
        meso_parallel_for(ctx, tiles, path_tile, pj);
    meso_progress_end(pj->progress);
    bool cancelled = atomic_load(&pj->cancelled);
    if (!cancelled) {
        double scale = 1.0 / pj->samples;
        for (size_t p = 0; p < 3 * pixels; p++) color[p] += (float)(reflected[p] * scale);
        meso_log_info(ctx, "reference: %s in %.2f s", pj->rtvs ? "RTV shading" : "path traced",
                      meso_time_seconds() - start);
    }
    release_rtv(pj, reference->num_objects);
    free(reflected);
    free(pj);
    if (cancelled) return meso_log_error(ctx, MESO_ERROR_CANCELLED, "reference: render: cancelled");
    return MESO_OK;
}
