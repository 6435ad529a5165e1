/* gdm under global illumination (gdm_gi.c, docs/techniques/gdm-gi.md): an open flat slab under
 * a uniform sky reflects the analytic irradiance; on bricks the RTV at gdm's hits agrees with
 * the reference's rtv mode (the same model at the true hits) and shadows the sky; with gi off,
 * or without an environment, the image is gdm's own bit for bit; the same bits with 1 and 2
 * threads. Small bakes and 24 x 24 images keep it to seconds. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_test_scene.h"
#include "test_util.h"

static meso_scene *plane_scene(meso_context *ctx, int size, const char *extra,
                               const char *mesostructure, float albedo) {
    return gi_plane_scene(ctx, size, extra, mesostructure, albedo, "gdm");
}

static const char default_sky_and_sun[] =
    "\"ambient\": [0.02, 0.02, 0.02], \"environment\": {\"sky\": {\"width\": 64}},"
    " \"lights\": [{\"type\": \"directional\", \"direction\": [0.5, 0.7, 0.3], \"color\": [1, 1, "
    "1]}]";
static const char flat_field[] =
    "{\"height_map\": {\"procedural\": \"tiles\", \"resolution\": 16, \"gap\": 0.001, "
    "\"bevel\": 0.001}, \"depth\": 0.02}";
static const char bricks[] =
    "{\"height_map\": {\"procedural\": \"bricks\", \"resolution\": 128}, \"depth\": 0.1}";

/* gdm with a small GDM bake and `gi` (-1: the default). */
static meso_framebuffer *render_gdm(meso_context *ctx, const meso_scene *scene, int gi) {
    meso_option options[5] = {{"gdm", "resolution", 32},
                              {"gdm", "layers", 16},
                              {"gdm", "num_theta", 8},
                              {"gdm", "num_phi", 16},
                              {"gdm", "gi", gi}};
    meso_render_desc desc = {.options = options, .num_options = gi < 0 ? 4 : 5};
    meso_framebuffer *fb = NULL;
    if (meso_render_scene(ctx, scene, &desc, &fb) != MESO_OK)
        fail_msg("gdm: %s", meso_context_last_error(ctx));
    return fb;
}

static bool same_bits(const float *a, const float *b, size_t count) {
    return memcmp(a, b, count * sizeof(float)) == 0;
}

static void test_flat_slab_under_a_gi_uniform_sky_reflects_the_irradiance(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_scene *scene = plane_scene(ctx, 24, gi_uniform_sky, flat_field, 0.5f);
    meso_framebuffer *fb = render_gdm(ctx, scene, -1);
    /* E = pi under radiance 1: albedo E / pi = 0.5 (the RTV's order-4 cosine lobe and the
     * vertices' hemisphere-cut radiance: within 2 %, as the reference's rtv mode) */
    size_t covered = 0;
    double mean = gi_mean_covered(fb, &covered);
    print_message("flat slab under a uniform sky: mean %.4f over %zu pixels (0.5 expected)\n", mean,
                  covered);
    assert_true(covered > 200);
    assert_float_equal(mean, 0.5, 0.01);
    for (size_t p = 0; p < (size_t)fb->width * (size_t)fb->height; p++)
        if (fb->coverage[p] > 0.0f) assert_float_equal(fb->color[3 * p + 1], 0.5, 0.02);
    meso_framebuffer_destroy(fb);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

static void test_bricks_agree_with_the_rtv_at_the_true_hits_and_shadow_the_sky(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_scene *scene = plane_scene(ctx, 24, default_sky_and_sun, bricks, 0.7f);
    meso_framebuffer *gi = render_gdm(ctx, scene, 1), *unshadowed = render_gdm(ctx, scene, 0);
    meso_option options[1] = {{"reference", "rtv", 1}};
    meso_render_desc desc = {.technique = "reference", .options = options, .num_options = 1};
    meso_framebuffer *rtv = NULL;
    assert_int_equal(meso_render_scene(ctx, scene, &desc, &rtv), MESO_OK);
    double a = gi_mean_covered(gi, NULL), b = gi_mean_covered(rtv, NULL);
    double c = gi_mean_covered(unshadowed, NULL);
    print_message("bricks: gdm gi %.4f, reference rtv %.4f, gdm gi off (SH ambient) %.4f\n", a, b,
                  c);
    /* the same model at gdm's hits and at the true ones: the hits and the shadows differ by
     * gdm's own error (docs/techniques/gdm.md), the light is the same */
    assert_float_equal(a, b, (float)(0.05 * b));
    assert_true(a < c); /* the RTV shadows the sky in the mortar */
    meso_framebuffer_destroy(rtv);
    meso_framebuffer_destroy(unshadowed);
    meso_framebuffer_destroy(gi);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

/* gi_eigen below the bake's 4 reads the first eigenfunctions of that bake (an SVD's
 * truncation): other bits than all 4, the same light within 1 %. */
static void test_gi_eigen_uses_the_first_eigenfunctions_of_the_bake(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_scene *scene = plane_scene(ctx, 24, default_sky_and_sun, bricks, 0.7f);
    meso_framebuffer *fb[2];
    for (int k = 0; k < 2; k++) {
        meso_option options[5] = {{"gdm", "resolution", 32},
                                  {"gdm", "layers", 16},
                                  {"gdm", "num_theta", 8},
                                  {"gdm", "num_phi", 16},
                                  {"gdm", "gi_eigen", 3 + k}};
        meso_render_desc desc = {.options = options, .num_options = 5};
        fb[k] = NULL;
        assert_int_equal(meso_render_scene(ctx, scene, &desc, &fb[k]), MESO_OK);
    }
    size_t pixels = 24 * 24;
    double a = gi_mean_covered(fb[0], NULL), b = gi_mean_covered(fb[1], NULL);
    print_message("bricks: gi_eigen 3 %.4f, 4 %.4f\n", a, b);
    assert_false(same_bits(fb[0]->color, fb[1]->color, 3 * pixels));
    assert_true(same_bits(fb[0]->depth, fb[1]->depth, pixels)); /* the colour only */
    assert_float_equal(a, b, (float)(0.01 * b));
    meso_framebuffer_destroy(fb[0]);
    meso_framebuffer_destroy(fb[1]);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

static void test_gi_off_or_without_a_sky_is_gdm_bit_for_bit(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    /* without an environment the option changes nothing */
    meso_scene *scene = plane_scene(
        ctx, 24,
        "\"ambient\": [0.1, 0.1, 0.1], \"lights\": [{\"type\": \"directional\", \"direction\": "
        "[0.5, 0.7, 0.3], \"color\": [1, 1, 1]}]",
        bricks, 0.7f);
    meso_framebuffer *on = render_gdm(ctx, scene, 1), *off = render_gdm(ctx, scene, 0);
    size_t n = (size_t)on->width * (size_t)on->height;
    assert_true(same_bits(on->color, off->color, 3 * n));
    assert_true(same_bits(on->depth, off->depth, n));
    meso_framebuffer_destroy(on);
    meso_framebuffer_destroy(off);
    meso_scene_destroy(scene);
    /* with one, gi changes the colour only: the hits (depth, coverage) are gdm's own */
    scene = plane_scene(ctx, 24, default_sky_and_sun, bricks, 0.7f);
    on = render_gdm(ctx, scene, 1), off = render_gdm(ctx, scene, 0);
    assert_true(same_bits(on->depth, off->depth, n));
    assert_true(same_bits(on->coverage, off->coverage, n));
    assert_false(same_bits(on->color, off->color, 3 * n));
    meso_framebuffer_destroy(on);
    meso_framebuffer_destroy(off);
    /* and it is the same for any thread count */
    meso_context *one = test_context(1);
    on = render_gdm(ctx, scene, 1), off = render_gdm(one, scene, 1);
    assert_true(same_bits(on->color, off->color, 3 * n));
    meso_framebuffer_destroy(on);
    meso_framebuffer_destroy(off);
    meso_context_destroy(one);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_flat_slab_under_a_gi_uniform_sky_reflects_the_irradiance),
        cmocka_unit_test(test_bricks_agree_with_the_rtv_at_the_true_hits_and_shadow_the_sky),
        cmocka_unit_test(test_gi_off_or_without_a_sky_is_gdm_bit_for_bit),
        cmocka_unit_test(test_gi_eigen_uses_the_first_eigenfunctions_of_the_bake),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
