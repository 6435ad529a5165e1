/* The relief family's `shell` option (relief_shell.h, docs/techniques/relief.md "On the shell"):
 *   - on a plane whose height field is constant, every pixel the straight search (shell 0)
 *     draws is drawn with the shell too, byte for byte, and
 *     the pixels the shell adds are the open border's side band: covered by the reference
 *     (within a pixel), and with them the drawing covers the reference's;
 *   - on a sphere whose bumps are 6 % of its radius deep, the hits' view depths agree with the
 *     reference's within SHELL_DEPTH_FRACTION of the shell's depth on almost every pixel both
 *     cover (the straight tangent-space search does not: checked too, so the test can fail);
 *   - the option is refused for an impostor, and the hits are the same for any thread count.
 * Set MESO_TEST_VERBOSE=1 to print the measured figures. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"

/* On a plane the shell's one stretch is the straight ray itself, searched with the same steps:
 * the interior's colours are drawn byte for byte as without the shell (measured so; a
 * difference of one rounding would show here first). Its view depths within this fraction of
 * the shell's depth: the hit point is reached from the prism's entry along the unit view
 * direction, not as the fragment's point plus t (P - eye), rounded differently (measured: a
 * thousandth). */
#define SHELL_PLANE_DEPTH 0.01f
/* Hit depth against the reference's, as a fraction of the shell's depth: a tenth (the linear
 * search's step is a sixteenth of the depth, the bilinear surface against the reference's
 * triangles), on all but SHELL_DEPTH_OUTLIERS of the pixels both cover (the cones' steep
 * flanks and the outline, where a pixel's ray grazes a surface). */
#define SHELL_DEPTH_FRACTION 0.1
#define SHELL_DEPTH_OUTLIERS 0.02

static bool verbose(void) {
    const char *v = getenv("MESO_TEST_VERBOSE");
    return v && v[0] == '1';
}

static meso_scene *scene_of(meso_context *ctx, const char *json) {
    meso_scene *scene = NULL;
    if (meso_scene_parse(ctx, json, "relief-shell.json", NULL, &scene) != MESO_OK)
        fail_msg("scene: %s", meso_context_last_error(ctx));
    return scene;
}

static meso_framebuffer *draw(meso_context *ctx, const meso_scene *scene, const char *technique,
                              int shell) {
    meso_option option = {0};
    snprintf(option.technique, sizeof option.technique, "%s", technique);
    snprintf(option.name, sizeof option.name, "shell");
    option.value = shell;
    bool reference = !strcmp(technique, "reference");
    meso_render_desc desc = {
        .technique = technique, .options = &option, .num_options = reference ? 0 : 1};
    meso_framebuffer *fb = NULL;
    if (meso_render_scene(ctx, scene, &desc, &fb) != MESO_OK)
        fail_msg("%s shell %d: %s", technique, shell, meso_context_last_error(ctx));
    return fb;
}

static bool covered(const meso_framebuffer *fb, int x, int y) {
    return x >= 0 && y >= 0 && x < fb->width && y < fb->height &&
           fb->coverage[(size_t)y * (size_t)fb->width + (size_t)x] >= 0.5f;
}

static bool covered_near(const meso_framebuffer *fb, int x, int y) {
    for (int dy = -1; dy <= 1; dy++)
        for (int dx = -1; dx <= 1; dx++)
            if (covered(fb, x + dx, y + dy)) return true;
    return false;
}

static void test_constant_field_on_a_plane_adds_exactly_the_side_band(void **state) {
    (void)state;
    meso_context *ctx = test_context(0);
    /* seen low over the plane's near corner: its two near sides' bands in view */
    meso_scene *scene = scene_of(
        ctx, "{\"image\": {\"width\": 160, \"height\": 120, \"background\": [0, 0, 0]},"
             " \"camera\": {\"eye\": [1.9, 0.45, 2.1], \"target\": [0, -0.05, 0],"
             " \"up\": [0, 1, 0], \"fov_y_deg\": 40},"
             " \"ambient\": [0.2, 0.2, 0.2],"
             " \"lights\": [{\"type\": \"directional\", \"direction\": [0.3, 0.8, 0.4],"
             " \"color\": [1, 1, 1]}],"
             " \"objects\": [{\"shape\": \"plane\", \"size\": 2, \"uv_scale\": [2, 2],"
             " \"material\": {\"albedo\": [0.8, 0.7, 0.6]},"
             " \"mesostructure\": {\"height_map\": {\"procedural\": \"bumps\", \"resolution\":"
             " 32}, \"depth\": 0.15}, \"technique\": \"relief\"}]}");
    meso_heightfield *constant = NULL;
    assert_int_equal(meso_heightfield_create_constant(ctx, 32, 32, 0.5f, &constant), MESO_OK);
    meso_heightfield_destroy(scene->objects[0].mesostructure.height_field);
    scene->objects[0].mesostructure.height_field = constant;
    float depth = scene->objects[0].mesostructure.depth;
    meso_framebuffer *truth = draw(ctx, scene, "reference", 0);
    static const char *const techniques[] = {"relief", "relief_exact", "relief_layers"};
    for (int t = 0; t < 3; t++) {
        meso_framebuffer *off = draw(ctx, scene, techniques[t], 0);
        meso_framebuffer *on = draw(ctx, scene, techniques[t], 1);
        long interior = 0, lost = 0, differ = 0, band = 0, band_stray = 0, missing = 0;
        float worst = 0.0f;
        for (int y = 0; y < on->height; y++)
            for (int x = 0; x < on->width; x++) {
                size_t i = (size_t)y * (size_t)on->width + (size_t)x;
                if (covered(off, x, y)) {
                    interior++;
                    if (!covered(on, x, y)) {
                        lost++;
                        continue;
                    }
                    float gap = fabsf(on->depth[i] - off->depth[i]);
                    differ += memcmp(on->color + 3 * i, off->color + 3 * i, 3 * sizeof(float)) ||
                              gap > SHELL_PLANE_DEPTH * depth;
                    worst = fmaxf(worst, gap / depth);
                } else if (covered(on, x, y)) {
                    band++;
                    band_stray += !covered_near(truth, x, y);
                }
                missing += covered(truth, x, y) && !covered_near(on, x, y);
            }
        if (verbose())
            printf("%s: interior %ld (lost %ld, %ld differ, depth off by %.2g of the shell), side "
                   "band %ld (%ld off the truth), "
                   "truth pixels not drawn %ld\n",
                   techniques[t], interior, lost, differ, (double)worst, band, band_stray, missing);
        if (lost || differ)
            fail_msg("%s: shell 1 lost %ld of shell 0's %ld pixels, %ld differ", techniques[t],
                     lost, interior, differ);
        if (band < 50 || band_stray || missing)
            fail_msg("%s: side band of %ld pixels, %ld off the reference; %ld reference pixels "
                     "not drawn",
                     techniques[t], band, band_stray, missing);
        meso_framebuffer_destroy(off);
        meso_framebuffer_destroy(on);
    }
    meso_framebuffer_destroy(truth);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

static const char sphere_json[] =
    "{\"image\": {\"width\": 128, \"height\": 128, \"background\": [0, 0, 0]},"
    " \"camera\": {\"eye\": [0, 1.2, 4.4], \"target\": [0, 0, 0], \"up\": [0, 1, 0],"
    " \"fov_y_deg\": 32},"
    " \"ambient\": [0.1, 0.1, 0.1],"
    " \"lights\": [{\"type\": \"directional\", \"direction\": [0.95, 0.25, 0.2],"
    " \"color\": [1, 1, 1]}],"
    " \"objects\": [{\"shape\": \"sphere\", \"size\": 1, \"uv_scale\": [4, 2],"
    " \"material\": {\"albedo\": [0.8, 0.8, 0.8]},"
    " \"mesostructure\": {\"height_map\": {\"procedural\": \"bumps\", \"resolution\": 64},"
    " \"depth\": 0.06}, \"technique\": \"relief\"}]}";

/* The fraction of the pixels both cover whose view depths differ by more than the bound. */
static double depth_outliers(const meso_framebuffer *a, const meso_framebuffer *b, float bound,
                             long *out_both) {
    long both = 0, off = 0;
    for (int y = 0; y < a->height; y++)
        for (int x = 0; x < a->width; x++) {
            if (!covered(a, x, y) || !covered(b, x, y)) continue;
            size_t i = (size_t)y * (size_t)a->width + (size_t)x;
            both++;
            off += fabsf(a->depth[i] - b->depth[i]) > bound;
        }
    *out_both = both;
    return both ? (double)off / (double)both : 1.0;
}

static void test_hit_depths_on_a_sphere_agree_with_the_reference(void **state) {
    (void)state;
    meso_context *ctx = test_context(0);
    meso_scene *scene = scene_of(ctx, sphere_json);
    float depth = scene->objects[0].mesostructure.depth;
    float bound = (float)SHELL_DEPTH_FRACTION * depth;
    meso_framebuffer *truth = draw(ctx, scene, "reference", 0);
    static const char *const techniques[] = {"relief", "relief_exact", "relief_layers"};
    for (int t = 0; t < 3; t++) {
        meso_framebuffer *off = draw(ctx, scene, techniques[t], 0);
        meso_framebuffer *on = draw(ctx, scene, techniques[t], 1);
        long both_on, both_off;
        double far_on = depth_outliers(on, truth, bound, &both_on);
        double far_off = depth_outliers(off, truth, bound, &both_off);
        if (verbose())
            printf("%s: hits deeper or shallower than %.4f: shell 1 %.4f of %ld, shell 0 %.4f "
                   "of %ld\n",
                   techniques[t], (double)bound, far_on, both_on, far_off, both_off);
        if (!(far_on <= SHELL_DEPTH_OUTLIERS))
            fail_msg("%s: %.2f %% of the hits off the reference's by more than %g of the depth",
                     techniques[t], 100.0 * far_on, SHELL_DEPTH_FRACTION);
        /* the straight search's hits are the worse: what the shell is for */
        if (!(far_off > far_on))
            fail_msg("%s: shell 0 (%.4f) no farther off than shell 1 (%.4f)", techniques[t],
                     far_off, far_on);
        meso_framebuffer_destroy(off);
        meso_framebuffer_destroy(on);
    }
    meso_framebuffer_destroy(truth);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

/* The same bytes with 1 and 2 worker threads (the walk reads the state only). */
static void test_shell_images_do_not_depend_on_the_thread_count(void **state) {
    (void)state;
    meso_framebuffer *fb[2] = {NULL, NULL};
    for (int k = 0; k < 2; k++) {
        meso_context *ctx = test_context(k + 1);
        meso_scene *scene = scene_of(ctx, sphere_json);
        fb[k] = draw(ctx, scene, "relief", 1);
        meso_scene_destroy(scene);
        meso_context_destroy(ctx);
    }
    size_t n = (size_t)fb[0]->width * (size_t)fb[0]->height;
    assert_memory_equal(fb[0]->color, fb[1]->color, 3 * n * sizeof(float));
    assert_memory_equal(fb[0]->depth, fb[1]->depth, n * sizeof(float));
    meso_framebuffer_destroy(fb[0]);
    meso_framebuffer_destroy(fb[1]);
}

static void test_an_impostor_has_no_shell(void **state) {
    (void)state;
    meso_context *ctx = test_context(0);
    meso_scene *scene = scene_of(
        ctx, "{\"image\": {\"width\": 32, \"height\": 32},"
             " \"camera\": {\"eye\": [0, 0, 3], \"target\": [0, 0, 0], \"up\": [0, 1, 0],"
             " \"fov_y_deg\": 40},"
             " \"objects\": [{\"shape\": \"plane\", \"size\": 2,"
             " \"mesostructure\": {\"solid\": {\"impostor\": \"sphere\", \"resolution\": 16},"
             " \"depth\": 1},"
             " \"technique\": \"relief_layers\"}]}");
    meso_option option = {"relief_layers", "shell", 1};
    meso_render_desc desc = {.technique = "relief_layers", .options = &option, .num_options = 1};
    meso_framebuffer *fb = NULL;
    assert_int_equal(meso_render_scene(ctx, scene, &desc, &fb), MESO_ERROR_INVALID_ARGUMENT);
    assert_null(fb);
    assert_non_null(strstr(meso_context_last_error(ctx), "shell"));
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_constant_field_on_a_plane_adds_exactly_the_side_band),
        cmocka_unit_test(test_hit_depths_on_a_sphere_agree_with_the_reference),
        cmocka_unit_test(test_shell_images_do_not_depend_on_the_thread_count),
        cmocka_unit_test(test_an_impostor_has_no_shell),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
