/* Materials from the mesh file: a glTF's baseColorFactor/baseColorTexture
 * and an OBJ's MTL Kd/map_Kd are read, used when the scene's material sets no colour, and
 * `meso info` says what was used and what ignored. Before, the mesh file's material was
 * dropped silently and every imported mesh was grey 0.8. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"
#include "meso/texture.h"

static const char *write_text(const char *dir, const char *name, const char *text) {
    const char *path = test_path(dir, name);
    test_write_file(path, text, strlen(text));
    return path;
}

/* A 4x2 RGB PNG whose every texel is one sRGB grey `value` (0-1). */
static void write_png(const char *path, float value) {
    meso_context *ctx = test_context(1);
    meso_image *image = NULL;
    assert_int_equal(meso_image_create(ctx, 4, 2, 3, &image), MESO_OK);
    for (int i = 0; i < 4 * 2 * 3; i++) image->pixels[i] = value;
    meso_png_desc linear = {.encoding = MESO_ENCODING_LINEAR}; /* the bytes as given */
    assert_int_equal(meso_image_save_png(ctx, image, path, &linear), MESO_OK);
    meso_image_destroy(image);
    meso_context_destroy(ctx);
}

/* One triangle with UVs; its material: baseColorFactor, baseColorTexture c.png, normalTexture
 * n.png, occlusionTexture o.png. */
static const char gltf_triangle[] =
    "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],"
    "\"nodes\":[{\"mesh\":0}],"
    "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":1},"
    "\"indices\":2,\"material\":0}]}],"
    "\"materials\":[{\"name\":\"painted\",\"pbrMetallicRoughness\":{"
    "\"baseColorFactor\":[0.25,0.5,0.75,1],\"baseColorTexture\":{\"index\":0}},"
    "\"normalTexture\":{\"index\":1},\"occlusionTexture\":{\"index\":2}}],"
    "\"textures\":[{\"source\":0},{\"source\":1},{\"source\":2}],"
    "\"images\":[{\"uri\":\"c.png\"},{\"uri\":\"n.png\"},{\"uri\":\"o.png\"}],"
    "\"buffers\":[{\"byteLength\":68,\"uri\":\"data:application/octet-stream;base64,"
    "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAAAAAAAAAAAAIA/AAAAAAAAAAAAAIA/"
    "AAABAAIAAAA=\"}"
    "],"
    "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":36},"
    "{\"buffer\":0,\"byteOffset\":36,\"byteLength\":24},"
    "{\"buffer\":0,\"byteOffset\":60,\"byteLength\":6}],"
    "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\","
    "\"min\":[0,0,0],\"max\":[1,1,0]},"
    "{\"bufferView\":1,\"componentType\":5126,\"count\":3,\"type\":\"VEC2\"},"
    "{\"bufferView\":2,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"}]}";

static const char obj_quad[] = "mtllib quad.mtl\nv -1 0 1\nv 1 0 1\nv 1 0 -1\nv -1 0 -1\n"
                               "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl brick\n"
                               "f 1/1 2/2 3/3 4/4\n";

/* The material of the mesh file `name` holding `text`, written in the test's folder. */
static meso_mesh_material load_material(const char *name, const char *text) {
    const char *path = write_text(test_temp_dir(), name, text);
    meso_context *ctx = test_context(1);
    meso_mesh *mesh = NULL;
    meso_mesh_material material;
    if (meso_mesh_load_with_material(ctx, path, &mesh, &material) != MESO_OK)
        fail_msg("%s: %s", path, meso_context_last_error(ctx));
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
    return material;
}

static void test_gltf_base_colour_and_textures_are_read(void **state) {
    (void)state;
    meso_mesh_material material = load_material("painted.gltf", gltf_triangle);
    assert_true(material.has_color);
    assert_float_equal(material.color.x, 0.25f, 1e-6f);
    assert_float_equal(material.color.y, 0.5f, 1e-6f);
    assert_float_equal(material.color.z, 0.75f, 1e-6f);
    assert_string_equal(material.color_map, "c.png");
    assert_string_equal(material.normal_map, "n.png");
    assert_non_null(strstr(material.ignored, "occlusion"));
}

static void test_obj_mtl_kd_and_map_kd_are_read_and_no_mtl_is_no_material(void **state) {
    (void)state;
    write_text(test_temp_dir(), "quad.mtl", "newmtl brick\nKd 0.6 0.3 0.1\nmap_Kd brick.png\n");
    meso_mesh_material material = load_material("quad.obj", obj_quad);
    assert_true(material.has_color);
    assert_float_equal(material.color.x, 0.6f, 1e-6f);
    assert_float_equal(material.color.z, 0.1f, 1e-6f);
    assert_string_equal(material.color_map, "brick.png");

    /* without an MTL, assimp's default material is no material */
    material = load_material("plain.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    assert_false(material.has_color);
    assert_string_equal(material.color_map, "");
    assert_string_equal(material.ignored, "");
}

static meso_scene *load_scene(meso_context *ctx, const char *dir, const char *name,
                              const char *material) {
    char text[1024];
    snprintf(text, sizeof text, "{\"objects\": [{\"shape\": {\"file\": \"painted.gltf\"}%s%s}]}",
             material ? ", \"material\": " : "", material ? material : "");
    const char *path = write_text(dir, name, text);
    meso_scene *scene = NULL;
    if (meso_scene_load(ctx, path, &scene) != MESO_OK)
        fail_msg("%s: %s", path, meso_context_last_error(ctx));
    return scene;
}

/* The scene uses the file's colour and texture when its material sets no colour, and says
 * so; a scene colour wins; what is ignored is listed. */
static void test_the_scene_uses_the_file_material_unless_it_sets_a_colour(void **state) {
    (void)state;
    const char *dir = test_temp_dir();
    write_text(dir, "painted.gltf", gltf_triangle);
    write_png(test_path(dir, "c.png"), 0.5f);
    write_png(test_path(dir, "n.png"), 0.5f);
    meso_context *ctx = test_context(1);

    meso_scene *scene = load_scene(ctx, dir, "uses-file.json", NULL);
    const meso_object *o = &scene->objects[0];
    assert_float_equal(o->material.albedo.x, 0.25f, 1e-6f);
    assert_float_equal(o->material.albedo.z, 0.75f, 1e-6f);
    assert_non_null(o->material.color_map);
    assert_int_equal(o->material.color_map->levels[0]->width, 4);
    /* loaded as a colour map: sRGB 0.5 -> linear 0.214 */
    assert_float_equal(o->material.color_map->levels[0]->pixels[0], 0.214f, 2e-3f);
    assert_non_null(strstr(o->mesh_material_note, "base colour used"));
    assert_non_null(strstr(o->mesh_material_note, "colour texture used"));
    /* the normalTexture is the normal map, linear (no sRGB decoding: 0.5 stays 0.5) */
    assert_non_null(o->material.normal_map);
    assert_float_equal(o->material.normal_map->levels[0]->pixels[0], 0.5f, 3e-3f);
    assert_false(o->material.normal_map_directx);
    assert_non_null(strstr(o->mesh_material_note, "normal texture used (OpenGL convention)"));
    assert_non_null(strstr(o->mesh_material_note, "ignored: occlusion texture"));
    meso_scene_destroy(scene);

    /* a scene normal_map wins over the file's */
    scene = load_scene(ctx, dir, "sets-normal.json",
                       "{\"normal_map\": \"c.png\", \"normal_map_convention\": \"directx\"}");
    o = &scene->objects[0];
    assert_non_null(o->material.normal_map);
    assert_true(o->material.normal_map_directx);
    assert_non_null(
        strstr(o->mesh_material_note, "normal texture not used: the scene's material sets one"));
    meso_scene_destroy(scene);

    scene = load_scene(ctx, dir, "sets-colour.json", "{\"albedo\": [1, 0, 0]}");
    o = &scene->objects[0];
    assert_float_equal(o->material.albedo.x, 1.0f, 0.0f);
    assert_float_equal(o->material.albedo.y, 0.0f, 0.0f);
    assert_null(o->material.color_map);
    assert_non_null(strstr(o->mesh_material_note, "the scene's material sets one"));
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

/* The folder `name` in the test's folder, made; its path in dir. */
static void make_subfolder(const char *name, char *dir, size_t size) {
    snprintf(dir, size, "%s/%s", test_temp_dir(), name);
    char command[1300];
    snprintf(command, sizeof command, "mkdir -p '%s'", dir);
    assert_int_equal(system(command), 0);
}

/* A texture outside the mesh's folder is not read. */
static void test_a_texture_outside_the_mesh_folder_is_not_read(void **state) {
    (void)state;
    char dir[1100];
    make_subfolder("outside", dir, sizeof dir);
    write_png(test_path(test_temp_dir(), "secret.png"), 0.5f);
    write_text(dir, "quad.mtl", "newmtl brick\nKd 0.6 0.3 0.1\nmap_Kd ../secret.png\n");
    write_text(dir, "quad.obj", obj_quad);
    const char *scene_path =
        write_text(dir, "scene.json", "{\"objects\": [{\"shape\": {\"file\": \"quad.obj\"}}]}");
    meso_context *ctx = test_context(1);
    meso_scene *scene = NULL;
    assert_int_equal(meso_scene_load(ctx, scene_path, &scene), MESO_OK);
    assert_null(scene->objects[0].material.color_map);
    assert_float_equal(scene->objects[0].material.albedo.x, 0.6f, 1e-6f);
    assert_non_null(strstr(scene->objects[0].mesh_material_note, "not beside the mesh file"));
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

/* meso info says it, for the scene and for the mesh file alone. */
static void test_meso_info_says_what_was_read_and_ignored(void **state) {
    (void)state;
    const char *dir = test_temp_dir();
    write_text(dir, "painted.gltf", gltf_triangle);
    write_png(test_path(dir, "c.png"), 0.5f);
    write_png(test_path(dir, "n.png"), 0.5f);
    char command[4096], out_path[1200];
    snprintf(out_path, sizeof out_path, "%s/info.txt", dir);
    const char *scene = write_text(dir, "info-scene.json",
                                   "{\"objects\": [{\"shape\": {\"file\": \"painted.gltf\"}}]}");
    snprintf(command, sizeof command, "%s info %s > %s", MESO_PROGRAM, scene, out_path);
    assert_int_equal(system(command), 0);
    size_t size;
    char *text = test_read_file(out_path, &size);
    if (!strstr(text, "material of the mesh file: base colour used, colour texture used, "
                      "normal texture used (OpenGL convention)"))
        fail_msg("meso info said:\n%s", text);
    free(text);
    snprintf(command, sizeof command, "%s info %s/painted.gltf > %s", MESO_PROGRAM, dir, out_path);
    assert_int_equal(system(command), 0);
    text = test_read_file(out_path, &size);
    if (!strstr(text, "base colour 0.25 0.5 0.75") || !strstr(text, "colour texture c.png") ||
        !strstr(text, "normal texture n.png") || !strstr(text, "ignored: occlusion texture"))
        fail_msg("meso info said:\n%s", text);
    /* the file alone says what the scene above says: its normal texture is used */
    if (strstr(text, "not used") ||
        !strstr(text, "normal texture n.png (used as the normal map, OpenGL convention, when the "
                      "scene's material sets none)"))
        fail_msg("meso info said:\n%s", text);
    free(text);
}

/* A normal map's tangent frame is dP/du, dP/dv (docs/scene-format.md, "Normal maps"): on a
 * mesh without UVs the file's normal texture alone had none to be oriented by, so it was
 * loaded, said "used" and changed nothing. It needs texture coordinates as a colour map does:
 * the scene projects them, and the scene and `meso info` of the file both say it is used. */
static void test_a_normal_texture_without_uvs_is_used_through_projected_ones(void **state) {
    (void)state;
    char dir[1100], command[4096];
    make_subfolder("no-uvs", dir, sizeof dir);
    char gltf[sizeof gltf_triangle];
    snprintf(gltf, sizeof gltf, "%s", gltf_triangle);
    const char *const cut[] = {",\"TEXCOORD_0\":1", ",\"baseColorTexture\":{\"index\":0}"};
    for (int i = 0; i < 2; i++) {
        char *at = strstr(gltf, cut[i]);
        assert_non_null(at);
        memmove(at, at + strlen(cut[i]), strlen(at + strlen(cut[i])) + 1);
    }
    write_text(dir, "painted.gltf", gltf);
    write_png(test_path(dir, "n.png"), 0.5f);
    meso_context *ctx = test_context(1);
    meso_scene *scene = load_scene(ctx, dir, "no-uvs.json", NULL);
    const meso_object *o = &scene->objects[0];
    assert_non_null(o->material.normal_map);
    assert_non_null(o->mesh->uvs); /* projected */
    assert_non_null(o->mesh->tangents);
    if (!strstr(o->mesh_material_note, "normal texture used (OpenGL convention)"))
        fail_msg("note: %s", o->mesh_material_note);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
    char out_path[1200];
    snprintf(out_path, sizeof out_path, "%s/info.txt", dir);
    snprintf(command, sizeof command, "%s info %s/painted.gltf > %s", MESO_PROGRAM, dir, out_path);
    assert_int_equal(system(command), 0);
    size_t size;
    char *text = test_read_file(out_path, &size);
    if (!strstr(text, "normal texture n.png (used as the normal map"))
        fail_msg("meso info said:\n%s", text);
    free(text);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gltf_base_colour_and_textures_are_read),
        cmocka_unit_test(test_obj_mtl_kd_and_map_kd_are_read_and_no_mtl_is_no_material),
        cmocka_unit_test(test_the_scene_uses_the_file_material_unless_it_sets_a_colour),
        cmocka_unit_test(test_a_texture_outside_the_mesh_folder_is_not_read),
        cmocka_unit_test(test_meso_info_says_what_was_read_and_ignored),
        cmocka_unit_test(test_a_normal_texture_without_uvs_is_used_through_projected_ones),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
