/* The command line's technique options: --set T.NAME=V on render, bench and demo, meso help
 * TECHNIQUE, options keyed by technique in --techniques runs, meso info refusing what render
 * refuses, and -o=x. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "test_util.h"

#define BRICKS MESO_SOURCE_DIR "/examples/bricks-plane.json"

static const char *fresh_dir(const char *name) {
    static char copy[8][1024];
    static int next;
    char *out = copy[next++ % 8];
    snprintf(out, 1024, "%s", test_path(test_temp_dir(), name));
    mkdir(out, 0755);
    return out;
}

static void run_ok(const char *arguments) {
    const char *err = NULL;
    int status = test_run_meso(arguments, &err);
    if (status != 0) fail_msg("meso %s: status %d, stderr: %s", arguments, status, err);
}

static void run_fails_with(const char *arguments, int expected, const char *message) {
    const char *err = NULL;
    int status = test_run_meso(arguments, &err);
    if (status != expected) fail_msg("meso %s: status %d, stderr: %s", arguments, status, err);
    if (!strstr(err, message)) fail_msg("meso %s: '%s' lacks '%s'", arguments, err, message);
    /* one line */
    const char *newline = strchr(err, '\n');
    assert_true(newline && newline[1] == 0);
}

static bool same_file(const char *a, const char *b) {
    char command[4096];
    snprintf(command, sizeof command, "cmp -s '%s' '%s'", a, b);
    return system(command) == 0;
}

/* The bricks example with its technique replaced by `technique_text` (JSON after the key). */
static const char *scene_with(const char *dir, const char *name, const char *technique_text) {
    FILE *in = fopen(BRICKS, "rb");
    assert_non_null(in);
    char text[8192];
    size_t n = fread(text, 1, sizeof text - 1, in);
    fclose(in);
    text[n] = 0;
    char *at = strstr(text, "\"technique\": \"bump\"");
    assert_non_null(at);
    char out[9000];
    snprintf(out, sizeof out, "%.*s\"technique\": %s%s", (int)(at - text), text, technique_text,
             at + strlen("\"technique\": \"bump\""));
    const char *path = test_path(dir, name);
    test_write_file(path, out, strlen(out));
    return path;
}

static void test_app_set_changes_the_technique_and_is_checked(void **state) {
    (void)state;
    const char *dir = fresh_dir("set");
    char args[4096];
    snprintf(args, sizeof args, "render %s -o %s --technique relief --size 48x48 --quiet", BRICKS,
             test_path(dir, "default.png"));
    run_ok(args);
    snprintf(args, sizeof args,
             "render %s -o %s --technique relief --size 48x48 --quiet --set relief.linear_steps=1 "
             "--set=relief.binary_steps=0",
             BRICKS, test_path(dir, "coarse.png"));
    run_ok(args);
    assert_false(same_file(test_path(dir, "default.png"), test_path(dir, "coarse.png")));
    /* the same settings from the scene's keyed options give the same bytes */
    const char *keyed = scene_with(dir, "keyed.json",
                                   "\"bump\", \"technique_options\": {\"relief\": "
                                   "{\"linear_steps\": 1, \"binary_steps\": 0}}");
    snprintf(args, sizeof args, "render %s -o %s --technique relief --size 48x48 --quiet", keyed,
             test_path(dir, "keyed.png"));
    run_ok(args);
    assert_true(same_file(test_path(dir, "keyed.png"), test_path(dir, "coarse.png")));

    snprintf(args, sizeof args, "render %s -o %s --set relief.linear_stepz=3", BRICKS,
             test_path(dir, "never.png"));
    run_fails_with(args, 2,
                   "meso: render: --set relief.linear_stepz: unknown option of technique "
                   "'relief' (known: linear_steps,");
    snprintf(args, sizeof args, "render %s -o %s --set relief.linear_steps=2000", BRICKS,
             test_path(dir, "never.png"));
    run_fails_with(args, 2, "--set relief.linear_steps: 2000 is not an integer in 1..1024");
    snprintf(args, sizeof args, "render %s -o %s --set linear_steps=2", BRICKS,
             test_path(dir, "never.png"));
    run_fails_with(args, 2, "--set: 'linear_steps=2' is not TECHNIQUE.OPTION=VALUE");
    snprintf(args, sizeof args, "bench %s --techniques relief --set vdm.shadows=maybe", BRICKS);
    run_fails_with(args, 2, "'maybe' is not a number, true or false");
    run_fails_with("demo --set relif.x=1", 2, "--set relif.x: unknown technique 'relif'");
    FILE *never = fopen(test_path(dir, "never.png"), "rb");
    assert_null(never);
}

/* Defect: relief's flat options made every other technique of --techniques fail. */
static void test_app_flat_options_do_not_fail_other_techniques(void **state) {
    (void)state;
    const char *dir = fresh_dir("flat-options");
    const char *scene =
        scene_with(dir, "relief.json", "\"relief\", \"technique_options\": {\"linear_steps\": 64}");
    char args[4096];
    snprintf(args, sizeof args,
             "render %s --techniques flat,bump,relief -o %s --size 32x32 --frames 1 --set "
             "reference.view_adaptive=1",
             scene, test_path(dir, "out"));
    const char *err = NULL;
    int status = test_run_meso(args, &err);
    if (status != 0 || strstr(err, "warning") || strstr(err, "failed"))
        fail_msg("status %d, stderr: %s", status, err);
    snprintf(args, sizeof args, "render %s -o %s --technique bump --size 32x32 --quiet", scene,
             test_path(dir, "bump.png"));
    run_ok(args);
}

static void test_app_info_refuses_what_render_refuses(void **state) {
    (void)state;
    const char *dir = fresh_dir("info-typo");
    const char *typo = scene_with(dir, "typo.json", "\"relif\"");
    char args[4096];
    snprintf(args, sizeof args, "info %s", typo);
    run_fails_with(args, 2, "typo.json: objects[0].technique: unknown technique 'relif' (known:");
    snprintf(args, sizeof args, "render %s -o %s", typo, test_path(dir, "x.png"));
    run_fails_with(args, 2, "typo.json: objects[0].technique: unknown technique 'relif'");
    const char *option = scene_with(
        dir, "option.json", "\"bump\", \"technique_options\": {\"vdm\": {\"shadowz\": true}}");
    snprintf(args, sizeof args, "info %s", option);
    run_fails_with(args, 2,
                   "option.json: objects[0].technique_options.vdm.shadowz: unknown option of "
                   "technique 'vdm'");
}

static void test_app_help_prints_a_techniques_option_table(void **state) {
    (void)state;
    char command[2048];
    snprintf(command, sizeof command, "%s help relief", MESO_PROGRAM);
    FILE *p = popen(command, "r");
    assert_non_null(p);
    char out[8192];
    size_t n = fread(out, 1, sizeof out - 1, p);
    out[n] = 0;
    assert_int_equal(pclose(p), 0);
    assert_non_null(strstr(out, "relief: relief mapping"));
    assert_non_null(strstr(out, "--set relief.NAME=V"));
    assert_non_null(strstr(out, "linear_steps         integer  1..1024        16"));
    assert_non_null(strstr(out, "shadows              boolean  true, false    true"));
    run_fails_with("help relif", 2, "'relif' is neither a command nor a technique");
}

static void test_app_short_option_takes_its_value_after_equals(void **state) {
    (void)state;
    const char *dir = fresh_dir("short-equals");
    char args[4096];
    snprintf(args, sizeof args, "render %s -o=%s --size 16x16 --quiet", BRICKS,
             test_path(dir, "x.png"));
    run_ok(args);
    struct stat st;
    assert_int_equal(stat(test_path(dir, "x.png"), &st), 0);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_app_set_changes_the_technique_and_is_checked),
        cmocka_unit_test(test_app_flat_options_do_not_fail_other_techniques),
        cmocka_unit_test(test_app_info_refuses_what_render_refuses),
        cmocka_unit_test(test_app_help_prints_a_techniques_option_table),
        cmocka_unit_test(test_app_short_option_takes_its_value_after_equals),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
