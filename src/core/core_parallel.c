/* Parallel loops, time and hashing. */
#include <omp.h>
#include <time.h>

#include "core_internal.h"

void meso_parallel_for(meso_context *ctx, size_t num_jobs, meso_job_fn fn, void *user) {
    int threads = ctx->num_threads;
    if (threads <= 1 || num_jobs <= 1) {
        for (size_t job = 0; job < num_jobs; job++) fn(user, job, 0);
        return;
    }
    /* Dynamic scheduling balances uneven jobs (tiles differ a lot in cost); determinism comes
     * from the jobs writing disjoint memory, not from the schedule. */
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
    for (size_t job = 0; job < num_jobs; job++) fn(user, job, omp_get_thread_num());
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
