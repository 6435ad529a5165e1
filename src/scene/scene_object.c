/* One scene object: shape and transform -> world-space mesh with tangent frames; material with
 * its colour map; mesostructure (height field or solid); technique and its options
 * (docs/scene-format.md). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene_internal.h"
#include "meso/texture.h"

/* ---- Helpers ------------------------------------------------------------------------------ */

static meso_result copy_name(const scene_parser *p, const scene_key *key, const char *value,
                             char out[MESO_NAME_MAX]) {
    if (strlen(value) >= MESO_NAME_MAX)
        return scene_error(p, MESO_ERROR_FORMAT, key, "longer than %d bytes", MESO_NAME_MAX - 1);
    snprintf(out, MESO_NAME_MAX, "%s", value);
    return MESO_OK;
}

static const char *base_name(const char *path) {
    const char *slash = strrchr(path, '/');
    return slash ? slash + 1 : path;
}

/* ---- Mesostructure ------------------------------------------------------------------------ */

static meso_result parse_procedural_heightfield(const scene_parser *p, const cJSON *item,
                                                const scene_key *key, meso_wrap wrap,
                                                bool want_color, meso_object *object,
                                                meso_image **out_color) {
    static const char *const keys[] = {"procedural", "resolution", "rows", "columns", "gap",
                                       "bevel",      "roughness",  "seed", NULL};
    meso_result r = scene_check_object(p, item, key, keys);
    if (r != MESO_OK) return r;
    const char *name = NULL;
    r = scene_get_string(p, item, key, "procedural", true, &name);
    if (r != MESO_OK) return r;
    meso_heightfield_desc desc = {.wrap = wrap};
    if (!meso_heightfield_kind_from_name(name, &desc.kind)) {
        scene_key k = scene_key_child(key, "procedural");
        return scene_error(
            p, MESO_ERROR_FORMAT, &k,
            "unknown procedural height field \"%s\" (bricks, bumps, weave, tiles, bark)", name);
    }
    long resolution = 0, rows = 0, columns = 0, seed = 0;
    float gap = 0.0f, bevel = 0.0f, roughness = 0.0f;
    if ((r = scene_get_int(p, item, key, "resolution", 1, MESO_HEIGHTFIELD_MAX_RESOLUTION, true,
                           &resolution)) ||
        (r = scene_get_int(p, item, key, "rows", 1, 1024, false, &rows)) ||
        (r = scene_get_int(p, item, key, "columns", 1, 1024, false, &columns)) ||
        (r = scene_get_int(p, item, key, "seed", 0, 4294967295L, false, &seed)) ||
        (r = scene_get_positive(p, item, key, "gap", false, false, &gap)) ||
        (r = scene_get_positive(p, item, key, "bevel", false, false, &bevel)) ||
        (r = scene_get_positive(p, item, key, "roughness", true, false, &roughness)))
        return r;
    if (gap >= 0.9f) {
        scene_key k = scene_key_child(key, "gap");
        return scene_error(p, MESO_ERROR_FORMAT, &k, "must be in (0, 0.9), not %g", (double)gap);
    }
    if (bevel > 0.5f) {
        scene_key k = scene_key_child(key, "bevel");
        return scene_error(p, MESO_ERROR_FORMAT, &k, "must be in (0, 0.5], not %g", (double)bevel);
    }
    if (roughness > 1.0f) {
        scene_key k = scene_key_child(key, "roughness");
        return scene_error(p, MESO_ERROR_FORMAT, &k, "must be in [0, 1], not %g",
                           (double)roughness);
    }
    desc.resolution = (int)resolution;
    /* heights (float) and the generated colour (3 floats) a texel */
    uint64_t texels =
        (uint64_t)(resolution ? resolution : 512) * (uint64_t)(resolution ? resolution : 512);
    if ((r = scene_account_memory(p, key, texels * (want_color ? 16 : 4))) != MESO_OK) return r;
    desc.rows = (int)rows;
    desc.columns = (int)columns;
    desc.seed = (uint32_t)seed;
    desc.gap = gap;
    desc.bevel = bevel;
    desc.roughness = roughness;
    meso_mesostructure *m = &object->mesostructure;
    r = meso_heightfield_create_procedural(p->ctx, &desc, &m->height_field,
                                           want_color ? out_color : NULL);
    if (r != MESO_OK) return scene_relog_as_format(p, key, r);
    snprintf(m->source, sizeof(m->source), "%s", meso_heightfield_kind_name(desc.kind));
    return MESO_OK;
}

static meso_result parse_procedural_solid(const scene_parser *p, const cJSON *item,
                                          const scene_key *key, meso_object *object) {
    static const char *const keys[] = {"procedural", "count", "thickness", NULL};
    meso_result r = scene_check_object(p, item, key, keys);
    if (r != MESO_OK) return r;
    const char *name = NULL;
    r = scene_get_string(p, item, key, "procedural", true, &name);
    if (r != MESO_OK) return r;
    meso_solid_desc desc = {0};
    if (!meso_solid_kind_from_name(name, &desc.kind)) {
        scene_key k = scene_key_child(key, "procedural");
        return scene_error(
            p, MESO_ERROR_FORMAT, &k,
            "unknown procedural solid \"%s\" (weave, chain, grid, squama, helix, slab)", name);
    }
    long count = 0;
    float thickness = 0.0f;
    if ((r = scene_get_int(p, item, key, "count", 1, 256, false, &count)) ||
        (r = scene_get_positive(p, item, key, "thickness", false, false, &thickness)))
        return r;
    desc.count = (int)count;
    desc.thickness = thickness;
    meso_mesostructure *m = &object->mesostructure;
    r = meso_solid_create_procedural(p->ctx, &desc, &m->solid);
    if (r != MESO_OK) return scene_relog_as_format(p, key, r);
    snprintf(m->source, sizeof(m->source), "%s", meso_solid_kind_name(desc.kind));
    return MESO_OK;
}

static meso_result parse_height_map_or_solid(const scene_parser *p, const cJSON *item,
                                             const scene_key *key, bool want_color,
                                             meso_object *object, meso_image **out_color);

/* "height": {"direction", "midlevel", "invert"}: the conventions of other tools (Blender,
 * Substance), converted once, here, into meso's inward one so that every technique and the
 * reference see the same field: the values are inverted in the field when asked, and the shell
 * is placed by moving the mesh along its normals by m->offset (build_mesh):
 *   inward   the mesh is the shell's top, white on it, black at -depth: offset 0 (meso's own)
 *   outward  the mesh is the shell's bottom, black on it, white at +depth: offset depth
 *   centered the value `midlevel` lies on the mesh: offset (1 - midlevel) depth
 * In each case P' = (P + offset N) - (1 - h) depth N, which is the tool's surface. */
static meso_result parse_height_convention(const scene_parser *p, const cJSON *item,
                                           const scene_key *key, meso_mesostructure *m) {
    static const char *const keys[] = {"direction", "midlevel", "invert", NULL};
    if (!cJSON_IsObject(item))
        return scene_error(p, MESO_ERROR_FORMAT, key,
                           "must be {\"direction\": ..., \"midlevel\": ..., \"invert\": ...}");
    meso_result r = scene_check_object(p, item, key, keys);
    if (r != MESO_OK) return r;
    const char *direction = "inward";
    double midlevel = 0.5;
    if ((r = scene_get_string(p, item, key, "direction", false, &direction)) ||
        (r = scene_get_number(p, item, key, "midlevel", false, &midlevel)))
        return r;
    scene_key midlevel_key = scene_key_child(key, "midlevel");
    bool has_midlevel = cJSON_GetObjectItemCaseSensitive(item, "midlevel") != NULL;
    if (!(midlevel >= 0.0 && midlevel <= 1.0))
        return scene_error(p, MESO_ERROR_FORMAT, &midlevel_key, "%g is not in [0, 1]", midlevel);
    if (strcmp(direction, "inward") == 0 || strcmp(direction, "outward") == 0) {
        if (has_midlevel)
            return scene_error(p, MESO_ERROR_FORMAT, &midlevel_key,
                               "only with \"direction\": \"centered\" (%s places the shell by "
                               "the mesh)",
                               direction);
        m->offset = direction[0] == 'o' ? m->depth : 0.0f;
    } else if (strcmp(direction, "centered") == 0) {
        m->offset = (float)(1.0 - midlevel) * m->depth;
    } else {
        scene_key k = scene_key_child(key, "direction");
        return scene_error(p, MESO_ERROR_FORMAT, &k,
                           "must be \"inward\", \"outward\" or \"centered\", not \"%s\"",
                           direction);
    }
    const cJSON *invert = cJSON_GetObjectItemCaseSensitive(item, "invert");
    if (invert && !cJSON_IsBool(invert)) {
        scene_key k = scene_key_child(key, "invert");
        return scene_error(p, MESO_ERROR_FORMAT, &k, "must be true or false");
    }
    if (cJSON_IsTrue(invert)) {
        meso_heightfield *hf = m->height_field;
        size_t n = (size_t)hf->width * (size_t)hf->height;
        for (size_t t = 0; t < n; t++) hf->heights[t] = 1.0f - hf->heights[t];
        meso_heightfield_update_hash(hf);
    }
    return MESO_OK;
}

/* A relief impostor's solid (Policarpo & Oliveira 2006 §4): a whole model (a built-in shape or
 * a mesh file) seen from above along -y, its bounds mapped into the unit box with a margin of
 * 0.05: x -> u, -z -> v (the built-in plane's axes, so the impostor on a plane of the model's
 * x-z size shows it unturned), y -> 1 - w. The plane's `size` should be the larger of the
 * model's x and z extents / 0.9 and `depth` its y extent / 0.9 (docs/techniques/
 * relief_layers.md), with the plane through the model's middle: the impostor's shell runs
 * from depth / 2 above the quad to depth / 2 below it (§4), and the reference traces the
 * model's own triangles there (meso_solid_model_view). */
static meso_result parse_impostor_solid(const scene_parser *p, const cJSON *item,
                                        const scene_key *key, meso_object *object) {
    static const char *const keys[] = {"impostor", "resolution", NULL};
    meso_result r = scene_check_object(p, item, key, keys);
    if (r != MESO_OK) return r;
    const char *model = NULL;
    long resolution = 96;
    if ((r = scene_get_string(p, item, key, "impostor", true, &model)) ||
        (r = scene_get_int(p, item, key, "resolution", 8, 256, false, &resolution)))
        return r;
    scene_key k = scene_key_child(key, "impostor");
    meso_mesh *mesh = NULL;
    meso_shape_desc shape = {0};
    char path[SCENE_PATH_MAX];
    snprintf(path, sizeof path, "%s", model);
    if (meso_shape_kind_from_name(model, &shape.kind)) {
        r = meso_mesh_create_shape(p->ctx, &shape, &mesh);
    } else {
        if ((r = scene_resolve_path(p, &k, model, path)) || (r = scene_check_readable(p, &k, path)))
            return r;
        r = meso_mesh_load(p->ctx, path, &mesh);
        if (r != MESO_OK) return scene_relog_at_key(p, &k, r);
    }
    if (r != MESO_OK) return r;
    meso_vec3 lo = mesh->positions[0], hi = lo;
    for (size_t i = 0; i < mesh->num_vertices; i++) {
        meso_vec3 q = mesh->positions[i];
        lo = (meso_vec3){fminf(lo.x, q.x), fminf(lo.y, q.y), fminf(lo.z, q.z)};
        hi = (meso_vec3){fmaxf(hi.x, q.x), fmaxf(hi.y, q.y), fmaxf(hi.z, q.z)};
    }
    float lateral = fmaxf(hi.x - lo.x, hi.z - lo.z), height = hi.y - lo.y;
    if (!(lateral > 0.0f) || !(height > 0.0f)) {
        meso_mesh_destroy(mesh);
        return scene_error(p, MESO_ERROR_FORMAT, &k, "%s: the model is flat", path);
    }
    for (size_t i = 0; i < mesh->num_vertices; i++) {
        meso_vec3 q = mesh->positions[i];
        mesh->positions[i] = (meso_vec3){0.5f + 0.9f * (q.x - 0.5f * (lo.x + hi.x)) / lateral,
                                         0.5f - 0.9f * (q.z - 0.5f * (lo.z + hi.z)) / lateral,
                                         0.05f + 0.9f * (q.y - lo.y) / height};
    }
    meso_mesostructure *m = &object->mesostructure;
    r = meso_solid_create_from_model(p->ctx, mesh->positions, mesh->num_vertices, mesh->indices,
                                     mesh->num_triangles, path, (int)resolution, &m->solid);
    meso_mesh_destroy(mesh);
    if (r != MESO_OK) return r;
    m->wrap = MESO_WRAP_CLAMP; /* one model, not a tiling */
    snprintf(m->source, sizeof(m->source), "%s impostor", base_name(model));
    return MESO_OK;
}

static meso_result parse_mesostructure(const scene_parser *p, const cJSON *item,
                                       const scene_key *key, bool want_color, meso_object *object,
                                       meso_image **out_color) {
    meso_result r = parse_height_map_or_solid(p, item, key, want_color, object, out_color);
    if (r != MESO_OK) return r;
    const cJSON *height = cJSON_GetObjectItemCaseSensitive(item, "height");
    if (!height) return MESO_OK;
    scene_key k = scene_key_child(key, "height");
    if (object->mesostructure.kind != MESO_MESOSTRUCTURE_HEIGHT_FIELD)
        return scene_error(p, MESO_ERROR_FORMAT, &k, "applies to a height_map, not a solid");
    return parse_height_convention(p, height, &k, &object->mesostructure);
}

static meso_result parse_height_map_or_solid(const scene_parser *p, const cJSON *item,
                                             const scene_key *key, bool want_color,
                                             meso_object *object, meso_image **out_color) {
    static const char *const keys[] = {"height_map", "solid", "depth", "wrap", "height", NULL};
    meso_result r = scene_check_object(p, item, key, keys);
    if (r != MESO_OK) return r;
    meso_mesostructure *m = &object->mesostructure;
    const cJSON *height_map = cJSON_GetObjectItemCaseSensitive(item, "height_map");
    const cJSON *solid = cJSON_GetObjectItemCaseSensitive(item, "solid");
    if (height_map && solid)
        return scene_error(p, MESO_ERROR_FORMAT, key, "height_map and solid exclude each other");
    if (!height_map && !solid)
        return scene_error(p, MESO_ERROR_FORMAT, key, "needs a height_map or a solid");
    r = scene_get_positive(p, item, key, "depth", true, true, &m->depth);
    if (r != MESO_OK) return r;
    const char *wrap = "repeat";
    r = scene_get_string(p, item, key, "wrap", false, &wrap);
    if (r != MESO_OK) return r;
    if (strcmp(wrap, "repeat") == 0) {
        m->wrap = MESO_WRAP_REPEAT;
    } else if (strcmp(wrap, "clamp") == 0) {
        m->wrap = MESO_WRAP_CLAMP;
    } else {
        scene_key k = scene_key_child(key, "wrap");
        return scene_error(p, MESO_ERROR_FORMAT, &k, "must be \"repeat\" or \"clamp\", not \"%s\"",
                           wrap);
    }

    if (height_map) {
        m->kind = MESO_MESOSTRUCTURE_HEIGHT_FIELD;
        scene_key k = scene_key_child(key, "height_map");
        if (cJSON_IsObject(height_map))
            return parse_procedural_heightfield(p, height_map, &k, m->wrap, want_color, object,
                                                out_color);
        if (!cJSON_IsString(height_map))
            return scene_error(p, MESO_ERROR_FORMAT, &k,
                               "must be a PNG path or {\"procedural\": NAME, ...}");
        const meso_scene_resource *resource = scene_find_resource(p, height_map->valuestring);
        if (resource) {
            if (!resource->image)
                return scene_error(p, MESO_ERROR_FORMAT, &k, "'%s' is not an image",
                                   resource->name);
            r = meso_heightfield_create_from_image(p->ctx, resource->image, m->wrap,
                                                   &m->height_field);
            if (r != MESO_OK) return scene_relog_at_key(p, &k, r);
        } else {
            char path[SCENE_PATH_MAX];
            if ((r = scene_resolve_path(p, &k, height_map->valuestring, path)) ||
                (r = scene_check_readable(p, &k, path)))
                return r;
            r = meso_heightfield_load_png(p->ctx, path, m->wrap, &m->height_field);
            if (r != MESO_OK) return scene_relog_at_key(p, &k, r);
        }
        uint64_t texels = (uint64_t)m->height_field->width * (uint64_t)m->height_field->height;
        if ((r = scene_account_memory(p, &k, 4 * texels)) != MESO_OK) return r;
        snprintf(m->source, sizeof(m->source), "%s", base_name(height_map->valuestring));
        return MESO_OK;
    }
    m->kind = MESO_MESOSTRUCTURE_SOLID;
    scene_key k = scene_key_child(key, "solid");
    if (cJSON_IsObject(solid))
        return cJSON_GetObjectItemCaseSensitive(solid, "impostor")
                   ? parse_impostor_solid(p, solid, &k, object)
                   : parse_procedural_solid(p, solid, &k, object);
    if (cJSON_IsString(solid)) { /* a tile mesh (docs/design.md: x, y -> u, v; z -> 1 - w) */
        const meso_scene_resource *resource = scene_find_resource(p, solid->valuestring);
        if (resource) {
            if (!resource->positions || !resource->indices)
                return scene_error(p, MESO_ERROR_FORMAT, &k, "'%s' is not a tile mesh",
                                   resource->name);
            r = meso_solid_create_from_triangles(
                p->ctx, resource->positions, resource->num_vertices, resource->indices,
                resource->num_triangles, resource->name, 0, &m->solid);
            if (r != MESO_OK) return r;
            snprintf(m->source, sizeof(m->source), "%s", resource->name);
            return MESO_OK;
        }
        char path[SCENE_PATH_MAX];
        if ((r = scene_resolve_path(p, &k, solid->valuestring, path)) ||
            (r = scene_check_readable(p, &k, path)))
            return r;
        meso_mesh *tile = NULL;
        if ((r = meso_mesh_load(p->ctx, path, &tile)) != MESO_OK)
            return scene_relog_at_key(p, &k, r);
        r = meso_solid_create_from_triangles(p->ctx, tile->positions, tile->num_vertices,
                                             tile->indices, tile->num_triangles, path, 0,
                                             &m->solid);
        meso_mesh_destroy(tile);
        if (r != MESO_OK) return r;
        snprintf(m->source, sizeof(m->source), "%s", base_name(solid->valuestring));
        return MESO_OK;
    }
    return scene_error(p, MESO_ERROR_FORMAT, &k,
                       "must be a tile mesh path or {\"procedural\": NAME, ...}");
}

/* ---- Material ----------------------------------------------------------------------------- */

/* A map's PNG at a resolved path, its memory accounted: the image and the texture made from
 * it with its mip levels (a third more), plus extra_per_texel bytes a texel. */
static meso_result load_map_image(const scene_parser *p, const scene_key *key, const char *path,
                                  uint64_t extra_per_texel, meso_image **out_image) {
    *out_image = NULL;
    meso_result r = scene_check_readable(p, key, path);
    if (r != MESO_OK) return r;
    meso_image *image = NULL;
    r = meso_image_load_png(p->ctx, path, &image);
    if (r != MESO_OK) return scene_relog_at_key(p, key, r);
    uint64_t texels = (uint64_t)image->width * (uint64_t)image->height;
    uint64_t image_bytes = texels * (uint64_t)image->channels * sizeof(float);
    r = scene_account_memory(p, key, image_bytes + image_bytes / 3 * 4 + texels * extra_per_texel);
    if (r != MESO_OK) {
        meso_image_destroy(image);
        return r;
    }
    *out_image = image;
    return MESO_OK;
}

/* A map the scene names: its resource's image (copied, its memory accounted as a file's),
 * or the PNG at the path resolved against the scene's folder. *out_encoding is the resource's
 * encoding, sRGB for a file. */
static meso_result load_named_map_image(const scene_parser *p, const scene_key *key,
                                        const char *file, uint64_t extra_per_texel,
                                        meso_image **out_image, meso_encoding *out_encoding) {
    *out_image = NULL;
    *out_encoding = MESO_ENCODING_SRGB;
    const meso_scene_resource *resource = scene_find_resource(p, file);
    if (!resource) {
        char path[SCENE_PATH_MAX];
        meso_result r = scene_resolve_path(p, key, file, path);
        return r == MESO_OK ? load_map_image(p, key, path, extra_per_texel, out_image) : r;
    }
    if (!resource->image)
        return scene_error(p, MESO_ERROR_FORMAT, key, "'%s' is not an image", resource->name);
    const meso_image *image = resource->image;
    uint64_t texels = (uint64_t)image->width * (uint64_t)image->height;
    uint64_t image_bytes = texels * (uint64_t)image->channels * sizeof(float);
    meso_result r =
        scene_account_memory(p, key, image_bytes + image_bytes / 3 * 4 + texels * extra_per_texel);
    if (r == MESO_OK) r = meso_image_clone(p->ctx, image, out_image);
    if (r != MESO_OK) return scene_relog_at_key(p, key, r);
    *out_encoding = resource->encoding;
    return MESO_OK;
}

typedef enum map_kind {
    MAP_COLOR,  /* authored in sRGB (decoded unless a resource says linear), alpha linear */
    MAP_NORMAL, /* data: RGB, x, y, z in [-1, 1] as 2 c - 1, never decoded */
} map_kind;

/* A colour or normal map's texture from its image (consumed); a colour map gets its 8-bit
 * sRGB copy (4 bytes a texel). */
static meso_result make_map_texture(const scene_parser *p, const scene_key *key, meso_image *image,
                                    map_kind kind, meso_encoding encoding, meso_wrap wrap,
                                    meso_texture **out_texture) {
    if (kind == MAP_NORMAL && image->channels < 3) {
        int channels = image->channels;
        meso_image_destroy(image);
        return scene_error(p, MESO_ERROR_FORMAT, key,
                           "a normal map needs RGB channels (this PNG has %d)", channels);
    }
    /* Colour maps are authored in sRGB; shading is linear (docs/design.md). Alpha stays linear. */
    if (kind == MAP_COLOR && encoding != MESO_ENCODING_LINEAR) {
        int colour_channels = image->channels >= 3 ? 3 : 1;
        size_t n = (size_t)image->width * (size_t)image->height;
        for (size_t t = 0; t < n; t++)
            for (int c = 0; c < colour_channels; c++) {
                float *value = &image->pixels[t * (size_t)image->channels + (size_t)c];
                *value = meso_srgb_to_linear(*value);
            }
    }
    meso_result r = meso_texture_create(p->ctx, image, wrap, true, out_texture);
    meso_image_destroy(image);
    if (r == MESO_OK && kind == MAP_COLOR) r = meso_texture_add_srgb8(p->ctx, *out_texture);
    return r;
}

/* A map at a resolved path (a mesh file's own textures). */
static meso_result load_map_file(const scene_parser *p, const scene_key *key, const char *path,
                                 map_kind kind, meso_wrap wrap, meso_texture **out_texture) {
    meso_image *image = NULL;
    meso_result r = load_map_image(p, key, path, kind == MAP_COLOR ? 4 : 0, &image);
    return r == MESO_OK
               ? make_map_texture(p, key, image, kind, MESO_ENCODING_SRGB, wrap, out_texture)
               : r;
}

/* A map the scene names: a resource or a file beside the scene. */
static meso_result load_named_map(const scene_parser *p, const scene_key *key, const char *file,
                                  map_kind kind, meso_wrap wrap, meso_texture **out_texture) {
    meso_image *image = NULL;
    meso_encoding encoding;
    meso_result r =
        load_named_map_image(p, key, file, kind == MAP_COLOR ? 4 : 0, &image, &encoding);
    return r == MESO_OK ? make_map_texture(p, key, image, kind, encoding, wrap, out_texture) : r;
}

/* A texture the mesh file names, beside the mesh file (`texture` relative to its folder), with
 * the object's mesostructure's wrap (repeat when it has none). */
static meso_result load_mesh_texture(const scene_parser *p, const scene_key *key,
                                     const char *mesh_path, const char *texture, map_kind kind,
                                     const meso_object *object, meso_texture **out_texture) {
    char path[SCENE_PATH_MAX];
    const char *slash = strrchr(mesh_path, '/');
    int folder = slash ? (int)(slash - mesh_path) : 1;
    int n = snprintf(path, sizeof path, "%.*s/%s", folder, slash ? mesh_path : ".", texture);
    scene_key k = scene_key_child(key, "shape");
    if (n < 0 || n >= (int)sizeof path)
        return scene_error(p, MESO_ERROR_LIMIT, &k, "texture path too long");
    const meso_mesostructure *m = &object->mesostructure;
    meso_wrap wrap = m->kind != MESO_MESOSTRUCTURE_NONE ? m->wrap : MESO_WRAP_REPEAT;
    return load_map_file(p, &k, path, kind, wrap, out_texture);
}

static void append_note(char *text, size_t size, const char *note) {
    size_t used = strlen(text);
    snprintf(text + used, size - used, "%s%s", used ? ", " : "", note);
}

/* "<kind> texture not used: <why>" */
static void append_unused_note(char *text, size_t size, const char *kind, const char *why) {
    char note[160];
    snprintf(note, sizeof note, "%s texture not used: %s", kind, why);
    append_note(text, size, note);
}

/* The mesh file's own material (shape {"file"}: glTF baseColorFactor / baseColorTexture, MTL
 * Kd / map_Kd), used when the scene's material sets no colour (neither "albedo" nor
 * "color_map"). The texture must lie beside the mesh file or below it (no absolute path, no
 * ".."), like a glTF's buffers. What was used and what not goes to object->mesh_material_note
 * for meso info. */
static meso_result apply_mesh_material(const scene_parser *p, const cJSON *obj,
                                       const scene_key *key, const char *mesh_path,
                                       const meso_mesh_material *from_file, meso_object *object) {
    char *note = object->mesh_material_note;
    size_t note_size = sizeof(object->mesh_material_note);
    const cJSON *material = cJSON_GetObjectItemCaseSensitive(obj, "material");
    bool scene_sets_colour = cJSON_GetObjectItemCaseSensitive(material, "albedo") ||
                             cJSON_GetObjectItemCaseSensitive(material, "color_map");
    bool has_any = from_file->has_color || from_file->color_map[0];
    if (has_any && scene_sets_colour) {
        append_note(note, note_size, "colour not used: the scene's material sets one");
    } else if (has_any) {
        if (from_file->has_color) {
            object->material.albedo = from_file->color;
            append_note(note, note_size, "base colour used");
        }
        const char *texture = from_file->color_map;
        const char *unused = meso_mesh_material_unused_reason(texture);
        if (texture[0] && unused) {
            append_unused_note(note, note_size, "colour", unused);
        } else if (texture[0]) {
            meso_result r = load_mesh_texture(p, key, mesh_path, texture, MAP_COLOR, object,
                                              &object->material.color_map);
            if (r != MESO_OK) return r;
            append_note(note, note_size, "colour texture used");
        }
    }
    const char *normal = from_file->normal_map;
    const char *unused = meso_mesh_material_unused_reason(normal);
    if (normal[0] && cJSON_GetObjectItemCaseSensitive(material, "normal_map")) {
        append_note(note, note_size, "normal texture not used: the scene's material sets one");
    } else if (normal[0] && unused) {
        append_unused_note(note, note_size, "normal", unused);
    } else if (normal[0]) {
        meso_result r = load_mesh_texture(p, key, mesh_path, normal, MAP_NORMAL, object,
                                          &object->material.normal_map);
        if (r != MESO_OK) return r;
        append_note(note, note_size,
                    object->material.normal_map_directx
                        ? "normal texture used (DirectX convention, from the scene)"
                        : "normal texture used (OpenGL convention)");
    }
    if (from_file->ignored[0]) {
        char ignored[600];
        snprintf(ignored, sizeof ignored, "ignored: %s", from_file->ignored);
        append_note(note, note_size, ignored);
    }
    return MESO_OK;
}

static meso_result parse_material(const scene_parser *p, const cJSON *item, const scene_key *key,
                                  const meso_image *generated_color, meso_object *object) {
    static const char *const keys[] = {"albedo",    "color_map",  "specular",
                                       "shininess", "normal_map", "normal_map_convention",
                                       NULL};
    meso_material *mat = &object->material;
    mat->albedo = (meso_vec3){0.8f, 0.8f, 0.8f};
    mat->specular = (meso_vec3){0.0f, 0.0f, 0.0f};
    mat->shininess = 32.0f;
    if (!item) return MESO_OK;
    meso_result r = scene_check_object(p, item, key, keys);
    if (r != MESO_OK) return r;
    const char *color_map = NULL;
    if ((r = scene_get_vec3(p, item, key, "albedo", true, false, &mat->albedo)) ||
        (r = scene_get_vec3(p, item, key, "specular", true, false, &mat->specular)) ||
        (r = scene_get_positive(p, item, key, "shininess", false, false, &mat->shininess)) ||
        (r = scene_get_string(p, item, key, "color_map", false, &color_map)))
        return r;
    const meso_mesostructure *m = &object->mesostructure;
    meso_wrap wrap = m->kind != MESO_MESOSTRUCTURE_NONE ? m->wrap : MESO_WRAP_REPEAT;
    const char *normal_map = NULL, *convention = NULL;
    if ((r = scene_get_string(p, item, key, "normal_map", false, &normal_map)) ||
        (r = scene_get_string(p, item, key, "normal_map_convention", false, &convention)))
        return r;
    if (convention) {
        scene_key k = scene_key_child(key, "normal_map_convention");
        if (strcmp(convention, "directx") == 0)
            mat->normal_map_directx = true;
        else if (strcmp(convention, "opengl") != 0)
            return scene_error(p, MESO_ERROR_FORMAT, &k, "must be \"opengl\" or \"directx\"");
    }
    if (normal_map) {
        scene_key k = scene_key_child(key, "normal_map");
        if ((r = load_named_map(p, &k, normal_map, MAP_NORMAL, wrap, &mat->normal_map))) return r;
    }
    if (!color_map) return MESO_OK;
    scene_key k = scene_key_child(key, "color_map");
    if (strcmp(color_map, "mesostructure") == 0) {
        if (!generated_color)
            return scene_error(p, MESO_ERROR_FORMAT, &k,
                               "\"mesostructure\" needs a procedural height_map");
        if ((r = meso_texture_create(p->ctx, generated_color, wrap, true, &mat->color_map)))
            return r;
        return meso_texture_add_srgb8(p->ctx, mat->color_map);
    }
    return load_named_map(p, &k, color_map, MAP_COLOR, wrap, &mat->color_map);
}

/* ---- Shape and transform ------------------------------------------------------------------ */

static meso_result parse_transform(const scene_parser *p, const cJSON *item, const scene_key *key,
                                   meso_mat4 *out) {
    static const char *const keys[] = {"translate", "rotate_deg", "scale", NULL};
    *out = meso_mat4_identity();
    if (!item) return MESO_OK;
    meso_result r = scene_check_object(p, item, key, keys);
    if (r != MESO_OK) return r;
    meso_vec3 translate = {0, 0, 0}, rotate = {0, 0, 0};
    float scale = 1.0f;
    if ((r = scene_get_vec3(p, item, key, "translate", false, false, &translate)) ||
        (r = scene_get_vec3(p, item, key, "rotate_deg", false, false, &rotate)) ||
        (r = scene_get_positive(p, item, key, "scale", false, false, &scale)))
        return r;
    const float to_radians = MESO_PI / 180.0f;
    /* Scale, then rotate about X, then Y, then Z, then translate (column vectors). */
    meso_mat4 m = meso_mat4_scale(scale);
    m = meso_mat4_mul(meso_mat4_rotate((meso_vec3){1, 0, 0}, rotate.x * to_radians), m);
    m = meso_mat4_mul(meso_mat4_rotate((meso_vec3){0, 1, 0}, rotate.y * to_radians), m);
    m = meso_mat4_mul(meso_mat4_rotate((meso_vec3){0, 0, 1}, rotate.z * to_radians), m);
    *out = meso_mat4_mul(meso_mat4_translate(translate), m);
    return MESO_OK;
}

/* The object's mesh: a built-in shape or a mesh file; for a file, its material (zeroed for a
 * built-in shape) and resolved path. */
static meso_result create_mesh(const scene_parser *p, const cJSON *obj, const scene_key *key,
                               meso_mesh **out_mesh, meso_mesh_material *out_material,
                               char out_path[SCENE_PATH_MAX]) {
    memset(out_material, 0, sizeof(*out_material));
    out_path[0] = 0;
    static const char *const shape_params[] = {"size", "minor_radius", "height", "segments"};
    const cJSON *shape = cJSON_GetObjectItemCaseSensitive(obj, "shape");
    scene_key shape_key = scene_key_child(key, "shape");
    meso_result r;
    if (cJSON_IsObject(shape)) {
        static const char *const keys[] = {"file", NULL};
        for (size_t k = 0; k < sizeof(shape_params) / sizeof(shape_params[0]); k++)
            if (cJSON_GetObjectItemCaseSensitive(obj, shape_params[k])) {
                scene_key pk = scene_key_child(key, shape_params[k]);
                return scene_error(p, MESO_ERROR_FORMAT, &pk, "applies to built-in shapes only");
            }
        const char *file = NULL;
        if ((r = scene_check_object(p, shape, &shape_key, keys)) ||
            (r = scene_get_string(p, shape, &shape_key, "file", true, &file)))
            return r;
        scene_key file_key = scene_key_child(&shape_key, "file");
        if ((r = scene_resolve_path(p, &file_key, file, out_path)) ||
            (r = scene_check_readable(p, &file_key, out_path)))
            return r;
        r = meso_mesh_load_with_material(p->ctx, out_path, out_mesh, out_material);
        if (r != MESO_OK) return scene_relog_at_key(p, &file_key, r);
        return scene_account_memory(
            p, key,
            meso_mesh_memory_estimate((*out_mesh)->num_vertices, (*out_mesh)->num_triangles));
    }
    if (shape && !cJSON_IsString(shape))
        return scene_error(p, MESO_ERROR_FORMAT, &shape_key,
                           "must be a shape name or {\"file\": PATH}");
    const char *name = shape ? shape->valuestring : "plane";
    meso_shape_desc desc = {0};
    if (!meso_shape_kind_from_name(name, &desc.kind))
        return scene_error(p, MESO_ERROR_FORMAT, &shape_key,
                           "unknown shape \"%s\" (plane, sphere, torus, cylinder, vase, teapot)",
                           name);
    long segments = 0;
    if ((r = scene_get_positive(p, obj, key, "size", false, false, &desc.size)) ||
        (r = scene_get_positive(p, obj, key, "minor_radius", false, false, &desc.minor_radius)) ||
        (r = scene_get_positive(p, obj, key, "height", false, false, &desc.height)) ||
        (r = scene_get_int(p, obj, key, "segments", 1, 4096, true, &segments)))
        return r;
    desc.segments = (int)segments;
    /* accounted before it is built: a mesh over the budget is never allocated */
    if ((r = scene_account_memory(p, key, meso_shape_memory_estimate(&desc))) != MESO_OK) return r;
    r = meso_mesh_create_shape(p->ctx, &desc, out_mesh);
    /* the generator names the shape ("cylinder: ... vertices exceed the limit"): said at the
     * object's key of the scene file */
    if (r == MESO_ERROR_INVALID_ARGUMENT) return scene_relog_as_format(p, key, r);
    return r == MESO_OK ? r : scene_relog_at_key(p, key, r);
}

/* Scaled texture coordinates are limited so that u times the largest texture side (16384 =
 * 2^14) stays within 2^30: samplers and techniques convert texel positions to int, and a
 * uv_scale of 1e10 would overflow them (undefined behaviour). 65536 tiles is far beyond what
 * can be seen. */
#define MAX_TEXTURE_COORDINATE 65536.0f

static meso_result check_texture_coordinates(const scene_parser *p, const scene_key *key,
                                             const meso_mesh *mesh, const char *cause) {
    float largest = 0.0f;
    for (size_t i = 0; i < mesh->num_vertices; i++) {
        float u = fabsf(mesh->uvs[i].x), v = fabsf(mesh->uvs[i].y);
        largest = u > largest ? u : largest;
        largest = v > largest ? v : largest;
    }
    if (largest <= MAX_TEXTURE_COORDINATE) return MESO_OK; /* NaN is refused by validation */
    scene_key k = scene_key_child(key, cause);
    return scene_error(p, MESO_ERROR_LIMIT, &k,
                       "scaled texture coordinates reach %g, beyond the limit %g", (double)largest,
                       (double)MAX_TEXTURE_COORDINATE);
}

/* World-space mesh, scaled UVs, validated, with tangents, curvature and quadrics. */
static meso_result build_mesh(const scene_parser *p, const cJSON *obj, const scene_key *key,
                              meso_object *object) {
    meso_mat4 transform;
    meso_vec2 uv_scale = {1.0f, 1.0f};
    meso_mesh_material from_file;
    char mesh_path[SCENE_PATH_MAX];
    scene_key transform_key = scene_key_child(key, "transform");
    meso_result r;
    if ((r = parse_transform(p, cJSON_GetObjectItemCaseSensitive(obj, "transform"), &transform_key,
                             &transform)) ||
        (r = scene_get_vec2(p, obj, key, "uv_scale", true, &uv_scale)) ||
        (r = create_mesh(p, obj, key, &object->mesh, &from_file, mesh_path)) ||
        (mesh_path[0] && (r = apply_mesh_material(p, obj, key, mesh_path, &from_file, object))))
        return r;
    /* a normal map needs them too: its tangent frame is dP/du, dP/dv (docs/scene-format.md) */
    bool require_uvs = object->mesostructure.kind != MESO_MESOSTRUCTURE_NONE ||
                       object->material.color_map != NULL || object->material.normal_map != NULL;
    /* The transform is a uniform scale times a rotation: its scale is the length of a column. */
    float world_per_mesh_unit =
        sqrtf(transform.m[0] * transform.m[0] + transform.m[1] * transform.m[1] +
              transform.m[2] * transform.m[2]);
    if ((r = scene_texture_coordinates(p, obj, key, mesh_path, require_uvs, world_per_mesh_unit,
                                       object)))
        return r;
    meso_mesh *mesh = object->mesh;
    meso_mesh_transform(mesh, transform);
    float offset = object->mesostructure.offset; /* "height": place the shell (see above) */
    if (offset != 0.0f)
        for (size_t v = 0; v < mesh->num_vertices; v++)
            mesh->positions[v] = meso_vec3_madd(mesh->positions[v], mesh->normals[v], offset);
    if (mesh->uvs) {
        meso_mesh_scale_uvs(mesh, uv_scale);
        /* a tiny "uv_projection_scale" makes large coordinates as surely as a large uv_scale */
        bool projected = strstr(object->texture_coordinates, "projection") != NULL;
        const char *cause = projected && uv_scale.x == 1.0f && uv_scale.y == 1.0f
                                ? "uv_projection_scale"
                                : "uv_scale";
        if ((r = check_texture_coordinates(p, key, mesh, cause)) != MESO_OK) return r;
    }
    char label[SCENE_KEY_MAX + 1100];
    snprintf(label, sizeof(label), "%s: %s", p->file, key->text);
    if ((r = meso_mesh_validate(p->ctx, mesh, label, require_uvs))) return r;
    if (!mesh->uvs) return MESO_OK;
    if ((r = meso_mesh_compute_tangents(p->ctx, mesh)) ||
        (r = meso_mesh_compute_curvature(p->ctx, mesh)) ||
        (r = meso_mesh_compute_quadrics(p->ctx, mesh)))
        return r;
    return MESO_OK;
}

/* ---- Technique ---------------------------------------------------------------------------- */

/* One option value: a finite number or a boolean (true = 1). */
static meso_result parse_option(const scene_parser *p, const cJSON *child, const scene_key *key,
                                const char *technique, meso_object *object) {
    scene_key k = scene_key_child(key, child->string);
    if (object->num_options >= MESO_OPTIONS_MAX)
        return scene_error(p, MESO_ERROR_LIMIT, key, "more than %d options", MESO_OPTIONS_MAX);
    for (int o = 0; o < object->num_options; o++)
        if (strcmp(object->options[o].technique, technique) == 0 &&
            strcmp(object->options[o].name, child->string) == 0)
            return scene_error(p, MESO_ERROR_FORMAT, &k, "duplicate key");
    meso_option *option = &object->options[object->num_options];
    snprintf(option->technique, sizeof option->technique, "%s", technique);
    meso_result r = copy_name(p, &k, child->string, option->name);
    if (r != MESO_OK) return r;
    if (cJSON_IsBool(child)) {
        option->value = cJSON_IsTrue(child) ? 1.0 : 0.0;
    } else if (cJSON_IsNumber(child) && isfinite(child->valuedouble)) {
        option->value = child->valuedouble;
    } else {
        return scene_error(p, MESO_ERROR_FORMAT, &k, "must be a finite number or a boolean");
    }
    object->num_options++;
    return MESO_OK;
}

/* "technique_options": {"relief": {"linear_steps": 64}, "vdm": {...}} keyed by technique, or
 * the flat form {"linear_steps": 64} for the object's own technique (technique ""). The names
 * are checked against the techniques' option tables by the renderer (meso_technique_check_scene),
 * which this module does not link. */
static meso_result parse_options(const scene_parser *p, const cJSON *item, const scene_key *key,
                                 meso_object *object) {
    if (!item) return MESO_OK;
    if (!cJSON_IsObject(item))
        return scene_error(p, MESO_ERROR_FORMAT, key,
                           "must be an object: {\"TECHNIQUE\": {\"option\": value}}");
    for (const cJSON *child = item->child; child; child = child->next) {
        meso_result r = MESO_OK;
        if (!cJSON_IsObject(child)) {
            r = parse_option(p, child, key, "", object);
        } else {
            scene_key technique_key = scene_key_child(key, child->string);
            char technique[MESO_NAME_MAX];
            if ((r = copy_name(p, &technique_key, child->string, technique)) != MESO_OK) return r;
            if (!technique[0])
                return scene_error(p, MESO_ERROR_FORMAT, &technique_key, "empty technique name");
            for (const cJSON *prev = item->child; prev != child; prev = prev->next)
                if (strcmp(prev->string, child->string) == 0)
                    return scene_error(p, MESO_ERROR_FORMAT, &technique_key, "duplicate key");
            for (const cJSON *option = child->child; option && r == MESO_OK; option = option->next)
                r = parse_option(p, option, &technique_key, technique, object);
        }
        if (r != MESO_OK) return r;
    }
    return MESO_OK;
}

/* ---- Object ------------------------------------------------------------------------------- */

/* Whether the material asks for the procedural height field's colours. */
static bool wants_generated_color(const cJSON *obj) {
    const cJSON *material = cJSON_GetObjectItemCaseSensitive(obj, "material");
    const cJSON *color_map = cJSON_GetObjectItemCaseSensitive(material, "color_map");
    return cJSON_IsString(color_map) && strcmp(color_map->valuestring, "mesostructure") == 0;
}

meso_result scene_parse_object(const scene_parser *p, const cJSON *item, int index,
                               meso_object *object) {
    static const char *const keys[] = {"name",
                                       "shape",
                                       "size",
                                       "minor_radius",
                                       "height",
                                       "segments",
                                       "transform",
                                       "uv_scale",
                                       "uv_projection",
                                       "uv_projection_scale",
                                       "uv_projection_axis",
                                       "material",
                                       "mesostructure",
                                       "technique",
                                       "technique_options",
                                       NULL};
    scene_key objects = {"objects"};
    scene_key key = scene_key_index(&objects, index);
    meso_image *generated_color = NULL;
    meso_result r = scene_check_object(p, item, &key, keys);
    if (r != MESO_OK) return r;

    const char *name = NULL, *technique = "flat";
    scene_key name_key = scene_key_child(&key, "name");
    scene_key technique_key = scene_key_child(&key, "technique");
    if ((r = scene_get_string(p, item, &key, "name", false, &name))) return r;
    if (name) {
        if ((r = copy_name(p, &name_key, name, object->name))) return r;
    } else if ((r = copy_name(p, &name_key, key.text, object->name))) {
        return r;
    }
    if ((r = scene_get_string(p, item, &key, "technique", false, &technique)) ||
        (r = copy_name(p, &technique_key, technique, object->technique)))
        return r;
    if (!technique[0]) return scene_error(p, MESO_ERROR_FORMAT, &technique_key, "empty name");
    scene_key options_key = scene_key_child(&key, "technique_options");
    r = parse_options(p, cJSON_GetObjectItemCaseSensitive(item, "technique_options"), &options_key,
                      object);
    if (r != MESO_OK) return r;

    const cJSON *mesostructure = cJSON_GetObjectItemCaseSensitive(item, "mesostructure");
    if (mesostructure) {
        scene_key k = scene_key_child(&key, "mesostructure");
        r = parse_mesostructure(p, mesostructure, &k, wants_generated_color(item), object,
                                &generated_color);
        if (r != MESO_OK) goto fail;
    }
    scene_key material_key = scene_key_child(&key, "material");
    r = parse_material(p, cJSON_GetObjectItemCaseSensitive(item, "material"), &material_key,
                       generated_color, object);
    if (r != MESO_OK) goto fail;
    r = build_mesh(p, item, &key, object);
fail:
    meso_image_destroy(generated_color);
    return r;
}

/* A number member in [lo, hi], else 0 (the default): the estimate reads the scene before
 * it is validated, and leaves the refusing of bad values to the parse. */
static double number_or_default(const cJSON *object, const char *name, double lo, double hi) {
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(object, name);
    return cJSON_IsNumber(item) && item->valuedouble >= lo && item->valuedouble <= hi
               ? item->valuedouble
               : 0.0;
}

uint64_t scene_objects_memory_estimate(const cJSON *objects) {
    uint64_t total = 0;
    for (const cJSON *obj = objects ? objects->child : NULL; obj; obj = obj->next) {
        const cJSON *shape = cJSON_GetObjectItemCaseSensitive(obj, "shape");
        meso_shape_desc desc = {0};
        if ((!shape || cJSON_IsString(shape)) &&
            meso_shape_kind_from_name(shape ? shape->valuestring : "plane", &desc.kind)) {
            desc.size = (float)number_or_default(obj, "size", 1e-30, 1e30);
            desc.minor_radius = (float)number_or_default(obj, "minor_radius", 1e-30, 1e30);
            desc.height = (float)number_or_default(obj, "height", 1e-30, 1e30);
            desc.segments = (int)number_or_default(obj, "segments", 1, 4096);
            total += meso_shape_memory_estimate(&desc);
        }
        const cJSON *m = cJSON_GetObjectItemCaseSensitive(obj, "mesostructure");
        const cJSON *source = cJSON_GetObjectItemCaseSensitive(m, "height_map");
        if (cJSON_IsObject(source)) {
            double side =
                number_or_default(source, "resolution", 1, MESO_HEIGHTFIELD_MAX_RESOLUTION);
            if (side == 0.0) side = 512.0;
            total += (uint64_t)(side * side) * 16; /* heights and generated colour */
        }
    }
    return total;
}

void scene_object_deinit(meso_object *object) {
    meso_mesh_destroy(object->mesh);
    meso_texture_destroy(object->material.color_map);
    meso_texture_destroy(object->material.normal_map);
    meso_heightfield_destroy(object->mesostructure.height_field);
    meso_solid_destroy(object->mesostructure.solid);
    memset(object, 0, sizeof(*object));
}
