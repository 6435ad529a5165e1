/* The frame description: camera basis, matrices and the sample-to-ray mapping shared by the
 * rasterizer and the reference tracer. */
#include <math.h>

#include "render_internal.h"

/* Clip-space near plane (view depth). The rasterizer stores view depth, not z_ndc, so neither
 * plane limits depth precision; nothing is clipped at the far plane (docs/rasterizer.md). */
#define FRAME_Z_NEAR 0.001f
#define FRAME_Z_FAR 1000.0f

void meso_frame_init(meso_frame *frame, const meso_scene *scene, int width, int height) {
    frame->scene = scene;
    frame->progress = NULL;
    frame->filter = false;
    frame->width = width > 0 ? width : 1;
    frame->height = height > 0 ? height : 1;
    const meso_camera *cam = &scene->camera;
    meso_vec3 eye = cam->eye;
    meso_vec3 f = meso_vec3_normalize(meso_vec3_sub(cam->target, eye));
    if (meso_vec3_dot(f, f) == 0.0f || !meso_vec3_is_finite(f)) f = (meso_vec3){0.0f, 0.0f, -1.0f};
    meso_vec3 up = cam->up;
    meso_vec3 s = meso_vec3_normalize(meso_vec3_cross(f, up));
    if (meso_vec3_dot(s, s) == 0.0f || !meso_vec3_is_finite(s)) {
        /* up parallel to the view direction: pick any perpendicular */
        up = fabsf(f.y) < 0.9f ? (meso_vec3){0.0f, 1.0f, 0.0f} : (meso_vec3){1.0f, 0.0f, 0.0f};
        s = meso_vec3_normalize(meso_vec3_cross(f, up));
    }
    meso_vec3 u = meso_vec3_cross(s, f);
    float fov = cam->fov_y_deg;
    if (!(fov > 0.0f && fov < 179.0f)) fov = 40.0f;
    float fov_rad = fov * MESO_PI / 180.0f;
    float aspect = (float)frame->width / (float)frame->height;
    float tan_half = tanf(0.5f * fov_rad);

    frame->eye = eye;
    frame->forward = f;
    frame->z_near = FRAME_Z_NEAR;
    frame->z_far = FRAME_Z_FAR;
    meso_vec3 target = meso_vec3_add(eye, f);
    frame->view = meso_mat4_look_at(eye, target, up);
    frame->projection = meso_mat4_perspective(fov_rad, aspect, FRAME_Z_NEAR, FRAME_Z_FAR);
    frame->view_projection = meso_mat4_mul(frame->projection, frame->view);
    /* On the plane at depth 1 the image spans [-aspect t, aspect t] x [-t, t], t = tan(fov/2):
     * the same mapping as the projection matrix, so sample (x, y) of the rasterizer and
     * meso_frame_ray_direction(x, y) agree. */
    frame->pixel_right = meso_vec3_scale(s, 2.0f * aspect * tan_half / (float)frame->width);
    frame->pixel_down = meso_vec3_scale(u, -2.0f * tan_half / (float)frame->height);
    frame->corner = meso_vec3_add(
        f, meso_vec3_add(meso_vec3_scale(s, -aspect * tan_half), meso_vec3_scale(u, tan_half)));
}

meso_render_camera meso_render_camera_get(const meso_scene *scene, int width, int height) {
    meso_frame frame;
    meso_frame_init(&frame, scene, width, height);
    return (meso_render_camera){.eye = frame.eye,
                                .forward = frame.forward,
                                .view_projection = frame.view_projection,
                                .z_near = frame.z_near,
                                .z_far = frame.z_far,
                                .pixel_size = meso_vec3_length(frame.pixel_right)};
}
