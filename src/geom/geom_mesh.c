/* Meshes: create, clone, destroy, bounds, transforms, validation and adjacency helpers. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geom_internal.h"
#include "meso/runtime.h"

/* A triangle is degenerate when its area is below this fraction of its longest edge squared:
 * float positions of collinear points typed in a file carry relative errors of a few 1e-8, so
 * an exact zero test would miss them, while no usable triangle is this thin. */
#define DEGENERATE_RELATIVE_AREA 1e-7

meso_result geom_check_counts(meso_context *ctx, const char *name, uint64_t num_vertices,
                              uint64_t num_triangles) {
    if (num_vertices > MESO_MESH_MAX_VERTICES)
        return meso_log_error(ctx, MESO_ERROR_LIMIT, "%s: %llu vertices exceed the limit %u", name,
                              (unsigned long long)num_vertices, MESO_MESH_MAX_VERTICES);
    if (num_triangles > MESO_MESH_MAX_TRIANGLES)
        return meso_log_error(ctx, MESO_ERROR_LIMIT, "%s: %llu triangles exceed the limit %u", name,
                              (unsigned long long)num_triangles, MESO_MESH_MAX_TRIANGLES);
    return meso_memory_check(ctx, name, meso_mesh_memory_estimate(num_vertices, num_triangles));
}

uint64_t meso_mesh_memory_estimate(uint64_t num_vertices, uint64_t num_triangles) {
    return 150 * num_vertices + 70 * num_triangles;
}

void geom_mesh_free_derived(meso_mesh *mesh) {
    free(mesh->tangents);
    free(mesh->bitangents);
    free(mesh->curvature_max);
    free(mesh->curvature_min);
    free(mesh->curvature_dir_max);
    free(mesh->curvature_dir_min);
    free(mesh->quadrics);
    mesh->tangents = mesh->bitangents = NULL;
    mesh->curvature_max = mesh->curvature_min = NULL;
    mesh->curvature_dir_max = mesh->curvature_dir_min = NULL;
    mesh->quadrics = NULL;
}

static size_t at_least_one(size_t n) { return n ? n : 1; }

meso_result meso_mesh_create(meso_context *ctx, size_t num_vertices, size_t num_triangles,
                             bool with_uvs, meso_mesh **out_mesh) {
    *out_mesh = NULL;
    meso_result r = geom_check_counts(ctx, "mesh", num_vertices, num_triangles);
    if (r != MESO_OK) return r;
    meso_mesh *mesh = calloc(1, sizeof(*mesh));
    if (!mesh) goto fail;
    mesh->num_vertices = num_vertices;
    mesh->num_triangles = num_triangles;
    mesh->positions = calloc(at_least_one(num_vertices), sizeof(meso_vec3));
    mesh->normals = calloc(at_least_one(num_vertices), sizeof(meso_vec3));
    mesh->indices = calloc(at_least_one(3 * num_triangles), sizeof(uint32_t));
    if (!mesh->positions || !mesh->normals || !mesh->indices) goto fail;
    if (with_uvs) {
        mesh->uvs = calloc(at_least_one(num_vertices), sizeof(meso_vec2));
        if (!mesh->uvs) goto fail;
    }
    *out_mesh = mesh;
    return MESO_OK;
fail:
    meso_mesh_destroy(mesh);
    return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY,
                          "mesh: out of memory for %zu vertices and %zu triangles", num_vertices,
                          num_triangles);
}

/* A copy of `count` elements of `size` bytes, or NULL when src is NULL; *ok turns false when an
 * allocation fails. */
static void *copy_array(const void *src, size_t count, size_t size, bool *ok) {
    if (!src) return NULL;
    void *dst = malloc(at_least_one(count) * size);
    if (!dst) {
        *ok = false;
        return NULL;
    }
    memcpy(dst, src, count * size);
    return dst;
}

meso_result meso_mesh_clone(meso_context *ctx, const meso_mesh *mesh, meso_mesh **out_mesh) {
    *out_mesh = NULL;
    meso_mesh *copy = calloc(1, sizeof(*copy));
    if (!copy) goto fail;
    bool ok = true;
    size_t nv = mesh->num_vertices;
    copy->num_vertices = nv;
    copy->num_triangles = mesh->num_triangles;
    copy->positions = copy_array(mesh->positions, nv, sizeof(meso_vec3), &ok);
    copy->normals = copy_array(mesh->normals, nv, sizeof(meso_vec3), &ok);
    copy->uvs = copy_array(mesh->uvs, nv, sizeof(meso_vec2), &ok);
    copy->tangents = copy_array(mesh->tangents, nv, sizeof(meso_vec3), &ok);
    copy->bitangents = copy_array(mesh->bitangents, nv, sizeof(meso_vec3), &ok);
    copy->indices = copy_array(mesh->indices, 3 * mesh->num_triangles, sizeof(uint32_t), &ok);
    copy->curvature_max = copy_array(mesh->curvature_max, nv, sizeof(float), &ok);
    copy->curvature_min = copy_array(mesh->curvature_min, nv, sizeof(float), &ok);
    copy->curvature_dir_max = copy_array(mesh->curvature_dir_max, nv, sizeof(meso_vec3), &ok);
    copy->curvature_dir_min = copy_array(mesh->curvature_dir_min, nv, sizeof(meso_vec3), &ok);
    copy->quadrics = copy_array(mesh->quadrics, nv, sizeof(meso_vec2), &ok);
    if (!ok) goto fail;
    *out_mesh = copy;
    return MESO_OK;
fail:
    meso_mesh_destroy(copy);
    return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "mesh: out of memory cloning %zu vertices",
                          mesh->num_vertices);
}

void meso_mesh_destroy(meso_mesh *mesh) {
    if (!mesh) return;
    geom_mesh_free_derived(mesh);
    free(mesh->positions);
    free(mesh->normals);
    free(mesh->uvs);
    free(mesh->indices);
    free(mesh);
}

void meso_mesh_bounds(const meso_mesh *mesh, meso_vec3 *out_min, meso_vec3 *out_max) {
    meso_vec3 lo = {0, 0, 0}, hi = {0, 0, 0};
    for (size_t i = 0; i < mesh->num_vertices; i++) {
        meso_vec3 p = mesh->positions[i];
        if (i == 0) {
            lo = hi = p;
            continue;
        }
        lo = (meso_vec3){fminf(lo.x, p.x), fminf(lo.y, p.y), fminf(lo.z, p.z)};
        hi = (meso_vec3){fmaxf(hi.x, p.x), fmaxf(hi.y, p.y), fmaxf(hi.z, p.z)};
    }
    *out_min = lo;
    *out_max = hi;
}

void meso_mesh_transform(meso_mesh *mesh, meso_mat4 transform) {
    meso_mat4 normal_matrix = meso_mat4_normal_matrix(transform);
    for (size_t i = 0; i < mesh->num_vertices; i++) {
        mesh->positions[i] = meso_mat4_transform_point(transform, mesh->positions[i]);
        mesh->normals[i] =
            meso_vec3_normalize(meso_mat4_transform_direction(normal_matrix, mesh->normals[i]));
    }
    /* A mirroring transform turns counter-clockwise triangles clockwise; swap two corners so
     * they stay counter-clockwise seen from outside (the normals already follow). */
    const float *m = transform.m;
    float det = m[0] * (m[5] * m[10] - m[9] * m[6]) - m[4] * (m[1] * m[10] - m[9] * m[2]) +
                m[8] * (m[1] * m[6] - m[5] * m[2]);
    if (det < 0.0f) {
        for (size_t t = 0; t < mesh->num_triangles; t++) {
            uint32_t swap = mesh->indices[3 * t + 1];
            mesh->indices[3 * t + 1] = mesh->indices[3 * t + 2];
            mesh->indices[3 * t + 2] = swap;
        }
    }
    geom_mesh_free_derived(mesh);
}

void meso_mesh_scale_uvs(meso_mesh *mesh, meso_vec2 scale) {
    if (mesh->uvs) {
        for (size_t i = 0; i < mesh->num_vertices; i++) {
            mesh->uvs[i].x *= scale.x;
            mesh->uvs[i].y *= scale.y;
        }
    }
    geom_mesh_free_derived(mesh);
}

double geom_triangle_double_area(const meso_mesh *mesh, size_t t) {
    const uint32_t *tri = mesh->indices + 3 * t;
    meso_vec3 a = mesh->positions[tri[0]], b = mesh->positions[tri[1]], c = mesh->positions[tri[2]];
    double e1[3] = {(double)b.x - a.x, (double)b.y - a.y, (double)b.z - a.z};
    double e2[3] = {(double)c.x - a.x, (double)c.y - a.y, (double)c.z - a.z};
    double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                   e1[0] * e2[1] - e1[1] * e2[0]};
    return sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

static double squared_distance(meso_vec3 a, meso_vec3 b) {
    double dx = (double)a.x - b.x, dy = (double)a.y - b.y, dz = (double)a.z - b.z;
    return dx * dx + dy * dy + dz * dz;
}

static bool triangle_is_degenerate(const meso_mesh *mesh, size_t t) {
    const uint32_t *tri = mesh->indices + 3 * t;
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) return true;
    meso_vec3 a = mesh->positions[tri[0]], b = mesh->positions[tri[1]], c = mesh->positions[tri[2]];
    double longest =
        fmax(squared_distance(a, b), fmax(squared_distance(b, c), squared_distance(c, a)));
    if (longest == 0.0) return true;
    return geom_triangle_double_area(mesh, t) <= DEGENERATE_RELATIVE_AREA * longest;
}

/* Zero-length normals (a file's "vn 0 0 0") take the area-weighted normal of the triangles
 * around their position (welded, so texture seams get one normal, as assimp's
 * GenSmoothNormals does); others are made unit. Vertices with no usable triangle get +y. */
static meso_result repair_normals(meso_context *ctx, meso_mesh *mesh) {
    size_t num_zero = 0;
    for (size_t i = 0; i < mesh->num_vertices; i++) {
        float len = meso_vec3_length(mesh->normals[i]);
        if (len == 0.0f)
            num_zero++;
        else if (fabsf(len - 1.0f) > 1e-6f)
            mesh->normals[i] = meso_vec3_scale(mesh->normals[i], 1.0f / len);
    }
    if (num_zero == 0) return MESO_OK;
    geom_weld weld;
    meso_result r = geom_weld_build(ctx, mesh, &weld);
    if (r != MESO_OK) return r;
    meso_vec3 *sums = calloc(at_least_one(weld.num_groups), sizeof(meso_vec3));
    if (!sums) {
        geom_weld_free(&weld);
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "mesh: out of memory for normals");
    }
    for (size_t t = 0; t < mesh->num_triangles; t++) {
        const uint32_t *tri = mesh->indices + 3 * t;
        meso_vec3 a = mesh->positions[tri[0]];
        meso_vec3 face = meso_vec3_cross(meso_vec3_sub(mesh->positions[tri[1]], a),
                                         meso_vec3_sub(mesh->positions[tri[2]], a));
        for (int k = 0; k < 3; k++) {
            meso_vec3 *sum = &sums[weld.group[tri[k]]];
            *sum = meso_vec3_add(*sum, face);
        }
    }
    for (size_t i = 0; i < mesh->num_vertices; i++) {
        if (meso_vec3_length(mesh->normals[i]) != 0.0f) continue;
        meso_vec3 n = meso_vec3_normalize(sums[weld.group[i]]);
        mesh->normals[i] = meso_vec3_length(n) > 0.5f ? n : meso_vec3_make(0.0f, 1.0f, 0.0f);
    }
    free(sums);
    geom_weld_free(&weld);
    return MESO_OK;
}

meso_result meso_mesh_validate(meso_context *ctx, meso_mesh *mesh, const char *name,
                               bool require_uvs) {
    if (!name) name = "mesh";
    meso_result r = geom_check_counts(ctx, name, mesh->num_vertices, mesh->num_triangles);
    if (r != MESO_OK) return r;
    if (!mesh->positions || !mesh->normals || (!mesh->indices && mesh->num_triangles))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: positions, normals and indices are required", name);
    for (size_t i = 0; i < mesh->num_vertices; i++) {
        if (!meso_vec3_is_finite(mesh->positions[i]))
            return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: vertex %zu: position is not finite",
                                  name, i);
        if (!meso_vec3_is_finite(mesh->normals[i]))
            return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: vertex %zu: normal is not finite",
                                  name, i);
        if (mesh->uvs && !(isfinite(mesh->uvs[i].x) && isfinite(mesh->uvs[i].y)))
            return meso_log_error(ctx, MESO_ERROR_FORMAT,
                                  "%s: vertex %zu: texture coordinate is not finite", name, i);
    }
    for (size_t t = 0; t < mesh->num_triangles; t++) {
        for (int k = 0; k < 3; k++) {
            uint32_t index = mesh->indices[3 * t + k];
            if (index >= mesh->num_vertices)
                return meso_log_error(ctx, MESO_ERROR_FORMAT,
                                      "%s: triangle %zu: vertex index %u is out of range "
                                      "(%zu vertices)",
                                      name, t, index, mesh->num_vertices);
        }
    }
    if (require_uvs && !mesh->uvs)
        return meso_log_error(ctx, MESO_ERROR_FORMAT,
                              "%s: has no texture coordinates; a mesostructure needs them", name);

    size_t kept = 0;
    for (size_t t = 0; t < mesh->num_triangles; t++) {
        if (triangle_is_degenerate(mesh, t)) continue;
        if (kept != t)
            memmove(mesh->indices + 3 * kept, mesh->indices + 3 * t, 3 * sizeof(uint32_t));
        kept++;
    }
    size_t dropped = mesh->num_triangles - kept;
    mesh->num_triangles = kept;
    if (kept == 0 && dropped)
        return meso_log_error(ctx, MESO_ERROR_FORMAT,
                              "%s: has no triangles left after dropping %zu degenerate ones", name,
                              dropped);
    if (kept == 0) return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: has no triangles", name);
    if (dropped) meso_log_warning(ctx, "%s: dropped %zu degenerate triangles", name, dropped);
    return repair_normals(ctx, mesh);
}

/* ---- Adjacency ---------------------------------------------------------------------------- */

meso_result geom_vertex_faces_build(meso_context *ctx, const meso_mesh *mesh,
                                    geom_vertex_faces *out) {
    size_t nv = mesh->num_vertices, nt = mesh->num_triangles;
    out->offsets = calloc(nv + 1, sizeof(size_t));
    out->faces = malloc(at_least_one(3 * nt) * sizeof(uint32_t));
    size_t *cursor = malloc((nv + 1) * sizeof(size_t));
    if (!out->offsets || !out->faces || !cursor) {
        free(cursor);
        geom_vertex_faces_free(out);
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY,
                              "mesh: out of memory for the adjacency of %zu vertices", nv);
    }
    for (size_t i = 0; i < 3 * nt; i++) out->offsets[mesh->indices[i] + 1]++;
    for (size_t v = 0; v < nv; v++) out->offsets[v + 1] += out->offsets[v];
    memcpy(cursor, out->offsets, (nv + 1) * sizeof(size_t));
    for (size_t t = 0; t < nt; t++) {
        for (int k = 0; k < 3; k++) {
            uint32_t v = mesh->indices[3 * t + k];
            /* A triangle listing a vertex twice is counted once per corner; that is harmless
             * for the gathers (the triangle is degenerate and weighs nothing). */
            out->faces[cursor[v]++] = (uint32_t)t;
        }
    }
    free(cursor);
    return MESO_OK;
}

void geom_vertex_faces_free(geom_vertex_faces *vf) {
    free(vf->offsets);
    free(vf->faces);
    vf->offsets = NULL;
    vf->faces = NULL;
}

typedef struct weld_key {
    uint32_t bits[3];
    uint32_t vertex;
} weld_key;

static uint32_t float_key(float x) {
    x += 0.0f; /* -0 becomes +0, so both weld */
    uint32_t bits;
    memcpy(&bits, &x, sizeof(bits));
    return bits;
}

static int compare_weld_keys(const void *pa, const void *pb) {
    const weld_key *a = pa, *b = pb;
    for (int k = 0; k < 3; k++)
        if (a->bits[k] != b->bits[k]) return a->bits[k] < b->bits[k] ? -1 : 1;
    return a->vertex < b->vertex ? -1 : (a->vertex > b->vertex);
}

meso_result geom_weld_build(meso_context *ctx, const meso_mesh *mesh, geom_weld *out) {
    size_t nv = mesh->num_vertices;
    memset(out, 0, sizeof(*out));
    weld_key *keys = malloc(at_least_one(nv) * sizeof(weld_key));
    out->group = malloc(at_least_one(nv) * sizeof(uint32_t));
    out->members = malloc(at_least_one(nv) * sizeof(uint32_t));
    out->offsets = malloc((nv + 1) * sizeof(size_t));
    if (!keys || !out->group || !out->members || !out->offsets) {
        free(keys);
        geom_weld_free(out);
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY,
                              "mesh: out of memory welding %zu vertices", nv);
    }
    for (size_t v = 0; v < nv; v++) {
        meso_vec3 p = mesh->positions[v];
        keys[v] = (weld_key){{float_key(p.x), float_key(p.y), float_key(p.z)}, (uint32_t)v};
    }
    qsort(keys, nv, sizeof(weld_key), compare_weld_keys);
    /* Groups are numbered in sorted order; members within a group ascend (the sort's tie
     * break), so every later gather visits them in a fixed order. */
    size_t groups = 0;
    for (size_t i = 0; i < nv; i++) {
        if (i == 0 || memcmp(keys[i].bits, keys[i - 1].bits, sizeof(keys[i].bits)) != 0)
            out->offsets[groups++] = i;
        out->group[keys[i].vertex] = (uint32_t)(groups - 1);
        out->members[i] = keys[i].vertex;
    }
    out->offsets[groups] = nv;
    out->num_groups = groups;
    free(keys);
    return MESO_OK;
}

void geom_weld_free(geom_weld *weld) {
    free(weld->group);
    free(weld->offsets);
    free(weld->members);
    memset(weld, 0, sizeof(*weld));
}

meso_vec3 geom_any_perpendicular(meso_vec3 n) {
    float sign = copysignf(1.0f, n.z);
    float a = -1.0f / (sign + n.z);
    float b = n.x * n.y * a;
    return meso_vec3_normalize(meso_vec3_make(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x));
}

float meso_mesh_tile_length(const meso_mesh *mesh) {
    if (!mesh || !mesh->uvs) return 0.0f;
    double world = 0.0, uv = 0.0;
    for (size_t t = 0; t < mesh->num_triangles; t++) {
        uint32_t a = mesh->indices[3 * t], b = mesh->indices[3 * t + 1],
                 c = mesh->indices[3 * t + 2];
        meso_vec3 e1 = meso_vec3_sub(mesh->positions[b], mesh->positions[a]);
        meso_vec3 e2 = meso_vec3_sub(mesh->positions[c], mesh->positions[a]);
        world += 0.5 * meso_vec3_length(meso_vec3_cross(e1, e2));
        meso_vec2 f1 = {mesh->uvs[b].x - mesh->uvs[a].x, mesh->uvs[b].y - mesh->uvs[a].y};
        meso_vec2 f2 = {mesh->uvs[c].x - mesh->uvs[a].x, mesh->uvs[c].y - mesh->uvs[a].y};
        uv += 0.5 * fabs((double)f1.x * f2.y - (double)f1.y * f2.x);
    }
    return uv > 0.0 && world > 0.0 ? (float)sqrt(world / uv) : 0.0f;
}

/* An edge of the mesh by its end points' positions (their bits), the lower point first, and
 * its slot (triangle * 3 + e). */
typedef struct edge_record {
    uint32_t key[6];
    size_t slot;
} edge_record;

static int edge_record_cmp(const void *pa, const void *pb) {
    const edge_record *a = pa, *b = pb;
    int c = memcmp(a->key, b->key, sizeof a->key);
    if (c) return c;
    return a->slot < b->slot ? -1 : a->slot > b->slot;
}

uint8_t *meso_mesh_open_border_edges(const meso_mesh *mesh) {
    size_t nt = mesh->num_triangles, ne = 3 * nt;
    uint8_t *border = calloc(nt ? nt : 1, 1);
    edge_record *records = malloc((ne ? ne : 1) * sizeof *records);
    if (!border || !records) {
        free(border);
        free(records);
        return NULL;
    }
    for (size_t t = 0; t < nt; t++)
        for (size_t e = 0; e < 3; e++) {
            meso_vec3 p = mesh->positions[mesh->indices[3 * t + e]];
            meso_vec3 q = mesh->positions[mesh->indices[3 * t + (e + 1) % 3]];
            uint32_t a[3], b[3];
            memcpy(a, &p, sizeof a);
            memcpy(b, &q, sizeof b);
            bool swap = memcmp(b, a, sizeof a) < 0;
            edge_record *r = &records[3 * t + e];
            memcpy(r->key, swap ? b : a, sizeof a);
            memcpy(r->key + 3, swap ? a : b, sizeof a);
            r->slot = 3 * t + e;
        }
    qsort(records, ne, sizeof *records, edge_record_cmp);
    for (size_t i = 0; i < ne;) {
        size_t j = i + 1;
        while (j < ne && !memcmp(records[j].key, records[i].key, sizeof records[i].key)) j++;
        if (j == i + 1) border[records[i].slot / 3] |= (uint8_t)(1u << (records[i].slot % 3));
        i = j;
    }
    free(records);
    return border;
}

bool meso_mesh_uv_domain(const meso_mesh *mesh, meso_uv_domain *out) {
    *out = (meso_uv_domain){0};
    if (!mesh->uvs || !mesh->indices || !mesh->num_triangles || !mesh->num_vertices) return true;
    uint8_t *border = meso_mesh_open_border_edges(mesh);
    if (!border) return false;
    meso_uv_domain d = {0, mesh->uvs[0].x, mesh->uvs[0].x, mesh->uvs[0].y, mesh->uvs[0].y};
    for (size_t i = 0; i < mesh->num_vertices; i++) {
        d.u_min = fminf(d.u_min, mesh->uvs[i].x), d.u_max = fmaxf(d.u_max, mesh->uvs[i].x);
        d.v_min = fminf(d.v_min, mesh->uvs[i].y), d.v_max = fmaxf(d.v_max, mesh->uvs[i].y);
    }
    /* a side is open when open borders lie on it and no edge two triangles share does (a
     * teapot's patches meet along their box sides: rays cross those) */
    bool on_box = true;
    unsigned interior = 0;
    for (size_t t = 0; t < mesh->num_triangles; t++)
        for (int e = 0; e < 3; e++) {
            meso_vec2 a = mesh->uvs[mesh->indices[3 * t + (size_t)e]];
            meso_vec2 b = mesh->uvs[mesh->indices[3 * t + (size_t)(e + 1) % 3]];
            unsigned side = a.x == d.u_min && b.x == d.u_min   ? MESO_UV_DOMAIN_U_MIN
                            : a.x == d.u_max && b.x == d.u_max ? MESO_UV_DOMAIN_U_MAX
                            : a.y == d.v_min && b.y == d.v_min ? MESO_UV_DOMAIN_V_MIN
                            : a.y == d.v_max && b.y == d.v_max ? MESO_UV_DOMAIN_V_MAX
                                                               : 0u;
            if (!(border[t] >> e & 1))
                interior |= side;
            else if (side)
                d.sides |= side;
            else
                on_box = false;
        }
    d.sides &= ~interior;
    free(border);
    if (on_box) *out = d;
    return true;
}
