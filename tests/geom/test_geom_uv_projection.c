/* Projected texture coordinates (box, cylindrical, spherical, planar) and the detection of
 * degenerate ones. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geom_internal.h"
#include "test_util.h"

static meso_mesh *shape(meso_context *ctx, meso_shape_kind kind, int segments) {
    meso_shape_desc desc = {.kind = kind, .segments = segments};
    meso_mesh *mesh = NULL;
    assert_int_equal(meso_mesh_create_shape(ctx, &desc, &mesh), MESO_OK);
    return mesh;
}

/* A unit cube of 8 shared vertices (as an OBJ without vt gives it), no UVs. */
static meso_mesh *shared_cube(meso_context *ctx) {
    static const uint32_t faces[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7},
                                          {0, 1, 5}, {0, 5, 4}, {2, 3, 7}, {2, 7, 6},
                                          {1, 2, 6}, {1, 6, 5}, {0, 4, 7}, {0, 7, 3}};
    meso_mesh *mesh = NULL;
    assert_int_equal(meso_mesh_create(ctx, 8, 12, false, &mesh), MESO_OK);
    /* bottom square 0..3 (y = -0.5), top 4..7 above it */
    static const float corners[4][2] = {{-0.5f, 0.5f}, {0.5f, 0.5f}, {0.5f, -0.5f}, {-0.5f, -0.5f}};
    for (int v = 0; v < 8; v++) {
        meso_vec3 p = {corners[v & 3][0], v < 4 ? -0.5f : 0.5f, corners[v & 3][1]};
        mesh->positions[v] = p;
        mesh->normals[v] = meso_vec3_normalize(p);
    }
    memcpy(mesh->indices, faces, sizeof faces);
    /* Made counter-clockwise seen from outside, so the face normals point out. */
    for (size_t t = 0; t < mesh->num_triangles; t++) {
        const uint32_t *tri = mesh->indices + 3 * t;
        meso_vec3 a = mesh->positions[tri[0]];
        meso_vec3 face = meso_vec3_cross(meso_vec3_sub(mesh->positions[tri[1]], a),
                                         meso_vec3_sub(mesh->positions[tri[2]], a));
        if (meso_vec3_dot(face, a) < 0.0f) {
            uint32_t swap = mesh->indices[3 * t + 1];
            mesh->indices[3 * t + 1] = mesh->indices[3 * t + 2];
            mesh->indices[3 * t + 2] = swap;
        }
    }
    return mesh;
}

/* Project, then count the triangles left with degenerate coordinates (and their area). */
static size_t project_and_count_degenerate(meso_context *ctx, meso_mesh *mesh,
                                           meso_uv_projection projection, double *out_area) {
    assert_int_equal(meso_mesh_project_uvs(ctx, mesh, &projection), MESO_OK);
    size_t degenerate = 0;
    meso_mesh_degenerate_uvs(mesh, &degenerate, out_area);
    return degenerate;
}

/* Every triangle: UV area > 0, and T x B along the face normal (no chart mirrored). */
static void assert_unmirrored_charts(meso_context *ctx, meso_mesh *mesh) {
    assert_int_equal(meso_mesh_compute_tangents(ctx, mesh), MESO_OK);
    for (size_t t = 0; t < mesh->num_triangles; t++) {
        const uint32_t *tri = mesh->indices + 3 * t;
        meso_vec3 a = mesh->positions[tri[0]];
        meso_vec3 face = meso_vec3_cross(meso_vec3_sub(mesh->positions[tri[1]], a),
                                         meso_vec3_sub(mesh->positions[tri[2]], a));
        assert_false(geom_uv_jacobian_is_degenerate(mesh->uvs[tri[0]], mesh->uvs[tri[1]],
                                                    mesh->uvs[tri[2]]));
        for (int k = 0; k < 3; k++) {
            meso_vec3 tb = meso_vec3_cross(mesh->tangents[tri[k]], mesh->bitangents[tri[k]]);
            assert_true(meso_vec3_dot(tb, face) > 0.0f);
        }
    }
}

static void test_box_splits_a_shared_cube_into_six_charts(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *mesh = shared_cube(ctx);
    meso_uv_projection box = {MESO_UV_PROJECTION_BOX, 0.5f, 1};
    assert_int_equal(meso_mesh_project_uvs(ctx, mesh, &box), MESO_OK);
    /* Each corner in each of its three faces' charts: 24 vertices, even where two charts give
     * a corner the same coordinates (its frame must not average two charts). */
    assert_int_equal(mesh->num_vertices, 24);
    assert_int_equal(mesh->num_triangles, 12);
    /* One tile is 0.5 units: a face of side 1 spans 2 tiles along u and v. */
    for (size_t t = 0; t < mesh->num_triangles; t++) {
        float lo = INFINITY, hi = -INFINITY;
        for (int k = 0; k < 3; k++) {
            float u = mesh->uvs[mesh->indices[3 * t + k]].x;
            lo = fminf(lo, u), hi = fmaxf(hi, u);
        }
        assert_float_equal(hi - lo, 2.0f, 1e-6f);
    }
    assert_unmirrored_charts(ctx, mesh);
    assert_float_equal(meso_mesh_tile_length(mesh), 0.5f, 1e-5f);
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

static void test_box_on_a_sphere_is_unmirrored_everywhere(void **state) {
    meso_context *ctx = test_context(2);
    meso_mesh *mesh = shape(ctx, MESO_SHAPE_SPHERE, 32);
    free(mesh->uvs);
    mesh->uvs = NULL;
    meso_uv_projection box = {MESO_UV_PROJECTION_BOX, 0.25f, 1};
    assert_int_equal(meso_mesh_project_uvs(ctx, mesh, &box), MESO_OK);
    assert_unmirrored_charts(ctx, mesh);
    /* Box stretch is at most sqrt(3): the tile length lies between 0.25 and 0.25 sqrt(3). */
    float tile = meso_mesh_tile_length(mesh);
    assert_true(tile >= 0.25f && tile <= 0.25f * sqrtf(3.0f));
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

static void test_cylindrical_wraps_a_whole_number_of_tiles_and_unwraps_its_seam(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *mesh = shape(ctx, MESO_SHAPE_CYLINDER, 48); /* radius 0.6, height 1.2 */
    free(mesh->uvs);
    mesh->uvs = NULL;
    meso_uv_projection cylinder = {MESO_UV_PROJECTION_CYLINDRICAL, 0.5f, 1};
    assert_int_equal(meso_mesh_project_uvs(ctx, mesh, &cylinder), MESO_OK);
    /* 2 pi 0.6 / 0.5 = 7.5 tiles around at the facets' mean radius (a little under 0.6):
     * rounded to a whole number, 7 or 8, so the seam's two sides see the same heights. */
    float u_lo = INFINITY, u_hi = -INFINITY;
    for (size_t v = 0; v < mesh->num_vertices; v++) {
        u_lo = fminf(u_lo, mesh->uvs[v].x);
        u_hi = fmaxf(u_hi, mesh->uvs[v].x);
    }
    float around = u_hi - u_lo;
    assert_true(fabsf(around - roundf(around)) < 1e-4f);
    assert_true(roundf(around) == 7.0f || roundf(around) == 8.0f);
    /* No triangle spans the seam the long way: every one is a thin sliver in u. */
    for (size_t t = 0; t < mesh->num_triangles; t++) {
        const uint32_t *tri = mesh->indices + 3 * t;
        float lo = fminf(mesh->uvs[tri[0]].x, fminf(mesh->uvs[tri[1]].x, mesh->uvs[tri[2]].x));
        float hi = fmaxf(mesh->uvs[tri[0]].x, fmaxf(mesh->uvs[tri[1]].x, mesh->uvs[tri[2]].x));
        assert_true(hi - lo < 0.5f);
    }
    /* v along the axis, one unit a tile: the 1.2-high tube spans 2.4. */
    float v_lo = INFINITY, v_hi = -INFINITY;
    for (size_t v = 0; v < mesh->num_vertices; v++) {
        v_lo = fminf(v_lo, mesh->uvs[v].y);
        v_hi = fmaxf(v_hi, mesh->uvs[v].y);
    }
    assert_float_equal(v_hi - v_lo, 2.4f, 1e-4f);
    assert_unmirrored_charts(ctx, mesh);
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

static void test_spherical_gives_poles_their_neighbours_longitude(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *mesh = shape(ctx, MESO_SHAPE_SPHERE, 24);
    meso_uv_projection sphere = {MESO_UV_PROJECTION_SPHERICAL, 0.5f, 1};
    double area = 1.0;
    assert_int_equal(project_and_count_degenerate(ctx, mesh, sphere, &area), 0);
    assert_true(area == 0.0);
    assert_unmirrored_charts(ctx, mesh);
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

static void test_planar_leaves_faces_along_its_axis_degenerate(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *mesh = shared_cube(ctx);
    meso_uv_projection planar = {MESO_UV_PROJECTION_PLANAR, 1.0f, 1};
    double area = 0.0;
    /* Seen along y, the four sides are edge-on: 8 of 12 triangles, 2/3 of the area. */
    assert_int_equal(project_and_count_degenerate(ctx, mesh, planar, &area), 8);
    assert_true(fabs(area - 2.0 / 3.0) < 1e-9);
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

static void test_one_shared_coordinate_is_degenerate_everywhere(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *mesh = shape(ctx, MESO_SHAPE_TORUS, 24);
    size_t degenerate = 1;
    double area = 1.0;
    meso_mesh_degenerate_uvs(mesh, &degenerate, &area);
    assert_int_equal(degenerate, 0);
    assert_true(area == 0.0);
    /* WusonOBJ.obj's case: every vertex at one "vt". */
    for (size_t v = 0; v < mesh->num_vertices; v++) mesh->uvs[v] = (meso_vec2){0.25f, 0.75f};
    meso_mesh_degenerate_uvs(mesh, &degenerate, &area);
    assert_int_equal(degenerate, mesh->num_triangles);
    assert_true(fabs(area - 1.0) < 1e-12);
    assert_true(area > MESO_MESH_MOSTLY_DEGENERATE_UVS);
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

static void test_projection_is_deterministic_and_refuses_bad_arguments(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *a = shape(ctx, MESO_SHAPE_TEAPOT, 6);
    meso_mesh *b = shape(ctx, MESO_SHAPE_TEAPOT, 6);
    meso_uv_projection box = {MESO_UV_PROJECTION_BOX, 0.3f, 1};
    assert_int_equal(meso_mesh_project_uvs(ctx, a, &box), MESO_OK);
    assert_int_equal(meso_mesh_project_uvs(ctx, b, &box), MESO_OK);
    assert_int_equal(a->num_vertices, b->num_vertices);
    assert_memory_equal(a->uvs, b->uvs, a->num_vertices * sizeof(meso_vec2));
    assert_memory_equal(a->indices, b->indices, 3 * a->num_triangles * sizeof(uint32_t));
    meso_uv_projection bad[] = {{MESO_UV_PROJECTION_NONE, 1.0f, 1},
                                {MESO_UV_PROJECTION_BOX, 0.0f, 1},
                                {MESO_UV_PROJECTION_PLANAR, NAN, 1},
                                {MESO_UV_PROJECTION_CYLINDRICAL, 1.0f, 3}};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
        assert_int_equal(meso_mesh_project_uvs(ctx, a, &bad[i]), MESO_ERROR_INVALID_ARGUMENT);
    meso_uv_projection_kind kind;
    assert_true(meso_uv_projection_kind_from_name("cylindrical", &kind));
    assert_int_equal(kind, MESO_UV_PROJECTION_CYLINDRICAL);
    assert_false(meso_uv_projection_kind_from_name("triplanar", &kind));
    assert_string_equal(meso_uv_projection_kind_name(MESO_UV_PROJECTION_SPHERICAL), "spherical");
    meso_mesh_destroy(a);
    meso_mesh_destroy(b);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_box_splits_a_shared_cube_into_six_charts),
        cmocka_unit_test(test_box_on_a_sphere_is_unmirrored_everywhere),
        cmocka_unit_test(test_cylindrical_wraps_a_whole_number_of_tiles_and_unwraps_its_seam),
        cmocka_unit_test(test_spherical_gives_poles_their_neighbours_longitude),
        cmocka_unit_test(test_planar_leaves_faces_along_its_axis_degenerate),
        cmocka_unit_test(test_one_shared_coordinate_is_degenerate_everywhere),
        cmocka_unit_test(test_projection_is_deterministic_and_refuses_bad_arguments),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
