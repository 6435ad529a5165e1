/* The GL side of `relief_exact` (shaders/relief_exact.frag): the height field's maximum
 * mip-map (meso_minmax_pyramid_bake, the CPU technique's pyramid) as the mip levels of one R32F
 * texture. */
#include <stdlib.h>

#include "meso/bake_minmax.h"
#include "meso/runtime.h"

#include "gl_internal.h"

typedef struct gl_max_mip {
    GLuint texture;
    int levels;
} gl_max_mip;

static meso_result max_mip_upload(meso_context *ctx, const meso_object *object, GLuint *out_texture,
                                  int *out_levels, size_t *memory) {
    const meso_heightfield *hf = object->mesostructure.height_field;
    int w = hf ? hf->width : 0, h = hf ? hf->height : 0;
    if (hf && hf->wrap != MESO_WRAP_CLAMP && ((w & (w - 1)) != 0 || (h & (h - 1)) != 0))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: relief_exact on the GL needs a height field of power-of-two "
                              "sides (this one is %d x %d)",
                              object->name, w, h);
    meso_minmax_pyramid *pyramid = NULL;
    meso_result r = meso_minmax_pyramid_bake(ctx, hf, &pyramid);
    if (r != MESO_OK) return r;
    glGenTextures(1, out_texture);
    glBindTexture(GL_TEXTURE_2D, *out_texture);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    for (int l = 0; l < pyramid->num_levels; l++) {
        const meso_minmax_level *level = &pyramid->levels[l];
        /* a power-of-two pyramid halves like a GL mip chain; a clamp field's is not read */
        glTexImage2D(GL_TEXTURE_2D, l, GL_R32F, level->width, level->height, 0, GL_RED, GL_FLOAT,
                     level->max);
        *memory += (size_t)level->width * (size_t)level->height * sizeof(float);
    }
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST_MIPMAP_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_BASE_LEVEL, 0);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, pyramid->num_levels - 1);
    *out_levels = pyramid->num_levels;
    meso_minmax_pyramid_destroy(pyramid);
    return gl_check_upload(ctx, object, "relief_exact: the maximum mip-map");
}

meso_result gl_max_mip_create(meso_context *ctx, const meso_scene *scene, const meso_object *object,
                              const meso_technique_info *info, const double *options, void **out,
                              size_t *memory) {
    (void)scene;
    (void)info;
    (void)options;
    *out = NULL;
    gl_max_mip *m = calloc(1, sizeof *m);
    if (!m) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", object->name);
    meso_result r = max_mip_upload(ctx, object, &m->texture, &m->levels, memory);
    if (r != MESO_OK) {
        gl_max_mip_destroy(m);
        return r;
    }
    *out = m;
    return MESO_OK;
}

void gl_max_mip_bind(const void *data, GLuint program, float pixel_size) {
    (void)pixel_size;
    const gl_max_mip *m = data;
    glActiveTexture(GL_TEXTURE2);
    glBindTexture(GL_TEXTURE_2D, m->texture);
    glUniform1i(glGetUniformLocation(program, "u_max_mip"), 2);
    glUniform1i(glGetUniformLocation(program, "u_max_mip_levels"), m->levels);
}

void gl_max_mip_destroy(void *data) {
    gl_max_mip *m = data;
    if (!m) return;
    if (m->texture) glDeleteTextures(1, &m->texture);
    free(m);
}
