/* "height": {"direction", "midlevel", "invert"} is converted once at load into meso's inward
 * convention, so every technique and the reference draw the tool's surface: an outward shell
 * on a plane at y = 0 is the inward shell on a plane at y = depth, pixel for pixel. */
#include <stdio.h>
#include <string.h>

#include "test_util.h"

static meso_scene *bricks_plane(meso_context *ctx, const char *translate_y, const char *height) {
    char json[2048];
    snprintf(json, sizeof json,
             "{\"image\": {\"width\": 40, \"height\": 40},"
             " \"camera\": {\"eye\": [0, 1.6, 1.6], \"target\": [0, 0, 0]},"
             " \"lights\": [{\"type\": \"directional\", \"direction\": [-0.8, 0.7, -0.6]}],"
             " \"objects\": [{\"shape\": \"plane\", \"size\": 2,"
             "   \"transform\": {\"translate\": [0, %s, 0]},"
             "   \"material\": {\"color_map\": \"mesostructure\"},"
             "   \"mesostructure\": {\"height_map\": {\"procedural\": \"bricks\","
             "                       \"resolution\": 32}, \"depth\": 0.1%s%s},"
             "   \"technique_options\": {\"vdm\": {\"resolution\": 16, \"num_theta\": 8,"
             "                          \"num_phi\": 4, \"num_curvatures\": 4}}}]}",
             translate_y, height[0] ? ", \"height\": " : "", height);
    meso_scene *scene = NULL;
    if (meso_scene_parse(ctx, json, "plane.json", ".", &scene) != MESO_OK)
        fail_msg("parse: %s", meso_context_last_error(ctx));
    return scene;
}

static void assert_same_render(meso_context *ctx, const meso_scene *a, const meso_scene *b,
                               const char *technique) {
    meso_framebuffer *fa = NULL, *fb = NULL;
    meso_render_desc desc = {.technique = technique};
    if (meso_render_scene(ctx, a, &desc, &fa) != MESO_OK ||
        meso_render_scene(ctx, b, &desc, &fb) != MESO_OK)
        fail_msg("%s: %s", technique, meso_context_last_error(ctx));
    size_t n = 3 * (size_t)fa->width * (size_t)fa->height;
    float worst = 0.0f;
    for (size_t i = 0; i < n; i++) {
        float d = fa->color[i] - fb->color[i];
        worst = d > worst ? d : -d > worst ? -d : worst;
    }
    if (worst > 1e-4f) fail_msg("%s: the images differ by up to %g", technique, worst);
    meso_framebuffer_destroy(fa);
    meso_framebuffer_destroy(fb);
}

static const char *const every_technique[] = {
    "flat",         "bump", "horizon",      "parallax",     "relief",
    "relief_exact", "vdm",  "tessellation", "displacement", "reference"};

static void test_outward_and_centered_move_the_shell_for_every_technique(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    static const struct {
        const char *height, *equivalent_y;
    } cases[] = {
        {"{\"direction\": \"outward\"}", "0.1"},
        {"{\"direction\": \"centered\"}", "0.05"}, /* midlevel 0.5 */
        {"{\"direction\": \"centered\", \"midlevel\": 0}", "0.1"},
        {"{\"direction\": \"inward\"}", "0"},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        meso_scene *converted = bricks_plane(ctx, "0", cases[c].height);
        meso_scene *moved = bricks_plane(ctx, cases[c].equivalent_y, "");
        assert_float_equal(converted->objects[0].mesostructure.offset,
                           moved->objects[0].mesh->positions[0].y, 1e-7);
        for (size_t t = 0; t < sizeof every_technique / sizeof every_technique[0]; t++)
            assert_same_render(ctx, converted, moved, every_technique[t]);
        meso_scene_destroy(converted);
        meso_scene_destroy(moved);
    }
    meso_context_destroy(ctx);
}

static void test_invert_flips_the_field_every_technique_reads(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_scene *plain = bricks_plane(ctx, "0", "");
    meso_scene *inverted = bricks_plane(ctx, "0", "{\"invert\": true}");
    const meso_heightfield *a = plain->objects[0].mesostructure.height_field;
    const meso_heightfield *b = inverted->objects[0].mesostructure.height_field;
    size_t n = (size_t)a->width * (size_t)a->height;
    for (size_t t = 0; t < n; t++) assert_float_equal(b->heights[t], 1.0f - a->heights[t], 0.0);
    /* a different field: bakes keyed by its hash are not shared with the plain one */
    assert_true(a->hash != b->hash);
    meso_scene_destroy(plain);
    meso_scene_destroy(inverted);
    meso_context_destroy(ctx);
}

static void test_height_errors_name_the_key(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    static const struct {
        const char *height, *message;
    } cases[] = {
        {"{\"direction\": \"up\"}",
         "objects[0].mesostructure.height.direction: must be \"inward\", \"outward\" or "
         "\"centered\", not \"up\""},
        {"{\"direction\": \"centered\", \"midlevel\": 1.5}",
         "objects[0].mesostructure.height.midlevel: 1.5 is not in [0, 1]"},
        {"{\"direction\": \"outward\", \"midlevel\": 0.5}",
         "objects[0].mesostructure.height.midlevel: only with \"direction\": \"centered\""},
        {"{\"invert\": 1}", "objects[0].mesostructure.height.invert: must be true or false"},
        {"{\"inverted\": true}", "objects[0].mesostructure.height.inverted: unknown key"},
        {"\"outward\"", "objects[0].mesostructure.height: must be {"},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        char json[1024];
        snprintf(json, sizeof json,
                 "{\"objects\": [{\"mesostructure\": {\"height_map\": {\"procedural\": \"bumps\","
                 " \"resolution\": 8}, \"depth\": 0.1, \"height\": %s}}]}",
                 cases[c].height);
        meso_scene *scene = NULL;
        assert_int_equal(meso_scene_parse(ctx, json, "h.json", ".", &scene), MESO_ERROR_FORMAT);
        assert_null(scene);
        if (!strstr(meso_context_last_error(ctx), cases[c].message))
            fail_msg("'%s' lacks '%s'", meso_context_last_error(ctx), cases[c].message);
        assert_non_null(strstr(meso_context_last_error(ctx), "h.json: "));
    }
    meso_scene *scene = NULL;
    assert_int_equal(
        meso_scene_parse(ctx,
                         "{\"objects\": [{\"mesostructure\": {\"solid\": {\"procedural\": "
                         "\"grid\"}, \"depth\": 0.1, \"height\": {\"invert\": true}}}]}",
                         "s.json", ".", &scene),
        MESO_ERROR_FORMAT);
    assert_non_null(strstr(meso_context_last_error(ctx),
                           "s.json: objects[0].mesostructure.height: applies to a height_map, "
                           "not a solid"));
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_outward_and_centered_move_the_shell_for_every_technique),
        cmocka_unit_test(test_invert_flips_the_field_every_technique_reads),
        cmocka_unit_test(test_height_errors_name_the_key),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
