/* The OpenGL renderer: per object a program (meso.vert + the technique's fragment shader),
 * one vertex buffer of the world-space mesh with its tangent frame and quadrics, the colour
 * map and the height field as textures; per frame the draw into a framebuffer object (linear
 * colour with coverage in alpha, view depth, a 32-bit float depth buffer) and the read-back
 * into a meso_framebuffer, rows flipped to meso's top-first order. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gl_internal.h"
#include "meso/runtime.h"
#include "meso/texture.h"

#define GL_MAX_OPTIONS 32 /* rows of any technique's option table */
#define GL_FLOATS_PER_VERTEX 24

typedef struct gl_object {
    const meso_object *object;
    const meso_technique_info *info;
    const gl_technique *gl; /* its row in gl_techniques.c */
    size_t technique;       /* its index in technique_list.h */
    void *data;             /* the technique's own (gl->create), or NULL */
    GLuint program;
    GLuint vao, vertices, indices;
    GLsizei index_count;
    GLuint color_map, height;
    meso_uv_domain domain; /* the relief family's open sides (meso_mesh_uv_domain) */
    double options[GL_MAX_OPTIONS];
} gl_object;

struct meso_gl_renderer {
    meso_context *ctx;
    const meso_scene *scene;
    gl_context gl;
    GLuint *programs; /* by technique index; 0: not built yet */
    gl_object *objects;
    int num_objects;
    GLuint framebuffer, color_target, depth_target, depth_buffer;
    int target_width, target_height;
    float *readback; /* 4 floats a pixel */
    meso_render_stats stats;
};

GLuint gl_texture_2d(GLenum internal_format, int width, int height, GLenum format, GLenum type,
                     const void *data) {
    GLuint texture;
    glGenTextures(1, &texture);
    glBindTexture(GL_TEXTURE_2D, texture);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexImage2D(GL_TEXTURE_2D, 0, (GLint)internal_format, width, height, 0, format, type, data);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, 0);
    return texture;
}

meso_result gl_check_upload(meso_context *ctx, const meso_object *object, const char *what) {
    return glGetError() == GL_NO_ERROR
               ? MESO_OK
               : meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: the GL could not store %s",
                                object->name, what);
}

double gl_option_value(const meso_technique_info *info, const double *values, const char *name) {
    const meso_technique_option *row = meso_technique_find_option(info, name);
    return row ? values[row - info->options] : 0.0;
}

meso_result gl_resolve_technique(meso_context *ctx, const meso_object *object,
                                 const meso_render_desc *desc, const meso_technique_info **out) {
    const char *own = object->technique[0] ? object->technique : "flat";
    const char *name = desc->technique ? desc->technique : own;
    const meso_technique_info *info = meso_technique_find(name);
    const meso_mesostructure *kind = &object->mesostructure;
    *out = NULL;
    if (info && desc->fallback && desc->technique && !meso_technique_accepts(info, kind)) {
        const meso_technique_info *mine = meso_technique_find(own);
        info = mine && mine->kind == MESO_TECHNIQUE_PER_PIXEL &&
                       meso_technique_accepts(mine, kind) && meso_gl_technique_supported(own)
                   ? mine
                   : meso_technique_find("flat");
    }
    if (!info)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: unknown technique '%s'",
                              object->name, name);
    if (!meso_technique_accepts(info, kind))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: technique '%s' does not accept this mesostructure", object->name,
                              info->name);
    if (!meso_gl_technique_supported(info->name)) {
        char list[256] = "";
        size_t used = 0;
        for (size_t i = 0; i < meso_technique_count(); i++) {
            const char *t = meso_technique_get(i)->name;
            if (!meso_gl_technique_supported(t)) continue;
            int w = snprintf(list + used, sizeof list - used, "%s%s", used ? ", " : "", t);
            if (w > 0 && (size_t)w < sizeof list - used) used += (size_t)w;
        }
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: technique '%s' has no GL shader (the GL back end draws: %s)",
                              object->name, info->name, list);
    }
    if (info->num_options > GL_MAX_OPTIONS)
        return meso_log_error(ctx, MESO_ERROR_INTERNAL, "%s: too many options", info->name);
    *out = info;
    return MESO_OK;
}

static meso_result program_for(meso_gl_renderer *r, const gl_object *o, const char *shader_dir,
                               GLuint *out) {
    if (r->programs[o->technique]) {
        *out = r->programs[o->technique];
        return MESO_OK;
    }
    meso_result result = gl_program_build(r->ctx, o->info->name, shader_dir, out);
    if (result == MESO_OK) r->programs[o->technique] = *out;
    return result;
}

/* The mesh as interleaved vertices: position, normal, tangent, bitangent, uv, quadric,
 * principal curvatures and their directions (meso.vert's locations 0-8), zero where the mesh
 * has no such array. gdm draws its prism layer's faces instead of the object's mesh. */
static meso_result upload_mesh(meso_gl_renderer *r, gl_object *o, const meso_mesh *mesh) {
    if (!mesh || mesh->num_triangles == 0) return MESO_OK;
    if (mesh->num_vertices > (size_t)INT32_MAX / GL_FLOATS_PER_VERTEX ||
        mesh->num_triangles > (size_t)INT32_MAX / 3)
        return meso_log_error(r->ctx, MESO_ERROR_LIMIT, "%s: mesh too large for one GL draw",
                              o->object->name);
    size_t bytes = mesh->num_vertices * GL_FLOATS_PER_VERTEX * sizeof(float);
    meso_result result = meso_memory_check(r->ctx, o->object->name, bytes);
    if (result != MESO_OK) return result;
    float *v = calloc(mesh->num_vertices, GL_FLOATS_PER_VERTEX * sizeof(float));
    if (!v)
        return meso_log_error(r->ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory",
                              o->object->name);
    for (size_t i = 0; i < mesh->num_vertices; i++) {
        float *p = v + i * GL_FLOATS_PER_VERTEX;
        memcpy(p, &mesh->positions[i], 3 * sizeof(float));
        if (mesh->normals) memcpy(p + 3, &mesh->normals[i], 3 * sizeof(float));
        if (mesh->tangents && mesh->bitangents) {
            memcpy(p + 6, &mesh->tangents[i], 3 * sizeof(float));
            memcpy(p + 9, &mesh->bitangents[i], 3 * sizeof(float));
        }
        if (mesh->uvs) memcpy(p + 12, &mesh->uvs[i], 2 * sizeof(float));
        if (mesh->quadrics) memcpy(p + 14, &mesh->quadrics[i], 2 * sizeof(float));
        if (mesh->curvature_max && mesh->curvature_min && mesh->curvature_dir_max &&
            mesh->curvature_dir_min) {
            p[16] = mesh->curvature_max[i];
            p[17] = mesh->curvature_min[i];
            memcpy(p + 18, &mesh->curvature_dir_max[i], 3 * sizeof(float));
            memcpy(p + 21, &mesh->curvature_dir_min[i], 3 * sizeof(float));
        }
    }
    glGenVertexArrays(1, &o->vao);
    glBindVertexArray(o->vao);
    glGenBuffers(1, &o->vertices);
    glBindBuffer(GL_ARRAY_BUFFER, o->vertices);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)bytes, v, GL_STATIC_DRAW);
    free(v);
    static const int sizes[9] = {3, 3, 3, 3, 2, 2, 2, 3, 3};
    size_t offset = 0;
    for (GLuint k = 0; k < 9; k++) {
        glEnableVertexAttribArray(k);
        glVertexAttribPointer(k, sizes[k], GL_FLOAT, GL_FALSE, GL_FLOATS_PER_VERTEX * sizeof(float),
                              (const void *)offset);
        offset += (size_t)sizes[k] * sizeof(float);
    }
    glGenBuffers(1, &o->indices);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, o->indices);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, (GLsizeiptr)(mesh->num_triangles * 3 * sizeof(uint32_t)),
                 mesh->indices, GL_STATIC_DRAW);
    glBindVertexArray(0);
    o->index_count = (GLsizei)(mesh->num_triangles * 3);
    r->stats.memory_bytes += bytes + mesh->num_triangles * 3 * sizeof(uint32_t);
    return MESO_OK;
}

/* A float texture sampled with texelFetch only (the shaders filter themselves). */
static meso_result upload_texture(meso_gl_renderer *r, const meso_object *object, int width,
                                  int height, GLenum internal_format, GLenum format,
                                  const float *data, size_t bytes_per_texel, GLuint *out) {
    GLint max_size = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
    if (width > max_size || height > max_size)
        return meso_log_error(r->ctx, MESO_ERROR_LIMIT,
                              "%s: a %d x %d map exceeds the GL's largest texture, %d a side",
                              object->name, width, height, max_size);
    *out = gl_texture_2d(internal_format, width, height, format, GL_FLOAT, data);
    r->stats.memory_bytes += (size_t)width * (size_t)height * bytes_per_texel;
    return gl_check_upload(r->ctx, object, "a map");
}

static meso_result prepare_object(meso_gl_renderer *r, int index, const meso_gl_desc *desc) {
    gl_object *o = &r->objects[index];
    const meso_object *object = &r->scene->objects[index];
    o->object = object;
    meso_result result;
    if ((result = gl_resolve_technique(r->ctx, object, &desc->render, &o->info)) != MESO_OK)
        return result;
    o->gl = gl_technique_of(o->info, &o->technique); /* drawn: gl_resolve_technique checked */
    if ((result = meso_technique_options_values(r->ctx, r->scene, index, &desc->render,
                                                o->info->name, o->options)) != MESO_OK ||
        (result = program_for(r, o, desc->shader_dir, &o->program)) != MESO_OK)
        return result;
    /* the relief family's shell walk (relief_shell.h) has no shader (docs/gpu.md) */
    if (gl_option_value(o->info, o->options, "shell") != 0.0)
        return meso_log_error(r->ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: %s: shell 1 (the search along the prism shell) is drawn on the "
                              "CPU only; set %s.shell=0 for the GL",
                              object->name, o->info->name, o->info->name);
    if (o->gl->create && (result = o->gl->create(r->ctx, r->scene, object, o->info, o->options,
                                                 &o->data, &r->stats.memory_bytes)) != MESO_OK)
        return result;
    if ((result = upload_mesh(r, o, o->gl->faces ? o->gl->faces(o->data) : object->mesh)) !=
        MESO_OK)
        return result;
    if (!meso_mesh_uv_domain(object->mesh, &o->domain))
        return meso_log_error(r->ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", object->name);
    const meso_texture *color_map = object->material.color_map;
    if (color_map &&
        (result = upload_texture(r, object, color_map->levels[0]->width,
                                 color_map->levels[0]->height, GL_RGBA32F, GL_RGBA,
                                 color_map->levels[0]->pixels, 16, &o->color_map)) != MESO_OK)
        return result;
    const meso_heightfield *hf = object->mesostructure.height_field;
    if (hf && (result = upload_texture(r, object, hf->width, hf->height, GL_R32F, GL_RED,
                                       hf->heights, 4, &o->height)) != MESO_OK)
        return result;
    return MESO_OK;
}

meso_result meso_gl_check_scene(meso_context *ctx, const meso_scene *scene,
                                const meso_render_desc *desc) {
    if (!scene) return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "gl: NULL scene");
    meso_render_desc d = desc ? *desc : (meso_render_desc){0};
    if (d.samples > 1 || d.wireframe)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: the GL back end draws one sample a pixel and no wireframe",
                              scene->path);
    meso_result result = meso_technique_check_scene(ctx, scene);
    for (int i = 0; result == MESO_OK && i < d.num_options; i++) {
        char where[160];
        snprintf(where, sizeof where, "render options: %s.%s", d.options[i].technique,
                 d.options[i].name);
        result = meso_technique_check_option(ctx, d.options[i].technique, d.options[i].name,
                                             d.options[i].value, where);
    }
    for (int i = 0; result == MESO_OK && i < scene->num_objects; i++) {
        const meso_technique_info *info;
        double values[GL_MAX_OPTIONS];
        result = gl_resolve_technique(ctx, &scene->objects[i], &d, &info);
        if (result == MESO_OK)
            result = meso_technique_options_values(ctx, scene, i, &d, info->name, values);
    }
    return result;
}

meso_result meso_gl_renderer_create(meso_context *ctx, const meso_scene *scene,
                                    const meso_gl_desc *desc, meso_gl_renderer **out_renderer) {
    *out_renderer = NULL;
    meso_gl_desc d = desc ? *desc : (meso_gl_desc){0};
    if (!scene) return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "gl: NULL scene");
    meso_result result = meso_gl_check_scene(ctx, scene, &d.render);
    if (result != MESO_OK) return result;
    double start = meso_time_seconds();
    meso_gl_renderer *r = calloc(1, sizeof *r);
    size_t slots = scene->num_objects > 0 ? (size_t)scene->num_objects : 1;
    if (!r || !(r->objects = calloc(slots, sizeof *r->objects)) ||
        !(r->programs = calloc(meso_technique_count(), sizeof *r->programs))) {
        result = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", scene->path);
        goto fail;
    }
    r->ctx = ctx;
    r->scene = scene;
    r->gl.context = EGL_NO_CONTEXT;
    if ((result = gl_context_create(ctx, &r->gl, NULL)) != MESO_OK) goto fail;
    r->num_objects = scene->num_objects;
    for (int i = 0; i < scene->num_objects; i++)
        if ((result = prepare_object(r, i, &d)) != MESO_OK) goto fail;
    r->stats.prepare_seconds = meso_time_seconds() - start;
    *out_renderer = r;
    return MESO_OK;
fail:
    meso_gl_renderer_destroy(r);
    return result;
}

static void release_targets(meso_gl_renderer *r) {
    if (r->framebuffer) glDeleteFramebuffers(1, &r->framebuffer);
    if (r->color_target) glDeleteRenderbuffers(1, &r->color_target);
    if (r->depth_target) glDeleteRenderbuffers(1, &r->depth_target);
    if (r->depth_buffer) glDeleteRenderbuffers(1, &r->depth_buffer);
    r->framebuffer = r->color_target = r->depth_target = r->depth_buffer = 0;
    free(r->readback);
    r->readback = NULL;
    r->target_width = r->target_height = 0;
}

static GLuint make_renderbuffer(GLenum format, int width, int height) {
    GLuint rb;
    glGenRenderbuffers(1, &rb);
    glBindRenderbuffer(GL_RENDERBUFFER, rb);
    glRenderbufferStorage(GL_RENDERBUFFER, format, width, height);
    return rb;
}

/* Colour (RGBA32F: linear colour, coverage in alpha), view depth (R32F) and a 32-bit float
 * depth buffer holding view depth / far (meso_common.glsl, meso_write). */
static meso_result reserve_targets(meso_gl_renderer *r, int width, int height) {
    if (r->framebuffer && r->target_width == width && r->target_height == height) return MESO_OK;
    release_targets(r);
    GLint max_size = 0, dims[2] = {0, 0};
    glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_size);
    glGetIntegerv(GL_MAX_VIEWPORT_DIMS, dims);
    if (width > max_size || height > max_size || width > dims[0] || height > dims[1])
        return meso_log_error(r->ctx, MESO_ERROR_LIMIT,
                              "%s: %d x %d exceeds the GL's largest target, %d x %d",
                              r->scene->path, width, height, dims[0], dims[1]);
    r->readback = malloc((size_t)width * (size_t)height * 4 * sizeof(float));
    if (!r->readback)
        return meso_log_error(r->ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory",
                              r->scene->path);
    glGenFramebuffers(1, &r->framebuffer);
    glBindFramebuffer(GL_FRAMEBUFFER, r->framebuffer);
    r->color_target = make_renderbuffer(GL_RGBA32F, width, height);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER,
                              r->color_target);
    r->depth_target = make_renderbuffer(GL_R32F, width, height);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_RENDERBUFFER,
                              r->depth_target);
    r->depth_buffer = make_renderbuffer(GL_DEPTH_COMPONENT32F, width, height);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER,
                              r->depth_buffer);
    static const GLenum buffers[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glDrawBuffers(2, buffers);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
        release_targets(r);
        return meso_log_error(r->ctx, MESO_ERROR_UNSUPPORTED,
                              "OpenGL: float render targets are not supported");
    }
    r->target_width = width;
    r->target_height = height;
    return MESO_OK;
}

static void set_uniform_vec3(GLuint program, const char *name, meso_vec3 v) {
    glUniform3f(glGetUniformLocation(program, name), v.x, v.y, v.z);
}

/* The frame's and the object's uniforms (meso_common.glsl), and its options as u_<name>. */
static void set_uniforms(const meso_gl_renderer *r, const gl_object *o,
                         const meso_render_camera *camera) {
    GLuint p = o->program;
    const meso_scene *scene = r->scene;
    const meso_material *m = &o->object->material;
    glUniformMatrix4fv(glGetUniformLocation(p, "u_view_projection"), 1, GL_FALSE,
                       camera->view_projection.m);
    set_uniform_vec3(p, "u_eye", camera->eye);
    set_uniform_vec3(p, "u_forward", camera->forward);
    glUniform1f(glGetUniformLocation(p, "u_depth_range"), camera->z_far);
    set_uniform_vec3(p, "u_ambient", scene->ambient);
    int num_lights =
        scene->num_lights < MESO_SCENE_MAX_LIGHTS ? scene->num_lights : MESO_SCENE_MAX_LIGHTS;
    glUniform1i(glGetUniformLocation(p, "u_num_lights"), num_lights);
    for (int i = 0; i < num_lights; i++) {
        const meso_light *light = &scene->lights[i];
        char name[48];
        snprintf(name, sizeof name, "u_light_is_point[%d]", i);
        glUniform1i(glGetUniformLocation(p, name), light->type == MESO_LIGHT_POINT);
        snprintf(name, sizeof name, "u_light_vector[%d]", i);
        set_uniform_vec3(p, name,
                         light->type == MESO_LIGHT_POINT ? light->position : light->direction);
        snprintf(name, sizeof name, "u_light_color[%d]", i);
        set_uniform_vec3(p, name, light->color);
    }
    set_uniform_vec3(p, "u_albedo", m->albedo);
    set_uniform_vec3(p, "u_specular", m->specular);
    glUniform1f(glGetUniformLocation(p, "u_shininess"), m->shininess);
    glUniform1i(glGetUniformLocation(p, "u_has_color_map"), o->color_map != 0);
    glUniform1i(glGetUniformLocation(p, "u_color_map_clamp"),
                m->color_map && m->color_map->wrap == MESO_WRAP_CLAMP);
    glUniform1i(glGetUniformLocation(p, "u_color_map"), 0);
    glUniform1i(glGetUniformLocation(p, "u_height"), 1);
    const meso_heightfield *hf = o->object->mesostructure.height_field;
    glUniform2i(glGetUniformLocation(p, "u_height_size"), hf ? hf->width : 1, hf ? hf->height : 1);
    glUniform1i(glGetUniformLocation(p, "u_height_clamp"), hf && hf->wrap == MESO_WRAP_CLAMP);
    glUniform1f(glGetUniformLocation(p, "u_depth"), o->object->mesostructure.depth);
    glUniform1i(glGetUniformLocation(p, "u_domain_sides"), (int)o->domain.sides);
    glUniform4f(glGetUniformLocation(p, "u_domain"), o->domain.u_min, o->domain.u_max,
                o->domain.v_min, o->domain.v_max);
    for (size_t k = 0; k < o->info->num_options; k++) {
        const meso_technique_option *option = &o->info->options[k];
        char name[80];
        snprintf(name, sizeof name, "u_%s", option->name);
        GLint at = glGetUniformLocation(p, name);
        if (option->type == MESO_OPTION_FLOAT)
            glUniform1f(at, (float)o->options[k]);
        else
            glUniform1i(at, (int)o->options[k]);
    }
}

meso_result meso_gl_renderer_render(meso_gl_renderer *r, meso_framebuffer *fb) {
    if (!r || !fb) return MESO_ERROR_INVALID_ARGUMENT;
    double start = meso_time_seconds();
    meso_result result;
    if ((result = gl_context_make_current(r->ctx, &r->gl)) != MESO_OK ||
        (result = reserve_targets(r, fb->width, fb->height)) != MESO_OK)
        return result;
    const meso_scene *scene = r->scene;
    meso_render_camera camera = meso_render_camera_get(scene, fb->width, fb->height);
    glBindFramebuffer(GL_FRAMEBUFFER, r->framebuffer);
    glViewport(0, 0, fb->width, fb->height);
    const float background[4] = {scene->background.x, scene->background.y, scene->background.z,
                                 0.0f};
    const float far_depth[4] = {INFINITY, 0.0f, 0.0f, 0.0f};
    glClearBufferfv(GL_COLOR, 0, background);
    glClearBufferfv(GL_COLOR, 1, far_depth);
    glClearBufferfv(GL_DEPTH, 0, (const float[]){1.0f});
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glEnable(GL_CULL_FACE); /* counter-clockwise seen from outside: the rasterizer culls so */
    glCullFace(GL_BACK);
    glFrontFace(GL_CCW);
    uint64_t triangles = 0;
    for (int i = 0; i < r->num_objects; i++) {
        const gl_object *o = &r->objects[i];
        if (!o->vao) continue;
        glUseProgram(o->program);
        set_uniforms(r, o, &camera);
        glActiveTexture(GL_TEXTURE0);
        glBindTexture(GL_TEXTURE_2D, o->color_map);
        glActiveTexture(GL_TEXTURE1);
        glBindTexture(GL_TEXTURE_2D, o->height);
        if (o->gl->bind) o->gl->bind(o->data, o->program, camera.pixel_size);
        /* relief_layers draws back faces too: the far wall of a closed mesh through holes of
         * the near one (render_internal.h, both_faces) */
        if (o->gl->both_faces)
            glDisable(GL_CULL_FACE);
        else
            glEnable(GL_CULL_FACE);
        glBindVertexArray(o->vao);
        glDrawElements(GL_TRIANGLES, o->index_count, GL_UNSIGNED_INT, NULL);
        triangles += (uint64_t)o->index_count / 3;
    }
    glBindVertexArray(0);
    /* read back, bottom row first in GL, top row first in meso */
    int w = fb->width, h = fb->height;
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glReadPixels(0, 0, w, h, GL_RGBA, GL_FLOAT, r->readback);
    for (int y = 0; y < h; y++) {
        const float *src = r->readback + (size_t)(h - 1 - y) * (size_t)w * 4;
        for (int x = 0; x < w; x++) {
            size_t i = (size_t)y * (size_t)w + (size_t)x;
            bool covered = src[4 * x + 3] > 0.0f;
            fb->color[3 * i + 0] = covered ? src[4 * x + 0] : scene->background.x;
            fb->color[3 * i + 1] = covered ? src[4 * x + 1] : scene->background.y;
            fb->color[3 * i + 2] = covered ? src[4 * x + 2] : scene->background.z;
            fb->coverage[i] = covered ? 1.0f : 0.0f;
        }
    }
    glReadBuffer(GL_COLOR_ATTACHMENT1);
    glReadPixels(0, 0, w, h, GL_RED, GL_FLOAT, r->readback);
    for (int y = 0; y < h; y++) {
        const float *src = r->readback + (size_t)(h - 1 - y) * (size_t)w;
        for (int x = 0; x < w; x++) {
            size_t i = (size_t)y * (size_t)w + (size_t)x;
            fb->depth[i] = fb->coverage[i] > 0.0f ? src[x] : INFINITY;
        }
    }
    GLenum error = glGetError();
    if (error != GL_NO_ERROR)
        return meso_log_error(r->ctx, MESO_ERROR_INTERNAL, "%s: OpenGL error 0x%x drawing",
                              scene->path, error);
    r->stats.triangles = triangles;
    r->stats.last_frame_seconds = meso_time_seconds() - start;
    return MESO_OK;
}

meso_render_stats meso_gl_renderer_get_stats(const meso_gl_renderer *r) {
    return r ? r->stats : (meso_render_stats){0};
}

const char *meso_gl_renderer_object_technique(const meso_gl_renderer *r, int object) {
    if (!r || object < 0 || object >= r->num_objects || !r->objects[object].info) return NULL;
    return r->objects[object].info->name;
}

void meso_gl_renderer_destroy(meso_gl_renderer *r) {
    if (!r) return;
    if (r->gl.context != EGL_NO_CONTEXT && gl_context_make_current(r->ctx, &r->gl) == MESO_OK) {
        release_targets(r);
        for (int i = 0; i < r->num_objects; i++) {
            gl_object *o = &r->objects[i];
            if (o->vao) glDeleteVertexArrays(1, &o->vao);
            if (o->vertices) glDeleteBuffers(1, &o->vertices);
            if (o->indices) glDeleteBuffers(1, &o->indices);
            if (o->color_map) glDeleteTextures(1, &o->color_map);
            if (o->height) glDeleteTextures(1, &o->height);
            if (o->gl && o->gl->destroy) o->gl->destroy(o->data);
        }
        for (size_t i = 0; r->programs && i < meso_technique_count(); i++)
            if (r->programs[i]) glDeleteProgram(r->programs[i]);
    }
    gl_context_destroy(&r->gl);
    free(r->readback);
    free(r->objects);
    free(r->programs);
    free(r);
}
