/* `displacement` (uniform): 4^L triangles a base triangle, vertices on the displaced surface of
 * docs/design.md, crack-free on closed meshes, the automatic level, limits, shadows. */
#include "displace_fixture.h"

extern const meso_technique meso_technique_displacement;
static const meso_technique *technique = &meso_technique_displacement;

static void test_displacement_level_makes_four_to_the_level_triangles(void **state) {
    (void)state;
    fixture f;
    fixture_init(&f, 2);
    fixture_torus(&f, 6, 4);
    fixture_set_option(&f, "shadows", 0);
    fixture_set_option(&f, "cluster_culling", 0); /* the whole mesh */
    for (int level = 0; level <= 4; level++) {
        fixture_set_option(&f, "level", level);
        void *st = NULL;
        const meso_mesh *mesh = fixture_geometry(&f, technique, &st);
        assert_int_equal(mesh->num_triangles, f.mesh->num_triangles << (2 * level));
        /* shared vertices within a base triangle: (n+1)(n+2)/2 each */
        size_t n = (size_t)1 << level;
        assert_int_equal(mesh->num_vertices, f.mesh->num_triangles * (n + 1) * (n + 2) / 2);
        assert_int_equal(fixture_count_open_edges(mesh), 0);
        technique->release(st);
    }
    fixture_deinit(&f);
}

static void test_displacement_sphere_has_no_cracks(void **state) {
    (void)state;
    fixture f;
    fixture_init(&f, 2);
    fixture_sphere(&f, 1);
    fixture_set_option(&f, "shadows", 0);
    fixture_set_option(&f, "cluster_culling", 0); /* the whole mesh */
    for (int level = 1; level <= 3; level++) {
        fixture_set_option(&f, "level", level);
        void *st = NULL;
        const meso_mesh *mesh = fixture_geometry(&f, technique, &st);
        assert_int_equal(fixture_count_open_edges(mesh), 0);
        technique->release(st);
    }
    fixture_deinit(&f);
}

/* Cluster culling hands the rasterizer the whole mesh's triangles in order less some, and each
 * one left out faces away from the eye by more than the rasterizer's own early margin (sine
 * 0.01 past edge-on) or lies outside the view frustum: so the rasterizer would have dropped it,
 * and the image is the same. On a closed sphere seen from outside about half are left out. */
static void test_displacement_clusters_left_out_are_back_facing_or_outside(void **state) {
    (void)state;
    fixture f;
    fixture_init(&f, 2);
    fixture_sphere(&f, 2);
    fixture_set_option(&f, "shadows", 0);
    fixture_set_option(&f, "level", 3);
    fixture_set_option(&f, "cluster_culling", 0);
    void *whole_state = NULL, *culled_state = NULL;
    const meso_mesh *whole = fixture_geometry(&f, technique, &whole_state);
    fixture_set_option(&f, "cluster_culling", 1);
    const meso_mesh *culled = fixture_geometry(&f, technique, &culled_state);
    assert_int_equal(culled->num_vertices, whole->num_vertices);
    assert_memory_equal(culled->positions, whole->positions,
                        whole->num_vertices * sizeof(meso_vec3));
    assert_true(culled->num_triangles < whole->num_triangles * 3 / 4);
    assert_true(culled->num_triangles > whole->num_triangles / 4);
    size_t next = 0, left_out = 0;
    for (size_t t = 0; t < whole->num_triangles; t++) {
        const uint32_t *w = whole->indices + 3 * t;
        if (next < culled->num_triangles &&
            memcmp(culled->indices + 3 * next, w, 3 * sizeof(uint32_t)) == 0) {
            next++;
            continue;
        }
        left_out++;
        meso_vec3 p[3] = {whole->positions[w[0]], whole->positions[w[1]], whole->positions[w[2]]};
        meso_vec3 n = meso_vec3_cross(meso_vec3_sub(p[1], p[0]), meso_vec3_sub(p[2], p[0]));
        meso_vec3 to_eye = meso_vec3_sub(f.frame.eye, p[0]);
        double facing = meso_vec3_dot(n, to_eye) / (meso_vec3_length(n) * meso_vec3_length(to_eye));
        bool outside = false;
        for (int axis = 0; axis < 2 && !outside; axis++)
            for (int sign = -1; sign <= 1 && !outside; sign += 2) {
                int beyond = 0;
                for (int k = 0; k < 3; k++) {
                    meso_vec4 c = meso_mat4_mul_vec4(f.frame.view_projection,
                                                     (meso_vec4){p[k].x, p[k].y, p[k].z, 1.0f});
                    beyond += (axis ? c.y : c.x) * (float)sign > c.w;
                }
                outside = beyond == 3;
            }
        assert_true(facing < -0.01 || outside);
    }
    assert_int_equal(next, culled->num_triangles); /* a subsequence, in order */
    assert_int_equal(left_out, whole->num_triangles - culled->num_triangles);
    technique->release(whole_state);
    technique->release(culled_state);
    fixture_deinit(&f);
}

static void test_displacement_vertices_lie_on_the_displaced_plane(void **state) {
    (void)state;
    fixture f;
    fixture_init(&f, 1);
    fixture_plane(&f, 1);
    fixture_set_option(&f, "shadows", 0);
    fixture_set_option(&f, "level", 4);
    void *st = NULL;
    const meso_mesh *mesh = fixture_geometry(&f, technique, &st);
    for (size_t i = 0; i < mesh->num_vertices; i++) {
        meso_vec2 uv = mesh->uvs[i];
        meso_vec3 p = mesh->positions[i];
        /* P(u, v) = (-1 + 2u, 0, 1 - 2v), P' = P - (1 - h(u, v)) depth (0, 1, 0) */
        float h = meso_heightfield_sample(&f.heightfield, uv.x - floorf(uv.x), uv.y - floorf(uv.y));
        assert_float_equal(p.x, -1.0f + 2.0f * uv.x, 1e-5f);
        assert_float_equal(p.z, 1.0f - 2.0f * uv.y, 1e-5f);
        assert_float_equal(p.y, -(1.0f - h) * 0.1f, 1e-6f);
        /* the base frame is carried for shading */
        assert_float_equal(mesh->normals[i].y, 1.0f, 0.0f);
        assert_float_equal(mesh->tangents[i].x, 2.0f, 1e-6f);
    }
    technique->release(st);
    fixture_deinit(&f);
}

static void test_displacement_automatic_level_reaches_texel_density(void **state) {
    (void)state;
    fixture f;
    fixture_init(&f, 1);
    fixture_heights(&f, 64, FIELD_BUMPS, 0.0f);
    fixture_plane(&f, 1); /* edges of 64 texels: level 6 */
    fixture_set_option(&f, "shadows", 0);
    void *st = NULL;
    const meso_mesh *mesh = fixture_geometry(&f, technique, &st);
    assert_int_equal(mesh->num_triangles, (size_t)2 << 12);
    technique->release(st);
    fixture_deinit(&f);
}

static void test_displacement_refuses_levels_above_the_triangle_limit(void **state) {
    (void)state;
    fixture f;
    fixture_init(&f, 1);
    fixture_plane(&f, 8); /* 128 triangles x 4^10 > 2^26 */
    f.object.mesh = f.mesh;
    fixture_set_option(&f, "level", 10);
    void *st = NULL;
    assert_int_equal(technique->prepare(f.ctx, &f.scene, &f.object, &st), MESO_ERROR_LIMIT);
    assert_null(st);
    assert_non_null(strstr(meso_context_last_error(f.ctx), "level"));
    fixture_set_option(&f, "level", 11);
    assert_int_equal(technique->prepare(f.ctx, &f.scene, &f.object, &st),
                     MESO_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(meso_context_last_error(f.ctx), "level"));
    fixture_clear_options(&f);
    fixture_set_option(&f, "shadow_map_size", 4);
    assert_int_equal(technique->prepare(f.ctx, &f.scene, &f.object, &st),
                     MESO_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(meso_context_last_error(f.ctx), "shadow_map_size"));
    fixture_deinit(&f);
}

/* A fragment at barycentrics (1/3, 1/3, 1/3) of triangle t. */
static meso_fragment centroid_fragment(const meso_mesh *mesh, size_t t) {
    const uint32_t *i = &mesh->indices[t * 3];
    const float third = 1.0f / 3.0f;
    meso_fragment frag = {0};
    frag.triangle = (uint32_t)t;
    frag.b0 = frag.b1 = frag.b2 = third;
    frag.position = meso_vec3_barycentric(mesh->positions[i[0]], mesh->positions[i[1]],
                                          mesh->positions[i[2]], third, third, third);
    frag.normal = meso_vec3_normalize(meso_vec3_barycentric(
        mesh->normals[i[0]], mesh->normals[i[1]], mesh->normals[i[2]], third, third, third));
    frag.tangent = meso_vec3_barycentric(mesh->tangents[i[0]], mesh->tangents[i[1]],
                                         mesh->tangents[i[2]], third, third, third);
    frag.bitangent = meso_vec3_barycentric(mesh->bitangents[i[0]], mesh->bitangents[i[1]],
                                           mesh->bitangents[i[2]], third, third, third);
    frag.uv = meso_vec2_barycentric(mesh->uvs[i[0]], mesh->uvs[i[1]], mesh->uvs[i[2]], third, third,
                                    third);
    return frag;
}

static void test_displacement_groove_floor_is_shadowed_by_its_wall(void **state) {
    (void)state;
    fixture f;
    fixture_init(&f, 2);
    /* a groove (h = 0) 0.5 wide and 0.3 deep across the middle, lit from +x at 27 degrees
     * elevation: the wall on the light's side shades the whole floor; the top stays lit */
    fixture_heights(&f, 64, FIELD_CONSTANT, 1.0f);
    for (int j = 0; j < 64; j++)
        for (int i = 24; i < 40; i++) f.heights[j * 64 + i] = 0.0f;
    f.object.mesostructure.depth = 0.3f;
    fixture_plane(&f, 1);
    fixture_set_option(&f, "level", 6);
    fixture_set_option(&f, "shadow_map_size", 1024);
    f.scene.lights[0].direction = meso_vec3_normalize((meso_vec3){1.0f, 0.5f, 0.0f});
    void *st = NULL;
    const meso_mesh *mesh = fixture_geometry(&f, technique, &st);
    int floor_lit = 0, floor_dark = 0, top_lit = 0, top_dark = 0;
    float ambient = 0.8f * 0.1f;
    for (size_t t = 0; t < mesh->num_triangles; t++) {
        meso_fragment frag = centroid_fragment(mesh, t);
        technique->shade(st, &f.frame, &f.object, &frag, 1);
        float u = frag.uv.x;
        bool dark = frag.color.x < ambient + 1e-3f;
        if (u > 0.4f && u < 0.45f && frag.position.y < -0.29f) /* floor near the left wall */
            dark ? floor_dark++ : floor_lit++;
        if ((u < 0.3f || u > 0.7f) && frag.position.y > -1e-6f) dark ? top_dark++ : top_lit++;
    }
    assert_true(floor_dark > 0);
    assert_int_equal(floor_lit, 0);
    assert_true(top_lit > 0);
    assert_int_equal(top_dark, 0); /* no shadow acne on the lit top */
    technique->release(st);
    fixture_deinit(&f);
}

/* The rasterizer shades displacement's blocks eight fragments at a time (displace_shade8.h):
 * the same colours, bit for bit, as the per-fragment shade (displace_fixture.h). */
static void test_displacement_block_shading_matches_per_fragment(void **state) {
    (void)state;
    fixture_check_block_shading(technique, "level");
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_displacement_level_makes_four_to_the_level_triangles),
        cmocka_unit_test(test_displacement_sphere_has_no_cracks),
        cmocka_unit_test(test_displacement_clusters_left_out_are_back_facing_or_outside),
        cmocka_unit_test(test_displacement_vertices_lie_on_the_displaced_plane),
        cmocka_unit_test(test_displacement_automatic_level_reaches_texel_density),
        cmocka_unit_test(test_displacement_refuses_levels_above_the_triangle_limit),
        cmocka_unit_test(test_displacement_groove_floor_is_shadowed_by_its_wall),
        cmocka_unit_test(test_displacement_block_shading_matches_per_fragment),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
