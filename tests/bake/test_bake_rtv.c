/* The radiance transfer volume (bake_rtv.c): a flat surface against the closed form, a groove
 * shadowed and filled by interreflection, the SVD's error, the file round trip, corrupted files
 * refused, thread-count independence, bad descs, the cell a hit reads. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"

/* Uniform radiance 1 in every direction: only c_0 = sqrt(4 pi). */
static void uniform_radiance(float out[3][MESO_SH_COUNT]) {
    for (int c = 0; c < 3; c++)
        for (int k = 0; k < MESO_SH_COUNT; k++)
            out[c][k] = k == 0 ? sqrtf(4.0f * (float)M_PI) : 0.0f;
}

static meso_heightfield *field(meso_context *ctx, int size, float (*h)(float u, float v)) {
    meso_heightfield *hf = NULL;
    assert_int_equal(meso_heightfield_create_constant(ctx, size, size, 0.0f, &hf), MESO_OK);
    for (int j = 0; j < size; j++)
        for (int i = 0; i < size; i++)
            hf->heights[(size_t)j * size + i] =
                h(((float)i + 0.5f) / (float)size, 1.0f - ((float)j + 0.5f) / (float)size);
    meso_heightfield_update_hash(hf);
    return hf;
}

static float flat(float u, float v) { return 0.6f; }
/* a V groove across u, bottom at u = 0.5, walls at 45 degrees for aspect 0.5 */
static float groove(float u, float v) { return fabsf(2.0f * u - 1.0f); }

static void test_rtv_flat_surface_is_the_cosine_lobe(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_heightfield *hf = field(ctx, 16, flat);
    meso_rtv *rtv = NULL;
    meso_rtv_desc desc = {.heightfield = hf,
                          .aspect = 0.2f,
                          .width = 4,
                          .height = 4,
                          .layers = 3,
                          .directions = 1024};
    assert_int_equal(meso_rtv_bake(ctx, &desc, &rtv), MESO_OK);
    /* nothing shadows: T_i = 1/pi integral over the upper hemisphere of cos Y_i:
     * T_0 = Y_0 = 0.2821, T_2 = 0.4886 * 2/3 = 0.3257, T_6 = 0.3154 / 2 = 0.1577, others 0;
     * the 1024 directions' quadrature is good to ~0.5 % */
    const float expected[MESO_SH_COUNT] = {0.2821f, 0, 0.3257f, 0, 0, 0, 0.1577f};
    for (size_t v = 0; v < 4 * 4 * 3; v++)
        for (int k = 0; k < MESO_SH_COUNT; k++)
            assert_float_equal(rtv->coefficients[v * MESO_SH_COUNT + k], expected[k], 0.004);
    /* under radiance 1 everywhere it reflects 1 per unit albedo (E = pi) */
    float radiance[3][MESO_SH_COUNT], rgb[3];
    uniform_radiance(radiance);
    const meso_vec3 up = {0, 0, 1}, slanted = {0.5f, 0.3f, 0.81f};
    meso_rtv_evaluate(rtv, (meso_vec3){0.3f, 0.7f, 0.4f}, up, radiance, rgb);
    assert_float_equal(rgb[1], 1.0, 0.01);
    /* every view shows the same surface: one eigenfunction holds the table */
    meso_rtv_evaluate(rtv, (meso_vec3){0.8f, 0.1f, 0.9f}, slanted, radiance, rgb);
    assert_float_equal(rgb[1], 1.0, 0.01);
    assert_true(rtv->rmse[0] < 1e-4f);
    meso_rtv_destroy(rtv);
    meso_heightfield_destroy(hf);
    meso_context_destroy(ctx);
}

static void test_rtv_groove_is_shadowed_and_filled_by_interreflection(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_heightfield *hf = field(ctx, 64, groove);
    float radiance[3][MESO_SH_COUNT], no_bounce[3], bounce[3], top[3];
    uniform_radiance(radiance);
    meso_rtv_desc desc = {.heightfield = hf,
                          .aspect = 0.5f,
                          .width = 16,
                          .height = 2,
                          .layers = 3,
                          .directions = 512,
                          .albedo = -1.0f};
    meso_rtv *direct = NULL, *bounced = NULL;
    assert_int_equal(meso_rtv_bake(ctx, &desc, &direct), MESO_OK);
    desc.albedo = 0.7f;
    assert_int_equal(meso_rtv_bake(ctx, &desc, &bounced), MESO_OK);
    /* the voxels at the groove's bottom (u = 0.5 +- 1/32, w = 1) hold points on its walls,
     * normals 45 degrees from up, which see the sky between their own wall's plane and the
     * opposite wall's top: the 2D form factor of that window, (sin 90 + sin(-3.4)) / 2 = 0.47,
     * plus a little of the end of the far wall's top; with a bounce the walls light each other
     * (albedo 0.7); near the top of a wall more sky shows */
    const meso_vec3 up = {0, 0, 1};
    meso_rtv_evaluate(direct, (meso_vec3){0.5f, 0.5f, 1.0f}, up, radiance, no_bounce);
    meso_rtv_evaluate(bounced, (meso_vec3){0.5f, 0.5f, 1.0f}, up, radiance, bounce);
    meso_rtv_evaluate(direct, (meso_vec3){0.03f, 0.5f, 0.0f}, up, radiance, top);
    print_message("groove bottom: direct %.3f, with a bounce %.3f; near the top %.3f\n",
                  no_bounce[0], bounce[0], top[0]);
    assert_float_equal(no_bounce[0], 0.5, 0.06);
    assert_true(bounce[0] > no_bounce[0] + 0.05f);
    assert_true(bounce[0] < 1.0f);
    assert_true(top[0] > no_bounce[0] + 0.2f);
    /* the same bytes with one thread */
    meso_context *one = test_context(1);
    meso_rtv *again = NULL;
    assert_int_equal(meso_rtv_bake(one, &desc, &again), MESO_OK);
    assert_memory_equal(again->coefficients, bounced->coefficients,
                        16 * 2 * 3 * MESO_SH_COUNT * sizeof(float));
    assert_memory_equal(again->weights, bounced->weights,
                        (size_t)MESO_SH_COUNT * 16 * 2 * 3 * 4 * sizeof(float));
    /* the groove's views differ (a wall seen from across the groove or along it): the error
     * falls as eigenfunctions are added */
    print_message("groove rtv RMSE with 1, 2, 4, 8 eigenfunctions: %.4f %.4f %.4f %.4f; "
                  "%llu bytes raw, %llu compressed\n",
                  bounced->rmse[0], bounced->rmse[1], bounced->rmse[3], bounced->rmse[7],
                  (unsigned long long)bounced->raw_bytes,
                  (unsigned long long)bounced->compressed_bytes);
    assert_true(bounced->rmse[0] > bounced->rmse[3] && bounced->rmse[3] >= bounced->rmse[7]);
    meso_rtv_destroy(again);
    meso_context_destroy(one);
    meso_rtv_destroy(bounced);
    meso_rtv_destroy(direct);
    meso_heightfield_destroy(hf);
    meso_context_destroy(ctx);
}

/* A closed box [lo, hi] as 8 corners and 12 outward triangles appended to the arrays. */
static void add_box(meso_vec3 lo, meso_vec3 hi, meso_vec3 *corners, uint32_t *indices,
                    size_t *num_corners, size_t *num_triangles) {
    static const uint32_t faces[36] = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                                       2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
    for (int c = 0; c < 8; c++)
        corners[*num_corners + (size_t)c] =
            (meso_vec3){c & 1 ? hi.x : lo.x, c & 2 ? hi.y : lo.y, c & 4 ? hi.z : lo.z};
    for (int k = 0; k < 36; k++)
        indices[*num_triangles * 3 + (size_t)k] = faces[k] + (uint32_t)*num_corners;
    *num_corners += 8;
    *num_triangles += 12;
}

/* A bar thinner than two layers of voxels lying above a slab: the voxels inside the bar are
 * nearer its underside than its top, and the underside, facing the slab, is dark. Every point
 * of the bar's top sees the whole sky, so the table must say so there -- up to the bar's edges,
 * where the voxels around a top point also answer for the bar's sides. */
static void test_rtv_thin_bar_top_sees_the_whole_sky(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_vec3 corners[16];
    uint32_t indices[72];
    size_t num_corners = 0, num_triangles = 0;
    /* z is 1 - w: the bar w in [0.2, 0.35], the slab w in [0.55, 0.9] */
    add_box((meso_vec3){0.3f, 0.1f, 0.65f}, (meso_vec3){0.7f, 0.9f, 0.8f}, corners, indices,
            &num_corners, &num_triangles);
    add_box((meso_vec3){0.05f, 0.05f, 0.1f}, (meso_vec3){0.95f, 0.95f, 0.45f}, corners, indices,
            &num_corners, &num_triangles);
    meso_solid *solid = NULL;
    assert_int_equal(meso_solid_create_from_triangles(ctx, corners, num_corners, indices,
                                                      num_triangles, "bar on a slab", 64, &solid),
                     MESO_OK);
    meso_rtv *rtv = NULL;
    meso_rtv_desc desc = {
        .solid = solid, .aspect = 0.5f, .width = 16, .height = 16, .layers = 8, .directions = 256};
    assert_int_equal(meso_rtv_bake(ctx, &desc, &rtv), MESO_OK);
    /* measured: 1.01 to 1.03 (the quadrature and the SVD), 0.885 within 0.02 of the edges
     * (the voxels there answer for the sides as well); 0.67 to 0.89 when every corner voxel
     * counted */
    float radiance[3][MESO_SH_COUNT], rgb[3], lowest = INFINITY, highest = 0.0f;
    uniform_radiance(radiance);
    for (int i = 0; i <= 16; i++) {
        float u = 0.34f + 0.32f * (float)i / 16.0f;
        meso_rtv_evaluate(rtv, (meso_vec3){u, 0.5f, 0.2f}, (meso_vec3){0, 0, 1}, radiance, rgb);
        lowest = fminf(lowest, rgb[1]);
        highest = fmaxf(highest, rgb[1]);
    }
    print_message("thin bar's top under radiance 1: %.3f to %.3f\n", lowest, highest);
    assert_true(lowest > 0.95f && highest < 1.05f);
    meso_rtv_destroy(rtv);
    meso_solid_destroy(solid);
    meso_context_destroy(ctx);
}

static void test_rtv_file_round_trip_and_corruption(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_heightfield *hf = field(ctx, 32, groove);
    meso_rtv *rtv = NULL, *loaded = NULL;
    meso_rtv_desc desc = {
        .heightfield = hf, .aspect = 0.5f, .width = 8, .height = 2, .layers = 3, .directions = 128};
    assert_int_equal(meso_rtv_bake(ctx, &desc, &rtv), MESO_OK);
    const char *path = test_path(test_temp_dir(), "groove.mesobake");
    assert_int_equal(meso_rtv_save(ctx, rtv, path), MESO_OK);
    assert_int_equal(meso_rtv_load(ctx, path, &loaded), MESO_OK);
    float radiance[3][MESO_SH_COUNT], a[3], b[3];
    uniform_radiance(radiance);
    radiance[0][2] = 1.0f; /* some light from above in red */
    meso_vec3 uvw = {0.37f, 0.2f, 0.6f}, view = meso_vec3_normalize((meso_vec3){0.3f, -0.2f, 0.9f});
    meso_rtv_evaluate(rtv, uvw, view, radiance, a);
    meso_rtv_evaluate(loaded, uvw, view, radiance, b);
    assert_memory_equal(a, b, sizeof a);
    assert_int_equal(loaded->compressed_bytes, rtv->compressed_bytes);
    /* meso info's report */
    const char *out = NULL;
    char arguments[1024];
    snprintf(arguments, sizeof arguments, "info %s", path);
    assert_int_equal(test_run_meso(arguments, &out), 0);
    meso_bake_file *file = NULL;
    assert_int_equal(meso_bake_file_load(ctx, path, &file), MESO_OK);
    char report[1024];
    assert_true(meso_rtv_describe(file, report, sizeof report) > 0);
    if (!strstr(report, "rtv: 8x2x3 voxels, 4x8 views, 4 eigenfunctions") ||
        !strstr(report, "RMSE with k eigenfunctions"))
        fail_msg("%s", report);
    meso_bake_file_destroy(file);
    /* corrupted: a flipped payload byte fails the checksum; a bake of another kind, or with
     * arrays whose sizes disagree, is refused naming the file */
    size_t size = 0;
    char *bytes = test_read_file(path, &size);
    bytes[size / 2] ^= 0x40;
    const char *bad = test_path(test_temp_dir(), "bad.mesobake");
    test_write_file(bad, bytes, size);
    meso_rtv *none = (meso_rtv *)1;
    assert_int_equal(meso_rtv_load(ctx, bad, &none), MESO_ERROR_FORMAT);
    assert_null(none);
    free(bytes);
    int32_t shape[5] = {9, 2, 3, 4, 8}; /* one voxel column more than the weights hold */
    meso_bake_file wrong = {
        .kind = MESO_RTV_KIND, .kind_version = 1, .params_json = "{}", .num_arrays = 4};
    wrong.arrays[0] = (meso_bake_array){
        .name = "shape", .type = MESO_BAKE_I32, .num_dims = 1, .dims = {5}, .data = shape};
    wrong.arrays[1] = (meso_bake_array){.name = "weights",
                                        .type = MESO_BAKE_F32,
                                        .num_dims = 3,
                                        .dims = {MESO_SH_COUNT, 8 * 2 * 3, 4},
                                        .data = rtv->weights};
    wrong.arrays[2] = (meso_bake_array){.name = "eigen",
                                        .type = MESO_BAKE_F32,
                                        .num_dims = 3,
                                        .dims = {MESO_SH_COUNT, 4, 32},
                                        .data = rtv->eigen};
    wrong.arrays[3] = (meso_bake_array){.name = "rmse",
                                        .type = MESO_BAKE_F32,
                                        .num_dims = 1,
                                        .dims = {MESO_RTV_RMSE_COUNT},
                                        .data = rtv->rmse};
    assert_int_equal(meso_bake_file_save(ctx, &wrong, bad), MESO_OK);
    assert_int_equal(meso_rtv_load(ctx, bad, &none), MESO_ERROR_FORMAT);
    if (!strstr(meso_context_last_error(ctx), "sizes do not agree"))
        fail_msg("%s", meso_context_last_error(ctx));
    strcpy(wrong.kind, "vdm");
    shape[0] = 8;
    assert_int_equal(meso_bake_file_save(ctx, &wrong, bad), MESO_OK);
    assert_int_equal(meso_rtv_load(ctx, bad, &none), MESO_ERROR_FORMAT);
    /* a non-finite value behind a valid checksum */
    strcpy(wrong.kind, MESO_RTV_KIND);
    float saved = rtv->eigen[5];
    rtv->eigen[5] = INFINITY;
    assert_int_equal(meso_bake_file_save(ctx, &wrong, bad), MESO_OK);
    assert_int_equal(meso_rtv_load(ctx, bad, &none), MESO_ERROR_FORMAT);
    rtv->eigen[5] = saved;
    /* a file of version 1 (before the same-surface read) still loads; a newer one is refused */
    meso_rtv *old_version = NULL;
    assert_int_equal(meso_bake_file_save(ctx, &wrong, bad), MESO_OK);
    assert_int_equal(meso_rtv_load(ctx, bad, &old_version), MESO_OK);
    meso_rtv_destroy(old_version);
    wrong.kind_version = MESO_RTV_KIND_VERSION + 1;
    assert_int_equal(meso_bake_file_save(ctx, &wrong, bad), MESO_OK);
    assert_int_equal(meso_rtv_load(ctx, bad, &none), MESO_ERROR_FORMAT);
    assert_null(none);
    if (!strstr(meso_context_last_error(ctx), "not an rtv bake (kind \"rtv\" version 3)"))
        fail_msg("%s", meso_context_last_error(ctx));
    meso_rtv_destroy(loaded);
    meso_rtv_destroy(rtv);
    meso_heightfield_destroy(hf);
    meso_context_destroy(ctx);
}

static void test_rtv_cache_returns_the_same_table(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    /* an empty cache of its own, so the first call bakes */
    setenv("MESO_CACHE_DIR", test_temp_dir(), 1);
    meso_heightfield *hf = field(ctx, 16, groove);
    meso_rtv_desc desc = {.heightfield = hf,
                          .aspect = 0.3141f,
                          .width = 4,
                          .height = 2,
                          .layers = 2,
                          .directions = 64};
    meso_rtv *baked = NULL, *cached = NULL;
    assert_int_equal(meso_rtv_bake_cached(ctx, &desc, &baked), MESO_OK);
    assert_int_equal(meso_rtv_bake_cached(ctx, &desc, &cached), MESO_OK);
    assert_null(cached->coefficients); /* it came from the cache */
    assert_memory_equal(cached->weights, baked->weights,
                        (size_t)MESO_SH_COUNT * 4 * 2 * 2 * 4 * sizeof(float));
    meso_rtv_destroy(cached);
    /* another aspect is another entry */
    desc.aspect = 0.2718f;
    assert_int_equal(meso_rtv_bake_cached(ctx, &desc, &cached), MESO_OK);
    assert_non_null(cached->coefficients);
    meso_rtv_destroy(cached);
    meso_rtv_destroy(baked);
    meso_heightfield_destroy(hf);
    meso_context_destroy(ctx);
}

static void test_rtv_bad_descs_are_refused(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_heightfield *hf = field(ctx, 4, flat);
    meso_rtv *rtv = (meso_rtv *)1;
    assert_int_equal(meso_rtv_bake(ctx, &(meso_rtv_desc){.heightfield = hf}, &rtv),
                     MESO_ERROR_INVALID_ARGUMENT);
    assert_string_equal(meso_context_last_error(ctx), "rtv: aspect: 0 is not in (0, 100]");
    assert_null(rtv);
    assert_int_equal(meso_rtv_bake(ctx, &(meso_rtv_desc){.aspect = 1}, &rtv),
                     MESO_ERROR_INVALID_ARGUMENT);
    assert_int_equal(
        meso_rtv_bake(
            ctx,
            &(meso_rtv_desc){
                .heightfield = hf, .aspect = 1, .width = 4096, .height = 4096, .layers = 4},
            &rtv),
        MESO_ERROR_LIMIT);
    meso_heightfield_destroy(hf);
    meso_context_destroy(ctx);
}

/* The cell a hit reads, against its definition with integer divisions (the indices wrapped as
 * ((i % n) + n) % n, the weights as products of the axes' factors): the same indices and the
 * same bits at the wrap's edges -- a coordinate whose fraction rounds up to 1 (-1e-9), exact
 * integers, negative and far tiles, the layers' clamp, views at phi = -pi and pi, one whose
 * phi + 2 pi rounds to 2 pi (p = num_phi), grazing and straight-up views. */
static void test_rtv_cell_matches_the_divisions(void **state) {
    (void)state;
    meso_rtv rtv = {.width = 32, .height = 16, .layers = 8, .num_theta = 4, .num_phi = 8};
    const float coordinates[] = {-1e-9f, 0.0f,    1.0f,    0.5f,  -0.25f, 3.999999f,
                                 -7.0f,  0.0156f, 0.9844f, 1e-9f, 12.5f,  -0.984375f};
    const float depths[] = {-0.5f, 0.0f, 0.3f, 0.999f, 1.0f, 2.0f};
    const meso_vec3 views[] = {{0, 0, 1},         {1, 0, 0},           {-1, -1e-8f, 0.1f},
                               {-1, 1e-8f, 0.1f}, {1, -1e-8f, 0.1f},   {-1, 0, 0.01f},
                               {0.6f, -0.8f, 0},  {0.3f, 0.4f, 0.866f}};
    int checked = 0;
    for (size_t a = 0; a < sizeof coordinates / sizeof *coordinates; a++)
        for (size_t b = 0; b < sizeof coordinates / sizeof *coordinates; b++)
            for (size_t c = 0; c < sizeof depths / sizeof *depths; c++)
                for (size_t d = 0; d < sizeof views / sizeof *views; d++) {
                    meso_vec3 uvw = {coordinates[a], coordinates[b], depths[c]};
                    meso_rtv_cell cell;
                    meso_rtv_cell_at(&rtv, uvw, views[d], &cell);
                    float x = (uvw.x - floorf(uvw.x)) * (float)rtv.width - 0.5f;
                    float y = (1.0f - (uvw.y - floorf(uvw.y))) * (float)rtv.height - 0.5f;
                    float z = fminf(fmaxf(uvw.z, 0.0f), 1.0f) * (float)(rtv.layers - 1);
                    float fx = floorf(x), fy = floorf(y), fz = floorf(z);
                    int i0 = ((int)fx % rtv.width + rtv.width) % rtv.width;
                    int j0 = ((int)fy % rtv.height + rtv.height) % rtv.height;
                    int l0 = (int)fz < rtv.layers - 1 ? (int)fz : rtv.layers - 1;
                    for (int k = 0; k < 8; k++) {
                        int ii = k & 1 ? (i0 + 1) % rtv.width : i0;
                        int jj = k & 2 ? (j0 + 1) % rtv.height : j0;
                        int ll = k & 4 ? (l0 + 1 < rtv.layers ? l0 + 1 : l0) : l0;
                        size_t corner =
                            ((size_t)ll * (size_t)rtv.height + (size_t)jj) * (size_t)rtv.width +
                            (size_t)ii;
                        float weight = (k & 1 ? x - fx : 1.0f - (x - fx)) *
                                       (k & 2 ? y - fy : 1.0f - (y - fy)) *
                                       (k & 4 ? z - fz : 1.0f - (z - fz));
                        assert_int_equal(cell.corner[k], corner);
                        assert_memory_equal(&cell.corner_weight[k], &weight, sizeof weight);
                    }
                    float phi = atan2f(views[d].y, views[d].x);
                    float p = (phi < 0.0f ? phi + 2.0f * (float)M_PI : phi) / (2.0f * (float)M_PI) *
                              (float)rtv.num_phi;
                    int p0 = (int)p % rtv.num_phi, p1 = (p0 + 1) % rtv.num_phi;
                    assert_int_equal(cell.view_index[0] % rtv.num_phi, p0);
                    assert_int_equal(cell.view_index[1] % rtv.num_phi, p1);
                    checked++;
                }
    assert_int_equal(checked, 12 * 12 * 6 * 8);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rtv_flat_surface_is_the_cosine_lobe),
        cmocka_unit_test(test_rtv_groove_is_shadowed_and_filled_by_interreflection),
        cmocka_unit_test(test_rtv_thin_bar_top_sees_the_whole_sky),
        cmocka_unit_test(test_rtv_file_round_trip_and_corruption),
        cmocka_unit_test(test_rtv_cache_returns_the_same_table),
        cmocka_unit_test(test_rtv_bad_descs_are_refused),
        cmocka_unit_test(test_rtv_cell_matches_the_divisions),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
