/* The command line's contract as a new user meets it: a technique that cannot draw a scene is
 * "not applicable" (silently), an output meso cannot write is refused before any work, a
 * request the command cannot serve is a usage error (exit 2, one line), and `meso info` says
 * the same thing about a mesh file's material as it says about a scene using the file. */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "test_util.h"

#define EXAMPLES MESO_SOURCE_DIR "/examples"

/* The line of a results.csv for `technique` (a static copy), failing when there is none. */
static const char *csv_row(const char *csv, const char *technique) {
    static char row[1024];
    char key[64];
    snprintf(key, sizeof key, ",%s,", technique);
    const char *at = strstr(csv, key);
    if (!at) fail_msg("no row for %s in:\n%s", technique, csv);
    while (at > csv && at[-1] != '\n') at--;
    size_t length = strcspn(at, "\n");
    snprintf(row, sizeof row, "%.*s", (int)length, at);
    return row;
}

/* One line on stderr, ending in a newline. */
static void assert_one_line(const char *err) {
    if (!err[0] || strchr(err, '\n') != err + strlen(err) - 1)
        fail_msg("not one line on stderr:\n%s", err);
}

/* gdm draws solids that tile (Wang et al. 2004 §3: the GDM of one tile repeats over the
 * surface); a relief impostor's solid is a whole model. `--techniques` (and the demo, which
 * shares its code) skips it as every technique that cannot draw a scene is skipped: "not
 * applicable", no warning, not "failed". */
static void test_gdm_is_not_applicable_to_an_impostor(void **state) {
    (void)state;
    /* examples/teapot-impostor.json, coarser (quick under the sanitizers) */
    const char *scene = test_path(test_temp_dir(), "impostor.json");
    const char text[] = "{\"objects\": [{\"name\": \"teapot impostor\", \"shape\": \"plane\", "
                        "\"size\": 3.4, \"mesostructure\": {\"solid\": {\"impostor\": "
                        "\"teapot\", \"resolution\": 24}, \"depth\": 1.6667}, "
                        "\"technique\": \"relief_layers\"}]}";
    test_write_file(scene, text, strlen(text));
    const char *dir = test_path(test_temp_dir(), "impostor");
    char arguments[2048];
    snprintf(arguments, sizeof arguments,
             "render %s --techniques flat,gdm --size 16x16 --frames 1 "
             "--set reference.resolution=8 -o %s",
             scene, dir);
    const char *err = NULL;
    assert_int_equal(test_run_meso(arguments, &err), 0);
    if (strstr(err, "warning") || strstr(err, "failed")) fail_msg("stderr said:\n%s", err);
    size_t size;
    char *csv = test_read_file(test_path(dir, "results.csv"), &size);
    const char *row = csv_row(csv, "gdm");
    if (!strstr(row, ",gdm,skipped,")) fail_msg("gdm's row: %s", row);
    free(csv);
    /* drawn with gdm on its own: refused before any bake, naming the object */
    snprintf(arguments, sizeof arguments, "render %s --technique gdm --size 16x16 -o %s", scene,
             test_path(test_temp_dir(), "impostor-gdm.png"));
    assert_int_equal(test_run_meso(arguments, &err), 2);
    assert_one_line(err);
    if (!strstr(err, "teapot impostor: technique 'gdm' does not accept")) fail_msg("%s", err);
}

/* An image output is named for a format meso writes (.png, .exr): `-o out.jpg` wrote a PNG
 * under a JPEG's name. Any other extension, or none, is refused before any work (the inputs
 * here do not exist: the output is what is refused), exit 2, one line naming the formats. */
static void test_an_image_output_meso_cannot_write_is_refused(void **state) {
    (void)state;
    const char *dir = test_temp_dir();
    const struct {
        const char *command; /* %s: the output */
        const char *output;
        const char *says;
    } cases[] = {
        {"render no-such-scene.json -o %s", "out.jpg", "meso writes .png and .exr"},
        {"render no-such-scene.json -o %s", "OUT.JPEG", "meso writes .png and .exr"},
        {"render no-such-scene.json -o %s", "out", "meso writes .png and .exr"},
        {"render no-such-scene.json -o ok.png --coverage %s", "mask.tif",
         "meso writes .png and .exr"},
        {"compare no-a.png no-b.png -o %s", "diff.jpg", "meso writes .png and .exr"},
        {"compare no-a.png no-b.png --sheet %s", "sheet.webp", "meso writes .png and .exr"},
        {"view no-such-scene.json --screenshot %s", "shot.exr", "meso view writes .png"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const char *output = test_path(dir, cases[i].output);
        char command[1200], arguments[1400];
        snprintf(command, sizeof command, cases[i].command, output);
        snprintf(arguments, sizeof arguments, "%s", command);
        const char *err = NULL;
        int status = test_run_meso(arguments, &err);
        if (strstr(err, "SDL2")) continue; /* a build without the viewer says that first */
        if (status != 2 || !strstr(err, cases[i].output) || !strstr(err, cases[i].says))
            fail_msg("meso %s: status %d, stderr:\n%s", arguments, status, err);
        assert_one_line(err);
        assert_int_not_equal(access(output, F_OK), 0);
    }
    /* the extensions it writes, in any case */
    char arguments[2048];
    const char *err = NULL;
    snprintf(arguments, sizeof arguments, "render %s/bricks-plane.json --size 8x8 -o %s", EXAMPLES,
             test_path(dir, "small.PNG"));
    assert_int_equal(test_run_meso(arguments, &err), 0);
}

/* A technique the command cannot serve is a usage error (README: 2 bad input or usage), said
 * in one line before any work: the GL back end and the texture export have no tessellation
 * shader. What the machine lacks (no EGL, no OpenGL 3.3) stays 1 (tests/gl). */
static void test_a_technique_the_command_cannot_serve_is_a_usage_error(void **state) {
    (void)state;
    const char *dir = test_path(test_temp_dir(), "bake-tessellation");
    const char *png = test_path(test_temp_dir(), "gl-tessellation.png");
    const char *commands[] = {"bake %s/bricks-plane.json -o %s --technique tessellation",
                              "render %s/bricks-plane.json --backend gl --technique tessellation "
                              "-o %s",
                              "render %s/bricks-plane.json --backend gl --technique tessellation "
                              "--samples 4 -o %s"};
    const char *outputs[] = {dir, png, png};
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++) {
        char arguments[2048];
        snprintf(arguments, sizeof arguments, commands[i], EXAMPLES, outputs[i]);
        const char *err = NULL;
        int status = test_run_meso(arguments, &err);
        if (status != 2) fail_msg("meso %s: status %d (not 2): %s", arguments, status, err);
        assert_one_line(err);
        assert_int_not_equal(access(outputs[i], F_OK), 0);
    }
    /* the same for a scene whose own technique has no shader */
    const char *scene = test_path(test_temp_dir(), "tessellated.json");
    const char text[] = "{\"objects\": [{\"shape\": \"plane\", \"technique\": \"tessellation\", "
                        "\"mesostructure\": {\"height_map\": {\"procedural\": \"bricks\", "
                        "\"resolution\": 64}, \"depth\": 0.05}}]}";
    test_write_file(scene, text, strlen(text));
    char arguments[2048];
    const char *err = NULL;
    snprintf(arguments, sizeof arguments, "bake %s -o %s", scene, dir);
    assert_int_equal(test_run_meso(arguments, &err), 2);
    assert_one_line(err);
    if (!strstr(err, "'tessellation' has no GL shader")) fail_msg("%s", err);
}

/* The program carries every example of examples/, those reading examples/assets included
 * (chainmail-plane's tile mesh): `meso demo` and `meso bench` without scenes render them all
 * (docs/cli.md). Bench, the quicker of the two, shows which were loaded. */
static void test_every_example_is_built_into_the_program(void **state) {
    (void)state;
    const char *json = test_path(test_temp_dir(), "bench.json");
    char arguments[2048];
    snprintf(arguments, sizeof arguments,
             "bench --techniques flat --frames 1 --size 8x8 --threads 1 --json %s", json);
    const char *err = NULL;
    if (test_run_meso(arguments, &err) != 0) fail_msg("%s", err);
    size_t size;
    char *text = test_read_file(json, &size);
    DIR *dir = opendir(EXAMPLES);
    assert_non_null(dir);
    int examples = 0;
    for (struct dirent *entry; (entry = readdir(dir)) != NULL;) {
        size_t length = strlen(entry->d_name);
        if (length < 6 || strcmp(entry->d_name + length - 5, ".json") != 0) continue;
        char key[300];
        snprintf(key, sizeof key, "\"scene\": \"%.*s\"", (int)(length - 5), entry->d_name);
        if (!strstr(text, key)) fail_msg("%s is not built in", entry->d_name);
        examples++;
    }
    closedir(dir);
    assert_true(examples >= 10);
    free(text);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gdm_is_not_applicable_to_an_impostor),
        cmocka_unit_test(test_an_image_output_meso_cannot_write_is_refused),
        cmocka_unit_test(test_a_technique_the_command_cannot_serve_is_a_usage_error),
        cmocka_unit_test(test_every_example_is_built_into_the_program),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
