/* The viewer's background reference render (view_reference.h). */
#include "view_reference.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "view_scene.h"
#include "meso/runtime.h"

struct view_reference {
    pthread_t thread;
    meso_context *ctx; /* the job's own: its workers and its last error are not the window's */
    view_scene *scene; /* the view as it was when the job started */
    meso_framebuffer *image;
    atomic_int status; /* view_reference_status */
    _Atomic double fraction;
    atomic_bool cancel;
    double start_seconds;
    char error[512];
};

/* The context's progress callback: the fraction for the title, the cancel flag back. */
static bool on_progress(void *user, const char *label, double fraction) {
    view_reference *job = user;
    atomic_store(&job->fraction, fraction);
    return atomic_load(&job->cancel);
}

static void *run(void *user) {
    view_reference *job = user;
    meso_renderer *renderer = NULL;
    meso_result r = meso_renderer_create(job->ctx, &job->scene->scene,
                                         &(meso_render_desc){.technique = "reference"}, &renderer);
    if (r == MESO_OK && atomic_load(&job->cancel)) r = MESO_ERROR_CANCELLED;
    if (r == MESO_OK) r = meso_renderer_render(renderer, job->image);
    meso_renderer_destroy(renderer);
    if (r != MESO_OK) {
        const char *message = meso_context_last_error(job->ctx);
        snprintf(job->error, sizeof(job->error), "%s",
                 r == MESO_ERROR_CANCELLED ? "cancelled"
                 : message[0]              ? message
                                           : meso_result_string(r));
    }
    atomic_store(&job->status, r == MESO_OK ? VIEW_REFERENCE_DONE : VIEW_REFERENCE_FAILED);
    return NULL;
}

static void free_job(view_reference *job) {
    meso_framebuffer_destroy(job->image);
    view_scene_destroy(job->scene);
    meso_context_destroy(job->ctx);
    free(job);
}

meso_result view_reference_start(meso_context *ctx, const meso_scene *source,
                                 const view_state *state, int width, int height, int num_threads,
                                 view_reference **out_job) {
    *out_job = NULL;
    view_reference *job = calloc(1, sizeof(*job));
    if (!job) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "reference: out of memory");
    atomic_init(&job->status, VIEW_REFERENCE_RUNNING);
    atomic_init(&job->fraction, 0.0);
    atomic_init(&job->cancel, false);
    job->start_seconds = meso_time_seconds();
    meso_context_desc desc = {.num_threads = num_threads,
                              .progress = MESO_PROGRESS_NEVER, /* the window shows it */
                              .on_progress = on_progress,
                              .progress_user = job};
    meso_result r = meso_context_create(&desc, &job->ctx);
    if (r != MESO_OK) r = meso_log_error(ctx, r, "reference: cannot create a context");
    /* the reference takes no technique_options: the objects' own are dropped */
    if (r == MESO_OK) r = view_scene_create(ctx, source, "reference", state, &job->scene);
    if (r == MESO_OK) {
        /* the reference subdivides to half a pixel of the scene's image size: this one's */
        job->scene->scene.width = width;
        job->scene->scene.height = height;
        r = meso_framebuffer_create(ctx, width, height, &job->image);
    }
    if (r == MESO_OK && pthread_create(&job->thread, NULL, run, job) != 0)
        r = meso_log_error(ctx, MESO_ERROR_INTERNAL, "reference: cannot start a thread");
    if (r != MESO_OK) {
        free_job(job);
        return r;
    }
    *out_job = job;
    return MESO_OK;
}

view_reference_status view_reference_poll(view_reference *job, double *out_fraction,
                                          double *out_seconds) {
    *out_fraction = atomic_load(&job->fraction);
    *out_seconds = meso_time_seconds() - job->start_seconds;
    return (view_reference_status)atomic_load(&job->status);
}

const meso_framebuffer *view_reference_image(const view_reference *job) {
    return atomic_load(&((view_reference *)job)->status) == VIEW_REFERENCE_DONE ? job->image : NULL;
}

const char *view_reference_error(const view_reference *job) {
    return atomic_load(&((view_reference *)job)->status) == VIEW_REFERENCE_FAILED ? job->error : "";
}

void view_reference_destroy(view_reference *job) {
    if (!job) return;
    atomic_store(&job->cancel, true);
    pthread_join(job->thread, NULL);
    free_job(job);
}
