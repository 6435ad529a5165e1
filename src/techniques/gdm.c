/* gdm: generalized displacement maps (Wang et al. 2004, §3.2, docs/techniques/gdm.md). Every
 * base triangle is extruded into a prism (meso/prism.h, the shared shell); the prisms'
 * forward-facing faces are rasterized (a geometry technique); per fragment the ray's exit
 * from its prism (Fig. 5), the texture-space segment T_in -> T_out, d = GDM(T_in, V_t), a hit
 * where d < |T_out - T_in| at T = T_in + d V_t, mapped back to object space for its depth and
 * shading; shadows where GDM(T, L_t) ends before the slab's boundary. Height fields and solids
 * alike: the map is baked from either (src/bake/bake_gdm.c) and cached. */
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "gdm_gi.h"
#include "gdm_lookup.h"
#include "gdm_shell_shadow.h"
#include "gdm_walk.h"
#include "meso/bake_gdm.h"
#include "meso/runtime.h"
#include "meso/prism.h"
#include "render_internal.h"

#define GDM_WINDOW_LEVELS 7 /* height fields' window maxima: up to 64 texels a side */
#define GDM_WINDOW_FIRST 2  /* the least level window_bound reads (its boxes: 4 texels) */
/* solids' distance grid (solid_grid): nodes a side in u and v, and in w (both slab faces), so
 * that a probe is at most ~0.009 (u, v, w) units from a node */
#define GDM_GRID_SIDE 128
#define GDM_GRID_LAYERS 65
/* Newton steps mapping the view ray's midpoint into its prism (shade_one): from the segment's
 * midpoint, usually a fraction of a voxel off, one step leaves rounding error; where the shell
 * turns sharply (weave-teapot's handle) the midpoint is farther off and the steps go on, up to
 * 4, until one moves (u, v, w) by less than the tolerance: a third of a voxel of a 64-voxel
 * tile, after which the error left is about its square (1e-3 drew the same, with more
 * instructions) */
#define GDM_UNMAP_ITERATIONS 4
#define GDM_UNMAP_TOLERANCE 5e-3f
/* refine_hit's most probes along a segment where the table was wrong */
#define GDM_PROBES 64
/* Prisms a view ray may cross in the walk before it gives up (a miss): a ray caught in a loop
 * of fins at a shared vertex ends instead of spinning. A ray grazing a fine plane crosses a
 * few hundred. */
#define GDM_WALK_MAX_PRISMS 4096

/* The work of a frame (meso_render_stats: prisms, lookups, samples), counted per thread while
 * shading (gdm_thread_counts) and added to the state's totals at the end of each block: the
 * prisms the view rays were tested in (segment_hit), the table lookups of the view rays and of
 * the slab's light test (lookup), the mesostructure's samples along them and along the shell
 * walk's light rays (ray_probe_inside's, not those a remembered bound answers). */
enum { GDM_COUNT_PRISMS, GDM_COUNT_LOOKUPS, GDM_COUNT_SAMPLES, GDM_NUM_COUNTS };
static _Thread_local uint64_t gdm_thread_counts[GDM_NUM_COUNTS];

typedef struct gdm_state {
    meso_gdm *gdm;
    /* the faces in this frame's drawing order (gdm_geometry): drawn shares the layer's
     * vertex arrays and has its own indices; drawn triangle i is layer face drawn_face[i] */
    meso_mesh drawn;
    uint32_t *drawn_indices, *drawn_face, *sort_counts;
    float *sort_keys;
    /* the walk (option walk): the layer's fin twins (gdm_walk.h) and the faces drawn, the
     * shell's outer boundary (walk_boundary): tops, then the fins drawn, then bottoms
     * (group_start[g] to group_start[g + 1]); NULL without the walk, every face drawn */
    uint32_t *fin_twin, *boundary;
    size_t group_start[4];
    /* the walk: per fin face of the layer, 1 where its twin's vertices carry the same (u, v, w)
     * (not a UV seam): the twin's linear (u, v, w) is then the face's own, and the exit's
     * (u, v, w) is the neighbour's entry */
    uint8_t *twin_same_uvw;
    gdm_lookup_table table; /* the compressed map laid out 8-wide (unless raw) */
    meso_prism_layer *layer;
    const meso_heightfield *heightfield; /* one of these two */
    const meso_solid *solid;
    float depth;       /* world units */
    float probe_scale; /* a height field's (1 - h) - w times this bounds the distance */
    /* a height field's slope bounds: |dh/du| <= slope_u, |dh/dv| <= slope_v (texture units) */
    float slope_u, slope_v;
    /* a repeating height field whose sides are powers of two: side - 1 (heightfield_sample's
     * wrap by a mask); 0 otherwise */
    int wrap_mask_u, wrap_mask_v;
    /* height fields: w below which nothing is solid, in each prism's column (prism_clear)
     * and anywhere (clear_w); for solids clear_w only (solid_clear_top), prism_clear NULL */
    float *prism_clear, clear_w, map_max;
    /* height fields: level L at texel (i, j) the highest texel of the window
     * [i, i + 2^L) x [j, j + 2^L), wrapped or clamped as the map samples (window_bound) */
    uint16_t *window_max; /* from level GDM_WINDOW_FIRST on, rounded up by window_unit */
    float window_unit;
    int window_levels;
    /* solids: meso_solid_distance at the nodes (i, j, l) / (GDM_GRID_SIDE, GDM_GRID_SIDE,
     * GDM_GRID_LAYERS - 1), [l][j][i]; NULL for height fields */
    float *grid;
    int num_eigen;
    bool raw, shadows, baked_normals; /* baked_normals: the "normals" option resolved */
    bool skip_clear_tops;             /* the clear_top_walk option off */
    int refine_steps, shadow_steps;
    bool refine_secant;  /* refine_hit ends with a secant step */
    float shadow_bias;   /* voxels off the surface */
    meso_vec3 voxel;     /* a voxel's sides in texture units */
    float refine_window; /* texture units: 3 layers */
    float hit_margin;    /* d < dt - hit_margin is a hit */
    gdm_gi *gi;          /* global illumination (gdm_gi.h); NULL: off */
    gdm_shell *shell;    /* shadows through the shell (gdm_shell_shadow.h); NULL: off */
    /* this frame's counts (GDM_COUNT_*), reset by gdm_geometry; the one thing shading writes */
    _Atomic uint64_t counted[GDM_NUM_COUNTS];
} gdm_state;

typedef struct gdm_options {
    bool compressed, shadows;
    int normals, eigenmaps, resolution, layers, num_theta, num_phi, refine_steps, shadow_steps;
    float shadow_bias, hit_margin;
    bool gi, macro_shadows, gi_inside_sky, clear_top_walk, refine_secant, walk;
    int gi_resolution, gi_layers, gi_eigen;
} gdm_options;

static const meso_technique_option gdm_option_table[] = {
    MESO_OPTION_ROW(MESO_OPTION_BOOL, compressed, 0, 1, 1,
                    "0: render from the raw 5D table (bakes and caches it)", gdm_options,
                    compressed),
    MESO_OPTION_ROW(MESO_OPTION_INT, eigenmaps, 1, MESO_GDM_MAX_EIGEN, 7,
                    "eigen-maps used (§4.1; bakes at least 7)", gdm_options, eigenmaps),
    MESO_OPTION_ROW(MESO_OPTION_INT, resolution, 4, MESO_GDM_MAX_SIDE, 64,
                    "bake: voxels a side in u and v", gdm_options, resolution),
    MESO_OPTION_ROW(MESO_OPTION_INT, layers, 2, MESO_GDM_MAX_LAYERS, 32,
                    "bake: voxels in depth (w)", gdm_options, layers),
    MESO_OPTION_ROW(MESO_OPTION_INT, num_theta, 2, MESO_GDM_MAX_THETA, 16,
                    "bake: polar directions over the whole sphere", gdm_options, num_theta),
    MESO_OPTION_ROW(MESO_OPTION_INT, num_phi, 1, MESO_GDM_MAX_PHI, 32, "bake: azimuthal directions",
                    gdm_options, num_phi),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, shadows, 0, 1, 1,
                    "self-shadows by a lookup along the light (§3.2)", gdm_options, shadows),
    MESO_OPTION_ROW(MESO_OPTION_FLOAT, shadow_bias, -1.0, 16.0, -1.0,
                    "the shadow test starts this many voxels off the surface (up for height "
                    "fields, along the normal for solids) and needs d_L this much short of "
                    "the slab's boundary; -1: 0.25, or 1.5 with refine_steps 0",
                    gdm_options, shadow_bias),
    MESO_OPTION_ROW(MESO_OPTION_INT, shadow_steps, 1, 256, 24,
                    "with refine_steps: probes of the mesostructure along the light ray",
                    gdm_options, shadow_steps),
    MESO_OPTION_ROW(MESO_OPTION_FLOAT, hit_margin, 0.0, 1.0, 0.0,
                    "a hit needs d < |T_out - T_in| - hit_margin (texture units; 0: the paper)",
                    gdm_options, hit_margin),
    MESO_OPTION_ROW(MESO_OPTION_INT, normals, 0, 2, 2,
                    "shading normal: 2 the mesostructure's own gradient (a height field's, as "
                    "every technique; a solid's: six distance samples); 1 the bake's normals; "
                    "0 the height field's gradient or a solid's baked normals",
                    gdm_options, normals),
    MESO_OPTION_ROW(MESO_OPTION_INT, refine_steps, 0, 32, 6,
                    "beyond the paper: check the hit (and a shadow) on the mesostructure and "
                    "bisect this many times; 0: the paper's d < |T_out - T_in| and d_L",
                    gdm_options, refine_steps),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, refine_secant, 0, 1, 1,
                    "with refine_steps >= 2: the last two bisections replaced by "
                    "one secant step through the bracket's two samples; 0: bisections only",
                    gdm_options, refine_secant),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, macro_shadows, 0, 1, 1,
                    "beyond the paper: a light that leaves the slab is followed through the "
                    "rest of the shell, GDM-tested in every prism it enters (a solid's light "
                    "toward the bottom too); 0: the slab only, a light toward its bottom blocked",
                    gdm_options, macro_shadows),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, clear_top_walk, 0, 1, 0,
                    "with macro_shadows: a light the slab finds clear is followed through the "
                    "rest of the shell from every prism; 0: not from a prism whose top has every "
                    "vertex of the shell behind it (a convex base mesh's), where it leaves the "
                    "shell through the tops",
                    gdm_options, clear_top_walk),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, walk, 0, 1, 1,
                    "1: the shell walk -- only the shell's outer boundary is drawn and each "
                    "pixel's ray walks front to back through the prisms it crosses, across "
                    "shared fins, to its first hit (watertight); 0: every prism's faces drawn "
                    "(§3.2)",
                    gdm_options, walk),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, gi, 0, 1, 1,
                    "where the scene has an environment: its light through the radiance "
                    "transfer volume (shadowed, interreflected; docs/techniques/gdm-gi.md); "
                    "0: the shading model's unshadowed SH ambient",
                    gdm_options, gi),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, gi_inside_sky, 0, 1, 0,
                    "gi, with macro_shadows: a hit seen from inside the base mesh takes the sky "
                    "through the shell (64 directions, multi-bounce fit) instead of the "
                    "unshadowed SH ambient; slow (docs/techniques/gdm-gi.md)",
                    gdm_options, gi_inside_sky),
    MESO_OPTION_ROW(MESO_OPTION_INT, gi_resolution, 4, 256, 32, "gi: RTV voxels a side in u and v",
                    gdm_options, gi_resolution),
    MESO_OPTION_ROW(MESO_OPTION_INT, gi_layers, 2, 64, 8, "gi: RTV voxels in depth (w)",
                    gdm_options, gi_layers),
    MESO_OPTION_ROW(MESO_OPTION_INT, gi_eigen, 1, 32, 3,
                    "gi: RTV eigenfunctions used per coefficient (§4.1; at most the 32 views; "
                    "the bake keeps at least 4)",
                    gdm_options, gi_eigen),
};

static void gdm_release(void *state) {
    gdm_state *s = state;
    if (!s) return;
    meso_gdm_destroy(s->gdm);
    gdm_gi_destroy(s->gi);
    gdm_shell_destroy(s->shell);
    gdm_lookup_table_deinit(&s->table);
    meso_prism_layer_destroy(s->layer);
    free(s->drawn_indices);
    free(s->drawn_face);
    free(s->fin_twin);
    free(s->boundary);
    free(s->twin_same_uvw);
    free(s->sort_counts);
    free(s->sort_keys);
    free(s->prism_clear);
    free(s->window_max);
    free(s->grid);
    free(s);
}

/* 1 / the Lipschitz constant of (1 - h(u, v)) - w in (u, v, w): h is bilinear between texel
 * centres, so its slope along u is at most the largest step between neighbouring texels
 * (wrapped pairs included: at worst an overestimate) times the width, likewise along v. The
 * two slope bounds go to *out_slope_u, *out_slope_v (ray_probe_start's bound along a ray). */
static float heightfield_probe_scale(const meso_heightfield *hf, float *out_slope_u,
                                     float *out_slope_v) {
    float step_u = 0.0f, step_v = 0.0f;
    for (int j = 0; j < hf->height; j++)
        for (int i = 0; i < hf->width; i++) {
            float h = meso_heightfield_texel(hf, i, j);
            step_u = fmaxf(step_u, fabsf(meso_heightfield_texel(hf, i + 1, j) - h));
            step_v = fmaxf(step_v, fabsf(meso_heightfield_texel(hf, i, j + 1) - h));
        }
    float gu = step_u * (float)hf->width, gv = step_v * (float)hf->height;
    *out_slope_u = gu, *out_slope_v = gv;
    float lipschitz = sqrtf(1.0f + gu * gu + gv * gv);
    return isfinite(lipschitz) ? 1.0f / lipschitz : 0.0f;
}

/* The highest texel a bilinear sample in [u0, u1] x [v0, v1] can read, with a texel's margin
 * for rounding; the whole map's when the box covers it. */
static float heightfield_box_max(const meso_heightfield *hf, float u0, float u1, float v0, float v1,
                                 float map_max) {
    float i0 = floorf(u0 * (float)hf->width - 0.5f) - 1.0f;
    float i1 = floorf(u1 * (float)hf->width - 0.5f) + 2.0f;
    float j0 = floorf((1.0f - v1) * (float)hf->height - 0.5f) - 1.0f;
    float j1 = floorf((1.0f - v0) * (float)hf->height - 0.5f) + 2.0f;
    if (!(i1 - i0 < (float)hf->width && j1 - j0 < (float)hf->height)) return map_max;
    float h = 0.0f;
    for (int j = (int)j0; j <= (int)j1; j++) {
        /* meso_heightfield_texel's wrapping, once a row and at the box's first column */
        int jj = j, ii = (int)i0;
        if (hf->wrap == MESO_WRAP_CLAMP) {
            jj = jj < 0 ? 0 : (jj >= hf->height ? hf->height - 1 : jj);
        } else {
            jj = (jj % hf->height + hf->height) % hf->height;
            ii = (ii % hf->width + hf->width) % hf->width;
        }
        const float *row = hf->heights + (size_t)jj * (size_t)hf->width;
        for (int i = (int)i0; i <= (int)i1; i++) {
            if (hf->wrap == MESO_WRAP_CLAMP) {
                h = fmaxf(h, row[i < 0 ? 0 : (i >= hf->width ? hf->width - 1 : i)]);
            } else {
                h = fmaxf(h, row[ii]);
                ii = ii + 1 == hf->width ? 0 : ii + 1;
            }
        }
    }
    return h;
}

/* For each prism, the w above which its column of a height field holds no solid: a probe
 * higher up is outside without sampling h (the ray's probes in refine_hit stay in the
 * prism's column; a shadow ray leaves it and uses the whole map's). false: out of memory. */
static bool heightfield_clearances(gdm_state *s) {
    const meso_heightfield *hf = s->heightfield;
    float map_max = 0.0f;
    for (size_t t = 0; t < (size_t)hf->width * (size_t)hf->height; t++)
        map_max = fmaxf(map_max, hf->heights[t]);
    /* 1e-6: a bilinear blend may round a hair above its texels */
    s->map_max = map_max;
    s->clear_w = 1.0f - map_max - 1e-6f;
    size_t n = s->layer->num_prisms;
    s->prism_clear = malloc((n ? n : 1) * sizeof(float));
    if (!s->prism_clear) return false;
    for (size_t i = 0; i < n; i++) {
        const meso_vec2 *uv = s->layer->prisms[i].uv;
        float u0 = fminf(fminf(uv[0].x, uv[1].x), uv[2].x);
        float u1 = fmaxf(fmaxf(uv[0].x, uv[1].x), uv[2].x);
        float v0 = fminf(fminf(uv[0].y, uv[1].y), uv[2].y);
        float v1 = fmaxf(fmaxf(uv[0].y, uv[1].y), uv[2].y);
        bool finite = isfinite(u0) && isfinite(u1) && isfinite(v0) && isfinite(v1);
        float h = finite ? heightfield_box_max(hf, u0, u1, v0, v1, map_max) : map_max;
        s->prism_clear[i] = 1.0f - h - 1e-6f;
    }
    return true;
}

/* A texel index of the map's wrapping, for the windows below. */
static inline int window_index(meso_wrap wrap, int i, int n) {
    if ((unsigned)i < (unsigned)n) return i; /* most: no division */
    if (wrap == MESO_WRAP_CLAMP) return i < 0 ? 0 : (i >= n ? n - 1 : i);
    i %= n;
    return i < 0 ? i + n : i;
}

/* The windows' maxima (window_max), level by level: a window of 2^(L+1) is four of 2^L. A
 * box of texels n wide then needs one read at the level with 2^L >= n, where the prism's
 * clearance (its whole UV triangle) is too coarse: bumps-sphere's prisms near the poles span
 * a wide UV box. Kept from level GDM_WINDOW_FIRST on (window_bound reads no lower one) as
 * 16-bit multiples of window_unit rounded up: a bound only proves a segment outside, which the
 * probes would find anyway (the same images), and a looser one by 1/65535 of the map's
 * highest texel proves about as many. As floats, all levels, the maxima took 7 MB for a 512²
 * map, read at random: a visible share of bark-cylinder's cycles went to that read (perf).
 * false: out of memory. */
static bool heightfield_windows(gdm_state *s) {
    const meso_heightfield *hf = s->heightfield;
    int width = hf->width, height = hf->height, longest = width > height ? width : height;
    int levels = 1;
    while (levels < GDM_WINDOW_LEVELS && (1 << (levels - 1)) < longest) levels++;
    size_t plane = (size_t)width * (size_t)height;
    int kept = levels > GDM_WINDOW_FIRST ? levels - GDM_WINDOW_FIRST : 0;
    float *maxima = malloc(2 * plane * sizeof(float)); /* a level and the one below */
    s->window_max = malloc((kept ? (size_t)kept * plane : 1) * sizeof(uint16_t));
    if (!maxima || !s->window_max) {
        free(maxima);
        return false;
    }
    s->window_levels = levels;
    s->window_unit = (s->map_max > 0.0f ? s->map_max : 1.0f) / 65535.0f;
    memcpy(maxima, hf->heights, plane * sizeof(float));
    for (int level = 1; level < levels; level++) {
        const float *below = maxima + (size_t)((level - 1) & 1) * plane;
        float *out = maxima + (size_t)(level & 1) * plane;
        int step = 1 << (level - 1);
        for (int j = 0; j < height; j++) {
            const float *r0 = below + (size_t)j * (size_t)width;
            const float *r1 =
                below + (size_t)window_index(hf->wrap, j + step, height) * (size_t)width;
            for (int i = 0; i < width; i++) {
                int i1 = window_index(hf->wrap, i + step, width);
                out[(size_t)j * (size_t)width + (size_t)i] =
                    fmaxf(fmaxf(r0[i], r0[i1]), fmaxf(r1[i], r1[i1]));
            }
        }
        if (level < GDM_WINDOW_FIRST) continue;
        uint16_t *stored = s->window_max + (size_t)(level - GDM_WINDOW_FIRST) * plane;
        for (size_t t = 0; t < plane; t++) {
            /* the least multiple of the unit, as window_bound computes it, not below h */
            float h = out[t], q = ceilf(h / s->window_unit);
            q = q > 0.0f ? (q < 65535.0f ? q : 65535.0f) : 0.0f;
            while (q < 65535.0f && q * s->window_unit < h) q += 1.0f;
            stored[t] = (uint16_t)q;
        }
    }
    free(maxima);
    return true;
}

/* The highest texel a bilinear sample anywhere in the (u, v) box [u0, u1] x [v0, v1] can read
 * (a texel's margin each side for rounding, as heightfield_box_max); the whole map's when the
 * box is wider than the largest window. One read of window_max. */
static inline float window_bound(const gdm_state *s, float u0, float u1, float v0, float v1) {
    const meso_heightfield *hf = s->heightfield;
    float x0 = floorf(u0 * (float)hf->width - 0.5f) - 1.0f;
    float x1 = floorf(u1 * (float)hf->width - 0.5f) + 2.0f;
    float y0 = floorf((1.0f - v1) * (float)hf->height - 0.5f) - 1.0f;
    float y1 = floorf((1.0f - v0) * (float)hf->height - 0.5f) + 2.0f;
    float extent = gdm_fmaxf(x1 - x0, y1 - y0) + 1.0f; /* texels a side; NaN fails below */
    if (!(extent <= (float)(1 << (s->window_levels - 1))) || !(fabsf(x0) < 1e6f) ||
        !(fabsf(y0) < 1e6f))
        return s->map_max;
    /* the least level with 2^level >= extent (an integer, at least 4): no loop */
    int level = 32 - __builtin_clz((unsigned)extent - 1u);
    int i = window_index(hf->wrap, (int)x0, hf->width);
    int j = window_index(hf->wrap, (int)y0, hf->height);
    size_t plane = (size_t)hf->width * (size_t)hf->height;
    uint16_t q = s->window_max[(size_t)(level - GDM_WINDOW_FIRST) * plane +
                               (size_t)j * (size_t)hf->width + (size_t)i];
    return (float)q * s->window_unit;
}

/* One layer of nodes of the solid's distance grid. */
static void solid_grid_layer(void *user, size_t job, int thread_index) {
    (void)thread_index;
    gdm_state *s = user;
    float w = (float)job / (float)(GDM_GRID_LAYERS - 1);
    float *out = s->grid + job * GDM_GRID_SIDE * GDM_GRID_SIDE;
    for (int j = 0; j < GDM_GRID_SIDE; j++)
        for (int i = 0; i < GDM_GRID_SIDE; i++)
            out[j * GDM_GRID_SIDE + i] = meso_solid_distance(
                s->solid, (meso_vec3){(float)i / GDM_GRID_SIDE, (float)j / GDM_GRID_SIDE, w});
}

/* The w above which a solid is empty in every tile: the top layers of the distance grid
 * whose every node is farther from the solid than any point is from its nearest node. A point
 * p with w < (L + 1/2) / (GDM_GRID_LAYERS - 1), layers 0..L all so, has its nearest node (as
 * solid_probe rounds) in one of them, within half a cell each way: solid_probe's proof then
 * holds at p and answers outside, so probes there are answered without the grid's read, as
 * a height field's above its highest texel (clear_w): the same answers, the same image. Above
 * the slab (w < 0) the solid is empty too (mesostructure_solid.c intersects it with the slab).
 * A weave's threads leave the top of the slab empty, where the shadow probes start. -1 where
 * the top layer is not clear. */
static float solid_clear_top(const float *grid) {
    const float cell = 0.5f / (float)GDM_GRID_SIDE, layer = 0.5f / (float)(GDM_GRID_LAYERS - 1);
    /* solid_probe's bound with its margins, and 1 % for the distance's own rounding */
    float farthest = 1.01f * sqrtf(2.0f * cell * cell + layer * layer);
    int clear = 0; /* layers 0 .. clear - 1 clear */
    for (; clear < GDM_GRID_LAYERS; clear++) {
        const float *nodes = grid + (size_t)clear * GDM_GRID_SIDE * GDM_GRID_SIDE;
        bool all = true;
        for (size_t k = 0; k < (size_t)GDM_GRID_SIDE * GDM_GRID_SIDE && all; k++)
            all = 0.999f * nodes[k] - 1e-6f > farthest; /* false for NaN */
        if (!all) break;
    }
    if (!clear) return -1.0f;
    /* 0.49: the rounding of w * (layers - 1) kept off the half-way point */
    return ((float)(clear - 1) + 0.49f) / (float)(GDM_GRID_LAYERS - 1);
}

/* The solid's distance at a grid of nodes, evaluated once (about a million evaluations, on
 * every thread): a probe near a node whose |f| exceeds the distance between them is on the
 * node's side (ray_probe_inside). false: out of memory. */
static bool solid_grid(meso_context *ctx, gdm_state *s) {
    s->grid = malloc((size_t)GDM_GRID_LAYERS * GDM_GRID_SIDE * GDM_GRID_SIDE * sizeof(float));
    if (!s->grid) return false;
    meso_parallel_for(ctx, GDM_GRID_LAYERS, solid_grid_layer, s);
    s->clear_w = solid_clear_top(s->grid);
    return true;
}

/* The walk's adjacency and the faces it draws (gdm_walk_boundary). false: out of memory. */
static bool walk_boundary(gdm_state *s) {
    return gdm_walk_boundary(s->layer, &s->fin_twin, &s->boundary, &s->twin_same_uvw,
                             s->group_start);
}

static bool state_inside(const void *state, meso_vec3 uvw);
static bool state_segment_outside(const void *state, meso_vec3 a, meso_vec3 b);
static bool state_probes_inside(const void *state, meso_vec3 t0, meso_vec3 dir, float first,
                                float length, int steps);

static meso_result gdm_prepare(meso_context *ctx, const meso_scene *scene,
                               const meso_object *object, void **out_state) {
    *out_state = NULL;
    gdm_options options;
    meso_result r =
        meso_technique_options_read(ctx, scene, object, &meso_technique_gdm.info, &options);
    if (r != MESO_OK) return r;
    const meso_mesostructure *ms = &object->mesostructure;
    meso_gdm_desc desc = {.width = options.resolution,
                          .height = options.resolution,
                          .layers = options.layers,
                          .num_theta = options.num_theta,
                          .num_phi = options.num_phi,
                          /* renders with fewer eigen-maps share one cached bake */
                          .eigenmaps = options.eigenmaps > 7 ? options.eigenmaps : 7,
                          .keep_raw = !options.compressed};
    if (ms->kind == MESO_MESOSTRUCTURE_SOLID && ms->solid) {
        desc.solid = ms->solid;
    } else if (ms->kind == MESO_MESOSTRUCTURE_HEIGHT_FIELD && ms->height_field) {
        desc.heightfield = ms->height_field;
    } else {
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: technique gdm needs a height field or a solid", object->name);
    }
    int rank = options.layers * options.num_theta;
    if (options.eigenmaps > rank)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: technique_options.eigenmaps: %d, at most %d (layers x "
                              "num_theta) for this table",
                              object->name, options.eigenmaps, rank);
    if (desc.eigenmaps > rank) desc.eigenmaps = rank;
    gdm_state *s = calloc(1, sizeof *s);
    if (!s) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: gdm", object->name);
    s->heightfield = desc.heightfield;
    s->solid = desc.solid;
    s->depth = ms->depth;
    s->num_eigen = options.eigenmaps;
    s->raw = !options.compressed;
    s->shadows = options.shadows;
    s->baked_normals = options.normals == 1 || (options.normals == 0 && desc.solid);
    s->refine_steps = options.refine_steps;
    s->skip_clear_tops = !options.clear_top_walk;
    s->refine_secant = options.refine_secant;
    s->shadow_steps = options.shadow_steps;
    /* The table's d next to the surface is blended with the solid voxels' 0: read from the
     * table alone, a shadow ray must start well off it; probed on the mesostructure (the
     * refinement), a quarter voxel keeps it off the surface and misses fewer near blockers
     * (docs/techniques/gdm.md, shadow_bias). */
    s->shadow_bias = options.shadow_bias >= 0.0f ? options.shadow_bias
                                                 : (options.refine_steps > 0 ? 0.25f : 1.5f);
    s->hit_margin = options.hit_margin;
    s->refine_window = 3.0f / (float)(options.layers - 1);
    s->voxel = (meso_vec3){1.0f / (float)options.resolution, 1.0f / (float)options.resolution,
                           1.0f / (float)(options.layers - 1)};
    if (desc.heightfield && desc.heightfield->wrap != MESO_WRAP_CLAMP &&
        !(desc.heightfield->width & (desc.heightfield->width - 1)) &&
        !(desc.heightfield->height & (desc.heightfield->height - 1))) {
        s->wrap_mask_u = desc.heightfield->width - 1;
        s->wrap_mask_v = desc.heightfield->height - 1;
    }
    s->probe_scale = desc.heightfield
                         ? heightfield_probe_scale(desc.heightfield, &s->slope_u, &s->slope_v)
                         : 1.0f;
    if ((r = meso_prism_layer_create(ctx, object->mesh, ms->depth, object->name, &s->layer)) !=
        MESO_OK)
        goto fail;
    if (s->layer->num_folded) /* docs/techniques/gdm.md, "Folded prisms" */
        meso_log_info(ctx,
                      "%s: gdm: the shell (depth %g) is deeper than the surface's curvature on %zu "
                      "of %zu prisms: they fold, and the fins bound them",
                      object->name, (double)ms->depth, s->layer->num_folded, s->layer->num_prisms);
    s->clear_w = -1.0f;
    if (s->heightfield ? !heightfield_clearances(s) || !heightfield_windows(s)
                       : !solid_grid(ctx, s)) {
        r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: gdm", object->name);
        goto fail;
    }
    size_t n = s->layer->num_prisms;
    s->group_start[0] = 0, s->group_start[1] = n, s->group_start[2] = 7 * n;
    s->group_start[3] = 8 * n;
    bool out_of_memory = options.walk && !walk_boundary(s);
    size_t faces = s->group_start[3] ? s->group_start[3] : 1; /* drawn */
    s->drawn_indices = malloc(3 * faces * sizeof(uint32_t));
    s->drawn_face = malloc(faces * sizeof(uint32_t));
    s->sort_counts = malloc((GDM_DEPTH_BUCKETS + 1) * sizeof(uint32_t));
    s->sort_keys = malloc(faces * sizeof(float));
    if (out_of_memory || !s->drawn_indices || !s->drawn_face || !s->sort_counts || !s->sort_keys) {
        r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: gdm", object->name);
        goto fail;
    }
    s->drawn = *s->layer->faces;
    s->drawn.indices = s->drawn_indices;
    s->drawn.num_triangles = s->group_start[3];
    if ((r = meso_gdm_bake_cached(ctx, &desc, &s->gdm)) != MESO_OK) goto fail;
    s->raw = s->raw && meso_gdm_get_view(s->gdm).raw;
    if (!s->raw) {
        meso_gdm_view view = meso_gdm_get_view(s->gdm);
        if (!gdm_lookup_table_init(&s->table, &view, s->num_eigen)) {
            r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: gdm", object->name);
            goto fail;
        }
    }
    if (options.shadows && options.macro_shadows &&
        (r = gdm_shell_create(
             ctx,
             &(gdm_shell_desc){.layer = s->layer,
                               .mesh = object->mesh,
                               .fin_twin = s->fin_twin,
                               .gdm = s->gdm,
                               .table = s->raw ? NULL : &s->table,
                               .heightfield = s->heightfield,
                               .solid = s->solid,
                               .voxel = s->voxel,
                               .shadow_bias = s->shadow_bias,
                               .refine_window = s->refine_window,
                               .refine_steps = s->refine_steps,
                               .shadow_steps = s->shadow_steps,
                               .inside = state_inside,
                               .inside_user = s,
                               .segment_outside = s->heightfield ? state_segment_outside : NULL,
                               .probes_inside = state_probes_inside},
             object->name, &s->shell)) != MESO_OK)
        goto fail;
    if (options.gi && scene->environment &&
        (r = gdm_gi_create(ctx, scene, object,
                           &(gdm_gi_desc){.resolution = options.gi_resolution,
                                          .layers = options.gi_layers,
                                          /* renders with fewer share the bake of 4 */
                                          .eigen = options.gi_eigen > 4 ? options.gi_eigen : 4,
                                          .used_eigen = options.gi_eigen,
                                          .shell = options.gi_inside_sky ? s->shell : NULL},
                           &s->gi)) != MESO_OK)
        goto fail;
    *out_state = s;
    return MESO_OK;
fail:
    gdm_release(s);
    return r;
}

/* The prisms do not depend on the view (made once in prepare), their drawing order does:
 * every face gets its fragments shaded unless a nearer hit is already in the depth buffer, and
 * a ray crosses several fins, so fins drawn back to front are each shaded for nothing (on
 * bumps-sphere 5.5 fin fragments a top one). Each frame the faces are drawn tops first, then
 * fins, then bottoms, each group front to back by a counting sort of their centroids' view
 * depth into GDM_DEPTH_BUCKETS (linear, O(faces), fixed order within a bucket: deterministic). */
static meso_result gdm_geometry(meso_context *ctx, void *state, const meso_frame *frame,
                                const meso_mesh **out_mesh) {
    (void)ctx;
    gdm_state *s = state;
    if (s->gi) gdm_gi_begin_frame(s->gi, frame);
    for (int k = 0; k < GDM_NUM_COUNTS; k++)
        atomic_store_explicit(&s->counted[k], 0, memory_order_relaxed);
    gdm_walk_sort_faces(s->layer->faces, s->boundary, s->group_start, frame->eye, frame->forward,
                        s->sort_keys, s->sort_counts, s->drawn_face, s->drawn_indices);
    *out_mesh = &s->drawn;
    return MESO_OK;
}

/* d_GDM(uvw, direction): the raw table, or the compressed one through the 8-wide path. */
static inline float lookup(const gdm_state *s, meso_vec3 uvw, meso_vec3 direction) {
    gdm_thread_counts[GDM_COUNT_LOOKUPS]++;
    if (s->raw) return meso_gdm_lookup(s->gdm, uvw, direction, 0, true);
    return gdm_lookup8(&s->table, uvw, direction);
}

/* ---- The frame at a texture point ---------------------------------------------------------- */

/* The Jacobian of the prism map at a texture point, with the interpolated tangent frame as the
 * reference's shading takes it (reference.c surface_at: (T, B, -depth N), so that normals are
 * the reference's and the base mesh's facets do not show), and its cofactors. */
typedef struct texture_frame {
    meso_vec3 normal, tangent, bitangent; /* the base surface's, interpolated; normal unit */
    meso_vec3 cu, cv, cw;                 /* cofactor columns: J^-T = (cu cv cw) / det */
    float det;
} texture_frame;

static texture_frame frame_at(const meso_mesh *mesh, const meso_prism *prism, meso_vec2 uv,
                              float depth) {
    texture_frame f;
    gdm_walk_base_frame(mesh, prism, uv, &f.normal, &f.tangent, &f.bitangent);
    meso_vec3 jw = meso_vec3_scale(f.normal, -depth);
    f.cu = meso_vec3_cross(f.bitangent, jw);
    f.cv = meso_vec3_cross(jw, f.tangent);
    f.cw = meso_vec3_cross(f.tangent, f.bitangent);
    f.det = meso_vec3_dot(f.tangent, f.cu);
    return f;
}

/* A texture-space normal (u, v, w) to a world one: J^-T n, unit; the base normal if degenerate. */
static inline meso_vec3 world_normal(const texture_frame *f, meso_vec3 n) {
    meso_vec3 m =
        meso_vec3_add(meso_vec3_add(meso_vec3_scale(f->cu, n.x), meso_vec3_scale(f->cv, n.y)),
                      meso_vec3_scale(f->cw, n.z));
    if (f->det < 0.0f) m = meso_vec3_negate(m);
    float len2 = meso_vec3_dot(m, m);
    return len2 > 0.0f && isfinite(len2) ? meso_vec3_scale(m, 1.0f / sqrtf(len2)) : f->normal;
}

/* A world direction in texture space: J^-1 x, unit (zero if degenerate). */
static inline meso_vec3 texture_direction(const texture_frame *f, meso_vec3 x) {
    meso_vec3 t = {meso_vec3_dot(f->cu, x), meso_vec3_dot(f->cv, x), meso_vec3_dot(f->cw, x)};
    float len2 = meso_vec3_dot(t, t);
    if (!(len2 > 0.0f) || !isfinite(len2)) return (meso_vec3){0.0f, 0.0f, 0.0f};
    t = meso_vec3_scale(t, (f->det < 0.0f ? -1.0f : 1.0f) / sqrtf(len2));
    return t;
}

/* ---- The mesostructure itself (normals; the refinement beyond the paper) ------------------- */

/* meso_heightfield_sample(s->heightfield, u, v), bit for bit (the same float operations in the
 * same order), with a repeating map's texel indices wrapped by a mask where its sides are
 * powers of two: gdm's (u, v) run over several tiles (uv_scale 6 x 3 on bumps-sphere), so most
 * samples took the header's wrap, two integer divisions. i & (n - 1) is the header's wrapped
 * index for every int i when n is a power of two (two's complement). */
__attribute__((noinline)) static float heightfield_sample_any(const meso_heightfield *hf, float u,
                                                              float v) {
    return meso_heightfield_sample(hf, u, v);
}

static inline float heightfield_sample(const gdm_state *s, float u, float v) {
    const meso_heightfield *hf = s->heightfield;
    if (!s->wrap_mask_u) return heightfield_sample_any(hf, u, v);
    float x = u * (float)hf->width - 0.5f;
    float y = (1.0f - v) * (float)hf->height - 0.5f;
    float fx = floorf(x), fy = floorf(y);
    float tx = x - fx, ty = y - fy;
    int i = (int)fx, j = (int)fy;
    int i0 = i & s->wrap_mask_u, i1 = (int)((unsigned)i + 1u) & s->wrap_mask_u;
    int j0 = j & s->wrap_mask_v, j1 = (int)((unsigned)j + 1u) & s->wrap_mask_v;
    const float *row0 = hf->heights + (size_t)j0 * (size_t)hf->width;
    const float *row1 = hf->heights + (size_t)j1 * (size_t)hf->width;
    float h00 = row0[i0], h10 = row0[i1], h01 = row1[i0], h11 = row1[i1];
    float top = h00 + (h10 - h00) * tx, bottom = h01 + (h11 - h01) * tx;
    return top + (bottom - top) * ty;
}

/* gdm_mesostructure_inside (gdm_shell_shadow.h) through heightfield_sample: the same answer. */
static inline bool inside_mesostructure(const gdm_state *s, meso_vec3 uvw) {
    if (s->heightfield) return uvw.z >= 1.0f - heightfield_sample(s, uvw.x, uvw.y);
    return gdm_mesostructure_inside(s->heightfield, s->solid, uvw);
}

/* Samples of the mesostructure along one texture-space ray t0 + x dir (dir unit), remembering
 * what the last outside and the last inside sample prove about their neighbours: a solid's
 * distance is a bound with Lipschitz constant 1 in (u, v, w) (mesostructure_solid.c), and so
 * is a height field's (1 - h) - w scaled by probe_scale; every point nearer than |f| to a
 * sample is on the same side of the surface. A probe there gets the same answer without
 * evaluating the mesostructure (the weave's distance function was most of weave-torus's
 * frame): the answers, and so the images, are those of evaluating every probe.
 *
 * Along one ray a height field's f changes faster than |dir.z| + |dir.x| slope_u + |dir.y|
 * slope_v per unit of x nowhere (h is bilinear: its slope along u is at most slope_u, along v
 * slope_v), at most probe_scale's sqrt(1 + slope_u^2 + slope_v^2) and much less where the ray
 * is steep in (u, v, w) -- where the shell is thin against a tile, most rays: bumps-sphere's
 * light rays and view rays are. So a sample's |f| proves `scale` |f| of the ray; the rounding
 * margin is the one the isotropic bound had, in f's units (margin = 1e-6 scale / probe_scale),
 * so a probe proven here differs from its evaluation only where one proven by the isotropic
 * bound could. */
typedef struct ray_probe {
    /* the path t0 + x dir + x (length - x) bow: a line where bow is zero (light rays), the view
     * ray's curve through its prism otherwise (view_path) */
    meso_vec3 t0, dir, bow;
    float length;
    float stretch; /* 1 / the bound of |dp/dx| on [0, length]: distances along x to (u, v, w) */
    float x[2], radius[2]; /* [0] the last outside sample, [1] the last inside: where, |f| */
    bool sampled[2];       /* solids: its radius is |f| there, not the distance grid's bound */
    float clear_w;         /* outside above this w (prism_clear, clear_w) */
    float scale, margin;   /* height fields: a sample proves scale |f| of x, less margin */
} ray_probe;

/* A solid's distance at p, or a value of its sign: the nearest node of the solid's distance
 * grid proves the side when p lies within the node's |f| (less the distance to it, with
 * ray_probe_inside's margins), and *out_radius is then that bound, remembered as a sample's
 * |f| would be; otherwise the solid is evaluated (*out_radius = |f|). Not inline: it keeps
 * ray_probe_inside small enough to be inlined for height fields (with the grid's code inline,
 * bumps-sphere ran more instructions). */
__attribute__((noinline)) static float solid_probe(const gdm_state *s, meso_vec3 p,
                                                   float *out_radius, bool *out_sampled) {
    meso_vec3 q = gdm_tile_point(p);
    float gx = q.x * (float)GDM_GRID_SIDE, gy = q.y * (float)GDM_GRID_SIDE;
    float gz = q.z * (float)(GDM_GRID_LAYERS - 1);
    float nx = floorf(gx + 0.5f), ny = floorf(gy + 0.5f);
    float nz = floorf(gz + 0.5f); /* clamped by comparisons: fminf/fmaxf are calls here */
    nz = nz > 0.0f ? (nz < (float)(GDM_GRID_LAYERS - 1) ? nz : (float)(GDM_GRID_LAYERS - 1)) : 0.0f;
    if (isfinite(nx + ny + nz)) {
        float dx = (gx - nx) / (float)GDM_GRID_SIDE, dy = (gy - ny) / (float)GDM_GRID_SIDE;
        float dz = (gz - nz) / (float)(GDM_GRID_LAYERS - 1);
        int i = (int)nx & (GDM_GRID_SIDE - 1), j = (int)ny & (GDM_GRID_SIDE - 1);
        float f = s->grid[((size_t)nz * GDM_GRID_SIDE + (size_t)j) * GDM_GRID_SIDE + (size_t)i];
        float bound = 0.999f * fabsf(f) - 1e-6f - sqrtf(dx * dx + dy * dy + dz * dz);
        if (bound > 0.0f) {
            *out_radius = bound;
            *out_sampled = false;
            return f;
        }
    }
    float f = meso_solid_distance(s->solid, q);
    *out_radius = fabsf(f);
    *out_sampled = true;
    return f;
}

/* gdm_mesostructure_inside's answer (gdm_shell_desc.inside: the shell walk's probes), by the
 * grid's proof for a solid where it has one and above the whole map's highest texel for a
 * height field, else by the evaluation: the same answer for every point. */
static bool state_inside(const void *state, meso_vec3 uvw) {
    const gdm_state *s = state;
    if (uvw.z < s->clear_w) return false;
    if (s->heightfield) return inside_mesostructure(s, uvw);
    float radius;
    bool sampled;
    return solid_probe(s, uvw, &radius, &sampled) <= 0.0f;
}

/* gdm_shell_desc.segment_outside: a height field's window proof (shade_one's, on the segment
 * a -> b): above the highest texel its (u, v) box can read, every point of it is outside. */
static bool state_segment_outside(const void *state, meso_vec3 a, meso_vec3 b) {
    const gdm_state *s = state;
    if (!s->window_max) return false;
    float highest = window_bound(s, gdm_fminf(a.x, b.x), gdm_fmaxf(a.x, b.x), gdm_fminf(a.y, b.y),
                                 gdm_fmaxf(a.y, b.y));
    return gdm_fmaxf(a.z, b.z) + 1e-6f < 1.0f - highest - 1e-6f;
}

static inline ray_probe ray_probe_start(const gdm_state *s, meso_vec3 t0, meso_vec3 dir,
                                        float clear_w) {
    ray_probe r = {
        .t0 = t0, .dir = dir, .stretch = 1.0f, .radius = {-1.0f, -1.0f}, .clear_w = clear_w};
    r.margin = 1e-6f; /* solids: solid_probe's radius is the bound itself */
    if (s->heightfield && s->probe_scale > 0.0f) {
        float rate = fabsf(dir.z) + fabsf(dir.x) * s->slope_u + fabsf(dir.y) * s->slope_v;
        r.scale = 1.0f / rate;
        r.margin = 1e-6f * r.scale / s->probe_scale;
        if (!(r.scale >= s->probe_scale) || !isfinite(r.margin)) /* rounding, 0 or NaN: */
            r.scale = s->probe_scale, r.margin = 1e-6f;          /* the isotropic bound */
    }
    return r;
}

/* The probe's path bent into the view ray's curve through its prism, given the curve's
 * midpoint `sag` off the segment's: p(x) = t0 + x dir + x (length - x) bow with bow = 4 sag /
 * length^2, |p'| <= stretch = 1 + 4 |sag| / length on [0, length]. A height field's bound
 * along the path takes each component's largest rate there, |dir_c| + |bow_c| length (p'(x) =
 * dir + (length - 2 x) bow), in place of stretch; a solid's (isotropic) bound is scaled by
 * stretch. A sag that is zero or not finite leaves the path straight. */
static inline void ray_probe_bend(const gdm_state *s, ray_probe *r, meso_vec3 sag, float length) {
    float sag_length = meso_vec3_length(sag);
    if (!(isfinite(sag_length) && sag_length > 0.0f)) return;
    meso_vec3 bow = meso_vec3_scale(sag, 4.0f / (length * length));
    float stretch = 1.0f + 4.0f * sag_length / length;
    r->bow = bow;
    r->length = length;
    r->stretch = stretch;
    if (!s->heightfield || !(s->probe_scale > 0.0f)) return;
    float rate = (fabsf(r->dir.z) + fabsf(bow.z) * length) +
                 (fabsf(r->dir.x) + fabsf(bow.x) * length) * s->slope_u +
                 (fabsf(r->dir.y) + fabsf(bow.y) * length) * s->slope_v;
    r->scale = 1.0f / rate;
    r->margin = 1e-6f * r->scale / s->probe_scale;
    r->stretch = 1.0f; /* in the scale */
    if (!(r->scale * stretch >= s->probe_scale) || !isfinite(r->margin)) {
        /* the isotropic bound along the path */
        r->scale = s->probe_scale, r->margin = 1e-6f, r->stretch = stretch;
    }
}

/* The point at x along the probe's path. */
static inline meso_vec3 ray_probe_point(const ray_probe *r, float x) {
    return meso_vec3_madd(meso_vec3_madd(r->t0, r->dir, x), r->bow, x * (r->length - x));
}

static inline bool ray_probe_inside(const gdm_state *s, ray_probe *r, float x) {
    for (int side = 0; side < 2; side++) /* 0.999, 1e-6: positions are rounded, bounds tight */
        if (fabsf(x - r->x[side]) * r->stretch < 0.999f * r->radius[side] - r->margin)
            return side == 1;
    meso_vec3 p = ray_probe_point(r, x);
    if (p.z < r->clear_w) return false;
    gdm_thread_counts[GDM_COUNT_SAMPLES]++;
    float f, radius;
    bool sampled = true;  /* a height field's radius is its |f| */
    if (s->heightfield) { /* inside_mesostructure's test: w >= 1 - h is (1 - h) - w <= 0 */
        f = (1.0f - heightfield_sample(s, p.x, p.y)) - p.z;
        radius = fabsf(f) * r->scale;
    } else {
        f = solid_probe(s, p, &radius, &sampled);
    }
    int side = f <= 0.0f;
    r->x[side] = x;
    r->radius[side] = radius;
    if (!s->heightfield) r->sampled[side] = sampled;
    return side == 1;
}

/* gdm_shell_desc.probes_inside: the walk's probes of a prism's segment (segment_blocked) as a
 * ray_probe, so that a sample's |f| answers the probes near it; each answer is state_inside's
 * (above clear_w: outside; else the sample or a solid's grid), so the walk's
 * answers are the same. */
static bool state_probes_inside(const void *state, meso_vec3 t0, meso_vec3 dir, float first,
                                float length, int steps) {
    const gdm_state *s = state;
    ray_probe probe = ray_probe_start(s, t0, dir, s->clear_w);
    if (first >= 0.0f && ray_probe_inside(s, &probe, first)) return true;
    for (int k = 0; k < steps; k++)
        if (ray_probe_inside(s, &probe, length * ((float)k + 0.5f) / (float)steps)) return true;
    return false;
}

/* How many of the probes x = length k / probes, k = 1, 2, ... (not the last, at the exit)
 * from the start of a path going down lie below its clear_w: each of them answers outside,
 * without a sample and without changing what the probe remembers (a remembered inside sample
 * proves nothing above clear_w: the two bounds agree), so refine_hit's even probes start
 * after them. On [0, length] the path's w is at most t0.z + x dir.z + max(bow.z, 0)
 * length^2 / 4 (the bow's factor x (length - x) is at most length^2 / 4); 1e-6 covers the
 * rounding of the probe's own point. On bark-cylinder, many of the even probes. */
static inline int ray_probe_below(const ray_probe *r, float length, int probes) {
    if (!(r->dir.z > 0.0f)) return 0;
    float room = r->clear_w - 1e-6f -
                 (r->t0.z + gdm_fmaxf(r->bow.z, 0.0f) * (0.25f * r->length * r->length));
    if (!(room > 0.0f)) return 0;
    /* the estimate, then the test each probe's own x passes */
    float estimate = room / r->dir.z / length * (float)probes;
    int k = estimate < (float)(probes - 1) ? (int)estimate : probes - 1;
    while (k > 0 && !(length * (float)k / (float)probes * r->dir.z < room)) k--;
    return k;
}

/* |f| of a solid at p where p is on the side `inside` says (refine_hit's secant step), else
 * -1: the distance itself, not a bound. */
static float solid_sample(const gdm_state *s, meso_vec3 p, bool inside) {
    gdm_thread_counts[GDM_COUNT_SAMPLES]++;
    float f = meso_solid_distance(s->solid, gdm_tile_point(p));
    return (f <= 0.0f) == inside ? fabsf(f) : -1.0f;
}

/* Beyond the paper (docs/techniques/gdm.md): d interpolated across an occluding edge lands
 * between the two surfaces (VDM's lesson, docs/design.md), and the compressed table errs by
 * a tenth of the shell on a weave. The table's answer is checked on the mesostructure: when
 * the ray is outside a window before it and inside just past it, the crossing lies there (the
 * table says nothing is nearer) and `steps` bisections close in on it -- two samples and the
 * bisection where the table is right. Otherwise (the table was wrong here) a few probes
 * from the entry find the first inside point. The segment's end on a solid floor counts as
 * inside whatever its rounding. Returns the hit's distance along V_t, negative for none. */
static float refine_hit(const gdm_state *s, ray_probe probe, float d, float dt, bool solid_floor) {
#define INSIDE(x) ((solid_floor && (x) >= dt) || ray_probe_inside(s, &probe, (x)))
    float window = s->refine_window;
    float guess = gdm_fminf(gdm_fmaxf(d, 0.0f), dt);
    float before = gdm_fmaxf(guess - window, 0.0f), after = gdm_fminf(guess + 0.5f * window, dt);
    float lo = 0.0f, hi = -1.0f;
    if (!INSIDE(before) && INSIDE(after)) {
        lo = before;
        hi = after;
    } else {
        if (INSIDE(0.0f)) return 0.0f;
        /* probes from the entry, evenly spaced, one every eighth of the refinement's window
         * (3 layers), 8 to GDM_PROBES: eight along a long segment skipped chainmail rings,
         * threads, bars and mortar grooves (docs/techniques/gdm.md); the probe cache skips the
         * evaluations the distance bounds already decide */
        float wanted = ceilf(8.0f * dt / window);
        int probes = wanted > 8.0f ? (wanted < (float)GDM_PROBES ? (int)wanted : GDM_PROBES) : 8;
        int first = ray_probe_below(&probe, dt, probes) + 1;
        if (first > 1) lo = dt * (float)(first - 1) / (float)probes; /* as the loop leaves it */
        for (int k = first; k <= probes && hi < 0.0f; k++) {
            /* the last probe exactly at the exit: dt k / k rounds below dt for most k, and a
             * solid floor there would be missed (a hole) */
            float x = k == probes ? dt : dt * (float)k / (float)probes;
            if (INSIDE(x))
                hi = x;
            else
                lo = x;
        }
        if (hi < 0.0f) return -1.0f;
    }
    /* the last two bisections replaced by one secant step (refine_secant) */
    bool secant = s->refine_secant && s->refine_steps >= 2;
    int bisections = secant ? s->refine_steps - 2 : s->refine_steps;
    for (int pass = 0; pass < 2; pass++) {
        for (int k = 0; k < bisections; k++) {
            float mid = 0.5f * (lo + hi);
            if (INSIDE(mid))
                hi = mid;
            else
                lo = mid;
        }
        if (!secant) break;
        /* Both ends sampled (not proven by a bound, neither a remembered sample's nor a
         * solid grid's): their |f| -- a height field's (1 - h) - w times a scale that is the
         * same along the path, a solid's distance -- and f is nearly linear over a bracket a
         * sixteenth of the window wide (a solid's surface is smooth on that scale away from
         * its edges: a thread's radius is a few voxels): the crossing where the line through
         * them is zero, two dependent samples fewer than bisecting on
         * (docs/techniques/gdm.md). */
        float r_lo =
            probe.x[0] == lo && (s->heightfield || probe.sampled[0]) ? probe.radius[0] : -1.0f;
        float r_hi =
            probe.x[1] == hi && (s->heightfield || probe.sampled[1]) ? probe.radius[1] : -1.0f;
        if (s->solid && !(solid_floor && hi >= dt)) {
            /* a solid's end proven by a bound (the grid's, or a remembered sample's) is
             * sampled now, as the GL shader samples both: one distance, not two bisections */
            if (r_lo < 0.0f) r_lo = solid_sample(s, ray_probe_point(&probe, lo), false);
            if (r_hi < 0.0f) r_hi = solid_sample(s, ray_probe_point(&probe, hi), true);
        }
        float sum = r_lo + r_hi;
        if (r_lo >= 0.0f && r_hi >= 0.0f && sum > 0.0f && isfinite(sum))
            return lo + (hi - lo) * (r_lo / sum);
        bisections = 2, secant = false; /* else the two bisections after all */
    }
#undef INSIDE
    return 0.5f * (lo + hi); /* the bracket's middle: half its width off, either way */
}

/* Solid where a ray leaves the slab's bottom at T (height fields: always); a solid's answer
 * through its distance grid where that proves it (state_inside: the same answer). */
static inline bool floor_is_solid(const gdm_state *s, meso_vec3 t) {
    return s->heightfield || state_inside(s, (meso_vec3){t.x, t.y, 1.0f - 1e-3f});
}

static meso_vec3 texture_normal(const gdm_state *s, meso_vec3 uvw) {
    if (s->baked_normals) return meso_gdm_normal(s->gdm, uvw);
    if (s->heightfield) {
        /* the solid w >= 1 - h: outward gradient of (1 - h) - w */
        /* meso_heightfield_gradient's central differences, through heightfield_sample */
        const meso_heightfield *hf = s->heightfield;
        float du = 1.0f / (float)hf->width, dv = 1.0f / (float)hf->height;
        float hu =
            (heightfield_sample(s, uvw.x + du, uvw.y) - heightfield_sample(s, uvw.x - du, uvw.y)) /
            (2.0f * du);
        float hv =
            (heightfield_sample(s, uvw.x, uvw.y + dv) - heightfield_sample(s, uvw.x, uvw.y - dv)) /
            (2.0f * dv);
        return (meso_vec3){-hu, -hv, -1.0f};
    }
    return meso_solid_gradient(s->solid, gdm_tile_point(uvw));
}

/* ---- Shading ------------------------------------------------------------------------------- */

/* Is the light, seen from T along the unit texture direction lt, blocked before the slab's
 * boundary? §3.2: "if d_GDM(T, L) is not equal to d_max" -- d_max being the distance to the
 * boundary since §4.1 replaced it. */
__attribute__((flatten)) static bool shadowed(const gdm_state *s, meso_vec3 t, meso_vec3 normal_t,
                                              meso_vec3 lt, bool at_seam) {
    /* A light toward the slab's bottom lies under the base surface: the object's own body is
     * between (the far wall of a torus seen through the holes of the near one). §3.2's local
     * test cannot see that; this much of the base geometry's shadow it can. Measured on an
     * open mesh too: inside grid-vase (lit only through its rim) it is nearer the truth than
     * letting such light through. */
    if (lt.z >= 0.0f) return true;
    float bias = s->shadow_bias;
    /* from a point `bias` voxels off the surface: at the surface d is interpolated with the
     * voxels inside the solid (d = 0) and would shadow every point (the floor of a height
     * field most of all). A height field's solid lies below its surface, so straight up
     * leaves it wherever the point is; a solid's along its normal. (A height field's normal
     * at the foot of a steep cone already leans toward it: a sideways step lands inside.) */
    meso_vec3 offset = s->heightfield ? (meso_vec3){0.0f, 0.0f, -1.0f} : normal_t;
    meso_vec3 step = meso_vec3_mul(offset, meso_vec3_scale(s->voxel, bias));
    t = meso_vec3_add(t, step);
    t.z = gdm_fminf(gdm_fmaxf(t.z, 0.0f), 1.0f);
    /* A hit at the entry through a seam fin (the neighbour prism's segment just missed the
     * thread, this one starts inside it) has its surface somewhere near, not at the point: a
     * start `bias` off along the normal can still be inside, and its probes then report the
     * thread itself (single dark specks on fin lines, weave-torus). Such a start is pushed on
     * until outside. Not at an open border's fins: there the thread is cut, its normal says
     * nothing of the cut face, and pushing lets light in (weave-plane drew further from its truth).
     */
    for (int k = 0; k < 8 && at_seam && inside_mesostructure(s, t); k++) {
        t = meso_vec3_add(t, step);
        t.z = gdm_fminf(gdm_fmaxf(t.z, 0.0f), 1.0f);
    }
    float boundary = gdm_fminf(t.z / -lt.z, MESO_GDM_MAX_RAY_LENGTH); /* to the top (lt.z < 0) */
    float margin = bias * s->voxel.z;
    if (boundary <= margin) return false;
    float d = lookup(s, t, lt);
    if (s->refine_steps > 0) {
        /* beyond the paper, with the refined hit: where the table says the light is blocked,
         * the blocker is looked for on the mesostructure -- just past d_L, else by probes
         * along the light ray, as VDM's refinement does where its table is ambiguous (the
         * table's error, 0.1 of the shell for a weave at k = 7, is larger than the gaps a
         * light ray threads through) */
        if (d >= boundary - margin) return false;
        float clear_w = s->clear_w;
        if (s->window_max) {
            /* every probe below lies on t + x lt, x in [0, reach]: above the highest texel
             * that stretch's (u, v) box can read, a probe is outside without a sample (the
             * answer the sample gives, so the same image) */
            float reach = gdm_fmaxf(boundary, d + 0.5f * s->refine_window);
            meso_vec3 end = meso_vec3_madd(t, lt, reach);
            float highest = window_bound(s, gdm_fminf(t.x, end.x), gdm_fmaxf(t.x, end.x),
                                         gdm_fminf(t.y, end.y), gdm_fmaxf(t.y, end.y));
            clear_w = gdm_fmaxf(clear_w, 1.0f - highest - 1e-6f);
        }
        ray_probe probe = ray_probe_start(s, t, lt, clear_w);
        if (ray_probe_inside(s, &probe, d + 0.5f * s->refine_window)) return true;
        for (int k = 0; k < s->shadow_steps; k++) {
            float x = boundary * ((float)k + 0.5f) / (float)s->shadow_steps;
            /* the light rises (lt.z < 0) and x grows: from the first probe above clear_w on,
             * every probe is (each would answer outside: no inside sample is remembered, the
             * first one returns) */
            if (t.z + lt.z * x < clear_w) return false;
            if (ray_probe_inside(s, &probe, x)) return true;
        }
        return false;
    }
    /* §3.2 with §4.1's d_max: lit when d_L reaches the boundary, within the table's error */
    return d < boundary - margin;
}

/* The view ray's stretch through one prism and what §3.2 finds on it (segment_hit). */
typedef struct prism_segment {
    meso_vec3 t_out; /* the exit's (u, v, w) */
    ray_probe path;  /* the ray's path through the prism in (u, v, w) */
    float d;         /* a hit: at ray_probe_point(&path, d) */
} prism_segment;

/* §3.2 in the crossing's prism (its exit made by gdm_walk_exit), entered at texture point t_in
 * along the unit view direction: true where the ray meets the mesostructure before it leaves
 * the prism (out->d, out->path), false where it passes through. */
static bool segment_hit(const gdm_state *s, const meso_mesh *mesh, const gdm_walk_crossing *c,
                        meso_vec3 t_in, meso_vec3 view, prism_segment *out) {
    const meso_prism_layer *layer = s->layer;
    size_t prism_index = c->prism;
    const meso_prism *prism = &layer->prisms[prism_index];
    int exit_slot = c->exit_slot;
    gdm_thread_counts[GDM_COUNT_PRISMS]++;
    meso_vec3 t_out = meso_prism_layer_face_uvw(
        layer, meso_prism_layer_face(layer, prism_index, exit_slot), c->p_out);
    out->t_out = t_out;
    /* height fields: outside above this w on the segment (the refinement's probes) */
    float clear_w = s->prism_clear ? s->prism_clear[prism_index] : s->clear_w;
    if (s->window_max && s->refine_steps > 0) {
        /* Beyond the paper: every probe of refine_hit lies on the ray's path through the prism
         * (below), near the segment; when the segment stays above the highest texel its (u, v)
         * box can read (a texel's margin each side), the probes are outside and it misses,
         * known without the lookup: most fins of a sphere's outline band are crossed above
         * the bumps. The prism's own clearance (its whole column, which the path stays in;
         * one read) settles some before the box's. */
        float top = gdm_fmaxf(t_in.z, t_out.z) + 1e-6f;
        if (top < clear_w) return false;
        float highest = window_bound(s, gdm_fminf(t_in.x, t_out.x), gdm_fmaxf(t_in.x, t_out.x),
                                     gdm_fminf(t_in.y, t_out.y), gdm_fmaxf(t_in.y, t_out.y));
        clear_w = gdm_fmaxf(clear_w, 1.0f - highest - 1e-6f);
        if (top < clear_w) return false;
    }
    meso_vec3 segment = meso_vec3_sub(t_out, t_in);
    float dt = meso_vec3_length(segment);
    if (!(dt > 1e-7f)) return false;
    meso_vec3 vt = meso_vec3_scale(segment, 1.0f / dt);
    ray_probe path = ray_probe_start(s, t_in, vt, clear_w);
    const uint32_t *v = prism->vertices;
    if (s->refine_steps > 0 && !gdm_normals_equal(mesh, v[0], v[1], v[2])) {
        /* Beyond the paper: the view ray's path through the prism is not straight in (u, v, w).
         * The prism's map is bilinear in the barycentrics and w, so where the vertex normals
         * turn a straight ray bows: its midpoint lies up to two voxels (0.13 on average) off
         * the segment's on grid-vase, which moved the thin bars' outlines by a fraction of a
         * pixel. The midpoint is mapped exactly (Newton) and the probes follow the parabola
         * through entry, midpoint and exit; the hit lies on it, and so on the ray. */
        meso_vec3 line_mid = meso_vec3_scale(meso_vec3_add(t_in, t_out), 0.5f);
        meso_vec3 mid =
            meso_prism_unmap(prism, mesh, s->depth, meso_vec3_madd(c->p_in, view, 0.5f * c->t_exit),
                             line_mid, GDM_UNMAP_ITERATIONS, GDM_UNMAP_TOLERANCE);
        ray_probe_bend(s, &path, meso_vec3_sub(mid, line_mid), dt);
    }
    float d = lookup(s, t_in, vt);
    if (s->refine_steps > 0) {
        d = refine_hit(s, path, d, dt, exit_slot == MESO_PRISM_BOTTOM && floor_is_solid(s, t_out));
        if (d < 0.0f) return false;
    } else if (!(d < dt - s->hit_margin)) {
        /* §3.2: the ray passes through the prism -- unless it leaves through the bottom into
         * solid: §4.1 made the miss distance that of the boundary, so there a hit on the floor
         * and a miss differ by the table's error only; the point's own property decides
         * (§4.1: "query the properties of the intersection point") */
        if (exit_slot != MESO_PRISM_BOTTOM || !floor_is_solid(s, t_out)) return false;
        d = d < dt ? d : dt;
    }
    out->path = path;
    out->d = d > 0.0f ? d : 0.0f;
    return true;
}

/* A hit of the view ray in the crossing's prism (segment_hit), shaded: fills the fragment's
 * position, normal, uv, out_depth and the lights' visibility. */
static void shade_hit(const gdm_state *s, const meso_frame *frame, const meso_object *object,
                      meso_fragment *f, const gdm_walk_crossing *c, const prism_segment *seg,
                      float *visibility, gdm_gi_hit *out_hit) {
    const meso_prism_layer *layer = s->layer;
    const meso_mesh *mesh = object->mesh;
    size_t prism_index = c->prism, face = c->entry_face;
    int slot = c->entry_slot;
    const meso_prism *prism = &layer->prisms[prism_index];
    float d = seg->d;
    meso_vec3 p_out = c->p_out;
    meso_vec3 hit = ray_probe_point(&seg->path, d);
    meso_vec3 position = meso_prism_map(prism, mesh, s->depth, hit, -1);
    /* Between the entry's depth (the contract: never nearer) and the exit's: the hit lies on
     * the segment, though mapped from texture space it may land a little past the exit --
     * behind the neighbour prism's entry, whose fragment would then win the depth test with
     * that prism's own (wrong) answer. */
    float depth = meso_vec3_dot(meso_vec3_sub(position, frame->eye), frame->forward);
    float exit_depth = meso_vec3_dot(meso_vec3_sub(p_out, frame->eye), frame->forward);
    depth = depth < exit_depth ? depth : exit_depth;
    f->out_depth = depth > f->depth ? depth : f->depth;
    texture_frame tf = frame_at(mesh, prism, (meso_vec2){hit.x, hit.y}, s->depth);
    meso_vec3 normal, normal_t = texture_normal(s, hit);
    /* for the walk (gdm_shell_shadow.h): the point as mapped here, and a solid's gradient */
    gdm_shell_point point = {position, tf.normal, normal_t, s->solid && !s->baked_normals};
    if (s->heightfield && !s->baked_normals) /* as the reference and the other techniques; */
        normal = meso_displaced_normal(tf.normal, tf.tangent, tf.bitangent, s->depth,
                                       (meso_vec2){-normal_t.x, -normal_t.y}); /* = gradient */
    else
        normal = world_normal(&tf, normal_t);
    /* An entry through an open border's fin with the mesostructure there (d = 0: the border
     * cuts it) lies on the cut face, whose normal is the fin's: the mesostructure's gradient
     * belongs to its own surfaces (a ring cut across at a vase's rim lit as its side). The
     * reference closes the cut with the same fin (reference_solid.c, "caps"). The shell's
     * twin table tells a border's fin from a seam's (macro_shadows). A height field's border
     * keeps the surface's normal: the reference draws no wall under its displaced surface
     * (docs/techniques/gdm.md, "open borders"). */
    bool seam = gdm_shell_face_is_seam(s->shell, face); /* false without the shell */
    bool seam_entry = d == 0.0f && seam;
    bool border_entry = d == 0.0f && slot >= MESO_PRISM_FIN && s->shell && !seam;
    bool border_cut = border_entry && s->solid;
    if (border_cut) {
        normal = layer->planes[prism_index * MESO_PRISM_NUM_FACES + (size_t)slot].normal;
        /* in texture space: J^T n (normals are covectors), for the shadow test's offset */
        normal_t =
            (meso_vec3){meso_vec3_dot(tf.tangent, normal), meso_vec3_dot(tf.bitangent, normal),
                        -s->depth * meso_vec3_dot(tf.normal, normal)};
    }
    float length_t = meso_vec3_length(normal_t);
    normal_t = length_t > 0.0f ? meso_vec3_scale(normal_t, 1.0f / length_t) : (meso_vec3){0, 0, -1};
    f->position = position;
    f->normal = normal;
    f->tangent = tf.tangent; /* the base surface's frame at the hit: orients a normal map */
    f->bitangent = tf.bitangent;
    f->uv = (meso_vec2){hit.x, hit.y};
    *out_hit = (gdm_gi_hit){hit, prism};
    const meso_scene *scene = frame->scene;
    for (int li = 0; li < scene->num_lights; li++) {
        visibility[li] = 1.0f;
        if (!s->shadows) continue;
        meso_vec3 l = meso_light_direction(&scene->lights[li], position);
        if (meso_vec3_dot(l, normal) <= 0.0f) continue; /* unlit anyway */
        meso_vec3 lt = texture_direction(&tf, l);
        /* beyond the paper (gdm_shell_shadow.h): past the slab the light is followed through
         * the rest of the shell; a solid's light toward the slab's bottom from the point on */
        bool through_floor = s->shell && s->solid && lt.z >= 0.0f;
        bool blocked;
        if (border_cut) {
            /* on an open border's cut face: past the border the flat slab holds the periodic
             * mesostructure's continuation, which the shell does not have. The walk leaves
             * through the border's fin and tests whatever part of the shell it meets after. */
            blocked =
                !gdm_shell_light_visible_at(s->shell, prism_index, hit, &point, l, true, false);
        } else {
            blocked = !through_floor && shadowed(s, hit, normal_t, lt, s->solid && seam_entry);
            /* §3.2's slab is the point's tangent frame extended flat: where the shell curves
             * away (a sphere's terminator, a vase's neck at its outline) the flat slab holds
             * mesostructure the curved shell does not, and its blockers are false. A blocker
             * it reports is checked by the walk from the point on, each prism's segment
             * probed every voxel (docs/techniques/gdm.md, "the slab's blockers checked on
             * the curved shell"); so is a solid's light toward the bottom, which the slab
             * cannot test. Not at a height field's open border, whose side the slab answers
             * as the reference (no wall) has it. */
            if (s->shell && (through_floor || (blocked && !border_entry)))
                blocked =
                    !gdm_shell_light_visible_at(s->shell, prism_index, hit, &point, l, false, true);
            /* A light the slab finds clear is walked on past the slab; not from a prism whose
             * top has the whole shell behind it (clear_top_walk 0): the ray leaves the shell
             * through a top before the flat slab's end on a convex mesh, and that walk only
             * crossed prisms untested (the same image with fewer instructions;
             * docs/techniques/gdm.md, clear_top_walk). */
            else if (s->shell && !blocked &&
                     !(s->skip_clear_tops && gdm_shell_top_clear(s->shell, prism_index)))
                blocked =
                    !gdm_shell_light_visible_at(s->shell, prism_index, hit, &point, l, true, false);
        }
        if (blocked) visibility[li] = 0.0f;
    }
}

/* The ray's entry on the drawn face and its crossing of the face's prism (gdm_walk_enter). */
static bool fragment_entry(const gdm_state *s, const meso_frame *frame, const meso_mesh *mesh,
                           const meso_fragment *f, bool walk, gdm_walk_crossing *c, meso_vec3 *t_in,
                           meso_vec3 *view) {
    return gdm_walk_enter(s->layer, mesh, s->drawn_face[f->triangle], f->b0, f->b1, f->b2,
                          f->position, frame->eye, walk, c, t_in, view);
}

/* One fragment of a prism's face (§3.2, every face drawn): false when the ray leaves its
 * prism without meeting the mesostructure. Fills position, normal, uv, out_depth and the
 * lights' visibility. */
static bool shade_one(const gdm_state *s, const meso_frame *frame, const meso_object *object,
                      meso_fragment *f, float *visibility, gdm_gi_hit *out_hit) {
    gdm_walk_crossing c;
    meso_vec3 t_in, view;
    prism_segment seg;
    if (!fragment_entry(s, frame, object->mesh, f, false, &c, &t_in, &view) ||
        !segment_hit(s, object->mesh, &c, t_in, view, &seg))
        return false;
    shade_hit(s, frame, object, f, &c, &seg, visibility, out_hit);
    return true;
}

/* One fragment of the shell's outer boundary (the walk): from the prism the ray enters, §3.2
 * in each prism it crosses, front to back, into the neighbour across each shared fin
 * (gdm_walk.h), to the first hit; false when it leaves the shell first (where it enters again
 * farther on, that boundary face's own fragment walks on). */
static bool shade_walk(const gdm_state *s, const meso_frame *frame, const meso_object *object,
                       meso_fragment *f, float *visibility, gdm_gi_hit *out_hit) {
    gdm_walk_crossing c;
    meso_vec3 t_in, view;
    prism_segment seg;
    if (!fragment_entry(s, frame, object->mesh, f, true, &c, &t_in, &view)) return false;
    for (int n = 0; n < GDM_WALK_MAX_PRISMS; n++) {
        /* a stretch of no length holds nothing (a fold's planes crossed at the entry point,
         * whose (u, v, w) on two faces' planes differ) -- but a floor there is the floor */
        bool tested = c.t_exit > 0.0f || c.exit_slot == MESO_PRISM_BOTTOM;
        if (tested && segment_hit(s, object->mesh, &c, t_in, view, &seg)) {
            shade_hit(s, frame, object, f, &c, &seg, visibility, out_hit);
            return true;
        }
        size_t exit_face = meso_prism_layer_face(s->layer, c.prism, c.exit_slot);
        if (!gdm_walk_next(s->layer, s->fin_twin, &c)) return false;
        /* the exit's (u, v, w), made by segment_hit, is the entry's unless a UV seam lies
         * between (the same linear interpolation of the same vertices) */
        t_in = tested && s->twin_same_uvw[exit_face]
                   ? seg.t_out
                   : meso_prism_layer_face_uvw(s->layer, c.entry_face, c.p_in);
        if (!gdm_walk_exit(s->layer, &c, view)) return false;
    }
    return false;
}

/* A block of fragments (render_internal.h): each one's ray through its prism (shade_one, on a
 * meso_fragment holding the inputs it reads), then the hits of up to 64 fragments shaded
 * together 8-wide; misses draw nothing. Read straight from the block's arrays: through the
 * per-fragment adapter every field of every fragment would be copied out and back, and most
 * fragments are misses. Each fragment's result is its own, so the
 * same bits as shading it alone. */
static void gdm_shade_block(const void *state, const meso_frame *frame, const meso_object *object,
                            meso_fragment_block *block) {
    const gdm_state *s = state;
    int num_lights = frame->scene->num_lights;
    enum { CHUNK = 64 };
    float visibility[CHUNK * MESO_SCENE_MAX_LIGHTS];
    gdm_gi_hit hits[CHUNK];
    meso_fragment fragments[CHUNK];
    size_t lanes[CHUNK]; /* the block lane of each hit */
    size_t count = block->count;
    memset(gdm_thread_counts, 0, sizeof gdm_thread_counts);
    for (size_t start = 0; start < count; start += CHUNK) {
        size_t end = start + CHUNK < count ? start + CHUNK : count, n = 0;
        for (size_t i = start; i < end; i++) {
            meso_fragment *f = &fragments[n];
            f->triangle = block->triangle[i];
            f->b0 = block->b0[i], f->b1 = block->b1[i], f->b2 = block->b2[i];
            f->position = (meso_vec3){block->px[i], block->py[i], block->pz[i]};
            f->depth = block->depth[i];
            f->out_depth = block->out_depth[i];
            meso_fragment_footprint_from_block(f, block, i);
            float *v = visibility + n * (size_t)num_lights;
            if (s->boundary ? shade_walk(s, frame, object, f, v, &hits[n])
                            : shade_one(s, frame, object, f, v, &hits[n]))
                lanes[n++] = i;
            else
                block->discard[i] = 1;
        }
        if (!n) continue;
        if (s->gi)
            gdm_gi_shade(s->gi, frame, object, fragments, n, visibility, hits);
        else
            meso_shade_fragments(frame, object, fragments, n, visibility);
        for (size_t h = 0; h < n; h++) {
            size_t i = lanes[h];
            block->r[i] = fragments[h].color.x;
            block->g[i] = fragments[h].color.y;
            block->b[i] = fragments[h].color.z;
            block->out_depth[i] = fragments[h].out_depth;
        }
    }
    /* the state's one write while shading: relaxed adds, the totals the same in any order */
    _Atomic uint64_t *counted = (_Atomic uint64_t *)s->counted;
    for (int c = 0; c < GDM_NUM_COUNTS; c++)
        atomic_fetch_add_explicit(&counted[c], gdm_thread_counts[c], memory_order_relaxed);
}

static size_t gdm_memory(const void *state) {
    const gdm_state *s = state;
    if (!s) return 0;
    meso_gdm_compression c = meso_gdm_get_compression(s->gdm);
    meso_gdm_view v = meso_gdm_get_view(s->gdm);
    size_t normals = (size_t)v.width * (size_t)v.height * (size_t)v.layers * 3 * sizeof(float);
    return (size_t)c.compressed_bytes + (v.raw ? (size_t)c.raw_bytes : 0) + normals +
           gdm_lookup_table_bytes(&s->table) + meso_prism_layer_memory(s->layer) +
           s->group_start[3] * (4 * sizeof(uint32_t) + sizeof(float)) +
           (s->boundary ? s->group_start[3] * sizeof(uint32_t) +
                              s->layer->faces->num_triangles * (sizeof(uint32_t) + 1)
                        : 0) +
           gdm_gi_memory(s->gi) + gdm_shell_memory(s->shell) +
           (s->grid ? (size_t)GDM_GRID_LAYERS * GDM_GRID_SIDE * GDM_GRID_SIDE * sizeof(float) : 0) +
           (s->window_max && s->window_levels > GDM_WINDOW_FIRST
                ? (size_t)(s->window_levels - GDM_WINDOW_FIRST) * (size_t)s->heightfield->width *
                      (size_t)s->heightfield->height * sizeof(uint16_t)
                : 0);
}

static void gdm_counters(const void *state, uint64_t out[3]) {
    const gdm_state *s = state;
    for (int c = 0; c < GDM_NUM_COUNTS; c++)
        out[c] += atomic_load_explicit((_Atomic uint64_t *)&s->counted[c], memory_order_relaxed);
}

const meso_technique meso_technique_gdm = {
    .info = {.name = "gdm",
             .summary = "generalized displacement maps: prisms rasterized, 5D distance lookup",
             .paper = "Wang et al. 2004, \"Generalized Displacement Maps\", §3.2",
             .kind = MESO_TECHNIQUE_GEOMETRY,
             /* solids that tile only: the GDM is one tile's volume repeated over the surface
              * (§3), and a model's solid (an impostor) is clamped at its box */
             .accepts = MESO_TECHNIQUE_ACCEPTS_HEIGHT_FIELD | MESO_TECHNIQUE_ACCEPTS_SOLID,
             .options = gdm_option_table,
             .num_options = MESO_OPTION_COUNT(gdm_option_table)},
    .prepare = gdm_prepare,
    .release = gdm_release,
    .geometry = gdm_geometry,
    .shade_block = gdm_shade_block,
    /* shade_one reads a fragment's triangle, barycentrics, position and depth */
    .skip_fields = MESO_FRAGMENT_SKIP_SAMPLE | MESO_FRAGMENT_SKIP_TANGENTS,
    .memory = gdm_memory,
    .counters = gdm_counters,
};
