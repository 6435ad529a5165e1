/* Where stderr is not a terminal (a log, CI, `make demo | tee`), no progress bar is drawn; a
 * bake that proves long still says so in one line, "meso: baking gdm for weave-plane (about
 * 10 s)", instead of leaving the log silent. Short bakes, other work and --quiet print
 * nothing. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "test_util.h"
#include "meso/runtime.h"

static void sleep_ms(long ms) {
    struct timespec t = {ms / 1000, (ms % 1000) * 1000000L};
    nanosleep(&t, NULL);
}

/* What `units` units of `total`, one every `ms` milliseconds, print on stderr (redirected to
 * a file) with the context's progress mode; bake: begun as a bake. */
static char *stderr_of(meso_progress_mode mode, bool bake, uint64_t total, uint64_t units,
                       long ms) {
    const char *path = test_path(test_temp_dir(), "stderr.txt");
    fflush(stderr);
    int saved = dup(STDERR_FILENO);
    FILE *file = fopen(path, "w");
    assert_non_null(file);
    dup2(fileno(file), STDERR_FILENO);
    meso_context *ctx = NULL;
    meso_context_desc desc = {.num_threads = 1, .progress = mode};
    assert_int_equal(meso_context_create(&desc, &ctx), MESO_OK);
    meso_context_set_subject(ctx, "weave-plane");
    meso_progress *p = bake ? meso_progress_begin_bake(ctx, "gdm", total)
                            : meso_progress_begin(ctx, "render", total);
    for (uint64_t i = 0; i < units; i++) {
        sleep_ms(ms);
        meso_progress_advance(p, 1);
    }
    meso_progress_end(p);
    meso_context_destroy(ctx);
    fflush(stderr);
    dup2(saved, STDERR_FILENO);
    close(saved);
    fclose(file);
    size_t size;
    return test_read_file(path, &size);
}

static void test_a_long_bake_says_so_in_one_line(void **state) {
    (void)state;
    /* 20 of 1000 units in 0.4 s: about 20 s in all (more on a busy machine) */
    char *text = stderr_of(MESO_PROGRESS_DEFAULT, true, 1000, 20, 20);
    const char *start = "meso: baking gdm for weave-plane (about ";
    if (strncmp(text, start, strlen(start)) != 0) fail_msg("stderr: '%s'", text);
    double seconds = atof(text + strlen(start));
    if (!(seconds >= 10.0)) fail_msg("stderr: '%s'", text);
    if (strchr(text, '\n') != text + strlen(text) - 1) fail_msg("not one line: '%s'", text);
    free(text);
}

static void test_short_bakes_other_work_and_quiet_say_nothing(void **state) {
    (void)state;
    char *text = stderr_of(MESO_PROGRESS_DEFAULT, true, 20, 20, 1); /* about 20 ms */
    assert_string_equal(text, "");
    free(text);
    text = stderr_of(MESO_PROGRESS_DEFAULT, false, 1000, 20, 20); /* not a bake */
    assert_string_equal(text, "");
    free(text);
    text = stderr_of(MESO_PROGRESS_NEVER, true, 1000, 20, 20); /* --quiet */
    assert_string_equal(text, "");
    free(text);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_a_long_bake_says_so_in_one_line),
        cmocka_unit_test(test_short_bakes_other_work_and_quiet_say_nothing),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
