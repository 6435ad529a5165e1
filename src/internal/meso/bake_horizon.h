/* meso horizon maps (Max 1988, "Horizon mapping: shadows for bump-mapped surfaces"; Sloan &
 * Cohen 2000, "Interactive horizon mapping"): for every texel of a height field and k azimuths,
 * the elevation of the horizon seen from the surface point, so that a light below it is in
 * shadow.
 *
 * Units. A height field knows nothing of the world scale (the shell depth and the tile size are
 * the object's), so the map stores the horizon as a slope in texture units:
 *     slope = max over distances s in (0, max_distance] of (h(p + s a) - h(p)) / s, and >= 0,
 * where a = (cos phi, sin phi) is a unit direction in (u, v), s is measured in u/v units and h
 * in height units ([0, 1]). Azimuth k is phi_k = 2 pi k / num_azimuths, counter-clockwise from
 * +u toward +v. A renderer turns it into the tangent of the elevation angle with
 *     tan(elevation) = slope * depth / |cos phi T + sin phi B|     (T = dP/du, B = dP/dv).
 * A flat field has slope 0 (horizon at the tangent plane) everywhere.
 *
 * Usage
 *   meso_horizon_map *map = NULL;
 *   meso_horizon_map_bake(ctx, heightfield, &(meso_horizon_desc){.num_azimuths = 8}, &map);
 *   float s = map->slopes[((size_t)j * map->width + i) * map->num_azimuths + k];
 *   meso_horizon_map_destroy(map);
 *
 * Threads: the bake uses every worker of ctx (parallel over texel rows; byte-identical for any
 * thread count). The map is read-only afterwards.
 */
#ifndef MESO_BAKE_HORIZON_H
#define MESO_BAKE_HORIZON_H

#include "meso/core.h"
#include "meso/mesostructure.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MESO_HORIZON_MAX_AZIMUTHS 64
#define MESO_HORIZON_MAX_DISTANCE 4096.0f /* texels */
#define MESO_HORIZON_MAX_SIDE 16384
/* Largest map in bytes (width * height * num_azimuths floats), checked before allocating. */
#define MESO_HORIZON_MAX_BYTES ((size_t)1 << 31)

/* Zero fields take the defaults of meso_horizon_desc_defaults(). */
typedef struct meso_horizon_desc {
    int num_azimuths;   /* directions around the texel (8), 1..MESO_HORIZON_MAX_AZIMUTHS */
    float max_distance; /* search radius in texels of the larger side (64) */
} meso_horizon_desc;

typedef struct meso_horizon_map {
    int width, height; /* the height field's */
    int num_azimuths;
    float max_distance; /* texels, as baked */
    uint64_t source_hash;
    float *slopes; /* width * height * num_azimuths, texel-major, row 0 at the top; owned */
} meso_horizon_map;

/* desc with zero fields replaced by the defaults (desc may be NULL). Pure. */
meso_horizon_desc meso_horizon_desc_defaults(const meso_horizon_desc *desc);

/* About how many seconds meso_horizon_map_bake takes for a width x height field on num_threads
 * threads (its samples times a measured cost a sample; the 4- and 8-azimuth square case is
 * faster). meso_horizon_map_bake says it before baking: a warning when it is 10 s or more, else
 * an info message. Pure. */
double meso_horizon_bake_seconds_estimate(int width, int height, const meso_horizon_desc *desc,
                                          int num_threads);

/* Bake the horizon map of `heightfield` (samples it bilinearly, wrapping as it wraps).
 * desc        Read during the call only; NULL: defaults.
 * out_map     On MESO_OK a new map owned by the caller (meso_horizon_map_destroy); else NULL.
 * Returns     MESO_OK, MESO_ERROR_INVALID_ARGUMENT (the message names the field:
 *             "horizon: num_azimuths: ..."), MESO_ERROR_LIMIT, MESO_ERROR_OUT_OF_MEMORY,
 *             MESO_ERROR_CANCELLED (progress callback).
 * Threads     Uses every worker of ctx; safe on different contexts at once. */
meso_result meso_horizon_map_bake(meso_context *ctx, const meso_heightfield *heightfield,
                                  const meso_horizon_desc *desc, meso_horizon_map **out_map);

/* The slope toward azimuth `phi` (radians, any value) at texel (i, j), linearly interpolated
 * between the two nearest baked azimuths. Pure, thread-safe. */
float meso_horizon_map_slope(const meso_horizon_map *map, int i, int j, float phi);

size_t meso_horizon_map_memory(const meso_horizon_map *map);
/* NULL does nothing. */
void meso_horizon_map_destroy(meso_horizon_map *map);

#ifdef __cplusplus
}
#endif
#endif
