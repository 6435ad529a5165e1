/* The reference tracer: the true micro-geometry of every object as real triangles, ray traced
 * with Embree 3. It is the ground truth every technique is measured against.
 *
 * Geometry: objects without mesostructure trace their mesh; height fields are displaced into
 * micro-triangles (reference_heightfield.c); solids are extracted in texture space and mapped
 * into the shell's prisms (reference_solid.c). One Embree scene holds them all (compact,
 * low/median build quality by size, built on the context's threads).
 *
 * Rendering: one primary ray per target sample, through meso_frame_ray_direction at the
 * sample centre, exactly the point the rasterizer samples; its direction has unit view depth,
 * so the hit distance t is the depth output. Hits are shaded with the shared model
 * (meso_shade_point) with the mesostructure's own normal and hard shadows from one occlusion
 * ray per light against the whole scene. Work is split into 16 x 16 sample tiles writing
 * disjoint memory, so the output does not depend on the thread count.
 */
#include <limits.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "reference_internal.h"
#include "meso/bake_isosurface.h"
#include "meso/runtime.h"

#define REFERENCE_LOW_QUALITY_TRIANGLES 2000000

/* ---- Small geometry helpers shared by the reference files --------------------------------- */

void reference_triangle_gradients(const meso_vec3 p[3], const meso_vec2 uv[3], meso_vec3 *out_t,
                                  meso_vec3 *out_b) {
    meso_vec3 e1 = meso_vec3_sub(p[1], p[0]), e2 = meso_vec3_sub(p[2], p[0]);
    float du1 = uv[1].x - uv[0].x, dv1 = uv[1].y - uv[0].y;
    float du2 = uv[2].x - uv[0].x, dv2 = uv[2].y - uv[0].y;
    float det = du1 * dv2 - du2 * dv1;
    if (!(fabsf(det) > 1e-20f)) {
        *out_t = *out_b = (meso_vec3){0, 0, 0};
        return;
    }
    float r = 1.0f / det;
    *out_t = meso_vec3_scale(meso_vec3_sub(meso_vec3_scale(e1, dv2), meso_vec3_scale(e2, dv1)), r);
    *out_b = meso_vec3_scale(meso_vec3_sub(meso_vec3_scale(e2, du1), meso_vec3_scale(e1, du2)), r);
}

bool reference_uv_barycentrics(const meso_vec2 uv[3], meso_vec2 point, float out_weights[3]) {
    float e1x = uv[1].x - uv[0].x, e1y = uv[1].y - uv[0].y;
    float e2x = uv[2].x - uv[0].x, e2y = uv[2].y - uv[0].y;
    float det = e1x * e2y - e1y * e2x;
    if (!(fabsf(det) > 1e-20f)) {
        out_weights[0] = out_weights[1] = out_weights[2] = 1.0f / 3.0f;
        return false;
    }
    float dx = point.x - uv[0].x, dy = point.y - uv[0].y;
    float b1 = (dx * e2y - dy * e2x) / det, b2 = (e1x * dy - e1y * dx) / det;
    out_weights[0] = 1.0f - b1 - b2;
    out_weights[1] = b1;
    out_weights[2] = b2;
    return true;
}

const meso_technique_option meso_reference_options[MESO_REFERENCE_NUM_OPTIONS] = {
    MESO_OPTION_ROW(MESO_OPTION_FLOAT, subdivision, 0.125, 64.0, 1.0,
                    "height fields: micro-triangle edges per texel of the tiled map",
                    reference_options, subdivision),
    MESO_OPTION_ROW(MESO_OPTION_FLOAT, view_adaptive, -1.0, 64.0, 2.0,
                    "height fields: at most this many micro-edges per pixel of the scene's image; "
                    "<= 0 keeps the texel rule alone",
                    reference_options, view_adaptive),
    MESO_OPTION_ROW(MESO_OPTION_INT, resolution, 2, MESO_ISOSURFACE_MAX_RESOLUTION, 128,
                    "solids: extraction grid cells a tile side in u and v (w: a quarter)",
                    reference_options, resolution),
    MESO_OPTION_ROW(MESO_OPTION_INT, samples, 0, 65536, 0,
                    "path-traced samples a pixel (environment and interreflection); 0: the "
                    "direct-light reference",
                    reference_options, samples),
    MESO_OPTION_ROW(MESO_OPTION_INT, bounces, 0, 16, 3,
                    "path tracing: interreflections inside and between objects (0: none)",
                    reference_options, bounces),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, rtv, 0, 1, 0,
                    "light the environment through the radiance transfer volume at the true hit "
                    "(GDM-GI's shading, docs/techniques/gdm-gi.md) instead of path tracing it",
                    reference_options, rtv),
};

meso_result reference_read_options(meso_context *ctx, const meso_scene *scene,
                                   const meso_object *object, const meso_reference_desc *desc,
                                   reference_options *out_options) {
    const meso_technique_info *info = meso_technique_find("reference");
    meso_technique_options_defaults(info, out_options);
    /* The desc (tests and tools) replaces the defaults; the scene still has the last word. */
    if (desc->subdivision > 0) out_options->subdivision = (float)desc->subdivision;
    if (desc->view_adaptive != 0.0f) out_options->view_adaptive = desc->view_adaptive;
    if (desc->isosurface.resolution_u > 0) out_options->resolution = desc->isosurface.resolution_u;
    return meso_technique_options_apply(ctx, scene, object, info, out_options);
}

size_t reference_base_triangle(const reference_object *ref, uint64_t triangle) {
    size_t lo = 0, hi = ref->num_base; /* base_offsets[lo] <= triangle < base_offsets[hi] */
    while (hi - lo > 1) {
        size_t mid = lo + (hi - lo) / 2;
        if (ref->base_offsets[mid] <= triangle)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

/* ---- Creation ----------------------------------------------------------------------------- */

static bool monitor_memory(void *user, ssize_t bytes, bool post) {
    meso_reference *reference = user;
    long long now = atomic_fetch_add(&reference->embree_bytes, (long long)bytes) + bytes;
    /* The micro-triangles' BVH is the reference's big allocation and is known only while
     * Embree builds it: refusing the allocation that crosses the budget makes the build fail
     * cleanly (RTC_ERROR_OUT_OF_MEMORY) instead of the process being killed. */
    if (bytes > 0 && !post && now > reference->memory_limit) {
        atomic_fetch_sub(&reference->embree_bytes, (long long)bytes);
        atomic_store(&reference->over_budget, true);
        return false;
    }
    if (now > reference->embree_peak) reference->embree_peak = now; /* an estimate under races */
    return true;
}

meso_result reference_too_many_triangles(meso_context *ctx, const meso_object *object,
                                         const char *what, uint64_t count, const char *hint) {
    return meso_log_error(ctx, MESO_ERROR_LIMIT,
                          "%s: reference: %s makes %llu triangles, above the limit %llu (%s)",
                          object->name, what, (unsigned long long)count,
                          (unsigned long long)MESO_REFERENCE_MAX_TRIANGLES, hint);
}

static meso_result build_plain(meso_context *ctx, RTCGeometry geometry, reference_object *ref,
                               uint64_t *total) {
    const meso_mesh *mesh = ref->object->mesh;
    if (*total + mesh->num_triangles > MESO_REFERENCE_MAX_TRIANGLES)
        return meso_log_error(ctx, MESO_ERROR_LIMIT,
                              "%s: reference: %llu triangles exceed the limit %llu",
                              ref->object->name, (unsigned long long)(*total + mesh->num_triangles),
                              (unsigned long long)MESO_REFERENCE_MAX_TRIANGLES);
    float *vertices =
        rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                3 * sizeof(float), mesh->num_vertices);
    uint32_t *indices =
        rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                3 * sizeof(uint32_t), mesh->num_triangles);
    if (!vertices || !indices)
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: reference: %zu triangles",
                              ref->object->name, mesh->num_triangles);
    for (size_t v = 0; v < mesh->num_vertices; v++) {
        vertices[3 * v + 0] = mesh->positions[v].x;
        vertices[3 * v + 1] = mesh->positions[v].y;
        vertices[3 * v + 2] = mesh->positions[v].z;
    }
    memcpy(indices, mesh->indices, 3 * mesh->num_triangles * sizeof *indices);
    ref->indices = indices;
    ref->num_triangles = mesh->num_triangles;
    ref->num_vertices = mesh->num_vertices;
    *total += mesh->num_triangles;
    return MESO_OK;
}

/* Embree's build progress, n in [0, 1], as thousandths of the bar. Embree may call from several
 * threads: each advances by what it alone moved `reported` forward. Never cancels. */
typedef struct build_progress {
    meso_progress *progress;
    _Atomic uint64_t reported;
} build_progress;

static bool report_build(void *user, double n) {
    build_progress *b = user;
    uint64_t target = n >= 1.0 ? 1000 : n > 0.0 ? (uint64_t)(n * 1000.0) : 0;
    uint64_t seen = atomic_load(&b->reported);
    while (target > seen && !atomic_compare_exchange_weak(&b->reported, &seen, target)) {
    }
    if (target > seen) meso_progress_advance(b->progress, target - seen);
    return true;
}

meso_result meso_reference_create_with(meso_context *ctx, const meso_scene *scene,
                                       const meso_reference_desc *desc_in,
                                       meso_reference **out_reference) {
    *out_reference = NULL;
    meso_reference_desc desc = desc_in ? *desc_in : (meso_reference_desc){0};
    if (desc.subdivision <= 0) desc.subdivision = 1;
    desc.isosurface = meso_isosurface_desc_defaults(&desc.isosurface);
    double start = meso_time_seconds();
    meso_result result = MESO_OK;
    meso_reference *reference = calloc(1, sizeof *reference);
    if (!reference) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "reference");
    atomic_init(&reference->embree_bytes, 0);
    reference->scene_data = scene;
    reference->num_objects = scene->num_objects;
    reference->objects = calloc((size_t)(scene->num_objects > 0 ? scene->num_objects : 1),
                                sizeof *reference->objects);
    if (!reference->objects) {
        free(reference);
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "reference");
    }

    char config[64];
    snprintf(config, sizeof config, "threads=%d", meso_context_num_threads(ctx));
    reference->device = rtcNewDevice(config);
    if (!reference->device) {
        result =
            meso_log_error(ctx, MESO_ERROR_INTERNAL, "reference: Embree: no device (%s)", config);
        goto fail;
    }
    uint64_t limit = meso_context_memory_limit(ctx);
    reference->memory_limit = limit > (uint64_t)LLONG_MAX ? LLONG_MAX : (long long)limit;
    rtcSetDeviceMemoryMonitorFunction(reference->device, monitor_memory, reference);
    reference->scene = rtcNewScene(reference->device);
    rtcSetSceneFlags(reference->scene, RTC_SCENE_FLAG_COMPACT | RTC_SCENE_FLAG_ROBUST);

    /* scene scale for the shadow-ray offset */
    meso_vec3 lo = {INFINITY, INFINITY, INFINITY}, hi = {-INFINITY, -INFINITY, -INFINITY};
    uint64_t total = 0;
    for (int o = 0; o < scene->num_objects; o++) {
        const meso_object *object = &scene->objects[o];
        reference_object *ref = &reference->objects[o];
        ref->object = object;
        meso_vec3 mlo, mhi;
        meso_mesh_bounds(object->mesh, &mlo, &mhi);
        lo = (meso_vec3){fminf(lo.x, mlo.x), fminf(lo.y, mlo.y), fminf(lo.z, mlo.z)};
        hi = (meso_vec3){fmaxf(hi.x, mhi.x), fmaxf(hi.y, mhi.y), fmaxf(hi.z, mhi.z)};
        meso_mesostructure_kind kind = object->mesostructure.kind;
        if (kind != MESO_MESOSTRUCTURE_NONE && !object->mesh->uvs) {
            result = meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                                    "%s: mesostructure needs texture coordinates, the mesh has "
                                    "none",
                                    object->name);
            goto fail;
        }
        if (kind == MESO_MESOSTRUCTURE_HEIGHT_FIELD && !object->mesostructure.height_field) {
            result = meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                                    "%s: mesostructure: no height field", object->name);
            goto fail;
        }
        if (object->mesh->num_triangles == 0) continue; /* nothing to trace */
        RTCGeometry geometry = rtcNewGeometry(
            reference->device, kind == MESO_MESOSTRUCTURE_HEIGHT_FIELD ? RTC_GEOMETRY_TYPE_GRID
                               : kind == MESO_MESOSTRUCTURE_SOLID      ? RTC_GEOMETRY_TYPE_QUAD
                                                                  : RTC_GEOMETRY_TYPE_TRIANGLE);
        reference_options options;
        result = reference_read_options(ctx, scene, object, &desc, &options);
        if (result == MESO_OK) {
            /* frame-wide settings: the most any object asks for */
            if (options.samples > reference->path_samples)
                reference->path_samples = options.samples;
            if (options.bounces > reference->path_bounces)
                reference->path_bounces = options.bounces;
            if (options.rtv) reference->path_rtv = true;
        }
        if (result != MESO_OK) {
        } else if (kind == MESO_MESOSTRUCTURE_HEIGHT_FIELD) {
            ref->kind = REFERENCE_HEIGHT_FIELD;
            result = reference_build_heightfield(ctx, scene, &options, geometry, ref, &total);
        } else if (kind == MESO_MESOSTRUCTURE_SOLID) {
            ref->kind = REFERENCE_SOLID;
            result = reference_build_solid(ctx, &desc, &options, geometry, ref, &total);
        } else {
            ref->kind = REFERENCE_PLAIN;
            result = build_plain(ctx, geometry, ref, &total);
        }
        if (result != MESO_OK) {
            rtcReleaseGeometry(geometry);
            goto fail;
        }
        reference->side_bytes += ref->side_bytes;
        rtcCommitGeometry(geometry);
        rtcAttachGeometryByID(reference->scene, geometry, (unsigned)o);
        rtcReleaseGeometry(geometry);
    }
    reference->num_triangles = total;
    double built = meso_time_seconds();
    /* the scene's quality picks the builder: Morton (LOW) builds several times faster than
     * SAH (MEDIUM) and costs little tracing time at one ray per pixel plus shadow rays */
    bool low = total > REFERENCE_LOW_QUALITY_TRIANGLES;
    rtcSetSceneBuildQuality(reference->scene,
                            low ? RTC_BUILD_QUALITY_LOW : RTC_BUILD_QUALITY_MEDIUM);
    build_progress build = {desc.progress ? meso_progress_begin(ctx, "reference BVH", 1000) : NULL,
                            0};
    if (build.progress) rtcSetSceneProgressMonitorFunction(reference->scene, report_build, &build);
    rtcCommitScene(reference->scene);
    meso_progress_end(build.progress);
    enum RTCError error = rtcGetDeviceError(reference->device);
    if (error != RTC_ERROR_NONE && atomic_load(&reference->over_budget)) {
        result = meso_log_error(ctx, MESO_ERROR_LIMIT,
                                "%s: reference: the ray-tracing structure needs more memory than "
                                "the limit of %.1f MiB (--memory-limit)",
                                scene->path, (double)limit / (double)(UINT64_C(1) << 20));
        goto fail;
    }
    if (error != RTC_ERROR_NONE) {
        result = meso_log_error(
            ctx, error == RTC_ERROR_OUT_OF_MEMORY ? MESO_ERROR_OUT_OF_MEMORY : MESO_ERROR_INTERNAL,
            "reference: Embree error %d while building", (int)error);
        goto fail;
    }
    float diagonal = meso_vec3_length(meso_vec3_sub(hi, lo));
    reference->epsilon = 1e-5f * (isfinite(diagonal) && diagonal > 0.0f ? diagonal : 1.0f);
    double end = meso_time_seconds();
    meso_log_info(ctx,
                  "reference: %llu triangles, %.1f MiB (Embree %.1f MiB measured, side data "
                  "%.1f MiB); geometry %.3f s, BVH %.3f s",
                  (unsigned long long)total, (double)meso_reference_memory(reference) / 1048576.0,
                  (double)reference->embree_peak / 1048576.0,
                  (double)reference->side_bytes / 1048576.0, built - start, end - built);
    *out_reference = reference;
    return MESO_OK;

fail:
    meso_reference_destroy(reference);
    return result;
}

meso_result meso_reference_create(meso_context *ctx, const meso_scene *scene,
                                  meso_reference **out_reference) {
    return meso_reference_create_with(ctx, scene, NULL, out_reference);
}

void meso_reference_destroy(meso_reference *reference) {
    if (!reference) return;
    for (int o = 0; o < reference->num_objects; o++) {
        free(reference->objects[o].uvws);
        free(reference->objects[o].grids);
        free(reference->objects[o].base_offsets);
        free(reference->objects[o].caps);
    }
    free(reference->objects);
    if (reference->scene) rtcReleaseScene(reference->scene);
    if (reference->device) rtcReleaseDevice(reference->device);
    free(reference);
}

size_t meso_reference_memory(const meso_reference *reference) {
    if (!reference) return 0;
    long long embree = reference->embree_peak;
    return (size_t)(embree > 0 ? embree : 0) + reference->side_bytes;
}

uint64_t meso_reference_triangle_count(const meso_reference *reference) {
    return reference ? reference->num_triangles : 0;
}

/* ---- Shading at a hit --------------------------------------------------------------------- */

meso_vec3 reference_quad_uvw(const reference_object *ref, unsigned primitive, float hu, float hv) {
    /* an Embree quad (q0, q1, q2, q3): (q0, q1, q3) with weights (1-u-v, u, v) below the
     * diagonal, (q2, q3, q1) with (u+v-1, 1-u, 1-v) above it */
    const uint32_t *q = ref->indices + 4 * (size_t)primitive;
    return hu + hv <= 1.0f
               ? meso_vec3_barycentric(ref->uvws[q[0]], ref->uvws[q[1]], ref->uvws[q[3]],
                                       1.0f - hu - hv, hu, hv)
               : meso_vec3_barycentric(ref->uvws[q[2]], ref->uvws[q[3]], ref->uvws[q[1]],
                                       hu + hv - 1.0f, 1.0f - hu, 1.0f - hv);
}

void reference_surface_at(const reference_object *ref, unsigned primitive, float hu, float hv,
                          meso_vec3 *out_normal, meso_vec2 *out_uv, reference_base *out_base) {
    const meso_mesh *mesh = ref->object->mesh;
    if (ref->kind == REFERENCE_PLAIN) {
        const uint32_t *tri = ref->indices + 3 * (size_t)primitive;
        float w0 = 1.0f - hu - hv;
        if (out_base) *out_base = (reference_base){primitive, {w0, hu, hv}, 0.0f};
        *out_normal = meso_vec3_normalize(meso_vec3_barycentric(
            mesh->normals[tri[0]], mesh->normals[tri[1]], mesh->normals[tri[2]], w0, hu, hv));
        *out_uv = mesh->uvs ? meso_vec2_barycentric(mesh->uvs[tri[0]], mesh->uvs[tri[1]],
                                                    mesh->uvs[tri[2]], w0, hu, hv)
                            : (meso_vec2){0, 0};
        return;
    }
    /* the base triangle and its frame at the hit's (u, v) */
    meso_vec2 uv;
    float w = 0.0f, b[3];
    size_t base;
    if (ref->kind == REFERENCE_HEIGHT_FIELD) {
        /* the grid's (u, v) are barycentrics of one of its (one or two) base triangles */
        base = reference_grid_weights(&ref->grids[primitive], hu, hv, b);
    } else {
        meso_vec3 x = reference_quad_uvw(ref, primitive, hu, hv);
        uv = (meso_vec2){x.x, x.y};
        w = x.z;
        base = reference_base_triangle(ref, primitive);
    }
    const uint32_t *bt = mesh->indices + 3 * base;
    meso_vec2 buv[3] = {mesh->uvs[bt[0]], mesh->uvs[bt[1]], mesh->uvs[bt[2]]};
    meso_vec3 bp[3] = {mesh->positions[bt[0]], mesh->positions[bt[1]], mesh->positions[bt[2]]};
    if (ref->kind == REFERENCE_HEIGHT_FIELD)
        uv = meso_vec2_barycentric(buv[0], buv[1], buv[2], b[0], b[1], b[2]);
    else
        reference_uv_barycentrics(buv, uv, b);
    meso_vec3 n = meso_vec3_normalize(meso_vec3_barycentric(
        mesh->normals[bt[0]], mesh->normals[bt[1]], mesh->normals[bt[2]], b[0], b[1], b[2]));
    *out_uv = uv;
    if (out_base) {
        /* a height field's hit lies on its surface: w = 1 - h (docs/design.md) */
        if (ref->kind == REFERENCE_HEIGHT_FIELD)
            w = 1.0f - meso_heightfield_sample(ref->object->mesostructure.height_field, uv.x, uv.y);
        *out_base = (reference_base){base, {b[0], b[1], b[2]}, w};
    }
    if (ref->kind == REFERENCE_HEIGHT_FIELD) {
        meso_vec3 t, bt_vec;
        if (mesh->tangents && mesh->bitangents) {
            t = meso_vec3_barycentric(mesh->tangents[bt[0]], mesh->tangents[bt[1]],
                                      mesh->tangents[bt[2]], b[0], b[1], b[2]);
            bt_vec = meso_vec3_barycentric(mesh->bitangents[bt[0]], mesh->bitangents[bt[1]],
                                           mesh->bitangents[bt[2]], b[0], b[1], b[2]);
        } else {
            reference_triangle_gradients(bp, buv, &t, &bt_vec);
        }
        const meso_mesostructure *ms = &ref->object->mesostructure;
        *out_normal = meso_displaced_normal(
            n, t, bt_vec, ms->depth, meso_heightfield_gradient(ms->height_field, uv.x, uv.y));
        return;
    }
    if (ref->caps && ref->caps[primitive]) {
        /* a cap at an open border (reference_solid.c): the fin's own normal, turned out of
         * the prism (away from the base triangle's centroid) */
        const uint32_t *q = ref->indices + 4 * (size_t)primitive;
        meso_vec3 p[4];
        for (int k = 0; k < 4; k++)
            p[k] = (meso_vec3){ref->vertices[3 * (size_t)q[k]], ref->vertices[3 * (size_t)q[k] + 1],
                               ref->vertices[3 * (size_t)q[k] + 2]};
        meso_vec3 m = meso_vec3_cross(meso_vec3_sub(p[2], p[0]), meso_vec3_sub(p[3], p[1]));
        meso_vec3 centroid =
            meso_vec3_scale(meso_vec3_add(meso_vec3_add(bp[0], bp[1]), bp[2]), 1.0f / 3.0f);
        meso_vec3 middle = meso_vec3_scale(
            meso_vec3_add(meso_vec3_add(p[0], p[1]), meso_vec3_add(p[2], p[3])), 0.25f);
        if (meso_vec3_dot(m, meso_vec3_sub(middle, centroid)) < 0.0f) m = meso_vec3_negate(m);
        float len = meso_vec3_length(m);
        *out_normal = len > 0.0f && isfinite(len) ? meso_vec3_scale(m, 1.0f / len) : n;
        return;
    }
    /* solid: the field's gradient through the Jacobian of the prism map
     * M(u, v, w) = sum_i b_i(u, v) (P_i - w depth N_i), n = J^-T grad f. J is taken with the
     * interpolated tangent frame (T, B, -depth N), as the rasterized techniques shade, rather
     * than the flat triangle's dM/du, dM/dv, which would show the base mesh's facets. */
    float depth = ref->object->mesostructure.depth;
    meso_vec3 ju, jv;
    if (mesh->tangents && mesh->bitangents) {
        ju = meso_vec3_barycentric(mesh->tangents[bt[0]], mesh->tangents[bt[1]],
                                   mesh->tangents[bt[2]], b[0], b[1], b[2]);
        jv = meso_vec3_barycentric(mesh->bitangents[bt[0]], mesh->bitangents[bt[1]],
                                   mesh->bitangents[bt[2]], b[0], b[1], b[2]);
    } else {
        reference_triangle_gradients(bp, buv, &ju, &jv);
    }
    meso_vec3 jw = meso_vec3_scale(n, -depth);
    /* the gradient by central differences of the field, in tile coordinates */
    meso_vec3 local = {uv.x - floorf(uv.x), uv.y - floorf(uv.y), w};
    const float h = 1e-3f;
    meso_vec3 g;
    g.x = ref->field(ref->field_user, (meso_vec3){local.x + h, local.y, local.z}) -
          ref->field(ref->field_user, (meso_vec3){local.x - h, local.y, local.z});
    g.y = ref->field(ref->field_user, (meso_vec3){local.x, local.y + h, local.z}) -
          ref->field(ref->field_user, (meso_vec3){local.x, local.y - h, local.z});
    g.z = ref->field(ref->field_user, (meso_vec3){local.x, local.y, local.z + h}) -
          ref->field(ref->field_user, (meso_vec3){local.x, local.y, local.z - h});
    meso_vec3 cu = meso_vec3_cross(jv, jw), cv = meso_vec3_cross(jw, ju),
              cw = meso_vec3_cross(ju, jv);
    float det = meso_vec3_dot(ju, cu);
    meso_vec3 m = meso_vec3_add(meso_vec3_add(meso_vec3_scale(cu, g.x), meso_vec3_scale(cv, g.y)),
                                meso_vec3_scale(cw, g.z));
    m = meso_vec3_normalize(det < 0.0f ? meso_vec3_negate(m) : m);
    *out_normal = meso_vec3_dot(m, m) > 0.0f ? m : n;
}

/* ---- Rendering ---------------------------------------------------------------------------- */

bool reference_trace(const meso_reference *reference, struct RTCIntersectContext *context,
                     meso_vec3 origin, meso_vec3 dir, float tnear, reference_hit *out_hit) {
    struct RTCRayHit rh;
    memset(&rh, 0, sizeof rh);
    rh.ray.org_x = origin.x;
    rh.ray.org_y = origin.y;
    rh.ray.org_z = origin.z;
    rh.ray.dir_x = dir.x;
    rh.ray.dir_y = dir.y;
    rh.ray.dir_z = dir.z;
    rh.ray.tnear = tnear;
    rh.ray.tfar = INFINITY; /* the rasterizer does not clip at the far plane */
    rh.ray.mask = UINT32_MAX;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(reference->scene, context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    reference_hit *hit = out_hit;
    hit->ref = &reference->objects[rh.hit.geomID];
    hit->t = rh.ray.tfar;
    hit->position = meso_vec3_madd(origin, dir, rh.ray.tfar);
    reference_surface_at(hit->ref, rh.hit.primID, rh.hit.u, rh.hit.v, &hit->normal, &hit->uv,
                         &hit->base);
    /* rays leaving the hit start on the side the ray came from */
    meso_vec3 ng = meso_vec3_normalize((meso_vec3){rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z});
    if (meso_vec3_dot(ng, dir) > 0.0f) ng = meso_vec3_negate(ng);
    hit->geometric_normal = ng;
    hit->origin = meso_vec3_madd(hit->position, ng, reference->epsilon);
    return true;
}

void reference_light_visibility(const meso_reference *reference, meso_vec3 origin,
                                meso_vec3 position, float *visibility) {
    const meso_scene *scene = reference->scene_data;
    struct RTCIntersectContext shadow;
    rtcInitIntersectContext(&shadow);
    for (int l = 0; l < scene->num_lights; l++) {
        const meso_light *light = &scene->lights[l];
        float tfar =
            light->type == MESO_LIGHT_DIRECTIONAL
                ? INFINITY
                : meso_vec3_length(meso_vec3_sub(light->position, origin)) * (1.0f - 1e-5f);
        visibility[l] = reference_unoccluded(reference->scene, &shadow, origin,
                                             meso_light_direction(light, position), tfar)
                            ? 1.0f
                            : 0.0f;
    }
}

typedef struct render_job {
    const meso_reference *reference;
    const meso_frame *frame;
    float *color, *coverage, *depth;
    int tiles_x;
    meso_progress *progress; /* a tile a unit; the user may cancel (an interactive viewer) */
    atomic_bool cancelled;
} render_job;

/* The footprint of the primary hit of sample (i, j) (meso_fragment.duv_dx, duv_dy) by ray
 * differentials (Igehy 1999, "Tracing ray differentials", §3): the camera rays through the next
 * sample to the right and down meet the plane through the hit parallel to its base triangle at
 * P + dP/dx and P + dP/dy, and duv solves dP = du dP/du + dv dP/dv in the least-squares sense,
 * with the base triangle's own dP/du, dP/dv: what the rasterizer's derivatives of the base uv
 * give for the same sample. Zero (a point) without uvs or on a degenerate or edge-on plane. */
static void primary_footprint(const meso_frame *frame, const reference_hit *hit, int i, int j,
                              meso_vec2 *duv_dx, meso_vec2 *duv_dy) {
    *duv_dx = *duv_dy = (meso_vec2){0.0f, 0.0f};
    const meso_mesh *mesh = hit->ref->object->mesh;
    if (!mesh->uvs) return;
    const uint32_t *tri = mesh->indices + 3 * hit->base.triangle;
    meso_vec3 p[3];
    meso_vec2 uv[3];
    for (int k = 0; k < 3; k++) p[k] = mesh->positions[tri[k]], uv[k] = mesh->uvs[tri[k]];
    meso_vec3 t, b;
    reference_triangle_gradients(p, uv, &t, &b);
    meso_vec3 n = meso_vec3_cross(t, b);
    float tt = meso_vec3_dot(t, t), tb = meso_vec3_dot(t, b), bb = meso_vec3_dot(b, b);
    float det = tt * bb - tb * tb;
    if (!(det > 0.0f) || !isfinite(det)) return;
    meso_vec3 dir = meso_frame_ray_direction(frame, (float)i + 0.5f, (float)j + 0.5f);
    float height = meso_vec3_dot(meso_vec3_sub(hit->position, frame->eye), n);
    meso_vec3 next[2] = {meso_vec3_add(dir, frame->pixel_right),
                         meso_vec3_add(dir, frame->pixel_down)};
    meso_vec2 out[2];
    for (int k = 0; k < 2; k++) {
        float along = meso_vec3_dot(next[k], n);
        if (!(fabsf(along) > 0.0f)) return;
        meso_vec3 q = meso_vec3_add(frame->eye, meso_vec3_scale(next[k], height / along));
        meso_vec3 dp = meso_vec3_sub(q, hit->position);
        float rt = meso_vec3_dot(t, dp), rb = meso_vec3_dot(b, dp);
        meso_vec2 d = {(bb * rt - tb * rb) / det, (tt * rb - tb * rt) / det};
        if (!isfinite(d.x) || !isfinite(d.y)) return;
        out[k] = d;
    }
    *duv_dx = out[0], *duv_dy = out[1];
}

bool reference_direct_sample(const meso_reference *reference, const meso_frame *frame,
                             struct RTCIntersectContext *primary, int i, int j, float *color,
                             float *coverage, float *depth, reference_hit *out_hit) {
    const meso_scene *scene = reference->scene_data;
    size_t pixel = (size_t)j * (size_t)frame->width + (size_t)i;
    meso_vec3 dir = meso_frame_ray_direction(frame, (float)i + 0.5f, (float)j + 0.5f);
    /* dot(dir, forward) = 1: t is the view depth, near-clipped like the rasterizer */
    float *c = color + 3 * pixel;
    if (!reference_trace(reference, primary, frame->eye, dir, frame->z_near, out_hit)) {
        c[0] = scene->background.x;
        c[1] = scene->background.y;
        c[2] = scene->background.z;
        coverage[pixel] = 0.0f;
        depth[pixel] = INFINITY;
        return false;
    }
    float visibility[MESO_SCENE_MAX_LIGHTS];
    reference_light_visibility(reference, out_hit->origin, out_hit->position, visibility);
    meso_vec2 duv_dx = {0.0f, 0.0f}, duv_dy = {0.0f, 0.0f};
    if (frame->filter) primary_footprint(frame, out_hit, i, j, &duv_dx, &duv_dy);
    meso_vec3 shaded = reference_shade_hit_footprint(frame, out_hit, duv_dx, duv_dy, visibility);
    c[0] = shaded.x;
    c[1] = shaded.y;
    c[2] = shaded.z;
    coverage[pixel] = 1.0f;
    depth[pixel] = out_hit->t;
    return true;
}

static void render_tile(void *user, size_t job, int thread_index) {
    render_job *rj = user;
    if (atomic_load_explicit(&rj->cancelled, memory_order_relaxed)) return;
    const meso_frame *frame = rj->frame;
    int x0, y0, x1, y1;
    reference_tile_bounds(job, rj->tiles_x, frame->width, frame->height, &x0, &y0, &x1, &y1);
    meso_progress_advance(frame->progress, (uint64_t)(x1 - x0) * (uint64_t)(y1 - y0));
    struct RTCIntersectContext primary;
    rtcInitIntersectContext(&primary);
    primary.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    for (int j = y0; j < y1; j++)
        for (int i = x0; i < x1; i++) {
            reference_hit hit;
            reference_direct_sample(rj->reference, frame, &primary, i, j, rj->color, rj->coverage,
                                    rj->depth, &hit);
        }
    if (meso_progress_advance(rj->progress, 1)) atomic_store(&rj->cancelled, true);
}

meso_result meso_reference_render(meso_context *ctx, const meso_reference *reference,
                                  const meso_frame *frame, float *color, float *coverage,
                                  float *depth) {
    if (!reference || !frame || !color || !coverage || !depth || frame->width <= 0 ||
        frame->height <= 0)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "reference: render: no target");
    if (reference->path_samples > 0 || reference->path_rtv)
        return reference_path_render(ctx, reference, frame, color, coverage, depth);
    render_job rj = {.reference = reference,
                     .frame = frame,
                     .color = color,
                     .coverage = coverage,
                     .depth = depth,
                     .tiles_x = (frame->width + REFERENCE_TILE - 1) / REFERENCE_TILE};
    size_t tiles =
        (size_t)rj.tiles_x * (size_t)((frame->height + REFERENCE_TILE - 1) / REFERENCE_TILE);
    atomic_init(&rj.cancelled, false);
    rj.progress = meso_progress_begin(ctx, "reference: trace", tiles);
    meso_parallel_for(ctx, tiles, render_tile, &rj);
    meso_progress_end(rj.progress);
    if (atomic_load(&rj.cancelled))
        return meso_log_error(ctx, MESO_ERROR_CANCELLED, "reference: render: cancelled");
    return MESO_OK;
}
