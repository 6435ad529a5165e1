/* The GL side of `relief_exact` (shaders/relief_exact.frag): the height field's maximum
 * mip-map (meso_bake_minmax, the CPU technique's pyramid) as the mip levels of one R32F
 * texture. */
#include "meso/bake_minmax.h"

#include "gl_internal.h"

meso_result gl_max_mip_create(meso_context *ctx, const meso_object *object, GLuint *out_texture,
                              int *out_levels, size_t *memory) {
    *out_texture = 0;
    *out_levels = 0;
    const meso_heightfield *hf = object->mesostructure.height_field;
    int w = hf ? hf->width : 0, h = hf ? hf->height : 0;
    if (hf && hf->wrap != MESO_WRAP_CLAMP && ((w & (w - 1)) != 0 || (h & (h - 1)) != 0))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: relief_exact on the GL needs a height field of power-of-two "
                              "sides (this one is %d x %d)",
                              object->name, w, h);
    meso_minmax_pyramid *pyramid = NULL;
    meso_result r = meso_bake_minmax(ctx, hf, &pyramid);
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
