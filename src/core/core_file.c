/* Atomic file writes, output checks and whole-file reads.
 *
 * Outputs are all-or-nothing (docs/design.md, "Nothing lost"): a file is written unnamed
 * (O_TMPFILE) or under a temporary name beside the destination and renamed into place only
 * when complete. Temporary names that exist are kept in a small registry so that a signal
 * handler can remove them (meso_atomic_file_remove_temporaries); with O_TMPFILE a name exists
 * only for the instant between linkat and rename, so even SIGKILL leaves nothing behind.
 * Inputs are opened non-blocking and checked to be regular files before a byte is read: a
 * FIFO given as an input would otherwise block open() forever.
 */
#define _GNU_SOURCE /* O_TMPFILE, linkat's AT_SYMLINK_FOLLOW */
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core_internal.h"
#include "meso/runtime.h"

/* ---- Registry of live temporary names (for signal handlers) ------------------------------- */

/* Slots hold the names of temporary files that exist on disk. States: 0 free, 1 being filled,
 * 2 live. The handler only reads live slots and calls unlink, both async-signal-safe. */
#define TEMP_SLOTS 64
static char temp_slot_paths[TEMP_SLOTS][PATH_MAX];
static atomic_int temp_slot_states[TEMP_SLOTS];

/* Returns the slot + 1, or 0 when the name is not registered (registry full or name too long:
 * the file is still removed on every normal path, only a signal could leave it). */
static int register_temporary(const char *path) {
    if (strlen(path) >= PATH_MAX) return 0;
    for (int i = 0; i < TEMP_SLOTS; i++) {
        int expected = 0;
        if (atomic_compare_exchange_strong(&temp_slot_states[i], &expected, 1)) {
            memcpy(temp_slot_paths[i], path, strlen(path) + 1);
            atomic_store(&temp_slot_states[i], 2);
            return i + 1;
        }
    }
    return 0;
}

static void unregister_temporary(int slot) {
    if (slot > 0) atomic_store(&temp_slot_states[slot - 1], 0);
}

void meso_atomic_file_remove_temporaries(void) {
    for (int i = 0; i < TEMP_SLOTS; i++)
        if (atomic_load(&temp_slot_states[i]) == 2) unlink(temp_slot_paths[i]);
}

/* ---- Output checks ------------------------------------------------------------------------ */

static const char *file_type_name(mode_t mode) {
    if (S_ISDIR(mode)) return "a folder";
    if (S_ISFIFO(mode)) return "a FIFO";
    if (S_ISCHR(mode)) return "a character device";
    if (S_ISBLK(mode)) return "a block device";
    if (S_ISSOCK(mode)) return "a socket";
    return "not a regular file";
}

/* The folder part of path ("." when none) into out. */
static bool folder_of(const char *path, char *out, size_t out_size) {
    const char *slash = strrchr(path, '/');
    if (!slash) return snprintf(out, out_size, ".") < (int)out_size;
    size_t length = slash == path ? 1 : (size_t)(slash - path);
    if (length + 1 > out_size) return false;
    memcpy(out, path, length);
    out[length] = 0;
    return true;
}

/* Where the bytes of `path` go: the path itself, or the file a symbolic link points to (a link
 * is written through, so the link stays a link). *out_exists tells whether it exists, and
 * *out_mode its permission bits when it does. */
static meso_result resolve_output(meso_context *ctx, const char *path, char **out_target,
                                  bool *out_exists, mode_t *out_mode) {
    *out_target = NULL;
    *out_exists = false;
    *out_mode = 0;
    if (!path[0]) return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "output: empty path");
    struct stat st;
    char *target = NULL;
    if (lstat(path, &st) == 0 && S_ISLNK(st.st_mode)) {
        if (stat(path, &st) != 0)
            return errno == ENOENT
                       ? meso_log_error(ctx, MESO_ERROR_IO,
                                        "%s: is a symbolic link to a missing file", path)
                       : meso_log_error(ctx, MESO_ERROR_IO, "%s: %s", path, strerror(errno));
        target = realpath(path, NULL);
        if (!target)
            return meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot resolve: %s", path,
                                  strerror(errno));
        *out_exists = true;
    } else if (lstat(path, &st) == 0) {
        *out_exists = true;
    } else if (errno != ENOENT) {
        return meso_log_error(ctx, MESO_ERROR_IO, "%s: %s", path, strerror(errno));
    }
    if (*out_exists && !S_ISREG(st.st_mode)) {
        free(target);
        return meso_log_error(ctx, MESO_ERROR_IO, "%s: is %s; meso writes only regular files", path,
                              file_type_name(st.st_mode));
    }
    if (*out_exists) *out_mode = st.st_mode & 07777;
    if (!target) target = strdup(path);
    if (!target) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", path);
    *out_target = target;
    return MESO_OK;
}

/* The temporary name in the destination's folder: short, so that it fits wherever the
 * destination's own name fits (a name of NAME_MAX bytes plus a suffix would not). */
#define TEMP_PREFIX ".meso.tmp"
#define TEMP_NAME_LENGTH (sizeof(TEMP_PREFIX) - 1 + 6)

/* The destination's name and the temporary's both fit: the name within the folder's
 * NAME_MAX, each whole path within PATH_MAX. Checked before any work, so that a long name is
 * refused at once rather than after minutes of rendering. */
static meso_result check_name_lengths(meso_context *ctx, const char *path, const char *target,
                                      const char *folder) {
    const char *slash = strrchr(target, '/');
    size_t name_length = strlen(slash ? slash + 1 : target);
    long name_max = pathconf(folder, _PC_NAME_MAX);
    if (name_max <= 0) name_max = NAME_MAX;
    if (name_length > (size_t)name_max)
        return meso_log_error(ctx, MESO_ERROR_IO,
                              "%s: cannot write: file name too long (%zu bytes, the folder "
                              "allows %ld)",
                              path, name_length, name_max);
    if (strlen(target) >= PATH_MAX || strlen(folder) + 1 + TEMP_NAME_LENGTH >= PATH_MAX)
        return meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot write: path too long (limit %d)",
                              path, PATH_MAX - 1);
    return MESO_OK;
}

/* resolve_output and the folder the output goes in (PATH_MAX bytes); on an error nothing is
 * left to free. */
static meso_result resolve_output_folder(meso_context *ctx, const char *path, char **out_target,
                                         bool *out_exists, mode_t *out_mode, char *folder) {
    meso_result r = resolve_output(ctx, path, out_target, out_exists, out_mode);
    if (r != MESO_OK) return r;
    if (!folder_of(*out_target, folder, PATH_MAX)) {
        free(*out_target);
        *out_target = NULL;
        return meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot write: path too long", path);
    }
    return MESO_OK;
}

meso_result meso_file_check_output(meso_context *ctx, const char *path) {
    char *target = NULL, folder[PATH_MAX];
    bool exists = false;
    mode_t mode = 0;
    meso_result r = resolve_output_folder(ctx, path, &target, &exists, &mode, folder);
    if (r != MESO_OK) return r;
    struct stat st;
    if (stat(folder, &st) != 0)
        r = meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot write: folder %s: %s", path, folder,
                           strerror(errno));
    else if (!S_ISDIR(st.st_mode))
        r = meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot write: %s is not a folder", path,
                           folder);
    else if (access(folder, W_OK | X_OK) != 0)
        r = meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot write: folder %s: %s", path, folder,
                           strerror(errno));
    else
        r = check_name_lengths(ctx, path, target, folder);
    free(target);
    return r;
}

/* ---- Atomic writes ------------------------------------------------------------------------ */

/* The process's umask, read once: umask() can only be read by setting it, which races with
 * other threads creating files, so it is done once (the first write) rather than per file. */
static mode_t process_umask(void) {
    static atomic_int cached = -1;
    int mask = atomic_load(&cached);
    if (mask < 0) {
        mode_t old = umask(022);
        umask(old);
        mask = (int)old;
        atomic_store(&cached, mask);
    }
    return (mode_t)mask;
}

/* An unnamed file in `folder` (Linux 3.11+, on file systems that support it), or -1. */
static int open_unnamed(const char *folder) {
#ifdef O_TMPFILE
    /* The file is named at commit through /proc/self/fd (linkat); without /proc it could not
     * be, so the named temporary is used instead. */
    if (access("/proc/self/fd", X_OK) != 0) return -1;
    return open(folder, O_TMPFILE | O_WRONLY | O_CLOEXEC, 0666);
#else
    (void)folder;
    errno = EOPNOTSUPP;
    return -1;
#endif
}

/* "<folder>/.meso.tmp" followed by six characters from `seed` (a new malloc'ed string). */
static char *temporary_name(const char *folder, unsigned seed) {
    size_t size = strlen(folder) + 1 + TEMP_NAME_LENGTH + 1;
    char *name = malloc(size);
    if (!name) return NULL;
    static const char digits[] = "abcdefghijklmnopqrstuvwxyz0123456789";
    char suffix[7];
    for (int i = 0; i < 6; i++, seed /= 36) suffix[i] = digits[seed % 36];
    suffix[6] = 0;
    snprintf(name, size, "%s/" TEMP_PREFIX "%s", folder, suffix);
    return name;
}

meso_result meso_atomic_file_open(meso_context *ctx, const char *path, meso_atomic_file *out_file) {
    *out_file = (meso_atomic_file){0};
    /* Same folder as the destination, so the rename cannot cross file systems. */
    char *dest = NULL, folder[PATH_MAX];
    bool exists = false;
    mode_t mode = 0;
    meso_result r = resolve_output_folder(ctx, path, &dest, &exists, &mode, folder);
    if (r != MESO_OK) return r;
    if ((r = check_name_lengths(ctx, path, dest, folder)) != MESO_OK) {
        free(dest);
        return r;
    }
    int fd = open_unnamed(folder);
    char *temp = NULL;
    int slot = 0;
    if (fd < 0) {
        temp = temporary_name(folder, 0);
        if (!temp) {
            free(dest);
            return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", path);
        }
        memcpy(temp + strlen(temp) - 6, "XXXXXX", 6);
        fd = mkostemp(temp, O_CLOEXEC);
        if (fd < 0) {
            r = meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot create: %s", path, strerror(errno));
            free(dest);
            free(temp);
            return r;
        }
        slot = register_temporary(temp);
    }
    /* An existing file keeps its permissions; a new one gets 0666 less the umask, as any
     * program creating it would give it. */
    fchmod(fd, exists ? mode : 0666 & ~process_umask());
    FILE *file = fdopen(fd, "wb");
    if (!file) {
        r = meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot open: %s", path, strerror(errno));
        close(fd);
        if (temp) unlink(temp);
        unregister_temporary(slot);
        free(dest);
        free(temp);
        return r;
    }
    *out_file = (meso_atomic_file){file, dest, temp, slot};
    return MESO_OK;
}

static void release(meso_atomic_file *f) {
    if (f->temp_path) unregister_temporary(f->temp_slot);
    free(f->path);
    free(f->temp_path);
    *f = (meso_atomic_file){0};
}

/* Give the unnamed file of `fd` a temporary name (registered) in the destination's folder, for
 * the rename. linkat straight to the destination would fail when it exists, and rename is what
 * replaces a file atomically. */
static bool name_unnamed_file(meso_atomic_file *f, int fd) {
    char proc_path[64], folder[PATH_MAX];
    snprintf(proc_path, sizeof(proc_path), "/proc/self/fd/%d", fd);
    if (!folder_of(f->path, folder, sizeof(folder))) {
        errno = ENAMETOOLONG;
        return false;
    }
    for (unsigned attempt = 0; attempt < 100; attempt++) {
        f->temp_path = temporary_name(folder, (unsigned)getpid() * 2654435761u + attempt * 40503u +
                                                  (unsigned)(uintptr_t)f);
        if (!f->temp_path) return false;
        f->temp_slot = register_temporary(f->temp_path);
        if (linkat(AT_FDCWD, proc_path, AT_FDCWD, f->temp_path, AT_SYMLINK_FOLLOW) == 0)
            return true;
        int saved = errno;
        unregister_temporary(f->temp_slot);
        f->temp_slot = 0;
        free(f->temp_path);
        f->temp_path = NULL;
        errno = saved;
        if (errno != EEXIST) break;
    }
    return false;
}

/* Flush, sync and close the file and leave it complete under its temporary name; on failure
 * remove it and log the system's reason. */
static meso_result finish(meso_context *ctx, meso_atomic_file *f) {
    errno = 0;
    bool ok = fflush(f->file) == 0 && !ferror(f->file);
    /* On the disk before the rename: a crash after it must not leave an empty file under
     * the destination's name (ext4 and XFS may order the rename before the data). */
    if (ok) ok = fsync(fileno(f->file)) == 0 || errno == EINVAL || errno == EROFS;
    if (ok && f->temp_path == NULL) ok = name_unnamed_file(f, fileno(f->file));
    int saved_errno = errno;
    bool closed = fclose(f->file) == 0;
    if (ok && !closed) saved_errno = errno;
    ok = ok && closed;
    f->file = NULL;
    if (ok) return MESO_OK;
    meso_result r = meso_log_error(ctx, MESO_ERROR_WRITE, "%s: cannot write: %s", f->path,
                                   strerror(saved_errno ? saved_errno : EIO));
    if (f->temp_path) unlink(f->temp_path);
    release(f);
    return r;
}

static meso_result publish(meso_context *ctx, meso_atomic_file *f) {
    meso_result r = MESO_OK;
    if (rename(f->temp_path, f->path) != 0) {
        r = meso_log_error(ctx, MESO_ERROR_WRITE, "%s: cannot write: %s", f->path, strerror(errno));
        unlink(f->temp_path);
    }
    release(f);
    return r;
}

/* ---- Groups of outputs published together ------------------------------------------------ */

typedef struct core_atomic_group {
    meso_atomic_file *files; /* finished, under their temporary names */
    size_t count, capacity;
    meso_result failure; /* the first failed commit in the group */
} core_atomic_group;

bool meso_atomic_group_begin(meso_context *ctx) {
    bool opened = false;
    pthread_mutex_lock(&ctx->lock);
    if (!ctx->atomic_group) {
        ctx->atomic_group = calloc(1, sizeof(core_atomic_group));
        opened = ctx->atomic_group != NULL;
    }
    pthread_mutex_unlock(&ctx->lock);
    return opened;
}

/* Hold a finished file in the group: 1 held, 0 no group (publish it now), -1 out of memory
 * (the file is removed: publishing it alone would break the group's all or nothing). */
static int hold(meso_context *ctx, meso_atomic_file *f) {
    pthread_mutex_lock(&ctx->lock);
    core_atomic_group *g = ctx->atomic_group;
    int held = g ? -1 : 0;
    if (g && g->count == g->capacity) {
        size_t capacity = g->capacity ? 2 * g->capacity : 32;
        meso_atomic_file *grown = realloc(g->files, capacity * sizeof(*grown));
        if (grown) g->files = grown, g->capacity = capacity;
    }
    if (g && g->count < g->capacity) {
        g->files[g->count++] = *f;
        *f = (meso_atomic_file){0};
        held = 1;
    }
    pthread_mutex_unlock(&ctx->lock);
    return held;
}

static void record_failure(meso_context *ctx, meso_result r) {
    pthread_mutex_lock(&ctx->lock);
    if (ctx->atomic_group && ctx->atomic_group->failure == MESO_OK) ctx->atomic_group->failure = r;
    pthread_mutex_unlock(&ctx->lock);
}

meso_result meso_atomic_group_end(meso_context *ctx, bool publish_all) {
    pthread_mutex_lock(&ctx->lock);
    core_atomic_group *g = ctx->atomic_group;
    ctx->atomic_group = NULL;
    pthread_mutex_unlock(&ctx->lock);
    if (!g) return MESO_OK;
    meso_result r = g->failure;
    for (size_t i = 0; i < g->count; i++) {
        if (publish_all && r == MESO_OK) {
            r = publish(ctx, &g->files[i]);
        } else {
            unlink(g->files[i].temp_path);
            release(&g->files[i]);
        }
    }
    free(g->files);
    free(g);
    return r;
}

void core_atomic_group_free(meso_context *ctx) { meso_atomic_group_end(ctx, false); }

meso_result meso_atomic_file_commit(meso_context *ctx, meso_atomic_file *f) {
    meso_result r = finish(ctx, f);
    if (r != MESO_OK) {
        record_failure(ctx, r);
        return r;
    }
    int held = hold(ctx, f);
    if (held > 0) return MESO_OK;
    if (held == 0) return publish(ctx, f);
    r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", f->path);
    unlink(f->temp_path);
    release(f);
    record_failure(ctx, r);
    return r;
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
        r = meso_log_error(ctx, MESO_ERROR_WRITE, "%s: cannot write: %s", path, strerror(errno));
        meso_atomic_file_abort(&f);
        record_failure(ctx, r);
        return r;
    }
    return meso_atomic_file_commit(ctx, &f);
}

/* ---- Reading ------------------------------------------------------------------------------ */

meso_result meso_file_open_read(meso_context *ctx, const char *path, FILE **out_file) {
    *out_file = NULL;
    /* O_NONBLOCK: opening a FIFO for reading would otherwise wait for a writer forever. It is
     * cleared again once the file is known to be regular. */
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0)
        return meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot open: %s", path, strerror(errno));
    struct stat st;
    bool stat_ok = fstat(fd, &st) == 0;
    if (!stat_ok || !S_ISREG(st.st_mode)) {
        close(fd);
        return meso_log_error(ctx, MESO_ERROR_IO, "%s: is %s, not a regular file", path,
                              stat_ok ? file_type_name(st.st_mode) : "unreadable");
    }
    int flags = fcntl(fd, F_GETFL);
    if (flags >= 0) fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
    FILE *file = fdopen(fd, "rb");
    if (!file) {
        close(fd);
        return meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot open: %s", path, strerror(errno));
    }
    *out_file = file;
    return MESO_OK;
}

meso_result meso_file_read(meso_context *ctx, const char *path, size_t max_size, char **out_data,
                           size_t *out_size) {
    *out_data = NULL;
    if (out_size) *out_size = 0;
    FILE *file = NULL;
    meso_result r = meso_file_open_read(ctx, path, &file);
    if (r != MESO_OK) return r;
    struct stat st;
    if (fstat(fileno(file), &st) != 0) {
        fclose(file);
        return meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot stat: %s", path, strerror(errno));
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
