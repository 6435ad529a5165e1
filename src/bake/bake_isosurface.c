/* Texture-space surface extraction of solid mesostructure: dual contouring on a periodic grid
 * (see include/meso/bake_isosurface.h for the contract).
 *
 * Steps: (1) sample the field at every node (parallel over w layers); (2) give every cell whose
 * corners change sign one vertex (cell_vertex_position): each of its edges that changes sign
 * has a zero crossing, found on the field from the edge's lower node toward its higher one (so
 * neighbouring cells agree), and the field's normal there; the vertex is the least-squares
 * meeting point of those planes, weakly pulled toward the crossings' mean and kept in the cell.
 * The mean alone (surface nets) cuts sharp edges by up to a cell, which on grid-vase's bars
 * kept the reference visibly off a finer one (docs/reference.md); cells one
 * step below u = 0 and v = 0 are copies of the last cells shifted by -1, so
 * a tile's border quads use exactly the vertices the neighbouring tile uses; (3) for every
 * grid edge that changes sign, one quad (two triangles) through the vertices of the four cells
 * around it. Each quad is shared by nothing else and every cell vertex is shared by all quads
 * around it, so the surface is watertight. Passes count first and write at prefix-summed
 * offsets: the output does not depend on the thread count.
 *
 * Marching tetrahedra, tried first, gave about three times the triangles for the same grid
 * (376832 against ~120000 a tile for the weave at 128 x 128 x 32), which the reference's BVH
 * build could not afford on the weave-torus scene.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "meso/bake_isosurface.h"
#include "meso/runtime.h"

/* Dual contouring's settings (cell_vertex_position): at most this many regula falsi steps for an
 * edge's crossing, the gradient's difference step and the pull toward the crossings' mean, in
 * cells. */
#define ISO_CROSSING_ITERATIONS 8
#define ISO_CROSSING_TOLERANCE 1e-3f /* of the edge: the bracket's width that ends the search */
#define ISO_GRADIENT_STEP 0.01f
#define ISO_QEF_PULL 0.02

typedef struct grid {
    int ru, rv, rw;        /* cells per tile */
    int nu, nv, nw;        /* nodes: ru + 1, rv + 1, rw + 3 (one padding layer each side) */
    int cw;                /* cell layers: nw - 1 */
    float *values;         /* nu * nv * nw */
    uint32_t *cell_vertex; /* extended cells (ru + 1) x (rv + 1) x cw, i and j from -1 */
    meso_scalar_field_fn field;
    void *user;
} grid;

static size_t node_index(const grid *g, int i, int j, int k) {
    return ((size_t)k * (size_t)g->nv + (size_t)j) * (size_t)g->nu + (size_t)i;
}

static meso_vec3 node_position(const grid *g, int i, int j, int k) {
    return (meso_vec3){(float)i / (float)g->ru, (float)j / (float)g->rv,
                       (float)(k - 1) / (float)g->rw};
}

/* Extended cell (i, j, k), i in [-1, ru), j in [-1, rv). */
static size_t cell_index(const grid *g, int i, int j, int k) {
    return ((size_t)k * (size_t)(g->rv + 1) + (size_t)(j + 1)) * (size_t)(g->ru + 1) +
           (size_t)(i + 1);
}

meso_isosurface_desc meso_isosurface_desc_defaults(const meso_isosurface_desc *desc) {
    meso_isosurface_desc d = desc ? *desc : (meso_isosurface_desc){0};
    if (d.resolution_u == 0) d.resolution_u = 128;
    if (d.resolution_v == 0) d.resolution_v = 128;
    if (d.resolution_w == 0) d.resolution_w = 32;
    return d;
}

void meso_isosurface_destroy(meso_isosurface *isosurface) {
    if (!isosurface) return;
    free(isosurface->positions);
    free(isosurface->indices);
    free(isosurface->column_offsets);
    free(isosurface);
}

static bool inside(float value) { return value < 0.0f; }

/* ---- Sampling ----------------------------------------------------------------------------- */

/* The field as the grid samples it: the slab 0 <= w <= 1 closes the solid (header), NaN
 * counts as outside. */
static float closed_field(const grid *g, meso_vec3 p) {
    float f = g->field(g->user, p);
    float slab = p.z < 0.5f ? -p.z : p.z - 1.0f;
    if (!(f == f)) f = 1.0f;
    return f > slab ? f : slab;
}

static void sample_layer(void *user, size_t job, int thread_index) {
    grid *g = user;
    int k = (int)job;
    for (int j = 0; j < g->nv; j++)
        for (int i = 0; i < g->nu; i++) {
            /* periodic: the last node column/row samples the first again, bit for bit */
            int si = i == g->ru ? 0 : i, sj = j == g->rv ? 0 : j;
            /* a node exactly on the slab's faces counts as outside (closed_field), so the cap
             * lies exactly at w = 0 and w = 1 */
            g->values[node_index(g, i, j, k)] = closed_field(g, node_position(g, si, sj, k));
        }
}

/* ---- Cell vertices ------------------------------------------------------------------------ */

/* The twelve edges of a cube as corner pairs (corner bits: 1 = +u, 2 = +v, 4 = +w), each from
 * the lower corner to the higher. */
static const unsigned char cube_edges[12][2] = {
    {0, 1}, {2, 3}, {4, 5}, {6, 7}, {0, 2}, {1, 3}, {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7},
};

/* Whether cell (i, j, k) (i, j in [0, ru), [0, rv)) has corners on both sides. */
static bool cell_has_vertex(const grid *g, int i, int j, int k) {
    int n_in = 0;
    for (int c = 0; c < 8; c++)
        n_in +=
            inside(g->values[node_index(g, i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1))]);
    return n_in != 0 && n_in != 8;
}

/* Where the field crosses zero on the edge pa -> pb (fa = F(pa) inside-or-not unlike fb): the
 * linear guess from the node values refined on the field itself by regula falsi (Illinois), so
 * that the crossing is the surface's to a small fraction of a cell whatever the field's
 * curvature (a box's distance is not linear across its edges). The edge is always taken from its
 * lower node to its higher one, so every cell around it finds the same point. */
static meso_vec3 edge_crossing(const grid *g, meso_vec3 pa, meso_vec3 pb, float fa, float fb) {
    float lo = 0.0f, hi = 1.0f;
    bool side_lo = inside(fa);
    for (int iteration = 0; iteration < ISO_CROSSING_ITERATIONS; iteration++) {
        float t = lo + (hi - lo) * (fa / (fa - fb));
        if (!(t > lo && t < hi)) t = 0.5f * (lo + hi); /* rounding, or equal values */
        float ft = closed_field(g, meso_vec3_lerp(pa, pb, t));
        if (ft == 0.0f) return meso_vec3_lerp(pa, pb, t);
        if (inside(ft) == side_lo) {
            lo = t, fa = ft;
            fb *= 0.5f; /* Illinois: the end that stays is halved, against slow convergence */
        } else {
            hi = t, fb = ft;
            fa *= 0.5f;
        }
        if (hi - lo < ISO_CROSSING_TOLERANCE) break;
    }
    float t = lo + (hi - lo) * (fa / (fa - fb));
    if (!(t >= lo && t <= hi)) t = 0.5f * (lo + hi);
    return meso_vec3_lerp(pa, pb, t);
}

/* The field's gradient at p in the cell's units (u * ru, v * rv, w * rw), unit; zero where it
 * vanishes. Central differences a small fraction of a cell wide. */
static meso_vec3 cell_gradient(const grid *g, meso_vec3 p) {
    meso_vec3 h = {ISO_GRADIENT_STEP / (float)g->ru, ISO_GRADIENT_STEP / (float)g->rv,
                   ISO_GRADIENT_STEP / (float)g->rw};
    meso_vec3 n = {
        closed_field(g, (meso_vec3){p.x + h.x, p.y, p.z}) -
            closed_field(g, (meso_vec3){p.x - h.x, p.y, p.z}),
        closed_field(g, (meso_vec3){p.x, p.y + h.y, p.z}) -
            closed_field(g, (meso_vec3){p.x, p.y - h.y, p.z}),
        closed_field(g, (meso_vec3){p.x, p.y, p.z + h.z}) -
            closed_field(g, (meso_vec3){p.x, p.y, p.z - h.z}),
    };
    float len2 = meso_vec3_dot(n, n);
    return len2 > 0.0f && isfinite(len2) ? meso_vec3_scale(n, 1.0f / sqrtf(len2))
                                         : (meso_vec3){0.0f, 0.0f, 0.0f};
}

/* Cell (i, j, k)'s vertex (i, j in [0, ru), [0, rv); the cell has corners on both sides): dual
 * contouring (Ju et al. 2002). Each edge crossing with the field's normal there is a plane the
 * surface passes through; the vertex is the point nearest all of them in the least-squares
 * sense, pulled weakly toward the crossings' mean where they leave a direction free (a flat
 * face: along it; an edge: along the edge), and kept inside the cell. The mean alone (surface
 * nets) cuts a box's edges and corners off by up to a cell: on grid-vase's thin bars that was
 * the reference's largest error (docs/reference.md). In double, in cell units. */
static meso_vec3 cell_vertex_position(const grid *g, int i, int j, int k) {
    float value[8];
    for (int c = 0; c < 8; c++)
        value[c] = g->values[node_index(g, i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1))];
    meso_vec3 origin = node_position(g, i, j, k);
    double scale[3] = {g->ru, g->rv, g->rw};
    double ata[3][3] = {{0}}, atb[3] = {0}, mean[3] = {0};
    int count = 0;
    for (int e = 0; e < 12; e++) {
        int a = cube_edges[e][0], b = cube_edges[e][1];
        if (inside(value[a]) == inside(value[b])) continue;
        meso_vec3 pa = node_position(g, i + (a & 1), j + ((a >> 1) & 1), k + ((a >> 2) & 1));
        meso_vec3 pb = node_position(g, i + (b & 1), j + ((b >> 1) & 1), k + ((b >> 2) & 1));
        meso_vec3 p = edge_crossing(g, pa, pb, value[a], value[b]);
        meso_vec3 n = cell_gradient(g, p);
        double x[3] = {((double)p.x - origin.x) * scale[0], ((double)p.y - origin.y) * scale[1],
                       ((double)p.z - origin.z) * scale[2]};
        double nn[3] = {n.x, n.y, n.z};
        double d = nn[0] * x[0] + nn[1] * x[1] + nn[2] * x[2];
        for (int r = 0; r < 3; r++) {
            for (int c = 0; c < 3; c++) ata[r][c] += nn[r] * nn[c];
            atb[r] += nn[r] * d;
            mean[r] += x[r];
        }
        count++;
    }
    double lambda = ISO_QEF_PULL * count;
    for (int r = 0; r < 3; r++) {
        mean[r] /= count;
        ata[r][r] += lambda;
        atb[r] += lambda * mean[r];
    }
    /* (A^T A + lambda I) x = A^T b + lambda mean: symmetric positive definite (lambda > 0), by
     * Cramer's rule */
    double(*m)[3] = ata;
    double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                 m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                 m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    double x[3] = {mean[0], mean[1], mean[2]};
    if (det > 0.0 && isfinite(det)) {
        for (int c = 0; c < 3; c++) {
            double col[3][3];
            memcpy(col, m, sizeof col);
            for (int r = 0; r < 3; r++) col[r][c] = atb[r];
            x[c] = (col[0][0] * (col[1][1] * col[2][2] - col[1][2] * col[2][1]) -
                    col[0][1] * (col[1][0] * col[2][2] - col[1][2] * col[2][0]) +
                    col[0][2] * (col[1][0] * col[2][1] - col[1][1] * col[2][0])) /
                   det;
        }
    }
    for (int r = 0; r < 3; r++) x[r] = x[r] > 0.0 ? (x[r] < 1.0 ? x[r] : 1.0) : 0.0;
    return (meso_vec3){(float)(origin.x + x[0] / scale[0]), (float)(origin.y + x[1] / scale[1]),
                       (float)(origin.z + x[2] / scale[2])};
}

typedef struct vertex_pass {
    grid *g;
    size_t *layer_counts, *layer_offsets;
    meso_vec3 *positions; /* NULL in the counting pass */
} vertex_pass;

static void vertices_layer(void *user, size_t job, int thread_index) {
    vertex_pass *pass = user;
    grid *g = pass->g;
    int k = (int)job;
    size_t count = 0, next = pass->positions ? pass->layer_offsets[k] : 0;
    for (int j = -1; j < g->rv; j++)
        for (int i = -1; i < g->ru; i++) {
            int ci = i < 0 ? g->ru - 1 : i, cj = j < 0 ? g->rv - 1 : j;
            bool has = cell_has_vertex(g, ci, cj, k);
            if (!pass->positions) {
                count += has;
                continue;
            }
            uint32_t *slot = &g->cell_vertex[cell_index(g, i, j, k)];
            if (!has) {
                *slot = UINT32_MAX;
                continue;
            }
            meso_vec3 p = cell_vertex_position(g, ci, cj, k);
            /* exact (Sterbenz): p.x is within a cell of 1, so tile + (p.x - 1) equals
             * (tile - 1) + p.x bit for bit */
            if (i < 0) p.x -= 1.0f;
            if (j < 0) p.y -= 1.0f;
            pass->positions[next] = p;
            *slot = (uint32_t)next++;
        }
    if (!pass->positions) pass->layer_counts[k] = count;
}

/* ---- Quads -------------------------------------------------------------------------------- */

typedef struct quad_pass {
    const grid *g;
    const meso_vec3 *positions;
    uint32_t *column_counts; /* per column (counting pass) */
    const uint32_t *column_offsets;
    uint32_t *indices; /* NULL in the counting pass */
} quad_pass;

static meso_vec3 cell_centre(const grid *g, int i, int j, int k) {
    return (meso_vec3){((float)i + 0.5f) / (float)g->ru, ((float)j + 0.5f) / (float)g->rv,
                       ((float)k - 0.5f) / (float)g->rw};
}

static void quads_column(void *user, size_t job, int thread_index) {
    quad_pass *pass = user;
    const grid *g = pass->g;
    int i = (int)(job % (size_t)g->ru), j = (int)(job / (size_t)g->ru);
    size_t cursor = pass->indices ? pass->column_offsets[job] : 0;
    for (int k = 0; k < g->nw; k++) {
        float f0 = g->values[node_index(g, i, j, k)];
        for (int d = 0; d < 3; d++) {
            int di = d == 0, dj = d == 1, dk = d == 2;
            if (k + dk >= g->nw) continue;
            float f1 = g->values[node_index(g, i + di, j + dj, k + dk)];
            if (inside(f0) == inside(f1)) continue;
            /* the four cells around the edge, in order around its axis */
            int ci[4], cj[4], ck[4];
            static const int ring[4][2] = {{-1, -1}, {0, -1}, {0, 0}, {-1, 0}};
            for (int q = 0; q < 4; q++) {
                int s = ring[q][0], t = ring[q][1];
                ci[q] = d == 0 ? i : i + (d == 1 ? t : s);
                cj[q] = d == 1 ? j : j + (d == 0 ? s : t);
                ck[q] = d == 2 ? k : k + (d == 0 ? t : s);
            }
            bool valid = true;
            for (int q = 0; q < 4; q++) valid &= ck[q] >= 0 && ck[q] < g->cw;
            if (!valid) continue; /* cannot happen: the padding layers are outside */
            if (!pass->indices) {
                cursor += 2;
                continue;
            }
            uint32_t v[4];
            meso_vec3 centre[4];
            for (int q = 0; q < 4; q++) {
                v[q] = g->cell_vertex[cell_index(g, ci[q], cj[q], ck[q])];
                centre[q] = cell_centre(g, ci[q], cj[q], ck[q]);
            }
            /* outward: from the inside node toward the outside one; decided on the cell
             * centres, which never form a degenerate quad */
            meso_vec3 axis = {(float)di, (float)dj, (float)dk};
            if (!inside(f0)) axis = meso_vec3_negate(axis);
            meso_vec3 n = meso_vec3_cross(meso_vec3_sub(centre[1], centre[0]),
                                          meso_vec3_sub(centre[2], centre[0]));
            if (meso_vec3_dot(n, axis) < 0.0f) {
                uint32_t swap = v[1];
                v[1] = v[3];
                v[3] = swap;
            }
            uint32_t *out = pass->indices + 3 * cursor;
            out[0] = v[0], out[1] = v[1], out[2] = v[2];
            out[3] = v[0], out[4] = v[2], out[5] = v[3];
            cursor += 2;
        }
    }
    if (!pass->indices) pass->column_counts[job] = (uint32_t)cursor;
}

/* ---- Entry points ------------------------------------------------------------------------- */

meso_result meso_isosurface_bake_function(meso_context *ctx, meso_scalar_field_fn field, void *user,
                                          const meso_isosurface_desc *desc,
                                          meso_isosurface **out_isosurface) {
    *out_isosurface = NULL;
    if (!field) return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "isosurface: no field");
    meso_isosurface_desc d = meso_isosurface_desc_defaults(desc);
    const char *names[3] = {"resolution_u", "resolution_v", "resolution_w"};
    int res[3] = {d.resolution_u, d.resolution_v, d.resolution_w};
    for (int a = 0; a < 3; a++)
        if (res[a] < 2 || res[a] > MESO_ISOSURFACE_MAX_RESOLUTION)
            return meso_log_error(ctx, MESO_ERROR_LIMIT, "isosurface: %s: %d is outside [2, %d]",
                                  names[a], res[a], MESO_ISOSURFACE_MAX_RESOLUTION);
    grid g = {.ru = d.resolution_u,
              .rv = d.resolution_v,
              .rw = d.resolution_w,
              .field = field,
              .user = user};
    g.nu = g.ru + 1;
    g.nv = g.rv + 1;
    g.nw = g.rw + 3;
    g.cw = g.nw - 1;
    size_t nodes = (size_t)g.nu * (size_t)g.nv * (size_t)g.nw;
    if (nodes > MESO_ISOSURFACE_MAX_NODES)
        return meso_log_error(ctx, MESO_ERROR_LIMIT,
                              "isosurface: %d x %d x %d cells: %zu nodes exceed the limit %u", g.ru,
                              g.rv, g.rw, nodes, MESO_ISOSURFACE_MAX_NODES);
    size_t columns = (size_t)g.ru * (size_t)g.rv;
    size_t cells = (size_t)(g.ru + 1) * (size_t)(g.rv + 1) * (size_t)g.cw;
    meso_result result = MESO_OK;
    meso_isosurface *iso = calloc(1, sizeof *iso);
    size_t *layer_counts = calloc((size_t)g.cw, sizeof *layer_counts);
    size_t *layer_offsets = calloc((size_t)g.cw, sizeof *layer_offsets);
    uint32_t *column_counts = calloc(columns, sizeof *column_counts);
    g.values = malloc(nodes * sizeof *g.values);
    g.cell_vertex = malloc(cells * sizeof *g.cell_vertex);
    if (!iso || !layer_counts || !layer_offsets || !column_counts || !g.values || !g.cell_vertex)
        goto out_of_memory;
    iso->resolution_u = g.ru;
    iso->resolution_v = g.rv;
    iso->resolution_w = g.rw;

    meso_parallel_for(ctx, (size_t)g.nw, sample_layer, &g);

    vertex_pass vp = {.g = &g, .layer_counts = layer_counts, .layer_offsets = layer_offsets};
    meso_parallel_for(ctx, (size_t)g.cw, vertices_layer, &vp);
    size_t num_vertices = 0;
    for (int k = 0; k < g.cw; k++) {
        layer_offsets[k] = num_vertices;
        num_vertices += layer_counts[k];
    }
    if (num_vertices >= UINT32_MAX) {
        result = meso_log_error(ctx, MESO_ERROR_LIMIT, "isosurface: %zu vertices exceed the limit",
                                num_vertices);
        goto fail;
    }
    iso->num_vertices = num_vertices;
    iso->positions = malloc((num_vertices ? num_vertices : 1) * sizeof *iso->positions);
    if (!iso->positions) goto out_of_memory;
    vp.positions = iso->positions;
    meso_parallel_for(ctx, (size_t)g.cw, vertices_layer, &vp);

    quad_pass qp = {.g = &g, .positions = iso->positions, .column_counts = column_counts};
    meso_parallel_for(ctx, columns, quads_column, &qp);
    iso->column_offsets = malloc((columns + 1) * sizeof *iso->column_offsets);
    if (!iso->column_offsets) goto out_of_memory;
    size_t num_triangles = 0;
    for (size_t c = 0; c < columns; c++) {
        iso->column_offsets[c] = (uint32_t)num_triangles;
        num_triangles += column_counts[c];
        if (num_triangles >= UINT32_MAX / 3) {
            result = meso_log_error(ctx, MESO_ERROR_LIMIT, "isosurface: more than %u triangles",
                                    UINT32_MAX / 3);
            goto fail;
        }
    }
    iso->column_offsets[columns] = (uint32_t)num_triangles;
    iso->num_triangles = num_triangles;
    iso->indices = malloc((num_triangles ? 3 * num_triangles : 3) * sizeof *iso->indices);
    if (!iso->indices) goto out_of_memory;
    qp.column_offsets = iso->column_offsets;
    qp.indices = iso->indices;
    meso_parallel_for(ctx, columns, quads_column, &qp);

    free(layer_counts);
    free(layer_offsets);
    free(column_counts);
    free(g.values);
    free(g.cell_vertex);
    *out_isosurface = iso;
    return MESO_OK;

out_of_memory:
    result = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "isosurface: %d x %d x %d cells",
                            d.resolution_u, d.resolution_v, d.resolution_w);
fail:
    meso_isosurface_destroy(iso);
    free(layer_counts);
    free(layer_offsets);
    free(column_counts);
    free(g.values);
    free(g.cell_vertex);
    return result;
}

static float solid_field(void *user, meso_vec3 uvw) {
    return meso_solid_distance((const meso_solid *)user, uvw);
}

meso_result meso_isosurface_bake(meso_context *ctx, const meso_solid *solid,
                                 const meso_isosurface_desc *desc,
                                 meso_isosurface **out_isosurface) {
    *out_isosurface = NULL;
    if (!solid) return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "isosurface: no solid");
    return meso_isosurface_bake_function(ctx, solid_field, (void *)solid, desc, out_isosurface);
}
