/* Text in sheets and plots: cairo with the DejaVu Sans Mono font (Debian's fonts-dejavu-core,
 * found through fontconfig), anti-aliased, composited onto the float image. Replaces a
 * hand-drawn 5x7 font that had no descenders ("bumP", "relief.Png"). Monospaced, so the
 * layout code can size a label from its character count (compare_text_size). */
#include <cairo.h>
#include <math.h>
#include <string.h>

#include "compare_internal.h"

/* Font size in pixels at scale 1: DejaVu Sans Mono advances 0.602 em, so 10 px gives the
 * 6-pixel advance of COMPARE_FONT_ADVANCE; ascent + descent is 11.6 px, inside the 12-pixel
 * line of COMPARE_FONT_LINE. */
#define FONT_PIXELS 10.0

/* One line of text into an 8-bit coverage mask, composited at (x, y) = its top left. */
static void draw_line(meso_image *image, int x, int y, double size, const float color[3],
                      const char *line, size_t length) {
    if (length == 0) return;
    char text[1024];
    length = length < sizeof text - 1 ? length : sizeof text - 1;
    for (size_t i = 0; i < length; i++) { /* printable ASCII only: labels are ours or escaped */
        unsigned char c = (unsigned char)line[i];
        text[i] = c >= 32 && c <= 126 ? (char)c : '?';
    }
    text[length] = 0;
    int width = (int)ceil((double)length * size * 0.61) + 2;
    int height = (int)ceil(size * COMPARE_FONT_LINE / FONT_PIXELS) + 1;
    cairo_surface_t *mask = cairo_image_surface_create(CAIRO_FORMAT_A8, width, height);
    cairo_t *cr = cairo_create(mask);
    if (cairo_status(cr) != CAIRO_STATUS_SUCCESS) goto done; /* out of memory: no text */
    cairo_select_font_face(cr, "DejaVu Sans Mono", CAIRO_FONT_SLANT_NORMAL,
                           CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(cr, size);
    cairo_font_extents_t font;
    cairo_font_extents(cr, &font);
    cairo_move_to(cr, 0.0, round(font.ascent));
    cairo_show_text(cr, text);
    cairo_surface_flush(mask);
    const unsigned char *alpha = cairo_image_surface_get_data(mask);
    int stride = cairo_image_surface_get_stride(mask);
    for (int row = 0; row < height; row++)
        for (int col = 0; col < width; col++) {
            float a = (float)alpha[(size_t)row * (size_t)stride + (size_t)col] / 255.0f;
            int px = x + col, py = y + row;
            if (a <= 0.0f || px < 0 || py < 0 || px >= image->width || py >= image->height)
                continue;
            float *p = meso_image_at(image, px, py);
            for (int c = 0; c < 3; c++) p[c] += (color[c] - p[c]) * a;
        }
done:
    cairo_destroy(cr);
    cairo_surface_destroy(mask);
}

void meso_image_draw_text(meso_image *image, int x, int y, int scale, const float color[3],
                          const char *text) {
    if (!image || !text || !color || image->channels < 3) return;
    if (scale < 1) scale = 1;
    int pen_y = y;
    for (const char *line = text;;) {
        const char *end = strchr(line, '\n');
        size_t length = end ? (size_t)(end - line) : strlen(line);
        draw_line(image, x, pen_y, FONT_PIXELS * scale, color, line, length);
        if (!end) break;
        line = end + 1;
        pen_y += COMPARE_FONT_LINE * scale;
    }
}

void compare_text_size(const char *text, int scale, int *out_width, int *out_height) {
    int lines = 1, longest = 0, current = 0;
    for (const char *s = text ? text : ""; *s; s++) {
        if (*s == '\n') {
            lines++;
            current = 0;
            continue;
        }
        current++;
        longest = current > longest ? current : longest;
    }
    *out_width = longest * COMPARE_FONT_ADVANCE * scale;
    *out_height = lines * COMPARE_FONT_LINE * scale;
}
