/* meso_scene_create: images and tile meshes given in memory stand in for the files a scene
 * names, and make the same scene as the files. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "test_util.h"
#include "meso/texture.h"

/* A 12 x 8 grey map with no symmetry, saved as a PNG in `dir` and read back: the resource
 * holds the values the PNG loads as (the contract: a resource's image is what a file gives). */
static meso_image *make_heights(meso_context *ctx, const char *dir) {
    meso_image *image = NULL, *loaded = NULL;
    assert_int_equal(meso_image_create(ctx, 12, 8, 1, &image), MESO_OK);
    for (int k = 0; k < 12 * 8; k++) image->pixels[k] = (float)((k * 37) % 255) / 255.0f;
    assert_int_equal(meso_image_save_png(ctx, image, test_path(dir, "heights.png"),
                                         &(meso_png_desc){.encoding = MESO_ENCODING_LINEAR}),
                     MESO_OK);
    assert_int_equal(meso_image_load_png(ctx, test_path(dir, "heights.png"), &loaded), MESO_OK);
    meso_image_destroy(image);
    return loaded;
}

static const char *scene_text(char *out, size_t size, const char *height_map,
                              const char *color_map) {
    snprintf(out, size,
             "{\"objects\": [{\"shape\": \"plane\", \"technique\": \"relief\","
             " \"material\": {\"color_map\": \"%s\"},"
             " \"mesostructure\": {\"height_map\": \"%s\", \"depth\": 0.1, \"wrap\": \"clamp\"}}]}",
             color_map, height_map);
    return out;
}

static void test_scene_resource_images_make_the_scene_of_their_files(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    const char *dir = test_temp_dir();
    meso_image *heights = make_heights(ctx, dir);
    char text[512];
    meso_scene *from_files = NULL, *from_memory = NULL;
    const meso_scene_desc files = {
        .json = scene_text(text, sizeof text, "heights.png", "heights.png"), .base_dir = dir};
    assert_int_equal(meso_scene_create(ctx, &files, &from_files), MESO_OK);

    const meso_scene_resource resources[] = {{.name = "<heights>", .image = heights}};
    const meso_scene_desc memory = {.json = scene_text(text, sizeof text, "<heights>", "<heights>"),
                                    .resources = resources,
                                    .num_resources = 1};
    assert_int_equal(meso_scene_create(ctx, &memory, &from_memory), MESO_OK);

    const meso_heightfield *a = from_files->objects[0].mesostructure.height_field;
    const meso_heightfield *b = from_memory->objects[0].mesostructure.height_field;
    assert_int_equal(b->width, 12);
    assert_int_equal(b->height, 8);
    assert_int_equal(b->wrap, MESO_WRAP_CLAMP);
    assert_memory_equal(a->heights, b->heights, 12 * 8 * sizeof(float));
    assert_true(a->hash == b->hash); /* the same bakes from the cache */
    /* the colour map decoded from sRGB alike */
    const meso_image *ca = from_files->objects[0].material.color_map->levels[0];
    const meso_image *cb = from_memory->objects[0].material.color_map->levels[0];
    assert_memory_equal(ca->pixels, cb->pixels, 12 * 8 * 4 * sizeof(float));
    assert_string_equal(from_memory->objects[0].mesostructure.source, "<heights>");

    meso_scene_destroy(from_files);
    meso_scene_destroy(from_memory);
    meso_image_destroy(heights);
    meso_context_destroy(ctx);
}

static void test_scene_resource_of_the_wrong_kind_names_the_key(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    const meso_vec3 positions[3] = {{0, 0, 0.5f}, {1, 0, 0.5f}, {0, 1, 0.5f}};
    const uint32_t indices[3] = {0, 1, 2};
    const meso_scene_resource resources[] = {{.name = "tile",
                                              .positions = positions,
                                              .num_vertices = 3,
                                              .indices = indices,
                                              .num_triangles = 1}};
    char text[512];
    meso_scene_desc desc = {.json = scene_text(text, sizeof text, "tile", "none.png"),
                            .name = "arrays",
                            .resources = resources,
                            .num_resources = 1};
    meso_scene *scene = NULL;
    assert_int_equal(meso_scene_create(ctx, &desc, &scene), MESO_ERROR_FORMAT);
    assert_null(scene);
    assert_string_equal(meso_context_last_error(ctx),
                        "arrays: objects[0].mesostructure.height_map: 'tile' is not an image");

    /* a tile mesh resource reaches the solid's checks, which name it: one triangle is open */
    desc.json = "{\"objects\": [{\"shape\": \"plane\", \"technique\": \"relief_layers\","
                " \"mesostructure\": {\"solid\": \"tile\", \"depth\": 0.1}}]}";
    assert_int_equal(meso_scene_create(ctx, &desc, &scene), MESO_ERROR_FORMAT);
    assert_null(scene);
    assert_non_null(strstr(meso_context_last_error(ctx), "tile"));

    /* no text, or resources missing */
    assert_int_equal(meso_scene_create(ctx, &(meso_scene_desc){0}, &scene),
                     MESO_ERROR_INVALID_ARGUMENT);
    assert_string_equal(meso_context_last_error(ctx), "scene: no scene text");
    assert_int_equal(
        meso_scene_create(ctx, &(meso_scene_desc){.json = "{}", .num_resources = 2}, &scene),
        MESO_ERROR_INVALID_ARGUMENT);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_scene_resource_images_make_the_scene_of_their_files),
        cmocka_unit_test(test_scene_resource_of_the_wrong_kind_names_the_key),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
