/* The shell's prisms (GDM §3.1 Fig. 3, §3.2 Fig. 5): one definition of the extrusion of a
 * mesh into a shell of thickness `depth` and of the mapping between object space and a
 * prism's texture space (u, v, w), for the reference tracer, the `gdm` technique and anything
 * else that needs them.
 *
 * Overview
 *   Base triangle t with vertices P_i, unit vertex normals N_i and texture coordinates uv_i
 *   (uv_scale applied) is extruded into a prism: its top is the triangle itself (w = 0), its
 *   bottom the triangle of P_i - depth N_i (w = 1), docs/design.md's "depth runs inward". A point
 *   (u, v, w) of the prism's texture volume, (u, v) inside the UV triangle, is the object-space
 *   point  sum_i b_i(u, v) (P_i - w depth N_i),  b the barycentric weights of (u, v) in the UV
 *   triangle (meso_prism_map). Its three sides ("fins") are bilinear patches; each is drawn as
 *   two triangles (§3.1: "approximated by two mesh triangles").
 *
 *   meso_prism_layer_create extrudes a whole mesh into a drawable mesh of 8 triangles a prism
 *   (top, bottom, 3 fins x 2), each wound counter-clockwise seen from outside its prism, with
 *   (u, v, w) per vertex. A fin is shared by the two prisms of an edge: both draw it from the
 *   same vertices (bit-identical positions, the same split diagonal chosen from the positions,
 *   not from vertex numbers, so UV seams agree too), wound oppositely, so back-face culling
 *   keeps exactly the copy of the prism the view ray enters and adjacent prisms meet without
 *   gaps or overlaps.
 *
 *   meso_prism_layer_exit gives, for a ray entering a prism, where it leaves: the nearest of
 *   the ray-plane intersections with the prism's face planes, where a fin's two planes count
 *   as one face -- the nearer of the two where the fin is convex, the farther where it is
 *   concave (§3.2 Fig. 5). meso_prism_layer_face_uvw maps a point of a face's plane to (u, v, w)
 *   by the face's own linear interpolation (the drawn triangles' attributes, extended over the
 *   plane).
 *
 * Usage
 *   meso_prism_layer *layer;
 *   meso_prism_layer_create(ctx, mesh, depth, name, &layer);  -> draw layer->faces
 *   per fragment of face f:  prism = meso_prism_layer_face_prism(layer, f, &slot);
 *                            meso_prism_layer_exit(layer, prism, P_in, V, slot, &t, &exit_slot);
 *                            T_out = meso_prism_layer_face_uvw(layer,
 *                                     meso_prism_layer_face(layer, prism, exit_slot), P_in + t V);
 *                            P = meso_prism_map(&layer->prisms[prism], mesh, depth, T, -1);
 *
 * Ownership: the layer owns its arrays; the mesh it was made from must outlive it (prisms
 * index its vertices). Threads: creation is single-threaded per layer; every query is pure
 * and thread-safe.
 */
#ifndef MESO_PRISM_H
#define MESO_PRISM_H

#include "meso/geom.h"

#ifdef __cplusplus
extern "C" {
#endif

/* An edge of a prism's base triangle in canonical orientation (lower mesh vertex first), so
 * that both triangles of the edge compute the same side function. */
typedef struct meso_prism_edge {
    uint32_t lo, hi; /* mesh vertices, lo < hi */
    meso_vec2 uv_lo, uv_hi;
    float sign; /* +1 or -1: the triangle's inside is sign * meso_prism_edge_side(e, uv) >= 0 */
} meso_prism_edge;

/* One base triangle's prism: what the texture <-> object mapping needs. */
typedef struct meso_prism {
    uint32_t vertices[3]; /* mesh vertices, in the triangle's order */
    meso_vec2 uv[3];
    float uv_inverse[4];      /* uv -> (b1, b2) = [i0 i1; i2 i3] (uv - uv[0]) */
    meso_prism_edge edges[3]; /* edge e joins vertices e and e + 1 */
    bool valid;               /* false: degenerate UV triangle (nothing is mapped into it) */
} meso_prism;

/* Set up the prism of mesh triangle `triangle` (the mesh has UVs). Returns prism->valid. */
bool meso_prism_init(meso_prism *prism, const meso_mesh *mesh, size_t triangle);

/* The edge's side function at uv: twice the signed area of (lo, hi, uv) in the UV plane. */
static inline float meso_prism_edge_side(const meso_prism_edge *edge, meso_vec2 uv) {
    float ax = edge->uv_hi.x - edge->uv_lo.x, ay = edge->uv_hi.y - edge->uv_lo.y;
    return ax * (uv.y - edge->uv_lo.y) - ay * (uv.x - edge->uv_lo.x);
}

/* Vertex v of the mesh moved w shell depths inward: P_v - w depth N_v. Not inline on purpose:
 * its rounding is part of the mapping's bits (the reference's images), whoever calls it. */
meso_vec3 meso_prism_shell_point(const meso_mesh *mesh, uint32_t vertex, float w, float depth);

/* The object-space point of texture point uvw = (u, v, w) of the prism (see the overview).
 * on_edge in 0..2 says the point lies on that edge: it is then mapped from the edge's two
 * vertices only (canonical order), so both prisms of the edge give the same bits; -1 finds
 * out (an exact zero of the side function). Points outside the UV triangle are extrapolated
 * linearly. Pure. */
meso_vec3 meso_prism_map(const meso_prism *prism, const meso_mesh *mesh, float depth, meso_vec3 uvw,
                         int on_edge);

/* The texture point (u, v, w) of the prism whose meso_prism_map is the object-space point x:
 * Newton's method from `guess`, at most `iterations` steps, ending after a step that moves
 * no coordinate by `tolerance` or more (0: every step). The map is bilinear in the
 * barycentrics and w: from a guess a fraction of a voxel off, one step leaves an error of the
 * square of that; where the shell turns sharply (a thin tube's prisms) the guess is farther
 * and the steps converge over two or three. The last estimate where the map's Jacobian is
 * singular. Inline, without meso_prism_shell_point's exact bits: a renderer calls it per
 * fragment. Pure. */
static inline meso_vec3 meso_prism_unmap(const meso_prism *prism, const meso_mesh *mesh,
                                         float depth, meso_vec3 x, meso_vec3 guess, int iterations,
                                         float tolerance) {
    const uint32_t *v = prism->vertices;
    const float *inv = prism->uv_inverse;
    meso_vec3 p0 = mesh->positions[v[0]], n0 = mesh->normals[v[0]];
    meso_vec3 dp1 = meso_vec3_sub(mesh->positions[v[1]], p0);
    meso_vec3 dp2 = meso_vec3_sub(mesh->positions[v[2]], p0);
    meso_vec3 dn1 = meso_vec3_sub(mesh->normals[v[1]], n0);
    meso_vec3 dn2 = meso_vec3_sub(mesh->normals[v[2]], n0);
    meso_vec3 uvw = guess;
    for (int k = 0; k < iterations; k++) {
        float du = uvw.x - prism->uv[0].x, dv = uvw.y - prism->uv[0].y;
        float b1 = inv[0] * du + inv[1] * dv, b2 = inv[2] * du + inv[3] * dv;
        float s = -uvw.z * depth;
        /* the shell's edges at this w, and the normal at (b1, b2) */
        meso_vec3 e1 = meso_vec3_madd(dp1, dn1, s), e2 = meso_vec3_madd(dp2, dn2, s);
        meso_vec3 n = meso_vec3_madd(meso_vec3_madd(n0, dn1, b1), dn2, b2);
        meso_vec3 residual = meso_vec3_sub(
            meso_vec3_madd(meso_vec3_madd(meso_vec3_madd(p0, n0, s), e1, b1), e2, b2), x);
        /* the Jacobian's columns: d/du and d/dv through the weights, d/dw = -depth n */
        meso_vec3 ju = meso_vec3_add(meso_vec3_scale(e1, inv[0]), meso_vec3_scale(e2, inv[2]));
        meso_vec3 jv = meso_vec3_add(meso_vec3_scale(e1, inv[1]), meso_vec3_scale(e2, inv[3]));
        meso_vec3 jw = meso_vec3_scale(n, -depth);
        /* J^-1 r by Cramer's rule: the rows of J^-1 are the cofactor columns over det */
        meso_vec3 cu = meso_vec3_cross(jv, jw), cv = meso_vec3_cross(jw, ju);
        meso_vec3 cw = meso_vec3_cross(ju, jv);
        float det = meso_vec3_dot(ju, cu);
        if (!(det != 0.0f) || !isfinite(det)) return uvw;
        float r = 1.0f / det;
        meso_vec3 step = {meso_vec3_dot(cu, residual) * r, meso_vec3_dot(cv, residual) * r,
                          meso_vec3_dot(cw, residual) * r};
        uvw = meso_vec3_sub(uvw, step);
        if (fabsf(step.x) < tolerance && fabsf(step.y) < tolerance && fabsf(step.z) < tolerance)
            break;
    }
    return uvw;
}

/* Barycentric weights of uv in the prism's UV triangle (the b_i of the overview). Pure. */
static inline void meso_prism_weights(const meso_prism *prism, meso_vec2 uv, float out[3]) {
    float dx = uv.x - prism->uv[0].x, dy = uv.y - prism->uv[0].y;
    out[1] = prism->uv_inverse[0] * dx + prism->uv_inverse[1] * dy;
    out[2] = prism->uv_inverse[2] * dx + prism->uv_inverse[3] * dy;
    out[0] = 1.0f - out[1] - out[2];
}

/* ---- The drawable layer ------------------------------------------------------------------ */

/* Faces of a prism, in the order of meso_prism_layer_face. */
enum {
    MESO_PRISM_TOP = 0,
    MESO_PRISM_BOTTOM = 1,
    MESO_PRISM_FIN = 2, /* fin e's triangles are MESO_PRISM_FIN + 2 e and + 2 e + 1 */
    MESO_PRISM_NUM_FACES = 8,
};

/* A face's plane: dot(normal, x) = offset, normal pointing out of the prism (zero when the
 * face is degenerate: it then bounds nothing). */
typedef struct meso_prism_plane {
    meso_vec3 normal;
    float offset;
} meso_prism_plane;

/* What meso_prism_layer_face_uvw needs of a face, computed once: its first vertex, edges and
 * their Gram matrix (the values the per-point computation made, so the same bits), and its
 * vertices' (u, v, w). */
typedef struct meso_prism_face_frame {
    meso_vec3 p0, e1, e2;
    float d00, d01, d11, det;
    meso_vec3 uvw[3];
} meso_prism_face_frame;

typedef struct meso_prism_layer {
    /* 8 triangles a prism. Face order: every prism's top first, then their fins, then their
     * bottoms, so that a renderer drawing in order meets the nearest layer first (early depth
     * rejection). Vertex v of the base mesh is vertex v here (top) and num_vertices + v
     * (bottom); positions, normals (the base's) and uvs are filled; tangents are not.
     * Prisms that are not valid have degenerate faces (never drawn). */
    meso_mesh *faces;
    meso_vec3 *uvws;          /* per vertex of `faces`: (u, v, 0) top, (u, v, 1) bottom */
    meso_prism *prisms;       /* per base triangle */
    meso_prism_plane *planes; /* MESO_PRISM_NUM_FACES per prism, in the face slots' order */
    /* the same planes by component, 32 floats a prism (normal x of the 8 slots, then y, z,
     * offset), 32-byte aligned: meso_prism_layer_exit tests the 8 planes at once */
    float *plane_lanes;
    meso_prism_face_frame *face_frames; /* per face of `faces`: meso_prism_layer_face_uvw's */
    uint8_t *fin_convex; /* 3 per prism: the fin's two triangles bound a convex side */
    size_t num_prisms;
    /* prisms whose bottom triangle turned over (the shell deeper than the surface's radius of
     * curvature there): their bottom's plane is the zero plane, the fins bound them */
    size_t num_folded;
    float depth;
} meso_prism_layer;

/* Extrude `mesh` (with UVs and unit normals) into a shell of thickness depth > 0.
 * MESO_ERROR_INVALID_ARGUMENT (no UVs, depth not positive and finite), MESO_ERROR_LIMIT (8
 * triangles a prism over MESO_MESH_MAX_TRIANGLES, checked before allocating),
 * MESO_ERROR_OUT_OF_MEMORY. `name` names the object in messages. */
meso_result meso_prism_layer_create(meso_context *ctx, const meso_mesh *mesh, float depth,
                                    const char *name, meso_prism_layer **out_layer);
void meso_prism_layer_destroy(meso_prism_layer *layer);
/* Bytes held by the layer. */
size_t meso_prism_layer_memory(const meso_prism_layer *layer);

/* Face index (a triangle of layer->faces) of a prism's face slot, and back: tops, then each
 * prism's six fin triangles, then bottoms. Pure; inline (gdm calls them for every fragment and
 * every crossing of its shadow walk). */
static inline size_t meso_prism_layer_face(const meso_prism_layer *layer, size_t prism, int slot) {
    size_t n = layer->num_prisms;
    if (slot == MESO_PRISM_TOP) return prism;
    if (slot == MESO_PRISM_BOTTOM) return 7 * n + prism;
    return n + 6 * prism + (size_t)(slot - MESO_PRISM_FIN);
}

static inline size_t meso_prism_layer_face_prism(const meso_prism_layer *layer, size_t face,
                                                 int *out_slot) {
    size_t n = layer->num_prisms;
    if (face < n) {
        *out_slot = MESO_PRISM_TOP;
        return face;
    }
    if (face >= 7 * n) {
        *out_slot = MESO_PRISM_BOTTOM;
        return face - 7 * n;
    }
    *out_slot = MESO_PRISM_FIN + (int)((face - n) % 6);
    return (face - n) / 6;
}

/* The (u, v, w) of point x of face `face`'s plane: the face's vertex attributes interpolated
 * linearly (exact on the face; extended over its plane). Pure. */
meso_vec3 meso_prism_layer_face_uvw(const meso_prism_layer *layer, size_t face, meso_vec3 x);

/* Where the ray origin + t direction, entering the prism through face slot entry_slot (origin
 * on that face; -1: none, origin inside), leaves it (§3.2 Fig. 5, see the overview): *out_t >= 0
 * (direction's units), *out_slot the face slot of the exit plane. Returns false when no face
 * bounds the ray (a degenerate prism). Pure. */
bool meso_prism_layer_exit(const meso_prism_layer *layer, size_t prism, meso_vec3 origin,
                           meso_vec3 direction, int entry_slot, float *out_t, int *out_slot);

#ifdef __cplusplus
}
#endif

#endif
