/* meso bench: median time per frame of techniques on scenes, and their thread scaling. */
#define _GNU_SOURCE /* pthread_attr_setaffinity_np: --busy pins its spinner */
#include "app.h"
#include "app_backend.h"
#include "render_camera.h"

#include <math.h>
#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#if defined(__x86_64__) || defined(__i386__)
#include <x86intrin.h>
#define BENCH_HAS_TSC 1
#else
#define BENCH_HAS_TSC 0
#endif

#include "examples_embedded.h"
#include "meso/runtime.h"

#define MAX_SCENES 64
#define MAX_TECHNIQUES 64
/* Without --frames or --seconds a run times at least 30 frames and at least 1 s, and stops at
 * 10 s: 30 frames of a millisecond frame last a few tens of ms, too short for a median that
 * repeats between runs (docs/performance.md, "How to measure"). */
#define DEFAULT_FRAMES 30
#define DEFAULT_MIN_SECONDS 1.0
#define DEFAULT_SECONDS 10.0
#define WARMUP_FRAMES 2
#define WARMUP_SECONDS 1.0 /* the second warm-up frame is skipped after a slow first one */
#define MAX_FRAMES 10000

static const app_command_help bench_help = {
    .name = "bench",
    .usage = "[SCENES...] [options]",
    .summary =
        "Time techniques on scenes: for each scene and each technique that can draw it, prepare\n"
        "once, draw 2 warm-up frames (1 when the first takes over 1 s), then time --frames\n"
        "frames or for --seconds (by default at least 30 frames and 1 s, at most 10 s) and report\n"
        "the MEDIAN time per frame and frames per second, with every worker thread (--threads)\n"
        "and with one thread; scaling = time at 1 thread / time at N threads. Without SCENES\n"
        "the examples built into the program are used. Prints the machine and an aligned\n"
        "table; --json writes the same numbers. --backend gl (or cpu,gl: both, side by side)\n"
        "times the GLSL shaders on OpenGL (docs/gpu.md), drawing and reading back the frame;\n"
        "the GL uses its own threads, so it has no one-thread column.\n\n"
        "The camera stands still unless --orbit N turns it about its target by 1/N of a turn\n"
        "every frame, warm-up frames included, from the scene's camera for each run (so both\n"
        "thread counts see the same views): what a technique keeps from one frame to the next\n"
        "while the view stays (tessellation's traversals, shadow maps of the camera's mesh)\n"
        "then counts as it would in an animation.\n\n"
        "With --busy a CPU-bound thread spins on the last CPU beside every run (pinned there),\n"
        "as another program would: the scaling column then says whether N threads still beat\n"
        "one when a core is shared (docs/performance.md, \"How to measure\").\n\n"
        "With --profile each row also gives the cost model of docs/performance.md, from the\n"
        "one-thread run: covered pixels of the frame, fragments shaded a covered pixel,\n"
        "nanoseconds and time-stamp-counter cycles a covered pixel, for techniques whose\n"
        "searches take a fixed number of steps (linear_steps, binary_steps, shadow_steps) the\n"
        "nominal steps a pixel and nanoseconds a step, and for techniques that count their\n"
        "work (gdm) the prisms tested, table lookups and mesostructure samples a covered\n"
        "pixel.",
    .examples = "  meso bench\n"
                "  meso bench examples/bricks-plane.json --techniques relief,parallax --frames 10\n"
                "  meso bench --size 256x256 --seconds 1 --json bench.json\n"
                "  meso bench examples/bricks-plane.json --techniques relief --backend cpu,gl\n"
                "  meso bench examples/bricks-teapot.json --techniques tessellation --orbit 120\n",
};

typedef struct bench_options {
    const char *techniques;
    int frames;     /* 0: not given */
    double seconds; /* 0: not given */
    app_size size;
    const char *json;
    bool profile;
    app_settings settings; /* --set */
    const char *backends;  /* --backend: "cpu", "gl" or "cpu,gl" */
    const char *shader_dir;
    int orbit;  /* frames a turn of the camera about its target; 0: a still camera */
    bool busy;  /* a spinning thread on the last CPU beside the runs */
    int filter; /* --filter (-1: not given) */
} bench_options;

typedef struct bench_row {
    char scene[MESO_NAME_MAX];
    char technique[MESO_NAME_MAX];
    char backend[4];
    double prepare_ms;
    double ms;        /* median at the full thread count */
    double ms_single; /* median at one thread, NAN when not measured */
    int frames;
    /* --profile, from the one-thread run (NAN when not measured) */
    double covered;       /* coverage summed over the last frame's pixels */
    double fragments;     /* shaded in the last frame */
    double cycles_single; /* median time-stamp-counter cycles a frame */
    double steps;         /* nominal search steps a covered pixel; NAN: no fixed count */
    /* the technique's own counts of the last frame (meso_render_stats; gdm's): prisms,
     * table lookups, mesostructure samples; all 0 for a technique that counts none */
    double prisms, lookups, samples;
} bench_row;

typedef struct bench_scene {
    char name[MESO_NAME_MAX];
    meso_scene *scene;
} bench_scene;

/* --busy: a thread that spins until told to stop, pinned to one CPU (the last; -1 when the
 * pinning failed and it runs wherever the scheduler puts it). */
typedef struct bench_spinner {
    pthread_t thread;
    atomic_bool stop;
    bool running;
    int cpu;
} bench_spinner;

static void *spinner_main(void *arg) {
    bench_spinner *spinner = arg;
    volatile uint64_t count = 0;
    while (!atomic_load_explicit(&spinner->stop, memory_order_relaxed)) count++;
    return NULL;
}

static bool spinner_start(bench_spinner *spinner) {
    atomic_init(&spinner->stop, false);
    spinner->running = false;
    long cpus = sysconf(_SC_NPROCESSORS_ONLN);
    spinner->cpu = cpus > 0 && cpus <= CPU_SETSIZE ? (int)cpus - 1 : -1;
    pthread_attr_t attr;
    if (pthread_attr_init(&attr) != 0) return false;
    if (spinner->cpu >= 0) {
        cpu_set_t set;
        CPU_ZERO(&set);
        CPU_SET(spinner->cpu, &set);
        if (pthread_attr_setaffinity_np(&attr, sizeof set, &set) != 0) spinner->cpu = -1;
    }
    spinner->running = pthread_create(&spinner->thread, &attr, spinner_main, spinner) == 0;
    pthread_attr_destroy(&attr);
    return spinner->running;
}

static void spinner_stop(bench_spinner *spinner) {
    if (!spinner->running) return;
    atomic_store(&spinner->stop, true);
    pthread_join(spinner->thread, NULL);
    spinner->running = false;
}

/* With --orbit, the camera of the run's frame-th frame (warm-up frames counted): turned
 * frame/orbit of a turn from the scene's own (app_render_orbit's turntable). */
static void orbit_camera(meso_scene *scene, const meso_camera *home, const bench_options *o,
                         int frame) {
    if (o->orbit <= 0) return;
    view_camera home_view = app_camera_to_view(home);
    view_camera turned = view_camera_turntable(&home_view, frame, o->orbit);
    scene->camera = frame % o->orbit == 0 ? *home : app_camera_from_view(&turned);
}

/* Time frames of a prepared renderer: the median in ms, frames counted in *out_frames. */
static meso_result time_frames(app_renderer *renderer, meso_framebuffer *fb, meso_scene *scene,
                               const bench_options *o, double *times, double *cycles,
                               double *out_ms, double *out_cycles, int *out_frames) {
    const meso_camera home = scene->camera;
    int frame = 0;
    meso_result result = MESO_OK;
    double warmup_start = meso_time_seconds();
    for (int i = 0; i < WARMUP_FRAMES && meso_time_seconds() - warmup_start < WARMUP_SECONDS; i++) {
        orbit_camera(scene, &home, o, frame++);
        result = app_renderer_render(renderer, fb);
        if (result != MESO_OK) break;
    }
    bool by_default = o->frames <= 0 && o->seconds <= 0.0;
    int limit = o->frames > 0 ? o->frames : MAX_FRAMES;
    double seconds = o->seconds > 0.0 ? o->seconds : o->frames > 0 ? 0.0 : DEFAULT_SECONDS;
    double start = meso_time_seconds();
    int count = 0;
    while (result == MESO_OK && count < limit &&
           (count == 0 || seconds <= 0.0 || meso_time_seconds() - start < seconds)) {
        if (by_default && count >= DEFAULT_FRAMES &&
            meso_time_seconds() - start >= DEFAULT_MIN_SECONDS)
            break;
        orbit_camera(scene, &home, o, frame++);
        double t = meso_time_seconds();
#if BENCH_HAS_TSC
        unsigned long long c = __rdtsc();
#endif
        result = app_renderer_render(renderer, fb);
        if (result != MESO_OK) break;
#if BENCH_HAS_TSC
        cycles[count] = (double)(__rdtsc() - c);
#else
        cycles[count] = NAN;
#endif
        times[count++] = 1000.0 * (meso_time_seconds() - t);
    }
    scene->camera = home;
    if (result != MESO_OK) return result;
    *out_ms = app_median(times, (size_t)count);
    *out_cycles = app_median(cycles, (size_t)count);
    *out_frames = count;
    return MESO_OK;
}

/* One scene x technique. The renderer is made at the full thread count, so per-thread scratch
 * it sizes then stays valid when the count is lowered to one. */
/* The value of option `name` of `technique` for this run: the last --set of it, else its
 * default; NAN when the technique has no such option. */
static double option_value(const meso_technique_info *technique, const bench_options *o,
                           const char *name) {
    const meso_technique_option *row = meso_technique_find_option(technique, name);
    if (!row) return NAN;
    double value = row->default_value;
    for (int i = 0; i < o->settings.count; i++) {
        const meso_option *set = &o->settings.items[i];
        if (strcmp(set->technique, technique->name) == 0 && strcmp(set->name, name) == 0)
            value = set->value;
    }
    return value;
}

/* Search steps a pixel when the technique's searches have fixed counts: linear + binary along
 * the view, plus the shadow search toward each light when shadows are on. NAN for adaptive
 * searches (a linear_steps of 0 means "chosen per pixel", and techniques without these
 * options walk a data structure). An upper bound where a search may stop early. */
static double nominal_steps(const meso_technique_info *technique, const bench_options *o,
                            const meso_scene *scene) {
    double linear = option_value(technique, o, "linear_steps");
    if (!(linear >= 1.0)) return NAN;
    double binary = option_value(technique, o, "binary_steps");
    double shadow = option_value(technique, o, "shadow_steps");
    double shadows = option_value(technique, o, "shadows");
    double steps = linear + (isnan(binary) ? 0.0 : binary);
    if (!isnan(shadow) && !(shadows == 0.0)) steps += shadow * (double)scene->num_lights;
    return steps;
}

static meso_result bench_one(meso_context *ctx, const bench_scene *s, const char *technique,
                             const app_backend *backend, const bench_options *o, double *times,
                             double *cycles, bench_row *row) {
    *row = (bench_row){
        .ms_single = NAN, .covered = NAN, .fragments = NAN, .cycles_single = NAN, .steps = NAN};
    snprintf(row->scene, sizeof(row->scene), "%.*s", MESO_NAME_MAX - 1, s->name);
    snprintf(row->technique, sizeof(row->technique), "%s", technique);
    snprintf(row->backend, sizeof(row->backend), "%s", app_backend_is_gl(backend) ? "gl" : "cpu");
    int threads = meso_context_num_threads(ctx);
    app_renderer renderer = {0};
    meso_framebuffer *fb = NULL;
    meso_render_desc desc = {.technique = technique,
                             .options = o->settings.items,
                             .num_options = o->settings.count,
                             .filter = app_filter_mode(o->filter)};
    meso_result result = app_renderer_create(ctx, s->scene, &desc, backend, &renderer);
    if (result == MESO_OK)
        result = meso_framebuffer_create(ctx, o->size.width, o->size.height, &fb);
    if (result == MESO_OK) {
        row->prepare_ms = 1000.0 * app_renderer_get_stats(&renderer).prepare_seconds;
        double frame_cycles;
        result = time_frames(&renderer, fb, s->scene, o, times, cycles, &row->ms, &frame_cycles,
                             &row->frames);
        if (threads == 1 && !renderer.gl)
            row->ms_single = row->ms, row->cycles_single = frame_cycles;
    }
    /* the GL draws with its own threads (llvmpipe: LP_NUM_THREADS): no one-thread column */
    if (result == MESO_OK && threads > 1 && !renderer.gl) {
        int frames = 0;
        meso_context_set_num_threads(ctx, 1);
        result = time_frames(&renderer, fb, s->scene, o, times, cycles, &row->ms_single,
                             &row->cycles_single, &frames);
        meso_context_set_num_threads(ctx, threads);
    }
    if (result == MESO_OK && o->profile) {
        double covered = 0.0;
        size_t pixels = (size_t)fb->width * (size_t)fb->height;
        for (size_t i = 0; i < pixels; i++) covered += fb->coverage[i];
        row->covered = covered;
        meso_render_stats stats = app_renderer_get_stats(&renderer);
        row->fragments = (double)stats.fragments;
        row->prisms = (double)stats.prisms, row->lookups = (double)stats.lookups;
        row->samples = (double)stats.samples;
        const meso_technique_info *info = meso_technique_find(technique);
        if (info) row->steps = nominal_steps(info, o, s->scene);
    }
    meso_framebuffer_destroy(fb);
    app_renderer_destroy(&renderer);
    return result;
}

static void print_table(const bench_row *rows, size_t count, int threads) {
    char ms_n[32], ms_1[32];
    snprintf(ms_n, sizeof(ms_n), "ms (%d thr)", threads);
    snprintf(ms_1, sizeof(ms_1), "ms (1 thr)");
    printf("%-20s %-14s %-7s %11s %12s %9s %12s %8s\n", "scene", "technique", "backend",
           "prepare ms", ms_n, "fps", ms_1, "scaling");
    for (size_t i = 0; i < count; i++) {
        const bench_row *r = &rows[i];
        printf("%-20s %-14s %-7s %11.1f %12.2f %9.1f", r->scene, r->technique, r->backend,
               r->prepare_ms, r->ms, 1000.0 / r->ms);
        if (isnan(r->ms_single))
            printf(" %12s %8s\n", "-", "-");
        else
            printf(" %12.2f %7.2fx\n", r->ms_single, r->ms_single / r->ms);
    }
}

/* The cost model (--profile): per covered pixel at one thread. */
static void print_profile(const bench_row *rows, size_t count) {
    printf("\nper covered pixel, one thread (cycles: time-stamp counter)\n");
    printf("%-20s %-14s %10s %8s %9s %9s %7s %8s %9s %9s %9s\n", "scene", "technique", "covered px",
           "frag/px", "ns/px", "cyc/px", "steps", "ns/step", "prism/px", "lookup/px", "sample/px");
    for (size_t i = 0; i < count; i++) {
        const bench_row *r = &rows[i];
        if (!(r->covered > 0.0)) {
            printf("%-20s %-14s %10s\n", r->scene, r->technique, "0");
            continue;
        }
        double ns = r->ms_single * 1e6 / r->covered;
        printf("%-20s %-14s %10.0f %8.2f %9.1f %9.0f", r->scene, r->technique, r->covered,
               r->fragments / r->covered, ns, r->cycles_single / r->covered);
        if (isnan(r->steps))
            printf(" %7s %8s", "-", "-");
        else
            printf(" %7.0f %8.2f", r->steps, ns / r->steps);
        if (r->prisms > 0.0 || r->lookups > 0.0 || r->samples > 0.0)
            printf(" %9.2f %9.2f %9.2f\n", r->prisms / r->covered, r->lookups / r->covered,
                   r->samples / r->covered);
        else
            printf(" %9s %9s %9s\n", "-", "-", "-");
    }
}

static meso_result write_json(meso_context *ctx, const char *path, const bench_row *rows,
                              size_t count, const char *machine, const char *date, int threads,
                              double load, const bench_options *o) {
    app_text json = {0};
    app_text_printf(&json, "{\n  \"date\": ");
    app_text_json_string(&json, date);
    app_text_printf(&json, ",\n  \"machine\": ");
    app_text_json_string(&json, machine);
    app_text_printf(&json, ",\n  \"load_average\": ");
    app_text_json_number(&json, load);
    app_text_printf(&json,
                    ",\n  \"threads\": %d,\n  \"width\": %d,\n  \"height\": %d,\n"
                    "  \"warmup_frames\": %d,\n  \"orbit\": %d,\n  \"busy\": %s,\n"
                    "  \"runs\": [",
                    threads, o->size.width, o->size.height, WARMUP_FRAMES, o->orbit,
                    o->busy ? "true" : "false");
    for (size_t i = 0; i < count; i++) {
        const bench_row *r = &rows[i];
        app_text_printf(&json, "%s\n    {\"scene\": ", i ? "," : "");
        app_text_json_string(&json, r->scene);
        app_text_printf(&json, ", \"technique\": ");
        app_text_json_string(&json, r->technique);
        app_text_printf(&json, ", \"backend\": ");
        app_text_json_string(&json, r->backend);
        app_text_printf(&json, ", \"frames\": %d, \"prepare_ms\": ", r->frames);
        app_text_json_number(&json, r->prepare_ms);
        app_text_printf(&json, ", \"median_ms\": ");
        app_text_json_number(&json, r->ms);
        app_text_printf(&json, ", \"fps\": ");
        app_text_json_number(&json, 1000.0 / r->ms);
        app_text_printf(&json, ", \"median_ms_1_thread\": ");
        app_text_json_number(&json, r->ms_single);
        app_text_printf(&json, ", \"scaling\": ");
        app_text_json_number(&json, r->ms_single / r->ms);
        if (o->profile) {
            app_text_printf(&json, ", \"covered_pixels\": ");
            app_text_json_number(&json, r->covered);
            app_text_printf(&json, ", \"fragments\": ");
            app_text_json_number(&json, r->fragments);
            app_text_printf(&json, ", \"prisms\": ");
            app_text_json_number(&json, r->prisms);
            app_text_printf(&json, ", \"lookups\": ");
            app_text_json_number(&json, r->lookups);
            app_text_printf(&json, ", \"samples\": ");
            app_text_json_number(&json, r->samples);
            app_text_printf(&json, ", \"ns_per_pixel_1_thread\": ");
            app_text_json_number(&json, r->ms_single * 1e6 / r->covered);
            app_text_printf(&json, ", \"tsc_cycles_per_pixel_1_thread\": ");
            app_text_json_number(&json, r->cycles_single / r->covered);
            app_text_printf(&json, ", \"nominal_steps_per_pixel\": ");
            app_text_json_number(&json, r->steps);
        }
        app_text_printf(&json, "}");
    }
    app_text_printf(&json, "\n  ]\n}\n");
    meso_result result = app_text_write(ctx, &json, path);
    app_text_free(&json);
    return result;
}

/* The scenes: files named on the command line, or the embedded examples. */
static meso_result load_scenes(meso_context *ctx, const char *const *paths, int num_paths,
                               bench_scene *scenes, size_t *out_count) {
    *out_count = 0;
    size_t n = num_paths > 0 ? (size_t)num_paths : meso_embedded_example_count;
    for (size_t i = 0; i < n && i < MAX_SCENES; i++) {
        bench_scene *s = &scenes[*out_count];
        meso_result result;
        if (num_paths > 0) {
            const char *slash = strrchr(paths[i], '/');
            snprintf(s->name, sizeof(s->name), "%s", slash ? slash + 1 : paths[i]);
            s->name[strcspn(s->name, ".")] = 0;
            result = meso_scene_load(ctx, paths[i], &s->scene);
        } else {
            const meso_embedded_example *ex = &meso_embedded_examples[i];
            snprintf(s->name, sizeof(s->name), "%s", ex->name);
            result = app_example_parse(ctx, i, &s->scene);
        }
        if (result != MESO_OK) return result;
        (*out_count)++;
    }
    return MESO_OK;
}

int meso_cmd_bench(int argc, char **argv) {
    bench_options o = {.techniques = "all", .size = {512, 512}, .backends = "cpu", .filter = -1};
    const app_option options[] = {
        {"--techniques", NULL, APP_OPTION_STRING, &o.techniques, "LIST",
         "'all' (every per-pixel and geometry technique) or comma-separated names", "all", 0, 0},
        {"--frames", NULL, APP_OPTION_INT, &o.frames, "N", "frames timed a run",
         "30 and 1 s at least, 10 s at most", 1, MAX_FRAMES},
        {"--seconds", NULL, APP_OPTION_DOUBLE, &o.seconds, "S",
         "time each run for S seconds instead (with --frames: whichever ends first)", NULL, 0.001,
         3600},
        {"--size", NULL, APP_OPTION_SIZE, &o.size, "WxH", "frame size", "512x512", 0, 0},
        {"--json", NULL, APP_OPTION_STRING, &o.json, "OUT.json", "also write the numbers as JSON",
         NULL, 0, 0},
        {"--profile", NULL, APP_OPTION_FLAG, &o.profile, NULL,
         "also the cost per covered pixel and per search step (one thread)", NULL, 0, 0},
        APP_SET_OPTION(&o.settings),
        APP_FILTER_OPTION(&o.filter),
        {"--backend", NULL, APP_OPTION_STRING, &o.backends, "cpu|gl|cpu,gl",
         "the back end(s) to time: meso's rasterizer, the GLSL shaders on OpenGL, or both", "cpu",
         0, 0},
        {"--shader-dir", NULL, APP_OPTION_STRING, &o.shader_dir, "DIR",
         "with --backend gl: read the shader files from DIR", "the built-in ones", 0, 0},
        {"--orbit", NULL, APP_OPTION_INT, &o.orbit, "N",
         "turn the camera about its target by 1/N of a turn every frame", "a still camera", 1,
         1000000},
        {"--busy", NULL, APP_OPTION_FLAG, &o.busy, NULL,
         "a CPU-bound thread spins on the last CPU beside every run", NULL, 0, 0},
    };
    app_globals globals;
    const char *paths[MAX_SCENES];
    int num_paths = 0;
    int status = app_parse_options(&bench_help, options, sizeof(options) / sizeof(options[0]), argc,
                                   argv, &globals, paths, MAX_SCENES, &num_paths);
    if (status >= 0) return status;
    const char *names[MAX_TECHNIQUES];
    char names_storage[1024];
    int num_names = app_parse_technique_list("bench", o.techniques, names_storage,
                                             sizeof(names_storage), names, MAX_TECHNIQUES);
    if (num_names < 0) return APP_EXIT_BAD_INPUT;
    app_backend backends[2];
    int num_backends = 0;
    if (strcmp(o.backends, "cpu") == 0 || strcmp(o.backends, "gl") == 0) {
        backends[num_backends++] = (app_backend){o.backends, o.shader_dir};
    } else if (strcmp(o.backends, "cpu,gl") == 0 || strcmp(o.backends, "gl,cpu") == 0) {
        backends[num_backends++] = (app_backend){"cpu", NULL};
        backends[num_backends++] = (app_backend){"gl", o.shader_dir};
    } else {
        return app_usage_error("bench", "--backend: '%s' is not cpu, gl or cpu,gl", o.backends);
    }
    if (o.shader_dir && !strstr(o.backends, "gl"))
        return app_usage_error("bench", "--shader-dir needs --backend gl");

    meso_context *ctx = app_context_create(&globals);
    if (!ctx) return APP_EXIT_FAILURE;
    bench_scene scenes[MAX_SCENES] = {0};
    size_t num_scenes = 0;
    bench_row *rows = calloc((size_t)MAX_SCENES * MAX_TECHNIQUES, sizeof(*rows));
    double *times = calloc(MAX_FRAMES, sizeof(*times));
    double *cycles = calloc(MAX_FRAMES, sizeof(*cycles));
    size_t num_rows = 0;
    meso_result result = rows && times && cycles
                             ? load_scenes(ctx, paths, num_paths, scenes, &num_scenes)
                             : MESO_ERROR_OUT_OF_MEMORY;

    bench_spinner spinner = {0};
    if (result == MESO_OK && o.busy && !spinner_start(&spinner))
        result = meso_log_error(ctx, MESO_ERROR_IO, "bench: --busy: cannot start a thread");
    char busy_text[96] = "";
    if (o.busy && spinner.cpu >= 0)
        snprintf(busy_text, sizeof(busy_text), "; a spinning thread on CPU %d beside the runs",
                 spinner.cpu);
    else if (o.busy)
        snprintf(busy_text, sizeof(busy_text), "; a spinning thread beside the runs (not pinned)");

    char machine[320], date[32];
    app_machine_description(machine, sizeof(machine));
    time_t now = time(NULL);
    strftime(date, sizeof(date), "%Y-%m-%d %H:%M UTC", gmtime(&now));
    int threads = meso_context_num_threads(ctx);
    double load = app_load_average();
    char orbit_text[64] = "a still camera";
    if (o.orbit > 0)
        snprintf(orbit_text, sizeof(orbit_text), "the camera turning 1/%d of a turn a frame",
                 o.orbit);
    if (result == MESO_OK)
        printf("machine: %s; %d worker thread(s); load average %.2f at the start\n"
               "%dx%d, %d warm-up frames, median of %s per run, %s%s\n\n",
               machine, threads, load, o.size.width, o.size.height, WARMUP_FRAMES,
               o.frames          ? "--frames frames"
               : o.seconds > 0.0 ? "--seconds of frames"
                                 : "at least 30 frames and 1 s (at most 10 s)",
               orbit_text, busy_text);

    meso_progress *progress = NULL;
    if (result == MESO_OK)
        progress = meso_progress_begin(ctx, "bench", (uint64_t)num_scenes * (uint64_t)num_names);
    for (size_t s = 0; s < num_scenes && result == MESO_OK; s++) {
        meso_context_set_subject(ctx, scenes[s].name); /* named by a long bake's notice */
        for (int t = 0; t < num_names && result == MESO_OK; t++) {
            const meso_technique_info *info = meso_technique_find(names[t]);
            meso_progress_advance(progress, 1);
            if (info && !app_technique_applies(info, scenes[s].scene)) continue;
            for (int b = 0; b < num_backends && result == MESO_OK; b++) {
                /* with every technique, the GL times those it has a shader for */
                if (app_backend_is_gl(&backends[b]) && strcmp(o.techniques, "all") == 0 &&
                    !meso_gl_technique_supported(names[t]))
                    continue;
                meso_result r = bench_one(ctx, &scenes[s], names[t], &backends[b], &o, times,
                                          cycles, &rows[num_rows]);
                if (r == MESO_OK)
                    num_rows++;
                else if (r == MESO_ERROR_OUT_OF_MEMORY)
                    result = r;
                else if (!globals.quiet)
                    fprintf(stderr, "meso: warning: %s: %s (%s): %s\n", scenes[s].name, names[t],
                            backends[b].name, meso_context_last_error(ctx));
            }
        }
    }
    meso_progress_end(progress);
    spinner_stop(&spinner);
    if (result == MESO_OK && num_rows == 0)
        result = meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                                "bench: no technique could draw the scenes");
    if (result == MESO_OK) print_table(rows, num_rows, threads);
    if (result == MESO_OK && o.profile) print_profile(rows, num_rows);
    if (result == MESO_OK && o.json)
        result = write_json(ctx, o.json, rows, num_rows, machine, date, threads, load, &o);
    status = result == MESO_OK ? APP_EXIT_OK : app_fail(ctx, result);
    for (size_t s = 0; s < num_scenes; s++) meso_scene_destroy(scenes[s].scene);
    free(times);
    free(cycles);
    free(rows);
    meso_context_destroy(ctx);
    return status;
}
