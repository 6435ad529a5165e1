/* What the subcommands of the meso program share: option parsing and --help from one table,
 * the context and its logger, exit statuses, paths, text reports, technique lists. */
#include "app.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include "meso/runtime.h"

/* ---- Options ------------------------------------------------------------------------------ */

/* The options every subcommand takes, appended to each command's table. */
static size_t global_options(app_globals *g, app_option *out) {
    const app_option options[] = {
        {"--threads", NULL, APP_OPTION_INT, &g->threads, "N", "worker threads, 0 = every core", "0",
         0, 4096},
        {"--progress", NULL, APP_OPTION_FLAG, &g->progress, NULL,
         "show the progress bar even when stderr is not a terminal", NULL, 0, 0},
        {"--quiet", NULL, APP_OPTION_FLAG, &g->quiet, NULL,
         "no summary, notes, warnings or progress bar on stderr (errors still)", NULL, 0, 0},
        {"--verbose", "-v", APP_OPTION_FLAG, &g->verbose, NULL,
         "also print the library's information lines (triangle counts, memory, bake times)", NULL,
         0, 0},
        {"--memory-limit", NULL, APP_OPTION_STRING, &g->memory_limit, "SIZE",
         "refuse work estimated to need more memory (bytes, or with K, M, G, T)", "3/4 of RAM", 0,
         0},
        {"--help", "-h", APP_OPTION_FLAG, &g->help, NULL, "print this help and exit", NULL, 0, 0},
    };
    memcpy(out, options, sizeof(options));
    return sizeof(options) / sizeof(options[0]);
}

int app_usage_error(const char *command, const char *format, ...) {
    char message[1024];
    va_list args;
    va_start(args, format);
    vsnprintf(message, sizeof(message), format, args);
    va_end(args);
    if (command && command[0])
        app_error("%s: %s (see meso %s --help)", command, message, command);
    else
        app_error("%s (see meso --help)", message);
    return APP_EXIT_BAD_INPUT;
}

int app_check_bits(const char *command, int bits) {
    if (bits == 0 || bits == 8 || bits == 16) return -1;
    return app_usage_error(command, "--bits: %d is not 8 or 16", bits);
}

/* Print text from column `indent` (already reached), breaking lines at spaces before `width`. */
static void print_wrapped(const char *text, int indent, int width) {
    int column = indent;
    while (*text) {
        size_t word = strcspn(text, " ");
        if (column > indent && column + 1 + (int)word > width) {
            printf("\n%*s", indent, "");
            column = indent;
        } else if (column > indent) {
            putchar(' ');
            column++;
        }
        printf("%.*s", (int)word, text);
        column += (int)word;
        text += word;
        while (*text == ' ') text++;
    }
    putchar('\n');
}

static void print_option_table(const app_option *options, size_t count) {
    for (size_t i = 0; i < count; i++) {
        const app_option *o = &options[i];
        char left[96];
        int n = 0;
        if (o->alias)
            n = snprintf(left, sizeof(left), "%s, %s", o->alias, o->name);
        else
            n = snprintf(left, sizeof(left), "    %s", o->name);
        if (o->metavar && n > 0 && (size_t)n < sizeof(left))
            snprintf(left + n, sizeof(left) - (size_t)n, " %s", o->metavar);
        char text[512];
        if (o->default_text && !strcmp(o->default_text, "required"))
            snprintf(text, sizeof(text), "%s (required)", o->help);
        else if (o->default_text)
            snprintf(text, sizeof(text), "%s (default: %s)", o->help, o->default_text);
        else
            snprintf(text, sizeof(text), "%s", o->help);
        printf("  %-30s ", left);
        print_wrapped(text, 33, 96);
    }
}

void app_print_help(const app_command_help *help, const app_option *options, size_t count) {
    app_globals unused = {0};
    app_option globals[8];
    size_t num_globals = global_options(&unused, globals);
    printf("Usage: meso %s %s\n\n%s\n", help->name, help->usage, help->summary);
    if (count > 0) {
        printf("\nOptions:\n");
        print_option_table(options, count);
    }
    printf("\nGlobal options:\n");
    print_option_table(globals, num_globals);
    if (help->examples) printf("\nExamples:\n%s", help->examples);
    printf("\nExit status: 0 success, 2 bad input or usage, 1 other failures.\n");
}

void app_print_technique_help(const meso_technique_info *t) {
    static const char *const type_names[] = {"integer", "boolean", "number"};
    printf("%s: %s\nPaper: %s\nDraws: ", t->name, t->summary, t->paper);
    const char *separator = "";
    const char *kinds[] = {"plain meshes", "height fields", "solids that tile",
                           "models' solids (impostors)"};
    const unsigned bits[] = {MESO_TECHNIQUE_ACCEPTS_NONE, MESO_TECHNIQUE_ACCEPTS_HEIGHT_FIELD,
                             MESO_TECHNIQUE_ACCEPTS_SOLID, MESO_TECHNIQUE_ACCEPTS_MODEL_SOLID};
    for (int k = 0; k < 4; k++) {
        if (!(t->accepts & bits[k])) continue;
        printf("%s%s", separator, kinds[k]);
        separator = ", ";
    }
    printf("\n\n");
    if (t->num_options == 0) {
        printf("It has no options.\n");
        return;
    }
    printf("Options (scene: \"technique_options\": {\"%s\": {\"NAME\": V}}; command line:\n"
           "--set %s.NAME=V on render, bench and demo):\n\n",
           t->name, t->name);
    printf("  %-20s %-8s %-14s %-8s %s\n", "name", "type", "range", "default", "meaning");
    for (size_t i = 0; i < t->num_options; i++) {
        const meso_technique_option *o = &t->options[i];
        char range[48], fallback[24];
        if (o->type == MESO_OPTION_BOOL) {
            snprintf(range, sizeof range, "true, false");
            snprintf(fallback, sizeof fallback, "%s", o->default_value != 0.0 ? "true" : "false");
        } else {
            snprintf(range, sizeof range, o->type == MESO_OPTION_INT ? "%g..%g" : "[%g, %g]",
                     o->min, o->max);
            snprintf(fallback, sizeof fallback, "%g", o->default_value);
        }
        printf("  %-20s %-8s %-14s %-8s ", o->name, type_names[o->type], range, fallback);
        print_wrapped(o->doc, 56, 100);
    }
}

static const app_option *find_option(const app_option *options, size_t count, const char *arg,
                                     size_t arg_length) {
    for (size_t i = 0; i < count; i++) {
        const char *names[2] = {options[i].name, options[i].alias};
        for (int k = 0; k < 2; k++)
            if (names[k] && strlen(names[k]) == arg_length && !strncmp(names[k], arg, arg_length))
                return &options[i];
    }
    return NULL;
}

static bool parse_int(const char *text, long long *out) {
    char *end = NULL;
    errno = 0;
    long long v = strtoll(text, &end, 10);
    if (errno || end == text || *end) return false;
    *out = v;
    return true;
}

static bool parse_size(const char *text, app_size *out) {
    char *end = NULL;
    errno = 0;
    long w = strtol(text, &end, 10);
    if (errno || end == text || (*end != 'x' && *end != 'X')) return false;
    const char *rest = end + 1;
    long h = strtol(rest, &end, 10);
    if (errno || end == rest || *end) return false;
    if (w < 1 || h < 1 || w > MESO_IMAGE_MAX_SIDE || h > MESO_IMAGE_MAX_SIDE) return false;
    if ((unsigned long long)w * (unsigned long long)h > MESO_IMAGE_MAX_PIXELS) return false;
    out->width = (int)w;
    out->height = (int)h;
    return true;
}

/* "relief.linear_steps=64" (the value a number, true or false) into the settings, checked
 * against the technique's option table; a usage error when it does not fit. */
static int add_setting(const char *command, const app_option *o, const char *text) {
    app_settings *settings = o->target;
    const char *dot = strchr(text, '.'), *equals = strchr(text, '=');
    if (!dot || !equals || dot > equals || dot == text || equals == dot + 1)
        return app_usage_error(command, "%s: '%s' is not TECHNIQUE.OPTION=VALUE", o->name, text);
    if (settings->count >= MESO_OPTIONS_MAX)
        return app_usage_error(command, "%s: more than %d settings", o->name, MESO_OPTIONS_MAX);
    meso_option setting = {0};
    if ((size_t)(dot - text) >= sizeof setting.technique ||
        (size_t)(equals - dot - 1) >= sizeof setting.name)
        return app_usage_error(command, "%s: '%s': name too long", o->name, text);
    memcpy(setting.technique, text, (size_t)(dot - text));
    memcpy(setting.name, dot + 1, (size_t)(equals - dot - 1));
    const char *value = equals + 1;
    char *end = NULL;
    if (!strcmp(value, "true")) {
        setting.value = 1.0;
    } else if (!strcmp(value, "false")) {
        setting.value = 0.0;
    } else {
        setting.value = strtod(value, &end);
        if (end == value || *end || !isfinite(setting.value))
            return app_usage_error(command, "%s %s: '%s' is not a number, true or false", o->name,
                                   text, value);
    }
    /* The library checks it against the table; a scratch context carries the message. */
    meso_context *scratch = NULL;
    if (meso_context_create(NULL, &scratch) != MESO_OK) {
        fprintf(stderr, "meso: out of memory\n");
        return APP_EXIT_FAILURE;
    }
    char where[192];
    snprintf(where, sizeof where, "%s %s.%s", o->name, setting.technique, setting.name);
    meso_result r =
        meso_technique_check_option(scratch, setting.technique, setting.name, setting.value, where);
    int status =
        r == MESO_OK ? -1 : app_usage_error(command, "%s", meso_context_last_error(scratch));
    meso_context_destroy(scratch);
    if (status >= 0) return status;
    int slot = 0; /* a later --set of the same option replaces the earlier */
    while (slot < settings->count &&
           !(strcmp(settings->items[slot].technique, setting.technique) == 0 &&
             strcmp(settings->items[slot].name, setting.name) == 0))
        slot++;
    settings->items[slot] = setting;
    if (slot == settings->count) settings->count++;
    return -1;
}

/* Store `value` into the option's target; a usage error (status 2) when it does not parse. */
static int set_option(const char *command, const app_option *o, const char *value) {
    bool bounded = o->min != 0.0 || o->max != 0.0;
    switch (o->type) {
    case APP_OPTION_FLAG:
        *(bool *)o->target = true;
        return -1;
    case APP_OPTION_SETTING:
        return add_setting(command, o, value);
    case APP_OPTION_STRING:
        *(const char **)o->target = value;
        return -1;
    case APP_OPTION_SIZE:
        if (!parse_size(value, (app_size *)o->target))
            return app_usage_error(command,
                                   "%s: '%s' is not a size WxH with sides in 1..%d and at most "
                                   "%u pixels",
                                   o->name, value, MESO_IMAGE_MAX_SIDE, MESO_IMAGE_MAX_PIXELS);
        return -1;
    case APP_OPTION_INT: {
        long long v = 0;
        if (!parse_int(value, &v) || (bounded && (v < (long long)o->min || v > (long long)o->max)))
            return app_usage_error(command, "%s: '%s' is not an integer in %.0f..%.0f", o->name,
                                   value, o->min, o->max);
        *(int *)o->target = (int)v;
        return -1;
    }
    case APP_OPTION_DOUBLE: {
        char *end = NULL;
        double v = strtod(value, &end);
        if (end == value || *end || !isfinite(v) || (bounded && (v < o->min || v > o->max)))
            return app_usage_error(command, "%s: '%s' is not a number in %g..%g", o->name, value,
                                   o->min, o->max);
        *(double *)o->target = v;
        return -1;
    }
    }
    return -1;
}

/* "4G", "512M", "1.5G" or bytes -> bytes; 0 when malformed. */
static uint64_t parse_memory_size(const char *text) {
    char *end = NULL;
    double value = strtod(text, &end);
    if (end == text || !isfinite(value) || value <= 0.0) return 0;
    static const char units[] = "KMGT";
    const char *unit = *end ? strchr(units, *end == 'k' ? 'K' : *end) : NULL;
    if (*end && (!unit || end[1])) return 0;
    if (unit)
        for (const char *u = units; u <= unit; u++) value *= 1024.0;
    return value >= 1.0 && value < 1.8e19 ? (uint64_t)value : 0;
}

int app_parse_options(const app_command_help *help, const app_option *options, size_t count,
                      int argc, char **argv, app_globals *globals, const char **positionals,
                      int max_positionals, int *out_num_positionals) {
    *out_num_positionals = 0;
    *globals = (app_globals){0};
    app_option all[64];
    size_t num_all = 0;
    for (size_t i = 0; i < count && num_all < 56; i++) all[num_all++] = options[i];
    num_all += global_options(globals, all + num_all);

    const char *command = help->name;
    bool only_positionals = false;
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i];
        if (only_positionals || arg[0] != '-' || arg[1] == 0) {
            if (*out_num_positionals >= max_positionals)
                return app_usage_error(command, "unexpected argument '%s'", arg);
            positionals[(*out_num_positionals)++] = arg;
            continue;
        }
        if (!strcmp(arg, "--")) {
            only_positionals = true;
            continue;
        }
        /* --name=value, and -o=value for a one-letter alias (-o=x is -o x, not -o "=x"). */
        const char *equals = strncmp(arg, "--", 2) == 0 ? strchr(arg, '=')
                             : arg[2] == '='            ? arg + 2
                                                        : NULL;
        size_t name_length = equals ? (size_t)(equals - arg) : strlen(arg);
        const app_option *o = find_option(all, num_all, arg, name_length);
        if (!o) return app_usage_error(command, "unknown option '%.*s'", (int)name_length, arg);
        const char *value = NULL;
        if (o->type == APP_OPTION_FLAG) {
            if (equals) return app_usage_error(command, "%s takes no value", o->name);
        } else if (equals) {
            value = equals + 1;
        } else {
            if (i + 1 >= argc)
                return app_usage_error(command, "%s needs a value %s", o->name, o->metavar);
            value = argv[++i];
        }
        int status = set_option(command, o, value);
        if (status >= 0) return status;
    }
    if (globals->help) {
        app_print_help(help, options, count);
        return APP_EXIT_OK;
    }
    if (globals->memory_limit && parse_memory_size(globals->memory_limit) == 0)
        return app_usage_error(command, "--memory-limit: '%s' is not a size (4G, 512M, bytes)",
                               globals->memory_limit);
    return -1;
}

/* ---- Context and errors ------------------------------------------------------------------- */

static void log_to_stderr(void *user, meso_log_level level, const char *message) {
    const app_globals *g = user;
    /* Errors are printed once, by app_fail, from the context's last error. */
    if (level == MESO_LOG_WARNING && !g->quiet) fprintf(stderr, "meso: warning: %s\n", message);
    if (level == MESO_LOG_INFO && g->verbose && !g->quiet) fprintf(stderr, "meso: %s\n", message);
}

meso_context *app_context_create(const app_globals *globals) {
    /* The logger reads only `quiet` and `verbose`, which are fixed for the program's life. */
    static app_globals logger_globals;
    logger_globals = *globals;
    meso_context_desc desc = {
        .num_threads = globals->threads,
        .log = log_to_stderr,
        .log_user = &logger_globals,
        .progress = globals->quiet      ? MESO_PROGRESS_NEVER
                    : globals->progress ? MESO_PROGRESS_ALWAYS
                                        : MESO_PROGRESS_DEFAULT,
    };
    if (globals->memory_limit) {
        desc.memory_limit = parse_memory_size(globals->memory_limit);
    }
    meso_context *ctx = NULL;
    if (meso_context_create(&desc, &ctx) != MESO_OK) {
        fprintf(stderr, "meso: out of memory\n");
        return NULL;
    }
    return ctx;
}

int app_exit_status(meso_result result) {
    if (result == MESO_OK) return APP_EXIT_OK;
    return meso_result_is_bad_input(result) ? APP_EXIT_BAD_INPUT : APP_EXIT_FAILURE;
}

static void print_line(const char *format, va_list args) {
    char message[2048], escaped[4 * sizeof(message)];
    vsnprintf(message, sizeof(message), format, args);
    /* One line whatever the arguments hold (a newline in a file name, a terminal escape). */
    meso_text_escape_controls(message, escaped, sizeof(escaped));
    fprintf(stderr, "meso: %s\n", escaped);
}

void app_error(const char *format, ...) {
    va_list args;
    va_start(args, format);
    print_line(format, args);
    va_end(args);
}

void app_note(const char *format, ...) {
    va_list args;
    va_start(args, format);
    print_line(format, args);
    va_end(args);
}

/* Whether a message already begins with `file` ("scene.json: ..."). Anything else is prefixed
 * with it, so that the first field is always the file: an object named "x.json" or "a/b"
 * cannot stand in for the scene. */
static bool begins_with_file(const char *message, const char *file) {
    size_t length = strlen(file);
    return strncmp(message, file, length) == 0 && message[length] == ':';
}

int app_fail_in(meso_context *ctx, meso_result result, const char *file) {
    const char *message = ctx ? meso_context_last_error(ctx) : "";
    if (!message || !message[0]) message = meso_result_string(result);
    if (file && !begins_with_file(message, file))
        app_error("%s: %s", file, message);
    else
        app_error("%s", message);
    return result == MESO_OK ? APP_EXIT_FAILURE : app_exit_status(result);
}

int app_fail(meso_context *ctx, meso_result result) { return app_fail_in(ctx, result, NULL); }

/* ---- Paths -------------------------------------------------------------------------------- */

meso_result app_make_dir(meso_context *ctx, const char *path) {
    char buffer[4096];
    if (snprintf(buffer, sizeof(buffer), "%s", path) >= (int)sizeof(buffer))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: path too long", path);
    for (char *p = buffer + 1;; p++) {
        if (*p == '/' || *p == 0) {
            char saved = *p;
            *p = 0;
            if (mkdir(buffer, 0755) != 0 && errno != EEXIST)
                return meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot create folder: %s", buffer,
                                      strerror(errno));
            *p = saved;
            if (saved == 0) break;
        }
    }
    struct stat st;
    if (stat(path, &st) != 0 || !S_ISDIR(st.st_mode))
        return meso_log_error(ctx, MESO_ERROR_IO, "%s: not a folder", path);
    return MESO_OK;
}

bool app_path_join(char *out, size_t out_size, const char *dir, const char *name) {
    size_t n = strlen(dir);
    const char *separator = n > 0 && dir[n - 1] != '/' ? "/" : "";
    int written = snprintf(out, out_size, "%s%s%s", dir, separator, name);
    return written >= 0 && (size_t)written < out_size;
}

void app_path_stem(const char *path, char *out, size_t size) {
    const char *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path;
    const char *dot = strrchr(base, '.');
    size_t length = dot && dot != base ? (size_t)(dot - base) : strlen(base);
    snprintf(out, size, "%.*s", (int)length, base);
}

void app_path_extension(const char *path, char *out, size_t out_size) {
    const char *slash = strrchr(path, '/');
    const char *dot = strrchr(slash ? slash + 1 : path, '.');
    size_t i = 0;
    if (dot && dot[1])
        for (const char *p = dot + 1; *p && i + 1 < out_size; p++)
            out[i++] = (char)((*p >= 'A' && *p <= 'Z') ? *p - 'A' + 'a' : *p);
    out[i] = 0;
}

static int compare_doubles(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int app_check_image_output(const char *path, bool exr, const char *writer) {
    char extension[16];
    app_path_extension(path, extension, sizeof extension);
    if (!strcmp(extension, "png") || (exr && !strcmp(extension, "exr"))) return -1;
    const char *formats = exr ? ".png and .exr" : ".png";
    if (extension[0])
        app_error("%s: cannot write .%s images (%s writes %s)", path, extension, writer, formats);
    else
        app_error("%s: no image extension (%s writes %s)", path, writer, formats);
    return APP_EXIT_BAD_INPUT;
}

double app_median(double *values, size_t count) {
    qsort(values, count, sizeof(double), compare_doubles);
    return count % 2 ? values[count / 2] : 0.5 * (values[count / 2 - 1] + values[count / 2]);
}

/* ---- Text reports ------------------------------------------------------------------------- */

void app_text_printf(app_text *text, const char *format, ...) {
    if (text->failed) return;
    va_list args;
    va_start(args, format);
    va_list copy;
    va_copy(copy, args);
    int n = vsnprintf(NULL, 0, format, copy);
    va_end(copy);
    if (n < 0) {
        text->failed = true;
        va_end(args);
        return;
    }
    size_t need = text->length + (size_t)n + 1;
    if (need > text->capacity) {
        size_t capacity = text->capacity ? text->capacity : 1024;
        while (capacity < need) capacity *= 2;
        char *data = realloc(text->data, capacity);
        if (!data) {
            text->failed = true;
            va_end(args);
            return;
        }
        text->data = data;
        text->capacity = capacity;
    }
    vsnprintf(text->data + text->length, text->capacity - text->length, format, args);
    text->length += (size_t)n;
    va_end(args);
}

void app_text_json_string(app_text *text, const char *s) {
    app_text_printf(text, "\"");
    for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
        if (*p == '"' || *p == '\\')
            app_text_printf(text, "\\%c", *p);
        else if (*p == '\n')
            app_text_printf(text, "\\n");
        else if (*p < 0x20)
            app_text_printf(text, "\\u%04x", *p);
        else
            app_text_printf(text, "%c", *p);
    }
    app_text_printf(text, "\"");
}

void app_text_xml(app_text *text, const char *s) {
    for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
        if (*p == '<')
            app_text_printf(text, "&lt;");
        else if (*p == '>')
            app_text_printf(text, "&gt;");
        else if (*p == '&')
            app_text_printf(text, "&amp;");
        else if (*p == '"')
            app_text_printf(text, "&quot;");
        else if (*p >= 0x20 || *p == '\t')
            app_text_printf(text, "%c", *p);
    }
}

void app_text_json_number(app_text *text, double value) {
    /* Whole numbers (counts such as triangles) as integers, never 2.09715e+06: exact up to
     * 2^53, where doubles stop holding every integer. */
    if (isfinite(value) && value == floor(value) && fabs(value) < 9007199254740992.0)
        app_text_printf(text, "%.0f", value);
    else if (isfinite(value))
        app_text_printf(text, "%.6g", value);
    else
        app_text_printf(text, "null");
}

meso_result app_text_write(meso_context *ctx, const app_text *text, const char *path) {
    if (text->failed)
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", path);
    return meso_file_write_atomic(ctx, path, text->data ? text->data : "", text->length);
}

void app_text_free(app_text *text) {
    free(text->data);
    *text = (app_text){0};
}

/* ---- Techniques and the machine ----------------------------------------------------------- */

bool app_technique_applies(const meso_technique_info *info, const meso_scene *scene) {
    return app_technique_draws(info, scene) == scene->num_objects;
}

int app_technique_draws(const meso_technique_info *info, const meso_scene *scene) {
    int count = 0;
    for (int i = 0; i < scene->num_objects; i++)
        count += meso_technique_accepts(info, &scene->objects[i].mesostructure);
    return count;
}

static void list_known_techniques(char *out, size_t out_size) {
    size_t used = 0;
    out[0] = 0;
    for (size_t i = 0; i < meso_technique_count() && used < out_size; i++) {
        int n = snprintf(out + used, out_size - used, "%s%s", used ? ", " : "",
                         meso_technique_get(i)->name);
        if (n < 0) break;
        used += (size_t)n;
    }
    if (!meso_technique_find("reference") && used < out_size)
        snprintf(out + used, out_size - used, "%sreference", used ? ", " : "");
}

bool app_technique_known(const char *name) {
    return meso_technique_find(name) != NULL || !strcmp(name, "reference");
}

void app_known_techniques(char *out, size_t out_size) { list_known_techniques(out, out_size); }

int app_parse_technique_list(const char *command, const char *list, char *storage,
                             size_t storage_size, const char **names, int max_names) {
    int count = 0;
    if (!strcmp(list, "all")) {
        for (size_t i = 0; i < meso_technique_count() && count < max_names; i++) {
            const meso_technique_info *info = meso_technique_get(i);
            if (info->kind != MESO_TECHNIQUE_REFERENCE) names[count++] = info->name;
        }
        return count;
    }
    if (snprintf(storage, storage_size, "%s", list) >= (int)storage_size)
        return app_usage_error(command, "--techniques: list too long"), -1;
    for (char *save = NULL, *name = strtok_r(storage, ",", &save); name;
         name = strtok_r(NULL, ",", &save)) {
        if (!app_technique_known(name)) {
            char known[1024];
            list_known_techniques(known, sizeof(known));
            app_usage_error(command, "--techniques: unknown technique '%s' (known: %s)", name,
                            known);
            return -1;
        }
        bool repeated = false; /* relief,relief renders once */
        for (int k = 0; k < count && !repeated; k++) repeated = strcmp(names[k], name) == 0;
        if (repeated) continue;
        if (count >= max_names) {
            app_usage_error(command, "--techniques: more than %d techniques", max_names);
            return -1;
        }
        names[count++] = name;
    }
    if (count == 0) {
        app_usage_error(command, "--techniques: empty list");
        return -1;
    }
    return count;
}

void app_machine_description(char *out, size_t out_size) {
    char model[256] = "unknown CPU";
    FILE *f = fopen("/proc/cpuinfo", "r");
    if (f) {
        char line[512];
        while (fgets(line, sizeof(line), f)) {
            if (strncmp(line, "model name", 10) != 0) continue;
            const char *colon = strchr(line, ':');
            if (!colon) continue;
            colon++;
            while (*colon == ' ' || *colon == '\t') colon++;
            snprintf(model, sizeof(model), "%s", colon);
            model[strcspn(model, "\n")] = 0;
            break;
        }
        fclose(f);
    }
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    /* the techniques' instruction set: a portable build picks it at run time */
    snprintf(out, out_size, "%ld cores, %s, techniques %s", cores, model, meso_technique_isa());
}

double app_load_average(void) {
    double load = NAN;
    FILE *f = fopen("/proc/loadavg", "r");
    if (f) {
        if (fscanf(f, "%lf", &load) != 1) load = NAN;
        fclose(f);
    }
    return load;
}
