/* Texture sampling: texel centres, filters, wrapping, mip pyramid. */
#include "test_util.h"
#include "meso/texture.h"

static meso_texture *checker_texture(meso_context *ctx, meso_wrap wrap, bool mips) {
    meso_image *image = NULL;
    assert_int_equal(meso_image_create(ctx, 4, 4, 1, &image), MESO_OK);
    for (int y = 0; y < 4; y++)
        for (int x = 0; x < 4; x++) meso_image_at(image, x, y)[0] = (float)((x + y) % 2);
    meso_texture *t = NULL;
    assert_int_equal(meso_texture_create(ctx, image, wrap, mips, &t), MESO_OK);
    meso_image_destroy(image);
    return t;
}

static void test_texture_texel_centres_follow_opengl(void **state) {
    meso_context *ctx = test_context(1);
    meso_image *image = NULL;
    assert_int_equal(meso_image_create(ctx, 2, 2, 1, &image), MESO_OK);
    meso_image_at(image, 0, 0)[0] = 0.1f; /* top-left of the file: u small, v large */
    meso_image_at(image, 1, 0)[0] = 0.2f;
    meso_image_at(image, 0, 1)[0] = 0.3f; /* bottom row: v small */
    meso_image_at(image, 1, 1)[0] = 0.4f;
    meso_texture *t = NULL;
    assert_int_equal(meso_texture_create(ctx, image, MESO_WRAP_CLAMP, false, &t), MESO_OK);
    assert_float_equal(meso_texture_sample(t, (meso_vec2){0.25f, 0.75f}, 0, MESO_FILTER_BILINEAR).x,
                       0.1f, 1e-6);
    assert_float_equal(meso_texture_sample(t, (meso_vec2){0.75f, 0.75f}, 0, MESO_FILTER_BILINEAR).x,
                       0.2f, 1e-6);
    assert_float_equal(meso_texture_sample(t, (meso_vec2){0.25f, 0.25f}, 0, MESO_FILTER_BILINEAR).x,
                       0.3f, 1e-6);
    assert_float_equal(meso_texture_sample(t, (meso_vec2){0.5f, 0.5f}, 0, MESO_FILTER_BILINEAR).x,
                       0.25f, 1e-6);
    /* grey spreads to RGB, alpha is 1 */
    meso_vec4 s = meso_texture_sample(t, (meso_vec2){0.75f, 0.25f}, 0, MESO_FILTER_NEAREST);
    assert_float_equal(s.y, 0.4f, 1e-6);
    assert_float_equal(s.w, 1.0f, 0);
    meso_texture_destroy(t);
    meso_image_destroy(image);
    meso_context_destroy(ctx);
}

static void test_texture_repeat_and_clamp_differ_at_the_border(void **state) {
    meso_context *ctx = test_context(1);
    meso_texture *repeat = checker_texture(ctx, MESO_WRAP_REPEAT, false);
    meso_texture *clamp = checker_texture(ctx, MESO_WRAP_CLAMP, false);
    /* u = 0 sits between texel 3 (value 0 or 1) and texel 0 of the same row under repeat */
    meso_vec2 border = {0.0f, 1.0f - 0.5f / 4.0f};
    assert_float_equal(meso_texture_sample(repeat, border, 0, MESO_FILTER_BILINEAR).x, 0.5f, 1e-6);
    assert_float_equal(meso_texture_sample(clamp, border, 0, MESO_FILTER_BILINEAR).x, 0.0f, 1e-6);
    /* repeat: one tile over gives the same value */
    meso_vec2 a = {0.3f, 0.6f}, b = {1.3f, -0.4f};
    assert_float_equal(meso_texture_sample(repeat, a, 0, 0).x,
                       meso_texture_sample(repeat, b, 0, 0).x, 1e-5);
    meso_texture_destroy(repeat);
    meso_texture_destroy(clamp);
    meso_context_destroy(ctx);
}

static void test_texture_mip_pyramid_averages(void **state) {
    meso_context *ctx = test_context(1);
    meso_texture *t = checker_texture(ctx, MESO_WRAP_REPEAT, true);
    assert_int_equal(t->num_levels, 3);
    assert_int_equal(t->levels[2]->width, 1);
    assert_float_equal(t->levels[1]->pixels[0], 0.5f, 1e-6);
    /* trilinear at lod 2 is the mean; at lod 0 the checker itself */
    assert_float_equal(
        meso_texture_sample(t, (meso_vec2){0.125f, 0.875f}, 2.0f, MESO_FILTER_TRILINEAR).x, 0.5f,
        1e-6);
    assert_float_equal(
        meso_texture_sample(t, (meso_vec2){0.125f, 0.875f}, 0.0f, MESO_FILTER_TRILINEAR).x, 0.0f,
        1e-6);
    assert_float_equal(
        meso_texture_sample(t, (meso_vec2){0.125f, 0.875f}, 0.5f, MESO_FILTER_TRILINEAR).x, 0.25f,
        1e-6);
    meso_texture_destroy(t);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_texture_texel_centres_follow_opengl),
        cmocka_unit_test(test_texture_repeat_and_clamp_differ_at_the_border),
        cmocka_unit_test(test_texture_mip_pyramid_averages),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
