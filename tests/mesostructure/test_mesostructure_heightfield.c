/* Height fields: procedural generators (tiling, determinism, range), sampling, wrapping,
 * gradients, PNG round trip, errors. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"
#include "meso/runtime.h"

static const meso_heightfield_kind all_kinds[] = {MESO_HEIGHTFIELD_BRICKS, MESO_HEIGHTFIELD_BUMPS,
                                                  MESO_HEIGHTFIELD_WEAVE, MESO_HEIGHTFIELD_TILES,
                                                  MESO_HEIGHTFIELD_BARK};
#define NUM_KINDS (sizeof(all_kinds) / sizeof(all_kinds[0]))

static meso_heightfield *make(meso_context *ctx, meso_heightfield_kind kind, int resolution,
                              meso_image **out_color) {
    meso_heightfield_desc desc = {.kind = kind, .resolution = resolution};
    meso_heightfield *hf = NULL;
    assert_int_equal(meso_heightfield_create_procedural(ctx, &desc, &hf, out_color), MESO_OK);
    assert_non_null(hf);
    return hf;
}

static float texel(const meso_heightfield *hf, int i, int j) {
    return hf->heights[(size_t)j * (size_t)hf->width + (size_t)i];
}

static void test_procedural_heightfields_tile_across_the_border(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    for (size_t k = 0; k < NUM_KINDS; k++) {
        meso_heightfield *hf = make(ctx, all_kinds[k], 128, NULL);
        /* The step across the seam is no larger than the largest step inside the tile. */
        float inner_u = 0.0f, seam_u = 0.0f, inner_v = 0.0f, seam_v = 0.0f;
        for (int j = 0; j < hf->height; j++) {
            for (int i = 0; i + 1 < hf->width; i++)
                inner_u = fmaxf(inner_u, fabsf(texel(hf, i + 1, j) - texel(hf, i, j)));
            seam_u = fmaxf(seam_u, fabsf(texel(hf, 0, j) - texel(hf, hf->width - 1, j)));
        }
        for (int i = 0; i < hf->width; i++) {
            for (int j = 0; j + 1 < hf->height; j++)
                inner_v = fmaxf(inner_v, fabsf(texel(hf, i, j + 1) - texel(hf, i, j)));
            seam_v = fmaxf(seam_v, fabsf(texel(hf, i, 0) - texel(hf, i, hf->height - 1)));
        }
        assert_true(seam_u <= inner_u + 1e-6f);
        assert_true(seam_v <= inner_v + 1e-6f);
        /* Sampling one tile over gives the same surface. */
        for (int s = 0; s < 200; s++) {
            float u = (float)((s * 37) % 101) / 101.0f, v = (float)((s * 53) % 97) / 97.0f;
            float h = meso_heightfield_sample(hf, u, v);
            assert_float_equal(h, meso_heightfield_sample(hf, u + 1.0f, v), 1e-3);
            assert_float_equal(h, meso_heightfield_sample(hf, u, v + 1.0f), 1e-3);
            assert_float_equal(h, meso_heightfield_sample(hf, u - 1.0f, v - 1.0f), 1e-3);
        }
        meso_heightfield_destroy(hf);
    }
    meso_context_destroy(ctx);
}

static void test_procedural_heightfields_are_deterministic_in_range_and_varied(void **state) {
    (void)state;
    meso_context *ctx1 = test_context(1), *ctx2 = test_context(2);
    for (size_t k = 0; k < NUM_KINDS; k++) {
        meso_image *color1 = NULL, *color2 = NULL;
        meso_heightfield *a = make(ctx1, all_kinds[k], 96, &color1);
        meso_heightfield *b = make(ctx2, all_kinds[k], 96, &color2);
        size_t n = (size_t)a->width * (size_t)a->height;
        assert_memory_equal(a->heights, b->heights, n * sizeof(float));
        assert_memory_equal(color1->pixels, color2->pixels, n * 3 * sizeof(float));
        assert_true(a->hash == b->hash);
        /* Asking for the colours does not change the heights. */
        meso_heightfield *no_color = make(ctx2, all_kinds[k], 96, NULL);
        assert_memory_equal(a->heights, no_color->heights, n * sizeof(float));
        meso_heightfield_destroy(no_color);
        assert_int_equal(color1->channels, 3);
        float lo = 1.0f, hi = 0.0f, clo = 1.0f, chi = 0.0f;
        for (size_t t = 0; t < n; t++) {
            lo = fminf(lo, a->heights[t]);
            hi = fmaxf(hi, a->heights[t]);
            for (int c = 0; c < 3; c++) {
                clo = fminf(clo, color1->pixels[t * 3 + (size_t)c]);
                chi = fmaxf(chi, color1->pixels[t * 3 + (size_t)c]);
            }
        }
        assert_true(lo >= 0.0f && hi <= 1.0f);
        assert_true(hi - lo > 0.5f);
        assert_true(clo >= 0.0f && chi <= 1.0f && chi - clo > 0.05f);
        meso_image_destroy(color1);
        meso_image_destroy(color2);
        meso_heightfield_destroy(a);
        meso_heightfield_destroy(b);
    }
    meso_context_destroy(ctx1);
    meso_context_destroy(ctx2);
}

static void test_seed_and_parameters_change_the_field(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_heightfield *a = NULL, *b = NULL;
    meso_heightfield_desc desc = {.kind = MESO_HEIGHTFIELD_BRICKS, .resolution = 64};
    assert_int_equal(meso_heightfield_create_procedural(ctx, &desc, &a, NULL), MESO_OK);
    desc.seed = 2;
    assert_int_equal(meso_heightfield_create_procedural(ctx, &desc, &b, NULL), MESO_OK);
    assert_true(a->hash != b->hash);
    assert_true(memcmp(a->heights, b->heights, 64 * 64 * sizeof(float)) != 0);
    meso_heightfield_destroy(a);
    meso_heightfield_destroy(b);
    meso_context_destroy(ctx);
}

static void test_bricks_have_grooves_near_zero_and_tops_near_one(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_heightfield *hf = make(ctx, MESO_HEIGHTFIELD_BRICKS, 256, NULL);
    /* Default 4 rows x 2 columns: the horizontal mortar line between rows 0 and 1 is at
     * v = 0.25, the middle of a row-0 brick at v = 0.125. */
    assert_true(meso_heightfield_sample(hf, 0.3f, 0.25f) < 0.1f);
    assert_true(meso_heightfield_sample(hf, 0.25f, 0.125f) > 0.85f);
    meso_heightfield_destroy(hf);
    meso_context_destroy(ctx);
}

static void test_defaults_fill_zero_fields(void **state) {
    (void)state;
    meso_heightfield_desc d = meso_heightfield_desc_defaults(NULL);
    assert_int_equal(d.kind, MESO_HEIGHTFIELD_BRICKS);
    assert_int_equal(d.resolution, 512);
    assert_int_equal(d.rows, 4);
    assert_int_equal(d.columns, 2);
    assert_float_equal(d.gap, 0.08f, 1e-7);
    assert_float_equal(d.bevel, 0.04f, 1e-7);
    assert_int_equal(d.seed, 1);
    assert_int_equal(d.wrap, MESO_WRAP_REPEAT);
    d = meso_heightfield_desc_defaults(&(meso_heightfield_desc){.kind = MESO_HEIGHTFIELD_BUMPS});
    assert_int_equal(d.rows, 4);
    assert_int_equal(d.columns, 4);
    meso_heightfield_kind kind;
    for (size_t k = 0; k < NUM_KINDS; k++) {
        assert_true(
            meso_heightfield_kind_from_name(meso_heightfield_kind_name(all_kinds[k]), &kind));
        assert_int_equal(kind, all_kinds[k]);
    }
    assert_false(meso_heightfield_kind_from_name("brick", &kind));
}

static void test_invalid_descs_name_the_field(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_heightfield *hf = (meso_heightfield *)1;
    meso_heightfield_desc desc = {.kind = MESO_HEIGHTFIELD_WEAVE, .rows = 3, .resolution = 16};
    assert_int_equal(meso_heightfield_create_procedural(ctx, &desc, &hf, NULL),
                     MESO_ERROR_INVALID_ARGUMENT);
    assert_null(hf);
    assert_non_null(strstr(meso_context_last_error(ctx), "weave"));
    desc = (meso_heightfield_desc){.resolution = MESO_IMAGE_MAX_SIDE + 1};
    assert_int_equal(meso_heightfield_create_procedural(ctx, &desc, &hf, NULL), MESO_ERROR_LIMIT);
    assert_non_null(strstr(meso_context_last_error(ctx), "resolution"));
    desc = (meso_heightfield_desc){.gap = -0.5f, .resolution = 16};
    assert_int_equal(meso_heightfield_create_procedural(ctx, &desc, &hf, NULL),
                     MESO_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(meso_context_last_error(ctx), "gap"));
    desc = (meso_heightfield_desc){.roughness = NAN, .resolution = 16};
    assert_int_equal(meso_heightfield_create_procedural(ctx, &desc, &hf, NULL),
                     MESO_ERROR_INVALID_ARGUMENT);
    assert_int_equal(meso_heightfield_create_constant(ctx, 4, 4, 2.0f, &hf),
                     MESO_ERROR_INVALID_ARGUMENT);
    assert_int_equal(meso_heightfield_create_constant(ctx, 0, 4, 0.5f, &hf),
                     MESO_ERROR_INVALID_ARGUMENT);
    meso_context_destroy(ctx);
}

/* A 4x3 field with distinct texels. */
static meso_heightfield *make_grid(meso_context *ctx, meso_wrap wrap) {
    meso_image *image = NULL;
    assert_int_equal(meso_image_create(ctx, 4, 3, 1, &image), MESO_OK);
    for (int k = 0; k < 12; k++) image->pixels[k] = (float)((k * 5) % 12) / 11.0f;
    meso_heightfield *hf = NULL;
    assert_int_equal(meso_heightfield_create_from_image(ctx, image, wrap, &hf), MESO_OK);
    meso_image_destroy(image);
    return hf;
}

static void test_sample_is_bilinear_between_texel_centres(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_heightfield *hf = make_grid(ctx, MESO_WRAP_REPEAT);
    for (int j = 0; j < 3; j++)
        for (int i = 0; i < 4; i++) {
            float u = ((float)i + 0.5f) / 4.0f, v = 1.0f - ((float)j + 0.5f) / 3.0f;
            assert_float_equal(meso_heightfield_sample(hf, u, v), texel(hf, i, j), 1e-6);
        }
    /* Midway between texels (1,1) and (2,1): their mean; at the centre of four: the mean of
     * all four. */
    float v1 = 1.0f - 1.5f / 3.0f;
    assert_float_equal(meso_heightfield_sample(hf, 0.5f, v1),
                       0.5f * (texel(hf, 1, 1) + texel(hf, 2, 1)), 1e-6);
    float mean4 = 0.25f * (texel(hf, 1, 0) + texel(hf, 2, 0) + texel(hf, 1, 1) + texel(hf, 2, 1));
    assert_float_equal(meso_heightfield_sample(hf, 0.5f, 1.0f - 1.0f / 3.0f), mean4, 1e-6);
    meso_heightfield_destroy(hf);
    meso_context_destroy(ctx);
}

static void test_clamp_and_repeat_differ_at_the_border(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_heightfield *repeat = make_grid(ctx, MESO_WRAP_REPEAT);
    meso_heightfield *clamp = make_grid(ctx, MESO_WRAP_CLAMP);
    float v = 1.0f - 0.5f / 3.0f; /* row 0's centre */
    /* u = 0 is half a texel left of texel 0's centre: clamp holds texel 0, repeat blends with
     * the last column. */
    assert_float_equal(meso_heightfield_sample(clamp, 0.0f, v), texel(clamp, 0, 0), 1e-6);
    assert_float_equal(meso_heightfield_sample(repeat, 0.0f, v),
                       0.5f * (texel(repeat, 0, 0) + texel(repeat, 3, 0)), 1e-6);
    assert_float_equal(meso_heightfield_sample(clamp, 1.0f, v), texel(clamp, 3, 0), 1e-6);
    assert_float_equal(meso_heightfield_texel(clamp, -5, 7), texel(clamp, 0, 2), 0.0);
    assert_float_equal(meso_heightfield_texel(repeat, -1, 4), texel(repeat, 3, 1), 0.0);
    assert_true(repeat->hash != clamp->hash);
    meso_heightfield_destroy(repeat);
    meso_heightfield_destroy(clamp);
    meso_context_destroy(ctx);
}

static void test_gradient_of_a_linear_ramp_is_exact(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_heightfield *hf = NULL;
    assert_int_equal(meso_heightfield_create_constant(ctx, 32, 16, 0.0f, &hf), MESO_OK);
    uint64_t before = hf->hash;
    /* h = a i + b (H-1-j): dh/du = a W, dh/dv = b H (v grows upward, rows downward). */
    const float a = 0.01f, b = 0.02f;
    for (int j = 0; j < 16; j++)
        for (int i = 0; i < 32; i++) hf->heights[j * 32 + i] = a * (float)i + b * (float)(15 - j);
    meso_heightfield_update_hash(hf);
    assert_true(hf->hash != before);
    meso_vec2 g = meso_heightfield_gradient(hf, 0.4f, 0.55f);
    assert_float_equal(g.x, a * 32.0f, 1e-3);
    assert_float_equal(g.y, b * 16.0f, 1e-3);
    meso_heightfield_destroy(hf);
    meso_context_destroy(ctx);
}

static void test_png_height_map_round_trips(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_image *image = NULL;
    assert_int_equal(meso_image_create(ctx, 40, 20, 1, &image), MESO_OK);
    for (int j = 0; j < 20; j++)
        for (int i = 0; i < 40; i++) *meso_image_at(image, i, j) = (float)(i * 20 + j) / 799.0f;
    const char *path = test_path(test_temp_dir(), "ramp16.png");
    meso_png_desc png = {.bit_depth = 16, .encoding = MESO_ENCODING_LINEAR};
    assert_int_equal(meso_image_save_png(ctx, image, path, &png), MESO_OK);
    meso_heightfield *hf = NULL;
    assert_int_equal(meso_heightfield_load_png(ctx, path, MESO_WRAP_CLAMP, &hf), MESO_OK);
    assert_int_equal(hf->width, 40);
    assert_int_equal(hf->height, 20);
    assert_int_equal(hf->wrap, MESO_WRAP_CLAMP);
    for (int j = 0; j < 20; j++)
        for (int i = 0; i < 40; i++)
            assert_float_equal(texel(hf, i, j), *meso_image_at(image, i, j),
                               (float)(1.0 / 65535.0));
    meso_heightfield_destroy(hf);
    meso_image_destroy(image);

    hf = (meso_heightfield *)1;
    const char *missing = test_path(test_temp_dir(), "no-such-height.png");
    assert_int_equal(meso_heightfield_load_png(ctx, missing, MESO_WRAP_REPEAT, &hf), MESO_ERROR_IO);
    assert_null(hf);
    assert_non_null(strstr(meso_context_last_error(ctx), "no-such-height.png"));
    meso_context_destroy(ctx);
}

/* Defect: an RGB map whose red channel is constant rendered silently flat. */
static void test_colour_height_maps_read_as_luminance(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    for (int channels = 3; channels <= 4; channels++) {
        meso_image *image = NULL;
        assert_int_equal(meso_image_create(ctx, 8, 4, channels, &image), MESO_OK);
        for (int j = 0; j < 4; j++)
            for (int i = 0; i < 8; i++) {
                float *p = meso_image_at(image, i, j);
                p[0] = 0.5f;                     /* red constant */
                p[1] = (float)i / 7.0f;          /* green: a ramp */
                p[2] = (float)j / 3.0f;          /* blue: another */
                if (channels == 4) p[3] = 0.25f; /* alpha: ignored */
            }
        meso_heightfield *hf = NULL;
        assert_int_equal(meso_heightfield_create_from_image(ctx, image, MESO_WRAP_REPEAT, &hf),
                         MESO_OK);
        for (int j = 0; j < 4; j++)
            for (int i = 0; i < 8; i++) {
                double expected = 0.2126 * 0.5 + 0.7152 * i / 7.0 + 0.0722 * j / 3.0;
                assert_float_equal(texel(hf, i, j), expected, 1e-6);
            }
        meso_heightfield_destroy(hf);
        meso_image_destroy(image);
    }
    /* grey + alpha: the grey */
    meso_image *grey = NULL;
    assert_int_equal(meso_image_create(ctx, 2, 1, 2, &grey), MESO_OK);
    grey->pixels[0] = 0.25f, grey->pixels[1] = 1.0f, grey->pixels[2] = 0.75f,
    grey->pixels[3] = 0.0f;
    meso_heightfield *hf = NULL;
    assert_int_equal(meso_heightfield_create_from_image(ctx, grey, MESO_WRAP_REPEAT, &hf), MESO_OK);
    assert_float_equal(texel(hf, 0, 0), 0.25, 0.0);
    assert_float_equal(texel(hf, 1, 0), 0.75, 0.0);
    meso_heightfield_destroy(hf);
    meso_image_destroy(grey);
    meso_context_destroy(ctx);
}

static void test_constant_height_map_warns_naming_the_file(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_image *image = NULL;
    assert_int_equal(meso_image_create(ctx, 8, 8, 3, &image), MESO_OK);
    for (size_t k = 0; k < 8 * 8 * 3; k++) image->pixels[k] = 0.6f;
    const char *path = test_path(test_temp_dir(), "constant-height.png");
    meso_png_desc png = {.bit_depth = 8, .encoding = MESO_ENCODING_LINEAR};
    assert_int_equal(meso_image_save_png(ctx, image, path, &png), MESO_OK);
    meso_heightfield *hf = NULL;
    assert_int_equal(meso_heightfield_load_png(ctx, path, MESO_WRAP_REPEAT, &hf), MESO_OK);
    assert_non_null(strstr(test_last_warning(), "constant-height.png: the height map is constant"));
    meso_heightfield_destroy(hf);
    /* a varied map gives no warning */
    image->pixels[5] = 0.1f;
    meso_log_warning(ctx, "%s", "none");
    assert_int_equal(meso_image_save_png(ctx, image, path, &png), MESO_OK);
    assert_int_equal(meso_heightfield_load_png(ctx, path, MESO_WRAP_REPEAT, &hf), MESO_OK);
    assert_string_equal(test_last_warning(), "none");
    meso_heightfield_destroy(hf);
    meso_image_destroy(image);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_procedural_heightfields_tile_across_the_border),
        cmocka_unit_test(test_procedural_heightfields_are_deterministic_in_range_and_varied),
        cmocka_unit_test(test_seed_and_parameters_change_the_field),
        cmocka_unit_test(test_bricks_have_grooves_near_zero_and_tops_near_one),
        cmocka_unit_test(test_defaults_fill_zero_fields),
        cmocka_unit_test(test_invalid_descs_name_the_field),
        cmocka_unit_test(test_sample_is_bilinear_between_texel_centres),
        cmocka_unit_test(test_clamp_and_repeat_differ_at_the_border),
        cmocka_unit_test(test_gradient_of_a_linear_ramp_is_exact),
        cmocka_unit_test(test_png_height_map_round_trips),
        cmocka_unit_test(test_colour_height_maps_read_as_luminance),
        cmocka_unit_test(test_constant_height_map_warns_naming_the_file),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
