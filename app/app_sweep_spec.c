/* A sweep file (docs/sweep.md) read with cJSON, checked whole and expanded to jobs in a stable
 * order: scenes, then sizes, then techniques, then each technique's option grid (its options in
 * the file's order, the last one varying fastest). */
#include "app_sweep.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "meso/runtime.h"

/* Print "meso: <file>: <key>: <reason>" and return the bad-input status. */
static int spec_error(const char *file, const char *key, const char *format, ...)
    __attribute__((format(printf, 3, 4)));
static int spec_error(const char *file, const char *key, const char *format, ...) {
    char reason[1024];
    va_list args;
    va_start(args, format);
    vsnprintf(reason, sizeof reason, format, args);
    va_end(args);
    app_error("%s: %s: %s", file, key, reason);
    return APP_EXIT_BAD_INPUT;
}

void app_sweep_hash_text(uint64_t hash, char out[17]) {
    snprintf(out, 17, "%016llx", (unsigned long long)hash);
}

/* A whole number in [min, max] at key, or the default when absent. */
static int read_int(const char *file, const cJSON *root, const char *key, int fallback, int min,
                    int max, int *out) {
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(root, key);
    if (!item) {
        *out = fallback;
        return -1;
    }
    double v = cJSON_IsNumber(item) ? item->valuedouble : NAN;
    if (!(v >= min && v <= max) || v != floor(v))
        return spec_error(file, key, "expected a whole number in %d..%d", min, max);
    *out = (int)v;
    return -1;
}

static int read_scenes(meso_context *ctx, const char *file, const cJSON *root, sweep_spec *spec) {
    const cJSON *scenes = cJSON_GetObjectItemCaseSensitive(root, "scenes");
    if (!cJSON_IsArray(scenes) || cJSON_GetArraySize(scenes) < 1)
        return spec_error(file, "scenes", "expected an array of scene files (at least one)");
    if (cJSON_GetArraySize(scenes) > SWEEP_MAX_SCENES)
        return spec_error(file, "scenes", "more than %d scenes", SWEEP_MAX_SCENES);
    /* Relative scene paths are relative to the sweep file's folder. */
    char folder[1024] = ".";
    const char *slash = strrchr(file, '/');
    if (slash) snprintf(folder, sizeof folder, "%.*s", (int)(slash - file), file);
    const cJSON *item;
    cJSON_ArrayForEach(item, scenes) {
        char key[64];
        snprintf(key, sizeof key, "scenes[%d]", spec->num_scenes);
        if (!cJSON_IsString(item) || !item->valuestring[0])
            return spec_error(file, key, "expected a scene file name");
        sweep_scene *s = &spec->scenes[spec->num_scenes];
        const char *name = item->valuestring;
        int n = name[0] == '/' ? snprintf(s->path, sizeof s->path, "%s", name)
                               : snprintf(s->path, sizeof s->path, "%s/%s", folder, name);
        if (n < 0 || (size_t)n >= sizeof s->path) return spec_error(file, key, "path too long");
        app_path_stem(s->path, s->name, sizeof s->name);
        for (int k = 0; k < spec->num_scenes; k++)
            if (strcmp(spec->scenes[k].name, s->name) == 0)
                return spec_error(file, key, "%s and %s would both write into '%s'",
                                  spec->scenes[k].path, s->path, s->name);
        char *bytes = NULL;
        size_t size = 0;
        meso_result r = meso_file_read(ctx, s->path, 64u << 20, &bytes, &size);
        if (r == MESO_OK) {
            s->file_hash = meso_hash64(bytes, size, MESO_HASH_SEED);
            free(bytes);
            r = meso_scene_load(ctx, s->path, &s->scene);
        }
        spec->num_scenes++;
        /* a scene that does not load is the sweep file's fault, whatever the reason */
        if (r != MESO_OK) return spec_error(file, key, "%s", meso_context_last_error(ctx));
    }
    return -1;
}

static int read_size(const char *file, const char *key, const cJSON *item, app_size *out) {
    double w = NAN, h = NAN;
    if (cJSON_IsNumber(item)) {
        w = h = item->valuedouble;
    } else if (cJSON_IsArray(item) && cJSON_GetArraySize(item) == 2 &&
               cJSON_IsNumber(cJSON_GetArrayItem(item, 0)) &&
               cJSON_IsNumber(cJSON_GetArrayItem(item, 1))) {
        w = cJSON_GetArrayItem(item, 0)->valuedouble;
        h = cJSON_GetArrayItem(item, 1)->valuedouble;
    } else if (cJSON_IsString(item)) {
        char *end = NULL;
        w = strtod(item->valuestring, &end);
        if (end && (*end == 'x' || *end == 'X')) {
            const char *rest = end + 1;
            h = strtod(rest, &end);
            if (end == rest || *end) h = NAN;
        }
    }
    if (!(w >= 1 && h >= 1 && w <= MESO_IMAGE_MAX_SIDE && h <= MESO_IMAGE_MAX_SIDE) ||
        w != floor(w) || h != floor(h) || w * h > (double)MESO_IMAGE_MAX_PIXELS)
        return spec_error(file, key,
                          "expected a size: N, [W, H] or \"WxH\" with sides in 1..%d and at "
                          "most %llu pixels",
                          MESO_IMAGE_MAX_SIDE, (unsigned long long)MESO_IMAGE_MAX_PIXELS);
    out->width = (int)w;
    out->height = (int)h;
    return -1;
}

static int read_sizes(const char *file, const cJSON *root, sweep_spec *spec) {
    const cJSON *sizes = cJSON_GetObjectItemCaseSensitive(root, "sizes");
    if (!sizes) { /* each scene's own */
        spec->num_sizes = 1;
        return -1;
    }
    if (!cJSON_IsArray(sizes) || cJSON_GetArraySize(sizes) < 1)
        return spec_error(file, "sizes", "expected an array of sizes (at least one)");
    if (cJSON_GetArraySize(sizes) > SWEEP_MAX_SIZES)
        return spec_error(file, "sizes", "more than %d sizes", SWEEP_MAX_SIZES);
    const cJSON *item;
    cJSON_ArrayForEach(item, sizes) {
        char key[64];
        snprintf(key, sizeof key, "sizes[%d]", spec->num_sizes);
        int status = read_size(file, key, item, &spec->sizes[spec->num_sizes]);
        if (status >= 0) return status;
        for (int k = 0; k < spec->num_sizes; k++)
            if (spec->sizes[k].width == spec->sizes[spec->num_sizes].width &&
                spec->sizes[k].height == spec->sizes[spec->num_sizes].height)
                return spec_error(file, key, "the size %dx%d is given twice", spec->sizes[k].width,
                                  spec->sizes[k].height);
        spec->num_sizes++;
    }
    return -1;
}

static int add_technique(const char *file, const char *key, const char *name, sweep_spec *spec) {
    if (strcmp(name, "reference") == 0)
        return spec_error(file, key,
                          "'reference' is the truth every job is measured against, not a job");
    const meso_technique_info *info = meso_technique_find(name);
    if (!info) {
        char known[1024];
        app_known_techniques(known, sizeof known);
        return spec_error(file, key, "unknown technique '%s' (known: %s)", name, known);
    }
    for (int k = 0; k < spec->num_techniques; k++)
        if (spec->techniques[k].info == info)
            return spec_error(file, key, "the technique '%s' is given twice", name);
    if (spec->num_techniques >= SWEEP_MAX_TECHNIQUES)
        return spec_error(file, key, "more than %d techniques", SWEEP_MAX_TECHNIQUES);
    spec->techniques[spec->num_techniques++].info = info;
    return -1;
}

static int read_techniques(const char *file, const cJSON *root, sweep_spec *spec) {
    const cJSON *list = cJSON_GetObjectItemCaseSensitive(root, "techniques");
    if (cJSON_IsString(list) && strcmp(list->valuestring, "all") == 0) {
        for (size_t i = 0; i < meso_technique_count(); i++) {
            const meso_technique_info *info = meso_technique_get(i);
            if (info->kind != MESO_TECHNIQUE_REFERENCE)
                spec->techniques[spec->num_techniques++].info = info;
        }
        return -1;
    }
    if (!cJSON_IsArray(list) || cJSON_GetArraySize(list) < 1)
        return spec_error(file, "techniques",
                          "expected \"all\" or an array of technique names (at least one)");
    const cJSON *item;
    int index = 0;
    cJSON_ArrayForEach(item, list) {
        char key[64];
        snprintf(key, sizeof key, "techniques[%d]", index++);
        if (!cJSON_IsString(item)) return spec_error(file, key, "expected a technique name");
        int status = add_technique(file, key, item->valuestring, spec);
        if (status >= 0) return status;
    }
    return -1;
}

/* One option's values: a number or boolean, or an array of them, each checked against the
 * technique's option table. */
static int read_axis(meso_context *ctx, const char *file, const char *technique, const cJSON *item,
                     sweep_axis *axis) {
    char where[512];
    snprintf(where, sizeof where, "%s: options.%s.%s", file, technique, item->string);
    const meso_technique_info *info = meso_technique_find(technique);
    if (!meso_technique_find_option(info, item->string)) {
        char names[512] = "";
        for (size_t i = 0; i < info->num_options; i++)
            snprintf(names + strlen(names), sizeof names - strlen(names), "%s%s", i ? ", " : "",
                     info->options[i].name);
        app_error("%s: unknown option of %s (%s)", where, technique,
                  names[0] ? names : "it has none");
        return APP_EXIT_BAD_INPUT;
    }
    snprintf(axis->name, sizeof axis->name, "%s", item->string);
    const cJSON *values = item;
    bool single = !cJSON_IsArray(item);
    int count = single ? 1 : cJSON_GetArraySize(item);
    if (count < 1 || count > SWEEP_MAX_GRID_VALUES) {
        app_error("%s: expected 1..%d values", where, SWEEP_MAX_GRID_VALUES);
        return APP_EXIT_BAD_INPUT;
    }
    for (int i = 0; i < count; i++) {
        const cJSON *v = single ? values : cJSON_GetArrayItem(values, i);
        char at[600];
        if (single)
            snprintf(at, sizeof at, "%s", where);
        else
            snprintf(at, sizeof at, "%s[%d]", where, i);
        if (!cJSON_IsNumber(v) && !cJSON_IsBool(v)) {
            app_error("%s: expected a number or true/false", at);
            return APP_EXIT_BAD_INPUT;
        }
        double value = cJSON_IsBool(v) ? (cJSON_IsTrue(v) ? 1.0 : 0.0) : v->valuedouble;
        meso_result r = meso_technique_check_option(ctx, technique, item->string, value, at);
        if (r != MESO_OK) return app_fail(ctx, r);
        for (int k = 0; k < axis->num_values; k++)
            if (axis->values[k] == value) {
                app_error("%s: the value %g is given twice", at, value);
                return APP_EXIT_BAD_INPUT;
            }
        axis->values[axis->num_values++] = value;
    }
    return -1;
}

static int read_options(meso_context *ctx, const char *file, const cJSON *root, sweep_spec *spec) {
    const cJSON *options = cJSON_GetObjectItemCaseSensitive(root, "options");
    if (!options) return -1;
    if (!cJSON_IsObject(options))
        return spec_error(file, "options", "expected {\"technique\": {\"option\": [values]}, ...}");
    const cJSON *grid;
    cJSON_ArrayForEach(grid, options) {
        char key[128];
        snprintf(key, sizeof key, "options.%s", grid->string);
        sweep_technique *t = NULL;
        for (int k = 0; k < spec->num_techniques; k++)
            if (strcmp(spec->techniques[k].info->name, grid->string) == 0) t = &spec->techniques[k];
        if (!t && !meso_technique_find(grid->string))
            return spec_error(file, key, "unknown technique '%s'", grid->string);
        if (!t)
            return spec_error(file, key, "'%s' is not among the sweep's techniques", grid->string);
        if (!cJSON_IsObject(grid))
            return spec_error(file, key, "expected {\"option\": [values], ...}");
        const cJSON *item;
        cJSON_ArrayForEach(item, grid) {
            if (t->num_axes >= MESO_OPTIONS_MAX)
                return spec_error(file, key, "more than %d options", MESO_OPTIONS_MAX);
            for (int k = 0; k < t->num_axes; k++)
                if (strcmp(t->axes[k].name, item->string) == 0)
                    return spec_error(file, key, "the option '%s' is given twice", item->string);
            int status = read_axis(ctx, file, t->info->name, item, &t->axes[t->num_axes]);
            if (status >= 0) return status;
            t->num_axes++;
        }
    }
    return -1;
}

/* ---- Cost model --------------------------------------------------------------------------- */

/* Seconds a job of a technique takes at 256 x 256, one sample, one view and 5 timed frames
 * (prepare with a warm cache, 6 frames, the comparison and the writes): medians of the jobs of
 * examples/sweeps/examples-256.json on the 2-core development machine under a load average of
 * about 18 (docs/scale-out.md, "Measured"). They matter relative to each other: the cost
 * partition balances shards with them. */
static double technique_job_seconds(const char *technique) {
    static const struct {
        const char *name;
        double seconds;
    } table[] = {
        {"flat", 0.10},   {"bump", 0.16},         {"horizon", 0.42},       {"parallax", 0.23},
        {"relief", 0.25}, {"relief_exact", 0.34}, {"relief_layers", 0.59}, {"vdm", 0.61},
        {"gdm", 2.86},    {"tessellation", 0.62}, {"displacement", 1.47},
    };
    for (size_t i = 0; i < sizeof table / sizeof table[0]; i++)
        if (strcmp(table[i].name, technique) == 0) return table[i].seconds;
    return 1.0;
}

/* The reference of a scene: building the true micro-geometry and its BVH once (a solid's
 * extraction by dual contouring dominates: 20-50 s for the examples' solids against 2-5 s for
 * a height field's grid, same machine and load), then a frame per view. */
static double reference_seconds(const sweep_spec *spec, const meso_scene *scene, double pixels) {
    bool solid = false;
    for (int i = 0; i < scene->num_objects; i++)
        solid = solid || scene->objects[i].mesostructure.kind == MESO_MESOSTRUCTURE_SOLID;
    double frame = 0.3 * pixels / 65536.0 * (double)spec->reference_samples;
    return (solid ? 40.0 : 3.0) + frame * (double)(1 + spec->frames) / 6.0 * (double)spec->orbit;
}

/* A job's estimated seconds; `sharing` jobs share its scene's reference at its size. */
static double job_cost(const sweep_spec *spec, const sweep_job *job, size_t sharing) {
    double pixels = (double)job->width * (double)job->height;
    double job_seconds = technique_job_seconds(job->technique->info->name) * pixels / 65536.0 *
                         (double)spec->samples * (double)spec->orbit * (double)(1 + spec->frames) /
                         6.0;
    double reference = reference_seconds(spec, spec->scenes[job->scene].scene, pixels);
    return job_seconds + reference / (double)(sharing ? sharing : 1);
}

/* ---- Expansion ---------------------------------------------------------------------------- */

static size_t grid_size(const sweep_technique *t) {
    size_t n = 1;
    for (int a = 0; a < t->num_axes; a++) n *= (size_t)t->axes[a].num_values;
    return n;
}

static int expand(const char *file, sweep_spec *spec) {
    size_t total = 0;
    for (int s = 0; s < spec->num_scenes; s++)
        for (int t = 0; t < spec->num_techniques; t++) {
            if (app_technique_draws(spec->techniques[t].info, spec->scenes[s].scene) == 0) continue;
            total += grid_size(&spec->techniques[t]) * (size_t)spec->num_sizes;
            if (total > SWEEP_MAX_JOBS)
                return spec_error(file, "options", "expands to more than %d jobs", SWEEP_MAX_JOBS);
        }
    if (total == 0)
        return spec_error(file, "techniques", "no technique can draw any of the scenes");
    spec->jobs = calloc(total, sizeof *spec->jobs);
    if (!spec->jobs) {
        app_error("%s: out of memory", file);
        return APP_EXIT_FAILURE;
    }
    for (int s = 0; s < spec->num_scenes; s++) {
        const meso_scene *scene = spec->scenes[s].scene;
        for (int z = 0; z < spec->num_sizes; z++) {
            int width = spec->sizes[z].width ? spec->sizes[z].width : scene->width;
            int height = spec->sizes[z].height ? spec->sizes[z].height : scene->height;
            for (int t = 0; t < spec->num_techniques; t++) {
                const sweep_technique *tech = &spec->techniques[t];
                if (app_technique_draws(tech->info, scene) == 0) continue;
                size_t combos = grid_size(tech);
                for (size_t c = 0; c < combos; c++) {
                    sweep_job *job = &spec->jobs[spec->num_jobs];
                    *job = (sweep_job){.id = (int)spec->num_jobs,
                                       .scene = s,
                                       .width = width,
                                       .height = height,
                                       .technique = tech};
                    int n = snprintf(job->key, sizeof job->key, "%s/%dx%d/%s", spec->scenes[s].name,
                                     width, height, tech->info->name);
                    size_t rest = c; /* the last axis varies fastest */
                    for (int a = tech->num_axes - 1; a >= 0; a--) {
                        const sweep_axis *axis = &tech->axes[a];
                        meso_option *o = &job->options[a];
                        snprintf(o->technique, sizeof o->technique, "%s", tech->info->name);
                        snprintf(o->name, sizeof o->name, "%s", axis->name);
                        o->value = axis->values[rest % (size_t)axis->num_values];
                        rest /= (size_t)axis->num_values;
                    }
                    job->num_options = tech->num_axes;
                    for (int a = 0; a < tech->num_axes && n > 0; a++) {
                        size_t used = strlen(job->options_text);
                        snprintf(job->options_text + used, sizeof job->options_text - used,
                                 "%s%s=%g", a ? " " : "", job->options[a].name,
                                 job->options[a].value);
                        n += snprintf(job->key + n, sizeof job->key - (size_t)n, "-%s=%g",
                                      job->options[a].name, job->options[a].value);
                    }
                    if (n < 0 || (size_t)n >= sizeof job->key)
                        return spec_error(file, "options", "a job's name is too long");
                    meso_render_desc desc = {.samples = spec->samples};
                    meso_render_desc reference = {.samples = spec->reference_samples};
                    /* the job's frame and the reference's views, kept for the comparison */
                    job->memory_bytes = meso_render_memory_estimate(&desc, width, height) +
                                        (uint64_t)(spec->orbit + 1) *
                                            meso_render_memory_estimate(&reference, width, height);
                    spec->num_jobs++;
                }
            }
        }
    }
    /* the jobs of one scene and size are consecutive: each run shares one reference */
    for (size_t first = 0, end; first < spec->num_jobs; first = end) {
        const sweep_job *a = &spec->jobs[first];
        for (end = first + 1;
             end < spec->num_jobs && spec->jobs[end].scene == a->scene &&
             spec->jobs[end].width == a->width && spec->jobs[end].height == a->height;
             end++) {
        }
        for (size_t i = first; i < end; i++)
            spec->jobs[i].cost_seconds = job_cost(spec, &spec->jobs[i], end - first);
    }
    return -1;
}

/* The hash of everything that decides a job's outputs: scene files, settings, the job list. */
static uint64_t spec_hash(const sweep_spec *spec) {
    char text[256];
    uint64_t h = MESO_HASH_SEED;
    int n = snprintf(text, sizeof text, "meso sweep 1 samples %d %d frames %d orbit %d\n",
                     spec->samples, spec->reference_samples, spec->frames, spec->orbit);
    h = meso_hash64(text, (size_t)n, h);
    for (int s = 0; s < spec->num_scenes; s++) {
        h = meso_hash64(spec->scenes[s].name, strlen(spec->scenes[s].name) + 1, h);
        h = meso_hash64(&spec->scenes[s].file_hash, sizeof spec->scenes[s].file_hash, h);
    }
    for (size_t i = 0; i < spec->num_jobs; i++)
        h = meso_hash64(spec->jobs[i].key, strlen(spec->jobs[i].key) + 1, h);
    return h;
}

int app_sweep_spec_load(meso_context *ctx, const char *path, sweep_spec *spec) {
    *spec = (sweep_spec){.path = path};
    char *text = NULL;
    meso_result r = meso_file_read(ctx, path, SWEEP_MAX_FILE_BYTES, &text, NULL);
    if (r != MESO_OK) return app_fail(ctx, r);
    cJSON *root = cJSON_Parse(text);
    int status = -1;
    if (!root || !cJSON_IsObject(root)) {
        const char *at = cJSON_GetErrorPtr();
        size_t offset = root || !at ? 0 : (size_t)(at - text);
        app_error("%s: not a JSON object (syntax error near byte %zu)", path, offset);
        status = APP_EXIT_BAD_INPUT;
    }
    static const char *const known[] = {"scenes", "techniques", "options",
                                        "sizes",  "samples",    "reference_samples",
                                        "frames", "orbit",      "comment"};
    const cJSON *item;
    if (status < 0) cJSON_ArrayForEach(item, root) {
            bool ok = false;
            for (size_t k = 0; k < sizeof known / sizeof known[0]; k++)
                ok = ok || strcmp(item->string, known[k]) == 0;
            if (!ok) {
                status = spec_error(path, item->string,
                                    "unknown key (known: scenes, techniques, options, sizes, "
                                    "samples, reference_samples, frames, orbit, comment)");
                break;
            }
        }
    if (status < 0) status = read_int(path, root, "samples", 1, 1, 256, &spec->samples);
    if (status < 0)
        status = read_int(path, root, "reference_samples", spec->samples, 1, 256,
                          &spec->reference_samples);
    if (status < 0) status = read_int(path, root, "frames", 5, 1, 1000, &spec->frames);
    if (status < 0) status = read_int(path, root, "orbit", 1, 1, SWEEP_MAX_ORBIT, &spec->orbit);
    if (status < 0) status = read_sizes(path, root, spec);
    if (status < 0) status = read_techniques(path, root, spec);
    if (status < 0) status = read_options(ctx, path, root, spec);
    if (status < 0) status = read_scenes(ctx, path, root, spec);
    if (status < 0) status = expand(path, spec);
    if (status < 0) spec->hash = spec_hash(spec);
    cJSON_Delete(root);
    free(text);
    if (status >= 0) app_sweep_spec_free(spec);
    return status;
}

void app_sweep_spec_free(sweep_spec *spec) {
    for (int s = 0; s < spec->num_scenes; s++) meso_scene_destroy(spec->scenes[s].scene);
    free(spec->jobs);
    spec->jobs = NULL;
    spec->num_scenes = 0;
    spec->num_jobs = 0;
}
