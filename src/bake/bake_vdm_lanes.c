/* The compressed VDM laid out for dot-product lookups (bake_vdm.h, meso_vdm_lanes): read by
 * the CPU technique (src/techniques/vdm.c) and uploaded as textures by the GL back end,
 * so both reconstruct d from the same half-float weights. */
#include <stdlib.h>
#include <string.h>

#include "bake_internal.h"
#include "meso/bake_vdm_lanes.h"
#include "meso/runtime.h"

void meso_vdm_lanes_deinit(meso_vdm_lanes *l) {
    for (int i = 0; i < l->num_levels; i++) free(l->level_weights[i]);
    free(l->eigen_t);
    free(l->mvm_t);
    memset(l, 0, sizeof *l);
}

meso_result meso_vdm_lanes_init(meso_context *ctx, const meso_vdm_view *v, int k, int m,
                                bool mipmap, const char *name, meso_vdm_lanes *out) {
    memset(out, 0, sizeof *out);
    int used = k > m ? k : m;
    int lanes = (used + 7) / 8 * 8;
    size_t rows = (size_t)v->width * v->height * v->num_phi;
    int vdm_columns = v->num_theta * v->num_curvatures;
    out->lanes = lanes;
    float *level = calloc(rows * (size_t)lanes, sizeof(float));
    out->eigen_t = calloc((size_t)vdm_columns * lanes, sizeof(float));
    out->mvm_t = calloc((size_t)v->num_curvatures * lanes, sizeof(float));
    out->level_weights[0] = malloc(rows * (size_t)lanes * sizeof(uint16_t));
    out->num_levels = 1;
    if (!level || !out->eigen_t || !out->mvm_t || !out->level_weights[0]) goto oom;
    int copy = used < v->num_weights ? used : v->num_weights;
    for (size_t r = 0; r < rows; r++)
        memcpy(level + r * lanes, v->weights + r * v->num_weights, sizeof(float) * copy);
    out->level_width[0] = v->width;
    out->level_height[0] = v->height;
    for (size_t i = 0; i < rows * (size_t)lanes; i++)
        out->level_weights[0][i] = meso_half_from_float(level[i]);
    while (
        mipmap && out->num_levels < MESO_VDM_MAX_LEVELS &&
        (out->level_width[out->num_levels - 1] > 1 || out->level_height[out->num_levels - 1] > 1)) {
        int l = out->num_levels, pw = out->level_width[l - 1], ph = out->level_height[l - 1];
        int w = pw > 1 ? pw / 2 : 1, h = ph > 1 ? ph / 2 : 1;
        size_t size = (size_t)w * h * v->num_phi * lanes;
        float *dst = calloc(size, sizeof(float));
        out->level_weights[l] = malloc(size * sizeof(uint16_t));
        out->num_levels++;
        if (!dst || !out->level_weights[l]) {
            free(dst);
            goto oom;
        }
        for (int j = 0; j < h; j++)
            for (int i = 0; i < w; i++)
                for (int p = 0; p < v->num_phi; p++) {
                    float *o = dst + (((size_t)j * w + i) * v->num_phi + p) * lanes;
                    for (int q = 0; q < 4; q++) {
                        int si = (2 * i + (q & 1)) % pw, sj = (2 * j + (q >> 1)) % ph;
                        const float *in = level + (((size_t)sj * pw + si) * v->num_phi + p) * lanes;
                        for (int c = 0; c < lanes; c++) o[c] += 0.25f * in[c];
                    }
                }
        for (size_t i = 0; i < size; i++) out->level_weights[l][i] = meso_half_from_float(dst[i]);
        free(level);
        level = dst;
        out->level_width[l] = w;
        out->level_height[l] = h;
    }
    free(level);
    for (int i = 0; i < k && i < v->num_vdm; i++)
        for (int col = 0; col < vdm_columns; col++)
            out->eigen_t[(size_t)col * lanes + i] = v->eigen_vdm[(size_t)i * vdm_columns + col];
    for (int i = 0; i < m && i < v->num_mvm; i++)
        for (int c = 0; c < v->num_curvatures; c++)
            out->mvm_t[(size_t)c * lanes + i] = v->eigen_mvm[(size_t)i * v->num_curvatures + c];
    return MESO_OK;
oom:
    free(level);
    meso_vdm_lanes_deinit(out);
    return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", name);
}
