/* The meso program: dispatches `meso CMD ...` to app/cmd_<CMD>.c. */
#include "app.h"

#include <signal.h>
#include <string.h>
#include "meso/runtime.h"

typedef struct command {
    const char *name;
    int (*run)(int argc, char **argv);
    const char *summary;
} command;

static const command commands[] = {
    {"render", meso_cmd_render, "render a scene to PNG, or every technique side by side"},
    {"compare", meso_cmd_compare, "compare images: metrics, difference image, sheet"},
    {"info", meso_cmd_info, "describe a PNG, scene, mesh or bake file"},
    {"demo", meso_cmd_demo, "render the built-in examples with every technique"},
    {"sweep", meso_cmd_sweep, "scenes x techniques x option grids against the truth, sharded"},
    {"bench", meso_cmd_bench, "time techniques per frame, and their thread scaling"},
    {"bake", meso_cmd_bake, "export the textures the GLSL shaders read (docs/gpu.md)"},
    {"cache", meso_cmd_cache, "list, size or clear the bake cache"},
    {"view", meso_cmd_view, "an interactive window: orbit, switch techniques, compare"},
};
#define NUM_COMMANDS (sizeof(commands) / sizeof(commands[0]))

static void print_help(void) {
    printf("meso %s: surface mesostructure rendering on the CPU\n\n"
           "Usage: meso COMMAND [options]\n\nCommands:\n",
           MESO_VERSION_STRING);
    for (size_t i = 0; i < NUM_COMMANDS; i++)
        printf("  %-10s %s\n", commands[i].name, commands[i].summary);
    printf("  %-10s %s\n", "help",
           "the help of a command or a technique (meso help render, "
           "meso help relief)");
    printf("\nGlobal options (every command): --threads N, --progress, --quiet, --verbose, --help\n"
           "Options: meso --help, meso --version\n\n"
           "Examples:\n"
           "  meso demo -o demo\n"
           "  meso render examples/bricks-plane.json -o bricks.png --technique relief\n"
           "  meso render examples/bricks-plane.json --techniques all -o out/bricks\n"
           "  meso info examples/bricks-plane.json\n"
           "  meso bench --frames 10\n\n"
           "Exit status: 0 success, 2 bad input or usage, 1 other failures.\n"
           "Documentation: README.md and docs/cli.md.\n");
}

static const command *find_command(const char *name) {
    for (size_t i = 0; i < NUM_COMMANDS; i++)
        if (!strcmp(commands[i].name, name)) return &commands[i];
    return NULL;
}

/* SIGINT/SIGTERM: remove the temporary files of outputs being written, then die of the signal
 * as if unhandled (the shell sees the usual status). */
static void on_terminating_signal(int signal_number) {
    meso_atomic_file_remove_temporaries();
    signal(signal_number, SIG_DFL);
    raise(signal_number);
}

int main(int argc, char **argv) {
    const int terminating[] = {SIGINT, SIGTERM, SIGHUP};
    for (size_t i = 0; i < sizeof(terminating) / sizeof(terminating[0]); i++) {
        struct sigaction action = {.sa_handler = on_terminating_signal};
        sigaction(terminating[i], &action, NULL);
    }
    if (argc < 2) {
        print_help();
        return APP_EXIT_BAD_INPUT;
    }
    const char *name = argv[1];
    if (!strcmp(name, "--help") || !strcmp(name, "-h")) {
        print_help();
        return APP_EXIT_OK;
    }
    if (!strcmp(name, "--version")) {
        printf("meso %s\n", MESO_VERSION_STRING);
        return APP_EXIT_OK;
    }
    if (!strcmp(name, "help")) {
        if (argc < 3) {
            print_help();
            return APP_EXIT_OK;
        }
        const command *c = find_command(argv[2]);
        const meso_technique_info *technique = meso_technique_find(argv[2]);
        if (!c && technique) {
            app_print_technique_help(technique);
            return APP_EXIT_OK;
        }
        if (!c)
            return app_usage_error(NULL, "help: '%s' is neither a command nor a technique",
                                   argv[2]);
        char *help_argv[] = {argv[2], "--help", NULL};
        return c->run(2, help_argv);
    }
    const command *c = find_command(name);
    if (!c) {
        if (name[0] == '-') return app_usage_error(NULL, "unknown option '%s'", name);
        return app_usage_error(NULL, "unknown command '%s'", name);
    }
    return c->run(argc - 1, argv + 1);
}
