/* horizon: horizon mapping (Max 1988, "Horizon mapping: shadows for bump-mapped surfaces";
 * Sloan & Cohen 2000, "Interactive horizon mapping"), the baseline of VDM's Table 1: shading
 * as bump mapping (the displaced normal at the fragment's own uv, no parallax) and a shadow per
 * light where the light's elevation is below the baked horizon in the light's azimuth,
 * interpolated between the two nearest baked azimuths and between the four nearest texels,
 * with a smooth step of SOFT_RADIANS so the shadow edge does not alias (Sloan & Cohen §3).
 * The bake is src/bake/bake_horizon.c. docs/techniques/horizon.md. */
#include "meso/bake_horizon.h"
#include "meso/runtime.h"
#include "relief_common.h"

/* Half-width of the smooth transition at the horizon, in sin of the angle between the light
 * and the horizon (about 2.9 degrees). */
#define SOFT_RADIANS 0.05f

typedef struct horizon_state {
    relief_heights heights;
    meso_horizon_map *map;
} horizon_state;

typedef struct horizon_options {
    int num_azimuths, max_distance;
} horizon_options;

static const meso_technique_option horizon_option_table[] = {
    MESO_OPTION_ROW(MESO_OPTION_INT, num_azimuths, 1, MESO_HORIZON_MAX_AZIMUTHS, 8,
                    "directions of the baked horizon map (Sloan & Cohen 2000)", horizon_options,
                    num_azimuths),
    MESO_OPTION_ROW(MESO_OPTION_INT, max_distance, 1, MESO_HORIZON_MAX_DISTANCE, 64,
                    "texels searched for the horizon in each direction", horizon_options,
                    max_distance),
};

static void release(void *state) {
    horizon_state *s = state;
    if (!s) return;
    relief_heights_deinit(&s->heights);
    meso_horizon_map_destroy(s->map);
    free(s);
}

static meso_result prepare(meso_context *ctx, const meso_scene *scene, const meso_object *object,
                           void **out_state) {
    *out_state = NULL;
    horizon_options options;
    meso_result r =
        meso_technique_options_read(ctx, scene, object, &meso_technique_horizon.info, &options);
    if (r != MESO_OK) return r;
    horizon_state *s = calloc(1, sizeof *s);
    if (!s) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", object->name);
    if ((r = relief_heights_init(ctx, object, &s->heights)) != MESO_OK) goto fail;
    meso_horizon_desc desc = {.num_azimuths = options.num_azimuths,
                              .max_distance = (float)options.max_distance};
    if ((r = meso_horizon_map_bake(ctx, object->mesostructure.height_field, &desc, &s->map)) !=
        MESO_OK)
        goto fail;
    *out_state = s;
    return MESO_OK;
fail:
    release(s);
    return r;
}

static float smooth_step(float edge0, float edge1, float x) {
    float t = meso_clampf((x - edge0) / (edge1 - edge0), 0.0f, 1.0f);
    return t * t * (3.0f - 2.0f * t);
}

/* atan2 to about 1e-5 radians (a minimax polynomial on [0, 1] and octant folding): the
 * azimuth only picks and blends two baked directions, so libm's last digits buy nothing. */
static inline float fast_atan2(float y, float x) {
    float ax = fabsf(x), ay = fabsf(y);
    float lo = ax < ay ? ax : ay, hi = ax < ay ? ay : ax;
    if (!(hi > 0.0f)) return 0.0f;
    float z = lo / hi, z2 = z * z;
    float r =
        z *
        (0.99997726f +
         z2 * (-0.33262347f +
               z2 * (0.19354346f + z2 * (-0.11643287f + z2 * (0.05265332f - z2 * 0.01172120f)))));
    if (ay > ax) r = 0.5f * MESO_PI - r;
    if (x < 0.0f) r = MESO_PI - r;
    return y < 0.0f ? -r : r;
}

/* The horizon slope toward phi at texel-centre coordinates (x, y): bilinear over the four
 * nearest texels, each interpolated between the two nearest azimuths (Max 1988 §2). */
static float horizon_slope(const meso_horizon_map *map, bool clamp, float x, float y, float phi) {
    int n = map->num_azimuths;
    float a = phi * (float)n * (1.0f / (2.0f * MESO_PI));
    a -= (float)n * floorf(a / (float)n);
    int k0 = (int)a;
    k0 = k0 >= n ? n - 1 : k0;
    float ta = a - (float)k0;
    int k1 = k0 + 1 == n ? 0 : k0 + 1;
    float fx = floorf(x), fy = floorf(y);
    int i = (int)fx, j = (int)fy;
    float tx = x - fx, ty = y - fy;
    float s[4];
    for (int c = 0; c < 4; ++c) {
        int ci = i + (c & 1), cj = j + (c >> 1);
        if (clamp) {
            ci = ci < 0 ? 0 : (ci >= map->width ? map->width - 1 : ci);
            cj = cj < 0 ? 0 : (cj >= map->height ? map->height - 1 : cj);
        } else {
            ci %= map->width;
            cj %= map->height;
            ci += ci < 0 ? map->width : 0;
            cj += cj < 0 ? map->height : 0;
        }
        const float *t = map->slopes + ((size_t)cj * (size_t)map->width + (size_t)ci) * (size_t)n;
        s[c] = t[k0] + (t[k1] - t[k0]) * ta;
    }
    float top = s[0] + (s[1] - s[0]) * tx, bottom = s[2] + (s[3] - s[2]) * tx;
    return top + (bottom - top) * ty;
}

static void shade(const void *state, const meso_frame *frame, const meso_object *object,
                  meso_fragment *fragments, size_t count) {
    const horizon_state *s = state;
    const relief_heights *m = &s->heights;
    const meso_scene *scene = frame->scene;
    int num_lights =
        scene->num_lights < MESO_SCENE_MAX_LIGHTS ? scene->num_lights : MESO_SCENE_MAX_LIGHTS;
    float depth = object->mesostructure.depth;
    for (size_t start = 0; start < count; start += RELIEF_LANES) {
        int n = count - start < RELIEF_LANES ? (int)(count - start) : RELIEF_LANES;
        meso_fragment *f = fragments + start;
        relief_lanes l;
        v8f x, y;
        meso_shade_batch in;
        relief_bump_lanes(m, frame, f, n, depth, &l, &x, &y, &in);
        for (int k = 0; k < n; ++k) {
            for (int li = 0; li < num_lights; ++li) {
                meso_vec3 L = meso_light_direction(&scene->lights[li], f[k].position);
                float lu, lv, ln;
                if (!(depth > 0.0f) || !relief_frame_solve(&f[k], L, &lu, &lv, &ln)) continue;
                /* The light's azimuth in (u, v) and its elevation above the tangent plane:
                 * rise ln over the run |lu T + lv B| (world units). */
                float phi = fast_atan2(lv, lu);
                meso_vec3 flat = meso_vec3_add(meso_vec3_scale(f[k].tangent, lu),
                                               meso_vec3_scale(f[k].bitangent, lv));
                float along = meso_vec3_length(flat);
                /* bake_horizon.h: tan(horizon) = slope depth / |cos phi T + sin phi B|, and
                 * |cos phi T + sin phi B| = along / |(lu, lv)|: rise S over run R. */
                float uv_len = sqrtf(lu * lu + lv * lv);
                float rise = horizon_slope(s->map, m->clamp, x[k], y[k], phi) * depth * uv_len;
                float run = along;
                /* sin(light elevation - horizon elevation), without inverse trigonometry; a
                 * difference beyond -90 degrees (cos < 0) is deep in shadow. */
                float sin_d = ln * run - along * rise, cos_d = along * run + ln * rise;
                float norm = sqrtf((ln * ln + along * along) * (run * run + rise * rise));
                sin_d = norm > 0.0f ? sin_d / norm : 1.0f;
                /* (a vector element is assigned, not pointed to: clang has no address of one) */
                in.visibility[li][k] = cos_d < 0.0f && sin_d < 0.0f
                                           ? 0.0f
                                           : smooth_step(-SOFT_RADIANS, SOFT_RADIANS, sin_d);
            }
        }
        relief_shade_store(frame, object, &in, f, n);
    }
}

static size_t memory(const void *state) {
    const horizon_state *s = state;
    return s ? relief_heights_memory(&s->heights) + meso_horizon_map_memory(s->map) : 0;
}

const meso_technique meso_technique_horizon = {
    .info = {.name = "horizon",
             .summary = "bump mapping with horizon-map self-shadows",
             .paper = "Max 1988; Sloan & Cohen 2000 (baseline of VDM Table 1)",
             .kind = MESO_TECHNIQUE_PER_PIXEL,
             .accepts = MESO_TECHNIQUE_ACCEPTS_HEIGHT_FIELD,
             .options = horizon_option_table,
             .num_options = MESO_OPTION_COUNT(horizon_option_table)},
    .prepare = prepare,
    .release = release,
    .shade = shade,
    .memory = memory,
};
