/* Solids from the user's tile meshes (docs/design.md's tile conventions): a closed
 * triangle mesh of one tile, x, y -> u, v (periodic), z -> 1 - w, turned once into signed
 * distances on a grid, the representation every consumer (the multilayer bake, the
 * reference's isosurface) reads through meso_solid_distance.
 *
 * With Embree (no hand-made BVH): the mesh and its eight neighbouring copies (so a link that
 * crosses the tile's border continues in the next tile) in one scene; the sign of a node by
 * the parity of the crossings of one ray up each grid column (a point is inside a closed mesh
 * iff a ray from it crosses the surface an odd number of times); the magnitude by Embree's
 * point queries with an exact closest-point-on-triangle callback. Trilinear interpolation of
 * exact distance samples has partial derivatives of at most 1, so dividing by sqrt(3) keeps
 * it a distance bound (the bake sphere traces it).
 */
#include <embree3/rtcore.h>
#include <stdlib.h>
#include <string.h>

#include "mesostructure_internal.h"
#include "meso/runtime.h"

#define DEFAULT_RESOLUTION 96
#define MAX_CROSSINGS 256

/* ---- Checks ------------------------------------------------------------------------------- */

typedef struct edge_use {
    uint32_t a, b; /* welded vertices, a < b */
    int sign;      /* +1 when the triangle runs a -> b */
} edge_use;

static int compare_edges(const void *x, const void *y) {
    const edge_use *e = x, *f = y;
    if (e->a != f->a) return e->a < f->a ? -1 : 1;
    if (e->b != f->b) return e->b < f->b ? -1 : 1;
    return e->sign - f->sign;
}

typedef struct keyed_vertex {
    meso_vec3 p;
    uint32_t index;
} keyed_vertex;

static int compare_positions(const void *x, const void *y) {
    const keyed_vertex *a = x, *b = y;
    if (a->p.x != b->p.x) return a->p.x < b->p.x ? -1 : 1;
    if (a->p.y != b->p.y) return a->p.y < b->p.y ? -1 : 1;
    if (a->p.z != b->p.z) return a->p.z < b->p.z ? -1 : 1;
    return a->index < b->index ? -1 : a->index > b->index;
}

/* Closed, manifold and consistently oriented: after welding equal positions, every edge is
 * used by exactly two triangles, once in each direction. */
static meso_result check_closed(meso_context *ctx, const meso_vec3 *positions, size_t nv,
                                const uint32_t *indices, size_t nt, const char *name) {
    keyed_vertex *order = malloc(nv * sizeof *order);
    uint32_t *weld = malloc(nv * sizeof *weld);
    edge_use *edges = malloc(3 * nt * sizeof *edges);
    meso_result r = MESO_OK;
    if (!order || !weld || !edges) {
        r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", name);
        goto done;
    }
    for (size_t i = 0; i < nv; i++) order[i] = (keyed_vertex){positions[i], (uint32_t)i};
    qsort(order, nv, sizeof *order, compare_positions);
    for (size_t i = 0; i < nv; i++) {
        bool same = i > 0 && order[i - 1].p.x == order[i].p.x && order[i - 1].p.y == order[i].p.y &&
                    order[i - 1].p.z == order[i].p.z;
        weld[order[i].index] = same ? weld[order[i - 1].index] : order[i].index;
    }
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t a = weld[indices[3 * t + (size_t)k]],
                     b = weld[indices[3 * t + (size_t)(k + 1) % 3]];
            edges[3 * t + (size_t)k] = a < b ? (edge_use){a, b, 1} : (edge_use){b, a, -1};
        }
    qsort(edges, 3 * nt, sizeof *edges, compare_edges);
    for (size_t i = 0; i < 3 * nt;) {
        size_t j = i;
        int sum = 0;
        while (j < 3 * nt && edges[j].a == edges[i].a && edges[j].b == edges[i].b)
            sum += edges[j++].sign;
        size_t uses = j - i;
        if (uses == 1) {
            r = meso_log_error(ctx, MESO_ERROR_FORMAT,
                               "%s: the tile mesh is not closed: the edge between vertices %u "
                               "and %u has one triangle (a closed mesh has two at every edge)",
                               name, edges[i].a, edges[i].b);
            goto done;
        }
        if (uses > 2) {
            r = meso_log_error(ctx, MESO_ERROR_FORMAT,
                               "%s: the tile mesh is not manifold: the edge between vertices %u "
                               "and %u has %zu triangles",
                               name, edges[i].a, edges[i].b, uses);
            goto done;
        }
        if (sum != 0) {
            r = meso_log_error(ctx, MESO_ERROR_FORMAT,
                               "%s: the tile mesh is not consistently oriented at the edge "
                               "between vertices %u and %u",
                               name, edges[i].a, edges[i].b);
            goto done;
        }
        i = j;
    }
done:
    free(order);
    free(weld);
    free(edges);
    return r;
}

/* ---- Embree ------------------------------------------------------------------------------- */

typedef struct tile_scene {
    RTCDevice device;
    RTCScene scene;
    const meso_vec3 *positions;
    const uint32_t *indices;
    size_t nt;
    unsigned copies; /* 9: a periodic tile and its neighbours; 1: a model (geometry 4) */
} tile_scene;

/* The closest point of triangle (a, b, c) to p (Ericson, Real-Time Collision Detection §5.1.5,
 * by Voronoi regions). */
static meso_vec3 closest_on_triangle(meso_vec3 p, meso_vec3 a, meso_vec3 b, meso_vec3 c) {
    meso_vec3 ab = meso_vec3_sub(b, a), ac = meso_vec3_sub(c, a), ap = meso_vec3_sub(p, a);
    float d1 = meso_vec3_dot(ab, ap), d2 = meso_vec3_dot(ac, ap);
    if (d1 <= 0.0f && d2 <= 0.0f) return a;
    meso_vec3 bp = meso_vec3_sub(p, b);
    float d3 = meso_vec3_dot(ab, bp), d4 = meso_vec3_dot(ac, bp);
    if (d3 >= 0.0f && d4 <= d3) return b;
    float vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) return meso_vec3_madd(a, ab, d1 / (d1 - d3));
    meso_vec3 cp = meso_vec3_sub(p, c);
    float d5 = meso_vec3_dot(ab, cp), d6 = meso_vec3_dot(ac, cp);
    if (d6 >= 0.0f && d5 <= d6) return c;
    float vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) return meso_vec3_madd(a, ac, d2 / (d2 - d6));
    float va = d3 * d6 - d5 * d4;
    if (va <= 0.0f && (d4 - d3) >= 0.0f && (d5 - d6) >= 0.0f)
        return meso_vec3_madd(b, meso_vec3_sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6)));
    float denom = 1.0f / (va + vb + vc);
    return meso_vec3_add(
        a, meso_vec3_add(meso_vec3_scale(ab, vb * denom), meso_vec3_scale(ac, vc * denom)));
}

typedef struct closest_query {
    const tile_scene *ts;
    float best2;
    float side; /* dot(p - closest, face normal) of the closest triangle: < 0 behind it */
} closest_query;

static bool closest_callback(struct RTCPointQueryFunctionArguments *args) {
    closest_query *q = args->userPtr;
    const tile_scene *ts = q->ts;
    unsigned copy = args->geomID; /* geometry g is the copy shifted by (g % 3 - 1, g / 3 - 1) */
    meso_vec3 shift = {(float)(copy % 3) - 1.0f, (float)(copy / 3) - 1.0f, 0.0f};
    const uint32_t *t = ts->indices + 3 * (size_t)args->primID;
    meso_vec3 p = {args->query->x, args->query->y, args->query->z};
    meso_vec3 a = meso_vec3_add(ts->positions[t[0]], shift);
    meso_vec3 b = meso_vec3_add(ts->positions[t[1]], shift);
    meso_vec3 e = meso_vec3_add(ts->positions[t[2]], shift);
    meso_vec3 c = closest_on_triangle(p, a, b, e);
    meso_vec3 d = meso_vec3_sub(c, p);
    float d2 = meso_vec3_dot(d, d);
    if (d2 < q->best2 || (d2 == q->best2 && q->side == 0.0f)) {
        q->best2 = d2;
        q->side = -meso_vec3_dot(d, meso_vec3_cross(meso_vec3_sub(b, a), meso_vec3_sub(e, a)));
        args->query->radius = sqrtf(d2);
        return true;
    }
    return false;
}

static void release_scene(tile_scene *ts) {
    if (ts->scene) rtcReleaseScene(ts->scene);
    if (ts->device) rtcReleaseDevice(ts->device);
}

/* The mesh and its eight neighbours, geometry g shifted by (g % 3 - 1, g / 3 - 1). */
static meso_result build_scene(meso_context *ctx, tile_scene *ts, size_t nv, const char *name) {
    ts->device = rtcNewDevice("threads=1");
    if (!ts->device)
        return meso_log_error(ctx, MESO_ERROR_INTERNAL, "%s: Embree could not start", name);
    ts->scene = rtcNewScene(ts->device);
    for (unsigned copy = 0; copy < 9; copy++) {
        if (ts->copies == 1 && copy != 4) continue; /* a model: only the unshifted copy */
        RTCGeometry g = rtcNewGeometry(ts->device, RTC_GEOMETRY_TYPE_TRIANGLE);
        float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                           3 * sizeof(float), nv);
        uint32_t *ix = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                               3 * sizeof(uint32_t), ts->nt);
        if (!v || !ix) {
            rtcReleaseGeometry(g);
            return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", name);
        }
        float dx = (float)(copy % 3) - 1.0f, dy = (float)(copy / 3) - 1.0f;
        for (size_t i = 0; i < nv; i++) {
            v[3 * i] = ts->positions[i].x + dx;
            v[3 * i + 1] = ts->positions[i].y + dy;
            v[3 * i + 2] = ts->positions[i].z;
        }
        memcpy(ix, ts->indices, 3 * ts->nt * sizeof(uint32_t));
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(ts->scene, g, copy);
        rtcReleaseGeometry(g);
    }
    rtcCommitScene(ts->scene);
    if (rtcGetDeviceError(ts->device) != RTC_ERROR_NONE)
        return meso_log_error(ctx, MESO_ERROR_INTERNAL, "%s: Embree could not build the tile",
                              name);
    return MESO_OK;
}

/* ---- The grid ----------------------------------------------------------------------------- */

typedef struct grid_job {
    const tile_scene *ts;
    float *grid;
    int n;
} grid_job;

/* One column (i, j): the crossings of a ray up z, then each node's sign and distance. */
static void grid_column(void *user, size_t job, int thread_index) {
    (void)thread_index;
    const grid_job *g = user;
    int n = g->n, i = (int)(job % (size_t)n), j = (int)(job / (size_t)n);
    /* a periodic tile's node n is node 0 of the next tile; a model's grid spans the box */
    float spacing = g->ts->copies == 9 ? 1.0f / (float)n : 1.0f / (float)(n - 1);
    float x = (float)i * spacing, y = (float)j * spacing;
    float crossings[MAX_CROSSINGS];
    int count = 0;
    /* a ray a hair off the node, so it does not run along the mesh's own edges */
    float ox = x + 1.3e-5f, oy = y + 0.7e-5f, tnear = 0.0f;
    while (count < MAX_CROSSINGS) {
        struct RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        struct RTCRayHit rh = {0};
        rh.ray.org_x = ox, rh.ray.org_y = oy, rh.ray.org_z = -1.0f;
        rh.ray.dir_x = 0.0f, rh.ray.dir_y = 0.0f, rh.ray.dir_z = 1.0f;
        rh.ray.tnear = tnear, rh.ray.tfar = 3.0f, rh.ray.mask = 0xffffffffu;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(g->ts->scene, &context, &rh);
        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) break;
        crossings[count++] = rh.ray.tfar - 1.0f;
        tnear = rh.ray.tfar + 1e-6f;
    }
    for (int k = 0; k < n; k++) {
        float w = (float)k / (float)(n - 1), z = 1.0f - w;
        int below = 0;
        for (int c = 0; c < count; c++) below += crossings[c] < z;
        struct RTCPointQueryContext context;
        rtcInitPointQueryContext(&context);
        struct RTCPointQuery q = {.x = x, .y = y, .z = z, .time = 0.0f, .radius = INFINITY};
        closest_query cq = {g->ts, INFINITY, 0.0f};
        rtcPointQuery(g->ts->scene, &q, &context, closest_callback, &cq);
        float d = isfinite(cq.best2) ? sqrtf(cq.best2) : 1.0f;
        /* a closed tile: inside by parity; a model (maybe open): behind its closest face */
        bool inside = g->ts->copies == 9 ? (below & 1) != 0 : cq.side < 0.0f;
        g->grid[((size_t)k * (size_t)n + (size_t)j) * (size_t)n + (size_t)i] = inside ? -d : d;
    }
}

static meso_result create_solid(meso_context *ctx, const meso_vec3 *positions, size_t num_vertices,
                                const uint32_t *indices, size_t num_triangles, const char *name,
                                int resolution, bool periodic, meso_solid **out_solid) {
    *out_solid = NULL;
    name = name ? name : "tile mesh";
    int n = resolution ? resolution : DEFAULT_RESOLUTION;
    if (n < 8 || n > 256)
        return meso_log_error(ctx, MESO_ERROR_LIMIT, "%s: resolution: %d is outside 8..256", name,
                              n);
    if (!positions || !indices || num_triangles == 0 || num_vertices < 3)
        return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: the tile mesh has no triangles", name);
    if (num_triangles > (size_t)1 << 26 || num_vertices > (size_t)UINT32_MAX)
        return meso_log_error(ctx, MESO_ERROR_LIMIT, "%s: %zu triangles exceed the limit %zu", name,
                              num_triangles, (size_t)1 << 26);
    for (size_t i = 0; i < 3 * num_triangles; i++)
        if (indices[i] >= num_vertices)
            return meso_log_error(ctx, MESO_ERROR_FORMAT,
                                  "%s: triangle %zu: vertex %u is out of "
                                  "range",
                                  name, i / 3, indices[i]);
    for (size_t i = 0; i < num_vertices; i++)
        if (!(positions[i].z >= -1e-4f && positions[i].z <= 1.0001f) || !isfinite(positions[i].x) ||
            !isfinite(positions[i].y))
            return meso_log_error(ctx, MESO_ERROR_FORMAT,
                                  "%s: vertex %zu at z = %g is outside the tile's 0 <= z <= 1 "
                                  "(the tile's top, z = 1, lies on the mesh)",
                                  name, i, (double)positions[i].z);
    meso_result r = periodic
                        ? check_closed(ctx, positions, num_vertices, indices, num_triangles, name)
                        : MESO_OK;
    if (r != MESO_OK) return r;
    meso_solid *s = calloc(1, sizeof *s);
    tile_scene ts = {.positions = positions,
                     .indices = indices,
                     .nt = num_triangles,
                     .copies = periodic ? 9u : 1u};
    if (!s || !(s->grid = malloc((size_t)n * (size_t)n * (size_t)n * sizeof(float)))) {
        r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", name);
        goto fail;
    }
    if (!periodic) {
        s->model_uvw = malloc(num_vertices * sizeof *s->model_uvw);
        s->model_indices = malloc(3 * num_triangles * sizeof *s->model_indices);
        if (!s->model_uvw || !s->model_indices) {
            r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", name);
            goto fail;
        }
        for (size_t i = 0; i < num_vertices; i++) /* the box's z runs up: w = 1 - z */
            s->model_uvw[i] = (meso_vec3){positions[i].x, positions[i].y, 1.0f - positions[i].z};
        memcpy(s->model_indices, indices, 3 * num_triangles * sizeof *indices);
        s->model_num_vertices = num_vertices;
        s->model_num_triangles = num_triangles;
    }
    if ((r = build_scene(ctx, &ts, num_vertices, name)) != MESO_OK) goto fail;
    grid_job job = {&ts, s->grid, n};
    meso_parallel_for(ctx, (size_t)n * (size_t)n, grid_column, &job);
    release_scene(&ts);
    s->desc = (meso_solid_desc){.kind = MESO_SOLID_MESH, .count = 1, .thickness = 1.0f};
    s->grid_side = n;
    s->grid_clamped = !periodic;
    s->depth_cells = 1.0f;
    s->scale = 1.0f;
    snprintf(s->grid_name, sizeof s->grid_name, "%s", name);
    uint64_t h = meso_hash64(periodic ? "tile mesh v1" : "model v1 ..", 12, MESO_HASH_SEED);
    h = meso_hash64(positions, num_vertices * sizeof *positions, h);
    h = meso_hash64(indices, 3 * num_triangles * sizeof *indices, h);
    s->grid_hash = meso_hash64(&n, sizeof n, h);
    *out_solid = s;
    return MESO_OK;
fail:
    release_scene(&ts);
    meso_solid_destroy(s);
    return r;
}

meso_result meso_solid_create_from_triangles(meso_context *ctx, const meso_vec3 *positions,
                                             size_t num_vertices, const uint32_t *indices,
                                             size_t num_triangles, const char *name, int resolution,
                                             meso_solid **out_solid) {
    return create_solid(ctx, positions, num_vertices, indices, num_triangles, name, resolution,
                        true, out_solid);
}

meso_result meso_solid_create_from_model(meso_context *ctx, const meso_vec3 *positions,
                                         size_t num_vertices, const uint32_t *indices,
                                         size_t num_triangles, const char *name, int resolution,
                                         meso_solid **out_solid) {
    return create_solid(ctx, positions, num_vertices, indices, num_triangles, name, resolution,
                        false, out_solid);
}

bool meso_solid_is_periodic(const meso_solid *solid) { return !solid->grid_clamped; }

bool meso_solid_model_view(const meso_solid *solid, const meso_vec3 **out_uvw,
                           size_t *out_num_vertices, const uint32_t **out_indices,
                           size_t *out_num_triangles) {
    bool model = solid && solid->model_uvw;
    *out_uvw = model ? solid->model_uvw : NULL;
    *out_num_vertices = model ? solid->model_num_vertices : 0;
    *out_indices = model ? solid->model_indices : NULL;
    *out_num_triangles = model ? solid->model_num_triangles : 0;
    return model;
}

float meso_solid_grid_distance(const meso_solid *solid, meso_vec3 uvw) {
    int n = solid->grid_side;
    float x, y;
    if (solid->grid_clamped) { /* a model: nodes at i / (n - 1), clamped at the box */
        x = fminf(fmaxf(uvw.x, 0.0f), 0.99999f) * (float)(n - 1);
        y = fminf(fmaxf(uvw.y, 0.0f), 0.99999f) * (float)(n - 1);
    } else {
        x = fract_tile(uvw.x) * (float)n;
        y = fract_tile(uvw.y) * (float)n;
    }
    float z = fminf(fmaxf(uvw.z, 0.0f), 1.0f) * (float)(n - 1);
    int i = (int)x, j = (int)y, k = (int)z;
    i = i >= n ? n - 1 : i;
    j = j >= n ? n - 1 : j;
    k = k >= n - 1 ? n - 2 : k;
    float tx = x - (float)i, ty = y - (float)j, tz = z - (float)k;
    int i1 = i + 1 == n ? 0 : i + 1, j1 = j + 1 == n ? 0 : j + 1;
    const float *g = solid->grid;
#define AT(a, b, c) g[((size_t)(c) * (size_t)n + (size_t)(b)) * (size_t)n + (size_t)(a)]
    float c00 = AT(i, j, k) + (AT(i1, j, k) - AT(i, j, k)) * tx;
    float c10 = AT(i, j1, k) + (AT(i1, j1, k) - AT(i, j1, k)) * tx;
    float c01 = AT(i, j, k + 1) + (AT(i1, j, k + 1) - AT(i, j, k + 1)) * tx;
    float c11 = AT(i, j1, k + 1) + (AT(i1, j1, k + 1) - AT(i, j1, k + 1)) * tx;
#undef AT
    float c0 = c00 + (c10 - c00) * ty, c1 = c01 + (c11 - c01) * ty;
    /* partial derivatives <= 1 (exact distance samples one cell apart): / sqrt(3) bounds the
     * gradient by 1 (file comment); the slab closes it as for the procedural solids */
    float d = (c0 + (c1 - c0) * tz) * 0.57735027f;
    return fmaxf(d, fmaxf(-uvw.z, uvw.z - 1.0f));
}
