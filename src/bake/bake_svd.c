/* The SVD of the bake module for tall tables (VDM §3.3, GDM §4.1): A (rows x columns, rows in
 * the millions, columns a few hundred) is never held whole. Pass 1 streams A in fixed blocks
 * into its Gram matrix G = A^T A (BLAS dsyrk, double); LAPACK's dsyevd gives G = E Lambda E^T,
 * so A = U S E^T with S = sqrt(Lambda); pass 2 streams A again into W = A E_k = U_k S_k. The
 * blocks do not depend on the thread count, so the result is the same for any. */
#include <cblas.h>
#include <lapacke.h>
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "bake_internal.h"
#include "meso/runtime.h"

/* Rows filled by one job of the parallel loop, and rows handed to BLAS at once. Both fixed:
 * the sums BLAS forms then do not depend on the number of threads. */
#define ROWS_PER_JOB 64
#define ROWS_PER_BLOCK 8192

typedef struct fill_job {
    const meso_bake_rows *source;
    size_t first, count; /* the block */
    float *block;        /* count x columns, row-major */
    atomic_bool cancelled;
} fill_job;

static void fill_rows(void *user, size_t job_index, int thread_index) {
    (void)thread_index;
    fill_job *job = user;
    if (atomic_load(&job->cancelled)) return;
    size_t first = job_index * ROWS_PER_JOB;
    size_t count = first + ROWS_PER_JOB < job->count ? ROWS_PER_JOB : job->count - first;
    const meso_bake_rows *s = job->source;
    s->fill(s->user, job->first + first, count, job->block + first * (size_t)s->columns);
    if (meso_progress_advance(s->progress, count)) atomic_store(&job->cancelled, true);
}

/* Fill rows [first, first + count) of A into block (from the raw copy when there is one). */
static bool fetch_block(meso_context *ctx, const meso_bake_rows *source, const float *raw,
                        size_t first, size_t count, float *block) {
    size_t columns = (size_t)source->columns;
    if (raw) { /* no progress: a copy is nothing beside a fill */
        memcpy(block, raw + first * columns, sizeof(float) * count * columns);
        return true;
    }
    fill_job job = {.source = source, .first = first, .count = count, .block = block};
    atomic_init(&job.cancelled, false);
    meso_parallel_for(ctx, (count + ROWS_PER_JOB - 1) / ROWS_PER_JOB, fill_rows, &job);
    return !atomic_load(&job.cancelled);
}

meso_result meso_bake_svd_streamed(meso_context *ctx, const char *name,
                                   const meso_bake_rows *source, int keep, float *out_singular,
                                   float *out_vectors, float *out_weights, float *out_raw) {
    size_t rows = source->rows, columns = (size_t)source->columns;
    size_t block_rows = rows < ROWS_PER_BLOCK ? rows : ROWS_PER_BLOCK;
    float *block = malloc(sizeof(float) * block_rows * columns);
    double *block_d = malloc(sizeof(double) * block_rows * columns);
    double *gram = calloc(columns * columns, sizeof(double));
    double *eigenvalues = malloc(sizeof(double) * columns);
    double *projection = malloc(sizeof(double) * columns * (size_t)keep);
    double *weights_d = malloc(sizeof(double) * block_rows * (size_t)keep);
    meso_result result = MESO_OK;
    if (!block || !block_d || !gram || !eigenvalues || !projection || !weights_d) {
        result = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: SVD: out of memory", name);
        goto done;
    }
    /* Pass 1: G = sum over blocks of B^T B. B row-major is B^T column-major (ld = columns). */
    for (size_t first = 0; first < rows; first += block_rows) {
        size_t count = first + block_rows < rows ? block_rows : rows - first;
        float *target = out_raw ? out_raw + first * columns : block;
        if (!fetch_block(ctx, source, NULL, first, count, target)) goto cancelled;
        for (size_t i = 0; i < count * columns; i++) block_d[i] = target[i];
        cblas_dsyrk(CblasColMajor, CblasUpper, CblasNoTrans, (int)columns, (int)count, 1.0, block_d,
                    (int)columns, 1.0, gram, (int)columns);
    }
    if (source->choose_scale) {
        for (size_t c = 0; c < columns; c++) eigenvalues[c] = gram[c * columns + c];
        source->choose_scale(source->user, eigenvalues, source->column_scale);
    }
    if (source->column_scale) /* G of A D is D G D */
        for (size_t c = 0; c < columns; c++)
            for (size_t r = 0; r <= c; r++)
                gram[c * columns + r] *= (double)source->column_scale[r] * source->column_scale[c];
    /* G = E Lambda E^T; dsyevd returns ascending eigenvalues, E's columns in gram. */
    lapack_int info = LAPACKE_dsyevd(LAPACK_COL_MAJOR, 'V', 'U', (lapack_int)columns, gram,
                                     (lapack_int)columns, eigenvalues);
    if (info != 0) {
        result = meso_log_error(ctx, MESO_ERROR_INTERNAL, "%s: SVD: LAPACK dsyevd failed (info %d)",
                                name, (int)info);
        goto done;
    }
    for (size_t i = 0; i < columns; i++) {
        size_t from = columns - 1 - i; /* descending */
        double lambda = eigenvalues[from] > 0.0 ? eigenvalues[from] : 0.0;
        out_singular[i] = (float)sqrt(lambda);
        for (size_t c = 0; c < columns; c++)
            out_vectors[c * columns + i] = (float)gram[from * columns + c];
    }
    /* Pass 2: W = (A D) E_k, with D folded into the projection. */
    for (size_t c = 0; c < columns; c++)
        for (int i = 0; i < keep; i++)
            projection[c * (size_t)keep + (size_t)i] =
                (double)out_vectors[c * columns + (size_t)i] *
                (source->column_scale ? source->column_scale[c] : 1.0f);
    for (size_t first = 0; first < rows; first += block_rows) {
        size_t count = first + block_rows < rows ? block_rows : rows - first;
        if (!fetch_block(ctx, source, out_raw, first, count, block)) goto cancelled;
        for (size_t i = 0; i < count * columns; i++) block_d[i] = block[i];
        cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, (int)count, keep, (int)columns, 1.0,
                    block_d, (int)columns, projection, keep, 0.0, weights_d, keep);
        for (size_t i = 0; i < count * (size_t)keep; i++)
            out_weights[first * (size_t)keep + i] = (float)weights_d[i];
    }
    goto done;
cancelled:
    result = meso_log_error(ctx, MESO_ERROR_CANCELLED, "%s: bake cancelled", name);
done:
    free(weights_d);
    free(projection);
    free(eigenvalues);
    free(gram);
    free(block_d);
    free(block);
    return result;
}
