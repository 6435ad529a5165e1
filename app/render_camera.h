/* Camera and light on the command line, shared by `meso render` and `meso view`: --eye,
 * --target, --fov and --light override the scene's camera and first light, and
 * `meso render --orbit N -o DIR` writes a turntable of N frames (docs/cli.md, docs/viewer.md).
 */
#ifndef MESO_APP_RENDER_CAMERA_H
#define MESO_APP_RENDER_CAMERA_H

#include "app.h"
#include "view_state.h"

/* The overrides as given ("X,Y,Z" texts point into argv; fov 0 = the scene's). */
typedef struct app_camera_override {
    const char *eye, *target, *up, *light;
    double fov;
} app_camera_override;

/* The five option rows of an app_camera_override `o`, for a command's option table. */
#define APP_CAMERA_OVERRIDE_OPTIONS(o)                                                             \
    {"--eye", NULL, APP_OPTION_STRING, &(o).eye, "X,Y,Z", "the camera's position", "the scene's",  \
     0,       0},                                                                                  \
        {"--target",    NULL,    APP_OPTION_STRING,                                                \
         &(o).target,   "X,Y,Z", "the point the camera looks at",                                  \
         "the scene's", 0,       0},                                                               \
        {"--up",        NULL,    APP_OPTION_STRING,                                                \
         &(o).up,       "X,Y,Z", "the camera's up direction (to look straight down, 0,0,-1)",      \
         "the scene's", 0,       0},                                                               \
        {"--fov",       NULL, APP_OPTION_DOUBLE,                                                   \
         &(o).fov,      "D",  "vertical field of view, degrees",                                   \
         "the scene's", 1,    179},                                                                \
    {                                                                                              \
        "--light", NULL, APP_OPTION_STRING, &(o).light, "X,Y,Z",                                   \
            "the first light: direction toward it (directional) or position (point); a scene "     \
            "without "                                                                             \
            "lights gets a white directional one",                                                 \
            "the scene's", 0, 0                                                                    \
    }

/* Apply the overrides to the scene. A malformed value prints a usage error for `command` and
 * returns 2; an eye on the target or an unusable up prints "meso: <scene>: ..." and returns 2;
 * otherwise -1 (go on). */
int app_camera_override_apply(const char *command, const app_camera_override *o, meso_scene *scene);

/* "X,Y,Z" (three finite numbers) into out; false when malformed. */
bool app_parse_vec3(const char *text, meso_vec3 *out);

/* A unit direction that normalising again leaves unchanged to the bit, so a light written to
 * a scene file (which the loader normalises) renders with the same bits when read back. */
meso_vec3 app_light_direction_stable(meso_vec3 direction);

/* Between the scene's camera (floats) and the viewer's (doubles); float -> double -> float
 * gives back the same bits. */
view_camera app_camera_to_view(const meso_camera *camera);
meso_camera app_camera_from_view(const view_camera *camera);

/* A turntable about the scene camera's up axis through its target: `frames` frames, frame k
 * turned by 360 k / period degrees (period 0: every frame the scene's view, a still camera;
 * frame 0 is always the scene's view). */
typedef struct app_orbit_path {
    int frames;
    int period;
} app_orbit_path;

/* Render the frames of `path` with one renderer into dir/frame-0000.png, ... (numbered for
 * ffmpeg). Prints a summary line unless quiet. The scene's camera is changed during the call
 * and restored. Returns an exit status. */
int app_render_orbit(meso_context *ctx, meso_scene *scene, const meso_render_desc *desc, int width,
                     int height, meso_encoding encoding, const app_orbit_path *path,
                     const char *dir, bool quiet);

/* The reference (with reference_samples a pixel; 0: desc->samples) and each technique of
 * `names` that can draw the scene along `path`, into dir/<name>/frame-0000.png ... (one that
 * cannot draw the scene is skipped with a note), each frame compared with the reference's of
 * the same view; prints per run the mean frame time, the mean PSNR (whole and covered) over
 * the frames, the change (mean |A_k - A_k-1|) and the flicker
 * (mean |(A_k - A_k-1) - (R_k - R_k-1)|), each also over the reference's change, and writes
 * them to dir/temporal.csv (docs/compare.md, "Motion: change and flicker"). Returns an exit
 * status. */
int app_render_orbit_measured(meso_context *ctx, meso_scene *scene, const char *const *names,
                              int num_names, const meso_render_desc *desc, int reference_samples,
                              const app_orbit_path *path, int width, int height,
                              meso_encoding encoding, const char *dir, bool quiet);

/* Mean over pixels and channels of |a1 - a0|: how much an image sequence changes from one
 * frame to the next. Same sizes. */
double app_image_change(const meso_image *a0, const meso_image *a1);
/* Mean over pixels and channels of |(a1 - a0) - (r1 - r0)|: how much a technique's change
 * from one frame to the next differs from the truth's, the error that shows as flicker when
 * the frames play as an animation. Same sizes. */
double app_flicker_between(const meso_image *a0, const meso_image *a1, const meso_image *r0,
                           const meso_image *r1);

#endif
