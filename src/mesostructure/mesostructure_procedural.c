/* Procedural height fields: bricks, bumps, weave, tiles, bark (docs/mesostructure.md).
 *
 * Each generator is a pure function of (u, v) in the unit tile, built from cell indices taken
 * modulo the repeat counts and from periodic hash noise, so the pattern is exactly periodic in
 * u and v: rasterised at texel centres and sampled with repeat wrapping, texel (0, j) continues
 * texel (W-1, j). No rand(): the same parameters give the same bytes everywhere.
 */
#include <stdlib.h>
#include <string.h>

#include "mesostructure_internal.h"
#include "meso/runtime.h"

typedef struct pattern {
    meso_heightfield_desc desc;
    float cell_u, cell_v; /* cell size in texture units: 1/columns, 1/rows */
    float cell_min;       /* the smaller side: gap and bevel are fractions of it */
    bool color;           /* whether colours are wanted (their noise is skipped otherwise) */
} pattern;

typedef struct texel_value {
    float height;
    float rgb[3];
} texel_value;

/* sin ramp 0 -> 1 over t in [0, 1]: a rounded edge with a finite slope, so bump mapping of
 * the bevel has no infinite normals. */
static float rounded_edge(float t) {
    if (t <= 0.0f) return 0.0f;
    if (t >= 1.0f) return 1.0f;
    return sinf(t * 0.5f * MESO_PI);
}

static void set_rgb(texel_value *out, float r, float g, float b) {
    out->rgb[0] = r;
    out->rgb[1] = g;
    out->rgb[2] = b;
}

/* Texture-space distance from (fx, fy) in a cell [0,1)^2 to the cell's border. */
static float distance_to_cell_border(const pattern *p, float fx, float fy) {
    float dx = fminf(fx, 1.0f - fx) * p->cell_u;
    float dy = fminf(fy, 1.0f - fy) * p->cell_v;
    return fminf(dx, dy);
}

/* A brick's or tile's top lowered by the roughness noise (*top), and the rounded edge's profile
 * at (fx, fy) in its cell: 1 on the top, 0 in the gap; *out_t > 0 on the top past the bevel's
 * start. */
static float rough_bevel(const pattern *p, float u, float v, float fx, float fy, float *top,
                         float *out_t) {
    const meso_heightfield_desc *d = &p->desc;
    float noise = d->roughness > 0.0f ? periodic_fbm(u, v, 8 * d->columns, d->seed + 7u) : 0.0f;
    *top -= d->roughness * (0.5f - 0.5f * noise);
    float half_gap = 0.5f * d->gap * p->cell_min;
    *out_t = (distance_to_cell_border(p, fx, fy) - half_gap) / (d->bevel * p->cell_min);
    return rounded_edge(*out_t);
}

/* Running-bond bricks: odd rows shifted by half a brick; mortar grooves near height 0, brick
 * tops near 1 with rounded edges, each brick slightly lower/tilted by its own hash. */
static void eval_bricks(const pattern *p, float u, float v, texel_value *out) {
    const meso_heightfield_desc *d = &p->desc;
    float y = v * (float)d->rows;
    float fr = floorf(y);
    int row = wrap_index((int)fr, d->rows);
    float x = u * (float)d->columns + ((row & 1) ? 0.5f : 0.0f);
    float fc = floorf(x);
    int column = wrap_index((int)fc, d->columns);
    float fx = x - fc, fy = y - fr;
    uint32_t h = hash_cell(column, row, d->seed);
    float top = 1.0f - 0.08f * hash_unit(h);
    /* A slight per-brick tilt, kept inside [0, 1] by lowering the top first. */
    float tilt = 0.04f * (hash_unit(mix32(h + 1u)) - 0.5f);
    top -= 0.02f;
    top += tilt * (2.0f * fx - 1.0f);
    float t, profile = rough_bevel(p, u, v, fx, fy, &top, &t);
    /* The mortar's noise only shows in the groove and on the bevel. */
    float mortar =
        profile < 1.0f ? 0.03f + 0.02f * periodic_fbm(u, v, 16 * d->columns, d->seed + 13u) : 0.0f;
    out->height = mortar + (top - mortar) * profile;
    if (!p->color) return;
    if (t > 0.0f) {
        /* Brick reds (linear), each brick its own shade, faint mottling inside. */
        float shade = 0.7f + 0.6f * hash_unit(mix32(h + 2u));
        float hue = 0.8f + 0.4f * hash_unit(mix32(h + 3u));
        float mottle = 0.92f + 0.08f * periodic_fbm(u, v, 16 * d->columns, d->seed + 17u);
        set_rgb(out, 0.40f * shade * mottle, 0.10f * shade * hue * mottle, 0.055f * shade * mottle);
    } else {
        float grain = 0.9f + 0.1f * periodic_fbm(u, v, 32 * d->columns, d->seed + 19u);
        set_rgb(out, 0.42f * grain, 0.40f * grain, 0.37f * grain);
    }
}

/* The grid cell (column, row) at (u, v), wrapped, and the point's place (fx, fy) in it. */
static void grid_cell_at(const meso_heightfield_desc *d, float u, float v, int *column, int *row,
                         float *fx, float *fy) {
    float x = u * (float)d->columns, y = v * (float)d->rows;
    float fc = floorf(x), fr = floorf(y);
    *column = wrap_index((int)fc, d->columns), *row = wrap_index((int)fr, d->rows);
    *fx = x - fc, *fy = y - fr;
}

/* A grid of smooth round bumps: a raised cosine of the distance to the cell centre, flat
 * ground (height 0) in the gap between bumps. */
static void eval_bumps(const pattern *p, float u, float v, texel_value *out) {
    const meso_heightfield_desc *d = &p->desc;
    int column, row;
    float fx, fy;
    grid_cell_at(d, u, v, &column, &row, &fx, &fy);
    float dx = (fx - 0.5f) * p->cell_u, dy = (fy - 0.5f) * p->cell_v;
    float radius = 0.5f * (1.0f - d->gap) * p->cell_min;
    float r = sqrtf(dx * dx + dy * dy) / radius;
    uint32_t h = hash_cell(column, row, d->seed);
    float peak = 1.0f - 0.1f * hash_unit(h);
    float bump = r < 1.0f ? peak * 0.5f * (1.0f + cosf(MESO_PI * r)) : 0.0f;
    float noise = d->roughness > 0.0f ? periodic_fbm(u, v, 8 * d->columns, d->seed + 7u) : 0.0f;
    out->height = bump * (1.0f - d->roughness) + d->roughness * (0.5f + 0.5f * noise);
    if (!p->color) return;
    float tint = 0.9f + 0.1f * periodic_fbm(u, v, 4 * d->columns, d->seed + 23u);
    float cell_tint = 0.95f + 0.1f * hash_unit(mix32(h + 5u));
    set_rgb(out, 0.72f * tint * cell_tint, 0.46f * tint, 0.26f * tint * cell_tint);
}

/* One woven ribbon seen across: a cosine cross-section over its width, 0 outside. */
static float ribbon_profile(float f, float width) {
    float s = (f - 0.5f) / (0.5f * width);
    return fabsf(s) < 1.0f ? cosf(0.5f * MESO_PI * s) : -1.0f;
}

/* Over-under plain weave: ribbons along v (one per column) and along u (one per row), each
 * undulating with period two cells so it passes over one crossing and under the next. The
 * visible top is the higher ribbon; the gap between ribbons is at height 0. */
static void eval_weave(const pattern *p, float u, float v, texel_value *out) {
    const meso_heightfield_desc *d = &p->desc;
    float x = u * (float)d->columns, y = v * (float)d->rows;
    float fc = floorf(x), fr = floorf(y);
    float fx = x - fc, fy = y - fr;
    float width = 1.0f - d->gap;
    /* The ribbon along v at this column is over where column + row is even. */
    float across_v = ribbon_profile(fx, width), across_u = ribbon_profile(fy, width);
    float centre_v = 0.5f + 0.25f * cosf(MESO_PI * (y - 0.5f - fc));
    float centre_u = 0.5f - 0.25f * cosf(MESO_PI * (x - 0.5f - fr));
    float top_v = across_v >= 0.0f ? centre_v - 0.25f + 0.5f * across_v : 0.0f;
    float top_u = across_u >= 0.0f ? centre_u - 0.25f + 0.5f * across_u : 0.0f;
    float noise =
        d->roughness > 0.0f || p->color ? periodic_fbm(u, v, 16 * d->columns, d->seed + 7u) : 0.0f;
    float fibre = d->roughness * (0.5f - 0.5f * noise);
    if (across_v < 0.0f && across_u < 0.0f) {
        out->height = 0.0f;
        set_rgb(out, 0.03f, 0.03f, 0.03f);
        return;
    }
    float grain = 0.9f + 0.1f * noise;
    if (top_v >= top_u) {
        out->height = fmaxf(0.0f, top_v - fibre);
        set_rgb(out, 0.70f * grain, 0.56f * grain, 0.32f * grain);
    } else {
        out->height = fmaxf(0.0f, top_u - fibre);
        set_rgb(out, 0.14f * grain, 0.22f * grain, 0.48f * grain);
    }
}

/* Square tiles with grout: tops near 0.95, each slightly tilted and lowered by its hash; grout
 * at 0.15 with a rounded edge between. */
static void eval_tiles(const pattern *p, float u, float v, texel_value *out) {
    const meso_heightfield_desc *d = &p->desc;
    int column, row;
    float fx, fy;
    grid_cell_at(d, u, v, &column, &row, &fx, &fy);
    uint32_t h = hash_cell(column, row, d->seed);
    float tilt_x = 0.03f * (hash_unit(mix32(h + 1u)) - 0.5f);
    float tilt_y = 0.03f * (hash_unit(mix32(h + 2u)) - 0.5f);
    float top =
        0.96f - 0.05f * hash_unit(h) + tilt_x * (2.0f * fx - 1.0f) + tilt_y * (2.0f * fy - 1.0f);
    float t, profile = rough_bevel(p, u, v, fx, fy, &top, &t);
    float grout =
        profile < 1.0f ? 0.15f + 0.02f * periodic_fbm(u, v, 32 * d->columns, d->seed + 11u) : 0.0f;
    out->height = grout + (top - grout) * profile;
    if (!p->color) return;
    if (t > 0.0f) {
        float shade = 0.85f + 0.25f * hash_unit(mix32(h + 3u));
        set_rgb(out, 0.62f * shade, 0.60f * shade, 0.55f * shade);
    } else {
        set_rgb(out, 0.16f, 0.16f, 0.15f);
    }
}

/* Tree bark (GDM paper Fig. 10 shows bark under global illumination): ridged plates along v,
 * one per column, separated by V furrows whose course wanders sideways with v; each plate is
 * split across by `rows` thin cracks a tile at its own heights; the tops carry fibrous noise
 * stretched along v. The furrows' walls rise over `gap` of a column on each side, so the
 * plates are rounded ridges with a flat top only where the furrows are far apart. */
static void eval_bark(const pattern *p, float u, float v, texel_value *out) {
    const meso_heightfield_desc *d = &p->desc;
    /* the furrows' sideways wander: periodic in u and v, so the tile repeats */
    float wander = 0.45f * periodic_fbm(u, v, 3, d->seed + 29u);
    float x = u * (float)d->columns + wander;
    float fc = floorf(x);
    int column = wrap_index((int)fc, d->columns);
    float fx = x - fc;
    uint32_t h = hash_cell(column, 0, d->seed);
    /* across the plate: 0 in the furrow's bottom, 1 on the ridge */
    float edge = fminf(fx, 1.0f - fx);
    float across = rounded_edge((edge - 0.02f) / d->gap);
    /* thin cracks across the plate at rows shifted by the plate's own hash */
    float y = v * (float)d->rows + hash_unit(mix32(h + 1u));
    float fy = y - floorf(y);
    float crack_width = 2.0f * d->bevel * (float)d->rows; /* `bevel` of a tile, both sides */
    float crack = rounded_edge(fminf(fy, 1.0f - fy) / crack_width);
    float crack_depth = 0.35f + 0.25f * hash_unit(mix32(h + 2u));
    /* fibres: noise stretched along v (a tile-periodic lattice 8x finer in u than in v) */
    float fibre = periodic_value_noise(u * (float)(32 * d->columns), v * (float)(4 * d->rows),
                                       32 * d->columns, 4 * d->rows, d->seed + 31u);
    float top =
        0.8f + 0.12f * periodic_fbm(u, v, 4 * d->columns, d->seed + 37u) + 0.06f * (fibre - 0.5f);
    top -= d->roughness * 0.5f * (1.0f + periodic_fbm(u, v, 16 * d->columns, d->seed + 41u));
    float plate = top * (1.0f - crack_depth * (1.0f - crack));
    out->height = 0.04f + (plate - 0.04f) * across;
    if (!p->color) return;
    float grain = 0.85f + 0.3f * fibre;
    float inner = 0.45f + 0.55f * fminf(across, crack); /* furrows and cracks: darker */
    set_rgb(out, 0.36f * grain * inner, 0.29f * grain * inner, 0.22f * grain * inner);
}

typedef void (*eval_fn)(const pattern *p, float u, float v, texel_value *out);

typedef struct raster_job {
    const pattern *pattern;
    eval_fn eval;
    meso_heightfield *heightfield;
    meso_image *color; /* NULL when not asked for */
} raster_job;

/* One row of texels per job: the split does not depend on the thread count. */
static void raster_row(void *user, size_t job, int thread_index) {
    (void)thread_index;
    const raster_job *rj = user;
    meso_heightfield *hf = rj->heightfield;
    int j = (int)job;
    float v = 1.0f - ((float)j + 0.5f) / (float)hf->height;
    for (int i = 0; i < hf->width; i++) {
        float u = ((float)i + 0.5f) / (float)hf->width;
        texel_value value;
        rj->eval(rj->pattern, u, v, &value);
        hf->heights[(size_t)j * (size_t)hf->width + (size_t)i] =
            meso_clampf(value.height, 0.0f, 1.0f);
        if (rj->color) {
            float *px = meso_image_at(rj->color, i, j);
            for (int c = 0; c < 3; c++) px[c] = meso_clampf(value.rgb[c], 0.0f, 1.0f);
        }
    }
}

static meso_result validate_desc(meso_context *ctx, const meso_heightfield_desc *d) {
    const char *name = meso_heightfield_kind_name(d->kind);
    if (d->kind < MESO_HEIGHTFIELD_BRICKS || d->kind > MESO_HEIGHTFIELD_BARK)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "procedural height field: kind: unknown kind %d", (int)d->kind);
    if (d->resolution < 1 || d->resolution > MESO_HEIGHTFIELD_MAX_RESOLUTION)
        return meso_log_error(ctx,
                              d->resolution < 1 ? MESO_ERROR_INVALID_ARGUMENT : MESO_ERROR_LIMIT,
                              "%s: resolution: %d is not in [1, %d]", name, d->resolution,
                              MESO_HEIGHTFIELD_MAX_RESOLUTION);
    if (d->rows < 1 || d->rows > 1024)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: rows: %d is not in [1, 1024]",
                              name, d->rows);
    if (d->columns < 1 || d->columns > 1024)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: columns: %d is not in [1, 1024]", name, d->columns);
    if (d->kind == MESO_HEIGHTFIELD_WEAVE && ((d->rows & 1) || (d->columns & 1)))
        /* The over-under undulation has a period of two cells. */
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: rows and columns must be even to tile (got %d x %d)", name,
                              d->rows, d->columns);
    if (!(d->gap > 0.0f && d->gap < 0.9f))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: gap: %g is not in (0, 0.9)",
                              name, (double)d->gap);
    if (!(d->bevel > 0.0f && d->bevel <= 0.5f))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: bevel: %g is not in (0, 0.5]",
                              name, (double)d->bevel);
    if (!(d->roughness >= 0.0f && d->roughness <= 1.0f))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: roughness: %g is not in [0, 1]", name, (double)d->roughness);
    return MESO_OK;
}

meso_result meso_heightfield_create_procedural(meso_context *ctx, const meso_heightfield_desc *desc,
                                               meso_heightfield **out_heightfield,
                                               meso_image **out_color) {
    *out_heightfield = NULL;
    if (out_color) *out_color = NULL;
    pattern p = {.desc = meso_heightfield_desc_defaults(desc)};
    meso_result r = validate_desc(ctx, &p.desc);
    if (r != MESO_OK) return r;
    p.cell_u = 1.0f / (float)p.desc.columns;
    p.cell_v = 1.0f / (float)p.desc.rows;
    p.cell_min = fminf(p.cell_u, p.cell_v);
    p.color = out_color != NULL;

    static const eval_fn evals[] = {
        [MESO_HEIGHTFIELD_BRICKS] = eval_bricks, [MESO_HEIGHTFIELD_BUMPS] = eval_bumps,
        [MESO_HEIGHTFIELD_WEAVE] = eval_weave,   [MESO_HEIGHTFIELD_TILES] = eval_tiles,
        [MESO_HEIGHTFIELD_BARK] = eval_bark,
    };
    meso_heightfield *hf = NULL;
    meso_image *color = NULL;
    const char *name = meso_heightfield_kind_name(p.desc.kind);
    r = meso_heightfield_alloc(ctx, name, p.desc.resolution, p.desc.resolution, p.desc.wrap, &hf);
    if (r != MESO_OK) goto fail;
    if (out_color) {
        r = meso_image_create(ctx, p.desc.resolution, p.desc.resolution, 3, &color);
        if (r != MESO_OK) goto fail;
    }
    raster_job job = {.pattern = &p, .eval = evals[p.desc.kind], .heightfield = hf, .color = color};
    meso_parallel_for(ctx, (size_t)hf->height, raster_row, &job);
    meso_heightfield_update_hash(hf);
    *out_heightfield = hf;
    if (out_color) *out_color = color;
    return MESO_OK;
fail:
    meso_image_destroy(color);
    meso_heightfield_destroy(hf);
    return r;
}
