/* Renderers: technique validation and preparation, then frames through the rasterizer (or the
 * reference tracer), supersampling resolve and statistics. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "raster_internal.h"
#include "reference_internal.h"
#include "meso/runtime.h"

#define RENDER_MAX_SAMPLES 256 /* samples a pixel (n = 16 a side) */

struct meso_renderer {
    meso_context *ctx;
    /* What is drawn: the caller's scene, or, when the desc sets options, a shallow copy whose
     * objects carry them too (view and objects are owned here; what they point to is not). */
    const meso_scene *scene;
    meso_scene *scene_view;
    meso_object *view_objects;
    const meso_scene *source; /* the caller's scene: the view's camera and lights each frame */
    int n;                    /* supersampling: n x n samples a pixel */
    bool wireframe;
    bool filter;   /* footprint filtering (meso_frame.filter) */
    bool progress; /* report each frame's progress */
    bool use_reference;
    meso_reference *reference;
    const meso_technique **techniques; /* per object */
    void **states;                     /* per object */
    raster_object *objects;
    const meso_mesh **meshes; /* drawn this frame */
    raster_pass pass;
    float *sample_color, *sample_coverage, *sample_depth;
    size_t sample_capacity;
    meso_render_stats stats;
    bool avx2; /* the rasterizer's AVX2 copy, with the techniques' (raster_internal.h) */
};

#if !MESO_HAS_AVX2_TECHNIQUES
#define raster_draw_avx2 raster_draw
#define raster_resolve_avx2 raster_resolve
#endif

static void list_names(char *buffer, size_t size, bool techniques_list, unsigned accepts) {
    size_t used = 0;
    buffer[0] = 0;
    if (techniques_list) {
        meso_technique_list_names(buffer, size);
        return;
    }
    const unsigned bits[] = {MESO_TECHNIQUE_ACCEPTS_NONE, MESO_TECHNIQUE_ACCEPTS_HEIGHT_FIELD,
                             MESO_TECHNIQUE_ACCEPTS_SOLID, MESO_TECHNIQUE_ACCEPTS_MODEL_SOLID};
    for (size_t i = 0; i < sizeof bits / sizeof bits[0]; i++) {
        if (!(accepts & bits[i])) continue;
        int w = snprintf(buffer + used, size - used, "%s%s", used ? ", " : "",
                         meso_mesostructure_accepts_name(bits[i]));
        if (w < 0 || (size_t)w >= size - used) return;
        used += (size_t)w;
    }
}

void meso_renderer_destroy(meso_renderer *renderer) {
    if (!renderer) return;
    if (renderer->states) {
        for (int i = 0; i < renderer->scene->num_objects; i++) {
            if (renderer->techniques[i] && renderer->techniques[i]->release)
                renderer->techniques[i]->release(renderer->states[i]);
        }
    }
    meso_reference_destroy(renderer->reference);
    raster_pass_release(&renderer->pass);
    free(renderer->view_objects);
    free(renderer->scene_view);
    free(renderer->techniques);
    free(renderer->states);
    free(renderer->objects);
    free(renderer->meshes);
    free(renderer->sample_color);
    free(renderer->sample_coverage);
    free(renderer->sample_depth);
    free(renderer);
}

/* The technique of object i, checked against its mesostructure. With `fallback`, an override
 * that cannot draw the object gives way to the object's own technique (mixed
 * scenes), or to `flat` when that is the reference or cannot draw it either. */
static meso_result resolve_technique(meso_context *ctx, const meso_object *object,
                                     const char *override, bool fallback,
                                     const meso_technique **out) {
    char list[512];
    const char *own = object->technique[0] ? object->technique : "flat";
    const char *name = override ? override : own;
    const meso_technique *t = meso_technique_lookup(name);
    *out = NULL;
    if (fallback && override && t && !meso_technique_accepts(&t->info, &object->mesostructure)) {
        const meso_technique *mine = meso_technique_lookup(own);
        bool usable = mine && mine->info.kind != MESO_TECHNIQUE_REFERENCE &&
                      meso_technique_accepts(&mine->info, &object->mesostructure);
        name = usable ? own : "flat";
        t = meso_technique_lookup(name);
    }
    if (!t) {
        list_names(list, sizeof(list), true, 0);
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: unknown technique '%s' (known: %s)", object->name, name, list);
    }
    if (!meso_technique_accepts(&t->info, &object->mesostructure)) {
        list_names(list, sizeof(list), false, t->info.accepts);
        return meso_log_error(
            ctx, MESO_ERROR_INVALID_ARGUMENT,
            "%s: technique '%s' does not accept mesostructure '%s' (it accepts: %s)", object->name,
            name,
            meso_mesostructure_accepts_name(meso_mesostructure_accepts_bit(&object->mesostructure)),
            list);
    }
    if (t->info.kind == MESO_TECHNIQUE_GEOMETRY && !t->geometry) {
        return meso_log_error(ctx, MESO_ERROR_INTERNAL,
                              "%s: technique '%s' has no geometry function", object->name, name);
    }
    if (t->info.kind != MESO_TECHNIQUE_REFERENCE && !t->shade && !t->shade_block) {
        return meso_log_error(ctx, MESO_ERROR_INTERNAL, "%s: technique '%s' has no shade function",
                              object->name, name);
    }
    *out = t;
    return MESO_OK;
}

/* The scene with the desc's options added to every object (replacing the object's own setting
 * of the same technique and name): the techniques read them like the scene's. */
static meso_result make_scene_view(meso_context *ctx, const meso_scene *scene,
                                   const meso_render_desc *desc, meso_renderer *rd) {
    int count = scene->num_objects > 0 ? scene->num_objects : 0;
    rd->scene_view = malloc(sizeof *rd->scene_view);
    rd->view_objects = calloc(count > 0 ? (size_t)count : 1, sizeof *rd->view_objects);
    if (!rd->scene_view || !rd->view_objects)
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", scene->path);
    *rd->scene_view = *scene;
    rd->scene_view->objects = rd->view_objects;
    for (int o = 0; o < count; o++) {
        rd->view_objects[o] = scene->objects[o];
        meso_result r = meso_object_merge_options(ctx, scene, &rd->view_objects[o], desc);
        if (r != MESO_OK) return r;
    }
    return MESO_OK;
}

meso_result meso_renderer_create(meso_context *ctx, const meso_scene *scene,
                                 const meso_render_desc *desc, meso_renderer **out_renderer) {
    *out_renderer = NULL;
    if (!scene) return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "render: NULL scene");
    meso_render_desc d = desc ? *desc : (meso_render_desc){0};
    if (d.filter < MESO_RENDER_FILTER_DEFAULT || d.filter > MESO_RENDER_FILTER_FOOTPRINT)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: filter: %d is not a mode",
                              scene->path, (int)d.filter);
    if (d.samples < 0) {
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: samples: %d must be >= 0",
                              scene->path, d.samples);
    }
    if (d.samples > RENDER_MAX_SAMPLES) {
        return meso_log_error(ctx, MESO_ERROR_LIMIT, "%s: samples: %d exceeds the limit %d",
                              scene->path, d.samples, RENDER_MAX_SAMPLES);
    }
    if (d.technique && !meso_technique_lookup(d.technique)) {
        char list[512];
        list_names(list, sizeof(list), true, 0);
        return meso_log_error(
            ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: unknown technique '%s' (known: %s)",
            scene->num_objects > 0 ? scene->objects[0].name : scene->path, d.technique, list);
    }
    meso_result r = meso_technique_check_scene(ctx, scene);
    if (r != MESO_OK) return r;
    for (int i = 0; i < d.num_options; i++) {
        char where[160];
        snprintf(where, sizeof where, "render options: %s.%s", d.options[i].technique,
                 d.options[i].name);
        if (!d.options[i].technique[0])
            return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                                  "%s: an option of the render desc needs its technique", where);
        if ((r = meso_technique_check_option(ctx, d.options[i].technique, d.options[i].name,
                                             d.options[i].value, where)) != MESO_OK)
            return r;
    }
    double start = meso_time_seconds();
    meso_renderer *rd = calloc(1, sizeof(*rd));
    int count = scene->num_objects > 0 ? scene->num_objects : 0;
    size_t slots = count > 0 ? (size_t)count : 1;
    if (!rd) goto oom;
    rd->ctx = ctx;
    rd->avx2 = strcmp(meso_technique_isa(), "avx2") == 0;
    rd->source = scene;
    if (d.num_options > 0) {
        if ((r = make_scene_view(ctx, scene, &d, rd)) != MESO_OK) goto fail;
        scene = rd->scene_view;
    }
    rd->scene = scene;
    rd->wireframe = d.wireframe;
    rd->filter = d.filter == MESO_RENDER_FILTER_FOOTPRINT;
    rd->progress = d.progress;
    rd->n = d.samples <= 1 ? 1 : (int)ceil(sqrt((double)d.samples) - 1e-9);
    rd->techniques = calloc(slots, sizeof(*rd->techniques));
    rd->states = calloc(slots, sizeof(*rd->states));
    rd->objects = calloc(slots, sizeof(*rd->objects));
    rd->meshes = calloc(slots, sizeof(*rd->meshes));
    if (!rd->techniques || !rd->states || !rd->objects || !rd->meshes) goto oom;

    int first_reference = -1, first_other = -1;
    for (int i = 0; i < count; i++) {
        const meso_technique *t = NULL;
        if ((r = resolve_technique(ctx, &scene->objects[i], d.technique, d.fallback, &t)) !=
            MESO_OK)
            goto fail;
        rd->techniques[i] = t; /* resolved once: prepared below unless the reference draws */
        if (t->info.kind == MESO_TECHNIQUE_REFERENCE) {
            if (first_reference < 0) first_reference = i;
        } else if (first_other < 0) {
            first_other = i;
        }
    }
    if (first_reference >= 0 && first_other >= 0) {
        const meso_object *a = &scene->objects[first_reference], *b = &scene->objects[first_other];
        const char *other = d.technique ? d.technique : b->technique;
        r = meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                           "%s: technique 'reference' cannot be mixed with '%s' of %s in one scene "
                           "(the reference traces the whole scene)",
                           a->name, other[0] ? other : "flat", b->name);
        goto fail;
    }
    rd->use_reference = first_reference >= 0;
    if (rd->use_reference) {
        meso_reference_desc reference_desc = {.progress = d.progress};
        if ((r = meso_reference_create_with(ctx, scene, &reference_desc, &rd->reference)) !=
            MESO_OK)
            goto fail;
        rd->stats.memory_bytes = meso_reference_memory(rd->reference);
    } else {
        for (int i = 0; i < count; i++) {
            const meso_object *object = &scene->objects[i];
            const meso_technique *t = rd->techniques[i];
            if (t->prepare && (r = t->prepare(ctx, scene, object, &rd->states[i])) != MESO_OK)
                goto fail;
            if (t->memory) rd->stats.memory_bytes += t->memory(rd->states[i]);
            rd->objects[i] = (raster_object){object, t, rd->states[i]};
        }
    }
    rd->stats.prepare_seconds = meso_time_seconds() - start;
    *out_renderer = rd;
    return MESO_OK;
oom:
    r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory preparing the renderer",
                       scene->path);
fail:
    meso_renderer_destroy(rd);
    return r;
}

static meso_result reserve_samples(meso_renderer *rd, size_t samples) {
    if (samples <= rd->sample_capacity) return MESO_OK;
    free(rd->sample_color);
    free(rd->sample_coverage);
    free(rd->sample_depth);
    rd->sample_capacity = 0;
    rd->sample_color = meso_render_alloc_floats(3 * samples);
    rd->sample_coverage = meso_render_alloc_floats(samples);
    rd->sample_depth = meso_render_alloc_floats(samples);
    if (!rd->sample_color || !rd->sample_coverage || !rd->sample_depth) {
        return meso_log_error(rd->ctx, MESO_ERROR_OUT_OF_MEMORY,
                              "render: out of memory for %zu samples", samples);
    }
    rd->sample_capacity = samples;
    return MESO_OK;
}

static void clear_target(const meso_scene *scene, size_t samples, float *color, float *coverage,
                         float *depth) {
    for (size_t i = 0; i < samples; i++) {
        color[3 * i + 0] = scene->background.x;
        color[3 * i + 1] = scene->background.y;
        color[3 * i + 2] = scene->background.z;
        coverage[i] = 0.0f;
        depth[i] = INFINITY;
    }
}

/* The frame's work: the reference or the rasterizer, then the supersampling resolve. */
static meso_result draw_frame(meso_renderer *rd, meso_framebuffer *fb, const meso_frame *f,
                              size_t samples) {
    meso_context *ctx = rd->ctx;
    meso_frame frame = *f;
    int n = rd->n;
    float *color = fb->color, *coverage = fb->coverage, *depth = fb->depth;
    meso_result r;
    if (n > 1) {
        meso_render_desc desc = {.samples = n * n};
        if ((r = meso_memory_check(ctx, rd->scene->path,
                                   meso_render_memory_estimate(&desc, fb->width, fb->height))) !=
                MESO_OK ||
            (r = reserve_samples(rd, samples)) != MESO_OK)
            return r;
        color = rd->sample_color, coverage = rd->sample_coverage, depth = rd->sample_depth;
    }
    uint64_t triangles = 0, fragments = 0;
    if (rd->use_reference) {
        clear_target(rd->scene, samples, color, coverage, depth);
        r = meso_reference_render(ctx, rd->reference, &frame, color, coverage, depth);
        if (r != MESO_OK) return r;
        triangles = meso_reference_triangle_count(rd->reference);
        fragments = samples;
    } else {
        int count = rd->scene->num_objects;
        for (int i = 0; i < count; i++) {
            const meso_technique *t = rd->techniques[i];
            rd->meshes[i] = rd->scene->objects[i].mesh;
            if (t->geometry) { /* a per-pixel technique's NULL: the object's mesh */
                const meso_mesh *mesh = NULL;
                if ((r = t->geometry(ctx, rd->states[i], &frame, &mesh)) != MESO_OK) return r;
                if (mesh || t->info.kind == MESO_TECHNIQUE_GEOMETRY) rd->meshes[i] = mesh;
            }
        }
        r = (rd->avx2 ? raster_draw_avx2 : raster_draw)(ctx, &rd->pass, &frame, rd->objects,
                                                        rd->meshes, count, rd->wireframe, color,
                                                        coverage, depth, &triangles, &fragments);
        if (r != MESO_OK) return r;
        uint64_t counted[3] = {0, 0, 0};
        for (int i = 0; i < count; i++)
            if (rd->techniques[i]->counters) rd->techniques[i]->counters(rd->states[i], counted);
        rd->stats.prisms = counted[0], rd->stats.lookups = counted[1];
        rd->stats.samples = counted[2];
    }
    if (n > 1) {
        (rd->avx2 ? raster_resolve_avx2 : raster_resolve)(ctx, n, fb->width, fb->height, color,
                                                          coverage, depth, fb->color, fb->coverage,
                                                          fb->depth);
    }
    rd->stats.triangles = triangles;
    rd->stats.fragments = fragments;
    return MESO_OK;
}

meso_result meso_renderer_render(meso_renderer *renderer, meso_framebuffer *fb) {
    meso_renderer *rd = renderer;
    if (!rd) return MESO_ERROR_INVALID_ARGUMENT;
    meso_context *ctx = rd->ctx;
    if (!fb || fb->width <= 0 || fb->height <= 0 || !fb->color || !fb->coverage || !fb->depth)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "render: invalid framebuffer");
    int n = rd->n;
    if ((int64_t)fb->width * n > RASTER_MAX_TARGET_SIDE ||
        (int64_t)fb->height * n > RASTER_MAX_TARGET_SIDE ||
        (uint64_t)fb->width * (uint64_t)fb->height * (uint64_t)(n * n) > ((uint64_t)1 << 30)) {
        return meso_log_error(ctx, MESO_ERROR_LIMIT,
                              "render: %d x %d pixels with %d x %d samples exceed the limit of "
                              "%d samples a side, 2^30 in all",
                              fb->width, fb->height, n, n, RASTER_MAX_TARGET_SIDE);
    }
    if (rd->scene_view) {
        /* the caller moves the camera or turns a light between frames (meso bench --orbit, the
         * viewer): the view copied at creation takes them, its objects (with the options) stay */
        meso_object *objects = rd->scene_view->objects;
        int num_objects = rd->scene_view->num_objects;
        *rd->scene_view = *rd->source;
        rd->scene_view->objects = objects;
        rd->scene_view->num_objects = num_objects;
    }
    double start = meso_time_seconds();
    meso_frame frame;
    meso_frame_init(&frame, rd->scene, fb->width * n, fb->height * n);
    frame.filter = rd->filter;
    size_t samples = (size_t)frame.width * (size_t)frame.height;
    if (rd->progress)
        frame.progress =
            meso_progress_begin(ctx, rd->use_reference ? "reference" : "render", (uint64_t)samples);
    meso_result r = draw_frame(rd, fb, &frame, samples);
    meso_progress_end(frame.progress);
    if (r != MESO_OK) return r;
    rd->stats.last_frame_seconds = meso_time_seconds() - start;
    return MESO_OK;
}

const char *meso_renderer_object_technique(const meso_renderer *renderer, int object) {
    if (!renderer || object < 0 || object >= renderer->scene->num_objects) return NULL;
    if (renderer->use_reference) return "reference";
    return renderer->techniques[object] ? renderer->techniques[object]->info.name : NULL;
}

meso_render_stats meso_renderer_get_stats(const meso_renderer *renderer) {
    return renderer ? renderer->stats : (meso_render_stats){0};
}

meso_result meso_render_scene(meso_context *ctx, const meso_scene *scene,
                              const meso_render_desc *desc, meso_framebuffer **out_framebuffer) {
    *out_framebuffer = NULL;
    if (!scene) return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "render: NULL scene");
    meso_renderer *renderer = NULL;
    meso_framebuffer *fb = NULL;
    meso_result r = meso_renderer_create(ctx, scene, desc, &renderer);
    if (r != MESO_OK) goto fail;
    if ((r = meso_framebuffer_create(ctx, scene->width, scene->height, &fb)) != MESO_OK) goto fail;
    if ((r = meso_renderer_render(renderer, fb)) != MESO_OK) goto fail;
    meso_renderer_destroy(renderer);
    *out_framebuffer = fb;
    return MESO_OK;
fail:
    meso_framebuffer_destroy(fb);
    meso_renderer_destroy(renderer);
    return r;
}
