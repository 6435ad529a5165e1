/* Open borders of the relief family (relief_common.h, relief_domain): on a plane whose map
 * repeats, a ray that leaves the plane's texture domain through its far side has left the shell
 * -- the truth has nothing there -- and must miss, not draw the next tile of the map as a strip
 * past the border. Seen low over the far edge, no technique may cover a pixel whose 3 x 3 the
 * reference leaves empty. */
#include <stdio.h>
#include <string.h>

#include "test_util.h"

static meso_scene *plane_scene(meso_context *ctx, const char *mesostructure) {
    char json[2048];
    snprintf(json, sizeof json,
             "{\"image\": {\"width\": 128, \"height\": 64, \"background\": [0, 0, 0]},"
             " \"camera\": {\"eye\": [0.3, 0.55, 2.2], \"target\": [0.1, -0.05, -0.9],"
             " \"up\": [0, 1, 0], \"fov_y_deg\": 30},"
             " \"ambient\": [0.2, 0.2, 0.2],"
             " \"lights\": [{\"type\": \"directional\", \"direction\": [0.3, 0.8, 0.4],"
             " \"color\": [1, 1, 1]}],"
             " \"objects\": [{\"shape\": \"plane\", \"size\": 2, \"uv_scale\": [3, 3],"
             " \"material\": {\"albedo\": [0.8, 0.7, 0.6]},"
             " \"mesostructure\": %s, \"technique\": \"reference\"}]}",
             mesostructure);
    meso_scene *scene = NULL;
    if (meso_scene_parse(ctx, json, "open-border.json", NULL, &scene) != MESO_OK)
        fail_msg("scene: %s", meso_context_last_error(ctx));
    return scene;
}

static meso_framebuffer *draw(meso_context *ctx, const meso_scene *scene, const char *technique) {
    meso_framebuffer *fb = NULL;
    if (meso_render_scene(ctx, scene, &(meso_render_desc){.technique = technique}, &fb) != MESO_OK)
        fail_msg("%s: %s", technique, meso_context_last_error(ctx));
    return fb;
}

/* Pixels the technique covers with no reference pixel covered in their 3 x 3. */
static int past_the_truth(const meso_framebuffer *t, const meso_framebuffer *r) {
    int count = 0;
    for (int y = 0; y < t->height; y++)
        for (int x = 0; x < t->width; x++) {
            if (t->coverage[(size_t)y * (size_t)t->width + (size_t)x] < 0.5f) continue;
            bool near = false;
            for (int dy = -1; dy <= 1 && !near; dy++)
                for (int dx = -1; dx <= 1 && !near; dx++) {
                    int xx = x + dx, yy = y + dy;
                    near = xx >= 0 && yy >= 0 && xx < r->width && yy < r->height &&
                           r->coverage[(size_t)yy * (size_t)r->width + (size_t)xx] >= 0.5f;
                }
            count += !near;
        }
    return count;
}

static void check(const char *mesostructure, const char *const *techniques, size_t n) {
    meso_context *ctx = test_context(0);
    meso_scene *scene = plane_scene(ctx, mesostructure);
    meso_framebuffer *truth = draw(ctx, scene, "reference");
    for (size_t i = 0; i < n; i++) {
        meso_framebuffer *fb = draw(ctx, scene, techniques[i]);
        int past = past_the_truth(fb, truth);
        if (past > 0) fail_msg("%s: %d pixels past the plane's border", techniques[i], past);
        meso_framebuffer_destroy(fb);
    }
    meso_framebuffer_destroy(truth);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

static void test_relief_family_draws_nothing_past_a_height_fields_open_border(void **state) {
    (void)state;
    static const char *const techniques[] = {"relief", "relief_exact", "relief_layers"};
    check("{\"height_map\": {\"procedural\": \"bricks\", \"resolution\": 128}, \"depth\": 0.12}",
          techniques, 3);
}

static void test_relief_layers_draws_nothing_past_a_solids_open_border(void **state) {
    (void)state;
    static const char *const techniques[] = {"relief_layers"};
    check("{\"solid\": {\"procedural\": \"weave\"}, \"depth\": 0.12}", techniques, 1);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_relief_family_draws_nothing_past_a_height_fields_open_border),
        cmocka_unit_test(test_relief_layers_draws_nothing_past_a_solids_open_border),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
