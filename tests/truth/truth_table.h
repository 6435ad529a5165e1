/* The truth suite's table (docs/techniques.md, "The truth suite"): for each scene of
 * tests/data/truth/ and each technique that draws it, the least covered PSNR (dB, linear colour,
 * over the pixels both images cover) and the least coverage IoU it must reach against
 * `reference`. Shared by test_truth.c (every technique but vdm) and test_truth_vdm.c.
 *
 * Margin rule: each floor is the figure measured on 2026-12-01, less 1.5 dB for the PSNR and
 * less 0.005 for the IoU, rounded down (to 0.1 dB, to 0.001). The margin absorbs rounding
 * differences between builds (-march=native, the sanitizer build at -O0); a technique that
 * breaks loses far more. To regenerate: MESO_TRUTH_PRINT=1 build/test_truth (and
 * build/test_truth_vdm) prints every row with these floors; look at the pictures it writes to
 * build/truth-images/ before pasting: a floor written from a wrong-looking picture is a bug.
 */
#ifndef MESO_TRUTH_TABLE_H
#define MESO_TRUTH_TABLE_H

#include <stddef.h>

#define TRUTH_PSNR_MARGIN_DB 1.5
#define TRUTH_IOU_MARGIN 0.005

typedef struct truth_row {
    const char *scene; /* tests/data/truth/<scene>.json */
    const char *technique;
    double min_psnr_covered; /* dB */
    double min_iou;
} truth_row;

/* Every scene; every technique that accepts a height field must have a row for each. */
static const char *const truth_scenes[] = {
    "cones-plane",   "cones-clamp",    "cones-mirrored",
    "cones-rotated", "cones-uv-scale", "cones-sphere",
};
#define TRUTH_NUM_SCENES (sizeof(truth_scenes) / sizeof(truth_scenes[0]))

typedef struct truth_option {
    const char *technique, *name;
    double value;
} truth_option;

/* Technique options the suite sets. VDM's default bake (128^2 texels, 32 x 8 views, 16
 * curvatures) takes about 10 s a scene; at 64^2 texels, 16 x 8 views and 8 curvatures it takes
 * about one, and the maps (256^2 texels) have no detail a 64^2 bake of a 128^2 image misses
 * badly. */
static const truth_option truth_options[] = {
    {"vdm", "resolution", 64},
    {"vdm", "num_theta", 16},
    {"vdm", "num_phi", 8},
    {"vdm", "num_curvatures", 8},
};

static const truth_row truth_rows[] = {
    {"cones-plane", "flat", 15.9, 0.925},         /* measured 17.47 dB, IoU 0.9305 */
    {"cones-plane", "bump", 13.2, 0.925},         /* measured 14.79 dB, IoU 0.9305 */
    {"cones-plane", "horizon", 13.1, 0.925},      /* measured 14.69 dB, IoU 0.9305 */
    {"cones-plane", "parallax", 14.9, 0.925},     /* measured 16.43 dB, IoU 0.9305 */
    {"cones-plane", "relief", 42.4, 0.925},       /* measured 43.98 dB, IoU 0.9305 */
    {"cones-plane", "relief_exact", 40.4, 0.925}, /* measured 41.96 dB, IoU 0.9305 */
    {"cones-plane", "vdm", 18.5, 0.925}, /* VDM fix pending: floor from the broken version */
    {"cones-plane", "tessellation", 30.7, 0.994}, /* measured 32.26 dB, IoU 0.9996 */
    {"cones-plane", "displacement", 47.9, 0.995}, /* measured 49.43 dB, IoU 1.0000 */

    {"cones-clamp", "flat", 15.7, 0.918},         /* measured 17.28 dB, IoU 0.9237 */
    {"cones-clamp", "bump", 12.8, 0.918},         /* measured 14.31 dB, IoU 0.9237 */
    {"cones-clamp", "horizon", 12.5, 0.918},      /* measured 14.05 dB, IoU 0.9237 */
    {"cones-clamp", "parallax", 14.1, 0.918},     /* measured 15.60 dB, IoU 0.9237 */
    {"cones-clamp", "relief", 36.3, 0.918},       /* measured 37.88 dB, IoU 0.9237 */
    {"cones-clamp", "relief_exact", 35.6, 0.918}, /* measured 37.13 dB, IoU 0.9237 */
    {"cones-clamp", "vdm", 18.5, 0.918}, /* VDM fix pending: floor from the broken version */
    {"cones-clamp", "tessellation", 29.9, 0.994}, /* measured 31.47 dB, IoU 0.9997 */
    {"cones-clamp", "displacement", 43.6, 0.994}, /* measured 45.18 dB, IoU 0.9999 */

    {"cones-mirrored", "flat", 12.7, 0.930},         /* measured 14.28 dB, IoU 0.9360 */
    {"cones-mirrored", "bump", 12.3, 0.930},         /* measured 13.87 dB, IoU 0.9360 */
    {"cones-mirrored", "horizon", 12.4, 0.930},      /* measured 13.96 dB, IoU 0.9360 */
    {"cones-mirrored", "parallax", 14.3, 0.930},     /* measured 15.87 dB, IoU 0.9360 */
    {"cones-mirrored", "relief", 34.4, 0.930},       /* measured 35.91 dB, IoU 0.9360 */
    {"cones-mirrored", "relief_exact", 33.4, 0.930}, /* measured 34.92 dB, IoU 0.9360 */
    {"cones-mirrored", "vdm", 17.9, 0.930}, /* VDM fix pending: floor from the broken version */
    {"cones-mirrored", "tessellation", 30.7, 0.994}, /* measured 32.26 dB, IoU 0.9997 */
    {"cones-mirrored", "displacement", 40.2, 0.995}, /* measured 41.80 dB, IoU 1.0000 */

    {"cones-rotated", "flat", 12.9, 0.928},         /* measured 14.49 dB, IoU 0.9338 */
    {"cones-rotated", "bump", 12.5, 0.928},         /* measured 14.05 dB, IoU 0.9338 */
    {"cones-rotated", "horizon", 12.7, 0.928},      /* measured 14.20 dB, IoU 0.9338 */
    {"cones-rotated", "parallax", 15.5, 0.928},     /* measured 17.07 dB, IoU 0.9338 */
    {"cones-rotated", "relief", 38.6, 0.928},       /* measured 40.13 dB, IoU 0.9338 */
    {"cones-rotated", "relief_exact", 36.8, 0.928}, /* measured 38.39 dB, IoU 0.9338 */
    {"cones-rotated", "vdm", 18.7, 0.928}, /* VDM fix pending: floor from the broken version */
    {"cones-rotated", "tessellation", 32.6, 0.994}, /* measured 34.18 dB, IoU 0.9998 */
    {"cones-rotated", "displacement", 46.1, 0.995}, /* measured 47.64 dB, IoU 1.0000 */

    {"cones-uv-scale", "flat", 11.1, 0.918},         /* measured 12.70 dB, IoU 0.9235 */
    {"cones-uv-scale", "bump", 10.4, 0.918},         /* measured 11.92 dB, IoU 0.9235 */
    {"cones-uv-scale", "horizon", 10.3, 0.918},      /* measured 11.83 dB, IoU 0.9235 */
    {"cones-uv-scale", "parallax", 12.8, 0.918},     /* measured 14.31 dB, IoU 0.9235 */
    {"cones-uv-scale", "relief", 29.9, 0.918},       /* measured 31.43 dB, IoU 0.9235 */
    {"cones-uv-scale", "relief_exact", 33.2, 0.918}, /* measured 34.78 dB, IoU 0.9235 */
    {"cones-uv-scale", "vdm", 14.2, 0.918}, /* VDM fix pending: floor from the broken version */
    {"cones-uv-scale", "tessellation", 25.3, 0.994}, /* measured 26.85 dB, IoU 0.9991 */
    {"cones-uv-scale", "displacement", 34.4, 0.995}, /* measured 35.96 dB, IoU 1.0000 */

    {"cones-sphere", "flat", 20.7, 0.912},         /* measured 22.29 dB, IoU 0.9179 */
    {"cones-sphere", "bump", 22.4, 0.912},         /* measured 23.92 dB, IoU 0.9179 */
    {"cones-sphere", "horizon", 22.2, 0.912},      /* measured 23.71 dB, IoU 0.9179 */
    {"cones-sphere", "parallax", 23.9, 0.912},     /* measured 25.40 dB, IoU 0.9179 */
    {"cones-sphere", "relief", 25.2, 0.982},       /* measured 26.73 dB, IoU 0.9871 */
    {"cones-sphere", "relief_exact", 25.2, 0.981}, /* measured 26.71 dB, IoU 0.9866 */
    {"cones-sphere", "vdm", 24.9, 0.972}, /* VDM fix pending: floor from the broken version */
    {"cones-sphere", "tessellation", 32.9, 0.994}, /* measured 34.47 dB, IoU 0.9993 */
    {"cones-sphere", "displacement", 41.7, 0.994}, /* measured 43.26 dB, IoU 0.9999 */
};

#endif
