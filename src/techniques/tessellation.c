/* `tessellation`: adaptive view-dependent tessellation of displacement maps (Doggett & Hirche
 * 2000). Per base triangle and in any order, edges are halved recursively ("Adaptive
 * Tessellation": calculate edge midpoint, displace, transform, calculate surface normal,
 * conditionally insert, tessellate with the selected midpoints), where the "Edge Tests" say so:
 *
 *   surface detection (propose a midpoint)
 *     normal_test  "Surface Normal Variance Test": some component of the displaced surface
 *                  normal at the midpoint differs from that at an end point by more than
 *                  normal_threshold (high-frequency change);
 *     area_test    "Local Area Average Height Test": the mean height over a box around the
 *                  midpoint differs from the mean of the boxes around the end points by more than
 *                  area_threshold (height units), boxes from a summed-area table (low-frequency
 *                  change); each box has a radius of a quarter of the edge's length in texels,
 *                  so the three boxes tile the edge;
 *   recursion limits (veto a midpoint)
 *     view_test    "View Dependent Test": the screen-space Manhattan length of the displaced
 *                  edge is at most view_threshold samples (stops sub-pixel triangles); also
 *                  (an extension for "invisible triangles") base normals facing away from the
 *                  eye at both end points;
 *     limit_test   "Refinement Limit Test": the rounded texel coordinates of the midpoint equal
 *                  those of an end point (no new surface detail).
 *
 * insert = (normal OR area, or "yes" when neither is enabled) AND NOT vetoed by view or limit,
 * and nothing at all when every test is off (the base mesh). The vetoes are evaluated first,
 * before the midpoint is displaced, as they are the cheaper ones; the statistics count in that
 * order. Extension: edges longer than span_texels texels are proposed untested (three samples
 * cannot see detail between them). Crack-free by construction: a decision sees only the edge
 * (displace_common.h). Measured behaviour: docs/techniques/tessellation.md. */
#include "displace_common.h"
#include "displace_shade8.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "meso/bake_sat.h"
#include "meso/runtime.h"

enum {
    COUNT_EDGES,      /* edges evaluated (midpoints computed) */
    COUNT_LIMIT_VETO, /* refinement limit test rejected */
    COUNT_VIEW_VETO,  /* view dependent test rejected */
    COUNT_NORMAL_YES, /* normal test proposed */
    COUNT_AREA_YES,   /* area test proposed */
    COUNT_NO_DETAIL,  /* neither surface test proposed */
    COUNT_INSERTED,
    COUNT_SPAN_YES, /* longer than span_texels: proposed untested */
};

typedef struct tessellation_state {
    displace_surface surface;
    meso_sat *sat;
    int max_level;
    bool normal_test, area_test, view_test, limit_test;
    float normal_threshold, area_threshold, view_threshold, span_texels;
    bool both_faces; /* the option; surface.both_faces: and the surface is open */
    displace_tessellator *tessellator;
    const meso_mesh *mesh;
    displace_shadows shadows;
    /* shadow_tessellation 1: each light's map drawn from a tessellation seen from the light,
     * kept while the lights are unchanged; 0: from the camera's mesh, redrawn when the camera
     * or the target size changes (shadow_view_projection, shadow_width, shadow_height) */
    bool shadow_tessellation;
    float shadow_view_threshold; /* the light view's view_threshold, in shadow-map texels */
    displace_tess_stats shadow_stats;
    meso_mat4 shadow_view_projection;
    int shadow_width, shadow_height;
    displace_tess_stats stats;
} tessellation_state;

/* What the edge tests read during one frame, or while tessellating for a light's shadow map. */
typedef struct frame_tests {
    const tessellation_state *state;
    meso_mat4 view_projection;
    meso_vec3 eye;
    float width, height, z_near;
    float view_threshold;
    bool directional; /* an orthographic light view: `toward` instead of the eye */
    meso_vec3 toward; /* unit direction toward a directional light */
} frame_tests;

/* Read straight into the state. */
static const meso_technique_option tessellation_option_table[] = {
    MESO_OPTION_ROW(MESO_OPTION_INT, max_level, -1, DISPLACE_MAX_LEVEL, -1,
                    "deepest subdivision level; -1: down to texel density", tessellation_state,
                    max_level),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, normal_test, 0, 1, 1, "split where the normals differ",
                    tessellation_state, normal_test),
    MESO_OPTION_ROW(MESO_OPTION_FLOAT, normal_threshold, 0.0, 2.0, 0.2,
                    "1 - cos of the normal difference that splits an edge", tessellation_state,
                    normal_threshold),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, area_test, 0, 1, 1,
                    "split where the height varies under the edge (summed-area table)",
                    tessellation_state, area_test),
    MESO_OPTION_ROW(MESO_OPTION_FLOAT, area_threshold, 0.0, 1.0, 0.05,
                    "height variation that splits an edge", tessellation_state, area_threshold),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, view_test, 0, 1, 1, "split edges long on screen",
                    tessellation_state, view_test),
    MESO_OPTION_ROW(MESO_OPTION_FLOAT, view_threshold, 0.0, 1e6, 2.0,
                    "screen length in pixels above which an edge splits", tessellation_state,
                    view_threshold),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, limit_test, 0, 1, 1, "stop at texel density",
                    tessellation_state, limit_test),
    MESO_OPTION_ROW(MESO_OPTION_FLOAT, span_texels, 0.0, 1e6, 32.0,
                    "texels an edge may span before it splits whatever the tests say",
                    tessellation_state, span_texels),
    DISPLACE_BOTH_FACES_OPTION_ROW(tessellation_state, both_faces),
    DISPLACE_SHADOW_OPTION_ROWS(tessellation_state, shadows.options),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, shadow_tessellation, 0, 1, 0,
                    "shadow maps from a tessellation seen from each light, kept while the "
                    "lights stay; 0: from the camera's mesh, redrawn when the camera moves",
                    tessellation_state, shadow_tessellation),
    MESO_OPTION_ROW(MESO_OPTION_FLOAT, shadow_view_threshold, 0.0, 1e6, 2.0,
                    "view_threshold of the light's tessellation, in shadow-map texels",
                    tessellation_state, shadow_view_threshold),
};

/* "Calculate surface normal": once per vertex, kept for the base mesh's vertices. */
static void tests_vertex_static(const void *user, displace_vertex *v) {
    const frame_tests *ft = user;
    const tessellation_state *s = ft->state;
    if (s->normal_test && s->surface.heightfield) {
        /* the bump-map operation: the height field's gradient in the base frame */
        meso_vec2 g =
            displace_heightfield_gradient(s->surface.heightfield, v->texture_uv.x, v->texture_uv.y);
        v->surface_normal =
            meso_displaced_normal(v->unit_normal, v->tangent, v->bitangent, s->surface.depth, g);
    }
}

/* "Transform midpoint": once per vertex and frame (slides, "Hardware Architecture": vertices
 * are only transformed once). */
static void tests_vertex(const void *user, displace_vertex *v) {
    const frame_tests *ft = user;
    const tessellation_state *s = ft->state;
    if (!s->view_test) return;
    v->clip = meso_mat4_mul_vec4(ft->view_projection,
                                 (meso_vec4){v->position.x, v->position.y, v->position.z, 1});
    /* the view test's per-vertex inputs, once a vertex instead of once an edge */
    v->in_front = v->clip.w > ft->z_near * 0.5f;
    v->screen = (meso_vec2){v->clip.x / v->clip.w * 0.5f * ft->width,
                            v->clip.y / v->clip.w * 0.5f * ft->height};
    meso_vec3 to_eye =
        ft->directional ? ft->toward : meso_vec3_normalize(meso_vec3_sub(ft->eye, v->position));
    v->faces_away = meso_vec3_dot(v->unit_normal, to_eye) < -0.2f;
}

static bool normals_differ(meso_vec3 a, meso_vec3 b, float threshold) {
    return fabsf(a.x - b.x) > threshold || fabsf(a.y - b.y) > threshold ||
           fabsf(a.z - b.z) > threshold;
}

/* Whether the edge is longer than the threshold on screen (Manhattan, in samples). */
static bool view_says_long(const frame_tests *ft, const displace_vertex *a,
                           const displace_vertex *b) {
    if (!a->in_front && !b->in_front) return false; /* behind the camera: invisible */
    if (!a->in_front || !b->in_front) return true;  /* crosses the eye plane: keep refining */
    return fabsf(b->screen.x - a->screen.x) + fabsf(b->screen.y - a->screen.y) > ft->view_threshold;
}

/* Whether the base surface faces away from the eye at both end points by more than the
 * shell's own tilt can hide (cos < -0.2, ~12 degrees past the silhouette, tests_vertex): such an
 * edge lies on the far side of a closed object and is invisible. Not on an open surface, whose
 * back faces show through its border (displace_common.h, both_faces): the inside of a tube seen
 * through its rim is refined as the outside is. An edge-only test, so still crack-free. */
static bool view_says_hidden(const frame_tests *ft, const displace_vertex *a,
                             const displace_vertex *b) {
    return !ft->state->surface.both_faces && a->faces_away && b->faces_away;
}

/* The recursion limits, before the midpoint is displaced. */
static bool tests_veto(const void *user, const displace_vertex *a, const displace_vertex *b,
                       const displace_vertex *m, uint64_t *counters) {
    const frame_tests *ft = user;
    const tessellation_state *s = ft->state;
    const meso_heightfield *hf = s->surface.heightfield;
    counters[COUNT_EDGES]++;
    if (!s->normal_test && !s->area_test && !s->view_test && !s->limit_test) {
        counters[COUNT_NO_DETAIL]++;
        return true; /* every test off: the base mesh */
    }
    if (s->limit_test && hf) {
        /* "Compare rounded texture coordinate": unwrapped uvs, so a seam's two sides (u and
         * u + 1) compare alike */
        if ((m->texel_i == a->texel_i && m->texel_j == a->texel_j) ||
            (m->texel_i == b->texel_i && m->texel_j == b->texel_j)) {
            counters[COUNT_LIMIT_VETO]++;
            return true;
        }
    }
    if (s->view_test && (!view_says_long(ft, a, b) || view_says_hidden(ft, a, b))) {
        counters[COUNT_VIEW_VETO]++;
        return true;
    }
    return false;
}

/* Surface detection on the displaced midpoint. */
static bool tests_insert(const void *user, const displace_vertex *a, const displace_vertex *b,
                         const displace_vertex *m, uint64_t *counters) {
    const frame_tests *ft = user;
    const tessellation_state *s = ft->state;
    const meso_heightfield *hf = s->surface.heightfield;
    if ((s->normal_test || s->area_test) && hf) {
        bool detail = false;
        float du = (b->uv.x - a->uv.x) * (float)hf->width;
        float dv = (b->uv.y - a->uv.y) * (float)hf->height;
        float span = fmaxf(fabsf(du), fabsf(dv)); /* the edge's length in texels */
        if (s->span_texels > 0.0f && span > s->span_texels) {
            /* three samples cannot see detail between them on a long edge (a 2-triangle plane
             * over a periodic map samples the same spot of every tile): split it untested */
            counters[COUNT_SPAN_YES]++;
            counters[COUNT_INSERTED]++;
            return true;
        }
        if (s->normal_test &&
            (normals_differ(m->surface_normal, a->surface_normal, s->normal_threshold) ||
             normals_differ(m->surface_normal, b->surface_normal, s->normal_threshold))) {
            counters[COUNT_NORMAL_YES]++;
            detail = true;
        }
        if (s->area_test && !detail) {
            float radius = 0.25f * span;
            float ha = meso_sat_box_average(s->sat, a->texture_uv.x, a->texture_uv.y, radius);
            float hb = meso_sat_box_average(s->sat, b->texture_uv.x, b->texture_uv.y, radius);
            float hm = meso_sat_box_average(s->sat, m->texture_uv.x, m->texture_uv.y, radius);
            /* the midpoint's neighbourhood against the straight edge's: a linear slope adds
             * nothing, a groove or ridge between the end points does */
            if (fabsf(hm - 0.5f * (ha + hb)) > s->area_threshold) {
                counters[COUNT_AREA_YES]++;
                detail = true;
            }
        }
        if (!detail) {
            counters[COUNT_NO_DETAIL]++;
            return false;
        }
    }
    counters[COUNT_INSERTED]++;
    return true;
}

static void tessellation_release(void *state) {
    tessellation_state *s = state;
    if (!s) return;
    displace_tessellator_destroy(s->tessellator);
    displace_shadows_release(&s->shadows);
    meso_sat_destroy(s->sat);
    free(s);
}

static meso_result tessellation_prepare(meso_context *ctx, const meso_scene *scene,
                                        const meso_object *object, void **out_state) {
    *out_state = NULL;
    tessellation_state *s = calloc(1, sizeof(*s));
    if (!s) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: tessellation", object->name);
    meso_result r;
    if ((r = meso_technique_options_read(ctx, scene, object, &meso_technique_tessellation.info,
                                         s)) ||
        (r = displace_surface_init(ctx, object, &s->surface)))
        goto fail;
    s->surface.both_faces = s->surface.both_faces && s->both_faces;
    if (s->max_level < 0) /* automatic: down to texel density (the limit test stops there) */
        s->max_level = displace_texel_level(&s->surface, DISPLACE_MAX_LEVEL);
    if (s->area_test && s->surface.heightfield &&
        (r = meso_sat_bake(ctx, s->surface.heightfield, &s->sat)) != MESO_OK)
        goto fail;
    if ((r = displace_tessellator_create(ctx, &s->surface, s->max_level, &s->tessellator)))
        goto fail;
    /* the camera's mesh is new whenever the camera moves, and its map with it: keep the
     * rasterizer's buffers (the light's own tessellation draws its map once) */
    s->shadows.keep_raster = !s->shadow_tessellation;
    *out_state = s;
    return MESO_OK;
fail:
    tessellation_release(s);
    return r;
}

static bool same_matrix(meso_mat4 a, meso_mat4 b) { return memcmp(&a, &b, sizeof(a)) == 0; }

/* Bounds of the displaced surface known before tessellating: of every base vertex P and its
 * deepest displacement P - depth N (P' = P - (1 - h) depth N, h in [0, 1]), grown by a hundredth
 * of the depth for the interpolated normals between vertices. As tight as the displaced mesh's
 * own bounds on a flat base (a looser box would coarsen the shadow-map texels). */
static void displaced_bounds(const tessellation_state *s, meso_vec3 *lo, meso_vec3 *hi) {
    const meso_mesh *base = s->surface.base;
    float depth = s->surface.heightfield ? s->surface.depth : 0.0f;
    *lo = (meso_vec3){INFINITY, INFINITY, INFINITY};
    *hi = (meso_vec3){-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < base->num_vertices; i++) {
        meso_vec3 n = meso_vec3_normalize(base->normals[i]);
        meso_vec3 p[2] = {base->positions[i], meso_vec3_madd(base->positions[i], n, -depth)};
        for (int k = 0; k < 2; k++) {
            lo->x = fminf(lo->x, p[k].x), lo->y = fminf(lo->y, p[k].y);
            lo->z = fminf(lo->z, p[k].z);
            hi->x = fmaxf(hi->x, p[k].x), hi->y = fmaxf(hi->y, p[k].y);
            hi->z = fmaxf(hi->z, p[k].z);
        }
    }
    float margin = 0.01f * depth;
    *lo = meso_vec3_sub(*lo, (meso_vec3){margin, margin, margin});
    *hi = meso_vec3_add(*hi, (meso_vec3){margin, margin, margin});
}

/* Each light's shadow map from the surface tessellated as that light sees it: the same edge
 * tests with the light's projection as the camera and shadow_view_threshold texels of its map
 * as the view test's threshold. Independent of the camera, so made once and kept while the
 * lights are unchanged (static lights, as engines keep them). */
static meso_result light_view_shadows(meso_context *ctx, tessellation_state *s,
                                      const meso_scene *scene) {
    double start = meso_time_seconds();
    s->shadows.drawn = false;
    s->shadows.num_lights = 0;
    memset(&s->shadow_stats, 0, sizeof(s->shadow_stats));
    meso_vec3 lo, hi;
    displaced_bounds(s, &lo, &hi);
    /* a tessellator of its own, freed after drawing: the light's mesh can be larger than the
     * camera's and is not needed once drawn */
    displace_tessellator *tessellator = NULL;
    meso_result r = displace_tessellator_create(ctx, &s->surface, s->max_level, &tessellator);
    for (int l = 0; r == MESO_OK && l < scene->num_lights; l++) {
        const meso_light *light = &scene->lights[l];
        s->shadows.lights[l].active = false;
        displace_light_map map;
        float z_near;
        if (!displace_light_projection(ctx, &s->shadows, light, lo, hi, &map, &z_near)) continue;
        bool directional = light->type == MESO_LIGHT_DIRECTIONAL;
        frame_tests ft = {.state = s,
                          .view_projection = map.view_projection,
                          .eye = light->position,
                          .width = (float)s->shadows.options.size,
                          .height = (float)s->shadows.options.size,
                          .z_near = z_near,
                          .view_threshold = s->shadow_view_threshold,
                          .directional = directional,
                          .toward = directional ? meso_vec3_normalize(light->direction)
                                                : (meso_vec3){0, 0, 0}};
        displace_edge_tests tests = {tests_vertex_static, tests_vertex, tests_veto,
                                     tests_insert,        &ft,          true};
        const meso_mesh *mesh = NULL;
        r = displace_tessellator_run(ctx, tessellator, &tests, &mesh, &s->shadow_stats);
        if (r == MESO_OK) r = displace_shadows_draw_light(ctx, &s->shadows, scene, l, mesh, &map);
    }
    displace_tessellator_destroy(tessellator);
    if (r != MESO_OK) return r;
    displace_shadows_mark_drawn(&s->shadows, scene, meso_time_seconds() - start);
    meso_log_info(ctx,
                  "%s: tessellation: shadow maps from the lights' view, %llu triangles (the "
                  "last light's), %d x %d, in %.1f ms",
                  s->surface.object->name, (unsigned long long)s->shadow_stats.triangles,
                  s->shadows.options.size, s->shadows.options.size, 1e3 * s->shadows.seconds);
    return MESO_OK;
}

static meso_result tessellation_geometry(meso_context *ctx, void *state, const meso_frame *frame,
                                         const meso_mesh **out_mesh) {
    tessellation_state *s = state;
    *out_mesh = NULL;
    frame_tests ft = {.state = s,
                      .view_projection = frame->view_projection,
                      .eye = frame->eye,
                      .width = (float)frame->width,
                      .height = (float)frame->height,
                      .z_near = frame->z_near,
                      .view_threshold = s->view_threshold};
    displace_edge_tests tests = {tests_vertex_static, tests_vertex, tests_veto,
                                 tests_insert,        &ft,          true};
    double start = meso_time_seconds();
    s->mesh = NULL;
    meso_result r = displace_tessellator_run(ctx, s->tessellator, &tests, &s->mesh, &s->stats);
    if (r != MESO_OK) return r;
    double tessellated = meso_time_seconds();
    if (s->shadows.options.enabled && s->shadow_tessellation) {
        if (!displace_shadows_current(&s->shadows, frame->scene)) {
            r = light_view_shadows(ctx, s, frame->scene);
            if (r != MESO_OK) return r;
        }
    } else if (!displace_shadows_current(&s->shadows, frame->scene) ||
               !same_matrix(s->shadow_view_projection, frame->view_projection) ||
               s->shadow_width != frame->width || s->shadow_height != frame->height) {
        /* the camera's mesh depends on the camera (view test) and the target size */
        s->shadows.drawn = false;
        r = displace_shadows_render(ctx, &s->shadows, frame->scene, s->mesh);
        if (r != MESO_OK) return r;
        s->shadow_view_projection = frame->view_projection;
        s->shadow_width = frame->width;
        s->shadow_height = frame->height;
    }
    const uint64_t *c = s->stats.counters;
    char levels[512];
    size_t used = 0;
    levels[0] = 0;
    for (int d = 0; d < DISPLACE_MAX_DEPTH && used < sizeof(levels) - 32; d++)
        if (s->stats.per_depth[d])
            used +=
                (size_t)snprintf(levels + used, sizeof(levels) - used, "%s%d: %llu",
                                 used ? ", " : "", d, (unsigned long long)s->stats.per_depth[d]);
    meso_log_info(
        ctx,
        "%s: tessellation: %llu triangles (per level %s) in %.2f ms; edges %llu: "
        "limit test rejected %llu, view test rejected %llu, long edges split %llu, "
        "normal test proposed %llu, area test proposed %llu (of the rest), no detail %llu, "
        "inserted %llu, recursion limit %llu; base triangles replayed %llu of %zu",
        s->surface.object->name, (unsigned long long)s->stats.triangles, levels,
        1e3 * (tessellated - start), (unsigned long long)c[COUNT_EDGES],
        (unsigned long long)c[COUNT_LIMIT_VETO], (unsigned long long)c[COUNT_VIEW_VETO],
        (unsigned long long)c[COUNT_SPAN_YES], (unsigned long long)c[COUNT_NORMAL_YES],
        (unsigned long long)c[COUNT_AREA_YES], (unsigned long long)c[COUNT_NO_DETAIL],
        (unsigned long long)c[COUNT_INSERTED], (unsigned long long)s->stats.grid_limited,
        (unsigned long long)s->stats.replayed, s->surface.base->num_triangles);
    *out_mesh = s->mesh;
    return MESO_OK;
}

/* One fragment at a time (hand-built fragments; the reference the block path is tested
 * against). */
static void tessellation_shade(const void *state, const meso_frame *frame,
                               const meso_object *object, meso_fragment *fragments, size_t count) {
    (void)object;
    const tessellation_state *s = state;
    displace_shade(&s->surface, &s->shadows, s->mesh, frame, fragments, count);
}

/* Eight fragments at a time from the rasterizer's block (displace_shade8.h, as `displacement`
 * shades): the colours of displace_shade, bit for bit, without the per-fragment adapter's
 * copies (docs/techniques/tessellation.md). */
static void tessellation_shade_block(const void *state, const meso_frame *frame,
                                     const meso_object *object, meso_fragment_block *block) {
    (void)object;
    const tessellation_state *s = state;
    displace_shade_block(&s->surface, &s->shadows, s->mesh, frame, block);
}

/* Both faces of an open displaced surface, as the reference traces it (displace_common.h). */
static bool tessellation_both_faces(const void *state) {
    const tessellation_state *s = state;
    return s && s->surface.both_faces;
}

static size_t tessellation_memory(const void *state) {
    const tessellation_state *s = state;
    if (!s) return 0;
    size_t bytes = displace_tessellator_memory(s->tessellator);
    if (s->sat)
        bytes += ((size_t)s->sat->width + 1) * ((size_t)s->sat->height + 1) * sizeof(double);
    return bytes + displace_shadows_memory(&s->shadows);
}

const meso_technique meso_technique_tessellation = {
    .info = {.name = "tessellation",
             .summary = "adaptive view-dependent tessellation by edge midpoints, shadow-mapped",
             .paper = "Doggett & Hirche 2000, \"Adaptive Tessellation\", \"Edge Tests\"",
             .kind = MESO_TECHNIQUE_GEOMETRY,
             .accepts = MESO_TECHNIQUE_ACCEPTS_NONE | MESO_TECHNIQUE_ACCEPTS_HEIGHT_FIELD,
             .options = tessellation_option_table,
             .num_options = MESO_OPTION_COUNT(tessellation_option_table)},
    .prepare = tessellation_prepare,
    .release = tessellation_release,
    .geometry = tessellation_geometry,
    .shade = tessellation_shade,
    .shade_block = tessellation_shade_block,
    /* reads the position, the tangent frame, uv and the triangle; writes every colour */
    .skip_fields = MESO_FRAGMENT_SKIP_SAMPLE | MESO_FRAGMENT_SKIP_BARYCENTRICS |
                   MESO_FRAGMENT_SKIP_COLOR_PRESET,
    .memory = tessellation_memory,
    .state_both_faces = tessellation_both_faces,
};
