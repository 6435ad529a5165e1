/* PNG round trips and bad PNG files. */
#include <stdlib.h>
#include <string.h>
#include <dirent.h>
#include <sys/stat.h>

#include "test_util.h"
#include "meso/runtime.h"

static meso_image *gradient_image(meso_context *ctx, int w, int h, int channels) {
    meso_image *image = NULL;
    assert_int_equal(meso_image_create(ctx, w, h, channels, &image), MESO_OK);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            for (int c = 0; c < channels; c++)
                meso_image_at(image, x, y)[c] = (float)((x * 7 + y * 13 + c * 29) % 256) / 255.0f;
    return image;
}

static void round_trip(int channels, int bit_depth) {
    meso_context *ctx = test_context(1);
    meso_image *image = gradient_image(ctx, 37, 19, channels);
    const char *path = test_path(test_temp_dir(), "round_trip.png");
    meso_png_desc desc = {.bit_depth = bit_depth, .encoding = MESO_ENCODING_LINEAR};
    assert_int_equal(meso_image_save_png(ctx, image, path, &desc), MESO_OK);
    meso_image *loaded = NULL;
    assert_int_equal(meso_image_load_png(ctx, path, &loaded), MESO_OK);
    assert_int_equal(loaded->width, 37);
    assert_int_equal(loaded->height, 19);
    assert_int_equal(loaded->channels, channels);
    size_t count = 37u * 19u * (size_t)channels;
    for (size_t i = 0; i < count; i++)
        assert_float_equal(loaded->pixels[i], image->pixels[i], (float)(0.5 / 255.0 + 1e-6));
    meso_image_destroy(loaded);
    meso_image_destroy(image);
    meso_context_destroy(ctx);
}

static void test_png_round_trip_8_bit_grey(void **state) { round_trip(1, 8); }
static void test_png_round_trip_8_bit_grey_alpha(void **state) { round_trip(2, 8); }
static void test_png_round_trip_8_bit_rgb(void **state) { round_trip(3, 8); }
static void test_png_round_trip_8_bit_rgba(void **state) { round_trip(4, 8); }
static void test_png_round_trip_16_bit_grey(void **state) { round_trip(1, 16); }
static void test_png_round_trip_16_bit_rgba(void **state) { round_trip(4, 16); }

static void test_png_16_bit_keeps_precision(void **state) {
    meso_context *ctx = test_context(1);
    meso_image *image = NULL;
    assert_int_equal(meso_image_create(ctx, 4, 1, 1, &image), MESO_OK);
    image->pixels[1] = 1000.0f / 65535.0f;
    const char *path = test_path(test_temp_dir(), "precise.png");
    meso_png_desc desc = {.bit_depth = 16, .encoding = MESO_ENCODING_LINEAR};
    assert_int_equal(meso_image_save_png(ctx, image, path, &desc), MESO_OK);
    meso_image *loaded = NULL;
    assert_int_equal(meso_image_load_png(ctx, path, &loaded), MESO_OK);
    assert_float_equal(loaded->pixels[1], 1000.0f / 65535.0f, 1e-7);
    meso_image_destroy(loaded);
    meso_image_destroy(image);
    meso_context_destroy(ctx);
}

static void test_png_srgb_encoding_applies_the_curve(void **state) {
    meso_context *ctx = test_context(1);
    meso_image *image = NULL;
    assert_int_equal(meso_image_create(ctx, 1, 1, 3, &image), MESO_OK);
    image->pixels[0] = image->pixels[1] = image->pixels[2] = 0.214f; /* sRGB ~0.5 */
    const char *path = test_path(test_temp_dir(), "srgb.png");
    assert_int_equal(meso_image_save_png(ctx, image, path, NULL), MESO_OK);
    meso_image *loaded = NULL;
    assert_int_equal(meso_image_load_png(ctx, path, &loaded), MESO_OK);
    assert_float_equal(loaded->pixels[0], 0.5f, 1.5f / 255.0f);
    meso_image_destroy(loaded);
    meso_image_destroy(image);
    meso_context_destroy(ctx);
}

static void test_png_save_leaves_no_temporary_file(void **state) {
    meso_context *ctx = test_context(1);
    char dir[1024];
    snprintf(dir, sizeof(dir), "%s/atomic", test_temp_dir());
    mkdir(dir, 0755);
    meso_image *image = gradient_image(ctx, 8, 8, 3);
    assert_int_equal(meso_image_save_png(ctx, image, test_path(dir, "a.png"), NULL), MESO_OK);
    DIR *d = opendir(dir);
    int files = 0;
    for (struct dirent *e; (e = readdir(d));)
        if (e->d_name[0] != '.') {
            assert_string_equal(e->d_name, "a.png");
            files++;
        }
    closedir(d);
    assert_int_equal(files, 1);
    meso_image_destroy(image);
    meso_context_destroy(ctx);
}

static void test_png_truncated_is_a_format_error_naming_the_file(void **state) {
    meso_context *ctx = test_context(1);
    meso_image *image = gradient_image(ctx, 64, 64, 3);
    const char *path = test_path(test_temp_dir(), "whole.png");
    assert_int_equal(meso_image_save_png(ctx, image, path, NULL), MESO_OK);
    char *data = NULL;
    size_t size = 0;
    assert_int_equal(meso_file_read(ctx, path, 1 << 20, &data, &size), MESO_OK);
    const char *cut = test_path(test_temp_dir(), "truncated.png");
    test_write_file(cut, data, size / 2);
    meso_image *loaded = (meso_image *)1;
    assert_int_equal(meso_image_load_png(ctx, cut, &loaded), MESO_ERROR_FORMAT);
    assert_null(loaded);
    assert_non_null(strstr(meso_context_last_error(ctx), "truncated.png"));
    free(data);
    meso_image_destroy(image);
    meso_context_destroy(ctx);
}

static void test_png_huge_declared_size_is_refused_before_allocating(void **state) {
    meso_context *ctx = test_context(1);
    const char *path = test_path(test_temp_dir(), "huge.png");
    test_write_png_header(path, 100000, 100000);
    meso_image *loaded = NULL;
    assert_int_equal(meso_image_load_png(ctx, path, &loaded), MESO_ERROR_LIMIT);
    assert_non_null(strstr(meso_context_last_error(ctx), "huge.png"));
    assert_non_null(strstr(meso_context_last_error(ctx), "100000x100000"));
    meso_context_destroy(ctx);
}

static void test_png_not_a_png_and_missing_file(void **state) {
    meso_context *ctx = test_context(1);
    const char *path = test_path(test_temp_dir(), "text.png");
    test_write_file(path, "hello, not a png", 16);
    meso_image *loaded = NULL;
    assert_int_equal(meso_image_load_png(ctx, path, &loaded), MESO_ERROR_FORMAT);
    assert_non_null(strstr(meso_context_last_error(ctx), "text.png: not a PNG"));
    assert_int_equal(meso_image_load_png(ctx, "/nonexistent/x.png", &loaded), MESO_ERROR_IO);
    assert_non_null(strstr(meso_context_last_error(ctx), "/nonexistent/x.png"));
    meso_context_destroy(ctx);
}

static void test_image_create_checks_limits(void **state) {
    meso_context *ctx = test_context(1);
    meso_image *image = NULL;
    assert_int_equal(meso_image_create(ctx, 0, 4, 3, &image), MESO_ERROR_INVALID_ARGUMENT);
    assert_int_equal(meso_image_create(ctx, MESO_IMAGE_MAX_SIDE + 1, 4, 3, &image),
                     MESO_ERROR_LIMIT);
    assert_int_equal(meso_image_create(ctx, 16384, 16384, 1, &image), MESO_ERROR_LIMIT);
    assert_null(image);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_png_round_trip_8_bit_grey),
        cmocka_unit_test(test_png_round_trip_8_bit_grey_alpha),
        cmocka_unit_test(test_png_round_trip_8_bit_rgb),
        cmocka_unit_test(test_png_round_trip_8_bit_rgba),
        cmocka_unit_test(test_png_round_trip_16_bit_grey),
        cmocka_unit_test(test_png_round_trip_16_bit_rgba),
        cmocka_unit_test(test_png_16_bit_keeps_precision),
        cmocka_unit_test(test_png_srgb_encoding_applies_the_curve),
        cmocka_unit_test(test_png_save_leaves_no_temporary_file),
        cmocka_unit_test(test_png_truncated_is_a_format_error_naming_the_file),
        cmocka_unit_test(test_png_huge_declared_size_is_refused_before_allocating),
        cmocka_unit_test(test_png_not_a_png_and_missing_file),
        cmocka_unit_test(test_image_create_checks_limits),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
