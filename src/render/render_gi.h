/* Bi-scale radiance transfer, macro scale (GDM paper §3.2 after Sloan et al. 2003; issue 17
 * item 2): the environment's light arriving at each vertex of the base mesh, including the
 * base mesh's own occlusion, as spherical harmonics in the vertex's tangent frame, ready to be
 * dotted with the meso-scale response (the radiance transfer volume) at a GDM hit.
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
#include "meso/scene.h"

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

#endif
