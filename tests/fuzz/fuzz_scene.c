/* Fuzz target: the scene parser (meso_scene_parse) on JSON text, files it names resolved in
 * the scratch folder (where there are none: those paths are refused). */
#include <stdlib.h>
#include <string.h>

#include "fuzz_target.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    char *text = malloc(size + 1);
    if (!text) return 0;
    memcpy(text, data, size);
    text[size] = 0;
    meso_scene *scene = NULL;
    if (meso_scene_parse(fuzz_context(), text, "fuzz.json", "/nonexistent", &scene) == MESO_OK)
        meso_scene_destroy(scene);
    free(text);
    return 0;
}
