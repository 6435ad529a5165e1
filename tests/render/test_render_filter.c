/* Filtering by pixel footprint (docs/techniques.md, "Filtering"): the mip chain of a constant
 * map is that constant; a footprint within one texel reads exactly what the unfiltered lookup
 * reads; a footprint of two texels on a one-texel checkerboard reads its level-1 grey; a plane
 * seen head-on at one texel a pixel is unchanged by filtering; filtering changes nothing in a
 * scene without maps; a still camera's orbit has no change and no flicker. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render_internal.h"
#include "test_util.h"
#include "meso/texture.h"

/* The footprint of a head-on pixel is one texel up to float rounding of the camera (about 1e-7
 * of a texel), which may pick level 0 plus a blend of that size toward level 1: a colour
 * tolerance of 1e-5, far below one 8-bit step (1/255 in sRGB). */
#define HEAD_ON_TOLERANCE 1e-5f

static meso_texture *texture_of(meso_context *ctx, int w, int h, const float *rgb_of_texel,
                                bool checker) {
    meso_image *image = NULL;
    assert_int_equal(meso_image_create(ctx, w, h, 3, &image), MESO_OK);
    unsigned seed = 7;
    for (int j = 0; j < h; j++)
        for (int i = 0; i < w; i++) {
            float *p = image->pixels + 3 * ((size_t)j * w + i);
            for (int c = 0; c < 3; c++)
                p[c] = rgb_of_texel ? rgb_of_texel[c]
                       : checker    ? (float)((i + j) & 1)
                                    : test_uniform(&seed);
        }
    meso_texture *t = NULL;
    assert_int_equal(meso_texture_create(ctx, image, MESO_WRAP_REPEAT, true, &t), MESO_OK);
    meso_image_destroy(image);
    return t;
}

static void test_the_mip_chain_of_a_constant_map_is_constant(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    const float rgb[3] = {0.3f, 0.6f, 0.9f};
    /* odd sizes repeat their last row and column into the next level */
    meso_texture *t = texture_of(ctx, 37, 20, rgb, false);
    for (int pass = 0; pass < 2; pass++) {
        assert_non_null(t->mip_chain);
        assert_int_equal(t->num_levels, 6);
        const float *level0 = t->mip_chain;
        for (int k = 0; k < t->num_levels; k++) {
            const float *p = t->mip_chain + t->mip_offset[k];
            size_t n = (size_t)t->levels[k]->width * (size_t)t->levels[k]->height;
            for (size_t i = 0; i < n; i++)
                for (int c = 0; c < 4; c++)
                    if (p[4 * i + c] != level0[c])
                        fail_msg("level %d texel %zu channel %d: %.9g, not %.9g", k, i, c,
                                 p[4 * i + c], level0[c]);
        }
        /* with 8-bit sRGB codes, the chain is rebuilt from the decoded codes */
        assert_int_equal(meso_texture_add_srgb8(ctx, t), MESO_OK);
        assert_non_null(t->srgb8);
    }
    meso_texture_destroy(t);
    meso_context_destroy(ctx);
}

/* A bare scene of one object with colour map `map` for meso_shade_point_footprint. */
typedef struct shade_scene {
    meso_scene scene;
    meso_object object;
    meso_frame frame;
} shade_scene;

static void shade_scene_init(shade_scene *s, meso_texture *map) {
    memset(s, 0, sizeof *s);
    s->scene.ambient = (meso_vec3){1.0f, 1.0f, 1.0f}; /* colour = map(uv) */
    s->object.material.albedo = (meso_vec3){1.0f, 1.0f, 1.0f};
    s->object.material.color_map = map;
    s->scene.camera =
        (meso_camera){.eye = {0, 2, 0}, .target = {0, 0, 0}, .up = {0, 0, -1}, .fov_y_deg = 40};
    meso_frame_init(&s->frame, &s->scene, 16, 16);
}

static meso_vec3 lookup(const shade_scene *s, meso_vec2 uv, meso_vec2 dx, meso_vec2 dy) {
    meso_vec3 p = {0, 0, 0}, n = {0, 1, 0}, zero = {0, 0, 0};
    return meso_shade_point_footprint(&s->frame, &s->object, p, n, zero, zero, uv, dx, dy, NULL);
}

static void test_a_footprint_within_a_texel_reads_the_unfiltered_lookup(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    const int w = 64, h = 32;
    meso_texture *t = texture_of(ctx, w, h, NULL, false);
    shade_scene s;
    shade_scene_init(&s, t);
    unsigned seed = 3;
    for (int srgb = 0; srgb < 2; srgb++) {
        if (srgb) assert_int_equal(meso_texture_add_srgb8(ctx, t), MESO_OK);
        for (int i = 0; i < 500; i++) {
            meso_vec2 uv = {4.0f * test_uniform(&seed) - 2.0f, 4.0f * test_uniform(&seed) - 2.0f};
            /* one texel along each axis, and a turned footprint of at most one texel */
            float a = 6.2831853f * test_uniform(&seed), r = test_uniform(&seed);
            meso_vec2 dxs[2] = {{1.0f / w, 0.0f}, {r * cosf(a) / w, r * sinf(a) / h}};
            meso_vec2 dys[2] = {{0.0f, 1.0f / h}, {-r * sinf(a) / w, r * cosf(a) / h}};
            /* and a hair over one texel both ways, as float rounding of a camera gives:
             * one tap, a negligible blend toward level 1 */
            meso_vec2 dx1 = {1.000001f / w, 0.0f}, dy1 = {0.0f, 1.000001f / h};
            s.frame.filter = false;
            meso_vec3 point = lookup(&s, uv, dxs[0], dys[0]);
            s.frame.filter = true;
            for (int k = 0; k < 2; k++) {
                meso_vec3 filtered = lookup(&s, uv, dxs[k], dys[k]);
                if (memcmp(&point, &filtered, sizeof point) != 0)
                    fail_msg("uv (%g, %g), footprint %d: (%.9g %.9g %.9g), not (%.9g %.9g %.9g)",
                             uv.x, uv.y, k, filtered.x, filtered.y, filtered.z, point.x, point.y,
                             point.z);
            }
            meso_vec3 hair = lookup(&s, uv, dx1, dy1);
            assert_float_equal(hair.x, point.x, HEAD_ON_TOLERANCE);
            assert_float_equal(hair.y, point.y, HEAD_ON_TOLERANCE);
        }
    }
    meso_texture_destroy(t);
    meso_context_destroy(ctx);
}

static void test_a_two_texel_footprint_on_a_checkerboard_reads_its_grey(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    const int side = 32;
    meso_texture *t = texture_of(ctx, side, side, NULL, true);
    shade_scene s;
    shade_scene_init(&s, t);
    unsigned seed = 5;
    double worst_point = 0.0;
    for (int i = 0; i < 200; i++) {
        meso_vec2 uv = {test_uniform(&seed), test_uniform(&seed)};
        meso_vec2 dx = {2.0f / side, 0.0f}, dy = {0.0f, 2.0f / side};
        s.frame.filter = true;
        meso_vec3 c = lookup(&s, uv, dx, dy);
        /* level 1 of a one-texel checkerboard is 0.5 everywhere, exactly */
        assert_float_equal(c.x, 0.5f, 1e-6f);
        assert_float_equal(c.z, 0.5f, 1e-6f);
        s.frame.filter = false;
        worst_point = fmax(worst_point, fabs(lookup(&s, uv, dx, dy).x - 0.5f));
    }
    assert_true(worst_point > 0.2); /* the point samples alias: the test could fail */
    /* an anisotropic footprint, 8 texels along u by one along v: eight taps at level 0 along u
     * average the checker's columns to 0.5 */
    s.frame.filter = true;
    for (int i = 0; i < 100; i++) {
        meso_vec2 uv = {test_uniform(&seed), test_uniform(&seed)};
        meso_vec3 c =
            lookup(&s, uv, (meso_vec2){8.0f / side, 0.0f}, (meso_vec2){0.0f, 1.0f / side});
        assert_float_equal(c.x, 0.5f, 1e-5f);
    }
    meso_texture_destroy(t);
    meso_context_destroy(ctx);
}

/* A plane of size 2 under a 64 x 64 random colour map, seen straight down from the height at
 * which it fills the 64 x 64 image: one texel a pixel. */
static meso_scene *head_on_plane(meso_context *ctx, const char *dir, const char *mesostructure) {
    meso_image *image = NULL;
    assert_int_equal(meso_image_create(ctx, 64, 64, 3, &image), MESO_OK);
    unsigned seed = 11;
    for (size_t i = 0; i < 64 * 64 * 3; i++) image->pixels[i] = test_uniform(&seed);
    meso_png_desc srgb = {.encoding = MESO_ENCODING_SRGB};
    assert_int_equal(meso_image_save_png(ctx, image, test_path(dir, "noise.png"), &srgb), MESO_OK);
    meso_image_destroy(image);
    char json[2048];
    double height = 1.0 / tan(20.0 * 3.14159265358979 / 180.0);
    snprintf(json, sizeof json,
             "{\"image\": {\"width\": 64, \"height\": 64},"
             " \"camera\": {\"eye\": [0, %.9f, 0], \"target\": [0, 0, 0], \"up\": [0, 0, -1],"
             "  \"fov_y_deg\": 40},"
             " \"ambient\": [0.2, 0.2, 0.2],"
             " \"lights\": [{\"type\": \"directional\", \"direction\": [0.3, 0.8, -0.5]}],"
             " \"objects\": [{\"shape\": \"plane\", \"size\": 2,"
             "   \"material\": {\"albedo\": [1, 1, 1], \"color_map\": \"noise.png\"}%s}]}",
             height, mesostructure);
    meso_scene *scene = NULL;
    if (meso_scene_parse(ctx, json, "plane.json", dir, &scene) != MESO_OK)
        fail_msg("parse: %s", meso_context_last_error(ctx));
    return scene;
}

static meso_framebuffer *render(meso_context *ctx, const meso_scene *scene, const char *technique,
                                meso_render_filter filter) {
    meso_render_desc desc = {.technique = technique, .filter = filter};
    meso_framebuffer *fb = NULL;
    if (meso_render_scene(ctx, scene, &desc, &fb) != MESO_OK)
        fail_msg("%s: %s", technique, meso_context_last_error(ctx));
    return fb;
}

static void test_a_plane_seen_head_on_at_one_texel_a_pixel_is_unchanged(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    const char *dir = test_temp_dir();
    meso_scene *scene = head_on_plane(ctx, dir, "");
    const char *techniques[] = {"flat", "reference"};
    for (int k = 0; k < 2; k++) {
        meso_framebuffer *point = render(ctx, scene, techniques[k], MESO_RENDER_FILTER_POINT);
        meso_framebuffer *filtered =
            render(ctx, scene, techniques[k], MESO_RENDER_FILTER_FOOTPRINT);
        float worst = 0.0f;
        for (size_t i = 0; i < 3 * 64 * 64; i++)
            worst = fmaxf(worst, fabsf(point->color[i] - filtered->color[i]));
        if (!(worst <= HEAD_ON_TOLERANCE))
            fail_msg("%s: filtering changed a head-on plane by %g", techniques[k], worst);
        meso_framebuffer_destroy(point);
        meso_framebuffer_destroy(filtered);
    }
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

/* Without colour or normal maps there is nothing to filter: the images keep their bytes (the
 * footprint the rasterizer fills changes no other input). */
static void test_filtering_changes_nothing_without_maps(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    char path[1024];
    snprintf(path, sizeof path, "%s/examples/chainmail-plane.json", MESO_SOURCE_DIR);
    meso_scene *scene = NULL;
    assert_int_equal(meso_scene_load(ctx, path, &scene), MESO_OK);
    scene->width = scene->height = 40;
    const char *techniques[] = {"flat", "relief_layers", "reference"};
    for (int k = 0; k < 3; k++) {
        meso_framebuffer *point = render(ctx, scene, techniques[k], MESO_RENDER_FILTER_POINT);
        meso_framebuffer *filtered =
            render(ctx, scene, techniques[k], MESO_RENDER_FILTER_FOOTPRINT);
        meso_framebuffer *by_default =
            render(ctx, scene, techniques[k], MESO_RENDER_FILTER_DEFAULT);
        size_t bytes = sizeof(float) * 3 * 40 * 40;
        if (memcmp(point->color, filtered->color, bytes) != 0)
            fail_msg("%s: filtering changed a scene without maps", techniques[k]);
        if (memcmp(point->color, by_default->color, bytes) != 0)
            fail_msg("%s: the default is not point sampling", techniques[k]);
        meso_framebuffer_destroy(point);
        meso_framebuffer_destroy(filtered);
        meso_framebuffer_destroy(by_default);
    }
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

/* meso render --orbit 3 --orbit-step 0: three frames of one view, no change and no flicker. */
static void test_a_still_orbit_has_no_change_and_no_flicker(void **state) {
    (void)state;
    const char *dir = test_path(test_temp_dir(), "still");
    char args[2048];
    snprintf(args, sizeof args,
             "render %s/examples/tiles-floor.json --orbit 3 --orbit-step 0 --techniques flat,bump "
             "--size 24x24 --filter 1 -o %s --quiet",
             MESO_SOURCE_DIR, dir);
    const char *err = NULL;
    if (test_run_meso(args, &err) != 0) fail_msg("meso %s: %s", args, err);
    size_t size = 0;
    char *csv = test_read_file(test_path(dir, "temporal.csv"), &size);
    int rows = 0;
    for (char *line = strchr(csv, '\n'); line && line[1]; line = strchr(line + 1, '\n')) {
        char name[64];
        int frames = 0;
        double ms, psnr, covered, change, change_ratio, flicker, flicker_ratio;
        int read = sscanf(line + 1, "%63[^,],%d,%lf,%lf,%lf,%lf,%lf,%lf,%lf", name, &frames, &ms,
                          &psnr, &covered, &change, &change_ratio, &flicker, &flicker_ratio);
        if (read < 9) { /* the reference's PSNR is nan, which sscanf may not read */
            read = sscanf(line + 1, "%63[^,],%d,%lf,nan,nan,%lf,%lf,%lf,%lf", name, &frames, &ms,
                          &change, &change_ratio, &flicker, &flicker_ratio);
            assert_int_equal(read, 7);
        }
        assert_int_equal(frames, 3);
        if (change != 0.0 || flicker != 0.0)
            fail_msg("%s: a still camera changed by %g, flicker %g", name, change, flicker);
        rows++;
    }
    assert_int_equal(rows, 3); /* reference, flat, bump */
    free(csv);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_the_mip_chain_of_a_constant_map_is_constant),
        cmocka_unit_test(test_a_footprint_within_a_texel_reads_the_unfiltered_lookup),
        cmocka_unit_test(test_a_two_texel_footprint_on_a_checkerboard_reads_its_grey),
        cmocka_unit_test(test_a_plane_seen_head_on_at_one_texel_a_pixel_is_unchanged),
        cmocka_unit_test(test_filtering_changes_nothing_without_maps),
        cmocka_unit_test(test_a_still_orbit_has_no_change_and_no_flicker),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
