/* meso geometry: triangle meshes, built-in shapes, import, validation, tangent frames,
 * curvature and quadric fits.
 *
 * Meshes are plain data (meso_mesh) owned by one meso_mesh_create_* / meso_mesh_load call and
 * released by meso_mesh_destroy. Every array has num_vertices entries (indices: 3 per
 * triangle); optional arrays are NULL until computed.
 *
 * Conventions (docs/design.md)
 *   Texture space is OpenGL's. tangents[i] = dP/du and bitangents[i] = dP/dv at vertex i, with
 *   their magnitudes (world units per unit of u or v), made orthogonal to the vertex normal;
 *   T x B points along N for unmirrored UVs. Normals are unit and outward.
 *   Curvature is positive where the surface is convex (a sphere of radius R: k = 1/R).
 *   The quadric of a vertex describes the surface near it in its tangent frame, with x along
 *   normalize(T), y along normalize(B) (world units) and depth measured inward along -N:
 *   depth(x, y) = a x^2 + b y^2, so a sphere of radius R has a = b = 1/(2R) and a plane 0.
 *
 * Threads: functions on different meshes may run at once; none is safe on one mesh from two
 * threads if either writes.
 */
#ifndef MESO_GEOM_H
#define MESO_GEOM_H

#include "meso/core.h"
#include "meso/math.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Limits, checked before allocating (imports and tessellations alike). */
#define MESO_MESH_MAX_VERTICES (1u << 26)
#define MESO_MESH_MAX_TRIANGLES (1u << 26)

/* The peak memory of a mesh of these counts through a scene's preparation (positions,
 * normals, UVs, indices, tangents, curvature, quadrics and the temporaries that build them):
 * 150 bytes a vertex and 70 a triangle, measured on subdivided planes (a 2048-segment plane,
 * 4.2 M vertices, peaks at 1.19 GB). Used for the memory budget (meso_memory_check); meshes
 * whose estimate exceeds the context's limit are refused before they are allocated. Pure. */
uint64_t meso_mesh_memory_estimate(uint64_t num_vertices, uint64_t num_triangles);

typedef struct meso_mesh {
    size_t num_vertices;
    size_t num_triangles;
    meso_vec3 *positions;
    meso_vec3 *normals;    /* unit, outward */
    meso_vec2 *uvs;        /* NULL when the mesh has no texture coordinates */
    meso_vec3 *tangents;   /* dP/du (see above); NULL until meso_mesh_compute_tangents */
    meso_vec3 *bitangents; /* dP/dv; NULL until meso_mesh_compute_tangents */
    uint32_t *indices;     /* 3 * num_triangles, counter-clockwise seen from outside */

    /* meso_mesh_compute_curvature: principal curvatures (k_max >= k_min) and their unit
     * directions in the tangent plane, world space. */
    float *curvature_max;
    float *curvature_min;
    meso_vec3 *curvature_dir_max;
    meso_vec3 *curvature_dir_min;

    /* meso_mesh_compute_quadrics: (a, b) per vertex, see the conventions above. */
    meso_vec2 *quadrics;
} meso_mesh;

typedef enum meso_shape_kind {
    MESO_SHAPE_DEFAULT = 0, /* plane */
    MESO_SHAPE_PLANE,
    MESO_SHAPE_SPHERE,
    MESO_SHAPE_TORUS,
    MESO_SHAPE_CYLINDER,
    MESO_SHAPE_VASE,
    MESO_SHAPE_TEAPOT,
} meso_shape_kind;

/* Zero fields take the defaults of meso_shape_desc_defaults(). */
typedef struct meso_shape_desc {
    meso_shape_kind kind;
    float size;         /* plane: side (2); sphere: radius (1); torus: major radius (1);
                           cylinder: radius (0.6); vase: height (2); teapot: height (1.5) */
    float minor_radius; /* torus tube radius (0.4 x size) */
    float height;       /* cylinder height (2 x size) */
    int segments;       /* tessellation: plane 1 quad per side cell (1); round shapes: segments
                           around (96); teapot: per patch side (16) */
} meso_shape_desc;

/* The desc with every zero field replaced by its default for desc->kind. Pure. */
meso_shape_desc meso_shape_desc_defaults(const meso_shape_desc *desc);
/* The kind named `name` ("plane", "sphere", ...); false when unknown. */
bool meso_shape_kind_from_name(const char *name, meso_shape_kind *out_kind);
const char *meso_shape_kind_name(meso_shape_kind kind);

/* A built-in shape with normals, UVs suited to tiling and tangents, centred at the origin.
 * plane: y = 0, normal +y, P(u,v) = (-s/2 + u s, 0, s/2 - v s). */
/* The memory a built-in shape will need through a scene's preparation
 * (meso_mesh_memory_estimate of its vertex and triangle counts, an upper bound), computed
 * without building it. Pure. */
uint64_t meso_shape_memory_estimate(const meso_shape_desc *desc);
meso_result meso_mesh_create_shape(meso_context *ctx, const meso_shape_desc *desc,
                                   meso_mesh **out_mesh);

/* Import OBJ / PLY / glTF (assimp), all meshes of the file joined, triangulated, normals
 * generated when missing. The first UV channel is kept (NULL when the file has none).
 * Errors name the file: MESO_ERROR_IO, MESO_ERROR_FORMAT, MESO_ERROR_LIMIT. The result has
 * passed meso_mesh_validate(require_uvs = false) under the file's name. */
meso_result meso_mesh_load(meso_context *ctx, const char *path, meso_mesh **out_mesh);

#define MESO_MESH_MATERIAL_PATH_MAX 512

/* The material of an imported mesh: of its first triangle mesh's material (a file whose
 * meshes use several has the others listed in `ignored`). Colours are as the file gives them
 * (glTF's baseColorFactor is linear; MTL's Kd is taken as linear). Paths are as written in
 * the file, relative to its folder; "" when absent. */
typedef struct meso_mesh_material {
    bool has_color; /* glTF baseColorFactor, MTL Kd */
    meso_vec3 color;
    char color_map[MESO_MESH_MATERIAL_PATH_MAX];  /* glTF baseColorTexture, MTL map_Kd */
    char normal_map[MESO_MESH_MATERIAL_PATH_MAX]; /* glTF normalTexture, MTL norm */
    char ignored[512]; /* what the file holds that meso does not use, comma-separated, or "" */
} meso_mesh_material;

/* Why a scene does not use the mesh file's texture `texture` (the color_map or normal_map of
 * its material): "not beside the mesh file" for an absolute path or one through "..", the rule
 * of a glTF's buffers. NULL when a scene uses it (unless its own material sets that map; a
 * mesh without usable UVs gets projected ones, docs/scene-format.md). The scene loader and
 * `meso info MODEL` both ask it, so they say the same. Pure. */
const char *meso_mesh_material_unused_reason(const char *texture);

/* meso_mesh_load, and the mesh's material in *out_material (zeroed when the file has none:
 * assimp's default material of an OBJ without MTL or of a PLY is "none"). */
meso_result meso_mesh_load_with_material(meso_context *ctx, const char *path, meso_mesh **out_mesh,
                                         meso_mesh_material *out_material);

/* An empty mesh with the given counts; positions, normals, indices allocated (zeroed), uvs too
 * when with_uvs. For generators and importers. */
meso_result meso_mesh_create(meso_context *ctx, size_t num_vertices, size_t num_triangles,
                             bool with_uvs, meso_mesh **out_mesh);
meso_result meso_mesh_clone(meso_context *ctx, const meso_mesh *mesh, meso_mesh **out_mesh);
void meso_mesh_destroy(meso_mesh *mesh);

/* Check a mesh for use: NaN/Inf positions, normals or UVs and out-of-range indices are errors
 * (MESO_ERROR_FORMAT, naming `name` and the vertex); degenerate (zero-area) triangles are
 * dropped with a warning; require_uvs and no UVs is an error that says the mesostructure
 * needs texture coordinates. Zero-length normals are rebuilt from the triangles around their
 * position; other normals are made unit. */
meso_result meso_mesh_validate(meso_context *ctx, meso_mesh *mesh, const char *name,
                               bool require_uvs);

/* Apply an affine transform to positions (and normals by its normal matrix, renormalised);
 * derived arrays (tangents, curvature, quadrics) are freed: recompute them afterwards. A
 * mirroring transform (negative determinant) also reverses every triangle's corner order, so
 * triangles stay counter-clockwise seen from outside. */
void meso_mesh_transform(meso_mesh *mesh, meso_mat4 transform);
/* Multiply the UVs by (su, sv); derived arrays are freed. */
void meso_mesh_scale_uvs(meso_mesh *mesh, meso_vec2 scale);

/* Per-vertex dP/du, dP/dv from the triangles' UV gradients, averaged and orthogonalised
 * against the normal (Gram-Schmidt), keeping magnitudes. Needs UVs (MESO_ERROR_INVALID_ARGUMENT
 * otherwise). */
meso_result meso_mesh_compute_tangents(meso_context *ctx, meso_mesh *mesh);
/* Per-vertex principal curvatures and directions (least-squares fit of the shape operator from
 * the one-ring's normals, Rusinkiewicz 2004). */
meso_result meso_mesh_compute_curvature(meso_context *ctx, meso_mesh *mesh);
/* Per-vertex quadric (a, b) by least squares over the one-ring's positions in the tangent
 * frame (Oliveira & Policarpo 2005). Needs tangents. */
meso_result meso_mesh_compute_quadrics(meso_context *ctx, meso_mesh *mesh);

/* ---- Projected texture coordinates (docs/shapes.md, "Projected texture coordinates") ---- */

typedef enum meso_uv_projection_kind {
    MESO_UV_PROJECTION_NONE = 0,
    MESO_UV_PROJECTION_BOX,         /* each triangle on the plane of its dominant normal axis */
    MESO_UV_PROJECTION_CYLINDRICAL, /* u around the axis, v along it */
    MESO_UV_PROJECTION_SPHERICAL,   /* u longitude around the axis, v latitude */
    MESO_UV_PROJECTION_PLANAR,      /* u, v in the plane across the axis */
} meso_uv_projection_kind;

typedef struct meso_uv_projection {
    meso_uv_projection_kind kind;
    float scale; /* mesh units per tile, > 0 (cylindrical and spherical round it so that a
                    whole number of tiles goes around the mean radius) */
    int axis;    /* 0 x, 1 y, 2 z: the cylinder's or sphere's axis, the plane's normal; box:
                    unused */
} meso_uv_projection;

/* The kind named `name` ("box", "cylindrical", "spherical", "planar"); false when unknown. */
bool meso_uv_projection_kind_from_name(const char *name, meso_uv_projection_kind *out_kind);
const char *meso_uv_projection_kind_name(meso_uv_projection_kind kind);

/* Replace the mesh's UVs (adding them when it has none) by a projection of its positions
 * around the centre of its bounds. Each triangle's corners are projected together, so its
 * coordinates are continuous inside it; a vertex that its triangles give different coordinates
 * (box chart borders, the cylinder's and sphere's seam, the poles) is split into one vertex per
 * coordinate with the same position and normal. Vertices no triangle uses are dropped. Derived
 * arrays are freed (compute the tangents after). MESO_ERROR_INVALID_ARGUMENT for a bad
 * projection, MESO_ERROR_LIMIT when the split vertices would exceed the limit. */
meso_result meso_mesh_project_uvs(meso_context *ctx, meso_mesh *mesh,
                                  const meso_uv_projection *projection);

/* The triangles whose UV Jacobian is degenerate (UV edges parallel within a sine of 1e-7, or
 * of zero length: the triangles the tangent code cannot use), and the fraction of the mesh's
 * world area they cover (0 without UVs). Pure. */
/* A scene treats a mesh whose degenerate UV triangles cover more than this fraction of its
 * area as having none (and projects them): most of it would show one texel smeared across each
 * triangle, which no technique can make into a mesostructure. Below it the coordinates are
 * kept and the count reported. */
#define MESO_MESH_MOSTLY_DEGENERATE_UVS 0.5
void meso_mesh_degenerate_uvs(const meso_mesh *mesh, size_t *out_count, double *out_area_fraction);

/* World length of one texture tile: sqrt(world area / uv area) over the mesh (uv_scale
 * applied); 0 without UVs or area. VDM §3.2 asks for a locally uniform texture scale; this is
 * its average. Pure. */
float meso_mesh_tile_length(const meso_mesh *mesh);

/* Axis-aligned bounds of the positions. */
void meso_mesh_bounds(const meso_mesh *mesh, meso_vec3 *out_min, meso_vec3 *out_max);

/* The mesh's open borders: bit e of entry t is set when edge e of triangle t (vertex e to
 * e + 1) belongs to no other triangle. Edges pair by their end points' positions (their
 * bits), so a texture seam's duplicated vertices close the seam. A new array of
 * num_triangles bytes (at least one) owned by the caller (free); NULL when out of memory.
 * Pure; thread-safe. */
uint8_t *meso_mesh_open_border_edges(const meso_mesh *mesh);

/* The texture domain's open sides: where every open border of a mesh lies on a side of its UV
 * bounding box and no edge two triangles share lies on that side (a plane's four sides, a
 * tube's two ends; not a teapot's patch borders), a ray that leaves the box through such a
 * side has left the shell -- the mesostructure ends at the border and the true surface
 * has nothing past it -- so the per-pixel techniques count a hit past it as a miss, not as the
 * next tile of a repeating map. A mesh with an open border elsewhere gets sides 0 (no check):
 * its borders need the shell's own sides (docs/techniques/relief.md, "Open borders"). */
typedef struct meso_uv_domain {
    unsigned sides; /* MESO_UV_DOMAIN_* bits of the box's sides that are open borders */
    float u_min, u_max, v_min, v_max;
} meso_uv_domain;

enum {
    MESO_UV_DOMAIN_U_MIN = 1u << 0,
    MESO_UV_DOMAIN_U_MAX = 1u << 1,
    MESO_UV_DOMAIN_V_MIN = 1u << 2,
    MESO_UV_DOMAIN_V_MAX = 1u << 3,
};

/* Fill *out (sides 0 without UVs or open borders). False only when out of memory. Pure;
 * thread-safe. */
bool meso_mesh_uv_domain(const meso_mesh *mesh, meso_uv_domain *out);

#ifdef __cplusplus
}
#endif
#endif
