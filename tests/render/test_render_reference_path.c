/* The path-traced reference (reference_path.c): a flat surface under a uniform sky
 * against the closed form, the direct-light reference reproduced without environment and
 * interreflection, interreflection adding light, convergence as 1/sqrt(N), and the same image
 * for any thread count. Images are tiny (24 x 24 to 32 x 32) to keep the test at seconds. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_test_scene.h"
#include "test_util.h"

static meso_scene *plane_scene(meso_context *ctx, int size, const char *extra,
                               const char *mesostructure, float albedo) {
    return gi_plane_scene(ctx, size, extra, mesostructure, albedo, "reference");
}

static const char bricks[] =
    "{\"height_map\": {\"procedural\": \"bricks\", \"resolution\": 128}, \"depth\": 0.1}";

/* Render with the reference's samples and bounces options. */
static meso_framebuffer *render(meso_context *ctx, const meso_scene *scene, int samples,
                                int bounces) {
    meso_option options[2] = {{"reference", "samples", samples}, {"reference", "bounces", bounces}};
    meso_render_desc desc = {.options = options, .num_options = 2};
    meso_framebuffer *fb = NULL;
    if (meso_render_scene(ctx, scene, &desc, &fb) != MESO_OK)
        fail_msg("render: %s", meso_context_last_error(ctx));
    return fb;
}

static void test_path_flat_surface_under_gi_uniform_sky_is_albedo_times_radiance(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    /* L = 1 from every direction, albedo 0.5, no ambient, no lights: the plane receives
     * E = pi L from its hemisphere and reflects albedo E / pi = 0.5 everywhere */
    meso_scene *scene = plane_scene(ctx, 24, gi_uniform_sky, NULL, 0.5f);
    meso_framebuffer *fb = render(ctx, scene, 16, 3);
    size_t covered = 0;
    /* the mean of ~500 pixels of 16 samples: its standard deviation is about 0.002 */
    assert_float_equal(gi_mean_covered(fb, &covered), 0.5, 0.006);
    assert_true(covered > 24 * 24 / 2);
    /* single pixels scatter by about 0.04 (the two strategies' weights vary with the angle) */
    for (size_t p = 0; p < 24 * 24; p++)
        if (fb->coverage[p] > 0.0f) assert_float_equal(fb->color[3 * p], 0.5, 0.2);
    meso_framebuffer_destroy(fb);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

static const char light_only[] =
    "\"ambient\": [0.1, 0.1, 0.1], \"lights\": [{\"type\": \"directional\", \"direction\": "
    "[-0.8, 0.7, -0.6], \"color\": [1, 1, 1]}]";

static void test_path_without_environment_or_interreflection_is_the_direct_reference(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_scene *scene = plane_scene(ctx, 32, light_only, bricks, 0.8f);
    meso_framebuffer *direct = render(ctx, scene, 0, 0);
    meso_framebuffer *path = render(ctx, scene, 4, 0);
    size_t n = 32 * 32;
    assert_memory_equal(path->color, direct->color, 3 * n * sizeof(float));
    assert_memory_equal(path->coverage, direct->coverage, n * sizeof(float));
    assert_memory_equal(path->depth, direct->depth, n * sizeof(float));
    /* with interreflection the grooves receive light from the lit brick sides: never darker,
     * and brighter on average */
    meso_framebuffer *bounced = render(ctx, scene, 16, 2);
    size_t brighter = 0;
    for (size_t p = 0; p < 3 * n; p++) {
        assert_true(bounced->color[p] >= direct->color[p] - 1e-6f);
        brighter += bounced->color[p] > direct->color[p] + 1e-3f;
    }
    assert_true(brighter > n / 10);
    assert_true(gi_mean_covered(bounced, NULL) > gi_mean_covered(direct, NULL) + 0.005);
    meso_framebuffer_destroy(bounced);
    meso_framebuffer_destroy(path);
    meso_framebuffer_destroy(direct);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

static double rmse(const meso_framebuffer *a, const meso_framebuffer *b) {
    double sum = 0.0;
    size_t n = 3 * (size_t)a->width * (size_t)a->height;
    for (size_t p = 0; p < n; p++) sum += (a->color[p] - b->color[p]) * (a->color[p] - b->color[p]);
    return sqrt(sum / (double)n);
}

static void test_path_error_falls_as_one_over_sqrt_samples(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    /* the default sky (a sun and a gradient) over bricks, one bounce: noisy at few samples */
    meso_scene *scene =
        plane_scene(ctx, 24, "\"ambient\": [0, 0, 0], \"environment\": {\"sky\": {\"width\": 64}}",
                    bricks, 0.7f);
    meso_framebuffer *truth = render(ctx, scene, 512, 1);
    const int counts[3] = {2, 8, 32};
    double errors[3];
    for (int k = 0; k < 3; k++) {
        meso_framebuffer *fb = render(ctx, scene, counts[k], 1);
        errors[k] = rmse(fb, truth);
        meso_framebuffer_destroy(fb);
    }
    /* the least-squares slope of log error against log N; 1/sqrt(N) is -0.5. The truth's own
     * noise (512 samples, the first of them shared) moves it by a few hundredths. */
    double mx = 0, my = 0, sxx = 0, sxy = 0;
    for (int k = 0; k < 3; k++) mx += log(counts[k]) / 3, my += log(errors[k]) / 3;
    for (int k = 0; k < 3; k++) {
        sxx += (log(counts[k]) - mx) * (log(counts[k]) - mx);
        sxy += (log(counts[k]) - mx) * (log(errors[k]) - my);
    }
    double slope = sxy / sxx;
    print_message("path RMSE at 2, 8, 32 samples: %.4f %.4f %.4f, slope %.3f\n", errors[0],
                  errors[1], errors[2], slope);
    assert_true(errors[0] > 0.01); /* there is noise to measure */
    assert_true(slope > -0.6 && slope < -0.4);
    meso_framebuffer_destroy(truth);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

static void test_path_output_is_identical_for_any_thread_count(void **state) {
    (void)state;
    meso_context *one = test_context(1), *three = test_context(3);
    meso_scene *scene =
        plane_scene(one, 32, "\"environment\": {\"sky\": {\"width\": 32}}", bricks, 0.7f);
    meso_framebuffer *a = render(one, scene, 6, 2);
    meso_framebuffer *b = render(three, scene, 6, 2);
    assert_memory_equal(a->color, b->color, 3 * 32 * 32 * sizeof(float));
    meso_framebuffer_destroy(b);
    meso_framebuffer_destroy(a);
    meso_scene_destroy(scene);
    meso_context_destroy(three);
    meso_context_destroy(one);
}

/* The rasterized techniques see the environment through its SH irradiance (unshadowed, in the
 * ambient term: render_environment.h). On an open plane nothing shadows or interreflects, so
 * they must agree with the path-traced truth up to the SH truncation of the sky. */
static void test_path_and_sh_ambient_agree_on_an_open_plane(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    const char *skies[2] = {gi_uniform_sky,
                            "\"ambient\": [0, 0, 0], \"environment\": {\"sky\": {\"width\": 64}}"};
    const double tolerance[2] = {0.003, 0.03};
    for (int k = 0; k < 2; k++) {
        meso_scene *scene = plane_scene(ctx, 24, skies[k], NULL, 0.5f);
        meso_framebuffer *truth = render(ctx, scene, 64, 1);
        meso_render_desc desc = {.technique = "flat"};
        meso_framebuffer *flat = NULL;
        assert_int_equal(meso_render_scene(ctx, scene, &desc, &flat), MESO_OK);
        double a = gi_mean_covered(flat, NULL), b = gi_mean_covered(truth, NULL);
        print_message("sky %d: flat with SH ambient %.4f, path traced %.4f\n", k, a, b);
        assert_float_equal(a, b, (float)(tolerance[k] * b + 0.002));
        /* and it is not the ambient term alone (0 here) */
        assert_true(a > 0.2);
        meso_framebuffer_destroy(flat);
        meso_framebuffer_destroy(truth);
        meso_scene_destroy(scene);
    }
    meso_context_destroy(ctx);
}

/* The RTV mode (option rtv): GDM-GI's shading at the true hit. A flat height field under a
 * uniform sky reflects albedo x 1; bricks under the default sky come within a few percent of
 * the path-traced truth on average; without an environment it is refused. */
static void test_rtv_mode_against_the_closed_form_and_the_truth(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    /* its own cache: the RTVs baked here do not outlive the test */
    setenv("MESO_CACHE_DIR", test_temp_dir(), 1);
    const char flat_field[] =
        "{\"height_map\": {\"procedural\": \"tiles\", \"resolution\": 16, \"gap\": 0.001, "
        "\"bevel\": 0.001}, \"depth\": 0.0001}";
    meso_scene *scene = plane_scene(ctx, 24, gi_uniform_sky, flat_field, 0.5f);
    meso_option options[1] = {{"reference", "rtv", 1}};
    meso_render_desc desc = {.options = options, .num_options = 1};
    meso_framebuffer *fb = NULL;
    assert_int_equal(meso_render_scene(ctx, scene, &desc, &fb), MESO_OK);
    /* the hemisphere-cut incident radiance truncated at order 4: within 2 % */
    assert_float_equal(gi_mean_covered(fb, NULL), 0.5, 0.01);
    meso_framebuffer_destroy(fb);
    meso_scene_destroy(scene);

    scene =
        plane_scene(ctx, 24, "\"ambient\": [0, 0, 0], \"environment\": {\"sky\": {\"width\": 64}}",
                    bricks, 0.7f);
    assert_int_equal(meso_render_scene(ctx, scene, &desc, &fb), MESO_OK);
    meso_framebuffer *truth = render(ctx, scene, 64, 1);
    meso_framebuffer *unshadowed = render(ctx, scene, 0, 0); /* the SH ambient, no shadowing */
    double a = gi_mean_covered(fb, NULL), b = gi_mean_covered(truth, NULL);
    double c = gi_mean_covered(unshadowed, NULL);
    print_message("bricks: RTV mode %.4f, path traced %.4f, unshadowed SH ambient %.4f; "
                  "RMSE against the truth: RTV %.4f, SH ambient %.4f\n",
                  a, b, c, rmse(fb, truth), rmse(unshadowed, truth));
    /* measured: 7 % low on average (order-4 SH blurs the sun's shadows, and 32 x 32 voxels a
     * tile hardly resolve the mortar grooves), RMSE 0.065 against the unshadowed SH ambient's
     * 0.063: on this small plane the RTV is no better; on bark-cylinder at 256^2 it is (32.4
     * against 28.3 dB covered, docs/techniques/gdm-gi.md). The test holds it to 10 % of the
     * truth's mean and the shading of the RTV below the unshadowed sky (it shadows). */
    assert_float_equal(a, b, (float)(0.1 * b));
    assert_true(a < c);
    meso_framebuffer_destroy(unshadowed);
    meso_framebuffer_destroy(truth);
    meso_framebuffer_destroy(fb);
    meso_scene_destroy(scene);

    scene = plane_scene(ctx, 8, light_only, bricks, 0.7f);
    assert_int_equal(meso_render_scene(ctx, scene, &desc, &fb), MESO_ERROR_INVALID_ARGUMENT);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_path_flat_surface_under_gi_uniform_sky_is_albedo_times_radiance),
        cmocka_unit_test(test_path_without_environment_or_interreflection_is_the_direct_reference),
        cmocka_unit_test(test_path_error_falls_as_one_over_sqrt_samples),
        cmocka_unit_test(test_path_output_is_identical_for_any_thread_count),
        cmocka_unit_test(test_path_and_sh_ambient_agree_on_an_open_plane),
        cmocka_unit_test(test_rtv_mode_against_the_closed_form_and_the_truth),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
