/* The reference tracer's solids: the solid's texture-space isosurface (bake_isosurface.c)
 * mapped into the shell prism of every base triangle.
 *
 * Mapping (GDM §3.1's shell): meso_prism_map (meso/prism.h, src/geom/geom_prism.c),
 * the one definition the gdm technique uses too: a point (u, v, w) inside base triangle t's
 * prism goes to sum_i b_i(u, v) (P_i - w depth N_i), b the barycentric weights of (u, v) in
 * the triangle's UV triangle (uv_scale applied, tiles repeat with period 1).
 *
 * Clipping: the isosurface is bucketed by grid column; a column whose (grown) cell is fully
 * inside the UV triangle is copied, one fully outside an edge is skipped, the others have each
 * iso-triangle clipped
 * to the triangle (Sutherland-Hodgman, in the uv plane, w carried along). So that neighbouring
 * prisms meet without a gap, every point on a base edge is computed the same way from both
 * sides: edges are oriented canonically (lower mesh vertex first, meso_prism_edge), the side
 * test is the same cross product, a cut through a part of an original iso-edge is computed from
 * that edge's end points in a canonical order, and points on an edge are mapped with the edge's two
 * vertices only (the third weight exactly 0).
 *
 * Caps at open borders: a base edge no other triangle shares (a plane's border, a vase's rim)
 * cuts the solid, and the clipped isosurface is open there -- a ray would look into a hollow
 * bar. The cut face is closed by the edge's fin (the shell's side over the edge, w 0..1, in
 * strips one extraction cell wide, mapped with the edge's two vertices as the cuts are), and
 * an Embree filter keeps a hit on it only where the solid's own field is inside: the cap is
 * the solid's cross-section in the fin, exact to the field, shaded with the fin's normal
 * (reference_surface_at). Seams (an edge two triangles share, found by its end points'
 * positions, so that a UV seam's duplicated vertices pair up) get no cap.
 */
#include <stdlib.h>
#include <string.h>

#include "meso/bake_isosurface.h"
#include "meso/runtime.h"
#include "meso/prism.h"
#include "reference_internal.h"

/* The tiles are added to the iso-mesh's local coordinates: every copy of a vertex is
 * tile + local, exact for the small integers of a tile index. */

typedef struct solid_build {
    const meso_mesh *mesh;
    const meso_isosurface *iso;
    float depth;
    /* the w that lies on the mesh: 0 for tiles (the mesh is the shell's top); 0.5 for a
     * model's solid, an impostor, whose quad passes through the model's middle (Policarpo &
     * Oliveira 2006 §4), as relief_layers draws it */
    float mesh_w;
    bool single_tile; /* a model: one copy at tile (0, 0), not a tiling */
    /* per base triangle: output counts (pass 1) and offsets (pass 2) */
    /* per base triangle, counted by primitives (Embree quads; a triangle is a quad with its
     * last vertex repeated) and by the triangles they hold */
    uint64_t *triangle_counts, *vertex_counts, *real_counts;
    const uint64_t *triangle_offsets, *vertex_offsets;
    float *vertices;
    uint32_t *indices;
    meso_vec3 *uvws;
    /* per thread: iso-vertex remap with stamps */
    uint32_t *remap, *stamp, *stamp_counter;
    uint8_t *border; /* per base triangle: bit e set when edge e is an open border */
    uint8_t *caps;   /* per Embree quad, pass 2: 1 for a cap's strip */
} solid_build;

typedef struct emitter {
    const solid_build *b;
    const meso_prism *st; /* the base triangle's prism (meso/prism.h: edges, UV inverse) */
    bool write;
    uint64_t num_triangles, num_vertices; /* primitives and vertices in the base triangle's block */
    uint64_t real_triangles;
    uint64_t triangle_base, vertex_base;
    uint32_t *remap, *stamp, current;
    size_t triangle; /* the base triangle */
    bool cap;        /* the quads emitted now close an open border */
} emitter;

static inline float side(const meso_prism_edge *e, meso_vec2 x) {
    return meso_prism_edge_side(e, x);
}

/* ---- Mapping into the prism (meso_prism_map: one definition for every user) -------------- */

static uint32_t new_vertex(emitter *em, meso_vec3 x, int on_edge) {
    uint64_t index = em->vertex_base + em->num_vertices++;
    if (em->write) {
        meso_vec3 shell = {x.x, x.y, x.z - em->b->mesh_w};
        meso_vec3 p = meso_prism_map(em->st, em->b->mesh, em->b->depth, shell, on_edge);
        float *out = em->b->vertices + 3 * index;
        out[0] = p.x;
        out[1] = p.y;
        out[2] = p.z;
        em->b->uvws[index] = x;
    }
    return (uint32_t)index;
}

/* An original iso-vertex of the current tile, shared by the triangles that use it. */
static uint32_t iso_vertex(emitter *em, uint32_t iso_index, meso_vec3 tile) {
    if (em->stamp[iso_index] == em->current) return em->remap[iso_index];
    em->stamp[iso_index] = em->current;
    meso_vec3 x = meso_vec3_add(em->b->iso->positions[iso_index], tile);
    return em->remap[iso_index] = new_vertex(em, x, -1);
}

/* One Embree quad (a, b, c, d), split by Embree into (a, b, d) and (c, d, b); a triangle is
 * the quad (a, b, c, c). */
static void emit_quad(emitter *em, uint32_t a, uint32_t b, uint32_t c, uint32_t d) {
    uint64_t index = em->triangle_base + em->num_triangles++;
    em->real_triangles += c == d ? 1 : 2;
    if (em->write) {
        uint32_t *out = em->b->indices + 4 * index;
        out[0] = a;
        out[1] = b;
        out[2] = c;
        out[3] = d;
        if (em->cap) em->b->caps[index] = 1;
    }
}

/* ---- Clipping ----------------------------------------------------------------------------- */

typedef struct poly_vertex {
    meso_vec3 x;
    int original; /* 0..2: the iso-triangle's vertex; -1: a cut */
    int iso_edge; /* a cut on the iso-triangle's edge k (from vertex k to k+1); -1: elsewhere */
    int on_edge;  /* a cut on base edge e; -1 */
} poly_vertex;

static bool lex_less(meso_vec3 a, meso_vec3 b) {
    if (a.x != b.x) return a.x < b.x;
    if (a.y != b.y) return a.y < b.y;
    return a.z < b.z;
}

/* The point where segment (p, q) crosses base edge e, computed the same way from both sides of
 * the edge: end points in lexicographic order, the canonical side function. */
static meso_vec3 cut(const meso_prism_edge *e, meso_vec3 p, meso_vec3 q) {
    if (lex_less(q, p)) {
        meso_vec3 s = p;
        p = q;
        q = s;
    }
    float dp = side(e, (meso_vec2){p.x, p.y}), dq = side(e, (meso_vec2){q.x, q.y});
    float t = dp / (dp - dq);
    return meso_vec3_lerp(p, q, t);
}

/* The original iso-edge both poly vertices lie on, or -1. */
static int shared_iso_edge(const poly_vertex *a, const poly_vertex *b) {
    int ea[2] = {-1, -1}, eb[2] = {-1, -1};
    if (a->original >= 0)
        ea[0] = a->original, ea[1] = (a->original + 2) % 3;
    else
        ea[0] = a->iso_edge;
    if (b->original >= 0)
        eb[0] = b->original, eb[1] = (b->original + 2) % 3;
    else
        eb[0] = b->iso_edge;
    for (int i = 0; i < 2; i++)
        for (int j = 0; j < 2; j++)
            if (ea[i] >= 0 && ea[i] == eb[j]) return ea[i];
    return -1;
}

static void clip_triangle(emitter *em, const uint32_t iso_tri[3], meso_vec3 tile,
                          const bool clip_edge[3]) {
    const meso_isosurface *iso = em->b->iso;
    meso_vec3 original[3];
    poly_vertex poly[2][9];
    int count = 3, which = 0;
    for (int k = 0; k < 3; k++) {
        original[k] = meso_vec3_add(iso->positions[iso_tri[k]], tile);
        poly[0][k] = (poly_vertex){original[k], k, -1, -1};
    }
    for (int e = 0; e < 3; e++) {
        if (!clip_edge[e]) continue;
        const meso_prism_edge *edge = &em->st->edges[e];
        const poly_vertex *in = poly[which];
        poly_vertex *out = poly[1 - which];
        int n_out = 0;
        for (int i = 0; i < count; i++) {
            const poly_vertex *a = &in[i], *c = &in[(i + 1) % count];
            float da = edge->sign * side(edge, (meso_vec2){a->x.x, a->x.y});
            float dc = edge->sign * side(edge, (meso_vec2){c->x.x, c->x.y});
            if (da >= 0.0f) out[n_out++] = *a;
            if ((da >= 0.0f) != (dc >= 0.0f) && da != 0.0f && dc != 0.0f) {
                int k = shared_iso_edge(a, c);
                meso_vec3 x =
                    k >= 0 ? cut(edge, original[k], original[(k + 1) % 3]) : cut(edge, a->x, c->x);
                out[n_out++] = (poly_vertex){x, -1, k, e};
            }
        }
        count = n_out;
        which = 1 - which;
        if (count < 3) return;
    }
    /* a fan of the clipped polygon; original vertices keep their shared index */
    uint32_t index[9];
    const poly_vertex *p = poly[which];
    for (int i = 0; i < count; i++)
        index[i] = p[i].original >= 0 ? iso_vertex(em, iso_tri[p[i].original], tile)
                                      : new_vertex(em, p[i].x, p[i].on_edge);
    /* the clipped piece is convex and planar: any split along its inner diagonals keeps its
     * outline, so the fan goes out as quads (p0, pi, pi+1, pi+2) and a last triangle */
    int i = 1;
    for (; i + 2 < count; i += 2) emit_quad(em, index[0], index[i], index[i + 1], index[i + 2]);
    if (i + 1 < count) emit_quad(em, index[0], index[i], index[i + 1], index[i + 1]);
}

/* ---- Caps at open borders ---------------------------------------------------------------- */

/* The fins of the current triangle's open-border edges, in strips about one extraction cell
 * wide along the edge (a fin is a ruled surface, straight across w at every point of the edge,
 * so a narrow strip is all but planar), from w = 0 to 1. Marked as caps: the filter keeps
 * only their hits inside the solid; reference_surface_at turns their normal out of the prism. */
static void emit_caps(emitter *em) {
    uint8_t border = em->b->border[em->triangle];
    if (!border) return;
    const meso_prism *st = em->st;
    const meso_isosurface *iso = em->b->iso;
    em->cap = true;
    for (int e = 0; e < 3; e++) {
        if (!(border & (1u << e))) continue;
        meso_vec2 from = st->uv[e], to = st->uv[(e + 1) % 3];
        float du = fabsf(to.x - from.x) * (float)iso->resolution_u;
        float dv = fabsf(to.y - from.y) * (float)iso->resolution_v;
        float cells = ceilf(fmaxf(du, dv));
        int strips = cells < 1.0f ? 1 : cells > 4096.0f ? 4096 : (int)cells;
        uint32_t top_prev = 0, bottom_prev = 0;
        for (int k = 0; k <= strips; k++) {
            float t = (float)k / (float)strips;
            meso_vec3 x = {from.x + (to.x - from.x) * t, from.y + (to.y - from.y) * t, 0.0f};
            uint32_t top = new_vertex(em, x, e);
            x.z = 1.0f;
            uint32_t bottom = new_vertex(em, x, e);
            if (k > 0) emit_quad(em, top_prev, bottom_prev, bottom, top);
            top_prev = top;
            bottom_prev = bottom;
        }
    }
    em->cap = false;
}

/* Embree's filter on a solid's quads: a cap's hit counts only where the solid is inside. */
static void keep_cap_hits_inside(const struct RTCFilterFunctionNArguments *args) {
    const reference_object *ref = args->geometryUserPtr;
    /* RTCHitN's layout (rtcore_ray.h: Ng x, y, z, u, v, primID, each N wide); its accessors
     * are C++ only */
    const float *hit = (const float *)args->hit;
    const unsigned *prim = (const unsigned *)args->hit + 5 * args->N;
    for (unsigned i = 0; i < args->N; i++) {
        if (args->valid[i] != -1) continue;
        unsigned primitive = prim[i];
        if (!ref->caps[primitive]) continue;
        meso_vec3 x =
            reference_quad_uvw(ref, primitive, hit[3 * args->N + i], hit[4 * args->N + i]);
        meso_vec3 local = {x.x - floorf(x.x), x.y - floorf(x.y), x.z};
        if (!(ref->field(ref->field_user, local) <= 0.0f)) args->valid[i] = 0;
    }
}

/* ---- Per base triangle -------------------------------------------------------------------- */

static long floor_div(long a, long b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

static void process_triangle(emitter *em) {
    const meso_prism *st = em->st;
    const meso_isosurface *iso = em->b->iso;
    int ru = iso->resolution_u, rv = iso->resolution_v;
    float umin = st->uv[0].x, umax = umin, vmin = st->uv[0].y, vmax = vmin;
    for (int i = 1; i < 3; i++) {
        umin = fminf(umin, st->uv[i].x), umax = fmaxf(umax, st->uv[i].x);
        vmin = fminf(vmin, st->uv[i].y), vmax = fmaxf(vmax, st->uv[i].y);
    }
    if (!(umax - umin < 1e6f && vmax - vmin < 1e6f)) return; /* guarded by the caller */
    /* a column's triangles lie within its cell grown by one cell (bake_isosurface.h): visit
     * every column whose grown cell meets the triangle's UV box, in the tiles they belong to */
    long gi0 = (long)floorf(umin * (float)ru) - 1, gi1 = (long)ceilf(umax * (float)ru);
    long gj0 = (long)floorf(vmin * (float)rv) - 1, gj1 = (long)ceilf(vmax * (float)rv);
    long tu0 = floor_div(gi0, ru), tu1 = floor_div(gi1, ru);
    long tv0 = floor_div(gj0, rv), tv1 = floor_div(gj1, rv);
    if (em->b->single_tile) tu0 = tu1 = tv0 = tv1 = 0;
    for (long tv = tv0; tv <= tv1; tv++)
        for (long tu = tu0; tu <= tu1; tu++) {
            meso_vec3 tile = {(float)tu, (float)tv, 0.0f};
            em->current++; /* a new stamp: iso-vertices are shared within one tile copy */
            long i0 = gi0 - tu * ru, i1 = gi1 - tu * ru;
            long j0 = gj0 - tv * rv, j1 = gj1 - tv * rv;
            i0 = i0 < 0 ? 0 : i0, j0 = j0 < 0 ? 0 : j0;
            i1 = i1 >= ru ? ru - 1 : i1, j1 = j1 >= rv ? rv - 1 : j1;
            for (long j = j0; j <= j1; j++)
                for (long i = i0; i <= i1; i++) {
                    size_t column = (size_t)j * (size_t)ru + (size_t)i;
                    uint32_t first = iso->column_offsets[column];
                    uint32_t last = iso->column_offsets[column + 1];
                    if (first == last) continue;
                    bool clip_edge[3], skip = false, any_clip = false;
                    for (int e = 0; e < 3 && !skip; e++) {
                        int n_in = 0;
                        for (int c = 0; c < 4; c++) {
                            meso_vec2 corner = {
                                (float)tu + (float)(i - 1 + 2 * (c & 1)) / (float)ru,
                                (float)tv + (float)(j - 1 + 2 * (c >> 1)) / (float)rv};
                            if (st->edges[e].sign * side(&st->edges[e], corner) >= 0.0f) n_in++;
                        }
                        skip = n_in == 0;
                        clip_edge[e] = n_in < 4;
                        any_clip |= clip_edge[e];
                    }
                    if (skip) continue;
                    if (any_clip) {
                        for (uint32_t t = first; t < last; t++)
                            clip_triangle(em, iso->indices + 3 * (size_t)t, tile, clip_edge);
                        continue;
                    }
                    /* whole quads of the surface net: triangles 2k and 2k + 1 are
                     * (v0, v1, v2) and (v0, v2, v3) (bake_isosurface.h); Embree splits the
                     * quad along v1-v3 instead, which changes no outer edge */
                    for (uint32_t t = first; t + 1 < last; t += 2) {
                        const uint32_t *q0 = iso->indices + 3 * (size_t)t, *q1 = q0 + 3;
                        uint32_t a = iso_vertex(em, q0[0], tile);
                        uint32_t b = iso_vertex(em, q0[1], tile);
                        uint32_t c = iso_vertex(em, q0[2], tile);
                        uint32_t d = iso_vertex(em, q1[2], tile);
                        emit_quad(em, a, b, c, d);
                    }
                }
        }
    emit_caps(em);
}

typedef struct solid_pass {
    solid_build *b;
    bool write;
    size_t num_threads;
} solid_pass;

static void triangle_job(void *user, size_t job, int thread_index) {
    solid_pass *pass = user;
    solid_build *b = pass->b;
    size_t nv_iso = b->iso->num_vertices ? b->iso->num_vertices : 1;
    emitter em = {.b = b,
                  .write = pass->write,
                  .remap = b->remap + (size_t)thread_index * nv_iso,
                  .stamp = b->stamp + (size_t)thread_index * nv_iso,
                  .current = b->stamp_counter[thread_index]};
    size_t end = (job + 1) * 8;
    if (end > b->mesh->num_triangles) end = b->mesh->num_triangles;
    for (size_t t = job * 8; t < end; t++) {
        meso_prism st;
        if (!meso_prism_init(&st, b->mesh, t)) {
            if (!pass->write) b->triangle_counts[t] = b->vertex_counts[t] = b->real_counts[t] = 0;
            continue;
        }
        em.st = &st;
        em.triangle = t;
        em.num_triangles = em.num_vertices = em.real_triangles = 0;
        em.triangle_base = pass->write ? b->triangle_offsets[t] : 0;
        em.vertex_base = pass->write ? b->vertex_offsets[t] : 0;
        process_triangle(&em);
        if (!pass->write) {
            b->triangle_counts[t] = em.num_triangles;
            b->real_counts[t] = em.real_triangles;
            b->vertex_counts[t] = em.num_vertices;
        }
    }
    b->stamp_counter[thread_index] = em.current;
}

static float solid_distance_field(void *user, meso_vec3 uvw) {
    return meso_solid_distance((const meso_solid *)user, uvw);
}

meso_result reference_build_solid(meso_context *ctx, const meso_reference_desc *desc,
                                  const reference_options *options, RTCGeometry geometry,
                                  reference_object *ref, uint64_t *total) {
    const meso_object *object = ref->object;
    const meso_mesh *mesh = object->mesh;
    meso_result result = MESO_OK;
    meso_isosurface_desc idesc = desc->isosurface;
    if (options->resolution != idesc.resolution_u) { /* the object asks for its own grid */
        idesc.resolution_u = idesc.resolution_v = options->resolution;
        idesc.resolution_w = options->resolution / 4 > 2 ? options->resolution / 4 : 2;
    }
    ref->field = desc->solid_field ? desc->solid_field : solid_distance_field;
    ref->field_user =
        desc->solid_field ? desc->solid_field_user : (void *)object->mesostructure.solid;
    if (!desc->solid_field && !object->mesostructure.solid)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: mesostructure: no solid",
                              object->name);

    /* a guard against absurd UV ranges before anything is counted: the tiles the triangles
     * span, each at least one iso-triangle */
    double tiles = 0.0;
    for (size_t t = 0; t < mesh->num_triangles; t++) {
        float umin = INFINITY, umax = -INFINITY, vmin = INFINITY, vmax = -INFINITY;
        for (int i = 0; i < 3; i++) {
            meso_vec2 uv = mesh->uvs[mesh->indices[3 * t + (size_t)i]];
            umin = fminf(umin, uv.x), umax = fmaxf(umax, uv.x);
            vmin = fminf(vmin, uv.y), vmax = fmaxf(vmax, uv.y);
        }
        tiles += (floor(umax) - floor(umin) + 1.0) * (floor(vmax) - floor(vmin) + 1.0);
    }
    if (tiles > (double)MESO_REFERENCE_MAX_TRIANGLES)
        return meso_log_error(ctx, MESO_ERROR_LIMIT,
                              "%s: reference: the solid spans %.0f tiles, above the limit %llu",
                              object->name, tiles,
                              (unsigned long long)MESO_REFERENCE_MAX_TRIANGLES);

    /* An impostor's truth is the model it stands for (Policarpo & Oliveira 2006 §4): its own
     * triangles, in one column of one tile, clipped into the prisms and mapped as the
     * extracted surface of a tile would be; no extraction, so no extraction error. */
    meso_isosurface *extracted = NULL, model_iso = {0};
    uint32_t model_columns[2] = {0, 0};
    const meso_vec3 *model_uvw = NULL;
    const uint32_t *model_indices = NULL;
    size_t model_vertices = 0, model_triangles = 0;
    bool model = !desc->solid_field &&
                 meso_solid_model_view(object->mesostructure.solid, &model_uvw, &model_vertices,
                                       &model_indices, &model_triangles);
    if (model) {
        model_columns[1] = (uint32_t)model_triangles;
        model_iso = (meso_isosurface){.resolution_u = 1,
                                      .resolution_v = 1,
                                      .resolution_w = 1,
                                      .num_vertices = model_vertices,
                                      .num_triangles = model_triangles,
                                      .positions = (meso_vec3 *)model_uvw,
                                      .indices = (uint32_t *)model_indices,
                                      .column_offsets = model_columns};
    } else {
        result =
            meso_isosurface_bake_function(ctx, ref->field, ref->field_user, &idesc, &extracted);
        if (result != MESO_OK) return result;
    }
    const meso_isosurface *iso = model ? &model_iso : extracted;
    meso_log_info(ctx, "%s: reference: %s %d x %d x %d: %zu triangles a tile", object->name,
                  model ? "the model" : "isosurface", iso->resolution_u, iso->resolution_v,
                  iso->resolution_w, iso->num_triangles);

    size_t nt = mesh->num_triangles;
    size_t threads = (size_t)meso_context_num_threads(ctx);
    size_t nv_iso = iso->num_vertices ? iso->num_vertices : 1;
    solid_build b = {.mesh = mesh,
                     .iso = iso,
                     .single_tile = model,
                     .depth = object->mesostructure.depth,
                     .mesh_w = object->mesostructure.solid &&
                                       !meso_solid_is_periodic(object->mesostructure.solid)
                                   ? 0.5f
                                   : 0.0f};
    b.triangle_counts = calloc(nt + 1, sizeof *b.triangle_counts);
    b.vertex_counts = calloc(nt + 1, sizeof *b.vertex_counts);
    b.real_counts = calloc(nt + 1, sizeof *b.real_counts);
    uint64_t *triangle_offsets = calloc(nt + 1, sizeof *triangle_offsets);
    uint64_t *vertex_offsets = calloc(nt + 1, sizeof *vertex_offsets);
    b.remap = calloc(threads * nv_iso, sizeof *b.remap);
    b.stamp = calloc(threads * nv_iso, sizeof *b.stamp);
    b.stamp_counter = calloc(threads, sizeof *b.stamp_counter);
    b.border = meso_mesh_open_border_edges(mesh);
    if (!b.triangle_counts || !b.vertex_counts || !b.real_counts || !triangle_offsets ||
        !vertex_offsets || !b.remap || !b.stamp || !b.stamp_counter || !b.border) {
        result =
            meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: reference: solid", object->name);
        goto fail;
    }

    solid_pass pass = {.b = &b, .write = false, .num_threads = threads};
    meso_parallel_for(ctx, (nt + 7) / 8, triangle_job, &pass);
    uint64_t primitives = 0, vertices = 0, triangles = 0;
    for (size_t t = 0; t < nt; t++) {
        triangle_offsets[t] = primitives;
        vertex_offsets[t] = vertices;
        primitives += b.triangle_counts[t];
        vertices += b.vertex_counts[t];
        triangles += b.real_counts[t];
    }
    triangle_offsets[nt] = primitives;
    vertex_offsets[nt] = vertices;
    if (*total + triangles > MESO_REFERENCE_MAX_TRIANGLES || vertices >= UINT32_MAX) {
        result = reference_too_many_triangles(ctx, object, "the solid", *total + triangles,
                                              "a smaller uv_scale or technique_options.resolution");
        goto fail;
    }
    size_t alloc_v = vertices ? (size_t)vertices : 1;
    size_t alloc_t = primitives ? (size_t)primitives : 1;
    bool any_border = false;
    for (size_t t = 0; t < nt && !any_border; t++) any_border = b.border[t] != 0;
    b.uvws = malloc(alloc_v * sizeof *b.uvws);
    b.caps = any_border ? calloc(alloc_t, 1) : NULL;
    b.vertices = rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                         3 * sizeof(float), alloc_v);
    b.indices = rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT4,
                                        4 * sizeof(uint32_t), alloc_t);
    if (!b.uvws || !b.vertices || !b.indices || (any_border && !b.caps)) {
        free(b.uvws);
        free(b.caps);
        result = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: reference: %llu triangles",
                                object->name, (unsigned long long)triangles);
        goto fail;
    }
    if (!primitives) {
        /* nothing to trace: one degenerate triangle keeps the geometry valid */
        memset(b.vertices, 0, 3 * sizeof(float));
        memset(b.indices, 0, 4 * sizeof(uint32_t));
        memset(b.uvws, 0, sizeof *b.uvws);
    }
    b.triangle_offsets = triangle_offsets;
    b.vertex_offsets = vertex_offsets;
    pass.write = true;
    memset(b.stamp, 0, threads * nv_iso * sizeof *b.stamp);
    memset(b.stamp_counter, 0, threads * sizeof *b.stamp_counter);
    meso_parallel_for(ctx, (nt + 7) / 8, triangle_job, &pass);

    ref->num_triangles = triangles;
    ref->num_vertices = alloc_v;
    ref->indices = b.indices;
    ref->uvws = b.uvws;
    ref->base_offsets = triangle_offsets;
    ref->num_base = nt;
    ref->side_bytes = alloc_v * sizeof *b.uvws + (nt + 1) * sizeof *triangle_offsets;
    ref->caps = b.caps;
    ref->vertices = b.vertices;
    if (b.caps) { /* the open border's caps count only inside the solid */
        size_t caps = 0;
        for (size_t q = 0; q < alloc_t; q++) caps += b.caps[q];
        meso_log_info(ctx, "%s: reference: %zu quads close the open border", object->name, caps);
        ref->side_bytes += alloc_t;
        rtcSetGeometryUserData(geometry, ref);
        rtcSetGeometryIntersectFilterFunction(geometry, keep_cap_hits_inside);
        rtcSetGeometryOccludedFilterFunction(geometry, keep_cap_hits_inside);
    }
    *total += triangles;
    meso_log_info(ctx, "%s: reference: %llu triangles in %llu Embree quads", object->name,
                  (unsigned long long)triangles, (unsigned long long)primitives);
    triangle_offsets = NULL;

fail:
    free(b.triangle_counts);
    free(b.vertex_counts);
    free(b.real_counts);
    free(triangle_offsets);
    free(vertex_offsets);
    free(b.remap);
    free(b.stamp);
    free(b.stamp_counter);
    free(b.border);
    meso_isosurface_destroy(extracted);
    return result;
}
