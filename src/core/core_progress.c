/* A progress bar on stderr for work longer than about a second. */
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core_internal.h"
#include "meso/runtime.h"

#define PROGRESS_DELAY_SECONDS 1.0 /* no bar for work shorter than this */
#define PROGRESS_REDRAW_SECONDS 0.1
#define PROGRESS_BAR_WIDTH 30
/* Without a bar, a bake that will take longer than this says so in one line, once its rate has
 * been measured for PROGRESS_NOTICE_MEASURE_SECONDS (a shorter sample misjudges the start-up of
 * a parallel loop). */
#define PROGRESS_NOTICE_SECONDS 2.0
#define PROGRESS_NOTICE_MEASURE_SECONDS 0.25

struct meso_progress {
    meso_context *ctx;
    char label[64];
    uint64_t total;
    _Atomic uint64_t done;
    _Atomic bool cancelled;
    atomic_flag drawing; /* one thread draws at a time; the others skip */
    double start;
    _Atomic double last_draw;
    bool show_bar;
    bool drawn;
    bool notice;   /* a bake without a bar: one line when it proves long */
    bool noticed;  /* that line was printed (or the bake proved short) */
    char what[64]; /* the bake's name in the notice: "gdm" */
};

static meso_progress *begin(meso_context *ctx, const char *label, uint64_t total, bool bake) {
    bool show_bar = ctx->progress_mode == MESO_PROGRESS_ALWAYS ||
                    (ctx->progress_mode == MESO_PROGRESS_DEFAULT && isatty(STDERR_FILENO));
    bool notice = bake && !show_bar && ctx->progress_mode == MESO_PROGRESS_DEFAULT;
    if ((!show_bar && !notice && !ctx->on_progress) || total == 0) return NULL;
    meso_progress *p = calloc(1, sizeof(*p));
    if (!p) return NULL;
    p->ctx = ctx;
    snprintf(p->label, sizeof(p->label), "%s", label);
    p->total = total;
    atomic_init(&p->done, 0);
    atomic_init(&p->cancelled, false);
    atomic_flag_clear(&p->drawing);
    p->start = meso_time_seconds();
    p->show_bar = show_bar;
    p->notice = notice;
    return p;
}

meso_progress *meso_progress_begin(meso_context *ctx, const char *label, uint64_t total) {
    return begin(ctx, label, total, false);
}

meso_progress *meso_progress_begin_bake(meso_context *ctx, const char *what, uint64_t total) {
    char label[64];
    snprintf(label, sizeof label, "%s bake", what);
    meso_progress *p = begin(ctx, label, total, true);
    if (p) snprintf(p->what, sizeof p->what, "%s", what);
    return p;
}

/* The one line of a long bake without a bar: the whole estimated from the rate so far. */
static void notice(meso_progress *p, double fraction, double elapsed) {
    if (elapsed < PROGRESS_NOTICE_MEASURE_SECONDS || fraction <= 0.0) return;
    double estimate = elapsed / fraction;
    p->noticed = true; /* measured once: a short bake stays silent */
    if (estimate <= PROGRESS_NOTICE_SECONDS) return;
    const char *subject = p->ctx->subject;
    fprintf(stderr, "meso: baking %s%s%s (about %.0f s)\n", p->what, subject[0] ? " for " : "",
            subject, estimate);
    fflush(stderr);
}

static void draw(meso_progress *p, uint64_t done, double now) {
    double fraction = (double)done / (double)p->total;
    if (fraction > 1.0) fraction = 1.0;
    if (p->ctx->on_progress && p->ctx->on_progress(p->ctx->progress_user, p->label, fraction))
        atomic_store(&p->cancelled, true);
    if (p->notice && !p->noticed) notice(p, fraction, now - p->start);
    if (!p->show_bar || now - p->start < PROGRESS_DELAY_SECONDS) return;
    int filled = (int)(fraction * PROGRESS_BAR_WIDTH + 0.5);
    char bar[PROGRESS_BAR_WIDTH + 1];
    memset(bar, '#', (size_t)filled);
    memset(bar + filled, '.', (size_t)(PROGRESS_BAR_WIDTH - filled));
    bar[PROGRESS_BAR_WIDTH] = 0;
    double elapsed = now - p->start;
    double eta = fraction > 0.0 ? elapsed * (1.0 - fraction) / fraction : 0.0;
    fprintf(stderr, "\r%-24s [%s] %3d%%  %.1fs, %.1fs left ", p->label, bar,
            (int)(fraction * 100.0), elapsed, eta);
    fflush(stderr);
    p->drawn = true;
}

bool meso_progress_advance(meso_progress *p, uint64_t units) {
    if (!p) return false;
    uint64_t done = atomic_fetch_add(&p->done, units) + units;
    double now = meso_time_seconds();
    if (now - p->last_draw >= PROGRESS_REDRAW_SECONDS && !atomic_flag_test_and_set(&p->drawing)) {
        if (now - p->last_draw >= PROGRESS_REDRAW_SECONDS) {
            p->last_draw = now;
            draw(p, done, now);
        }
        atomic_flag_clear(&p->drawing);
    }
    return atomic_load(&p->cancelled);
}

void meso_progress_end(meso_progress *p) {
    if (!p) return;
    if (p->drawn) {
        draw(p, p->total, meso_time_seconds());
        fputc('\n', stderr);
    }
    free(p);
}
