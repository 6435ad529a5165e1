/* The GL side of `vdm` (shaders/vdm.frag): the same bake as the CPU technique (the cache's,
 * keyed by the same parameters), laid out by meso_vdm_lanes as the CPU reads it, uploaded as
 * three textures: W with its mip levels stacked in rows (half floats, the CPU's bits), E_VDM
 * and E_MVM. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "meso/bake_vdm.h"
#include "meso/bake_vdm_lanes.h"
#include "meso/runtime.h"

#include "gl_internal.h"

typedef struct gl_vdm {
    GLuint weights, eigen, mvm;
    int chunks, num_levels;
    int level_size[MESO_VDM_MAX_LEVELS][2], level_row[MESO_VDM_MAX_LEVELS];
    float curvature_min, curvature_max, tile_world, depth_tiles;
    bool has_curvature;
} gl_vdm;

/* Upload the layout: W rows of every level one under the other. */
static meso_result upload(meso_context *ctx, const meso_object *object, const meso_vdm_view *v,
                          const meso_vdm_lanes *l, gl_vdm *g, size_t *memory) {
    g->chunks = l->lanes / 4;
    g->num_levels = l->num_levels;
    int width = v->width * v->num_phi * g->chunks, height = 0;
    for (int i = 0; i < l->num_levels; i++) {
        g->level_size[i][0] = l->level_width[i];
        g->level_size[i][1] = l->level_height[i];
        g->level_row[i] = height;
        height += l->level_height[i];
    }
    GLint max_size = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
    if (width > max_size || height > max_size)
        return meso_log_error(ctx, MESO_ERROR_LIMIT,
                              "%s: vdm: the weights make a %d x %d texture, over the GL's %d",
                              object->name, width, height, max_size);
    size_t row_halves = (size_t)width * 4;
    uint16_t *atlas = calloc((size_t)height * row_halves, sizeof(uint16_t));
    if (!atlas)
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", object->name);
    for (int i = 0; i < l->num_levels; i++) /* a level's row y is [x][phi][lanes]: contiguous */
        for (int y = 0; y < l->level_height[i]; y++)
            memcpy(atlas + (size_t)(g->level_row[i] + y) * row_halves,
                   l->level_weights[i] +
                       (size_t)y * l->level_width[i] * v->num_phi * (size_t)l->lanes,
                   (size_t)l->level_width[i] * v->num_phi * (size_t)l->lanes * sizeof(uint16_t));
    g->weights = gl_texture_2d(GL_RGBA16F, width, height, GL_RGBA, GL_HALF_FLOAT, atlas);
    free(atlas);
    /* E transposed is [column][lanes]: texel (column, j) wants lanes 4j..4j+3, so rows of
     * chunks: re-pack as [j][column][4] */
    int columns = v->num_theta * v->num_curvatures;
    float *eigen = malloc(sizeof(float) * (size_t)columns * l->lanes);
    float *mvm = malloc(sizeof(float) * (size_t)v->num_curvatures * l->lanes);
    if (!eigen || !mvm) {
        free(eigen);
        free(mvm);
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", object->name);
    }
    for (int j = 0; j < g->chunks; j++) {
        for (int c = 0; c < columns; c++)
            memcpy(eigen + ((size_t)j * columns + c) * 4, l->eigen_t + (size_t)c * l->lanes + 4 * j,
                   4 * sizeof(float));
        for (int c = 0; c < v->num_curvatures; c++)
            memcpy(mvm + ((size_t)j * v->num_curvatures + c) * 4,
                   l->mvm_t + (size_t)c * l->lanes + 4 * j, 4 * sizeof(float));
    }
    g->eigen = gl_texture_2d(GL_RGBA32F, columns, g->chunks, GL_RGBA, GL_FLOAT, eigen);
    g->mvm = gl_texture_2d(GL_RGBA32F, v->num_curvatures, g->chunks, GL_RGBA, GL_FLOAT, mvm);
    free(eigen);
    free(mvm);
    *memory += (size_t)width * height * 8 + ((size_t)columns + v->num_curvatures) * l->lanes * 4;
    return gl_check_upload(ctx, object, "vdm: the table");
}

meso_result gl_vdm_bake(meso_context *ctx, const meso_object *object,
                        const meso_technique_info *info, const double *options, gl_vdm_table *out) {
    memset(out, 0, sizeof *out);
    const meso_heightfield *hf = object->mesostructure.height_field;
    if (gl_option_value(info, options, "compressed") == 0.0)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: vdm: compressed 0 (the raw 5D table) is drawn on the CPU only",
                              object->name);
    float tile = meso_mesh_tile_length(object->mesh);
    if (!hf || !(tile > 0.0f))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: vdm needs a height field and texture coordinates with area",
                              object->name);
    float depth_tiles = object->mesostructure.depth / tile;
    if (!(depth_tiles > 0.0f && depth_tiles <= 16.0f))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: mesostructure.depth: %g is %g tiles; vdm needs (0, 16]",
                              object->name, object->mesostructure.depth, depth_tiles);
    /* the CPU technique's bake (vdm.c, vdm_prepare): at least the paper's 8 + 4 kept, so both
     * back ends and renders with fewer share one cached bake */
    int k = (int)gl_option_value(info, options, "eigenfunctions");
    int m = (int)gl_option_value(info, options, "mvm_eigenfunctions");
    int resolution = (int)gl_option_value(info, options, "resolution");
    meso_vdm_desc desc = {.heightfield = hf,
                          .depth = depth_tiles,
                          .width = resolution,
                          .height = resolution,
                          .num_theta = (int)gl_option_value(info, options, "num_theta"),
                          .num_phi = (int)gl_option_value(info, options, "num_phi"),
                          .num_curvatures = (int)gl_option_value(info, options, "num_curvatures"),
                          .vdm_eigenfunctions = k > 8 ? k : 8,
                          .mvm_eigenfunctions = m > 4 ? m : 4};
    int rank = desc.num_theta * desc.num_curvatures + desc.num_curvatures;
    int rows = resolution * resolution * desc.num_phi;
    rank = rank < rows ? rank : rows;
    if (desc.vdm_eigenfunctions > rank) desc.vdm_eigenfunctions = rank;
    if (desc.mvm_eigenfunctions > rank) desc.mvm_eigenfunctions = rank;
    if (k > rank || m > rank)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: technique_options.eigenfunctions: at most %d for this table",
                              object->name, rank);
    meso_result r = meso_vdm_bake_cached(ctx, &desc, &out->vdm);
    if (r == MESO_OK) {
        out->view = meso_vdm_get_view(out->vdm);
        r = meso_vdm_lanes_init(ctx, &out->view, k, m,
                                gl_option_value(info, options, "mipmap") != 0.0, object->name,
                                &out->lanes);
    }
    if (r != MESO_OK) {
        gl_vdm_table_release(out);
        return r;
    }
    out->k = k;
    out->m = m;
    out->tile_world = tile;
    out->depth_tiles = depth_tiles;
    return MESO_OK;
}

void gl_vdm_table_release(gl_vdm_table *table) {
    meso_vdm_lanes_deinit(&table->lanes);
    meso_vdm_destroy(table->vdm);
    memset(table, 0, sizeof *table);
}

meso_result gl_vdm_create(meso_context *ctx, const meso_scene *scene, const meso_object *object,
                          const meso_technique_info *info, const double *options, void **out,
                          size_t *memory) {
    (void)scene;
    *out = NULL;
    gl_vdm_table table;
    meso_result r = gl_vdm_bake(ctx, object, info, options, &table);
    if (r != MESO_OK) return r;
    gl_vdm *g = calloc(1, sizeof *g);
    r = g ? upload(ctx, object, &table.view, &table.lanes, g, memory)
          : meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", object->name);
    if (r == MESO_OK) {
        const meso_mesh *mesh = object->mesh;
        g->curvature_min = table.view.curvature_min;
        g->curvature_max = table.view.curvature_max;
        g->tile_world = table.tile_world;
        g->depth_tiles = table.depth_tiles;
        g->has_curvature = mesh->curvature_max && mesh->curvature_min && mesh->curvature_dir_max &&
                           mesh->curvature_dir_min;
        *out = g;
        g = NULL;
    }
    gl_vdm_table_release(&table);
    gl_vdm_destroy(g);
    return r;
}

void gl_vdm_bind(const void *data, GLuint program, float pixel_size) {
    const gl_vdm *g = data;
    glActiveTexture(GL_TEXTURE2);
    glBindTexture(GL_TEXTURE_2D, g->weights);
    glActiveTexture(GL_TEXTURE3);
    glBindTexture(GL_TEXTURE_2D, g->eigen);
    glActiveTexture(GL_TEXTURE4);
    glBindTexture(GL_TEXTURE_2D, g->mvm);
    glUniform1i(glGetUniformLocation(program, "u_vdm_weights"), 2);
    glUniform1i(glGetUniformLocation(program, "u_vdm_eigen"), 3);
    glUniform1i(glGetUniformLocation(program, "u_mvm_eigen"), 4);
    glUniform1i(glGetUniformLocation(program, "u_vdm_chunks"), g->chunks);
    glUniform1i(glGetUniformLocation(program, "u_vdm_levels"), g->num_levels);
    glUniform2iv(glGetUniformLocation(program, "u_vdm_level_size"), g->num_levels,
                 &g->level_size[0][0]);
    glUniform1iv(glGetUniformLocation(program, "u_vdm_level_row"), g->num_levels, g->level_row);
    glUniform2f(glGetUniformLocation(program, "u_curvature_range"), g->curvature_min,
                g->curvature_max);
    glUniform1f(glGetUniformLocation(program, "u_tile_world"), g->tile_world);
    glUniform1f(glGetUniformLocation(program, "u_depth_tiles"), g->depth_tiles);
    glUniform1f(glGetUniformLocation(program, "u_pixel_size"), pixel_size);
    glUniform1i(glGetUniformLocation(program, "u_has_curvature"), g->has_curvature);
}

void gl_vdm_destroy(void *data) {
    gl_vdm *g = data;
    if (!g) return;
    if (g->weights) glDeleteTextures(1, &g->weights);
    if (g->eigen) glDeleteTextures(1, &g->eigen);
    if (g->mvm) glDeleteTextures(1, &g->mvm);
    free(g);
}
