/* Scripted input for `meso view --events "..."` / `--script FILE` (docs/viewer.md): a short
 * text of events replayed one a frame as if typed and dragged, so the window can be tested
 * without a person (and without a display, under SDL's offscreen driver).
 *
 * Grammar: events separated by ';' or new lines, '#' starts a comment to the end of the line.
 *   key K         press a key: one character (p, W, 3, +) or tab, shift+tab, esc
 *   drag DX,DY    drag with the left button (orbit), in pixels
 *   light DX,DY   drag with Shift held (turn the light)
 *   pan DX,DY     drag with the right button
 *   wheel N       turn the wheel N notches (positive: closer)
 *   wait          wait until the background reference render has finished
 *   frames N      let N frames pass (e.g. so that adaptive resolution settles)
 * After the last event the viewer quits.
 *
 * Pure: no SDL, no libmeso; thread-compatible.
 */
#ifndef MESO_APP_VIEW_SCRIPT_H
#define MESO_APP_VIEW_SCRIPT_H

#include <stdbool.h>
#include <stddef.h>

#define VIEW_SCRIPT_MAX_EVENTS 4096

typedef enum view_event_type {
    VIEW_EVENT_KEY = 0,
    VIEW_EVENT_DRAG,
    VIEW_EVENT_LIGHT,
    VIEW_EVENT_PAN,
    VIEW_EVENT_WHEEL,
    VIEW_EVENT_WAIT,
    VIEW_EVENT_FRAMES,
} view_event_type;

typedef struct view_event {
    view_event_type type;
    int key;       /* KEY: a character as in view_state.h ('\t', 27 for Escape) */
    bool shift;    /* KEY: with Shift */
    double dx, dy; /* DRAG, LIGHT, PAN: pixels; WHEEL: dx = notches */
    int count;     /* FRAMES */
} view_event;

/* Parse `text` into events (at most max_events). Returns the count, or -1 with a message
 * ("event 3: 'drag 1': expected DX,DY") in error (error_size bytes). */
int view_script_parse(const char *text, view_event *events, int max_events, char *error,
                      size_t error_size);

#endif
