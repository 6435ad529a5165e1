/* meso sweep (docs/sweep.md): a sweep file expanded to jobs (app_sweep_spec.c), the jobs run
 * and their results written (cmd_sweep.c), the reports built from the finished jobs' results
 * (app_sweep_report.c): results.csv, results.json, a plot per scene and size, index.html. */
#ifndef MESO_APP_SWEEP_H
#define MESO_APP_SWEEP_H

#include "app.h"

/* Limits checked while reading a sweep file, before anything is allocated for them. */
#define SWEEP_MAX_SCENES 64
#define SWEEP_MAX_SIZES 16
#define SWEEP_MAX_TECHNIQUES 32
#define SWEEP_MAX_GRID_VALUES 64 /* values of one option */
#define SWEEP_MAX_JOBS 100000
#define SWEEP_MAX_ORBIT 360
#define SWEEP_MAX_FILE_BYTES (1u << 20)
#define SWEEP_KEY_MAX 400 /* "scene/WxH/technique-name=value-..." */

/* One option's values in a grid. */
typedef struct sweep_axis {
    char name[MESO_NAME_MAX];
    double values[SWEEP_MAX_GRID_VALUES];
    int num_values;
} sweep_axis;

/* A technique of the sweep and its option grid (the cartesian product of its axes). */
typedef struct sweep_technique {
    const meso_technique_info *info;
    sweep_axis axes[MESO_OPTIONS_MAX];
    int num_axes;
} sweep_technique;

typedef struct sweep_scene {
    char path[1024]; /* as loaded (relative to the sweep file's folder) */
    char name[256];  /* file name without folder and extension: the folder of its jobs */
    meso_scene *scene;
    uint64_t file_hash; /* of the scene file's bytes: part of the spec's hash */
} sweep_scene;

typedef struct sweep_job {
    int id; /* the index in the expansion order: stable for one spec */
    int scene, width, height;
    const sweep_technique *technique;
    meso_option options[MESO_OPTIONS_MAX]; /* one value of each axis */
    int num_options;
    char key[SWEEP_KEY_MAX]; /* its folder under jobs/, unique */
    char options_text[256];  /* "linear_steps=8 binary_steps=4", "" for the defaults */
    double cost_seconds; /* estimated by the cost model (docs/sweep.md), its reference share too */
    uint64_t memory_bytes; /* estimated frame memory (meso_render_memory_estimate) */
} sweep_job;

typedef struct sweep_spec {
    const char *path;
    sweep_scene scenes[SWEEP_MAX_SCENES];
    int num_scenes;
    app_size sizes[SWEEP_MAX_SIZES]; /* 0 x 0: the scene's own */
    int num_sizes;
    sweep_technique techniques[SWEEP_MAX_TECHNIQUES];
    int num_techniques;
    int samples, reference_samples;
    int frames; /* timed frames a job (median reported) */
    int orbit;  /* views of a turntable a job (1: the scene's camera only) */
    sweep_job *jobs;
    size_t num_jobs;
    uint64_t hash; /* of the expanded spec: shards of one sweep carry the same */
} sweep_spec;

/* Read, check and expand the sweep file at `path`: every scene loaded, every technique, option
 * and value checked, before any job runs. On bad input prints one line "meso: <file>: <key>:
 * <reason>" and returns 2; 1 on other failures; -1 on success. */
int app_sweep_spec_load(meso_context *ctx, const char *path, sweep_spec *out);
void app_sweep_spec_free(sweep_spec *spec);

/* "%016llx" of a hash. */
void app_sweep_hash_text(uint64_t hash, char out[17]);

/* ---- Results and reports (app_sweep_report.c) --------------------------------------------- */

/* One finished job as its result.json holds it. */
typedef struct sweep_row {
    int id;
    char key[SWEEP_KEY_MAX];
    char scene[256];
    char technique[MESO_NAME_MAX];
    char options[256];
    int width, height, samples, views;
    char status[16]; /* ok, failed */
    char note[256];
    double prepare_ms, frame_ms, reference_ms;
    double job_seconds; /* the job's wall time, its scene's references included when it drew them */
    bool has_metrics;
    double psnr_db, psnr_covered_db, rmse, rmse_covered, ssim, max_error, coverage_iou;
    double flicker; /* NAN without orbit */
} sweep_row;

/* Write a row as the job's result.json text (doubles as %.17g: read back to the same bits). */
void app_sweep_row_json(const sweep_row *row, const char *spec_hash, app_text *out);
/* Read a job's result.json. MESO_OK, or MESO_ERROR_IO / MESO_ERROR_INVALID_ARGUMENT (logged)
 * when it is missing or malformed; *out_hash receives its spec hash. */
meso_result app_sweep_row_read(meso_context *ctx, const char *path, sweep_row *row,
                               char out_hash[17]);

/* results.csv, results.json, plots/<scene>-<WxH>.svg/.png and index.html in dir from rows (in
 * job order). */
meso_result app_sweep_write_reports(meso_context *ctx, const char *dir, const sweep_row *rows,
                                    size_t count, const char *spec_hash);

#endif
