/* Built-in shapes: defaults, names, validity, orientation, closure, UVs and tangent frames. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"

static const meso_shape_kind all_kinds[] = {MESO_SHAPE_PLANE, MESO_SHAPE_SPHERE,
                                            MESO_SHAPE_TORUS, MESO_SHAPE_CYLINDER,
                                            MESO_SHAPE_VASE,  MESO_SHAPE_TEAPOT};
#define NUM_KINDS (sizeof(all_kinds) / sizeof(all_kinds[0]))

static meso_mesh *make_shape(meso_context *ctx, meso_shape_kind kind, int segments) {
    meso_mesh *mesh = NULL;
    meso_shape_desc desc = {.kind = kind, .segments = segments};
    assert_int_equal(meso_mesh_create_shape(ctx, &desc, &mesh), MESO_OK);
    assert_non_null(mesh);
    return mesh;
}

static void test_shape_defaults_follow_the_header(void **state) {
    meso_shape_desc d = meso_shape_desc_defaults(&(meso_shape_desc){0});
    assert_int_equal(d.kind, MESO_SHAPE_PLANE);
    assert_float_equal(d.size, 2.0f, 0.0f);
    assert_int_equal(d.segments, 1);
    d = meso_shape_desc_defaults(&(meso_shape_desc){.kind = MESO_SHAPE_SPHERE});
    assert_float_equal(d.size, 1.0f, 0.0f);
    assert_int_equal(d.segments, 96);
    d = meso_shape_desc_defaults(&(meso_shape_desc){.kind = MESO_SHAPE_TORUS, .size = 2.0f});
    assert_float_equal(d.size, 2.0f, 0.0f);
    assert_float_equal(d.minor_radius, 0.8f, 1e-6f);
    d = meso_shape_desc_defaults(&(meso_shape_desc){.kind = MESO_SHAPE_CYLINDER});
    assert_float_equal(d.size, 0.6f, 1e-6f);
    assert_float_equal(d.height, 1.2f, 1e-6f);
    d = meso_shape_desc_defaults(&(meso_shape_desc){.kind = MESO_SHAPE_VASE});
    assert_float_equal(d.size, 2.0f, 0.0f);
    d = meso_shape_desc_defaults(&(meso_shape_desc){.kind = MESO_SHAPE_TEAPOT, .segments = 5});
    assert_float_equal(d.size, 1.5f, 0.0f);
    assert_int_equal(d.segments, 5);
}

static void test_shape_names_round_trip(void **state) {
    for (size_t k = 0; k < NUM_KINDS; k++) {
        meso_shape_kind kind = MESO_SHAPE_DEFAULT;
        assert_true(meso_shape_kind_from_name(meso_shape_kind_name(all_kinds[k]), &kind));
        assert_int_equal(kind, all_kinds[k]);
    }
    meso_shape_kind kind = MESO_SHAPE_SPHERE;
    assert_false(meso_shape_kind_from_name("cube", &kind));
    assert_int_equal(kind, MESO_SHAPE_SPHERE);
    assert_string_equal(meso_shape_kind_name(MESO_SHAPE_DEFAULT), "plane");
}

static void test_shape_bad_desc_names_the_field(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *mesh = (meso_mesh *)1;
    meso_shape_desc desc = {.kind = MESO_SHAPE_SPHERE, .size = -1.0f};
    assert_int_equal(meso_mesh_create_shape(ctx, &desc, &mesh), MESO_ERROR_INVALID_ARGUMENT);
    assert_null(mesh);
    assert_non_null(strstr(meso_context_last_error(ctx), "sphere: size"));
    desc = (meso_shape_desc){.kind = MESO_SHAPE_TORUS, .size = 1.0f, .minor_radius = 1.5f};
    assert_int_equal(meso_mesh_create_shape(ctx, &desc, &mesh), MESO_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(meso_context_last_error(ctx), "torus: minor_radius"));
    desc = (meso_shape_desc){.kind = MESO_SHAPE_CYLINDER, .segments = 2};
    assert_int_equal(meso_mesh_create_shape(ctx, &desc, &mesh), MESO_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(meso_context_last_error(ctx), "cylinder: segments"));
    desc = (meso_shape_desc){.kind = MESO_SHAPE_TEAPOT, .segments = 100000};
    assert_int_equal(meso_mesh_create_shape(ctx, &desc, &mesh), MESO_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(meso_context_last_error(ctx), "teapot: segments"));
    desc = (meso_shape_desc){.kind = (meso_shape_kind)42};
    assert_int_equal(meso_mesh_create_shape(ctx, &desc, &mesh), MESO_ERROR_INVALID_ARGUMENT);
    meso_context_destroy(ctx);
}

/* Every shape: validates without dropping anything, finite data, unit normals, UVs in [0,1],
 * triangles wound counter-clockwise around their vertex normals, tangent frames orthogonal to
 * N with T x B along N. */
static void test_every_shape_is_valid_with_consistent_frames(void **state) {
    meso_context *ctx = test_context(2);
    for (size_t k = 0; k < NUM_KINDS; k++) {
        meso_mesh *mesh = make_shape(ctx, all_kinds[k], 0);
        const char *name = meso_shape_kind_name(all_kinds[k]);
        size_t triangles = mesh->num_triangles;
        assert_int_equal(meso_mesh_validate(ctx, mesh, name, true), MESO_OK);
        if (mesh->num_triangles != triangles) fail_msg("%s: dropped triangles", name);
        assert_non_null(mesh->uvs);
        assert_non_null(mesh->tangents);
        assert_non_null(mesh->bitangents);
        for (size_t i = 0; i < mesh->num_vertices; i++) {
            meso_vec3 n = mesh->normals[i], t = mesh->tangents[i], b = mesh->bitangents[i];
            meso_vec2 uv = mesh->uvs[i];
            if (fabsf(meso_vec3_length(n) - 1.0f) > 1e-4f)
                fail_msg("%s: normal %zu not unit", name, i);
            if (!(uv.x >= 0.0f && uv.x <= 1.0f && uv.y >= 0.0f && uv.y <= 1.0f))
                fail_msg("%s: uv %zu = (%g, %g) out of [0,1]", name, i, uv.x, uv.y);
            float lt = meso_vec3_length(t), lb = meso_vec3_length(b);
            if (!(lt > 0.0f && lb > 0.0f) || !meso_vec3_is_finite(t) || !meso_vec3_is_finite(b))
                fail_msg("%s: vertex %zu: tangent frame degenerate", name, i);
            if (fabsf(meso_vec3_dot(t, n)) > 1e-3f * lt || fabsf(meso_vec3_dot(b, n)) > 1e-3f * lb)
                fail_msg("%s: vertex %zu: tangents not orthogonal to N", name, i);
            if (meso_vec3_dot(meso_vec3_cross(t, b), n) <= 0.0f)
                fail_msg("%s: vertex %zu: T x B points against N", name, i);
        }
        for (size_t f = 0; f < mesh->num_triangles; f++) {
            const uint32_t *tri = mesh->indices + 3 * f;
            meso_vec3 p0 = mesh->positions[tri[0]];
            meso_vec3 face = meso_vec3_cross(meso_vec3_sub(mesh->positions[tri[1]], p0),
                                             meso_vec3_sub(mesh->positions[tri[2]], p0));
            meso_vec3 n = meso_vec3_add(meso_vec3_add(mesh->normals[tri[0]], mesh->normals[tri[1]]),
                                        mesh->normals[tri[2]]);
            if (meso_vec3_dot(face, n) <= 0.0f)
                fail_msg("%s: triangle %zu is wound against its normals", name, f);
        }
        meso_mesh_destroy(mesh);
    }
    meso_context_destroy(ctx);
}

/* The closed part of every shape encloses positive volume: normals and winding point out. */
static void test_every_shape_faces_outward(void **state) {
    meso_context *ctx = test_context(1);
    for (size_t k = 1; k < NUM_KINDS; k++) {
        meso_mesh *mesh = make_shape(ctx, all_kinds[k], 0);
        double volume = 0.0;
        for (size_t f = 0; f < mesh->num_triangles; f++) {
            const uint32_t *tri = mesh->indices + 3 * f;
            meso_vec3 a = mesh->positions[tri[0]], b = mesh->positions[tri[1]],
                      c = mesh->positions[tri[2]];
            volume += meso_vec3_dot(a, meso_vec3_cross(b, c)) / 6.0;
        }
        if (!(volume > 0.0))
            fail_msg("%s: signed volume %g", meso_shape_kind_name(all_kinds[k]), volume);
        meso_mesh_destroy(mesh);
    }
    meso_context_destroy(ctx);
}

static void test_round_shape_normals_point_away_from_the_axis(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *sphere = make_shape(ctx, MESO_SHAPE_SPHERE, 0);
    for (size_t i = 0; i < sphere->num_vertices; i++) {
        meso_vec3 p = sphere->positions[i];
        assert_float_equal(meso_vec3_length(p), 1.0f, 1e-5f);
        assert_true(meso_vec3_dot(sphere->normals[i], p) > 0.999f);
    }
    meso_mesh *torus = make_shape(ctx, MESO_SHAPE_TORUS, 0);
    for (size_t i = 0; i < torus->num_vertices; i++) {
        meso_vec3 p = torus->positions[i];
        float r = hypotf(p.x, p.z);
        meso_vec3 centre = meso_vec3_make(p.x / r, 0.0f, p.z / r); /* on the major circle */
        meso_vec3 d = meso_vec3_sub(p, centre);
        assert_float_equal(meso_vec3_length(d), 0.4f, 1e-5f);
        assert_true(meso_vec3_dot(torus->normals[i], meso_vec3_normalize(d)) > 0.999f);
    }
    meso_mesh *cylinder = make_shape(ctx, MESO_SHAPE_CYLINDER, 0);
    for (size_t i = 0; i < cylinder->num_vertices; i++) {
        meso_vec3 p = cylinder->positions[i], n = cylinder->normals[i];
        assert_float_equal(hypotf(p.x, p.z), 0.6f, 1e-5f);
        assert_true(p.x * n.x + p.z * n.z > 0.59f);
        assert_true(fabsf(p.y) <= 0.6f + 1e-6f);
    }
    meso_mesh_destroy(sphere);
    meso_mesh_destroy(torus);
    meso_mesh_destroy(cylinder);
    meso_context_destroy(ctx);
}

/* ---- Closure by position ------------------------------------------------------------------ */

typedef struct edge_key {
    float a[3], b[3];
    int direction; /* +1 when stored as given, -1 when swapped */
} edge_key;

static int compare_points(const float *a, const float *b) {
    for (int k = 0; k < 3; k++)
        if (a[k] != b[k]) return a[k] < b[k] ? -1 : 1;
    return 0;
}

static int compare_edges(const void *pa, const void *pb) {
    const edge_key *a = pa, *b = pb;
    int c = compare_points(a->a, b->a);
    return c ? c : compare_points(a->b, b->b);
}

/* Counts edges (by position) used once (boundary) and edges used other than exactly twice in
 * opposite directions (bad). */
static void count_edges(const meso_mesh *mesh, size_t *out_boundary, size_t *out_bad) {
    size_t n = 3 * mesh->num_triangles;
    edge_key *edges = malloc(n * sizeof(edge_key));
    assert_non_null(edges);
    for (size_t f = 0; f < mesh->num_triangles; f++)
        for (int k = 0; k < 3; k++) {
            meso_vec3 p = mesh->positions[mesh->indices[3 * f + k]];
            meso_vec3 q = mesh->positions[mesh->indices[3 * f + (k + 1) % 3]];
            float pa[3] = {p.x + 0.0f, p.y + 0.0f, p.z + 0.0f},
                  qa[3] = {q.x + 0.0f, q.y + 0.0f, q.z + 0.0f};
            edge_key *e = &edges[3 * f + k];
            bool swap = compare_points(pa, qa) > 0;
            memcpy(e->a, swap ? qa : pa, sizeof(pa));
            memcpy(e->b, swap ? pa : qa, sizeof(qa));
            e->direction = swap ? -1 : 1;
        }
    qsort(edges, n, sizeof(edge_key), compare_edges);
    size_t boundary = 0, bad = 0;
    for (size_t i = 0; i < n;) {
        size_t j = i;
        int sum = 0;
        while (j < n && compare_edges(&edges[i], &edges[j]) == 0) sum += edges[j++].direction;
        if (j - i == 1)
            boundary++;
        else if (j - i != 2 || sum != 0)
            bad++;
        i = j;
    }
    free(edges);
    *out_boundary = boundary;
    *out_bad = bad;
}

static void test_closed_shapes_are_watertight_by_position(void **state) {
    meso_context *ctx = test_context(1);
    const meso_shape_kind closed[] = {MESO_SHAPE_SPHERE, MESO_SHAPE_TORUS};
    for (size_t k = 0; k < 2; k++) {
        for (int segments = 7; segments <= 96; segments += 89) {
            meso_mesh *mesh = make_shape(ctx, closed[k], segments);
            size_t boundary, bad;
            count_edges(mesh, &boundary, &bad);
            assert_int_equal(boundary, 0);
            assert_int_equal(bad, 0);
            meso_mesh_destroy(mesh);
        }
    }
    /* Open shapes are open only where they should be: the rims. */
    meso_mesh *cylinder = make_shape(ctx, MESO_SHAPE_CYLINDER, 24);
    size_t boundary, bad;
    count_edges(cylinder, &boundary, &bad);
    assert_int_equal(boundary, 2 * 24);
    assert_int_equal(bad, 0);
    meso_mesh *vase = make_shape(ctx, MESO_SHAPE_VASE, 24);
    count_edges(vase, &boundary, &bad);
    assert_int_equal(boundary, 24);
    assert_int_equal(bad, 0);
    meso_mesh_destroy(cylinder);
    meso_mesh_destroy(vase);
    meso_context_destroy(ctx);
}

/* Newell's patches leave open only the rim's inner edge, the lid's outer edge and the four
 * ends of handle and spout (4 loops of 4 patch edges, 4 loops of 2): 16 patch edges. Any
 * crack between patches would show as more boundary edges. */
static void test_teapot_patches_meet_without_cracks(void **state) {
    meso_context *ctx = test_context(1);
    for (int segments = 3; segments <= 16; segments += 13) {
        meso_mesh *mesh = make_shape(ctx, MESO_SHAPE_TEAPOT, segments);
        size_t boundary, bad;
        count_edges(mesh, &boundary, &bad);
        assert_int_equal(boundary, 16 * (size_t)segments);
        assert_int_equal(bad, 0);
        meso_mesh_destroy(mesh);
    }
    meso_context_destroy(ctx);
}

static void test_teapot_height_is_size_and_box_is_centred(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *mesh = NULL;
    meso_shape_desc desc = {.kind = MESO_SHAPE_TEAPOT, .size = 3.0f, .segments = 12};
    assert_int_equal(meso_mesh_create_shape(ctx, &desc, &mesh), MESO_OK);
    meso_vec3 lo, hi;
    meso_mesh_bounds(mesh, &lo, &hi);
    assert_float_equal(hi.y - lo.y, 3.0f, 1e-3f);
    assert_float_equal(hi.y + lo.y, 0.0f, 1e-3f);
    assert_float_equal(hi.x + lo.x, 0.0f, 2e-2f);
    assert_float_equal(hi.z + lo.z, 0.0f, 1e-3f);
    /* The spout points toward +x, the handle toward -x, both narrower than the body. */
    assert_true(hi.x > 1.3f * hi.z);
    for (size_t i = 0; i < mesh->num_vertices; i++)
        assert_true(meso_vec3_is_finite(mesh->normals[i]));
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

static void test_plane_matches_the_design_parametrisation(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *mesh = NULL;
    meso_shape_desc desc = {.kind = MESO_SHAPE_PLANE, .size = 4.0f, .segments = 3};
    assert_int_equal(meso_mesh_create_shape(ctx, &desc, &mesh), MESO_OK);
    assert_int_equal(mesh->num_vertices, 16);
    assert_int_equal(mesh->num_triangles, 18);
    for (size_t i = 0; i < mesh->num_vertices; i++) {
        meso_vec2 uv = mesh->uvs[i];
        meso_vec3 p = mesh->positions[i];
        assert_float_equal(p.x, -2.0f + 4.0f * uv.x, 1e-6f);
        assert_float_equal(p.y, 0.0f, 0.0f);
        assert_float_equal(p.z, 2.0f - 4.0f * uv.y, 1e-6f);
        assert_float_equal(mesh->normals[i].y, 1.0f, 0.0f);
        /* T = dP/du = (s, 0, 0), B = dP/dv = (0, 0, -s). */
        assert_float_equal(mesh->tangents[i].x, 4.0f, 1e-5f);
        assert_float_equal(mesh->bitangents[i].z, -4.0f, 1e-5f);
        assert_float_equal(mesh->tangents[i].z, 0.0f, 1e-5f);
        assert_float_equal(mesh->bitangents[i].x, 0.0f, 1e-5f);
    }
    for (size_t f = 0; f < mesh->num_triangles; f++) {
        const uint32_t *tri = mesh->indices + 3 * f;
        meso_vec3 p0 = mesh->positions[tri[0]];
        meso_vec3 face = meso_vec3_cross(meso_vec3_sub(mesh->positions[tri[1]], p0),
                                         meso_vec3_sub(mesh->positions[tri[2]], p0));
        assert_true(face.y > 0.0f); /* counter-clockwise seen from +y */
    }
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

/* Sphere UVs: u = longitude, v from the south pole (0) to the north (1); the equator's tangent
 * spans 2 pi R per unit u and pi R per unit v, so uv_scale [4, 2] gives square tiles. */
static void test_sphere_uvs_follow_longitude_and_latitude(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *mesh = make_shape(ctx, MESO_SHAPE_SPHERE, 64);
    for (size_t i = 0; i < mesh->num_vertices; i++) {
        meso_vec3 p = mesh->positions[i];
        meso_vec2 uv = mesh->uvs[i];
        assert_float_equal(p.y, -cosf(MESO_PI * uv.y), 1e-5f);
        if (fabsf(p.y) < 0.01f) {
            assert_float_equal(meso_vec3_length(mesh->tangents[i]), 2.0f * MESO_PI, 0.06f);
            assert_float_equal(meso_vec3_length(mesh->bitangents[i]), MESO_PI, 0.03f);
            assert_true(mesh->bitangents[i].y > 0.0f);
        }
        if (fabsf(uv.x - 0.5f) < 1e-6f && fabsf(uv.y - 0.5f) < 1e-6f) {
            /* u = 1/2 faces the default camera (+z); the seam is at the back. */
            assert_float_equal(p.z, 1.0f, 1e-5f);
            assert_true(mesh->tangents[i].x > 0.0f);
        }
    }
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_shape_defaults_follow_the_header),
        cmocka_unit_test(test_shape_names_round_trip),
        cmocka_unit_test(test_shape_bad_desc_names_the_field),
        cmocka_unit_test(test_every_shape_is_valid_with_consistent_frames),
        cmocka_unit_test(test_every_shape_faces_outward),
        cmocka_unit_test(test_round_shape_normals_point_away_from_the_axis),
        cmocka_unit_test(test_closed_shapes_are_watertight_by_position),
        cmocka_unit_test(test_teapot_patches_meet_without_cracks),
        cmocka_unit_test(test_teapot_height_is_size_and_box_is_centred),
        cmocka_unit_test(test_plane_matches_the_design_parametrisation),
        cmocka_unit_test(test_sphere_uvs_follow_longitude_and_latitude),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
