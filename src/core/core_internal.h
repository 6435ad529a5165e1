/* Private to the core module. */
#ifndef MESO_CORE_INTERNAL_H
#define MESO_CORE_INTERNAL_H

#include <pthread.h>

#include "meso/core.h"

#define MESO_MESSAGE_MAX 1024

/* The worker threads of a context (core_parallel.c). */
typedef struct meso_pool meso_pool;
void meso_pool_destroy(meso_pool *pool);

struct meso_context {
    int num_threads;
    meso_pool *pool;           /* made by the first parallel loop; NULL until then */
    pthread_mutex_t pool_lock; /* guards the pool's creation */
    meso_log_fn log;
    void *log_user;
    meso_progress_mode progress_mode;
    meso_progress_fn on_progress;
    void *progress_user;
    uint64_t memory_limit; /* bytes a job may estimate to need (meso_memory_check) */
    pthread_mutex_t lock;  /* serialises logging, last_error and the atomic group */
    struct core_atomic_group *atomic_group; /* outputs held back until published together */
    char last_error[MESO_MESSAGE_MAX];
    char subject[256]; /* meso_context_set_subject: named in a bake's notice */
};

/* Remove the files of an atomic group left open (meso_context_destroy). */
void core_atomic_group_free(meso_context *ctx);

#endif
