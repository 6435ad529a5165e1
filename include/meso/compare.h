/* meso compare: image metrics against a reference, false-colour differences, labelled sheets.
 *
 * Metrics (docs/design.md, "Measuring against the truth"): PSNR over the whole image and over the
 * pixels both images cover, RMSE, SSIM (Wang et al. 2004; Gaussian window, sigma 1.5, 11x11,
 * on luminance), maximum absolute error, coverage IoU and the pixels covered by one image only.
 * Values are compared as given (callers compare linear images for the papers' numbers); the
 * peak value is 1.
 *
 * All functions are pure apart from allocation, and thread-safe.
 */
#ifndef MESO_COMPARE_H
#define MESO_COMPARE_H

#include "meso/core.h"
#include "meso/image.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct meso_compare_desc {
    const meso_image *coverage_a; /* grey masks (> 0.5 = covered); NULL: taken from the colour, */
    const meso_image *coverage_b; /* a pixel differing from `background` counts as covered    */
    float background[3];          /* used only without masks */
} meso_compare_desc;

typedef struct meso_compare_result {
    double psnr;         /* dB, whole image; INFINITY when identical */
    double psnr_covered; /* dB, over pixels both cover; NAN when none */
    double rmse, rmse_covered;
    double ssim;         /* whole image, mean over windows */
    double max_error;    /* largest absolute channel difference */
    double coverage_iou; /* |A and B| / |A or B|; 1 when neither covers anything */
    size_t covered_both, covered_only_a, covered_only_b;
} meso_compare_result;

/* Compare two images of the same size (MESO_ERROR_INVALID_ARGUMENT naming both sizes
 * otherwise). Channels: the first three (grey is spread). desc may be NULL. */
meso_result meso_image_compare(meso_context *ctx, const meso_image *a, const meso_image *b,
                               const meso_compare_desc *desc, meso_compare_result *out_result);

/* A false-colour map of |a - b| (mean over channels): black 0, through blue, green, yellow to
 * red at `full_scale` (0: 0.25). RGB. */
meso_result meso_image_diff(meso_context *ctx, const meso_image *a, const meso_image *b,
                            float full_scale, meso_image **out_image);

/* A sheet: images laid out in `columns` columns (0: all in one row), each with its label (lines
 * separated by '\n') drawn beneath in meso's built-in bitmap font. Images may differ in size;
 * cells take the largest. RGB, values as given (linear or encoded: the caller's choice). */
meso_result meso_compare_sheet_create(meso_context *ctx, const meso_image *const *images,
                                      const char *const *labels, size_t count, int columns,
                                      meso_image **out_image);

/* The width and height of the sheet meso_compare_sheet_create would make of `count` cells of
 * cell_width x cell_height with labels of at most `label_lines` lines, before any image
 * exists (so a command can refuse a sheet over the limits before its work). MESO_OK, or
 * MESO_ERROR_LIMIT (logged) when a side exceeds MESO_IMAGE_MAX_SIDE. */
meso_result meso_compare_sheet_size(meso_context *ctx, size_t count, int columns, int cell_width,
                                    int cell_height, int label_lines, int *out_width,
                                    int *out_height);

/* Draw text into an RGB(A) image at (x, y) (top-left) in `color`, anti-aliased, with DejaVu
 * Sans Mono (cairo, fontconfig) at 10 * `scale` pixels: 6 * scale pixels a character, lines
 * 12 * scale apart ('\n' starts one). Clipped to the image. Not thread-safe (fontconfig). */
void meso_image_draw_text(meso_image *image, int x, int y, int scale, const float color[3],
                          const char *text);

#ifdef __cplusplus
}
#endif
#endif
