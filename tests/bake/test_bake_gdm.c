/* GDM bake (Wang et al. 2004 §3.1, §4.1): analytic slabs, a brute-force march, compression,
 * files and threads, on tables small enough to keep the tests to seconds. */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"
#include "meso/runtime.h"

#define PI MESO_PI_D

/* A small table: 16 x 16 x 8 voxels, 8 x 8 directions (the surface is still extracted at its
 * floor of 128 x 128 x 64 cells, as for the defaults). */
static meso_gdm_desc small_desc(void) {
    return (meso_gdm_desc){
        .width = 16, .layers = 8, .num_theta = 8, .num_phi = 8, .eigenmaps = 4, .keep_raw = true};
}

static meso_heightfield *make_constant(float value) {
    meso_heightfield *hf = calloc(1, sizeof(*hf));
    hf->width = hf->height = 8;
    hf->heights = calloc(64, sizeof(float));
    for (int i = 0; i < 64; i++) hf->heights[i] = value;
    hf->wrap = MESO_WRAP_REPEAT;
    hf->hash = meso_hash64(hf->heights, 64 * sizeof(float), MESO_HASH_SEED);
    return hf;
}

static meso_heightfield *make_bumps(int side) {
    meso_heightfield *hf = make_constant(0.0f);
    free(hf->heights);
    hf->width = hf->height = side;
    hf->heights = calloc((size_t)side * (size_t)side, sizeof(float));
    for (int j = 0; j < side; j++)
        for (int i = 0; i < side; i++) {
            float x = ((float)i + 0.5f) / (float)side, y = ((float)j + 0.5f) / (float)side;
            hf->heights[j * side + i] =
                0.5f + 0.45f * sinf(6.2831853f * 2.0f * x) * cosf(6.2831853f * 2.0f * y);
        }
    hf->hash = meso_hash64(hf->heights, sizeof(float) * (size_t)side * side, MESO_HASH_SEED);
    return hf;
}

static void free_heightfield(meso_heightfield *hf) {
    free(hf->heights);
    free(hf);
}

/* The header's conventions, written out again here so that the test checks them. */
static meso_vec3 voxel_at(const meso_gdm_view *v, int i, int j, int l) {
    return (meso_vec3){((float)i + 0.5f) / (float)v->width,
                       1.0f - ((float)j + 0.5f) / (float)v->height,
                       (float)l / (float)(v->layers - 1)};
}
static meso_vec3 direction_at(const meso_gdm_view *v, int t, int p) {
    double theta = (t + 0.5) * PI / v->num_theta, phi = p * 2.0 * PI / v->num_phi;
    return (meso_vec3){(float)(sin(theta) * cos(phi)), (float)(sin(theta) * sin(phi)),
                       (float)-cos(theta)};
}
static float raw_entry(const meso_gdm_view *v, int i, int j, int l, int t, int p) {
    size_t row = ((size_t)j * v->width + i) * v->num_phi + p;
    return v->raw[(row * v->layers + l) * v->num_theta + t];
}

/* The slab w >= 1 - h: down, (1 - h - w) / cos; up, to the top w = 0; inside, 0. */
static float slab_distance(float h, meso_vec3 o, meso_vec3 dir) {
    float surface = 1.0f - h;
    if (o.z >= surface) return 0.0f;
    return dir.z > 0.0f ? (surface - o.z) / dir.z : o.z / -dir.z;
}

static void expect_slab(meso_gdm *gdm, float h) {
    meso_gdm_view v = meso_gdm_get_view(gdm);
    assert_non_null(v.raw);
    int checked = 0;
    for (int j = 0; j < v.height; j += 5)
        for (int i = 0; i < v.width; i += 3)
            for (int l = 0; l < v.layers; l++)
                for (int p = 0; p < v.num_phi; p++)
                    for (int t = 0; t < v.num_theta; t++) {
                        meso_vec3 o = voxel_at(&v, i, j, l), dir = direction_at(&v, t, p);
                        float expected = fminf(slab_distance(h, o, dir), MESO_GDM_MAX_RAY_LENGTH);
                        float got = raw_entry(&v, i, j, l, t, p);
                        if (fabsf(got - expected) > 1e-4f * (1.0f + expected))
                            fail_msg("voxel (%d, %d, %d) direction (%d, %d): d %g, expected %g", i,
                                     j, l, t, p, got, expected);
                        /* the scalar lookup at a sample point returns the sample */
                        assert_float_equal(meso_gdm_lookup(gdm, o, dir, 0, true), got,
                                           1e-4f * (1.0f + got));
                        checked++;
                    }
    assert_true(checked > 1000);
}

static void test_defaults_are_the_papers(void **state) {
    (void)state;
    meso_gdm_desc d = meso_gdm_desc_defaults(NULL);
    assert_int_equal(d.width, 64);
    assert_int_equal(d.height, 64);
    assert_int_equal(d.layers, 32);
    assert_int_equal(d.num_theta, 16);
    assert_int_equal(d.num_phi, 32);
    assert_true(d.eigenmaps >= 1 && d.eigenmaps <= 16);
    meso_gdm_desc some = {.width = 16, .num_phi = 8};
    d = meso_gdm_desc_defaults(&some);
    assert_int_equal(d.height, 16);
    assert_int_equal(d.num_phi, 8);
}

static void test_slab_solid_gives_the_analytic_distances(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_solid *solid = NULL;
    assert_int_equal(
        meso_solid_create_procedural(
            ctx, &(meso_solid_desc){.kind = MESO_SOLID_SLAB, .thickness = 0.4f}, &solid),
        MESO_OK);
    meso_gdm_desc desc = small_desc();
    desc.solid = solid;
    meso_gdm *gdm = NULL;
    assert_int_equal(meso_gdm_bake(ctx, &desc, &gdm), MESO_OK);
    expect_slab(gdm, 0.4f);
    /* the normal of the slab's top, out of the solid: up (-w) */
    meso_vec3 n = meso_gdm_normal(gdm, (meso_vec3){0.3f, 0.7f, 0.75f});
    assert_float_equal(n.x, 0.0f, 1e-3f);
    assert_float_equal(n.y, 0.0f, 1e-3f);
    assert_float_equal(n.z, -1.0f, 1e-3f);
    meso_gdm_destroy(gdm);
    meso_solid_destroy(solid);
    meso_context_destroy(ctx);
}

static void test_constant_height_field_gives_the_analytic_distances(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_heightfield *hf = make_constant(0.3f);
    meso_gdm_desc desc = small_desc();
    desc.heightfield = hf;
    meso_gdm *gdm = NULL;
    assert_int_equal(meso_gdm_bake(ctx, &desc, &gdm), MESO_OK);
    expect_slab(gdm, 0.3f);
    meso_vec3 n = meso_gdm_normal(gdm, (meso_vec3){0.1f, 0.2f, 0.1f});
    assert_float_equal(n.z, -1.0f, 1e-5f);
    meso_gdm_destroy(gdm);
    free_heightfield(hf);
    meso_context_destroy(ctx);
}

/* A tile mesh (a solid given as triangles, converted to a distance grid): a closed box over
 * u, v in [0.25, 0.75], z in [0.3, 0.7], so w in [0.3, 0.7]. Rays straight down onto its top
 * from above its middle, and up from below it (to its bottom face), are analytic. */
static void test_tile_mesh_box_gives_the_analytic_distances(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    const float lo = 0.25f, hi = 0.75f, bottom = 0.3f, top = 0.7f;
    meso_vec3 corners[8];
    for (int c = 0; c < 8; c++)
        corners[c] = (meso_vec3){c & 1 ? hi : lo, c & 2 ? hi : lo, c & 4 ? top : bottom};
    /* two outward triangles per face */
    static const uint32_t indices[36] = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                                         2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
    meso_solid *solid = NULL;
    assert_int_equal(
        meso_solid_create_from_triangles(ctx, corners, 8, indices, 12, "box", 0, &solid), MESO_OK);
    meso_gdm_desc desc = small_desc();
    desc.solid = solid;
    meso_gdm *gdm = NULL;
    assert_int_equal(meso_gdm_bake(ctx, &desc, &gdm), MESO_OK);
    meso_gdm_view v = meso_gdm_get_view(gdm);
    int checked = 0;
    for (int j = 6; j <= 9; j++)     /* v in [0.41, 0.59] */
        for (int i = 6; i <= 9; i++) /* u likewise */
            for (int l = 0; l < v.layers; l++)
                for (int p = 0; p < v.num_phi; p++) {
                    meso_vec3 o = voxel_at(&v, i, j, l);
                    float w_top = 1.0f - top, w_bottom = 1.0f - bottom;
                    /* the most vertical sampled directions: theta_0 up, theta_{T-1} down */
                    meso_vec3 up = direction_at(&v, 0, p),
                              down = direction_at(&v, v.num_theta - 1, p);
                    float d_up = raw_entry(&v, i, j, l, 0, p);
                    float d_down = raw_entry(&v, i, j, l, v.num_theta - 1, p);
                    if (o.z < w_top - 0.02f) { /* above the box: down onto its top */
                        assert_float_equal(d_down, (w_top - o.z) / down.z, 0.01f);
                        assert_float_equal(d_up, o.z / -up.z, 1e-4f);
                        checked++;
                    } else if (o.z > w_bottom + 0.02f) { /* below: up onto its bottom */
                        assert_float_equal(d_up, (o.z - w_bottom) / -up.z, 0.01f);
                        assert_float_equal(d_down, (1.0f - o.z) / down.z, 1e-4f);
                        checked++;
                    } else if (o.z > w_top + 0.02f && o.z < w_bottom - 0.02f) {
                        assert_float_equal(d_up, 0.0f, 0.0f); /* inside */
                        checked++;
                    }
                }
    assert_true(checked > 300);
    meso_gdm_destroy(gdm);
    meso_solid_destroy(solid);
    meso_context_destroy(ctx);
}

/* ---- Against a brute-force march ---------------------------------------------------------- */

static bool inside_source(const meso_solid *solid, const meso_heightfield *hf, meso_vec3 p) {
    if (solid) return meso_solid_distance(solid, p) <= 0.0f;
    return p.z >= 1.0f - meso_heightfield_sample(hf, p.x, p.y);
}

/* The first solid point along the ray by a fine march in the tiled volume (steps of 1e-3, or
 * of the solid's distance bound where that is longer: it never steps over the surface), then
 * bisection to 1e-6; where none before the slab's face, that face. */
static float march(const meso_solid *solid, const meso_heightfield *hf, meso_vec3 o,
                   meso_vec3 dir) {
    if (inside_source(solid, hf, o)) return 0.0f;
    float limit = dir.z < 0.0f ? -o.z / dir.z : (1.0f - o.z) / dir.z;
    limit = fminf(limit, MESO_GDM_MAX_RAY_LENGTH);
    float t = 0.0f;
    while (t < limit) {
        float step = 1e-3f;
        if (solid) step = fmaxf(step, meso_solid_distance(solid, meso_vec3_madd(o, dir, t)));
        float next = fminf(t + step, limit);
        if (inside_source(solid, hf, meso_vec3_madd(o, dir, next))) {
            float lo = t, hi = next;
            while (hi - lo > 1e-6f) {
                float mid = 0.5f * (lo + hi);
                if (inside_source(solid, hf, meso_vec3_madd(o, dir, mid)))
                    hi = mid;
                else
                    lo = mid;
            }
            return hi;
        }
        t = next;
    }
    return limit;
}

static int compare_floats(const void *a, const void *b) {
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/* Every 7th entry of the table against the march: the error of the traced surface (surface
 * nets for solids, texel-centre triangles for height fields) against the source itself. */
static void expect_close_to_march(meso_gdm *gdm, const meso_solid *solid,
                                  const meso_heightfield *hf, float median_limit, float p95_limit,
                                  float far_fraction_limit) {
    meso_gdm_view v = meso_gdm_get_view(gdm);
    size_t total = (size_t)v.width * v.height * v.num_phi * v.layers * v.num_theta;
    size_t count = 0;
    float *errors = malloc(sizeof(float) * (total / 7 + 1));
    for (size_t e = 0; e < total; e += 7) {
        int t = (int)(e % v.num_theta), l = (int)(e / v.num_theta % v.layers);
        size_t row = e / ((size_t)v.num_theta * v.layers);
        int p = (int)(row % v.num_phi), i = (int)(row / v.num_phi % v.width);
        int j = (int)(row / v.num_phi / v.width);
        float expected = march(solid, hf, voxel_at(&v, i, j, l), direction_at(&v, t, p));
        errors[count++] = fabsf(v.raw[e] - expected);
    }
    qsort(errors, count, sizeof(float), compare_floats);
    float median = errors[count / 2], p95 = errors[count * 95 / 100];
    size_t far = 0;
    for (size_t c = 0; c < count; c++) far += errors[c] > 0.1f;
    print_message("  %zu entries: median error %.5f, 95th percentile %.5f, max %.4f, "
                  "%.3f %% above 0.1\n",
                  count, median, p95, errors[count - 1], 100.0 * far / count);
    assert_true(median <= median_limit);
    assert_true(p95 <= p95_limit);
    assert_true((float)far / (float)count <= far_fraction_limit);
    free(errors);
}

static void test_weave_entries_match_a_brute_force_march(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_solid *solid = NULL;
    assert_int_equal(
        meso_solid_create_procedural(ctx, &(meso_solid_desc){.kind = MESO_SOLID_WEAVE}, &solid),
        MESO_OK);
    meso_gdm_desc desc = small_desc();
    desc.solid = solid;
    meso_gdm *gdm = NULL;
    assert_int_equal(meso_gdm_bake(ctx, &desc, &gdm), MESO_OK);
    expect_close_to_march(gdm, solid, NULL, 1e-3f, 5e-3f, 5e-3f);
    meso_gdm_destroy(gdm);
    meso_solid_destroy(solid);
    meso_context_destroy(ctx);
}

static void test_height_field_entries_match_a_brute_force_march(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_heightfield *hf = make_bumps(64);
    meso_gdm_desc desc = small_desc();
    desc.heightfield = hf;
    meso_gdm *gdm = NULL;
    assert_int_equal(meso_gdm_bake(ctx, &desc, &gdm), MESO_OK);
    expect_close_to_march(gdm, NULL, hf, 1e-3f, 5e-3f, 5e-3f);
    meso_gdm_destroy(gdm);
    free_heightfield(hf);
    meso_context_destroy(ctx);
}

/* ---- Compression, files, threads ---------------------------------------------------------- */

static meso_gdm *bake_weave(meso_context *ctx, meso_solid **out_solid, int eigenmaps) {
    assert_int_equal(
        meso_solid_create_procedural(ctx, &(meso_solid_desc){.kind = MESO_SOLID_WEAVE}, out_solid),
        MESO_OK);
    meso_gdm_desc desc = small_desc();
    desc.solid = *out_solid;
    desc.eigenmaps = eigenmaps;
    meso_gdm *gdm = NULL;
    assert_int_equal(meso_gdm_bake(ctx, &desc, &gdm), MESO_OK);
    return gdm;
}

/* The RMSE of the lookups at every sample point against the raw table, with k terms. */
static double lookup_rmse(meso_gdm *gdm, int k) {
    meso_gdm_view v = meso_gdm_get_view(gdm);
    double sum = 0.0;
    size_t count = 0;
    for (int j = 0; j < v.height; j += 3)
        for (int i = 0; i < v.width; i += 2)
            for (int l = 0; l < v.layers; l++)
                for (int p = 0; p < v.num_phi; p++)
                    for (int t = 0; t < v.num_theta; t++) {
                        meso_vec3 o = voxel_at(&v, i, j, l), dir = direction_at(&v, t, p);
                        double e =
                            meso_gdm_lookup(gdm, o, dir, k, false) - raw_entry(&v, i, j, l, t, p);
                        sum += e * e;
                        count++;
                    }
    return sqrt(sum / (double)count);
}

static void test_compression_error_falls_with_k(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_solid *solid = NULL;
    meso_gdm *gdm = bake_weave(ctx, &solid, 16);
    meso_gdm_compression c = meso_gdm_get_compression(gdm);
    assert_int_equal(c.num_rmse, MESO_GDM_RMSE_COUNT);
    for (int k = 1; k < MESO_GDM_RMSE_COUNT; k++) assert_true(c.rmse[k] <= c.rmse[k - 1]);
    assert_true(c.rmse[15] < 0.7f * c.rmse[0]);
    assert_true(c.rmse[0] > 0.0f);
    /* the report agrees with the lookups at the sample points (a subset of the entries, so
     * loosely), and the lookups' error falls with k too */
    double e1 = lookup_rmse(gdm, 1), e4 = lookup_rmse(gdm, 4), e16 = lookup_rmse(gdm, 16);
    print_message("  rmse k=1 %.4f (report %.4f), k=4 %.4f (%.4f), k=16 %.4f (%.4f)\n", e1,
                  c.rmse[0], e4, c.rmse[3], e16, c.rmse[15]);
    assert_true(e16 < e4 && e4 < e1);
    assert_true(fabs(e1 - c.rmse[0]) < 0.25 * c.rmse[0]);
    assert_true(fabs(e16 - c.rmse[15]) < 0.25 * c.rmse[15]);
    /* the held table let the bake measure the stored map (halves, k = 16) over every entry */
    assert_true(c.rmse_stored >= c.rmse[15] && c.rmse_stored < 1.01f * c.rmse[15] + 1e-4f);
    assert_true(c.compressed_bytes < c.raw_bytes);
    meso_gdm_destroy(gdm);
    meso_solid_destroy(solid);
    meso_context_destroy(ctx);
}

static bool same_maps(meso_gdm *a, meso_gdm *b) {
    meso_gdm_view x = meso_gdm_get_view(a), y = meso_gdm_get_view(b);
    size_t rows = (size_t)x.width * x.height * x.num_phi;
    size_t columns = (size_t)x.layers * x.num_theta;
    size_t voxels = (size_t)x.width * x.height * x.layers;
    if (memcmp(&x, &y, offsetof(meso_gdm_view, weights)) != 0) return false;
    if (memcmp(x.weights, y.weights, sizeof(float) * rows * x.num_eigen) != 0) return false;
    if (memcmp(x.eigen, y.eigen, sizeof(float) * columns * x.num_eigen) != 0) return false;
    if (memcmp(x.normals, y.normals, sizeof(float) * 3 * voxels) != 0) return false;
    if ((x.raw == NULL) != (y.raw == NULL)) return false;
    return !x.raw || memcmp(x.raw, y.raw, sizeof(float) * rows * columns) == 0;
}

static void test_same_bytes_for_one_and_two_threads(void **state) {
    (void)state;
    meso_context *one = test_context(1), *two = test_context(2);
    meso_solid *solid_one = NULL, *solid_two = NULL;
    meso_gdm *a = bake_weave(one, &solid_one, 4), *b = bake_weave(two, &solid_two, 4);
    assert_true(same_maps(a, b));
    meso_heightfield *hf = make_bumps(32);
    meso_gdm_desc desc = small_desc();
    desc.heightfield = hf;
    desc.keep_raw = false;
    meso_gdm *c = NULL, *d = NULL;
    assert_int_equal(meso_gdm_bake(one, &desc, &c), MESO_OK);
    assert_int_equal(meso_gdm_bake(two, &desc, &d), MESO_OK);
    assert_true(same_maps(c, d));
    meso_gdm_destroy(a);
    meso_gdm_destroy(b);
    meso_gdm_destroy(c);
    meso_gdm_destroy(d);
    free_heightfield(hf);
    meso_solid_destroy(solid_one);
    meso_solid_destroy(solid_two);
    meso_context_destroy(one);
    meso_context_destroy(two);
}

static void test_save_load_round_trip_and_describe(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_solid *solid = NULL;
    meso_gdm *gdm = bake_weave(ctx, &solid, 4);
    const char *path = test_path(test_temp_dir(), "weave.mesobake");
    assert_int_equal(meso_gdm_save(ctx, gdm, path), MESO_OK);
    meso_gdm *loaded = NULL;
    assert_int_equal(meso_gdm_load(ctx, path, &loaded), MESO_OK);
    assert_true(same_maps(gdm, loaded));
    meso_gdm_compression a = meso_gdm_get_compression(gdm), b = meso_gdm_get_compression(loaded);
    assert_memory_equal(a.rmse, b.rmse, sizeof(a.rmse));
    assert_true(a.rmse_stored == b.rmse_stored);
    assert_true(a.compressed_bytes == b.compressed_bytes && a.raw_bytes == b.raw_bytes);
    assert_true(b.bake_seconds == 0.0 && a.bake_seconds > 0.0);
    meso_vec3 uvw = {0.37f, 0.81f, 0.43f}, dir = {0.6f, -0.3f, 0.74f};
    assert_true(meso_gdm_lookup(gdm, uvw, dir, 0, false) ==
                meso_gdm_lookup(loaded, uvw, dir, 0, false));
    meso_bake_file *bake = NULL;
    assert_int_equal(meso_bake_file_load(ctx, path, &bake), MESO_OK);
    char text[4096];
    size_t needed = meso_gdm_describe(bake, text, sizeof(text));
    assert_true(needed > 0 && needed < sizeof(text));
    assert_non_null(strstr(text, "k= 1"));
    assert_non_null(strstr(text, "k=16"));
    assert_non_null(strstr(text, "16 x 16 x 8 voxels"));
    meso_bake_file_destroy(bake);
    meso_gdm_destroy(loaded);
    meso_gdm_destroy(gdm);
    meso_solid_destroy(solid);
    meso_context_destroy(ctx);
}

/* A tiny bake of hf saved in the test's folder as `name`; its path. */
static const char *save_tiny_bake(meso_context *ctx, meso_heightfield *hf, const char *name) {
    meso_gdm_desc desc = {
        .heightfield = hf, .width = 8, .layers = 4, .num_theta = 4, .num_phi = 4, .eigenmaps = 2};
    meso_gdm *gdm = NULL;
    assert_int_equal(meso_gdm_bake(ctx, &desc, &gdm), MESO_OK);
    const char *path = test_path(test_temp_dir(), name);
    assert_int_equal(meso_gdm_save(ctx, gdm, path), MESO_OK);
    meso_gdm_destroy(gdm);
    return path;
}

static void test_corrupted_file_is_refused_naming_it(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_heightfield *hf = make_bumps(16);
    const char *path = save_tiny_bake(ctx, hf, "corrupt.mesobake");
    meso_gdm *gdm = NULL;
    char arguments[1200];
    snprintf(arguments, sizeof(arguments), "info %s", path);
    const char *err = NULL;
    assert_int_equal(test_run_meso(arguments, &err), 0);
    size_t size = 0;
    char *bytes = test_read_file(path, &size);
    bytes[size - 40] ^= 0x10; /* in the payload, before the checksum */
    test_write_file(path, bytes, size);
    assert_int_equal(meso_gdm_load(ctx, path, &gdm), MESO_ERROR_FORMAT);
    assert_null(gdm);
    assert_non_null(strstr(meso_context_last_error(ctx), path));
    /* the program: one line naming the file, status 2 */
    assert_int_equal(test_run_meso(arguments, &err), 2);
    char expected[1200];
    snprintf(expected, sizeof(expected), "meso: %s: ", path);
    assert_true(strncmp(err, expected, strlen(expected)) == 0);
    assert_non_null(strchr(err, '\n'));
    assert_true(strchr(err, '\n')[1] == 0);
    /* a valid file of another kind is refused too */
    test_write_file(path, bytes, 0);
    assert_int_equal(meso_gdm_load(ctx, path, &gdm), MESO_ERROR_FORMAT);
    assert_non_null(strstr(meso_context_last_error(ctx), path));
    free(bytes);
    free_heightfield(hf);
    meso_context_destroy(ctx);
}

/* Files with a valid checksum whose contents do not fit: params against the arrays, values. */
static void test_inconsistent_files_with_valid_checksums_are_refused(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_heightfield *hf = make_bumps(16);
    const char *path = save_tiny_bake(ctx, hf, "inconsistent.mesobake");
    meso_gdm *gdm = NULL;
    meso_bake_file *bake = NULL;
    assert_int_equal(meso_bake_file_load(ctx, path, &bake), MESO_OK);
    /* params that claim another width: the arrays no longer fit them */
    char *params = strdup(bake->params_json);
    char *width = strstr(params, "\"width\": 8");
    assert_non_null(width);
    width[9] = '9'; /* "width": 9 */
    char *original = bake->params_json;
    bake->params_json = params;
    const char *edited = test_path(test_temp_dir(), "inconsistent_width.mesobake");
    assert_int_equal(meso_bake_file_save(ctx, bake, edited), MESO_OK);
    assert_int_equal(meso_gdm_load(ctx, edited, &gdm), MESO_ERROR_FORMAT);
    assert_non_null(strstr(meso_context_last_error(ctx), "wrong type or shape"));
    /* a NaN in an eigen-map, an out-of-range normal */
    bake->params_json = original;
    const meso_bake_array *eigen = meso_bake_file_find(bake, "eigen");
    float saved = ((float *)eigen->data)[5], nan_value = NAN;
    memcpy((float *)eigen->data + 5, &nan_value, sizeof(float));
    assert_int_equal(meso_bake_file_save(ctx, bake, edited), MESO_OK);
    assert_int_equal(meso_gdm_load(ctx, edited, &gdm), MESO_ERROR_FORMAT);
    assert_non_null(strstr(meso_context_last_error(ctx), "array \"eigen\": element 5 is nan"));
    ((float *)eigen->data)[5] = saved;
    const meso_bake_array *normals = meso_bake_file_find(bake, "normals");
    ((float *)normals->data)[7] = 1.5f;
    assert_int_equal(meso_bake_file_save(ctx, bake, edited), MESO_OK);
    assert_int_equal(meso_gdm_load(ctx, edited, &gdm), MESO_ERROR_FORMAT);
    assert_non_null(strstr(meso_context_last_error(ctx), "array \"normals\": element 7"));
    assert_null(gdm);
    free(params);
    meso_bake_file_destroy(bake);
    free_heightfield(hf);
    meso_context_destroy(ctx);
}

static void test_cached_bake_is_found_again_and_keyed_by_every_parameter(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    setenv("MESO_CACHE_DIR", test_path(test_temp_dir(), "gdm_cache"), 1);
    meso_heightfield *hf = make_bumps(16);
    meso_gdm_desc desc = {
        .heightfield = hf, .width = 8, .layers = 4, .num_theta = 4, .num_phi = 4, .eigenmaps = 2};
    meso_gdm *first = NULL, *second = NULL;
    assert_int_equal(meso_gdm_bake_cached(ctx, &desc, &first), MESO_OK);
    assert_true(meso_gdm_get_compression(first).bake_seconds > 0.0);
    assert_int_equal(meso_gdm_bake_cached(ctx, &desc, &second), MESO_OK);
    assert_true(meso_gdm_get_compression(second).bake_seconds == 0.0); /* loaded */
    assert_true(same_maps(first, second));
    uint64_t key = meso_gdm_cache_key(&desc);
    meso_gdm_desc other = desc;
    other.num_phi = 8;
    assert_true(meso_gdm_cache_key(&other) != key);
    other = desc;
    other.eigenmaps = 3;
    assert_true(meso_gdm_cache_key(&other) != key);
    other = desc;
    other.float_weights = true;
    assert_true(meso_gdm_cache_key(&other) != key);
    hf->heights[3] += 0.01f;
    hf->hash = meso_hash64(hf->heights, sizeof(float) * 256, MESO_HASH_SEED);
    assert_true(meso_gdm_cache_key(&desc) != key);
    meso_gdm_destroy(first);
    meso_gdm_destroy(second);
    unsetenv("MESO_CACHE_DIR");
    free_heightfield(hf);
    meso_context_destroy(ctx);
}

static void test_bad_descs_are_refused_before_allocating(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_heightfield *hf = make_constant(0.5f);
    meso_solid *solid = NULL;
    assert_int_equal(meso_solid_create_procedural(ctx, &(meso_solid_desc){0}, &solid), MESO_OK);
    meso_gdm *gdm = NULL;
    meso_gdm_desc both = {.heightfield = hf, .solid = solid};
    assert_int_equal(meso_gdm_bake(ctx, &both, &gdm), MESO_ERROR_INVALID_ARGUMENT);
    assert_null(gdm);
    meso_gdm_desc none = {0};
    assert_int_equal(meso_gdm_bake(ctx, &none, &gdm), MESO_ERROR_INVALID_ARGUMENT);
    meso_gdm_desc wide = {.heightfield = hf, .width = MESO_GDM_MAX_SIDE + 1};
    assert_int_equal(meso_gdm_bake(ctx, &wide, &gdm), MESO_ERROR_LIMIT);
    assert_non_null(strstr(meso_context_last_error(ctx), "width"));
    meso_gdm_desc huge = {
        .heightfield = hf, .width = 512, .layers = 256, .num_theta = 64, .num_phi = 128};
    assert_int_equal(meso_gdm_bake(ctx, &huge, &gdm), MESO_ERROR_LIMIT);
    assert_non_null(strstr(meso_context_last_error(ctx), "table"));
    meso_gdm_desc many = {.heightfield = hf,
                          .width = 4,
                          .layers = 2,
                          .num_theta = 2,
                          .num_phi = 1,
                          .eigenmaps = 5}; /* rank 4 */
    assert_int_equal(meso_gdm_bake(ctx, &many, &gdm), MESO_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(meso_context_last_error(ctx), "eigenmaps"));
    /* the default bake within a budget of 64 MiB: refused by the estimate, not by malloc */
    meso_context *small = NULL;
    assert_int_equal(meso_context_create(&(meso_context_desc){.num_threads = 1,
                                                              .memory_limit = 64u << 20,
                                                              .progress = MESO_PROGRESS_NEVER},
                                         &small),
                     MESO_OK);
    meso_gdm_desc defaults = {.heightfield = hf, .keep_raw = true};
    assert_int_equal(meso_gdm_bake(small, &defaults, &gdm), MESO_ERROR_LIMIT);
    meso_context_destroy(small);
    meso_solid_destroy(solid);
    free_heightfield(hf);
    meso_context_destroy(ctx);
}

static bool cancel_at_once(void *user, const char *label, double fraction) {
    (void)label;
    (void)fraction;
    ++*(int *)user;
    return true;
}

static void test_a_cancelled_bake_returns_cancelled_and_no_map(void **state) {
    (void)state;
    int calls = 0;
    meso_context *ctx = NULL;
    assert_int_equal(meso_context_create(&(meso_context_desc){.num_threads = 2,
                                                              .progress = MESO_PROGRESS_NEVER,
                                                              .on_progress = cancel_at_once,
                                                              .progress_user = &calls},
                                         &ctx),
                     MESO_OK);
    meso_heightfield *hf = make_bumps(16);
    meso_gdm_desc desc = small_desc();
    desc.heightfield = hf;
    meso_gdm *gdm = NULL;
    assert_int_equal(meso_gdm_bake(ctx, &desc, &gdm), MESO_ERROR_CANCELLED);
    assert_null(gdm);
    assert_true(calls > 0);
    free_heightfield(hf);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_defaults_are_the_papers),
        cmocka_unit_test(test_slab_solid_gives_the_analytic_distances),
        cmocka_unit_test(test_constant_height_field_gives_the_analytic_distances),
        cmocka_unit_test(test_tile_mesh_box_gives_the_analytic_distances),
        cmocka_unit_test(test_weave_entries_match_a_brute_force_march),
        cmocka_unit_test(test_height_field_entries_match_a_brute_force_march),
        cmocka_unit_test(test_compression_error_falls_with_k),
        cmocka_unit_test(test_same_bytes_for_one_and_two_threads),
        cmocka_unit_test(test_save_load_round_trip_and_describe),
        cmocka_unit_test(test_corrupted_file_is_refused_naming_it),
        cmocka_unit_test(test_inconsistent_files_with_valid_checksums_are_refused),
        cmocka_unit_test(test_cached_bake_is_found_again_and_keyed_by_every_parameter),
        cmocka_unit_test(test_bad_descs_are_refused_before_allocating),
        cmocka_unit_test(test_a_cancelled_bake_returns_cancelled_and_no_map),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
