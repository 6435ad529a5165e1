/* meso sweep: scenes x techniques x option grids x sizes (docs/sweep.md), each job measured
 * against the reference, in one process or sharded over many (--shard K/N, then --merge;
 * docs/scale-out.md). Every job's outputs are written all or nothing and its result.json last,
 * so a shard killed and run again skips the jobs it finished. */
#include "app_sweep.h"
#include "render_camera.h"

#include <cjson/cJSON.h>
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include "meso/runtime.h"

typedef enum partition {
    PARTITION_COST = 0, /* contiguous runs of jobs of about equal estimated cost */
    PARTITION_MODULO,   /* job id modulo N */
} partition;

typedef struct sweep_options {
    const char *output;
    const char *shard_text;
    const char *partition_text;
    bool list, dry_run, merge;
    int shard, shards;
    partition partition;
} sweep_options;

static const app_command_help sweep_help = {
    .name = "sweep",
    .usage = "SPEC.json -o DIR [--shard K/N] [options]\n       meso sweep --merge DIR\n"
             "       meso sweep SPEC.json --list | --dry-run [--shard K/N]",
    .summary =
        "Render every job of a sweep file (docs/sweep.md: scenes, techniques, option grids,\n"
        "sizes, samples, orbit views) and measure each against the ray-traced reference,\n"
        "rendered once per scene, view and size. Writes DIR/jobs/<scene>/<WxH>/<job>/ (images,\n"
        "difference images, result.json), DIR/refs/, DIR/results.csv, DIR/results.json,\n"
        "DIR/plots/<scene>-<WxH>.svg/.png (error against frame time, Pareto front drawn) and\n"
        "DIR/index.html. Jobs already finished in DIR are skipped.\n\n"
        "With --shard K/N only shard K of N runs, into DIR/shards/K/; when every shard has\n"
        "run, --merge DIR writes the same reports a single process writes\n"
        "(docs/scale-out.md: Slurm job arrays, GNU parallel, Kubernetes).",
    .examples = "  meso sweep sweep.json -o out\n"
                "  meso sweep sweep.json --list\n"
                "  meso sweep sweep.json --dry-run --shard 0/4\n"
                "  meso sweep sweep.json -o /shared/out --shard 2/4   # on each of 4 machines\n"
                "  meso sweep --merge /shared/out\n",
};

/* ---- Shards ------------------------------------------------------------------------------- */

static int parse_shard(sweep_options *o) {
    if (!o->shard_text) {
        o->shard = 0;
        o->shards = 1;
    } else {
        char *end = NULL;
        long k = strtol(o->shard_text, &end, 10);
        long n = end && *end == '/' ? strtol(end + 1, &end, 10) : -1;
        if (!end || *end || end == o->shard_text || n < 1 || n > SWEEP_MAX_JOBS || k < 0 || k >= n)
            return app_usage_error("sweep", "--shard: '%s' is not K/N with 0 <= K < N",
                                   o->shard_text);
        o->shard = (int)k;
        o->shards = (int)n;
    }
    if (!o->partition_text || strcmp(o->partition_text, "cost") == 0)
        o->partition = PARTITION_COST;
    else if (strcmp(o->partition_text, "modulo") == 0)
        o->partition = PARTITION_MODULO;
    else
        return app_usage_error("sweep", "--partition: '%s' is not cost or modulo",
                               o->partition_text);
    return -1;
}

/* Whether job i starts a new scene and size (a run of jobs sharing one reference). */
static bool starts_group(const sweep_spec *spec, size_t i) {
    if (i == 0 || i >= spec->num_jobs) return true;
    const sweep_job *a = &spec->jobs[i - 1], *b = &spec->jobs[i];
    return a->scene != b->scene || a->width != b->width || a->height != b->height;
}

/* The shard of every job: by id modulo N, or N contiguous runs of about equal estimated cost.
 * Each cut between runs goes to the job boundary nearest to k/N of the total cost, moved to
 * the nearest boundary between scenes (or sizes) when one lies within a quarter of a shard's
 * share: a scene split over two shards has its reference rendered by both, and a solid's
 * reference costs as much as dozens of jobs. */
/* The index in sorted[0..count) of the value nearest to target. */
static size_t nearest(const double *sorted, size_t count, double target) {
    size_t lo = 0, hi = count; /* the first value >= target, by bisection */
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (sorted[mid] < target)
            lo = mid + 1;
        else
            hi = mid;
    }
    if (lo == count) return count - 1;
    if (lo > 0 && target - sorted[lo - 1] <= sorted[lo] - target) return lo - 1;
    return lo;
}

static bool assign_shards(const sweep_spec *spec, const sweep_options *o, int *shard_of) {
    size_t n = spec->num_jobs;
    double total = 0.0;
    for (size_t i = 0; i < n; i++) total += spec->jobs[i].cost_seconds;
    if (o->partition == PARTITION_MODULO || !(total > 0.0) || o->shards == 1) {
        for (size_t i = 0; i < n; i++) shard_of[i] = (int)(i % (size_t)o->shards);
        return true;
    }
    /* before[i]: the cost of jobs 0..i-1; groups: the job indices starting a scene and size,
     * and n, with their `before` */
    double *before = calloc(n + 1, sizeof *before), *group_before = calloc(n + 1, sizeof *before);
    size_t *groups = calloc(n + 1, sizeof *groups), num_groups = 0;
    if (!before || !group_before || !groups) {
        free(before);
        free(group_before);
        free(groups);
        return false;
    }
    for (size_t i = 0; i < n; i++) before[i + 1] = before[i] + spec->jobs[i].cost_seconds;
    for (size_t i = 0; i <= n; i++)
        if (starts_group(spec, i)) {
            groups[num_groups] = i;
            group_before[num_groups++] = before[i];
        }
    double share = total / o->shards;
    size_t previous = 0;
    for (int k = 1; k <= o->shards; k++) {
        size_t cut = n;
        if (k < o->shards) {
            double target = k * share;
            cut = nearest(before, n + 1, target);
            size_t g = nearest(group_before, num_groups, target);
            if (fabs(group_before[g] - target) <= 0.25 * share && groups[g] > previous)
                cut = groups[g];
            if (cut < previous) cut = previous;
        }
        for (size_t i = previous; i < cut; i++) shard_of[i] = k - 1;
        previous = cut;
    }
    free(before);
    free(group_before);
    free(groups);
    return true;
}

/* ---- Files -------------------------------------------------------------------------------- */

static bool join3(char *out, size_t size, const char *a, const char *b, const char *c) {
    char middle[4096];
    return app_path_join(middle, sizeof middle, a, b) && app_path_join(out, size, middle, c);
}

/* spec.json of a sweep folder (a shard's or the whole's): the spec's hash, which shard, and
 * the ids and keys of its jobs, so --merge needs no sweep file. */
static meso_result write_spec_file(meso_context *ctx, const char *dir, const sweep_spec *spec,
                                   const char *hash, int shard, int shards, const int *shard_of) {
    app_text t = {0};
    app_text_printf(&t, "{\n  \"spec_hash\": \"%s\",\n  \"sweep_file\": ", hash);
    app_text_json_string(&t, spec->path);
    app_text_printf(&t,
                    ",\n  \"shard\": %d,\n  \"shards\": %d,\n  \"num_jobs\": %zu,\n  \"jobs\": [",
                    shard, shards, spec->num_jobs);
    bool first = true;
    for (size_t i = 0; i < spec->num_jobs; i++) {
        if (shard_of && shard_of[i] != shard) continue;
        app_text_printf(&t, "%s\n    {\"id\": %d, \"key\": ", first ? "" : ",", spec->jobs[i].id);
        app_text_json_string(&t, spec->jobs[i].key);
        app_text_printf(&t, "}");
        first = false;
    }
    app_text_printf(&t, "\n  ]\n}\n");
    char path[4096];
    meso_result r =
        app_path_join(path, sizeof path, dir, "spec.json")
            ? app_text_write(ctx, &t, path)
            : meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: path too long", dir);
    app_text_free(&t);
    return r;
}

/* A folder's spec.json parsed (caller deletes), or NULL when absent (*missing) or unreadable
 * (logged). */
static cJSON *read_spec_file(meso_context *ctx, const char *dir, bool *missing) {
    char path[4096], *text = NULL;
    *missing = false;
    if (!app_path_join(path, sizeof path, dir, "spec.json")) return NULL;
    struct stat st;
    if (stat(path, &st) != 0) {
        *missing = true;
        return NULL;
    }
    if (meso_file_read(ctx, path, 64u << 20, &text, NULL) != MESO_OK) return NULL;
    cJSON *root = cJSON_Parse(text);
    free(text);
    const cJSON *hash = root ? cJSON_GetObjectItemCaseSensitive(root, "spec_hash") : NULL;
    if (!cJSON_IsString(hash) || strlen(hash->valuestring) != 16) {
        cJSON_Delete(root);
        meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: not a sweep's spec.json", path);
        return NULL;
    }
    return root;
}

/* A folder already holding another sweep's jobs is refused: mixing them would merge results of
 * different specs. */
static int check_folder_spec(meso_context *ctx, const char *dir, const char *hash) {
    bool missing = false;
    cJSON *root = read_spec_file(ctx, dir, &missing);
    if (missing) return -1;
    if (!root) return app_fail(ctx, MESO_ERROR_INVALID_ARGUMENT);
    const char *found = cJSON_GetObjectItemCaseSensitive(root, "spec_hash")->valuestring;
    int status = -1;
    if (strcmp(found, hash) != 0) {
        app_error("%s/spec.json: written by another sweep (spec hash %s, this one %s): use another "
                  "folder",
                  dir, found, hash);
        status = APP_EXIT_BAD_INPUT;
    }
    cJSON_Delete(root);
    return status;
}

static meso_result copy_file(meso_context *ctx, const char *from, const char *to) {
    char *data = NULL;
    size_t size = 0;
    meso_result r = meso_file_read(ctx, from, (size_t)1 << 34, &data, &size);
    if (r == MESO_OK) r = meso_file_write_atomic(ctx, to, data, size);
    free(data);
    return r;
}

/* Copy the regular files of folder `from` (not temporaries) into `to`, made when missing. */
static meso_result copy_folder(meso_context *ctx, const char *from, const char *to) {
    meso_result r = app_make_dir(ctx, to);
    DIR *d = r == MESO_OK ? opendir(from) : NULL;
    if (r == MESO_OK && !d)
        return meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot read: %s", from, strerror(errno));
    struct dirent *e;
    while (r == MESO_OK && (e = readdir(d)) != NULL) {
        char src[4096], dst[4096];
        if (e->d_name[0] == '.' || strstr(e->d_name, ".tmp")) continue;
        if (!app_path_join(src, sizeof src, from, e->d_name) ||
            !app_path_join(dst, sizeof dst, to, e->d_name))
            r = meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: path too long", from);
        struct stat st;
        if (r == MESO_OK && stat(src, &st) == 0 && S_ISREG(st.st_mode))
            r = copy_file(ctx, src, dst);
    }
    if (d) closedir(d);
    return r;
}

/* ---- Running jobs ------------------------------------------------------------------------- */

/* The references of one scene and size, a run per view. */
typedef struct reference_views {
    int scene, width, height; /* -1: none yet */
    app_compare_all *views;
} reference_views;

static void reference_views_free(reference_views *refs, int count) {
    for (int v = 0; refs->views && v < count; v++) app_compare_all_free(&refs->views[v]);
    refs->scene = -1;
}

/* Set the scene's camera to view v of spec->orbit (view 0: the scene's own camera). */
static void set_view(meso_scene *scene, const meso_camera *home, int view, int count) {
    view_camera home_view = app_camera_to_view(home);
    view_camera turned = view_camera_turntable(&home_view, view, count);
    scene->camera = view == 0 ? *home : app_camera_from_view(&turned);
}

/* One view of a job's scene and size, rendered and timed as the sweep file says. */
static app_compare_all_desc view_desc(const sweep_spec *spec, const sweep_job *job,
                                      const meso_scene *scene) {
    return (app_compare_all_desc){.scene = scene,
                                  .width = job->width,
                                  .height = job->height,
                                  .samples = spec->samples,
                                  .reference_samples = spec->reference_samples,
                                  .timing_frames = spec->frames};
}

static meso_result save_srgb(meso_context *ctx, const meso_image *image, const char *dir,
                             const char *name) {
    char path[4096];
    if (!app_path_join(path, sizeof path, dir, name))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: path too long", dir);
    meso_png_desc srgb = {.encoding = MESO_ENCODING_SRGB};
    return meso_image_save_png(ctx, image, path, &srgb);
}

/* Render the reference views of the job's scene and size (unless held) into refs, and write
 * them to base/refs/<scene>/<WxH>/view-NNNN.png. */
static meso_result render_references(meso_context *ctx, const sweep_spec *spec,
                                     const sweep_job *job, const char *base,
                                     reference_views *refs) {
    if (refs->scene == job->scene && refs->width == job->width && refs->height == job->height)
        return MESO_OK;
    reference_views_free(refs, spec->orbit);
    meso_scene *scene = spec->scenes[job->scene].scene;
    const meso_camera home = scene->camera;
    char scene_dir[4096], dir[4096], size[32];
    snprintf(size, sizeof size, "%dx%d", job->width, job->height);
    if (!join3(scene_dir, sizeof scene_dir, base, "refs", spec->scenes[job->scene].name) ||
        !app_path_join(dir, sizeof dir, scene_dir, size))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: path too long", base);
    meso_result r = app_make_dir(ctx, dir);
    const char *none[1] = {NULL};
    for (int v = 0; v < spec->orbit && r == MESO_OK; v++) {
        set_view(scene, &home, v, spec->orbit);
        app_compare_all_desc desc = view_desc(spec, job, scene);
        desc.techniques = none; /* the reference alone */
        desc.with_reference = true;
        r = app_compare_all_render(ctx, &desc, &refs->views[v]);
        const app_run *ref = r == MESO_OK ? &refs->views[v].runs[0] : NULL;
        char name[32];
        snprintf(name, sizeof name, "view-%04d.png", v);
        if (ref && ref->rendered) r = save_srgb(ctx, ref->color, dir, name);
    }
    scene->camera = home;
    refs->scene = job->scene;
    refs->width = job->width;
    refs->height = job->height;
    return r;
}

/* Metric sums over the views of a job. */
static void add_metrics(sweep_row *row, const meso_compare_result *m) {
    row->psnr_db += m->psnr;
    row->psnr_covered_db += m->psnr_covered;
    row->rmse += m->rmse;
    row->rmse_covered += m->rmse_covered;
    row->ssim += m->ssim;
    row->max_error = fmax(row->max_error, m->max_error);
    row->coverage_iou += m->coverage_iou;
}

static void row_from_job(const sweep_spec *spec, const sweep_job *job, sweep_row *row) {
    *row = (sweep_row){.id = job->id,
                       .width = job->width,
                       .height = job->height,
                       .samples = spec->samples,
                       .views = spec->orbit,
                       .flicker = NAN};
    snprintf(row->key, sizeof row->key, "%s", job->key);
    snprintf(row->scene, sizeof row->scene, "%s", spec->scenes[job->scene].name);
    snprintf(row->technique, sizeof row->technique, "%s", job->technique->info->name);
    snprintf(row->options, sizeof row->options, "%s", job->options_text);
    snprintf(row->status, sizeof row->status, "ok");
}

/* One job, every view: images, difference images and result.json into base/jobs/<key>/. */
static meso_result run_job(meso_context *ctx, const sweep_spec *spec, const sweep_job *job,
                           const char *base, const char *hash, reference_views *refs,
                           sweep_row *row) {
    double start = meso_time_seconds();
    row_from_job(spec, job, row);
    char dir[4096];
    if (!join3(dir, sizeof dir, base, "jobs", job->key))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: path too long", base);
    meso_result r = app_make_dir(ctx, dir);
    if (r == MESO_OK) r = render_references(ctx, spec, job, base, refs);
    if (r != MESO_OK) return r;
    meso_scene *scene = spec->scenes[job->scene].scene;
    const meso_camera home = scene->camera;
    app_settings settings = {.count = job->num_options};
    memcpy(settings.items, job->options, sizeof(meso_option) * (size_t)job->num_options);
    const char *technique[1] = {job->technique->info->name};
    app_compare_all previous = {.reference = -1};
    double frame_ms_sum = 0.0, flicker_sum = 0.0;
    int compared = 0;
    for (int v = 0; v < spec->orbit && r == MESO_OK; v++) {
        set_view(scene, &home, v, spec->orbit);
        app_compare_all_desc desc = view_desc(spec, job, scene);
        desc.techniques = technique;
        desc.num_techniques = 1;
        desc.settings = &settings;
        app_compare_all now;
        r = app_compare_all_render(ctx, &desc, &now);
        if (r != MESO_OK) break;
        app_run *run = &now.runs[0];
        const app_run *ref = &refs->views[v].runs[0];
        if (!run->rendered) { /* the technique failed: noted, the sweep goes on */
            snprintf(row->status, sizeof row->status, "failed");
            snprintf(row->note, sizeof row->note, "%s", run->note);
            app_compare_all_free(&now);
            break;
        }
        if (v == 0) {
            row->prepare_ms = run->prepare_ms;
            row->reference_ms = ref->rendered ? ref->frame_ms : 0.0;
            snprintf(row->note, sizeof row->note, "%s", run->note);
        }
        frame_ms_sum += run->frame_ms;
        app_run_compare(ctx, run, ref);
        char name[32];
        snprintf(name, sizeof name, "view-%04d.png", v);
        r = save_srgb(ctx, run->color, dir, name);
        if (r == MESO_OK && run->has_metrics) {
            add_metrics(row, &run->metrics);
            compared++;
            meso_image *diff = NULL;
            snprintf(name, sizeof name, "diff-%04d.png", v);
            r = meso_image_diff(ctx, run->color, ref->color, 0.0f, &diff);
            /* a false-colour map: its values are the colours to show, stored as they are */
            char path[4096];
            meso_png_desc raw = {.encoding = MESO_ENCODING_LINEAR};
            if (r == MESO_OK && app_path_join(path, sizeof path, dir, name))
                r = meso_image_save_png(ctx, diff, path, &raw);
            meso_image_destroy(diff);
        }
        if (v > 0 && run->has_metrics && previous.num_runs)
            flicker_sum += app_flicker_between(previous.runs[0].color, run->color,
                                               refs->views[v - 1].runs[0].color, ref->color);
        app_compare_all_free(&previous);
        previous = now;
    }
    app_compare_all_free(&previous);
    scene->camera = home;
    if (r != MESO_OK) return r;
    if (strcmp(row->status, "ok") == 0) {
        row->frame_ms = frame_ms_sum / spec->orbit;
        row->has_metrics = compared == spec->orbit;
        if (row->has_metrics) {
            row->psnr_db /= compared;
            row->psnr_covered_db /= compared;
            row->rmse /= compared;
            row->rmse_covered /= compared;
            row->ssim /= compared;
            row->coverage_iou /= compared;
            if (spec->orbit > 1) row->flicker = flicker_sum / (spec->orbit - 1);
        }
    }
    row->job_seconds = meso_time_seconds() - start;
    app_text json = {0};
    app_sweep_row_json(row, hash, &json);
    char path[4096];
    if (app_path_join(path, sizeof path, dir, "result.json")) r = app_text_write(ctx, &json, path);
    app_text_free(&json);
    return r;
}

/* Whether the job's result.json is there, of this spec (then the job is skipped). */
static bool job_finished(meso_context *ctx, const char *base, const sweep_job *job,
                         const char *hash) {
    char folder[4096], path[4096];
    struct stat st;
    if (!join3(folder, sizeof folder, base, "jobs", job->key) ||
        !app_path_join(path, sizeof path, folder, "result.json") || stat(path, &st) != 0)
        return false;
    sweep_row row;
    char found[17];
    return app_sweep_row_read(ctx, path, &row, found) == MESO_OK && strcmp(found, hash) == 0 &&
           row.id == job->id;
}

/* Read the rows of every job (in id order) from dir/jobs/<key>/result.json. */
static meso_result read_rows(meso_context *ctx, const char *dir, const char *const *keys,
                             size_t count, const char *hash, sweep_row *rows) {
    for (size_t i = 0; i < count; i++) {
        char folder[4096], path[4096], found[17];
        if (!join3(folder, sizeof folder, dir, "jobs", keys[i]) ||
            !app_path_join(path, sizeof path, folder, "result.json"))
            return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: path too long", dir);
        meso_result r = app_sweep_row_read(ctx, path, &rows[i], found);
        if (r != MESO_OK) return r;
        if (strcmp(found, hash) != 0)
            return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                                  "%s: written by another sweep (spec hash %s, not %s)", path,
                                  found, hash);
    }
    return MESO_OK;
}

static int run_sweep(meso_context *ctx, sweep_spec *spec, const sweep_options *o,
                     const int *shard_of, bool quiet) {
    char hash[17], base[4096];
    app_sweep_hash_text(spec->hash, hash);
    if (o->shard_text) {
        char shard[32];
        snprintf(shard, sizeof shard, "%d", o->shard);
        if (!join3(base, sizeof base, o->output, "shards", shard))
            return app_usage_error("sweep", "%s: path too long", o->output);
    } else {
        snprintf(base, sizeof base, "%s", o->output);
    }
    meso_result r = app_make_dir(ctx, base);
    if (r != MESO_OK) return app_fail(ctx, r);
    int status = check_folder_spec(ctx, base, hash);
    if (status >= 0) return status;
    r = write_spec_file(ctx, base, spec, hash, o->shard, o->shards,
                        o->shard_text ? shard_of : NULL);
    if (r != MESO_OK) return app_fail(ctx, r);

    size_t mine = 0, done = 0;
    for (size_t i = 0; i < spec->num_jobs; i++)
        if (shard_of[i] == o->shard) {
            mine++;
            done += job_finished(ctx, base, &spec->jobs[i], hash);
        }
    if (!quiet)
        fprintf(stderr, "meso: sweep: %s%zu jobs, %zu already done, %zu to run -> %s\n",
                o->shard_text ? "this shard: " : "", mine, done, mine - done, base);
    reference_views refs = {.scene = -1,
                            .views = calloc((size_t)spec->orbit, sizeof(app_compare_all))};
    if (!refs.views)
        return app_fail(ctx, meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "out of memory"));
    meso_progress *progress = meso_progress_begin(ctx, "sweep", mine - done);
    size_t ran = 0;
    for (size_t i = 0; i < spec->num_jobs && r == MESO_OK; i++) {
        const sweep_job *job = &spec->jobs[i];
        if (shard_of[i] != o->shard || job_finished(ctx, base, job, hash)) continue;
        sweep_row row;
        r = run_job(ctx, spec, job, base, hash, &refs, &row);
        ran++;
        if (r == MESO_OK && !quiet) {
            if (row.has_metrics)
                fprintf(stderr, "meso: sweep: [%zu/%zu] job %d %s: %.2f ms, %.2f dB covered\n", ran,
                        mine - done, job->id, job->key, row.frame_ms, row.psnr_covered_db);
            else
                fprintf(stderr, "meso: sweep: [%zu/%zu] job %d %s: %s%s%s\n", ran, mine - done,
                        job->id, job->key, row.status, row.note[0] ? ": " : "", row.note);
        }
        if (meso_progress_advance(progress, 1)) r = MESO_ERROR_CANCELLED;
    }
    meso_progress_end(progress);
    reference_views_free(&refs, spec->orbit);
    free(refs.views);
    if (r != MESO_OK) return app_fail(ctx, r);
    if (o->shard_text) return APP_EXIT_OK; /* --merge writes the reports */

    sweep_row *rows = calloc(spec->num_jobs, sizeof *rows);
    const char **keys = calloc(spec->num_jobs, sizeof *keys);
    r = rows && keys ? MESO_OK : meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "out of memory");
    for (size_t i = 0; r == MESO_OK && i < spec->num_jobs; i++) keys[i] = spec->jobs[i].key;
    if (r == MESO_OK) r = read_rows(ctx, base, keys, spec->num_jobs, hash, rows);
    if (r == MESO_OK) r = app_sweep_write_reports(ctx, base, rows, spec->num_jobs, hash);
    if (r == MESO_OK && !quiet)
        fprintf(stderr,
                "meso: sweep: %zu jobs: results.csv, results.json, plots/ and index.html in %s\n",
                spec->num_jobs, base);
    free(rows);
    free(keys);
    return r == MESO_OK ? APP_EXIT_OK : app_fail(ctx, r);
}

/* ---- Merge -------------------------------------------------------------------------------- */

typedef struct merge_job {
    char key[SWEEP_KEY_MAX];
    int shard; /* -1: no shard has it */
} merge_job;

/* Read DIR/shards/<K>/spec.json of every shard, check they are one sweep's, complete and
 * finished, copy their jobs and references into DIR and write the reports. */
static int merge(meso_context *ctx, const char *dir, bool quiet) {
    char shards_dir[4096];
    if (!app_path_join(shards_dir, sizeof shards_dir, dir, "shards"))
        return app_usage_error("sweep", "%s: path too long", dir);
    DIR *d = opendir(shards_dir);
    if (!d) {
        app_error("%s: no shards to merge: %s", shards_dir, strerror(errno));
        return APP_EXIT_BAD_INPUT;
    }
    char hash[17] = "", first_file[4096] = "", sweep_file[1024] = "";
    int shards = 0, seen = 0;
    long num_jobs = -1;
    merge_job *jobs = NULL;
    int status = -1;
    bool shard_seen[4096] = {false};
    struct dirent *e;
    while (status < 0 && (e = readdir(d)) != NULL) {
        if (e->d_name[0] == '.') continue;
        char shard_dir[4096];
        bool missing = false;
        if (!app_path_join(shard_dir, sizeof shard_dir, shards_dir, e->d_name)) continue;
        cJSON *root = read_spec_file(ctx, shard_dir, &missing);
        if (!root) {
            if (missing) continue; /* not a shard folder */
            status = app_fail(ctx, MESO_ERROR_INVALID_ARGUMENT);
            break;
        }
        const cJSON *h = cJSON_GetObjectItemCaseSensitive(root, "spec_hash");
        const cJSON *k = cJSON_GetObjectItemCaseSensitive(root, "shard");
        const cJSON *n = cJSON_GetObjectItemCaseSensitive(root, "shards");
        const cJSON *count = cJSON_GetObjectItemCaseSensitive(root, "num_jobs");
        const cJSON *list = cJSON_GetObjectItemCaseSensitive(root, "jobs");
        const cJSON *file = cJSON_GetObjectItemCaseSensitive(root, "sweep_file");
        if (!cJSON_IsNumber(k) || !cJSON_IsNumber(n) || !cJSON_IsNumber(count) ||
            !cJSON_IsArray(list) || n->valueint < 1 || n->valueint > 4096 || k->valueint < 0 ||
            k->valueint >= n->valueint || count->valuedouble < 1 ||
            count->valuedouble > SWEEP_MAX_JOBS) {
            app_error("%s/spec.json: not a shard's spec.json", shard_dir);
            status = APP_EXIT_BAD_INPUT;
        } else if (!jobs) {
            snprintf(hash, sizeof hash, "%s", h->valuestring);
            app_path_join(first_file, sizeof first_file, shard_dir, "spec.json");
            if (cJSON_IsString(file))
                snprintf(sweep_file, sizeof sweep_file, "%s", file->valuestring);
            shards = n->valueint;
            num_jobs = (long)count->valuedouble;
            jobs = calloc((size_t)num_jobs, sizeof *jobs);
            for (long i = 0; jobs && i < num_jobs; i++) jobs[i].shard = -1;
            if (!jobs)
                status =
                    app_fail(ctx, meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "out of memory"));
        }
        if (status < 0 && strcmp(h->valuestring, hash) != 0) {
            app_error("%s/spec.json: a shard of another sweep (spec hash %s; %s has %s): shards of "
                      "different sweep files cannot be merged",
                      shard_dir, h->valuestring, first_file, hash);
            status = APP_EXIT_BAD_INPUT;
        } else if (status < 0 && (n->valueint != shards || (long)count->valuedouble != num_jobs ||
                                  strcmp(e->d_name, "") == 0 || atoi(e->d_name) != k->valueint)) {
            app_error("%s/spec.json: shard %d of %d, but %s says %d shards", shard_dir, k->valueint,
                      n->valueint, first_file, shards);
            status = APP_EXIT_BAD_INPUT;
        }
        const cJSON *job;
        if (status < 0) cJSON_ArrayForEach(job, list) {
                const cJSON *id = cJSON_GetObjectItemCaseSensitive(job, "id");
                const cJSON *key = cJSON_GetObjectItemCaseSensitive(job, "key");
                if (!cJSON_IsNumber(id) || id->valueint < 0 || id->valueint >= num_jobs ||
                    !cJSON_IsString(key) || strlen(key->valuestring) >= SWEEP_KEY_MAX ||
                    strstr(key->valuestring, "..") || key->valuestring[0] == '/' ||
                    jobs[id->valueint].shard >= 0) {
                    app_error("%s/spec.json: jobs: a bad or repeated job", shard_dir);
                    status = APP_EXIT_BAD_INPUT;
                    break;
                }
                jobs[id->valueint].shard = k->valueint;
                snprintf(jobs[id->valueint].key, SWEEP_KEY_MAX, "%s", key->valuestring);
            }
        if (status < 0) {
            shard_seen[k->valueint] = true;
            seen++;
        }
        cJSON_Delete(root);
    }
    closedir(d);
    if (status < 0 && !jobs) {
        app_error("%s: no shard has run yet", shards_dir);
        status = APP_EXIT_BAD_INPUT;
    }
    for (int k = 0; status < 0 && k < shards; k++)
        if (!shard_seen[k]) {
            app_error("%s/%d: missing: shard %d of %d has not run", shards_dir, k, k, shards);
            status = APP_EXIT_BAD_INPUT;
        }
    for (long i = 0; status < 0 && i < num_jobs; i++)
        if (jobs[i].shard < 0) {
            app_error("%s: job %ld is in no shard", shards_dir, i);
            status = APP_EXIT_BAD_INPUT;
        }
    (void)seen;
    /* every job finished, before anything is copied */
    sweep_row *rows = status < 0 ? calloc((size_t)num_jobs, sizeof *rows) : NULL;
    if (status < 0 && !rows)
        status = app_fail(ctx, meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "out of memory"));
    for (long i = 0; status < 0 && i < num_jobs; i++) {
        char shard_dir[4096], shard[32], folder[4096], path[4096], found[17];
        snprintf(shard, sizeof shard, "%d", jobs[i].shard);
        join3(shard_dir, sizeof shard_dir, dir, "shards", shard);
        if (!join3(folder, sizeof folder, shard_dir, "jobs", jobs[i].key) ||
            !app_path_join(path, sizeof path, folder, "result.json"))
            continue;
        struct stat st;
        if (stat(path, &st) != 0) {
            app_error("%s: missing: shard %d has not finished (run it again: it skips the jobs it "
                      "finished)",
                      path, jobs[i].shard);
            status = APP_EXIT_BAD_INPUT;
        } else if (app_sweep_row_read(ctx, path, &rows[i], found) != MESO_OK) {
            status = app_fail(ctx, MESO_ERROR_INVALID_ARGUMENT);
        } else if (strcmp(found, hash) != 0 || rows[i].id != i) {
            app_error("%s: written by another sweep (spec hash %s, not %s)", path, found, hash);
            status = APP_EXIT_BAD_INPUT;
        }
    }
    /* a folder holding the results of another sweep is not overwritten */
    if (status < 0) status = check_folder_spec(ctx, dir, hash);
    meso_result r = MESO_OK;
    for (long i = 0; status < 0 && r == MESO_OK && i < num_jobs; i++) {
        char shard_dir[4096], shard[32], from[4096], to[4096];
        snprintf(shard, sizeof shard, "%d", jobs[i].shard);
        join3(shard_dir, sizeof shard_dir, dir, "shards", shard);
        join3(from, sizeof from, shard_dir, "jobs", jobs[i].key);
        join3(to, sizeof to, dir, "jobs", jobs[i].key);
        r = copy_folder(ctx, from, to);
        /* the job's references: refs/<scene>/<WxH>, the key's first two parts */
        const char *slash = strchr(jobs[i].key, '/');
        slash = slash ? strchr(slash + 1, '/') : NULL;
        char refs_key[SWEEP_KEY_MAX];
        snprintf(refs_key, sizeof refs_key, "%.*s", slash ? (int)(slash - jobs[i].key) : 0,
                 jobs[i].key);
        bool new_refs = i == 0 || strncmp(jobs[i - 1].key, refs_key, strlen(refs_key)) != 0 ||
                        jobs[i - 1].key[strlen(refs_key)] != '/';
        if (r == MESO_OK && slash && new_refs) {
            join3(from, sizeof from, shard_dir, "refs", refs_key);
            join3(to, sizeof to, dir, "refs", refs_key);
            r = copy_folder(ctx, from, to);
        }
    }
    if (status < 0 && r == MESO_OK) {
        /* the same spec.json a single process writes */
        app_text t = {0};
        app_text_printf(&t, "{\n  \"spec_hash\": \"%s\",\n  \"sweep_file\": ", hash);
        app_text_json_string(&t, sweep_file);
        app_text_printf(&t,
                        ",\n  \"shard\": 0,\n  \"shards\": 1,\n  \"num_jobs\": %ld,\n  \"jobs\": [",
                        num_jobs);
        for (long i = 0; i < num_jobs; i++) {
            app_text_printf(&t, "%s\n    {\"id\": %ld, \"key\": ", i ? "," : "", i);
            app_text_json_string(&t, jobs[i].key);
            app_text_printf(&t, "}");
        }
        app_text_printf(&t, "\n  ]\n}\n");
        char path[4096];
        if (app_path_join(path, sizeof path, dir, "spec.json")) r = app_text_write(ctx, &t, path);
        app_text_free(&t);
    }
    if (status < 0 && r == MESO_OK)
        r = app_sweep_write_reports(ctx, dir, rows, (size_t)num_jobs, hash);
    if (status < 0) status = r == MESO_OK ? APP_EXIT_OK : app_fail(ctx, r);
    if (status == APP_EXIT_OK && !quiet)
        fprintf(stderr,
                "meso: sweep: merged %d shards, %ld jobs: results.csv, results.json, plots/ and "
                "index.html in %s\n",
                shards, num_jobs, dir);
    free(rows);
    free(jobs);
    return status;
}

/* ---- List and dry run --------------------------------------------------------------------- */

static void print_list(const sweep_spec *spec, const sweep_options *o, const int *shard_of) {
    printf("%6s %5s %9s  %s\n", "id", "shard", "est. s", "job");
    for (size_t i = 0; i < spec->num_jobs; i++) {
        if (o->shard_text && shard_of[i] != o->shard) continue;
        printf("%6d %5d %9.2f  %s\n", spec->jobs[i].id, shard_of[i], spec->jobs[i].cost_seconds,
               spec->jobs[i].key);
    }
}

static void print_dry_run(meso_context *ctx, const sweep_spec *spec, const sweep_options *o,
                          const int *shard_of) {
    double *seconds = calloc((size_t)o->shards, sizeof *seconds);
    size_t *counts = calloc((size_t)o->shards, sizeof *counts);
    if (!seconds || !counts) {
        free(seconds);
        free(counts);
        return;
    }
    uint64_t memory = 0;
    double total = 0.0;
    for (size_t i = 0; i < spec->num_jobs; i++) {
        seconds[shard_of[i]] += spec->jobs[i].cost_seconds;
        counts[shard_of[i]]++;
        total += spec->jobs[i].cost_seconds;
        if (spec->jobs[i].memory_bytes > memory) memory = spec->jobs[i].memory_bytes;
    }
    char hash[17];
    app_sweep_hash_text(spec->hash, hash);
    printf("sweep %s: %zu jobs (%d scenes, %d sizes, %d techniques), spec hash %s\n", spec->path,
           spec->num_jobs, spec->num_scenes, spec->num_sizes, spec->num_techniques, hash);
    printf("estimated time: %.0f s in one process on this machine's cores (prepare and bakes "
           "not included)\n",
           total);
    printf("estimated frame memory: %.1f MiB at most a job (the scenes besides; limit %.1f "
           "GiB)\n",
           (double)memory / (1024.0 * 1024.0),
           (double)meso_context_memory_limit(ctx) / (1024.0 * 1024.0 * 1024.0));
    if (o->shards > 1)
        for (int k = 0; k < o->shards; k++)
            printf("shard %d/%d: %zu jobs, %.0f s%s\n", k, o->shards, counts[k], seconds[k],
                   o->shard_text && k == o->shard ? " (this one)" : "");
    free(seconds);
    free(counts);
}

/* ---- The command -------------------------------------------------------------------------- */

int meso_cmd_sweep(int argc, char **argv) {
    sweep_options o = {0};
    const app_option options[] = {
        {"--output", "-o", APP_OPTION_STRING, &o.output, "DIR", "the folder of the results",
         "required to run", 0, 0},
        {"--shard", NULL, APP_OPTION_STRING, &o.shard_text, "K/N",
         "run shard K of N only (0 <= K < N), into DIR/shards/K", NULL, 0, 0},
        {"--partition", NULL, APP_OPTION_STRING, &o.partition_text, "cost|modulo",
         "how jobs are dealt to shards: contiguous runs of equal estimated cost, or id modulo N",
         "cost", 0, 0},
        {"--list", NULL, APP_OPTION_FLAG, &o.list, NULL,
         "print the jobs (id, shard, estimated seconds, name) and exit", NULL, 0, 0},
        {"--dry-run", NULL, APP_OPTION_FLAG, &o.dry_run, NULL,
         "print the job count, estimated time and memory (per shard with --shard) and exit", NULL,
         0, 0},
        {"--merge", NULL, APP_OPTION_FLAG, &o.merge, NULL,
         "merge the shards of DIR (the positional argument) into DIR's reports", NULL, 0, 0},
    };
    app_globals globals;
    const char *positionals[2];
    int num_positionals = 0;
    int status = app_parse_options(&sweep_help, options, sizeof options / sizeof options[0], argc,
                                   argv, &globals, positionals, 2, &num_positionals);
    if (status >= 0) return status;
    if (num_positionals != 1)
        return app_usage_error("sweep",
                               o.merge ? "--merge takes one folder" : "expected one sweep file");
    if ((status = parse_shard(&o)) >= 0) return status;
    if (o.merge && (o.output || o.shard_text || o.list || o.dry_run))
        return app_usage_error("sweep", "--merge DIR takes no other option");
    if (!o.merge && !o.list && !o.dry_run && !o.output)
        return app_usage_error("sweep", "missing -o DIR");
    meso_context *ctx = app_context_create(&globals);
    if (!ctx) return APP_EXIT_FAILURE;
    if (o.merge) {
        status = merge(ctx, positionals[0], globals.quiet);
        meso_context_destroy(ctx);
        return status;
    }
    sweep_spec spec;
    status = app_sweep_spec_load(ctx, positionals[0], &spec);
    if (status >= 0) {
        meso_context_destroy(ctx);
        return status;
    }
    int *shard_of = calloc(spec.num_jobs, sizeof *shard_of);
    if (!shard_of) {
        status = app_fail(ctx, meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "out of memory"));
    } else {
        if (!assign_shards(&spec, &o, shard_of)) {
            status = app_fail(ctx, meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "out of memory"));
        } else if (o.list)
            print_list(&spec, &o, shard_of);
        else if (o.dry_run)
            print_dry_run(ctx, &spec, &o, shard_of);
        else
            status = run_sweep(ctx, &spec, &o, shard_of, globals.quiet);
    }
    if (status < 0) status = APP_EXIT_OK;
    free(shard_of);
    app_sweep_spec_free(&spec);
    meso_context_destroy(ctx);
    return status;
}
