/* The maximum mip-map bounds of the relief family (relief_common.h): relief_box_max8 bounds
 * every bilinear sample relief_sample8 can read inside a box, on repeated power-of-two fields,
 * repeated fields of other sizes (boxes across the tile's seam included) and clamped ones, and
 * is tight away from a peak; relief_shadow_clear8 only clears lanes whose shadow search finds
 * nothing, so skipping their search cannot change an image. The lookups that read texels by
 * loads instead of gathers (relief_gradient8's 4 x 4 block, relief_sample8_loads,
 * v8_load_pairs) give the bits of relief_sample8 and of plain indexing. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "relief_common.h"
#include "test_util.h"
#include "meso/bake_minmax.h"

typedef struct bounds_case {
    meso_context *ctx;
    meso_heightfield *hf;
    meso_object object;
    relief_heights heights;
    meso_minmax_pyramid *pyramid;
    relief_maxmip maxmip;
} bounds_case;

static uint32_t next_random(uint32_t *state) {
    *state = *state * 1664525u + 1013904223u;
    return *state >> 8;
}
static float random_unit(uint32_t *state) { return (float)next_random(state) / 16777216.0f; }

/* A field of random heights (peak >= 0: texel 0 of row 0 at 1, the others at 0.2). */
static void case_init(bounds_case *c, int width, int height, meso_wrap wrap, bool peak,
                      uint32_t seed) {
    memset(c, 0, sizeof *c);
    c->ctx = test_context(1);
    assert_int_equal(meso_heightfield_create_constant(c->ctx, width, height, 0.0f, &c->hf),
                     MESO_OK);
    c->hf->wrap = wrap;
    for (int k = 0; k < width * height; ++k)
        c->hf->heights[k] = peak ? (k == 0 ? 1.0f : 0.2f) : random_unit(&seed);
    c->object.mesostructure.kind = MESO_MESOSTRUCTURE_HEIGHT_FIELD;
    c->object.mesostructure.height_field = c->hf;
    c->object.mesostructure.depth = 0.1f;
    strcpy(c->object.name, "objects[0]");
    assert_int_equal(relief_heights_init(c->ctx, &c->object, &c->heights), MESO_OK);
    assert_int_equal(meso_minmax_pyramid_bake(c->ctx, c->hf, &c->pyramid), MESO_OK);
    relief_maxmip_init(c->pyramid, &c->maxmip);
}

static void case_deinit(bounds_case *c) {
    relief_heights_deinit(&c->heights);
    meso_minmax_pyramid_destroy(c->pyramid);
    meso_heightfield_destroy(c->hf);
    meso_context_destroy(c->ctx);
}

/* Random boxes of 0 to 40 texels anywhere in three tiles either way; every sample of a 25 x 25
 * grid over each (borders included) lies at or under its bound. */
static void check_box_bounds(int width, int height, meso_wrap wrap) {
    bounds_case c;
    case_init(&c, width, height, wrap, false, 7u);
    uint32_t rng = 12345u;
    for (int trial = 0; trial < 400; ++trial) {
        v8f x0, x1, y0, y1;
        for (int k = 0; k < 8; ++k) {
            float sx = 40.0f * random_unit(&rng) * random_unit(&rng);
            float sy = 40.0f * random_unit(&rng) * random_unit(&rng);
            x0[k] = (6.0f * random_unit(&rng) - 3.0f) * (float)width;
            y0[k] = (6.0f * random_unit(&rng) - 3.0f) * (float)height;
            if (trial % 4 == 0) x0[k] = (float)width - 0.5f * sx; /* across the seam */
            x1[k] = x0[k] + sx;
            y1[k] = y0[k] + sy;
        }
        v8f bound = relief_box_max8(&c.maxmip, &c.heights, x0, x1, y0, y1);
        for (int a = 0; a <= 24; ++a)
            for (int b = 0; b <= 24; ++b) {
                v8f fa = v8_splat((float)a / 24.0f), fb = v8_splat((float)b / 24.0f);
                v8f h = relief_sample8(&c.heights, x0 + (x1 - x0) * fa, y0 + (y1 - y0) * fb);
                for (int k = 0; k < 8; ++k)
                    if (!(h[k] <= bound[k])) {
                        fprintf(stderr, "%dx%d: box [%g, %g] x [%g, %g]: sample %g > bound %g\n",
                                width, height, (double)x0[k], (double)x1[k], (double)y0[k],
                                (double)y1[k], (double)h[k], (double)bound[k]);
                        fail();
                    }
            }
    }
    case_deinit(&c);
}

static void test_box_max_bounds_every_sample_repeat_power_of_two(void **state) {
    (void)state;
    check_box_bounds(64, 32, MESO_WRAP_REPEAT);
}

static void test_box_max_bounds_every_sample_repeat_other_sizes(void **state) {
    (void)state;
    check_box_bounds(48, 37, MESO_WRAP_REPEAT);
}

static void test_box_max_bounds_every_sample_clamp(void **state) {
    (void)state;
    check_box_bounds(64, 64, MESO_WRAP_CLAMP);
    check_box_bounds(45, 30, MESO_WRAP_CLAMP);
}

/* One peak at texel (0, 0), 0.2 elsewhere: a small box far from it is bounded by 0.2 exactly,
 * also across the seam of a repeated field (a bound that fell back to the field's maximum
 * would say 1); a box holding the peak's patch says 1. */
static void test_box_max_is_tight_away_from_a_peak(void **state) {
    (void)state;
    bounds_case c;
    case_init(&c, 64, 64, MESO_WRAP_REPEAT, true, 1u);
    v8f x0 = {20.0f, 62.2f, 126.0f, -30.0f, 10.0f, 0.2f, 63.5f, -0.5f};
    v8f y0 = {20.0f, 30.0f, 40.3f, 10.0f, 63.3f, 0.2f, 63.5f, -0.5f};
    v8f x1 = x0 + (v8f){3.0f, 3.0f, 1.0f, 7.5f, 2.0f, 0.1f, 0.2f, 0.2f};
    v8f y1 = y0 + (v8f){2.0f, 5.0f, 1.0f, 7.5f, 2.0f, 0.1f, 0.2f, 0.2f};
    v8f bound = relief_box_max8(&c.maxmip, &c.heights, x0, x1, y0, y1);
    for (int k = 0; k < 5; ++k) assert_float_equal(bound[k], 0.2f, 0.0f);
    for (int k = 5; k < 8; ++k) assert_float_equal(bound[k], 1.0f, 0.0f);
    case_deinit(&c);
}

/* Random light rays from random depths (with bulges either way): a lane cleared without
 * sampling is never blocked by the search, at 16 or 256 steps; and some lanes are cleared. */
static void test_shadow_clear_only_lanes_the_search_finds_lit(void **state) {
    (void)state;
    int sizes[3][2] = {{64, 64}, {48, 40}, {64, 64}};
    meso_wrap wraps[3] = {MESO_WRAP_REPEAT, MESO_WRAP_REPEAT, MESO_WRAP_CLAMP};
    int cleared = 0, lanes = 0;
    for (int f = 0; f < 3; ++f) {
        bounds_case c;
        case_init(&c, sizes[f][0], sizes[f][1], wraps[f], false, 99u + (uint32_t)f);
        /* a smoother field: random heights squeezed into [0.7, 0.9] with a few deep texels */
        for (int k = 0; k < sizes[f][0] * sizes[f][1]; ++k)
            c.hf->heights[k] = 0.7f + 0.2f * c.hf->heights[k];
        relief_heights_deinit(&c.heights);
        meso_minmax_pyramid_destroy(c.pyramid);
        assert_int_equal(relief_heights_init(c.ctx, &c.object, &c.heights), MESO_OK);
        assert_int_equal(meso_minmax_pyramid_bake(c.ctx, c.hf, &c.pyramid), MESO_OK);
        relief_maxmip_init(c.pyramid, &c.maxmip);
        uint32_t rng = 4242u;
        for (int trial = 0; trial < 2000; ++trial) {
            relief_shadow_batch s;
            memset(&s, 0, sizeof s);
            s.count = 8;
            s.active_bits = 0xff;
            for (int k = 0; k < 8; ++k) {
                s.x[k] = (4.0f * random_unit(&rng) - 2.0f) * (float)sizes[f][0];
                s.y[k] = (4.0f * random_unit(&rng) - 2.0f) * (float)sizes[f][1];
                float length = 12.0f * random_unit(&rng) * random_unit(&rng);
                float angle = 6.2831853f * random_unit(&rng);
                s.xd[k] = length * cosf(angle);
                s.yd[k] = length * sinf(angle);
                s.d[k] = 0.35f * random_unit(&rng);
                s.bulge[k] = 0.3f * random_unit(&rng) - 0.1f;
            }
            int clear = relief_shadow_clear8(&c.maxmip, &c.heights, &s);
            assert_int_equal(clear & ~s.active_bits, 0);
            relief_shadow_batch only = s;
            only.active_bits = clear;
            assert_int_equal(relief_shadow_search8(&c.heights, &only, 16), 0);
            assert_int_equal(relief_shadow_search8(&c.heights, &only, 256), 0);
            cleared += __builtin_popcount((unsigned)clear);
            lanes += 8;
        }
        case_deinit(&c);
    }
    printf("cleared %d of %d random lanes\n", cleared, lanes);
    assert_true(cleared > lanes / 10);
}

/* relief_gradient8 against its definition by relief_sample8 (central differences one texel
 * apart) and relief_sample8_loads against relief_sample8, bit for bit: groups whose eight lanes
 * lie well inside the field (the loads' paths of an AVX2 build) and groups anywhere in three
 * tiles either way (wraps, clamped borders: the gathers' paths). v8_load_pairs against plain
 * indexing. */
static void test_loaded_lookups_match_the_gathers(void **state) {
    (void)state;
    int sizes[3][2] = {{64, 64}, {48, 40}, {64, 64}};
    meso_wrap wraps[3] = {MESO_WRAP_REPEAT, MESO_WRAP_REPEAT, MESO_WRAP_CLAMP};
    for (int f = 0; f < 3; ++f) {
        bounds_case c;
        case_init(&c, sizes[f][0], sizes[f][1], wraps[f], false, 31u + (uint32_t)f);
        const relief_heights *m = &c.heights;
        float w = (float)m->width, h = (float)m->height;
        uint32_t rng = 777u;
        for (int trial = 0; trial < 4000; ++trial) {
            bool inside = trial % 2 == 0;
            v8f x, y;
            for (int k = 0; k < 8; ++k) {
                x[k] = inside ? 2.0f + (w - 5.0f) * random_unit(&rng)
                              : (6.0f * random_unit(&rng) - 3.0f) * w;
                y[k] = inside ? 2.0f + (h - 5.0f) * random_unit(&rng)
                              : (6.0f * random_unit(&rng) - 3.0f) * h;
            }
            if (trial % 7 == 0) x[3] = floorf(x[3]), y[5] = floorf(y[5]); /* on texel centres */
            v8f gu, gv;
            relief_gradient8(m, x, y, &gu, &gv);
            v8f want_gu =
                (relief_sample8(m, x + 1.0f, y) - relief_sample8(m, x - 1.0f, y)) * (0.5f * w);
            v8f want_gv =
                (relief_sample8(m, x, y - 1.0f) - relief_sample8(m, x, y + 1.0f)) * (0.5f * h);
            assert_memory_equal(&gu, &want_gu, sizeof gu);
            assert_memory_equal(&gv, &want_gv, sizeof gv);
            v8f loaded = relief_sample8_loads(m, x, y), gathered = relief_sample8(m, x, y);
            assert_memory_equal(&loaded, &gathered, sizeof loaded);
        }
        v8i index;
        for (int k = 0; k < 8; ++k)
            index[k] = (int32_t)(next_random(&rng) % (uint32_t)(m->stride * m->height));
        v8f left, right;
        v8_load_pairs(m->padded, index, &left, &right);
        for (int k = 0; k < 8; ++k) {
            assert_true(left[k] == m->padded[index[k]]);
            assert_true(right[k] == m->padded[index[k] + 1]);
        }
        case_deinit(&c);
    }
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_box_max_bounds_every_sample_repeat_power_of_two),
        cmocka_unit_test(test_box_max_bounds_every_sample_repeat_other_sizes),
        cmocka_unit_test(test_box_max_bounds_every_sample_clamp),
        cmocka_unit_test(test_box_max_is_tight_away_from_a_peak),
        cmocka_unit_test(test_shadow_clear_only_lanes_the_search_finds_lit),
        cmocka_unit_test(test_loaded_lookups_match_the_gathers),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
