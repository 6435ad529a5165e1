/* GDM bake (Wang et al. 2004 §3.1, §4.1): analytic slabs, a brute-force march, compression,
 * files and threads, on tables small enough to keep the tests to seconds. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"

#define PI 3.14159265358979323846

/* A small table: 16 x 16 x 8 voxels, 8 x 8 directions (the surface is still extracted at its
 * floor of 128 x 128 x 64 cells, as for the defaults). */
static meso_gdm_desc small_desc(void) {
    return (meso_gdm_desc){.width = 16, .layers = 8, .num_theta = 8, .num_phi = 8,
                           .eigenmaps = 4, .keep_raw = true};
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
    meso_gdm_desc d = meso_query_gdm_defaults(NULL);
    assert_int_equal(d.width, 64);
    assert_int_equal(d.height, 64);
    assert_int_equal(d.layers, 32);
    assert_int_equal(d.num_theta, 16);
    assert_int_equal(d.num_phi, 32);
    assert_true(d.eigenmaps >= 1 && d.eigenmaps <= 16);
    meso_gdm_desc some = {.width = 16, .num_phi = 8};
    d = meso_query_gdm_defaults(&some);
    assert_int_equal(d.height, 16);
    assert_int_equal(d.num_phi, 8);
}

static void test_slab_solid_gives_the_analytic_distances(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_solid *solid = NULL;
    assert_int_equal(meso_solid_create_procedural(
                         ctx, &(meso_solid_desc){.kind = MESO_SOLID_SLAB, .thickness = 0.4f},
                         &solid),
                     MESO_OK);
    meso_gdm_desc desc = small_desc();
    desc.solid = solid;
    meso_gdm *gdm = NULL;
    assert_int_equal(meso_bake_gdm(ctx, &desc, &gdm), MESO_OK);
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
    assert_int_equal(meso_bake_gdm(ctx, &desc, &gdm), MESO_OK);
    expect_slab(gdm, 0.3f);
    meso_vec3 n = meso_gdm_normal(gdm, (meso_vec3){0.1f, 0.2f, 0.1f});
    assert_float_equal(n.z, -1.0f, 1e-5f);
    meso_gdm_destroy(gdm);
    free_heightfield(hf);
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
                                  const meso_heightfield *hf, float median_limit,
                                  float p95_limit, float far_fraction_limit) {
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
    assert_int_equal(meso_bake_gdm(ctx, &desc, &gdm), MESO_OK);
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
    assert_int_equal(meso_bake_gdm(ctx, &desc, &gdm), MESO_OK);
    expect_close_to_march(gdm, NULL, hf, 1e-3f, 5e-3f, 5e-3f);
    meso_gdm_destroy(gdm);
    free_heightfield(hf);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_defaults_are_the_papers),
        cmocka_unit_test(test_slab_solid_gives_the_analytic_distances),
        cmocka_unit_test(test_constant_height_field_gives_the_analytic_distances),
        cmocka_unit_test(test_weave_entries_match_a_brute_force_march),
        cmocka_unit_test(test_height_field_entries_match_a_brute_force_march),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
