/* Error-vs-time plots as SVG and PNG: each point a (technique, setting) at its median frame
 * time on a logarithmic axis against its PSNR over the covered pixels, the reference's time
 * marked; `meso render --techniques` plots one scene's techniques, `meso sweep` every setting of
 * a scene with the Pareto front drawn. The SVG is plain text; the PNG the same layout drawn with
 * meso's text (cairo). Both are written atomically. */
#include "app.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "meso/runtime.h"

#define PLOT_WIDTH 720
#define PLOT_HEIGHT 460
#define PLOT_LEFT 70 /* margins around the axes, pixels */
#define PLOT_RIGHT 30
#define PLOT_TOP 40
#define PLOT_BOTTOM 60

/* Series colours (a sweep's techniques), cycled. */
static const float series_colors[][3] = {
    {0.12f, 0.37f, 0.66f}, {0.85f, 0.37f, 0.01f}, {0.11f, 0.62f, 0.47f}, {0.46f, 0.44f, 0.70f},
    {0.91f, 0.16f, 0.54f}, {0.40f, 0.65f, 0.12f}, {0.65f, 0.46f, 0.11f}, {0.40f, 0.40f, 0.40f},
    {0.00f, 0.60f, 0.80f}, {0.55f, 0.00f, 0.25f}, {0.80f, 0.70f, 0.00f}, {0.30f, 0.20f, 0.10f},
};
#define NUM_SERIES_COLORS (sizeof(series_colors) / sizeof(series_colors[0]))

static const float *series_color(const app_plot_desc *d, int series) {
    if (!d->pareto || series < 0) return series_colors[0];
    return series_colors[(size_t)series % NUM_SERIES_COLORS];
}

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

static bool point_drawn(const app_plot_point *p) {
    return p->frame_ms > 0.0 && isfinite(p->frame_ms) && isfinite(p->psnr_covered_db);
}

bool app_plot_on_front(const app_plot_point *points, size_t count, size_t i) {
    const app_plot_point *p = &points[i];
    if (!point_drawn(p)) return false;
    for (size_t j = 0; j < count; j++) {
        const app_plot_point *q = &points[j];
        if (j == i || !point_drawn(q)) continue;
        bool no_worse = q->frame_ms <= p->frame_ms && q->psnr_covered_db >= p->psnr_covered_db;
        bool better = q->frame_ms < p->frame_ms || q->psnr_covered_db > p->psnr_covered_db;
        /* equal points: the first one is on the front */
        if (no_worse && (better || j < i)) return false;
    }
    return true;
}

/* Whole decades around every time, steps of 5 dB around every PSNR. False: nothing to plot. */
static bool fit_axes(const app_plot_desc *d, plot_axes *out) {
    double lo_ms = INFINITY, hi_ms = 0.0, lo_db = INFINITY, hi_db = -INFINITY;
    if (d->reference_ms > 0.0) lo_ms = hi_ms = d->reference_ms;
    for (size_t i = 0; i < d->num_points; i++) {
        const app_plot_point *p = &d->points[i];
        if (!(p->frame_ms > 0.0)) continue;
        lo_ms = fmin(lo_ms, p->frame_ms);
        hi_ms = fmax(hi_ms, p->frame_ms);
        if (!isfinite(p->psnr_covered_db)) continue;
        lo_db = fmin(lo_db, p->psnr_covered_db);
        hi_db = fmax(hi_db, p->psnr_covered_db);
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

/* The front's points in order of time (indices into d->points), count returned. */
static size_t front_order(const app_plot_desc *d, size_t *order) {
    size_t count = 0;
    for (size_t i = 0; i < d->num_points; i++)
        if (app_plot_on_front(d->points, d->num_points, i)) order[count++] = i;
    for (size_t i = 1; i < count; i++) /* insertion sort: fronts are short */
        for (size_t j = i; j > 0 && d->points[order[j]].frame_ms < d->points[order[j - 1]].frame_ms;
             j--) {
            size_t t = order[j];
            order[j] = order[j - 1];
            order[j - 1] = t;
        }
    return count;
}

/* Where the front's labels go (top-left corners, pixels; x -1: not drawn): right of the point
 * and above it, else below it, else left of it, whichever first overlaps no label placed before
 * (the front in order of time); a label that fits nowhere is left out, its point still drawn. */
static void place_labels(const app_plot_desc *d, const plot_axes *a, const size_t *front,
                         size_t front_count, int *label_x, int *label_y) {
    for (size_t i = 0; i < d->num_points; i++) label_x[i] = -1;
    for (size_t k = 0; k < front_count; k++) {
        const app_plot_point *p = &d->points[front[k]];
        int x = (int)plot_x(a, p->frame_ms), y = (int)plot_y(a, p->psnr_covered_db);
        int width = 6 * (int)strlen(p->label), height = 12; /* the font's advance and line */
        const int candidates[3][2] = {{x + 7, y - 12}, {x + 7, y + 4}, {x - 7 - width, y - 12}};
        for (int c = 0; c < 3; c++) {
            int cx = candidates[c][0], cy = candidates[c][1];
            bool fits = cx >= 0 && cx + width < PLOT_WIDTH && cy >= PLOT_TOP - 12;
            for (size_t j = 0; j < k && fits; j++) {
                size_t q = front[j];
                if (label_x[q] < 0) continue;
                int qw = 6 * (int)strlen(d->points[q].label);
                fits = cx + width <= label_x[q] || label_x[q] + qw <= cx ||
                       cy + height <= label_y[q] || label_y[q] + height <= cy;
            }
            if (fits) {
                label_x[front[k]] = cx;
                label_y[front[k]] = cy;
                break;
            }
        }
    }
}

static void svg_color(app_text *svg, const float c[3]) {
    app_text_printf(svg, "#%02x%02x%02x", (int)(c[0] * 255.0f + 0.5f), (int)(c[1] * 255.0f + 0.5f),
                    (int)(c[2] * 255.0f + 0.5f));
}

static void svg_points(app_text *svg, const app_plot_desc *d, const plot_axes *axes,
                       const size_t *front, size_t front_count, const int *label_x,
                       const int *label_y) {
    if (d->reference_ms > 0.0) { /* the truth has no error: its time is a line */
        double x = plot_x(axes, d->reference_ms);
        app_text_printf(svg,
                        "<line x1=\"%.1f\" y1=\"%d\" x2=\"%.1f\" y2=\"%d\" stroke=\"#c00\" "
                        "stroke-dasharray=\"6 4\"/>\n"
                        "<text x=\"%.1f\" y=\"%d\" fill=\"#c00\" text-anchor=\"%s\">reference "
                        "%.1f ms</text>\n",
                        x, PLOT_TOP, x, PLOT_HEIGHT - PLOT_BOTTOM,
                        x < PLOT_WIDTH - 140 ? x + 4 : x - 4, PLOT_TOP + 14,
                        x < PLOT_WIDTH - 140 ? "start" : "end", d->reference_ms);
    }
    if (front_count > 1) { /* the staircase: what each time budget buys at best */
        app_text_printf(svg, "<polyline fill=\"none\" stroke=\"#333\" stroke-width=\"1.5\" "
                             "points=\"");
        for (size_t k = 0; k < front_count; k++) {
            const app_plot_point *p = &d->points[front[k]];
            double x = plot_x(axes, p->frame_ms), y = plot_y(axes, p->psnr_covered_db);
            if (k > 0)
                app_text_printf(svg, " %.1f,%.1f", x,
                                plot_y(axes, d->points[front[k - 1]].psnr_covered_db));
            app_text_printf(svg, " %.1f,%.1f", x, y);
        }
        app_text_printf(svg, "\"/>\n");
    }
    for (size_t i = 0; i < d->num_points; i++) {
        const app_plot_point *p = &d->points[i];
        if (!point_drawn(p)) continue;
        double x = plot_x(axes, p->frame_ms), y = plot_y(axes, p->psnr_covered_db);
        app_text_printf(svg, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"4\" fill=\"", x, y);
        svg_color(svg, series_color(d, p->series));
        app_text_printf(svg, "\"/>\n");
        if (d->pareto && label_x[i] < 0) continue;
        if (d->pareto) /* the text's baseline, 10 pixels under its top */
            app_text_printf(svg, "<text x=\"%d\" y=\"%d\">", label_x[i], label_y[i] + 10);
        else
            app_text_printf(svg, "<text x=\"%.1f\" y=\"%.1f\">", x + 7, y - 6);
        app_text_xml(svg, p->label);
        app_text_printf(svg, "</text>\n");
    }
    for (int s = 0; d->pareto && s < d->num_series; s++) { /* the legend */
        /* bottom right: slow and inaccurate, the corner a plot's points least often reach */
        double y = PLOT_HEIGHT - PLOT_BOTTOM - 8 - 14 * (d->num_series - 1 - s);
        app_text_printf(svg, "<circle cx=\"%d\" cy=\"%.1f\" r=\"4\" fill=\"",
                        PLOT_WIDTH - PLOT_RIGHT - 120, y - 4);
        svg_color(svg, series_color(d, s));
        app_text_printf(svg, "\"/>\n<text x=\"%d\" y=\"%.1f\">", PLOT_WIDTH - PLOT_RIGHT - 110, y);
        app_text_xml(svg, d->series_names[s]);
        app_text_printf(svg, "</text>\n");
    }
}

static meso_result write_png(meso_context *ctx, const app_plot_desc *d, const plot_axes *a,
                             const size_t *front, size_t front_count, const int *label_x,
                             const int *label_y, const char *path);

meso_result app_plot_write(meso_context *ctx, const app_plot_desc *desc, const char *path,
                           const char *png_path) {
    plot_axes axes;
    if (!fit_axes(desc, &axes)) { /* no reference, no metrics: no plot, not an old one either */
        if (remove(path) != 0 && errno != ENOENT)
            return meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot remove the stale plot: %s", path,
                                  strerror(errno));
        return MESO_OK;
    }
    size_t *front = calloc(desc->num_points + 1, sizeof(*front));
    if (!front) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", path);
    size_t front_count = desc->pareto ? front_order(desc, front) : 0;
    int *label_x = calloc(2 * desc->num_points + 1, sizeof *label_x);
    if (!label_x) {
        free(front);
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", path);
    }
    int *label_y = label_x + desc->num_points;
    if (desc->pareto) place_labels(desc, &axes, front, front_count, label_x, label_y);
    app_text svg = {0};
    app_text_printf(&svg,
                    "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" "
                    "font-family=\"DejaVu Sans, sans-serif\" font-size=\"12\">\n"
                    "<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n",
                    PLOT_WIDTH, PLOT_HEIGHT);
    draw_axes(&svg, &axes, desc->title);
    svg_points(&svg, desc, &axes, front, front_count, label_x, label_y);
    app_text_printf(&svg, "</svg>\n");
    meso_result result = app_text_write(ctx, &svg, path);
    app_text_free(&svg);
    if (result == MESO_OK)
        result = write_png(ctx, desc, &axes, front, front_count, label_x, label_y, png_path);
    free(label_x);
    free(front);
    return result;
}

meso_result app_plot_error_vs_time(meso_context *ctx, const app_compare_all *all,
                                   const char *scene_name, const char *path, const char *png_path) {
    app_plot_point *points = calloc(all->num_runs + 1, sizeof(*points));
    if (!points) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", path);
    app_plot_desc desc = {.points = points};
    for (size_t i = 0; i < all->num_runs; i++) {
        const app_run *r = &all->runs[i];
        if (!r->rendered || !(r->frame_ms > 0.0)) continue;
        if ((int)i == all->reference) {
            desc.reference_ms = r->frame_ms;
            continue;
        }
        if (!r->has_metrics) continue;
        points[desc.num_points++] = (app_plot_point){.label = r->technique,
                                                     .frame_ms = r->frame_ms,
                                                     .psnr_covered_db = r->metrics.psnr_covered};
    }
    char title[512];
    snprintf(title, sizeof title, "%s: error against the reference vs frame time", scene_name);
    desc.title = title;
    meso_result result = app_plot_write(ctx, &desc, path, png_path);
    free(points);
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

static void png_front(meso_image *image, const app_plot_desc *d, const plot_axes *a,
                      const size_t *front, size_t front_count) {
    static const float dark[3] = {0.2f, 0.2f, 0.2f};
    for (size_t k = 1; k < front_count; k++) { /* horizontal to the next time, then up */
        const app_plot_point *p = &d->points[front[k - 1]], *q = &d->points[front[k]];
        int x0 = (int)plot_x(a, p->frame_ms), x1 = (int)plot_x(a, q->frame_ms);
        int y0 = (int)plot_y(a, p->psnr_covered_db), y1 = (int)plot_y(a, q->psnr_covered_db);
        fill_rect(image, x0, y0, x1, y0 + 1, dark);
        fill_rect(image, x1, y1 < y0 ? y1 : y0, x1 + 1, y1 < y0 ? y0 : y1, dark);
    }
}

static meso_result write_png(meso_context *ctx, const app_plot_desc *d, const plot_axes *a,
                             const size_t *front, size_t front_count, const int *label_x,
                             const int *label_y, const char *path) {
    static const float white[3] = {1, 1, 1}, black[3] = {0.15f, 0.15f, 0.15f},
                       grid[3] = {0.87f, 0.87f, 0.87f}, red[3] = {0.8f, 0.0f, 0.0f};
    meso_image *image = NULL;
    meso_result result = meso_image_create(ctx, PLOT_WIDTH, PLOT_HEIGHT, 3, &image);
    if (result != MESO_OK) return result;
    fill_rect(image, 0, 0, PLOT_WIDTH - 1, PLOT_HEIGHT - 1, white);
    int x0 = PLOT_LEFT, x1 = PLOT_WIDTH - PLOT_RIGHT, y0 = PLOT_HEIGHT - PLOT_BOTTOM, y1 = PLOT_TOP;
    char text[64];
    for (double dec = a->log_min; dec <= a->log_max + 1e-9; dec += 1.0) {
        int x = (int)plot_x(a, pow(10.0, dec));
        fill_rect(image, x, y1, x, y0, grid);
        snprintf(text, sizeof text, "%g", pow(10.0, dec));
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
    meso_image_draw_text(image, x0, 8, 1, black, d->title);
    meso_image_draw_text(image, x0 + 120, PLOT_HEIGHT - 24, 1, black,
                         "median frame time, ms (log scale)");
    meso_image_draw_text(image, 4, y1 - 14, 1, black, "PSNR covered, dB");
    if (d->reference_ms > 0.0) {
        int x = (int)plot_x(a, d->reference_ms);
        for (int y = y1; y < y0; y += 10) fill_rect(image, x, y, x, y + 5, red);
        snprintf(text, sizeof text, "reference %.1f ms", d->reference_ms);
        int width = 6 * (int)strlen(text);
        meso_image_draw_text(image, x + 4 + width < PLOT_WIDTH ? x + 4 : x - 4 - width, y1 + 4, 1,
                             red, text);
    }
    png_front(image, d, a, front, front_count);
    for (size_t i = 0; i < d->num_points; i++) {
        const app_plot_point *p = &d->points[i];
        if (!point_drawn(p)) continue;
        int x = (int)plot_x(a, p->frame_ms);
        double y = plot_y(a, p->psnr_covered_db);
        fill_disc(image, x, y, 4, series_color(d, p->series));
        if (d->pareto) {
            if (label_x[i] >= 0)
                meso_image_draw_text(image, label_x[i], label_y[i], 1, black, p->label);
            continue;
        }
        int width = 6 * (int)strlen(p->label); /* the font's advance is 6 pixels */
        int at = x + 7 + width < x1 ? x + 7 : x - 7 - width;
        meso_image_draw_text(image, at, (int)y - 12, 1, black, p->label);
    }
    for (int s = 0; d->pareto && s < d->num_series; s++) { /* the legend */
        int y = PLOT_HEIGHT - PLOT_BOTTOM - 12 - 14 * (d->num_series - 1 - s);
        fill_disc(image, x1 - 120, y, 4, series_color(d, s));
        meso_image_draw_text(image, x1 - 110, y - 5, 1, black, d->series_names[s]);
    }
    meso_png_desc srgb = {.encoding = MESO_ENCODING_SRGB};
    result = meso_image_save_png(ctx, image, path, &srgb);
    meso_image_destroy(image);
    return result;
}
