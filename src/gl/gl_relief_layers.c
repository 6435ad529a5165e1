/* The GL side of `relief_layers` (shaders/relief_layers.frag): the CPU technique's bake (the
 * cache's multilayer map for the same options, meso_layers_bake_cached) and for solids its
 * mirror, as RGBA32F texture arrays (depths, normals' x, y in groups of four layers) and R32F
 * layer counts; the options whose value 0 (or -1) means "automatic" resolved as relief_layers.c
 * resolves them. */
#include <stdlib.h>
#include <string.h>

#include "meso/bake_layers.h"
#include "meso/runtime.h"

#include "gl_internal.h"

typedef struct gl_layer_maps {
    GLuint maps, count;
} gl_layer_maps;

typedef struct gl_layers {
    gl_layer_maps above, below; /* below.maps == 0: no back faces (a height field) */
    int num_layers, groups, width, height, linear_steps;
    bool clamp, heightfield, impostor, enclosed;
} gl_layers;

static meso_result upload_map(meso_context *ctx, const meso_object *object, const meso_layers *map,
                              int num_layers, int groups, gl_layer_maps *out, size_t *memory) {
    int W = map->width, H = map->height, L = map->num_layers;
    size_t texels = (size_t)W * H;
    float *planes = malloc(texels * 4 * (size_t)(3 * groups) * sizeof(float));
    float *count = malloc(texels * sizeof(float));
    if (!planes || !count) {
        free(planes);
        free(count);
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", object->name);
    }
    for (int g = 0; g < groups; g++)
        for (size_t i = 0; i < texels; i++)
            for (int c = 0; c < 4; c++) {
                int k = 4 * g + c;
                bool used = k < L && k < num_layers;
                size_t slot = i * (size_t)L + (size_t)k;
                /* unused: depth 1.0, as in the map */
                planes[((size_t)g * texels + i) * 4 + c] = used ? map->depth[slot] : 1.0f;
                planes[((size_t)(groups + g) * texels + i) * 4 + c] =
                    used && map->normal_x ? map->normal_x[slot] : 0.0f;
                planes[((size_t)(2 * groups + g) * texels + i) * 4 + c] =
                    used && map->normal_y ? map->normal_y[slot] : 0.0f;
            }
    for (size_t i = 0; i < texels; i++) count[i] = (float)map->count[i];
    glGenTextures(1, &out->maps);
    glBindTexture(GL_TEXTURE_2D_ARRAY, out->maps);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTexImage3D(GL_TEXTURE_2D_ARRAY, 0, GL_RGBA32F, W, H, 3 * groups, 0, GL_RGBA, GL_FLOAT,
                 planes);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAX_LEVEL, 0);
    out->count = gl_texture_2d(GL_R32F, W, H, GL_RED, GL_FLOAT, count);
    free(planes);
    free(count);
    *memory += texels * (4 * (size_t)(3 * groups) + 1) * sizeof(float);
    return gl_check_upload(ctx, object, "relief_layers: the map");
}

meso_result gl_layers_bake(meso_context *ctx, const meso_object *object,
                           const meso_technique_info *info, const double *options,
                           gl_layers_maps *out) {
    memset(out, 0, sizeof *out);
    const meso_mesostructure *m = &object->mesostructure;
    bool solid = m->kind == MESO_MESOSTRUCTURE_SOLID && m->solid;
    /* relief_layers.c, prepare: an impostor (§4, a whole model on one quad) takes a finer map
     * and search; float by default on height fields */
    bool impostor = solid && !meso_solid_is_periodic(m->solid);
    int size = (int)gl_option_value(info, options, "size");
    int as_float = (int)gl_option_value(info, options, "float");
    int linear_steps = (int)gl_option_value(info, options, "linear_steps");
    int layers = (int)gl_option_value(info, options, "layers");
    int side = size > 0 ? size : (impostor ? 512 : 256);
    if (as_float < 0) as_float = m->kind == MESO_MESOSTRUCTURE_HEIGHT_FIELD;
    if (side < 16 || (layers != 4 && layers != 8))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: relief_layers: size %d (at least 16) or layers %d (4 or 8)",
                              object->name, side, layers);
    meso_layers_desc desc = {.num_layers = layers,
                             .format = as_float ? MESO_LAYERS_FORMAT_F32 : MESO_LAYERS_FORMAT_U8};
    if (solid) {
        desc.solid = m->solid;
        desc.width = desc.height = side;
    } else if (m->kind == MESO_MESOSTRUCTURE_HEIGHT_FIELD && m->height_field) {
        desc.heightfield = m->height_field;
    } else {
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: mesostructure: a solid or a height field is required "
                              "(relief_layers)",
                              object->name);
    }
    meso_result r = meso_layers_bake_cached(ctx, &desc, &out->map);
    if (r == MESO_OK && !out->map->from_heightfield)
        r = meso_layers_mirror(ctx, out->map, &out->mirrored);
    if (r != MESO_OK) {
        gl_layers_maps_release(out);
        return r;
    }
    if (solid && m->wrap == MESO_WRAP_CLAMP) out->map->wrap = MESO_WRAP_CLAMP;
    out->num_layers = out->map->max_count > 0 ? out->map->max_count : 1;
    out->linear_steps = linear_steps > 0 ? linear_steps : (impostor ? 64 : 32);
    out->impostor = impostor;
    out->enclosed = solid && !impostor;
    return MESO_OK;
}

void gl_layers_maps_release(gl_layers_maps *maps) {
    meso_layers_destroy(maps->map);
    meso_layers_destroy(maps->mirrored);
    memset(maps, 0, sizeof *maps);
}

meso_result gl_layers_create(meso_context *ctx, const meso_scene *scene, const meso_object *object,
                             const meso_technique_info *info, const double *options, void **out,
                             size_t *memory) {
    (void)scene;
    *out = NULL;
    gl_layers_maps maps;
    meso_result r = gl_layers_bake(ctx, object, info, options, &maps);
    if (r != MESO_OK) return r;
    gl_layers *g = calloc(1, sizeof *g);
    if (!g) {
        gl_layers_maps_release(&maps);
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", object->name);
    }
    g->num_layers = maps.num_layers;
    g->groups = (g->num_layers + 3) / 4;
    g->width = maps.map->width;
    g->height = maps.map->height;
    g->clamp = maps.map->wrap == MESO_WRAP_CLAMP;
    g->heightfield = maps.map->from_heightfield;
    g->linear_steps = maps.linear_steps;
    g->impostor = maps.impostor;
    g->enclosed = maps.enclosed;
    r = upload_map(ctx, object, maps.map, g->num_layers, g->groups, &g->above, memory);
    if (r == MESO_OK && maps.mirrored)
        r = upload_map(ctx, object, maps.mirrored, g->num_layers, g->groups, &g->below, memory);
    gl_layers_maps_release(&maps);
    if (r != MESO_OK) {
        gl_layers_destroy(g);
        return r;
    }
    *out = g;
    return MESO_OK;
}

void gl_layers_bind(const void *data, GLuint program, float pixel_size) {
    (void)pixel_size;
    const gl_layers *g = data;
    const GLuint units[4] = {g->above.maps, g->above.count, g->below.maps, g->below.count};
    const char *names[4] = {"u_layer_maps", "u_layer_count", "u_layer_maps_below",
                            "u_layer_count_below"};
    for (int i = 0; i < 4; i++) {
        glActiveTexture(GL_TEXTURE2 + (GLenum)i);
        glBindTexture(i % 2 == 0 ? GL_TEXTURE_2D_ARRAY : GL_TEXTURE_2D, units[i]);
        glUniform1i(glGetUniformLocation(program, names[i]), 2 + i);
    }
    glUniform1i(glGetUniformLocation(program, "u_linear_steps"), g->linear_steps);
    glUniform1i(glGetUniformLocation(program, "u_num_layers"), g->num_layers);
    glUniform1i(glGetUniformLocation(program, "u_layer_groups"), g->groups);
    glUniform2i(glGetUniformLocation(program, "u_layer_size"), g->width, g->height);
    /* the relief family's texel-centre coordinates are the map's (a height field's map has the
     * field's size; a solid has no u_height) */
    glUniform2i(glGetUniformLocation(program, "u_height_size"), g->width, g->height);
    glUniform1i(glGetUniformLocation(program, "u_height_clamp"), g->clamp);
    glUniform1i(glGetUniformLocation(program, "u_layer_clamp"), g->clamp);
    glUniform1i(glGetUniformLocation(program, "u_layer_heightfield"), g->heightfield);
    glUniform1i(glGetUniformLocation(program, "u_impostor"), g->impostor);
    glUniform1i(glGetUniformLocation(program, "u_enclosed"), g->enclosed);
    glUniform1i(glGetUniformLocation(program, "u_has_below"), g->below.maps != 0);
}

void gl_layers_destroy(void *data) {
    gl_layers *g = data;
    if (!g) return;
    GLuint textures[4] = {g->above.maps, g->above.count, g->below.maps, g->below.count};
    for (int i = 0; i < 4; i++)
        if (textures[i]) glDeleteTextures(1, &textures[i]);
    free(g);
}
