/* Private interface of the OpenGL back end: the embedded shader files, the headless context
 * and program building. The GL entry points come from libepoxy, which resolves them at run
 * time from whatever libEGL / libGL the machine has (glvnd + Mesa on Debian). */
#ifndef MESO_GL_INTERNAL_H
#define MESO_GL_INTERNAL_H

#include <stddef.h>

#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include "meso/bake_gdm.h"
#include "meso/bake_layers.h"
#include "meso/bake_vdm.h"
#include "meso/bake_vdm_lanes.h"
#include "meso/prism.h"
#include "meso/gl.h"

/* ---- The shader files, built in (cmake/embed_shaders.cmake) ------------------------------- */

typedef struct gl_embedded_shader {
    const char *name; /* "relief.frag" */
    const char *text;
} gl_embedded_shader;
extern const gl_embedded_shader gl_embedded_shaders[];
extern const size_t gl_embedded_shader_count;

/* The built-in text of shaders/<name>, NULL when there is none. */
const char *gl_shader_builtin(const char *name);

/* ---- Headless context (gl_context.c) ------------------------------------------------------ */

typedef struct gl_context {
    EGLDisplay display;
    EGLContext context;
} gl_context;

/* An OpenGL 3.3 core context with no surface (drawing goes to framebuffer objects), current on
 * the calling thread. MESO_ERROR_UNSUPPORTED naming what is missing; out_info (may be NULL)
 * says how far it got. */
meso_result gl_context_create(meso_context *ctx, gl_context *out, meso_gl_info *out_info);
/* Make it current on the calling thread. */
meso_result gl_context_make_current(meso_context *ctx, const gl_context *gl);
void gl_context_destroy(gl_context *gl);

/* ---- Programs (gl_program.c) -------------------------------------------------------------- */

/* Compile and link meso.vert with `<technique>.frag` and the files its first line requires
 * ("// meso:requires a.glsl b.glsl"), read from shader_dir or the built-in copies. Errors:
 * MESO_ERROR_FORMAT with the log as "<shader_dir or shaders>/<file>:<line>: <message>". */
meso_result gl_program_build(meso_context *ctx, const char *technique, const char *shader_dir,
                             GLuint *out_program);

/* ---- Techniques ---------------------------------------------------------------------------- */

/* The technique of an object: desc's override or its own; with desc->fallback, an override
 * that cannot draw the object gives way to the object's own, else flat (as
 * meso_renderer_create). MESO_ERROR_INVALID_ARGUMENT when it does not accept the object's
 * mesostructure or has no shader: a request the back end cannot serve. */
meso_result gl_resolve_technique(meso_context *ctx, const meso_object *object,
                                 const meso_render_desc *desc, const meso_technique_info **out);

/* A 2D texture of one level read with texelFetch only (GL_NEAREST): the shaders filter
 * themselves (meso_common.glsl says why). */
GLuint gl_texture_2d(GLenum internal_format, int width, int height, GLenum format, GLenum type,
                     const void *data);

/* MESO_OK when the GL reports no error, else MESO_ERROR_OUT_OF_MEMORY logged as
 * "<object>: <technique>: the GL could not store <what>" (uploads fail for memory). */
meso_result gl_check_upload(meso_context *ctx, const meso_object *object, const char *what);

/* The value of option `name` in `values` (meso_technique_options_values' order); 0 when the
 * technique has no such option. */
double gl_option_value(const meso_technique_info *info, const double *values, const char *name);

/* ---- The techniques (gl_techniques.c) ------------------------------------------------------ */

/* The GL side of one technique of technique_list.h: whether it has a fragment shader
 * (shaders/<name>.frag) and the data it keeps for an object, each step NULL when it keeps
 * none. `out` of create receives the data; memory grows by the bytes the GL holds. */
typedef struct gl_technique {
    bool drawn;      /* it has a shader: the back end draws it */
    bool both_faces; /* back faces drawn too (relief_layers: render_internal.h, both_faces) */
    meso_result (*create)(meso_context *ctx, const meso_scene *scene, const meso_object *object,
                          const meso_technique_info *info, const double *options, void **out,
                          size_t *memory);
    /* the faces to draw instead of the object's mesh; NULL: the mesh */
    const meso_mesh *(*faces)(const void *data);
    /* bind its textures and set its uniforms on `program` (current) */
    void (*bind)(const void *data, GLuint program, float pixel_size);
    void (*destroy)(void *data);
} gl_technique;

/* The GL side of the technique `info` (from meso_technique_find) and its index in
 * technique_list.h into *out_index; NULL for a technique outside the list (reference). */
const gl_technique *gl_technique_of(const meso_technique_info *info, size_t *out_index);

/* ---- Per-technique data (gl_<technique>.c), each with gl_technique's steps ----------------- */

/* relief_exact: the maximum mip-map as the mip levels of an R32F texture (unit 2). */
meso_result gl_max_mip_create(meso_context *ctx, const meso_scene *scene, const meso_object *object,
                              const meso_technique_info *info, const double *options, void **out,
                              size_t *memory);
void gl_max_mip_bind(const void *data, GLuint program, float pixel_size);
void gl_max_mip_destroy(void *data);

/* relief_layers: the multilayer map (the CPU technique's bake) and, for solids, its mirror
 * (back faces), with the options' automatic values resolved; no GL needed. */
typedef struct gl_layers_maps {
    meso_layers *map, *mirrored; /* mirrored: NULL for a height field */
    int num_layers;              /* searched: the most a texel holds */
    int linear_steps;
    bool impostor, enclosed;
} gl_layers_maps;
meso_result gl_layers_bake(meso_context *ctx, const meso_object *object,
                           const meso_technique_info *info, const double *options,
                           gl_layers_maps *out);
void gl_layers_maps_release(gl_layers_maps *maps);

/* The maps as texture arrays (units 2-5). */
meso_result gl_layers_create(meso_context *ctx, const meso_scene *scene, const meso_object *object,
                             const meso_technique_info *info, const double *options, void **out,
                             size_t *memory);
void gl_layers_bind(const void *data, GLuint program, float pixel_size);
void gl_layers_destroy(void *data);

/* vdm: the bake (cached, the CPU technique's bake for the same options) laid out as the CPU
 * technique reads it; no GL needed (texture export uses it too). */
typedef struct gl_vdm_table {
    meso_vdm *vdm;
    meso_vdm_view view;
    meso_vdm_lanes lanes;
    int k, m;                      /* eigenfunctions used */
    float tile_world, depth_tiles; /* world length of a tile; the shell depth in tiles */
} gl_vdm_table;
meso_result gl_vdm_bake(meso_context *ctx, const meso_object *object,
                        const meso_technique_info *info, const double *options, gl_vdm_table *out);
void gl_vdm_table_release(gl_vdm_table *table);

/* The table uploaded as textures units 2-4. */
meso_result gl_vdm_create(meso_context *ctx, const meso_scene *scene, const meso_object *object,
                          const meso_technique_info *info, const double *options, void **out,
                          size_t *memory);
void gl_vdm_bind(const void *data, GLuint program, float pixel_size);
void gl_vdm_destroy(void *data);

/* gdm: the bake (cached, the CPU technique's bake for the same options); no GL needed (texture
 * export uses it too). Refuses compressed 0 and, in a scene with an environment, gi 1 (scene
 * may be NULL: no environment). */
typedef struct gl_gdm_table {
    meso_gdm *gdm;
    meso_gdm_view view;
    int k;      /* eigen-maps used (the option, at most the bake's) */
    int chunks; /* groups of 4 of them: texels a row of W, a column of E */
} gl_gdm_table;
meso_result gl_gdm_bake(meso_context *ctx, const meso_scene *scene, const meso_object *object,
                        const meso_technique_info *info, const double *options, gl_gdm_table *out);
void gl_gdm_table_release(gl_gdm_table *table);
/* W as [height][width][num_phi][4 chunks] floats and E as [layers][num_theta][4 chunks] (E
 * transposed), zero past k: the shader's texel layout. Caller frees; NULL: out of memory. */
float *gl_gdm_weights_rgba(const gl_gdm_table *table);
float *gl_gdm_eigen_rgba(const gl_gdm_table *table);

/* The prism layer as the shader reads it: GL_GDM_PRISM_TEXELS RGBA texels a prism (planes,
 * fin convexity, UV inverse, the vertices' frames; shaders/gdm.frag), GL_GDM_FACE_TEXELS a face
 * (vertices and their (u, v, w)). Caller frees; NULL: out of memory. */
#define GL_GDM_PRISM_TEXELS 24
#define GL_GDM_FACE_TEXELS 5
float *gl_gdm_prism_texels(const meso_prism_layer *layer, const meso_mesh *mesh);
float *gl_gdm_face_texels(const meso_prism_layer *layer);

/* The table, the prism layer and the solid uploaded as buffer textures (units 2-7). */
meso_result gl_gdm_create(meso_context *ctx, const meso_scene *scene, const meso_object *object,
                          const meso_technique_info *info, const double *options, void **out,
                          size_t *memory);
/* The prism faces to draw, in face order (the shader reads gl_PrimitiveID as the face). */
const meso_mesh *gl_gdm_faces(const void *data);
void gl_gdm_bind(const void *data, GLuint program, float pixel_size);
void gl_gdm_destroy(void *data);

#endif
