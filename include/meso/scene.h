/* meso scenes: the JSON scene file (docs/design.md, docs/scene-format.md) as an immutable struct.
 *
 * Loading resolves everything a renderer needs: meshes are built or imported, transformed to
 * world space, validated, given UVs scaled by uv_scale, tangents, curvature and quadrics;
 * height fields and solids are made; colour maps are loaded and converted from sRGB to linear.
 * After loading the scene is read-only and may be shared by any number of renderers/threads.
 *
 * Errors name the file, the key path and the reason: "scene.json: objects[0].mesostructure.depth:
 * must be a finite number >= 0". Unknown keys are errors (they are usually typos).
 */
#ifndef MESO_SCENE_H
#define MESO_SCENE_H

#include <string.h>

#include "meso/core.h"
#include "meso/environment.h"
#include "meso/geom.h"
#include "meso/image.h"
#include "meso/math.h"
#include "meso/mesostructure.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MESO_SCENE_MAX_FILE_BYTES (16u << 20)
#define MESO_SCENE_MAX_OBJECTS 256
#define MESO_SCENE_MAX_LIGHTS 16
#define MESO_OPTIONS_MAX 32
#define MESO_NAME_MAX 64

typedef enum meso_light_type {
    MESO_LIGHT_DIRECTIONAL = 0,
    MESO_LIGHT_POINT,
} meso_light_type;

typedef struct meso_light {
    meso_light_type type;
    meso_vec3 direction; /* directional: unit vector toward the light */
    meso_vec3 position;  /* point */
    meso_vec3 color;     /* linear RGB intensity; point lights are not attenuated */
} meso_light;

typedef struct meso_camera {
    meso_vec3 eye, target, up;
    float fov_y_deg;
} meso_camera;

typedef struct meso_material {
    meso_vec3 albedo;
    meso_texture *color_map; /* linear RGB, NULL when none; owned by the scene */
    meso_vec3 specular;      /* Blinn-Phong, 0 = none */
    float shininess;
    /* tangent-space normal map (linear RGB, OpenGL convention: +x along dP/du, +y along dP/dv,
     * +z the normal), NULL when none; owned by the scene. It replaces the shading normal
     * (docs/scene-format.md, "normal_map"). */
    meso_texture *normal_map;
    bool normal_map_directx; /* the map's green points along -dP/dv (flipped when read) */
} meso_material;

typedef enum meso_mesostructure_kind {
    MESO_MESOSTRUCTURE_NONE = 0,
    MESO_MESOSTRUCTURE_HEIGHT_FIELD,
    MESO_MESOSTRUCTURE_SOLID,
} meso_mesostructure_kind;

typedef struct meso_mesostructure {
    meso_mesostructure_kind kind;
    meso_heightfield *height_field; /* HEIGHT_FIELD: owned by the scene */
    meso_solid *solid;              /* SOLID: owned by the scene */
    float depth;                    /* shell thickness, world units */
    float offset; /* how far the mesh was moved along its normals to make the scene's "height"
                     convention inward (0 for inward; docs/scene-format.md) */
    meso_wrap wrap;
    char source[MESO_NAME_MAX]; /* "bricks" or the file name, for labels and logs */
} meso_mesostructure;

/* A technique parameter: numbers and booleans (true = 1). From the scene, keyed by technique
 * ("technique_options": {"relief": {"linear_steps": 64}}: technique "relief") or in the flat
 * form of one technique ("technique_options": {"linear_steps": 64}: technique "", meaning the
 * object's own technique; for an object built by hand without a technique name, whichever
 * technique draws it). Every technique reads its options through its option table
 * (meso_technique_info.options); meso_technique_check_scene checks them all. */
typedef struct meso_option {
    char technique[MESO_NAME_MAX]; /* "" = the object's own technique (the flat form) */
    char name[MESO_NAME_MAX];
    double value;
} meso_option;

typedef struct meso_object {
    char name[MESO_NAME_MAX]; /* "objects[0]" unless the scene names it */
    meso_mesh *mesh;          /* world space, uv_scale applied, tangents/curvature/quadrics */
    meso_material material;
    meso_mesostructure mesostructure;
    char technique[MESO_NAME_MAX]; /* as written in the scene ("flat" when absent) */
    meso_option options[MESO_OPTIONS_MAX];
    int num_options;
    /* shape {"file"}: what of the mesh file's material was used and what not ("base colour
     * used, colour texture used, ignored: occlusion texture"), "" otherwise (meso info) */
    char mesh_material_note[768];
    /* Which texture coordinates the mesh carries and why: "the file's", "the shape's", "none",
     * or "box projection, 0.5 world units a tile (the file has none)" (meso info;
     * docs/scene-format.md, "uv_projection"). */
    char texture_coordinates[256];
} meso_object;

typedef struct meso_scene {
    char path[1024];      /* the file it came from, or the name given to meso_scene_parse */
    int width, height;    /* 512 x 512 when absent */
    meso_vec3 background; /* linear RGB */
    meso_encoding encoding;
    meso_camera camera;
    meso_vec3 ambient;
    /* Distant light from every direction ("environment": an .hdr map or a procedural sky;
     * docs/scene-format.md); NULL when the scene has none. Owned by the scene. */
    meso_environment *environment;
    meso_light lights[MESO_SCENE_MAX_LIGHTS];
    int num_lights;
    meso_object *objects;
    int num_objects;
} meso_scene;

/* Load a scene file. Relative paths inside resolve against the file's folder. Returns MESO_OK,
 * MESO_ERROR_IO (missing/unreadable, naming the file), MESO_ERROR_FORMAT (malformed JSON, wrong
 * type, unknown key, bad value: naming file and key path), MESO_ERROR_LIMIT. */
meso_result meso_scene_load(meso_context *ctx, const char *path, meso_scene **out_scene);
/* Parse scene text; `name` is used in messages, `base_dir` resolves relative paths (NULL: "."). */
meso_result meso_scene_parse(meso_context *ctx, const char *json, const char *name,
                             const char *base_dir, meso_scene **out_scene);

/* Data a scene's text names in place of a file, for programs that hold their pictures and
 * tile meshes in memory (the Python package hands over NumPy arrays this way, docs/python.md).
 * A string value of "height_map", "color_map", "normal_map" or a tile-mesh "solid" that equals
 * a resource's `name` takes the resource instead of a file: the same conversions follow as for
 * a file (a height map's luminance, a colour map's sRGB decoding, the memory budget). */
typedef struct meso_scene_resource {
    const char *name; /* matched exactly against the scene's string, before path resolution */
    /* height_map, color_map, normal_map: values as a PNG loads them ([0, 1]; 1-4 channels) */
    const meso_image *image;
    meso_encoding encoding; /* a colour map's: sRGB (default) is decoded, linear kept as is */
    /* a tile-mesh "solid" (meso_solid_create_from_triangles): 3 indices a triangle */
    const meso_vec3 *positions;
    size_t num_vertices;
    const uint32_t *indices;
    size_t num_triangles;
} meso_scene_resource;

typedef struct meso_scene_desc {
    const char *json;     /* the scene text */
    const char *name;     /* used in messages (NULL: "scene") */
    const char *base_dir; /* relative paths resolve against it (NULL: ".") */
    const meso_scene_resource *resources;
    size_t num_resources;
} meso_scene_desc;

/* Make a scene from desc's text, as meso_scene_parse does, with desc's resources standing in
 * for the files they name. desc and the resources are read during the call only (images and
 * arrays are copied). Returns as meso_scene_parse; a resource of the wrong kind for its key
 * (an image given as a tile mesh, or the reverse) is MESO_ERROR_FORMAT naming the key.
 * Threads: safe on different contexts at once. */
meso_result meso_scene_create(meso_context *ctx, const meso_scene_desc *desc,
                              meso_scene **out_scene);
void meso_scene_destroy(meso_scene *scene);

#ifdef __cplusplus
}
#endif
#endif
