/* Parallel loops on a pool of worker threads that sleep while they wait, time and hashing.
 *
 * Why not OpenMP: libgomp's idle threads spin (OMP_WAIT_POLICY is read once, before main, and
 * cannot be changed by a library), so on a machine busy with other programs the spinning
 * helpers took the cores the working threads needed: 2 threads drew a frame several times
 * slower than 1. Here the helpers sleep on a condition variable between loops, and
 * the calling thread works through the jobs itself, so it never waits for a helper that the
 * scheduler has not run yet: with every helper descheduled, a loop costs what it costs on one
 * thread plus one wake-up call. */
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <time.h>

#include "core_internal.h"
#include "meso/runtime.h"

struct meso_pool {
    pthread_mutex_t lock;
    pthread_cond_t wake;  /* helpers: a new loop (or stop) */
    pthread_cond_t done;  /* the caller: the last job of the loop finished */
    pthread_mutex_t busy; /* held by the thread running a loop: one loop at a time */
    pthread_t *helpers;
    int num_helpers;
    bool stopping;
    /* The current loop, written under `lock` before `generation` changes. */
    uint32_t generation;
    meso_job_fn fn;
    void *user;
    uint32_t num_jobs;
    /* (generation << 32) | next job: a helper that read an older loop's parameters and woke
     * late cannot claim a job of the next loop, because its generation no longer matches. */
    _Atomic uint64_t ticket;
    _Atomic uint32_t finished; /* jobs of the current loop finished */
};

typedef struct helper_start {
    meso_pool *pool;
    int thread_index;
} helper_start;

/* Claim and run jobs of loop `generation` until none is left. */
static void run_jobs(meso_pool *pool, uint32_t generation, meso_job_fn fn, void *user,
                     uint32_t num_jobs, int thread_index) {
    for (;;) {
        uint64_t ticket = atomic_load(&pool->ticket);
        uint32_t job;
        do {
            job = (uint32_t)ticket;
            if ((uint32_t)(ticket >> 32) != generation || job >= num_jobs) return;
        } while (!atomic_compare_exchange_weak(&pool->ticket, &ticket, ticket + 1));
        fn(user, job, thread_index);
        if (atomic_fetch_add(&pool->finished, 1) + 1 == num_jobs) {
            pthread_mutex_lock(&pool->lock);
            pthread_cond_signal(&pool->done);
            pthread_mutex_unlock(&pool->lock);
        }
    }
}

static void *helper_main(void *arg) {
    helper_start start = *(helper_start *)arg;
    free(arg);
    meso_pool *pool = start.pool;
    uint32_t seen = 0;
    for (;;) {
        pthread_mutex_lock(&pool->lock);
        while (!pool->stopping && pool->generation == seen)
            pthread_cond_wait(&pool->wake, &pool->lock);
        if (pool->stopping) {
            pthread_mutex_unlock(&pool->lock);
            return NULL;
        }
        seen = pool->generation;
        meso_job_fn fn = pool->fn;
        void *user = pool->user;
        uint32_t num_jobs = pool->num_jobs;
        pthread_mutex_unlock(&pool->lock);
        run_jobs(pool, seen, fn, user, num_jobs, start.thread_index);
    }
}

void meso_pool_destroy(meso_pool *pool) {
    if (!pool) return;
    pthread_mutex_lock(&pool->lock);
    pool->stopping = true;
    pthread_cond_broadcast(&pool->wake);
    pthread_mutex_unlock(&pool->lock);
    for (int i = 0; i < pool->num_helpers; i++) pthread_join(pool->helpers[i], NULL);
    pthread_mutex_destroy(&pool->busy);
    pthread_cond_destroy(&pool->done);
    pthread_cond_destroy(&pool->wake);
    pthread_mutex_destroy(&pool->lock);
    free(pool->helpers);
    free(pool);
}

/* A pool of num_threads - 1 helpers; NULL when it cannot be made (loops then run serially). */
static meso_pool *pool_create(int num_threads) {
    meso_pool *pool = calloc(1, sizeof *pool);
    if (!pool) return NULL;
    pool->helpers = calloc((size_t)num_threads, sizeof *pool->helpers);
    if (!pool->helpers) {
        free(pool);
        return NULL;
    }
    pthread_mutex_init(&pool->lock, NULL);
    pthread_cond_init(&pool->wake, NULL);
    pthread_cond_init(&pool->done, NULL);
    pthread_mutex_init(&pool->busy, NULL);
    atomic_init(&pool->ticket, 0);
    atomic_init(&pool->finished, 0);
    for (int i = 1; i < num_threads; i++) {
        helper_start *start = malloc(sizeof *start);
        if (!start) break;
        *start = (helper_start){pool, i};
        if (pthread_create(&pool->helpers[pool->num_helpers], NULL, helper_main, start) != 0) {
            free(start);
            break;
        }
        pool->num_helpers++;
    }
    if (pool->num_helpers == 0) {
        meso_pool_destroy(pool);
        return NULL;
    }
    return pool;
}

/* The context's pool, made on first use (contexts that never run a parallel loop start no
 * thread). */
static meso_pool *context_pool(meso_context *ctx) {
    pthread_mutex_lock(&ctx->pool_lock);
    if (!ctx->pool && ctx->num_threads > 1) ctx->pool = pool_create(ctx->num_threads);
    meso_pool *pool = ctx->pool;
    pthread_mutex_unlock(&ctx->pool_lock);
    return pool;
}

void meso_parallel_for(meso_context *ctx, size_t num_jobs, meso_job_fn fn, void *user) {
    meso_pool *pool = NULL;
    if (ctx->num_threads > 1 && num_jobs > 1 && num_jobs < UINT32_MAX) pool = context_pool(ctx);
    /* A loop started inside a job, or beside another loop of this context on another thread,
     * runs on its caller's thread: the pool is busy. */
    if (!pool || pthread_mutex_trylock(&pool->busy) != 0) {
        for (size_t job = 0; job < num_jobs; job++) fn(user, job, 0);
        return;
    }
    pthread_mutex_lock(&pool->lock);
    uint32_t generation = ++pool->generation;
    if (generation == 0) generation = ++pool->generation; /* helpers start having seen 0 */
    pool->fn = fn;
    pool->user = user;
    pool->num_jobs = (uint32_t)num_jobs;
    atomic_store(&pool->finished, 0);
    atomic_store(&pool->ticket, (uint64_t)generation << 32);
    pthread_cond_broadcast(&pool->wake);
    pthread_mutex_unlock(&pool->lock);

    run_jobs(pool, generation, fn, user, (uint32_t)num_jobs, 0);

    pthread_mutex_lock(&pool->lock);
    while (atomic_load(&pool->finished) < (uint32_t)num_jobs)
        pthread_cond_wait(&pool->done, &pool->lock);
    pthread_mutex_unlock(&pool->lock);
    pthread_mutex_unlock(&pool->busy);
}

double meso_time_seconds(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

uint64_t meso_hash64(const void *data, size_t size, uint64_t seed) {
    const unsigned char *bytes = data;
    uint64_t hash = seed;
    for (size_t i = 0; i < size; i++) {
        hash ^= bytes[i];
        hash *= UINT64_C(0x100000001b3);
    }
    return hash;
}
