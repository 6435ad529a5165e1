/* meso bench and meso info: what they print and write. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

#include "test_util.h"

#define BRICKS MESO_SOURCE_DIR "/examples/bricks-plane.json"

/* Run meso with stdout captured into out; returns the exit status. */
static int run_capture_stdout(const char *arguments, char *out, size_t out_size) {
    char command[4096];
    snprintf(command, sizeof(command), "%s %s 2>/dev/null", MESO_PROGRAM, arguments);
    FILE *p = popen(command, "r");
    assert_non_null(p);
    size_t n = fread(out, 1, out_size - 1, p);
    out[n] = 0;
    int status = pclose(p);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

static char *read_text(const char *path) {
    FILE *f = fopen(path, "rb");
    if (!f) fail_msg("%s was not written", path);
    fseek(f, 0, SEEK_END);
    long size = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *data = malloc((size_t)size + 1);
    assert_non_null(data);
    assert_int_equal(fread(data, 1, (size_t)size, f), (size_t)size);
    data[size] = 0;
    fclose(f);
    return data;
}

/* meso info says whether an object's shell folds (docs/techniques/gdm.md, "Folded prisms"):
 * the teapot's bricks, 0.02 deep, fold on its lid's flange; the plane's do not. */
static void test_app_info_says_where_the_shell_folds(void **state) {
    (void)state;
    char out[16384], args[4096];
    snprintf(args, sizeof(args), "info %s", MESO_SOURCE_DIR "/examples/bricks-teapot.json");
    assert_int_equal(run_capture_stdout(args, out, sizeof(out)), 0);
    if (!strstr(out, "shell: folds on 996 of 16256 prisms")) fail_msg("no folds in:\n%s", out);
    snprintf(args, sizeof(args), "info %s", BRICKS);
    assert_int_equal(run_capture_stdout(args, out, sizeof(out)), 0);
    if (!strstr(out, "shell: does not fold")) fail_msg("folds in:\n%s", out);
}

/* meso bench on bricks-plane with `options` and --json: its stdout in out, its JSON returned
 * (free it). */
static char *bench_with_json(const char *options, char *out, size_t size) {
    const char *json_path = test_path(test_temp_dir(), "bench.json");
    char args[4096];
    snprintf(args, sizeof(args), "bench %s %s --json %s", BRICKS, options, json_path);
    assert_int_equal(run_capture_stdout(args, out, size), 0);
    return read_text(json_path);
}

static void test_app_bench_prints_table_and_writes_json(void **state) {
    (void)state;
    static char out[65536];
    char *json = bench_with_json("--techniques flat,bump --frames 2 --size 32x32 --threads 2", out,
                                 sizeof(out));
    assert_non_null(strstr(out, "machine:"));
    assert_non_null(strstr(out, "bricks-plane"));
    assert_non_null(strstr(out, "flat"));
    assert_non_null(strstr(out, "bump"));
    static const char *const keys[] = {"\"machine\"",   "\"threads\": 2",         "\"width\": 32",
                                       "\"median_ms\"", "\"median_ms_1_thread\"", "\"scaling\"",
                                       "\"fps\"",       "\"frames\": 2"};
    for (size_t i = 0; i < sizeof(keys) / sizeof(keys[0]); i++)
        if (!strstr(json, keys[i])) fail_msg("bench.json lacks %s:\n%s", keys[i], json);
    free(json);
}

/* --busy: the header names the spinning thread beside the runs, the JSON says so, and the
 * rows are still there (the spinner stops with the bench: the command returns). */
static void test_app_bench_busy_runs_a_spinner_beside(void **state) {
    (void)state;
    static char out[65536];
    char *json = bench_with_json("--techniques flat --frames 2 --size 32x32 --threads 2 --busy",
                                 out, sizeof(out));
    if (!strstr(out, "a spinning thread")) fail_msg("no spinner in:\n%s", out);
    assert_non_null(strstr(out, "flat"));
    if (!strstr(json, "\"busy\": true")) fail_msg("bench.json lacks busy:\n%s", json);
    free(json);
    json = bench_with_json("--techniques flat --frames 1 --size 32x32", out, sizeof(out));
    assert_null(strstr(out, "a spinning thread"));
    if (!strstr(json, "\"busy\": false")) fail_msg("bench.json lacks busy:\n%s", json);
    free(json);
}

/* --profile: a cost row per technique whose covered pixels lie within the frame, and the
 * nominal search steps of a fixed-step search (relief: 16 linear + 6 binary + 16 shadow
 * steps toward the scene's one light; 40 + 6 + 20 with --set). */
static void test_app_bench_profile_reports_cost_per_pixel(void **state) {
    (void)state;
    static char out[65536];
    char args[4096];
    snprintf(args, sizeof(args),
             "bench %s --techniques flat,relief --frames 1 --size 64x48 --threads 1 --profile",
             BRICKS);
    assert_int_equal(run_capture_stdout(args, out, sizeof(out)), 0);
    const char *profile = strstr(out, "per covered pixel");
    if (!profile) fail_msg("no profile table:\n%s", out);
    static const char *const techniques[] = {"flat", "relief"};
    for (int t = 0; t < 2; t++) {
        char key[64];
        snprintf(key, sizeof(key), "bricks-plane         %-14s", techniques[t]);
        const char *row = strstr(profile, key);
        if (!row) fail_msg("no profile row for %s:\n%s", techniques[t], out);
        double covered = 0.0, per_fragment = 0.0, ns = 0.0, cycles = 0.0;
        char steps[32] = "";
        int fields = sscanf(row + strlen(key), "%lf %lf %lf %lf %31s", &covered, &per_fragment, &ns,
                            &cycles, steps);
        assert_int_equal(fields, 5);
        if (!(covered > 0.0 && covered <= 64.0 * 48.0)) fail_msg("covered %g", covered);
        if (!(per_fragment >= 1.0)) fail_msg("fragments a pixel %g", per_fragment);
        if (!(ns > 0.0)) fail_msg("ns a pixel %g", ns);
        assert_string_equal(steps, t == 0 ? "-" : "38");
    }
    snprintf(args, sizeof(args),
             "bench %s --techniques relief --frames 1 --size 32x32 --threads 1 --profile "
             "--set relief.linear_steps=40 --set relief.shadow_steps=20",
             BRICKS);
    assert_int_equal(run_capture_stdout(args, out, sizeof(out)), 0);
    profile = strstr(out, "per covered pixel");
    assert_non_null(profile);
    const char *row = strstr(profile, "relief");
    assert_non_null(row);
    double covered, per_fragment, ns, cycles, steps;
    assert_int_equal(sscanf(row + strlen("relief"), "%lf %lf %lf %lf %lf", &covered, &per_fragment,
                            &ns, &cycles, &steps),
                     5);
    assert_true(steps == 66.0);
}

/* The covered pixels of the last frame bench's --profile reports for flat on bricks-plane. */
static double bench_covered_pixels(const char *extra) {
    static char out[65536];
    char args[4096];
    snprintf(args, sizeof(args),
             "bench %s --techniques flat --frames 1 --size 64x48 --threads 1 --profile %s", BRICKS,
             extra);
    assert_int_equal(run_capture_stdout(args, out, sizeof(out)), 0);
    const char *profile = strstr(out, "per covered pixel");
    if (!profile) fail_msg("no profile table:\n%s", out);
    const char *row = strstr(profile, "bricks-plane");
    if (!row) fail_msg("no profile row:\n%s", out);
    double covered = -1.0;
    assert_int_equal(sscanf(row + strlen("bricks-plane"), " flat %lf", &covered), 1);
    return covered;
}

/* --orbit N turns the camera 1/N of a turn a frame: the one-thread run's last frame (2 warm-up
 * frames and 1 timed: the third) sees the square plane 45 degrees round with N = 16, so it
 * covers other pixels; with N = 1 every frame is the scene's own view again. */
static void test_app_bench_orbit_turns_the_camera(void **state) {
    (void)state;
    double still = bench_covered_pixels("");
    assert_true(still > 0.0);
    assert_true(bench_covered_pixels("--orbit 1") == still);
    double turned = bench_covered_pixels("--orbit 16");
    if (!(fabs(turned - still) > 10.0)) fail_msg("covered %g turned, %g still", turned, still);
}

static void test_app_bench_unknown_technique_is_usage_error(void **state) {
    (void)state;
    const char *err = NULL;
    char args[4096];
    snprintf(args, sizeof(args), "bench %s --techniques flat,nope --frames 1", BRICKS);
    assert_int_equal(test_run_meso(args, &err), 2);
    assert_non_null(strstr(err, "meso: bench: --techniques: unknown technique 'nope'"));
}

static void test_app_info_describes_scene_png_and_bake(void **state) {
    (void)state;
    static char out[65536];
    char args[4096];
    snprintf(args, sizeof(args), "info %s", BRICKS);
    assert_int_equal(run_capture_stdout(args, out, sizeof(out)), 0);
    assert_non_null(strstr(out, "objects: 1"));
    assert_non_null(strstr(out, "height field"));
    assert_non_null(strstr(out, "depth"));
    assert_non_null(strstr(out, "technique:"));

    meso_context *ctx = test_context(1);
    meso_image *image = NULL;
    assert_int_equal(meso_image_create(ctx, 5, 3, 2, &image), MESO_OK);
    for (int i = 0; i < 5 * 3 * 2; i++) image->pixels[i] = i % 2 ? 1.0f : 0.25f;
    const char *png = test_path(test_temp_dir(), "grey-alpha.png");
    meso_png_desc linear = {.encoding = MESO_ENCODING_LINEAR, .bit_depth = 16};
    assert_int_equal(meso_image_save_png(ctx, image, png, &linear), MESO_OK);
    meso_image_destroy(image);
    snprintf(args, sizeof(args), "info %s", png);
    assert_int_equal(run_capture_stdout(args, out, sizeof(out)), 0);
    assert_non_null(strstr(out, "5x3, 2 channels"));
    assert_non_null(strstr(out, "16-bit grey+alpha"));
    assert_non_null(strstr(out, "min 0.2500  max 0.2500"));

    float values[6] = {1, 2, 3, 4, 5, 6};
    meso_bake_file bake = {.kind = "test",
                           .kind_version = 3,
                           .source_hash = 0xabcdef,
                           .params_json = "{\"answer\": 42}",
                           .num_arrays = 1};
    bake.arrays[0] = (meso_bake_array){
        .name = "values", .type = MESO_BAKE_F32, .num_dims = 2, .dims = {2, 3}, .data = values};
    const char *bake_path = test_path(test_temp_dir(), "test.mesobake");
    assert_int_equal(meso_bake_file_save(ctx, &bake, bake_path), MESO_OK);
    meso_context_destroy(ctx);
    snprintf(args, sizeof(args), "info %s", bake_path);
    assert_int_equal(run_capture_stdout(args, out, sizeof(out)), 0);
    assert_non_null(strstr(out, "kind: test (version 3)"));
    assert_non_null(strstr(out, "\"answer\": 42"));
    assert_non_null(strstr(out, "values"));
    assert_non_null(strstr(out, "[2 x 3]"));
}

static void test_app_info_on_folder_is_bad_input(void **state) {
    (void)state;
    const char *err = NULL;
    char args[4096];
    snprintf(args, sizeof(args), "info %s", test_temp_dir());
    assert_int_equal(test_run_meso(args, &err), 2);
    assert_non_null(strstr(err, "is a folder"));
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_app_info_says_where_the_shell_folds),
        cmocka_unit_test(test_app_bench_prints_table_and_writes_json),
        cmocka_unit_test(test_app_bench_busy_runs_a_spinner_beside),
        cmocka_unit_test(test_app_bench_profile_reports_cost_per_pixel),
        cmocka_unit_test(test_app_bench_orbit_turns_the_camera),
        cmocka_unit_test(test_app_bench_unknown_technique_is_usage_error),
        cmocka_unit_test(test_app_info_describes_scene_png_and_bake),
        cmocka_unit_test(test_app_info_on_folder_is_bad_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
