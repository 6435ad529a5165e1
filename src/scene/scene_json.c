/* Typed access to the cJSON tree: every getter validates the type and range of one key and
 * names the key path in its error, so callers read like a list of fields. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "scene_internal.h"
#include "meso/runtime.h"

/* ---- Key paths and errors ----------------------------------------------------------------- */

/* Key paths longer than SCENE_KEY_MAX are cut (only messages read them); a cut one ends in
 * "..." so the reader sees it. */
static void mark_if_cut(scene_key *k, int written) {
    if (written >= (int)sizeof(k->text)) memcpy(k->text + sizeof(k->text) - 4, "...", 4);
}

scene_key scene_key_child(const scene_key *parent, const char *key) {
    scene_key k;
    int n;
    if (!parent || !parent->text[0])
        n = snprintf(k.text, sizeof(k.text), "%s", key);
    else
        n = snprintf(k.text, sizeof(k.text), "%s.%s", parent->text, key);
    mark_if_cut(&k, n);
    return k;
}

scene_key scene_key_index(const scene_key *parent, int index) {
    scene_key k;
    int n = snprintf(k.text, sizeof(k.text), "%s[%d]", parent ? parent->text : "", index);
    mark_if_cut(&k, n);
    return k;
}

meso_result scene_error(const scene_parser *p, meso_result code, const scene_key *key,
                        const char *format, ...) {
    char reason[1024];
    va_list args;
    va_start(args, format);
    vsnprintf(reason, sizeof(reason), format, args);
    va_end(args);
    if (key && key->text[0])
        return meso_log_error(p->ctx, code, "%s: %s: %s", p->file, key->text, reason);
    return meso_log_error(p->ctx, code, "%s: %s", p->file, reason);
}

static const char *type_name(const cJSON *item) {
    if (cJSON_IsNumber(item)) return "a number";
    if (cJSON_IsString(item)) return "a string";
    if (cJSON_IsBool(item)) return "a boolean";
    if (cJSON_IsNull(item)) return "null";
    if (cJSON_IsArray(item)) return "an array";
    if (cJSON_IsObject(item)) return "an object";
    return "invalid";
}

meso_result scene_check_object(const scene_parser *p, const cJSON *item, const scene_key *key,
                               const char *const allowed[]) {
    if (!cJSON_IsObject(item))
        return scene_error(p, MESO_ERROR_FORMAT, key, "must be an object, not %s", type_name(item));
    for (const cJSON *child = item->child; child; child = child->next) {
        scene_key child_key = scene_key_child(key, child->string ? child->string : "");
        bool known = false;
        for (int k = 0; allowed[k] && !known; k++) known = strcmp(allowed[k], child->string) == 0;
        if (!known) return scene_error(p, MESO_ERROR_FORMAT, &child_key, "unknown key");
        /* cJSON keeps duplicates and finds the first: a second one would be silently ignored. */
        for (const cJSON *other = item->child; other != child; other = other->next)
            if (strcmp(other->string, child->string) == 0)
                return scene_error(p, MESO_ERROR_FORMAT, &child_key, "duplicate key");
    }
    return MESO_OK;
}

/* ---- Getters ------------------------------------------------------------------------------ */

/* obj[name], or NULL; a missing required key is an error. */
static meso_result find(const scene_parser *p, const cJSON *obj, const scene_key *key,
                        const char *name, bool required, const cJSON **out) {
    *out = cJSON_GetObjectItemCaseSensitive(obj, name);
    if (!*out && required) {
        scene_key k = scene_key_child(key, name);
        return scene_error(p, MESO_ERROR_FORMAT, &k, "missing (required)");
    }
    return MESO_OK;
}

static meso_result number_value(const scene_parser *p, const cJSON *item, const scene_key *key,
                                double *out) {
    if (!cJSON_IsNumber(item))
        return scene_error(p, MESO_ERROR_FORMAT, key, "must be a number, not %s", type_name(item));
    /* cJSON turns 1e999 into inf: numbers the scene cannot mean. */
    if (!isfinite(item->valuedouble))
        return scene_error(p, MESO_ERROR_FORMAT, key, "must be a finite number");
    *out = item->valuedouble;
    return MESO_OK;
}

meso_result scene_get_number(const scene_parser *p, const cJSON *obj, const scene_key *key,
                             const char *name, bool required, double *out) {
    const cJSON *item;
    meso_result r = find(p, obj, key, name, required, &item);
    if (r != MESO_OK || !item) return r;
    scene_key k = scene_key_child(key, name);
    return number_value(p, item, &k, out);
}

meso_result scene_get_int(const scene_parser *p, const cJSON *obj, const scene_key *key,
                          const char *name, long min_value, long max_value, bool limit_error,
                          long *out) {
    const cJSON *item;
    meso_result r = find(p, obj, key, name, false, &item);
    if (r != MESO_OK || !item) return r;
    scene_key k = scene_key_child(key, name);
    double value;
    r = number_value(p, item, &k, &value);
    if (r != MESO_OK) return r;
    if (value != floor(value))
        return scene_error(p, MESO_ERROR_FORMAT, &k, "must be an integer, not %g", value);
    if (value > (double)max_value)
        return scene_error(p, limit_error ? MESO_ERROR_LIMIT : MESO_ERROR_FORMAT, &k,
                           "%.0f exceeds the limit of %ld", value, max_value);
    if (value < (double)min_value)
        return scene_error(p, MESO_ERROR_FORMAT, &k, "must be at least %ld, not %.0f", min_value,
                           value);
    *out = (long)value;
    return MESO_OK;
}

meso_result scene_get_positive(const scene_parser *p, const cJSON *obj, const scene_key *key,
                               const char *name, bool allow_zero, bool required, float *out) {
    const cJSON *item;
    meso_result r = find(p, obj, key, name, required, &item);
    if (r != MESO_OK || !item) return r;
    scene_key k = scene_key_child(key, name);
    /* Not number_value: a NaN or inf here is reported with the range it misses. */
    if (!cJSON_IsNumber(item))
        return scene_error(p, MESO_ERROR_FORMAT, &k, "must be a number, not %s", type_name(item));
    double value = item->valuedouble;
    bool ok = isfinite(value) && (allow_zero ? value >= 0.0 : value > 0.0) && value <= 1e30;
    if (!ok)
        return scene_error(p, MESO_ERROR_FORMAT, &k, "must be a finite number %s",
                           allow_zero ? ">= 0" : "> 0");
    *out = (float)value;
    return MESO_OK;
}

static meso_result get_vector(const scene_parser *p, const cJSON *obj, const scene_key *key,
                              const char *name, int size, bool non_negative, bool positive,
                              bool required, float *out) {
    const cJSON *item;
    meso_result r = find(p, obj, key, name, required, &item);
    if (r != MESO_OK || !item) return r;
    scene_key k = scene_key_child(key, name);
    if (!cJSON_IsArray(item) || cJSON_GetArraySize(item) != size)
        return scene_error(p, MESO_ERROR_FORMAT, &k, "must be an array of %d numbers", size);
    float values[3];
    int n = 0;
    for (const cJSON *e = item->child; e; e = e->next, n++) {
        scene_key ek = scene_key_index(&k, n);
        double value;
        r = number_value(p, e, &ek, &value);
        if (r != MESO_OK) return r;
        if (fabs(value) > 1e30)
            return scene_error(p, MESO_ERROR_FORMAT, &ek, "%g is out of range", value);
        if (non_negative && value < 0.0)
            return scene_error(p, MESO_ERROR_FORMAT, &ek, "must be >= 0, not %g", value);
        if (positive && value <= 0.0)
            return scene_error(p, MESO_ERROR_FORMAT, &ek, "must be > 0, not %g", value);
        values[n] = (float)value;
    }
    memcpy(out, values, (size_t)size * sizeof(float));
    return MESO_OK;
}

meso_result scene_get_vec3(const scene_parser *p, const cJSON *obj, const scene_key *key,
                           const char *name, bool non_negative, bool required, meso_vec3 *out) {
    float v[3];
    meso_result r = get_vector(p, obj, key, name, 3, non_negative, false, required, v);
    if (r == MESO_OK && cJSON_GetObjectItemCaseSensitive(obj, name))
        *out = (meso_vec3){v[0], v[1], v[2]};
    return r;
}

meso_result scene_get_vec2(const scene_parser *p, const cJSON *obj, const scene_key *key,
                           const char *name, bool positive, meso_vec2 *out) {
    float v[2];
    meso_result r = get_vector(p, obj, key, name, 2, false, positive, false, v);
    if (r == MESO_OK && cJSON_GetObjectItemCaseSensitive(obj, name)) *out = (meso_vec2){v[0], v[1]};
    return r;
}

meso_result scene_get_string(const scene_parser *p, const cJSON *obj, const scene_key *key,
                             const char *name, bool required, const char **out) {
    const cJSON *item;
    meso_result r = find(p, obj, key, name, required, &item);
    if (r != MESO_OK || !item) return r;
    if (!cJSON_IsString(item)) {
        scene_key k = scene_key_child(key, name);
        return scene_error(p, MESO_ERROR_FORMAT, &k, "must be a string, not %s", type_name(item));
    }
    *out = item->valuestring;
    return MESO_OK;
}

meso_result scene_resolve_path(const scene_parser *p, const scene_key *key, const char *path,
                               char out[SCENE_PATH_MAX]) {
    if (!path[0]) return scene_error(p, MESO_ERROR_FORMAT, key, "empty path");
    int n = path[0] == '/' ? snprintf(out, SCENE_PATH_MAX, "%s", path)
                           : snprintf(out, SCENE_PATH_MAX, "%s/%s", p->base_dir, path);
    if (n < 0 || n >= SCENE_PATH_MAX)
        return scene_error(p, MESO_ERROR_LIMIT, key, "path longer than %d bytes",
                           SCENE_PATH_MAX - 1);
    return MESO_OK;
}

/* ---- Strict numbers ----------------------------------------------------------------------- */

/* Whether text[0 .. length) is a number as RFC 8259 §6 spells it:
 * -?(0|[1-9][0-9]*)(.[0-9]+)?([eE][+-]?[0-9]+)? */
static bool is_json_number(const char *text, size_t length) {
    size_t i = 0;
    if (i < length && text[i] == '-') i++;
    if (i < length && text[i] == '0') {
        i++;
    } else if (i < length && text[i] >= '1' && text[i] <= '9') {
        while (i < length && text[i] >= '0' && text[i] <= '9') i++;
    } else {
        return false;
    }
    if (i < length && text[i] == '.') {
        size_t digits = ++i;
        while (i < length && text[i] >= '0' && text[i] <= '9') i++;
        if (i == digits) return false;
    }
    if (i < length && (text[i] == 'e' || text[i] == 'E')) {
        i++;
        if (i < length && (text[i] == '+' || text[i] == '-')) i++;
        size_t digits = i;
        while (i < length && text[i] >= '0' && text[i] <= '9') i++;
        if (i == digits) return false;
    }
    return i == length;
}

/* One open container while scanning: an array counts its elements, an object remembers the
 * last key read. */
typedef struct scan_frame {
    bool is_array;
    int index;
    char key[64];
} scan_frame;

meso_result scene_check_numbers(const scene_parser *p, const char *json) {
    scan_frame stack[SCENE_MAX_DEPTH];
    int depth = 0;
    for (const char *c = json; *c; c++) {
        if (*c == '{' || *c == '[') {
            if (depth == SCENE_MAX_DEPTH)
                return scene_error(p, MESO_ERROR_LIMIT, NULL, "nested deeper than %d",
                                   SCENE_MAX_DEPTH);
            stack[depth++] = (scan_frame){*c == '[', 0, ""};
        } else if (*c == '}' || *c == ']') {
            if (depth > 0) depth--;
        } else if (*c == ',' && depth > 0 && stack[depth - 1].is_array) {
            stack[depth - 1].index++;
        } else if (*c == '"') {
            const char *start = ++c;
            while (*c && *c != '"') c += c[0] == '\\' && c[1] ? 2 : 1;
            if (!*c) break;
            const char *after = c + 1;
            while (*after == ' ' || *after == '\t' || *after == '\n' || *after == '\r') after++;
            if (*after == ':' && depth > 0 && !stack[depth - 1].is_array)
                snprintf(stack[depth - 1].key, sizeof(stack[depth - 1].key), "%.*s",
                         (int)(c - start), start);
        } else if (*c == '-' || (*c >= '0' && *c <= '9')) {
            size_t length = strspn(c, "0123456789+-.eE");
            if (!is_json_number(c, length)) {
                scene_key key = {""};
                for (int i = 0; i < depth; i++)
                    key = stack[i].is_array ? scene_key_index(&key, stack[i].index)
                                            : scene_key_child(&key, stack[i].key);
                return scene_error(p, MESO_ERROR_FORMAT, &key,
                                   "'%.*s' is not a JSON number (no leading zeros, digits after "
                                   "the point)",
                                   (int)(length < 32 ? length : 32), c);
            }
            c += length - 1;
        }
    }
    return MESO_OK;
}

/* ---- Referenced files --------------------------------------------------------------------- */

/* A missing referenced file is reported with the scene, the key and the resolved path, which
 * the loaders' own messages (naming only the file) would not say. */
meso_result scene_check_readable(const scene_parser *p, const scene_key *key, const char *path) {
    FILE *file = NULL;
    if (meso_file_open_read(p->ctx, path, &file) != MESO_OK) {
        /* the loader's reason ("path: is a FIFO, ..."), said at the scene's key */
        char reason[1024];
        snprintf(reason, sizeof(reason), "%s", meso_context_last_error(p->ctx));
        return scene_error(p, MESO_ERROR_IO, key, "%s", reason);
    }
    fclose(file);
    return MESO_OK;
}

/* A loader's error (naming only its own file) said again at the scene's key, so that the
 * one line names the scene, the key and the loaded file's reason. */
meso_result scene_relog_at_key(const scene_parser *p, const scene_key *key, meso_result r) {
    if (r == MESO_ERROR_OUT_OF_MEMORY) return r;
    char reason[1024];
    snprintf(reason, sizeof(reason), "%s", meso_context_last_error(p->ctx));
    return scene_error(p, r, key, "%s", reason);
}

/* A library call refused parameters the parser let through (e.g. an odd weave count): report
 * it as a bad value of the scene, at the key, with the library's reason. */
meso_result scene_relog_as_format(const scene_parser *p, const scene_key *key, meso_result r) {
    if (r != MESO_ERROR_INVALID_ARGUMENT) return r;
    char reason[1024];
    snprintf(reason, sizeof(reason), "%s", meso_context_last_error(p->ctx));
    return scene_error(p, MESO_ERROR_FORMAT, key, "%s", reason);
}
