/* Outputs on a full disk: a small tmpfs the test mounts (as root, as in CI; skipped with a
 * message otherwise) and fills. A failed write ends the command at once with one line naming
 * the file and the system's reason, exit status 1 (the machine's fault, not the input's), and
 * no output of the command is changed: every one is written and synced before the first is
 * renamed into place. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <sys/wait.h>
#include <unistd.h>

#include "test_util.h"

#define SCENE MESO_SOURCE_DIR "/examples/bricks-plane.json"

static char mount_dir[1200];
static bool mounted;

/* 2 MB of tmpfs under the test's folder; skipped (every test) when it cannot be mounted. */
static int mount_small_disk(void **state) {
    (void)state;
    snprintf(mount_dir, sizeof mount_dir, "%s/full-disk", test_temp_dir());
    mkdir(mount_dir, 0755);
    if (geteuid() != 0) {
        fprintf(stderr, "test_app_full_disk: skipped: mounting a tmpfs needs root\n");
        return 0;
    }
    if (mount("tmpfs", mount_dir, "tmpfs", 0, "size=2m") != 0) {
        fprintf(stderr, "test_app_full_disk: skipped: cannot mount a tmpfs: %s\n", strerror(errno));
        return 0;
    }
    mounted = true;
    return 0;
}

/* Runs after the tests whether they passed or failed. */
static int unmount_small_disk(void **state) {
    (void)state;
    if (mounted && umount2(mount_dir, MNT_DETACH) != 0)
        fprintf(stderr, "test_app_full_disk: cannot unmount %s: %s\n", mount_dir, strerror(errno));
    mounted = false;
    return 0;
}

static void require_disk(void) {
    if (!mounted) skip();
}

/* Fill the disk but for about `leave` bytes (a file named fill), or remove the filling. */
static void fill_disk(size_t leave) {
    const char *fill = test_path(mount_dir, "fill");
    unlink(fill);
    if (leave == SIZE_MAX) return;
    struct statvfs vfs;
    assert_int_equal(statvfs(mount_dir, &vfs), 0);
    size_t available = (size_t)vfs.f_bavail * vfs.f_frsize;
    size_t size = available > leave ? available - leave : 0;
    FILE *f = fopen(fill, "wb");
    assert_non_null(f);
    static char block[65536];
    while (size > 0) {
        size_t n = size < sizeof block ? size : sizeof block;
        if (fwrite(block, 1, n, f) != n) break;
        size -= n;
    }
    fclose(f);
}

/* `meso arguments` with a time limit (a hang is a failure, not a stuck suite): the status
 * (124 when it had to be killed) and stderr. */
static int run_meso_with_timeout(const char *arguments, const char **out_stderr) {
    static char err[8192];
    char err_path[1300], command[8192];
    snprintf(err_path, sizeof err_path, "%s/full-disk-stderr.txt", test_temp_dir());
    snprintf(command, sizeof command, "timeout -s KILL 60 %s %s >/dev/null 2>%s </dev/null",
             MESO_PROGRAM, arguments, err_path);
    int status = system(command);
    err[0] = 0;
    FILE *f = fopen(err_path, "rb");
    if (f) {
        err[fread(err, 1, sizeof err - 1, f)] = 0;
        fclose(f);
    }
    *out_stderr = err;
    if (WIFSIGNALED(status)) return 124;
    int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return code == 128 + 9 ? 124 : code;
}

/* Status 1 and one line: "meso: <name>...: cannot write: No space left on device". */
static void expect_disk_full(const char *arguments, const char *name) {
    const char *err = NULL;
    int status = run_meso_with_timeout(arguments, &err);
    size_t length = strlen(err);
    if (status != 1 || strncmp(err, "meso: ", 6) != 0 || !strstr(err, name) ||
        !strstr(err, "No space left on device") || length == 0 || err[length - 1] != '\n' ||
        memchr(err, '\n', length - 1))
        fail_msg("meso %s\n  status %d (want 1; 124: killed after 60 s), stderr: %s", arguments,
                 status, err);
}

static bool same_file(const char *a, const char *b) {
    size_t size_a = 0, size_b = 0;
    char *data_a = test_read_file(a, &size_a), *data_b = test_read_file(b, &size_b);
    bool same = size_a == size_b && memcmp(data_a, data_b, size_a) == 0;
    free(data_a);
    free(data_b);
    return same;
}

static void copy_file(const char *from, const char *to) {
    size_t size = 0;
    char *data = test_read_file(from, &size);
    test_write_file(to, data, size);
    free(data);
}

static void test_full_disk_ends_png_and_exr_writes_with_one_line_status_1(void **state) {
    (void)state;
    require_disk();
    fill_disk(0);
    char arguments[4096];
    /* OpenEXR: the library's error handler once waited forever on a lock its writer held */
    snprintf(arguments, sizeof arguments, "render " SCENE " -o %s/x.exr --size 32x32 --quiet",
             mount_dir);
    expect_disk_full(arguments, "x.exr: cannot write");
    snprintf(arguments, sizeof arguments, "render " SCENE " -o %s/x.png --size 32x32 --quiet",
             mount_dir);
    expect_disk_full(arguments, "x.png: cannot write");
    /* a PNG larger than stdio's buffer fails inside libpng, which said only "Write Error" */
    snprintf(arguments, sizeof arguments,
             "render " SCENE " -o %s/big.png --size 512x512 --technique flat --quiet", mount_dir);
    expect_disk_full(arguments, "big.png: cannot write");
    struct stat st;
    assert_int_equal(stat(test_path(mount_dir, "x.exr"), &st), -1);
    assert_int_equal(stat(test_path(mount_dir, "x.png"), &st), -1);
    fill_disk(SIZE_MAX);
}

static void test_coverage_on_a_full_disk_leaves_the_image_unchanged(void **state) {
    (void)state;
    require_disk();
    const char *dir = test_temp_dir();
    char out[1200], before[1200], arguments[4096];
    snprintf(out, sizeof out, "%s/coverage-full.png", dir);
    snprintf(before, sizeof before, "%s/coverage-full-before.png", dir);
    snprintf(arguments, sizeof arguments, "render " SCENE " -o %s --size 16x16 --quiet", out);
    assert_int_equal(test_run_meso(arguments, NULL), 0);
    copy_file(out, before);
    fill_disk(0);
    snprintf(arguments, sizeof arguments,
             "render " SCENE " -o %s --size 32x32 --coverage %s/cov.png --quiet", out, mount_dir);
    expect_disk_full(arguments, "cov.png: cannot write");
    assert_true(same_file(out, before));
    fill_disk(SIZE_MAX);
}

static void test_techniques_folder_on_a_full_disk_is_left_as_it_was(void **state) {
    (void)state;
    require_disk();
    char out[1300], arguments[4096];
    snprintf(out, sizeof out, "%s/techniques", mount_dir);
    snprintf(arguments, sizeof arguments,
             "render " SCENE " --techniques flat,bump,parallax -o %s --size 48x48 --frames 1 "
             "--quiet",
             out);
    assert_int_equal(test_run_meso(arguments, NULL), 0);
    /* keep the first run's files outside the disk */
    static const char *const names[] = {"flat.png",    "bump.png",     "parallax.png", "sheet.png",
                                        "results.csv", "results.json", "reference.png"};
    const size_t count = sizeof names / sizeof names[0];
    char kept[8][1300];
    for (size_t i = 0; i < count; i++) {
        snprintf(kept[i], sizeof kept[i], "%s/techniques-before-%s", test_temp_dir(), names[i]);
        copy_file(test_path(out, names[i]), kept[i]);
    }
    /* room for a few of the second run's images, not for all of its files */
    fill_disk(24 * 1024);
    snprintf(arguments, sizeof arguments,
             "render " SCENE " --techniques flat,bump,parallax -o %s --size 64x64 --frames 1 "
             "--quiet",
             out);
    expect_disk_full(arguments, "cannot write");
    for (size_t i = 0; i < count; i++)
        if (!same_file(test_path(out, names[i]), kept[i]))
            fail_msg("%s was changed by the run that failed", names[i]);
    fill_disk(SIZE_MAX);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_full_disk_ends_png_and_exr_writes_with_one_line_status_1),
        cmocka_unit_test(test_coverage_on_a_full_disk_leaves_the_image_unchanged),
        cmocka_unit_test(test_techniques_folder_on_a_full_disk_is_left_as_it_was),
    };
    return cmocka_run_group_tests(tests, mount_small_disk, unmount_small_disk);
}
