/* gdm's shell walk (docs/techniques/gdm.md, "The shell walk"): the view ray followed through the
 * prism shell from prism to prism across their shared fins, in the manner of ray casting in a
 * cell complex by walking its faces (Bunyk, Kaufman & Silva 1997, "Simple, fast, and robust
 * ray casting of irregular grids"), with GDM's per-prism test (Wang et al. 2004, §3.2 Fig. 5)
 * in each prism it crosses. Only the shell's outer boundary is rasterized (tops, bottoms, the
 * fins of open borders): a ray that leaves a prism through a shared fin enters the neighbour
 * that owns the fin's twin, at the same point, whatever the fin's angle to the view.
 *
 * The adjacency is the fin twin table: per face of the layer, the face coincident with it in
 * the neighbour prism (bit-identical vertices, wound the other way: geom_prism.c). Built once
 * in prepare; the shell shadows' walk (gdm_shell_shadow.h) crosses fins through it too.
 *
 * Usage:
 *   uint32_t *twin = gdm_fin_twins(layer);                       prepare; free() it
 *   gdm_walk_crossing c = {prism, entry_slot, entry_face, p_in};   per ray, from its entry
 *   while (gdm_walk_exit(layer, &c, dir)) {                         the prism's stretch
 *       ... [c.p_in, c.p_out] in prism c.prism ...
 *       if (!gdm_walk_next(layer, twin, &c)) break;                 the ray leaves the shell
 *   }
 * Pure and thread-safe after the table is made. */
#ifndef MESO_GDM_WALK_H
#define MESO_GDM_WALK_H

#include <math.h>
#include <stdint.h>

#include "meso/prism.h"

#define GDM_NO_TWIN UINT32_MAX

/* The twin table of the layer's faces (see above), malloc'd, one entry a face: GDM_NO_TWIN for
 * tops, bottoms, fins on an open border and fins of a non-manifold edge (shared by more than
 * two prisms). NULL: out of memory. */
uint32_t *gdm_fin_twins(const meso_prism_layer *layer);

/* Is the face part of the shell's outer boundary (a ray may enter the shell through it)? */
static inline bool gdm_walk_face_is_boundary(const uint32_t *twin, size_t face) {
    return twin[face] == GDM_NO_TWIN;
}

/* One prism's stretch of a ray: entered through entry_slot (face entry_face) at p_in; its exit
 * (gdm_walk_exit): p_out = p_in + t_exit dir, through exit_slot. */
typedef struct gdm_walk_crossing {
    size_t prism, entry_face;
    int entry_slot;
    meso_vec3 p_in;
    float t_exit;
    int exit_slot;
    meso_vec3 p_out;
} gdm_walk_crossing;

/* How far inside face `face` the point x lies, projected on the face's plane: its least
 * barycentric weight there (negative outside the triangle), as meso_prism_layer_face_uvw
 * weighs it; -INFINITY for a degenerate face. */
static inline float gdm_walk_face_inside(const meso_prism_layer *layer, size_t face, meso_vec3 x) {
    const meso_prism_face_frame *f = &layer->face_frames[face];
    if (!(f->det > 0.0f)) return -INFINITY;
    meso_vec3 d = meso_vec3_sub(x, f->p0);
    float d20 = meso_vec3_dot(d, f->e1), d21 = meso_vec3_dot(d, f->e2);
    /* the weights times det, the least of them divided once */
    float b1 = f->d11 * d20 - f->d01 * d21, b2 = f->d00 * d21 - f->d01 * d20;
    float b0 = f->det - b1 - b2, least = b1 < b2 ? b1 : b2;
    least = b0 < least ? b0 : least;
    return least / f->det;
}

/* Where the ray origin + t dir crosses face `face`'s triangle going out of its prism (the
 * face's outward normal along dir), its barycentric weights at least -slack: *out_t; false
 * where it does not (Moller-Trumbore). */
static inline bool gdm_walk_face_crossing(const meso_prism_layer *layer, size_t face,
                                          meso_vec3 origin, meso_vec3 dir, float slack,
                                          float *out_t) {
    const meso_prism_face_frame *f = &layer->face_frames[face];
    if (!(meso_vec3_dot(meso_vec3_cross(f->e1, f->e2), dir) > 0.0f)) return false;
    meso_vec3 pv = meso_vec3_cross(dir, f->e2);
    float det = meso_vec3_dot(f->e1, pv);
    if (!(fabsf(det) > 0.0f)) return false;
    meso_vec3 tv = meso_vec3_sub(origin, f->p0);
    float b1 = meso_vec3_dot(tv, pv) / det;
    meso_vec3 qv = meso_vec3_cross(tv, f->e1);
    float b2 = meso_vec3_dot(dir, qv) / det;
    if (!(b1 >= -slack && b2 >= -slack && 1.0f - b1 - b2 >= -slack)) return false;
    *out_t = meso_vec3_dot(f->e2, qv) / det;
    return isfinite(*out_t);
}

/* The exit of the crossing's prism along dir by Fig. 5's planes alone (meso_prism_layer_exit),
 * as the per-prism drawing takes it. false: no face bounds the ray or the exit is not
 * finite. */
static inline bool gdm_walk_exit_planes(const meso_prism_layer *layer, gdm_walk_crossing *c,
                                        meso_vec3 dir) {
    if (!meso_prism_layer_exit(layer, c->prism, c->p_in, dir, c->entry_slot, &c->t_exit,
                               &c->exit_slot) ||
        !isfinite(c->t_exit))
        return false;
    c->p_out = meso_vec3_madd(c->p_in, dir, c->t_exit);
    return true;
}

/* Barycentric slack of the exit's face: beyond it the exit point is not on the face Fig. 5's
 * planes picked (a fold's plane crossed beside its triangle) and the walk looks for the face
 * the ray crosses. A hundredth of a face: far above rounding, far below the misses. */
#define GDM_WALK_FACE_SLACK 1e-2f

/* The exit of the crossing's prism along dir (meso_prism_layer_exit, §3.2 Fig. 5). A fin's
 * exit is then given to whichever of its two triangles holds the exit point: Fig. 5 picks the
 * plane the ray leaves by, and where the fin is nearly flat the two planes cross the ray at
 * nearly the same point, either side of the diagonal; the other triangle's linear (u, v, w)
 * extended over the plane is off by the fin's bend there (a thousandth of a tile on
 * bumps-sphere), and the walk carries the exit's (u, v, w) into the neighbour through the
 * twin. Where the point lies off both fin triangles (a folded prism's planes, crossed beside
 * their triangles: the teapot's lid rim), or the ray does not go out through the face's plane
 * at all (entered at an edge, rounded a hair outside the plane of a face it goes in through: a
 * top at once, t = 0, which would end the walk there), the exit is the nearest of the prism's
 * faces whose triangle the ray crosses going out, as a walk through a cell complex takes it
 * (Bunyk et al. 1997); Fig. 5's answer stands where none is crossed. false: no face bounds the
 * ray (a degenerate prism) or the exit is not finite. */
static inline bool gdm_walk_exit(const meso_prism_layer *layer, gdm_walk_crossing *c,
                                 meso_vec3 dir) {
    if (!gdm_walk_exit_planes(layer, c, dir)) return false;
    float inside = 0.0f; /* a top or a bottom ends the walk: only its direction is checked */
    if (c->exit_slot >= MESO_PRISM_FIN) {
        int partner = c->exit_slot ^ 1; /* the fin's other triangle: slots 2k, 2k + 1 */
        inside = gdm_walk_face_inside(layer, meso_prism_layer_face(layer, c->prism, c->exit_slot),
                                      c->p_out);
        float other =
            gdm_walk_face_inside(layer, meso_prism_layer_face(layer, c->prism, partner), c->p_out);
        if (other > inside) c->exit_slot = partner, inside = other;
    }
    const meso_prism_plane *plane =
        &layer->planes[c->prism * MESO_PRISM_NUM_FACES + (size_t)c->exit_slot];
    if (inside >= -GDM_WALK_FACE_SLACK && meso_vec3_dot(plane->normal, dir) > 0.0f) return true;
    float best = INFINITY;
    int best_slot = -1;
    for (int slot = 0; slot < MESO_PRISM_NUM_FACES; slot++) {
        float t;
        if (slot != c->entry_slot &&
            gdm_walk_face_crossing(layer, meso_prism_layer_face(layer, c->prism, slot), c->p_in,
                                   dir, GDM_WALK_FACE_SLACK, &t) &&
            t >= 0.0f && t < best)
            best = t, best_slot = slot;
    }
    if (best_slot >= 0) {
        c->t_exit = best;
        c->exit_slot = best_slot;
        c->p_out = meso_vec3_madd(c->p_in, dir, best);
    }
    return true;
}

/* Across the exit face into the neighbour that shares it: the crossing becomes the
 * neighbour's, entered at the exit point through the twin face. false: the exit face is on
 * the shell's boundary (a top, a bottom, an open border's fin): the ray leaves the shell. */
static inline bool gdm_walk_next(const meso_prism_layer *layer, const uint32_t *twin,
                                 gdm_walk_crossing *c) {
    if (c->exit_slot < MESO_PRISM_FIN) return false;
    uint32_t next = twin[meso_prism_layer_face(layer, c->prism, c->exit_slot)];
    if (next == GDM_NO_TWIN) return false;
    c->entry_face = next;
    c->prism = meso_prism_layer_face_prism(layer, next, &c->entry_slot);
    c->p_in = c->p_out;
    return true;
}

/* ---- Drawing the shell's outer boundary and starting the walk (gdm, and the relief family's
 * `shell` option, relief_shell.h) ---- */

#define GDM_DEPTH_BUCKETS 1024 /* gdm_walk_sort_faces' counting sort */

/* The walk's adjacency and the faces a walk draws: *out_twin the fin twin table
 * (gdm_fin_twins); *out_boundary the faces drawn -- every top, the fins without a twin (open
 * borders, non-manifold edges), every bottom (a ray from inside the base mesh, or below an
 * open one, enters there) and both copies of every fin of a folded prism -- as the groups
 * [group_start[g], group_start[g + 1]): tops, fins, bottoms; *out_same_uvw per face, 1 where a
 * fin's twin carries the same (u, v, w) (not a UV seam: the exit's (u, v, w) is the
 * neighbour's entry). The three arrays malloc'd (free() them, also on failure). false: out of
 * memory. */
bool gdm_walk_boundary(const meso_prism_layer *layer, uint32_t **out_twin, uint32_t **out_boundary,
                       uint8_t **out_same_uvw, size_t group_start[4]);

/* A frame's drawing order of the faces: the groups (tops, fins, bottoms) each front to back by
 * the view depth of the faces' centroids, drawn triangle i being face drawn_face[i] with its
 * indices at drawn_indices + 3 i. boundary NULL: every face of the layer (group_start then
 * the layer's own groups). keys: group_start[3] floats; count: GDM_DEPTH_BUCKETS + 1. */
void gdm_walk_sort_faces(const meso_mesh *faces, const uint32_t *boundary,
                         const size_t group_start[4], meso_vec3 eye, meso_vec3 forward, float *keys,
                         uint32_t *count, uint32_t *drawn_face, uint32_t *drawn_indices);

/* The base surface's frame at (u, v) of a prism: the mesh's unit normal, dP/du and dP/dv
 * interpolated by the point's barycentrics, or the flat triangle's dP/du, dP/dv (from the UV
 * inverse) where the mesh has no tangents. gdm's and the relief family's shell (relief_shell.h)
 * shade a hit in it. */
static inline void gdm_walk_base_frame(const meso_mesh *mesh, const meso_prism *prism, meso_vec2 uv,
                                       meso_vec3 *normal, meso_vec3 *tangent,
                                       meso_vec3 *bitangent) {
    float b[3];
    meso_prism_weights(prism, uv, b);
    const uint32_t *v = prism->vertices;
    *normal = meso_vec3_normalize(meso_vec3_barycentric(mesh->normals[v[0]], mesh->normals[v[1]],
                                                        mesh->normals[v[2]], b[0], b[1], b[2]));
    if (mesh->tangents && mesh->bitangents) {
        *tangent = meso_vec3_barycentric(mesh->tangents[v[0]], mesh->tangents[v[1]],
                                         mesh->tangents[v[2]], b[0], b[1], b[2]);
        *bitangent = meso_vec3_barycentric(mesh->bitangents[v[0]], mesh->bitangents[v[1]],
                                           mesh->bitangents[v[2]], b[0], b[1], b[2]);
    } else {
        const float *inv = prism->uv_inverse;
        meso_vec3 e1 = meso_vec3_sub(mesh->positions[v[1]], mesh->positions[v[0]]);
        meso_vec3 e2 = meso_vec3_sub(mesh->positions[v[2]], mesh->positions[v[0]]);
        *tangent = meso_vec3_add(meso_vec3_scale(e1, inv[0]), meso_vec3_scale(e2, inv[2]));
        *bitangent = meso_vec3_add(meso_vec3_scale(e1, inv[1]), meso_vec3_scale(e2, inv[3]));
    }
}

/* Do the three vertices share one normal (a prism of a flat stretch of the mesh, whose map is
 * affine: a straight ray stays straight in (u, v, w))? */
static inline bool gdm_normals_equal(const meso_mesh *mesh, uint32_t a, uint32_t b, uint32_t c) {
    meso_vec3 na = mesh->normals[a], nb = mesh->normals[b], nc = mesh->normals[c];
    return na.x == nb.x && na.y == nb.y && na.z == nb.z && na.x == nc.x && na.y == nc.y &&
           na.z == nc.z;
}

/* A fragment of drawn face `face` (barycentrics b0..b2, position on the face): the ray's entry
 * (u, v, w) on the face, perspective-correct, its unit direction from the eye, and the
 * crossing of the face's prism: Fig. 5's exit (walk false, the per-prism drawing) or the
 * walk's (gdm_walk_exit). With flat_mesh (the base mesh) and a prism whose vertex normals are
 * one, the entry is the face's own (u, v, w) at the position instead, consistent with the
 * straight path gdm then follows. false: the prism bounds nothing. */
static inline bool gdm_walk_enter(const meso_prism_layer *layer, const meso_mesh *flat_mesh,
                                  size_t face, float b0, float b1, float b2, meso_vec3 position,
                                  meso_vec3 eye, bool walk, gdm_walk_crossing *c, meso_vec3 *t_in,
                                  meso_vec3 *view) {
    const uint32_t *idx = layer->faces->indices + 3 * face;
    *view = meso_vec3_normalize(meso_vec3_sub(position, eye));
    c->entry_face = face;
    c->prism = meso_prism_layer_face_prism(layer, face, &c->entry_slot);
    const uint32_t *v = layer->prisms[c->prism].vertices;
    if (flat_mesh && gdm_normals_equal(flat_mesh, v[0], v[1], v[2]))
        *t_in = meso_prism_layer_face_uvw(layer, face, position);
    else
        *t_in = meso_vec3_barycentric(layer->uvws[idx[0]], layer->uvws[idx[1]], layer->uvws[idx[2]],
                                      b0, b1, b2);
    c->p_in = position;
    return walk ? gdm_walk_exit(layer, c, *view) : gdm_walk_exit_planes(layer, c, *view);
}

#endif
