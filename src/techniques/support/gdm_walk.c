/* gdm's shell walk: the fin twin table, the prisms' adjacency (gdm_walk.h). */
#include "gdm_walk.h"

#include <stdlib.h>
#include <string.h>
#include "meso/prism.h"

/* A fin triangle's key: its three vertex positions' bits, sorted, and its face. Twins have
 * equal keys. */
typedef struct fin_key {
    uint32_t bits[9];
    uint32_t face;
} fin_key;

static int compare_fin_keys(const void *a, const void *b) {
    const fin_key *x = a, *y = b;
    int c = memcmp(x->bits, y->bits, sizeof x->bits);
    if (c) return c;
    return (x->face > y->face) - (x->face < y->face);
}

static int compare_bits3(const void *a, const void *b) {
    return memcmp(a, b, 3 * sizeof(uint32_t));
}

/* The twin table (gdm_walk.h): keys with exactly two faces whose prisms differ pair up; a key
 * shared by more (a non-manifold edge) or by one (an open border) leaves GDM_NO_TWIN. */
uint32_t *gdm_fin_twins(const meso_prism_layer *layer) {
    const meso_mesh *faces = layer->faces;
    size_t num_faces = faces->num_triangles, num_fins = layer->num_prisms * 6;
    uint32_t *twin = malloc(num_faces * sizeof *twin);
    fin_key *keys = malloc((num_fins ? num_fins : 1) * sizeof *keys);
    if (!twin || !keys) {
        free(twin);
        free(keys);
        return NULL;
    }
    for (size_t f = 0; f < num_faces; f++) twin[f] = GDM_NO_TWIN;
    size_t n = 0;
    for (size_t prism = 0; prism < layer->num_prisms; prism++)
        for (int slot = MESO_PRISM_FIN; slot < MESO_PRISM_NUM_FACES; slot++) {
            size_t f = meso_prism_layer_face(layer, prism, slot);
            uint32_t corner[3][3];
            for (int k = 0; k < 3; k++)
                memcpy(corner[k], &faces->positions[faces->indices[3 * f + (size_t)k]],
                       3 * sizeof(uint32_t));
            qsort(corner, 3, sizeof corner[0], compare_bits3);
            memcpy(keys[n].bits, corner, sizeof keys[n].bits);
            keys[n++].face = (uint32_t)f;
        }
    qsort(keys, n, sizeof *keys, compare_fin_keys);
    for (size_t i = 0; i < n;) {
        size_t j = i + 1;
        while (j < n && memcmp(keys[j].bits, keys[i].bits, sizeof keys[i].bits) == 0) j++;
        if (j - i == 2) {
            int slot;
            size_t a = meso_prism_layer_face_prism(layer, keys[i].face, &slot);
            size_t b = meso_prism_layer_face_prism(layer, keys[i + 1].face, &slot);
            if (a != b)
                twin[keys[i].face] = keys[i + 1].face, twin[keys[i + 1].face] = keys[i].face;
        }
        i = j;
    }
    free(keys);
    return twin;
}
