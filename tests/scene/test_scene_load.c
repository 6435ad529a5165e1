/* Scene files that load: the docs/design.md example, defaults, extensions, transforms, examples/.
 */
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"
#include "meso/texture.h"

/* Write a small grey height map and an sRGB colour map beside a scene in the temp folder. */
static void write_maps(meso_context *ctx, const char *dir) {
    meso_image *grey = NULL, *rgb = NULL;
    assert_int_equal(meso_image_create(ctx, 16, 8, 1, &grey), MESO_OK);
    for (int k = 0; k < 16 * 8; k++) grey->pixels[k] = (float)(k % 16) / 15.0f;
    assert_int_equal(meso_image_save_png(ctx, grey, test_path(dir, "bricks.png"),
                                         &(meso_png_desc){.encoding = MESO_ENCODING_LINEAR}),
                     MESO_OK);
    assert_int_equal(meso_image_create(ctx, 8, 8, 3, &rgb), MESO_OK);
    for (int k = 0; k < 8 * 8 * 3; k++) rgb->pixels[k] = 0.5f; /* stored as 128/255 */
    assert_int_equal(meso_image_save_png(ctx, rgb, test_path(dir, "bricks_color.png"),
                                         &(meso_png_desc){.encoding = MESO_ENCODING_LINEAR}),
                     MESO_OK);
    meso_image_destroy(grey);
    meso_image_destroy(rgb);
}

/* docs/design.md's example, line breaks moved to fit 100 columns. */
static const char design_example[] =
    "{\n"
    "  \"image\":   { \"width\": 512, \"height\": 512, \"background\": [0, 0, 0],\n"
    "               \"encoding\": \"srgb\" },\n"
    "  \"camera\":  { \"eye\": [0, 1.2, 2.2], \"target\": [0, 0, 0], \"up\": [0, 1, 0],\n"
    "               \"fov_y_deg\": 40 },\n"
    "  \"ambient\": [0.1, 0.1, 0.1],\n"
    "  \"lights\":  [ { \"type\": \"directional\", \"direction\": [0.5, 0.7, 0.3],\n"
    "                 \"color\": [1, 1, 1] },\n"
    "               { \"type\": \"point\", \"position\": [2, 3, 1], \"color\": [1, 1, 1] } ],\n"
    "  \"objects\": [ {\n"
    "      \"shape\": \"plane\", \"size\": 2,\n"
    "      \"transform\": { \"translate\": [0, 0, 0], \"rotate_deg\": [0, 0, 0], \"scale\": 1 },\n"
    "      \"uv_scale\": [1, 1],\n"
    "      \"material\": { \"albedo\": [0.8, 0.8, 0.8], \"color_map\": \"bricks_color.png\",\n"
    "                    \"specular\": [0, 0, 0], \"shininess\": 32 },\n"
    "      \"mesostructure\": { \"height_map\": \"bricks.png\", \"depth\": 0.1 },\n"
    "      \"technique\": \"relief\"\n"
    "  } ]\n"
    "}\n";

static void assert_vec3(meso_vec3 a, float x, float y, float z) {
    assert_float_equal(a.x, x, 1e-5);
    assert_float_equal(a.y, y, 1e-5);
    assert_float_equal(a.z, z, 1e-5);
}

static void test_design_example_loads_with_its_values(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    const char *dir = test_temp_dir();
    write_maps(ctx, dir);
    const char *path = test_path(dir, "design.json");
    test_write_file(path, design_example, strlen(design_example));
    meso_scene *scene = NULL;
    assert_int_equal(meso_scene_load(ctx, path, &scene), MESO_OK);
    assert_string_equal(scene->path, path);
    assert_int_equal(scene->width, 512);
    assert_int_equal(scene->height, 512);
    assert_int_equal(scene->encoding, MESO_ENCODING_SRGB);
    assert_vec3(scene->background, 0, 0, 0);
    assert_vec3(scene->camera.eye, 0, 1.2f, 2.2f);
    assert_vec3(scene->camera.up, 0, 1, 0);
    assert_float_equal(scene->camera.fov_y_deg, 40.0f, 1e-6);
    assert_vec3(scene->ambient, 0.1f, 0.1f, 0.1f);
    assert_int_equal(scene->num_lights, 2);
    assert_int_equal(scene->lights[0].type, MESO_LIGHT_DIRECTIONAL);
    float len = sqrtf(0.25f + 0.49f + 0.09f);
    assert_vec3(scene->lights[0].direction, 0.5f / len, 0.7f / len, 0.3f / len);
    assert_int_equal(scene->lights[1].type, MESO_LIGHT_POINT);
    assert_vec3(scene->lights[1].position, 2, 3, 1);
    assert_vec3(scene->lights[1].color, 1, 1, 1);

    assert_int_equal(scene->num_objects, 1);
    const meso_object *o = &scene->objects[0];
    assert_string_equal(o->name, "objects[0]");
    assert_string_equal(o->technique, "relief");
    assert_int_equal(o->num_options, 0);
    assert_vec3(o->material.albedo, 0.8f, 0.8f, 0.8f);
    assert_float_equal(o->material.shininess, 32.0f, 0.0);
    assert_non_null(o->material.color_map);
    /* sRGB 128/255 -> linear 0.2158 */
    meso_vec4 c = meso_texture_sample(o->material.color_map, (meso_vec2){0.5f, 0.5f}, 0.0f,
                                      MESO_FILTER_NEAREST);
    assert_float_equal(c.x, meso_srgb_to_linear(128.0f / 255.0f), 1e-4);
    assert_true(o->material.color_map->num_levels > 1);
    assert_int_equal(o->mesostructure.kind, MESO_MESOSTRUCTURE_HEIGHT_FIELD);
    assert_float_equal(o->mesostructure.depth, 0.1f, 1e-7);
    assert_int_equal(o->mesostructure.wrap, MESO_WRAP_REPEAT);
    assert_string_equal(o->mesostructure.source, "bricks.png");
    assert_int_equal(o->mesostructure.height_field->width, 16);
    assert_int_equal(o->mesostructure.height_field->height, 8);
    assert_null(o->mesostructure.solid);
    const meso_mesh *mesh = o->mesh;
    assert_non_null(mesh);
    assert_non_null(mesh->uvs);
    assert_non_null(mesh->tangents);
    assert_non_null(mesh->bitangents);
    assert_non_null(mesh->curvature_max);
    assert_non_null(mesh->quadrics);
    meso_vec3 lo, hi;
    meso_mesh_bounds(mesh, &lo, &hi);
    assert_vec3(lo, -1, 0, -1);
    assert_vec3(hi, 1, 0, 1);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

static meso_scene *parse_ok(meso_context *ctx, const char *json) {
    meso_scene *scene = NULL;
    meso_result r = meso_scene_parse(ctx, json, "scene.json", test_temp_dir(), &scene);
    if (r != MESO_OK) fail_msg("%s", meso_context_last_error(ctx));
    return scene;
}

static void test_absent_keys_take_the_documented_defaults(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_scene *scene = parse_ok(ctx, "{\"objects\": [{\"shape\": \"sphere\"}]}");
    assert_string_equal(scene->path, "scene.json");
    assert_int_equal(scene->width, 512);
    assert_int_equal(scene->height, 512);
    assert_vec3(scene->background, 0, 0, 0);
    assert_int_equal(scene->encoding, MESO_ENCODING_SRGB);
    assert_vec3(scene->camera.eye, 0, 1.2f, 2.2f);
    assert_vec3(scene->camera.target, 0, 0, 0);
    assert_float_equal(scene->camera.fov_y_deg, 40.0f, 0.0);
    assert_vec3(scene->ambient, 0.1f, 0.1f, 0.1f);
    assert_int_equal(scene->num_lights, 0);
    const meso_object *o = &scene->objects[0];
    assert_string_equal(o->technique, "flat");
    assert_vec3(o->material.albedo, 0.8f, 0.8f, 0.8f);
    assert_vec3(o->material.specular, 0, 0, 0);
    assert_float_equal(o->material.shininess, 32.0f, 0.0);
    assert_null(o->material.color_map);
    assert_int_equal(o->mesostructure.kind, MESO_MESOSTRUCTURE_NONE);
    assert_null(o->mesostructure.height_field);
    meso_vec3 lo, hi;
    meso_mesh_bounds(o->mesh, &lo, &hi);
    assert_float_equal(hi.x, 1.0f, 1e-3); /* default radius 1 */
    /* A light's colour defaults to white; a shape defaults to the plane. */
    meso_scene_destroy(scene);
    scene = parse_ok(ctx, "{\"lights\": [{\"type\": \"point\", \"position\": [0, 1, 0]}],"
                          " \"objects\": [{}]}");
    assert_vec3(scene->lights[0].color, 1, 1, 1);
    meso_mesh_bounds(scene->objects[0].mesh, &lo, &hi);
    assert_vec3(lo, -1, 0, -1);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

static void test_procedural_sources_names_and_options(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_scene *scene = parse_ok(
        ctx,
        "{\"image\": {\"width\": 64, \"height\": 32, \"encoding\": \"linear\","
        "             \"background\": [0.2, 0.3, 0.4]},"
        " \"objects\": ["
        "  {\"name\": \"floor\", \"technique\": \"relief\","
        "   \"technique_options\": {\"linear_steps\": 16, \"shadows\": true, \"exact\": false},"
        "   \"material\": {\"color_map\": \"mesostructure\", \"specular\": [0.1, 0.1, 0.1],"
        "                  \"shininess\": 8},"
        "   \"mesostructure\": {\"height_map\": {\"procedural\": \"bricks\", \"resolution\": 64,"
        "                       \"rows\": 2, \"columns\": 2, \"gap\": 0.1, \"bevel\": 0.05,"
        "                       \"roughness\": 0.2, \"seed\": 9}, \"depth\": 0.05,"
        "                       \"wrap\": \"clamp\"}},"
        "  {\"shape\": \"torus\", \"size\": 1, \"minor_radius\": 0.3, \"segments\": 24,"
        "   \"mesostructure\": {\"solid\": {\"procedural\": \"chain\", \"count\": 4,"
        "                                   \"thickness\": 0.1}, \"depth\": 0}}]}");
    assert_int_equal(scene->width, 64);
    assert_int_equal(scene->height, 32);
    assert_int_equal(scene->encoding, MESO_ENCODING_LINEAR);
    assert_vec3(scene->background, 0.2f, 0.3f, 0.4f);
    assert_int_equal(scene->num_objects, 2);
    const meso_object *floor_object = &scene->objects[0];
    assert_string_equal(floor_object->name, "floor");
    assert_int_equal(floor_object->num_options, 3);
    /* the flat form: technique "" (the object's own) */
    const char *names[] = {"linear_steps", "shadows", "exact"};
    const double values[] = {16.0, 1.0, 0.0};
    for (int i = 0; i < 3; i++) {
        assert_string_equal(floor_object->options[i].technique, "");
        assert_string_equal(floor_object->options[i].name, names[i]);
        assert_float_equal(floor_object->options[i].value, values[i], 0.0);
    }
    const meso_mesostructure *m = &floor_object->mesostructure;
    assert_int_equal(m->kind, MESO_MESOSTRUCTURE_HEIGHT_FIELD);
    assert_string_equal(m->source, "bricks");
    assert_int_equal(m->height_field->width, 64);
    assert_int_equal(m->wrap, MESO_WRAP_CLAMP);
    assert_int_equal(m->height_field->wrap, MESO_WRAP_CLAMP);
    assert_non_null(floor_object->material.color_map);
    assert_int_equal(floor_object->material.color_map->wrap, MESO_WRAP_CLAMP);
    assert_int_equal(floor_object->material.color_map->levels[0]->width, 64);
    assert_float_equal(floor_object->material.shininess, 8.0f, 0.0);
    /* The same procedural parameters through the library give the same texels. */
    meso_heightfield *direct = NULL;
    meso_heightfield_desc desc = {.kind = MESO_HEIGHTFIELD_BRICKS,
                                  .resolution = 64,
                                  .rows = 2,
                                  .columns = 2,
                                  .gap = 0.1f,
                                  .bevel = 0.05f,
                                  .roughness = 0.2f,
                                  .seed = 9,
                                  .wrap = MESO_WRAP_CLAMP};
    assert_int_equal(meso_heightfield_create_procedural(ctx, &desc, &direct, NULL), MESO_OK);
    assert_true(direct->hash == m->height_field->hash);
    meso_heightfield_destroy(direct);

    const meso_object *torus = &scene->objects[1];
    assert_string_equal(torus->name, "objects[1]");
    assert_int_equal(torus->mesostructure.kind, MESO_MESOSTRUCTURE_SOLID);
    assert_float_equal(torus->mesostructure.depth, 0.0f, 0.0);
    assert_string_equal(torus->mesostructure.source, "chain");
    meso_solid_desc sd = meso_solid_get_desc(torus->mesostructure.solid);
    assert_int_equal(sd.kind, MESO_SOLID_CHAIN);
    assert_int_equal(sd.count, 4);
    assert_float_equal(sd.thickness, 0.1f, 1e-7);
    assert_non_null(torus->mesh->tangents);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

static void test_transform_scales_rotates_x_then_y_then_z_and_translates(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    meso_scene *scene = parse_ok(
        ctx,
        "{\"objects\": [{\"shape\": \"plane\", \"size\": 2, \"uv_scale\": [2, 3],"
        " \"transform\": {\"translate\": [1, 2, 3], \"rotate_deg\": [90, 0, 0], \"scale\": 2}},"
        " {\"shape\": \"plane\", \"transform\": {\"rotate_deg\": [90, 90, 0]}}]}");
    const meso_mesh *mesh = scene->objects[0].mesh;
    meso_vec3 lo, hi;
    meso_mesh_bounds(mesh, &lo, &hi);
    /* The plane y = 0 (side 4 after scaling) turned into z = 0 by +90 deg about X, moved. */
    assert_vec3(lo, -1, 0, 3);
    assert_vec3(hi, 3, 4, 3);
    assert_vec3(mesh->normals[0], 0, 0, 1);
    float max_u = 0, max_v = 0;
    for (size_t i = 0; i < mesh->num_vertices; i++) {
        max_u = fmaxf(max_u, mesh->uvs[i].x);
        max_v = fmaxf(max_v, mesh->uvs[i].y);
    }
    assert_float_equal(max_u, 2.0f, 1e-5);
    assert_float_equal(max_v, 3.0f, 1e-5);
    /* X first: +y -> +z, then Y: +z -> +x. (Y first would leave +z.) */
    assert_vec3(scene->objects[1].mesh->normals[0], 1, 0, 0);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

static void test_parse_resolves_paths_against_base_dir(void **state) {
    (void)state;
    meso_context *ctx = test_context(1);
    const char *dir = test_temp_dir();
    write_maps(ctx, dir);
    const char *json = "{\"objects\": [{\"mesostructure\": {\"height_map\": \"bricks.png\","
                       " \"depth\": 0.02}, \"material\": {\"color_map\": \"bricks_color.png\"}}]}";
    meso_scene *scene = NULL;
    assert_int_equal(meso_scene_parse(ctx, json, "embedded", dir, &scene), MESO_OK);
    assert_int_equal(scene->objects[0].mesostructure.height_field->width, 16);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

/* Every scene in examples/ loads (the program embeds them and parses them the same way). */
static void test_every_example_scene_loads(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    char dir[1024];
    snprintf(dir, sizeof(dir), "%s/examples", MESO_SOURCE_DIR);
    DIR *d = opendir(dir);
    assert_non_null(d);
    int count = 0;
    for (struct dirent *e; (e = readdir(d));) {
        size_t n = strlen(e->d_name);
        if (n < 5 || strcmp(e->d_name + n - 5, ".json") != 0) continue;
        meso_scene *scene = NULL;
        const char *path = test_path(dir, e->d_name);
        if (meso_scene_load(ctx, path, &scene) != MESO_OK)
            fail_msg("%s", meso_context_last_error(ctx));
        assert_true(scene->num_objects > 0);
        meso_scene_destroy(scene);
        count++;
    }
    closedir(d);
    assert_true(count >= 4);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_design_example_loads_with_its_values),
        cmocka_unit_test(test_absent_keys_take_the_documented_defaults),
        cmocka_unit_test(test_procedural_sources_names_and_options),
        cmocka_unit_test(test_transform_scales_rotates_x_then_y_then_z_and_translates),
        cmocka_unit_test(test_parse_resolves_paths_against_base_dir),
        cmocka_unit_test(test_every_example_scene_loads),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
