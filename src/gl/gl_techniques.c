/* The GL back end's techniques: one row for each technique of technique_list.h, in its order
 * (the table below is built from that list, so a technique added there without a row here
 * fails to compile). A row says whether the back end draws the technique (it has
 * shaders/<name>.frag) and which per-object data it keeps (gl_internal.h, gl_technique). */
#include "gl_internal.h"

static const gl_technique gl_technique_flat = {.drawn = true};
static const gl_technique gl_technique_bump = {.drawn = true};
static const gl_technique gl_technique_horizon = {.drawn = false};
static const gl_technique gl_technique_parallax = {.drawn = true};
static const gl_technique gl_technique_relief = {.drawn = true};
static const gl_technique gl_technique_relief_exact = {.drawn = true,
                                                       .create = gl_max_mip_create,
                                                       .bind = gl_max_mip_bind,
                                                       .destroy = gl_max_mip_destroy};
static const gl_technique gl_technique_relief_layers = {.drawn = true,
                                                        .both_faces = true,
                                                        .create = gl_layers_create,
                                                        .bind = gl_layers_bind,
                                                        .destroy = gl_layers_destroy};
static const gl_technique gl_technique_vdm = {
    .drawn = true, .create = gl_vdm_create, .bind = gl_vdm_bind, .destroy = gl_vdm_destroy};
static const gl_technique gl_technique_gdm = {.drawn = true,
                                              .create = gl_gdm_create,
                                              .faces = gl_gdm_faces,
                                              .bind = gl_gdm_bind,
                                              .destroy = gl_gdm_destroy};
static const gl_technique gl_technique_tessellation = {.drawn = false};
static const gl_technique gl_technique_displacement = {.drawn = false};

static const gl_technique *const gl_techniques[] = {
#define MESO_TECHNIQUE(name) &gl_technique_##name,
#include "technique_list.h"
#undef MESO_TECHNIQUE
};
#define NUM_GL_TECHNIQUES (sizeof gl_techniques / sizeof gl_techniques[0])

const gl_technique *gl_technique_of(const meso_technique_info *info, size_t *out_index) {
    for (size_t i = 0; info && i < NUM_GL_TECHNIQUES; i++)
        if (meso_technique_get(i) == info) {
            if (out_index) *out_index = i;
            return gl_techniques[i];
        }
    return NULL;
}

bool meso_gl_technique_supported(const char *technique) {
    const gl_technique *gl = gl_technique_of(meso_technique_find(technique), NULL);
    return gl && gl->drawn;
}
