/* Scene files that do not load: each error returns its exact code, leaves no scene, and the
 * message names the file and the key path. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "test_util.h"

/* Parse `json` as "scene.json", expect `code`, and return the message. */
static const char *parse_fails(meso_context *ctx, const char *json, meso_result code) {
    meso_scene *scene = (meso_scene *)1;
    meso_result r = meso_scene_parse(ctx, json, "scene.json", test_temp_dir(), &scene);
    if (r != code)
        fail_msg("expected %s, got %s: %s", meso_result_string(code), meso_result_string(r),
                 meso_context_last_error(ctx));
    assert_null(scene);
    return meso_context_last_error(ctx);
}

static void assert_contains(const char *message, const char *part) {
    if (!strstr(message, part)) fail_msg("\"%s\" does not contain \"%s\"", message, part);
}

/* One object around a fragment of object keys. */
static char *object_scene(const char *fragment) {
    static char buffer[4096];
    snprintf(buffer, sizeof(buffer), "{\"objects\": [{%s}]}", fragment);
    return buffer;
}

static void test_malformed_json_names_the_line(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    const char *message =
        parse_fails(ctx, "{\n  \"image\": {\n    \"width\": 5,,\n  }\n}", MESO_ERROR_FORMAT);
    assert_string_equal(message, "scene.json: malformed JSON near line 3");
    parse_fails(ctx, "", MESO_ERROR_FORMAT);
    parse_fails(ctx, "{\"objects\": [{}]} trailing", MESO_ERROR_FORMAT);
    assert_contains(parse_fails(ctx, "[1, 2]", MESO_ERROR_FORMAT), "scene.json: ");
    meso_context_destroy(ctx);
}

static void test_unknown_key_names_the_key_path(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    assert_string_equal(parse_fails(ctx, object_scene("\"materal\": {}"), MESO_ERROR_FORMAT),
                        "scene.json: objects[0].materal: unknown key");
    assert_string_equal(
        parse_fails(ctx, object_scene("\"material\": {\"albdo\": [1, 1, 1]}"), MESO_ERROR_FORMAT),
        "scene.json: objects[0].material.albdo: unknown key");
    assert_string_equal(parse_fails(ctx, "{\"imgae\": {}, \"objects\": [{}]}", MESO_ERROR_FORMAT),
                        "scene.json: imgae: unknown key");
    assert_contains(
        parse_fails(ctx,
                    "{\"lights\": [{\"type\": \"directional\", \"direction\": [0, 1, 0],"
                    " \"position\": [0, 1, 0]}], \"objects\": [{}]}",
                    MESO_ERROR_FORMAT),
        "scene.json: lights[0].position: unknown key");
    assert_contains(
        parse_fails(ctx, object_scene("\"name\": \"a\", \"name\": \"b\""), MESO_ERROR_FORMAT),
        "objects[0].name: duplicate key");
    meso_context_destroy(ctx);
}

static void test_wrong_types_name_the_key(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    assert_contains(
        parse_fails(ctx, "{\"image\": {\"width\": \"512\"}, \"objects\": [{}]}", MESO_ERROR_FORMAT),
        "scene.json: image.width: must be a number");
    assert_contains(
        parse_fails(ctx, "{\"camera\": {\"eye\": [0, 1]}, \"objects\": [{}]}", MESO_ERROR_FORMAT),
        "scene.json: camera.eye: must be an array of 3 numbers");
    assert_contains(parse_fails(ctx, object_scene("\"material\": {\"albedo\": [1, \"x\", 1]}"),
                                MESO_ERROR_FORMAT),
                    "objects[0].material.albedo[1]: must be a number");
    assert_contains(parse_fails(ctx, object_scene("\"technique\": 3"), MESO_ERROR_FORMAT),
                    "objects[0].technique: must be a string");
    assert_contains(parse_fails(ctx, object_scene("\"technique_options\": {\"steps\": \"8\"}"),
                                MESO_ERROR_FORMAT),
                    "objects[0].technique_options.steps: must be a finite number or a boolean");
    assert_contains(parse_fails(ctx, "{\"objects\": {}}", MESO_ERROR_FORMAT),
                    "scene.json: objects: must be an array");
    assert_contains(parse_fails(ctx, object_scene("\"shape\": 4"), MESO_ERROR_FORMAT),
                    "objects[0].shape");
    meso_context_destroy(ctx);
}

static void test_bad_depth_is_an_error_naming_the_key(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    const char *expected =
        "scene.json: objects[0].mesostructure.depth: must be a finite number >= 0";
    assert_string_equal(
        parse_fails(ctx,
                    object_scene("\"mesostructure\": {\"height_map\": {\"procedural\": \"bumps\","
                                 " \"resolution\": 8}, \"depth\": -0.1}"),
                    MESO_ERROR_FORMAT),
        expected);
    /* NaN cannot be written in JSON; cJSON reads 1e999 as infinity. */
    assert_string_equal(
        parse_fails(ctx,
                    object_scene("\"mesostructure\": {\"height_map\": {\"procedural\": \"bumps\","
                                 " \"resolution\": 8}, \"depth\": 1e999}"),
                    MESO_ERROR_FORMAT),
        expected);
    assert_contains(
        parse_fails(ctx,
                    object_scene("\"mesostructure\": {\"height_map\": {\"procedural\": \"bumps\","
                                 " \"resolution\": 8}, \"depth\": \"NaN\"}"),
                    MESO_ERROR_FORMAT),
        "objects[0].mesostructure.depth: must be a number");
    assert_contains(parse_fails(ctx,
                                object_scene("\"mesostructure\": {\"height_map\": {\"procedural\":"
                                             " \"bumps\", \"resolution\": 8}}"),
                                MESO_ERROR_FORMAT),
                    "objects[0].mesostructure.depth: missing");
    meso_context_destroy(ctx);
}

static void test_missing_height_map_file_is_an_io_error_naming_it(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    const char *message = parse_fails(
        ctx,
        object_scene("\"mesostructure\": {\"height_map\": \"no-such-map.png\", \"depth\": 0.1}"),
        MESO_ERROR_IO);
    assert_contains(message, "scene.json: objects[0].mesostructure.height_map: ");
    assert_contains(message, "no-such-map.png");
    message = parse_fails(ctx, object_scene("\"material\": {\"color_map\": \"no-colour.png\"}"),
                          MESO_ERROR_IO);
    assert_contains(message, "objects[0].material.color_map");
    assert_contains(message, "no-colour.png");
    message =
        parse_fails(ctx, object_scene("\"shape\": {\"file\": \"no-model.obj\"}"), MESO_ERROR_IO);
    assert_contains(message, "no-model.obj");
    meso_context_destroy(ctx);
}

static void test_a_scene_needs_objects(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    const char *expected = "scene.json: objects: a scene needs at least one object";
    assert_string_equal(parse_fails(ctx, "{\"objects\": []}", MESO_ERROR_FORMAT), expected);
    assert_string_equal(parse_fails(ctx, "{\"image\": {\"width\": 8}}", MESO_ERROR_FORMAT),
                        expected);
    meso_context_destroy(ctx);
}

static void test_bad_values_name_the_key(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    assert_contains(parse_fails(ctx, "{\"camera\": {\"fov_y_deg\": 180}, \"objects\": [{}]}",
                                MESO_ERROR_FORMAT),
                    "scene.json: camera.fov_y_deg: must be in (0, 180)");
    assert_contains(parse_fails(ctx,
                                "{\"camera\": {\"up\": [0, 0, -1], \"eye\": [0, 0, 2]},"
                                " \"objects\": [{}]}",
                                MESO_ERROR_FORMAT),
                    "camera.up");
    assert_contains(
        parse_fails(ctx, "{\"image\": {\"width\": 0}, \"objects\": [{}]}", MESO_ERROR_FORMAT),
        "image.width");
    assert_contains(
        parse_fails(ctx, "{\"image\": {\"height\": 16385}, \"objects\": [{}]}", MESO_ERROR_LIMIT),
        "image.height: 16385 exceeds the limit of 16384");
    assert_contains(
        parse_fails(ctx, "{\"image\": {\"width\": 10.5}, \"objects\": [{}]}", MESO_ERROR_FORMAT),
        "image.width: must be an integer");
    assert_contains(parse_fails(ctx, "{\"image\": {\"encoding\": \"gamma\"}, \"objects\": [{}]}",
                                MESO_ERROR_FORMAT),
                    "image.encoding");
    assert_contains(parse_fails(ctx,
                                "{\"lights\": [{\"type\": \"directional\", \"direction\":"
                                " [0, 0, 0]}], \"objects\": [{}]}",
                                MESO_ERROR_FORMAT),
                    "lights[0].direction: must not be zero");
    assert_contains(parse_fails(ctx, "{\"lights\": [{\"type\": \"spot\"}], \"objects\": [{}]}",
                                MESO_ERROR_FORMAT),
                    "lights[0].type");
    assert_contains(parse_fails(ctx, "{\"lights\": [{\"type\": \"point\"}], \"objects\": [{}]}",
                                MESO_ERROR_FORMAT),
                    "lights[0].position: missing");
    assert_contains(parse_fails(ctx, object_scene("\"shape\": \"cube\""), MESO_ERROR_FORMAT),
                    "objects[0].shape: unknown shape \"cube\"");
    assert_contains(parse_fails(ctx, object_scene("\"size\": -2"), MESO_ERROR_FORMAT),
                    "objects[0].size: must be a finite number > 0");
    assert_contains(
        parse_fails(ctx, object_scene("\"material\": {\"albedo\": [1, -1, 1]}"), MESO_ERROR_FORMAT),
        "objects[0].material.albedo[1]: must be >= 0");
    assert_contains(parse_fails(ctx, object_scene("\"uv_scale\": [0, 1]"), MESO_ERROR_FORMAT),
                    "objects[0].uv_scale[0]");
    assert_contains(
        parse_fails(ctx, object_scene("\"transform\": {\"scale\": 0}"), MESO_ERROR_FORMAT),
        "objects[0].transform.scale");
    assert_contains(
        parse_fails(ctx, object_scene("\"material\": {\"color_map\": \"mesostructure\"}"),
                    MESO_ERROR_FORMAT),
        "objects[0].material.color_map: \"mesostructure\" needs a procedural height_map");
    assert_contains(parse_fails(ctx, object_scene("\"shape\": {\"file\": \"x.obj\"}, \"size\": 2"),
                                MESO_ERROR_FORMAT),
                    "objects[0].size: applies to built-in shapes only");
    meso_context_destroy(ctx);
}

static void test_mesostructure_errors(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    assert_contains(
        parse_fails(ctx,
                    object_scene("\"mesostructure\": {\"solid\": \"weave.obj\", \"depth\": 0.1}"),
                    MESO_ERROR_IO),
        "objects[0].mesostructure.solid: ");
    assert_contains(
        parse_fails(ctx,
                    object_scene("\"mesostructure\": {\"height_map\": {\"procedural\": \"stone\"},"
                                 " \"depth\": 0.1}"),
                    MESO_ERROR_FORMAT),
        "objects[0].mesostructure.height_map.procedural: unknown procedural height field "
        "\"stone\"");
    assert_contains(
        parse_fails(ctx,
                    object_scene("\"mesostructure\": {\"solid\": {\"procedural\": \"knit\"},"
                                 " \"depth\": 0.1}"),
                    MESO_ERROR_FORMAT),
        "objects[0].mesostructure.solid.procedural");
    /* The library refuses an odd weave; the scene reports it at the key. */
    assert_contains(
        parse_fails(ctx,
                    object_scene("\"mesostructure\": {\"height_map\": {\"procedural\": \"weave\","
                                 " \"rows\": 3, \"resolution\": 8}, \"depth\": 0.1}"),
                    MESO_ERROR_FORMAT),
        "scene.json: objects[0].mesostructure.height_map: ");
    assert_contains(
        parse_fails(ctx,
                    object_scene("\"mesostructure\": {\"solid\": {\"procedural\": \"chain\","
                                 " \"count\": 3}, \"depth\": 0.1}"),
                    MESO_ERROR_FORMAT),
        "objects[0].mesostructure.solid: ");
    assert_contains(
        parse_fails(ctx,
                    object_scene("\"mesostructure\": {\"height_map\": {\"procedural\": \"bumps\","
                                 " \"gap\": 0.95}, \"depth\": 0.1}"),
                    MESO_ERROR_FORMAT),
        "objects[0].mesostructure.height_map.gap");
    assert_contains(
        parse_fails(ctx,
                    object_scene("\"mesostructure\": {\"height_map\": {\"procedural\": \"bumps\","
                                 " \"resolution\": 100000}, \"depth\": 0.1}"),
                    MESO_ERROR_LIMIT),
        "objects[0].mesostructure.height_map.resolution");
    assert_contains(
        parse_fails(ctx, object_scene("\"mesostructure\": {\"depth\": 0.1}"), MESO_ERROR_FORMAT),
        "objects[0].mesostructure: needs a height_map or a solid");
    assert_contains(
        parse_fails(ctx,
                    object_scene("\"mesostructure\": {\"height_map\": \"a.png\", \"solid\":"
                                 " {\"procedural\": \"grid\"}, \"depth\": 0.1}"),
                    MESO_ERROR_FORMAT),
        "objects[0].mesostructure: height_map and solid exclude each other");
    assert_contains(
        parse_fails(ctx,
                    object_scene("\"mesostructure\": {\"height_map\": {\"procedural\": \"bumps\"},"
                                 " \"depth\": 0.1, \"wrap\": \"mirror\"}"),
                    MESO_ERROR_FORMAT),
        "objects[0].mesostructure.wrap");
    meso_context_destroy(ctx);
}

static void test_limits(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    char json[4096] = "{\"lights\": [";
    for (int i = 0; i <= MESO_SCENE_MAX_LIGHTS; i++)
        strcat(json, i ? ", {\"type\": \"point\", \"position\": [0, 1, 0]}"
                       : "{\"type\": \"point\", \"position\": [0, 1, 0]}");
    strcat(json, "], \"objects\": [{}]}");
    assert_contains(parse_fails(ctx, json, MESO_ERROR_LIMIT), "scene.json: lights: ");
    char options[4096] = "\"technique_options\": {";
    for (int i = 0; i <= MESO_OPTIONS_MAX; i++) {
        char one[32];
        snprintf(one, sizeof(one), "%s\"o%d\": %d", i ? ", " : "", i, i);
        strcat(options, one);
    }
    strcat(options, "}");
    assert_contains(parse_fails(ctx, object_scene(options), MESO_ERROR_LIMIT),
                    "objects[0].technique_options");
    meso_context_destroy(ctx);
}

static void test_load_errors_name_the_file(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_scene *scene = (meso_scene *)1;
    const char *missing = test_path(test_temp_dir(), "missing-scene.json");
    assert_int_equal(meso_scene_load(ctx, missing, &scene), MESO_ERROR_IO);
    assert_null(scene);
    assert_contains(meso_context_last_error(ctx), "missing-scene.json");

    const char *bad = test_path(test_temp_dir(), "bad-scene.json");
    test_write_file(bad, "{\n\n  \"objects\": [}\n", 18);
    assert_int_equal(meso_scene_load(ctx, bad, &scene), MESO_ERROR_FORMAT);
    char expected[1200];
    snprintf(expected, sizeof(expected), "%s: malformed JSON near line 3", bad);
    assert_string_equal(meso_context_last_error(ctx), expected);

    /* Larger than MESO_SCENE_MAX_FILE_BYTES: refused before reading (a sparse file). */
    const char *huge = test_path(test_temp_dir(), "huge-scene.json");
    test_write_file(huge, "{", 1);
    assert_int_equal(truncate(huge, (off_t)MESO_SCENE_MAX_FILE_BYTES + 1), 0);
    assert_int_equal(meso_scene_load(ctx, huge, &scene), MESO_ERROR_LIMIT);
    assert_contains(meso_context_last_error(ctx), "huge-scene.json");
    unlink(huge);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_malformed_json_names_the_line),
        cmocka_unit_test(test_unknown_key_names_the_key_path),
        cmocka_unit_test(test_wrong_types_name_the_key),
        cmocka_unit_test(test_bad_depth_is_an_error_naming_the_key),
        cmocka_unit_test(test_missing_height_map_file_is_an_io_error_naming_it),
        cmocka_unit_test(test_a_scene_needs_objects),
        cmocka_unit_test(test_bad_values_name_the_key),
        cmocka_unit_test(test_mesostructure_errors),
        cmocka_unit_test(test_limits),
        cmocka_unit_test(test_load_errors_name_the_file),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
