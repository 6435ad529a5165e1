/* Spherical harmonics (include/meso/sh.h) and their use on environments: orthonormality, the
 * projection of a constant environment, rotation against rotating the map, irradiance of
 * uniform and hemispherical skies against the closed forms. */
#include <math.h>
#include <stdlib.h>

#include "test_util.h"

/* A direction from two numbers in [0, 1). */
static meso_vec3 sphere_point(double a, double b) {
    double z = 1.0 - 2.0 * a, r = sqrt(fmax(0.0, 1.0 - z * z)), phi = 2.0 * M_PI * b;
    return (meso_vec3){(float)(r * cos(phi)), (float)(r * sin(phi)), (float)z};
}

/* An environment of `width` x width/2 texels whose radiance toward d is fn(d) in every channel. */
static meso_environment *environment_of(meso_context *ctx, int width,
                                        float (*fn)(meso_vec3 d, const void *user),
                                        const void *user) {
    meso_image *image = NULL;
    int height = width / 2;
    assert_int_equal(meso_image_create(ctx, width, height, 3, &image), MESO_OK);
    for (int j = 0; j < height; j++)
        for (int i = 0; i < width; i++) {
            meso_vec3 d =
                meso_environment_direction((i + 0.5f) / (float)width, (j + 0.5f) / (float)height);
            float v = fn(d, user);
            float *p = meso_image_at(image, i, j);
            p[0] = p[1] = p[2] = v;
        }
    meso_environment *env = NULL;
    assert_int_equal(meso_environment_create_from_image(ctx, image, 1.0f, "test", &env), MESO_OK);
    meso_image_destroy(image);
    return env;
}

static float constant_one(meso_vec3 d, const void *user) {
    (void)d, (void)user;
    return 1.0f;
}

static float upper_hemisphere(meso_vec3 d, const void *user) {
    (void)user;
    return d.y > 0.0f ? 1.0f : 0.0f;
}

/* A smooth, asymmetric function: a wide lobe toward (0.3, 0.5, -0.8) plus a gradient in x. */
static float smooth_lobes(meso_vec3 d, const void *user) {
    (void)user;
    meso_vec3 a = meso_vec3_normalize((meso_vec3){0.3f, 0.5f, -0.8f});
    float c = meso_vec3_dot(d, a);
    return 1.0f + 2.0f * c * c * (c > 0.0f ? 1.0f : 0.3f) + 0.5f * d.x;
}

static void test_sh_basis_is_orthonormal(void **state) {
    (void)state;
    /* midpoint rule over a fine (cos theta, phi) grid: exact to ~1e-4 for polynomials */
    double gram[MESO_SH_COUNT][MESO_SH_COUNT] = {{0}};
    const int n = 400;
    for (int a = 0; a < n; a++)
        for (int b = 0; b < 2 * n; b++) {
            float basis[MESO_SH_COUNT];
            meso_sh_basis(sphere_point((a + 0.5) / n, (b + 0.5) / (2 * n)), basis);
            double dw = 4.0 * M_PI / (2.0 * n * n);
            for (int i = 0; i < MESO_SH_COUNT; i++)
                for (int j = 0; j < MESO_SH_COUNT; j++) gram[i][j] += basis[i] * basis[j] * dw;
        }
    for (int i = 0; i < MESO_SH_COUNT; i++)
        for (int j = 0; j < MESO_SH_COUNT; j++)
            assert_float_equal(gram[i][j], i == j ? 1.0 : 0.0, 1e-3);
}

static void test_sh_constant_environment_is_dc_only(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    meso_environment *env = environment_of(ctx, 256, constant_one, NULL);
    /* c_0 = integral of Y_0 = 4 pi * 0.2821 = sqrt(4 pi); the others vanish up to the
     * projection's quadrature (basis at texel centres: 1e-4 at 256 x 128, 1.6e-3 at 64 x 32) */
    for (int c = 0; c < 3; c++) {
        assert_float_equal(env->sh[c][0], sqrt(4.0 * M_PI), 1e-4);
        for (int k = 1; k < MESO_SH_COUNT; k++) assert_float_equal(env->sh[c][k], 0.0, 2e-4);
    }
    /* and a flat surface under it, any orientation, receives E = pi L */
    for (int k = 0; k < 20; k++) {
        meso_vec3 n = sphere_point((k * 0.618034) - floor(k * 0.618034), k / 20.0);
        assert_float_equal(meso_sh_irradiance(env->sh[1], n), M_PI, 1e-3);
    }
    meso_environment_destroy(env);
    meso_context_destroy(ctx);
}

static void test_sh_hemisphere_sky_gives_the_analytic_irradiance(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    /* radiance 1 above the horizon, 0 below: a plane whose normal is tilted by alpha from up
     * receives E = pi (1 + cos alpha) / 2 (the sky fills the part of its hemisphere above the
     * horizon). E is linear in cos alpha, so bands 0 and 1 carry it exactly; the other bands
     * of the step are 0 (band 2) or cut by the clamped cosine (band 3). The tolerance is the
     * 256 x 128 map's horizon row being half in, half out. */
    meso_environment *env = environment_of(ctx, 256, upper_hemisphere, NULL);
    for (int k = 0; k <= 12; k++) {
        float alpha = (float)M_PI * k / 12.0f;
        meso_vec3 n = {sinf(alpha) * 0.6f, cosf(alpha), sinf(alpha) * 0.8f};
        double expected = M_PI * (1.0 + cos(alpha)) / 2.0;
        assert_float_equal(meso_sh_irradiance(env->sh[0], n), expected, 0.01);
    }
    meso_environment_destroy(env);
    meso_context_destroy(ctx);
}

/* frame rows: an orthonormal matrix from an axis and an angle (Rodrigues). */
static void rotation_matrix(meso_vec3 axis, float angle, float out[3][3]) {
    axis = meso_vec3_normalize(axis);
    float c = cosf(angle), s = sinf(angle), t = 1.0f - c;
    float x = axis.x, y = axis.y, z = axis.z;
    float m[3][3] = {{t * x * x + c, t * x * y - s * z, t * x * z + s * y},
                     {t * x * y + s * z, t * y * y + c, t * y * z - s * x},
                     {t * x * z - s * y, t * y * z + s * x, t * z * z + c}};
    for (int r = 0; r < 3; r++)
        for (int k = 0; k < 3; k++) out[r][k] = m[r][k];
}

static meso_vec3 apply(const float m[3][3], meso_vec3 d) {
    return (meso_vec3){m[0][0] * d.x + m[0][1] * d.y + m[0][2] * d.z,
                       m[1][0] * d.x + m[1][1] * d.y + m[1][2] * d.z,
                       m[2][0] * d.x + m[2][1] * d.y + m[2][2] * d.z};
}

static void test_sh_rotation_is_exact_for_band_limited_functions(void **state) {
    (void)state;
    float c[MESO_SH_COUNT], rotated[MESO_SH_COUNT], m[3][3];
    for (int k = 0; k < MESO_SH_COUNT; k++) c[k] = sinf(1.7f * (float)k + 0.3f);
    rotation_matrix((meso_vec3){0.2f, -0.7f, 0.4f}, 2.1f, m);
    meso_sh_rotation rotation;
    meso_sh_rotation_init(m, &rotation);
    meso_sh_rotate(&rotation, c, rotated);
    /* g(d) = f(M d) at many directions */
    for (int k = 0; k < 64; k++) {
        meso_vec3 d = sphere_point((k + 0.5) / 64.0, fmod(k * 0.618034, 1.0));
        assert_float_equal(meso_sh_evaluate(rotated, d), meso_sh_evaluate(c, apply(m, d)), 2e-5);
    }
    /* each band's matrix is orthogonal (rotations keep the L2 norm) */
    double before = 0, after = 0;
    for (int k = 0; k < MESO_SH_COUNT; k++) before += c[k] * c[k], after += rotated[k] * rotated[k];
    assert_float_equal(after, before, (float)(1e-5 * before));
}

typedef struct rotated_source {
    float m[3][3];
} rotated_source;

static float smooth_lobes_rotated(meso_vec3 d, const void *user) {
    const rotated_source *src = user;
    return smooth_lobes(apply(src->m, d), NULL);
}

static void test_sh_rotating_coefficients_matches_rotating_the_map(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    rotated_source src;
    rotation_matrix((meso_vec3){0.9f, 0.3f, -0.2f}, 1.2f, src.m);
    meso_environment *env = environment_of(ctx, 256, smooth_lobes, NULL);
    meso_environment *turned = environment_of(ctx, 256, smooth_lobes_rotated, &src);
    meso_sh_rotation rotation;
    meso_sh_rotation_init(src.m, &rotation);
    float rotated[MESO_SH_COUNT];
    meso_sh_rotate(&rotation, env->sh[0], rotated);
    double norm = 0;
    for (int k = 0; k < MESO_SH_COUNT; k++) norm += rotated[k] * rotated[k];
    for (int k = 0; k < MESO_SH_COUNT; k++)
        assert_float_equal(rotated[k], turned->sh[0][k], (float)(2e-3 * sqrt(norm)));
    /* the rotation is not the identity here: the coefficients move by far more than the
     * tolerance */
    double moved = 0;
    for (int k = 0; k < MESO_SH_COUNT; k++)
        moved += (rotated[k] - env->sh[0][k]) * (rotated[k] - env->sh[0][k]);
    assert_true(sqrt(moved) > 0.1 * sqrt(norm));
    meso_environment_destroy(turned);
    meso_environment_destroy(env);
    meso_context_destroy(ctx);
}

static void test_sh_local_frame_sees_the_normal_as_z(void **state) {
    (void)state;
    /* rotating into a tangent frame (T, B, N): evaluating at (0, 0, 1) reads f(N) */
    float c[MESO_SH_COUNT], local[MESO_SH_COUNT];
    for (int k = 0; k < MESO_SH_COUNT; k++) c[k] = cosf(0.9f * (float)k);
    meso_vec3 n = meso_vec3_normalize((meso_vec3){0.3f, 0.8f, 0.5f});
    meso_vec3 t = meso_vec3_normalize(meso_vec3_cross((meso_vec3){0, 0, 1}, n));
    meso_vec3 b = meso_vec3_cross(n, t);
    float frame[3][3] = {{t.x, b.x, n.x}, {t.y, b.y, n.y}, {t.z, b.z, n.z}};
    meso_sh_rotation rotation;
    meso_sh_rotation_init(frame, &rotation);
    meso_sh_rotate(&rotation, c, local);
    assert_float_equal(meso_sh_evaluate(local, (meso_vec3){0, 0, 1}), meso_sh_evaluate(c, n), 2e-5);
    assert_float_equal(meso_sh_irradiance(local, (meso_vec3){0, 0, 1}), meso_sh_irradiance(c, n),
                       2e-5);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sh_basis_is_orthonormal),
        cmocka_unit_test(test_sh_constant_environment_is_dc_only),
        cmocka_unit_test(test_sh_hemisphere_sky_gives_the_analytic_irradiance),
        cmocka_unit_test(test_sh_rotation_is_exact_for_band_limited_functions),
        cmocka_unit_test(test_sh_rotating_coefficients_matches_rotating_the_map),
        cmocka_unit_test(test_sh_local_frame_sees_the_normal_as_z),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
