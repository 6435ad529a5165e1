/* View-dependent displacement maps (Wang et al. 2003): bake (§3.1, Appendix), MVM and SVD
 * compression (§3.3), lookups, bake files. Conventions in include/meso/bake_vdm.h. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake_internal.h"
#include "meso/bake_cache.h"
#include "meso/runtime.h"

#define HALF_PI (0.5 * MESO_PI_D)
#define TWO_PI (2.0 * MESO_PI_D)

struct meso_vdm {
    meso_vdm_desc desc; /* heightfield NULL */
    uint64_t source_hash;
    meso_wrap wrap;
    int num_weights;        /* max(k, m) */
    int num_sv;             /* singular values kept */
    float *weights;         /* [rows][num_weights] */
    float *eigen_vdm;       /* [k][n_c][n_theta] */
    float *eigen_mvm;       /* [m][n_c] */
    float *singular;        /* [num_sv] */
    float *raw;             /* [rows][columns] or NULL */
    uint16_t *weights_half; /* W as IEEE halves (the values of `weights`) unless float_weights */
    meso_vdm_compression compression;
};

meso_vdm_desc meso_vdm_desc_defaults(const meso_vdm_desc *desc) {
    meso_vdm_desc d = desc ? *desc : (meso_vdm_desc){0};
    if (d.depth == 0.0f) d.depth = 0.05f;
    if (d.width == 0) d.width = 128;
    if (d.height == 0) d.height = d.width;
    if (d.num_theta == 0) d.num_theta = 32;
    if (d.num_phi == 0) d.num_phi = 8;
    if (d.num_curvatures == 0) d.num_curvatures = 16;
    if (d.curvature_min == 0.0f && d.curvature_max == 0.0f) {
        d.curvature_min = -2.0f;
        d.curvature_max = 3.0f;
    }
    if (d.step_texels == 0.0f) d.step_texels = 0.5f;
    if (d.vdm_eigenfunctions == 0) d.vdm_eigenfunctions = 8;
    if (d.mvm_eigenfunctions == 0) d.mvm_eigenfunctions = 4;
    return d;
}

static int columns_of(const meso_vdm_desc *d) {
    return d->num_theta * d->num_curvatures + d->num_curvatures;
}
static size_t rows_of(const meso_vdm_desc *d) {
    return (size_t)d->width * (size_t)d->height * (size_t)d->num_phi;
}
static float theta_of(const meso_vdm_desc *d, int t) {
    return (float)(((double)t + 0.5) * HALF_PI / (double)d->num_theta);
}
static float curvature_of(const meso_vdm_desc *d, int k) {
    if (d->num_curvatures == 1) return 0.0f;
    return d->curvature_min +
           (d->curvature_max - d->curvature_min) * (float)k / (float)(d->num_curvatures - 1);
}

/* Validate a filled-in desc; `name` starts the messages. */
static meso_result check_desc(meso_context *ctx, const char *name, const meso_vdm_desc *d) {
#define CHECK(cond, code, ...)                                                                     \
    if (!(cond)) return meso_log_error(ctx, code, __VA_ARGS__)
    CHECK(isfinite(d->depth) && d->depth > 0.0f && d->depth <= 16.0f, MESO_ERROR_INVALID_ARGUMENT,
          "%s: depth: %g must be in (0, 16] tiles", name, d->depth);
    CHECK(d->width >= 1 && d->width <= MESO_VDM_MAX_SIDE, MESO_ERROR_LIMIT,
          "%s: width: %d is outside 1-%d", name, d->width, MESO_VDM_MAX_SIDE);
    CHECK(d->height >= 1 && d->height <= MESO_VDM_MAX_SIDE, MESO_ERROR_LIMIT,
          "%s: height: %d is outside 1-%d", name, d->height, MESO_VDM_MAX_SIDE);
    CHECK(d->num_theta >= 2 && d->num_theta <= MESO_VDM_MAX_THETA, MESO_ERROR_LIMIT,
          "%s: num_theta: %d is outside 2-%d", name, d->num_theta, MESO_VDM_MAX_THETA);
    CHECK(d->num_phi >= 1 && d->num_phi <= MESO_VDM_MAX_PHI, MESO_ERROR_LIMIT,
          "%s: num_phi: %d is outside 1-%d", name, d->num_phi, MESO_VDM_MAX_PHI);
    CHECK(d->num_curvatures >= 1 && d->num_curvatures <= MESO_VDM_MAX_CURVATURES, MESO_ERROR_LIMIT,
          "%s: num_curvatures: %d is outside 1-%d", name, d->num_curvatures,
          MESO_VDM_MAX_CURVATURES);
    CHECK(isfinite(d->curvature_min) && isfinite(d->curvature_max) &&
              d->curvature_min < d->curvature_max && d->curvature_min >= -100.0f &&
              d->curvature_max <= 100.0f,
          MESO_ERROR_INVALID_ARGUMENT,
          "%s: curvature_min %g, curvature_max %g: need min < max within [-100, 100]", name,
          d->curvature_min, d->curvature_max);
    CHECK(isfinite(d->step_texels) && d->step_texels >= 0.05f && d->step_texels <= 4.0f,
          MESO_ERROR_INVALID_ARGUMENT, "%s: step_texels: %g is outside [0.05, 4]", name,
          d->step_texels);
    int columns = columns_of(d);
    size_t rows = rows_of(d);
    int rank = (size_t)columns < rows ? columns : (int)rows;
    CHECK(d->vdm_eigenfunctions >= 1 && d->vdm_eigenfunctions <= MESO_VDM_MAX_EIGEN &&
              d->vdm_eigenfunctions <= rank,
          MESO_ERROR_INVALID_ARGUMENT, "%s: vdm_eigenfunctions: %d is outside 1-%d", name,
          d->vdm_eigenfunctions, rank < MESO_VDM_MAX_EIGEN ? rank : MESO_VDM_MAX_EIGEN);
    CHECK(d->mvm_eigenfunctions >= 1 && d->mvm_eigenfunctions <= MESO_VDM_MAX_EIGEN &&
              d->mvm_eigenfunctions <= rank,
          MESO_ERROR_INVALID_ARGUMENT, "%s: mvm_eigenfunctions: %d is outside 1-%d", name,
          d->mvm_eigenfunctions, rank < MESO_VDM_MAX_EIGEN ? rank : MESO_VDM_MAX_EIGEN);
    CHECK((uint64_t)rows * (uint64_t)columns <= MESO_VDM_MAX_TABLE_ENTRIES, MESO_ERROR_LIMIT,
          "%s: the table of %zu x %d values exceeds the limit %llu", name, rows, columns,
          (unsigned long long)MESO_VDM_MAX_TABLE_ENTRIES);
    CHECK(!d->keep_raw || (uint64_t)rows * (uint64_t)columns <= MESO_VDM_MAX_RAW_FLOATS,
          MESO_ERROR_LIMIT, "%s: keeping the raw table of %zu x %d values exceeds the limit %llu",
          name, rows, columns, (unsigned long long)MESO_VDM_MAX_RAW_FLOATS);
#undef CHECK
    return MESO_OK;
}

uint64_t meso_vdm_cache_key(const meso_vdm_desc *desc) {
    meso_vdm_desc d = meso_vdm_desc_defaults(desc);
    uint64_t h = MESO_HASH_SEED;
    uint64_t source = d.heightfield ? d.heightfield->hash : 0;
    h = meso_hash64(&source, sizeof(source), h);
    int32_t ints[] = {d.width,
                      d.height,
                      d.num_theta,
                      d.num_phi,
                      d.num_curvatures,
                      d.vdm_eigenfunctions,
                      d.mvm_eigenfunctions,
                      d.keep_raw ? 1 : 0,
                      d.float_weights ? 1 : 0,
                      (int32_t)MESO_VDM_KIND_VERSION};
    float floats[] = {d.depth, d.curvature_min, d.curvature_max, d.step_texels};
    h = meso_hash64(ints, sizeof(ints), h);
    h = meso_hash64(floats, sizeof(floats), h);
    return h;
}

/* ---- The bake: ray casting (§3.1) and the curvature dimension (Appendix) ------------------ */

typedef struct bake_job {
    meso_vdm_desc desc;
    const float *grid; /* the height field resampled to width x height */
    bool clamp;
} bake_job;

/* h at texture (u, v) on the resampled grid: bilinear between texel centres, as
 * meso_heightfield_sample. */
static float grid_sample(const bake_job *job, float u, float v) {
    int w = job->desc.width, hgt = job->desc.height;
    float x = u * (float)w - 0.5f, y = (1.0f - v) * (float)hgt - 0.5f;
    float fx = floorf(x), fy = floorf(y);
    float tx = x - fx, ty = y - fy;
    int i0 = (int)fx, j0 = (int)fy, i1 = i0 + 1, j1 = j0 + 1;
    if (job->clamp) {
        i0 = i0 < 0 ? 0 : (i0 >= w ? w - 1 : i0);
        i1 = i1 < 0 ? 0 : (i1 >= w ? w - 1 : i1);
        j0 = j0 < 0 ? 0 : (j0 >= hgt ? hgt - 1 : j0);
        j1 = j1 < 0 ? 0 : (j1 >= hgt ? hgt - 1 : j1);
    } else {
        i0 %= w;
        i0 += i0 < 0 ? w : 0;
        j0 %= hgt;
        j0 += j0 < 0 ? hgt : 0;
        i1 = i0 + 1 == w ? 0 : i0 + 1;
        j1 = j0 + 1 == hgt ? 0 : j0 + 1;
    }
    const float *g = job->grid;
    float h00 = g[(size_t)j0 * w + i0], h10 = g[(size_t)j0 * w + i1];
    float h01 = g[(size_t)j1 * w + i0], h11 = g[(size_t)j1 * w + i1];
    float top = h00 + (h10 - h00) * tx, bottom = h01 + (h11 - h01) * tx;
    return top + (bottom - top) * ty;
}

/* Zero-curvature ray casting for one texel and azimuth (§3.1): the ray enters the reference
 * surface at (u0, v0) with polar angle theta_t and travels along -(cos phi, sin phi) in
 * texture space. One march serves every theta: the ray of theta_t has depth s cot(theta_t) at
 * horizontal distance s, so it meets the surface at the first s where
 * s cot(theta_t) >= depth (1 - h(s)); unresolved thetas are always the largest ones. Each hit
 * is refined by linear interpolation within the step. Outputs, tiles: horizontal distance
 * out_s[t] and depth out_z[t] of the hit. */
static void cast_rays(const bake_job *job, float u0, float v0, float phi, float *out_s,
                      float *out_z) {
    const meso_vdm_desc *d = &job->desc;
    int n = d->num_theta;
    float depth = d->depth;
    float z0 = depth * (1.0f - grid_sample(job, u0, v0));
    if (z0 <= 0.0f) { /* the mesostructure touches the reference surface here */
        for (int t = 0; t < n; t++) out_s[t] = out_z[t] = 0.0f;
        return;
    }
    float cot[MESO_VDM_MAX_THETA];
    for (int t = 0; t < n; t++) cot[t] = 1.0f / tanf(theta_of(d, t));
    float step = d->step_texels / (float)(d->width > d->height ? d->width : d->height);
    float du = -cosf(phi), dv = -sinf(phi);
    /* The deepest point is at depth <= depth, so every ray has hit by s = depth tan(theta). */
    float s_max = depth / cot[n - 1] + 2.0f * step;
    int next = 0;
    float s_prev = 0.0f, z_prev = z0;
    for (int k = 1; next < n; k++) {
        float s = (float)k * step;
        float z = depth * (1.0f - grid_sample(job, u0 + s * du, v0 + s * dv));
        while (next < n && (s * cot[next] >= z || s > s_max)) {
            float f_prev = s_prev * cot[next] - z_prev, f = s * cot[next] - z;
            float w = f > f_prev ? -f_prev / (f - f_prev) : 1.0f;
            w = w < 0.0f ? 0.0f : (w > 1.0f ? 1.0f : w);
            float s_hit = s_prev + (s - s_prev) * w;
            out_s[next] = s_hit;
            out_z[next] = s_hit * cot[next];
            next++;
        }
        s_prev = s;
        z_prev = z;
    }
}

/* atan(y / x) for y >= 0, x > 0 (the bent hits' view angles) to 2e-8 rad: the minimax
 * polynomial of Abramowitz & Stegun 4.4.49 on [0, 1], mirrored through pi/2 - atan(1/t) above.
 * glibc's atan2f was a third of the bake, and the table's theta spacing is 0.05 rad. */
static float polar_angle(float y, float x) {
    bool swap = y > x;
    float t = swap ? x / y : y / x, t2 = t * t;
    float p = -0.0161657367f + t2 * 0.0028662257f;
    p = 0.0429096138f + t2 * p;
    p = -0.0752896400f + t2 * p;
    p = 0.1065626393f + t2 * p;
    p = -0.1420889944f + t2 * p;
    p = 0.1999355085f + t2 * p;
    p = -0.3333314528f + t2 * p;
    float a = t + t * t2 * p;
    return swap ? (float)HALF_PI - a : a;
}

/* The Appendix: bend the zero-curvature hits (s, z) onto a reference surface of curvature c
 * along the view plane, find their new view angles theta', drop the reordered (occluded)
 * ones, resample linearly at the uniform thetas; -1 where no intersection exists. d is the
 * extended l / sin(theta') with l = s, the texture-space distance (so that T' = T - d V_xy
 * still lands on the hit), in shell depths. */
static void bend_and_resample(const meso_vdm_desc *d, float c, const float *s, const float *z,
                              float *out_d) {
    int n = d->num_theta;
    float kept_theta[MESO_VDM_MAX_THETA], kept_d[MESO_VDM_MAX_THETA];
    int count = 0;
    /* Single precision throughout: s, z and 1/c are at least 1e-3 tile apart from round-off
     * trouble and the table is stored as float; double trig made this loop most of the bake. */
    for (int t = 0; t < n; t++) {
        if (s[t] == 0.0f && z[t] == 0.0f) { /* the hit is P itself, whatever the bend */
            kept_theta[count] = theta_of(d, t);
            kept_d[count++] = 0.0f;
            continue;
        }
        float alpha = s[t] * c, q = 1.0f - z[t] * c;
        if (fabsf(alpha) >= (float)HALF_PI) break; /* past a quarter turn the bend is meaningless */
        float horizontal, vertical;                /* of the bent hit relative to P, vertical up */
        if (fabsf(alpha) < 1e-3f) { /* second order in alpha: the third is below float precision */
            horizontal = s[t] * q;
            vertical = -z[t] - 0.5f * s[t] * s[t] * c * q;
        } else {
            float sin_a = sinf(alpha), cos_a = cosf(alpha); /* GCC fuses them into sincosf */
            horizontal = q * sin_a / c;
            vertical = (q * cos_a - 1.0f) / c;
        }
        if (horizontal < 0.0f || -vertical <= 1e-9f) continue; /* above P's tangent plane */
        float theta = polar_angle(horizontal, -vertical);
        if (count > 0 && theta <= kept_theta[count - 1]) continue; /* reordered: occluded */
        float length = sqrtf(horizontal * horizontal + vertical * vertical);
        /* l / sin(theta') with sin(theta') = horizontal / length */
        float dist = s[t] > 1e-9f && horizontal > 0.0f ? s[t] * length / horizontal : length;
        kept_theta[count] = theta;
        kept_d[count] = dist / d->depth;
        count++;
    }
    int k = 0;
    for (int t = 0; t < n; t++) {
        float theta = theta_of(d, t);
        if (count == 0) {
            out_d[t] = -1.0f;
        } else if (theta <= kept_theta[0]) {
            out_d[t] = kept_d[0];
        } else if (theta > kept_theta[count - 1]) {
            /* Convex: the ray leaves the shell without a hit. Concave: the rising surface is
             * always hit; the last hit is the nearest sample we have. */
            out_d[t] = c > 0.0f ? -1.0f : kept_d[count - 1];
        } else {
            while (k + 1 < count && kept_theta[k + 1] < theta) k++;
            float w = (theta - kept_theta[k]) / (kept_theta[k + 1] - kept_theta[k]);
            out_d[t] = kept_d[k] + (kept_d[k + 1] - kept_d[k]) * w;
        }
    }
}

/* Rows [first, first + count) of A (rows (y, x, phi), row-major): for each curvature the d of
 * every theta, then theta_MVM per curvature (§3.3). The streamed SVD calls this twice. */
static void fill_rows(void *user, size_t first, size_t count, float *out) {
    const bake_job *job = user;
    const meso_vdm_desc *d = &job->desc;
    int n = d->num_theta, nc = d->num_curvatures, columns = columns_of(d);
    float s[MESO_VDM_MAX_THETA], z[MESO_VDM_MAX_THETA], flat_d[MESO_VDM_MAX_THETA];
    float dd[MESO_VDM_MAX_THETA];
    for (size_t r = 0; r < count; r++) {
        size_t row = first + r;
        int p = (int)(row % (size_t)d->num_phi);
        size_t texel = row / (size_t)d->num_phi;
        int i = (int)(texel % (size_t)d->width), j = (int)(texel / (size_t)d->width);
        float u0 = ((float)i + 0.5f) / (float)d->width;
        float v0 = 1.0f - ((float)j + 0.5f) / (float)d->height;
        float phi = (float)(TWO_PI * p / d->num_phi);
        float *a = out + r * (size_t)columns;
        cast_rays(job, u0, v0, phi, s, z);
        for (int t = 0; t < n; t++) flat_d[t] = sqrtf(s[t] * s[t] + z[t] * z[t]) / d->depth;
        for (int k = 0; k < nc; k++) {
            float c = curvature_of(d, k);
            if (c == 0.0f) {
                memcpy(dd, flat_d, sizeof(float) * (size_t)n);
            } else {
                bend_and_resample(d, c, s, z, dd);
            }
            /* §3.3: theta_MVM = the largest theta with a valid d; the -1 entries above it get
             * the d of theta_MVM (constant extension: keeps the rows of A smooth for the SVD;
             * the renderer never reads them, it discards above theta_MVM). */
            int last = -1;
            for (int t = 0; t < n; t++)
                if (dd[t] >= 0.0f) last = t;
            float fill = last >= 0 ? dd[last] : 0.0f;
            for (int t = 0; t < n; t++) a[k * n + t] = (t > last || dd[t] < 0.0f) ? fill : dd[t];
            a[n * nc + k] = last >= 0 ? theta_of(d, last) : 0.0f;
        }
    }
}

/* Box-filter the height field to width x height (supersampled bilinear samples). */
static void resample_heightfield(const meso_heightfield *hf, int width, int height, float *grid) {
    int sx = (hf->width + width - 1) / width, sy = (hf->height + height - 1) / height;
    sx = sx < 1 ? 1 : (sx > 8 ? 8 : sx);
    sy = sy < 1 ? 1 : (sy > 8 ? 8 : sy);
    for (int j = 0; j < height; j++)
        for (int i = 0; i < width; i++) {
            double sum = 0.0;
            for (int b = 0; b < sy; b++)
                for (int a = 0; a < sx; a++) {
                    float u = ((float)i + ((float)a + 0.5f) / (float)sx) / (float)width;
                    float v = 1.0f - ((float)j + ((float)b + 0.5f) / (float)sy) / (float)height;
                    sum += meso_heightfield_sample(hf, u, v);
                }
            grid[(size_t)j * width + i] = (float)(sum / (sx * sy));
        }
}

/* Round W to IEEE halves (kept as floats for lookups, and as halves for the bake file), so
 * that a fresh bake and one loaded from its file are the same map. */
static bool make_half_weights(meso_vdm *vdm) {
    size_t count = rows_of(&vdm->desc) * (size_t)vdm->num_weights;
    free(vdm->weights_half);
    vdm->weights_half = malloc(count * sizeof(uint16_t));
    if (!vdm->weights_half) return false;
    meso_bake_round_to_halves(vdm->weights, vdm->weights_half, count);
    return true;
}

void meso_vdm_destroy(meso_vdm *vdm) {
    if (!vdm) return;
    free(vdm->weights);
    free(vdm->eigen_vdm);
    free(vdm->eigen_mvm);
    free(vdm->singular);
    free(vdm->raw);
    free(vdm->weights_half);
    free(vdm);
}

/* Sizes and the RMSE table from the singular values and eigenfunctions (§3.3). With
 * A = U S V^T exactly, the error of keeping k terms over a set of columns C is
 * sum_{i >= k} s_i^2 sum_{col in C} V[col][i]^2 (U has orthonormal columns). */
static void fill_compression(meso_vdm *vdm, const float *vt, int rank, float mvm_scale) {
    const meso_vdm_desc *d = &vdm->desc;
    size_t rows = rows_of(d);
    int columns = columns_of(d), vdm_columns = d->num_theta * d->num_curvatures;
    meso_vdm_compression *c = &vdm->compression;
    c->raw_bytes = (uint64_t)rows * (uint64_t)columns * 4u;
    c->compressed_bytes =
        (uint64_t)rows * (uint64_t)vdm->num_weights * (d->float_weights ? 4u : 2u) +
        ((uint64_t)d->vdm_eigenfunctions * vdm_columns +
         (uint64_t)d->mvm_eigenfunctions * d->num_curvatures) *
            4u;
    double vdm_energy[MESO_VDM_MAX_THETA * MESO_VDM_MAX_CURVATURES + MESO_VDM_MAX_CURVATURES];
    double mvm_energy[MESO_VDM_MAX_THETA * MESO_VDM_MAX_CURVATURES + MESO_VDM_MAX_CURVATURES];
    int terms = rank < (int)(sizeof(vdm_energy) / sizeof(vdm_energy[0])) ? rank : 0;
    for (int i = 0; i < terms; i++) {
        double e = 0.0, m = 0.0;
        for (int col = 0; col < columns; col++) {
            double v = vt[(size_t)col * rank + i];
            if (col < vdm_columns)
                e += v * v;
            else
                m += v * v;
        }
        double s2 = (double)vdm->singular[i] * vdm->singular[i];
        vdm_energy[i] = s2 * e;
        mvm_energy[i] = s2 * m;
    }
    c->num_rmse = MESO_VDM_RMSE_COUNT;
    for (int k = 1; k <= MESO_VDM_RMSE_COUNT; k++) {
        double sum = 0.0;
        for (int i = k; i < terms; i++) sum += vdm_energy[i];
        float rmse = k > rank ? 0.0f : (float)sqrt(sum / ((double)rows * vdm_columns));
        c->rmse[k - 1] = rmse;
        c->rmse_texels[k - 1] = rmse * d->depth * (float)d->width;
    }
    double sum = 0.0;
    for (int i = d->mvm_eigenfunctions; i < terms; i++) sum += mvm_energy[i];
    c->mvm_rmse = (float)(sqrt(sum / ((double)rows * d->num_curvatures)) / mvm_scale);
}

/* The MVM columns hold angles below pi/2 while d reaches tens of shell depths: unweighted, the
 * SVD would spend its first eigenfunctions on d alone and theta_MVM, which decides the
 * silhouettes, would be poor with m = 4. Scale A_MVM so both parts carry the same energy; E_MVM
 * is divided by the same factor afterwards, so W E_MVM^T is theta_MVM again. */
static void balance_mvm(void *user, const double *column_energy, float *column_scale) {
    const bake_job *job = user;
    int vdm_columns = job->desc.num_theta * job->desc.num_curvatures;
    int columns = columns_of(&job->desc);
    double energy_vdm = 0.0, energy_mvm = 0.0;
    for (int c = 0; c < columns; c++)
        *(c < vdm_columns ? &energy_vdm : &energy_mvm) += column_energy[c];
    float mvm_scale =
        energy_mvm > 0.0 && energy_vdm > 0.0 ? (float)sqrt(energy_vdm / energy_mvm) : 1.0f;
    for (int c = 0; c < columns; c++) column_scale[c] = c < vdm_columns ? 1.0f : mvm_scale;
}

meso_result meso_vdm_bake(meso_context *ctx, const meso_vdm_desc *desc, meso_vdm **out_vdm) {
    if (out_vdm) *out_vdm = NULL;
    if (!out_vdm) return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "vdm: out_vdm is NULL");
    meso_vdm_desc d = meso_vdm_desc_defaults(desc);
    if (!d.heightfield || !d.heightfield->heights || d.heightfield->width < 1 ||
        d.heightfield->height < 1)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "vdm: heightfield: missing");
    meso_result result = check_desc(ctx, "vdm", &d);
    if (result != MESO_OK) return result;

    double start = meso_time_seconds();
    size_t rows = rows_of(&d);
    int columns = columns_of(&d), vdm_columns = d.num_theta * d.num_curvatures;
    int k = d.vdm_eigenfunctions, m = d.mvm_eigenfunctions, kw = k > m ? k : m;
    /* The memory budget, before allocating: W (float, then halves), the resampled grid, the
     * streamed SVD's blocks and Gram matrix (bake_svd.c: 8192 rows as float and double), the
     * raw table when kept. Holding A between the passes is extra, taken only if it fits. */
    uint64_t table_bytes = (uint64_t)rows * (uint64_t)columns * sizeof(float);
    uint64_t needed = (uint64_t)rows * (uint64_t)kw * (sizeof(float) + sizeof(uint16_t)) +
                      (uint64_t)d.width * (uint64_t)d.height * sizeof(float) +
                      UINT64_C(8192) * (uint64_t)columns * (sizeof(float) + sizeof(double)) +
                      3u * (uint64_t)columns * (uint64_t)columns * sizeof(double) +
                      (d.keep_raw ? table_bytes : 0);
    if ((result = meso_memory_check(ctx, "vdm bake", needed)) != MESO_OK) return result;
    bool hold_table = !d.keep_raw && table_bytes <= (UINT64_C(1) << 31) &&
                      needed + table_bytes <= meso_context_memory_limit(ctx);
    float *grid = NULL, *vectors = NULL, *scale = NULL;
    meso_vdm *vdm = calloc(1, sizeof(*vdm));
    if (!vdm) goto out_of_memory;
    vdm->desc = d;
    vdm->desc.heightfield = NULL;
    vdm->source_hash = d.heightfield->hash;
    vdm->wrap = d.heightfield->wrap;
    vdm->num_weights = kw;
    vdm->num_sv = columns;
    grid = malloc(sizeof(float) * (size_t)d.width * (size_t)d.height);
    vectors = malloc(sizeof(float) * (size_t)columns * (size_t)columns);
    scale = malloc(sizeof(float) * (size_t)columns);
    vdm->singular = malloc(sizeof(float) * (size_t)columns);
    vdm->weights = malloc(sizeof(float) * rows * (size_t)kw);
    vdm->eigen_vdm = malloc(sizeof(float) * (size_t)k * (size_t)vdm_columns);
    vdm->eigen_mvm = malloc(sizeof(float) * (size_t)m * (size_t)d.num_curvatures);
    if (d.keep_raw) vdm->raw = malloc(sizeof(float) * rows * (size_t)columns);
    if (!grid || !vectors || !scale || !vdm->singular || !vdm->weights || !vdm->eigen_vdm ||
        !vdm->eigen_mvm || (d.keep_raw && !vdm->raw))
        goto out_of_memory;

    resample_heightfield(d.heightfield, d.width, d.height, grid);
    bake_job job = {.desc = d, .grid = grid, .clamp = d.heightfield->wrap == MESO_WRAP_CLAMP};
    /* A table of up to 2 GiB (128^2: 277 MB, 256^2: 1.1 GB) within the memory budget is held
     * between the passes instead of cast again: half the bake. Larger ones (512^2: 4.4 GB),
     * or no room for it, stream twice. */
    float *table = vdm->raw;
    if (hold_table) table = malloc(table_bytes);
    meso_bake_rows source = {
        .rows = rows,
        .columns = columns,
        .fill = fill_rows,
        .user = &job,
        .column_scale = scale,
        .choose_scale = balance_mvm,
        .progress = meso_progress_begin_bake(ctx, "vdm", (table ? 1u : 2u) * (uint64_t)rows)};
    /* §3.3: A = U lambda E^T = W E^T, the MVM part weighted (balance_mvm) */
    result = meso_bake_svd_streamed(ctx, "vdm", &source, kw, vdm->singular, vectors, vdm->weights,
                                    table);
    if (table != vdm->raw) free(table);
    meso_progress_end(source.progress);
    if (result != MESO_OK) goto fail;
    if (!d.float_weights && !make_half_weights(vdm)) goto out_of_memory;
    float mvm_scale = scale[columns - 1];
    for (int i = 0; i < k; i++)
        for (int col = 0; col < vdm_columns; col++)
            vdm->eigen_vdm[(size_t)i * vdm_columns + col] = vectors[(size_t)col * columns + i];
    for (int i = 0; i < m; i++)
        for (int c = 0; c < d.num_curvatures; c++)
            vdm->eigen_mvm[(size_t)i * d.num_curvatures + c] =
                vectors[(size_t)(vdm_columns + c) * columns + i] / mvm_scale;
    fill_compression(vdm, vectors, columns, mvm_scale);
    vdm->compression.bake_seconds = meso_time_seconds() - start;
    free(scale);
    free(vectors);
    free(grid);
    *out_vdm = vdm;
    return MESO_OK;
out_of_memory:
    result = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "vdm: out of memory for %zu x %d table",
                            rows, columns);
fail:
    free(scale);
    free(vectors);
    free(grid);
    meso_vdm_destroy(vdm);
    return result;
}

/* ---- Accessors and lookups ---------------------------------------------------------------- */

meso_vdm_desc meso_vdm_get_desc(const meso_vdm *vdm) { return vdm->desc; }
meso_vdm_compression meso_vdm_get_compression(const meso_vdm *vdm) { return vdm->compression; }

meso_vdm_view meso_vdm_get_view(const meso_vdm *vdm) {
    const meso_vdm_desc *d = &vdm->desc;
    return (meso_vdm_view){.width = d->width,
                           .height = d->height,
                           .num_theta = d->num_theta,
                           .num_phi = d->num_phi,
                           .num_curvatures = d->num_curvatures,
                           .depth = d->depth,
                           .curvature_min = d->curvature_min,
                           .curvature_max = d->curvature_max,
                           .num_vdm = d->vdm_eigenfunctions,
                           .num_mvm = d->mvm_eigenfunctions,
                           .num_weights = vdm->num_weights,
                           .weights = vdm->weights,
                           .eigen_vdm = vdm->eigen_vdm,
                           .eigen_mvm = vdm->eigen_mvm,
                           .raw = vdm->raw,
                           .raw_columns = columns_of(d)};
}

typedef struct lookup_axes {
    meso_axis x, y, phi, theta, c;
} lookup_axes;

static lookup_axes axes_of(const meso_vdm *vdm, float u, float v, float theta, float phi, float c) {
    const meso_vdm_desc *d = &vdm->desc;
    lookup_axes a;
    float x = u * (float)d->width - 0.5f, y = (1.0f - v) * (float)d->height - 0.5f;
    if (vdm->wrap == MESO_WRAP_CLAMP) {
        a.x = meso_axis_clamp(x, d->width);
        a.y = meso_axis_clamp(y, d->height);
    } else {
        a.x = meso_axis_wrap(x, d->width);
        a.y = meso_axis_wrap(y, d->height);
    }
    a.phi = meso_axis_wrap(phi * (float)d->num_phi / (float)TWO_PI, d->num_phi);
    a.theta = meso_axis_clamp(theta * (float)d->num_theta / (float)HALF_PI - 0.5f, d->num_theta);
    float cn = d->num_curvatures > 1
                   ? (c - d->curvature_min) / (d->curvature_max - d->curvature_min) *
                         (float)(d->num_curvatures - 1)
                   : 0.0f;
    a.c = meso_axis_clamp(cn, d->num_curvatures);
    return a;
}

/* Corner `corner` (bit 0: x, 1: y, 2: phi) of the trilinear cell: its weight, and in *cell its
 * (x, y, phi) row of the tables. */
static float corner_of(const meso_vdm *vdm, const lookup_axes *a, int corner, size_t *cell) {
    const meso_vdm_desc *d = &vdm->desc;
    int ix = corner & 1 ? a->x.i1 : a->x.i0, iy = corner & 2 ? a->y.i1 : a->y.i0;
    int ip = corner & 4 ? a->phi.i1 : a->phi.i0;
    *cell = ((size_t)iy * d->width + ix) * d->num_phi + ip;
    return (corner & 1 ? a->x.w : 1.0f - a->x.w) * (corner & 2 ? a->y.w : 1.0f - a->y.w) *
           (corner & 4 ? a->phi.w : 1.0f - a->phi.w);
}

/* Value of column `col` at row corners, trilinear over (x, y, phi), from the raw table or the
 * interpolated weights. */
static void interpolate_weights(const meso_vdm *vdm, const lookup_axes *a, int kw, float *out) {
    for (int i = 0; i < kw; i++) out[i] = 0.0f;
    for (int corner = 0; corner < 8; corner++) {
        size_t cell;
        float w = corner_of(vdm, a, corner, &cell);
        if (w == 0.0f) continue;
        const float *row = vdm->weights + cell * vdm->num_weights;
        for (int i = 0; i < kw; i++) out[i] += w * row[i];
    }
}

static float raw_value(const meso_vdm *vdm, const lookup_axes *a, int column_of_corner[4],
                       const float column_weight[4]) {
    int columns = columns_of(&vdm->desc);
    float sum = 0.0f;
    for (int corner = 0; corner < 8; corner++) {
        size_t cell;
        float w = corner_of(vdm, a, corner, &cell);
        if (w == 0.0f) continue;
        const float *row = vdm->raw + cell * columns;
        for (int q = 0; q < 4; q++) sum += w * column_weight[q] * row[column_of_corner[q]];
    }
    return sum;
}

float meso_vdm_lookup(const meso_vdm *vdm, float u, float v, float theta, float phi, float c,
                      int num_eigen, bool raw) {
    const meso_vdm_desc *d = &vdm->desc;
    lookup_axes a = axes_of(vdm, u, v, theta, phi, c);
    int cols[4] = {a.c.i0 * d->num_theta + a.theta.i0, a.c.i0 * d->num_theta + a.theta.i1,
                   a.c.i1 * d->num_theta + a.theta.i0, a.c.i1 * d->num_theta + a.theta.i1};
    float cw[4] = {(1.0f - a.c.w) * (1.0f - a.theta.w), (1.0f - a.c.w) * a.theta.w,
                   a.c.w * (1.0f - a.theta.w), a.c.w * a.theta.w};
    if (raw && vdm->raw) return raw_value(vdm, &a, cols, cw);
    int k = num_eigen <= 0 || num_eigen > d->vdm_eigenfunctions ? d->vdm_eigenfunctions : num_eigen;
    float w[MESO_VDM_MAX_EIGEN];
    interpolate_weights(vdm, &a, k, w);
    int vdm_columns = d->num_theta * d->num_curvatures;
    float sum = 0.0f;
    for (int i = 0; i < k; i++) {
        const float *e = vdm->eigen_vdm + (size_t)i * vdm_columns;
        float ei =
            cw[0] * e[cols[0]] + cw[1] * e[cols[1]] + cw[2] * e[cols[2]] + cw[3] * e[cols[3]];
        sum += w[i] * ei;
    }
    return sum;
}

float meso_vdm_max_theta(const meso_vdm *vdm, float u, float v, float phi, float c, bool raw) {
    const meso_vdm_desc *d = &vdm->desc;
    lookup_axes a = axes_of(vdm, u, v, 0.0f, phi, c);
    int base = d->num_theta * d->num_curvatures;
    if (raw && vdm->raw) {
        int cols[4] = {base + a.c.i0, base + a.c.i1, base, base};
        float cw[4] = {1.0f - a.c.w, a.c.w, 0.0f, 0.0f};
        return raw_value(vdm, &a, cols, cw);
    }
    int m = d->mvm_eigenfunctions;
    float w[MESO_VDM_MAX_EIGEN];
    interpolate_weights(vdm, &a, m, w);
    float sum = 0.0f;
    for (int i = 0; i < m; i++) {
        const float *e = vdm->eigen_mvm + (size_t)i * d->num_curvatures;
        sum += w[i] * (e[a.c.i0] * (1.0f - a.c.w) + e[a.c.i1] * a.c.w);
    }
    return sum;
}

/* ---- Bake files --------------------------------------------------------------------------- */

#define REPORT_FLOATS (2 * MESO_VDM_RMSE_COUNT + 4)

static int write_params(const meso_vdm *vdm, char *buffer, size_t size) {
    const meso_vdm_desc *d = &vdm->desc;
    const meso_vdm_compression *c = &vdm->compression;
    return snprintf(buffer, size,
                    "{\"width\": %d, \"height\": %d, \"num_theta\": %d, \"num_phi\": %d, "
                    "\"num_curvatures\": %d, \"curvature_min\": %.9g, \"curvature_max\": %.9g, "
                    "\"depth\": %.9g, \"step_texels\": %.9g, \"vdm_eigenfunctions\": %d, "
                    "\"mvm_eigenfunctions\": %d, \"float_weights\": %d, \"wrap\": %d, "
                    "\"raw_bytes\": %llu, "
                    "\"compressed_bytes\": %llu, \"bake_seconds\": %.3f, "
                    "\"units\": \"d in shell depths, curvature in 1/tile, theta in radians\"}",
                    d->width, d->height, d->num_theta, d->num_phi, d->num_curvatures,
                    d->curvature_min, d->curvature_max, d->depth, d->step_texels,
                    d->vdm_eigenfunctions, d->mvm_eigenfunctions, d->float_weights ? 1 : 0,
                    (int)vdm->wrap, (unsigned long long)c->raw_bytes,
                    (unsigned long long)c->compressed_bytes, c->bake_seconds);
}

static meso_bake_file to_bake_file(const meso_vdm *vdm, char *params, size_t params_size,
                                   float *report) {
    const meso_vdm_desc *d = &vdm->desc;
    write_params(vdm, params, params_size);
    const meso_vdm_compression *c = &vdm->compression;
    for (int i = 0; i < MESO_VDM_RMSE_COUNT; i++) {
        report[i] = c->rmse[i];
        report[MESO_VDM_RMSE_COUNT + i] = c->rmse_texels[i];
    }
    report[2 * MESO_VDM_RMSE_COUNT] = c->mvm_rmse;
    report[2 * MESO_VDM_RMSE_COUNT + 1] = (float)c->num_rmse;
    report[2 * MESO_VDM_RMSE_COUNT + 2] = (float)c->bake_seconds;
    report[2 * MESO_VDM_RMSE_COUNT + 3] = 0.0f;
    meso_bake_file bake = {.kind = MESO_VDM_KIND,
                           .kind_version = MESO_VDM_KIND_VERSION,
                           .source_hash = vdm->source_hash,
                           .params_json = params,
                           .num_arrays = 5};
    uint64_t rows_dims[4] = {(uint64_t)d->height, (uint64_t)d->width, (uint64_t)d->num_phi, 0};
    bake.arrays[0] = (meso_bake_array){
        .name = "weights",
        .type = vdm->weights_half ? MESO_BAKE_F16 : MESO_BAKE_F32,
        .num_dims = 4,
        .dims = {rows_dims[0], rows_dims[1], rows_dims[2], (uint64_t)vdm->num_weights},
        .data = vdm->weights_half ? (void *)vdm->weights_half : (void *)vdm->weights};
    bake.arrays[1] =
        (meso_bake_array){.name = "eigen_vdm",
                          .type = MESO_BAKE_F32,
                          .num_dims = 3,
                          .dims = {(uint64_t)d->vdm_eigenfunctions, (uint64_t)d->num_curvatures,
                                   (uint64_t)d->num_theta},
                          .data = vdm->eigen_vdm};
    bake.arrays[2] =
        (meso_bake_array){.name = "eigen_mvm",
                          .type = MESO_BAKE_F32,
                          .num_dims = 2,
                          .dims = {(uint64_t)d->mvm_eigenfunctions, (uint64_t)d->num_curvatures},
                          .data = vdm->eigen_mvm};
    bake.arrays[3] = (meso_bake_array){.name = "singular_values",
                                       .type = MESO_BAKE_F32,
                                       .num_dims = 1,
                                       .dims = {(uint64_t)vdm->num_sv},
                                       .data = vdm->singular};
    bake.arrays[4] = (meso_bake_array){.name = "report",
                                       .type = MESO_BAKE_F32,
                                       .num_dims = 1,
                                       .dims = {REPORT_FLOATS},
                                       .data = report};
    if (vdm->raw) {
        bake.arrays[5] = (meso_bake_array){
            .name = "raw",
            .type = MESO_BAKE_F32,
            .num_dims = 4,
            .dims = {rows_dims[0], rows_dims[1], rows_dims[2], (uint64_t)columns_of(d)},
            .data = vdm->raw};
        bake.num_arrays = 6;
    }
    return bake;
}

meso_result meso_vdm_save(meso_context *ctx, const meso_vdm *vdm, const char *path) {
    char params[2048];
    float report[REPORT_FLOATS];
    meso_bake_file bake = to_bake_file(vdm, params, sizeof(params), report);
    return meso_bake_file_save(ctx, &bake, path);
}

/* The array `name` of type f32 with exactly the dims given, or NULL. */
static const float *expect_array(const meso_bake_file *bake, const char *name, int num_dims,
                                 const uint64_t *dims) {
    return meso_bake_file_expect(bake, name, MESO_BAKE_F32, num_dims, dims);
}

static float *copy_floats(const float *src, size_t count) {
    float *dst = malloc(sizeof(float) * count);
    if (dst) memcpy(dst, src, sizeof(float) * count);
    return dst;
}

meso_result meso_vdm_from_bake_file(meso_context *ctx, const meso_bake_file *bake, const char *name,
                                    meso_vdm **out_vdm) {
    if (out_vdm) *out_vdm = NULL;
    if (!bake || !out_vdm)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "vdm: NULL argument");
    name = name ? name : "vdm";
    if (strcmp(bake->kind, MESO_VDM_KIND) != 0 || bake->kind_version != MESO_VDM_KIND_VERSION)
        return meso_log_error(ctx, MESO_ERROR_FORMAT,
                              "%s: kind %s version %u is not vdm version %u", name, bake->kind,
                              bake->kind_version, MESO_VDM_KIND_VERSION);
    meso_vdm_desc d = {0};
    double v[13];
    const char *keys[13] = {"float_weights",
                            "width",
                            "height",
                            "num_theta",
                            "num_phi",
                            "num_curvatures",
                            "curvature_min",
                            "curvature_max",
                            "depth",
                            "step_texels",
                            "vdm_eigenfunctions",
                            "mvm_eigenfunctions",
                            "wrap"};
    for (int i = 0; i < 13; i++)
        if (!bake->params_json || !meso_bake_params_number(bake->params_json, keys[i], &v[i]))
            return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: params: %s: missing or not a number",
                                  name, keys[i]);
    for (int i = 0; i < 13; i++)
        if (fabs(v[i]) > 1e6)
            return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: params: %s: out of range", name,
                                  keys[i]);
    d.float_weights = v[0] != 0.0;
    d.width = (int)v[1];
    d.height = (int)v[2];
    d.num_theta = (int)v[3];
    d.num_phi = (int)v[4];
    d.num_curvatures = (int)v[5];
    d.curvature_min = (float)v[6];
    d.curvature_max = (float)v[7];
    d.depth = (float)v[8];
    d.step_texels = (float)v[9];
    d.vdm_eigenfunctions = (int)v[10];
    d.mvm_eigenfunctions = (int)v[11];
    meso_result result = check_desc(ctx, name, &d);
    if (result != MESO_OK) return result == MESO_ERROR_LIMIT ? result : MESO_ERROR_FORMAT;
    size_t rows = rows_of(&d);
    int columns = columns_of(&d), rank = (size_t)columns < rows ? columns : (int)rows;
    int kw =
        d.vdm_eigenfunctions > d.mvm_eigenfunctions ? d.vdm_eigenfunctions : d.mvm_eigenfunctions;
    uint64_t wd[4] = {(uint64_t)d.height, (uint64_t)d.width, (uint64_t)d.num_phi, (uint64_t)kw};
    uint64_t ed[3] = {(uint64_t)d.vdm_eigenfunctions, (uint64_t)d.num_curvatures,
                      (uint64_t)d.num_theta};
    uint64_t md[2] = {(uint64_t)d.mvm_eigenfunctions, (uint64_t)d.num_curvatures};
    uint64_t sd[1] = {(uint64_t)rank}, rd[1] = {REPORT_FLOATS};
    uint64_t raw_dims[4] = {wd[0], wd[1], wd[2], (uint64_t)columns};
    const meso_bake_array *weights_array = meso_bake_file_find(bake, "weights");
    bool half = weights_array && weights_array->type == MESO_BAKE_F16;
    if (half != !d.float_weights)
        return meso_log_error(ctx, MESO_ERROR_FORMAT,
                              "%s: array \"weights\": type does not match float_weights", name);
    const void *weights = half ? meso_bake_file_expect(bake, "weights", MESO_BAKE_F16, 4, wd)
                               : (const void *)expect_array(bake, "weights", 4, wd);
    const float *eigen_vdm = expect_array(bake, "eigen_vdm", 3, ed);
    const float *eigen_mvm = expect_array(bake, "eigen_mvm", 2, md);
    const float *singular = expect_array(bake, "singular_values", 1, sd);
    const float *report = expect_array(bake, "report", 1, rd);
    const float *raw = expect_array(bake, "raw", 4, raw_dims);
    if (!weights || !eigen_vdm || !eigen_mvm || !singular || !report)
        return meso_log_error(ctx, MESO_ERROR_FORMAT,
                              "%s: arrays weights, eigen_vdm, eigen_mvm, singular_values, report "
                              "missing or of the wrong shape for the params",
                              name);
    if (meso_bake_file_find(bake, "raw") && !raw)
        return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: array \"raw\": wrong shape", name);
    /* Values, not only shapes: a valid checksum does not make Inf or NaN usable. Eigenvectors
     * are unit vectors (|x| <= 1); weights are bounded by half precision's range, so a
     * reconstruction of at most 16 terms stays far inside int range where the technique
     * converts it to indices; the rest must be finite and the RMSEs and singular values >= 0. */
    static const struct {
        const char *array;
        double min, max;
    } ranges[] = {{"weights", -65504.0, 65504.0}, {"eigen_vdm", -1.001, 1.001},
                  {"eigen_mvm", -1.001, 1.001},   {"singular_values", 0.0, 3.4e38},
                  {"report", 0.0, 3.4e38},        {"raw", -1e6, 1e6}};
    for (size_t i = 0; i < sizeof(ranges) / sizeof(ranges[0]); i++) {
        const meso_bake_array *a = meso_bake_file_find(bake, ranges[i].array);
        if (a && (result = meso_bake_array_check_values(ctx, name, a, ranges[i].min,
                                                        ranges[i].max)) != MESO_OK)
            return result;
    }
    meso_vdm *vdm = calloc(1, sizeof(*vdm));
    if (!vdm) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", name);
    vdm->desc = d;
    vdm->desc.keep_raw = raw != NULL;
    vdm->source_hash = bake->source_hash;
    vdm->wrap = (int)v[12] == MESO_WRAP_CLAMP ? MESO_WRAP_CLAMP : MESO_WRAP_REPEAT;
    vdm->num_weights = kw;
    vdm->num_sv = rank;
    if (half) {
        vdm->weights = malloc(sizeof(float) * rows * (size_t)kw);
        vdm->weights_half = malloc(sizeof(uint16_t) * rows * (size_t)kw);
        if (vdm->weights && vdm->weights_half) {
            memcpy(vdm->weights_half, weights, sizeof(uint16_t) * rows * (size_t)kw);
            meso_bake_halves_to_floats(vdm->weights_half, vdm->weights, rows * (size_t)kw);
        }
    } else {
        vdm->weights = copy_floats(weights, rows * (size_t)kw);
    }
    vdm->eigen_vdm = copy_floats(eigen_vdm, (size_t)(ed[0] * ed[1] * ed[2]));
    vdm->eigen_mvm = copy_floats(eigen_mvm, (size_t)(md[0] * md[1]));
    vdm->singular = copy_floats(singular, (size_t)rank);
    vdm->raw = raw ? copy_floats(raw, rows * (size_t)columns) : NULL;
    if (!vdm->weights || (half && !vdm->weights_half) || !vdm->eigen_vdm || !vdm->eigen_mvm ||
        !vdm->singular || (raw && !vdm->raw)) {
        meso_vdm_destroy(vdm);
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", name);
    }
    meso_vdm_compression *c = &vdm->compression;
    c->raw_bytes = (uint64_t)rows * (uint64_t)columns * 4u;
    c->compressed_bytes =
        (uint64_t)rows * kw * (half ? 2u : 4u) + (ed[0] * ed[1] * ed[2] + md[0] * md[1]) * 4u;
    c->num_rmse = MESO_VDM_RMSE_COUNT;
    for (int i = 0; i < MESO_VDM_RMSE_COUNT; i++) {
        c->rmse[i] = report[i];
        c->rmse_texels[i] = report[MESO_VDM_RMSE_COUNT + i];
    }
    c->mvm_rmse = report[2 * MESO_VDM_RMSE_COUNT];
    c->bake_seconds = 0.0;
    *out_vdm = vdm;
    return MESO_OK;
}

/* The steps of meso_bake_cache_run for a vdm; desc: the caller's meso_vdm_desc. */
static meso_result vdm_from_file(meso_context *ctx, const meso_bake_file *bake, const char *where,
                                 const void *desc, void *out) {
    (void)desc;
    return meso_vdm_from_bake_file(ctx, bake, where, out);
}

static meso_result vdm_bake(meso_context *ctx, const void *desc, void *out) {
    return meso_vdm_bake(ctx, desc, out);
}

static meso_result vdm_store(meso_context *ctx, const meso_cached_bake *entry, const void *out) {
    char params[2048];
    float report[REPORT_FLOATS];
    meso_bake_file bake = to_bake_file(*(meso_vdm *const *)out, params, sizeof(params), report);
    return meso_bake_cache_save(ctx, &bake, entry->key);
}

meso_result meso_vdm_load(meso_context *ctx, const char *path, meso_vdm **out_vdm) {
    if (out_vdm) *out_vdm = NULL;
    return meso_bake_load_with(ctx, path, vdm_from_file, NULL, out_vdm);
}

meso_result meso_vdm_bake_cached(meso_context *ctx, const meso_vdm_desc *desc, meso_vdm **out_vdm) {
    if (out_vdm) *out_vdm = NULL;
    meso_cached_bake entry = {MESO_VDM_KIND,
                              MESO_VDM_KIND_VERSION,
                              "vdm",
                              meso_vdm_cache_key(desc),
                              desc && desc->heightfield ? desc->heightfield->hash : 0,
                              desc,
                              vdm_from_file,
                              vdm_bake,
                              vdm_store};
    return meso_bake_cache_run(ctx, &entry, out_vdm);
}

size_t meso_vdm_describe(const meso_bake_file *bake, char *buffer, size_t size) {
    if (!bake || strcmp(bake->kind, MESO_VDM_KIND) != 0 || !bake->params_json) return 0;
    const meso_bake_array *report = meso_bake_file_find(bake, "report");
    if (!report || report->type != MESO_BAKE_F32 || report->num_dims != 1 ||
        report->dims[0] != REPORT_FLOATS)
        return 0;
    const float *r = report->data;
    double v[6] = {0};
    const char *keys[6] = {
        "raw_bytes", "compressed_bytes", "vdm_eigenfunctions", "mvm_eigenfunctions",
        "depth",     "bake_seconds"};
    for (int i = 0; i < 6; i++)
        if (!meso_bake_params_number(bake->params_json, keys[i], &v[i])) return 0;
    char text[4096];
    int n = snprintf(text, sizeof(text),
                     "vdm: raw VDM+MVM %.2f MB, compressed (k=%d, m=%d) %.2f MB, ratio %.1f:1, "
                     "baked in %.1f s\n"
                     "reconstruction RMSE of d (shell depths / texels of depth):\n",
                     v[0] / 1048576.0, (int)v[2], (int)v[3], v[1] / 1048576.0,
                     v[1] > 0 ? v[0] / v[1] : 0.0, v[5]);
    for (int k = 1; k <= MESO_VDM_RMSE_COUNT && n > 0 && (size_t)n < sizeof(text); k++)
        n += snprintf(text + n, sizeof(text) - (size_t)n, "  k=%2d  %.5f  %.4f\n", k, r[k - 1],
                      r[MESO_VDM_RMSE_COUNT + k - 1]);
    if (n > 0 && (size_t)n < sizeof(text))
        n += snprintf(text + n, sizeof(text) - (size_t)n, "theta_MVM RMSE (m=%d): %.5f rad\n",
                      (int)v[3], r[2 * MESO_VDM_RMSE_COUNT]);
    if (n < 0) return 0;
    if (buffer && size) snprintf(buffer, size, "%s", text);
    return (size_t)n;
}
