/* The meso program and relief_layers: bad technique options and bad layer bakes are bad input
 * (exit 2, one line naming the file, no output file); `meso info` reports a layer bake's
 * sizes beside the paper's; a mixed scene (height field + solid) renders with every technique
 * asked for, the CSV saying which objects were drawn with their own technique. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "test_util.h"

static const char *write_text(const char *name, const char *text) {
    const char *path = test_path(test_temp_dir(), name);
    test_write_file(path, text, strlen(text));
    return path;
}

/* A 32x32 scene: a slab solid on a plane drawn with relief_layers and `options` (JSON), and
 * optionally a second plane with a height field. */
static const char *write_scene(const char *name, const char *options, bool mixed) {
    char text[2048];
    snprintf(text, sizeof text,
             "{\"image\": {\"width\": 32, \"height\": 32},\n"
             " \"camera\": {\"eye\": [0, 1.5, 1.5], \"target\": [0, 0, 0], \"up\": [0, 1, 0],"
             " \"fov_y_deg\": 45},\n"
             " \"lights\": [{\"type\": \"directional\", \"direction\": [0.3, 1, 0.2],"
             " \"color\": [1, 1, 1]}],\n"
             " \"objects\": [{\"name\": \"slab\", \"shape\": \"plane\", \"size\": 1,"
             " \"mesostructure\": {\"solid\": {\"procedural\": \"slab\"}, \"depth\": 0.05},"
             " \"technique\": \"relief_layers\", \"technique_options\": %s}%s]}\n",
             options,
             mixed ? ", {\"name\": \"bricks\", \"shape\": \"plane\", \"size\": 1,"
                     " \"transform\": {\"translate\": [0, -0.3, 0]},"
                     " \"mesostructure\": {\"height_map\": {\"procedural\": \"bricks\","
                     " \"resolution\": 64}, \"depth\": 0.05}, \"technique\": \"relief\"}"
                   : "");
    return write_text(name, text);
}

static bool exists(const char *path) {
    struct stat st;
    return stat(path, &st) == 0;
}

/* Status 2, exactly one stderr line "meso: ..." containing `needle`, no `output` written. */
static void expect_bad_input(const char *arguments, const char *needle, const char *output) {
    const char *err = NULL;
    int status = test_run_meso(arguments, &err);
    if (status != 2 || strncmp(err, "meso: ", 6) != 0 || !strstr(err, needle))
        fail_msg("meso %s\n  status %d (want 2), stderr: %s  (want one line naming '%s')",
                 arguments, status, err, needle);
    size_t length = strlen(err);
    assert_null(memchr(err, '\n', length - 1));
    if (output) assert_false(exists(output));
}

static void test_bad_technique_options_are_bad_input(void **state) {
    (void)state;
    setenv("MESO_CACHE_DIR", "off", 1);
    const char *out = test_path(test_temp_dir(), "never.png");
    char args[4096];
    const char *scene = write_scene("layers_six.json", "{\"layers\": 6}", false);
    snprintf(args, sizeof args, "render %s -o %s", scene, out);
    expect_bad_input(args, "layers", out);
    scene = write_scene("layers_unknown.json", "{\"linear_step\": 8}", false);
    snprintf(args, sizeof args, "render %s -o %s", scene, out);
    expect_bad_input(args, "linear_step", out);
    scene = write_scene("layers_size.json", "{\"size\": 1000000}", false);
    snprintf(args, sizeof args, "render %s -o %s", scene, out);
    expect_bad_input(args, "size", out);
    unsetenv("MESO_CACHE_DIR");
}

static void test_open_tile_mesh_is_bad_input_naming_it(void **state) {
    (void)state;
    /* one triangle: open */
    write_text("open-tile.obj", "v 0.2 0.2 0.5\nv 0.8 0.2 0.5\nv 0.5 0.8 0.5\nf 1 2 3\n");
    const char *scene = write_text(
        "open-tile.json",
        "{\"image\": {\"width\": 32, \"height\": 32},\n"
        " \"camera\": {\"eye\": [0, 1.5, 1.5], \"target\": [0, 0, 0], \"up\": [0, 1, 0],"
        " \"fov_y_deg\": 45},\n"
        " \"objects\": [{\"shape\": \"plane\", \"mesostructure\": {\"solid\": \"open-tile.obj\","
        " \"depth\": 0.05}, \"technique\": \"relief_layers\"}]}\n");
    const char *out = test_path(test_temp_dir(), "open-tile.png");
    char args[4096];
    snprintf(args, sizeof args, "render %s -o %s", scene, out);
    expect_bad_input(args, "open-tile.obj: the tile mesh is not closed", out);
    /* a tile mesh that is not there */
    scene = write_text(
        "missing-tile.json",
        "{\"objects\": [{\"shape\": \"plane\", \"mesostructure\": {\"solid\": \"none.obj\","
        " \"depth\": 0.05}, \"technique\": \"relief_layers\"}]}\n");
    snprintf(args, sizeof args, "render %s -o %s", scene, out);
    expect_bad_input(args, "none.obj", out);
}

static void test_bad_impostors_are_bad_input(void **state) {
    (void)state;
    const char *out = test_path(test_temp_dir(), "impostor.png");
    char args[4096];
    const char *scene = write_text(
        "impostor-missing.json",
        "{\"objects\": [{\"shape\": \"plane\", \"mesostructure\": {\"solid\": {\"impostor\":"
        " \"no-such-model.obj\"}, \"depth\": 1}, \"technique\": \"relief_layers\"}]}\n");
    snprintf(args, sizeof args, "render %s -o %s", scene, out);
    expect_bad_input(args, "no-such-model.obj", out);
    scene = write_text(
        "impostor-resolution.json",
        "{\"objects\": [{\"shape\": \"plane\", \"mesostructure\": {\"solid\": {\"impostor\":"
        " \"teapot\", \"resolution\": 100000}, \"depth\": 1}, \"technique\": "
        "\"relief_layers\"}]}\n");
    snprintf(args, sizeof args, "render %s -o %s", scene, out);
    expect_bad_input(args, "resolution", out);
    scene = write_text(
        "impostor-key.json",
        "{\"objects\": [{\"shape\": \"plane\", \"mesostructure\": {\"solid\": {\"impostor\":"
        " \"teapot\", \"axis\": 1}, \"depth\": 1}, \"technique\": \"relief_layers\"}]}\n");
    snprintf(args, sizeof args, "render %s -o %s", scene, out);
    expect_bad_input(args, "axis", out);
}

static void test_bad_layer_bakes_are_bad_input_and_good_ones_described(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_heightfield *hf = NULL;
    assert_int_equal(meso_heightfield_create_constant(ctx, 16, 16, 0.25f, &hf), MESO_OK);
    meso_layers *map = NULL;
    meso_layers_desc desc = {.heightfield = hf};
    assert_int_equal(meso_layers_bake(ctx, &desc, &map), MESO_OK);
    const char *good = test_path(test_temp_dir(), "good_layers.mesobake");
    assert_int_equal(meso_layers_save(ctx, map, good), MESO_OK);
    char args[4096];
    const char *out = NULL;
    snprintf(args, sizeof args, "info %s", good);
    assert_int_equal(test_run_meso(args, &out), 0);
    /* a corrupted copy: one byte flipped */
    FILE *f = fopen(good, "rb");
    assert_non_null(f);
    unsigned char data[65536];
    size_t size = fread(data, 1, sizeof data, f);
    fclose(f);
    data[size - 20] ^= 0xff;
    const char *bad = test_path(test_temp_dir(), "bad_layers.mesobake");
    test_write_file(bad, data, size);
    snprintf(args, sizeof args, "info %s", bad);
    expect_bad_input(args, "bad_layers.mesobake", NULL);
    /* a valid container with an inconsistent map (a depth above 1) */
    map->depth[0] = 0.75f;
    map->depth[1] = 0.5f; /* unused slot that is not 1.0 */
    const char *odd = test_path(test_temp_dir(), "odd_layers.mesobake");
    assert_int_equal(meso_layers_save(ctx, map, odd), MESO_OK);
    snprintf(args, sizeof args, "info %s", odd);
    expect_bad_input(args, "odd_layers.mesobake", NULL);
    meso_layers_destroy(map);
    meso_heightfield_destroy(hf);
    meso_context_destroy(ctx);
}

static void test_info_reports_sizes_beside_the_paper(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_heightfield *hf = NULL;
    assert_int_equal(meso_heightfield_create_constant(ctx, 16, 16, 0.25f, &hf), MESO_OK);
    meso_layers *map = NULL;
    meso_layers_desc desc = {.heightfield = hf};
    assert_int_equal(meso_layers_bake(ctx, &desc, &map), MESO_OK);
    const char *path = test_path(test_temp_dir(), "info_layers.mesobake");
    assert_int_equal(meso_layers_save(ctx, map, path), MESO_OK);
    char command[4096];
    const char *listing = test_path(test_temp_dir(), "info_layers.txt");
    snprintf(command, sizeof command, "%s info %s > %s 2>&1", MESO_PROGRAM, path, listing);
    assert_int_equal(system(command), 0);
    FILE *f = fopen(listing, "r");
    assert_non_null(f);
    char text[8192];
    size_t n = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[n] = 0;
    assert_non_null(strstr(text, "relief_layers: 16 x 16 texels, 4 layers (8-bit)"));
    assert_non_null(strstr(text, "768.0 KB"));
    meso_layers_destroy(map);
    meso_heightfield_destroy(hf);
    meso_context_destroy(ctx);
}

static void test_mixed_scene_renders_with_every_technique_asked(void **state) {
    (void)state;
    setenv("MESO_CACHE_DIR", "off", 1);
    const char *scene = write_scene("mixed.json", "{}", true);
    const char *dir = test_path(test_temp_dir(), "mixed_out");
    char args[4096];
    snprintf(args, sizeof args, "render %s --techniques bump,relief,relief_layers -o %s --frames 1",
             scene, dir);
    const char *err = NULL;
    assert_int_equal(test_run_meso(args, &err), 0);
    char csv_path[4096];
    snprintf(csv_path, sizeof csv_path, "%s/results.csv", dir);
    FILE *f = fopen(csv_path, "r");
    assert_non_null(f);
    char text[8192];
    size_t n = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[n] = 0;
    /* bump and relief draw the bricks and leave the slab to relief_layers; relief_layers draws
     * both itself */
    assert_non_null(strstr(text, ",bump,ok,"));
    assert_non_null(strstr(text, ",relief,ok,"));
    assert_non_null(strstr(text, "mixed: slab (solid) with relief_layers"));
    assert_non_null(strstr(text, ",relief_layers,ok,"));
    char *line = strstr(text, ",relief_layers,ok,");
    char *end = strchr(line, '\n');
    if (end) *end = 0;
    assert_null(strstr(line, "mixed:"));
    unsetenv("MESO_CACHE_DIR");
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bad_technique_options_are_bad_input),
        cmocka_unit_test(test_open_tile_mesh_is_bad_input_naming_it),
        cmocka_unit_test(test_bad_impostors_are_bad_input),
        cmocka_unit_test(test_bad_layer_bakes_are_bad_input_and_good_ones_described),
        cmocka_unit_test(test_info_reports_sizes_beside_the_paper),
        cmocka_unit_test(test_mixed_scene_renders_with_every_technique_asked),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
