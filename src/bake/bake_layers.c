/* Multilayer relief maps (Policarpo & Oliveira 2006, §3; contract in
 * include/meso/bake_layers.h).
 *
 * The paper bakes by ray casting parallel orthographic views in 3D Max (§5, Fig. 6's parallel
 * rays). Here each texel centre's ray down the shell is sphere traced against the solid's
 * distance bound (1-Lipschitz in (u, v, w), mesostructure_solid.c): a step of |f| cannot
 * cross the surface, so every crossing thicker than MIN_STEP is found; each sign change is
 * bisected to float precision and the normal taken from the distance's gradient there.
 * A height field needs no tracing: its one layer is 1 - h at the texel (§3: "a height-field
 * surface can be represented by setting the last three channels of the depth texture to 1.0").
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bake_internal.h"
#include "meso/bake_cache.h"
#include "meso/bake_layers.h"
#include "meso/runtime.h"

#define DEFAULT_SIDE 256
#define DEFAULT_LAYERS 4
/* Smallest sphere-tracing step in w: features thinner than 1/2048 of the shell are skipped. */
#define MIN_STEP (1.0f / 2048.0f)
#define MAX_STEPS 8192
#define BISECTIONS 24
/* Crossings recorded per texel before the num_layers limit (the rest are only counted). */
#define MAX_CROSSINGS 64
#define GRADIENT_STEP 1e-3f
/* The report array: max_count, max_crossings, clipped_texels, clipped_at_four, bake_seconds. */
#define REPORT_FLOATS 5

meso_layers_desc meso_layers_desc_defaults(const meso_layers_desc *desc) {
    meso_layers_desc d = desc ? *desc : (meso_layers_desc){0};
    if (d.width == 0) d.width = d.heightfield ? d.heightfield->width : DEFAULT_SIDE;
    if (d.height == 0) d.height = d.heightfield ? d.heightfield->height : DEFAULT_SIDE;
    if (d.num_layers == 0) d.num_layers = DEFAULT_LAYERS;
    if (d.format == MESO_LAYERS_FORMAT_DEFAULT) d.format = MESO_LAYERS_FORMAT_U8;
    return d;
}

void meso_layers_destroy(meso_layers *map) {
    if (!map) return;
    free(map->depth);
    free(map->normal_x);
    free(map->normal_y);
    free(map->count);
    free(map);
}

static size_t slots(const meso_layers *map) {
    return (size_t)map->width * (size_t)map->height * (size_t)map->num_layers;
}

size_t meso_layers_memory(const meso_layers *map) {
    if (!map) return 0;
    return slots(map) * 3u * sizeof(float) + (size_t)map->width * (size_t)map->height;
}

size_t meso_layers_file_bytes(const meso_layers *map) {
    if (!map) return 0;
    size_t value = map->format == MESO_LAYERS_FORMAT_F32 ? 4u : 1u;
    return slots(map) * 3u * value + (size_t)map->width * (size_t)map->height;
}

meso_vec3 meso_layers_normal(const meso_layers *map, int i, int j, int k) {
    size_t s = ((size_t)j * (size_t)map->width + (size_t)i) * (size_t)map->num_layers + (size_t)k;
    float x = map->normal_x[s], y = map->normal_y[s];
    /* §3: z = sqrt(max(0, 1 - (x^2 + y^2))), negative on exits (they face down). */
    float z = sqrtf(fmaxf(0.0f, 1.0f - (x * x + y * y)));
    return (meso_vec3){x, y, (k & 1) ? -z : z};
}

/* ---- Quantisation ------------------------------------------------------------------------- */

static uint8_t encode_depth(float d) {
    return (uint8_t)lrintf(meso_clampf(d, 0.0f, 1.0f) * 255.0f);
}
static float decode_depth(uint8_t b) { return (float)b / 255.0f; }
static uint8_t encode_normal(float n) {
    return (uint8_t)lrintf((meso_clampf(n, -1.0f, 1.0f) + 1.0f) * 127.5f);
}
static float decode_normal(uint8_t b) { return (float)b / 127.5f - 1.0f; }

/* ---- Validation and allocation ------------------------------------------------------------ */

static meso_result check_desc(meso_context *ctx, const meso_layers_desc *d) {
    int sources = (d->solid != NULL) + (d->heightfield != NULL) + (d->field != NULL);
    if (sources != 1)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "relief_layers: exactly one source (solid, height field or field) "
                              "is needed, %d given",
                              sources);
    if (d->num_layers != 4 && d->num_layers != 8)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "relief_layers: num_layers: %d is not 4 or 8", d->num_layers);
    if (d->width < 1 || d->height < 1 || d->width > MESO_LAYERS_MAX_SIDE ||
        d->height > MESO_LAYERS_MAX_SIDE)
        return meso_log_error(ctx, MESO_ERROR_LIMIT,
                              "relief_layers: size: %d x %d is outside 1..%d a side", d->width,
                              d->height, MESO_LAYERS_MAX_SIDE);
    if (d->format != MESO_LAYERS_FORMAT_U8 && d->format != MESO_LAYERS_FORMAT_F32)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "relief_layers: format: unknown format %d", (int)d->format);
    if (d->heightfield &&
        (d->width != d->heightfield->width || d->height != d->heightfield->height))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "relief_layers: size: %d x %d differs from the height field's "
                              "%d x %d",
                              d->width, d->height, d->heightfield->width, d->heightfield->height);
    return MESO_OK;
}

static meso_result allocate(meso_context *ctx, int width, int height, int num_layers,
                            meso_layers **out) {
    /* the memory budget: depth and two normal planes as float, the counts, and the 8-bit
     * copies a save or load makes of the three planes */
    uint64_t texels = (uint64_t)width * (uint64_t)height;
    meso_result budget = meso_memory_check(ctx, "relief_layers bake",
                                           texels * (uint64_t)num_layers * (3u * 4u + 3u) + texels);
    if (budget != MESO_OK) return budget;
    meso_layers *map = calloc(1, sizeof *map);
    if (!map) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "relief_layers: out of memory");
    map->width = width;
    map->height = height;
    map->num_layers = num_layers;
    size_t n = slots(map);
    map->depth = malloc(n * sizeof(float));
    map->normal_x = malloc(n * sizeof(float));
    map->normal_y = malloc(n * sizeof(float));
    map->count = calloc((size_t)width * (size_t)height, 1);
    if (!map->depth || !map->normal_x || !map->normal_y || !map->count) {
        meso_layers_destroy(map);
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "relief_layers: out of memory");
    }
    *out = map;
    return MESO_OK;
}

/* ---- The bake ----------------------------------------------------------------------------- */

typedef struct bake_job {
    const meso_layers_desc *desc;
    meso_layers *map;
    int *row_max_count, *row_max_crossings;
    uint64_t *row_clipped, *row_clipped_four;
    meso_progress *progress; /* a row a unit */
} bake_job;

static float field_at(const meso_layers_desc *d, meso_vec3 p) {
    float f;
    if (d->solid) {
        f = meso_solid_distance(d->solid, p);
    } else {
        /* a user field: closed by the slab 0 <= w <= 1 like the procedural solids */
        f = d->field(d->field_user, p);
        f = fmaxf(f, fmaxf(-p.z, p.z - 1.0f));
    }
    return f == f ? f : 1.0f; /* NaN counts as outside */
}

static meso_vec3 field_normal(const meso_layers_desc *d, meso_vec3 p) {
    const float h = GRADIENT_STEP;
    meso_vec3 g = {
        field_at(d, (meso_vec3){p.x + h, p.y, p.z}) - field_at(d, (meso_vec3){p.x - h, p.y, p.z}),
        field_at(d, (meso_vec3){p.x, p.y + h, p.z}) - field_at(d, (meso_vec3){p.x, p.y - h, p.z}),
        field_at(d, (meso_vec3){p.x, p.y, p.z + h}) - field_at(d, (meso_vec3){p.x, p.y, p.z - h})};
    float len = sqrtf(meso_vec3_dot(g, g));
    return len > 0.0f ? meso_vec3_scale(g, 1.0f / len) : (meso_vec3){0.0f, 0.0f, -1.0f};
}

/* The crossings of the ray down texel (u, v): sphere tracing with bisection. Writes up to
 * MAX_CROSSINGS depths and returns how many there were in all. A ray still inside at w = 1
 * leaves through the shell's bottom there. */
static int trace_column(const meso_layers_desc *d, float u, float v, float *out_w) {
    int n = 0;
    float w = 0.0f, f = field_at(d, (meso_vec3){u, v, 0.0f});
    bool inside = f < 0.0f;
    if (inside) out_w[n++] = 0.0f;
    for (int step = 0; step < MAX_STEPS && w < 1.0f; step++) {
        float next = fminf(w + fmaxf(fabsf(f), MIN_STEP), 1.0f);
        float g = field_at(d, (meso_vec3){u, v, next});
        bool now = g < 0.0f && next < 1.0f;
        if (now != inside) {
            float lo = w, hi = next; /* lo on the `inside` side, hi on the other */
            for (int b = 0; b < BISECTIONS; b++) {
                float mid = 0.5f * (lo + hi);
                if ((field_at(d, (meso_vec3){u, v, mid}) < 0.0f) == inside)
                    lo = mid;
                else
                    hi = mid;
            }
            if (n < MAX_CROSSINGS) out_w[n] = hi;
            n++;
            inside = now;
        }
        w = next;
        f = g;
    }
    return n;
}

static void bake_row(void *user, size_t job, int thread_index) {
    (void)thread_index;
    bake_job *b = user;
    const meso_layers_desc *d = b->desc;
    meso_layers *map = b->map;
    int j = (int)job, L = map->num_layers;
    int row_max = 0, row_crossings = 0;
    uint64_t clipped = 0, clipped_four = 0;
    float w[MAX_CROSSINGS];
    for (int i = 0; i < map->width; i++) {
        size_t texel = (size_t)j * (size_t)map->width + (size_t)i;
        float *depth = map->depth + texel * (size_t)L;
        float *nx = map->normal_x + texel * (size_t)L, *ny = map->normal_y + texel * (size_t)L;
        float u = ((float)i + 0.5f) / (float)map->width;
        float v = 1.0f - ((float)j + 0.5f) / (float)map->height;
        int n, kept;
        if (d->heightfield) {
            /* one layer: the surface at 1 - h with the normal of w = 1 - h(u, v), i.e. the
             * outward gradient of (1 - h) - w: (-h_u, -h_v, -1) in (u, v, w) */
            meso_vec2 g = meso_heightfield_gradient(d->heightfield, u, v);
            float len = sqrtf(g.x * g.x + g.y * g.y + 1.0f);
            depth[0] = 1.0f - meso_heightfield_texel(d->heightfield, i, j);
            nx[0] = -g.x / len;
            ny[0] = -g.y / len;
            n = kept = 1;
        } else {
            n = trace_column(d, u, v, w);
            /* clip to the limit, keeping an even count (whole entry-exit pairs) */
            kept = n < L ? n : L;
            if (n > L) {
                clipped++;
                kept &= ~1;
            }
            for (int k = 0; k < kept; k++) {
                depth[k] = w[k];
                meso_vec3 normal = field_normal(d, (meso_vec3){u, v, w[k]});
                /* stored with z toward the top: (n_u, n_v, -n_w) */
                nx[k] = normal.x;
                ny[k] = normal.y;
            }
        }
        if (n > 4) clipped_four++;
        for (int k = kept; k < L; k++) {
            depth[k] = 1.0f; /* unused (§3, Fig. 5) */
            nx[k] = ny[k] = 0.0f;
        }
        if (d->format == MESO_LAYERS_FORMAT_U8)
            for (int k = 0; k < L; k++) {
                depth[k] = decode_depth(encode_depth(depth[k]));
                nx[k] = decode_normal(encode_normal(nx[k]));
                ny[k] = decode_normal(encode_normal(ny[k]));
            }
        map->count[texel] = (uint8_t)kept;
        row_max = kept > row_max ? kept : row_max;
        row_crossings = n > row_crossings ? n : row_crossings;
    }
    b->row_max_count[j] = row_max;
    b->row_max_crossings[j] = row_crossings;
    b->row_clipped[j] = clipped;
    b->row_clipped_four[j] = clipped_four;
    meso_progress_advance(b->progress, 1);
}

meso_result meso_layers_bake(meso_context *ctx, const meso_layers_desc *desc,
                             meso_layers **out_map) {
    *out_map = NULL;
    meso_layers_desc d = meso_layers_desc_defaults(desc);
    meso_result r = check_desc(ctx, &d);
    if (r != MESO_OK) return r;
    double start = meso_time_seconds();
    meso_layers *map = NULL;
    if ((r = allocate(ctx, d.width, d.height, d.num_layers, &map)) != MESO_OK) return r;
    map->format = d.format;
    map->wrap = d.heightfield ? d.heightfield->wrap : MESO_WRAP_REPEAT;
    map->from_heightfield = d.heightfield != NULL;
    map->source_hash = meso_layers_cache_key(&d);
    size_t rows = (size_t)d.height;
    bake_job job = {&d,
                    map,
                    calloc(rows, sizeof(int)),
                    calloc(rows, sizeof(int)),
                    calloc(rows, sizeof(uint64_t)),
                    calloc(rows, sizeof(uint64_t)),
                    NULL};
    if (!job.row_max_count || !job.row_max_crossings || !job.row_clipped || !job.row_clipped_four) {
        r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "relief_layers: out of memory");
        meso_layers_destroy(map);
        map = NULL;
    } else {
        job.progress = meso_progress_begin_bake(ctx, "relief_layers", rows);
        meso_parallel_for(ctx, rows, bake_row, &job);
        meso_progress_end(job.progress);
        for (size_t j = 0; j < rows; j++) { /* fixed order: thread-count independent */
            if (job.row_max_count[j] > map->max_count) map->max_count = job.row_max_count[j];
            if (job.row_max_crossings[j] > map->max_crossings)
                map->max_crossings = job.row_max_crossings[j];
            map->clipped_texels += job.row_clipped[j];
            map->clipped_at_four += job.row_clipped_four[j];
        }
        map->bake_seconds = meso_time_seconds() - start;
    }
    free(job.row_max_count);
    free(job.row_max_crossings);
    free(job.row_clipped);
    free(job.row_clipped_four);
    *out_map = map;
    return r;
}

meso_result meso_layers_mirror(meso_context *ctx, const meso_layers *map, meso_layers **out_map) {
    *out_map = NULL;
    if (!map || map->from_heightfield)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "relief_layers: only a solid's map can be seen from below");
    meso_layers *m = NULL;
    meso_result r = allocate(ctx, map->width, map->height, map->num_layers, &m);
    if (r != MESO_OK) return r;
    int L = map->num_layers;
    for (size_t t = 0; t < (size_t)map->width * (size_t)map->height; t++) {
        int c = map->count[t];
        const float *d = map->depth + t * (size_t)L;
        const float *nx = map->normal_x + t * (size_t)L, *ny = map->normal_y + t * (size_t)L;
        for (int k = 0; k < L; k++) {
            size_t s = t * (size_t)L + (size_t)k;
            /* layer c-1-k seen from below; (x, y) of the outward normal are unchanged and its
             * z flips with the axis, as the parity of the layer does */
            m->depth[s] = k < c ? 1.0f - d[c - 1 - k] : 1.0f;
            m->normal_x[s] = k < c ? nx[c - 1 - k] : 0.0f;
            m->normal_y[s] = k < c ? ny[c - 1 - k] : 0.0f;
        }
        m->count[t] = (uint8_t)c;
    }
    m->format = map->format;
    m->wrap = map->wrap;
    m->source_hash = map->source_hash ^ UINT64_C(0x9e3779b97f4a7c15);
    m->max_count = map->max_count;
    m->max_crossings = map->max_crossings;
    m->clipped_texels = map->clipped_texels;
    m->clipped_at_four = map->clipped_at_four;
    *out_map = m;
    return MESO_OK;
}

uint64_t meso_layers_cache_key(const meso_layers_desc *desc) {
    meso_layers_desc d = meso_layers_desc_defaults(desc);
    uint64_t source = d.solid         ? meso_solid_hash(d.solid)
                      : d.heightfield ? d.heightfield->hash
                                      : d.field_hash;
    int32_t ints[] = {
        d.solid ? 1 : d.heightfield ? 2 : 3, d.width, d.height, d.num_layers, (int32_t)d.format,
        (int32_t)MESO_LAYERS_KIND_VERSION};
    uint64_t h = meso_hash64(&source, sizeof source, MESO_HASH_SEED);
    return meso_hash64(ints, sizeof ints, h);
}

/* ---- The bake file ------------------------------------------------------------------------ */

typedef struct file_buffers {
    uint8_t *bytes; /* U8: 3 planes */
    float report[REPORT_FLOATS];
    char params[256];
} file_buffers;

static meso_result to_bake_file(meso_context *ctx, const meso_layers *map, file_buffers *buf,
                                meso_bake_file *out) {
    size_t n = slots(map);
    bool u8 = map->format != MESO_LAYERS_FORMAT_F32;
    buf->bytes = NULL;
    if (u8) {
        buf->bytes = malloc(3 * n);
        if (!buf->bytes)
            return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "relief_layers: out of memory");
        for (size_t s = 0; s < n; s++) {
            buf->bytes[s] = encode_depth(map->depth[s]);
            buf->bytes[n + s] = encode_normal(map->normal_x[s]);
            buf->bytes[2 * n + s] = encode_normal(map->normal_y[s]);
        }
    }
    buf->report[0] = (float)map->max_count;
    buf->report[1] = (float)map->max_crossings;
    buf->report[2] = (float)map->clipped_texels;
    buf->report[3] = (float)map->clipped_at_four;
    buf->report[4] = (float)map->bake_seconds;
    snprintf(buf->params, sizeof buf->params,
             "{\"width\": %d, \"height\": %d, \"num_layers\": %d, \"format\": \"%s\", "
             "\"wrap\": \"%s\", \"heightfield\": %s}",
             map->width, map->height, map->num_layers, u8 ? "u8" : "f32",
             map->wrap == MESO_WRAP_CLAMP ? "clamp" : "repeat",
             map->from_heightfield ? "true" : "false");
    *out = (meso_bake_file){.kind = MESO_LAYERS_KIND,
                            .kind_version = MESO_LAYERS_KIND_VERSION,
                            .source_hash = map->source_hash,
                            .params_json = buf->params,
                            .num_arrays = 5};
    const char *names[3] = {"depth", "normal_x", "normal_y"};
    const float *planes[3] = {map->depth, map->normal_x, map->normal_y};
    for (int a = 0; a < 3; a++) {
        meso_bake_array *arr = &out->arrays[a];
        snprintf(arr->name, sizeof arr->name, "%s", names[a]);
        arr->type = u8 ? MESO_BAKE_U8 : MESO_BAKE_F32;
        arr->num_dims = 3;
        arr->dims[0] = (uint64_t)map->height;
        arr->dims[1] = (uint64_t)map->width;
        arr->dims[2] = (uint64_t)map->num_layers;
        arr->data = u8 ? (void *)(buf->bytes + (size_t)a * n) : (void *)planes[a];
    }
    out->arrays[3] = (meso_bake_array){.name = "count",
                                       .type = MESO_BAKE_U8,
                                       .num_dims = 2,
                                       .dims = {(uint64_t)map->height, (uint64_t)map->width},
                                       .data = map->count};
    out->arrays[4] = (meso_bake_array){.name = "report",
                                       .type = MESO_BAKE_F32,
                                       .num_dims = 1,
                                       .dims = {REPORT_FLOATS},
                                       .data = buf->report};
    return MESO_OK;
}

meso_result meso_layers_save(meso_context *ctx, const meso_layers *map, const char *path) {
    if (!map || !path)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "relief_layers: NULL map or path");
    file_buffers buf;
    meso_bake_file bake;
    meso_result r = to_bake_file(ctx, map, &buf, &bake);
    if (r == MESO_OK) r = meso_bake_file_save(ctx, &bake, path);
    free(buf.bytes);
    return r;
}

/* The params' flags read back: small fixed strings written by to_bake_file. */
static bool params_flag(const char *json, const char *needle) {
    return json && strstr(json, needle) != NULL;
}

meso_result meso_layers_from_bake_file(meso_context *ctx, const meso_bake_file *bake,
                                       const char *name, meso_layers **out_map) {
    *out_map = NULL;
    if (strcmp(bake->kind, MESO_LAYERS_KIND) != 0 || bake->kind_version != MESO_LAYERS_KIND_VERSION)
        return meso_log_error(ctx, MESO_ERROR_FORMAT,
                              "%s: kind '%s' version %u is not a relief_layers bake (version %u)",
                              name, bake->kind, bake->kind_version, MESO_LAYERS_KIND_VERSION);
    const meso_bake_array *depth = meso_bake_file_find(bake, "depth");
    const meso_bake_array *nx = meso_bake_file_find(bake, "normal_x");
    const meso_bake_array *ny = meso_bake_file_find(bake, "normal_y");
    const meso_bake_array *count = meso_bake_file_find(bake, "count");
    const meso_bake_array *report = meso_bake_file_find(bake, "report");
    if (!depth || !nx || !ny || !count || !report)
        return meso_log_error(ctx, MESO_ERROR_FORMAT,
                              "%s: arrays depth, normal_x, normal_y, count and report are "
                              "required",
                              name);
    /* Shapes first, before anything is allocated. */
    bool ok = depth->num_dims == 3 && (depth->type == MESO_BAKE_U8 || depth->type == MESO_BAKE_F32);
    ok = ok && depth->dims[0] >= 1 && depth->dims[0] <= MESO_LAYERS_MAX_SIDE &&
         depth->dims[1] >= 1 && depth->dims[1] <= MESO_LAYERS_MAX_SIDE &&
         (depth->dims[2] == 4 || depth->dims[2] == 8);
    for (int a = 0; a < 2 && ok; a++) {
        const meso_bake_array *x = a ? ny : nx;
        ok = x->type == depth->type && x->num_dims == 3 &&
             !memcmp(x->dims, depth->dims, 3 * sizeof(uint64_t));
    }
    ok = ok && count->type == MESO_BAKE_U8 && count->num_dims == 2 &&
         count->dims[0] == depth->dims[0] && count->dims[1] == depth->dims[1];
    ok = ok && report->type == MESO_BAKE_F32 && report->num_dims == 1 &&
         report->dims[0] == REPORT_FLOATS;
    if (!ok)
        return meso_log_error(ctx, MESO_ERROR_FORMAT,
                              "%s: arrays of the wrong type or shape (depth, normal_x, normal_y: "
                              "height x width x 4 or 8, u8 or f32; count: height x width u8)",
                              name);
    int height = (int)depth->dims[0], width = (int)depth->dims[1], L = (int)depth->dims[2];
    bool u8 = depth->type == MESO_BAKE_U8;
    meso_layers *map = NULL;
    meso_result r = allocate(ctx, width, height, L, &map);
    if (r != MESO_OK) return r;
    map->format = u8 ? MESO_LAYERS_FORMAT_U8 : MESO_LAYERS_FORMAT_F32;
    map->wrap =
        params_flag(bake->params_json, "\"wrap\": \"clamp\"") ? MESO_WRAP_CLAMP : MESO_WRAP_REPEAT;
    map->from_heightfield = params_flag(bake->params_json, "\"heightfield\": true");
    map->source_hash = bake->source_hash;
    size_t n = slots(map);
    const meso_bake_array *src[3] = {depth, nx, ny};
    float *dst[3] = {map->depth, map->normal_x, map->normal_y};
    for (int a = 0; a < 3; a++)
        for (size_t s = 0; s < n; s++)
            dst[a][s] = u8 ? (a ? decode_normal(((const uint8_t *)src[a]->data)[s])
                                : decode_depth(((const uint8_t *)src[a]->data)[s]))
                           : ((const float *)src[a]->data)[s];
    memcpy(map->count, count->data, (size_t)width * (size_t)height);
    /* Values: depths in [0, 1] sorted, unused = 1, normals in [-1, 1], counts even or one. */
    const char *what = NULL;
    size_t bad = 0;
    for (size_t t = 0; t < (size_t)width * (size_t)height && !what; t++) {
        int c = map->count[t];
        if (c > L || (c & 1 && !(map->from_heightfield && c == 1))) what = "layer count", bad = t;
        for (int k = 0; k < L && !what; k++) {
            size_t s = t * (size_t)L + (size_t)k;
            float d = map->depth[s];
            if (!(d >= 0.0f && d <= 1.0f) || (k > 0 && d < map->depth[s - 1]) ||
                (k >= c && d != 1.0f))
                what = "depth", bad = t;
            if (!(fabsf(map->normal_x[s]) <= 1.0f && fabsf(map->normal_y[s]) <= 1.0f))
                what = "normal", bad = t;
        }
        if (c > map->max_count) map->max_count = c;
    }
    if (what) {
        meso_layers_destroy(map);
        return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: texel %zu: invalid %s", name, bad, what);
    }
    const float *rep = report->data;
    map->max_crossings = (int)rep[1];
    map->clipped_texels = (uint64_t)fmaxf(rep[2], 0.0f);
    map->clipped_at_four = (uint64_t)fmaxf(rep[3], 0.0f);
    *out_map = map;
    return MESO_OK;
}

/* The steps of meso_bake_cache_run for relief_layers; desc: the caller's meso_layers_desc. */
static meso_result layers_from_file(meso_context *ctx, const meso_bake_file *bake,
                                    const char *where, const void *desc, void *out) {
    (void)desc;
    return meso_layers_from_bake_file(ctx, bake, where, out);
}

static meso_result layers_bake(meso_context *ctx, const void *desc, void *out) {
    return meso_layers_bake(ctx, desc, out);
}

static meso_result layers_store(meso_context *ctx, const meso_cached_bake *entry, const void *out) {
    file_buffers buf;
    meso_bake_file bake;
    meso_result r = to_bake_file(ctx, *(meso_layers *const *)out, &buf, &bake);
    if (r == MESO_OK) r = meso_bake_cache_save(ctx, &bake, entry->key);
    free(buf.bytes);
    return r;
}

meso_result meso_layers_load(meso_context *ctx, const char *path, meso_layers **out_map) {
    *out_map = NULL;
    return meso_bake_load_with(ctx, path, layers_from_file, NULL, out_map);
}

meso_result meso_layers_bake_cached(meso_context *ctx, const meso_layers_desc *desc,
                                    meso_layers **out_map) {
    *out_map = NULL;
    uint64_t key = meso_layers_cache_key(desc);
    /* a layers bake stores its cache key as its source hash (meso_layers_bake) */
    meso_cached_bake entry = {MESO_LAYERS_KIND,
                              MESO_LAYERS_KIND_VERSION,
                              "relief_layers",
                              key,
                              key,
                              desc,
                              layers_from_file,
                              layers_bake,
                              layers_store};
    return meso_bake_cache_run(ctx, &entry, out_map);
}

size_t meso_layers_describe(const meso_bake_file *bake, char *buffer, size_t size) {
    if (!bake || strcmp(bake->kind, MESO_LAYERS_KIND) != 0) return 0;
    const meso_bake_array *depth = meso_bake_file_find(bake, "depth");
    const meso_bake_array *report = meso_bake_file_find(bake, "report");
    if (!depth || depth->num_dims != 3 || !report || report->type != MESO_BAKE_F32 ||
        report->num_dims != 1 || report->dims[0] != REPORT_FLOATS)
        return 0;
    uint64_t texels = depth->dims[0] * depth->dims[1];
    uint64_t values = texels * depth->dims[2];
    uint64_t bytes = values * 3u * meso_bake_type_size(depth->type) + texels;
    const float *r = report->data;
    char text[1024];
    int n = snprintf(text, sizeof text,
                     "relief_layers: %llu x %llu texels, %llu layers (%s), %.1f KB "
                     "(the paper's three RGBA8 256x256 maps: %.1f KB)\n"
                     "layers used: at most %d; crossings: at most %d; texels clipped by this "
                     "map's limit: %.0f; by the paper's 4-layer limit: %.0f; baked in %.2f s\n",
                     (unsigned long long)depth->dims[1], (unsigned long long)depth->dims[0],
                     (unsigned long long)depth->dims[2],
                     depth->type == MESO_BAKE_U8 ? "8-bit" : "float", (double)bytes / 1024.0,
                     MESO_LAYERS_PAPER_BYTES / 1024.0, (int)r[0], (int)r[1], (double)r[2],
                     (double)r[3], (double)r[4]);
    if (n < 0) return 0;
    if (buffer && size) snprintf(buffer, size, "%s", text);
    return (size_t)n;
}
