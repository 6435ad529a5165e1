/* meso environments: distant light from every direction (GDM paper §3.2).
 *
 * An environment is an equirectangular map of linear RGB radiance, from a Radiance .hdr file
 * (read with stb_image) or an OpenEXR file (the OpenEXR library), or made from a procedural
 * sky, times an intensity. It is held as a
 * piecewise-constant function: the radiance toward d is that of the texel d falls in (no
 * filtering), so the projection onto spherical harmonics, the importance sampling and the
 * lookups of the path tracer all see the same function.
 *
 * Mapping (world space, y up): row 0 is straight up (+y), the last row straight down;
 * column u = (i + 0.5) / W looks toward azimuth phi = 2 pi (u - 0.5) with phi = atan2(x, -z):
 * the centre column looks toward -z (the default camera's view), u grows toward +x.
 *   d = (sin(theta) sin(phi), cos(theta), -sin(theta) cos(phi)), theta = pi (j + 0.5) / H.
 *
 * Usage
 *   meso_environment *env = NULL;
 *   meso_environment_load(ctx, "sky.hdr", 1.0f, &env);
 *   meso_vec3 L = meso_environment_radiance(env, direction);
 *   float E = meso_sh_irradiance(env->sh[0], normal);     // red channel's irradiance
 *   meso_environment_destroy(env);
 *
 * Limits: MESO_ENVIRONMENT_MAX_SIDE texels a side and MESO_ENVIRONMENT_MAX_PIXELS in all,
 * checked from the file's header before any pixel is decoded, and the context's memory budget.
 * Errors name the file and the reason (MESO_ERROR_IO, _FORMAT, _LIMIT, _OUT_OF_MEMORY).
 *
 * An environment is immutable after creation: every query is pure and thread-safe.
 */
#ifndef MESO_ENVIRONMENT_H
#define MESO_ENVIRONMENT_H

#include "meso/core.h"
#include "meso/image.h"
#include "meso/math.h"
#include "meso/sh.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MESO_ENVIRONMENT_MAX_SIDE 8192
#define MESO_ENVIRONMENT_MAX_PIXELS (1u << 25) /* 8192 x 4096: 384 MiB of RGB floats */
#define MESO_ENVIRONMENT_MAX_FILE_BYTES (UINT64_C(512) << 20)
#define MESO_ENVIRONMENT_MAX_INTENSITY 1.0e6f
#define MESO_ENVIRONMENT_SOURCE_MAX 256

/* A procedural sky. Zero fields take the defaults of meso_sky_desc_defaults(); a colour of
 * exactly (0, 0, 0) is taken as "default" too, so give (1e-6, 0, 0) for a black one. */
typedef struct meso_sky_desc {
    meso_vec3 zenith;        /* radiance straight up: (0.25, 0.42, 0.85) */
    meso_vec3 horizon;       /* radiance at the horizon: (0.85, 0.88, 0.92) */
    meso_vec3 ground;        /* radiance below the horizon (uniform): (0.25, 0.22, 0.2) */
    float gradient;          /* sky(elevation e) = horizon + (zenith - horizon) e^gradient (0.5) */
    meso_vec3 sun_direction; /* toward the sun; (0, 0, 0): the default (0.5, 0.6, 0.3) */
    meso_vec3 sun_color;     /* the sun lobe's peak radiance: (40, 36, 30) */
    float sun_size_deg;      /* the lobe's angular radius, degrees (4) */
    bool no_sun;             /* true: no sun lobe */
    int width;               /* the map's columns; rows = width / 2 (256) */
} meso_sky_desc;

meso_sky_desc meso_sky_desc_defaults(const meso_sky_desc *desc);

typedef struct meso_environment {
    meso_image *map; /* W x H RGB linear radiance, intensity applied; owned */
    float intensity; /* as given (already applied to map and sh) */
    /* The projection onto spherical harmonics, per channel (sh[0] red ... sh[2] blue), of the
     * piecewise-constant map: c_i = sum over texels L Y_i(texel centre) dw(texel). */
    float sh[3][MESO_SH_COUNT];
    /* Importance sampling of luminance x solid angle: cumulative sums, normalised to 1. */
    float *row_cdf;    /* H + 1 values: rows */
    float *column_cdf; /* H x (W + 1) values: columns within each row */
    double weight_sum; /* sum of luminance x dw over texels (0: a black map, sampled uniformly) */
    char source[MESO_ENVIRONMENT_SOURCE_MAX]; /* the file name or "sky", for labels and logs */
    uint64_t hash; /* of the map's texels and size: caches of what is baked from it */
} meso_environment;

/* Load a Radiance .hdr (RGBE) or OpenEXR (told by its magic number) equirectangular map,
 * radiance times `intensity` (finite, >= 0, at most MESO_ENVIRONMENT_MAX_INTENSITY). Any aspect
 * ratio is mapped onto the whole sphere. Errors name the file: MESO_ERROR_IO (missing,
 * unreadable), MESO_ERROR_FORMAT (neither format, corrupt), MESO_ERROR_LIMIT (too large),
 * MESO_ERROR_INVALID_ARGUMENT (intensity). Thread-safe. */
meso_result meso_environment_load(meso_context *ctx, const char *path, float intensity,
                                  meso_environment **out_environment);
/* A procedural sky (desc may be NULL: the defaults) times `intensity`. Errors:
 * MESO_ERROR_INVALID_ARGUMENT naming the field ("sky: width: 3 is not in [8, 8192]"). */
meso_result meso_environment_create_sky(meso_context *ctx, const meso_sky_desc *desc,
                                        float intensity, meso_environment **out_environment);
/* An environment of an existing map (RGB or RGBA linear radiance; copied), times intensity;
 * `source` names it in messages. */
meso_result meso_environment_create_from_image(meso_context *ctx, const meso_image *image,
                                               float intensity, const char *source,
                                               meso_environment **out_environment);
/* Free; NULL does nothing. */
void meso_environment_destroy(meso_environment *environment);

/* Save the map (intensity applied) as a Radiance .hdr file, atomically. MESO_OK or
 * MESO_ERROR_IO (logged). */
meso_result meso_environment_save_hdr(meso_context *ctx, const meso_environment *environment,
                                      const char *path);

/* The radiance toward the unit direction d. */
meso_vec3 meso_environment_radiance(const meso_environment *environment, meso_vec3 d);

/* Draw a direction with probability density (per steradian) proportional to the map's
 * luminance, from two uniform numbers in [0, 1). *out_pdf is the density of the direction
 * (> 0). A black map is sampled uniformly over the sphere. */
meso_vec3 meso_environment_sample(const meso_environment *environment, float u1, float u2,
                                  float *out_pdf);
/* The density meso_environment_sample draws the unit direction d with. */
float meso_environment_pdf(const meso_environment *environment, meso_vec3 d);

/* The unit direction of map coordinates (u, v) in [0, 1]^2 (v = 0 at the top row) and back. */
meso_vec3 meso_environment_direction(float u, float v);
meso_vec2 meso_environment_coordinates(meso_vec3 d);

#ifdef __cplusplus
}
#endif
#endif
