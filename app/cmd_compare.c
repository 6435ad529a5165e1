/* meso compare: metrics between two images, a false-colour difference and a labelled sheet. */
#include "app.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "meso/runtime.h"

static const app_command_help compare_help = {
    .name = "compare",
    .usage = "A.png B.png [-o DIFF.png] [--json] [--sheet SHEET.png] [options]",
    .summary =
        "Compare image A with image B (usually B is the reference) and print PSNR over the "
        "whole image and over the pixels both images cover, RMSE, SSIM (Wang et al. 2004, "
        "11x11 Gaussian window, sigma 1.5, on luminance), the largest channel difference and "
        "the coverage IoU with the counts of pixels covered by one image only (docs/compare.md). "
        "Values are compared as stored in the files (peak 1). Coverage comes from the masks "
        "given with --mask-a/--mask-b, or from A.coverage.png / B.coverage.png beside the "
        "images when they exist, else from the pixels that differ from --background.\n"
        "Exit status: 0, or 1 when --fail-below is not met, 2 for bad input (unreadable files, "
        "images of different sizes).",
    .examples = "  meso compare relief.png reference.png -o diff.png\n"
                "  meso compare relief.png reference.png --json --fail-below 30\n"
                "  meso compare relief.png reference.png --sheet sheet.png\n",
};

/* "x.png" -> "x.coverage.png" when that file exists. */
static bool coverage_beside(const char *path, char *out, size_t out_size) {
    size_t n = strlen(path);
    size_t stem = n >= 4 && !strcmp(path + n - 4, ".png") ? n - 4 : n;
    if (snprintf(out, out_size, "%.*s.coverage.png", (int)stem, path) >= (int)out_size)
        return false;
    return access(out, R_OK) == 0;
}

static bool parse_rgb(const char *text, float out[3]) {
    char *end = NULL;
    for (int c = 0; c < 3; c++) {
        out[c] = strtof(text, &end);
        if (end == text || !isfinite(out[c])) return false;
        text = end;
        if (c < 2) {
            if (*text != ',') return false;
            text++;
        }
    }
    return *text == 0;
}

static void print_json_number(FILE *out, double value) {
    if (isfinite(value))
        fprintf(out, "%.6g", value);
    else
        fputs("null", out);
}

static void print_json_string(FILE *out, const char *s) {
    fputc('"', out);
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\')
            fprintf(out, "\\%c", c);
        else if (c < 0x20)
            fprintf(out, "\\u%04x", c);
        else
            fputc(c, out);
    }
    fputc('"', out);
}

static void format_db(char *out, size_t size, double db) {
    if (isinf(db))
        snprintf(out, size, "inf (identical)");
    else if (isnan(db))
        snprintf(out, size, "n/a (no pixel covered by both)");
    else
        snprintf(out, size, "%.2f dB", db);
}

int meso_cmd_compare(int argc, char **argv) {
    const char *diff_path = NULL, *sheet_path = NULL, *mask_a_path = NULL, *mask_b_path = NULL;
    const char *background_text = NULL;
    bool json = false;
    double fail_below = NAN, diff_scale = 0.25;
    int bits = 0;
    const app_option options[] = {
        {"--output", "-o", APP_OPTION_STRING, &diff_path, "DIFF.png",
         "write the false-colour difference (black 0, blue, green, yellow, red at --diff-scale); "
         "DIFF.exr writes OpenEXR (half floats)",
         NULL, 0, 0},
        {"--json", NULL, APP_OPTION_FLAG, &json, NULL, "print the numbers as one JSON object", NULL,
         0, 0},
        {"--mask-a", NULL, APP_OPTION_STRING, &mask_a_path, "M.png", "coverage mask of A",
         "A.coverage.png when it exists", 0, 0},
        {"--mask-b", NULL, APP_OPTION_STRING, &mask_b_path, "M.png", "coverage mask of B",
         "B.coverage.png when it exists", 0, 0},
        {"--background", NULL, APP_OPTION_STRING, &background_text, "R,G,B",
         "background colour for coverage without masks", "0,0,0", 0, 0},
        {"--fail-below", NULL, APP_OPTION_DOUBLE, &fail_below, "PSNR",
         "exit 1 when the whole-image PSNR is below this (dB)", NULL, 0, 0},
        {"--diff-scale", NULL, APP_OPTION_DOUBLE, &diff_scale, "E",
         "mean channel difference shown red in the difference image", "0.25", 1e-6, 1e6},
        {"--sheet", NULL, APP_OPTION_STRING, &sheet_path, "SHEET.png",
         "write a labelled sheet: A, B, the difference and the numbers", NULL, 0, 0},
        APP_BITS_OPTION(&bits),
    };
    size_t num_options = sizeof options / sizeof options[0];
    app_globals globals;
    const char *positionals[2];
    int num_positionals = 0;
    int status = app_parse_options(&compare_help, options, num_options, argc, argv, &globals,
                                   positionals, 2, &num_positionals);
    if (status >= 0) return status;
    if (num_positionals != 2)
        return app_usage_error("compare", "needs two images, A.png and B.png");
    if ((status = app_check_bits("compare", bits)) >= 0) return status;
    float background[3] = {0, 0, 0};
    if (background_text && !parse_rgb(background_text, background))
        return app_usage_error("compare", "--background: '%s' is not R,G,B", background_text);

    meso_context *ctx = app_context_create(&globals);
    if (!ctx) return APP_EXIT_FAILURE;
    const char *path_a = positionals[0], *path_b = positionals[1];
    meso_image *a = NULL, *b = NULL, *mask_a = NULL, *mask_b = NULL, *diff = NULL, *sheet = NULL;
    char auto_a[4096], auto_b[4096];
    if (!mask_a_path && coverage_beside(path_a, auto_a, sizeof auto_a)) mask_a_path = auto_a;
    if (!mask_b_path && coverage_beside(path_b, auto_b, sizeof auto_b)) mask_b_path = auto_b;
    /* Outputs are checked before any work and written together at the end: both or none. */
    meso_result result = diff_path ? meso_file_check_output(ctx, diff_path) : MESO_OK;
    if (result == MESO_OK && sheet_path) result = meso_file_check_output(ctx, sheet_path);
    /* and their names say their formats: one meso does not write is refused */
    const char *image_outputs[2] = {diff_path, sheet_path};
    for (int i = 0; i < 2 && result == MESO_OK; i++)
        if (image_outputs[i] &&
            (status = app_check_image_output(image_outputs[i], true, "meso")) >= 0)
            goto done;
    if (result == MESO_OK) result = meso_image_load_png(ctx, path_a, &a);
    if (result == MESO_OK) result = meso_image_load_png(ctx, path_b, &b);
    if (result == MESO_OK && mask_a_path) result = meso_image_load_png(ctx, mask_a_path, &mask_a);
    if (result == MESO_OK && mask_b_path) result = meso_image_load_png(ctx, mask_b_path, &mask_b);
    if (result != MESO_OK) {
        status = app_fail(ctx, result);
        goto done;
    }
    if (a->width != b->width || a->height != b->height) {
        app_error("%s: is %dx%d but %s is %dx%d", path_a, a->width, a->height, path_b, b->width,
                  b->height);
        status = APP_EXIT_BAD_INPUT;
        goto done;
    }
    const meso_image *masks[2] = {mask_a, mask_b};
    const char *mask_paths[2] = {mask_a_path, mask_b_path};
    for (int m = 0; m < 2; m++)
        if (masks[m] && (masks[m]->width != a->width || masks[m]->height != a->height)) {
            app_error("%s: is %dx%d but the images are %dx%d", mask_paths[m], masks[m]->width,
                      masks[m]->height, a->width, a->height);
            status = APP_EXIT_BAD_INPUT;
            goto done;
        }
    /* one mask alone would compare a mask with a colour guess: use both or neither */
    bool with_masks = mask_a && mask_b;
    meso_compare_desc desc = {.coverage_a = with_masks ? mask_a : NULL,
                              .coverage_b = with_masks ? mask_b : NULL};
    memcpy(desc.background, background, sizeof background);
    meso_compare_result r;
    result = meso_image_compare(ctx, a, b, &desc, &r);
    if (result == MESO_OK && (diff_path || sheet_path))
        result = meso_image_diff(ctx, a, b, (float)diff_scale, &diff);
    if (result != MESO_OK) {
        status = app_fail(ctx, result);
        goto done;
    }
    char psnr[64], psnr_covered[64];
    format_db(psnr, sizeof psnr, r.psnr);
    format_db(psnr_covered, sizeof psnr_covered, r.psnr_covered);
    if (sheet_path) {
        char label_a[512], label_b[512], label_d[512];
        snprintf(label_a, sizeof label_a, "A: %s", path_a);
        snprintf(label_b, sizeof label_b, "B: %s", path_b);
        snprintf(label_d, sizeof label_d,
                 "|A-B|, red = %g\nPSNR %s\ncovered %s\nSSIM %.4f  IoU %.4f\nmax error %.4f",
                 diff_scale, psnr, psnr_covered, r.ssim, r.coverage_iou, r.max_error);
        const meso_image *cells[3] = {a, b, diff};
        const char *labels[3] = {label_a, label_b, label_d};
        result = meso_compare_sheet_create(ctx, cells, labels, 3, 3, &sheet);
    }
    if (result == MESO_OK && (diff_path || sheet_path)) {
        /* linear: the difference's colours as designed, the sheet's values as the files give */
        const meso_png_desc linear[2] = {{.bit_depth = bits, .encoding = MESO_ENCODING_LINEAR},
                                         {.bit_depth = bits, .encoding = MESO_ENCODING_LINEAR}};
        const meso_image *images[2] = {diff_path ? diff : sheet, sheet};
        const char *paths[2] = {diff_path ? diff_path : sheet_path, sheet_path};
        size_t count = diff_path && sheet_path ? 2 : 1;
        result = meso_image_save_all(ctx, count, images, paths, linear); /* .exr: OpenEXR */
    }
    if (result != MESO_OK) {
        status = app_fail(ctx, result);
        goto done;
    }
    const char *coverage_from = with_masks ? "masks" : "background colour";
    if (json) {
        printf("{\"a\": ");
        print_json_string(stdout, path_a);
        printf(", \"b\": ");
        print_json_string(stdout, path_b);
        printf(", \"width\": %d, \"height\": %d, \"psnr\": ", a->width, a->height);
        print_json_number(stdout, r.psnr);
        printf(", \"psnr_identical\": %s, \"psnr_covered\": ", isinf(r.psnr) ? "true" : "false");
        print_json_number(stdout, r.psnr_covered);
        printf(", \"rmse\": ");
        print_json_number(stdout, r.rmse);
        printf(", \"rmse_covered\": ");
        print_json_number(stdout, r.rmse_covered);
        printf(", \"ssim\": ");
        print_json_number(stdout, r.ssim);
        printf(", \"max_error\": ");
        print_json_number(stdout, r.max_error);
        printf(", \"coverage_iou\": ");
        print_json_number(stdout, r.coverage_iou);
        printf(", \"covered_both\": %zu, \"covered_only_a\": %zu, \"covered_only_b\": %zu, "
               "\"coverage_from\": \"%s\"}\n",
               r.covered_both, r.covered_only_a, r.covered_only_b, coverage_from);
    } else {
        printf("%-16s %dx%d\n", "size", a->width, a->height);
        printf("%-16s %s\n", "psnr", psnr);
        printf("%-16s %s\n", "psnr_covered", psnr_covered);
        printf("%-16s %.6f\n", "rmse", r.rmse);
        printf("%-16s %.6f\n", "rmse_covered", r.rmse_covered);
        printf("%-16s %.6f\n", "ssim", r.ssim);
        printf("%-16s %.6f\n", "max_error", r.max_error);
        printf("%-16s %.6f\n", "coverage_iou", r.coverage_iou);
        printf("%-16s %zu\n", "covered_both", r.covered_both);
        printf("%-16s %zu\n", "covered_only_a", r.covered_only_a);
        printf("%-16s %zu\n", "covered_only_b", r.covered_only_b);
        printf("%-16s %s\n", "coverage_from", coverage_from);
    }
    status = APP_EXIT_OK;
    if (!isnan(fail_below) && r.psnr < fail_below) {
        fprintf(stderr, "meso: compare: PSNR %.2f dB is below %.2f dB\n", r.psnr, fail_below);
        status = APP_EXIT_FAILURE;
    }

done:
    meso_image_destroy(a);
    meso_image_destroy(b);
    meso_image_destroy(mask_a);
    meso_image_destroy(mask_b);
    meso_image_destroy(diff);
    meso_image_destroy(sheet);
    meso_context_destroy(ctx);
    return status;
}
