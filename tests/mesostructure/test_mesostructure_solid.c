/* Procedural solids: tiling, occupancy, the slab, holes and overhangs, the distance bound. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"

static const meso_solid_kind all_kinds[] = {MESO_SOLID_WEAVE, MESO_SOLID_CHAIN, MESO_SOLID_GRID,
                                            MESO_SOLID_SQUAMA, MESO_SOLID_HELIX};
#define NUM_KINDS (sizeof(all_kinds) / sizeof(all_kinds[0]))

static meso_solid *make(meso_context *ctx, meso_solid_kind kind) {
    meso_solid *solid = NULL;
    assert_int_equal(meso_solid_create_procedural(ctx, &(meso_solid_desc){.kind = kind}, &solid),
                     MESO_OK);
    assert_non_null(solid);
    return solid;
}

/* Deterministic points in [0, 1). */
static float next_unit(uint32_t *state) {
    *state = *state * 1664525u + 1013904223u;
    return (float)(*state >> 8) / 16777216.0f;
}

static float dist(const meso_solid *s, float u, float v, float w) {
    return meso_solid_distance(s, (meso_vec3){u, v, w});
}

static void test_solids_tile_with_period_one(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    for (size_t k = 0; k < NUM_KINDS; k++) {
        meso_solid *s = make(ctx, all_kinds[k]);
        uint32_t seed = 7;
        for (int n = 0; n < 2000; n++) {
            float u = next_unit(&seed), v = next_unit(&seed), w = next_unit(&seed);
            float d = dist(s, u, v, w);
            assert_float_equal(d, dist(s, u + 1.0f, v, w), 1e-5);
            assert_float_equal(d, dist(s, u, v + 1.0f, w), 1e-5);
            assert_float_equal(d, dist(s, u - 1.0f, v - 1.0f, w), 1e-5);
        }
        /* Continuous across the seam: just inside either side of u = 0 agree. */
        for (int n = 0; n < 200; n++) {
            float v = next_unit(&seed), w = next_unit(&seed);
            assert_float_equal(dist(s, 1e-4f, v, w), dist(s, 1.0f - 1e-4f, v, w), 1e-3);
            assert_float_equal(dist(s, v, 1e-4f, w), dist(s, v, 1.0f - 1e-4f, w), 1e-3);
        }
        meso_solid_destroy(s);
    }
    meso_context_destroy(ctx);
}

static void test_solids_are_neither_empty_nor_full(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    for (size_t k = 0; k < NUM_KINDS; k++) {
        meso_solid *s = make(ctx, all_kinds[k]);
        int inside = 0, total = 0;
        for (int i = 0; i < 20; i++)
            for (int j = 0; j < 20; j++)
                for (int l = 0; l < 20; l++) {
                    inside += dist(s, (i + 0.5f) / 20, (j + 0.5f) / 20, (l + 0.5f) / 20) < 0.0f;
                    total++;
                }
        assert_true(inside > total / 50);
        assert_true(inside < total * 9 / 10);
        meso_solid_destroy(s);
    }
    meso_context_destroy(ctx);
}

static void test_solids_are_empty_outside_the_slab(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    const float outside[] = {-2.0f, -0.5f, -0.01f, -1e-4f, 1.0001f, 1.01f, 1.5f, 3.0f};
    for (size_t k = 0; k < NUM_KINDS; k++) {
        meso_solid *s = make(ctx, all_kinds[k]);
        uint32_t seed = 11;
        for (int n = 0; n < 500; n++) {
            float u = next_unit(&seed), v = next_unit(&seed);
            for (size_t o = 0; o < sizeof(outside) / sizeof(outside[0]); o++)
                assert_true(dist(s, u, v, outside[o]) > 0.0f);
        }
        meso_solid_destroy(s);
    }
    meso_context_destroy(ctx);
}

/* Lipschitz <= 1: |d(p) - d(q)| <= |p - q|, which with d = 0 on the surface makes d a lower
 * bound of the distance, so sphere tracing never steps through material. */
static void test_solid_distance_is_a_safe_bound(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    for (size_t k = 0; k < NUM_KINDS; k++) {
        meso_solid *s = make(ctx, all_kinds[k]);
        uint32_t seed = 3;
        for (int n = 0; n < 5000; n++) {
            meso_vec3 p = {next_unit(&seed), next_unit(&seed), next_unit(&seed) * 1.2f - 0.1f};
            float step = 0.05f * next_unit(&seed);
            meso_vec3 q = {p.x + step * (next_unit(&seed) - 0.5f),
                           p.y + step * (next_unit(&seed) - 0.5f),
                           p.z + step * (next_unit(&seed) - 0.5f)};
            float len = meso_vec3_length(meso_vec3_sub(p, q));
            float dp = meso_solid_distance(s, p), dq = meso_solid_distance(s, q);
            assert_true(fabsf(dp - dq) <= len * 1.001f + 1e-6f);
        }
        meso_solid_destroy(s);
    }
    meso_context_destroy(ctx);
}

/* Whether the column at (u, v) holds no material at any depth. */
static bool column_is_open(const meso_solid *s, float u, float v) {
    for (int l = 0; l <= 200; l++)
        if (dist(s, u, v, (float)l / 200.0f) <= 0.0f) return false;
    return true;
}

static void test_weave_and_grid_have_holes_through_the_slab(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    const meso_solid_kind holed[] = {MESO_SOLID_WEAVE, MESO_SOLID_GRID};
    for (size_t k = 0; k < 2; k++) {
        meso_solid *s = make(ctx, holed[k]);
        int open = 0;
        for (int i = 0; i < 16 && !open; i++)
            for (int j = 0; j < 16 && !open; j++)
                open += column_is_open(s, (i + 0.5f) / 16, (j + 0.5f) / 16);
        assert_true(open > 0);
        meso_solid_destroy(s);
    }
    meso_context_destroy(ctx);
}

/* Non-height-field: some column meets material, then empty space, then material again. */
static void test_solids_have_overhangs(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    const meso_solid_kind kinds[] = {MESO_SOLID_WEAVE, MESO_SOLID_CHAIN, MESO_SOLID_SQUAMA,
                                     MESO_SOLID_HELIX};
    for (size_t k = 0; k < 4; k++) {
        meso_solid *s = make(ctx, kinds[k]);
        bool found = false;
        for (int i = 0; i < 48 && !found; i++)
            for (int j = 0; j < 48 && !found; j++) {
                int runs = 0;
                bool was_inside = false;
                for (int l = 0; l <= 100; l++) {
                    bool in = dist(s, (i + 0.5f) / 48, (j + 0.5f) / 48, (float)l / 100.0f) < 0.0f;
                    if (in && !was_inside) runs++;
                    was_inside = in;
                }
                found = runs >= 2;
            }
        assert_true(found);
        meso_solid_destroy(s);
    }
    meso_context_destroy(ctx);
}

static void test_gradient_points_outward(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    for (size_t k = 0; k < NUM_KINDS; k++) {
        meso_solid *s = make(ctx, all_kinds[k]);
        uint32_t seed = 5;
        int checked = 0;
        for (int n = 0; n < 5000 && checked < 50; n++) {
            meso_vec3 p = {next_unit(&seed), next_unit(&seed), next_unit(&seed)};
            float d = meso_solid_distance(s, p);
            if (d >= 0.0f || d < -0.01f) continue; /* just inside the surface */
            meso_vec3 g = meso_solid_gradient(s, p);
            assert_true(meso_vec3_length(g) > 0.1f);
            /* A small step along the gradient increases the distance. */
            meso_vec3 q = meso_vec3_madd(p, meso_vec3_normalize(g), 2e-3f);
            assert_true(meso_solid_distance(s, q) > d);
            checked++;
        }
        assert_true(checked > 0);
        meso_solid_destroy(s);
    }
    meso_context_destroy(ctx);
}

static void test_defaults_hash_and_names(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_solid_desc d = meso_solid_desc_defaults(NULL);
    assert_int_equal(d.kind, MESO_SOLID_WEAVE);
    assert_int_equal(d.count, 2);
    assert_true(d.thickness > 0.0f);
    meso_solid *a = make(ctx, MESO_SOLID_DEFAULT);
    meso_solid *b = make(ctx, MESO_SOLID_WEAVE);
    meso_solid *c = make(ctx, MESO_SOLID_GRID);
    assert_int_equal(meso_solid_get_desc(a).kind, MESO_SOLID_WEAVE);
    assert_int_equal(meso_solid_get_desc(c).count, 4);
    assert_true(meso_solid_hash(a) == meso_solid_hash(b));
    assert_true(meso_solid_hash(a) != meso_solid_hash(c));
    meso_solid *thin = NULL;
    assert_int_equal(
        meso_solid_create_procedural(
            ctx, &(meso_solid_desc){.kind = MESO_SOLID_WEAVE, .thickness = 0.2f}, &thin),
        MESO_OK);
    assert_true(meso_solid_hash(thin) != meso_solid_hash(a));
    meso_solid_kind kind;
    for (size_t k = 0; k < NUM_KINDS; k++) {
        assert_true(meso_solid_kind_from_name(meso_solid_kind_name(all_kinds[k]), &kind));
        assert_int_equal(kind, all_kinds[k]);
    }
    assert_false(meso_solid_kind_from_name("chains", &kind));
    meso_solid_destroy(thin);
    meso_solid_destroy(a);
    meso_solid_destroy(b);
    meso_solid_destroy(c);
    meso_context_destroy(ctx);
}

static void test_invalid_solid_descs_name_the_field(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_solid *s = (meso_solid *)1;
    assert_int_equal(meso_solid_create_procedural(
                         ctx, &(meso_solid_desc){.kind = MESO_SOLID_CHAIN, .count = 3}, &s),
                     MESO_ERROR_INVALID_ARGUMENT);
    assert_null(s);
    assert_non_null(strstr(meso_context_last_error(ctx), "count"));
    assert_int_equal(meso_solid_create_procedural(
                         ctx, &(meso_solid_desc){.kind = MESO_SOLID_GRID, .thickness = 0.9f}, &s),
                     MESO_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(meso_context_last_error(ctx), "thickness"));
    assert_int_equal(meso_solid_create_procedural(
                         ctx, &(meso_solid_desc){.kind = MESO_SOLID_HELIX, .thickness = -0.1f}, &s),
                     MESO_ERROR_INVALID_ARGUMENT);
    assert_int_equal(
        meso_solid_create_procedural(ctx, &(meso_solid_desc){.kind = (meso_solid_kind)99}, &s),
        MESO_ERROR_INVALID_ARGUMENT);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_solids_tile_with_period_one),
        cmocka_unit_test(test_solids_are_neither_empty_nor_full),
        cmocka_unit_test(test_solids_are_empty_outside_the_slab),
        cmocka_unit_test(test_solid_distance_is_a_safe_bound),
        cmocka_unit_test(test_weave_and_grid_have_holes_through_the_slab),
        cmocka_unit_test(test_solids_have_overhangs),
        cmocka_unit_test(test_gradient_points_outward),
        cmocka_unit_test(test_defaults_hash_and_names),
        cmocka_unit_test(test_invalid_solid_descs_name_the_field),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
