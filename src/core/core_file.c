/* Atomic file writes and whole-file reads. */
#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core_internal.h"

meso_result meso_atomic_file_open(meso_context *ctx, const char *path, meso_atomic_file *out_file) {
    *out_file = (meso_atomic_file){0};
    size_t length = strlen(path);
    char *dest = malloc(length + 1);
    char *temp = malloc(length + 16);
    if (!dest || !temp) {
        free(dest);
        free(temp);
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", path);
    }
    memcpy(dest, path, length + 1);
    /* Same folder as the destination, so the rename cannot cross file systems. */
    snprintf(temp, length + 16, "%s.tmpXXXXXX", path);
    int fd = mkstemp(temp);
    if (fd < 0) {
        meso_result r = meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot create: %s", path,
                                       strerror(errno));
        free(dest);
        free(temp);
        return r;
    }
    fchmod(fd, 0644);
    FILE *file = fdopen(fd, "wb");
    if (!file) {
        close(fd);
        unlink(temp);
        free(dest);
        free(temp);
        return meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot open: %s", path, strerror(errno));
    }
    *out_file = (meso_atomic_file){file, dest, temp};
    return MESO_OK;
}

static void release(meso_atomic_file *f) {
    free(f->path);
    free(f->temp_path);
    *f = (meso_atomic_file){0};
}

meso_result meso_atomic_file_commit(meso_context *ctx, meso_atomic_file *f) {
    bool ok = fflush(f->file) == 0 && !ferror(f->file);
    ok = fclose(f->file) == 0 && ok;
    f->file = NULL;
    if (!ok || rename(f->temp_path, f->path) != 0) {
        meso_result r = meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot write: %s", f->path,
                                       strerror(errno));
        unlink(f->temp_path);
        release(f);
        return r;
    }
    release(f);
    return MESO_OK;
}

void meso_atomic_file_abort(meso_atomic_file *f) {
    if (f->file) fclose(f->file);
    if (f->temp_path) unlink(f->temp_path);
    release(f);
}

meso_result meso_file_write_atomic(meso_context *ctx, const char *path, const void *data,
                                   size_t size) {
    meso_atomic_file f;
    meso_result r = meso_atomic_file_open(ctx, path, &f);
    if (r != MESO_OK) return r;
    if (size > 0 && fwrite(data, 1, size, f.file) != size) {
        r = meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot write: %s", path, strerror(errno));
        meso_atomic_file_abort(&f);
        return r;
    }
    return meso_atomic_file_commit(ctx, &f);
}

meso_result meso_file_read(meso_context *ctx, const char *path, size_t max_size, char **out_data,
                           size_t *out_size) {
    *out_data = NULL;
    if (out_size) *out_size = 0;
    FILE *file = fopen(path, "rb");
    if (!file) return meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot open: %s", path, strerror(errno));
    struct stat st;
    if (fstat(fileno(file), &st) != 0 || !S_ISREG(st.st_mode)) {
        fclose(file);
        return meso_log_error(ctx, MESO_ERROR_IO, "%s: not a regular file", path);
    }
    if ((uint64_t)st.st_size > max_size) {
        fclose(file);
        return meso_log_error(ctx, MESO_ERROR_LIMIT, "%s: %lld bytes exceeds the limit of %zu",
                              path, (long long)st.st_size, max_size);
    }
    size_t size = (size_t)st.st_size;
    char *data = malloc(size + 1);
    if (!data) {
        fclose(file);
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", path);
    }
    size_t got = fread(data, 1, size, file);
    fclose(file);
    if (got != size) {
        free(data);
        return meso_log_error(ctx, MESO_ERROR_IO, "%s: read %zu of %zu bytes", path, got, size);
    }
    data[size] = 0;
    *out_data = data;
    if (out_size) *out_size = size;
    return MESO_OK;
}
