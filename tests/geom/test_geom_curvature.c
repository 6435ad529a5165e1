/* Curvature (Rusinkiewicz 2004) and quadric fits (Oliveira & Policarpo 2005) on shapes whose
 * answers are known in closed form. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"

static meso_mesh *make_shape(meso_context *ctx, meso_shape_desc desc) {
    meso_mesh *mesh = NULL;
    assert_int_equal(meso_mesh_create_shape(ctx, &desc, &mesh), MESO_OK);
    return mesh;
}

static void test_sphere_curvature_is_one_over_radius(void **state) {
    meso_context *ctx = test_context(2);
    const float radius = 2.5f;
    meso_mesh *mesh = make_shape(ctx, (meso_shape_desc){.kind = MESO_SHAPE_SPHERE, .size = radius});
    assert_int_equal(meso_mesh_compute_curvature(ctx, mesh), MESO_OK);
    size_t checked = 0;
    for (size_t i = 0; i < mesh->num_vertices; i++) {
        if (fabsf(mesh->positions[i].y) > 0.7f * radius) continue; /* mid latitudes */
        assert_float_equal(mesh->curvature_max[i], 1.0f / radius, 0.05f / radius);
        assert_float_equal(mesh->curvature_min[i], 1.0f / radius, 0.05f / radius);
        assert_true(mesh->curvature_max[i] >= mesh->curvature_min[i]);
        /* Directions: unit, in the tangent plane, orthogonal to each other. */
        meso_vec3 d1 = mesh->curvature_dir_max[i], d2 = mesh->curvature_dir_min[i];
        assert_float_equal(meso_vec3_length(d1), 1.0f, 1e-4f);
        assert_float_equal(meso_vec3_dot(d1, mesh->normals[i]), 0.0f, 1e-4f);
        assert_float_equal(meso_vec3_dot(d1, d2), 0.0f, 1e-4f);
        checked++;
    }
    assert_true(checked > 1000);
    /* Everywhere else (poles, seam) still convex and finite. */
    for (size_t i = 0; i < mesh->num_vertices; i++) {
        assert_true(isfinite(mesh->curvature_max[i]) && isfinite(mesh->curvature_min[i]));
        assert_float_equal(mesh->curvature_min[i], 1.0f / radius, 0.15f / radius);
    }
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

static void test_plane_curvature_and_quadrics_are_zero(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *mesh = make_shape(ctx, (meso_shape_desc){.kind = MESO_SHAPE_PLANE, .segments = 8});
    assert_int_equal(meso_mesh_compute_curvature(ctx, mesh), MESO_OK);
    assert_int_equal(meso_mesh_compute_quadrics(ctx, mesh), MESO_OK);
    for (size_t i = 0; i < mesh->num_vertices; i++) {
        assert_float_equal(mesh->curvature_max[i], 0.0f, 1e-5f);
        assert_float_equal(mesh->curvature_min[i], 0.0f, 1e-5f);
        assert_float_equal(mesh->quadrics[i].x, 0.0f, 1e-5f);
        assert_float_equal(mesh->quadrics[i].y, 0.0f, 1e-5f);
    }
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

/* Torus (R = 1, r = 0.4): along the tube 1/r everywhere; around the axis cos(psi) / (R + r
 * cos(psi)): 1/(R + r) > 0 on the outer equator, -1/(R - r) < 0 on the inner one (a saddle). */
static void test_torus_curvature_signs_match_convexity(void **state) {
    meso_context *ctx = test_context(2);
    meso_mesh *mesh = make_shape(ctx, (meso_shape_desc){.kind = MESO_SHAPE_TORUS});
    assert_int_equal(meso_mesh_compute_curvature(ctx, mesh), MESO_OK);
    size_t outer = 0, inner = 0;
    for (size_t i = 0; i < mesh->num_vertices; i++) {
        meso_vec3 p = mesh->positions[i];
        if (fabsf(p.y) > 1e-3f) continue;
        float rho = hypotf(p.x, p.z);
        if (rho > 1.3f) { /* outer equator */
            assert_float_equal(mesh->curvature_max[i], 2.5f, 0.05f * 2.5f);
            assert_float_equal(mesh->curvature_min[i], 1.0f / 1.4f, 0.05f / 1.4f);
            /* The strongest bend runs around the tube: vertical here. */
            assert_true(fabsf(mesh->curvature_dir_max[i].y) > 0.99f);
            outer++;
        } else { /* inner equator */
            assert_float_equal(mesh->curvature_max[i], 2.5f, 0.05f * 2.5f);
            assert_float_equal(mesh->curvature_min[i], -1.0f / 0.6f, 0.05f / 0.6f);
            inner++;
        }
    }
    assert_true(outer >= 96 && inner >= 96);
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

static void test_sphere_quadrics_are_one_over_twice_the_radius(void **state) {
    meso_context *ctx = test_context(2);
    const float radius = 0.75f;
    meso_mesh *mesh = make_shape(ctx, (meso_shape_desc){.kind = MESO_SHAPE_SPHERE, .size = radius});
    assert_int_equal(meso_mesh_compute_quadrics(ctx, mesh), MESO_OK);
    float expected = 1.0f / (2.0f * radius);
    for (size_t i = 0; i < mesh->num_vertices; i++) {
        assert_true(isfinite(mesh->quadrics[i].x) && isfinite(mesh->quadrics[i].y));
        if (fabsf(mesh->positions[i].y) > 0.7f * radius) continue;
        assert_float_equal(mesh->quadrics[i].x, expected, 0.05f * expected);
        assert_float_equal(mesh->quadrics[i].y, expected, 0.05f * expected);
    }
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

/* Cylinder of radius r: bent around (x along T) with a = 1/(2r), straight along (b = 0). */
static void test_cylinder_quadrics_follow_the_tangent_frame(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *mesh = make_shape(ctx, (meso_shape_desc){.kind = MESO_SHAPE_CYLINDER, .size = 0.5f});
    assert_int_equal(meso_mesh_compute_quadrics(ctx, mesh), MESO_OK);
    for (size_t i = 0; i < mesh->num_vertices; i++) {
        assert_float_equal(mesh->quadrics[i].x, 1.0f, 0.05f);
        assert_float_equal(mesh->quadrics[i].y, 0.0f, 0.05f);
    }
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

static void test_quadrics_need_tangents(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *mesh = make_shape(ctx, (meso_shape_desc){.kind = MESO_SHAPE_PLANE});
    meso_mesh_scale_uvs(mesh, meso_vec2_make(2.0f, 2.0f)); /* frees the tangents */
    assert_null(mesh->tangents);
    assert_int_equal(meso_mesh_compute_quadrics(ctx, mesh), MESO_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(meso_context_last_error(ctx), "tangents"));
    assert_null(mesh->quadrics);
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

/* The teapot: finite everywhere (patch borders, the knob's top, the bottom's centre). */
static void test_teapot_curvature_and_quadrics_are_finite(void **state) {
    meso_context *ctx = test_context(2);
    meso_mesh *mesh = make_shape(ctx, (meso_shape_desc){.kind = MESO_SHAPE_TEAPOT, .segments = 8});
    assert_int_equal(meso_mesh_compute_curvature(ctx, mesh), MESO_OK);
    assert_int_equal(meso_mesh_compute_quadrics(ctx, mesh), MESO_OK);
    for (size_t i = 0; i < mesh->num_vertices; i++) {
        assert_true(isfinite(mesh->curvature_max[i]) && isfinite(mesh->curvature_min[i]));
        assert_true(meso_vec3_is_finite(mesh->curvature_dir_max[i]));
        assert_true(isfinite(mesh->quadrics[i].x) && isfinite(mesh->quadrics[i].y));
    }
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

/* Byte-identical results whatever the number of threads (CONTRIBUTING.md). */
static void test_derived_arrays_do_not_depend_on_thread_count(void **state) {
    meso_mesh *meshes[2];
    for (int k = 0; k < 2; k++) {
        meso_context *ctx = test_context(k == 0 ? 1 : 3);
        meshes[k] = make_shape(ctx, (meso_shape_desc){.kind = MESO_SHAPE_SPHERE, .segments = 200});
        assert_int_equal(meso_mesh_compute_curvature(ctx, meshes[k]), MESO_OK);
        assert_int_equal(meso_mesh_compute_quadrics(ctx, meshes[k]), MESO_OK);
        meso_context_destroy(ctx);
    }
    size_t nv = meshes[0]->num_vertices;
    assert_int_equal(nv, meshes[1]->num_vertices);
    assert_memory_equal(meshes[0]->tangents, meshes[1]->tangents, nv * sizeof(meso_vec3));
    assert_memory_equal(meshes[0]->bitangents, meshes[1]->bitangents, nv * sizeof(meso_vec3));
    assert_memory_equal(meshes[0]->curvature_max, meshes[1]->curvature_max, nv * sizeof(float));
    assert_memory_equal(meshes[0]->curvature_dir_min, meshes[1]->curvature_dir_min,
                        nv * sizeof(meso_vec3));
    assert_memory_equal(meshes[0]->quadrics, meshes[1]->quadrics, nv * sizeof(meso_vec2));
    meso_mesh_destroy(meshes[0]);
    meso_mesh_destroy(meshes[1]);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sphere_curvature_is_one_over_radius),
        cmocka_unit_test(test_plane_curvature_and_quadrics_are_zero),
        cmocka_unit_test(test_torus_curvature_signs_match_convexity),
        cmocka_unit_test(test_sphere_quadrics_are_one_over_twice_the_radius),
        cmocka_unit_test(test_cylinder_quadrics_follow_the_tangent_frame),
        cmocka_unit_test(test_quadrics_need_tangents),
        cmocka_unit_test(test_teapot_curvature_and_quadrics_are_finite),
        cmocka_unit_test(test_derived_arrays_do_not_depend_on_thread_count),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
