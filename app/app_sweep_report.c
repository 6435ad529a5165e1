/* A sweep's results: each job's result.json, and the reports built from all of them (the same
 * for one process and for merged shards, since both read the jobs' result.json files):
 * results.csv, results.json, a plot per scene and size with its Pareto front, index.html. */
#include "app_sweep.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "meso/runtime.h"

/* ---- result.json -------------------------------------------------------------------------- */

/* A double that reads back to the same bits; infinities as strings, NaN as null (JSON has
 * neither). */
static void exact_number(app_text *t, const char *name, double v) {
    app_text_printf(t, ",\n  \"%s\": ", name);
    if (isnan(v))
        app_text_printf(t, "null");
    else if (isinf(v))
        app_text_printf(t, "\"%s\"", v > 0 ? "inf" : "-inf");
    else
        app_text_printf(t, "%.17g", v);
}

static void string_field(app_text *t, const char *name, const char *value) {
    app_text_printf(t, ",\n  \"%s\": ", name);
    app_text_json_string(t, value);
}

void app_sweep_row_json(const sweep_row *row, const char *spec_hash, app_text *t) {
    app_text_printf(t, "{\n  \"spec_hash\": \"%s\",\n  \"id\": %d", spec_hash, row->id);
    string_field(t, "key", row->key);
    string_field(t, "scene", row->scene);
    string_field(t, "technique", row->technique);
    string_field(t, "options", row->options);
    app_text_printf(t,
                    ",\n  \"width\": %d,\n  \"height\": %d,\n  \"samples\": %d,\n  \"views\": %d",
                    row->width, row->height, row->samples, row->views);
    string_field(t, "status", row->status);
    string_field(t, "note", row->note);
    exact_number(t, "prepare_ms", row->prepare_ms);
    exact_number(t, "frame_ms", row->frame_ms);
    exact_number(t, "reference_ms", row->reference_ms);
    exact_number(t, "job_seconds", row->job_seconds);
    app_text_printf(t, ",\n  \"has_metrics\": %s", row->has_metrics ? "true" : "false");
    exact_number(t, "psnr_db", row->psnr_db);
    exact_number(t, "psnr_covered_db", row->psnr_covered_db);
    exact_number(t, "rmse", row->rmse);
    exact_number(t, "rmse_covered", row->rmse_covered);
    exact_number(t, "ssim", row->ssim);
    exact_number(t, "max_error", row->max_error);
    exact_number(t, "coverage_iou", row->coverage_iou);
    exact_number(t, "flicker", row->flicker);
    app_text_printf(t, "\n}\n");
}

static bool read_number(const cJSON *root, const char *name, double *out) {
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(root, name);
    if (cJSON_IsNumber(item))
        *out = item->valuedouble;
    else if (cJSON_IsNull(item))
        *out = NAN;
    else if (cJSON_IsString(item) && strcmp(item->valuestring, "inf") == 0)
        *out = INFINITY;
    else if (cJSON_IsString(item) && strcmp(item->valuestring, "-inf") == 0)
        *out = -INFINITY;
    else
        return false;
    return true;
}

static bool read_string(const cJSON *root, const char *name, char *out, size_t size) {
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(root, name);
    if (!cJSON_IsString(item) || strlen(item->valuestring) >= size) return false;
    memcpy(out, item->valuestring, strlen(item->valuestring) + 1);
    return true;
}

static bool read_int(const cJSON *root, const char *name, int *out) {
    double v = NAN;
    if (!read_number(root, name, &v) || !(v >= 0 && v <= 1e9) || v != floor(v)) return false;
    *out = (int)v;
    return true;
}

meso_result app_sweep_row_read(meso_context *ctx, const char *path, sweep_row *row,
                               char out_hash[17]) {
    *row = (sweep_row){0};
    out_hash[0] = 0;
    char *text = NULL;
    meso_result r = meso_file_read(ctx, path, 1u << 20, &text, NULL);
    if (r != MESO_OK) return r;
    cJSON *root = cJSON_Parse(text);
    free(text);
    const cJSON *metrics = root ? cJSON_GetObjectItemCaseSensitive(root, "has_metrics") : NULL;
    bool ok =
        root && cJSON_IsBool(metrics) && read_string(root, "spec_hash", out_hash, 17) &&
        read_int(root, "id", &row->id) && read_string(root, "key", row->key, sizeof row->key) &&
        read_string(root, "scene", row->scene, sizeof row->scene) &&
        read_string(root, "technique", row->technique, sizeof row->technique) &&
        read_string(root, "options", row->options, sizeof row->options) &&
        read_int(root, "width", &row->width) && read_int(root, "height", &row->height) &&
        read_int(root, "samples", &row->samples) && read_int(root, "views", &row->views) &&
        read_string(root, "status", row->status, sizeof row->status) &&
        read_string(root, "note", row->note, sizeof row->note) &&
        read_number(root, "prepare_ms", &row->prepare_ms) &&
        read_number(root, "frame_ms", &row->frame_ms) &&
        read_number(root, "reference_ms", &row->reference_ms) &&
        read_number(root, "job_seconds", &row->job_seconds) &&
        read_number(root, "psnr_db", &row->psnr_db) &&
        read_number(root, "psnr_covered_db", &row->psnr_covered_db) &&
        read_number(root, "rmse", &row->rmse) &&
        read_number(root, "rmse_covered", &row->rmse_covered) &&
        read_number(root, "ssim", &row->ssim) && read_number(root, "max_error", &row->max_error) &&
        read_number(root, "coverage_iou", &row->coverage_iou) &&
        read_number(root, "flicker", &row->flicker);
    if (ok) row->has_metrics = cJSON_IsTrue(metrics);
    cJSON_Delete(root);
    if (!ok)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: not a job's result.json",
                              path);
    return MESO_OK;
}

/* ---- results.csv and results.json --------------------------------------------------------- */

/* The columns of the tables, in order; the timing columns are prepare_ms, frame_ms,
 * reference_ms and job_s. */
typedef enum column_kind { COLUMN_INT, COLUMN_TEXT, COLUMN_NUMBER } column_kind;
typedef struct column {
    const char *name;
    column_kind kind;
    const char *format; /* numbers in the CSV and the page */
} column;

static const column columns[] = {
    {"id", COLUMN_INT, NULL},
    {"scene", COLUMN_TEXT, NULL},
    {"size", COLUMN_TEXT, NULL},
    {"technique", COLUMN_TEXT, NULL},
    {"options", COLUMN_TEXT, NULL},
    {"samples", COLUMN_INT, NULL},
    {"views", COLUMN_INT, NULL},
    {"status", COLUMN_TEXT, NULL},
    {"prepare_ms", COLUMN_NUMBER, "%.3f"},
    {"frame_ms", COLUMN_NUMBER, "%.3f"},
    {"reference_ms", COLUMN_NUMBER, "%.3f"},
    {"job_s", COLUMN_NUMBER, "%.3f"},
    {"psnr_db", COLUMN_NUMBER, "%.4f"},
    {"psnr_covered_db", COLUMN_NUMBER, "%.4f"},
    {"rmse", COLUMN_NUMBER, "%.6f"},
    {"rmse_covered", COLUMN_NUMBER, "%.6f"},
    {"ssim", COLUMN_NUMBER, "%.5f"},
    {"max_error", COLUMN_NUMBER, "%.5f"},
    {"coverage_iou", COLUMN_NUMBER, "%.5f"},
    {"flicker", COLUMN_NUMBER, "%.6f"},
};
#define NUM_COLUMNS (sizeof columns / sizeof columns[0])

/* Column c of a row: an int, a text or a number (NAN: none). */
static void cell(const sweep_row *row, size_t c, long *i, const char **text, double *number,
                 char *size_text) {
    *i = 0;
    *text = NULL;
    *number = NAN;
    bool m = row->has_metrics;
    bool ok = strcmp(row->status, "ok") == 0;
    const char *name = columns[c].name;
    /* text and whole-number columns */
    if (!strcmp(name, "id")) *i = row->id;
    if (!strcmp(name, "scene")) *text = row->scene;
    if (!strcmp(name, "size")) {
        snprintf(size_text, 32, "%dx%d", row->width, row->height);
        *text = size_text;
    }
    if (!strcmp(name, "technique")) *text = row->technique;
    if (!strcmp(name, "options")) *text = row->options;
    if (!strcmp(name, "samples")) *i = row->samples;
    if (!strcmp(name, "views")) *i = row->views;
    if (!strcmp(name, "status")) *text = row->status;
    /* timing: blank for a failed job */
    if (!strcmp(name, "prepare_ms") && ok) *number = row->prepare_ms;
    if (!strcmp(name, "frame_ms") && ok) *number = row->frame_ms;
    if (!strcmp(name, "reference_ms") && row->reference_ms > 0) *number = row->reference_ms;
    if (!strcmp(name, "job_s")) *number = row->job_seconds;
    /* metrics: blank without the reference */
    static const struct {
        const char *name;
        size_t offset;
    } metrics[] = {
        {"psnr_db", offsetof(sweep_row, psnr_db)},
        {"psnr_covered_db", offsetof(sweep_row, psnr_covered_db)},
        {"rmse", offsetof(sweep_row, rmse)},
        {"rmse_covered", offsetof(sweep_row, rmse_covered)},
        {"ssim", offsetof(sweep_row, ssim)},
        {"max_error", offsetof(sweep_row, max_error)},
        {"coverage_iou", offsetof(sweep_row, coverage_iou)},
        {"flicker", offsetof(sweep_row, flicker)},
    };
    for (size_t k = 0; k < sizeof metrics / sizeof metrics[0]; k++)
        if (m && !strcmp(name, metrics[k].name))
            memcpy(number, (const char *)row + metrics[k].offset, sizeof *number);
}

static void format_number(char *out, size_t size, const char *format, double v) {
    if (isnan(v))
        out[0] = 0;
    else if (isinf(v))
        snprintf(out, size, "%s", v > 0 ? "inf" : "-inf");
    else
        snprintf(out, size, format, v);
}

static void csv_text(app_text *t, const char *s) { /* quoted, quotes doubled (RFC 4180) */
    app_text_printf(t, "\"");
    for (const char *p = s; *p; p++) app_text_printf(t, *p == '"' ? "\"\"" : "%c", *p);
    app_text_printf(t, "\"");
}

static void write_csv(const sweep_row *rows, size_t count, app_text *t) {
    for (size_t c = 0; c < NUM_COLUMNS; c++) app_text_printf(t, "%s,", columns[c].name);
    app_text_printf(t, "image,note\n");
    for (size_t r = 0; r < count; r++) {
        for (size_t c = 0; c < NUM_COLUMNS; c++) {
            long i;
            const char *text;
            double number;
            char size_text[32], value[64];
            cell(&rows[r], c, &i, &text, &number, size_text);
            if (columns[c].kind == COLUMN_INT)
                app_text_printf(t, "%ld,", i);
            else if (columns[c].kind == COLUMN_TEXT)
                csv_text(t, text), app_text_printf(t, ",");
            else {
                format_number(value, sizeof value, columns[c].format, number);
                app_text_printf(t, "%s,", value);
            }
        }
        app_text_printf(t, "jobs/%s/view-0000.png,", rows[r].key);
        csv_text(t, rows[r].note);
        app_text_printf(t, "\n");
    }
}

static void write_json(const sweep_row *rows, size_t count, const char *hash, app_text *t) {
    app_text_printf(t, "{\n  \"spec_hash\": \"%s\",\n  \"jobs\": [", hash);
    for (size_t r = 0; r < count; r++) {
        app_text_printf(t, "%s\n    {", r ? "," : "");
        for (size_t c = 0; c < NUM_COLUMNS; c++) {
            long i;
            const char *text;
            double number;
            char size_text[32];
            cell(&rows[r], c, &i, &text, &number, size_text);
            app_text_printf(t, "%s\"%s\": ", c ? ", " : "", columns[c].name);
            if (columns[c].kind == COLUMN_INT)
                app_text_printf(t, "%ld", i);
            else if (columns[c].kind == COLUMN_TEXT)
                app_text_json_string(t, text);
            else
                app_text_json_number(t, number);
        }
        char image[SWEEP_KEY_MAX + 32];
        snprintf(image, sizeof image, "jobs/%s/view-0000.png", rows[r].key);
        app_text_printf(t, ", \"image\": ");
        app_text_json_string(t, image);
        app_text_printf(t, ", \"note\": ");
        app_text_json_string(t, rows[r].note);
        app_text_printf(t, "}");
    }
    app_text_printf(t, "\n  ]\n}\n");
}

/* ---- Plots -------------------------------------------------------------------------------- */

/* A point's label: the technique, a space and its options. */
#define SWEEP_LABEL_MAX (MESO_NAME_MAX + 1 + 256)

/* Whether rows a and b belong to one plot (scene and size). */
static bool same_group(const sweep_row *a, const sweep_row *b) {
    return strcmp(a->scene, b->scene) == 0 && a->width == b->width && a->height == b->height;
}

static meso_result write_plot(meso_context *ctx, const char *dir, const sweep_row *rows,
                              size_t count, size_t first, char (*labels)[SWEEP_LABEL_MAX],
                              app_plot_point *points) {
    const char *series[SWEEP_MAX_TECHNIQUES];
    int num_series = 0;
    app_plot_desc desc = {.points = points, .pareto = true, .series_names = series};
    for (size_t r = first; r < count; r++) {
        const sweep_row *row = &rows[r];
        if (!same_group(row, &rows[first])) continue;
        if (row->reference_ms > 0) desc.reference_ms = row->reference_ms;
        if (!row->has_metrics) continue;
        int s = 0;
        while (s < num_series && strcmp(series[s], row->technique) != 0) s++;
        if (s == num_series && num_series < SWEEP_MAX_TECHNIQUES)
            series[num_series++] = row->technique;
        size_t p = desc.num_points++;
        snprintf(labels[p], SWEEP_LABEL_MAX, "%s%s%s", row->technique, row->options[0] ? " " : "",
                 row->options);
        points[p] = (app_plot_point){.label = labels[p],
                                     .frame_ms = row->frame_ms,
                                     .psnr_covered_db = row->psnr_covered_db,
                                     .series = s};
    }
    desc.num_series = num_series;
    char title[512], name[400], svg[4096], png[4096];
    snprintf(title, sizeof title, "%s %dx%d: error against the reference vs frame time",
             rows[first].scene, rows[first].width, rows[first].height);
    desc.title = title;
    snprintf(name, sizeof name, "%s-%dx%d", rows[first].scene, rows[first].width,
             rows[first].height);
    if (snprintf(svg, sizeof svg, "%s/plots/%s.svg", dir, name) >= (int)sizeof svg ||
        snprintf(png, sizeof png, "%s/plots/%s.png", dir, name) >= (int)sizeof png)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: path too long", dir);
    return app_plot_write(ctx, &desc, svg, png);
}

/* The first row of each scene and size, in order. */
static bool group_start(const sweep_row *rows, size_t r) {
    for (size_t k = 0; k < r; k++)
        if (same_group(&rows[k], &rows[r])) return false;
    return true;
}

static meso_result write_plots(meso_context *ctx, const char *dir, const sweep_row *rows,
                               size_t count) {
    char plots[4096];
    if (!app_path_join(plots, sizeof plots, dir, "plots"))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: path too long", dir);
    meso_result r = app_make_dir(ctx, plots);
    char(*labels)[SWEEP_LABEL_MAX] = calloc(count, sizeof *labels);
    app_plot_point *points = calloc(count, sizeof *points);
    if (r == MESO_OK && (!labels || !points))
        r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", dir);
    for (size_t i = 0; i < count && r == MESO_OK; i++)
        if (group_start(rows, i)) r = write_plot(ctx, dir, rows, count, i, labels, points);
    free(labels);
    free(points);
    return r;
}

/* ---- index.html --------------------------------------------------------------------------- */

/* The page's script and style: sorting by any column (a click on its head, or the URL's
 * #sort=COLUMN or #sort=COLUMN:desc), each job's image over the truth with a swipe slider and a
 * flip button, and a check that every image loaded and no script failed, written into the
 * body's data-broken-images and data-script-errors for tests and readers. */
static const char page_head[] =
    "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n"
    "<title>meso sweep</title>\n<style>\n"
    "body{font-family:sans-serif;margin:1em 2em;color:#222}\n"
    "table{border-collapse:collapse;font-size:13px;white-space:nowrap}\n"
    "th,td{border:1px solid #ccc;padding:2px 6px;text-align:right}\n"
    "td.t{text-align:left}\n"
    "th{cursor:pointer;background:#eee;position:sticky;top:0}\n"
    "th.asc::after{content:' \\25B2'}th.desc::after{content:' \\25BC'}\n"
    ".plots{display:flex;flex-wrap:wrap}.plots img{margin:4px;border:1px solid #ccc}\n"
    ".job{display:inline-block;margin:6px;vertical-align:top;font-size:12px}\n"
    ".swipe{position:relative;display:inline-block;line-height:0}\n"
    ".swipe img.over{position:absolute;left:0;top:0}\n"
    ".job img{image-rendering:pixelated}\n"
    "</style></head>\n";

static const char page_script[] =
    "<script>\n"
    "'use strict';\n"
    "document.body.dataset.scriptErrors = '0';\n"
    "window.addEventListener('error', function (e) {\n"
    "  if (e.target && e.target.tagName === 'IMG') return;\n"
    "  document.body.dataset.scriptErrors = String(Number(document.body.dataset.scriptErrors) + "
    "1);\n"
    "});\n"
    "function cellValue(row, column) {\n"
    "  var td = row.cells[column];\n"
    "  var v = td.getAttribute('data-v');\n"
    "  if (v === null) return td.textContent;\n"
    "  return v === '' ? NaN : Number(v);\n"
    "}\n"
    "function sortTable(name, descending) {\n"
    "  var table = document.getElementById('results');\n"
    "  var heads = table.tHead.rows[0].cells, column = -1;\n"
    "  for (var i = 0; i < heads.length; i++) {\n"
    "    heads[i].className = '';\n"
    "    if (heads[i].getAttribute('data-column') === name) column = i;\n"
    "  }\n"
    "  if (column < 0) return false;\n"
    "  var body = table.tBodies[0], rows = Array.prototype.slice.call(body.rows);\n"
    "  rows.sort(function (a, b) {\n"
    "    var x = cellValue(a, column), y = cellValue(b, column);\n"
    "    var c;\n"
    "    if (typeof x === 'number') {\n"
    "      if (isNaN(x) || isNaN(y)) return isNaN(x) - isNaN(y); /* blanks last */\n"
    "      c = x - y;\n"
    "    } else c = x < y ? -1 : x > y ? 1 : 0;\n"
    "    if (descending) c = -c;\n"
    "    return c || cellValue(a, 0) - cellValue(b, 0);\n"
    "  });\n"
    "  rows.forEach(function (r) { body.appendChild(r); });\n"
    "  heads[column].className = descending ? 'desc' : 'asc';\n"
    "  document.body.dataset.sorted = name + (descending ? ':desc' : ':asc');\n"
    "  return true;\n"
    "}\n"
    "function sortFromHash() {\n"
    "  var m = /^#sort=([a-z_]+)(:desc)?$/.exec(location.hash);\n"
    "  if (m) sortTable(m[1], !!m[2]);\n"
    "}\n"
    "Array.prototype.forEach.call(document.querySelectorAll('#results th'), function (th) {\n"
    "  th.addEventListener('click', function () {\n"
    "    sortTable(th.getAttribute('data-column'), th.className === 'asc');\n"
    "  });\n"
    "});\n"
    "Array.prototype.forEach.call(document.querySelectorAll('.job'), function (job) {\n"
    "  var over = job.querySelector('img.over'), range = job.querySelector('input');\n"
    "  range.addEventListener('input', function () {\n"
    "    over.style.clipPath = 'inset(0 ' + (100 - range.value) + '% 0 0)';\n"
    "  });\n"
    "  job.querySelector('button').addEventListener('click', function () {\n"
    "    range.value = range.value > 0 ? 0 : 100;\n"
    "    range.dispatchEvent(new Event('input'));\n"
    "  });\n"
    "});\n"
    "window.addEventListener('hashchange', sortFromHash);\n"
    "sortFromHash();\n"
    "window.addEventListener('load', function () {\n"
    "  var broken = 0;\n"
    "  Array.prototype.forEach.call(document.images, function (img) {\n"
    "    if (!img.complete || img.naturalWidth === 0) broken++;\n"
    "  });\n"
    "  document.body.dataset.brokenImages = String(broken);\n"
    "  document.body.dataset.images = String(document.images.length);\n"
    "});\n"
    "</script>\n";

/* A relative path as a URL in an attribute: bytes other than letters, digits and -._~/=,
 * percent-encoded (a scene named "a#b" or "a b" still links to its files). */
static void url_path(app_text *t, const char *s) {
    for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
        bool plain = (*p >= 'a' && *p <= 'z') || (*p >= 'A' && *p <= 'Z') ||
                     (*p >= '0' && *p <= '9') || strchr("-._~/=", *p);
        app_text_printf(t, plain ? "%c" : "%%%02X", *p);
    }
}

static void write_html(const sweep_row *rows, size_t count, const char *hash, app_text *t) {
    app_text_printf(t,
                    "%s<body>\n<h1>meso sweep</h1>\n<p>%zu jobs, spec hash %s. Click a "
                    "column's head to sort by it. Each job's image lies over the truth: "
                    "drag the slider to swipe, <em>flip</em> to switch.</p>\n",
                    page_head, count, hash);
    app_text_printf(t, "<h2>Error against frame time</h2>\n<div class=\"plots\">\n");
    for (size_t r = 0; r < count; r++) {
        if (!group_start(rows, r)) continue;
        char name[400];
        snprintf(name, sizeof name, "plots/%s-%dx%d.png", rows[r].scene, rows[r].width,
                 rows[r].height);
        bool any = false;
        for (size_t k = r; k < count; k++)
            any = any || (same_group(&rows[k], &rows[r]) && rows[k].has_metrics);
        if (!any) continue; /* no metrics: no plot */
        app_text_printf(t, "<img src=\"");
        url_path(t, name);
        app_text_printf(t, "\" alt=\"plot\" width=\"720\" height=\"460\">\n");
    }
    app_text_printf(t, "</div>\n<h2>Results</h2>\n<table id=\"results\"><thead><tr>");
    for (size_t c = 0; c < NUM_COLUMNS; c++)
        app_text_printf(t, "<th data-column=\"%s\">%s</th>", columns[c].name, columns[c].name);
    app_text_printf(t, "</tr></thead>\n<tbody>\n");
    for (size_t r = 0; r < count; r++) {
        app_text_printf(t, "<tr>");
        for (size_t c = 0; c < NUM_COLUMNS; c++) {
            long i;
            const char *text;
            double number;
            char size_text[32], value[64];
            cell(&rows[r], c, &i, &text, &number, size_text);
            if (columns[c].kind == COLUMN_INT) {
                app_text_printf(t, "<td data-v=\"%ld\">%ld</td>", i, i);
            } else if (columns[c].kind == COLUMN_TEXT) {
                app_text_printf(t, "<td class=\"t\">");
                app_text_xml(t, text);
                app_text_printf(t, "</td>");
            } else {
                format_number(value, sizeof value, "%.17g", number);
                app_text_printf(t, "<td data-v=\"%s\">",
                                isinf(number) ? (number > 0 ? "Infinity" : "-Infinity") : value);
                format_number(value, sizeof value, columns[c].format, number);
                app_text_printf(t, "%s</td>", value);
            }
        }
        app_text_printf(t, "</tr>\n");
    }
    app_text_printf(t, "</tbody></table>\n<h2>Images</h2>\n");
    for (size_t r = 0; r < count; r++) {
        const sweep_row *row = &rows[r];
        if (strcmp(row->status, "ok") != 0) continue;
        char truth[400];
        snprintf(truth, sizeof truth, "refs/%s/%dx%d/view-0000.png", row->scene, row->width,
                 row->height);
        /* small images shown enlarged (pixelated), so a few pixels of error can be seen */
        int scale = row->width < 192 ? (192 + row->width - 1) / row->width : 1;
        int shown_w = row->width * scale, shown_h = row->height * scale;
        app_text_printf(t, "<div class=\"job\" id=\"job-%d\"><div>%d: ", row->id, row->id);
        app_text_xml(t, row->key);
        app_text_printf(t, "</div>\n<div class=\"swipe\"><img src=\"");
        url_path(t, truth);
        app_text_printf(
            t, "\" alt=\"truth\" width=\"%d\" height=\"%d\"><img class=\"over\" src=\"jobs/",
            shown_w, shown_h);
        url_path(t, row->key);
        app_text_printf(t, "/view-0000.png\" alt=\"job\" width=\"%d\" height=\"%d\"></div>\n",
                        shown_w, shown_h);
        if (row->has_metrics) {
            app_text_printf(t, "<img src=\"jobs/");
            url_path(t, row->key);
            app_text_printf(t, "/diff-0000.png\" alt=\"difference\" width=\"%d\" height=\"%d\">\n",
                            shown_w, shown_h);
        }
        app_text_printf(t,
                        "<div><input type=\"range\" min=\"0\" max=\"100\" value=\"100\" "
                        "aria-label=\"swipe\"> <button type=\"button\">flip</button> job | "
                        "truth%s</div></div>\n",
                        row->has_metrics ? " | difference" : "");
    }
    app_text_printf(t, "%s</body></html>\n", page_script);
}

meso_result app_sweep_write_reports(meso_context *ctx, const char *dir, const sweep_row *rows,
                                    size_t count, const char *spec_hash) {
    app_text csv = {0}, json = {0}, html = {0};
    write_csv(rows, count, &csv);
    write_json(rows, count, spec_hash, &json);
    write_html(rows, count, spec_hash, &html);
    char path[4096];
    meso_result r = write_plots(ctx, dir, rows, count);
    if (r == MESO_OK && app_path_join(path, sizeof path, dir, "results.csv"))
        r = app_text_write(ctx, &csv, path);
    if (r == MESO_OK && app_path_join(path, sizeof path, dir, "results.json"))
        r = app_text_write(ctx, &json, path);
    /* the page last: when it is there, everything it shows is */
    if (r == MESO_OK && app_path_join(path, sizeof path, dir, "index.html"))
        r = app_text_write(ctx, &html, path);
    app_text_free(&csv);
    app_text_free(&json);
    app_text_free(&html);
    return r;
}
