/* What the GL tests share: whether this machine has an EGL device (the only reason to skip),
 * and rendering one example scene with either back end at a small size. Header-only. */
#ifndef MESO_GL_FIXTURE_H
#define MESO_GL_FIXTURE_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"

/* Skip (cmocka) when the machine has no EGL display at all; fail when it has one but no
 * OpenGL 3.3 core context: CI installs Mesa, so there the tests must run. */
static inline void gl_require_device(void) {
    meso_context *ctx = test_context(1);
    meso_gl_info info;
    meso_result r = meso_gl_probe(ctx, &info);
    if (!info.egl) {
        print_message("no EGL device (%s): GL tests skipped\n", meso_context_last_error(ctx));
        meso_context_destroy(ctx);
        skip();
    }
    if (r != MESO_OK) fail_msg("EGL works but: %s", meso_context_last_error(ctx));
    meso_context_destroy(ctx);
}

static inline meso_scene *gl_load_example(meso_context *ctx, const char *name) {
    char path[1024];
    snprintf(path, sizeof path, "%s/examples/%s.json", MESO_SOURCE_DIR, name);
    meso_scene *scene = NULL;
    meso_result r = meso_scene_load(ctx, path, &scene);
    if (r != MESO_OK) fail_msg("%s: %s", path, meso_context_last_error(ctx));
    return scene;
}

/* One frame of `scene` drawn with `technique` (options in desc) on the GL or the CPU. */
static inline meso_framebuffer *gl_render(meso_context *ctx, const meso_scene *scene, bool gl,
                                          const meso_render_desc *desc, int size) {
    meso_framebuffer *fb = NULL;
    assert_int_equal(meso_framebuffer_create(ctx, size, size, &fb), MESO_OK);
    meso_result r;
    if (gl) {
        meso_gl_renderer *renderer = NULL;
        meso_gl_desc gl_desc = {.render = *desc};
        r = meso_gl_renderer_create(ctx, scene, &gl_desc, &renderer);
        if (r == MESO_OK) r = meso_gl_renderer_render(renderer, fb);
        meso_gl_renderer_destroy(renderer);
    } else {
        meso_renderer *renderer = NULL;
        r = meso_renderer_create(ctx, scene, desc, &renderer);
        if (r == MESO_OK) r = meso_renderer_render(renderer, fb);
        meso_renderer_destroy(renderer);
    }
    if (r != MESO_OK)
        fail_msg("%s (%s): %s", scene->path, gl ? "gl" : "cpu", meso_context_last_error(ctx));
    return fb;
}

#endif
