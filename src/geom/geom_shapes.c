/* Built-in shapes: plane, sphere, torus, cylinder, vase (the teapot is in geom_teapot.c).
 *
 * Every round shape is a grid over (u, v) in [0,1]^2 with u around the y axis. Angles come
 * from per-column and per-row tables whose last entry repeats the first, so seam and pole
 * vertices are bit-identical copies and the surface is closed by position. The longitude
 * lambda = 2 pi (u - 1/2) puts the u seam at the back (-z), away from the default camera, and
 * makes dP/du point toward +x at the front, so T x B = N with B = dP/dv pointing "up" the
 * surface (docs/design.md: T x B along N for unmirrored UVs).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geom_internal.h"
#include "meso/runtime.h"

/* Tessellation bounds: enough for any use, small enough that the counts stay far below the
 * mesh limits, so the limit check never has to reject a shape a user could reasonably ask
 * for. */
#define MIN_ROUND_SEGMENTS 3
#define MAX_ROUND_SEGMENTS 4096
#define MAX_PLANE_SEGMENTS 4096
#define MAX_TEAPOT_SEGMENTS 256

static const char *const shape_names[] = {
    [MESO_SHAPE_DEFAULT] = "plane",     [MESO_SHAPE_PLANE] = "plane",
    [MESO_SHAPE_SPHERE] = "sphere",     [MESO_SHAPE_TORUS] = "torus",
    [MESO_SHAPE_CYLINDER] = "cylinder", [MESO_SHAPE_VASE] = "vase",
    [MESO_SHAPE_TEAPOT] = "teapot",
};
#define NUM_SHAPES (sizeof(shape_names) / sizeof(shape_names[0]))

const char *meso_shape_kind_name(meso_shape_kind kind) {
    if ((unsigned)kind >= NUM_SHAPES) return "unknown";
    return shape_names[kind];
}

bool meso_shape_kind_from_name(const char *name, meso_shape_kind *out_kind) {
    if (!name) return false;
    for (size_t k = MESO_SHAPE_PLANE; k < NUM_SHAPES; k++) {
        if (strcmp(name, shape_names[k]) == 0) {
            *out_kind = (meso_shape_kind)k;
            return true;
        }
    }
    return false;
}

meso_shape_desc meso_shape_desc_defaults(const meso_shape_desc *desc) {
    meso_shape_desc d = desc ? *desc : (meso_shape_desc){0};
    if (d.kind == MESO_SHAPE_DEFAULT) d.kind = MESO_SHAPE_PLANE;
    if (d.size == 0.0f) {
        switch (d.kind) {
        case MESO_SHAPE_PLANE:
            d.size = 2.0f;
            break;
        case MESO_SHAPE_SPHERE:
            d.size = 1.0f;
            break;
        case MESO_SHAPE_TORUS:
            d.size = 1.0f;
            break;
        case MESO_SHAPE_CYLINDER:
            d.size = 0.6f;
            break;
        case MESO_SHAPE_VASE:
            d.size = 2.0f;
            break;
        case MESO_SHAPE_TEAPOT:
            d.size = 1.5f;
            break;
        default:
            break;
        }
    }
    if (d.kind == MESO_SHAPE_TORUS && d.minor_radius == 0.0f) d.minor_radius = 0.4f * d.size;
    if (d.kind == MESO_SHAPE_CYLINDER && d.height == 0.0f) d.height = 2.0f * d.size;
    if (d.segments == 0) {
        switch (d.kind) {
        case MESO_SHAPE_PLANE:
            d.segments = 1;
            break;
        case MESO_SHAPE_TEAPOT:
            d.segments = 16;
            break;
        default:
            d.segments = 96;
            break;
        }
    }
    return d;
}

/* ---- The grid builder --------------------------------------------------------------------- */

/* Position and outward unit normal of grid vertex (i, j) at (u, v). In a pole row i counts
 * the cells and u is the cell's centre. */
typedef void (*grid_eval_fn)(const void *shape, int i, int j, double u, double v,
                             meso_vec3 *out_position, meso_vec3 *out_normal);

typedef struct grid_desc {
    const char *name;
    int nu, nv;                  /* cells around (u) and along (v) */
    bool south_pole, north_pole; /* row 0 / row nv collapses to one point */
    grid_eval_fn eval;
    const void *shape;
} grid_desc;

static bool is_pole_row(const grid_desc *g, int j) {
    return (j == 0 && g->south_pole) || (j == g->nv && g->north_pole);
}

static uint32_t row_start(const grid_desc *g, int j) {
    /* Pole rows hold nu vertices (one per cell, each with the cell's centre u, so the pole's
     * triangles have non-degenerate UVs); other rows nu + 1 (the seam column repeated). */
    uint32_t start = 0;
    for (int r = 0; r < j; r++) start += (uint32_t)(is_pole_row(g, r) ? g->nu : g->nu + 1);
    return start;
}

static meso_result build_grid(meso_context *ctx, const grid_desc *g, meso_mesh **out_mesh) {
    *out_mesh = NULL;
    uint64_t num_vertices = 0, num_triangles = 0;
    for (int j = 0; j <= g->nv; j++) num_vertices += is_pole_row(g, j) ? g->nu : g->nu + 1;
    for (int j = 0; j < g->nv; j++)
        num_triangles += (uint64_t)g->nu * ((is_pole_row(g, j) || is_pole_row(g, j + 1)) ? 1 : 2);
    meso_result r = geom_check_counts(ctx, g->name, num_vertices, num_triangles);
    if (r != MESO_OK) return r;
    meso_mesh *mesh = NULL;
    r = meso_mesh_create(ctx, (size_t)num_vertices, (size_t)num_triangles, true, &mesh);
    if (r != MESO_OK) return r;

    size_t vertex = 0;
    for (int j = 0; j <= g->nv; j++) {
        double v = (double)j / g->nv;
        bool pole = is_pole_row(g, j);
        int count = pole ? g->nu : g->nu + 1;
        for (int i = 0; i < count; i++) {
            double u = pole ? (i + 0.5) / g->nu : (double)i / g->nu;
            g->eval(g->shape, i, j, u, v, &mesh->positions[vertex], &mesh->normals[vertex]);
            mesh->uvs[vertex] = meso_vec2_make((float)u, (float)v);
            vertex++;
        }
    }

    /* Counter-clockwise in (u, v) is counter-clockwise seen from outside because T x B = N. */
    uint32_t *out = mesh->indices;
    for (int j = 0; j < g->nv; j++) {
        uint32_t lo = row_start(g, j), hi = row_start(g, j + 1);
        for (uint32_t i = 0; i < (uint32_t)g->nu; i++) {
            if (is_pole_row(g, j)) {
                *out++ = lo + i, *out++ = hi + i + 1, *out++ = hi + i;
            } else if (is_pole_row(g, j + 1)) {
                *out++ = lo + i, *out++ = lo + i + 1, *out++ = hi + i;
            } else {
                *out++ = lo + i, *out++ = lo + i + 1, *out++ = hi + i + 1;
                *out++ = lo + i, *out++ = hi + i + 1, *out++ = hi + i;
            }
        }
    }
    r = meso_mesh_compute_tangents(ctx, mesh);
    if (r != MESO_OK) {
        meso_mesh_destroy(mesh);
        return r;
    }
    *out_mesh = mesh;
    return MESO_OK;
}

/* cos and sin of 2 pi (k / n - 1/2) for k in [0, n], the last entry equal to the first. */
static meso_result make_angle_table(meso_context *ctx, int n, double **out_cos, double **out_sin) {
    *out_cos = malloc((size_t)(n + 1) * sizeof(double));
    *out_sin = malloc((size_t)(n + 1) * sizeof(double));
    if (!*out_cos || !*out_sin) {
        free(*out_cos);
        free(*out_sin);
        *out_cos = *out_sin = NULL;
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "shape: out of memory");
    }
    for (int k = 0; k < n; k++) {
        double angle = 2.0 * MESO_PI_D * ((double)k / n - 0.5);
        (*out_cos)[k] = cos(angle);
        (*out_sin)[k] = sin(angle);
    }
    (*out_cos)[n] = (*out_cos)[0];
    (*out_sin)[n] = (*out_sin)[0];
    return MESO_OK;
}

/* Around the y axis: radial direction (sin lambda, 0, cos lambda) for column i of a non-pole
 * row (pole rows never ask for it). */
static meso_vec3 radial(const double *cos_table, const double *sin_table, int i) {
    return meso_vec3_make((float)sin_table[i], 0.0f, (float)cos_table[i]);
}

/* ---- Plane -------------------------------------------------------------------------------- */

typedef struct plane_shape {
    double size;
} plane_shape;

static void eval_plane(const void *shape, int i, int j, double u, double v, meso_vec3 *p,
                       meso_vec3 *n) {
    const plane_shape *s = shape;
    /* docs/design.md: P(u,v) = (-s/2 + u s, 0, s/2 - v s), so the height map reads like the image
     * when seen from above with -z up. */
    *p = meso_vec3_make((float)(-0.5 * s->size + u * s->size), 0.0f,
                        (float)(0.5 * s->size - v * s->size));
    *n = meso_vec3_make(0.0f, 1.0f, 0.0f);
}

/* ---- Sphere ------------------------------------------------------------------------------- */

typedef struct sphere_shape {
    double radius;
    int nv;
    const double *cos_lon, *sin_lon;
} sphere_shape;

static void eval_sphere(const void *shape, int i, int j, double u, double v, meso_vec3 *p,
                        meso_vec3 *n) {
    const sphere_shape *s = shape;
    if (j == 0 || j == s->nv) {
        float y = j == 0 ? -1.0f : 1.0f;
        *n = meso_vec3_make(0.0f, y, 0.0f);
        *p = meso_vec3_make(0.0f, (float)(y * s->radius), 0.0f);
        return;
    }
    double latitude = MESO_PI_D * (v - 0.5);
    double c = cos(latitude), sy = sin(latitude);
    double nx = c * s->sin_lon[i], nz = c * s->cos_lon[i];
    *n = meso_vec3_normalize(meso_vec3_make((float)nx, (float)sy, (float)nz));
    *p = meso_vec3_make((float)(s->radius * nx), (float)(s->radius * sy), (float)(s->radius * nz));
}

/* ---- Torus -------------------------------------------------------------------------------- */

typedef struct torus_shape {
    double major, minor;
    const double *cos_lon, *sin_lon;
    const double *cos_tube, *sin_tube; /* psi = 2 pi (v - 1/2): v = 0 on the inner equator,
                                          1/2 on the outer one */
} torus_shape;

static void eval_torus(const void *shape, int i, int j, double u, double v, meso_vec3 *p,
                       meso_vec3 *n) {
    const torus_shape *s = shape;
    /* psi = 2 pi (v - 1/2) grows with v, so dP/dv runs inner equator -> bottom -> outer
     * equator -> top and T x B points out of the tube. */
    double cp = s->cos_tube[j], sp = s->sin_tube[j];
    double rad = s->major + s->minor * cp;
    double sx = s->sin_lon[i], cz = s->cos_lon[i];
    *p = meso_vec3_make((float)(rad * sx), (float)(s->minor * sp), (float)(rad * cz));
    *n = meso_vec3_normalize(meso_vec3_make((float)(cp * sx), (float)sp, (float)(cp * cz)));
}

/* ---- Cylinder ----------------------------------------------------------------------------- */

typedef struct cylinder_shape {
    double radius, height;
    const double *cos_lon, *sin_lon;
} cylinder_shape;

static void eval_cylinder(const void *shape, int i, int j, double u, double v, meso_vec3 *p,
                          meso_vec3 *n) {
    const cylinder_shape *s = shape;
    *n = radial(s->cos_lon, s->sin_lon, i);
    *p = meso_vec3_make((float)(s->radius * s->sin_lon[i]), (float)(s->height * (v - 0.5)),
                        (float)(s->radius * s->cos_lon[i]));
}

/* ---- Vase --------------------------------------------------------------------------------- */

/* The profile (radius, height) is a uniform cubic B-spline (C2, so the curvature is
 * continuous) through these control points, in units of the height. The first three are
 * mirror images about the axis, so the curve starts on the axis with a horizontal tangent: a
 * closed, smooth bottom pole. Heights never decrease, so the curve is monotonic in y. */
static const double vase_control[][2] = {
    {-0.12, -0.50}, {0.00, -0.50}, {0.12, -0.50}, {0.22, -0.48}, {0.30, -0.36}, {0.31, -0.16},
    {0.21, 0.08},   {0.12, 0.26},  {0.12, 0.40},  {0.19, 0.50},  {0.23, 0.54},
};
#define VASE_CONTROL_COUNT (sizeof(vase_control) / sizeof(vase_control[0]))
#define VASE_SPANS (VASE_CONTROL_COUNT - 3)
/* Samples of the arc-length table per B-spline span: the reparametrisation error is well
 * below a thousandth of a ring spacing. */
#define VASE_TABLE_PER_SPAN 512

/* Point (radius, y) and derivative of the profile at t in [0, VASE_SPANS]. */
static void vase_profile(double t, double out_point[2], double out_tangent[2]) {
    int span = (int)floor(t);
    if (span < 0) span = 0;
    if (span > (int)VASE_SPANS - 1) span = (int)VASE_SPANS - 1;
    double s = t - span, s2 = s * s, s3 = s2 * s;
    double w[4] = {(1 - s) * (1 - s) * (1 - s) / 6.0, (3 * s3 - 6 * s2 + 4) / 6.0,
                   (-3 * s3 + 3 * s2 + 3 * s + 1) / 6.0, s3 / 6.0};
    double dw[4] = {-(1 - s) * (1 - s) / 2.0, (3 * s2 - 4 * s) / 2.0, (-3 * s2 + 2 * s + 1) / 2.0,
                    s2 / 2.0};
    for (int c = 0; c < 2; c++) {
        out_point[c] = out_tangent[c] = 0.0;
        for (int k = 0; k < 4; k++) {
            out_point[c] += w[k] * vase_control[span + k][c];
            out_tangent[c] += dw[k] * vase_control[span + k][c];
        }
    }
}

typedef struct vase_shape {
    int nv;
    double scale, y_offset; /* profile units -> world */
    double *ring_t;         /* nv + 1 curve parameters, equally spaced in arc length */
    const double *cos_lon, *sin_lon;
} vase_shape;

static void eval_vase(const void *shape, int i, int j, double u, double v, meso_vec3 *p,
                      meso_vec3 *n) {
    const vase_shape *s = shape;
    double point[2], tangent[2];
    vase_profile(s->ring_t[j], point, tangent);
    float y = (float)(point[1] * s->scale + s->y_offset);
    if (j == 0) { /* the bottom pole */
        *p = meso_vec3_make(0.0f, y, 0.0f);
        *n = meso_vec3_make(0.0f, -1.0f, 0.0f);
        return;
    }
    double r = point[0] * s->scale;
    double len = hypot(tangent[0], tangent[1]);
    /* Outward normal of a surface of revolution: the profile tangent (r', y') turned
     * clockwise, (y', -r'), placed on the radial direction. */
    double nr = tangent[1] / len, ny = -tangent[0] / len;
    *p = meso_vec3_make((float)(r * s->sin_lon[i]), y, (float)(r * s->cos_lon[i]));
    *n = meso_vec3_normalize(
        meso_vec3_make((float)(nr * s->sin_lon[i]), (float)ny, (float)(nr * s->cos_lon[i])));
}

/* Curve parameters of nv + 1 rings equally spaced in arc length along the profile, from a
 * piecewise-linear arc-length table inverted by linear interpolation. */
static meso_result vase_rings(meso_context *ctx, int nv, double **out_ring_t) {
    size_t samples = VASE_SPANS * VASE_TABLE_PER_SPAN;
    double *length = malloc((samples + 1) * sizeof(double));
    double *ring_t = malloc((size_t)(nv + 1) * sizeof(double));
    if (!length || !ring_t) {
        free(length);
        free(ring_t);
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "vase: out of memory");
    }
    double prev[2], tangent[2];
    vase_profile(0.0, prev, tangent);
    length[0] = 0.0;
    for (size_t k = 1; k <= samples; k++) {
        double point[2];
        vase_profile((double)k / VASE_TABLE_PER_SPAN, point, tangent);
        length[k] = length[k - 1] + hypot(point[0] - prev[0], point[1] - prev[1]);
        prev[0] = point[0], prev[1] = point[1];
    }
    size_t k = 0;
    for (int j = 0; j <= nv; j++) {
        double target = length[samples] * j / nv;
        while (k + 1 < samples && length[k + 1] < target) k++;
        double span = length[k + 1] - length[k];
        double f = span > 0.0 ? (target - length[k]) / span : 0.0;
        ring_t[j] = ((double)k + meso_clampf((float)f, 0.0f, 1.0f)) / VASE_TABLE_PER_SPAN;
    }
    ring_t[0] = 0.0;
    ring_t[nv] = (double)VASE_SPANS;
    free(length);
    *out_ring_t = ring_t;
    return MESO_OK;
}

/* Length and largest radius of the profile in profile units (for the ring count). */
static void vase_measure(double *out_length, double *out_max_radius, double *out_height) {
    double prev[2], tangent[2], first[2];
    vase_profile(0.0, prev, tangent);
    first[0] = prev[0], first[1] = prev[1];
    double length = 0.0, max_radius = 0.0;
    for (int k = 1; k <= (int)VASE_SPANS * 64; k++) {
        double point[2];
        vase_profile(k / 64.0, point, tangent);
        length += hypot(point[0] - prev[0], point[1] - prev[1]);
        max_radius = fmax(max_radius, point[0]);
        prev[0] = point[0], prev[1] = point[1];
    }
    *out_length = length;
    *out_max_radius = max_radius;
    *out_height = prev[1] - first[1];
}

/* ---- Entry point -------------------------------------------------------------------------- */

static meso_result check_desc(meso_context *ctx, const meso_shape_desc *d) {
    const char *name = meso_shape_kind_name(d->kind);
    if ((unsigned)d->kind >= NUM_SHAPES)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "shape: unknown kind %d",
                              (int)d->kind);
    if (!(d->size > 0.0f) || !isfinite(d->size))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: size: %g must be a positive number", name, (double)d->size);
    if (d->kind == MESO_SHAPE_TORUS && (!(d->minor_radius > 0.0f) || !(d->minor_radius < d->size)))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: minor_radius: %g must be positive and below size %g", name,
                              (double)d->minor_radius, (double)d->size);
    if (d->kind == MESO_SHAPE_CYLINDER && (!(d->height > 0.0f) || !isfinite(d->height)))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: height: %g must be a positive number", name, (double)d->height);
    int lo = 1, hi = MAX_PLANE_SEGMENTS;
    if (d->kind == MESO_SHAPE_TEAPOT) hi = MAX_TEAPOT_SEGMENTS;
    if (d->kind != MESO_SHAPE_PLANE && d->kind != MESO_SHAPE_TEAPOT)
        lo = MIN_ROUND_SEGMENTS, hi = MAX_ROUND_SEGMENTS;
    if (d->segments < lo || d->segments > hi)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: segments: %d is outside [%d, %d]", name, d->segments, lo, hi);
    return MESO_OK;
}

static int rounded_count(double x, int lo) {
    int n = (int)lround(x);
    return n < lo ? lo : n;
}

/* Rows of the (segments x rows) grid of a shape (defaults applied): one definition for the
 * generator and the memory estimate. */
static int grid_rows(const meso_shape_desc *d) {
    int n = d->segments;
    switch (d->kind) {
    case MESO_SHAPE_SPHERE: /* half as many rings as columns: square cells at the equator */
        return rounded_count(n / 2.0, 2);
    case MESO_SHAPE_TORUS: /* tube cells as long as wide, on the tube's centre circle */
        return rounded_count(n * (double)d->minor_radius / d->size, 3);
    case MESO_SHAPE_CYLINDER:
        return rounded_count(n * (double)d->height / (2.0 * MESO_PI_D * d->size), 1);
    case MESO_SHAPE_VASE: {
        double length, max_radius, height;
        vase_measure(&length, &max_radius, &height);
        int nv = rounded_count(n * length / (2.0 * MESO_PI_D * max_radius), 4);
        return nv > MAX_ROUND_SEGMENTS ? MAX_ROUND_SEGMENTS : nv;
    }
    default: /* plane: square cells; teapot: per patch side */
        return n;
    }
}

uint64_t meso_shape_memory_estimate(const meso_shape_desc *desc) {
    meso_shape_desc d = meso_shape_desc_defaults(desc);
    if (d.segments < 1) return 0; /* refused by the generator anyway */
    uint64_t columns = (uint64_t)d.segments, rows = (uint64_t)grid_rows(&d);
    /* a grid's bound; the teapot is 32 such patches */
    uint64_t patches = d.kind == MESO_SHAPE_TEAPOT ? 32 : 1;
    return patches * meso_mesh_memory_estimate((columns + 1) * (rows + 1), 2 * columns * rows);
}

meso_result meso_mesh_create_shape(meso_context *ctx, const meso_shape_desc *desc,
                                   meso_mesh **out_mesh) {
    *out_mesh = NULL;
    meso_shape_desc d = meso_shape_desc_defaults(desc);
    meso_result r = check_desc(ctx, &d);
    if (r != MESO_OK) return r;
    if (d.kind == MESO_SHAPE_TEAPOT) return geom_create_teapot(ctx, &d, out_mesh);

    const char *name = meso_shape_kind_name(d.kind);
    int n = d.segments;
    if (d.kind == MESO_SHAPE_PLANE) {
        plane_shape plane = {d.size};
        grid_desc g = {name, n, n, false, false, eval_plane, &plane};
        return build_grid(ctx, &g, out_mesh);
    }

    double *cos_lon = NULL, *sin_lon = NULL, *cos_tube = NULL, *sin_tube = NULL, *ring_t = NULL;
    r = make_angle_table(ctx, n, &cos_lon, &sin_lon);
    if (r != MESO_OK) return r;
    switch (d.kind) {
    case MESO_SHAPE_SPHERE: {
        sphere_shape s = {d.size, grid_rows(&d), cos_lon, sin_lon};
        grid_desc g = {name, n, s.nv, true, true, eval_sphere, &s};
        r = build_grid(ctx, &g, out_mesh);
        break;
    }
    case MESO_SHAPE_TORUS: {
        int nv = grid_rows(&d);
        r = make_angle_table(ctx, nv, &cos_tube, &sin_tube);
        if (r != MESO_OK) break;
        torus_shape s = {d.size, d.minor_radius, cos_lon, sin_lon, cos_tube, sin_tube};
        grid_desc g = {name, n, nv, false, false, eval_torus, &s};
        r = build_grid(ctx, &g, out_mesh);
        break;
    }
    case MESO_SHAPE_CYLINDER: {
        int nv = grid_rows(&d);
        cylinder_shape s = {d.size, d.height, cos_lon, sin_lon};
        grid_desc g = {name, n, nv, false, false, eval_cylinder, &s};
        r = build_grid(ctx, &g, out_mesh);
        break;
    }
    case MESO_SHAPE_VASE: {
        double length, max_radius, height;
        vase_measure(&length, &max_radius, &height);
        int nv = grid_rows(&d);
        r = vase_rings(ctx, nv, &ring_t);
        if (r != MESO_OK) break;
        double point[2], tangent[2];
        vase_profile(0.0, point, tangent);
        double scale = d.size / height;
        /* Centred: the bottom at -size/2, the lip at +size/2. */
        vase_shape s = {nv, scale, -0.5 * d.size - point[1] * scale, ring_t, cos_lon, sin_lon};
        grid_desc g = {name, n, nv, true, false, eval_vase, &s};
        r = build_grid(ctx, &g, out_mesh);
        break;
    }
    default:
        r = meso_log_error(ctx, MESO_ERROR_INTERNAL, "%s: no generator", name);
        break;
    }
    free(ring_t);
    free(cos_tube);
    free(sin_tube);
    free(cos_lon);
    free(sin_lon);
    return r;
}
