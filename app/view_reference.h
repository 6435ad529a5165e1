/* The ray-traced reference of the viewer's current view, rendered on a thread of its own with
 * a context of its own, so the window keeps drawing while it runs (docs/viewer.md). The main
 * thread starts a job, polls its progress once a frame, takes the image when it is done, and
 * may cancel it (a new view, quitting). */
#ifndef MESO_APP_VIEW_REFERENCE_H
#define MESO_APP_VIEW_REFERENCE_H

#include "app.h"
#include "view_state.h"

typedef struct view_reference view_reference;

typedef enum view_reference_status {
    VIEW_REFERENCE_RUNNING = 0,
    VIEW_REFERENCE_DONE,
    VIEW_REFERENCE_FAILED, /* or cancelled: view_reference_error says why */
} view_reference_status;

/* Start rendering `source` with `reference` for the state's camera and light at width x
 * height on `num_threads` workers (0: every core). The source scene must outlive the job.
 * Returns MESO_OK, or an error logged on ctx (out of memory, no thread). */
meso_result view_reference_start(meso_context *ctx, const meso_scene *source,
                                 const view_state *state, int width, int height, int num_threads,
                                 view_reference **out_job);

/* The job's status; *out_fraction receives the fraction traced (0 while the true geometry
 * is being built), *out_seconds the time since it started. Thread-safe. */
view_reference_status view_reference_poll(view_reference *job, double *out_fraction,
                                          double *out_seconds);

/* When DONE: the image (the job keeps ownership until destroyed). NULL otherwise. */
const meso_framebuffer *view_reference_image(const view_reference *job);
/* When FAILED: the reason ("" otherwise). */
const char *view_reference_error(const view_reference *job);

/* Ask the job to stop (the trace stops at its next tile; building the geometry cannot be
 * interrupted), wait for its thread and free everything. NULL does nothing. */
void view_reference_destroy(view_reference *job);

#endif
