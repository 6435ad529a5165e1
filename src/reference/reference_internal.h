/* The reference tracer's options beyond render_internal.h (tests and tools).
 *
 * meso_reference_create(ctx, scene, out) is meso_reference_create_with(ctx, scene, NULL, out).
 */
#ifndef MESO_REFERENCE_INTERNAL_H
#define MESO_REFERENCE_INTERNAL_H

#include "meso/bake_isosurface.h"
#include "render_internal.h"

/* The most triangles the reference builds for one scene (all objects together), checked
 * before any geometry is allocated: 64 M triangles take about 6 GB with the BVH. */
#define MESO_REFERENCE_MAX_TRIANGLES (UINT64_C(1) << 26)

/* Zero fields take the defaults. */
typedef struct meso_reference_desc {
    /* Height fields: micro-triangle edges per texel of the tiled map (1: an edge spans at most
     * one texel; 2: half a texel). Objects may set the technique option "subdivision". */
    int subdivision;
    /* Height fields: also cap the micro-triangles at `view_adaptive` edges per pixel of the
     * scene's image seen from the scene's camera (0: 2, the default; negative: off, texel
     * rule only). See reference_heightfield.c. Objects may set the option "view_adaptive". */
    float view_adaptive;
    /* Solids: the texture-space extraction grid per tile (128 x 128 x 32). Objects may set
     * the option "resolution" (u and v; w is a quarter of it). */
    meso_isosurface_desc isosurface;
    /* Tests: replaces the distance field of every solid object (NULL: meso_solid_distance of
     * the object's solid); shading then uses central differences of this field. */
    meso_scalar_field_fn solid_field;
    void *solid_field_user;
    /* Report the acceleration structure's build as progress ("reference BVH"). */
    bool progress;
} meso_reference_desc;

/* The reference's option table, for the registry's entry. */
extern const meso_technique_option meso_reference_options[];
#define MESO_REFERENCE_NUM_OPTIONS 6

meso_result meso_reference_create_with(meso_context *ctx, const meso_scene *scene,
                                       const meso_reference_desc *desc,
                                       meso_reference **out_reference);

/* ---- Private to reference*.c ------------------------------------------------------------- */

#include <embree3/rtcore.h>
#include <math.h>
#include <stdatomic.h>
#include <string.h>

typedef enum reference_kind {
    REFERENCE_PLAIN = 0,    /* the mesh itself */
    REFERENCE_HEIGHT_FIELD, /* displaced micro-triangles */
    REFERENCE_SOLID,        /* the isosurface mapped into the shell's prisms */
} reference_kind;

/* A height field's Embree grid: one base triangle, or two sharing an edge
 * (reference_heightfield.c). */
typedef struct reference_grid {
    uint32_t first, second; /* base triangles; second = UINT32_MAX: a single one */
    uint8_t first_edge;     /* the edge of `first` on the grid's diagonal (shared with second) */
    uint8_t second_edge;    /* the same edge in `second` */
} reference_grid;

/* The base triangle and its barycentric weights (in its own vertex order) at grid (u, v). */
static inline uint32_t reference_grid_weights(const reference_grid *grid, float u, float v,
                                              float out_weights[3]) {
    if (grid->second == UINT32_MAX || u + v <= 1.0f) {
        int e = grid->first_edge;
        out_weights[(e + 2) % 3] = 1.0f - u - v;
        out_weights[e] = u;
        out_weights[(e + 1) % 3] = v;
        return grid->first;
    }
    int f = grid->second_edge;
    out_weights[f] = 1.0f - u;
    out_weights[(f + 1) % 3] = 1.0f - v;
    out_weights[(f + 2) % 3] = u + v - 1.0f;
    return grid->second;
}

/* One object's traced geometry and what shading needs at a hit. */
typedef struct reference_object {
    const meso_object *object;
    reference_kind kind;
    uint64_t num_triangles;
    size_t num_vertices;
    const uint32_t *indices; /* the Embree index buffer: plain 3 a triangle, solid 4 a quad */
    meso_vec3 *uvws;         /* solid: per vertex (u, v, w), uv_scale applied */
    reference_grid *grids;   /* height field: one per Embree grid primitive */
    uint64_t *base_offsets;  /* solid: first quad of each base triangle, num_base + 1 */
    uint8_t *caps;         /* solid with open borders: per quad, 1 for a cap (reference_solid.c) */
    const float *vertices; /* solid: the Embree vertex buffer, 3 floats a vertex */
    size_t num_base;
    meso_scalar_field_fn field; /* solid */
    void *field_user;
    size_t side_bytes; /* uvws, base_offsets, grids */
} reference_object;

/* The options an object gives the reference ("technique_options": {"reference": {...}}),
 * read by meso_technique_options_read with the table meso_reference_options (reference.c). */
typedef struct reference_options {
    float subdivision;   /* height fields: micro-edges per texel */
    float view_adaptive; /* height fields: micro-edges per pixel at most; <= 0: no cap */
    int resolution;      /* solids: extraction grid cells a tile side (u and v; w a quarter) */
    int samples;         /* path-traced samples a pixel; 0: the direct-light reference */
    int bounces;         /* path tracing: interreflections (0: the environment's direct light) */
    bool rtv;            /* the environment through the RTV at the true hit (GDM-GI's shading) */
} reference_options;

/* The tracer (reference.c); its fields are shared with reference_path.c. */
struct meso_reference {
    RTCDevice device;
    RTCScene scene;
    const meso_scene *scene_data;
    reference_object *objects;
    int num_objects;
    uint64_t num_triangles;
    float epsilon;                  /* shadow-ray offset, world units */
    _Atomic long long embree_bytes; /* Embree's own allocations (memory monitor) */
    long long embree_peak;
    long long memory_limit;   /* the context's budget: Embree allocations beyond it fail */
    _Atomic bool over_budget; /* an allocation was refused for the budget */
    size_t side_bytes;
    /* Path tracing (reference_path.c): the largest `samples` and `bounces` any object's
     * options ask for; samples 0 draws the direct-light reference. */
    int path_samples;
    int path_bounces;
    bool path_rtv; /* any object's option `rtv`: reference_path.c shades with the RTV */
};

/* The object's options: the table's defaults replaced by desc's, then the object's own. */
meso_result reference_read_options(meso_context *ctx, const meso_scene *scene,
                                   const meso_object *object, const meso_reference_desc *desc,
                                   reference_options *out_options);

/* Build the geometry of one object into `geometry` (a new RTC_GEOMETRY_TYPE_GRID for height
 * fields, RTC_GEOMETRY_TYPE_QUAD for solids):
 * counts first, adds the count to *total and checks MESO_REFERENCE_MAX_TRIANGLES before
 * allocating the buffers. */
meso_result reference_build_heightfield(meso_context *ctx, const meso_scene *scene,
                                        const reference_options *options, RTCGeometry geometry,
                                        reference_object *ref, uint64_t *total);
meso_result reference_build_solid(meso_context *ctx, const meso_reference_desc *desc,
                                  const reference_options *options, RTCGeometry geometry,
                                  reference_object *ref, uint64_t *total);

/* The MESO_ERROR_LIMIT error for `what` (the height field, the solid) of an object that would
 * take the scene to `count` triangles, above MESO_REFERENCE_MAX_TRIANGLES; `hint`: how to stay
 * below it. */
meso_result reference_too_many_triangles(meso_context *ctx, const meso_object *object,
                                         const char *what, uint64_t count, const char *hint);

/* The base triangle of a traced solid quad (binary search in base_offsets). */
size_t reference_base_triangle(const reference_object *ref, uint64_t triangle);

/* dP/du and dP/dv of a triangle from its positions and UVs (zero when the UVs are degenerate). */
void reference_triangle_gradients(const meso_vec3 p[3], const meso_vec2 uv[3], meso_vec3 *out_t,
                                  meso_vec3 *out_b);

/* Where a hit lies on the base mesh: its triangle, the barycentric weights (of the triangle's
 * own vertex order) and the depth w in the shell (0 at the mesh, 1 at -depth; 0 for plain
 * objects). */
typedef struct reference_base {
    size_t triangle;
    float weights[3];
    float w;
} reference_base;

/* The mesostructure's shading normal and the shading uv at a hit of `ref`, and (out_base not
 * NULL) where it lies on the base mesh. */
/* A solid's hit (u, v) in Embree quad `primitive` to its texture point (u, v, w). */
meso_vec3 reference_quad_uvw(const reference_object *ref, unsigned primitive, float hu, float hv);
void reference_surface_at(const reference_object *ref, unsigned primitive, float hu, float hv,
                          meso_vec3 *out_normal, meso_vec2 *out_uv, reference_base *out_base);

/* What a ray hit. */
typedef struct reference_hit {
    const reference_object *ref;
    float t; /* the ray's parameter at the hit */
    meso_vec3 position;
    meso_vec3 normal;           /* the mesostructure's shading normal */
    meso_vec2 uv;               /* shading uv */
    meso_vec3 geometric_normal; /* of the hit triangle, facing the ray's origin */
    meso_vec3 origin;           /* position moved off the surface toward the ray's side: where
                                   shadow and bounce rays start */
    reference_base base;        /* where it lies on the base mesh */
} reference_hit;

/* The shading model at a hit (meso_shade_point_footprint): the base mesh's tangent and bitangent
 * at the hit's base point orient the object's normal map as the rasterizer's fragments do, and
 * the maps are read by the footprint duv_dx, duv_dy (zero: a point) when frame->filter. */
static inline meso_vec3 reference_shade_hit_footprint(const meso_frame *frame,
                                                      const reference_hit *hit, meso_vec2 duv_dx,
                                                      meso_vec2 duv_dy, const float *visibility) {
    const meso_mesh *mesh = hit->ref->object->mesh;
    meso_vec3 t = {0.0f, 0.0f, 0.0f}, b = {0.0f, 0.0f, 0.0f};
    if (hit->ref->object->material.normal_map && mesh->tangents && mesh->bitangents) {
        const uint32_t *tri = mesh->indices + 3 * hit->base.triangle;
        const float *w = hit->base.weights;
        t = meso_vec3_barycentric(mesh->tangents[tri[0]], mesh->tangents[tri[1]],
                                  mesh->tangents[tri[2]], w[0], w[1], w[2]);
        b = meso_vec3_barycentric(mesh->bitangents[tri[0]], mesh->bitangents[tri[1]],
                                  mesh->bitangents[tri[2]], w[0], w[1], w[2]);
    }
    return meso_shade_point_footprint(frame, hit->ref->object, hit->position, hit->normal, t, b,
                                      hit->uv, duv_dx, duv_dy, visibility);
}

/* reference_shade_hit_footprint of a point (secondary hits). */
static inline meso_vec3 reference_shade_hit(const meso_frame *frame, const reference_hit *hit,
                                            const float *visibility) {
    meso_vec2 point = {0.0f, 0.0f};
    return reference_shade_hit_footprint(frame, hit, point, point, visibility);
}

/* True when the ray origin + t dir, t in [0, tfar), hits nothing in `scene`. Thread-safe. */
static inline bool reference_unoccluded(RTCScene scene, struct RTCIntersectContext *context,
                                        meso_vec3 origin, meso_vec3 dir, float tfar) {
    struct RTCRay ray;
    memset(&ray, 0, sizeof ray);
    ray.org_x = origin.x, ray.org_y = origin.y, ray.org_z = origin.z;
    ray.dir_x = dir.x, ray.dir_y = dir.y, ray.dir_z = dir.z;
    ray.tnear = 0.0f;
    ray.tfar = tfar;
    ray.mask = UINT32_MAX;
    rtcOccluded1(scene, context, &ray);
    return ray.tfar != -INFINITY;
}

/* The samples of 16 x 16 tile `job` of a width x height target, tiles_x tiles a row:
 * [x0, x1) x [y0, y1). */
enum { REFERENCE_TILE = 16 };
static inline void reference_tile_bounds(size_t job, int tiles_x, int width, int height, int *x0,
                                         int *y0, int *x1, int *y1) {
    *x0 = (int)(job % (size_t)tiles_x) * REFERENCE_TILE;
    *y0 = (int)(job / (size_t)tiles_x) * REFERENCE_TILE;
    *x1 = *x0 + REFERENCE_TILE < width ? *x0 + REFERENCE_TILE : width;
    *y1 = *y0 + REFERENCE_TILE < height ? *y0 + REFERENCE_TILE : height;
}

/* The direct reference's sample (i, j) of the frame: the camera ray through its centre, the
 * hit shaded by meso_shade_point with hard shadows (colour, coverage 1, depth t), or the
 * background (coverage 0, depth +inf). Returns whether it hit; *out_hit is the hit. */
bool reference_direct_sample(const meso_reference *reference, const meso_frame *frame,
                             struct RTCIntersectContext *primary, int i, int j, float *color,
                             float *coverage, float *depth, reference_hit *out_hit);

/* Trace the ray origin + t dir, t in [tnear, inf), against the whole scene; false when it
 * hits nothing. Thread-safe. */
bool reference_trace(const meso_reference *reference, struct RTCIntersectContext *context,
                     meso_vec3 origin, meso_vec3 dir, float tnear, reference_hit *out_hit);

/* visibility[l] = 1 when light l of the scene is seen from `origin` (a point just off the
 * surface at `position`), else 0: one occlusion ray a light against the whole scene. */
void reference_light_visibility(const meso_reference *reference, meso_vec3 origin,
                                meso_vec3 position, float *visibility);

/* The path-traced frame (reference_path.c): as meso_reference_render, with reference->path_*
 * (docs/reference.md "Path tracing"). */
meso_result reference_path_render(meso_context *ctx, const meso_reference *reference,
                                  const meso_frame *frame, float *color, float *coverage,
                                  float *depth);

/* Barycentric weights of `uv` in the UV triangle; false when it is degenerate (weights 1/3). */
bool reference_uv_barycentrics(const meso_vec2 uv[3], meso_vec2 point, float out_weights[3]);

#endif
