/* The truth suite's table (docs/techniques.md, "The truth suite"): for each scene of
 * tests/data/truth/ and each technique that draws it, the least covered PSNR (dB, linear colour,
 * over the pixels both images cover) and the least coverage IoU it must reach against
 * `reference`. Shared by test_truth.c (every technique but vdm) and test_truth_vdm.c.
 *
 * Margin rule: each floor is the figure measured when the row was written, less 1.5 dB for the
 * PSNR and less 0.005 for the IoU, rounded down (to 0.1 dB, to 0.001). The margin absorbs rounding
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
    const char *scene;       /* tests/data/truth/<scene>.json */
    const char *technique;   /* a name, or "name:option=value" (that option set too) */
    double min_psnr_covered; /* dB */
    double min_iou;
} truth_row;

/* Every scene; every technique that accepts a height field must have a row for each. */
static const char *const truth_scenes[] = {
    "cones-plane",    "cones-clamp",  "cones-mirrored",    "cones-rotated",
    "cones-uv-scale", "cones-sphere", "cones-sphere-deep",
};
#define TRUTH_NUM_SCENES (sizeof(truth_scenes) / sizeof(truth_scenes[0]))

typedef struct truth_option {
    const char *technique, *name;
    double value;
} truth_option;

/* Technique options the suite sets. VDM's default bake (128^2 texels, 32 x 8 views, 16
 * curvatures) would be most of the suite's time; a quarter of the texels, half the views and half
 * the curvatures keep it short. vdm's floors are for these settings. */
static const truth_option truth_options[] = {
    {"vdm", "resolution", 64},
    {"vdm", "num_theta", 16},
    {"vdm", "num_phi", 8},
    {"vdm", "num_curvatures", 8},
    /* GDM's default bake (64^2 x 32 voxels, 16 x 32 directions) takes 20-60 s; a quarter of
     * the voxels and half the azimuths keep it to a few. gdm's floors are for these. */
    {"gdm", "resolution", 32},
    {"gdm", "layers", 16},
    {"gdm", "num_phi", 16},
};

static const truth_row truth_rows[] = {
    {"cones-plane", "flat", 15.5, 0.995},          /* measured 17.01 dB, IoU 1.0000 */
    {"cones-plane", "bump", 13.0, 0.995},          /* measured 14.56 dB, IoU 1.0000 */
    {"cones-plane", "horizon", 12.7, 0.995},       /* measured 14.22 dB, IoU 1.0000 */
    {"cones-plane", "parallax", 14.0, 0.995},      /* measured 15.58 dB, IoU 1.0000 */
    {"cones-plane", "relief", 37.3, 0.995},        /* measured 38.83 dB, IoU 1.0000 */
    {"cones-plane", "relief_exact", 34.2, 0.995},  /* measured 35.75 dB, IoU 1.0000 */
    {"cones-plane", "relief_layers", 36.2, 0.995}, /* measured 37.79 dB, IoU 1.0000 */
    {"cones-plane", "vdm", 36.8, 0.995},           /* measured 38.35 dB, IoU 1.0000 */
    {"cones-plane", "gdm", 35.8, 0.995},           /* measured 37.36 dB, IoU 1.0000 */
    {"cones-plane", "tessellation", 33.5, 0.995},  /* measured 35.09 dB, IoU 1.0000 */
    {"cones-plane", "displacement", 36.5, 0.995},  /* measured 38.08 dB, IoU 1.0000 */

    {"cones-clamp", "flat", 15.7, 0.925},          /* measured 17.23 dB, IoU 0.9302 */
    {"cones-clamp", "bump", 12.8, 0.925},          /* measured 14.38 dB, IoU 0.9302 */
    {"cones-clamp", "horizon", 12.6, 0.925},       /* measured 14.13 dB, IoU 0.9302 */
    {"cones-clamp", "parallax", 14.2, 0.925},      /* measured 15.73 dB, IoU 0.9302 */
    {"cones-clamp", "relief", 37.5, 0.925},        /* measured 39.09 dB, IoU 0.9302 */
    {"cones-clamp", "relief_exact", 36.9, 0.925},  /* measured 38.43 dB, IoU 0.9302 */
    {"cones-clamp", "relief_layers", 37.2, 0.925}, /* measured 38.73 dB, IoU 0.9302 */
    {"cones-clamp", "vdm", 36.4, 0.925},           /* measured 37.90 dB, IoU 0.9302 */
    {"cones-clamp", "gdm", 33.9, 0.987},           /* measured 35.45 dB, IoU 0.9925 */
    {"cones-clamp", "tessellation", 30.5, 0.994},  /* measured 32.07 dB, IoU 0.9998 */
    {"cones-clamp", "displacement", 45.3, 0.994},  /* measured 46.86 dB, IoU 0.9999 */

    {"cones-mirrored", "flat", 13.8, 0.995},          /* measured 15.30 dB, IoU 1.0000 */
    {"cones-mirrored", "bump", 13.0, 0.995},          /* measured 14.56 dB, IoU 1.0000 */
    {"cones-mirrored", "horizon", 12.8, 0.995},       /* measured 14.33 dB, IoU 1.0000 */
    {"cones-mirrored", "parallax", 17.6, 0.995},      /* measured 19.13 dB, IoU 1.0000 */
    {"cones-mirrored", "relief", 34.7, 0.995},        /* measured 36.29 dB, IoU 1.0000 */
    {"cones-mirrored", "relief_exact", 32.1, 0.995},  /* measured 33.69 dB, IoU 1.0000 */
    {"cones-mirrored", "relief_layers", 33.8, 0.995}, /* measured 35.36 dB, IoU 1.0000 */
    {"cones-mirrored", "vdm", 32.9, 0.995},           /* measured 34.47 dB, IoU 1.0000 */
    {"cones-mirrored", "gdm", 33.7, 0.995},           /* measured 35.28 dB, IoU 1.0000 */
    {"cones-mirrored", "tessellation", 32.9, 0.995},  /* measured 34.49 dB, IoU 1.0000 */
    {"cones-mirrored", "displacement", 34.8, 0.995},  /* measured 36.39 dB, IoU 1.0000 */

    {"cones-rotated", "flat", 15.5, 0.995},          /* measured 17.09 dB, IoU 1.0000 */
    {"cones-rotated", "bump", 13.4, 0.995},          /* measured 14.97 dB, IoU 1.0000 */
    {"cones-rotated", "horizon", 13.0, 0.995},       /* measured 14.55 dB, IoU 1.0000 */
    {"cones-rotated", "parallax", 14.6, 0.995},      /* measured 16.16 dB, IoU 1.0000 */
    {"cones-rotated", "relief", 38.3, 0.995},        /* measured 39.82 dB, IoU 1.0000 */
    {"cones-rotated", "relief_exact", 34.8, 0.995},  /* measured 36.33 dB, IoU 1.0000 */
    {"cones-rotated", "relief_layers", 38.2, 0.995}, /* measured 39.77 dB, IoU 1.0000 */
    {"cones-rotated", "vdm", 35.5, 0.995},           /* measured 37.01 dB, IoU 1.0000 */
    {"cones-rotated", "gdm", 34.6, 0.995},           /* measured 36.11 dB, IoU 1.0000 */
    {"cones-rotated", "tessellation", 34.5, 0.995},  /* measured 36.10 dB, IoU 1.0000 */
    {"cones-rotated", "displacement", 37.7, 0.995},  /* measured 39.24 dB, IoU 1.0000 */

    {"cones-uv-scale", "flat", 11.9, 0.995},          /* measured 13.42 dB, IoU 1.0000 */
    {"cones-uv-scale", "bump", 10.5, 0.995},          /* measured 12.03 dB, IoU 1.0000 */
    {"cones-uv-scale", "horizon", 10.1, 0.995},       /* measured 11.67 dB, IoU 1.0000 */
    {"cones-uv-scale", "parallax", 12.7, 0.995},      /* measured 14.23 dB, IoU 1.0000 */
    {"cones-uv-scale", "relief", 29.2, 0.995},        /* measured 30.71 dB, IoU 1.0000 */
    {"cones-uv-scale", "relief_exact", 31.7, 0.995},  /* measured 33.21 dB, IoU 1.0000 */
    {"cones-uv-scale", "relief_layers", 29.3, 0.995}, /* measured 30.81 dB, IoU 1.0000 */
    {"cones-uv-scale", "vdm", 29.5, 0.995},           /* measured 31.02 dB, IoU 1.0000 */
    {"cones-uv-scale", "gdm", 26.1, 0.995},           /* measured 27.66 dB, IoU 1.0000 */
    {"cones-uv-scale", "tessellation", 26.7, 0.995},  /* measured 28.24 dB, IoU 1.0000 */
    {"cones-uv-scale", "displacement", 26.8, 0.995},  /* measured 28.36 dB, IoU 1.0000 */

    {"cones-sphere", "flat", 19.9, 0.900},                       /* measured 21.48 dB, IoU 0.9057 */
    {"cones-sphere", "bump", 21.3, 0.900},                       /* measured 22.86 dB, IoU 0.9057 */
    {"cones-sphere", "horizon", 21.2, 0.900},                    /* measured 22.79 dB, IoU 0.9057 */
    {"cones-sphere", "parallax", 22.9, 0.900},                   /* measured 24.49 dB, IoU 0.9057 */
    {"cones-sphere", "relief", 26.2, 0.980},                     /* measured 27.76 dB, IoU 0.9853 */
    {"cones-sphere", "relief_exact", 26.5, 0.980},               /* measured 28.07 dB, IoU 0.9852 */
    {"cones-sphere", "relief_layers", 26.5, 0.980},              /* measured 28.04 dB, IoU 0.9853 */
    {"cones-sphere", "vdm", 26.7, 0.975},                        /* measured 28.29 dB, IoU 0.9801 */
    {"cones-sphere", "gdm", 30.6, 0.994},                        /* measured 32.18 dB, IoU 0.9997 */
    {"cones-sphere", "tessellation", 34.3, 0.993},               /* measured 35.88 dB, IoU 0.9988 */
    {"cones-sphere", "displacement", 40.3, 0.994},               /* measured 41.87 dB, IoU 0.9996 */
    {"cones-sphere-deep", "flat", 20.2, 0.906},                  /* measured 21.78 dB, IoU 0.9115 */
    {"cones-sphere-deep", "bump", 23.0, 0.906},                  /* measured 24.59 dB, IoU 0.9115 */
    {"cones-sphere-deep", "horizon", 22.6, 0.906},               /* measured 24.17 dB, IoU 0.9115 */
    {"cones-sphere-deep", "parallax", 25.6, 0.906},              /* measured 27.10 dB, IoU 0.9115 */
    {"cones-sphere-deep", "relief", 29.7, 0.979},                /* measured 31.25 dB, IoU 0.9847 */
    {"cones-sphere-deep", "relief_exact", 29.2, 0.979},          /* measured 30.74 dB, IoU 0.9845 */
    {"cones-sphere-deep", "relief_layers", 29.1, 0.980},         /* measured 30.64 dB, IoU 0.9850 */
    {"cones-sphere-deep", "vdm", 28.0, 0.972},                   /* measured 29.51 dB, IoU 0.9775 */
    {"cones-sphere-deep", "gdm", 41.8, 0.993},                   /* measured 43.40 dB, IoU 0.9989 */
    {"cones-sphere-deep", "tessellation", 41.3, 0.993},          /* measured 42.87 dB, IoU 0.9982 */
    {"cones-sphere-deep", "displacement", 42.8, 0.994},          /* measured 44.33 dB, IoU 0.9994 */
    {"cones-sphere-deep", "relief:shell=1", 45.7, 0.993},        /* measured 47.25 dB, IoU 0.9983 */
    {"cones-sphere-deep", "relief_exact:shell=1", 41.3, 0.993},  /* measured 42.81 dB, IoU 0.9989 */
    {"cones-sphere-deep", "relief_layers:shell=1", 45.7, 0.993}, /* measured 47.23 dB, IoU 0.9985 */
};

#endif
