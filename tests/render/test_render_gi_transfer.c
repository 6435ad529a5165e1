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
        cmocka_unit_test(test_gi_bad_arguments_are_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
