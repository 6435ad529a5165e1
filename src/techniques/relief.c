/* relief: relief mapping (Policarpo, Oliveira, Comba 2005, as summarised in Policarpo &
 * Oliveira 2006 §2.1 and its Appendix A): the view ray in tangent space, a linear search then a
 * binary search over the bilinear depth, shading with the normal at the hit, self-shadows by a
 * second linear search toward each light, depth correction, and silhouettes with per-vertex
 * quadrics (Oliveira & Policarpo 2005). The shared code is in relief_common.h; this file holds
 * the options and the linear + binary search; with `shell` 1 the search runs along the ray's
 * path through the prism shell (relief_shell.h). docs/techniques/relief.md. */
#include "relief_shell.h"
#include "meso/bake_minmax.h"
#include "meso/runtime.h"

typedef struct relief_options {
    int linear_steps, binary_steps, shadow_steps;
    bool shadows, silhouettes, shell;
} relief_options;

static const meso_technique_option relief_option_table[] = {
    MESO_OPTION_ROW(MESO_OPTION_INT, linear_steps, 1, 1024, 16,
                    "steps of the linear search along the view ray (App. A)", relief_options,
                    linear_steps),
    MESO_OPTION_ROW(MESO_OPTION_INT, binary_steps, 0, 32, 6,
                    "steps of the binary search after the linear one", relief_options,
                    binary_steps),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, shadows, 0, 1, 1,
                    "self-shadows: a second linear search toward each light", relief_options,
                    shadows),
    MESO_OPTION_ROW(MESO_OPTION_INT, shadow_steps, 1, 1024, 16, "steps of the shadow search",
                    relief_options, shadow_steps),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, silhouettes, 0, 1, 1,
                    "silhouettes from per-vertex quadrics (Oliveira & Policarpo 2005)",
                    relief_options, silhouettes),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, shell, 0, 1, 0,
                    "1: the searches run along the ray's path through the prism shell, prism by "
                    "prism (exact on curved surfaces, side bands at open borders, silhouettes "
                    "from the shell; CPU only); 0: a straight ray in the pixel's tangent space",
                    relief_options, shell),
};

typedef struct relief_state {
    relief_heights heights;
    /* bounds the shadow rays' footprints so lit lanes skip the search (relief_shadow_clear8) */
    meso_minmax_pyramid *pyramid;
    relief_maxmip maxmip;
    relief_options options;
    relief_params params;
    relief_shell *shell; /* the shell option; NULL: off */
} relief_state;

static void release(void *state) {
    relief_state *s = state;
    if (!s) return;
    relief_heights_deinit(&s->heights);
    meso_minmax_pyramid_destroy(s->pyramid);
    relief_shell_destroy(s->shell);
    free(s);
}

static meso_result prepare(meso_context *ctx, const meso_scene *scene, const meso_object *object,
                           void **out_state) {
    *out_state = NULL;
    relief_state *s = calloc(1, sizeof *s);
    if (!s) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", object->name);
    meso_result r;
    if ((r = meso_technique_options_read(ctx, scene, object, &meso_technique_relief.info,
                                         &s->options)) != MESO_OK ||
        (r = relief_heights_init(ctx, object, &s->heights)) != MESO_OK)
        goto fail;
    if (s->options.shadows && (r = meso_minmax_pyramid_bake(ctx, object->mesostructure.height_field,
                                                            &s->pyramid)) != MESO_OK)
        goto fail;
    if (s->pyramid) relief_maxmip_init(s->pyramid, &s->maxmip);
    s->params.shadows = s->options.shadows;
    s->params.silhouettes = s->options.silhouettes;
    if ((r = relief_domain_init(ctx, object, &s->params.domain)) != MESO_OK ||
        (s->options.shell &&
         (r = relief_shell_create(ctx, object, "relief", &s->shell)) != MESO_OK))
        goto fail;
    *out_state = s;
    return MESO_OK;
fail:
    release(s);
    return r;
}

static void search(const void *user, const relief_batch *batches, int count, v8f *out_t,
                   int *out_hit) {
    const relief_state *s = user;
    relief_search8x2(&s->heights, batches, count, s->options.linear_steps, s->options.binary_steps,
                     out_t, out_hit);
}

static void shadow(const void *user, const relief_shadow_batch *batches, int count,
                   int *out_blocked) {
    const relief_state *s = user;
    for (int g = 0; g < count; ++g) {
        relief_shadow_batch b = batches[g];
        if (b.active_bits && s->pyramid)
            b.active_bits &= ~relief_shadow_clear8(&s->maxmip, &s->heights, &b);
        out_blocked[g] =
            b.active_bits ? relief_shadow_search8(&s->heights, &b, s->options.shadow_steps) : 0;
    }
}

/* ---- On the shell (relief_shell.h): the same search along each prism's stretch ---------- */

static bool shell_inside(const void *user, float x, float y, float d, float *out_f) {
    return relief_shell_heights_inside(&((const relief_state *)user)->heights, x, y, d, out_f);
}

static int shell_inside8(const void *user, const v8f *x, const v8f *y, const v8f *d, v8f *out_f) {
    return relief_shell_heights_inside8(&((const relief_state *)user)->heights, *x, *y, *d, out_f);
}

static meso_vec3 shell_normal(const void *user, float x, float y, float d, bool upward,
                              const relief_shell_frame *f) {
    (void)d, (void)upward;
    return relief_shell_heights_normal(&((const relief_state *)user)->heights, x, y, f);
}

static relief_shell_search shell_search(const relief_state *s) {
    return (relief_shell_search){.user = s,
                                 .width = s->heights.width,
                                 .height = s->heights.height,
                                 .inside = shell_inside,
                                 .inside8 = shell_inside8,
                                 .normal = shell_normal,
                                 .linear_steps = s->options.linear_steps,
                                 .binary_steps = s->options.binary_steps,
                                 .shadow_steps = s->options.shadow_steps,
                                 .shadows = s->options.shadows,
                                 .floor_solid = true,
                                 .shadow_bias = RELIEF_SHADOW_BIAS};
}

static meso_result geometry(meso_context *ctx, void *state, const meso_frame *frame,
                            const meso_mesh **out_mesh) {
    (void)ctx;
    relief_state *s = state;
    *out_mesh = s->shell ? relief_shell_geometry(s->shell, frame) : NULL;
    return MESO_OK;
}

__attribute__((always_inline)) static inline void
shade_either(const relief_state *s, const meso_frame *frame, const meso_object *object,
             meso_fragment *fragments, meso_fragment_block *block, size_t count) {
    relief_shell_search q = shell_search(s);
    relief_tracer tracer = {s, search, shadow, NULL};
    relief_shade_shell_or_ray(s->shell, &q, &s->heights, &tracer, s->params, frame, object,
                              fragments, block, count);
}

static void shade(const void *state, const meso_frame *frame, const meso_object *object,
                  meso_fragment *fragments, size_t count) {
    shade_either(state, frame, object, fragments, NULL, count);
}

/* The rasterizer's blocks straight to the shared loop (no adapter copies); the same images
 * as shade. */
static void shade_block(const void *state, const meso_frame *frame, const meso_object *object,
                        meso_fragment_block *block) {
    shade_either(state, frame, object, NULL, block, block->count);
}

static size_t memory(const void *state) {
    const relief_state *s = state;
    return s ? relief_heights_memory(&s->heights) + meso_minmax_pyramid_memory(s->pyramid) +
                   relief_shell_memory(s->shell)
             : 0;
}

const meso_technique meso_technique_relief = {
    .info = {.name = "relief",
             .summary = "relief mapping: linear + binary search, self-shadows, silhouettes",
             .paper = "Policarpo & Oliveira 2006, §2.1 and Appendix A",
             .kind = MESO_TECHNIQUE_PER_PIXEL,
             .accepts = MESO_TECHNIQUE_ACCEPTS_HEIGHT_FIELD,
             .options = relief_option_table,
             .num_options = MESO_OPTION_COUNT(relief_option_table)},
    .prepare = prepare,
    .release = release,
    .geometry = geometry,
    .shade = shade,
    .shade_block = shade_block,
    .memory = memory,
};
