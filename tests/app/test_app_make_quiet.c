/* `make demo` (and `make test`) build first: the build's progress lines (~830 on a fresh
 * clone, ~150 "Built target" lines when up to date) buried the first picture. The build is
 * quiet unless asked (make VERBOSE=1); its warnings and errors, on stderr, still show. Run on
 * this test's own, up-to-date build tree: nothing to build, so nothing to say but one line. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"

static void test_an_up_to_date_build_is_quiet(void **state) {
    (void)state;
    const char *out = test_path(test_temp_dir(), "make.txt");
    char command[4096];
    /* a make of its own, not a job of the `make test` that may be running this */
    snprintf(command, sizeof command,
             "env -u MAKEFLAGS -u MFLAGS -u MAKELEVEL make -C %s build BUILD=%s JOBS=1 "
             "> %s 2>&1",
             MESO_SOURCE_DIR, MESO_BINARY_DIR, out);
    int status = system(command);
    size_t size;
    char *text = test_read_file(out, &size);
    if (status != 0) fail_msg("make build failed:\n%s", text);
    int lines = 0;
    for (const char *c = text; *c; c++) lines += *c == '\n';
    if (lines > 2) fail_msg("make build said %d lines:\n%s", lines, text);
    free(text);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_an_up_to_date_build_is_quiet),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
