/* The meso program against the inputs of the bad-input campaign, kept under
 * tests/data/bad/: every one refused with status 2 and one line "meso: <file>: <reason>", and
 * outputs written all or none, never through a FIFO or device, never leaving temporaries. */
#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "test_util.h"
#include "meso/runtime.h"

#define BAD MESO_SOURCE_DIR "/tests/data/bad/"
#define SCENE MESO_SOURCE_DIR "/examples/bricks-plane.json"

/* Status 2, exactly one line on stderr, "meso: " then `needle` somewhere. */
static void expect_refused(const char *arguments, const char *needle) {
    const char *err = NULL;
    int status = test_run_meso(arguments, &err);
    size_t length = strlen(err);
    if (status != 2 || strncmp(err, "meso: ", 6) != 0 || !strstr(err, needle) || length == 0 ||
        err[length - 1] != '\n' || memchr(err, '\n', length - 1))
        fail_msg("meso %s\n  status %d (want 2), stderr: %s  (want one line with '%s')", arguments,
                 status, err, needle);
}

static bool exists(const char *path) {
    struct stat st;
    return lstat(path, &st) == 0;
}

/* Whether `dir` holds a file whose name contains ".tmp". */
static bool has_temporaries(const char *dir) {
    DIR *d = opendir(dir);
    assert_non_null(d);
    bool found = false;
    for (struct dirent *e; (e = readdir(d));) found = found || strstr(e->d_name, ".tmp") != NULL;
    closedir(d);
    return found;
}

static void test_meshes_declaring_more_than_they_hold_are_refused(void **state) {
    (void)state;
    expect_refused("info " BAD "ply-declares-67m-faces.ply",
                   "ply-declares-67m-faces.ply: truncated PLY: header declares 536871079 bytes, "
                   "file has 208");
    expect_refused("info " BAD "ply-binary-truncated.ply",
                   "ply-binary-truncated.ply: truncated PLY: header declares");
    expect_refused("info " BAD "gltf-buffer-truncated.gltf",
                   "gltf-buffer-truncated.gltf: truncated glTF: buffers[0] declares 36 bytes");
    expect_refused("info " BAD "glb-cut.glb", "glb-cut.glb: truncated GLB");
    expect_refused("info " BAD "glb-accessor-overflows-view.glb",
                   "glb-accessor-overflows-view.glb: truncated glTF: accessors[0]");
}

static void test_gltf_buffers_must_be_files_beside_the_gltf(void **state) {
    (void)state;
    expect_refused("info " BAD "gltf-uri-absolute.gltf",
                   "gltf-uri-absolute.gltf: buffers[0].uri: must name a file beside the glTF");
    expect_refused("info " BAD "gltf-uri-parent.gltf", "gltf-uri-parent.gltf: buffers[0].uri");
    expect_refused("info " BAD "gltf-uri-device.gltf", "gltf-uri-device.gltf: buffers[0].uri");
}

/* An OBJ's material libraries are read by meso's own MTL reader, never by assimp's parser
 * (which crashed on a statement before the first newmtl and leaked on a one-byte file), and
 * only from beside the mesh, as glTF buffers; an ASCII PLY value that is not a number is
 * refused before assimp (whose parser leaked on it). */
static void test_obj_materials_are_read_by_meso_from_beside_the_mesh_only(void **state) {
    (void)state;
    char dir[1100], arguments[4096];
    snprintf(dir, sizeof dir, "%s/mtl", test_temp_dir());
    mkdir(dir, 0755);
    char sub[1200];
    snprintf(sub, sizeof sub, "%s/sub", dir);
    mkdir(sub, 0755);
    static const char geometry[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n"
                                   "usemtl m\nf 1/1 2/2 3/3\n";
    char text[1024];
    snprintf(text, sizeof text, "mtllib a.mtl\n%s", geometry);
    const char *obj = test_path(dir, "a.obj");
    test_write_file(obj, text, strlen(text));
    const char *mtl = test_path(dir, "a.mtl");
    const char *err = NULL;
    /* a texture before any newmtl: a segfault inside assimp */
    test_write_file(mtl, "map_Kd x.png\n", 13);
    snprintf(arguments, sizeof arguments, "info %s", obj);
    int status = test_run_meso(arguments, &err);
    if (status != 0) fail_msg("map_Kd before newmtl: status %d: %s", status, err);
    test_write_file(mtl, "K", 1);
    assert_int_equal(test_run_meso(arguments, NULL), 0);
    /* a library below the mesh's folder is read */
    snprintf(text, sizeof text, "mtllib sub/b.mtl\n%s", geometry);
    obj = test_path(dir, "b.obj");
    test_write_file(obj, text, strlen(text));
    const char *library = "newmtl m\nKd 0.5 0.25 1\nmap_Kd -s 2 2 1 bricks.png\n";
    test_write_file(test_path(sub, "b.mtl"), library, strlen(library));
    char out[1300];
    snprintf(out, sizeof out, "%s/info.txt", dir);
    snprintf(arguments, sizeof arguments, "%s info %s > %s", MESO_PROGRAM, obj, out);
    assert_int_equal(system(arguments), 0);
    size_t size = 0;
    char *said = test_read_file(out, &size);
    if (!strstr(said, "base colour 0.5 0.25 1") || !strstr(said, "colour texture bricks.png"))
        fail_msg("meso info said: %s", said);
    free(said);
    /* a missing library: "<the OBJ's name>.mtl" is read instead, as assimp did */
    snprintf(text, sizeof text, "mtllib missing.mtl\n%s", geometry);
    obj = test_path(dir, "d.obj");
    test_write_file(obj, text, strlen(text));
    library = "newmtl m\nKd 0.125 0.25 0.5\n";
    test_write_file(test_path(dir, "d.mtl"), library, strlen(library));
    snprintf(arguments, sizeof arguments, "%s info %s > %s", MESO_PROGRAM, obj, out);
    assert_int_equal(system(arguments), 0);
    said = test_read_file(out, &size);
    if (!strstr(said, "base colour 0.125 0.25 0.5")) fail_msg("meso info said: %s", said);
    free(said);
    /* an absolute path or ".." is refused, like a glTF buffer's */
    snprintf(text, sizeof text, "mtllib %s\n%s", test_path(sub, "b.mtl"), geometry);
    obj = test_path(dir, "c.obj");
    test_write_file(obj, text, strlen(text));
    snprintf(arguments, sizeof arguments, "info %s", obj);
    expect_refused(arguments, "c.obj: mtllib /");
    expect_refused(arguments, "must name a file beside the mesh");
    snprintf(text, sizeof text, "mtllib ../mtl/a.mtl\n%s", geometry);
    test_write_file(obj, text, strlen(text));
    expect_refused(arguments, "c.obj: mtllib ../mtl/a.mtl: must name a file beside the mesh");
    expect_refused("info " BAD "obj-mtllib-nul.obj", "obj-mtllib-nul.obj: line 1: mtllib: a NUL");
    expect_refused("info " BAD "ply-ascii-non-numeric.ply",
                   "ply-ascii-non-numeric.ply: PLY data line 2: a value that is not a number");
}

static void test_a_bad_output_fails_before_any_work_and_writes_nothing(void **state) {
    (void)state;
    const char *dir = test_temp_dir();
    char arguments[4096];
    const char *out = test_path(dir, "all_or_none.png");
    unlink(out);
    /* the colour's folder is fine, the coverage's is missing: neither is written */
    snprintf(arguments, sizeof arguments,
             "render " SCENE " -o %s --size 32x32 --coverage /missing/c.png", out);
    double start = meso_time_seconds();
    expect_refused(arguments, "/missing/c.png: cannot write");
    assert_false(exists(out));
    snprintf(arguments, sizeof arguments, "render " SCENE " -o %s/nodir/x.png --size 32x32", dir);
    expect_refused(arguments, "nodir/x.png: cannot write");
    /* at once: before the scene is loaded or rendered */
    assert_true(meso_time_seconds() - start < 5.0);

    /* compare: the difference is not written when the sheet cannot be */
    const char *a = test_path(dir, "cmp_a.png");
    snprintf(arguments, sizeof arguments, "render " SCENE " -o %s --size 32x32 --quiet", a);
    assert_int_equal(test_run_meso(arguments, NULL), 0);
    const char *diff = test_path(dir, "cmp_diff.png");
    unlink(diff);
    snprintf(arguments, sizeof arguments, "compare %s %s -o %s --sheet /missing/s.png", a, a, diff);
    expect_refused(arguments, "/missing/s.png: cannot write");
    assert_false(exists(diff));
    snprintf(arguments, sizeof arguments, "compare %s %s -o %s --sheet %s", a, a, diff,
             test_path(dir, "cmp_sheet.png"));
    assert_int_equal(test_run_meso(arguments, NULL), 0);
    assert_true(exists(diff));
    assert_false(has_temporaries(dir));
}

/* A legal name of 252 bytes (NAME_MAX is 255) is written: the temporary name beside it is
 * short, never the destination's name plus a suffix. A name over the limit is refused before
 * any work, not after it. */
static void test_long_output_names_are_written_or_refused_before_the_work(void **state) {
    (void)state;
    char name[300], arguments[4096];
    memset(name, 'a', 248);
    memcpy(name + 248, ".png", 5);
    const char *out = test_path(test_temp_dir(), name);
    unlink(out);
    snprintf(arguments, sizeof arguments, "render " SCENE " -o %s --size 16x16 --quiet", out);
    const char *err = NULL;
    int status = test_run_meso(arguments, &err);
    if (status != 0) fail_msg("a 252-byte name: status %d: %s", status, err);
    assert_true(exists(out));
    unlink(out);
    memset(name, 'b', 260);
    memcpy(name + 260, ".png", 5);
    snprintf(arguments, sizeof arguments,
             "render " SCENE " -o %s --size 4096x4096 --samples 4 --technique reference",
             test_path(test_temp_dir(), name));
    double start = meso_time_seconds();
    expect_refused(arguments, "File name too long");
    assert_true(meso_time_seconds() - start < 5.0);
}

/* The success line escapes the output's name (a newline cannot make it two lines); a loop of
 * symbolic links at -o is called a loop. */
static void test_status_lines_escape_names_and_say_what_a_link_loop_is(void **state) {
    (void)state;
    const char *dir = test_temp_dir();
    char arguments[4096];
    snprintf(arguments, sizeof arguments, "render " SCENE " -o '%s/new\nline.png' --size 16x16",
             dir);
    const char *err = NULL;
    assert_int_equal(test_run_meso(arguments, &err), 0);
    size_t length = strlen(err);
    if (length == 0 || memchr(err, '\n', length - 1) || !strstr(err, "new\\nline.png"))
        fail_msg("want one line naming new\\nline.png, got: %s", err);
    const char *a = test_path(dir, "loop_a.png"), *b = test_path(dir, "loop_b.png");
    unlink(a);
    unlink(b);
    assert_int_equal(symlink("loop_b.png", a), 0);
    assert_int_equal(symlink("loop_a.png", b), 0);
    snprintf(arguments, sizeof arguments, "render " SCENE " -o %s --size 16x16", a);
    expect_refused(arguments, "loop_a.png: Too many levels of symbolic links");
}

static void test_outputs_are_regular_files_that_keep_their_mode(void **state) {
    (void)state;
    const char *dir = test_temp_dir();
    char arguments[4096];
    const char *fifo = test_path(dir, "out.fifo");
    unlink(fifo);
    assert_int_equal(mkfifo(fifo, 0644), 0);
    snprintf(arguments, sizeof arguments, "render " SCENE " -o %s --size 16x16", fifo);
    expect_refused(arguments, "out.fifo: is a FIFO; meso writes only regular files");
    struct stat st;
    assert_int_equal(lstat(fifo, &st), 0);
    assert_true(S_ISFIFO(st.st_mode)); /* not replaced */
    snprintf(arguments, sizeof arguments, "render " SCENE " -o /dev/null --size 16x16");
    expect_refused(arguments, "/dev/null: is a character device");
    snprintf(arguments, sizeof arguments, "render " SCENE " -o %s --size 16x16", dir);
    expect_refused(arguments, "is a folder");

    /* an existing 0600 file stays 0600 */
    const char *private_png = test_path(dir, "private.png");
    test_write_file(private_png, "x", 1);
    chmod(private_png, 0600);
    snprintf(arguments, sizeof arguments, "render " SCENE " -o %s --size 16x16 --quiet",
             private_png);
    assert_int_equal(test_run_meso(arguments, NULL), 0);
    assert_int_equal(stat(private_png, &st), 0);
    assert_int_equal(st.st_mode & 0777, 0600);
    assert_true(st.st_size > 1);

    /* a symbolic link is written through: it stays a link to the new image */
    const char *link = test_path(dir, "link.png");
    unlink(link);
    assert_int_equal(symlink("private.png", link), 0);
    snprintf(arguments, sizeof arguments, "render " SCENE " -o %s --size 8x8 --quiet", link);
    assert_int_equal(test_run_meso(arguments, NULL), 0);
    assert_int_equal(lstat(link, &st), 0);
    assert_true(S_ISLNK(st.st_mode));
    assert_false(has_temporaries(dir));
}

static void test_a_fifo_as_input_is_refused_without_blocking(void **state) {
    (void)state;
    const char *fifo = test_path(test_temp_dir(), "in.fifo");
    unlink(fifo);
    assert_int_equal(mkfifo(fifo, 0644), 0);
    char arguments[4096];
    /* a hang here would be the bug: ctest's timeout ends it */
    snprintf(arguments, sizeof arguments, "info %s", fifo);
    expect_refused(arguments, "in.fifo: is a FIFO, not a regular file");
    snprintf(arguments, sizeof arguments, "render %s -o %s", fifo,
             test_path(test_temp_dir(), "never.png"));
    expect_refused(arguments, "in.fifo: is a FIFO, not a regular file");
    snprintf(arguments, sizeof arguments, "compare %s %s", fifo, fifo);
    expect_refused(arguments, "in.fifo: is a FIFO, not a regular file");
    /* a mesh and a height map named by a scene */
    const char *scene = test_path(test_temp_dir(), "fifo_refs.json");
    char text[1024];
    snprintf(text, sizeof text,
             "{\"camera\": {\"eye\": [0, 2, 2], \"target\": [0, 0, 0], \"up\": [0, 1, 0],"
             " \"fov_y_deg\": 45}, \"objects\": [{\"shape\": {\"file\": \"in.fifo\"}}]}");
    test_write_file(scene, text, strlen(text));
    snprintf(arguments, sizeof arguments, "render %s -o %s", scene,
             test_path(test_temp_dir(), "never.png"));
    expect_refused(arguments, "in.fifo: is a FIFO");
    /* a material library an OBJ names, which assimp would open */
    const char *obj = test_path(test_temp_dir(), "fifo_mtllib.obj");
    const char *obj_text = "mtllib in.fifo\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    test_write_file(obj, obj_text, strlen(obj_text));
    snprintf(arguments, sizeof arguments, "info %s", obj);
    expect_refused(arguments, "fifo_mtllib.obj: mtllib");
}

/* Start `meso render` at a size that takes a while, kill it after `delay` seconds. */
static void render_and_kill(const char *out, int signal_number, double delay) {
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        int null = open("/dev/null", O_WRONLY);
        dup2(null, 2);
        execl(MESO_PROGRAM, "meso", "render", SCENE, "-o", out, "--size", "1024x1024",
              "--technique", "relief", "--threads", "1", "--quiet", (char *)NULL);
        _exit(127);
    }
    struct timespec pause = {(time_t)delay, (long)((delay - (double)(time_t)delay) * 1e9)};
    nanosleep(&pause, NULL);
    kill(pid, signal_number);
    int status = 0;
    waitpid(pid, &status, 0);
}

static void test_killed_renders_leave_no_temporary_and_no_partial_file(void **state) {
    (void)state;
    char dir[1100];
    snprintf(dir, sizeof dir, "%s/killed", test_temp_dir());
    mkdir(dir, 0755);
    const char *out = test_path(dir, "killed.png");
    const int signals[3] = {SIGINT, SIGTERM, SIGKILL};
    srand(15);
    for (int i = 0; i < 12; i++) {
        render_and_kill(out, signals[i % 3], 0.05 * (double)(rand() % 20));
        assert_false(has_temporaries(dir));
        /* absent, or a complete PNG */
        meso_context *ctx = test_context(1);
        meso_image *image = NULL;
        if (exists(out)) assert_int_equal(meso_image_load_png(ctx, out, &image), MESO_OK);
        meso_image_destroy(image);
        meso_context_destroy(ctx);
    }
}

static void test_jobs_over_the_memory_budget_are_refused_before_allocating(void **state) {
    (void)state;
    /* eight 4096-segment planes: ~36 GiB estimated, refused before the first is built */
    char objects[1024] = "";
    for (int i = 0; i < 8; i++)
        strcat(objects, i ? ", {\"shape\": \"plane\", \"segments\": 4096}"
                          : "{\"shape\": \"plane\", \"segments\": 4096}");
    char text[2048];
    snprintf(text, sizeof text,
             "{\"camera\": {\"eye\": [0, 2, 2], \"target\": [0, 0, 0], \"up\": [0, 1, 0],"
             " \"fov_y_deg\": 45}, \"objects\": [%s]}",
             objects);
    const char *scene = test_path(test_temp_dir(), "eight_planes.json");
    test_write_file(scene, text, strlen(text));
    char arguments[4096];
    double start = meso_time_seconds();
    snprintf(arguments, sizeof arguments, "info %s --memory-limit 16G", scene);
    expect_refused(arguments, "eight_planes.json: objects: needs about");
    expect_refused(arguments, "more than the limit of 16.00 GiB (--memory-limit)");
    /* a frame of 16384 x 4096 with 16 samples: ~22 GiB, refused before the framebuffer */
    snprintf(arguments, sizeof arguments,
             "render " SCENE " -o %s --technique flat --size 16384x4096 --samples 16 "
             "--memory-limit 16G",
             test_path(test_temp_dir(), "huge.png"));
    expect_refused(arguments, "bricks-plane.json: needs about 22.25 GiB of memory");
    assert_true(meso_time_seconds() - start < 10.0);
    /* the reference's ray-tracing structure is held to the budget while Embree builds it */
    snprintf(arguments, sizeof arguments,
             "render " SCENE " -o %s --technique reference --size 32x32 --memory-limit 20M",
             test_path(test_temp_dir(), "reference.png"));
    expect_refused(arguments, "bricks-plane.json: reference: the ray-tracing structure needs more "
                              "memory than the limit of 20.0 MiB");
    /* a small limit refuses even the example; a malformed one is a usage error */
    snprintf(arguments, sizeof arguments, "render " SCENE " -o %s --memory-limit 1M",
             test_path(test_temp_dir(), "small.png"));
    expect_refused(arguments, "needs about");
    expect_refused("render " SCENE " -o x.png --memory-limit 1Q", "--memory-limit: '1Q'");
    /* the documented procedural limit is the one enforced */
    snprintf(text, sizeof text,
             "{\"camera\": {\"eye\": [0, 2, 2], \"target\": [0, 0, 0], \"up\": [0, 1, 0],"
             " \"fov_y_deg\": 45}, \"objects\": [{\"mesostructure\": {\"height_map\":"
             " {\"procedural\": \"bricks\", \"resolution\": 16384}, \"depth\": 0.1}}]}");
    scene = test_path(test_temp_dir(), "resolution.json");
    test_write_file(scene, text, strlen(text));
    snprintf(arguments, sizeof arguments, "info %s", scene);
    expect_refused(arguments, "objects[0].mesostructure.height_map.resolution");
}

/* A scene with `object` (JSON text) as its one object. */
static const char *write_scene(const char *name, const char *object) {
    char text[2048];
    snprintf(text, sizeof text,
             "{\"image\": {\"width\": 16, \"height\": 16}, \"camera\": {\"eye\": [0, 2, 2],"
             " \"target\": [0, 0, 0], \"up\": [0, 1, 0], \"fov_y_deg\": 45},"
             " \"objects\": [%s]}",
             object);
    const char *path = test_path(test_temp_dir(), name);
    test_write_file(path, text, strlen(text));
    return path;
}

static void test_errors_are_one_escaped_line_naming_the_file(void **state) {
    (void)state;
    char arguments[4096];
    /* a newline and an escape sequence in a key cannot forge a second line or reach the
     * terminal raw */
    const char *scene =
        write_scene("control.json", "{\"shape\": \"plane\", \"x\\nmeso: forged\\u001b[31m\": 1}");
    snprintf(arguments, sizeof arguments, "info %s", scene);
    expect_refused(arguments, "control.json: objects[0].x\\nmeso: forged\\x1b[31m: unknown key");
    /* an error of the renderer names an object: the scene is named first */
    snprintf(arguments, sizeof arguments,
             "render " MESO_SOURCE_DIR "/examples/weave-torus.json -o %s --technique bump",
             test_path(test_temp_dir(), "never.png"));
    expect_refused(arguments, "weave-torus.json: torus: technique 'bump' does not accept");
    /* an object named like a file does not stand in for the scene */
    scene =
        write_scene("named.json", "{\"name\": \"x.json\", \"shape\": \"torus\", \"mesostructure\":"
                                  " {\"solid\": {\"procedural\": \"weave\"}, \"depth\": 0.1}}");
    snprintf(arguments, sizeof arguments, "render %s -o %s --technique bump", scene,
             test_path(test_temp_dir(), "never.png"));
    expect_refused(arguments, "named.json: x.json: technique 'bump' does not accept");
    /* a shape over the mesh limits is said at the object's key of the scene file */
    scene = write_scene("long_cylinder.json",
                        "{\"shape\": \"cylinder\", \"segments\": 4096, \"height\": 30}");
    snprintf(arguments, sizeof arguments, "info %s --memory-limit 64G", scene);
    expect_refused(arguments,
                   "long_cylinder.json: objects[0]: cylinder: 133545812 vertices exceed");
}

static void test_non_standard_json_numbers_are_refused_with_the_key_path(void **state) {
    (void)state;
    const char *numbers[] = {"01", "64.", "1.e5", "-.5"};
    char arguments[4096], object[256];
    for (size_t i = 0; i < sizeof numbers / sizeof numbers[0]; i++) {
        snprintf(object, sizeof object, "{\"shape\": \"plane\", \"size\": %s}", numbers[i]);
        snprintf(arguments, sizeof arguments, "info %s", write_scene("numbers.json", object));
        expect_refused(arguments, "numbers.json: objects[0].size:");
    }
    snprintf(arguments, sizeof arguments, "info %s",
             write_scene("numbers.json", "{\"shape\": \"plane\", \"size\": 0.5e1}"));
    assert_int_equal(test_run_meso(arguments, NULL), 0);
}

static void test_uv_scale_beyond_int_range_of_texels_is_refused(void **state) {
    (void)state;
    char arguments[4096];
    const char *scene = write_scene(
        "uv_scale.json", "{\"shape\": \"plane\", \"uv_scale\": [1e10, 1], \"technique\":"
                         " \"horizon\", \"mesostructure\": {\"height_map\": {\"procedural\":"
                         " \"bricks\", \"resolution\": 64}, \"depth\": 0.1}}");
    snprintf(arguments, sizeof arguments, "render %s -o %s", scene,
             test_path(test_temp_dir(), "never.png"));
    expect_refused(arguments, "uv_scale.json: objects[0].uv_scale: scaled texture coordinates");
}

/* Every input kept under tests/data/bad/ refused by `meso info`: status 2, one line naming it.
 * (--memory-limit fixes the budget, so the result does not depend on the machine's memory.) */
static void test_every_kept_bad_input_is_refused(void **state) {
    (void)state;
    DIR *d = opendir(BAD);
    assert_non_null(d);
    int count = 0;
    for (struct dirent *e; (e = readdir(d));) {
        if (e->d_name[0] == '.') continue;
        char arguments[4096];
        snprintf(arguments, sizeof arguments, "info " BAD "%s --memory-limit 16G", e->d_name);
        expect_refused(arguments, e->d_name);
        count++;
    }
    closedir(d);
    assert_true(count >= 20);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_meshes_declaring_more_than_they_hold_are_refused),
        cmocka_unit_test(test_gltf_buffers_must_be_files_beside_the_gltf),
        cmocka_unit_test(test_obj_materials_are_read_by_meso_from_beside_the_mesh_only),
        cmocka_unit_test(test_a_bad_output_fails_before_any_work_and_writes_nothing),
        cmocka_unit_test(test_outputs_are_regular_files_that_keep_their_mode),
        cmocka_unit_test(test_long_output_names_are_written_or_refused_before_the_work),
        cmocka_unit_test(test_status_lines_escape_names_and_say_what_a_link_loop_is),
        cmocka_unit_test(test_a_fifo_as_input_is_refused_without_blocking),
        cmocka_unit_test(test_killed_renders_leave_no_temporary_and_no_partial_file),
        cmocka_unit_test(test_jobs_over_the_memory_budget_are_refused_before_allocating),
        cmocka_unit_test(test_errors_are_one_escaped_line_naming_the_file),
        cmocka_unit_test(test_non_standard_json_numbers_are_refused_with_the_key_path),
        cmocka_unit_test(test_uv_scale_beyond_int_range_of_texels_is_refused),
        cmocka_unit_test(test_every_kept_bad_input_is_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
