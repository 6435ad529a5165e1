/* The relief family on the prism shell (the `shell` option of relief, relief_exact and
 * relief_layers; docs/techniques/relief.md, "On the shell"). Without it these techniques trace
 * a straight ray in the tangent space of the pixel's base point (relief_common.h), which is
 * wrong where the surface curves under the ray and at open borders, where the ray leaves
 * through the shell's side. With it the base mesh is extruded into gdm's prism shell
 * (meso/prism.h; Wang et al. 2004, "Generalized Displacement Maps", §3.1), the shell's outer
 * boundary is drawn and each pixel's ray walks through the prisms it crosses (gdm_walk.h, the
 * same drawing and walk as gdm). Within a prism the ray's (u, v, w) path is taken as the
 * straight segment between its entry and exit (as gdm's §3.2 test takes it), so each prism's
 * stretch is a short straight ray in texture space: the technique's own search runs on the
 * stretches front to back and stops at the first hit. Self-shadow rays walk the same way from
 * the hit toward each light. Silhouettes and open borders' side bands come from the shell.
 *
 * The technique hands its search as hooks (relief_shell_search): the inside test its linear +
 * binary search samples (relief: the height field; relief_layers: §3.1's multilayer test), or
 * an exact trace of a stretch (relief_exact: the maximum mip-map), and its normal at the hit.
 *
 * Usage (per object):
 *   relief_shell *shell;  relief_shell_create(ctx, object, "relief", &shell);   prepare
 *   geometry:    *out_mesh = relief_shell_geometry(shell, frame);
 *   shade:       relief_shell_shade(shell, &search, frame, object, fragments, count);
 *   shade_block: relief_shell_shade_block(shell, &search, frame, object, block);
 *   release:     relief_shell_destroy(shell);
 * Shading reads the state only: thread-safe, the same bits for any thread count or batching.
 * CPU only (docs/gpu.md). */
#ifndef MESO_RELIEF_SHELL_H
#define MESO_RELIEF_SHELL_H

#include "relief_common.h"

typedef struct relief_shell relief_shell;

/* A prism's stretch of a ray in texel-centre coordinates (x = u W - 0.5, y = (1 - v) H - 0.5,
 * relief_common.h) and depth d in shell units (d = w: 0 at the mesh, 1 at the shell's bottom):
 * the point at s in [0, 1] is (x0 + s xd, y0 + s yd, d0 + s dd). */
typedef struct relief_shell_stretch {
    float x0, y0, d0, xd, yd, dd;
} relief_shell_stretch;

/* The base surface's frame at a point of the shell: unit normal, dP/du, dP/dv (the base mesh's
 * interpolated at the point's (u, v)), the dual basis (B x N, N x T, T x B) / det that writes
 * a world direction D = du T + dv B + dn N as (D.bn, D.nt, D.tb), and the shell's depth. */
typedef struct relief_shell_frame {
    meso_vec3 normal, tangent, bitangent, bn, nt, tb;
    float depth;
} relief_shell_frame;

typedef struct relief_shell_search {
    const void *user;
    int width, height; /* the map's texels: the texel-centre coordinates */
    /* Inside the mesostructure at (x, y, d)? *out_f: the secant step's signed distance in depth
     * (>= 0 inside; a height field's d + h - 1). */
    bool (*inside)(const void *user, float x, float y, float d, float *out_f);
    /* The same test at eight points at once (the same bits lane by lane): the bits of the
     * lanes inside, *out_f per lane. The linear searches' samples go through it. Vectors by
     * pointer: the technique's copy is built for AVX2 and relief_shell.c is not, and the two
     * pass a 32-byte vector by value differently. */
    int (*inside8)(const void *user, const v8f *x, const v8f *y, const v8f *d, v8f *out_f);
    /* Optional: the technique's own exact trace of a stretch, the first s in [0, 1] where the
     * point lies `bias` or more inside; false: none. NULL: the linear + binary search below. */
    bool (*trace)(const void *user, const relief_shell_stretch *stretch, float bias, float *out_s);
    /* The unit world normal at the hit (x, y, d), given the base frame there; upward: the ray
     * met it going up (w decreasing: from the shell's bottom, a solid's underside). */
    meso_vec3 (*normal)(const void *user, float x, float y, float d, bool upward,
                        const relief_shell_frame *f);
    /* Relief mapping's steps, per unit of depth crossed: a stretch that goes down dd of the
     * shell takes ceil(linear_steps |dd|) (at least 1) uniform steps, then binary_steps
     * halvings and a secant step -- a whole ray from the top to the floor as many as the
     * straight ray's search; the shadow search alike with shadow_steps. */
    int linear_steps, binary_steps, shadow_steps;
    bool shadows;
    bool floor_solid;  /* height fields: a ray that reaches the shell's bottom hits it */
    float shadow_bias; /* shell units: a light sample must be this much inside to block */
} relief_shell_search;

/* The shell of the object's mesh (its UVs and normals) at its mesostructure's depth: the prism
 * layer, the fin twins and the boundary faces. `technique` names the caller in messages.
 * MESO_ERROR_INVALID_ARGUMENT (no UVs), MESO_ERROR_LIMIT, MESO_ERROR_OUT_OF_MEMORY. */
meso_result relief_shell_create(meso_context *ctx, const meso_object *object, const char *technique,
                                relief_shell **out_shell);
void relief_shell_destroy(relief_shell *shell);
size_t relief_shell_memory(const relief_shell *shell);

/* The boundary faces in this frame's drawing order (tops, fins, bottoms, each front to back:
 * gdm_walk_sort_faces). Called once a frame before rasterization (meso_technique.geometry). */
const meso_mesh *relief_shell_geometry(relief_shell *shell, const meso_frame *frame);

/* The fragments of the boundary faces: each one's ray walked to its first hit, shaded with the
 * hit's normal and self-shadows; misses and fragments of faces turned away (a both_faces
 * technique's exits) discarded. */
void relief_shell_shade(const relief_shell *shell, const relief_shell_search *search,
                        const meso_frame *frame, const meso_object *object,
                        meso_fragment *fragments, size_t count);
void relief_shell_shade_block(const relief_shell *shell, const relief_shell_search *search,
                              const meso_frame *frame, const meso_object *object,
                              meso_fragment_block *block);

/* shade (block NULL) and shade_block (fragments NULL) of relief and relief_exact: on the shell
 * when the object has one (q: the technique's search on it), else relief_common.h's
 * straight-ray loop with `tracer`. Inline, so that the tracer's hooks stay direct calls. */
__attribute__((always_inline)) static inline void
relief_shade_shell_or_ray(const relief_shell *shell, const relief_shell_search *q,
                          const relief_heights *m, const relief_tracer *tracer,
                          relief_params params, const meso_frame *frame, const meso_object *object,
                          meso_fragment *fragments, meso_fragment_block *block, size_t count) {
    if (shell && block)
        relief_shell_shade_block(shell, q, frame, object, block);
    else if (shell)
        relief_shell_shade(shell, q, frame, object, fragments, count);
    else
        relief_shade_core(m, tracer, params, frame, object, fragments, block, count);
}

/* h at texel-centre coordinates (x, y): relief_sample8's bilinear surface, one lookup, the same
 * operations. */
static inline float relief_shell_sample(const relief_heights *m, float x, float y) {
    float fw = (float)m->width, fh = (float)m->height;
    if (m->clamp) {
        x = fminf(fmaxf(x, 0.0f), fw - 1.0f);
        y = fminf(fmaxf(y, 0.0f), fh - 1.0f);
    } else {
        x -= fw * floorf(x * (1.0f / fw));
        y -= fh * floorf(y * (1.0f / fh));
    }
    int i = (int)x, j = (int)y;
    i = i > m->width - 1 ? m->width - 1 : i;
    j = j > m->height - 1 ? m->height - 1 : j;
    float tx = x - (float)i, ty = y - (float)j;
    const float *r0 = m->padded + (size_t)j * (size_t)m->stride + (size_t)i, *r1 = r0 + m->stride;
    float top = r0[0] + (r0[1] - r0[0]) * tx, bottom = r1[0] + (r1[1] - r1[0]) * tx;
    return top + (bottom - top) * ty;
}

/* relief's inside test on the height field: d + h - 1 >= 0 (relief_common.h). */
static inline bool relief_shell_heights_inside(const relief_heights *m, float x, float y, float d,
                                               float *out_f) {
    *out_f = d + relief_shell_sample(m, x, y) - 1.0f;
    return *out_f >= 0.0f;
}

/* relief_shell_heights_inside at eight points (relief_sample8: the same bits). */
static inline int relief_shell_heights_inside8(const relief_heights *m, v8f x, v8f y, v8f d,
                                               v8f *out_f) {
    *out_f = d + relief_sample8(m, x, y) - 1.0f;
    return v8_mask_bits(*out_f >= 0.0f);
}

/* The height field's normal at (x, y) (relief_gradient8's central differences, the gradient's
 * displaced normal meso_displaced_normal), as relief and relief_exact shade. */
meso_vec3 relief_shell_heights_normal(const relief_heights *m, float x, float y,
                                      const relief_shell_frame *f);

#endif
