/* VDM bake (Wang et al. 2003 §3.1, §3.3, Appendix): tiny tables so that the tests stay fast. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"
#include "meso/runtime.h"

#define HALF_PI (0.5 * MESO_PI_D)

/* A height field built by hand (no dependency on the mesostructure generators). */
static meso_heightfield *make_heightfield(int width, int height) {
    meso_heightfield *hf = calloc(1, sizeof(*hf));
    hf->width = width;
    hf->height = height;
    hf->heights = calloc((size_t)width * height, sizeof(float));
    hf->wrap = MESO_WRAP_REPEAT;
    return hf;
}
static void rehash(meso_heightfield *hf) {
    hf->hash =
        meso_hash64(hf->heights, sizeof(float) * (size_t)hf->width * hf->height, MESO_HASH_SEED);
}
static void free_heightfield(meso_heightfield *hf) {
    free(hf->heights);
    free(hf);
}
static meso_heightfield *make_bumps(int side) {
    meso_heightfield *hf = make_heightfield(side, side);
    for (int j = 0; j < side; j++)
        for (int i = 0; i < side; i++) {
            float x = ((float)i + 0.5f) / side, y = ((float)j + 0.5f) / side;
            hf->heights[j * side + i] =
                0.5f + 0.5f * sinf(6.2831853f * 2.0f * x) * cosf(6.2831853f * 2.0f * y);
        }
    rehash(hf);
    return hf;
}

static float theta_at(int t, int n) { return (float)((t + 0.5) * HALF_PI / n); }

static void test_vdm_defaults_are_the_papers(void **state) {
    meso_vdm_desc d = meso_vdm_desc_defaults(NULL);
    assert_int_equal(d.width, 128);
    assert_int_equal(d.height, 128);
    assert_int_equal(d.num_theta, 32);
    assert_int_equal(d.num_phi, 8);
    assert_int_equal(d.num_curvatures, 16);
    assert_true(d.curvature_min == -2.0f && d.curvature_max == 3.0f);
    assert_int_equal(d.vdm_eigenfunctions, 8);
    assert_int_equal(d.mvm_eigenfunctions, 4);
    meso_vdm_desc some = {.width = 16, .num_theta = 8};
    d = meso_vdm_desc_defaults(&some);
    assert_int_equal(d.width, 16);
    assert_int_equal(d.height, 16);
    assert_int_equal(d.num_theta, 8);
    assert_int_equal(d.num_phi, 8);
}

static void test_vdm_constant_top_height_field_bakes_zero_everywhere(void **state) {
    meso_context *ctx = test_context(2);
    meso_heightfield *hf = make_heightfield(8, 8);
    for (int i = 0; i < 64; i++) hf->heights[i] = 1.0f;
    rehash(hf);
    meso_vdm_desc desc = {.heightfield = hf,
                          .width = 8,
                          .num_theta = 8,
                          .num_phi = 4,
                          .num_curvatures = 4,
                          .keep_raw = true,
                          .depth = 0.1f};
    meso_vdm *vdm = NULL;
    assert_int_equal(meso_vdm_bake(ctx, &desc, &vdm), MESO_OK);
    meso_vdm_view view = meso_vdm_get_view(vdm);
    assert_non_null(view.raw);
    size_t rows = 8 * 8 * 4;
    for (size_t r = 0; r < rows; r++) {
        for (int col = 0; col < 32; col++)
            assert_float_equal(view.raw[r * view.raw_columns + col], 0.0f, 1e-6f);
        for (int c = 0; c < 4; c++) /* every direction is valid: theta_MVM is the last theta */
            assert_float_equal(view.raw[r * view.raw_columns + 32 + c], theta_at(7, 8), 1e-6f);
    }
    /* and the compressed map says the same at any continuous point */
    for (int i = 0; i < 20; i++) {
        float u = 0.037f * i, v = 0.91f - 0.03f * i, th = 0.07f * i, phi = 0.3f * i;
        assert_float_equal(meso_vdm_lookup(vdm, u, v, th, phi, 0.0f, 0, false), 0.0f, 1e-5f);
    }
    meso_vdm_destroy(vdm);
    free_heightfield(hf);
    meso_context_destroy(ctx);
}

static void test_vdm_flat_floor_gives_depth_over_cos_theta(void **state) {
    meso_context *ctx = test_context(1);
    meso_heightfield *hf = make_heightfield(8, 8);
    for (int i = 0; i < 64; i++) hf->heights[i] = 0.25f;
    rehash(hf);
    meso_vdm_desc desc = {.heightfield = hf,
                          .width = 8,
                          .num_theta = 8,
                          .num_phi = 4,
                          .num_curvatures = 1,
                          .keep_raw = true,
                          .depth = 0.05f};
    meso_vdm *vdm = NULL;
    assert_int_equal(meso_vdm_bake(ctx, &desc, &vdm), MESO_OK);
    for (int t = 0; t < 8; t++) {
        float th = theta_at(t, 8);
        float d = meso_vdm_lookup(vdm, 0.3f, 0.6f, th, 1.0f, 0.0f, 0, true);
        assert_float_equal(d, 0.75f / cosf(th), 1e-3f * (1.0f / cosf(th)));
    }
    meso_vdm_destroy(vdm);
    free_heightfield(hf);
    meso_context_destroy(ctx);
}

/* A single groove h = 0 in columns [24, 40) of a 64-texel field, 1 elsewhere; the bilinear
 * surface ramps over one texel at each wall. Rays inside the groove looking along +-u. */
static double groove_ray_length(double u0, int p, double theta, double depth) {
    double wall = p == 0 ? u0 - 24.5 / 64.0 : 39.5 / 64.0 - u0; /* horizontal distance to ramp */
    double cot = 1.0 / tan(theta);
    if (depth * tan(theta) <= wall) return 1.0 / cos(theta); /* the floor */
    double x = (depth - wall * cot) / (cot + 64.0 * depth);  /* into the ramp */
    return (wall + x) / sin(theta) / depth;
}

static void test_vdm_single_groove_matches_the_analytic_ray_length(void **state) {
    meso_context *ctx = test_context(2);
    meso_heightfield *hf = make_heightfield(64, 4);
    for (int j = 0; j < 4; j++)
        for (int i = 0; i < 64; i++) hf->heights[j * 64 + i] = (i >= 24 && i < 40) ? 0.0f : 1.0f;
    rehash(hf);
    float depth = 0.1f, step = 0.5f;
    meso_vdm_desc desc = {.heightfield = hf,
                          .width = 64,
                          .height = 4,
                          .num_theta = 8,
                          .num_phi = 4,
                          .num_curvatures = 1,
                          .keep_raw = true,
                          .depth = depth,
                          .step_texels = step};
    meso_vdm *vdm = NULL;
    assert_int_equal(meso_vdm_bake(ctx, &desc, &vdm), MESO_OK);
    meso_vdm_view view = meso_vdm_get_view(vdm);
    int checked_walls = 0;
    for (int i = 24; i < 40; i++)
        for (int p = 0; p <= 2; p += 2)
            for (int t = 0; t < 8; t++) {
                double u0 = (i + 0.5) / 64.0, theta = theta_at(t, 8);
                double expected = groove_ray_length(u0, p, theta, depth);
                size_t row = ((size_t)1 * 64 + i) * 4 + p;
                double baked = view.raw[row * view.raw_columns + t];
                /* within one marching step of horizontal travel */
                double tolerance = (step / 64.0) / (sin(theta) * depth);
                if (fabs(baked - expected) > tolerance)
                    fail_msg("texel %d phi %d theta %d: baked %g, analytic %g", i, p, t, baked,
                             expected);
                checked_walls += expected < 0.99 / cos(theta);
            }
    assert_true(checked_walls > 20); /* both floor and wall hits were exercised */
    meso_vdm_destroy(vdm);
    free_heightfield(hf);
    meso_context_destroy(ctx);
}

static void test_vdm_all_eigenfunctions_reproduce_the_table(void **state) {
    meso_context *ctx = test_context(2);
    meso_heightfield *hf = make_bumps(32);
    meso_vdm_desc desc = {.heightfield = hf,
                          .width = 16,
                          .num_theta = 8,
                          .num_phi = 4,
                          .num_curvatures = 4,
                          .keep_raw = true,
                          .depth = 0.08f,
                          .vdm_eigenfunctions = 36,
                          .mvm_eigenfunctions = 36,
                          .float_weights = true};
    meso_vdm *vdm = NULL;
    assert_int_equal(meso_vdm_bake(ctx, &desc, &vdm), MESO_OK);
    meso_vdm_view view = meso_vdm_get_view(vdm);
    assert_int_equal(view.raw_columns, 36);
    size_t rows = 16 * 16 * 4;
    double max_error = 0.0, err2 = 0.0;
    for (size_t r = 0; r < rows; r++) {
        const float *w = view.weights + r * view.num_weights;
        for (int col = 0; col < 32; col++) {
            double sum = 0.0, sum2 = 0.0;
            for (int i = 0; i < 36; i++) sum += (double)w[i] * view.eigen_vdm[i * 32 + col];
            for (int i = 0; i < 2; i++) sum2 += (double)w[i] * view.eigen_vdm[i * 32 + col];
            double truth = view.raw[r * 36 + col];
            max_error = fmax(max_error, fabs(sum - truth));
            err2 += (sum2 - truth) * (sum2 - truth);
        }
        for (int c = 0; c < 4; c++) {
            double sum = 0.0;
            for (int i = 0; i < 36; i++) sum += (double)w[i] * view.eigen_mvm[i * 4 + c];
            max_error = fmax(max_error, fabs(sum - view.raw[r * 36 + 32 + c]));
        }
    }
    assert_true(max_error <= 1e-5);
    /* the reported RMSE for k = 2 is the measured one */
    meso_vdm_compression comp = meso_vdm_get_compression(vdm);
    double rmse2 = sqrt(err2 / (rows * 32.0));
    assert_float_equal(comp.rmse[1], rmse2, (float)(1e-3 * rmse2 + 1e-6));
    assert_true(comp.rmse[0] >= comp.rmse[1] && comp.rmse[1] >= comp.rmse[7]);
    assert_true(comp.raw_bytes == rows * 36 * 4);
    meso_vdm_destroy(vdm);
    free_heightfield(hf);
    meso_context_destroy(ctx);
}

static void test_vdm_convex_curvature_lowers_the_maximal_view_angle(void **state) {
    meso_context *ctx = test_context(2);
    meso_heightfield *hf = make_heightfield(8, 8);
    for (int i = 0; i < 64; i++) hf->heights[i] = 0.0f;
    rehash(hf);
    meso_vdm_desc desc = {.heightfield = hf,
                          .width = 8,
                          .num_theta = 16,
                          .num_phi = 4,
                          .num_curvatures = 6,
                          .curvature_min = -2.0f,
                          .curvature_max = 3.0f,
                          .keep_raw = true,
                          .depth = 0.1f};
    meso_vdm *vdm = NULL;
    assert_int_equal(meso_vdm_bake(ctx, &desc, &vdm), MESO_OK);
    float previous = 10.0f;
    for (int c = 0; c < 6; c++) {
        float curvature = -2.0f + c;
        float mvm = meso_vdm_max_theta(vdm, 0.5f, 0.5f, 0.0f, curvature, true);
        assert_true(mvm <= previous + 1e-6f);
        previous = mvm;
        if (curvature <= 0.0f) assert_float_equal(mvm, theta_at(15, 16), 1e-6f);
    }
    assert_true(previous < theta_at(15, 16) - 0.05f); /* c = 3 has no hit at grazing angles */
    /* concave surfaces bend the floor up: shorter rays than flat at the same angle */
    float flat = meso_vdm_lookup(vdm, 0.5f, 0.5f, theta_at(12, 16), 0.0f, 0.0f, 0, true);
    float concave = meso_vdm_lookup(vdm, 0.5f, 0.5f, theta_at(12, 16), 0.0f, -2.0f, 0, true);
    assert_true(concave < flat);
    meso_vdm_destroy(vdm);
    free_heightfield(hf);
    meso_context_destroy(ctx);
}

static void test_vdm_bake_is_identical_for_any_thread_count(void **state) {
    meso_heightfield *hf = make_bumps(32);
    meso_vdm_desc desc = {.heightfield = hf,
                          .width = 16,
                          .num_theta = 8,
                          .num_phi = 4,
                          .num_curvatures = 4,
                          .depth = 0.08f};
    meso_vdm *one = NULL, *two = NULL;
    meso_context *ctx1 = test_context(1), *ctx2 = test_context(2);
    assert_int_equal(meso_vdm_bake(ctx1, &desc, &one), MESO_OK);
    assert_int_equal(meso_vdm_bake(ctx2, &desc, &two), MESO_OK);
    meso_vdm_view a = meso_vdm_get_view(one), b = meso_vdm_get_view(two);
    assert_memory_equal(a.weights, b.weights, sizeof(float) * 16 * 16 * 4 * a.num_weights);
    assert_memory_equal(a.eigen_vdm, b.eigen_vdm, sizeof(float) * a.num_vdm * 32);
    meso_vdm_destroy(one);
    meso_vdm_destroy(two);
    meso_context_destroy(ctx1);
    meso_context_destroy(ctx2);
    free_heightfield(hf);
}

static void test_vdm_bake_file_round_trip_and_corruption_is_refused(void **state) {
    meso_context *ctx = test_context(2);
    meso_heightfield *hf = make_bumps(16);
    meso_vdm_desc desc = {.heightfield = hf,
                          .width = 16,
                          .num_theta = 8,
                          .num_phi = 4,
                          .num_curvatures = 4,
                          .depth = 0.08f};
    meso_vdm *vdm = NULL, *loaded = NULL;
    assert_int_equal(meso_vdm_bake(ctx, &desc, &vdm), MESO_OK);
    const char *dir = test_temp_dir();
    const char *path = test_path(dir, "map.mesobake");
    assert_int_equal(meso_vdm_save(ctx, vdm, path), MESO_OK);
    assert_int_equal(meso_vdm_load(ctx, path, &loaded), MESO_OK);
    for (int i = 0; i < 10; i++) {
        float u = 0.1f * i, th = 0.15f * i, phi = 0.6f * i, c = -2.0f + 0.5f * i;
        assert_float_equal(meso_vdm_lookup(vdm, u, u, th, phi, c, 0, false),
                           meso_vdm_lookup(loaded, u, u, th, phi, c, 0, false), 0.0f);
    }
    meso_vdm_compression a = meso_vdm_get_compression(vdm), b = meso_vdm_get_compression(loaded);
    assert_memory_equal(a.rmse, b.rmse, sizeof(a.rmse));
    meso_vdm_destroy(loaded);

    /* the report for `meso info` */
    meso_bake_file *bake = NULL;
    assert_int_equal(meso_bake_file_load(ctx, path, &bake), MESO_OK);
    char text[4096];
    assert_true(meso_vdm_describe(bake, text, sizeof(text)) > 0);
    /* W is stored as IEEE halves by default */
    assert_int_equal(meso_bake_file_find(bake, "weights")->type, MESO_BAKE_F16);
    assert_non_null(strstr(text, "k=16"));
    meso_bake_file_destroy(bake);

    FILE *f = fopen(path, "rb");
    fseek(f, 0, SEEK_END);
    size_t size = (size_t)ftell(f);
    fseek(f, 0, SEEK_SET);
    char *data = malloc(size);
    assert_int_equal(fread(data, 1, size, f), size);
    fclose(f);
    const char *bad = test_path(dir, "bad_map.mesobake");
    test_write_file(bad, data, size / 2);
    assert_int_equal(meso_vdm_load(ctx, bad, &loaded), MESO_ERROR_FORMAT);
    assert_null(loaded);
    assert_non_null(strstr(meso_context_last_error(ctx), "bad_map.mesobake"));
    data[size / 3] ^= 4;
    test_write_file(bad, data, size);
    assert_int_equal(meso_vdm_load(ctx, bad, &loaded), MESO_ERROR_FORMAT);
    assert_non_null(strstr(meso_context_last_error(ctx), "checksum mismatch"));
    free(data);
    meso_vdm_destroy(vdm);
    free_heightfield(hf);
    meso_context_destroy(ctx);
}

static void test_vdm_cached_bake_is_reused(void **state) {
    meso_context *ctx = test_context(2);
    setenv("MESO_CACHE_DIR", test_path(test_temp_dir(), "vdm_cache"), 1);
    meso_heightfield *hf = make_bumps(16);
    meso_vdm_desc desc = {.heightfield = hf,
                          .width = 8,
                          .num_theta = 4,
                          .num_phi = 2,
                          .num_curvatures = 2,
                          .depth = 0.08f,
                          .vdm_eigenfunctions = 2,
                          .mvm_eigenfunctions = 1};
    meso_vdm *first = NULL, *second = NULL;
    assert_int_equal(meso_vdm_bake_cached(ctx, &desc, &first), MESO_OK);
    assert_true(meso_vdm_get_compression(first).bake_seconds > 0.0);
    assert_int_equal(meso_vdm_bake_cached(ctx, &desc, &second), MESO_OK);
    assert_true(meso_vdm_get_compression(second).bake_seconds == 0.0); /* loaded */
    meso_vdm_desc other = desc;
    other.depth = 0.09f;
    assert_true(meso_vdm_cache_key(&other) != meso_vdm_cache_key(&desc));
    meso_vdm_destroy(first);
    meso_vdm_destroy(second);
    unsetenv("MESO_CACHE_DIR");
    free_heightfield(hf);
    meso_context_destroy(ctx);
}

/* The memory budget: a bake that cannot fit is refused before it allocates, and one
 * with no room to hold its table between the SVD's passes casts it twice, to the same map. */
static void test_vdm_bake_keeps_to_the_memory_budget(void **state) {
    meso_heightfield *hf = make_bumps(16);
    meso_vdm_desc desc = {.heightfield = hf,
                          .width = 16,
                          .num_theta = 8,
                          .num_phi = 4,
                          .num_curvatures = 4,
                          .vdm_eigenfunctions = 4,
                          .mvm_eigenfunctions = 2};
    meso_context *tiny = NULL;
    assert_int_equal(meso_context_create(
                         &(meso_context_desc){.num_threads = 1, .memory_limit = 1u << 20}, &tiny),
                     MESO_OK);
    meso_vdm *vdm = (meso_vdm *)1;
    assert_int_equal(meso_vdm_bake(tiny, &desc, &vdm), MESO_ERROR_LIMIT);
    assert_null(vdm);
    assert_non_null(strstr(meso_context_last_error(tiny), "vdm bake"));
    meso_context_destroy(tiny);
    /* the essentials (3.6 MB, mostly the SVD's blocks) fit; the 147 KB table does not */
    meso_context *tight = NULL, *roomy = test_context(1);
    assert_int_equal(meso_context_create(
                         &(meso_context_desc){.num_threads = 1, .memory_limit = 3650000}, &tight),
                     MESO_OK);
    meso_vdm *streamed = NULL, *held = NULL;
    assert_int_equal(meso_vdm_bake(tight, &desc, &streamed), MESO_OK);
    assert_int_equal(meso_vdm_bake(roomy, &desc, &held), MESO_OK);
    meso_vdm_view a = meso_vdm_get_view(streamed), b = meso_vdm_get_view(held);
    assert_memory_equal(a.weights, b.weights, sizeof(float) * 16 * 16 * 4 * (size_t)a.num_weights);
    meso_vdm_destroy(streamed);
    meso_vdm_destroy(held);
    meso_context_destroy(tight);
    meso_context_destroy(roomy);
    free_heightfield(hf);
}

static void test_vdm_rejects_bad_parameters_naming_the_field(void **state) {
    meso_context *ctx = test_context(1);
    meso_heightfield *hf = make_bumps(8);
    meso_vdm *vdm = (meso_vdm *)1;
    meso_vdm_desc desc = {.heightfield = hf, .depth = -1.0f};
    assert_int_equal(meso_vdm_bake(ctx, &desc, &vdm), MESO_ERROR_INVALID_ARGUMENT);
    assert_null(vdm);
    assert_non_null(strstr(meso_context_last_error(ctx), "depth"));
    desc = (meso_vdm_desc){.heightfield = hf, .width = 100000};
    assert_int_equal(meso_vdm_bake(ctx, &desc, &vdm), MESO_ERROR_LIMIT);
    assert_non_null(strstr(meso_context_last_error(ctx), "width"));
    desc = (meso_vdm_desc){.heightfield = hf,
                           .width = 4,
                           .num_theta = 4,
                           .num_phi = 1,
                           .num_curvatures = 1,
                           .vdm_eigenfunctions = 9};
    assert_int_equal(meso_vdm_bake(ctx, &desc, &vdm), MESO_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(meso_context_last_error(ctx), "vdm_eigenfunctions"));
    desc = (meso_vdm_desc){0};
    assert_int_equal(meso_vdm_bake(ctx, &desc, &vdm), MESO_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(meso_context_last_error(ctx), "heightfield"));
    free_heightfield(hf);
    meso_context_destroy(ctx);
}

static bool cancel_now(void *user, const char *label, double fraction) { return true; }

static void test_vdm_bake_can_be_cancelled(void **state) {
    meso_context *ctx = NULL;
    meso_context_desc cd = {
        .num_threads = 2, .progress = MESO_PROGRESS_NEVER, .on_progress = cancel_now};
    assert_int_equal(meso_context_create(&cd, &ctx), MESO_OK);
    meso_heightfield *hf = make_bumps(16);
    meso_vdm_desc desc = {
        .heightfield = hf, .width = 16, .num_theta = 8, .num_phi = 4, .num_curvatures = 2};
    meso_vdm *vdm = (meso_vdm *)1;
    assert_int_equal(meso_vdm_bake(ctx, &desc, &vdm), MESO_ERROR_CANCELLED);
    assert_null(vdm);
    free_heightfield(hf);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_vdm_defaults_are_the_papers),
        cmocka_unit_test(test_vdm_constant_top_height_field_bakes_zero_everywhere),
        cmocka_unit_test(test_vdm_flat_floor_gives_depth_over_cos_theta),
        cmocka_unit_test(test_vdm_single_groove_matches_the_analytic_ray_length),
        cmocka_unit_test(test_vdm_all_eigenfunctions_reproduce_the_table),
        cmocka_unit_test(test_vdm_convex_curvature_lowers_the_maximal_view_angle),
        cmocka_unit_test(test_vdm_bake_is_identical_for_any_thread_count),
        cmocka_unit_test(test_vdm_bake_file_round_trip_and_corruption_is_refused),
        cmocka_unit_test(test_vdm_cached_bake_is_reused),
        cmocka_unit_test(test_vdm_bake_keeps_to_the_memory_budget),
        cmocka_unit_test(test_vdm_rejects_bad_parameters_naming_the_field),
        cmocka_unit_test(test_vdm_bake_can_be_cancelled),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
