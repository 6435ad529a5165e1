/* Summed-area table of a height field: the "Local Area Average Height Test" of Doggett &
 * Hirche 2000 reads box averages from it in constant time (Crow 1984). */
#include "meso/bake_sat.h"
#include "meso/runtime.h"

#include <math.h>
#include <stdlib.h>

meso_result meso_sat_bake(meso_context *ctx, const meso_heightfield *heightfield,
                          meso_sat **out_sat) {
    if (out_sat) *out_sat = NULL;
    if (!out_sat || !heightfield || !heightfield->heights)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "summed-area table: %s",
                              "height field is NULL");
    int w = heightfield->width, h = heightfield->height;
    if (w <= 0 || h <= 0)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "summed-area table: size %d x %d is empty", w, h);
    if ((uint64_t)w * (uint64_t)h > MESO_SAT_MAX_TEXELS)
        return meso_log_error(ctx, MESO_ERROR_LIMIT,
                              "summed-area table: %d x %d texels exceed the limit %u", w, h,
                              MESO_SAT_MAX_TEXELS);
    meso_sat *sat = calloc(1, sizeof(*sat));
    size_t stride = (size_t)w + 1;
    double *sums = calloc(stride * ((size_t)h + 1), sizeof(double));
    if (!sat || !sums) {
        free(sat);
        free(sums);
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "summed-area table: %d x %d", w, h);
    }
    for (int j = 0; j < h; j++) {
        /* row prefix added to the row above: one pass, fixed order (deterministic) */
        double row = 0.0;
        const float *texels = heightfield->heights + (size_t)j * (size_t)w;
        double *above = sums + (size_t)j * stride, *here = sums + ((size_t)j + 1) * stride;
        for (int i = 0; i < w; i++) {
            row += (double)texels[i];
            here[i + 1] = above[i + 1] + row;
        }
    }
    sat->width = w;
    sat->height = h;
    sat->wrap = heightfield->wrap == MESO_WRAP_CLAMP ? MESO_WRAP_CLAMP : MESO_WRAP_REPEAT;
    sat->sums = sums;
    *out_sat = sat;
    return MESO_OK;
}

void meso_sat_destroy(meso_sat *sat) {
    if (!sat) return;
    free(sat->sums);
    free(sat);
}

static double table(const meso_sat *sat, int i, int j) {
    return sat->sums[(size_t)j * ((size_t)sat->width + 1) + (size_t)i];
}

/* floor division and its remainder in [0, n) */
static void split_period(int x, int n, long long *quotient, int *remainder) {
    long long q = x / n, r = x % n;
    if (r < 0) {
        r += n;
        q -= 1;
    }
    *quotient = q;
    *remainder = (int)r;
}

/* Sum over texels x < i, y < j of the periodic extension, counted from (0, 0): with i = qi W + ri,
 * j = qj H + rj the rectangle is qi x qj whole tiles, qi strips of rj rows, qj strips of ri
 * columns and one ri x rj corner. Valid for negative i, j too (signed counts). */
static double periodic_prefix(const meso_sat *sat, int i, int j) {
    long long qi, qj;
    int ri, rj;
    split_period(i, sat->width, &qi, &ri);
    split_period(j, sat->height, &qj, &rj);
    double total = table(sat, sat->width, sat->height);
    return (double)qi * (double)qj * total + (double)qi * table(sat, sat->width, rj) +
           (double)qj * table(sat, ri, sat->height) + table(sat, ri, rj);
}

static int clampi(int x, int lo, int hi) { return x < lo ? lo : (x > hi ? hi : x); }

/* A clamp-to-edge table's box cut to the table; false: nothing of it is left. */
static bool clamp_box(const meso_sat *sat, int *i0, int *j0, int *i1, int *j1) {
    *i0 = clampi(*i0, 0, sat->width);
    *i1 = clampi(*i1, 0, sat->width);
    *j0 = clampi(*j0, 0, sat->height);
    *j1 = clampi(*j1, 0, sat->height);
    return *i1 > *i0 && *j1 > *j0;
}

double meso_sat_box_sum(const meso_sat *sat, int i0, int j0, int i1, int j1) {
    if (i1 <= i0 || j1 <= j0) return 0.0;
    if (sat->wrap == MESO_WRAP_CLAMP) {
        if (!clamp_box(sat, &i0, &j0, &i1, &j1)) return 0.0;
        return table(sat, i1, j1) - table(sat, i0, j1) - table(sat, i1, j0) + table(sat, i0, j0);
    }
    if (i0 >= 0 && j0 >= 0 && i1 <= sat->width && j1 <= sat->height) /* inside: no wrapping */
        return table(sat, i1, j1) - table(sat, i0, j1) - table(sat, i1, j0) + table(sat, i0, j0);
    return periodic_prefix(sat, i1, j1) - periodic_prefix(sat, i0, j1) -
           periodic_prefix(sat, i1, j0) + periodic_prefix(sat, i0, j0);
}

double meso_sat_box_count(const meso_sat *sat, int i0, int j0, int i1, int j1) {
    if (i1 <= i0 || j1 <= j0) return 0.0;
    if (sat->wrap == MESO_WRAP_CLAMP) {
        if (!clamp_box(sat, &i0, &j0, &i1, &j1)) return 0.0;
    }
    return (double)(i1 - i0) * (double)(j1 - j0);
}

/* Texel indices [*lo, *hi) whose centres (k + 0.5) lie within radius of x, at least the texel
 * containing x. Coordinates are limited so that int arithmetic cannot overflow. */
static void box_range(float x, float radius, int *lo, int *hi) {
    x = meso_clampf(x, -1.0e8f, 1.0e8f);
    radius = meso_clampf(radius, 0.0f, 1.0e6f);
    int a = (int)ceilf(x - radius - 0.5f), b = (int)floorf(x + radius - 0.5f) + 1;
    if (b <= a) {
        a = (int)floorf(x);
        b = a + 1;
    }
    *lo = a;
    *hi = b;
}

/* box_range for x and radius its clamps leave unchanged: the same indices without them */
static inline void box_range_unclamped(float x, float radius, int *lo, int *hi) {
    int a = (int)ceilf(x - radius - 0.5f), b = (int)floorf(x + radius - 0.5f) + 1;
    if (b <= a) {
        a = (int)floorf(x);
        b = a + 1;
    }
    *lo = a;
    *hi = b;
}

float meso_sat_box_average(const meso_sat *sat, float u, float v, float radius) {
    int i0, i1, j0, j1;
    /* texel space: column x = u W, row y = (1 - v) H (row 0 at the top, docs/design.md) */
    float x = u * (float)sat->width, y = (1.0f - v) * (float)sat->height;
    /* The common case, a point of the field and a box inside it (the tessellator's area test
     * calls this three times an edge): box_range's clamps change nothing, neither wrap mode
     * moves or clips the box, and the sum and the count are the general path's, in its order
     * (the same bits, one table read a corner instead of the calls below). */
    if (x >= 0.0f && x <= (float)sat->width && y >= 0.0f && y <= (float)sat->height &&
        radius >= 0.0f && radius <= 1.0e6f) {
        box_range_unclamped(x, radius, &i0, &i1);
        box_range_unclamped(y, radius, &j0, &j1);
        if (i0 >= 0 && j0 >= 0 && i1 <= sat->width && j1 <= sat->height) {
            double sum =
                table(sat, i1, j1) - table(sat, i0, j1) - table(sat, i1, j0) + table(sat, i0, j0);
            return (float)(sum / ((double)(i1 - i0) * (double)(j1 - j0)));
        }
    }
    if (!isfinite(u) || !isfinite(v)) return 0.0f;
    box_range(x, radius, &i0, &i1);
    box_range(y, radius, &j0, &j1);
    double count = meso_sat_box_count(sat, i0, j0, i1, j1);
    if (count <= 0.0) {
        /* clamp mode, box entirely outside: the nearest edge texel */
        i0 = clampi(i0, 0, sat->width - 1);
        j0 = clampi(j0, 0, sat->height - 1);
        i1 = i0 + 1;
        j1 = j0 + 1;
        count = 1.0;
    }
    return (float)(meso_sat_box_sum(sat, i0, j0, i1, j1) / count);
}
