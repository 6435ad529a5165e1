/* The bake cache (docs/bake-format.md, "The bake cache"): one file per (kind, key) in a folder
 * from $MESO_CACHE_DIR, $XDG_CACHE_HOME/meso or $HOME/.cache/meso. */
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include "bake_internal.h"
#include "meso/bake_cache.h"
#include "meso/bake_file.h"
#include "meso/runtime.h"

/* mkdir -p for the cache folder; existing folders are fine. */
static bool make_dirs(char *path) {
    for (char *p = path + 1; *p; p++) {
        if (*p != '/') continue;
        *p = 0;
        bool ok = mkdir(path, 0755) == 0 || errno == EEXIST;
        *p = '/';
        if (!ok) return false;
    }
    return mkdir(path, 0755) == 0 || errno == EEXIST;
}

meso_result meso_bake_cache_dir(meso_context *ctx, char *out_dir, size_t size) {
    if (!out_dir || size == 0) return MESO_ERROR_INVALID_ARGUMENT;
    out_dir[0] = 0;
    const char *env = getenv("MESO_CACHE_DIR");
    int n;
    if (env && env[0]) {
        if (strcmp(env, "off") == 0) return MESO_ERROR_UNSUPPORTED;
        n = snprintf(out_dir, size, "%s", env);
    } else if ((env = getenv("XDG_CACHE_HOME")) && env[0]) {
        n = snprintf(out_dir, size, "%s/meso", env);
    } else if ((env = getenv("HOME")) && env[0]) {
        n = snprintf(out_dir, size, "%s/.cache/meso", env);
    } else {
        return MESO_ERROR_UNSUPPORTED;
    }
    if (n < 0 || (size_t)n >= size) {
        out_dir[0] = 0;
        return MESO_ERROR_UNSUPPORTED;
    }
    struct stat st;
    if (stat(out_dir, &st) == 0 && S_ISDIR(st.st_mode)) return MESO_OK;
    if (!make_dirs(out_dir)) {
        meso_result r =
            meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot create the bake cache folder: %s",
                           out_dir, strerror(errno));
        out_dir[0] = 0;
        return r;
    }
    return MESO_OK;
}

meso_result meso_bake_cache_path(meso_context *ctx, const char *kind, uint64_t key, char *out_path,
                                 size_t size) {
    if (!kind || !out_path || size == 0) return MESO_ERROR_INVALID_ARGUMENT;
    char dir[1024];
    meso_result result = meso_bake_cache_dir(ctx, dir, sizeof(dir));
    if (result != MESO_OK) {
        out_path[0] = 0;
        return result;
    }
    int n = snprintf(out_path, size, "%s/%s-%016llx.mesobake", dir, kind, (unsigned long long)key);
    if (n < 0 || (size_t)n >= size) {
        out_path[0] = 0;
        return MESO_ERROR_UNSUPPORTED;
    }
    return MESO_OK;
}

/* Log the load failure as a warning instead of an error: a bad cache entry is re-baked. */
meso_result meso_bake_cache_load(meso_context *ctx, const char *kind, uint32_t kind_version,
                                 uint64_t key, uint64_t source_hash, meso_bake_file **out_bake) {
    if (out_bake) *out_bake = NULL;
    if (!kind || !out_bake) return MESO_ERROR_INVALID_ARGUMENT;
    char path[1200];
    if (meso_bake_cache_path(ctx, kind, key, path, sizeof(path)) != MESO_OK) return MESO_OK;
    if (access(path, F_OK) != 0) return MESO_OK; /* not cached yet */
    meso_bake_file *bake = NULL;
    meso_result result = meso_bake_file_load(ctx, path, &bake);
    if (result == MESO_ERROR_OUT_OF_MEMORY) return result;
    if (result != MESO_OK) {
        meso_log_warning(ctx, "%s: unusable cache entry, baking again: %s", path,
                         meso_context_last_error(ctx));
        return MESO_OK;
    }
    if (strcmp(bake->kind, kind) != 0 || bake->kind_version != kind_version) {
        meso_log_warning(ctx,
                         "%s: cache entry of kind %s version %u, expected %s version %u; "
                         "baking again",
                         path, bake->kind, bake->kind_version, kind, kind_version);
        meso_bake_file_destroy(bake);
        return MESO_OK;
    }
    if (bake->source_hash != source_hash) {
        meso_log_warning(ctx,
                         "%s: cache entry made from another source (hash %016llx, expected "
                         "%016llx); baking again",
                         path, (unsigned long long)bake->source_hash,
                         (unsigned long long)source_hash);
        meso_bake_file_destroy(bake);
        return MESO_OK;
    }
    *out_bake = bake;
    return MESO_OK;
}

meso_result meso_bake_cache_save(meso_context *ctx, const meso_bake_file *bake, uint64_t key) {
    if (!bake) return MESO_ERROR_INVALID_ARGUMENT;
    char path[1200];
    meso_result result = meso_bake_cache_path(ctx, bake->kind, key, path, sizeof(path));
    if (result == MESO_ERROR_UNSUPPORTED) return MESO_OK; /* cache disabled */
    if (result != MESO_OK) return result;
    result = meso_bake_file_save(ctx, bake, path);
    /* one line a bake stored: how shards sharing a cache count the bakes they duplicated */
    if (result == MESO_OK) meso_log_info(ctx, "bake cache: stored %s", path);
    return result;
}

/* The lock file is removed by the holder before it unlocks, so a waiter that wakes up holding
 * a lock on a removed (or replaced) file has locked nothing: it checks that the path still
 * names the file it locked, and starts over otherwise. A process killed while holding the
 * claim leaves the file, unlocked (the kernel releases the lock): the next claimer locks it,
 * uses it and removes it. */
void meso_bake_cache_claim_entry(meso_context *ctx, const char *kind, uint64_t key,
                                 meso_bake_cache_claim *out) {
    out->fd = -1;
    out->path[0] = 0;
    char entry[1100];
    if (meso_bake_cache_path(ctx, kind, key, entry, sizeof entry) != MESO_OK) return;
    int n = snprintf(out->path, sizeof out->path, "%s.lock", entry);
    if (n < 0 || (size_t)n >= sizeof out->path) return;
    for (int attempt = 0; attempt < 1000; attempt++) {
        int fd = open(out->path, O_RDWR | O_CREAT | O_CLOEXEC, 0644);
        if (fd < 0) return; /* a read-only cache: no claim, bakes are still stored atomically */
        int locked;
        while ((locked = flock(fd, LOCK_EX)) != 0 && errno == EINTR) {
        }
        if (locked != 0) { /* ENOLCK, EOPNOTSUPP: a file system without locks */
            close(fd);
            return;
        }
        struct stat held, named;
        if (fstat(fd, &held) == 0 && stat(out->path, &named) == 0 && held.st_ino == named.st_ino &&
            held.st_dev == named.st_dev) {
            out->fd = fd;
            return;
        }
        close(fd); /* the holder before us removed it: claim the new one */
    }
}

void meso_bake_cache_release(meso_bake_cache_claim *claim) {
    if (claim->fd < 0) return;
    unlink(claim->path);
    close(claim->fd);
    claim->fd = -1;
}

static meso_result load_or_bake(meso_context *ctx, const meso_cached_bake *e, void *out) {
    meso_bake_file *cached = NULL;
    meso_result result =
        meso_bake_cache_load(ctx, e->kind, e->kind_version, e->key, e->source_hash, &cached);
    if (result != MESO_OK) return result;
    if (cached) {
        char where[96];
        snprintf(where, sizeof where, "%s cache entry", e->label);
        result = e->from_file(ctx, cached, where, e->desc, out);
        meso_bake_file_destroy(cached);
        if (result == MESO_OK || result == MESO_ERROR_OUT_OF_MEMORY) return result;
        meso_log_warning(ctx, "%s: cache entry unusable, baking again: %s", e->label,
                         meso_context_last_error(ctx));
    }
    if ((result = e->bake(ctx, e->desc, out)) != MESO_OK) return result;
    if (e->store(ctx, e, out) != MESO_OK)
        meso_log_warning(ctx, "%s: could not store the bake in the cache: %s", e->label,
                         meso_context_last_error(ctx));
    return MESO_OK;
}

meso_result meso_bake_cache_run(meso_context *ctx, const meso_cached_bake *entry, void *out) {
    meso_bake_cache_claim claim;
    meso_bake_cache_claim_entry(ctx, entry->kind, entry->key, &claim);
    meso_result result = load_or_bake(ctx, entry, out);
    meso_bake_cache_release(&claim);
    return result;
}

meso_result
meso_bake_load_with(meso_context *ctx, const char *path,
                    meso_result (*from_file)(meso_context *ctx, const meso_bake_file *bake,
                                             const char *where, const void *desc, void *out),
                    const void *desc, void *out) {
    meso_bake_file *bake = NULL;
    meso_result result = meso_bake_file_load(ctx, path, &bake);
    if (result != MESO_OK) return result;
    result = from_file(ctx, bake, path, desc, out);
    meso_bake_file_destroy(bake);
    return result;
}
