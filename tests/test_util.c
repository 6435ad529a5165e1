#include "test_util.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

static char last_warning[1024];

static void capture_log(void *user, meso_log_level level, const char *message) {
    (void)user;
    if (level == MESO_LOG_WARNING) snprintf(last_warning, sizeof(last_warning), "%s", message);
}

/* Bakes of tests go under the build tree, never the user's ~/.cache/meso, also when a test
 * runs outside ctest (which sets the same): the variables are set unless already set. */
static void use_test_cache(void) {
    setenv("MESO_CACHE_DIR", MESO_BINARY_DIR "/test-cache", 0);
    setenv("XDG_CACHE_HOME", MESO_BINARY_DIR "/test-xdg-cache", 0);
}

meso_context *test_context(int num_threads) {
    use_test_cache();
    meso_context *ctx = NULL;
    meso_context_desc desc = {
        .num_threads = num_threads, .log = capture_log, .progress = MESO_PROGRESS_NEVER};
    assert_int_equal(meso_context_create(&desc, &ctx), MESO_OK);
    last_warning[0] = 0;
    return ctx;
}

const char *test_last_warning(void) { return last_warning; }

const char *test_temp_dir(void) {
    static char dir[1024];
    if (!dir[0]) {
        snprintf(dir, sizeof(dir), "%s/test-tmp/XXXXXX", MESO_BINARY_DIR);
        char parent[1024];
        snprintf(parent, sizeof(parent), "%s/test-tmp", MESO_BINARY_DIR);
        mkdir(parent, 0755);
        if (!mkdtemp(dir)) fail_msg("cannot create %s", dir);
    }
    return dir;
}

const char *test_path(const char *dir, const char *name) {
    static char buffers[8][1024];
    static int next;
    char *b = buffers[next++ % 8];
    snprintf(b, 1024, "%s/%s", dir, name);
    return b;
}

void test_write_file(const char *path, const void *data, size_t size) {
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, size, f), size);
    fclose(f);
}

char *test_read_file(const char *path, size_t *out_size) {
    FILE *f = fopen(path, "rb");
    if (!f) fail_msg("%s was not written", path);
    fseek(f, 0, SEEK_END);
    long size = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *data = malloc((size_t)size + 1);
    assert_non_null(data);
    assert_int_equal(fread(data, 1, (size_t)size, f), (size_t)size);
    fclose(f);
    data[size] = 0;
    *out_size = (size_t)size;
    return data;
}

int test_run_meso(const char *arguments, const char **out_stderr) {
    use_test_cache();
    static char err[8192];
    char err_path[1100], command[4096];
    snprintf(err_path, sizeof(err_path), "%s/stderr.txt", test_temp_dir());
    snprintf(command, sizeof(command), "%s %s >/dev/null 2>%s </dev/null", MESO_PROGRAM, arguments,
             err_path);
    int status = system(command);
    err[0] = 0;
    FILE *f = fopen(err_path, "rb");
    if (f) {
        size_t n = fread(err, 1, sizeof(err) - 1, f);
        err[n] = 0;
        fclose(f);
    }
    if (out_stderr) *out_stderr = err;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

static uint32_t crc32_of(const unsigned char *data, size_t size) {
    uint32_t crc = 0xffffffffu;
    for (size_t i = 0; i < size; i++) {
        crc ^= data[i];
        for (int k = 0; k < 8; k++) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
    }
    return ~crc;
}

static void put_u32(unsigned char *p, uint32_t v) {
    p[0] = (unsigned char)(v >> 24);
    p[1] = (unsigned char)(v >> 16);
    p[2] = (unsigned char)(v >> 8);
    p[3] = (unsigned char)v;
}

void test_write_png_header(const char *path, uint32_t width, uint32_t height) {
    unsigned char bytes[8 + 25] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    unsigned char *chunk = bytes + 8;
    put_u32(chunk, 13);
    memcpy(chunk + 4, "IHDR", 4);
    put_u32(chunk + 8, width);
    put_u32(chunk + 12, height);
    chunk[16] = 8; /* bit depth */
    chunk[17] = 2; /* RGB */
    put_u32(chunk + 21, crc32_of(chunk + 4, 17));
    test_write_file(path, bytes, sizeof(bytes));
}

float test_uniform(unsigned *seed) {
    *seed = *seed * 1103515245u + 12345u;
    return (float)(*seed >> 8) / 16777216.0f;
}
