/* Float images and textures with mip pyramids. */
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "core_internal.h"
#include "meso/runtime.h"
#include "meso/image.h"
#include "meso/texture.h"

meso_result meso_image_create(meso_context *ctx, int width, int height, int channels,
                              meso_image **out_image) {
    *out_image = NULL;
    if (width <= 0 || height <= 0 || channels < 1 || channels > 4)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "image: invalid size %dx%d with %d channels", width, height,
                              channels);
    if (width > MESO_IMAGE_MAX_SIDE || height > MESO_IMAGE_MAX_SIDE ||
        (uint64_t)width * (uint64_t)height > MESO_IMAGE_MAX_PIXELS)
        return meso_log_error(ctx, MESO_ERROR_LIMIT,
                              "image: %dx%d exceeds the limit of %d a side and %u pixels", width,
                              height, MESO_IMAGE_MAX_SIDE, MESO_IMAGE_MAX_PIXELS);
    meso_image *image = calloc(1, sizeof(*image));
    float *pixels = calloc((size_t)width * (size_t)height * (size_t)channels, sizeof(float));
    if (!image || !pixels) {
        free(image);
        free(pixels);
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "image: out of memory for %dx%d",
                              width, height);
    }
    *image = (meso_image){width, height, channels, pixels};
    *out_image = image;
    return MESO_OK;
}

meso_result meso_image_clone(meso_context *ctx, const meso_image *image, meso_image **out_image) {
    meso_result r = meso_image_create(ctx, image->width, image->height, image->channels, out_image);
    if (r == MESO_OK)
        memcpy((*out_image)->pixels, image->pixels,
               (size_t)image->width * (size_t)image->height * (size_t)image->channels *
                   sizeof(float));
    return r;
}

void meso_image_destroy(meso_image *image) {
    if (!image) return;
    free(image->pixels);
    free(image);
}

/* ---- Textures ----------------------------------------------------------------------------- */

static void to_rgba(const meso_image *src, meso_image *dst) {
    size_t count = (size_t)src->width * (size_t)src->height;
    for (size_t i = 0; i < count; i++) {
        const float *s = src->pixels + i * (size_t)src->channels;
        float *d = dst->pixels + i * 4;
        switch (src->channels) {
        case 1:
            d[0] = d[1] = d[2] = s[0];
            d[3] = 1.0f;
            break;
        case 2:
            d[0] = d[1] = d[2] = s[0];
            d[3] = s[1];
            break;
        case 3:
            d[0] = s[0];
            d[1] = s[1];
            d[2] = s[2];
            d[3] = 1.0f;
            break;
        default:
            memcpy(d, s, 4 * sizeof(float));
            break;
        }
    }
}

/* Next mip level by a box filter over 2x2 texels (odd sizes repeat the last row/column). */
static void downsample(const meso_image *src, meso_image *dst) {
    for (int y = 0; y < dst->height; y++)
        for (int x = 0; x < dst->width; x++) {
            int x0 = 2 * x < src->width ? 2 * x : src->width - 1;
            int y0 = 2 * y < src->height ? 2 * y : src->height - 1;
            int x1 = x0 + 1 < src->width ? x0 + 1 : x0;
            int y1 = y0 + 1 < src->height ? y0 + 1 : y0;
            float *d = meso_image_at(dst, x, y);
            for (int c = 0; c < 4; c++)
                d[c] = 0.25f * (meso_image_at(src, x0, y0)[c] + meso_image_at(src, x1, y0)[c] +
                                meso_image_at(src, x0, y1)[c] + meso_image_at(src, x1, y1)[c]);
        }
}

/* texture->mip_chain (meso_texture) from level 0's values, or from the decoded srgb8 codes
 * when the texture has them, so the chain's level 0 is what the unfiltered lookup reads. */
static meso_result build_mip_chain(meso_context *ctx, meso_texture *t) {
    free(t->mip_chain);
    t->mip_chain = NULL;
    if (t->num_levels < 2) return MESO_OK;
    size_t total = 0;
    for (int k = 0; k < t->num_levels; k++) {
        /* level sizes within MESO_IMAGE_MAX_PIXELS: the chain's 4/3 of level 0 in RGBA floats
         * stays below 2^31 floats, the range of the lookups' 32-bit gather indices */
        t->mip_offset[k] = (int32_t)total;
        total += (size_t)t->levels[k]->width * (size_t)t->levels[k]->height * 4;
    }
    float *chain = malloc(total * sizeof *chain);
    if (!chain) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "texture: out of memory");
    const meso_image *l0 = t->levels[0];
    size_t n0 = (size_t)l0->width * (size_t)l0->height;
    const float *table = meso_srgb8_table();
    for (size_t i = 0; i < n0; i++) {
        float *d = chain + 4 * i;
        if (t->srgb8) {
            uint32_t code = t->srgb8[i];
            d[0] = table[code & 255u], d[1] = table[(code >> 8) & 255u];
            d[2] = table[(code >> 16) & 255u];
        } else {
            d[0] = l0->pixels[4 * i], d[1] = l0->pixels[4 * i + 1], d[2] = l0->pixels[4 * i + 2];
        }
        d[3] = l0->pixels[4 * i + 3];
    }
    for (int k = 1; k < t->num_levels; k++) {
        int sw = t->levels[k - 1]->width, sh = t->levels[k - 1]->height;
        int w = t->levels[k]->width, h = t->levels[k]->height;
        const float *src = chain + t->mip_offset[k - 1];
        float *dst = chain + t->mip_offset[k];
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++) {
                int x0 = 2 * x < sw ? 2 * x : sw - 1, y0 = 2 * y < sh ? 2 * y : sh - 1;
                int x1 = x0 + 1 < sw ? x0 + 1 : x0, y1 = y0 + 1 < sh ? y0 + 1 : y0;
                const float *a = src + 4 * ((size_t)y0 * sw + x0);
                const float *b = src + 4 * ((size_t)y0 * sw + x1);
                const float *c = src + 4 * ((size_t)y1 * sw + x0);
                const float *e = src + 4 * ((size_t)y1 * sw + x1);
                float *d = dst + 4 * ((size_t)y * w + x);
                for (int ch = 0; ch < 4; ch++) d[ch] = 0.25f * ((a[ch] + b[ch]) + (c[ch] + e[ch]));
            }
    }
    t->mip_chain = chain;
    return MESO_OK;
}

meso_result meso_texture_create(meso_context *ctx, const meso_image *image, meso_wrap wrap,
                                bool build_mips, meso_texture **out_texture) {
    *out_texture = NULL;
    meso_texture *t = calloc(1, sizeof(*t));
    if (!t) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "texture: out of memory");
    t->wrap = wrap == MESO_WRAP_DEFAULT ? MESO_WRAP_REPEAT : wrap;
    meso_result r = meso_image_create(ctx, image->width, image->height, 4, &t->levels[0]);
    if (r != MESO_OK) goto fail;
    to_rgba(image, t->levels[0]);
    t->num_levels = 1;
    while (build_mips && t->num_levels < MESO_TEXTURE_MAX_LEVELS) {
        const meso_image *prev = t->levels[t->num_levels - 1];
        if (prev->width == 1 && prev->height == 1) break;
        int w = prev->width > 1 ? prev->width / 2 : 1, h = prev->height > 1 ? prev->height / 2 : 1;
        r = meso_image_create(ctx, w, h, 4, &t->levels[t->num_levels]);
        if (r != MESO_OK) goto fail;
        downsample(prev, t->levels[t->num_levels]);
        t->num_levels++;
    }
    if ((r = build_mip_chain(ctx, t)) != MESO_OK) goto fail;
    *out_texture = t;
    return MESO_OK;
fail:
    meso_texture_destroy(t);
    return r;
}

void meso_texture_destroy(meso_texture *t) {
    if (!t) return;
    for (int i = 0; i < MESO_TEXTURE_MAX_LEVELS; i++) meso_image_destroy(t->levels[i]);
    free(t->srgb8);
    free(t->mip_chain);
    free(t);
}

static float srgb8_values[256];
static pthread_once_t srgb8_once = PTHREAD_ONCE_INIT;

static void srgb8_fill(void) {
    /* the PNG reader's 8-bit scale (core_png.c), so a decoded PNG code comes back exactly */
    for (int k = 0; k < 256; k++) srgb8_values[k] = meso_srgb_to_linear((float)k * (1.0f / 255.0f));
}

const float *meso_srgb8_table(void) {
    pthread_once(&srgb8_once, srgb8_fill);
    return srgb8_values;
}

/* The code whose decoded value is nearest `linear` (in [0, 1]): the rounded encode and its two
 * neighbours, the encode's float rounding being the only doubt. */
static uint32_t srgb8_encode(const float *table, float linear) {
    long k = lrintf(meso_linear_to_srgb(linear) * 255.0f);
    k = k < 0 ? 0 : k > 255 ? 255 : k;
    long best = k;
    for (long c = k - 1; c <= k + 1; c++) {
        if (c < 0 || c > 255) continue;
        if (fabsf(table[c] - linear) < fabsf(table[best] - linear)) best = c;
    }
    return (uint32_t)best;
}

meso_result meso_texture_add_srgb8(meso_context *ctx, meso_texture *t) {
    const meso_image *level = t->levels[0];
    size_t n = (size_t)level->width * (size_t)level->height;
    for (size_t i = 0; i < n; i++) {
        for (int c = 0; c < 3; c++) {
            float v = level->pixels[4 * i + (size_t)c];
            if (!(v >= 0.0f && v <= 1.0f)) return MESO_OK; /* HDR or NaN: stays float */
        }
    }
    uint32_t *codes = malloc(n * sizeof(*codes));
    if (!codes) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "texture: out of memory");
    const float *table = meso_srgb8_table();
    for (size_t i = 0; i < n; i++) {
        const float *p = level->pixels + 4 * i;
        codes[i] = srgb8_encode(table, p[0]) | srgb8_encode(table, p[1]) << 8 |
                   srgb8_encode(table, p[2]) << 16;
    }
    free(t->srgb8);
    t->srgb8 = codes;
    /* the chain's level 0 becomes the decoded codes the unfiltered lookup now reads */
    return t->mip_chain ? build_mip_chain(ctx, t) : MESO_OK;
}

static inline int wrap_index(int i, int n, meso_wrap wrap) {
    if (wrap == MESO_WRAP_CLAMP) return i < 0 ? 0 : (i >= n ? n - 1 : i);
    i %= n;
    return i < 0 ? i + n : i;
}

static meso_vec4 fetch(const meso_image *level, int i, int j, meso_wrap wrap) {
    const float *p =
        meso_image_at(level, wrap_index(i, level->width, wrap), wrap_index(j, level->height, wrap));
    return (meso_vec4){p[0], p[1], p[2], p[3]};
}

static meso_vec4 lerp4(meso_vec4 a, meso_vec4 b, float t) {
    return (meso_vec4){a.x + (b.x - a.x) * t, a.y + (b.y - a.y) * t, a.z + (b.z - a.z) * t,
                       a.w + (b.w - a.w) * t};
}

static meso_vec4 sample_level(const meso_image *level, meso_vec2 uv, meso_wrap wrap, bool nearest) {
    /* Texel centres: u = (i + 0.5) / W, v = 1 - (j + 0.5) / H (docs/design.md). */
    float x = uv.x * (float)level->width - 0.5f;
    float y = (1.0f - uv.y) * (float)level->height - 0.5f;
    if (nearest) return fetch(level, (int)floorf(x + 0.5f), (int)floorf(y + 0.5f), wrap);
    float fx = floorf(x), fy = floorf(y);
    int i = (int)fx, j = (int)fy;
    float tx = x - fx, ty = y - fy;
    meso_vec4 top = lerp4(fetch(level, i, j, wrap), fetch(level, i + 1, j, wrap), tx);
    meso_vec4 bottom = lerp4(fetch(level, i, j + 1, wrap), fetch(level, i + 1, j + 1, wrap), tx);
    return lerp4(top, bottom, ty);
}

meso_vec4 meso_texture_sample(const meso_texture *t, meso_vec2 uv, float lod, meso_filter filter) {
    if (!isfinite(uv.x) || !isfinite(uv.y)) return (meso_vec4){0, 0, 0, 0};
    /* Keep coordinates small so float texel arithmetic stays exact for tiled lookups. */
    if (t->wrap != MESO_WRAP_CLAMP) {
        uv.x -= floorf(uv.x);
        uv.y -= floorf(uv.y);
    }
    if (filter == MESO_FILTER_NEAREST) return sample_level(t->levels[0], uv, t->wrap, true);
    if (filter != MESO_FILTER_TRILINEAR || t->num_levels == 1)
        return sample_level(t->levels[0], uv, t->wrap, false);
    float max_lod = (float)(t->num_levels - 1);
    lod = lod < 0.0f ? 0.0f : (lod > max_lod ? max_lod : lod);
    int level = (int)floorf(lod);
    float blend = lod - (float)level;
    meso_vec4 a = sample_level(t->levels[level], uv, t->wrap, false);
    if (blend == 0.0f || level + 1 >= t->num_levels) return a;
    return lerp4(a, sample_level(t->levels[level + 1], uv, t->wrap, false), blend);
}
