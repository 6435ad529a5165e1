/* relief and relief_exact (and the flat-field cases of parallax and horizon), shaded on
 * fragments built by hand on the built-in plane P(u,v) = (-1 + 2u, 0, 1 - 2v) (size 2), so the
 * expected hits follow from the ray's equation alone. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "technique_fixture.h"

static float h_one(int i, int j) {
    (void)i;
    (void)j;
    return 1.0f;
}
static float h_zero(int i, int j) {
    (void)i;
    (void)j;
    return 0.0f;
}
static float h_step(int i, int j) {
    (void)j;
    return i < 32 ? 1.0f : 0.0f;
}
static float h_wall(int i, int j) {
    (void)j;
    return i == 20 ? 1.0f : 0.0f;
}
static float h_bumpy(int i, int j) {
    return 0.5f + 0.25f * sinf(0.37f * (float)i) * cosf(0.23f * (float)j) +
           0.2f * sinf(0.11f * (float)(i + 2 * j));
}

#define GRID 6
static size_t grid_fragments(const fixture *fx, meso_fragment *f) {
    size_t n = 0;
    for (int j = 0; j < GRID; ++j)
        for (int i = 0; i < GRID; ++i)
            f[n++] =
                plane_fragment(fx, 0.1f + 0.8f * (float)i / GRID, 0.1f + 0.8f * (float)j / GRID);
    return n;
}

/* A field at full height everywhere is the mesh itself: every technique draws the `flat` image
 * (the flat normal) and keeps the rasterizer's depth. */
static void test_full_height_field_equals_flat_everywhere(void **state) {
    (void)state;
    fixture fx;
    fixture_init(&fx, field(NULL, 32, 32, h_one), 0.1f, (meso_vec3){0.3f, 1.2f, 2.2f},
                 (meso_vec3){0, 0, 0}, (meso_vec3){0.5f, 0.7f, 0.3f});
    meso_fragment expect[GRID * GRID], got[GRID * GRID];
    size_t n = grid_fragments(&fx, expect);
    shade_with(&fx, "flat", expect, n);
    const char *names[] = {"parallax", "horizon", "relief", "relief_exact"};
    for (int t = 0; t < 4; ++t) {
        grid_fragments(&fx, got);
        shade_with(&fx, names[t], got, n);
        for (size_t k = 0; k < n; ++k) {
            assert_false(got[k].discard);
            assert_true(got[k].out_depth == got[k].depth);
            assert_memory_equal(&got[k].color, &expect[k].color, sizeof(meso_vec3));
        }
    }
    fixture_deinit(&fx);
}

/* h = 0: the ray meets the floor plane y = -depth at t = -depth / V.y. */
static void test_zero_field_hit_is_depth_below_along_the_ray(void **state) {
    (void)state;
    fixture fx;
    const float depth = 0.1f;
    fixture_init(&fx, field(NULL, 32, 32, h_zero), depth, (meso_vec3){0.3f, 1.2f, 2.2f},
                 (meso_vec3){0, 0, 0}, (meso_vec3){0.5f, 0.7f, 0.3f});
    set_option(&fx, "shadows", 0);
    const char *names[] = {"relief", "relief_exact"};
    for (int t = 0; t < 2; ++t) {
        meso_fragment f[GRID * GRID];
        size_t n = grid_fragments(&fx, f);
        shade_with(&fx, names[t], f, n);
        for (size_t k = 0; k < n; ++k) {
            meso_vec3 view = meso_vec3_sub(f[k].position, fx.frame.eye);
            double tt = -(double)depth / (double)view.y;
            double expect = (double)f[k].depth * (1.0 + tt);
            assert_false(f[k].discard);
            assert_true(fabs((double)f[k].out_depth - expect) < 1e-5 * expect);
        }
    }
    fixture_deinit(&fx);
}

/* The exact first hit of a ray with a field that varies along u only (bilinear = piecewise
 * linear in x between texel centres), in double precision, cell by cell. Returns the depth d
 * of the hit in shell units. */
static double exact_hit_depth_1d(const meso_heightfield *hf, double x0, double xd, double a) {
    double t = 0.0;
    for (int guard = 0; guard < 100000; ++guard) {
        double x = x0 + xd * t, fx = floor(x);
        double next = xd > 0 ? fx + 1.0 : (x == fx ? fx - 1.0 : fx);
        double t1 = xd != 0.0 ? (next - x0) / xd : 1e30;
        int i = (int)fx;
        double h0 = meso_heightfield_texel(hf, i, 0), h1 = meso_heightfield_texel(hf, i + 1, 0);
        /* f(t) = a t - 1 + h0 + (h1 - h0) (x(t) - fx), linear on [t, t1] */
        double f0 = a * t - 1.0 + h0 + (h1 - h0) * (x - fx);
        if (f0 >= 0.0) return a * t;
        double slope = a + (h1 - h0) * xd;
        if (slope > 0.0 && t + (-f0) / slope <= t1) return a * (t + (-f0) / slope);
        t = t1;
    }
    return -1.0;
}

/* The hit depth d that the technique reports through its depth correction. */
static double reported_depth(const meso_fragment *f, const fixture *fx) {
    meso_vec3 view = meso_vec3_sub(f->position, fx->frame.eye);
    double t = (double)f->out_depth / (double)f->depth - 1.0;
    return t * -(double)view.y / (double)fx->object.mesostructure.depth;
}

static double analytic_depth(const meso_fragment *f, const fixture *fx) {
    meso_vec3 view = meso_vec3_sub(f->position, fx->frame.eye);
    double x0 = (double)f->uv.x * fx->hf->width - 0.5;
    double xd = (double)view.x / 2.0 * fx->hf->width;
    double a = -(double)view.y / (double)fx->object.mesostructure.depth;
    return exact_hit_depth_1d(fx->hf, x0, xd, a);
}

#define ROW 48
static void row_fragments(const fixture *fx, meso_fragment *f) {
    for (int i = 0; i < ROW; ++i) f[i] = plane_fragment(fx, 0.02f + 0.96f * (float)i / ROW, 0.5f);
}

/* A step edge seen at an oblique angle: relief_exact's hit is the analytic one to 1e-3 of the
 * depth, and relief converges to it as its steps grow. */
static void step_edge_case(int width) {
    fixture fx;
    /* eye to the left and low: rays run toward +u (+x) and meet the rising wall at the wrap */
    fixture_init(&fx, field(NULL, width, 4, h_step), 0.2f, (meso_vec3){-2.5f, 1.0f, 0.0f},
                 (meso_vec3){0.2f, 0.0f, 0.0f}, (meso_vec3){0.5f, 0.7f, 0.3f});
    set_option(&fx, "shadows", 0);
    meso_fragment f[ROW];
    row_fragments(&fx, f);
    shade_with(&fx, "relief_exact", f, ROW);
    double worst = 0.0;
    for (int i = 0; i < ROW; ++i) {
        double e = fabs(reported_depth(&f[i], &fx) - analytic_depth(&f[i], &fx));
        worst = e > worst ? e : worst;
    }
    assert_true(worst < 1e-3);

    int steps[3][2] = {{4, 0}, {16, 6}, {256, 12}};
    double mean[3];
    for (int s = 0; s < 3; ++s) {
        fx.object.num_options = 0;
        set_option(&fx, "shadows", 0);
        set_option(&fx, "linear_steps", steps[s][0]);
        set_option(&fx, "binary_steps", steps[s][1]);
        row_fragments(&fx, f);
        shade_with(&fx, "relief", f, ROW);
        mean[s] = 0.0;
        for (int i = 0; i < ROW; ++i)
            mean[s] += fabs(reported_depth(&f[i], &fx) - analytic_depth(&f[i], &fx)) / ROW;
    }
    if (getenv("MESO_TEST_VERBOSE"))
        printf("step edge %d: exact worst %.2e; relief mean %.2e %.2e %.2e\n", width, worst,
               mean[0], mean[1], mean[2]);
    assert_true(mean[0] > mean[1]);
    assert_true(mean[1] >= mean[2]);
    assert_true(mean[2] < 2e-3);
    fixture_deinit(&fx);
}

/* 64 texels: the 8-wide power-of-two traversal; 60: the general one. */
static void test_step_edge_exact_hit_and_relief_converges(void **state) {
    (void)state;
    step_edge_case(64);
    step_edge_case(60);
}

/* A wall one texel wide at full height: a 4-step linear search jumps over it, the maximum
 * mip-map traversal does not. */
static void thin_wall_case(int width) {
    fixture fx;
    fixture_init(&fx, field(NULL, width, 4, h_wall), 0.2f, (meso_vec3){-2.5f, 1.0f, 0.0f},
                 (meso_vec3){0.2f, 0.0f, 0.0f}, (meso_vec3){0.5f, 0.7f, 0.3f});
    set_option(&fx, "shadows", 0);
    /* u so that the ray starts a few texels before the wall at x = 20 */
    meso_fragment exact = plane_fragment(&fx, 18.0f / (float)width, 0.5f), coarse = exact;
    double expect = analytic_depth(&exact, &fx);
    assert_true(expect > 0.0 && expect < 0.9); /* the wall is hit above the floor */
    shade_with(&fx, "relief_exact", &exact, 1);
    assert_true(fabs(reported_depth(&exact, &fx) - expect) < 1e-3);
    set_option(&fx, "linear_steps", 4);
    shade_with(&fx, "relief", &coarse, 1);
    if (getenv("MESO_TEST_VERBOSE"))
        printf("thin wall: analytic %.4f exact %.4f relief(4) %.4f\n", expect,
               reported_depth(&exact, &fx), reported_depth(&coarse, &fx));
    assert_true(reported_depth(&coarse, &fx) > expect + 0.05);
    fixture_deinit(&fx);
}

static void test_exact_never_misses_a_thin_wall(void **state) {
    (void)state;
    thin_wall_case(64);
    thin_wall_case(60);
}

/* The floor right of a full-height block: a low light from the block's side leaves it dark
 * (ambient only), a light from the other side lights it. */
static void test_shadow_dark_behind_the_wall_lit_in_front(void **state) {
    (void)state;
    const char *names[] = {"relief", "relief_exact"};
    for (int t = 0; t < 2; ++t) {
        for (int side = 0; side < 2; ++side) {
            fixture fx;
            float u = 36.5f / 64.0f;
            meso_vec3 p = {-1.0f + 2.0f * u, 0.0f, 0.0f};
            meso_vec3 light =
                side == 0 ? (meso_vec3){-1.0f, 0.5f, 0.0f} : (meso_vec3){1.0f, 0.5f, 0.0f};
            fixture_init(&fx, field(NULL, 64, 4, h_step), 0.2f, (meso_vec3){p.x, 2.0f, 0.0f}, p,
                         light);
            meso_fragment f = plane_fragment(&fx, u, 0.5f);
            shade_with(&fx, names[t], &f, 1);
            meso_vec3 l = meso_vec3_normalize(light);
            float ambient = 0.1f, lit = 0.1f + l.y;
            float expect = side == 0 ? ambient : lit;
            assert_false(f.discard);
            assert_true(fabsf(f.color.x - 0.8f * expect) < 1e-4f);
            fixture_deinit(&fx);
        }
    }
}

/* A sphere of radius 1 seen from z = 5: near the rim the view ray leaves the curved shell
 * before it reaches a mid-height surface, so the fragment is discarded with silhouettes on and
 * kept with them off; facing the camera it is kept either way. */
/* One triangle whose vertices carry the given curvature quadrics (relief reads a mesh only for
 * them), all at one position. */
typedef struct curved_triangle {
    meso_vec3 positions[3];
    meso_vec2 quadrics[3];
    uint32_t indices[3];
    meso_mesh mesh;
} curved_triangle;

static void curved_triangle_init(curved_triangle *t, meso_vec3 position,
                                 const meso_vec2 quadrics[3]) {
    for (int i = 0; i < 3; i++) {
        t->positions[i] = position;
        t->quadrics[i] = quadrics[i];
        t->indices[i] = (uint32_t)i;
    }
    t->mesh = (meso_mesh){.num_vertices = 3,
                          .num_triangles = 1,
                          .positions = t->positions,
                          .indices = t->indices,
                          .quadrics = t->quadrics};
}

static void test_silhouettes_discard_near_the_rim_of_a_sphere(void **state) {
    (void)state;
    const char *names[] = {"relief", "relief_exact"};
    for (int t = 0; t < 2; ++t) {
        for (int on = 0; on < 2; ++on) {
            fixture fx;
            meso_context *c = test_context(1);
            meso_heightfield *hf = NULL;
            assert_int_equal(meso_heightfield_create_constant(c, 16, 16, 0.5f, &hf), MESO_OK);
            meso_context_destroy(c);
            fixture_init(&fx, hf, 0.1f, (meso_vec3){0.0f, 0.0f, 5.0f}, (meso_vec3){0, 0, 0},
                         (meso_vec3){0.0f, 0.0f, 1.0f});
            curved_triangle tri;
            curved_triangle_init(&tri, (meso_vec3){0, 0, 1},
                                 (meso_vec2[3]){{0.5f, 0.5f}, {0.5f, 0.5f}, {0.5f, 0.5f}});
            fx.object.mesh = &tri.mesh;
            set_option(&fx, "silhouettes", on);
            set_option(&fx, "shadows", 0);
            float angles[2] = {0.2f, 1.33f}; /* from the axis toward +x: facing, near the rim */
            for (int a = 0; a < 2; ++a) {
                float th = angles[a];
                meso_vec3 n = {sinf(th), 0.0f, cosf(th)};
                meso_fragment f;
                memset(&f, 0, sizeof f);
                f.position = n; /* radius 1 */
                f.normal = n;
                f.tangent = meso_vec3_scale((meso_vec3){cosf(th), 0.0f, -sinf(th)}, 6.28f);
                f.bitangent = (meso_vec3){0.0f, 3.14f, 0.0f};
                f.uv = (meso_vec2){0.3f, 0.4f};
                f.b0 = 1.0f;
                f.depth = meso_vec3_dot(meso_vec3_sub(f.position, fx.frame.eye), fx.frame.forward);
                f.out_depth = f.depth;
                shade_with(&fx, names[t], &f, 1);
                bool expect_discard = on && a == 1;
                assert_int_equal(f.discard, expect_discard);
            }
            fixture_deinit(&fx);
        }
    }
}

static void test_unknown_and_bad_options_are_rejected_by_name(void **state) {
    (void)state;
    const char *names[] = {"parallax", "horizon", "relief", "relief_exact"};
    for (int t = 0; t < 4; ++t) {
        fixture fx;
        fixture_init(&fx, field(NULL, 8, 8, h_bumpy), 0.1f, (meso_vec3){0.3f, 1.2f, 2.2f},
                     (meso_vec3){0, 0, 0}, (meso_vec3){0.5f, 0.7f, 0.3f});
        const meso_technique *tech = meso_technique_lookup(names[t]);
        assert_non_null(tech);
        void *st = NULL;
        set_option(&fx, "linear_stepz", 3);
        assert_int_equal(tech->prepare(fx.ctx, &fx.scene, &fx.object, &st),
                         MESO_ERROR_INVALID_ARGUMENT);
        assert_null(st);
        assert_non_null(strstr(meso_context_last_error(fx.ctx), "linear_stepz"));
        fx.object.num_options = 0;
        const char *bad = t == 0 ? "offset_limiting" : t == 1 ? "num_azimuths" : "shadows";
        set_option(&fx, bad, 2.5);
        assert_int_equal(tech->prepare(fx.ctx, &fx.scene, &fx.object, &st),
                         MESO_ERROR_INVALID_ARGUMENT);
        assert_null(st);
        assert_non_null(strstr(meso_context_last_error(fx.ctx), bad));
        fixture_deinit(&fx);
    }
}

/* Eight-wide batches and their scalar remainder agree: shading fragments one by one gives the
 * same bytes as shading them together. */
static void test_batches_and_single_fragments_agree(void **state) {
    (void)state;
    const char *names[] = {"parallax", "horizon", "relief", "relief_exact"};
    for (int t = 0; t < 8; ++t) {
        fixture fx;
        /* the second round clamps to the edge (relief_exact's fallback search) */
        meso_heightfield *hf = field(NULL, 64, 64, h_bumpy);
        hf->wrap = t >= 4 ? MESO_WRAP_CLAMP : MESO_WRAP_REPEAT;
        fixture_init(&fx, hf, 0.15f, (meso_vec3){0.3f, 1.0f, 2.2f}, (meso_vec3){0, 0, 0},
                     (meso_vec3){0.5f, 0.7f, 0.3f});
        meso_fragment all[GRID * GRID], one[GRID * GRID];
        size_t n = grid_fragments(&fx, all);
        grid_fragments(&fx, one);
        shade_with(&fx, names[t % 4], all, n);
        for (size_t k = 0; k < n; ++k) shade_with(&fx, names[t % 4], &one[k], 1);
        for (size_t k = 0; k < n; ++k) {
            assert_memory_equal(&all[k].color, &one[k].color, sizeof(meso_vec3));
            assert_true(all[k].out_depth == one[k].out_depth);
        }
        fixture_deinit(&fx);
    }
}

/* The rasterizer's blocks (shade_block: lanes loaded as vectors, quadrics read by gathers)
 * and the per-fragment arrays (shade) give the same bytes: on a plane and on a curved
 * triangle, with shadows, for counts that leave partial batches (relief_exact merges the
 * two groups' last rays into one vector there too). */
static void test_blocks_and_arrays_agree(void **state) {
    (void)state;
    const char *names[] = {"relief", "relief_exact"};
    enum { SIDE = 37 };
    static meso_fragment array[SIDE * SIDE], block[SIDE * SIDE];
    for (int t = 0; t < 4; ++t) {
        bool curved = t >= 2;
        fixture fx;
        fixture_init(&fx, field(NULL, 64, 64, h_bumpy), 0.15f, (meso_vec3){0.3f, 1.0f, 2.2f},
                     (meso_vec3){0, 0, 0}, (meso_vec3){0.5f, 0.7f, 0.3f});
        curved_triangle tri;
        curved_triangle_init(&tri, (meso_vec3){0, 0, 0},
                             (meso_vec2[3]){{0.4f, 0.1f}, {0.2f, 0.3f}, {0.05f, 0.25f}});
        if (curved) fx.object.mesh = &tri.mesh;
        size_t n = 0;
        for (int j = 0; j < SIDE; ++j)
            for (int i = 0; i < SIDE; ++i) {
                meso_fragment f = plane_fragment(&fx, 0.02f + 0.96f * (float)i / SIDE,
                                                 0.02f + 0.96f * (float)j / SIDE);
                f.b0 = 0.5f - 0.01f * (float)(i % 7), f.b1 = 0.3f, f.b2 = 1.0f - f.b0 - f.b1;
                array[n++] = f;
            }
        memcpy(block, array, n * sizeof *array);
        const meso_technique *tech = meso_technique_lookup(names[t % 2]);
        assert_non_null(tech->shade_block);
        void *st = NULL;
        assert_int_equal(tech->prepare(fx.ctx, &fx.scene, &fx.object, &st), MESO_OK);
        size_t parts[3] = {n, 100, 13}; /* whole, and cut into partial batches */
        for (int p = 0; p < 3; ++p) {
            memcpy(array, block, n * sizeof *array);
            for (size_t first = 0; first < n; first += parts[p]) {
                size_t count = n - first < parts[p] ? n - first : parts[p];
                tech->shade(st, &fx.frame, &fx.object, array + first, count);
            }
            meso_fragment viablock[SIDE * SIDE];
            memcpy(viablock, block, n * sizeof *block);
            assert_int_equal(meso_technique_shade(tech, st, &fx.frame, &fx.object, viablock, n),
                             MESO_OK);
            int discarded = 0;
            for (size_t k = 0; k < n; ++k) {
                assert_memory_equal(&array[k].color, &viablock[k].color, sizeof(meso_vec3));
                assert_memory_equal(&array[k].out_depth, &viablock[k].out_depth, sizeof(float));
                assert_int_equal(array[k].discard, viablock[k].discard);
                discarded += viablock[k].discard;
            }
            if (!curved) assert_int_equal(discarded, 0);
        }
        tech->release(st);
        fixture_deinit(&fx);
    }
}

/* Through the whole renderer: a small bricks scene drawn with 1 and 2 threads gives the same
 * bytes with every technique of this family (and the hits change the image: not flat). */
static void test_one_and_two_threads_render_the_same_bytes(void **state) {
    (void)state;
    const char *json =
        "{\"image\": {\"width\": 64, \"height\": 48},"
        " \"camera\": {\"eye\": [0, 1.2, 2.2], \"target\": [0, 0, 0], \"up\": [0, 1, 0],"
        " \"fov_y_deg\": 40},"
        " \"lights\": [{\"type\": \"directional\", \"direction\": [0.5, 0.7, 0.3],"
        " \"color\": [1, 1, 1]}],"
        " \"objects\": [{\"shape\": \"plane\", \"size\": 2,"
        " \"mesostructure\": {\"height_map\": {\"procedural\": \"bricks\", \"resolution\": 64},"
        " \"depth\": 0.1}}]}";
    const char *names[] = {"parallax", "horizon", "relief", "relief_exact"};
    meso_context *one = test_context(1), *two = test_context(2);
    meso_scene *scene = NULL;
    assert_int_equal(meso_scene_parse(one, json, "threads.json", NULL, &scene), MESO_OK);
    meso_framebuffer *flat = NULL;
    assert_int_equal(meso_render_scene(one, scene, &(meso_render_desc){.technique = "flat"}, &flat),
                     MESO_OK);
    for (int t = 0; t < 4; ++t) {
        meso_framebuffer *a = NULL, *b = NULL;
        meso_render_desc desc = {.technique = names[t]};
        assert_int_equal(meso_render_scene(one, scene, &desc, &a), MESO_OK);
        assert_int_equal(meso_render_scene(two, scene, &desc, &b), MESO_OK);
        size_t n = (size_t)a->width * (size_t)a->height;
        assert_memory_equal(a->color, b->color, 3 * n * sizeof(float));
        assert_memory_equal(a->depth, b->depth, n * sizeof(float));
        assert_memory_not_equal(a->color, flat->color, 3 * n * sizeof(float));
        meso_framebuffer_destroy(a);
        meso_framebuffer_destroy(b);
    }
    meso_framebuffer_destroy(flat);
    meso_scene_destroy(scene);
    meso_context_destroy(one);
    meso_context_destroy(two);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_full_height_field_equals_flat_everywhere),
        cmocka_unit_test(test_zero_field_hit_is_depth_below_along_the_ray),
        cmocka_unit_test(test_step_edge_exact_hit_and_relief_converges),
        cmocka_unit_test(test_exact_never_misses_a_thin_wall),
        cmocka_unit_test(test_shadow_dark_behind_the_wall_lit_in_front),
        cmocka_unit_test(test_silhouettes_discard_near_the_rim_of_a_sphere),
        cmocka_unit_test(test_unknown_and_bad_options_are_rejected_by_name),
        cmocka_unit_test(test_batches_and_single_fragments_agree),
        cmocka_unit_test(test_blocks_and_arrays_agree),
        cmocka_unit_test(test_one_and_two_threads_render_the_same_bytes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
