/* The VDM table laid out for the renderers' lookups (not installed): what the CPU technique
 * and the GL back end both read. */
#ifndef MESO_BAKE_VDM_LANES_H
#define MESO_BAKE_VDM_LANES_H

#include "meso/bake_vdm.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The compressed table laid out for lookups of k VDM and m MVM eigenfunctions as dot products
 * of `lanes` = max(k, m) rounded up to 8 numbers (§3.3's reconstruction d = sum_i W^i E^i):
 * W per (x, y, phi) as IEEE half floats with its mip pyramid (§4: "VDM as a texture map is
 * easily anti-aliased by mip-mapping": d is linear in W, so box-filtering W filters the table
 * exactly; 2 x 2 boxes in float, odd sizes wrapped), and E_VDM, E_MVM transposed, zero past
 * k and m. What the CPU technique and the GL back end both read, so they read the same bits. */
#define MESO_VDM_MAX_LEVELS 12
typedef struct meso_vdm_lanes {
    int lanes;
    int num_levels; /* 1 without mipmap */
    int level_width[MESO_VDM_MAX_LEVELS], level_height[MESO_VDM_MAX_LEVELS];
    uint16_t *level_weights[MESO_VDM_MAX_LEVELS]; /* [height][width][num_phi][lanes] */
    float *eigen_t; /* [num_theta * num_curvatures][lanes] (column c * num_theta + t) */
    float *mvm_t;   /* [num_curvatures][lanes] */
} meso_vdm_lanes;
/* MESO_OK or MESO_ERROR_OUT_OF_MEMORY (logged, naming `name`); k, m at most the view's. */
meso_result meso_vdm_lanes_init(meso_context *ctx, const meso_vdm_view *view, int k, int m,
                                bool mipmap, const char *name, meso_vdm_lanes *out);
void meso_vdm_lanes_deinit(meso_vdm_lanes *lanes);

#ifdef __cplusplus
}
#endif
#endif
