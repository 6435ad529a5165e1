/* The fixture the per-pixel technique tests share: one object on the built-in plane of size 2,
 * P(u,v) = (-1 + 2u, 0, 1 - 2v), a camera, one directional light, fragments built by hand and
 * height fields from a function of the texel. Header-only, included by one test file each. */
#ifndef MESO_TECHNIQUE_FIXTURE_H
#define MESO_TECHNIQUE_FIXTURE_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render_internal.h"
#include "test_util.h"

typedef struct fixture {
    meso_context *ctx;
    meso_heightfield *hf;
    meso_scene scene;
    meso_object object;
    meso_frame frame;
} fixture;

static void fixture_init(fixture *fx, meso_heightfield *hf, float depth, meso_vec3 eye,
                         meso_vec3 target, meso_vec3 light) {
    memset(fx, 0, sizeof *fx);
    fx->ctx = test_context(1);
    fx->hf = hf;
    fx->scene.width = fx->scene.height = 64;
    fx->scene.camera = (meso_camera){eye, target, {0.0f, 1.0f, 0.0f}, 40.0f};
    if (fabsf(eye.x - target.x) < 1e-6f && fabsf(eye.z - target.z) < 1e-6f)
        fx->scene.camera.up = (meso_vec3){0.0f, 0.0f, -1.0f};
    fx->scene.ambient = (meso_vec3){0.1f, 0.1f, 0.1f};
    fx->scene.num_lights = 1;
    fx->scene.lights[0] = (meso_light){
        MESO_LIGHT_DIRECTIONAL, meso_vec3_normalize(light), {0, 0, 0}, {1.0f, 1.0f, 1.0f}};
    fx->scene.objects = &fx->object;
    fx->scene.num_objects = 1;
    strcpy(fx->object.name, "objects[0]");
    fx->object.material.albedo = (meso_vec3){0.8f, 0.6f, 0.4f};
    fx->object.mesostructure.kind = MESO_MESOSTRUCTURE_HEIGHT_FIELD;
    fx->object.mesostructure.height_field = hf;
    fx->object.mesostructure.depth = depth;
    meso_frame_init(&fx->frame, &fx->scene, 64, 64);
}

static void fixture_deinit(fixture *fx) {
    meso_heightfield_destroy(fx->hf);
    meso_context_destroy(fx->ctx);
}

static void set_option(fixture *fx, const char *name, double value) {
    meso_option *o = &fx->object.options[fx->object.num_options++];
    snprintf(o->name, sizeof o->name, "%s", name);
    o->value = value;
}

static meso_fragment plane_fragment(const fixture *fx, float u, float v) {
    meso_fragment f;
    memset(&f, 0, sizeof f);
    f.position = (meso_vec3){-1.0f + 2.0f * u, 0.0f, 1.0f - 2.0f * v};
    f.normal = (meso_vec3){0.0f, 1.0f, 0.0f};
    f.tangent = (meso_vec3){2.0f, 0.0f, 0.0f};
    f.bitangent = (meso_vec3){0.0f, 0.0f, -2.0f};
    f.uv = (meso_vec2){u, v};
    f.b0 = 1.0f;
    f.depth = meso_vec3_dot(meso_vec3_sub(f.position, fx->frame.eye), fx->frame.forward);
    f.out_depth = f.depth;
    return f;
}

/* Shade `count` fragments with technique `name` (prepared on fx's object). */
static void shade_with(fixture *fx, const char *name, meso_fragment *f, size_t count) {
    const meso_technique *t = meso_technique_lookup(name);
    assert_non_null(t);
    void *state = NULL;
    assert_int_equal(t->prepare(fx->ctx, &fx->scene, &fx->object, &state), MESO_OK);
    assert_int_equal(meso_technique_shade(t, state, &fx->frame, &fx->object, f, count), MESO_OK);
    t->release(state);
}

static meso_heightfield *field(void *unused, int width, int height, float (*h)(int i, int j)) {
    (void)unused;
    meso_context *ctx = test_context(1);
    meso_heightfield *hf = NULL;
    assert_int_equal(meso_heightfield_create_constant(ctx, width, height, 0.0f, &hf), MESO_OK);
    for (int j = 0; j < height; ++j)
        for (int i = 0; i < width; ++i)
            hf->heights[(size_t)j * (size_t)width + (size_t)i] = h(i, j);
    meso_heightfield_update_hash(hf);
    meso_context_destroy(ctx);
    return hf;
}

#endif
