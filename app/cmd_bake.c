/* meso bake SCENE -o DIR: what each object's shader reads, exported as ordinary textures with a
 * manifest (docs/gpu.md), for the shaders of shaders/ in another engine. */
#include "app.h"

#include <string.h>
#include "meso/runtime.h"

static const app_command_help bake_help = {
    .name = "bake",
    .usage = "SCENE -o DIR [options]",
    .summary =
        "Export what each object's technique reads as files an engine loads without meso, into\n"
        "the folder DIR (made with its parents): heights and colour maps as 16-bit PNG, VDM's\n"
        "SVD tables (weights as half, eigenfunctions as float) as OpenEXR, and manifest.json:\n"
        "per object the technique, its vertex and fragment shader (shaders/), every uniform's\n"
        "value and, per file, the uniform that reads it, its size, format and layout. Bakes come\n"
        "from the bake cache (made when missing); the .mesobake files stay as they are. Objects\n"
        "whose technique has no GL shader are refused (--technique chooses another).",
    .examples = "  meso bake examples/bricks-plane.json -o textures --technique relief\n"
                "  meso bake examples/bricks-plane.json -o vdm --technique vdm "
                "--set vdm.resolution=256\n",
};

int meso_cmd_bake(int argc, char **argv) {
    const char *output = NULL, *technique = NULL;
    app_settings settings = {0};
    const app_option options[] = {
        {"--output", "-o", APP_OPTION_STRING, &output, "DIR", "the folder to write into",
         "required", 0, 0},
        {"--technique", NULL, APP_OPTION_STRING, &technique, "T",
         "export for technique T for every object", "each object's own", 0, 0},
        APP_SET_OPTION(&settings),
    };
    app_globals globals;
    const char *positionals[1];
    int num_positionals = 0;
    int status = app_parse_options(&bake_help, options, sizeof options / sizeof options[0], argc,
                                   argv, &globals, positionals, 1, &num_positionals);
    if (status >= 0) return status;
    if (num_positionals < 1) return app_usage_error("bake", "missing the SCENE file");
    if (!output) return app_usage_error("bake", "missing -o DIR");
    if (technique && !app_technique_known(technique)) {
        char known[1024];
        app_known_techniques(known, sizeof known);
        app_error("%s: --technique: unknown technique '%s' (known: %s)", positionals[0], technique,
                  known);
        return APP_EXIT_BAD_INPUT;
    }
    meso_context *ctx = app_context_create(&globals);
    if (!ctx) return APP_EXIT_FAILURE;
    meso_scene *scene = NULL;
    meso_context_set_subject(ctx, positionals[0]); /* named by a long bake's notice */
    meso_result result = meso_scene_load(ctx, positionals[0], &scene);
    if (result != MESO_OK) {
        status = app_fail(ctx, result);
    } else {
        meso_render_desc desc = {
            .technique = technique, .options = settings.items, .num_options = settings.count};
        /* a technique without a GL shader is a request this command cannot serve: bad input,
         * said before the folder is made */
        result = meso_gl_check_scene(ctx, scene, &desc);
        if (result == MESO_OK) result = app_make_dir(ctx, output);
        if (result == MESO_OK) result = meso_gl_export_textures(ctx, scene, &desc, output);
        status = result == MESO_OK ? APP_EXIT_OK : app_fail_in(ctx, result, scene->path);
        if (result == MESO_OK && !globals.quiet)
            fprintf(stderr, "meso: bake: %d object(s) -> %s/manifest.json\n", scene->num_objects,
                    output);
    }
    meso_scene_destroy(scene);
    meso_context_destroy(ctx);
    return status;
}
