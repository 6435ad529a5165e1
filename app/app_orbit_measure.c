/* meso render --orbit N --techniques LIST: every technique and the reference along one camera
 * path, each frame compared with the reference's of the same view, and the frame-to-frame
 * change of each image sequence against the reference's: the temporal measure of
 * docs/compare.md ("Motion: change and flicker"). */
#include "app.h"
#include "render_camera.h"
#include "view_state.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "meso/runtime.h"

double app_image_change(const meso_image *a0, const meso_image *a1) {
    size_t n = (size_t)a0->width * (size_t)a0->height;
    double sum = 0.0;
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++) {
            size_t k = i * (size_t)a0->channels + (size_t)c;
            sum += fabs((double)a1->pixels[k] - a0->pixels[k]);
        }
    return sum / (3.0 * (double)n);
}

double app_flicker_between(const meso_image *a0, const meso_image *a1, const meso_image *r0,
                           const meso_image *r1) {
    size_t n = (size_t)a0->width * (size_t)a0->height;
    double sum = 0.0;
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++) {
            size_t k = i * (size_t)a0->channels + (size_t)c;
            size_t q = i * (size_t)r0->channels + (size_t)c;
            sum += fabs(((double)a1->pixels[k] - a0->pixels[k]) -
                        ((double)r1->pixels[q] - r0->pixels[q]));
        }
    return sum / (3.0 * (double)n);
}

/* One image sequence: a technique's or the reference's renderer and what is summed over it. */
typedef struct orbit_run {
    char name[64];
    char dir[4096];
    meso_renderer *renderer;
    meso_framebuffer *fb;
    meso_image *color[2], *coverage[2]; /* this frame's and the last one's (by frame parity) */
    double frame_seconds, psnr, psnr_covered, change, flicker;
    int compared;
} orbit_run;

static void run_free(orbit_run *r) {
    meso_framebuffer_destroy(r->fb);
    meso_renderer_destroy(r->renderer);
    for (int k = 0; k < 2; k++) {
        meso_image_destroy(r->color[k]);
        meso_image_destroy(r->coverage[k]);
    }
}

/* Draw frame `frame` of run r into its image slot frame % 2 and its PNG. */
static meso_result run_frame(meso_context *ctx, orbit_run *r, int frame, meso_encoding encoding) {
    char name[64], path[4096];
    snprintf(name, sizeof name, "frame-%04d.png", frame);
    if (!app_path_join(path, sizeof path, r->dir, name))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: path too long", r->dir);
    int slot = frame % 2;
    meso_image_destroy(r->color[slot]);
    meso_image_destroy(r->coverage[slot]);
    r->color[slot] = r->coverage[slot] = NULL;
    meso_result result = meso_renderer_render(r->renderer, r->fb);
    if (result == MESO_OK) result = meso_framebuffer_save_png(ctx, r->fb, encoding, path, NULL);
    if (result == MESO_OK) result = meso_framebuffer_color_image(ctx, r->fb, &r->color[slot]);
    if (result == MESO_OK) result = meso_framebuffer_coverage_image(ctx, r->fb, &r->coverage[slot]);
    r->frame_seconds += meso_renderer_get_stats(r->renderer).last_frame_seconds;
    return result;
}

static void write_table(const orbit_run *runs, int num_runs, int count, app_text *csv) {
    const orbit_run *ref = &runs[0];
    double truth_change = count > 1 ? ref->change / (count - 1) : 0.0;
    printf("%-14s %10s %10s %12s %12s %8s %12s %8s\n", "technique", "frame ms", "PSNR dB",
           "covered dB", "change", "x truth", "flicker", "x truth");
    app_text_printf(csv, "technique,frames,frame_ms,psnr_db,psnr_covered_db,change,"
                         "change_over_truth,flicker,flicker_over_truth\n");
    for (int i = 0; i < num_runs; i++) {
        const orbit_run *r = &runs[i];
        double ms = 1000.0 * r->frame_seconds / count;
        double change = count > 1 ? r->change / (count - 1) : 0.0;
        double flicker = count > 1 ? r->flicker / (count - 1) : 0.0;
        double psnr = i > 0 && r->compared ? r->psnr / r->compared : NAN;
        double covered = i > 0 && r->compared ? r->psnr_covered / r->compared : NAN;
        /* a still camera: no change anywhere, the ratios are 0 by definition, not 0 / 0 */
        double change_ratio = truth_change > 0.0 ? change / truth_change : 0.0;
        double flicker_ratio = truth_change > 0.0 ? flicker / truth_change : 0.0;
        if (i == 0) /* the reference: no error against itself */
            printf("%-14s %10.2f %10s %12s", r->name, ms, "-", "-");
        else
            printf("%-14s %10.2f %10.2f %12.2f", r->name, ms, psnr, covered);
        printf(" %12.6f %8.3f %12.6f %8.3f\n", change, change_ratio, flicker, flicker_ratio);
        app_text_printf(csv, "%s,%d,%.3f,%.4f,%.4f,%.8f,%.5f,%.8f,%.5f\n", r->name, count, ms, psnr,
                        covered, change, change_ratio, flicker, flicker_ratio);
    }
}

int app_render_orbit_measured(meso_context *ctx, meso_scene *scene, const char *const *names,
                              int num_names, const meso_render_desc *desc, int reference_samples,
                              const app_orbit_path *path, int width, int height,
                              meso_encoding encoding, const char *dir, bool quiet) {
    const meso_camera home = scene->camera;
    const view_camera home_view = app_camera_to_view(&home);
    int count = path->frames;
    orbit_run *runs = calloc((size_t)num_names + 1, sizeof *runs);
    if (!runs) return app_fail(ctx, meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "out of memory"));
    int num_runs = 0;
    meso_result result = app_make_dir(ctx, dir);
    /* every run keeps two frames of colour and coverage, and the largest frame is drawn */
    uint64_t pixels = (uint64_t)width * (uint64_t)height;
    meso_render_desc reference_desc = *desc;
    reference_desc.technique = "reference";
    reference_desc.samples = reference_samples > 0 ? reference_samples : desc->samples;
    uint64_t need = (uint64_t)(num_names + 1) * 2 * pixels * 4 * sizeof(float) +
                    meso_render_memory_estimate(&reference_desc, width, height) +
                    (uint64_t)num_names * meso_render_memory_estimate(desc, width, height);
    if (result == MESO_OK) result = meso_memory_check(ctx, scene->path, need);
    for (int i = -1; i < num_names && result == MESO_OK; i++) {
        const char *name = i < 0 ? "reference" : names[i];
        if (i >= 0 && strcmp(name, "reference") == 0) continue; /* drawn first, always */
        const meso_technique_info *info = meso_technique_find(name);
        if (i >= 0 && info && !app_technique_applies(info, scene)) {
            if (!quiet)
                fprintf(stderr, "meso: note: %s: skipped: it cannot draw this scene's objects\n",
                        name);
            continue;
        }
        orbit_run *r = &runs[num_runs++];
        snprintf(r->name, sizeof r->name, "%s", name);
        if (!app_path_join(r->dir, sizeof r->dir, dir, name)) {
            result = meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: path too long", dir);
            break;
        }
        meso_render_desc run_desc = *desc;
        run_desc.technique = name;
        if (i < 0) run_desc = reference_desc;
        result = app_make_dir(ctx, r->dir);
        if (result == MESO_OK) result = meso_renderer_create(ctx, scene, &run_desc, &r->renderer);
        if (result == MESO_OK) result = meso_framebuffer_create(ctx, width, height, &r->fb);
    }
    meso_progress *progress = NULL;
    if (result == MESO_OK)
        progress = meso_progress_begin(ctx, "render orbit", (uint64_t)count * (uint64_t)num_runs);
    for (int frame = 0; frame < count && result == MESO_OK; frame++) {
        view_camera camera = view_camera_turntable(&home_view, frame, path->period);
        scene->camera = frame == 0 || path->period == 0 ? home : app_camera_from_view(&camera);
        int now = frame % 2, last = 1 - now;
        for (int i = 0; i < num_runs && result == MESO_OK; i++) {
            orbit_run *r = &runs[i];
            result = run_frame(ctx, r, frame, encoding);
            if (result == MESO_OK && i > 0) {
                meso_compare_desc compare = {.coverage_a = r->coverage[now],
                                             .coverage_b = runs[0].coverage[now]};
                meso_compare_result m;
                result = meso_image_compare(ctx, r->color[now], runs[0].color[now], &compare, &m);
                if (result == MESO_OK) {
                    r->psnr += m.psnr, r->psnr_covered += m.psnr_covered;
                    r->compared++;
                }
            }
            if (result == MESO_OK && frame > 0) {
                r->change += app_image_change(r->color[last], r->color[now]);
                r->flicker += app_flicker_between(r->color[last], r->color[now],
                                                  runs[0].color[last], runs[0].color[now]);
            }
            if (meso_progress_advance(progress, 1)) result = MESO_ERROR_CANCELLED;
        }
    }
    meso_progress_end(progress);
    scene->camera = home;
    app_text csv = {0};
    char csv_path[4096];
    if (result == MESO_OK) {
        write_table(runs, num_runs, count, &csv);
        if (!app_path_join(csv_path, sizeof csv_path, dir, "temporal.csv"))
            result = meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: path too long", dir);
        else
            result = app_text_write(ctx, &csv, csv_path);
    }
    if (result == MESO_OK && !quiet)
        app_note("render: %d orbit frames %dx%d of %d runs into %s/<technique>/frame-%%04d.png, "
                 "temporal.csv",
                 count, width, height, num_runs, dir);
    app_text_free(&csv);
    int status = result == MESO_OK ? APP_EXIT_OK : app_fail(ctx, result);
    for (int i = 0; i < num_runs; i++) run_free(&runs[i]);
    free(runs);
    return status;
}
