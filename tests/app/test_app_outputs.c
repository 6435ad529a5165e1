/* Output formats of renders and difference images: `-o X.exr` writes
 * OpenEXR (half floats, linear, read back here with the OpenEXR library), `--bits 16` a 16-bit
 * PNG; both hold the same linear values as each other within their precision. Before, every
 * output was an 8-bit PNG whatever its name, and --bits did not exist. */
#include <ImfCRgbaFile.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"

#define BRICKS MESO_SOURCE_DIR "/examples/bricks-plane.json"

static void run_ok(const char *arguments) {
    const char *err = NULL;
    int status = test_run_meso(arguments, &err);
    if (status != 0) fail_msg("meso %s: status %d, stderr: %s", arguments, status, err);
}

/* The EXR's R, G, B as floats, row-major. */
static float *read_exr_rgb(const char *path, int width, int height) {
    ImfInputFile *in = ImfOpenInputFile(path);
    if (!in) fail_msg("OpenEXR cannot read %s: %s", path, ImfErrorMessage());
    int x0, y0, x1, y1;
    ImfHeaderDataWindow(ImfInputHeader(in), &x0, &y0, &x1, &y1);
    assert_int_equal(x1 - x0 + 1, width);
    assert_int_equal(y1 - y0 + 1, height);
    assert_int_equal(ImfInputChannels(in), IMF_WRITE_RGB);
    ImfRgba *pixels = calloc((size_t)width * height, sizeof(ImfRgba));
    assert_true(ImfInputSetFrameBuffer(in, pixels, 1, (size_t)width));
    assert_true(ImfInputReadPixels(in, 0, height - 1));
    ImfCloseInputFile(in);
    float *rgb = malloc(sizeof(float) * 3 * (size_t)width * height);
    for (size_t i = 0; i < (size_t)width * height; i++) {
        rgb[3 * i] = ImfHalfToFloat(pixels[i].r);
        rgb[3 * i + 1] = ImfHalfToFloat(pixels[i].g);
        rgb[3 * i + 2] = ImfHalfToFloat(pixels[i].b);
    }
    free(pixels);
    return rgb;
}

/* The PNG's bit depth: IHDR byte 24 of the file. */
static int png_bit_depth(const char *path) {
    size_t size;
    unsigned char *bytes = (unsigned char *)test_read_file(path, &size);
    assert_true(size > 25);
    int depth = bytes[24];
    free(bytes);
    return depth;
}

/* The 16-bit linear PNG and the EXR agree: PNG = clamp(EXR) within half's rounding plus half a
 * 16-bit step; and at least min_off_grid values lie between 8-bit steps (not an 8-bit image in
 * disguise). */
static void check_png16_matches_exr(const char *png_path, const char *exr_path, int width,
                                    int height, int min_off_grid) {
    assert_int_equal(png_bit_depth(png_path), 16);
    meso_context *ctx = test_context(1);
    meso_image *png = NULL;
    assert_int_equal(meso_image_load_png(ctx, png_path, &png), MESO_OK);
    assert_int_equal(png->width, width);
    assert_int_equal(png->channels, 3);
    float *exr = read_exr_rgb(exr_path, width, height);
    int off_8bit_grid = 0;
    for (size_t i = 0; i < (size_t)width * height * 3; i++) {
        float e = exr[i], p = png->pixels[i];
        float clamped = e < 0.0f ? 0.0f : (e > 1.0f ? 1.0f : e);
        float tolerance = fabsf(e) * 0x1p-11f + 0.5f / 65535.0f + 1e-7f;
        if (!(fabsf(clamped - p) <= tolerance))
            fail_msg("value %zu: EXR %.7g, 16-bit PNG %.7g", i, e, p);
        float steps = p * 255.0f;
        if (fabsf(steps - roundf(steps)) > 0.01f) off_8bit_grid++;
    }
    if (off_8bit_grid < min_off_grid)
        fail_msg("%d values between 8-bit steps, expected %d", off_8bit_grid, min_off_grid);
    free(exr);
    meso_image_destroy(png);
    meso_context_destroy(ctx);
}

static void test_render_writes_exr_and_16_bit_png(void **state) {
    (void)state;
    const char *dir = test_temp_dir();
    char exr[1100], png[1100], args[4096];
    snprintf(exr, sizeof exr, "%s/render.exr", dir);
    snprintf(png, sizeof png, "%s/render16.png", dir);
    snprintf(args, sizeof args, "render %s -o %s --size 48x40 --technique bump --quiet", BRICKS,
             exr);
    run_ok(args);
    snprintf(args, sizeof args,
             "render %s -o %s --size 48x40 --technique bump --linear --bits 16 --quiet", BRICKS,
             png);
    run_ok(args);
    check_png16_matches_exr(png, exr, 48, 40, 48 * 40 / 4);
}

static void test_compare_writes_the_difference_as_exr_and_16_bit_png(void **state) {
    (void)state;
    const char *dir = test_temp_dir();
    char a[1100], b[1100], exr[1100], png[1100], args[4096];
    snprintf(a, sizeof a, "%s/a.png", dir);
    snprintf(b, sizeof b, "%s/b.png", dir);
    snprintf(exr, sizeof exr, "%s/diff.exr", dir);
    snprintf(png, sizeof png, "%s/diff16.png", dir);
    snprintf(args, sizeof args, "render %s -o %s --size 40x40 --technique flat --quiet", BRICKS, a);
    run_ok(args);
    snprintf(args, sizeof args, "render %s -o %s --size 40x40 --technique bump --quiet", BRICKS, b);
    run_ok(args);
    snprintf(args, sizeof args, "compare %s %s -o %s --diff-scale 0.3 --quiet", a, b, exr);
    run_ok(args);
    snprintf(args, sizeof args, "compare %s %s -o %s --diff-scale 0.3 --bits 16 --quiet", a, b,
             png);
    run_ok(args);
    check_png16_matches_exr(png, exr, 40, 40, 1);
}

static void test_bits_other_than_8_or_16_are_refused(void **state) {
    (void)state;
    char args[4096];
    snprintf(args, sizeof args, "render %s -o %s/never.png --bits 12", BRICKS, test_temp_dir());
    const char *err = NULL;
    assert_int_equal(test_run_meso(args, &err), 2);
    assert_non_null(strstr(err, "--bits: 12 is not 8 or 16"));
    int lines = 0;
    for (const char *c = err; *c; c++) lines += *c == '\n';
    assert_int_equal(lines, 1);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_render_writes_exr_and_16_bit_png),
        cmocka_unit_test(test_compare_writes_the_difference_as_exr_and_16_bit_png),
        cmocka_unit_test(test_bits_other_than_8_or_16_are_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
