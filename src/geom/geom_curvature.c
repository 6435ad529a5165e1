/* Per-vertex principal curvatures (Rusinkiewicz 2004) and quadric fits (Oliveira & Policarpo
 * 2005, used by relief mapping's silhouettes, Policarpo & Oliveira 2006 §4).
 *
 * Both look across texture seams and patch borders: vertices at bit-identical positions are
 * welded for the neighbourhood (geom_weld), so a sphere's seam column or the teapot's patch
 * edges see the same surface as any other vertex.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geom_internal.h"
#include "meso/runtime.h"

#define JOB_SIZE 4096

/* Copies of a vertex whose normals differ by more than this (a crease, a hard edge) do not
 * share their faces' curvature. cos(~11 degrees). */
#define SMOOTH_NORMAL_COS 0.98f

/* ---- Curvature: per-face shape operators -------------------------------------------------- */

typedef struct face_tensor {
    meso_vec3 t, b, n;      /* the face's orthonormal frame */
    float ku, kuv, kv;      /* second fundamental form in (t, b) */
    float corner_weight[3]; /* mixed Voronoi area of each corner (Meyer et al. 2003) */
    int valid;
} face_tensor;

typedef struct curvature_job {
    meso_mesh *mesh;
    face_tensor *faces;
    geom_vertex_faces adjacency;
    geom_weld weld;
} curvature_job;

typedef struct dvec3 {
    double x, y, z;
} dvec3;

static dvec3 dv(meso_vec3 a) { return (dvec3){a.x, a.y, a.z}; }
static dvec3 dsub(dvec3 a, dvec3 b) { return (dvec3){a.x - b.x, a.y - b.y, a.z - b.z}; }
static dvec3 dadd(dvec3 a, dvec3 b) { return (dvec3){a.x + b.x, a.y + b.y, a.z + b.z}; }
static dvec3 dscale(dvec3 a, double s) { return (dvec3){a.x * s, a.y * s, a.z * s}; }
static double ddot(dvec3 a, dvec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static dvec3 dcross(dvec3 a, dvec3 b) {
    return (dvec3){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
static dvec3 dnormalize(dvec3 a) {
    double len = sqrt(ddot(a, a));
    return len > 0.0 ? dscale(a, 1.0 / len) : a;
}
static meso_vec3 fv(dvec3 a) { return meso_vec3_make((float)a.x, (float)a.y, (float)a.z); }

/* Solve the symmetric 3x3 system m x = r (Cramer's rule); false when (nearly) singular. */
static bool solve3(const double m[3][3], const double r[3], double x[3]) {
    double c00 = m[1][1] * m[2][2] - m[1][2] * m[2][1];
    double c01 = m[1][2] * m[2][0] - m[1][0] * m[2][2];
    double c02 = m[1][0] * m[2][1] - m[1][1] * m[2][0];
    double det = m[0][0] * c00 + m[0][1] * c01 + m[0][2] * c02;
    double scale = fabs(m[0][0]) + fabs(m[1][1]) + fabs(m[2][2]);
    if (!(fabs(det) > 1e-12 * scale * scale * scale)) return false;
    double inv[3][3] = {
        {c00, m[0][2] * m[2][1] - m[0][1] * m[2][2], m[0][1] * m[1][2] - m[0][2] * m[1][1]},
        {c01, m[0][0] * m[2][2] - m[0][2] * m[2][0], m[0][2] * m[1][0] - m[0][0] * m[1][2]},
        {c02, m[0][1] * m[2][0] - m[0][0] * m[2][1], m[0][0] * m[1][1] - m[0][1] * m[1][0]},
    };
    for (int i = 0; i < 3; i++)
        x[i] = (inv[i][0] * r[0] + inv[i][1] * r[1] + inv[i][2] * r[2]) / det;
    return true;
}

/* Mixed Voronoi areas of the corners (Meyer, Desbrun, Schroeder, Barr 2003, §3.3): the Voronoi
 * region for non-obtuse triangles, else half / a quarter of the area. */
static void corner_weights(const dvec3 p[3], double area, float out[3]) {
    dvec3 e[3] = {dsub(p[2], p[1]), dsub(p[0], p[2]), dsub(p[1], p[0])}; /* opposite corner i */
    double l2[3] = {ddot(e[0], e[0]), ddot(e[1], e[1]), ddot(e[2], e[2])};
    for (int i = 0; i < 3; i++) {
        int j = (i + 1) % 3, k = (i + 2) % 3;
        /* The corner i is obtuse when its opposite edge is longer than the other two combined. */
        if (l2[i] > l2[j] + l2[k]) {
            out[i] = (float)(0.5 * area);
            out[j] = out[k] = (float)(0.25 * area);
            return;
        }
    }
    /* cot(angle at corner i) = (a . b) / |a x b| with a, b the edges leaving i. */
    double cot[3];
    for (int i = 0; i < 3; i++) {
        dvec3 a = dsub(p[(i + 1) % 3], p[i]), b = dsub(p[(i + 2) % 3], p[i]);
        cot[i] = ddot(a, b) / (2.0 * area);
    }
    for (int i = 0; i < 3; i++) {
        int j = (i + 1) % 3, k = (i + 2) % 3;
        /* Edge i-j is opposite corner k, edge i-k opposite corner j. */
        out[i] = (float)((l2[k] * cot[k] + l2[j] * cot[j]) / 8.0);
    }
}

static void compute_face_tensors(void *user, size_t job, int thread_index) {
    curvature_job *cj = user;
    const meso_mesh *mesh = cj->mesh;
    size_t end = (job + 1) * JOB_SIZE;
    if (end > mesh->num_triangles) end = mesh->num_triangles;
    for (size_t f = job * JOB_SIZE; f < end; f++) {
        const uint32_t *tri = mesh->indices + 3 * f;
        face_tensor *ft = &cj->faces[f];
        memset(ft, 0, sizeof(*ft));
        dvec3 p[3], n[3];
        for (int k = 0; k < 3; k++)
            p[k] = dv(mesh->positions[tri[k]]), n[k] = dv(mesh->normals[tri[k]]);
        dvec3 e[3] = {dsub(p[2], p[1]), dsub(p[0], p[2]), dsub(p[1], p[0])};
        dvec3 dn[3] = {dsub(n[2], n[1]), dsub(n[0], n[2]), dsub(n[1], n[0])};
        dvec3 cross = dcross(e[2], dscale(e[1], -1.0));
        double area = 0.5 * sqrt(ddot(cross, cross));
        if (!(area > 0.0)) continue;
        dvec3 nf = dnormalize(cross);
        /* The face frame follows the vertex normals, so a triangle wound against them still
         * measures convexity with the mesh's sign convention. */
        if (ddot(nf, dadd(dadd(n[0], n[1]), n[2])) < 0.0) nf = dscale(nf, -1.0);
        dvec3 t = dnormalize(e[0]);
        dvec3 b = dcross(nf, t);
        /* Rusinkiewicz 2004 §3: the shape operator II maps each edge to its change of normal,
         * II (e.t, e.b) = (dn.t, dn.b); six equations, three unknowns, least squares. */
        double m[3][3] = {{0}}, r[3] = {0};
        for (int k = 0; k < 3; k++) {
            double eu = ddot(e[k], t), ev = ddot(e[k], b);
            double nu = ddot(dn[k], t), nv = ddot(dn[k], b);
            m[0][0] += eu * eu, m[0][1] += eu * ev;
            m[1][1] += eu * eu + ev * ev, m[1][2] += eu * ev;
            m[2][2] += ev * ev;
            r[0] += nu * eu, r[1] += nu * ev + nv * eu, r[2] += nv * ev;
        }
        m[1][0] = m[0][1], m[2][1] = m[1][2];
        double x[3];
        if (!solve3(m, r, x)) continue;
        ft->t = fv(t), ft->b = fv(b), ft->n = fv(nf);
        ft->ku = (float)x[0], ft->kuv = (float)x[1], ft->kv = (float)x[2];
        corner_weights(p, area, ft->corner_weight);
        ft->valid = isfinite(x[0]) && isfinite(x[1]) && isfinite(x[2]);
    }
}

/* Rotate the frame (u, v) of normal `from` rigidly about from x to so that its normal becomes
 * `to` (Rusinkiewicz 2004 §3.2: the tensors of faces and vertices live in different planes). */
static void rotate_frame(dvec3 from, dvec3 to, dvec3 *u, dvec3 *v) {
    double d = ddot(from, to);
    if (d <= -1.0 + 1e-12) {
        *u = dscale(*u, -1.0), *v = dscale(*v, -1.0);
        return;
    }
    dvec3 perp = dsub(to, dscale(from, d));
    dvec3 dperp = dscale(dadd(from, to), 1.0 / (1.0 + d));
    *u = dsub(*u, dscale(dperp, ddot(*u, perp)));
    *v = dsub(*v, dscale(dperp, ddot(*v, perp)));
}

static void compute_vertex_curvature(void *user, size_t job, int thread_index) {
    curvature_job *cj = user;
    meso_mesh *mesh = cj->mesh;
    size_t end = (job + 1) * JOB_SIZE;
    if (end > mesh->num_vertices) end = mesh->num_vertices;
    for (size_t v = job * JOB_SIZE; v < end; v++) {
        meso_vec3 normal = mesh->normals[v];
        dvec3 nv = dv(normal);
        dvec3 pu = dv(geom_any_perpendicular(normal));
        dvec3 pv = dcross(nv, pu);
        double ku = 0.0, kuv = 0.0, kv = 0.0, total = 0.0;
        uint32_t group = cj->weld.group[v];
        for (size_t g = cj->weld.offsets[group]; g < cj->weld.offsets[group + 1]; g++) {
            uint32_t member = cj->weld.members[g];
            if (meso_vec3_dot(mesh->normals[member], normal) < SMOOTH_NORMAL_COS) continue;
            for (size_t k = cj->adjacency.offsets[member]; k < cj->adjacency.offsets[member + 1];
                 k++) {
                uint32_t f = cj->adjacency.faces[k];
                const face_tensor *ft = &cj->faces[f];
                if (!ft->valid) continue;
                int corner = 0;
                while (corner < 2 && mesh->indices[3 * f + corner] != member) corner++;
                double w = ft->corner_weight[corner];
                /* Express the face's tensor in the vertex frame: turn the vertex frame into the
                 * face's plane and read II along the turned axes. */
                dvec3 ru = pu, rv = pv;
                rotate_frame(nv, dv(ft->n), &ru, &rv);
                double u1 = ddot(ru, dv(ft->t)), v1 = ddot(ru, dv(ft->b));
                double u2 = ddot(rv, dv(ft->t)), v2 = ddot(rv, dv(ft->b));
                ku += w * (ft->ku * u1 * u1 + 2.0 * ft->kuv * u1 * v1 + ft->kv * v1 * v1);
                kuv += w * (ft->ku * u1 * u2 + ft->kuv * (u1 * v2 + u2 * v1) + ft->kv * v1 * v2);
                kv += w * (ft->ku * u2 * u2 + 2.0 * ft->kuv * u2 * v2 + ft->kv * v2 * v2);
                total += w;
            }
        }
        double k1 = 0.0, k2 = 0.0, dx = 1.0, dy = 0.0;
        if (total > 0.0) {
            ku /= total, kuv /= total, kv /= total;
            double mean = 0.5 * (ku + kv), half = hypot(0.5 * (ku - kv), kuv);
            k1 = mean + half, k2 = mean - half;
            /* Eigenvector of k1: the larger of the two (equivalent) candidate rows. */
            double ax = kuv, ay = k1 - ku, bx = k1 - kv, by = kuv;
            if (ax * ax + ay * ay >= bx * bx + by * by)
                dx = ax, dy = ay;
            else
                dx = bx, dy = by;
            if (dx * dx + dy * dy < 1e-30) dx = 1.0, dy = 0.0;
        }
        dvec3 dmax = dnormalize(dadd(dscale(pu, dx), dscale(pv, dy)));
        mesh->curvature_max[v] = (float)k1;
        mesh->curvature_min[v] = (float)k2;
        mesh->curvature_dir_max[v] = fv(dmax);
        mesh->curvature_dir_min[v] = fv(dcross(nv, dmax));
    }
}

meso_result meso_mesh_compute_curvature(meso_context *ctx, meso_mesh *mesh) {
    curvature_job cj = {mesh, NULL, {NULL, NULL}, {0}};
    size_t nv = mesh->num_vertices ? mesh->num_vertices : 1;
    float *kmax = malloc(nv * sizeof(float)), *kmin = malloc(nv * sizeof(float));
    meso_vec3 *dmax = malloc(nv * sizeof(meso_vec3)), *dmin = malloc(nv * sizeof(meso_vec3));
    cj.faces = malloc((mesh->num_triangles ? mesh->num_triangles : 1) * sizeof(face_tensor));
    meso_result r = MESO_OK;
    if (!kmax || !kmin || !dmax || !dmin || !cj.faces) {
        r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY,
                           "mesh: out of memory for the curvature of %zu vertices",
                           mesh->num_vertices);
        goto fail;
    }
    r = geom_vertex_faces_build(ctx, mesh, &cj.adjacency);
    if (r != MESO_OK) goto fail;
    r = geom_weld_build(ctx, mesh, &cj.weld);
    if (r != MESO_OK) goto fail;
    free(mesh->curvature_max), free(mesh->curvature_min);
    free(mesh->curvature_dir_max), free(mesh->curvature_dir_min);
    mesh->curvature_max = kmax, mesh->curvature_min = kmin;
    mesh->curvature_dir_max = dmax, mesh->curvature_dir_min = dmin;
    kmax = kmin = NULL;
    dmax = dmin = NULL;
    meso_parallel_for(ctx, (mesh->num_triangles + JOB_SIZE - 1) / JOB_SIZE, compute_face_tensors,
                      &cj);
    meso_parallel_for(ctx, (mesh->num_vertices + JOB_SIZE - 1) / JOB_SIZE, compute_vertex_curvature,
                      &cj);
fail:
    geom_weld_free(&cj.weld);
    geom_vertex_faces_free(&cj.adjacency);
    free(cj.faces);
    free(dmin), free(dmax), free(kmin), free(kmax);
    return r;
}

/* ---- Quadrics ----------------------------------------------------------------------------- */

/* Fewer one-ring neighbours than this, or a badly conditioned fit, widens to the two-ring. */
#define MIN_RING_POINTS 5
/* The smallest Hadamard ratio (determinant over the product of the diagonal) of the fit's
 * normal equations: below it the samples cannot tell the terms apart (all on a line, or in
 * two directions only). A regular one-ring of six gives about 0.1. */
#define MIN_FIT_CONDITION 1e-3

typedef struct thread_scratch {
    uint32_t *stamp; /* num_groups: the vertex (+1) that last listed the group */
    uint32_t *list;  /* num_groups: the neighbourhood being gathered */
} thread_scratch;

typedef struct quadric_job {
    meso_mesh *mesh;
    geom_vertex_faces adjacency;
    geom_weld weld;
    thread_scratch *scratch; /* one per thread */
} quadric_job;

/* Add the groups of the corners of every triangle around the vertices of `group` (optionally
 * only those whose normal is within SMOOTH_NORMAL_COS of `normal`) to the list. */
static size_t gather_ring(const quadric_job *qj, uint32_t group, const meso_vec3 *normal,
                          uint32_t stamp, thread_scratch *s, size_t count) {
    const meso_mesh *mesh = qj->mesh;
    for (size_t g = qj->weld.offsets[group]; g < qj->weld.offsets[group + 1]; g++) {
        uint32_t member = qj->weld.members[g];
        if (normal && meso_vec3_dot(mesh->normals[member], *normal) < SMOOTH_NORMAL_COS) continue;
        for (size_t k = qj->adjacency.offsets[member]; k < qj->adjacency.offsets[member + 1]; k++) {
            const uint32_t *tri = mesh->indices + 3 * qj->adjacency.faces[k];
            for (int c = 0; c < 3; c++) {
                uint32_t other = qj->weld.group[tri[c]];
                if (s->stamp[other] == stamp) continue;
                s->stamp[other] = stamp;
                s->list[count++] = other;
            }
        }
    }
    return count;
}

typedef struct quadric_sums {
    double m[3][3], r[3]; /* normal equations over the features (x^2, y^2, x y) */
    double rrrr, rrz;     /* the isotropic fallback */
    size_t count;
} quadric_sums;

static void add_samples(const quadric_job *qj, size_t v, meso_vec3 x_axis, meso_vec3 y_axis,
                        double cos_xy, const uint32_t *groups, size_t count, quadric_sums *sums) {
    const meso_mesh *mesh = qj->mesh;
    dvec3 p = dv(mesh->positions[v]), n = dv(mesh->normals[v]);
    dvec3 ax = dv(x_axis), ay = dv(y_axis);
    for (size_t i = 0; i < count; i++) {
        uint32_t member = qj->weld.members[qj->weld.offsets[groups[i]]];
        dvec3 d = dsub(dv(mesh->positions[member]), p);
        double z = -ddot(d, n); /* depth runs inward, along -N */
        /* Coordinates along the (possibly skewed) unit axes: solve
         * d_tangential = x ax + y ay with the Gram matrix [[1, c], [c, 1]]. */
        double dx = ddot(d, ax), dy = ddot(d, ay);
        double inv = 1.0 / (1.0 - cos_xy * cos_xy);
        double x = (dx - cos_xy * dy) * inv, y = (dy - cos_xy * dx) * inv;
        double feature[3] = {x * x, y * y, x * y};
        for (int a = 0; a < 3; a++) {
            for (int b = 0; b < 3; b++) sums->m[a][b] += feature[a] * feature[b];
            sums->r[a] += feature[a] * z;
        }
        /* rho^2 of the true distance, for the isotropic fallback */
        double rr = ddot(d, d) - z * z;
        sums->rrrr += rr * rr, sums->rrz += rr * z;
        sums->count++;
    }
}

/* Least squares of depth = a x^2 + b y^2 + c x y. The cross term is fitted and dropped: without
 * it, principal directions that are not along T and B (or skewed T, B) would bias a and b;
 * with it, a and b are exactly half the normal curvatures along T and B. False when the
 * samples cannot separate the three terms. */
static bool solve_quadric(const quadric_sums *s, meso_vec2 *out) {
    if (s->count < 3) return false;
    double diagonal = s->m[0][0] * s->m[1][1] * s->m[2][2];
    double c00 = s->m[1][1] * s->m[2][2] - s->m[1][2] * s->m[2][1];
    double c01 = s->m[1][2] * s->m[2][0] - s->m[1][0] * s->m[2][2];
    double c02 = s->m[1][0] * s->m[2][1] - s->m[1][1] * s->m[2][0];
    double det = s->m[0][0] * c00 + s->m[0][1] * c01 + s->m[0][2] * c02;
    /* Hadamard ratio det / prod(diagonal) in (0, 1]: near 0 the features are dependent. */
    if (!(diagonal > 0.0) || det < MIN_FIT_CONDITION * diagonal) return false;
    double x[3];
    if (!solve3((const double(*)[3])s->m, s->r, x)) return false;
    out->x = (float)x[0];
    out->y = (float)x[1];
    return isfinite(out->x) && isfinite(out->y);
}

static void compute_vertex_quadrics(void *user, size_t job, int thread_index) {
    quadric_job *qj = user;
    meso_mesh *mesh = qj->mesh;
    thread_scratch *s = &qj->scratch[thread_index];
    size_t end = (job + 1) * JOB_SIZE;
    if (end > mesh->num_vertices) end = mesh->num_vertices;
    for (size_t v = job * JOB_SIZE; v < end; v++) {
        meso_vec3 n = mesh->normals[v];
        /* Oliveira & Policarpo 2005: the quadric lives in the tangent frame that the relief
         * map is traced in, x along T and y along B. */
        meso_vec3 x_axis = meso_vec3_normalize(mesh->tangents[v]);
        meso_vec3 y_axis = meso_vec3_normalize(mesh->bitangents[v]);
        double cos_xy = meso_vec3_dot(x_axis, y_axis);
        if (meso_vec3_length(x_axis) < 0.5f || meso_vec3_length(y_axis) < 0.5f ||
            1.0 - cos_xy * cos_xy < 1e-4) {
            x_axis = geom_any_perpendicular(n);
            y_axis = meso_vec3_cross(n, x_axis);
            cos_xy = 0.0;
        }
        uint32_t group = qj->weld.group[v];
        uint32_t stamp = (uint32_t)v + 1;
        s->stamp[group] = stamp;
        size_t one = gather_ring(qj, group, &n, stamp, s, 0);
        quadric_sums sums = {0};
        add_samples(qj, v, x_axis, y_axis, cos_xy, s->list, one, &sums);
        meso_vec2 q = {0.0f, 0.0f};
        if (one < MIN_RING_POINTS || !solve_quadric(&sums, &q)) {
            size_t two = one;
            for (size_t i = 0; i < one; i++) two = gather_ring(qj, s->list[i], NULL, stamp, s, two);
            add_samples(qj, v, x_axis, y_axis, cos_xy, s->list + one, two - one, &sums);
            if (!solve_quadric(&sums, &q)) {
                /* Cannot separate the two directions: one isotropic quadric. */
                double a = sums.rrrr > 0.0 ? sums.rrz / sums.rrrr : 0.0;
                q = meso_vec2_make((float)a, (float)a);
            }
        }
        mesh->quadrics[v] = q;
    }
}

meso_result meso_mesh_compute_quadrics(meso_context *ctx, meso_mesh *mesh) {
    if (!mesh->tangents || !mesh->bitangents)
        return meso_log_error(
            ctx, MESO_ERROR_INVALID_ARGUMENT,
            "mesh: quadrics need tangents; call meso_mesh_compute_tangents first");
    int threads = meso_context_num_threads(ctx);
    quadric_job qj = {mesh, {NULL, NULL}, {0}, NULL};
    meso_vec2 *quadrics = malloc((mesh->num_vertices ? mesh->num_vertices : 1) * sizeof(meso_vec2));
    qj.scratch = calloc((size_t)threads, sizeof(thread_scratch));
    meso_result r = MESO_OK;
    if (!quadrics || !qj.scratch) goto out_of_memory;
    r = geom_vertex_faces_build(ctx, mesh, &qj.adjacency);
    if (r != MESO_OK) goto fail;
    r = geom_weld_build(ctx, mesh, &qj.weld);
    if (r != MESO_OK) goto fail;
    size_t groups = qj.weld.num_groups ? qj.weld.num_groups : 1;
    for (int t = 0; t < threads; t++) {
        qj.scratch[t].stamp = calloc(groups, sizeof(uint32_t));
        qj.scratch[t].list = malloc(groups * sizeof(uint32_t));
        if (!qj.scratch[t].stamp || !qj.scratch[t].list) goto out_of_memory;
    }
    free(mesh->quadrics);
    mesh->quadrics = quadrics;
    quadrics = NULL;
    meso_parallel_for(ctx, (mesh->num_vertices + JOB_SIZE - 1) / JOB_SIZE, compute_vertex_quadrics,
                      &qj);
    goto fail; /* the shared cleanup */
out_of_memory:
    r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY,
                       "mesh: out of memory for the quadrics of %zu vertices", mesh->num_vertices);
fail:
    if (qj.scratch)
        for (int t = 0; t < threads; t++) free(qj.scratch[t].stamp), free(qj.scratch[t].list);
    free(qj.scratch);
    geom_weld_free(&qj.weld);
    geom_vertex_faces_free(&qj.adjacency);
    free(quadrics);
    return r;
}
