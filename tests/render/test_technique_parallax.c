/* parallax and horizon, shaded on fragments built by hand on the built-in plane
 * P(u,v) = (-1 + 2u, 0, 1 - 2v) (size 2): the texture shift of Kaneko et al. §3.1 read back
 * through a colour ramp, and horizon shadows of a step edge. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "technique_fixture.h"
#include "meso/texture.h"

static float h_half(int i, int j) {
    (void)i;
    (void)j;
    return 0.5f;
}
static float h_step(int i, int j) {
    (void)j;
    return i < 32 ? 1.0f : 0.0f;
}

/* A colour map whose red channel is u itself over the interior, so the shaded red gives back
 * the u the technique looked the colour up at. */
static meso_texture *u_ramp(void) {
    meso_context *ctx = test_context(1);
    meso_image *img = NULL;
    meso_texture *tex = NULL;
    assert_int_equal(meso_image_create(ctx, 256, 1, 3, &img), MESO_OK);
    for (int i = 0; i < 256; ++i)
        for (int c = 0; c < 3; ++c)
            img->pixels[3 * i + c] = ((float)i + 0.5f) / 256.0f; /* = u at texel centres */
    assert_int_equal(meso_texture_create(ctx, img, MESO_WRAP_CLAMP, false, &tex), MESO_OK);
    meso_image_destroy(img);
    meso_context_destroy(ctx);
    return tex;
}

/* Kaneko §3.1: u' = u + tan(theta_u) depth(u, v), here depth = (1 - 0.5) shell depths; with
 * offset limiting the shift is (1 - h) depth times the view's u rate per unit length. */
static void test_parallax_shifts_by_tan_theta_times_depth(void **state) {
    (void)state;
    for (int limiting = 0; limiting < 2; ++limiting) {
        fixture fx;
        const float depth = 0.1f;
        fixture_init(&fx, field(NULL, 32, 32, h_half), depth, (meso_vec3){-1.5f, 1.0f, 0.0f},
                     (meso_vec3){0, 0, 0}, (meso_vec3){0.0f, 1.0f, 0.0f});
        meso_texture *ramp = u_ramp();
        fx.object.material.albedo = (meso_vec3){1.0f, 1.0f, 1.0f};
        fx.object.material.color_map = ramp;
        set_option(&fx, "offset_limiting", limiting);
        float us[3] = {0.4f, 0.5f, 0.6f};
        for (int k = 0; k < 3; ++k) {
            meso_fragment f = plane_fragment(&fx, us[k], 0.5f);
            shade_with(&fx, "parallax", &f, 1);
            meso_vec3 view = meso_vec3_sub(f.position, fx.frame.eye);
            float cu = view.x / 2.0f, cn = view.y; /* T = (2,0,0), N = +y */
            float along = limiting ? meso_vec3_length(view) : -cn;
            float expect = us[k] + 0.5f * depth * cu / along;
            /* flat normal, light along N: red = u' * (ambient 0.1 + 1) */
            float got = f.color.x / 1.1f;
            assert_true(fabsf(got - expect) < 1e-4f);
            assert_true(got > us[k] + 1e-3f); /* the view runs toward +u: a real shift */
        }
        meso_texture_destroy(ramp);
        fixture_deinit(&fx);
    }
}

/* The floor right of a full-height block: the horizon toward the block is at 52 degrees, the
 * other way at 13: a light at 27 degrees is blocked from the block's side and not from the
 * other. */
static void test_horizon_dark_behind_the_wall_lit_in_front(void **state) {
    (void)state;
    for (int side = 0; side < 2; ++side) {
        fixture fx;
        float u = 36.5f / 64.0f;
        meso_vec3 p = {-1.0f + 2.0f * u, 0.0f, 0.0f};
        meso_vec3 light =
            side == 0 ? (meso_vec3){-1.0f, 0.5f, 0.0f} : (meso_vec3){1.0f, 0.5f, 0.0f};
        fixture_init(&fx, field(NULL, 64, 4, h_step), 0.2f, (meso_vec3){p.x, 2.0f, 0.0f}, p, light);
        meso_fragment f = plane_fragment(&fx, u, 0.5f);
        shade_with(&fx, "horizon", &f, 1);
        meso_vec3 l = meso_vec3_normalize(light);
        float expect = side == 0 ? 0.1f : 0.1f + l.y;
        assert_true(fabsf(f.color.x - 0.8f * expect) < 1e-4f);
        fixture_deinit(&fx);
    }
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_parallax_shifts_by_tan_theta_times_depth),
        cmocka_unit_test(test_horizon_dark_behind_the_wall_lit_in_front),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
