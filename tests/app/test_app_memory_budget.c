/* The memory budget (--memory-limit) where the work grows with an option or an input: each job
 * below once took gigabytes past a small limit. Now each is refused before the work, or stops
 * within the limit: the program's peak resident memory (from wait4) stays under the limit plus
 * 64 MB, and the refusal is one line, status 2. */
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include "test_util.h"
#include "meso/runtime.h"

#define MIB (1024.0 * 1024.0)

/* Run meso with argv (NULL-terminated, after the program), stderr to a file read back into
 * *out_stderr; the exit status, and the peak resident memory in MiB. */
static int run_measured(const char *const *argv, const char **out_stderr, double *out_peak_mib) {
    static char err[8192];
    char err_path[1200];
    snprintf(err_path, sizeof err_path, "%s/budget-stderr.txt", test_temp_dir());
    const char *args[32] = {MESO_PROGRAM};
    int n = 1;
    for (; argv[n - 1] && n < 31; n++) args[n] = argv[n - 1];
    args[n] = NULL;
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        int fd = open(err_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        int null = open("/dev/null", O_RDWR);
        if (fd < 0 || null < 0) _exit(127);
        dup2(fd, 2);
        dup2(null, 1);
        dup2(null, 0);
        execv(MESO_PROGRAM, (char *const *)args);
        _exit(127);
    }
    int status = 0;
    struct rusage usage;
    assert_int_equal(wait4(pid, &status, 0, &usage), pid);
    err[0] = 0;
    FILE *f = fopen(err_path, "rb");
    if (f) {
        err[fread(err, 1, sizeof err - 1, f)] = 0;
        fclose(f);
    }
    *out_stderr = err;
    *out_peak_mib = (double)usage.ru_maxrss / 1024.0;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/* Refused with status 2 and one line containing `needle`, within limit_mib + 64 MiB. */
static void expect_refused_within(const char *const *argv, double limit_mib, const char *needle) {
    const char *err = NULL;
    double peak = 0.0;
    double start = meso_time_seconds();
    int status = run_measured(argv, &err, &peak);
    size_t length = strlen(err);
    const char *refusal = err; /* the last line: a warning may come before it */
    for (size_t i = 0; i + 1 < length; i++)
        if (err[i] == '\n') refusal = err + i + 1;
    if (status != 2 || strncmp(refusal, "meso: ", 6) != 0 || !strstr(refusal, needle))
        fail_msg("%s %s ...: status %d (want 2), stderr: %s (want '%s')", argv[0], argv[1], status,
                 err, needle);
    /* AddressSanitizer's shadow memory and quarantine inflate the resident size: the peak is
     * held to the limit in the ordinary build only */
    bool sanitized = sizeof(MESO_SANITIZE_FLAGS) > 1;
    if (!sanitized && peak > limit_mib + 64.0)
        fail_msg("%s %s: peak %.0f MiB, over the limit %.0f MiB + 64", argv[0], argv[1], peak,
                 limit_mib);
    print_message("      %s: refused in %.2f s at a peak of %.0f MiB (limit %.0f MiB)\n", needle,
                  meso_time_seconds() - start, peak, limit_mib);
}

static const char *write_text(const char *name, const char *text) {
    const char *path = test_path(test_temp_dir(), name);
    test_write_file(path, text, strlen(text));
    return path;
}

/* max_level 10 with every threshold 0 asks for 4^10 triangles a base triangle: 8.6 G on a
 * 64-segment plane (it was killed at 24.4 GB). */
static void test_tessellation_stops_within_the_limit(void **state) {
    (void)state;
    const char *scene = write_text(
        "budget-tessellation.json",
        "{\"image\": {\"width\": 64, \"height\": 64}, \"camera\": {\"eye\": [0, 2, 2],"
        " \"target\": [0, 0, 0], \"up\": [0, 1, 0], \"fov_y_deg\": 45},"
        " \"objects\": [{\"shape\": \"plane\", \"segments\": 64, \"technique\": \"tessellation\","
        " \"technique_options\": {\"max_level\": 10, \"normal_threshold\": 0, \"area_threshold\":"
        " 0, \"view_threshold\": 0, \"span_texels\": 0}, \"mesostructure\": {\"height_map\":"
        " {\"procedural\": \"bumps\", \"resolution\": 1024}, \"depth\": 0.1}}]}");
    const char *out = test_path(test_temp_dir(), "budget-tessellation.png");
    const char *argv[] = {"render", scene, "-o", out, "--memory-limit", "256M", NULL};
    expect_refused_within(argv, 256.0, "tessellation: more than");
}

/* 16 directional lights with 8192^2 shadow maps: 4.3 GB of depth (it succeeded at 4.22 GB
 * under a 512M limit), for both techniques with shadow maps. */
static void test_shadow_maps_are_within_the_limit(void **state) {
    (void)state;
    const char *techniques[] = {"tessellation", "displacement"};
    for (int t = 0; t < 2; t++) {
        char lights[2048] = "", text[4096];
        for (int l = 0; l < 16; l++)
            snprintf(lights + strlen(lights), sizeof lights - strlen(lights),
                     "%s{\"type\": \"directional\", \"direction\": [%.1f, 1, 0.3],"
                     " \"color\": [0.1, 0.1, 0.1]}",
                     l ? ", " : "", 0.1 * l - 0.8);
        snprintf(text, sizeof text,
                 "{\"image\": {\"width\": 64, \"height\": 64}, \"camera\": {\"eye\": [0, 2, 2],"
                 " \"target\": [0, 0, 0], \"up\": [0, 1, 0], \"fov_y_deg\": 45},"
                 " \"lights\": [%s], \"objects\": [{\"shape\": \"plane\", \"segments\": 8,"
                 " \"technique\": \"%s\", \"technique_options\": {\"shadow_map_size\": 8192},"
                 " \"mesostructure\": {\"height_map\": {\"procedural\": \"bumps\","
                 " \"resolution\": 256}, \"depth\": 0.1}}]}",
                 lights, techniques[t]);
        const char *scene = write_text("budget-shadows.json", text);
        const char *out = test_path(test_temp_dir(), "budget-shadows.png");
        const char *argv[] = {"render", scene, "-o", out, "--memory-limit", "512M", NULL};
        expect_refused_within(argv, 512.0, "shadow maps: needs about 4.00 GiB");
    }
}

/* Every technique at 4096^2: the sheet (16424 pixels wide) and the kept images were refused
 * only after 99 s of rendering; both are known before the work. */
static void test_techniques_sheet_and_images_are_checked_before_the_work(void **state) {
    (void)state;
    const char *dir = test_path(test_temp_dir(), "budget-techniques");
    const char *argv[] = {"render",
                          MESO_SOURCE_DIR "/examples/bricks-plane.json",
                          "--techniques",
                          "all",
                          "--size",
                          "4096x4096",
                          "--memory-limit",
                          "1G",
                          "-o",
                          dir,
                          NULL};
    double start = meso_time_seconds();
    expect_refused_within(argv, 1024.0, "sheet: 16424x");
    assert_true(meso_time_seconds() - start < 10.0);
    /* a smaller sheet fits; the five runs' kept images (335 MB) do not fit the budget */
    const char *fewer[] = {"render",
                           MESO_SOURCE_DIR "/examples/bricks-plane.json",
                           "--techniques",
                           "flat,bump,parallax,relief",
                           "--size",
                           "2048x2048",
                           "--memory-limit",
                           "256M",
                           "-o",
                           dir,
                           NULL};
    expect_refused_within(fewer, 256.0, "bricks-plane.json: needs about");
}

/* PNGs are refused from their header: 8192^2 declares 768 MiB of floats (compare took 3.43 GB
 * under 64M; a height map reached 545 MB before its refusal under 128M). */
static void test_decoded_pngs_are_checked_from_their_header(void **state) {
    (void)state;
    const char *png = test_path(test_temp_dir(), "budget-8192.png");
    test_write_png_header(png, 8192, 8192);
    const char *compare[] = {"compare", png, png, "--memory-limit", "64M", NULL};
    expect_refused_within(compare, 64.0, "budget-8192.png: needs about 768.0 MiB");
    char text[1024];
    snprintf(text, sizeof text,
             "{\"camera\": {\"eye\": [0, 2, 2], \"target\": [0, 0, 0], \"up\": [0, 1, 0],"
             " \"fov_y_deg\": 45}, \"objects\": [{\"shape\": \"plane\", \"mesostructure\":"
             " {\"height_map\": \"budget-8192.png\", \"depth\": 0.1}}]}");
    const char *scene = write_text("budget-height-map.json", text);
    const char *info[] = {"info", scene, "--memory-limit", "128M", NULL};
    expect_refused_within(info, 128.0, "budget-8192.png: needs about 768.0 MiB");
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_tessellation_stops_within_the_limit),
        cmocka_unit_test(test_shadow_maps_are_within_the_limit),
        cmocka_unit_test(test_techniques_sheet_and_images_are_checked_before_the_work),
        cmocka_unit_test(test_decoded_pngs_are_checked_from_their_header),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
