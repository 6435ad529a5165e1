/* The worker pool behind meso_parallel_for: every job exactly once, thread indices in range,
 * nested and concurrent loops, thread-count changes, and helpers that sleep (use no CPU)
 * between loops, so they do not take cores from other programs. */
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "test_util.h"
#include "meso/runtime.h"

typedef struct counts {
    _Atomic int *runs; /* per job */
    _Atomic int bad_thread;
    int num_threads;
    meso_context *ctx; /* for nested loops */
    _Atomic int nested_off_caller;
} counts;

static void count_job(void *user, size_t job, int thread) {
    counts *c = user;
    atomic_fetch_add(&c->runs[job], 1);
    if (thread < 0 || thread >= c->num_threads) atomic_store(&c->bad_thread, 1);
}

static void test_every_job_runs_once_on_a_valid_thread(void **state) {
    (void)state;
    meso_context *ctx = test_context(3);
    enum { MAX_JOBS = 1000 };
    _Atomic int *runs = calloc(MAX_JOBS, sizeof *runs);
    counts c = {.runs = runs, .num_threads = 3};
    for (int loop = 0; loop < 300; loop++) {
        size_t jobs = (size_t)(loop * 37 % MAX_JOBS);
        for (size_t j = 0; j < MAX_JOBS; j++) atomic_store(&runs[j], 0);
        meso_parallel_for(ctx, jobs, count_job, &c);
        for (size_t j = 0; j < MAX_JOBS; j++)
            if (atomic_load(&runs[j]) != (j < jobs ? 1 : 0))
                fail_msg("loop %d: job %zu ran %d times", loop, j, atomic_load(&runs[j]));
    }
    assert_int_equal(atomic_load(&c.bad_thread), 0);
    free(runs);
    meso_context_destroy(ctx);
}

static void inner_job(void *user, size_t job, int thread) {
    counts *c = user;
    if (thread != 0) atomic_store(&c->nested_off_caller, 1);
    atomic_fetch_add(&c->runs[job], 1);
}

static void outer_job(void *user, size_t job, int thread) {
    counts *c = user;
    (void)thread;
    counts inner = {.runs = c->runs + 100 * (job + 1), .num_threads = c->num_threads};
    meso_parallel_for(c->ctx, 100, inner_job, &inner);
    if (atomic_load(&inner.nested_off_caller)) atomic_store(&c->nested_off_caller, 1);
}

static void test_a_loop_inside_a_job_runs_on_its_caller(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    _Atomic int *runs = calloc(100 * 9, sizeof *runs);
    counts c = {.runs = runs, .num_threads = 2, .ctx = ctx};
    meso_parallel_for(ctx, 8, outer_job, &c);
    for (int j = 100; j < 900; j++) assert_int_equal(atomic_load(&runs[j]), 1);
    assert_int_equal(atomic_load(&c.nested_off_caller), 0);
    free(runs);
    meso_context_destroy(ctx);
}

typedef struct concurrent {
    meso_context *ctx;
    _Atomic int *runs;
} concurrent;

static void *run_loops(void *arg) {
    concurrent *k = arg;
    counts c = {.runs = k->runs, .num_threads = meso_context_num_threads(k->ctx)};
    for (int loop = 0; loop < 200; loop++) meso_parallel_for(k->ctx, 64, count_job, &c);
    return NULL;
}

static void test_loops_from_two_threads_on_one_context(void **state) {
    (void)state;
    meso_context *ctx = test_context(2);
    concurrent a = {ctx, calloc(64, sizeof(_Atomic int))},
               b = {ctx, calloc(64, sizeof(_Atomic int))};
    pthread_t ta, tb;
    assert_int_equal(pthread_create(&ta, NULL, run_loops, &a), 0);
    assert_int_equal(pthread_create(&tb, NULL, run_loops, &b), 0);
    pthread_join(ta, NULL);
    pthread_join(tb, NULL);
    for (int j = 0; j < 64; j++) {
        assert_int_equal(atomic_load(&a.runs[j]), 200);
        assert_int_equal(atomic_load(&b.runs[j]), 200);
    }
    free(a.runs);
    free(b.runs);
    meso_context_destroy(ctx);
}

static void test_thread_count_changes_between_loops(void **state) {
    (void)state;
    meso_context *ctx = test_context(4);
    _Atomic int *runs = calloc(50, sizeof *runs);
    const int counts_to_try[] = {4, 1, 3, 2, 2, 5};
    for (size_t i = 0; i < sizeof counts_to_try / sizeof counts_to_try[0]; i++) {
        meso_context_set_num_threads(ctx, counts_to_try[i]);
        assert_int_equal(meso_context_num_threads(ctx), counts_to_try[i]);
        counts c = {.runs = runs, .num_threads = counts_to_try[i]};
        meso_parallel_for(ctx, 50, count_job, &c);
        assert_int_equal(atomic_load(&c.bad_thread), 0);
    }
    for (int j = 0; j < 50; j++) assert_int_equal(atomic_load(&runs[j]), 6);
    free(runs);
    meso_context_destroy(ctx);
}

static double process_cpu_seconds(void) {
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void test_helpers_sleep_between_loops(void **state) {
    (void)state;
    meso_context *ctx = test_context(4);
    _Atomic int *runs = calloc(64, sizeof *runs);
    counts c = {.runs = runs, .num_threads = 4};
    meso_parallel_for(ctx, 64, count_job, &c);
    /* Let any spinning end, then the idle helpers must use (next to) no CPU for 300 ms: three
     * spinning helpers on this 2-core box would use at least one core, 0.3 s. The clock counts
     * the whole process, so 0.1 s leaves room for the sanitizer runtime's own background
     * thread (0.03-0.04 s measured in the ASan build; the Release build stays under 0.02 s). */
    struct timespec pause = {0, 50 * 1000 * 1000};
    nanosleep(&pause, NULL);
    double before = process_cpu_seconds();
    pause.tv_nsec = 300 * 1000 * 1000;
    nanosleep(&pause, NULL);
    double used = process_cpu_seconds() - before;
    if (used > 0.1) fail_msg("idle helpers used %.3f s of CPU in 0.3 s", used);
    free(runs);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_job_runs_once_on_a_valid_thread),
        cmocka_unit_test(test_a_loop_inside_a_job_runs_on_its_caller),
        cmocka_unit_test(test_loops_from_two_threads_on_one_context),
        cmocka_unit_test(test_thread_count_changes_between_loops),
        cmocka_unit_test(test_helpers_sleep_between_loops),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
