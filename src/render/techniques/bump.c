/* bump: Blinn 1978, "Simulation of wrinkled surfaces": the shading normal of the displaced
 * surface P' = P - (1 - h) depth N from the height field's gradient; the geometry stays flat,
 * so there is no parallax, no self-shadowing and no silhouette (docs/techniques/bump.md).
 * Eight fragments at a time on the relief family's padded height field, like parallax. */
#include "relief_common.h"

typedef struct bump_state {
    relief_heights heights;
} bump_state;

static void bump_release(void *state) {
    bump_state *s = state;
    if (!s) return;
    relief_heights_deinit(&s->heights);
    free(s);
}

static meso_result bump_prepare(meso_context *ctx, const meso_scene *scene,
                                const meso_object *object, void **out_state) {
    *out_state = NULL;
    /* no options: any setting for it is an error naming its key */
    meso_result r =
        meso_technique_options_read(ctx, scene, object, &meso_technique_bump.info, NULL);
    if (r != MESO_OK) return r;
    bump_state *s = calloc(1, sizeof *s);
    if (!s) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", object->name);
    if ((r = relief_heights_init(ctx, object, &s->heights)) != MESO_OK) {
        bump_release(s);
        return r;
    }
    *out_state = s;
    return MESO_OK;
}

static void bump_shade(const void *state, const meso_frame *frame, const meso_object *object,
                       meso_fragment *fragments, size_t count) {
    const bump_state *s = state;
    const relief_heights *m = &s->heights;
    float depth = object->mesostructure.depth;
    for (size_t start = 0; start < count; start += RELIEF_LANES) {
        int n = count - start < RELIEF_LANES ? (int)(count - start) : RELIEF_LANES;
        meso_fragment *f = fragments + start;
        /* Blinn 1978: the perturbed normal from dh/du, dh/dv */
        relief_lanes l;
        v8f x, y;
        meso_shade_batch in;
        relief_bump_lanes(m, frame, f, n, depth, &l, &x, &y, &in);
        relief_shade_store(frame, object, &in, f, n);
    }
}

static size_t bump_memory(const void *state) {
    return state ? relief_heights_memory(&((const bump_state *)state)->heights) : 0;
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
    .memory = bump_memory,
};
