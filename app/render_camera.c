/* Camera and light overrides on the command line, and turntable frames (render_camera.h). */
#include "render_camera.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "meso/runtime.h"

bool app_parse_vec3(const char *text, meso_vec3 *out) {
    double v[3];
    const char *p = text;
    for (int i = 0; i < 3; i++) {
        char *end = NULL;
        v[i] = strtod(p, &end);
        if (end == p || !isfinite(v[i]) || fabs(v[i]) > 1e30) return false;
        if (i < 2 && *end != ',') return false;
        if (i == 2 && *end != 0) return false;
        p = end + 1;
    }
    *out = (meso_vec3){(float)v[0], (float)v[1], (float)v[2]};
    return true;
}

meso_vec3 app_light_direction_stable(meso_vec3 direction) {
    meso_vec3 d = meso_vec3_normalize(direction);
    /* Rounding makes normalize(normalize(x)) differ from normalize(x) in the last bit now and
     * then; a few rounds reach a fixed point (in practice one or two). */
    for (int i = 0; i < 8; i++) {
        meso_vec3 again = meso_vec3_normalize(d);
        if (!memcmp(&again, &d, sizeof(d))) break;
        d = again;
    }
    return d;
}

view_camera app_camera_to_view(const meso_camera *c) {
    return (view_camera){{c->eye.x, c->eye.y, c->eye.z},
                         {c->target.x, c->target.y, c->target.z},
                         {c->up.x, c->up.y, c->up.z},
                         c->fov_y_deg};
}

meso_camera app_camera_from_view(const view_camera *c) {
    return (meso_camera){{(float)c->eye.x, (float)c->eye.y, (float)c->eye.z},
                         {(float)c->target.x, (float)c->target.y, (float)c->target.z},
                         {(float)c->up.x, (float)c->up.y, (float)c->up.z},
                         (float)c->fov_y_deg};
}

static int bad_vector(const char *command, const char *option, const char *text) {
    return app_usage_error(command, "%s: '%s' is not X,Y,Z (three numbers)", option, text);
}

int app_camera_override_apply(const char *command, const app_camera_override *o,
                              meso_scene *scene) {
    meso_camera camera = scene->camera;
    if (o->eye && !app_parse_vec3(o->eye, &camera.eye)) return bad_vector(command, "--eye", o->eye);
    if (o->target && !app_parse_vec3(o->target, &camera.target))
        return bad_vector(command, "--target", o->target);
    if (o->up && !app_parse_vec3(o->up, &camera.up)) return bad_vector(command, "--up", o->up);
    if (o->fov > 0.0) camera.fov_y_deg = (float)o->fov;
    meso_vec3 forward = meso_vec3_sub(camera.target, camera.eye);
    meso_vec3 side = meso_vec3_cross(forward, camera.up);
    /* the same conditions the scene loader puts on a camera, with the same kind of message */
    if (!(meso_vec3_length(forward) > 1e-9f) || !(meso_vec3_length(side) > 1e-9f)) {
        fprintf(stderr,
                "meso: %s: --eye/--target/--up: the eye must differ from the target and "
                "not look along up\n",
                scene->path);
        return APP_EXIT_BAD_INPUT;
    }
    scene->camera = camera;
    if (o->light) {
        meso_vec3 v;
        if (!app_parse_vec3(o->light, &v)) return bad_vector(command, "--light", o->light);
        if (scene->num_lights == 0) {
            scene->lights[0] = (meso_light){.type = MESO_LIGHT_DIRECTIONAL, .color = {1, 1, 1}};
            scene->num_lights = 1;
        }
        meso_light *light = &scene->lights[0];
        if (light->type == MESO_LIGHT_POINT) {
            light->position = v;
        } else if (!(meso_vec3_length(v) > 1e-12f)) {
            return app_usage_error(command, "--light: the direction must not be zero");
        } else {
            light->direction = app_light_direction_stable(v);
        }
    }
    return -1;
}

int app_render_orbit(meso_context *ctx, meso_scene *scene, const meso_render_desc *desc, int width,
                     int height, meso_encoding encoding, const app_orbit_path *orbit,
                     const char *dir, bool quiet) {
    int count = orbit->frames;
    const meso_camera home = scene->camera;
    const view_camera home_view = app_camera_to_view(&home);
    meso_renderer *renderer = NULL;
    meso_framebuffer *fb = NULL;
    meso_progress *progress = NULL;
    double frame_seconds = 0.0;
    char path[4096], name[64];
    meso_result result = app_make_dir(ctx, dir);
    if (result == MESO_OK) result = meso_renderer_create(ctx, scene, desc, &renderer);
    if (result == MESO_OK) result = meso_framebuffer_create(ctx, width, height, &fb);
    if (result == MESO_OK) progress = meso_progress_begin(ctx, "render orbit", (uint64_t)count);
    for (int frame = 0; frame < count && result == MESO_OK; frame++) {
        view_camera camera = view_camera_turntable(&home_view, frame, orbit->period);
        scene->camera = frame == 0 || orbit->period == 0 ? home : app_camera_from_view(&camera);
        snprintf(name, sizeof(name), "frame-%04d.png", frame);
        if (!app_path_join(path, sizeof(path), dir, name)) {
            result = meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: path too long", dir);
            break;
        }
        result = meso_renderer_render(renderer, fb);
        if (result == MESO_OK) result = meso_framebuffer_save_png(ctx, fb, encoding, path, NULL);
        frame_seconds += meso_renderer_get_stats(renderer).last_frame_seconds;
        if (meso_progress_advance(progress, 1)) result = MESO_ERROR_CANCELLED;
    }
    meso_progress_end(progress);
    scene->camera = home;
    if (result == MESO_OK && !quiet) {
        meso_render_stats stats = meso_renderer_get_stats(renderer);
        app_note("render: %d orbit frames %dx%d, prepare %.1f ms, mean frame %.1f ms -> "
                 "%s/frame-%%04d.png",
                 count, width, height, 1000.0 * stats.prepare_seconds,
                 1000.0 * frame_seconds / count, dir);
    }
    int status = result == MESO_OK ? APP_EXIT_OK : app_fail(ctx, result);
    meso_framebuffer_destroy(fb);
    meso_renderer_destroy(renderer);
    return status;
}
