/* error-vs-time.svg and .png: the picture that answers "which technique should I use": each
 * technique a labelled point, its median frame time on a logarithmic axis against its PSNR over
 * the covered pixels, and the reference's time marked. The SVG is plain text; the PNG the same
 * layout drawn with meso's bitmap font. Both are written atomically. */
#include "app.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#define PLOT_WIDTH 720
#define PLOT_HEIGHT 460
#define PLOT_LEFT 70 /* margins around the axes, pixels */
#define PLOT_RIGHT 30
#define PLOT_TOP 40
#define PLOT_BOTTOM 60

typedef struct plot_axes {
    double log_min, log_max; /* decades of milliseconds */
    double psnr_min, psnr_max;
} plot_axes;

static double plot_x(const plot_axes *a, double ms) {
    double t = (log10(ms) - a->log_min) / (a->log_max - a->log_min);
    return PLOT_LEFT + t * (PLOT_WIDTH - PLOT_LEFT - PLOT_RIGHT);
}

static double plot_y(const plot_axes *a, double psnr) {
    double t = (psnr - a->psnr_min) / (a->psnr_max - a->psnr_min);
    return PLOT_HEIGHT - PLOT_BOTTOM - t * (PLOT_HEIGHT - PLOT_TOP - PLOT_BOTTOM);
}

/* Whole decades around every time, steps of 5 dB around every PSNR. False: nothing to plot. */
static bool fit_axes(const app_compare_all *all, plot_axes *out) {
    double lo_ms = INFINITY, hi_ms = 0.0, lo_db = INFINITY, hi_db = -INFINITY;
    for (size_t i = 0; i < all->num_runs; i++) {
        const app_run *r = &all->runs[i];
        bool is_reference = (int)i == all->reference;
        if (!r->rendered || !(r->frame_ms > 0.0) || (!is_reference && !r->has_metrics)) continue;
        lo_ms = fmin(lo_ms, r->frame_ms);
        hi_ms = fmax(hi_ms, r->frame_ms);
        if (is_reference || !isfinite(r->metrics.psnr_covered)) continue;
        lo_db = fmin(lo_db, r->metrics.psnr_covered);
        hi_db = fmax(hi_db, r->metrics.psnr_covered);
    }
    if (!(hi_ms > 0.0) || !isfinite(lo_db)) return false;
    out->log_min = floor(log10(lo_ms));
    out->log_max = ceil(log10(hi_ms));
    if (out->log_max <= out->log_min) out->log_max = out->log_min + 1.0;
    out->psnr_min = 5.0 * floor(lo_db / 5.0);
    out->psnr_max = 5.0 * ceil(hi_db / 5.0);
    if (out->psnr_max <= out->psnr_min) out->psnr_max = out->psnr_min + 5.0;
    return true;
}

static void draw_axes(app_text *svg, const plot_axes *a, const char *title) {
    double x0 = PLOT_LEFT, x1 = PLOT_WIDTH - PLOT_RIGHT;
    double y0 = PLOT_HEIGHT - PLOT_BOTTOM, y1 = PLOT_TOP;
    app_text_printf(svg, "<text x=\"%d\" y=\"24\" font-size=\"15\">", PLOT_LEFT);
    app_text_xml(svg, title);
    app_text_printf(svg, "</text>\n");
    app_text_printf(svg,
                    "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"none\" "
                    "stroke=\"#444\"/>\n",
                    x0, y1, x1 - x0, y0 - y1);
    for (double d = a->log_min; d <= a->log_max + 1e-9; d += 1.0) {
        double x = plot_x(a, pow(10.0, d));
        app_text_printf(svg,
                        "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#ddd\"/>\n"
                        "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">%g</text>\n",
                        x, y1, x, y0, x, y0 + 18, pow(10.0, d));
    }
    for (double db = a->psnr_min; db <= a->psnr_max + 1e-9; db += 5.0) {
        double y = plot_y(a, db);
        app_text_printf(svg,
                        "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#ddd\"/>\n"
                        "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\">%g</text>\n",
                        x0, y, x1, y, x0 - 6, y + 4, db);
    }
    app_text_printf(svg,
                    "<text x=\"%.1f\" y=\"%d\" text-anchor=\"middle\">median frame time, ms (log "
                    "scale)</text>\n"
                    "<text x=\"18\" y=\"%.1f\" text-anchor=\"middle\" "
                    "transform=\"rotate(-90 18 %.1f)\">PSNR over covered pixels, dB</text>\n",
                    0.5 * (x0 + x1), PLOT_HEIGHT - 16, 0.5 * (y0 + y1), 0.5 * (y0 + y1));
}

static meso_result write_png(meso_context *ctx, const app_compare_all *all, const plot_axes *a,
                             const char *title, const char *path);

meso_result app_plot_error_vs_time(meso_context *ctx, const app_compare_all *all,
                                   const char *scene_name, const char *path, const char *png_path) {
    plot_axes axes;
    if (!fit_axes(all, &axes)) { /* no reference, no metrics: no plot, not an old one either */
        if (remove(path) != 0 && errno != ENOENT)
            return meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot remove the stale plot: %s", path,
                                  strerror(errno));
        return MESO_OK;
    }
    app_text svg = {0};
    app_text_printf(&svg,
                    "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" "
                    "font-family=\"DejaVu Sans, sans-serif\" font-size=\"12\">\n"
                    "<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n",
                    PLOT_WIDTH, PLOT_HEIGHT);
    char title[512];
    snprintf(title, sizeof title, "%s: error against the reference vs frame time", scene_name);
    draw_axes(&svg, &axes, title);
    for (size_t i = 0; i < all->num_runs; i++) {
        const app_run *r = &all->runs[i];
        if (!r->rendered || !(r->frame_ms > 0.0)) continue;
        double x = plot_x(&axes, r->frame_ms);
        if ((int)i == all->reference) { /* the truth has no error: its time is a line */
            app_text_printf(&svg,
                            "<line x1=\"%.1f\" y1=\"%d\" x2=\"%.1f\" y2=\"%d\" stroke=\"#c00\" "
                            "stroke-dasharray=\"6 4\"/>\n"
                            "<text x=\"%.1f\" y=\"%d\" fill=\"#c00\">reference %.1f ms</text>\n",
                            x, PLOT_TOP, x, PLOT_HEIGHT - PLOT_BOTTOM, x + 4,
                            PLOT_HEIGHT - PLOT_BOTTOM - 8, r->frame_ms);
            continue;
        }
        if (!r->has_metrics || !isfinite(r->metrics.psnr_covered)) continue;
        double y = plot_y(&axes, r->metrics.psnr_covered);
        app_text_printf(&svg,
                        "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"4\" fill=\"#1f5fa8\"/>\n"
                        "<text x=\"%.1f\" y=\"%.1f\">",
                        x, y, x + 7, y - 6);
        app_text_xml(&svg, r->technique);
        app_text_printf(&svg, "</text>\n");
    }
    app_text_printf(&svg, "</svg>\n");
    meso_result result = app_text_write(ctx, &svg, path);
    app_text_free(&svg);
    if (result == MESO_OK) result = write_png(ctx, all, &axes, title, png_path);
    return result;
}

/* ---- The PNG ------------------------------------------------------------------------------ */

static void fill_rect(meso_image *image, int x0, int y0, int x1, int y1, const float color[3]) {
    for (int y = y0 < 0 ? 0 : y0; y <= y1 && y < image->height; y++)
        for (int x = x0 < 0 ? 0 : x0; x <= x1 && x < image->width; x++)
            memcpy(meso_image_at(image, x, y), color, 3 * sizeof(float));
}

static void fill_disc(meso_image *image, double cx, double cy, int radius, const float color[3]) {
    for (int dy = -radius; dy <= radius; dy++)
        for (int dx = -radius; dx <= radius; dx++)
            if (dx * dx + dy * dy <= radius * radius)
                fill_rect(image, (int)cx + dx, (int)cy + dy, (int)cx + dx, (int)cy + dy, color);
}

static meso_result write_png(meso_context *ctx, const app_compare_all *all, const plot_axes *a,
                             const char *title, const char *path) {
    static const float white[3] = {1, 1, 1}, black[3] = {0.15f, 0.15f, 0.15f},
                       grid[3] = {0.87f, 0.87f, 0.87f}, blue[3] = {0.12f, 0.37f, 0.66f},
                       red[3] = {0.8f, 0.0f, 0.0f};
    meso_image *image = NULL;
    meso_result result = meso_image_create(ctx, PLOT_WIDTH, PLOT_HEIGHT, 3, &image);
    if (result != MESO_OK) return result;
    fill_rect(image, 0, 0, PLOT_WIDTH - 1, PLOT_HEIGHT - 1, white);
    int x0 = PLOT_LEFT, x1 = PLOT_WIDTH - PLOT_RIGHT, y0 = PLOT_HEIGHT - PLOT_BOTTOM, y1 = PLOT_TOP;
    char text[64];
    for (double d = a->log_min; d <= a->log_max + 1e-9; d += 1.0) {
        int x = (int)plot_x(a, pow(10.0, d));
        fill_rect(image, x, y1, x, y0, grid);
        snprintf(text, sizeof text, "%g", pow(10.0, d));
        meso_image_draw_text(image, x - 3 * (int)strlen(text), y0 + 8, 1, black, text);
    }
    for (double db = a->psnr_min; db <= a->psnr_max + 1e-9; db += 5.0) {
        int y = (int)plot_y(a, db);
        fill_rect(image, x0, y, x1, y, grid);
        snprintf(text, sizeof text, "%g", db);
        meso_image_draw_text(image, x0 - 8 - 6 * (int)strlen(text), y - 3, 1, black, text);
    }
    fill_rect(image, x0, y1, x1, y1, black); /* the frame */
    fill_rect(image, x0, y0, x1, y0, black);
    fill_rect(image, x0, y1, x0, y0, black);
    fill_rect(image, x1, y1, x1, y0, black);
    meso_image_draw_text(image, x0, 8, 1, black, title);
    meso_image_draw_text(image, x0 + 120, PLOT_HEIGHT - 24, 1, black,
                         "median frame time, ms (log scale)");
    meso_image_draw_text(image, 4, y1 - 14, 1, black, "PSNR covered, dB");
    for (size_t i = 0; i < all->num_runs; i++) {
        const app_run *r = &all->runs[i];
        if (!r->rendered || !(r->frame_ms > 0.0)) continue;
        int x = (int)plot_x(a, r->frame_ms);
        if ((int)i == all->reference) {
            for (int y = y1; y < y0; y += 10) fill_rect(image, x, y, x, y + 5, red);
            snprintf(text, sizeof text, "reference %.1f ms", r->frame_ms);
            meso_image_draw_text(image, x + 4, y0 - 14, 1, red, text);
            continue;
        }
        if (!r->has_metrics || !isfinite(r->metrics.psnr_covered)) continue;
        double y = plot_y(a, r->metrics.psnr_covered);
        fill_disc(image, x, y, 4, blue);
        int width = 6 * (int)strlen(r->technique); /* the font's advance is 6 pixels */
        int label_x = x + 7 + width < x1 ? x + 7 : x - 7 - width;
        meso_image_draw_text(image, label_x, (int)y - 12, 1, black, r->technique);
    }
    meso_png_desc srgb = {.encoding = MESO_ENCODING_SRGB};
    result = meso_image_save_png(ctx, image, path, &srgb);
    meso_image_destroy(image);
    return result;
}
