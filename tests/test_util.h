/* Helpers shared by the cmocka tests. */
#ifndef MESO_TEST_UTIL_H
#define MESO_TEST_UTIL_H

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "meso/meso.h"

/* A context whose log is captured (last warning/error text) rather than printed. */
meso_context *test_context(int num_threads);
/* The text of the last warning logged on a test_context ("" if none). */
const char *test_last_warning(void);
/* A fresh temporary folder for the test's files (removed by nothing: under the build tree). */
const char *test_temp_dir(void);
/* Path join into a static buffer rotating among 8 slots. */
const char *test_path(const char *dir, const char *name);
/* Write `text` to a file. */
void test_write_file(const char *path, const void *data, size_t size);
/* A whole file, NUL-terminated, in memory the caller frees; its size (without the NUL) in
 * *out_size. Fails the test, naming the file, when it cannot be read. */
char *test_read_file(const char *path, size_t *out_size);
/* Write a PNG that is only a signature and an IHDR (valid CRC) declaring width x height RGB:
 * for testing that declared sizes are checked before allocating. */
void test_write_png_header(const char *path, uint32_t width, uint32_t height);
/* A repeatable uniform number in [0, 1): the next draw of a 32-bit linear congruential
 * generator whose state is *seed (its top 24 bits), the same sequence on every platform. */
float test_uniform(unsigned *seed);
/* Run the meso program with arguments (a shell command line after "meso"), capturing stderr to
 * *out_stderr (static buffer); returns the exit status. */
int test_run_meso(const char *arguments, const char **out_stderr);

#endif
