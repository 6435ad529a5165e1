/* The shell's prisms (include/meso/prism.h): the base triangle's texture <-> object mapping, the
 * extrusion of a mesh into 8 drawable triangles a prism, and the exit of a ray from a prism
 * (GDM §3.1 Fig. 3, §3.2 Fig. 5). */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "geom_internal.h"
#include "meso/runtime.h"
#include "meso/prism.h"

/* ---- One prism ----------------------------------------------------------------------------- */

bool meso_prism_init(meso_prism *prism, const meso_mesh *mesh, size_t triangle) {
    memset(prism, 0, sizeof *prism);
    for (int i = 0; i < 3; i++) {
        prism->vertices[i] = mesh->indices[3 * triangle + (size_t)i];
        prism->uv[i] = mesh->uvs[prism->vertices[i]];
    }
    float e1x = prism->uv[1].x - prism->uv[0].x, e1y = prism->uv[1].y - prism->uv[0].y;
    float e2x = prism->uv[2].x - prism->uv[0].x, e2y = prism->uv[2].y - prism->uv[0].y;
    float det = e1x * e2y - e1y * e2x;
    if (!(fabsf(det) > 1e-12f)) return false;
    prism->uv_inverse[0] = e2y / det;
    prism->uv_inverse[1] = -e2x / det;
    prism->uv_inverse[2] = -e1y / det;
    prism->uv_inverse[3] = e1x / det;
    for (int e = 0; e < 3; e++) {
        uint32_t a = prism->vertices[e], c = prism->vertices[(e + 1) % 3];
        meso_prism_edge *edge = &prism->edges[e];
        edge->lo = a < c ? a : c;
        edge->hi = a < c ? c : a;
        edge->uv_lo = mesh->uvs[edge->lo];
        edge->uv_hi = mesh->uvs[edge->hi];
        float s = meso_prism_edge_side(edge, prism->uv[(e + 2) % 3]);
        if (s == 0.0f) return false;
        edge->sign = s > 0.0f ? 1.0f : -1.0f;
    }
    prism->valid = true;
    return true;
}

meso_vec3 meso_prism_shell_point(const meso_mesh *mesh, uint32_t vertex, float w, float depth) {
    return meso_vec3_madd(mesh->positions[vertex], mesh->normals[vertex], -w * depth);
}

meso_vec3 meso_prism_map(const meso_prism *prism, const meso_mesh *mesh, float depth, meso_vec3 uvw,
                         int on_edge) {
    meso_vec2 uv = {uvw.x, uvw.y};
    if (on_edge < 0)
        for (int e = 0; e < 3 && on_edge < 0; e++)
            if (meso_prism_edge_side(&prism->edges[e], uv) == 0.0f) on_edge = e;
    if (on_edge >= 0) {
        /* from the edge's two vertices in canonical order: the same bits from both sides */
        const meso_prism_edge *e = &prism->edges[on_edge];
        float ax = e->uv_hi.x - e->uv_lo.x, ay = e->uv_hi.y - e->uv_lo.y;
        float t = (ax * (uv.x - e->uv_lo.x) + ay * (uv.y - e->uv_lo.y)) / (ax * ax + ay * ay);
        return meso_vec3_lerp(meso_prism_shell_point(mesh, e->lo, uvw.z, depth),
                              meso_prism_shell_point(mesh, e->hi, uvw.z, depth), t);
    }
    float dx = uv.x - prism->uv[0].x, dy = uv.y - prism->uv[0].y;
    float b1 = prism->uv_inverse[0] * dx + prism->uv_inverse[1] * dy;
    float b2 = prism->uv_inverse[2] * dx + prism->uv_inverse[3] * dy;
    return meso_vec3_barycentric(meso_prism_shell_point(mesh, prism->vertices[0], uvw.z, depth),
                                 meso_prism_shell_point(mesh, prism->vertices[1], uvw.z, depth),
                                 meso_prism_shell_point(mesh, prism->vertices[2], uvw.z, depth),
                                 1.0f - b1 - b2, b1, b2);
}

/* ---- The layer ----------------------------------------------------------------------------- */

static bool lex_less(meso_vec3 a, meso_vec3 b) {
    if (a.x != b.x) return a.x < b.x;
    if (a.y != b.y) return a.y < b.y;
    return a.z < b.z;
}

static meso_prism_plane plane_of(meso_vec3 p0, meso_vec3 p1, meso_vec3 p2) {
    meso_vec3 n = meso_vec3_cross(meso_vec3_sub(p1, p0), meso_vec3_sub(p2, p0));
    float len = meso_vec3_length(n);
    if (!(len > 0.0f) || !isfinite(len)) return (meso_prism_plane){{0.0f, 0.0f, 0.0f}, 0.0f};
    n = meso_vec3_scale(n, 1.0f / len);
    return (meso_prism_plane){n, meso_vec3_dot(n, p0)};
}

/* A face's plane, in `planes` and by component in `plane_lanes`. */
static void store_plane(meso_prism_layer *layer, size_t prism, int slot, meso_prism_plane pl) {
    layer->planes[prism * MESO_PRISM_NUM_FACES + (size_t)slot] = pl;
    float *lanes = layer->plane_lanes + prism * 4 * MESO_PRISM_NUM_FACES + (size_t)slot;
    lanes[0] = pl.normal.x;
    lanes[MESO_PRISM_NUM_FACES] = pl.normal.y;
    lanes[2 * MESO_PRISM_NUM_FACES] = pl.normal.z;
    lanes[3 * MESO_PRISM_NUM_FACES] = pl.offset;
}

static void set_face(meso_prism_layer *layer, size_t prism, int slot, uint32_t a, uint32_t b,
                     uint32_t c) {
    size_t face = meso_prism_layer_face(layer, prism, slot);
    uint32_t *idx = layer->faces->indices + 3 * face;
    idx[0] = a, idx[1] = b, idx[2] = c;
    const meso_vec3 *p = layer->faces->positions;
    store_plane(layer, prism, slot, plane_of(p[a], p[b], p[c]));
}

/* Fin e of prism t over the edge (a, b) of its counter-clockwise base triangle: outward it is
 * the quad (a_top, a_bottom, b_bottom, b_top). Its diagonal joins the top of the edge's
 * lexicographically smaller end to the bottom of the other, decided from positions, so the
 * neighbour (which sees the edge as (b, a), maybe through other vertex numbers at a UV seam)
 * splits it the same way and draws the same two triangles, wound the other way. */
static void extrude_fin(meso_prism_layer *layer, size_t prism, int e, uint32_t a, uint32_t b) {
    const meso_mesh *faces = layer->faces;
    uint32_t nv = (uint32_t)(faces->num_vertices / 2);
    uint32_t at = a, ab = nv + a, bt = b, bb = nv + b;
    int first = MESO_PRISM_FIN + 2 * e;
    bool a_first = lex_less(faces->positions[a], faces->positions[b]) ||
                   (!lex_less(faces->positions[b], faces->positions[a]) && a < b);
    uint32_t apex; /* the second triangle's vertex off the first one's plane */
    if (a_first) { /* diagonal a_top - b_bottom */
        set_face(layer, prism, first, at, ab, bb);
        set_face(layer, prism, first + 1, at, bb, bt);
        apex = bt;
    } else { /* diagonal b_top - a_bottom */
        set_face(layer, prism, first, at, ab, bt);
        set_face(layer, prism, first + 1, ab, bb, bt);
        apex = bb;
    }
    /* convex: the second triangle bends inward of the first one's plane (Fig. 5 b) */
    const meso_prism_plane *pl = &layer->planes[prism * MESO_PRISM_NUM_FACES + (size_t)first];
    float s = meso_vec3_dot(pl->normal, faces->positions[apex]) - pl->offset;
    layer->fin_convex[3 * prism + (size_t)e] = s <= 0.0f;
}

/* A face whose plane no longer bounds its prism: the zero plane (meso_prism_plane). */
static void unbind_face(meso_prism_layer *layer, size_t prism, int slot) {
    store_plane(layer, prism, slot, (meso_prism_plane){{0.0f, 0.0f, 0.0f}, 0.0f});
}

/* Where the shell is deeper than the surface's radius of curvature across a triangle (a
 * teapot's lid flange, the lip of its spout), the points P - w depth N of its vertices cross
 * below some w < 1 and the prism folds: its bottom triangle comes out mirrored, its outward
 * normal pointing up to the top's side, and a fin whose two bottom corners swapped sides is a
 * bow tie, its two triangles facing opposite ways. Such a plane puts the whole top outside it:
 * a ray entering through the top left the prism at once (t = 0; the texture-space segment then
 * ran from the top to another face's (u, v, w) of the same point, and the hit on it lay beside
 * the ray: on weave-teapot the folded prisms made most of gdm's squared error against its
 * truth). Those planes are unbound: the fold's remaining faces, which cross before
 * the fold's depth, bound the ray. A bow tie's other triangle bounds its fin alone (convex: the
 * nearer of a bound and an unbound plane). Returns whether the prism folds. */
static bool unbind_folded_faces(meso_prism_layer *layer, size_t prism) {
    const meso_prism_plane *planes = layer->planes + prism * MESO_PRISM_NUM_FACES;
    const meso_vec3 *p = layer->faces->positions;
    const uint32_t *top =
        layer->faces->indices + 3 * meso_prism_layer_face(layer, prism, MESO_PRISM_TOP);
    meso_vec3 centre =
        meso_vec3_scale(meso_vec3_add(meso_vec3_add(p[top[0]], p[top[1]]), p[top[2]]), 1.0f / 3.0f);
    bool folded = false;
    if (meso_vec3_dot(planes[MESO_PRISM_TOP].normal, planes[MESO_PRISM_BOTTOM].normal) > 0.0f) {
        unbind_face(layer, prism, MESO_PRISM_BOTTOM);
        folded = true;
    }
    for (int e = 0; e < 3; e++) {
        int first = MESO_PRISM_FIN + 2 * e;
        if (!(meso_vec3_dot(planes[first].normal, planes[first + 1].normal) < 0.0f)) continue;
        for (int slot = first; slot <= first + 1; slot++) {
            if (!(meso_vec3_dot(planes[slot].normal, centre) - planes[slot].offset > 0.0f))
                continue;
            unbind_face(layer, prism, slot);
            layer->fin_convex[3 * prism + (size_t)e] = 1;
            folded = true;
            break;
        }
    }
    return folded;
}

static meso_prism_face_frame face_frame_of(const meso_prism_layer *layer, size_t face);

meso_result meso_prism_layer_create(meso_context *ctx, const meso_mesh *mesh, float depth,
                                    const char *name, meso_prism_layer **out_layer) {
    *out_layer = NULL;
    if (!mesh->uvs)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: the shell's prisms need texture coordinates", name);
    if (!(depth > 0.0f) || !isfinite(depth))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: mesostructure.depth: %g, the shell needs a positive depth", name,
                              (double)depth);
    uint64_t nv = 2 * (uint64_t)mesh->num_vertices, nt = 8 * (uint64_t)mesh->num_triangles;
    meso_result r = geom_check_counts(ctx, name, nv, nt);
    if (r != MESO_OK) return r;
    meso_prism_layer *layer = calloc(1, sizeof *layer);
    if (!layer) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: prisms", name);
    layer->num_prisms = mesh->num_triangles;
    layer->depth = depth;
    if ((r = meso_mesh_create(ctx, (size_t)nv, (size_t)nt, true, &layer->faces)) != MESO_OK)
        goto fail;
    size_t n = layer->num_prisms ? layer->num_prisms : 1;
    layer->uvws = malloc((size_t)(nv ? nv : 1) * sizeof *layer->uvws);
    layer->prisms = calloc(n, sizeof *layer->prisms);
    layer->planes = calloc(n * MESO_PRISM_NUM_FACES, sizeof *layer->planes);
    layer->fin_convex = calloc(3 * n, 1);
    layer->face_frames = malloc((size_t)(nt ? nt : 1) * sizeof *layer->face_frames);
    size_t lanes_bytes = n * 4 * MESO_PRISM_NUM_FACES * sizeof(float); /* a multiple of 32 */
    layer->plane_lanes = aligned_alloc(32, lanes_bytes);
    if (layer->plane_lanes) memset(layer->plane_lanes, 0, lanes_bytes);
    if (!layer->uvws || !layer->prisms || !layer->planes || !layer->fin_convex ||
        !layer->plane_lanes || !layer->face_frames) {
        r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: prisms", name);
        goto fail;
    }
    meso_mesh *faces = layer->faces;
    size_t base = mesh->num_vertices;
    for (size_t v = 0; v < base; v++) {
        faces->positions[v] = meso_prism_shell_point(mesh, (uint32_t)v, 0.0f, depth);
        faces->positions[base + v] = meso_prism_shell_point(mesh, (uint32_t)v, 1.0f, depth);
        faces->normals[v] = faces->normals[base + v] = mesh->normals[v];
        faces->uvs[v] = faces->uvs[base + v] = mesh->uvs[v];
        layer->uvws[v] = (meso_vec3){mesh->uvs[v].x, mesh->uvs[v].y, 0.0f};
        layer->uvws[base + v] = (meso_vec3){mesh->uvs[v].x, mesh->uvs[v].y, 1.0f};
    }
    for (size_t t = 0; t < layer->num_prisms; t++) {
        meso_prism *prism = &layer->prisms[t];
        if (!meso_prism_init(prism, mesh, t)) continue; /* its faces stay (0, 0, 0): not drawn */
        const uint32_t *v = prism->vertices;
        uint32_t b = (uint32_t)base;
        set_face(layer, t, MESO_PRISM_TOP, v[0], v[1], v[2]);
        set_face(layer, t, MESO_PRISM_BOTTOM, b + v[0], b + v[2], b + v[1]);
        for (int e = 0; e < 3; e++) extrude_fin(layer, t, e, v[e], v[(e + 1) % 3]);
        layer->num_folded += unbind_folded_faces(layer, t);
    }
    for (size_t f = 0; f < (size_t)nt; f++) layer->face_frames[f] = face_frame_of(layer, f);
    *out_layer = layer;
    return MESO_OK;
fail:
    meso_prism_layer_destroy(layer);
    return r;
}

void meso_prism_layer_destroy(meso_prism_layer *layer) {
    if (!layer) return;
    meso_mesh_destroy(layer->faces);
    free(layer->uvws);
    free(layer->prisms);
    free(layer->planes);
    free(layer->plane_lanes);
    free(layer->face_frames);
    free(layer->fin_convex);
    free(layer);
}

size_t meso_prism_layer_memory(const meso_prism_layer *layer) {
    if (!layer) return 0;
    size_t nv = layer->faces->num_vertices, nt = layer->faces->num_triangles;
    return nv * (2 * sizeof(meso_vec3) + sizeof(meso_vec2) + sizeof(meso_vec3)) +
           nt * (3 * sizeof(uint32_t) + sizeof(meso_prism_face_frame)) +
           layer->num_prisms *
               (sizeof(meso_prism) + MESO_PRISM_NUM_FACES * sizeof(meso_prism_plane) +
                4 * MESO_PRISM_NUM_FACES * sizeof(float) + 3);
}

/* The face's constants of meso_prism_layer_face_uvw (once a face, at creation). */
static meso_prism_face_frame face_frame_of(const meso_prism_layer *layer, size_t face) {
    const uint32_t *idx = layer->faces->indices + 3 * face;
    const meso_vec3 *p = layer->faces->positions;
    meso_prism_face_frame f;
    f.p0 = p[idx[0]];
    f.e1 = meso_vec3_sub(p[idx[1]], p[idx[0]]);
    f.e2 = meso_vec3_sub(p[idx[2]], p[idx[0]]);
    f.d00 = meso_vec3_dot(f.e1, f.e1), f.d01 = meso_vec3_dot(f.e1, f.e2);
    f.d11 = meso_vec3_dot(f.e2, f.e2);
    f.det = f.d00 * f.d11 - f.d01 * f.d01;
    for (int k = 0; k < 3; k++) f.uvw[k] = layer->uvws[idx[k]];
    return f;
}

meso_vec3 meso_prism_layer_face_uvw(const meso_prism_layer *layer, size_t face, meso_vec3 x) {
    const meso_prism_face_frame *f = &layer->face_frames[face];
    meso_vec3 d = meso_vec3_sub(x, f->p0);
    float d20 = meso_vec3_dot(d, f->e1), d21 = meso_vec3_dot(d, f->e2);
    float b1 = 0.0f, b2 = 0.0f;
    if (f->det > 0.0f) {
        b1 = (f->d11 * d20 - f->d01 * d21) / f->det;
        b2 = (f->d00 * d21 - f->d01 * d20) / f->det;
    }
    return meso_vec3_barycentric(f->uvw[0], f->uvw[1], f->uvw[2], 1.0f - b1 - b2, b1, b2);
}

/* Four float lanes (GCC vector extensions): one SSE register, which every x86-64 build has.
 * Eight-lane vectors, in a portable build (this file is not among the AVX2 copies), were split
 * into SSE pairs whose comparisons and selects GCC lowered lane by lane: several hundred
 * instructions a call, where gdm calls this for every prism its view and light rays cross. */
typedef float prism_v4f __attribute__((vector_size(16)));
typedef int32_t prism_v4i __attribute__((vector_size(16)));

static inline prism_v4f prism_splat(float x) { return (prism_v4f){x, x, x, x}; }

/* For every face plane of the prism at once, the ray parameter from which the ray stays
 * outside the plane's half-space for good: 0 when it starts outside (beyond `tolerance`) and
 * does not come back, INFINITY when it never leaves. A line meets a half-space's outside in one
 * interval [t, inf) or not at all, so the exit of an intersection of half-spaces is the least
 * such t, of a union the largest. The entry face's own plane never bounds (INFINITY); the other
 * triangle of the fin the ray entered through (its "partner") is not outside by its start: the
 * origin is on that fin, so "outside" there is the fin's own rounding (a flat fin's two planes
 * differ in their last bits), not a concave fold the ray starts beyond. Each lane computes what
 * the scalar test did, operation for operation (dot products left to right, -s0 / dn), so the
 * times are the same bits. Slots first .. first + 3 of the eight. */
static inline prism_v4f leave_times4(const float *lanes, int first, meso_vec3 o, meso_vec3 d,
                                     float tolerance, int entry_slot) {
    prism_v4f nx, ny, nz, offset;
    memcpy(&nx, lanes + first, sizeof nx);
    memcpy(&ny, lanes + MESO_PRISM_NUM_FACES + first, sizeof ny);
    memcpy(&nz, lanes + 2 * MESO_PRISM_NUM_FACES + first, sizeof nz);
    memcpy(&offset, lanes + 3 * MESO_PRISM_NUM_FACES + first, sizeof offset);
    prism_v4f dn = nx * prism_splat(d.x) + ny * prism_splat(d.y) + nz * prism_splat(d.z);
    prism_v4f s0 = (nx * prism_splat(o.x) + ny * prism_splat(o.y) + nz * prism_splat(o.z)) - offset;
    const prism_v4i slot = (prism_v4i){0, 1, 2, 3} + first;
    prism_v4i entry = (prism_v4i){0, 0, 0, 0} + entry_slot;
    prism_v4i partner = (slot >= 2) & ((slot ^ 1) == entry);
    const prism_v4f zero = prism_splat(0.0f), infinity = prism_splat(INFINITY);
    prism_v4f leaving = -s0 / dn; /* only where dn > 0 */
    prism_v4i forward = dn > zero, started = s0 >= zero;
    prism_v4i away = (s0 > prism_splat(tolerance)) & ~partner;
    prism_v4i t = (forward & ((started & (prism_v4i)zero) | (~started & (prism_v4i)leaving))) |
                  (~forward & ((away & (prism_v4i)zero) | (~away & (prism_v4i)infinity)));
    t = (t & ~(slot == entry)) | ((prism_v4i)infinity & (slot == entry));
    return (prism_v4f)t;
}

static inline void leave_times(const float *lanes, meso_vec3 o, meso_vec3 d, float tolerance,
                               int entry_slot, float out[MESO_PRISM_NUM_FACES]) {
    prism_v4f low = leave_times4(lanes, 0, o, d, tolerance, entry_slot);
    prism_v4f high = leave_times4(lanes, 4, o, d, tolerance, entry_slot);
    memcpy(out, &low, sizeof low);
    memcpy(out + 4, &high, sizeof high);
}

bool meso_prism_layer_exit(const meso_prism_layer *layer, size_t prism, meso_vec3 origin,
                           meso_vec3 direction, int entry_slot, float *out_t, int *out_slot) {
    /* the origin lies on the entry face: a point of another face's plane through the same edge
     * may round to either side of it; beyond this it is really outside (a concave fin) */
    float tolerance = 1e-5f * (fabsf(origin.x) + fabsf(origin.y) + fabsf(origin.z) + layer->depth);
    float times[MESO_PRISM_NUM_FACES];
    leave_times(layer->plane_lanes + prism * 4 * MESO_PRISM_NUM_FACES, origin, direction, tolerance,
                entry_slot, times);
    /* the top, the bottom, then the three fins, in slot order (a loop of constant trip count,
     * unrolled: gdm calls this for every fragment and every crossing of its shadow walk) */
    float best = INFINITY;
    int best_slot = -1;
    if (times[MESO_PRISM_TOP] < best) best = times[MESO_PRISM_TOP], best_slot = MESO_PRISM_TOP;
    if (times[MESO_PRISM_BOTTOM] < best)
        best = times[MESO_PRISM_BOTTOM], best_slot = MESO_PRISM_BOTTOM;
#pragma GCC unroll 3
    for (int e = 0; e < 3; e++) {
        int slot = MESO_PRISM_FIN + 2 * e;
        float t = times[slot], t2 = times[slot + 1];
        bool convex = layer->fin_convex[3 * prism + (size_t)e];
        /* Fig. 5: a convex fin bounds the intersection of its two half-spaces (the nearer
         * plane), a concave one their union (the farther) */
        bool first = convex ? t <= t2 : t >= t2;
        t = first ? t : t2;
        int which = first ? slot : slot + 1;
        if (t < best) {
            best = t;
            best_slot = which;
        }
    }
    *out_t = best;
    *out_slot = best_slot;
    return best_slot >= 0;
}
