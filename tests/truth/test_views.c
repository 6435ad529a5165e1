/* The random-view test (docs/techniques.md, "From every side"): every example, drawn with every
 * technique that can draw it and with `reference`, from seeded cameras around the scene --
 * elevations from 5 degrees to exactly top-down, azimuths at random and exactly along edges of
 * the base mesh (its prisms' shared fins seen edge-on), near and far, the light moved too --
 * and checked against the reference of the same view for
 *   pinholes: background pixels inside the technique's drawing (at least 6 of their 8
 *             neighbours covered) and its footprint (for per-pixel techniques the base mesh,
 *             less a band of 2 pixels inside its outline) where the reference covers the
 *             whole 3 x 3 around them;
 *   specks:   pixels inside the drawing that differ by more than SPECK_THRESHOLD (sRGB luma)
 *             from all 8 neighbours and from the reference, where the reference is smooth;
 *   floors:   covered PSNR and coverage IoU above the technique's floor (views_floors.h).
 *
 *   test_views [--views K] [--size N] [--seed S] [--examples a,b] [--techniques a,b]
 *              [--small-bakes] [--report FILE.md] [--csv FILE] [--images DIR] [--no-floors]
 *
 * The techniques run at their default settings, and the variants of technique_variants (a
 * technique with one option set, named "technique:option=value" in --techniques, the report
 * and the floors); --small-bakes bakes small instead
 * (example_renders.h, as the determinism test does), for a quick look on a cold cache, with
 * no floors of its own.
 *
 * Exit status 0 when every view passes, 1 otherwise; a failing view prints the `meso render`
 * command that draws it. `make test` runs a few views; `make test-views K=200` many, with a
 * report. Bakes are cached in <build>/test-cache (as for every test), so repeated runs start
 * at once. */
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "../render/example_renders.h"
#include "meso/meso.h"
#include "views_floors.h"

#define MAX_EXAMPLES 32
#define MAX_TECHNIQUES 32
#define SPECK_THRESHOLD 0.4f /* sRGB luma: a speck stands out from its whole neighbourhood */
#define SPECK_SMOOTH 0.08f   /* sRGB luma: the reference's 3 x 3 counts as smooth */
#define PINHOLE_NEIGHBOURS 6
#define OUTLINE_BAND 2 /* pixels inside the base mesh's outline: a per-pixel silhouette's band */

typedef struct options {
    int views, size;
    unsigned seed;
    const char *examples, *techniques, *report, *images, *csv;
    bool floors, verbose;
    bool small_bakes; /* the determinism test's small bakes (example_renders.h): make test */
} options;

typedef struct view {
    meso_camera camera;
    meso_vec3 light;
    const char *kind; /* "random", "edge", "top" */
} view;

/* Per technique over all views. */
typedef struct tally {
    const char *technique;
    int views, failed, known; /* known: views with flaws of a documented limit (views_floors.h) */
    long pinholes, specks;
    double worst_psnr, worst_iou;
    char worst_command[768];
} tally;

/* Techniques drawn again with one option set: the relief family on the prism shell, which
 * draws the shell's boundary like a geometry technique (its pinholes are looked for over the
 * whole drawing, not only the base mesh's footprint). */
static const char *const technique_variants[] = {"relief:shell=1", "relief_exact:shell=1",
                                                 "relief_layers:shell=1"};
#define NUM_VARIANTS (sizeof technique_variants / sizeof technique_variants[0])

/* "name:option=value" into its parts; false when it is not of that form. */
static bool parse_variant(const char *spec, char *name, size_t name_size, meso_option *option) {
    const char *colon = strchr(spec, ':'), *equals = colon ? strchr(colon, '=') : NULL;
    if (!equals || (size_t)(colon - spec) >= name_size ||
        (size_t)(equals - colon - 1) >= sizeof option->name)
        return false;
    snprintf(name, name_size, "%.*s", (int)(colon - spec), spec);
    *option = (meso_option){0};
    snprintf(option->technique, sizeof option->technique, "%s", name);
    snprintf(option->name, sizeof option->name, "%.*s", (int)(equals - colon - 1), colon + 1);
    option->value = atof(equals + 1);
    return true;
}

/* ---- Seeded numbers: the same views on every machine ------------------------------------- */

static uint32_t mix(uint32_t x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

static float unit(uint32_t *state) {
    *state = mix(*state + 0x9e3779b9u);
    return (float)(*state >> 8) * (1.0f / 16777216.0f);
}

/* ---- Views -------------------------------------------------------------------------------- */

/* View k of an example: every fifth exactly top-down (up turned to -z), every third of the
 * rest looking along an edge of the base mesh at the edge's middle (fins edge-on), the others
 * anywhere above the surface; distance 0.45-1.5 x the scene's; a directional light from a
 * random side, low or high. */
static view make_view(const meso_scene *scene, unsigned seed, int example, int k) {
    uint32_t state = mix(seed ^ mix((uint32_t)example * 7919u + (uint32_t)k * 104729u));
    const meso_camera *home = &scene->camera;
    float distance = meso_vec3_length(meso_vec3_sub(home->eye, home->target));
    view v = {.camera = *home, .kind = "random"};
    meso_vec3 target = home->target;
    float azimuth = 6.2831853f * unit(&state);
    float elevation = (5.0f + 84.0f * unit(&state)) * 0.017453293f;
    distance *= 0.45f + 1.05f * unit(&state);
    if (k % 5 == 0) {
        v.kind = "top";
        elevation = 1.5707964f;
    } else if (k % 3 == 1) {
        const meso_object *object =
            &scene->objects[(size_t)(unit(&state) * 0.999f * (float)scene->num_objects)];
        const meso_mesh *mesh = object->mesh;
        size_t t = (size_t)(unit(&state) * 0.999f * (float)mesh->num_triangles);
        int e = (int)(unit(&state) * 2.999f);
        meso_vec3 a = mesh->positions[mesh->indices[3 * t + (size_t)e]];
        meso_vec3 b = mesh->positions[mesh->indices[3 * t + (size_t)(e + 1) % 3]];
        meso_vec3 along = meso_vec3_sub(b, a);
        if (fabsf(along.x) + fabsf(along.z) > 1e-6f) {
            v.kind = "edge";
            target = meso_vec3_scale(meso_vec3_add(a, b), 0.5f);
            azimuth = atan2f(along.z, along.x) + (unit(&state) < 0.5f ? 3.1415927f : 0.0f);
        }
    }
    v.camera.target = target;
    if (elevation >= 1.5707964f) {
        v.camera.eye = (meso_vec3){target.x, target.y + distance, target.z};
        v.camera.up = (meso_vec3){0.0f, 0.0f, -1.0f};
    } else {
        float c = cosf(elevation);
        v.camera.eye = (meso_vec3){target.x - distance * c * cosf(azimuth),
                                   target.y + distance * sinf(elevation),
                                   target.z - distance * c * sinf(azimuth)};
        v.camera.up = (meso_vec3){0.0f, 1.0f, 0.0f};
    }
    float light_azimuth = 6.2831853f * unit(&state);
    float light_elevation = (8.0f + 80.0f * unit(&state)) * 0.017453293f;
    v.light = (meso_vec3){cosf(light_elevation) * cosf(light_azimuth), sinf(light_elevation),
                          cosf(light_elevation) * sinf(light_azimuth)};
    return v;
}

static void apply_view(meso_scene *scene, const view *v) {
    scene->camera = v->camera;
    if (scene->num_lights > 0 && scene->lights[0].type == MESO_LIGHT_DIRECTIONAL)
        scene->lights[0].direction = v->light;
}

static void view_command(char *out, size_t size, const char *path, const char *technique,
                         const view *v, int image_size) {
    const meso_camera *c = &v->camera;
    char name[64], set[160] = "", file[96];
    meso_option option;
    snprintf(file, sizeof file, "%s", technique);
    if (parse_variant(technique, name, sizeof name, &option)) {
        snprintf(set, sizeof set, " --set %s.%s=%g", name, option.name, option.value);
        technique = name;
        for (char *p = file; *p; p++)
            if (*p == ':' || *p == '=') *p = '-';
    }
    snprintf(out, size,
             "meso render %s --technique %s%s --size %dx%d --eye %.6g,%.6g,%.6g "
             "--target %.6g,%.6g,%.6g --up %.6g,%.6g,%.6g --light %.6g,%.6g,%.6g -o %s.png",
             path, technique, set, image_size, image_size, (double)c->eye.x, (double)c->eye.y,
             (double)c->eye.z, (double)c->target.x, (double)c->target.y, (double)c->target.z,
             (double)c->up.x, (double)c->up.y, (double)c->up.z, (double)v->light.x,
             (double)v->light.y, (double)v->light.z, file);
}

/* ---- Checks ------------------------------------------------------------------------------- */

typedef struct frame_images {
    meso_image *color, *coverage; /* linear colour; coverage 0..1 */
} frame_images;

static float srgb(float x) {
    x = x < 0.0f ? 0.0f : x > 1.0f ? 1.0f : x;
    return x <= 0.0031308f ? 12.92f * x : 1.055f * powf(x, 1.0f / 2.4f) - 0.055f;
}

/* The distance of two pixels in sRGB luma (Rec. 709 weights): a speck is a pixel too dark or too
 * bright, the defect users see; a difference of hue at equal brightness -- a grey mortar texel
 * point-sampled where the truth shows brick -- is the texture's own detail. */
static float pixel_distance(const meso_image *a, size_t p, const meso_image *b, size_t q) {
    static const float weight[3] = {0.2126f, 0.7152f, 0.0722f};
    float d = 0.0f;
    for (int c = 0; c < 3; c++)
        d += weight[c] * (srgb(a->pixels[3 * p + (size_t)c]) - srgb(b->pixels[3 * q + (size_t)c]));
    return fabsf(d);
}

static bool covered(const meso_image *coverage, size_t p) { return coverage->pixels[p] >= 0.5f; }

/* A pixel OUTLINE_BAND or more pixels inside the footprint's outline. */
static bool inside_outline(const meso_image *footprint, int x, int y, int w, int h) {
    for (int dy = -OUTLINE_BAND; dy <= OUTLINE_BAND; dy++)
        for (int dx = -OUTLINE_BAND; dx <= OUTLINE_BAND; dx++) {
            int xx = x + dx, yy = y + dy;
            if (xx < 0 || yy < 0 || xx >= w || yy >= h ||
                !covered(footprint, (size_t)yy * (size_t)w + (size_t)xx))
                return false;
        }
    return true;
}

/* A pinhole: a pixel the technique leaves at the background inside its own drawing (at least
 * PINHOLE_NEIGHBOURS of its 8 neighbours covered) where the reference covers the pixel and all
 * its neighbours, and, for a per-pixel technique, where the base mesh covers it (`footprint`,
 * the coverage of `flat`; NULL for the geometry techniques, whose footprint is the whole shell).
 * Requiring the reference's whole 3 x 3 keeps the see-through gaps of solids (weave, chain
 * mail) out: a gap drawn a pixel wider or shifted is an error of the coverage IoU, not a crack.
 * The footprint keeps out the band a per-pixel technique cannot draw by its design: the true
 * surface seen beyond the base mesh's outline, through an open border's cut or a gap of the
 * mesh (documented with each technique), and so does the band of OUTLINE_BAND pixels inside
 * the outline, where a per-pixel technique draws the silhouette by discarding the rays that
 * leave its approximation of the curved shell (per-vertex quadrics, Oliveira & Policarpo
 * 2005): a miss there is that approximation's error, which the coverage IoU measures. */
static long count_pinholes(const frame_images *t, const frame_images *r,
                           const meso_image *footprint, int w, int h, uint8_t *marks) {
    long count = 0;
    for (int y = 1; y + 1 < h; y++)
        for (int x = 1; x + 1 < w; x++) {
            size_t p = (size_t)y * (size_t)w + (size_t)x;
            if (covered(t->coverage, p) || (footprint && !inside_outline(footprint, x, y, w, h)))
                continue;
            int around = 0, truth = 0;
            for (int dy = -1; dy <= 1; dy++)
                for (int dx = -1; dx <= 1; dx++) {
                    size_t q = (size_t)(y + dy) * (size_t)w + (size_t)(x + dx);
                    around += (dx || dy) && covered(t->coverage, q);
                    truth += covered(r->coverage, q);
                }
            bool pinhole = around >= PINHOLE_NEIGHBOURS && truth == 9;
            count += pinhole;
            if (pinhole) marks[p] = 1;
        }
    return count;
}

/* A speck: a pixel inside the technique's drawing (its 3 x 3 covered) where the reference is
 * smooth (its 3 x 3 within SPECK_SMOOTH of its centre, all covered) but the technique's pixel
 * lies farther than SPECK_THRESHOLD from the reference's and from each of its own 8
 * neighbours: a dark dot on a lit wall. A lone covered pixel at an outline is coverage, which
 * the IoU measures. Where the
 * reference itself varies from pixel to pixel -- point-sampled texture detail, mortar lines,
 * highlights on minified bumps -- a pixel that differs is aliasing of the truth's own detail
 * (docs/techniques.md), not a speck. */
static long count_specks(const frame_images *t, const frame_images *r, int w, int h,
                         uint8_t *marks) {
    long count = 0;
    for (int y = 1; y + 1 < h; y++)
        for (int x = 1; x + 1 < w; x++) {
            size_t p = (size_t)y * (size_t)w + (size_t)x;
            if (!covered(t->coverage, p) ||
                !(pixel_distance(t->color, p, r->color, p) > SPECK_THRESHOLD))
                continue;
            bool alone = true;
            for (int dy = -1; dy <= 1 && alone; dy++)
                for (int dx = -1; dx <= 1 && alone; dx++) {
                    size_t q = (size_t)(y + dy) * (size_t)w + (size_t)(x + dx);
                    alone = covered(r->coverage, q) && covered(t->coverage, q) &&
                            pixel_distance(r->color, q, r->color, p) <= SPECK_SMOOTH &&
                            (q == p || pixel_distance(t->color, p, t->color, q) > SPECK_THRESHOLD);
                }
            count += alone;
            if (alone) marks[p] = 2;
        }
    return count;
}

/* The technique's image with its pinholes in magenta and its specks in green, for a look. */
static void save_marks(meso_context *ctx, const meso_image *color, const uint8_t *marks,
                       const char *dir, const char *name) {
    meso_image *image = NULL;
    if (meso_image_create(ctx, color->width, color->height, 3, &image) != MESO_OK) return;
    size_t n = (size_t)color->width * (size_t)color->height;
    for (size_t p = 0; p < n; p++)
        for (int c = 0; c < 3; c++)
            image->pixels[3 * p + (size_t)c] = marks[p] == 1   ? (c == 1 ? 0.0f : 1.0f)
                                               : marks[p] == 2 ? (c == 1 ? 1.0f : 0.0f)
                                                               : color->pixels[3 * p + (size_t)c];
    char path[1024];
    snprintf(path, sizeof path, "%s/%s.png", dir, name);
    if (meso_image_save_png(ctx, image, path, NULL) != MESO_OK)
        fprintf(stderr, "test_views: %s: %s\n", path, meso_context_last_error(ctx));
    meso_image_destroy(image);
}

/* ---- Rendering ---------------------------------------------------------------------------- */

static bool render(meso_context *ctx, meso_renderer *renderer, int size, frame_images *out) {
    meso_framebuffer *fb = NULL;
    *out = (frame_images){0};
    bool ok = meso_framebuffer_create(ctx, size, size, &fb) == MESO_OK &&
              meso_renderer_render(renderer, fb) == MESO_OK &&
              meso_framebuffer_color_image(ctx, fb, &out->color) == MESO_OK &&
              meso_framebuffer_coverage_image(ctx, fb, &out->coverage) == MESO_OK;
    meso_framebuffer_destroy(fb);
    return ok;
}

static void frame_images_free(frame_images *f) {
    meso_image_destroy(f->color);
    meso_image_destroy(f->coverage);
    *f = (frame_images){0};
}

/* The one applicability test (meso_technique_accepts) for every object of the scene. */
static bool technique_draws(const meso_technique_info *info, const meso_scene *scene) {
    for (int i = 0; i < scene->num_objects; i++)
        if (!meso_technique_accepts(info, &scene->objects[i].mesostructure)) return false;
    return true;
}

static bool in_list(const char *list, const char *name) {
    if (!list) return true;
    size_t n = strlen(name);
    for (const char *p = list; *p;) {
        const char *end = strchr(p, ',');
        size_t len = end ? (size_t)(end - p) : strlen(p);
        if (len == n && !strncmp(p, name, n)) return true;
        if (!end) break;
        p = end + 1;
    }
    return false;
}

static void save_png(meso_context *ctx, const meso_image *image, const char *dir,
                     const char *name) {
    char path[1024];
    snprintf(path, sizeof path, "%s/%s.png", dir, name);
    if (meso_image_save_png(ctx, image, path, NULL) != MESO_OK)
        fprintf(stderr, "test_views: %s: %s\n", path, meso_context_last_error(ctx));
}

static meso_render_desc render_desc(const options *o, const char *technique) {
    meso_render_desc desc = {.technique = technique};
    if (o->small_bakes) {
        desc.options = example_small_bakes;
        desc.num_options = (int)(sizeof example_small_bakes / sizeof example_small_bakes[0]);
    }
    return desc;
}

#define NUM_SMALL_BAKES (sizeof example_small_bakes / sizeof example_small_bakes[0])

/* render_desc of a variant's technique with its option after the small bakes' (`storage`:
 * NUM_SMALL_BAKES + 1 options, alive while the renderer is made). */
static meso_render_desc variant_desc(const options *o, const char *technique,
                                     const meso_option *option, meso_option *storage) {
    meso_render_desc desc = render_desc(o, technique);
    int n = desc.num_options;
    if (n) memcpy(storage, desc.options, (size_t)n * sizeof *storage);
    storage[n] = *option;
    desc.options = storage;
    desc.num_options = n + 1;
    return desc;
}

/* An impostor (a model's solid on a quad): no shell to walk. */
static bool scene_has_impostor(const meso_scene *scene) {
    for (int i = 0; i < scene->num_objects; i++) {
        const meso_mesostructure *m = &scene->objects[i].mesostructure;
        if (m->kind == MESO_MESOSTRUCTURE_SOLID && m->solid && !meso_solid_is_periodic(m->solid))
            return true;
    }
    return false;
}

/* ---- One example -------------------------------------------------------------------------- */

typedef struct example_run {
    meso_context *ctx;
    const options *o;
    FILE *csv; /* every (example, technique, view) row, with --csv */
    tally *tallies;
    size_t num_tallies;
    int failures;
} example_run;

static tally *tally_of(example_run *run, const char *technique) {
    for (size_t i = 0; i < run->num_tallies; i++)
        if (!strcmp(run->tallies[i].technique, technique)) return &run->tallies[i];
    tally *t = &run->tallies[run->num_tallies++];
    *t = (tally){.technique = technique, .worst_psnr = INFINITY, .worst_iou = INFINITY};
    return t;
}

static void run_example(example_run *run, const char *file, const char *path, int example) {
    char example_name[256];
    const char *slash = strrchr(path, '/');
    snprintf(example_name, sizeof example_name, "%.*s", (int)strlen(slash ? slash + 1 : path) - 5,
             slash ? slash + 1 : path);
    meso_context *ctx = run->ctx;
    const options *o = run->o;
    meso_scene *scene = NULL;
    if (meso_scene_load(ctx, file, &scene) != MESO_OK) {
        fprintf(stderr, "FAIL %s: %s\n", path, meso_context_last_error(ctx));
        run->failures++;
        return;
    }
    const meso_camera home = scene->camera;
    meso_renderer *renderers[MAX_TECHNIQUES] = {0};
    const meso_technique_info *infos[MAX_TECHNIQUES] = {0};
    const char *names[MAX_TECHNIQUES] = {0}; /* the technique's or the variant's name */
    bool shells[MAX_TECHNIQUES] = {0};       /* a variant drawing the whole shell */
    size_t count = 0;
    for (size_t i = 0; i < meso_technique_count() + NUM_VARIANTS && count < MAX_TECHNIQUES; i++) {
        const meso_technique_info *info = NULL;
        const char *name;
        meso_option option, storage[NUM_SMALL_BAKES + 1];
        char technique[64];
        bool variant = i >= meso_technique_count();
        if (!variant) {
            info = meso_technique_get(i);
            name = info->name;
        } else {
            name = technique_variants[i - meso_technique_count()];
            if (!parse_variant(name, technique, sizeof technique, &option)) continue;
            for (size_t k = 0; k < meso_technique_count() && !info; k++)
                if (!strcmp(meso_technique_get(k)->name, technique)) info = meso_technique_get(k);
            if (!info || scene_has_impostor(scene)) continue;
        }
        if (info->kind == MESO_TECHNIQUE_REFERENCE || !technique_draws(info, scene) ||
            !in_list(o->techniques, name))
            continue;
        meso_render_desc desc =
            variant ? variant_desc(o, info->name, &option, storage) : render_desc(o, info->name);
        if (meso_renderer_create(ctx, scene, &desc, &renderers[count]) != MESO_OK) {
            fprintf(stderr, "FAIL %s %s: %s\n", path, name, meso_context_last_error(ctx));
            run->failures++;
            continue;
        }
        shells[count] = variant && !strcmp(option.name, "shell");
        names[count] = name;
        infos[count++] = info;
    }
    /* The reference's geometry depends on the view only through the height fields' subdivision
     * (capped at half a pixel of the view); a scene without height fields keeps one. */
    bool reference_kept = true;
    for (int i = 0; i < scene->num_objects; i++)
        reference_kept &= scene->objects[i].mesostructure.kind != MESO_MESOSTRUCTURE_HEIGHT_FIELD;
    meso_renderer *reference = NULL;
    if (reference_kept) {
        meso_render_desc reference_desc = render_desc(o, "reference");
        if (meso_renderer_create(ctx, scene, &reference_desc, &reference) != MESO_OK)
            reference = NULL;
    }
    /* the base mesh's footprint, which bounds what a per-pixel technique can draw */
    uint8_t *marks = malloc((size_t)o->size * (size_t)o->size);
    meso_renderer *flat = NULL;
    meso_render_desc flat_desc = render_desc(o, "flat");
    if (meso_renderer_create(ctx, scene, &flat_desc, &flat) != MESO_OK) flat = NULL;
    for (int k = 0; k < o->views; k++) {
        scene->camera = home;
        view v = make_view(scene, o->seed, example, k);
        apply_view(scene, &v);
        frame_images truth = {0};
        if (!reference_kept) {
            meso_render_desc reference_desc = render_desc(o, "reference");
            if (meso_renderer_create(ctx, scene, &reference_desc, &reference) != MESO_OK)
                reference = NULL;
        }
        if (!reference || !render(ctx, reference, o->size, &truth)) {
            char command[768];
            view_command(command, sizeof command, path, "reference", &v, o->size);
            fprintf(stderr, "FAIL %s reference view %d: %s\n  %s\n", path, k,
                    meso_context_last_error(ctx), command);
            run->failures++;
            frame_images_free(&truth);
            if (!reference_kept) meso_renderer_destroy(reference), reference = NULL;
            continue;
        }
        if (!reference_kept) meso_renderer_destroy(reference), reference = NULL;
        frame_images footprint = {0};
        if (flat && !render(ctx, flat, o->size, &footprint)) frame_images_free(&footprint);
        char base[512];
        const char *name = strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
        if (o->images) {
            snprintf(base, sizeof base, "%.*s-%03d-reference", (int)(strlen(name) - 5), name, k);
            save_png(ctx, truth.color, o->images, base);
        }
        for (size_t i = 0; i < count; i++) {
            frame_images image;
            char command[768];
            view_command(command, sizeof command, path, names[i], &v, o->size);
            tally *t = tally_of(run, names[i]);
            t->views++;
            if (!render(ctx, renderers[i], o->size, &image)) {
                fprintf(stderr, "FAIL %s %s view %d: %s\n  %s\n", path, names[i], k,
                        meso_context_last_error(ctx), command);
                t->failed++;
                run->failures++;
                frame_images_free(&image);
                continue;
            }
            bool per_pixel = infos[i]->kind == MESO_TECHNIQUE_PER_PIXEL && !shells[i];
            const meso_image *fp = per_pixel ? footprint.coverage : NULL;
            if (per_pixel && !fp) fp = image.coverage;
            memset(marks, 0, (size_t)o->size * (size_t)o->size);
            long pinholes = count_pinholes(&image, &truth, fp, o->size, o->size, marks);
            long specks = count_specks(&image, &truth, o->size, o->size, marks);
            meso_compare_result m;
            meso_compare_desc cd = {.coverage_a = image.coverage, .coverage_b = truth.coverage};
            if (meso_image_compare(ctx, image.color, truth.color, &cd, &m) != MESO_OK)
                m = (meso_compare_result){0};
            double psnr = isnan(m.psnr_covered) ? INFINITY : m.psnr_covered;
            views_floor floor = views_floor_of(example_name, names[i]);
            bool below = o->floors && !o->small_bakes && o->size == VIEWS_FLOORS_SIZE &&
                         (psnr < floor.psnr_covered || m.coverage_iou < floor.iou);
            const char *known = views_known(example_name, names[i]);
            if (run->csv)
                fprintf(run->csv, "%s,%s,%d,%s,%ld,%ld,%.3f,%.5f\n", path, names[i], k, v.kind,
                        pinholes, specks, psnr, m.coverage_iou);
            t->pinholes += pinholes;
            t->specks += specks;
            if (psnr < t->worst_psnr) {
                t->worst_psnr = psnr;
                snprintf(t->worst_command, sizeof t->worst_command, "%s", command);
            }
            if (m.coverage_iou < t->worst_iou) t->worst_iou = m.coverage_iou;
            bool flawed = pinholes > 0 || specks > 0;
            bool bad = (flawed && !known) || below;
            if (flawed && known) t->known++;
            if (bad) {
                t->failed++;
                run->failures++;
            }
            if (bad || (flawed && o->verbose))
                fprintf(stderr,
                        "%s %s %s view %d (%s): %ld pinholes, %ld specks, covered %.2f dB "
                        "(floor %.1f), IoU %.4f (floor %.3f)\n  %s\n",
                        bad ? "FAIL" : "KNOWN", path, names[i], k, v.kind, pinholes, specks, psnr,
                        (double)floor.psnr_covered, m.coverage_iou, (double)floor.iou, command);
            if (o->images && (bad || k < 2)) {
                snprintf(base, sizeof base, "%.*s-%03d-%s", (int)(strlen(name) - 5), name, k,
                         names[i]);
                save_png(ctx, image.color, o->images, base);
                if (pinholes || specks) {
                    snprintf(base, sizeof base, "%.*s-%03d-%s-marks", (int)(strlen(name) - 5), name,
                             k, names[i]);
                    save_marks(ctx, image.color, marks, o->images, base);
                }
            }
            frame_images_free(&image);
        }
        frame_images_free(&truth);
        frame_images_free(&footprint);
    }
    free(marks);
    meso_renderer_destroy(flat);
    meso_renderer_destroy(reference);
    for (size_t i = 0; i < count; i++) meso_renderer_destroy(renderers[i]);
    meso_scene_destroy(scene);
}

/* ---- Main --------------------------------------------------------------------------------- */

static int compare_names(const void *a, const void *b) {
    return strcmp(*(char *const *)a, *(char *const *)b);
}

static void write_report(const example_run *run, const options *o, int num_examples) {
    FILE *f = fopen(o->report, "w");
    if (!f) {
        fprintf(stderr, "test_views: %s: cannot write\n", o->report);
        return;
    }
    fprintf(f,
            "%d examples, %d views each at %dx%d, seed %u, %s bakes (%s techniques).\n\n"
            "| technique | views | failed | known | pinholes | specks | worst covered dB | "
            "worst IoU | worst view |\n"
            "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |\n",
            num_examples, o->views, o->size, o->size, o->seed, o->small_bakes ? "small" : "default",
            meso_technique_isa());
    for (size_t i = 0; i < run->num_tallies; i++) {
        const tally *t = &run->tallies[i];
        fprintf(f, "| %s | %d | %d | %d | %ld | %ld | %.2f | %.4f | `%s` |\n", t->technique,
                t->views, t->failed, t->known, t->pinholes, t->specks, t->worst_psnr, t->worst_iou,
                t->worst_command);
    }
    fclose(f);
}

int main(int argc, char **argv) {
    /* make test: every example, two views, at the techniques' default settings (their bakes
     * cached in the build tree); under the sanitizers (10-30 times slower) one plane and the
     * techniques without minutes-long bakes, which exercises every check's code */
    options o = {.views = 2, .size = 64, .seed = 1, .floors = true};
    if (MESO_SANITIZE_FLAGS[0]) {
        o.views = 1;
        o.size = 48;
        o.examples = "bricks-plane";
        o.techniques = "flat,bump,horizon,parallax,relief,relief_layers,tessellation,displacement";
    }
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *next = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--no-floors") || !strcmp(a, "--small-bakes") || !strcmp(a, "--verbose")) {
            *(a[2] == 'n' ? &o.floors : a[2] == 's' ? &o.small_bakes : &o.verbose) = a[2] != 'n';
            continue;
        }
        if (!next) {
            fprintf(stderr, "test_views: %s: needs a value (see the file's comment)\n", a);
            return 2;
        }
        if (!strcmp(a, "--views"))
            o.views = atoi(next);
        else if (!strcmp(a, "--size"))
            o.size = atoi(next);
        else if (!strcmp(a, "--seed"))
            o.seed = (unsigned)strtoul(next, NULL, 10);
        else if (!strcmp(a, "--examples"))
            o.examples = next;
        else if (!strcmp(a, "--techniques"))
            o.techniques = next;
        else if (!strcmp(a, "--report"))
            o.report = next;
        else if (!strcmp(a, "--images"))
            o.images = next;
        else if (!strcmp(a, "--csv"))
            o.csv = next;
        else {
            fprintf(stderr, "test_views: %s: unknown option\n", a);
            return 2;
        }
        i++;
    }
    if (o.views < 1 || o.size < 16 || o.size > 1024) {
        fprintf(stderr, "test_views: --views must be >= 1 and --size 16..1024\n");
        return 2;
    }
    if (o.images) mkdir(o.images, 0777);
    setenv("MESO_CACHE_DIR", MESO_BINARY_DIR "/test-cache", 0);

    const char *dir = MESO_SOURCE_DIR "/examples";
    char *names[MAX_EXAMPLES];
    int num = 0;
    DIR *d = opendir(dir);
    if (!d) {
        fprintf(stderr, "test_views: %s: cannot open\n", dir);
        return 2;
    }
    for (struct dirent *e; (e = readdir(d)) && num < MAX_EXAMPLES;) {
        size_t n = strlen(e->d_name);
        if (n < 6 || strcmp(e->d_name + n - 5, ".json")) continue;
        char stem[256];
        snprintf(stem, sizeof stem, "%.*s", (int)(n - 5), e->d_name);
        if (!in_list(o.examples, stem)) continue;
        names[num++] = strdup(e->d_name);
    }
    closedir(d);
    qsort(names, (size_t)num, sizeof *names, compare_names);

    meso_context *ctx = NULL;
    if (meso_context_create(&(meso_context_desc){0}, &ctx) != MESO_OK) return 1;
    tally tallies[MAX_TECHNIQUES];
    example_run run = {.ctx = ctx, .o = &o, .tallies = tallies};
    if (o.csv && !(run.csv = fopen(o.csv, "w"))) {
        fprintf(stderr, "test_views: %s: cannot write\n", o.csv);
        return 2;
    }
    if (run.csv) fprintf(run.csv, "example,technique,view,kind,pinholes,specks,covered_db,iou\n");
    for (int i = 0; i < num; i++) {
        char path[1024];
        snprintf(path, sizeof path, "examples/%s", names[i]);
        char file[1200];
        snprintf(file, sizeof file, "%s/%s", dir, names[i]);
        fprintf(stderr, "test_views: %s, %d views\n", path, o.views);
        run_example(&run, file, path, i);
        free(names[i]);
    }
    if (o.report) write_report(&run, &o, num);
    if (run.csv) fclose(run.csv);
    int checks = 0;
    for (size_t i = 0; i < run.num_tallies; i++) checks += tallies[i].views;
    printf("%d passed, %d failed\n", checks - run.failures, run.failures);
    meso_context_destroy(ctx);
    return run.failures ? 1 : 0;
}
