/* parallax: parallax mapping (Kaneko et al. 2001, "Detailed shape representation with parallax
 * mapping", §3): each pixel's texture coordinates are shifted along the view direction by
 * u' = u + tan(theta_u) depth(u, v), v' = v + tan(theta_v) depth(u, v) (§3.1), with the depth
 * read at the unshifted coordinates, depth(u, v) ~ depth(u', v') (§3.2). Option
 * `offset_limiting` (Welsh 2004, "Parallax mapping with offset limiting") drops the division by
 * cos(theta) so the shift never exceeds the depth: no swimming at grazing angles, less parallax.
 * No self-shadow, no silhouette, no depth correction: that is the method.
 * docs/techniques/parallax.md. */
#include "relief_common.h"
#include "meso/runtime.h"

typedef struct parallax_options {
    bool offset_limiting;
} parallax_options;

static const meso_technique_option parallax_option_table[] = {
    MESO_OPTION_ROW(MESO_OPTION_BOOL, offset_limiting, 0, 1, 0,
                    "Welsh 2004: no division by cos(theta), the shift never exceeds the depth",
                    parallax_options, offset_limiting),
};

typedef struct parallax_state {
    relief_heights heights;
    bool offset_limiting;
} parallax_state;

static void release(void *state) {
    parallax_state *s = state;
    if (!s) return;
    relief_heights_deinit(&s->heights);
    free(s);
}

static meso_result prepare(meso_context *ctx, const meso_scene *scene, const meso_object *object,
                           void **out_state) {
    *out_state = NULL;
    parallax_options options;
    meso_result r =
        meso_technique_options_read(ctx, scene, object, &meso_technique_parallax.info, &options);
    if (r != MESO_OK) return r;
    parallax_state *s = calloc(1, sizeof *s);
    if (!s) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", object->name);
    if ((r = relief_heights_init(ctx, object, &s->heights)) != MESO_OK) {
        release(s);
        return r;
    }
    s->offset_limiting = options.offset_limiting;
    *out_state = s;
    return MESO_OK;
}

/* Whole blocks (render_internal.h): eight lanes at a time straight from the rasterizer's
 * arrays to the shading model, RELIEF_SHADE_GROUPS groups a call of the shading. */
static void shade_block(const void *state, const meso_frame *frame, const meso_object *object,
                        meso_fragment_block *block) {
    const parallax_state *s = state;
    const relief_heights *m = &s->heights;
    float depth = object->mesostructure.depth;
    meso_shade_batch batches[RELIEF_SHADE_GROUPS];
    /* no shadows: every light visible, set once a slot rather than once a group */
    for (size_t g = 0; g < RELIEF_SHADE_GROUPS; g++)
        meso_shade_batch_all_visible(&batches[g], frame);
    /* the shading reads the tangents for a normal map only (meso_shade_batch) */
    bool tangents = object->material.normal_map != NULL;
    size_t groups = 0, group_first = 0;
    for (size_t first = 0; first < block->count; first += RELIEF_LANES) {
        if (groups == RELIEF_SHADE_GROUPS) {
            meso_shade_batches_to_block(frame, object, batches, groups, block, group_first);
            groups = 0;
        }
        if (!groups) group_first = first;
        relief_lanes l;
        relief_lanes_load_block(&l, frame, block, first);
        v8f x, y;
        relief_lanes_texel(m, &l, &x, &y);
        v8f cu = v8_dot(l.view, l.bn), cv = v8_dot(l.view, l.nt), cn = v8_dot(l.view, l.tb);
        /* §3.1: tan(theta_u) = (view along u) / (view along -N), in uv per world depth; with
         * offset limiting, per unit length of the view ray instead. */
        v8f along = s->offset_limiting ? v8_sqrt(v8_dot(l.view, l.view)) : -cn;
        v8i on = v8_mask_from_bits(depth > 0.0f ? v8_mask_bits(cn < 0.0f) & l.frame_bits : 0);
        v8f scale = v8_select(on, depth / v8_select(on, along, v8_splat(1.0f)), v8_splat(0.0f));
        /* §3.2: the depth read at the unshifted coordinates stands for the shifted point's. */
        v8f d = 1.0f - relief_sample8_loads(m, x, y);
        v8f uo = cu * scale * d, vo = cv * scale * d;
        v8f gu, gv;
        relief_gradient8(m, x + uo * (float)m->width, y - vo * (float)m->height, &gu, &gv);
        v8vec3 normal = relief_normal8(&l, depth, gu, gv);
        /* field by field: an initializer would also zero every light's visibility (a
         * 512-byte memset a group) */
        meso_shade_batch *in = &batches[groups++];
        in->px = l.position.x, in->py = l.position.y, in->pz = l.position.z;
        in->nx = normal.x, in->ny = normal.y, in->nz = normal.z;
        in->u = l.u + uo, in->v = l.v + vo;
        if (tangents) {
            in->tx = l.tangent.x, in->ty = l.tangent.y, in->tz = l.tangent.z;
            in->bx = l.bitangent.x, in->by = l.bitangent.y, in->bz = l.bitangent.z;
        }
    }
    meso_shade_batches_to_block(frame, object, batches, groups, block, group_first);
}

static size_t memory(const void *state) {
    return state ? relief_heights_memory(&((const parallax_state *)state)->heights) : 0;
}

const meso_technique meso_technique_parallax = {
    .info = {.name = "parallax",
             .summary = "parallax mapping: one texture-coordinate shift along the view",
             .paper = "Kaneko et al. 2001, §3.1-3.4",
             .kind = MESO_TECHNIQUE_PER_PIXEL,
             .accepts = MESO_TECHNIQUE_ACCEPTS_HEIGHT_FIELD,
             .options = parallax_option_table,
             .num_options = MESO_OPTION_COUNT(parallax_option_table)},
    .prepare = prepare,
    .release = release,
    .shade_block = shade_block,
    /* reads the position, the tangent frame and uv; writes every colour */
    .skip_fields = MESO_FRAGMENT_SKIP_SAMPLE | MESO_FRAGMENT_SKIP_TRIANGLE |
                   MESO_FRAGMENT_SKIP_BARYCENTRICS | MESO_FRAGMENT_SKIP_COLOR_PRESET,
    .memory = memory,
};
