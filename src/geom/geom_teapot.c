/* The Utah teapot: Martin Newell's 32 bicubic Bezier patches (1975, public domain), the
 * classic 306 control points, tessellated per patch.
 *
 * The data is z-up with the spout toward +x; meso is y-up, so (x, y, z) -> (x, z, -y), a
 * rotation that keeps the spout at +x and the handle at -x. Each patch is a 4x4 grid of control
 * points, row r and column c; P(s, t) with s along the rows and t along the columns. For every
 * patch of this data dP/dt x dP/ds points out of the pot, so UVs (u, v) = (1 - t, 1 - s) give
 * T x B = N (docs/design.md) and, on the body, v grows upward.
 *
 * No cracks: neighbouring patches share their border control points, and the evaluation below
 * returns bit-identical positions for a shared border whichever patch evaluates it (exact
 * endpoints, and a curve evaluated from its nearer end, see bezier_point).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geom_internal.h"
#include "meso/runtime.h"

#define TEAPOT_PATCHES 32

/* Control points, 1-based in the patch table below, as in Newell's listing. */
static const float teapot_points[306][3] = {
    {1.4f, 0.0f, 2.4f},
    {1.4f, -0.784f, 2.4f},
    {0.784f, -1.4f, 2.4f},
    {0.0f, -1.4f, 2.4f},
    {1.3375f, 0.0f, 2.53125f},
    {1.3375f, -0.749f, 2.53125f},
    {0.749f, -1.3375f, 2.53125f},
    {0.0f, -1.3375f, 2.53125f},
    {1.4375f, 0.0f, 2.53125f},
    {1.4375f, -0.805f, 2.53125f},
    {0.805f, -1.4375f, 2.53125f},
    {0.0f, -1.4375f, 2.53125f},
    {1.5f, 0.0f, 2.4f},
    {1.5f, -0.84f, 2.4f},
    {0.84f, -1.5f, 2.4f},
    {0.0f, -1.5f, 2.4f},
    /* 17 */
    {-0.784f, -1.4f, 2.4f},
    {-1.4f, -0.784f, 2.4f},
    {-1.4f, 0.0f, 2.4f},
    {-0.749f, -1.3375f, 2.53125f},
    {-1.3375f, -0.749f, 2.53125f},
    {-1.3375f, 0.0f, 2.53125f},
    {-0.805f, -1.4375f, 2.53125f},
    {-1.4375f, -0.805f, 2.53125f},
    {-1.4375f, 0.0f, 2.53125f},
    {-0.84f, -1.5f, 2.4f},
    {-1.5f, -0.84f, 2.4f},
    {-1.5f, 0.0f, 2.4f},
    /* 29 */
    {-1.4f, 0.784f, 2.4f},
    {-0.784f, 1.4f, 2.4f},
    {0.0f, 1.4f, 2.4f},
    {-1.3375f, 0.749f, 2.53125f},
    {-0.749f, 1.3375f, 2.53125f},
    {0.0f, 1.3375f, 2.53125f},
    {-1.4375f, 0.805f, 2.53125f},
    {-0.805f, 1.4375f, 2.53125f},
    {0.0f, 1.4375f, 2.53125f},
    {-1.5f, 0.84f, 2.4f},
    {-0.84f, 1.5f, 2.4f},
    {0.0f, 1.5f, 2.4f},
    /* 41 */
    {0.784f, 1.4f, 2.4f},
    {1.4f, 0.784f, 2.4f},
    {0.749f, 1.3375f, 2.53125f},
    {1.3375f, 0.749f, 2.53125f},
    {0.805f, 1.4375f, 2.53125f},
    {1.4375f, 0.805f, 2.53125f},
    {0.84f, 1.5f, 2.4f},
    {1.5f, 0.84f, 2.4f},
    /* 49 */
    {1.75f, 0.0f, 1.875f},
    {1.75f, -0.98f, 1.875f},
    {0.98f, -1.75f, 1.875f},
    {0.0f, -1.75f, 1.875f},
    {2.0f, 0.0f, 1.35f},
    {2.0f, -1.12f, 1.35f},
    {1.12f, -2.0f, 1.35f},
    {0.0f, -2.0f, 1.35f},
    {2.0f, 0.0f, 0.9f},
    {2.0f, -1.12f, 0.9f},
    {1.12f, -2.0f, 0.9f},
    {0.0f, -2.0f, 0.9f},
    /* 61 */
    {-0.98f, -1.75f, 1.875f},
    {-1.75f, -0.98f, 1.875f},
    {-1.75f, 0.0f, 1.875f},
    {-1.12f, -2.0f, 1.35f},
    {-2.0f, -1.12f, 1.35f},
    {-2.0f, 0.0f, 1.35f},
    {-1.12f, -2.0f, 0.9f},
    {-2.0f, -1.12f, 0.9f},
    {-2.0f, 0.0f, 0.9f},
    /* 70 */
    {-1.75f, 0.98f, 1.875f},
    {-0.98f, 1.75f, 1.875f},
    {0.0f, 1.75f, 1.875f},
    {-2.0f, 1.12f, 1.35f},
    {-1.12f, 2.0f, 1.35f},
    {0.0f, 2.0f, 1.35f},
    {-2.0f, 1.12f, 0.9f},
    {-1.12f, 2.0f, 0.9f},
    {0.0f, 2.0f, 0.9f},
    /* 79 */
    {0.98f, 1.75f, 1.875f},
    {1.75f, 0.98f, 1.875f},
    {1.12f, 2.0f, 1.35f},
    {2.0f, 1.12f, 1.35f},
    {1.12f, 2.0f, 0.9f},
    {2.0f, 1.12f, 0.9f},
    /* 85 */
    {2.0f, 0.0f, 0.45f},
    {2.0f, -1.12f, 0.45f},
    {1.12f, -2.0f, 0.45f},
    {0.0f, -2.0f, 0.45f},
    {1.5f, 0.0f, 0.225f},
    {1.5f, -0.84f, 0.225f},
    {0.84f, -1.5f, 0.225f},
    {0.0f, -1.5f, 0.225f},
    {1.5f, 0.0f, 0.15f},
    {1.5f, -0.84f, 0.15f},
    {0.84f, -1.5f, 0.15f},
    {0.0f, -1.5f, 0.15f},
    /* 97 */
    {-1.12f, -2.0f, 0.45f},
    {-2.0f, -1.12f, 0.45f},
    {-2.0f, 0.0f, 0.45f},
    {-0.84f, -1.5f, 0.225f},
    {-1.5f, -0.84f, 0.225f},
    {-1.5f, 0.0f, 0.225f},
    {-0.84f, -1.5f, 0.15f},
    {-1.5f, -0.84f, 0.15f},
    {-1.5f, 0.0f, 0.15f},
    /* 106 */
    {-2.0f, 1.12f, 0.45f},
    {-1.12f, 2.0f, 0.45f},
    {0.0f, 2.0f, 0.45f},
    {-1.5f, 0.84f, 0.225f},
    {-0.84f, 1.5f, 0.225f},
    {0.0f, 1.5f, 0.225f},
    {-1.5f, 0.84f, 0.15f},
    {-0.84f, 1.5f, 0.15f},
    {0.0f, 1.5f, 0.15f},
    /* 115 */
    {1.12f, 2.0f, 0.45f},
    {2.0f, 1.12f, 0.45f},
    {0.84f, 1.5f, 0.225f},
    {1.5f, 0.84f, 0.225f},
    {0.84f, 1.5f, 0.15f},
    {1.5f, 0.84f, 0.15f},
    /* 121: handle */
    {-1.6f, 0.0f, 2.025f},
    {-1.6f, -0.3f, 2.025f},
    {-1.5f, -0.3f, 2.25f},
    {-1.5f, 0.0f, 2.25f},
    {-2.3f, 0.0f, 2.025f},
    {-2.3f, -0.3f, 2.025f},
    {-2.5f, -0.3f, 2.25f},
    {-2.5f, 0.0f, 2.25f},
    {-2.7f, 0.0f, 2.025f},
    {-2.7f, -0.3f, 2.025f},
    {-3.0f, -0.3f, 2.25f},
    {-3.0f, 0.0f, 2.25f},
    {-2.7f, 0.0f, 1.8f},
    {-2.7f, -0.3f, 1.8f},
    {-3.0f, -0.3f, 1.8f},
    {-3.0f, 0.0f, 1.8f},
    /* 137 */
    {-1.5f, 0.3f, 2.25f},
    {-1.6f, 0.3f, 2.025f},
    {-2.5f, 0.3f, 2.25f},
    {-2.3f, 0.3f, 2.025f},
    {-3.0f, 0.3f, 2.25f},
    {-2.7f, 0.3f, 2.025f},
    {-3.0f, 0.3f, 1.8f},
    {-2.7f, 0.3f, 1.8f},
    /* 145 */
    {-2.7f, 0.0f, 1.575f},
    {-2.7f, -0.3f, 1.575f},
    {-3.0f, -0.3f, 1.35f},
    {-3.0f, 0.0f, 1.35f},
    {-2.5f, 0.0f, 1.125f},
    {-2.5f, -0.3f, 1.125f},
    {-2.65f, -0.3f, 0.9375f},
    {-2.65f, 0.0f, 0.9375f},
    {-2.0f, -0.3f, 0.9f},
    {-1.9f, -0.3f, 0.6f},
    {-1.9f, 0.0f, 0.6f},
    /* 156 */
    {-3.0f, 0.3f, 1.35f},
    {-2.7f, 0.3f, 1.575f},
    {-2.65f, 0.3f, 0.9375f},
    {-2.5f, 0.3f, 1.125f},
    {-1.9f, 0.3f, 0.6f},
    {-2.0f, 0.3f, 0.9f},
    /* 162: spout */
    {1.7f, 0.0f, 1.425f},
    {1.7f, -0.66f, 1.425f},
    {1.7f, -0.66f, 0.6f},
    {1.7f, 0.0f, 0.6f},
    {2.6f, 0.0f, 1.425f},
    {2.6f, -0.66f, 1.425f},
    {3.1f, -0.66f, 0.825f},
    {3.1f, 0.0f, 0.825f},
    {2.3f, 0.0f, 2.1f},
    {2.3f, -0.25f, 2.1f},
    {2.4f, -0.25f, 2.025f},
    {2.4f, 0.0f, 2.025f},
    {2.7f, 0.0f, 2.4f},
    {2.7f, -0.25f, 2.4f},
    {3.3f, -0.25f, 2.4f},
    {3.3f, 0.0f, 2.4f},
    /* 178 */
    {1.7f, 0.66f, 0.6f},
    {1.7f, 0.66f, 1.425f},
    {3.1f, 0.66f, 0.825f},
    {2.6f, 0.66f, 1.425f},
    {2.4f, 0.25f, 2.025f},
    {2.3f, 0.25f, 2.1f},
    {3.3f, 0.25f, 2.4f},
    {2.7f, 0.25f, 2.4f},
    /* 186 */
    {2.8f, 0.0f, 2.475f},
    {2.8f, -0.25f, 2.475f},
    {3.525f, -0.25f, 2.49375f},
    {3.525f, 0.0f, 2.49375f},
    {2.9f, 0.0f, 2.475f},
    {2.9f, -0.15f, 2.475f},
    {3.45f, -0.15f, 2.5125f},
    {3.45f, 0.0f, 2.5125f},
    {2.8f, 0.0f, 2.4f},
    {2.8f, -0.15f, 2.4f},
    {3.2f, -0.15f, 2.4f},
    {3.2f, 0.0f, 2.4f},
    /* 198 */
    {3.525f, 0.25f, 2.49375f},
    {2.8f, 0.25f, 2.475f},
    {3.45f, 0.15f, 2.5125f},
    {2.9f, 0.15f, 2.475f},
    {3.2f, 0.15f, 2.4f},
    {2.8f, 0.15f, 2.4f},
    /* 204: lid */
    {0.0f, 0.0f, 3.15f},
    {0.0f, -0.002f, 3.15f},
    {0.002f, 0.0f, 3.15f},
    {0.8f, 0.0f, 3.15f},
    {0.8f, -0.45f, 3.15f},
    {0.45f, -0.8f, 3.15f},
    {0.0f, -0.8f, 3.15f},
    {0.0f, 0.0f, 2.85f},
    {0.2f, 0.0f, 2.7f},
    {0.2f, -0.112f, 2.7f},
    {0.112f, -0.2f, 2.7f},
    {0.0f, -0.2f, 2.7f},
    /* 216 */
    {0.002f, 0.0f, 3.15f},
    {-0.45f, -0.8f, 3.15f},
    {-0.8f, -0.45f, 3.15f},
    {-0.8f, 0.0f, 3.15f},
    {-0.112f, -0.2f, 2.7f},
    {-0.2f, -0.112f, 2.7f},
    {-0.2f, 0.0f, 2.7f},
    /* 223 */
    {0.0f, 0.002f, 3.15f},
    {-0.8f, 0.45f, 3.15f},
    {-0.45f, 0.8f, 3.15f},
    {0.0f, 0.8f, 3.15f},
    {-0.2f, 0.112f, 2.7f},
    {-0.112f, 0.2f, 2.7f},
    {0.0f, 0.2f, 2.7f},
    /* 230 */
    {0.45f, 0.8f, 3.15f},
    {0.8f, 0.45f, 3.15f},
    {0.112f, 0.2f, 2.7f},
    {0.2f, 0.112f, 2.7f},
    /* 234 */
    {0.4f, 0.0f, 2.55f},
    {0.4f, -0.224f, 2.55f},
    {0.224f, -0.4f, 2.55f},
    {0.0f, -0.4f, 2.55f},
    {1.3f, 0.0f, 2.55f},
    {1.3f, -0.728f, 2.55f},
    {0.728f, -1.3f, 2.55f},
    {0.0f, -1.3f, 2.55f},
    {1.3f, 0.0f, 2.4f},
    {1.3f, -0.728f, 2.4f},
    {0.728f, -1.3f, 2.4f},
    {0.0f, -1.3f, 2.4f},
    /* 246 */
    {-0.224f, -0.4f, 2.55f},
    {-0.4f, -0.224f, 2.55f},
    {-0.4f, 0.0f, 2.55f},
    {-0.728f, -1.3f, 2.55f},
    {-1.3f, -0.728f, 2.55f},
    {-1.3f, 0.0f, 2.55f},
    {-0.728f, -1.3f, 2.4f},
    {-1.3f, -0.728f, 2.4f},
    {-1.3f, 0.0f, 2.4f},
    /* 255 */
    {-0.4f, 0.224f, 2.55f},
    {-0.224f, 0.4f, 2.55f},
    {0.0f, 0.4f, 2.55f},
    {-1.3f, 0.728f, 2.55f},
    {-0.728f, 1.3f, 2.55f},
    {0.0f, 1.3f, 2.55f},
    {-1.3f, 0.728f, 2.4f},
    {-0.728f, 1.3f, 2.4f},
    {0.0f, 1.3f, 2.4f},
    /* 264 */
    {0.224f, 0.4f, 2.55f},
    {0.4f, 0.224f, 2.55f},
    {0.728f, 1.3f, 2.55f},
    {1.3f, 0.728f, 2.55f},
    {0.728f, 1.3f, 2.4f},
    {1.3f, 0.728f, 2.4f},
    /* 270: bottom */
    {0.0f, 0.0f, 0.0f},
    {1.5f, 0.0f, 0.15f},
    {1.5f, 0.84f, 0.15f},
    {0.84f, 1.5f, 0.15f},
    {0.0f, 1.5f, 0.15f},
    {1.5f, 0.0f, 0.075f},
    {1.5f, 0.84f, 0.075f},
    {0.84f, 1.5f, 0.075f},
    {0.0f, 1.5f, 0.075f},
    {1.425f, 0.0f, 0.0f},
    {1.425f, 0.798f, 0.0f},
    {0.798f, 1.425f, 0.0f},
    {0.0f, 1.425f, 0.0f},
    /* 283 */
    {-0.84f, 1.5f, 0.15f},
    {-1.5f, 0.84f, 0.15f},
    {-1.5f, 0.0f, 0.15f},
    {-0.84f, 1.5f, 0.075f},
    {-1.5f, 0.84f, 0.075f},
    {-1.5f, 0.0f, 0.075f},
    {-0.798f, 1.425f, 0.0f},
    {-1.425f, 0.798f, 0.0f},
    {-1.425f, 0.0f, 0.0f},
    /* 292 */
    {-1.5f, -0.84f, 0.15f},
    {-0.84f, -1.5f, 0.15f},
    {0.0f, -1.5f, 0.15f},
    {-1.5f, -0.84f, 0.075f},
    {-0.84f, -1.5f, 0.075f},
    {0.0f, -1.5f, 0.075f},
    {-1.425f, -0.798f, 0.0f},
    {-0.798f, -1.425f, 0.0f},
    {0.0f, -1.425f, 0.0f},
    /* 301 */
    {0.84f, -1.5f, 0.15f},
    {1.5f, -0.84f, 0.15f},
    {0.84f, -1.5f, 0.075f},
    {1.5f, -0.84f, 0.075f},
    {0.798f, -1.425f, 0.0f},
    {1.425f, -0.798f, 0.0f},
};

/* The 32 patches: 16 control point numbers each (1-based), row by row. */
static const unsigned short teapot_patches[TEAPOT_PATCHES][16] = {
    /* rim */
    {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16},
    {4, 17, 18, 19, 8, 20, 21, 22, 12, 23, 24, 25, 16, 26, 27, 28},
    {19, 29, 30, 31, 22, 32, 33, 34, 25, 35, 36, 37, 28, 38, 39, 40},
    {31, 41, 42, 1, 34, 43, 44, 5, 37, 45, 46, 9, 40, 47, 48, 13},
    /* upper body */
    {13, 14, 15, 16, 49, 50, 51, 52, 53, 54, 55, 56, 57, 58, 59, 60},
    {16, 26, 27, 28, 52, 61, 62, 63, 56, 64, 65, 66, 60, 67, 68, 69},
    {28, 38, 39, 40, 63, 70, 71, 72, 66, 73, 74, 75, 69, 76, 77, 78},
    {40, 47, 48, 13, 72, 79, 80, 49, 75, 81, 82, 53, 78, 83, 84, 57},
    /* lower body */
    {57, 58, 59, 60, 85, 86, 87, 88, 89, 90, 91, 92, 93, 94, 95, 96},
    {60, 67, 68, 69, 88, 97, 98, 99, 92, 100, 101, 102, 96, 103, 104, 105},
    {69, 76, 77, 78, 99, 106, 107, 108, 102, 109, 110, 111, 105, 112, 113, 114},
    {78, 83, 84, 57, 108, 115, 116, 85, 111, 117, 118, 89, 114, 119, 120, 93},
    /* handle */
    {121, 122, 123, 124, 125, 126, 127, 128, 129, 130, 131, 132, 133, 134, 135, 136},
    {124, 137, 138, 121, 128, 139, 140, 125, 132, 141, 142, 129, 136, 143, 144, 133},
    {133, 134, 135, 136, 145, 146, 147, 148, 149, 150, 151, 152, 69, 153, 154, 155},
    {136, 143, 144, 133, 148, 156, 157, 145, 152, 158, 159, 149, 155, 160, 161, 69},
    /* spout */
    {162, 163, 164, 165, 166, 167, 168, 169, 170, 171, 172, 173, 174, 175, 176, 177},
    {165, 178, 179, 162, 169, 180, 181, 166, 173, 182, 183, 170, 177, 184, 185, 174},
    {174, 175, 176, 177, 186, 187, 188, 189, 190, 191, 192, 193, 194, 195, 196, 197},
    {177, 184, 185, 174, 189, 198, 199, 186, 193, 200, 201, 190, 197, 202, 203, 194},
    /* lid knob */
    {204, 204, 204, 204, 207, 208, 209, 210, 211, 211, 211, 211, 212, 213, 214, 215},
    {204, 204, 204, 204, 210, 217, 218, 219, 211, 211, 211, 211, 215, 220, 221, 222},
    {204, 204, 204, 204, 219, 224, 225, 226, 211, 211, 211, 211, 222, 227, 228, 229},
    {204, 204, 204, 204, 226, 230, 231, 207, 211, 211, 211, 211, 229, 232, 233, 212},
    /* lid */
    {212, 213, 214, 215, 234, 235, 236, 237, 238, 239, 240, 241, 242, 243, 244, 245},
    {215, 220, 221, 222, 237, 246, 247, 248, 241, 249, 250, 251, 245, 252, 253, 254},
    {222, 227, 228, 229, 248, 255, 256, 257, 251, 258, 259, 260, 254, 261, 262, 263},
    {229, 232, 233, 212, 257, 264, 265, 234, 260, 266, 267, 238, 263, 268, 269, 242},
    /* bottom */
    {270, 270, 270, 270, 279, 280, 281, 282, 275, 276, 277, 278, 271, 272, 273, 274},
    {270, 270, 270, 270, 282, 289, 290, 291, 278, 286, 287, 288, 274, 283, 284, 285},
    {270, 270, 270, 270, 291, 298, 299, 300, 288, 295, 296, 297, 285, 292, 293, 294},
    {270, 270, 270, 270, 300, 305, 306, 279, 297, 303, 304, 275, 294, 301, 302, 271},
};

/* Samples per patch side for the bounding box used to centre the pot: independent of the
 * tessellation, so the placement does not move with `segments`. */
#define BOUNDS_SAMPLES 32

typedef struct dpoint {
    double v[3];
} dpoint;

/* The point at t = k / n of the cubic Bezier curve p[0..3], bit-identical for the same curve
 * given in reverse order at n - k: endpoints are returned as they are, the midpoint uses a
 * symmetric sum, and other parameters are evaluated (de Casteljau, a + t (b - a), which keeps
 * equal control points exactly equal) from the nearer end. */
static dpoint bezier_point(const dpoint p[4], int k, int n) {
    if (k == 0) return p[0];
    if (k == n) return p[3];
    if (memcmp(&p[0], &p[1], sizeof(dpoint)) == 0 && memcmp(&p[0], &p[2], sizeof(dpoint)) == 0 &&
        memcmp(&p[0], &p[3], sizeof(dpoint)) == 0)
        return p[0]; /* a collapsed row (the knob's top, the bottom's centre) */
    dpoint r;
    if (2 * k == n) {
        for (int c = 0; c < 3; c++)
            r.v[c] = ((p[0].v[c] + p[3].v[c]) + 3.0 * (p[1].v[c] + p[2].v[c])) * 0.125;
        return r;
    }
    dpoint q[4];
    double t;
    if (2 * k < n) {
        for (int i = 0; i < 4; i++) q[i] = p[i];
        t = (double)k / n;
    } else {
        for (int i = 0; i < 4; i++) q[i] = p[3 - i];
        t = (double)(n - k) / n;
    }
    for (int level = 3; level > 0; level--)
        for (int i = 0; i < level; i++)
            for (int c = 0; c < 3; c++) q[i].v[c] = q[i].v[c] + t * (q[i + 1].v[c] - q[i].v[c]);
    return q[0];
}

static void load_patch(int patch, dpoint out[4][4]) {
    for (int r = 0; r < 4; r++)
        for (int c = 0; c < 4; c++) {
            const float *p = teapot_points[teapot_patches[patch][4 * r + c] - 1];
            out[r][c] = (dpoint){{p[0], p[1], p[2]}};
        }
}

/* P(s, t) at s = ks / n, t = kt / n: first along each row (t), then down the column of results
 * (s). A border s = 0 or 1 is then one row's curve and a border t = 0 or 1 the curve of one
 * column's points, exactly as the neighbouring patch evaluates it. */
static dpoint patch_point(const dpoint cp[4][4], int ks, int kt, int n) {
    dpoint column[4];
    for (int r = 0; r < 4; r++) column[r] = bezier_point(cp[r], kt, n);
    return bezier_point(column, ks, n);
}

static void bernstein(double t, double b[4], double db[4]) {
    double s = 1.0 - t;
    b[0] = s * s * s, b[1] = 3.0 * t * s * s, b[2] = 3.0 * t * t * s, b[3] = t * t * t;
    db[0] = -3.0 * s * s, db[1] = 3.0 * s * s - 6.0 * t * s, db[2] = 6.0 * t * s - 3.0 * t * t;
    db[3] = 3.0 * t * t;
}

/* dP/dt x dP/ds at (s, t) (outward for this data, see the file comment), not normalised. */
static dpoint patch_cross(const dpoint cp[4][4], double s, double t) {
    double bs[4], dbs[4], bt[4], dbt[4];
    bernstein(s, bs, dbs);
    bernstein(t, bt, dbt);
    double ds[3] = {0, 0, 0}, dt[3] = {0, 0, 0};
    for (int r = 0; r < 4; r++)
        for (int c = 0; c < 4; c++)
            for (int k = 0; k < 3; k++) {
                ds[k] += dbs[r] * bt[c] * cp[r][c].v[k];
                dt[k] += bs[r] * dbt[c] * cp[r][c].v[k];
            }
    return (dpoint){{dt[1] * ds[2] - dt[2] * ds[1], dt[2] * ds[0] - dt[0] * ds[2],
                     dt[0] * ds[1] - dt[1] * ds[0]}};
}

static double length3(dpoint a) {
    return sqrt(a.v[0] * a.v[0] + a.v[1] * a.v[1] + a.v[2] * a.v[2]);
}

/* Unit outward normal (z-up data frame). Where a whole border row collapses to a point (the lid
 * knob's top, the bottom's centre) dP/dt vanishes; the limit of the normal is taken a tiny
 * step inside the patch instead. */
static dpoint patch_normal(const dpoint cp[4][4], double s, double t) {
    dpoint n = patch_cross(cp, s, t);
    double len = length3(n);
    const double step = 1e-4;
    for (int attempt = 0; attempt < 3 && !(len > 1e-9); attempt++) {
        double scale = (double)(attempt + 1);
        double s2 = s < 0.5 ? s + step * scale : s - step * scale;
        double t2 = t < 0.5 ? t + step * scale : t - step * scale;
        n = patch_cross(cp, s2, attempt == 0 ? t : t2);
        len = length3(n);
    }
    if (!(len > 0.0)) return (dpoint){{0.0, 0.0, 1.0}};
    for (int k = 0; k < 3; k++) n.v[k] /= len;
    return n;
}

/* Data frame (z up) -> meso (y up): (x, y, z) -> (x, z, -y). */
static meso_vec3 to_y_up(const double v[3], double scale, const double offset[3]) {
    return meso_vec3_make((float)(v[0] * scale + offset[0]), (float)(v[2] * scale + offset[1]),
                          (float)(-v[1] * scale + offset[2]));
}

static bool same_position(meso_vec3 a, meso_vec3 b) {
    return a.x == b.x && a.y == b.y && a.z == b.z;
}

meso_result geom_create_teapot(meso_context *ctx, const meso_shape_desc *desc,
                               meso_mesh **out_mesh) {
    *out_mesh = NULL;
    int n = desc->segments;
    size_t per_patch = (size_t)(n + 1) * (size_t)(n + 1);
    uint64_t max_vertices = (uint64_t)TEAPOT_PATCHES * per_patch;
    uint64_t max_triangles = (uint64_t)TEAPOT_PATCHES * 2u * (uint64_t)n * (uint64_t)n;
    meso_result r = geom_check_counts(ctx, "teapot", max_vertices, max_triangles);
    if (r != MESO_OK) return r;

    /* Bounds in the y-up frame from a fixed sampling: height -> size, box centred. */
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    const double zero[3] = {0, 0, 0};
    for (int patch = 0; patch < TEAPOT_PATCHES; patch++) {
        dpoint cp[4][4];
        load_patch(patch, cp);
        for (int ks = 0; ks <= BOUNDS_SAMPLES; ks++)
            for (int kt = 0; kt <= BOUNDS_SAMPLES; kt++) {
                dpoint p = patch_point(cp, ks, kt, BOUNDS_SAMPLES);
                double y_up[3] = {p.v[0], p.v[2], -p.v[1]};
                for (int c = 0; c < 3; c++)
                    lo[c] = fmin(lo[c], y_up[c]), hi[c] = fmax(hi[c], y_up[c]);
            }
    }
    double scale = desc->size / (hi[1] - lo[1]);
    double offset[3];
    for (int c = 0; c < 3; c++) offset[c] = -0.5 * (lo[c] + hi[c]) * scale;

    meso_vec3 *positions = malloc(max_vertices * sizeof(meso_vec3));
    meso_vec3 *normals = malloc(max_vertices * sizeof(meso_vec3));
    meso_vec2 *uvs = malloc(max_vertices * sizeof(meso_vec2));
    uint32_t *indices = malloc(3 * max_triangles * sizeof(uint32_t));
    meso_mesh *mesh = NULL;
    if (!positions || !normals || !uvs || !indices) {
        r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "teapot: out of memory");
        goto fail;
    }

    size_t num_triangles = 0;
    for (int patch = 0; patch < TEAPOT_PATCHES; patch++) {
        dpoint cp[4][4];
        load_patch(patch, cp);
        uint32_t base = (uint32_t)(patch * per_patch);
        /* Vertex (i, j) has u = i / n = 1 - t and v = j / n = 1 - s. */
        for (int j = 0; j <= n; j++)
            for (int i = 0; i <= n; i++) {
                size_t index = base + (size_t)j * (n + 1) + i;
                dpoint p = patch_point(cp, n - j, n - i, n);
                dpoint nn = patch_normal(cp, (double)(n - j) / n, (double)(n - i) / n);
                positions[index] = to_y_up(p.v, scale, offset);
                normals[index] = meso_vec3_normalize(to_y_up(nn.v, 1.0, zero));
                uvs[index] = meso_vec2_make((float)i / n, (float)j / n);
            }
        /* Counter-clockwise in (u, v) is counter-clockwise from outside. Triangles that a
         * collapsed border row makes degenerate (two corners at one point) are left out. */
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                uint32_t a = base + (uint32_t)(j * (n + 1) + i), b = a + 1;
                uint32_t d = a + (uint32_t)(n + 1), c = d + 1;
                uint32_t tris[2][3] = {{a, b, c}, {a, c, d}};
                for (int k = 0; k < 2; k++) {
                    meso_vec3 p0 = positions[tris[k][0]], p1 = positions[tris[k][1]],
                              p2 = positions[tris[k][2]];
                    if (same_position(p0, p1) || same_position(p1, p2) || same_position(p0, p2))
                        continue;
                    memcpy(indices + 3 * num_triangles, tris[k], sizeof(tris[k]));
                    num_triangles++;
                }
            }
    }

    r = meso_mesh_create(ctx, (size_t)max_vertices, num_triangles, true, &mesh);
    if (r != MESO_OK) goto fail;
    memcpy(mesh->positions, positions, max_vertices * sizeof(meso_vec3));
    memcpy(mesh->normals, normals, max_vertices * sizeof(meso_vec3));
    memcpy(mesh->uvs, uvs, max_vertices * sizeof(meso_vec2));
    memcpy(mesh->indices, indices, 3 * num_triangles * sizeof(uint32_t));
    r = meso_mesh_compute_tangents(ctx, mesh);
    if (r != MESO_OK) goto fail;
    *out_mesh = mesh;
    mesh = NULL;
fail:
    meso_mesh_destroy(mesh);
    free(indices);
    free(uvs);
    free(normals);
    free(positions);
    return r;
}
