/* Framebuffers: linear colour, coverage and view depth, and their images and PNG files. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "raster_internal.h"
#include "meso/runtime.h"

float *meso_render_alloc_floats(size_t count) {
    size_t bytes = (count * sizeof(float) + 63u) & ~(size_t)63u;
    return aligned_alloc(64, bytes ? bytes : 64);
}

/* colour (3 floats), coverage and depth a sample */
#define BYTES_PER_SAMPLE (5 * sizeof(float))

uint64_t meso_render_memory_estimate(const meso_render_desc *desc, int width, int height) {
    uint64_t pixels = (uint64_t)(width > 0 ? width : 0) * (uint64_t)(height > 0 ? height : 0);
    int samples = desc && desc->samples > 1 ? desc->samples : 1;
    uint64_t n = samples > 1 ? (uint64_t)ceil(sqrt((double)samples) - 1e-9) : 1;
    /* + the colour and coverage images a save converts the framebuffer to (16 bytes a pixel) */
    return pixels * (BYTES_PER_SAMPLE * (1 + (n > 1 ? n * n : 0)) + 16);
}

meso_result meso_framebuffer_create(meso_context *ctx, int width, int height,
                                    meso_framebuffer **out_framebuffer) {
    *out_framebuffer = NULL;
    if (width <= 0 || height <= 0) {
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "framebuffer: size %d x %d must be positive", width, height);
    }
    if (width > MESO_IMAGE_MAX_SIDE || height > MESO_IMAGE_MAX_SIDE ||
        (uint64_t)width * (uint64_t)height > MESO_IMAGE_MAX_PIXELS) {
        return meso_log_error(ctx, MESO_ERROR_LIMIT,
                              "framebuffer: size %d x %d exceeds the limit %d a side, %u pixels",
                              width, height, MESO_IMAGE_MAX_SIDE, (unsigned)MESO_IMAGE_MAX_PIXELS);
    }
    meso_result r =
        meso_memory_check(ctx, "framebuffer", meso_render_memory_estimate(NULL, width, height));
    if (r != MESO_OK) return r;
    size_t n = (size_t)width * (size_t)height;
    meso_framebuffer *fb = calloc(1, sizeof(*fb));
    if (!fb) goto oom;
    fb->width = width;
    fb->height = height;
    /* 64-byte aligned: the rasterizer streams whole rows into them */
    fb->color = meso_render_alloc_floats(3 * n);
    fb->coverage = meso_render_alloc_floats(n);
    fb->depth = meso_render_alloc_floats(n);
    if (!fb->color || !fb->coverage || !fb->depth) goto oom;
    for (size_t i = 0; i < n; i++) {
        fb->color[3 * i] = fb->color[3 * i + 1] = fb->color[3 * i + 2] = 0.0f;
        fb->coverage[i] = 0.0f;
        fb->depth[i] = INFINITY;
    }
    *out_framebuffer = fb;
    return MESO_OK;
oom:
    meso_framebuffer_destroy(fb);
    return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "framebuffer: out of memory for %d x %d",
                          width, height);
}

void meso_framebuffer_destroy(meso_framebuffer *framebuffer) {
    if (!framebuffer) return;
    free(framebuffer->color);
    free(framebuffer->coverage);
    free(framebuffer->depth);
    free(framebuffer);
}

/* A copy of one of the framebuffer's planes (`channels` floats a pixel) as an image. */
static meso_result plane_image(meso_context *ctx, const meso_framebuffer *fb, int channels,
                               bool coverage, meso_image **out_image) {
    *out_image = NULL;
    if (!fb) return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "framebuffer: NULL");
    meso_image *image = NULL;
    meso_result r = meso_image_create(ctx, fb->width, fb->height, channels, &image);
    if (r != MESO_OK) return r;
    memcpy(image->pixels, coverage ? fb->coverage : fb->color,
           (size_t)channels * (size_t)fb->width * (size_t)fb->height * sizeof(float));
    *out_image = image;
    return MESO_OK;
}

meso_result meso_framebuffer_color_image(meso_context *ctx, const meso_framebuffer *fb,
                                         meso_image **out_image) {
    return plane_image(ctx, fb, 3, false, out_image);
}

meso_result meso_framebuffer_coverage_image(meso_context *ctx, const meso_framebuffer *fb,
                                            meso_image **out_image) {
    return plane_image(ctx, fb, 1, true, out_image);
}

/* save_png and save: PNG always, or each file's format from its extension. */
static meso_result save_framebuffer(meso_context *ctx, const meso_framebuffer *fb,
                                    const meso_png_desc *desc, const char *path,
                                    const char *coverage_path, bool format_from_extension) {
    if (!fb || !path) {
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "framebuffer: NULL %s",
                              fb ? "path" : "framebuffer");
    }
    meso_image *color = NULL, *coverage = NULL;
    meso_result r = meso_framebuffer_color_image(ctx, fb, &color);
    if (r == MESO_OK && coverage_path) r = meso_framebuffer_coverage_image(ctx, fb, &coverage);
    if (r == MESO_OK) {
        const meso_image *images[2] = {color, coverage};
        const char *paths[2] = {path, coverage_path};
        /* the mask is a fraction, not a colour: written linearly */
        const meso_png_desc descs[2] = {
            *desc, {.bit_depth = desc->bit_depth, .encoding = MESO_ENCODING_LINEAR}};
        size_t count = coverage_path ? 2 : 1;
        r = format_from_extension ? meso_image_save_all(ctx, count, images, paths, descs)
                                  : meso_image_save_png_all(ctx, count, images, paths, descs);
    }
    meso_image_destroy(color);
    meso_image_destroy(coverage);
    return r;
}

meso_result meso_framebuffer_save_png(meso_context *ctx, const meso_framebuffer *fb,
                                      meso_encoding encoding, const char *path,
                                      const char *coverage_path) {
    meso_png_desc desc = {.encoding = encoding};
    return save_framebuffer(ctx, fb, &desc, path, coverage_path, false);
}

meso_result meso_framebuffer_save(meso_context *ctx, const meso_framebuffer *fb,
                                  const meso_png_desc *desc, const char *path,
                                  const char *coverage_path) {
    meso_png_desc defaults = {0};
    return save_framebuffer(ctx, fb, desc ? desc : &defaults, path, coverage_path, true);
}
