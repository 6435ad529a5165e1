/* The environment's light in the shared shading model, eight normals at a time.
 *
 * Where a scene has an environment, the model's ambient term becomes ambient + E(n) / pi, with
 * E(n) the environment's irradiance at the shading normal n from its spherical-harmonic
 * projection (meso_sh_irradiance: Ramamoorthi & Hanrahan's clamped-cosine convolution; band 3
 * is multiplied by 0, so bands 0-2 suffice). It is unshadowed: the cheap way for every
 * technique to see the sky; the path-traced reference (reference_path.c) computes the
 * shadowed, interreflected truth instead, and its direct part leaves this term out. */
#ifndef MESO_RENDER_ENVIRONMENT_H
#define MESO_RENDER_ENVIRONMENT_H

#include "meso/environment.h"
#include "render_simd.h"

/* *r, *g, *b += E(n) / pi of each channel, for eight unit normals (nx, ny, nz). */
static inline void meso_environment_ambient8(const meso_environment *env, v8f nx, v8f ny, v8f nz,
                                             v8f *r, v8f *g, v8f *b) {
    /* meso_sh_basis's bands 0-2 (sh.h) */
    v8f basis[9] = {v8_splat(0.282094791773878f),
                    v8_splat(0.488602511902920f) * ny,
                    v8_splat(0.488602511902920f) * nz,
                    v8_splat(0.488602511902920f) * nx,
                    v8_splat(1.092548430592079f) * nx * ny,
                    v8_splat(1.092548430592079f) * ny * nz,
                    v8_splat(0.315391565252520f) * (v8_splat(3.0f) * nz * nz - v8_splat(1.0f)),
                    v8_splat(1.092548430592079f) * nx * nz,
                    v8_splat(0.546274215296040f) * (nx * nx - ny * ny)};
    /* A_l / pi: 1, 2/3, 1/4 */
    static const float band_scale[9] = {1.0f,  2.0f / 3.0f, 2.0f / 3.0f, 2.0f / 3.0f, 0.25f,
                                        0.25f, 0.25f,       0.25f,       0.25f};
    v8f *out[3] = {r, g, b};
    for (int c = 0; c < 3; c++) {
        v8f sum = v8_splat(0.0f);
        for (int k = 0; k < 9; k++) sum += v8_splat(band_scale[k] * env->sh[c][k]) * basis[k];
        /* truncation rings slightly negative behind a bright sun: no negative light */
        *out[c] += v8_max(sum, v8_splat(0.0f));
    }
}

#endif
