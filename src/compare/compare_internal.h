/* Private to the compare module. */
#ifndef MESO_COMPARE_INTERNAL_H
#define MESO_COMPARE_INTERNAL_H

#include "meso/compare.h"

/* Font metrics in font pixels (times the scale): glyph 5 x 7, advance 6, line 9. */
#define COMPARE_FONT_ADVANCE 6
#define COMPARE_FONT_LINE 9

/* The size a text takes when drawn with meso_image_draw_text. */
void compare_text_size(const char *text, int scale, int *out_width, int *out_height);

#endif
