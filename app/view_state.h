/* The viewer's logic without a window (meso view, docs/viewer.md): camera maths (orbit, pan,
 * zoom about the scene's target, turntable frames for `meso render --orbit`), the light
 * dragged by the mouse, the key bindings and what they do to the state, each technique's
 * switches and main option, and the adaptive resolution.
 *
 * Nothing here knows SDL or libmeso: app/cmd_view.c turns window events into these calls and
 * the state into renders, and tests/app/test_app_view_state.c drives it directly. Keys are
 * given as characters ('a'..'z', '0'..'9', '\t', 27 for Escape, '+', '-'), which is also what
 * SDL2's keycodes are for those keys.
 *
 * Conventions (docs/design.md): right-handed, y up by default (the camera's `up`), angles in
 * degrees where the scene uses them. Every function is pure apart from writing its state
 * argument, and thread-compatible (one state, one thread).
 */
#ifndef MESO_APP_VIEW_STATE_H
#define MESO_APP_VIEW_STATE_H

#include <stdbool.h>
#include <stddef.h>

#define VIEW_MAX_TECHNIQUES 32
#define VIEW_MIN_SCALE 0.25 /* adaptive resolution never drops below a quarter a side */

typedef struct view_vec3 {
    double x, y, z;
} view_vec3;

typedef struct view_camera {
    view_vec3 eye, target, up;
    double fov_y_deg;
} view_camera;

/* ---- Camera maths ------------------------------------------------------------------------- */

/* Turn the eye about the target: `yaw_deg` about the camera's up axis, `pitch_deg` about its
 * right axis (positive looks more from above). The angle between the view direction and up
 * stays within [1, 179] degrees, so the camera never flips over the pole. */
void view_camera_orbit(view_camera *camera, double yaw_deg, double pitch_deg);

/* Move eye and target together by (dx, dy) pixels of a viewport `viewport_height` pixels high,
 * so that a point at the target's depth follows the mouse (dx right, dy down). */
void view_camera_pan(view_camera *camera, double dx, double dy, int viewport_height);

/* Move the eye toward the target by `steps` wheel notches (positive: closer), each 10% of
 * the distance; the distance stays within [min_distance, max_distance]. */
void view_camera_zoom(view_camera *camera, double steps, double min_distance, double max_distance);

/* Frame `frame` of `count` of a turntable around `home`: its eye turned by 360 * frame / count
 * degrees about the up axis through the target (frame 0 is home itself). */
view_camera view_camera_turntable(const view_camera *home, int frame, int count);

/* Turn a unit light direction (toward the light) by `yaw_deg` about `up` and `pitch_deg`
 * about the camera's right axis, as dragging turns it; returns a unit vector. */
view_vec3 view_light_turn(view_vec3 direction, const view_camera *camera, double yaw_deg,
                          double pitch_deg);

/* ---- Techniques and their switches -------------------------------------------------------- */

/* What the viewer can change of a technique: its switches and its main option. The names are
 * the technique's own `technique_options` (docs/techniques/). */
typedef struct view_technique_knobs {
    const char *technique;   /* "relief" */
    bool has_shadows;        /* takes "shadows" 0/1 */
    bool has_silhouettes;    /* takes "silhouettes" 0/1 */
    const char *main_option; /* "linear_steps", or NULL */
    double main_default, main_min, main_max;
    double main_factor; /* > 1: steps multiply and divide by it; else they add main_step */
    double main_step;
} view_technique_knobs;

/* The knobs of a technique, from its option table: the switches it has, and the main option
 * the viewer steps with its default and range; an unknown technique has none (every field 0
 * but `technique`). */
view_technique_knobs view_technique_knobs_find(const char *technique);

/* ---- Key bindings ------------------------------------------------------------------------- */

typedef enum view_action {
    VIEW_ACTION_NONE = 0,
    VIEW_ACTION_QUIT,
    VIEW_ACTION_RESET,              /* the scene's camera and light */
    VIEW_ACTION_NEXT_TECHNIQUE,     /* Tab */
    VIEW_ACTION_PREVIOUS_TECHNIQUE, /* Shift+Tab */
    VIEW_ACTION_SELECT_TECHNIQUE,   /* 1..9: argument = index */
    VIEW_ACTION_TOGGLE_SHADOWS,
    VIEW_ACTION_TOGGLE_SILHOUETTES,
    VIEW_ACTION_TOGGLE_WIREFRAME,
    VIEW_ACTION_OPTION_UP,
    VIEW_ACTION_OPTION_DOWN,
    VIEW_ACTION_RENDER_REFERENCE, /* start the reference of the current view */
    VIEW_ACTION_CYCLE_DISPLAY,    /* live -> reference -> difference -> live */
    VIEW_ACTION_TOGGLE_ADAPTIVE,
    VIEW_ACTION_SCREENSHOT,
    VIEW_ACTION_WRITE_SCENE,
} view_action;

typedef struct view_binding {
    int key;    /* character, see the top of this file */
    bool shift; /* only with Shift held (else: only without) */
    view_action action;
    int argument;
    const char *keys_text; /* "Shift+Tab", for the help */
    const char *help;      /* "previous technique" */
} view_binding;

/* The table of bindings (for the help and docs/viewer.md), and its length. */
const view_binding *view_bindings(size_t *out_count);

/* The binding of a key, or NULL. */
const view_binding *view_binding_find(int key, bool shift);

/* ---- State -------------------------------------------------------------------------------- */

typedef enum view_display {
    VIEW_DISPLAY_LIVE = 0,
    VIEW_DISPLAY_REFERENCE,
    VIEW_DISPLAY_DIFFERENCE,
} view_display;

typedef struct view_state {
    view_camera camera, home_camera;
    view_vec3 light, home_light; /* unit, toward the light (the scene's first light) */
    bool has_light;              /* the scene's first light is directional */
    double min_distance, max_distance;

    const char *techniques[VIEW_MAX_TECHNIQUES]; /* borrowed names */
    int num_techniques;
    int technique; /* index into techniques */
    double main_option[VIEW_MAX_TECHNIQUES];

    bool shadows, silhouettes, wireframe, adaptive;
    view_display display;
    bool has_reference; /* a reference image exists, so the display may cycle to it */

    /* Set when the camera or light moves (the reference image is then out of date); the
     * caller clears it. Whether a renderer must be prepared again is the caller's to compare:
     * the technique, the switches and main_option say all it was prepared with. */
    bool view_changed;
} view_state;

/* A state for the scene's camera and first light (light NULL when it is not directional),
 * drawing `techniques[initial]` with the switches on and each main option at its default. */
void view_state_init(view_state *state, const view_camera *camera, const view_vec3 *light,
                     const char *const *techniques, int num_techniques, int initial);

/* Do what a binding does to the state. Screenshot, write-scene, reference and quit are the
 * caller's to carry out: they return true without changing anything. Returns false when the
 * action does nothing here (e.g. cycling the display with no reference). */
bool view_state_apply(view_state *state, view_action action, int argument);

/* Mouse drags, in pixels of a viewport `viewport_height` high: the left button orbits (with
 * Shift: turns the light), the right or middle button (or Ctrl+left) pans; the wheel zooms. */
typedef enum view_drag {
    VIEW_DRAG_ORBIT = 0,
    VIEW_DRAG_LIGHT,
    VIEW_DRAG_PAN,
} view_drag;
void view_state_drag(view_state *state, view_drag drag, double dx, double dy, int viewport_height);
void view_state_wheel(view_state *state, double steps);

/* The current technique's name and its main option's value (NAN when it has none). */
const char *view_state_technique(const view_state *state);
double view_state_main_option(const view_state *state);

/* ---- Adaptive resolution ------------------------------------------------------------------ */

/* The fraction of the window's width and height to render at. While the view moves, a frame
 * slower than the target lowers it (cost goes with the pixel count, so by the square root of
 * the ratio) and a frame well under the target raises it; when still, it returns to 1. */
typedef struct view_resolution {
    double scale;          /* in [VIEW_MIN_SCALE, 1] */
    double target_seconds; /* frame time aimed at while moving */
} view_resolution;

void view_resolution_update(view_resolution *resolution, double frame_seconds, bool moving);

/* The render size for a window of width x height at `scale` (at least 16 x 16 or the window). */
void view_resolution_size(double scale, int width, int height, int *out_width, int *out_height);

#endif
