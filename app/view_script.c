/* Scripted input for meso view (view_script.h). */
#include "view_script.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A key name: one printable character, or a named key. Returns false when unknown. */
static bool parse_key(const char *word, int *out_key, bool *out_shift) {
    *out_shift = false;
    if (!strncmp(word, "shift+", 6)) {
        *out_shift = true;
        word += 6;
    }
    if (!strcmp(word, "tab"))
        *out_key = '\t';
    else if (!strcmp(word, "esc"))
        *out_key = 27;
    else if (strlen(word) == 1 && isgraph((unsigned char)word[0])) {
        *out_key = (unsigned char)word[0];
        if (isupper(*out_key)) { /* "W" is Shift+w, as a keyboard sends it */
            *out_key = tolower(*out_key);
            *out_shift = true;
        }
    } else
        return false;
    return true;
}

static bool parse_pair(const char *text, double *out_x, double *out_y) {
    char *end = NULL;
    *out_x = strtod(text, &end);
    if (end == text || *end != ',') return false;
    const char *second = end + 1;
    *out_y = strtod(second, &end);
    return end != second && *end == 0 && isfinite(*out_x) && isfinite(*out_y);
}

/* Parse one event "verb argument" (already trimmed, not empty). */
static bool parse_event(const char *verb, const char *argument, view_event *event,
                        const char **out_problem) {
    memset(event, 0, sizeof(*event));
    *out_problem = NULL;
    if (!strcmp(verb, "key")) {
        event->type = VIEW_EVENT_KEY;
        if (!parse_key(argument, &event->key, &event->shift)) *out_problem = "unknown key";
    } else if (!strcmp(verb, "drag") || !strcmp(verb, "light") || !strcmp(verb, "pan")) {
        event->type = verb[0] == 'd'   ? VIEW_EVENT_DRAG
                      : verb[0] == 'l' ? VIEW_EVENT_LIGHT
                                       : VIEW_EVENT_PAN;
        if (!parse_pair(argument, &event->dx, &event->dy)) *out_problem = "expected DX,DY";
    } else if (!strcmp(verb, "wheel")) {
        char *end = NULL;
        event->type = VIEW_EVENT_WHEEL;
        event->dx = strtod(argument, &end);
        if (end == argument || *end || !isfinite(event->dx)) *out_problem = "expected N";
    } else if (!strcmp(verb, "wait")) {
        event->type = VIEW_EVENT_WAIT;
        if (*argument) *out_problem = "takes no argument";
    } else if (!strcmp(verb, "frames")) {
        char *end = NULL;
        event->type = VIEW_EVENT_FRAMES;
        long n = strtol(argument, &end, 10);
        if (end == argument || *end || n < 1 || n > 100000)
            *out_problem = "expected N in 1..100000";
        event->count = (int)n;
    } else {
        *out_problem = "unknown event (key, drag, light, pan, wheel, wait, frames)";
    }
    return *out_problem == NULL;
}

int view_script_parse(const char *text, view_event *events, int max_events, char *error,
                      size_t error_size) {
    int count = 0;
    const char *p = text ? text : "";
    while (*p) {
        /* one event: up to ';' or a new line; a comment runs to the end of the line */
        size_t length = strcspn(p, ";\n#");
        char item[256];
        const char *next = p + length;
        if (*next == '#') next += strcspn(next, "\n");
        if (*next) next++;
        while (length > 0 && isspace((unsigned char)*p)) p++, length--;
        while (length > 0 && isspace((unsigned char)p[length - 1])) length--;
        if (length == 0) {
            p = next;
            continue;
        }
        if (length >= sizeof(item)) {
            snprintf(error, error_size, "event %d: longer than %zu characters", count + 1,
                     sizeof(item) - 1);
            return -1;
        }
        memcpy(item, p, length);
        item[length] = 0;
        char *argument = item + strcspn(item, " \t");
        if (*argument) *argument++ = 0;
        while (isspace((unsigned char)*argument)) argument++;
        const char *problem = NULL;
        view_event event;
        if (!parse_event(item, argument, &event, &problem)) {
            snprintf(error, error_size, "event %d: '%s%s%s': %s", count + 1, item,
                     *argument ? " " : "", argument, problem);
            return -1;
        }
        if (count >= max_events) {
            snprintf(error, error_size, "more than %d events", max_events);
            return -1;
        }
        events[count++] = event;
        p = next;
    }
    return count;
}
