/* Hand-built scenes for the rasterizer tests (header-only; no dependency on the scene parser).
 * A test_scene owns its meshes and height fields. */
#ifndef RENDER_TEST_SCENE_H
#define RENDER_TEST_SCENE_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"

#define TEST_SCENE_MAX_OBJECTS 8

typedef struct test_scene {
    meso_scene scene;
    meso_object objects[TEST_SCENE_MAX_OBJECTS];
} test_scene;

/* A scene of width x height, the docs/design.md camera, one directional light, ambient 0.1. */
static inline void test_scene_init(test_scene *ts, int width, int height) {
    memset(ts, 0, sizeof(*ts));
    meso_scene *s = &ts->scene;
    snprintf(s->path, sizeof(s->path), "test.json");
    s->width = width;
    s->height = height;
    s->background = (meso_vec3){0.1f, 0.2f, 0.3f};
    s->camera = (meso_camera){{0.0f, 1.2f, 2.2f}, {0.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.0f}, 40.0f};
    s->ambient = (meso_vec3){0.1f, 0.1f, 0.1f};
    s->lights[0] = (meso_light){.type = MESO_LIGHT_DIRECTIONAL,
                                .direction = meso_vec3_normalize((meso_vec3){0.5f, 0.7f, 0.3f}),
                                .color = {1.0f, 1.0f, 1.0f}};
    s->num_lights = 1;
    s->objects = ts->objects;
}

/* Append an object drawing `mesh` (taken over) with `technique`; returns it. */
static inline meso_object *test_scene_add(test_scene *ts, meso_mesh *mesh, const char *technique) {
    assert_true(ts->scene.num_objects < TEST_SCENE_MAX_OBJECTS);
    meso_object *o = &ts->objects[ts->scene.num_objects];
    snprintf(o->name, sizeof(o->name), "objects[%d]", ts->scene.num_objects);
    ts->scene.num_objects++;
    o->mesh = mesh;
    o->material.albedo = (meso_vec3){0.8f, 0.8f, 0.8f};
    o->material.shininess = 32.0f;
    snprintf(o->technique, sizeof(o->technique), "%s", technique);
    return o;
}

/* A built-in shape with tangents, moved by `offset`. */
static inline meso_mesh *test_shape(meso_context *ctx, meso_shape_kind kind, float size,
                                    int segments, meso_vec3 offset) {
    meso_mesh *mesh = NULL;
    meso_shape_desc desc = {.kind = kind, .size = size, .segments = segments};
    assert_int_equal(meso_mesh_create_shape(ctx, &desc, &mesh), MESO_OK);
    if (offset.x != 0.0f || offset.y != 0.0f || offset.z != 0.0f) {
        meso_mesh_transform(mesh, meso_mat4_translate(offset));
    }
    if (mesh->uvs && !mesh->tangents)
        assert_int_equal(meso_mesh_compute_tangents(ctx, mesh), MESO_OK);
    return mesh;
}

/* Give the object a procedural bricks height field of depth 0.05. */
static inline void test_object_bricks(meso_context *ctx, meso_object *o) {
    meso_heightfield *hf = NULL;
    meso_heightfield_desc desc = {.kind = MESO_HEIGHTFIELD_BRICKS, .resolution = 128};
    assert_int_equal(meso_heightfield_create_procedural(ctx, &desc, &hf, NULL), MESO_OK);
    o->mesostructure.kind = MESO_MESOSTRUCTURE_HEIGHT_FIELD;
    o->mesostructure.height_field = hf;
    o->mesostructure.depth = 0.05f;
    snprintf(o->mesostructure.source, sizeof(o->mesostructure.source), "bricks");
}

/* Give the object a constant height field of 0.5 (8 x 8 texels), the shell `depth` deep: its
 * surface is the base mesh moved half the depth inward. */
static inline void test_object_constant_height(meso_context *ctx, meso_object *o, float depth) {
    meso_heightfield *hf = NULL;
    assert_int_equal(meso_heightfield_create_constant(ctx, 8, 8, 0.5f, &hf), MESO_OK);
    o->mesostructure.kind = MESO_MESOSTRUCTURE_HEIGHT_FIELD;
    o->mesostructure.height_field = hf;
    o->mesostructure.depth = depth;
}

static inline void test_scene_free(test_scene *ts) {
    for (int i = 0; i < ts->scene.num_objects; i++) {
        meso_mesh_destroy(ts->objects[i].mesh);
        meso_heightfield_destroy(ts->objects[i].mesostructure.height_field);
    }
    ts->scene.num_objects = 0;
}

#endif
