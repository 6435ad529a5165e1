/* The bake file container: round trip, truncation, corruption, absurd sizes, the cache. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"
#include "meso/bake_cache.h"
#include "meso/runtime.h"

static float weights[6 * 5];
static uint8_t labels[7];

static meso_bake_file sample_bake(void) {
    for (int i = 0; i < 30; i++) weights[i] = (float)i * 0.25f - 3.0f;
    for (int i = 0; i < 7; i++) labels[i] = (uint8_t)(i * 31);
    meso_bake_file bake = {.kind = "test_kind",
                           .kind_version = 3,
                           .source_hash = UINT64_C(0x0123456789abcdef),
                           .params_json = "{\"width\": 6, \"note\": \"x\"}",
                           .num_arrays = 2};
    bake.arrays[0] = (meso_bake_array){
        .name = "weights", .type = MESO_BAKE_F32, .num_dims = 2, .dims = {6, 5}, .data = weights};
    bake.arrays[1] = (meso_bake_array){
        .name = "labels", .type = MESO_BAKE_U8, .num_dims = 1, .dims = {7}, .data = labels};
    return bake;
}

static char *read_all(const char *path, size_t *out_size) {
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *data = malloc((size_t)n);
    assert_int_equal(fread(data, 1, (size_t)n, f), (size_t)n);
    fclose(f);
    *out_size = (size_t)n;
    return data;
}

static void write_sample(meso_context *ctx, const char *path) {
    meso_bake_file bake = sample_bake();
    assert_int_equal(meso_bake_file_save(ctx, &bake, path), MESO_OK);
}

static void test_bake_file_round_trip_keeps_everything(void **state) {
    meso_context *ctx = test_context(1);
    const char *path = test_path(test_temp_dir(), "round.mesobake");
    write_sample(ctx, path);
    meso_bake_file *loaded = NULL;
    assert_int_equal(meso_bake_file_load(ctx, path, &loaded), MESO_OK);
    assert_string_equal(loaded->kind, "test_kind");
    assert_int_equal(loaded->kind_version, 3);
    assert_true(loaded->source_hash == UINT64_C(0x0123456789abcdef));
    assert_string_equal(loaded->params_json, "{\"width\": 6, \"note\": \"x\"}");
    assert_int_equal(loaded->num_arrays, 2);
    const meso_bake_array *w = meso_bake_file_find(loaded, "weights");
    assert_non_null(w);
    assert_int_equal(w->type, MESO_BAKE_F32);
    assert_int_equal(w->num_dims, 2);
    assert_int_equal(w->dims[0], 6);
    assert_int_equal(w->dims[1], 5);
    assert_memory_equal(w->data, weights, sizeof(weights));
    const meso_bake_array *l = meso_bake_file_find(loaded, "labels");
    assert_non_null(l);
    assert_memory_equal(l->data, labels, sizeof(labels));
    assert_null(meso_bake_file_find(loaded, "missing"));
    meso_bake_file_destroy(loaded);
    meso_context_destroy(ctx);
}

static void test_bake_file_truncated_anywhere_is_a_format_error_naming_the_file(void **state) {
    meso_context *ctx = test_context(1);
    const char *dir = test_temp_dir();
    const char *path = test_path(dir, "full.mesobake");
    write_sample(ctx, path);
    size_t size = 0;
    char *data = read_all(path, &size);
    for (int part = 0; part < 7; part++) {
        size_t cut = size * (size_t)part / 7;
        const char *bad = test_path(dir, "cut.mesobake");
        test_write_file(bad, data, cut);
        meso_bake_file *loaded = (meso_bake_file *)1;
        assert_int_equal(meso_bake_file_load(ctx, bad, &loaded), MESO_ERROR_FORMAT);
        assert_null(loaded);
        assert_non_null(strstr(meso_context_last_error(ctx), "cut.mesobake"));
    }
    /* one byte short too */
    const char *bad = test_path(dir, "cut.mesobake");
    test_write_file(bad, data, size - 1);
    meso_bake_file *loaded = NULL;
    assert_int_equal(meso_bake_file_load(ctx, bad, &loaded), MESO_ERROR_FORMAT);
    assert_non_null(strstr(meso_context_last_error(ctx), "truncated"));
    free(data);
    meso_context_destroy(ctx);
}

static void test_bake_file_any_flipped_bit_is_detected(void **state) {
    meso_context *ctx = test_context(1);
    const char *dir = test_temp_dir();
    const char *path = test_path(dir, "flip_src.mesobake");
    write_sample(ctx, path);
    size_t size = 0;
    char *data = read_all(path, &size);
    const char *bad = test_path(dir, "flip.mesobake");
    for (size_t byte = 0; byte < size; byte += 3) {
        data[byte] ^= (char)(1 << (byte % 8));
        test_write_file(bad, data, size);
        data[byte] ^= (char)(1 << (byte % 8));
        meso_bake_file *loaded = NULL;
        assert_int_equal(meso_bake_file_load(ctx, bad, &loaded), MESO_ERROR_FORMAT);
        assert_null(loaded);
        assert_non_null(strstr(meso_context_last_error(ctx), "flip.mesobake"));
    }
    /* a payload bit: only the checksum can tell */
    size_t payload_byte = size - 12;
    data[payload_byte] ^= 0x10;
    test_write_file(bad, data, size);
    meso_bake_file *loaded = NULL;
    assert_int_equal(meso_bake_file_load(ctx, bad, &loaded), MESO_ERROR_FORMAT);
    assert_non_null(strstr(meso_context_last_error(ctx), "checksum mismatch (file corrupted)"));
    free(data);
    meso_context_destroy(ctx);
}

/* Rewrite the checksum so that only the structural checks can refuse the file. */
static void reseal(char *data, size_t size) {
    uint64_t hash = meso_hash64(data, size - 8, MESO_HASH_SEED);
    for (int i = 0; i < 8; i++) data[size - 8 + (size_t)i] = (char)(hash >> (8 * i));
}

static void test_bake_file_absurd_dims_are_refused_before_allocating(void **state) {
    meso_context *ctx = test_context(1);
    const char *dir = test_temp_dir();
    const char *path = test_path(dir, "dims_src.mesobake");
    write_sample(ctx, path);
    size_t size = 0;
    char *data = read_all(path, &size);
    size_t params = strlen("{\"width\": 6, \"note\": \"x\"}");
    size_t table = (72 + params + 7) & ~(size_t)7;
    const char *bad = test_path(dir, "dims.mesobake");

    /* dims {2^40, 2^40}: the product overflows any allocation */
    char *copy = malloc(size);
    memcpy(copy, data, size);
    for (int d = 0; d < 2; d++) {
        uint64_t huge = UINT64_C(1) << 40;
        for (int i = 0; i < 8; i++)
            copy[table + 40 + 8 * (size_t)d + (size_t)i] = (char)(huge >> (8 * i));
    }
    reseal(copy, size);
    test_write_file(bad, copy, size);
    meso_bake_file *loaded = NULL;
    assert_int_equal(meso_bake_file_load(ctx, bad, &loaded), MESO_ERROR_FORMAT);
    assert_non_null(strstr(meso_context_last_error(ctx), "dims.mesobake"));
    assert_non_null(strstr(meso_context_last_error(ctx), "weights"));

    /* a consistent but huge array (size matches dims) pointing past the end */
    memcpy(copy, data, size);
    uint64_t dims0 = UINT64_C(1) << 24, bytes = dims0 * 5 * 4;
    for (int i = 0; i < 8; i++) {
        copy[table + 40 + (size_t)i] = (char)(dims0 >> (8 * i));
        copy[table + 96 + (size_t)i] = (char)(bytes >> (8 * i));
    }
    reseal(copy, size);
    test_write_file(bad, copy, size);
    assert_int_equal(meso_bake_file_load(ctx, bad, &loaded), MESO_ERROR_FORMAT);
    assert_non_null(strstr(meso_context_last_error(ctx), "outside the payload"));

    /* too many arrays */
    memcpy(copy, data, size);
    copy[64] = (char)200;
    reseal(copy, size);
    test_write_file(bad, copy, size);
    assert_int_equal(meso_bake_file_load(ctx, bad, &loaded), MESO_ERROR_FORMAT);
    assert_non_null(strstr(meso_context_last_error(ctx), "arrays exceed the limit"));
    free(copy);
    free(data);
    meso_context_destroy(ctx);
}

static void test_bake_file_not_a_bake_and_missing_file(void **state) {
    meso_context *ctx = test_context(1);
    const char *dir = test_temp_dir();
    const char *bad = test_path(dir, "text.mesobake");
    const char text[] = "this is certainly not a bake file, but it is long enough to have a header "
                        "and more bytes after it";
    test_write_file(bad, text, sizeof(text));
    meso_bake_file *loaded = NULL;
    assert_int_equal(meso_bake_file_load(ctx, bad, &loaded), MESO_ERROR_FORMAT);
    assert_non_null(strstr(meso_context_last_error(ctx), "bad magic"));
    assert_int_equal(meso_bake_file_load(ctx, test_path(dir, "absent.mesobake"), &loaded),
                     MESO_ERROR_IO);
    assert_null(loaded);
    meso_context_destroy(ctx);
}

static void test_bake_file_save_rejects_bad_names(void **state) {
    meso_context *ctx = test_context(1);
    meso_bake_file bake = sample_bake();
    strcpy(bake.arrays[1].name, "Bad Name");
    assert_int_equal(meso_bake_file_save(ctx, &bake, test_path(test_temp_dir(), "x.mesobake")),
                     MESO_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(meso_context_last_error(ctx), "arrays[1].name"));
    bake = sample_bake();
    bake.arrays[0].dims[1] = 0;
    assert_int_equal(meso_bake_file_save(ctx, &bake, test_path(test_temp_dir(), "x.mesobake")),
                     MESO_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(meso_context_last_error(ctx), "weights"));
    meso_context_destroy(ctx);
}

static void test_bake_cache_uses_meso_cache_dir_and_round_trips(void **state) {
    meso_context *ctx = test_context(1);
    const char *dir = test_path(test_temp_dir(), "cache/nested");
    setenv("MESO_CACHE_DIR", dir, 1);
    char path[1200];
    assert_int_equal(meso_bake_cache_path(ctx, "test_kind", 0xabcull, path, sizeof(path)), MESO_OK);
    assert_non_null(strstr(path, "cache/nested/test_kind-0000000000000abc.mesobake"));
    meso_bake_file *loaded = (meso_bake_file *)1;
    meso_bake_file bake = sample_bake();
    assert_int_equal(meso_bake_cache_load(ctx, "test_kind", 3, 0xabc, bake.source_hash, &loaded),
                     MESO_OK);
    assert_null(loaded);
    assert_int_equal(meso_bake_cache_save(ctx, &bake, 0xabc), MESO_OK);
    assert_int_equal(meso_bake_cache_load(ctx, "test_kind", 3, 0xabc, bake.source_hash, &loaded),
                     MESO_OK);
    assert_non_null(loaded);
    meso_bake_file_destroy(loaded);
    /* made from another source (the stored source hash is not the one asked for): not used */
    assert_int_equal(meso_bake_cache_load(ctx, "test_kind", 3, 0xabc, 0x42, &loaded), MESO_OK);
    assert_null(loaded);
    assert_non_null(strstr(test_last_warning(), "made from another source"));
    /* another kind version: not used */
    assert_int_equal(meso_bake_cache_load(ctx, "test_kind", 4, 0xabc, bake.source_hash, &loaded),
                     MESO_OK);
    assert_null(loaded);
    /* a corrupted entry: a warning, then treated as absent */
    test_write_file(path, "MESOBAKE garbage", 16);
    assert_int_equal(meso_bake_cache_load(ctx, "test_kind", 3, 0xabc, bake.source_hash, &loaded),
                     MESO_OK);
    assert_null(loaded);
    assert_non_null(strstr(test_last_warning(), "unusable cache entry"));
    setenv("MESO_CACHE_DIR", "off", 1);
    assert_int_equal(meso_bake_cache_dir(ctx, path, sizeof(path)), MESO_ERROR_UNSUPPORTED);
    assert_int_equal(meso_bake_cache_save(ctx, &bake, 0xabc), MESO_OK);
    unsetenv("MESO_CACHE_DIR");
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bake_file_round_trip_keeps_everything),
        cmocka_unit_test(test_bake_file_truncated_anywhere_is_a_format_error_naming_the_file),
        cmocka_unit_test(test_bake_file_any_flipped_bit_is_detected),
        cmocka_unit_test(test_bake_file_absurd_dims_are_refused_before_allocating),
        cmocka_unit_test(test_bake_file_not_a_bake_and_missing_file),
        cmocka_unit_test(test_bake_file_save_rejects_bad_names),
        cmocka_unit_test(test_bake_cache_uses_meso_cache_dir_and_round_trips),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
