/* Cone maps (bake_cone.h): the bake against a brute-force search over every texel, the bound
 * it promises checked on the bilinear surface between texels, byte identity across thread
 * counts, and errors. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "meso/bake_cone.h"
#include "meso/bake_minmax.h"
#include "test_util.h"

static meso_heightfield *random_field(meso_context *ctx, int w, int h, meso_wrap wrap,
                                      unsigned seed) {
    meso_heightfield *hf = NULL;
    assert_int_equal(meso_heightfield_create_constant(ctx, w, h, 0.0f, &hf), MESO_OK);
    srand(seed);
    for (int k = 0; k < w * h; ++k) hf->heights[k] = (float)rand() / (float)RAND_MAX;
    hf->wrap = wrap;
    meso_heightfield_update_hash(hf);
    return hf;
}

/* The L1 distance on the torus from coordinate x to the interval [c, c + 1]. */
static double circle_distance(double x, int c, int period) {
    double best = (double)period;
    for (int k = -1; k <= 1; ++k) {
        double y = x + (double)(k * period);
        double d =
            y < (double)c ? (double)c - y : (y > (double)(c + 1) ? y - (double)(c + 1) : 0.0);
        best = d < best ? d : best;
    }
    return best;
}

static void bake(meso_context *ctx, const meso_heightfield *hf, meso_minmax_pyramid **out_p,
                 meso_cone_map **out_c) {
    assert_int_equal(meso_minmax_pyramid_bake(ctx, hf, out_p), MESO_OK);
    assert_int_equal(meso_cone_map_bake(ctx, hf, *out_p, out_c), MESO_OK);
}

/* Every cell against the largest ratio over every texel of the field (the fields are small
 * enough that every texel lies within MESO_CONE_RADIUS, so the two must agree); then the bound
 * at random points of the bilinear surface. */
static void check_against_brute_force(int w, int h, unsigned seed) {
    meso_context *ctx = test_context(2);
    meso_heightfield *hf = random_field(ctx, w, h, MESO_WRAP_REPEAT, seed);
    meso_minmax_pyramid *p = NULL;
    meso_cone_map *c = NULL;
    bake(ctx, hf, &p, &c);
    assert_true(w / 2 + h / 2 <= MESO_CONE_RADIUS);
    assert_int_equal(c->width, w);
    assert_int_equal(c->height, h);
    for (int cj = 0; cj < h; ++cj) {
        for (int ci = 0; ci < w; ++ci) {
            float top = meso_heightfield_texel(hf, ci, cj);
            top = fmaxf(top, meso_heightfield_texel(hf, ci + 1, cj));
            top = fmaxf(top, meso_heightfield_texel(hf, ci, cj + 1));
            top = fmaxf(top, meso_heightfield_texel(hf, ci + 1, cj + 1));
            double brute = 0.0;
            for (int y = 0; y < h; ++y) {
                for (int x = 0; x < w; ++x) {
                    float t = hf->heights[y * w + x];
                    if (!(t > top)) continue;
                    double d = circle_distance(x, ci, w) + circle_distance(y, cj, h);
                    brute = fmax(brute, ((double)t - (double)top) / d);
                }
            }
            const float *cell = c->cells + 2 * (cj * w + ci);
            assert_true(cell[0] == top);
            assert_true((double)cell[1] >= brute);
            assert_true((double)cell[1] <= brute * (1.0 + 1e-6) + 1e-12);
        }
    }
    for (int probe = 0; probe < 20000; ++probe) {
        int ci = rand() % w, cj = rand() % h;
        double x = (double)rand() / RAND_MAX * w, y = (double)rand() / RAND_MAX * h;
        float hq =
            meso_heightfield_sample(hf, (float)((x + 0.5) / w), (float)(1.0 - (y + 0.5) / h));
        const float *cell = c->cells + 2 * (cj * w + ci);
        double d = circle_distance(x, ci, w) + circle_distance(y, cj, h);
        assert_true((double)hq <= (double)cell[0] + (double)cell[1] * d + 1e-5);
    }
    meso_cone_map_destroy(c);
    meso_minmax_pyramid_destroy(p);
    meso_heightfield_destroy(hf);
    meso_context_destroy(ctx);
}

static void test_cones_match_a_brute_force_search(void **state) {
    (void)state;
    check_against_brute_force(16, 16, 5u);
    check_against_brute_force(13, 9, 6u); /* odd sides: the torus folds inside a patch */
    check_against_brute_force(1, 7, 8u);
}

/* Beyond the radius the field's highest texel bounds the slope: a single spike far from a
 * flat cell gives it (spike - top) / (radius + 1) however far the spike is. */
static void test_far_texels_are_bounded_by_the_field_maximum(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_heightfield *hf = NULL;
    assert_int_equal(meso_heightfield_create_constant(ctx, 128, 128, 0.25f, &hf), MESO_OK);
    hf->heights[64 * 128 + 64] = 1.0f;
    meso_heightfield_update_hash(hf);
    meso_minmax_pyramid *p = NULL;
    meso_cone_map *c = NULL;
    bake(ctx, hf, &p, &c);
    /* cell (0, 0): the spike at L1 distance 63 + 63 */
    float far = c->cells[1], near = c->cells[2 * (60 * 128 + 60) + 1];
    assert_true(fabsf(far - 0.75f / (float)(MESO_CONE_RADIUS + 1)) < 1e-6f);
    assert_true(fabsf(near - 0.75f / 6.0f) < 1e-6f); /* cell (60, 60): distance 3 + 3 */
    assert_true(c->cells[2 * (64 * 128 + 64)] == 1.0f && c->cells[2 * (64 * 128 + 64) + 1] == 0.0f);
    meso_cone_map_destroy(c);
    meso_minmax_pyramid_destroy(p);
    meso_heightfield_destroy(hf);
    meso_context_destroy(ctx);
}

static void test_one_and_two_threads_bake_the_same_bytes(void **state) {
    (void)state;
    meso_context *one = test_context(1), *two = test_context(2);
    meso_heightfield *hf = random_field(one, 200, 130, MESO_WRAP_REPEAT, 3u);
    meso_minmax_pyramid *pa = NULL, *pb = NULL;
    meso_cone_map *a = NULL, *b = NULL;
    bake(one, hf, &pa, &a);
    bake(two, hf, &pb, &b);
    assert_memory_equal(a->cells, b->cells, 2 * 200 * 130 * sizeof(float));
    meso_cone_map_destroy(a);
    meso_cone_map_destroy(b);
    meso_minmax_pyramid_destroy(pa);
    meso_minmax_pyramid_destroy(pb);
    meso_heightfield_destroy(hf);
    meso_context_destroy(one);
    meso_context_destroy(two);
}

/* Through the cache: the first call bakes and stores, the second loads the same bytes. */
static void test_cached_map_is_the_baked_map(void **state) {
    (void)state;
    setenv("MESO_CACHE_DIR", test_path(test_temp_dir(), "cone_cache"), 1);
    meso_context *ctx = test_context(2);
    meso_heightfield *hf = random_field(ctx, 64, 32, MESO_WRAP_REPEAT, 11u);
    meso_minmax_pyramid *p = NULL;
    meso_cone_map *baked = NULL, *first = NULL, *second = NULL;
    bake(ctx, hf, &p, &baked);
    assert_int_equal(meso_cone_map_bake_cached(ctx, hf, p, &first), MESO_OK);
    assert_int_equal(meso_cone_map_bake_cached(ctx, hf, p, &second), MESO_OK);
    size_t bytes = 2 * 64 * 32 * sizeof(float);
    assert_memory_equal(baked->cells, first->cells, bytes);
    assert_memory_equal(baked->cells, second->cells, bytes);
    assert_int_equal(second->width, 64);
    assert_int_equal(second->height, 32);
    meso_cone_map_destroy(baked);
    meso_cone_map_destroy(first);
    meso_cone_map_destroy(second);
    meso_minmax_pyramid_destroy(p);
    meso_heightfield_destroy(hf);
    meso_context_destroy(ctx);
    unsetenv("MESO_CACHE_DIR");
}

static void test_bad_input_is_an_invalid_argument(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_heightfield *hf = random_field(ctx, 8, 8, MESO_WRAP_CLAMP, 1u);
    meso_heightfield *other = random_field(ctx, 8, 8, MESO_WRAP_REPEAT, 2u);
    meso_minmax_pyramid *p = NULL;
    assert_int_equal(meso_minmax_pyramid_bake(ctx, hf, &p), MESO_OK);
    meso_cone_map *c = (meso_cone_map *)1;
    assert_int_equal(meso_cone_map_bake(ctx, NULL, p, &c), MESO_ERROR_INVALID_ARGUMENT);
    assert_null(c);
    assert_int_equal(meso_cone_map_bake(ctx, hf, p, &c), MESO_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(meso_context_last_error(ctx), "clamp"));
    assert_int_equal(meso_cone_map_bake(ctx, other, p, &c), MESO_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(meso_context_last_error(ctx), "pyramid"));
    assert_null(c);
    meso_minmax_pyramid_destroy(p);
    meso_heightfield_destroy(other);
    meso_heightfield_destroy(hf);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cones_match_a_brute_force_search),
        cmocka_unit_test(test_far_texels_are_bounded_by_the_field_maximum),
        cmocka_unit_test(test_one_and_two_threads_bake_the_same_bytes),
        cmocka_unit_test(test_cached_map_is_the_baked_map),
        cmocka_unit_test(test_bad_input_is_an_invalid_argument),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
