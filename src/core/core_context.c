/* The context: threads, logging, the last error. */
#include <omp.h>
#include <stdlib.h>
#include <unistd.h>
#include <string.h>

#include "core_internal.h"
#include "meso/runtime.h"

static const char *const result_strings[] = {
#define MESO_RESULT_STRING(name, text) text,
    MESO_RESULT_LIST(MESO_RESULT_STRING)
#undef MESO_RESULT_STRING
};

const char *meso_result_string(meso_result result) {
    size_t count = sizeof(result_strings) / sizeof(result_strings[0]);
    return (size_t)result < count ? result_strings[result] : "unknown result";
}

bool meso_result_is_bad_input(meso_result result) {
    return result == MESO_ERROR_INVALID_ARGUMENT || result == MESO_ERROR_FORMAT ||
           result == MESO_ERROR_LIMIT || result == MESO_ERROR_UNSUPPORTED ||
           result == MESO_ERROR_IO;
}

meso_result meso_context_create(const meso_context_desc *desc, meso_context **out_ctx) {
    *out_ctx = NULL;
    meso_context *ctx = calloc(1, sizeof(*ctx));
    if (!ctx) return MESO_ERROR_OUT_OF_MEMORY;
    meso_context_desc d = desc ? *desc : (meso_context_desc){0};
    ctx->log = d.log;
    ctx->log_user = d.log_user;
    ctx->progress_mode = d.progress;
    ctx->on_progress = d.on_progress;
    ctx->progress_user = d.progress_user;
    ctx->memory_limit = d.memory_limit ? d.memory_limit : meso_memory_default_limit();
    pthread_mutex_init(&ctx->lock, NULL);
    pthread_mutex_init(&ctx->pool_lock, NULL);
    meso_context_set_num_threads(ctx, d.num_threads);
    *out_ctx = ctx;
    return MESO_OK;
}

void meso_context_destroy(meso_context *ctx) {
    if (!ctx) return;
    core_atomic_group_free(ctx);
    meso_pool_destroy(ctx->pool);
    pthread_mutex_destroy(&ctx->pool_lock);
    pthread_mutex_destroy(&ctx->lock);
    free(ctx);
}

int meso_context_num_threads(const meso_context *ctx) { return ctx->num_threads; }

void meso_context_set_subject(meso_context *ctx, const char *subject) {
    snprintf(ctx->subject, sizeof ctx->subject, "%s", subject ? subject : "");
}

void meso_context_set_num_threads(meso_context *ctx, int num_threads) {
    int count = num_threads > 0 ? num_threads : omp_get_max_threads();
    if (count < 1) count = 1;
    if (count != ctx->num_threads) { /* the next loop makes a pool of the new size */
        meso_pool_destroy(ctx->pool);
        ctx->pool = NULL;
    }
    ctx->num_threads = count;
}

const char *meso_context_last_error(const meso_context *ctx) { return ctx->last_error; }

size_t meso_text_escape_controls(const char *text, char *out, size_t out_size) {
    if (out_size == 0) return 0;
    size_t used = 0;
    /* up to 4 bytes an input byte (\xNN), and the NUL */
    for (const unsigned char *p = (const unsigned char *)text; *p && used + 5 <= out_size; p++) {
        if (*p >= 0x20 && *p != 0x7f)
            out[used++] = (char)*p;
        else if (*p == '\n' || *p == '\t')
            used += (size_t)snprintf(out + used, out_size - used, "\\%c", *p == '\n' ? 'n' : 't');
        else
            used += (size_t)snprintf(out + used, out_size - used, "\\x%02x", *p);
    }
    out[used] = 0;
    return used;
}

static void log_message(meso_context *ctx, meso_log_level level, const char *format, va_list args) {
    char raw[MESO_MESSAGE_MAX], message[MESO_MESSAGE_MAX];
    vsnprintf(raw, sizeof(raw), format, args);
    /* Control characters from file names and scene text (a newline in a JSON key, a terminal
     * escape) would forge a second "meso:" line or drive the terminal: every message stays one
     * printable line. */
    meso_text_escape_controls(raw, message, sizeof(message));
    pthread_mutex_lock(&ctx->lock);
    if (level == MESO_LOG_ERROR) memcpy(ctx->last_error, message, sizeof(message));
    if (ctx->log) ctx->log(ctx->log_user, level, message);
    pthread_mutex_unlock(&ctx->lock);
}

meso_result meso_log_error(meso_context *ctx, meso_result code, const char *format, ...) {
    va_list args;
    va_start(args, format);
    log_message(ctx, MESO_LOG_ERROR, format, args);
    va_end(args);
    return code;
}

void meso_log_warning(meso_context *ctx, const char *format, ...) {
    va_list args;
    va_start(args, format);
    log_message(ctx, MESO_LOG_WARNING, format, args);
    va_end(args);
}

void meso_log_info(meso_context *ctx, const char *format, ...) {
    va_list args;
    va_start(args, format);
    log_message(ctx, MESO_LOG_INFO, format, args);
    va_end(args);
}

/* ---- Memory budget ------------------------------------------------------------------------ */

uint64_t meso_memory_default_limit(void) {
    long pages = sysconf(_SC_PHYS_PAGES), page_size = sysconf(_SC_PAGESIZE);
    if (pages <= 0 || page_size <= 0) return UINT64_C(8) << 30; /* unknown: 8 GiB */
    /* Three quarters of the machine: room for the system and the estimate's error. */
    return (uint64_t)pages * (uint64_t)page_size / 4 * 3;
}

uint64_t meso_context_memory_limit(const meso_context *ctx) { return ctx->memory_limit; }

/* "18.50 GiB", "3.2 MiB" */
static void format_bytes(uint64_t bytes, char *out, size_t out_size) {
    if (bytes >= (UINT64_C(1) << 30))
        snprintf(out, out_size, "%.2f GiB", (double)bytes / (double)(UINT64_C(1) << 30));
    else
        snprintf(out, out_size, "%.1f MiB", (double)bytes / (double)(UINT64_C(1) << 20));
}

meso_result meso_memory_check(meso_context *ctx, const char *name, uint64_t estimate_bytes) {
    if (estimate_bytes <= ctx->memory_limit) return MESO_OK;
    char estimate[32], limit[32];
    format_bytes(estimate_bytes, estimate, sizeof(estimate));
    format_bytes(ctx->memory_limit, limit, sizeof(limit));
    return meso_log_error(ctx, MESO_ERROR_LIMIT,
                          "%s: needs about %s of memory, more than the limit of %s "
                          "(--memory-limit)",
                          name, estimate, limit);
}
