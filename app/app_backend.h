/* The back end a command draws with (--backend cpu | gl, --shader-dir): one renderer type for
 * render and bench, so neither branches on the back end beyond parsing it. */
#ifndef MESO_APP_BACKEND_H
#define MESO_APP_BACKEND_H

#include "app.h"

typedef struct app_backend {
    const char *name;       /* "cpu" (NULL: cpu) or "gl" */
    const char *shader_dir; /* gl: read shaders from this folder instead of the built-in ones */
} app_backend;

/* The two rows of a command's option table. */
#define APP_BACKEND_OPTIONS(backend)                                                               \
    {"--backend",                                                                                  \
     NULL,                                                                                         \
     APP_OPTION_STRING,                                                                            \
     &(backend).name,                                                                              \
     "cpu|gl",                                                                                     \
     "cpu: meso's rasterizer; gl: the GLSL shaders on OpenGL 3.3 through EGL, headless "           \
     "(docs/gpu.md)",                                                                              \
     "cpu",                                                                                        \
     0,                                                                                            \
     0},                                                                                           \
    {                                                                                              \
        "--shader-dir", NULL, APP_OPTION_STRING, &(backend).shader_dir, "DIR",                     \
            "with --backend gl: read the shader files from DIR (edited copies of shaders/)",       \
            "the built-in ones", 0, 0                                                              \
    }

/* -1 when the options make sense, else the usage error's exit status (2). */
int app_backend_check(const char *command, const app_backend *backend);
static inline bool app_backend_is_gl(const app_backend *backend) {
    return backend->name && backend->name[0] == 'g';
}

typedef struct app_renderer {
    meso_renderer *cpu;
    meso_gl_renderer *gl;
} app_renderer;

meso_result app_renderer_create(meso_context *ctx, const meso_scene *scene,
                                const meso_render_desc *desc, const app_backend *backend,
                                app_renderer *out);
meso_result app_renderer_render(app_renderer *renderer, meso_framebuffer *fb);
meso_render_stats app_renderer_get_stats(const app_renderer *renderer);
void app_renderer_destroy(app_renderer *renderer);

/* app_fail_in, and for what the GL cannot do (MESO_ERROR_UNSUPPORTED: no EGL, no GL 3.3, a
 * technique without a shader) the same line ending "; --backend cpu works", exit 1. */
int app_fail_backend(meso_context *ctx, meso_result result, const char *file,
                     const app_backend *backend);

#endif
