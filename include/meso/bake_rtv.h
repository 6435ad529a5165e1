/* The radiance transfer volume (GDM paper §3.2 and §4.1, after Sloan et al. 2003's bi-scale
 * radiance transfer).
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
 * The view dimension (§3.2: f_i(x, y, z, theta, phi)): meso's shading model is Lambertian
 * for everything but the scene lights' specular, so the response at a surface point does not
 * depend on the view; what does is which surface point a voxel stands for. Entry (voxel c,
 * view w_v) is T at the surface point the view ray through c shows: the ray, travelling along
 * -w_v, is followed back out of the solid when c is inside it, and on until it meets the solid
 * when c is outside (GDM's own semantics: the voxels around a thin feature answer for the side
 * that is seen). Views: theta_t = (t + 0.5) (pi/2) / num_theta from the normal, phi_p =
 * p 2 pi / num_phi, w_v = (sin theta cos phi, sin theta sin phi, cos theta) toward the viewer.
 *
 * Compression (§4.1): per coefficient i, the matrix with rows (z, y, x) and columns
 * (theta, phi) is decomposed by SVD (meso_bake_svd_streamed) and `eigen` eigenfunctions kept:
 * f_i(c, view) = sum_k W_ik(c) E_ik(view). rmse[k - 1] is the RMSE of the table over every
 * entry with k eigenfunctions, from the singular values.
 *
 * Files: bake file kind "rtv" (meso_rtv_save / meso_rtv_load): arrays "weights" f32
 * [16][voxels][k], "eigen" f32 [16][k][views], "shape" i32 {width, height, layers, num_theta,
 * num_phi}, "rmse" f32 [16]; every size is checked against the others and the limits, every
 * value is finite, before use. The rendering hook at the GDM hit is the gdm technique's option
 * `gi` (docs/techniques/gdm-gi.md).
 *
 * Conventions (those of bake_gdm.h): x = u, y = v in tiles (period 1), z = w in shell depths
 * (0 at the mesh, 1 at the shell's bottom); voxel (i, j, l) at u = (i + 0.5) / width,
 * v = 1 - (j + 0.5) / height, w = l / (layers - 1). The tangent frame of the SH is x along +u,
 * y along +v, z out of the surface (up, toward -w). Shadowing depends on the shell's world
 * shape, so the bake takes `aspect` = shell depth / tile side in world units (a tile is
 * assumed square in the world). A height field h is the solid w >= 1 - h(u, v); below the
 * shell's bottom is solid. A solid's shell is open at both faces: a ray that leaves through the
 * bottom escapes too, and carries the light arriving from below the tangent plane (the inside
 * of a closed mesh seen through the holes, meso_gi_vertex_radiance_through_shell). A ray that
 * stays inside the shell for `max_tiles` tiles is taken to escape.
 *
 * Threads: meso_rtv_bake uses every worker of ctx, output identical for any thread count;
 * meso_rtv_evaluate is pure and thread-safe.
 */
#ifndef MESO_BAKE_RTV_H
#define MESO_BAKE_RTV_H

#include "meso/bake_file.h"
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
    float aspect;           /* shell depth / tile side in world units: required, (0, 100] */
    int width, height;      /* voxels in u, v (32 x 32) */
    int layers;             /* voxels in w, >= 2 (8) */
    int directions;         /* incident directions over the sphere, spherical Fibonacci (256) */
    float albedo;           /* of the interreflection bounce (0.7); negative: none */
    float max_tiles;        /* a ray inside the shell this far (tiles) escapes (2) */
    int num_theta, num_phi; /* views (4 x 8) */
    int eigen;              /* eigenfunctions kept per coefficient (4), <= views */
} meso_rtv_desc;

#define MESO_RTV_KIND "rtv"
#define MESO_RTV_KIND_VERSION 2u /* 2: the same-surface lookup; solids open below */
#define MESO_RTV_RMSE_COUNT 16

typedef struct meso_rtv {
    int width, height, layers, num_theta, num_phi, num_eigen;
    float *coefficients; /* [layers][height][width][16] at the nearest surface point; owned;
                            NULL for a loaded RTV */
    float *weights;      /* [16][layers][height][width][num_eigen]; owned */
    float *eigen;        /* [16][num_eigen][num_theta][num_phi]; owned */
    float rmse[MESO_RTV_RMSE_COUNT]; /* with k = 1..16 eigenfunctions (0 past the views) */
    uint64_t raw_bytes, compressed_bytes;
    double bake_seconds; /* 0 when loaded */
} meso_rtv;

/* Bake. Errors: MESO_ERROR_INVALID_ARGUMENT naming the field ("rtv: aspect: 0 is not in
 * (0, 100]"), MESO_ERROR_LIMIT (voxels above MESO_RTV_MAX_VOXELS or the memory budget),
 * MESO_ERROR_OUT_OF_MEMORY. *out_rtv is NULL on failure. */
meso_result meso_rtv_bake(meso_context *ctx, const meso_rtv_desc *desc, meso_rtv **out_rtv);
void meso_rtv_destroy(meso_rtv *rtv);

/* meso_rtv_bake through the bake cache (bake_file.h): keyed by the source's hash and every
 * desc field; a cached RTV has no `coefficients` and bake_seconds 0. */
meso_result meso_rtv_bake_cached(meso_context *ctx, const meso_rtv_desc *desc, meso_rtv **out_rtv);

/* Save as a bake file (atomically); load one, validated (MESO_ERROR_FORMAT naming the file and
 * the array for anything inconsistent, MESO_ERROR_IO, MESO_ERROR_LIMIT). */
meso_result meso_rtv_save(meso_context *ctx, const meso_rtv *rtv, const char *path);
meso_result meso_rtv_load(meso_context *ctx, const char *path, meso_rtv **out_rtv);
/* An RTV from a loaded bake file, validated as meso_rtv_load does; `name` names it in
 * messages. The bake file may be destroyed afterwards. */
meso_result meso_rtv_from_bake_file(meso_context *ctx, const meso_bake_file *bake, const char *name,
                                    meso_rtv **out_rtv);
/* A text report of a bake file of kind "rtv" for `meso info`: voxels, views, eigenfunctions,
 * raw and compressed size, RMSE for k = 1..16. Writes at most size bytes (NUL-terminated)
 * like snprintf and returns the length it needed; 0 when the file is not an rtv bake whose
 * arrays have the expected shapes. Thread-safe. */
size_t meso_rtv_describe(const meso_bake_file *bake, char *buffer, size_t size);

/* Where meso_rtv_evaluate reads for (uvw, view): the 8 voxels (indices into the voxel arrays,
 * [layers][height][width]) with their trilinear weights and the 4 views ([num_theta][num_phi])
 * with their bilinear weights. For renderers that lay the arrays out their own way. Pure. */
typedef struct meso_rtv_cell {
    size_t corner[8];
    float corner_weight[8];
    int view_index[4];
    float view_weight[4];
} meso_rtv_cell;
void meso_rtv_cell_at(const meso_rtv *rtv, meso_vec3 uvw, meso_vec3 view, meso_rtv_cell *out);

/* The compressed response at (u, v, w) (trilinear between voxels, periodic in u and v, clamped
 * in w) seen from `view` (unit, tangent frame, toward the viewer; bilinear between the baked
 * views, clamped at the horizon) to incident radiance `radiance` (per channel, 16 coefficients
 * in the tangent frame): the reflected radiance per unit albedo, out_rgb, >= 0. Multiply by
 * the albedo (x colour map). The GDM technique calls it at its hit. Pure, thread-safe. */
void meso_rtv_evaluate(const meso_rtv *rtv, meso_vec3 uvw, meso_vec3 view,
                       const float radiance[3][MESO_SH_COUNT], float out_rgb[3]);

#ifdef __cplusplus
}
#endif
#endif
