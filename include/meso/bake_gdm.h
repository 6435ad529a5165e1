/* Generalized displacement maps (Wang et al. 2004, docs/techniques/gdm.md).
 *
 * Overview
 *   The GDM d(x, y, z, theta, phi) (GDM §3.1) is, for a point (x, y, z) of the mesostructure
 *   volume and a direction (theta, phi), the distance along that direction to the first solid
 *   point: 0 inside the solid, and where the ray leaves the slab 0 <= z <= 1 without meeting
 *   the solid, the distance to that slab boundary (§4.1's replacement of d_max, which keeps
 *   the table smooth for the SVD). The volume is surrounded by identical tiles in x and y.
 *   Compression (§4.1): rows (y, x, phi), columns (z, theta); A ~ W E^T.
 *
 * Conventions (the solid's texture space of meso/mesostructure.h)
 *   - x = u, y = v in tiles (period 1); z = w in shell depths, 0 at the mesh (top), 1 at the
 *     shell's bottom; distances are measured in this (u, v, w) space, where a tile is 1 wide
 *     and the shell 1 deep (the world mapping stretches it; the technique maps its rays).
 *   - A height field h is the solid w >= 1 - h(u, v).
 *   - Voxel (i, j) has u = (i + 0.5) / width, v = 1 - (j + 0.5) / height (row 0 at the top,
 *     as images); layer l has w = l / (layers - 1) (both slab faces are sampled: the view
 *     rays of the technique enter on them).
 *   - Direction (theta, phi) is the unit vector (sin theta cos phi, sin theta sin phi,
 *     -cos theta) in (u, v, w): theta = 0 points up, out of the surface (toward -w), theta = pi
 *     down into it; theta_t = (t + 0.5) pi / num_theta, phi_p = p 2 pi / num_phi.
 *
 * Threads: meso_gdm_bake uses every worker of ctx; output identical for any thread count;
 * lookups are pure and thread-safe.
 */
#ifndef MESO_BAKE_GDM_H
#define MESO_BAKE_GDM_H

#include "meso/bake_file.h"
#include "meso/mesostructure.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MESO_GDM_KIND "gdm"
#define MESO_GDM_KIND_VERSION 2u /* 2: solids baked on the dual-contoured surface */
#define MESO_GDM_RMSE_COUNT 16
/* Limits, checked before allocating (MESO_ERROR_LIMIT naming the field). */
#define MESO_GDM_MAX_SIDE 512
#define MESO_GDM_MAX_LAYERS 256
#define MESO_GDM_MAX_THETA 64
#define MESO_GDM_MAX_PHI 128
#define MESO_GDM_MAX_EIGEN 64
/* The table A (rows x columns) is streamed through the SVD, never held whole unless it fits
 * the memory budget; its size bounds the bake's time. keep_raw keeps it: at most 1 GiB. */
#define MESO_GDM_MAX_TABLE_ENTRIES (UINT64_C(1) << 31)
#define MESO_GDM_MAX_RAW_FLOATS (UINT64_C(1) << 28)
/* A ray that neither meets the solid nor leaves the slab (theta = pi/2 exactly, or nearly so)
 * stops after this distance (texture units): d is at most this. */
#define MESO_GDM_MAX_RAY_LENGTH 16.0f

/* Zero fields take the defaults of meso_gdm_desc_defaults(). Exactly one of heightfield and
 * solid is set. */
typedef struct meso_gdm_desc {
    const meso_heightfield *heightfield; /* read during the call only */
    const meso_solid *solid;             /* read during the call only; a periodic one (a tile,
                                            procedural or from a tile mesh), not a model's */
    int width, height, layers;           /* voxels in u, v, w (64 x 64 x 32) */
    int num_theta, num_phi;              /* directions (16 x 32) */
    int eigenmaps;                       /* k, the eigen-maps kept (7: 1.77 MiB at the defaults,
                                            under the paper's 2 MB) */
    bool keep_raw;                       /* keep the uncompressed table (comparison renders) */
    bool float_weights; /* W as float32; default: rounded to IEEE halves and stored so (the
                           view's weights are the rounded values as floats either way) */
} meso_gdm_desc;

/* The desc with zero fields replaced by their defaults; NULL: all defaults. Pure. */
meso_gdm_desc meso_gdm_desc_defaults(const meso_gdm_desc *desc);

typedef struct meso_gdm meso_gdm;

/* Borrowed view of a map's arrays, valid until meso_gdm_destroy. */
typedef struct meso_gdm_view {
    int width, height, layers, num_theta, num_phi, num_eigen;
    const float *weights; /* [height][width][num_phi][num_eigen]: W = U lambda */
    const float *eigen;   /* [num_eigen][layers][num_theta] */
    const float *raw;     /* NULL unless kept: [height][width][num_phi][layers][num_theta] */
    const float *normals; /* [layers][height][width][3]: unit (u, v, w) normal of the solid's
                             surface nearest the voxel, pointing out of the solid */
} meso_gdm_view;

typedef struct meso_gdm_compression {
    uint64_t raw_bytes, compressed_bytes;
    int num_rmse;
    float rmse[MESO_GDM_RMSE_COUNT]; /* of d over every entry, k = 1..16, in texture units */
    float rmse_stored;   /* of the map as stored (k kept, weights as halves unless float_weights),
                            measured over every entry; -1 when the bake streamed the table */
    float rms;           /* of d itself over every entry: the scale the RMSEs compare with */
    double bake_seconds; /* 0 when loaded */
} meso_gdm_compression;

/* Bake the GDM of a solid or a height field (§3.1) and compress it (§4.1).
 *
 * Rays are traced with Embree against a watertight triangle surface of the source: the
 * solid's dual-contoured surface (meso_isosurface_bake, 2x finer than the voxels and at least 128 x
 * 128 x 64 cells a tile) or the height field's texel-centre triangles (at most 1024 a side). A
 * voxel inside the source (meso_solid_distance <= 0; w >= 1 - h) gets 0 without a ray; a ray
 * from outside takes the first point where it enters that surface.
 * desc      Read during the call only. Zero fields take the defaults.
 * out_gdm   On MESO_OK a new map owned by the caller (meso_gdm_destroy); NULL otherwise.
 * Returns   MESO_OK, MESO_ERROR_INVALID_ARGUMENT (no or two sources, a model's solid, a bad
 *           field: the log names it), MESO_ERROR_LIMIT (the limits above, or the memory
 *           budget, checked before allocating), MESO_ERROR_OUT_OF_MEMORY, MESO_ERROR_CANCELLED
 *           (progress), MESO_ERROR_INTERNAL (Embree, LAPACK).
 * Threads   Uses every worker of ctx (rays from its pool; Embree's BVH is built on one thread
 *           so that it is the same tree for any count); output identical for any thread
 *           count; a progress bar "gdm bake". Safe on different contexts at once. */
meso_result meso_gdm_bake(meso_context *ctx, const meso_gdm_desc *desc, meso_gdm **out_gdm);
/* Free; NULL does nothing. */
void meso_gdm_destroy(meso_gdm *gdm);
/* The parameters the map was baked with (sources NULL; keep_raw true when the raw table is
 * held). Pure. */
meso_gdm_desc meso_gdm_get_desc(const meso_gdm *gdm);
meso_gdm_view meso_gdm_get_view(const meso_gdm *gdm);
/* Sizes as stored: raw_bytes the table A as float32; compressed_bytes W (2 bytes a value, 4
 * with float_weights) + E (float32); the normals (12 bytes a voxel) are in neither. */
meso_gdm_compression meso_gdm_get_compression(const meso_gdm *gdm);
/* Hash of the source's hash and every parameter the bake depends on: the cache key. Pure. */
uint64_t meso_gdm_cache_key(const meso_gdm_desc *desc);

/* Save / load as a bake file of kind "gdm" (docs/bake-format.md). Loading checks the params
 * against the limits, every array's type and shape against the params, and every value
 * (finite, in range) before anything is used: MESO_ERROR_FORMAT (or MESO_ERROR_LIMIT) naming
 * the file. The save is atomic. Thread-safe on different maps. */
meso_result meso_gdm_save(meso_context *ctx, const meso_gdm *gdm, const char *path);
meso_result meso_gdm_load(meso_context *ctx, const char *path, meso_gdm **out_gdm);
/* From a loaded bake file (copies the arrays); `name` is used in messages. */
meso_result meso_gdm_from_bake_file(meso_context *ctx, const meso_bake_file *bake, const char *name,
                                    meso_gdm **out_gdm);
/* The cached map of desc, or a new bake stored in the cache (docs/bake-format.md); an
 * unusable cache entry is a warning and baked again. Same results as meso_gdm_bake. */
meso_result meso_gdm_bake_cached(meso_context *ctx, const meso_gdm_desc *desc, meso_gdm **out_gdm);

/* d at continuous uvw (u, v repeat; w clamped to [0, 1]) along the (u, v, w) direction
 * `direction` (any length > 0), interpolated over x, y, z, theta and phi; num_eigen 0 (or
 * more than stored) = all stored; raw reads the uncompressed table (falls back to the
 * compressed one when not kept). Pure, thread-safe.
 * Exactly: with theta = acos(-dir.z / |dir|) and phi = atan2(dir.y, dir.x) in [0, 2 pi), the
 * sample positions are x = u W - 1/2 and y = (1 - v) H - 1/2 (repeating with periods W and H),
 * z = w (L - 1) (clamped to [0, L - 1]), t = theta T / pi - 1/2 (clamped to [0, T - 1]: the
 * half intervals next to the poles take the nearest sample), p = phi P / (2 pi) (repeating with
 * period P); d is the multilinear interpolation of the 32 surrounding table entries. The
 * compressed map computes it as sum_e [trilinear W_e over (x, y, p)] [bilinear E_e over
 * (z, t)], which is the same number (up to rounding) as interpolating the reconstructed
 * entries. Non-finite uvw components are taken as 0; a zero or non-finite direction as
 * straight up (theta 0). */
float meso_gdm_lookup(const meso_gdm *gdm, meso_vec3 uvw, meso_vec3 direction, int num_eigen,
                      bool raw);
/* The stored normal at uvw, trilinear over x, y (repeating) and z (clamped) as above,
 * renormalised; (0, 0, -1) where the corners cancel. Pure, thread-safe. */
meso_vec3 meso_gdm_normal(const meso_gdm *gdm, meso_vec3 uvw);

/* A text report of a bake file of kind "gdm" for `meso info`: shape, raw and compressed size,
 * RMSE for k = 1..16, the stored map's measured RMSE. Writes at most size bytes
 * (NUL-terminated) like snprintf and returns the length it needed; 0 when the file is not a
 * readable GDM bake. Thread-safe. */
size_t meso_gdm_describe(const meso_bake_file *bake, char *buffer, size_t size);

#ifdef __cplusplus
}
#endif

#endif
