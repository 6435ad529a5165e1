/* Procedural solids: signed distance bounds over texture space (u, v, w) (docs/mesostructure.md).
 *
 * Every kind is modelled in "cell space" (x, y, z) = (count u, count v, depth_cells w): one
 * repeat of the pattern is a unit cell laterally and the slab is depth_cells cells deep, so
 * threads and links have round cross-sections there. A function f is built whose zero set is
 * the surface and whose Lipschitz constant in cell space is at most `lipschitz`; the map from
 * (u, v, w) to cell space stretches lengths by at most max(count, depth_cells), so
 *     d(u, v, w) = f / (lipschitz * max(count, depth_cells))
 * has Lipschitz constant <= 1 and never exceeds the true distance: sphere tracing with steps
 * of d cannot step through material (GDM §4 traces the volume the same way, by ray segments).
 * Candidates near the point are evaluated explicitly; every omitted repeat is farther than a
 * constant `cap` (in f's units), and min(f, cap) keeps the bound valid.
 */
#include <stdlib.h>
#include <string.h>

#include "mesostructure_internal.h"
#include "meso/runtime.h"

/* ---- Kinds and defaults ------------------------------------------------------------------- */

#define SOLID_LAST_KIND MESO_SOLID_SLAB

static const char *const solid_kind_names[] = {
    [MESO_SOLID_WEAVE] = "weave",   [MESO_SOLID_CHAIN] = "chain", [MESO_SOLID_GRID] = "grid",
    [MESO_SOLID_SQUAMA] = "squama", [MESO_SOLID_HELIX] = "helix", [MESO_SOLID_SLAB] = "slab",
};

/* Per kind: default count, default thickness, largest thickness that keeps the shape valid
 * (threads/links of neighbouring cells must not merge), whether count must be even (patterns
 * that alternate from cell to cell). */
static const struct {
    int count;
    float thickness, max_thickness;
    bool even;
} solid_kinds[] = {
    [MESO_SOLID_WEAVE] = {2, 0.3f, 0.45f, true},   [MESO_SOLID_CHAIN] = {2, 0.08f, 0.14f, true},
    [MESO_SOLID_GRID] = {4, 0.12f, 0.4f, false},   [MESO_SOLID_SQUAMA] = {4, 0.08f, 0.2f, true},
    [MESO_SOLID_HELIX] = {2, 0.08f, 0.16f, false}, [MESO_SOLID_SLAB] = {1, 0.5f, 1.0f, false},
};

bool meso_solid_kind_from_name(const char *name, meso_solid_kind *out_kind) {
    for (int k = MESO_SOLID_WEAVE; k <= SOLID_LAST_KIND; k++)
        if (name && strcmp(name, solid_kind_names[k]) == 0) {
            *out_kind = (meso_solid_kind)k;
            return true;
        }
    return false;
}

const char *meso_solid_kind_name(meso_solid_kind kind) {
    if (kind == MESO_SOLID_DEFAULT) kind = MESO_SOLID_WEAVE;
    if (kind == MESO_SOLID_MESH) return "mesh";
    if (kind < MESO_SOLID_WEAVE || kind > SOLID_LAST_KIND) return "unknown";
    return solid_kind_names[kind];
}

meso_solid_desc meso_solid_desc_defaults(const meso_solid_desc *desc) {
    meso_solid_desc d = desc ? *desc : (meso_solid_desc){0};
    if (d.kind == MESO_SOLID_DEFAULT) d.kind = MESO_SOLID_WEAVE;
    if (d.kind < MESO_SOLID_WEAVE || d.kind > SOLID_LAST_KIND) return d;
    if (d.count == 0) d.count = solid_kinds[d.kind].count;
    if (d.thickness == 0.0f) d.thickness = solid_kinds[d.kind].thickness;
    return d;
}

/* ---- Shapes in cell space ----------------------------------------------------------------- */

/* fminf and fmaxf with libm's results, NaNs included (glibc's x86-64 minss/maxss: the second
 * operand when equal, the other one when one is a NaN), inline: without -ffinite-math-only
 * each is a call into libm, and meso_solid_distance takes several an evaluation (a tenth of
 * the weave's; gdm evaluates millions a frame, docs/techniques/gdm.md). gdm_lookup.h has the
 * same pair, tested against libm. */
static inline float solid_fminf(float a, float b) { return a < b || b != b ? a : b; }
static inline float solid_fmaxf(float a, float b) { return a > b || b != b ? a : b; }

static float length2(float x, float y) { return sqrtf(x * x + y * y); }
static float length3(float x, float y, float z) { return sqrtf(x * x + y * y + z * z); }

/* Plain weave: threads along x (one per row) and along y (one per column), circular
 * cross-section of radius r at the same x (resp. y), centres undulating in z with period two
 * cells so each thread passes over one crossing and under the next. The undulation shears the
 * tube: |grad f| <= sqrt(1 + (A pi)^2), accounted for in `scale`. */
static float weave_distance(const meso_solid *s, float x, float y, float z) {
    float r = s->desc.thickness, zc = 0.5f * s->depth_cells, a = s->amplitude;
    float best = s->cap;
    /* The two nearest rows (threads along x) and columns (threads along y); any other thread
     * is at least one cell away laterally: f >= 1 - r >= cap. */
    float row = floorf(y), column = floorf(x);
    float rows[2] = {row, y - row < 0.5f ? row - 1.0f : row + 1.0f};
    float columns[2] = {column, x - column < 0.5f ? column - 1.0f : column + 1.0f};
    for (int k = 0; k < 2; k++) {
        /* Thread along x in row k is over (small z) at columns where column - row is even. */
        float centre = zc - a * cosf(MESO_PI * (x - 0.5f - rows[k]));
        best = solid_fminf(best, length2(y - (rows[k] + 0.5f), z - centre) - r);
        float centre_v = zc + a * cosf(MESO_PI * (y - 0.5f - columns[k]));
        best = solid_fminf(best, length2(x - (columns[k] + 0.5f), z - centre_v) - r);
    }
    return best;
}

/* A chain link: a stadium (two half circles of radius `major` joined by straight parts of
 * half-length `half_length` along a) swept by a circle of radius r; the ring lies in the plane
 * spanned by a (along the chain) and b. Exact distance. */
static float link_distance(float along, float across, float normal, float half_length, float major,
                           float r) {
    float q = solid_fmaxf(fabsf(along) - half_length, 0.0f);
    return length2(length2(q, across) - major, normal) - r;
}

/* Chains along x, one per row: link i centred at (i + 0.5, row + 0.5, depth/2), even links
 * lying flat (ring in the x-y plane), odd links upright (ring in the x-z plane), each upright
 * link threaded through its flat neighbours. */
static float chain_distance(const meso_solid *s, float x, float y, float z) {
    float r = s->desc.thickness, zc = 0.5f * s->depth_cells;
    float best = s->cap;
    float row = floorf(y), link = floorf(x);
    float rows[2] = {row, y - row < 0.5f ? row - 1.0f : row + 1.0f};
    for (int k = 0; k < 2; k++)
        for (int di = -1; di <= 1; di++) {
            float i = link + (float)di;
            float along = x - (i + 0.5f), across = y - (rows[k] + 0.5f), normal = z - zc;
            bool flat = (wrap_index((int)i, 2) == 0);
            float d = flat ? link_distance(along, across, normal, s->half_length, s->major, r)
                           : link_distance(along, normal, across, s->half_length, s->major, r);
            best = solid_fminf(best, d);
        }
    return best;
}

/* Exact distance to an axis-aligned box of half-extents (hx, hy, hz) centred at the origin. */
static float box_distance(float x, float y, float z, float hx, float hy, float hz) {
    float qx = fabsf(x) - hx, qy = fabsf(y) - hy, qz = fabsf(z) - hz;
    float outside = length3(solid_fmaxf(qx, 0.0f), solid_fmaxf(qy, 0.0f), solid_fmaxf(qz, 0.0f));
    return outside + solid_fminf(solid_fmaxf(qx, solid_fmaxf(qy, qz)), 0.0f);
}

/* A two-level lattice (GDM Fig. 9a's grid): bars along x on the cell borders in the upper
 * part of the slab, bars along y in the lower part, overlapping in the middle so they join.
 * Looking down, each cell has a square hole through the slab. */
static float grid_distance(const meso_solid *s, float x, float y, float z) {
    float t = s->desc.thickness, depth = s->depth_cells;
    float dy = y - floorf(y + 0.5f), dx = x - floorf(x + 0.5f); /* to the nearest border line */
    float upper = box_distance(0.0f, dy, z - 0.275f * depth, 1e30f, t, 0.275f * depth);
    float lower = box_distance(dx, 0.0f, z - 0.725f * depth, t, 1e30f, 0.275f * depth);
    return solid_fminf(upper, lower);
}

/* Fish scales: rows of discs (rounded flat cylinders) offset by half a cell on odd rows, each
 * tilted about x so its front edge (toward -y) rises toward the surface and overhangs the back
 * of the scale in front of it, whose back is tucked under. Rotation keeps distances exact. */
static float squama_distance(const meso_solid *s, float x, float y, float z) {
    float half_thickness = s->desc.thickness, radius = s->radius;
    float round = 0.5f * half_thickness, zc = 0.5f * s->depth_cells;
    float best = s->cap;
    float row = floorf(y);
    for (int dj = -1; dj <= 1; dj++) {
        float j = row + (float)dj;
        float shift = wrap_index((int)j, 2) ? 0.5f : 0.0f;
        float column = floorf(x - shift);
        for (int di = -1; di <= 1; di++) {
            float cx = column + (float)di + 0.5f + shift, cy = j + 0.5f;
            float px = x - cx, py = y - cy, pz = z - zc;
            /* Into the disc's frame: rotate (y, z) so the disc's normal becomes the z axis;
             * the front (-y) lies at smaller z, nearer the surface. */
            float ly = s->tilt_cos * py + s->tilt_sin * pz;
            float lz = s->tilt_cos * pz - s->tilt_sin * py;
            float radial = length2(px, ly) - radius + round;
            float axial = fabsf(lz) - half_thickness + round;
            float d = solid_fminf(solid_fmaxf(radial, axial), 0.0f) +
                      length2(solid_fmaxf(radial, 0.0f), solid_fmaxf(axial, 0.0f)) - round;
            best = solid_fminf(best, d);
        }
    }
    return best;
}

/* A double helix along x in each row: two threads of radius r circling the row's axis at
 * radius `major`, half a turn apart, one turn per cell. Distance in the cross-section at the
 * same x; |grad f| <= sqrt(1 + (2 pi major)^2), accounted for in `scale`. */
static float helix_distance(const meso_solid *s, float x, float y, float z) {
    float r = s->desc.thickness, zc = 0.5f * s->depth_cells, major = s->major;
    float best = s->cap;
    float row = floorf(y);
    float rows[2] = {row, y - row < 0.5f ? row - 1.0f : row + 1.0f};
    float angle = 2.0f * MESO_PI * x;
    float c = cosf(angle), sn = sinf(angle);
    for (int k = 0; k < 2; k++) {
        float py = y - (rows[k] + 0.5f), pz = z - zc;
        best = solid_fminf(best, length2(py - major * c, pz - major * sn) - r);
        best = solid_fminf(best, length2(py + major * c, pz + major * sn) - r);
    }
    return best;
}

/* ---- Public ------------------------------------------------------------------------------- */

meso_result meso_solid_create_procedural(meso_context *ctx, const meso_solid_desc *desc,
                                         meso_solid **out_solid) {
    *out_solid = NULL;
    meso_solid_desc d = meso_solid_desc_defaults(desc);
    if (d.kind < MESO_SOLID_WEAVE || d.kind > SOLID_LAST_KIND)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "procedural solid: kind: unknown kind %d", (int)d.kind);
    const char *name = meso_solid_kind_name(d.kind);
    if (d.count < 1 || d.count > 256)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: count: %d is not in [1, 256]",
                              name, d.count);
    if (solid_kinds[d.kind].even && (d.count & 1))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: count: %d must be even for the pattern to tile", name, d.count);
    float max_thickness = solid_kinds[d.kind].max_thickness;
    if (!(d.thickness > 0.0f && d.thickness <= max_thickness))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: thickness: %g is not in (0, %g]", name, (double)d.thickness,
                              (double)max_thickness);
    meso_solid *s = calloc(1, sizeof(*s));
    if (!s) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", name);
    s->desc = d;
    float r = d.thickness, lipschitz = 1.0f;
    switch (d.kind) {
    case MESO_SOLID_WEAVE:
        /* Centres r above and below mid-depth: the threads touch at crossings. */
        s->amplitude = r;
        s->depth_cells = 4.0f * r + 0.1f;
        lipschitz = sqrtf(1.0f + (MESO_PI * s->amplitude) * (MESO_PI * s->amplitude));
        s->cap = 1.0f - r;
        break;
    case MESO_SOLID_CHAIN:
        /* The ring reaches 0.46 cells from the chain's axis, clear of the next chain. Each
         * link's centreline reaches 0.55 + r past its centre, so the end of an upright link
         * passes through the hole of the flat one before it with 0.1 cells between the tubes'
         * surfaces; major > 2r keeps each hole wider than the tube through it. */
        s->major = 0.46f - r;
        s->half_length = solid_fmaxf(0.5f + r + 0.05f - s->major, 0.0f);
        s->depth_cells = 2.0f * (s->major + r) + 0.04f;
        /* Omitted links: one row away (>= 1 - 0.46) or two links away (>= 1.5 - reach). */
        s->cap = solid_fminf(0.54f, 1.5f - (s->half_length + s->major + r));
        break;
    case MESO_SOLID_GRID:
        s->depth_cells = 0.5f;
        s->cap = 1e30f;
        break;
    case MESO_SOLID_SQUAMA: {
        float tilt = 20.0f * MESO_PI / 180.0f;
        s->tilt_cos = cosf(tilt);
        s->tilt_sin = sinf(tilt);
        s->radius = 0.62f;
        s->depth_cells = 2.0f * (s->radius * s->tilt_sin + r * s->tilt_cos) + 0.04f;
        /* Omitted scales are >= 1.5 cells away laterally (two rows or columns). */
        s->cap = 1.5f - s->radius;
        break;
    }
    case MESO_SOLID_HELIX:
        s->major = 0.25f;
        s->depth_cells = 2.0f * (s->major + r) + 0.04f;
        lipschitz = sqrtf(1.0f + (2.0f * MESO_PI * s->major) * (2.0f * MESO_PI * s->major));
        s->cap = 1.0f - (s->major + r);
        break;
    case MESO_SOLID_SLAB:
        s->depth_cells = 1.0f;
        s->cap = 1e30f;
        break;
    default:
        break;
    }
    s->scale = 1.0f / (lipschitz * solid_fmaxf((float)d.count, s->depth_cells));
    *out_solid = s;
    return MESO_OK;
}

void meso_solid_destroy(meso_solid *solid) {
    if (!solid) return;
    free(solid->grid);
    free(solid->model_uvw);
    free(solid->model_indices);
    free(solid);
}

meso_solid_desc meso_solid_get_desc(const meso_solid *solid) { return solid->desc; }

meso_solid_shape meso_solid_get_shape(const meso_solid *solid) {
    return (meso_solid_shape){.desc = solid->desc,
                              .depth_cells = solid->depth_cells,
                              .scale = solid->scale,
                              .cap = solid->cap,
                              .amplitude = solid->amplitude,
                              .major = solid->major,
                              .half_length = solid->half_length,
                              .tilt_cos = solid->tilt_cos,
                              .tilt_sin = solid->tilt_sin,
                              .radius = solid->radius,
                              .grid = solid->grid,
                              .grid_side = solid->grid_side,
                              .grid_clamped = solid->grid_clamped};
}

uint64_t meso_solid_hash(const meso_solid *solid) {
    if (solid->desc.kind == MESO_SOLID_MESH) return solid->grid_hash;
    /* Version the shapes: a change to a generator must change every cached bake's key. */
    const uint32_t version = 1;
    uint64_t h = meso_hash64(&version, sizeof(version), MESO_HASH_SEED);
    int32_t ints[2] = {(int32_t)solid->desc.kind, solid->desc.count};
    h = meso_hash64(ints, sizeof(ints), h);
    return meso_hash64(&solid->desc.thickness, sizeof(float), h);
}

float meso_solid_distance(const meso_solid *solid, meso_vec3 uvw) {
    float count = (float)solid->desc.count;
    float x = fract_tile(uvw.x) * count, y = fract_tile(uvw.y) * count;
    float z = uvw.z * solid->depth_cells;
    float f;
    switch (solid->desc.kind) {
    case MESO_SOLID_WEAVE:
        f = weave_distance(solid, x, y, z);
        break;
    case MESO_SOLID_CHAIN:
        f = chain_distance(solid, x, y, z);
        break;
    case MESO_SOLID_GRID:
        f = grid_distance(solid, x, y, z);
        break;
    case MESO_SOLID_SQUAMA:
        f = squama_distance(solid, x, y, z);
        break;
    case MESO_SOLID_HELIX:
        f = helix_distance(solid, x, y, z);
        break;
    case MESO_SOLID_MESH:
        return meso_solid_grid_distance(solid, uvw);
    case MESO_SOLID_SLAB:
        /* exact: the plane w = 1 - thickness, solid below (the test of relief_layers against
         * relief on the height field h = thickness) */
        f = (1.0f - solid->desc.thickness) * solid->depth_cells - z;
        break;
    default:
        f = 1.0f;
        break;
    }
    /* Intersect with the slab 0 <= w <= 1: empty above the mesh and below -depth. */
    float slab = solid_fmaxf(-z, z - solid->depth_cells);
    return solid_fmaxf(f, slab) * solid->scale;
}

meso_vec3 meso_solid_gradient(const meso_solid *solid, meso_vec3 uvw) {
    const float h = 1e-3f;
    float gx = meso_solid_distance(solid, (meso_vec3){uvw.x + h, uvw.y, uvw.z}) -
               meso_solid_distance(solid, (meso_vec3){uvw.x - h, uvw.y, uvw.z});
    float gy = meso_solid_distance(solid, (meso_vec3){uvw.x, uvw.y + h, uvw.z}) -
               meso_solid_distance(solid, (meso_vec3){uvw.x, uvw.y - h, uvw.z});
    float gz = meso_solid_distance(solid, (meso_vec3){uvw.x, uvw.y, uvw.z + h}) -
               meso_solid_distance(solid, (meso_vec3){uvw.x, uvw.y, uvw.z - h});
    float inv = 1.0f / (2.0f * h);
    return (meso_vec3){gx * inv, gy * inv, gz * inv};
}
