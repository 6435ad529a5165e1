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
 * Threads: meso_bake_gdm uses every worker of ctx; output identical for any thread count;
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
#define MESO_GDM_KIND_VERSION 1u
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

/* Zero fields take the defaults of meso_query_gdm_defaults(). Exactly one of heightfield and
 * solid is set. */
typedef struct meso_gdm_desc {
    const meso_heightfield *heightfield; /* read during the call only */
    const meso_solid *solid;             /* read during the call only */
    int width, height, layers;           /* voxels in u, v, w (64 x 64 x 32) */
    int num_theta, num_phi;              /* directions (16 x 32) */
    int eigenmaps;                       /* k, the eigen-maps kept */
    bool keep_raw;                       /* keep the uncompressed table (comparison renders) */
    bool float_weights; /* W as float32; default: rounded to IEEE halves and stored so */
} meso_gdm_desc;

meso_gdm_desc meso_query_gdm_defaults(const meso_gdm_desc *desc);

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
    float rmse_stored; /* of the map as stored (k kept, weights as halves unless float_weights),
                          measured over every entry; -1 when the bake streamed the table */
    double bake_seconds; /* 0 when loaded */
} meso_gdm_compression;

meso_result meso_bake_gdm(meso_context *ctx, const meso_gdm_desc *desc, meso_gdm **out_gdm);
void meso_gdm_destroy(meso_gdm *gdm);
meso_gdm_desc meso_gdm_get_desc(const meso_gdm *gdm);
meso_gdm_view meso_gdm_get_view(const meso_gdm *gdm);
meso_gdm_compression meso_gdm_get_compression(const meso_gdm *gdm);
uint64_t meso_gdm_cache_key(const meso_gdm_desc *desc);

meso_result meso_gdm_save(meso_context *ctx, const meso_gdm *gdm, const char *path);
meso_result meso_gdm_load(meso_context *ctx, const char *path, meso_gdm **out_gdm);
meso_result meso_gdm_from_bake_file(meso_context *ctx, const meso_bake_file *bake, const char *name,
                                    meso_gdm **out_gdm);
meso_result meso_gdm_bake_cached(meso_context *ctx, const meso_gdm_desc *desc, meso_gdm **out_gdm);

/* d at continuous uvw (u, v repeat; w clamped to [0, 1]) along the unit (u, v, w) direction
 * `direction`, interpolated over x, y, z, theta and phi; num_eigen 0 = all stored; raw reads
 * the uncompressed table (falls back to the compressed one when not kept). Pure. */
float meso_gdm_lookup(const meso_gdm *gdm, meso_vec3 uvw, meso_vec3 direction, int num_eigen,
                      bool raw);
/* The stored normal at uvw, trilinear, renormalised. Pure. */
meso_vec3 meso_gdm_normal(const meso_gdm *gdm, meso_vec3 uvw);

/* `meso info`'s report of a bake file of kind "gdm", like meso_vdm_describe. */
size_t meso_gdm_describe(const meso_bake_file *bake, char *buffer, size_t size);

#ifdef __cplusplus
}
#endif

#endif
