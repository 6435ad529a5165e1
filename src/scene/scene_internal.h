/* Private to the scene module: the parser's state and the typed JSON getters that name the
 * key path in every error ("scene.json: objects[0].mesostructure.depth: must be ..."). */
#ifndef MESO_SCENE_INTERNAL_H
#define MESO_SCENE_INTERNAL_H

#include <cjson/cJSON.h>

#include "meso/scene.h"

#define SCENE_PATH_MAX 4096 /* resolved file paths */
#define SCENE_KEY_MAX 256   /* key paths such as objects[12].mesostructure.height_map */

typedef struct scene_parser {
    meso_context *ctx;
    const char *file;          /* the scene's name in messages */
    const char *base_dir;      /* relative paths resolve against it */
    uint64_t *memory_estimate; /* bytes the objects parsed so far need (the memory budget) */
    const meso_scene_resource *resources; /* in-memory data named in place of files */
    size_t num_resources;
} scene_parser;

/* The resource called `name`, or NULL (then `name` is a file). */
const meso_scene_resource *scene_find_resource(const scene_parser *p, const char *name);

/* A key path: "" at the top, "objects[0]", "objects[0].material". */
typedef struct scene_key {
    char text[SCENE_KEY_MAX];
} scene_key;

scene_key scene_key_child(const scene_key *parent, const char *key);
scene_key scene_key_index(const scene_key *parent, int index);

/* Log "<file>: <key path>: <reason>" (or "<file>: <reason>" at the top) and return code. */
/* Add `bytes` to the scene's memory estimate and refuse (MESO_ERROR_LIMIT, naming the file
 * and key) when the total exceeds the context's limit: eight 4096-segment planes are refused
 * at the second, not after 18 GB. */
meso_result scene_account_memory(const scene_parser *p, const scene_key *key, uint64_t bytes);

/* Containers nested deeper than this are refused (cJSON's own limit is 1000). */
#define SCENE_MAX_DEPTH 64

/* Refuse numbers cJSON accepts but JSON does not ("01", "64.", "1.e5", "+1"), naming the key
 * path: the text of a scene cJSON has parsed. */
meso_result scene_check_numbers(const scene_parser *p, const char *json);

meso_result scene_error(const scene_parser *p, meso_result code, const scene_key *key,
                        const char *format, ...) __attribute__((format(printf, 4, 5)));

/* `item` must be an object whose keys are all in allowed[] (NULL-terminated), each once. */
meso_result scene_check_object(const scene_parser *p, const cJSON *item, const scene_key *key,
                               const char *const allowed[]);

/* Typed getters of obj[name]. Absent keys leave *out at the default given and return MESO_OK,
 * unless `required`. Wrong types and non-finite numbers are MESO_ERROR_FORMAT naming the key. */
meso_result scene_get_number(const scene_parser *p, const cJSON *obj, const scene_key *key,
                             const char *name, bool required, double *out);
/* An integer in [min_value, max_value]; above max_value is MESO_ERROR_LIMIT when limit_error. */
meso_result scene_get_int(const scene_parser *p, const cJSON *obj, const scene_key *key,
                          const char *name, long min_value, long max_value, bool limit_error,
                          long *out);
/* A finite number > 0 (positive) or >= 0. */
meso_result scene_get_positive(const scene_parser *p, const cJSON *obj, const scene_key *key,
                               const char *name, bool allow_zero, bool required, float *out);
meso_result scene_get_vec3(const scene_parser *p, const cJSON *obj, const scene_key *key,
                           const char *name, bool non_negative, bool required, meso_vec3 *out);
meso_result scene_get_vec2(const scene_parser *p, const cJSON *obj, const scene_key *key,
                           const char *name, bool positive, meso_vec2 *out);
meso_result scene_get_string(const scene_parser *p, const cJSON *obj, const scene_key *key,
                             const char *name, bool required, const char **out);

/* Resolve a path from the scene against base_dir (absolute paths stay). */
meso_result scene_resolve_path(const scene_parser *p, const scene_key *key, const char *path,
                               char out[SCENE_PATH_MAX]);

/* A missing or unreadable referenced file, reported with the scene, the key and the path. */
meso_result scene_check_readable(const scene_parser *p, const scene_key *key, const char *path);
/* A loader's error (naming only its own file) said again at the scene's key. */
meso_result scene_relog_at_key(const scene_parser *p, const scene_key *key, meso_result r);
/* A library's MESO_ERROR_INVALID_ARGUMENT for parameters the parser let through, said as a bad
 * value (MESO_ERROR_FORMAT) at the key with the library's reason; other results pass. */
meso_result scene_relog_as_format(const scene_parser *p, const scene_key *key, meso_result r);

/* The texture coordinates of object->mesh (in its own coordinates, before the transform): the
 * mesh's, or the projection of "uv_projection" / "uv_projection_scale" / "uv_projection_axis"
 * when asked, when the mesh has none and `needs_uvs`, or when its own are degenerate over most
 * of its area (scene_texture_coordinates.c). mesh_file is the mesh's path, "" for a built-in
 * shape; world_per_mesh_unit the transform's scale. Fills object->texture_coordinates. */
meso_result scene_texture_coordinates(const scene_parser *p, const cJSON *obj, const scene_key *key,
                                      const char *mesh_file, bool needs_uvs,
                                      float world_per_mesh_unit, meso_object *object);

/* "environment" of the top level (scene_environment.c); item may be NULL (none). */
meso_result scene_parse_environment(const scene_parser *p, const cJSON *item, meso_scene *scene);

/* Parse objects[index] into *object (zeroed by the caller; released by scene_object_deinit
 * whatever the result). */
/* The memory the objects' built-in shapes and procedural height fields will need, read from
 * the JSON before any is built (values the parse would refuse count as defaults). */
uint64_t scene_objects_memory_estimate(const cJSON *objects);
meso_result scene_parse_object(const scene_parser *p, const cJSON *item, int index,
                               meso_object *object);
void scene_object_deinit(meso_object *object);

#endif
