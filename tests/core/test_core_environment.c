/* Environments (include/meso/environment.h): the .hdr round trip through stb_image, the
 * shipped example map, bad files refused with their exact code and a message naming the file,
 * and the importance sampling's density against the map. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"

static void assert_starts_with(const char *message, const char *prefix) {
    if (strncmp(message, prefix, strlen(prefix)) != 0)
        fail_msg("\"%s\" does not start with \"%s\"", message, prefix);
}

static void test_environment_hdr_round_trip(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_environment *sky = NULL, *loaded = NULL;
    assert_int_equal(meso_environment_create_sky(ctx, &(meso_sky_desc){.width = 64}, 2.0f, &sky),
                     MESO_OK);
    assert_int_equal(sky->map->width, 64);
    assert_int_equal(sky->map->height, 32);
    const char *path = test_path(test_temp_dir(), "sky.hdr");
    assert_int_equal(meso_environment_save_hdr(ctx, sky, path), MESO_OK);
    assert_int_equal(meso_environment_load(ctx, path, 1.0f, &loaded), MESO_OK);
    assert_int_equal(loaded->map->width, 64);
    assert_int_equal(loaded->map->height, 32);
    /* RGBE keeps 8 bits of mantissa a texel: within 1 % of the largest channel */
    for (size_t t = 0; t < 64 * 32 * 3; t++) {
        float a = sky->map->pixels[t], b = loaded->map->pixels[t];
        float largest = fmaxf(fmaxf(sky->map->pixels[t / 3 * 3], sky->map->pixels[t / 3 * 3 + 1]),
                              sky->map->pixels[t / 3 * 3 + 2]);
        assert_float_equal(b, a, 0.01f * largest + 1e-6f);
    }
    for (int k = 0; k < MESO_SH_COUNT; k++)
        assert_float_equal(loaded->sh[1][k], sky->sh[1][k], (float)(0.01 * fabs(sky->sh[1][0])));
    /* intensity scales the map and the projection */
    meso_environment *unit = NULL;
    assert_int_equal(meso_environment_create_sky(ctx, &(meso_sky_desc){.width = 64}, 1.0f, &unit),
                     MESO_OK);
    for (int k = 0; k < MESO_SH_COUNT; k++)
        assert_float_equal(sky->sh[2][k], 2.0 * unit->sh[2][k],
                           (float)(1e-5 * fabs(sky->sh[2][0])));
    meso_environment_destroy(unit);
    meso_environment_destroy(loaded);
    meso_environment_destroy(sky);
    meso_context_destroy(ctx);
}

/* An OpenEXR map (written as half floats by meso's own writer) loads as the same radiance to
 * half precision, through the same path as a .hdr; a cut one and an EXR whose data window is
 * over the limits are refused naming the file, the second before any texel is read. */
static void test_environment_exr_loads_and_bad_exr_is_refused(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_environment *sky = NULL, *loaded = NULL;
    assert_int_equal(meso_environment_create_sky(ctx, &(meso_sky_desc){.width = 64}, 1.0f, &sky),
                     MESO_OK);
    const char *dir = test_temp_dir();
    const char *path = test_path(dir, "sky.exr");
    static const char *const names[3] = {"R", "G", "B"};
    assert_int_equal(meso_exr_write(ctx, path, 64, 32, 3, names, sky->map->pixels, true), MESO_OK);
    assert_int_equal(meso_environment_load(ctx, path, 1.0f, &loaded), MESO_OK);
    assert_int_equal(loaded->map->width, 64);
    assert_int_equal(loaded->map->height, 32);
    /* half floats: 11 bits of mantissa */
    for (size_t t = 0; t < 64 * 32 * 3; t++)
        assert_float_equal(loaded->map->pixels[t], sky->map->pixels[t],
                           1e-3f * sky->map->pixels[t] + 1e-6f);
    meso_environment_destroy(loaded);

    size_t size = 0;
    char *bytes = test_read_file(path, &size);
    const char *cut = test_path(dir, "cut.exr");
    test_write_file(cut, bytes, size / 2);
    meso_environment *env = (meso_environment *)1;
    assert_int_equal(meso_environment_load(ctx, cut, 1.0f, &env), MESO_ERROR_FORMAT);
    assert_null(env);
    assert_starts_with(meso_context_last_error(ctx), cut);
    free(bytes);

    const char *wide = test_path(dir, "wide.exr");
    float *row = calloc((size_t)(MESO_ENVIRONMENT_MAX_SIDE + 1) * 3, sizeof(float));
    assert_non_null(row);
    assert_int_equal(
        meso_exr_write(ctx, wide, MESO_ENVIRONMENT_MAX_SIDE + 1, 1, 3, names, row, true), MESO_OK);
    free(row);
    assert_int_equal(meso_environment_load(ctx, wide, 1.0f, &env), MESO_ERROR_LIMIT);
    assert_starts_with(meso_context_last_error(ctx), wide);
    meso_environment_destroy(sky);
    meso_context_destroy(ctx);
}

static void test_environment_example_map_loads(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_environment *env = NULL;
    assert_int_equal(meso_environment_load(ctx, MESO_SOURCE_DIR "/examples/sky.hdr", 1.0f, &env),
                     MESO_OK);
    assert_int_equal(env->map->width, 128);
    assert_int_equal(env->map->height, 64);
    /* the sky is brighter up than down, and blue at the zenith */
    meso_vec3 up = meso_environment_radiance(env, (meso_vec3){0, 1, 0});
    meso_vec3 down = meso_environment_radiance(env, (meso_vec3){0, -1, 0});
    assert_true(up.z > down.z && up.z > up.x);
    /* the sun lies where its direction says (the map's orientation), nowhere opposite */
    meso_vec3 sun = meso_vec3_normalize((meso_vec3){0.5f, 0.6f, 0.3f});
    meso_vec3 toward = meso_environment_radiance(env, sun);
    meso_vec3 mirrored = meso_environment_radiance(env, (meso_vec3){-sun.x, sun.y, sun.z});
    assert_true(toward.x > 50.0f && mirrored.x < 2.0f);
    meso_environment_destroy(env);
    meso_context_destroy(ctx);
}

static void test_environment_bad_files_are_refused(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_environment *env = (meso_environment *)1;
    const char *dir = test_temp_dir();

    const char *text = test_path(dir, "not-hdr.hdr");
    test_write_file(text, "hello, world\n", 13);
    assert_int_equal(meso_environment_load(ctx, text, 1.0f, &env), MESO_ERROR_FORMAT);
    assert_null(env);
    assert_starts_with(meso_context_last_error(ctx), text);

    /* a header declaring 100000 x 100000 texels: refused from the header, nothing decoded */
    const char *huge = test_path(dir, "huge.hdr");
    const char header[] = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 8000 +X 9000\n";
    test_write_file(huge, header, sizeof header - 1);
    assert_int_equal(meso_environment_load(ctx, huge, 1.0f, &env), MESO_ERROR_LIMIT);
    assert_starts_with(meso_context_last_error(ctx), huge);

    /* a valid header, then too few texels */
    const char *truncated = test_path(dir, "truncated.hdr");
    const char short_file[] = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 4 +X 4\n\x80\x80\x80\x80";
    test_write_file(truncated, short_file, sizeof short_file - 1);
    assert_int_equal(meso_environment_load(ctx, truncated, 1.0f, &env), MESO_ERROR_FORMAT);
    assert_starts_with(meso_context_last_error(ctx), truncated);

    /* a run-length encoded map cut short: stb 2.27 would loop forever on the zeros it reads
     * past the end; refused as truncated */
    size_t size = 0;
    char *sky = test_read_file(MESO_SOURCE_DIR "/examples/sky.hdr", &size);
    const char *cut = test_path(dir, "cut.hdr");
    test_write_file(cut, sky, 600);
    assert_int_equal(meso_environment_load(ctx, cut, 1.0f, &env), MESO_ERROR_FORMAT);
    assert_starts_with(meso_context_last_error(ctx), cut);
    /* and one whose run-length data holds counts of 0 (crafted): the bytes after the header of
     * a 16-wide scanline, "2 2 0 16", then zeros up to the end */
    char crafted[256];
    int start =
        snprintf(crafted, sizeof crafted, "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 16\n");
    memset(crafted + start, 0, sizeof crafted - (size_t)start);
    crafted[start] = 2;
    crafted[start + 1] = 2;
    crafted[start + 2] = 0;
    crafted[start + 3] = 16;
    const char *zeros = test_path(dir, "zeros.hdr");
    test_write_file(zeros, crafted, sizeof crafted);
    assert_int_equal(meso_environment_load(ctx, zeros, 1.0f, &env), MESO_ERROR_FORMAT);
    free(sky);

    assert_int_equal(meso_environment_load(ctx, test_path(dir, "missing.hdr"), 1.0f, &env),
                     MESO_ERROR_IO);
    assert_int_equal(meso_environment_load(ctx, MESO_SOURCE_DIR "/examples/sky.hdr", -1.0f, &env),
                     MESO_ERROR_INVALID_ARGUMENT);
    assert_int_equal(meso_environment_create_sky(ctx, &(meso_sky_desc){.width = 7}, 1.0f, &env),
                     MESO_ERROR_INVALID_ARGUMENT);
    assert_string_equal(meso_context_last_error(ctx),
                        "sky: width: 7 is not an even number in [8, 8192]");
    assert_null(env);
    meso_context_destroy(ctx);
}

static void test_environment_sampling_density_matches_the_map(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_environment *env = NULL;
    assert_int_equal(meso_environment_create_sky(ctx, &(meso_sky_desc){.width = 64}, 1.0f, &env),
                     MESO_OK);
    /* the density integrates to 1 over the sphere (a fine midpoint rule in cos theta, phi) */
    double integral = 0.0;
    const int n = 512;
    for (int a = 0; a < n; a++)
        for (int b = 0; b < 2 * n; b++) {
            double z = 1.0 - 2.0 * (a + 0.5) / n, r = sqrt(1.0 - z * z);
            double phi = 2.0 * M_PI * (b + 0.5) / (2 * n);
            meso_vec3 d = {(float)(r * cos(phi)), (float)z, (float)(r * sin(phi))};
            integral += meso_environment_pdf(env, d) * 4.0 * M_PI / (2.0 * n * n);
        }
    assert_float_equal(integral, 1.0, 2e-3);
    /* E[L/pdf] over its own samples is the integral of L: sh[.][0] sqrt(4 pi) is that integral
     * (Y_0 = 1/sqrt(4 pi)); the luminance-proportional density makes the estimate of the
     * luminance exact in every sample, of the green channel nearly so */
    double sum = 0.0;
    const int samples = 4096;
    for (int s = 0; s < samples; s++) {
        float u1 = (float)((s + 0.5) / samples), u2 = (float)fmod(s * 0.6180339887, 1.0);
        float pdf = 0.0f;
        meso_vec3 d = meso_environment_sample(env, u1, u2, &pdf);
        assert_float_equal(meso_vec3_length(d), 1.0, 1e-5);
        assert_true(pdf > 0.0f);
        assert_float_equal(pdf, meso_environment_pdf(env, d), 1e-3 * pdf);
        sum += meso_environment_radiance(env, d).y / pdf;
    }
    double expected = env->sh[1][0] * sqrt(4.0 * M_PI);
    assert_float_equal(sum / samples, expected, (float)(0.02 * expected));
    meso_environment_destroy(env);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_environment_hdr_round_trip),
        cmocka_unit_test(test_environment_exr_loads_and_bad_exr_is_refused),
        cmocka_unit_test(test_environment_example_map_loads),
        cmocka_unit_test(test_environment_bad_files_are_refused),
        cmocka_unit_test(test_environment_sampling_density_matches_the_map),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
