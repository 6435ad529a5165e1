/* Import through assimp: OBJ, PLY, glTF; errors that name the file; limits. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geom_internal.h"
#include "test_util.h"

static const char *write_text(const char *name, const char *text) {
    const char *path = test_path(test_temp_dir(), name);
    test_write_file(path, text, strlen(text));
    return path;
}

static const char quad_with_uvs[] = "v -1 0 1\nv 1 0 1\nv 1 0 -1\nv -1 0 -1\n"
                                    "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                                    "f 1/1 2/2 3/3 4/4\n";

static void test_obj_with_uvs_loads_as_triangles_with_uvs(void **state) {
    meso_context *ctx = test_context(1);
    const char *path = write_text("quad.obj", quad_with_uvs);
    meso_mesh *mesh = NULL;
    assert_int_equal(meso_mesh_load(ctx, path, &mesh), MESO_OK);
    assert_int_equal(mesh->num_triangles, 2);
    assert_int_equal(mesh->num_vertices, 4);
    assert_non_null(mesh->uvs);
    for (size_t i = 0; i < mesh->num_vertices; i++) {
        meso_vec3 p = mesh->positions[i];
        /* OpenGL convention kept: vt 0 0 is at (-1, 0, 1), nothing flipped. */
        assert_float_equal(mesh->uvs[i].x, 0.5f * (p.x + 1.0f), 1e-6f);
        assert_float_equal(mesh->uvs[i].y, 0.5f * (1.0f - p.z), 1e-6f);
        /* Generated normals: the quad is counter-clockwise seen from +y. */
        assert_float_equal(mesh->normals[i].y, 1.0f, 1e-5f);
    }
    assert_int_equal(meso_mesh_validate(ctx, mesh, path, true), MESO_OK);
    assert_int_equal(meso_mesh_compute_tangents(ctx, mesh), MESO_OK);
    assert_float_equal(mesh->tangents[0].x, 2.0f, 1e-5f);
    assert_float_equal(mesh->bitangents[0].z, -2.0f, 1e-5f);
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

static void test_obj_without_uvs_loads_but_cannot_carry_a_mesostructure(void **state) {
    meso_context *ctx = test_context(1);
    const char *path = write_text("no_uvs.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    meso_mesh *mesh = NULL;
    assert_int_equal(meso_mesh_load(ctx, path, &mesh), MESO_OK);
    assert_null(mesh->uvs);
    assert_int_equal(meso_mesh_validate(ctx, mesh, path, false), MESO_OK);
    assert_int_equal(meso_mesh_validate(ctx, mesh, path, true), MESO_ERROR_FORMAT);
    const char *message = meso_context_last_error(ctx);
    assert_non_null(strstr(message, path));
    assert_non_null(strstr(message, "texture coordinates"));
    assert_int_equal(meso_mesh_compute_tangents(ctx, mesh), MESO_ERROR_INVALID_ARGUMENT);
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

static void test_obj_with_nan_coordinate_is_rejected_naming_the_file(void **state) {
    meso_context *ctx = test_context(1);
    const char *path = write_text("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n"
                                             "f 1/1 2/2 3/3\n");
    meso_mesh *mesh = NULL;
    meso_result r = meso_mesh_load(ctx, path, &mesh);
    if (r == MESO_OK) r = meso_mesh_validate(ctx, mesh, path, true);
    assert_int_equal(r, MESO_ERROR_FORMAT);
    assert_non_null(strstr(meso_context_last_error(ctx), path));
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

static void test_degenerate_triangle_is_dropped_with_one_warning(void **state) {
    meso_context *ctx = test_context(1);
    /* The second and third faces are collinear. */
    const char *path =
        write_text("degenerate.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nv 3 0 0\n"
                                     "vt 0 0\nvt 1 0\nvt 0 1\n"
                                     "f 1/1 2/2 3/3\nf 1/1 2/2 4/3\nf 2/1 4/2 5/3\n");
    meso_mesh *mesh = NULL;
    assert_int_equal(meso_mesh_load(ctx, path, &mesh), MESO_OK);
    assert_int_equal(mesh->num_triangles, 1);
    assert_non_null(strstr(test_last_warning(), path));
    assert_non_null(strstr(test_last_warning(), "dropped 2 degenerate triangles"));
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

static void test_missing_file_is_an_io_error_naming_the_path(void **state) {
    meso_context *ctx = test_context(1);
    const char *path = test_path(test_temp_dir(), "does-not-exist.obj");
    meso_mesh *mesh = (meso_mesh *)1;
    assert_int_equal(meso_mesh_load(ctx, path, &mesh), MESO_ERROR_IO);
    assert_null(mesh);
    assert_non_null(strstr(meso_context_last_error(ctx), path));
    assert_int_equal(meso_mesh_load(ctx, test_temp_dir(), &mesh), MESO_ERROR_IO);
    assert_null(mesh);
    assert_non_null(strstr(meso_context_last_error(ctx), test_temp_dir()));
    meso_context_destroy(ctx);
}

static void test_unparsable_file_is_a_format_error_naming_the_path(void **state) {
    meso_context *ctx = test_context(1);
    const char *path = write_text("broken.ply", "ply\nformat ascii 1.0\nelement vertex 3\n"
                                                "property float x\nend_header\n1 2\n");
    meso_mesh *mesh = (meso_mesh *)1;
    assert_int_equal(meso_mesh_load(ctx, path, &mesh), MESO_ERROR_FORMAT);
    assert_null(mesh);
    assert_non_null(strstr(meso_context_last_error(ctx), path));
    /* assimp 5.2 loops forever on this one; meso refuses it first. */
    const char *endless = write_text("endless.ply", "ply\nformat ascii 1.0\nelement vertex 3\n"
                                                    "property float x\nend_headen\n1\n2\n3\n");
    assert_int_equal(meso_mesh_load(ctx, endless, &mesh), MESO_ERROR_FORMAT);
    assert_non_null(strstr(meso_context_last_error(ctx), "endless.ply: PLY header"));
    /* A face index past the vertex count would crash assimp's later steps. */
    const char *far =
        write_text("far.ply", "ply\nformat ascii 1.0\nelement vertex 3\n"
                              "property float x\nproperty float y\nproperty float z\n"
                              "element face 1\nproperty list uchar int vertex_indices\n"
                              "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n");
    assert_int_equal(meso_mesh_load(ctx, far, &mesh), MESO_ERROR_FORMAT);
    assert_non_null(strstr(meso_context_last_error(ctx), "far.ply"));
    /* A face with no corners makes assimp's Triangulate abort the process. */
    const char *empty =
        write_text("empty_face.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                                     "property float y\nproperty float z\nelement face 1\n"
                                     "property list uchar int vertex_indices\nend_header\n"
                                     "0 0 0\n1 0 0\n0 1 0\n0\n");
    assert_int_equal(meso_mesh_load(ctx, empty, &mesh), MESO_ERROR_FORMAT);
    assert_non_null(strstr(meso_context_last_error(ctx), "empty_face.ply"));
    const char *garbage = write_text("garbage.xyzzy", "\x01\x02 this is not a mesh\n");
    assert_int_equal(meso_mesh_load(ctx, garbage, &mesh), MESO_ERROR_FORMAT);
    assert_non_null(strstr(meso_context_last_error(ctx), garbage));
    meso_context_destroy(ctx);
}

static void test_ply_loads(void **state) {
    meso_context *ctx = test_context(1);
    const char *path =
        write_text("quad.ply", "ply\nformat ascii 1.0\nelement vertex 4\n"
                               "property float x\nproperty float y\nproperty float z\n"
                               "property float s\nproperty float t\n"
                               "element face 1\nproperty list uchar int vertex_indices\n"
                               "end_header\n"
                               "0 0 0 0 0\n1 0 0 1 0\n1 1 0 1 1\n0 1 0 0 1\n"
                               "4 0 1 2 3\n");
    meso_mesh *mesh = NULL;
    assert_int_equal(meso_mesh_load(ctx, path, &mesh), MESO_OK);
    assert_int_equal(mesh->num_triangles, 2);
    assert_non_null(mesh->uvs);
    assert_float_equal(mesh->normals[0].z, 1.0f, 1e-5f);
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

/* glTF: one triangle under a node that translates by (10, 0, 0) and scales x by -1 (a mirror):
 * the transform is applied and the winding stays counter-clockwise around the normals. */
static void test_gltf_node_transforms_are_applied(void **state) {
    meso_context *ctx = test_context(1);
    const char *path = write_text(
        "tri.gltf",
        "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],"
        "\"nodes\":[{\"children\":[1],\"translation\":[10,0,0]},{\"mesh\":0,\"scale\":[-1,1,1]}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}],"
        "\"buffers\":[{\"byteLength\":44,\"uri\":\"data:application/octet-stream;base64,"
        "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAABAAIAAAA=\"}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":36},"
        "{\"buffer\":0,\"byteOffset\":36,\"byteLength\":6}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\","
        "\"min\":[0,0,0],\"max\":[1,1,0]},"
        "{\"bufferView\":1,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"}]}");
    meso_mesh *mesh = NULL;
    assert_int_equal(meso_mesh_load(ctx, path, &mesh), MESO_OK);
    assert_int_equal(mesh->num_triangles, 1);
    assert_null(mesh->uvs);
    meso_vec3 lo, hi;
    meso_mesh_bounds(mesh, &lo, &hi);
    assert_float_equal(lo.x, 9.0f, 1e-5f);
    assert_float_equal(hi.x, 10.0f, 1e-5f);
    const uint32_t *tri = mesh->indices;
    meso_vec3 p0 = mesh->positions[tri[0]];
    meso_vec3 face = meso_vec3_cross(meso_vec3_sub(mesh->positions[tri[1]], p0),
                                     meso_vec3_sub(mesh->positions[tri[2]], p0));
    assert_true(meso_vec3_dot(face, mesh->normals[tri[0]]) > 0.0f);
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

static void test_counts_over_the_limit_are_refused_before_allocating(void **state) {
    meso_context *ctx = test_context(1);
    assert_int_equal(geom_check_counts(ctx, "big.obj", MESO_MESH_MAX_VERTICES, 1), MESO_OK);
    assert_int_equal(geom_check_counts(ctx, "big.obj", (uint64_t)MESO_MESH_MAX_VERTICES + 1, 1),
                     MESO_ERROR_LIMIT);
    assert_non_null(strstr(meso_context_last_error(ctx), "big.obj"));
    assert_non_null(strstr(meso_context_last_error(ctx), "vertices"));
    assert_int_equal(geom_check_counts(ctx, "big.obj", 3, UINT64_C(1) << 40), MESO_ERROR_LIMIT);
    assert_non_null(strstr(meso_context_last_error(ctx), "triangles"));
    /* A PLY declaring too many vertices is refused before assimp reads (or allocates) them. */
    const char *huge = write_text("huge.ply", "ply\nformat ascii 1.0\nelement vertex 4000000000\n"
                                              "property float x\nend_header\n0\n");
    meso_mesh *mesh = (meso_mesh *)1;
    assert_int_equal(meso_mesh_load(ctx, huge, &mesh), MESO_ERROR_LIMIT);
    assert_null(mesh);
    assert_non_null(strstr(meso_context_last_error(ctx), "huge.ply: 4000000000 vertices"));
    assert_int_equal(meso_mesh_create(ctx, (size_t)MESO_MESH_MAX_VERTICES + 1, 1, true, &mesh),
                     MESO_ERROR_LIMIT);
    assert_null(mesh);
    meso_context_destroy(ctx);
}

/* assimp's error text may quote lines of the file: only its first line is kept, cut short. */
static void test_assimp_reasons_are_one_line_cut_short(void **state) {
    (void)state;
    char out[32];
    geom_import_reason("OBJ: bad line\nmeso: forged second line", out, sizeof out);
    assert_string_equal(out, "OBJ: bad line ...");
    geom_import_reason("a reason far longer than the thirty-two bytes given", out, sizeof out);
    assert_string_equal(out, "a reason far longer than th ...");
    assert_int_equal(strlen(out), sizeof out - 1);
    geom_import_reason(NULL, out, sizeof out);
    assert_string_equal(out, "unknown format");
    geom_import_reason("short\r\n", out, sizeof out);
    assert_string_equal(out, "short");
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_obj_with_uvs_loads_as_triangles_with_uvs),
        cmocka_unit_test(test_assimp_reasons_are_one_line_cut_short),
        cmocka_unit_test(test_obj_without_uvs_loads_but_cannot_carry_a_mesostructure),
        cmocka_unit_test(test_obj_with_nan_coordinate_is_rejected_naming_the_file),
        cmocka_unit_test(test_degenerate_triangle_is_dropped_with_one_warning),
        cmocka_unit_test(test_missing_file_is_an_io_error_naming_the_path),
        cmocka_unit_test(test_unparsable_file_is_a_format_error_naming_the_path),
        cmocka_unit_test(test_ply_loads),
        cmocka_unit_test(test_gltf_node_transforms_are_applied),
        cmocka_unit_test(test_counts_over_the_limit_are_refused_before_allocating),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
