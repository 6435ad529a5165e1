/* flat: the base mesh shaded with its smooth interpolated normal; the mesostructure is ignored.
 * The baseline every other technique improves on (docs/techniques/flat.md). */
#include "render_shading.h"

static meso_result flat_prepare(meso_context *ctx, const meso_scene *scene,
                                const meso_object *object, void **out_state) {
    (void)scene;
    *out_state = NULL;
    /* no options: any setting for it is an error naming its key */
    return meso_technique_options_read(ctx, scene, object, &meso_technique_flat.info, NULL);
}

static void flat_release(void *state) { (void)state; }

/* Whole blocks (render_internal.h): the rasterizer's lanes go to the shading model as they
 * are, no gather into eight-lane batches. */
static void flat_shade_block(const void *state, const meso_frame *frame, const meso_object *object,
                             meso_fragment_block *block) {
    (void)state;
    meso_shade_block(frame, object, block);
}

const meso_technique meso_technique_flat = {
    .info = {.name = "flat",
             .summary = "the base mesh with its interpolated normal, no mesostructure",
             .paper = "Gouraud 1971 / Phong 1975 smooth normals (baseline)",
             .kind = MESO_TECHNIQUE_PER_PIXEL,
             .accepts = MESO_TECHNIQUE_ACCEPTS_NONE | MESO_TECHNIQUE_ACCEPTS_HEIGHT_FIELD |
                        MESO_TECHNIQUE_ACCEPTS_SOLID | MESO_TECHNIQUE_ACCEPTS_MODEL_SOLID},
    .prepare = flat_prepare,
    .release = flat_release,
    .shade_block = flat_shade_block,
    /* reads the position, normal and uv (the tangents only for a normal map, which the
     * rasterizer fills anyway); writes every colour */
    .skip_fields = MESO_FRAGMENT_SKIP_SAMPLE | MESO_FRAGMENT_SKIP_TRIANGLE |
                   MESO_FRAGMENT_SKIP_BARYCENTRICS | MESO_FRAGMENT_SKIP_TANGENTS |
                   MESO_FRAGMENT_SKIP_COLOR_PRESET,
};
