/* The context: threads, logging, the last error. */
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "core_internal.h"

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
    pthread_mutex_init(&ctx->lock, NULL);
    pthread_mutex_init(&ctx->pool_lock, NULL);
    meso_context_set_num_threads(ctx, d.num_threads);
    *out_ctx = ctx;
    return MESO_OK;
}

void meso_context_destroy(meso_context *ctx) {
    if (!ctx) return;
    meso_pool_destroy(ctx->pool);
    pthread_mutex_destroy(&ctx->pool_lock);
    pthread_mutex_destroy(&ctx->lock);
    free(ctx);
}

int meso_context_num_threads(const meso_context *ctx) { return ctx->num_threads; }

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

static void log_message(meso_context *ctx, meso_log_level level, const char *format, va_list args) {
    char message[MESO_MESSAGE_MAX];
    vsnprintf(message, sizeof(message), format, args);
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
