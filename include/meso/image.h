/* meso images: float pixel buffers, PNG files (libpng), textures with mip pyramids.
 *
 * Images are plain data (meso_image): width, height, channels (1-4) and interleaved float
 * pixels, row 0 at the top. Per-pixel code reads them in its inner loops, so they are not
 * hidden behind accessors (docs/design.md). Values are whatever the producer put there: PNG
 * loading maps 0..max to 0..1 without colour conversion; renderers write linear RGB.
 *
 * Texture space follows OpenGL (docs/design.md): texel column i <-> u = (i+0.5)/W, row j (0 = top)
 * <-> v = 1 - (j+0.5)/H.
 *
 * Limits: MESO_IMAGE_MAX_SIDE pixels a side and MESO_IMAGE_MAX_PIXELS pixels in all, checked
 * before allocating, for created and loaded images alike.
 */
#ifndef MESO_IMAGE_H
#define MESO_IMAGE_H

#include "meso/core.h"
#include "meso/math.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MESO_IMAGE_MAX_SIDE 16384
#define MESO_IMAGE_MAX_PIXELS (1u << 26) /* 64 Mpixels: 1 GiB as float RGBA */

typedef struct meso_image {
    int width, height;
    int channels;  /* 1 grey, 2 grey+alpha, 3 RGB, 4 RGBA */
    float *pixels; /* width * height * channels floats, row-major, row 0 at the top; owned */
} meso_image;

/* A new image of zeros. Returns MESO_OK, MESO_ERROR_INVALID_ARGUMENT (size <= 0, channels not
 * 1-4), MESO_ERROR_LIMIT (above the limits), MESO_ERROR_OUT_OF_MEMORY. Thread-safe. */
meso_result meso_image_create(meso_context *ctx, int width, int height, int channels,
                              meso_image **out_image);
/* A deep copy. */
meso_result meso_image_clone(meso_context *ctx, const meso_image *image, meso_image **out_image);
/* Free; NULL does nothing. */
void meso_image_destroy(meso_image *image);

/* The pixel at (x, y), channel c; no bounds check. */
static inline float *meso_image_at(const meso_image *image, int x, int y) {
    return image->pixels + ((size_t)y * (size_t)image->width + (size_t)x) * (size_t)image->channels;
}

/* Load an 8- or 16-bit grey, grey+alpha, RGB, RGBA or palette PNG; values scaled to [0,1],
 * channels as stored (palette becomes RGB or RGBA). Errors name the file: MESO_ERROR_IO
 * (missing, unreadable), MESO_ERROR_FORMAT (not a PNG, truncated, corrupt), MESO_ERROR_LIMIT
 * (declared size above the limits; refused before any pixel memory is allocated). */
meso_result meso_image_load_png(meso_context *ctx, const char *path, meso_image **out_image);

typedef enum meso_encoding {
    MESO_ENCODING_DEFAULT = 0, /* sRGB */
    MESO_ENCODING_SRGB,        /* colour channels pass through the sRGB curve; alpha does not */
    MESO_ENCODING_LINEAR,      /* values written as they are */
} meso_encoding;

typedef struct meso_png_desc {
    int bit_depth;          /* 0 or 8: 8-bit; 16: 16-bit */
    meso_encoding encoding; /* default sRGB */
} meso_png_desc;

/* Save as PNG with as many channels as the image (1-4), values clamped to [0,1] and rounded to
 * nearest. Written to a temporary file and renamed into place. desc may be NULL (defaults).
 * Returns MESO_OK or MESO_ERROR_IO (logged). */
meso_result meso_image_save_png(meso_context *ctx, const meso_image *image, const char *path,
                                const meso_png_desc *desc);
/* Save `count` images (at most MESO_PNG_SAVE_ALL_MAX) to paths[i] with descs[i] (descs may be
 * NULL: defaults), all or none: every file is written under a temporary name first and renamed
 * into place only when all were written. Returns as meso_image_save_png. */
#define MESO_PNG_SAVE_ALL_MAX 8
meso_result meso_image_save_png_all(meso_context *ctx, size_t count,
                                    const meso_image *const *images, const char *const *paths,
                                    const meso_png_desc *descs);
/* Save as OpenEXR when the path ends in ".exr" (any case), else as PNG with desc: OpenEXR
 * files hold the values as they are (linear, not clamped: desc's encoding and bit depth do not
 * apply) as 16-bit half floats (1 channel: Y, 2: Y A, 3: R G B, 4: R G B A), ZIP-compressed,
 * one scanline part. Atomic as meso_image_save_png; the _all form writes all or none. */
meso_result meso_image_save(meso_context *ctx, const meso_image *image, const char *path,
                            const meso_png_desc *desc);
meso_result meso_image_save_all(meso_context *ctx, size_t count, const meso_image *const *images,
                                const char *const *paths, const meso_png_desc *descs);
/* Whether meso_image_save writes `path` as OpenEXR (it ends in ".exr", any case). */
bool meso_image_path_is_exr(const char *path);
/* An OpenEXR file (as meso_image_save) written to an open stream at its start, through its
 * file descriptor; `path` only names the file in messages. MESO_OK, MESO_ERROR_IO (logged). */
meso_result meso_image_write_exr(meso_context *ctx, const meso_image *image, FILE *file,
                                 const char *path);
/* Write an OpenEXR image (scanlines, ZIP) of num_channels (1..MESO_EXR_MAX_CHANNELS) channels
 * named names[c], pixels interleaved [y][x][c] (row 0 at the top), stored as half floats when
 * `half` else as floats; atomically. For tables with their own channel names (meso bake -o,
 * docs/gpu.md); meso_image_save is the form for images. MESO_ERROR_IO naming the path. */
#define MESO_EXR_MAX_CHANNELS 1024
meso_result meso_exr_write(meso_context *ctx, const char *path, int width, int height,
                           int num_channels, const char *const *names, const float *pixels,
                           bool half);
/* Whether `data` starts with OpenEXR's magic number. */
bool meso_file_is_exr(const void *data, size_t size);
/* Read an OpenEXR file's RGB (scanline or tiled, any compression; luminance files as grey RGB;
 * a missing channel is 0) into a new linear float image of 3 channels. The data window's size
 * is checked against max_side, max_pixels and the context's memory budget before anything is
 * allocated. MESO_OK, MESO_ERROR_FORMAT (unreadable, corrupt), MESO_ERROR_LIMIT,
 * MESO_ERROR_OUT_OF_MEMORY; logged naming the path. *out_image NULL on failure. */
meso_result meso_image_read_exr_rgb(meso_context *ctx, const char *path, int max_side,
                                    uint64_t max_pixels, meso_image **out_image);
/* The same PNG written to an open stream (e.g. a meso_atomic_file's, so that several outputs
 * can be committed together); `path` only names the file in messages. Not flushed or closed. */
meso_result meso_image_write_png(meso_context *ctx, const meso_image *image, FILE *file,
                                 const char *path, const meso_png_desc *desc);

/* ---- Textures ----------------------------------------------------------------------------- */

typedef enum meso_filter {
    MESO_FILTER_DEFAULT = 0, /* bilinear */
    MESO_FILTER_NEAREST,
    MESO_FILTER_BILINEAR,
    MESO_FILTER_TRILINEAR, /* bilinear in the two mip levels around lod, blended */
} meso_filter;

typedef enum meso_wrap {
    MESO_WRAP_DEFAULT = 0, /* repeat */
    MESO_WRAP_REPEAT,
    MESO_WRAP_CLAMP, /* clamp to edge */
} meso_wrap;

#define MESO_TEXTURE_MAX_LEVELS 16

typedef struct meso_texture {
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
} meso_texture;

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
