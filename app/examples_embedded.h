/* The example scenes compiled into the program (cmake/embed_examples.cmake). */
#ifndef MESO_APP_EXAMPLES_EMBEDDED_H
#define MESO_APP_EXAMPLES_EMBEDDED_H
#include <stddef.h>

typedef struct meso_embedded_example {
    const char *name; /* file name without .json, e.g. "bricks-plane" */
    const char *json; /* the scene text, NUL-terminated */
} meso_embedded_example;

extern const meso_embedded_example meso_embedded_examples[];
extern const size_t meso_embedded_example_count;

#endif
