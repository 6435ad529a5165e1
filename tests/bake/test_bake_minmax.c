/* Min-max pyramids (bake_minmax.h): every level bounds the bilinear surface over its cells'
 * footprints, the shape of the levels, errors, and byte identity across thread counts. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"
#include "meso/bake_minmax.h"

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

/* Random points in each probed cell's footprint (texel-centre coordinates x = u W - 0.5):
 * the bilinear height lies within [min, max] of the cell. */
static void check_bounds(const meso_heightfield *hf, const meso_minmax_pyramid *p) {
    for (int l = 0; l < p->num_levels; ++l) {
        const meso_minmax_level *lv = &p->levels[l];
        for (int probe = 0; probe < 400; ++probe) {
            int cx = rand() % lv->width, cy = rand() % lv->height;
            float size = (float)(1 << l);
            float x_hi = fminf((float)(cx + 1) * size, (float)hf->width);
            float y_hi = fminf((float)(cy + 1) * size, (float)hf->height);
            float rx = (float)rand() / (float)RAND_MAX, ry = (float)rand() / (float)RAND_MAX;
            float x = (float)cx * size + rx * (x_hi - (float)cx * size);
            float y = (float)cy * size + ry * (y_hi - (float)cy * size);
            if (hf->wrap == MESO_WRAP_CLAMP &&
                (x > (float)hf->width - 1 || y > (float)hf->height - 1))
                continue; /* clamp: beyond the last texel centre the field is the edge's */
            float h = meso_heightfield_sample(hf, (x + 0.5f) / (float)hf->width,
                                              1.0f - (y + 0.5f) / (float)hf->height);
            size_t k = (size_t)cy * (size_t)lv->width + (size_t)cx;
            assert_true(h <= lv->max[k] + 1e-6f);
            assert_true(h >= lv->min[k] - 1e-6f);
        }
    }
}

static void test_every_level_bounds_the_bilinear_surface(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_wrap wraps[2] = {MESO_WRAP_REPEAT, MESO_WRAP_CLAMP};
    for (int w = 0; w < 2; ++w) {
        meso_heightfield *hf = random_field(ctx, 37, 23, wraps[w], 7u + (unsigned)w);
        meso_minmax_pyramid *p = NULL;
        assert_int_equal(meso_minmax_pyramid_bake(ctx, hf, &p), MESO_OK);
        assert_int_equal(p->num_levels, 7); /* 37 -> 19 -> 10 -> 5 -> 3 -> 2 -> 1 */
        assert_int_equal(p->levels[0].width, 37);
        assert_int_equal(p->levels[0].height, 23);
        assert_int_equal(p->levels[6].width, 1);
        assert_int_equal(p->levels[6].height, 1);
        float hi = 0.0f, lo = 1.0f;
        for (int k = 0; k < 37 * 23; ++k) {
            hi = fmaxf(hi, hf->heights[k]);
            lo = fminf(lo, hf->heights[k]);
        }
        assert_true(p->levels[6].max[0] == hi);
        assert_true(p->levels[6].min[0] == lo);
        check_bounds(hf, p);
        meso_minmax_pyramid_destroy(p);
        meso_heightfield_destroy(hf);
    }
    meso_context_destroy(ctx);
}

static void test_one_and_two_threads_bake_the_same_bytes(void **state) {
    (void)state;
    meso_context *one = test_context(1), *two = test_context(2);
    meso_heightfield *hf = random_field(one, 200, 130, MESO_WRAP_REPEAT, 3u);
    meso_minmax_pyramid *a = NULL, *b = NULL;
    assert_int_equal(meso_minmax_pyramid_bake(one, hf, &a), MESO_OK);
    assert_int_equal(meso_minmax_pyramid_bake(two, hf, &b), MESO_OK);
    assert_int_equal(a->block_floats, b->block_floats);
    assert_memory_equal(a->block, b->block, a->block_floats * sizeof(float));
    meso_minmax_pyramid_destroy(a);
    meso_minmax_pyramid_destroy(b);
    meso_heightfield_destroy(hf);
    meso_context_destroy(one);
    meso_context_destroy(two);
}

static void test_missing_field_is_an_invalid_argument(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_minmax_pyramid *p = (meso_minmax_pyramid *)1;
    assert_int_equal(meso_minmax_pyramid_bake(ctx, NULL, &p), MESO_ERROR_INVALID_ARGUMENT);
    assert_null(p);
    assert_non_null(strstr(meso_context_last_error(ctx), "heightfield"));
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_level_bounds_the_bilinear_surface),
        cmocka_unit_test(test_one_and_two_threads_bake_the_same_bytes),
        cmocka_unit_test(test_missing_field_is_an_invalid_argument),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
