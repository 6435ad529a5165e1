/* Private interface of the bake module. */
#ifndef MESO_BAKE_INTERNAL_H
#define MESO_BAKE_INTERNAL_H

#include "meso/bake.h"

/* Economical SVD (LAPACK gesdd, jobz = 'S') of the m x n column-major matrix `a` (destroyed):
 * a = U diag(s) VT with U m x r (column-major, leading dimension m), s r values descending,
 * VT r x n (column-major, leading dimension r), r = min(m, n). Computed in double precision
 * (the table's d reach tens of shell depths; float gesdd left 1e-4 reconstruction errors) and
 * returned as float. Returns MESO_OK, MESO_ERROR_OUT_OF_MEMORY or MESO_ERROR_INTERNAL (LAPACK
 * did not converge), logged naming `name`. */
meso_result meso_bake_svd(meso_context *ctx, const char *name, const float *a, size_t m, size_t n,
                          float *out_u, float *out_s, float *out_vt);

#endif
