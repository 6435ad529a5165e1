/* The meso program: what its subcommands share (app.c, app_compare_all.c).
 *
 * Every subcommand is `int meso_cmd_<name>(int argc, char **argv)` with argv[0] the command's
 * name, and returns an exit status (docs/design.md): 0 success, 2 bad input or usage, 1 anything
 * else. A failing command prints exactly one line to stderr, "meso: <message>", where the
 * message is the library's last error (it names the file and the reason) or a usage message.
 * The program uses only the public API, <meso/meso.h>.
 */
#ifndef MESO_APP_H
#define MESO_APP_H

#include <meso/meso.h>
#include "meso/runtime.h"

/* ---- Exit statuses ------------------------------------------------------------------------ */

enum {
    APP_EXIT_OK = 0,
    APP_EXIT_FAILURE = 1,   /* the machine's fault: I/O while writing, memory, internal */
    APP_EXIT_BAD_INPUT = 2, /* the user's: usage, malformed or missing input */
};

/* ---- Subcommands -------------------------------------------------------------------------- */

int meso_cmd_render(int argc, char **argv);
int meso_cmd_info(int argc, char **argv);
int meso_cmd_demo(int argc, char **argv);
int meso_cmd_bench(int argc, char **argv);
int meso_cmd_cache(int argc, char **argv);
int meso_cmd_bake(int argc, char **argv);
int meso_cmd_compare(int argc, char **argv); /* app/cmd_compare.c (the compare helper's) */
int meso_cmd_view(int argc, char **argv);    /* app/cmd_view.c: needs SDL2 */
int meso_cmd_sweep(int argc, char **argv);   /* app/cmd_sweep.c */

/* ---- Command-line options ----------------------------------------------------------------- */

typedef enum app_option_type {
    APP_OPTION_FLAG,    /* bool: present or not */
    APP_OPTION_INT,     /* int, within [min, max] */
    APP_OPTION_DOUBLE,  /* double, within [min, max] */
    APP_OPTION_STRING,  /* const char * (points into argv) */
    APP_OPTION_SIZE,    /* app_size: "WxH" */
    APP_OPTION_SETTING, /* app_settings: "technique.option=value", repeatable (--set) */
} app_option_type;

/* Technique options from the command line (--set relief.linear_steps=64), each checked against
 * its technique's option table while parsing; passed on in meso_render_desc.options. */
typedef struct app_settings {
    meso_option items[MESO_OPTIONS_MAX];
    int count;
} app_settings;

/* The --set row of a command's option table, writing into `settings`. */
/* --bits 8|16: the bit depth of the PNGs a command writes (OpenEXR outputs, chosen by an
 * ".exr" extension, are always half floats); app_check_bits says the usage error. */
#define APP_BITS_OPTION(bits)                                                                      \
    {                                                                                              \
        "--bits", NULL, APP_OPTION_INT, (bits), "8|16",                                            \
            "bits a channel of the PNG written (an .exr output is half floats, linear)", "8", 8,   \
            16                                                                                     \
    }
/* -1 when bits is 0 (not given), 8 or 16, else the usage error's exit status. */
int app_check_bits(const char *command, int bits);

/* --filter 0|1 into an int that starts at -1 (not given: the library's default); the mode for a
 * meso_render_desc is app_filter_mode's. */
#define APP_FILTER_OPTION(filter)                                                                  \
    {                                                                                              \
        "--filter", NULL, APP_OPTION_INT, (filter), "0|1",                                         \
            "texture filtering: 0 reads the maps at level 0 at each sample (the papers' images), " \
            "1 mip-maps them by the pixel's footprint (docs/techniques.md#filtering)",             \
            "0", 0, 1                                                                              \
    }
static inline meso_render_filter app_filter_mode(int filter) {
    return filter < 0    ? MESO_RENDER_FILTER_DEFAULT
           : filter == 0 ? MESO_RENDER_FILTER_POINT
                         : MESO_RENDER_FILTER_FOOTPRINT;
}

#define APP_SET_OPTION(settings)                                                                   \
    {                                                                                              \
        "--set", NULL, APP_OPTION_SETTING, (settings), "T.NAME=V",                                 \
            "set technique T's option NAME for every object (repeatable; meso help T lists them)", \
            NULL, 0, 0                                                                             \
    }

typedef struct app_size {
    int width, height; /* 0 x 0: not given */
} app_size;

/* One option of a subcommand. The table of a command drives both parsing and --help, so the
 * two cannot disagree. */
typedef struct app_option {
    const char *name;  /* "--size" */
    const char *alias; /* "-o", or NULL */
    app_option_type type;
    void *target;        /* bool *, int *, double *, const char **, app_size *, app_settings * */
    const char *metavar; /* "WxH" (not for flags) */
    const char *help;    /* one line */
    const char *default_text; /* "the scene's", or NULL for none */
    double min, max;          /* INT and DOUBLE bounds (both 0: no bounds) */
} app_option;

/* Options every subcommand takes. */
typedef struct app_globals {
    int threads;              /* --threads N: 0 = every core */
    bool progress;            /* --progress: the bar even when stderr is not a terminal */
    bool quiet;               /* --quiet: only errors */
    bool verbose;             /* --verbose: the library's info lines too */
    bool help;                /* --help */
    const char *memory_limit; /* --memory-limit SIZE: "4G", "512M", bytes; NULL: the default */
} app_globals;

/* What --help prints about a command, besides its options. */
typedef struct app_command_help {
    const char *name;     /* "render" */
    const char *usage;    /* "SCENE -o OUT.png [options]" */
    const char *summary;  /* paragraph(s) */
    const char *examples; /* lines, each a full command */
} app_command_help;

/* Parse argv[1..argc) of a command: options from `options` (count of them) and the global
 * options; other arguments are collected in positionals (at most max_positionals; the array
 * holds pointers into argv). Returns -1 to go on, or an exit status: 0 after printing --help,
 * 2 after printing a usage error ("meso: render: unknown option '--foo' (see meso render
 * --help)"). */
int app_parse_options(const app_command_help *help, const app_option *options, size_t count,
                      int argc, char **argv, app_globals *globals, const char **positionals,
                      int max_positionals, int *out_num_positionals);

/* Print the command's help (usage, options with defaults, examples) to stdout. */
void app_print_help(const app_command_help *help, const app_option *options, size_t count);

/* Print a technique's summary, paper, what it draws and its option table (meso help T). */
void app_print_technique_help(const meso_technique_info *technique);

/* Print "meso: <command>: <message> (see meso <command> --help)" and return 2. */
int app_usage_error(const char *command, const char *format, ...)
    __attribute__((format(printf, 2, 3)));

/* ---- Context and errors ------------------------------------------------------------------- */

/* A context with the globals' threads and progress mode and a logger printing warnings as
 * "meso: warning: ..." (unless quiet); errors are not printed by the logger but by
 * app_fail. Returns NULL (after printing why) when it cannot be made. */
meso_context *app_context_create(const app_globals *globals);

/* Print "meso: <last error of ctx>" (or the result's phrase when nothing was logged) and
 * return the exit status for `result`. */
int app_fail(meso_context *ctx, meso_result result);
/* The same, naming `file` first when the message does not begin with a file name (errors of
 * the renderer name objects: "meso: scene.json: objects[0]: ..."). */
int app_fail_in(meso_context *ctx, meso_result result, const char *file);
/* Print one error line "meso: <formatted>" to stderr, control characters escaped. */
void app_error(const char *format, ...) __attribute__((format(printf, 1, 2)));
/* A status line on stderr, "meso: <text>", escaped to one line like app_error (an output
 * name with a newline in it cannot forge a second line). */
void app_note(const char *format, ...) __attribute__((format(printf, 1, 2)));

/* The exit status for a result: 0, 2 when meso_result_is_bad_input, else 1. */
int app_exit_status(meso_result result);

/* ---- Small helpers ------------------------------------------------------------------------ */

/* Create a folder and its parents (like mkdir -p). MESO_ERROR_IO (logged) on failure. */
meso_result app_make_dir(meso_context *ctx, const char *path);

/* "dir/name" into out (size out_size); false when it does not fit. */
bool app_path_join(char *out, size_t out_size, const char *dir, const char *name);

/* A file's name without folder and extension ("bricks-plane"): a scene's name in a batch. */
void app_path_stem(const char *path, char *out, size_t size);

/* The extension of a path in lower case without the dot ("png"), "" if none. */
void app_path_extension(const char *path, char *out, size_t out_size);

/* An image output's name checked before any work: it must end in an extension meso writes,
 * .png or (with exr) .exr, in any case: -1 when it does, else one line "meso: <path>: ..."
 * naming the formats `writer` writes ("meso", "meso view") and 2. */
int app_check_image_output(const char *path, bool exr, const char *writer);

/* The median of values (count >= 1); reorders the array. */
double app_median(double *values, size_t count);

/* A growable text buffer for reports (CSV, JSON). */
typedef struct app_text {
    char *data;
    size_t length, capacity;
    bool failed; /* out of memory at some point: the text is incomplete */
} app_text;

void app_text_printf(app_text *text, const char *format, ...) __attribute__((format(printf, 2, 3)));
/* Append s as a JSON string literal (quotes and escapes included). */
void app_text_json_string(app_text *text, const char *s);
/* Append s as XML character data (<, >, & and " escaped; control characters dropped). */
void app_text_xml(app_text *text, const char *s);
/* Append a number as JSON (null for NaN and infinities). */
void app_text_json_number(app_text *text, double value);
/* Write the text atomically to path. */
meso_result app_text_write(meso_context *ctx, const app_text *text, const char *path);
void app_text_free(app_text *text);

/* Whether technique `info` can draw every object of the scene (its accepts vs each object's
 * mesostructure kind). */
bool app_technique_applies(const meso_technique_info *info, const meso_scene *scene);
/* How many objects of the scene technique `info` can draw. */
int app_technique_draws(const meso_technique_info *info, const meso_scene *scene);

/* Whether `name` is a registered technique or "reference". */
bool app_technique_known(const char *name);
/* "flat, bump, ..., reference" into out. */
void app_known_techniques(char *out, size_t out_size);

/* Parse a technique list: "all" (every registered per-pixel and geometry technique, in the
 * registry's order) or names separated by commas. Names must be registered techniques or
 * "reference". Fills names (pointers to static strings or into `list`'s copy in storage, of
 * storage_size bytes) and returns the count, or -1 after printing a usage error for `command`.
 * A name given twice counts once. */
int app_parse_technique_list(const char *command, const char *list, char *storage,
                             size_t storage_size, const char **names, int max_names);

/* The machine: "2 cores, Intel(R) Xeon(R) Processor" (from /proc/cpuinfo). */
void app_machine_description(char *out, size_t out_size);
/* The 1-minute load average (/proc/loadavg), NAN when unknown: above the number of cores,
 * timings are contended by other work. */
double app_load_average(void);

/* ---- The examples built into the program (app_examples.c) -------------------------------- */

/* Parse example `index` of meso_embedded_examples (examples_embedded.h), with the files of
 * examples/assets it reads. */
meso_result app_example_parse(meso_context *ctx, size_t index, meso_scene **out_scene);

/* ---- Render every technique and compare (app_compare_all.c) ------------------------------- */

/* One technique's run of a scene. */
typedef struct app_run {
    char technique[MESO_NAME_MAX];
    bool rendered;  /* false: skipped or failed, see note */
    bool skipped;   /* the technique cannot draw the scene's kind of mesostructure */
    char note[256]; /* why it was skipped or failed; when rendered, "" or which objects of a
                       mixed scene were drawn with their own scene technique */
    double prepare_ms;
    double frame_ms; /* median over the timed frames */
    int frames_timed;
    uint64_t triangles;
    meso_image *color;    /* linear RGB */
    meso_image *coverage; /* grey, 0..1 */
    bool has_metrics;     /* compared against the reference */
    meso_compare_result metrics;
} app_run;

typedef struct app_compare_all_desc {
    const meso_scene *scene;
    int width, height;             /* the size to render at */
    const char *const *techniques; /* NULL: every applicable technique (registry order) */
    int num_techniques;
    bool with_reference;          /* render `reference` first and compare against it */
    int samples;                  /* per technique (0: 1) */
    int reference_samples;        /* for the reference (0: same as samples) */
    int timing_frames;            /* frames timed after the prepare, median taken (0: 5) */
    double timing_budget_seconds; /* stop timing a technique after this long (0: 2 s) */
    meso_progress *progress;      /* advanced by 1 per technique run (may be NULL) */
    const app_settings *settings; /* --set: technique options for every run (may be NULL) */
    meso_render_filter filter;    /* --filter: for every run, the reference's too */
} app_compare_all_desc;

typedef struct app_compare_all {
    app_run *runs; /* the reference first when asked for, then the techniques */
    size_t num_runs;
    int reference;     /* index of the reference run, -1 when not asked for */
    bool reference_ok; /* the reference rendered, so metrics exist */
} app_compare_all;

/* The number of runs app_compare_all_render will make for desc (for progress totals). */
size_t app_compare_all_count(const app_compare_all_desc *desc);

/* Before any work: the sheet of desc's runs (sheet_columns > 0; labels of at most label_lines
 * lines) within the image limits, and the memory the runs' kept images, one frame and the
 * sheet need within the budget. MESO_OK, MESO_ERROR_LIMIT (logged, naming `name`). */
meso_result app_compare_all_check_memory(meso_context *ctx, const app_compare_all_desc *desc,
                                         int sheet_columns, int label_lines, const char *name);

/* Render the scene with each technique (inapplicable ones are kept as skipped runs with a
 * note) and the reference, time them and compare each against the reference's linear image
 * with both coverage masks. A technique that fails (for any reason) is noted in its run, not
 * fatal; the call itself fails only when it cannot allocate its list of runs. */
meso_result app_compare_all_render(meso_context *ctx, const app_compare_all_desc *desc,
                                   app_compare_all *out);
void app_compare_all_free(app_compare_all *all);
/* Compare a rendered run against the rendered reference (linear colour, both coverage masks)
 * into run->metrics, setting has_metrics; nothing when either did not render. */
void app_run_compare(meso_context *ctx, app_run *run, const app_run *reference);

/* Print to stderr why runs did not render: "meso: warning: reference not available (...)",
 * "meso: warning: <technique>: failed: ...", and with show_skipped "meso: note: <technique>:
 * skipped: ...". scene_name (may be NULL) prefixes the technique. */
void app_compare_all_print_notes(const app_compare_all *all, const char *scene_name,
                                 bool show_skipped);

/* The label of a run on a sheet: "technique\nN.N ms  PSNR xx.x dB (covered yy.y)\nSSIM 0.xxx
 * IoU 0.xxx", or one figure a line when cells of cell_width pixels are too narrow for that;
 * with a non-NULL prefix, that line comes first. */
void app_run_label(const app_run *run, const char *prefix, int cell_width, char *out,
                   size_t out_size);

/* Write DIR/<prefix><technique>.png (sRGB) for every rendered run, and with coverage also
 * DIR/<prefix><technique>.coverage.png; remove those two files of every other technique (an
 * earlier run's), so the folder holds what the sheet shows. */
meso_result app_compare_all_write_images(meso_context *ctx, const app_compare_all *all,
                                         const char *dir, const char *prefix, bool coverage);

/* Append the rows of a results table (CSV with a header when text is empty) / a JSON array
 * element per run, naming the scene. */
void app_compare_all_csv(const app_compare_all *all, const char *scene_name, app_text *csv);
void app_compare_all_json(const app_compare_all *all, const char *scene_name, app_text *json,
                          bool *first);

/* Write the plot of a run (app_plot.c) as SVG and PNG: each technique with metrics a labelled
 * point, median frame time (log axis) against covered PSNR, the reference's time a dashed line.
 * Writes nothing, and removes an earlier run's plot, when no technique has metrics (the
 * reference did not render). */
meso_result app_plot_error_vs_time(meso_context *ctx, const app_compare_all *all,
                                   const char *scene_name, const char *path, const char *png_path);

/* One point of an error-vs-time plot. */
typedef struct app_plot_point {
    const char *label; /* drawn beside the point */
    double frame_ms;   /* > 0 */
    double psnr_covered_db;
    int series; /* colour: index into app_plot_desc.series_names (0 with none) */
} app_plot_point;

typedef struct app_plot_desc {
    const char *title;
    const app_plot_point *points;
    size_t num_points;
    double reference_ms; /* the truth's frame time, a dashed line (0: none) */
    /* With a Pareto front: the points no other point beats in both time and error are joined
     * by a staircase and only they are labelled (a sweep has too many points to label all);
     * the series are coloured and named in a legend. */
    bool pareto;
    const char *const *series_names;
    int num_series;
} app_plot_desc;

/* Write an error-vs-time plot as SVG and PNG (atomically). Writes nothing, and removes an
 * earlier plot at `path`, when no point has a finite PSNR. */
meso_result app_plot_write(meso_context *ctx, const app_plot_desc *desc, const char *path,
                           const char *png_path);

/* Whether point i is on the Pareto front of points: no other point is at least as fast and at
 * least as accurate and strictly better in one of the two. */
bool app_plot_on_front(const app_plot_point *points, size_t count, size_t i);

/* A sheet of labelled cells saved as sRGB PNG: images are linear RGB, NULL cells are drawn as
 * empty (background grey). */
meso_result app_sheet_save(meso_context *ctx, const meso_image *const *images,
                           const char *const *labels, size_t count, int columns, const char *path);

#endif
