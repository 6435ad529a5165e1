/* Image metrics against a reference (include/meso/compare.h; definitions in docs/compare.md).
 *
 * PSNR = 10 log10(1 / MSE), the mean over pixels and the three colour channels of (a - b)^2,
 * peak 1; over the whole image and over the pixels both images cover. SSIM after Wang, Bovik,
 * Sheikh & Simoncelli 2004 (IEEE TIP 13(4), eq. 13): on luminance Y = 0.2126 R + 0.7152 G +
 * 0.0722 B, local statistics under an 11 x 11 Gaussian window of sigma 1.5 (normalised),
 * C1 = (0.01 L)^2, C2 = (0.03 L)^2 with L = 1, averaged over the window positions that fit
 * inside the image (their reference implementation's 'valid' filter); images smaller than the
 * window use the window cut at the border and renormalised.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "compare_internal.h"
#include "meso/runtime.h"

enum { SSIM_RADIUS = 5 };

/* The colour channel c (0..2) of a pixel: grey images spread. */
static float channel(const meso_image *image, size_t pixel, int c) {
    int ch = image->channels >= 3 ? c : 0;
    return image->pixels[pixel * (size_t)image->channels + (size_t)ch];
}

static float luminance(const meso_image *image, size_t pixel) {
    return 0.2126f * channel(image, pixel, 0) + 0.7152f * channel(image, pixel, 1) +
           0.0722f * channel(image, pixel, 2);
}

static bool covered(const meso_image *color, const meso_image *mask, const float background[3],
                    size_t pixel) {
    if (mask) return mask->pixels[pixel * (size_t)mask->channels] > 0.5f;
    /* half an 8-bit step: a PNG round trip of the background still counts as background */
    for (int c = 0; c < 3; c++)
        if (fabsf(channel(color, pixel, c) - background[c]) > 0.5f / 255.0f) return true;
    return false;
}

static double psnr_of(double mse) { return mse > 0.0 ? 10.0 * log10(1.0 / mse) : INFINITY; }

/* Separable Gaussian blur of `in` (w x h) into `out`, the window cut at the border and
 * renormalised; tmp is w x h scratch. */
static void blur(const float *in, float *out, float *tmp, int w, int h, const float *kernel) {
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double sum = 0.0, weight = 0.0;
            for (int k = -SSIM_RADIUS; k <= SSIM_RADIUS; k++) {
                int xx = x + k;
                if (xx < 0 || xx >= w) continue;
                sum += (double)kernel[k + SSIM_RADIUS] * in[(size_t)y * w + xx];
                weight += kernel[k + SSIM_RADIUS];
            }
            tmp[(size_t)y * w + x] = (float)(sum / weight);
        }
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double sum = 0.0, weight = 0.0;
            for (int k = -SSIM_RADIUS; k <= SSIM_RADIUS; k++) {
                int yy = y + k;
                if (yy < 0 || yy >= h) continue;
                sum += (double)kernel[k + SSIM_RADIUS] * tmp[(size_t)yy * w + x];
                weight += kernel[k + SSIM_RADIUS];
            }
            out[(size_t)y * w + x] = (float)(sum / weight);
        }
}

static meso_result compute_ssim(meso_context *ctx, const meso_image *a, const meso_image *b,
                                double *out_ssim) {
    int w = a->width, h = a->height;
    size_t n = (size_t)w * (size_t)h;
    float *buffers = calloc(n * 11, sizeof(float));
    if (!buffers)
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "compare: SSIM of %dx%d", w, h);
    float *ya = buffers, *yb = ya + n, *prod = yb + n, *tmp = prod + n;
    float *mu_a = tmp + n, *mu_b = mu_a + n, *s_aa = mu_b + n, *s_bb = s_aa + n, *s_ab = s_bb + n,
          *sq = s_ab + n, *sq2 = sq + n;
    float kernel[2 * SSIM_RADIUS + 1];
    for (int k = -SSIM_RADIUS; k <= SSIM_RADIUS; k++)
        kernel[k + SSIM_RADIUS] = expf(-(float)(k * k) / (2.0f * 1.5f * 1.5f));
    for (size_t p = 0; p < n; p++) {
        ya[p] = luminance(a, p);
        yb[p] = luminance(b, p);
    }
    blur(ya, mu_a, tmp, w, h, kernel);
    blur(yb, mu_b, tmp, w, h, kernel);
    for (size_t p = 0; p < n; p++)
        sq[p] = ya[p] * ya[p], sq2[p] = yb[p] * yb[p], prod[p] = ya[p] * yb[p];
    blur(sq, s_aa, tmp, w, h, kernel);
    blur(sq2, s_bb, tmp, w, h, kernel);
    blur(prod, s_ab, tmp, w, h, kernel);
    const double c1 = 0.01 * 0.01, c2 = 0.03 * 0.03;
    bool valid = w > 2 * SSIM_RADIUS && h > 2 * SSIM_RADIUS;
    int x0 = valid ? SSIM_RADIUS : 0, x1 = valid ? w - SSIM_RADIUS : w;
    int y0 = valid ? SSIM_RADIUS : 0, y1 = valid ? h - SSIM_RADIUS : h;
    double sum = 0.0;
    for (int y = y0; y < y1; y++)
        for (int x = x0; x < x1; x++) {
            size_t p = (size_t)y * w + x;
            double ma = mu_a[p], mb = mu_b[p];
            double va = s_aa[p] - ma * ma, vb = s_bb[p] - mb * mb, cov = s_ab[p] - ma * mb;
            sum += ((2.0 * ma * mb + c1) * (2.0 * cov + c2)) /
                   ((ma * ma + mb * mb + c1) * (va + vb + c2));
        }
    *out_ssim = sum / ((double)(x1 - x0) * (double)(y1 - y0));
    free(buffers);
    return MESO_OK;
}

meso_result meso_image_compare(meso_context *ctx, const meso_image *a, const meso_image *b,
                               const meso_compare_desc *desc, meso_compare_result *out_result) {
    memset(out_result, 0, sizeof *out_result);
    if (!a || !b || !a->pixels || !b->pixels)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "compare: missing image");
    if (a->width != b->width || a->height != b->height)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "compare: the images differ in size: %dx%d and %dx%d", a->width,
                              a->height, b->width, b->height);
    meso_compare_desc d = desc ? *desc : (meso_compare_desc){0};
    const meso_image *masks[2] = {d.coverage_a, d.coverage_b};
    for (int m = 0; m < 2; m++)
        if (masks[m] && (masks[m]->width != a->width || masks[m]->height != a->height))
            return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                                  "compare: coverage mask of %s: %dx%d, the images are %dx%d",
                                  m == 0 ? "A" : "B", masks[m]->width, masks[m]->height, a->width,
                                  a->height);
    size_t n = (size_t)a->width * (size_t)a->height;
    double sum = 0.0, sum_covered = 0.0, max_error = 0.0;
    size_t both = 0, only_a = 0, only_b = 0;
    for (size_t p = 0; p < n; p++) {
        double e2 = 0.0;
        for (int c = 0; c < 3; c++) {
            double e = (double)channel(a, p, c) - (double)channel(b, p, c);
            e2 += e * e;
            if (fabs(e) > max_error) max_error = fabs(e);
        }
        sum += e2;
        bool ca = covered(a, d.coverage_a, d.background, p);
        bool cb = covered(b, d.coverage_b, d.background, p);
        if (ca && cb) {
            both++;
            sum_covered += e2;
        } else if (ca) {
            only_a++;
        } else if (cb) {
            only_b++;
        }
    }
    meso_compare_result r = {0};
    double mse = sum / (3.0 * (double)n);
    r.psnr = psnr_of(mse);
    r.rmse = sqrt(mse);
    if (both) {
        double mse_covered = sum_covered / (3.0 * (double)both);
        r.psnr_covered = psnr_of(mse_covered);
        r.rmse_covered = sqrt(mse_covered);
    } else {
        r.psnr_covered = NAN;
        r.rmse_covered = NAN;
    }
    r.max_error = max_error;
    r.covered_both = both;
    r.covered_only_a = only_a;
    r.covered_only_b = only_b;
    size_t uni = both + only_a + only_b;
    r.coverage_iou = uni ? (double)both / (double)uni : 1.0;
    meso_result result = compute_ssim(ctx, a, b, &r.ssim);
    if (result != MESO_OK) return result;
    *out_result = r;
    return MESO_OK;
}
