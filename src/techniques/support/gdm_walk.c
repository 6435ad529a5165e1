/* gdm's shell walk: the fin twin table, the prisms' adjacency (gdm_walk.h). */
#include "gdm_walk.h"

#include <math.h>
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

/* A prism that folds (geom_prism.c, unbind_folded_faces: the shell deeper than the surface's
 * radius of curvature there): some of its planes are unbound. */
static bool prism_folded(const meso_prism_layer *layer, size_t prism) {
    const meso_prism_plane *planes = layer->planes + prism * MESO_PRISM_NUM_FACES;
    for (int slot = MESO_PRISM_BOTTOM; slot < MESO_PRISM_NUM_FACES; slot++)
        if (planes[slot].normal.x == 0.0f && planes[slot].normal.y == 0.0f &&
            planes[slot].normal.z == 0.0f)
            return layer->prisms[prism].valid;
    return false;
}

/* The walk's adjacency and the faces it draws (gdm_walk.h, gdm_walk_boundary): every top, the fins
 * without a twin (open borders, non-manifold edges), every bottom (a ray from inside the base
 * mesh, or below an open one, enters there), and both copies of every fin of a folded prism.
 * Where prisms fold the shell overlaps itself (the teapot's lid rim and knob): a ray inside
 * one prism is inside another too, whose fins it crosses without leaving the first, so the walk
 * alone would miss it; there each fin's own fragment starts a walk, as every face's does in the
 * per-prism drawing (weave-teapot: 17 % of the fins, the coverage IoU of the per-prism drawing;
 * without them 0.4 % of the outline lost). false: out of memory. */
bool gdm_walk_boundary(const meso_prism_layer *layer, uint32_t **out_twin, uint32_t **out_boundary,
                       uint8_t **out_same_uvw, size_t group_start[4]) {
    size_t n = layer->num_prisms;
    uint32_t *fin_twin = *out_twin = gdm_fin_twins(layer);
    uint32_t *boundary = *out_boundary = malloc((n ? 8 * n : 1) * sizeof *boundary);
    uint8_t *same_uvw = *out_same_uvw = calloc(n ? 8 * n : 1, 1);
    if (!fin_twin || !boundary || !same_uvw) return false;
    for (size_t f = n; f < 7 * n; f++) {
        uint32_t twin = fin_twin[f];
        if (twin == GDM_NO_TWIN) continue;
        const meso_vec3 *a = layer->face_frames[f].uvw, *b = layer->face_frames[twin].uvw;
        bool same = true;
        for (int i = 0; i < 3 && same; i++) {
            bool found = false;
            for (int j = 0; j < 3 && !found; j++)
                found = a[i].x == b[j].x && a[i].y == b[j].y && a[i].z == b[j].z;
            same = found;
        }
        same_uvw[f] = same;
    }
    size_t count = 0;
    for (size_t f = 0; f < n; f++) boundary[count++] = (uint32_t)f;
    for (size_t f = n; f < 7 * n; f++) {
        int slot;
        size_t prism = meso_prism_layer_face_prism(layer, f, &slot);
        uint32_t twin = fin_twin[f];
        size_t other =
            twin == GDM_NO_TWIN ? prism : meso_prism_layer_face_prism(layer, twin, &slot);
        if (gdm_walk_face_is_boundary(fin_twin, f) || prism_folded(layer, prism) ||
            prism_folded(layer, other))
            boundary[count++] = (uint32_t)f;
    }
    group_start[2] = count;
    for (size_t f = 7 * n; f < 8 * n; f++) boundary[count++] = (uint32_t)f;
    group_start[3] = count;
    group_start[0] = 0, group_start[1] = n;
    uint32_t *fit = realloc(boundary, (count ? count : 1) * sizeof *boundary);
    if (fit) *out_boundary = fit;
    return true;
}

/* The faces in a frame's drawing order (gdm_walk.h): each group front to back by a counting
 * sort of the centroids' view depth into GDM_DEPTH_BUCKETS (linear, O(faces), a fixed order
 * within a bucket: deterministic). */
void gdm_walk_sort_faces(const meso_mesh *faces, const uint32_t *boundary,
                         const size_t group_start[4], meso_vec3 eye, meso_vec3 forward, float *keys,
                         uint32_t *count, uint32_t *drawn_face, uint32_t *drawn_indices) {
    size_t total = group_start[3];
    float lo = INFINITY, hi = -INFINITY;
    for (size_t k = 0; k < total; k++) { /* k: a place in the list of faces drawn */
        size_t f = boundary ? boundary[k] : k;
        const uint32_t *idx = faces->indices + 3 * f;
        meso_vec3 c =
            meso_vec3_add(meso_vec3_add(faces->positions[idx[0]], faces->positions[idx[1]]),
                          faces->positions[idx[2]]);
        float key = meso_vec3_dot(meso_vec3_sub(meso_vec3_scale(c, 1.0f / 3.0f), eye), forward);
        keys[k] = isfinite(key) ? key : 0.0f;
        lo = fminf(lo, keys[k]);
        hi = fmaxf(hi, keys[k]);
    }
    float scale = hi > lo ? (float)(GDM_DEPTH_BUCKETS - 1) / (hi - lo) : 0.0f;
    for (int g = 0; g < 3; g++) { /* tops, fins, bottoms */
        memset(count, 0, sizeof(uint32_t) * (GDM_DEPTH_BUCKETS + 1));
        for (size_t k = group_start[g]; k < group_start[g + 1]; k++)
            count[1 + (int)((keys[k] - lo) * scale)]++;
        for (int b = 0; b < GDM_DEPTH_BUCKETS; b++) count[b + 1] += count[b];
        for (size_t k = group_start[g]; k < group_start[g + 1]; k++) {
            size_t f = boundary ? boundary[k] : k;
            size_t slot = group_start[g] + count[(int)((keys[k] - lo) * scale)]++;
            drawn_face[slot] = (uint32_t)f;
            memcpy(drawn_indices + 3 * slot, faces->indices + 3 * f, 3 * sizeof(uint32_t));
        }
    }
}
