/* The viewer's window-free logic: camera maths, light dragging, bindings, state, adaptive
 * resolution (view_state.h). */
#include "view_state.h"

#include <math.h>
#include <string.h>

#include "meso/math.h"
#include "meso/render.h"

#define DEGREES (MESO_PI_D / 180.0)
#define ORBIT_DEGREES_PER_PIXEL 0.4
#define LIGHT_DEGREES_PER_PIXEL 0.4
#define ZOOM_PER_STEP 0.9
/* Polar angle limits: 1 degree off the pole keeps right = forward x up well defined. */
#define MIN_POLAR_DEG 1.0
#define MAX_POLAR_DEG 179.0

/* ---- Vectors ------------------------------------------------------------------------------ */

static view_vec3 add(view_vec3 a, view_vec3 b) {
    return (view_vec3){a.x + b.x, a.y + b.y, a.z + b.z};
}
static view_vec3 sub(view_vec3 a, view_vec3 b) {
    return (view_vec3){a.x - b.x, a.y - b.y, a.z - b.z};
}
static view_vec3 scale(view_vec3 a, double s) { return (view_vec3){a.x * s, a.y * s, a.z * s}; }
static double dot(view_vec3 a, view_vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static view_vec3 cross(view_vec3 a, view_vec3 b) {
    return (view_vec3){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
static double length(view_vec3 a) { return sqrt(dot(a, a)); }
static view_vec3 normalize_or(view_vec3 a, view_vec3 fallback) {
    double len = length(a);
    return len > 1e-12 && isfinite(len) ? scale(a, 1.0 / len) : fallback;
}
static double clamp(double v, double lo, double hi) { return v < lo ? lo : v > hi ? hi : v; }

/* Any unit vector perpendicular to unit n. */
static view_vec3 any_perpendicular(view_vec3 n) {
    view_vec3 axis = fabs(n.x) < 0.9 ? (view_vec3){1, 0, 0} : (view_vec3){0, 1, 0};
    return normalize_or(cross(n, axis), (view_vec3){0, 0, 1});
}

/* Turn `offset` about unit `up` by yaw and toward up by pitch, in polar coordinates about up
 * (so repeated drags never accumulate a roll), keeping its length and its polar angle within
 * [min_polar, max_polar] degrees. */
static view_vec3 turn_polar(view_vec3 offset, view_vec3 up, double yaw_deg, double pitch_deg,
                            double min_polar_deg, double max_polar_deg) {
    double radius = length(offset);
    if (!(radius > 0.0)) return offset;
    view_vec3 direction = scale(offset, 1.0 / radius);
    double polar = acos(clamp(dot(direction, up), -1.0, 1.0)) / DEGREES;
    view_vec3 horizontal = sub(direction, scale(up, dot(direction, up)));
    horizontal = normalize_or(horizontal, any_perpendicular(up));
    double yaw = yaw_deg * DEGREES;
    horizontal = add(scale(horizontal, cos(yaw)), scale(cross(up, horizontal), sin(yaw)));
    polar = clamp(polar - pitch_deg, min_polar_deg, max_polar_deg) * DEGREES;
    return scale(add(scale(up, cos(polar)), scale(horizontal, sin(polar))), radius);
}

/* ---- Camera maths ------------------------------------------------------------------------- */

void view_camera_orbit(view_camera *camera, double yaw_deg, double pitch_deg) {
    view_vec3 up = normalize_or(camera->up, (view_vec3){0, 1, 0});
    view_vec3 offset = sub(camera->eye, camera->target);
    camera->eye = add(camera->target,
                      turn_polar(offset, up, yaw_deg, pitch_deg, MIN_POLAR_DEG, MAX_POLAR_DEG));
}

void view_camera_pan(view_camera *camera, double dx, double dy, int viewport_height) {
    if (viewport_height <= 0) return;
    view_vec3 offset = sub(camera->eye, camera->target);
    double distance = length(offset);
    view_vec3 forward = normalize_or(scale(offset, -1.0), (view_vec3){0, 0, -1});
    view_vec3 right = normalize_or(cross(forward, camera->up), any_perpendicular(forward));
    view_vec3 camera_up = cross(right, forward);
    /* the height of the view at the target's depth, spread over the viewport's pixels */
    double pixel = 2.0 * distance * tan(0.5 * camera->fov_y_deg * DEGREES) / viewport_height;
    view_vec3 move = add(scale(right, -dx * pixel), scale(camera_up, dy * pixel));
    camera->eye = add(camera->eye, move);
    camera->target = add(camera->target, move);
}

void view_camera_zoom(view_camera *camera, double steps, double min_distance, double max_distance) {
    view_vec3 offset = sub(camera->eye, camera->target);
    double distance = length(offset);
    if (!(distance > 0.0)) return;
    double wanted = clamp(distance * pow(ZOOM_PER_STEP, steps), min_distance, max_distance);
    camera->eye = add(camera->target, scale(offset, wanted / distance));
}

view_camera view_camera_turntable(const view_camera *home, int frame, int count) {
    view_camera camera = *home;
    if (count <= 0 || frame % count == 0) return camera; /* frame 0 is the scene's camera */
    view_vec3 up = normalize_or(home->up, (view_vec3){0, 1, 0});
    view_vec3 offset = sub(home->eye, home->target);
    double angle = 2.0 * MESO_PI_D * (double)frame / (double)count;
    /* Rodrigues about up: the height along up is kept exactly, unlike the polar clamp */
    view_vec3 along = scale(up, dot(offset, up));
    view_vec3 across = sub(offset, along);
    view_vec3 turned = add(scale(across, cos(angle)), scale(cross(up, across), sin(angle)));
    camera.eye = add(home->target, add(along, turned));
    return camera;
}

view_vec3 view_light_turn(view_vec3 direction, const view_camera *camera, double yaw_deg,
                          double pitch_deg) {
    view_vec3 up = normalize_or(camera->up, (view_vec3){0, 1, 0});
    view_vec3 unit = normalize_or(direction, up);
    /* a light may go below the horizon (a surface lit from behind is a valid test), but not
     * onto the pole, where yaw would be undefined */
    return normalize_or(turn_polar(unit, up, yaw_deg, pitch_deg, 0.5, 179.5), up);
}

/* ---- Techniques and their switches -------------------------------------------------------- */

/* The option + / - step, by technique, and how: by a factor (> 1), else by a step. Its
 * default and range are the technique's option table's (meso_technique_find_option). */
static const struct main_option {
    const char *technique, *option;
    double factor, step;
} main_options[] = {
    {"relief", "linear_steps", 2.0, 0},
    {"vdm", "eigenfunctions", 0, 1},
    {"tessellation", "view_threshold", 2.0, 0},
    /* refine_steps 0 is the paper's table-only hit (docs/techniques/gdm.md) */
    {"gdm", "refine_steps", 0, 1},
};

view_technique_knobs view_technique_knobs_find(const char *technique) {
    view_technique_knobs knobs = {.technique = technique};
    const meso_technique_info *info = meso_technique_find(technique);
    if (!info) return knobs;
    knobs.has_shadows = meso_technique_find_option(info, "shadows") != NULL;
    knobs.has_silhouettes = meso_technique_find_option(info, "silhouettes") != NULL;
    for (size_t i = 0; i < sizeof(main_options) / sizeof(main_options[0]); i++) {
        const meso_technique_option *row =
            strcmp(main_options[i].technique, info->name) == 0
                ? meso_technique_find_option(info, main_options[i].option)
                : NULL;
        if (!row) continue;
        knobs.main_option = row->name;
        knobs.main_default = row->default_value;
        knobs.main_min = row->min;
        knobs.main_max = row->max;
        knobs.main_factor = main_options[i].factor;
        knobs.main_step = main_options[i].step;
    }
    return knobs;
}

/* ---- Key bindings ------------------------------------------------------------------------- */

static const view_binding bindings[] = {
    {27, false, VIEW_ACTION_QUIT, 0, "Esc, Q", "quit"},
    {'q', false, VIEW_ACTION_QUIT, 0, NULL, NULL},
    {'r', false, VIEW_ACTION_RESET, 0, "R", "reset the camera and light to the scene's"},
    {'\t', false, VIEW_ACTION_NEXT_TECHNIQUE, 0, "Tab", "next technique"},
    {'\t', true, VIEW_ACTION_PREVIOUS_TECHNIQUE, 0, "Shift+Tab", "previous technique"},
    {'1', false, VIEW_ACTION_SELECT_TECHNIQUE, 0, "1 .. 9", "technique 1 .. 9 of the list"},
    {'2', false, VIEW_ACTION_SELECT_TECHNIQUE, 1, NULL, NULL},
    {'3', false, VIEW_ACTION_SELECT_TECHNIQUE, 2, NULL, NULL},
    {'4', false, VIEW_ACTION_SELECT_TECHNIQUE, 3, NULL, NULL},
    {'5', false, VIEW_ACTION_SELECT_TECHNIQUE, 4, NULL, NULL},
    {'6', false, VIEW_ACTION_SELECT_TECHNIQUE, 5, NULL, NULL},
    {'7', false, VIEW_ACTION_SELECT_TECHNIQUE, 6, NULL, NULL},
    {'8', false, VIEW_ACTION_SELECT_TECHNIQUE, 7, NULL, NULL},
    {'9', false, VIEW_ACTION_SELECT_TECHNIQUE, 8, NULL, NULL},
    {'s', false, VIEW_ACTION_TOGGLE_SHADOWS, 0, "S", "shadows on / off"},
    {'e', false, VIEW_ACTION_TOGGLE_SILHOUETTES, 0, "E", "silhouettes (edges) on / off"},
    {'m', false, VIEW_ACTION_TOGGLE_WIREFRAME, 0, "M", "wireframe (mesh) on / off"},
    {'+', false, VIEW_ACTION_OPTION_UP, 0, "+ / -",
     "step the main option up / down (relief linear_steps, vdm eigenfunctions, "
     "tessellation view_threshold)"},
    {'=', false, VIEW_ACTION_OPTION_UP, 0, NULL, NULL},
    {']', false, VIEW_ACTION_OPTION_UP, 0, NULL, NULL},
    {'-', false, VIEW_ACTION_OPTION_DOWN, 0, NULL, NULL},
    {'[', false, VIEW_ACTION_OPTION_DOWN, 0, NULL, NULL},
    {'c', false, VIEW_ACTION_RENDER_REFERENCE, 0, "C",
     "render the reference of this view in the background, then compare"},
    {'v', false, VIEW_ACTION_CYCLE_DISPLAY, 0, "V",
     "show the live image, the reference, the difference"},
    {'a', false, VIEW_ACTION_TOGGLE_ADAPTIVE, 0, "A", "adaptive resolution on / off"},
    {'p', false, VIEW_ACTION_SCREENSHOT, 0, "P", "screenshot (full resolution PNG)"},
    {'w', false, VIEW_ACTION_WRITE_SCENE, 0, "W",
     "write the current camera and light as a scene file"},
};

const view_binding *view_bindings(size_t *out_count) {
    *out_count = sizeof(bindings) / sizeof(bindings[0]);
    return bindings;
}

const view_binding *view_binding_find(int key, bool shift) {
    if (key >= 'A' && key <= 'Z') key += 'a' - 'A', shift = true;
    const view_binding *unshifted = NULL;
    for (size_t i = 0; i < sizeof(bindings) / sizeof(bindings[0]); i++) {
        if (bindings[i].key != key) continue;
        if (bindings[i].shift == shift) return &bindings[i];
        if (!bindings[i].shift) unshifted = &bindings[i];
    }
    /* Shift+P is P: only bindings that need Shift (Shift+Tab) tell the two apart */
    return shift ? unshifted : NULL;
}

/* ---- State -------------------------------------------------------------------------------- */

void view_state_init(view_state *state, const view_camera *camera, const view_vec3 *light,
                     const char *const *techniques, int num_techniques, int initial) {
    memset(state, 0, sizeof(*state));
    state->camera = state->home_camera = *camera;
    state->has_light = light != NULL;
    state->light = state->home_light = light ? *light : (view_vec3){0, 1, 0};
    double distance = length(sub(camera->eye, camera->target));
    if (!(distance > 0.0)) distance = 1.0;
    state->min_distance = 1e-3 * distance;
    state->max_distance = 1e3 * distance;
    if (num_techniques > VIEW_MAX_TECHNIQUES) num_techniques = VIEW_MAX_TECHNIQUES;
    for (int i = 0; i < num_techniques; i++) {
        state->techniques[i] = techniques[i];
        state->main_option[i] = view_technique_knobs_find(techniques[i]).main_default;
    }
    state->num_techniques = num_techniques;
    state->technique = initial >= 0 && initial < num_techniques ? initial : 0;
    state->shadows = state->silhouettes = state->adaptive = true;
}

const char *view_state_technique(const view_state *state) {
    return state->num_techniques > 0 ? state->techniques[state->technique] : "";
}

double view_state_main_option(const view_state *state) {
    const view_technique_knobs knobs = view_technique_knobs_find(view_state_technique(state));
    return knobs.main_option ? state->main_option[state->technique] : NAN;
}

static bool select_technique(view_state *state, int index) {
    if (index < 0 || index >= state->num_techniques || index == state->technique) return false;
    state->technique = index;
    return true;
}

static bool step_main_option(view_state *state, int direction) {
    const view_technique_knobs knobs = view_technique_knobs_find(view_state_technique(state));
    if (!knobs.main_option) return false;
    double *value = &state->main_option[state->technique];
    double next = knobs.main_factor > 1.0
                      ? (direction > 0 ? *value * knobs.main_factor : *value / knobs.main_factor)
                      : *value + direction * knobs.main_step;
    next = clamp(next, knobs.main_min, knobs.main_max);
    if (next == *value) return false;
    *value = next;
    return true;
}

/* The view moved: what was compared no longer matches what is seen. */
static void view_moved(view_state *state) {
    state->view_changed = true;
    state->display = VIEW_DISPLAY_LIVE;
}

bool view_state_apply(view_state *state, view_action action, int argument) {
    const view_technique_knobs knobs = view_technique_knobs_find(view_state_technique(state));
    switch (action) {
    case VIEW_ACTION_RESET:
        state->camera = state->home_camera;
        state->light = state->home_light;
        view_moved(state);
        return true;
    case VIEW_ACTION_NEXT_TECHNIQUE:
        return state->num_techniques > 1 &&
               select_technique(state, (state->technique + 1) % state->num_techniques);
    case VIEW_ACTION_PREVIOUS_TECHNIQUE:
        return state->num_techniques > 1 &&
               select_technique(state, (state->technique + state->num_techniques - 1) %
                                           state->num_techniques);
    case VIEW_ACTION_SELECT_TECHNIQUE:
        return select_technique(state, argument);
    case VIEW_ACTION_TOGGLE_SHADOWS:
        if (!knobs.has_shadows) return false;
        state->shadows = !state->shadows;
        return true;
    case VIEW_ACTION_TOGGLE_SILHOUETTES:
        if (!knobs.has_silhouettes) return false;
        state->silhouettes = !state->silhouettes;
        return true;
    case VIEW_ACTION_TOGGLE_WIREFRAME:
        state->wireframe = !state->wireframe;
        return true;
    case VIEW_ACTION_OPTION_UP:
        return step_main_option(state, +1);
    case VIEW_ACTION_OPTION_DOWN:
        return step_main_option(state, -1);
    case VIEW_ACTION_CYCLE_DISPLAY:
        if (!state->has_reference) return false;
        state->display = (view_display)((state->display + 1) % 3);
        return true;
    case VIEW_ACTION_TOGGLE_ADAPTIVE:
        state->adaptive = !state->adaptive;
        return true;
    case VIEW_ACTION_QUIT:
    case VIEW_ACTION_RENDER_REFERENCE:
    case VIEW_ACTION_SCREENSHOT:
    case VIEW_ACTION_WRITE_SCENE:
        return true;
    case VIEW_ACTION_NONE:
        break;
    }
    return false;
}

void view_state_drag(view_state *state, view_drag drag, double dx, double dy, int viewport_height) {
    if (dx == 0.0 && dy == 0.0) return;
    switch (drag) {
    case VIEW_DRAG_ORBIT: /* the object turns with the mouse: the eye goes the other way */
        view_camera_orbit(&state->camera, -dx * ORBIT_DEGREES_PER_PIXEL,
                          dy * ORBIT_DEGREES_PER_PIXEL);
        break;
    case VIEW_DRAG_LIGHT:
        if (!state->has_light) return;
        state->light = view_light_turn(state->light, &state->camera, dx * LIGHT_DEGREES_PER_PIXEL,
                                       -dy * LIGHT_DEGREES_PER_PIXEL);
        break;
    case VIEW_DRAG_PAN:
        view_camera_pan(&state->camera, dx, dy, viewport_height);
        break;
    }
    view_moved(state);
}

void view_state_wheel(view_state *state, double steps) {
    if (steps == 0.0) return;
    view_camera_zoom(&state->camera, steps, state->min_distance, state->max_distance);
    view_moved(state);
}

/* ---- Adaptive resolution ------------------------------------------------------------------ */

void view_resolution_update(view_resolution *resolution, double frame_seconds, bool moving) {
    if (!moving || !(resolution->target_seconds > 0.0)) {
        resolution->scale = 1.0; /* still: refine to the full size */
        return;
    }
    double s = resolution->scale > 0.0 ? resolution->scale : 1.0;
    if (frame_seconds > 0.0) {
        /* a frame's cost goes with its pixels, the square of the scale; aim a quarter under
         * the target, as frame times on a shared machine scatter by that much */
        double ratio = sqrt(0.75 * resolution->target_seconds / frame_seconds);
        if (frame_seconds > resolution->target_seconds)
            s *= ratio < 0.5 ? 0.5 : ratio;
        else if (frame_seconds < 0.6 * resolution->target_seconds)
            s *= ratio > 1.25 ? 1.25 : ratio; /* come back up gently: timings are noisy */
    }
    resolution->scale = clamp(s, VIEW_MIN_SCALE, 1.0);
}

void view_resolution_size(double scale, int width, int height, int *out_width, int *out_height) {
    int w = (int)lround(width * clamp(scale, VIEW_MIN_SCALE, 1.0));
    int h = (int)lround(height * clamp(scale, VIEW_MIN_SCALE, 1.0));
    int min_w = width < 16 ? width : 16, min_h = height < 16 ? height : 16;
    *out_width = w < min_w ? min_w : w;
    *out_height = h < min_h ? min_h : h;
}
