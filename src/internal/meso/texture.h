/* Textures as the renderer samples them (not installed): the mip levels and the compact sRGB
 * copy of a colour map. Scenes hold them behind the opaque meso_texture of image.h. */
#ifndef MESO_TEXTURE_H
#define MESO_TEXTURE_H

#include "meso/image.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MESO_TEXTURE_MAX_LEVELS 16

struct meso_texture {
    int num_levels;                              /* 1 + floor(log2(max side)) with mips, else 1 */
    meso_image *levels[MESO_TEXTURE_MAX_LEVELS]; /* level 0 is the full image; all RGBA */
    meso_wrap wrap;
    /* NULL, or level 0's RGB as 8-bit sRGB codes, R in bits 0-7, G 8-15, B 16-23, one uint32 a
     * texel, row-major (meso_texture_add_srgb8): the colour lookup of the shading reads these,
     * decoded to linear by meso_srgb8_table, a quarter of the float level's bytes. */
    uint32_t *srgb8;
    /* NULL without mips, else every level one after another as RGBA floats, level k at
     * mip_chain + mip_offset[k] (row-major, its width levels[k]->width): what the shading's
     * footprint-filtered lookups gather from (docs/techniques.md, "Filtering"). Level 0 holds
     * the values the unfiltered lookup reads (srgb8's decoded codes when present), each next
     * level the 2 x 2 box average of the one before, summed as (a + b) + (c + d) so a constant
     * map stays exactly constant. */
    float *mip_chain;
    int32_t mip_offset[MESO_TEXTURE_MAX_LEVELS];
};

/* A texture of `image` converted to RGBA (grey spreads to RGB, missing alpha is 1), with a box
 * filtered mip pyramid when build_mips. `image` is copied. */
meso_result meso_texture_create(meso_context *ctx, const meso_image *image, meso_wrap wrap,
                                bool build_mips, meso_texture **out_texture);
void meso_texture_destroy(meso_texture *texture);

/* Give a colour texture its compact copy (texture->srgb8): each linear R, G, B of level 0 as
 * the 8-bit sRGB code whose decoded value (meso_srgb8_table) is nearest, so a map loaded from
 * an 8-bit sRGB PNG keeps its exact values. Leaves texture->srgb8 NULL, and returns MESO_OK,
 * when a value lies outside [0, 1] (not representable; the float level stays in use). Returns
 * MESO_ERROR_OUT_OF_MEMORY. Not thread-safe on one texture. */
meso_result meso_texture_add_srgb8(meso_context *ctx, meso_texture *texture);
/* The 256 linear values of the 8-bit sRGB codes: meso_srgb_to_linear(k / 255). Thread-safe. */
const float *meso_srgb8_table(void);

/* Sample at (u, v) in texture space. lod (mip level, fractional) is used by TRILINEAR only and
 * clamped to the pyramid. Pure and thread-safe. */
meso_vec4 meso_texture_sample(const meso_texture *texture, meso_vec2 uv, float lod,
                              meso_filter filter);

#ifdef __cplusplus
}
#endif
#endif
