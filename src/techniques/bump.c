/* bump: Blinn 1978, "Simulation of wrinkled surfaces": the shading normal of the displaced
 * surface P' = P - (1 - h) depth N from the height field's gradient; the geometry stays flat,
 * so there is no parallax, no self-shadowing and no silhouette (docs/techniques/bump.md).
 * Eight fragments at a time on the relief family's padded height field, like parallax. */
#include "relief_common.h"
#include "meso/runtime.h"

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

/* Whole blocks (render_internal.h): eight lanes at a time straight from the rasterizer's
 * arrays to the shading model, RELIEF_SHADE_GROUPS groups a call of the shading. */
static void bump_shade_block(const void *state, const meso_frame *frame, const meso_object *object,
                             meso_fragment_block *block) {
    const bump_state *s = state;
    const relief_heights *m = &s->heights;
    float depth = object->mesostructure.depth;
    meso_shade_batch in[RELIEF_SHADE_GROUPS];
    /* no shadows: every light visible, set once a slot rather than once a group */
    for (size_t g = 0; g < RELIEF_SHADE_GROUPS; g++) meso_shade_batch_all_visible(&in[g], frame);
    for (size_t first = 0; first < block->count; first += RELIEF_SHADE_GROUPS * RELIEF_LANES) {
        size_t groups = 0;
        for (size_t at = first; at < block->count && groups < RELIEF_SHADE_GROUPS;
             at += RELIEF_LANES, groups++) {
            /* Blinn 1978: the perturbed normal from dh/du, dh/dv */
            relief_lanes l;
            v8f x, y;
            relief_lanes_load_block(&l, frame, block, at);
            relief_bump_inputs(m, depth, &l, &x, &y, &in[groups]);
        }
        meso_shade_batches_to_block(frame, object, in, groups, block, first);
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
    .shade_block = bump_shade_block,
    /* reads the position, the tangent frame and uv; writes every colour */
    .skip_fields = MESO_FRAGMENT_SKIP_SAMPLE | MESO_FRAGMENT_SKIP_TRIANGLE |
                   MESO_FRAGMENT_SKIP_BARYCENTRICS | MESO_FRAGMENT_SKIP_COLOR_PRESET,
    .memory = bump_memory,
};
