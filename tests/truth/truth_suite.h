/* The truth suite's one test body (docs/techniques.md, "The truth suite"): render a scene of
 * tests/data/truth/ with a technique and with `reference`, compare them on linear colour with
 * both coverage masks (as `meso render --techniques` does) and hold the covered PSNR and the
 * coverage IoU to the row's floors of truth_table.h.
 *
 * Each test executable runs the rows whose technique it selects, one cmocka test a row named
 * "<scene>/<technique>"; scenes are loaded and their reference rendered once per executable.
 * Header-only (static functions), included by one test file each.
 *
 * On a failure, and for every row when MESO_TRUTH_PRINT=1, the technique's image, the
 * reference and their difference are written to <build>/truth-images/. MESO_TRUTH_PRINT=1 also
 * prints each row as measured, with floors by the margin rule, ready to paste into the table.
 */
#ifndef MESO_TRUTH_SUITE_H
#define MESO_TRUTH_SUITE_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "test_util.h"
#include "truth_table.h"

#define TRUTH_DATA_DIR MESO_SOURCE_DIR "/tests/data/truth"
#define TRUTH_IMAGE_DIR MESO_BINARY_DIR "/truth-images"
#define TRUTH_MAX_ROWS 256

/* A scene of the suite, loaded with its reference rendered, on first use. */
typedef struct truth_scene {
    const char *name;
    meso_scene *scene;
    meso_image *color, *coverage; /* the reference's */
} truth_scene;

static meso_context *truth_ctx;
static truth_scene truth_loaded[TRUTH_NUM_SCENES];

static bool truth_print_enabled(void) {
    const char *value = getenv("MESO_TRUTH_PRINT");
    return value && strcmp(value, "1") == 0;
}

static int truth_setup(void **state) {
    (void)state;
    /* Bakes are made fresh in memory: a stale cached bake must not hide a fault in the baker
     * (docs/design.md, "Bakes are cached per user"). */
    setenv("MESO_CACHE_DIR", "off", 1);
    truth_ctx = test_context(0);
    return 0;
}

static int truth_teardown(void **state) {
    (void)state;
    for (size_t i = 0; i < TRUTH_NUM_SCENES; i++) {
        meso_image_destroy(truth_loaded[i].color);
        meso_image_destroy(truth_loaded[i].coverage);
        meso_scene_destroy(truth_loaded[i].scene);
    }
    memset(truth_loaded, 0, sizeof(truth_loaded));
    meso_context_destroy(truth_ctx);
    truth_ctx = NULL;
    unsetenv("MESO_CACHE_DIR");
    return 0;
}

/* Render `scene` with `technique` into colour and coverage images; fails the test, naming the
 * library's message, when the technique cannot draw it. */
static void render_images(const meso_scene *scene, const char *technique, meso_image **out_color,
                          meso_image **out_coverage) {
    meso_framebuffer *fb = NULL;
    meso_result r =
        meso_render_scene(truth_ctx, scene, &(meso_render_desc){.technique = technique}, &fb);
    if (r != MESO_OK)
        fail_msg("%s: %s failed: %s", scene->path, technique, meso_context_last_error(truth_ctx));
    assert_int_equal(meso_framebuffer_color_image(truth_ctx, fb, out_color), MESO_OK);
    assert_int_equal(meso_framebuffer_coverage_image(truth_ctx, fb, out_coverage), MESO_OK);
    meso_framebuffer_destroy(fb);
}

/* Set every object's options to the technique's of truth_options[], keyed by the technique (the
 * scene files set none). Setting, not appending, so a row that failed half-way leaves nothing
 * behind for the next. */
static void set_options(meso_scene *scene, const char *spec) {
    char technique[64], variant[64] = "";
    double variant_value = 0.0;
    const char *colon = strchr(spec, ':'), *equals = colon ? strchr(colon, '=') : NULL;
    snprintf(technique, sizeof technique, "%.*s", (int)(colon ? colon - spec : 63), spec);
    if (equals) {
        snprintf(variant, sizeof variant, "%.*s", (int)(equals - colon - 1), colon + 1);
        variant_value = atof(equals + 1);
    }
    for (int o = 0; o < scene->num_objects; o++) {
        meso_object *object = &scene->objects[o];
        object->num_options = 0;
        if (variant[0]) { /* the row's "technique:option=value" */
            meso_option *option = &object->options[object->num_options++];
            snprintf(option->technique, sizeof(option->technique), "%s", technique);
            snprintf(option->name, sizeof(option->name), "%s", variant);
            option->value = variant_value;
        }
        for (size_t i = 0; i < sizeof(truth_options) / sizeof(truth_options[0]); i++) {
            if (strcmp(truth_options[i].technique, technique) != 0) continue;
            assert_true(object->num_options < MESO_OPTIONS_MAX);
            meso_option *option = &object->options[object->num_options++];
            snprintf(option->technique, sizeof(option->technique), "%s", technique);
            snprintf(option->name, sizeof(option->name), "%s", truth_options[i].name);
            option->value = truth_options[i].value;
        }
    }
}

/* The scene `name` of truth_scenes[], loaded and its reference rendered on first use. */
static truth_scene *get_scene(const char *name) {
    size_t index = TRUTH_NUM_SCENES;
    for (size_t i = 0; i < TRUTH_NUM_SCENES; i++)
        if (strcmp(truth_scenes[i], name) == 0) index = i;
    if (index == TRUTH_NUM_SCENES) fail_msg("%s: not in truth_scenes[]", name);
    truth_scene *ts = &truth_loaded[index];
    ts->name = name;
    if (ts->color) return ts;
    /* A scene that failed to load or to render fails each of its rows, with the message. */
    if (!ts->scene) {
        char path[1024];
        snprintf(path, sizeof(path), "%s/%s.json", TRUTH_DATA_DIR, name);
        if (meso_scene_load(truth_ctx, path, &ts->scene) != MESO_OK)
            fail_msg("%s", meso_context_last_error(truth_ctx));
    }
    set_options(ts->scene, "reference");
    render_images(ts->scene, "reference", &ts->color, &ts->coverage);
    return ts;
}

static void save_image(const meso_image *image, const char *path) {
    meso_png_desc srgb = {.encoding = MESO_ENCODING_SRGB};
    if (meso_image_save_png(truth_ctx, image, path, &srgb) != MESO_OK)
        print_error("%s\n", meso_context_last_error(truth_ctx));
}

/* <scene>-<technique>.png, <scene>-reference.png and <scene>-<technique>.diff.png (sRGB; the
 * difference in false colour, red at 0.25 linear) under TRUTH_IMAGE_DIR. */
static void write_images(const truth_scene *ts, const char *technique, const meso_image *color) {
    mkdir(TRUTH_IMAGE_DIR, 0755);
    char path[1024];
    snprintf(path, sizeof(path), "%s/%s-%s.png", TRUTH_IMAGE_DIR, ts->name, technique);
    save_image(color, path);
    snprintf(path, sizeof(path), "%s/%s-reference.png", TRUTH_IMAGE_DIR, ts->name);
    save_image(ts->color, path);
    meso_image *diff = NULL;
    if (meso_image_diff(truth_ctx, color, ts->color, 0.0f, &diff) == MESO_OK) {
        snprintf(path, sizeof(path), "%s/%s-%s.diff.png", TRUTH_IMAGE_DIR, ts->name, technique);
        save_image(diff, path);
    }
    meso_image_destroy(diff);
}

/* The row as truth_table.h would hold it for these measurements: floors by the margin rule. */
static void print_row(const truth_row *row, const meso_compare_result *m) {
    double psnr_floor = floor((m->psnr_covered - TRUTH_PSNR_MARGIN_DB) * 10.0) / 10.0;
    double iou_floor = floor((m->coverage_iou - TRUTH_IOU_MARGIN) * 1000.0) / 1000.0;
    print_message("    {\"%s\", \"%s\", %.1f, %.3f}, /* measured %.2f dB, IoU %.4f */\n",
                  row->scene, row->technique, psnr_floor, iou_floor, m->psnr_covered,
                  m->coverage_iou);
}

/* The one test body: the row's technique against the reference on the row's scene. */
static void test_truth_row(void **state) {
    const truth_row *row = *state;
    truth_scene *ts = get_scene(row->scene);
    meso_image *color = NULL, *coverage = NULL;
    set_options(ts->scene, row->technique);
    char technique[64]; /* a variant's technique: the name before its ':' */
    snprintf(technique, sizeof technique, "%.*s", (int)strcspn(row->technique, ":"),
             row->technique);
    render_images(ts->scene, technique, &color, &coverage);

    meso_compare_desc desc = {.coverage_a = coverage, .coverage_b = ts->coverage};
    meso_compare_result m;
    assert_int_equal(meso_image_compare(truth_ctx, color, ts->color, &desc, &m), MESO_OK);
    /* NaN (nothing covered by both) fails the comparison below, as it should. */
    bool ok = m.psnr_covered >= row->min_psnr_covered && m.coverage_iou >= row->min_iou;
    if (truth_print_enabled()) print_row(row, &m);
    if (!ok || truth_print_enabled()) write_images(ts, row->technique, color);
    meso_image_destroy(color);
    meso_image_destroy(coverage);
    if (!ok)
        fail_msg("%s/%s: covered PSNR %.2f dB (floor %.1f), coverage IoU %.4f (floor %.3f); "
                 "images in %s: %s-%s.png, %s-reference.png, %s-%s.diff.png",
                 row->scene, row->technique, m.psnr_covered, row->min_psnr_covered, m.coverage_iou,
                 row->min_iou, TRUTH_IMAGE_DIR, row->scene, row->technique, row->scene, row->scene,
                 row->technique);
}

/* Run the rows whose technique `select` accepts, one cmocka test each. */
static int truth_run(const char *group, bool (*select)(const char *technique)) {
    static struct CMUnitTest tests[TRUTH_MAX_ROWS];
    static char names[TRUTH_MAX_ROWS][2 * MESO_NAME_MAX];
    size_t count = 0;
    for (size_t i = 0; i < sizeof(truth_rows) / sizeof(truth_rows[0]); i++) {
        if (!select(truth_rows[i].technique)) continue;
        if (count == TRUTH_MAX_ROWS) {
            print_error("truth_suite.h: more than TRUTH_MAX_ROWS (%d) rows\n", TRUTH_MAX_ROWS);
            return 1;
        }
        snprintf(names[count], sizeof(names[count]), "%s/%s", truth_rows[i].scene,
                 truth_rows[i].technique);
        tests[count] = (struct CMUnitTest){.name = names[count],
                                           .test_func = test_truth_row,
                                           .initial_state = (void *)&truth_rows[i]};
        count++;
    }
    return _cmocka_run_group_tests(group, tests, count, truth_setup, truth_teardown);
}

#endif
