/* meso bake -o: the OpenEXR writer round-trips (read back with OpenEXR's own C reader), and
 * the export writes what the manifest lists: 16-bit heights equal to the field within one
 * step of 1/65535, the VDM tables with the sizes the manifest says. No GL context needed. */
#include <cjson/cJSON.h>
#include <math.h>
#include <openexr.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "test_util.h"

/* Read every channel of a scanline EXR as floats, interleaved in the order of `names`. */
static float *read_exr(const char *path, int num_channels, const char *const *names, int *out_width,
                       int *out_height) {
    exr_context_t exr = NULL;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    assert_int_equal(exr_start_read(&exr, path, &init), EXR_ERR_SUCCESS);
    exr_attr_box2i_t window;
    assert_int_equal(exr_get_data_window(exr, 0, &window), EXR_ERR_SUCCESS);
    int width = window.max.x - window.min.x + 1, height = window.max.y - window.min.y + 1;
    int32_t lines = 0;
    assert_int_equal(exr_get_scanlines_per_chunk(exr, 0, &lines), EXR_ERR_SUCCESS);
    float *planes = calloc((size_t)width * height * num_channels, sizeof(float));
    for (int y = 0; y < height; y += lines) {
        exr_chunk_info_t chunk;
        exr_decode_pipeline_t decoder;
        assert_int_equal(exr_read_scanline_chunk_info(exr, 0, window.min.y + y, &chunk),
                         EXR_ERR_SUCCESS);
        assert_int_equal(exr_decoding_initialize(exr, 0, &chunk, &decoder), EXR_ERR_SUCCESS);
        assert_int_equal(decoder.channel_count, num_channels);
        for (int k = 0; k < decoder.channel_count; k++) {
            int c = 0;
            while (c < num_channels && strcmp(names[c], decoder.channels[k].channel_name)) c++;
            assert_true(c < num_channels);
            decoder.channels[k].user_bytes_per_element = 4;
            decoder.channels[k].user_data_type = EXR_PIXEL_FLOAT;
            decoder.channels[k].user_pixel_stride = 4;
            decoder.channels[k].user_line_stride = 4 * width;
            decoder.channels[k].decode_to_ptr =
                (uint8_t *)(planes + (size_t)c * width * height + (size_t)y * width);
        }
        assert_int_equal(exr_decoding_choose_default_routines(exr, 0, &decoder), EXR_ERR_SUCCESS);
        assert_int_equal(exr_decoding_run(exr, 0, &decoder), EXR_ERR_SUCCESS);
        exr_decoding_destroy(exr, &decoder);
    }
    exr_finish(&exr);
    float *pixels = malloc((size_t)width * height * num_channels * sizeof(float));
    for (size_t i = 0; i < (size_t)width * height; i++)
        for (int c = 0; c < num_channels; c++)
            pixels[i * num_channels + c] = planes[(size_t)c * width * height + i];
    free(planes);
    *out_width = width;
    *out_height = height;
    return pixels;
}

static void test_exr_round_trip(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    enum { W = 37, H = 21, C = 3 }; /* not a multiple of the 16-line chunks */
    const char *names[C] = {"b", "A", "c0"};
    float pixels[W * H * C];
    for (int i = 0; i < W * H * C; i++) pixels[i] = sinf((float)i * 0.37f) * 3.0f + 0.001f * i;
    for (int half = 0; half < 2; half++) {
        const char *path = test_path(test_temp_dir(), half ? "half.exr" : "float.exr");
        assert_int_equal(meso_exr_write(ctx, path, W, H, C, names, pixels, half), MESO_OK);
        int w, h;
        float *back = read_exr(path, C, names, &w, &h);
        assert_int_equal(w, W);
        assert_int_equal(h, H);
        for (int i = 0; i < W * H * C; i++) {
            float expected = half ? meso_half_to_float(meso_half_from_float(pixels[i])) : pixels[i];
            if (back[i] != expected)
                fail_msg("%s: value %d: %g, not %g", path, i, back[i], expected);
        }
        free(back);
    }
    /* bad size: refused, nothing written */
    const char *bad = test_path(test_temp_dir(), "bad.exr");
    assert_int_equal(meso_exr_write(ctx, bad, 0, 4, 1, names, pixels, false),
                     MESO_ERROR_INVALID_ARGUMENT);
    assert_int_not_equal(access(bad, F_OK), 0);
    meso_context_destroy(ctx);
}

/* Export `example` with one option set into a fresh folder; its parsed manifest (caller
 * deletes) and the folder in *out_dir. */
static cJSON *export_example(meso_context *ctx, const char *example, const meso_option *option,
                             const char *folder, meso_scene **out_scene, const char **out_dir) {
    char path[1024];
    snprintf(path, sizeof path, "%s/examples/%s.json", MESO_SOURCE_DIR, example);
    assert_int_equal(meso_scene_load(ctx, path, out_scene), MESO_OK);
    const char *dir = test_path(test_temp_dir(), folder);
    char command[1200];
    snprintf(command, sizeof command, "rm -rf %s && mkdir -p %s", dir, dir);
    assert_int_equal(system(command), 0);
    meso_render_desc desc = {.technique = option->technique, .options = option, .num_options = 1};
    assert_int_equal(meso_gl_export_textures(ctx, *out_scene, &desc, dir), MESO_OK);
    size_t size;
    char *text = test_read_file(test_path(dir, "manifest.json"), &size);
    cJSON *manifest = cJSON_Parse(text);
    free(text);
    assert_non_null(manifest);
    *out_dir = dir;
    return manifest;
}

static void test_export_vdm_scene(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_scene *scene = NULL;
    const char *dir = NULL;
    meso_option small = {.technique = "vdm", .name = "resolution", .value = 32};
    cJSON *manifest = export_example(ctx, "bumps-sphere", &small, "export", &scene, &dir);
    cJSON *object = cJSON_GetArrayItem(cJSON_GetObjectItem(manifest, "objects"), 0);
    assert_string_equal(cJSON_GetObjectItem(object, "fragment_shader")->valuestring, "vdm.frag");
    cJSON *uniforms = cJSON_GetObjectItem(object, "uniforms");
    assert_int_equal(cJSON_GetObjectItem(uniforms, "u_resolution")->valueint, 32);
    assert_true(cJSON_GetObjectItem(uniforms, "u_depth_tiles")->valuedouble > 0.0);
    bool found = false;
    cJSON *texture;
    cJSON_ArrayForEach(texture, cJSON_GetObjectItem(object, "textures")) {
        if (strcmp(cJSON_GetObjectItem(texture, "uniform")->valuestring, "u_vdm_weights") != 0)
            continue;
        found = true;
        assert_int_equal(cJSON_GetObjectItem(texture, "width")->valueint, 32 * 8);
        assert_int_equal(cJSON_GetObjectItem(texture, "height")->valueint, 32);
        assert_int_equal(
            access(test_path(dir, cJSON_GetObjectItem(texture, "file")->valuestring), F_OK), 0);
    }
    assert_true(found);
    cJSON_Delete(manifest);

    /* the heights, 16 bits: within half a step of the field */
    const meso_heightfield *hf = scene->objects[0].mesostructure.height_field;
    char name[160];
    snprintf(name, sizeof name, "0-%s.height.png", scene->objects[0].name);
    meso_image *heights = NULL;
    assert_int_equal(meso_image_load_png(ctx, test_path(dir, name), &heights), MESO_OK);
    assert_int_equal(heights->width, hf->width);
    float worst = 0.0f;
    for (size_t i = 0; i < (size_t)hf->width * hf->height; i++)
        worst = fmaxf(worst, fabsf(heights->pixels[i * heights->channels] - hf->heights[i]));
    assert_true(worst <= 0.5f / 65535.0f + 1e-6f);
    meso_image_destroy(heights);

    /* the tables: sizes and channels as the manifest says, finite, not all zero */
    const char *w_names[8] = {"W00", "W01", "W02", "W03", "W04", "W05", "W06", "W07"};
    const char *e_names[8] = {"E00", "E01", "E02", "E03", "E04", "E05", "E06", "E07"};
    int w, h;
    snprintf(name, sizeof name, "0-%s.vdm-weights.exr", scene->objects[0].name);
    float *weights = read_exr(test_path(dir, name), 8, w_names, &w, &h);
    assert_int_equal(w, 32 * 8);
    assert_int_equal(h, 32);
    double energy = 0.0;
    for (int i = 0; i < w * h * 8; i++) {
        assert_true(isfinite(weights[i]));
        energy += weights[i] * weights[i];
    }
    assert_true(energy > 0.0);
    free(weights);
    snprintf(name, sizeof name, "0-%s.vdm-eigen.exr", scene->objects[0].name);
    float *eigen = read_exr(test_path(dir, name), 8, e_names, &w, &h);
    assert_int_equal(w, 32); /* num_theta */
    assert_int_equal(h, 16); /* num_curvatures */
    free(eigen);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

/* relief_layers: the map and its mirror, with the channels the manifest's u_num_layers says,
 * depths in [0, 1] and counts at most that many. */
static void test_export_layers(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_scene *scene = NULL;
    const char *dir = NULL;
    meso_option small = {.technique = "relief_layers", .name = "size", .value = 64};
    cJSON *manifest = export_example(ctx, "weave-plane", &small, "export-layers", &scene, &dir);
    cJSON *object = cJSON_GetArrayItem(cJSON_GetObjectItem(manifest, "objects"), 0);
    cJSON *uniforms = cJSON_GetObjectItem(object, "uniforms");
    int n = cJSON_GetObjectItem(uniforms, "u_num_layers")->valueint;
    assert_true(n >= 1 && n <= 8);
    assert_int_equal(cJSON_GetObjectItem(uniforms, "u_has_below")->valueint, 1);
    char storage[25][16];
    const char *names[25];
    for (int k = 0; k < n; k++) {
        snprintf(storage[k], 16, "D%02d", k);
        snprintf(storage[n + k], 16, "X%02d", k);
        snprintf(storage[2 * n + k], 16, "Y%02d", k);
    }
    snprintf(storage[3 * n], 16, "C");
    for (int c = 0; c <= 3 * n; c++) names[c] = storage[c];
    const char *files[2] = {"0-cloth.layers.exr", "0-cloth.layers-below.exr"};
    for (int f = 0; f < 2; f++) {
        int w, h;
        float *pixels = read_exr(test_path(dir, files[f]), 3 * n + 1, names, &w, &h);
        assert_int_equal(w, 64);
        assert_int_equal(h, 64);
        for (int i = 0; i < w * h; i++) {
            const float *p = pixels + (size_t)i * (3 * n + 1);
            assert_true(p[3 * n] >= 0.0f && p[3 * n] <= (float)n);
            for (int k = 0; k < n; k++) assert_true(p[k] >= 0.0f && p[k] <= 1.0f);
        }
        free(pixels);
    }
    cJSON_Delete(manifest);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

/* A bake folder is meant to be moved with its project: the manifest names the scene relative
 * to itself (an absolute path, or one relative to where meso ran, breaks on the move), and
 * every file it lists lies beside it. Exported, moved, read back from the new place. */
static void test_export_survives_moving_the_project(void **state) {
    (void)state;
    const char *project = test_path(test_temp_dir(), "project");
    const char *moved = test_path(test_temp_dir(), "moved/elsewhere");
    char command[4096];
    snprintf(command, sizeof command,
             "rm -rf %s %s && mkdir -p %s/scenes %s && cp %s/examples/bricks-plane.json "
             "%s/scenes/wall.json",
             project, moved, project, moved, MESO_SOURCE_DIR, project);
    assert_int_equal(system(command), 0);
    /* run from the project's folder with relative paths, as a user would */
    snprintf(command, sizeof command,
             "cd %s && %s bake scenes/wall.json -o textures/wall --technique relief --quiet",
             project, MESO_PROGRAM);
    assert_int_equal(system(command), 0);
    snprintf(command, sizeof command, "mv %s %s/", project, moved);
    assert_int_equal(system(command), 0);

    char folder[1200];
    snprintf(folder, sizeof folder, "%s/project/textures/wall", moved);
    size_t size;
    char *text = test_read_file(test_path(folder, "manifest.json"), &size);
    cJSON *manifest = cJSON_Parse(text);
    free(text);
    assert_non_null(manifest);
    const char *scene_name = cJSON_GetObjectItem(manifest, "scene")->valuestring;
    assert_string_equal(scene_name, "../../scenes/wall.json");
    meso_context *ctx = test_context(1);
    meso_scene *scene = NULL;
    if (meso_scene_load(ctx, test_path(folder, scene_name), &scene) != MESO_OK)
        fail_msg("%s", meso_context_last_error(ctx));
    meso_scene_destroy(scene);
    cJSON *object, *texture;
    int files = 0;
    cJSON_ArrayForEach(object, cJSON_GetObjectItem(manifest, "objects")) {
        cJSON_ArrayForEach(texture, cJSON_GetObjectItem(object, "textures")) {
            const char *file = cJSON_GetObjectItem(texture, "file")->valuestring;
            assert_null(strchr(file, '/'));
            assert_int_equal(access(test_path(folder, file), F_OK), 0);
            files++;
        }
    }
    assert_true(files > 0);
    cJSON_Delete(manifest);
    meso_context_destroy(ctx);
}

/* meso bake's bad input: one line, status 2, nothing written; a technique without a shader
 * too, as `meso render --backend gl` says it. */
static void test_bake_command_bad_input(void **state) {
    (void)state;
    const char *dir = test_path(test_temp_dir(), "bake-bad");
    char arguments[2048];
    const char *err = NULL;
    snprintf(arguments, sizeof arguments, "bake %s/examples/bricks-plane.json", MESO_SOURCE_DIR);
    assert_int_equal(test_run_meso(arguments, &err), 2);
    assert_non_null(strstr(err, "missing -o DIR"));
    snprintf(arguments, sizeof arguments, "bake %s/no-such-scene.json -o %s", MESO_SOURCE_DIR, dir);
    assert_int_equal(test_run_meso(arguments, &err), 2);
    snprintf(arguments, sizeof arguments,
             "bake %s/examples/bricks-plane.json -o %s --technique horizon", MESO_SOURCE_DIR, dir);
    assert_int_equal(test_run_meso(arguments, &err), 2); /* as render --backend gl */
    assert_non_null(strstr(err, "'horizon' has no GL shader"));
    assert_ptr_equal(strchr(err, '\n'), err + strlen(err) - 1);
    assert_int_not_equal(access(test_path(dir, "manifest.json"), F_OK), 0);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_exr_round_trip),
        cmocka_unit_test(test_export_vdm_scene),
        cmocka_unit_test(test_export_layers),
        cmocka_unit_test(test_export_survives_moving_the_project),
        cmocka_unit_test(test_bake_command_bad_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
