/* The bake cache's claim on an entry (meso_bake_cache_claim_entry): a second process asking
 * for the claim a first one holds waits until it is released, and the lock file is gone after;
 * a lock file left by a killed holder is taken over. */
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "meso/bake_cache.h"
#include "meso/bake_file.h"
#include "test_util.h"

static bool exists(const char *path) {
    struct stat st;
    return stat(path, &st) == 0;
}

static void test_claim_waits_for_the_holder(void **state) {
    (void)state;
    char dir[1100], held[1200], released[1200];
    snprintf(dir, sizeof dir, "%s", test_path(test_temp_dir(), "claim_cache"));
    mkdir(dir, 0755);
    setenv("MESO_CACHE_DIR", dir, 1);
    snprintf(held, sizeof held, "%s/held", test_temp_dir());
    snprintf(released, sizeof released, "%s/released", test_temp_dir());
    meso_context *ctx = test_context(1);
    pid_t child = fork();
    assert_true(child >= 0);
    if (child == 0) { /* the holder: claims, says so, works a while, says it lets go, releases */
        meso_bake_cache_claim claim;
        meso_bake_cache_claim_entry(ctx, "vdm", 0x1234, &claim);
        test_write_file(held, "1", 1);
        usleep(300000);
        test_write_file(released, "1", 1);
        meso_bake_cache_release(&claim);
        _exit(claim.path[0] && exists(claim.path) ? 1 : 0);
    }
    while (!exists(held)) usleep(1000);
    meso_bake_cache_claim claim;
    meso_bake_cache_claim_entry(ctx, "vdm", 0x1234, &claim);
    assert_true(claim.fd >= 0);
    /* the claim came only after the holder let go, whatever the timing */
    assert_true(exists(released));
    assert_true(exists(claim.path));
    meso_bake_cache_release(&claim);
    assert_false(exists(claim.path));
    int status = 0;
    assert_int_equal(waitpid(child, &status, 0), child);
    assert_true(WIFEXITED(status) && WEXITSTATUS(status) == 0);

    /* a lock file a killed holder left (no lock on it) is taken over and removed */
    char stale[1300];
    snprintf(stale, sizeof stale, "%s/gdm-0000000000000042.mesobake.lock", dir);
    test_write_file(stale, "", 0);
    meso_bake_cache_claim_entry(ctx, "gdm", 0x42, &claim);
    assert_true(claim.fd >= 0);
    assert_string_equal(claim.path, stale);
    meso_bake_cache_release(&claim);
    assert_false(exists(stale));

    /* the cache off: an empty claim, nothing written */
    setenv("MESO_CACHE_DIR", "off", 1);
    meso_bake_cache_claim_entry(ctx, "gdm", 0x42, &claim);
    assert_int_equal(claim.fd, -1);
    meso_bake_cache_release(&claim);
    unsetenv("MESO_CACHE_DIR");
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_claim_waits_for_the_holder),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
