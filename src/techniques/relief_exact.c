/* relief_exact: relief mapping without the linear search's misses and stair-steps. The view
 * ray (and each shadow ray) is traced through the maximum mip-map of the height field (Tevs,
 * Ihrke, Seidel 2008, "Maximum mipmaps for fast, accurate, and scalable dynamic height field
 * rendering", §3-4): a cell whose highest point lies above the ray over the ray's whole span in
 * the cell is skipped to its exit; otherwise the traversal descends; at level 0 the ray meets
 * the bilinear patch between four texel centres, solved exactly (both the ray's depth and the
 * bilinear height are quadratics in the ray parameter). On power-of-two repeating fields the view
 * rays first take conservative cone steps (Dummer 2006; bake_cone.h) through the space the cone
 * map proves empty, then the traversal takes over. Silhouettes, depth correction, shading
 * and the shadow rays' set-up are relief's (relief_common.h); with `shell` 1 the traversal runs
 * on each prism's stretch of the ray's path through the prism shell (relief_shell.h).
 * docs/techniques/relief_exact.md. */
#include <float.h>

#include "meso/bake_cone.h"
#include "meso/bake_minmax.h"
#include "meso/runtime.h"
#include "relief_shell.h"

/* Clamp-to-edge fields are not periodic, so the pyramid's wrapped cells do not bound them; they
 * use relief's search with these many steps instead (documented). */
#define CLAMP_LINEAR_STEPS 64
#define CLAMP_BINARY_STEPS 8
#define CLAMP_SHADOW_STEPS 64
/* A ray crosses at most a few thousand cells at the grazing angles a frame holds; the cap only
 * guards against a non-terminating traversal on pathological input. */
#define MAX_ITERATIONS 20000
#ifndef START_LEVEL_CAP
#define START_LEVEL_CAP 2
#endif
/* Cone steps (trace8_cone): at most this many before the maximum mip-map traversal, which
 * takes over once a step would be shorter than CONE_MIN_STEP texels (L1). */
#ifndef CONE_STEPS
#define CONE_STEPS 32
#endif
#ifndef CONE_MIN_STEP
#define CONE_MIN_STEP 0.25f
#endif
/* The cone's bound is shortened by this many texels of the ray's position (float rounding). */
#define CONE_POSITION_SLACK 1e-3f

typedef struct exact_state {
    relief_heights heights;
    meso_minmax_pyramid *pyramid;
    /* The cone map's slopes as bytes (power-of-two repeating fields only, else NULL): slope =
     * (code / 255)^2 * cone_scale, rounded up, so the cone steps read a quarter of the map's
     * bytes (the tops come from the pyramid's level 0, which the traversal reads too). */
    uint8_t *cone_codes;
    float cone_scale;
    relief_maxmip maxmip; /* the pyramid's tables for relief_shadow_clear8 */
    relief_params params;
    bool power_of_two; /* both sides: the 8-wide traversal applies */
    /* per level: the offset of its max array in pyramid->block (gathered per lane) */
    int32_t level_offset[MESO_MINMAX_MAX_LEVELS];
    bool shadows;
    relief_shell *shell; /* the shell option; NULL: off */
} exact_state;

typedef struct exact_options {
    bool shadows, silhouettes, shell;
} exact_options;

static const meso_technique_option exact_option_table[] = {
    MESO_OPTION_ROW(MESO_OPTION_BOOL, shadows, 0, 1, 1,
                    "self-shadows: the exact trace toward each light", exact_options, shadows),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, silhouettes, 0, 1, 1, "silhouettes from per-vertex quadrics",
                    exact_options, silhouettes),
    MESO_OPTION_ROW(MESO_OPTION_BOOL, shell, 0, 1, 0,
                    "1: the traversal runs along the ray's path through the prism shell, prism "
                    "by prism (exact on curved surfaces, side bands at open borders, silhouettes "
                    "from the shell; CPU only); 0: a straight ray in the pixel's tangent space",
                    exact_options, shell),
};

/* A ray in texel-centre coordinates with depth d(t) = c0 + c1 t + c2 t^2 over [t0, t1]; it hits
 * where d >= 1 - h + bias. */
typedef struct exact_ray {
    double x0, y0, xd, yd;
    double c0, c1, c2;
    double t0, t1;
    double bias;
} exact_ray;

static inline double ray_depth(const exact_ray *r, double t) {
    return r->c0 + t * (r->c1 + t * r->c2);
}

/* The deepest point of the ray over [ta, tb]: the ends, or the vertex of the parabola. */
static inline double max_depth(const exact_ray *r, double ta, double tb) {
    double da = ray_depth(r, ta), db = ray_depth(r, tb), m = da > db ? da : db;
    if (r->c2 < 0.0) {
        double tv = -r->c1 / (2.0 * r->c2);
        if (tv > ta && tv < tb) {
            double dv = ray_depth(r, tv);
            m = dv > m ? dv : m;
        }
    }
    return m;
}

/* The first tau in [0, tau_max] with A tau^2 + B tau + C >= 0, given C < 0; false if none. */
static inline bool first_root(double A, double B, double C, double tau_max, double *out_tau) {
    double best = DBL_MAX;
    if (fabs(A) < 1e-12 * (fabs(B) + fabs(C) + 1e-30)) {
        if (B > 0.0) best = -C / B;
    } else {
        double disc = B * B - 4.0 * A * C;
        if (disc < 0.0) return false;
        double q = -0.5 * (B + copysign(sqrt(disc), B));
        double r1 = q / A, r2 = q != 0.0 ? C / q : DBL_MAX;
        if (r1 >= 0.0 && r1 < best) best = r1;
        if (r2 >= 0.0 && r2 < best) best = r2;
    }
    if (best > tau_max) return false;
    *out_tau = best;
    return true;
}

/* The cell of level `level` containing x (periodic with `size` level-0 cells), nudged along
 * the direction so a point on a border belongs to the cell the ray enters. Returns the cell
 * index and its [lo, hi] in unwrapped coordinates. */
static inline int locate(double x, double dir, int size, int level, double *lo, double *hi) {
    double nudge = dir > 0.0 ? 1e-7 : (dir < 0.0 ? -1e-7 : 0.0);
    double xn = x + nudge * (1.0 + fabs(x));
    double tile = floor(xn / (double)size);
    double local = xn - tile * (double)size;
    int cell = (int)local;
    cell = cell >= size ? size - 1 : (cell < 0 ? 0 : cell);
    cell >>= level;
    double base = tile * (double)size;
    int end = (cell + 1) << level;
    *lo = base + (double)(cell << level);
    *hi = base + (double)(end < size ? end : size);
    return cell;
}

/* The level to start at: the finest whose cells are as long as the ray's whole footprint, so
 * a short (steep) ray does not descend from the top of the pyramid. */
static inline int start_level(const exact_ray *r, int top) {
    double extent = (fabs(r->xd) + fabs(r->yd)) * (r->t1 - r->t0);
    int level = 0;
    while (level < top && (double)(1 << level) < extent) ++level;
    return level;
}

/* Tevs et al. 2008 §4: hierarchical traversal of the maximum mip-map, any field size. */
static bool trace_any(const exact_state *s, const exact_ray *r, double *out_t) {
    const meso_minmax_pyramid *p = s->pyramid;
    const relief_heights *m = &s->heights;
    int top = p->num_levels - 1, level = start_level(r, top);
    double t = r->t0;
    for (int iteration = 0; iteration < MAX_ITERATIONS; ++iteration) {
        if (t >= r->t1) return false;
        double px = r->x0 + r->xd * t, py = r->y0 + r->yd * t;
        double xlo, xhi, ylo, yhi;
        int cx = locate(px, r->xd, m->width, level, &xlo, &xhi);
        int cy = locate(py, r->yd, m->height, level, &ylo, &yhi);
        double tx =
            r->xd > 0.0 ? (xhi - r->x0) / r->xd : (r->xd < 0.0 ? (xlo - r->x0) / r->xd : DBL_MAX);
        double ty =
            r->yd > 0.0 ? (yhi - r->y0) / r->yd : (r->yd < 0.0 ? (ylo - r->y0) / r->yd : DBL_MAX);
        double t_exit = tx < ty ? tx : ty;
        t_exit = t_exit < r->t1 ? t_exit : r->t1;
        if (!(t_exit > t))
            t_exit = t + 1e-9 * (1.0 + t); /* a border rounded behind t: step over it */
        const meso_minmax_level *lv = &p->levels[level];
        double top_depth = 1.0 - (double)lv->max[(size_t)cy * (size_t)lv->width + (size_t)cx];
        if (max_depth(r, t, t_exit) >= top_depth + r->bias) {
            if (level > 0) {
                --level;
                continue;
            }
            /* Level 0: the bilinear patch of texels (cx..cx+1, cy..cy+1) along the ray. */
            const float *r0 = m->padded + (size_t)cy * (size_t)m->stride + (size_t)cx;
            const float *r1 = r0 + m->stride;
            double h00 = r0[0], h10 = r0[1], h01 = r1[0], h11 = r1[1];
            double hx = h10 - h00, hy = h01 - h00, hxy = h00 - h10 - h01 + h11;
            double sx = px - xlo, sy = py - ylo; /* local coordinates at t */
            /* f(tau) = d(t + tau) - 1 + h(sx + xd tau, sy + yd tau) - bias */
            double C = ray_depth(r, t) - 1.0 + h00 + hx * sx + hy * sy + hxy * sx * sy - r->bias;
            if (C >= 0.0) {
                *out_t = t;
                return true;
            }
            double B =
                r->c1 + 2.0 * r->c2 * t + hx * r->xd + hy * r->yd + hxy * (sx * r->yd + sy * r->xd);
            double A = r->c2 + hxy * r->xd * r->yd;
            double tau;
            if (first_root(A, B, C, t_exit - t, &tau)) {
                *out_t = t + tau;
                return true;
            }
        }
        /* Skip the cell; climb when the exit is also the parent's border (§4). */
        bool exit_x = tx <= ty;
        int c = exit_x ? cx : cy;
        double dir = exit_x ? r->xd : r->yd;
        double hi = exit_x ? xhi : yhi, lo = exit_x ? xlo : ylo;
        double tile_end = exit_x ? (double)m->width : (double)m->height;
        bool parent_border = dir > 0.0 ? ((c & 1) || fmod(hi, tile_end) == 0.0) : !(c & 1);
        (void)lo;
        if (parent_border && level < top) ++level;
        t = t_exit;
    }
    *out_t = t; /* the cap: take where the traversal got to */
    return true;
}

/* Eight rays in the vector registers (c0 + c1 t + c2 t^2 depth, t in [t0, t1]). */
typedef struct exact_rays8 {
    v8f x0, y0, xd, yd, c0, c1, c2, t0, t1;
    float bias;
} exact_rays8;

/* The offset of each lane's level in the pyramid's block: two in-register table lookups
 * (levels 0-7 and 8-15) instead of a gather, for pyramids of up to 16 levels. */
static inline v8i level_offsets(const exact_state *s, v8i level) {
#if defined(__AVX2__)
    if (s->pyramid->num_levels <= 16) {
        __m256i lo = _mm256_loadu_si256((const __m256i *)s->level_offset);
        __m256i hi = _mm256_loadu_si256((const __m256i *)(s->level_offset + 8));
        v8i a = (v8i)_mm256_permutevar8x32_epi32(lo, (__m256i)level);
        v8i b = (v8i)_mm256_permutevar8x32_epi32(hi, (__m256i)level);
        return (v8i)v8_select(level > 7, (v8f)b, (v8f)a);
    }
#endif
    return v8i_gather(s->level_offset, level);
}

static inline v8f depth8(const exact_rays8 *r, v8f t) { return r->c0 + t * (r->c1 + t * r->c2); }

/* The traversal of trace_any for power-of-two fields, eight rays at once, each with its own
 * level and position (Tevs et al. 2008 §4 run per lane): every level is a regular periodic
 * grid, so cells follow from the integer texel index by shifts and masks, and the pyramid is
 * read with gathers. Lanes leave as they hit or run out. One iteration is a long chain of
 * dependent operations (position, cell, exit, gather, test), so two groups of eight rays are
 * stepped in turn (trace8x2) and the processor overlaps their chains. */
typedef struct trace8_state {
    v8f t, t_hit, inv_xd, inv_yd, nudge_x, nudge_y;
    v8i level;
    v8i advanced;  /* lanes whose t lies inside a cell (the clearance advance), not on its border */
    v8f inv_slope; /* 0.99 / the depth's greatest slope, 0: no clearance advance */
    bool may_advance; /* some lane has inv_slope > 0 (view rays; shadow rays rise) */
    int active, hit;
    bool curved; /* a parabola's vertex may lie inside a cell */
} trace8_state;

static inline void trace8_begin(const exact_state *s, const exact_rays8 *r, int active, bool view,
                                trace8_state *st) {
    const v8f zero = v8_splat(0.0f);
    /* View rays start where the cells are as long as the ray's footprint (start_level, per
     * lane). Shadow rays start at level 0: they leave the surface, so every coarser cell
     * around their start reaches them and would only be descended, a step a level (fewer
     * instructions, the same images). */
    v8f extent = (v8_max(r->xd, -r->xd) + v8_max(r->yd, -r->yd)) * (r->t1 - r->t0);
    st->level = v8i_splat(0);
    int start_cap =
        s->pyramid->num_levels < START_LEVEL_CAP + 1 ? s->pyramid->num_levels : START_LEVEL_CAP + 1;
    if (!view) start_cap = 1;
    for (int l = 1; l < start_cap; ++l) st->level += (extent > (float)(1 << (l - 1))) & 1;
    st->t = r->t0;
    st->t_hit = zero;
    st->inv_xd =
        v8_select(r->xd != 0.0f, 1.0f / v8_select(r->xd != 0.0f, r->xd, v8_splat(1.0f)), zero);
    st->inv_yd =
        v8_select(r->yd != 0.0f, 1.0f / v8_select(r->yd != 0.0f, r->yd, v8_splat(1.0f)), zero);
    /* A point on a cell border belongs to the cell the ray enters: nudge along the ray by far
     * more than the rounding of the position (float: 6e-8 relative). */
    st->nudge_x =
        v8_select(r->xd > 0.0f, v8_splat(1e-5f), v8_select(r->xd < 0.0f, v8_splat(-1e-5f), zero));
    st->nudge_y =
        v8_select(r->yd > 0.0f, v8_splat(1e-5f), v8_select(r->yd < 0.0f, v8_splat(-1e-5f), zero));
    st->advanced = v8i_splat(0);
    /* The depth's slope c1 + 2 c2 t is greatest at t0 where it is concave (c2 <= 0): the
     * tangent there bounds the depth from above over the whole ray (clearance advance). */
    v8f slope = r->c1 + 2.0f * r->c2 * r->t0;
    v8i descends = (slope > 0.0f) & (r->c2 <= 0.0f) & v8_mask_from_bits(active);
    st->inv_slope = v8_select(descends, 0.99f / v8_select(descends, slope, v8_splat(1.0f)), zero);
    st->may_advance = v8_mask_bits(descends) != 0;
    st->active = active;
    st->hit = 0;
    st->curved = v8_mask_bits(r->c2 < 0.0f) != 0;
}

/* One iteration for every active lane: descend, solve at level 0, or skip to the cell's exit. */
__attribute__((always_inline)) static inline void
trace8_step(const exact_state *s, const exact_rays8 *r, trace8_state *st) {
    const relief_heights *m = &s->heights;
    const v8f zero = v8_splat(0.0f), big = v8_splat(FLT_MAX);
    v8i level = st->level;
    v8f t = st->t;
    v8i on = v8_mask_from_bits(st->active);
    v8f px = r->x0 + r->xd * t, py = r->y0 + r->yd * t;
    v8i ix = __builtin_convertvector(v8_floor(px + st->nudge_x * (1.0f + v8_max(px, -px))), v8i);
    v8i iy = __builtin_convertvector(v8_floor(py + st->nudge_y * (1.0f + v8_max(py, -py))), v8i);
    v8i cx = ix >> level, cy = iy >> level; /* arithmetic shifts: floor for negatives */
    v8f xlo = __builtin_convertvector(cx << level, v8f);
    v8f ylo = __builtin_convertvector(cy << level, v8f);
    v8f size = __builtin_convertvector(v8i_splat(1) << level, v8f);
    v8f tx = v8_select(r->xd == 0.0f, big,
                       (xlo + v8_select(r->xd > 0.0f, size, zero) - r->x0) * st->inv_xd);
    v8f ty = v8_select(r->yd == 0.0f, big,
                       (ylo + v8_select(r->yd > 0.0f, size, zero) - r->y0) * st->inv_yd);
    v8f t_exit = v8_min(v8_min(tx, ty), r->t1);
    t_exit = v8_max(t_exit, t + (1e-6f * t + 1e-12f)); /* a border rounded behind t */
    /* power-of-two sides: a level is (W >> level) x (H >> level) cells, at least 1 */
    v8i lw = v8i_splat(m->width) >> level, lh = v8i_splat(m->height) >> level;
    lw = (v8i)v8_select(lw < 1, (v8f)v8i_splat(1), (v8f)lw);
    lh = (v8i)v8_select(lh < 1, (v8f)v8i_splat(1), (v8f)lh);
    v8i wx = cx & (lw - 1), wy = cy & (lh - 1);
    v8i index = level_offsets(s, level) + wy * lw + wx;
    index = (v8i)v8_select(on, (v8f)index, (v8f)v8i_splat(0));
    v8f top_depth = 1.0f - v8_gather(s->pyramid->block, index);
    /* the deepest point of the ray in the cell: its ends or the parabola's vertex */
    v8f dmax = v8_max(depth8(r, t), depth8(r, t_exit));
    if (st->curved) {
        v8f tv = -r->c1 / v8_select(r->c2 < 0.0f, 2.0f * r->c2, v8_splat(-1.0f));
        v8i inside_v = (r->c2 < 0.0f) & (tv > t) & (tv < t_exit);
        dmax = v8_select(inside_v, v8_max(dmax, depth8(r, tv)), dmax);
    }
    v8i overlap = on & (dmax >= top_depth + r->bias);
    v8i at_leaf = level == 0;
    v8i solve = overlap & at_leaf;
    v8i found = v8i_splat(0);
    if (v8_mask_bits(solve)) {
        /* Level 0: the bilinear patch of texels (cx..cx+1, cy..cy+1) along the ray;
         * f(tau) = d(t + tau) - 1 + h(sx + xd tau, sy + yd tau) - bias = A tau^2 + B tau + C */
        v8i corner = (v8i)v8_select(solve, (v8f)(wy * m->stride + wx), (v8f)v8i_splat(0));
        v8f h00, h10, h01, h11;
        relief_gather_pairs8(m->padded, corner, &h00, &h10);
        relief_gather_pairs8(m->padded + m->stride, corner, &h01, &h11);
        v8f hx = h10 - h00, hy = h01 - h00, hxy = h00 - h10 - h01 + h11;
        /* The root is found from where the ray entered the cell (or its start), not from t,
         * which the clearance advance (below) may have moved into the cell: the same
         * arithmetic, so the same hit, as a traversal that steps from border to border. The
         * entry is the later of the borders it crossed, computed as the exits were. */
        v8f ex = v8_select(r->xd == 0.0f, -big,
                           (xlo + v8_select(r->xd > 0.0f, zero, size) - r->x0) * st->inv_xd);
        v8f ey = v8_select(r->yd == 0.0f, -big,
                           (ylo + v8_select(r->yd > 0.0f, zero, size) - r->y0) * st->inv_yd);
        v8f origin = t;
        if (v8_mask_bits(st->advanced & solve))
            origin = v8_select(st->advanced, v8_max(r->t0, v8_min(t, v8_max(ex, ey))), t);
        v8f ox = r->x0 + r->xd * origin, oy = r->y0 + r->yd * origin;
        v8f sx = ox - xlo, sy = oy - ylo;
        v8f C = depth8(r, origin) - 1.0f + h00 + hx * sx + hy * sy + hxy * sx * sy - r->bias;
        v8f B = r->c1 + 2.0f * r->c2 * origin + hx * r->xd + hy * r->yd +
                hxy * (sx * r->yd + sy * r->xd);
        v8f A = r->c2 + hxy * r->xd * r->yd;
        v8f span = t_exit - origin;
        /* the smallest root in [0, span]; C >= 0: at once */
        v8f tau = v8_select(B > 0.0f, -C / v8_select(B > 0.0f, B, v8_splat(1.0f)), big);
        v8f disc = B * B - 4.0f * A * C;
        v8f root = v8_sqrt(v8_max(disc, zero));
        v8f q = -0.5f * (B + v8_select(B < 0.0f, -root, root));
        v8f r1 = q / v8_select(A != 0.0f, A, v8_splat(1.0f));
        v8f r2 = C / v8_select(q != 0.0f, q, v8_splat(1.0f));
        v8f best = v8_min(v8_select(r1 >= 0.0f, r1, big), v8_select(r2 >= 0.0f, r2, big));
        v8i linear = v8_max(A, -A) < 1e-7f * (v8_max(B, -B) + v8_max(C, -C) + 1e-30f);
        best = v8_select(linear, tau, v8_select(disc >= 0.0f, best, big));
        best = v8_select(C >= 0.0f, zero, best);
        found = solve & (best <= span);
        st->t_hit = v8_select(found, origin + best, st->t_hit);
    }
    int found_bits = v8_mask_bits(found);
    st->hit |= found_bits;
    /* descend where the cell reaches the ray above level 0; else skip to the exit and climb
     * when that exit is also the parent's border (§4) */
    v8i descend = overlap & ~at_leaf;
    v8i skip = on & ~descend & ~found;
    v8i exit_x = tx <= ty;
    v8i c = (v8i)v8_select(exit_x, (v8f)cx, (v8f)cy);
    v8f dir = v8_select(exit_x, r->xd, r->yd);
    v8i odd = (c & 1) != 0;
    v8i border = (v8i)v8_select(dir > 0.0f, (v8f)odd, (v8f)~odd);
    v8i climb = skip & border & (level < v8i_splat(s->pyramid->num_levels - 1));
    st->level = level - (descend & 1) + (climb & 1);
    /* Clearance advance (beyond Tevs et al.): a descending view ray above the cell's highest
     * point at t stays above it until its depth reaches that height, so the first hit lies
     * past that point; the ray moves there before it descends, and so enters the finer cells
     * near the hit instead of skipping them one by one. The depth's tangent at the start
     * (inv_slope) bounds a concave depth from above; the step is shortened a little so its
     * rounding never passes the point, and kept inside the cell. */
    v8f t_next = v8_select(skip, t_exit, t);
    if (st->may_advance) {
        v8f t_clear = t + (top_depth + r->bias - depth8(r, t)) * st->inv_slope;
        v8i advance = descend & (t_clear > t) & (t_clear < t_exit);
        st->advanced = (st->advanced | advance) & ~skip;
        t_next = v8_select(advance, t_clear, t_next);
    }
    st->t = t_next;
    int done = v8_mask_bits(skip & (t_exit >= r->t1));
    st->active &= ~(found_bits | done);
}

/* Cone steps (Dummer 2006, conservative cones; bake_cone.h) before the traversal: a ray at t
 * above the top of the level-0 cell under it, by `gap` in depth, meets no surface while its
 * depth rises less than gap minus the cone's rise, slope * (L1 distance moved); with the
 * depth's steepest slope over the ray (a bound for any parabola: the slope is linear in t)
 * that is a step of gap / (depth slope + cone slope * L1 length a unit of t). The steps only
 * skip space the surface provably leaves empty, so the traversal that takes over (at level 0,
 * solving each patch from the cell's entry as after the clearance advance) finds the same first
 * hit. A lane stops when its step falls under CONE_MIN_STEP texels; a lane whose step passes
 * the ray's end has no hit. */
/* codes[index[k]] per lane (the array has 3 bytes of padding: 32-bit loads). */
static inline v8i cone_code8(const uint8_t *codes, v8i index) {
#if defined(__AVX2__)
    return (v8i)_mm256_i32gather_epi32((const int *)(const void *)codes, (__m256i)index, 1) & 0xff;
#else
    v8i r;
    for (int k = 0; k < V8_LANES; ++k) r[k] = codes[index[k]];
    return r;
#endif
}

static void trace8_cone(const exact_state *s, const exact_rays8 *r, trace8_state *st) {
    const relief_heights *m = &s->heights;
    const v8f zero = v8_splat(0.0f);
    v8f length = v8_max(r->xd, -r->xd) + v8_max(r->yd, -r->yd);
    v8f slope = v8_max(v8_max(r->c1 + 2.0f * r->c2 * r->t0, r->c1 + 2.0f * r->c2 * r->t1), zero);
    v8f t = st->t;
    v8i moved = v8i_splat(0), finished = v8i_splat(0);
    v8i wmask = v8i_splat(m->width - 1), hmask = v8i_splat(m->height - 1);
    int row_shift = __builtin_ctz((unsigned)m->width);
    const float *tops = s->pyramid->levels[0].max;
    const v8f inv255 = v8_splat(1.0f / 255.0f), scale = v8_splat(s->cone_scale);
    v8i on = v8_mask_from_bits(st->active);
    for (int i = 0; i < CONE_STEPS && v8_mask_bits(on); ++i) {
        v8f px = r->x0 + r->xd * t, py = r->y0 + r->yd * t;
        v8i ix = __builtin_convertvector(v8_floor(px), v8i);
        v8i iy = __builtin_convertvector(v8_floor(py), v8i);
        /* wrapped by the masks, so every lane reads inside the map */
        v8i cell = ((iy & hmask) << row_shift) | (ix & wmask);
        v8f top = v8_gather(tops, cell);
        v8f q = __builtin_convertvector(cone_code8(s->cone_codes, cell), v8f) * inv255;
        v8f cone = q * q * scale;
        v8f gap = (1.0f - top) + r->bias - depth8(r, t) - cone * CONE_POSITION_SLACK;
        /* a zero denominator (a level ray, no higher texel) makes an infinite step: past t1 */
        v8f dt = 0.99f * gap / v8_max(slope + cone * length, v8_splat(FLT_MIN));
        v8f t_next = t + dt;
        v8i ok = on & (gap > 0.0f);
        v8i past = ok & (t_next >= r->t1);
        v8i advance = ok & ~past;
        t = v8_select(advance, t_next, t);
        moved |= advance;
        finished |= past;
        on = advance & (dt * length >= CONE_MIN_STEP);
    }
    st->active &= ~v8_mask_bits(finished);
    st->t = t;
    st->advanced |= moved;
    st->level = (v8i)v8_select(moved, (v8f)v8i_splat(0), (v8f)st->level);
}

static inline int trace8_end(trace8_state *st, v8f *out_t) {
    /* the iteration cap (pathological input only): take where the lanes got to */
    st->t_hit = v8_select(v8_mask_from_bits(st->active), st->t, st->t_hit);
    *out_t = st->t_hit;
    return st->hit | st->active;
}

/* Lane k of rays b (state q) into lane j of rays a (state p): the ray and its traversal. */
static inline void trace8_move_lane(exact_rays8 *a, trace8_state *p, int j, const exact_rays8 *b,
                                    const trace8_state *q, int k) {
    a->x0[j] = b->x0[k], a->y0[j] = b->y0[k], a->xd[j] = b->xd[k], a->yd[j] = b->yd[k];
    a->c0[j] = b->c0[k], a->c1[j] = b->c1[k], a->c2[j] = b->c2[k];
    a->t0[j] = b->t0[k], a->t1[j] = b->t1[k];
    p->t[j] = q->t[k], p->inv_xd[j] = q->inv_xd[k], p->inv_yd[j] = q->inv_yd[k];
    p->nudge_x[j] = q->nudge_x[k], p->nudge_y[j] = q->nudge_y[k];
    p->level[j] = q->level[k], p->advanced[j] = q->advanced[k];
    p->inv_slope[j] = q->inv_slope[k];
}

/* Trace `count` (1 or 2) groups of eight rays; returns the bits of lanes that hit per group.
 * Once the two groups' active lanes fit in one vector, they are moved into one group and only
 * it steps on: the slowest rays of a group set its pace, so two half-empty groups would cost
 * two steps for one step's work. Every lane's arithmetic is its own (the group-wide `curved`
 * only enables a computation the other lanes ignore), so the results do not change. `view`:
 * view rays (cone steps, the footprint's start level), else shadow rays. */
static void trace8x2(const exact_state *s, const exact_rays8 *rays, const int *active, int count,
                     bool view, v8f *out_t, int *out_hit) {
    trace8_state st[2];
    memset(st, 0, sizeof st);
    const exact_rays8 *r = rays;
    for (int g = 0; g < count; ++g) {
        trace8_begin(s, &r[g], active[g], view, &st[g]);
        if (view && s->cone_codes) trace8_cone(s, &r[g], &st[g]);
    }
    int i = 0;
    if (count == 2) {
        for (; (st[0].active | st[1].active) && i < MAX_ITERATIONS; ++i) {
            if (st[0].active && st[1].active &&
                __builtin_popcount((unsigned)st[0].active) +
                        __builtin_popcount((unsigned)st[1].active) <=
                    RELIEF_LANES)
                break;
            if (st[0].active) trace8_step(s, &r[0], &st[0]);
            if (st[1].active) trace8_step(s, &r[1], &st[1]);
        }
        if (st[0].active && st[1].active && i < MAX_ITERATIONS) {
            /* the finished lanes' results, then the move (into the fuller group: fewer
             * copies) */
            int into = __builtin_popcount((unsigned)st[0].active) >=
                               __builtin_popcount((unsigned)st[1].active)
                           ? 0
                           : 1;
            int from = 1 - into;
            v8f t_done[2] = {st[0].t_hit, st[1].t_hit};
            int hit_done[2] = {st[0].hit, st[1].hit};
            exact_rays8 merged = r[into];
            int source[RELIEF_LANES], moved = 0, free_lanes = ~st[into].active & 0xff;
            for (int pending = st[from].active; pending; pending &= pending - 1) {
                int k = __builtin_ctz((unsigned)pending), j = __builtin_ctz((unsigned)free_lanes);
                free_lanes &= free_lanes - 1;
                trace8_move_lane(&merged, &st[into], j, &r[from], &st[from], k);
                source[j] = k;
                moved |= 1 << j;
            }
            st[into].active |= moved;
            st[into].hit &= ~moved;
            st[into].curved |= st[from].curved;
            st[into].may_advance |= st[from].may_advance;
            st[from].active = 0;
            for (; st[into].active && i < MAX_ITERATIONS; ++i) trace8_step(s, &merged, &st[into]);
            v8f t_merged;
            int bits = trace8_end(&st[into], &t_merged);
            v8i own = v8_mask_from_bits(moved);
            out_t[into] = v8_select(own, t_done[into], t_merged);
            out_hit[into] = (bits & ~moved) | (hit_done[into] & moved);
            out_t[from] = t_done[from];
            out_hit[from] = hit_done[from];
            for (int pending = moved; pending; pending &= pending - 1) {
                int j = __builtin_ctz((unsigned)pending), k = source[j];
                out_t[from][k] = t_merged[j];
                out_hit[from] |= (bits >> j & 1) << k;
            }
            return;
        }
    } else {
        for (; st[0].active && i < MAX_ITERATIONS; ++i) trace8_step(s, &r[0], &st[0]);
    }
    for (int g = 0; g < count; ++g) out_hit[g] = trace8_end(&st[g], &out_t[g]);
}

/* Rays of a view batch for trace8 (origins wrapped into the first tile keep floats small). */
static exact_rays8 view_rays(const exact_state *s, const relief_batch *batch) {
    float w = (float)s->heights.width, h = (float)s->heights.height;
    return (exact_rays8){.x0 = batch->x0 - w * v8_floor(batch->x0 * (1.0f / w)),
                         .y0 = batch->y0 - h * v8_floor(batch->y0 * (1.0f / h)),
                         .xd = batch->xd,
                         .yd = batch->yd,
                         .c0 = v8_splat(0.0f),
                         .c1 = batch->a,
                         .c2 = -batch->b,
                         .t0 = v8_splat(0.0f),
                         .t1 = batch->t_end,
                         .bias = 0.0f};
}

static void search(const void *user, const relief_batch *batches, int count, v8f *out_t,
                   int *out_hit) {
    const exact_state *s = user;
    int todo[2] = {0, 0}, found[2] = {0, 0};
    for (int g = 0; g < count; ++g) {
        const relief_batch *batch = &batches[g];
        out_t[g] = v8_splat(0.0f);
        if (s->heights.clamp) {
            out_hit[g] = relief_search8(&s->heights, batch, CLAMP_LINEAR_STEPS, CLAMP_BINARY_STEPS,
                                        &out_t[g]);
            continue;
        }
        int all = (1 << batch->count) - 1;
        /* Where the ray enters at a texel of full height it hits at once. */
        found[g] = (batch->flat_bits |
                    v8_mask_bits(relief_sample8(&s->heights, batch->x0, batch->y0) >= 1.0f)) &
                   all;
        todo[g] = all & ~found[g];
        if (!s->power_of_two) {
            int hit = 0;
            for (int k = 0; k < batch->count; ++k) {
                if (!(todo[g] >> k & 1)) continue;
                exact_ray r = {batch->x0[k], batch->y0[k], batch->xd[k], batch->yd[k],    0.0,
                               batch->a[k],  -batch->b[k], 0.0,          batch->t_end[k], 0.0};
                double t;
                if (trace_any(s, &r, &t)) {
                    out_t[g][k] = (float)t;
                    hit |= 1 << k;
                }
            }
            out_hit[g] = hit;
        }
    }
    if (s->heights.clamp) return;
    if (s->power_of_two) {
        exact_rays8 r[2];
        v8f t[2];
        int hit[2] = {0, 0};
        memset(r, 0, sizeof r);
        /* No probes to shorten the rays: with the start level capped at 2 and the clearance
         * advance they save no step (they only cost instructions; the same images). */
        for (int g = 0; g < count; ++g) r[g] = view_rays(s, &batches[g]);
        trace8x2(s, r, todo, count, true, t, hit);
        for (int g = 0; g < count; ++g) {
            out_t[g] = v8_select(v8_mask_from_bits(hit[g]), t[g], out_t[g]);
            out_hit[g] = hit[g];
        }
    }
    for (int g = 0; g < count; ++g) {
        /* d = 1 at t_end: rays that reach the floor hit it whatever rounding says */
        int floor_only = batches[g].floor_bits & todo[g] & ~out_hit[g];
        out_t[g] = v8_select(v8_mask_from_bits(floor_only), batches[g].t_end, out_t[g]);
        out_hit[g] |= found[g] | floor_only;
    }
}

static void shadow(const void *user, const relief_shadow_batch *batches, int count,
                   int *out_blocked) {
    const exact_state *s = user;
    /* Lanes the maximum mip-map proves lit need no trace (relief_shadow_clear8: no point of
     * the light ray comes within the bias of the surface). */
    relief_shadow_batch cleared[2];
    for (int g = 0; g < count; ++g) {
        cleared[g] = batches[g];
        if (cleared[g].active_bits)
            cleared[g].active_bits &= ~relief_shadow_clear8(&s->maxmip, &s->heights, &batches[g]);
    }
    batches = cleared;
    if (s->heights.clamp) {
        for (int g = 0; g < count; ++g)
            out_blocked[g] =
                batches[g].active_bits
                    ? relief_shadow_search8(&s->heights, &batches[g], CLAMP_SHADOW_STEPS)
                    : 0;
        return;
    }
    if (s->power_of_two) {
        /* From the hit (s = 0, depth d) up to the mesh (s = 1, depth 0). */
        float w = (float)s->heights.width, h = (float)s->heights.height;
        exact_rays8 r[2];
        int active[2] = {0, 0}, probed[2] = {0, 0};
        v8f t[2];
        memset(r, 0, sizeof r);
        for (int g = 0; g < count; ++g) {
            const relief_shadow_batch *b = &batches[g];
            r[g] = (exact_rays8){.x0 = b->x - w * v8_floor(b->x * (1.0f / w)),
                                 .y0 = b->y - h * v8_floor(b->y * (1.0f / h)),
                                 .xd = b->xd,
                                 .yd = b->yd,
                                 .c0 = b->d, /* d (1 - s) + bulge s (1 - s) */
                                 .c1 = b->bulge - b->d,
                                 .c2 = -b->bulge,
                                 .t0 = v8_splat(0.0f),
                                 .t1 = v8_splat(1.0f),
                                 .bias = RELIEF_SHADOW_BIAS};
            /* A probe below the surface proves the light blocked (that point of the light
             * ray is inside the relief); only the other lanes need the traversal. */
            int blocked = 0;
            for (int p = 1; p <= 3 && (b->active_bits & ~blocked); ++p) {
                float sp = 0.25f * (float)p;
                v8f f = (b->d + b->bulge * sp) * (1.0f - sp) - 1.0f +
                        relief_sample8(&s->heights, b->x + b->xd * sp, b->y + b->yd * sp);
                blocked |= v8_mask_bits(f > RELIEF_SHADOW_BIAS) & b->active_bits;
            }
            probed[g] = blocked;
            active[g] = b->active_bits & ~blocked;
        }
        /* No cone steps: a shadow ray starts on the surface, where the cone of the cell under it
         * allows no step (with them, more instructions on bumps-sphere and
         * bricks-plane). */
        trace8x2(s, r, active, count, false, t, out_blocked);
        for (int g = 0; g < count; ++g) out_blocked[g] |= probed[g];
        return;
    }
    for (int g = 0; g < count; ++g) {
        const relief_shadow_batch *b = &batches[g];
        int blocked = 0;
        for (int k = 0; k < b->count; ++k) {
            if (!(b->active_bits >> k & 1)) continue;
            exact_ray r = {
                b->x[k],      b->y[k], b->xd[k], b->yd[k],          b->d[k], b->bulge[k] - b->d[k],
                -b->bulge[k], 0.0,     1.0,      RELIEF_SHADOW_BIAS};
            double t;
            if (trace_any(s, &r, &t)) blocked |= 1 << k;
        }
        out_blocked[g] = blocked;
    }
}

static void release(void *state) {
    exact_state *s = state;
    if (!s) return;
    relief_heights_deinit(&s->heights);
    free(s->cone_codes);
    meso_minmax_pyramid_destroy(s->pyramid);
    relief_shell_destroy(s->shell);
    free(s);
}

/* The cone map's slopes as bytes, each rounded up with the tracer's arithmetic
 * ((code / 255)^2 * scale >= slope), so a step is never longer than the map allows. */
static meso_result cone_codes_init(meso_context *ctx, const meso_object *object,
                                   const meso_cone_map *cones, exact_state *s) {
    size_t n = (size_t)cones->width * (size_t)cones->height;
    float scale = 0.0f;
    for (size_t k = 0; k < n; ++k)
        scale = cones->cells[2 * k + 1] > scale ? cones->cells[2 * k + 1] : scale;
    s->cone_codes = calloc(n + 3, 1);
    if (!s->cone_codes)
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", object->name);
    s->cone_scale = scale;
    for (size_t k = 0; k < n; ++k) {
        float slope = cones->cells[2 * k + 1];
        int code = scale > 0.0f ? (int)ceil(sqrt((double)slope / (double)scale) * 255.0) : 0;
        code = code < 0 ? 0 : (code > 255 ? 255 : code);
        for (;;) {
            float q = (float)code * (1.0f / 255.0f);
            if (q * q * scale >= slope || code == 255) break;
            ++code;
        }
        s->cone_codes[k] = (uint8_t)code;
    }
    return MESO_OK;
}

static meso_result prepare(meso_context *ctx, const meso_scene *scene, const meso_object *object,
                           void **out_state) {
    *out_state = NULL;
    exact_options options;
    meso_result r = meso_technique_options_read(ctx, scene, object,
                                                &meso_technique_relief_exact.info, &options);
    if (r != MESO_OK) return r;
    exact_state *s = calloc(1, sizeof *s);
    if (!s) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", object->name);
    if ((r = relief_heights_init(ctx, object, &s->heights)) != MESO_OK ||
        (r = meso_minmax_pyramid_bake(ctx, object->mesostructure.height_field, &s->pyramid)) !=
            MESO_OK)
        goto fail;
    int w = s->heights.width, h = s->heights.height;
    s->power_of_two = (w & (w - 1)) == 0 && (h & (h - 1)) == 0;
    if (s->power_of_two && !s->heights.clamp) {
        meso_cone_map *cones = NULL;
        if ((r = meso_cone_map_bake_cached(ctx, object->mesostructure.height_field, s->pyramid,
                                           &cones)) != MESO_OK)
            goto fail;
        r = cone_codes_init(ctx, object, cones, s);
        meso_cone_map_destroy(cones);
        if (r != MESO_OK) goto fail;
    }
    for (int l = 0; l < s->pyramid->num_levels; ++l) {
        s->level_offset[l] = (int32_t)(s->pyramid->levels[l].max - s->pyramid->block);
    }
    relief_maxmip_init(s->pyramid, &s->maxmip);
    s->params.shadows = options.shadows;
    s->params.silhouettes = options.silhouettes;
    s->shadows = options.shadows;
    if ((r = relief_domain_init(ctx, object, &s->params.domain)) != MESO_OK ||
        (options.shell &&
         (r = relief_shell_create(ctx, object, "relief_exact", &s->shell)) != MESO_OK))
        goto fail;
    *out_state = s;
    return MESO_OK;
fail:
    release(s);
    return r;
}

/* ---- On the shell (relief_shell.h): the traversal on each prism's stretch ----------------- */

static bool shell_inside(const void *user, float x, float y, float d, float *out_f) {
    return relief_shell_heights_inside(&((const exact_state *)user)->heights, x, y, d, out_f);
}

static int shell_inside8(const void *user, const v8f *x, const v8f *y, const v8f *d, v8f *out_f) {
    return relief_shell_heights_inside8(&((const exact_state *)user)->heights, *x, *y, *d, out_f);
}

/* Tevs et al.'s traversal (trace_any) of a stretch: depth d0 + s dd, s in [0, 1], the start
 * wrapped into the first tile as view_rays does. */
static bool shell_trace(const void *user, const relief_shell_stretch *st, float bias,
                        float *out_s) {
    const exact_state *s = user;
    double w = s->heights.width, h = s->heights.height;
    exact_ray r = {st->x0 - w * floor(st->x0 / w),
                   st->y0 - h * floor(st->y0 / h),
                   st->xd,
                   st->yd,
                   st->d0,
                   st->dd,
                   0.0,
                   0.0,
                   1.0,
                   bias};
    double t;
    if (!trace_any(s, &r, &t)) return false;
    *out_s = (float)t;
    return true;
}

static meso_vec3 shell_normal(const void *user, float x, float y, float d, bool upward,
                              const relief_shell_frame *f) {
    (void)d, (void)upward;
    return relief_shell_heights_normal(&((const exact_state *)user)->heights, x, y, f);
}

/* Clamp-to-edge fields: relief's search with CLAMP_* steps, as off the shell. */
static relief_shell_search shell_search(const exact_state *s) {
    return (relief_shell_search){.user = s,
                                 .width = s->heights.width,
                                 .height = s->heights.height,
                                 .inside = shell_inside,
                                 .inside8 = shell_inside8,
                                 .trace = s->heights.clamp ? NULL : shell_trace,
                                 .normal = shell_normal,
                                 .linear_steps = CLAMP_LINEAR_STEPS,
                                 .binary_steps = CLAMP_BINARY_STEPS,
                                 .shadow_steps = CLAMP_SHADOW_STEPS,
                                 .shadows = s->shadows,
                                 .floor_solid = true,
                                 .shadow_bias = RELIEF_SHADOW_BIAS};
}

static meso_result geometry(meso_context *ctx, void *state, const meso_frame *frame,
                            const meso_mesh **out_mesh) {
    (void)ctx;
    exact_state *s = state;
    *out_mesh = s->shell ? relief_shell_geometry(s->shell, frame) : NULL;
    return MESO_OK;
}

__attribute__((always_inline)) static inline void
shade_either(const exact_state *s, const meso_frame *frame, const meso_object *object,
             meso_fragment *fragments, meso_fragment_block *block, size_t count) {
    relief_shell_search q = shell_search(s);
    relief_tracer tracer = {s, search, shadow, NULL};
    relief_shade_shell_or_ray(s->shell, &q, &s->heights, &tracer, s->params, frame, object,
                              fragments, block, count);
}

static void shade(const void *state, const meso_frame *frame, const meso_object *object,
                  meso_fragment *fragments, size_t count) {
    shade_either(state, frame, object, fragments, NULL, count);
}

/* The rasterizer's blocks straight to the shared loop (no adapter copies); the same images
 * as shade. */
static void shade_block(const void *state, const meso_frame *frame, const meso_object *object,
                        meso_fragment_block *block) {
    shade_either(state, frame, object, NULL, block, block->count);
}

static size_t memory(const void *state) {
    const exact_state *s = state;
    if (!s) return 0;
    size_t codes = s->cone_codes ? (size_t)s->heights.width * (size_t)s->heights.height + 3 : 0;
    return relief_heights_memory(&s->heights) + meso_minmax_pyramid_memory(s->pyramid) + codes +
           relief_shell_memory(s->shell);
}

const meso_technique meso_technique_relief_exact = {
    .info = {.name = "relief_exact",
             .summary = "relief mapping traced exactly through a maximum mip-map",
             .paper = "Tevs, Ihrke & Seidel 2008 (beyond the papers); Policarpo & Oliveira 2006",
             .kind = MESO_TECHNIQUE_PER_PIXEL,
             .accepts = MESO_TECHNIQUE_ACCEPTS_HEIGHT_FIELD,
             .options = exact_option_table,
             .num_options = MESO_OPTION_COUNT(exact_option_table)},
    .prepare = prepare,
    .release = release,
    .geometry = geometry,
    .shade = shade,
    .shade_block = shade_block,
    .memory = memory,
};
