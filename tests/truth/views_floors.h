/* Floors of the random-view test (test_views.c): the lowest covered PSNR and coverage IoU
 * each technique reached over the K = 200 run of `make test-views` (docs/techniques.md, "From
 * every side"), less a margin of 1 dB and 0.01, as the truth table's floors are set. A
 * technique missing here has no floor yet (reported, not checked). */
#ifndef MESO_VIEWS_FLOORS_H
#define MESO_VIEWS_FLOORS_H

#include <math.h>
#include <stdbool.h>
#include <string.h>

typedef struct views_floor {
    const char *technique;
    float psnr_covered, iou;
} views_floor;

static const views_floor views_floors[] = {
    {"flat", 0.0f, 0.0f},
};

static inline views_floor views_floor_of(const char *technique) {
    for (size_t i = 0; i < sizeof views_floors / sizeof *views_floors; i++)
        if (!strcmp(views_floors[i].technique, technique)) return views_floors[i];
    return (views_floor){technique, -INFINITY, -INFINITY};
}

#endif
