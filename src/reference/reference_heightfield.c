/* The reference tracer's height fields: the base mesh displaced into real micro-triangles.
 *
 * Subdivision rule: every base edge gets n_e segments so that one segment spans at
 * most one texel of the tiled map along u and along v, n_e = ceil(max(|du| W, |dv| H) * s)
 * (s = the "subdivision" option, 1 by default). A base triangle is split uniformly into
 * n^2 micro-triangles with n = the largest n_e of its edges. Edge vertices are shared between
 * the base triangles of the edge: keyed by the mesh's vertex indices and computed by one
 * function from the edge's two vertices in its canonical direction (lower index first), so
 * both triangles get bit-identical positions and Embree's watertight (robust) test leaves no
 * crack. Where a triangle is finer than one of its edges, its boundary grid points snap to the
 * nearest vertex of that edge, which leaves a few zero-area micro-triangles.
 *
 * Embree representation: RTC_GEOMETRY_TYPE_GRID primitives, each an (n+1) x (n+1) vertex
 * grid. Embree splits grid cell (a, c) into the triangles (a,c)(a+1,c)(a,c+1) and
 * (a+1,c)(a+1,c+1)(a,c+1), so the half a + c <= n is exactly the uniform subdivision of a base
 * triangle T1 = (v0 at (0,0), v1 at (n,0), v3 at (0,n)) with weights ((n-a-c), a, c) / n, and
 * the half a + c >= n that of the triangle T2 = (v2 at (n,n), v3, v1) across T1's edge v1-v3,
 * with weights ((a+c-n), n-a, n-c) / n. Adjacent base triangles with the same n are paired
 * greedily (preferring their longest UV edge, the diagonal of a split quad) into one grid; a
 * triangle left alone gets a grid whose far half is moved onto its edge (c clamped to n - a),
 * zero-area cells. Grids build several times faster and smaller than triangle meshes; the hit's
 * grid (u, v) give the base triangle and its barycentrics directly, so no per-vertex data is kept.
 *
 * View cap: a map tiled many times over a mesh whose UVs span a tile per patch (the teapot)
 * would need hundreds of millions of micro-triangles at one per texel, thousands per pixel.
 * So n_e is also capped at `view_adaptive` (2) segments per pixel of the scene's image, the
 * edge's length measured at its distance from the scene's camera (minus the shell depth):
 * n_e = min(texel rule, ceil(view_adaptive * length / (distance * 2 tan(fov/2) / height))).
 * Geometry is then exact to about half a pixel where the texel rule would be finer; shading
 * normals still come from the height field at the hit's (u, v).
 *
 * Vertices (docs/design.md): P' = P - (1 - h(u, v)) depth N, P on the flat base triangle, N the
 * normalised barycentric interpolation of the vertex normals, h sampled bilinearly.
 */
#include <stdlib.h>
#include <string.h>

#include "reference_internal.h"
#include "meso/runtime.h"

typedef struct hf_edge {
    uint64_t key;  /* low vertex << 32 | high vertex */
    uint32_t slot; /* triangle * 3 + edge */
} hf_edge;

typedef struct hf_build {
    const meso_mesh *mesh;
    const meso_heightfield *hf;
    float depth;
    float subdivision;
    float view_adaptive; /* segments per pixel, 0: off */
    meso_vec3 eye;
    float pixel_angle;  /* 2 tan(fov/2) / height: a pixel's size at distance 1 */
    uint32_t *tri_n;    /* per base triangle */
    uint32_t *tri_edge; /* per base triangle edge: edge id */
    uint32_t *edge_lo, *edge_hi, *edge_n;
    size_t num_edges, num_grids;
    float *vertices;              /* Embree vertex buffer, 3 floats a vertex */
    const uint64_t *grid_offsets; /* first vertex of each grid */
    const reference_grid *grids;
} hf_build;

static int compare_edges(const void *a, const void *b) {
    const hf_edge *x = a, *y = b;
    if (x->key != y->key) return x->key < y->key ? -1 : 1;
    return x->slot < y->slot ? -1 : (x->slot > y->slot);
}

/* Segments of an edge: at most one texel per segment (see the top of the file). */
static double distance_to_segment(meso_vec3 p, meso_vec3 a, meso_vec3 c) {
    meso_vec3 ac = meso_vec3_sub(c, a);
    double len2 = meso_vec3_dot(ac, ac);
    double t = len2 > 0.0 ? meso_vec3_dot(meso_vec3_sub(p, a), ac) / len2 : 0.0;
    t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
    return meso_vec3_length(meso_vec3_sub(p, meso_vec3_madd(a, ac, (float)t)));
}

static uint32_t edge_segments(const hf_build *b, uint32_t lo, uint32_t hi) {
    meso_vec2 uv0 = b->mesh->uvs[lo], uv1 = b->mesh->uvs[hi];
    double du = fabs((double)uv1.x - uv0.x) * b->hf->width;
    double dv = fabs((double)uv1.y - uv0.y) * b->hf->height;
    double span = (du > dv ? du : dv) * b->subdivision;
    if (b->view_adaptive > 0.0f) {
        meso_vec3 p0 = b->mesh->positions[lo], p1 = b->mesh->positions[hi];
        double distance = distance_to_segment(b->eye, p0, p1) - b->depth;
        double pixel = (distance > 0.0 ? distance : 0.0) * b->pixel_angle;
        double length = meso_vec3_length(meso_vec3_sub(p1, p0));
        if (pixel > 0.0) {
            double view = b->view_adaptive * length / pixel;
            span = view < span ? view : span;
        }
    }
    /* 1e-4 absorbs rounding so an edge of exactly 512 texels gets 512 segments */
    double n = ceil(span - 1e-4);
    if (!(n >= 1.0)) n = 1.0;
    if (n > 1048576.0) n = 1048576.0; /* far beyond any limit: keeps the counts finite */
    return (uint32_t)n;
}

static void write_vertex(const hf_build *b, uint64_t index, uint32_t i0, uint32_t i1, uint32_t i2,
                         float w0, float w1, float w2) {
    const meso_mesh *m = b->mesh;
    meso_vec3 p =
        meso_vec3_barycentric(m->positions[i0], m->positions[i1], m->positions[i2], w0, w1, w2);
    meso_vec3 n = meso_vec3_normalize(
        meso_vec3_barycentric(m->normals[i0], m->normals[i1], m->normals[i2], w0, w1, w2));
    meso_vec2 uv = meso_vec2_barycentric(m->uvs[i0], m->uvs[i1], m->uvs[i2], w0, w1, w2);
    float h = meso_heightfield_sample(b->hf, uv.x, uv.y);
    meso_vec3 q = meso_vec3_madd(p, n, -(1.0f - h) * b->depth);
    b->vertices[3 * index + 0] = q.x;
    b->vertices[3 * index + 1] = q.y;
    b->vertices[3 * index + 2] = q.z;
}

/* Write the point of base triangle t with integer weights k (sum n, the triangle's own vertex
 * order) at vertex `index`: corners and edge points through the shared per-vertex / per-edge
 * formulas, interior points barycentrically. */
static void write_point(const hf_build *b, size_t t, uint32_t n, const uint32_t k[3],
                        uint64_t index) {
    const uint32_t *tv = b->mesh->indices + 3 * t;
    for (int i = 0; i < 3; i++)
        if (k[i] == n) {
            write_vertex(b, index, tv[i], tv[i], tv[i], 1.0f, 0.0f, 0.0f);
            return;
        }
    int e = -1;
    uint32_t position = 0; /* along edge e from its first vertex, 0 < position < n */
    if (k[2] == 0)
        e = 0, position = k[1]; /* v0 -> v1 */
    else if (k[0] == 0)
        e = 1, position = k[2]; /* v1 -> v2 */
    else if (k[1] == 0)
        e = 2, position = k[0]; /* v2 -> v0 */
    if (e < 0) {
        write_vertex(b, index, tv[0], tv[1], tv[2], (float)k[0] / (float)n, (float)k[1] / (float)n,
                     (float)k[2] / (float)n);
        return;
    }
    uint32_t id = b->tri_edge[3 * t + (size_t)e];
    uint32_t lo = b->edge_lo[id], hi = b->edge_hi[id], ne = b->edge_n[id];
    uint64_t canonical = tv[e] == lo ? position : n - position;
    /* the nearest of the edge's own ne points, counted in its canonical direction so both
     * triangles of the edge agree */
    uint32_t kc = (uint32_t)((2 * canonical * ne + n) / (2 * (uint64_t)n));
    if (kc == 0) {
        write_vertex(b, index, lo, lo, lo, 1.0f, 0.0f, 0.0f);
    } else if (kc >= ne) {
        write_vertex(b, index, hi, hi, hi, 1.0f, 0.0f, 0.0f);
    } else {
        float s = (float)kc / (float)ne;
        write_vertex(b, index, lo, hi, lo, 1.0f - s, s, 0.0f);
    }
}

static void fill_grids(void *user, size_t job, int thread_index) {
    const hf_build *b = user;
    size_t end = (job + 1) * 4;
    size_t num_grids = b->num_grids;
    if (end > num_grids) end = num_grids;
    for (size_t g = job * 4; g < end; g++) {
        const reference_grid *grid = &b->grids[g];
        uint32_t n = b->tri_n[grid->first];
        uint64_t index = b->grid_offsets[g];
        int e = grid->first_edge, f = grid->second_edge;
        for (uint32_t c = 0; c <= n; c++)
            for (uint32_t a = 0; a <= n; a++) {
                uint32_t k[3];
                if (a + c <= n || grid->second == UINT32_MAX) {
                    uint32_t cc = a + c > n ? n - a : c; /* a lone triangle's far half */
                    k[(e + 2) % 3] = n - a - cc;
                    k[e] = a;
                    k[(e + 1) % 3] = cc;
                    write_point(b, grid->first, n, k, index++);
                } else {
                    k[f] = n - a;
                    k[(f + 1) % 3] = n - c;
                    k[(f + 2) % 3] = a + c - n;
                    write_point(b, grid->second, n, k, index++);
                }
            }
    }
}

/* Pair adjacent base triangles with the same n into grids (see the top of the file). */
static size_t pair_triangles(const hf_build *b, const hf_edge *edges, reference_grid *grids,
                             uint32_t *neighbour, bool *paired) {
    const meso_mesh *mesh = b->mesh;
    size_t nt = mesh->num_triangles, slots = 3 * nt;
    for (size_t i = 0; i < slots; i++) neighbour[i] = UINT32_MAX;
    for (size_t i = 0; i + 1 < slots; i++)
        if (edges[i].key == edges[i + 1].key &&
            (i + 2 >= slots || edges[i + 2].key != edges[i].key) &&
            (i == 0 || edges[i - 1].key != edges[i].key)) {
            neighbour[edges[i].slot] = edges[i + 1].slot;
            neighbour[edges[i + 1].slot] = edges[i].slot;
        }
    size_t count = 0;
    for (size_t t = 0; t < nt; t++) {
        if (paired[t]) continue;
        const uint32_t *tv = mesh->indices + 3 * t;
        int best = -1;
        float best_length = -1.0f;
        for (int e = 0; e < 3; e++) {
            uint32_t slot = neighbour[3 * t + (size_t)e];
            if (slot == UINT32_MAX) continue;
            size_t t2 = slot / 3;
            int f = (int)(slot % 3);
            const uint32_t *sv = mesh->indices + 3 * t2;
            /* consistently oriented neighbours run the shared edge the other way */
            if (paired[t2] || t2 == t || b->tri_n[t2] != b->tri_n[t] || sv[f] != tv[(e + 1) % 3] ||
                sv[(f + 1) % 3] != tv[e])
                continue;
            meso_vec2 d = {mesh->uvs[tv[(e + 1) % 3]].x - mesh->uvs[tv[e]].x,
                           mesh->uvs[tv[(e + 1) % 3]].y - mesh->uvs[tv[e]].y};
            float length = d.x * d.x + d.y * d.y;
            if (length > best_length) best = e, best_length = length;
        }
        paired[t] = true;
        if (best < 0) {
            /* alone: T1 = (v0, v1, v2) is (i_{e+2}, i_e, i_{e+1}) with e = 1 */
            grids[count++] = (reference_grid){(uint32_t)t, UINT32_MAX, 1, 0};
            continue;
        }
        uint32_t slot = neighbour[3 * t + (size_t)best];
        paired[slot / 3] = true;
        grids[count++] =
            (reference_grid){(uint32_t)t, slot / 3, (uint8_t)best, (uint8_t)(slot % 3)};
    }
    return count;
}

meso_result reference_build_heightfield(meso_context *ctx, const meso_scene *scene,
                                        const reference_options *options, RTCGeometry geometry,
                                        reference_object *ref, uint64_t *total) {
    const meso_object *object = ref->object;
    const meso_mesh *mesh = object->mesh;
    meso_result result = MESO_OK;
    hf_build b = {.mesh = mesh,
                  .hf = object->mesostructure.height_field,
                  .depth = object->mesostructure.depth};
    b.subdivision = options->subdivision;
    float fov = scene->camera.fov_y_deg > 0.0f && scene->camera.fov_y_deg < 179.0f
                    ? scene->camera.fov_y_deg
                    : 40.0f;
    b.view_adaptive = options->view_adaptive > 0.0f ? options->view_adaptive : 0.0f;
    b.eye = scene->camera.eye;
    b.pixel_angle = 2.0f * tanf(0.5f * fov * MESO_PI / 180.0f) /
                    (float)(scene->height > 0 ? scene->height : 512);
    size_t nt = mesh->num_triangles;
    hf_edge *edges = malloc(3 * nt * sizeof *edges + 1);
    b.tri_n = malloc(nt * sizeof *b.tri_n + 1);
    b.tri_edge = malloc(3 * nt * sizeof *b.tri_edge + 1);
    b.edge_lo = malloc(3 * nt * sizeof *b.edge_lo + 1);
    b.edge_hi = malloc(3 * nt * sizeof *b.edge_hi + 1);
    b.edge_n = malloc(3 * nt * sizeof *b.edge_n + 1);
    uint64_t *grid_offsets = malloc((nt + 1) * sizeof *grid_offsets);
    reference_grid *grids = malloc(nt * sizeof *grids + 1);
    uint32_t *neighbour = malloc(3 * nt * sizeof *neighbour + 1);
    bool *paired = calloc(nt + 1, sizeof *paired);
    if (!edges || !b.tri_n || !b.tri_edge || !b.edge_lo || !b.edge_hi || !b.edge_n ||
        !grid_offsets || !grids || !neighbour || !paired) {
        result = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: reference: %zu triangles",
                                object->name, nt);
        goto fail;
    }

    /* unique edges by vertex pair */
    for (size_t t = 0; t < nt; t++)
        for (int e = 0; e < 3; e++) {
            uint32_t a = mesh->indices[3 * t + (size_t)e];
            uint32_t c = mesh->indices[3 * t + (size_t)((e + 1) % 3)];
            uint32_t lo = a < c ? a : c, hi = a < c ? c : a;
            edges[3 * t + (size_t)e] =
                (hf_edge){((uint64_t)lo << 32) | hi, (uint32_t)(3 * t + (size_t)e)};
        }
    qsort(edges, 3 * nt, sizeof *edges, compare_edges);
    size_t ne = 0;
    for (size_t i = 0; i < 3 * nt; i++) {
        if (i == 0 || edges[i].key != edges[i - 1].key) {
            uint32_t lo = (uint32_t)(edges[i].key >> 32), hi = (uint32_t)edges[i].key;
            b.edge_lo[ne] = lo;
            b.edge_hi[ne] = hi;
            b.edge_n[ne] = edge_segments(&b, lo, hi);
            ne++;
        }
        b.tri_edge[edges[i].slot] = (uint32_t)(ne - 1);
    }
    b.num_edges = ne;

    /* counts, checked against the limit before the geometry is allocated */
    uint64_t vertices = 0, triangles = 0;
    for (size_t t = 0; t < nt; t++) {
        uint32_t n = 1;
        for (int e = 0; e < 3; e++) {
            uint32_t m = b.edge_n[b.tri_edge[3 * t + (size_t)e]];
            n = m > n ? m : n;
        }
        b.tri_n[t] = n;
        triangles += (uint64_t)n * n;
    }
    size_t num_grids = pair_triangles(&b, edges, grids, neighbour, paired);
    for (size_t g = 0; g < num_grids; g++) {
        uint64_t n = b.tri_n[grids[g].first];
        grid_offsets[g] = vertices;
        vertices += (n + 1) * (n + 1);
    }
    grid_offsets[num_grids] = vertices;
    if (*total + triangles > MESO_REFERENCE_MAX_TRIANGLES || vertices >= UINT32_MAX) {
        result = reference_too_many_triangles(ctx, object, "the height field", *total + triangles,
                                              "fewer texels, a smaller uv_scale or subdivision");
        goto fail;
    }

    b.vertices = rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                         3 * sizeof(float), (size_t)vertices);
    struct RTCGrid *rtc_grids = rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_GRID, 0, RTC_FORMAT_GRID, sizeof(struct RTCGrid), num_grids);
    if (!b.vertices || !rtc_grids) {
        result = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: reference: %llu triangles",
                                object->name, (unsigned long long)triangles);
        goto fail;
    }
    for (size_t g = 0; g < num_grids; g++) {
        /* n <= 8192 here: n^2 is within the triangle limit, and Embree allows 32767 */
        uint32_t n = b.tri_n[grids[g].first];
        rtc_grids[g] = (struct RTCGrid){.startVertexID = (unsigned)grid_offsets[g],
                                        .stride = n + 1,
                                        .width = (unsigned short)(n + 1),
                                        .height = (unsigned short)(n + 1)};
    }
    b.grid_offsets = grid_offsets;
    b.grids = grids;
    b.num_grids = num_grids;
    meso_parallel_for(ctx, (num_grids + 3) / 4, fill_grids, &b);

    ref->num_triangles = triangles;
    ref->num_vertices = (size_t)vertices;
    ref->num_base = nt;
    ref->grids = grids;
    ref->side_bytes = num_grids * sizeof *grids;
    grids = NULL;
    *total += triangles;
    meso_log_info(ctx, "%s: reference: %zu base triangles in %zu grids, %llu grid vertices",
                  object->name, nt, num_grids, (unsigned long long)vertices);

fail:
    free(grid_offsets);
    free(grids);
    free(neighbour);
    free(paired);
    free(edges);
    free(b.tri_n);
    free(b.tri_edge);
    free(b.edge_lo);
    free(b.edge_hi);
    free(b.edge_n);
    return result;
}
