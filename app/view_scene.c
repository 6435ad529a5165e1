/* The viewer's scene copies and the scene file written back (view_scene.h). */
#include "view_scene.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "render_camera.h"
#include "meso/runtime.h"

/* ---- Scene copies ------------------------------------------------------------------------- */

static const char *own_technique(const meso_object *object) {
    return object->technique[0] ? object->technique : "flat";
}

/* The object's setting of `technique`'s option `name`, keyed or (for its own technique) in the
 * flat form; the keyed one wins, as the renderer's reader has it. NULL when unset. */
static meso_option *find_option(meso_object *object, const char *technique, const char *name) {
    meso_option *flat = NULL;
    for (int i = 0; i < object->num_options; i++) {
        meso_option *o = &object->options[i];
        if (strcmp(o->name, name) != 0) continue;
        if (!strcmp(o->technique, technique)) return o;
        if (!o->technique[0] && !strcmp(own_technique(object), technique)) flat = o;
    }
    return flat;
}

/* Set technique's option `name` keyed by the technique, over whatever the scene says. */
static void set_option(meso_object *object, const char *technique, const char *name, double value) {
    meso_option *option = find_option(object, technique, name);
    if (!option || !option->technique[0]) {
        if (object->num_options >= MESO_OPTIONS_MAX) return; /* the scene's own fill the table */
        option = &object->options[object->num_options++];
        snprintf(option->technique, sizeof(option->technique), "%s", technique);
        snprintf(option->name, sizeof(option->name), "%s", name);
    }
    option->value = value;
}

meso_result view_scene_create(meso_context *ctx, const meso_scene *source, const char *technique,
                              const view_state *state, view_scene **out_scene) {
    *out_scene = NULL;
    view_scene *copy = calloc(1, sizeof(*copy));
    size_t count = source->num_objects > 0 ? (size_t)source->num_objects : 1;
    if (copy) copy->objects = calloc(count, sizeof(*copy->objects));
    if (!copy || !copy->objects) {
        free(copy);
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory copying the scene",
                              source->path);
    }
    copy->scene = *source;
    copy->scene.objects = copy->objects;
    copy->source = source;
    const view_technique_knobs knobs = view_technique_knobs_find(technique);
    for (int i = 0; i < source->num_objects; i++) {
        meso_object *object = &copy->objects[i];
        *object = source->objects[i];
        if (!technique) continue;
        if (!state) continue;
        if (knobs.has_shadows) set_option(object, technique, "shadows", state->shadows);
        if (knobs.has_silhouettes) set_option(object, technique, "silhouettes", state->silhouettes);
        if (knobs.main_option) {
            for (int t = 0; t < state->num_techniques; t++)
                if (!strcmp(state->techniques[t], technique))
                    set_option(object, technique, knobs.main_option, state->main_option[t]);
        }
    }
    if (state) view_scene_set_view(copy, state);
    *out_scene = copy;
    return MESO_OK;
}

void view_scene_destroy(view_scene *scene) {
    if (!scene) return;
    free(scene->objects);
    free(scene);
}

void view_scene_set_view(view_scene *scene, const view_state *state) {
    scene->scene.camera = app_camera_from_view(&state->camera);
    /* an unmoved light keeps the loaded bits: normalising them again may change the last one */
    bool light_moved = memcmp(&state->light, &state->home_light, sizeof(state->light)) != 0;
    if (state->has_light && light_moved && scene->scene.num_lights > 0 &&
        scene->scene.lights[0].type == MESO_LIGHT_DIRECTIONAL) {
        meso_vec3 d = {(float)state->light.x, (float)state->light.y, (float)state->light.z};
        scene->scene.lights[0].direction = app_light_direction_stable(d);
    } else if (scene->scene.num_lights > 0) {
        scene->scene.lights[0] = scene->source->lights[0];
    }
}

double view_scene_initial_option(const meso_scene *scene, const char *technique, const char *name,
                                 double fallback) {
    if (scene->num_objects < 1) return fallback;
    const meso_option *option = find_option(&scene->objects[0], technique, name);
    return option ? option->value : fallback;
}

/* ---- Writing the view back ---------------------------------------------------------------- */

/* A minimal walk over JSON text that the scene loader has already accepted: enough to find a
 * member's value and replace it, keeping everything else byte for byte. Each returns the index
 * just past what it skipped, 0 on malformed text. */
static size_t skip_space(const char *t, size_t i) {
    while (t[i] == ' ' || t[i] == '\t' || t[i] == '\n' || t[i] == '\r') i++;
    return i;
}

static size_t skip_string(const char *t, size_t i) {
    for (i++; t[i]; i++) {
        if (t[i] == '\\' && t[i + 1])
            i++;
        else if (t[i] == '"')
            return i + 1;
    }
    return 0;
}

static size_t skip_value(const char *t, size_t i) {
    i = skip_space(t, i);
    if (t[i] == '"') return skip_string(t, i);
    if (t[i] == '{' || t[i] == '[') {
        int depth = 0;
        while (t[i]) {
            if (t[i] == '"') {
                if (!(i = skip_string(t, i))) return 0;
                continue;
            }
            if (t[i] == '{' || t[i] == '[') depth++;
            if (t[i] == '}' || t[i] == ']') depth--;
            i++;
            if (depth == 0) return i;
        }
        return 0;
    }
    size_t start = i;
    while (t[i] && !strchr(",}] \t\r\n", t[i])) i++;
    return i > start ? i : 0;
}

/* The value of member `key` of the object at t[open]: [*out_start, *out_end). */
static bool find_member(const char *t, size_t open, const char *key, size_t *out_start,
                        size_t *out_end) {
    size_t i = skip_space(t, open), key_length = strlen(key);
    if (t[i] != '{') return false;
    i++;
    for (;;) {
        i = skip_space(t, i);
        if (t[i] != '"') return false; /* '}' (not found) or malformed */
        size_t name = i + 1, name_end = skip_string(t, i);
        if (!name_end) return false;
        bool match = name_end - 1 - name == key_length && !memcmp(t + name, key, key_length);
        i = skip_space(t, name_end);
        if (t[i] != ':') return false;
        i = skip_space(t, i + 1);
        size_t value_end = skip_value(t, i);
        if (!value_end) return false;
        if (match) {
            *out_start = i;
            *out_end = value_end;
            return true;
        }
        i = skip_space(t, value_end);
        if (t[i] != ',') return false;
        i++;
    }
}

/* One replacement of t[start, end) by text. */
typedef struct text_edit {
    size_t start, end;
    char text[512];
} text_edit;

meso_result view_scene_save(meso_context *ctx, const char *source_path, const meso_camera *camera,
                            const meso_vec3 *light_direction, const char *out_path) {
    char *t = NULL;
    size_t size = 0;
    meso_result r = meso_file_read(ctx, source_path, MESO_SCENE_MAX_FILE_BYTES, &t, &size);
    if (r != MESO_OK) return r;
    size_t top = skip_space(t, 0);
    text_edit edits[2];
    int num_edits = 0;
    if (t[top] != '{') {
        free(t);
        return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: not a JSON object", source_path);
    }
    /* %.9g: a float printed so, read back as a double and rounded to float, is the same float,
     * so the written scene renders with the viewer's very bits */
    char camera_text[384];
    snprintf(camera_text, sizeof(camera_text),
             "{ \"eye\": [%.9g, %.9g, %.9g], \"target\": [%.9g, %.9g, %.9g], "
             "\"up\": [%.9g, %.9g, %.9g], \"fov_y_deg\": %.9g }",
             camera->eye.x, camera->eye.y, camera->eye.z, camera->target.x, camera->target.y,
             camera->target.z, camera->up.x, camera->up.y, camera->up.z, camera->fov_y_deg);
    text_edit *e = &edits[num_edits++];
    if (find_member(t, top, "camera", &e->start, &e->end)) {
        snprintf(e->text, sizeof(e->text), "%s", camera_text);
    } else { /* no camera yet: add one */
        bool empty = t[skip_space(t, top + 1)] == '}';
        snprintf(e->text, sizeof(e->text), "\n  \"camera\": %s%s", camera_text, empty ? "" : ",");
        e->start = e->end = top + 1;
    }
    size_t lights_start, lights_end;
    if (light_direction && find_member(t, top, "lights", &lights_start, &lights_end) &&
        t[lights_start] == '[') {
        size_t first = skip_space(t, lights_start + 1);
        e = &edits[num_edits];
        if (t[first] == '{' && find_member(t, first, "direction", &e->start, &e->end)) {
            snprintf(e->text, sizeof(e->text), "[%.9g, %.9g, %.9g]", light_direction->x,
                     light_direction->y, light_direction->z);
            num_edits++;
        }
    }
    if (num_edits == 2 && edits[1].start < edits[0].start) { /* in file order */
        text_edit swap = edits[0];
        edits[0] = edits[1];
        edits[1] = swap;
    }
    app_text out = {0};
    size_t at = 0;
    for (int i = 0; i < num_edits; i++) {
        app_text_printf(&out, "%.*s%s", (int)(edits[i].start - at), t + at, edits[i].text);
        at = edits[i].end;
    }
    app_text_printf(&out, "%s", t + at);
    if (out.failed)
        r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", out_path);
    else
        r = app_text_write(ctx, &out, out_path);
    app_text_free(&out);
    free(t);
    return r;
}
