/* False-colour difference images and labelled sheets (include/meso/compare.h). */
#include <stdlib.h>
#include <string.h>

#include "compare_internal.h"
#include "meso/runtime.h"

static float colour_channel(const meso_image *image, int x, int y, int c) {
    const float *p = meso_image_at(image, x, y);
    return p[image->channels >= 3 ? c : 0];
}

/* black -> blue -> green -> yellow -> red as t goes 0 -> 1 (clamped) */
static void false_colour(float t, float out[3]) {
    static const float stops[5][3] = {{0, 0, 0}, {0, 0, 1}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}};
    t = t < 0.0f ? 0.0f : (t > 1.0f ? 1.0f : t);
    float s = t * 4.0f;
    int i = (int)s;
    if (i >= 4) i = 3;
    float f = s - (float)i;
    for (int c = 0; c < 3; c++) out[c] = stops[i][c] + (stops[i + 1][c] - stops[i][c]) * f;
}

meso_result meso_image_diff(meso_context *ctx, const meso_image *a, const meso_image *b,
                            float full_scale, meso_image **out_image) {
    *out_image = NULL;
    if (!a || !b)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "compare: diff: missing image");
    if (a->width != b->width || a->height != b->height)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "compare: the images differ in size: %dx%d and %dx%d", a->width,
                              a->height, b->width, b->height);
    if (!(full_scale > 0.0f)) full_scale = 0.25f;
    meso_image *out = NULL;
    meso_result result = meso_image_create(ctx, a->width, a->height, 3, &out);
    if (result != MESO_OK) return result;
    for (int y = 0; y < a->height; y++)
        for (int x = 0; x < a->width; x++) {
            float e = 0.0f;
            for (int c = 0; c < 3; c++)
                e += fabsf(colour_channel(a, x, y, c) - colour_channel(b, x, y, c));
            false_colour(e / 3.0f / full_scale, meso_image_at(out, x, y));
        }
    *out_image = out;
    return MESO_OK;
}

enum { SHEET_PAD = 8 };

/* The layout of a sheet of `count` cells of cell_w x cell_h with labels label_h high. */
typedef struct sheet_layout {
    int cols, step_x, step_y;
    long width, height;
} sheet_layout;

static meso_result sheet_lay_out(meso_context *ctx, size_t count, int columns, int cell_w,
                                 int cell_h, int label_h, sheet_layout *out) {
    if (count > 4096)
        return meso_log_error(ctx, MESO_ERROR_LIMIT, "sheet: %zu images exceed the limit 4096",
                              count);
    int cols = columns > 0 ? columns : (int)count;
    if ((size_t)cols > count) cols = (int)count;
    int rows = (int)((count + (size_t)cols - 1) / (size_t)cols);
    int step_x = cell_w + SHEET_PAD, step_y = cell_h + label_h + 2 * SHEET_PAD;
    long width = (long)cols * step_x + SHEET_PAD, height = (long)rows * step_y + SHEET_PAD;
    if (width > MESO_IMAGE_MAX_SIDE || height > MESO_IMAGE_MAX_SIDE)
        return meso_log_error(ctx, MESO_ERROR_LIMIT,
                              "sheet: %ldx%ld pixels exceed the limit %d a side", width, height,
                              MESO_IMAGE_MAX_SIDE);
    *out = (sheet_layout){cols, step_x, step_y, width, height};
    return MESO_OK;
}

/* Labels at twice the font size on cells wide enough, so they stay readable. */
static int label_scale(int cell_w) { return cell_w >= 256 ? 2 : 1; }

meso_result meso_compare_sheet_size(meso_context *ctx, size_t count, int columns, int cell_width,
                                    int cell_height, int label_lines, int *out_width,
                                    int *out_height) {
    *out_width = *out_height = 0;
    if (count == 0 || cell_width < 1 || cell_height < 1)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "sheet: no images");
    sheet_layout layout;
    meso_result r =
        sheet_lay_out(ctx, count, columns, cell_width, cell_height,
                      label_lines * COMPARE_FONT_LINE * label_scale(cell_width), &layout);
    if (r != MESO_OK) return r;
    *out_width = (int)layout.width;
    *out_height = (int)layout.height;
    return MESO_OK;
}

meso_result meso_compare_sheet_create(meso_context *ctx, const meso_image *const *images,
                                      const char *const *labels, size_t count, int columns,
                                      meso_image **out_image) {
    *out_image = NULL;
    if (!images || count == 0)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "sheet: no images");
    int cell_w = 1, cell_h = 1, label_h = 0;
    for (size_t i = 0; i < count; i++) {
        if (images[i]) {
            cell_w = images[i]->width > cell_w ? images[i]->width : cell_w;
            cell_h = images[i]->height > cell_h ? images[i]->height : cell_h;
        }
    }
    int scale = label_scale(cell_w);
    for (size_t i = 0; i < count; i++) {
        int tw, th;
        compare_text_size(labels ? labels[i] : NULL, scale, &tw, &th);
        label_h = th > label_h ? th : label_h;
    }
    sheet_layout layout;
    meso_result laid_out = sheet_lay_out(ctx, count, columns, cell_w, cell_h, label_h, &layout);
    if (laid_out != MESO_OK) return laid_out;
    int cols = layout.cols, step_x = layout.step_x, step_y = layout.step_y;
    long width = layout.width, height = layout.height;
    meso_image *sheet = NULL;
    meso_result result = meso_image_create(ctx, (int)width, (int)height, 3, &sheet);
    if (result != MESO_OK) return result;
    size_t n = (size_t)width * (size_t)height * 3;
    for (size_t i = 0; i < n; i++) sheet->pixels[i] = 0.12f;
    const float white[3] = {1.0f, 1.0f, 1.0f};
    for (size_t i = 0; i < count; i++) {
        int x0 = SHEET_PAD + (int)(i % (size_t)cols) * step_x;
        int y0 = SHEET_PAD + (int)(i / (size_t)cols) * step_y;
        const meso_image *image = images[i];
        if (image)
            for (int y = 0; y < image->height; y++)
                for (int x = 0; x < image->width; x++) {
                    float *p = meso_image_at(sheet, x0 + x, y0 + y);
                    for (int c = 0; c < 3; c++) p[c] = colour_channel(image, x, y, c);
                }
        if (labels && labels[i])
            meso_image_draw_text(sheet, x0, y0 + cell_h + SHEET_PAD / 2, scale, white, labels[i]);
    }
    *out_image = sheet;
    return MESO_OK;
}
