/* The vdm technique (Wang et al. 2003 §3.2): tiny bakes so that the tests stay fast. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"

/* Small bake parameters for every scene here. */
#define SMALL_BAKE "\"resolution\": 16, \"num_theta\": 8, \"num_phi\": 4, \"num_curvatures\": 4"

static const char *write_grey_png(const char *name, float value, bool groove) {
    meso_context *ctx = test_context(1);
    meso_image *image = NULL;
    assert_int_equal(meso_image_create(ctx, 32, 32, 1, &image), MESO_OK);
    for (int j = 0; j < 32; j++)
        for (int i = 0; i < 32; i++)
            meso_image_at(image, i, j)[0] = groove && i >= 12 && i < 20 ? 0.0f : value;
    const char *path = test_path(test_temp_dir(), name);
    assert_int_equal(
        meso_image_save_png(ctx, image, path, &(meso_png_desc){.encoding = MESO_ENCODING_LINEAR}),
        MESO_OK);
    meso_image_destroy(image);
    meso_context_destroy(ctx);
    return path;
}

/* How a test scene looks at its plane: image side, eye, field of view, light, uv_scale, depth. */
typedef struct scene_view {
    int side;
    const char *eye, *light;
    int fov_y_deg, uv_scale;
    float depth;
} scene_view;

static meso_scene *plane_scene_seen(meso_context *ctx, const char *png, const char *technique,
                                    const char *options, scene_view view) {
    char json[2048];
    snprintf(json, sizeof(json),
             "{\"image\": {\"width\": %d, \"height\": %d, \"encoding\": \"linear\"},"
             " \"camera\": {\"eye\": [%s], \"target\": [0, 0, 0], \"up\": [0, 1, 0],"
             " \"fov_y_deg\": %d},"
             " \"lights\": [{\"type\": \"directional\", \"direction\": [%s],"
             " \"color\": [1, 1, 1]}],"
             " \"objects\": [{\"shape\": \"plane\", \"size\": 2, \"uv_scale\": [%d, %d],"
             " \"mesostructure\": {\"height_map\": \"%s\", \"depth\": %g},"
             " \"technique\": \"%s\", \"technique_options\": {%s}}]}",
             view.side, view.side, view.eye, view.fov_y_deg, view.light, view.uv_scale,
             view.uv_scale, png, (double)view.depth, technique, options);
    meso_scene *scene = NULL;
    assert_int_equal(meso_scene_parse(ctx, json, "vdm-test.json", NULL, &scene), MESO_OK);
    return scene;
}

/* The plane tiled 2 x 2, seen from the front at 40 x 40 pixels. */
static meso_scene *plane_scene(meso_context *ctx, const char *png, const char *technique,
                               const char *options) {
    scene_view view = {40, "0, 1.1, 1.3", "0.3, 0.8, 0.2", 55, 2, 0.1f};
    return plane_scene_seen(ctx, png, technique, options, view);
}

static meso_framebuffer *render(meso_context *ctx, const meso_scene *scene) {
    meso_framebuffer *fb = NULL;
    meso_result r = meso_render_scene(ctx, scene, &(meso_render_desc){0}, &fb);
    if (r != MESO_OK) fail_msg("render: %s", meso_context_last_error(ctx));
    return fb;
}

static void use_test_cache(void) {
    setenv("MESO_CACHE_DIR", test_path(test_temp_dir(), "cache"), 1);
}

static void test_vdm_is_registered_for_height_fields(void **state) {
    const meso_technique_info *info = meso_technique_find("vdm");
    assert_non_null(info);
    assert_int_equal(info->kind, MESO_TECHNIQUE_PER_PIXEL);
    assert_true(info->accepts & MESO_TECHNIQUE_ACCEPTS_HEIGHT_FIELD);
}

static void test_vdm_constant_height_field_renders_like_flat(void **state) {
    use_test_cache();
    meso_context *ctx = test_context(2);
    const char *png = write_grey_png("white.png", 1.0f, false);
    meso_scene *vdm_scene = plane_scene(ctx, png, "vdm", SMALL_BAKE);
    meso_scene *flat_scene = plane_scene(ctx, png, "flat", "");
    meso_framebuffer *a = render(ctx, vdm_scene), *b = render(ctx, flat_scene);
    double max_difference = 0.0, covered = 0.0;
    for (int i = 0; i < 40 * 40; i++) {
        covered += a->coverage[i];
        assert_float_equal(a->coverage[i], b->coverage[i], 0.0f);
        for (int c = 0; c < 3; c++)
            max_difference = fmax(max_difference, fabs(a->color[3 * i + c] - b->color[3 * i + c]));
    }
    assert_true(covered > 0.5 * 40 * 40); /* the plane fills most of the picture */
    if (max_difference > 1e-3) fail_msg("vdm differs from flat by %g", max_difference);
    meso_framebuffer_destroy(a);
    meso_framebuffer_destroy(b);
    meso_scene_destroy(vdm_scene);
    meso_scene_destroy(flat_scene);
    meso_context_destroy(ctx);
}

static void test_vdm_groove_changes_the_picture_and_compressed_matches_raw(void **state) {
    use_test_cache();
    meso_context *ctx = test_context(2);
    const char *png = write_grey_png("groove.png", 1.0f, true);
    meso_scene *compressed = plane_scene(ctx, png, "vdm",
                                         SMALL_BAKE ", \"eigenfunctions\": 36, "
                                                    "\"mvm_eigenfunctions\": 36");
    meso_scene *raw = plane_scene(ctx, png, "vdm", SMALL_BAKE ", \"compressed\": 0");
    meso_scene *flat = plane_scene(ctx, png, "flat", "");
    meso_framebuffer *a = render(ctx, compressed), *b = render(ctx, raw), *f = render(ctx, flat);
    double to_raw = 0.0, to_flat = 0.0;
    for (int i = 0; i < 40 * 40 * 3; i++) {
        to_raw = fmax(to_raw, fabs(a->color[i] - b->color[i]));
        to_flat = fmax(to_flat, fabs(a->color[i] - f->color[i]));
    }
    /* all eigenfunctions: the compressed map is the raw table (up to half-float weights) */
    if (to_raw > 0.05) fail_msg("compressed differs from raw by %g", to_raw);
    assert_true(to_flat > 0.1); /* the groove is visible */
    meso_framebuffer_destroy(a);
    meso_framebuffer_destroy(b);
    meso_framebuffer_destroy(f);
    meso_scene_destroy(compressed);
    meso_scene_destroy(raw);
    meso_scene_destroy(flat);
    meso_context_destroy(ctx);
}

static void test_vdm_render_is_identical_for_any_thread_count(void **state) {
    use_test_cache();
    meso_context *one = test_context(1), *two = test_context(2);
    const char *png = write_grey_png("groove2.png", 0.9f, true);
    meso_scene *scene = plane_scene(one, png, "vdm", SMALL_BAKE);
    meso_framebuffer *a = render(one, scene), *b = render(two, scene);
    assert_memory_equal(a->color, b->color, sizeof(float) * 3 * 40 * 40);
    meso_framebuffer_destroy(a);
    meso_framebuffer_destroy(b);
    meso_scene_destroy(scene);
    meso_context_destroy(one);
    meso_context_destroy(two);
}

/* Three cones at places with no symmetry, 64 x 64 texels, white tips. */
static const char *write_cones_png(void) {
    meso_context *ctx = test_context(1);
    meso_image *image = NULL;
    assert_int_equal(meso_image_create(ctx, 64, 64, 1, &image), MESO_OK);
    const float cones[3][3] = {{17.0f, 22.0f, 11.0f}, {41.0f, 13.0f, 8.0f}, {36.0f, 45.0f, 14.0f}};
    for (int j = 0; j < 64; j++)
        for (int i = 0; i < 64; i++) {
            float h = 0.0f;
            for (int k = 0; k < 3; k++) {
                float d = hypotf((float)i - cones[k][0], (float)j - cones[k][1]) / cones[k][2];
                h = fmaxf(h, d < 1.0f ? 1.0f - d : 0.0f);
            }
            meso_image_at(image, i, j)[0] = h;
        }
    const char *path = test_path(test_temp_dir(), "cones.png");
    assert_int_equal(
        meso_image_save_png(ctx, image, path, &(meso_png_desc){.encoding = MESO_ENCODING_LINEAR}),
        MESO_OK);
    meso_image_destroy(image);
    meso_context_destroy(ctx);
    return path;
}

/* The cones once over a plane, seen from off every axis at 35 degrees of elevation. */
static meso_scene *cones_scene(meso_context *ctx, const char *png, const char *technique,
                               const char *options) {
    scene_view view = {96, "0.9, 1.1, 1.3", "-0.5, 0.7, 0.3", 45, 1, 0.15f};
    return plane_scene_seen(ctx, png, technique, options, view);
}

/* The fraction of pixels both cover whose view depth differs from the reference's by more than
 * 0.006 world units (a 25th of the shell depth): a hit off the surface the truth sees. */
static double wrong_hits(const meso_framebuffer *fb, const meso_framebuffer *truth) {
    int both = 0, wrong = 0;
    for (int i = 0; i < fb->width * fb->height; i++) {
        if (fb->coverage[i] < 1.0f || truth->coverage[i] < 1.0f) continue;
        both++;
        wrong += fabsf(fb->depth[i] - truth->depth[i]) > 0.006f;
    }
    assert_true(both > fb->width * fb->height / 3);
    return (double)wrong / both;
}

/* The fault of the first VDM: interpolating d across the jumps at the cones' outlines (8
 * azimuths 45 degrees apart, a map with no symmetry, a view off the axes) put the hit between
 * a cone and the ground behind it. The refined hit must land where the truth's does. */
static void test_vdm_hits_the_surface_the_reference_hits_on_asymmetric_cones(void **state) {
    use_test_cache();
    meso_context *ctx = test_context(2);
    const char *png = write_cones_png();
    const char *bake = "\"resolution\": 32, \"num_theta\": 16, \"num_curvatures\": 1";
    char refined_options[256], paper_options[256];
    snprintf(refined_options, sizeof(refined_options), "%s", bake);
    snprintf(paper_options, sizeof(paper_options), "%s, \"refine_steps\": 0", bake);
    meso_scene *refined = cones_scene(ctx, png, "vdm", refined_options);
    meso_scene *paper = cones_scene(ctx, png, "vdm", paper_options);
    meso_scene *truth = cones_scene(ctx, png, "reference", "");
    meso_framebuffer *a = render(ctx, refined), *b = render(ctx, paper), *t = render(ctx, truth);
    double refined_wrong = wrong_hits(a, t), paper_wrong = wrong_hits(b, t);
    /* measured: refined 0.003, interpolated 0.085; the second shows the scene has the fault */
    if (refined_wrong > 0.02 || paper_wrong < 0.04)
        fail_msg("wrong hits: refined %.3f, interpolated %.3f", refined_wrong, paper_wrong);
    meso_framebuffer_destroy(a);
    meso_framebuffer_destroy(b);
    meso_framebuffer_destroy(t);
    meso_scene_destroy(refined);
    meso_scene_destroy(paper);
    meso_scene_destroy(truth);
    meso_context_destroy(ctx);
}

static void expect_option_error(const char *options, const char *field) {
    use_test_cache();
    meso_context *ctx = test_context(1);
    const char *png = write_grey_png("grey.png", 0.5f, false);
    meso_scene *scene = plane_scene(ctx, png, "vdm", options);
    meso_framebuffer *fb = NULL;
    assert_int_equal(meso_render_scene(ctx, scene, &(meso_render_desc){0}, &fb),
                     MESO_ERROR_INVALID_ARGUMENT);
    assert_null(fb);
    if (!strstr(meso_context_last_error(ctx), field))
        fail_msg("message \"%s\" does not name %s", meso_context_last_error(ctx), field);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

static void test_vdm_rejects_bad_options_naming_them(void **state) {
    expect_option_error(SMALL_BAKE ", \"no_such_option\": 1", "no_such_option");
    expect_option_error(SMALL_BAKE ", \"compressed\": 2", "compressed");
    expect_option_error(SMALL_BAKE ", \"eigenfunctions\": 0", "eigenfunctions");
    expect_option_error(SMALL_BAKE ", \"eigenfunctions\": 40", "eigenfunctions");
    expect_option_error(SMALL_BAKE ", \"shadow_bias\": -2", "shadow_bias");
    expect_option_error(SMALL_BAKE ", \"refine_steps\": 17", "refine_steps");
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_vdm_is_registered_for_height_fields),
        cmocka_unit_test(test_vdm_constant_height_field_renders_like_flat),
        cmocka_unit_test(test_vdm_groove_changes_the_picture_and_compressed_matches_raw),
        cmocka_unit_test(test_vdm_render_is_identical_for_any_thread_count),
        cmocka_unit_test(test_vdm_rejects_bad_options_naming_them),
        cmocka_unit_test(test_vdm_hits_the_surface_the_reference_hits_on_asymmetric_cones),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
