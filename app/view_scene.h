/* The scenes meso view renders: each renderer gets its own copy of the scene's top level
 * (camera, lights, object structs with their technique_options), so the viewer can move the
 * camera and light of the live renderer, give each technique its switches and main option,
 * and hand the background reference a view of its own, while meshes, height fields, solids
 * and textures stay shared (read-only) with the loaded scene. And: writing the current
 * camera and light back as a scene file.
 */
#ifndef MESO_APP_VIEW_SCENE_H
#define MESO_APP_VIEW_SCENE_H

#include "app.h"
#include "view_state.h"

typedef struct view_scene {
    meso_scene scene;     /* shallow copy of the source; objects points to `objects` */
    meso_object *objects; /* own copies of the object structs */
    const meso_scene *source;
} view_scene;

/* A copy of `source` to render with `technique`: each object keeps its own technique_options
 * only when `technique` is its own (another technique would reject them), then gets the
 * state's switches and main option for the technique (view_technique_knobs_find); camera and
 * light from the state. state may be NULL (the source's options, camera and light). The
 * source must outlive the copy. */
meso_result view_scene_create(meso_context *ctx, const meso_scene *source, const char *technique,
                              const view_state *state, view_scene **out_scene);
void view_scene_destroy(view_scene *scene);

/* Set the copy's camera and first light (when directional) from the state. */
void view_scene_set_view(view_scene *scene, const view_state *state);

/* The scene's value of a technique's switch or option for the viewer's initial state: the
 * first object's option when `technique` is its own, else `fallback`. */
double view_scene_initial_option(const meso_scene *scene, const char *technique, const char *name,
                                 double fallback);

/* Write the scene file `source_path` again to `out_path` (atomically) with its top-level
 * "camera" replaced by `camera` and the "direction" of its first light by `light_direction`
 * (NULL: left as it is). Everything else is kept as written, so relative paths still hold
 * when out_path is in the same folder. MESO_ERROR_IO / MESO_ERROR_FORMAT (logged) otherwise. */
meso_result view_scene_save(meso_context *ctx, const char *source_path, const meso_camera *camera,
                            const meso_vec3 *light_direction, const char *out_path);

#endif
