/* meso render: one scene to a PNG, or every technique side by side against the reference. */
#include "app.h"
#include "app_backend.h"
#include "render_camera.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "meso/runtime.h"

#define SHEET_COLUMNS 4
#define SHEET_LABEL_LINES 5 /* app_run_label's longest form */
#define MAX_BATCH_SCENES 256

typedef struct render_options {
    const char *output;
    const char *technique;
    const char *techniques;
    app_size size;
    int samples;
    int reference_samples;
    int frames;
    int filter; /* --filter (-1: not given) */
    bool wireframe;
    const char *coverage;
    bool linear;
    int bits;                   /* --bits: PNG bit depth (0: 8) */
    app_settings settings;      /* --set */
    int orbit;                  /* frames of a turntable into folder OUT (0: none) */
    double orbit_step;          /* degrees a frame (-1: not given, a whole turn in `orbit`) */
    app_camera_override camera; /* --eye, --target, --up, --fov, --light */
    app_backend backend;        /* --backend, --shader-dir */
} render_options;

static const app_command_help render_help = {
    .name = "render",
    .usage = "SCENE -o OUT.png [options]\n       meso render SCENE --techniques all -o DIR "
             "[options]\n       meso render SCENE1 SCENE2 ... -o DIR [options]",
    .summary =
        "Render a scene file (docs/scene-format.md) to a PNG, with each object's technique or\n"
        "the one given by --technique. A one-line summary (technique, size, prepare and frame\n"
        "times, triangles) goes to stderr.\n\n"
        "With --techniques all (or a comma-separated list) the scene is rendered with every\n"
        "technique that can draw its objects and with the ray-traced reference; OUT is then a\n"
        "folder receiving <technique>.png (sRGB), <technique>.coverage.png, sheet.png (the\n"
        "images side by side, labelled with the median frame time of a few frames, PSNR over\n"
        "the whole image and over the covered pixels, SSIM and coverage IoU against the\n"
        "reference, measured on linear colour), results.csv and results.json.\n\n"
        "With several scenes OUT is a folder: each scene is rendered in turn, in one process\n"
        "(bakes are shared through the cache), into OUT/<scene name>.png, or with --techniques\n"
        "into the folder OUT/<scene name>/. The first scene that fails stops the batch.",
    .examples = "  meso render examples/bricks-plane.json -o bricks.png\n"
                "  meso render examples/bricks-plane.json -o relief.png --technique relief "
                "--size 256x256\n"
                "  meso render examples/bricks-plane.json --techniques all -o out/bricks\n"
                "  meso render examples/*.json -o out --size 256x256\n"
                "  meso render examples/bricks-teapot.json --technique relief --orbit 120 -o "
                "orbit\n"
                "  meso render examples/bricks-plane.json --backend gl -o gl.png\n",
};

/* "relief", or "mixed" when the objects use different techniques. */
static const char *scene_technique(const meso_scene *scene, const char *override) {
    if (override) return override;
    if (scene->num_objects == 0) return "none";
    for (int i = 1; i < scene->num_objects; i++)
        if (strcmp(scene->objects[i].technique, scene->objects[0].technique) != 0) return "mixed";
    return scene->objects[0].technique;
}

static int render_one(meso_context *ctx, const meso_scene *scene, const render_options *o,
                      bool quiet) {
    app_renderer renderer = {0};
    meso_framebuffer *fb = NULL;
    meso_render_desc desc = {.technique = o->technique,
                             .samples = o->samples,
                             .wireframe = o->wireframe,
                             .filter = app_filter_mode(o->filter),
                             .options = o->settings.items,
                             .num_options = o->settings.count,
                             .progress = true};
    int width = o->size.width ? o->size.width : scene->width;
    int height = o->size.height ? o->size.height : scene->height;
    meso_encoding encoding = o->linear ? MESO_ENCODING_LINEAR : scene->encoding;

    /* the frame's memory is checked before the renderer prepares (and bakes) anything */
    meso_result result =
        meso_memory_check(ctx, scene->path, meso_render_memory_estimate(&desc, width, height));
    if (result == MESO_OK) result = app_renderer_create(ctx, scene, &desc, &o->backend, &renderer);
    if (result == MESO_OK) result = meso_framebuffer_create(ctx, width, height, &fb);
    if (result == MESO_OK) result = app_renderer_render(&renderer, fb);
    /* the output's extension chooses PNG or OpenEXR */
    meso_png_desc png = {.bit_depth = o->bits, .encoding = encoding};
    if (result == MESO_OK) result = meso_framebuffer_save(ctx, fb, &png, o->output, o->coverage);
    if (result == MESO_OK && !quiet) {
        meso_render_stats stats = app_renderer_get_stats(&renderer);
        app_note("render: %s%s, %dx%d, prepare %.1f ms, frame %.1f ms, %llu triangles -> %s",
                 scene_technique(scene, o->technique),
                 app_backend_is_gl(&o->backend) ? " (gl)" : "", width, height,
                 1000.0 * stats.prepare_seconds, 1000.0 * stats.last_frame_seconds,
                 (unsigned long long)stats.triangles, o->output);
    }
    int status =
        result == MESO_OK ? APP_EXIT_OK : app_fail_backend(ctx, result, scene->path, &o->backend);
    meso_framebuffer_destroy(fb);
    app_renderer_destroy(&renderer);
    return status;
}

static void print_results(const app_compare_all *all) {
    printf("%-14s %10s %10s %10s %12s %7s %7s\n", "technique", "prepare ms", "frame ms", "PSNR dB",
           "covered dB", "SSIM", "IoU");
    for (size_t i = 0; i < all->num_runs; i++) {
        const app_run *r = &all->runs[i];
        if (!r->rendered) {
            printf("%-14s %s\n", r->technique, r->skipped ? "(not applicable)" : "(failed)");
            continue;
        }
        printf("%-14s %10.1f %10.2f", r->technique, r->prepare_ms, r->frame_ms);
        if (r->has_metrics)
            printf(" %10.2f %12.2f %7.3f %7.3f\n", r->metrics.psnr, r->metrics.psnr_covered,
                   r->metrics.ssim, r->metrics.coverage_iou);
        else
            printf(" %10s %12s %7s %7s\n", "-", "-", "-", "-");
    }
}

/* Write sheet.png, results.csv, results.json and error-vs-time.svg of `all` into dir. */
static meso_result write_reports(meso_context *ctx, const app_compare_all *all,
                                 const meso_scene *scene, const char *dir) {
    const meso_image *images[256];
    const char *labels[256];
    char label_text[256][256];
    size_t count = 0;
    for (size_t i = 0; i < all->num_runs && count < 256; i++) {
        if (!all->runs[i].rendered) continue;
        app_run_label(&all->runs[i], NULL, all->runs[i].color->width, label_text[count],
                      sizeof(label_text[count]));
        images[count] = all->runs[i].color;
        labels[count] = label_text[count];
        count++;
    }
    char path[4096];
    meso_result result = MESO_OK;
    if (count > 0 && app_path_join(path, sizeof(path), dir, "sheet.png"))
        result = app_sheet_save(ctx, images, labels, count,
                                count < SHEET_COLUMNS ? (int)count : SHEET_COLUMNS, path);
    app_text csv = {0}, json = {0};
    bool first = true;
    app_compare_all_csv(all, scene->path, &csv);
    app_text_printf(&json, "{\n  \"scene\": ");
    app_text_json_string(&json, scene->path);
    app_text_printf(&json, ",\n  \"reference_rendered\": %s,\n  \"runs\": [",
                    all->reference_ok ? "true" : "false");
    app_compare_all_json(all, scene->path, &json, &first);
    app_text_printf(&json, "\n  ]\n}\n");
    if (result == MESO_OK && app_path_join(path, sizeof(path), dir, "results.csv"))
        result = app_text_write(ctx, &csv, path);
    if (result == MESO_OK && app_path_join(path, sizeof(path), dir, "results.json"))
        result = app_text_write(ctx, &json, path);
    char png_path[4096];
    if (result == MESO_OK && app_path_join(path, sizeof(path), dir, "error-vs-time.svg") &&
        app_path_join(png_path, sizeof(png_path), dir, "error-vs-time.png"))
        result = app_plot_error_vs_time(ctx, all, scene->path, path, png_path);
    app_text_free(&csv);
    app_text_free(&json);
    return result;
}

static int render_all(meso_context *ctx, const meso_scene *scene, const render_options *o,
                      const char *const *names, int num_names, bool quiet) {
    meso_result result = app_make_dir(ctx, o->output);
    if (result != MESO_OK) return app_fail(ctx, result);
    app_compare_all_desc desc = {
        .scene = scene,
        .width = o->size.width ? o->size.width : scene->width,
        .height = o->size.height ? o->size.height : scene->height,
        .techniques = names,
        .num_techniques = num_names,
        .with_reference = true,
        .samples = o->samples,
        .reference_samples = o->reference_samples,
        .timing_frames = o->frames,
        .settings = &o->settings,
        .filter = app_filter_mode(o->filter),
    };
    /* the sheet's size and the images kept for it are known before the work */
    result =
        app_compare_all_check_memory(ctx, &desc, SHEET_COLUMNS, SHEET_LABEL_LINES, scene->path);
    if (result != MESO_OK) return app_fail_in(ctx, result, scene->path);
    desc.progress = meso_progress_begin(ctx, "render techniques", app_compare_all_count(&desc));
    app_compare_all all;
    result = app_compare_all_render(ctx, &desc, &all);
    meso_progress_end(desc.progress);
    if (result != MESO_OK) return app_fail_in(ctx, result, scene->path);

    size_t rendered = 0;
    for (size_t i = 0; i < all.num_runs; i++) rendered += all.runs[i].rendered;
    if (rendered == 0) { /* one line: the last failure */
        app_compare_all_free(&all);
        return app_fail_in(ctx, MESO_ERROR_UNSUPPORTED, scene->path);
    }
    if (!quiet) app_compare_all_print_notes(&all, NULL, true);
    /* The folder's files are published together: none is renamed into place before every one
     * is written, so a full disk leaves the previous run's files as they were. */
    bool group = meso_atomic_group_begin(ctx);
    result = app_compare_all_write_images(ctx, &all, o->output, NULL, true);
    if (result == MESO_OK) result = write_reports(ctx, &all, scene, o->output);
    if (group) {
        meso_result published = meso_atomic_group_end(ctx, result == MESO_OK);
        if (result == MESO_OK) result = published;
    }
    if (result == MESO_OK) print_results(&all);
    if (result == MESO_OK && !quiet)
        app_note("render: %zu images, sheet.png, results.csv, results.json and "
                 "error-vs-time.svg/.png in %s",
                 rendered, o->output);
    int status = result == MESO_OK ? APP_EXIT_OK : app_fail(ctx, result);
    app_compare_all_free(&all);
    return status;
}

/* Two scenes of a batch with one name would write one file: refused before any work. */
static int check_batch_names(const char *const *paths, int count) {
    for (int a = 0; a < count; a++)
        for (int b = a + 1; b < count; b++) {
            char name_a[256], name_b[256];
            app_path_stem(paths[a], name_a, sizeof name_a);
            app_path_stem(paths[b], name_b, sizeof name_b);
            if (strcmp(name_a, name_b) == 0)
                return app_usage_error("render", "%s and %s would both write '%s' into the folder",
                                       paths[a], paths[b], name_a);
        }
    return -1;
}

int meso_cmd_render(int argc, char **argv) {
    render_options o = {.samples = 1, .frames = 5, .filter = -1, .orbit_step = -1.0};
    const app_option options[] = {
        {"--output", "-o", APP_OPTION_STRING, &o.output, "OUT",
         "the image to write: OUT.png, or OUT.exr for OpenEXR (half floats, linear); a folder "
         "with --techniques",
         "required", 0, 0},
        {"--technique", NULL, APP_OPTION_STRING, &o.technique, "T",
         "draw every object with technique T", "each object's own", 0, 0},
        {"--techniques", NULL, APP_OPTION_STRING, &o.techniques, "LIST",
         "'all' or comma-separated names: render each plus the reference into folder OUT", NULL, 0,
         0},
        {"--size", NULL, APP_OPTION_SIZE, &o.size, "WxH", "image size", "the scene's", 0, 0},
        {"--samples", NULL, APP_OPTION_INT, &o.samples, "S",
         "samples a pixel (an n x n grid, n = ceil(sqrt(S)))", "1", 1, 256},
        {"--wireframe", NULL, APP_OPTION_FLAG, &o.wireframe, NULL,
         "overlay the rasterized triangles' edges", NULL, 0, 0},
        {"--coverage", NULL, APP_OPTION_STRING, &o.coverage, "MASK.png",
         "also write the coverage mask (grey PNG)", NULL, 0, 0},
        APP_BITS_OPTION(&o.bits),
        {"--linear", NULL, APP_OPTION_FLAG, &o.linear, NULL, "write linear values instead of sRGB",
         "the scene's encoding", 0, 0},
        {"--reference-samples", NULL, APP_OPTION_INT, &o.reference_samples, "S",
         "samples a pixel of the reference (with --techniques)", "--samples", 1, 256},
        {"--frames", NULL, APP_OPTION_INT, &o.frames, "N",
         "frames timed per technique after the first, median reported (with --techniques; "
         "at most 2 s each)",
         "5", 1, 1000},
        APP_SET_OPTION(&o.settings),
        APP_FILTER_OPTION(&o.filter),
        {"--orbit", NULL, APP_OPTION_INT, &o.orbit, "N",
         "write N frames turning about the camera's up axis through its target into folder OUT "
         "(OUT/frame-0000.png ...; with --techniques OUT/<technique>/frame-0000.png ... and "
         "the reference's, each compared with it: error, change and flicker into "
         "OUT/temporal.csv)",
         NULL, 1, 100000},
        {"--orbit-step", NULL, APP_OPTION_DOUBLE, &o.orbit_step, "DEG",
         "degrees the orbit turns a frame, 360 / DEG a whole number (0: a still camera)", "360 / N",
         0, 360},
        APP_CAMERA_OVERRIDE_OPTIONS(o.camera),
        APP_BACKEND_OPTIONS(o.backend),
    };
    app_globals globals;
    const char *positionals[MAX_BATCH_SCENES];
    int num_positionals = 0;
    int status =
        app_parse_options(&render_help, options, sizeof(options) / sizeof(options[0]), argc, argv,
                          &globals, positionals, MAX_BATCH_SCENES, &num_positionals);
    if (status >= 0) return status;
    if (num_positionals < 1) return app_usage_error("render", "missing the SCENE file");
    if (!o.output) return app_usage_error("render", "missing -o OUT");
    if ((status = app_check_bits("render", o.bits)) >= 0) return status;
    if (o.technique && o.techniques)
        return app_usage_error("render", "--technique and --techniques exclude each other");
    if ((status = app_backend_check("render", &o.backend)) >= 0) return status;
    if (app_backend_is_gl(&o.backend) && (o.techniques || o.orbit))
        return app_usage_error("render", "--backend gl draws one image: not with %s",
                               o.techniques ? "--techniques" : "--orbit");
    app_orbit_path orbit = {.frames = o.orbit, .period = o.orbit};
    if (o.orbit_step >= 0.0) {
        if (!o.orbit) return app_usage_error("render", "--orbit-step needs --orbit");
        double period = o.orbit_step > 0.0 ? 360.0 / o.orbit_step : 0.0;
        /* the turntable turns by whole fractions of a turn (view_camera_turntable) */
        if (fabs(period - round(period)) > 1e-6 * period || period > 1e9)
            return app_usage_error("render", "--orbit-step: 360 / %g is not a whole number",
                                   o.orbit_step);
        orbit.period = (int)round(period);
    }
    if (num_positionals > 1 && o.coverage)
        return app_usage_error("render", "--coverage takes one file: it needs one scene");
    if (num_positionals > 1 && (status = check_batch_names(positionals, num_positionals)) >= 0)
        return status;
    const char *scene_path = positionals[0];
    if (o.technique && !app_technique_known(o.technique)) {
        char known[1024];
        app_known_techniques(known, sizeof(known));
        app_error("%s: --technique: unknown technique '%s' (known: %s)", scene_path, o.technique,
                  known);
        return APP_EXIT_BAD_INPUT;
    }
    const char *names[64];
    char names_storage[1024];
    int num_names = 0;
    if (o.techniques) {
        num_names = app_parse_technique_list("render", o.techniques, names_storage,
                                             sizeof(names_storage), names, 64);
        if (num_names < 0) return APP_EXIT_BAD_INPUT;
    }

    meso_context *ctx = app_context_create(&globals);
    if (!ctx) return APP_EXIT_FAILURE;
    /* Every output is checked before any work, so a bad one fails at once and nothing is
     * written (with --techniques or several scenes, OUT is a folder, made below with its
     * parents; the files in it are checked as they are written). */
    bool output_is_file = !o.techniques && !o.orbit && num_positionals == 1;
    const char *outputs[2] = {output_is_file ? o.output : NULL, o.coverage};
    for (int i = 0; i < 2; i++) {
        meso_result checked = outputs[i] ? meso_file_check_output(ctx, outputs[i]) : MESO_OK;
        if (checked != MESO_OK) {
            status = app_fail(ctx, checked);
            meso_context_destroy(ctx);
            return status;
        }
        /* and its name says its format: one meso does not write is refused */
        if (outputs[i] && (status = app_check_image_output(outputs[i], true, "meso")) >= 0) {
            meso_context_destroy(ctx);
            return status;
        }
    }
    const char *batch_dir = num_positionals > 1 ? o.output : NULL;
    if (batch_dir) {
        meso_result made = app_make_dir(ctx, batch_dir);
        if (made != MESO_OK) {
            status = app_fail(ctx, made);
            meso_context_destroy(ctx);
            return status;
        }
    }
    status = APP_EXIT_OK;
    for (int s = 0; s < num_positionals && status == APP_EXIT_OK; s++) {
        char output[4096];
        render_options scene_options = o;
        if (batch_dir) { /* OUT/<name>.png, or the folder OUT/<name> with --techniques */
            char name[256];
            app_path_stem(positionals[s], name, sizeof name);
            if (!o.techniques) strncat(name, ".png", sizeof name - strlen(name) - 1);
            if (!app_path_join(output, sizeof output, batch_dir, name)) {
                status = app_usage_error("render", "%s: output path too long", batch_dir);
                break;
            }
            scene_options.output = output;
        }
        meso_scene *scene = NULL;
        meso_context_set_subject(ctx, positionals[s]); /* "baking gdm for SCENE (about 10 s)" */
        meso_result result = meso_scene_load(ctx, positionals[s], &scene);
        meso_render_desc orbit_desc = {.technique = o.technique,
                                       .samples = o.samples,
                                       .wireframe = o.wireframe,
                                       .filter = app_filter_mode(o.filter),
                                       .options = o.settings.items,
                                       .num_options = o.settings.count};
        if (result != MESO_OK)
            status = app_fail(ctx, result);
        else if ((status = app_camera_override_apply("render", &o.camera, scene)) >= 0)
            ; /* the override's message is printed */
        else if (o.orbit)
            status = o.techniques
                         ? app_render_orbit_measured(
                               ctx, scene, names, num_names, &orbit_desc, o.reference_samples,
                               &orbit, o.size.width ? o.size.width : scene->width,
                               o.size.height ? o.size.height : scene->height,
                               o.linear ? MESO_ENCODING_LINEAR : scene->encoding,
                               scene_options.output, globals.quiet)
                         : app_render_orbit(ctx, scene, &orbit_desc,
                                            o.size.width ? o.size.width : scene->width,
                                            o.size.height ? o.size.height : scene->height,
                                            o.linear ? MESO_ENCODING_LINEAR : scene->encoding,
                                            &orbit, scene_options.output, globals.quiet);
        else if (o.techniques)
            status = render_all(ctx, scene, &scene_options, names, num_names, globals.quiet);
        else
            status = render_one(ctx, scene, &scene_options, globals.quiet);
        if (status < 0) status = APP_EXIT_OK;
        meso_scene_destroy(scene);
    }
    meso_context_destroy(ctx);
    return status;
}
