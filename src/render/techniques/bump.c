/* bump: Blinn 1978, "Simulation of wrinkled surfaces": the shading normal of the displaced
 * surface P' = P - (1 - h) depth N from the height field's gradient; the geometry stays flat,
 * so there is no parallax, no self-shadowing and no silhouette (docs/techniques/bump.md). */
#include "render_internal.h"

static meso_result bump_prepare(meso_context *ctx, const meso_scene *scene,
                                const meso_object *object, void **out_state) {
    (void)scene;
    *out_state = NULL;
    /* no options: any setting for it is an error naming its key */
    return meso_technique_options_read(ctx, scene, object, &meso_technique_bump.info, NULL);
}

static void bump_release(void *state) { (void)state; }

static void bump_shade(const void *state, const meso_frame *frame, const meso_object *object,
                       meso_fragment *fragments, size_t count) {
    (void)state;
    const meso_heightfield *hf = object->mesostructure.height_field;
    float depth = object->mesostructure.depth;
    for (size_t i = 0; hf && i < count; i++) {
        meso_fragment *f = &fragments[i];
        /* Blinn 1978: the perturbed normal from dh/du, dh/dv; the fragment's normal is its
         * own scratch once shading starts */
        meso_vec2 g = meso_heightfield_gradient(hf, f->uv.x, f->uv.y);
        f->normal = meso_displaced_normal(f->normal, f->tangent, f->bitangent, depth, g);
    }
    meso_shade_fragments(frame, object, fragments, count, NULL);
}

const meso_technique meso_technique_bump = {
    .info = {.name = "bump",
             .summary = "normals perturbed by the height field's gradient (shading only)",
             .paper = "Blinn 1978, Simulation of Wrinkled Surfaces",
             .kind = MESO_TECHNIQUE_PER_PIXEL,
             .accepts = MESO_TECHNIQUE_ACCEPTS_HEIGHT_FIELD},
    .prepare = bump_prepare,
    .release = bump_release,
    .shade = bump_shade,
};
