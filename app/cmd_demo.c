/* meso demo: every built-in example with every technique, and one labelled sheet. */
#include "app.h"

#include <stdlib.h>
#include <string.h>

#include "examples_embedded.h"
#include "meso/runtime.h"

#define MAX_RUNS 64

static const app_command_help demo_help = {
    .name = "demo",
    .usage = "[-o DIR] [options]",
    .summary =
        "Render every example built into the program (the scenes of examples/) with every\n"
        "technique that can draw it, and with the ray-traced reference when it is available,\n"
        "at a modest size. Writes DIR/<example>-<technique>.png, DIR/results.csv and\n"
        "DIR/sheet.png: rows are examples, columns techniques, each cell labelled with the\n"
        "example, the technique, its median frame time and its error against the reference.",
    .examples = "  meso demo\n  meso demo -o /tmp/demo --size 128x128\n",
};

typedef struct demo_example {
    const char *name;
    meso_scene *scene;
    app_compare_all all;
} demo_example;

/* The sheet: one row per example, one column per technique some example could draw. */
static meso_result write_sheet(meso_context *ctx, const demo_example *examples, size_t count,
                               int width, const char *path) {
    size_t num_columns = 0, columns[MAX_RUNS];
    size_t num_runs = count > 0 ? examples[0].all.num_runs : 0;
    for (size_t j = 0; j < num_runs && j < MAX_RUNS; j++) {
        bool used = false;
        for (size_t e = 0; e < count; e++) used |= examples[e].all.runs[j].rendered;
        if (used) columns[num_columns++] = j;
    }
    size_t cells = count * num_columns;
    const meso_image **images = calloc(cells ? cells : 1, sizeof(*images));
    char **labels = calloc(cells ? cells : 1, sizeof(*labels));
    char *text = calloc(cells ? cells : 1, 256);
    meso_result result = MESO_OK;
    if (!images || !labels || !text) {
        result = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", path);
    } else {
        for (size_t e = 0; e < count; e++)
            for (size_t c = 0; c < num_columns; c++) {
                size_t cell = e * num_columns + c;
                const app_run *run = &examples[e].all.runs[columns[c]];
                labels[cell] = text + cell * 256;
                app_run_label(run, examples[e].name, width, labels[cell], 256);
                images[cell] = run->rendered ? run->color : NULL;
            }
        result =
            app_sheet_save(ctx, images, (const char *const *)labels, cells, (int)num_columns, path);
    }
    free(text);
    free(labels);
    free(images);
    return result;
}

static meso_result render_examples(meso_context *ctx, demo_example *examples, size_t count,
                                   app_size size, int frames, const app_settings *settings,
                                   const char *dir, bool quiet) {
    app_compare_all_desc desc = {.width = size.width,
                                 .height = size.height,
                                 .with_reference = true,
                                 .timing_frames = frames,
                                 .timing_budget_seconds = 1.0,
                                 .settings = settings};
    size_t total = count * app_compare_all_count(&desc);
    desc.progress = meso_progress_begin(ctx, "demo", total);
    meso_result result = MESO_OK;
    for (size_t e = 0; e < count && result == MESO_OK; e++) {
        desc.scene = examples[e].scene;
        meso_context_set_subject(ctx, examples[e].name); /* "baking gdm for weave-plane ..." */
        result = app_compare_all_render(ctx, &desc, &examples[e].all);
        if (result != MESO_OK) break;
        if (!quiet) app_compare_all_print_notes(&examples[e].all, examples[e].name, false);
        char prefix[MESO_NAME_MAX + 2];
        snprintf(prefix, sizeof(prefix), "%s-", examples[e].name);
        result = app_compare_all_write_images(ctx, &examples[e].all, dir, prefix, false);
    }
    meso_progress_end(desc.progress);
    return result;
}

static meso_result write_results(meso_context *ctx, const demo_example *examples, size_t count,
                                 const char *dir) {
    app_text csv = {0};
    for (size_t e = 0; e < count; e++)
        app_compare_all_csv(&examples[e].all, examples[e].name, &csv);
    char path[4096];
    meso_result result = MESO_OK;
    if (app_path_join(path, sizeof(path), dir, "results.csv"))
        result = app_text_write(ctx, &csv, path);
    app_text_free(&csv);
    return result;
}

int meso_cmd_demo(int argc, char **argv) {
    const char *dir = "demo";
    app_size size = {256, 256};
    int frames = 3;
    app_settings settings = {0};
    const app_option options[] = {
        {"--output", "-o", APP_OPTION_STRING, &dir, "DIR", "the folder to write", "./demo", 0, 0},
        {"--size", NULL, APP_OPTION_SIZE, &size, "WxH", "size of each image", "256x256", 0, 0},
        {"--frames", NULL, APP_OPTION_INT, &frames, "N",
         "frames timed per image after the first (median; at most 1 s each)", "3", 1, 1000},
        APP_SET_OPTION(&settings),
    };
    app_globals globals;
    int num_positionals = 0;
    int status = app_parse_options(&demo_help, options, sizeof(options) / sizeof(options[0]), argc,
                                   argv, &globals, NULL, 0, &num_positionals);
    if (status >= 0) return status;
    if (meso_embedded_example_count == 0) {
        fprintf(stderr, "meso: demo: this build has no embedded examples\n");
        return APP_EXIT_FAILURE;
    }

    meso_context *ctx = app_context_create(&globals);
    if (!ctx) return APP_EXIT_FAILURE;
    demo_example *examples = calloc(meso_embedded_example_count, sizeof(*examples));
    size_t count = 0;
    meso_result result = examples ? app_make_dir(ctx, dir) : MESO_ERROR_OUT_OF_MEMORY;
    /* An example that does not parse is a bug of this build, but the others still show. */
    for (size_t i = 0; result == MESO_OK && i < meso_embedded_example_count; i++) {
        const meso_embedded_example *ex = &meso_embedded_examples[i];
        demo_example *d = &examples[count];
        d->name = ex->name;
        d->all.reference = -1;
        if (app_example_parse(ctx, i, &d->scene) == MESO_OK)
            count++;
        else if (!globals.quiet)
            fprintf(stderr, "meso: warning: %s\n", meso_context_last_error(ctx));
    }
    if (result == MESO_OK && count == 0) result = MESO_ERROR_FORMAT;
    if (result == MESO_OK)
        result = render_examples(ctx, examples, count, size, frames, &settings, dir, globals.quiet);
    char path[4096];
    if (result == MESO_OK && !app_path_join(path, sizeof(path), dir, "sheet.png"))
        result = meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: path too long", dir);
    if (result == MESO_OK) result = write_sheet(ctx, examples, count, size.width, path);
    if (result == MESO_OK) result = write_results(ctx, examples, count, dir);
    if (result == MESO_OK && !globals.quiet) {
        size_t images = 0;
        bool reference = false;
        for (size_t e = 0; e < count; e++) {
            for (size_t j = 0; j < examples[e].all.num_runs; j++)
                images += examples[e].all.runs[j].rendered;
            reference |= examples[e].all.reference_ok;
        }
        fprintf(stderr, "meso: demo: %zu examples, %zu images, %s and results.csv%s\n", count,
                images, path, reference ? "" : " (reference not available: no error metrics)");
    }
    status = result == MESO_OK ? APP_EXIT_OK : app_fail(ctx, result);
    for (size_t e = 0; examples && e < meso_embedded_example_count; e++) {
        app_compare_all_free(&examples[e].all);
        meso_scene_destroy(examples[e].scene);
    }
    free(examples);
    meso_context_destroy(ctx);
    return status;
}
