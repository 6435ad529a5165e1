/* The reference tracer's truth checks: constant height fields against the plain mesh,
 * an analytic V groove, a solid slab against a height field, grazing rays along a shared prism
 * edge, limits and determinism. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "reference_internal.h"
#include "test_util.h"

/* A plane of size 2 (two triangles) seen obliquely, one directional light. */
static const char *plane_scene(char *buffer, size_t size, int width, int height, const char *eye,
                               const char *target, const char *mesostructure,
                               const char *transform) {
    snprintf(buffer, size,
             "{\"image\": {\"width\": %d, \"height\": %d, \"background\": [0, 0, 0],"
             " \"encoding\": \"linear\"},"
             " \"camera\": {\"eye\": %s, \"target\": %s, \"up\": [0, 1, 0], \"fov_y_deg\": 40},"
             " \"ambient\": [0.1, 0.1, 0.1],"
             " \"lights\": [{\"type\": \"directional\", \"direction\": [0.3, 0.8, 0.4],"
             " \"color\": [0.9, 0.9, 0.9]}],"
             " \"objects\": [{\"shape\": \"plane\", \"size\": 2 %s%s%s,"
             " \"material\": {\"albedo\": [0.8, 0.7, 0.6]}, \"technique\": \"reference\"}]}",
             width, height, eye, target, mesostructure ? ", \"mesostructure\": " : "",
             mesostructure ? mesostructure : "", transform ? transform : "");
    return buffer;
}

static meso_scene *parse(meso_context *ctx, const char *json) {
    meso_scene *scene = NULL;
    meso_result r = meso_scene_parse(ctx, json, "test.json", NULL, &scene);
    if (r != MESO_OK) fail_msg("scene: %s", meso_context_last_error(ctx));
    return scene;
}

/* Replace the first object's height field by h(u) sampled at texel centres. */
static void set_heights(meso_context *ctx, meso_scene *scene, int width, int height,
                        float (*h)(float u, float v)) {
    meso_heightfield *hf = NULL;
    assert_int_equal(meso_heightfield_create_constant(ctx, width, height, 0.0f, &hf), MESO_OK);
    for (int j = 0; j < height; j++)
        for (int i = 0; i < width; i++)
            hf->heights[(size_t)j * width + i] =
                h(((float)i + 0.5f) / (float)width, 1.0f - ((float)j + 0.5f) / (float)height);
    meso_heightfield_update_hash(hf);
    meso_heightfield_destroy(scene->objects[0].mesostructure.height_field);
    scene->objects[0].mesostructure.height_field = hf;
}

typedef struct target {
    int width, height;
    float *color, *coverage, *depth;
} target;

static target trace(meso_context *ctx, const meso_scene *scene, const meso_reference_desc *desc) {
    target t = {scene->width, scene->height, NULL, NULL, NULL};
    size_t n = (size_t)t.width * (size_t)t.height;
    t.color = malloc(3 * n * sizeof(float));
    t.coverage = malloc(n * sizeof(float));
    t.depth = malloc(n * sizeof(float));
    meso_reference *reference = NULL;
    meso_result r = meso_reference_create_with(ctx, scene, desc, &reference);
    if (r != MESO_OK) fail_msg("reference: %s", meso_context_last_error(ctx));
    meso_frame frame;
    meso_frame_init(&frame, scene, t.width, t.height);
    assert_int_equal(meso_reference_render(ctx, reference, &frame, t.color, t.coverage, t.depth),
                     MESO_OK);
    meso_reference_destroy(reference);
    return t;
}

static void target_free(target *t) {
    free(t->color);
    free(t->coverage);
    free(t->depth);
}

/* A pixel whose 3x3 neighbourhood is covered in both: away from silhouettes. */
static bool interior(const target *a, const target *b, int x, int y) {
    for (int dy = -1; dy <= 1; dy++)
        for (int dx = -1; dx <= 1; dx++) {
            int xx = x + dx, yy = y + dy;
            if (xx < 0 || yy < 0 || xx >= a->width || yy >= a->height) return false;
            size_t p = (size_t)yy * a->width + xx;
            if (a->coverage[p] < 0.5f || b->coverage[p] < 0.5f) return false;
        }
    return true;
}

/* Colours and depths agree on interior pixels; returns how many were compared. */
static size_t assert_same_interior(const target *a, const target *b, float color_tolerance,
                                   float depth_tolerance) {
    size_t compared = 0;
    for (int y = 0; y < a->height; y++)
        for (int x = 0; x < a->width; x++) {
            if (!interior(a, b, x, y)) continue;
            size_t p = (size_t)y * a->width + x;
            for (int c = 0; c < 3; c++)
                if (fabsf(a->color[3 * p + c] - b->color[3 * p + c]) > color_tolerance)
                    fail_msg("pixel (%d, %d) channel %d: %g vs %g", x, y, c, a->color[3 * p + c],
                             b->color[3 * p + c]);
            if (depth_tolerance >= 0.0f && fabsf(a->depth[p] - b->depth[p]) > depth_tolerance)
                fail_msg("pixel (%d, %d) depth: %.7f vs %.7f", x, y, a->depth[p], b->depth[p]);
            compared++;
        }
    return compared;
}

static const meso_reference_desc texel_rule_only = {.view_adaptive = -1.0f};

static float height_one(float u, float v) { return 1.0f; }
static float height_zero(float u, float v) { return 0.0f; }
static float height_half(float u, float v) { return 0.5f; }

/* h = 1 everywhere: the micro-triangles lie on the mesh and the normal is the mesh's, so the
 * reference equals the plain mesh drawn by `flat` (same camera, linear colour). */
static void test_reference_constant_one_renders_like_flat(void **state) {
    meso_context *ctx = test_context(2);
    char json[2048];
    meso_scene *scene =
        parse(ctx, plane_scene(json, sizeof json, 96, 72, "[0.3, 1.4, 2.4]", "[0, 0, 0]",
                               "{\"height_map\": {\"procedural\": \"bricks\","
                               " \"resolution\": 32}, \"depth\": 0.2}",
                               NULL));
    set_heights(ctx, scene, 32, 32, height_one);
    target ref = trace(ctx, scene, &texel_rule_only);
    meso_framebuffer *fb = NULL;
    meso_result r = meso_render_scene(ctx, scene, &(meso_render_desc){.technique = "flat"}, &fb);
    if (r != MESO_OK) fail_msg("flat: %s", meso_context_last_error(ctx));
    target flat = {fb->width, fb->height, fb->color, fb->coverage, fb->depth};
    size_t compared = assert_same_interior(&ref, &flat, 2e-5f, 1e-4f);
    assert_true(compared > 1000);
    meso_framebuffer_destroy(fb);
    target_free(&ref);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

/* h = 0: the surface is the mesh moved by -depth along N: the same as a plain plane translated
 * by -depth (reference against reference). */
static void test_reference_zero_height_is_the_mesh_offset_by_depth(void **state) {
    meso_context *ctx = test_context(2);
    char json[2048];
    meso_scene *displaced =
        parse(ctx, plane_scene(json, sizeof json, 96, 72, "[0.3, 1.4, 2.4]", "[0, 0, 0]",
                               "{\"height_map\": {\"procedural\": \"bricks\", \"resolution\": 16},"
                               " \"depth\": 0.25}",
                               NULL));
    set_heights(ctx, displaced, 16, 16, height_zero);
    meso_scene *moved =
        parse(ctx, plane_scene(json, sizeof json, 96, 72, "[0.3, 1.4, 2.4]", "[0, 0, 0]", NULL,
                               ", \"transform\": {\"translate\": [0, -0.25, 0]}"));
    target a = trace(ctx, displaced, &texel_rule_only);
    target b = trace(ctx, moved, &texel_rule_only);
    assert_true(assert_same_interior(&a, &b, 2e-5f, 1e-5f) > 1000);
    target_free(&a);
    target_free(&b);
    meso_scene_destroy(displaced);
    meso_scene_destroy(moved);
    meso_context_destroy(ctx);
}

/* h(u) = |2u - 1|: on the plane x = 2u - 1 the surface is y = -(1 - |x|) depth, two planes. */
static float height_v_groove(float u, float v) { return fabsf(2.0f * u - 1.0f); }

static void test_reference_v_groove_hits_match_the_analytic_intersection(void **state) {
    meso_context *ctx = test_context(2);
    const float depth = 0.3f;
    char json[2048], ms[256];
    snprintf(ms, sizeof ms,
             "{\"height_map\": {\"procedural\": \"bricks\", \"resolution\": 64}, \"depth\": %g}",
             depth);
    meso_scene *scene = parse(
        ctx, plane_scene(json, sizeof json, 80, 80, "[0.2, 1.5, 1.6]", "[0, -0.1, 0]", ms, NULL));
    set_heights(ctx, scene, 64, 64, height_v_groove);
    target t = trace(ctx, scene, &texel_rule_only);
    meso_frame frame;
    meso_frame_init(&frame, scene, t.width, t.height);
    size_t checked = 0;
    double worst = 0.0;
    for (int y = 0; y < t.height; y++)
        for (int x = 0; x < t.width; x++) {
            size_t p = (size_t)y * t.width + x;
            meso_vec3 dir = meso_frame_ray_direction(&frame, x + 0.5f, y + 0.5f);
            meso_vec3 eye = frame.eye;
            /* first intersection with the two half-planes y = -(1 + s x) depth, s = +-1 */
            double best = INFINITY;
            for (int s = -1; s <= 1; s += 2) {
                /* eye.y + t dir.y = -(1 + s (eye.x + t dir.x)) depth */
                double denom = dir.y + s * depth * dir.x;
                if (fabs(denom) < 1e-12) continue;
                double tt = (-(double)depth - s * depth * eye.x - eye.y) / denom;
                double hx = eye.x + tt * dir.x, hz = eye.z + tt * dir.z;
                if (tt <= 0.0 || (s < 0 ? hx < 0.0 : hx > 0.0)) continue; /* wrong half */
                if (fabs(hx) > 1.0 || fabs(hz) > 1.0) continue;
                best = tt < best ? tt : best;
            }
            if (!isfinite(best)) continue;
            double hx = eye.x + best * dir.x, hz = eye.z + best * dir.z;
            /* away from the kinks (u = 0, 0.5, 1 flattened over a texel by the bilinear
             * sampling) and the plane's border */
            double u = (hx + 1.0) / 2.0;
            if (fabs(u - 0.5) < 3.0 / 64 || u < 3.0 / 64 || u > 1.0 - 3.0 / 64 || fabs(hz) > 0.95)
                continue;
            assert_true(t.coverage[p] == 1.0f);
            double distance = fabs(t.depth[p] - best) * meso_vec3_length(dir);
            worst = distance > worst ? distance : worst;
            checked++;
        }
    assert_true(checked > 500);
    if (worst > 1e-4 * depth) fail_msg("worst hit distance %g > 1e-4 depth", worst);
    target_free(&t);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

/* The slab 0.5 <= w <= 1 (negative inside), periodic in u and v. */
static float slab_field(void *user, meso_vec3 uvw) { return 0.5f - uvw.z; }

static const char solid_ms[] = "{\"solid\": {\"procedural\": \"weave\"}, \"depth\": 0.2}";
static const char half_ms[] =
    "{\"height_map\": {\"procedural\": \"bricks\", \"resolution\": 8}, \"depth\": 0.2}";

static void test_reference_solid_slab_renders_like_height_half(void **state) {
    meso_context *ctx = test_context(2);
    char json[2048];
    meso_scene *solid = parse(ctx, plane_scene(json, sizeof json, 96, 72, "[0.3, 1.4, 2.4]",
                                               "[0, 0, 0]", solid_ms, NULL));
    meso_scene *half = parse(
        ctx, plane_scene(json, sizeof json, 96, 72, "[0.3, 1.4, 2.4]", "[0, 0, 0]", half_ms, NULL));
    set_heights(ctx, half, 8, 8, height_half);
    meso_reference_desc desc = {
        .solid_field = slab_field,
        .isosurface = {.resolution_u = 16, .resolution_v = 16, .resolution_w = 8}};
    target a = trace(ctx, solid, &desc);
    target b = trace(ctx, half, &texel_rule_only);
    assert_true(assert_same_interior(&a, &b, 1e-4f, 1e-5f) > 1000);
    target_free(&a);
    target_free(&b);
    meso_scene_destroy(solid);
    meso_scene_destroy(half);
    meso_context_destroy(ctx);
}

/* Rays in the vertical plane of the plane's diagonal (the edge both triangles share) hit the
 * slab's top right on the edge where the two prisms' pieces meet: none may pass through. */
static void test_reference_rays_grazing_a_shared_prism_edge_never_leak(void **state) {
    meso_context *ctx = test_context(2);
    char json[2048];
    meso_scene *probe =
        parse(ctx, plane_scene(json, sizeof json, 8, 8, "[0, 2, 2]", "[0, 0, 0]", solid_ms, NULL));
    /* the shared edge: the vertex pair used by both triangles */
    const meso_mesh *mesh = probe->objects[0].mesh;
    assert_int_equal(mesh->num_triangles, 2);
    meso_vec3 a = {0}, b = {0};
    int found = 0;
    for (int i = 0; i < 3 && !found; i++)
        for (int j = 0; j < 3 && !found; j++) {
            uint32_t p0 = mesh->indices[i], p1 = mesh->indices[(i + 1) % 3];
            uint32_t q0 = mesh->indices[3 + j], q1 = mesh->indices[3 + (j + 1) % 3];
            if ((p0 == q1 && p1 == q0) || (p0 == q0 && p1 == q1)) {
                a = mesh->positions[p0];
                b = mesh->positions[p1];
                found = 1;
            }
        }
    assert_true(found);
    meso_vec3 along = meso_vec3_sub(b, a);
    char eye[128], target_text[128];
    snprintf(eye, sizeof eye, "[%.9g, 0.25, %.9g]", a.x - 0.4f * along.x, a.z - 0.4f * along.z);
    snprintf(target_text, sizeof target_text, "[%.9g, -0.1, %.9g]", b.x, b.z);
    meso_scene *scene =
        parse(ctx, plane_scene(json, sizeof json, 65, 65, eye, target_text, solid_ms, NULL));
    meso_reference_desc desc = {
        .solid_field = slab_field,
        .isosurface = {.resolution_u = 64, .resolution_v = 64, .resolution_w = 16}};
    target t = trace(ctx, scene, &desc);
    meso_frame frame;
    meso_frame_init(&frame, scene, t.width, t.height);
    size_t expected = 0;
    for (int y = 0; y < t.height; y++)
        for (int x = 0; x < t.width; x++) {
            meso_vec3 dir = meso_frame_ray_direction(&frame, x + 0.5f, y + 0.5f);
            /* the slab's top at y = -0.5 depth = -0.1 */
            if (dir.y >= 0.0f) continue;
            float tt = (-0.1f - frame.eye.y) / dir.y;
            float hx = frame.eye.x + tt * dir.x, hz = frame.eye.z + tt * dir.z;
            if (fabsf(hx) > 0.98f || fabsf(hz) > 0.98f) continue;
            expected++;
            size_t p = (size_t)y * t.width + x;
            if (t.coverage[p] != 1.0f) fail_msg("pixel (%d, %d) passes through the shell", x, y);
            if (fabsf(t.depth[p] - tt) > 1e-3f * tt)
                fail_msg("pixel (%d, %d) hits at depth %g, the slab is at %g", x, y, t.depth[p],
                         tt);
        }
    if (expected < 400) fail_msg("only %zu pixels see the slab", expected);
    target_free(&t);
    meso_scene_destroy(probe);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

static void test_reference_too_many_triangles_is_a_limit_error_naming_the_object(void **state) {
    meso_context *ctx = test_context(2);
    char json[2048];
    meso_scene *scene =
        parse(ctx, plane_scene(json, sizeof json, 16, 16, "[0, 2, 2]", "[0, 0, 0]",
                               "{\"height_map\": {\"procedural\": \"bricks\", \"resolution\": 512},"
                               " \"depth\": 0.1}",
                               ", \"uv_scale\": [64, 64]"));
    meso_reference *reference = (meso_reference *)(uintptr_t)1;
    /* 2 x (64 * 512)^2 = 2.1e9 micro-triangles: refused before any is allocated */
    assert_int_equal(meso_reference_create_with(ctx, scene, &texel_rule_only, &reference),
                     MESO_ERROR_LIMIT);
    assert_null(reference);
    const char *message = meso_context_last_error(ctx);
    assert_non_null(strstr(message, "objects[0]"));
    assert_non_null(strstr(message, "2147483648"));
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

/* The same tiling under the default view cap (2 segments a pixel of the scene's 16 x 16 image)
 * stays far below the limit and still renders the plane. */
static void test_reference_view_cap_bounds_triangles_by_pixels(void **state) {
    meso_context *ctx = test_context(2);
    char json[2048];
    meso_scene *scene =
        parse(ctx, plane_scene(json, sizeof json, 16, 16, "[0, 2, 2]", "[0, 0, 0]",
                               "{\"height_map\": {\"procedural\": \"bricks\", \"resolution\": 512},"
                               " \"depth\": 0.1}",
                               ", \"uv_scale\": [64, 64]"));
    meso_reference *reference = NULL;
    assert_int_equal(meso_reference_create(ctx, scene, &reference), MESO_OK);
    uint64_t triangles = meso_reference_triangle_count(reference);
    assert_true(triangles > 100 && triangles < 20000);
    assert_true(meso_reference_memory(reference) > 0);
    meso_reference_destroy(reference);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

static void test_reference_output_is_identical_for_any_thread_count(void **state) {
    char json[2048];
    meso_context *one = test_context(1), *two = test_context(2);
    meso_scene *scene =
        parse(one, plane_scene(json, sizeof json, 64, 48, "[0.3, 1.4, 2.4]", "[0, 0, 0]",
                               "{\"height_map\": {\"procedural\": \"bricks\","
                               " \"resolution\": 64}, \"depth\": 0.15}",
                               NULL));
    meso_scene *solid = parse(one, plane_scene(json, sizeof json, 64, 48, "[0.3, 1.4, 2.4]",
                                               "[0, 0, 0]", solid_ms, ", \"uv_scale\": [3, 2]"));
    meso_reference_desc weave = {
        .isosurface = {.resolution_u = 32, .resolution_v = 32, .resolution_w = 8}};
    const meso_scene *scenes[2] = {scene, solid};
    const meso_reference_desc *descs[2] = {NULL, &weave};
    for (int s = 0; s < 2; s++) {
        target a = trace(one, scenes[s], descs[s]), b = trace(two, scenes[s], descs[s]);
        size_t n = (size_t)a.width * (size_t)a.height;
        assert_memory_equal(a.color, b.color, 3 * n * sizeof(float));
        assert_memory_equal(a.depth, b.depth, n * sizeof(float));
        assert_memory_equal(a.coverage, b.coverage, n * sizeof(float));
        size_t covered = 0;
        for (size_t p = 0; p < n; p++) covered += a.coverage[p] > 0.5f;
        assert_true(covered > n / 4);
        target_free(&a);
        target_free(&b);
    }
    meso_scene_destroy(solid);
    meso_scene_destroy(scene);
    meso_context_destroy(one);
    meso_context_destroy(two);
}

/* The sRGB encoding the PNGs carry, so a PSNR here is the one `meso compare` reports. */
static float srgb(float x) {
    x = x < 0.0f ? 0.0f : x > 1.0f ? 1.0f : x;
    return x <= 0.0031308f ? 12.92f * x : 1.055f * powf(x, 1.0f / 2.4f) - 0.055f;
}

static double srgb_psnr(const target *a, const target *b) {
    size_t n = 3 * (size_t)a->width * (size_t)a->height;
    double sum = 0.0;
    for (size_t i = 0; i < n; i++) {
        double d = (double)srgb(a->color[i]) - (double)srgb(b->color[i]);
        sum += d * d;
    }
    return sum > 0.0 ? 10.0 * log10((double)n / sum) : INFINITY;
}

/* The truth of an impostor is the object it stands for (Policarpo & Oliveira 2006 §4): the
 * reference of the teapot impostor on its quad (the quad through the model's middle) draws
 * the built-in teapot where the teapot itself stands, from views above, beside and below. */
static void test_reference_of_an_impostor_is_the_model_it_stands_for(void **state) {
    static const char *const eyes[] = {"[2.2, 2.6, 3.6]", "[-3.5, 0.4, 1.2]", "[0.8, -2.8, 2.5]"};
    meso_context *ctx = test_context(0);
    for (int e = 0; e < 3; e++) {
        char json[2048];
        static const char *const format =
            "{\"image\": {\"width\": 96, \"height\": 96, \"background\": [0.02, 0.02, 0.03],"
            " \"encoding\": \"linear\"},"
            " \"camera\": {\"eye\": %s, \"target\": [0, 0, 0], \"up\": [0, 1, 0],"
            " \"fov_y_deg\": 40},"
            " \"ambient\": [0.15, 0.15, 0.15],"
            " \"lights\": [{\"type\": \"directional\", \"direction\": [0.4, 0.8, 0.5],"
            " \"color\": [1, 1, 1]}],"
            " \"objects\": [{%s, \"material\": {\"albedo\": [0.8, 0.55, 0.3]},"
            " \"technique\": \"reference\"}]}";
        snprintf(json, sizeof json, format, eyes[e],
                 "\"shape\": \"plane\", \"size\": 3.404, \"mesostructure\":"
                 " {\"solid\": {\"impostor\": \"teapot\"}, \"depth\": 1.6667}");
        meso_scene *impostor = parse(ctx, json);
        snprintf(json, sizeof json, format, eyes[e], "\"shape\": \"teapot\"");
        meso_scene *teapot = parse(ctx, json);
        target a = trace(ctx, impostor, NULL), b = trace(ctx, teapot, NULL);
        double psnr = srgb_psnr(&a, &b);
        if (!(psnr >= 35.0)) fail_msg("eye %s: %.2f dB against the teapot itself", eyes[e], psnr);
        target_free(&a);
        target_free(&b);
        meso_scene_destroy(teapot);
        meso_scene_destroy(impostor);
    }
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_reference_constant_one_renders_like_flat),
        cmocka_unit_test(test_reference_zero_height_is_the_mesh_offset_by_depth),
        cmocka_unit_test(test_reference_v_groove_hits_match_the_analytic_intersection),
        cmocka_unit_test(test_reference_solid_slab_renders_like_height_half),
        cmocka_unit_test(test_reference_rays_grazing_a_shared_prism_edge_never_leak),
        cmocka_unit_test(test_reference_too_many_triangles_is_a_limit_error_naming_the_object),
        cmocka_unit_test(test_reference_view_cap_bounds_triangles_by_pixels),
        cmocka_unit_test(test_reference_output_is_identical_for_any_thread_count),
        cmocka_unit_test(test_reference_of_an_impostor_is_the_model_it_stands_for),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
