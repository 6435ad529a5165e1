/* `displacement`: uniform tessellation of every base triangle into 4^L triangles whose vertices
 * are displaced by the height field (docs/design.md: P' = P - (1 - h) depth N), rasterized with the
 * shared shading; the brute-force baseline of Doggett & Hirche 2000 ("Displacement Mapping":
 * base mesh + displacement map = displaced mesh) and of VDM §1. Self-shadowing by a shadow map
 * of the displaced mesh (displace_common.c). */
#include "displace_common.h"
#include "displace_shade8.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "meso/runtime.h"

/* The automatic level keeps the whole object under this many triangles. */
#define DISPLACEMENT_AUTO_BUDGET (1u << 21)
#define DISPLACEMENT_AUTO_MAX_LEVEL 9
/* Consecutive triangles culled together. The tessellator emits each base triangle's 4^L
 * triangles depth first, so 16 consecutive ones (4^2) are one small patch of the surface. Their
 * cone of normals is what limits culling on a rough surface (a brick's side walls): smaller
 * clusters drop more triangles (docs/techniques/displacement.md, CLUSTER_TRIANGLES). */
#define CLUSTER_TRIANGLES 16
/* A cluster is dropped as back-facing only when every triangle in it faces away by more than
 * this angle (radians) past edge-on: twice the rasterizer's own early margin
 * (RASTER_BACK_FACE_MARGIN, 0.01), so the rasterizer would have dropped each of them before
 * transforming it, and the image cannot change. */
#define CLUSTER_BACK_FACE_MARGIN 0.02f

/* Bounds of a cluster for culling (Shirman & Abi-Ezzi's cone of normals, as meshlet culling
 * does): a sphere holding its vertices and a cone holding its unit face normals. */
typedef struct cluster_bounds {
    meso_vec3 center;
    float radius;
    meso_vec3 axis;
    float spread; /* half-angle of the cone of normals; > pi/2: never back-facing as a whole */
} cluster_bounds;

typedef struct displacement_state {
    displace_surface surface;
    int level;
    bool cluster_culling;
    displace_tessellator *tessellator;
    const meso_mesh *mesh; /* made on the first frame, kept: it does not depend on the view */
    displace_shadows shadows;
    displace_tess_stats stats;
    /* per frame: the clusters of `mesh` that may show, as a mesh sharing its vertices */
    cluster_bounds *clusters;
    size_t num_clusters;
    uint32_t *drawn_indices;
    meso_mesh drawn;
    size_t drawn_clusters;
} displacement_state;

typedef struct displacement_options {
    int level;
    bool cluster_culling;
    bool both_faces;
    displace_shadow_options shadows;
} displacement_options;

static const meso_technique_option displacement_option_table[] = {
    MESO_OPTION_ROW(MESO_OPTION_INT, level, -1, DISPLACE_MAX_LEVEL, -1,
                    "uniform subdivision level (4^level triangles a base triangle); -1: texel "
                    "density within the triangle budget",
                    displacement_options, level),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, cluster_culling, 0, 1, 1,
                    "hand the rasterizer only the 16-triangle clusters the camera may see "
                    "(the same image; 0: the whole mesh every frame)",
                    displacement_options, cluster_culling),
    DISPLACE_BOTH_FACES_OPTION_ROW(displacement_options, both_faces),
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
    free(s->clusters);
    free(s->drawn_indices);
    free(s);
}

/* The bounds of every CLUSTER_TRIANGLES consecutive triangles of the (view-independent) mesh,
 * once. A cluster with a degenerate triangle gets no cone (its orientation is the rasterizer's
 * to decide). One pass: the sphere is the box's (centre and half diagonal). */
static void cluster_bounds_compute(const meso_mesh *mesh, size_t first, size_t count,
                                   cluster_bounds *out) {
    meso_vec3 lo = {INFINITY, INFINITY, INFINITY}, hi = {-INFINITY, -INFINITY, -INFINITY};
    meso_vec3 sum = {0.0f, 0.0f, 0.0f};
    meso_vec3 normals[CLUSTER_TRIANGLES];
    bool degenerate = false;
    for (size_t i = 0; i < count; i++) {
        const uint32_t *idx = mesh->indices + 3 * (first + i);
        meso_vec3 p[3] = {mesh->positions[idx[0]], mesh->positions[idx[1]],
                          mesh->positions[idx[2]]};
        for (int k = 0; k < 3; k++) {
            lo = (meso_vec3){fminf(lo.x, p[k].x), fminf(lo.y, p[k].y), fminf(lo.z, p[k].z)};
            hi = (meso_vec3){fmaxf(hi.x, p[k].x), fmaxf(hi.y, p[k].y), fmaxf(hi.z, p[k].z)};
        }
        meso_vec3 n = meso_vec3_cross(meso_vec3_sub(p[1], p[0]), meso_vec3_sub(p[2], p[0]));
        float len = meso_vec3_length(n);
        normals[i] = n;
        if (!(len > 0.0f) || !isfinite(len)) {
            degenerate = true;
            continue;
        }
        normals[i] = meso_vec3_scale(n, 1.0f / len);
        sum = meso_vec3_add(sum, normals[i]);
    }
    out->center = meso_vec3_scale(meso_vec3_add(lo, hi), 0.5f);
    /* a little more than half the diagonal: the tests below run in float */
    out->radius = 0.5f * meso_vec3_length(meso_vec3_sub(hi, lo)) * 1.001f + 1e-6f;
    out->spread = 4.0f; /* no cone */
    float sum_len = meso_vec3_length(sum);
    if (degenerate || !(sum_len > 0.0f) || !isfinite(sum_len) || !isfinite(out->radius)) return;
    out->axis = meso_vec3_scale(sum, 1.0f / sum_len);
    float min_cos = 1.0f;
    for (size_t i = 0; i < count; i++)
        min_cos = fminf(min_cos, meso_vec3_dot(normals[i], out->axis));
    /* widened by 1e-3 radians for the rounding of the normals */
    if (min_cos > 0.0f) out->spread = acosf(fminf(min_cos, 1.0f)) + 1e-3f;
}

typedef struct bounds_job {
    displacement_state *state;
} bounds_job;

#define CLUSTERS_PER_JOB 1024

static void bounds_run(void *user, size_t job, int thread_index) {
    (void)thread_index;
    displacement_state *s = ((bounds_job *)user)->state;
    size_t triangles = s->mesh->num_triangles;
    size_t end = (job + 1) * CLUSTERS_PER_JOB;
    end = end < s->num_clusters ? end : s->num_clusters;
    for (size_t c = job * CLUSTERS_PER_JOB; c < end; c++) {
        size_t first = c * CLUSTER_TRIANGLES;
        size_t count =
            triangles - first < CLUSTER_TRIANGLES ? triangles - first : CLUSTER_TRIANGLES;
        cluster_bounds_compute(s->mesh, first, count, &s->clusters[c]);
    }
}

/* Whether the camera cannot see any triangle of the cluster: the sphere lies outside one plane
 * of the view frustum the rasterizer rejects against (x, y = +-w, w = z_near: then every vertex
 * does, and it rejects the triangle), or every triangle faces away from the eye. For the
 * second: from any point of the sphere the eye lies within beta = asin(r / D) of the direction
 * to the centre, and every normal within `spread` of the axis, so each triangle faces away by
 * at least angle(axis, to eye) - 90 deg - spread - beta. */
static bool cluster_hidden(const cluster_bounds *c, const meso_frame *frame,
                           const float planes[5][4], bool both_faces) {
    for (int i = 0; i < 5; i++) {
        const float *q = planes[i];
        float d = q[0] * c->center.x + q[1] * c->center.y + q[2] * c->center.z + q[3];
        float norm = sqrtf(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
        if (d < -c->radius * norm * 1.001f) return true;
    }
    /* an open surface's back faces show through its border (displace_common.h) */
    if (both_faces || c->spread > 1.5f) return false;
    meso_vec3 to_eye = meso_vec3_sub(frame->eye, c->center);
    float distance = meso_vec3_length(to_eye);
    if (!(distance > c->radius * 1.01f)) return false;
    float angle = c->spread + asinf(c->radius / distance) + CLUSTER_BACK_FACE_MARGIN;
    if (angle >= 0.5f * MESO_PI) return false;
    return meso_vec3_dot(c->axis, to_eye) < -sinf(angle) * distance;
}

/* The clusters' bounds and the index buffer of the drawn mesh, once the mesh exists. */
static meso_result clusters_prepare(meso_context *ctx, displacement_state *s) {
    size_t triangles = s->mesh->num_triangles;
    s->num_clusters = (triangles + CLUSTER_TRIANGLES - 1) / CLUSTER_TRIANGLES;
    s->clusters = malloc((s->num_clusters ? s->num_clusters : 1) * sizeof(*s->clusters));
    s->drawn_indices = malloc((triangles ? triangles : 1) * 3 * sizeof(uint32_t));
    if (!s->clusters || !s->drawn_indices)
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: displacement clusters",
                              s->surface.object->name);
    /* each cluster's bounds depend on its triangles only: any split gives the same bits */
    bounds_job job = {s};
    meso_parallel_for(ctx, (s->num_clusters + CLUSTERS_PER_JOB - 1) / CLUSTERS_PER_JOB, bounds_run,
                      &job);
    return MESO_OK;
}

/* This frame's drawn mesh: the mesh's triangles in their order, less the hidden clusters. */
static void clusters_select(displacement_state *s, const meso_frame *frame) {
    /* clip = view_projection (p, 1); rows r of the column-major matrix: m[4 j + r] */
    const float *m = frame->view_projection.m;
    float planes[5][4];
    for (int j = 0; j < 4; j++) {
        planes[0][j] = m[4 * j + 3] - m[4 * j + 0]; /* w - x >= 0 */
        planes[1][j] = m[4 * j + 3] + m[4 * j + 0]; /* w + x >= 0 */
        planes[2][j] = m[4 * j + 3] - m[4 * j + 1]; /* w - y >= 0 */
        planes[3][j] = m[4 * j + 3] + m[4 * j + 1]; /* w + y >= 0 */
        planes[4][j] = m[4 * j + 3];                /* w - z_near >= 0 */
    }
    planes[4][3] -= frame->z_near;
    size_t triangles = s->mesh->num_triangles, kept = 0, drawn = 0;
    for (size_t c = 0; c < s->num_clusters; c++) {
        if (s->cluster_culling &&
            cluster_hidden(&s->clusters[c], frame, planes, s->surface.both_faces))
            continue;
        size_t first = c * CLUSTER_TRIANGLES;
        size_t count =
            triangles - first < CLUSTER_TRIANGLES ? triangles - first : CLUSTER_TRIANGLES;
        memcpy(s->drawn_indices + 3 * kept, s->mesh->indices + 3 * first,
               3 * count * sizeof(uint32_t));
        kept += count;
        drawn++;
    }
    s->drawn = *s->mesh;
    s->drawn.indices = s->drawn_indices;
    s->drawn.num_triangles = kept;
    s->drawn_clusters = drawn;
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
    s->cluster_culling = options.cluster_culling;
    if ((r = displace_surface_init(ctx, object, &s->surface)) != MESO_OK) goto fail;
    s->surface.both_faces = s->surface.both_faces && options.both_faces;
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
        /* the mesh is static: one shadow map for every frame while the lights stay */
        r = displace_shadows_render(ctx, &s->shadows, frame->scene, s->mesh);
        if (r == MESO_OK) r = clusters_prepare(ctx, s);
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
    } else if (!displace_shadows_current(&s->shadows, frame->scene)) {
        /* the viewer turned a light (in place, without preparing again) */
        meso_result r = displace_shadows_render(ctx, &s->shadows, frame->scene, s->mesh);
        if (r != MESO_OK) return r;
    }
    /* The mesh and the shadow maps stay; per frame only the clusters the camera may see are
     * handed to the rasterizer (the back half of a closed object costs no setup). */
    clusters_select(s, frame);
    meso_log_info(ctx, "%s: displacement: %zu of %zu clusters of %d triangles may show",
                  s->surface.object->name, s->drawn_clusters, s->num_clusters, CLUSTER_TRIANGLES);
    *out_mesh = &s->drawn;
    return MESO_OK;
}

/* One fragment at a time (hand-built fragments; the reference the block path is tested
 * against). */
static void displacement_shade(const void *state, const meso_frame *frame,
                               const meso_object *object, meso_fragment *fragments, size_t count) {
    (void)object;
    const displacement_state *s = state;
    /* fragments name triangles of this frame's drawn mesh */
    displace_shade(&s->surface, &s->shadows, &s->drawn, frame, fragments, count);
}

/* Eight fragments at a time from the rasterizer's block (displace_shade8.h): the colours of
 * displace_shade, bit for bit. */
static void displacement_shade_block(const void *state, const meso_frame *frame,
                                     const meso_object *object, meso_fragment_block *block) {
    (void)object;
    const displacement_state *s = state;
    /* fragments name triangles of this frame's drawn mesh */
    displace_shade_block(&s->surface, &s->shadows, &s->drawn, frame, block);
}

/* Both faces of an open displaced surface, as the reference traces it (displace_common.h). */
static bool displacement_both_faces(const void *state) {
    const displacement_state *s = state;
    return s && s->surface.both_faces;
}

static size_t displacement_memory(const void *state) {
    const displacement_state *s = state;
    if (!s) return 0;
    return displace_tessellator_memory(s->tessellator) + s->num_clusters * sizeof(cluster_bounds) +
           (s->mesh ? s->mesh->num_triangles * 3 * sizeof(uint32_t) : 0) +
           displace_shadows_memory(&s->shadows);
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
    .shade_block = displacement_shade_block,
    /* reads the position, the tangent frame, uv and the triangle; writes every colour */
    .skip_fields = MESO_FRAGMENT_SKIP_SAMPLE | MESO_FRAGMENT_SKIP_BARYCENTRICS |
                   MESO_FRAGMENT_SKIP_COLOR_PRESET,
    .memory = displacement_memory,
    .state_both_faces = displacement_both_faces,
};
