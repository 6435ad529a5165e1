/* The examples compiled into the program, parsed as if read from examples/: the scenes that
 * read files of examples/assets (a tile mesh) read the copies compiled in, written to a
 * private temporary folder for the parse and removed after it (the scene keeps what it built
 * from them: the bake cache keys a tile mesh's solid by its grid, not by its path). */
#include "app.h"
#include "examples_embedded.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include "meso/runtime.h"

/* Write every asset under dir ("dir/assets/..." in the folder `assets`, made here); the paths
 * written into written[]. */
static meso_result write_assets(meso_context *ctx, const char *dir, const char *assets,
                                char (*written)[4096], size_t *out_count) {
    *out_count = 0;
    if (mkdir(assets, 0700) != 0)
        return meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot make the folder: %s", assets,
                              strerror(errno));
    for (size_t i = 0; i < meso_embedded_asset_count; i++) {
        const meso_embedded_asset *a = &meso_embedded_assets[i];
        char *path = written[*out_count];
        if (!app_path_join(path, 4096, dir, a->path))
            return meso_log_error(ctx, MESO_ERROR_IO, "%s: path too long", dir);
        FILE *f = fopen(path, "wb");
        if (!f)
            return meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot write: %s", path,
                                  strerror(errno));
        (*out_count)++;
        bool ok = fwrite(a->bytes, 1, a->size, f) == a->size;
        if (fclose(f) != 0 || !ok)
            return meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot write: %s", path,
                                  strerror(errno));
    }
    return MESO_OK;
}

meso_result app_example_parse(meso_context *ctx, size_t index, meso_scene **out_scene) {
    const meso_embedded_example *ex = &meso_embedded_examples[index];
    *out_scene = NULL;
    if (!ex->uses_assets) return meso_scene_parse(ctx, ex->json, ex->name, ".", out_scene);
    const char *tmp = getenv("TMPDIR");
    char dir[2048], assets[4096];
    if (!app_path_join(dir, sizeof dir, tmp && tmp[0] ? tmp : "/tmp", "meso-example-XXXXXX"))
        return meso_log_error(ctx, MESO_ERROR_IO, "TMPDIR: path too long");
    if (!mkdtemp(dir))
        return meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot make a temporary folder: %s", dir,
                              strerror(errno));
    app_path_join(assets, sizeof assets, dir, "assets"); /* fits: dir is at most half as long */
    char(*written)[4096] = calloc(meso_embedded_asset_count + 1, sizeof *written);
    size_t count = 0;
    meso_result result = written ? write_assets(ctx, dir, assets, written, &count)
                                 : meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "out of memory");
    if (result == MESO_OK) result = meso_scene_parse(ctx, ex->json, ex->name, dir, out_scene);
    for (size_t i = 0; i < count; i++) unlink(written[i]);
    rmdir(assets);
    rmdir(dir);
    free(written);
    return result;
}
