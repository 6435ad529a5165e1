/* The plane scenes of the global-illumination tests (test_render_reference_path.c,
 * test_technique_gdm_gi.c), header-only. */
#ifndef GI_TEST_SCENE_H
#define GI_TEST_SCENE_H

#include <stdio.h>

#include "test_util.h"

/* A plane of size 2 seen from above at an angle, linear output, albedo `albedo`, drawn with
 * `technique`; `extra` adds top-level keys (environment, lights, ambient) and `mesostructure`
 * (may be NULL) the object's. */
static inline meso_scene *gi_plane_scene(meso_context *ctx, int size, const char *extra,
                                         const char *mesostructure, float albedo,
                                         const char *technique) {
    char json[4096];
    snprintf(json, sizeof json,
             "{\"image\": {\"width\": %d, \"height\": %d, \"encoding\": \"linear\"},"
             " \"camera\": {\"eye\": [0, 1.6, 1.2], \"target\": [0, 0, 0], \"fov_y_deg\": 40},"
             " %s,"
             " \"objects\": [{\"shape\": \"plane\", \"size\": 2, \"uv_scale\": [2, 2]%s%s,"
             " \"material\": {\"albedo\": [%g, %g, %g]}, \"technique\": \"%s\"}]}",
             size, size, extra, mesostructure ? ", \"mesostructure\": " : "",
             mesostructure ? mesostructure : "", (double)albedo, (double)albedo, (double)albedo,
             technique);
    meso_scene *scene = NULL;
    if (meso_scene_parse(ctx, json, "gi.json", NULL, &scene) != MESO_OK)
        fail_msg("scene: %s", meso_context_last_error(ctx));
    return scene;
}

/* The mean green channel over the covered pixels, and their count. */
static inline double gi_mean_covered(const meso_framebuffer *fb, size_t *out_covered) {
    double sum = 0.0;
    size_t covered = 0;
    for (size_t p = 0; p < (size_t)fb->width * (size_t)fb->height; p++)
        if (fb->coverage[p] > 0.0f) {
            sum += fb->color[3 * p + 1];
            covered++;
        }
    if (out_covered) *out_covered = covered;
    return covered ? sum / (double)covered : 0.0;
}

/* Radiance 1 from every direction, no constant ambient. */
static const char gi_uniform_sky[] =
    "\"ambient\": [0, 0, 0], \"environment\": {\"sky\": {\"zenith\": [1, 1, 1], \"horizon\": "
    "[1, 1, 1], \"ground\": [1, 1, 1], \"sun\": false, \"width\": 32}}";

#endif
