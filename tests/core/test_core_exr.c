/* OpenEXR output: images written by meso_image_save(".exr") and read back
 * with the OpenEXR library's own reader (its RGBA interface, not meso's code) hold the same
 * linear values within half precision, unclamped, in the channels their layout names. */
#include <ImfCRgbaFile.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"

/* A value, its neighbours in the image differ: a ramp with HDR, negative and tiny values. */
static float test_value(int x, int y, int c) {
    float base = (float)(x * 7 + y * 13 + c * 29) / 97.0f;
    if ((x + y) % 5 == 0) return base * 40.0f;  /* above 1: not clamped */
    if ((x + y) % 7 == 0) return -base;         /* negative */
    if ((x + y) % 11 == 0) return base * 1e-5f; /* near half's subnormals */
    return base;
}

static meso_image *make_image(meso_context *ctx, int width, int height, int channels) {
    meso_image *image = NULL;
    assert_int_equal(meso_image_create(ctx, width, height, channels, &image), MESO_OK);
    for (int y = 0; y < height; y++)
        for (int x = 0; x < width; x++)
            for (int c = 0; c < channels; c++) meso_image_at(image, x, y)[c] = test_value(x, y, c);
    return image;
}

/* |a - b| within half's rounding: half a unit in the last place (11 significant bits), or
 * half the smallest subnormal. */
static void assert_half_close(float expected, float actual, int x, int y, int c) {
    float tolerance = fabsf(expected) * 0x1p-11f + 0x1p-25f;
    if (!(fabsf(expected - actual) <= tolerance))
        fail_msg("(%d, %d) channel %d: wrote %.8g, read %.8g", x, y, c, expected, actual);
}

/* Read with the library: RGBA halves, data window from (0, 0). */
static ImfRgba *read_exr(const char *path, int *out_width, int *out_height, int *out_channels) {
    ImfInputFile *in = ImfOpenInputFile(path);
    if (!in) fail_msg("OpenEXR cannot read %s: %s", path, ImfErrorMessage());
    int x0, y0, x1, y1;
    ImfHeaderDataWindow(ImfInputHeader(in), &x0, &y0, &x1, &y1);
    assert_int_equal(x0, 0);
    assert_int_equal(y0, 0);
    int width = x1 + 1, height = y1 + 1;
    ImfRgba *pixels = calloc((size_t)width * (size_t)height, sizeof(ImfRgba));
    assert_non_null(pixels);
    assert_true(ImfInputSetFrameBuffer(in, pixels, 1, (size_t)width));
    assert_true(ImfInputReadPixels(in, 0, height - 1));
    *out_channels = ImfInputChannels(in);
    ImfCloseInputFile(in);
    *out_width = width;
    *out_height = height;
    return pixels;
}

static void check_round_trip(int channels, int expected_mask, const char *name) {
    meso_context *ctx = test_context(1);
    /* taller than one ZIP chunk (16 lines) and not a multiple of it */
    int width = 37, height = 41;
    meso_image *image = make_image(ctx, width, height, channels);
    const char *path = test_path(test_temp_dir(), name);
    assert_int_equal(meso_image_save(ctx, image, path, NULL), MESO_OK);
    int w, h, mask;
    ImfRgba *pixels = read_exr(path, &w, &h, &mask);
    assert_int_equal(w, width);
    assert_int_equal(h, height);
    assert_int_equal(mask, expected_mask);
    for (int y = 0; y < height; y++)
        for (int x = 0; x < width; x++) {
            const ImfRgba *p = &pixels[(size_t)y * width + x];
            float read[4] = {ImfHalfToFloat(p->r), ImfHalfToFloat(p->g), ImfHalfToFloat(p->b),
                             ImfHalfToFloat(p->a)};
            const float *wrote = meso_image_at(image, x, y);
            if (channels >= 3) {
                for (int c = 0; c < channels; c++) assert_half_close(wrote[c], read[c], x, y, c);
            } else { /* luminance: the RGBA interface spreads Y to R, G and B */
                for (int c = 0; c < 3; c++) assert_half_close(wrote[0], read[c], x, y, c);
                if (channels == 2) assert_half_close(wrote[1], read[3], x, y, 3);
            }
        }
    free(pixels);
    meso_image_destroy(image);
    meso_context_destroy(ctx);
}

static void test_rgb_reads_back_within_half_precision(void **state) {
    (void)state;
    check_round_trip(3, IMF_WRITE_RGB, "rgb.exr");
}
static void test_rgba_reads_back_within_half_precision(void **state) {
    (void)state;
    check_round_trip(4, IMF_WRITE_RGBA, "rgba.EXR"); /* the extension in any case */
}
static void test_grey_is_written_as_luminance(void **state) {
    (void)state;
    check_round_trip(1, IMF_WRITE_Y, "grey.exr");
    check_round_trip(2, IMF_WRITE_YA, "grey-alpha.exr");
}

/* Only the extension chooses: other paths stay PNG, and save_png never writes EXR. */
static void test_the_extension_chooses_the_format(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_image *image = make_image(ctx, 8, 8, 3);
    const char *dir = test_temp_dir();
    char exr[1100], png[1100], png_named_exr[1100];
    snprintf(exr, sizeof exr, "%s/format.exr", dir);
    snprintf(png, sizeof png, "%s/format.png", dir);
    snprintf(png_named_exr, sizeof png_named_exr, "%s/png-anyway.exr", dir);
    assert_int_equal(meso_image_save(ctx, image, exr, NULL), MESO_OK);
    assert_int_equal(meso_image_save(ctx, image, png, NULL), MESO_OK);
    assert_int_equal(meso_image_save_png(ctx, image, png_named_exr, NULL), MESO_OK);
    size_t size;
    char *bytes = test_read_file(exr, &size);
    assert_true(size > 4 && memcmp(bytes, "\x76\x2f\x31\x01", 4) == 0); /* EXR magic */
    free(bytes);
    bytes = test_read_file(png, &size);
    assert_true(size > 8 && memcmp(bytes, "\x89PNG", 4) == 0);
    free(bytes);
    bytes = test_read_file(png_named_exr, &size);
    assert_true(size > 8 && memcmp(bytes, "\x89PNG", 4) == 0);
    free(bytes);
    assert_true(meso_image_path_is_exr("a/b.Exr"));
    assert_false(meso_image_path_is_exr("exr"));
    assert_false(meso_image_path_is_exr("a.exr.png"));
    meso_image_destroy(image);
    meso_context_destroy(ctx);
}

/* EXR and PNG outputs together are all or none: a missing folder for the second leaves no
 * first. */
static void test_exr_outputs_are_all_or_none(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_image *image = make_image(ctx, 8, 8, 3);
    char first[1100], second[1100];
    snprintf(first, sizeof first, "%s/first.exr", test_temp_dir());
    snprintf(second, sizeof second, "%s/missing-folder/second.png", test_temp_dir());
    remove(first);
    const meso_image *images[2] = {image, image};
    const char *paths[2] = {first, second};
    assert_int_equal(meso_image_save_all(ctx, 2, images, paths, NULL), MESO_ERROR_IO);
    FILE *f = fopen(first, "rb");
    assert_null(f);
    meso_image_destroy(image);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rgb_reads_back_within_half_precision),
        cmocka_unit_test(test_rgba_reads_back_within_half_precision),
        cmocka_unit_test(test_grey_is_written_as_luminance),
        cmocka_unit_test(test_the_extension_chooses_the_format),
        cmocka_unit_test(test_exr_outputs_are_all_or_none),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
