/* OpenEXR files through the library's C API (OpenEXRCore): linear half-float scanline images,
 * ZIP-compressed, written through a stream callback into a meso_atomic_file so they commit
 * all-or-nothing like the PNGs. Read (environment maps) through the library's RGBA C
 * interface (ImfCRgbaFile.h), which takes scanline and tiled files, any compression, and
 * turns luminance/chroma files into RGB. */
#include <ImfCRgbaFile.h>
#include <errno.h>
#include <openexr.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "core_internal.h"
#include "meso/runtime.h"
#include "meso/image.h"

typedef struct exr_stream {
    int fd;
    int write_errno;   /* the system's reason of a failed write (ENOSPC), or 0 */
    char message[256]; /* the library's last error */
} exr_stream;

/* The stream being written on this thread. The error handler finds it here rather than through
 * exr_get_user_data: the library calls the handler while it holds the context's lock (a failed
 * write inside exr_write_header), and exr_get_user_data takes that lock again, which hung a
 * write to a full disk forever. A handler must not call back into the library. */
static _Thread_local exr_stream *current_stream;

static void on_exr_error(exr_const_context_t exr, exr_result_t code, const char *message) {
    (void)exr;
    exr_stream *stream = current_stream;
    if (stream && !stream->message[0])
        snprintf(stream->message, sizeof(stream->message), "%s",
                 message ? message : exr_get_default_error_message(code));
}

/* The library writes the header, the chunks and finally the offset table at given offsets. */
static int64_t write_at(exr_const_context_t exr, void *user, const void *buffer, uint64_t size,
                        uint64_t offset, exr_stream_error_func_ptr_t error) {
    exr_stream *stream = user;
    const unsigned char *bytes = buffer;
    uint64_t done = 0;
    while (done < size) {
        ssize_t n = pwrite(stream->fd, bytes + done, size - done, (off_t)(offset + done));
        if (n <= 0) {
            stream->write_errno = n < 0 ? errno : ENOSPC;
            error(exr, EXR_ERR_WRITE_IO, "%s", strerror(stream->write_errno));
            return -1;
        }
        done += (uint64_t)n;
    }
    return (int64_t)done;
}

/* EXR's channel names for 1-4 channels: luminance, luminance + alpha, RGB, RGBA. */
static const char *const channel_names[5][4] = {
    {NULL}, {"Y"}, {"Y", "A"}, {"R", "G", "B"}, {"R", "G", "B", "A"}};

/* The one OpenEXR encoder: num_channels interleaved float channels ([y][x][c], row 0 at the
 * top) named names[c], stored as halves or floats, written to `file` from its start. */
static meso_result write_exr_channels(meso_context *ctx, FILE *file, const char *path, int width,
                                      int height, int num_channels, const char *const *names,
                                      const float *pixels, bool half) {
    size_t element = half ? sizeof(uint16_t) : sizeof(float);
    exr_stream stream = {.fd = fileno(file)};
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.user_data = &stream;
    init.write_fn = write_at;
    init.error_handler_fn = on_exr_error;
    exr_context_t exr = NULL;
    exr_encode_pipeline_t encoder = EXR_ENCODE_PIPELINE_INITIALIZER;
    bool encoder_started = false;
    int32_t lines_per_chunk = 0;
    /* one chunk of rows in the file's type, interleaved as the pixels are */
    unsigned char *chunk_values = NULL;
    int part = 0;
    exr_stream *outer_stream = current_stream;
    current_stream = &stream;
    exr_result_t e = exr_start_write(&exr, path, EXR_WRITE_FILE_DIRECTLY, &init);
    if (e == EXR_ERR_SUCCESS) e = exr_add_part(exr, "", EXR_STORAGE_SCANLINE, &part);
    if (e == EXR_ERR_SUCCESS)
        e = exr_initialize_required_attr_simple(exr, part, width, height, EXR_COMPRESSION_ZIP);
    for (int c = 0; c < num_channels && e == EXR_ERR_SUCCESS; c++)
        e = exr_add_channel(exr, part, names[c], half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT,
                            EXR_PERCEPTUALLY_LINEAR, 1, 1);
    if (e == EXR_ERR_SUCCESS) e = exr_write_header(exr);
    if (e == EXR_ERR_SUCCESS) e = exr_get_scanlines_per_chunk(exr, part, &lines_per_chunk);
    size_t row_values = (size_t)width * (size_t)num_channels;
    if (e == EXR_ERR_SUCCESS) {
        chunk_values = malloc(row_values * (size_t)lines_per_chunk * element);
        if (!chunk_values) e = EXR_ERR_OUT_OF_MEMORY;
    }
    for (int y = 0; y < height && e == EXR_ERR_SUCCESS; y += lines_per_chunk) {
        int lines = height - y < lines_per_chunk ? height - y : lines_per_chunk;
        const float *src = pixels + (size_t)y * row_values;
        size_t n = row_values * (size_t)lines;
        if (half)
            for (size_t i = 0; i < n; i++)
                ((uint16_t *)chunk_values)[i] = meso_half_from_float(src[i]);
        else
            memcpy(chunk_values, src, n * sizeof(float));
        exr_chunk_info_t chunk;
        e = exr_write_scanline_chunk_info(exr, part, y, &chunk);
        if (e != EXR_ERR_SUCCESS) break;
        e = encoder_started ? exr_encoding_update(exr, part, &chunk, &encoder)
                            : exr_encoding_initialize(exr, part, &chunk, &encoder);
        if (e != EXR_ERR_SUCCESS) break;
        for (int c = 0; c < encoder.channel_count; c++) {
            exr_coding_channel_info_t *channel = &encoder.channels[c];
            /* the library orders channels by name: find each one's place in our pixels */
            int index = 0;
            while (index < num_channels && strcmp(names[index], channel->channel_name)) index++;
            channel->user_data_type = half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT;
            channel->user_bytes_per_element = (int16_t)element;
            channel->user_pixel_stride = (int32_t)((size_t)num_channels * element);
            channel->user_line_stride = (int32_t)(row_values * element);
            channel->encode_from_ptr = chunk_values + (size_t)index * element;
        }
        if (!encoder_started) {
            e = exr_encoding_choose_default_routines(exr, part, &encoder);
            encoder_started = true;
        }
        if (e == EXR_ERR_SUCCESS) e = exr_encoding_run(exr, part, &encoder);
    }
    if (encoder_started) exr_encoding_destroy(exr, &encoder);
    exr_result_t finished = exr ? exr_finish(&exr) : EXR_ERR_SUCCESS; /* writes the offsets */
    if (e == EXR_ERR_SUCCESS) e = finished;
    current_stream = outer_stream;
    free(chunk_values);
    if (stream.write_errno)
        return meso_log_error(ctx, MESO_ERROR_WRITE, "%s: cannot write: %s", path,
                              strerror(stream.write_errno));
    if (e == EXR_ERR_OUT_OF_MEMORY)
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", path);
    if (e != EXR_ERR_SUCCESS)
        return meso_log_error(ctx, MESO_ERROR_WRITE, "%s: cannot write OpenEXR (%s)", path,
                              stream.message[0] ? stream.message
                                                : exr_get_default_error_message(e));
    return MESO_OK;
}

meso_result meso_image_write_exr(meso_context *ctx, const meso_image *image, FILE *file,
                                 const char *path) {
    if (!image || image->channels < 1 || image->channels > 4)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: no image to write", path);
    return write_exr_channels(ctx, file, path, image->width, image->height, image->channels,
                              channel_names[image->channels], meso_image_at(image, 0, 0), true);
}

meso_result meso_exr_write(meso_context *ctx, const char *path, int width, int height,
                           int num_channels, const char *const *names, const float *pixels,
                           bool half) {
    if (width <= 0 || height <= 0 || num_channels <= 0 || num_channels > MESO_EXR_MAX_CHANNELS)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: %d x %d x %d channels", path,
                              width, height, num_channels);
    meso_atomic_file out;
    meso_result r = meso_atomic_file_open(ctx, path, &out);
    if (r != MESO_OK) return r;
    r = write_exr_channels(ctx, out.file, path, width, height, num_channels, names, pixels, half);
    if (r != MESO_OK) {
        meso_atomic_file_abort(&out);
        return r;
    }
    return meso_atomic_file_commit(ctx, &out);
}

bool meso_image_path_is_exr(const char *path) {
    size_t n = path ? strlen(path) : 0;
    return n >= 4 && strcasecmp(path + n - 4, ".exr") == 0;
}

bool meso_file_is_exr(const void *data, size_t size) {
    static const unsigned char magic[4] = {0x76, 0x2f, 0x31, 0x01};
    return data && size >= 4 && memcmp(data, magic, 4) == 0;
}

meso_result meso_image_read_exr_rgb(meso_context *ctx, const char *path, int max_side,
                                    uint64_t max_pixels, meso_image **out_image) {
    *out_image = NULL;
    ImfInputFile *in = ImfOpenInputFile(path);
    if (!in)
        return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: not a readable OpenEXR file (%s)", path,
                              ImfErrorMessage());
    int xmin, ymin, xmax, ymax;
    ImfHeaderDataWindow(ImfInputHeader(in), &xmin, &ymin, &xmax, &ymax);
    int64_t width = (int64_t)xmax - xmin + 1, height = (int64_t)ymax - ymin + 1;
    meso_result r = MESO_OK;
    ImfRgba *rgba = NULL;
    if (width < 1 || height < 1) {
        r = meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: empty data window", path);
        goto done;
    }
    if (width > max_side || height > max_side || (uint64_t)(width * height) > max_pixels) {
        r = meso_log_error(
            ctx, MESO_ERROR_LIMIT, "%s: %lldx%lld exceeds the limit of %d a side and %llu texels",
            path, (long long)width, (long long)height, max_side, (unsigned long long)max_pixels);
        goto done;
    }
    size_t pixels = (size_t)(width * height);
    if ((r = meso_memory_check(ctx, path, (uint64_t)pixels * (sizeof *rgba + 3 * sizeof(float)))))
        goto done;
    rgba = malloc(pixels * sizeof *rgba);
    if (!rgba) {
        r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: %zu texels", path, pixels);
        goto done;
    }
    /* the library addresses pixel (x, y) at base + x + y * width: the base is the buffer moved
     * back by the window's origin (as an address, so that no out-of-range pointer is formed) */
    uintptr_t base = (uintptr_t)rgba - (uintptr_t)(((intptr_t)xmin + (intptr_t)ymin * width) *
                                                   (intptr_t)sizeof *rgba);
    if (!ImfInputSetFrameBuffer(in, (ImfRgba *)base, 1, (size_t)width) ||
        !ImfInputReadPixels(in, ymin, ymax)) {
        r = meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: corrupt OpenEXR data (%s)", path,
                           ImfErrorMessage());
        goto done;
    }
    if ((r = meso_image_create(ctx, (int)width, (int)height, 3, out_image))) goto done;
    float *rgb = (*out_image)->pixels;
    for (size_t i = 0; i < pixels; i++) {
        rgb[3 * i + 0] = ImfHalfToFloat(rgba[i].r);
        rgb[3 * i + 1] = ImfHalfToFloat(rgba[i].g);
        rgb[3 * i + 2] = ImfHalfToFloat(rgba[i].b);
    }
done:
    free(rgba);
    ImfCloseInputFile(in);
    return r;
}
