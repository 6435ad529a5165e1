/* meso view: an interactive window drawing a scene with meso's renderer (docs/viewer.md).
 *
 * The window's logic lives in view_state.c (camera maths, bindings, state), the scene copies
 * in view_scene.c, the background reference in view_reference.c and the scripted input in
 * view_script.c; this file turns SDL events into those calls and frames into the window.
 * Built with SDL2 only (MESO_HAS_SDL2); without it the command says so.
 */
#include "app.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "render_camera.h"
#include "view_reference.h"
#include "view_scene.h"
#include "view_script.h"
#include "view_state.h"

typedef struct view_options {
    const char *technique;
    const char *techniques; /* the list to prepare and switch between (NULL: all that apply) */
    app_size size;
    double target_fps;
    bool fixed_resolution;
    const char *events;
    const char *script;
    const char *screenshot;
    const char *save_scene;
    app_camera_override camera;
} view_options;

static const app_command_help view_help = {
    .name = "view",
    .usage = "SCENE [options]",
    .summary =
        "Open a window drawing the scene with meso's renderer. Drag with the left button to\n"
        "orbit about the camera's target, with Shift to turn the light, with the right button\n"
        "(or Ctrl) to pan; the wheel zooms. Keys (docs/viewer.md):\n"
        "  Tab, Shift+Tab, 1..9  technique     S shadows   E silhouettes   M wireframe\n"
        "  + / -  step the main option (relief linear_steps, vdm eigenfunctions,\n"
        "         tessellation view_threshold)\n"
        "  C  render the reference of this view in the background, then compare\n"
        "  V  show the live image / the reference / the difference (title: PSNR)\n"
        "  A  adaptive resolution on / off    R  reset the camera and light\n"
        "  P  screenshot    W  write the camera and light as a scene file    Esc, Q  quit\n"
        "The title shows the technique, frame time, triangles and resolution. Every\n"
        "technique is prepared (baked) before the window opens. While the view moves, frames\n"
        "slower than 1/--fps are drawn at a lower resolution and refined when it stops.\n"
        "Without a display, use meso render SCENE --orbit N -o DIR for frames.",
    .examples = "  meso view examples/bricks-teapot.json --technique relief --size 800x600\n"
                "  SDL_VIDEODRIVER=offscreen meso view examples/bricks-plane.json --events "
                "'drag 40,0; key p' --screenshot shot.png\n",
};

#if !MESO_HAS_SDL2

int meso_cmd_view(int argc, char **argv) {
    (void)argc;
    (void)argv;
    fprintf(stderr, "meso: view: this meso was built without SDL2 (install libsdl2-dev and "
                    "rebuild); for frames without a window use meso render SCENE --orbit N -o "
                    "DIR\n");
    return APP_EXIT_FAILURE;
}

#else

#include <SDL.h>
#include "meso/runtime.h"

#define MAX_TIMED_FRAMES 100000
#define NOTICE_SECONDS 3.0
#define MOVING_SECONDS 0.25 /* the view counts as moving this long after the last change */
#define IDLE_WAIT_MS 50     /* nothing to draw: sleep on the event queue, not the CPU */

typedef struct viewer {
    meso_context *ctx;
    meso_scene *scene; /* as loaded, with the command line's camera and light */
    const view_options *options;
    view_state state;
    view_resolution resolution;
    view_scene *scenes[VIEW_MAX_TECHNIQUES]; /* per technique: its options, the live view */
    meso_renderer *renderers[VIEW_MAX_TECHNIQUES];
    meso_framebuffer *frame; /* the live frame, at the render size */
    bool frame_reduced;      /* drawn below the window's size */
    bool frame_valid;        /* matches the state */

    SDL_Window *window;
    SDL_Renderer *sdl;
    SDL_Texture *texture;
    int texture_width, texture_height;
    int window_width, window_height;
    uint8_t srgb[4096]; /* linear [0,1] in 4096 steps -> sRGB byte, for the display only */

    view_reference *job;
    bool job_stale;                                   /* the view moved since the job started */
    meso_image *compare_live, *compare_live_coverage; /* the technique at the job's view */
    meso_image *reference, *reference_coverage, *difference;
    meso_compare_result metrics;

    view_event events[VIEW_SCRIPT_MAX_EVENTS];
    int num_events, next_event, frames_to_wait;
    bool scripted;

    double last_move;
    double frame_ms;            /* the last live frame's render time (the title's) */
    double frame_total_seconds; /* and with its events, upload and present: what adaptive
                                   resolution holds to 1 / --fps */
    /* per drawn frame, for the summary's medians: render, events (handling, preparing),
     * upload (sRGB conversion into the texture), present (copy to the window) */
    double *timed[4];
    size_t num_timed;
    double open_seconds;
    int frames_reduced;
    char notice[256];
    double notice_until;
    char title[1024];
    double title_time;
    int screenshot_number;
    int status;
    int threads; /* --threads, for the reference's own context too */
    bool quiet, verbose;
    bool running;
    /* what each technique's renderer was prepared with: prepared again when the state differs */
    struct prepared_with {
        bool shadows, silhouettes, wireframe;
        double main_option;
    } prepared[VIEW_MAX_TECHNIQUES];
} viewer;

/* ---- Messages ----------------------------------------------------------------------------- */

static void notice(viewer *v, const char *format, ...) __attribute__((format(printf, 2, 3)));
static void notice(viewer *v, const char *format, ...) {
    va_list args;
    va_start(args, format);
    vsnprintf(v->notice, sizeof(v->notice), format, args);
    va_end(args);
    v->notice_until = meso_time_seconds() + NOTICE_SECONDS;
    v->title_time = 0.0; /* show it now */
}

/* A failure of something the user asked for (a screenshot, a scene file): one line on stderr
 * as every command prints it, the same in the title, and the exit status remembers it. */
static void report_failure(viewer *v, meso_result result) {
    const char *message = meso_context_last_error(v->ctx);
    if (!message[0]) message = meso_result_string(result);
    fprintf(stderr, "meso: %s\n", message);
    notice(v, "%s", message);
    if (v->status == APP_EXIT_OK) v->status = app_exit_status(result);
}

static void update_title(viewer *v, bool force) {
    double now = meso_time_seconds();
    if (!force && now - v->title_time < 0.25) return; /* a title is a round trip to X */
    v->title_time = now;
    const char *technique = view_state_technique(&v->state);
    const view_technique_knobs knobs = view_technique_knobs_find(technique);
    char option[96] = "", reference[160] = "", switches[64] = "";
    if (knobs.main_option)
        snprintf(option, sizeof(option), " %s %g", knobs.main_option,
                 view_state_main_option(&v->state));
    if (knobs.has_shadows || knobs.has_silhouettes)
        snprintf(switches, sizeof(switches), "%s%s%s | ",
                 knobs.has_shadows ? (v->state.shadows ? "shadows" : "no shadows") : "",
                 knobs.has_shadows && knobs.has_silhouettes ? ", " : "",
                 knobs.has_silhouettes ? (v->state.silhouettes ? "silhouettes" : "no silhouettes")
                                       : "");
    if (v->job) {
        double fraction, seconds;
        view_reference_poll(v->job, &fraction, &seconds);
        if (fraction > 0.0)
            snprintf(reference, sizeof(reference), " | reference %d%% (%.0f s)%s",
                     (int)(100.0 * fraction), seconds, v->job_stale ? ", view moved" : "");
        else
            snprintf(reference, sizeof(reference),
                     " | reference: building the true surface (%.0f s)", seconds);
    } else if (v->state.has_reference) {
        static const char *const shown[] = {"live", "reference", "difference"};
        snprintf(reference, sizeof(reference), " | %s, PSNR %.1f dB (covered %.1f)",
                 shown[v->state.display], v->metrics.psnr, v->metrics.psnr_covered);
    }
    meso_render_stats stats = meso_renderer_get_stats(v->renderers[v->state.technique]);
    int width = v->frame ? v->frame->width : 0, height = v->frame ? v->frame->height : 0;
    snprintf(v->title, sizeof(v->title),
             "meso view: %s%s | %s%.1f ms | %llu triangles | %dx%d%s%s%s%s", technique, option,
             switches, v->frame_ms, (unsigned long long)stats.triangles, width, height,
             v->state.wireframe ? " | wireframe" : "", reference,
             now < v->notice_until ? " | " : "", now < v->notice_until ? v->notice : "");
    SDL_SetWindowTitle(v->window, v->title);
}

/* ---- Renderers ---------------------------------------------------------------------------- */

/* (Re)prepare the renderer of technique `index` for the state's switches and options. */
static meso_result prepare_technique(viewer *v, int index) {
    const char *technique = v->state.techniques[index];
    view_scene *scene = NULL;
    meso_renderer *renderer = NULL;
    meso_result r = view_scene_create(v->ctx, v->scene, technique, &v->state, &scene);
    if (r == MESO_OK) {
        meso_render_desc desc = {.technique = technique, .wireframe = v->state.wireframe};
        r = meso_renderer_create(v->ctx, &scene->scene, &desc, &renderer);
    }
    if (r != MESO_OK) {
        view_scene_destroy(scene);
        return r;
    }
    meso_renderer_destroy(v->renderers[index]);
    view_scene_destroy(v->scenes[index]);
    v->prepared[index] = (struct prepared_with){v->state.shadows, v->state.silhouettes,
                                                v->state.wireframe, v->state.main_option[index]};
    v->renderers[index] = renderer;
    v->scenes[index] = scene;
    return MESO_OK;
}

/* Render the current technique at width x height into a framebuffer (v->frame when `into` is
 * NULL, resized as needed). */
static meso_result render_live(viewer *v, int width, int height, meso_framebuffer **into) {
    meso_framebuffer **target = into ? into : &v->frame;
    if (*target && ((*target)->width != width || (*target)->height != height)) {
        meso_framebuffer_destroy(*target);
        *target = NULL;
    }
    meso_result r = MESO_OK;
    if (!*target) r = meso_framebuffer_create(v->ctx, width, height, target);
    int t = v->state.technique;
    view_scene_set_view(v->scenes[t], &v->state);
    if (r == MESO_OK) r = meso_renderer_render(v->renderers[t], *target);
    return r;
}

/* ---- Display ------------------------------------------------------------------------------ */

static void make_srgb_table(viewer *v) {
    for (int i = 0; i < 4096; i++) {
        float s = meso_linear_to_srgb((float)i / 4095.0f);
        v->srgb[i] = (uint8_t)(s * 255.0f + 0.5f);
    }
}

/* Rows of the texture converted by one job of the upload's parallel loop. */
#define UPLOAD_ROWS 32

typedef struct upload_job {
    const viewer *v;
    const float *rgb;
    uint8_t *data;
    int pitch, width, height;
    bool linear;
} upload_job;

/* A channel in [0,1] as a step of 4095 (NaN and below 0 give 0: the comparisons fail). */
static inline int channel_step(float c) {
    float scaled = c * 4095.0f + 0.5f;
    scaled = scaled > 0.0f ? scaled : 0.0f;
    return (int)(scaled < 4095.0f ? scaled : 4095.0f);
}

static void upload_rows(void *user, size_t job, int thread_index) {
    const upload_job *u = user;
    int y0 = (int)job * UPLOAD_ROWS;
    int y1 = y0 + UPLOAD_ROWS < u->height ? y0 + UPLOAD_ROWS : u->height;
    uint8_t display[4096]; /* step -> byte: through the sRGB curve, or as it is */
    for (int i = 0; i < 4096; i++)
        display[i] = u->linear ? u->v->srgb[i] : (uint8_t)((i * 255 + 2047) / 4095);
    for (int y = y0; y < y1; y++) {
        uint32_t *row = (uint32_t *)(u->data + (size_t)y * (size_t)u->pitch);
        const float *in = u->rgb + (size_t)y * (size_t)u->width * 3;
        for (int x = 0; x < u->width; x++, in += 3)
            row[x] = (uint32_t)display[channel_step(in[0])] << 16 |
                     (uint32_t)display[channel_step(in[1])] << 8 | display[channel_step(in[2])];
    }
}

/* Upload RGB floats (linear: through the sRGB curve; else as they are) as the texture. */
static bool upload(viewer *v, const float *rgb, int width, int height, bool linear) {
    if (!v->texture || v->texture_width != width || v->texture_height != height) {
        if (v->texture) SDL_DestroyTexture(v->texture);
        /* XRGB8888, the window surface's own format: the software renderer's copy is then a
         * plain one (RGB24 went through SDL's generic converter) */
        v->texture = SDL_CreateTexture(v->sdl, SDL_PIXELFORMAT_RGB888, SDL_TEXTUREACCESS_STREAMING,
                                       width, height);
        if (!v->texture) return false;
        v->texture_width = width, v->texture_height = height;
        /* a reduced frame is magnified: bilinear reads better than blocks while moving */
        SDL_SetTextureScaleMode(v->texture, SDL_ScaleModeLinear);
    }
    void *data = NULL;
    int pitch = 0;
    if (SDL_LockTexture(v->texture, NULL, &data, &pitch) != 0) return false;
    upload_job job = {v, rgb, data, pitch, width, height, linear};
    /* Serial on purpose: on the shared 2-core box a parallel loop here waited for a descheduled
     * worker, several times longer than one thread takes. */
    for (size_t block = 0; block < (size_t)(height + UPLOAD_ROWS - 1) / UPLOAD_ROWS; block++)
        upload_rows(&job, block, 0);
    SDL_UnlockTexture(v->texture);
    return true;
}

/* Upload what the state says is shown. */
static bool upload_shown(viewer *v) {
    switch (v->state.display) {
    case VIEW_DISPLAY_REFERENCE:
        return upload(v, v->reference->pixels, v->reference->width, v->reference->height, true);
    case VIEW_DISPLAY_DIFFERENCE: /* false colours, designed as display values */
        return upload(v, v->difference->pixels, v->difference->width, v->difference->height, false);
    case VIEW_DISPLAY_LIVE:
        break;
    }
    return upload(v, v->frame->color, v->frame->width, v->frame->height, true);
}

static void present(viewer *v) {
    SDL_RenderClear(v->sdl);
    if (v->texture) SDL_RenderCopy(v->sdl, v->texture, NULL, NULL);
    SDL_RenderPresent(v->sdl);
}

/* ---- Actions ------------------------------------------------------------------------------ */

static void next_screenshot_path(viewer *v, char *path, size_t size) {
    if (v->options->screenshot) {
        snprintf(path, size, "%s", v->options->screenshot);
        return;
    }
    for (;;) { /* the first free meso-view-NNNN.png: never overwrite an earlier one */
        snprintf(path, size, "meso-view-%04d.png", ++v->screenshot_number);
        FILE *f = fopen(path, "rb");
        if (!f) return;
        fclose(f);
    }
}

/* Save what is shown, at full resolution: the live view is rendered again at the window's
 * size, so the file is what `meso render` writes for the same camera (same bytes). */
static void screenshot(viewer *v) {
    char path[4096];
    next_screenshot_path(v, path, sizeof(path));
    meso_result r = MESO_OK;
    if (v->state.display == VIEW_DISPLAY_LIVE) {
        meso_framebuffer *full = NULL;
        r = render_live(v, v->window_width, v->window_height, &full);
        if (r == MESO_OK)
            r = meso_framebuffer_save_png(v->ctx, full, v->scene->encoding, path, NULL);
        meso_framebuffer_destroy(full);
    } else {
        bool reference = v->state.display == VIEW_DISPLAY_REFERENCE;
        meso_png_desc png = {.encoding = reference ? v->scene->encoding : MESO_ENCODING_LINEAR};
        r = meso_image_save_png(v->ctx, reference ? v->reference : v->difference, path, &png);
    }
    if (r != MESO_OK) return report_failure(v, r);
    notice(v, "wrote %s", path);
    if (!v->quiet) fprintf(stderr, "meso: view: wrote %s\n", path);
}

/* The scene file path for W: --save-scene, else SCENE-view.json beside the scene, so the
 * relative paths inside it still hold. */
static void scene_file_path(const viewer *v, char *path, size_t size) {
    if (v->options->save_scene) {
        snprintf(path, size, "%s", v->options->save_scene);
        return;
    }
    const char *source = v->scene->path;
    size_t length = strlen(source);
    if (length > 5 && !strcmp(source + length - 5, ".json")) length -= 5;
    snprintf(path, size, "%.*s-view.json", (int)length, source);
}

static void write_scene(viewer *v) {
    char path[4096];
    scene_file_path(v, path, sizeof(path));
    meso_camera camera = app_camera_from_view(&v->state.camera);
    bool light_moved = memcmp(&v->state.light, &v->state.home_light, sizeof(v->state.light)) != 0;
    meso_vec3 light = {0};
    if (v->state.has_light && light_moved) /* the very bits the live view renders with */
        light = v->scenes[v->state.technique]->scene.lights[0].direction;
    meso_result r = view_scene_save(v->ctx, v->scene->path, &camera,
                                    v->state.has_light && light_moved ? &light : NULL, path);
    if (r != MESO_OK) return report_failure(v, r);
    notice(v, "wrote %s", path);
    if (!v->quiet) fprintf(stderr, "meso: view: wrote %s\n", path);
}

/* ---- The reference in the background ------------------------------------------------------ */

static void drop_comparison(viewer *v) {
    meso_image_destroy(v->compare_live);
    meso_image_destroy(v->compare_live_coverage);
    meso_image_destroy(v->reference);
    meso_image_destroy(v->reference_coverage);
    meso_image_destroy(v->difference);
    v->compare_live = v->compare_live_coverage = v->reference = v->reference_coverage =
        v->difference = NULL;
    v->state.has_reference = false;
    v->state.display = VIEW_DISPLAY_LIVE;
}

static void start_reference(viewer *v) {
    if (v->job) return notice(v, "the reference is still rendering");
    drop_comparison(v);
    v->frame_valid = false;
    /* the technique at the same view and size, now, to compare with when the reference is in */
    meso_framebuffer *full = NULL;
    meso_result r = render_live(v, v->window_width, v->window_height, &full);
    if (r == MESO_OK) r = meso_framebuffer_color_image(v->ctx, full, &v->compare_live);
    if (r == MESO_OK) r = meso_framebuffer_coverage_image(v->ctx, full, &v->compare_live_coverage);
    meso_framebuffer_destroy(full);
    if (r == MESO_OK)
        r = view_reference_start(v->ctx, v->scene, &v->state, v->window_width, v->window_height,
                                 v->threads, &v->job);
    if (r != MESO_OK) return report_failure(v, r);
    v->job_stale = false;
    notice(v, "reference started");
}

/* Once a frame: when the job has finished, take its image, compare, show it. */
static void poll_reference(viewer *v) {
    if (!v->job) return;
    double fraction, seconds;
    view_reference_status status = view_reference_poll(v->job, &fraction, &seconds);
    if (status == VIEW_REFERENCE_RUNNING) return;
    meso_result r = MESO_OK;
    if (status == VIEW_REFERENCE_FAILED) {
        notice(v, "reference: %s", view_reference_error(v->job));
    } else if (v->job_stale) {
        notice(v, "reference discarded: the view moved while it rendered (press C again)");
    } else {
        const meso_framebuffer *image = view_reference_image(v->job);
        r = meso_framebuffer_color_image(v->ctx, image, &v->reference);
        if (r == MESO_OK)
            r = meso_framebuffer_coverage_image(v->ctx, image, &v->reference_coverage);
        meso_compare_desc desc = {.coverage_a = v->compare_live_coverage,
                                  .coverage_b = v->reference_coverage};
        if (r == MESO_OK)
            r = meso_image_compare(v->ctx, v->compare_live, v->reference, &desc, &v->metrics);
        if (r == MESO_OK)
            r = meso_image_diff(v->ctx, v->compare_live, v->reference, 0.0f, &v->difference);
        if (r == MESO_OK) {
            v->state.has_reference = true;
            v->state.display = VIEW_DISPLAY_REFERENCE;
            v->frame_valid = false;
            notice(v, "reference in %.1f s (V: live / reference / difference)", seconds);
            if (!v->quiet)
                fprintf(stderr,
                        "meso: view: reference in %.1f s: %s against it: PSNR %.2f dB "
                        "(covered %.2f), SSIM %.3f, IoU %.3f\n",
                        seconds, view_state_technique(&v->state), v->metrics.psnr,
                        v->metrics.psnr_covered, v->metrics.ssim, v->metrics.coverage_iou);
        }
    }
    view_reference_destroy(v->job); /* its thread has finished: no wait */
    v->job = NULL;
    if (r != MESO_OK) {
        drop_comparison(v);
        report_failure(v, r);
    }
}

/* ---- Events ------------------------------------------------------------------------------- */

/* Why an action did nothing, for the title. */
static void explain_refusal(viewer *v, view_action action) {
    const char *technique = view_state_technique(&v->state);
    switch (action) {
    case VIEW_ACTION_TOGGLE_SHADOWS:
        return notice(v, "%s has no shadows switch", technique);
    case VIEW_ACTION_TOGGLE_SILHOUETTES:
        return notice(v, "%s has no silhouettes switch", technique);
    case VIEW_ACTION_OPTION_UP:
    case VIEW_ACTION_OPTION_DOWN:
        if (!view_technique_knobs_find(technique).main_option)
            return notice(v, "%s has no main option to step", technique);
        return notice(v, "%s: %s is at its limit", technique,
                      view_technique_knobs_find(technique).main_option);
    case VIEW_ACTION_CYCLE_DISPLAY:
        return notice(v, "no reference yet: press C");
    default:
        return;
    }
}

static void handle_key(viewer *v, SDL_Keycode sym, Uint16 mod) {
    int key = sym == SDLK_TAB        ? '\t'
              : sym == SDLK_ESCAPE   ? 27
              : sym == SDLK_KP_PLUS  ? '+'
              : sym == SDLK_KP_MINUS ? '-'
              : sym > 0 && sym < 128 ? (int)sym
                                     : 0;
    const view_binding *binding = view_binding_find(key, (mod & KMOD_SHIFT) != 0);
    if (!binding) return;
    if (!view_state_apply(&v->state, binding->action, binding->argument))
        return explain_refusal(v, binding->action);
    switch (binding->action) {
    case VIEW_ACTION_QUIT:
        v->running = false;
        break;
    case VIEW_ACTION_SCREENSHOT:
        screenshot(v);
        break;
    case VIEW_ACTION_WRITE_SCENE:
        write_scene(v);
        break;
    case VIEW_ACTION_RENDER_REFERENCE:
        start_reference(v);
        break;
    default:
        v->frame_valid = false;
        break;
    }
    v->title_time = 0.0;
}

static void handle_event(viewer *v, const SDL_Event *e) {
    switch (e->type) {
    case SDL_QUIT:
        v->running = false;
        break;
    case SDL_KEYDOWN:
        handle_key(v, e->key.keysym.sym, e->key.keysym.mod);
        break;
    case SDL_MOUSEMOTION: {
        Uint32 buttons = e->motion.state;
        if (!(buttons & (SDL_BUTTON_LMASK | SDL_BUTTON_MMASK | SDL_BUTTON_RMASK))) break;
        SDL_Keymod mod = SDL_GetModState();
        view_drag drag = (buttons & (SDL_BUTTON_MMASK | SDL_BUTTON_RMASK)) || (mod & KMOD_CTRL)
                             ? VIEW_DRAG_PAN
                         : (mod & KMOD_SHIFT) ? VIEW_DRAG_LIGHT
                                              : VIEW_DRAG_ORBIT;
        view_state_drag(&v->state, drag, e->motion.xrel, e->motion.yrel, v->window_height);
        break;
    }
    case SDL_MOUSEWHEEL:
        view_state_wheel(&v->state,
                         e->wheel.direction == SDL_MOUSEWHEEL_FLIPPED ? -e->wheel.y : e->wheel.y);
        break;
    case SDL_WINDOWEVENT:
        if (e->window.event == SDL_WINDOWEVENT_SIZE_CHANGED && e->window.data1 > 0 &&
            e->window.data2 > 0) {
            v->window_width = e->window.data1;
            v->window_height = e->window.data2;
            v->frame_valid = false;
        } else if (e->window.event == SDL_WINDOWEVENT_EXPOSED) {
            v->title_time = 0.0;
        }
        break;
    default:
        break;
    }
}

/* Feed the script's next event to SDL's queue, as the keyboard and mouse would: one a frame,
 * so every event is handled, drawn and timed like a person's. */
static void push_script_event(viewer *v) {
    SDL_SetModState(KMOD_NONE);
    if (v->frames_to_wait > 0) {
        v->frames_to_wait--;
        return;
    }
    while (v->next_event < v->num_events) {
        const view_event *e = &v->events[v->next_event];
        if (e->type == VIEW_EVENT_WAIT && v->job) return; /* until the reference is in */
        v->next_event++;
        SDL_Event event;
        memset(&event, 0, sizeof(event));
        switch (e->type) {
        case VIEW_EVENT_KEY:
            event.type = SDL_KEYDOWN;
            event.key.state = SDL_PRESSED;
            event.key.keysym.sym = e->key == '\t' ? SDLK_TAB : e->key == 27 ? SDLK_ESCAPE : e->key;
            event.key.keysym.mod = e->shift ? KMOD_LSHIFT : KMOD_NONE;
            SDL_PushEvent(&event);
            return;
        case VIEW_EVENT_DRAG:
        case VIEW_EVENT_LIGHT:
        case VIEW_EVENT_PAN:
            event.type = SDL_MOUSEMOTION;
            event.motion.state = e->type == VIEW_EVENT_PAN ? SDL_BUTTON_RMASK : SDL_BUTTON_LMASK;
            event.motion.xrel = (Sint32)lround(e->dx);
            event.motion.yrel = (Sint32)lround(e->dy);
            /* the modifier as a held key: read when the motion is handled, this frame */
            if (e->type == VIEW_EVENT_LIGHT) SDL_SetModState(KMOD_LSHIFT);
            SDL_PushEvent(&event);
            return;
        case VIEW_EVENT_WHEEL:
            event.type = SDL_MOUSEWHEEL;
            event.wheel.y = (Sint32)lround(e->dx);
            event.wheel.direction = SDL_MOUSEWHEEL_NORMAL;
            SDL_PushEvent(&event);
            return;
        case VIEW_EVENT_FRAMES:
            v->frames_to_wait = e->count;
            return;
        case VIEW_EVENT_WAIT:
            break; /* nothing running: go on */
        }
    }
}

/* ---- The loop ----------------------------------------------------------------------------- */

static bool needs_prepare(const viewer *v) {
    int t = v->state.technique;
    const struct prepared_with *p = &v->prepared[t];
    return p->shadows != v->state.shadows || p->silhouettes != v->state.silhouettes ||
           p->wireframe != v->state.wireframe || p->main_option != v->state.main_option[t];
}

static void record_timing(viewer *v, const double seconds[4]) {
    if (v->num_timed >= MAX_TIMED_FRAMES) return;
    for (int i = 0; i < 4; i++) v->timed[i][v->num_timed] = 1000.0 * seconds[i];
    v->num_timed++;
}

/* One frame: events, (re)preparing, drawing at the adaptive size, presenting. */
static void run_frame(viewer *v, double start_seconds) {
    SDL_Event event;
    /* Nothing to draw: sleep on the event queue rather than spin, also while the reference
     * renders (it needs the cores) and while a script waits for it. */
    bool script_waits = v->scripted && v->job && v->next_event < v->num_events &&
                        v->events[v->next_event].type == VIEW_EVENT_WAIT;
    bool idle = v->frame_valid && !v->frame_reduced && (!v->scripted || script_waits);
    if (idle && SDL_WaitEventTimeout(&event, IDLE_WAIT_MS)) handle_event(v, &event);
    double t0 = meso_time_seconds();
    if (v->scripted) push_script_event(v);
    while (SDL_PollEvent(&event)) handle_event(v, &event);
    if (v->state.view_changed) {
        v->state.view_changed = false;
        v->last_move = t0;
        v->frame_valid = false;
        if (v->job) v->job_stale = true;
    }
    poll_reference(v);
    if (needs_prepare(v)) {
        meso_result r = prepare_technique(v, v->state.technique);
        if (r != MESO_OK) {
            report_failure(v, r);
            int t = v->state.technique; /* keep drawing what was prepared; do not retry */
            v->prepared[t] = (struct prepared_with){v->state.shadows, v->state.silhouettes,
                                                    v->state.wireframe, v->state.main_option[t]};
        }
        v->frame_valid = false;
    }
    double events_seconds = meso_time_seconds() - t0;

    bool moving = t0 - v->last_move < MOVING_SECONDS;
    double render_seconds = 0.0, upload_seconds = 0.0;
    bool drew = false;
    if (v->state.display == VIEW_DISPLAY_LIVE) {
        if (v->state.adaptive && moving && !v->frame_valid)
            view_resolution_update(&v->resolution, v->frame_total_seconds, true);
        else if (!moving)
            view_resolution_update(&v->resolution, 0.0, false);
        int width, height;
        view_resolution_size(v->resolution.scale, v->window_width, v->window_height, &width,
                             &height);
        bool refine = v->frame_reduced && !moving;
        if (!v->frame_valid || refine) {
            double t = meso_time_seconds();
            meso_result r = render_live(v, width, height, NULL);
            render_seconds = meso_time_seconds() - t;
            if (r != MESO_OK) {
                report_failure(v, r);
                v->running = false; /* a renderer that cannot draw will not draw next frame */
                return;
            }
            v->frame_ms = 1000.0 * render_seconds;
            v->frame_reduced = width < v->window_width || height < v->window_height;
            v->frames_reduced += v->frame_reduced;
            t = meso_time_seconds();
            upload_shown(v);
            upload_seconds = meso_time_seconds() - t;
            v->frame_valid = drew = true;
        }
    } else if (!v->frame_valid) {
        upload_shown(v);
        v->frame_valid = true;
    }
    double t = meso_time_seconds();
    present(v);
    double present_seconds = meso_time_seconds() - t;
    if (v->open_seconds == 0.0) v->open_seconds = meso_time_seconds() - start_seconds;
    if (drew) {
        record_timing(v,
                      (double[4]){render_seconds, events_seconds, upload_seconds, present_seconds});
        v->frame_total_seconds = render_seconds + events_seconds + upload_seconds + present_seconds;
    }
    update_title(v, false);
    if (v->scripted && v->next_event >= v->num_events && v->frames_to_wait == 0 && !v->job)
        v->running = false; /* the script's last event has been handled and drawn */
}

/* ---- Setting up --------------------------------------------------------------------------- */

/* Whether the window can show technique `name` on the scene: not the reference (C renders
 * it), and it must draw every object. */
static bool technique_shown(const meso_scene *scene, const char *name) {
    const meso_technique_info *info = meso_technique_find(name);
    return info && info->kind != MESO_TECHNIQUE_REFERENCE && app_technique_applies(info, scene);
}

/* The techniques of the window: those of --techniques (each must draw the scene), else every
 * one that can, in the registry's order; and the initial one. Returns -1, or an exit status
 * after printing why. */
static int list_techniques(const meso_scene *scene, const char *const *listed, int num_listed,
                           const char *wanted, const char **names, int *out_count,
                           int *out_initial) {
    int count = 0;
    for (int i = 0; i < num_listed && count < VIEW_MAX_TECHNIQUES; i++) {
        if (!technique_shown(scene, listed[i])) {
            fprintf(stderr, "meso: %s: --techniques: '%s' cannot draw this scene's objects%s\n",
                    scene->path, listed[i],
                    !strcmp(listed[i], "reference") ? " in the window (press C for it)" : "");
            return APP_EXIT_BAD_INPUT;
        }
        names[count++] = listed[i];
    }
    for (size_t i = 0; !listed && i < meso_technique_count() && count < VIEW_MAX_TECHNIQUES; i++) {
        if (technique_shown(scene, meso_technique_get(i)->name))
            names[count++] = meso_technique_get(i)->name;
    }
    const char *initial = wanted ? wanted
                          : scene->num_objects > 0 && scene->objects[0].technique[0]
                              ? scene->objects[0].technique
                              : "flat";
    *out_count = count;
    *out_initial = 0;
    for (int i = 0; i < count; i++)
        if (!strcmp(names[i], initial)) *out_initial = i;
    if (count == 0) {
        fprintf(stderr, "meso: %s: no technique can draw this scene's objects\n", scene->path);
        return APP_EXIT_BAD_INPUT;
    }
    if (wanted && strcmp(names[*out_initial], wanted) != 0) {
        char known[1024];
        app_known_techniques(known, sizeof(known));
        fprintf(stderr, "meso: %s: --technique: '%s' cannot be shown here (%s)\n", scene->path,
                wanted,
                app_technique_known(wanted) ? "it cannot draw this scene's objects, or it is the "
                                              "reference: press C in the window"
                                            : "unknown technique");
        return APP_EXIT_BAD_INPUT;
    }
    return -1;
}

/* Prepare every technique before the window opens (bakes, with the progress bar), so that
 * switching is instant. One that fails is dropped with a warning. */
static int prepare_all(viewer *v) {
    meso_progress *progress =
        meso_progress_begin(v->ctx, "prepare techniques", (uint64_t)v->state.num_techniques);
    int kept = 0, initial = v->state.technique;
    for (int i = 0; i < v->state.num_techniques; i++) {
        int slot = kept;
        v->state.techniques[slot] = v->state.techniques[i];
        v->state.main_option[slot] = v->state.main_option[i];
        v->state.technique = slot; /* prepare_technique reads the state's options of slot */
        if (prepare_technique(v, slot) == MESO_OK) {
            if (i == initial) initial = slot;
            kept++;
        } else if (!v->quiet) {
            fprintf(stderr, "meso: warning: %s: left out: %s\n", v->state.techniques[slot],
                    meso_context_last_error(v->ctx));
        }
        meso_progress_advance(progress, 1);
    }
    meso_progress_end(progress);
    if (kept == 0) return app_fail(v->ctx, MESO_ERROR_UNSUPPORTED);
    v->state.num_techniques = kept;
    v->state.technique = initial < kept ? initial : 0;
    return -1;
}

static void init_state(viewer *v, const char *const *names, int count, int initial) {
    const meso_scene *scene = v->scene;
    view_camera camera = app_camera_to_view(&scene->camera);
    bool directional = scene->num_lights > 0 && scene->lights[0].type == MESO_LIGHT_DIRECTIONAL;
    view_vec3 light = {0, 1, 0};
    if (directional)
        light = (view_vec3){scene->lights[0].direction.x, scene->lights[0].direction.y,
                            scene->lights[0].direction.z};
    view_state_init(&v->state, &camera, directional ? &light : NULL, names, count, initial);
    /* the scene's own switches and options of its own technique are where the viewer starts */
    const char *own = scene->num_objects > 0 && scene->objects[0].technique[0]
                          ? scene->objects[0].technique
                          : "flat";
    v->state.shadows = view_scene_initial_option(scene, own, "shadows", 1) != 0.0;
    v->state.silhouettes = view_scene_initial_option(scene, own, "silhouettes", 1) != 0.0;
    for (int i = 0; i < count; i++) {
        const view_technique_knobs knobs = view_technique_knobs_find(names[i]);
        if (knobs.main_option)
            v->state.main_option[i] =
                view_scene_initial_option(scene, names[i], knobs.main_option, knobs.main_default);
    }
    v->state.adaptive = !v->options->fixed_resolution;
    v->resolution = (view_resolution){1.0, 1.0 / v->options->target_fps};
}

static bool open_window(viewer *v) {
    SDL_SetHint(SDL_HINT_RENDER_SCALE_QUALITY, "1");
    /* The frame is drawn on the CPU already; all SDL does is copy it to the window. Its GL
     * renderer without a GPU is llvmpipe, whose threads compete with meso's for the cores and
     * whose teardown took 2 s. SDL_RENDER_DRIVER in the environment still wins. */
    SDL_SetHintWithPriority(SDL_HINT_RENDER_DRIVER, "software", SDL_HINT_DEFAULT);
    /* and the window surface is the video driver's own (X11: shared memory), not a texture of
     * a GL renderer again (slow through llvmpipe) */
    SDL_SetHintWithPriority(SDL_HINT_FRAMEBUFFER_ACCELERATION, "0", SDL_HINT_DEFAULT);
    v->window = SDL_CreateWindow("meso view", SDL_WINDOWPOS_UNDEFINED, SDL_WINDOWPOS_UNDEFINED,
                                 v->window_width, v->window_height, SDL_WINDOW_RESIZABLE);
    if (v->window) v->sdl = SDL_CreateRenderer(v->window, -1, 0);
    if (v->window && !v->sdl) v->sdl = SDL_CreateRenderer(v->window, -1, SDL_RENDERER_SOFTWARE);
    if (!v->sdl) {
        fprintf(stderr, "meso: view: cannot open a window (SDL: %s)\n", SDL_GetError());
        return false;
    }
    SDL_RendererInfo info;
    if (v->verbose && SDL_GetRendererInfo(v->sdl, &info) == 0)
        fprintf(stderr, "meso: view: SDL video driver %s, renderer %s\n",
                SDL_GetCurrentVideoDriver(), info.name);
    return true;
}

static void print_summary(viewer *v, double seconds) {
    if (v->quiet || v->num_timed == 0) return;
    size_t n = v->num_timed;
    double median[4];
    for (int i = 0; i < 4; i++) median[i] = app_median(v->timed[i], n);
    fprintf(stderr,
            "meso: view: window open %.0f ms after start; %zu frames drawn in %.2f s (%.1f "
            "frames/s), %d below full size; median ms a frame: render %.1f, events %.2f, upload "
            "%.2f, present %.2f; load average %.2f\n",
            1000.0 * v->open_seconds, n, seconds, (double)n / seconds, v->frames_reduced, median[0],
            median[1], median[2], median[3], app_load_average());
}

static void viewer_close(viewer *v) {
    view_reference_destroy(v->job);
    drop_comparison(v);
    for (int i = 0; i < VIEW_MAX_TECHNIQUES; i++) {
        meso_renderer_destroy(v->renderers[i]);
        view_scene_destroy(v->scenes[i]);
    }
    meso_framebuffer_destroy(v->frame);
    if (v->texture) SDL_DestroyTexture(v->texture);
    if (v->sdl) SDL_DestroyRenderer(v->sdl);
    if (v->window) SDL_DestroyWindow(v->window);
    for (int i = 0; i < 4; i++) free(v->timed[i]);
}

/* Whether a window can open. SDL falls back to its offscreen driver when there is no display,
 * which would run an invisible window: that driver (or dummy) counts only when asked for by
 * SDL_VIDEODRIVER (the tests). Without DISPLAY or WAYLAND_DISPLAY SDL is not even started, as
 * its Wayland probe prints to stderr. *out_started: SDL_Init ran (and SDL_Quit is due). */
static bool display_available(bool *out_started, char *reason, size_t reason_size) {
    const char *driver = getenv("SDL_VIDEODRIVER");
    *out_started = false;
    if (!(driver && driver[0]) && !getenv("DISPLAY") && !getenv("WAYLAND_DISPLAY")) {
        snprintf(reason, reason_size, "neither DISPLAY nor WAYLAND_DISPLAY is set");
        return false;
    }
    if (SDL_Init(SDL_INIT_VIDEO) != 0) {
        snprintf(reason, reason_size, "SDL: %s", SDL_GetError());
        return false;
    }
    *out_started = true;
    const char *current = SDL_GetCurrentVideoDriver();
    bool headless = current && (!strcmp(current, "offscreen") || !strcmp(current, "dummy"));
    if (headless && !(driver && !strcmp(driver, current))) {
        snprintf(reason, reason_size, "SDL found only its %s driver", current);
        return false;
    }
    return true;
}

/* Load the --script file or take --events; -1, or an exit status after printing why. */
static int read_script(const view_options *o, viewer *v) {
    const char *text = o->events;
    char *file_text = NULL;
    if (o->script) {
        FILE *f = fopen(o->script, "rb");
        if (!f) {
            fprintf(stderr, "meso: %s: cannot open the script\n", o->script);
            return APP_EXIT_BAD_INPUT;
        }
        file_text = calloc(1, 1 << 20);
        size_t length = file_text ? fread(file_text, 1, (1 << 20) - 1, f) : 0;
        fclose(f);
        if (!file_text) return APP_EXIT_FAILURE;
        file_text[length] = 0;
        text = file_text;
    }
    char error[512];
    int count = view_script_parse(text, v->events, VIEW_SCRIPT_MAX_EVENTS, error, sizeof(error));
    free(file_text);
    if (count < 0) {
        fprintf(stderr, "meso: %s: %s\n", o->script ? o->script : "--events", error);
        return APP_EXIT_BAD_INPUT;
    }
    v->num_events = count;
    v->scripted = true;
    return -1;
}

int meso_cmd_view(int argc, char **argv) {
    double start = meso_time_seconds();
    view_options o = {.target_fps = 30.0};
    const app_option options[] = {
        {"--technique", NULL, APP_OPTION_STRING, &o.technique, "T", "the technique shown first",
         "the first object's", 0, 0},
        {"--techniques", NULL, APP_OPTION_STRING, &o.techniques, "LIST",
         "comma-separated techniques to prepare and switch between",
         "all that can draw the "
         "scene",
         0, 0},
        {"--size", NULL, APP_OPTION_SIZE, &o.size, "WxH", "the window's size", "the scene's", 0, 0},
        {"--fps", NULL, APP_OPTION_DOUBLE, &o.target_fps, "F",
         "frame rate aimed at while the view moves (adaptive resolution)", "30", 1, 1000},
        {"--fixed-resolution", NULL, APP_OPTION_FLAG, &o.fixed_resolution, NULL,
         "always draw at the window's size (A toggles it in the window)", NULL, 0, 0},
        {"--events", NULL, APP_OPTION_STRING, &o.events, "TEXT",
         "replay events one a frame, then quit: 'drag 40,0; light 0,-20; wheel 2; key p' "
         "(docs/viewer.md)",
         NULL, 0, 0},
        {"--script", NULL, APP_OPTION_STRING, &o.script, "FILE", "replay the events in FILE", NULL,
         0, 0},
        {"--screenshot", NULL, APP_OPTION_STRING, &o.screenshot, "OUT.png",
         "where P writes (overwritten each time)", "meso-view-NNNN.png, the next free", 0, 0},
        {"--save-scene", NULL, APP_OPTION_STRING, &o.save_scene, "OUT.json",
         "where W writes the scene with the current camera and light", "SCENE-view.json", 0, 0},
        APP_CAMERA_OVERRIDE_OPTIONS(o.camera),
    };
    app_globals globals;
    const char *positionals[1];
    int num_positionals = 0;
    int status = app_parse_options(&view_help, options, sizeof(options) / sizeof(options[0]), argc,
                                   argv, &globals, positionals, 1, &num_positionals);
    if (status >= 0) return status;
    if (num_positionals < 1) return app_usage_error("view", "missing the SCENE file");
    if (o.events && o.script)
        return app_usage_error("view", "--events and --script exclude each other");
    /* screenshots are PNGs */
    if (o.screenshot && (status = app_check_image_output(o.screenshot, false, "meso view")) >= 0)
        return status;
    const char *listed[VIEW_MAX_TECHNIQUES];
    char listed_storage[1024];
    int num_listed = 0;
    if (o.techniques) {
        num_listed = app_parse_technique_list("view", o.techniques, listed_storage,
                                              sizeof(listed_storage), listed, VIEW_MAX_TECHNIQUES);
        if (num_listed < 0) return APP_EXIT_BAD_INPUT;
    }

    viewer *v = calloc(1, sizeof(*v));
    if (!v) return APP_EXIT_FAILURE;
    v->options = &o;
    v->threads = globals.threads;
    v->quiet = globals.quiet;
    v->verbose = globals.verbose;
    v->running = true;
    if ((o.events || o.script) && (status = read_script(&o, v)) >= 0) {
        free(v);
        return status;
    }
    bool allocated = true;
    for (int i = 0; i < 4; i++)
        allocated &= (v->timed[i] = malloc(MAX_TIMED_FRAMES * sizeof(double))) != NULL;
    v->ctx = app_context_create(&globals);
    meso_result r = MESO_OK;
    bool sdl_started = false;
    char reason[256];
    const char *names[VIEW_MAX_TECHNIQUES];
    int count = 0, initial = 0;
    if (!v->ctx || !allocated) {
        status = APP_EXIT_FAILURE;
    } else if ((r = meso_scene_load(v->ctx, positionals[0], &v->scene)) != MESO_OK) {
        status = app_fail(v->ctx, r); /* the same line as meso render's */
    } else if ((status = app_camera_override_apply("view", &o.camera, v->scene)) >= 0) {
    } else if ((status = list_techniques(v->scene, o.techniques ? listed : NULL, num_listed,
                                         o.technique, names, &count, &initial)) >= 0) {
    } else if (!display_available(&sdl_started, reason, sizeof(reason))) {
        fprintf(stderr,
                "meso: view: no display (%s); for frames without a window use meso render %s "
                "--orbit N -o DIR\n",
                reason, positionals[0]);
        status = APP_EXIT_FAILURE;
    } else {
        v->window_width = o.size.width ? o.size.width : v->scene->width;
        v->window_height = o.size.height ? o.size.height : v->scene->height;
        make_srgb_table(v);
        init_state(v, names, count, initial);
        if ((status = prepare_all(v)) < 0 && open_window(v)) {
            double loop_start = meso_time_seconds();
            while (v->running) run_frame(v, start);
            print_summary(v, meso_time_seconds() - loop_start);
            status = v->status;
        } else if (status < 0) {
            status = APP_EXIT_FAILURE;
        }
    }
    viewer_close(v);
    if (sdl_started) SDL_Quit();
    meso_scene_destroy(v->scene);
    meso_context_destroy(v->ctx);
    free(v);
    return status;
}

#endif /* MESO_HAS_SDL2 */
