/* Macro-scale transfer: per-vertex incident radiance in SH with the base mesh's occlusion
 * (render_gi.h; GDM paper §3.2, Sloan et al. 2003's bi-scale radiance transfer). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "reference_internal.h"
#include "render_gi.h"
#include "meso/runtime.h"

enum { VERTICES_PER_JOB = 64, CHANNELS = 3 };

typedef struct transfer_job {
    const meso_mesh *mesh;
    RTCScene scene;
    int directions;
    const meso_vec3 *direction; /* the fixed sample directions */
    const float *weighted;      /* per direction: 3 x 16 of w L(d) Y_i(d) */
    float epsilon;              /* ray offset along the normal, world units */
    float *radiance;
    /* through the shell: per direction w Y_i(d), and per vertex the 16 coefficients of the
     * directions below the tangent plane that meet the base mesh (NULL: opaque below) */
    const float *basis;
    float *interior;
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
        meso_vec3 below = meso_vec3_madd(mesh->positions[v], n, -tj->epsilon);
        float world[CHANNELS * MESO_SH_COUNT] = {0}, inside[MESO_SH_COUNT] = {0};
        for (int d = 0; d < tj->directions; d++) {
            meso_vec3 w = tj->direction[d];
            bool up = meso_vec3_dot(w, n) > 0.0f;
            if (!up && !tj->interior) continue; /* below the macro surface: opaque */
            if (!reference_unoccluded(tj->scene, &context, up ? origin : below, w, INFINITY)) {
                if (up) continue;
                const float *add = tj->basis + (size_t)d * MESO_SH_COUNT;
                for (int k = 0; k < MESO_SH_COUNT; k++) inside[k] += add[k];
                continue;
            }
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
        if (tj->interior) meso_sh_rotate(&rotation, inside, tj->interior + v * MESO_SH_COUNT);
    }
}

meso_result meso_gi_vertex_radiance(meso_context *ctx, const meso_mesh *mesh,
                                    const meso_environment *environment,
                                    const meso_gi_vertex_desc *desc, float **out_radiance) {
    return meso_gi_vertex_radiance_through_shell(ctx, mesh, environment, desc, out_radiance, NULL);
}

meso_result meso_gi_vertex_radiance_through_shell(meso_context *ctx, const meso_mesh *mesh,
                                                  const meso_environment *environment,
                                                  const meso_gi_vertex_desc *desc,
                                                  float **out_radiance, float **out_interior) {
    *out_radiance = NULL;
    if (out_interior) *out_interior = NULL;
    int directions = desc && desc->directions ? desc->directions : 1024;
    if (!mesh || !environment || mesh->num_vertices == 0)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "vertex radiance: needs a mesh and an environment");
    if (directions < 16 || directions > 65536)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "vertex radiance: directions: %d is not in [16, 65536]", directions);
    uint64_t bytes = (uint64_t)mesh->num_vertices * (CHANNELS + 1) * MESO_SH_COUNT * sizeof(float) +
                     (uint64_t)directions * (CHANNELS * MESO_SH_COUNT + 3) * sizeof(float) +
                     (uint64_t)mesh->num_triangles * 64; /* Embree's BVH, generously */
    meso_result r = meso_memory_check(ctx, "vertex radiance", bytes);
    if (r != MESO_OK) return r;
    float *radiance = malloc((size_t)mesh->num_vertices * CHANNELS * MESO_SH_COUNT * sizeof(float));
    meso_vec3 *direction = malloc((size_t)directions * sizeof *direction);
    float *weighted = malloc((size_t)directions * CHANNELS * MESO_SH_COUNT * sizeof(float));
    float *basis = NULL, *interior = NULL;
    if (out_interior) {
        basis = malloc((size_t)directions * MESO_SH_COUNT * sizeof(float));
        interior = malloc((size_t)mesh->num_vertices * MESO_SH_COUNT * sizeof(float));
    }
    RTCDevice device = NULL;
    RTCScene scene = NULL;
    if (!radiance || !direction || !weighted || (out_interior && (!basis || !interior))) {
        r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "vertex radiance: %zu vertices",
                           mesh->num_vertices);
        goto done;
    }
    /* per direction: w L(d) Y_i(d), L from the environment's SH, clamped at 0 */
    float weight = (float)(4.0 * MESO_PI_D / directions);
    for (int d = 0; d < directions; d++) {
        direction[d] = meso_gi_fibonacci_direction(d, directions);
        float y[MESO_SH_COUNT];
        meso_sh_basis(direction[d], y);
        for (int c = 0; c < CHANNELS; c++) {
            float l = fmaxf(0.0f, meso_sh_evaluate(environment->sh[c], direction[d]));
            for (int i = 0; i < MESO_SH_COUNT; i++)
                weighted[((size_t)d * CHANNELS + (size_t)c) * MESO_SH_COUNT + (size_t)i] =
                    weight * l * y[i];
        }
        for (int i = 0; basis && i < MESO_SH_COUNT; i++)
            basis[(size_t)d * MESO_SH_COUNT + (size_t)i] = weight * y[i];
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
                       radiance,  basis,    interior};
    size_t jobs = (mesh->num_vertices + VERTICES_PER_JOB - 1) / VERTICES_PER_JOB;
    meso_parallel_for(ctx, jobs, transfer_vertices, &tj);
    *out_radiance = radiance;
    radiance = NULL;
    if (out_interior) *out_interior = interior;
    interior = NULL;
    r = MESO_OK;
done:
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
    free(weighted);
    free(direction);
    free(radiance);
    free(basis);
    free(interior);
    return r;
}

float meso_gi_open_fraction(const meso_mesostructure *ms) {
    if (ms->kind != MESO_MESOSTRUCTURE_SOLID || !ms->solid) return 0.0f;
    enum { COLUMNS = 64, SAMPLES = 64 };
    int open = 0;
    for (int j = 0; j < COLUMNS; j++)
        for (int i = 0; i < COLUMNS; i++) {
            meso_vec3 uvw = {((float)i + 0.5f) / COLUMNS, ((float)j + 0.5f) / COLUMNS, 0.0f};
            bool through = true;
            for (int k = 0; k < SAMPLES && through; k++) {
                uvw.z = ((float)k + 0.5f) / SAMPLES;
                through = meso_solid_distance(ms->solid, uvw) > 0.0f;
            }
            open += through;
        }
    return (float)open / (COLUMNS * COLUMNS);
}

/* The light arriving on the outside per unit area, averaged over the mesh by area: the
 * environment's irradiance from each vertex's coefficients about its local z, and the lights'
 * at their cosine, unshadowed. */
static meso_vec3 mean_outside_irradiance(const meso_mesh *mesh, const float *radiance,
                                         const meso_scene *scene) {
    double sum[CHANNELS] = {0}, area = 0.0;
    for (size_t t = 0; t < mesh->num_triangles; t++) {
        const uint32_t *tri = mesh->indices + 3 * t;
        meso_vec3 p0 = mesh->positions[tri[0]], p1 = mesh->positions[tri[1]];
        meso_vec3 p2 = mesh->positions[tri[2]];
        double a =
            0.5 * meso_vec3_length(meso_vec3_cross(meso_vec3_sub(p1, p0), meso_vec3_sub(p2, p0)));
        for (int k = 0; k < 3; k++) {
            const float *c = radiance + (size_t)tri[k] * CHANNELS * MESO_SH_COUNT;
            meso_vec3 n = meso_vec3_normalize(mesh->normals[tri[k]]);
            for (int ch = 0; ch < CHANNELS; ch++) {
                double e = meso_sh_irradiance(c + ch * MESO_SH_COUNT, (meso_vec3){0, 0, 1});
                for (int i = 0; i < scene->num_lights; i++) {
                    const meso_light *light = &scene->lights[i];
                    meso_vec3 to = light->type == MESO_LIGHT_DIRECTIONAL
                                       ? light->direction
                                       : meso_vec3_normalize(meso_vec3_sub(
                                             light->position, mesh->positions[tri[k]]));
                    e += (&light->color.x)[ch] * fmax(0.0, meso_vec3_dot(n, to));
                }
                sum[ch] += a / 3.0 * e;
            }
        }
        area += a;
    }
    meso_vec3 out = {0.0f, 0.0f, 0.0f};
    for (int ch = 0; area > 0.0 && ch < CHANNELS; ch++) (&out.x)[ch] = (float)(sum[ch] / area);
    return out;
}

meso_vec3 meso_gi_interior_radiance(const meso_mesh *mesh, const float *radiance,
                                    const meso_scene *scene, meso_vec3 albedo,
                                    float open_fraction) {
    float tau = meso_clampf(open_fraction, 0.0f, 1.0f);
    meso_vec3 e = mean_outside_irradiance(mesh, radiance, scene), out;
    for (int ch = 0; ch < CHANNELS; ch++) {
        float rho = meso_clampf((&albedo.x)[ch], 0.0f, 1.0f);
        float sky = scene->environment ? 0.282095f * scene->environment->sh[ch][0] : 0.0f;
        float wall = tau < 1.0f ? rho * tau * (&e.x)[ch] /
                                      (MESO_PI * (1.0f - tau) * (1.0f - rho * (1.0f - tau)))
                                : 0.0f;
        (&out.x)[ch] = (1.0f - tau) * wall + tau * fmaxf(sky, 0.0f);
    }
    return out;
}
