/* Floors and documented limits of the random-view test (test_views.c).
 *
 * Floors: per example and technique, the lowest covered PSNR and coverage IoU measured over the
 * views of `make test-views` at VIEWS_FLOORS_SIZE pixels, less 1 dB and 0.02 (the truth
 * table's margin rule); checked only at that size. A pair missing here has no floor.
 *
 * Known: pairs whose pinholes or specks are a documented limit of the technique as meso
 * implements it today (docs/techniques.md, "From every side"); their views are reported as
 * KNOWN, not failed. Every other pair must show none. */
#ifndef MESO_VIEWS_FLOORS_H
#define MESO_VIEWS_FLOORS_H

#include <math.h>
#include <stdbool.h>
#include <string.h>

#define VIEWS_FLOORS_SIZE 64

typedef struct views_floor {
    const char *example, *technique;
    float psnr_covered, iou;
} views_floor;

static const views_floor views_floors[] = {
#include "views_floors.inc"
};

typedef struct views_limit {
    const char *example, *technique; /* NULL example: every example */
    const char *reason;
} views_limit;

static const views_limit views_limits[] = {
#include "views_limits.inc"
};

static inline views_floor views_floor_of(const char *example, const char *technique) {
    for (size_t i = 0; i < sizeof views_floors / sizeof *views_floors; i++)
        if (!strcmp(views_floors[i].example, example) &&
            !strcmp(views_floors[i].technique, technique))
            return views_floors[i];
    return (views_floor){example, technique, -INFINITY, -INFINITY};
}

static inline const char *views_known(const char *example, const char *technique) {
    for (size_t i = 0; i < sizeof views_limits / sizeof *views_limits; i++)
        if ((!views_limits[i].example || !strcmp(views_limits[i].example, example)) &&
            !strcmp(views_limits[i].technique, technique))
            return views_limits[i].reason;
    return NULL;
}

#endif
