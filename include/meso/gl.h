/* meso OpenGL back end: the per-pixel techniques and gdm (its prism layer drawn) as GLSL
 * shaders (shaders/), drawn headless
 * through EGL with OpenGL 3.3 core, read back into a meso_framebuffer (docs/gpu.md).
 *
 * Usage
 *   meso_gl_renderer *r = NULL; meso_framebuffer *fb = NULL;
 *   meso_gl_renderer_create(ctx, scene, &(meso_gl_desc){.render = {.technique = "relief"}}, &r);
 *   meso_framebuffer_create(ctx, scene->width, scene->height, &fb);
 *   meso_gl_renderer_render(r, fb);          // as often as you like
 *   meso_framebuffer_save_png(ctx, fb, scene->encoding, "out.png", NULL);
 *
 * The shaders compute what the CPU techniques compute, with the same option tables (each
 * option is the uniform u_<name>), the same texel-centre conventions and the same shading,
 * so a GL image and a CPU image of one scene agree to float rounding except where a search
 * step lands on the other side of an edge, or where gdm's yes/no decisions flip a pixel as
 * they do on the CPU under a nudge of the eye (tests/gl). Techniques with a shader:
 * meso_gl_technique_supported. The context is created without any window system: Mesa's
 * surfaceless EGL platform (llvmpipe without a GPU; LIBGL_ALWAYS_SOFTWARE=1 forces it), else
 * the first EGL device.
 *
 * Errors: no EGL, or no OpenGL 3.3 core context: MESO_ERROR_UNSUPPORTED with a message saying
 * what is missing. A shader that does not compile: MESO_ERROR_FORMAT with the compiler's log,
 * each line as "shaders/<file>:<line>: <message>" (the folder is shader_dir when given).
 *
 * Threads: a renderer makes its context current on the calling thread in each call; use one
 * renderer from one thread at a time. meso's CPU thread count does not apply (llvmpipe has
 * its own threads, LP_NUM_THREADS).
 */
#ifndef MESO_GL_H
#define MESO_GL_H

#include "meso/render.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct meso_gl_desc {
    /* technique, options and fallback as for meso_renderer_create; samples > 1 and wireframe
     * are not supported (MESO_ERROR_UNSUPPORTED) */
    meso_render_desc render;
    /* NULL: the shaders built into the library (the files of shaders/ when it was built);
     * else read <shader_dir>/<file> at creation, to try an edited shader without rebuilding */
    const char *shader_dir;
} meso_gl_desc;

/* What the machine offers. */
typedef struct meso_gl_info {
    bool egl;           /* an EGL display could be initialised */
    bool core33;        /* and an OpenGL 3.3 core context created on it */
    char renderer[128]; /* GL_RENDERER ("llvmpipe (LLVM 15.0.6, 256 bits)") */
    char version[128];  /* GL_VERSION */
} meso_gl_info;

/* Try to create a context and describe it. MESO_OK when both egl and core33, else
 * MESO_ERROR_UNSUPPORTED with the message of what is missing (out_info filled either way).
 * Thread-safe. */
meso_result meso_gl_probe(meso_context *ctx, meso_gl_info *out_info);

/* True when `technique` has a fragment shader (flat, parallax, relief, ...). Thread-safe. */
bool meso_gl_technique_supported(const char *technique);

/* What meso_gl_renderer_create and meso_gl_export_textures check first, without a GL context
 * and before any bake or file: desc (may be NULL) asks for one sample a pixel and no
 * wireframe, the scene's techniques and options are valid (meso_technique_check_scene) and
 * every object's technique accepts its mesostructure and has a shader. A request the GL back
 * end cannot serve is bad input, MESO_ERROR_INVALID_ARGUMENT naming the object ("wall:
 * technique 'tessellation' has no GL shader (the GL back end draws: ...)"); what the machine
 * lacks (no EGL, no GL 3.3) is MESO_ERROR_UNSUPPORTED, from the calls that make a context. */
meso_result meso_gl_check_scene(meso_context *ctx, const meso_scene *scene,
                                const meso_render_desc *desc);

typedef struct meso_gl_renderer meso_gl_renderer;

/* Check the scene (meso_gl_check_scene), create the context, compile the programs, upload
 * meshes and maps. The scene must outlive the renderer. Errors: those of meso_gl_check_scene;
 * MESO_ERROR_INVALID_ARGUMENT for an option the GL does not draw (gdm or vdm with compressed 0,
 * gdm's gi under an environment, relief_exact on a repeating map of other than power-of-two
 * sides); MESO_ERROR_UNSUPPORTED for no EGL or no GL 3.3; MESO_ERROR_FORMAT for a shader that
 * does not compile; MESO_ERROR_LIMIT for maps larger than the GL allows. */
meso_result meso_gl_renderer_create(meso_context *ctx, const meso_scene *scene,
                                    const meso_gl_desc *desc, meso_gl_renderer **out_renderer);
/* Draw one frame into fb (any size up to the GL's largest viewport) and read it back: colour,
 * coverage (0 or 1) and view depth, as the CPU renderer writes them. */
meso_result meso_gl_renderer_render(meso_gl_renderer *renderer, meso_framebuffer *fb);
/* prepare_seconds, last_frame_seconds (drawing and read-back), triangles, memory_bytes (the
 * textures and vertex buffers); fragments is 0 (the GL does not count them). */
meso_render_stats meso_gl_renderer_get_stats(const meso_gl_renderer *renderer);
/* The technique drawing object `object` (NULL for an index out of range). */
const char *meso_gl_renderer_object_technique(const meso_gl_renderer *renderer, int object);
void meso_gl_renderer_destroy(meso_gl_renderer *renderer);

/* ---- Texture export (meso bake -o) -------------------------------------------------------- */

/* Write into folder `dir` (existing) what each object's shader reads, as ordinary files, and
 * manifest.json describing them (sizes, formats, scale factors, which uniform reads which file,
 * the uniforms' values): per object <i>-<name>.height.png (16-bit grey, h = value / 65535),
 * <i>-<name>.color.png (16-bit linear RGB) and for vdm the SVD tables as OpenEXR:
 * .vdm-weights.exr (half), .vdm-eigen.exr and .mvm-eigen.exr (float). The techniques are
 * resolved and their options read as meso_gl_renderer_create does (desc may be NULL); bakes
 * come from the cache. No GL context is needed. Each file is written atomically, the manifest
 * last. docs/gpu.md. */
meso_result meso_gl_export_textures(meso_context *ctx, const meso_scene *scene,
                                    const meso_render_desc *desc, const char *dir);

#ifdef __cplusplus
}
#endif
#endif
