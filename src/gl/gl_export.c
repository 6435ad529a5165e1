/* Texture export (meso bake SCENE -o DIR): what each object's shader reads, as files an engine
 * loads without meso: heights and colours as 16-bit PNG, the VDM's SVD tables as OpenEXR, and
 * manifest.json saying which uniform reads which file and the uniforms' values (docs/gpu.md). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "meso/bake_minmax.h"
#include "meso/runtime.h"
#include "meso/prism.h"
#include "meso/texture.h"

#include "gl_internal.h"

#define EXPORT_MAX_CHANNELS 64

/* ---- Files ---------------------------------------------------------------------------------- */

typedef struct export_object {
    meso_context *ctx;
    const char *dir;
    char prefix[80];
    cJSON *textures; /* the object's "textures" array of the manifest */
    cJSON *uniforms; /* its "uniforms" object */
} export_object;

/* The file's path and its manifest entry. */
static void texture_entry(export_object *e, const char *file, const char *uniform, int width,
                          int height, const char *format, const char *layout) {
    cJSON *entry = cJSON_CreateObject();
    cJSON_AddStringToObject(entry, "file", file);
    cJSON_AddStringToObject(entry, "uniform", uniform);
    cJSON_AddNumberToObject(entry, "width", width);
    cJSON_AddNumberToObject(entry, "height", height);
    cJSON_AddStringToObject(entry, "format", format);
    cJSON_AddStringToObject(entry, "layout", layout);
    cJSON_AddItemToArray(e->textures, entry);
}

/* A uniform's value: a number, or an array of `count` numbers. */
static void uniform_value(export_object *e, const char *name, const float *values, int count) {
    if (count == 1) {
        cJSON_AddNumberToObject(e->uniforms, name, values[0]);
        return;
    }
    cJSON *array = cJSON_AddArrayToObject(e->uniforms, name);
    for (int i = 0; i < count; i++) cJSON_AddItemToArray(array, cJSON_CreateNumber(values[i]));
}

static meso_result path_of(export_object *e, const char *suffix, char *file, size_t file_size,
                           char *path, size_t path_size) {
    if (snprintf(file, file_size, "%s%s", e->prefix, suffix) >= (int)file_size ||
        snprintf(path, path_size, "%s/%s", e->dir, file) >= (int)path_size)
        return meso_log_error(e->ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: path too long", e->dir);
    return MESO_OK;
}

/* A 16-bit PNG of `channels` channels taken from `pixels` (stride `stride` floats a pixel). */
static meso_result save_png16(export_object *e, const char *suffix, const char *uniform, int width,
                              int height, int channels, const float *pixels, int stride,
                              const char *layout) {
    char file[160], path[4096];
    meso_result r = path_of(e, suffix, file, sizeof file, path, sizeof path);
    meso_image *image = NULL;
    if (r == MESO_OK) r = meso_image_create(e->ctx, width, height, channels, &image);
    if (r != MESO_OK) return r;
    for (size_t i = 0; i < (size_t)width * height; i++)
        for (int c = 0; c < channels; c++) image->pixels[i * channels + c] = pixels[i * stride + c];
    meso_png_desc desc = {.bit_depth = 16, .encoding = MESO_ENCODING_LINEAR};
    r = meso_image_save_png(e->ctx, image, path, &desc);
    meso_image_destroy(image);
    if (r == MESO_OK)
        texture_entry(e, file, uniform, width, height,
                      channels == 1 ? "png16 grey" : "png16 rgb linear", layout);
    return r;
}

/* An EXR of `count` channels "<letter>00".. from rows of `stride` numbers (halves or floats). */
static meso_result save_exr(export_object *e, const char *suffix, const char *uniform, int width,
                            int height, char letter, int count, const void *rows, int stride,
                            bool rows_are_half, bool half, const char *layout) {
    char file[160], path[4096];
    meso_result r = path_of(e, suffix, file, sizeof file, path, sizeof path);
    if (r != MESO_OK) return r;
    char names_storage[EXPORT_MAX_CHANNELS][16];
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
                data[i * count + c] = meso_half_to_float(((const uint16_t *)rows)[at]);
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
        float range[2] = {v->curvature_min, v->curvature_max};
        float chunks = (float)(t.lanes.lanes / 4);
        uniform_value(e, "u_tile_world", &t.tile_world, 1);
        uniform_value(e, "u_depth_tiles", &t.depth_tiles, 1);
        uniform_value(e, "u_curvature_range", range, 2);
        uniform_value(e, "u_vdm_chunks", &chunks, 1);
    }
    gl_vdm_table_release(&t);
    return r;
}

/* relief_exact's maximum mip-map, one float EXR per level (channel M00): the mip levels of
 * u_max_mip. */
static meso_result export_max_mip(export_object *e, const meso_object *object) {
    meso_minmax_pyramid *pyramid = NULL;
    meso_result r = meso_minmax_pyramid_bake(e->ctx, object->mesostructure.height_field, &pyramid);
    for (int l = 0; r == MESO_OK && l < pyramid->num_levels; l++) {
        char suffix[32];
        snprintf(suffix, sizeof suffix, ".max-mip-%d.exr", l);
        const meso_minmax_level *level = &pyramid->levels[l];
        r = save_exr(e, suffix, "u_max_mip", level->width, level->height, 'M', 1, level->max, 1,
                     false, false,
                     "mip level = the number in the name: per cell of 2^l x 2^l bilinear patches "
                     "the highest h; row 0 at v = 1");
    }
    if (r == MESO_OK) {
        float levels = (float)pyramid->num_levels;
        uniform_value(e, "u_max_mip_levels", &levels, 1);
    }
    meso_minmax_pyramid_destroy(pyramid);
    return r;
}

/* relief_layers' map (and its mirror, for back faces) as one float EXR each: channels D0k
 * (depth of layer k, 1 = unused), X0k, Y0k (its normal's x, y) and C (layers held). */
static meso_result export_layers(export_object *e, const meso_object *object,
                                 const meso_technique_info *info, const double *options) {
    gl_layers_maps maps;
    meso_result r = gl_layers_bake(e->ctx, object, info, options, &maps);
    if (r != MESO_OK) return r;
    const meso_layers *sides[2] = {maps.map, maps.mirrored};
    const char *suffixes[2] = {".layers.exr", ".layers-below.exr"};
    const char *uniforms[2] = {"u_layer_maps", "u_layer_maps_below"};
    int n = maps.num_layers, channels = 3 * n + 1;
    for (int side = 0; side < 2 && r == MESO_OK && sides[side]; side++) {
        const meso_layers *map = sides[side];
        size_t texels = (size_t)map->width * map->height;
        float *pixels = malloc(texels * (size_t)channels * sizeof(float));
        char storage[3 * MESO_LAYERS_MAX + 1][16];
        const char *names[3 * MESO_LAYERS_MAX + 1];
        if (!pixels) {
            r = meso_log_error(e->ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", e->dir);
            break;
        }
        for (int k = 0; k < n; k++) {
            snprintf(storage[k], sizeof storage[k], "D%02d", k);
            snprintf(storage[n + k], sizeof storage[k], "X%02d", k);
            snprintf(storage[2 * n + k], sizeof storage[k], "Y%02d", k);
        }
        snprintf(storage[3 * n], sizeof storage[0], "C");
        for (int c = 0; c < channels; c++) names[c] = storage[c];
        for (size_t i = 0; i < texels; i++) {
            float *p = pixels + i * (size_t)channels;
            for (int k = 0; k < n; k++) {
                size_t slot = i * (size_t)map->num_layers + (size_t)k;
                p[k] = map->depth[slot];
                p[n + k] = map->normal_x ? map->normal_x[slot] : 0.0f;
                p[2 * n + k] = map->normal_y ? map->normal_y[slot] : 0.0f;
            }
            p[3 * n] = (float)map->count[i];
        }
        char file[160], path[4096];
        r = path_of(e, suffixes[side], file, sizeof file, path, sizeof path);
        if (r == MESO_OK)
            r = meso_exr_write(e->ctx, path, map->width, map->height, channels, names, pixels,
                               false);
        free(pixels);
        if (r == MESO_OK)
            texture_entry(e, file, uniforms[side], map->width, map->height,
                          "exr float, channels D00.. X00.. Y00.. C",
                          "per texel: layer depths (0 at the mesh, 1 at the bottom or unused), "
                          "their normals' x, y in texture space (z = sqrt(1 - x^2 - y^2)), the "
                          "count; the shader packs D, X, Y four to an RGBA array layer and C as "
                          "u_layer_count; row 0 at v = 1");
    }
    if (r == MESO_OK) {
        float values[6] = {(float)n,
                           (float)maps.linear_steps,
                           (float)maps.map->from_heightfield,
                           (float)maps.impostor,
                           (float)maps.enclosed,
                           maps.mirrored != NULL};
        const char *names[6] = {"u_num_layers", "u_linear_steps", "u_layer_heightfield",
                                "u_impostor",   "u_enclosed",     "u_has_below"};
        for (int i = 0; i < 6; i++) {
            cJSON_DeleteItemFromObject(e->uniforms, names[i]); /* u_linear_steps: resolved */
            uniform_value(e, names[i], &values[i], 1);
        }
    }
    gl_layers_maps_release(&maps);
    return r;
}

/* gdm's table (W half, E and the normals float), its prism layer and, for a tile-mesh solid,
 * the distance grid as EXRs; the table's sizes and the solid's constants as uniforms. */
static meso_result export_gdm(export_object *e, const meso_scene *scene, const meso_object *object,
                              const meso_technique_info *info, const double *options) {
    gl_gdm_table t;
    meso_result r = gl_gdm_bake(e->ctx, scene, object, info, options, &t);
    if (r != MESO_OK) return r;
    const meso_gdm_view *v = &t.view;
    meso_prism_layer *layer = NULL;
    float *weights = gl_gdm_weights_rgba(&t), *eigen = gl_gdm_eigen_rgba(&t);
    float *prisms = NULL, *faces = NULL;
    r = meso_prism_layer_create(e->ctx, object->mesh, object->mesostructure.depth, object->name,
                                &layer);
    if (r == MESO_OK) {
        prisms = gl_gdm_prism_texels(layer, object->mesh);
        faces = gl_gdm_face_texels(layer);
    }
    if (r == MESO_OK && (!weights || !eigen || !prisms || !faces))
        r = meso_log_error(e->ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", e->dir);
    int lanes = 4 * t.chunks;
    if (r == MESO_OK)
        r = save_exr(e, ".gdm-weights.exr", "u_gdm_weights", v->width * v->num_phi, v->height, 'W',
                     t.k, weights, lanes, false, true,
                     "W_i(x, y, phi) at pixel (x * num_phi + phi, y), row 0 at v = 1; channels "
                     "W00.. are i (the shader reads them 4 to an RGBA16F texel of a buffer "
                     "texture: ((y W + x) P + phi) u_gdm_chunks + j)");
    if (r == MESO_OK)
        r = save_exr(e, ".gdm-eigen.exr", "u_gdm_eigen", v->num_theta, v->layers, 'E', t.k, eigen,
                     lanes, false, false,
                     "E_i(z, theta) at pixel (theta index, layer z), z = 0 at the mesh; d = sum_i "
                     "W_i E_i in texture units (a tile 1 wide, the shell 1 deep)");
    bool heightfield = object->mesostructure.kind == MESO_MESOSTRUCTURE_HEIGHT_FIELD;
    if (r == MESO_OK)
        r = save_exr(e, ".gdm-normals.exr", "u_gdm_normals", v->width, v->height * v->layers, 'N',
                     3, v->normals, 3, false, false,
                     "unit (u, v, w) normal of the nearest surface at pixel (x, z H + y): layer "
                     "z's rows under layer z - 1's");
    if (r == MESO_OK)
        r = save_exr(e, ".gdm-prisms.exr", "u_gdm_prisms", GL_GDM_PRISM_TEXELS,
                     (int)layer->num_prisms, 'P', 4, prisms, 4, false, false,
                     "row = prism (base triangle), pixel k = texel k of shaders/gdm.frag's "
                     "layout (planes, fin convexity, UV inverse, vertices' P, N, T, B), world "
                     "space");
    if (r == MESO_OK)
        r = save_exr(e, ".gdm-faces.exr", "u_gdm_faces", GL_GDM_FACE_TEXELS,
                     (int)layer->faces->num_triangles, 'F', 4, faces, 4, false, false,
                     "row = face (gl_PrimitiveID: tops, fins, bottoms), pixels: (P_c, u_c) c = "
                     "0..2, (v_0, w_0, v_1, w_1), (v_2, w_2, 0, 0); draw these triangles");
    meso_solid_shape shape = {0};
    if (!heightfield) shape = meso_solid_get_shape(object->mesostructure.solid);
    if (r == MESO_OK && shape.grid)
        r = save_exr(e, ".solid-grid.exr", "u_solid_grid", shape.grid_side,
                     shape.grid_side * shape.grid_side, 'G', 1, shape.grid, 1, false, false,
                     "signed distance samples of the tile mesh at pixel (i, k n + j)");
    if (r == MESO_OK) {
        float sizes[3] = {(float)v->width, (float)v->height, (float)v->layers};
        float directions[2] = {(float)v->num_theta, (float)v->num_phi};
        float values[15] = {(float)t.chunks,
                            (float)layer->num_prisms,
                            heightfield,
                            (float)shape.desc.kind,
                            (float)shape.desc.count,
                            shape.desc.thickness,
                            shape.depth_cells,
                            shape.scale,
                            shape.cap,
                            shape.amplitude,
                            shape.major,
                            shape.half_length,
                            shape.radius,
                            (float)shape.grid_side,
                            shape.grid_clamped};
        const char *names[15] = {
            "u_gdm_chunks",   "u_num_prisms",      "u_gdm_heightfield",   "u_solid_kind",
            "u_solid_count",  "u_solid_thickness", "u_solid_depth_cells", "u_solid_scale",
            "u_solid_cap",    "u_solid_amplitude", "u_solid_major",       "u_solid_half_length",
            "u_solid_radius", "u_solid_grid_side", "u_solid_grid_clamped"};
        float tilt[2] = {shape.tilt_cos, shape.tilt_sin};
        uniform_value(e, "u_gdm_size", sizes, 3);
        uniform_value(e, "u_gdm_directions", directions, 2);
        uniform_value(e, "u_solid_tilt", tilt, 2);
        for (int i = 0; i < 15; i++) uniform_value(e, names[i], &values[i], 1);
    }
    free(weights);
    free(eigen);
    free(prisms);
    free(faces);
    meso_prism_layer_destroy(layer);
    gl_gdm_table_release(&t);
    return r;
}

static meso_result export_object_textures(meso_context *ctx, const meso_scene *scene, int index,
                                          const meso_render_desc *desc, const char *dir,
                                          cJSON *objects) {
    const meso_object *object = &scene->objects[index];
    const meso_technique_info *info;
    double options[64];
    meso_result r = gl_resolve_technique(ctx, object, desc, &info);
    if (r == MESO_OK)
        r = meso_technique_options_values(ctx, scene, index, desc, info->name, options);
    if (r != MESO_OK) return r;
    export_object e = {.ctx = ctx, .dir = dir};
    int n = snprintf(e.prefix, sizeof e.prefix, "%d-%s", index, object->name);
    for (int i = 0; i < n && i < (int)sizeof e.prefix; i++) {
        char c = e.prefix[i];
        bool keep = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '-' || c == '_';
        if (!keep) e.prefix[i] = '_';
    }
    cJSON *entry = cJSON_CreateObject();
    cJSON_AddItemToArray(objects, entry);
    char shader[96];
    snprintf(shader, sizeof shader, "%s.frag", info->name);
    cJSON_AddStringToObject(entry, "object", object->name);
    cJSON_AddStringToObject(entry, "technique", info->name);
    cJSON_AddStringToObject(entry, "vertex_shader", "meso.vert");
    cJSON_AddStringToObject(entry, "fragment_shader", shader);
    e.uniforms = cJSON_AddObjectToObject(entry, "uniforms");
    e.textures = cJSON_AddArrayToObject(entry, "textures");
    for (size_t k = 0; k < info->num_options; k++) {
        char name[80];
        snprintf(name, sizeof name, "u_%s", info->options[k].name);
        cJSON_AddNumberToObject(e.uniforms, name, options[k]);
    }
    const meso_material *m = &object->material;
    const meso_heightfield *hf = object->mesostructure.height_field;
    float size[2] = {hf ? (float)hf->width : 0.0f, hf ? (float)hf->height : 0.0f};
    float flags[3] = {m->color_map != NULL, m->color_map && m->color_map->wrap == MESO_WRAP_CLAMP,
                      hf && hf->wrap == MESO_WRAP_CLAMP};
    uniform_value(&e, "u_depth", &object->mesostructure.depth, 1);
    uniform_value(&e, "u_albedo", &m->albedo.x, 3);
    uniform_value(&e, "u_specular", &m->specular.x, 3);
    uniform_value(&e, "u_shininess", &m->shininess, 1);
    uniform_value(&e, "u_has_color_map", &flags[0], 1);
    uniform_value(&e, "u_color_map_clamp", &flags[1], 1);
    uniform_value(&e, "u_height_size", size, 2);
    uniform_value(&e, "u_height_clamp", &flags[2], 1);
    if (m->color_map)
        r = save_png16(&e, ".color.png", "u_color_map", m->color_map->levels[0]->width,
                       m->color_map->levels[0]->height, 3, m->color_map->levels[0]->pixels, 4,
                       "linear RGB, value / 65535; texture unit 0; row 0 at v = 1");
    if (r == MESO_OK && hf)
        r = save_png16(&e, ".height.png", "u_height", hf->width, hf->height, 1, hf->heights, 1,
                       "h = value / 65535 (1 on the mesh, 0 at -depth); texture unit 1; row 0 "
                       "at v = 1");
    if (r == MESO_OK && strcmp(info->name, "vdm") == 0) r = export_vdm(&e, object, info, options);
    if (r == MESO_OK && strcmp(info->name, "relief_exact") == 0) r = export_max_mip(&e, object);
    if (r == MESO_OK && strcmp(info->name, "relief_layers") == 0)
        r = export_layers(&e, object, info, options);
    if (r == MESO_OK && strcmp(info->name, "gdm") == 0)
        r = export_gdm(&e, scene, object, info, options);
    return r;
}

/* The scene's path relative to the folder `dir` ("../scenes/wall.json"), so that the folder
 * moves with its project; the path as given when either cannot be resolved (a scene parsed
 * from memory). */
static void scene_path_from(const char *dir, const char *scene_path, char *out, size_t size) {
    snprintf(out, size, "%s", scene_path);
    char *from = realpath(dir, NULL), *to = realpath(scene_path, NULL);
    if (from && to) {
        /* the longest common run of whole components, then one ".." a component of `from` left */
        size_t common = 0, length = strlen(from);
        for (size_t i = 0; from[i] && from[i] == to[i]; i++)
            if (from[i] == '/') common = i;
        if (strncmp(from, to, length) == 0 && to[length] == '/') common = length; /* below dir */
        size_t used = 0;
        for (const char *c = from + common; *c; c++)
            if (*c == '/' && used + 3 < size) {
                memcpy(out + used, "../", 3);
                used += 3;
            }
        snprintf(out + used, size - used, "%s", to + common + 1);
    }
    free(from);
    free(to);
}

meso_result meso_gl_export_textures(meso_context *ctx, const meso_scene *scene,
                                    const meso_render_desc *desc, const char *dir) {
    if (!scene || !dir) return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "export: NULL");
    meso_render_desc d = desc ? *desc : (meso_render_desc){0};
    /* every object's technique and options first: a scene that cannot be exported writes
     * nothing */
    meso_result r = meso_gl_check_scene(ctx, scene, &d);
    if (r != MESO_OK) return r;
    cJSON *manifest = cJSON_CreateObject();
    char scene_path[4096];
    scene_path_from(dir, scene->path, scene_path, sizeof scene_path);
    cJSON_AddStringToObject(manifest, "scene", scene_path); /* relative to the manifest */
    cJSON_AddStringToObject(
        manifest, "conventions",
        "docs/design.md: texture space u right, v up (row 0 of every file at v = "
        "1); heights inward (1 on the mesh); shaders/ document every uniform");
    cJSON *objects = cJSON_AddArrayToObject(manifest, "objects");
    for (int i = 0; i < scene->num_objects && r == MESO_OK; i++)
        r = export_object_textures(ctx, scene, i, &d, dir, objects);
    char *text = r == MESO_OK ? cJSON_Print(manifest) : NULL;
    cJSON_Delete(manifest);
    if (r == MESO_OK && !text)
        r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", dir);
    char path[4096];
    if (r == MESO_OK && snprintf(path, sizeof path, "%s/manifest.json", dir) >= (int)sizeof path)
        r = meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: path too long", dir);
    if (r == MESO_OK) r = meso_file_write_atomic(ctx, path, text, strlen(text));
    cJSON_free(text);
    return r;
}
