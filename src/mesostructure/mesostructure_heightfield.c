/* Height fields: creation from images, PNG files and constants; hashing; kind names.
 * The procedural generators live in mesostructure_procedural.c. */
#include <stdlib.h>
#include <string.h>

#include "mesostructure_internal.h"
#include "meso/runtime.h"

/* ---- Allocation --------------------------------------------------------------------------- */

/* A zeroed height field of width x height texels, sizes checked against the image limits
 * before allocating (a height field is rasterised like an image). */
meso_result meso_heightfield_alloc(meso_context *ctx, const char *name, int width, int height,
                                   meso_wrap wrap, meso_heightfield **out_heightfield) {
    *out_heightfield = NULL;
    if (width <= 0 || height <= 0)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: invalid size %dx%d", name,
                              width, height);
    if (width > MESO_IMAGE_MAX_SIDE || height > MESO_IMAGE_MAX_SIDE ||
        (uint64_t)width * (uint64_t)height > MESO_IMAGE_MAX_PIXELS)
        return meso_log_error(ctx, MESO_ERROR_LIMIT,
                              "%s: size %dx%d exceeds the limit of %d a side, %u texels", name,
                              width, height, MESO_IMAGE_MAX_SIDE, MESO_IMAGE_MAX_PIXELS);
    meso_heightfield *hf = calloc(1, sizeof(*hf));
    if (!hf) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", name);
    hf->heights = calloc((size_t)width * (size_t)height, sizeof(float));
    if (!hf->heights) {
        free(hf);
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", name);
    }
    hf->width = width;
    hf->height = height;
    hf->wrap = wrap == MESO_WRAP_DEFAULT ? MESO_WRAP_REPEAT : wrap;
    *out_heightfield = hf;
    return MESO_OK;
}

void meso_heightfield_destroy(meso_heightfield *heightfield) {
    if (!heightfield) return;
    free(heightfield->heights);
    free(heightfield);
}

void meso_heightfield_update_hash(meso_heightfield *heightfield) {
    /* Size and wrap are part of the key: the same texels clamped or repeated bake differently. */
    int32_t header[3] = {heightfield->width, heightfield->height, (int32_t)heightfield->wrap};
    uint64_t h = meso_hash64(header, sizeof(header), MESO_HASH_SEED);
    h = meso_hash64(heightfield->heights,
                    (size_t)heightfield->width * (size_t)heightfield->height * sizeof(float), h);
    heightfield->hash = h;
}

/* ---- From data ---------------------------------------------------------------------------- */

meso_result meso_heightfield_create_constant(meso_context *ctx, int width, int height, float value,
                                             meso_heightfield **out_heightfield) {
    *out_heightfield = NULL;
    if (!isfinite(value) || value < 0.0f || value > 1.0f)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "constant height field: value %g is not in [0, 1]", (double)value);
    meso_heightfield *hf = NULL;
    meso_result r =
        meso_heightfield_alloc(ctx, "constant height field", width, height, MESO_WRAP_REPEAT, &hf);
    if (r != MESO_OK) return r;
    size_t n = (size_t)width * (size_t)height;
    for (size_t k = 0; k < n; k++) hf->heights[k] = value;
    meso_heightfield_update_hash(hf);
    *out_heightfield = hf;
    return MESO_OK;
}

meso_result meso_heightfield_create_from_image(meso_context *ctx, const meso_image *image,
                                               meso_wrap wrap, meso_heightfield **out_heightfield) {
    *out_heightfield = NULL;
    if (!image || !image->pixels || image->channels < 1 || image->channels > 4)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "height field: invalid image");
    meso_heightfield *hf = NULL;
    meso_result r =
        meso_heightfield_alloc(ctx, "height field", image->width, image->height, wrap, &hf);
    if (r != MESO_OK) return r;
    size_t n = (size_t)image->width * (size_t)image->height;
    size_t channels = (size_t)image->channels;
    for (size_t k = 0; k < n; k++) {
        const float *pixel = image->pixels + k * channels;
        /* Grey (+ alpha): the grey value. RGB (+ alpha): its luminance with the Rec. 709
         * weights, on the values as stored (a height map is data, not colour: no sRGB
         * decoding), so a map painted in colour is not read from its red channel alone.
         * Alpha is ignored. */
        float value =
            channels >= 3 ? 0.2126f * pixel[0] + 0.7152f * pixel[1] + 0.0722f * pixel[2] : pixel[0];
        /* Heights live in [0, 1] (docs/design.md); a float image may hold anything, NaN included.
         */
        hf->heights[k] = isfinite(value) ? meso_clampf(value, 0.0f, 1.0f) : 0.0f;
    }
    meso_heightfield_update_hash(hf);
    *out_heightfield = hf;
    return MESO_OK;
}

meso_result meso_heightfield_load_png(meso_context *ctx, const char *path, meso_wrap wrap,
                                      meso_heightfield **out_heightfield) {
    *out_heightfield = NULL;
    meso_image *image = NULL;
    meso_result r = meso_image_load_png(ctx, path, &image);
    if (r != MESO_OK) return r;
    r = meso_heightfield_create_from_image(ctx, image, wrap, out_heightfield);
    meso_image_destroy(image);
    if (r == MESO_OK) {
        /* A constant map renders exactly like `flat`: almost always a wrong file or channel. */
        const meso_heightfield *hf = *out_heightfield;
        size_t n = (size_t)hf->width * (size_t)hf->height;
        size_t k = 1;
        while (k < n && hf->heights[k] == hf->heights[0]) k++;
        if (k == n)
            meso_log_warning(ctx,
                             "%s: the height map is constant (every texel %g): the mesostructure "
                             "is flat",
                             path, (double)hf->heights[0]);
    }
    return r;
}

/* ---- Kinds and defaults ------------------------------------------------------------------- */

static const char *const heightfield_kind_names[] = {
    [MESO_HEIGHTFIELD_BRICKS] = "bricks", [MESO_HEIGHTFIELD_BUMPS] = "bumps",
    [MESO_HEIGHTFIELD_WEAVE] = "weave",   [MESO_HEIGHTFIELD_TILES] = "tiles",
    [MESO_HEIGHTFIELD_BARK] = "bark",
};

bool meso_heightfield_kind_from_name(const char *name, meso_heightfield_kind *out_kind) {
    for (int k = MESO_HEIGHTFIELD_BRICKS; k <= MESO_HEIGHTFIELD_BARK; k++)
        if (name && strcmp(name, heightfield_kind_names[k]) == 0) {
            *out_kind = (meso_heightfield_kind)k;
            return true;
        }
    return false;
}

const char *meso_heightfield_kind_name(meso_heightfield_kind kind) {
    if (kind == MESO_HEIGHTFIELD_DEFAULT) kind = MESO_HEIGHTFIELD_BRICKS;
    if (kind < MESO_HEIGHTFIELD_BRICKS || kind > MESO_HEIGHTFIELD_BARK) return "unknown";
    return heightfield_kind_names[kind];
}

meso_heightfield_desc meso_heightfield_desc_defaults(const meso_heightfield_desc *desc) {
    meso_heightfield_desc d = desc ? *desc : (meso_heightfield_desc){0};
    if (d.kind == MESO_HEIGHTFIELD_DEFAULT) d.kind = MESO_HEIGHTFIELD_BRICKS;
    if (d.resolution == 0) d.resolution = 512;
    bool bark = d.kind == MESO_HEIGHTFIELD_BARK;
    if (d.rows == 0) d.rows = bark ? 3 : 4;
    if (d.columns == 0) d.columns = d.kind == MESO_HEIGHTFIELD_BRICKS ? 2 : bark ? 6 : 4;
    if (d.gap == 0.0f) d.gap = bark ? 0.3f : 0.08f;
    if (d.bevel == 0.0f) d.bevel = 0.04f;
    if (d.seed == 0) d.seed = 1;
    if (d.wrap == MESO_WRAP_DEFAULT) d.wrap = MESO_WRAP_REPEAT;
    return d;
}
