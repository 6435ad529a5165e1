/* meso math: small vectors and 4x4 matrices, all static inline.
 *
 * Conventions: right-handed, y up. meso_mat4 is column-major (m[col*4 + row]) and multiplies
 * column vectors, as OpenGL. Names follow cglm's grammar: meso_<type>_<verb>, outputs returned
 * by value. Every function is pure and thread-safe.
 */
#ifndef MESO_MATH_H
#define MESO_MATH_H

#include <math.h>
#include <stdint.h>
#include <string.h>

typedef struct meso_vec2 {
    float x, y;
} meso_vec2;
typedef struct meso_vec3 {
    float x, y, z;
} meso_vec3;
typedef struct meso_vec4 {
    float x, y, z, w;
} meso_vec4;
typedef struct meso_mat4 {
    float m[16];
} meso_mat4;

/* pi for float arithmetic, its reciprocal, and pi in double for the bakes and shapes computed in
 * double (M_PI and M_1_PI are POSIX, not C; the float ones are the same bits as (float)M_PI). */
#define MESO_PI 3.14159265358979323846f
#define MESO_INV_PI 0.318309886183790671538f
#define MESO_PI_D 3.14159265358979323846

static inline meso_vec2 meso_vec2_make(float x, float y) { return (meso_vec2){x, y}; }
static inline meso_vec3 meso_vec3_make(float x, float y, float z) { return (meso_vec3){x, y, z}; }
static inline meso_vec3 meso_vec3_add(meso_vec3 a, meso_vec3 b) {
    return (meso_vec3){a.x + b.x, a.y + b.y, a.z + b.z};
}
static inline meso_vec3 meso_vec3_sub(meso_vec3 a, meso_vec3 b) {
    return (meso_vec3){a.x - b.x, a.y - b.y, a.z - b.z};
}
/* Component-wise product (colours: albedo times radiance). */
static inline meso_vec3 meso_vec3_mul(meso_vec3 a, meso_vec3 b) {
    return (meso_vec3){a.x * b.x, a.y * b.y, a.z * b.z};
}
static inline meso_vec3 meso_vec3_scale(meso_vec3 a, float s) {
    return (meso_vec3){a.x * s, a.y * s, a.z * s};
}
/* a + b * s */
static inline meso_vec3 meso_vec3_madd(meso_vec3 a, meso_vec3 b, float s) {
    return (meso_vec3){a.x + b.x * s, a.y + b.y * s, a.z + b.z * s};
}
static inline meso_vec3 meso_vec3_negate(meso_vec3 a) { return (meso_vec3){-a.x, -a.y, -a.z}; }
static inline float meso_vec3_dot(meso_vec3 a, meso_vec3 b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
static inline meso_vec3 meso_vec3_cross(meso_vec3 a, meso_vec3 b) {
    return (meso_vec3){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
static inline float meso_vec3_length(meso_vec3 a) { return sqrtf(meso_vec3_dot(a, a)); }
/* a / |a|; the zero vector stays zero. */
static inline meso_vec3 meso_vec3_normalize(meso_vec3 a) {
    float len2 = meso_vec3_dot(a, a);
    return len2 > 0.0f ? meso_vec3_scale(a, 1.0f / sqrtf(len2)) : a;
}
static inline meso_vec3 meso_vec3_lerp(meso_vec3 a, meso_vec3 b, float t) {
    return meso_vec3_madd(a, meso_vec3_sub(b, a), t);
}
/* b0*a + b1*b + b2*c: barycentric interpolation. */
static inline meso_vec3 meso_vec3_barycentric(meso_vec3 a, meso_vec3 b, meso_vec3 c, float b0,
                                              float b1, float b2) {
    return (meso_vec3){a.x * b0 + b.x * b1 + c.x * b2, a.y * b0 + b.y * b1 + c.y * b2,
                       a.z * b0 + b.z * b1 + c.z * b2};
}
static inline meso_vec2 meso_vec2_barycentric(meso_vec2 a, meso_vec2 b, meso_vec2 c, float b0,
                                              float b1, float b2) {
    return (meso_vec2){a.x * b0 + b.x * b1 + c.x * b2, a.y * b0 + b.y * b1 + c.y * b2};
}
static inline int meso_vec3_is_finite(meso_vec3 a) {
    return isfinite(a.x) && isfinite(a.y) && isfinite(a.z);
}
static inline float meso_clampf(float x, float lo, float hi) {
    return x < lo ? lo : (x > hi ? hi : x);
}

static inline meso_mat4 meso_mat4_identity(void) {
    return (meso_mat4){{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}};
}
static inline meso_mat4 meso_mat4_mul(meso_mat4 a, meso_mat4 b) {
    meso_mat4 r;
    for (int c = 0; c < 4; c++)
        for (int row = 0; row < 4; row++) {
            float s = 0.0f;
            for (int k = 0; k < 4; k++) s += a.m[k * 4 + row] * b.m[c * 4 + k];
            r.m[c * 4 + row] = s;
        }
    return r;
}
static inline meso_vec4 meso_mat4_mul_vec4(meso_mat4 a, meso_vec4 v) {
    return (meso_vec4){a.m[0] * v.x + a.m[4] * v.y + a.m[8] * v.z + a.m[12] * v.w,
                       a.m[1] * v.x + a.m[5] * v.y + a.m[9] * v.z + a.m[13] * v.w,
                       a.m[2] * v.x + a.m[6] * v.y + a.m[10] * v.z + a.m[14] * v.w,
                       a.m[3] * v.x + a.m[7] * v.y + a.m[11] * v.z + a.m[15] * v.w};
}
static inline meso_vec3 meso_mat4_transform_point(meso_mat4 a, meso_vec3 p) {
    meso_vec4 r = meso_mat4_mul_vec4(a, (meso_vec4){p.x, p.y, p.z, 1.0f});
    return (meso_vec3){r.x, r.y, r.z};
}
static inline meso_vec3 meso_mat4_transform_direction(meso_mat4 a, meso_vec3 d) {
    meso_vec4 r = meso_mat4_mul_vec4(a, (meso_vec4){d.x, d.y, d.z, 0.0f});
    return (meso_vec3){r.x, r.y, r.z};
}
static inline meso_mat4 meso_mat4_translate(meso_vec3 t) {
    meso_mat4 r = meso_mat4_identity();
    r.m[12] = t.x;
    r.m[13] = t.y;
    r.m[14] = t.z;
    return r;
}
static inline meso_mat4 meso_mat4_scale(float s) {
    meso_mat4 r = meso_mat4_identity();
    r.m[0] = r.m[5] = r.m[10] = s;
    return r;
}
/* Rotation by `radians` about the unit axis (x, y, z), right-handed. */
static inline meso_mat4 meso_mat4_rotate(meso_vec3 axis, float radians) {
    float c = cosf(radians), s = sinf(radians), t = 1.0f - c;
    float x = axis.x, y = axis.y, z = axis.z;
    return (meso_mat4){{t * x * x + c, t * x * y + s * z, t * x * z - s * y, 0, t * x * y - s * z,
                        t * y * y + c, t * y * z + s * x, 0, t * x * z + s * y, t * y * z - s * x,
                        t * z * z + c, 0, 0, 0, 0, 1}};
}
/* World-to-camera transform: the camera at eye looks down -z toward target. */
static inline meso_mat4 meso_mat4_look_at(meso_vec3 eye, meso_vec3 target, meso_vec3 up) {
    meso_vec3 f = meso_vec3_normalize(meso_vec3_sub(target, eye));
    meso_vec3 s = meso_vec3_normalize(meso_vec3_cross(f, up));
    meso_vec3 u = meso_vec3_cross(s, f);
    return (meso_mat4){{s.x, u.x, -f.x, 0, s.y, u.y, -f.y, 0, s.z, u.z, -f.z, 0,
                        -meso_vec3_dot(s, eye), -meso_vec3_dot(u, eye), meso_vec3_dot(f, eye), 1}};
}
/* OpenGL perspective projection: clip w = view-space distance in front of the camera. */
static inline meso_mat4 meso_mat4_perspective(float fov_y_radians, float aspect, float z_near,
                                              float z_far) {
    float f = 1.0f / tanf(0.5f * fov_y_radians);
    meso_mat4 r = {{0}};
    r.m[0] = f / aspect;
    r.m[5] = f;
    r.m[10] = (z_far + z_near) / (z_near - z_far);
    r.m[11] = -1.0f;
    r.m[14] = 2.0f * z_far * z_near / (z_near - z_far);
    return r;
}
/* The inverse transpose of the upper 3x3, for normals (returned as a 4x4 with no translation). */
static inline meso_mat4 meso_mat4_normal_matrix(meso_mat4 a) {
    float a00 = a.m[0], a01 = a.m[4], a02 = a.m[8];
    float a10 = a.m[1], a11 = a.m[5], a12 = a.m[9];
    float a20 = a.m[2], a21 = a.m[6], a22 = a.m[10];
    float c00 = a11 * a22 - a12 * a21, c01 = a12 * a20 - a10 * a22, c02 = a10 * a21 - a11 * a20;
    float c10 = a02 * a21 - a01 * a22, c11 = a00 * a22 - a02 * a20, c12 = a01 * a20 - a00 * a21;
    float c20 = a01 * a12 - a02 * a11, c21 = a02 * a10 - a00 * a12, c22 = a00 * a11 - a01 * a10;
    float det = a00 * c00 + a01 * c01 + a02 * c02;
    float inv = det != 0.0f ? 1.0f / det : 0.0f;
    /* inverse = cofactor^T / det; its transpose = cofactor / det */
    return (meso_mat4){{c00 * inv, c10 * inv, c20 * inv, 0, c01 * inv, c11 * inv, c21 * inv, 0,
                        c02 * inv, c12 * inv, c22 * inv, 0, 0, 0, 0, 1}};
}

/* ---- Multilinear lookups of sampled tables (the VDM, GDM and RTV bakes and their techniques) */

/* One axis of a multilinear lookup: lower index, upper index, weight of the upper. */
typedef struct meso_axis {
    int i0, i1;
    float w;
} meso_axis;

/* Sample position x in [0, n - 1] clamped at both ends. */
static inline meso_axis meso_axis_clamp(float x, int n) {
    if (n <= 1 || x <= 0.0f) return (meso_axis){0, 0, 0.0f};
    if (x >= (float)(n - 1)) return (meso_axis){n - 1, n - 1, 0.0f};
    int i = (int)x;
    return (meso_axis){i, i + 1, x - (float)i};
}
/* Sample position x wrapped with period n (x finite, |x| far below 2^31). */
static inline meso_axis meso_axis_wrap(float x, int n) {
    float f = floorf(x);
    int i = (int)f % n;
    i += i < 0 ? n : 0;
    return (meso_axis){i, i + 1 == n ? 0 : i + 1, x - f};
}

/* sRGB transfer functions (IEC 61966-2-1). */
static inline float meso_srgb_to_linear(float c) {
    return c <= 0.04045f ? c / 12.92f : powf((c + 0.055f) / 1.055f, 2.4f);
}
static inline float meso_linear_to_srgb(float c) {
    return c <= 0.0031308f ? c * 12.92f : 1.055f * powf(c, 1.0f / 2.4f) - 0.055f;
}

/* IEEE 754 binary16 ("half") bits to and from float, rounding to nearest even, in plain integer
 * arithmetic: the same bits from every compiler and CPU (GCC's _Float16, clang 14 has none on
 * x86-64; F16C's vcvtps2ph gives the same bits, a test says so). Infinities stay infinite,
 * values past the largest half (65504, rounding) become infinite, NaN stays a quiet NaN. */
static inline uint16_t meso_half_from_float(float value) {
    uint32_t bits;
    memcpy(&bits, &value, sizeof(bits));
    uint16_t sign = (uint16_t)((bits >> 16) & 0x8000u);
    uint32_t magnitude = bits & 0x7fffffffu;
    if (magnitude >= 0x7f800000u) /* Inf, NaN (payload's top bits kept, made quiet) */
        return (uint16_t)(sign | 0x7c00u |
                          (magnitude > 0x7f800000u ? 0x200u | ((magnitude >> 13) & 0x3ffu) : 0));
    if (magnitude >= 0x477ff000u) return (uint16_t)(sign | 0x7c00u); /* rounds past 65504 */
    if (magnitude >= 0x38800000u) { /* normal: rebias the exponent (127 - 15), round 13 bits */
        uint32_t rebiased = magnitude - 0x38000000u;
        return (uint16_t)(sign | ((rebiased + 0xfffu + ((rebiased >> 13) & 1u)) >> 13));
    }
    /* subnormal half: value / 2^-24 rounded to nearest even */
    int shift = 126 - (int)(magnitude >> 23);
    if (shift > 24) return sign;
    uint32_t mantissa = (magnitude & 0x7fffffu) | 0x800000u;
    uint32_t result = mantissa >> shift, rest = mantissa & ((1u << shift) - 1u);
    uint32_t halfway = 1u << (shift - 1);
    if (rest > halfway || (rest == halfway && (result & 1u))) result++;
    return (uint16_t)(sign | result);
}
static inline float meso_half_to_float(uint16_t half) {
    uint32_t sign = (uint32_t)(half & 0x8000u) << 16;
    uint32_t exponent = (half >> 10) & 0x1fu, mantissa = half & 0x3ffu, bits;
    if (exponent == 0x1fu) {
        bits = sign | 0x7f800000u | (mantissa << 13);
    } else if (exponent) {
        bits = sign | ((exponent + 112u) << 23) | (mantissa << 13);
    } else { /* zero or subnormal: mantissa * 2^-24, exact in float */
        float magnitude = (float)mantissa * 0x1p-24f;
        memcpy(&bits, &magnitude, sizeof(bits));
        bits |= sign;
    }
    float value;
    memcpy(&value, &bits, sizeof(value));
    return value;
}

#endif
