/* The gdm technique (Wang et al. 2004 §3.2): the 8-wide lookup against the bake's own, a closed
 * mesh without gaps, a slab solid equal to the translated base mesh (with the view along the
 * fin two prisms share), and a height field's GDM against relief_exact on a plane. Small bakes
 * (16-32 voxels a side) keep it to seconds. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gdm_lookup.h"
#include "render_internal.h"
#include "render_test_scene.h"

static const meso_option small_bake[] = {
    {"gdm", "resolution", 32},
    {"gdm", "layers", 16},
    {"gdm", "num_theta", 8},
    {"gdm", "num_phi", 16},
};
#define NUM_SMALL_BAKE (int)(sizeof small_bake / sizeof small_bake[0])

static meso_heightfield *bumps(meso_context *ctx, int resolution) {
    meso_heightfield *hf = NULL;
    meso_heightfield_desc desc = {.kind = MESO_HEIGHTFIELD_BUMPS, .resolution = resolution};
    assert_int_equal(meso_heightfield_create_procedural(ctx, &desc, &hf, NULL), MESO_OK);
    return hf;
}

static meso_framebuffer *render(meso_context *ctx, const meso_scene *scene, const char *technique,
                                const meso_option *options, int num_options) {
    meso_render_desc desc = {
        .technique = technique, .options = options, .num_options = num_options};
    meso_framebuffer *fb = NULL;
    if (meso_render_scene(ctx, scene, &desc, &fb) != MESO_OK)
        fail_msg("%s: %s", technique, meso_context_last_error(ctx));
    return fb;
}

/* The lookup's atan2 (without libm's call) is as close to the exact angle as atan2f: directions
 * of every octant, near the axes and the diagonals, and the zero vector. */
static void test_lookup_atan2_is_within_3e7_radians(void **state) {
    (void)state;
    unsigned seed = 5;
    double worst = 0.0;
    for (int i = 0; i < 200000; i++) {
        float r[2];
        for (int k = 0; k < 2; k++) r[k] = test_uniform(&seed) * 2.0f - 1.0f;
        if (i % 4 == 1) r[0] *= 1e-3f;                       /* near the x axis */
        if (i % 4 == 2) r[1] = r[0] * (1.0f + 1e-6f * r[1]); /* near a diagonal */
        double error = fabs((double)gdm_atan2(r[0], r[1]) - atan2((double)r[0], (double)r[1]));
        worst = error > worst ? error : worst;
    }
    print_message("largest difference from atan2: %.3g rad\n", worst);
    assert_true(worst < 3e-7);
    assert_true(gdm_atan2(0.0f, 0.0f) == 0.0f);
    assert_true(fabs(gdm_atan2(1.0f, -1.0f) - 0.75 * 3.14159265358979) < 3e-7);
    assert_true(fabs(gdm_atan2(-1.0f, 0.0f) + 0.5 * 3.14159265358979) < 3e-7);
}

/* gdm_axis_wrap gives meso_axis_wrap's indices and weight bit for bit, on power-of-two periods
 * (the mask) and others (the remainder), for positions in and far outside [0, n), negative
 * ones and exact integers included. */
static void test_lookup_axis_wrap_equals_math_h(void **state) {
    (void)state;
    const int periods[] = {1, 2, 3, 32, 64, 100, 128};
    unsigned seed = 11;
    for (size_t p = 0; p < sizeof periods / sizeof periods[0]; p++) {
        int n = periods[p];
        for (int i = 0; i < 20000; i++) {
            float x = (test_uniform(&seed) * 2.0f - 1.0f) * (float)(i % 3 == 0 ? n : 40 * n);
            if (i % 7 == 0) x = floorf(x); /* on a texel centre */
            meso_axis a = meso_axis_wrap(x, n), b = gdm_axis_wrap(x, n);
            assert_int_equal(a.i0, b.i0);
            assert_int_equal(a.i1, b.i1);
            assert_memory_equal(&a.w, &b.w, sizeof a.w);
        }
    }
}

/* gdm_fminf and gdm_fmaxf give libm's fminf and fmaxf bits, infinities, subnormals and NaNs
 * included (a NaN result only as a NaN). Of two zeros either may come back: C allows both and
 * GCC, taking fminf as commutative, may swap the call's operands, so libm's own pick varies
 * with the call site. */
static void test_inline_fmin_fmax_equal_libm(void **state) {
    (void)state;
    const float values[] = {0.0f,    -0.0f, 1.0f,     -1.0f,     0.5f, 1e-40f,
                            -1e-40f, 3e38f, INFINITY, -INFINITY, NAN};
    const size_t n = sizeof values / sizeof values[0];
    for (size_t i = 0; i < n; i++)
        for (size_t j = 0; j < n; j++) {
            float a = values[i], b = values[j];
            /* volatile: libm's call, not a folded constant */
            volatile float va = a, vb = b;
            float lo = fminf(va, vb), hi = fmaxf(va, vb);
            float my_lo = gdm_fminf(a, b), my_hi = gdm_fmaxf(a, b);
            if (isnan(lo) || lo == 0.0f)
                assert_true(isnan(lo) ? isnan(my_lo) : my_lo == 0.0f);
            else
                assert_memory_equal(&lo, &my_lo, sizeof lo);
            if (isnan(hi) || hi == 0.0f)
                assert_true(isnan(hi) ? isnan(my_hi) : my_hi == 0.0f);
            else
                assert_memory_equal(&hi, &my_hi, sizeof hi);
        }
}

/* gdm_lookup8 gives meso_gdm_lookup's d (one group of 8 eigen-maps and two). */
static void test_lookup8_equals_the_bakes_lookup(void **state) {
    meso_context *ctx = test_context(2);
    meso_heightfield *hf = bumps(ctx, 64);
    meso_gdm_desc desc = {
        .heightfield = hf, .width = 16, .layers = 8, .num_theta = 8, .num_phi = 8, .eigenmaps = 12};
    meso_gdm *gdm = NULL;
    assert_int_equal(meso_gdm_bake(ctx, &desc, &gdm), MESO_OK);
    meso_gdm_view view = meso_gdm_get_view(gdm);
    int ks[] = {5, 12};
    for (int c = 0; c < 2; c++) {
        gdm_lookup_table table;
        assert_true(gdm_lookup_table_init(&table, &view, ks[c]));
        assert_int_equal(table.chunks, (ks[c] + 7) / 8);
        unsigned seed = 11;
        double worst = 0.0;
        for (int i = 0; i < 4000; i++) {
            float r[6];
            for (int k = 0; k < 6; k++) r[k] = test_uniform(&seed);
            /* u, v beyond one tile and negative too; w past both faces (clamped) */
            meso_vec3 uvw = {4.0f * r[0] - 2.0f, 4.0f * r[1] - 2.0f, 1.2f * r[2] - 0.1f};
            meso_vec3 dir = meso_vec3_normalize(
                (meso_vec3){2.0f * r[3] - 1.0f, 2.0f * r[4] - 1.0f, 2.0f * r[5] - 1.0f});
            float expected = meso_gdm_lookup(gdm, uvw, dir, ks[c], false);
            float got = gdm_lookup8(&table, uvw, dir);
            double error = fabs((double)got - expected);
            worst = error > worst ? error : worst;
            if (error > 1e-5 * (1.0 + fabs(expected)))
                fail_msg("k %d at (%g, %g, %g) along (%g, %g, %g): %g, the bake's %g", ks[c], uvw.x,
                         uvw.y, uvw.z, dir.x, dir.y, dir.z, got, expected);
        }
        print_message("k = %d: largest difference %.3g\n", ks[c], worst);
        gdm_lookup_table_deinit(&table);
    }
    meso_gdm_destroy(gdm);
    meso_heightfield_destroy(hf);
    meso_context_destroy(ctx);
}

/* Adjacent prisms leave no gap. A sphere under a constant height field is a
 * smaller sphere: its pixels form one run in every row and every column (a crack between
 * prisms would show the background inside the outline). */
static void test_closed_mesh_with_a_constant_height_field_has_no_gap(void **state) {
    meso_context *ctx = test_context(2);
    test_scene ts;
    test_scene_init(&ts, 96, 96);
    ts.scene.camera = (meso_camera){{0.3f, 0.9f, 2.8f}, {0.0f, 0.0f, 0.0f}, {0, 1, 0}, 45.0f};
    meso_object *o = test_scene_add(
        &ts, test_shape(ctx, MESO_SHAPE_SPHERE, 1.0f, 24, (meso_vec3){0, 0, 0}), "gdm");
    test_object_constant_height(ctx, o, 0.2f);
    meso_mesh_scale_uvs(o->mesh, (meso_vec2){4.0f, 2.0f});
    assert_int_equal(meso_mesh_compute_tangents(ctx, o->mesh), MESO_OK);
    meso_framebuffer *fb = render(ctx, &ts.scene, "gdm", small_bake, NUM_SMALL_BAKE);
    int w = fb->width, h = fb->height;
    size_t covered = 0;
    for (int pass = 0; pass < 2; pass++)
        for (int line = 0; line < (pass ? w : h); line++) {
            int runs = 0;
            bool previous = false;
            for (int k = 0; k < (pass ? h : w); k++) {
                int x = pass ? line : k, y = pass ? k : line;
                bool c = fb->coverage[(size_t)y * w + x] > 0.0f;
                runs += c && !previous;
                previous = c;
                covered += c && pass == 0;
            }
            if (runs > 1)
                fail_msg("%s %d: %d runs of covered pixels (a gap)", pass ? "column" : "row", line,
                         runs);
        }
    /* the inner sphere of radius 0.9 at distance D covers a disc of radius
     * tan(asin(0.9 / D)) / tan(fov / 2) half-images (the mesh's 24 segments a little less) */
    double distance = meso_vec3_length(ts.scene.camera.eye);
    double radius = tan(asin(0.9 / distance)) / tan(22.5 * 3.14159265 / 180.0);
    double expected = 3.14159265 * radius * radius / 4.0 * w * h;
    print_message("covered %zu pixels, a sphere of radius 0.9: about %.0f\n", covered, expected);
    assert_true(fabs((double)covered - expected) < 0.04 * expected);
    meso_framebuffer_destroy(fb);
    test_scene_free(&ts);
    meso_context_destroy(ctx);
}

/* A built-in shape of side 2 (`segments` as test_shape takes them) drawn by gdm with a slab
 * solid `thickness` thick at the shell's floor, the shell `depth` deep; returns the solid (the
 * caller destroys it). */
static meso_solid *add_slab(meso_context *ctx, test_scene *ts, meso_shape_kind shape, int segments,
                            float depth, float thickness) {
    meso_object *o =
        test_scene_add(ts, test_shape(ctx, shape, 2.0f, segments, (meso_vec3){0, 0, 0}), "gdm");
    meso_solid *solid = NULL;
    meso_solid_desc desc = {.kind = MESO_SOLID_SLAB, .thickness = thickness};
    assert_int_equal(meso_solid_create_procedural(ctx, &desc, &solid), MESO_OK);
    o->mesostructure.kind = MESO_MESOSTRUCTURE_SOLID;
    o->mesostructure.solid = solid;
    o->mesostructure.depth = depth;
    return solid;
}

static int compare_doubles(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* A coarse sphere (8 segments: the vertex normals turn 45 degrees across a triangle) with a
 * slab solid: its surface is the level w = 0.5 mapped into the prisms, which the reference
 * traces as its iso-mesh mapped through the same map (a height field's truth displaces along
 * the normalised normal instead, a different shell on so coarse a mesh). A view ray's path through
 * such a prism bows in (u, v, w); gdm follows it (shade_one), so each hit lies on its pixel's ray
 * and the depths agree with the reference's; along the straight segment between entry and exit the
 * hit, mapped back, lies beside the ray and this test fails. */
static void test_hits_lie_on_the_ray_in_a_curved_prism(void **state) {
    meso_context *ctx = test_context(2);
    test_scene ts;
    test_scene_init(&ts, 64, 64);
    ts.scene.camera = (meso_camera){{0.4f, 0.7f, 2.6f}, {0.0f, 0.0f, 0.0f}, {0, 1, 0}, 45.0f};
    meso_solid *solid = add_slab(ctx, &ts, MESO_SHAPE_SPHERE, 8, 0.2f, 0.5f);
    meso_framebuffer *gdm = render(ctx, &ts.scene, "gdm", small_bake, NUM_SMALL_BAKE);
    meso_framebuffer *truth = render(ctx, &ts.scene, "reference", NULL, 0);
    size_t n = (size_t)gdm->width * (size_t)gdm->height, both = 0;
    double *error = malloc(n * sizeof *error);
    for (size_t i = 0; i < n; i++)
        if (gdm->coverage[i] > 0.0f && truth->coverage[i] > 0.0f)
            error[both++] = fabs((double)gdm->depth[i] - (double)truth->depth[i]) / 0.2;
    qsort(error, both, sizeof *error, compare_doubles);
    print_message("%zu pixels: depth off by %.2e (median), %.2e (95th percentile) shell depths\n",
                  both, error[both / 2], error[both * 95 / 100]);
    assert_true(both > 800);
    /* measured: 3.4e-4 and 8.4e-3 along the curve; 2.2e-3 and 2.2e-2 along the segment */
    if (error[both / 2] > 1e-3 || error[both * 95 / 100] > 1.2e-2)
        fail_msg("hits off the reference's by %g (median), %g (95th percentile) shell depths",
                 error[both / 2], error[both * 95 / 100]);
    free(error);
    meso_framebuffer_destroy(gdm);
    meso_framebuffer_destroy(truth);
    test_scene_free(&ts);
    meso_solid_destroy(solid);
    meso_context_destroy(ctx);
}

/* A slab solid equals the base mesh translated down by its thickness -- depth and
 * colour at every pixel both cover away from the border -- seen along each diagonal of the
 * plane, one of which is the fin its two prisms share: a ray along that fin must not leak
 * into the neighbour (a hole or a wrong depth on the diagonal). */
static void test_slab_solid_equals_the_translated_base_mesh(void **state) {
    meso_context *ctx = test_context(2);
    const float depth = 0.2f, thickness = 0.4f;
    meso_vec3 eyes[2] = {{-1.6f, 1.0f, -1.6f}, {1.6f, 1.0f, -1.6f}};
    for (int e = 0; e < 2; e++) {
        test_scene ts, flat;
        test_scene_init(&ts, 64, 64);
        ts.scene.camera = (meso_camera){eyes[e], {0, -0.2f, 0}, {0, 1, 0}, 50.0f};
        meso_solid *solid = add_slab(ctx, &ts, MESO_SHAPE_PLANE, 1, depth, thickness);
        test_scene_init(&flat, 64, 64);
        flat.scene.camera = ts.scene.camera;
        test_scene_add(&flat,
                       test_shape(ctx, MESO_SHAPE_PLANE, 2.0f, 1,
                                  (meso_vec3){0, -depth * (1.0f - thickness), 0}),
                       "flat");
        meso_framebuffer *a = render(ctx, &ts.scene, "gdm", small_bake, NUM_SMALL_BAKE);
        meso_framebuffer *b = render(ctx, &flat.scene, "flat", NULL, 0);
        meso_frame frame;
        meso_frame_init(&frame, &ts.scene, a->width, a->height);
        int compared = 0;
        double worst_depth = 0.0, worst_colour = 0.0;
        for (int y = 0; y < a->height; y++)
            for (int x = 0; x < a->width; x++) {
                size_t p = (size_t)y * a->width + x;
                if (!(b->coverage[p] > 0.0f)) continue;
                /* the point on the translated plane, away from the border's side walls */
                meso_vec3 dir = meso_frame_ray_direction(&frame, x + 0.5f, y + 0.5f);
                meso_vec3 q = meso_vec3_madd(frame.eye, dir, b->depth[p]);
                if (fabsf(q.x) > 0.9f || fabsf(q.z) > 0.9f) continue;
                if (!(a->coverage[p] > 0.0f))
                    fail_msg("eye %d: pixel (%d, %d) on the slab is not drawn", e, x, y);
                double dd = fabs((double)a->depth[p] - b->depth[p]);
                worst_depth = dd > worst_depth ? dd : worst_depth;
                for (int c = 0; c < 3; c++) {
                    double dc = fabs((double)a->color[3 * p + c] - b->color[3 * p + c]);
                    worst_colour = dc > worst_colour ? dc : worst_colour;
                }
                compared++;
            }
        print_message("eye %d: %d pixels, largest depth difference %.2g, colour %.2g\n", e,
                      compared, worst_depth, worst_colour);
        assert_true(compared > 1000);
        assert_true(worst_depth < 2e-3);
        assert_true(worst_colour < 2e-3);
        meso_framebuffer_destroy(a);
        meso_framebuffer_destroy(b);
        test_scene_free(&ts);
        test_scene_free(&flat);
        meso_solid_destroy(solid);
    }
    meso_context_destroy(ctx);
}

/* An open border cuts the solid: the cut face is closed by the border's fin, in the truth
 * (reference_solid.c's caps; before them a ray looked into the hollow slab and hit nothing)
 * and in gdm (an entry through a border fin inside the solid, shaded with the fin's normal and
 * lit past the border by the shell walk). Seen head-on, the slab's cut band on the plane's
 * front edge (z = 1, between the slab's top and the shell's floor) is drawn by both at the
 * same depth and in the same colour: a face of normal +z under the light. */
static void test_open_border_cut_is_closed_in_gdm_and_the_reference(void **state) {
    meso_context *ctx = test_context(2);
    const float depth = 0.2f, thickness = 0.4f;
    test_scene ts;
    test_scene_init(&ts, 64, 64);
    ts.scene.camera = (meso_camera){{0.3f, -0.05f, 3.0f}, {0, -0.16f, 0.9f}, {0, 1, 0}, 20.0f};
    ts.scene.lights[0].direction = meso_vec3_normalize((meso_vec3){0.2f, 0.5f, 0.8f});
    meso_solid *solid = add_slab(ctx, &ts, MESO_SHAPE_PLANE, 1, depth, thickness);
    meso_framebuffer *a = render(ctx, &ts.scene, "gdm", small_bake, NUM_SMALL_BAKE);
    meso_framebuffer *b = render(ctx, &ts.scene, "reference", NULL, 0);
    meso_frame frame;
    meso_frame_init(&frame, &ts.scene, a->width, a->height);
    int band = 0;
    double worst_depth = 0.0, worst_colour = 0.0;
    for (int y = 0; y < a->height; y++)
        for (int x = 0; x < a->width; x++) {
            /* the ray's point on the plane z = 1, inside the band with a margin */
            meso_vec3 dir = meso_frame_ray_direction(&frame, x + 0.5f, y + 0.5f);
            float t = (1.0f - frame.eye.z) / dir.z;
            meso_vec3 q = meso_vec3_madd(frame.eye, dir, t);
            float top = -depth * (1.0f - thickness), bottom = -depth;
            if (fabsf(q.x) > 0.9f || q.y > top - 0.01f || q.y < bottom + 0.01f) continue;
            size_t p = (size_t)y * a->width + x;
            if (!(b->coverage[p] > 0.0f))
                fail_msg("reference: (%d, %d) in the cut not drawn", x, y);
            if (!(a->coverage[p] > 0.0f)) fail_msg("gdm: (%d, %d) in the cut not drawn", x, y);
            float depth_expected = t * meso_vec3_dot(dir, frame.forward);
            double dd = fmax(fabs((double)a->depth[p] - depth_expected),
                             fabs((double)b->depth[p] - depth_expected));
            worst_depth = dd > worst_depth ? dd : worst_depth;
            for (int c = 0; c < 3; c++) {
                double dc = fabs((double)a->color[3 * p + c] - b->color[3 * p + c]);
                worst_colour = dc > worst_colour ? dc : worst_colour;
            }
            band++;
        }
    print_message("%d pixels of the cut: largest depth difference %.2g, colour %.2g\n", band,
                  worst_depth, worst_colour);
    assert_true(band > 100);
    assert_true(worst_depth < 2e-3);
    assert_true(worst_colour < 2e-3);
    meso_framebuffer_destroy(a);
    meso_framebuffer_destroy(b);
    test_scene_free(&ts);
    meso_solid_destroy(solid);
    meso_context_destroy(ctx);
}

/* A plane of bumps (64² map, depth 0.1, uv_scale 2) seen at a slant, 64², every pixel covered:
 * where gdm is checked against relief_exact. */
static void bumps_plane_scene(meso_context *ctx, test_scene *ts) {
    test_scene_init(ts, 64, 64);
    ts->scene.camera = (meso_camera){{0.3f, 0.8f, 0.9f}, {0, -0.05f, -0.1f}, {0, 1, 0}, 40.0f};
    meso_object *o =
        test_scene_add(ts, test_shape(ctx, MESO_SHAPE_PLANE, 4.0f, 1, (meso_vec3){0, 0, 0}), "gdm");
    meso_mesh_scale_uvs(o->mesh, (meso_vec2){2.0f, 2.0f});
    assert_int_equal(meso_mesh_compute_tangents(ctx, o->mesh), MESO_OK);
    o->mesostructure.kind = MESO_MESOSTRUCTURE_HEIGHT_FIELD;
    o->mesostructure.height_field = bumps(ctx, 64);
    o->mesostructure.depth = 0.1f;
}

/* The GDM of a height field draws what relief_exact draws on a plane's interior
 * (both checked against the truth elsewhere; here against each other, shadows included). */
static void test_height_field_matches_relief_exact_on_a_plane(void **state) {
    meso_context *ctx = test_context(2);
    test_scene ts;
    bumps_plane_scene(ctx, &ts);
    meso_framebuffer *a = render(ctx, &ts.scene, "gdm", small_bake, NUM_SMALL_BAKE);
    meso_framebuffer *b = render(ctx, &ts.scene, "relief_exact", NULL, 0);
    double sum = 0.0;
    size_t n = 0;
    for (size_t p = 0; p < (size_t)a->width * a->height; p++) {
        assert_true(a->coverage[p] > 0.0f && b->coverage[p] > 0.0f); /* interior only */
        for (int c = 0; c < 3; c++) {
            double d = (double)a->color[3 * p + c] - b->color[3 * p + c];
            sum += d * d;
            n++;
        }
    }
    double psnr = 10.0 * log10(1.0 / (sum / (double)n));
    print_message("gdm against relief_exact: %.2f dB\n", psnr);
    assert_true(psnr > 30.0);
    meso_framebuffer_destroy(a);
    meso_framebuffer_destroy(b);
    test_scene_free(&ts);
    meso_context_destroy(ctx);
}

/* refine_secant: a height field's hit ends with a secant step through the bracket's two
 * samples in place of the last two bisections; on the plane of bumps its depths are as close
 * to relief_exact's as the bisections' (mean |difference| in view depth, covered pixels). */
static void test_secant_step_is_as_close_as_the_bisections(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    test_scene ts;
    bumps_plane_scene(ctx, &ts);
    meso_framebuffer *exact = render(ctx, &ts.scene, "relief_exact", NULL, 0);
    double error[2];
    bool same = true;
    meso_framebuffer *fb[2];
    for (int secant = 0; secant < 2; secant++) {
        meso_option options[NUM_SMALL_BAKE + 1];
        memcpy(options, small_bake, sizeof small_bake);
        options[NUM_SMALL_BAKE] = (meso_option){"gdm", "refine_secant", secant};
        fb[secant] = render(ctx, &ts.scene, "gdm", options, NUM_SMALL_BAKE + 1);
        double sum = 0.0;
        size_t n = 0;
        for (size_t p = 0; p < 64 * 64; p++) {
            if (!(fb[secant]->coverage[p] > 0.0f && exact->coverage[p] > 0.0f)) continue;
            sum += fabs((double)fb[secant]->depth[p] - exact->depth[p]);
            n++;
        }
        assert_true(n > 3000);
        error[secant] = sum / (double)n;
    }
    for (size_t p = 0; p < 64 * 64; p++) same = same && fb[0]->depth[p] == fb[1]->depth[p];
    print_message("mean depth error against relief_exact: bisections %.3g, secant %.3g\n", error[0],
                  error[1]);
    assert_false(same); /* the option changes the hits */
    assert_true(error[1] <= 1.05 * error[0]);
    meso_framebuffer_destroy(fb[0]);
    meso_framebuffer_destroy(fb[1]);
    meso_framebuffer_destroy(exact);
    test_scene_free(&ts);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lookup_atan2_is_within_3e7_radians),
        cmocka_unit_test(test_inline_fmin_fmax_equal_libm),
        cmocka_unit_test(test_lookup_axis_wrap_equals_math_h),
        cmocka_unit_test(test_lookup8_equals_the_bakes_lookup),
        cmocka_unit_test(test_closed_mesh_with_a_constant_height_field_has_no_gap),
        cmocka_unit_test(test_hits_lie_on_the_ray_in_a_curved_prism),
        cmocka_unit_test(test_slab_solid_equals_the_translated_base_mesh),
        cmocka_unit_test(test_open_border_cut_is_closed_in_gdm_and_the_reference),
        cmocka_unit_test(test_height_field_matches_relief_exact_on_a_plane),
        cmocka_unit_test(test_secant_step_is_as_close_as_the_bisections),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
