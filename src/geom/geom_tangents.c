/* Tangent frames: per-vertex dP/du and dP/dv from the triangles' UV gradients.
 *
 * docs/design.md: T = dP/du, B = dP/dv with their magnitudes (world units per unit of u or v), made
 * orthogonal to the vertex normal; T x B points along N for unmirrored UVs and against it for
 * mirrored ones (the sign is kept, never forced).
 */
#include <math.h>
#include <stdlib.h>

#include "geom_internal.h"
#include "meso/runtime.h"

/* Triangles and vertices per parallel job: fixed, so the result is independent of the thread
 * count (every job writes its own range). */
#define JOB_SIZE 4096

typedef struct face_gradient {
    meso_vec3 dpdu, dpdv;
    float weight; /* world area; 0 when the UVs are degenerate */
} face_gradient;

typedef struct tangent_job {
    meso_mesh *mesh;
    face_gradient *faces;
    geom_vertex_faces adjacency;
} tangent_job;

static void compute_face_gradients(void *user, size_t job, int thread_index) {
    tangent_job *tj = user;
    const meso_mesh *mesh = tj->mesh;
    size_t end = (job + 1) * JOB_SIZE;
    if (end > mesh->num_triangles) end = mesh->num_triangles;
    for (size_t t = job * JOB_SIZE; t < end; t++) {
        const uint32_t *tri = mesh->indices + 3 * t;
        face_gradient *f = &tj->faces[t];
        *f = (face_gradient){{0, 0, 0}, {0, 0, 0}, 0.0f};
        meso_vec3 p0 = mesh->positions[tri[0]];
        meso_vec2 t0 = mesh->uvs[tri[0]], t1 = mesh->uvs[tri[1]], t2 = mesh->uvs[tri[2]];
        meso_vec3 e1 = meso_vec3_sub(mesh->positions[tri[1]], p0);
        meso_vec3 e2 = meso_vec3_sub(mesh->positions[tri[2]], p0);
        double du1 = (double)t1.x - t0.x, dv1 = (double)t1.y - t0.y;
        double du2 = (double)t2.x - t0.x, dv2 = (double)t2.y - t0.y;
        if (geom_uv_edges_are_degenerate(du1, dv1, du2, dv2)) continue;
        double det = du1 * dv2 - du2 * dv1;
        /* e1 = dP/du du1 + dP/dv dv1 and e2 = dP/du du2 + dP/dv dv2, solved for the two
         * gradients (the inverse of the 2x2 UV edge matrix). */
        double inv = 1.0 / det;
        f->dpdu = meso_vec3_make((float)((e1.x * dv2 - e2.x * dv1) * inv),
                                 (float)((e1.y * dv2 - e2.y * dv1) * inv),
                                 (float)((e1.z * dv2 - e2.z * dv1) * inv));
        f->dpdv = meso_vec3_make((float)((e2.x * du1 - e1.x * du2) * inv),
                                 (float)((e2.y * du1 - e1.y * du2) * inv),
                                 (float)((e2.z * du1 - e1.z * du2) * inv));
        f->weight = 0.5f * meso_vec3_length(meso_vec3_cross(e1, e2));
        if (!meso_vec3_is_finite(f->dpdu) || !meso_vec3_is_finite(f->dpdv)) f->weight = 0.0f;
    }
}

static void compute_vertex_frames(void *user, size_t job, int thread_index) {
    tangent_job *tj = user;
    meso_mesh *mesh = tj->mesh;
    size_t end = (job + 1) * JOB_SIZE;
    if (end > mesh->num_vertices) end = mesh->num_vertices;
    for (size_t v = job * JOB_SIZE; v < end; v++) {
        /* Area-weighted mean of the gradients of the vertex's triangles, in a fixed order. */
        double t[3] = {0, 0, 0}, b[3] = {0, 0, 0}, total = 0.0;
        for (size_t k = tj->adjacency.offsets[v]; k < tj->adjacency.offsets[v + 1]; k++) {
            const face_gradient *f = &tj->faces[tj->adjacency.faces[k]];
            if (f->weight <= 0.0f) continue;
            t[0] += (double)f->weight * f->dpdu.x, t[1] += (double)f->weight * f->dpdu.y;
            t[2] += (double)f->weight * f->dpdu.z;
            b[0] += (double)f->weight * f->dpdv.x, b[1] += (double)f->weight * f->dpdv.y;
            b[2] += (double)f->weight * f->dpdv.z;
            total += f->weight;
        }
        meso_vec3 n = mesh->normals[v];
        meso_vec3 tangent = {0, 0, 0}, bitangent = {0, 0, 0};
        if (total > 0.0) {
            tangent =
                meso_vec3_make((float)(t[0] / total), (float)(t[1] / total), (float)(t[2] / total));
            bitangent =
                meso_vec3_make((float)(b[0] / total), (float)(b[1] / total), (float)(b[2] / total));
            /* Gram-Schmidt against N, keeping the in-plane part (and so the magnitude the
             * surface really has along u and v). */
            tangent = meso_vec3_madd(tangent, n, -meso_vec3_dot(tangent, n));
            bitangent = meso_vec3_madd(bitangent, n, -meso_vec3_dot(bitangent, n));
        }
        float lt = meso_vec3_length(tangent), lb = meso_vec3_length(bitangent);
        /* Scale-relative "vanished" test: one gradient may collapse (a pole, a UV strip of
         * zero width) while the other is fine. */
        float floor_length = 1e-6f * fmaxf(lt, lb);
        if (lt > floor_length && lb <= floor_length) {
            bitangent = meso_vec3_scale(meso_vec3_normalize(meso_vec3_cross(n, tangent)), lt);
        } else if (lb > floor_length && lt <= floor_length) {
            tangent = meso_vec3_scale(meso_vec3_normalize(meso_vec3_cross(bitangent, n)), lb);
        } else if (!(lt > 0.0f && lb > 0.0f)) {
            /* No usable UV triangle: any orthonormal frame with T x B = N. */
            tangent = geom_any_perpendicular(n);
            bitangent = meso_vec3_cross(n, tangent);
        }
        mesh->tangents[v] = tangent;
        mesh->bitangents[v] = bitangent;
    }
}

meso_result meso_mesh_compute_tangents(meso_context *ctx, meso_mesh *mesh) {
    if (!mesh->uvs)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "mesh: tangents need texture coordinates and the mesh has none");
    tangent_job tj = {mesh, NULL, {NULL, NULL}};
    meso_vec3 *tangents = NULL, *bitangents = NULL;
    meso_result r = geom_vertex_faces_build(ctx, mesh, &tj.adjacency);
    if (r != MESO_OK) return r;
    tj.faces = malloc((mesh->num_triangles ? mesh->num_triangles : 1) * sizeof(face_gradient));
    tangents = malloc((mesh->num_vertices ? mesh->num_vertices : 1) * sizeof(meso_vec3));
    bitangents = malloc((mesh->num_vertices ? mesh->num_vertices : 1) * sizeof(meso_vec3));
    if (!tj.faces || !tangents || !bitangents) {
        r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY,
                           "mesh: out of memory for the tangents of %zu vertices",
                           mesh->num_vertices);
        goto fail;
    }
    free(mesh->tangents);
    free(mesh->bitangents);
    mesh->tangents = tangents;
    mesh->bitangents = bitangents;
    tangents = bitangents = NULL;
    meso_parallel_for(ctx, (mesh->num_triangles + JOB_SIZE - 1) / JOB_SIZE, compute_face_gradients,
                      &tj);
    meso_parallel_for(ctx, (mesh->num_vertices + JOB_SIZE - 1) / JOB_SIZE, compute_vertex_frames,
                      &tj);
fail:
    free(tangents);
    free(bitangents);
    free(tj.faces);
    geom_vertex_faces_free(&tj.adjacency);
    return r;
}
