/* Horizon maps (bake_horizon.h): known horizons of simple fields, interpolation between
 * azimuths, errors, and byte identity across thread counts. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"
#include "meso/bake_horizon.h"

static meso_heightfield *make_field(meso_context *ctx, int w, int h, float value) {
    meso_heightfield *hf = NULL;
    assert_int_equal(meso_heightfield_create_constant(ctx, w, h, value, &hf), MESO_OK);
    return hf;
}

static float slope_at(const meso_horizon_map *m, int i, int j, int k) {
    return m
        ->slopes[((size_t)j * (size_t)m->width + (size_t)i) * (size_t)m->num_azimuths + (size_t)k];
}

static void test_flat_field_has_horizon_zero_everywhere(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_heightfield *hf = make_field(ctx, 40, 24, 0.7f);
    meso_horizon_map *map = NULL;
    assert_int_equal(meso_horizon_map_bake(ctx, hf, NULL, &map), MESO_OK);
    assert_int_equal(map->num_azimuths, 8);
    assert_true(map->max_distance == 64.0f);
    for (size_t k = 0; k < (size_t)40 * 24 * 8; ++k) assert_true(map->slopes[k] == 0.0f);
    meso_horizon_map_destroy(map);
    meso_heightfield_destroy(hf);
    meso_context_destroy(ctx);
}

/* One texel at full height on a zero field: seen from 5 texels to its left, the horizon toward
 * +u has slope 1 / (5 / 64) (rise 1 over 5 texels of a 64-texel tile); toward -u it is 0. */
static void test_pillar_gives_its_angle_at_its_distance(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_heightfield *hf = make_field(ctx, 64, 64, 0.0f);
    hf->heights[32 * 64 + 32] = 1.0f;
    meso_heightfield_update_hash(hf);
    meso_horizon_map *map = NULL;
    /* 12 azimuths: the general (bilinear) march; azimuth 3 is phi = 90 deg */
    assert_int_equal(
        meso_horizon_map_bake(ctx, hf, &(meso_horizon_desc){.num_azimuths = 12, .max_distance = 16},
                              &map),
        MESO_OK);
    assert_true(fabsf(slope_at(map, 27, 32, 0) - 12.8f) < 1e-4f);
    assert_true(fabsf(slope_at(map, 32, 37, 3) - 12.8f) < 1e-4f);
    assert_true(slope_at(map, 27, 32, 6) == 0.0f);
    meso_horizon_map_destroy(map);
    /* 8 azimuths: the texel-aligned march */
    assert_int_equal(meso_horizon_map_bake(ctx, hf, &(meso_horizon_desc){.max_distance = 16}, &map),
                     MESO_OK);
    assert_true(fabsf(slope_at(map, 27, 32, 0) - 12.8f) < 1e-4f);
    assert_true(slope_at(map, 27, 32, 4) == 0.0f);
    /* +v is up in the image: from 5 rows below the pillar, azimuth 2 (phi = 90 deg) sees it */
    assert_true(fabsf(slope_at(map, 32, 37, 2) - 12.8f) < 1e-4f);
    assert_true(slope_at(map, 32, 37, 6) == 0.0f);
    /* beyond max_distance nothing is seen */
    assert_true(slope_at(map, 10, 32, 0) == 0.0f);
    /* halfway between azimuths 0 and 1 the slope is their mean */
    float mid = meso_horizon_map_slope(map, 27, 32, (float)(M_PI / 8.0));
    assert_true(fabsf(mid - 0.5f * (slope_at(map, 27, 32, 0) + slope_at(map, 27, 32, 1))) < 1e-5f);
    meso_horizon_map_destroy(map);
    meso_heightfield_destroy(hf);
    meso_context_destroy(ctx);
}

static void test_bad_desc_fields_are_named(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_heightfield *hf = make_field(ctx, 8, 8, 0.5f);
    meso_horizon_map *map = (meso_horizon_map *)1;
    assert_int_equal(meso_horizon_map_bake(ctx, hf, &(meso_horizon_desc){.num_azimuths = 65}, &map),
                     MESO_ERROR_INVALID_ARGUMENT);
    assert_null(map);
    assert_non_null(strstr(meso_context_last_error(ctx), "num_azimuths"));
    assert_int_equal(meso_horizon_map_bake(ctx, hf, &(meso_horizon_desc){.max_distance = -3}, &map),
                     MESO_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(meso_context_last_error(ctx), "max_distance"));
    assert_int_equal(meso_horizon_map_bake(ctx, NULL, NULL, &map), MESO_ERROR_INVALID_ARGUMENT);
    meso_heightfield_destroy(hf);
    meso_context_destroy(ctx);
}

static void test_one_and_two_threads_bake_the_same_bytes(void **state) {
    (void)state;
    meso_context *one = test_context(1), *two = test_context(2);
    meso_heightfield *hf = NULL;
    meso_heightfield_desc desc = {.kind = MESO_HEIGHTFIELD_BRICKS, .resolution = 96};
    assert_int_equal(meso_heightfield_create_procedural(one, &desc, &hf, NULL), MESO_OK);
    meso_horizon_map *a = NULL, *b = NULL;
    assert_int_equal(meso_horizon_map_bake(one, hf, NULL, &a), MESO_OK);
    assert_int_equal(meso_horizon_map_bake(two, hf, NULL, &b), MESO_OK);
    assert_memory_equal(a->slopes, b->slopes, meso_horizon_map_memory(a));
    bool any = false;
    for (size_t k = 0; k < meso_horizon_map_memory(a) / sizeof(float); ++k)
        any |= a->slopes[k] > 0.0f;
    assert_true(any); /* bricks have mortar grooves: some horizon is above the tangent plane */
    meso_horizon_map_destroy(a);
    meso_horizon_map_destroy(b);
    /* the general march too */
    assert_int_equal(meso_horizon_map_bake(one, hf, &(meso_horizon_desc){.num_azimuths = 6}, &a),
                     MESO_OK);
    assert_int_equal(meso_horizon_map_bake(two, hf, &(meso_horizon_desc){.num_azimuths = 6}, &b),
                     MESO_OK);
    assert_memory_equal(a->slopes, b->slopes, meso_horizon_map_memory(a));
    meso_horizon_map_destroy(a);
    meso_horizon_map_destroy(b);
    meso_heightfield_destroy(hf);
    meso_context_destroy(one);
    meso_context_destroy(two);
}

/* The memory budget: 40 x 24 texels x 8 azimuths is 30 KiB, refused under 16 KiB. */
static void test_bake_keeps_to_the_memory_budget(void **state) {
    (void)state;
    meso_context *tiny = NULL;
    assert_int_equal(meso_context_create(
                         &(meso_context_desc){.num_threads = 1, .memory_limit = 16u << 10}, &tiny),
                     MESO_OK);
    meso_heightfield *hf = make_field(tiny, 40, 24, 0.7f);
    meso_horizon_map *map = NULL;
    assert_int_equal(meso_horizon_map_bake(tiny, hf, NULL, &map), MESO_ERROR_LIMIT);
    assert_null(map);
    assert_non_null(strstr(meso_context_last_error(tiny), "horizon bake"));
    meso_heightfield_destroy(hf);
    meso_context_destroy(tiny);
}

typedef struct said {
    char warning[512];
    int progress_calls;
} said;

static void keep_warning(void *user, meso_log_level level, const char *message) {
    said *s = user;
    if (level == MESO_LOG_WARNING && !s->warning[0])
        snprintf(s->warning, sizeof s->warning, "%s", message);
}

static bool cancel_at_once(void *user, const char *label, double fraction) {
    (void)label, (void)fraction;
    ((said *)user)->progress_calls++;
    return true;
}

/* A bake of minutes (2048^2 texels, 64 azimuths to 4096 texels) is said before it starts, with
 * its estimate, and reports progress (here cancelled at the first report). */
static void test_a_long_bake_is_announced_with_its_estimate(void **state) {
    (void)state;
    meso_horizon_desc long_bake = {.num_azimuths = 64, .max_distance = 4096.0f};
    double seconds = meso_horizon_bake_seconds_estimate(2048, 2048, &long_bake, 2);
    assert_true(seconds > 60.0 && seconds < 1000.0);
    /* the estimate grows with the work: 4 times the texels, 4 times the time */
    assert_true(fabs(meso_horizon_bake_seconds_estimate(1024, 1024, &long_bake, 2) * 4.0 -
                     seconds) <= 1e-6 * seconds);
    said s = {{0}, 0};
    meso_context_desc desc = {.num_threads = 1,
                              .log = keep_warning,
                              .log_user = &s,
                              .progress = MESO_PROGRESS_NEVER,
                              .on_progress = cancel_at_once,
                              .progress_user = &s};
    meso_context *ctx = NULL;
    assert_int_equal(meso_context_create(&desc, &ctx), MESO_OK);
    meso_heightfield *hf = make_field(ctx, 2048, 2048, 0.0f);
    meso_horizon_map *map = NULL;
    assert_int_equal(meso_horizon_map_bake(ctx, hf, &long_bake, &map), MESO_ERROR_CANCELLED);
    assert_null(map);
    if (!strstr(s.warning, "horizon map: 2048 x 2048 texels x 64 azimuths to 4096 texels: about") ||
        !strstr(s.warning, "s of baking on 1 thread (--progress shows it)"))
        fail_msg("warning: '%s'", s.warning);
    assert_true(s.progress_calls >= 1);
    meso_heightfield_destroy(hf);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_flat_field_has_horizon_zero_everywhere),
        cmocka_unit_test(test_pillar_gives_its_angle_at_its_distance),
        cmocka_unit_test(test_bad_desc_fields_are_named),
        cmocka_unit_test(test_one_and_two_threads_bake_the_same_bytes),
        cmocka_unit_test(test_bake_keeps_to_the_memory_budget),
        cmocka_unit_test(test_a_long_bake_is_announced_with_its_estimate),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
