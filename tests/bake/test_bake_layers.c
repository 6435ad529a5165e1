/* Multilayer relief maps (bake_layers.c): analytic layers of slabs and bars, the 4- and
 * 8-layer limits, height fields as one layer, the file round trip and refusal of corrupted or
 * inconsistent files, determinism across thread counts. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"

/* Exact signed distances in (u, v, w) (1-Lipschitz, negative inside). */
static float slab_field(void *user, meso_vec3 p) {
    (void)user;
    return 0.5f - p.z; /* solid below w = 0.5 */
}

static float interval(float x, float lo, float hi) { return fmaxf(lo - x, x - hi); }

/* Three plates w in [0.1, 0.2], [0.4, 0.5], [0.7, 0.8]: six crossings down every texel. */
static float plates_field(void *user, meso_vec3 p) {
    (void)user;
    return fminf(fminf(interval(p.z, 0.1f, 0.2f), interval(p.z, 0.4f, 0.5f)),
                 interval(p.z, 0.7f, 0.8f));
}

/* A bar along u at v in [0.4, 0.6], w in [0.2, 0.4], over a floor w >= 0.8. */
static float bar_field(void *user, meso_vec3 p) {
    (void)user;
    float bar = fmaxf(interval(p.y, 0.4f, 0.6f), interval(p.z, 0.2f, 0.4f));
    return fminf(bar, 0.8f - p.z);
}

static meso_layers *bake(meso_context *ctx, meso_scalar_field_fn fn, int layers,
                         meso_layers_format format) {
    meso_layers *map = NULL;
    meso_layers_desc desc = {
        .field = fn, .width = 32, .height = 32, .num_layers = layers, .format = format};
    assert_int_equal(meso_layers_bake(ctx, &desc, &map), MESO_OK);
    return map;
}

static const float *texel_depths(const meso_layers *m, int i, int j) {
    return m->depth + ((size_t)j * (size_t)m->width + (size_t)i) * (size_t)m->num_layers;
}

static void test_slab_is_one_entry_and_the_floor(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_layers *m = bake(ctx, slab_field, 4, MESO_LAYERS_FORMAT_F32);
    for (int j = 0; j < 32; j++)
        for (int i = 0; i < 32; i++) {
            const float *d = texel_depths(m, i, j);
            assert_int_equal(m->count[j * 32 + i], 2);
            assert_true(fabsf(d[0] - 0.5f) < 1e-5f);
            assert_true(fabsf(d[1] - 1.0f) < 1e-5f);
            assert_true(d[2] == 1.0f && d[3] == 1.0f); /* unused = 1.0 (Fig. 5) */
            meso_vec3 n = meso_layers_normal(m, i, j, 0);
            assert_true(fabsf(n.z - 1.0f) < 1e-4f); /* the entry faces up */
        }
    assert_int_equal(m->max_count, 2);
    assert_int_equal(m->clipped_texels, 0);
    meso_layers_destroy(m);
    meso_context_destroy(ctx);
}

static void test_bar_over_floor_has_four_layers_under_the_bar_only(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_layers *m = bake(ctx, bar_field, 4, MESO_LAYERS_FORMAT_F32);
    for (int j = 0; j < 32; j++) {
        float v = 1.0f - ((float)j + 0.5f) / 32.0f;
        const float *d = texel_depths(m, 5, j);
        if (v > 0.4f && v < 0.6f) {
            assert_int_equal(m->count[j * 32 + 5], 4);
            assert_true(fabsf(d[0] - 0.2f) < 1e-5f && fabsf(d[1] - 0.4f) < 1e-5f);
            assert_true(fabsf(d[2] - 0.8f) < 1e-5f);
            assert_true(meso_layers_normal(m, 5, j, 1).z < -0.99f); /* the bar's underside */
        } else {
            assert_int_equal(m->count[j * 32 + 5], 2);
            assert_true(fabsf(d[0] - 0.8f) < 1e-5f);
        }
    }
    meso_layers_destroy(m);
    meso_context_destroy(ctx);
}

static void test_eight_layers_keep_six_crossings_four_clip_them(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_layers *eight = bake(ctx, plates_field, 8, MESO_LAYERS_FORMAT_F32);
    const float expect[6] = {0.1f, 0.2f, 0.4f, 0.5f, 0.7f, 0.8f};
    for (int t = 0; t < 32 * 32; t++) {
        assert_int_equal(eight->count[t], 6);
        for (int k = 0; k < 6; k++)
            assert_true(fabsf(eight->depth[(size_t)t * 8 + (size_t)k] - expect[k]) < 1e-5f);
        assert_true(eight->depth[(size_t)t * 8 + 6] == 1.0f);
    }
    assert_int_equal(eight->clipped_texels, 0);
    assert_int_equal(eight->clipped_at_four, 32 * 32); /* what the paper's limit would clip */
    assert_int_equal(eight->max_crossings, 6);
    meso_layers *four = bake(ctx, plates_field, 4, MESO_LAYERS_FORMAT_F32);
    assert_int_equal(four->clipped_texels, 32 * 32);
    assert_int_equal(four->count[0], 4);
    meso_layers_destroy(eight);
    meso_layers_destroy(four);
    meso_context_destroy(ctx);
}

static float h_ramp(int i, int j) { return (float)(i + 2 * j) / 100.0f; }

static void test_height_field_is_one_layer_of_one_minus_h(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_heightfield *hf = NULL;
    assert_int_equal(meso_heightfield_create_constant(ctx, 16, 8, 0.0f, &hf), MESO_OK);
    for (int j = 0; j < 8; j++)
        for (int i = 0; i < 16; i++) hf->heights[j * 16 + i] = h_ramp(i, j);
    meso_heightfield_update_hash(hf);
    meso_layers *m = NULL;
    meso_layers_desc desc = {.heightfield = hf, .format = MESO_LAYERS_FORMAT_F32};
    assert_int_equal(meso_layers_bake(ctx, &desc, &m), MESO_OK);
    assert_int_equal(m->width, 16);
    assert_int_equal(m->height, 8);
    assert_true(m->from_heightfield);
    for (int j = 0; j < 8; j++)
        for (int i = 0; i < 16; i++) {
            assert_int_equal(m->count[j * 16 + i], 1);
            assert_true(texel_depths(m, i, j)[0] == 1.0f - h_ramp(i, j));
        }
    meso_layers_destroy(m);
    meso_heightfield_destroy(hf);
    meso_context_destroy(ctx);
}

static void test_bake_is_identical_for_any_thread_count(void **state) {
    (void)state;
    meso_context *one = test_context(1), *two = test_context(2);
    meso_solid *solid = NULL;
    assert_int_equal(
        meso_solid_create_procedural(one, &(meso_solid_desc){.kind = MESO_SOLID_CHAIN}, &solid),
        MESO_OK);
    meso_layers_desc desc = {.solid = solid, .width = 48, .height = 48, .num_layers = 8};
    meso_layers *a = NULL, *b = NULL;
    assert_int_equal(meso_layers_bake(one, &desc, &a), MESO_OK);
    assert_int_equal(meso_layers_bake(two, &desc, &b), MESO_OK);
    size_t n = 48u * 48u * 8u;
    assert_memory_equal(a->depth, b->depth, n * sizeof(float));
    assert_memory_equal(a->normal_x, b->normal_x, n * sizeof(float));
    assert_memory_equal(a->count, b->count, 48u * 48u);
    assert_true(a->max_count >= 4); /* links threaded through links */
    meso_layers_destroy(a);
    meso_layers_destroy(b);
    meso_solid_destroy(solid);
    meso_context_destroy(one);
    meso_context_destroy(two);
}

static void test_save_load_round_trip_u8_and_float(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    const meso_layers_format formats[2] = {MESO_LAYERS_FORMAT_U8, MESO_LAYERS_FORMAT_F32};
    for (int f = 0; f < 2; f++) {
        meso_layers *m = bake(ctx, bar_field, 4, formats[f]), *back = NULL;
        const char *path = test_path(test_temp_dir(), f ? "bar_f32.mesobake" : "bar_u8.mesobake");
        assert_int_equal(meso_layers_save(ctx, m, path), MESO_OK);
        assert_int_equal(meso_layers_load(ctx, path, &back), MESO_OK);
        size_t n = 32u * 32u * 4u;
        assert_int_equal(back->format, formats[f]);
        assert_memory_equal(m->depth, back->depth, n * sizeof(float));
        assert_memory_equal(m->normal_x, back->normal_x, n * sizeof(float));
        assert_memory_equal(m->normal_y, back->normal_y, n * sizeof(float));
        assert_memory_equal(m->count, back->count, 32u * 32u);
        assert_int_equal(meso_layers_file_bytes(m),
                         f ? 32 * 32 * (4 * 3 * 4 + 1) : 32 * 32 * (4 * 3 + 1));
        meso_layers_destroy(m);
        meso_layers_destroy(back);
    }
    meso_context_destroy(ctx);
}

static unsigned char *read_all(const char *path, size_t *out_size) {
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long size = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *data = malloc((size_t)size);
    assert_int_equal(fread(data, 1, (size_t)size, f), (size_t)size);
    fclose(f);
    *out_size = (size_t)size;
    return data;
}

static void test_corrupted_layer_bake_is_refused_naming_the_file(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_layers *m = bake(ctx, bar_field, 4, MESO_LAYERS_FORMAT_U8), *back = NULL;
    const char *path = test_path(test_temp_dir(), "corrupt_layers.mesobake");
    assert_int_equal(meso_layers_save(ctx, m, path), MESO_OK);
    size_t size = 0;
    unsigned char *data = read_all(path, &size);
    data[size / 2] ^= 0x5a; /* a flipped byte in the payload: the checksum fails */
    test_write_file(path, data, size);
    assert_int_equal(meso_layers_load(ctx, path, &back), MESO_ERROR_FORMAT);
    assert_null(back);
    assert_non_null(strstr(meso_context_last_error(ctx), "corrupt_layers.mesobake"));
    /* truncated */
    test_write_file(path, data, size / 3);
    assert_int_equal(meso_layers_load(ctx, path, &back), MESO_ERROR_FORMAT);
    free(data);
    meso_layers_destroy(m);
    meso_context_destroy(ctx);
}

static void test_inconsistent_layers_with_valid_checksum_are_refused(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_layers *m = bake(ctx, bar_field, 4, MESO_LAYERS_FORMAT_F32), *back = NULL;
    const char *path = test_path(test_temp_dir(), "unsorted_layers.mesobake");
    m->depth[1] = 0.01f; /* below its entry: the depths of texel 0 are no longer sorted */
    assert_int_equal(meso_layers_save(ctx, m, path), MESO_OK);
    assert_int_equal(meso_layers_load(ctx, path, &back), MESO_ERROR_FORMAT);
    assert_non_null(strstr(meso_context_last_error(ctx), "depth"));
    m->depth[1] = 1.0f;
    m->count[0] = 7; /* more layers than the map has */
    assert_int_equal(meso_layers_save(ctx, m, path), MESO_OK);
    assert_int_equal(meso_layers_load(ctx, path, &back), MESO_ERROR_FORMAT);
    assert_non_null(strstr(meso_context_last_error(ctx), "layer count"));
    /* a bake of another kind */
    float x = 1.0f;
    meso_bake_file other = {.kind = "horizon", .kind_version = 1, .num_arrays = 1};
    other.arrays[0] = (meso_bake_array){
        .name = "x", .type = MESO_BAKE_F32, .num_dims = 1, .dims = {1}, .data = &x};
    assert_int_equal(meso_bake_file_save(ctx, &other, path), MESO_OK);
    assert_int_equal(meso_layers_load(ctx, path, &back), MESO_ERROR_FORMAT);
    assert_non_null(strstr(meso_context_last_error(ctx), "relief_layers"));
    meso_layers_destroy(m);
    meso_context_destroy(ctx);
}

/* Seen from below (back faces, impostors' backs): depths 1 - d in reverse order. */
static void test_mirror_reverses_the_layers(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_layers *m = bake(ctx, bar_field, 4, MESO_LAYERS_FORMAT_F32), *back = NULL;
    assert_int_equal(meso_layers_mirror(ctx, m, &back), MESO_OK);
    for (int j = 0; j < 32; j++) {
        const float *d = texel_depths(m, 5, j), *e = texel_depths(back, 5, j);
        int c = m->count[j * 32 + 5];
        assert_int_equal(back->count[j * 32 + 5], c);
        for (int k = 0; k < c; k++) assert_true(e[k] == 1.0f - d[c - 1 - k]);
        /* the floor's underside (an exit, facing down) is the first layer seen from below,
         * facing up */
        assert_true(meso_layers_normal(back, 5, j, 0).z > 0.99f);
    }
    meso_layers_destroy(back);
    m->from_heightfield = true;
    assert_int_equal(meso_layers_mirror(ctx, m, &back), MESO_ERROR_INVALID_ARGUMENT);
    meso_layers_destroy(m);
    meso_context_destroy(ctx);
}

static void test_bad_descs_name_the_field(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_layers *m = NULL;
    meso_layers_desc desc = {.field = slab_field, .num_layers = 5};
    assert_int_equal(meso_layers_bake(ctx, &desc, &m), MESO_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(meso_context_last_error(ctx), "num_layers"));
    desc = (meso_layers_desc){0};
    assert_int_equal(meso_layers_bake(ctx, &desc, &m), MESO_ERROR_INVALID_ARGUMENT);
    desc = (meso_layers_desc){.field = slab_field, .width = MESO_LAYERS_MAX_SIDE + 1};
    assert_int_equal(meso_layers_bake(ctx, &desc, &m), MESO_ERROR_LIMIT);
    assert_null(m);
    meso_context_destroy(ctx);
    /* the memory budget: a 256^2 x 4 map needs 4 MiB, refused under 1 MiB */
    meso_context *tiny = NULL;
    assert_int_equal(meso_context_create(
                         &(meso_context_desc){.num_threads = 1, .memory_limit = 1u << 20}, &tiny),
                     MESO_OK);
    desc = (meso_layers_desc){.field = slab_field};
    assert_int_equal(meso_layers_bake(tiny, &desc, &m), MESO_ERROR_LIMIT);
    assert_null(m);
    assert_non_null(strstr(meso_context_last_error(tiny), "relief_layers bake"));
    meso_context_destroy(tiny);
}

static void test_cached_bake_is_reused(void **state) {
    (void)state;
    setenv("MESO_CACHE_DIR", test_path(test_temp_dir(), "layers_cache"), 1);
    meso_context *ctx = test_context(1);
    meso_layers_desc desc = {.field = bar_field, .field_hash = 42, .width = 16, .height = 16};
    meso_layers *a = NULL, *b = NULL;
    assert_int_equal(meso_layers_bake_cached(ctx, &desc, &a), MESO_OK);
    assert_int_equal(meso_layers_bake_cached(ctx, &desc, &b), MESO_OK);
    assert_true(a->bake_seconds >= 0.0 && b->bake_seconds == 0.0); /* b came from the file */
    assert_memory_equal(a->depth, b->depth, 16u * 16u * 4u * sizeof(float));
    meso_layers_destroy(a);
    meso_layers_destroy(b);
    meso_context_destroy(ctx);
    unsetenv("MESO_CACHE_DIR");
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_slab_is_one_entry_and_the_floor),
        cmocka_unit_test(test_bar_over_floor_has_four_layers_under_the_bar_only),
        cmocka_unit_test(test_eight_layers_keep_six_crossings_four_clip_them),
        cmocka_unit_test(test_height_field_is_one_layer_of_one_minus_h),
        cmocka_unit_test(test_bake_is_identical_for_any_thread_count),
        cmocka_unit_test(test_save_load_round_trip_u8_and_float),
        cmocka_unit_test(test_corrupted_layer_bake_is_refused_naming_the_file),
        cmocka_unit_test(test_inconsistent_layers_with_valid_checksum_are_refused),
        cmocka_unit_test(test_mirror_reverses_the_layers),
        cmocka_unit_test(test_bad_descs_name_the_field),
        cmocka_unit_test(test_cached_bake_is_reused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
