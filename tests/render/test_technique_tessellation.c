/* `tessellation` (Doggett & Hirche 2000): crack-free for every combination of the four edge
 * tests on closed meshes, the base mesh when every test is off, fewer triangles when the camera
 * moves away (view test), nothing inserted on a constant height field, deterministic; shadow
 * maps that follow a turned light and, drawn from the lights' view, not the camera. */
#include "displace_fixture.h"

extern const meso_technique meso_technique_tessellation;
static const meso_technique *technique = &meso_technique_tessellation;

static void set_tests(fixture *f, int normal, int area, int view, int limit) {
    fixture_set_option(f, "normal_test", normal);
    fixture_set_option(f, "area_test", area);
    fixture_set_option(f, "view_test", view);
    fixture_set_option(f, "limit_test", limit);
    fixture_set_option(f, "shadows", 0);
}

static size_t triangle_count(fixture *f) {
    void *state = NULL;
    size_t count = fixture_geometry(f, technique, &state)->num_triangles;
    technique->release(state);
    return count;
}

static void check_closed_for_every_combination(fixture *f) {
    fixture_set_option(f, "max_level", 4);
    /* low thresholds so that every test inserts plenty */
    fixture_set_option(f, "normal_threshold", 0.05);
    fixture_set_option(f, "area_threshold", 0.01);
    fixture_set_option(f, "view_threshold", 2.0);
    size_t base = f->mesh->num_triangles, refined = 0;
    for (int combo = 0; combo < 16; combo++) {
        set_tests(f, combo & 1, (combo >> 1) & 1, (combo >> 2) & 1, (combo >> 3) & 1);
        void *state = NULL;
        const meso_mesh *mesh = fixture_geometry(f, technique, &state);
        size_t open = fixture_count_open_edges(mesh);
        if (open != 0)
            fail_msg("tests normal %d area %d view %d limit %d: %zu open edges in %zu triangles",
                     combo & 1, (combo >> 1) & 1, (combo >> 2) & 1, (combo >> 3) & 1, open,
                     mesh->num_triangles);
        refined += mesh->num_triangles > base;
        technique->release(state);
    }
    assert_true(refined >= 12); /* the check saw real tessellations, not just base meshes */
}

static void test_tessellation_sphere_has_no_cracks_for_every_test_combination(void **state) {
    (void)state;
    fixture f;
    fixture_init(&f, 2);
    fixture_sphere(&f, 1);
    check_closed_for_every_combination(&f);
    fixture_deinit(&f);
}

static void test_tessellation_torus_has_no_cracks_across_uv_seams(void **state) {
    (void)state;
    fixture f;
    fixture_init(&f, 2);
    fixture_torus(&f, 12, 8);
    check_closed_for_every_combination(&f);
    fixture_deinit(&f);
}

static void test_tessellation_with_every_test_off_returns_the_base_mesh(void **state) {
    (void)state;
    fixture f;
    fixture_init(&f, 1);
    fixture_heights(&f, 32, FIELD_CONSTANT, 1.0f); /* h = 1: vertices stay on the mesh */
    fixture_torus(&f, 10, 6);
    set_tests(&f, 0, 0, 0, 0);
    void *st = NULL;
    const meso_mesh *mesh = fixture_geometry(&f, technique, &st);
    assert_int_equal(mesh->num_triangles, f.mesh->num_triangles);
    for (size_t t = 0; t < mesh->num_triangles * 3; t++) {
        meso_vec3 a = mesh->positions[mesh->indices[t]], b = f.mesh->positions[f.mesh->indices[t]];
        /* exactly equal (== rather than bits: -0 + 0 gives +0) */
        assert_true(a.x == b.x && a.y == b.y && a.z == b.z);
    }
    technique->release(st);
    /* with a real height field too: the same triangles, only displaced */
    fixture_heights(&f, 32, FIELD_BUMPS, 0.0f);
    assert_int_equal(triangle_count(&f), f.mesh->num_triangles);
    fixture_deinit(&f);
}

static void test_tessellation_view_test_makes_fewer_triangles_farther_away(void **state) {
    (void)state;
    fixture f;
    fixture_init(&f, 2);
    fixture_sphere(&f, 1);
    set_tests(&f, 0, 0, 1, 0);
    fixture_set_option(&f, "max_level", 6);
    const float distances[] = {2.5f, 3.0f, 4.0f, 6.0f, 10.0f, 20.0f, 40.0f};
    size_t previous = SIZE_MAX, first = 0, last = 0;
    for (size_t i = 0; i < sizeof(distances) / sizeof(distances[0]); i++) {
        f.scene.camera.eye = (meso_vec3){0.0f, 0.3f * distances[i], distances[i]};
        size_t count = triangle_count(&f);
        if (count > previous)
            fail_msg("distance %g: %zu triangles, more than %zu nearer", distances[i], count,
                     previous);
        if (i == 0) first = count;
        last = count;
        previous = count;
    }
    assert_true(first > 4 * last);
    assert_true(last >= f.mesh->num_triangles);
    fixture_deinit(&f);
}

static void test_tessellation_constant_height_field_inserts_nothing(void **state) {
    (void)state;
    fixture f;
    fixture_init(&f, 1);
    fixture_heights(&f, 64, FIELD_CONSTANT, 0.3f);
    fixture_plane(&f, 2);
    fixture_set_option(&f, "normal_threshold", 0.0);
    fixture_set_option(&f, "area_threshold", 0.0);
    fixture_set_option(&f, "span_texels", 0.0); /* the surface tests alone */
    const int combos[3][2] = {{1, 0}, {0, 1}, {1, 1}};
    for (int c = 0; c < 3; c++) {
        /* with the recursion limits on, as by default: they only veto */
        set_tests(&f, combos[c][0], combos[c][1], 1, 1);
        assert_int_equal(triangle_count(&f), f.mesh->num_triangles);
    }
    /* the same plane with bumps does get refined by each test alone */
    fixture_heights(&f, 64, FIELD_BUMPS, 0.0f);
    for (int c = 0; c < 2; c++) {
        set_tests(&f, combos[c][0], combos[c][1], 0, 0);
        assert_true(triangle_count(&f) > f.mesh->num_triangles * 4);
    }
    fixture_deinit(&f);
}

static void test_tessellation_max_level_bounds_the_count(void **state) {
    (void)state;
    fixture f;
    fixture_init(&f, 1);
    fixture_plane(&f, 1);
    set_tests(&f, 1, 1, 0, 0);
    fixture_set_option(&f, "normal_threshold", 0.0);
    fixture_set_option(&f, "area_threshold", 0.0);
    for (int level = 0; level <= 5; level++) {
        fixture_set_option(&f, "max_level", level);
        size_t count = triangle_count(&f);
        assert_true(count <= (size_t)2 << (2 * level));
        assert_true(count >= 2);
    }
    fixture_deinit(&f);
}

static void test_tessellation_output_does_not_depend_on_thread_count(void **state) {
    (void)state;
    fixture one, two;
    fixture_init(&one, 1);
    fixture_init(&two, 2);
    fixture_torus(&one, 12, 8);
    fixture_torus(&two, 12, 8);
    set_tests(&one, 1, 1, 1, 1);
    set_tests(&two, 1, 1, 1, 1);
    void *sa = NULL, *sb = NULL;
    const meso_mesh *a = fixture_geometry(&one, technique, &sa);
    const meso_mesh *b = fixture_geometry(&two, technique, &sb);
    assert_int_equal(a->num_triangles, b->num_triangles);
    assert_int_equal(a->num_vertices, b->num_vertices);
    assert_memory_equal(a->positions, b->positions, a->num_vertices * sizeof(meso_vec3));
    assert_memory_equal(a->indices, b->indices, a->num_triangles * 3 * sizeof(uint32_t));
    /* the same state after its context gains a thread (meso bench measures scaling so) */
    meso_context_set_num_threads(one.ctx, 2);
    const meso_mesh *c = NULL;
    assert_int_equal(technique->geometry(one.ctx, sa, &one.frame, &c), MESO_OK);
    assert_int_equal(c->num_triangles, b->num_triangles);
    assert_memory_equal(c->positions, b->positions, b->num_vertices * sizeof(meso_vec3));
    assert_memory_equal(c->indices, b->indices, b->num_triangles * 3 * sizeof(uint32_t));
    technique->release(sa);
    technique->release(sb);
    fixture_deinit(&one);
    fixture_deinit(&two);
}

static void assert_same_mesh(const meso_mesh *a, const meso_mesh *b) {
    assert_int_equal(a->num_triangles, b->num_triangles);
    assert_int_equal(a->num_vertices, b->num_vertices);
    size_t n = a->num_vertices;
    assert_memory_equal(a->positions, b->positions, n * sizeof(meso_vec3));
    assert_memory_equal(a->normals, b->normals, n * sizeof(meso_vec3));
    assert_memory_equal(a->tangents, b->tangents, n * sizeof(meso_vec3));
    assert_memory_equal(a->bitangents, b->bitangents, n * sizeof(meso_vec3));
    assert_memory_equal(a->uvs, b->uvs, n * sizeof(meso_vec2));
    assert_memory_equal(a->indices, b->indices, a->num_triangles * 3 * sizeof(uint32_t));
}

/* The tessellator remembers displaced midpoints and their edges' decisions across frames
 * (displace_tessellator_run): a state that has drawn other views first must draw the mesh of a
 * fresh state, bit for bit, and the same view twice the same mesh. */
static void kept_midpoints_fixture(fixture *f, int threads) {
    fixture_init(f, threads);
    fixture_torus(f, 12, 8);
    set_tests(f, 1, 1, 1, 1);
    fixture_set_option(f, "normal_threshold", 0.05);
    fixture_set_option(f, "area_threshold", 0.01);
}

static void test_tessellation_kept_midpoints_give_the_fresh_mesh(void **state) {
    (void)state;
    const meso_vec3 eyes[3] = {{0.0f, 1.5f, 3.5f}, {2.0f, 0.5f, 2.0f}, {-0.5f, 2.5f, 1.5f}};
    fixture kept;
    kept_midpoints_fixture(&kept, 2);
    void *kept_state = NULL;
    const meso_mesh *mesh = fixture_geometry(&kept, technique, &kept_state);
    for (int e = 1; e < 3; e++) {
        fixture fresh;
        kept_midpoints_fixture(&fresh, 1);
        fresh.scene.camera.eye = eyes[e];
        void *fresh_state = NULL;
        const meso_mesh *expected = fixture_geometry(&fresh, technique, &fresh_state);
        kept.scene.camera.eye = eyes[e];
        meso_frame_init(&kept.frame, &kept.scene, kept.scene.width, kept.scene.height);
        for (int repeat = 0; repeat < 2; repeat++) {
            assert_int_equal(technique->geometry(kept.ctx, kept_state, &kept.frame, &mesh),
                             MESO_OK);
            assert_same_mesh(mesh, expected);
        }
        technique->release(fresh_state);
        fixture_deinit(&fresh);
    }
    technique->release(kept_state);
    fixture_deinit(&kept);
}

static void test_tessellation_rejects_bad_options_naming_them(void **state) {
    (void)state;
    fixture f;
    fixture_init(&f, 1);
    fixture_plane(&f, 1);
    f.object.mesh = f.mesh;
    void *st = NULL;
    fixture_set_option(&f, "normal_treshold", 0.1); /* typo */
    assert_int_equal(technique->prepare(f.ctx, &f.scene, &f.object, &st),
                     MESO_ERROR_INVALID_ARGUMENT);
    assert_null(st);
    assert_non_null(strstr(meso_context_last_error(f.ctx), "normal_treshold"));
    fixture_clear_options(&f);
    fixture_set_option(&f, "max_level", 11);
    assert_int_equal(technique->prepare(f.ctx, &f.scene, &f.object, &st),
                     MESO_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(meso_context_last_error(f.ctx), "max_level"));
    fixture_clear_options(&f);
    fixture_set_option(&f, "view_threshold", -1.0);
    assert_int_equal(technique->prepare(f.ctx, &f.scene, &f.object, &st),
                     MESO_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(meso_context_last_error(f.ctx), "view_threshold"));
    assert_null(st);
    fixture_deinit(&f);
}

static void test_tessellation_shades_a_lit_flat_surface_unshadowed(void **state) {
    (void)state;
    fixture f;
    fixture_init(&f, 1);
    fixture_heights(&f, 32, FIELD_CONSTANT, 0.5f);
    fixture_plane(&f, 2);
    fixture_set_option(&f, "shadow_map_size", 256);
    f.scene.lights[0].direction = meso_vec3_normalize((meso_vec3){0.3f, 1.0f, 0.2f});
    void *st = NULL;
    const meso_mesh *mesh = fixture_geometry(&f, technique, &st);
    /* a fragment at the centroid of every output triangle, as the rasterizer would make it */
    float expected = 0.8f * (0.1f + f.scene.lights[0].direction.y);
    for (size_t t = 0; t < mesh->num_triangles; t++) {
        const uint32_t *i = &mesh->indices[t * 3];
        meso_fragment frag = {0};
        frag.triangle = (uint32_t)t;
        frag.b0 = frag.b1 = frag.b2 = 1.0f / 3.0f;
        frag.position = meso_vec3_barycentric(mesh->positions[i[0]], mesh->positions[i[1]],
                                              mesh->positions[i[2]], 1 / 3.f, 1 / 3.f, 1 / 3.f);
        frag.normal = mesh->normals[i[0]];
        frag.tangent = mesh->tangents[i[0]];
        frag.bitangent = mesh->bitangents[i[0]];
        frag.uv = meso_vec2_barycentric(mesh->uvs[i[0]], mesh->uvs[i[1]], mesh->uvs[i[2]], 1 / 3.f,
                                        1 / 3.f, 1 / 3.f);
        technique->shade(st, &f.frame, &f.object, &frag, 1);
        assert_float_equal(frag.color.x, expected, 2e-3f);
        /* the displaced surface is at -(1 - h) depth */
        assert_float_equal(frag.position.y, -0.05f, 1e-6f);
    }
    technique->release(st);
    fixture_deinit(&f);
}

/* Shade a fixed grid of fragments on the displaced plane (no source triangle: the face normal
 * is the fragment's) with `frame`: what the shadow maps say there. */
#define PROBES 64
static void shade_probes(const fixture *f, void *st, const meso_frame *frame,
                         meso_vec3 colors[PROBES]) {
    for (int k = 0; k < PROBES; k++) {
        float x = -0.9f + 1.8f * (float)(k % 8) / 7.0f, z = -0.9f + 1.8f * (float)(k / 8) / 7.0f;
        meso_fragment frag = {0};
        frag.triangle = UINT32_MAX;
        frag.b0 = 1.0f;
        frag.uv = (meso_vec2){0.5f * (x + 1.0f), 0.5f * (1.0f - z)};
        float h = meso_heightfield_sample(&f->heightfield, frag.uv.x, frag.uv.y);
        frag.position = (meso_vec3){x, -(1.0f - h) * f->object.mesostructure.depth, z};
        frag.normal = (meso_vec3){0, 1, 0};
        frag.tangent = (meso_vec3){1, 0, 0};
        frag.bitangent = (meso_vec3){0, 0, -1};
        technique->shade(st, frame, &f->object, &frag, 1);
        colors[k] = frag.color;
    }
}

/* Probes darker than half the brightest: in shadow. */
static int shadowed_probes(const meso_vec3 colors[PROBES]) {
    float brightest = 0.0f;
    for (int k = 0; k < PROBES; k++) brightest = fmaxf(brightest, colors[k].x);
    int count = 0;
    for (int k = 0; k < PROBES; k++) count += colors[k].x < 0.5f * brightest;
    return count;
}

static void prepare_shadowed_bumps(fixture *f, int shadow_tessellation) {
    fixture_init(f, 1);
    fixture_plane(f, 2);
    fixture_set_option(f, "max_level", 5);
    fixture_set_option(f, "shadow_map_size", 256);
    fixture_set_option(f, "shadow_tessellation", shadow_tessellation);
    f->object.mesostructure.depth = 0.3f; /* deep: the bumps shadow each other */
}

/* The viewer turns a light in place, without preparing again: the shadow maps must follow,
 * exactly as a state prepared with the new light draws them (both shadow sources). */
static void test_tessellation_shadows_follow_a_turned_light(void **state) {
    (void)state;
    for (int mode = 0; mode <= 1; mode++) {
        fixture f;
        prepare_shadowed_bumps(&f, mode);
        void *st = NULL;
        fixture_geometry(&f, technique, &st);
        meso_vec3 before[PROBES], turned[PROBES], fresh[PROBES];
        shade_probes(&f, st, &f.frame, before);
        f.scene.lights[0].direction = meso_vec3_normalize((meso_vec3){-0.8f, 0.35f, -0.2f});
        const meso_mesh *mesh = NULL;
        assert_int_equal(technique->geometry(f.ctx, st, &f.frame, &mesh), MESO_OK);
        shade_probes(&f, st, &f.frame, turned);
        void *st2 = NULL;
        fixture_geometry(&f, technique, &st2);
        shade_probes(&f, st2, &f.frame, fresh);
        assert_memory_equal(turned, fresh, sizeof(turned));
        assert_true(shadowed_probes(fresh) > 0);
        assert_memory_not_equal(before, turned, sizeof(turned));
        technique->release(st);
        technique->release(st2);
        fixture_deinit(&f);
    }
}

/* shadow_tessellation 1: the maps come from the lights' view, so a camera elsewhere leaves
 * them as they are (they are kept while the camera moves). */
static void test_tessellation_light_view_shadows_do_not_depend_on_the_camera(void **state) {
    (void)state;
    fixture f;
    prepare_shadowed_bumps(&f, 1);
    void *near = NULL, *far = NULL;
    fixture_geometry(&f, technique, &near);
    f.scene.camera.eye = (meso_vec3){2.0f, 4.0f, 9.0f};
    fixture_geometry(&f, technique, &far);
    meso_vec3 a[PROBES], b[PROBES];
    shade_probes(&f, near, &f.frame, a);
    shade_probes(&f, far, &f.frame, b);
    assert_memory_equal(a, b, sizeof(a));
    assert_true(shadowed_probes(a) > 0); /* the test sees the maps */
    technique->release(near);
    technique->release(far);
    fixture_deinit(&f);
}

/* The rasterizer shades tessellation's blocks eight fragments at a time (displace_shade8.h):
 * the same colours, bit for bit, as the per-fragment shade (displace_fixture.h). */
static void test_tessellation_block_shading_matches_per_fragment(void **state) {
    (void)state;
    fixture_check_block_shading(technique, "max_level");
}

/* ---- A moving camera: frames of an orbit against fresh renderers ------------------------- */

/* The info lines of a context, the last tessellation line kept: "... base triangles replayed R
 * of B". */
typedef struct replay_log {
    unsigned long long replayed, base;
    int lines;
} replay_log;

static void capture_replays(void *user, meso_log_level level, const char *message) {
    replay_log *log = user;
    const char *at = strstr(message, "base triangles replayed ");
    if (level != MESO_LOG_INFO || !at) return;
    if (sscanf(at, "base triangles replayed %llu of %llu", &log->replayed, &log->base) == 2)
        log->lines++;
}

static meso_scene *orbit_scene(meso_context *ctx) {
    /* the teapot in bricks (examples/bricks-teapot.json, smaller): open borders, seams and
     * a self-shadowing surface under the default options (shadow map of the camera's mesh) */
    const char *json =
        "{\"image\": {\"width\": 96, \"height\": 96},"
        " \"camera\": {\"eye\": [0, 1.8, 3.6], \"target\": [0, 0.1, 0], \"fov_y_deg\": 40},"
        " \"lights\": [{\"type\": \"directional\", \"direction\": [-0.6, 0.7, 0.5]}],"
        " \"objects\": [{\"shape\": \"teapot\", \"uv_scale\": [2, 2],"
        "   \"material\": {\"color_map\": \"mesostructure\"},"
        "   \"mesostructure\": {\"height_map\": {\"procedural\": \"bricks\","
        "                       \"resolution\": 128}, \"depth\": 0.05},"
        "   \"technique\": \"tessellation\","
        "   \"technique_options\": {\"shadow_map_size\": 512}}]}";
    meso_scene *scene = NULL;
    meso_result r = meso_scene_parse(ctx, json, "orbit.json", ".", &scene);
    if (r != MESO_OK) fail_msg("parse: %s", meso_context_last_error(ctx));
    return scene;
}

/* The eye turned by `turns` of a turn about the vertical axis through the target (meso bench
 * --orbit turns the camera so, frame after frame). */
static meso_vec3 orbit_eye(meso_vec3 eye, meso_vec3 target, float turns) {
    float c = cosf(2.0f * MESO_PI * turns), s = sinf(2.0f * MESO_PI * turns);
    meso_vec3 d = meso_vec3_sub(eye, target);
    return meso_vec3_add(target, (meso_vec3){c * d.x + s * d.z, d.y, -s * d.x + c * d.z});
}

static meso_framebuffer *render_frame(meso_context *ctx, meso_renderer *renderer,
                                      const meso_scene *scene) {
    meso_framebuffer *fb = NULL;
    assert_int_equal(meso_framebuffer_create(ctx, scene->width, scene->height, &fb), MESO_OK);
    meso_result r = meso_renderer_render(renderer, fb);
    if (r != MESO_OK) fail_msg("render: %s", meso_context_last_error(ctx));
    return fb;
}

/* One renderer drawing frame after frame of an orbit keeps the tessellator's traversals and
 * replays those whose vetoes still answer alike, and redraws the shadow map from each frame's
 * mesh: every frame must be, byte for byte, the frame of a renderer made for that view alone
 * (2 threads against 1). Steps of 1/120 and 1/30 of a turn, then the camera standing still:
 * a still camera replays every base triangle, a moving one some but not all. */
static void test_tessellation_orbit_frames_equal_fresh_renders(void **state) {
    (void)state;
    replay_log log = {0};
    meso_context *kept_ctx = NULL;
    meso_context_desc desc = {.num_threads = 2,
                              .log = capture_replays,
                              .log_user = &log,
                              .progress = MESO_PROGRESS_NEVER};
    assert_int_equal(meso_context_create(&desc, &kept_ctx), MESO_OK);
    meso_context *fresh_ctx = test_context(1);
    meso_scene *kept_scene = orbit_scene(kept_ctx);
    meso_scene *fresh_scene = orbit_scene(fresh_ctx);
    const meso_camera home = kept_scene->camera;
    meso_renderer *kept = NULL;
    assert_int_equal(meso_renderer_create(kept_ctx, kept_scene, &(meso_render_desc){0}, &kept),
                     MESO_OK);
    /* frame k at turns[k]: small steps, larger ones, then standing still */
    const float turns[] = {0.0f,       1.0f / 120,  2.0f / 120,  3.0f / 120,  4.0f / 120,
                           8.0f / 120, 12.0f / 120, 16.0f / 120, 16.0f / 120, 16.0f / 120};
    const int frames = (int)(sizeof(turns) / sizeof(turns[0]));
    int moving_replays = 0;
    for (int k = 0; k < frames; k++) {
        meso_camera camera = home;
        camera.eye = orbit_eye(home.eye, home.target, turns[k]);
        kept_scene->camera = camera;
        fresh_scene->camera = camera;
        int lines = log.lines;
        meso_framebuffer *a = render_frame(kept_ctx, kept, kept_scene);
        assert_int_equal(log.lines, lines + 1);
        meso_renderer *fresh = NULL;
        assert_int_equal(
            meso_renderer_create(fresh_ctx, fresh_scene, &(meso_render_desc){0}, &fresh), MESO_OK);
        meso_framebuffer *b = render_frame(fresh_ctx, fresh, fresh_scene);
        size_t pixels = (size_t)a->width * (size_t)a->height;
        assert_memory_equal(a->color, b->color, pixels * 3 * sizeof(float));
        assert_memory_equal(a->depth, b->depth, pixels * sizeof(float));
        bool still = k > 0 && turns[k] == turns[k - 1];
        if (still) assert_int_equal(log.replayed, log.base);
        if (k > 0 && !still) {
            assert_true(log.replayed < log.base);
            moving_replays += log.replayed > 0;
        }
        meso_framebuffer_destroy(a);
        meso_framebuffer_destroy(b);
        meso_renderer_destroy(fresh);
    }
    assert_true(moving_replays > 0); /* small steps leave most of the far side as it was */
    meso_renderer_destroy(kept);
    meso_scene_destroy(kept_scene);
    meso_scene_destroy(fresh_scene);
    meso_context_destroy(kept_ctx);
    meso_context_destroy(fresh_ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_tessellation_sphere_has_no_cracks_for_every_test_combination),
        cmocka_unit_test(test_tessellation_torus_has_no_cracks_across_uv_seams),
        cmocka_unit_test(test_tessellation_with_every_test_off_returns_the_base_mesh),
        cmocka_unit_test(test_tessellation_view_test_makes_fewer_triangles_farther_away),
        cmocka_unit_test(test_tessellation_constant_height_field_inserts_nothing),
        cmocka_unit_test(test_tessellation_max_level_bounds_the_count),
        cmocka_unit_test(test_tessellation_output_does_not_depend_on_thread_count),
        cmocka_unit_test(test_tessellation_kept_midpoints_give_the_fresh_mesh),
        cmocka_unit_test(test_tessellation_block_shading_matches_per_fragment),
        cmocka_unit_test(test_tessellation_rejects_bad_options_naming_them),
        cmocka_unit_test(test_tessellation_shades_a_lit_flat_surface_unshadowed),
        cmocka_unit_test(test_tessellation_shadows_follow_a_turned_light),
        cmocka_unit_test(test_tessellation_light_view_shadows_do_not_depend_on_the_camera),
        cmocka_unit_test(test_tessellation_orbit_frames_equal_fresh_renders),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
