/* "environment" in scene files: a map, a procedural sky, and the errors naming the key. */
#include <stdio.h>
#include <string.h>

#include "test_util.h"

static const char *const plane = "\"objects\": [{\"shape\": \"plane\"}]";

static meso_result parse(meso_context *ctx, const char *environment, meso_scene **out) {
    char json[2048];
    snprintf(json, sizeof json, "{\"environment\": %s, %s}", environment, plane);
    return meso_scene_parse(ctx, json, "scene.json", MESO_SOURCE_DIR "/examples", out);
}

static void test_scene_environment_map_and_sky(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_scene *scene = NULL;
    assert_int_equal(parse(ctx, "{\"map\": \"sky.hdr\", \"intensity\": 0.5}", &scene), MESO_OK);
    assert_non_null(scene->environment);
    assert_int_equal(scene->environment->map->width, 128);
    assert_float_equal(scene->environment->intensity, 0.5, 0);
    meso_scene_destroy(scene);
    assert_int_equal(parse(ctx,
                           "{\"sky\": {\"zenith\": [1, 1, 1], \"horizon\": [1, 1, 1], \"ground\": "
                           "[1, 1, 1], \"sun\": false, \"width\": 32}}",
                           &scene),
                     MESO_OK);
    /* a uniform sky: radiance 1 everywhere */
    meso_vec3 l = meso_environment_radiance(scene->environment, (meso_vec3){0.3f, -0.9f, 0.1f});
    assert_float_equal(l.x, 1.0, 0);
    assert_int_equal(scene->environment->map->width, 32);
    meso_scene_destroy(scene);
    /* no environment: NULL */
    assert_int_equal(meso_scene_parse(ctx, "{\"objects\": [{}]}", "scene.json", ".", &scene),
                     MESO_OK);
    assert_null(scene->environment);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

static void expect_error(meso_context *ctx, const char *environment, meso_result code,
                         const char *message) {
    meso_scene *scene = (meso_scene *)1;
    meso_result r = parse(ctx, environment, &scene);
    if (r != code)
        fail_msg("%s: expected %s, got %s: %s", environment, meso_result_string(code),
                 meso_result_string(r), meso_context_last_error(ctx));
    assert_null(scene);
    if (!strstr(meso_context_last_error(ctx), message))
        fail_msg("\"%s\" does not contain \"%s\"", meso_context_last_error(ctx), message);
}

static void test_scene_environment_errors_name_the_key(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    expect_error(ctx, "{}", MESO_ERROR_FORMAT,
                 "scene.json: environment: needs either \"map\" or \"sky\"");
    expect_error(ctx, "{\"map\": \"sky.hdr\", \"sky\": {}}", MESO_ERROR_FORMAT,
                 "scene.json: environment: needs either");
    expect_error(ctx, "{\"map\": \"missing.hdr\"}", MESO_ERROR_IO, "scene.json: environment.map: ");
    expect_error(ctx, "{\"map\": \"bricks-plane.json\"}", MESO_ERROR_FORMAT,
                 "bricks-plane.json: not a Radiance .hdr or OpenEXR file");
    expect_error(ctx, "{\"map\": \"sky.hdr\", \"intensity\": -1}", MESO_ERROR_FORMAT,
                 "scene.json: environment.intensity: must be in [0, 1e+06], not -1");
    expect_error(ctx, "{\"sky\": {\"sunn\": false}}", MESO_ERROR_FORMAT,
                 "scene.json: environment.sky.sunn: unknown key");
    expect_error(ctx, "{\"sky\": {\"width\": 9}}", MESO_ERROR_FORMAT,
                 "scene.json: environment.sky: sky: width: 9 is not an even number");
    expect_error(ctx, "{\"sky\": {\"width\": 100000}}", MESO_ERROR_LIMIT,
                 "scene.json: environment.sky.width: ");
    expect_error(ctx, "{\"sky\": {\"sun\": [0, 0, 0]}}", MESO_ERROR_FORMAT,
                 "scene.json: environment.sky.sun: must not be zero");
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_scene_environment_map_and_sky),
        cmocka_unit_test(test_scene_environment_errors_name_the_key),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
