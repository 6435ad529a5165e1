/* meso spherical harmonics: order 4 (bands l = 0..3), 16 coefficients.
 *
 * The basis is the real, orthonormal one (integral over the sphere of Y_i Y_j = delta_ij)
 * written as polynomials of a unit direction (x, y, z), without the Condon-Shortley phase:
 *   l = 0  Y0 = 0.2821
 *   l = 1  Y1 = 0.4886 y, Y2 = 0.4886 z, Y3 = 0.4886 x
 *   l = 2  Y4 = 1.0925 xy, Y5 = 1.0925 yz, Y6 = 0.3154 (3z^2 - 1), Y7 = 1.0925 xz,
 *          Y8 = 0.5463 (x^2 - y^2)
 *   l = 3  Y9 = 0.5900 y (3x^2 - y^2), Y10 = 2.8906 xyz, Y11 = 0.4570 y (5z^2 - 1),
 *          Y12 = 0.3732 z (5z^2 - 3), Y13 = 0.4570 x (5z^2 - 1), Y14 = 1.4453 z (x^2 - y^2),
 *          Y15 = 0.5900 x (x^2 - 3y^2)
 * Coefficient i = l (l + 1) + m. The polynomials are those of Sloan, "Stupid Spherical
 * Harmonics Tricks" (2008), with every sign positive. Coordinates are those of whatever frame
 * the direction is given in: world space (y up) for an environment, a tangent frame (z along
 * the normal) after meso_sh_rotation_init with that frame.
 *
 * A function f on the sphere is f(d) ~ sum_i c_i Y_i(d), c_i = integral f Y_i dw. Products
 * integrate as dot products: integral f g dw ~ sum_i f_i g_i (the PRT inner product, Sloan et
 * al. 2002/2003; GDM paper §3.2).
 *
 * Pure functions, thread-safe.
 */
#ifndef MESO_SH_H
#define MESO_SH_H

#include "meso/math.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MESO_SH_ORDER 4
#define MESO_SH_COUNT 16

/* The 16 basis functions at the unit direction d. */
void meso_sh_basis(meso_vec3 d, float out_basis[MESO_SH_COUNT]);

/* sum_i coefficients[i] Y_i(d). */
float meso_sh_evaluate(const float coefficients[MESO_SH_COUNT], meso_vec3 d);

/* The irradiance E(n) = integral L(w) max(0, n.w) dw of the radiance L given by `radiance`'s
 * coefficients, at the unit normal n: the clamped cosine convolved band by band (Ramamoorthi
 * & Hanrahan 2001), A_0 = pi, A_1 = 2 pi / 3, A_2 = pi / 4, A_3 = 0. Exact for a radiance of
 * order 4; for any other the error is that of truncating L at order 4 (bands 4 and up carry
 * at most a few percent of an irradiance). */
float meso_sh_irradiance(const float radiance[MESO_SH_COUNT], meso_vec3 n);

/* A rotation of SH coefficients: band 0 is unchanged, each band l = 1..3 is mixed by a
 * (2l+1) x (2l+1) matrix. */
typedef struct meso_sh_rotation {
    float band1[3][3];
    float band2[5][5];
    float band3[7][7];
} meso_sh_rotation;

/* The rotation that turns the coefficients of f into those of g(d) = f(M d), M = frame (rows
 * of a 3 x 3 orthonormal matrix, frame[r][c]). With M's columns (T, B, N) of a tangent frame,
 * g is f seen from that frame: g(0, 0, 1) = f(N). Each band's matrix is fitted, in double
 * precision, to the band's values at 32 fixed directions and their images under M; rotations
 * keep bands apart, so the fit is exact up to rounding. */
void meso_sh_rotation_init(const float frame[3][3], meso_sh_rotation *out_rotation);

/* out = the rotation applied to in. out must not alias in. */
void meso_sh_rotate(const meso_sh_rotation *rotation, const float in[MESO_SH_COUNT],
                    float out[MESO_SH_COUNT]);

#ifdef __cplusplus
}
#endif
#endif
