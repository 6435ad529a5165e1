/* What the fuzz targets share: a context and a scratch file per process. */
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include "fuzz_target.h"

meso_context *fuzz_context(void) {
    static meso_context *ctx;
    if (!ctx) {
        meso_context_desc desc = {
            .num_threads = 1, .progress = MESO_PROGRESS_NEVER, .memory_limit = UINT64_C(1) << 30};
        if (meso_context_create(&desc, &ctx) != MESO_OK) abort();
    }
    return ctx;
}

const char *fuzz_write_file(const uint8_t *data, size_t size, const char *extension) {
    static char path[256];
    const char *dir = getenv("TMPDIR");
    snprintf(path, sizeof path, "%s/meso-fuzz-%ld.%s", dir && dir[0] ? dir : "/tmp", (long)getpid(),
             extension);
    FILE *file = fopen(path, "wb");
    if (!file) abort();
    if (size > 0 && fwrite(data, 1, size, file) != size) abort();
    fclose(file);
    return path;
}
