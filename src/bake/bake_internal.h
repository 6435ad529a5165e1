/* Private interface of the bake module. */
#ifndef MESO_BAKE_INTERNAL_H
#define MESO_BAKE_INTERNAL_H

#include <math.h>

#include "meso/bake.h"
#include "meso/runtime.h"

/* A tall table streamed by rows: fill(user, first, count, out) writes rows [first, first +
 * count) row-major (count x columns floats) into out. Called from worker threads on disjoint
 * ranges, twice per row (once per pass) unless the caller keeps the raw table. */
typedef struct meso_bake_rows {
    size_t rows;
    int columns;
    void (*fill)(void *user, size_t first, size_t count, float *out);
    void *user;
    /* NULL, or columns factors: the SVD is of A diag(column_scale). When choose_scale is set
     * it fills column_scale between the passes from the energy (sum of squares) of every
     * column of A, so a caller can weight parts of the table by their energy. */
    float *column_scale;
    void (*choose_scale)(void *user, const double *column_energy, float *column_scale);
    meso_progress *progress; /* one unit per row filled: rows with out_raw, else 2 x rows */
} meso_bake_rows;

/* SVD of the tall matrix A D (D = diag(column_scale)) = U S E^T without holding A: its Gram
 * matrix (BLAS dsyrk in double, fixed blocks) and LAPACK's symmetric eigensolver (dsyevd).
 * Outputs: out_singular[columns] descending; out_vectors[column * columns + i] = E[column][i]
 * (eigenfunction i); out_weights[row * keep + i] = (A D E)[row][i] = U S, for i < keep;
 * out_raw (NULL or rows x columns, row-major) receives A itself and saves the second fill.
 * The singular values come from the squared problem: exact for the leading ones this module
 * keeps, relative precision ~1e-8 of s_1 for the smallest. Same result for any thread count.
 * Returns MESO_OK, MESO_ERROR_OUT_OF_MEMORY, MESO_ERROR_CANCELLED (progress) or
 * MESO_ERROR_INTERNAL (LAPACK did not converge), logged naming `name`. */
meso_result meso_bake_svd_streamed(meso_context *ctx, const char *name,
                                   const meso_bake_rows *source, int keep, float *out_singular,
                                   float *out_vectors, float *out_weights, float *out_raw);

/* ---- Helpers shared by the kinds' loaders and lookups ------------------------------------- */

/* The number after "key": in a bake's params (flat JSON objects the kinds write themselves);
 * false when the key is absent or its value is not a finite number. Pure. */
bool meso_bake_params_number(const char *json, const char *key, double *out);
/* The array `name` of `type` with exactly num_dims and dims, or NULL. Pure. */
const void *meso_bake_file_expect(const meso_bake_file *bake, const char *name, meso_bake_type type,
                                  int num_dims, const uint64_t *dims);
/* Round count values to IEEE halves in place and write the halves to out_halves, so that a
 * fresh bake and one loaded from its file hold the same values. */
void meso_bake_round_to_halves(float *values, uint16_t *out_halves, size_t count);
/* Widen count IEEE halves to floats. */
void meso_bake_halves_to_floats(const uint16_t *halves, float *out_values, size_t count);

/* ---- The cached bakes (meso_<kind>_bake_cached) -------------------------------------------- */

/* One kind's cached bake: the cache entry (kind, key) made from source_hash, and the three
 * steps the cache runs for it. `out` is the caller's `meso_<kind> **`, `desc` its request. */
typedef struct meso_cached_bake {
    const char *kind; /* MESO_<KIND>_KIND */
    uint32_t kind_version;
    const char *label; /* the messages' prefix: "gdm", "relief_layers" ... */
    uint64_t key, source_hash;
    const void *desc;
    /* the bake from a loaded cache file (where names it in messages) into *out */
    meso_result (*from_file)(meso_context *ctx, const meso_bake_file *bake, const char *where,
                             const void *desc, void *out);
    /* a fresh bake into *out */
    meso_result (*bake)(meso_context *ctx, const void *desc, void *out);
    /* store the bake *out under (kind, key) with meso_bake_cache_save */
    meso_result (*store)(meso_context *ctx, const struct meso_cached_bake *entry, const void *out);
} meso_cached_bake;

/* Load the entry's bake from the cache, or bake it and store it, holding the entry's claim
 * (meso_bake_cache_claim_entry) throughout so concurrent callers bake it once. An unusable
 * entry is baked again and a failed store only warns: the cache never fails a bake. */
meso_result meso_bake_cache_run(meso_context *ctx, const meso_cached_bake *entry, void *out);
/* Load the bake file at path and convert it with from_file (as meso_<kind>_load). */
meso_result
meso_bake_load_with(meso_context *ctx, const char *path,
                    meso_result (*from_file)(meso_context *ctx, const meso_bake_file *bake,
                                             const char *where, const void *desc, void *out),
                    const void *desc, void *out);

#endif
