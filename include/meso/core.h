/* meso core: results and errors, the context, parallel loops, progress, hashing, atomic files.
 *
 * Overview
 *   Every libmeso call that can fail takes a meso_context and returns a meso_result. The
 *   context carries the number of worker threads, a logger and the progress mode. A failing
 *   call logs one message that names the file, object or field and the reason, e.g.
 *   "bricks.png: width 70000 exceeds the limit 16384", and returns the code; the message is
 *   also kept as the context's last error for callers that want it as a string.
 *
 * Usage
 *   meso_context *ctx = NULL;
 *   if (meso_context_create(&(meso_context_desc){0}, &ctx) != MESO_OK) return 1;
 *   ...
 *   if (meso_scene_load(ctx, "scene.json", &scene) != MESO_OK)
 *       fprintf(stderr, "meso: %s\n", meso_context_last_error(ctx));
 *   meso_context_destroy(ctx);
 *
 * Threads
 *   A context may be used from several threads at once: logging is serialised, and worker
 *   loops started from different threads run independently (the context's pool runs one at a
 *   time; another runs on its caller's thread). Library calls never exit or print
 *   (but for the progress bar, which writes to stderr only when enabled).
 */
#ifndef MESO_CORE_H
#define MESO_CORE_H

#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ---- Results ------------------------------------------------------------------------------ */

/* The one list of results; it also generates meso_result_string(). */
#define MESO_RESULT_LIST(X)                                                                        \
    X(MESO_OK, "ok")                                                                               \
    X(MESO_ERROR_INVALID_ARGUMENT, "invalid argument")                                             \
    X(MESO_ERROR_IO, "input/output error")                                                         \
    X(MESO_ERROR_FORMAT, "malformed input")                                                        \
    X(MESO_ERROR_LIMIT, "input exceeds a documented limit")                                        \
    X(MESO_ERROR_OUT_OF_MEMORY, "out of memory")                                                   \
    X(MESO_ERROR_UNSUPPORTED, "unsupported")                                                       \
    X(MESO_ERROR_CANCELLED, "cancelled")                                                           \
    X(MESO_ERROR_INTERNAL, "internal error")                                                       \
    X(MESO_ERROR_WRITE, "cannot write an output")

typedef enum meso_result {
#define MESO_RESULT_ENUM(name, text) name,
    MESO_RESULT_LIST(MESO_RESULT_ENUM)
#undef MESO_RESULT_ENUM
} meso_result;

/* A short English phrase for a result; never NULL. Thread-safe. */
const char *meso_result_string(meso_result result);

/* Whether a result is the fault of the input (usage or data), which the CLI reports with exit
 * status 2, rather than of the machine (a failed write such as a full disk, memory, internal),
 * reported with status 1. MESO_ERROR_IO is an input that cannot be read or an output refused
 * before any work (missing folder, not a regular file, name too long); MESO_ERROR_WRITE an
 * output that could not be written after the work. */
bool meso_result_is_bad_input(meso_result result);

/* ---- Context ------------------------------------------------------------------------------ */

typedef enum meso_log_level {
    MESO_LOG_ERROR = 0,
    MESO_LOG_WARNING,
    MESO_LOG_INFO,
} meso_log_level;

/* Called for every message; may be called from worker threads, one call at a time. */
typedef void (*meso_log_fn)(void *user, meso_log_level level, const char *message);

/* Called by long operations with the fraction done in [0,1]; return true to cancel the
 * operation, which then returns MESO_ERROR_CANCELLED. Called from one thread at a time. */
typedef bool (*meso_progress_fn)(void *user, const char *label, double fraction);

typedef enum meso_progress_mode {
    MESO_PROGRESS_DEFAULT = 0, /* a bar on stderr for work over ~1 s, when stderr is a terminal */
    MESO_PROGRESS_ALWAYS,      /* the bar even when stderr is not a terminal (--progress) */
    MESO_PROGRESS_NEVER,
} meso_progress_mode;

typedef struct meso_context_desc {
    int num_threads; /* 0: every core (omp_get_max_threads(): OMP_NUM_THREADS) */
    meso_log_fn log; /* NULL: warnings and errors are only kept, not printed */
    void *log_user;
    meso_progress_mode progress;
    meso_progress_fn on_progress; /* NULL: none; called in addition to the bar */
    void *progress_user;
    uint64_t memory_limit; /* bytes a job may need; 0: meso_memory_default_limit() */
} meso_context_desc;

typedef struct meso_context meso_context;

/* Create a context. desc is read during the call only; NULL means all defaults.
 * Returns MESO_OK or MESO_ERROR_OUT_OF_MEMORY; *out_ctx is NULL on failure. */
meso_result meso_context_create(const meso_context_desc *desc, meso_context **out_ctx);
/* Destroy a context; NULL does nothing. No call on ctx may be running. */
void meso_context_destroy(meso_context *ctx);

/* The number of worker threads loops on this context use (>= 1). Thread-safe. */
int meso_context_num_threads(const meso_context *ctx);
/* Change the number of worker threads (0: every core). Not thread-safe against running loops. */
void meso_context_set_num_threads(meso_context *ctx, int num_threads);
/* The message of the last error logged on ctx ("" if none). Valid until the next error. */
const char *meso_context_last_error(const meso_context *ctx);

/* ---- Memory budget ------------------------------------------------------------------------
 * Jobs estimate the memory they will need (meshes after subdivision with their derived
 * arrays, height fields, colour maps, framebuffers times samples) before allocating it, and
 * refuse with MESO_ERROR_LIMIT when the estimate is over the context's limit, rather than
 * running out of memory (or being killed) after minutes of work. */

/* Three quarters of the physical memory (8 GiB when it cannot be read). Thread-safe. */
uint64_t meso_memory_default_limit(void);
/* The context's limit in bytes. Thread-safe. */
uint64_t meso_context_memory_limit(const meso_context *ctx);
/* MESO_OK when estimate_bytes is within the context's limit, else MESO_ERROR_LIMIT logged as
 * "<name>: needs about 18.50 GiB of memory, more than the limit of 17.25 GiB (--memory-limit)".
 * Thread-safe. */
meso_result meso_memory_check(meso_context *ctx, const char *name, uint64_t estimate_bytes);

#ifdef __cplusplus
}
#endif
#endif
