/* Private interface of the render module: the frame description, fragments, the technique
 * vtable every file in techniques/ implements, the shared shading model, and the hooks of the
 * rasterizer and the reference tracer.
 *
 * Front end / back end (as Quake III's renderer): meso_renderer_render builds an immutable
 * meso_frame (camera, matrices, lights), then the back end (rasterizer or reference tracer)
 * executes it. Techniques read the frame and their own prepared state; they never write shared
 * memory while shading, so tiles shade in parallel.
 */
#ifndef MESO_RENDER_INTERNAL_H
#define MESO_RENDER_INTERNAL_H

#include <stddef.h>

#include "meso/runtime.h"
#include "meso/render.h"

/* ---- The frame ---------------------------------------------------------------------------- */

typedef struct meso_frame {
    const meso_scene *scene;
    int width, height; /* the target's size in samples (pixels x supersampling factor) */
    meso_vec3 eye;
    meso_vec3 forward;     /* unit camera axis: view depth of P = dot(P - eye, forward) */
    meso_vec3 pixel_right; /* world step of one sample to the right on the plane depth = 1 */
    meso_vec3 pixel_down;  /* world step of one sample down on the plane depth = 1 */
    meso_vec3 corner;      /* eye-relative direction to the top-left corner (0,0) at depth 1 */
    meso_mat4 view, projection, view_projection;
    float z_near, z_far;
    /* footprint filtering (meso_render_filter): the rasterizer fills the fragments' uv
     * derivatives and the shading reads the maps' mip levels by them; false (the default of
     * meso_frame_init): level 0 at the sample's uv, as if every footprint were a point */
    bool filter;
    meso_progress *progress; /* NULL, or advanced by each tile's samples (width x height in all) */
} meso_frame;

/* Fill a frame for the scene's camera and a target of width x height samples. */
void meso_frame_init(meso_frame *frame, const meso_scene *scene, int width, int height);

/* The (unnormalised) direction of the camera ray through the point (x, y) of the target in
 * sample units; the centre of sample (i, j) is (i + 0.5, j + 0.5). Its depth component
 * dot(dir, forward) is 1. The rasterizer's fragments and the reference's rays agree exactly. */
static inline meso_vec3 meso_frame_ray_direction(const meso_frame *frame, float x, float y) {
    return meso_vec3_add(frame->corner, meso_vec3_add(meso_vec3_scale(frame->pixel_right, x),
                                                      meso_vec3_scale(frame->pixel_down, y)));
}

/* ---- Fragments ---------------------------------------------------------------------------- */

typedef struct meso_fragment {
    /* inputs, set by the rasterizer */
    float x, y;                   /* sample centre in the target (i + 0.5, j + 0.5) */
    uint32_t triangle;            /* triangle index in the drawn mesh */
    float b0, b1, b2;             /* perspective-correct barycentrics of its vertices */
    meso_vec3 position;           /* point on the drawn (base) mesh, world space */
    meso_vec3 normal;             /* interpolated vertex normal, unit */
    meso_vec3 tangent, bitangent; /* interpolated dP/du, dP/dv (zero without UVs) */
    meso_vec2 uv;                 /* interpolated, uv_scale applied */
    /* the footprint: duv/dx and duv/dy, the change of uv from this sample to the next one to
     * the right and down on the base triangle's plane (filled when frame->filter; else 0) */
    meso_vec2 duv_dx, duv_dy;
    float depth; /* view depth of `position` */
    /* outputs, preset by the rasterizer */
    meso_vec3 color; /* linear RGB (preset 0) */
    float out_depth; /* preset to depth; a technique may replace it (depth
                        correction); it must not be smaller than `depth` except
                        on back faces of a both_faces technique */
    bool discard;    /* preset false; true: nothing is drawn (silhouettes) */
} meso_fragment;

/* A block of fragments in structure-of-arrays form:
 * what the rasterizer hands a technique's shade_block, one (object, screen tile) batch at a time.
 * Fragment i is lane i of every array, in the rasterizer's order (chunks, their triangles,
 * each triangle's samples row by row), so a triangle's fragments are consecutive. The arrays
 * are 32-byte aligned and hold MESO_FRAGMENT_BLOCK_CAPACITY + 8 entries: lanes
 * count..(count rounded up to 8) - 1 repeat fragment count - 1 (finite inputs a technique may
 * compute on; their outputs are ignored), so a technique reads and writes whole groups of 8
 * with aligned vector loads and stores. The fields mean what meso_fragment's do. */
#define MESO_FRAGMENT_BLOCK_CAPACITY 1024 /* a screen tile's samples (raster_internal.h) */
#define MESO_FRAGMENT_BLOCK_LANES (MESO_FRAGMENT_BLOCK_CAPACITY + 8)
typedef struct meso_fragment_block {
    size_t count; /* fragments 0..count-1, at most MESO_FRAGMENT_BLOCK_CAPACITY */
    /* inputs, set by the rasterizer */
    _Alignas(32) float x[MESO_FRAGMENT_BLOCK_LANES];
    _Alignas(32) float y[MESO_FRAGMENT_BLOCK_LANES];
    _Alignas(32) uint32_t triangle[MESO_FRAGMENT_BLOCK_LANES];
    _Alignas(32) float b0[MESO_FRAGMENT_BLOCK_LANES];
    _Alignas(32) float b1[MESO_FRAGMENT_BLOCK_LANES];
    _Alignas(32) float b2[MESO_FRAGMENT_BLOCK_LANES];
    _Alignas(32) float px[MESO_FRAGMENT_BLOCK_LANES]; /* position */
    _Alignas(32) float py[MESO_FRAGMENT_BLOCK_LANES];
    _Alignas(32) float pz[MESO_FRAGMENT_BLOCK_LANES];
    _Alignas(32) float nx[MESO_FRAGMENT_BLOCK_LANES]; /* normal, unit */
    _Alignas(32) float ny[MESO_FRAGMENT_BLOCK_LANES];
    _Alignas(32) float nz[MESO_FRAGMENT_BLOCK_LANES];
    _Alignas(32) float tx[MESO_FRAGMENT_BLOCK_LANES]; /* tangent dP/du */
    _Alignas(32) float ty[MESO_FRAGMENT_BLOCK_LANES];
    _Alignas(32) float tz[MESO_FRAGMENT_BLOCK_LANES];
    _Alignas(32) float bx[MESO_FRAGMENT_BLOCK_LANES]; /* bitangent dP/dv */
    _Alignas(32) float by[MESO_FRAGMENT_BLOCK_LANES];
    _Alignas(32) float bz[MESO_FRAGMENT_BLOCK_LANES];
    _Alignas(32) float u[MESO_FRAGMENT_BLOCK_LANES];
    _Alignas(32) float v[MESO_FRAGMENT_BLOCK_LANES];
    /* the footprint (meso_fragment.duv_dx, duv_dy): filled only when frame->filter */
    _Alignas(32) float dudx[MESO_FRAGMENT_BLOCK_LANES];
    _Alignas(32) float dvdx[MESO_FRAGMENT_BLOCK_LANES];
    _Alignas(32) float dudy[MESO_FRAGMENT_BLOCK_LANES];
    _Alignas(32) float dvdy[MESO_FRAGMENT_BLOCK_LANES];
    _Alignas(32) float depth[MESO_FRAGMENT_BLOCK_LANES];
    /* outputs, preset by the rasterizer as meso_fragment's: colour 0, out_depth = depth,
     * discard 0 (1: nothing drawn) */
    _Alignas(32) float r[MESO_FRAGMENT_BLOCK_LANES];
    _Alignas(32) float g[MESO_FRAGMENT_BLOCK_LANES];
    _Alignas(32) float b[MESO_FRAGMENT_BLOCK_LANES];
    _Alignas(32) float out_depth[MESO_FRAGMENT_BLOCK_LANES];
    _Alignas(32) uint8_t discard[MESO_FRAGMENT_BLOCK_LANES];
} meso_fragment_block;

/* Fields of a block a technique may declare it never reads (meso_technique.skip_fields). The
 * position, normal, uv, depth and the out_depth and discard presets are always filled. The
 * tangents are filled whatever a technique declares for an object with a normal map (the
 * shading model reads them there). */
#define MESO_FRAGMENT_SKIP_SAMPLE 1u       /* x, y */
#define MESO_FRAGMENT_SKIP_TRIANGLE 2u     /* triangle */
#define MESO_FRAGMENT_SKIP_BARYCENTRICS 4u /* b0, b1, b2 */
#define MESO_FRAGMENT_SKIP_TANGENTS 8u     /* tx..tz, bx..bz */
/* the colour preset (r, g, b = 0): the technique writes the colour of every lane */
#define MESO_FRAGMENT_SKIP_COLOR_PRESET 16u

/* Fragment i of the block as a meso_fragment, inputs and outputs. */
void meso_fragment_block_get(const meso_fragment_block *block, size_t i, meso_fragment *out);
/* Write fragment i of the block from f, inputs and outputs; fragments past count are not
 * padded (meso_fragment_block_pad does). */
void meso_fragment_block_set(meso_fragment_block *block, size_t i, const meso_fragment *f);
/* Fill the lanes count..(count rounded up to 8) - 1 with copies of fragment count - 1. */
void meso_fragment_block_pad(meso_fragment_block *block);
/* Fragment i's footprint (duv_dx, duv_dy) from the block: for a technique that builds its own
 * meso_fragments from a block's lanes and shades them with meso_shade_fragments. */
static inline void meso_fragment_footprint_from_block(meso_fragment *f,
                                                      const meso_fragment_block *block, size_t i) {
    f->duv_dx = (meso_vec2){block->dudx[i], block->dvdx[i]};
    f->duv_dy = (meso_vec2){block->dudy[i], block->dvdy[i]};
}

/* ---- Techniques --------------------------------------------------------------------------- */

typedef struct meso_technique {
    meso_technique_info info;
    /* Per-object preparation: bake maps, per-vertex data. *out_state may be left NULL.
     * Reads the object's options with meso_technique_options_read and the technique's table
     * (info.options), which rejects unknown names and values out of range. */
    meso_result (*prepare)(meso_context *ctx, const meso_scene *scene, const meso_object *object,
                           void **out_state);
    /* Free the state; called with NULL too. */
    void (*release)(void *state);
    /* Geometry techniques (NULL otherwise): the triangles to rasterize for this frame,
     * owned by the state and valid until the next call. Called once a frame, single-threaded,
     * before rasterization. Per-pixel techniques draw object->mesh, unless they have this
     * function and it gives other triangles (the relief family's `shell` option draws the
     * prism shell's boundary; *out_mesh NULL: object->mesh). */
    meso_result (*geometry)(meso_context *ctx, void *state, const meso_frame *frame,
                            const meso_mesh **out_mesh);
    /* Shade `count` fragments of one object in one screen tile. A batch may span triangles:
     * each fragment names its own `triangle`, and a triangle's fragments are consecutive (the
     * rasterizer gathers one object's triangles of a tile in order, raster_tiles.c); no two
     * fragments of a batch share a sample. The result of a fragment must not depend on the
     * others of its batch (images stay byte-identical whatever the batching). Called from many
     * threads at once with different fragments; reads the state only. */
    void (*shade)(const void *state, const meso_frame *frame, const meso_object *object,
                  meso_fragment *fragments, size_t count);
    /* The same batch in structure-of-arrays form (NULL: the rasterizer calls `shade` through
     * meso_technique_shade_block's adapter). When present the rasterizer calls it instead of
     * `shade`, and `shade` may be NULL. Everything said of `shade` holds: block->count
     * fragments (>= 1) of one object in one tile, a triangle's fragments consecutive, no two
     * sharing a sample, each fragment's result independent of the others and of where the
     * block is cut. It reads the inputs and writes only the outputs (r, g, b, out_depth,
     * discard) of lanes 0..count-1; it may write the padding lanes' outputs too (whole groups
     * of 8) but no other memory, and must not change the inputs. Called from many threads at
     * once with different blocks; reads the state only. Images are byte-identical whether a
     * technique is drawn through shade or shade_block, for any thread count. */
    void (*shade_block)(const void *state, const meso_frame *frame, const meso_object *object,
                        meso_fragment_block *block);
    /* Fragment fields the rasterizer need not fill for this technique's shade_block
     * (MESO_FRAGMENT_SKIP_*; 0: every field, the default; ignored for techniques drawn
     * through `shade`, whose adapter copies every field). A skipped field holds stale values
     * the technique must not read. Filling only what is read saves a flat frame's tangent
     * frame and barycentrics (docs/rasterizer.md). */
    unsigned skip_fields;
    /* Bytes of baked data held by the state (NULL: 0). */
    size_t (*memory)(const void *state);
    /* Per-pixel techniques that draw back faces too (relief_layers: a closed mesh's far wall
     * seen through holes in the near one, and impostors seen from behind, Policarpo &
     * Oliveira 2006 §4). Their back-face fragments have dot(position - eye, normal) > 0 and
     * may write an out_depth smaller than `depth` (the hit lies between the shell's bottom and
     * the mesh, toward the eye); early depth rejection stays valid since nothing else lies
     * inside the shell. */
    bool both_faces;
    /* NULL, or whether one object's state draws both faces although the technique does not
     * always (the geometry techniques on an open displaced surface, displace_common.h). */
    bool (*state_both_faces)(const void *state);
    /* NULL, or the work counted in the last frame drawn (meso_render_stats: prisms, lookups,
     * samples), added to out[0..2]. Called once a frame after it is drawn, single-threaded. */
    void (*counters)(const void *state, uint64_t out[3]);
} meso_technique;

/* Every technique's entry (techniques/<name>.c), so a file can name its own info. */
#define MESO_TECHNIQUE(name) extern const meso_technique meso_technique_##name;
#include "technique_list.h"
#undef MESO_TECHNIQUE

/* Shade a block with technique t: t->shade_block, or (adapter for techniques written per
 * fragment) the block as meso_fragments through t->shade and back (render_fragments.c).
 * `scratch` holds block->count meso_fragments for the adapter (NULL when t has shade_block).
 * Thread-safe as the technique is. */
void meso_technique_shade_block(const meso_technique *t, const void *state, const meso_frame *frame,
                                const meso_object *object, meso_fragment_block *block,
                                meso_fragment *scratch);
/* Shade `count` meso_fragments with technique t: t->shade, or (a technique with shade_block
 * only) through a block, MESO_FRAGMENT_BLOCK_CAPACITY at a time. For callers that build
 * fragments by hand (tests); returns MESO_ERROR_OUT_OF_MEMORY when the block cannot be
 * allocated. Thread-safe as the technique is. */
meso_result meso_technique_shade(const meso_technique *t, const void *state,
                                 const meso_frame *frame, const meso_object *object,
                                 meso_fragment *fragments, size_t count);

/* The registry (technique_registry.c, list in techniques/technique_list.h). NULL if unknown. */
const meso_technique *meso_technique_lookup(const char *name);
/* "flat, bump, ..." into buffer (truncated to fit), for messages. */
void meso_technique_list_names(char *buffer, size_t size);

/* ---- Technique options -------------------------------------------------------------------- */

/* A row of an option table: the value lives at offsetof(struct, member) of the technique's own
 * option struct, with the type and range given. */
#define MESO_OPTION_ROW(type, name, min, max, default_value, doc, struct_type, member)             \
    { #name, type, min, max, default_value, doc, offsetof(struct_type, member) }
#define MESO_OPTION_COUNT(table) (sizeof(table) / sizeof((table)[0]))

/* Write the table's defaults into `values` (the technique's option struct). */
void meso_technique_options_defaults(const meso_technique_info *technique, void *values);
/* The one option reader: write over `values` the object's options for this technique (the
 * flat form, then the keyed form, so the keyed one wins), each checked by
 * meso_technique_check_option; the message names the scene file and the key path. */
meso_result meso_technique_options_apply(meso_context *ctx, const meso_scene *scene,
                                         const meso_object *object,
                                         const meso_technique_info *technique, void *values);
/* Defaults, then the object's options: what a technique's prepare calls. */
meso_result meso_technique_options_read(meso_context *ctx, const meso_scene *scene,
                                        const meso_object *object,
                                        const meso_technique_info *technique, void *values);

/* Add desc's options to `object` (a copy the caller owns), replacing its own setting of the
 * same technique and name: what meso_renderer_create draws. MESO_ERROR_LIMIT past
 * MESO_OPTIONS_MAX settings. */
meso_result meso_object_merge_options(meso_context *ctx, const meso_scene *scene,
                                      meso_object *object, const meso_render_desc *desc);

/* ---- Shading (shared by every technique and the reference) -------------------------------- */

/* Unit direction from `position` toward the light. */
static inline meso_vec3 meso_light_direction(const meso_light *light, meso_vec3 position) {
    return light->type == MESO_LIGHT_DIRECTIONAL
               ? light->direction
               : meso_vec3_normalize(meso_vec3_sub(light->position, position));
}

/* The shading model of docs/design.md: albedo * colour map(uv) * (ambient + sum over lights of
 * colour * max(0, N.L) * visibility[i]) + Blinn-Phong specular * visibility[i].
 * normal is unit; visibility may be NULL (every light visible). Pure, thread-safe. */
meso_vec3 meso_shade_point(const meso_frame *frame, const meso_object *object, meso_vec3 position,
                           meso_vec3 normal, meso_vec2 uv, const float *visibility);

/* meso_shade_point with the base surface's tangent (dP/du) and bitangent (dP/dv) at the point,
 * which orient an object's normal map (render_shading.c); meso_shade_point passes zero ones
 * (a normal map is then not applied). */
meso_vec3 meso_shade_point_tb(const meso_frame *frame, const meso_object *object,
                              meso_vec3 position, meso_vec3 normal, meso_vec3 tangent,
                              meso_vec3 bitangent, meso_vec2 uv, const float *visibility);

/* meso_shade_point_tb for a sample whose base uv changes by duv_dx, duv_dy from one sample to
 * the next (its footprint, meso_fragment): the maps are read filtered by it when
 * frame->filter (render_filter.h), else as meso_shade_point_tb reads them. */
meso_vec3 meso_shade_point_footprint(const meso_frame *frame, const meso_object *object,
                                     meso_vec3 position, meso_vec3 normal, meso_vec3 tangent,
                                     meso_vec3 bitangent, meso_vec2 uv, meso_vec2 duv_dx,
                                     meso_vec2 duv_dy, const float *visibility);

/* meso_shade_point for every fragment of a batch, 8 at a time, with the same bits:
 * fragments[i].color = meso_shade_point(frame, object, fragments[i].position,
 * fragments[i].normal, fragments[i].uv, visibility ? visibility + i * num_lights : NULL)
 * (meso_shade_point_tb with fragments[i].tangent, .bitangent).
 * A technique that changes the normal or uv writes them into the fragment first; with
 * frame->filter the maps are read by each fragment's footprint (duv_dx, duv_dy). Pure. */
void meso_shade_fragments(const meso_frame *frame, const meso_object *object,
                          meso_fragment *fragments, size_t count, const float *visibility);

/* The normal of the height-field surface P' = P - (1 - h) depth N over a base point with frame
 * (normal, tangent = dP/du, bitangent = dP/dv) and height gradient (dh/du, dh/dv):
 * normalize(cross(T + depth h_u N, B + depth h_v N)), turned to the side of `normal`.
 * Inline: it runs once per fragment in every height-field technique, and a call passing
 * vec3s by value cost a third of bump mapping's frame. */
static inline meso_vec3 meso_displaced_normal(meso_vec3 normal, meso_vec3 tangent,
                                              meso_vec3 bitangent, float depth,
                                              meso_vec2 gradient) {
    /* P' = P - (1 - h) depth N: dP'/du = T + depth h_u N, dP'/dv = B + depth h_v N
     * (Blinn 1978, with the variation of N over the surface neglected). */
    meso_vec3 du = meso_vec3_madd(tangent, normal, depth * gradient.x);
    meso_vec3 dv = meso_vec3_madd(bitangent, normal, depth * gradient.y);
    meso_vec3 n = meso_vec3_cross(du, dv);
    float len2 = meso_vec3_dot(n, n);
    if (!(len2 > 0.0f) || !isfinite(len2)) return normal;
    n = meso_vec3_scale(n, 1.0f / sqrtf(len2));
    return meso_vec3_dot(n, normal) < 0.0f ? meso_vec3_negate(n) : n;
}

/* ---- Rasterizer hooks for techniques ------------------------------------------------------ */

/* The set-up triangles and tile lists of meso_raster_depth_map, kept from one call to the next
 * (the buffers only grow): a shadow map redrawn every frame from a new mesh then reuses pages
 * already touched instead of having the kernel zero fresh ones (moving camera).
 * Opaque; made by the first meso_raster_depth_map given a pointer to NULL. */
typedef struct meso_raster_depth_scratch meso_raster_depth_scratch;

/* Rasterize `mesh` (all triangles, both faces) with `view_projection` into a depth-only target
 * of width x height samples, for shadow maps: depth[j * width + i] receives the smallest
 * z_ndc * 0.5 + 0.5 of the triangles covering sample centre (i + 0.5, j + 0.5) (row 0 at the
 * top, +y up in NDC), and +INFINITY where none does. Same fill rule and clipping as the colour
 * rasterizer; parallel over tiles; byte-identical for any thread count.
 * scratch   NULL: the buffers are allocated and freed within the call. Else *scratch (NULL the
 *           first time: created here) holds them after the call, for the next; the caller frees
 *           it with meso_raster_depth_scratch_destroy. Not shared between concurrent calls. */
meso_result meso_raster_depth_map(meso_context *ctx, meso_raster_depth_scratch **scratch,
                                  const meso_mesh *mesh, meso_mat4 view_projection, int width,
                                  int height, float *depth);
/* Bytes held by the scratch (0 for NULL). */
size_t meso_raster_depth_scratch_memory(const meso_raster_depth_scratch *scratch);
/* Frees the scratch; NULL does nothing. */
void meso_raster_depth_scratch_destroy(meso_raster_depth_scratch *scratch);

/* ---- Back ends ---------------------------------------------------------------------------- */

/* The reference tracer (reference.c): true micro-geometry with Embree. */
typedef struct meso_reference meso_reference;
meso_result meso_reference_create(meso_context *ctx, const meso_scene *scene,
                                  meso_reference **out_reference);
/* Trace one sample per target sample of `frame` into the target arrays (width x height of the
 * frame): colour RGB, coverage 0/1, depth. */
meso_result meso_reference_render(meso_context *ctx, const meso_reference *reference,
                                  const meso_frame *frame, float *color, float *coverage,
                                  float *depth);
size_t meso_reference_memory(const meso_reference *reference);
uint64_t meso_reference_triangle_count(const meso_reference *reference);
void meso_reference_destroy(meso_reference *reference);

#endif
