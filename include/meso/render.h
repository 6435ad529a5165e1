/* meso rendering: framebuffers, the technique registry, renderers.
 *
 * Usage
 *   meso_renderer *r = NULL; meso_framebuffer *fb = NULL;
 *   meso_renderer_create(ctx, scene, &(meso_render_desc){.technique = "relief"}, &r);
 *   meso_framebuffer_create(ctx, scene->width, scene->height, &fb);
 *   meso_renderer_render(r, fb);             // as often as you like: prepared once
 *   meso_framebuffer_save_png(ctx, fb, scene->encoding, "out.png", NULL);
 *
 * A renderer prepares every object once (bakes maps, per-vertex data) and then draws frames:
 * per-pixel techniques run in meso's tiled multithreaded rasterizer; `reference` ray traces
 * the true micro-geometry with Embree. Output is byte-identical for any thread count.
 *
 * The framebuffer holds linear RGB colour, coverage (fraction of the pixel's samples covered
 * by any object: the silhouette mask) and depth (view-space distance along the camera's axis of
 * the visible surface; +inf where nothing is).
 */
#ifndef MESO_RENDER_H
#define MESO_RENDER_H

#include "meso/core.h"
#include "meso/image.h"
#include "meso/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- Framebuffers ------------------------------------------------------------------------- */

/* Made by meso_framebuffer_create, or by the caller around its own arrays (colour 3 floats a
 * pixel, coverage and depth 1, rows packed; any alignment, 64 bytes is what create uses):
 * renderers and the save functions only read and write through the pointers, never free or
 * replace them (the Python package draws into NumPy's arrays so, docs/python.md). */
typedef struct meso_framebuffer {
    int width, height;
    float *color;    /* RGB linear, 3 floats a pixel, row 0 at the top; background where empty */
    float *coverage; /* [0,1] a pixel */
    float *depth;    /* view depth of the nearest surface, +inf where empty */
} meso_framebuffer;

meso_result meso_framebuffer_create(meso_context *ctx, int width, int height,
                                    meso_framebuffer **out_framebuffer);
void meso_framebuffer_destroy(meso_framebuffer *framebuffer);

/* The colour as an RGB image (linear values), and the coverage as a grey image. */
meso_result meso_framebuffer_color_image(meso_context *ctx, const meso_framebuffer *fb,
                                         meso_image **out_image);
meso_result meso_framebuffer_coverage_image(meso_context *ctx, const meso_framebuffer *fb,
                                            meso_image **out_image);
/* Save the colour with the scene's encoding (sRGB unless the scene says linear). When
 * coverage_path is not NULL the coverage mask is written there as a grey PNG too: both files
 * or neither (meso_image_save_png_all). */
meso_result meso_framebuffer_save_png(meso_context *ctx, const meso_framebuffer *fb,
                                      meso_encoding encoding, const char *path,
                                      const char *coverage_path);
/* As meso_framebuffer_save_png, each file's format chosen by its extension (meso_image_save:
 * ".exr" is OpenEXR, half floats, linear and unclamped; else PNG), the colour PNG with desc's
 * bit depth and encoding (NULL: 8-bit sRGB), the coverage PNG linear at desc's bit depth. */
meso_result meso_framebuffer_save(meso_context *ctx, const meso_framebuffer *fb,
                                  const meso_png_desc *desc, const char *path,
                                  const char *coverage_path);

/* ---- Techniques --------------------------------------------------------------------------- */

typedef enum meso_technique_kind {
    MESO_TECHNIQUE_PER_PIXEL = 0, /* a fragment function on the base mesh */
    MESO_TECHNIQUE_GEOMETRY,      /* makes displaced triangles for the rasterizer */
    MESO_TECHNIQUE_REFERENCE,     /* ray traces the true micro-geometry */
} meso_technique_kind;

/* What a technique needs of an object's mesostructure. */
enum {
    MESO_TECHNIQUE_ACCEPTS_NONE = 1u << 0, /* objects without mesostructure */
    MESO_TECHNIQUE_ACCEPTS_HEIGHT_FIELD = 1u << 1,
    MESO_TECHNIQUE_ACCEPTS_SOLID = 1u << 2, /* a solid that tiles (procedural or a tile mesh) */
    /* a whole model's solid, clamped at its box (a relief impostor, Policarpo & Oliveira 2006
     * §4; meso_solid_is_periodic is false): no tile to repeat */
    MESO_TECHNIQUE_ACCEPTS_MODEL_SOLID = 1u << 3,
};

typedef enum meso_option_type {
    MESO_OPTION_INT = 0, /* a whole number in [min, max]; kept as int */
    MESO_OPTION_BOOL,    /* true / false (1 / 0); kept as bool */
    MESO_OPTION_FLOAT,   /* a finite number in [min, max]; kept as float */
} meso_option_type;

/* One row of a technique's option table: what `meso help TECHNIQUE` prints, and what the one
 * option reader (meso_technique_check_option and the render module's reader) checks. */
typedef struct meso_technique_option {
    const char *name; /* "linear_steps" */
    meso_option_type type;
    double min, max; /* inclusive (BOOL: 0, 1) */
    double default_value;
    const char *doc; /* one line */
    size_t offset;   /* where the technique keeps the value in its own option struct */
} meso_technique_option;

typedef struct meso_technique_info {
    const char *name;    /* "relief" */
    const char *summary; /* one line */
    const char *paper;   /* "Policarpo & Oliveira 2006, §2.1" */
    meso_technique_kind kind;
    unsigned accepts;                     /* MESO_TECHNIQUE_ACCEPTS_* */
    const meso_technique_option *options; /* the option table (NULL when it has none) */
    size_t num_options;
} meso_technique_info;

/* The MESO_TECHNIQUE_ACCEPTS_* bit a technique needs to draw `mesostructure`, and its name
 * ("none", "height field", "solid", "model's solid"). Pure. */
unsigned meso_mesostructure_accepts_bit(const meso_mesostructure *mesostructure);
const char *meso_mesostructure_accepts_name(unsigned accepts_bit);
/* Whether `technique` can draw an object with `mesostructure` (its accepts has the bit). The
 * one test of applicability: the renderers refuse what it refuses, and the commands skip
 * those techniques as "not applicable". Pure. */
bool meso_technique_accepts(const meso_technique_info *technique,
                            const meso_mesostructure *mesostructure);

/* The registered techniques, in a fixed order (flat, bump, ...). Thread-safe. */
size_t meso_technique_count(void);
/* The instruction set the techniques run with: "avx2" (a portable x86-64 build on a CPU with
 * AVX2, FMA and F16C), "baseline" (the portable code: other CPUs, or MESO_ISA=baseline in the
 * environment) or "native" (built with -DMESO_NATIVE=ON). The images are the same bits in every
 * case (docs/performance.md). Thread-safe. */
const char *meso_technique_isa(void);
const meso_technique_info *meso_technique_get(size_t index);
/* NULL when no technique has that name. */
const meso_technique_info *meso_technique_find(const char *name);
/* The row of the technique's option table called `name`; NULL when it has none. */
const meso_technique_option *meso_technique_find_option(const meso_technique_info *technique,
                                                        const char *name);
/* Check one option setting against its technique's table: the technique exists, it has the
 * option, the value has the option's type and lies in its range. `where` starts the message
 * ("scene.json: objects[0].technique_options.relief.linear_steps", "--set relief.x"):
 * "<where>: 2000 is not an integer in 1..1024". Returns MESO_OK or
 * MESO_ERROR_INVALID_ARGUMENT. Thread-safe. */
meso_result meso_technique_check_option(meso_context *ctx, const char *technique, const char *name,
                                        double value, const char *where);
/* Check what a scene says about techniques before any work: every object's technique name
 * exists, and every technique option (both forms) passes meso_technique_check_option. The
 * message names the file and the key path: "scene.json: objects[0].technique: unknown technique
 * 'relif' (known: ...)". meso_renderer_create runs it too. Thread-safe. */
meso_result meso_technique_check_scene(meso_context *ctx, const meso_scene *scene);

/* ---- Renderers ---------------------------------------------------------------------------- */

/* How the maps (colour, normal) are read per pixel (docs/techniques.md, "Filtering"). */
typedef enum meso_render_filter {
    MESO_RENDER_FILTER_DEFAULT = 0, /* MESO_RENDER_FILTER_POINT */
    MESO_RENDER_FILTER_POINT,       /* level 0, bilinear at the sample's uv: the papers' images */
    MESO_RENDER_FILTER_FOOTPRINT,   /* mip-mapped by the sample's footprint in texels */
} meso_render_filter;

typedef struct meso_render_desc {
    const char *technique;     /* NULL: each object's own; else overrides every object's */
    int samples;               /* 0 or 1: one sample at each pixel centre; S: an n x n ordered grid
                                  with n = ceil(sqrt(S)) */
    bool wireframe;            /* overlay the rasterized triangles' edges */
    meso_render_filter filter; /* texture filtering */
    /* Technique options for every object, each keyed by technique (meso_option.technique must
     * be set), over the scene's own: what `meso render --set relief.linear_steps=64` passes.
     * Read during meso_renderer_create only. */
    const meso_option *options;
    int num_options;
    /* Report progress (the context's bar and callback, docs/cli.md --progress) of the
     * reference's build and of every frame: for one long render, not for loops of frames. */
    bool progress;
    bool fallback; /* with `technique`: an object it cannot draw (its mesostructure is
                      not one it accepts) is drawn with the object's own scene technique
                      (or `flat` when that is `reference` or cannot draw it either)
                      instead of failing; see meso_renderer_object_technique */
} meso_render_desc;

/* The memory a frame of width x height with desc's samples needs besides the scene (the
 * framebuffer and, with supersampling, the n x n-times larger sample targets: colour,
 * coverage and depth, 20 bytes a sample; and the images it is saved from, 16 bytes a pixel).
 * desc may be NULL (one sample). Callers check it with meso_memory_check before
 * meso_framebuffer_create; meso_renderer_render checks it too. Pure. */
uint64_t meso_render_memory_estimate(const meso_render_desc *desc, int width, int height);

/* The values technique `technique` reads for scene->objects[object] when drawn with `desc`
 * (may be NULL): its option table's defaults, then the object's settings, then desc->options,
 * each checked as meso_renderer_create checks them. out_values[k] receives row k of the
 * technique's table (info->num_options entries; bools as 0 or 1). For other back ends that
 * draw the same techniques (the OpenGL one) with the same options. Thread-safe. */
meso_result meso_technique_options_values(meso_context *ctx, const meso_scene *scene, int object,
                                          const meso_render_desc *desc, const char *technique,
                                          double *out_values);

typedef struct meso_render_stats {
    double prepare_seconds;    /* meso_renderer_create */
    double last_frame_seconds; /* the last meso_renderer_render */
    uint64_t triangles;        /* rasterized or traced in the last frame */
    uint64_t fragments;        /* shaded in the last frame */
    size_t memory_bytes;       /* baked data, acceleration structures */
    /* work counted by the techniques in the last frame (0 where a technique counts none; gdm:
     * the prisms its view rays were tested in, its table lookups along view and light rays
     * in the slab, and the mesostructure's samples along them) */
    uint64_t prisms, lookups, samples;
} meso_render_stats;

/* The camera of a frame of width x height pixels, as the rasterizer and the reference use it:
 * eye, unit axis (view depth of P = dot(P - eye, forward)), OpenGL-style projection * view
 * (column-major; the rasterizer's clip space) and its near and far planes. Pure. */
typedef struct meso_render_camera {
    meso_vec3 eye, forward;
    meso_mat4 view_projection;
    float z_near, z_far;
    float pixel_size; /* world width of a pixel at view depth 1 */
} meso_render_camera;
meso_render_camera meso_render_camera_get(const meso_scene *scene, int width, int height);

typedef struct meso_renderer meso_renderer;

/* Prepare `scene` for rendering: checks each object's technique against its mesostructure
 * (MESO_ERROR_INVALID_ARGUMENT naming the object and technique), bakes what techniques need.
 * The scene must outlive the renderer. */
meso_result meso_renderer_create(meso_context *ctx, const meso_scene *scene,
                                 const meso_render_desc *desc, meso_renderer **out_renderer);
/* Draw one frame into fb (any size; the camera's aspect follows fb). Not thread-safe on one
 * renderer; uses every worker of the context. */
meso_result meso_renderer_render(meso_renderer *renderer, meso_framebuffer *fb);
meso_render_stats meso_renderer_get_stats(const meso_renderer *renderer);
/* The name of the technique drawing object `object` ("reference" for every object of a
 * reference renderer; NULL for an index out of range). Valid as long as the program runs. */
const char *meso_renderer_object_technique(const meso_renderer *renderer, int object);
void meso_renderer_destroy(meso_renderer *renderer);

/* Create a renderer, draw one frame of the scene's size, destroy: the one-call form. */
meso_result meso_render_scene(meso_context *ctx, const meso_scene *scene,
                              const meso_render_desc *desc, meso_framebuffer **out_framebuffer);

#ifdef __cplusplus
}
#endif
#endif
