/* An object's texture coordinates: the mesh's own, or a projection of its positions
 * ("uv_projection", docs/scene-format.md) when asked for, when the mesh has none but needs them,
 * or when its own are degenerate over most of its area (docs/shapes.md, "Projected texture
 * coordinates"). Decided once here, on the mesh in its own coordinates, so that every
 * technique, the reference and the GL back end read the same coordinates from the mesh. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "scene_internal.h"
#include "meso/runtime.h"

/* The default tile when "uv_projection_scale" is absent: a quarter of the mesh's largest
 * bounding-box side, so that about four tiles cross the object whatever units its file uses. */
#define DEFAULT_TILES_ACROSS 4.0f

static const char *base_name(const char *path) {
    const char *slash = strrchr(path, '/');
    return slash ? slash + 1 : path;
}

static meso_result parse_projection(const scene_parser *p, const cJSON *obj, const scene_key *key,
                                    meso_uv_projection *out, float *out_world_scale) {
    const char *kind = NULL, *axis = NULL;
    meso_result r;
    *out_world_scale = 0.0f;
    if ((r = scene_get_string(p, obj, key, "uv_projection", false, &kind)) ||
        (r = scene_get_positive(p, obj, key, "uv_projection_scale", false, false,
                                out_world_scale)) ||
        (r = scene_get_string(p, obj, key, "uv_projection_axis", false, &axis)))
        return r;
    out->kind = MESO_UV_PROJECTION_NONE;
    out->axis = 1;
    if (!kind) {
        const char *stray = *out_world_scale > 0.0f ? "uv_projection_scale"
                            : axis                  ? "uv_projection_axis"
                                                    : NULL;
        if (!stray) return MESO_OK;
        scene_key k = scene_key_child(key, stray);
        return scene_error(p, MESO_ERROR_FORMAT, &k, "applies with \"uv_projection\" only");
    }
    scene_key kind_key = scene_key_child(key, "uv_projection");
    if (!meso_uv_projection_kind_from_name(kind, &out->kind))
        return scene_error(
            p, MESO_ERROR_FORMAT, &kind_key,
            "must be \"box\", \"cylindrical\", \"spherical\" or \"planar\", not \"%s\"", kind);
    if (axis) {
        scene_key k = scene_key_child(key, "uv_projection_axis");
        if (out->kind == MESO_UV_PROJECTION_BOX)
            return scene_error(p, MESO_ERROR_FORMAT, &k,
                               "does not apply to \"box\" (it projects along all three axes)");
        if (strlen(axis) != 1 || !strchr("xyz", axis[0]))
            return scene_error(p, MESO_ERROR_FORMAT, &k,
                               "must be \"x\", \"y\" or \"z\", not \"%s\"", axis);
        out->axis = axis[0] - 'x';
    }
    return MESO_OK;
}

meso_result scene_texture_coordinates(const scene_parser *p, const cJSON *obj, const scene_key *key,
                                      const char *mesh_file, bool needs_uvs,
                                      float world_per_mesh_unit, meso_object *object) {
    meso_uv_projection projection;
    float world_scale;
    meso_result r = parse_projection(p, obj, key, &projection, &world_scale);
    if (r != MESO_OK) return r;
    meso_mesh *mesh = object->mesh;
    const char *owner = mesh_file[0] ? "the file's" : "the shape's";
    char *out = object->texture_coordinates;
    size_t out_size = sizeof object->texture_coordinates;
    char why[160] = "asked for";
    size_t degenerate = 0;
    double degenerate_area = 0.0;
    meso_mesh_degenerate_uvs(mesh, &degenerate, &degenerate_area);
    if (projection.kind == MESO_UV_PROJECTION_NONE) {
        if (mesh->uvs && degenerate_area <= MESO_MESH_MOSTLY_DEGENERATE_UVS) {
            if (degenerate)
                meso_log_warning(p->ctx,
                                 "%s: %s: %zu of %zu triangles (%.1f %% of the area) have "
                                 "degenerate texture coordinates; the mesostructure is smeared "
                                 "across them",
                                 p->file, key->text, degenerate, mesh->num_triangles,
                                 100.0 * degenerate_area);
            snprintf(out, out_size, "%s", owner);
            if (degenerate)
                snprintf(out + strlen(out), out_size - strlen(out),
                         " (degenerate on %zu of %zu triangles)", degenerate, mesh->num_triangles);
            return MESO_OK;
        }
        if (!mesh->uvs && !needs_uvs) {
            snprintf(out, out_size, "none");
            return MESO_OK;
        }
        /* None, or degenerate almost everywhere: the box, which maps any shape with at most
         * sqrt(3) stretch (docs/shapes.md), rather than a refusal or an unmapped image. */
        projection.kind = MESO_UV_PROJECTION_BOX;
        if (mesh->uvs)
            snprintf(why, sizeof why, "%s are degenerate on %zu of %zu triangles", owner,
                     degenerate, mesh->num_triangles);
        else
            snprintf(why, sizeof why, "%s has none", mesh_file[0] ? "the file" : "the shape");
    }
    meso_vec3 lo, hi;
    meso_mesh_bounds(mesh, &lo, &hi);
    float largest = fmaxf(hi.x - lo.x, fmaxf(hi.y - lo.y, hi.z - lo.z));
    if (world_scale > 0.0f) {
        projection.scale = world_scale / world_per_mesh_unit;
    } else {
        projection.scale = largest / DEFAULT_TILES_ACROSS;
        world_scale = projection.scale * world_per_mesh_unit;
    }
    if (!(projection.scale > 0.0f) || !isfinite(projection.scale))
        return scene_error(p, MESO_ERROR_FORMAT, key,
                           "cannot project texture coordinates on a mesh of no extent");
    if (strcmp(why, "asked for") != 0)
        meso_log_warning(p->ctx,
                         "%s: %s: %s: %s; using \"uv_projection\": \"box\", %g world units a "
                         "tile (set \"uv_projection\" to choose)",
                         p->file, key->text, mesh_file[0] ? base_name(mesh_file) : "shape", why,
                         (double)world_scale);
    size_t vertices_before = mesh->num_vertices;
    r = meso_mesh_project_uvs(p->ctx, mesh, &projection);
    if (r != MESO_OK) return scene_relog_at_key(p, key, r);
    /* The split vertices count against the memory budget like the file's own. */
    if (mesh->num_vertices > vertices_before &&
        (r = scene_account_memory(
             p, key, meso_mesh_memory_estimate(mesh->num_vertices - vertices_before, 0))) !=
            MESO_OK)
        return r;
    static const char *const axis_names[] = {" along x", " along y", " along z"};
    snprintf(out, out_size, "%s projection%s, %g world units a tile (%s)",
             meso_uv_projection_kind_name(projection.kind),
             projection.kind == MESO_UV_PROJECTION_BOX ? "" : axis_names[projection.axis],
             (double)world_scale, why);
    /* Planar faces seen edge-on, cylinder caps: report what the projection left degenerate. */
    meso_mesh_degenerate_uvs(mesh, &degenerate, &degenerate_area);
    if (degenerate) {
        meso_log_warning(p->ctx,
                         "%s: %s: the %s projection leaves %zu of %zu triangles (%.1f %% of the "
                         "area) with degenerate texture coordinates (faces it sees edge-on); the "
                         "mesostructure is smeared across them",
                         p->file, key->text, meso_uv_projection_kind_name(projection.kind),
                         degenerate, mesh->num_triangles, 100.0 * degenerate_area);
        snprintf(out + strlen(out), out_size - strlen(out), ", degenerate on %zu of %zu triangles",
                 degenerate, mesh->num_triangles);
    }
    return MESO_OK;
}
