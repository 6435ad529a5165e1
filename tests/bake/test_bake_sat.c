/* The summed-area table (Doggett & Hirche 2000, "Local Area Average Height Test"): box sums
 * against brute force, both wrap modes, averages, errors. */
#include "test_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "meso/bake_sat.h"

static uint32_t rng_state = 12345u;
static uint32_t next_random(void) {
    rng_state = rng_state * 1664525u + 1013904223u;
    return rng_state >> 8;
}

static meso_heightfield make_field(int width, int height, meso_wrap wrap, float *storage) {
    for (int i = 0; i < width * height; i++) storage[i] = (float)(next_random() % 1000) / 999.0f;
    return (meso_heightfield){.width = width, .height = height, .heights = storage, .wrap = wrap};
}

static double brute_sum(const meso_heightfield *hf, int i0, int j0, int i1, int j1, double *count) {
    double sum = 0.0;
    *count = 0.0;
    for (int j = j0; j < j1; j++)
        for (int i = i0; i < i1; i++) {
            if (hf->wrap == MESO_WRAP_CLAMP &&
                (i < 0 || j < 0 || i >= hf->width || j >= hf->height))
                continue; /* clamp: the box is clipped to the field */
            sum += meso_heightfield_texel(hf, i, j);
            *count += 1.0;
        }
    return sum;
}

static void check_random_boxes(meso_wrap wrap) {
    meso_context *ctx = test_context(1);
    float storage[13 * 7];
    meso_heightfield hf = make_field(13, 7, wrap, storage);
    meso_sat *sat = NULL;
    assert_int_equal(meso_sat_bake(ctx, &hf, &sat), MESO_OK);
    assert_non_null(sat);
    assert_int_equal(sat->width, 13);
    assert_int_equal(sat->height, 7);
    for (int k = 0; k < 2000; k++) {
        /* boxes inside, across the borders, larger than the field, with negative corners */
        int i0 = (int)(next_random() % 60) - 30, j0 = (int)(next_random() % 40) - 20;
        int i1 = i0 + (int)(next_random() % 35), j1 = j0 + (int)(next_random() % 25);
        double count = 0.0;
        double expected = brute_sum(&hf, i0, j0, i1, j1, &count);
        double got = meso_sat_box_sum(sat, i0, j0, i1, j1);
        assert_true(fabs(got - expected) <= 1e-9 * (1.0 + fabs(expected)));
        assert_true(meso_sat_box_count(sat, i0, j0, i1, j1) == count);
    }
    meso_sat_destroy(sat);
    meso_context_destroy(ctx);
}

static void test_bake_sat_box_sums_equal_brute_force_repeat(void **state) {
    (void)state;
    check_random_boxes(MESO_WRAP_REPEAT);
}

static void test_bake_sat_box_sums_equal_brute_force_clamp(void **state) {
    (void)state;
    check_random_boxes(MESO_WRAP_CLAMP);
}

static void test_bake_sat_average_of_a_constant_field_is_the_constant(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    float storage[16 * 16];
    for (int i = 0; i < 256; i++) storage[i] = 0.375f;
    meso_heightfield hf = {.width = 16, .height = 16, .heights = storage, .wrap = MESO_WRAP_REPEAT};
    meso_sat *sat = NULL;
    assert_int_equal(meso_sat_bake(ctx, &hf, &sat), MESO_OK);
    const float radii[] = {0.0f, 0.3f, 1.0f, 2.5f, 7.0f, 40.0f};
    for (size_t r = 0; r < sizeof(radii) / sizeof(radii[0]); r++)
        for (int k = 0; k < 50; k++) {
            float u = (float)(next_random() % 4000) / 1000.0f - 2.0f;
            float v = (float)(next_random() % 4000) / 1000.0f - 2.0f;
            assert_float_equal(meso_sat_box_average(sat, u, v, radii[r]), 0.375f, 1e-6f);
        }
    meso_sat_destroy(sat);
    meso_context_destroy(ctx);
}

static void test_bake_sat_average_takes_the_box_of_texel_centres_around_the_point(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    float storage[8 * 4];
    meso_heightfield hf = make_field(8, 4, MESO_WRAP_REPEAT, storage);
    meso_sat *sat = NULL;
    assert_int_equal(meso_sat_bake(ctx, &hf, &sat), MESO_OK);
    /* radius 0: the texel containing the point; (u, v) = centre of texel (5, 1) */
    float u = 5.5f / 8.0f, v = 1.0f - 1.5f / 4.0f;
    assert_float_equal(meso_sat_box_average(sat, u, v, 0.0f), storage[1 * 8 + 5], 1e-6f);
    /* radius 1: the 3 x 3 texels around it */
    double sum = 0.0;
    for (int j = 0; j <= 2; j++)
        for (int i = 4; i <= 6; i++) sum += storage[j * 8 + i];
    assert_float_equal(meso_sat_box_average(sat, u, v, 1.0f), (float)(sum / 9.0), 1e-6f);
    meso_sat_destroy(sat);
    meso_context_destroy(ctx);
}

/* The box of meso_sat_box_average by its definition (texel centres k + 0.5 within radius of x,
 * at least the texel holding x), for points and radii well inside the limits. */
static void definition_range(float x, float radius, int *lo, int *hi) {
    *lo = (int)ceilf(x - radius - 0.5f);
    *hi = (int)floorf(x + radius - 0.5f) + 1;
    if (*hi <= *lo) {
        *lo = (int)floorf(x);
        *hi = *lo + 1;
    }
}

/* The average's shortcut for boxes inside the field returns the bits of the general path
 * (meso_sat_box_sum / meso_sat_box_count in doubles), for boxes inside, touching the border and
 * crossing it, in both wrap modes (the tessellator's area test relies on the same bits). */
static void check_average_bits(meso_wrap wrap) {
    meso_context *ctx = test_context(1);
    float storage[37 * 23];
    meso_heightfield hf = make_field(37, 23, wrap, storage);
    meso_sat *sat = NULL;
    assert_int_equal(meso_sat_bake(ctx, &hf, &sat), MESO_OK);
    int inside = 0, outside = 0;
    for (int k = 0; k < 4000; k++) {
        float u = (float)(next_random() % 20001) / 20000.0f * 1.2f - 0.1f;
        float v = (float)(next_random() % 20001) / 20000.0f * 1.2f - 0.1f;
        float radius = (float)(next_random() % 1601) / 100.0f;
        float x = u * 37.0f, y = (1.0f - v) * 23.0f;
        int i0, i1, j0, j1;
        definition_range(x, radius, &i0, &i1);
        definition_range(y, radius, &j0, &j1);
        double count = meso_sat_box_count(sat, i0, j0, i1, j1);
        if (count <= 0.0) continue; /* clamp, box outside: the nearest texel (tested above) */
        float expected = (float)(meso_sat_box_sum(sat, i0, j0, i1, j1) / count);
        float got = meso_sat_box_average(sat, u, v, radius);
        assert_memory_equal(&got, &expected, sizeof(float));
        if (i0 >= 0 && j0 >= 0 && i1 <= 37 && j1 <= 23)
            inside++;
        else
            outside++;
    }
    assert_true(inside > 100 && outside > 100); /* both paths were taken */
    meso_sat_destroy(sat);
    meso_context_destroy(ctx);
}

static void test_bake_sat_average_has_the_bits_of_sum_over_count_repeat(void **state) {
    (void)state;
    check_average_bits(MESO_WRAP_REPEAT);
}

static void test_bake_sat_average_has_the_bits_of_sum_over_count_clamp(void **state) {
    (void)state;
    check_average_bits(MESO_WRAP_CLAMP);
}

static void test_bake_sat_rejects_empty_and_oversized_fields(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    float one = 0.5f;
    meso_sat *sat = (meso_sat *)&one; /* must be reset to NULL on failure */
    meso_heightfield empty = {.width = 0, .height = 4, .heights = &one};
    assert_int_equal(meso_sat_bake(ctx, &empty, &sat), MESO_ERROR_INVALID_ARGUMENT);
    assert_null(sat);
    assert_non_null(strstr(meso_context_last_error(ctx), "summed-area table"));
    /* the size is checked before anything is read or allocated */
    meso_heightfield huge = {.width = 8192, .height = 8192, .heights = &one};
    assert_int_equal(meso_sat_bake(ctx, &huge, &sat), MESO_ERROR_LIMIT);
    assert_null(sat);
    assert_non_null(strstr(meso_context_last_error(ctx), "limit"));
    assert_int_equal(meso_sat_bake(ctx, NULL, &sat), MESO_ERROR_INVALID_ARGUMENT);
    meso_sat_destroy(NULL);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bake_sat_box_sums_equal_brute_force_repeat),
        cmocka_unit_test(test_bake_sat_box_sums_equal_brute_force_clamp),
        cmocka_unit_test(test_bake_sat_average_of_a_constant_field_is_the_constant),
        cmocka_unit_test(test_bake_sat_average_takes_the_box_of_texel_centres_around_the_point),
        cmocka_unit_test(test_bake_sat_average_has_the_bits_of_sum_over_count_repeat),
        cmocka_unit_test(test_bake_sat_average_has_the_bits_of_sum_over_count_clamp),
        cmocka_unit_test(test_bake_sat_rejects_empty_and_oversized_fields),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
