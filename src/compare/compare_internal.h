/* Private to the compare module. */
#ifndef MESO_COMPARE_INTERNAL_H
#define MESO_COMPARE_INTERNAL_H

#include "meso/compare.h"

/* Text metrics in pixels (times the scale) of compare_text.c: DejaVu Sans Mono at 10 px. */
#define COMPARE_FONT_ADVANCE 6
#define COMPARE_FONT_LINE 12

/* The size a text takes when drawn with meso_image_draw_text. */
void compare_text_size(const char *text, int scale, int *out_width, int *out_height);

#endif
