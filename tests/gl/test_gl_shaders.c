/* The shader files themselves: every one passes glslangValidator (the Khronos reference
 * compiler, stricter than a driver) as the back end puts it together; every option of a
 * technique's CPU table is a uniform of its shader; a compile error names the file and line;
 * and the program's one-line messages when EGL or GL 3.3 is missing. */
#include <dirent.h>
#include <unistd.h>
#include <sys/wait.h>

#include "gl_fixture.h"

#define SHADER_DIR MESO_SOURCE_DIR "/shaders"

/* "#version 330 core", the files named on the first line "// meso:requires ...", the file:
 * what gl_program.c compiles (without its #line markers). Caller frees. */
static char *assemble(const char *name) {
    size_t size;
    char *main_text = test_read_file(test_path(SHADER_DIR, name), &size);
    size_t capacity = 64 + size, used = 0;
    char *out = malloc(capacity);
    used += (size_t)sprintf(out, "#version 330 core\n");
    const char *tag = "// meso:requires";
    if (strncmp(main_text, tag, strlen(tag)) == 0) {
        char line[256];
        size_t n = strcspn(main_text + strlen(tag), "\n");
        snprintf(line, sizeof line, "%.*s", (int)n, main_text + strlen(tag));
        for (char *word = strtok(line, " \t"); word; word = strtok(NULL, " \t")) {
            size_t part_size;
            char *part = test_read_file(test_path(SHADER_DIR, word), &part_size);
            capacity += part_size + 1;
            out = realloc(out, capacity);
            memcpy(out + used, part, part_size);
            used += part_size;
            out[used++] = '\n';
            free(part);
        }
    }
    memcpy(out + used, main_text, size);
    out[used + size] = 0;
    free(main_text);
    return out;
}

static bool ends_with(const char *s, const char *suffix) {
    size_t a = strlen(s), b = strlen(suffix);
    return a >= b && strcmp(s + a - b, suffix) == 0;
}

static void test_glslang_validates_every_shader(void **state) {
    (void)state;
    DIR *dir = opendir(SHADER_DIR);
    assert_non_null(dir);
    int checked = 0;
    for (struct dirent *e; (e = readdir(dir));) {
        bool vert = ends_with(e->d_name, ".vert"), frag = ends_with(e->d_name, ".frag");
        if (!vert && !frag) continue; /* .glsl files are parts, validated inside each .frag */
        char *text = assemble(e->d_name);
        const char *path = test_path(test_temp_dir(), e->d_name);
        test_write_file(path, text, strlen(text));
        free(text);
        char command[2048];
        snprintf(command, sizeof command, "glslangValidator -S %s %s", vert ? "vert" : "frag",
                 path);
        int status = system(command);
        if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
            fail_msg("glslangValidator rejects %s (exit %d; is glslang-tools installed? "
                     "scripts/install-deps.sh)",
                     e->d_name, WEXITSTATUS(status));
        checked++;
    }
    closedir(dir);
    assert_true(checked >= 3); /* meso.vert, flat.frag, relief.frag at least */
}

/* Same names, so the option tables are the shaders' interface (meso help T documents both). */
static void test_every_option_is_a_uniform(void **state) {
    (void)state;
    int techniques = 0;
    for (size_t t = 0; t < meso_technique_count(); t++) {
        const meso_technique_info *info = meso_technique_get(t);
        if (!meso_gl_technique_supported(info->name)) continue;
        char name[96];
        snprintf(name, sizeof name, "%s.frag", info->name);
        char *text = assemble(name);
        for (size_t k = 0; k < info->num_options; k++) {
            char declaration[128];
            snprintf(declaration, sizeof declaration, " u_%s;", info->options[k].name);
            if (!strstr(text, declaration))
                fail_msg("%s: option %s has no uniform u_%s", name, info->options[k].name,
                         info->options[k].name);
        }
        free(text);
        techniques++;
    }
    assert_true(techniques >= 2);
}

/* The GL's technique rows (gl_techniques.c) say it draws exactly the techniques that have a
 * fragment shader in shaders/. */
static void test_drawn_techniques_have_a_shader(void **state) {
    (void)state;
    int drawn = 0;
    for (size_t t = 0; t < meso_technique_count(); t++) {
        const char *name = meso_technique_get(t)->name;
        char path[1024];
        snprintf(path, sizeof path, "%s/%s.frag", SHADER_DIR, name);
        bool has_shader = access(path, F_OK) == 0;
        if (meso_gl_technique_supported(name) != has_shader)
            fail_msg("%s: the GL row says drawn %d, shaders/%s.frag %s", name,
                     meso_gl_technique_supported(name), name, has_shader ? "exists" : "is missing");
        drawn += has_shader;
    }
    assert_true(drawn >= 2);
}

/* A broken copy of relief.frag: the message names that file and line. */
static void test_compile_error_names_file_and_line(void **state) {
    (void)state;
    gl_require_device();
    const char *dir = test_path(test_temp_dir(), "broken-shaders");
    char command[2048];
    snprintf(command, sizeof command, "rm -rf %s && cp -r %s %s", dir, SHADER_DIR, dir);
    assert_int_equal(system(command), 0);
    size_t size;
    char *text = test_read_file(test_path(dir, "relief.frag"), &size);
    const char *needle = "return relief_linear_search(r, u_linear_steps, u_binary_steps, t);";
    char *at = strstr(text, needle);
    assert_non_null(at);
    int line = 1;
    for (const char *c = text; c < at; c++) line += *c == '\n';
    char *broken = malloc(size + 64);
    sprintf(broken, "%.*sreturn relief_linear_search(r, no_such_name, u_binary_steps, t);%s",
            (int)(at - text), text, at + strlen(needle));
    test_write_file(test_path(dir, "relief.frag"), broken, strlen(broken));
    free(broken);
    free(text);

    meso_context *ctx = test_context(1);
    meso_scene *scene = gl_load_example(ctx, "bricks-plane");
    meso_gl_renderer *renderer = NULL;
    meso_gl_desc desc = {.render = {.technique = "relief"}, .shader_dir = dir};
    assert_int_equal(meso_gl_renderer_create(ctx, scene, &desc, &renderer), MESO_ERROR_FORMAT);
    assert_null(renderer);
    char expected[1200];
    snprintf(expected, sizeof expected, "%s/relief.frag:%d: ", dir, line);
    const char *message = meso_context_last_error(ctx);
    if (!strstr(message, expected)) fail_msg("'%s' does not name '%s'", message, expected);
    assert_non_null(strstr(message, "no_such_name"));
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
}

/* No EGL vendor (glvnd finds none), no GL 3.3 (Mesa told to offer 3.1): one line saying what
 * is missing and that the CPU back end works, exit 1. A technique without a shader: the same. */
static void test_missing_gl_is_one_line(void **state) {
    (void)state;
    gl_require_device();
    const char *scene = MESO_SOURCE_DIR "/examples/bricks-plane.json";
    const char *out = test_path(test_temp_dir(), "gl-missing.png");
    char arguments[2048];
    snprintf(arguments, sizeof arguments, "render %s --backend gl --technique relief -o %s", scene,
             out);
    const struct {
        const char *variable, *value, *says;
    } cases[] = {
        {"__EGL_VENDOR_LIBRARY_FILENAMES", "/nonexistent/egl.json", "no EGL display"},
        {"MESA_GL_VERSION_OVERRIDE", "3.1", "no OpenGL 3.3 core context"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        setenv(cases[i].variable, cases[i].value, 1);
        const char *err = NULL;
        int status = test_run_meso(arguments, &err);
        unsetenv(cases[i].variable);
        print_message("%s=%s: %s", cases[i].variable, cases[i].value, err);
        assert_int_equal(status, 1);
        assert_non_null(strstr(err, cases[i].says));
        assert_non_null(strstr(err, "--backend cpu works"));
        assert_ptr_equal(strchr(err, '\n'), err + strlen(err) - 1); /* one line */
        assert_int_not_equal(access(out, F_OK), 0);                 /* nothing written */
    }
    snprintf(arguments, sizeof arguments, "render %s --backend gl --technique tessellation -o %s",
             scene, out);
    const char *err = NULL;
    assert_int_equal(test_run_meso(arguments, &err), 2); /* a usage error, not the machine's */
    assert_non_null(strstr(err, "'tessellation' has no GL shader"));
    snprintf(arguments, sizeof arguments, "render %s --backend vulkan -o %s", scene, out);
    assert_int_equal(test_run_meso(arguments, &err), 2);
    assert_non_null(strstr(err, "'vulkan' is not cpu or gl"));
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_glslang_validates_every_shader),
        cmocka_unit_test(test_every_option_is_a_uniform),
        cmocka_unit_test(test_drawn_techniques_have_a_shader),
        cmocka_unit_test(test_compile_error_names_file_and_line),
        cmocka_unit_test(test_missing_gl_is_one_line),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
