/* relief_layers on fragments built by hand on the built-in plane P(u,v) = (-1 + 2u, 0, 1 - 2v):
 * a slab solid against relief on the equivalent height field, an analytic two-layer case (a
 * ray passing under a bar hits the floor below it), discarded misses, option errors. The
 * technique's file is included so a test can hand it a map baked from an analytic field;
 * its registry symbol is renamed so it does not clash with the library's. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "technique_fixture.h"

#define meso_technique_relief_layers test_copy_of_relief_layers
#include "relief_layers.c"
#undef meso_technique_relief_layers

static float h_half(int i, int j) {
    (void)i;
    (void)j;
    return 0.5f;
}

#define GRID 6
static size_t grid_fragments(const fixture *fx, meso_fragment *f) {
    size_t n = 0;
    for (int j = 0; j < GRID; ++j)
        for (int i = 0; i < GRID; ++i)
            f[n++] =
                plane_fragment(fx, 0.1f + 0.8f * (float)i / GRID, 0.1f + 0.8f * (float)j / GRID);
    return n;
}

static void test_slab_solid_equals_relief_on_the_height_field(void **state) {
    (void)state;
    setenv("MESO_CACHE_DIR", "off", 1);
    fixture fx;
    fixture_init(&fx, field(NULL, 64, 64, h_half), 0.1f, (meso_vec3){0.3f, 1.2f, 2.2f},
                 (meso_vec3){0, 0, 0}, (meso_vec3){0.5f, 0.7f, 0.3f});
    meso_fragment expect[GRID * GRID], got[GRID * GRID];
    size_t n = grid_fragments(&fx, expect);
    shade_with(&fx, "relief", expect, n);
    /* the same object as a solid: the slab below w = 0.5 */
    meso_solid *slab = NULL;
    assert_int_equal(
        meso_solid_create_procedural(
            fx.ctx, &(meso_solid_desc){.kind = MESO_SOLID_SLAB, .thickness = 0.5f}, &slab),
        MESO_OK);
    fx.object.mesostructure.kind = MESO_MESOSTRUCTURE_SOLID;
    fx.object.mesostructure.solid = slab;
    set_option(&fx, "float", 1);
    set_option(&fx, "size", 64);
    grid_fragments(&fx, got);
    shade_with(&fx, "relief_layers", got, n);
    for (size_t k = 0; k < n; ++k) {
        assert_false(got[k].discard);
        assert_true(fabsf(got[k].out_depth - expect[k].out_depth) < 1e-4f * expect[k].out_depth);
        assert_true(fabsf(got[k].color.x - expect[k].color.x) < 1e-3f);
        assert_true(fabsf(got[k].color.y - expect[k].color.y) < 1e-3f);
        assert_true(fabsf(got[k].color.z - expect[k].color.z) < 1e-3f);
    }
    /* and the height field itself through relief_layers (one layer) */
    fx.object.mesostructure.kind = MESO_MESOSTRUCTURE_HEIGHT_FIELD;
    grid_fragments(&fx, got);
    shade_with(&fx, "relief_layers", got, n);
    for (size_t k = 0; k < n; ++k)
        assert_true(fabsf(got[k].out_depth - expect[k].out_depth) < 1e-4f * expect[k].out_depth);
    meso_solid_destroy(slab);
    fixture_deinit(&fx);
    unsetenv("MESO_CACHE_DIR");
}

/* One steep cone, its tip between texel centres: 1 at the centre, 0 eight texels away. Its
 * normal in texture space (u, v, -w) is nearly horizontal (slope 8 per u: z = 0.12), where z
 * rebuilt from an interpolated (x, y) is far off (docs/techniques/relief_layers.md, "Height
 * fields' normals"). */
static float h_cone(int i, int j) {
    float r = hypotf((float)i - 31.5f, (float)j - 31.5f);
    return fmaxf(0.0f, 1.0f - r / 8.0f);
}

/* A fragment of the plane with uv_scale s: the point of plane_fragment at uv / s, texture
 * coordinates uv, tangents shorter by s (the truth suite's cones-plane tiles 2.5 times). */
static meso_fragment tiled_fragment(const fixture *fx, float s, float u, float v) {
    meso_fragment f = plane_fragment(fx, u / s, v / s);
    f.uv = (meso_vec2){u, v};
    f.tangent = meso_vec3_scale(f.tangent, 1.0f / s);
    f.bitangent = meso_vec3_scale(f.bitangent, 1.0f / s);
    return f;
}

/* A height field through relief_layers shades like relief: the same hits, and the normal of
 * the field's gradient there (docs/design.md), also on a cone's flanks and tip and on tiled UVs. */
static void test_heightfield_normals_equal_relief_on_a_steep_cone(void **state) {
    (void)state;
    setenv("MESO_CACHE_DIR", "off", 1);
    fixture fx;
    fixture_init(&fx, field(NULL, 64, 64, h_cone), 0.1f, (meso_vec3){0.3f, 1.2f, 2.2f},
                 (meso_vec3){0, 0, 0}, (meso_vec3){0.5f, 0.7f, 0.3f});
    enum { SIDE = 16, N = SIDE * SIDE };
    const float scales[] = {1.0f, 2.5f};
    for (size_t sc = 0; sc < sizeof scales / sizeof scales[0]; sc++) {
        float s = scales[sc];
        meso_fragment expect[N], got[N];
        /* a grid over the cone's footprint (texture u, v in 0.5 +- 0.14) of the tile that
         * holds the middle of the plane */
        float tile = floorf(0.5f * s);
        for (int j = 0; j < SIDE; ++j)
            for (int i = 0; i < SIDE; ++i) {
                float u = tile + 0.36f + 0.28f * ((float)i + 0.5f) / SIDE;
                float v = tile + 0.36f + 0.28f * ((float)j + 0.5f) / SIDE;
                expect[j * SIDE + i] = got[j * SIDE + i] = tiled_fragment(&fx, s, u, v);
            }
        shade_with(&fx, "relief", expect, N);
        shade_with(&fx, "relief_layers", got, N);
        int same_hit = 0;
        float worst = 0.0f;
        for (int k = 0; k < N; ++k) {
            assert_false(expect[k].discard);
            assert_false(got[k].discard);
            /* the searches differ in their last steps (secant on another f); compare the
             * shading where they found the same point */
            if (fabsf(got[k].out_depth - expect[k].out_depth) > 1e-4f * expect[k].out_depth)
                continue;
            same_hit++;
            worst = fmaxf(worst, fabsf(got[k].color.x - expect[k].color.x));
            worst = fmaxf(worst, fabsf(got[k].color.y - expect[k].color.y));
            worst = fmaxf(worst, fabsf(got[k].color.z - expect[k].color.z));
        }
        print_message("uv_scale %.1f: %d of %d fragments hit the same point, largest colour "
                      "difference there %.4f\n",
                      (double)s, same_hit, N, (double)worst);
        assert_true(same_hit >= N * 9 / 10);
        assert_true(worst < 2e-3f);
    }
    fixture_deinit(&fx);
    unsetenv("MESO_CACHE_DIR");
}

/* The shadow search of a height field is relief's, the curved mesh's bulge included (on a
 * sphere a light ray from a hit runs deeper below the surface than the straight line from the
 * hit to where it leaves the shell): light rays of every kind, blocked for both or neither. */
static void test_heightfield_shadows_equal_relief_with_a_bulge(void **state) {
    (void)state;
    setenv("MESO_CACHE_DIR", "off", 1);
    fixture fx;
    fixture_init(&fx, field(NULL, 64, 64, h_cone), 0.1f, (meso_vec3){0.3f, 1.2f, 2.2f},
                 (meso_vec3){0, 0, 0}, (meso_vec3){0.5f, 0.7f, 0.3f});
    void *st = NULL;
    assert_int_equal(test_copy_of_relief_layers.prepare(fx.ctx, &fx.scene, &fx.object, &st),
                     MESO_OK);
    layers_state *s = st;
    srand(7);
    int differ = 0, blocked = 0;
    for (int n = 0; n < 400; ++n) {
        relief_shadow_batch b = {.count = 8, .active_bits = 0xff};
        for (int k = 0; k < 8; ++k) {
            /* around the cone (texels 24..40), where light rays can be blocked */
            b.x[k] = 24.0f + 16.0f * (float)rand() / (float)RAND_MAX;
            b.y[k] = 24.0f + 16.0f * (float)rand() / (float)RAND_MAX;
            b.d[k] = (float)rand() / (float)RAND_MAX;
            b.xd[k] = 40.0f * (2.0f * (float)rand() / (float)RAND_MAX - 1.0f);
            b.yd[k] = 40.0f * (2.0f * (float)rand() / (float)RAND_MAX - 1.0f);
            b.bulge[k] = 2.0f * (float)rand() / (float)RAND_MAX;
        }
        int got = 0;
        shadow(s, &b, 1, &got);
        int expect = relief_shadow_search8(&s->size, &b, s->shadow_steps);
        differ += __builtin_popcount((unsigned)(got ^ expect));
        blocked += __builtin_popcount((unsigned)expect);
    }
    print_message("shadows: %d of 3200 light rays blocked, %d differ from relief\n", blocked,
                  differ);
    assert_true(blocked > 400 && blocked < 2800); /* both kinds are tested */
    assert_int_equal(differ, 0);
    release(s);
    fixture_deinit(&fx);
    unsetenv("MESO_CACHE_DIR");
}

static float interval(float x, float lo, float hi) { return fmaxf(lo - x, x - hi); }

/* A bar along u at v in [0.4, 0.6], w in [0.2, 0.4], over a floor w >= 0.8. */
static float bar_field(void *user, meso_vec3 p) {
    (void)user;
    float bar = fmaxf(interval(p.y, 0.4f, 0.6f), interval(p.z, 0.2f, 0.4f));
    return fminf(bar, 0.8f - p.z);
}

/* A state for the bar, as prepare makes it from a map. */
static layers_state *bar_state(meso_context *ctx, const meso_object *object) {
    meso_layers *map = NULL;
    meso_layers_desc desc = {
        .field = bar_field, .width = 256, .height = 256, .format = MESO_LAYERS_FORMAT_F32};
    assert_int_equal(meso_layers_bake(ctx, &desc, &map), MESO_OK);
    layers_state *s = calloc(1, sizeof *s);
    assert_int_equal(fill_planes(ctx, object, map, s), MESO_OK);
    meso_layers_destroy(map);
    s->filter = true;
    s->linear_steps = 64;
    s->binary_steps = 8;
    s->shadow_steps = 16;
    return s;
}

/* The hit of fragment f: (v, w) in texture space. */
static void hit_vw(const fixture *fx, const meso_fragment *f, float *v, float *w) {
    float cu = 0.0f, cv = 0.0f, cn = 0.0f;
    meso_vec3 view = meso_vec3_sub(f->position, fx->frame.eye);
    assert_true(relief_frame_solve(f, view, &cu, &cv, &cn));
    float t = f->out_depth / f->depth - 1.0f;
    *v = f->uv.y + cv * t;
    *w = -cn * t / fx->object.mesostructure.depth;
}

static void test_ray_under_the_bar_hits_the_floor_below(void **state) {
    (void)state;
    fixture fx;
    /* eye low over the v < 0 side: rays run toward +v, dropping ~0.5 shell depths while they
     * cross the bar's width */
    fixture_init(&fx, field(NULL, 4, 4, h_half), 0.2f, (meso_vec3){0.0f, 0.5f, 2.2f},
                 (meso_vec3){0, 0, 0}, (meso_vec3){0.0f, 1.0f, 0.0f});
    layers_state *s = bar_state(fx.ctx, &fx.object);
    meso_fragment f[3] = {plane_fragment(&fx, 0.5f, 0.2f), plane_fragment(&fx, 0.5f, 0.3f),
                          plane_fragment(&fx, 0.5f, 0.5f)};
    shade(s, &fx.frame, &fx.object, f, 3);
    float v, w;
    /* v = 0.2: the ray is at w = 0.62 where the bar begins (v = 0.4), passes under it and
     * meets the floor at w = 0.8, v = 0.456, under the bar */
    assert_false(f[0].discard);
    hit_vw(&fx, &f[0], &v, &w);
    assert_true(fabsf(w - 0.8f) < 0.01f);
    assert_true(fabsf(v - 0.456f) < 0.01f);
    /* v = 0.3: into the bar's side at v = 0.4, w = 0.31, between its top and bottom */
    assert_false(f[1].discard);
    hit_vw(&fx, &f[1], &v, &w);
    assert_true(fabsf(v - 0.4f) < 0.01f);
    assert_true(w > 0.2f && w < 0.4f);
    /* v = 0.5: on the bar's top */
    hit_vw(&fx, &f[2], &v, &w);
    assert_true(fabsf(w - 0.2f) < 0.01f);
    /* light from straight above: the bar's top is lit, the floor under it is not */
    meso_fragment lit = plane_fragment(&fx, 0.5f, 0.5f), dark = plane_fragment(&fx, 0.5f, 0.2f);
    s->params.shadows = true;
    shade(s, &fx.frame, &fx.object, &lit, 1);
    shade(s, &fx.frame, &fx.object, &dark, 1);
    assert_true(lit.color.x > 2.0f * dark.color.x);
    release(s);
    fixture_deinit(&fx);
}

/* With nothing but a bar (no floor), a ray beside it leaves through the bottom: discarded
 * (§3.1), or drawn on the shell's floor with "missed": 1. */
static float lone_bar(void *user, meso_vec3 p) {
    (void)user;
    return fmaxf(interval(p.y, 0.4f, 0.6f), interval(p.z, 0.2f, 0.4f));
}

static void test_missed_rays_are_discarded_or_drawn_on_the_floor(void **state) {
    (void)state;
    fixture fx;
    fixture_init(&fx, field(NULL, 4, 4, h_half), 0.2f, (meso_vec3){0.0f, 3.0f, 0.3f},
                 (meso_vec3){0, 0, 0}, (meso_vec3){0.0f, 1.0f, 0.0f});
    meso_layers *map = NULL;
    meso_layers_desc desc = {.field = lone_bar, .width = 64, .height = 64};
    assert_int_equal(meso_layers_bake(fx.ctx, &desc, &map), MESO_OK);
    layers_state *s = calloc(1, sizeof *s);
    assert_int_equal(fill_planes(fx.ctx, &fx.object, map, s), MESO_OK);
    meso_layers_destroy(map);
    s->filter = true;
    s->linear_steps = 32;
    s->binary_steps = 6;
    s->shadow_steps = 8;
    meso_fragment f[2] = {plane_fragment(&fx, 0.5f, 0.1f), plane_fragment(&fx, 0.5f, 0.5f)};
    shade(s, &fx.frame, &fx.object, f, 2);
    assert_true(f[0].discard);
    assert_false(f[1].discard);
    s->missed_floor = true;
    f[0] = plane_fragment(&fx, 0.5f, 0.1f);
    shade(s, &fx.frame, &fx.object, f, 1);
    assert_false(f[0].discard);
    float v, w;
    hit_vw(&fx, &f[0], &v, &w);
    assert_true(fabsf(w - 1.0f) < 0.01f);
    release(s);
    fixture_deinit(&fx);
}

/* §4: an impostor of a model symmetric under y -> -y (a torus lying flat), seen from above
 * (front faces) and from the mirrored point below (back faces, the search turned around), with
 * a light in the mirror plane: the two images are each other's vertical mirror. */
static meso_image *render_impostor(meso_context *ctx, float eye_y) {
    char json[2048];
    snprintf(json, sizeof json,
             "{\"image\": {\"width\": 48, \"height\": 48},"
             " \"camera\": {\"eye\": [0, %g, 3.2], \"target\": [0, 0, 0], \"up\": [0, 1, 0],"
             " \"fov_y_deg\": 50},"
             " \"lights\": [{\"type\": \"directional\", \"direction\": [0.3, 0, 1],"
             " \"color\": [1, 1, 1]}],"
             " \"objects\": [{\"shape\": \"plane\", \"size\": 3.1111,"
             " \"mesostructure\": {\"solid\": {\"impostor\": \"torus\", \"resolution\": 48},"
             " \"depth\": 0.8889}, \"technique\": \"relief_layers\"}]}",
             (double)eye_y);
    meso_scene *scene = NULL;
    assert_int_equal(meso_scene_parse(ctx, json, "impostor.json", ".", &scene), MESO_OK);
    meso_framebuffer *fb = NULL;
    assert_int_equal(meso_render_scene(ctx, scene, NULL, &fb), MESO_OK);
    meso_image *image = NULL;
    assert_int_equal(meso_framebuffer_color_image(ctx, fb, &image), MESO_OK);
    meso_framebuffer_destroy(fb);
    meso_scene_destroy(scene);
    return image;
}

static void test_impostor_front_and_back_views_of_a_symmetric_model_agree(void **state) {
    (void)state;
    setenv("MESO_CACHE_DIR", "off", 1);
    meso_context *ctx = test_context(2);
    meso_image *above = render_impostor(ctx, 2.0f), *below = render_impostor(ctx, -2.0f);
    double sum = 0.0;
    int covered = 0, agree = 0;
    for (int j = 0; j < 48; j++)
        for (int i = 0; i < 48; i++)
            for (int c = 0; c < 3; c++) {
                float a = above->pixels[(j * 48 + i) * 3 + c];
                float b = below->pixels[((47 - j) * 48 + i) * 3 + c];
                sum += fabs((double)a - (double)b);
                if (c == 0) {
                    covered += a > 0.0f;
                    agree += (a > 0.0f) == (b > 0.0f);
                }
            }
    print_message("impostor: %d covered, %d agree, mean difference %.4f\n", covered, agree,
                  sum / (48.0 * 48.0 * 3.0));
    assert_true(covered > 200);         /* the torus is there */
    assert_true(agree >= 48 * 48 - 60); /* the same outline, up to a few edge pixels */
    assert_true(sum / (48.0 * 48.0 * 3.0) < 0.02);
    meso_image_destroy(above);
    meso_image_destroy(below);
    meso_context_destroy(ctx);
    unsetenv("MESO_CACHE_DIR");
}

static void test_bad_options_name_the_option(void **state) {
    (void)state;
    setenv("MESO_CACHE_DIR", "off", 1);
    fixture fx;
    fixture_init(&fx, field(NULL, 8, 8, h_half), 0.1f, (meso_vec3){0.3f, 1.2f, 2.2f},
                 (meso_vec3){0, 0, 0}, (meso_vec3){0.5f, 0.7f, 0.3f});
    const meso_technique *t = meso_technique_lookup("relief_layers");
    assert_non_null(t);
    void *st = NULL;
    set_option(&fx, "layers", 6);
    assert_int_equal(t->prepare(fx.ctx, &fx.scene, &fx.object, &st), MESO_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(meso_context_last_error(fx.ctx), "layers"));
    fx.object.num_options = 0;
    set_option(&fx, "linear_step", 6);
    assert_int_equal(t->prepare(fx.ctx, &fx.scene, &fx.object, &st), MESO_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(meso_context_last_error(fx.ctx), "linear_step"));
    assert_null(st);
    fixture_deinit(&fx);
    unsetenv("MESO_CACHE_DIR");
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_slab_solid_equals_relief_on_the_height_field),
        cmocka_unit_test(test_heightfield_normals_equal_relief_on_a_steep_cone),
        cmocka_unit_test(test_heightfield_shadows_equal_relief_with_a_bulge),
        cmocka_unit_test(test_ray_under_the_bar_hits_the_floor_below),
        cmocka_unit_test(test_missed_rays_are_discarded_or_drawn_on_the_floor),
        cmocka_unit_test(test_impostor_front_and_back_views_of_a_symmetric_model_agree),
        cmocka_unit_test(test_bad_options_name_the_option),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
