/* View-dependent displacement maps (Wang et al. 2003, docs/techniques/vdm.md).
 *
 * Overview
 *   The VDM d(x, y, theta, phi, c) (VDM §3.1) is, for a texel (x, y) of the reference surface,
 *   a view direction (theta, phi) and a curvature c of the reference surface along the view,
 *   the distance along the view ray from the reference surface to the first mesostructure
 *   point; -1 where the ray meets none. With curvature it is the extended d = l / sin(theta)
 *   of the Appendix (l: texture-space distance to the hit). The MVM theta_MVM(x, y, phi, c) is
 *   the largest sampled theta with a valid d (§3.3). Both are compressed by SVD (§3.3):
 *   A = [A_VDM, A_MVM], rows (y, x, phi), columns (c, theta) then c, A ~ W E^T with shared
 *   weights W(x, y, phi).
 *
 * Conventions
 *   - Texture space, one tile = 1 in u and v; texel (i, j) has u = (i+0.5)/W, v = 1-(j+0.5)/H
 *     (row 0 at the top, as images).
 *   - theta: polar angle of V (from the surface toward the eye) to the normal, sampled at
 *     theta_t = (t + 0.5) * (pi/2) / num_theta. phi: azimuth of V in the tangent plane from +u
 *     toward +v, phi_p = p * 2 pi / num_phi. The hit's texture coordinate is
 *     T' = T - d * depth * (sin theta cos phi, sin theta sin phi)  (the paper's T + d V_xy with
 *     V_xy along the ray).
 *   - d is in units of the shell depth (d = 1: one shell thickness along the ray).
 *   - c is in 1/tile (the inverse radius in texture units; world curvature times the world
 *     length of one tile), positive convex; c_k uniform in [curvature_min, curvature_max].
 *   - theta_MVM in radians.
 *
 * Defaults (meso_vdm_desc_defaults): 128 x 128 texels, 32 theta x 8 phi views, 16 curvatures
 * in [-2, 3], depth 0.05 tile, ray step 0.5 texel, 8 VDM and 4 MVM eigenfunctions.
 *
 * Threads: meso_vdm_bake uses every worker of ctx; lookups are pure and thread-safe.
 */
#ifndef MESO_BAKE_VDM_H
#define MESO_BAKE_VDM_H

#include "meso/bake_file.h"
#include "meso/mesostructure.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MESO_VDM_KIND "vdm"
#define MESO_VDM_KIND_VERSION 4u
/* Limits, checked before allocating. */
#define MESO_VDM_MAX_SIDE 1024
#define MESO_VDM_MAX_THETA 128
#define MESO_VDM_MAX_PHI 128
#define MESO_VDM_MAX_CURVATURES 64
#define MESO_VDM_MAX_EIGEN 64
/* The table A is streamed through the SVD, never held whole: its size bounds the bake's time
 * (512 x 512 texels x 8 azimuths x 528 columns = 2^30). Kept whole only with keep_raw. */
#define MESO_VDM_MAX_TABLE_ENTRIES (UINT64_C(1) << 31)
#define MESO_VDM_MAX_RAW_FLOATS (UINT64_C(1) << 28) /* keep_raw: 1 GiB of floats */
#define MESO_VDM_RMSE_COUNT 16

/* Zero fields take the defaults of meso_vdm_desc_defaults(). */
typedef struct meso_vdm_desc {
    const meso_heightfield *heightfield; /* required; read during the call only */
    float depth;                         /* shell thickness in tiles (0.05) */
    int width, height;                   /* texels (128 x 128); the height field is resampled */
    int num_theta;                       /* polar angles (32) */
    int num_phi;                         /* azimuths (8) */
    int num_curvatures;                  /* curvatures (16); 1: zero curvature only */
    float curvature_min;                 /* (-2.0) both 0: the defaults */
    float curvature_max;                 /* (3.0) */
    float step_texels;                   /* ray-marching step (0.5 texel) */
    int vdm_eigenfunctions;              /* k (8) */
    int mvm_eigenfunctions;              /* m (4) */
    bool keep_raw;      /* keep the uncompressed table A (for comparison renders) */
    bool float_weights; /* W as float32; default: rounded to IEEE halves and stored so (2 MiB
                           instead of 4 for the defaults) */
} meso_vdm_desc;

/* The desc with zero fields replaced by their defaults; NULL: all defaults. Pure. */
meso_vdm_desc meso_vdm_desc_defaults(const meso_vdm_desc *desc);

typedef struct meso_vdm meso_vdm;

/* Borrowed view of a map's arrays, valid until meso_vdm_destroy. */
typedef struct meso_vdm_view {
    int width, height, num_theta, num_phi, num_curvatures;
    float depth, curvature_min, curvature_max;
    int num_vdm, num_mvm, num_weights; /* k, m, max(k, m) */
    const float *weights;              /* [height][width][num_phi][num_weights]: W = U lambda */
    const float *eigen_vdm;            /* [num_vdm][num_curvatures][num_theta] */
    const float *eigen_mvm;            /* [num_mvm][num_curvatures] */
    /* NULL unless kept: A itself, [height][width][num_phi][columns], columns
     * c * num_theta + t (d, -1 replaced by d at theta_MVM) then num_theta*num_curvatures + c
     * (theta_MVM). */
    const float *raw;
    int raw_columns;
} meso_vdm_view;

/* The compression report (§3.3): sizes in bytes as stored (float32), and the RMSE of d over
 * every VDM entry of A when reconstructed with k = 1..16 eigenfunctions (k above the number of
 * columns: 0), in shell depths and in texels (shell depths * depth * width). */
typedef struct meso_vdm_compression {
    uint64_t raw_bytes;        /* A_VDM + A_MVM as float32 */
    uint64_t compressed_bytes; /* W (k or m columns, whichever is more; 2 bytes each unless
                                  float_weights) + E_VDM + E_MVM (float32) */
    int num_rmse;
    float rmse[MESO_VDM_RMSE_COUNT];
    float rmse_texels[MESO_VDM_RMSE_COUNT];
    float mvm_rmse;      /* theta_MVM with m eigenfunctions, radians */
    double bake_seconds; /* 0 when loaded */
} meso_vdm_compression;

/* Bake the view-dependent displacement map of a height field (VDM §3.1, Appendix, §3.3).
 *
 * desc      Read during the call only. Zero fields take the defaults of
 *           meso_vdm_desc_defaults(): 128x128 texels, 32x8 views, 16 curvatures.
 * out_vdm   On MESO_OK a new map owned by the caller (meso_vdm_destroy); NULL otherwise.
 * Returns   MESO_OK, MESO_ERROR_INVALID_ARGUMENT (the log names the field), MESO_ERROR_LIMIT,
 *           MESO_ERROR_OUT_OF_MEMORY, MESO_ERROR_CANCELLED, MESO_ERROR_INTERNAL (LAPACK).
 * Threads   Uses every worker of ctx; output identical for any thread count; a progress bar.
 */
meso_result meso_vdm_bake(meso_context *ctx, const meso_vdm_desc *desc, meso_vdm **out_vdm);
void meso_vdm_destroy(meso_vdm *vdm);

/* The parameters the map was baked with (heightfield NULL). */
meso_vdm_desc meso_vdm_get_desc(const meso_vdm *vdm);
meso_vdm_view meso_vdm_get_view(const meso_vdm *vdm);
/* Hash of the height field's hash and every parameter the bake depends on: the cache key. */
uint64_t meso_vdm_cache_key(const meso_vdm_desc *desc);
meso_vdm_compression meso_vdm_get_compression(const meso_vdm *vdm);

/* Save / load as a bake file of kind "vdm" (docs/bake-format.md). Loading validates the
 * arrays' shapes against the params: MESO_ERROR_FORMAT naming the file. */
meso_result meso_vdm_save(meso_context *ctx, const meso_vdm *vdm, const char *path);
meso_result meso_vdm_load(meso_context *ctx, const char *path, meso_vdm **out_vdm);
/* From a loaded bake file (copies the arrays); `name` is used in messages. */
meso_result meso_vdm_from_bake_file(meso_context *ctx, const meso_bake_file *bake, const char *name,
                                    meso_vdm **out_vdm);
/* The cached map of desc, or a new bake stored in the cache (docs/bake-format.md). */
meso_result meso_vdm_bake_cached(meso_context *ctx, const meso_vdm_desc *desc, meso_vdm **out_vdm);

/* d (shell depths) and theta_MVM at continuous (u, v) in tiles (repeat), theta, phi (radians)
 * and c, multilinear over x, y, phi, theta, c as the paper (§4: "interpolated"). num_eigen
 * 0 = all stored; raw = true reads the uncompressed table (NULL view.raw: falls back to the
 * compressed one). Pure, thread-safe. */
float meso_vdm_lookup(const meso_vdm *vdm, float u, float v, float theta, float phi, float c,
                      int num_eigen, bool raw);
float meso_vdm_max_theta(const meso_vdm *vdm, float u, float v, float phi, float c, bool raw);

/* A text report of a bake file of kind "vdm" for `meso info`: parameters, raw and compressed
 * size, RMSE for k = 1..16. Writes at most size bytes (NUL-terminated) like snprintf and
 * returns the length it needed; 0 when the file is not a valid VDM bake. Thread-safe. */
size_t meso_vdm_describe(const meso_bake_file *bake, char *buffer, size_t size);

#ifdef __cplusplus
}
#endif
#endif
