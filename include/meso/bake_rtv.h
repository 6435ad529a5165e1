/* The radiance transfer volume (GDM paper §3.2, after Sloan et al. 2003's bi-scale radiance
 * transfer; issue 17 item 3), uncompressed and view-independent: a first step.
 *
 * Overview
 *   For every voxel (x, y, z) of the mesostructure volume, 16 SH coefficients T_i of the
 *   meso-scale response at the mesostructure surface point nearest the voxel: the radiance it
 *   reflects, per unit albedo, for incident radiance L(w) = sum_i L_i Y_i(w) in the tangent
 *   frame, is sum_i T_i L_i (meso_rtv_evaluate). T includes the shadowing by the mesostructure
 *   and one bounce of interreflection inside it:
 *     T1_i(p) = 1/pi integral V(p, w) max(0, n.w) Y_i(w) dw,
 *     T_i(p)  = T1_i(p) + albedo/pi integral (1 - V(p, w)) max(0, n.w) T1_i(q(p, w)) dw,
 *   q the mesostructure point the ray from p meets. The incident radiance vector is the one
 *   meso_gi_vertex_radiance computes per vertex (render module), interpolated to the hit.
 *
 * What is not here yet (docs/techniques/gdm-gi.md): the view dimension (θ, φ) and its SVD
 * compression (§4.1), the bake file kind "rtv" with its cache, and the rendering hook at the
 * GDM hit. meso's shading model is Lambertian for everything but the scene lights' specular,
 * so the response at a surface point does not depend on the view: the view columns of §4.1
 * would repeat this table.
 *
 * Conventions (those of bake_gdm.h): x = u, y = v in tiles (period 1), z = w in shell depths
 * (0 at the mesh, 1 at the shell's bottom); voxel (i, j, l) at u = (i + 0.5) / width,
 * v = 1 - (j + 0.5) / height, w = l / (layers - 1). The tangent frame of the SH is x along +u,
 * y along +v, z out of the surface (up, toward -w). Shadowing depends on the shell's world
 * shape, so the bake takes `aspect` = shell depth / tile side in world units (a tile is
 * assumed square in the world). A height field h is the solid w >= 1 - h(u, v); below the
 * shell's bottom is solid; a ray that stays inside the shell for `max_tiles` tiles is taken
 * to escape.
 *
 * Threads: meso_bake_rtv uses every worker of ctx, output identical for any thread count;
 * meso_rtv_evaluate is pure and thread-safe.
 */
#ifndef MESO_BAKE_RTV_H
#define MESO_BAKE_RTV_H

#include "meso/mesostructure.h"
#include "meso/sh.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MESO_RTV_MAX_VOXELS (UINT64_C(1) << 24)

/* Zero fields take the defaults. Exactly one of heightfield and solid is set. */
typedef struct meso_rtv_desc {
    const meso_heightfield *heightfield; /* read during the call only */
    const meso_solid *solid;             /* read during the call only */
    float aspect;         /* shell depth / tile side in world units: required, (0, 100] */
    int width, height;    /* voxels in u, v (32 x 32) */
    int layers;           /* voxels in w, >= 2 (8) */
    int directions;       /* incident directions over the sphere, spherical Fibonacci (256) */
    float albedo;         /* of the interreflection bounce (0.7); negative: none */
    float max_tiles;      /* a ray inside the shell this far (tiles) escapes (2) */
} meso_rtv_desc;

typedef struct meso_rtv {
    int width, height, layers;
    float *coefficients; /* [layers][height][width][16]; owned */
    double bake_seconds;
} meso_rtv;

/* Bake. Errors: MESO_ERROR_INVALID_ARGUMENT naming the field ("rtv: aspect: 0 is not in
 * (0, 100]"), MESO_ERROR_LIMIT (voxels above MESO_RTV_MAX_VOXELS or the memory budget),
 * MESO_ERROR_OUT_OF_MEMORY. *out_rtv is NULL on failure. */
meso_result meso_bake_rtv(meso_context *ctx, const meso_rtv_desc *desc, meso_rtv **out_rtv);
void meso_rtv_destroy(meso_rtv *rtv);

/* The response at (u, v, w) (trilinear between voxels, periodic in u and v, clamped in w) to
 * incident radiance `radiance` (per channel, 16 coefficients in the tangent frame): the
 * reflected radiance per unit albedo, out_rgb. Multiply by the albedo (x colour map). */
void meso_rtv_evaluate(const meso_rtv *rtv, meso_vec3 uvw, const float radiance[3][MESO_SH_COUNT],
                       float out_rgb[3]);

#ifdef __cplusplus
}
#endif
#endif
