/* Open displaced surfaces drawn by the geometry techniques (displace_common.h, both_faces): the
 * reference traces a height field's micro-triangles as they are, both faces, with no cap at an
 * open border; through a mesh's opening -- the gap between the teapot's lid and its rim, a
 * tube's rim -- it sees the inside of the surface. `displacement` and `tessellation` must draw
 * it too: no pixel left at the background where the reference covers the whole 5 x 5 around
 * it. The band of OUTLINE_BAND pixels inside the reference's outline is left out (as the
 * random-view test leaves it out of the per-pixel techniques' footprint): there a coarser
 * silhouette -- `tessellation` stops splitting edges shorter than view_threshold pixels, and a
 * mortar groove's step at the far rim is thinner than that -- may differ by a pixel, an error
 * of the coverage IoU, not an opening. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "example_renders.h"
#include "test_util.h"

static meso_framebuffer *draw_with(meso_context *ctx, const meso_scene *scene,
                                   const char *technique, const meso_option *options,
                                   int num_options) {
    meso_framebuffer *fb = NULL;
    meso_render_desc desc = {
        .technique = technique, .options = options, .num_options = num_options};
    if (meso_render_scene(ctx, scene, &desc, &fb) != MESO_OK)
        fail_msg("%s: %s", technique, meso_context_last_error(ctx));
    return fb;
}

static meso_framebuffer *draw(meso_context *ctx, const meso_scene *scene, const char *technique) {
    return draw_with(ctx, scene, technique, NULL, 0);
}

static bool covered(const meso_framebuffer *fb, int x, int y) {
    return fb->coverage[(size_t)y * (size_t)fb->width + (size_t)x] >= 0.5f;
}

#define OUTLINE_BAND 2

/* Pixels the technique leaves at the background where the reference covers the whole square
 * of OUTLINE_BAND pixels around them. */
static int holes_inside_the_truth(const meso_framebuffer *t, const meso_framebuffer *r) {
    int count = 0;
    for (int y = OUTLINE_BAND; y + OUTLINE_BAND < t->height; y++)
        for (int x = OUTLINE_BAND; x + OUTLINE_BAND < t->width; x++) {
            if (covered(t, x, y)) continue;
            bool inside = true;
            for (int dy = -OUTLINE_BAND; dy <= OUTLINE_BAND && inside; dy++)
                for (int dx = -OUTLINE_BAND; dx <= OUTLINE_BAND && inside; dx++)
                    inside = covered(r, x + dx, y + dy);
            count += inside;
        }
    return count;
}

/* Every geometry technique against the reference on `scene`; and with the option both_faces 0
 * (back faces culled, faster) the opening is seen as background again: at least `culled`
 * holes, so the view does look through an opening. */
static void check_geometry_techniques(meso_context *ctx, const meso_scene *scene, const char *what,
                                      int culled) {
    static const char *const techniques[] = {"displacement", "tessellation"};
    meso_framebuffer *truth = draw(ctx, scene, "reference");
    for (size_t i = 0; i < sizeof techniques / sizeof *techniques; i++) {
        meso_framebuffer *fb = draw(ctx, scene, techniques[i]);
        int holes = holes_inside_the_truth(fb, truth);
        if (holes > 0)
            fail_msg("%s, %s: %d background pixels where the reference draws the surface seen "
                     "through the opening",
                     what, techniques[i], holes);
        meso_framebuffer_destroy(fb);
        meso_option one_face = {.value = 0};
        snprintf(one_face.technique, sizeof one_face.technique, "%s", techniques[i]);
        snprintf(one_face.name, sizeof one_face.name, "both_faces");
        fb = draw_with(ctx, scene, techniques[i], &one_face, 1);
        holes = holes_inside_the_truth(fb, truth);
        if (holes < culled)
            fail_msg("%s, %s with both_faces 0: %d holes, expected at least %d", what,
                     techniques[i], holes, culled);
        meso_framebuffer_destroy(fb);
    }
    meso_framebuffer_destroy(truth);
}

/* bricks-teapot from above: the lid sits in the rim with a gap between them (Newell's patches:
 * the lid ends at radius 1.3, the rim starts at 1.4), and the pot's inside shows through it. */
static void test_teapot_lid_gap_shows_the_pots_inside(void **state) {
    (void)state;
    meso_context *ctx = test_context(0);
    meso_scene *scene = example_scene_load(ctx, "bricks-teapot", 128);
    scene->camera.eye = (meso_vec3){0.6882f, 3.1342f, 2.4839f};
    scene->camera.target = (meso_vec3){0.0f, 0.1f, 0.0f};
    check_geometry_techniques(ctx, scene, "bricks-teapot's lid", 100);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

/* An open tube of a user's OBJ file (no caps; positions, normals and UVs as an exporter writes
 * them, the seam's vertices duplicated, u = 1 - i / AROUND so that T x B = N as
 * docs/design.md has it), seen from above through its rim: the far inside wall shows between
 * the rims. */
static void test_tube_seen_through_its_rim(void **state) {
    (void)state;
    enum { AROUND = 48, ALONG = 8 };
    char obj[64 * 1024];
    size_t used = 0;
    for (int j = 0; j <= ALONG; j++)
        for (int i = 0; i <= AROUND; i++) {
            float a = 2.0f * MESO_PI * (float)(i % AROUND) / (float)AROUND;
            float y = -0.6f + 1.2f * (float)j / (float)ALONG;
            used += (size_t)snprintf(obj + used, sizeof obj - used,
                                     "v %.6f %.6f %.6f\nvn %.6f 0 %.6f\nvt %.6f %.6f\n",
                                     0.5 * cos(a), y, 0.5 * sin(a), cos(a), sin(a),
                                     1.0 - (double)i / AROUND, (double)j / ALONG);
        }
    for (int j = 0; j < ALONG; j++)
        for (int i = 0; i < AROUND; i++) {
            int a = j * (AROUND + 1) + i + 1, b = a + 1, c = a + AROUND + 1, d = c + 1;
            /* counter-clockwise seen from outside (normals out) */
            used += (size_t)snprintf(obj + used, sizeof obj - used,
                                     "f %d/%d/%d %d/%d/%d %d/%d/%d\nf %d/%d/%d %d/%d/%d %d/%d/%d\n",
                                     a, a, a, c, c, c, b, b, b, b, b, b, c, c, c, d, d, d);
        }
    assert_true(used < sizeof obj);
    const char *dir = test_temp_dir();
    const char *path = test_path(dir, "tube.obj");
    test_write_file(path, obj, used);
    char json[4096];
    snprintf(json, sizeof json,
             "{\"image\": {\"width\": 128, \"height\": 128, \"background\": [0, 0, 0]},"
             " \"camera\": {\"eye\": [0.4, 2.2, 1.3], \"target\": [0, 0, 0],"
             " \"up\": [0, 1, 0], \"fov_y_deg\": 40},"
             " \"ambient\": [0.2, 0.2, 0.2],"
             " \"lights\": [{\"type\": \"directional\", \"direction\": [0.3, 0.8, 0.4],"
             " \"color\": [1, 1, 1]}],"
             " \"objects\": [{\"shape\": {\"file\": \"%s\"}, \"uv_scale\": [6, 2],"
             " \"material\": {\"albedo\": [0.8, 0.7, 0.6]},"
             " \"mesostructure\": {\"height_map\": {\"procedural\": \"bricks\", \"resolution\": "
             "128}, \"depth\": 0.04}, \"technique\": \"reference\"}]}",
             path);
    meso_context *ctx = test_context(0);
    meso_scene *scene = NULL;
    if (meso_scene_parse(ctx, json, test_path(dir, "tube.json"), NULL, &scene) != MESO_OK)
        fail_msg("scene: %s", meso_context_last_error(ctx));
    check_geometry_techniques(ctx, scene, "an OBJ tube", 1000);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_teapot_lid_gap_shows_the_pots_inside),
        cmocka_unit_test(test_tube_seen_through_its_rim),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
