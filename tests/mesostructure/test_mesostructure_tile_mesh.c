/* Solids from tile meshes (mesostructure_tile_mesh.c): a cube's signed distances and its two
 * layers, the periodic continuation across the tile's border, and refusal of open,
 * non-manifold and out-of-box meshes with a message naming the file. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"

/* A box [x0, x1] x [y0, y1] x [z0, z1], triangles counter-clockwise seen from outside. */
static void box(float x0, float x1, float y0, float y1, float z0, float z1, meso_vec3 *p,
                uint32_t *idx) {
    for (int c = 0; c < 8; c++)
        p[c] = (meso_vec3){c & 1 ? x1 : x0, c & 2 ? y1 : y0, c & 4 ? z1 : z0};
    static const uint32_t faces[12][3] = {
        {0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, /* z0 (down), z1 (up) */
        {0, 1, 4}, {1, 5, 4}, {2, 6, 3}, {3, 6, 7}, /* y0, y1 */
        {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}, /* x0, x1 */
    };
    memcpy(idx, faces, sizeof faces);
}

static void test_cube_has_signed_distances_and_two_layers(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_vec3 p[8];
    uint32_t idx[36];
    box(0.25f, 0.75f, 0.25f, 0.75f, 0.3f, 0.8f, p, idx);
    meso_solid *s = NULL;
    assert_int_equal(meso_solid_create_from_triangles(ctx, p, 8, idx, 12, "cube.obj", 64, &s),
                     MESO_OK);
    /* inside at the centre (z = 0.55 -> w = 0.45), outside beside it and above it */
    assert_true(meso_solid_distance(s, (meso_vec3){0.5f, 0.5f, 0.45f}) < -0.1f);
    assert_true(meso_solid_distance(s, (meso_vec3){0.1f, 0.5f, 0.45f}) > 0.05f);
    assert_true(meso_solid_distance(s, (meso_vec3){0.5f, 0.5f, 0.05f}) > 0.05f);
    /* the distance bound never exceeds the true distance (0.25 to the side x = 0.25) */
    assert_true(meso_solid_distance(s, (meso_vec3){0.0f, 0.5f, 0.45f}) <= 0.25f + 1e-4f);
    meso_layers *m = NULL;
    meso_layers_desc desc = {
        .solid = s, .width = 16, .height = 16, .format = MESO_LAYERS_FORMAT_F32};
    assert_int_equal(meso_layers_bake(ctx, &desc, &m), MESO_OK);
    /* texel (8, 8) is over the cube: entry at w = 1 - 0.8, exit at w = 1 - 0.3 */
    const float *d = m->depth + (8 * 16 + 8) * 4;
    assert_int_equal(m->count[8 * 16 + 8], 2);
    assert_true(fabsf(d[0] - 0.2f) < 0.02f && fabsf(d[1] - 0.7f) < 0.02f);
    assert_int_equal(m->count[0], 0); /* texel (0, 0) is beside it */
    meso_layers_destroy(m);
    meso_solid_destroy(s);
    meso_context_destroy(ctx);
}

static void test_tile_mesh_continues_across_the_border(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_vec3 p[8];
    uint32_t idx[36];
    box(0.8f, 1.2f, 0.4f, 0.6f, 0.2f, 0.8f, p, idx); /* pokes out at u = 1 */
    meso_solid *s = NULL;
    assert_int_equal(meso_solid_create_from_triangles(ctx, p, 8, idx, 12, "edge.obj", 48, &s),
                     MESO_OK);
    assert_true(meso_solid_distance(s, (meso_vec3){0.9f, 0.5f, 0.5f}) < 0.0f);
    assert_true(meso_solid_distance(s, (meso_vec3){0.1f, 0.5f, 0.5f}) < 0.0f); /* wrapped */
    assert_true(meso_solid_distance(s, (meso_vec3){0.5f, 0.5f, 0.5f}) > 0.0f);
    meso_solid_destroy(s);
    meso_context_destroy(ctx);
}

static void test_grid_is_identical_for_any_thread_count(void **state) {
    (void)state;
    meso_context *one = test_context(1), *two = test_context(2);
    meso_vec3 p[8];
    uint32_t idx[36];
    box(0.8f, 1.2f, 0.4f, 0.6f, 0.2f, 0.8f, p, idx);
    meso_solid *a = NULL, *b = NULL;
    assert_int_equal(meso_solid_create_from_triangles(one, p, 8, idx, 12, "a.obj", 24, &a),
                     MESO_OK);
    assert_int_equal(meso_solid_create_from_triangles(two, p, 8, idx, 12, "a.obj", 24, &b),
                     MESO_OK);
    for (int k = 0; k < 1000; k++) {
        meso_vec3 q = {(float)(k % 10) / 10.0f + 0.013f, (float)(k / 10 % 10) / 10.0f + 0.021f,
                       (float)(k / 100) / 10.0f + 0.017f};
        float da = meso_solid_distance(a, q), db = meso_solid_distance(b, q);
        assert_memory_equal(&da, &db, sizeof da);
    }
    assert_true(meso_solid_hash(a) == meso_solid_hash(b));
    meso_solid_destroy(a);
    meso_solid_destroy(b);
    meso_context_destroy(one);
    meso_context_destroy(two);
}

static void test_bad_tile_meshes_are_refused_naming_the_file(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_vec3 p[9];
    uint32_t idx[40];
    box(0.25f, 0.75f, 0.25f, 0.75f, 0.3f, 0.8f, p, idx);
    meso_solid *s = NULL;
    /* open: the top face's two triangles missing */
    assert_int_equal(meso_solid_create_from_triangles(ctx, p, 8, idx, 10, "open.obj", 32, &s),
                     MESO_ERROR_FORMAT);
    assert_non_null(strstr(meso_context_last_error(ctx), "open.obj: the tile mesh is not closed"));
    assert_null(s);
    /* non-manifold: a fin on an edge of the box (edge 0-1 gets a third triangle) */
    p[8] = (meso_vec3){0.5f, 0.1f, 0.1f};
    uint32_t fin[3] = {0, 1, 8};
    memcpy(idx + 36, fin, sizeof fin);
    assert_int_equal(meso_solid_create_from_triangles(ctx, p, 9, idx, 13, "fin.obj", 32, &s),
                     MESO_ERROR_FORMAT);
    assert_non_null(strstr(meso_context_last_error(ctx), "fin.obj"));
    /* outside the box in z */
    box(0.25f, 0.75f, 0.25f, 0.75f, 0.3f, 1.5f, p, idx);
    assert_int_equal(meso_solid_create_from_triangles(ctx, p, 8, idx, 12, "tall.obj", 32, &s),
                     MESO_ERROR_FORMAT);
    assert_non_null(strstr(meso_context_last_error(ctx), "tall.obj"));
    /* a flipped triangle: inconsistent orientation */
    box(0.25f, 0.75f, 0.25f, 0.75f, 0.3f, 0.8f, p, idx);
    uint32_t t = idx[1];
    idx[1] = idx[2];
    idx[2] = t;
    assert_int_equal(meso_solid_create_from_triangles(ctx, p, 8, idx, 12, "flip.obj", 32, &s),
                     MESO_ERROR_FORMAT);
    assert_non_null(strstr(meso_context_last_error(ctx), "oriented"));
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cube_has_signed_distances_and_two_layers),
        cmocka_unit_test(test_tile_mesh_continues_across_the_border),
        cmocka_unit_test(test_grid_is_identical_for_any_thread_count),
        cmocka_unit_test(test_bad_tile_meshes_are_refused_naming_the_file),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
