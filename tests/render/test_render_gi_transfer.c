/* Macro-scale transfer (render_gi_transfer.c): per-vertex incident radiance in SH in each
 * vertex's tangent frame, with the base mesh's occlusion. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "render_gi.h"
#include "test_util.h"

static meso_environment *uniform_sky(meso_context *ctx) {
    meso_sky_desc sky = {.zenith = {1, 1, 1},
                         .horizon = {1, 1, 1},
                         .ground = {1, 1, 1},
                         .no_sun = true,
                         .width = 64};
    meso_environment *env = NULL;
    assert_int_equal(meso_environment_create_sky(ctx, &sky, 1.0f, &env), MESO_OK);
    return env;
}

static meso_mesh *shape(meso_context *ctx, meso_shape_kind kind) {
    meso_mesh *mesh = NULL;
    meso_shape_desc desc = {.kind = kind, .segments = kind == MESO_SHAPE_PLANE ? 4 : 48};
    assert_int_equal(meso_mesh_create_shape(ctx, &desc, &mesh), MESO_OK);
    return mesh;
}

/* The irradiance at the vertex's normal: local z. */
static float vertex_irradiance(const float *radiance, size_t v, int channel) {
    return meso_sh_irradiance(radiance + (v * 3 + (size_t)channel) * MESO_SH_COUNT,
                              (meso_vec3){0, 0, 1});
}

static void test_gi_open_plane_receives_the_sky(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_mesh *plane = shape(ctx, MESO_SHAPE_PLANE);
    /* uniform sky, nothing occludes: E = pi L. The lower hemisphere is cut before the order-4
     * projection, so the step at the horizon rings: measured within 1 % */
    meso_environment *env = uniform_sky(ctx);
    float *radiance = NULL;
    assert_int_equal(meso_gi_vertex_radiance(ctx, plane, env, NULL, &radiance), MESO_OK);
    for (size_t v = 0; v < plane->num_vertices; v++)
        assert_float_equal(vertex_irradiance(radiance, v, 0), M_PI, (float)(0.01 * M_PI));
    free(radiance);
    meso_environment_destroy(env);
    /* the default sky (a sun): the plane's local frame sees what the world frame sees at +y */
    assert_int_equal(meso_environment_create_sky(ctx, &(meso_sky_desc){.width = 128}, 1.0f, &env),
                     MESO_OK);
    assert_int_equal(meso_gi_vertex_radiance(ctx, plane, env, NULL, &radiance), MESO_OK);
    for (int c = 0; c < 3; c++) {
        float world = meso_sh_irradiance(env->sh[c], (meso_vec3){0, 1, 0});
        assert_float_equal(vertex_irradiance(radiance, 0, c), world, 0.03 * world);
    }
    free(radiance);
    meso_environment_destroy(env);
    meso_mesh_destroy(plane);
    meso_context_destroy(ctx);
}

static void test_gi_torus_hole_is_darker_than_its_outside(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_mesh *torus = shape(ctx, MESO_SHAPE_TORUS);
    meso_environment *env = uniform_sky(ctx);
    float *radiance = NULL;
    assert_int_equal(meso_gi_vertex_radiance(ctx, torus, env, NULL, &radiance), MESO_OK);
    /* the vertices nearest the axis (inner equator) and farthest (outer equator) */
    size_t inner = 0, outer = 0;
    for (size_t v = 0; v < torus->num_vertices; v++) {
        meso_vec3 p = torus->positions[v];
        float r = sqrtf(p.x * p.x + p.z * p.z);
        meso_vec3 pi = torus->positions[inner], po = torus->positions[outer];
        if (r < sqrtf(pi.x * pi.x + pi.z * pi.z)) inner = v;
        if (r > sqrtf(po.x * po.x + po.z * po.z)) outer = v;
    }
    float e_inner = vertex_irradiance(radiance, inner, 1);
    float e_outer = vertex_irradiance(radiance, outer, 1);
    print_message("torus: inner equator E = %.3f, outer %.3f (pi = %.3f)\n", e_inner, e_outer,
                  M_PI);
    /* outside nothing occludes; inside, the far side of the ring fills much of the view */
    assert_float_equal(e_outer, M_PI, (float)(0.02 * M_PI));
    assert_true(e_inner < 0.8f * e_outer);
    assert_true(e_inner > 0.0f);
    /* the same with any number of threads */
    meso_context *one = test_context(1);
    float *again = NULL;
    assert_int_equal(meso_gi_vertex_radiance(one, torus, env, NULL, &again), MESO_OK);
    assert_memory_equal(again, radiance, torus->num_vertices * 3 * MESO_SH_COUNT * sizeof(float));
    free(again);
    meso_context_destroy(one);
    free(radiance);
    meso_environment_destroy(env);
    meso_mesh_destroy(torus);
    meso_context_destroy(ctx);
}

/* Through the shell, on a closed sphere under a uniform sky: above the tangent plane as
 * before; every direction below it meets the sphere's far side, so the interior's
 * coefficients are those of the lower hemisphere (c_0 = 2 pi Y_0 = 1.7725, c_2 = -pi 0.4886 =
 * -1.5349, c_12 = pi / 2 0.3732 = 0.5862), and the cavity's radiance has its closed form. */
static void test_gi_closed_sphere_through_the_shell(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_mesh *sphere = shape(ctx, MESO_SHAPE_SPHERE);
    meso_environment *env = uniform_sky(ctx);
    float *opaque = NULL, *radiance = NULL, *interior = NULL;
    assert_int_equal(meso_gi_vertex_radiance(ctx, sphere, env, NULL, &opaque), MESO_OK);
    assert_int_equal(
        meso_gi_vertex_radiance_through_shell(ctx, sphere, env, NULL, &radiance, &interior),
        MESO_OK);
    /* a few directions just below the tangent plane slip past the faceted sphere */
    float largest = 0.0f;
    for (size_t k = 0; k < sphere->num_vertices * 3 * MESO_SH_COUNT; k++)
        largest = fmaxf(largest, fabsf(opaque[k] - radiance[k]));
    print_message("through the shell, largest change above: %.4f\n", largest);
    assert_true(largest < 0.05f);
    const float lower[MESO_SH_COUNT] = {1.7725f, 0, -1.5349f, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0.5862f};
    for (size_t v = 0; v < sphere->num_vertices; v += 97)
        for (int k = 0; k < MESO_SH_COUNT; k++)
            assert_float_equal(interior[v * MESO_SH_COUNT + (size_t)k], lower[k], 0.03);
    /* tau 0.5, albedo 0.5, E = pi, the sky's mean 1: wall = 0.25 pi / (pi 0.5 0.75) = 2 / 3,
     * interior = 0.5 (2 / 3) + 0.5 = 5 / 6; closed, no light comes in; open, the sky */
    meso_scene scene = {.environment = env};
    meso_vec3 grey = {0.5f, 0.5f, 0.5f};
    meso_vec3 half = meso_gi_interior_radiance(sphere, radiance, &scene, grey, 0.5f);
    assert_float_equal(half.y, 5.0f / 6.0f, 0.02f);
    assert_float_equal(meso_gi_interior_radiance(sphere, radiance, &scene, grey, 0.0f).y, 0.0,
                       1e-6);
    assert_float_equal(meso_gi_interior_radiance(sphere, radiance, &scene, grey, 1.0f).y, 1.0,
                       0.01);
    /* a light adds its mean cosine over the sphere, 1/4 of its intensity, to E: 1 here, so
     * the interior 0.5 x 0.25 / (pi 0.5 0.75) more */
    scene.lights[0] =
        (meso_light){.type = MESO_LIGHT_DIRECTIONAL, .direction = {0, 1, 0}, .color = {4, 4, 4}};
    scene.num_lights = 1;
    meso_vec3 lit = meso_gi_interior_radiance(sphere, radiance, &scene, grey, 0.5f);
    assert_float_equal(lit.y - half.y, (float)(0.125 / (M_PI * 0.375)), 0.005f);
    free(opaque);
    free(radiance);
    free(interior);
    meso_environment_destroy(env);
    meso_mesh_destroy(sphere);
    meso_context_destroy(ctx);
}

/* A woven solid lets light through its holes; a height field's shell is closed. */
static void test_gi_open_fraction_of_the_shell(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_solid *weave = NULL;
    assert_int_equal(
        meso_solid_create_procedural(ctx, &(meso_solid_desc){.kind = MESO_SOLID_WEAVE}, &weave),
        MESO_OK);
    meso_mesostructure woven = {.kind = MESO_MESOSTRUCTURE_SOLID, .solid = weave};
    float tau = meso_gi_open_fraction(&woven);
    print_message("weave: open fraction %.3f\n", tau);
    assert_true(tau > 0.05f && tau < 0.5f);
    meso_heightfield *hf = NULL;
    assert_int_equal(meso_heightfield_create_constant(ctx, 4, 4, 0.0f, &hf), MESO_OK);
    meso_mesostructure field = {.kind = MESO_MESOSTRUCTURE_HEIGHT_FIELD, .height_field = hf};
    assert_float_equal(meso_gi_open_fraction(&field), 0.0, 0.0);
    meso_heightfield_destroy(hf);
    meso_solid_destroy(weave);
    meso_context_destroy(ctx);
}

static void test_gi_bad_arguments_are_refused(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_mesh *plane = shape(ctx, MESO_SHAPE_PLANE);
    float *radiance = (float *)1;
    assert_int_equal(meso_gi_vertex_radiance(ctx, plane, NULL, NULL, &radiance),
                     MESO_ERROR_INVALID_ARGUMENT);
    assert_null(radiance);
    meso_environment *env = uniform_sky(ctx);
    assert_int_equal(meso_gi_vertex_radiance(ctx, plane, env,
                                             &(meso_gi_vertex_desc){.directions = 8}, &radiance),
                     MESO_ERROR_INVALID_ARGUMENT);
    assert_string_equal(meso_context_last_error(ctx),
                        "vertex radiance: directions: 8 is not in [16, 65536]");
    meso_environment_destroy(env);
    meso_mesh_destroy(plane);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gi_open_plane_receives_the_sky),
        cmocka_unit_test(test_gi_torus_hole_is_darker_than_its_outside),
        cmocka_unit_test(test_gi_closed_sphere_through_the_shell),
        cmocka_unit_test(test_gi_open_fraction_of_the_shell),
        cmocka_unit_test(test_gi_bad_arguments_are_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
