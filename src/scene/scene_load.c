/* Scene files: JSON text -> meso_scene (docs/design.md "The scene file",
 * docs/scene-format.md). The top level (image, camera, ambient, lights, objects) lives here; the
 * environment is parsed by scene_environment.c, objects by scene_object.c. Every error names the
 * file and the key path; nothing leaks on any path. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene_internal.h"
#include "meso/runtime.h"

static meso_result parse_image(const scene_parser *p, const cJSON *item, meso_scene *scene) {
    static const char *const keys[] = {"width", "height", "background", "encoding", NULL};
    scene->width = 512;
    scene->height = 512;
    scene->background = (meso_vec3){0, 0, 0};
    scene->encoding = MESO_ENCODING_SRGB;
    if (!item) return MESO_OK;
    scene_key key = {"image"};
    long width = 512, height = 512;
    const char *encoding = NULL;
    meso_result r;
    if ((r = scene_check_object(p, item, &key, keys)) ||
        (r = scene_get_int(p, item, &key, "width", 1, MESO_IMAGE_MAX_SIDE, true, &width)) ||
        (r = scene_get_int(p, item, &key, "height", 1, MESO_IMAGE_MAX_SIDE, true, &height)) ||
        (r = scene_get_vec3(p, item, &key, "background", true, false, &scene->background)) ||
        (r = scene_get_string(p, item, &key, "encoding", false, &encoding)))
        return r;
    if ((uint64_t)width * (uint64_t)height > MESO_IMAGE_MAX_PIXELS)
        return scene_error(p, MESO_ERROR_LIMIT, &key, "%ldx%ld exceeds the limit of %u pixels",
                           width, height, MESO_IMAGE_MAX_PIXELS);
    scene->width = (int)width;
    scene->height = (int)height;
    if (encoding) {
        scene_key k = scene_key_child(&key, "encoding");
        if (strcmp(encoding, "srgb") == 0)
            scene->encoding = MESO_ENCODING_SRGB;
        else if (strcmp(encoding, "linear") == 0)
            scene->encoding = MESO_ENCODING_LINEAR;
        else
            return scene_error(p, MESO_ERROR_FORMAT, &k,
                               "must be \"srgb\" or \"linear\", not \"%s\"", encoding);
    }
    return MESO_OK;
}

static meso_result parse_camera(const scene_parser *p, const cJSON *item, meso_camera *camera) {
    static const char *const keys[] = {"eye", "target", "up", "fov_y_deg", NULL};
    camera->eye = (meso_vec3){0.0f, 1.2f, 2.2f};
    camera->target = (meso_vec3){0, 0, 0};
    camera->up = (meso_vec3){0, 1, 0};
    camera->fov_y_deg = 40.0f;
    if (!item) return MESO_OK;
    scene_key key = {"camera"};
    double fov = camera->fov_y_deg;
    meso_result r;
    if ((r = scene_check_object(p, item, &key, keys)) ||
        (r = scene_get_vec3(p, item, &key, "eye", false, false, &camera->eye)) ||
        (r = scene_get_vec3(p, item, &key, "target", false, false, &camera->target)) ||
        (r = scene_get_vec3(p, item, &key, "up", false, false, &camera->up)) ||
        (r = scene_get_number(p, item, &key, "fov_y_deg", false, &fov)))
        return r;
    if (!(fov > 0.0 && fov < 180.0)) {
        scene_key k = scene_key_child(&key, "fov_y_deg");
        return scene_error(p, MESO_ERROR_FORMAT, &k, "must be in (0, 180), not %g", fov);
    }
    camera->fov_y_deg = (float)fov;
    meso_vec3 view = meso_vec3_sub(camera->target, camera->eye);
    if (meso_vec3_length(view) <= 1e-6f) {
        scene_key k = scene_key_child(&key, "target");
        return scene_error(p, MESO_ERROR_FORMAT, &k, "must differ from the eye");
    }
    meso_vec3 side = meso_vec3_cross(meso_vec3_normalize(view), meso_vec3_normalize(camera->up));
    if (meso_vec3_length(side) <= 1e-4f) {
        scene_key k = scene_key_child(&key, "up");
        return scene_error(p, MESO_ERROR_FORMAT, &k,
                           "must not be zero or along the view direction");
    }
    return MESO_OK;
}

static meso_result parse_light(const scene_parser *p, const cJSON *item, const scene_key *key,
                               meso_light *light) {
    static const char *const directional_keys[] = {"type", "direction", "color", NULL};
    static const char *const point_keys[] = {"type", "position", "color", NULL};
    if (!cJSON_IsObject(item)) return scene_error(p, MESO_ERROR_FORMAT, key, "must be an object");
    const char *type = NULL;
    meso_result r = scene_get_string(p, item, key, "type", true, &type);
    if (r != MESO_OK) return r;
    light->color = (meso_vec3){1, 1, 1};
    if (strcmp(type, "directional") == 0) {
        light->type = MESO_LIGHT_DIRECTIONAL;
        if ((r = scene_check_object(p, item, key, directional_keys)) ||
            (r = scene_get_vec3(p, item, key, "direction", false, true, &light->direction)))
            return r;
        if (meso_vec3_length(light->direction) <= 1e-12f) {
            scene_key k = scene_key_child(key, "direction");
            return scene_error(p, MESO_ERROR_FORMAT, &k, "must not be zero");
        }
        light->direction = meso_vec3_normalize(light->direction);
    } else if (strcmp(type, "point") == 0) {
        light->type = MESO_LIGHT_POINT;
        if ((r = scene_check_object(p, item, key, point_keys)) ||
            (r = scene_get_vec3(p, item, key, "position", false, true, &light->position)))
            return r;
    } else {
        scene_key k = scene_key_child(key, "type");
        return scene_error(p, MESO_ERROR_FORMAT, &k,
                           "must be \"directional\" or \"point\", not \"%s\"", type);
    }
    return scene_get_vec3(p, item, key, "color", true, false, &light->color);
}

static meso_result parse_lights(const scene_parser *p, const cJSON *item, meso_scene *scene) {
    scene_key key = {"lights"};
    if (!item) return MESO_OK;
    if (!cJSON_IsArray(item)) return scene_error(p, MESO_ERROR_FORMAT, &key, "must be an array");
    int count = cJSON_GetArraySize(item);
    if (count > MESO_SCENE_MAX_LIGHTS)
        return scene_error(p, MESO_ERROR_LIMIT, &key, "%d lights exceed the limit of %d", count,
                           MESO_SCENE_MAX_LIGHTS);
    int index = 0;
    for (const cJSON *light = item->child; light; light = light->next, index++) {
        scene_key k = scene_key_index(&key, index);
        meso_result r = parse_light(p, light, &k, &scene->lights[index]);
        if (r != MESO_OK) return r;
        scene->num_lights = index + 1;
    }
    return MESO_OK;
}

static meso_result parse_objects(const scene_parser *p, const cJSON *item, meso_scene *scene) {
    scene_key key = {"objects"};
    if (item && !cJSON_IsArray(item))
        return scene_error(p, MESO_ERROR_FORMAT, &key, "must be an array");
    int count = item ? cJSON_GetArraySize(item) : 0;
    if (count == 0)
        return scene_error(p, MESO_ERROR_FORMAT, &key, "a scene needs at least one object");
    if (count > MESO_SCENE_MAX_OBJECTS)
        return scene_error(p, MESO_ERROR_LIMIT, &key, "%d objects exceed the limit of %d", count,
                           MESO_SCENE_MAX_OBJECTS);
    /* The whole scene's estimate first, so that a scene over the memory budget is refused
     * before its first mesh is built (the running account below catches imported meshes). */
    char name[1024 + SCENE_KEY_MAX];
    snprintf(name, sizeof(name), "%s: objects", p->file);
    meso_result r = meso_memory_check(p->ctx, name, scene_objects_memory_estimate(item));
    if (r != MESO_OK) return r;
    scene->objects = calloc((size_t)count, sizeof(meso_object));
    if (!scene->objects) return scene_error(p, MESO_ERROR_OUT_OF_MEMORY, &key, "out of memory");
    int index = 0;
    for (const cJSON *object = item->child; object; object = object->next, index++) {
        /* Counted before parsing so that destroy releases a half-built object too. */
        scene->num_objects = index + 1;
        r = scene_parse_object(p, object, index, &scene->objects[index]);
        if (r != MESO_OK) return r;
    }
    return MESO_OK;
}

/* The 1-based line of `position` in `text`. */
static int line_of(const char *text, const char *position) {
    int line = 1;
    for (const char *c = text; c < position && *c; c++) line += *c == '\n';
    return line;
}

static meso_result parse_document(const scene_parser *p, const char *json, meso_scene *scene) {
    static const char *const keys[] = {"description", "image",   "camera",      "ambient",
                                       "lights",      "objects", "environment", NULL};
    /* The error position comes back through return_parse_end (the same pointer as
     * cJSON_GetErrorPtr()); cJSON also stores it in a global, which is never read here. */
    const char *end = NULL;
    cJSON *root = cJSON_ParseWithOpts(json, &end, true);
    if (!root)
        return scene_error(p, MESO_ERROR_FORMAT, NULL, "malformed JSON near line %d",
                           line_of(json, end ? end : json));
    scene_key top = {""};
    meso_result r;
    if (!cJSON_IsObject(root)) {
        r = scene_error(p, MESO_ERROR_FORMAT, NULL, "the top level must be a JSON object");
        goto done;
    }
    if ((r = scene_check_numbers(p, json))) goto done;
    if ((r = scene_check_object(p, root, &top, keys))) goto done;
    const cJSON *description = cJSON_GetObjectItemCaseSensitive(root, "description");
    if (description && !cJSON_IsString(description)) {
        scene_key k = {"description"};
        r = scene_error(p, MESO_ERROR_FORMAT, &k, "must be a string");
        goto done;
    }
    scene->ambient = (meso_vec3){0.1f, 0.1f, 0.1f};
    if ((r = parse_image(p, cJSON_GetObjectItemCaseSensitive(root, "image"), scene)) ||
        (r = parse_camera(p, cJSON_GetObjectItemCaseSensitive(root, "camera"), &scene->camera)) ||
        (r = scene_get_vec3(p, root, &top, "ambient", true, false, &scene->ambient)) ||
        (r = parse_lights(p, cJSON_GetObjectItemCaseSensitive(root, "lights"), scene)) ||
        (r = scene_parse_environment(p, cJSON_GetObjectItemCaseSensitive(root, "environment"),
                                     scene)) ||
        (r = parse_objects(p, cJSON_GetObjectItemCaseSensitive(root, "objects"), scene)))
        goto done;
done:
    cJSON_Delete(root);
    return r;
}

meso_result scene_account_memory(const scene_parser *p, const scene_key *key, uint64_t bytes) {
    *p->memory_estimate += bytes;
    if (*p->memory_estimate <= meso_context_memory_limit(p->ctx)) return MESO_OK;
    char name[1024 + SCENE_KEY_MAX + 2];
    snprintf(name, sizeof(name), "%s: %s", p->file, key->text[0] ? key->text : "objects");
    return meso_memory_check(p->ctx, name, *p->memory_estimate);
}

const meso_scene_resource *scene_find_resource(const scene_parser *p, const char *name) {
    for (size_t i = 0; i < p->num_resources; i++)
        if (p->resources[i].name && strcmp(p->resources[i].name, name) == 0)
            return &p->resources[i];
    return NULL;
}

meso_result meso_scene_create(meso_context *ctx, const meso_scene_desc *desc,
                              meso_scene **out_scene) {
    *out_scene = NULL;
    const char *name = desc && desc->name ? desc->name : "scene";
    const char *base_dir = desc && desc->base_dir && desc->base_dir[0] ? desc->base_dir : ".";
    if (!desc || !desc->json)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: no scene text", name);
    if (desc->num_resources > 0 && !desc->resources)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: NULL resources", name);
    uint64_t memory_estimate = 0;
    scene_parser p = {.ctx = ctx,
                      .file = name,
                      .base_dir = base_dir,
                      .memory_estimate = &memory_estimate,
                      .resources = desc->resources,
                      .num_resources = desc->num_resources};
    meso_scene *scene = calloc(1, sizeof(*scene));
    if (!scene) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", name);
    snprintf(scene->path, sizeof(scene->path), "%s", name);
    meso_result r = parse_document(&p, desc->json, scene);
    if (r != MESO_OK) {
        meso_scene_destroy(scene);
        return r;
    }
    *out_scene = scene;
    return MESO_OK;
}

meso_result meso_scene_parse(meso_context *ctx, const char *json, const char *name,
                             const char *base_dir, meso_scene **out_scene) {
    const meso_scene_desc desc = {.json = json, .name = name, .base_dir = base_dir};
    return meso_scene_create(ctx, &desc, out_scene);
}

meso_result meso_scene_load(meso_context *ctx, const char *path, meso_scene **out_scene) {
    *out_scene = NULL;
    char *text = NULL;
    size_t size = 0;
    meso_result r = meso_file_read(ctx, path, MESO_SCENE_MAX_FILE_BYTES, &text, &size);
    if (r != MESO_OK) return r;
    if (strlen(text) != size) {
        free(text);
        return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: malformed JSON: contains a NUL byte",
                              path);
    }
    /* Relative paths inside the scene resolve against the scene file's folder. */
    char base_dir[SCENE_PATH_MAX];
    const char *slash = strrchr(path, '/');
    if (!slash)
        snprintf(base_dir, sizeof(base_dir), ".");
    else if (slash == path)
        snprintf(base_dir, sizeof(base_dir), "/");
    else
        snprintf(base_dir, sizeof(base_dir), "%.*s", (int)(slash - path), path);
    r = meso_scene_parse(ctx, text, path, base_dir, out_scene);
    free(text);
    return r;
}

void meso_scene_destroy(meso_scene *scene) {
    if (!scene) return;
    for (int i = 0; i < scene->num_objects; i++) scene_object_deinit(&scene->objects[i]);
    free(scene->objects);
    meso_environment_destroy(scene->environment);
    free(scene);
}
