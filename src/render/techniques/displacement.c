/* `displacement`: uniform tessellation of every base triangle into 4^L triangles whose vertices
 * are displaced by the height field (DESIGN.md: P' = P - (1 - h) depth N), rasterized with the
 * shared shading; the brute-force baseline of Doggett & Hirche 2000 ("Displacement Mapping":
 * base mesh + displacement map = displaced mesh) and of VDM §1. Self-shadowing by a shadow map
 * of the displaced mesh (displace_common.c). */
#include "displace_common.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The automatic level keeps the whole object under this many triangles. */
#define DISPLACEMENT_AUTO_BUDGET (1u << 21)
#define DISPLACEMENT_AUTO_MAX_LEVEL 9

typedef struct displacement_state {
    displace_surface surface;
    int level;
    displace_tessellator *tessellator;
    const meso_mesh *mesh; /* made on the first frame, kept: it does not depend on the view */
    displace_shadows shadows;
    displace_tess_stats stats;
} displacement_state;

typedef struct displacement_options {
    int level;
    displace_shadow_options shadows;
} displacement_options;

static const meso_technique_option displacement_option_table[] = {
    MESO_OPTION_ROW(MESO_OPTION_INT, level, -1, DISPLACE_MAX_LEVEL, -1,
                    "uniform subdivision level (4^level triangles a base triangle); -1: texel "
                    "density within the triangle budget",
                    displacement_options, level),
    DISPLACE_SHADOW_OPTION_ROWS(displacement_options, shadows),
};

/* Texel density (the longest base edge at about one texel) within the triangle budget. */
static int auto_level(const displace_surface *surface) {
    int level = displace_texel_level(surface, DISPLACEMENT_AUTO_MAX_LEVEL);
    while (level > 0 && (double)surface->base->num_triangles * pow(4.0, level) >
                            (double)DISPLACEMENT_AUTO_BUDGET)
        level--;
    return level;
}

static void displacement_release(void *state) {
    displacement_state *s = state;
    if (!s) return;
    displace_tessellator_destroy(s->tessellator);
    displace_shadows_release(&s->shadows);
    free(s);
}

static meso_result displacement_prepare(meso_context *ctx, const meso_scene *scene,
                                        const meso_object *object, void **out_state) {
    *out_state = NULL;
    displacement_options options;
    meso_result r = meso_technique_options_read(ctx, scene, object,
                                                &meso_technique_displacement.info, &options);
    if (r != MESO_OK) return r;
    displacement_state *s = calloc(1, sizeof(*s));
    if (!s) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: displacement", object->name);
    s->shadows.options = options.shadows;
    if ((r = displace_surface_init(ctx, object, &s->surface)) != MESO_OK) goto fail;
    s->level = options.level < 0 ? auto_level(&s->surface) : options.level;
    double triangles = (double)object->mesh->num_triangles * pow(4.0, s->level);
    if (triangles > (double)MESO_MESH_MAX_TRIANGLES) {
        r = meso_log_error(ctx, MESO_ERROR_LIMIT,
                           "%s: technique_options.level: %d makes %.0f triangles, above the "
                           "limit %u",
                           object->name, s->level, triangles, MESO_MESH_MAX_TRIANGLES);
        goto fail;
    }
    if ((r = displace_tessellator_create(ctx, &s->surface, s->level, &s->tessellator))) goto fail;
    *out_state = s;
    return MESO_OK;
fail:
    displacement_release(s);
    return r;
}

static meso_result displacement_geometry(meso_context *ctx, void *state, const meso_frame *frame,
                                         const meso_mesh **out_mesh) {
    displacement_state *s = state;
    *out_mesh = NULL;
    if (!s->mesh) {
        /* no edge tests: every midpoint on the grid of 2^level segments is inserted */
        double start = meso_time_seconds();
        meso_result r = displace_tessellator_run(ctx, s->tessellator, NULL, &s->mesh, &s->stats);
        if (r != MESO_OK) return r;
        double tessellated = meso_time_seconds();
        /* lights are static and so is the mesh: one shadow map for every frame */
        r = displace_shadows_render(ctx, &s->shadows, frame->scene, s->mesh);
        if (r != MESO_OK) {
            s->mesh = NULL;
            return r;
        }
        meso_log_info(ctx,
                      "%s: displacement: level %d, %llu triangles, %llu vertices "
                      "(tessellated in %.1f ms, shadow maps %d x %d in %.1f ms)",
                      s->surface.object->name, s->level, (unsigned long long)s->stats.triangles,
                      (unsigned long long)s->stats.vertices, 1e3 * (tessellated - start),
                      s->shadows.options.size, s->shadows.options.size, 1e3 * s->shadows.seconds);
    }
    *out_mesh = s->mesh;
    return MESO_OK;
}

static void displacement_shade(const void *state, const meso_frame *frame,
                               const meso_object *object, meso_fragment *fragments, size_t count) {
    (void)object;
    const displacement_state *s = state;
    displace_shade(&s->surface, &s->shadows, s->mesh, frame, fragments, count);
}

static size_t displacement_memory(const void *state) {
    const displacement_state *s = state;
    if (!s) return 0;
    return displace_tessellator_memory(s->tessellator) +
           (s->shadows.depth ? (size_t)s->shadows.num_lights * (size_t)s->shadows.options.size *
                                   (size_t)s->shadows.options.size * sizeof(float)
                             : 0);
}

const meso_technique meso_technique_displacement = {
    .info = {.name = "displacement",
             .summary = "uniform tessellation into 4^L displaced triangles, shadow-mapped",
             .paper = "Doggett & Hirche 2000, \"Displacement Mapping\" (uniform baseline)",
             .kind = MESO_TECHNIQUE_GEOMETRY,
             .accepts = MESO_TECHNIQUE_ACCEPTS_NONE | MESO_TECHNIQUE_ACCEPTS_HEIGHT_FIELD,
             .options = displacement_option_table,
             .num_options = MESO_OPTION_COUNT(displacement_option_table)},
    .prepare = displacement_prepare,
    .release = displacement_release,
    .geometry = displacement_geometry,
    .shade = displacement_shade,
    .memory = displacement_memory,
};
