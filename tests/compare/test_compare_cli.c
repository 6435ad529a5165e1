/* `meso compare`: numbers, exit statuses, masks beside the images, diff and sheet files. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

#include "meso/meso.h"
#include "test_util.h"

static void write_png(meso_context *ctx, const char *path, int width, int height, float base,
                      float noise) {
    meso_image *image = NULL;
    assert_int_equal(meso_image_create(ctx, width, height, 3, &image), MESO_OK);
    for (int y = 0; y < height; y++)
        for (int x = 0; x < width; x++)
            for (int c = 0; c < 3; c++)
                meso_image_at(image, x, y)[c] = base + ((x + y) % 2 ? noise : -noise);
    meso_png_desc desc = {.encoding = MESO_ENCODING_LINEAR};
    assert_int_equal(meso_image_save_png(ctx, image, path, &desc), MESO_OK);
    meso_image_destroy(image);
}

static const char *dir;

static int setup(void **state) {
    meso_context *ctx = test_context(1);
    dir = test_temp_dir();
    write_png(ctx, test_path(dir, "a.png"), 24, 16, 0.5f, 0.0f);
    write_png(ctx, test_path(dir, "b.png"), 24, 16, 0.5f, 0.2f);
    write_png(ctx, test_path(dir, "small.png"), 12, 8, 0.5f, 0.0f);
    meso_context_destroy(ctx);
    return 0;
}

/* Run the program with stdout captured into a file; returns the exit status. */
static int run_capture(const char *arguments, char *out, size_t out_size) {
    char command[4096];
    const char *stdout_path = test_path(dir, "stdout.txt");
    snprintf(command, sizeof command, "%s %s >%s 2>/dev/null </dev/null", MESO_PROGRAM, arguments,
             stdout_path);
    int status = system(command);
    out[0] = 0;
    FILE *f = fopen(stdout_path, "rb");
    if (f) {
        size_t n = fread(out, 1, out_size - 1, f);
        out[n] = 0;
        fclose(f);
    }
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

static void test_compare_cli_prints_aligned_numbers_and_json(void **state) {
    char args[2048], out[8192];
    snprintf(args, sizeof args, "compare %s %s", test_path(dir, "a.png"), test_path(dir, "b.png"));
    assert_int_equal(run_capture(args, out, sizeof out), 0);
    assert_non_null(strstr(out, "psnr "));
    assert_non_null(strstr(out, "ssim "));
    assert_non_null(strstr(out, "coverage_iou "));
    /* 0.2 noise in 8 bits: PSNR close to 10 log10(1/0.04) = 13.98 dB */
    const char *psnr = strstr(out, "psnr ");
    assert_true(fabs(atof(psnr + 5) - 13.98) < 0.1);

    snprintf(args, sizeof args, "compare %s %s --json", test_path(dir, "a.png"),
             test_path(dir, "a.png"));
    assert_int_equal(run_capture(args, out, sizeof out), 0);
    assert_non_null(strstr(out, "\"psnr\": null"));
    assert_non_null(strstr(out, "\"psnr_identical\": true"));
    assert_non_null(strstr(out, "\"ssim\": 1"));
}

static void test_compare_cli_different_sizes_exit_2_naming_both_sizes(void **state) {
    char args[2048];
    const char *err = NULL;
    snprintf(args, sizeof args, "compare %s %s", test_path(dir, "a.png"),
             test_path(dir, "small.png"));
    assert_int_equal(test_run_meso(args, &err), 2);
    assert_non_null(strstr(err, "24x16"));
    assert_non_null(strstr(err, "12x8"));
    assert_null(strchr(strchr(err, '\n') + 1, '\n')); /* one line */
}

static void test_compare_cli_fail_below_exits_1_when_not_met(void **state) {
    char args[2048];
    snprintf(args, sizeof args, "compare %s %s --fail-below 30", test_path(dir, "a.png"),
             test_path(dir, "b.png"));
    assert_int_equal(test_run_meso(args, NULL), 1);
    snprintf(args, sizeof args, "compare %s %s --fail-below 10", test_path(dir, "a.png"),
             test_path(dir, "b.png"));
    assert_int_equal(test_run_meso(args, NULL), 0);
}

static void test_compare_cli_writes_diff_and_sheet(void **state) {
    char args[4096];
    const char *diff = test_path(dir, "diff.png"), *sheet = test_path(dir, "sheet.png");
    snprintf(args, sizeof args, "compare %s %s -o %s --sheet %s", test_path(dir, "a.png"),
             test_path(dir, "b.png"), diff, sheet);
    assert_int_equal(test_run_meso(args, NULL), 0);
    meso_context *ctx = test_context(1);
    meso_image *image = NULL;
    assert_int_equal(meso_image_load_png(ctx, test_path(dir, "diff.png"), &image), MESO_OK);
    assert_int_equal(image->width, 24);
    meso_image_destroy(image);
    assert_int_equal(meso_image_load_png(ctx, test_path(dir, "sheet.png"), &image), MESO_OK);
    assert_true(image->width > 3 * 24);
    meso_image_destroy(image);
    meso_context_destroy(ctx);
}

static void test_compare_cli_uses_coverage_masks_beside_the_images(void **state) {
    meso_context *ctx = test_context(1);
    /* masks that cover nothing in A and everything in B: IoU 0 */
    meso_image *mask = NULL;
    assert_int_equal(meso_image_create(ctx, 24, 16, 1, &mask), MESO_OK);
    assert_int_equal(meso_image_save_png(ctx, mask, test_path(dir, "a.coverage.png"), NULL),
                     MESO_OK);
    for (int i = 0; i < 24 * 16; i++) mask->pixels[i] = 1.0f;
    assert_int_equal(meso_image_save_png(ctx, mask, test_path(dir, "b.coverage.png"), NULL),
                     MESO_OK);
    meso_image_destroy(mask);
    meso_context_destroy(ctx);
    char args[2048], out[8192];
    snprintf(args, sizeof args, "compare %s %s --json", test_path(dir, "a.png"),
             test_path(dir, "b.png"));
    assert_int_equal(run_capture(args, out, sizeof out), 0);
    assert_non_null(strstr(out, "\"coverage_iou\": 0,"));
    assert_non_null(strstr(out, "\"coverage_from\": \"masks\""));
    remove(test_path(dir, "a.coverage.png"));
    remove(test_path(dir, "b.coverage.png"));
}

static void test_compare_cli_usage_errors_and_help(void **state) {
    const char *err = NULL;
    assert_int_equal(test_run_meso("compare --help", NULL), 0);
    assert_int_equal(test_run_meso("compare only-one.png", &err), 2);
    assert_non_null(strstr(err, "compare"));
    char args[2048];
    snprintf(args, sizeof args, "compare %s %s", test_path(dir, "a.png"),
             test_path(dir, "missing.png"));
    assert_int_equal(test_run_meso(args, &err), 2);
    assert_non_null(strstr(err, "missing.png"));
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_compare_cli_prints_aligned_numbers_and_json),
        cmocka_unit_test(test_compare_cli_different_sizes_exit_2_naming_both_sizes),
        cmocka_unit_test(test_compare_cli_fail_below_exits_1_when_not_met),
        cmocka_unit_test(test_compare_cli_writes_diff_and_sheet),
        cmocka_unit_test(test_compare_cli_uses_coverage_masks_beside_the_images),
        cmocka_unit_test(test_compare_cli_usage_errors_and_help),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
