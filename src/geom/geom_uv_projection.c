/* Projected texture coordinates for meshes that have none (or only degenerate ones): box,
 * cylindrical, spherical and planar projections, and the test that finds degenerate UV
 * triangles (docs/shapes.md, "Projected texture coordinates").
 *
 * Every projection is computed per triangle corner, so a triangle always gets coordinates that
 * are continuous inside it (a box chart, a cylinder unwrapped across its seam, a pole vertex
 * taking its neighbours' longitude); a vertex whose triangles give it different coordinates is
 * then split into one vertex per distinct coordinate (same position and normal), which is how
 * the built-in shapes carry their seams too.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geom_internal.h"
#include "meso/runtime.h"

static const char *const projection_names[] = {"none", "box", "cylindrical", "spherical", "planar"};

bool meso_uv_projection_kind_from_name(const char *name, meso_uv_projection_kind *out_kind) {
    for (int k = MESO_UV_PROJECTION_BOX; k <= MESO_UV_PROJECTION_PLANAR; k++)
        if (strcmp(name, projection_names[k]) == 0) {
            *out_kind = (meso_uv_projection_kind)k;
            return true;
        }
    return false;
}

const char *meso_uv_projection_kind_name(meso_uv_projection_kind kind) {
    return kind >= MESO_UV_PROJECTION_NONE && kind <= MESO_UV_PROJECTION_PLANAR
               ? projection_names[kind]
               : "unknown";
}

bool geom_uv_edges_are_degenerate(double du1, double dv1, double du2, double dv2) {
    double det = du1 * dv2 - du2 * dv1;
    double scale = hypot(du1, dv1) * hypot(du2, dv2);
    return !(fabs(det) > GEOM_DEGENERATE_UV_SINE * scale);
}

bool geom_uv_jacobian_is_degenerate(meso_vec2 t0, meso_vec2 t1, meso_vec2 t2) {
    return geom_uv_edges_are_degenerate((double)t1.x - t0.x, (double)t1.y - t0.y,
                                        (double)t2.x - t0.x, (double)t2.y - t0.y);
}

void meso_mesh_degenerate_uvs(const meso_mesh *mesh, size_t *out_count, double *out_area_fraction) {
    size_t count = 0;
    double degenerate_area = 0.0, total_area = 0.0;
    for (size_t t = 0; mesh->uvs && t < mesh->num_triangles; t++) {
        const uint32_t *tri = mesh->indices + 3 * t;
        double area = geom_triangle_double_area(mesh, t);
        total_area += area;
        if (!geom_uv_jacobian_is_degenerate(mesh->uvs[tri[0]], mesh->uvs[tri[1]],
                                            mesh->uvs[tri[2]]))
            continue;
        count++;
        degenerate_area += area;
    }
    *out_count = count;
    *out_area_fraction = total_area > 0.0 ? degenerate_area / total_area : 0.0;
}

/* ---- The projections ---------------------------------------------------------------------- */

/* Coordinates relative to the centre of the bounds, turned by a cyclic permutation (a
 * rotation) so that the projection's axis becomes y: axis y keeps (x, y, z), x gives
 * (z, x, y), z gives (y, z, x). The built-in round shapes' convention then holds around any
 * axis: longitude 0 faces +z', u grows toward +x', v grows along +y'. */
static meso_vec3 to_axis_frame(meso_vec3 p, meso_vec3 centre, int axis) {
    meso_vec3 d = meso_vec3_sub(p, centre);
    if (axis == 0) return (meso_vec3){d.z, d.x, d.y};
    if (axis == 2) return (meso_vec3){d.y, d.z, d.x};
    return d;
}

typedef struct projector {
    const meso_mesh *mesh;
    meso_uv_projection_kind kind;
    int axis;
    meso_vec3 centre;
    float inv_scale;     /* tiles per mesh unit */
    double tiles_around; /* cylindrical, spherical: whole tiles around the axis */
    double tiles_pole;   /* spherical: whole tiles from pole to pole */
} projector;

/* Box: the chart of the triangle's dominant face-normal axis and sign, oriented like the faces
 * of a cube map seen from outside, so that T x B points along the face normal (no chart is
 * mirrored): +x (-z, y), -x (z, y), +y (x, -z), -y (x, z), +z (x, y), -z (-x, y). */
static int box_chart(meso_vec3 face_normal) {
    float ax = fabsf(face_normal.x), ay = fabsf(face_normal.y), az = fabsf(face_normal.z);
    int axis = ax >= ay && ax >= az ? 0 : ay >= az ? 1 : 2;
    float component = axis == 0 ? face_normal.x : axis == 1 ? face_normal.y : face_normal.z;
    return 2 * axis + (component < 0.0f);
}

static meso_vec2 box_uv(meso_vec3 d, int chart) {
    switch (chart) {
    case 0:
        return (meso_vec2){-d.z, d.y};
    case 1:
        return (meso_vec2){d.z, d.y};
    case 2:
        return (meso_vec2){d.x, -d.z};
    case 3:
        return (meso_vec2){d.x, d.z};
    case 4:
        return (meso_vec2){d.x, d.y};
    default:
        return (meso_vec2){-d.x, d.y};
    }
}

/* Longitude in turns, in (-1/2, 1/2], 0 facing +z' (the built-in sphere's u = 1/2); NAN on the
 * axis, where it is undefined. */
static double longitude_turns(meso_vec3 q, double on_axis) {
    if (hypot(q.x, q.z) <= on_axis) return NAN;
    return atan2(q.x, q.z) / (2.0 * MESO_PI);
}

/* The three corners' coordinates of triangle t, and its chart (box: 0..5, +x -x +y -y +z -z;
 * the other projections have one). */
static int project_triangle(const projector *pr, size_t t, meso_vec2 out[3]) {
    const meso_mesh *mesh = pr->mesh;
    const uint32_t *tri = mesh->indices + 3 * t;
    meso_vec3 p[3];
    for (int k = 0; k < 3; k++) p[k] = mesh->positions[tri[k]];
    if (pr->kind == MESO_UV_PROJECTION_BOX) {
        meso_vec3 face = meso_vec3_cross(meso_vec3_sub(p[1], p[0]), meso_vec3_sub(p[2], p[0]));
        int chart = box_chart(face);
        for (int k = 0; k < 3; k++) {
            meso_vec2 uv = box_uv(meso_vec3_sub(p[k], pr->centre), chart);
            out[k] = (meso_vec2){uv.x * pr->inv_scale, uv.y * pr->inv_scale};
        }
        return chart;
    }
    meso_vec3 q[3];
    for (int k = 0; k < 3; k++) q[k] = to_axis_frame(p[k], pr->centre, pr->axis);
    if (pr->kind == MESO_UV_PROJECTION_PLANAR) {
        /* The +y chart of the box, around the chosen axis: the built-in plane's (x, -z). */
        for (int k = 0; k < 3; k++)
            out[k] = (meso_vec2){q[k].x * pr->inv_scale, -q[k].z * pr->inv_scale};
        return 0;
    }
    /* Cylindrical and spherical: longitude, unwrapped across the seam (the back, -z') so that
     * the corners lie within half a turn of each other; whole tiles around keep the heights
     * equal on both sides of the seam under repeat wrapping. A corner on the axis (a pole)
     * takes the mean longitude of the others. */
    double extent = fmax(fmax(fabs(q[0].x), fabs(q[0].z)), fmax(fabs(q[1].x), fabs(q[1].z)));
    extent = fmax(extent, fmax(fabs(q[2].x), fabs(q[2].z)));
    double turns[3], reference = NAN;
    for (int k = 0; k < 3; k++) {
        turns[k] = longitude_turns(q[k], 1e-6 * extent);
        if (isnan(turns[k])) continue;
        if (isnan(reference)) {
            reference = turns[k];
        } else {
            turns[k] -= floor(turns[k] - reference + 0.5); /* nearest copy to the reference */
        }
    }
    double sum = 0.0;
    int valid = 0;
    for (int k = 0; k < 3; k++)
        if (!isnan(turns[k])) sum += turns[k], valid++;
    double mean = valid ? sum / valid : 0.0;
    for (int k = 0; k < 3; k++) {
        double u = ((isnan(turns[k]) ? mean : turns[k]) + 0.5) * pr->tiles_around;
        double v;
        if (pr->kind == MESO_UV_PROJECTION_CYLINDRICAL) {
            v = q[k].y * pr->inv_scale;
        } else {
            double r =
                sqrt((double)q[k].x * q[k].x + (double)q[k].y * q[k].y + (double)q[k].z * q[k].z);
            double polar = r > 0.0 ? acos(fmax(-1.0, fmin(1.0, -q[k].y / r))) : 0.0;
            v = polar / MESO_PI * pr->tiles_pole; /* 0 at the south pole (-y'), as the sphere */
        }
        out[k] = (meso_vec2){(float)u, (float)v};
    }
    return 0;
}

/* Area-weighted mean distance of the triangles' centroids from the axis (cylindrical) or the
 * centre (spherical): the radius whose circumference is divided into whole tiles. */
static double mean_radius(const projector *pr) {
    const meso_mesh *mesh = pr->mesh;
    double sum = 0.0, weight = 0.0;
    for (size_t t = 0; t < mesh->num_triangles; t++) {
        const uint32_t *tri = mesh->indices + 3 * t;
        meso_vec3 c = {0, 0, 0};
        for (int k = 0; k < 3; k++)
            c = meso_vec3_add(c, to_axis_frame(mesh->positions[tri[k]], pr->centre, pr->axis));
        c = meso_vec3_scale(c, 1.0f / 3.0f);
        double r =
            pr->kind == MESO_UV_PROJECTION_CYLINDRICAL ? hypot(c.x, c.z) : meso_vec3_length(c);
        double area = geom_triangle_double_area(mesh, t);
        sum += area * r;
        weight += area;
    }
    return weight > 0.0 ? sum / weight : 0.0;
}

typedef struct corner_key {
    uint32_t vertex;
    uint32_t chart; /* a vertex is split between box charts even where their UVs meet: its
                       tangent frame would otherwise average two charts' directions */
    uint32_t u_bits, v_bits;
    uint32_t corner; /* 3 t + k */
} corner_key;

static int compare_corner_keys(const void *pa, const void *pb) {
    const corner_key *a = pa, *b = pb;
    if (a->vertex != b->vertex) return a->vertex < b->vertex ? -1 : 1;
    if (a->chart != b->chart) return a->chart < b->chart ? -1 : 1;
    if (a->u_bits != b->u_bits) return a->u_bits < b->u_bits ? -1 : 1;
    if (a->v_bits != b->v_bits) return a->v_bits < b->v_bits ? -1 : 1;
    return a->corner < b->corner ? -1 : (a->corner > b->corner);
}

static bool same_vertex(const corner_key *a, const corner_key *b) {
    return a->vertex == b->vertex && a->chart == b->chart && a->u_bits == b->u_bits &&
           a->v_bits == b->v_bits;
}

static uint32_t float_bits(float x) {
    x += 0.0f; /* -0 and +0 are one coordinate */
    uint32_t bits;
    memcpy(&bits, &x, sizeof bits);
    return bits;
}

meso_result meso_mesh_project_uvs(meso_context *ctx, meso_mesh *mesh,
                                  const meso_uv_projection *projection) {
    if (projection->kind < MESO_UV_PROJECTION_BOX || projection->kind > MESO_UV_PROJECTION_PLANAR ||
        !(projection->scale > 0.0f) || !isfinite(projection->scale) || projection->axis < 0 ||
        projection->axis > 2)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "mesh: uv projection: unknown kind, scale not positive or axis "
                              "not 0..2");
    size_t nt = mesh->num_triangles, corners = 3 * nt;
    /* Every corner may become a vertex of its own: checked before allocating. */
    meso_result r = geom_check_counts(ctx, "mesh", corners, nt);
    if (r != MESO_OK) return r;
    projector pr = {
        mesh, projection->kind, projection->axis, {0, 0, 0}, 1.0f / projection->scale, 1.0, 1.0};
    meso_vec3 lo, hi;
    meso_mesh_bounds(mesh, &lo, &hi);
    pr.centre = meso_vec3_scale(meso_vec3_add(lo, hi), 0.5f);
    if (pr.kind == MESO_UV_PROJECTION_CYLINDRICAL || pr.kind == MESO_UV_PROJECTION_SPHERICAL) {
        double radius = mean_radius(&pr);
        pr.tiles_around = fmax(1.0, round(2.0 * MESO_PI * radius * pr.inv_scale));
        pr.tiles_pole = fmax(1.0, round(MESO_PI * radius * pr.inv_scale));
    }

    meso_vec2 *corner_uvs = malloc((corners ? corners : 1) * sizeof(meso_vec2));
    corner_key *keys = malloc((corners ? corners : 1) * sizeof(corner_key));
    meso_vec3 *positions = NULL, *normals = NULL;
    meso_vec2 *uvs = NULL;
    if (!corner_uvs || !keys) goto out_of_memory;
    for (size_t t = 0; t < nt; t++) {
        uint32_t chart = (uint32_t)project_triangle(&pr, t, corner_uvs + 3 * t);
        for (size_t c = 3 * t; c < 3 * t + 3; c++)
            keys[c] = (corner_key){mesh->indices[c], chart, float_bits(corner_uvs[c].x),
                                   float_bits(corner_uvs[c].y), (uint32_t)c};
    }
    /* Sorted by (vertex, chart, u, v): vertices keep their order, and the copies of a split vertex
     * follow each other, so the result does not depend on anything but the mesh. */
    qsort(keys, corners, sizeof(corner_key), compare_corner_keys);
    size_t num_vertices = 0;
    for (size_t c = 0; c < corners; c++)
        num_vertices += c == 0 || !same_vertex(&keys[c], &keys[c - 1]);
    positions = malloc((num_vertices ? num_vertices : 1) * sizeof(meso_vec3));
    normals = malloc((num_vertices ? num_vertices : 1) * sizeof(meso_vec3));
    uvs = malloc((num_vertices ? num_vertices : 1) * sizeof(meso_vec2));
    if (!positions || !normals || !uvs) goto out_of_memory;
    size_t v = 0;
    for (size_t c = 0; c < corners; c++) {
        if (c > 0 && !same_vertex(&keys[c], &keys[c - 1])) v++;
        positions[v] = mesh->positions[keys[c].vertex];
        normals[v] = mesh->normals[keys[c].vertex];
        uvs[v] = corner_uvs[keys[c].corner];
        mesh->indices[keys[c].corner] = (uint32_t)v;
    }
    free(mesh->positions);
    free(mesh->normals);
    free(mesh->uvs);
    mesh->positions = positions;
    mesh->normals = normals;
    mesh->uvs = uvs;
    mesh->num_vertices = num_vertices;
    geom_mesh_free_derived(mesh);
    free(corner_uvs);
    free(keys);
    return MESO_OK;
out_of_memory:
    free(corner_uvs);
    free(keys);
    free(positions);
    free(normals);
    free(uvs);
    return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY,
                          "mesh: out of memory projecting texture coordinates on %zu triangles",
                          nt);
}
