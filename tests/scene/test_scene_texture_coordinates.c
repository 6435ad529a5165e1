/* An object's texture coordinates: the mesh's own, "uv_projection" when asked, the box
 * projection with a note for a mesh that has none or only degenerate ones, and the errors of
 * the projection's keys (docs/scene-format.md, "uv_projection"). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"

/* A closed tetrahedron without "vt", and one whose every corner uses one "vt" (WusonOBJ.obj). */
static const char tetrahedron[] = "v 1 1 1\nv -1 -1 1\nv -1 1 -1\nv 1 -1 -1\n"
                                  "f 1 2 4\nf 1 3 2\nf 1 4 3\nf 2 3 4\n";
static const char tetrahedron_one_vt[] = "v 1 1 1\nv -1 -1 1\nv -1 1 -1\nv 1 -1 -1\nvt 0.5 0.5\n"
                                         "f 1/1 2/1 4/1\nf 1/1 3/1 2/1\nf 1/1 4/1 3/1\n"
                                         "f 2/1 3/1 4/1\n";

static meso_result parse(meso_context *ctx, const char *obj_text, const char *object_keys,
                         meso_scene **out_scene) {
    const char *dir = test_temp_dir();
    const char *path = test_path(dir, "model.obj");
    test_write_file(path, obj_text, strlen(obj_text));
    char json[2048];
    snprintf(json, sizeof json,
             "{\"objects\": [{\"shape\": {\"file\": \"model.obj\"}, %s\"mesostructure\": "
             "{\"height_map\": {\"procedural\": \"bumps\", \"resolution\": 16}, \"depth\": "
             "0.05}, \"technique\": \"relief\"}]}",
             object_keys);
    *out_scene = NULL;
    return meso_scene_parse(ctx, json, "scene.json", dir, out_scene);
}

static void test_a_mesh_without_uvs_gets_the_box_projection_with_a_note(void **state) {
    meso_context *ctx = test_context(1);
    meso_scene *scene = NULL;
    assert_int_equal(parse(ctx, tetrahedron, "", &scene), MESO_OK);
    const meso_object *o = &scene->objects[0];
    assert_non_null(o->mesh->uvs);
    assert_non_null(o->mesh->tangents);
    /* The face normals lie on the diagonals, so the axes tie and x (the first) wins: two faces
     * in the +x chart, two in the -x chart, each pair sharing its edge's vertices: 8. */
    assert_int_equal(o->mesh->num_vertices, 8);
    size_t degenerate = 1;
    double area = 1.0;
    meso_mesh_degenerate_uvs(o->mesh, &degenerate, &area);
    assert_int_equal(degenerate, 0);
    /* The default tile: a quarter of the largest side (2). */
    assert_string_equal(o->texture_coordinates,
                        "box projection, 0.5 world units a tile (the file has none)");
    const char *note = test_last_warning();
    if (!strstr(note, "scene.json: objects[0]: model.obj: the file has none; using "
                      "\"uv_projection\": \"box\", 0.5 world units a tile"))
        fail_msg("warning: %s", note);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

static void test_degenerate_uvs_are_replaced_the_same_way(void **state) {
    meso_context *ctx = test_context(1);
    meso_scene *scene = NULL;
    assert_int_equal(parse(ctx, tetrahedron_one_vt, "", &scene), MESO_OK);
    const meso_object *o = &scene->objects[0];
    assert_string_equal(o->texture_coordinates, "box projection, 0.5 world units a tile (the "
                                                "file's are degenerate on 4 of 4 triangles)");
    size_t degenerate = 1;
    double area = 1.0;
    meso_mesh_degenerate_uvs(o->mesh, &degenerate, &area);
    assert_int_equal(degenerate, 0);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

static void test_an_asked_projection_scales_with_the_transform(void **state) {
    meso_context *ctx = test_context(1);
    meso_scene *scene = NULL;
    assert_int_equal(parse(ctx, tetrahedron,
                           "\"uv_projection\": \"spherical\", \"uv_projection_scale\": 0.4, "
                           "\"uv_projection_axis\": \"z\", \"transform\": {\"scale\": 2}, ",
                           &scene),
                     MESO_OK);
    const meso_object *o = &scene->objects[0];
    assert_string_equal(o->texture_coordinates,
                        "spherical projection along z, 0.4 world units a tile (asked for)");
    meso_scene_destroy(scene);
    /* World units: the same tile on a mesh twice the size covers the same world length. */
    assert_int_equal(parse(ctx, tetrahedron,
                           "\"uv_projection\": \"box\", \"uv_projection_scale\": 0.25, "
                           "\"transform\": {\"scale\": 3}, ",
                           &scene),
                     MESO_OK);
    assert_true(fabsf(meso_mesh_tile_length(scene->objects[0].mesh) - 0.25f) < 0.25f * 0.8f);
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

static void test_bad_projection_keys_are_refused_naming_them(void **state) {
    static const struct {
        const char *keys, *message;
    } cases[] = {
        {"\"uv_projection\": \"triplanar\", ",
         "objects[0].uv_projection: must be \"box\", \"cylindrical\", \"spherical\" or "
         "\"planar\", not \"triplanar\""},
        {"\"uv_projection_scale\": 2, ",
         "objects[0].uv_projection_scale: applies with \"uv_projection\" only"},
        {"\"uv_projection\": \"box\", \"uv_projection_axis\": \"x\", ",
         "objects[0].uv_projection_axis: does not apply to \"box\""},
        {"\"uv_projection\": \"planar\", \"uv_projection_axis\": \"w\", ",
         "objects[0].uv_projection_axis: must be \"x\", \"y\" or \"z\", not \"w\""},
        {"\"uv_projection\": \"planar\", \"uv_projection_scale\": -1, ",
         "objects[0].uv_projection_scale:"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        meso_context *ctx = test_context(1);
        meso_scene *scene = NULL;
        assert_int_equal(parse(ctx, tetrahedron, cases[i].keys, &scene), MESO_ERROR_FORMAT);
        assert_null(scene);
        if (!strstr(meso_context_last_error(ctx), cases[i].message))
            fail_msg("%s: %s", cases[i].keys, meso_context_last_error(ctx));
        meso_context_destroy(ctx);
    }
}

static void test_a_tiny_projection_scale_is_refused_naming_it(void **state) {
    meso_context *ctx = test_context(1);
    meso_scene *scene = NULL;
    /* 2 units across in tiles of 1e-6: coordinates of 1e6, beyond the limit of 65536. */
    assert_int_equal(parse(ctx, tetrahedron,
                           "\"uv_projection\": \"box\", \"uv_projection_scale\": 1e-6, ", &scene),
                     MESO_ERROR_LIMIT);
    assert_null(scene);
    if (!strstr(meso_context_last_error(ctx), "objects[0].uv_projection_scale: scaled texture "
                                              "coordinates reach"))
        fail_msg("%s", meso_context_last_error(ctx));
    meso_context_destroy(ctx);
}

static void test_a_mesh_without_uvs_and_nothing_to_map_keeps_none(void **state) {
    meso_context *ctx = test_context(1);
    const char *dir = test_temp_dir();
    const char *path = test_path(dir, "plain.obj");
    test_write_file(path, tetrahedron, strlen(tetrahedron));
    meso_scene *scene = NULL;
    assert_int_equal(meso_scene_parse(ctx,
                                      "{\"objects\": [{\"shape\": {\"file\": \"plain.obj\"}}]}",
                                      "scene.json", dir, &scene),
                     MESO_OK);
    assert_null(scene->objects[0].mesh->uvs);
    assert_string_equal(scene->objects[0].texture_coordinates, "none");
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_a_mesh_without_uvs_gets_the_box_projection_with_a_note),
        cmocka_unit_test(test_degenerate_uvs_are_replaced_the_same_way),
        cmocka_unit_test(test_an_asked_projection_scales_with_the_transform),
        cmocka_unit_test(test_bad_projection_keys_are_refused_naming_them),
        cmocka_unit_test(test_a_tiny_projection_scale_is_refused_naming_it),
        cmocka_unit_test(test_a_mesh_without_uvs_and_nothing_to_map_keeps_none),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
