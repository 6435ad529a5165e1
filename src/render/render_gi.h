/* Bi-scale radiance transfer, macro scale (GDM paper §3.2 after Sloan et al. 2003): the
 * environment's light arriving at each vertex of the base mesh, including the base mesh's own
 * occlusion, as spherical harmonics in the vertex's tangent frame, ready to be dotted with the
 * meso-scale response (the radiance transfer volume) at a GDM hit.
 *
 * What is computed: for vertex v with position P, unit normal N and tangent frame (T, B, N)
 * (T from dP/du made orthogonal to N, B = N x T), the coefficients
 *     c_i(v) = integral L(w) V(P, w) Y_i(R_v w) dw,
 * L the environment's radiance reconstructed from its order-4 SH (smooth: no aliasing of a
 * sun into the sample directions), V = 1 where the ray P + t w leaves the base mesh and
 * w.N > 0 (the macro surface is opaque below its tangent plane), R_v the rotation from world
 * space into (T, B, N): the local z axis is N, x is T. Directions: a fixed spherical
 * Fibonacci set of `directions` points of equal weight 4 pi / n, the same for every vertex.
 * Interreflection at the macro scale (light bounced by other parts of the base mesh) is not
 * included.
 */
#ifndef MESO_RENDER_GI_H
#define MESO_RENDER_GI_H

#include <math.h>

#include "meso/environment.h"
#include "meso/geom.h"
#include "meso/mesostructure.h"
#include "meso/scene.h"
#include "meso/sh.h"

/* Zero fields take the defaults. */
typedef struct meso_gi_vertex_desc {
    int directions; /* sample directions over the sphere (1024), 16 .. 65536 */
} meso_gi_vertex_desc;

/* Per-vertex incident radiance: out_radiance[(v * 3 + channel) * MESO_SH_COUNT + i], a new
 * array of num_vertices x 3 x 16 floats the caller frees. Traces with Embree on the context's
 * threads; the result does not depend on the thread count. Errors: MESO_ERROR_INVALID_ARGUMENT
 * (no mesh, no environment, directions out of range), MESO_ERROR_LIMIT (the memory budget),
 * MESO_ERROR_OUT_OF_MEMORY, MESO_ERROR_INTERNAL (Embree). */
meso_result meso_gi_vertex_radiance(meso_context *ctx, const meso_mesh *mesh,
                                    const meso_environment *environment,
                                    const meso_gi_vertex_desc *desc, float **out_radiance);

/* meso_gi_vertex_radiance for a shell that lets light through (a woven solid with holes):
 * directions below the tangent plane count too. One that leaves the base mesh brings the
 * environment's radiance into out_radiance; one that meets it (the inside of a closed mesh)
 * is counted in *out_interior, num_vertices x 16 floats in the vertex's frame: the SH
 * coefficients of those directions, to be multiplied by the interior's radiance
 * (meso_gi_interior_radiance) when the frame's lights are known. */
meso_result meso_gi_vertex_radiance_through_shell(meso_context *ctx, const meso_mesh *mesh,
                                                  const meso_environment *environment,
                                                  const meso_gi_vertex_desc *desc,
                                                  float **out_radiance, float **out_interior);

/* The fraction of a solid mesostructure's tile that light crosses straight through the shell
 * (columns of (u, v) with no solid over the depth, 64 x 64 columns of 64 samples); 0 for a
 * height field, whose shell is closed. Pure. */
float meso_gi_open_fraction(const meso_mesostructure *ms);

/* The radiance inside a closed base mesh whose shell lets through the fraction tau of the
 * light, as a cavity in balance (one uniform radiance): the light arriving on the outside,
 * E (the environment from the vertices' coefficients, the scene's lights at their cosine,
 * averaged over the mesh by area), enters through the holes; the inner walls, a fraction
 * 1 - tau of what a ray inside meets, reflect rho of it again and again, the holes let it out:
 *     wall radiance = rho tau E / (pi (1 - tau) (1 - rho (1 - tau))),
 *     interior = (1 - tau) wall + tau (the environment's mean radiance, seen through a hole).
 * Per channel; rho the material's albedo. Pure. */
meso_vec3 meso_gi_interior_radiance(const meso_mesh *mesh, const float *radiance,
                                    const meso_scene *scene, meso_vec3 albedo, float open_fraction);

/* Direction k of n over the sphere: a spherical Fibonacci point (equal areas). Pure. */
static inline meso_vec3 meso_gi_fibonacci_direction(int k, int n) {
    double z = 1.0 - (2.0 * k + 1.0) / n, r = sqrt(fmax(0.0, 1.0 - z * z));
    double phi = 2.399963229728653 * k;
    return (meso_vec3){(float)(r * cos(phi)), (float)z, (float)(r * sin(phi))};
}

/* The unit tangent T of vertex v's frame: dP/du made orthogonal to the normal (any direction
 * across the normal where the mesh has no usable tangent). The frame is (T, N x T, N). */
meso_vec3 meso_gi_vertex_tangent(const meso_mesh *mesh, size_t v);

/* The shell's world aspect (depth / tile side) of an object with mesostructure, the RTV bake's
 * `aspect` (bake_rtv.h): the tile side is the mean of |dP/du| and |dP/dv| over its vertices;
 * clamped to [1e-4, 100]. Pure. */
float meso_gi_shell_aspect(const meso_object *object);

/* The incident radiance at a point of triangle (i0, i1, i2) with barycentric weights
 * (b0, b1, b2): the vertices' coefficients interpolated (the paper interpolates the vertex
 * vectors across the triangle, §4.2). */
static inline void meso_gi_radiance_interpolate(const float *radiance, uint32_t i0, uint32_t i1,
                                                uint32_t i2, float b0, float b1, float b2,
                                                float out[3][MESO_SH_COUNT]) {
    const float *a = radiance + (size_t)i0 * 3 * MESO_SH_COUNT;
    const float *b = radiance + (size_t)i1 * 3 * MESO_SH_COUNT;
    const float *c = radiance + (size_t)i2 * 3 * MESO_SH_COUNT;
    for (int k = 0; k < 3 * MESO_SH_COUNT; k++)
        out[k / MESO_SH_COUNT][k % MESO_SH_COUNT] = b0 * a[k] + b1 * b[k] + b2 * c[k];
}

/* Add the interior's light to a radiance interpolated at a point of triangle (i0, i1, i2)
 * (meso_gi_radiance_interpolate): the vertices' interior coefficients
 * (meso_gi_vertex_radiance_through_shell) interpolated alike, times the interior's radiance. */
static inline void meso_gi_radiance_add_interior(const float *interior, uint32_t i0, uint32_t i1,
                                                 uint32_t i2, float b0, float b1, float b2,
                                                 meso_vec3 interior_radiance,
                                                 float radiance[3][MESO_SH_COUNT]) {
    const float *l = &interior_radiance.x;
    for (int i = 0; i < MESO_SH_COUNT; i++) {
        float m = b0 * interior[(size_t)i0 * MESO_SH_COUNT + (size_t)i] +
                  b1 * interior[(size_t)i1 * MESO_SH_COUNT + (size_t)i] +
                  b2 * interior[(size_t)i2 * MESO_SH_COUNT + (size_t)i];
        for (int c = 0; c < 3; c++) radiance[c][i] += l[c] * m;
    }
}

/* What a surface facing the light from below the tangent plane (a hit seen from inside the base
 * mesh) reflects per unit albedo: its irradiance about -z over pi, per channel. */
static inline void meso_gi_reflected_from_below(const float radiance[3][MESO_SH_COUNT],
                                                float out_rgb[3]) {
    for (int c = 0; c < 3; c++)
        out_rgb[c] =
            fmaxf(0.0f, meso_sh_irradiance(radiance[c], (meso_vec3){0, 0, -1}) * MESO_INV_PI);
}

#endif
