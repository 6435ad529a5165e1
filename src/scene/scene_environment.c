/* "environment" of a scene file (docs/scene-format.md): a Radiance .hdr map or a procedural
 * sky, times an intensity. The map is loaded here, once, for every renderer of the scene. */
#include <stdio.h>

#include "scene_internal.h"

static meso_result parse_sky(const scene_parser *p, const cJSON *item, const scene_key *key,
                             meso_sky_desc *sky) {
    static const char *const keys[] = {"zenith",    "horizon",      "ground", "gradient", "sun",
                                       "sun_color", "sun_size_deg", "width",  NULL};
    *sky = meso_sky_desc_defaults(NULL);
    double gradient = sky->gradient, sun_size = sky->sun_size_deg;
    long width = sky->width;
    const cJSON *sun = cJSON_GetObjectItemCaseSensitive(item, "sun");
    meso_result r;
    if ((r = scene_check_object(p, item, key, keys)) ||
        (r = scene_get_vec3(p, item, key, "zenith", true, false, &sky->zenith)) ||
        (r = scene_get_vec3(p, item, key, "horizon", true, false, &sky->horizon)) ||
        (r = scene_get_vec3(p, item, key, "ground", true, false, &sky->ground)) ||
        (r = scene_get_vec3(p, item, key, "sun_color", true, false, &sky->sun_color)) ||
        (r = scene_get_number(p, item, key, "gradient", false, &gradient)) ||
        (r = scene_get_number(p, item, key, "sun_size_deg", false, &sun_size)) ||
        (r = scene_get_int(p, item, key, "width", 8, MESO_ENVIRONMENT_MAX_SIDE, true, &width)))
        return r;
    /* "sun": a direction toward it, or false for a sky without one */
    if (cJSON_IsFalse(sun)) {
        sky->no_sun = true;
    } else if (sun) {
        if ((r = scene_get_vec3(p, item, key, "sun", false, false, &sky->sun_direction))) return r;
        if (meso_vec3_length(sky->sun_direction) <= 1e-12f) {
            scene_key k = scene_key_child(key, "sun");
            return scene_error(p, MESO_ERROR_FORMAT, &k, "must not be zero");
        }
    }
    sky->gradient = (float)gradient;
    sky->sun_size_deg = (float)sun_size;
    sky->width = (int)width;
    return MESO_OK;
}

meso_result scene_parse_environment(const scene_parser *p, const cJSON *item, meso_scene *scene) {
    static const char *const keys[] = {"map", "sky", "intensity", NULL};
    if (!item) return MESO_OK;
    scene_key key = {"environment"};
    const char *map = NULL;
    double intensity = 1.0;
    meso_result r;
    if ((r = scene_check_object(p, item, &key, keys)) ||
        (r = scene_get_string(p, item, &key, "map", false, &map)) ||
        (r = scene_get_number(p, item, &key, "intensity", false, &intensity)))
        return r;
    const cJSON *sky = cJSON_GetObjectItemCaseSensitive(item, "sky");
    if (!map == !sky)
        return scene_error(p, MESO_ERROR_FORMAT, &key, "needs either \"map\" or \"sky\"");
    if (!(intensity >= 0.0 && intensity <= MESO_ENVIRONMENT_MAX_INTENSITY)) {
        scene_key k = scene_key_child(&key, "intensity");
        return scene_error(p, MESO_ERROR_FORMAT, &k, "must be in [0, %g], not %g",
                           (double)MESO_ENVIRONMENT_MAX_INTENSITY, intensity);
    }
    if (map) {
        scene_key k = scene_key_child(&key, "map");
        char path[SCENE_PATH_MAX];
        if ((r = scene_resolve_path(p, &k, map, path)) || (r = scene_check_readable(p, &k, path)))
            return r;
        r = meso_environment_load(p->ctx, path, (float)intensity, &scene->environment);
        if (r != MESO_OK) return scene_relog_at_key(p, &k, r);
    } else {
        scene_key k = scene_key_child(&key, "sky");
        if (!cJSON_IsObject(sky)) return scene_error(p, MESO_ERROR_FORMAT, &k, "must be an object");
        meso_sky_desc desc;
        if ((r = parse_sky(p, sky, &k, &desc))) return r;
        r = meso_environment_create_sky(p->ctx, &desc, (float)intensity, &scene->environment);
        if (r != MESO_OK) return scene_relog_as_format(p, &k, r);
    }
    const meso_image *m = scene->environment->map;
    return scene_account_memory(p, &key, (uint64_t)m->width * (uint64_t)m->height * 16);
}
