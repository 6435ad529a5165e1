/* Shared code of the two geometry techniques, `displacement` (uniform) and `tessellation`
 * (Doggett & Hirche 2000): vertex displacement (docs/design.md), the recursive midpoint tessellator
 * with its triangle stack, shading with the height field's normal, and shadow maps of the
 * displaced mesh. Private to src/techniques.
 *
 * Crack-freeness (Doggett & Hirche 2000, "Approach": "avoid cracks between triangles by only
 * evaluating the edge"): every vertex record is computed from the two records of the edge it
 * halves by a symmetric formula ((a + b) * 0.5 is commutative in IEEE arithmetic), and the
 * decision to insert it sees only those three records, given in a canonical order. So two base
 * triangles sharing an edge (same positions, normals, tangent frames, and uvs equal up to whole
 * tiles under repeat wrapping) produce bit-identical edge vertices and the same decisions.
 */
#ifndef MESO_DISPLACE_COMMON_H
#define MESO_DISPLACE_COMMON_H

#include "meso/bake_sat.h"
#include "render_internal.h"

#if defined(__SSE4_1__)
#include <immintrin.h>
#endif

/* Recursion limit of the tessellator: 2^10 segments per base edge. */
#define DISPLACE_MAX_LEVEL 10
/* Emitted triangles are counted per recursion depth up to this (deeper ones in the last). */
#define DISPLACE_MAX_DEPTH 32
/* Counters a technique's edge test may increment (meaning defined by the technique). */
#define DISPLACE_NUM_COUNTERS 8

/* ---- The displaced surface ---------------------------------------------------------------- */

typedef struct displace_surface {
    const meso_object *object;
    const meso_mesh *base;               /* object->mesh, world space */
    const meso_heightfield *heightfield; /* NULL: no mesostructure (h = 1 everywhere) */
    float depth;                         /* world units */
    bool repeat;                         /* height field wraps: uv taken modulo 1 */
    /* The displaced surface is not closed, so its back faces can show: the base mesh has an
     * open border (a tube's rim, the teapot's lid), or vertices at one position displace
     * differently (a sphere's pole: different uvs, different heights). The reference traces
     * such a surface as it is, both faces, each shaded with its outward normal
     * (reference_heightfield.c: no cap at the border, no weld at a pole); the geometry
     * techniques then draw both faces too (set by displace_surface_init, cleared by the
     * techniques' option both_faces 0). */
    bool both_faces;
} displace_surface;

/* Fill from an object; validates that the mesh has UVs when there is a height field. */
meso_result displace_surface_init(meso_context *ctx, const meso_object *object,
                                  displace_surface *out_surface);

/* uv as the height field is sampled: modulo 1 with repeat wrapping, so that vertices on a UV
 * seam (u = 0 on one side, u = 1 on the other) see the same heights. */
static inline meso_vec2 displace_texture_uv(const displace_surface *surface, meso_vec2 uv) {
    if (!surface->repeat) return uv;
    return (meso_vec2){uv.x - floorf(uv.x), uv.y - floorf(uv.y)};
}

/* The level at which the longest edge of the base mesh spans at most one texel of the height
 * field (Chebyshev length: max(|du| W, |dv| H)), at most max_level; 0 without a height field. */
int displace_texel_level(const displace_surface *surface, int max_level);

/* meso_heightfield_gradient with its four bilinear samples side by side in the lanes of one
 * SSE vector: every lane does the scalar version's operations in its order
 * (-ffp-contract=off), so the bits are the same. The tessellator's normal test calls it for
 * every midpoint it displaces, the shading for every fragment. */
static inline meso_vec2 displace_heightfield_gradient(const meso_heightfield *hf, float u,
                                                      float v) {
#if defined(__SSE4_1__)
    float du = 1.0f / (float)hf->width, dv = 1.0f / (float)hf->height;
    __m128 x =
        _mm_sub_ps(_mm_mul_ps(_mm_setr_ps(u + du, u - du, u, u), _mm_set1_ps((float)hf->width)),
                   _mm_set1_ps(0.5f));
    __m128 y =
        _mm_sub_ps(_mm_mul_ps(_mm_sub_ps(_mm_set1_ps(1.0f), _mm_setr_ps(v, v, v + dv, v - dv)),
                              _mm_set1_ps((float)hf->height)),
                   _mm_set1_ps(0.5f));
    __m128 fx = _mm_floor_ps(x), fy = _mm_floor_ps(y);
    __m128 tx = _mm_sub_ps(x, fx), ty = _mm_sub_ps(y, fy);
    __m128i ixv = _mm_cvttps_epi32(fx), iyv = _mm_cvttps_epi32(fy);
    float h00[4], h10[4], h01[4], h11[4];
    /* every sample's texel and its right and lower neighbours inside the field (the common
     * case): meso_heightfield_wrap_pair's first branch, the texel offsets four at a time */
    __m128i inside =
        _mm_and_si128(_mm_and_si128(_mm_cmpgt_epi32(ixv, _mm_set1_epi32(-1)),
                                    _mm_cmplt_epi32(ixv, _mm_set1_epi32(hf->width - 1))),
                      _mm_and_si128(_mm_cmpgt_epi32(iyv, _mm_set1_epi32(-1)),
                                    _mm_cmplt_epi32(iyv, _mm_set1_epi32(hf->height - 1))));
    if (_mm_movemask_ps(_mm_castsi128_ps(inside)) == 0xf) {
        int32_t at[4];
        _mm_storeu_si128((__m128i *)at,
                         _mm_add_epi32(_mm_mullo_epi32(iyv, _mm_set1_epi32(hf->width)), ixv));
        for (int k = 0; k < 4; k++) {
            const float *p = hf->heights + at[k];
            h00[k] = p[0], h10[k] = p[1], h01[k] = p[hf->width], h11[k] = p[hf->width + 1];
        }
    } else {
        int32_t ix[4], iy[4];
        _mm_storeu_si128((__m128i *)ix, ixv);
        _mm_storeu_si128((__m128i *)iy, iyv);
        for (int k = 0; k < 4; k++) {
            int i0, i1, j0, j1;
            meso_heightfield_wrap_pair(hf->wrap, ix[k], hf->width, &i0, &i1);
            meso_heightfield_wrap_pair(hf->wrap, iy[k], hf->height, &j0, &j1);
            const float *row0 = hf->heights + (size_t)j0 * (size_t)hf->width;
            const float *row1 = hf->heights + (size_t)j1 * (size_t)hf->width;
            h00[k] = row0[i0], h10[k] = row0[i1], h01[k] = row1[i0], h11[k] = row1[i1];
        }
    }
    __m128 a = _mm_loadu_ps(h00), b = _mm_loadu_ps(h10);
    __m128 c = _mm_loadu_ps(h01), d = _mm_loadu_ps(h11);
    __m128 top = _mm_add_ps(a, _mm_mul_ps(_mm_sub_ps(b, a), tx));
    __m128 bottom = _mm_add_ps(c, _mm_mul_ps(_mm_sub_ps(d, c), tx));
    float h[4];
    _mm_storeu_ps(h, _mm_add_ps(top, _mm_mul_ps(_mm_sub_ps(bottom, top), ty)));
    return (meso_vec2){(h[0] - h[1]) / (2.0f * du), (h[2] - h[3]) / (2.0f * dv)};
#else
    return meso_heightfield_gradient(hf, u, v);
#endif
}

/* Height and its gradient at a texture-space point (wrapped as above). */
float displace_height(const displace_surface *surface, meso_vec2 uv);
meso_vec2 displace_gradient(const displace_surface *surface, meso_vec2 uv);

/* A vertex of a tessellated base triangle. */
typedef struct displace_vertex {
    /* interpolated over the flat base triangle (midpoints of midpoints) */
    meso_vec3 base;               /* P on the base triangle */
    meso_vec3 normal;             /* interpolated vertex normal, not normalised */
    meso_vec3 tangent, bitangent; /* dP/du, dP/dv */
    meso_vec2 uv;                 /* as the mesh has it (uv_scale applied, not wrapped) */
    /* derived by displace_vertex_finish */
    meso_vec2 texture_uv;  /* displace_texture_uv(uv) */
    meso_vec3 unit_normal; /* N = normalize(normal) */
    float height;          /* h(uv) */
    meso_vec3 position;    /* P' = P - (1 - h) depth N (docs/design.md) */
    /* filled by the technique's vertex hook (tessellation: the edge tests' inputs) */
    meso_vec3 surface_normal; /* normal of the displaced surface (bump-map operation) */
    meso_vec4 clip;           /* view_projection * position */
    meso_vec2 screen;         /* clip x, y / w in samples (the view test's, once a vertex) */
    bool in_front;            /* clip w beyond half the near plane */
    bool faces_away;          /* the base normal turned away from the eye */
    /* set by the tessellator before the veto: the texel of the height field holding uv
     * (unwrapped), for the recursion-limit test, once a vertex instead of once an edge */
    int64_t texel_i, texel_j;
    /* bookkeeping of the tessellator */
    int32_t key_b, key_c;       /* barycentric grid coordinates of corners 1 and 2 */
    int32_t parent_a, parent_b; /* the edge this vertex halves (-1: a corner) */
    uint32_t out_index;         /* index in the job's output, UINT32_MAX until emitted */
    int8_t inserted;            /* the decision on its edge */
    int8_t displaced;           /* past the veto (or a corner): displaced and hooked */
} displace_vertex;

/* Compute the derived fields from the interpolated ones. */
void displace_vertex_finish(const displace_surface *surface, displace_vertex *vertex);
/* Set texel_i, texel_j from uv: the texel (column, row from the top) of the height field
 * holding it, uv unwrapped so that the two sides of a seam (u and u + 1) differ (0 without a
 * height field). */
static inline void displace_vertex_texel(const displace_surface *surface, displace_vertex *vertex) {
    const meso_heightfield *hf = surface->heightfield;
    if (!hf) {
        vertex->texel_i = vertex->texel_j = 0;
        return;
    }
    meso_vec2 uv = vertex->uv;
    vertex->texel_i = (int64_t)floorf(meso_clampf(uv.x, -1e6f, 1e6f) * (float)hf->width);
    vertex->texel_j = (int64_t)floorf((1.0f - meso_clampf(uv.y, -1e6f, 1e6f)) * (float)hf->height);
}

/* ---- The recursive midpoint tessellator --------------------------------------------------- */

/* Doggett & Hirche 2000, "Adaptive Tessellation" and "Hardware Architecture": per base triangle,
 * a triangle stack; for each popped triangle the midpoints of its three edges are computed,
 * displaced, handed to the vertex hook (transform, surface normal) and inserted when `insert`
 * says so; the triangle is then split with the selected midpoints (1-, 2- or 3-midpoint
 * patterns) and its children pushed, or emitted when no midpoint is selected.
 *
 * The recursion limit is a property of the EDGE, not of the triangle, so that both triangles of
 * an edge agree: vertices live on the barycentric grid of 2^max_level segments per base edge,
 * and an edge whose midpoint is not a grid point is never split. */
typedef struct displace_edge_tests {
    /* Called once per new vertex after displacement, for its view-independent data (the
     * surface normal); for the base mesh's vertices only on the first run, whose results are
     * kept, so it must give the same answer on every run (may be NULL). */
    void (*vertex_static)(const void *user, displace_vertex *vertex);
    /* Called once per vertex per run after vertex_static, for the frame's data (the
     * transformed position) (may be NULL). */
    void (*vertex_hook)(const void *user, displace_vertex *vertex);
    /* Whether to reject m, the midpoint of the edge (a, b), before it is displaced: m has only
     * its uv and texel (the recursion-limit tests need no more, so the work of wrapping,
     * interpolating and displacing rejected midpoints is saved). May be NULL. */
    bool (*veto)(const void *user, const displace_vertex *a, const displace_vertex *b,
                 const displace_vertex *m, uint64_t *counters);
    /* Whether to insert m (displaced, hooked) unless vetoed. a and b come in a canonical order
     * (by position), and both answers must depend only on the three records. `counters` are
     * the calling job's DISPLACE_NUM_COUNTERS statistics. */
    bool (*insert)(const void *user, const displace_vertex *a, const displace_vertex *b,
                   const displace_vertex *m, uint64_t *counters);
    const void *user;
    /* true: insert reads only uv, texture_uv and surface_normal of a and b and the fields of m
     * vertex_static and displace_vertex_finish set (none of the frame's), and increments each
     * counter at most once; vertex_hook reads only position and unit_normal; veto reads only
     * the texels and what vertex_hook writes. The tessellator then keeps a displaced
     * midpoint's derived fields and its decision across runs, and replays a base triangle
     * whose vetoes all answer as in its last traversal (displace_tessellator_run). */
    bool view_independent_insert;
} displace_edge_tests;

typedef struct displace_tess_stats {
    uint64_t triangles;
    uint64_t vertices;
    uint64_t per_depth[DISPLACE_MAX_DEPTH]; /* emitted triangles by recursion depth */
    uint64_t grid_limited;                  /* midpoints not on the grid (recursion limit) */
    uint64_t replayed; /* base triangles whose last traversal was replayed (unchanged) */
    uint64_t counters[DISPLACE_NUM_COUNTERS];
} displace_tess_stats;

typedef struct displace_tessellator displace_tessellator;

/* A tessellator for `surface` (which must outive it) with the recursion limit max_level in
 * [0, DISPLACE_MAX_LEVEL]. Scratch for every worker of ctx is allocated here. */
meso_result displace_tessellator_create(meso_context *ctx, const displace_surface *surface,
                                        int max_level, displace_tessellator **out_tessellator);
/* Tessellate every base triangle (in parallel, fixed jobs: byte-identical for any thread
 * count). *out_mesh is owned by the tessellator and valid until the next run.
 *
 * With tests->view_independent_insert, the tessellator remembers across runs (frames), per
 * base triangle and grid point, each displaced midpoint's inputs (its interpolated fields:
 * base, normal, tangent, bitangent, uv), what was derived from them (displace_vertex_finish and
 * vertex_static: both pure functions of those inputs), and the decision with the end points'
 * fields it read. A midpoint whose inputs are bit for bit the remembered ones takes the
 * remembered results instead of computing them again: the same bits as computing them, so the
 * same mesh, for any camera. Only vetoes and the vertex hook (the frame's transform) run again.
 *
 * It then also records each base triangle's last traversal: its vertices' positions and texels, the
 * vetoes asked in order with their answers, and its output. A traversal is a function of the
 * answers (everything else it reads is the same every run), so when every recorded veto,
 * asked again of this run's transformed vertices, answers as recorded, the traversal would
 * repeat itself exactly: the recorded output is appended instead (the same bits). The first
 * veto that answers otherwise makes the triangle traverse again and be recorded anew. */
meso_result displace_tessellator_run(meso_context *ctx, displace_tessellator *tessellator,
                                     const displace_edge_tests *tests, const meso_mesh **out_mesh,
                                     displace_tess_stats *out_stats);
size_t displace_tessellator_memory(const displace_tessellator *tessellator);
void displace_tessellator_destroy(displace_tessellator *tessellator);

/* ---- Shadow maps -------------------------------------------------------------------------- */

typedef struct displace_shadow_options {
    bool enabled; /* "shadows" (1) */
    int size;     /* "shadow_map_size" (2048) */
    float bias;   /* "shadow_bias" in shadow-map texels, scaled by the slope (1.5) */
    bool pcf;     /* "shadow_pcf" (1): 2 x 2 bilinear percentage-closer filtering */
} displace_shadow_options;

/* The option-table rows of the shadow maps, for a struct_type whose `member` is a
 * displace_shadow_options: both geometry techniques list them in their tables. */
#define DISPLACE_SHADOW_OPTION_ROWS(struct_type, member)                                           \
    MESO_OPTION_ROW(MESO_OPTION_BOOL, shadows, 0, 1, 1, "shadow maps from every light",            \
                    struct_type, member.enabled),                                                  \
        MESO_OPTION_ROW(MESO_OPTION_INT, shadow_map_size, 16, 8192, 2048,                          \
                        "shadow map texels a side", struct_type, member.size),                     \
        MESO_OPTION_ROW(MESO_OPTION_FLOAT, shadow_bias, 0.0, 64.0, 1.5,                            \
                        "depth bias in shadow-map texels, scaled by the slope", struct_type,       \
                        member.bias),                                                              \
        MESO_OPTION_ROW(MESO_OPTION_BOOL, shadow_pcf, 0, 1, 1,                                     \
                        "2 x 2 bilinear percentage-closer filtering", struct_type, member.pcf)

/* The option-table row of `both_faces` (displace_surface.both_faces), for a struct_type whose
 * `member` is a bool: both geometry techniques list it. */
#define DISPLACE_BOTH_FACES_OPTION_ROW(struct_type, member)                                        \
    MESO_OPTION_ROW(MESO_OPTION_BOOL, both_faces, 0, 1, 1,                                         \
                    "draw the back faces of an open displaced surface, the inside seen through "   \
                    "its border (a tube's rim, the teapot's lid gap), as the reference does; 0: "  \
                    "cull them (faster, background there)",                                        \
                    struct_type, member)

typedef struct displace_light_map {
    bool active; /* false: the light casts no shadow (visibility 1) */
    meso_mat4 view_projection;
    float texel_size;   /* world size of a texel (ortho) or its angle in radians (point) */
    const float *depth; /* size x size, inside displace_shadows.depth */
} displace_light_map;

typedef struct displace_shadows {
    displace_shadow_options options;
    int num_lights;
    displace_light_map lights[MESO_SCENE_MAX_LIGHTS];
    float *depth; /* depth_lights * size * size, owned */
    int depth_lights;
    /* Set by a technique whose maps are redrawn frame after frame (tessellation's camera mesh
     * under a moving camera): the rasterizer's buffers are then kept in `raster` between
     * draws; otherwise they are freed after each draw. */
    bool keep_raster;
    meso_raster_depth_scratch *raster; /* owned */
    double seconds;                    /* time of the last render */
    /* the scene's lights the maps were drawn for (displace_shadows_current) */
    bool drawn;
    int drawn_num_lights;
    meso_light drawn_lights[MESO_SCENE_MAX_LIGHTS];
} displace_shadows;

/* Whether the maps were drawn for exactly the scene's present lights: the viewer turns a light
 * in place, without preparing the technique again, so a kept map must be checked each frame. */
bool displace_shadows_current(const displace_shadows *shadows, const meso_scene *scene);

/* The light-space projection of `light` for a mesh inside the box (lo, hi): orthographic fitted
 * to the box for a directional light, perspective around it for a point light; *out_z_near is
 * the clip w in front of which geometry counts as visible (0 for orthographic). False (and a
 * warning) for a point light inside the box: it casts no shadow map. */
bool displace_light_projection(meso_context *ctx, const displace_shadows *shadows,
                               const meso_light *light, meso_vec3 lo, meso_vec3 hi,
                               displace_light_map *out_map, float *out_z_near);
/* Draw the depth map of light l (of the scene) from `mesh` with the projection in *map
 * (displace_light_projection); allocates the maps on first use. */
meso_result displace_shadows_draw_light(meso_context *ctx, displace_shadows *shadows,
                                        const meso_scene *scene, int l, const meso_mesh *mesh,
                                        const displace_light_map *map);
/* Record that every light's map is now drawn for the scene's lights (after
 * displace_shadows_draw_light for each). */
void displace_shadows_mark_drawn(displace_shadows *shadows, const meso_scene *scene,
                                 double seconds);

/* Render a light-space depth map of `mesh` for every light of the scene with
 * meso_raster_depth_map: orthographic fitted to the mesh's bounds for directional lights,
 * perspective for point lights outside the bounds (a point light inside them casts no shadow
 * map; a warning says so). Does nothing when shadows are disabled. */
meso_result displace_shadows_render(meso_context *ctx, displace_shadows *shadows,
                                    const meso_scene *scene, const meso_mesh *mesh);
/* visibility[i] in [0,1] for every light of the scene at `position` with shading normal
 * `normal` (lights behind it are not looked up: they add nothing) on a surface with geometric
 * normal `face_normal` (for the slope-scaled bias). Pure, thread-safe. */
void displace_shadows_visibility(const displace_shadows *shadows, const meso_scene *scene,
                                 meso_vec3 position, meso_vec3 normal, meso_vec3 face_normal,
                                 float *visibility);
/* Bytes held: the maps and the kept rasterizer buffers. */
size_t displace_shadows_memory(const displace_shadows *shadows);
void displace_shadows_release(displace_shadows *shadows);

/* ---- Shading ------------------------------------------------------------------------------ */

/* A fragment counts as a back face when its triangle faces away from the eye by more than
 * this (the sine of the angle past edge-on): twice the rasterizer's own margin
 * (RASTER_BACK_FACE_MARGIN, 0.01), so a triangle seen edge-on, which the rasterizer drew as a
 * front face with culling on, stays lit. */
#define DISPLACE_BACK_FACE_MARGIN 0.02f

/* Whether a fragment at `position` on a triangle of unit face normal `face` (outward, by the
 * winding) shows the triangle's back face, to be shaded in the surface's own shadow: on an
 * open surface (both_faces) with shadows on. The reference shades such a hit with the outward
 * normal and traces its shadow rays from the side the eye is on, through the surface itself
 * toward any light outside; a light inside faces away from the outward normal and adds
 * nothing either, so direct light never reaches it. */
static inline bool displace_back_face(const displace_surface *surface,
                                      const displace_shadows *shadows, const meso_frame *frame,
                                      meso_vec3 position, meso_vec3 face) {
    if (!surface->both_faces || shadows->num_lights <= 0) return false;
    meso_vec3 to = meso_vec3_sub(position, frame->eye);
    return meso_vec3_dot(to, face) > sqrtf(meso_vec3_dot(to, to)) * DISPLACE_BACK_FACE_MARGIN;
}

/* Shade fragments of `mesh` (the displaced mesh, whose normals/tangents/bitangents carry the
 * BASE frame): the normal is the height field's (meso_displaced_normal at the fragment's uv,
 * the bump-map operation of the slides' "Hardware Architecture"), shadows from `shadows`. */
void displace_shade(const displace_surface *surface, const displace_shadows *shadows,
                    const meso_mesh *mesh, const meso_frame *frame, meso_fragment *fragments,
                    size_t count);

#endif
