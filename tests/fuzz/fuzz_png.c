/* Fuzz target: the PNG loader (meso_image_load_png). */
#include "fuzz_target.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    meso_image *image = NULL;
    if (meso_image_load_png(fuzz_context(), fuzz_write_file(data, size, "png"), &image) == MESO_OK)
        meso_image_destroy(image);
    return 0;
}
