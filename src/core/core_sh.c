/* Spherical harmonics of order 4 (include/meso/sh.h): basis, evaluation, irradiance, rotation. */
#include <math.h>
#include <string.h>

#include "meso/sh.h"

void meso_sh_basis(meso_vec3 d, float out[MESO_SH_COUNT]) {
    float x = d.x, y = d.y, z = d.z;
    float x2 = x * x, y2 = y * y, z2 = z * z;
    out[0] = 0.282094791773878f;
    out[1] = 0.488602511902920f * y;
    out[2] = 0.488602511902920f * z;
    out[3] = 0.488602511902920f * x;
    out[4] = 1.092548430592079f * x * y;
    out[5] = 1.092548430592079f * y * z;
    out[6] = 0.315391565252520f * (3.0f * z2 - 1.0f);
    out[7] = 1.092548430592079f * x * z;
    out[8] = 0.546274215296040f * (x2 - y2);
    out[9] = 0.590043589926644f * y * (3.0f * x2 - y2);
    out[10] = 2.890611442640554f * x * y * z;
    out[11] = 0.457045799464466f * y * (5.0f * z2 - 1.0f);
    out[12] = 0.373176332590115f * z * (5.0f * z2 - 3.0f);
    out[13] = 0.457045799464466f * x * (5.0f * z2 - 1.0f);
    out[14] = 1.445305721320277f * z * (x2 - y2);
    out[15] = 0.590043589926644f * x * (x2 - 3.0f * y2);
}

float meso_sh_evaluate(const float coefficients[MESO_SH_COUNT], meso_vec3 d) {
    float basis[MESO_SH_COUNT], sum = 0.0f;
    meso_sh_basis(d, basis);
    for (int i = 0; i < MESO_SH_COUNT; i++) sum += coefficients[i] * basis[i];
    return sum;
}

float meso_sh_irradiance(const float radiance[MESO_SH_COUNT], meso_vec3 n) {
    /* the clamped cosine's zonal coefficients times sqrt(4 pi / (2l + 1)) (Funk-Hecke) */
    static const float band_scale[MESO_SH_ORDER] = {MESO_PI, (float)(2.0 * MESO_PI_D / 3.0),
                                                    (float)(MESO_PI_D / 4.0), 0.0f};
    float basis[MESO_SH_COUNT], sum = 0.0f;
    meso_sh_basis(n, basis);
    for (int l = 0; l < MESO_SH_ORDER; l++)
        for (int i = l * l; i < (l + 1) * (l + 1); i++)
            sum += band_scale[l] * radiance[i] * basis[i];
    return sum;
}

/* ---- Rotation ----------------------------------------------------------------------------- */

/* Solve A X = B for X (n x n, row-major, n <= 7) by Gauss-Jordan with partial pivoting. A is
 * a Gram matrix of the basis at well-spread directions, so it is far from singular. */
static void solve_square(int n, double a[7][7], double b[7][7], double x[7][7]) {
    for (int col = 0; col < n; col++) {
        int pivot = col;
        for (int r = col + 1; r < n; r++)
            if (fabs(a[r][col]) > fabs(a[pivot][col])) pivot = r;
        if (pivot != col)
            for (int c = 0; c < n; c++) {
                double t = a[col][c];
                a[col][c] = a[pivot][c], a[pivot][c] = t;
                t = b[col][c];
                b[col][c] = b[pivot][c], b[pivot][c] = t;
            }
        double inv = 1.0 / a[col][col];
        for (int c = 0; c < n; c++) a[col][c] *= inv, b[col][c] *= inv;
        for (int r = 0; r < n; r++) {
            if (r == col) continue;
            double f = a[r][col];
            if (f == 0.0) continue;
            for (int c = 0; c < n; c++) a[r][c] -= f * a[col][c], b[r][c] -= f * b[col][c];
        }
    }
    for (int r = 0; r < n; r++)
        for (int c = 0; c < n; c++) x[r][c] = b[r][c];
}

/* The 16 basis functions in double, for the rotation's solve. */
static void basis_double(const double d[3], double out[MESO_SH_COUNT]) {
    float f[MESO_SH_COUNT];
    meso_sh_basis((meso_vec3){(float)d[0], (float)d[1], (float)d[2]}, f);
    for (int i = 0; i < MESO_SH_COUNT; i++) out[i] = f[i];
}

/* Direction k of ROTATION_POINTS fixed directions: a spherical Fibonacci set, spread evenly so
 * that the least-squares fit below is well conditioned for every band. */
enum { ROTATION_POINTS = 32 };
static void fixed_direction(int k, double out[3]) {
    double z = 1.0 - (2.0 * k + 1.0) / ROTATION_POINTS;
    double r = sqrt(fmax(0.0, 1.0 - z * z));
    double phi = 2.399963229728653 * k + 0.3; /* the golden angle; offset off the axes */
    out[0] = r * cos(phi), out[1] = r * sin(phi), out[2] = z;
}

void meso_sh_rotation_init(const float frame[3][3], meso_sh_rotation *out_rotation) {
    memset(out_rotation, 0, sizeof *out_rotation);
    double ya[ROTATION_POINTS][MESO_SH_COUNT], yb[ROTATION_POINTS][MESO_SH_COUNT];
    for (int k = 0; k < ROTATION_POINTS; k++) {
        double d[3], md[3];
        fixed_direction(k, d);
        for (int r = 0; r < 3; r++)
            md[r] = frame[r][0] * d[0] + frame[r][1] * d[1] + frame[r][2] * d[2];
        basis_double(d, ya[k]);
        basis_double(md, yb[k]);
    }
    for (int l = 1; l < MESO_SH_ORDER; l++) {
        int n = 2 * l + 1, first = l * l;
        /* g = f(M .) has coefficients c' with sum_m c'_m Y_lm(d_k) = sum_m c_m Y_lm(M d_k) at
         * every direction d_k: A c' = B c with A[k][m] = Y_lm(d_k), B[k][m] = Y_lm(M d_k).
         * The band is closed under rotation, so the system is consistent and its
         * least-squares solution (A^T A) X = A^T B is the exact rotation matrix X. */
        double ata[7][7] = {{0}}, atb[7][7] = {{0}}, x[7][7];
        for (int k = 0; k < ROTATION_POINTS; k++)
            for (int r = 0; r < n; r++)
                for (int c = 0; c < n; c++) {
                    ata[r][c] += ya[k][first + r] * ya[k][first + c];
                    atb[r][c] += ya[k][first + r] * yb[k][first + c];
                }
        solve_square(n, ata, atb, x);
        for (int r = 0; r < n; r++)
            for (int c = 0; c < n; c++) {
                float v = (float)x[r][c];
                if (l == 1)
                    out_rotation->band1[r][c] = v;
                else if (l == 2)
                    out_rotation->band2[r][c] = v;
                else
                    out_rotation->band3[r][c] = v;
            }
    }
}

void meso_sh_rotate(const meso_sh_rotation *rotation, const float in[MESO_SH_COUNT],
                    float out[MESO_SH_COUNT]) {
    out[0] = in[0];
    for (int r = 0; r < 3; r++) {
        float s = 0.0f;
        for (int c = 0; c < 3; c++) s += rotation->band1[r][c] * in[1 + c];
        out[1 + r] = s;
    }
    for (int r = 0; r < 5; r++) {
        float s = 0.0f;
        for (int c = 0; c < 5; c++) s += rotation->band2[r][c] * in[4 + c];
        out[4 + r] = s;
    }
    for (int r = 0; r < 7; r++) {
        float s = 0.0f;
        for (int c = 0; c < 7; c++) s += rotation->band3[r][c] * in[9 + c];
        out[9 + r] = s;
    }
}
