/* Fuzz target: mesh import with meso's screening (meso_mesh_load). The first byte picks the
 * format by extension, the rest is the file. An OBJ whose first byte has bit 2 set also gets a
 * material library: the bytes after the first 0xff are written to an MTL file its first line
 * names, and the mesh is loaded with its material (meso's own MTL reader). */
#include <stdio.h>
#include <string.h>

#include "fuzz_target.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    static const char *const extensions[] = {"ply", "obj", "gltf", "glb"};
    if (size < 1) return 0;
    const char *extension = extensions[data[0] % 4];
    bool with_mtl = data[0] % 4 == 1 && (data[0] & 4);
    meso_mesh *mesh = NULL;
    meso_mesh_material material;
    if (!with_mtl) {
        const char *path = fuzz_write_file(data + 1, size - 1, extension);
        if (meso_mesh_load(fuzz_context(), path, &mesh) == MESO_OK) meso_mesh_destroy(mesh);
        return 0;
    }
    const uint8_t *split = memchr(data + 1, 0xff, size - 1);
    size_t obj_size = split ? (size_t)(split - (data + 1)) : size - 1;
    const char *mtl_path = fuzz_write_file(split ? split + 1 : data,
                                           split ? (size_t)(data + size - split - 1) : 0, "mtl");
    const char *slash = strrchr(mtl_path, '/');
    char header[300];
    int header_size = snprintf(header, sizeof header, "mtllib %s\n", slash ? slash + 1 : mtl_path);
    static uint8_t obj[1 << 17];
    if (obj_size > sizeof obj - (size_t)header_size) return 0;
    memcpy(obj, header, (size_t)header_size);
    memcpy(obj + header_size, data + 1, obj_size);
    const char *path = fuzz_write_file(obj, (size_t)header_size + obj_size, "obj");
    if (meso_mesh_load_with_material(fuzz_context(), path, &mesh, &material) == MESO_OK)
        meso_mesh_destroy(mesh);
    return 0;
}
