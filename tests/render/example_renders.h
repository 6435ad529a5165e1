/* Rendering the shipped examples small, for the tests that compare whole images of every
 * example x technique (test_render_determinism, test_render_isa). */
#ifndef MESO_TEST_EXAMPLE_RENDERS_H
#define MESO_TEST_EXAMPLE_RENDERS_H

#include <stdio.h>

#include "test_util.h"

/* Small bakes for the techniques that bake, keyed by technique as --set passes them; the
 * reference's solids extracted on 64 cells a tile (the examples ask for up to 256, for accuracy
 * these tests do not measure). */
static const meso_option example_small_bakes[] = {
    {"vdm", "resolution", 32},     {"vdm", "num_theta", 16},        {"vdm", "num_curvatures", 4},
    {"relief_layers", "size", 64}, {"gdm", "resolution", 16},       {"gdm", "layers", 8},
    {"gdm", "num_theta", 8},       {"gdm", "num_phi", 8},           {"gdm", "gi_resolution", 16},
    {"gdm", "gi_layers", 4},       {"reference", "resolution", 64},
};

/* examples/<name>.json, its image made side x side. */
static inline meso_scene *example_scene_load(meso_context *ctx, const char *name, int side) {
    char path[1024];
    snprintf(path, sizeof path, "%s/examples/%s.json", MESO_SOURCE_DIR, name);
    meso_scene *scene = NULL;
    if (meso_scene_load(ctx, path, &scene) != MESO_OK)
        fail_msg("%s: %s", path, meso_context_last_error(ctx));
    scene->width = scene->height = side;
    return scene;
}

/* The scene drawn with `technique` (an object it cannot draw falls back to its own), the small
 * bakes, on `threads` threads, with texture filtering `filter`. */
static inline meso_framebuffer *example_render_filtered(const meso_scene *scene,
                                                        const char *technique, int threads,
                                                        meso_render_filter filter) {
    meso_context *ctx = test_context(threads);
    meso_render_desc desc = {.technique = technique,
                             .fallback = true,
                             .filter = filter,
                             .options = example_small_bakes,
                             .num_options =
                                 (int)(sizeof example_small_bakes / sizeof example_small_bakes[0])};
    meso_framebuffer *fb = NULL;
    if (meso_render_scene(ctx, scene, &desc, &fb) != MESO_OK)
        fail_msg("%s with %s, %d threads (%s techniques): %s", scene->path, technique, threads,
                 meso_technique_isa(), meso_context_last_error(ctx));
    meso_context_destroy(ctx);
    return fb;
}

/* example_render_filtered with the default filtering. */
static inline meso_framebuffer *example_render(const meso_scene *scene, const char *technique,
                                               int threads) {
    return example_render_filtered(scene, technique, threads, MESO_RENDER_FILTER_DEFAULT);
}

#endif
