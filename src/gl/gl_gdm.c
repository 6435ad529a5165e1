/* The GL side of `gdm` (shaders/gdm.frag, Wang et al. 2004 §3.2): the same bake as the CPU
 * technique (the cache's, keyed by the same parameters) and the same prism layer
 * (meso_prism_layer_create), uploaded as buffer textures: W as half floats (the bits the CPU
 * renders from), E and the baked normals as floats, per prism its face planes, Fig. 5's fin
 * convexity, its UV inverse and its vertices' frames, per face its vertices and (u, v, w); for
 * a tile-mesh solid its distance grid. The renderer draws the layer's faces in their order, so
 * gl_PrimitiveID is the face index. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "meso/bake_gdm.h"
#include "meso/runtime.h"
#include "meso/prism.h"

#include "gl_internal.h"

enum { UNIT_FIRST = 2, NUM_BUFFERS = 6 }; /* weights, eigen, normals, prisms, faces, grid */

typedef struct gl_gdm {
    GLuint buffers[NUM_BUFFERS], textures[NUM_BUFFERS];
    meso_prism_layer *layer;
    int width, height, layers, num_theta, num_phi, chunks;
    bool heightfield;
    meso_solid_shape shape;
} gl_gdm;

meso_result gl_gdm_bake(meso_context *ctx, const meso_scene *scene, const meso_object *object,
                        const meso_technique_info *info, const double *options, gl_gdm_table *out) {
    memset(out, 0, sizeof *out);
    const meso_mesostructure *ms = &object->mesostructure;
    if (gl_option_value(info, options, "compressed") == 0.0)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: gdm: compressed 0 (the raw 5D table) is drawn on the CPU only",
                              object->name);
    if (scene && scene->environment && gl_option_value(info, options, "gi") != 0.0)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: gdm: gi 1 (the radiance transfer volume of an environment) is "
                              "drawn on the CPU only; set gdm.gi=0 for the GL",
                              object->name);
    /* gdm.c, gdm_prepare: the same desc, so both back ends share one cached bake */
    int eigenmaps = (int)gl_option_value(info, options, "eigenmaps");
    int layers = (int)gl_option_value(info, options, "layers");
    int num_theta = (int)gl_option_value(info, options, "num_theta");
    meso_gdm_desc desc = {.width = (int)gl_option_value(info, options, "resolution"),
                          .height = (int)gl_option_value(info, options, "resolution"),
                          .layers = layers,
                          .num_theta = num_theta,
                          .num_phi = (int)gl_option_value(info, options, "num_phi"),
                          .eigenmaps = eigenmaps > 7 ? eigenmaps : 7};
    if (ms->kind == MESO_MESOSTRUCTURE_SOLID && ms->solid)
        desc.solid = ms->solid;
    else if (ms->kind == MESO_MESOSTRUCTURE_HEIGHT_FIELD && ms->height_field)
        desc.heightfield = ms->height_field;
    else
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: technique gdm needs a height field or a solid", object->name);
    int rank = layers * num_theta;
    if (eigenmaps > rank)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: technique_options.eigenmaps: %d, at most %d (layers x "
                              "num_theta) for this table",
                              object->name, eigenmaps, rank);
    if (desc.eigenmaps > rank) desc.eigenmaps = rank;
    meso_result r = meso_gdm_bake_cached(ctx, &desc, &out->gdm);
    if (r != MESO_OK) return r;
    out->view = meso_gdm_get_view(out->gdm);
    out->k = eigenmaps < out->view.num_eigen ? eigenmaps : out->view.num_eigen;
    out->chunks = (out->k + 3) / 4;
    return MESO_OK;
}

void gl_gdm_table_release(gl_gdm_table *table) {
    meso_gdm_destroy(table->gdm);
    memset(table, 0, sizeof *table);
}

float *gl_gdm_weights_rgba(const gl_gdm_table *t) {
    const meso_gdm_view *v = &t->view;
    size_t rows = (size_t)v->width * (size_t)v->height * (size_t)v->num_phi;
    float *out = calloc(rows * 4 * (size_t)t->chunks, sizeof(float));
    if (!out) return NULL;
    for (size_t row = 0; row < rows; row++)
        memcpy(out + row * 4 * (size_t)t->chunks, v->weights + row * (size_t)v->num_eigen,
               (size_t)t->k * sizeof(float));
    return out;
}

float *gl_gdm_eigen_rgba(const gl_gdm_table *t) {
    const meso_gdm_view *v = &t->view;
    size_t columns = (size_t)v->layers * (size_t)v->num_theta;
    float *out = calloc(columns * 4 * (size_t)t->chunks, sizeof(float));
    if (!out) return NULL;
    for (int e = 0; e < t->k; e++)
        for (size_t c = 0; c < columns; c++)
            out[c * 4 * (size_t)t->chunks + (size_t)e] = v->eigen[(size_t)e * columns + c];
    return out;
}

/* A buffer texture of `texels` texels of `format` (4 or 1 channels of `bytes_per_texel`). */
static meso_result buffer_texture(meso_context *ctx, const meso_object *object, GLenum format,
                                  const void *data, size_t texels, size_t bytes_per_texel,
                                  GLuint *out_buffer, GLuint *out_texture, size_t *memory) {
    GLint max_texels = 0;
    glGetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &max_texels);
    if (texels > (size_t)max_texels)
        return meso_log_error(ctx, MESO_ERROR_LIMIT,
                              "%s: gdm: a table of %zu texels, over the GL's %d for a buffer "
                              "texture",
                              object->name, texels, max_texels);
    glGenBuffers(1, out_buffer);
    glBindBuffer(GL_TEXTURE_BUFFER, *out_buffer);
    glBufferData(GL_TEXTURE_BUFFER, (GLsizeiptr)(texels * bytes_per_texel), data, GL_STATIC_DRAW);
    glGenTextures(1, out_texture);
    glBindTexture(GL_TEXTURE_BUFFER, *out_texture);
    glTexBuffer(GL_TEXTURE_BUFFER, format, *out_buffer);
    glBindBuffer(GL_TEXTURE_BUFFER, 0);
    *memory += texels * bytes_per_texel;
    return gl_check_upload(ctx, object, "gdm: its tables");
}

/* Per prism: planes (8), fin convexity, uv[0] and the UV inverse, the vertices' P, N, T, B
 * (T, B of the flat triangle when the mesh has none: gdm.c frame_at). */
static void pack_prism(const meso_prism_layer *layer, const meso_mesh *mesh, size_t i, float *p) {
    const meso_prism *prism = &layer->prisms[i];
    for (int k = 0; k < MESO_PRISM_NUM_FACES; k++) {
        const meso_prism_plane *pl = &layer->planes[i * MESO_PRISM_NUM_FACES + (size_t)k];
        memcpy(p + 4 * k, &pl->normal, 3 * sizeof(float));
        p[4 * k + 3] = pl->offset;
    }
    for (int e = 0; e < 3; e++) p[32 + e] = layer->fin_convex[3 * i + (size_t)e] ? 1.0f : 0.0f;
    p[36] = prism->uv[0].x;
    p[37] = prism->uv[0].y;
    p[38] = prism->uv_inverse[0];
    p[39] = prism->uv_inverse[1];
    p[40] = prism->uv_inverse[2];
    p[41] = prism->uv_inverse[3];
    p[42] = prism->valid ? 1.0f : 0.0f;
    if (!prism->valid) return;
    const uint32_t *v = prism->vertices;
    const float *inv = prism->uv_inverse;
    meso_vec3 e1 = meso_vec3_sub(mesh->positions[v[1]], mesh->positions[v[0]]);
    meso_vec3 e2 = meso_vec3_sub(mesh->positions[v[2]], mesh->positions[v[0]]);
    meso_vec3 flat_t = meso_vec3_add(meso_vec3_scale(e1, inv[0]), meso_vec3_scale(e2, inv[2]));
    meso_vec3 flat_b = meso_vec3_add(meso_vec3_scale(e1, inv[1]), meso_vec3_scale(e2, inv[3]));
    bool frame = mesh->tangents && mesh->bitangents;
    for (int c = 0; c < 3; c++) {
        memcpy(p + 4 * (11 + c), &mesh->positions[v[c]], 3 * sizeof(float));
        memcpy(p + 4 * (14 + c), &mesh->normals[v[c]], 3 * sizeof(float));
        memcpy(p + 4 * (17 + c), frame ? &mesh->tangents[v[c]] : &flat_t, 3 * sizeof(float));
        memcpy(p + 4 * (20 + c), frame ? &mesh->bitangents[v[c]] : &flat_b, 3 * sizeof(float));
    }
}

/* Per face: (P_c, u_c) for its three vertices, then (v0, w0, v1, w1), (v2, w2, 0, 0). */
static void pack_face(const meso_prism_layer *layer, size_t f, float *p) {
    const uint32_t *idx = layer->faces->indices + 3 * f;
    for (int c = 0; c < 3; c++) {
        memcpy(p + 4 * c, &layer->faces->positions[idx[c]], 3 * sizeof(float));
        p[4 * c + 3] = layer->uvws[idx[c]].x;
        p[12 + 2 * c] = layer->uvws[idx[c]].y;
        p[13 + 2 * c] = layer->uvws[idx[c]].z;
    }
}

float *gl_gdm_prism_texels(const meso_prism_layer *layer, const meso_mesh *mesh) {
    size_t n = layer->num_prisms;
    float *out = calloc((n ? n : 1) * GL_GDM_PRISM_TEXELS * 4, sizeof(float));
    for (size_t i = 0; out && i < n; i++)
        pack_prism(layer, mesh, i, out + i * GL_GDM_PRISM_TEXELS * 4);
    return out;
}

float *gl_gdm_face_texels(const meso_prism_layer *layer) {
    size_t n = layer->faces->num_triangles;
    float *out = calloc((n ? n : 1) * GL_GDM_FACE_TEXELS * 4, sizeof(float));
    for (size_t f = 0; out && f < n; f++) pack_face(layer, f, out + f * GL_GDM_FACE_TEXELS * 4);
    return out;
}

static meso_result upload(meso_context *ctx, const meso_object *object, const gl_gdm_table *t,
                          bool normals, gl_gdm *g, size_t *memory) {
    const meso_gdm_view *v = &t->view;
    const meso_prism_layer *layer = g->layer;
    size_t rows = (size_t)v->width * v->height * v->num_phi;
    size_t columns = (size_t)v->layers * v->num_theta;
    size_t voxels = (size_t)v->width * v->height * v->layers;
    size_t prisms = layer->num_prisms, faces = layer->faces->num_triangles;
    size_t grid = g->shape.grid
                      ? (size_t)g->shape.grid_side * g->shape.grid_side * (size_t)g->shape.grid_side
                      : 1;
    float *weights = gl_gdm_weights_rgba(t), *eigen = gl_gdm_eigen_rgba(t);
    uint16_t *halves = malloc(rows * 4 * (size_t)t->chunks * sizeof(uint16_t));
    float *normal_rgba = calloc(normals ? voxels * 4 : 4, sizeof(float));
    float *prism_data = gl_gdm_prism_texels(layer, object->mesh);
    float *face_data = gl_gdm_face_texels(layer);
    meso_result r = MESO_OK;
    if (!weights || !eigen || !halves || !normal_rgba || !prism_data || !face_data) {
        r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", object->name);
        goto done;
    }
    /* W is stored as halves (bake_gdm.h): the view's floats convert back exactly */
    for (size_t i = 0; i < rows * 4 * (size_t)t->chunks; i++)
        halves[i] = meso_half_from_float(weights[i]);
    for (size_t i = 0; normals && i < voxels; i++)
        memcpy(normal_rgba + 4 * i, v->normals + 3 * i, 3 * sizeof(float));
    static const float zero[4] = {0.0f, 0.0f, 0.0f, 0.0f};
    if ((r = buffer_texture(ctx, object, GL_RGBA16F, halves, rows * (size_t)t->chunks, 8,
                            &g->buffers[0], &g->textures[0], memory)) != MESO_OK ||
        (r = buffer_texture(ctx, object, GL_RGBA32F, eigen, columns * (size_t)t->chunks, 16,
                            &g->buffers[1], &g->textures[1], memory)) != MESO_OK ||
        (r = buffer_texture(ctx, object, GL_RGBA32F, normal_rgba, normals ? voxels : 1, 16,
                            &g->buffers[2], &g->textures[2], memory)) != MESO_OK ||
        (r = buffer_texture(ctx, object, GL_RGBA32F, prism_data,
                            (prisms ? prisms : 1) * GL_GDM_PRISM_TEXELS, 16, &g->buffers[3],
                            &g->textures[3], memory)) != MESO_OK ||
        (r = buffer_texture(ctx, object, GL_RGBA32F, face_data,
                            (faces ? faces : 1) * GL_GDM_FACE_TEXELS, 16, &g->buffers[4],
                            &g->textures[4], memory)) != MESO_OK ||
        (r = buffer_texture(ctx, object, GL_R32F,
                            g->shape.grid ? (const void *)g->shape.grid : zero, grid, 4,
                            &g->buffers[5], &g->textures[5], memory)) != MESO_OK)
        goto done;
done:
    free(weights);
    free(eigen);
    free(halves);
    free(normal_rgba);
    free(prism_data);
    free(face_data);
    return r;
}

meso_result gl_gdm_create(meso_context *ctx, const meso_scene *scene, const meso_object *object,
                          const meso_technique_info *info, const double *options, void **out,
                          size_t *memory) {
    *out = NULL;
    gl_gdm_table table;
    meso_result r = gl_gdm_bake(ctx, scene, object, info, options, &table);
    if (r != MESO_OK) return r;
    gl_gdm *g = calloc(1, sizeof *g);
    if (!g) {
        gl_gdm_table_release(&table);
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", object->name);
    }
    const meso_mesostructure *ms = &object->mesostructure;
    g->heightfield = ms->kind == MESO_MESOSTRUCTURE_HEIGHT_FIELD;
    if (!g->heightfield) g->shape = meso_solid_get_shape(ms->solid);
    g->width = table.view.width;
    g->height = table.view.height;
    g->layers = table.view.layers;
    g->num_theta = table.view.num_theta;
    g->num_phi = table.view.num_phi;
    g->chunks = table.chunks;
    /* gdm.c: baked normals with normals 1, and for solids with 0 */
    int normals = (int)gl_option_value(info, options, "normals");
    bool baked = normals == 1 || (normals == 0 && !g->heightfield);
    r = meso_prism_layer_create(ctx, object->mesh, ms->depth, object->name, &g->layer);
    if (r == MESO_OK) r = upload(ctx, object, &table, baked, g, memory);
    gl_gdm_table_release(&table);
    if (r != MESO_OK) {
        gl_gdm_destroy(g);
        return r;
    }
    *out = g;
    return MESO_OK;
}

const meso_mesh *gl_gdm_faces(const void *data) { return ((const gl_gdm *)data)->layer->faces; }

void gl_gdm_bind(const void *data, GLuint program, float pixel_size) {
    (void)pixel_size;
    const gl_gdm *g = data;
    static const char *const names[NUM_BUFFERS] = {"u_gdm_weights", "u_gdm_eigen", "u_gdm_normals",
                                                   "u_gdm_prisms",  "u_gdm_faces", "u_solid_grid"};
    for (int i = 0; i < NUM_BUFFERS; i++) {
        glActiveTexture((GLenum)(GL_TEXTURE0 + UNIT_FIRST + i));
        glBindTexture(GL_TEXTURE_BUFFER, g->textures[i]);
        glUniform1i(glGetUniformLocation(program, names[i]), UNIT_FIRST + i);
    }
    glUniform3i(glGetUniformLocation(program, "u_gdm_size"), g->width, g->height, g->layers);
    glUniform2i(glGetUniformLocation(program, "u_gdm_directions"), g->num_theta, g->num_phi);
    glUniform1i(glGetUniformLocation(program, "u_gdm_chunks"), g->chunks);
    glUniform1i(glGetUniformLocation(program, "u_num_prisms"), (GLint)g->layer->num_prisms);
    glUniform1i(glGetUniformLocation(program, "u_gdm_heightfield"), g->heightfield);
    const meso_solid_shape *s = &g->shape;
    glUniform1i(glGetUniformLocation(program, "u_solid_kind"), (GLint)s->desc.kind);
    glUniform1f(glGetUniformLocation(program, "u_solid_count"), (float)s->desc.count);
    glUniform1f(glGetUniformLocation(program, "u_solid_thickness"), s->desc.thickness);
    glUniform1f(glGetUniformLocation(program, "u_solid_depth_cells"), s->depth_cells);
    glUniform1f(glGetUniformLocation(program, "u_solid_scale"), s->scale);
    glUniform1f(glGetUniformLocation(program, "u_solid_cap"), s->cap);
    glUniform1f(glGetUniformLocation(program, "u_solid_amplitude"), s->amplitude);
    glUniform1f(glGetUniformLocation(program, "u_solid_major"), s->major);
    glUniform1f(glGetUniformLocation(program, "u_solid_half_length"), s->half_length);
    glUniform2f(glGetUniformLocation(program, "u_solid_tilt"), s->tilt_cos, s->tilt_sin);
    glUniform1f(glGetUniformLocation(program, "u_solid_radius"), s->radius);
    glUniform1i(glGetUniformLocation(program, "u_solid_grid_side"), s->grid_side);
    glUniform1i(glGetUniformLocation(program, "u_solid_grid_clamped"), s->grid_clamped);
}

void gl_gdm_destroy(void *data) {
    gl_gdm *g = data;
    if (!g) return;
    for (int i = 0; i < NUM_BUFFERS; i++) {
        if (g->textures[i]) glDeleteTextures(1, &g->textures[i]);
        if (g->buffers[i]) glDeleteBuffers(1, &g->buffers[i]);
    }
    meso_prism_layer_destroy(g->layer);
    free(g);
}
