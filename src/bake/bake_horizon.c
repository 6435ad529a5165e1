/* Horizon maps: Max 1988 ("Horizon mapping: shadows for bump-mapped surfaces", §2: the horizon
 * angle per texel and azimuth, interpolated between azimuths) and Sloan & Cohen 2000
 * ("Interactive horizon mapping": 8 azimuths, a smooth transition at the horizon). The map
 * stores slopes in texture units (see bake_horizon.h) so that one bake serves any shell depth
 * and tile size. */
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "meso/bake_horizon.h"
#include "meso/runtime.h"

#define DEFAULT_AZIMUTHS 8
#define DEFAULT_DISTANCE 64.0f

meso_horizon_desc meso_horizon_desc_defaults(const meso_horizon_desc *desc) {
    meso_horizon_desc d = desc ? *desc : (meso_horizon_desc){0};
    if (d.num_azimuths == 0) d.num_azimuths = DEFAULT_AZIMUTHS;
    if (d.max_distance == 0.0f) d.max_distance = DEFAULT_DISTANCE;
    return d;
}

typedef struct horizon_job {
    const meso_heightfield *hf;
    const float *padded; /* (width + 1) x (height + 1): wrapped copy, so i + 1 needs no wrap */
    meso_horizon_map *map;
    const float *dir_x, *dir_y; /* per azimuth: texel steps per unit of distance (texels) */
    float max_distance;
    float uv_per_texel; /* 1 / max(width, height) */
    meso_progress *progress;
    atomic_int cancelled;
    float *scratch;     /* texel_aligned: one row of floats per thread */
    bool texel_aligned; /* square field, 4 or 8 azimuths: march texel to texel */
} horizon_job;

/* Bilinear h at texel-centre coordinates (x, y) (x = u W - 0.5): the same surface as
 * meso_heightfield_sample, without its integer modulo in the inner loop. */
static inline float sample_padded(const horizon_job *w, float x, float y) {
    int width = w->hf->width, height = w->hf->height;
    if (w->hf->wrap == MESO_WRAP_CLAMP) {
        x = x < 0.0f ? 0.0f : (x > (float)(width - 1) ? (float)(width - 1) : x);
        y = y < 0.0f ? 0.0f : (y > (float)(height - 1) ? (float)(height - 1) : y);
    } else {
        x -= (float)width * floorf(x / (float)width);
        y -= (float)height * floorf(y / (float)height);
    }
    int i = (int)x, j = (int)y;
    i = i > width - 1 ? width - 1 : i;
    j = j > height - 1 ? height - 1 : j;
    float tx = x - (float)i, ty = y - (float)j;
    const float *r0 = w->padded + (size_t)j * (size_t)(width + 1) + (size_t)i;
    const float *r1 = r0 + width + 1;
    float top = r0[0] + (r0[1] - r0[0]) * tx, bottom = r1[0] + (r1[1] - r1[0]) * tx;
    return top + (bottom - top) * ty;
}

/* The next step along a horizon ray: unit steps near the texel, then growing by 1/8, so a
 * wall nearby is found exactly and a far one, which subtends a small angle, with few samples. */
/* Bakes estimated longer than this are announced as a warning (else said with --verbose). */
#define LONG_BAKE_SECONDS 10.0

static inline int next_step(int k) { return k < 8 ? k + 1 : k + k / 8; }

/* Square fields with 4 or 8 azimuths: every azimuth is a texel axis or diagonal, so stepping k
 * texels along the major axis lands on texels (no bilinear lookups), and a whole row of texels
 * shares each step's offset: the inner loop is a vectorisable max over a row. */
static void bake_row_aligned(horizon_job *w, int j, int thread_index) {
    const meso_heightfield *hf = w->hf;
    int width = hf->width, height = hf->height, n = w->map->num_azimuths;
    bool clamp = hf->wrap == MESO_WRAP_CLAMP;
    const float *h0 = hf->heights + (size_t)j * (size_t)width;
    float *best = w->scratch + (size_t)thread_index * (size_t)width;
    float *out = w->map->slopes + (size_t)j * (size_t)width * (size_t)n;
    for (int a = 0; a < n; ++a) {
        double phi = 2.0 * MESO_PI_D * (double)a / (double)n;
        int dx = (int)lround(cos(phi)), dy = -(int)lround(sin(phi)); /* rows run against v */
        float len = sqrtf((float)(dx * dx + dy * dy));
        for (int i = 0; i < width; ++i)
            best[i] = 0.0f; /* the tangent plane: a flat field has slope 0 */
        for (int k = 1; (float)k * len <= w->max_distance; k = next_step(k)) {
            float inv = 1.0f / ((float)k * len * w->uv_per_texel);
            int jj = j + dy * k;
            if (clamp)
                jj = jj < 0 ? 0 : (jj >= height ? height - 1 : jj);
            else
                jj = ((jj % height) + height) % height;
            const float *row = hf->heights + (size_t)jj * (size_t)width;
            int off = dx * k;
            if (clamp) {
                for (int i = 0; i < width; ++i) {
                    int c = i + off;
                    c = c < 0 ? 0 : (c >= width ? width - 1 : c);
                    float v = (row[c] - h0[i]) * inv;
                    best[i] = v > best[i] ? v : best[i];
                }
            } else {
                int o = ((off % width) + width) % width;
                for (int i = 0; i < width - o; ++i) {
                    float v = (row[i + o] - h0[i]) * inv;
                    best[i] = v > best[i] ? v : best[i];
                }
                for (int i = width - o; i < width; ++i) {
                    float v = (row[i + o - width] - h0[i]) * inv;
                    best[i] = v > best[i] ? v : best[i];
                }
            }
        }
        for (int i = 0; i < width; ++i) out[(size_t)i * (size_t)n + (size_t)a] = best[i];
    }
}

/* The samples along one ray out to max_distance (the schedule of bake_row). */
static uint64_t ray_samples(float max_distance) {
    uint64_t count = 0;
    for (float s = 1.0f; s <= max_distance; s += s < 8.0f ? 1.0f : floorf(s * 0.125f)) count++;
    return count;
}

/* CPU time of one bilinear sample of a ray (a lookup, a divide, a max), measured on a
 * 512 x 512 bake with 64 azimuths to 4096 texels: 1.0 G samples in 20.6 CPU seconds on the
 * 2-core development machine (docs/robustness.md). An estimate, said before a long bake. */
#define SECONDS_PER_SAMPLE 20e-9

double meso_horizon_bake_seconds_estimate(int width, int height, const meso_horizon_desc *desc,
                                          int num_threads) {
    meso_horizon_desc d = meso_horizon_desc_defaults(desc);
    if (width <= 0 || height <= 0 || d.num_azimuths < 1 || !(d.max_distance >= 1.0f)) return 0.0;
    double samples = (double)width * (double)height * (double)d.num_azimuths *
                     (double)ray_samples(d.max_distance);
    return samples * SECONDS_PER_SAMPLE / (double)(num_threads > 0 ? num_threads : 1);
}

static void bake_row(void *user, size_t job, int thread_index) {
    horizon_job *w = user;
    if (atomic_load(&w->cancelled)) return;
    if (w->texel_aligned) {
        bake_row_aligned(w, (int)job, thread_index);
        if (meso_progress_advance(w->progress, 1)) atomic_store(&w->cancelled, 1);
        return;
    }
    const meso_heightfield *hf = w->hf;
    int j = (int)job, k_count = w->map->num_azimuths;
    float *out = w->map->slopes + (size_t)j * (size_t)hf->width * (size_t)k_count;
    for (int i = 0; i < hf->width; ++i) {
        float h0 = hf->heights[(size_t)j * (size_t)hf->width + (size_t)i];
        for (int k = 0; k < k_count; ++k) {
            float best = 0.0f; /* the tangent plane: a flat field has slope 0 */
            /* The steps of next_step, in texels of the larger side. */
            for (float s = 1.0f; s <= w->max_distance; s += s < 8.0f ? 1.0f : floorf(s * 0.125f)) {
                float h = sample_padded(w, (float)i + w->dir_x[k] * s, (float)j + w->dir_y[k] * s);
                float slope = (h - h0) / (s * w->uv_per_texel);
                best = slope > best ? slope : best;
            }
            out[(size_t)i * (size_t)k_count + (size_t)k] = best;
        }
    }
    if (meso_progress_advance(w->progress, 1)) atomic_store(&w->cancelled, 1);
}

meso_result meso_horizon_map_bake(meso_context *ctx, const meso_heightfield *heightfield,
                                  const meso_horizon_desc *desc, meso_horizon_map **out_map) {
    meso_horizon_map *map = NULL;
    float *padded = NULL, dir_x[MESO_HORIZON_MAX_AZIMUTHS], dir_y[MESO_HORIZON_MAX_AZIMUTHS];
    meso_result result;
    *out_map = NULL;
    meso_horizon_desc d = meso_horizon_desc_defaults(desc);
    if (!heightfield || !heightfield->heights || heightfield->width <= 0 ||
        heightfield->height <= 0)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "horizon: heightfield: missing or empty");
    if (d.num_azimuths < 1 || d.num_azimuths > MESO_HORIZON_MAX_AZIMUTHS)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "horizon: num_azimuths: %d is outside 1..%d", d.num_azimuths,
                              MESO_HORIZON_MAX_AZIMUTHS);
    if (!(d.max_distance >= 1.0f && d.max_distance <= MESO_HORIZON_MAX_DISTANCE))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "horizon: max_distance: %g is outside 1..%g texels",
                              (double)d.max_distance, (double)MESO_HORIZON_MAX_DISTANCE);
    int width = heightfield->width, height = heightfield->height;
    size_t bytes = (size_t)width * (size_t)height * (size_t)d.num_azimuths * sizeof(float);
    if (width > MESO_HORIZON_MAX_SIDE || height > MESO_HORIZON_MAX_SIDE ||
        bytes > MESO_HORIZON_MAX_BYTES)
        return meso_log_error(ctx, MESO_ERROR_LIMIT,
                              "horizon: %d x %d texels x %d azimuths exceeds the limit of %zu "
                              "bytes or %d a side",
                              width, height, d.num_azimuths, (size_t)MESO_HORIZON_MAX_BYTES,
                              MESO_HORIZON_MAX_SIDE);
    /* the memory budget: the slopes, the padded field and a row of scratch per thread */
    uint64_t needed = (uint64_t)bytes + (uint64_t)(width + 1) * (uint64_t)(height + 1) * 4u +
                      (uint64_t)meso_context_num_threads(ctx) * (uint64_t)width * 4u;
    meso_result budget = meso_memory_check(ctx, "horizon bake", needed);
    if (budget != MESO_OK) return budget;
    map = calloc(1, sizeof *map);
    padded = malloc((size_t)(width + 1) * (size_t)(height + 1) * sizeof(float));
    if (!map || !padded) goto oom;
    map->slopes = malloc(bytes);
    if (!map->slopes) goto oom;
    map->width = width;
    map->height = height;
    map->num_azimuths = d.num_azimuths;
    map->max_distance = d.max_distance;
    map->source_hash = heightfield->hash;
    for (int j = 0; j <= height; ++j)
        for (int i = 0; i <= width; ++i)
            padded[(size_t)j * (size_t)(width + 1) + (size_t)i] =
                meso_heightfield_texel(heightfield, i, j);
    int side = width > height ? width : height;
    for (int k = 0; k < d.num_azimuths; ++k) {
        /* phi from +u toward +v; rows run against v (row 0 at the top). One unit of distance
         * is a texel of the larger side. */
        double phi = 2.0 * MESO_PI_D * (double)k / (double)d.num_azimuths;
        dir_x[k] = (float)(cos(phi) * (double)width / (double)side);
        dir_y[k] = (float)(-sin(phi) * (double)height / (double)side);
    }
    horizon_job job = {.hf = heightfield,
                       .padded = padded,
                       .map = map,
                       .dir_x = dir_x,
                       .dir_y = dir_y,
                       .max_distance = d.max_distance,
                       .uv_per_texel = 1.0f / (float)side};
    atomic_init(&job.cancelled, 0);
    job.texel_aligned = width == height && (d.num_azimuths == 4 || d.num_azimuths == 8);
    if (job.texel_aligned) {
        job.scratch = malloc((size_t)meso_context_num_threads(ctx) * (size_t)width * sizeof(float));
        if (!job.scratch) goto oom;
    }
    /* a bake of minutes is said before it starts (--progress shows how it goes) */
    double seconds =
        meso_horizon_bake_seconds_estimate(width, height, &d, meso_context_num_threads(ctx));
    if (!job.texel_aligned && seconds >= LONG_BAKE_SECONDS)
        meso_log_warning(ctx,
                         "horizon map: %d x %d texels x %d azimuths to %g texels: about %.0f s "
                         "of baking on %d thread%s (--progress shows it)",
                         width, height, d.num_azimuths, (double)d.max_distance, seconds,
                         meso_context_num_threads(ctx),
                         meso_context_num_threads(ctx) == 1 ? "" : "s");
    else if (!job.texel_aligned)
        meso_log_info(ctx, "horizon map: %d x %d texels x %d azimuths: about %.1f s of baking",
                      width, height, d.num_azimuths, seconds);
    job.progress = meso_progress_begin_bake(ctx, "horizon map", (uint64_t)height);
    meso_parallel_for(ctx, (size_t)height, bake_row, &job);
    meso_progress_end(job.progress);
    free(job.scratch);
    job.scratch = NULL;
    if (atomic_load(&job.cancelled)) {
        result = meso_log_error(ctx, MESO_ERROR_CANCELLED, "horizon: cancelled");
        goto fail;
    }
    free(padded);
    *out_map = map;
    return MESO_OK;
oom:
    result = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "horizon: out of memory for %d x %d",
                            width, height);
fail:
    free(padded);
    meso_horizon_map_destroy(map);
    return result;
}

float meso_horizon_map_slope(const meso_horizon_map *map, int i, int j, float phi) {
    int n = map->num_azimuths;
    i = i < 0 ? 0 : (i >= map->width ? map->width - 1 : i);
    j = j < 0 ? 0 : (j >= map->height ? map->height - 1 : j);
    const float *s = map->slopes + ((size_t)j * (size_t)map->width + (size_t)i) * (size_t)n;
    /* Max 1988 §2: linear interpolation between the two nearest azimuths. */
    float a = phi * (float)n / (2.0f * MESO_PI);
    a -= (float)n * floorf(a / (float)n);
    int k0 = (int)a;
    k0 = k0 >= n ? n - 1 : k0;
    float t = a - (float)k0;
    int k1 = k0 + 1 == n ? 0 : k0 + 1;
    return s[k0] + (s[k1] - s[k0]) * t;
}

size_t meso_horizon_map_memory(const meso_horizon_map *map) {
    return map ? (size_t)map->width * (size_t)map->height * (size_t)map->num_azimuths *
                     sizeof(float)
               : 0;
}

void meso_horizon_map_destroy(meso_horizon_map *map) {
    if (!map) return;
    free(map->slopes);
    free(map);
}
