/* meso view under SDL's offscreen driver, driven by --events: a scripted orbit, light drag,
 * zoom and pan, then the screenshot (P) is byte for byte `meso render` of the scene file the
 * viewer wrote (W); the camera options and technique keys agree with meso render; the
 * reference and difference images come back from the background thread; no display and a
 * bad scene are one line each. Also meso render --orbit and the camera options' errors. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "test_util.h"

#define BRICKS MESO_SOURCE_DIR "/examples/bricks-plane.json"
#define SIZE "--size 96x72"

static char dir[1024];

static void assert_same_bytes(const char *a, const char *b) {
    size_t size_a, size_b;
    char *data_a = test_read_file(a, &size_a), *data_b = test_read_file(b, &size_b);
    if (size_a != size_b || memcmp(data_a, data_b, size_a) != 0)
        fail_msg("%s and %s differ (%zu and %zu bytes)", a, b, size_a, size_b);
    free(data_a);
    free(data_b);
}

static void run_ok(const char *format, ...) __attribute__((format(printf, 1, 2)));
static void run_ok(const char *format, ...) {
    char arguments[4096];
    va_list args;
    va_start(args, format);
    vsnprintf(arguments, sizeof(arguments), format, args);
    va_end(args);
    const char *err = NULL;
    int status = test_run_meso(arguments, &err);
    if (status != 0) fail_msg("meso %s: status %d, stderr: %s", arguments, status, err);
}

static const char *in_dir(const char *name) {
    static char paths[8][1200];
    static int next;
    char *out = paths[next++ % 8];
    snprintf(out, 1200, "%s/%s", dir, name);
    return out;
}

/* The window tests run only where meso view was built (SDL2 found). */
static int setup(void **state) {
    (void)state;
    snprintf(dir, sizeof(dir), "%s", test_path(test_temp_dir(), "view"));
    mkdir(dir, 0755);
    setenv("MESO_CACHE_DIR", in_dir("cache"), 1); /* the plane's bakes, once for all tests */
    setenv("SDL_VIDEODRIVER", "offscreen", 1);
    return 0;
}

static bool viewer_built(void) {
    const char *err = NULL;
    test_run_meso("view " BRICKS " --events 'frames 1' --techniques bump " SIZE " --quiet", &err);
    return strstr(err, "without SDL2") == NULL;
}

static void test_app_view_scripted_screenshot_is_render_of_the_written_scene(void **state) {
    (void)state;
    if (!viewer_built()) skip();
    run_ok("view %s %s --techniques bump,relief --technique relief --quiet --events "
           "'drag 40,10; light 30,-20; wheel 2; pan 5,5; drag -3,25; key W; key p' "
           "--screenshot %s --save-scene %s",
           BRICKS, SIZE, in_dir("scripted.png"), in_dir("scripted.json"));
    run_ok("render %s %s --technique relief -o %s --quiet", in_dir("scripted.json"), SIZE,
           in_dir("scripted-render.png"));
    assert_same_bytes(in_dir("scripted.png"), in_dir("scripted-render.png"));
    /* and the view did move: the scene's own camera gives another image */
    run_ok("render %s %s --technique relief -o %s --quiet", BRICKS, SIZE, in_dir("home.png"));
    size_t a, b;
    char *moved = test_read_file(in_dir("scripted.png"), &a),
         *home = test_read_file(in_dir("home.png"), &b);
    assert_true(a != b || memcmp(moved, home, a) != 0);
    free(moved);
    free(home);
}

static void test_app_view_camera_options_and_technique_keys_match_render(void **state) {
    (void)state;
    if (!viewer_built()) skip();
    const char *camera = "--eye 0.4,1.1,1.6 --target 0.1,0,0 --fov 35 --light -0.3,0.8,0.2";
    /* Tab from bump to relief: the screenshot is relief's */
    run_ok("view %s %s %s --techniques bump,relief --technique bump --quiet --events "
           "'key tab; key p' --screenshot %s",
           BRICKS, SIZE, camera, in_dir("options.png"));
    run_ok("render %s %s %s --technique relief -o %s --quiet", BRICKS, SIZE, camera,
           in_dir("options-render.png"));
    assert_same_bytes(in_dir("options.png"), in_dir("options-render.png"));
}

static void test_app_view_reference_and_difference_come_back(void **state) {
    (void)state;
    if (!viewer_built()) skip();
    /* C starts the reference on its own thread; wait holds the script until it is in; the
     * display then shows it, and V steps on to the difference */
    run_ok("view %s --size 48x36 --techniques bump --quiet --events "
           "'key c; wait; key p' --screenshot %s",
           BRICKS, in_dir("reference.png"));
    run_ok("view %s --size 48x36 --techniques bump --quiet --events "
           "'key c; wait; key v; key p' --screenshot %s",
           BRICKS, in_dir("difference.png"));
    meso_context *ctx = test_context(1);
    meso_image *reference = NULL, *difference = NULL;
    assert_int_equal(meso_image_load_png(ctx, in_dir("reference.png"), &reference), MESO_OK);
    assert_int_equal(meso_image_load_png(ctx, in_dir("difference.png"), &difference), MESO_OK);
    assert_int_equal(reference->width, 48);
    assert_int_equal(difference->height, 36);
    meso_image_destroy(reference);
    meso_image_destroy(difference);
    meso_context_destroy(ctx);
}

static int count_lines(const char *text) {
    int lines = 0;
    for (; *text; text++) lines += *text == '\n';
    return lines;
}

static void test_app_view_without_display_says_so_and_suggests_orbit(void **state) {
    (void)state;
    if (!viewer_built()) skip();
    const char *err = NULL;
    char saved_driver[64];
    snprintf(saved_driver, sizeof(saved_driver), "%s", getenv("SDL_VIDEODRIVER"));
    unsetenv("SDL_VIDEODRIVER");
    unsetenv("DISPLAY");
    unsetenv("WAYLAND_DISPLAY");
    int status = test_run_meso("view " BRICKS, &err);
    setenv("SDL_VIDEODRIVER", saved_driver, 1);
    assert_int_equal(status, 1);
    assert_non_null(strstr(err, "meso: view: no display"));
    assert_non_null(strstr(err, "--orbit"));
    assert_int_equal(count_lines(err), 1);
}

static void test_app_view_scene_error_is_render_s_line(void **state) {
    (void)state;
    char view_err[4096];
    const char *err = NULL;
    test_write_file(in_dir("bad.json"), "{\"camera\": {\"eye\": [0, 1]}}", 27);
    char args[2048];
    snprintf(args, sizeof(args), "view %s --events 'key q'", in_dir("bad.json"));
    int view_status = test_run_meso(args, &err);
    snprintf(view_err, sizeof(view_err), "%s", err);
    snprintf(args, sizeof(args), "render %s -o %s", in_dir("bad.json"), in_dir("bad.png"));
    int render_status = test_run_meso(args, &err);
    if (strstr(view_err, "without SDL2")) skip();
    assert_int_equal(view_status, 2);
    assert_int_equal(render_status, 2);
    assert_string_equal(view_err, err);
    assert_int_equal(count_lines(err), 1);
}

static void test_app_view_bad_events_are_usage_errors(void **state) {
    (void)state;
    if (!viewer_built()) skip();
    const char *err = NULL;
    assert_int_equal(test_run_meso("view " BRICKS " --events 'drag 1'", &err), 2);
    assert_non_null(strstr(err, "meso: --events: event 1: 'drag 1': expected DX,DY"));
    assert_int_equal(test_run_meso("view " BRICKS " --techniques reference", &err), 2);
    assert_non_null(strstr(err, "'reference' cannot draw"));
}

static void test_app_render_orbit_writes_numbered_frames_from_the_scene_s_view(void **state) {
    (void)state;
    run_ok("render %s %s --technique bump --orbit 3 -o %s --quiet", BRICKS, SIZE, in_dir("orbit"));
    run_ok("render %s %s --technique bump -o %s --quiet", BRICKS, SIZE, in_dir("orbit-0.png"));
    assert_same_bytes(in_dir("orbit/frame-0000.png"), in_dir("orbit-0.png"));
    size_t a, b;
    char *first = test_read_file(in_dir("orbit/frame-0001.png"), &a);
    char *second = test_read_file(in_dir("orbit/frame-0002.png"), &b);
    assert_true(a != b || memcmp(first, second, a) != 0);
    free(first);
    free(second);
    FILE *f = fopen(in_dir("orbit/frame-0003.png"), "rb");
    assert_null(f);
    /* with --techniques: a strip of frames per technique, the same frames as one at a time */
    run_ok("render %s %s --techniques bump,relief --orbit 3 -o %s --quiet", BRICKS, SIZE,
           in_dir("orbits"));
    assert_same_bytes(in_dir("orbits/bump/frame-0002.png"), in_dir("orbit/frame-0002.png"));
    f = fopen(in_dir("orbits/relief/frame-0002.png"), "rb");
    assert_non_null(f);
    fclose(f);
}

static void test_app_render_camera_options_reject_malformed_values(void **state) {
    (void)state;
    const char *err = NULL;
    assert_int_equal(test_run_meso("render " BRICKS " -o x.png --eye 1,2", &err), 2);
    assert_non_null(strstr(err, "--eye: '1,2' is not X,Y,Z"));
    assert_int_equal(test_run_meso("render " BRICKS " -o x.png --light 0,0,0", &err), 2);
    assert_non_null(strstr(err, "--light: the direction must not be zero"));
    assert_int_equal(test_run_meso("render " BRICKS " -o x.png --eye 0,0,0 --target 0,0,0", &err),
                     2);
    assert_non_null(strstr(err, "the eye must differ from the target"));
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_app_view_scripted_screenshot_is_render_of_the_written_scene),
        cmocka_unit_test(test_app_view_camera_options_and_technique_keys_match_render),
        cmocka_unit_test(test_app_view_reference_and_difference_come_back),
        cmocka_unit_test(test_app_view_without_display_says_so_and_suggests_orbit),
        cmocka_unit_test(test_app_view_scene_error_is_render_s_line),
        cmocka_unit_test(test_app_view_bad_events_are_usage_errors),
        cmocka_unit_test(test_app_render_orbit_writes_numbered_frames_from_the_scene_s_view),
        cmocka_unit_test(test_app_render_camera_options_reject_malformed_values),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
