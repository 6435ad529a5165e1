/* PNG files through libpng: 8/16-bit grey, grey+alpha, RGB, RGBA and palette. */
#include <errno.h>
#include <png.h>
#include <setjmp.h>
#include <stdlib.h>
#include <string.h>

#include "core_internal.h"
#include "meso/runtime.h"
#include "meso/image.h"

typedef struct png_error_state {
    meso_context *ctx;
    const char *path;
    char message[256];
} png_error_state;

static void on_png_error(png_structp png, png_const_charp message) {
    png_error_state *state = png_get_error_ptr(png);
    snprintf(state->message, sizeof(state->message), "%s", message);
    png_longjmp(png, 1);
}

static void on_png_warning(png_structp png, png_const_charp message) {
    (void)png;
    (void)message;
}

/* libpng's own stdio writer reports only "Write Error": this one says why (a full disk). */
static void write_to_file(png_structp png, png_bytep data, size_t length) {
    FILE *file = png_get_io_ptr(png);
    errno = 0;
    if (fwrite(data, 1, length, file) != length) png_error(png, strerror(errno ? errno : EIO));
}

static void flush_file(png_structp png) { fflush((FILE *)png_get_io_ptr(png)); }

static uint32_t read_u32(const unsigned char *p) {
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

meso_result meso_image_load_png(meso_context *ctx, const char *path, meso_image **out_image) {
    *out_image = NULL;
    FILE *file = NULL;
    meso_result opened = meso_file_open_read(ctx, path, &file);
    if (opened != MESO_OK) return opened;
    unsigned char signature[8];
    if (fread(signature, 1, 8, file) != 8 || png_sig_cmp(signature, 0, 8) != 0) {
        fclose(file);
        return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: not a PNG file", path);
    }
    /* The IHDR must come first; its declared size is checked here, before libpng reads on to
     * the first IDAT, so a huge declaration is refused even in a file cut after its header. */
    unsigned char ihdr[16];
    if (fread(ihdr, 1, 16, file) != 16 || memcmp(ihdr + 4, "IHDR", 4) != 0) {
        fclose(file);
        return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: truncated PNG (no IHDR chunk)", path);
    }
    uint32_t declared_width = read_u32(ihdr + 8), declared_height = read_u32(ihdr + 12);
    if (declared_width > MESO_IMAGE_MAX_SIDE || declared_height > MESO_IMAGE_MAX_SIDE ||
        (uint64_t)declared_width * declared_height > MESO_IMAGE_MAX_PIXELS) {
        fclose(file);
        return meso_log_error(ctx, MESO_ERROR_LIMIT,
                              "%s: %ux%u exceeds the limit of %d a side and %u pixels", path,
                              (unsigned)declared_width, (unsigned)declared_height,
                              MESO_IMAGE_MAX_SIDE, MESO_IMAGE_MAX_PIXELS);
    }
    /* The decoded image (floats) and libpng's rows (all of them when interlaced, 16 bits a
     * value at most) within the memory budget, from the header, before libpng reads on: a PNG
     * of 82 KB can declare 8192 x 8192 pixels, 768 MiB decoded. The channels after expansion
     * follow the colour type (a palette may gain alpha: 4). */
    unsigned char fields[5]; /* bit depth, colour type, compression, filter, interlace */
    if (fread(fields, 1, 5, file) != 5) {
        fclose(file);
        return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: truncated PNG (IHDR)", path);
    }
    static const uint64_t channels_of_type[7] = {1, 0, 3, 4, 2, 0, 4};
    uint64_t declared_channels =
        fields[1] < 7 && channels_of_type[fields[1]] ? channels_of_type[fields[1]] : 4;
    uint64_t value_bytes = fields[0] == 16 ? 2 : 1, rows_held = fields[4] ? declared_height : 1;
    meso_result budget = meso_memory_check(
        ctx, path,
        declared_channels * ((uint64_t)declared_width * declared_height * sizeof(float) +
                             (uint64_t)declared_width * rows_held * value_bytes));
    if (budget != MESO_OK) {
        fclose(file);
        return budget;
    }
    fseek(file, 8, SEEK_SET);
    png_error_state state = {ctx, path, ""};
    png_structp png =
        png_create_read_struct(PNG_LIBPNG_VER_STRING, &state, on_png_error, on_png_warning);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    /* volatile: assigned between setjmp and a possible longjmp */
    meso_image *volatile image = NULL;
    unsigned char *volatile row = NULL;
    png_bytep *volatile rows = NULL;
    meso_result r = MESO_OK;
    if (!png || !info) {
        r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", path);
        goto done;
    }
    if (setjmp(png_jmpbuf(png))) {
        r = meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: corrupt or truncated PNG (%s)", path,
                           state.message);
        goto done;
    }
    png_init_io(png, file);
    png_set_sig_bytes(png, 8);
    png_read_info(png, info);
    png_uint_32 width = png_get_image_width(png, info), height = png_get_image_height(png, info);
    /* The declared size is checked before any pixel memory exists. */
    if (width > MESO_IMAGE_MAX_SIDE || height > MESO_IMAGE_MAX_SIDE ||
        (uint64_t)width * height > MESO_IMAGE_MAX_PIXELS) {
        r = meso_log_error(
            ctx, MESO_ERROR_LIMIT, "%s: %ux%u exceeds the limit of %d a side and %u pixels", path,
            (unsigned)width, (unsigned)height, MESO_IMAGE_MAX_SIDE, MESO_IMAGE_MAX_PIXELS);
        goto done;
    }
    int color_type = png_get_color_type(png, info);
    int bit_depth = png_get_bit_depth(png, info);
    if (color_type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
    if (color_type == PNG_COLOR_TYPE_GRAY && bit_depth < 8) png_set_expand_gray_1_2_4_to_8(png);
    if (png_get_valid(png, info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(png);
    png_set_interlace_handling(png);
    png_read_update_info(png, info);
    int channels = png_get_channels(png, info);
    bit_depth = png_get_bit_depth(png, info);
    size_t row_bytes = png_get_rowbytes(png, info);
    if (channels < 1 || channels > 4 || (bit_depth != 8 && bit_depth != 16)) {
        r = meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: unsupported PNG layout", path);
        goto done;
    }
    bool interlaced = png_get_interlace_type(png, info) != PNG_INTERLACE_NONE;
    meso_image *created = NULL;
    r = meso_image_create(ctx, (int)width, (int)height, channels, &created);
    if (r != MESO_OK) goto done;
    image = created;
    /* Interlaced images need every row in memory at once; others are read row by row. */
    row = malloc(row_bytes * (interlaced ? height : 1));
    if (!row) {
        r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", path);
        goto done;
    }
    if (interlaced) {
        rows = malloc(sizeof(png_bytep) * height);
        if (!rows) {
            r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", path);
            goto done;
        }
        for (png_uint_32 y = 0; y < height; y++) rows[y] = row + row_bytes * y;
        png_read_image(png, rows);
    }
    size_t values = (size_t)width * (size_t)channels;
    for (png_uint_32 y = 0; y < height; y++) {
        const unsigned char *src = interlaced ? row + row_bytes * y : row;
        if (!interlaced) png_read_row(png, row, NULL);
        float *dst = image->pixels + (size_t)y * values;
        if (bit_depth == 16)
            for (size_t i = 0; i < values; i++)
                dst[i] = (float)((src[2 * i] << 8) | src[2 * i + 1]) * (1.0f / 65535.0f);
        else
            for (size_t i = 0; i < values; i++) dst[i] = (float)src[i] * (1.0f / 255.0f);
    }
    png_read_end(png, NULL);
done:
    png_destroy_read_struct(png ? &png : NULL, info ? &info : NULL, NULL);
    fclose(file);
    free(row);
    free(rows);
    if (r != MESO_OK) {
        meso_image_destroy(image);
        return r;
    }
    *out_image = image;
    return MESO_OK;
}

static unsigned quantise(float value, bool srgb, unsigned max) {
    if (!(value > 0.0f)) return 0; /* also NaN */
    if (srgb) value = meso_linear_to_srgb(value);
    if (value >= 1.0f) return max;
    return (unsigned)(value * (float)max + 0.5f);
}

meso_result meso_image_write_png(meso_context *ctx, const meso_image *image, FILE *file,
                                 const char *path, const meso_png_desc *desc) {
    meso_png_desc d = desc ? *desc : (meso_png_desc){0};
    int bit_depth = d.bit_depth == 16 ? 16 : 8;
    bool srgb = d.encoding != MESO_ENCODING_LINEAR;
    int channels = image->channels;
    int color_channels = channels == 2 || channels == 4 ? channels - 1 : channels;
    static const int color_types[] = {0, PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA,
                                      PNG_COLOR_TYPE_RGB, PNG_COLOR_TYPE_RGB_ALPHA};
    meso_result r = MESO_OK;
    png_error_state state = {ctx, path, ""};
    png_structp png =
        png_create_write_struct(PNG_LIBPNG_VER_STRING, &state, on_png_error, on_png_warning);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    size_t row_bytes = (size_t)image->width * (size_t)channels * (size_t)(bit_depth / 8);
    unsigned char *volatile row = malloc(row_bytes);
    if (!png || !info || !row) {
        r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", path);
        goto fail;
    }
    if (setjmp(png_jmpbuf(png))) {
        r = meso_log_error(ctx, MESO_ERROR_WRITE, "%s: cannot write: %s", path, state.message);
        goto fail;
    }
    png_set_write_fn(png, file, write_to_file, flush_file);
    png_set_IHDR(png, info, (png_uint_32)image->width, (png_uint_32)image->height, bit_depth,
                 color_types[channels], PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    if (srgb) png_set_sRGB(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
    png_write_info(png, info);
    unsigned max = bit_depth == 16 ? 65535u : 255u;
    for (int y = 0; y < image->height; y++) {
        const float *src = meso_image_at(image, 0, y);
        for (int x = 0; x < image->width; x++)
            for (int c = 0; c < channels; c++) {
                size_t i = (size_t)x * (size_t)channels + (size_t)c;
                unsigned q = quantise(src[i], srgb && c < color_channels, max);
                if (bit_depth == 16) {
                    row[2 * i] = (unsigned char)(q >> 8);
                    row[2 * i + 1] = (unsigned char)(q & 0xff);
                } else {
                    row[i] = (unsigned char)q;
                }
            }
        png_write_row(png, row);
    }
    png_write_end(png, NULL);
    png_destroy_write_struct(&png, &info);
    free(row);
    return MESO_OK;
fail:
    png_destroy_write_struct(png ? &png : NULL, info ? &info : NULL);
    free(row);
    return r;
}

meso_result meso_image_save_png(meso_context *ctx, const meso_image *image, const char *path,
                                const meso_png_desc *desc) {
    meso_atomic_file out;
    meso_result r = meso_atomic_file_open(ctx, path, &out);
    if (r != MESO_OK) return r;
    r = meso_image_write_png(ctx, image, out.file, path, desc);
    if (r != MESO_OK) {
        meso_atomic_file_abort(&out);
        return r;
    }
    return meso_atomic_file_commit(ctx, &out);
}

/* save_png_all and save_all: PNG always, or the format the path's extension names. */
static meso_result save_all(meso_context *ctx, size_t count, const meso_image *const *images,
                            const char *const *paths, const meso_png_desc *descs,
                            bool format_from_extension) {
    if (count > MESO_PNG_SAVE_ALL_MAX)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: more than %d files at once",
                              count ? paths[0] : "png", MESO_PNG_SAVE_ALL_MAX);
    meso_atomic_file files[MESO_PNG_SAVE_ALL_MAX] = {{0}};
    meso_result r = MESO_OK;
    /* Every file is written completely, flushed and synced under its temporary name before
     * any is renamed (one group, unless the caller's group holds them already), so a failure
     * (a missing folder, a full disk) leaves none of them changed. */
    bool group = meso_atomic_group_begin(ctx);
    for (size_t i = 0; i < count && r == MESO_OK; i++) {
        r = meso_atomic_file_open(ctx, paths[i], &files[i]);
        if (r != MESO_OK) break;
        if (format_from_extension && meso_image_path_is_exr(paths[i]))
            r = meso_image_write_exr(ctx, images[i], files[i].file, paths[i]);
        else
            r = meso_image_write_png(ctx, images[i], files[i].file, paths[i],
                                     descs ? &descs[i] : NULL);
        if (r == MESO_OK) r = meso_atomic_file_commit(ctx, &files[i]);
    }
    if (r != MESO_OK)
        for (size_t i = 0; i < count; i++) meso_atomic_file_abort(&files[i]); /* zeroed: no-op */
    if (group) {
        meso_result published = meso_atomic_group_end(ctx, r == MESO_OK);
        if (r == MESO_OK) r = published;
    }
    return r;
}

meso_result meso_image_save_png_all(meso_context *ctx, size_t count,
                                    const meso_image *const *images, const char *const *paths,
                                    const meso_png_desc *descs) {
    return save_all(ctx, count, images, paths, descs, false);
}

meso_result meso_image_save_all(meso_context *ctx, size_t count, const meso_image *const *images,
                                const char *const *paths, const meso_png_desc *descs) {
    return save_all(ctx, count, images, paths, descs, true);
}

meso_result meso_image_save(meso_context *ctx, const meso_image *image, const char *path,
                            const meso_png_desc *desc) {
    return save_all(ctx, 1, &image, &path, desc, true);
}
