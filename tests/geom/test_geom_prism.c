/* The shell's prisms (meso/prism.h): shared fins without cracks, the texture <-> object
 * mapping, Fig. 5's exit point, and a ray along a fin that stays in its own prism. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"
#include "meso/prism.h"

static meso_mesh *make_shape(meso_context *ctx, meso_shape_kind kind, int segments) {
    meso_mesh *mesh = NULL;
    meso_shape_desc desc = {.kind = kind, .segments = segments};
    assert_int_equal(meso_mesh_create_shape(ctx, &desc, &mesh), MESO_OK);
    return mesh;
}

static bool same_point(meso_vec3 a, meso_vec3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

/* Every drawn fin triangle of a closed mesh has a twin: the same three positions, bit for bit,
 * wound the other way (the neighbour prism's copy), so the two prisms meet without a crack and
 * back-face culling keeps exactly one of them. */
static void test_closed_mesh_fins_have_bit_identical_twins(void **state) {
    meso_context *ctx = test_context(1);
    meso_shape_kind kinds[] = {MESO_SHAPE_SPHERE, MESO_SHAPE_TORUS};
    for (size_t k = 0; k < 2; k++) {
        meso_mesh *mesh = make_shape(ctx, kinds[k], 12);
        meso_prism_layer *layer = NULL;
        assert_int_equal(meso_prism_layer_create(ctx, mesh, 0.1f, "shape", &layer), MESO_OK);
        const meso_mesh *faces = layer->faces;
        assert_int_equal(faces->num_triangles, 8 * mesh->num_triangles);
        size_t fins = 0, twins = 0;
        for (size_t p = 0; p < layer->num_prisms; p++) {
            if (!layer->prisms[p].valid) continue;
            for (int slot = MESO_PRISM_FIN; slot < MESO_PRISM_NUM_FACES; slot++) {
                size_t f = meso_prism_layer_face(layer, p, slot);
                const uint32_t *a = faces->indices + 3 * f;
                fins++;
                bool found = false;
                for (size_t q = 0; q < layer->num_prisms && !found; q++) {
                    if (q == p || !layer->prisms[q].valid) continue;
                    for (int s = MESO_PRISM_FIN; s < MESO_PRISM_NUM_FACES && !found; s++) {
                        const uint32_t *b = faces->indices + 3 * meso_prism_layer_face(layer, q, s);
                        for (int r = 0; r < 3 && !found; r++) /* reversed, any rotation */
                            found = same_point(faces->positions[a[0]],
                                               faces->positions[b[(r + 2) % 3]]) &&
                                    same_point(faces->positions[a[1]],
                                               faces->positions[b[(r + 1) % 3]]) &&
                                    same_point(faces->positions[a[2]], faces->positions[b[r]]);
                    }
                }
                twins += found;
            }
        }
        assert_true(fins > 0);
        assert_int_equal(twins, fins);
        meso_prism_layer_destroy(layer);
        meso_mesh_destroy(mesh);
    }
    meso_context_destroy(ctx);
}

/* Faces are wound counter-clockwise seen from outside their prism: every face plane has the
 * prism's centroid behind it. */
static void test_faces_face_out_of_their_prism(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *mesh = make_shape(ctx, MESO_SHAPE_TORUS, 10);
    meso_prism_layer *layer = NULL;
    assert_int_equal(meso_prism_layer_create(ctx, mesh, 0.08f, "torus", &layer), MESO_OK);
    for (size_t p = 0; p < layer->num_prisms; p++) {
        const meso_prism *prism = &layer->prisms[p];
        assert_true(prism->valid);
        meso_vec3 centre = {0};
        for (int i = 0; i < 3; i++)
            centre = meso_vec3_add(
                centre,
                meso_vec3_add(mesh->positions[prism->vertices[i]],
                              meso_prism_shell_point(mesh, prism->vertices[i], 1.0f, 0.08f)));
        centre = meso_vec3_scale(centre, 1.0f / 6.0f);
        for (int slot = 0; slot < MESO_PRISM_NUM_FACES; slot++) {
            const meso_prism_plane *pl = &layer->planes[p * MESO_PRISM_NUM_FACES + (size_t)slot];
            assert_true(meso_vec3_dot(pl->normal, centre) - pl->offset < 0.0f);
        }
    }
    meso_prism_layer_destroy(layer);
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

/* meso_prism_map puts the vertices' (u, v, w) on the extruded vertices and is linear between. */
static void test_map_reaches_the_extruded_vertices(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *mesh = make_shape(ctx, MESO_SHAPE_SPHERE, 8);
    const float depth = 0.2f;
    for (size_t t = 0; t < mesh->num_triangles; t++) {
        meso_prism prism;
        if (!meso_prism_init(&prism, mesh, t)) continue;
        for (int i = 0; i < 3; i++) {
            uint32_t v = prism.vertices[i];
            for (int w = 0; w <= 1; w++) {
                meso_vec3 uvw = {mesh->uvs[v].x, mesh->uvs[v].y, (float)w};
                meso_vec3 p = meso_prism_map(&prism, mesh, depth, uvw, -1);
                meso_vec3 q = meso_vec3_madd(mesh->positions[v], mesh->normals[v], -depth * w);
                assert_float_equal(meso_vec3_length(meso_vec3_sub(p, q)), 0.0f, 1e-5f);
            }
        }
        /* the centroid at half depth: the mean of the six corners */
        meso_vec3 uvw = {0.0f, 0.0f, 0.5f}, expect = {0};
        for (int i = 0; i < 3; i++) {
            uint32_t v = prism.vertices[i];
            uvw.x += mesh->uvs[v].x / 3.0f, uvw.y += mesh->uvs[v].y / 3.0f;
            expect = meso_vec3_add(
                expect,
                meso_vec3_scale(meso_vec3_madd(mesh->positions[v], mesh->normals[v], -0.5f * depth),
                                1.0f / 3.0f));
        }
        meso_vec3 p = meso_prism_map(&prism, mesh, depth, uvw, -1);
        assert_float_equal(meso_vec3_length(meso_vec3_sub(p, expect)), 0.0f, 1e-5f);
    }
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

/* meso_prism_unmap inverts meso_prism_map inside a curved prism (a coarse sphere's: its vertex
 * normals turn by 45 degrees across a triangle): from a guess a hundredth of the prism off, one
 * Newton step is within 2e-4 prism widths of the texture point (3.6e-5 measured) and three
 * within 1e-5 (4.3e-6: rounding); from a quarter off, one step is not, but steps until one
 * moves less than the tolerance are. */
static void test_unmap_inverts_the_map_in_a_curved_prism(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *mesh = make_shape(ctx, MESO_SHAPE_SPHERE, 8);
    const float depth = 0.2f;
    int checked = 0;
    float worst1 = 0.0f, worst3 = 0.0f, worst_far1 = 0.0f, worst_until = 0.0f;
    for (size_t t = 0; t < mesh->num_triangles; t++) {
        meso_prism prism;
        if (!meso_prism_init(&prism, mesh, t)) continue;
        for (int k = 0; k < 8; k++) {
            float b1 = 0.1f + 0.1f * (float)(k % 3), b2 = 0.15f + 0.08f * (float)(k % 4);
            float w = (float)k / 7.0f;
            meso_vec2 uv0 = prism.uv[0], uv1 = prism.uv[1], uv2 = prism.uv[2];
            meso_vec3 uvw = {uv0.x + b1 * (uv1.x - uv0.x) + b2 * (uv2.x - uv0.x),
                             uv0.y + b1 * (uv1.y - uv0.y) + b2 * (uv2.y - uv0.y), w};
            meso_vec3 x = meso_prism_map(&prism, mesh, depth, uvw, -1);
            float span = hypotf(uv1.x - uv0.x, uv1.y - uv0.y);
            meso_vec3 guess = {uvw.x + 0.01f * span, uvw.y - 0.01f * span, w + 0.01f};
            meso_vec3 one = meso_prism_unmap(&prism, mesh, depth, x, guess, 1, 0.0f);
            meso_vec3 three = meso_prism_unmap(&prism, mesh, depth, x, guess, 3, 0.0f);
            worst1 = fmaxf(worst1, meso_vec3_length(meso_vec3_sub(one, uvw)) / span);
            worst3 = fmaxf(worst3, meso_vec3_length(meso_vec3_sub(three, uvw)) / span);
            /* from a guess a quarter of the prism off, as a ray's midpoint in a sharply
             * turning shell: one step is not enough, steps until one is small are */
            meso_vec3 far = {uvw.x + 0.25f * span, uvw.y - 0.25f * span, w + 0.25f};
            meso_vec3 far1 = meso_prism_unmap(&prism, mesh, depth, x, far, 1, 0.0f);
            meso_vec3 until = meso_prism_unmap(&prism, mesh, depth, x, far, 4, 1e-3f * span);
            worst_far1 = fmaxf(worst_far1, meso_vec3_length(meso_vec3_sub(far1, uvw)) / span);
            worst_until = fmaxf(worst_until, meso_vec3_length(meso_vec3_sub(until, uvw)) / span);
            checked++;
        }
    }
    assert_true(checked > 100);
    print_message("unmap from a quarter off: %g after one step, %g after steps to 1e-3\n",
                  (double)worst_far1, (double)worst_until);
    if (worst1 > 2e-4f || worst3 > 1e-5f)
        fail_msg("unmap off by %g (1 step), %g (3 steps) prism widths", worst1, worst3);
    /* measured 0.024 and 4.1e-6 */
    assert_true(worst_far1 > 1e-2f);
    assert_true(worst_until < 1e-5f);
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

/* On the plane (two prisms), a ray straight down from the top leaves through the bottom one
 * depth below with w = 1 and the same uv; a slanted one through a fin, where the fin's (u, v, w)
 * is the analytic crossing. */
static void test_exit_on_a_plane_is_exact(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *mesh = make_shape(ctx, MESO_SHAPE_PLANE, 1); /* size 2, y = 0, normal +y */
    const float depth = 0.25f;
    meso_prism_layer *layer = NULL;
    assert_int_equal(meso_prism_layer_create(ctx, mesh, depth, "plane", &layer), MESO_OK);
    for (size_t p = 0; p < layer->num_prisms; p++) {
        const meso_prism *prism = &layer->prisms[p];
        meso_vec2 uv = {0.0f, 0.0f};
        for (int i = 0; i < 3; i++) uv.x += prism->uv[i].x / 3.0f, uv.y += prism->uv[i].y / 3.0f;
        meso_vec3 origin = meso_prism_map(prism, mesh, depth, (meso_vec3){uv.x, uv.y, 0.0f}, -1);
        float t;
        int slot;
        assert_true(meso_prism_layer_exit(layer, p, origin, (meso_vec3){0.0f, -1.0f, 0.0f},
                                          MESO_PRISM_TOP, &t, &slot));
        assert_int_equal(slot, MESO_PRISM_BOTTOM);
        assert_float_equal(t, depth, 1e-6f);
        meso_vec3 exit = meso_vec3_madd(origin, (meso_vec3){0.0f, -1.0f, 0.0f}, t);
        meso_vec3 uvw =
            meso_prism_layer_face_uvw(layer, meso_prism_layer_face(layer, p, slot), exit);
        assert_float_equal(uvw.x, uv.x, 1e-6f);
        assert_float_equal(uvw.y, uv.y, 1e-6f);
        assert_float_equal(uvw.z, 1.0f, 1e-6f);
    }
    /* toward the plane's border x = +1 (u = 1), 45 degrees down, from x = 0.9: through the
     * border fin at x = 1, 0.1 below the top: w = 0.4, u = 1 */
    meso_vec3 origin = {0.9f, 0.0f, 0.3f}, dir = meso_vec3_normalize((meso_vec3){1, -1, 0});
    size_t prism = SIZE_MAX;
    for (size_t p = 0; p < layer->num_prisms; p++) {
        float b[3];
        meso_prism_weights(&layer->prisms[p], (meso_vec2){0.95f, 0.35f}, b);
        if (b[0] >= 0.0f && b[1] >= 0.0f && b[2] >= 0.0f) prism = p;
    }
    assert_true(prism != SIZE_MAX);
    float t;
    int slot;
    assert_true(meso_prism_layer_exit(layer, prism, origin, dir, MESO_PRISM_TOP, &t, &slot));
    assert_true(slot >= MESO_PRISM_FIN);
    assert_float_equal(t, 0.1f * sqrtf(2.0f), 1e-5f);
    meso_vec3 uvw = meso_prism_layer_face_uvw(layer, meso_prism_layer_face(layer, prism, slot),
                                              meso_vec3_madd(origin, dir, t));
    assert_float_equal(uvw.x, 1.0f, 1e-5f);
    assert_float_equal(uvw.y, 0.35f, 1e-5f);
    assert_float_equal(uvw.z, 0.4f, 1e-5f);
    meso_prism_layer_destroy(layer);
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

/* Rays entering a prism of a curved mesh (convex and concave fins: the torus' inside) leave it
 * where its own (u, v, w) volume ends: the exit's uv lies in the prism's UV triangle and w in
 * [0, 1], even for rays that run along a fin a hair inside it -- they never leak into the
 * neighbour's volume. */
static void test_rays_along_fins_stay_in_their_prism(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *mesh = make_shape(ctx, MESO_SHAPE_TORUS, 12);
    const float depth = 0.1f;
    meso_prism_layer *layer = NULL;
    assert_int_equal(meso_prism_layer_create(ctx, mesh, depth, "torus", &layer), MESO_OK);
    size_t convex = 0, concave = 0;
    for (size_t i = 0; i < 3 * layer->num_prisms; i++) layer->fin_convex[i] ? convex++ : concave++;
    assert_true(convex > 0 && concave > 0);
    unsigned seed = 7;
    float worst = 0.0f;
    for (size_t p = 0; p < layer->num_prisms; p += 3) {
        const meso_prism *prism = &layer->prisms[p];
        for (int e = 0; e < 3; e++) {
            /* start a hair inside edge e on the top, heading down along the fin's plane */
            meso_vec2 a = prism->uv[e], b = prism->uv[(e + 1) % 3], c = prism->uv[(e + 2) % 3];
            for (int k = 0; k < 8; k++) {
                float s = 0.1f + 0.8f * test_uniform(&seed);
                meso_vec2 on = {a.x + (b.x - a.x) * s, a.y + (b.y - a.y) * s};
                meso_vec2 in = {on.x + 1e-4f * (c.x - on.x), on.y + 1e-4f * (c.y - on.y)};
                meso_vec3 top = meso_prism_map(prism, mesh, depth, (meso_vec3){in.x, in.y, 0}, -1);
                meso_vec3 bottom =
                    meso_prism_map(prism, mesh, depth, (meso_vec3){on.x, on.y, 1.0f}, -1);
                /* toward a point on the fin's bottom edge (through the fin) or along it */
                meso_vec3 dir = meso_vec3_normalize(meso_vec3_sub(bottom, top));
                float t;
                int slot;
                assert_true(meso_prism_layer_exit(layer, p, top, dir, MESO_PRISM_TOP, &t, &slot));
                assert_true(t >= 0.0f && t < 2.0f * depth + 1.0f);
                meso_vec3 uvw = meso_prism_layer_face_uvw(
                    layer, meso_prism_layer_face(layer, p, slot), meso_vec3_madd(top, dir, t));
                float w[3];
                meso_prism_weights(prism, (meso_vec2){uvw.x, uvw.y}, w);
                float least = fminf(w[0], fminf(w[1], w[2]));
                worst = fminf(worst, least);
                assert_true(least > -2e-3f);
                assert_true(uvw.z > -1e-3f && uvw.z < 1.0f + 1e-3f);
            }
        }
    }
    print_message("least barycentric weight of an exit: %g\n", (double)worst);
    meso_prism_layer_destroy(layer);
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

/* The exit and face_uvw as they were computed one plane and one point at a time, before the
 * 8-wide plane test and the per-face constants: the library must give these bits. */
static float scalar_leave_time(const meso_prism_plane *pl, meso_vec3 o, meso_vec3 d,
                               float tolerance, bool partner) {
    float dn = meso_vec3_dot(pl->normal, d);
    float s0 = meso_vec3_dot(pl->normal, o) - pl->offset;
    if (dn > 0.0f) return s0 >= 0.0f ? 0.0f : -s0 / dn;
    return s0 > tolerance && !partner ? 0.0f : INFINITY;
}

static bool scalar_exit(const meso_prism_layer *layer, size_t prism, meso_vec3 origin,
                        meso_vec3 direction, int entry_slot, float *out_t, int *out_slot) {
    const meso_prism_plane *pl = layer->planes + prism * MESO_PRISM_NUM_FACES;
    float tolerance = 1e-5f * (fabsf(origin.x) + fabsf(origin.y) + fabsf(origin.z) + layer->depth);
    float best = INFINITY;
    int best_slot = -1;
    for (int slot = 0; slot < MESO_PRISM_NUM_FACES; slot += slot < MESO_PRISM_FIN ? 1 : 2) {
        float t;
        int which = slot;
        if (slot < MESO_PRISM_FIN) {
            t = slot == entry_slot
                    ? INFINITY
                    : scalar_leave_time(&pl[slot], origin, direction, tolerance, false);
        } else {
            float t1 = slot == entry_slot ? INFINITY
                                          : scalar_leave_time(&pl[slot], origin, direction,
                                                              tolerance, slot + 1 == entry_slot);
            float t2 = slot + 1 == entry_slot ? INFINITY
                                              : scalar_leave_time(&pl[slot + 1], origin, direction,
                                                                  tolerance, slot == entry_slot);
            bool convex = layer->fin_convex[3 * prism + (size_t)(slot - MESO_PRISM_FIN) / 2];
            bool first = convex ? t1 <= t2 : t1 >= t2;
            t = first ? t1 : t2;
            which = first ? slot : slot + 1;
        }
        if (t < best) {
            best = t;
            best_slot = which;
        }
    }
    *out_t = best;
    *out_slot = best_slot;
    return best_slot >= 0;
}

static meso_vec3 scalar_face_uvw(const meso_prism_layer *layer, size_t face, meso_vec3 x) {
    const uint32_t *idx = layer->faces->indices + 3 * face;
    const meso_vec3 *p = layer->faces->positions;
    meso_vec3 e1 = meso_vec3_sub(p[idx[1]], p[idx[0]]), e2 = meso_vec3_sub(p[idx[2]], p[idx[0]]);
    meso_vec3 d = meso_vec3_sub(x, p[idx[0]]);
    float d00 = meso_vec3_dot(e1, e1), d01 = meso_vec3_dot(e1, e2), d11 = meso_vec3_dot(e2, e2);
    float d20 = meso_vec3_dot(d, e1), d21 = meso_vec3_dot(d, e2);
    float det = d00 * d11 - d01 * d01;
    float b1 = 0.0f, b2 = 0.0f;
    if (det > 0.0f) {
        b1 = (d11 * d20 - d01 * d21) / det;
        b2 = (d00 * d21 - d01 * d20) / det;
    }
    return meso_vec3_barycentric(layer->uvws[idx[0]], layer->uvws[idx[1]], layer->uvws[idx[2]],
                                 1.0f - b1 - b2, b1, b2);
}

static bool same_bits(float a, float b) { return memcmp(&a, &b, sizeof a) == 0; }

/* meso_prism_layer_exit tests the 8 planes at once and face_uvw reads per-face constants: the
 * same bits as the one-at-a-time computation, for rays from every face slot (and from inside)
 * in every direction, on a torus (convex and concave fins). */
static void test_exit_and_face_uvw_match_the_scalar_computation(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *mesh = make_shape(ctx, MESO_SHAPE_TORUS, 10);
    meso_prism_layer *layer = NULL;
    assert_int_equal(meso_prism_layer_create(ctx, mesh, 0.1f, "torus", &layer), MESO_OK);
    unsigned seed = 11;
    size_t checked = 0;
    for (size_t p = 0; p < layer->num_prisms; p++) {
        for (int k = 0; k < 40; k++) {
            float r[6];
            for (int i = 0; i < 6; i++) r[i] = test_uniform(&seed);
            float a = r[0], b = r[1] * (1.0f - a);
            meso_vec3 uvw = {0, 0, r[2]};
            const meso_prism *prism = &layer->prisms[p];
            uvw.x = prism->uv[0].x * (1.0f - a - b) + prism->uv[1].x * a + prism->uv[2].x * b;
            uvw.y = prism->uv[0].y * (1.0f - a - b) + prism->uv[1].y * a + prism->uv[2].y * b;
            int entry = k % 9 - 1; /* -1 (inside) and every slot */
            if (entry == MESO_PRISM_TOP) uvw.z = 0.0f;
            if (entry == MESO_PRISM_BOTTOM) uvw.z = 1.0f;
            meso_vec3 origin = meso_prism_map(prism, mesh, 0.1f, uvw, -1);
            meso_vec3 dir = meso_vec3_normalize((meso_vec3){r[3] - 0.5f, r[4] - 0.5f, r[5] - 0.5f});
            float t0, t1;
            int s0, s1;
            bool ok0 = scalar_exit(layer, p, origin, dir, entry, &t0, &s0);
            bool ok1 = meso_prism_layer_exit(layer, p, origin, dir, entry, &t1, &s1);
            assert_true(ok0 == ok1);
            assert_int_equal(s0, s1);
            assert_true(same_bits(t0, t1));
            if (!ok0 || !isfinite(t0)) continue;
            size_t face = meso_prism_layer_face(layer, p, s0);
            meso_vec3 x = meso_vec3_madd(origin, dir, t0);
            meso_vec3 u0 = scalar_face_uvw(layer, face, x);
            meso_vec3 u1 = meso_prism_layer_face_uvw(layer, face, x);
            assert_true(same_bits(u0.x, u1.x) && same_bits(u0.y, u1.y) && same_bits(u0.z, u1.z));
            checked++;
        }
    }
    print_message("exits compared bit for bit: %zu\n", checked);
    assert_true(checked > 1000);
    meso_prism_layer_destroy(layer);
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

static int compare_floats(const void *a, const void *b) {
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/* A shell deeper than the surface's radius of curvature folds: a cylinder of radius 0.6 in a
 * shell 0.75 deep crosses its axis at w = 0.8. Every prism's bottom triangle comes out mirrored
 * (its outward normal pointing up) and the fins over its circumferential edges are bow ties.
 * Before meso_prism_layer_create unbound those planes, a ray entering through the top left at
 * t = 0 through the bottom. Now no ray leaves through the bottom, and the exit lies in the
 * prism: the map takes its (u, v, w) back to within 0.05 of it (the fins' flat triangles against
 * the map's bilinear fins). A ray from the top toward the axis stays in its prism's volume
 * down to the axis: most get there (the median exit). The fins over the grid's diagonals are
 * twisted past the fold, and their flat triangles end some rays early (docs/techniques/gdm.md,
 * "folded prisms"). A shell 0.5 deep does not fold. */
static void test_folded_prisms_are_left_through_their_fins(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *mesh = make_shape(ctx, MESO_SHAPE_CYLINDER, 16);
    meso_prism_layer *layer = NULL;
    assert_int_equal(meso_prism_layer_create(ctx, mesh, 0.5f, "cylinder", &layer), MESO_OK);
    assert_int_equal(layer->num_folded, 0);
    meso_prism_layer_destroy(layer);
    const float depth = 0.75f;
    assert_int_equal(meso_prism_layer_create(ctx, mesh, depth, "cylinder", &layer), MESO_OK);
    float *exits = malloc(layer->num_prisms * sizeof *exits);
    assert_non_null(exits);
    size_t valid = 0;
    float worst_off = 0.0f;
    unsigned seed = 5;
    for (size_t p = 0; p < layer->num_prisms; p++) {
        const meso_prism *prism = &layer->prisms[p];
        if (!prism->valid) continue;
        /* from a point of the top toward the axis at its height, a little off */
        float a = 0.2f + 0.6f * test_uniform(&seed), b = (0.8f - a) * test_uniform(&seed);
        meso_vec3 uvw = {0.0f, 0.0f, 0.0f};
        uvw.x = prism->uv[0].x * (1.0f - a - b) + prism->uv[1].x * a + prism->uv[2].x * b;
        uvw.y = prism->uv[0].y * (1.0f - a - b) + prism->uv[1].y * a + prism->uv[2].y * b;
        meso_vec3 origin = meso_prism_map(prism, mesh, depth, uvw, -1);
        meso_vec3 aim = {0.02f * (test_uniform(&seed) - 0.5f), origin.y,
                         0.02f * (test_uniform(&seed) - 0.5f)};
        meso_vec3 dir = meso_vec3_normalize(meso_vec3_sub(aim, origin));
        float t;
        int slot;
        assert_true(meso_prism_layer_exit(layer, p, origin, dir, MESO_PRISM_TOP, &t, &slot));
        assert_true(slot >= MESO_PRISM_FIN);
        assert_true(t > 0.0f);
        exits[valid++] = t;
        meso_vec3 x = meso_vec3_madd(origin, dir, t);
        meso_vec3 exit = meso_prism_layer_face_uvw(layer, meso_prism_layer_face(layer, p, slot), x);
        meso_vec3 back = meso_prism_map(prism, mesh, depth, exit, -1);
        worst_off = fmaxf(worst_off, meso_vec3_length(meso_vec3_sub(back, x)));
    }
    qsort(exits, valid, sizeof *exits, compare_floats);
    float median = exits[valid / 2];
    print_message("folded prisms: %zu of %zu; exits at t %g (least), %g (median), %g (most), "
                  "mapped back within %g\n",
                  layer->num_folded, valid, (double)exits[0], (double)median,
                  (double)exits[valid - 1], (double)worst_off);
    assert_int_equal(layer->num_folded, valid);
    assert_true(median > 0.5f && median < 0.7f); /* the axis is 0.57 to 0.6 away */
    assert_true(worst_off < 0.05f);
    free(exits);
    meso_prism_layer_destroy(layer);
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

static void test_layer_refuses_bad_input_naming_it(void **state) {
    meso_context *ctx = test_context(1);
    meso_mesh *mesh = make_shape(ctx, MESO_SHAPE_PLANE, 1);
    meso_prism_layer *layer = (meso_prism_layer *)1;
    assert_int_equal(meso_prism_layer_create(ctx, mesh, 0.0f, "floor", &layer),
                     MESO_ERROR_INVALID_ARGUMENT);
    assert_null(layer);
    assert_non_null(strstr(meso_context_last_error(ctx), "floor: mesostructure.depth"));
    meso_vec2 *uvs = mesh->uvs;
    mesh->uvs = NULL;
    layer = (meso_prism_layer *)1;
    assert_int_equal(meso_prism_layer_create(ctx, mesh, 0.1f, "floor", &layer),
                     MESO_ERROR_INVALID_ARGUMENT);
    assert_null(layer);
    assert_non_null(strstr(meso_context_last_error(ctx), "texture coordinates"));
    mesh->uvs = uvs;
    meso_prism_layer_destroy(NULL);
    meso_mesh_destroy(mesh);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_closed_mesh_fins_have_bit_identical_twins),
        cmocka_unit_test(test_faces_face_out_of_their_prism),
        cmocka_unit_test(test_map_reaches_the_extruded_vertices),
        cmocka_unit_test(test_unmap_inverts_the_map_in_a_curved_prism),
        cmocka_unit_test(test_exit_on_a_plane_is_exact),
        cmocka_unit_test(test_rays_along_fins_stay_in_their_prism),
        cmocka_unit_test(test_exit_and_face_uvw_match_the_scalar_computation),
        cmocka_unit_test(test_folded_prisms_are_left_through_their_fins),
        cmocka_unit_test(test_layer_refuses_bad_input_naming_it),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
