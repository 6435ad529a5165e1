/* relief_layers: relief mapping of non-height-field surface details (Policarpo & Oliveira
 * 2006, §3) with a multilayer relief map (bake_layers.h): up to 4 (or 8) depths per texel,
 * a ray at depth d being inside the solid where an odd number of them are <= d (§3.1).
 * Algorithm 1's linear search and Algorithm 2's binary search, then a secant step; the
 * interface rule of §3.2 for the texel whose normals shade the hit; self-shadows by a search
 * toward each light (§3.1, last paragraphs); silhouettes, depth correction and shading shared
 * with `relief` (relief_common.h). Height fields are one layer (§3, Fig. 10) and shade with
 * the field's own gradient, as relief (docs/design.md; why not the baked normals: normal()). Missed
 * rays are discarded (§3.1, "the fragment can be discarded") or, with "missed": 1, drawn on the
 * shell's floor with the mesh's normal (§3.1's base texture). With `shell` 1 the searches run
 * on each prism's stretch of the ray's path through the prism shell (relief_shell.h).
 * docs/techniques/relief_layers.md.
 */
#include "meso/bake_layers.h"
#include "meso/runtime.h"
#include "relief_shell.h"

/* The map as padded planes: plane k of a quantity is (W + 1) x (H + 1) floats whose last row
 * and column repeat the wrapped first ones (or the clamped last ones), as relief_heights. */
typedef struct layers_state {
    /* width, height, clamp; for a height field also the field's heights, which give its
     * shading normal (relief_gradient8); solids: no heights */
    relief_heights size;
    int stride, num_layers; /* layers searched: the most any texel holds */
    bool heightfield;       /* one layer over a floor that is hit (relief's floor rule) */
    bool filter;            /* bilinear where the four texels hold the layer, else nearest */
    bool missed_floor;      /* draw missed rays on the shell's floor */
    /* nx, ny: solids only (a height field shades with its gradient) */
    float *depth[MESO_LAYERS_MAX], *nx[MESO_LAYERS_MAX], *ny[MESO_LAYERS_MAX], *count;
    float *planes;
    /* the depths again with a texel's layers consecutive in groups of four, as the paper's RGBA
     * texels: nearest lookups load a texel's four depths at once instead of four gathers
     * (solids only: a height field is read bilinearly) */
    float *quads;
    int groups;
    int linear_steps, binary_steps, shadow_steps;
    relief_params params;
    size_t bytes;
    struct layers_state *below; /* solids: the map seen from the shell's bottom (back faces) */
    bool enclosed;              /* the `below` state: hits lie inside a closed mesh, unlit */
    bool impostor;              /* §4: the mesh lies at the middle of the shell */
    relief_shell *shell;        /* the shell option; NULL: off */
} layers_state;

typedef struct layers_options {
    int linear_steps, binary_steps, shadow_steps, layers, size, as_float;
    bool shadows, silhouettes, missed, filter, curved, shell;
} layers_options;

/* 0 (and -1 for `float`) are "automatic": the defaults depend on the mesostructure, which the
 * table's fixed defaults cannot say (prepare fills them in). */
static const meso_technique_option layers_option_table[] = {
    MESO_OPTION_ROW(MESO_OPTION_INT, linear_steps, 0, 1024, 0,
                    "steps of the linear search (Algorithm 1); 0: 32, or 64 for an impostor",
                    layers_options, linear_steps),
    MESO_OPTION_ROW(MESO_OPTION_INT, binary_steps, 0, 32, 6,
                    "steps of the binary search after it (Algorithm 2)", layers_options,
                    binary_steps),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, shadows, 0, 1, 1, "self-shadows: a search toward each light",
                    layers_options, shadows),
    MESO_OPTION_ROW(MESO_OPTION_INT, shadow_steps, 1, 1024, 16, "steps of the shadow search",
                    layers_options, shadow_steps),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, silhouettes, 0, 1, 1, "silhouettes from per-vertex quadrics",
                    layers_options, silhouettes),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, missed, 0, 1, 0,
                    "a ray that meets nothing: 0 discards it, 1 draws the shell's floor (§3.1)",
                    layers_options, missed),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, filter, 0, 1, 0,
                    "0: nearest depths and normals (the paper); 1: bilinear", layers_options,
                    filter),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, curved, 0, 1, 1,
                    "scale the texture walk by the surface's curvature", layers_options, curved),
    MESO_OPTION_ROW(MESO_OPTION_INT, layers, 4, 8, 4, "depth layers of the bake: 4 or 8",
                    layers_options, layers),
    MESO_OPTION_ROW(MESO_OPTION_INT, size, 0, 4096, 0,
                    "bake: texels a side; 0: 256, or 512 for an impostor", layers_options, size),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, shell, 0, 1, 0,
                    "1: the searches run along the ray's path through the prism shell, prism by "
                    "prism (exact on curved surfaces, side bands at open borders, silhouettes "
                    "from the shell; CPU only; not for impostors); 0: a straight ray in the "
                    "pixel's tangent space",
                    layers_options, shell),
    MESO_OPTION_ROW(MESO_OPTION_INT, float, -1, 1, -1,
                    "bake in float (1) or 8 bits like the paper (0); -1: float on height fields",
                    layers_options, as_float),
};

static void release(void *state) {
    layers_state *s = state;
    if (!s) return;
    release(s->below);
    relief_shell_destroy(s->shell);
    relief_heights_deinit(&s->size);
    free(s->quads);
    free(s->planes);
    free(s);
}

/* The baked map into padded planes. */
static meso_result fill_planes(meso_context *ctx, const meso_object *object, const meso_layers *map,
                               layers_state *s) {
    int W = map->width, H = map->height, L = map->num_layers;
    s->size = (relief_heights){
        .width = W, .height = H, .stride = W + 1, .clamp = map->wrap == MESO_WRAP_CLAMP};
    s->stride = W + 1;
    s->num_layers = map->max_count > 0 ? map->max_count : 1;
    s->heightfield = map->from_heightfield;
    size_t plane = (size_t)(W + 1) * (size_t)(H + 1);
    size_t per_layer = s->heightfield ? 1u : 3u; /* depth, and nx, ny for solids */
    size_t planes = (size_t)s->num_layers * per_layer + 1u;
    s->planes = malloc(plane * planes * sizeof(float));
    if (!s->planes)
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", object->name);
    s->bytes = plane * planes * sizeof(float);
    for (int k = 0; k < s->num_layers; k++) {
        s->depth[k] = s->planes + plane * per_layer * (size_t)k;
        s->nx[k] = s->heightfield ? NULL : s->depth[k] + plane;
        s->ny[k] = s->heightfield ? NULL : s->nx[k] + plane;
    }
    s->count = s->planes + plane * per_layer * (size_t)s->num_layers;
    s->groups = s->heightfield ? 0 : (s->num_layers + 3) / 4;
    if (s->groups > 0) {
        s->quads = malloc(plane * (size_t)s->groups * 4u * sizeof(float));
        if (!s->quads)
            return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", object->name);
        s->bytes += plane * (size_t)s->groups * 4u * sizeof(float);
    }
    for (int j = 0; j <= H; j++)
        for (int i = 0; i <= W; i++) {
            int si = i, sj = j;
            if (s->size.clamp) {
                si = si >= W ? W - 1 : si;
                sj = sj >= H ? H - 1 : sj;
            } else {
                si = si >= W ? 0 : si;
                sj = sj >= H ? 0 : sj;
            }
            size_t texel = (size_t)sj * (size_t)W + (size_t)si;
            size_t p = (size_t)j * (size_t)s->stride + (size_t)i;
            for (int k = 0; k < 4 * s->groups; k++) /* unused: 1.0, as in the map */
                s->quads[p * 4u * (size_t)s->groups + (size_t)k] =
                    k < L ? map->depth[texel * (size_t)L + (size_t)k] : 1.0f;
            for (int k = 0; k < s->num_layers; k++) {
                size_t slot = texel * (size_t)L + (size_t)k;
                s->depth[k][p] = map->depth[slot];
                if (s->heightfield) continue;
                s->nx[k][p] = map->normal_x[slot];
                s->ny[k][p] = map->normal_y[slot];
            }
            s->count[p] = (float)map->count[texel];
        }
    return MESO_OK;
}

/* Declared here as well as in technique_list.h: prepare reads its own option table through it,
 * and a test compiles this file with the symbol renamed. */
extern const meso_technique meso_technique_relief_layers;

static meso_result prepare(meso_context *ctx, const meso_scene *scene, const meso_object *object,
                           void **out_state) {
    *out_state = NULL;
    const char *name = "relief_layers";
    layers_options options;
    meso_result r = meso_technique_options_read(ctx, scene, object,
                                                &meso_technique_relief_layers.info, &options);
    if (r != MESO_OK) return r;
    /* "float" defaults to 1 on height fields: the search then meets the field's own heights,
     * as relief does (their normals come from the field, not the map, so 8 bits now costs
     * only the depths' rounding, docs/techniques/relief_layers.md); solids keep
     * the paper's 8 bits. */
    /* an impostor (§4) is a whole model on one quad: finer map and search by default */
    bool impostor = object->mesostructure.kind == MESO_MESOSTRUCTURE_SOLID &&
                    object->mesostructure.solid &&
                    !meso_solid_is_periodic(object->mesostructure.solid);
    int shadows = options.shadows, silhouettes = options.silhouettes, missed = options.missed,
        filter = options.filter, layers = options.layers, curved = options.curved;
    int side = options.size > 0 ? options.size : (impostor ? 512 : 256);
    int as_float = options.as_float >= 0
                       ? options.as_float
                       : object->mesostructure.kind == MESO_MESOSTRUCTURE_HEIGHT_FIELD;
    if (side < 16) {
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: technique_options.size: %d is below 16 (%s)", object->name, side,
                              name);
    }
    layers_state *s = calloc(1, sizeof *s);
    if (!s) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", object->name);
    meso_layers *map = NULL, *mirrored = NULL;
    s->linear_steps = options.linear_steps > 0 ? options.linear_steps : (impostor ? 64 : 32);
    s->binary_steps = options.binary_steps;
    s->shadow_steps = options.shadow_steps;
    if (layers != 4 && layers != 8) {
        r = meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                           "%s: technique_options.layers: %d is not 4 or 8 (%s)", object->name,
                           layers, name);
        goto fail;
    }
    meso_layers_desc desc = {.num_layers = layers,
                             .format = as_float ? MESO_LAYERS_FORMAT_F32 : MESO_LAYERS_FORMAT_U8};
    const meso_mesostructure *m = &object->mesostructure;
    if (m->kind == MESO_MESOSTRUCTURE_SOLID && m->solid) {
        desc.solid = m->solid;
        desc.width = desc.height = side;
    } else if (m->kind == MESO_MESOSTRUCTURE_HEIGHT_FIELD && m->height_field) {
        desc.heightfield = m->height_field; /* one layer at the field's own resolution */
    } else {
        r = meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                           "%s: mesostructure: a solid or a height field is required (%s)",
                           object->name, name);
        goto fail;
    }
    if ((r = meso_layers_bake_cached(ctx, &desc, &map)) != MESO_OK) goto fail;
    if (m->kind == MESO_MESOSTRUCTURE_SOLID && m->wrap == MESO_WRAP_CLAMP)
        map->wrap = MESO_WRAP_CLAMP;
    if ((r = fill_planes(ctx, object, map, s)) != MESO_OK) goto fail;
    if (map->from_heightfield) {
        /* the field itself, for its gradient at the hit (normal()); the map is baked at the
         * field's resolution and wrap, so the texel coordinates are the same */
        if ((r = relief_heights_init(ctx, object, &s->size)) != MESO_OK) goto fail;
        s->bytes += relief_heights_memory(&s->size);
    }
    s->filter = filter != 0;
    s->missed_floor = missed != 0;
    s->params.shadows = shadows != 0;
    s->params.silhouettes = silhouettes != 0;
    s->params.curved_uv = curved != 0;
    if ((r = relief_domain_init(ctx, object, &s->params.domain)) != MESO_OK) goto fail;
    if (!map->from_heightfield) {
        /* back faces: the far wall of a closed mesh seen through holes in the near one */
        if (!(s->below = calloc(1, sizeof *s->below))) {
            r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", object->name);
            goto fail;
        }
        if ((r = meso_layers_mirror(ctx, map, &mirrored)) != MESO_OK ||
            (r = fill_planes(ctx, object, mirrored, s->below)) != MESO_OK)
            goto fail;
        layers_state *b = s->below;
        b->filter = s->filter;
        b->linear_steps = s->linear_steps;
        b->binary_steps = s->binary_steps;
        b->shadow_steps = s->shadow_steps;
        b->params = (relief_params){
            .shadows = s->params.shadows, .silhouettes = false, .domain = s->params.domain};
        /* a closed mesh's inside is unlit; an impostor's quad (§4) is seen from behind in the
         * open, lit as from the front */
        b->enclosed = meso_solid_is_periodic(m->solid);
        s->impostor = b->impostor = !meso_solid_is_periodic(m->solid);
        s->bytes += b->bytes;
    }
    if (options.shell && s->impostor) {
        r = meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                           "%s: technique_options.shell: an impostor's quad has no shell (%s)",
                           object->name, name);
        goto fail;
    }
    if (options.shell && (r = relief_shell_create(ctx, object, name, &s->shell)) != MESO_OK)
        goto fail;
    s->bytes += relief_shell_memory(s->shell);
    meso_layers_destroy(map);
    meso_layers_destroy(mirrored);
    *out_state = s;
    return MESO_OK;
fail:
    meso_layers_destroy(map);
    meso_layers_destroy(mirrored);
    release(s);
    return r;
}

/* ---- Sampling ----------------------------------------------------------------------------- */

/* The four texels around eight texel-centre positions and the nearest of them. */
typedef struct layers_cell {
    v8i index, nearest;
    v8f tx, ty;
} layers_cell;

static inline layers_cell layers_locate8(const layers_state *s, v8f x, v8f y) {
    v8i i, j;
    layers_cell c;
    relief_texel8(&s->size, x, y, &i, &j, &c.tx, &c.ty);
    c.index = j * s->stride + i;
    c.nearest = c.index + ((c.tx >= 0.5f) & 1) + ((c.ty >= 0.5f) & s->stride);
    return c;
}

/* A plane at the cell. Solids: the nearest texel (filter 0, the default: the paper's maps are
 * read without mixing layers, §3.2's interfaces), or with filter 1 bilinear where the layer
 * exists in all four texels (its depth < 1: a bilinear mix of a surface with the unused 1.0 of
 * a texel without it would be a surface that is not there) and nearest elsewhere. Height
 * fields: always bilinear, like relief. */
static inline v8f layers_plane8(const layers_state *s, const float *plane, const float *depth,
                                layers_cell c) {
    if (!s->filter && !s->heightfield) return v8_gather(plane, c.nearest);
    v8f p00 = v8_gather(plane, c.index), p10 = v8_gather(plane + 1, c.index);
    v8f p01 = v8_gather(plane + s->stride, c.index);
    v8f p11 = v8_gather(plane + s->stride + 1, c.index);
    v8f top = p00 + (p10 - p00) * c.tx, bottom = p01 + (p11 - p01) * c.tx;
    v8f mixed = top + (bottom - top) * c.ty;
    if (s->heightfield) return mixed;
    v8i full;
    if (plane == depth) {
        full = (p00 < 1.0f) & (p10 < 1.0f) & (p01 < 1.0f) & (p11 < 1.0f);
    } else {
        v8f d00 = v8_gather(depth, c.index), d10 = v8_gather(depth + 1, c.index);
        v8f d01 = v8_gather(depth + s->stride, c.index);
        v8f d11 = v8_gather(depth + s->stride + 1, c.index);
        full = (d00 < 1.0f) & (d10 < 1.0f) & (d01 < 1.0f) & (d11 < 1.0f);
    }
    if (v8_mask_bits(full) == 0xff) return mixed;
    v8i right = c.tx >= 0.5f, down = c.ty >= 0.5f;
    v8f near = v8_select(down, v8_select(right, p11, p01), v8_select(right, p10, p00));
    return v8_select(full, mixed, near);
}

/* Group g of four layers of the nearest texels of eight lanes, as four vectors: eight 16-byte
 * loads and a transpose (AVX), or four gathers. */
static inline void layers_quad8(const layers_state *s, v8i nearest, int g, v8f out[4]) {
#if defined(__AVX__)
    const float *q = s->quads + 4 * g;
    int stride = 4 * s->groups;
    __m256 t0 = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(q + nearest[0] * stride)),
                                     _mm_loadu_ps(q + nearest[4] * stride), 1);
    __m256 t1 = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(q + nearest[1] * stride)),
                                     _mm_loadu_ps(q + nearest[5] * stride), 1);
    __m256 t2 = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(q + nearest[2] * stride)),
                                     _mm_loadu_ps(q + nearest[6] * stride), 1);
    __m256 t3 = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(q + nearest[3] * stride)),
                                     _mm_loadu_ps(q + nearest[7] * stride), 1);
    __m256 u0 = _mm256_unpacklo_ps(t0, t1), u1 = _mm256_unpackhi_ps(t0, t1);
    __m256 u2 = _mm256_unpacklo_ps(t2, t3), u3 = _mm256_unpackhi_ps(t2, t3);
    out[0] = (v8f)_mm256_shuffle_ps(u0, u2, 0x44);
    out[1] = (v8f)_mm256_shuffle_ps(u0, u2, 0xee);
    out[2] = (v8f)_mm256_shuffle_ps(u1, u3, 0x44);
    out[3] = (v8f)_mm256_shuffle_ps(u1, u3, 0xee);
#else
    for (int k = 0; k < 4; k++)
        out[k] =
            4 * g + k < s->num_layers ? v8_gather(s->depth[4 * g + k], nearest) : v8_splat(1.0f);
#endif
}

/* §3.1: inside where d lies between an entry and its exit, i.e. an odd number of the texel's
 * depths are <= d. Returns the mask and f: + or - the distance in depth to the nearest layer
 * (the secant step's function; for a height field exactly relief's d + h - 1). The
 * map's layer count and kind are arguments: constants where the caller knows them, so the loop
 * over the layers unrolls and the tests of the kind vanish. */
__attribute__((always_inline)) static inline v8i layers_inside_core(const layers_state *s, v8f x,
                                                                    v8f y, v8f d, v8f *out_f,
                                                                    int layers, bool quads,
                                                                    bool heightfield) {
    layers_cell c = layers_locate8(s, x, y);
    v8i odd = v8i_splat(0);
    v8f nearest = v8_splat(2.0f);
    /* unused layers (1.0) must not count at the floor itself (d = 1) */
    v8f dt = heightfield ? d : v8_min(d, v8_splat(0.99999f));
    v8f quad[4];
    for (int k = 0; k < layers; k++) {
        if (quads && (k & 3) == 0) layers_quad8(s, c.nearest, k >> 2, quad);
        v8f D = quads ? quad[k & 3] : layers_plane8(s, s->depth[k], s->depth[k], c);
        odd ^= dt >= D;
        v8f gap = d - D;
        gap = v8_select(gap < 0.0f, -gap, gap);
        v8i present = heightfield ? v8i_splat(-1) : D < 1.0f;
        nearest = v8_select(present & (gap < nearest), gap, nearest);
    }
    nearest = v8_min(nearest, v8_splat(1.0f));
    *out_f = v8_select(odd, nearest, -nearest);
    return odd;
}

/* The inside test of the searches (relief_inside8_fn), any map. */
static v8i layers_inside(const void *field, v8f x, v8f y, v8f d, v8f *out_f) {
    const layers_state *s = field;
    return layers_inside_core(s, x, y, d, out_f, s->num_layers, !s->filter && !s->heightfield,
                              s->heightfield);
}

/* ---- Search (§3.1, Algorithms 1 and 2) ---------------------------------------------------- */

/* The same test for the usual map, a solid read at its nearest texels (filter 0) with at most
 * four layers, all in one quad: the four are tested unrolled, the unused ones too, which hold
 * 1.0 (fill_planes) and so neither count (dt < 1) nor are present, as the loop to num_layers
 * leaves them: the same result. */
__attribute__((always_inline)) static inline v8i layers_inside_quad(const void *field, v8f x, v8f y,
                                                                    v8f d, v8f *out_f) {
    return layers_inside_core(field, x, y, d, out_f, 4, true, false);
}

static bool layers_one_quad(const layers_state *s) {
    return !s->filter && !s->heightfield && s->groups == 1;
}

/* The same test for a height field's map (one layer, bilinear), unrolled. */
__attribute__((always_inline)) static inline v8i layers_inside_height(const void *field, v8f x,
                                                                      v8f y, v8f d, v8f *out_f) {
    return layers_inside_core(field, x, y, d, out_f, 1, false, true);
}

/* relief's search with the multilayer inside test; a height field's floor is solid, and so is
 * a solid's with "missed": 1 (drawn there). */
static void search(const void *user, const relief_batch *batches, int count, v8f *out_t,
                   int *out_hit) {
    const layers_state *s = user;
    bool floor_solid = s->heightfield || s->missed_floor;
    /* the curvature's scale of the texture walk is exactly 1 where `lateral` is 0 (a plane,
     * or "curved": 0): those searches skip its division, with the same t */
    bool curved = false;
    for (int g = 0; g < count; ++g) curved |= v8_mask_bits(batches[g].lateral != 0.0f) != 0;
    if (layers_one_quad(s) && curved)
        relief_search8_batches(s, layers_inside_quad, true, floor_solid, batches, count,
                               s->linear_steps, s->binary_steps, out_t, out_hit);
    else if (layers_one_quad(s))
        relief_search8_batches(s, layers_inside_quad, false, floor_solid, batches, count,
                               s->linear_steps, s->binary_steps, out_t, out_hit);
    else if (s->heightfield && s->num_layers == 1)
        relief_search8_batches(s, layers_inside_height, curved, floor_solid, batches, count,
                               s->linear_steps, s->binary_steps, out_t, out_hit);
    else
        relief_search8_batches(s, layers_inside, curved, floor_solid, batches, count,
                               s->linear_steps, s->binary_steps, out_t, out_hit);
}

/* Self-shadows (§3.1): relief's shadow search with the multilayer inside test. The sample's
 * depth is relief's, d (1 - s) + bulge s (1 - s) (relief_shadow_batch): on a curved mesh the
 * surface falls away from the light ray, which so runs deeper than the straight line; without
 * the bulge a sphere's bumps lost shadows that relief and the reference draw. */
static void shadow(const void *user, const relief_shadow_batch *batches, int count,
                   int *out_blocked) {
    const layers_state *s = user;
    for (int g = 0; g < count; ++g) {
        if (s->enclosed) { /* light reaches the inside of a closed mesh only through its other
                              walls, which this map does not hold: taken as blocked */
            out_blocked[g] = batches[g].active_bits;
            continue;
        }
        if (layers_one_quad(s))
            out_blocked[g] =
                relief_shadow_walk8(s, layers_inside_quad, &batches[g], s->shadow_steps);
        else if (s->heightfield && s->num_layers == 1)
            out_blocked[g] =
                relief_shadow_walk8(s, layers_inside_height, &batches[g], s->shadow_steps);
        else
            out_blocked[g] = relief_shadow_walk8(s, layers_inside, &batches[g], s->shadow_steps);
    }
}

/* ---- Normals (§3, Fig. 5; §3.2) ---------------------------------------------------------- */

/* The layer normals at the hit, for solids. §3.2: the last outside and inside points of the
 * binary search lie one bracket (t_end / (linear_steps 2^binary_steps)) either side of the hit;
 * of their nearest texels the one with more layers is read, so a ray that entered a four-layer
 * texel is not shaded with a two-layer neighbour's normals. Its entry layer nearest in depth
 * gives (x, y), z = sqrt(max(0, 1 - x^2 - y^2)) (§3), and the texture-space normal goes to
 * world space through the gradients of u, v and -w: x grad u + y grad v + z N / depth (the
 * same normal as relief_normal8's cross product for a height field's (-h_u, -h_v, 1)).
 *
 * Height fields do not come here (shade passes no callback: relief's gradient normal). Their
 * baked normals are right at texel centres, but texture space is anisotropic (u spans a tile,
 * w only the shell's depth), so a field's normal there is nearly horizontal: a cone one shell
 * deep over 8 texels of 256 has slope 32 per u, z = 0.03. Bilinear (x, y) of unit normals
 * whose directions differ (around a cone's tip, across a ridge) is shorter than 1, and the z
 * rebuilt from it is too large, by a factor of two and more on many points of the truth
 * suite's cones: they drew far below relief (docs/techniques/relief_layers.md). Solids read the
 * nearest texel's normal, not a mix, so they do not meet it. */
static void normal(const void *user, const relief_lanes *l, const relief_batch *batch, v8f t,
                   v8f hx, v8f hy, v8f hd, float depth, v8vec3 *out) {
    const layers_state *s = user;
    float scale = 1.0f / ((float)s->linear_steps * (float)(1 << s->binary_steps));
    v8f delta = batch->t_end * scale;
    layers_cell a = layers_locate8(s, hx - batch->xd * delta, hy - batch->yd * delta);
    layers_cell b = layers_locate8(s, hx + batch->xd * delta, hy + batch->yd * delta);
    v8f ca = v8_gather(s->count, a.nearest), cb = v8_gather(s->count, b.nearest);
    v8i index = (v8i)v8_select(cb > ca, (v8f)b.nearest, (v8f)a.nearest);
    (void)t;
    v8f x = v8_splat(0.0f), y = v8_splat(0.0f), best = v8_splat(3.0f);
    for (int k = 0; k < s->num_layers; k += 2) { /* entries: the even layers */
        v8f D = v8_gather(s->depth[k], index);
        v8f gap = hd - D;
        gap = v8_select(gap < 0.0f, -gap, gap);
        v8i closer = (gap < best) & (D < 1.0f);
        if (!v8_any(closer)) continue;
        x = v8_select(closer, v8_gather(s->nx[k], index), x);
        y = v8_select(closer, v8_gather(s->ny[k], index), y);
        best = v8_select(closer, gap, best);
    }
    v8f z = v8_sqrt(v8_max(v8_splat(0.0f), 1.0f - (x * x + y * y)));
    float inv_depth = depth > 0.0f ? 1.0f / depth : 0.0f;
    v8vec3 n = {x * l->bn.x + y * l->nt.x + z * inv_depth * l->tb.x,
                x * l->bn.y + y * l->nt.y + z * inv_depth * l->tb.y,
                x * l->bn.z + y * l->nt.z + z * inv_depth * l->tb.z};
    v8f len2 = v8_dot(n, n);
    v8i ok = (len2 > 1e-30f) & (len2 < 1e30f) & (best < 2.0f);
    /* a ray that missed and is drawn on the floor (missed = 1) keeps the mesh's normal */
    if (s->missed_floor) ok &= (best < 0.02f) | (hd < 0.999f);
    v8f inv = 1.0f / v8_sqrt(v8_select(ok, len2, v8_splat(1.0f)));
    inv = v8_select(v8_dot(n, l->normal) < 0.0f, -inv, inv);
    *out = (v8vec3){v8_select(ok, n.x * inv, l->normal.x), v8_select(ok, n.y * inv, l->normal.y),
                    v8_select(ok, n.z * inv, l->normal.z)};
}

/* Whether the fragment's triangle faces away from the eye (geometric normal, counter-clockwise
 * from outside). */
static bool back_facing(const meso_frame *frame, const meso_object *object,
                        const meso_fragment *f) {
    const meso_mesh *mesh = object->mesh;
    if (!mesh || f->triangle >= mesh->num_triangles)
        return meso_vec3_dot(meso_vec3_sub(f->position, frame->eye), f->normal) > 0.0f;
    const uint32_t *t = mesh->indices + 3 * (size_t)f->triangle;
    meso_vec3 a = mesh->positions[t[0]], b = mesh->positions[t[1]], c = mesh->positions[t[2]];
    meso_vec3 n = meso_vec3_cross(meso_vec3_sub(b, a), meso_vec3_sub(c, a));
    return meso_vec3_dot(meso_vec3_sub(a, frame->eye), n) > 0.0f;
}

/* Move a fragment along its view ray by t (in units of position - eye): position, texture
 * coordinates (by the ray's texture-space direction) and view depth. */
static void move_along_ray(meso_fragment *f, const meso_frame *frame, float t) {
    meso_vec3 view = meso_vec3_sub(f->position, frame->eye);
    float cu, cv, cn;
    if (relief_frame_solve(f, view, &cu, &cv, &cn)) {
        f->uv.x += t * cu;
        f->uv.y += t * cv;
    }
    f->position = meso_vec3_madd(f->position, view, t);
    f->depth *= 1.0f + t;
    f->out_depth = f->depth;
}

/* Fragments of front faces: the search from the mesh (or, for an impostor, from the shell's
 * top) down. */
static void shade_front(const layers_state *s, const meso_frame *frame, const meso_object *object,
                        meso_fragment *fragments, size_t count) {
    if (s->impostor) {
        /* §4: the quad passes through the middle of the object (depth 0.5): the search
         * starts where the ray crosses the shell's top, half the depth above the quad */
        float half = 0.5f * object->mesostructure.depth;
        for (size_t i = 0; i < count; ++i) {
            meso_fragment *f = &fragments[i];
            float vn = meso_vec3_dot(meso_vec3_sub(f->position, frame->eye), f->normal);
            if (vn < 0.0f) move_along_ray(f, frame, half / vn);
        }
    }
    /* a height field: no normal callback, so relief_shade_fragments takes the field's
     * gradient from s->size's heights (normal() says why not the baked normals) */
    relief_tracer tracer = {s, search, shadow, s->heightfield ? NULL : normal};
    relief_shade_fragments(&s->size, &tracer, s->params, frame, object, fragments, count);
}

/* Fragments of back faces (both_faces): the mirrored search from the shell's bottom up. */
static void shade_back(const layers_state *s, const meso_frame *frame, const meso_object *object,
                       meso_fragment *fragments, size_t count) {
    if (!s->below) { /* a height field's floor is solid: nothing shows through it */
        for (size_t i = 0; i < count; ++i) fragments[i].discard = true;
        return;
    }
    /* A back face: the view ray left the mesh here, after crossing the shell from its bottom
     * (w = 1) up to the mesh. Seen from below, the shell is the mirrored solid over the bottom
     * surface with normal -N: the front-face search runs unchanged on the mirrored map (as §4
     * turns the search around for an impostor's back), from the point where the ray crossed
     * w = 1, and its hit lies nearer than the mesh. Going back along the ray by tau from the
     * fragment, the depth below the curved surface is w = tau (a - b tau) (the quadric of
     * relief_common.h); a ray that never reached w = 1 skimmed the shell and the front face's
     * search already covered its whole path (a silhouette): discarded. */
    float depth = object->mesostructure.depth;
    for (size_t i = 0; i < count; ++i) {
        meso_fragment *f = &fragments[i];
        meso_vec3 view = meso_vec3_sub(f->position, frame->eye);
        float a = meso_vec3_dot(view, f->normal) / depth, b = 0.0f;
        if (s->params.silhouettes) {
            meso_vec2 q = relief_fragment_quadric(object, f);
            float tl = meso_vec3_length(f->tangent), bl = meso_vec3_length(f->bitangent);
            float x = tl > 0.0f ? meso_vec3_dot(view, f->tangent) / tl : 0.0f;
            float y = bl > 0.0f ? meso_vec3_dot(view, f->bitangent) / bl : 0.0f;
            b = (q.x * x * x + q.y * y * y) / depth;
        }
        if (s->impostor) a *= 2.0f; /* §4: the bottom lies half the depth below the quad */
        float disc = a * a - 4.0f * b;
        float tau = disc >= 0.0f && a > 0.0f ? 2.0f / (a + sqrtf(disc)) : INFINITY;
        if (!(tau < 1.0f)) { /* skimmed (or the bottom lies behind the eye) */
            f->discard = true;
            continue;
        }
        move_along_ray(f, frame, -tau);
        f->normal = meso_vec3_negate(f->normal);
    }
    /* the fragments still drawn, in runs */
    size_t kept = 0;
    for (size_t i = 0; i < count; ++i)
        if (!fragments[i].discard) kept++;
    if (kept == count) {
        relief_tracer tracer = {s->below, search, shadow, normal};
        relief_shade_fragments(&s->below->size, &tracer, s->below->params, frame, object, fragments,
                               count);
        return;
    }
    for (size_t start = 0; start < count;) { /* runs of kept fragments */
        while (start < count && fragments[start].discard) start++;
        size_t end = start;
        while (end < count && !fragments[end].discard) end++;
        if (end > start) {
            relief_tracer tracer = {s->below, search, shadow, normal};
            relief_shade_fragments(&s->below->size, &tracer, s->below->params, frame, object,
                                   fragments + start, end - start);
        }
        start = end;
    }
}

/* ---- On the shell (relief_shell.h): §3.1's test on each prism's stretch ------------------- */

static bool shell_inside(const void *user, float x, float y, float d, float *out_f) {
    v8f f;
    v8i in = layers_inside(user, v8_splat(x), v8_splat(y), v8_splat(d), &f);
    *out_f = f[0];
    return in[0] != 0;
}

static int shell_inside8(const void *user, const v8f *x, const v8f *y, const v8f *d, v8f *out_f) {
    return v8_mask_bits(layers_inside(user, *x, *y, *d, out_f));
}

/* The hit's normal: a height field's gradient (as relief; normal() says why not the baked
 * normals); a solid's from the nearest texel's layer nearest in depth among those the ray can
 * meet going its way -- entries (even layers, facing up) going down, exits (odd, facing down)
 * going up, as the far wall of a closed mesh is seen from inside -- (x, y, +-z) to world space
 * as normal() does, through the base frame at the hit. */
static meso_vec3 shell_normal(const void *user, float x, float y, float d, bool upward,
                              const relief_shell_frame *f) {
    const layers_state *s = user;
    if (s->heightfield) return relief_shell_heights_normal(&s->size, x, y, f);
    layers_cell c = layers_locate8(s, v8_splat(x), v8_splat(y));
    int index = c.nearest[0];
    float nx = 0.0f, ny = 0.0f, best = 3.0f;
    for (int k = upward ? 1 : 0; k < s->num_layers; k += 2) {
        float D = s->depth[k][index], gap = fabsf(d - D);
        if (gap < best && D < 1.0f) nx = s->nx[k][index], ny = s->ny[k][index], best = gap;
    }
    if (!(best < 2.0f)) return upward ? meso_vec3_negate(f->normal) : f->normal;
    float nz = sqrtf(fmaxf(0.0f, 1.0f - (nx * nx + ny * ny)));
    float inv_depth = f->depth > 0.0f ? 1.0f / f->depth : 0.0f;
    meso_vec3 n =
        meso_vec3_add(meso_vec3_add(meso_vec3_scale(f->bn, nx), meso_vec3_scale(f->nt, ny)),
                      meso_vec3_scale(f->tb, (upward ? -nz : nz) * inv_depth));
    float len2 = meso_vec3_dot(n, n);
    if (!(len2 > 1e-30f && len2 < 1e30f)) return upward ? meso_vec3_negate(f->normal) : f->normal;
    return meso_vec3_scale(n, 1.0f / sqrtf(len2));
}

static meso_result geometry(meso_context *ctx, void *state, const meso_frame *frame,
                            const meso_mesh **out_mesh) {
    (void)ctx;
    layers_state *s = state;
    *out_mesh = s->shell ? relief_shell_geometry(s->shell, frame) : NULL;
    return MESO_OK;
}

/* A batch may span triangles (render_internal.h): runs of fragments whose triangles face the
 * same way go to the front or the back search. A triangle's fragments are consecutive, so the
 * facing is computed once a triangle. */
static void shade(const void *state, const meso_frame *frame, const meso_object *object,
                  meso_fragment *fragments, size_t count) {
    const layers_state *s = state;
    if (s->shell) { /* a light leaving through the shell's bottom: lit (the walk's rule) */
        relief_shell_search q = {.user = s,
                                 .width = s->size.width,
                                 .height = s->size.height,
                                 .inside = shell_inside,
                                 .inside8 = shell_inside8,
                                 .normal = shell_normal,
                                 .linear_steps = s->linear_steps,
                                 .binary_steps = s->binary_steps,
                                 .shadow_steps = s->shadow_steps,
                                 .shadows = s->params.shadows,
                                 .floor_solid = s->heightfield,
                                 .shadow_bias = RELIEF_SHADOW_BIAS};
        relief_shell_shade(s->shell, &q, frame, object, fragments, count);
        return;
    }
    size_t start = 0;
    bool back = false;
    uint32_t triangle = UINT32_MAX;
    for (size_t i = 0; i < count; i++) {
        if (fragments[i].triangle == triangle && i > 0) continue;
        triangle = fragments[i].triangle;
        bool facing_back = back_facing(frame, object, &fragments[i]);
        if (i > 0 && facing_back == back) continue;
        if (i > start) {
            if (back)
                shade_back(s, frame, object, fragments + start, i - start);
            else
                shade_front(s, frame, object, fragments + start, i - start);
        }
        start = i;
        back = facing_back;
    }
    if (count > start) {
        if (back)
            shade_back(s, frame, object, fragments + start, count - start);
        else
            shade_front(s, frame, object, fragments + start, count - start);
    }
}

static size_t memory(const void *state) { return state ? ((const layers_state *)state)->bytes : 0; }

const meso_technique meso_technique_relief_layers = {
    .info = {.name = "relief_layers",
             .summary = "multilayer relief maps: non-height-field details, shadows, silhouettes",
             .paper = "Policarpo & Oliveira 2006, §3",
             .kind = MESO_TECHNIQUE_PER_PIXEL,
             .accepts = MESO_TECHNIQUE_ACCEPTS_HEIGHT_FIELD | MESO_TECHNIQUE_ACCEPTS_SOLID |
                        MESO_TECHNIQUE_ACCEPTS_MODEL_SOLID, /* §4: impostors */
             .options = layers_option_table,
             .num_options = MESO_OPTION_COUNT(layers_option_table)},
    .prepare = prepare,
    .release = release,
    .geometry = geometry,
    .shade = shade,
    .memory = memory,
    .both_faces = true,
};
