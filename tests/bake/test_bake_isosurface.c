/* Texture-space isosurfaces (dual contouring): watertight, tileable, outward, sharp features
 * kept, limits, determinism. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "meso/bake_isosurface.h"
#include "test_util.h"

/* A ball of radius 0.3 in the middle of the tile (u, v) and of the slab (w). */
static float ball(void *user, meso_vec3 p) {
    float dx = p.x - 0.5f, dy = p.y - 0.5f, dz = p.z - 0.5f;
    return sqrtf(dx * dx + dy * dy + dz * dz) - 0.3f;
}

/* Bars along u through every tile: crosses the u borders, so tiles must join. */
static float bars(void *user, meso_vec3 p) {
    float dy = p.y - 0.5f, dz = p.z - 0.5f;
    return sqrtf(dy * dy + dz * dz) - 0.2f + 0.05f * cosf(2.0f * MESO_PI * p.x);
}

/* A box turned 30 degrees about w, its faces and edges off the grid's nodes: exact distance. */
static float turned_box(void *user, meso_vec3 p) {
    const float c = 0.8660254f, s = 0.5f;
    float dx = p.x - 0.5f, dy = p.y - 0.5f, dz = p.z - 0.5f;
    float x = c * dx + s * dy, y = -s * dx + c * dy;
    float qx = fabsf(x) - 0.2137f, qy = fabsf(y) - 0.1523f, qz = fabsf(dz) - 0.2391f;
    float ox = qx > 0.0f ? qx : 0.0f, oy = qy > 0.0f ? qy : 0.0f, oz = qz > 0.0f ? qz : 0.0f;
    float in = fmaxf(qx, fmaxf(qy, qz));
    return sqrtf(ox * ox + oy * oy + oz * oz) + (in < 0.0f ? in : 0.0f);
}

/* The volume a closed outward mesh encloses (the divergence theorem). */
static double signed_volume(const meso_isosurface *iso) {
    double volume = 0.0;
    for (size_t t = 0; t < iso->num_triangles; t++) {
        meso_vec3 a = iso->positions[iso->indices[3 * t]];
        meso_vec3 b = iso->positions[iso->indices[3 * t + 1]];
        meso_vec3 c = iso->positions[iso->indices[3 * t + 2]];
        volume += meso_vec3_dot(a, meso_vec3_cross(b, c)) / 6.0;
    }
    return volume;
}

static int compare_u64(const void *a, const void *b) {
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* Every undirected edge used by exactly two triangles, in opposite directions. */
static void assert_closed(const meso_isosurface *iso) {
    size_t n = 3 * iso->num_triangles;
    uint64_t *directed = malloc(n * sizeof *directed);
    for (size_t t = 0; t < iso->num_triangles; t++)
        for (int e = 0; e < 3; e++) {
            uint64_t a = iso->indices[3 * t + e], b = iso->indices[3 * t + (e + 1) % 3];
            directed[3 * t + e] = a << 32 | b;
        }
    qsort(directed, n, sizeof *directed, compare_u64);
    for (size_t i = 0; i < n; i++) {
        if (i > 0) assert_true(directed[i] != directed[i - 1]); /* no edge twice one way */
        uint64_t reverse = directed[i] << 32 | directed[i] >> 32;
        if (!bsearch(&reverse, directed, n, sizeof *directed, compare_u64))
            fail_msg("edge %llu-%llu has no opposite", (unsigned long long)(directed[i] >> 32),
                     (unsigned long long)(directed[i] & 0xffffffffu));
    }
    free(directed);
}

/* A periodic surface is open only where it leaves the tile: every edge without an opposite
 * has both ends outside [0, 1) in u or v (in the borrowed cells below 0 or the last cells). */
static void assert_closed_or_open_at_borders(const meso_isosurface *iso) {
    size_t open = 0;
    for (size_t t = 0; t < iso->num_triangles; t++)
        for (int e = 0; e < 3; e++) {
            uint32_t a = iso->indices[3 * t + e], b = iso->indices[3 * t + (e + 1) % 3];
            bool found = false;
            for (size_t s = 0; s < iso->num_triangles && !found; s++)
                for (int f = 0; f < 3; f++)
                    if (iso->indices[3 * s + f] == b && iso->indices[3 * s + (f + 1) % 3] == a)
                        found = true;
            if (found) continue;
            meso_vec3 p = iso->positions[a], q = iso->positions[b];
            float lo = 1.0f / (float)iso->resolution_u, hi = 1.0f - lo;
            bool border = (p.x < lo || p.x > hi || p.y < lo || p.y > hi) &&
                          (q.x < lo || q.x > hi || q.y < lo || q.y > hi);
            if (!border) fail_msg("open edge inside the tile at (%g, %g, %g)", p.x, p.y, p.z);
            open++;
        }
    assert_true(open > 0);
}

static void test_isosurface_of_a_ball_is_closed_outward_and_the_right_size(void **state) {
    meso_context *ctx = test_context(2);
    meso_isosurface *iso = NULL;
    meso_isosurface_desc desc = {.resolution_u = 40, .resolution_v = 40, .resolution_w = 40};
    assert_int_equal(meso_isosurface_bake_function(ctx, ball, NULL, &desc, &iso), MESO_OK);
    assert_true(iso->num_triangles > 1000);
    assert_closed(iso);
    /* the signed volume of a closed outward mesh is the ball's */
    double volume = signed_volume(iso);
    double expected = 4.0 / 3.0 * MESO_PI * 0.3 * 0.3 * 0.3;
    if (fabs(volume - expected) > 0.04 * expected)
        fail_msg("volume %g, the ball's %g", volume, expected);
    /* columns hold their triangles */
    assert_int_equal(iso->column_offsets[40 * 40], iso->num_triangles);
    for (int c = 0; c < 40 * 40; c++) {
        int i = c % 40, j = c / 40;
        for (uint32_t t = iso->column_offsets[c]; t < iso->column_offsets[c + 1]; t++)
            for (int k = 0; k < 3; k++) {
                meso_vec3 p = iso->positions[iso->indices[3 * t + k]];
                /* within the column's cell grown by one cell (header) */
                assert_true(p.x >= (i - 1) / 40.0f - 1e-6f && p.x <= (i + 1) / 40.0f + 1e-6f);
                assert_true(p.y >= (j - 1) / 40.0f - 1e-6f && p.y <= (j + 1) / 40.0f + 1e-6f);
            }
    }
    meso_isosurface_destroy(iso);
    meso_context_destroy(ctx);
}

/* Dual contouring puts every vertex on the surface, at a box's edges and corners too: the mean
 * of the edge crossings (surface nets) cuts them off by a fraction of a cell -- the reference's
 * largest error on grid-vase's bars (docs/reference.md). */
static void test_isosurface_keeps_a_box_edges_and_corners(void **state) {
    meso_context *ctx = test_context(2);
    meso_isosurface *iso = NULL;
    const int n = 32;
    meso_isosurface_desc desc = {.resolution_u = n, .resolution_v = n, .resolution_w = n};
    assert_int_equal(meso_isosurface_bake_function(ctx, turned_box, NULL, &desc, &iso), MESO_OK);
    assert_closed(iso);
    float worst = 0.0f, highest = -1.0f;
    for (size_t i = 0; i < iso->num_vertices; i++) {
        worst = fmaxf(worst, fabsf(turned_box(NULL, iso->positions[i])));
        highest = fmaxf(highest, iso->positions[i].z);
    }
    /* in cells: 0.020 measured (the normals by differences 0.01 cells wide tilt at the edges);
     * surface nets 0.35 */
    if (worst * (float)n > 0.05f) fail_msg("a vertex %g cells off the box", worst * (float)n);
    assert_float_equal(highest, 0.5f + 0.2391f, 0.05f / (float)n); /* the top face */
    /* the volume of the box, which chamfered edges would shrink */
    double volume = signed_volume(iso);
    double expected = 8.0 * 0.2137 * 0.1523 * 0.2391;
    /* 0.11 % measured; surface nets 2.0 % */
    if (fabs(volume - expected) > 0.003 * expected)
        fail_msg("volume %g, the box's %g", volume, expected);
    meso_isosurface_destroy(iso);
    meso_context_destroy(ctx);
}

/* Bars cross u = 0 / u = 1: the vertices a tile borrows from the cells below u = 0 are the
 * last cells' vertices shifted by exactly -1, so copies of the tile side by side share them. */
static void test_isosurface_tiles_join_at_the_borders(void **state) {
    meso_context *ctx = test_context(2);
    meso_isosurface *iso = NULL;
    meso_isosurface_desc desc = {.resolution_u = 16, .resolution_v = 24, .resolution_w = 12};
    assert_int_equal(meso_isosurface_bake_function(ctx, bars, NULL, &desc, &iso), MESO_OK);
    assert_closed_or_open_at_borders(iso);
    size_t borrowed = 0, matched = 0;
    for (size_t i = 0; i < iso->num_vertices; i++) {
        meso_vec3 p = iso->positions[i];
        if (p.x >= 0.0f) continue;
        borrowed++;
        for (size_t j = 0; j < iso->num_vertices; j++) {
            meso_vec3 q = iso->positions[j];
            if (q.x == p.x + 1.0f && q.y == p.y && q.z == p.z) {
                matched++;
                break;
            }
        }
    }
    assert_true(borrowed > 10);
    assert_int_equal(matched, borrowed);
    meso_isosurface_destroy(iso);
    meso_context_destroy(ctx);
}

/* The slab caps the solid: a field negative everywhere gives the two faces w = 0 and w = 1. */
static float everything(void *user, meso_vec3 p) { return -1.0f; }

static void test_isosurface_caps_the_solid_at_the_slab_faces(void **state) {
    meso_context *ctx = test_context(1);
    meso_isosurface *iso = NULL;
    meso_isosurface_desc desc = {.resolution_u = 4, .resolution_v = 4, .resolution_w = 4};
    assert_int_equal(meso_isosurface_bake_function(ctx, everything, NULL, &desc, &iso), MESO_OK);
    for (size_t i = 0; i < iso->num_vertices; i++)
        assert_true(iso->positions[i].z == 0.0f || iso->positions[i].z == 1.0f);
    assert_true(iso->num_triangles >= 2 * 2 * 4 * 4);
    meso_isosurface_destroy(iso);
    meso_context_destroy(ctx);
}

static void test_isosurface_resolution_limits_name_the_field(void **state) {
    meso_context *ctx = test_context(1);
    meso_isosurface *iso = (meso_isosurface *)(uintptr_t)1;
    meso_isosurface_desc desc = {.resolution_u = 4, .resolution_v = 5000, .resolution_w = 4};
    assert_int_equal(meso_isosurface_bake_function(ctx, ball, NULL, &desc, &iso), MESO_ERROR_LIMIT);
    assert_null(iso);
    assert_non_null(strstr(meso_context_last_error(ctx), "resolution_v"));
    desc = (meso_isosurface_desc){.resolution_u = 1000, .resolution_v = 1000, .resolution_w = 1000};
    assert_int_equal(meso_isosurface_bake_function(ctx, ball, NULL, &desc, &iso), MESO_ERROR_LIMIT);
    assert_int_equal(meso_isosurface_bake(ctx, NULL, NULL, &iso), MESO_ERROR_INVALID_ARGUMENT);
    meso_isosurface_desc d = meso_isosurface_desc_defaults(NULL);
    assert_int_equal(d.resolution_u, 128);
    assert_int_equal(d.resolution_w, 32);
    meso_context_destroy(ctx);
}

static void test_isosurface_is_identical_for_any_thread_count(void **state) {
    meso_context *one = test_context(1), *two = test_context(2);
    meso_isosurface *a = NULL, *b = NULL;
    meso_isosurface_desc desc = {.resolution_u = 24, .resolution_v = 24, .resolution_w = 16};
    assert_int_equal(meso_isosurface_bake_function(one, bars, NULL, &desc, &a), MESO_OK);
    assert_int_equal(meso_isosurface_bake_function(two, bars, NULL, &desc, &b), MESO_OK);
    assert_int_equal(a->num_vertices, b->num_vertices);
    assert_int_equal(a->num_triangles, b->num_triangles);
    assert_memory_equal(a->positions, b->positions, a->num_vertices * sizeof *a->positions);
    assert_memory_equal(a->indices, b->indices, 3 * a->num_triangles * sizeof *a->indices);
    meso_isosurface_destroy(a);
    meso_isosurface_destroy(b);
    meso_context_destroy(one);
    meso_context_destroy(two);
}

/* The procedural weave solid extracts to a non-empty closed surface. */
static void test_isosurface_of_the_weave_solid_is_closed(void **state) {
    meso_context *ctx = test_context(2);
    meso_solid *solid = NULL;
    assert_int_equal(meso_solid_create_procedural(ctx, &(meso_solid_desc){0}, &solid), MESO_OK);
    meso_isosurface *iso = NULL;
    meso_isosurface_desc desc = {.resolution_u = 32, .resolution_v = 32, .resolution_w = 8};
    assert_int_equal(meso_isosurface_bake(ctx, solid, &desc, &iso), MESO_OK);
    assert_true(iso->num_triangles > 100);
    meso_isosurface_destroy(iso);
    meso_solid_destroy(solid);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_isosurface_of_a_ball_is_closed_outward_and_the_right_size),
        cmocka_unit_test(test_isosurface_tiles_join_at_the_borders),
        cmocka_unit_test(test_isosurface_keeps_a_box_edges_and_corners),
        cmocka_unit_test(test_isosurface_caps_the_solid_at_the_slab_faces),
        cmocka_unit_test(test_isosurface_resolution_limits_name_the_field),
        cmocka_unit_test(test_isosurface_is_identical_for_any_thread_count),
        cmocka_unit_test(test_isosurface_of_the_weave_solid_is_closed),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
