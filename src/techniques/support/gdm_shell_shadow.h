/* gdm's shadows through the whole shell (beyond the paper; docs/techniques/gdm.md, "Beyond the
 * paper: shadows through the shell"). GDM §3.2 tests a light inside one prism's slab only
 * ("does not handle shadows from the base geometry or distant mesostructure"), and gdm takes a
 * light toward the slab's bottom as blocked by the object's body. Both are wrong for a solid
 * with holes on an open or hollow mesh (grid-vase: the inside lit over the rim and through the
 * holes; a teapot's spout shadowing its body). Here the light ray is followed through the
 * shell in object space with GDM's own data: from the point to where it leaves its prism
 * (meso_prism_layer_exit), then, each time it leaves a prism through the top, a fin or an
 * open floor, the next prism it enters -- found by Embree among the prism layer's faces (every
 * face, a filter keeping those the ray enters) -- and in each the paper's per-prism segment
 * test, d_GDM(T_in, V_t) < |T_out - T_in|, with gdm's probes of the mesostructure confirming
 * a blocker. Blocked at the first blocker or at a solid floor (a height field's body is
 * solid: its floor always is); visible when the ray leaves the shell for good.
 *
 * Usage (gdm.c):
 *   gdm_shell_create(ctx, &(gdm_shell_desc){...}, name, &shell);       prepare, once
 *   gdm_shell_light_visible(shell, prism, uvw, light, slab_clear, thorough)   per fragment, light
 *   gdm_shell_light_visible_at(shell, prism, uvw, &point, light, slab_clear, thorough)  the
 *                                                  same, with what the caller knows of the point
 *   gdm_shell_destroy(shell);
 *
 * Threads: creation builds the Embree scene on the calling thread (so its BVH, and every
 * answer, is the same whatever the number of workers); gdm_shell_light_visible is pure and
 * may run on many threads at once. */
#ifndef MESO_GDM_SHELL_SHADOW_H
#define MESO_GDM_SHELL_SHADOW_H

#include "gdm_lookup.h"
#include "meso/prism.h"
#include "render_internal.h"

/* The tile's point of texture point uvw (the mesostructure repeats in u and v). */
static inline meso_vec3 gdm_tile_point(meso_vec3 uvw) {
    return (meso_vec3){uvw.x - floorf(uvw.x), uvw.y - floorf(uvw.y), uvw.z};
}

/* Inside the mesostructure at uvw: a height field's solid is w >= 1 - h(u, v) (docs/design.md), a
 * solid's is where its distance bound is <= 0. One of heightfield / solid is non-NULL. The one
 * definition gdm's refinement and the shell walk share. */
static inline bool gdm_mesostructure_inside(const meso_heightfield *heightfield,
                                            const meso_solid *solid, meso_vec3 uvw) {
    if (heightfield) return uvw.z >= 1.0f - meso_heightfield_sample(heightfield, uvw.x, uvw.y);
    return meso_solid_distance(solid, gdm_tile_point(uvw)) <= 0.0f;
}

typedef struct gdm_shell gdm_shell;

/* What the walk reads; all borrowed and read during gdm_shell_light_visible: they must
 * outlive the shell. */
typedef struct gdm_shell_desc {
    const meso_prism_layer *layer;
    const meso_mesh *mesh; /* the base mesh the layer was extruded from */
    /* NULL, or the layer's fin twin table (gdm_fin_twins), borrowed: the shell builds its own
     * without it */
    const uint32_t *fin_twin;
    const meso_gdm *gdm;
    const gdm_lookup_table *table;       /* the compressed map 8-wide; NULL: gdm's raw table */
    const meso_heightfield *heightfield; /* one of these two */
    const meso_solid *solid;
    meso_vec3 voxel;     /* a voxel's sides in texture units */
    float shadow_bias;   /* voxels: the start's offset off the surface, the lookup's margin */
    float refine_window; /* texture units: the confirming probe lies this far past d / 2 */
    int refine_steps;    /* > 0: a blocker the table reports is confirmed by probes; 0: not */
    int shadow_steps;    /* the probes along a blocked segment */
    /* NULL, or gdm_mesostructure_inside's answer for uvw by a cheaper route (gdm.c: a solid's
     * distance grid, a height field's clearance), called with inside_user; it must give the
     * same answer for every point */
    bool (*inside)(const void *inside_user, meso_vec3 uvw);
    const void *inside_user;
    /* NULL, or true where every point t0 + x dir with x between 0 and the end's x (b =
     * meso_vec3_madd(t0, dir, x_end), so each coordinate lies between a's and b's) is proven
     * outside without evaluating the mesostructure (gdm.c: a height field's window maxima);
     * false where not proven. Called with inside_user. */
    bool (*segment_outside)(const void *inside_user, meso_vec3 a, meso_vec3 b);
    /* NULL, or whether any of the points t0 + x dir is inside -- x = first (when first >= 0),
     * then x = length (k + 0.5) / steps for k = 0 .. steps - 1 -- each point answered as
     * `inside` answers it (gdm.c: the probes remember what a sample proves about the next
     * ones, gdm.c's ray_probe). Called with inside_user. */
    bool (*probes_inside)(const void *inside_user, meso_vec3 t0, meso_vec3 dir, float first,
                          float length, int steps);
} gdm_shell_desc;

/* Build the Embree scene of desc->layer's faces. *out_shell NULL on failure:
 * MESO_ERROR_INVALID_ARGUMENT (no layer or no mesostructure), MESO_ERROR_OUT_OF_MEMORY,
 * MESO_ERROR_INTERNAL (Embree). `name` names the object in messages. */
meso_result gdm_shell_create(meso_context *ctx, const gdm_shell_desc *desc, const char *name,
                             gdm_shell **out_shell);
void gdm_shell_destroy(gdm_shell *shell);
/* Bytes held (the BVH estimated). */
size_t gdm_shell_memory(const gdm_shell *shell);

/* Per prism, clear[prism] = 1 where every vertex of the layer lies behind (or on) the prism's
 * top plane: a ray leaving that prism through its top meets no prism again, and the walk ends
 * there without a ray query (every prism of a convex or flat base mesh; a torus's outer side).
 * Returns how many are proven; 0 with every entry 0 above 2^29 vertex-plane tests, out of
 * memory or with non-finite positions. The same answers for any number of threads. */
size_t gdm_prism_tops_clear(meso_context *ctx, const meso_prism_layer *layer, uint8_t *clear);

/* Is layer face `face` a fin shared with a neighbour prism (a seam inside the shell), rather
 * than a top, a bottom or a fin on an open border? false without the twin table. Pure. */
bool gdm_shell_face_is_seam(const gdm_shell *shell, size_t face);

/* Is prism `prism`'s top clear (gdm_prism_tops_clear: every vertex of the layer behind or on
 * its top plane, so a ray leaving through that top meets no prism again)? false where not
 * proven or without the proof. Pure. */
bool gdm_shell_top_clear(const gdm_shell *shell, size_t prism);
/* The index of one of the layer's prisms (a pointer into layer->prisms). Pure. */
size_t gdm_shell_prism_index(const gdm_shell *shell, const meso_prism *prism);

/* Is the light along unit object-space direction `light` seen from texture point uvw of prism
 * `prism` (a point of the mesostructure's surface)?
 * slab_clear true: the caller's own §3.2 test found the light unblocked up to the slab's top;
 *   the prisms the ray crosses before it leaves the slab are not tested again, the ones it
 *   enters afterwards are.
 * slab_clear false: every prism from the point on is tested, the first from `shadow_bias`
 *   voxels off the surface (a solid's light toward the slab's bottom, which §3.2 cannot see).
 * thorough: a prism's segment is probed on the mesostructure every voxel even where the
 *   table says it is clear (the table trusted only where it reports a blocker otherwise): for
 *   a light the caller's own test found blocked in a flat slab, checked on the curved shell.
 * Pure; thread-safe. */
bool gdm_shell_light_visible(const gdm_shell *shell, size_t prism, meso_vec3 uvw, meso_vec3 light,
                             bool slab_clear, bool thorough);

/* What a caller may know of the point already (gdm.c has each at its hit), so that the walk
 * need not work it out again: the same answers. */
typedef struct gdm_shell_point {
    /* meso_prism_map(&layer->prisms[prism], mesh, layer->depth, uvw, -1) */
    meso_vec3 position;
    /* the mesh's vertex normals interpolated at uvw's (u, v) by meso_prism_weights, normalised */
    meso_vec3 normal;
    /* with has_gradient: a solid's meso_solid_gradient at gdm_tile_point(uvw) */
    meso_vec3 gradient;
    bool has_gradient;
} gdm_shell_point;

/* gdm_shell_light_visible for a caller that knows `point` of the point (position and normal are
 * read with slab_clear, the gradient without it). Pure; thread-safe. */
bool gdm_shell_light_visible_at(const gdm_shell *shell, size_t prism, meso_vec3 uvw,
                                const gdm_shell_point *point, meso_vec3 light, bool slab_clear,
                                bool thorough);

#endif
