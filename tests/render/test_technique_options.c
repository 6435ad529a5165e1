/* Technique options: one table per technique read by one parser; options keyed by technique
 * (the flat form for the object's own technique only); the render desc's options over the
 * scene's; every error names the file and the key path. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "test_util.h"

/* A small relief-able plane scene with `options` as its technique_options and `technique`. */
static meso_scene *plane_scene(meso_context *ctx, const char *technique, const char *options) {
    char json[2048];
    snprintf(json, sizeof json,
             "{\"image\": {\"width\": 32, \"height\": 32},"
             " \"camera\": {\"eye\": [0, 1.5, 1.5], \"target\": [0, 0, 0]},"
             " \"lights\": [{\"type\": \"directional\", \"direction\": [-0.8, 0.7, -0.6]}],"
             " \"objects\": [{\"shape\": \"plane\", \"size\": 2,"
             "   \"material\": {\"color_map\": \"mesostructure\"},"
             "   \"mesostructure\": {\"height_map\": {\"procedural\": \"bricks\","
             "                       \"resolution\": 32}, \"depth\": 0.1},"
             "   \"technique\": \"%s\", \"technique_options\": {%s}}]}",
             technique, options);
    meso_scene *scene = NULL;
    meso_result r = meso_scene_parse(ctx, json, "plane.json", ".", &scene);
    if (r != MESO_OK) fail_msg("parse: %s", meso_context_last_error(ctx));
    return scene;
}

static meso_result render(meso_context *ctx, const meso_scene *scene, const meso_render_desc *d,
                          meso_framebuffer **out) {
    *out = NULL;
    return meso_render_scene(ctx, scene, d, out);
}

static bool same_image(const meso_framebuffer *a, const meso_framebuffer *b) {
    return memcmp(a->color, b->color, sizeof(float) * 3 * (size_t)a->width * a->height) == 0;
}

static void test_flat_options_belong_to_the_objects_own_technique(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    /* Defect: relief's flat options made every other technique fail. */
    meso_scene *scene = plane_scene(ctx, "relief", "\"linear_steps\": 64");
    const char *others[] = {"flat", "bump", "parallax", "relief_exact", "tessellation"};
    for (size_t i = 0; i < sizeof others / sizeof others[0]; i++) {
        meso_framebuffer *fb = NULL;
        meso_result r = render(ctx, scene, &(meso_render_desc){.technique = others[i]}, &fb);
        if (r != MESO_OK) fail_msg("%s: %s", others[i], meso_context_last_error(ctx));
        meso_framebuffer_destroy(fb);
    }
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

static void test_keyed_options_reach_only_their_technique(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_scene *plain = plane_scene(ctx, "bump", "");
    meso_scene *keyed = plane_scene(ctx, "bump",
                                    "\"relief\": {\"linear_steps\": 1, \"binary_steps\": 0},"
                                    " \"parallax\": {\"offset_limiting\": true}");
    meso_framebuffer *a = NULL, *b = NULL;
    /* relief with 1 linear step and no binary search draws another image than the default */
    assert_int_equal(render(ctx, plain, &(meso_render_desc){.technique = "relief"}, &a), MESO_OK);
    assert_int_equal(render(ctx, keyed, &(meso_render_desc){.technique = "relief"}, &b), MESO_OK);
    assert_false(same_image(a, b));
    meso_framebuffer_destroy(a);
    meso_framebuffer_destroy(b);
    /* bump, the object's own technique, has no options and ignores the others' */
    assert_int_equal(render(ctx, plain, NULL, &a), MESO_OK);
    assert_int_equal(render(ctx, keyed, NULL, &b), MESO_OK);
    assert_true(same_image(a, b));
    meso_framebuffer_destroy(a);
    meso_framebuffer_destroy(b);
    meso_scene_destroy(plain);
    meso_scene_destroy(keyed);
    meso_context_destroy(ctx);
}

static void test_keyed_option_wins_over_the_flat_form(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_scene *keyed = plane_scene(ctx, "relief", "\"relief\": {\"linear_steps\": 1}");
    meso_scene *both =
        plane_scene(ctx, "relief", "\"linear_steps\": 200, \"relief\": {\"linear_steps\": 1}");
    meso_framebuffer *a = NULL, *b = NULL;
    assert_int_equal(render(ctx, keyed, NULL, &a), MESO_OK);
    assert_int_equal(render(ctx, both, NULL, &b), MESO_OK);
    assert_true(same_image(a, b));
    meso_framebuffer_destroy(a);
    meso_framebuffer_destroy(b);
    meso_scene_destroy(keyed);
    meso_scene_destroy(both);
    meso_context_destroy(ctx);
}

static void test_render_desc_options_override_the_scene(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_scene *scene = plane_scene(ctx, "relief", "\"linear_steps\": 64");
    meso_scene *one = plane_scene(ctx, "relief", "\"linear_steps\": 1");
    meso_option set = {"relief", "linear_steps", 1.0};
    meso_framebuffer *a = NULL, *b = NULL;
    assert_int_equal(render(ctx, scene, &(meso_render_desc){.options = &set, .num_options = 1}, &a),
                     MESO_OK);
    assert_int_equal(render(ctx, one, NULL, &b), MESO_OK);
    assert_true(same_image(a, b));
    meso_framebuffer_destroy(a);
    meso_framebuffer_destroy(b);
    /* a desc option out of range is refused before any work */
    meso_option bad = {"relief", "linear_steps", 5000.0};
    meso_renderer *renderer = NULL;
    assert_int_equal(meso_renderer_create(ctx, scene,
                                          &(meso_render_desc){.options = &bad, .num_options = 1},
                                          &renderer),
                     MESO_ERROR_INVALID_ARGUMENT);
    assert_null(renderer);
    assert_non_null(strstr(meso_context_last_error(ctx), "relief.linear_steps: 5000 is not an "
                                                         "integer in 1..1024"));
    meso_scene_destroy(scene);
    meso_scene_destroy(one);
    meso_context_destroy(ctx);
}

/* Whatever technique draws the object, an unknown option of any technique is an error naming
 * the file and the key path. */
static void test_unknown_options_name_the_file_and_key_path(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    static const struct {
        const char *technique, *options, *message;
    } cases[] = {
        {"relief", "\"relief\": {\"linear_stepz\": 3}",
         "plane.json: objects[0].technique_options.relief.linear_stepz: unknown option of "
         "technique 'relief' (known: linear_steps,"},
        {"bump", "\"vdm\": {\"eigenfunctions\": 0}",
         "plane.json: objects[0].technique_options.vdm.eigenfunctions: 0 is not an integer in "
         "1..64"},
        {"relief", "\"linear_steps\": 2.5",
         "plane.json: objects[0].technique_options.linear_steps: 2.5 is not an integer in "
         "1..1024"},
        {"bump", "\"steps\": 3",
         "plane.json: objects[0].technique_options.steps: unknown option of technique 'bump' (it "
         "has none)"},
        {"bump", "\"relif\": {\"linear_steps\": 3}",
         "plane.json: objects[0].technique_options.relif: unknown technique (known: flat,"},
        {"relif", "",
         "plane.json: objects[0].technique: unknown technique 'relif' (known: flat, bump,"},
        {"bump", "\"parallax\": {\"offset_limiting\": 2}",
         "objects[0].technique_options.parallax.offset_limiting: 2 is not a boolean"},
        {"bump", "\"reference\": {\"view_adaptive\": 100}",
         "objects[0].technique_options.reference.view_adaptive: 100 is not a number in [-1, 64]"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        meso_scene *scene = plane_scene(ctx, cases[i].technique, cases[i].options);
        assert_int_equal(meso_technique_check_scene(ctx, scene), MESO_ERROR_INVALID_ARGUMENT);
        if (!strstr(meso_context_last_error(ctx), cases[i].message))
            fail_msg("case %zu: '%s' does not contain '%s'", i, meso_context_last_error(ctx),
                     cases[i].message);
        /* the renderer refuses it too, whatever technique it is asked for */
        meso_renderer *renderer = NULL;
        assert_int_equal(
            meso_renderer_create(ctx, scene, &(meso_render_desc){.technique = "flat"}, &renderer),
            MESO_ERROR_INVALID_ARGUMENT);
        assert_non_null(strstr(meso_context_last_error(ctx), cases[i].message));
        meso_scene_destroy(scene);
    }
    meso_context_destroy(ctx);
}

/* Every table: unique names, a doc line, defaults of the option's type within its range. */
static void test_every_option_table_is_well_formed(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    size_t total = 0;
    for (size_t t = 0; t < meso_technique_count(); t++) {
        const meso_technique_info *info = meso_technique_get(t);
        for (size_t i = 0; i < info->num_options; i++) {
            const meso_technique_option *o = &info->options[i];
            total++;
            assert_non_null(o->doc);
            assert_true(strlen(o->doc) > 8);
            assert_ptr_equal(meso_technique_find_option(info, o->name), o);
            assert_true(o->min <= o->max);
            if (meso_technique_check_option(ctx, info->name, o->name, o->default_value, "x"))
                fail_msg("%s.%s: default: %s", info->name, o->name, meso_context_last_error(ctx));
        }
        assert_null(meso_technique_find_option(info, "no_such_option"));
    }
    assert_true(total >= 40);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_flat_options_belong_to_the_objects_own_technique),
        cmocka_unit_test(test_keyed_options_reach_only_their_technique),
        cmocka_unit_test(test_keyed_option_wins_over_the_flat_form),
        cmocka_unit_test(test_render_desc_options_override_the_scene),
        cmocka_unit_test(test_unknown_options_name_the_file_and_key_path),
        cmocka_unit_test(test_every_option_table_is_well_formed),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
