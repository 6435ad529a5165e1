/* Macro-scale transfer: per-vertex incident radiance in SH with the base mesh's occlusion
 * (render_gi.h; GDM paper §3.2, Sloan et al. 2003's bi-scale radiance transfer). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "reference_internal.h"
#include "render_gi.h"

enum { VERTICES_PER_JOB = 64, CHANNELS = 3 };

typedef struct transfer_job {
    const meso_mesh *mesh;
    RTCScene scene;
    int directions;
    const meso_vec3 *direction; /* the fixed sample directions */
    const float *weighted;      /* per direction: 3 x 16 of w L(d) Y_i(d) */
    float epsilon;              /* ray offset along the normal, world units */
    float *radiance;
} transfer_job;

meso_vec3 meso_gi_vertex_tangent(const meso_mesh *mesh, size_t v) {
    meso_vec3 n = meso_vec3_normalize(mesh->normals[v]);
    meso_vec3 t = mesh->tangents ? mesh->tangents[v] : (meso_vec3){0, 0, 0};
    t = meso_vec3_sub(t, meso_vec3_scale(n, meso_vec3_dot(n, t)));
    if (!(meso_vec3_length(t) > 1e-12f)) {
        /* no usable tangent: any direction across the normal */
        t = fabsf(n.x) < 0.9f ? (meso_vec3){1, 0, 0} : (meso_vec3){0, 1, 0};
        t = meso_vec3_sub(t, meso_vec3_scale(n, meso_vec3_dot(n, t)));
    }
    return meso_vec3_normalize(t);
}

float meso_gi_shell_aspect(const meso_object *object) {
    const meso_mesh *mesh = object->mesh;
    double side = 0.0;
    size_t counted = 0;
    for (size_t v = 0; mesh->tangents && mesh->bitangents && v < mesh->num_vertices; v++) {
        float s =
            0.5f * (meso_vec3_length(mesh->tangents[v]) + meso_vec3_length(mesh->bitangents[v]));
        if (s > 0.0f && isfinite(s)) side += s, counted++;
    }
    float mean = counted ? (float)(side / (double)counted) : 1.0f;
    float aspect = object->mesostructure.depth / mean;
    return meso_clampf(aspect, 1e-4f, 100.0f);
}

/* The vertex's tangent frame as the rows of the matrix M with g(d) = f(M d): columns T, B, N. */
static void vertex_frame(const meso_mesh *mesh, size_t v, float out_frame[3][3]) {
    meso_vec3 n = meso_vec3_normalize(mesh->normals[v]);
    meso_vec3 t = meso_gi_vertex_tangent(mesh, v);
    meso_vec3 b = meso_vec3_cross(n, t);
    const meso_vec3 columns[3] = {t, b, n};
    for (int c = 0; c < 3; c++) {
        out_frame[0][c] = columns[c].x;
        out_frame[1][c] = columns[c].y;
        out_frame[2][c] = columns[c].z;
    }
}

static void transfer_vertices(void *user, size_t job, int thread_index) {
    (void)thread_index;
    const transfer_job *tj = user;
    const meso_mesh *mesh = tj->mesh;
    size_t first = job * VERTICES_PER_JOB;
    size_t last = first + VERTICES_PER_JOB < mesh->num_vertices ? first + VERTICES_PER_JOB
                                                                : mesh->num_vertices;
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (size_t v = first; v < last; v++) {
        meso_vec3 n = meso_vec3_normalize(mesh->normals[v]);
        meso_vec3 origin = meso_vec3_madd(mesh->positions[v], n, tj->epsilon);
        float world[CHANNELS * MESO_SH_COUNT] = {0};
        for (int d = 0; d < tj->directions; d++) {
            meso_vec3 w = tj->direction[d];
            if (meso_vec3_dot(w, n) <= 0.0f) continue; /* below the macro surface: opaque */
            if (!reference_unoccluded(tj->scene, &context, origin, w, INFINITY)) continue;
            const float *add = tj->weighted + (size_t)d * CHANNELS * MESO_SH_COUNT;
            for (int k = 0; k < CHANNELS * MESO_SH_COUNT; k++) world[k] += add[k];
        }
        /* into the vertex's frame: local z is the normal, as the meso-scale response's */
        float frame[3][3];
        vertex_frame(mesh, v, frame);
        meso_sh_rotation rotation;
        meso_sh_rotation_init(frame, &rotation);
        for (int c = 0; c < CHANNELS; c++)
            meso_sh_rotate(&rotation, world + c * MESO_SH_COUNT,
                           tj->radiance + (v * CHANNELS + (size_t)c) * MESO_SH_COUNT);
    }
}

meso_result meso_gi_vertex_radiance(meso_context *ctx, const meso_mesh *mesh,
                                    const meso_environment *environment,
                                    const meso_gi_vertex_desc *desc, float **out_radiance) {
    *out_radiance = NULL;
    int directions = desc && desc->directions ? desc->directions : 1024;
    if (!mesh || !environment || mesh->num_vertices == 0)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "vertex radiance: needs a mesh and an environment");
    if (directions < 16 || directions > 65536)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "vertex radiance: directions: %d is not in [16, 65536]", directions);
    uint64_t bytes = (uint64_t)mesh->num_vertices * CHANNELS * MESO_SH_COUNT * sizeof(float) +
                     (uint64_t)directions * (CHANNELS * MESO_SH_COUNT + 3) * sizeof(float) +
                     (uint64_t)mesh->num_triangles * 64; /* Embree's BVH, generously */
    meso_result r = meso_memory_check(ctx, "vertex radiance", bytes);
    if (r != MESO_OK) return r;
    float *radiance = malloc((size_t)mesh->num_vertices * CHANNELS * MESO_SH_COUNT * sizeof(float));
    meso_vec3 *direction = malloc((size_t)directions * sizeof *direction);
    float *weighted = malloc((size_t)directions * CHANNELS * MESO_SH_COUNT * sizeof(float));
    RTCDevice device = NULL;
    RTCScene scene = NULL;
    if (!radiance || !direction || !weighted) {
        r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "vertex radiance: %zu vertices",
                           mesh->num_vertices);
        goto done;
    }
    /* per direction: w L(d) Y_i(d), L from the environment's SH, clamped at 0 */
    float weight = (float)(4.0 * M_PI / directions);
    for (int d = 0; d < directions; d++) {
        direction[d] = meso_gi_fibonacci_direction(d, directions);
        float basis[MESO_SH_COUNT];
        meso_sh_basis(direction[d], basis);
        for (int c = 0; c < CHANNELS; c++) {
            float l = fmaxf(0.0f, meso_sh_evaluate(environment->sh[c], direction[d]));
            for (int i = 0; i < MESO_SH_COUNT; i++)
                weighted[((size_t)d * CHANNELS + (size_t)c) * MESO_SH_COUNT + (size_t)i] =
                    weight * l * basis[i];
        }
    }
    /* the base mesh alone: its triangles as Embree geometry */
    char config[32];
    snprintf(config, sizeof config, "threads=%d", meso_context_num_threads(ctx));
    device = rtcNewDevice(config);
    scene = device ? rtcNewScene(device) : NULL;
    RTCGeometry geometry = scene ? rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE) : NULL;
    float *vertices =
        geometry ? rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                           3 * sizeof(float), mesh->num_vertices)
                 : NULL;
    uint32_t *indices =
        geometry ? rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                           3 * sizeof(uint32_t), mesh->num_triangles)
                 : NULL;
    if (!vertices || !indices) {
        if (geometry) rtcReleaseGeometry(geometry);
        r = meso_log_error(ctx, MESO_ERROR_INTERNAL, "vertex radiance: Embree could not start");
        goto done;
    }
    meso_vec3 lo = mesh->positions[0], hi = lo;
    for (size_t v = 0; v < mesh->num_vertices; v++) {
        meso_vec3 p = mesh->positions[v];
        vertices[3 * v] = p.x, vertices[3 * v + 1] = p.y, vertices[3 * v + 2] = p.z;
        lo = (meso_vec3){fminf(lo.x, p.x), fminf(lo.y, p.y), fminf(lo.z, p.z)};
        hi = (meso_vec3){fmaxf(hi.x, p.x), fmaxf(hi.y, p.y), fmaxf(hi.z, p.z)};
    }
    memcpy(indices, mesh->indices, 3 * mesh->num_triangles * sizeof *indices);
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(scene, geometry);
    rtcReleaseGeometry(geometry);
    rtcCommitScene(scene);
    if (rtcGetDeviceError(device) != RTC_ERROR_NONE) {
        r = meso_log_error(ctx, MESO_ERROR_INTERNAL, "vertex radiance: Embree could not build");
        goto done;
    }
    /* off the surface by 1e-4 of the mesh's size: clear of its own (flat) triangles */
    float diagonal = meso_vec3_length(meso_vec3_sub(hi, lo));
    transfer_job tj = {mesh,      scene,    directions,
                       direction, weighted, 1e-4f * (diagonal > 0.0f ? diagonal : 1.0f),
                       radiance};
    size_t jobs = (mesh->num_vertices + VERTICES_PER_JOB - 1) / VERTICES_PER_JOB;
    meso_parallel_for(ctx, jobs, transfer_vertices, &tj);
    *out_radiance = radiance;
    radiance = NULL;
    r = MESO_OK;
done:
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
    free(weighted);
    free(direction);
    free(radiance);
    return r;
}
