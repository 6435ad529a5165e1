/* The runtime the modules, the program and the tests share (the core module; not
 * installed): logging, parallel loops, progress, time, hashing and all-or-nothing files. */
#ifndef MESO_RUNTIME_H
#define MESO_RUNTIME_H

#include "meso/core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Copy text into out (out_size bytes, always NUL-terminated, cut when it does not fit) with
 * control characters written as \n, \t or \xNN, so that it prints as one line and sends no
 * terminal escapes. Every logged message goes through it. Returns the length written.
 * Thread-safe. */
size_t meso_text_escape_controls(const char *text, char *out, size_t out_size);

/* Log an error and return `code`, so that a failing path reads
 *     return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: truncated PNG", path);
 * The message names the file/object/field first, then the reason, without a trailing period. */
meso_result meso_log_error(meso_context *ctx, meso_result code, const char *format, ...)
    __attribute__((format(printf, 3, 4)));
void meso_log_warning(meso_context *ctx, const char *format, ...)
    __attribute__((format(printf, 2, 3)));
void meso_log_info(meso_context *ctx, const char *format, ...)
    __attribute__((format(printf, 2, 3)));

/* ---- Parallel loops ----------------------------------------------------------------------- */

/* One job of a parallel loop. `thread_index` is in [0, meso_context_num_threads(ctx)) and lets
 * a job use per-thread scratch allocated once by the caller. */
typedef void (*meso_job_fn)(void *user, size_t job, int thread_index);

/* Run fn for every job in [0, num_jobs) on the context's threads (the calling thread and a pool
 * of helpers that sleep between loops; jobs are handed out one at a time, in order).
 * For byte-identical output whatever the thread count, split work into jobs that do not depend
 * on the thread count and write disjoint memory. Returns when every job has run. A loop started
 * from inside a job, or while another loop of the same context runs on another thread, runs
 * on its caller's thread alone (thread_index 0). */
void meso_parallel_for(meso_context *ctx, size_t num_jobs, meso_job_fn fn, void *user);

/* ---- Progress ----------------------------------------------------------------------------- */

typedef struct meso_progress meso_progress;

/* Start reporting progress of `total` units of work. Never fails: returns NULL when nothing is
 * to be reported, and every progress function accepts NULL. */
meso_progress *meso_progress_begin(meso_context *ctx, const char *label, uint64_t total);
/* meso_progress_begin for a bake (work made once and cached), its bar labelled "<what> bake".
 * Where no bar is drawn because stderr is not a terminal (MESO_PROGRESS_DEFAULT: a log, CI),
 * one line goes to stderr instead as soon as the rate of the work shows it will take more
 * than about 2 s in all: "meso: baking <what> for <subject> (about N s)" (the subject of
 * meso_context_set_subject, when set), so that a log is not silent through a long bake. */
meso_progress *meso_progress_begin_bake(meso_context *ctx, const char *what, uint64_t total);
/* Name what the context's work is for ("weave-plane", a scene's path) in the line above; NULL
 * or "" names nothing. Copied (at most 255 bytes). Set it between pieces of work, not while a
 * bake runs. */
void meso_context_set_subject(meso_context *ctx, const char *subject);
/* Add `units` done. Thread-safe. Returns true when the user cancelled (see meso_progress_fn). */
bool meso_progress_advance(meso_progress *progress, uint64_t units);
/* Finish: the bar, if shown, is completed and ended with a newline. */
void meso_progress_end(meso_progress *progress);

/* ---- Time, hashing, files ----------------------------------------------------------------- */

/* Seconds on a monotonic clock. Thread-safe. */
double meso_time_seconds(void);

/* 64-bit FNV-1a of `size` bytes, continuing from `seed` (use MESO_HASH_SEED to start).
 * Stable across machines and versions: bake caches are keyed by it. */
#define MESO_HASH_SEED UINT64_C(0xcbf29ce484222325)
uint64_t meso_hash64(const void *data, size_t size, uint64_t seed);

/* A file being written beside its destination, unnamed (O_TMPFILE) where the file system
 * allows it, else under a short temporary name ".meso.tmpXXXXXX" in the destination's folder
 * (never longer than a name the folder accepts, whatever the destination's length); commit
 * renames it into place, abort removes it, so an interrupted run never leaves a half-written
 * file. A symbolic link at the destination is written through (the file it points to is
 * replaced, the link stays); a destination that exists and is not a regular file (folder,
 * FIFO, device) is refused. An existing file keeps its permission bits; a new one gets 0666
 * less the umask. */
typedef struct meso_atomic_file {
    FILE *file;      /* write here */
    char *path;      /* the destination (the link's target when path was a link) */
    char *temp_path; /* the temporary name, NULL while the file is unnamed */
    int temp_slot;   /* private: the name's entry for meso_atomic_file_remove_temporaries */
} meso_atomic_file;

/* Open a temporary file beside `path`. Returns MESO_OK, MESO_ERROR_IO (logged: the folder is
 * missing or not writable, or path is not a regular file) or MESO_ERROR_OUT_OF_MEMORY. */
meso_result meso_atomic_file_open(meso_context *ctx, const char *path, meso_atomic_file *out_file);
/* Flush, fsync, close and rename into place (or, inside a meso_atomic_group, leave the
 * complete file under its temporary name until the group ends). Returns MESO_OK or
 * MESO_ERROR_WRITE (logged with the system's reason, e.g. "No space left on device"); on
 * error the temporary file is removed. Frees the struct's strings in every case. */
meso_result meso_atomic_file_commit(meso_context *ctx, meso_atomic_file *file);
/* Close and remove the temporary file. */
void meso_atomic_file_abort(meso_atomic_file *file);
/* A command's outputs published together: between begin and end, every
 * meso_atomic_file_commit on ctx (from any writer: images, text, sheets) writes its file
 * completely, flushed and synced, under its temporary name, and only end(publish = true)
 * renames them all into place; end(false), or a failed commit within the group, removes them
 * all. So a full disk at the last output leaves every earlier one unchanged. Groups do not
 * nest: begin returns true when it opened the group, false when one was already open (or out
 * of memory), and only the caller that opened it ends it. end returns MESO_OK, or the first
 * failure. */
bool meso_atomic_group_begin(meso_context *ctx);
meso_result meso_atomic_group_end(meso_context *ctx, bool publish);
/* Remove every temporary file of atomic files still open in this process. Async-signal-safe:
 * meant for SIGINT/SIGTERM handlers, which then end the process. Unnamed (O_TMPFILE) files
 * need no removal: the kernel drops them with the process. */
void meso_atomic_file_remove_temporaries(void);
/* Write `size` bytes to `path` atomically. */
meso_result meso_file_write_atomic(meso_context *ctx, const char *path, const void *data,
                                   size_t size);
/* Check, before any work, that meso_atomic_file_open(path) would succeed: path is absent or a
 * regular file (or a link to one), its name fits the folder's limit (NAME_MAX) and the whole
 * path PATH_MAX, and its folder exists and is writable. Commands check every output first so
 * that they write all of their outputs or none. MESO_OK or MESO_ERROR_IO (logged, naming
 * path). Thread-safe. */
meso_result meso_file_check_output(meso_context *ctx, const char *path);

/* Open an input file for reading, refusing anything but a regular file (a FIFO, device or
 * folder) without blocking. MESO_OK or MESO_ERROR_IO (logged). The caller fcloses *out_file. */
meso_result meso_file_open_read(meso_context *ctx, const char *path, FILE **out_file);

/* Read a whole regular file into a new NUL-terminated buffer (caller frees). Refuses files
 * larger than max_size bytes with MESO_ERROR_LIMIT before allocating. Missing file or not a
 * regular file: MESO_ERROR_IO naming it. */
meso_result meso_file_read(meso_context *ctx, const char *path, size_t max_size, char **out_data,
                           size_t *out_size);

#ifdef __cplusplus
}
#endif
#endif
