/* Normal maps: a constant tangent-space normal map on a flat plane shades
 * every technique and the reference as the analytic Lambert value of the tilted normal;
 * "normal_map_convention": "directx" flips green; a bad normal_map is one error line. Before,
 * "normal_map" was an unknown material key. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"

/* A 4x4 PNG, every texel the bytes (r, g, b). */
static void write_png(const char *path, int channels, int r, int g, int b) {
    meso_context *ctx = test_context(1);
    meso_image *image = NULL;
    assert_int_equal(meso_image_create(ctx, 4, 4, channels, &image), MESO_OK);
    const int rgb[3] = {r, g, b};
    for (int t = 0; t < 16; t++)
        for (int c = 0; c < channels; c++) image->pixels[t * channels + c] = rgb[c] / 255.0f;
    meso_png_desc linear = {.encoding = MESO_ENCODING_LINEAR}; /* the bytes as given */
    assert_int_equal(meso_image_save_png(ctx, image, path, &linear), MESO_OK);
    meso_image_destroy(image);
    meso_context_destroy(ctx);
}

/* The normal map's bytes: x = 2 * 128/255 - 1 (about 0), y = 0.6, z = 2 * 230/255 - 1. */
enum { NR = 128, NG = 204, NB = 230 };

/* A plane (P(u, v) = (-1 + 2u, 0, 1 - 2v): T = +x, B = -z, N = +y) seen from above, a flat
 * height field (a constant white map) so every technique draws it, no ambient, one white light
 * from direction (0, 0.8, -0.6). */
static meso_scene *plane(meso_context *ctx, const char *dir, const char *material) {
    char json[2048];
    snprintf(json, sizeof json,
             "{\"image\": {\"width\": 16, \"height\": 16},"
             " \"camera\": {\"eye\": [0, 3, 0], \"target\": [0, 0, 0], \"up\": [0, 0, -1],"
             "  \"fov_y_deg\": 20},"
             " \"ambient\": [0, 0, 0],"
             " \"lights\": [{\"type\": \"directional\", \"direction\": [0, 0.8, -0.6]}],"
             " \"objects\": [{\"shape\": \"plane\", \"size\": 2,"
             "   \"material\": {\"albedo\": [1, 1, 1]%s%s},"
             "   \"mesostructure\": {\"height_map\": \"white.png\", \"depth\": 0.05},"
             "   \"technique_options\": {\"vdm\": {\"resolution\": 16, \"num_theta\": 8,"
             "                          \"num_phi\": 4, \"num_curvatures\": 4}}}]}",
             material[0] ? ", " : "", material);
    meso_scene *scene = NULL;
    if (meso_scene_parse(ctx, json, "plane.json", dir, &scene) != MESO_OK)
        fail_msg("parse: %s", meso_context_last_error(ctx));
    return scene;
}

/* max(0, n.L) for the map's normal n = normalize(T x + B y + N z) = normalize(x, z, -y). */
static float lambert(bool directx) {
    float x = 2.0f * NR / 255.0f - 1.0f, y = 2.0f * NG / 255.0f - 1.0f;
    float z = 2.0f * NB / 255.0f - 1.0f;
    if (directx) y = -y;
    float len = sqrtf(x * x + y * y + z * z);
    float ndl = (z * 0.8f + y * 0.6f) / len;
    return ndl > 0.0f ? ndl : 0.0f;
}

static void check_centre(meso_context *ctx, const meso_scene *scene, const char *technique,
                         float want) {
    meso_framebuffer *fb = NULL;
    meso_render_desc desc = {.technique = technique};
    if (meso_render_scene(ctx, scene, &desc, &fb) != MESO_OK)
        fail_msg("%s: %s", technique, meso_context_last_error(ctx));
    size_t p = (size_t)(fb->height / 2) * (size_t)fb->width + (size_t)(fb->width / 2);
    assert_true(fb->coverage[p] > 0.0f);
    for (int c = 0; c < 3; c++)
        if (!(fabsf(fb->color[3 * p + c] - want) < 2e-3f))
            fail_msg("%s: channel %d is %.5f, want %.5f", technique, c, fb->color[3 * p + c], want);
    meso_framebuffer_destroy(fb);
}

static const char *const techniques[] = {"flat",         "bump",         "horizon",   "parallax",
                                         "relief",       "relief_exact", "vdm",       "gdm",
                                         "tessellation", "displacement", "reference", NULL};

static void test_a_constant_normal_map_shades_as_lambert_in_every_technique(void **state) {
    (void)state;
    const char *dir = test_temp_dir();
    write_png(test_path(dir, "white.png"), 3, 255, 255, 255);
    write_png(test_path(dir, "n.png"), 3, NR, NG, NB);
    meso_context *ctx = test_context(2);
    meso_scene *none = plane(ctx, dir, "");
    meso_scene *gl = plane(ctx, dir, "\"normal_map\": \"n.png\"");
    meso_scene *dx =
        plane(ctx, dir, "\"normal_map\": \"n.png\", \"normal_map_convention\": \"directx\"");
    /* the two conventions and no map differ well beyond the tolerance */
    assert_true(fabsf(lambert(false) - lambert(true)) > 0.5f);
    assert_true(fabsf(lambert(false) - 0.8f) > 0.1f);
    for (int i = 0; techniques[i]; i++) {
        check_centre(ctx, none, techniques[i], 0.8f);
        check_centre(ctx, gl, techniques[i], lambert(false));
        check_centre(ctx, dx, techniques[i], lambert(true));
    }
    meso_scene_destroy(none);
    meso_scene_destroy(gl);
    meso_scene_destroy(dx);
    meso_context_destroy(ctx);
}

/* meso render on a scene whose normal_map is bad: exit 2, one line naming the key. */
static void check_bad(const char *dir, const char *name, const char *material, const char *why) {
    char json[1024], command[4096], err[1200];
    snprintf(json, sizeof json, "{\"objects\": [{\"shape\": \"plane\", \"material\": {%s}}]}",
             material);
    const char *scene = test_path(dir, name);
    test_write_file(scene, json, strlen(json));
    snprintf(err, sizeof err, "%s.err", scene);
    snprintf(command, sizeof command, "%s render %s -o %s.png 2> %s", MESO_PROGRAM, scene, scene,
             err);
    int status = system(command);
    assert_true(WIFEXITED(status));
    assert_int_equal(WEXITSTATUS(status), 2);
    size_t size;
    char *text = test_read_file(err, &size);
    char want[1400];
    snprintf(want, sizeof want, "meso: %s: objects[0].material.", scene);
    if (!strstr(text, want) || !strstr(text, why) || strchr(text, '\n') != text + size - 1)
        fail_msg("stderr:\n%s", text);
    free(text);
}

/* meso info names the map and its convention. */
static void test_meso_info_reports_the_normal_map(void **state) {
    (void)state;
    const char *dir = test_temp_dir();
    write_png(test_path(dir, "n.png"), 3, NR, NG, NB);
    const char *json = "{\"objects\": [{\"shape\": \"plane\", \"material\": "
                       "{\"normal_map\": \"n.png\", \"normal_map_convention\": \"directx\"}}]}";
    const char *scene = test_path(dir, "info.json");
    test_write_file(scene, json, strlen(json));
    char command[4096], out[1200];
    snprintf(out, sizeof out, "%s.txt", scene);
    snprintf(command, sizeof command, "%s info %s > %s", MESO_PROGRAM, scene, out);
    assert_int_equal(system(command), 0);
    size_t size;
    char *text = test_read_file(out, &size);
    if (!strstr(text, ", normal map 4x4 (DirectX),")) fail_msg("meso info said:\n%s", text);
    free(text);
}

static void test_a_bad_normal_map_is_one_error_line(void **state) {
    (void)state;
    const char *dir = test_temp_dir();
    write_png(test_path(dir, "grey.png"), 1, 128, 0, 0);
    check_bad(dir, "missing.json", "\"normal_map\": \"nowhere.png\"", "normal_map");
    check_bad(dir, "grey.json", "\"normal_map\": \"grey.png\"", "needs RGB channels");
    check_bad(dir, "convention.json",
              "\"normal_map\": \"grey.png\", \"normal_map_convention\": \"vulkan\"",
              "normal_map_convention: must be \"opengl\" or \"directx\"");
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_a_constant_normal_map_shades_as_lambert_in_every_technique),
        cmocka_unit_test(test_a_bad_normal_map_is_one_error_line),
        cmocka_unit_test(test_meso_info_reports_the_normal_map),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
