/* Installing to any prefix gives a library that builds and runs the README's example, through
 * pkg-config and through find_package(meso). Defect: libmeso.pc said /usr/local whatever
 * --prefix was given, and there was no CMake package. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "test_util.h"

/* Run a shell command, its output into log; fail with the log when it fails. */
static void shell(const char *dir, const char *command) {
    char line[8192], log[1200];
    snprintf(log, sizeof log, "%s/log.txt", dir);
    snprintf(line, sizeof line, "cd '%s' && ( %s ) > '%s' 2>&1", dir, command, log);
    if (system(line) != 0) {
        char text[4096] = "";
        FILE *f = fopen(log, "rb");
        if (f) {
            size_t n = fread(text, 1, sizeof text - 1, f);
            text[n] = 0;
            fclose(f);
        }
        fail_msg("%s failed:\n%s", command, text);
    }
}

/* The README's C example (its first ```c block), made a program: includes first, the rest as
 * the body of main. */
static void write_readme_example(const char *path) {
    FILE *f = fopen(MESO_SOURCE_DIR "/README.md", "rb");
    assert_non_null(f);
    static char readme[65536];
    size_t n = fread(readme, 1, sizeof readme - 1, f);
    fclose(f);
    readme[n] = 0;
    char *start = strstr(readme, "```c\n");
    assert_non_null(start);
    start += 5;
    char *end = strstr(start, "```");
    assert_non_null(end);
    *end = 0;
    FILE *out = fopen(path, "wb");
    assert_non_null(out);
    fprintf(out, "#include <stdio.h>\n");
    char *body = start;
    while (strncmp(body, "#include", 8) == 0) { /* the includes stay at file scope */
        char *eol = strchr(body, '\n');
        fprintf(out, "%.*s\n", (int)(eol - body), body);
        body = eol + 1;
    }
    fprintf(out, "int main(void) {\n%s    return 0; /* success is bricks.png */\n}\n", body);
    fclose(out);
}

static void test_install_to_a_prefix_builds_the_readme_example(void **state) {
    (void)state;
    char dir[1100], command[4096];
    snprintf(dir, sizeof dir, "%s/install", test_temp_dir());
    snprintf(command, sizeof command, "rm -rf '%s' && mkdir -p '%s'", dir, dir);
    assert_int_equal(system(command), 0);
    snprintf(command, sizeof command, "cmake --install '%s' --prefix '%s/prefix'", MESO_BINARY_DIR,
             dir);
    shell(dir, command);

    char pc[1300];
    snprintf(pc, sizeof pc, "%s/prefix/lib/pkgconfig/libmeso.pc", dir);
    FILE *f = fopen(pc, "rb");
    assert_non_null(f);
    char text[2048];
    size_t n = fread(text, 1, sizeof text - 1, f);
    text[n] = 0;
    fclose(f);
    assert_null(strstr(text, "/usr/local")); /* found from where it lies */

    char source[1300];
    snprintf(source, sizeof source, "%s/app.c", dir);
    write_readme_example(source);
    /* the example reads examples/bricks-plane.json and writes bricks.png in its folder */
    shell(dir, "ln -s " MESO_SOURCE_DIR "/examples examples");

    /* pkg-config, as the README says; a sanitized build installs sanitized archives, so their
     * users link the runtime too, with the compiler that built them (CMake passes both) */
#if MESO_SHARED_BUILD
    /* -DMESO_SHARED=ON: both ways link the installed libmeso.so (found at run time through
     * LD_LIBRARY_PATH for pkg-config, the imported target's run path for CMake) */
    shell(dir, "export PKG_CONFIG_PATH=\"$PWD/prefix/lib/pkgconfig\" && "
               "'" MESO_C_COMPILER "' -std=c17 " MESO_SANITIZE_FLAGS
               " app.c -o app-pkg-config $(pkg-config --cflags --libs libmeso) && "
               "readelf -d app-pkg-config | grep -q 'NEEDED.*libmeso\\.so' && "
               "MESO_CACHE_DIR=off LD_LIBRARY_PATH=\"$PWD/prefix/lib\" ./app-pkg-config && "
               "test -s bricks.png && rm bricks.png");
#else
    shell(dir, "export PKG_CONFIG_PATH=\"$PWD/prefix/lib/pkgconfig\" && "
               "'" MESO_C_COMPILER "' -std=c17 " MESO_SANITIZE_FLAGS
               " app.c -o app-pkg-config $(pkg-config --cflags --libs --static libmeso) "
               "&& MESO_CACHE_DIR=off ./app-pkg-config && test -s bricks.png && rm bricks.png");
#endif

    /* find_package(meso) */
    snprintf(command, sizeof command, "%s/cmake-consumer", dir);
    mkdir(command, 0755);
    char lists[1400];
    snprintf(lists, sizeof lists, "%s/cmake-consumer/CMakeLists.txt", dir);
    const char *cmake_text = "cmake_minimum_required(VERSION 3.18)\n"
                             "project(consumer C)\n"
                             "find_package(meso 0.1 REQUIRED)\n"
                             "add_executable(app ../app.c)\n"
                             "target_link_libraries(app PRIVATE meso::meso)\n";
    test_write_file(lists, cmake_text, strlen(cmake_text));
    shell(dir,
          "cmake -S cmake-consumer -B cmake-build -DCMAKE_PREFIX_PATH=\"$PWD/prefix\" "
          "-DCMAKE_C_COMPILER='" MESO_C_COMPILER "' -DCMAKE_C_FLAGS=\"" MESO_SANITIZE_FLAGS "\" && "
          "cmake --build cmake-build && MESO_CACHE_DIR=off ./cmake-build/app && "
          "test -s bricks.png");
#if MESO_SHARED_BUILD
    shell(dir, "readelf -d cmake-build/app | grep -q 'NEEDED.*libmeso\\.so' && "
               "test -L prefix/lib/libmeso.so && "
               "! nm -D --defined-only prefix/lib/libmeso.so | grep -v ' meso_' | grep -q ' T '");
#endif
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_install_to_a_prefix_builds_the_readme_example),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
