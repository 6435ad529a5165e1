/* OpenEXR output through the C API of OpenEXR 3.1 (OpenEXRCore, openexr.h): scanline images of
 * any number of named half or float channels, ZIP-compressed, for the baked tables of
 * `meso bake -o` (docs/gpu.md). Written through meso's atomic files: the library's write
 * callback writes into the unnamed temporary file, renamed into place at the end. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <openexr.h>

#include "gl_internal.h"

/* Rows per chunk of ZIP compression (the format's own). */
#define EXR_ZIP_LINES 16

static int64_t write_at(exr_const_context_t ctxt, void *userdata, const void *buffer, uint64_t size,
                        uint64_t offset, exr_stream_error_func_ptr_t error_cb) {
    FILE *file = userdata;
    if (fseeko(file, (off_t)offset, SEEK_SET) != 0 || fwrite(buffer, 1, size, file) != size) {
        error_cb(ctxt, EXR_ERR_WRITE_IO, "write failed");
        return -1;
    }
    return (int64_t)size;
}

meso_result meso_exr_write(meso_context *ctx, const char *path, int width, int height,
                           int num_channels, const char *const *names, const float *pixels,
                           bool half) {
    if (width <= 0 || height <= 0 || num_channels <= 0 || num_channels > 1024)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: %d x %d x %d channels", path,
                              width, height, num_channels);
    size_t count = (size_t)width * height * num_channels;
    /* planar copies in the file's type: channel c's plane at c * width * height */
    size_t element = half ? sizeof(uint16_t) : sizeof(float);
    unsigned char *planes = malloc(count * element);
    if (!planes) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", path);
    for (int c = 0; c < num_channels; c++)
        for (size_t i = 0; i < (size_t)width * height; i++) {
            float v = pixels[i * num_channels + c];
            unsigned char *at = planes + ((size_t)c * width * height + i) * element;
            if (half) {
                _Float16 h = (_Float16)v;
                memcpy(at, &h, sizeof h);
            } else {
                memcpy(at, &v, sizeof v);
            }
        }
    meso_atomic_file out;
    meso_result r = meso_atomic_file_open(ctx, path, &out);
    if (r != MESO_OK) {
        free(planes);
        return r;
    }
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.user_data = out.file;
    init.write_fn = write_at;
    exr_context_t exr = NULL;
    int part = 0;
    exr_result_t e = exr_start_write(&exr, path, EXR_WRITE_FILE_DIRECTLY, &init);
    if (e == EXR_ERR_SUCCESS) e = exr_add_part(exr, "meso", EXR_STORAGE_SCANLINE, &part);
    if (e == EXR_ERR_SUCCESS)
        e = exr_initialize_required_attr_simple(exr, part, width, height, EXR_COMPRESSION_ZIP);
    for (int c = 0; c < num_channels && e == EXR_ERR_SUCCESS; c++)
        e = exr_add_channel(exr, part, names[c], half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT,
                            EXR_PERCEPTUALLY_LINEAR, 1, 1);
    if (e == EXR_ERR_SUCCESS) e = exr_write_header(exr);
    for (int y = 0; y < height && e == EXR_ERR_SUCCESS; y += EXR_ZIP_LINES) {
        exr_chunk_info_t chunk;
        exr_encode_pipeline_t encoder;
        e = exr_write_scanline_chunk_info(exr, part, y, &chunk);
        if (e != EXR_ERR_SUCCESS) break;
        e = exr_encoding_initialize(exr, part, &chunk, &encoder);
        if (e != EXR_ERR_SUCCESS) break;
        /* the library sorts channels by name: find each one's plane */
        for (int k = 0; k < encoder.channel_count; k++) {
            int c = 0;
            while (c < num_channels && strcmp(names[c], encoder.channels[k].channel_name) != 0) c++;
            exr_coding_channel_info_t *info = &encoder.channels[k];
            info->user_bytes_per_element = (int16_t)element;
            info->user_data_type = half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT;
            info->user_pixel_stride = (int32_t)element;
            info->user_line_stride = (int32_t)(element * (size_t)width);
            info->encode_from_ptr =
                planes + ((size_t)c * width * height + (size_t)chunk.start_y * width) * element;
        }
        e = exr_encoding_choose_default_routines(exr, part, &encoder);
        if (e == EXR_ERR_SUCCESS) e = exr_encoding_run(exr, part, &encoder);
        exr_encoding_destroy(exr, &encoder);
    }
    exr_result_t finished = exr ? exr_finish(&exr) : EXR_ERR_SUCCESS;
    free(planes);
    if (e == EXR_ERR_SUCCESS) e = finished;
    if (e != EXR_ERR_SUCCESS) {
        meso_atomic_file_abort(&out);
        return meso_log_error(ctx, MESO_ERROR_IO, "%s: OpenEXR: %s", path,
                              exr_get_default_error_message(e));
    }
    return meso_atomic_file_commit(ctx, &out);
}
