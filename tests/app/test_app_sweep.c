/* meso sweep: bad sweep files refused before any job runs; shards merged equal to one process
 * (images byte-identical, metric columns equal); a shard run again skips its finished jobs;
 * shards of different sweeps are not merged; index.html opened in headless Chromium (when
 * installed): every image loads, no script error, sorting by a column works. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "test_util.h"

static char spec_path[1200];

/* Write a sweep file into the test's folder: two scenes, 10 jobs at 32x32. */
static const char *write_spec(const char *name, const char *sizes) {
    static char path[1200];
    char text[2048];
    snprintf(
        text, sizeof text,
        "{\"scenes\": [\"%s/examples/bricks-plane.json\", \"%s/examples/bumps-sphere.json\"],\n"
        " \"techniques\": [\"flat\", \"parallax\", \"relief\"],\n"
        " \"options\": {\"relief\": {\"linear_steps\": [4, 16, 64]}},\n"
        " \"sizes\": [%s], \"frames\": 1}\n",
        MESO_SOURCE_DIR, MESO_SOURCE_DIR, sizes);
    snprintf(path, sizeof path, "%s", test_path(test_temp_dir(), name));
    test_write_file(path, text, strlen(text));
    return path;
}

static int run(const char *format, ...) __attribute__((format(printf, 1, 2)));
static int run(const char *format, ...) {
    char arguments[4096];
    va_list args;
    va_start(args, format);
    vsnprintf(arguments, sizeof arguments, format, args);
    va_end(args);
    const char *err = NULL;
    int status = test_run_meso(arguments, &err);
    if (status != 0) fprintf(stderr, "meso %s: %d: %s\n", arguments, status, err);
    return status;
}

static void expect_refused(const char *json, const char *message) {
    const char *path = test_path(test_temp_dir(), "bad.json");
    test_write_file(path, json, strlen(json));
    char out[1200], arguments[4096];
    snprintf(out, sizeof out, "%s", test_path(test_temp_dir(), "bad-out"));
    snprintf(arguments, sizeof arguments, "sweep %s -o %s", path, out);
    const char *err = NULL;
    assert_int_equal(test_run_meso(arguments, &err), 2);
    if (!strstr(err, message)) fail_msg("expected '%s' in: %s", message, err);
    assert_non_null(strstr(err, "bad.json: "));
    int lines = 0;
    for (const char *c = err; *c; c++) lines += *c == '\n';
    assert_true(lines <= 1);
    struct stat st;
    assert_int_not_equal(stat(out, &st), 0); /* nothing ran, nothing written */
}

static void test_sweep_refuses_bad_files(void **state) {
    (void)state;
    char scene[1100];
    snprintf(scene, sizeof scene, "\"%s/examples/bricks-plane.json\"", MESO_SOURCE_DIR);
    char json[2048];
    snprintf(json, sizeof json, "{\"scenes\": [%s], \"techniques\": [\"relif\"]}", scene);
    expect_refused(json, "techniques[0]: unknown technique 'relif'");
    snprintf(json, sizeof json,
             "{\"scenes\": [%s], \"techniques\": [\"relief\"], \"options\": {\"relief\": "
             "{\"linear_steps\": [4, 5000]}}}",
             scene);
    expect_refused(json, "options.relief.linear_steps[1]: 5000 is not an integer in 1..1024");
    snprintf(json, sizeof json,
             "{\"scenes\": [%s], \"techniques\": [\"relief\"], \"options\": {\"relief\": "
             "{\"steps\": [4]}}}",
             scene);
    expect_refused(json, "options.relief.steps: unknown option of relief");
    snprintf(json, sizeof json,
             "{\"scenes\": [%s], \"techniques\": [\"relief\"], \"options\": {\"vdm\": "
             "{\"refine_steps\": [1]}}}",
             scene);
    expect_refused(json, "options.vdm: 'vdm' is not among the sweep's techniques");
    expect_refused("{\"scenes\": [\"missing.json\"], \"techniques\": \"all\"}", "scenes[0]: ");
    snprintf(json, sizeof json, "{\"scenes\": [%s], \"techniques\": \"all\", \"sizes\": [0]}",
             scene);
    expect_refused(json, "sizes[0]: expected a size");
    snprintf(json, sizeof json, "{\"scenes\": [%s], \"techniques\": \"all\", \"colour\": 1}",
             scene);
    expect_refused(json, "colour: unknown key");
    snprintf(json, sizeof json, "{\"scenes\": [%s], \"techniques\": [\"reference\"]}", scene);
    expect_refused(json, "techniques[0]: 'reference' is the truth");
    expect_refused("{\"scenes\": [", "bad.json: not a JSON object");

    const char *err = NULL;
    const char *spec = write_spec("spec-usage.json", "32");
    char arguments[2048];
    snprintf(arguments, sizeof arguments, "sweep %s -o x --shard 2/2", spec);
    assert_int_equal(test_run_meso(arguments, &err), 2);
    assert_non_null(strstr(err, "--shard: '2/2' is not K/N"));
    snprintf(arguments, sizeof arguments, "sweep %s -o x --shard 0/0", spec);
    assert_int_equal(test_run_meso(arguments, &err), 2);
}

/* The rows of a results.csv without its timing columns (prepare_ms, frame_ms, reference_ms,
 * job_s: the 9th to 12th), into a new string. */
static char *results_without_timing(const char *path) {
    size_t size = 0;
    char *text = test_read_file(path, &size);
    char *out = calloc(size + 1, 1);
    assert_non_null(out);
    size_t n = 0;
    int column = 0;
    bool quoted = false;
    for (size_t i = 0; i < size; i++) {
        char c = text[i];
        if (c == '"') quoted = !quoted;
        bool timing = column >= 8 && column <= 11;
        if (!timing || (c == ',' && !quoted) || c == '\n') out[n++] = c;
        if (c == ',' && !quoted) column++;
        if (c == '\n') column = 0;
    }
    free(text);
    return out;
}

static void expect_same_file(const char *a, const char *b) {
    size_t size_a = 0, size_b = 0;
    char *x = test_read_file(a, &size_a), *y = test_read_file(b, &size_b);
    if (size_a != size_b || memcmp(x, y, size_a) != 0) fail_msg("%s and %s differ", a, b);
    free(x);
    free(y);
}

static void test_sweep_shards_merge_to_one_process(void **state) {
    (void)state;
    const char *spec = write_spec("spec.json", "32");
    snprintf(spec_path, sizeof spec_path, "%s", spec);
    char single[1200], sharded[1200];
    snprintf(single, sizeof single, "%s", test_path(test_temp_dir(), "single"));
    snprintf(sharded, sizeof sharded, "%s", test_path(test_temp_dir(), "sharded"));
    assert_int_equal(run("sweep %s -o %s --quiet", spec, single), 0);
    /* the shards in any order, one of them dealt by id modulo N */
    assert_int_equal(run("sweep %s -o %s --shard 1/2 --quiet", spec, sharded), 0);
    const char *err = NULL;
    char arguments[4096];
    snprintf(arguments, sizeof arguments, "sweep --merge %s", sharded);
    assert_int_equal(test_run_meso(arguments, &err), 2); /* shard 0 has not run */
    assert_non_null(strstr(err, "shard 0 of 2 has not run"));
    assert_int_equal(run("sweep %s -o %s --shard 0/2 --quiet", spec, sharded), 0);
    assert_int_equal(run("sweep --merge %s --quiet", sharded), 0);

    char a[1300], b[1300];
    snprintf(a, sizeof a, "%s/results.csv", single);
    snprintf(b, sizeof b, "%s/results.csv", sharded);
    char *rows_a = results_without_timing(a), *rows_b = results_without_timing(b);
    assert_string_equal(rows_a, rows_b);
    assert_non_null(strstr(rows_a, "bumps-sphere"));
    free(rows_a);
    free(rows_b);
    static const char *const images[] = {
        "jobs/bricks-plane/32x32/relief-linear_steps=16/view-0000.png",
        "jobs/bricks-plane/32x32/relief-linear_steps=16/diff-0000.png",
        "jobs/bumps-sphere/32x32/flat/view-0000.png",
        "jobs/bumps-sphere/32x32/relief-linear_steps=64/view-0000.png",
        "refs/bumps-sphere/32x32/view-0000.png",
        "refs/bricks-plane/32x32/view-0000.png",
    };
    for (size_t i = 0; i < sizeof images / sizeof images[0]; i++) {
        snprintf(a, sizeof a, "%s/%s", single, images[i]);
        snprintf(b, sizeof b, "%s/%s", sharded, images[i]);
        expect_same_file(a, b);
    }

    /* a shard run again skips its finished jobs */
    snprintf(arguments, sizeof arguments, "sweep %s -o %s --shard 0/2", spec, sharded);
    assert_int_equal(test_run_meso(arguments, &err), 0);
    assert_non_null(strstr(err, "already done, 0 to run"));

    /* a shard of another sweep (another size) in the same folder is refused */
    char other[1200]; /* write_spec's buffer is reused */
    snprintf(other, sizeof other, "%s", write_spec("other.json", "24"));
    spec = spec_path;
    snprintf(arguments, sizeof arguments, "sweep %s -o %s --shard 1/2", other, sharded);
    assert_int_equal(test_run_meso(arguments, &err), 2);
    assert_non_null(strstr(err, "written by another sweep"));
    char mixed[1200];
    snprintf(mixed, sizeof mixed, "%s", test_path(test_temp_dir(), "mixed"));
    assert_int_equal(run("sweep %s -o %s --shard 0/2 --quiet", spec, mixed), 0);
    assert_int_equal(run("sweep %s -o %s --shard 1/2 --quiet", other, mixed), 0);
    snprintf(arguments, sizeof arguments, "sweep --merge %s", mixed);
    assert_int_equal(test_run_meso(arguments, &err), 2);
    assert_non_null(strstr(err, "shards of different sweep files cannot be merged"));
}

/* The ids `meso sweep --list` prints for a shard, in order; their count. */
static int listed_ids(const char *spec, const char *shard, const char *partition, int *ids) {
    char command[2048];
    snprintf(command, sizeof command, "%s sweep %s --list --shard %s --partition %s 2>/dev/null",
             MESO_PROGRAM, spec, shard, partition);
    FILE *p = popen(command, "r");
    assert_non_null(p);
    char line[1024];
    int count = 0;
    assert_non_null(fgets(line, sizeof line, p)); /* the heading */
    while (fgets(line, sizeof line, p) && count < 100) ids[count++] = atoi(line);
    assert_int_equal(pclose(p), 0);
    return count;
}

static void test_sweep_lists_jobs_in_a_stable_order(void **state) {
    (void)state;
    /* 2 scenes x 2 sizes x (flat, parallax, relief x 3) = 20 jobs */
    const char *spec = write_spec("spec-list.json", "32, \"40x24\"");
    int all[100], ids[100], seen[20] = {0};
    assert_int_equal(listed_ids(spec, "0/1", "cost", all), 20);
    for (int i = 0; i < 20; i++) assert_int_equal(all[i], i);
    /* by cost: each shard a contiguous run of ids, together every job once */
    int total = 0;
    for (int k = 0; k < 3; k++) {
        char shard[16];
        snprintf(shard, sizeof shard, "%d/3", k);
        int count = listed_ids(spec, shard, "cost", ids);
        assert_true(count > 0);
        for (int i = 0; i < count; i++) {
            if (i > 0) assert_int_equal(ids[i], ids[i - 1] + 1);
            seen[ids[i]]++;
        }
        total += count;
    }
    assert_int_equal(total, 20);
    for (int i = 0; i < 20; i++) assert_int_equal(seen[i], 1);
    int count = listed_ids(spec, "1/3", "modulo", ids);
    assert_int_equal(count, 7);
    for (int i = 0; i < count; i++) assert_int_equal(ids[i], 1 + 3 * i);
}

/* Three shards started at once on a cold cache, each needing every bake (modulo: every shard
 * has jobs of both scenes): each entry is baked and stored once, the others wait for it. */
static void test_sweep_concurrent_shards_bake_each_entry_once(void **state) {
    (void)state;
    char cache[1200], out[1200], logs[1200], spec[1200], command[8192];
    snprintf(cache, sizeof cache, "%s", test_path(test_temp_dir(), "cold-cache"));
    snprintf(out, sizeof out, "%s", test_path(test_temp_dir(), "cold"));
    snprintf(logs, sizeof logs, "%s", test_path(test_temp_dir(), "cold-stored.txt"));
    snprintf(spec, sizeof spec, "%s", test_path(test_temp_dir(), "cold.json"));
    char text[1024];
    snprintf(text, sizeof text,
             "{\"scenes\": [\"%s/examples/bricks-plane.json\", \"%s/examples/bumps-sphere.json\"],"
             " \"techniques\": [\"relief_exact\", \"relief_layers\"], \"sizes\": [24, 32],"
             " \"frames\": 1}",
             MESO_SOURCE_DIR, MESO_SOURCE_DIR);
    test_write_file(spec, text, strlen(text));
    snprintf(command, sizeof command,
             "export MESO_CACHE_DIR=%s; for k in 0 1 2; do %s sweep %s -o %s --shard $k/3 "
             "--partition modulo --verbose 2>&1 | grep 'bake cache: stored' & done; wait",
             cache, MESO_PROGRAM, spec, out);
    char capture[9600];
    snprintf(capture, sizeof capture, "(%s) > %s", command, logs);
    assert_int_equal(system(capture), 0);
    size_t size = 0;
    char *stored = test_read_file(logs, &size);
    /* cone and relief_layers of each scene: 4 entries, each stored by one shard only */
    int lines = 0;
    for (char *line = stored; (line = strstr(line, "stored ")) != NULL; line++) {
        lines++;
        char *end = strchr(line, '\n');
        size_t length = end ? (size_t)(end - line) : strlen(line);
        char *again = line + length;
        while ((again = strstr(again, "stored ")) != NULL) {
            if (!strncmp(again, line, length)) fail_msg("stored twice: %.*s", (int)length, line);
            again++;
        }
    }
    assert_int_equal(lines, 4);
    free(stored);
}

/* Orbit views: every view's image and difference, the metrics averaged, flicker measured. */
static void test_sweep_orbit_views_measure_flicker(void **state) {
    (void)state;
    char spec[1200], out[1200], text[1024];
    snprintf(spec, sizeof spec, "%s", test_path(test_temp_dir(), "orbit.json"));
    snprintf(out, sizeof out, "%s", test_path(test_temp_dir(), "orbit"));
    snprintf(text, sizeof text,
             "{\"scenes\": [\"%s/examples/bumps-sphere.json\"], \"techniques\": [\"flat\", "
             "\"relief\"], \"sizes\": [24], \"frames\": 1, \"orbit\": 3}",
             MESO_SOURCE_DIR);
    test_write_file(spec, text, strlen(text));
    assert_int_equal(run("sweep %s -o %s --quiet", spec, out), 0);
    char path[1400];
    snprintf(path, sizeof path, "%s/jobs/bumps-sphere/24x24/relief/view-0002.png", out);
    struct stat st;
    assert_int_equal(stat(path, &st), 0);
    snprintf(path, sizeof path, "%s/jobs/bumps-sphere/24x24/relief/diff-0002.png", out);
    assert_int_equal(stat(path, &st), 0);
    snprintf(path, sizeof path, "%s/refs/bumps-sphere/24x24/view-0002.png", out);
    assert_int_equal(stat(path, &st), 0);
    snprintf(path, sizeof path, "%s/results.json", out);
    size_t size = 0;
    char *json = test_read_file(path, &size);
    assert_non_null(strstr(json, "\"views\": 3"));
    const char *job_s = strstr(json, "\"job_s\": ");
    assert_non_null(job_s);
    assert_true(atof(job_s + 9) > 0.0); /* the job's wall time, read back from its result */
    /* flat shades no mesostructure: its change between views is the truth's change minus the
     * relief's, not zero; relief follows the truth more closely */
    const char *flat = strstr(json, "\"technique\": \"flat\"");
    const char *relief = strstr(json, "\"technique\": \"relief\"");
    assert_non_null(flat);
    assert_non_null(relief);
    double flicker_flat = atof(strstr(flat, "\"flicker\": ") + 11);
    double flicker_relief = atof(strstr(relief, "\"flicker\": ") + 11);
    assert_true(flicker_flat > 0.0);
    assert_true(flicker_relief > 0.0);
    assert_true(flicker_relief < flicker_flat);
    free(json);
}

static bool have_chromium(void) { return access("/usr/bin/chromium", X_OK) == 0; }

static void test_sweep_report_opens_in_chromium(void **state) {
    (void)state;
    if (!have_chromium()) {
        fprintf(stderr, "test_app_sweep: chromium is not installed (scripts/install-deps.sh): "
                        "the page is not opened\n");
        skip();
    }
    char dir[1200];
    snprintf(dir, sizeof dir, "%s", test_path(test_temp_dir(), "single"));
    char page[1300];
    snprintf(page, sizeof page, "%s/index.html", dir);
    struct stat st;
    if (stat(page, &st) != 0) /* run alone */
        assert_int_equal(run("sweep %s -o %s --quiet", write_spec("spec.json", "32"), dir), 0);
    char profile[1200], dom[1200], shot[1200], log[1200], command[8192];
    snprintf(profile, sizeof profile, "%s", test_path(test_temp_dir(), "chromium-profile"));
    snprintf(dom, sizeof dom, "%s", test_path(test_temp_dir(), "dom.html"));
    snprintf(shot, sizeof shot, "%s", test_path(test_temp_dir(), "index.png"));
    snprintf(log, sizeof log, "%s", test_path(test_temp_dir(), "chromium.log"));
    static const char flags[] =
        "--headless --no-sandbox --disable-gpu --disable-quic --no-first-run "
        "--disable-background-networking --disable-component-update --disable-sync "
        "--enable-logging=stderr --v=0 --virtual-time-budget=10000";
    /* sorted by covered PSNR, highest first, through the page's #sort= hash */
    snprintf(command, sizeof command,
             "rm -rf %s && /usr/bin/chromium %s --user-data-dir=%s --dump-dom "
             "'file://%s#sort=psnr_covered_db:desc' >%s 2>%s",
             profile, flags, profile, page, dom, log);
    assert_int_equal(system(command), 0);
    snprintf(command, sizeof command,
             "rm -rf %s && /usr/bin/chromium %s --user-data-dir=%s --window-size=1280,1400 "
             "--screenshot=%s 'file://%s' >/dev/null 2>>%s; rm -rf %s",
             profile, flags, profile, shot, page, log, profile);
    assert_int_equal(system(command), 0);

    size_t size = 0;
    char *text = test_read_file(dom, &size);
    const char *body = strstr(text, "<body");
    assert_non_null(body);
    if (!strstr(body, "data-broken-images=\"0\"") || !strstr(body, "data-script-errors=\"0\"") ||
        !strstr(body, "data-sorted=\"psnr_covered_db:desc\""))
        fail_msg("the page did not load cleanly: %.200s", body);
    /* the table's rows in order of the covered PSNR column (the 14th), highest first */
    int rows = 0;
    double previous = 1e30;
    for (const char *row = strstr(body, "<tbody>"); (row = strstr(row, "<tr>")) != NULL; row++) {
        const char *cell = row;
        for (int c = 0; c < 14; c++) cell = strstr(cell + 1, "<td");
        const char *value = strstr(cell, "data-v=\"");
        assert_non_null(value);
        double psnr = atof(value + 8);
        assert_true(psnr <= previous);
        previous = psnr;
        rows++;
    }
    assert_int_equal(rows, 10);
    free(text);
    char *messages = test_read_file(log, &size);
    if (strstr(messages, "Uncaught") || strstr(messages, "CONSOLE"))
        fail_msg("console messages: %.300s", messages);
    free(messages);

    /* the screenshot: the page drawn, not blank */
    meso_context *ctx = test_context(1);
    meso_image *image = NULL;
    assert_int_equal(meso_image_load_png(ctx, shot, &image), MESO_OK);
    assert_int_equal(image->width, 1280);
    size_t dark = 0, n = (size_t)image->width * (size_t)image->height;
    for (size_t i = 0; i < n; i++) dark += image->pixels[i * (size_t)image->channels] < 0.5f;
    assert_true(dark > n / 200); /* text, plots and table lines */
    meso_image_destroy(image);
    meso_context_destroy(ctx);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sweep_refuses_bad_files),
        cmocka_unit_test(test_sweep_shards_merge_to_one_process),
        cmocka_unit_test(test_sweep_lists_jobs_in_a_stable_order),
        cmocka_unit_test(test_sweep_orbit_views_measure_flicker),
        cmocka_unit_test(test_sweep_concurrent_shards_bake_each_entry_once),
        cmocka_unit_test(test_sweep_report_opens_in_chromium),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
