/* The SVD wrapper of the bake module: LAPACK's divide-and-conquer SVD (dgesdd), economical. */
#include <lapacke.h>
#include <stdlib.h>

#include "bake_internal.h"

meso_result meso_bake_svd(meso_context *ctx, const char *name, const float *a, size_t m, size_t n,
                          float *out_u, float *out_s, float *out_vt) {
    size_t r = m < n ? m : n;
    double *ad = malloc(m * n * sizeof(double));
    double *ud = malloc(m * r * sizeof(double));
    double *sd = malloc(r * sizeof(double));
    double *vtd = malloc(r * n * sizeof(double));
    meso_result result = MESO_OK;
    if (!ad || !ud || !sd || !vtd) {
        result = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: SVD: out of memory", name);
        goto done;
    }
    for (size_t i = 0; i < m * n; i++) ad[i] = a[i];
    /* VDM §3.3: A = U lambda E^T; jobz 'S' keeps only the first min(m, n) columns of U. */
    lapack_int info = LAPACKE_dgesdd(LAPACK_COL_MAJOR, 'S', (lapack_int)m, (lapack_int)n, ad,
                                     (lapack_int)m, sd, ud, (lapack_int)m, vtd, (lapack_int)r);
    if (info != 0) {
        result = meso_log_error(ctx, info < 0 ? MESO_ERROR_INTERNAL : MESO_ERROR_INTERNAL,
                                "%s: SVD: LAPACK dgesdd failed (info %d)", name, (int)info);
        goto done;
    }
    for (size_t i = 0; i < m * r; i++) out_u[i] = (float)ud[i];
    for (size_t i = 0; i < r; i++) out_s[i] = (float)sd[i];
    for (size_t i = 0; i < r * n; i++) out_vt[i] = (float)vtd[i];
done:
    free(vtd);
    free(sd);
    free(ud);
    free(ad);
    return result;
}
