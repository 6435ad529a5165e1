/* Environments (include/meso/environment.h): Radiance .hdr maps read with stb_image, OpenEXR
 * maps with the OpenEXR library (core_exr.c), a procedural sky, the spherical-harmonic projection
 * and luminance importance sampling. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <stb_image.h>
#include <stb_image_write.h>

#include "meso/runtime.h"
#include "meso/environment.h"
#include "meso/image.h"

#define TWO_PI (2.0 * MESO_PI_D)

/* ---- Mapping ------------------------------------------------------------------------------ */

meso_vec3 meso_environment_direction(float u, float v) {
    double theta = MESO_PI_D * v, phi = TWO_PI * (u - 0.5);
    double s = sin(theta);
    return (meso_vec3){(float)(s * sin(phi)), (float)cos(theta), (float)(-s * cos(phi))};
}

meso_vec2 meso_environment_coordinates(meso_vec3 d) {
    float y = meso_clampf(d.y, -1.0f, 1.0f);
    float u = 0.5f + atan2f(d.x, -d.z) / (float)TWO_PI;
    float v = acosf(y) / MESO_PI;
    return (meso_vec2){u, v};
}

/* The texel d falls in. */
static void texel_of(const meso_environment *env, meso_vec3 d, int *out_i, int *out_j) {
    meso_vec2 uv = meso_environment_coordinates(d);
    int w = env->map->width, h = env->map->height;
    float x = uv.x * (float)w, y = uv.y * (float)h;
    int i = x == x ? (int)x : 0, j = y == y ? (int)y : 0; /* NaN (a zero vector) -> texel 0 */
    *out_i = i < 0 ? 0 : i >= w ? w - 1 : i;
    *out_j = j < 0 ? 0 : j >= h ? h - 1 : j;
}

/* The solid angle of one texel of row j: the band's area split over the row's columns. */
static double texel_solid_angle(int j, int width, int height) {
    double c0 = cos(MESO_PI_D * j / height), c1 = cos(MESO_PI_D * (j + 1) / height);
    return TWO_PI / width * (c0 - c1);
}

static float luminance(const float *rgb) {
    return 0.2126f * rgb[0] + 0.7152f * rgb[1] + 0.0722f * rgb[2];
}

meso_vec3 meso_environment_radiance(const meso_environment *env, meso_vec3 d) {
    int i, j;
    texel_of(env, d, &i, &j);
    const float *p = meso_image_at(env->map, i, j);
    return (meso_vec3){p[0], p[1], p[2]};
}

/* ---- Sampling ----------------------------------------------------------------------------- */

/* The first index k in [0, n) with cdf[k + 1] > x (cdf[0] = 0, cdf[n] = 1), skipping empty
 * bins. */
static int search_cdf(const float *cdf, int n, float x) {
    int lo = 0, hi = n; /* cdf[lo] <= x < cdf[hi] */
    while (hi - lo > 1) {
        int mid = lo + (hi - lo) / 2;
        if (cdf[mid] <= x)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

meso_vec3 meso_environment_sample(const meso_environment *env, float u1, float u2, float *out_pdf) {
    if (env->weight_sum <= 0.0) {
        float z = 1.0f - 2.0f * u1, r = sqrtf(fmaxf(0.0f, 1.0f - z * z));
        float phi = (float)TWO_PI * u2;
        *out_pdf = (float)(1.0 / (2.0 * TWO_PI));
        return (meso_vec3){r * cosf(phi), z, r * sinf(phi)};
    }
    int w = env->map->width, h = env->map->height;
    int j = search_cdf(env->row_cdf, h, u1);
    const float *columns = env->column_cdf + (size_t)j * (size_t)(w + 1);
    int i = search_cdf(columns, w, u2);
    /* the numbers' positions inside their bins place the point inside the texel, uniform in
     * solid angle (uniform in cos theta and phi) */
    float row_width = env->row_cdf[j + 1] - env->row_cdf[j];
    float column_width = columns[i + 1] - columns[i];
    float fy =
        row_width > 0.0f ? meso_clampf((u1 - env->row_cdf[j]) / row_width, 0.0f, 1.0f) : 0.5f;
    float fx =
        column_width > 0.0f ? meso_clampf((u2 - columns[i]) / column_width, 0.0f, 1.0f) : 0.5f;
    double c0 = cos(MESO_PI_D * j / h), c1 = cos(MESO_PI_D * (j + 1) / h);
    double cos_theta = c0 + (c1 - c0) * fy;
    double sin_theta = sqrt(fmax(0.0, 1.0 - cos_theta * cos_theta));
    double phi = TWO_PI * ((i + fx) / w - 0.5);
    meso_vec3 d = {(float)(sin_theta * sin(phi)), (float)cos_theta, (float)(-sin_theta * cos(phi))};
    *out_pdf = meso_environment_pdf(env, d);
    return d;
}

float meso_environment_pdf(const meso_environment *env, meso_vec3 d) {
    if (env->weight_sum <= 0.0) return (float)(1.0 / (2.0 * TWO_PI));
    int i, j;
    texel_of(env, d, &i, &j);
    /* p(texel) / dw(texel) with p(texel) = lum dw / sum: the solid angle cancels */
    return (float)(luminance(meso_image_at(env->map, i, j)) / env->weight_sum);
}

/* ---- Creation ----------------------------------------------------------------------------- */

typedef struct projection_job {
    const meso_image *map;
    double *row_sums; /* per row: 3 x 16 SH sums, then the row's luminance weight */
} projection_job;

enum { ROW_SUMS = 3 * MESO_SH_COUNT + 1 };

/* One row per job, summed in double; the rows are added in order afterwards, so the result
 * does not depend on the thread count. */
static void project_row(void *user, size_t job, int thread_index) {
    (void)thread_index;
    const projection_job *pj = user;
    const meso_image *map = pj->map;
    int j = (int)job, w = map->width, h = map->height;
    double dw = texel_solid_angle(j, w, h);
    double *sums = pj->row_sums + (size_t)j * ROW_SUMS;
    float basis[MESO_SH_COUNT];
    for (int i = 0; i < w; i++) {
        const float *p = meso_image_at(map, i, j);
        meso_sh_basis(meso_environment_direction((i + 0.5f) / (float)w, (j + 0.5f) / (float)h),
                      basis);
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < MESO_SH_COUNT; k++)
                sums[c * MESO_SH_COUNT + k] += (double)p[c] * basis[k] * dw;
        sums[3 * MESO_SH_COUNT] += (double)luminance(p) * dw;
    }
}

/* Fill sh, the sampling tables, the hash. The map is final. */
static meso_result finish(meso_context *ctx, meso_environment *env) {
    const meso_image *map = env->map;
    int w = map->width, h = map->height;
    env->row_cdf = malloc((size_t)(h + 1) * sizeof(float));
    env->column_cdf = malloc((size_t)h * (size_t)(w + 1) * sizeof(float));
    double *row_sums = calloc((size_t)h * ROW_SUMS, sizeof(double));
    if (!env->row_cdf || !env->column_cdf || !row_sums) {
        free(row_sums);
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", env->source);
    }
    projection_job pj = {map, row_sums};
    meso_parallel_for(ctx, (size_t)h, project_row, &pj);
    double sh[3 * MESO_SH_COUNT] = {0}, total = 0.0;
    for (int j = 0; j < h; j++) {
        for (int k = 0; k < 3 * MESO_SH_COUNT; k++) sh[k] += row_sums[(size_t)j * ROW_SUMS + k];
        total += row_sums[(size_t)j * ROW_SUMS + 3 * MESO_SH_COUNT];
    }
    for (int c = 0; c < 3; c++)
        for (int k = 0; k < MESO_SH_COUNT; k++) env->sh[c][k] = (float)sh[c * MESO_SH_COUNT + k];
    env->weight_sum = total;
    /* rows by their weight; columns within a row by luminance (their solid angles are equal) */
    double running = 0.0;
    env->row_cdf[0] = 0.0f;
    for (int j = 0; j < h; j++) {
        running += row_sums[(size_t)j * ROW_SUMS + 3 * MESO_SH_COUNT];
        env->row_cdf[j + 1] = total > 0.0 ? (float)(running / total) : 0.0f;
        float *columns = env->column_cdf + (size_t)j * (size_t)(w + 1);
        double row = 0.0;
        for (int i = 0; i < w; i++) row += luminance(meso_image_at(map, i, j));
        double acc = 0.0;
        columns[0] = 0.0f;
        for (int i = 0; i < w; i++) {
            acc += luminance(meso_image_at(map, i, j));
            columns[i + 1] = row > 0.0 ? (float)(acc / row) : (float)(i + 1) / (float)w;
        }
        columns[w] = 1.0f;
    }
    env->row_cdf[h] = 1.0f;
    free(row_sums);
    env->hash = meso_hash64(&w, sizeof w, MESO_HASH_SEED);
    env->hash = meso_hash64(&h, sizeof h, env->hash);
    env->hash = meso_hash64(map->pixels, (size_t)w * (size_t)h * 3 * sizeof(float), env->hash);
    return MESO_OK;
}

static meso_result check_intensity(meso_context *ctx, const char *source, float intensity) {
    if (!(intensity >= 0.0f && intensity <= MESO_ENVIRONMENT_MAX_INTENSITY))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: intensity: %g is not in [0, %g]", source, (double)intensity,
                              (double)MESO_ENVIRONMENT_MAX_INTENSITY);
    return MESO_OK;
}

static meso_result check_size(meso_context *ctx, const char *source, int width, int height) {
    if (width < 1 || height < 1)
        return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: invalid size %dx%d", source, width,
                              height);
    if (width > MESO_ENVIRONMENT_MAX_SIDE || height > MESO_ENVIRONMENT_MAX_SIDE ||
        (uint64_t)width * (uint64_t)height > MESO_ENVIRONMENT_MAX_PIXELS)
        return meso_log_error(
            ctx, MESO_ERROR_LIMIT, "%s: %dx%d exceeds the limit of %d a side and %u texels", source,
            width, height, MESO_ENVIRONMENT_MAX_SIDE, MESO_ENVIRONMENT_MAX_PIXELS);
    /* the map, the sampling tables and the projection's row sums */
    uint64_t bytes = (uint64_t)width * (uint64_t)height * (3 + 1) * sizeof(float) +
                     (uint64_t)height * ROW_SUMS * sizeof(double);
    return meso_memory_check(ctx, source, bytes);
}

static meso_result new_environment(meso_context *ctx, const char *source, int width, int height,
                                   float intensity, meso_environment **out) {
    *out = NULL;
    meso_environment *env = calloc(1, sizeof *env);
    if (!env) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", source);
    snprintf(env->source, sizeof env->source, "%s", source);
    env->intensity = intensity;
    meso_result r = meso_image_create(ctx, width, height, 3, &env->map);
    if (r != MESO_OK) {
        free(env);
        return r;
    }
    *out = env;
    return MESO_OK;
}

meso_result meso_environment_create_from_image(meso_context *ctx, const meso_image *image,
                                               float intensity, const char *source,
                                               meso_environment **out_environment) {
    *out_environment = NULL;
    if (!source) source = "environment";
    meso_result r;
    if (!image || image->channels < 3)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: needs an RGB image", source);
    if ((r = check_intensity(ctx, source, intensity)) ||
        (r = check_size(ctx, source, image->width, image->height)))
        return r;
    size_t texels = (size_t)image->width * (size_t)image->height;
    for (size_t t = 0; t < texels; t++)
        for (int c = 0; c < 3; c++) {
            float v = image->pixels[t * (size_t)image->channels + (size_t)c];
            if (!(v >= 0.0f && v <= 3.0e38f))
                return meso_log_error(ctx, MESO_ERROR_FORMAT,
                                      "%s: texel %zu holds %g, not a finite radiance >= 0", source,
                                      t, (double)v);
        }
    meso_environment *env = NULL;
    if ((r = new_environment(ctx, source, image->width, image->height, intensity, &env))) return r;
    for (size_t t = 0; t < texels; t++)
        for (int c = 0; c < 3; c++)
            env->map->pixels[3 * t + (size_t)c] =
                image->pixels[t * (size_t)image->channels + (size_t)c] * intensity;
    if ((r = finish(ctx, env)) != MESO_OK) {
        meso_environment_destroy(env);
        return r;
    }
    *out_environment = env;
    return MESO_OK;
}

/* stb_image 2.27 (Debian's) reads past the end of a file as zeros, and its run-length decoder
 * loops forever on a count of 0 (a later stb checks it). So the reader serves 0xff past the end
 * instead: a run of 127 that always advances the decoder, which then ends or reports corrupt
 * data; `past_end` records that the file was short, and the load is refused as truncated. stb
 * asks for more only when it has used every byte it has, so a complete file never sets it. */
typedef struct memory_reader {
    const unsigned char *data;
    size_t size, position;
    bool past_end;
} memory_reader;

static int reader_read(void *user, char *out, int size) {
    memory_reader *m = user;
    if (size <= 0) return 0;
    size_t left = m->size - m->position, n = (size_t)size < left ? (size_t)size : left;
    if (n == 0) {
        /* stb refills only when it has used every byte and needs one more */
        memset(out, 0xff, (size_t)size);
        m->past_end = true;
        return size;
    }
    memcpy(out, m->data + m->position, n);
    m->position += n;
    return (int)n;
}

static void reader_skip(void *user, int n) {
    memory_reader *m = user;
    if (n < 0 && (size_t)-n > m->position)
        m->position = 0;
    else if (n > 0 && (size_t)n > m->size - m->position)
        m->position = m->size, m->past_end = true;
    else
        m->position = (size_t)((long long)m->position + n);
}

static int reader_eof(void *user) {
    memory_reader *m = user;
    return m->position >= m->size;
}

meso_result meso_environment_load(meso_context *ctx, const char *path, float intensity,
                                  meso_environment **out_environment) {
    *out_environment = NULL;
    meso_result r = check_intensity(ctx, path, intensity);
    if (r != MESO_OK) return r;
    /* an OpenEXR file is read by its library from the path: only its magic number is looked
     * at here (a file that cannot be opened falls through to meso_file_read's message) */
    unsigned char head[4];
    size_t head_size = 0;
    FILE *file = fopen(path, "rb");
    if (file) {
        head_size = fread(head, 1, sizeof head, file);
        fclose(file);
    }
    if (meso_file_is_exr(head, head_size)) {
        meso_image *image = NULL;
        r = meso_image_read_exr_rgb(ctx, path, MESO_ENVIRONMENT_MAX_SIDE,
                                    MESO_ENVIRONMENT_MAX_PIXELS, &image);
        if (r == MESO_OK)
            r = meso_environment_create_from_image(ctx, image, intensity, path, out_environment);
        meso_image_destroy(image);
        return r;
    }
    char *data = NULL;
    size_t size = 0;
    if ((r = meso_file_read(ctx, path, MESO_ENVIRONMENT_MAX_FILE_BYTES, &data, &size))) return r;
    float *pixels = NULL;
    meso_image view = {0};
    int width = 0, height = 0, channels = 0;
    if (size > INT32_MAX || !stbi_is_hdr_from_memory((const unsigned char *)data, (int)size)) {
        r = meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: not a Radiance .hdr or OpenEXR file", path);
        goto done;
    }
    /* the header's size first: nothing is decoded past the limits */
    if (!stbi_info_from_memory((const unsigned char *)data, (int)size, &width, &height,
                               &channels)) {
        r = meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: corrupt Radiance header (%s)", path,
                           stbi_failure_reason());
        goto done;
    }
    if ((r = check_size(ctx, path, width, height))) goto done;
    /* stb holds the decoded map besides ours while it is copied */
    if ((r = meso_memory_check(ctx, path, (uint64_t)width * (uint64_t)height * 6 * sizeof(float))))
        goto done;
    memory_reader reader = {(const unsigned char *)data, size, 0, false};
    stbi_io_callbacks callbacks = {reader_read, reader_skip, reader_eof};
    pixels = stbi_loadf_from_callbacks(&callbacks, &reader, &width, &height, &channels, 3);
    if (!pixels) {
        r = meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: corrupt Radiance data (%s)", path,
                           stbi_failure_reason());
        goto done;
    }
    if (reader.past_end) {
        r = meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: truncated Radiance data", path);
        goto done;
    }
    view = (meso_image){width, height, 3, pixels};
    r = meso_environment_create_from_image(ctx, &view, intensity, path, out_environment);
done:
    stbi_image_free(pixels);
    free(data);
    return r;
}

meso_sky_desc meso_sky_desc_defaults(const meso_sky_desc *desc) {
    meso_sky_desc d = desc ? *desc : (meso_sky_desc){0};
    meso_vec3 zero = {0, 0, 0};
#define DEFAULT_VEC(field, x, y, z)                                                                \
    if (memcmp(&d.field, &zero, sizeof zero) == 0) d.field = (meso_vec3){x, y, z}
    DEFAULT_VEC(zenith, 0.25f, 0.42f, 0.85f);
    DEFAULT_VEC(horizon, 0.85f, 0.88f, 0.92f);
    DEFAULT_VEC(ground, 0.25f, 0.22f, 0.2f);
    DEFAULT_VEC(sun_direction, 0.5f, 0.6f, 0.3f);
    DEFAULT_VEC(sun_color, 150.0f, 135.0f, 110.0f);
#undef DEFAULT_VEC
    if (d.gradient == 0.0f) d.gradient = 0.5f;
    if (d.sun_size_deg == 0.0f) d.sun_size_deg = 4.0f;
    if (d.width == 0) d.width = 256;
    return d;
}

meso_result meso_environment_create_sky(meso_context *ctx, const meso_sky_desc *desc,
                                        float intensity, meso_environment **out_environment) {
    *out_environment = NULL;
    meso_sky_desc d = meso_sky_desc_defaults(desc);
    meso_result r = check_intensity(ctx, "sky", intensity);
    if (r != MESO_OK) return r;
    if (d.width < 8 || d.width > MESO_ENVIRONMENT_MAX_SIDE || (d.width & 1))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "sky: width: %d is not an even number in [8, %d]", d.width,
                              MESO_ENVIRONMENT_MAX_SIDE);
    if (!(d.gradient > 0.0f && d.gradient <= 16.0f))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "sky: gradient: %g is not in (0, 16]", (double)d.gradient);
    if (!(d.sun_size_deg > 0.0f && d.sun_size_deg <= 90.0f))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "sky: sun_size_deg: %g is not in (0, 90]", (double)d.sun_size_deg);
    const meso_vec3 *colours[] = {&d.zenith, &d.horizon, &d.ground, &d.sun_color};
    const char *names[] = {"zenith", "horizon", "ground", "sun_color"};
    for (int k = 0; k < 4; k++) {
        meso_vec3 c = *colours[k];
        if (!(c.x >= 0.0f && c.y >= 0.0f && c.z >= 0.0f && c.x <= 1e6f && c.y <= 1e6f &&
              c.z <= 1e6f))
            return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                                  "sky: %s: must be three radiances in [0, 1e6]", names[k]);
    }
    if (!meso_vec3_is_finite(d.sun_direction) || meso_vec3_length(d.sun_direction) < 1e-6f)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "sky: sun_direction: must be a finite non-zero vector");
    int width = d.width, height = d.width / 2;
    if ((r = check_size(ctx, "sky", width, height))) return r;
    meso_image *map = NULL;
    if ((r = meso_image_create(ctx, width, height, 3, &map))) return r;
    meso_vec3 sun = meso_vec3_normalize(d.sun_direction);
    float sun_radius = d.sun_size_deg * MESO_PI / 180.0f;
    for (int j = 0; j < height; j++)
        for (int i = 0; i < width; i++) {
            meso_vec3 dir =
                meso_environment_direction((i + 0.5f) / (float)width, (j + 0.5f) / (float)height);
            meso_vec3 c = d.ground;
            if (dir.y >= 0.0f) {
                float t = powf(dir.y, d.gradient);
                c = meso_vec3_lerp(d.horizon, d.zenith, t);
                /* the sun: a raised-cosine lobe of the angle to its direction, smooth so that
                 * its projection and its samples agree at any map size */
                float angle = acosf(meso_clampf(meso_vec3_dot(dir, sun), -1.0f, 1.0f));
                if (!d.no_sun && angle < sun_radius)
                    c = meso_vec3_madd(c, d.sun_color,
                                       0.5f * (1.0f + cosf(MESO_PI * angle / sun_radius)));
            }
            float *p = meso_image_at(map, i, j);
            p[0] = c.x, p[1] = c.y, p[2] = c.z;
        }
    r = meso_environment_create_from_image(ctx, map, intensity, "sky", out_environment);
    meso_image_destroy(map);
    return r;
}

void meso_environment_destroy(meso_environment *environment) {
    if (!environment) return;
    meso_image_destroy(environment->map);
    free(environment->row_cdf);
    free(environment->column_cdf);
    free(environment);
}

/* ---- Saving ------------------------------------------------------------------------------- */

typedef struct write_state {
    FILE *file;
    bool failed;
} write_state;

static void write_bytes(void *context, void *data, int size) {
    write_state *ws = context;
    if (size > 0 && fwrite(data, 1, (size_t)size, ws->file) != (size_t)size) ws->failed = true;
}

meso_result meso_environment_save_hdr(meso_context *ctx, const meso_environment *environment,
                                      const char *path) {
    meso_atomic_file out;
    meso_result r = meso_atomic_file_open(ctx, path, &out);
    if (r != MESO_OK) return r;
    write_state ws = {out.file, false};
    errno = 0;
    const meso_image *map = environment->map;
    if (!stbi_write_hdr_to_func(write_bytes, &ws, map->width, map->height, 3, map->pixels) ||
        ws.failed) {
        int reason = errno ? errno : EIO;
        meso_atomic_file_abort(&out);
        return meso_log_error(ctx, MESO_ERROR_WRITE, "%s: cannot write: %s", path,
                              strerror(reason));
    }
    return meso_atomic_file_commit(ctx, &out);
}
