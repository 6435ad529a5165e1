/* Shared code of `displacement` and `tessellation`: vertex displacement, the recursive midpoint
 * tessellator of Doggett & Hirche 2000, shading with the height field's normal, shadow maps.
 * See displace_common.h for the contracts and the crack-freeness argument. */
#include "displace_common.h"

#include <math.h>
#include <stdatomic.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include "meso/runtime.h"

/* ---- The displaced surface ---------------------------------------------------------------- */

typedef struct colocated_record {
    uint32_t position[3]; /* the bits of the base position */
    uint32_t vertex;
} colocated_record;

static int compare_colocated(const void *a, const void *b) {
    const colocated_record *x = a, *y = b;
    int c = memcmp(x->position, y->position, sizeof x->position);
    if (c) return c;
    return x->vertex < y->vertex ? -1 : x->vertex > y->vertex;
}

/* Whether two vertices at one position can displace to different points: they differ in the
 * height they sample (the wrapped uv) or in the normal they move along. Both sides of a seam
 * whose uvs differ by whole tiles wrap to the same uv and agree. */
static bool displace_differently(const displace_surface *surface, uint32_t a, uint32_t b) {
    const meso_mesh *m = surface->base;
    meso_vec2 ta = displace_texture_uv(surface, m->uvs[a]);
    meso_vec2 tb = displace_texture_uv(surface, m->uvs[b]);
    meso_vec3 na = meso_vec3_normalize(m->normals[a]), nb = meso_vec3_normalize(m->normals[b]);
    return memcmp(&ta, &tb, sizeof ta) != 0 || memcmp(&na, &nb, sizeof na) != 0;
}

/* Sets surface->both_faces (displace_common.h): an open border of the base mesh (edges paired
 * by their end points' positions, meso_mesh_open_border_edges), or a displaced tear: two
 * vertices at one position that displace differently (only with a height field and a depth:
 * otherwise every vertex stays where it is). False when out of memory. */
static bool find_open_surface(displace_surface *surface) {
    const meso_mesh *mesh = surface->base;
    uint8_t *border = meso_mesh_open_border_edges(mesh);
    if (!border) return false;
    bool open = false;
    for (size_t t = 0; t < mesh->num_triangles && !open; t++) open = border[t] != 0;
    free(border);
    if (!open && surface->heightfield && surface->depth > 0.0f && mesh->num_vertices > 1) {
        colocated_record *records = malloc(mesh->num_vertices * sizeof *records);
        if (!records) return false;
        for (size_t i = 0; i < mesh->num_vertices; i++) {
            memcpy(records[i].position, &mesh->positions[i], sizeof records[i].position);
            records[i].vertex = (uint32_t)i;
        }
        qsort(records, mesh->num_vertices, sizeof *records, compare_colocated);
        for (size_t i = 1; i < mesh->num_vertices && !open; i++)
            open =
                !memcmp(records[i].position, records[i - 1].position, sizeof records[i].position) &&
                displace_differently(surface, records[i].vertex, records[i - 1].vertex);
        free(records);
    }
    surface->both_faces = open;
    return true;
}

meso_result displace_surface_init(meso_context *ctx, const meso_object *object,
                                  displace_surface *out_surface) {
    memset(out_surface, 0, sizeof(*out_surface));
    if (!object->mesh || object->mesh->num_triangles == 0)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: mesh: has no triangles",
                              object->name);
    out_surface->object = object;
    out_surface->base = object->mesh;
    if (object->mesostructure.kind == MESO_MESOSTRUCTURE_HEIGHT_FIELD &&
        object->mesostructure.height_field) {
        const meso_heightfield *hf = object->mesostructure.height_field;
        if (!object->mesh->uvs)
            return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                                  "%s: mesh: the height field needs texture coordinates",
                                  object->name);
        if (!isfinite(object->mesostructure.depth) || object->mesostructure.depth < 0.0f)
            return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                                  "%s: mesostructure.depth: must be a finite number >= 0",
                                  object->name);
        out_surface->heightfield = hf;
        out_surface->depth = object->mesostructure.depth;
        out_surface->repeat = hf->wrap != MESO_WRAP_CLAMP;
    }
    if (!find_open_surface(out_surface))
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: mesh: open borders",
                              object->name);
    return MESO_OK;
}

float displace_height(const displace_surface *surface, meso_vec2 uv) {
    if (!surface->heightfield) return 1.0f;
    meso_vec2 t = displace_texture_uv(surface, uv);
    return meso_heightfield_sample(surface->heightfield, t.x, t.y);
}

meso_vec2 displace_gradient(const displace_surface *surface, meso_vec2 uv) {
    if (!surface->heightfield) return (meso_vec2){0.0f, 0.0f};
    meso_vec2 t = displace_texture_uv(surface, uv);
    return displace_heightfield_gradient(surface->heightfield, t.x, t.y);
}

/* docs/design.md: P' = P - (1 - h) depth N, N the normalised interpolated vertex normal */
static meso_vec3 displaced_position(const displace_surface *surface,
                                    const displace_vertex *vertex) {
    return meso_vec3_madd(vertex->base, vertex->unit_normal,
                          -(1.0f - vertex->height) * surface->depth);
}

void displace_vertex_finish(const displace_surface *surface, displace_vertex *vertex) {
    vertex->texture_uv = displace_texture_uv(surface, vertex->uv);
    vertex->unit_normal = meso_vec3_normalize(vertex->normal);
    vertex->height = surface->heightfield
                         ? meso_heightfield_sample(surface->heightfield, vertex->texture_uv.x,
                                                   vertex->texture_uv.y)
                         : 1.0f;
    vertex->position = displaced_position(surface, vertex);
}

int displace_texel_level(const displace_surface *surface, int max_level) {
    const meso_mesh *mesh = surface->base;
    const meso_heightfield *hf = surface->heightfield;
    if (!hf || !mesh->uvs) return 0;
    float longest = 0.0f;
    for (size_t t = 0; t < mesh->num_triangles; t++)
        for (int k = 0; k < 3; k++) {
            meso_vec2 a = mesh->uvs[mesh->indices[t * 3 + (size_t)k]];
            meso_vec2 b = mesh->uvs[mesh->indices[t * 3 + (size_t)(k + 1) % 3]];
            float len =
                fmaxf(fabsf(b.x - a.x) * (float)hf->width, fabsf(b.y - a.y) * (float)hf->height);
            if (len > longest) longest = len;
        }
    int level = 0;
    while (level < max_level && longest > 1.0f) {
        longest *= 0.5f;
        level++;
    }
    return level;
}

/* (a + b) * 0.5 per component: commutative, so both triangles of an edge get the same bits. */
static meso_vec3 mid3(meso_vec3 a, meso_vec3 b) {
    return (meso_vec3){(a.x + b.x) * 0.5f, (a.y + b.y) * 0.5f, (a.z + b.z) * 0.5f};
}

/* The midpoint's uv: all the vetoes read (through its texel). */
static void vertex_midpoint_uv(const displace_vertex *a, const displace_vertex *b,
                               displace_vertex *out) {
    out->uv = (meso_vec2){(a->uv.x + b->uv.x) * 0.5f, (a->uv.y + b->uv.y) * 0.5f};
}

/* The rest of the interpolated fields, only for a midpoint that survived the vetoes (most do
 * not on bricks-teapot, and nothing reads a vetoed record's other fields). */
static void vertex_midpoint_frame(const displace_vertex *a, const displace_vertex *b,
                                  displace_vertex *out) {
    out->base = mid3(a->base, b->base);
    out->normal = mid3(a->normal, b->normal);
    out->tangent = mid3(a->tangent, b->tangent);
    out->bitangent = mid3(a->bitangent, b->bitangent);
}

/* A total order on vertices that both triangles of an edge agree on: by base position, then
 * uv (never needed for a valid mesh: an edge's end points differ in position). */
static inline bool vertex_before(const displace_vertex *a, const displace_vertex *b) {
    if (a->base.x != b->base.x) return a->base.x < b->base.x;
    if (a->base.y != b->base.y) return a->base.y < b->base.y;
    if (a->base.z != b->base.z) return a->base.z < b->base.z;
    if (a->uv.x != b->uv.x) return a->uv.x < b->uv.x;
    return a->uv.y < b->uv.y;
}

/* ---- The tessellator ---------------------------------------------------------------------- */

typedef struct tess_entry {
    int32_t v[3];
    int32_t depth;
} tess_entry;

/* A veto asked during a traversal: the nodes it read and its answer (the top bit of
 * m_vetoed; node indices are below 2^31). */
typedef struct tess_asked {
    int32_t a, b;
    uint32_t m_vetoed;
} tess_asked;

/* What a replay reads of a displaced node besides its texel: the vertex hook's inputs. */
typedef struct tess_record_hooked {
    int32_t node;
    meso_vec3 position, unit_normal;
} tess_record_hooked;

/* One base triangle's last traversal (displace_tessellator_run), in one block: its nodes, the
 * vetoes in order, its output (vertices, indices from 0, each triangle's recursion depth). */
typedef struct tess_record {
    bool valid;
    void *block;
    size_t cap_bytes;
    /* kept small: a replay streams through every record each frame */
    size_t num_nodes, num_hooked, num_asked, num_vertices, num_triangles;
    int32_t *texels; /* each node's texel_i, texel_j (the recursion-limit test's) */
    tess_record_hooked *hooked;
    tess_asked *asked;
    meso_vec3 *positions, *normals, *tangents, *bitangents;
    meso_vec2 *uvs;
    uint32_t *indices;
    uint8_t *depths;
    uint64_t counters[DISPLACE_NUM_COUNTERS]; /* what the traversal added */
    uint64_t grid_limited;
    size_t memo_used;
} tess_record;

typedef struct tess_scratch {
    displace_vertex *nodes;
    size_t num_nodes, cap_nodes;
    /* the traversal being recorded: the vetoes asked and the depths of the emitted triangles */
    bool recording;
    tess_asked *asked;
    size_t num_asked, cap_asked;
    uint8_t *depths;
    size_t num_depths, cap_depths;
    bool record_failed; /* out of memory while logging: do not keep this traversal */
    int32_t *grid;      /* (n+1)^2 node index per grid point ... */
    uint32_t *stamp;    /* ... valid when stamp == current (no clearing per triangle) */
    uint32_t current;
    tess_entry *stack;
    size_t cap_stack;
} tess_scratch;

/* A displaced midpoint remembered across runs (displace_tessellator_run): its inputs, what
 * displace_vertex_finish and vertex_static derived from them, and the edge's decision with the
 * end points' fields it read. */
typedef struct tess_memo {
    uint64_t key; /* base triangle and grid point (memo_key) */
    /* the inputs, laid out as displace_vertex's base ... uv (compared as one block) */
    meso_vec3 base, normal, tangent, bitangent;
    meso_vec2 uv;
    /* derived (texture_uv and position are computed again from these: cheap, and a fifth of
     * the bytes) */
    meso_vec3 unit_normal, surface_normal;
    float height;
    /* the decision's other inputs: a's and b's uv and surface normal, in the canonical order */
    meso_vec2 uv_a, uv_b;
    meso_vec3 surface_normal_a, surface_normal_b;
    uint8_t decided, inserted;
    uint8_t counters; /* bit c: the decision incremented counter c */
} tess_memo;

#define MEMO_PAGE_BITS 10 /* 1,024 entries (139 kB) a page */
#define MEMO_PAGE_ENTRIES ((size_t)1 << MEMO_PAGE_BITS)
#define MEMO_INPUT_BYTES (4 * sizeof(meso_vec3) + sizeof(meso_vec2))
_Static_assert(offsetof(displace_vertex, uv) - offsetof(displace_vertex, base) ==
                       4 * sizeof(meso_vec3) &&
                   offsetof(tess_memo, uv) - offsetof(tess_memo, base) == 4 * sizeof(meso_vec3),
               "the inputs are one block of base, normal, tangent, bitangent, uv");

/* A slot of a job's memo table: entry index + 1 (0: empty), and 32 bits of the key's hash that
 * the slot's position does not use, so that a probe passing another key's slot mostly skips
 * reading that entry (a cache miss each: the memo's look-ups were a large part of a moving
 * bricks-teapot frame's time). */
typedef struct tess_memo_slot {
    uint32_t entry;
    uint32_t tag;
} tess_memo_slot;

/* What one output triangle of a run costs at most, all told: its share of the output's
 * vertices and indices in the job and again in the joined mesh, of the record kept for the
 * replay, of the memo and of the traversal's nodes (about half a vertex each). A run stops
 * with MESO_ERROR_LIMIT once its triangles would need more than the memory limit: levels and
 * thresholds can ask for 4^max_level triangles a base triangle (8.6 G on a 64-segment plane at
 * level 10), far more than the machine holds. Measured peak of such a refused run: within the
 * limit (docs/robustness.md). */
#define TESS_BYTES_PER_TRIANGLE 512
/* Jobs add their triangles to the run's shared count in blocks of this many, as each block is
 * complete (an atomic add per triangle would bounce a cache line between the workers). The
 * count lags the truth by less than a block a job (256 jobs: 65,536 triangles, 32 MB), and its
 * final value does not depend on the order, so whether a run exceeds the bound does not
 * depend on the threads. */
#define TESS_COUNT_STEP 256

typedef struct tess_job {
    size_t first, count;          /* base triangles */
    atomic_size_t *run_triangles; /* the run's shared count (steps of TESS_COUNT_STEP) */
    size_t max_triangles;         /* the run's bound */
    size_t num_vertices, cap_vertices, num_triangles, cap_triangles;
    meso_vec3 *positions, *normals, *tangents, *bitangents;
    meso_vec2 *uvs;
    uint32_t *indices;
    size_t vertex_offset, triangle_offset; /* in the joined mesh */
    displace_tess_stats stats;
    meso_result result;
    /* the remembered midpoints of this job's triangles: entries in pages of MEMO_PAGE_ENTRIES
     * (memo_entry), and an open-addressing table of entry index + 1 (0: empty) with
     * 2^memo_bits slots, at most half full */
    tess_memo **memo_pages;
    size_t num_memo_pages, cap_memo_pages;
    tess_memo_slot *memo_slots;
    size_t num_memo, cap_memo; /* cap_memo: num_memo_pages * MEMO_PAGE_ENTRIES */
    int memo_bits;
    size_t memo_used;     /* entries read or written by the last run */
    tess_record *records; /* count, one a base triangle (NULL until the first replayable run) */
} tess_job;

struct displace_tessellator {
    const displace_surface *surface;
    int max_level;
    int32_t n; /* 2^max_level segments per base edge */
    int num_threads;
    tess_scratch *scratch;
    size_t num_jobs;
    atomic_size_t run_triangles; /* output triangles of the run so far (tess_job) */
    size_t max_triangles;
    tess_job *jobs;
    displace_vertex *corners; /* the base mesh's vertices, displaced, vertex_static applied */
    bool corners_ready;
    meso_mesh mesh; /* arrays owned here (not by meso_mesh_create) */
    size_t cap_vertices, cap_triangles;
    const displace_edge_tests *tests; /* during a run */
};

#define TESS_MAX_JOBS 256

/* Scratch for `count` workers (the context may gain threads after creation, as `meso bench`
 * does when it measures scaling). */
static bool ensure_scratch(displace_tessellator *t, int count) {
    if (count <= t->num_threads) return true;
    tess_scratch *grown = realloc(t->scratch, (size_t)count * sizeof(*grown));
    if (!grown) return false;
    t->scratch = grown;
    memset(grown + t->num_threads, 0, (size_t)(count - t->num_threads) * sizeof(*grown));
    int first = t->num_threads;
    t->num_threads = count; /* destroy frees every entry, zeroed ones included */
    size_t side = (size_t)t->n + 1;
    for (int i = first; i < count; i++) {
        tess_scratch *s = &t->scratch[i];
        /* grown on demand up to one node per grid point of a base triangle (the exceptional
         * re-evaluation of an edge whose midpoint exists under another edge stores none) */
        s->cap_nodes = side * (side + 1) / 2 < 4096 ? side * (side + 1) / 2 : 4096;
        s->nodes = malloc(s->cap_nodes * sizeof(*s->nodes));
        s->grid = malloc(side * side * sizeof(*s->grid));
        s->stamp = calloc(side * side, sizeof(*s->stamp));
        s->cap_stack = 256;
        s->stack = malloc(s->cap_stack * sizeof(*s->stack));
        if (!s->nodes || !s->grid || !s->stamp || !s->stack) return false;
    }
    return true;
}

meso_result displace_tessellator_create(meso_context *ctx, const displace_surface *surface,
                                        int max_level, displace_tessellator **out_tessellator) {
    *out_tessellator = NULL;
    if (max_level < 0 || max_level > DISPLACE_MAX_LEVEL)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: tessellation level %d is outside [0, %d]", surface->object->name,
                              max_level, DISPLACE_MAX_LEVEL);
    displace_tessellator *t = calloc(1, sizeof(*t));
    if (!t) goto fail;
    t->surface = surface;
    t->max_level = max_level;
    t->n = (int32_t)1 << max_level;
    size_t num_base = surface->base->num_triangles;
    t->num_jobs = num_base < TESS_MAX_JOBS ? num_base : TESS_MAX_JOBS;
    t->jobs = calloc(t->num_jobs, sizeof(*t->jobs));
    t->corners =
        calloc(surface->base->num_vertices ? surface->base->num_vertices : 1, sizeof(*t->corners));
    if (!t->jobs || !t->corners || !ensure_scratch(t, meso_context_num_threads(ctx))) goto fail;
    for (size_t j = 0; j < t->num_jobs; j++) {
        /* fixed split independent of the thread count (determinism) */
        t->jobs[j].first = num_base * j / t->num_jobs;
        t->jobs[j].count = num_base * (j + 1) / t->num_jobs - t->jobs[j].first;
    }
    *out_tessellator = t;
    return MESO_OK;
fail:
    displace_tessellator_destroy(t);
    return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: tessellation scratch (level %d)",
                          surface->object->name, max_level);
}

static void job_free(tess_job *job) {
    if (job->records)
        for (size_t i = 0; i < job->count; i++) free(job->records[i].block);
    free(job->records);
    for (size_t i = 0; i < job->num_memo_pages; i++) free(job->memo_pages[i]);
    free(job->memo_pages);
    free(job->memo_slots);
    free(job->positions);
    free(job->normals);
    free(job->tangents);
    free(job->bitangents);
    free(job->uvs);
    free(job->indices);
}

void displace_tessellator_destroy(displace_tessellator *t) {
    if (!t) return;
    if (t->scratch)
        for (int i = 0; i < t->num_threads; i++) {
            free(t->scratch[i].nodes);
            free(t->scratch[i].grid);
            free(t->scratch[i].asked);
            free(t->scratch[i].depths);
            free(t->scratch[i].stamp);
            free(t->scratch[i].stack);
        }
    if (t->jobs)
        for (size_t j = 0; j < t->num_jobs; j++) job_free(&t->jobs[j]);
    free(t->scratch);
    free(t->jobs);
    free(t->corners);
    free(t->mesh.positions);
    free(t->mesh.normals);
    free(t->mesh.tangents);
    free(t->mesh.bitangents);
    free(t->mesh.uvs);
    free(t->mesh.indices);
    free(t);
}

size_t displace_tessellator_memory(const displace_tessellator *t) {
    if (!t) return 0;
    size_t bytes = sizeof(*t) + t->surface->base->num_vertices * sizeof(displace_vertex) +
                   t->cap_vertices * (4 * sizeof(meso_vec3) + sizeof(meso_vec2)) +
                   t->cap_triangles * 3 * sizeof(uint32_t);
    for (size_t j = 0; j < t->num_jobs; j++) {
        bytes += t->jobs[j].cap_vertices * (4 * sizeof(meso_vec3) + sizeof(meso_vec2)) +
                 t->jobs[j].cap_triangles * 3 * sizeof(uint32_t);
        if (t->jobs[j].records)
            for (size_t i = 0; i < t->jobs[j].count; i++) bytes += t->jobs[j].records[i].cap_bytes;
        if (t->jobs[j].memo_slots)
            bytes += ((size_t)1 << t->jobs[j].memo_bits) * sizeof(tess_memo_slot) +
                     t->jobs[j].cap_memo * sizeof(tess_memo) +
                     t->jobs[j].cap_memo_pages * sizeof(tess_memo *);
    }
    size_t side = (size_t)t->n + 1;
    for (int i = 0; i < t->num_threads; i++)
        bytes += t->scratch[i].cap_nodes * sizeof(displace_vertex) + side * side * 8;
    return bytes;
}

#define GROW(ptr, cap, type)                                                                       \
    do {                                                                                           \
        type *grown_ = realloc((ptr), (cap) * sizeof(type));                                       \
        if (!grown_) return false;                                                                 \
        (ptr) = grown_;                                                                            \
    } while (0)

static bool job_reserve_vertices(tess_job *job, size_t extra) {
    if (job->num_vertices + extra <= job->cap_vertices) return true;
    size_t cap = job->cap_vertices ? job->cap_vertices * 2 : 1024;
    while (cap < job->num_vertices + extra) cap *= 2;
    GROW(job->positions, cap, meso_vec3);
    GROW(job->normals, cap, meso_vec3);
    GROW(job->tangents, cap, meso_vec3);
    GROW(job->bitangents, cap, meso_vec3);
    GROW(job->uvs, cap, meso_vec2);
    job->cap_vertices = cap;
    return true;
}

static bool job_reserve_triangles(tess_job *job, size_t extra) {
    if (job->num_triangles + extra <= job->cap_triangles) return true;
    size_t cap = job->cap_triangles ? job->cap_triangles * 2 : 1024;
    while (cap < job->num_triangles + extra) cap *= 2;
    GROW(job->indices, cap * 3, uint32_t);
    job->cap_triangles = cap;
    return true;
}

/* A traversal's log (the vetoes asked, the triangles' depths) with room for one more entry:
 * log itself, or log doubled when full; NULL when out of memory, log then stays as it was and
 * the traversal is not kept (record_failed: a record is a shortcut, not needed for the result). */
static void *record_room(tess_scratch *s, void *log, size_t *cap, size_t count, size_t size) {
    if (count < *cap) return log;
    size_t grown_cap = *cap ? 2 * *cap : 1024;
    void *grown = realloc(log, grown_cap * size);
    if (!grown) {
        s->record_failed = true;
        return NULL;
    }
    *cap = grown_cap;
    return grown;
}

static bool emit_triangle(tess_scratch *s, tess_job *job, const tess_entry *e) {
    if ((job->num_triangles + 1) % TESS_COUNT_STEP == 0 &&
        atomic_fetch_add_explicit(job->run_triangles, TESS_COUNT_STEP, memory_order_relaxed) +
                TESS_COUNT_STEP >
            job->max_triangles) {
        job->result = MESO_ERROR_LIMIT;
        return false;
    }
    if (!job_reserve_vertices(job, 3) || !job_reserve_triangles(job, 1)) {
        job->result = MESO_ERROR_OUT_OF_MEMORY;
        return false;
    }
    for (int k = 0; k < 3; k++) {
        displace_vertex *v = &s->nodes[e->v[k]];
        if (v->out_index == UINT32_MAX) {
            size_t i = job->num_vertices++;
            v->out_index = (uint32_t)i;
            job->positions[i] = v->position;
            /* the BASE frame: shade() rebuilds the height field's normal from it */
            job->normals[i] = v->unit_normal;
            job->tangents[i] = v->tangent;
            job->bitangents[i] = v->bitangent;
            job->uvs[i] = v->uv;
        }
        job->indices[job->num_triangles * 3 + (size_t)k] = v->out_index;
    }
    job->num_triangles++;
    int depth = e->depth < DISPLACE_MAX_DEPTH ? e->depth : DISPLACE_MAX_DEPTH - 1;
    job->stats.per_depth[depth]++;
    uint8_t *depths =
        s->recording ? record_room(s, s->depths, &s->cap_depths, s->num_depths, sizeof(*s->depths))
                     : NULL;
    if (depths) {
        s->depths = depths;
        s->depths[s->num_depths++] = (uint8_t)depth;
    }
    return true;
}

/* ---- Midpoints remembered across runs ---------------------------------------------------- */

/* grid coordinates are at most 2^DISPLACE_MAX_LEVEL: 11 bits each */
static uint64_t memo_key(size_t triangle, int32_t kb, int32_t kc) {
    return ((uint64_t)triangle << 22) | ((uint64_t)kb << 11) | (uint64_t)kc;
}

/* Entry e of the job's memo. The entries live in pages that never move: a moving camera adds
 * midpoints every frame, and one growing array would be copied by realloc each time it grew (a
 * visible part of a moving bricks-teapot frame's instructions). */
static inline tess_memo *memo_entry(const tess_job *job, size_t e) {
    return &job->memo_pages[e >> MEMO_PAGE_BITS][e & (MEMO_PAGE_ENTRIES - 1)];
}

/* The slot holding key, or the empty slot where it would go (the table is never full). */
static inline uint64_t memo_hash(uint64_t key) { return key * 0x9E3779B97F4A7C15ull; }

/* The slot of a key's hash: its position from the top bits (at most 31 of them), its tag the
 * low 32. */
static inline uint32_t memo_tag(uint64_t hash) { return (uint32_t)hash; }

static tess_memo_slot *memo_slot(const tess_job *job, uint64_t key) {
    size_t mask = ((size_t)1 << job->memo_bits) - 1;
    uint64_t hash = memo_hash(key);
    uint32_t tag = memo_tag(hash);
    size_t i = (size_t)(hash >> (64 - job->memo_bits));
    for (;;) {
        const tess_memo_slot *slot = &job->memo_slots[i];
        if (slot->entry == 0 || (slot->tag == tag && memo_entry(job, slot->entry - 1)->key == key))
            return &job->memo_slots[i];
        i = (i + 1) & mask;
    }
}

static tess_memo *memo_find(const tess_job *job, uint64_t key) {
    if (!job->memo_slots) return NULL;
    uint32_t e = memo_slot(job, key)->entry;
    return e ? memo_entry(job, e - 1) : NULL;
}

/* Twice the slots, the entries rehashed; false when out of memory (the job then remembers no
 * more: the memo is a shortcut, not needed for the result). */
static bool memo_grow_slots(tess_job *job) {
    int bits = job->memo_slots ? job->memo_bits + 1 : 12;
    if (bits > 31) return false;
    tess_memo_slot *table = calloc((size_t)1 << bits, sizeof(*table));
    if (!table) return false;
    free(job->memo_slots);
    job->memo_slots = table;
    job->memo_bits = bits;
    for (size_t e = 0; e < job->num_memo; e++) {
        uint64_t key = memo_entry(job, e)->key;
        *memo_slot(job, key) = (tess_memo_slot){(uint32_t)e + 1, memo_tag(memo_hash(key))};
    }
    return true;
}

/* The entry for key, made (undecided) if there is none; NULL when out of memory. */
static tess_memo *memo_store(tess_job *job, uint64_t key) {
    if (!job->memo_slots || (job->num_memo + 1) * 2 > ((size_t)1 << job->memo_bits))
        if (!memo_grow_slots(job)) return NULL;
    tess_memo_slot *slot = memo_slot(job, key);
    if (slot->entry) return memo_entry(job, slot->entry - 1);
    if (job->num_memo == job->cap_memo) { /* one more page: the entries already made stay */
        if (job->num_memo_pages == job->cap_memo_pages) {
            size_t cap = job->cap_memo_pages ? 2 * job->cap_memo_pages : 16;
            tess_memo **grown = realloc(job->memo_pages, cap * sizeof(*grown));
            if (!grown) return NULL;
            job->memo_pages = grown;
            job->cap_memo_pages = cap;
        }
        tess_memo *page = malloc(MEMO_PAGE_ENTRIES * sizeof(*page));
        if (!page) return NULL;
        job->memo_pages[job->num_memo_pages++] = page;
        job->cap_memo += MEMO_PAGE_ENTRIES;
    }
    tess_memo *e = memo_entry(job, job->num_memo++);
    e->key = key;
    e->decided = 0;
    *slot = (tess_memo_slot){(uint32_t)job->num_memo, memo_tag(memo_hash(key))};
    return e;
}

/* At a run's start: forget everything when the entries outgrow twice what the last run used (a
 * moving camera leaves midpoints behind that it may never reach again). */
static void memo_trim(tess_job *job) {
    if (job->memo_slots && job->num_memo > 2 * job->memo_used + 4096) {
        job->num_memo = 0;
        memset(job->memo_slots, 0, ((size_t)1 << job->memo_bits) * sizeof(*job->memo_slots));
    }
    job->memo_used = 0;
}

static int32_t node_at(tess_scratch *s, int32_t n, int32_t kb, int32_t kc) {
    size_t cell = (size_t)kb * ((size_t)n + 1) + (size_t)kc;
    return s->stamp[cell] == s->current ? s->grid[cell] : -1;
}

static void node_store(tess_scratch *s, int32_t n, int32_t index) {
    const displace_vertex *v = &s->nodes[index];
    size_t cell = (size_t)v->key_b * ((size_t)n + 1) + (size_t)v->key_c;
    s->stamp[cell] = s->current;
    s->grid[cell] = index;
}

/* The edge's decision: veto first (before displacing m when `displaced` is false), then the
 * insertion test. a and b are put in a canonical order: the neighbouring triangle walks the edge
 * the other way round. */
static inline void order_edge(const displace_vertex **a, const displace_vertex **b) {
    if (vertex_before(*b, *a)) {
        const displace_vertex *swap = *a;
        *a = *b;
        *b = swap;
    }
}

/* a and b in the canonical order (order_edge); logged while recording */
static bool vetoed(const displace_tessellator *t, tess_scratch *s, const displace_vertex *a,
                   const displace_vertex *b, const displace_vertex *m, tess_job *job) {
    if (!t->tests || !t->tests->veto) return false;
    bool answer = t->tests->veto(t->tests->user, a, b, m, job->stats.counters);
    tess_asked *asked =
        s->recording ? record_room(s, s->asked, &s->cap_asked, s->num_asked, sizeof(*s->asked))
                     : NULL;
    if (asked) {
        s->asked = asked;
        s->asked[s->num_asked++] =
            (tess_asked){(int32_t)(a - s->nodes), (int32_t)(b - s->nodes),
                         (uint32_t)(m - s->nodes) | (answer ? 0x80000000u : 0u)};
    }
    return answer;
}

/* a and b in the canonical order (order_edge) */
static bool decide(const displace_tessellator *t, const displace_vertex *a,
                   const displace_vertex *b, const displace_vertex *m, tess_job *job) {
    if (!t->tests || !t->tests->insert) return true;
    return t->tests->insert(t->tests->user, a, b, m, job->stats.counters);
}

/* The midpoint of edge (p, q) if it is to be inserted, else -1. Computed and decided once per
 * edge of a base triangle; the grid makes the recursion limit an edge property. */
static bool reserve_node(const displace_tessellator *t, tess_scratch *s, tess_job *job) {
    if (s->num_nodes < s->cap_nodes) return true;
    size_t side = (size_t)t->n + 1, full = side * (side + 1) / 2;
    if (s->cap_nodes >= full) return true; /* every grid point has its node: none is made */
    size_t cap = s->cap_nodes * 2 < full ? s->cap_nodes * 2 : full;
    displace_vertex *grown = realloc(s->nodes, cap * sizeof(*grown));
    if (!grown) {
        job->result = MESO_ERROR_OUT_OF_MEMORY;
        return false;
    }
    s->nodes = grown;
    s->cap_nodes = cap;
    return true;
}

/* m's derived fields and the decision on its edge: remembered from an earlier run when m's
 * inputs (and for the decision a's and b's fields it reads) are bit for bit the same, else
 * computed and remembered. a and b in the canonical order. */
static void midpoint_derive(const displace_tessellator *t, tess_job *job, size_t triangle,
                            const displace_vertex *a, const displace_vertex *b,
                            displace_vertex *m) {
    const displace_edge_tests *tests = t->tests;
    bool view_independent = tests && tests->view_independent_insert;
    uint64_t key = memo_key(triangle, m->key_b, m->key_c);
    /* kept only for tests that declare their insert view-independent: the others (`displacement`
     * without tests tessellates once) would keep what no frame reads again */
    tess_memo *e = view_independent ? memo_find(job, key) : NULL;
    bool known = e && memcmp(&e->base, &m->base, MEMO_INPUT_BYTES) == 0;
    if (known) { /* displace_vertex_finish's results, the two cheap ones computed again */
        m->texture_uv = displace_texture_uv(t->surface, m->uv);
        m->unit_normal = e->unit_normal;
        m->height = e->height;
        m->position = displaced_position(t->surface, m);
        m->surface_normal = e->surface_normal;
    } else {
        /* "Displace midpoint", "Calculate surface normal" */
        displace_vertex_finish(t->surface, m);
        m->surface_normal = m->unit_normal;
        if (tests && tests->vertex_static) tests->vertex_static(tests->user, m);
    }
    /* "Transform midpoint": the frame's */
    m->clip = (meso_vec4){0, 0, 0, 1};
    if (tests && tests->vertex_hook) tests->vertex_hook(tests->user, m);
    if (known && e->decided && memcmp(&e->uv_a, &a->uv, sizeof(a->uv)) == 0 &&
        memcmp(&e->uv_b, &b->uv, sizeof(b->uv)) == 0 &&
        memcmp(&e->surface_normal_a, &a->surface_normal, sizeof(meso_vec3)) == 0 &&
        memcmp(&e->surface_normal_b, &b->surface_normal, sizeof(meso_vec3)) == 0) {
        m->inserted = (int8_t)e->inserted;
        for (int c = 0; c < DISPLACE_NUM_COUNTERS; c++)
            job->stats.counters[c] += (uint64_t)((e->counters >> c) & 1u);
        job->memo_used++;
        return;
    }
    if (!view_independent) {
        m->inserted = decide(t, a, b, m, job) ? 1 : 0;
        return;
    }
    uint64_t before[DISPLACE_NUM_COUNTERS];
    memcpy(before, job->stats.counters, sizeof(before));
    m->inserted = decide(t, a, b, m, job) ? 1 : 0;
    if (!known && !(e = memo_store(job, key))) return;
    job->memo_used++;
    if (!known) {
        memcpy(&e->base, &m->base, MEMO_INPUT_BYTES);
        e->unit_normal = m->unit_normal;
        e->height = m->height;
        e->surface_normal = m->surface_normal;
    }
    e->uv_a = a->uv;
    e->uv_b = b->uv;
    e->surface_normal_a = a->surface_normal;
    e->surface_normal_b = b->surface_normal;
    e->inserted = (uint8_t)m->inserted;
    e->counters = 0;
    for (int c = 0; c < DISPLACE_NUM_COUNTERS; c++)
        if (job->stats.counters[c] != before[c]) e->counters |= (uint8_t)(1u << c);
    e->decided = 1;
}

static int32_t edge_midpoint(const displace_tessellator *t, tess_scratch *s, tess_job *job,
                             size_t triangle, int32_t p, int32_t q) {
    /* before taking pointers into the node array: growing it moves it */
    if (!reserve_node(t, s, job)) return -1;
    const displace_vertex *a = &s->nodes[p], *b = &s->nodes[q];
    int32_t sb = a->key_b + b->key_b, sc = a->key_c + b->key_c;
    if ((sb | sc) & 1) {
        job->stats.grid_limited++;
        return -1;
    }
    int32_t lo = p < q ? p : q, hi = p < q ? q : p;
    int32_t existing = node_at(s, t->n, sb / 2, sc / 2);
    if (existing >= 0) {
        const displace_vertex *m = &s->nodes[existing];
        if (m->parent_a == lo && m->parent_b == hi) return m->inserted ? existing : -1;
        order_edge(&a, &b);
        /* Another edge of this base triangle has the same midpoint (two crossing diagonals of
         * different refinement branches). Decide for this edge with the stored vertex: it is
         * interior to the base triangle, so no neighbour depends on it; the answer is a
         * function of the records only (a vetoed vertex was never displaced: no). */
        return m->inserted && !vetoed(t, s, a, b, m, job) && decide(t, a, b, m, job) ? existing
                                                                                     : -1;
    }
    if (s->num_nodes >= s->cap_nodes) return -1; /* cannot happen: one node per grid point */
    int32_t index = (int32_t)s->num_nodes++;
    displace_vertex *m = &s->nodes[index];
    vertex_midpoint_uv(a, b, m); /* texture_uv: by displace_vertex_finish, past the veto */
    if (t->tests && t->tests->veto) displace_vertex_texel(t->surface, m); /* for the veto only */
    m->key_b = sb / 2;
    m->key_c = sc / 2;
    m->parent_a = lo;
    m->parent_b = hi;
    m->out_index = UINT32_MAX;
    m->inserted = 0;
    m->displaced = 0;
    order_edge(&a, &b);
    if (!vetoed(t, s, a, b, m, job)) {
        m->displaced = 1;
        vertex_midpoint_frame(a, b, m); /* commutative sums: the order does not matter */
        midpoint_derive(t, job, triangle, a, b, m);
    }
    node_store(s, t->n, index);
    return m->inserted ? index : -1;
}

static bool push(tess_scratch *s, size_t *top, int32_t a, int32_t b, int32_t c, int32_t depth,
                 tess_job *job) {
    if (*top >= s->cap_stack) {
        size_t cap = s->cap_stack * 2;
        tess_entry *grown = realloc(s->stack, cap * sizeof(*grown));
        if (!grown) {
            job->result = MESO_ERROR_OUT_OF_MEMORY;
            return false;
        }
        s->stack = grown;
        s->cap_stack = cap;
    }
    s->stack[(*top)++] = (tess_entry){{a, b, c}, depth};
    return true;
}

static float base_distance2(const tess_scratch *s, int32_t p, int32_t q) {
    meso_vec3 d = meso_vec3_sub(s->nodes[p].base, s->nodes[q].base);
    return meso_vec3_dot(d, d);
}

static bool traverse_triangle(const displace_tessellator *t, tess_scratch *s, tess_job *job,
                              size_t triangle) {
    const meso_mesh *base = t->surface->base;
    if (++s->current == 0) { /* stamp wrapped: clear once every 2^32 triangles */
        memset(s->stamp, 0, ((size_t)t->n + 1) * ((size_t)t->n + 1) * sizeof(*s->stamp));
        s->current = 1;
    }
    s->num_nodes = 0;
    const int32_t keys[3][2] = {{0, 0}, {t->n, 0}, {0, t->n}};
    for (int k = 0; k < 3; k++) {
        uint32_t i = base->indices[triangle * 3 + (size_t)k];
        displace_vertex *v = &s->nodes[s->num_nodes];
        *v = t->corners[i]; /* displaced once, on the first run */
        v->key_b = keys[k][0];
        v->key_c = keys[k][1];
        if (t->tests && t->tests->vertex_hook) t->tests->vertex_hook(t->tests->user, v);
        node_store(s, t->n, (int32_t)s->num_nodes);
        s->num_nodes++;
    }
    size_t top = 0;
    if (!push(s, &top, 0, 1, 2, 0, job)) return false;
    while (top > 0) {
        tess_entry e = s->stack[--top];
        int32_t m[3];
        int present = 0;
        for (int k = 0; k < 3; k++) {
            m[k] = edge_midpoint(t, s, job, triangle, e.v[k], e.v[(k + 1) % 3]);
            present += m[k] >= 0;
        }
        if (job->result != MESO_OK) return false;
        int32_t d = e.depth + 1;
        bool ok = true;
        if (present == 0) {
            if (!emit_triangle(s, job, &e)) return false;
        } else if (present == 3) {
            /* "Tessellate with selected midpoints": the regular 1-to-4 split */
            ok = push(s, &top, m[1], m[2], m[0], d, job) &&
                 push(s, &top, e.v[2], m[2], m[1], d, job) &&
                 push(s, &top, m[0], e.v[1], m[1], d, job) &&
                 push(s, &top, e.v[0], m[0], m[2], d, job);
        } else if (present == 1) {
            /* rotate so that the midpoint is on edge (a, b): split into (a, m, c), (m, b, c) */
            int r = m[0] >= 0 ? 0 : (m[1] >= 0 ? 1 : 2);
            int32_t a = e.v[r], b = e.v[(r + 1) % 3], c = e.v[(r + 2) % 3], mm = m[r];
            ok = push(s, &top, mm, b, c, d, job) && push(s, &top, a, mm, c, d, job);
        } else {
            /* two midpoints: rotate so the missing one is on edge (c, a); cut the corner b off
             * and split the quad (a, m0, m1, c) along its shorter diagonal */
            int r = m[0] < 0 ? 1 : (m[1] < 0 ? 2 : 0);
            int32_t a = e.v[r], b = e.v[(r + 1) % 3], c = e.v[(r + 2) % 3];
            int32_t m0 = m[r], m1 = m[(r + 1) % 3];
            ok = push(s, &top, m0, b, m1, d, job);
            if (ok && base_distance2(s, a, m1) <= base_distance2(s, m0, c))
                ok = push(s, &top, a, m1, c, d, job) && push(s, &top, a, m0, m1, d, job);
            else if (ok)
                ok = push(s, &top, m0, m1, c, d, job) && push(s, &top, a, m0, c, d, job);
        }
        if (!ok) return false;
    }
    return true;
}

/* ---- Replaying a base triangle's last traversal ------------------------------------------- */

static bool replayable(const displace_tessellator *t) {
    return t->tests && t->tests->view_independent_insert && t->tests->veto;
}

/* A record's part of `bytes`, rounded up to 8 so that every part of the block is aligned. */
static size_t record_part_bytes(size_t bytes) { return (bytes + 7) & ~(size_t)7; }

/* The part at *cursor, the cursor moved past it. */
static void *record_carve(char **cursor, size_t bytes) {
    void *part = *cursor;
    *cursor += record_part_bytes(bytes);
    return part;
}

/* The record's block (grown when too small) cut into its arrays for its counts. A record has
 * at least a triangle's three corners as nodes, so the block is never empty. */
static bool record_layout(tess_record *r) {
    size_t texels = r->num_nodes * 2 * sizeof(int32_t);
    size_t hooked = r->num_hooked * sizeof(tess_record_hooked);
    size_t asked = r->num_asked * sizeof(tess_asked);
    size_t vec3s = r->num_vertices * sizeof(meso_vec3), uvs = r->num_vertices * sizeof(meso_vec2);
    size_t indices = r->num_triangles * 3 * sizeof(uint32_t), depths = r->num_triangles;
    size_t total = record_part_bytes(texels) + record_part_bytes(hooked) +
                   record_part_bytes(asked) + 4 * record_part_bytes(vec3s) +
                   record_part_bytes(uvs) + record_part_bytes(indices) + record_part_bytes(depths);
    if (total > r->cap_bytes) {
        /* the whole block is written anew: a fresh one, not realloc's copy of the old (a moving
         * camera re-records most triangles a frame, a few bytes larger each time), with an
         * eighth to spare for the next growth */
        size_t cap = total + total / 8;
        free(r->block);
        r->block = malloc(cap);
        r->cap_bytes = r->block ? cap : 0;
        if (!r->block) return false;
    }
    char *cursor = r->block;
    r->texels = record_carve(&cursor, texels);
    r->hooked = record_carve(&cursor, hooked);
    r->asked = record_carve(&cursor, asked);
    r->positions = record_carve(&cursor, vec3s);
    r->normals = record_carve(&cursor, vec3s);
    r->tangents = record_carve(&cursor, vec3s);
    r->bitangents = record_carve(&cursor, vec3s);
    r->uvs = record_carve(&cursor, uvs);
    r->indices = record_carve(&cursor, indices);
    r->depths = record_carve(&cursor, depths);
    return true;
}

/* Keep the traversal just made: nodes, the vetoes asked, the output from vertex v0 and
 * triangle t0 of the job, and what it added to the statistics. */
static void record_traversal(tess_record *r, const tess_scratch *s, const tess_job *job, size_t v0,
                             size_t t0, const uint64_t *counters_before,
                             uint64_t grid_limited_before, size_t memo_used_before) {
    r->valid = false;
    if (s->record_failed) return;
    r->num_nodes = s->num_nodes;
    r->num_hooked = 0;
    for (size_t i = 0; i < s->num_nodes; i++) {
        const displace_vertex *v = &s->nodes[i];
        if (v->texel_i < INT32_MIN || v->texel_i > INT32_MAX || v->texel_j < INT32_MIN ||
            v->texel_j > INT32_MAX)
            return; /* uv beyond 2^31 texels: not kept in 32 bits, so not replayed */
        r->num_hooked += v->displaced ? 1 : 0;
    }
    r->num_asked = s->num_asked;
    r->num_vertices = job->num_vertices - v0;
    r->num_triangles = job->num_triangles - t0;
    if (!record_layout(r)) return;
    size_t hooked = 0;
    for (size_t i = 0; i < s->num_nodes; i++) {
        const displace_vertex *v = &s->nodes[i];
        r->texels[2 * i] = (int32_t)v->texel_i;
        r->texels[2 * i + 1] = (int32_t)v->texel_j;
        if (v->displaced)
            r->hooked[hooked++] = (tess_record_hooked){(int32_t)i, v->position, v->unit_normal};
    }
    /* empty logs and outputs may have no arrays yet (NULL), which memcpy must not be given */
    if (s->num_asked) memcpy(r->asked, s->asked, s->num_asked * sizeof(*s->asked));
    size_t nv = r->num_vertices;
    if (nv) {
        memcpy(r->positions, job->positions + v0, nv * sizeof(meso_vec3));
        memcpy(r->normals, job->normals + v0, nv * sizeof(meso_vec3));
        memcpy(r->tangents, job->tangents + v0, nv * sizeof(meso_vec3));
        memcpy(r->bitangents, job->bitangents + v0, nv * sizeof(meso_vec3));
        memcpy(r->uvs, job->uvs + v0, nv * sizeof(meso_vec2));
    }
    for (size_t i = 0; i < r->num_triangles * 3; i++)
        r->indices[i] = job->indices[t0 * 3 + i] - (uint32_t)v0;
    if (r->num_triangles) memcpy(r->depths, s->depths, r->num_triangles);
    for (int c = 0; c < DISPLACE_NUM_COUNTERS; c++)
        r->counters[c] = job->stats.counters[c] - counters_before[c];
    r->grid_limited = job->stats.grid_limited - grid_limited_before;
    r->memo_used = job->memo_used - memo_used_before;
    r->valid = true;
}

/* Ask the recorded vetoes again of this run's transformed nodes; when every answer is the
 * recorded one, append the recorded output and statistics (what the traversal would give) and
 * return true. False leaves the job as it was, for a traversal. */
static bool replay_traversal(const displace_tessellator *t, tess_scratch *s, tess_job *job,
                             const tess_record *r) {
    const displace_edge_tests *tests = t->tests;
    if (job->num_triangles + r->num_triangles > MESO_MESH_MAX_TRIANGLES) return false;
    if (r->num_nodes > s->cap_nodes) {
        displace_vertex *grown = realloc(s->nodes, r->num_nodes * sizeof(*grown));
        if (!grown) return false;
        s->nodes = grown;
        s->cap_nodes = r->num_nodes;
    }
    if (!job_reserve_vertices(job, r->num_vertices) ||
        !job_reserve_triangles(job, r->num_triangles))
        return false;
    for (size_t i = 0; i < r->num_nodes; i++) {
        s->nodes[i].texel_i = r->texels[2 * i];
        s->nodes[i].texel_j = r->texels[2 * i + 1];
    }
    for (size_t i = 0; i < r->num_hooked; i++) {
        displace_vertex *v = &s->nodes[r->hooked[i].node];
        v->position = r->hooked[i].position;
        v->unit_normal = r->hooked[i].unit_normal;
        v->clip = (meso_vec4){0, 0, 0, 1};
        if (tests->vertex_hook) tests->vertex_hook(tests->user, v);
    }
    uint64_t before[DISPLACE_NUM_COUNTERS];
    memcpy(before, job->stats.counters, sizeof(before));
    for (size_t k = 0; k < r->num_asked; k++) {
        const tess_asked *q = &r->asked[k];
        bool answer = tests->veto(tests->user, &s->nodes[q->a], &s->nodes[q->b],
                                  &s->nodes[q->m_vetoed & 0x7fffffffu], job->stats.counters);
        if (answer != ((q->m_vetoed >> 31) != 0)) {
            memcpy(job->stats.counters, before, sizeof(before));
            return false;
        }
    }
    /* the vetoes added what they added in the traversal: the recorded totals replace them */
    for (int c = 0; c < DISPLACE_NUM_COUNTERS; c++)
        job->stats.counters[c] = before[c] + r->counters[c];
    job->stats.grid_limited += r->grid_limited;
    job->memo_used += r->memo_used;
    for (size_t i = 0; i < r->num_triangles; i++) job->stats.per_depth[r->depths[i]]++;
    size_t v0 = job->num_vertices, nv = r->num_vertices;
    if (nv) { /* (an empty output may have no arrays yet) */
        memcpy(job->positions + v0, r->positions, nv * sizeof(meso_vec3));
        memcpy(job->normals + v0, r->normals, nv * sizeof(meso_vec3));
        memcpy(job->tangents + v0, r->tangents, nv * sizeof(meso_vec3));
        memcpy(job->bitangents + v0, r->bitangents, nv * sizeof(meso_vec3));
        memcpy(job->uvs + v0, r->uvs, nv * sizeof(meso_vec2));
    }
    for (size_t i = 0; i < r->num_triangles * 3; i++)
        job->indices[job->num_triangles * 3 + i] = r->indices[i] + (uint32_t)v0;
    job->num_vertices += nv;
    job->num_triangles += r->num_triangles;
    return true;
}

/* One base triangle: replayed when its record still holds, else traversed (and recorded). */
static bool tessellate_triangle(const displace_tessellator *t, tess_scratch *s, tess_job *job,
                                size_t triangle) {
    tess_record *r = job->records ? &job->records[triangle - job->first] : NULL;
    if (r && r->valid && replay_traversal(t, s, job, r)) {
        job->stats.replayed++;
        return true;
    }
    size_t v0 = job->num_vertices, t0 = job->num_triangles, memo_used = job->memo_used;
    uint64_t counters[DISPLACE_NUM_COUNTERS], grid_limited = job->stats.grid_limited;
    memcpy(counters, job->stats.counters, sizeof(counters));
    s->recording = r != NULL;
    s->record_failed = false;
    s->num_asked = s->num_depths = 0;
    bool ok = traverse_triangle(t, s, job, triangle);
    s->recording = false;
    if (r) {
        if (ok)
            record_traversal(r, s, job, v0, t0, counters, grid_limited, memo_used);
        else
            r->valid = false;
    }
    return ok;
}

typedef struct run_args {
    displace_tessellator *t;
} run_args;

static void run_job(void *user, size_t index, int thread_index) {
    displace_tessellator *t = ((run_args *)user)->t;
    /* Work on copies on this thread's stack, written back once at the end: the job records
     * and the workers' scratch records lie side by side in arrays, and the counters and sizes
     * written for every edge would otherwise share cache lines with the neighbouring job's
     * (run at the same time on the other thread) or the other worker's: false sharing made two
     * threads slower than one. */
    tess_job job = t->jobs[index];
    tess_scratch s = t->scratch[thread_index];
    job.run_triangles = &t->run_triangles;
    job.max_triangles = t->max_triangles;
    job.num_vertices = job.num_triangles = 0;
    memset(&job.stats, 0, sizeof(job.stats));
    job.result = MESO_OK;
    memo_trim(&job);
    if (replayable(t) && !job.records) job.records = calloc(job.count, sizeof(*job.records));
    for (size_t i = 0; i < job.count; i++)
        if (!tessellate_triangle(t, &s, &job, job.first + i)) break;
    t->jobs[index] = job;
    t->scratch[thread_index] = s;
}

static void join_job(void *user, size_t index, int thread_index) {
    (void)thread_index;
    displace_tessellator *t = ((run_args *)user)->t;
    const tess_job *job = &t->jobs[index];
    size_t v0 = job->vertex_offset, n = job->num_vertices;
    memcpy(t->mesh.positions + v0, job->positions, n * sizeof(meso_vec3));
    memcpy(t->mesh.normals + v0, job->normals, n * sizeof(meso_vec3));
    memcpy(t->mesh.tangents + v0, job->tangents, n * sizeof(meso_vec3));
    memcpy(t->mesh.bitangents + v0, job->bitangents, n * sizeof(meso_vec3));
    memcpy(t->mesh.uvs + v0, job->uvs, n * sizeof(meso_vec2));
    uint32_t *out = t->mesh.indices + job->triangle_offset * 3;
    for (size_t i = 0; i < job->num_triangles * 3; i++) out[i] = job->indices[i] + (uint32_t)v0;
}

static bool mesh_reserve(displace_tessellator *t, size_t vertices, size_t triangles) {
    if (vertices > t->cap_vertices) {
        GROW(t->mesh.positions, vertices, meso_vec3);
        GROW(t->mesh.normals, vertices, meso_vec3);
        GROW(t->mesh.tangents, vertices, meso_vec3);
        GROW(t->mesh.bitangents, vertices, meso_vec3);
        GROW(t->mesh.uvs, vertices, meso_vec2);
        t->cap_vertices = vertices;
    }
    if (triangles > t->cap_triangles) {
        GROW(t->mesh.indices, triangles * 3, uint32_t);
        t->cap_triangles = triangles;
    }
    return true;
}

meso_result displace_tessellator_run(meso_context *ctx, displace_tessellator *t,
                                     const displace_edge_tests *tests, const meso_mesh **out_mesh,
                                     displace_tess_stats *out_stats) {
    *out_mesh = NULL;
    if (out_stats) memset(out_stats, 0, sizeof(*out_stats));
    if (!ensure_scratch(t, meso_context_num_threads(ctx)))
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: tessellation scratch",
                              t->surface->object->name);
    t->tests = tests;
    if (!t->corners_ready) {
        const meso_mesh *base = t->surface->base;
        for (size_t i = 0; i < base->num_vertices; i++) {
            displace_vertex *v = &t->corners[i];
            memset(v, 0, sizeof(*v));
            v->base = base->positions[i];
            v->normal = base->normals[i];
            v->tangent = base->tangents ? base->tangents[i] : (meso_vec3){0, 0, 0};
            v->bitangent = base->bitangents ? base->bitangents[i] : (meso_vec3){0, 0, 0};
            v->uv = base->uvs ? base->uvs[i] : (meso_vec2){0, 0};
            displace_vertex_finish(t->surface, v);
            displace_vertex_texel(t->surface, v);
            v->surface_normal = v->unit_normal;
            v->clip = (meso_vec4){0, 0, 0, 1};
            v->parent_a = v->parent_b = -1;
            v->out_index = UINT32_MAX;
            v->inserted = 1;
            v->displaced = 1;
            if (tests && tests->vertex_static) tests->vertex_static(tests->user, v);
        }
        t->corners_ready = true;
    }
    uint64_t affordable = meso_context_memory_limit(ctx) / TESS_BYTES_PER_TRIANGLE;
    t->max_triangles =
        affordable < MESO_MESH_MAX_TRIANGLES ? (size_t)affordable : (size_t)MESO_MESH_MAX_TRIANGLES;
    atomic_store(&t->run_triangles, 0);
    run_args args = {t};
    meso_parallel_for(ctx, t->num_jobs, run_job, &args);
    t->tests = NULL;
    size_t vertices = 0, triangles = 0;
    displace_tess_stats stats = {0};
    for (size_t j = 0; j < t->num_jobs; j++) { /* fixed order: deterministic sums */
        tess_job *job = &t->jobs[j];
        if (job->result == MESO_ERROR_LIMIT)
            return t->max_triangles < MESO_MESH_MAX_TRIANGLES
                       ? meso_log_error(ctx, MESO_ERROR_LIMIT,
                                        "%s: tessellation: more than %zu triangles, which need "
                                        "more memory than the limit of %.1f MiB "
                                        "(--memory-limit; lower max_level or raise the "
                                        "thresholds)",
                                        t->surface->object->name, t->max_triangles,
                                        (double)meso_context_memory_limit(ctx) / 1048576.0)
                       : meso_log_error(ctx, MESO_ERROR_LIMIT,
                                        "%s: tessellation: more than %u triangles",
                                        t->surface->object->name, MESO_MESH_MAX_TRIANGLES);
        if (job->result != MESO_OK)
            return meso_log_error(ctx, job->result, "%s: tessellation output",
                                  t->surface->object->name);
        job->vertex_offset = vertices;
        job->triangle_offset = triangles;
        vertices += job->num_vertices;
        triangles += job->num_triangles;
        for (int d = 0; d < DISPLACE_MAX_DEPTH; d++) stats.per_depth[d] += job->stats.per_depth[d];
        for (int c = 0; c < DISPLACE_NUM_COUNTERS; c++) stats.counters[c] += job->stats.counters[c];
        stats.grid_limited += job->stats.grid_limited;
        stats.replayed += job->stats.replayed;
    }
    if (triangles > MESO_MESH_MAX_TRIANGLES || vertices > MESO_MESH_MAX_VERTICES)
        return meso_log_error(ctx, MESO_ERROR_LIMIT,
                              "%s: tessellation: %zu triangles exceed the limit %u",
                              t->surface->object->name, triangles, MESO_MESH_MAX_TRIANGLES);
    if (!mesh_reserve(t, vertices, triangles))
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: tessellation: %zu triangles",
                              t->surface->object->name, triangles);
    meso_parallel_for(ctx, t->num_jobs, join_job, &args);
    t->mesh.num_vertices = vertices;
    t->mesh.num_triangles = triangles;
    stats.triangles = triangles;
    stats.vertices = vertices;
    if (out_stats) *out_stats = stats;
    *out_mesh = &t->mesh;
    return MESO_OK;
}

/* ---- Shadow maps -------------------------------------------------------------------------- */

static meso_mat4 ortho(float left, float right, float bottom, float top, float z_near,
                       float z_far) {
    meso_mat4 r = {{0}};
    r.m[0] = 2.0f / (right - left);
    r.m[5] = 2.0f / (top - bottom);
    r.m[10] = -2.0f / (z_far - z_near);
    r.m[12] = -(right + left) / (right - left);
    r.m[13] = -(top + bottom) / (top - bottom);
    r.m[14] = -(z_far + z_near) / (z_far - z_near);
    r.m[15] = 1.0f;
    return r;
}

/* fminf and fmaxf as x86-64's C library computes them (the MINSS / MAXSS result, or the operand
 * that is not a NaN), without a call a coordinate: the bounds are taken over every vertex of
 * the camera's mesh each time a moving camera redraws the map. x is never a NaN here. */
static inline float bound_min(float x, float y) { return x < y || y != y ? x : y; }
static inline float bound_max(float x, float y) { return x > y || y != y ? x : y; }

static void mesh_bounds(const meso_mesh *mesh, meso_vec3 *lo, meso_vec3 *hi) {
    *lo = (meso_vec3){INFINITY, INFINITY, INFINITY};
    *hi = (meso_vec3){-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < mesh->num_vertices; i++) {
        meso_vec3 p = mesh->positions[i];
        lo->x = bound_min(lo->x, p.x), lo->y = bound_min(lo->y, p.y);
        lo->z = bound_min(lo->z, p.z);
        hi->x = bound_max(hi->x, p.x), hi->y = bound_max(hi->y, p.y);
        hi->z = bound_max(hi->z, p.z);
    }
}

static meso_vec3 pick_up(meso_vec3 forward) {
    return fabsf(forward.y) < 0.9f ? (meso_vec3){0, 1, 0} : (meso_vec3){1, 0, 0};
}

bool displace_shadows_current(const displace_shadows *shadows, const meso_scene *scene) {
    return shadows->drawn && shadows->drawn_num_lights == scene->num_lights &&
           memcmp(shadows->drawn_lights, scene->lights,
                  (size_t)scene->num_lights * sizeof(meso_light)) == 0;
}

void displace_shadows_mark_drawn(displace_shadows *shadows, const meso_scene *scene,
                                 double seconds) {
    shadows->num_lights = shadows->options.enabled ? scene->num_lights : 0;
    shadows->drawn = true;
    shadows->drawn_num_lights = scene->num_lights;
    memcpy(shadows->drawn_lights, scene->lights, (size_t)scene->num_lights * sizeof(meso_light));
    shadows->seconds = seconds;
}

bool displace_light_projection(meso_context *ctx, const displace_shadows *shadows,
                               const meso_light *light, meso_vec3 lo, meso_vec3 hi,
                               displace_light_map *out_map, float *out_z_near) {
    size_t size = (size_t)shadows->options.size;
    meso_vec3 center = meso_vec3_scale(meso_vec3_add(lo, hi), 0.5f);
    float radius = 0.5f * meso_vec3_length(meso_vec3_sub(hi, lo));
    float margin = 1e-3f * radius + 1e-6f;
    memset(out_map, 0, sizeof(*out_map));
    *out_z_near = 0.0f;
    if (light->type == MESO_LIGHT_DIRECTIONAL) {
        meso_vec3 dir = meso_vec3_normalize(light->direction);
        meso_vec3 eye = meso_vec3_madd(center, dir, 2.0f * radius + 1.0f);
        meso_mat4 view = meso_mat4_look_at(eye, center, pick_up(dir));
        /* fit the light's frustum to the bounds' eight corners in light space */
        float x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
        float d0 = INFINITY, d1 = -INFINITY;
        for (int c = 0; c < 8; c++) {
            meso_vec3 p = {c & 1 ? hi.x : lo.x, c & 2 ? hi.y : lo.y, c & 4 ? hi.z : lo.z};
            meso_vec3 q = meso_mat4_transform_point(view, p);
            x0 = fminf(x0, q.x), x1 = fmaxf(x1, q.x), y0 = fminf(y0, q.y), y1 = fmaxf(y1, q.y);
            d0 = fminf(d0, -q.z), d1 = fmaxf(d1, -q.z);
        }
        /* square texels: the larger extent on both axes */
        float half = 0.5f * fmaxf(x1 - x0, y1 - y0) + margin;
        float cx = 0.5f * (x0 + x1), cy = 0.5f * (y0 + y1);
        meso_mat4 proj =
            ortho(cx - half, cx + half, cy - half, cy + half, d0 - margin, d1 + margin);
        out_map->view_projection = meso_mat4_mul(proj, view);
        out_map->texel_size = 2.0f * half / (float)size;
        return true;
    }
    meso_vec3 to_center = meso_vec3_sub(center, light->position);
    float distance = meso_vec3_length(to_center);
    if (!(distance > radius * 1.01f)) {
        meso_log_warning(ctx, "shadow maps: a point light lies inside the displaced mesh's bounds: "
                              "it casts no shadow map");
        return false;
    }
    float fov = 2.0f * asinf(radius / distance) * 1.02f;
    float z_near = fmaxf(distance - radius, 1e-3f * distance) * 0.99f;
    meso_mat4 view =
        meso_mat4_look_at(light->position, center, pick_up(meso_vec3_normalize(to_center)));
    meso_mat4 proj = meso_mat4_perspective(fov, 1.0f, z_near, (distance + radius) * 1.01f);
    out_map->view_projection = meso_mat4_mul(proj, view);
    out_map->texel_size = 2.0f * tanf(0.5f * fov) / (float)size;
    *out_z_near = z_near;
    return true;
}

meso_result displace_shadows_draw_light(meso_context *ctx, displace_shadows *shadows,
                                        const meso_scene *scene, int l, const meso_mesh *mesh,
                                        const displace_light_map *map) {
    size_t size = (size_t)shadows->options.size, count = (size_t)scene->num_lights;
    if (shadows->depth_lights < scene->num_lights) { /* first use, or the scene gained lights */
        /* lights x size^2 floats: 16 lights at 8192^2 are 4.3 GB, checked before allocating */
        meso_result r = meso_memory_check(ctx, "shadow maps", count * size * size * sizeof(float));
        if (r != MESO_OK) return r;
        float *grown = realloc(shadows->depth, count * size * size * sizeof(float));
        if (!grown)
            return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "shadow maps: %zu x %zu x %zu",
                                  count, size, size);
        shadows->depth = grown;
        shadows->depth_lights = scene->num_lights;
    }
    displace_light_map *out = &shadows->lights[l];
    *out = *map;
    float *depth = shadows->depth + (size_t)l * size * size;
    out->depth = depth;
    out->active = false;
    if (mesh->num_triangles == 0) return MESO_OK;
    meso_result r = meso_raster_depth_map(ctx, shadows->keep_raster ? &shadows->raster : NULL, mesh,
                                          map->view_projection, (int)size, (int)size, depth);
    if (r != MESO_OK) return r;
    out->active = true;
    return MESO_OK;
}

meso_result displace_shadows_render(meso_context *ctx, displace_shadows *shadows,
                                    const meso_scene *scene, const meso_mesh *mesh) {
    double start = meso_time_seconds();
    shadows->num_lights = 0;
    shadows->drawn = false;
    if (!shadows->options.enabled || scene->num_lights <= 0 || mesh->num_triangles == 0) {
        displace_shadows_mark_drawn(shadows, scene, 0.0);
        shadows->num_lights = 0;
        return MESO_OK;
    }
    meso_vec3 lo, hi;
    mesh_bounds(mesh, &lo, &hi);
    for (int l = 0; l < scene->num_lights; l++) {
        displace_light_map map;
        float z_near;
        shadows->lights[l].active = false;
        if (!displace_light_projection(ctx, shadows, &scene->lights[l], lo, hi, &map, &z_near))
            continue;
        meso_result r = displace_shadows_draw_light(ctx, shadows, scene, l, mesh, &map);
        if (r != MESO_OK) return r;
    }
    displace_shadows_mark_drawn(shadows, scene, meso_time_seconds() - start);
    return MESO_OK;
}

static float lit_tap(const displace_light_map *map, int size, int i, int j, float z) {
    i = i < 0 ? 0 : (i >= size ? size - 1 : i);
    j = j < 0 ? 0 : (j >= size ? size - 1 : j);
    return z <= map->depth[(size_t)j * (size_t)size + (size_t)i] ? 1.0f : 0.0f;
}

void displace_shadows_visibility(const displace_shadows *shadows, const meso_scene *scene,
                                 meso_vec3 position, meso_vec3 normal, meso_vec3 face_normal,
                                 float *visibility) {
    for (int l = 0; l < scene->num_lights; l++) {
        visibility[l] = 1.0f;
        if (l >= shadows->num_lights || !shadows->lights[l].active) continue;
        const displace_light_map *map = &shadows->lights[l];
        const meso_light *light = &scene->lights[l];
        meso_vec3 to_light = meso_light_direction(light, position);
        /* facing away from the light: no diffuse or specular term for visibility to scale */
        if (meso_vec3_dot(normal, to_light) <= 0.0f) continue;
        /* slope-scaled bias: a texel of the map spans tan(angle) texels of depth on a surface
         * tilted from the light; moving the receiver toward the light by that much removes
         * self-shadowing acne without a depth-unit constant */
        float c = fabsf(meso_vec3_dot(face_normal, to_light));
        c = c < 0.1f ? 0.1f : c;
        float slope = sqrtf(fmaxf(0.0f, 1.0f - c * c)) / c;
        float texel = map->texel_size;
        if (light->type != MESO_LIGHT_DIRECTIONAL)
            texel *= meso_vec3_length(meso_vec3_sub(light->position, position));
        float offset = shadows->options.bias * texel * (1.0f + slope);
        meso_vec3 p = meso_vec3_madd(position, to_light, offset);
        meso_vec4 clip = meso_mat4_mul_vec4(map->view_projection, (meso_vec4){p.x, p.y, p.z, 1.0f});
        if (!(clip.w > 0.0f)) continue;
        float nx = clip.x / clip.w, ny = clip.y / clip.w, nz = clip.z / clip.w;
        if (!(nx >= -1.0f && nx <= 1.0f && ny >= -1.0f && ny <= 1.0f)) continue;
        float z = nz * 0.5f + 0.5f;
        int size = shadows->options.size;
        /* continuous texel coordinates whose integers are the sample centres */
        float x = (nx * 0.5f + 0.5f) * (float)size - 0.5f;
        float y = (0.5f - ny * 0.5f) * (float)size - 0.5f;
        if (shadows->options.pcf) {
            float fx = floorf(x), fy = floorf(y);
            int i = (int)fx, j = (int)fy;
            float tx = x - fx, ty = y - fy;
            float top =
                lit_tap(map, size, i, j, z) * (1.0f - tx) + lit_tap(map, size, i + 1, j, z) * tx;
            float bottom = lit_tap(map, size, i, j + 1, z) * (1.0f - tx) +
                           lit_tap(map, size, i + 1, j + 1, z) * tx;
            visibility[l] = top * (1.0f - ty) + bottom * ty;
        } else {
            visibility[l] = lit_tap(map, size, (int)floorf(x + 0.5f), (int)floorf(y + 0.5f), z);
        }
    }
}

size_t displace_shadows_memory(const displace_shadows *shadows) {
    size_t maps = shadows->depth ? (size_t)shadows->depth_lights * (size_t)shadows->options.size *
                                       (size_t)shadows->options.size * sizeof(float)
                                 : 0;
    return maps + meso_raster_depth_scratch_memory(shadows->raster);
}

void displace_shadows_release(displace_shadows *shadows) {
    if (!shadows) return;
    free(shadows->depth);
    shadows->depth = NULL;
    meso_raster_depth_scratch_destroy(shadows->raster);
    shadows->raster = NULL;
    shadows->depth_lights = 0;
    shadows->num_lights = 0;
}

/* ---- Shading ------------------------------------------------------------------------------ */

void displace_shade(const displace_surface *surface, const displace_shadows *shadows,
                    const meso_mesh *mesh, const meso_frame *frame, meso_fragment *fragments,
                    size_t count) {
    enum { CHUNK = 64 };
    int num_lights = frame->scene->num_lights;
    float visibility[CHUNK * MESO_SCENE_MAX_LIGHTS];
    uint32_t cached_triangle = UINT32_MAX;
    meso_vec3 face_normal = {0.0f, 0.0f, 0.0f};
    bool have_face = false;
    for (size_t first = 0; first < count; first += CHUNK) {
        size_t n = count - first < CHUNK ? count - first : CHUNK;
        for (size_t f = 0; f < n; f++) {
            meso_fragment *frag = &fragments[first + f];
            meso_vec3 normal = frag->normal;
            if (surface->heightfield) {
                /* the bump-map operation on the interpolated BASE frame (slides, "Hardware
                 * Architecture"): the same normal every other technique shades with */
                meso_vec2 g = displace_gradient(surface, frag->uv);
                meso_vec3 n3 = meso_displaced_normal(frag->normal, frag->tangent, frag->bitangent,
                                                     surface->depth, g);
                if (meso_vec3_dot(n3, n3) > 0.0f && meso_vec3_is_finite(n3)) normal = n3;
            }
            /* a batch spans triangles, each one's fragments consecutive: the face normal
             * once a triangle */
            if (frag->triangle != cached_triangle) {
                cached_triangle = frag->triangle;
                have_face = false;
                if (mesh && frag->triangle < mesh->num_triangles) {
                    const uint32_t *t = mesh->indices + (size_t)frag->triangle * 3;
                    meso_vec3 p0 = mesh->positions[t[0]];
                    meso_vec3 e = meso_vec3_cross(meso_vec3_sub(mesh->positions[t[1]], p0),
                                                  meso_vec3_sub(mesh->positions[t[2]], p0));
                    if (meso_vec3_dot(e, e) > 0.0f) {
                        face_normal = meso_vec3_normalize(e);
                        have_face = true;
                    }
                }
            }
            meso_vec3 face = have_face ? face_normal : frag->normal;
            float *seen = visibility + f * (size_t)num_lights;
            displace_shadows_visibility(shadows, frame->scene, frag->position, normal, face, seen);
            if (displace_back_face(surface, shadows, frame, frag->position, face))
                for (int l = 0; l < num_lights; l++) seen[l] = 0.0f;
            frag->normal = normal;
        }
        meso_shade_fragments(frame, surface->object, fragments + first, n, visibility);
    }
}
