/* libFuzzer targets of meso's loaders (docs/robustness.md). Each fuzz_<name>.c defines
 * LLVMFuzzerTestOneInput; built with clang -fsanitize=fuzzer by scripts/fuzz.sh, and with
 * fuzz_replay.c's main by the ordinary build, which replays the corpus in `make test`. */
#ifndef MESO_FUZZ_TARGET_H
#define MESO_FUZZ_TARGET_H

#include <stddef.h>
#include <stdint.h>

#include "meso/meso.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* A quiet context (errors kept, not printed; no progress bar) with a 1 GiB memory budget, so
 * that an accepted input stays within libFuzzer's 2 GB RSS limit. Created once. */
meso_context *fuzz_context(void);

/* Write data to a file of this process named with `extension` ("ply") and return its path
 * (a static buffer): the loaders take paths. */
const char *fuzz_write_file(const uint8_t *data, size_t size, const char *extension);

#endif
