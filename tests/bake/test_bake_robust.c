/* Bake files that pass the container's checks but must still not be trusted: values
 * that are not finite, entries made from another source; and every truncation and single-bit
 * flip of a real VDM, relief layers and GDM file refused. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "test_util.h"
#include "meso/bake_cache.h"
#include "meso/runtime.h"

static meso_heightfield *make_bumps(int side) {
    meso_heightfield *hf = calloc(1, sizeof(*hf));
    assert_non_null(hf);
    hf->width = hf->height = side;
    hf->heights = calloc((size_t)side * (size_t)side, sizeof(float));
    assert_non_null(hf->heights);
    for (int y = 0; y < side; y++)
        for (int x = 0; x < side; x++)
            hf->heights[y * side + x] = 0.5f + 0.4f * sinf(6.2831853f * (float)x / (float)side) *
                                                   sinf(6.2831853f * (float)y / (float)side);
    hf->hash =
        meso_hash64(hf->heights, sizeof(float) * (size_t)side * (size_t)side, MESO_HASH_SEED);
    return hf;
}

static void free_heightfield(meso_heightfield *hf) {
    free(hf->heights);
    free(hf);
}

/* A tiny VDM baked through the cache (a folder under the test's temporary folder); its cache
 * file's path into out_path. */
static meso_vdm_desc tiny_desc(meso_heightfield *hf) {
    return (meso_vdm_desc){.heightfield = hf,
                           .width = 8,
                           .num_theta = 4,
                           .num_phi = 2,
                           .num_curvatures = 2,
                           .depth = 0.08f,
                           .vdm_eigenfunctions = 2,
                           .mvm_eigenfunctions = 1};
}

static void bake_into_cache(meso_context *ctx, const meso_vdm_desc *desc, char *out_path,
                            size_t size) {
    meso_vdm *vdm = NULL;
    assert_int_equal(meso_vdm_bake_cached(ctx, desc, &vdm), MESO_OK);
    meso_vdm_destroy(vdm);
    assert_int_equal(
        meso_bake_cache_path(ctx, MESO_VDM_KIND, meso_vdm_cache_key(desc), out_path, size),
        MESO_OK);
}

/* Load `path`, let `edit` change it, save it back (so its checksum is valid again). */
static void rewrite(meso_context *ctx, const char *path, void (*edit)(meso_bake_file *bake)) {
    meso_bake_file *bake = NULL;
    assert_int_equal(meso_bake_file_load(ctx, path, &bake), MESO_OK);
    edit(bake);
    assert_int_equal(meso_bake_file_save(ctx, bake, path), MESO_OK);
    meso_bake_file_destroy(bake);
}

static void put_nan_in_eigen_vdm(meso_bake_file *bake) {
    const meso_bake_array *a = meso_bake_file_find(bake, "eigen_vdm");
    assert_non_null(a);
    float nan_value = NAN;
    memcpy((void *)((const float *)a->data + 3), &nan_value, sizeof(float));
}

static void put_huge_eigen_mvm(meso_bake_file *bake) {
    const meso_bake_array *a = meso_bake_file_find(bake, "eigen_mvm");
    assert_non_null(a);
    float huge = 1e30f;
    memcpy((void *)a->data, &huge, sizeof(float));
}

static void change_source(meso_bake_file *bake) { bake->source_hash ^= 1; }

static void test_non_finite_values_with_a_valid_checksum_are_refused_and_rebaked(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    setenv("MESO_CACHE_DIR", test_path(test_temp_dir(), "robust_cache"), 1);
    meso_heightfield *hf = make_bumps(16);
    meso_vdm_desc desc = tiny_desc(hf);
    char path[1200];
    bake_into_cache(ctx, &desc, path, sizeof(path));

    rewrite(ctx, path, put_nan_in_eigen_vdm);
    meso_vdm *vdm = NULL;
    assert_int_equal(meso_vdm_load(ctx, path, &vdm), MESO_ERROR_FORMAT);
    assert_null(vdm);
    assert_non_null(strstr(meso_context_last_error(ctx), "array \"eigen_vdm\": element 3 is nan"));
    /* through the cache: a warning, and baked again */
    assert_int_equal(meso_vdm_bake_cached(ctx, &desc, &vdm), MESO_OK);
    assert_non_null(strstr(test_last_warning(), "eigen_vdm"));
    assert_true(meso_vdm_get_compression(vdm).bake_seconds > 0.0);
    meso_vdm_destroy(vdm);

    rewrite(ctx, path, put_huge_eigen_mvm); /* finite, but out of range */
    assert_int_equal(meso_vdm_load(ctx, path, &vdm), MESO_ERROR_FORMAT);
    assert_non_null(strstr(meso_context_last_error(ctx), "array \"eigen_mvm\": element 0"));

    unsetenv("MESO_CACHE_DIR");
    free_heightfield(hf);
    meso_context_destroy(ctx);
}

static void test_a_cache_entry_of_another_source_is_not_used(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    setenv("MESO_CACHE_DIR", test_path(test_temp_dir(), "robust_cache_source"), 1);
    meso_heightfield *hf = make_bumps(16);
    meso_vdm_desc desc = tiny_desc(hf);
    char path[1200];
    bake_into_cache(ctx, &desc, path, sizeof(path));
    rewrite(ctx, path, change_source);
    meso_vdm *vdm = NULL;
    assert_int_equal(meso_vdm_bake_cached(ctx, &desc, &vdm), MESO_OK);
    assert_non_null(strstr(test_last_warning(), "made from another source"));
    assert_true(meso_vdm_get_compression(vdm).bake_seconds > 0.0); /* baked, not loaded */
    meso_vdm_destroy(vdm);
    unsetenv("MESO_CACHE_DIR");
    free_heightfield(hf);
    meso_context_destroy(ctx);
}

static void test_a_fifo_in_the_cache_is_skipped_without_blocking(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    setenv("MESO_CACHE_DIR", test_path(test_temp_dir(), "robust_cache_fifo"), 1);
    meso_heightfield *hf = make_bumps(16);
    meso_vdm_desc desc = tiny_desc(hf);
    char path[1200];
    bake_into_cache(ctx, &desc, path, sizeof(path));
    unlink(path);
    assert_int_equal(mkfifo(path, 0644), 0);
    meso_vdm *vdm = NULL;
    assert_int_equal(meso_vdm_bake_cached(ctx, &desc, &vdm), MESO_OK); /* baked, not blocked */
    assert_true(meso_vdm_get_compression(vdm).bake_seconds > 0.0);
    meso_vdm_destroy(vdm);
    struct stat st;
    assert_int_equal(lstat(path, &st), 0);
    assert_true(S_ISFIFO(st.st_mode)); /* not replaced either: only regular files are written */
    unlink(path);
    unsetenv("MESO_CACHE_DIR");
    free_heightfield(hf);
    meso_context_destroy(ctx);
}

static char *read_file(const char *path, size_t *out_size) {
    meso_context *ctx = test_context(1);
    char *data = NULL;
    assert_int_equal(meso_file_read(ctx, path, 1u << 30, &data, out_size), MESO_OK);
    meso_context_destroy(ctx);
    return data;
}

/* Whether a loader accepts the file at path (the object it makes is destroyed). */
typedef bool (*accepts_fn)(meso_context *ctx, const char *path);

static bool vdm_accepts(meso_context *ctx, const char *path) {
    meso_vdm *vdm = NULL;
    meso_result r = meso_vdm_load(ctx, path, &vdm);
    assert_true(r == MESO_OK || vdm == NULL);
    meso_vdm_destroy(vdm);
    return r == MESO_OK;
}

static bool layers_accepts(meso_context *ctx, const char *path) {
    meso_layers *map = NULL;
    meso_result r = meso_layers_load(ctx, path, &map);
    assert_true(r == MESO_OK || map == NULL);
    meso_layers_destroy(map);
    return r == MESO_OK;
}

static bool gdm_accepts(meso_context *ctx, const char *path) {
    meso_gdm *gdm = NULL;
    meso_result r = meso_gdm_load(ctx, path, &gdm);
    assert_true(r == MESO_OK || gdm == NULL);
    meso_gdm_destroy(gdm);
    return r == MESO_OK;
}

/* The file truncated at every byte of its first 2,048 (header, parameters, array table) and
 * at 1,000 random lengths, and with 1,000 single bits flipped: every one refused by the kind's
 * loader (the checksum and the container's checks), none crashing; the file itself loads. */
static void expect_every_mutation_refused(meso_context *ctx, const char *path, accepts_fn accepts) {
    size_t size = 0;
    char *original = read_file(path, &size);
    const char *mutated = test_path(test_temp_dir(), "mutated.mesobake");
    srand(15);
    size_t header_and_table = size < 2048 ? size : 2048;
    int accepted = 0;
    for (size_t k = 0; k < header_and_table + 1000; k++) {
        size_t length = k < header_and_table ? k : (size_t)rand() % size;
        test_write_file(mutated, original, length);
        accepted += accepts(ctx, mutated);
    }
    for (int k = 0; k < 1000; k++) {
        size_t bit = (size_t)rand() % (size * 8);
        original[bit / 8] ^= (char)(1u << (bit % 8));
        test_write_file(mutated, original, size);
        original[bit / 8] ^= (char)(1u << (bit % 8));
        accepted += accepts(ctx, mutated);
    }
    assert_int_equal(accepted, 0);
    test_write_file(mutated, original, size);
    assert_true(accepts(ctx, mutated));
    free(original);
}

static void test_every_truncation_and_bit_flip_of_a_vdm_file_is_refused(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    setenv("MESO_CACHE_DIR", test_path(test_temp_dir(), "robust_cache_flips"), 1);
    meso_heightfield *hf = make_bumps(16);
    meso_vdm_desc desc = tiny_desc(hf);
    char path[1200];
    bake_into_cache(ctx, &desc, path, sizeof(path));
    expect_every_mutation_refused(ctx, path, vdm_accepts);
    unsetenv("MESO_CACHE_DIR");
    free_heightfield(hf);
    meso_context_destroy(ctx);
}

static void test_every_truncation_and_bit_flip_of_a_layers_file_is_refused(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_heightfield *hf = make_bumps(8);
    meso_layers_desc desc = {.heightfield = hf, .width = 8, .height = 8, .num_layers = 4};
    meso_layers *map = NULL;
    assert_int_equal(meso_layers_bake(ctx, &desc, &map), MESO_OK);
    const char *path = test_path(test_temp_dir(), "layers.mesobake");
    assert_int_equal(meso_layers_save(ctx, map, path), MESO_OK);
    meso_layers_destroy(map);
    expect_every_mutation_refused(ctx, path, layers_accepts);
    free_heightfield(hf);
    meso_context_destroy(ctx);
}

static void test_every_truncation_and_bit_flip_of_a_gdm_file_is_refused(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_heightfield *hf = make_bumps(8);
    meso_gdm_desc desc = {.heightfield = hf,
                          .width = 4,
                          .layers = 3,
                          .num_theta = 4,
                          .num_phi = 2,
                          .eigenmaps = 2,
                          .keep_raw = true};
    meso_gdm *gdm = NULL;
    assert_int_equal(meso_gdm_bake(ctx, &desc, &gdm), MESO_OK);
    const char *path = test_path(test_temp_dir(), "gdm.mesobake");
    assert_int_equal(meso_gdm_save(ctx, gdm, path), MESO_OK);
    meso_gdm_destroy(gdm);
    expect_every_mutation_refused(ctx, path, gdm_accepts);
    free_heightfield(hf);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_non_finite_values_with_a_valid_checksum_are_refused_and_rebaked),
        cmocka_unit_test(test_a_cache_entry_of_another_source_is_not_used),
        cmocka_unit_test(test_a_fifo_in_the_cache_is_skipped_without_blocking),
        cmocka_unit_test(test_every_truncation_and_bit_flip_of_a_vdm_file_is_refused),
        cmocka_unit_test(test_every_truncation_and_bit_flip_of_a_layers_file_is_refused),
        cmocka_unit_test(test_every_truncation_and_bit_flip_of_a_gdm_file_is_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
