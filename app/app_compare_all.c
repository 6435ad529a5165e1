/* Render one scene with every technique and the reference, time the frames and compare each
 * image against the ground truth: shared by `meso render --techniques` and `meso demo`.
 *
 * Metrics compare LINEAR colour with both coverage masks (docs/design.md, "Measuring against the
 * truth"): PSNR over the whole image and over the pixels both cover, SSIM and coverage IoU. */
#include "app.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "meso/runtime.h"

#define DEFAULT_TIMING_FRAMES 5
#define DEFAULT_TIMING_BUDGET_SECONDS 2.0
#define MAX_TIMING_FRAMES 1000

/* The techniques to run: desc's list, or every registered per-pixel/geometry technique.
 * "reference" in a list is dropped (it is rendered first, separately). */
static size_t technique_names(const app_compare_all_desc *desc, const char **names,
                              size_t max_names) {
    size_t count = 0;
    if (desc->techniques) {
        for (int i = 0; i < desc->num_techniques && count < max_names; i++)
            if (strcmp(desc->techniques[i], "reference") != 0) names[count++] = desc->techniques[i];
        return count;
    }
    for (size_t i = 0; i < meso_technique_count() && count < max_names; i++) {
        const meso_technique_info *info = meso_technique_get(i);
        if (info->kind != MESO_TECHNIQUE_REFERENCE) names[count++] = info->name;
    }
    return count;
}

size_t app_compare_all_count(const app_compare_all_desc *desc) {
    const char *names[256];
    return technique_names(desc, names, 256) + (desc->with_reference ? 1 : 0);
}

meso_result app_compare_all_check_memory(meso_context *ctx, const app_compare_all_desc *desc,
                                         int sheet_columns, int label_lines, const char *name) {
    size_t runs = app_compare_all_count(desc);
    if (runs == 0) return MESO_OK;
    uint64_t pixels = (uint64_t)desc->width * (uint64_t)desc->height;
    /* every run keeps its colour (RGB) and coverage images in floats until the sheet is made */
    uint64_t total = runs * pixels * 4 * sizeof(float);
    /* one frame at a time, at the larger of the two sample counts */
    int samples = desc->samples > desc->reference_samples ? desc->samples : desc->reference_samples;
    meso_render_desc frame = {.samples = samples};
    total += meso_render_memory_estimate(&frame, desc->width, desc->height);
    if (sheet_columns > 0) { /* the sheet, and its grey cell for a run without an image */
        int width = 0, height = 0;
        meso_result r = meso_compare_sheet_size(ctx, runs, sheet_columns, desc->width, desc->height,
                                                label_lines, &width, &height);
        if (r != MESO_OK) return r;
        total += ((uint64_t)width * (uint64_t)height + pixels) * 3 * sizeof(float);
    }
    return meso_memory_check(ctx, name, total);
}

/* Time frames after the first (which is the image kept): the median of up to `frames`, within
 * the budget; a first frame slower than the budget is its own measure. */
static void time_frames(meso_renderer *renderer, meso_framebuffer *fb, double first_seconds,
                        int frames, double budget, app_run *run) {
    double times[MAX_TIMING_FRAMES];
    int count = 0;
    double spent = first_seconds;
    while (count < frames && count < MAX_TIMING_FRAMES && (count == 0 || spent < budget) &&
           first_seconds < budget) {
        double start = meso_time_seconds();
        if (meso_renderer_render(renderer, fb) != MESO_OK) break;
        times[count] = meso_time_seconds() - start;
        spent += times[count++];
    }
    if (count == 0) {
        times[0] = first_seconds;
        count = 1;
    }
    run->frames_timed = count;
    run->frame_ms = 1000.0 * app_median(times, (size_t)count);
}

/* The objects a renderer drew with another technique than `technique`, into run->note:
 * "mixed: objects[1] (solid) with relief_layers". */
static void note_fallbacks(const meso_renderer *renderer, const meso_scene *scene,
                           const char *technique, app_run *run) {
    size_t used = 0;
    run->note[0] = 0;
    for (int i = 0; i < scene->num_objects && used < sizeof(run->note); i++) {
        const char *drawn = meso_renderer_object_technique(renderer, i);
        if (!drawn || strcmp(drawn, technique) == 0) continue;
        const meso_object *o = &scene->objects[i];
        const char *kind = o->mesostructure.kind == MESO_MESOSTRUCTURE_SOLID ? "solid"
                           : o->mesostructure.kind == MESO_MESOSTRUCTURE_HEIGHT_FIELD
                               ? "height field"
                               : "none";
        int n = snprintf(run->note + used, sizeof(run->note) - used, "%s%s (%s) with %s",
                         used ? "; " : "mixed: ", o->name, kind, drawn);
        used += n > 0 ? (size_t)n : 0;
    }
}

/* One technique (or the reference) of the scene into run. A failure, whatever its cause (an
 * exhausted memory included: a technique may ask for more than the machine has), is noted in
 * the run and does not stop the others. */
static void render_run(meso_context *ctx, const app_compare_all_desc *desc, const char *technique,
                       int samples, app_run *run) {
    snprintf(run->technique, sizeof(run->technique), "%s", technique);
    const meso_technique_info *info = meso_technique_find(technique);
    if (info && app_technique_draws(info, desc->scene) == 0) {
        run->skipped = true;
        snprintf(run->note, sizeof(run->note),
                 "%s: skipped: it does not draw this scene's kind of mesostructure", technique);
        return;
    }
    meso_renderer *renderer = NULL;
    meso_framebuffer *fb = NULL;
    /* Mixed scenes: the objects this technique cannot draw are drawn with
     * their own scene technique, and the note says which. */
    meso_render_desc render_desc = {
        .technique = technique, .samples = samples, .fallback = true, .filter = desc->filter};
    if (desc->settings) {
        render_desc.options = desc->settings->items;
        render_desc.num_options = desc->settings->count;
    }
    meso_result result = meso_renderer_create(ctx, desc->scene, &render_desc, &renderer);
    if (result == MESO_OK) result = meso_framebuffer_create(ctx, desc->width, desc->height, &fb);
    double start = meso_time_seconds();
    if (result == MESO_OK) result = meso_renderer_render(renderer, fb);
    double first_seconds = meso_time_seconds() - start;
    if (result == MESO_OK) {
        /* Keep the first frame's image: later frames draw the same bytes (determinism). */
        result = meso_framebuffer_color_image(ctx, fb, &run->color);
        if (result == MESO_OK) result = meso_framebuffer_coverage_image(ctx, fb, &run->coverage);
    }
    if (result == MESO_OK) {
        int frames = desc->timing_frames > 0 ? desc->timing_frames : DEFAULT_TIMING_FRAMES;
        double budget = desc->timing_budget_seconds > 0.0 ? desc->timing_budget_seconds
                                                          : DEFAULT_TIMING_BUDGET_SECONDS;
        time_frames(renderer, fb, first_seconds, frames, budget, run);
        meso_render_stats stats = meso_renderer_get_stats(renderer);
        run->prepare_ms = 1000.0 * stats.prepare_seconds;
        run->triangles = stats.triangles;
        run->rendered = true;
        note_fallbacks(renderer, desc->scene, technique, run);
    } else {
        snprintf(run->note, sizeof(run->note), "%s", meso_context_last_error(ctx));
        meso_image_destroy(run->color);
        meso_image_destroy(run->coverage);
        run->color = run->coverage = NULL;
    }
    meso_framebuffer_destroy(fb);
    meso_renderer_destroy(renderer);
}

meso_result app_compare_all_render(meso_context *ctx, const app_compare_all_desc *desc,
                                   app_compare_all *out) {
    *out = (app_compare_all){.reference = -1};
    const char *names[256];
    size_t num_names = technique_names(desc, names, 256);
    size_t total = num_names + (desc->with_reference ? 1 : 0);
    app_run *runs = calloc(total ? total : 1, sizeof(*runs));
    if (!runs) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "compare: out of memory");
    out->runs = runs;
    out->num_runs = total;

    size_t next = 0;
    if (desc->with_reference) {
        int samples = desc->reference_samples > 0 ? desc->reference_samples : desc->samples;
        out->reference = 0;
        render_run(ctx, desc, "reference", samples, &runs[next++]);
        out->reference_ok = runs[0].rendered;
        meso_progress_advance(desc->progress, 1);
    }
    for (size_t i = 0; i < num_names; i++) {
        app_run *run = &runs[next++];
        render_run(ctx, desc, names[i], desc->samples, run);
        meso_progress_advance(desc->progress, 1);
        if (out->reference_ok) app_run_compare(ctx, run, &runs[out->reference]);
    }
    return MESO_OK;
}

void app_run_compare(meso_context *ctx, app_run *run, const app_run *reference) {
    if (!run->rendered || !reference->rendered) return;
    meso_compare_desc compare = {.coverage_a = run->coverage, .coverage_b = reference->coverage};
    if (meso_image_compare(ctx, run->color, reference->color, &compare, &run->metrics) == MESO_OK)
        run->has_metrics = true;
}

void app_compare_all_free(app_compare_all *all) {
    for (size_t i = 0; i < all->num_runs; i++) {
        meso_image_destroy(all->runs[i].color);
        meso_image_destroy(all->runs[i].coverage);
    }
    free(all->runs);
    *all = (app_compare_all){.reference = -1};
}

void app_compare_all_print_notes(const app_compare_all *all, const char *scene_name,
                                 bool show_skipped) {
    char where[MESO_NAME_MAX + 2] = "";
    if (scene_name) snprintf(where, sizeof(where), "%.*s: ", MESO_NAME_MAX - 1, scene_name);
    char skipped[1024] = "";
    size_t used = 0;
    for (size_t i = 0; i < all->num_runs; i++) {
        const app_run *r = &all->runs[i];
        if (r->rendered) {
            if (show_skipped && r->note[0])
                fprintf(stderr, "meso: note: %s%s: %s\n", where, r->technique, r->note);
            continue;
        }
        if ((int)i == all->reference)
            fprintf(stderr,
                    "meso: warning: %sreference not available (%s): images and sheet are "
                    "written without metrics\n",
                    where, r->note);
        else if (!r->skipped)
            fprintf(stderr, "meso: warning: %s%s: failed: %s\n", where, r->technique, r->note);
        else if (used < sizeof(skipped)) {
            int n = snprintf(skipped + used, sizeof(skipped) - used, "%s%s", used ? ", " : "",
                             r->technique);
            used += n > 0 ? (size_t)n : 0;
        }
    }
    /* One line for all the techniques that do not apply, not one each. */
    if (show_skipped && skipped[0])
        fprintf(stderr, "meso: note: %sskipped, they cannot draw this scene's mesostructure: %s\n",
                where, skipped);
}

/* ---- Labels, images, tables --------------------------------------------------------------- */

static void format_db(char *out, size_t out_size, double db) {
    if (isnan(db))
        snprintf(out, out_size, "-");
    else if (isinf(db))
        snprintf(out, out_size, "inf");
    else
        snprintf(out, out_size, "%.1f", db);
}

/* Characters a label line may hold under a cell `width` pixels wide: meso_compare_sheet_create
 * draws its 5x7 font with a 6-pixel advance, doubled on cells 256 pixels wide or more. */
static int label_chars(int width) { return width >= 256 ? width / 12 : width / 6; }

void app_run_label(const app_run *run, const char *prefix, int cell_width, char *out,
                   size_t out_size) {
    char head[160];
    if (prefix)
        snprintf(head, sizeof(head), "%s\n%s", prefix, run->technique);
    else
        snprintf(head, sizeof(head), "%s", run->technique);
    if (run->rendered && run->note[0]) /* a mixed scene: say so under the name */
        snprintf(head + strlen(head), sizeof(head) - strlen(head), " (+own)");
    if (!run->rendered) {
        snprintf(out, out_size, "%s\n%s", head, run->skipped ? "not applicable" : "failed");
    } else if (run->has_metrics) {
        char psnr[16], covered[16];
        format_db(psnr, sizeof(psnr), run->metrics.psnr);
        format_db(covered, sizeof(covered), run->metrics.psnr_covered);
        /* The wide form needs 36 characters a line; narrow cells get one figure a line. */
        const char *format = label_chars(cell_width) >= 36
                                 ? "%s\n%.1f ms  PSNR %s dB (covered %s)\nSSIM %.3f  IoU %.3f"
                                 : "%s\n%.1f ms\nPSNR %s dB\n(covered %s dB)\nSSIM %.3f IoU %.3f";
        snprintf(out, out_size, format, head, run->frame_ms, psnr, covered, run->metrics.ssim,
                 run->metrics.coverage_iou);
    } else {
        snprintf(out, out_size, "%s\n%.1f ms", head, run->frame_ms);
    }
}

/* Remove DIR/<prefix><technique>.png and .coverage.png of every technique this run did not
 * render: an earlier run's images would otherwise sit beside a sheet that no longer shows
 * them. Only names meso itself writes are touched. */
static meso_result remove_stale_images(meso_context *ctx, const app_compare_all *all,
                                       const char *dir, const char *prefix) {
    for (size_t t = 0; t < meso_technique_count(); t++) {
        const char *technique = meso_technique_get(t)->name;
        bool rendered = false;
        for (size_t i = 0; i < all->num_runs && !rendered; i++)
            rendered = all->runs[i].rendered && strcmp(all->runs[i].technique, technique) == 0;
        if (rendered) continue;
        static const char *const suffixes[] = {".png", ".coverage.png"};
        for (int s = 0; s < 2; s++) {
            char name[256], path[4096];
            snprintf(name, sizeof(name), "%s%s%s", prefix ? prefix : "", technique, suffixes[s]);
            if (!app_path_join(path, sizeof(path), dir, name)) continue;
            if (remove(path) != 0 && errno != ENOENT)
                return meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot remove the stale image: %s",
                                      path, strerror(errno));
        }
    }
    return MESO_OK;
}

meso_result app_compare_all_write_images(meso_context *ctx, const app_compare_all *all,
                                         const char *dir, const char *prefix, bool coverage) {
    for (size_t i = 0; i < all->num_runs; i++) {
        const app_run *run = &all->runs[i];
        if (!run->rendered) continue;
        char name[256], path[4096];
        snprintf(name, sizeof(name), "%s%s.png", prefix ? prefix : "", run->technique);
        if (!app_path_join(path, sizeof(path), dir, name))
            return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: path too long", dir);
        meso_png_desc srgb = {.encoding = MESO_ENCODING_SRGB};
        meso_result result = meso_image_save_png(ctx, run->color, path, &srgb);
        if (result != MESO_OK) return result;
        if (!coverage) continue;
        snprintf(name, sizeof(name), "%s%s.coverage.png", prefix ? prefix : "", run->technique);
        if (!app_path_join(path, sizeof(path), dir, name))
            return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: path too long", dir);
        meso_png_desc linear = {.encoding = MESO_ENCODING_LINEAR};
        result = meso_image_save_png(ctx, run->coverage, path, &linear);
        if (result != MESO_OK) return result;
    }
    return remove_stale_images(ctx, all, dir, prefix);
}

void app_compare_all_csv(const app_compare_all *all, const char *scene_name, app_text *csv) {
    if (csv->length == 0)
        app_text_printf(csv, "scene,technique,status,prepare_ms,frame_ms,frames_timed,triangles,"
                             "psnr_db,psnr_covered_db,rmse,rmse_covered,ssim,max_error,"
                             "coverage_iou,note\n");
    for (size_t i = 0; i < all->num_runs; i++) {
        const app_run *r = &all->runs[i];
        const char *status = r->rendered ? "ok" : r->skipped ? "skipped" : "failed";
        app_text_printf(csv, "%s,%s,%s,", scene_name, r->technique, status);
        if (r->rendered)
            app_text_printf(csv, "%.3f,%.3f,%d,%llu,", r->prepare_ms, r->frame_ms, r->frames_timed,
                            (unsigned long long)r->triangles);
        else
            app_text_printf(csv, ",,,,");
        if (r->has_metrics) {
            const meso_compare_result *m = &r->metrics;
            app_text_printf(csv, "%.3f,%.3f,%.6f,%.6f,%.4f,%.6f,%.4f,", m->psnr, m->psnr_covered,
                            m->rmse, m->rmse_covered, m->ssim, m->max_error, m->coverage_iou);
        } else {
            app_text_printf(csv, ",,,,,,,");
        }
        /* The note is free text: quote it, doubling quotes (RFC 4180). */
        app_text_printf(csv, "\"");
        for (const char *p = r->note; *p; p++) app_text_printf(csv, *p == '"' ? "\"\"" : "%c", *p);
        app_text_printf(csv, "\"\n");
    }
}

static void json_field(app_text *json, const char *name, double value) {
    app_text_printf(json, ", \"%s\": ", name);
    app_text_json_number(json, value);
}

void app_compare_all_json(const app_compare_all *all, const char *scene_name, app_text *json,
                          bool *first) {
    for (size_t i = 0; i < all->num_runs; i++) {
        const app_run *r = &all->runs[i];
        app_text_printf(json, "%s\n    {\"scene\": ", *first ? "" : ",");
        *first = false;
        app_text_json_string(json, scene_name);
        app_text_printf(json, ", \"technique\": ");
        app_text_json_string(json, r->technique);
        app_text_printf(json, ", \"rendered\": %s", r->rendered ? "true" : "false");
        if (r->rendered) {
            json_field(json, "prepare_ms", r->prepare_ms);
            json_field(json, "frame_ms", r->frame_ms);
            json_field(json, "frames_timed", r->frames_timed);
            json_field(json, "triangles", (double)r->triangles);
        }
        if (r->has_metrics) {
            const meso_compare_result *m = &r->metrics;
            json_field(json, "psnr_db", m->psnr);
            json_field(json, "psnr_covered_db", m->psnr_covered);
            json_field(json, "rmse", m->rmse);
            json_field(json, "rmse_covered", m->rmse_covered);
            json_field(json, "ssim", m->ssim);
            json_field(json, "max_error", m->max_error);
            json_field(json, "coverage_iou", m->coverage_iou);
        }
        if (r->note[0]) {
            app_text_printf(json, ", \"note\": ");
            app_text_json_string(json, r->note);
        }
        app_text_printf(json, "}");
    }
}

/* ---- Sheets ------------------------------------------------------------------------------- */

meso_result app_sheet_save(meso_context *ctx, const meso_image *const *images,
                           const char *const *labels, size_t count, int columns, const char *path) {
    /* Empty cells get a grey image of the first real image's size. */
    int width = 0, height = 0;
    for (size_t i = 0; i < count && !width; i++)
        if (images[i]) width = images[i]->width, height = images[i]->height;
    if (!width)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: no image to put on the sheet",
                              path);
    const meso_image **cells = calloc(count, sizeof(*cells));
    meso_image *empty = NULL, *sheet = NULL;
    meso_result result =
        cells ? MESO_OK : meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", path);
    if (result == MESO_OK) result = meso_image_create(ctx, width, height, 3, &empty);
    if (result == MESO_OK) {
        for (size_t i = 0; i < (size_t)width * (size_t)height * 3; i++) empty->pixels[i] = 0.02f;
        for (size_t i = 0; i < count; i++) cells[i] = images[i] ? images[i] : empty;
        result = meso_compare_sheet_create(ctx, cells, labels, count, columns, &sheet);
    }
    /* The cells are linear: the sheet is encoded once, on saving. */
    meso_png_desc srgb = {.encoding = MESO_ENCODING_SRGB};
    if (result == MESO_OK) result = meso_image_save_png(ctx, sheet, path, &srgb);
    meso_image_destroy(sheet);
    meso_image_destroy(empty);
    free(cells);
    return result;
}
