/* meso info: describe a PNG, a scene, a mesh or a bake file, found by content and extension. */
#include "app.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include "meso/runtime.h"
#include "meso/prism.h"
#include "meso/texture.h"

static const app_command_help info_help = {
    .name = "info",
    .usage = "FILE [options]",
    .summary =
        "Describe FILE on stdout, by its content and extension:\n"
        "  PNG          size, channels, bit depth and colour type, value range per channel\n"
        "  scene .json  image, camera, lights, objects (mesh counts, bounds, material,\n"
        "               mesostructure kind/source/depth, whether its shell folds,\n"
        "               technique and its options)\n"
        "  mesh         .obj .ply .gltf .glb: vertices, triangles, UVs, bounds\n"
        "  .mesobake    kind, version, source hash, parameters, arrays with shapes and sizes\n"
        "A file that does not load is reported as by every command (exit status 2).",
    .examples = "  meso info examples/bricks-plane.json\n"
                "  meso info bricks.png\n",
};

typedef enum file_kind { FILE_UNKNOWN, FILE_PNG, FILE_SCENE, FILE_MESH, FILE_BAKE } file_kind;

static void print_vec3(const char *name, meso_vec3 v) {
    printf("%s(%g, %g, %g)", name, v.x, v.y, v.z);
}

static file_kind detect_kind(const unsigned char *head, size_t size, const char *extension) {
    static const unsigned char png_signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    if (size >= 8 && !memcmp(head, png_signature, 8)) return FILE_PNG;
    if (size >= 8 && !memcmp(head, "MESOBAKE", 8)) return FILE_BAKE; /* docs/bake-format.md */
    if (!strcmp(extension, "png")) return FILE_PNG; /* the loader says what is wrong with it */
    if (!strcmp(extension, "mesobake")) return FILE_BAKE;
    if (!strcmp(extension, "obj") || !strcmp(extension, "ply") || !strcmp(extension, "gltf") ||
        !strcmp(extension, "glb"))
        return FILE_MESH;
    if (!strcmp(extension, "json")) return FILE_SCENE;
    for (size_t i = 0; i < size; i++) {
        if (head[i] == ' ' || head[i] == '\t' || head[i] == '\r' || head[i] == '\n') continue;
        return head[i] == '{' ? FILE_SCENE : FILE_UNKNOWN;
    }
    return FILE_UNKNOWN;
}

static const char *png_color_type(int type) {
    switch (type) {
    case 0:
        return "grey";
    case 2:
        return "RGB";
    case 3:
        return "palette";
    case 4:
        return "grey+alpha";
    case 6:
        return "RGBA";
    default:
        return "unknown";
    }
}

static meso_result info_png(meso_context *ctx, const char *path, const unsigned char *head,
                            size_t head_size) {
    meso_image *image = NULL;
    meso_result result = meso_image_load_png(ctx, path, &image);
    if (result != MESO_OK) return result;
    printf("PNG: %s\n", path);
    printf("size: %dx%d, %d channel%s\n", image->width, image->height, image->channels,
           image->channels == 1 ? "" : "s");
    /* IHDR is the first chunk (the loader checked): bit depth at byte 24, colour type at 25. */
    if (head_size >= 26)
        printf("file: %d-bit %s, loaded as floats in [0, 1]\n", head[24], png_color_type(head[25]));
    static const char *const channel_names[4][4] = {
        {"grey"}, {"grey", "alpha"}, {"red", "green", "blue"}, {"red", "green", "blue", "alpha"}};
    size_t pixels = (size_t)image->width * (size_t)image->height;
    for (int c = 0; c < image->channels; c++) {
        double lo = INFINITY, hi = -INFINITY, sum = 0.0;
        for (size_t i = 0; i < pixels; i++) {
            double v = image->pixels[i * (size_t)image->channels + (size_t)c];
            lo = v < lo ? v : lo;
            hi = v > hi ? v : hi;
            sum += v;
        }
        printf("%-6s min %.4f  max %.4f  mean %.4f\n", channel_names[image->channels - 1][c], lo,
               hi, sum / (double)pixels);
    }
    meso_image_destroy(image);
    return MESO_OK;
}

static void print_mesh(const meso_mesh *mesh, const char *indent) {
    meso_vec3 lo, hi;
    meso_mesh_bounds(mesh, &lo, &hi);
    printf("%s%zu vertices, %zu triangles, UVs %s, tangents %s\n", indent, mesh->num_vertices,
           mesh->num_triangles, mesh->uvs ? "yes" : "no", mesh->tangents ? "yes" : "no");
    printf("%sbounds ", indent);
    print_vec3("", lo);
    print_vec3(" .. ", hi);
    printf("\n");
}

static meso_result info_mesh(meso_context *ctx, const char *path) {
    meso_mesh *mesh = NULL;
    meso_mesh_material material;
    meso_result result = meso_mesh_load_with_material(ctx, path, &mesh, &material);
    if (result == MESO_OK) result = meso_mesh_validate(ctx, mesh, path, false);
    if (result == MESO_OK) {
        printf("mesh: %s\n", path);
        print_mesh(mesh, "");
        /* what a scene does with them (docs/scene-format.md, "uv_projection") */
        size_t degenerate = 0;
        double degenerate_area = 0.0;
        meso_mesh_degenerate_uvs(mesh, &degenerate, &degenerate_area);
        if (!mesh->uvs)
            printf("texture coordinates: none (a scene projects them: \"uv_projection\", "
                   "\"box\" unless it says otherwise)\n");
        else if (degenerate_area > MESO_MESH_MOSTLY_DEGENERATE_UVS)
            printf("texture coordinates: degenerate on %zu of %zu triangles (%.1f %% of the "
                   "area): a scene treats them as none (\"uv_projection\")\n",
                   degenerate, mesh->num_triangles, 100.0 * degenerate_area);
        else if (degenerate)
            printf("texture coordinates: the file's, degenerate on %zu of %zu triangles (%.1f %% "
                   "of the area)\n",
                   degenerate, mesh->num_triangles, 100.0 * degenerate_area);
        else
            printf("texture coordinates: the file's\n");
        /* what a scene using this file would take from it (docs/scene-format.md) */
        printf("material:");
        if (material.has_color)
            printf(" base colour %g %g %g,", material.color.x, material.color.y, material.color.z);
        /* as the scene loader decides (meso_mesh_material_unused_reason) */
        const char *unused = meso_mesh_material_unused_reason(material.color_map);
        if (material.color_map[0] && unused)
            printf(" colour texture %s (not used: %s),", material.color_map, unused);
        else if (material.color_map[0])
            printf(" colour texture %s,", material.color_map);
        unused = meso_mesh_material_unused_reason(material.normal_map);
        if (material.normal_map[0] && unused)
            printf(" normal texture %s (not used: %s),", material.normal_map, unused);
        else if (material.normal_map[0])
            printf(" normal texture %s (used as the normal map, OpenGL convention, when the "
                   "scene's material sets none),",
                   material.normal_map);
        if (!material.has_color && !material.color_map[0] && !material.normal_map[0])
            printf(" none,");
        printf(" ignored: %s\n", material.ignored[0] ? material.ignored : "nothing");
    }
    meso_mesh_destroy(mesh);
    return result;
}

static void print_mesostructure(const meso_mesostructure *m) {
    const char *wrap = m->wrap == MESO_WRAP_CLAMP ? "clamp" : "repeat";
    switch (m->kind) {
    case MESO_MESOSTRUCTURE_NONE:
        printf("      mesostructure: none\n");
        break;
    case MESO_MESOSTRUCTURE_HEIGHT_FIELD:
        printf("      mesostructure: height field '%s'", m->source);
        if (m->height_field)
            printf(", %dx%d texels", m->height_field->width, m->height_field->height);
        printf(", depth %g, wrap %s", m->depth, wrap);
        if (m->offset != 0.0f) printf(", mesh moved %g along its normals (\"height\")", m->offset);
        printf("\n");
        break;
    case MESO_MESOSTRUCTURE_SOLID:
        printf("      mesostructure: solid '%s'", m->source);
        if (m->solid) {
            meso_solid_desc d = meso_solid_get_desc(m->solid);
            printf(" (%s, count %d, thickness %g)", meso_solid_kind_name(d.kind), d.count,
                   d.thickness);
        }
        printf(", depth %g, wrap %s\n", m->depth, wrap);
        break;
    }
}

/* Whether the object's shell folds: where it is deeper than the surface's radius of curvature
 * across a triangle, its prism turns over (meso_prism_layer.num_folded). The techniques and the
 * reference disagree there, so a user choosing a depth should know (docs/techniques/gdm.md,
 * "Folded prisms"). Silent when the layer cannot be made (no UVs: nothing draws a shell). */
static void print_shell_folds(meso_context *ctx, const meso_object *o) {
    if (o->mesostructure.kind == MESO_MESOSTRUCTURE_NONE || !o->mesh || !o->mesh->uvs) return;
    meso_prism_layer *layer = NULL;
    if (meso_prism_layer_create(ctx, o->mesh, o->mesostructure.depth, o->name, &layer) != MESO_OK)
        return;
    if (layer->num_folded)
        printf("      shell: folds on %zu of %zu prisms (deeper than the surface's radius of "
               "curvature there; techniques disagree there)\n",
               layer->num_folded, layer->num_prisms);
    else
        printf("      shell: does not fold\n");
    meso_prism_layer_destroy(layer);
}

static meso_result info_scene(meso_context *ctx, const char *path) {
    meso_scene *scene = NULL;
    meso_result result = meso_scene_load(ctx, path, &scene);
    /* What the renderer would refuse (a misspelt technique, an unknown option) is refused here
     * too, before anything is printed. */
    if (result == MESO_OK && (result = meso_technique_check_scene(ctx, scene)) != MESO_OK) {
        meso_scene_destroy(scene);
        return result;
    }
    if (result != MESO_OK) return result;
    printf("scene: %s\n", scene->path);
    printf("image: %dx%d, background ", scene->width, scene->height);
    print_vec3("", scene->background);
    printf(", encoding %s\n", scene->encoding == MESO_ENCODING_LINEAR ? "linear" : "srgb");
    const meso_camera *c = &scene->camera;
    print_vec3("camera: eye ", c->eye);
    print_vec3(", target ", c->target);
    print_vec3(", up ", c->up);
    printf(", fov_y %g deg\n", c->fov_y_deg);
    print_vec3("ambient: ", scene->ambient);
    if (scene->environment) {
        const meso_environment *e = scene->environment;
        meso_vec3 up = {0, 1, 0};
        printf("\nenvironment: %s, %dx%d texels, intensity %g, irradiance facing up (%g, %g, %g)",
               e->source, e->map->width, e->map->height, (double)e->intensity,
               (double)meso_sh_irradiance(e->sh[0], up), (double)meso_sh_irradiance(e->sh[1], up),
               (double)meso_sh_irradiance(e->sh[2], up));
    }
    printf("\nlights: %d\n", scene->num_lights);
    for (int i = 0; i < scene->num_lights; i++) {
        const meso_light *l = &scene->lights[i];
        printf("  [%d] ", i);
        if (l->type == MESO_LIGHT_DIRECTIONAL)
            print_vec3("directional toward ", l->direction);
        else
            print_vec3("point at ", l->position);
        print_vec3(", colour ", l->color);
        printf("\n");
    }
    printf("objects: %d\n", scene->num_objects);
    for (int i = 0; i < scene->num_objects; i++) {
        const meso_object *o = &scene->objects[i];
        printf("  [%d] %s\n", i, o->name);
        if (o->mesh) print_mesh(o->mesh, "      ");
        if (o->texture_coordinates[0])
            printf("      texture coordinates: %s\n", o->texture_coordinates);
        print_vec3("      material: albedo ", o->material.albedo);
        if (o->material.color_map && o->material.color_map->levels[0])
            printf(", colour map %dx%d", o->material.color_map->levels[0]->width,
                   o->material.color_map->levels[0]->height);
        if (o->material.normal_map && o->material.normal_map->levels[0])
            printf(", normal map %dx%d (%s)", o->material.normal_map->levels[0]->width,
                   o->material.normal_map->levels[0]->height,
                   o->material.normal_map_directx ? "DirectX" : "OpenGL");
        print_vec3(", specular ", o->material.specular);
        printf(", shininess %g\n", o->material.shininess);
        if (o->mesh_material_note[0])
            printf("      material of the mesh file: %s\n", o->mesh_material_note);
        print_mesostructure(&o->mesostructure);
        print_shell_folds(ctx, o);
        const meso_technique_info *t = meso_technique_find(o->technique);
        printf("      technique: %s", o->technique);
        if (t) printf(" (%s)", t->paper);
        for (int k = 0; k < o->num_options; k++)
            printf("%s%s%s%s=%g", k ? ", " : "; options: ",
                   o->options[k].technique[0] ? o->options[k].technique : "",
                   o->options[k].technique[0] ? "." : "", o->options[k].name, o->options[k].value);
        printf("\n");
    }
    meso_scene_destroy(scene);
    return MESO_OK;
}

static const char *bake_type_name(meso_bake_type type, size_t *out_bytes) {
    switch (type) {
    case MESO_BAKE_F32:
        *out_bytes = 4;
        return "f32";
    case MESO_BAKE_U8:
        *out_bytes = 1;
        return "u8";
    case MESO_BAKE_U16:
        *out_bytes = 2;
        return "u16";
    case MESO_BAKE_I32:
        *out_bytes = 4;
        return "i32";
    case MESO_BAKE_F16:
        *out_bytes = 2;
        return "f16";
    }
    *out_bytes = 0;
    return "?";
}

static meso_result info_bake(meso_context *ctx, const char *path) {
    meso_bake_file *bake = NULL;
    meso_result result = meso_bake_file_load(ctx, path, &bake);
    if (result != MESO_OK) return result;
    if (!strcmp(bake->kind, MESO_RTV_KIND)) {
        /* GDM §4.1: sizes and the reconstruction error for each eigenfunction count */
        char report[1024];
        if (meso_rtv_describe(bake, report, sizeof(report))) fputs(report, stdout);
    }
    if (!strcmp(bake->kind, MESO_LAYERS_KIND)) {
        /* Multilayer relief maps (Policarpo & Oliveira 2006 §3): checked as a renderer reads
         * them before anything is printed, so a bad file is one error line. */
        meso_layers *map = NULL;
        result = meso_layers_from_bake_file(ctx, bake, path, &map);
        meso_layers_destroy(map);
        if (result != MESO_OK) {
            meso_bake_file_destroy(bake);
            return result;
        }
    }
    if (!strcmp(bake->kind, MESO_GDM_KIND)) {
        /* GDM (Wang et al. 2004 §4.1): checked as the technique reads it, the same way */
        meso_gdm *gdm = NULL;
        result = meso_gdm_from_bake_file(ctx, bake, path, &gdm);
        meso_gdm_destroy(gdm);
        if (result != MESO_OK) {
            meso_bake_file_destroy(bake);
            return result;
        }
    }
    printf("bake: %s\n", path);
    printf("kind: %s (version %u), source hash %016llx\n", bake->kind, bake->kind_version,
           (unsigned long long)bake->source_hash);
    printf("params: %s\n", bake->params_json ? bake->params_json : "{}");
    printf("arrays: %d\n", bake->num_arrays);
    uint64_t total = 0;
    for (int i = 0; i < bake->num_arrays; i++) {
        const meso_bake_array *a = &bake->arrays[i];
        size_t element = 0;
        const char *type = bake_type_name(a->type, &element);
        uint64_t count = 1;
        printf("  %-16s %-4s [", a->name, type);
        for (int d = 0; d < a->num_dims; d++) {
            printf("%s%llu", d ? " x " : "", (unsigned long long)a->dims[d]);
            count *= a->dims[d];
        }
        uint64_t bytes = count * element;
        total += bytes;
        printf("]  %.3f MiB\n", (double)bytes / (1024.0 * 1024.0));
    }
    printf("total: %.3f MiB\n", (double)total / (1024.0 * 1024.0));
    if (!strcmp(bake->kind, "vdm")) {
        /* VDM §3.3: sizes and the reconstruction error for each eigenfunction count. */
        size_t needed = meso_vdm_describe(bake, NULL, 0);
        char *report = needed ? malloc(needed + 1) : NULL;
        if (report) {
            meso_vdm_describe(bake, report, needed + 1);
            fputs(report, stdout);
            free(report);
        }
    }
    if (!strcmp(bake->kind, MESO_GDM_KIND)) {
        /* GDM §4.1: sizes and the reconstruction error for k = 1..16 eigen-maps */
        char report[4096];
        if (meso_gdm_describe(bake, report, sizeof(report))) fputs(report, stdout);
    }
    if (!strcmp(bake->kind, MESO_RTV_KIND)) {
        /* GDM §4.1: sizes and the reconstruction error for each eigenfunction count */
        char report[1024];
        if (meso_rtv_describe(bake, report, sizeof(report))) fputs(report, stdout);
    }
    if (!strcmp(bake->kind, MESO_LAYERS_KIND)) {
        /* sizes beside the paper's three 256x256 RGBA8 maps, and what the layer limit clips */
        char report[1024];
        if (meso_layers_describe(bake, report, sizeof(report))) fputs(report, stdout);
    }
    meso_bake_file_destroy(bake);
    return result;
}

int meso_cmd_info(int argc, char **argv) {
    app_globals globals;
    const char *positionals[1];
    int num_positionals = 0;
    int status = app_parse_options(&info_help, NULL, 0, argc, argv, &globals, positionals, 1,
                                   &num_positionals);
    if (status >= 0) return status;
    if (num_positionals < 1) return app_usage_error("info", "missing the FILE to describe");
    const char *path = positionals[0];

    unsigned char head[64];
    size_t head_size = 0;
    meso_context *probe_ctx = app_context_create(&globals);
    if (!probe_ctx) return APP_EXIT_FAILURE;
    FILE *f = NULL; /* a regular file only: a FIFO would block, a folder has no bytes */
    meso_result opened = meso_file_open_read(probe_ctx, path, &f);
    if (opened != MESO_OK) {
        status = app_fail(probe_ctx, opened);
        meso_context_destroy(probe_ctx);
        return status;
    }
    meso_context_destroy(probe_ctx);
    head_size = fread(head, 1, sizeof(head), f);
    fclose(f);
    char extension[16];
    app_path_extension(path, extension, sizeof(extension));
    file_kind kind = detect_kind(head, head_size, extension);
    if (kind == FILE_UNKNOWN) {
        fprintf(stderr,
                "meso: %s: unknown file type (expected a PNG, a scene .json, an "
                ".obj/.ply/.gltf/.glb mesh or a .mesobake file)\n",
                path);
        return APP_EXIT_BAD_INPUT;
    }

    meso_context *ctx = app_context_create(&globals);
    if (!ctx) return APP_EXIT_FAILURE;
    meso_result result = MESO_OK;
    switch (kind) {
    case FILE_PNG:
        result = info_png(ctx, path, head, head_size);
        break;
    case FILE_SCENE:
        result = info_scene(ctx, path);
        break;
    case FILE_MESH:
        result = info_mesh(ctx, path);
        break;
    case FILE_BAKE:
        result = info_bake(ctx, path);
        break;
    case FILE_UNKNOWN:
        break;
    }
    status = result == MESO_OK ? APP_EXIT_OK : app_fail(ctx, result);
    meso_context_destroy(ctx);
    return status;
}
