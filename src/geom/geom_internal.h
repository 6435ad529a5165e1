/* Private helpers of the geom module: limits, derived-array bookkeeping, adjacency. */
#ifndef MESO_GEOM_INTERNAL_H
#define MESO_GEOM_INTERNAL_H

#include "meso/geom.h"

/* Refuse counts over MESO_MESH_MAX_* with MESO_ERROR_LIMIT naming `name`; call before
 * allocating anything sized by them. Counts are 64-bit so that sums cannot wrap first. */
meso_result geom_check_counts(meso_context *ctx, const char *name, uint64_t num_vertices,
                              uint64_t num_triangles);

/* What the screen recognised a mesh file as (by content, glTF JSON and OBJ by extension). */
typedef enum geom_mesh_kind {
    GEOM_MESH_OTHER = 0,
    GEOM_MESH_PLY,
    GEOM_MESH_GLTF, /* JSON or GLB: its buffers may be files beside it */
    GEOM_MESH_OBJ,
} geom_mesh_kind;

/* Check a mesh file's declared sizes against its real size before assimp reads it (PLY
 * element counts and ASCII values, glTF buffers, views and accessors, GLB chunks) and that
 * the files it names (glTF buffers, OBJ material libraries) are files beside it
 * (geom_screen.c). `file` is open at any position. MESO_OK, or MESO_ERROR_FORMAT / _LIMIT /
 * _IO logged naming the file; *out_kind says what the file is. */
meso_result geom_screen_mesh_file(meso_context *ctx, const char *path, FILE *file,
                                  geom_mesh_kind *out_kind);

/* A file a mesh names (glTF buffer URI, OBJ mtllib) may be read only when it lies beside the
 * mesh or below its folder: relative, no "..", no scheme (':'), no backslash, no
 * percent-escaped '.' or '/'. */
bool geom_name_is_beside(const char *name);
/* `name` resolved against the folder of `path` into out; false when it does not fit. */
bool geom_resolve_beside(const char *path, const char *name, char *out, size_t out_size);

/* assimp's error message as a reason: its first line only (it may quote lines of the file),
 * cut to out_size with " ..." when anything was left out. */
void geom_import_reason(const char *message, char *out, size_t out_size);

/* Add `what` to the material's list of what the file holds that meso does not use. */
void geom_material_ignore(meso_mesh_material *m, const char *what);

/* MTL files larger than this are refused (real libraries are kilobytes). */
#define GEOM_MTL_MAX_BYTES (16u << 20)

/* The material `name` (a `usemtl` name) from the material libraries the OBJ at `path` (open
 * as `obj`) names, read by meso's own MTL reader (geom_mtl.c); zeroed when no library defines
 * it. MESO_OK, or the error of a library that cannot be read (logged). */
meso_result geom_obj_read_material(meso_context *ctx, const char *path, FILE *obj, const char *name,
                                   meso_mesh_material *out);

/* Free (and NULL) tangents, bitangents, curvature and quadrics: the arrays that depend on the
 * positions, normals or UVs. */
void geom_mesh_free_derived(meso_mesh *mesh);

/* Twice the area of triangle t (|(p1 - p0) x (p2 - p0)|), in double. */
double geom_triangle_double_area(const meso_mesh *mesh, size_t t);

/* Vertex -> incident triangles as compressed rows: the triangles of vertex v are
 * faces[offsets[v] .. offsets[v + 1]), ascending (so gathers run in a fixed order). */
typedef struct geom_vertex_faces {
    size_t *offsets; /* num_vertices + 1 */
    uint32_t *faces; /* 3 * num_triangles */
} geom_vertex_faces;

meso_result geom_vertex_faces_build(meso_context *ctx, const meso_mesh *mesh,
                                    geom_vertex_faces *out);
void geom_vertex_faces_free(geom_vertex_faces *vf);

/* Vertices at bit-identical positions (texture seams, patch borders, duplicated poles) form
 * one group, so neighbourhood queries see across seams. Members of a group are
 * members[offsets[g] .. offsets[g + 1]), ascending. */
typedef struct geom_weld {
    uint32_t *group;   /* num_vertices: the group of each vertex */
    size_t *offsets;   /* num_groups + 1 */
    uint32_t *members; /* num_vertices */
    size_t num_groups;
} geom_weld;

meso_result geom_weld_build(meso_context *ctx, const meso_mesh *mesh, geom_weld *out);
void geom_weld_free(geom_weld *weld);

/* Any unit vector orthogonal to the unit vector n (deterministic; Frisvad-style branchless
 * basis, Duff et al. 2017). */
meso_vec3 geom_any_perpendicular(meso_vec3 n);

/* UV triangles whose (signed) area is below this fraction of the product of their UV edge
 * lengths have no usable Jacobian: the UV edges are (nearly) parallel, or one has zero length
 * (every corner at one coordinate included). The tangent code skips them; a mesh that has
 * them over most of its area is treated as having no UVs (docs/shapes.md). */
#define GEOM_DEGENERATE_UV_SINE 1e-7

/* Whether UV edges (du1, dv1), (du2, dv2) are degenerate by the test above. */
bool geom_uv_edges_are_degenerate(double du1, double dv1, double du2, double dv2);
/* The same for the triangle of corner coordinates t0, t1, t2. */
bool geom_uv_jacobian_is_degenerate(meso_vec2 t0, meso_vec2 t1, meso_vec2 t2);

/* The teapot (geom_teapot.c): desc already defaulted and checked. */
meso_result geom_create_teapot(meso_context *ctx, const meso_shape_desc *desc,
                               meso_mesh **out_mesh);

#endif
