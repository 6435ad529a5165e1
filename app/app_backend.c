/* --backend: the CPU rasterizer or the OpenGL back end behind one renderer type. */
#include "app_backend.h"

#include <string.h>

int app_backend_check(const char *command, const app_backend *backend) {
    if (backend->name && strcmp(backend->name, "cpu") != 0 && strcmp(backend->name, "gl") != 0)
        return app_usage_error(command, "--backend: '%s' is not cpu or gl", backend->name);
    if (backend->shader_dir && !app_backend_is_gl(backend))
        return app_usage_error(command, "--shader-dir needs --backend gl");
    return -1;
}

meso_result app_renderer_create(meso_context *ctx, const meso_scene *scene,
                                const meso_render_desc *desc, const app_backend *backend,
                                app_renderer *out) {
    *out = (app_renderer){0};
    if (!app_backend_is_gl(backend)) return meso_renderer_create(ctx, scene, desc, &out->cpu);
    meso_gl_desc gl_desc = {.render = *desc, .shader_dir = backend->shader_dir};
    gl_desc.render.progress = false; /* the GL draws in one call: nothing to report */
    return meso_gl_renderer_create(ctx, scene, &gl_desc, &out->gl);
}

meso_result app_renderer_render(app_renderer *renderer, meso_framebuffer *fb) {
    return renderer->gl ? meso_gl_renderer_render(renderer->gl, fb)
                        : meso_renderer_render(renderer->cpu, fb);
}

meso_render_stats app_renderer_get_stats(const app_renderer *renderer) {
    return renderer->gl ? meso_gl_renderer_get_stats(renderer->gl)
                        : meso_renderer_get_stats(renderer->cpu);
}

void app_renderer_destroy(app_renderer *renderer) {
    meso_gl_renderer_destroy(renderer->gl);
    meso_renderer_destroy(renderer->cpu);
    *renderer = (app_renderer){0};
}

int app_fail_backend(meso_context *ctx, meso_result result, const char *file,
                     const app_backend *backend) {
    if (result != MESO_ERROR_UNSUPPORTED || !app_backend_is_gl(backend))
        return app_fail_in(ctx, result, file);
    const char *message = meso_context_last_error(ctx);
    if (!message || !message[0]) message = meso_result_string(result);
    if (strncmp(message, file, strlen(file)) == 0)
        app_error("%s; --backend cpu works", message);
    else
        app_error("%s: %s; --backend cpu works", file, message);
    return APP_EXIT_FAILURE;
}
