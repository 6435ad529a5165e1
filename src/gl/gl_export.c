/* Texture export (meso bake SCENE -o DIR): what each object's shader reads, as files an engine
 * loads without meso: heights and colours as 16-bit PNG, the VDM's SVD tables as OpenEXR, and
 * manifest.json saying which uniform reads which file and the uniforms' values (docs/gpu.md). */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gl_internal.h"

#define EXPORT_MAX_CHANNELS 64

/* ---- A growing JSON text ------------------------------------------------------------------ */

typedef struct json_text {
    char *data;
    size_t length, capacity;
    bool failed;
} json_text;

static void json_printf(json_text *t, const char *format, ...) __attribute__((format(printf, 2, 3)));
static void json_printf(json_text *t, const char *format, ...) {
    if (t->failed) return;
    va_list args;
    va_start(args, format);
    int n = vsnprintf(NULL, 0, format, args);
    va_end(args);
    if (n < 0 || t->length + (size_t)n + 1 > t->capacity) {
        size_t capacity = (t->capacity + (size_t)(n > 0 ? n : 0) + 1) * 2;
        char *grown = realloc(t->data, capacity);
        if (!grown || n < 0) {
            t->failed = true;
            return;
        }
        t->data = grown;
        t->capacity = capacity;
    }
    va_start(args, format);
    vsnprintf(t->data + t->length, t->capacity - t->length, format, args);
    va_end(args);
    t->length += (size_t)n;
}

static void json_string(json_text *t, const char *s) {
    json_printf(t, "\"");
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\')
            json_printf(t, "\\%c", c);
        else if (c < 0x20)
            json_printf(t, "\\u%04x", c);
        else
            json_printf(t, "%c", c);
    }
    json_printf(t, "\"");
}

/* ---- Files ---------------------------------------------------------------------------------- */

typedef struct export_object {
    meso_context *ctx;
    const char *dir;
    char prefix[80];
    json_text *json;
    int num_textures;
} export_object;

/* The file's path and its manifest entry. */
static void texture_entry(export_object *e, const char *file, const char *uniform, int width,
                          int height, const char *format, const char *layout) {
    json_printf(e->json, "%s\n        {\"file\": ", e->num_textures++ ? "," : "");
    json_string(e->json, file);
    json_printf(e->json, ", \"uniform\": \"%s\", \"width\": %d, \"height\": %d, \"format\": ",
                uniform, width, height);
    json_string(e->json, format);
    json_printf(e->json, ", \"layout\": ");
    json_string(e->json, layout);
    json_printf(e->json, "}");
}

static meso_result path_of(export_object *e, const char *suffix, char *file, size_t file_size,
                           char *path, size_t path_size) {
    if (snprintf(file, file_size, "%s%s", e->prefix, suffix) >= (int)file_size ||
        snprintf(path, path_size, "%s/%s", e->dir, file) >= (int)path_size)
        return meso_log_error(e->ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: path too long", e->dir);
    return MESO_OK;
}

/* A 16-bit PNG of `channels` channels taken from `pixels` (stride `stride` floats a pixel). */
static meso_result save_png16(export_object *e, const char *suffix, const char *uniform,
                              int width, int height, int channels, const float *pixels,
                              int stride, const char *layout) {
    char file[160], path[4096];
    meso_result r = path_of(e, suffix, file, sizeof file, path, sizeof path);
    meso_image *image = NULL;
    if (r == MESO_OK) r = meso_image_create(e->ctx, width, height, channels, &image);
    if (r != MESO_OK) return r;
    for (size_t i = 0; i < (size_t)width * height; i++)
        for (int c = 0; c < channels; c++)
            image->pixels[i * channels + c] = pixels[i * stride + c];
    meso_png_desc desc = {.bit_depth = 16, .encoding = MESO_ENCODING_LINEAR};
    r = meso_image_save_png(e->ctx, image, path, &desc);
    meso_image_destroy(image);
    if (r == MESO_OK) texture_entry(e, file, uniform, width, height, channels == 1 ? "png16 grey" : "png16 rgb linear", layout);
    return r;
}

/* An EXR of `count` channels "<letter>00".. from rows of `stride` numbers (halves or floats). */
static meso_result save_exr(export_object *e, const char *suffix, const char *uniform, int width,
                            int height, char letter, int count, const void *rows, int stride,
                            bool rows_are_half, bool half, const char *layout) {
    char file[160], path[4096];
    meso_result r = path_of(e, suffix, file, sizeof file, path, sizeof path);
    if (r != MESO_OK) return r;
    char names_storage[EXPORT_MAX_CHANNELS][8];
    const char *names[EXPORT_MAX_CHANNELS];
    for (int c = 0; c < count; c++) {
        snprintf(names_storage[c], sizeof names_storage[c], "%c%02d", letter, c);
        names[c] = names_storage[c];
    }
    size_t pixels = (size_t)width * height;
    float *data = malloc(pixels * (size_t)count * sizeof(float));
    if (!data) return meso_log_error(e->ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", path);
    for (size_t i = 0; i < pixels; i++)
        for (int c = 0; c < count; c++) {
            size_t at = i * (size_t)stride + (size_t)c;
            if (rows_are_half) {
                _Float16 h;
                memcpy(&h, (const uint16_t *)rows + at, sizeof h);
                data[i * count + c] = (float)h;
            } else {
                data[i * count + c] = ((const float *)rows)[at];
            }
        }
    r = meso_exr_write(e->ctx, path, width, height, count, names, data, half);
    free(data);
    if (r == MESO_OK) {
        char format[64];
        snprintf(format, sizeof format, "exr %s, channels %c00..%c%02d", half ? "half" : "float",
                 letter, letter, count - 1);
        texture_entry(e, file, uniform, width, height, format, layout);
    }
    return r;
}

static meso_result export_vdm(export_object *e, const meso_object *object,
                              const meso_technique_info *info, const double *options) {
    gl_vdm_table t;
    meso_result r = gl_vdm_bake(e->ctx, object, info, options, &t);
    if (r != MESO_OK) return r;
    const meso_vdm_view *v = &t.view;
    int used = t.k > t.m ? t.k : t.m;
    r = save_exr(e, ".vdm-weights.exr", "u_vdm_weights", v->width * v->num_phi, v->height, 'W',
                 used, t.lanes.level_weights[0], t.lanes.lanes, true, true,
                 "W^i(x, y, phi) at pixel (x * num_phi + phi, y), row 0 at v = 1; channels "
                 "W00.. are i (the shader packs them 4 to an RGBA16F texel); level 0 (mip "
                 "levels: 2 x 2 box filters)");
    if (r == MESO_OK)
        r = save_exr(e, ".vdm-eigen.exr", "u_vdm_eigen", v->num_theta, v->num_curvatures, 'E', t.k,
                     t.lanes.eigen_t, t.lanes.lanes, false, false,
                     "E^i(theta, c) at pixel (theta index, curvature index); d = sum_i W^i E^i "
                     "in shell depths");
    if (r == MESO_OK)
        r = save_exr(e, ".mvm-eigen.exr", "u_mvm_eigen", v->num_curvatures, 1, 'M', t.m,
                     t.lanes.mvm_t, t.lanes.lanes, false, false,
                     "E_MVM^i(c) at pixel (curvature index, 0); theta_MVM = sum_i W^i E_MVM^i "
                     "in radians");
    if (r == MESO_OK) {
        json_printf(e->json,
                    "\n      ],\n      \"vdm\": {\"u_tile_world\": %.9g, \"u_depth_tiles\": %.9g, "
                    "\"u_curvature_range\": [%.9g, %.9g], \"u_vdm_chunks\": %d, "
                    "\"k\": %d, \"m\": %d, \"compressed_bytes_as_exported\": %llu",
                    t.tile_world, t.depth_tiles, v->curvature_min, v->curvature_max,
                    t.lanes.lanes / 4, t.k, t.m,
                    (unsigned long long)((size_t)v->width * v->height * v->num_phi * used * 2 +
                                         ((size_t)v->num_theta * v->num_curvatures * t.k +
                                          (size_t)v->num_curvatures * t.m) *
                                             4));
        json_printf(e->json, "}");
    }
    gl_vdm_table_release(&t);
    return r;
}

static meso_result export_object_textures(meso_context *ctx, const meso_scene *scene, int index,
                                          const meso_render_desc *desc, const char *dir,
                                          json_text *json) {
    const meso_object *object = &scene->objects[index];
    const meso_technique_info *info;
    double options[64];
    meso_result r = gl_resolve_technique(ctx, object, desc, &info);
    if (r == MESO_OK) r = meso_technique_options_values(ctx, scene, index, desc, info->name, options);
    if (r != MESO_OK) return r;
    export_object e = {.ctx = ctx, .dir = dir, .json = json};
    int n = snprintf(e.prefix, sizeof e.prefix, "%d-%s", index, object->name);
    for (int i = 0; i < n && i < (int)sizeof e.prefix; i++) {
        char c = e.prefix[i];
        bool keep = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '-' || c == '_';
        if (!keep) e.prefix[i] = '_';
    }
    json_printf(json, "%s\n    {\"object\": ", index ? "," : "");
    json_string(json, object->name);
    json_printf(json, ", \"technique\": \"%s\", \"vertex_shader\": \"meso.vert\", "
                      "\"fragment_shader\": \"%s.frag\",\n      \"uniforms\": {",
                info->name, info->name);
    for (size_t k = 0; k < info->num_options; k++)
        json_printf(json, "%s\"u_%s\": %.9g", k ? ", " : "", info->options[k].name, options[k]);
    const meso_material *m = &object->material;
    const meso_heightfield *hf = object->mesostructure.height_field;
    json_printf(json,
                "%s\"u_depth\": %.9g, \"u_albedo\": [%.9g, %.9g, %.9g], \"u_specular\": [%.9g, "
                "%.9g, %.9g], \"u_shininess\": %.9g, \"u_has_color_map\": %d, "
                "\"u_color_map_clamp\": %d, \"u_height_size\": [%d, %d], \"u_height_clamp\": %d},"
                "\n      \"textures\": [",
                info->num_options ? ", " : "", object->mesostructure.depth, m->albedo.x,
                m->albedo.y, m->albedo.z, m->specular.x, m->specular.y, m->specular.z,
                m->shininess, m->color_map != NULL,
                m->color_map && m->color_map->wrap == MESO_WRAP_CLAMP, hf ? hf->width : 0,
                hf ? hf->height : 0, hf && hf->wrap == MESO_WRAP_CLAMP);
    if (m->color_map)
        r = save_png16(&e, ".color.png", "u_color_map", m->color_map->levels[0]->width,
                       m->color_map->levels[0]->height, 3, m->color_map->levels[0]->pixels, 4,
                       "linear RGB, value / 65535; texture unit 0; row 0 at v = 1");
    if (r == MESO_OK && hf)
        r = save_png16(&e, ".height.png", "u_height", hf->width, hf->height, 1, hf->heights, 1,
                       "h = value / 65535 (1 on the mesh, 0 at -depth); texture unit 1; row 0 "
                       "at v = 1");
    bool vdm = strcmp(info->name, "vdm") == 0;
    if (r == MESO_OK && vdm) r = export_vdm(&e, object, info, options);
    if (r == MESO_OK && !vdm) json_printf(json, "\n      ]");
    json_printf(json, "}");
    return r;
}

meso_result meso_gl_export_textures(meso_context *ctx, const meso_scene *scene,
                                    const meso_render_desc *desc, const char *dir) {
    if (!scene || !dir) return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "export: NULL");
    meso_render_desc d = desc ? *desc : (meso_render_desc){0};
    meso_result r = meso_technique_check_scene(ctx, scene);
    if (r != MESO_OK) return r;
    json_text json = {0};
    json_printf(&json, "{\n  \"scene\": ");
    json_string(&json, scene->path);
    json_printf(&json, ",\n  \"conventions\": \"DESIGN.md: texture space u right, v up (row 0 of "
                       "every file at v = 1); heights inward (1 on the mesh); shaders/ document "
                       "every uniform\",\n  \"objects\": [");
    for (int i = 0; i < scene->num_objects && r == MESO_OK; i++)
        r = export_object_textures(ctx, scene, i, &d, dir, &json);
    json_printf(&json, "\n  ]\n}\n");
    if (r == MESO_OK && json.failed)
        r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", dir);
    char path[4096];
    if (r == MESO_OK && snprintf(path, sizeof path, "%s/manifest.json", dir) >= (int)sizeof path)
        r = meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: path too long", dir);
    if (r == MESO_OK) r = meso_file_write_atomic(ctx, path, json.data, json.length);
    free(json.data);
    return r;
}
