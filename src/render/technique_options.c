/* Technique options: the one reader of every technique's option table (name, type, range,
 * default, doc), and the scene check that runs before any work. A technique declares its table
 * in its own file (info.options) and calls meso_technique_options_read in prepare; nothing else
 * reads options. */
#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "render_internal.h"
#include "meso/runtime.h"

const meso_technique_option *meso_technique_find_option(const meso_technique_info *technique,
                                                        const char *name) {
    if (!technique || !name) return NULL;
    for (size_t i = 0; i < technique->num_options; i++)
        if (strcmp(technique->options[i].name, name) == 0) return &technique->options[i];
    return NULL;
}

/* "a, b, c" into buffer (truncated to fit). */
static void list_option_names(const meso_technique_info *technique, char *buffer, size_t size) {
    size_t used = 0;
    buffer[0] = 0;
    for (size_t i = 0; i < technique->num_options; i++) {
        int w =
            snprintf(buffer + used, size - used, "%s%s", i ? ", " : "", technique->options[i].name);
        if (w < 0 || (size_t)w >= size - used) return;
        used += (size_t)w;
    }
}

meso_result meso_technique_check_option(meso_context *ctx, const char *technique, const char *name,
                                        double value, const char *where) {
    const meso_technique_info *info = meso_technique_find(technique);
    char list[512];
    if (!info) {
        meso_technique_list_names(list, sizeof list);
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: unknown technique '%s' (known: %s)", where, technique, list);
    }
    const meso_technique_option *option = meso_technique_find_option(info, name);
    if (!option) {
        list_option_names(info, list, sizeof list);
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: unknown option of technique '%s' (%s%s)", where, technique,
                              list[0] ? "known: " : "it has none", list);
    }
    switch (option->type) {
    case MESO_OPTION_BOOL:
        if (value == 0.0 || value == 1.0) return MESO_OK;
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: %g is not a boolean (true, false, 1 or 0)", where, value);
    case MESO_OPTION_INT:
        if (isfinite(value) && value == floor(value) && value >= option->min &&
            value <= option->max)
            return MESO_OK;
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: %g is not an integer in %g..%g", where, value, option->min,
                              option->max);
    case MESO_OPTION_FLOAT:
    default:
        if (isfinite(value) && value >= option->min && value <= option->max) return MESO_OK;
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: %g is not a number in [%g, %g]", where, value, option->min,
                              option->max);
    }
}

static void store_value(const meso_technique_option *option, void *values, double value) {
    char *at = (char *)values + option->offset;
    switch (option->type) {
    case MESO_OPTION_BOOL:
        *(bool *)at = value != 0.0;
        break;
    case MESO_OPTION_INT:
        *(int *)at = (int)value;
        break;
    case MESO_OPTION_FLOAT:
    default:
        *(float *)at = (float)value;
        break;
    }
}

void meso_technique_options_defaults(const meso_technique_info *technique, void *values) {
    for (size_t i = 0; i < technique->num_options; i++)
        store_value(&technique->options[i], values, technique->options[i].default_value);
}

/* The technique an option is for: its own key, else the object's technique (the flat form). */
static const char *option_technique(const meso_object *object, const meso_option *option) {
    if (option->technique[0]) return option->technique;
    return object->technique[0] ? object->technique : "flat";
}

/* "<file>: objects[i].technique_options[.technique].name" for messages. */
static void option_where(const meso_scene *scene, const meso_object *object,
                         const meso_option *option, char *buffer, size_t size) {
    char object_key[MESO_NAME_MAX + 16];
    if (scene && object >= scene->objects && object < scene->objects + scene->num_objects)
        snprintf(object_key, sizeof object_key, "objects[%d]", (int)(object - scene->objects));
    else
        snprintf(object_key, sizeof object_key, "%s", object->name);
    snprintf(buffer, size, "%s%s%s.technique_options%s%s.%s",
             scene && scene->path[0] ? scene->path : "", scene && scene->path[0] ? ": " : "",
             object_key, option->technique[0] ? "." : "", option->technique, option->name);
}

meso_result meso_technique_options_apply(meso_context *ctx, const meso_scene *scene,
                                         const meso_object *object,
                                         const meso_technique_info *technique, void *values) {
    /* Two passes, flat form then keyed: a key naming the technique is the more specific. An
     * object built by hand without a technique name gives its flat options to whichever
     * technique draws it. */
    for (int pass = 0; pass < 2; pass++) {
        for (int i = 0; i < object->num_options && i < MESO_OPTIONS_MAX; i++) {
            const meso_option *option = &object->options[i];
            bool keyed = option->technique[0] != 0;
            if (keyed != (pass == 1)) continue;
            if (object->technique[0] || keyed) {
                if (strcmp(option_technique(object, option), technique->name) != 0) continue;
            }
            char where[1280];
            option_where(scene, object, option, where, sizeof where);
            meso_result r = meso_technique_check_option(ctx, technique->name, option->name,
                                                        option->value, where);
            if (r != MESO_OK) return r;
            store_value(meso_technique_find_option(technique, option->name), values, option->value);
        }
    }
    return MESO_OK;
}

meso_result meso_technique_options_read(meso_context *ctx, const meso_scene *scene,
                                        const meso_object *object,
                                        const meso_technique_info *technique, void *values) {
    meso_technique_options_defaults(technique, values);
    return meso_technique_options_apply(ctx, scene, object, technique, values);
}

meso_result meso_object_merge_options(meso_context *ctx, const meso_scene *scene,
                                      meso_object *object, const meso_render_desc *desc) {
    for (int i = 0; desc && i < desc->num_options; i++) {
        const meso_option *setting = &desc->options[i];
        int slot = 0;
        while (slot < object->num_options &&
               !(strcmp(object->options[slot].technique, setting->technique) == 0 &&
                 strcmp(object->options[slot].name, setting->name) == 0))
            slot++;
        if (slot == MESO_OPTIONS_MAX)
            return meso_log_error(ctx, MESO_ERROR_LIMIT,
                                  "%s: %s: more than %d technique options with the render's",
                                  scene->path, object->name, MESO_OPTIONS_MAX);
        object->options[slot] = *setting;
        if (slot == object->num_options) object->num_options++;
    }
    return MESO_OK;
}

/* Room for any technique's option struct, read back row by row as doubles. */
#define OPTION_VALUES_BYTES 1024

meso_result meso_technique_options_values(meso_context *ctx, const meso_scene *scene, int object,
                                          const meso_render_desc *desc, const char *technique,
                                          double *out_values) {
    const meso_technique_info *info = meso_technique_find(technique);
    if (!scene || object < 0 || object >= scene->num_objects || !info)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "options: no object %d or no technique '%s'", object,
                              technique ? technique : "(null)");
    _Alignas(max_align_t) unsigned char values[OPTION_VALUES_BYTES];
    for (size_t k = 0; k < info->num_options; k++)
        if (info->options[k].offset + sizeof(double) > sizeof values)
            return meso_log_error(ctx, MESO_ERROR_INTERNAL, "%s: option table too large",
                                  technique);
    /* The object the renderer would draw: a copy carrying the desc's settings, read by the one
     * reader the techniques use, so every back end gets the same values and messages. */
    meso_object copy = scene->objects[object];
    meso_result r = meso_object_merge_options(ctx, scene, &copy, desc);
    if (r == MESO_OK) r = meso_technique_options_read(ctx, scene, &copy, info, values);
    if (r != MESO_OK) return r;
    for (size_t k = 0; k < info->num_options; k++) {
        const meso_technique_option *option = &info->options[k];
        const unsigned char *at = values + option->offset;
        switch (option->type) {
        case MESO_OPTION_BOOL:
            out_values[k] = *(const bool *)at ? 1.0 : 0.0;
            break;
        case MESO_OPTION_INT:
            out_values[k] = *(const int *)at;
            break;
        case MESO_OPTION_FLOAT:
        default:
            out_values[k] = *(const float *)at;
            break;
        }
    }
    return MESO_OK;
}

meso_result meso_technique_check_scene(meso_context *ctx, const meso_scene *scene) {
    if (!scene) return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "NULL scene");
    char where[1280], list[512];
    const char *path = scene->path[0] ? scene->path : "scene";
    for (int o = 0; o < scene->num_objects; o++) {
        const meso_object *object = &scene->objects[o];
        if (object->technique[0] && !meso_technique_find(object->technique)) {
            meso_technique_list_names(list, sizeof list);
            return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                                  "%s: objects[%d].technique: unknown technique '%s' (known: %s)",
                                  path, o, object->technique, list);
        }
        for (int i = 0; i < object->num_options && i < MESO_OPTIONS_MAX; i++) {
            const meso_option *option = &object->options[i];
            if (option->technique[0] && !meso_technique_find(option->technique)) {
                meso_technique_list_names(list, sizeof list);
                return meso_log_error(
                    ctx, MESO_ERROR_INVALID_ARGUMENT,
                    "%s: objects[%d].technique_options.%s: unknown technique (known: %s)", path, o,
                    option->technique, list);
            }
            /* Flat options of an object built without a technique name belong to whichever
             * technique draws it: that one checks them. */
            if (!option->technique[0] && !object->technique[0]) continue;
            option_where(scene, object, option, where, sizeof where);
            meso_result r = meso_technique_check_option(ctx, option_technique(object, option),
                                                        option->name, option->value, where);
            if (r != MESO_OK) return r;
        }
    }
    return MESO_OK;
}
