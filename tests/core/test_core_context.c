/* Context, errors, parallel loops, hashing, atomic files, progress. */
#include <stdlib.h>
#include <string.h>

#include "test_util.h"
#include "meso/runtime.h"

static void test_result_strings_cover_every_result(void **state) {
    assert_string_equal(meso_result_string(MESO_OK), "ok");
    assert_string_equal(meso_result_string(MESO_ERROR_LIMIT), "input exceeds a documented limit");
    assert_string_equal(meso_result_string((meso_result)999), "unknown result");
    assert_true(meso_result_is_bad_input(MESO_ERROR_FORMAT));
    assert_false(meso_result_is_bad_input(MESO_ERROR_OUT_OF_MEMORY));
}

static void test_log_error_returns_the_code_and_keeps_the_message(void **state) {
    meso_context *ctx = test_context(1);
    assert_string_equal(meso_context_last_error(ctx), "");
    assert_int_equal(meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: bad %d", "a.json", 3),
                     MESO_ERROR_FORMAT);
    assert_string_equal(meso_context_last_error(ctx), "a.json: bad 3");
    meso_log_warning(ctx, "w %d", 1);
    assert_string_equal(test_last_warning(), "w 1");
    assert_string_equal(meso_context_last_error(ctx), "a.json: bad 3");
    meso_context_destroy(ctx);
}

typedef struct squares {
    uint64_t *out;
} squares;
static void square_job(void *user, size_t job, int thread) {
    squares *s = user;
    s->out[job] = (uint64_t)job * job + (uint64_t)thread * 0; /* thread index must not matter */
}

static void test_parallel_for_runs_every_job_once(void **state) {
    for (int threads = 1; threads <= 4; threads++) {
        meso_context *ctx = test_context(threads);
        assert_int_equal(meso_context_num_threads(ctx), threads);
        uint64_t out[1000];
        memset(out, 0xff, sizeof(out));
        squares s = {out};
        meso_parallel_for(ctx, 1000, square_job, &s);
        for (size_t i = 0; i < 1000; i++) assert_int_equal(out[i], (uint64_t)i * i);
        meso_context_destroy(ctx);
    }
}

static void test_hash_is_fnv1a(void **state) {
    /* Published FNV-1a 64 test vectors. */
    assert_int_equal(meso_hash64("", 0, MESO_HASH_SEED), UINT64_C(0xcbf29ce484222325));
    assert_int_equal(meso_hash64("a", 1, MESO_HASH_SEED), UINT64_C(0xaf63dc4c8601ec8c));
    assert_int_equal(meso_hash64("foobar", 6, MESO_HASH_SEED), UINT64_C(0x85944171f73967e8));
}

static void test_atomic_file_commit_and_abort(void **state) {
    meso_context *ctx = test_context(1);
    const char *path = test_path(test_temp_dir(), "atomic.txt");
    assert_int_equal(meso_file_write_atomic(ctx, path, "first", 5), MESO_OK);
    meso_atomic_file f;
    assert_int_equal(meso_atomic_file_open(ctx, path, &f), MESO_OK);
    fputs("second, interrupted", f.file);
    meso_atomic_file_abort(&f);
    char *data = NULL;
    size_t size = 0;
    assert_int_equal(meso_file_read(ctx, path, 100, &data, &size), MESO_OK);
    assert_string_equal(data, "first");
    free(data);
    assert_int_equal(meso_file_read(ctx, path, 3, &data, &size), MESO_ERROR_LIMIT);
    assert_null(data);
    assert_int_equal(meso_file_write_atomic(ctx, "/nonexistent-dir/x.txt", "x", 1), MESO_ERROR_IO);
    assert_non_null(strstr(meso_context_last_error(ctx), "/nonexistent-dir/x.txt"));
    meso_context_destroy(ctx);
}

static bool cancel_at_half(void *user, const char *label, double fraction) {
    (void)label;
    *(double *)user = fraction;
    return fraction >= 0.5;
}

static void test_progress_reports_and_cancels(void **state) {
    double seen = -1.0;
    meso_context *ctx = NULL;
    meso_context_desc desc = {
        .progress = MESO_PROGRESS_NEVER, .on_progress = cancel_at_half, .progress_user = &seen};
    assert_int_equal(meso_context_create(&desc, &ctx), MESO_OK);
    meso_progress *p = meso_progress_begin(ctx, "work", 10);
    assert_non_null(p);
    bool cancelled = false;
    for (int i = 0; i < 10 && !cancelled; i++) {
        cancelled = meso_progress_advance(p, 1);
        if (!cancelled) {
            /* the callback is rate-limited; wait past the redraw interval */
            double until = meso_time_seconds() + 0.11;
            while (meso_time_seconds() < until) {
            }
        }
    }
    meso_progress_end(p);
    assert_true(cancelled);
    assert_true(seen >= 0.5);
    assert_null(meso_progress_begin(ctx, "nothing", 0));
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_result_strings_cover_every_result),
        cmocka_unit_test(test_log_error_returns_the_code_and_keeps_the_message),
        cmocka_unit_test(test_parallel_for_runs_every_job_once),
        cmocka_unit_test(test_hash_is_fnv1a),
        cmocka_unit_test(test_atomic_file_commit_and_abort),
        cmocka_unit_test(test_progress_reports_and_cancels),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
