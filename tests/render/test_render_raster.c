/* The rasterizer: exact coverage (top-left rule), clipping, depth test, supersampling, the ray
 * mapping shared with the reference, wireframe, depth maps, and renderer errors. */
#include <math.h>

#include "raster_internal.h"
#include "render_test_scene.h"
#include "meso/texture.h"

/* ---- A counting technique: every covered sample reaches shade (discarded, so the depth
 * buffer never hides a second fragment). ---------------------------------------------------- */

static int *g_counts;

static void count_shade(const void *state, const meso_frame *frame, const meso_object *object,
                        meso_fragment *fragments, size_t count) {
    (void)state;
    (void)object;
    for (size_t i = 0; i < count; i++) {
        g_counts[(int)fragments[i].y * frame->width + (int)fragments[i].x]++;
        fragments[i].discard = true;
    }
}

static const meso_technique count_technique = {
    .info = {.name = "count",
             .kind = MESO_TECHNIQUE_PER_PIXEL,
             .accepts = MESO_TECHNIQUE_ACCEPTS_NONE},
    .shade = count_shade,
};

/* Rasterize the scene's objects with `technique` straight through raster_draw. */
static void draw_with(meso_context *ctx, const meso_scene *scene, const meso_technique *technique,
                      int width, int height, float *color, float *coverage, float *depth,
                      meso_frame *out_frame) {
    meso_frame frame;
    meso_frame_init(&frame, scene, width, height);
    raster_object objects[TEST_SCENE_MAX_OBJECTS];
    const meso_mesh *meshes[TEST_SCENE_MAX_OBJECTS];
    for (int i = 0; i < scene->num_objects; i++) {
        objects[i] = (raster_object){&scene->objects[i], technique, NULL};
        meshes[i] = scene->objects[i].mesh;
    }
    raster_pass pass;
    memset(&pass, 0, sizeof(pass));
    uint64_t triangles = 0, fragments = 0;
    assert_int_equal(raster_draw(ctx, &pass, &frame, objects, meshes, scene->num_objects, false,
                                 color, coverage, depth, &triangles, &fragments),
                     MESO_OK);
    raster_pass_release(&pass);
    if (out_frame) *out_frame = frame;
}

/* Screen position of a world point (double precision, independent of the rasterizer). */
static void project(const meso_frame *frame, meso_vec3 p, double *sx, double *sy) {
    const float *m = frame->view_projection.m;
    double x = m[0] * p.x + m[4] * p.y + m[8] * p.z + m[12];
    double y = m[1] * p.x + m[5] * p.y + m[9] * p.z + m[13];
    double w = m[3] * p.x + m[7] * p.y + m[11] * p.z + m[15];
    *sx = (x / w * 0.5 + 0.5) * frame->width;
    *sy = (0.5 - 0.5 * y / w) * frame->height;
}

/* Signed distance (samples) of (x, y) inside the convex screen polygon: > 0 inside. */
static double inside_distance(const double *px, const double *py, int n, double x, double y) {
    double area = 0.0;
    for (int i = 0; i < n; i++) area += px[i] * py[(i + 1) % n] - px[(i + 1) % n] * py[i];
    double best = INFINITY;
    for (int i = 0; i < n; i++) {
        double ex = px[(i + 1) % n] - px[i], ey = py[(i + 1) % n] - py[i];
        double d = (ex * (y - py[i]) - ey * (x - px[i])) / sqrt(ex * ex + ey * ey);
        d = area > 0 ? d : -d;
        best = d < best ? d : best;
    }
    return best;
}

/* Counts every sample of the scene once; then: no sample twice, every sample well inside the
 * outline (world points `outline`) once, every sample well outside never. */
static void check_exact_coverage(meso_context *ctx, const meso_scene *scene, int width, int height,
                                 const meso_vec3 *outline, int n) {
    size_t samples = (size_t)width * (size_t)height;
    float *color = malloc(3 * samples * sizeof(float));
    float *coverage = malloc(samples * sizeof(float));
    float *depth = malloc(samples * sizeof(float));
    g_counts = calloc(samples, sizeof(int));
    meso_frame frame;
    draw_with(ctx, scene, &count_technique, width, height, color, coverage, depth, &frame);
    double px[64], py[64];
    for (int i = 0; i < n; i++) project(&frame, outline[i], &px[i], &py[i]);
    int inside = 0;
    for (int y = 0; y < height; y++) {
        for (int x = 0; x < width; x++) {
            int c = g_counts[y * width + x];
            double d = inside_distance(px, py, n, x + 0.5, y + 0.5);
            if (c > 1) fail_msg("sample (%d, %d) covered %d times", x, y, c);
            if (d > 0.01 && c != 1) fail_msg("sample (%d, %d) inside not covered", x, y);
            if (d < -0.01 && c != 0) fail_msg("sample (%d, %d) outside covered", x, y);
            inside += c;
        }
    }
    assert_true(inside > (int)(samples / 10));
    free(g_counts);
    free(color);
    free(coverage);
    free(depth);
}

static void test_raster_plane_of_many_triangles_covers_each_sample_once(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    test_scene ts;
    test_scene_init(&ts, 97, 83);
    test_scene_add(&ts, test_shape(ctx, MESO_SHAPE_PLANE, 1.6f, 17, (meso_vec3){0}), "flat");
    meso_vec3 outline[4] = {{-0.8f, 0, -0.8f}, {0.8f, 0, -0.8f}, {0.8f, 0, 0.8f}, {-0.8f, 0, 0.8f}};
    check_exact_coverage(ctx, &ts.scene, 97, 83, outline, 4);
    /* straight down: grid lines parallel to the sample rows and columns */
    ts.scene.camera = (meso_camera){{0, 2, 0}, {0, 0, 0}, {0, 0, -1}, 40.0f};
    check_exact_coverage(ctx, &ts.scene, 64, 64, outline, 4);
    test_scene_free(&ts);
    meso_context_destroy(ctx);
}

/* Triangles of a sample or less, at a size that is no multiple of the tile or of the eight
 * samples coverage tests at once: every group of a row is partly covered, and the compaction
 * of the survivors keeps each sample once. */
static void test_raster_tiny_triangles_cover_each_sample_once(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    test_scene ts;
    test_scene_init(&ts, 131, 77);
    test_scene_add(&ts, test_shape(ctx, MESO_SHAPE_PLANE, 1.6f, 120, (meso_vec3){0}), "flat");
    meso_vec3 outline[4] = {{-0.8f, 0, -0.8f}, {0.8f, 0, -0.8f}, {0.8f, 0, 0.8f}, {-0.8f, 0, 0.8f}};
    check_exact_coverage(ctx, &ts.scene, 131, 77, outline, 4);
    ts.scene.camera = (meso_camera){{0, 2, 0}, {0, 0, 0}, {0, 0, -1}, 40.0f};
    check_exact_coverage(ctx, &ts.scene, 131, 77, outline, 4);
    test_scene_free(&ts);
    meso_context_destroy(ctx);
}

/* A disc of thin triangles around a centre that projects exactly onto a sample centre. */
static meso_mesh *fan_mesh(meso_context *ctx, int n, float radius) {
    meso_mesh *mesh = NULL;
    assert_int_equal(meso_mesh_create(ctx, (size_t)n + 1, (size_t)n, false, &mesh), MESO_OK);
    mesh->positions[0] = (meso_vec3){0, 0, 0};
    for (int i = 0; i < n; i++) {
        float a = 2.0f * MESO_PI * (float)i / (float)n;
        mesh->positions[i + 1] = (meso_vec3){radius * cosf(a), 0.0f, -radius * sinf(a)};
    }
    for (int i = 0; i <= n; i++) mesh->normals[i] = (meso_vec3){0, 1, 0};
    for (int i = 0; i < n; i++) {
        mesh->indices[3 * i + 0] = 0;
        mesh->indices[3 * i + 1] = (uint32_t)(i + 1);
        mesh->indices[3 * i + 2] = (uint32_t)((i + 1) % n + 1);
    }
    return mesh;
}

static void test_raster_fan_of_thin_triangles_covers_each_sample_once(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    test_scene ts;
    test_scene_init(&ts, 65, 65);
    ts.scene.camera = (meso_camera){{0, 2, 0}, {0, 0, 0}, {0, 0, -1}, 40.0f};
    int n = 48;
    test_scene_add(&ts, fan_mesh(ctx, n, 0.6f), "flat");
    meso_vec3 outline[48];
    for (int i = 0; i < n; i++) outline[i] = ts.objects[0].mesh->positions[i + 1];
    check_exact_coverage(ctx, &ts.scene, 65, 65, outline, n);
    /* oblique view as well */
    ts.scene.camera = (meso_camera){{0.3f, 1.0f, 1.4f}, {0, 0, 0}, {0, 1, 0}, 50.0f};
    check_exact_coverage(ctx, &ts.scene, 80, 61, outline, n);
    test_scene_free(&ts);
    meso_context_destroy(ctx);
}

static void check_camera_close_to_plane(float size) {
    meso_context *ctx = test_context(2);
    test_scene ts;
    test_scene_init(&ts, 64, 48);
    ts.scene.camera = (meso_camera){{0, 0.0005f, 0}, {0, 0.0005f, -1}, {0, 1, 0}, 40.0f};
    test_scene_add(&ts, test_shape(ctx, MESO_SHAPE_PLANE, size, 1, (meso_vec3){0}), "flat");
    meso_framebuffer *fb = NULL;
    assert_int_equal(meso_render_scene(ctx, &ts.scene, NULL, &fb), MESO_OK);
    for (int i = 0; i < 64 * 48 * 3; i++) assert_true(isfinite(fb->color[i]));
    for (int y = 0; y < 48; y++) {
        for (int x = 0; x < 64; x++) {
            float c = fb->coverage[y * 64 + x];
            if (y <= 22) assert_true(c == 0.0f); /* sky: above the horizon at row 24 */
            if (y >= 25) {
                assert_true(c == 1.0f);
                assert_true(isfinite(fb->depth[y * 64 + x]) && fb->depth[y * 64 + x] > 0.0f);
            }
        }
    }
    meso_framebuffer_destroy(fb);
    test_scene_free(&ts);
    meso_context_destroy(ctx);
}

static void test_raster_camera_close_to_large_plane_clips_at_near_plane(void **state) {
    (void)state;
    check_camera_close_to_plane(100.0f);
    /* vertices so far out that the guard band clips them too */
    check_camera_close_to_plane(1e5f);
}

static void render_two_planes(meso_context *ctx, bool high_first, meso_framebuffer **out) {
    test_scene ts;
    test_scene_init(&ts, 48, 40);
    meso_mesh *low = test_shape(ctx, MESO_SHAPE_PLANE, 1.5f, 3, (meso_vec3){0.2f, 0.0f, 0.0f});
    meso_mesh *high = test_shape(ctx, MESO_SHAPE_PLANE, 1.0f, 2, (meso_vec3){0.0f, 0.2f, 0.0f});
    meso_object *a = test_scene_add(&ts, high_first ? high : low, "flat");
    meso_object *b = test_scene_add(&ts, high_first ? low : high, "flat");
    (high_first ? a : b)->material.albedo = (meso_vec3){0.9f, 0.1f, 0.1f};
    (high_first ? b : a)->material.albedo = (meso_vec3){0.1f, 0.1f, 0.9f};
    assert_int_equal(meso_render_scene(ctx, &ts.scene, NULL, out), MESO_OK);
    test_scene_free(&ts);
}

static void test_raster_nearer_surface_wins_in_any_order(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_framebuffer *a = NULL, *b = NULL;
    render_two_planes(ctx, true, &a);
    render_two_planes(ctx, false, &b);
    size_t n = (size_t)a->width * (size_t)a->height;
    assert_memory_equal(a->color, b->color, 3 * n * sizeof(float));
    assert_memory_equal(a->depth, b->depth, n * sizeof(float));
    /* the centre shows the high (red) plane */
    size_t centre = (size_t)(a->height / 2) * (size_t)a->width + (size_t)(a->width / 2);
    assert_true(a->color[3 * centre] > a->color[3 * centre + 2]);
    meso_framebuffer_destroy(a);
    meso_framebuffer_destroy(b);
    meso_context_destroy(ctx);
}

/* Options make the renderer draw a copy of the scene (with them in its objects); the camera and
 * the lights the caller changes between frames must still reach it (meso bench --orbit --set
 * drew a still camera). */
static void test_renderer_with_options_follows_the_moving_camera(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    test_scene ts;
    test_scene_init(&ts, 48, 48);
    test_scene_add(&ts, test_shape(ctx, MESO_SHAPE_SPHERE, 0.6f, 24, (meso_vec3){0.3f, 0, 0}),
                   "flat");
    meso_option options[1] = {{"relief", "linear_steps", 16}};
    meso_renderer *with = NULL, *without = NULL;
    assert_int_equal(meso_renderer_create(ctx, &ts.scene,
                                          &(meso_render_desc){.options = options, .num_options = 1},
                                          &with),
                     MESO_OK);
    assert_int_equal(meso_renderer_create(ctx, &ts.scene, &(meso_render_desc){0}, &without),
                     MESO_OK);
    meso_framebuffer *first = NULL, *a = NULL, *b = NULL;
    assert_int_equal(meso_framebuffer_create(ctx, 48, 48, &first), MESO_OK);
    assert_int_equal(meso_framebuffer_create(ctx, 48, 48, &a), MESO_OK);
    assert_int_equal(meso_framebuffer_create(ctx, 48, 48, &b), MESO_OK);
    assert_int_equal(meso_renderer_render(with, first), MESO_OK);
    ts.scene.camera.eye.x += 1.0f; /* the caller turns the camera */
    assert_int_equal(meso_renderer_render(with, a), MESO_OK);
    assert_int_equal(meso_renderer_render(without, b), MESO_OK);
    assert_memory_equal(a->color, b->color, 48 * 48 * 3 * sizeof(float));
    assert_memory_equal(a->coverage, b->coverage, 48 * 48 * sizeof(float));
    assert_true(memcmp(first->coverage, a->coverage, 48 * 48 * sizeof(float)) != 0);
    meso_framebuffer_destroy(first);
    meso_framebuffer_destroy(a);
    meso_framebuffer_destroy(b);
    meso_renderer_destroy(with);
    meso_renderer_destroy(without);
    test_scene_free(&ts);
    meso_context_destroy(ctx);
}

static void test_raster_supersampling_averages_the_fine_grid(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    test_scene ts;
    test_scene_init(&ts, 40, 30);
    test_scene_add(&ts, test_shape(ctx, MESO_SHAPE_SPHERE, 0.8f, 24, (meso_vec3){0}), "flat");
    meso_framebuffer *fine = NULL, *ss = NULL;
    meso_renderer *r = NULL;
    assert_int_equal(meso_renderer_create(ctx, &ts.scene, &(meso_render_desc){.samples = 4}, &r),
                     MESO_OK);
    assert_int_equal(meso_framebuffer_create(ctx, 40, 30, &ss), MESO_OK);
    assert_int_equal(meso_renderer_render(r, ss), MESO_OK);
    meso_renderer_destroy(r);
    ts.scene.width = 80, ts.scene.height = 60;
    assert_int_equal(meso_render_scene(ctx, &ts.scene, NULL, &fine), MESO_OK);
    int fractional = 0;
    for (int y = 0; y < 30; y++) {
        for (int x = 0; x < 40; x++) {
            float cov = 0.0f, c = 0.0f, d = INFINITY;
            for (int j = 0; j < 2; j++)
                for (int i = 0; i < 2; i++) {
                    size_t s = (size_t)(2 * y + j) * 80 + (size_t)(2 * x + i);
                    cov += fine->coverage[s];
                    c += fine->color[3 * s];
                    d = fminf(d, fine->depth[s]);
                }
            size_t p = (size_t)y * 40 + (size_t)x;
            assert_true(ss->coverage[p] == cov * 0.25f);
            assert_true(fabsf(ss->color[3 * p] - c * 0.25f) < 1e-6f);
            assert_true(ss->depth[p] == d);
            fractional += ss->coverage[p] > 0.0f && ss->coverage[p] < 1.0f;
        }
    }
    assert_true(fractional > 10); /* the silhouette has partial pixels */
    meso_framebuffer_destroy(fine);
    meso_framebuffer_destroy(ss);
    test_scene_free(&ts);
    meso_context_destroy(ctx);
}

/* ---- The ray mapping: fragments agree with meso_frame_ray_direction ----------------------- */

static const meso_mesh *g_mesh;
static double g_worst;
static int g_checked;

static void ray_shade(const void *state, const meso_frame *frame, const meso_object *object,
                      meso_fragment *fragments, size_t count) {
    (void)state;
    (void)object;
    for (size_t i = 0; i < count; i++) {
        const meso_fragment *f = &fragments[i];
        const uint32_t *idx = g_mesh->indices + 3 * f->triangle;
        /* the surface point from the barycentrics alone, projected back to the screen */
        meso_vec3 p = meso_vec3_barycentric(g_mesh->positions[idx[0]], g_mesh->positions[idx[1]],
                                            g_mesh->positions[idx[2]], f->b0, f->b1, f->b2);
        double sx, sy;
        project(frame, p, &sx, &sy);
        double err = fmax(fabs(sx - f->x), fabs(sy - f->y));
        g_worst = err > g_worst ? err : g_worst;
        /* the position lies on the sample's ray at view depth `depth` */
        meso_vec3 dir = meso_frame_ray_direction(frame, f->x, f->y);
        assert_true(fabsf(meso_vec3_dot(dir, frame->forward) - 1.0f) < 1e-5f);
        meso_vec3 q = meso_vec3_madd(frame->eye, dir, f->depth);
        assert_true(meso_vec3_length(meso_vec3_sub(q, p)) < 1e-4f);
        assert_true(fabsf(meso_vec3_dot(meso_vec3_sub(f->position, frame->eye), frame->forward) -
                          f->depth) < 1e-4f);
        g_checked++;
    }
}

static void test_raster_fragments_lie_on_the_frame_rays(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    test_scene ts;
    test_scene_init(&ts, 70, 50);
    ts.scene.camera = (meso_camera){{0.4f, 1.0f, 1.5f}, {0, 0.1f, 0}, {0, 1, 0}, 45.0f};
    meso_mesh *sphere = test_shape(ctx, MESO_SHAPE_SPHERE, 0.7f, 20, (meso_vec3){0});
    test_scene_add(&ts, sphere, "flat");
    const meso_technique ray_technique = {
        .info = {.name = "ray", .accepts = MESO_TECHNIQUE_ACCEPTS_NONE}, .shade = ray_shade};
    size_t n = 70 * 50;
    float *color = malloc(3 * n * sizeof(float)), *cov = malloc(n * sizeof(float));
    float *depth = malloc(n * sizeof(float));
    g_mesh = sphere;
    g_worst = 0.0;
    g_checked = 0;
    draw_with(ctx, &ts.scene, &ray_technique, 70, 50, color, cov, depth, NULL);
    assert_true(g_checked > 500);
    /* vertices snap to 1/256 sample: positions agree to that */
    if (!(g_worst < 1.0 / 256.0)) fail_msg("fragment and ray disagree by %g samples", g_worst);
    free(color);
    free(cov);
    free(depth);
    test_scene_free(&ts);
    meso_context_destroy(ctx);
}

static void test_raster_wireframe_draws_edges(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    test_scene ts;
    test_scene_init(&ts, 64, 64);
    test_scene_add(&ts, test_shape(ctx, MESO_SHAPE_SPHERE, 0.8f, 12, (meso_vec3){0}), "flat");
    meso_framebuffer *plain = NULL, *wire = NULL;
    assert_int_equal(meso_render_scene(ctx, &ts.scene, NULL, &plain), MESO_OK);
    assert_int_equal(
        meso_render_scene(ctx, &ts.scene, &(meso_render_desc){.wireframe = true}, &wire), MESO_OK);
    int changed = 0;
    for (int i = 0; i < 64 * 64; i++) {
        changed += plain->color[3 * i] != wire->color[3 * i];
        assert_true(plain->coverage[i] == wire->coverage[i]);
    }
    assert_true(changed > 100);
    meso_framebuffer_destroy(plain);
    meso_framebuffer_destroy(wire);
    test_scene_free(&ts);
    meso_context_destroy(ctx);
}

/* Buffers kept between draws (a shadow map redrawn each frame) give the maps of fresh ones, after
 * a larger mesh and after a smaller one, and are counted in the memory. */
static void test_raster_depth_map_kept_scratch_draws_the_same(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_mesh *fine = test_shape(ctx, MESO_SHAPE_SPHERE, 0.7f, 48, (meso_vec3){0});
    meso_mesh *coarse = test_shape(ctx, MESO_SHAPE_SPHERE, 0.5f, 12, (meso_vec3){0.1f, 0, 0});
    test_scene ts;
    test_scene_init(&ts, 70, 70);
    meso_frame frame;
    meso_frame_init(&frame, &ts.scene, 70, 70);
    size_t bytes = 70 * 70 * sizeof(float);
    float *fresh = malloc(bytes), *kept = malloc(bytes);
    meso_raster_depth_scratch *scratch = NULL;
    assert_int_equal(meso_raster_depth_scratch_memory(scratch), 0);
    const meso_mesh *order[3] = {fine, coarse, fine};
    for (int i = 0; i < 3; i++) {
        assert_int_equal(
            meso_raster_depth_map(ctx, NULL, order[i], frame.view_projection, 70, 70, fresh),
            MESO_OK);
        memset(kept, 0, bytes);
        assert_int_equal(
            meso_raster_depth_map(ctx, &scratch, order[i], frame.view_projection, 70, 70, kept),
            MESO_OK);
        assert_non_null(scratch);
        assert_memory_equal(fresh, kept, bytes);
        assert_true(meso_raster_depth_scratch_memory(scratch) >
                    order[i]->num_triangles / 4 * sizeof(float));
    }
    meso_raster_depth_scratch_destroy(scratch);
    meso_raster_depth_scratch_destroy(NULL);
    free(fresh);
    free(kept);
    meso_mesh_destroy(fine);
    meso_mesh_destroy(coarse);
    test_scene_free(&ts);
    meso_context_destroy(ctx);
}

static void test_raster_depth_map_is_thread_independent_and_bounded(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_mesh *sphere = test_shape(ctx, MESO_SHAPE_SPHERE, 0.7f, 24, (meso_vec3){0});
    test_scene ts;
    test_scene_init(&ts, 50, 50);
    meso_frame frame;
    meso_frame_init(&frame, &ts.scene, 50, 50);
    float *a = malloc(50 * 50 * sizeof(float)), *b = malloc(50 * 50 * sizeof(float));
    assert_int_equal(meso_raster_depth_map(ctx, NULL, sphere, frame.view_projection, 50, 50, a),
                     MESO_OK);
    meso_context_set_num_threads(ctx, 3);
    assert_int_equal(meso_raster_depth_map(ctx, NULL, sphere, frame.view_projection, 50, 50, b),
                     MESO_OK);
    assert_memory_equal(a, b, 50 * 50 * sizeof(float));
    int covered = 0;
    for (int i = 0; i < 50 * 50; i++) {
        if (isinf(a[i])) continue;
        assert_true(a[i] > 0.0f && a[i] < 1.0f);
        covered++;
    }
    assert_true(covered > 200 && covered < 50 * 50);
    assert_true(isinf(a[0]) && !isinf(a[25 * 50 + 25]));
    free(a);
    free(b);
    meso_mesh_destroy(sphere);
    meso_context_destroy(ctx);
}

/* Which source triangles the setup kept (flags indexed by triangle). */
static void kept_triangles(const raster_bins *bins, uint8_t *kept, size_t count) {
    memset(kept, 0, count);
    for (size_t c = 0; c < bins->num_chunks; c++)
        for (size_t i = 0; i < bins->chunks[c].num_triangles; i++)
            kept[bins->chunks[c].triangles[i].triangle] = 1;
}

/* Back faces are dropped before their vertices are transformed (raster_setup.c, faces_away):
 * the eye recovered from the view-projection is the camera's, and the triangles kept are those
 * kept without culling whose screen orientation (in double, independent of the rasterizer) is
 * clearly front-facing; clearly back-facing ones are gone. */
static void test_raster_back_faces_dropped_early_are_exactly_the_back_faces(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_mesh *sphere = test_shape(ctx, MESO_SHAPE_SPHERE, 0.7f, 48, (meso_vec3){0.1f, 0, 0});
    test_scene ts;
    test_scene_init(&ts, 200, 200);
    meso_frame frame;
    meso_frame_init(&frame, &ts.scene, 200, 200);
    raster_setup_desc desc = {.view_projection = frame.view_projection,
                              .width = 200,
                              .height = 200,
                              .z_near = frame.z_near,
                              .cull_back = true};
    const meso_mesh *meshes[1] = {sphere};
    raster_bins culled, both;
    memset(&culled, 0, sizeof(culled));
    memset(&both, 0, sizeof(both));
    bool keep_back[1] = {true};
    assert_int_equal(raster_bins_build(ctx, &culled, meshes, NULL, 1, &desc), MESO_OK);
    assert_int_equal(raster_bins_build(ctx, &both, meshes, keep_back, 1, &desc), MESO_OK);
    assert_true(culled.has_eye);
    assert_true(fabsf(culled.eye.x - frame.eye.x) < 1e-4f &&
                fabsf(culled.eye.y - frame.eye.y) < 1e-4f &&
                fabsf(culled.eye.z - frame.eye.z) < 1e-4f);
    size_t n = sphere->num_triangles;
    uint8_t *kept = malloc(n), *kept_both = malloc(n);
    kept_triangles(&culled, kept, n);
    kept_triangles(&both, kept_both, n);
    size_t front = 0, back = 0;
    for (size_t t = 0; t < n; t++) {
        if (!kept_both[t]) {
            assert_false(kept[t]);
            continue;
        }
        double x[3], y[3];
        for (int k = 0; k < 3; k++)
            project(&frame, sphere->positions[sphere->indices[3 * t + (size_t)k]], &x[k], &y[k]);
        double area = (x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0]);
        /* counter-clockwise from outside is clockwise on screen (y down): area < 0 */
        if (area < -1e-3) {
            assert_true(kept[t]);
            front++;
        } else if (area > 1e-3) {
            assert_false(kept[t]);
            back++;
        }
    }
    assert_true(front > 500 && back > 500);
    /* an orthographic projection has no eye: nothing is dropped early */
    desc.view_projection = meso_mat4_identity();
    assert_int_equal(raster_bins_build(ctx, &culled, meshes, NULL, 1, &desc), MESO_OK);
    assert_false(culled.has_eye);
    free(kept);
    free(kept_both);
    raster_bins_release(&culled);
    raster_bins_release(&both);
    test_scene_free(&ts);
    meso_mesh_destroy(sphere);
    meso_context_destroy(ctx);
}

/* ---- The 8-wide setup (raster_setup.c, setup_source_triangles8) ---------------------------- */

static uint32_t g_lcg = 12345u;
static float random_unit(void) { /* [0, 1) */
    g_lcg = g_lcg * 1664525u + 1013904223u;
    return (float)(g_lcg >> 8) / 16777216.0f;
}

/* Asserts that two binnings hold the same triangles, bit for bit, and the same tile lists. */
static void assert_same_bins(const raster_bins *a, const raster_bins *b) {
    assert_int_equal(a->num_chunks, b->num_chunks);
    size_t num_tiles = (size_t)a->tiles_x * (size_t)a->tiles_y;
    for (size_t c = 0; c < a->num_chunks; c++) {
        const raster_chunk *ca = &a->chunks[c], *cb = &b->chunks[c];
        assert_int_equal(ca->num_triangles, cb->num_triangles);
        if (ca->num_triangles)
            assert_memory_equal(ca->triangles, cb->triangles,
                                ca->num_triangles * sizeof(raster_triangle));
        assert_memory_equal(ca->tile_start, cb->tile_start, (num_tiles + 1) * sizeof(uint32_t));
        assert_int_equal(ca->num_entries, cb->num_entries);
        if (ca->num_entries)
            assert_memory_equal(ca->entries, cb->entries, ca->num_entries * sizeof(uint32_t));
    }
}

/* Sets the mesh up 8 triangles at a time and one at a time with `desc`; the same bins. Returns
 * the triangles kept. */
static size_t check_setup_8_wide(meso_context *ctx, const meso_mesh *mesh, bool both_faces,
                                 raster_setup_desc desc) {
    const meso_mesh *meshes[1] = {mesh};
    bool keep_back[1] = {both_faces};
    raster_bins wide, single;
    memset(&wide, 0, sizeof(wide));
    memset(&single, 0, sizeof(single));
    desc.one_at_a_time = false;
    assert_int_equal(raster_bins_build(ctx, &wide, meshes, keep_back, 1, &desc), MESO_OK);
    desc.one_at_a_time = true;
    assert_int_equal(raster_bins_build(ctx, &single, meshes, keep_back, 1, &desc), MESO_OK);
    assert_same_bins(&wide, &single);
    size_t kept = 0;
    for (size_t c = 0; c < wide.num_chunks; c++) kept += wide.chunks[c].num_triangles;
    raster_bins_release(&wide);
    raster_bins_release(&single);
    return kept;
}

/* The 8-wide setup keeps the triangles, bit for bit and in the order, that the one-triangle
 * path keeps: sub-sample triangles (most end at the sample-box test), triangles crossing the
 * near plane and the guard band (clipped one by one), slivers, degenerate and non-finite
 * triangles, back faces near and far from edge-on, a mesh whose size is not a multiple of 8;
 * for the colour pass (culling back faces, or both faces) and for depth maps (z_ndc clipping,
 * the depth plane, perspective and orthographic). */
static void test_raster_setup_8_wide_matches_one_at_a_time(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    enum { NUM_TRIANGLES = 6007 };
    meso_vec3 *positions = malloc(3 * NUM_TRIANGLES * sizeof(meso_vec3));
    uint32_t *indices = malloc(3 * NUM_TRIANGLES * sizeof(uint32_t));
    for (uint32_t t = 0; t < NUM_TRIANGLES; t++) {
        int kind = (int)(random_unit() * 10.0f);
        meso_vec3 centre = {random_unit() * 3.0f - 1.5f, random_unit() * 2.0f - 1.0f,
                            random_unit() * 3.0f - 1.5f};
        float size = kind < 5 ? 0.004f : kind < 7 ? 0.05f : kind < 8 ? 3.0f : 2000.0f;
        if (kind == 8) centre.z = 2.0f; /* about the camera: crosses the near plane */
        for (int k = 0; k < 3; k++) {
            positions[3 * t + (uint32_t)k] = (meso_vec3){centre.x + size * (random_unit() - 0.5f),
                                                         centre.y + size * (random_unit() - 0.5f),
                                                         centre.z + size * (random_unit() - 0.5f)};
            indices[3 * t + (uint32_t)k] = 3 * t + (uint32_t)k;
        }
        if (kind == 9 && t % 3 == 0) positions[3 * t + 1] = positions[3 * t]; /* degenerate */
        if (kind == 9 && t % 3 == 1) positions[3 * t + 2].x = t % 2 ? INFINITY : NAN;
        if (kind == 9 && t % 3 == 2) { /* a sliver: the third vertex nearly on the first edge */
            meso_vec3 a = positions[3 * t], b = positions[3 * t + 1];
            positions[3 * t + 2] =
                (meso_vec3){0.5f * (a.x + b.x) + 1e-6f, 0.5f * (a.y + b.y), 0.5f * (a.z + b.z)};
        }
    }
    meso_mesh soup = {.num_vertices = 3 * NUM_TRIANGLES,
                      .num_triangles = NUM_TRIANGLES,
                      .positions = positions,
                      .indices = indices};
    meso_mesh *sphere = test_shape(ctx, MESO_SHAPE_SPHERE, 0.7f, 96, (meso_vec3){0.1f, 0, 0});
    test_scene ts;
    test_scene_init(&ts, 256, 192);
    meso_frame frame;
    meso_frame_init(&frame, &ts.scene, 256, 192);
    raster_setup_desc colour = {.view_projection = frame.view_projection,
                                .width = 256,
                                .height = 192,
                                .z_near = frame.z_near,
                                .cull_back = true};
    raster_setup_desc depth = {.view_projection = frame.view_projection,
                               .width = 300,
                               .height = 200,
                               .clip_z = true,
                               .depth_plane = true};
    raster_setup_desc ortho = depth;
    ortho.view_projection = meso_mat4_scale(0.7f); /* w = 1: orthographic */
    const meso_mesh *tested[2] = {&soup, sphere};
    for (int m = 0; m < 2; m++) {
        assert_true(check_setup_8_wide(ctx, tested[m], false, colour) > 100);
        assert_true(check_setup_8_wide(ctx, tested[m], true, colour) > 100);
        assert_true(check_setup_8_wide(ctx, tested[m], false, depth) > 100);
        assert_true(check_setup_8_wide(ctx, tested[m], false, ortho) > 100);
        /* with the triangles that cover no sample of a small box dropped */
        raster_setup_desc dropping[3] = {colour, depth, ortho};
        for (int d = 0; d < 3; d++) {
            dropping[d].drop_uncovered = true;
            assert_true(check_setup_8_wide(ctx, tested[m], false, dropping[d]) > 100);
        }
    }
    /* a camera inside the soup: most triangles are clipped or behind */
    ts.scene.camera.eye = (meso_vec3){0.1f, 0.05f, 0.2f};
    meso_frame_init(&frame, &ts.scene, 256, 192);
    colour.view_projection = frame.view_projection;
    assert_true(check_setup_8_wide(ctx, &soup, false, colour) > 100);
    free(positions);
    free(indices);
    test_scene_free(&ts);
    meso_mesh_destroy(sphere);
    meso_context_destroy(ctx);
}

/* Whether the set-up triangle covers some sample centre of its box (the edge functions of
 * cover_triangle, sample by sample). */
static bool covers_some_sample(const raster_triangle *tri) {
    for (int y = tri->min_y; y <= tri->max_y; y++)
        for (int x = tri->min_x; x <= tri->max_x; x++) {
            int64_t px = ((int64_t)x << RASTER_SUBPIXEL_BITS) + RASTER_SUBPIXEL_ONE / 2;
            int64_t py = ((int64_t)y << RASTER_SUBPIXEL_BITS) + RASTER_SUBPIXEL_ONE / 2;
            bool inside = true;
            for (int k = 0; k < 3; k++) {
                int a = (k + 1) % 3;
                inside &= (int64_t)tri->edge_a[k] * (px - tri->x[a]) +
                              (int64_t)tri->edge_b[k] * (py - tri->y[a]) + tri->bias[k] >=
                          0;
            }
            if (inside) return true;
        }
    return false;
}

/* drop_uncovered leaves out exactly the triangles whose sample box is at most 2 x 2 samples and
 * that cover none of them; the others stay, bit for bit and in their order (so the colour
 * pass and the depth maps draw the same samples). */
static void test_raster_dropped_triangles_cover_no_sample(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_mesh *sphere = test_shape(ctx, MESO_SHAPE_SPHERE, 0.7f, 192, (meso_vec3){0.1f, 0, 0});
    test_scene ts;
    test_scene_init(&ts, 256, 192);
    meso_frame frame;
    meso_frame_init(&frame, &ts.scene, 256, 192);
    raster_setup_desc descs[2] = {{.view_projection = frame.view_projection,
                                   .width = 256,
                                   .height = 192,
                                   .z_near = frame.z_near,
                                   .cull_back = true},
                                  {.view_projection = frame.view_projection,
                                   .width = 300,
                                   .height = 200,
                                   .clip_z = true,
                                   .depth_plane = true}};
    const meso_mesh *meshes[1] = {sphere};
    for (int d = 0; d < 2; d++) {
        raster_bins all, kept;
        memset(&all, 0, sizeof(all));
        memset(&kept, 0, sizeof(kept));
        assert_int_equal(raster_bins_build(ctx, &all, meshes, NULL, 1, &descs[d]), MESO_OK);
        descs[d].drop_uncovered = true;
        assert_int_equal(raster_bins_build(ctx, &kept, meshes, NULL, 1, &descs[d]), MESO_OK);
        assert_int_equal(all.num_chunks, kept.num_chunks);
        size_t dropped = 0;
        for (size_t c = 0; c < all.num_chunks; c++) {
            const raster_chunk *ca = &all.chunks[c], *ck = &kept.chunks[c];
            size_t j = 0;
            for (size_t i = 0; i < ca->num_triangles; i++) {
                const raster_triangle *t = &ca->triangles[i];
                bool small = t->max_x - t->min_x <= 1 && t->max_y - t->min_y <= 1;
                if (small && !covers_some_sample(t)) {
                    dropped++;
                    continue;
                }
                assert_true(j < ck->num_triangles);
                assert_memory_equal(t, &ck->triangles[j], sizeof(*t));
                j++;
            }
            assert_int_equal(j, ck->num_triangles);
        }
        assert_true(dropped > 100);
        raster_bins_release(&all);
        raster_bins_release(&kept);
    }
    test_scene_free(&ts);
    meso_mesh_destroy(sphere);
    meso_context_destroy(ctx);
}

/* ---- Renderer errors ------------------------------------------------------------------------ */

/* ---- Blocks and fragments: a technique written per block sees exactly what one written per
 * fragment sees (render_internal.h, shade_block). ------------------------------------------ */

static meso_fragment *g_seen; /* per sample: the fragment a technique was handed */
static int g_seen_width;

/* Every field equal to the bit (the struct's padding after `discard` is not compared). */
static void assert_same_fragment(const meso_fragment *a, const meso_fragment *b) {
    assert_memory_equal(a, b, offsetof(meso_fragment, discard));
    assert_int_equal(a->discard, b->discard);
}

static void record_shade(const void *state, const meso_frame *frame, const meso_object *object,
                         meso_fragment *fragments, size_t count) {
    (void)state;
    (void)frame;
    (void)object;
    for (size_t i = 0; i < count; i++) {
        meso_fragment *f = &fragments[i];
        g_seen[(int)f->y * g_seen_width + (int)f->x] = *f;
        /* a colour from the inputs, so the image checks the write-back too */
        f->color = (meso_vec3){f->uv.x, f->normal.y, f->b1};
        f->discard = f->triangle % 3 == 2;
    }
}

static void record_shade_block(const void *state, const meso_frame *frame,
                               const meso_object *object, meso_fragment_block *block) {
    (void)state;
    (void)frame;
    (void)object;
    size_t n = block->count;
    assert_true(n >= 1 && n <= MESO_FRAGMENT_BLOCK_CAPACITY);
    meso_fragment last, pad;
    meso_fragment_block_get(block, n - 1, &last);
    for (size_t i = n; i % 8; i++) { /* the padding repeats the last fragment */
        meso_fragment_block_get(block, i, &pad);
        assert_same_fragment(&pad, &last);
    }
    for (size_t i = 0; i < n; i++) {
        meso_fragment f;
        meso_fragment_block_get(block, i, &f);
        g_seen[(int)f.y * g_seen_width + (int)f.x] = f;
        block->r[i] = f.uv.x, block->g[i] = f.normal.y, block->b[i] = f.b1;
        block->discard[i] = f.triangle % 3 == 2;
    }
}

static void test_raster_block_and_fragment_techniques_see_the_same_fragments(void **state) {
    (void)state;
    const meso_technique per_fragment = {
        .info = {.name = "record", .accepts = MESO_TECHNIQUE_ACCEPTS_NONE}, .shade = record_shade};
    const meso_technique per_block = {
        .info = {.name = "record", .accepts = MESO_TECHNIQUE_ACCEPTS_NONE},
        .shade_block = record_shade_block};
    meso_context *ctx = test_context(2);
    test_scene ts;
    test_scene_init(&ts, 97, 83);
    /* a sphere over a plane: triangles of every size, overlaps, batches split on repeats */
    test_scene_add(&ts, test_shape(ctx, MESO_SHAPE_PLANE, 1.6f, 7, (meso_vec3){0}), "flat");
    test_scene_add(&ts, test_shape(ctx, MESO_SHAPE_SPHERE, 0.8f, 24, (meso_vec3){0, 0.3f, 0}),
                   "flat");
    const int w = 97, h = 83;
    size_t samples = (size_t)w * (size_t)h;
    float *color[2], *coverage[2], *depth[2];
    meso_fragment *seen[2];
    const meso_technique *techniques[2] = {&per_fragment, &per_block};
    g_seen_width = w;
    for (int k = 0; k < 2; k++) {
        color[k] = malloc(3 * samples * sizeof(float));
        coverage[k] = malloc(samples * sizeof(float));
        depth[k] = malloc(samples * sizeof(float));
        seen[k] = g_seen = calloc(samples, sizeof(meso_fragment));
        draw_with(ctx, &ts.scene, techniques[k], w, h, color[k], coverage[k], depth[k], NULL);
    }
    int covered = 0;
    for (size_t i = 0; i < samples; i++) covered += coverage[0][i] > 0.0f;
    assert_true(covered > (int)(samples / 10));
    for (size_t i = 0; i < samples; i++) assert_same_fragment(&seen[0][i], &seen[1][i]);
    assert_memory_equal(color[0], color[1], 3 * samples * sizeof(float));
    assert_memory_equal(coverage[0], coverage[1], samples * sizeof(float));
    assert_memory_equal(depth[0], depth[1], samples * sizeof(float));
    for (int k = 0; k < 2; k++) free(color[k]), free(coverage[k]), free(depth[k]), free(seen[k]);
    test_scene_free(&ts);
    meso_context_destroy(ctx);
}

/* A technique that declares fields it never reads (meso_technique.skip_fields) is handed the
 * same fragments in the same order, with the same values in every field it reads, and the
 * tangents still filled for an object with a normal map (the shading model reads them there). */
static meso_fragment *g_order; /* fragments in the order the technique saw them */
static size_t g_order_count;

static void record_in_order_block(const void *state, const meso_frame *frame,
                                  const meso_object *object, meso_fragment_block *block) {
    (void)state;
    (void)frame;
    (void)object;
    for (size_t i = 0; i < block->count; i++) {
        meso_fragment_block_get(block, i, &g_order[g_order_count++]);
        block->r[i] = block->nx[i], block->g[i] = block->u[i], block->b[i] = block->depth[i];
    }
}

static void test_raster_skipped_fields_leave_the_read_ones_as_they_were(void **state) {
    (void)state;
    const unsigned all_skips = MESO_FRAGMENT_SKIP_SAMPLE | MESO_FRAGMENT_SKIP_TRIANGLE |
                               MESO_FRAGMENT_SKIP_BARYCENTRICS | MESO_FRAGMENT_SKIP_TANGENTS |
                               MESO_FRAGMENT_SKIP_COLOR_PRESET;
    const unsigned skips[3] = {0, all_skips, all_skips & ~MESO_FRAGMENT_SKIP_TANGENTS};
    meso_context *ctx = test_context(1); /* one thread: the order of the blocks is fixed */
    test_scene ts;
    test_scene_init(&ts, 61, 47);
    test_scene_add(&ts, test_shape(ctx, MESO_SHAPE_PLANE, 1.6f, 7, (meso_vec3){0}), "flat");
    meso_object *sphere = test_scene_add(
        &ts, test_shape(ctx, MESO_SHAPE_SPHERE, 0.8f, 24, (meso_vec3){0, 0.3f, 0}), "flat");
    meso_image *image = NULL;
    meso_texture *normal_map = NULL;
    assert_int_equal(meso_image_create(ctx, 2, 2, 3, &image), MESO_OK);
    assert_int_equal(meso_texture_create(ctx, image, MESO_WRAP_REPEAT, false, &normal_map),
                     MESO_OK);
    const int w = 61, h = 47;
    size_t samples = (size_t)w * (size_t)h;
    for (int with_map = 0; with_map < 2; with_map++) {
        sphere->material.normal_map = with_map ? normal_map : NULL;
        meso_fragment *seen[3];
        size_t count[3];
        float *color[3], *coverage = malloc(samples * sizeof(float));
        float *depth = malloc(samples * sizeof(float));
        for (int k = 0; k < 3; k++) {
            const meso_technique t = {
                .info = {.name = "record", .accepts = MESO_TECHNIQUE_ACCEPTS_NONE},
                .shade_block = record_in_order_block,
                .skip_fields = skips[k]};
            seen[k] = g_order = calloc(2 * samples, sizeof(meso_fragment));
            g_order_count = 0;
            color[k] = malloc(3 * samples * sizeof(float));
            draw_with(ctx, &ts.scene, &t, w, h, color[k], coverage, depth, NULL);
            count[k] = g_order_count;
        }
        assert_true(count[0] > samples / 4);
        for (int k = 1; k < 3; k++) {
            assert_int_equal(count[k], count[0]);
            assert_memory_equal(color[k], color[0], 3 * samples * sizeof(float));
            for (size_t i = 0; i < count[0]; i++) {
                const meso_fragment *a = &seen[0][i], *b = &seen[k][i];
                assert_memory_equal(&a->position, &b->position, sizeof a->position);
                assert_memory_equal(&a->normal, &b->normal, sizeof a->normal);
                assert_memory_equal(&a->uv, &b->uv, sizeof a->uv);
                assert_memory_equal(&a->depth, &b->depth, sizeof a->depth);
                assert_memory_equal(&a->out_depth, &b->out_depth, sizeof a->out_depth);
                assert_int_equal(a->discard, b->discard);
                /* the tangents where declared read, and on the normal-mapped sphere */
                bool on_sphere = a->position.y > 0.01f;
                if (!(skips[k] & MESO_FRAGMENT_SKIP_TANGENTS) || (with_map && on_sphere)) {
                    assert_memory_equal(&a->tangent, &b->tangent, sizeof a->tangent);
                    assert_memory_equal(&a->bitangent, &b->bitangent, sizeof a->bitangent);
                }
            }
        }
        for (int k = 0; k < 3; k++) free(seen[k]), free(color[k]);
        free(coverage);
        free(depth);
    }
    sphere->material.normal_map = NULL;
    meso_texture_destroy(normal_map);
    meso_image_destroy(image);
    test_scene_free(&ts);
    meso_context_destroy(ctx);
}

/* flat through its block and through meso_technique_shade's adapter: the same colours as
 * meso_shade_point_tb fragment by fragment, counts that are not multiples of 8 included. */
static void test_flat_block_matches_shade_point(void **state) {
    (void)state;
    test_scene ts;
    test_scene_init(&ts, 16, 16);
    meso_object *o = test_scene_add(&ts, NULL, "flat");
    o->material.specular = (meso_vec3){0.3f, 0.3f, 0.3f};
    meso_frame frame;
    meso_frame_init(&frame, &ts.scene, 16, 16);
    const meso_technique *flat = meso_technique_lookup("flat");
    assert_non_null(flat);
    assert_non_null(flat->shade_block);
    meso_fragment frags[13];
    for (size_t n = 1; n <= 13; n += 4) {
        for (size_t i = 0; i < n; i++) {
            float a = 0.3f * (float)i;
            frags[i] =
                (meso_fragment){.position = {0.1f * (float)i, 0.0f, -0.2f},
                                .normal = meso_vec3_normalize((meso_vec3){sinf(a), 1.0f, cosf(a)}),
                                .uv = {0.05f * (float)i, 0.5f}};
        }
        assert_int_equal(meso_technique_shade(flat, NULL, &frame, o, frags, n), MESO_OK);
        for (size_t i = 0; i < n; i++) {
            meso_vec3 want =
                meso_shade_point(&frame, o, frags[i].position, frags[i].normal, frags[i].uv, NULL);
            assert_memory_equal(&frags[i].color, &want, sizeof want);
            assert_false(frags[i].discard);
        }
    }
    test_scene_free(&ts);
}

static void test_renderer_unknown_technique_names_object_and_known_ones(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    test_scene ts;
    test_scene_init(&ts, 16, 16);
    test_scene_add(&ts, test_shape(ctx, MESO_SHAPE_PLANE, 1.0f, 1, (meso_vec3){0}), "flat");
    test_scene_add(&ts, test_shape(ctx, MESO_SHAPE_PLANE, 1.0f, 1, (meso_vec3){0}), "foo");
    meso_renderer *r = (meso_renderer *)&ts; /* must be reset to NULL */
    assert_int_equal(meso_renderer_create(ctx, &ts.scene, NULL, &r), MESO_ERROR_INVALID_ARGUMENT);
    assert_null(r);
    const char *msg = meso_context_last_error(ctx);
    assert_non_null(strstr(msg, "objects[1]"));
    assert_non_null(strstr(msg, "'foo'"));
    assert_non_null(strstr(msg, "flat, bump"));
    /* an override is checked too */
    snprintf(ts.objects[1].technique, MESO_NAME_MAX, "flat");
    assert_int_equal(
        meso_renderer_create(ctx, &ts.scene, &(meso_render_desc){.technique = "nope"}, &r),
        MESO_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(meso_context_last_error(ctx), "'nope'"));
    test_scene_free(&ts);
    meso_context_destroy(ctx);
}

static void test_renderer_rejects_technique_for_wrong_mesostructure(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    test_scene ts;
    test_scene_init(&ts, 16, 16);
    test_scene_add(&ts, test_shape(ctx, MESO_SHAPE_PLANE, 1.0f, 1, (meso_vec3){0}), "bump");
    meso_renderer *r = NULL;
    assert_int_equal(meso_renderer_create(ctx, &ts.scene, NULL, &r), MESO_ERROR_INVALID_ARGUMENT);
    const char *msg = meso_context_last_error(ctx);
    assert_non_null(strstr(msg, "objects[0]"));
    assert_non_null(strstr(msg, "'bump'"));
    test_scene_free(&ts);
    meso_context_destroy(ctx);
}

static void test_renderer_rejects_reference_mixed_with_others(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    test_scene ts;
    test_scene_init(&ts, 16, 16);
    test_scene_add(&ts, test_shape(ctx, MESO_SHAPE_PLANE, 1.0f, 1, (meso_vec3){0}), "flat");
    test_scene_add(&ts, test_shape(ctx, MESO_SHAPE_PLANE, 1.0f, 1, (meso_vec3){0}), "reference");
    meso_renderer *r = NULL;
    assert_int_equal(meso_renderer_create(ctx, &ts.scene, NULL, &r), MESO_ERROR_INVALID_ARGUMENT);
    const char *msg = meso_context_last_error(ctx);
    assert_non_null(strstr(msg, "objects[1]"));
    assert_non_null(strstr(msg, "reference"));
    assert_non_null(strstr(msg, "objects[0]"));
    assert_int_equal(meso_renderer_create(ctx, &ts.scene, &(meso_render_desc){.samples = -1}, &r),
                     MESO_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(meso_context_last_error(ctx), "samples"));
    test_scene_free(&ts);
    meso_context_destroy(ctx);
}

static void test_renderer_empty_scene_is_background(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    test_scene ts;
    test_scene_init(&ts, 20, 10);
    meso_framebuffer *fb = NULL;
    assert_int_equal(meso_render_scene(ctx, &ts.scene, &(meso_render_desc){.samples = 2}, &fb),
                     MESO_OK);
    for (int i = 0; i < 200; i++) {
        assert_true(fb->color[3 * i + 1] == 0.2f);
        assert_true(fb->coverage[i] == 0.0f);
        assert_true(isinf(fb->depth[i]));
    }
    meso_framebuffer_destroy(fb);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_raster_plane_of_many_triangles_covers_each_sample_once),
        cmocka_unit_test(test_raster_fan_of_thin_triangles_covers_each_sample_once),
        cmocka_unit_test(test_raster_tiny_triangles_cover_each_sample_once),
        cmocka_unit_test(test_raster_camera_close_to_large_plane_clips_at_near_plane),
        cmocka_unit_test(test_raster_nearer_surface_wins_in_any_order),
        cmocka_unit_test(test_raster_supersampling_averages_the_fine_grid),
        cmocka_unit_test(test_raster_fragments_lie_on_the_frame_rays),
        cmocka_unit_test(test_raster_wireframe_draws_edges),
        cmocka_unit_test(test_raster_depth_map_is_thread_independent_and_bounded),
        cmocka_unit_test(test_raster_depth_map_kept_scratch_draws_the_same),
        cmocka_unit_test(test_renderer_with_options_follows_the_moving_camera),
        cmocka_unit_test(test_raster_block_and_fragment_techniques_see_the_same_fragments),
        cmocka_unit_test(test_raster_skipped_fields_leave_the_read_ones_as_they_were),
        cmocka_unit_test(test_flat_block_matches_shade_point),
        cmocka_unit_test(test_raster_back_faces_dropped_early_are_exactly_the_back_faces),
        cmocka_unit_test(test_raster_setup_8_wide_matches_one_at_a_time),
        cmocka_unit_test(test_raster_dropped_triangles_cover_no_sample),
        cmocka_unit_test(test_renderer_unknown_technique_names_object_and_known_ones),
        cmocka_unit_test(test_renderer_rejects_technique_for_wrong_mesostructure),
        cmocka_unit_test(test_renderer_rejects_reference_mixed_with_others),
        cmocka_unit_test(test_renderer_empty_scene_is_background),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
