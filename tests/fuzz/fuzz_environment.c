/* Fuzz target: environment maps (meso_environment_load): Radiance .hdr or OpenEXR, told by
 * the magic number, so the file's name does not matter. */
#include "fuzz_target.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const char *path = fuzz_write_file(data, size, "hdr");
    meso_environment *environment = NULL;
    if (meso_environment_load(fuzz_context(), path, 1.0f, &environment) == MESO_OK)
        meso_environment_destroy(environment);
    return 0;
}
