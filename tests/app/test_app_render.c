/* meso render on the bricks example: the PNG's size, no temporary files left behind, the same
 * bytes for any thread count; --techniques writes its folder. */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "test_util.h"

#define BRICKS MESO_SOURCE_DIR "/examples/bricks-plane.json"

static const char *fresh_dir(const char *name) {
    const char *dir = test_path(test_temp_dir(), name);
    static char copy[8][1024];
    static int next;
    char *out = copy[next++ % 8];
    snprintf(out, 1024, "%s", dir);
    mkdir(out, 0755);
    return out;
}

/* The names in dir, sorted, joined by spaces. */
static void list_dir(const char *dir, char *out, size_t out_size) {
    struct dirent **entries = NULL;
    int n = scandir(dir, &entries, NULL, alphasort);
    assert_true(n >= 0);
    out[0] = 0;
    for (int i = 0; i < n; i++) {
        if (entries[i]->d_name[0] != '.') {
            strncat(out, entries[i]->d_name, out_size - strlen(out) - 2);
            strncat(out, " ", out_size - strlen(out) - 1);
        }
        free(entries[i]);
    }
    free(entries);
}

static void run_ok(const char *arguments) {
    const char *err = NULL;
    int status = test_run_meso(arguments, &err);
    if (status != 0) fail_msg("meso %s: status %d, stderr: %s", arguments, status, err);
}

static void test_app_render_writes_png_of_the_asked_size(void **state) {
    (void)state;
    const char *dir = fresh_dir("render-size");
    char args[4096];
    snprintf(args, sizeof(args), "render %s -o %s --size 64x64 --coverage %s", BRICKS,
             test_path(dir, "x.png"), test_path(dir, "x.coverage.png"));
    run_ok(args);
    meso_context *ctx = test_context(1);
    meso_image *image = NULL, *coverage = NULL;
    assert_int_equal(meso_image_load_png(ctx, test_path(dir, "x.png"), &image), MESO_OK);
    assert_int_equal(image->width, 64);
    assert_int_equal(image->height, 64);
    assert_int_equal(meso_image_load_png(ctx, test_path(dir, "x.coverage.png"), &coverage),
                     MESO_OK);
    assert_int_equal(coverage->width, 64);
    /* The bricks plane fills part of the view: some pixels are covered. */
    float covered = 0.0f;
    for (int i = 0; i < 64 * 64; i++) covered += coverage->pixels[i * coverage->channels];
    assert_true(covered > 0.0f);
    meso_image_destroy(coverage);
    meso_image_destroy(image);
    meso_context_destroy(ctx);

    char names[4096];
    list_dir(dir, names, sizeof(names));
    assert_string_equal(names, "x.coverage.png x.png "); /* no temporary file left */
}

/* Straight down the scene's up axis needs another up: refused without --up (exit 2, naming
 * the scene), drawn with it, and the plane then fills the middle of the view. */
static void test_app_render_up_lets_the_camera_look_straight_down(void **state) {
    (void)state;
    const char *dir = fresh_dir("render-up");
    char args[4096];
    const char *err = NULL;
    snprintf(args, sizeof(args), "render %s -o %s --size 32x32 --eye 0,3,0 --target 0,0,0", BRICKS,
             test_path(dir, "down.png"));
    assert_int_equal(test_run_meso(args, &err), 2);
    assert_non_null(strstr(err, "bricks-plane.json: --eye/--target/--up"));
    snprintf(args, sizeof(args),
             "render %s -o %s --size 32x32 --eye 0,3,0 --target 0,0,0 --up 0,0,-1 --coverage %s",
             BRICKS, test_path(dir, "down.png"), test_path(dir, "down.coverage.png"));
    run_ok(args);
    meso_context *ctx = test_context(1);
    meso_image *coverage = NULL;
    assert_int_equal(meso_image_load_png(ctx, test_path(dir, "down.coverage.png"), &coverage),
                     MESO_OK);
    assert_true(coverage->pixels[(16 * 32 + 16) * coverage->channels] > 0.5f);
    meso_image_destroy(coverage);
    meso_context_destroy(ctx);
}

static void test_app_render_same_bytes_for_any_thread_count(void **state) {
    (void)state;
    const char *dir = fresh_dir("render-threads");
    char args[4096];
    snprintf(args, sizeof(args), "render %s -o %s --size 64x64 --threads 1 --quiet", BRICKS,
             test_path(dir, "one.png"));
    run_ok(args);
    snprintf(args, sizeof(args), "render %s -o %s --size 64x64 --threads 2 --quiet", BRICKS,
             test_path(dir, "two.png"));
    run_ok(args);
    size_t size_one = 0, size_two = 0;
    char *one = test_read_file(test_path(dir, "one.png"), &size_one);
    char *two = test_read_file(test_path(dir, "two.png"), &size_two);
    assert_int_equal(size_one, size_two);
    assert_memory_equal(one, two, size_one);
    free(one);
    free(two);
    char names[4096];
    list_dir(dir, names, sizeof(names));
    assert_string_equal(names, "one.png two.png ");
}

static void test_app_render_techniques_writes_images_sheet_and_results(void **state) {
    (void)state;
    const char *dir = fresh_dir("render-techniques");
    char args[4096];
    snprintf(args, sizeof(args), "render %s --techniques flat,bump -o %s --size 32x32 --frames 1",
             BRICKS, dir);
    run_ok(args);
    const char *files[] = {"flat.png",  "flat.coverage.png", "bump.png",
                           "sheet.png", "results.csv",       "results.json"};
    for (size_t i = 0; i < sizeof(files) / sizeof(files[0]); i++) {
        struct stat st;
        if (stat(test_path(dir, files[i]), &st) != 0 || st.st_size == 0)
            fail_msg("%s/%s missing", dir, files[i]);
    }
    size_t size = 0;
    char *csv = test_read_file(test_path(dir, "results.csv"), &size);
    csv[size] = 0;
    assert_non_null(strstr(csv, "scene,technique,status"));
    assert_non_null(strstr(csv, ",flat,ok,"));
    assert_non_null(strstr(csv, ",bump,ok,"));
    free(csv);
}

static void test_app_info_describes_the_example_and_its_render(void **state) {
    (void)state;
    const char *dir = fresh_dir("info");
    char args[4096];
    snprintf(args, sizeof(args), "info %s", BRICKS);
    run_ok(args);
    snprintf(args, sizeof(args), "render %s -o %s --size 16x8 --quiet", BRICKS,
             test_path(dir, "small.png"));
    run_ok(args);
    snprintf(args, sizeof(args), "info %s", test_path(dir, "small.png"));
    run_ok(args);
}

/* Defects: "triangles": 2.09715e+06; relief,relief rendered twice; a second run's folder kept
 * the first run's images beside a sheet that no longer showed them. */
static void test_app_render_techniques_results_and_folder_are_exact(void **state) {
    (void)state;
    const char *dir = fresh_dir("render-techniques-rerun");
    char args[4096];
    snprintf(args, sizeof(args),
             "render %s --techniques bump,parallax -o %s --size 32x32 --frames 1 --quiet", BRICKS,
             dir);
    run_ok(args);
    /* a file of the user's own stays whatever happens */
    test_write_file(test_path(dir, "notes.txt"), "mine", 4);
    snprintf(args, sizeof(args),
             "render %s --techniques relief,relief -o=%s --size 32x32 --frames 1 --quiet "
             "--set relief.linear_steps=4",
             BRICKS, dir);
    run_ok(args);
    char names[4096];
    list_dir(dir, names, sizeof(names));
    assert_string_equal(names,
                        "error-vs-time.png error-vs-time.svg notes.txt reference.coverage.png "
                        "reference.png "
                        "relief.coverage.png relief.png results.csv results.json sheet.png ");
    size_t size = 0;
    char *json = test_read_file(test_path(dir, "results.json"), &size);
    json[size] = 0;
    /* one relief run, after the reference */
    const char *first = strstr(json, "\"technique\": \"relief\"");
    assert_non_null(first);
    assert_null(strstr(first + 1, "\"technique\": \"relief\""));
    /* the reference's triangle count (~2 M) as an integer */
    const char *triangles = strstr(json, "\"triangles\": ");
    assert_non_null(triangles);
    triangles += strlen("\"triangles\": ");
    size_t digits = strspn(triangles, "0123456789");
    assert_true(digits >= 6);
    assert_true(triangles[digits] == ',' || triangles[digits] == '}');
    assert_null(strstr(json, "e+"));
    free(json);
    /* the plot: relief a labelled point, the reference's time a line */
    char *svg = test_read_file(test_path(dir, "error-vs-time.svg"), &size);
    svg[size] = 0;
    assert_non_null(strstr(svg, "<svg xmlns="));
    assert_non_null(strstr(svg, "<circle"));
    assert_non_null(strstr(svg, ">relief</text>"));
    assert_non_null(strstr(svg, ">reference "));
    assert_non_null(strstr(svg, "</svg>"));
    free(svg);
}

#define SPHERE MESO_SOURCE_DIR "/examples/bumps-sphere.json"

/* Several scenes in one process: OUT/<name>.png each, the same bytes as one at a time. */
static void test_app_render_batch_writes_one_image_per_scene(void **state) {
    (void)state;
    const char *dir = fresh_dir("render-batch");
    char args[4096];
    snprintf(args, sizeof(args), "render %s %s -o %s --size 32x32 --technique relief --quiet",
             BRICKS, SPHERE, test_path(dir, "out"));
    run_ok(args);
    snprintf(args, sizeof(args), "render %s -o %s --size 32x32 --technique relief --quiet", SPHERE,
             test_path(dir, "alone.png"));
    run_ok(args);
    char names[4096];
    list_dir(test_path(dir, "out"), names, sizeof(names));
    assert_string_equal(names, "bricks-plane.png bumps-sphere.png ");
    size_t size_a = 0, size_b = 0;
    char *a = test_read_file(test_path(test_path(dir, "out"), "bumps-sphere.png"), &size_a);
    char *b = test_read_file(test_path(dir, "alone.png"), &size_b);
    assert_int_equal(size_a, size_b);
    assert_memory_equal(a, b, size_a);
    free(a);
    free(b);
    /* with --techniques: a folder per scene */
    snprintf(args, sizeof(args),
             "render %s %s -o %s --size 16x16 --techniques flat --frames 1 --quiet", BRICKS, SPHERE,
             test_path(dir, "all"));
    run_ok(args);
    list_dir(test_path(test_path(dir, "all"), "bumps-sphere"), names, sizeof(names));
    assert_non_null(strstr(names, "flat.png"));
    assert_non_null(strstr(names, "sheet.png"));
    /* two scenes of one name, and --coverage, are refused before any work */
    const char *err = NULL;
    snprintf(args, sizeof(args), "render %s %s -o %s", BRICKS, BRICKS, test_path(dir, "twice"));
    assert_int_equal(test_run_meso(args, &err), 2);
    assert_non_null(strstr(err, "would both write 'bricks-plane' into the folder"));
    snprintf(args, sizeof(args), "render %s %s -o %s --coverage c.png", BRICKS, SPHERE,
             test_path(dir, "cov"));
    assert_int_equal(test_run_meso(args, &err), 2);
    struct stat st;
    assert_true(stat(test_path(dir, "twice"), &st) != 0 && stat(test_path(dir, "cov"), &st) != 0);
}

/* Defect: --progress showed nothing for one long render (the bar appears after a second). */
static void test_app_render_progress_shows_for_one_long_render(void **state) {
    (void)state;
    const char *dir = fresh_dir("render-progress");
    char args[4096];
    snprintf(args, sizeof(args),
             "render %s -o %s --technique reference --size 512x512 --samples 36 --progress", BRICKS,
             test_path(dir, "reference.png"));
    const char *err = NULL;
    int status = test_run_meso(args, &err);
    if (status != 0) fail_msg("status %d: %s", status, err);
    if (!strstr(err, "\rreference ") || !strstr(err, "%  ")) /* (stderr is kept to 8 KiB) */
        fail_msg("no progress bar on stderr: %s", err);
    /* without --progress (stderr is not a terminal) nothing but the summary */
    snprintf(args, sizeof(args), "render %s -o %s --technique relief --size 64x64", BRICKS,
             test_path(dir, "relief.png"));
    assert_int_equal(test_run_meso(args, &err), 0);
    assert_null(strchr(err, '\r'));
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_app_render_writes_png_of_the_asked_size),
        cmocka_unit_test(test_app_render_up_lets_the_camera_look_straight_down),
        cmocka_unit_test(test_app_render_same_bytes_for_any_thread_count),
        cmocka_unit_test(test_app_render_techniques_writes_images_sheet_and_results),
        cmocka_unit_test(test_app_info_describes_the_example_and_its_render),
        cmocka_unit_test(test_app_render_progress_shows_for_one_long_render),
        cmocka_unit_test(test_app_render_techniques_results_and_folder_are_exact),
        cmocka_unit_test(test_app_render_batch_writes_one_image_per_scene),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
