/* Mesh operations: create, clone, transform, UV scaling, validation, tangent frames. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"

/* Two triangles sharing an edge, in y = 0, normal +y; UVs as given. */
static meso_mesh *make_quad(meso_context *ctx, const meso_vec2 uvs[4]) {
    meso_mesh *mesh = NULL;
    assert_int_equal(meso_mesh_create(ctx, 4, 2, uvs != NULL, &mesh), MESO_OK);
    const meso_vec3 p[4] = {{0, 0, 1}, {1, 0, 1}, {1, 0, 0}, {0, 0, 0}};
    const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    for (int i = 0; i < 4; i++) {
        mesh->positions[i] = p[i];
        mesh->normals[i] = meso_vec3_make(0, 1, 0);
        if (uvs) mesh->uvs[i] = uvs[i];
    }
    memcpy(mesh->indices, idx, sizeof(idx));
    return mesh;
}

static const meso_vec2 quad_uvs[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};

static void test_create_allocates_the_required_arrays_only(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *mesh = NULL;
    assert_int_equal(meso_mesh_create(ctx, 5, 3, false, &mesh), MESO_OK);
    assert_non_null(mesh->positions);
    assert_non_null(mesh->normals);
    assert_non_null(mesh->indices);
    assert_null(mesh->uvs);
    assert_null(mesh->tangents);
    assert_null(mesh->curvature_max);
    assert_null(mesh->quadrics);
    assert_int_equal(mesh->indices[8], 0);
    meso_mesh_destroy(mesh);
    meso_mesh_destroy(NULL);
    meso_context_destroy(ctx);
}

static void test_clone_is_deep(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *mesh = make_quad(ctx, quad_uvs);
    assert_int_equal(meso_mesh_compute_tangents(ctx, mesh), MESO_OK);
    assert_int_equal(meso_mesh_compute_curvature(ctx, mesh), MESO_OK);
    meso_mesh *copy = NULL;
    assert_int_equal(meso_mesh_clone(ctx, mesh, &copy), MESO_OK);
    assert_ptr_not_equal(copy->positions, mesh->positions);
    assert_memory_equal(copy->tangents, mesh->tangents, 4 * sizeof(meso_vec3));
    assert_memory_equal(copy->indices, mesh->indices, 6 * sizeof(uint32_t));
    assert_non_null(copy->curvature_dir_min);
    assert_null(copy->quadrics);
    copy->positions[0].x = 42.0f;
    assert_float_equal(mesh->positions[0].x, 0.0f, 0.0f);
    meso_mesh_destroy(copy);
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

static void test_transform_moves_normals_by_the_normal_matrix(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *mesh = NULL;
    meso_shape_desc desc = {.kind = MESO_SHAPE_SPHERE, .segments = 16};
    assert_int_equal(meso_mesh_create_shape(ctx, &desc, &mesh), MESO_OK);
    assert_int_equal(meso_mesh_compute_curvature(ctx, mesh), MESO_OK);
    /* Non-uniform scale (an ellipsoid) then a translation. */
    meso_mat4 scale = meso_mat4_identity();
    scale.m[0] = 2.0f;
    meso_mat4 transform = meso_mat4_mul(meso_mat4_translate(meso_vec3_make(0, 3, 0)), scale);
    meso_mesh_transform(mesh, transform);
    assert_null(mesh->tangents);
    assert_null(mesh->curvature_max);
    for (size_t i = 0; i < mesh->num_vertices; i++) {
        meso_vec3 p = mesh->positions[i], n = mesh->normals[i];
        /* Ellipsoid (x/2)^2 + (y-3)^2 + z^2 = 1: the normal is along (x/4, y-3, z). */
        meso_vec3 expected = meso_vec3_normalize(meso_vec3_make(p.x / 4.0f, p.y - 3.0f, p.z));
        assert_float_equal(meso_vec3_length(n), 1.0f, 1e-5f);
        assert_true(meso_vec3_dot(n, expected) > 0.9999f);
    }
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

static void test_mirroring_transform_keeps_triangles_counter_clockwise(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *mesh = make_quad(ctx, quad_uvs);
    meso_mat4 mirror = meso_mat4_identity();
    mirror.m[0] = -1.0f;
    meso_mesh_transform(mesh, mirror);
    for (size_t f = 0; f < mesh->num_triangles; f++) {
        const uint32_t *tri = mesh->indices + 3 * f;
        meso_vec3 p0 = mesh->positions[tri[0]];
        meso_vec3 face = meso_vec3_cross(meso_vec3_sub(mesh->positions[tri[1]], p0),
                                         meso_vec3_sub(mesh->positions[tri[2]], p0));
        assert_true(meso_vec3_dot(face, mesh->normals[tri[0]]) > 0.0f);
    }
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

static void test_scale_uvs_scales_and_frees_derived_arrays(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *mesh = make_quad(ctx, quad_uvs);
    assert_int_equal(meso_mesh_compute_tangents(ctx, mesh), MESO_OK);
    assert_float_equal(meso_vec3_length(mesh->tangents[0]), 1.0f, 1e-6f);
    meso_mesh_scale_uvs(mesh, meso_vec2_make(4.0f, 2.0f));
    assert_null(mesh->tangents);
    assert_float_equal(mesh->uvs[2].x, 4.0f, 0.0f);
    assert_float_equal(mesh->uvs[2].y, 2.0f, 0.0f);
    assert_int_equal(meso_mesh_compute_tangents(ctx, mesh), MESO_OK);
    /* dP/du shrinks as u repeats faster. */
    assert_float_equal(meso_vec3_length(mesh->tangents[0]), 0.25f, 1e-6f);
    assert_float_equal(meso_vec3_length(mesh->bitangents[0]), 0.5f, 1e-6f);
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

static void test_validate_names_the_vertex_that_is_not_finite(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *mesh = make_quad(ctx, quad_uvs);
    mesh->positions[2].y = INFINITY;
    assert_int_equal(meso_mesh_validate(ctx, mesh, "rock.obj", true), MESO_ERROR_FORMAT);
    assert_string_equal(meso_context_last_error(ctx), "rock.obj: vertex 2: position is not finite");
    mesh->positions[2].y = 0.0f;
    mesh->normals[1].x = NAN;
    assert_int_equal(meso_mesh_validate(ctx, mesh, "rock.obj", true), MESO_ERROR_FORMAT);
    assert_string_equal(meso_context_last_error(ctx), "rock.obj: vertex 1: normal is not finite");
    mesh->normals[1].x = 0.0f;
    mesh->uvs[3].y = NAN;
    assert_int_equal(meso_mesh_validate(ctx, mesh, "rock.obj", true), MESO_ERROR_FORMAT);
    assert_non_null(strstr(meso_context_last_error(ctx), "rock.obj: vertex 3: texture"));
    mesh->uvs[3].y = 1.0f;
    mesh->indices[4] = 4;
    assert_int_equal(meso_mesh_validate(ctx, mesh, "rock.obj", true), MESO_ERROR_FORMAT);
    assert_non_null(strstr(meso_context_last_error(ctx), "rock.obj: triangle 1"));
    mesh->indices[4] = 2;
    assert_int_equal(meso_mesh_validate(ctx, mesh, "rock.obj", true), MESO_OK);
    assert_int_equal(mesh->num_triangles, 2);
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

static void test_validate_drops_degenerate_triangles_and_refuses_an_empty_mesh(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *mesh = make_quad(ctx, quad_uvs);
    mesh->indices[1] = mesh->indices[0]; /* first triangle: a repeated corner */
    assert_int_equal(meso_mesh_validate(ctx, mesh, "quad", false), MESO_OK);
    assert_int_equal(mesh->num_triangles, 1);
    assert_int_equal(mesh->indices[0], 0);
    assert_int_equal(mesh->indices[1], 2);
    assert_int_equal(mesh->indices[2], 3);
    assert_string_equal(test_last_warning(), "quad: dropped 1 degenerate triangles");
    mesh->positions[2] = mesh->positions[3]; /* the last one collapses too */
    assert_int_equal(meso_mesh_validate(ctx, mesh, "quad", false), MESO_ERROR_FORMAT);
    assert_non_null(strstr(meso_context_last_error(ctx), "quad: has no triangles"));
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

/* Mirrored UVs (u runs the other way): T flips, B does not, so T x B points against N. */
static void test_mirrored_uvs_keep_their_sign(void **state) {
    meso_context *ctx = test_context(1);
    const meso_vec2 mirrored[4] = {{1, 0}, {0, 0}, {0, 1}, {1, 1}};
    meso_mesh *mesh = make_quad(ctx, mirrored);
    assert_int_equal(meso_mesh_compute_tangents(ctx, mesh), MESO_OK);
    for (size_t i = 0; i < 4; i++) {
        assert_float_equal(mesh->tangents[i].x, -1.0f, 1e-6f);
        assert_float_equal(mesh->bitangents[i].z, -1.0f, 1e-6f);
        assert_true(meso_vec3_dot(meso_vec3_cross(mesh->tangents[i], mesh->bitangents[i]),
                                  mesh->normals[i]) < 0.0f);
    }
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

/* Tangents keep magnitudes and lose the normal component (Gram-Schmidt). */
static void test_tangents_are_orthogonalised_against_the_vertex_normal(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *mesh = make_quad(ctx, quad_uvs);
    meso_vec3 tilted = meso_vec3_normalize(meso_vec3_make(0.3f, 1.0f, 0.0f));
    for (int i = 0; i < 4; i++) mesh->normals[i] = tilted;
    assert_int_equal(meso_mesh_compute_tangents(ctx, mesh), MESO_OK);
    for (int i = 0; i < 4; i++) {
        assert_float_equal(meso_vec3_dot(mesh->tangents[i], tilted), 0.0f, 1e-6f);
        /* (1,0,0) minus its component along the tilted normal. */
        float expected = sqrtf(1.0f - tilted.x * tilted.x);
        assert_float_equal(meso_vec3_length(mesh->tangents[i]), expected, 1e-5f);
        assert_float_equal(meso_vec3_length(mesh->bitangents[i]), 1.0f, 1e-5f);
    }
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

/* A vertex whose triangles all have degenerate UVs still gets a unit frame orthogonal to N. */
static void test_vertex_without_uv_gradient_gets_an_orthonormal_frame(void **state) {
    meso_context *ctx = test_context(1);
    const meso_vec2 flat[4] = {{0.5f, 0.5f}, {0.5f, 0.5f}, {0.5f, 0.5f}, {0.5f, 0.5f}};
    meso_mesh *mesh = make_quad(ctx, flat);
    assert_int_equal(meso_mesh_compute_tangents(ctx, mesh), MESO_OK);
    for (int i = 0; i < 4; i++) {
        meso_vec3 t = mesh->tangents[i], b = mesh->bitangents[i], n = mesh->normals[i];
        assert_float_equal(meso_vec3_length(t), 1.0f, 1e-6f);
        assert_float_equal(meso_vec3_length(b), 1.0f, 1e-6f);
        assert_float_equal(meso_vec3_dot(t, n), 0.0f, 1e-6f);
        assert_float_equal(meso_vec3_dot(t, b), 0.0f, 1e-6f);
        assert_true(meso_vec3_dot(meso_vec3_cross(t, b), n) > 0.99f);
    }
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

/* Curvature from normals averaged over faces (what importers give), not analytic ones. */
static void test_curvature_from_averaged_normals_is_close_on_a_sphere(void **state) {
    meso_context *ctx = test_context(2);
    meso_mesh *mesh = NULL;
    meso_shape_desc desc = {.kind = MESO_SHAPE_SPHERE, .size = 2.0f, .segments = 64};
    assert_int_equal(meso_mesh_create_shape(ctx, &desc, &mesh), MESO_OK);
    memset(mesh->normals, 0, mesh->num_vertices * sizeof(meso_vec3));
    assert_int_equal(meso_mesh_validate(ctx, mesh, "sphere", true), MESO_OK); /* rebuilds them */
    assert_int_equal(meso_mesh_compute_curvature(ctx, mesh), MESO_OK);
    for (size_t i = 0; i < mesh->num_vertices; i++) {
        if (fabsf(mesh->positions[i].y) > 1.4f) continue;
        assert_true(meso_vec3_dot(mesh->normals[i], meso_vec3_scale(mesh->positions[i], 0.5f)) >
                    0.99f);
        assert_float_equal(mesh->curvature_max[i], 0.5f, 0.05f * 0.5f);
        assert_float_equal(mesh->curvature_min[i], 0.5f, 0.05f * 0.5f);
    }
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_create_allocates_the_required_arrays_only),
        cmocka_unit_test(test_clone_is_deep),
        cmocka_unit_test(test_transform_moves_normals_by_the_normal_matrix),
        cmocka_unit_test(test_mirroring_transform_keeps_triangles_counter_clockwise),
        cmocka_unit_test(test_scale_uvs_scales_and_frees_derived_arrays),
        cmocka_unit_test(test_validate_names_the_vertex_that_is_not_finite),
        cmocka_unit_test(test_validate_drops_degenerate_triangles_and_refuses_an_empty_mesh),
        cmocka_unit_test(test_mirrored_uvs_keep_their_sign),
        cmocka_unit_test(test_tangents_are_orthogonalised_against_the_vertex_normal),
        cmocka_unit_test(test_vertex_without_uv_gradient_gets_an_orthonormal_frame),
        cmocka_unit_test(test_curvature_from_averaged_normals_is_close_on_a_sphere),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
