/* The meso program on bad input: exit status 2 and ONE stderr line "meso: ..." naming the
 * file, for broken images, scenes and meshes; usage errors; --help everywhere. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

#include "test_util.h"

/* A minimal valid scene: one plane with procedural bricks, `depth` and `height_map` (JSON text)
 * and `shape` (JSON text) substituted. */
static const char *write_scene(const char *name, const char *shape, const char *height_map,
                               const char *depth, const char *objects_override) {
    char text[2048];
    char objects[1024];
    if (objects_override) {
        snprintf(objects, sizeof(objects), "%s", objects_override);
    } else {
        snprintf(objects, sizeof(objects),
                 "[{\"shape\": %s, \"mesostructure\": {\"height_map\": %s, \"depth\": %s},"
                 " \"technique\": \"bump\"}]",
                 shape, height_map, depth);
    }
    snprintf(text, sizeof(text),
             "{\n  \"image\": {\"width\": 32, \"height\": 32},\n"
             "  \"camera\": {\"eye\": [0, 1.5, 1.5], \"target\": [0, 0, 0], \"up\": [0, 1, 0],"
             " \"fov_y_deg\": 45},\n"
             "  \"lights\": [{\"type\": \"directional\", \"direction\": [0.3, 1, 0.2],"
             " \"color\": [1, 1, 1]}],\n"
             "  \"objects\": %s\n}\n",
             objects);
    const char *path = test_path(test_temp_dir(), name);
    test_write_file(path, text, strlen(text));
    return path;
}

/* Status 2, exactly one line on stderr, starting "meso: " and containing `needle`. */
static void expect_bad_input(const char *arguments, const char *needle) {
    const char *err = NULL;
    int status = test_run_meso(arguments, &err);
    if (status != 2 || strncmp(err, "meso: ", 6) != 0 || !strstr(err, needle))
        fail_msg("meso %s\n  status %d (want 2), stderr: %s  (want one line naming '%s')",
                 arguments, status, err, needle);
    size_t length = strlen(err);
    assert_true(length > 0 && err[length - 1] == '\n');
    assert_null(memchr(err, '\n', length - 1)); /* one line */
}

static void expect_bad_input_either(const char *arguments, const char *a, const char *b) {
    const char *err = NULL;
    int status = test_run_meso(arguments, &err);
    if (status != 2 || strncmp(err, "meso: ", 6) != 0 || (!strstr(err, a) && !strstr(err, b)))
        fail_msg("meso %s\n  status %d (want 2), stderr: %s  (want one line naming '%s' or '%s')",
                 arguments, status, err, a, b);
    size_t length = strlen(err);
    assert_null(memchr(err, '\n', length - 1));
}

/* A PNG cut in half: valid signature and header, missing image data. */
static const char *write_truncated_png(void) {
    meso_context *ctx = test_context(1);
    meso_image *image = NULL;
    assert_int_equal(meso_image_create(ctx, 32, 32, 1, &image), MESO_OK);
    for (int i = 0; i < 32 * 32; i++) image->pixels[i] = (float)((i * 37) % 101) / 100.0f;
    const char *full = test_path(test_temp_dir(), "full.png");
    assert_int_equal(meso_image_save_png(ctx, image, full, NULL), MESO_OK);
    meso_image_destroy(image);
    meso_context_destroy(ctx);
    size_t size = 0;
    char *data = test_read_file(full, &size);
    const char *path = test_path(test_temp_dir(), "truncated.png");
    test_write_file(path, data, size / 2);
    free(data);
    return path;
}

static uint32_t crc32_png(const unsigned char *data, size_t size) {
    uint32_t crc = 0xffffffffu;
    for (size_t i = 0; i < size; i++) {
        crc ^= data[i];
        for (int k = 0; k < 8; k++) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
    }
    return crc ^ 0xffffffffu;
}

static void put_be32(unsigned char *p, uint32_t v) {
    p[0] = (unsigned char)(v >> 24);
    p[1] = (unsigned char)(v >> 16);
    p[2] = (unsigned char)(v >> 8);
    p[3] = (unsigned char)v;
}

/* A PNG whose header declares 100000 x 100000 8-bit grey pixels (10 GB), with a valid CRC, a
 * tiny IDAT and IEND: the loader must refuse it from the header, before allocating. */
static const char *write_huge_png(void) {
    unsigned char png[8 + 25 + 12 + 12];
    static const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    memcpy(png, signature, 8);
    unsigned char *ihdr = png + 8;
    put_be32(ihdr, 13);
    memcpy(ihdr + 4, "IHDR", 4);
    put_be32(ihdr + 8, 100000);
    put_be32(ihdr + 12, 100000);
    ihdr[16] = 8; /* bit depth */
    ihdr[17] = 0; /* grey */
    ihdr[18] = ihdr[19] = ihdr[20] = 0;
    put_be32(ihdr + 21, crc32_png(ihdr + 4, 17));
    unsigned char *idat = ihdr + 25;
    put_be32(idat, 0);
    memcpy(idat + 4, "IDAT", 4);
    put_be32(idat + 8, crc32_png(idat + 4, 4));
    unsigned char *iend = idat + 12;
    put_be32(iend, 0);
    memcpy(iend + 4, "IEND", 4);
    put_be32(iend + 8, crc32_png(iend + 4, 4));
    const char *path = test_path(test_temp_dir(), "huge.png");
    test_write_file(path, png, sizeof(png));
    return path;
}

static const char *out_png(void) { return test_path(test_temp_dir(), "out.png"); }

static void test_app_truncated_png_names_the_file(void **state) {
    (void)state;
    const char *png = write_truncated_png();
    char args[4096];
    snprintf(args, sizeof(args), "info %s", png);
    expect_bad_input(args, "truncated.png");
    const char *scene =
        write_scene("truncated-map.json", "\"plane\"", "\"truncated.png\"", "0.1", NULL);
    snprintf(args, sizeof(args), "render %s -o %s", scene, out_png());
    expect_bad_input(args, "truncated.png");
}

static void test_app_huge_png_is_refused_naming_the_file(void **state) {
    (void)state;
    const char *png = write_huge_png();
    char args[4096];
    snprintf(args, sizeof(args), "info %s", png);
    expect_bad_input(args, "huge.png");
    const char *scene = write_scene("huge-map.json", "\"plane\"", "\"huge.png\"", "0.1", NULL);
    snprintf(args, sizeof(args), "render %s -o %s", scene, out_png());
    expect_bad_input(args, "huge.png");
}

static void test_app_malformed_json_names_the_file(void **state) {
    (void)state;
    const char *path = test_path(test_temp_dir(), "malformed.json");
    const char *text = "{\"image\": {\"width\": 32,, \"objects\": [";
    test_write_file(path, text, strlen(text));
    char args[4096];
    snprintf(args, sizeof(args), "render %s -o %s", path, out_png());
    expect_bad_input(args, "malformed.json");
    snprintf(args, sizeof(args), "info %s", path);
    expect_bad_input(args, "malformed.json");
}

static void test_app_unknown_technique_names_the_scene(void **state) {
    (void)state;
    const char *scene =
        write_scene("technique.json", "\"plane\"", "{\"procedural\": \"bricks\"}", "0.1", NULL);
    char args[4096];
    snprintf(args, sizeof(args), "render %s -o %s --technique nope", scene, out_png());
    expect_bad_input(args, "technique.json");
    expect_bad_input(args, "nope");
}

/* A mesh without texture coordinates under a mesostructure is drawn through the box
 * projection, with one note naming the file and the key (docs/scene-format.md); a bad
 * projection key is bad input. */
static void test_app_obj_without_uvs_is_projected_with_a_note(void **state) {
    (void)state;
    const char *obj = "v 0 0 0\nv 1 0 0\nv 0 0 -1\nf 1 2 3\n";
    test_write_file(test_path(test_temp_dir(), "nouv.obj"), obj, strlen(obj));
    const char *scene = write_scene("nouv.json", "{\"file\": \"nouv.obj\"}",
                                    "{\"procedural\": \"bricks\"}", "0.1", NULL);
    char args[4096];
    snprintf(args, sizeof(args), "render %s -o %s", scene, out_png());
    const char *err = NULL;
    int status = test_run_meso(args, &err);
    if (status != 0 || !strstr(err, "meso: warning: ") ||
        !strstr(err, "nouv.obj: the file has none") || !strstr(err, "\"uv_projection\": \"box\""))
        fail_msg("meso %s\n  status %d (want 0), stderr: %s", args, status, err);
    scene = write_scene("badproj.json", "{\"file\": \"nouv.obj\"}, \"uv_projection\": \"cubic\"",
                        "{\"procedural\": \"bricks\"}", "0.1", NULL);
    snprintf(args, sizeof(args), "render %s -o %s", scene, out_png());
    expect_bad_input(args, "objects[0].uv_projection: must be");
}

static void test_app_obj_with_nan_vertex_is_bad_input(void **state) {
    (void)state;
    const char *obj = "v 0 0 0\nv nan 0 0\nv 0 0 -1\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n";
    test_write_file(test_path(test_temp_dir(), "nan.obj"), obj, strlen(obj));
    const char *scene = write_scene("nan-obj.json", "{\"file\": \"nan.obj\"}",
                                    "{\"procedural\": \"bricks\"}", "0.1", NULL);
    char args[4096];
    snprintf(args, sizeof(args), "render %s -o %s", scene, out_png());
    expect_bad_input_either(args, "nan.obj", "nan-obj.json");
    snprintf(args, sizeof(args), "info %s", test_path(test_temp_dir(), "nan.obj"));
    expect_bad_input(args, "nan.obj");
}

static void test_app_missing_scene_names_the_file(void **state) {
    (void)state;
    char args[4096];
    snprintf(args, sizeof(args), "render %s -o %s", test_path(test_temp_dir(), "missing.json"),
             out_png());
    expect_bad_input(args, "missing.json");
    snprintf(args, sizeof(args), "info %s", test_path(test_temp_dir(), "missing.png"));
    expect_bad_input(args, "missing.png");
}

static void test_app_scene_without_objects_is_bad_input(void **state) {
    (void)state;
    const char *scene = write_scene("empty.json", NULL, NULL, NULL, "[]");
    char args[4096];
    snprintf(args, sizeof(args), "render %s -o %s", scene, out_png());
    expect_bad_input(args, "empty.json");
}

static void test_app_bad_depths_name_the_file(void **state) {
    (void)state;
    static const char *const depths[][2] = {
        {"negative-depth.json", "-0.1"},
        {"nan-depth.json", "NaN"},        /* not JSON: malformed */
        {"infinite-depth.json", "1e999"}, /* JSON parsers read this as +inf */
    };
    for (size_t i = 0; i < sizeof(depths) / sizeof(depths[0]); i++) {
        const char *scene = write_scene(depths[i][0], "\"plane\"", "{\"procedural\": \"bricks\"}",
                                        depths[i][1], NULL);
        char args[4096];
        snprintf(args, sizeof(args), "render %s -o %s", scene, out_png());
        expect_bad_input(args, depths[i][0]);
    }
}

static void test_app_usage_errors_exit_2(void **state) {
    (void)state;
    const char *scene =
        write_scene("usage.json", "\"plane\"", "{\"procedural\": \"bricks\"}", "0.1", NULL);
    char args[4096];
    snprintf(args, sizeof(args), "render %s -o %s --foo", scene, out_png());
    expect_bad_input(args, "render: unknown option '--foo'");
    snprintf(args, sizeof(args), "render %s", scene);
    expect_bad_input(args, "-o");
    snprintf(args, sizeof(args), "render %s -o %s --size 0x10", scene, out_png());
    expect_bad_input(args, "--size");
    snprintf(args, sizeof(args), "bench %s --orbit 0", scene); /* a turn in 0 frames */
    expect_bad_input(args, "bench: --orbit: '0' is not an integer in 1..1000000");
    expect_bad_input("nosuchcommand", "nosuchcommand");
    expect_bad_input("info", "info");
    snprintf(args, sizeof(args), "info %s", test_path(test_temp_dir(), "full.png.unknown"));
    test_write_file(test_path(test_temp_dir(), "full.png.unknown"), "hello", 5);
    expect_bad_input(args, "full.png.unknown");
}

/* Run meso with stdout captured; returns the exit status. */
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

static void test_app_help_exits_0_and_prints_usage(void **state) {
    (void)state;
    static char out[65536];
    static const char *const commands[] = {"--help",      "help render", "render --help",
                                           "info --help", "demo --help", "bench --help",
                                           "help bench"};
    for (size_t i = 0; i < sizeof(commands) / sizeof(commands[0]); i++) {
        int status = run_capture_stdout(commands[i], out, sizeof(out));
        if (status != 0 || !strstr(out, "Usage: meso"))
            fail_msg("meso %s: status %d, stdout: %.200s", commands[i], status, out);
    }
    assert_int_equal(run_capture_stdout("render --help", out, sizeof(out)), 0);
    assert_non_null(strstr(out, "--technique"));
    assert_non_null(strstr(out, "default"));
    assert_int_equal(run_capture_stdout("--version", out, sizeof(out)), 0);
    assert_non_null(strstr(out, MESO_VERSION_STRING));
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_app_truncated_png_names_the_file),
        cmocka_unit_test(test_app_huge_png_is_refused_naming_the_file),
        cmocka_unit_test(test_app_malformed_json_names_the_file),
        cmocka_unit_test(test_app_unknown_technique_names_the_scene),
        cmocka_unit_test(test_app_obj_without_uvs_is_projected_with_a_note),
        cmocka_unit_test(test_app_obj_with_nan_vertex_is_bad_input),
        cmocka_unit_test(test_app_missing_scene_names_the_file),
        cmocka_unit_test(test_app_scene_without_objects_is_bad_input),
        cmocka_unit_test(test_app_bad_depths_name_the_file),
        cmocka_unit_test(test_app_usage_errors_exit_2),
        cmocka_unit_test(test_app_help_exits_0_and_prints_usage),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
