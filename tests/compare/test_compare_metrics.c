/* meso_image_compare, meso_image_diff, meso_compare_sheet_create and the bitmap font. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "meso/compare.h"
#include "test_util.h"

static meso_image *filled(meso_context *ctx, int width, int height, int channels, float value) {
    meso_image *image = NULL;
    assert_int_equal(meso_image_create(ctx, width, height, channels, &image), MESO_OK);
    size_t n = (size_t)width * height * channels;
    for (size_t i = 0; i < n; i++) image->pixels[i] = value;
    return image;
}

static void test_compare_identical_images_give_infinite_psnr_and_ssim_one(void **state) {
    meso_context *ctx = test_context(1);
    meso_image *a = filled(ctx, 32, 24, 3, 0.0f);
    for (size_t i = 0; i < 32 * 24 * 3; i++) a->pixels[i] = (float)((i * 37) % 101) / 100.0f;
    meso_image *b = NULL;
    assert_int_equal(meso_image_clone(ctx, a, &b), MESO_OK);
    meso_compare_result r;
    assert_int_equal(meso_image_compare(ctx, a, b, NULL, &r), MESO_OK);
    assert_true(isinf(r.psnr) && r.psnr > 0);
    assert_true(r.ssim == 1.0);
    assert_true(r.rmse == 0.0 && r.max_error == 0.0);
    meso_image_destroy(a);
    meso_image_destroy(b);
    meso_context_destroy(ctx);
}

/* b = a +- 0.1 in a checkerboard: MSE 0.01, so PSNR = 10 log10(1 / 0.01) = 20 dB exactly. */
static void test_compare_known_noise_gives_the_known_psnr(void **state) {
    meso_context *ctx = test_context(1);
    meso_image *a = filled(ctx, 16, 16, 3, 0.5f), *b = filled(ctx, 16, 16, 3, 0.5f);
    for (int y = 0; y < 16; y++)
        for (int x = 0; x < 16; x++)
            for (int c = 0; c < 3; c++) meso_image_at(b, x, y)[c] += (x + y) % 2 ? 0.1f : -0.1f;
    meso_compare_result r;
    assert_int_equal(meso_image_compare(ctx, a, b, NULL, &r), MESO_OK);
    assert_true(fabs(r.psnr - 20.0) < 1e-4);
    assert_true(fabs(r.rmse - 0.1) < 1e-6);
    assert_true(fabs(r.max_error - 0.1) < 1e-6);
    assert_true(r.ssim < 1.0 && r.ssim > 0.0);
    /* without masks every pixel differs from the black background: all covered */
    assert_int_equal(r.covered_both, 256);
    assert_true(fabs(r.psnr_covered - 20.0) < 1e-4);
    meso_image_destroy(a);
    meso_image_destroy(b);
    meso_context_destroy(ctx);
}

/* Masks: A covers columns 0..5, B columns 3..7 of an 8x4 image: both 3 x 4, A only 3 x 4,
 * B only 2 x 4: IoU = 12 / 32. The covered PSNR ignores the differing background. */
static void test_compare_iou_and_counts_from_masks(void **state) {
    meso_context *ctx = test_context(1);
    meso_image *a = filled(ctx, 8, 4, 3, 0.3f), *b = filled(ctx, 8, 4, 3, 0.3f);
    meso_image *ma = filled(ctx, 8, 4, 1, 0.0f), *mb = filled(ctx, 8, 4, 1, 0.0f);
    for (int y = 0; y < 4; y++)
        for (int x = 0; x < 8; x++) {
            if (x <= 5) meso_image_at(ma, x, y)[0] = 1.0f;
            if (x >= 3) meso_image_at(mb, x, y)[0] = 1.0f;
            if (x < 3 || x > 5) meso_image_at(b, x, y)[0] = 0.9f; /* outside both: differs */
        }
    meso_compare_desc desc = {.coverage_a = ma, .coverage_b = mb};
    meso_compare_result r;
    assert_int_equal(meso_image_compare(ctx, a, b, &desc, &r), MESO_OK);
    assert_int_equal(r.covered_both, 12);
    assert_int_equal(r.covered_only_a, 12);
    assert_int_equal(r.covered_only_b, 8);
    assert_true(fabs(r.coverage_iou - 12.0 / 32.0) < 1e-12);
    assert_true(isinf(r.psnr_covered));
    assert_true(isfinite(r.psnr));
    meso_image_destroy(a);
    meso_image_destroy(b);
    meso_image_destroy(ma);
    meso_image_destroy(mb);
    meso_context_destroy(ctx);
}

static void test_compare_coverage_from_background_without_masks(void **state) {
    meso_context *ctx = test_context(1);
    meso_image *a = filled(ctx, 4, 4, 3, 0.2f), *b = filled(ctx, 4, 4, 3, 0.2f);
    meso_image_at(a, 0, 0)[0] = 0.7f; /* covered in A only */
    meso_compare_desc desc = {.background = {0.2f, 0.2f, 0.2f}};
    meso_compare_result r;
    assert_int_equal(meso_image_compare(ctx, a, b, &desc, &r), MESO_OK);
    assert_int_equal(r.covered_only_a, 1);
    assert_int_equal(r.covered_both + r.covered_only_b, 0);
    assert_true(r.coverage_iou == 0.0);
    assert_true(isnan(r.psnr_covered));
    meso_image_destroy(a);
    meso_image_destroy(b);
    meso_context_destroy(ctx);
}

static void test_compare_different_sizes_is_an_error_naming_both_sizes(void **state) {
    meso_context *ctx = test_context(1);
    meso_image *a = filled(ctx, 4, 3, 3, 0.0f), *b = filled(ctx, 8, 6, 3, 0.0f);
    meso_compare_result r;
    r.psnr = 1.0;
    assert_int_equal(meso_image_compare(ctx, a, b, NULL, &r), MESO_ERROR_INVALID_ARGUMENT);
    assert_true(r.psnr == 0.0);
    const char *message = meso_context_last_error(ctx);
    assert_non_null(strstr(message, "4x3"));
    assert_non_null(strstr(message, "8x6"));
    meso_image *diff = (meso_image *)(uintptr_t)1;
    assert_int_equal(meso_image_diff(ctx, a, b, 0.0f, &diff), MESO_ERROR_INVALID_ARGUMENT);
    assert_null(diff);
    meso_image_destroy(a);
    meso_image_destroy(b);
    meso_context_destroy(ctx);
}

static void test_compare_diff_is_black_where_equal_and_red_at_full_scale(void **state) {
    meso_context *ctx = test_context(1);
    meso_image *a = filled(ctx, 2, 1, 3, 0.5f), *b = filled(ctx, 2, 1, 1, 0.5f);
    for (int c = 0; c < 3; c++) meso_image_at(a, 1, 0)[c] = 0.5f + 0.25f;
    meso_image *diff = NULL;
    assert_int_equal(meso_image_diff(ctx, a, b, 0.0f, &diff), MESO_OK);
    assert_int_equal(diff->channels, 3);
    const float *p0 = meso_image_at(diff, 0, 0), *p1 = meso_image_at(diff, 1, 0);
    assert_true(p0[0] == 0.0f && p0[1] == 0.0f && p0[2] == 0.0f);
    assert_true(fabsf(p1[0] - 1.0f) < 1e-6f && p1[1] < 1e-6f && p1[2] < 1e-6f);
    meso_image_destroy(diff);
    meso_image_destroy(a);
    meso_image_destroy(b);
    meso_context_destroy(ctx);
}

static size_t lit_pixels(const meso_image *image, int x0, int y0, int x1, int y1) {
    size_t lit = 0;
    for (int y = y0; y < y1; y++)
        for (int x = x0; x < x1; x++) lit += meso_image_at(image, x, y)[0] > 0.5f;
    return lit;
}

static void test_compare_text_draws_distinct_glyphs_inside_the_image(void **state) {
    meso_context *ctx = test_context(1);
    meso_image *image = filled(ctx, 40, 12, 3, 0.0f);
    const float white[3] = {1, 1, 1};
    meso_image_draw_text(image, 1, 1, 1, white, "I");
    size_t i_count = lit_pixels(image, 0, 0, 40, 12);
    meso_image_draw_text(image, 7, 1, 1, white, "W");
    size_t w_count = lit_pixels(image, 6, 0, 12, 12);
    assert_true(i_count > 5 && w_count > i_count);
    /* clipped, not crashing */
    meso_image_draw_text(image, 36, 8, 3, white, "clip\n~\x01");
    meso_image_draw_text(image, -100, -100, 1, white, "x");
    meso_image_destroy(image);
    meso_context_destroy(ctx);
}

/* The lowest row with ink (> 0.5) in columns [x0, x1), -1 for none. */
static int lowest_ink(const meso_image *image, int x0, int x1) {
    for (int y = image->height - 1; y >= 0; y--)
        for (int x = x0; x < x1; x++)
            if (meso_image_at(image, x, y)[0] > 0.5f) return y;
    return -1;
}

/* The 5 x 7 font once drew "p" and "g" on the baseline ("bumP"). */
static void test_compare_text_has_descenders(void **state) {
    meso_context *ctx = test_context(1);
    meso_image *image = filled(ctx, 40, 16, 3, 0.0f);
    const float white[3] = {1, 1, 1};
    meso_image_draw_text(image, 1, 1, 1, white, "op");
    int o_bottom = lowest_ink(image, 1, 7), p_bottom = lowest_ink(image, 7, 13);
    if (!(o_bottom > 0 && p_bottom >= o_bottom + 2))
        fail_msg("o ends at row %d, p at %d: no descender", o_bottom, p_bottom);
    meso_image_destroy(image);
    meso_context_destroy(ctx);
}

static void test_compare_sheet_lays_out_cells_with_labels(void **state) {
    meso_context *ctx = test_context(1);
    meso_image *a = filled(ctx, 20, 10, 3, 0.25f), *b = filled(ctx, 30, 12, 1, 0.75f);
    const meso_image *images[3] = {a, b, a};
    const char *labels[3] = {"A", "B\ntwo lines", NULL};
    meso_image *sheet = NULL;
    assert_int_equal(meso_compare_sheet_create(ctx, images, labels, 3, 2, &sheet), MESO_OK);
    /* 2 columns of 30 + 8 px, 2 rows of 12 + 24 (two lines of 12) + 16 */
    assert_int_equal(sheet->width, 2 * (30 + 8) + 8);
    assert_int_equal(sheet->height, 2 * (12 + 24 + 16) + 8);
    assert_true(fabsf(meso_image_at(sheet, 8, 8)[0] - 0.25f) < 1e-6f);
    assert_true(fabsf(meso_image_at(sheet, 8 + 38, 8)[1] - 0.75f) < 1e-6f);
    /* label ink beneath the first cell */
    assert_true(lit_pixels(sheet, 8, 8 + 12, 8 + 30, 8 + 12 + 24 + 8) > 5);
    meso_image_destroy(sheet);
    meso_image_destroy(a);
    meso_image_destroy(b);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_compare_identical_images_give_infinite_psnr_and_ssim_one),
        cmocka_unit_test(test_compare_known_noise_gives_the_known_psnr),
        cmocka_unit_test(test_compare_iou_and_counts_from_masks),
        cmocka_unit_test(test_compare_coverage_from_background_without_masks),
        cmocka_unit_test(test_compare_different_sizes_is_an_error_naming_both_sizes),
        cmocka_unit_test(test_compare_diff_is_black_where_equal_and_red_at_full_scale),
        cmocka_unit_test(test_compare_text_draws_distinct_glyphs_inside_the_image),
        cmocka_unit_test(test_compare_text_has_descenders),
        cmocka_unit_test(test_compare_sheet_lays_out_cells_with_labels),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
