/* flat and bump: byte-identical images for any thread count, their shading, the registry and
 * the shared shading functions. */
#include <math.h>

#include "render_internal.h"
#include "render_shading.h"
#include "render_test_scene.h"
#include "meso/texture.h"

static void render_threads(test_scene *ts, const char *technique, int threads,
                           meso_framebuffer **out) {
    meso_context *ctx = test_context(threads);
    assert_int_equal(
        meso_render_scene(ctx, &ts->scene, &(meso_render_desc){.technique = technique}, out),
        MESO_OK);
    meso_context_destroy(ctx);
}

static void check_thread_identity(test_scene *ts, const char *technique) {
    meso_framebuffer *fb[3] = {NULL, NULL, NULL};
    const int threads[3] = {1, 2, 4};
    for (int i = 0; i < 3; i++) render_threads(ts, technique, threads[i], &fb[i]);
    size_t n = (size_t)fb[0]->width * (size_t)fb[0]->height;
    int covered = 0;
    for (size_t p = 0; p < n; p++) covered += fb[0]->coverage[p] > 0.0f;
    assert_true(covered > (int)(n / 8));
    for (int i = 1; i < 3; i++) {
        assert_memory_equal(fb[0]->color, fb[i]->color, 3 * n * sizeof(float));
        assert_memory_equal(fb[0]->depth, fb[i]->depth, n * sizeof(float));
        assert_memory_equal(fb[0]->coverage, fb[i]->coverage, n * sizeof(float));
    }
    for (int i = 0; i < 3; i++) meso_framebuffer_destroy(fb[i]);
}

static void test_flat_and_bump_are_identical_for_1_2_4_threads_on_a_sphere(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    test_scene ts;
    test_scene_init(&ts, 160, 120);
    meso_object *o =
        test_scene_add(&ts, test_shape(ctx, MESO_SHAPE_SPHERE, 0.9f, 64, (meso_vec3){0}), "flat");
    test_object_bricks(ctx, o);
    check_thread_identity(&ts, "flat");
    check_thread_identity(&ts, "bump");
    test_scene_free(&ts);
    meso_context_destroy(ctx);
}

static void test_flat_and_bump_are_identical_for_1_2_4_threads_on_a_plane(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    test_scene ts;
    test_scene_init(&ts, 150, 100);
    meso_object *o =
        test_scene_add(&ts, test_shape(ctx, MESO_SHAPE_PLANE, 2.0f, 8, (meso_vec3){0}), "flat");
    test_object_bricks(ctx, o);
    o->material.specular = (meso_vec3){0.3f, 0.3f, 0.3f};
    check_thread_identity(&ts, "flat");
    check_thread_identity(&ts, "bump");
    test_scene_free(&ts);
    meso_context_destroy(ctx);
}

static void test_bump_changes_shading_but_not_coverage_or_depth(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    test_scene ts;
    test_scene_init(&ts, 96, 96);
    meso_object *o =
        test_scene_add(&ts, test_shape(ctx, MESO_SHAPE_PLANE, 2.0f, 4, (meso_vec3){0}), "flat");
    test_object_bricks(ctx, o);
    meso_framebuffer *flat = NULL, *bump = NULL;
    assert_int_equal(
        meso_render_scene(ctx, &ts.scene, &(meso_render_desc){.technique = "flat"}, &flat),
        MESO_OK);
    assert_int_equal(
        meso_render_scene(ctx, &ts.scene, &(meso_render_desc){.technique = "bump"}, &bump),
        MESO_OK);
    size_t n = 96 * 96;
    assert_memory_equal(flat->coverage, bump->coverage, n * sizeof(float));
    assert_memory_equal(flat->depth, bump->depth, n * sizeof(float));
    int differ = 0;
    for (size_t i = 0; i < 3 * n; i++) differ += fabsf(flat->color[i] - bump->color[i]) > 1e-3f;
    assert_true(differ > 100); /* mortar grooves shade differently */
    meso_framebuffer_destroy(flat);
    meso_framebuffer_destroy(bump);
    test_scene_free(&ts);
    meso_context_destroy(ctx);
}

static void test_registry_lists_flat_first_and_reference_last(void **state) {
    (void)state;
    size_t n = meso_technique_count();
    assert_true(n >= 3);
    assert_string_equal(meso_technique_get(0)->name, "flat");
    assert_string_equal(meso_technique_get(1)->name, "bump");
    const meso_technique_info *ref = meso_technique_get(n - 1);
    assert_string_equal(ref->name, "reference");
    assert_int_equal(ref->kind, MESO_TECHNIQUE_REFERENCE);
    assert_null(meso_technique_get(n));
    assert_ptr_equal(meso_technique_find("bump"), meso_technique_get(1));
    assert_null(meso_technique_find("nope"));
    assert_null(meso_technique_lookup(NULL));
    const meso_technique *bump = meso_technique_lookup("bump");
    assert_int_equal(bump->info.accepts, MESO_TECHNIQUE_ACCEPTS_HEIGHT_FIELD);
    assert_non_null(bump->info.paper);
}

static void test_unknown_technique_option_names_object_and_option(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    test_scene ts;
    test_scene_init(&ts, 16, 16);
    meso_object *o =
        test_scene_add(&ts, test_shape(ctx, MESO_SHAPE_PLANE, 1.0f, 1, (meso_vec3){0}), "flat");
    snprintf(o->options[0].name, MESO_NAME_MAX, "steps");
    o->options[0].value = 3;
    o->num_options = 1;
    meso_renderer *r = NULL;
    assert_int_equal(meso_renderer_create(ctx, &ts.scene, NULL, &r), MESO_ERROR_INVALID_ARGUMENT);
    const char *msg = meso_context_last_error(ctx);
    assert_non_null(strstr(msg, "objects[0]"));
    assert_non_null(strstr(msg, "steps"));
    assert_non_null(strstr(msg, "unknown option of technique 'flat'"));
    test_scene_free(&ts);
    meso_context_destroy(ctx);
}

static void test_shade_point_follows_the_shading_model(void **state) {
    (void)state;
    test_scene ts;
    test_scene_init(&ts, 8, 8);
    ts.scene.lights[0].direction = (meso_vec3){0, 1, 0};
    meso_object o;
    memset(&o, 0, sizeof(o));
    o.material.albedo = (meso_vec3){0.5f, 0.25f, 1.0f};
    meso_frame frame;
    meso_frame_init(&frame, &ts.scene, 8, 8);
    meso_vec3 c = meso_shade_point(&frame, &o, (meso_vec3){0, 0, 0}, (meso_vec3){0, 1, 0},
                                   (meso_vec2){0, 0}, NULL);
    assert_true(fabsf(c.x - 0.5f * 1.1f) < 1e-6f && fabsf(c.y - 0.25f * 1.1f) < 1e-6f);
    float shadowed = 0.0f;
    c = meso_shade_point(&frame, &o, (meso_vec3){0, 0, 0}, (meso_vec3){0, 1, 0}, (meso_vec2){0, 0},
                         &shadowed);
    assert_true(fabsf(c.x - 0.05f) < 1e-6f);
    /* facing away: ambient only, and no specular */
    o.material.specular = (meso_vec3){1, 1, 1};
    c = meso_shade_point(&frame, &o, (meso_vec3){0, 0, 0}, (meso_vec3){0, -1, 0}, (meso_vec2){0, 0},
                         NULL);
    assert_true(fabsf(c.x - 0.05f) < 1e-6f);
}

/* A frame whose shading returns the colour map's value: no lights, white ambient. */
static void color_map_frame(test_scene *ts, meso_frame *frame) {
    test_scene_init(ts, 8, 8);
    ts->scene.num_lights = 0;
    ts->scene.ambient = (meso_vec3){1.0f, 1.0f, 1.0f};
    meso_frame_init(frame, &ts->scene, 8, 8);
}

/* The compact colour map (meso_texture_add_srgb8): a map whose values are 8-bit sRGB codes
 * (as a PNG gives) shades to the same bits as the float map, any other map within half an
 * 8-bit sRGB step (the largest, at 1.0, is 0.0089 in linear), and a value outside [0, 1]
 * keeps the float map. Single points and batches agree bit for bit in both paths. */
static void test_shading_compact_color_map_matches_float_map(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    const float *codes = meso_srgb8_table();
    assert_true(codes[0] == 0.0f && codes[255] == 1.0f);
    test_scene ts;
    meso_frame frame;
    color_map_frame(&ts, &frame);
    for (int exact = 0; exact < 2; exact++) {
        meso_image *image = NULL;
        assert_int_equal(meso_image_create(ctx, 7, 5, 3, &image), MESO_OK);
        for (int i = 0; i < 7 * 5 * 3; i++)
            image->pixels[i] = exact ? codes[(i * 97) % 256] : (float)((i * 37) % 101) / 100.0f;
        meso_texture *plain = NULL, *compact = NULL;
        assert_int_equal(meso_texture_create(ctx, image, MESO_WRAP_REPEAT, false, &plain), MESO_OK);
        assert_int_equal(meso_texture_create(ctx, image, MESO_WRAP_REPEAT, false, &compact),
                         MESO_OK);
        assert_int_equal(meso_texture_add_srgb8(ctx, compact), MESO_OK);
        assert_non_null(compact->srgb8);
        meso_object a, b;
        memset(&a, 0, sizeof(a));
        a.material.albedo = (meso_vec3){1.0f, 1.0f, 1.0f};
        b = a;
        a.material.color_map = plain;
        b.material.color_map = compact;
        meso_fragment frags[64];
        memset(frags, 0, sizeof(frags));
        float worst = 0.0f;
        for (int i = 0; i < 64; i++) {
            meso_vec2 uv = {(float)i * 0.173f - 2.0f, (float)(i * i % 17) * 0.0711f};
            meso_vec3 want =
                meso_shade_point(&frame, &a, (meso_vec3){0, 0, 0}, (meso_vec3){0, 1, 0}, uv, NULL);
            meso_vec3 got =
                meso_shade_point(&frame, &b, (meso_vec3){0, 0, 0}, (meso_vec3){0, 1, 0}, uv, NULL);
            if (exact) assert_memory_equal(&want, &got, sizeof(got));
            worst = fmaxf(worst, fmaxf(fabsf(got.x - want.x),
                                       fmaxf(fabsf(got.y - want.y), fabsf(got.z - want.z))));
            frags[i].normal = (meso_vec3){0, 1, 0};
            frags[i].uv = uv;
        }
        if (!(worst <= 0.0045f)) fail_msg("compact map off by %g", worst);
        if (!exact && !(worst > 0.0f)) fail_msg("quantisation left no trace: not the 8-bit path");
        meso_shade_fragments(&frame, &b, frags, 64, NULL);
        for (int i = 0; i < 64; i++) {
            meso_vec3 one =
                meso_shade_point(&frame, &b, frags[i].position, frags[i].normal, frags[i].uv, NULL);
            assert_memory_equal(&one, &frags[i].color, sizeof(one));
        }
        meso_texture_destroy(plain);
        meso_texture_destroy(compact);
        /* HDR: not representable, the float map stays */
        image->pixels[4] = 1.5f;
        assert_int_equal(meso_texture_create(ctx, image, MESO_WRAP_REPEAT, false, &compact),
                         MESO_OK);
        assert_int_equal(meso_texture_add_srgb8(ctx, compact), MESO_OK);
        assert_null(compact->srgb8);
        meso_texture_destroy(compact);
        meso_image_destroy(image);
    }
    meso_context_destroy(ctx);
}

/* meso_shade_batches_to_block (the per-object constants once a call) writes the bits of
 * meso_shade_batch8 group by group, with a compact colour map, a specular term, a point light
 * and a count that ends inside a group. */
static void test_shading_batches_to_block_match_shade_batch8(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    test_scene ts;
    test_scene_init(&ts, 8, 8);
    assert_true(ts.scene.num_lights < MESO_SCENE_MAX_LIGHTS);
    ts.scene.lights[ts.scene.num_lights++] = (meso_light){
        .type = MESO_LIGHT_POINT, .position = {1.0f, 2.0f, 0.5f}, .color = {0.7f, 0.6f, 0.5f}};
    meso_frame frame;
    meso_frame_init(&frame, &ts.scene, 8, 8);
    const float *codes = meso_srgb8_table();
    meso_image *image = NULL;
    assert_int_equal(meso_image_create(ctx, 5, 3, 3, &image), MESO_OK);
    for (int i = 0; i < 5 * 3 * 3; i++) image->pixels[i] = codes[(i * 71) % 256];
    meso_texture *map = NULL;
    assert_int_equal(meso_texture_create(ctx, image, MESO_WRAP_REPEAT, false, &map), MESO_OK);
    assert_int_equal(meso_texture_add_srgb8(ctx, map), MESO_OK);
    assert_non_null(map->srgb8);
    meso_object o;
    memset(&o, 0, sizeof(o));
    o.material.albedo = (meso_vec3){0.9f, 0.8f, 0.7f};
    o.material.color_map = map;
    o.material.specular = (meso_vec3){0.4f, 0.4f, 0.4f};
    o.material.shininess = 24.0f;
    meso_fragment_block *block = aligned_alloc(32, sizeof(*block));
    assert_non_null(block);
    block->count = 29;
    meso_shade_batch in[4];
    for (int g = 0; g < 4; g++) {
        for (int k = 0; k < 8; k++) {
            float a = 0.37f * (float)(8 * g + k);
            meso_vec3 n = meso_vec3_normalize((meso_vec3){sinf(a), 1.0f, cosf(2.0f * a)});
            in[g].px[k] = 0.1f * a, in[g].py[k] = 0.0f, in[g].pz[k] = -0.05f * a;
            in[g].nx[k] = n.x, in[g].ny[k] = n.y, in[g].nz[k] = n.z;
            in[g].u[k] = 0.61f * a - 1.0f, in[g].v[k] = 0.23f * a;
            in[g].tx[k] = in[g].ty[k] = in[g].tz[k] = 0.0f;
            in[g].bx[k] = in[g].by[k] = in[g].bz[k] = 0.0f;
        }
        meso_shade_batch_all_visible(&in[g], &frame);
    }
    meso_shade_batches_to_block(&frame, &o, in, 4, block, 0);
    for (int g = 0; g < 4; g++) {
        int lanes = 29 - 8 * g < 8 ? 29 - 8 * g : 8;
        v8f r, gr, b;
        meso_shade_batch8(&frame, &o, &in[g], lanes, &r, &gr, &b);
        float want[3][8];
        memcpy(want[0], &r, sizeof r), memcpy(want[1], &gr, sizeof gr),
            memcpy(want[2], &b, sizeof b);
        assert_memory_equal(block->r + 8 * g, want[0], (size_t)lanes * sizeof(float));
        assert_memory_equal(block->g + 8 * g, want[1], (size_t)lanes * sizeof(float));
        assert_memory_equal(block->b + 8 * g, want[2], (size_t)lanes * sizeof(float));
    }
    free(block);
    meso_texture_destroy(map);
    meso_image_destroy(image);
    meso_context_destroy(ctx);
}

/* The colour map in the shading equals meso_texture_sample's bilinear level-0 lookup, for
 * repeat and clamp, out-of-range and non-finite uvs, in single points and in batches. */
static void test_shading_samples_the_color_map_like_meso_texture_sample(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_image *image = NULL;
    assert_int_equal(meso_image_create(ctx, 5, 3, 3, &image), MESO_OK);
    for (int i = 0; i < 5 * 3 * 3; i++) image->pixels[i] = (float)((i * 37) % 11) / 10.0f;
    test_scene ts;
    meso_frame frame;
    color_map_frame(&ts, &frame);
    const meso_vec2 uvs[] = {{0.1f, 0.2f},     {0.95f, 0.03f},     {-0.3f, 1.7f},    {1.0f, 1.0f},
                             {0.0f, 0.0f},     {-1e-9f, 0.5f},     {3.2f, -7.9f},    {0.5f, NAN},
                             {INFINITY, 0.5f}, {0.4999f, 0.5001f}, {123.456f, 0.25f}};
    size_t n = sizeof(uvs) / sizeof(uvs[0]);
    for (int wrap = 0; wrap < 2; wrap++) {
        meso_texture *texture = NULL;
        assert_int_equal(meso_texture_create(ctx, image, wrap ? MESO_WRAP_CLAMP : MESO_WRAP_REPEAT,
                                             false, &texture),
                         MESO_OK);
        meso_object o;
        memset(&o, 0, sizeof(o));
        o.material.albedo = (meso_vec3){1.0f, 1.0f, 1.0f};
        o.material.color_map = texture;
        meso_fragment frags[16];
        memset(frags, 0, sizeof(frags));
        for (size_t i = 0; i < n; i++) {
            meso_vec4 want = meso_texture_sample(texture, uvs[i], 0.0f, MESO_FILTER_BILINEAR);
            meso_vec3 got = meso_shade_point(&frame, &o, (meso_vec3){0, 0, 0}, (meso_vec3){0, 1, 0},
                                             uvs[i], NULL);
            if (fabsf(got.x - want.x) > 1e-6f || fabsf(got.y - want.y) > 1e-6f ||
                fabsf(got.z - want.z) > 1e-6f)
                fail_msg("wrap %d uv (%g, %g): %g %g %g, want %g %g %g", wrap, uvs[i].x, uvs[i].y,
                         got.x, got.y, got.z, want.x, want.y, want.z);
            frags[i].normal = (meso_vec3){0, 1, 0};
            frags[i].uv = uvs[i];
        }
        meso_shade_fragments(&frame, &o, frags, n, NULL);
        for (size_t i = 0; i < n; i++) {
            meso_vec3 one =
                meso_shade_point(&frame, &o, frags[i].position, frags[i].normal, frags[i].uv, NULL);
            assert_memory_equal(&one, &frags[i].color, sizeof(one)); /* the same bits */
        }
        meso_texture_destroy(texture);
    }
    meso_image_destroy(image);
    meso_context_destroy(ctx);
}

static void test_displaced_normal_tilts_against_the_slope(void **state) {
    (void)state;
    meso_vec3 n = {0, 1, 0}, t = {1, 0, 0}, b = {0, 0, -1};
    meso_vec3 flat = meso_displaced_normal(n, t, b, 0.1f, (meso_vec2){0, 0});
    assert_true(fabsf(flat.y - 1.0f) < 1e-6f);
    meso_vec3 tilted = meso_displaced_normal(n, t, b, 1.0f, (meso_vec2){1, 0});
    assert_true(fabsf(tilted.x + sqrtf(0.5f)) < 1e-5f && fabsf(tilted.y - sqrtf(0.5f)) < 1e-5f);
    /* no tangent frame: the normal itself */
    meso_vec3 none =
        meso_displaced_normal(n, (meso_vec3){0}, (meso_vec3){0}, 1.0f, (meso_vec2){1, 1});
    assert_true(none.y == 1.0f);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_flat_and_bump_are_identical_for_1_2_4_threads_on_a_sphere),
        cmocka_unit_test(test_flat_and_bump_are_identical_for_1_2_4_threads_on_a_plane),
        cmocka_unit_test(test_bump_changes_shading_but_not_coverage_or_depth),
        cmocka_unit_test(test_registry_lists_flat_first_and_reference_last),
        cmocka_unit_test(test_unknown_technique_option_names_object_and_option),
        cmocka_unit_test(test_shade_point_follows_the_shading_model),
        cmocka_unit_test(test_displaced_normal_tilts_against_the_slope),
        cmocka_unit_test(test_shading_samples_the_color_map_like_meso_texture_sample),
        cmocka_unit_test(test_shading_compact_color_map_matches_float_map),
        cmocka_unit_test(test_shading_batches_to_block_match_shade_batch8),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
