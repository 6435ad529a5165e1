/* Fuzz target: mesh import with meso's screening (meso_mesh_load). The first byte picks the
 * format by extension, the rest is the file. */
#include "fuzz_target.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    static const char *const extensions[] = {"ply", "obj", "gltf", "glb"};
    if (size < 1) return 0;
    const char *path = fuzz_write_file(data + 1, size - 1, extensions[data[0] % 4]);
    meso_mesh *mesh = NULL;
    if (meso_mesh_load(fuzz_context(), path, &mesh) == MESO_OK) meso_mesh_destroy(mesh);
    return 0;
}
