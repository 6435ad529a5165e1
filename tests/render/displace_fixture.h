/* Test fixture shared by test_technique_displacement.c and test_technique_tessellation.c: a
 * hand-built scene of one object (closed meshes whose shared vertices are bit-identical, height
 * fields made in place), and the crack checker. Header-only (static functions). */
#ifndef DISPLACE_FIXTURE_H
#define DISPLACE_FIXTURE_H

#include "test_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "render_internal.h"

typedef struct fixture {
    meso_context *ctx;
    meso_scene scene;
    meso_object object;
    meso_heightfield heightfield;
    float *heights;
    meso_mesh *mesh;
    meso_frame frame;
} fixture;

typedef enum fixture_field {
    FIELD_BUMPS,    /* smooth bumps plus a sharp groove: every test has something to find */
    FIELD_CONSTANT, /* every texel `value` */
} fixture_field;

static void fixture_heights(fixture *f, int size, fixture_field kind, float value) {
    free(f->heights);
    f->heights = malloc((size_t)size * (size_t)size * sizeof(float));
    assert_non_null(f->heights);
    for (int j = 0; j < size; j++)
        for (int i = 0; i < size; i++) {
            float x = ((float)i + 0.5f) / (float)size, y = ((float)j + 0.5f) / (float)size;
            float h = value;
            if (kind == FIELD_BUMPS) {
                h = 0.5f + 0.4f * sinf(2.0f * MESO_PI * 3.0f * x) * sinf(2.0f * MESO_PI * 2.0f * y);
                if (fabsf(x - 0.5f) < 0.04f) h = 0.0f; /* a groove */
            }
            f->heights[(size_t)j * (size_t)size + (size_t)i] = h;
        }
    f->heightfield = (meso_heightfield){
        .width = size, .height = size, .heights = f->heights, .wrap = MESO_WRAP_REPEAT};
}

static void fixture_alloc_frames(fixture *f) {
    f->mesh->tangents = calloc(f->mesh->num_vertices, sizeof(meso_vec3));
    f->mesh->bitangents = calloc(f->mesh->num_vertices, sizeof(meso_vec3));
    assert_non_null(f->mesh->tangents);
    assert_non_null(f->mesh->bitangents);
}

/* The built-in plane's parametrisation (docs/design.md) on a cells x cells grid, side 2. */
static void fixture_plane(fixture *f, int cells) {
    size_t side = (size_t)cells + 1;
    assert_int_equal(
        meso_mesh_create(f->ctx, side * side, (size_t)cells * (size_t)cells * 2, true, &f->mesh),
        MESO_OK);
    fixture_alloc_frames(f);
    for (size_t j = 0; j < side; j++)
        for (size_t i = 0; i < side; i++) {
            size_t k = j * side + i;
            float u = (float)i / (float)cells, v = (float)j / (float)cells;
            f->mesh->positions[k] = (meso_vec3){-1.0f + 2.0f * u, 0.0f, 1.0f - 2.0f * v};
            f->mesh->normals[k] = (meso_vec3){0, 1, 0};
            f->mesh->uvs[k] = (meso_vec2){u, v};
            f->mesh->tangents[k] = (meso_vec3){2, 0, 0};
            f->mesh->bitangents[k] = (meso_vec3){0, 0, -2};
        }
    uint32_t *t = f->mesh->indices;
    for (size_t j = 0; j < (size_t)cells; j++)
        for (size_t i = 0; i < (size_t)cells; i++) {
            uint32_t a = (uint32_t)(j * side + i), b = a + 1, c = a + (uint32_t)side, d = c + 1;
            /* counter-clockwise seen from +y */
            *t++ = a, *t++ = b, *t++ = d;
            *t++ = a, *t++ = d, *t++ = c;
        }
}

/* A torus (major radius 1, minor 0.4), u around the ring, v around the tube, uvs scaled by
 * 2 x 1. The seams carry duplicated vertices whose positions, normals and frames are copies
 * (bit-identical) and whose uvs differ by whole tiles. */
static void fixture_torus(fixture *f, int nu, int nv) {
    size_t su = (size_t)nu + 1, sv = (size_t)nv + 1;
    assert_int_equal(meso_mesh_create(f->ctx, su * sv, (size_t)nu * (size_t)nv * 2, true, &f->mesh),
                     MESO_OK);
    fixture_alloc_frames(f);
    meso_mesh *m = f->mesh;
    for (size_t j = 0; j < sv; j++)
        for (size_t i = 0; i < su; i++) {
            size_t k = j * su + i;
            m->uvs[k] = (meso_vec2){2.0f * (float)i / (float)nu, (float)j / (float)nv};
            if (i == (size_t)nu || j == (size_t)nv) continue; /* copied below */
            float a = 2.0f * MESO_PI * (float)i / (float)nu,
                  b = 2.0f * MESO_PI * (float)j / (float)nv;
            meso_vec3 ring = {cosf(a), 0.0f, -sinf(a)};
            meso_vec3 n = {cosf(b) * ring.x, sinf(b), cosf(b) * ring.z};
            m->positions[k] = meso_vec3_add(ring, meso_vec3_scale(n, 0.4f));
            m->normals[k] = n;
            float r = 1.0f + 0.4f * cosf(b);
            m->tangents[k] = (meso_vec3){-sinf(a) * r * MESO_PI, 0.0f, -cosf(a) * r * MESO_PI};
            m->bitangents[k] =
                (meso_vec3){-sinf(b) * ring.x * 0.8f * MESO_PI, cosf(b) * 0.8f * MESO_PI,
                            -sinf(b) * ring.z * 0.8f * MESO_PI};
        }
    for (size_t j = 0; j < sv; j++)
        for (size_t i = 0; i < su; i++) {
            if (i != (size_t)nu && j != (size_t)nv) continue;
            size_t k = j * su + i, src = (j % (size_t)nv) * su + (i % (size_t)nu);
            m->positions[k] = m->positions[src];
            m->normals[k] = m->normals[src];
            m->tangents[k] = m->tangents[src];
            m->bitangents[k] = m->bitangents[src];
        }
    uint32_t *t = m->indices;
    for (size_t j = 0; j < (size_t)nv; j++)
        for (size_t i = 0; i < (size_t)nu; i++) {
            uint32_t a = (uint32_t)(j * su + i), b = a + 1, c = a + (uint32_t)su, d = c + 1;
            *t++ = a, *t++ = b, *t++ = d;
            *t++ = a, *t++ = d, *t++ = c;
        }
}

/* An icosphere of radius 1 (shared vertices everywhere), planar uvs u = (x + 1) / 2,
 * v = (1 - z) / 2 tiled twice, frames the projection's derivatives made tangent. */
static void fixture_sphere(fixture *f, int subdivisions) {
    const float g = 1.61803398875f;
    meso_vec3 pos[2000];
    uint32_t tri[4000 * 3];
    size_t nv = 0, nt = 0;
    const float base[12][3] = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0},
                               {0, -1, g}, {0, 1, g}, {0, -1, -g}, {0, 1, -g},
                               {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
    const uint32_t faces[20][3] = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                   {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                   {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                   {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
    for (int i = 0; i < 12; i++)
        pos[nv++] = meso_vec3_normalize((meso_vec3){base[i][0], base[i][1], base[i][2]});
    for (int i = 0; i < 20; i++)
        for (int k = 0; k < 3; k++) tri[nt * 3 + (size_t)k] = faces[i][k], nt += k == 2;
    for (int s = 0; s < subdivisions; s++) {
        static uint32_t edge_a[6000], edge_b[6000], edge_m[6000];
        size_t ne = 0, old = nt;
        uint32_t next[4000 * 3];
        size_t count = 0;
        for (size_t t = 0; t < old; t++) {
            uint32_t mid[3];
            for (int k = 0; k < 3; k++) {
                uint32_t a = tri[t * 3 + (size_t)k], b = tri[t * 3 + (size_t)(k + 1) % 3];
                uint32_t lo = a < b ? a : b, hi = a < b ? b : a;
                size_t e = 0;
                while (e < ne && !(edge_a[e] == lo && edge_b[e] == hi)) e++;
                if (e == ne) {
                    edge_a[ne] = lo, edge_b[ne] = hi;
                    pos[nv] = meso_vec3_normalize(meso_vec3_add(pos[lo], pos[hi]));
                    edge_m[ne++] = (uint32_t)nv++;
                }
                mid[k] = edge_m[e];
            }
            const uint32_t *v = &tri[t * 3];
            const uint32_t kids[4][3] = {{v[0], mid[0], mid[2]},
                                         {mid[0], v[1], mid[1]},
                                         {mid[2], mid[1], v[2]},
                                         {mid[0], mid[1], mid[2]}};
            for (int c = 0; c < 4; c++)
                for (int k = 0; k < 3; k++) next[count++] = kids[c][k];
        }
        memcpy(tri, next, count * sizeof(uint32_t));
        nt = count / 3;
    }
    assert_int_equal(meso_mesh_create(f->ctx, nv, nt, true, &f->mesh), MESO_OK);
    fixture_alloc_frames(f);
    for (size_t i = 0; i < nv; i++) {
        meso_vec3 p = pos[i];
        f->mesh->positions[i] = p;
        f->mesh->normals[i] = p;
        f->mesh->uvs[i] = (meso_vec2){p.x + 1.0f, 1.0f - p.z};
        meso_vec3 tx = {0.5f, 0, 0}, tz = {0, 0, -0.5f};
        f->mesh->tangents[i] = meso_vec3_madd(tx, p, -meso_vec3_dot(tx, p));
        f->mesh->bitangents[i] = meso_vec3_madd(tz, p, -meso_vec3_dot(tz, p));
    }
    memcpy(f->mesh->indices, tri, nt * 3 * sizeof(uint32_t));
}

static void fixture_init(fixture *f, int threads) {
    memset(f, 0, sizeof(*f));
    f->ctx = test_context(threads);
    fixture_heights(f, 64, FIELD_BUMPS, 0.0f);
    f->scene.width = f->scene.height = 128;
    f->scene.camera = (meso_camera){{0.0f, 1.5f, 3.5f}, {0, 0, 0}, {0, 1, 0}, 40.0f};
    f->scene.ambient = (meso_vec3){0.1f, 0.1f, 0.1f};
    f->scene.num_lights = 1;
    f->scene.lights[0] =
        (meso_light){.type = MESO_LIGHT_DIRECTIONAL,
                     .direction = meso_vec3_normalize((meso_vec3){0.5f, 0.7f, 0.3f}),
                     .color = {1, 1, 1}};
    f->scene.objects = &f->object;
    f->scene.num_objects = 1;
    snprintf(f->object.name, sizeof(f->object.name), "objects[0]");
    f->object.material.albedo = (meso_vec3){0.8f, 0.8f, 0.8f};
    f->object.mesostructure.kind = MESO_MESOSTRUCTURE_HEIGHT_FIELD;
    f->object.mesostructure.height_field = &f->heightfield;
    f->object.mesostructure.depth = 0.1f;
}

static void fixture_set_option(fixture *f, const char *name, double value) {
    for (int i = 0; i < f->object.num_options; i++)
        if (strcmp(f->object.options[i].name, name) == 0) {
            f->object.options[i].value = value;
            return;
        }
    assert_true(f->object.num_options < MESO_OPTIONS_MAX);
    meso_option *o = &f->object.options[f->object.num_options++];
    snprintf(o->name, sizeof(o->name), "%s", name);
    o->value = value;
}

static void fixture_clear_options(fixture *f) { f->object.num_options = 0; }

static void fixture_deinit(fixture *f) {
    meso_mesh_destroy(f->mesh);
    free(f->heights);
    meso_context_destroy(f->ctx);
}

/* Prepare the technique, run its geometry once; the mesh is valid until release. */
static const meso_mesh *fixture_geometry(fixture *f, const meso_technique *t, void **out_state) {
    f->object.mesh = f->mesh;
    meso_frame_init(&f->frame, &f->scene, f->scene.width, f->scene.height);
    void *state = NULL;
    meso_result r = t->prepare(f->ctx, &f->scene, &f->object, &state);
    if (r != MESO_OK) fail_msg("prepare: %s", meso_context_last_error(f->ctx));
    const meso_mesh *mesh = NULL;
    r = t->geometry(f->ctx, state, &f->frame, &mesh);
    if (r != MESO_OK) fail_msg("geometry: %s", meso_context_last_error(f->ctx));
    assert_non_null(mesh);
    *out_state = state;
    return mesh;
}

/* ---- The crack checker -------------------------------------------------------------------- */

typedef struct fixture_edge {
    uint32_t key[6]; /* the two end points' position bits, smaller first */
} fixture_edge;

static int compare_edges(const void *a, const void *b) {
    const fixture_edge *x = a, *y = b;
    for (int i = 0; i < 6; i++)
        if (x->key[i] != y->key[i]) return x->key[i] < y->key[i] ? -1 : 1;
    return 0;
}

/* Every edge of the mesh, identified by the bit patterns of its end points' positions, is
 * shared by exactly two triangles: no T-junction, no gap. Returns the number of bad edges. */
static size_t fixture_count_open_edges(const meso_mesh *mesh) {
    size_t n = mesh->num_triangles * 3;
    fixture_edge *edges = malloc(n * sizeof(*edges));
    assert_non_null(edges);
    for (size_t t = 0; t < mesh->num_triangles; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t a[3], b[3];
            memcpy(a, &mesh->positions[mesh->indices[t * 3 + (size_t)k]], sizeof(a));
            memcpy(b, &mesh->positions[mesh->indices[t * 3 + (size_t)(k + 1) % 3]], sizeof(b));
            fixture_edge *e = &edges[t * 3 + (size_t)k];
            bool a_first = memcmp(a, b, sizeof(a)) < 0;
            memcpy(e->key, a_first ? a : b, sizeof(a));
            memcpy(e->key + 3, a_first ? b : a, sizeof(a));
        }
    qsort(edges, n, sizeof(*edges), compare_edges);
    size_t bad = 0;
    for (size_t i = 0; i < n;) {
        size_t j = i;
        while (j < n && compare_edges(&edges[i], &edges[j]) == 0) j++;
        bad += (j - i) != 2;
        i = j;
    }
    free(edges);
    return bad;
}

/* ---- Block shading ----------------------------------------------------------------------- */

/* The rasterizer shades a geometry technique's blocks eight fragments at a time
 * (displace_shade8.h): check the same colours, bit for bit, as its per-fragment shade, with a
 * directional light and 2 x 2 PCF, a point light and one tap, and without shadows; fragments at
 * several barycentrics of every triangle (lit, shadowed, at the map's edge) in blocks whose
 * counts are not multiples of eight. `level_option` is the technique's subdivision level
 * option, set to 5. */
static void fixture_check_block_shading(const meso_technique *tech, const char *level_option) {
    fixture f;
    fixture_init(&f, 2);
    fixture_heights(&f, 64, FIELD_CONSTANT, 1.0f);
    for (int j = 0; j < 64; j++)
        for (int i = 24; i < 40; i++) f.heights[j * 64 + i] = (float)((i * 7 + j * 3) % 11) / 10.0f;
    f.object.mesostructure.depth = 0.3f;
    fixture_plane(&f, 1);
    fixture_set_option(&f, level_option, 5);
    fixture_set_option(&f, "shadow_map_size", 256);
    for (int config = 0; config < 3; config++) {
        if (config == 0) {
            f.scene.lights[0].direction = meso_vec3_normalize((meso_vec3){1.0f, 0.5f, 0.0f});
        } else if (config == 1) {
            f.scene.lights[0].type = MESO_LIGHT_POINT;
            f.scene.lights[0].position = (meso_vec3){0.7f, 1.5f, 0.3f};
            fixture_set_option(&f, "shadow_pcf", 0);
        } else {
            fixture_set_option(&f, "shadows", 0);
        }
        void *st = NULL;
        const meso_mesh *mesh = fixture_geometry(&f, tech, &st);
        size_t count = 3 * mesh->num_triangles;
        meso_fragment *per_fragment = calloc(count, sizeof(meso_fragment));
        meso_fragment *per_block = calloc(count, sizeof(meso_fragment));
        assert_non_null(per_fragment);
        assert_non_null(per_block);
        const float weights[3][3] = {
            {1.0f / 3.0f, 1.0f / 3.0f, 1.0f / 3.0f}, {0.8f, 0.1f, 0.1f}, {0.05f, 0.15f, 0.8f}};
        for (size_t t = 0; t < mesh->num_triangles; t++) {
            const uint32_t *i = &mesh->indices[t * 3];
            for (int w = 0; w < 3; w++) {
                const float *b = weights[w];
                meso_fragment frag = {0};
                frag.triangle = (uint32_t)t;
                frag.b0 = b[0], frag.b1 = b[1], frag.b2 = b[2];
                frag.position = meso_vec3_barycentric(mesh->positions[i[0]], mesh->positions[i[1]],
                                                      mesh->positions[i[2]], b[0], b[1], b[2]);
                frag.normal = meso_vec3_normalize(
                    meso_vec3_barycentric(mesh->normals[i[0]], mesh->normals[i[1]],
                                          mesh->normals[i[2]], b[0], b[1], b[2]));
                frag.tangent = meso_vec3_barycentric(mesh->tangents[i[0]], mesh->tangents[i[1]],
                                                     mesh->tangents[i[2]], b[0], b[1], b[2]);
                frag.bitangent =
                    meso_vec3_barycentric(mesh->bitangents[i[0]], mesh->bitangents[i[1]],
                                          mesh->bitangents[i[2]], b[0], b[1], b[2]);
                frag.uv = meso_vec2_barycentric(mesh->uvs[i[0]], mesh->uvs[i[1]], mesh->uvs[i[2]],
                                                b[0], b[1], b[2]);
                frag.depth = frag.out_depth = 1.0f;
                per_fragment[3 * t + (size_t)w] = per_block[3 * t + (size_t)w] = frag;
            }
        }
        tech->shade(st, &f.frame, &f.object, per_fragment, count);
        /* through blocks (meso_technique_shade prefers shade_block), in uneven pieces */
        for (size_t first = 0; first < count;) {
            size_t n = count - first < 1021 ? count - first : 1021;
            assert_int_equal(
                meso_technique_shade(tech, st, &f.frame, &f.object, per_block + first, n), MESO_OK);
            first += n;
        }
        size_t dark = 0, back = 0;
        for (size_t k = 0; k < count; k++) {
            assert_memory_equal(&per_fragment[k].color, &per_block[k].color, sizeof(meso_vec3));
            dark += per_fragment[k].color.x < 0.1f;
            /* the plane is an open surface: fragments of triangles facing away are drawn, in
             * the surface's own shadow (displace_back_face), on both paths alike */
            const uint32_t *i = &mesh->indices[(k / 3) * 3];
            meso_vec3 p0 = mesh->positions[i[0]];
            meso_vec3 face = meso_vec3_cross(meso_vec3_sub(mesh->positions[i[1]], p0),
                                             meso_vec3_sub(mesh->positions[i[2]], p0));
            meso_vec3 to = meso_vec3_sub(per_block[k].position, f.frame.eye);
            back += meso_vec3_dot(to, face) > 0.1f * meso_vec3_length(to) * meso_vec3_length(face);
        }
        if (config < 2) assert_true(dark > 0); /* shadows were looked up */
        assert_true(back > 0);
        free(per_fragment);
        free(per_block);
        tech->release(st);
    }
    fixture_deinit(&f);
}

#endif
