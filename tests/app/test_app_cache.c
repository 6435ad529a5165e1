/* meso cache list|size|clear on a cache folder of its own: only meso's bake files are listed
 * and removed. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "test_util.h"

/* Run the program with stdout captured into out. */
static int run_capture(const char *arguments, char *out, size_t size) {
    char command[4096];
    snprintf(command, sizeof command, "%s %s 2>/dev/null", MESO_PROGRAM, arguments);
    FILE *p = popen(command, "r");
    assert_non_null(p);
    size_t n = fread(out, 1, size - 1, p);
    out[n] = 0;
    int status = pclose(p);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

static void test_cache_lists_sizes_and_clears_only_bakes(void **state) {
    (void)state;
    char dir[1100];
    snprintf(dir, sizeof dir, "%s/cache", test_temp_dir());
    mkdir(dir, 0755);
    setenv("MESO_CACHE_DIR", dir, 1);
    char big[3000];
    memset(big, 'x', sizeof big);
    test_write_file(test_path(dir, "vdm-00000000000000aa.mesobake"), big, 2048);
    test_write_file(test_path(dir, "horizon-00000000000000bb.mesobake"), big, 1000);
    test_write_file(test_path(dir, "vdm-00000000000000cc.mesobake.tmpAbc123"), big, 10);
    test_write_file(test_path(dir, "notes.txt"), "mine", 4);

    char out[4096];
    assert_int_equal(run_capture("cache list", out, sizeof out), 0);
    const char *horizon = strstr(out, "horizon-00000000000000bb.mesobake");
    const char *vdm = strstr(out, "vdm-00000000000000aa.mesobake");
    assert_non_null(horizon);
    assert_non_null(vdm);
    assert_true(horizon < vdm); /* sorted by name */
    assert_null(strstr(out, "notes.txt"));
    assert_int_equal(run_capture("cache size", out, sizeof out), 0);
    assert_non_null(strstr(out, "3 bakes, 0.0 MiB (3058 bytes) in "));
    assert_int_equal(run_capture("cache clear", out, sizeof out), 0);
    assert_int_equal(run_capture("cache size", out, sizeof out), 0);
    assert_non_null(strstr(out, "0 bakes, 0.0 MiB (0 bytes)"));
    struct stat st;
    assert_int_equal(stat(test_path(dir, "notes.txt"), &st), 0); /* the user's file stays */

    setenv("MESO_CACHE_DIR", "off", 1);
    assert_int_equal(run_capture("cache size", out, sizeof out), 0);
    assert_non_null(strstr(out, "the bake cache is off"));
    const char *err = NULL;
    assert_int_equal(test_run_meso("cache remove", &err), 2);
    assert_non_null(strstr(err, "meso: cache: unknown action 'remove' (list, size or clear)"));
    assert_int_equal(test_run_meso("cache", &err), 2);
    unsetenv("MESO_CACHE_DIR");
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cache_lists_sizes_and_clears_only_bakes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
