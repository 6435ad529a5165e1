/* The example scenes compiled into the program (cmake/embed_examples.cmake), and the files of
 * examples/assets they read. */
#ifndef MESO_APP_EXAMPLES_EMBEDDED_H
#define MESO_APP_EXAMPLES_EMBEDDED_H
#include <stddef.h>

typedef struct meso_embedded_example {
    const char *name; /* file name without .json, e.g. "bricks-plane" */
    const char *json; /* the scene text, NUL-terminated */
    int uses_assets;  /* it names files of examples/assets ("assets/chainmail-tile.obj") */
} meso_embedded_example;

typedef struct meso_embedded_asset {
    const char *path; /* relative to examples/: "assets/chainmail-tile.obj" */
    const unsigned char *bytes;
    size_t size;
} meso_embedded_asset;

extern const meso_embedded_example meso_embedded_examples[];
extern const size_t meso_embedded_example_count;
extern const meso_embedded_asset meso_embedded_assets[];
extern const size_t meso_embedded_asset_count;

#endif
