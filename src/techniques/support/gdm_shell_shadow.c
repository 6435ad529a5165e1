/* gdm's shadows through the whole shell: the light ray followed from prism to prism, each
 * tested with GDM's per-prism segment (gdm_shell_shadow.h; GDM §3.2 Fig. 5 applied to the light
 * ray; docs/techniques/gdm.md). */
#include "gdm_shell_shadow.h"

#include "gdm_walk.h"

#include <embree3/rtcore.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include "meso/runtime.h"
#include "meso/prism.h"

/* Prisms a light ray may cross before the answer is "visible": a walk stuck on a fin's plane
 * (a ray in it) ends instead of looping. A grazing ray across a fine mesh crosses tens. */
enum { WALK_MAX_PRISMS = 256 };

struct gdm_shell {
    gdm_shell_desc desc;
    RTCDevice device;
    RTCScene scene;
    /* object-space: the Embree ray starts this far back from the point where the ray left a
     * prism, so that the neighbour's copy of the shared fin lies ahead of it (at `step`) */
    float step;
    /* Per face of the layer, the face coincident with it and wound the other way (a fin's
     * copy in the neighbour prism: the twins are bit-identical, geom_prism.c), NO_TWIN for
     * tops, bottoms and fins on an open border. A ray leaving a prism through a fin enters
     * the twin's prism right there: the walk crosses sideways without asking Embree, which
     * was most of its cost on a convex mesh (docs/techniques/gdm.md). NULL: out of memory at
     * create, every crossing asks Embree. gdm's own table (gdm_shell_desc.fin_twin) or
     * owned_twin, built here (gdm_walk.h). */
    const uint32_t *fin_twin;
    uint32_t *owned_twin;
    /* Per prism, 1 where every vertex of the layer lies behind (or on) the prism's top plane:
     * the whole layer is in that half-space, so a ray that leaves the prism through its top
     * is outside it from then on and meets no prism again. The walk then ends there without
     * asking Embree (every prism of a convex or flat base mesh; the outer side of a torus).
     * NULL: not proven (cost cap, out of memory). */
    uint8_t *top_clear;
};

#define NO_TWIN GDM_NO_TWIN

/* The proof of top_clear: each job tests a run of prisms' top planes against every vertex of
 * the layer, a cell of a coarse grid over the layer at a time by the cell's bounding box
 * (most cells lie far behind any one top), the vertices only of a cell the plane cuts, until
 * the first vertex in front. Skipped above a cost cap. Each prism's answer is its own: the
 * same for any number of threads. */
enum { TOPS_PER_JOB = 64, VERTICES_PER_CELL = 16, MAX_CELLS_A_SIDE = 32 };
#define TOPS_PROOF_MAX_TESTS ((uint64_t)1 << 29)

typedef struct proof_cell {
    meso_vec3 centre, half; /* the cell's vertices' bounding box */
    uint32_t first, end;    /* into tops_proof.order */
} proof_cell;

typedef struct tops_proof {
    const meso_prism_layer *layer;
    const proof_cell *cells;
    const uint32_t *order; /* the layer's vertices, cell by cell */
    size_t num_cells;
    float tolerance;
    uint8_t *clear; /* out: per prism */
} tops_proof;

static bool behind(const meso_prism_plane *plane, meso_vec3 p, float margin) {
    /* NaN fails: nothing is proven about a broken layer */
    return meso_vec3_dot(plane->normal, p) - plane->offset <= margin;
}

static void prove_tops(void *user, size_t job, int thread_index) {
    (void)thread_index;
    tops_proof *proof = user;
    const meso_prism_layer *layer = proof->layer;
    const meso_vec3 *positions = layer->faces->positions;
    size_t end = (job + 1) * TOPS_PER_JOB;
    if (end > layer->num_prisms) end = layer->num_prisms;
    for (size_t prism = job * TOPS_PER_JOB; prism < end; prism++) {
        proof->clear[prism] = 0;
        if (!layer->prisms[prism].valid) continue; /* draws nothing, is never left */
        const meso_prism_plane *top = &layer->planes[prism * MESO_PRISM_NUM_FACES + MESO_PRISM_TOP];
        bool clear = true;
        for (size_t k = 0; clear && k < proof->num_cells; k++) {
            const proof_cell *cell = &proof->cells[k];
            /* the box's farthest corner along the plane's normal */
            meso_vec3 n = top->normal;
            float reach =
                fabsf(n.x) * cell->half.x + fabsf(n.y) * cell->half.y + fabsf(n.z) * cell->half.z;
            if (behind(top, cell->centre, proof->tolerance - reach)) continue;
            for (uint32_t i = cell->first; clear && i < cell->end; i++)
                clear = behind(top, positions[proof->order[i]], proof->tolerance);
        }
        proof->clear[prism] = clear;
    }
}

/* The grid cell of p, `side` cells a side over [lo, lo + extent]. */
static uint32_t cell_of(meso_vec3 p, meso_vec3 lo, meso_vec3 extent, int side) {
    float q[3] = {(p.x - lo.x) / extent.x, (p.y - lo.y) / extent.y, (p.z - lo.z) / extent.z};
    int c[3];
    for (int a = 0; a < 3; a++) {
        float f = q[a] * (float)side;
        c[a] = f >= 0.0f && f < (float)side ? (int)f : (f >= (float)side ? side - 1 : 0);
    }
    return (uint32_t)((c[2] * side + c[1]) * side + c[0]);
}

size_t gdm_prism_tops_clear(meso_context *ctx, const meso_prism_layer *layer, uint8_t *clear) {
    const meso_mesh *faces = layer->faces;
    size_t nv = faces->num_vertices;
    memset(clear, 0, layer->num_prisms);
    if (layer->num_prisms == 0 || nv == 0 || nv >= UINT32_MAX ||
        (uint64_t)layer->num_prisms * (uint64_t)nv > TOPS_PROOF_MAX_TESTS)
        return 0;
    meso_vec3 lo = faces->positions[0], hi = lo;
    for (size_t v = 1; v < nv; v++) {
        meso_vec3 p = faces->positions[v];
        lo = (meso_vec3){fminf(lo.x, p.x), fminf(lo.y, p.y), fminf(lo.z, p.z)};
        hi = (meso_vec3){fmaxf(hi.x, p.x), fmaxf(hi.y, p.y), fmaxf(hi.z, p.z)};
    }
    meso_vec3 extent = meso_vec3_sub(hi, lo);
    float diagonal = meso_vec3_length(extent);
    if (!isfinite(diagonal)) return 0;
    extent = (meso_vec3){fmaxf(extent.x, 1e-30f), fmaxf(extent.y, 1e-30f), fmaxf(extent.z, 1e-30f)};
    int side = (int)cbrt((double)nv / VERTICES_PER_CELL);
    side = side < 1 ? 1 : (side > MAX_CELLS_A_SIDE ? MAX_CELLS_A_SIDE : side);
    size_t num_grid = (size_t)side * (size_t)side * (size_t)side;
    uint32_t *count = calloc(num_grid + 1, sizeof *count);
    uint32_t *order = malloc(nv * sizeof *order);
    proof_cell *cells = malloc(num_grid * sizeof *cells);
    if (!count || !order || !cells) {
        free(count), free(order), free(cells);
        return 0; /* unproven: the walk asks Embree as before */
    }
    for (size_t v = 0; v < nv; v++) count[cell_of(faces->positions[v], lo, extent, side) + 1]++;
    for (size_t g = 0; g < num_grid; g++) count[g + 1] += count[g];
    size_t num_cells = 0;
    for (size_t g = 0; g < num_grid; g++)
        if (count[g + 1] > count[g])
            cells[num_cells++] = (proof_cell){.first = count[g], .end = count[g + 1]};
    uint32_t *fill = calloc(num_grid, sizeof *fill);
    if (!fill) {
        free(count), free(order), free(cells);
        return 0;
    }
    for (size_t v = 0; v < nv; v++) {
        uint32_t g = cell_of(faces->positions[v], lo, extent, side);
        order[count[g] + fill[g]++] = (uint32_t)v;
    }
    free(fill);
    free(count);
    for (size_t k = 0; k < num_cells; k++) {
        proof_cell *cell = &cells[k];
        meso_vec3 a = faces->positions[order[cell->first]], b = a;
        for (uint32_t i = cell->first + 1; i < cell->end; i++) {
            meso_vec3 p = faces->positions[order[i]];
            a = (meso_vec3){fminf(a.x, p.x), fminf(a.y, p.y), fminf(a.z, p.z)};
            b = (meso_vec3){fmaxf(b.x, p.x), fmaxf(b.y, p.y), fmaxf(b.z, p.z)};
        }
        cell->centre = meso_vec3_scale(meso_vec3_add(a, b), 0.5f);
        /* a little more than the box: the box's test must not pass a vertex its own test
         * would fail by rounding */
        meso_vec3 half = meso_vec3_scale(meso_vec3_sub(b, a), 0.5f * (1.0f + 1e-5f));
        cell->half =
            meso_vec3_add(half, (meso_vec3){1e-6f * diagonal, 1e-6f * diagonal, 1e-6f * diagonal});
    }
    /* a vertex on a top's plane (a flat mesh: all of them) may sit above it by rounding: a
     * hundred-thousandth of the layer's extent, far below the Embree walk's own `step` */
    tops_proof proof = {.layer = layer,
                        .cells = cells,
                        .order = order,
                        .num_cells = num_cells,
                        .tolerance = 1e-5f * diagonal,
                        .clear = clear};
    meso_parallel_for(ctx, (layer->num_prisms + TOPS_PER_JOB - 1) / TOPS_PER_JOB, prove_tops,
                      &proof);
    free(cells);
    free(order);
    size_t proven = 0;
    for (size_t prism = 0; prism < layer->num_prisms; prism++) proven += clear[prism];
    return proven;
}

/* The prism the ray is in (its faces are not entries) and the ray's direction, for the
 * filter; Embree hands the context back to it. */
typedef struct walk_context {
    struct RTCIntersectContext base; /* first: the filter casts the context back */
    const meso_prism_layer *layer;
    size_t current;
    meso_vec3 direction;
} walk_context;

/* Keep the faces the ray enters a prism through: a face's outward normal against the ray. A
 * fin is two coincident triangles, one a prism; this picks the one whose prism lies ahead. */
static void keep_entries(const struct RTCFilterFunctionNArguments *args) {
    const walk_context *walk = (const walk_context *)args->context;
    for (unsigned i = 0; i < args->N; i++) {
        if (args->valid[i] != -1) continue;
        /* RTCHitN's layout (rtcore_ray.h: Ng x, y, z, u, v, primID, each N wide); its
         * accessor is C++ only */
        unsigned face = ((const unsigned *)args->hit)[5 * args->N + i];
        int slot;
        size_t prism = meso_prism_layer_face_prism(walk->layer, face, &slot);
        const meso_prism_plane *plane =
            &walk->layer->planes[prism * MESO_PRISM_NUM_FACES + (size_t)slot];
        if (prism == walk->current || !(meso_vec3_dot(plane->normal, walk->direction) < 0.0f))
            args->valid[i] = 0;
    }
}

meso_result gdm_shell_create(meso_context *ctx, const gdm_shell_desc *desc, const char *name,
                             gdm_shell **out_shell) {
    *out_shell = NULL;
    if (!desc || !desc->layer || !desc->mesh || !desc->gdm || (!desc->heightfield && !desc->solid))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: gdm shell shadows: needs the prisms, the map and the "
                              "mesostructure",
                              name);
    const meso_mesh *faces = desc->layer->faces;
    meso_result r =
        meso_memory_check(ctx, "gdm shell shadows",
                          (uint64_t)faces->num_triangles * 64 + (uint64_t)faces->num_vertices * 16);
    if (r != MESO_OK) return r;
    gdm_shell *shell = calloc(1, sizeof *shell);
    if (!shell) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: gdm shell", name);
    shell->desc = *desc;
    shell->step = 1e-3f * desc->layer->depth;
    /* one build thread: the BVH, and so which of two equal hits Embree reports, does not
     * depend on the number of workers (the images are byte-identical for any) */
    shell->device = rtcNewDevice("threads=1");
    shell->scene = shell->device ? rtcNewScene(shell->device) : NULL;
    RTCGeometry geometry =
        shell->scene ? rtcNewGeometry(shell->device, RTC_GEOMETRY_TYPE_TRIANGLE) : NULL;
    size_t num_vertices = faces->num_vertices ? faces->num_vertices : 1;
    size_t num_faces = faces->num_triangles;
    float *vertices =
        geometry ? rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                           3 * sizeof(float), num_vertices)
                 : NULL;
    uint32_t *indices =
        geometry && num_faces
            ? rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                      3 * sizeof(uint32_t), num_faces)
            : NULL;
    if (!vertices || (num_faces && !indices)) {
        if (geometry) rtcReleaseGeometry(geometry);
        r = meso_log_error(ctx, MESO_ERROR_INTERNAL,
                           "%s: gdm shell shadows: Embree could not start", name);
        goto fail;
    }
    memset(vertices, 0, 3 * sizeof(float) * num_vertices);
    for (size_t v = 0; v < faces->num_vertices; v++) {
        meso_vec3 p = faces->positions[v];
        vertices[3 * v] = p.x, vertices[3 * v + 1] = p.y, vertices[3 * v + 2] = p.z;
    }
    if (num_faces) memcpy(indices, faces->indices, 3 * num_faces * sizeof *indices);
    rtcSetGeometryIntersectFilterFunction(geometry, keep_entries);
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(shell->scene, geometry);
    rtcReleaseGeometry(geometry);
    rtcCommitScene(shell->scene);
    if (rtcGetDeviceError(shell->device) != RTC_ERROR_NONE) {
        r = meso_log_error(ctx, MESO_ERROR_INTERNAL,
                           "%s: gdm shell shadows: Embree could not build", name);
        goto fail;
    }
    if (!desc->fin_twin) shell->owned_twin = gdm_fin_twins(desc->layer);
    shell->fin_twin = desc->fin_twin ? desc->fin_twin : shell->owned_twin;
    shell->top_clear = malloc(desc->layer->num_prisms ? desc->layer->num_prisms : 1);
    if (shell->top_clear && gdm_prism_tops_clear(ctx, desc->layer, shell->top_clear) == 0) {
        free(shell->top_clear); /* nothing proven: every top exit asks Embree */
        shell->top_clear = NULL;
    }
    *out_shell = shell;
    return MESO_OK;
fail:
    gdm_shell_destroy(shell);
    return r;
}

void gdm_shell_destroy(gdm_shell *shell) {
    if (!shell) return;
    if (shell->scene) rtcReleaseScene(shell->scene);
    if (shell->device) rtcReleaseDevice(shell->device);
    free(shell->owned_twin);
    free(shell->top_clear);
    free(shell);
}

size_t gdm_shell_memory(const gdm_shell *shell) {
    if (!shell) return 0;
    const meso_mesh *faces = shell->desc.layer->faces;
    return sizeof *shell + (shell->owned_twin ? faces->num_triangles * sizeof(uint32_t) : 0) +
           (shell->top_clear ? shell->desc.layer->num_prisms : 0) +
           faces->num_vertices * 3 * sizeof(float) +
           faces->num_triangles * (3 * sizeof(uint32_t) + 32); /* + the BVH, about */
}

/* ---- The mesostructure: the same tests as gdm.c's --------------------------------------- */

static inline bool inside(const gdm_shell_desc *d, meso_vec3 uvw) {
    if (d->inside) return d->inside(d->inside_user, uvw);
    return gdm_mesostructure_inside(d->heightfield, d->solid, uvw);
}

static inline float lookup(const gdm_shell_desc *d, meso_vec3 uvw, meso_vec3 direction) {
    if (!d->table) return meso_gdm_lookup(d->gdm, uvw, direction, 0, true);
    return gdm_lookup8(d->table, uvw, direction);
}

/* Is any probe of t0 + x dir inside: at x = first (unless negative), then at `steps` evenly
 * spaced x over [0, length]. */
static bool probes_blocked(const gdm_shell_desc *d, meso_vec3 t0, meso_vec3 dir, float first,
                           float length, int steps) {
    if (d->probes_inside) return d->probes_inside(d->inside_user, t0, dir, first, length, steps);
    if (first >= 0.0f && inside(d, meso_vec3_madd(t0, dir, first))) return true;
    for (int k = 0; k < steps; k++) {
        float x = length * ((float)k + 0.5f) / (float)steps;
        if (inside(d, meso_vec3_madd(t0, dir, x))) return true;
    }
    return false;
}

/* Does the mesostructure block the texture-space segment t0 + x dir, x in [0, length] (dir
 * unit)? §3.2 per prism: d_GDM(t0, dir) short of the segment's end by more than the margin
 * (the table's error near a boundary, as gdm's local test allows it). With refine_steps the
 * table's blocker is confirmed on the mesostructure as gdm's shadows confirm it: just past d,
 * else by shadow_steps probes along the segment (the compressed table errs by more than the
 * gaps of a weave; the answers then are the mesostructure's). `thorough`: the table's "lit"
 * is not trusted either -- the segment is probed every voxel (at most shadow_steps times)
 * whatever the table says. */
static bool segment_blocked(const gdm_shell_desc *d, meso_vec3 t0, meso_vec3 dir, float length,
                            bool thorough) {
    float margin = d->shadow_bias * d->voxel.z;
    if (!(length > margin)) return false;
    /* every probe below lies on t0 + x dir, x in [0, length]: where that stretch is proven
     * outside they all answer outside, whatever the table says (the same answer) */
    if (d->refine_steps > 0 && d->segment_outside &&
        d->segment_outside(d->inside_user, t0, meso_vec3_madd(t0, dir, length)))
        return false;
    int steps = d->shadow_steps;
    if (thorough) { /* a probe every voxel, at most shadow_steps */
        float voxels = ceilf(length / fminf(d->voxel.x, fminf(d->voxel.y, d->voxel.z)));
        steps = voxels < 2.0f ? 2 : voxels < (float)steps ? (int)voxels : steps;
    }
    if (d->refine_steps > 0 && thorough && d->heightfield) {
        /* The answer is "any probe inside": the one just past the table's d and one every
         * voxel. Each probe's answer is the mesostructure's whatever the order, so a height
         * field's voxel probes (a sample each, cheaper than the lookup) go first, and the
         * lookup is made only where none of them is inside (most segments that a thorough
         * walk tests hold its blocker: fewer instructions, the same images). Not for a solid, whose
         * probes cost about a lookup each (the distance function): weave-teapot gained nothing in
         * that order. */
        if (probes_blocked(d, t0, dir, -1.0f, length, steps)) return true;
        float hit = lookup(d, t0, dir);
        if (!(hit < length - margin)) return false;
        return probes_blocked(d, t0, dir, fminf(fmaxf(hit, 0.0f) + 0.5f * d->refine_window, length),
                              length, 0);
    }
    float hit = lookup(d, t0, dir);
    if (d->refine_steps <= 0) return hit < length - margin;
    if (!thorough && !(hit < length - margin)) return false;
    float past = -1.0f; /* none */
    if (hit < length - margin) past = fminf(fmaxf(hit, 0.0f) + 0.5f * d->refine_window, length);
    return probes_blocked(d, t0, dir, past, length, steps);
}

/* ---- The walk -------------------------------------------------------------------------- */

/* A prism's stretch of the ray: from `origin` (texture point t_in, entering through face slot
 * entry_slot; -1 inside) to where it leaves. false: the prism bounds nothing (degenerate).
 * Its (u, v, w) at both ends are made only when a test reads them (crossing_uvw): most
 * crossings of a convex mesh's walk are neither tested nor floors (bumps-sphere: 352 k
 * face_uvw calls a frame for none read). */
typedef struct crossing {
    meso_vec3 t_in, t_out, p_in, p_out;
    size_t prism, entry_face; /* t_in is entry_face's (u, v, w) at p_in; NO_FACE: given */
    int exit_slot;
    bool uvw; /* t_in, t_out made */
} crossing;

#define NO_FACE SIZE_MAX

static bool cross_prism(const meso_prism_layer *layer, size_t prism, meso_vec3 origin,
                        meso_vec3 t_in, meso_vec3 light, int entry_slot, crossing *out) {
    float t;
    if (!meso_prism_layer_exit(layer, prism, origin, light, entry_slot, &t, &out->exit_slot) ||
        !isfinite(t))
        return false;
    out->t_in = t_in;
    out->p_in = origin;
    out->p_out = meso_vec3_madd(origin, light, t);
    out->prism = prism;
    out->entry_face = NO_FACE;
    out->uvw = false;
    return true;
}

/* The crossing's (u, v, w) at both ends, made once. */
static void crossing_uvw(const meso_prism_layer *layer, crossing *c) {
    if (c->uvw) return;
    if (c->entry_face != NO_FACE)
        c->t_in = meso_prism_layer_face_uvw(layer, c->entry_face, c->p_in);
    c->t_out = meso_prism_layer_face_uvw(
        layer, meso_prism_layer_face(layer, c->prism, c->exit_slot), c->p_out);
    c->uvw = true;
}

static bool crossing_blocked(const gdm_shell_desc *d, crossing *c, bool thorough) {
    crossing_uvw(d->layer, c);
    meso_vec3 segment = meso_vec3_sub(c->t_out, c->t_in);
    float length = meso_vec3_length(segment);
    if (!(length > 1e-7f) || !isfinite(length)) return false;
    return segment_blocked(d, c->t_in, meso_vec3_scale(segment, 1.0f / length), length, thorough);
}

/* A ray leaving the slab's bottom: into the object's body for a height field; for a solid,
 * through solid where the solid's floor is (gdm.c's floor_is_solid; its hits count the same
 * floor) -- unless the ray starts on that floor (a point on a bar's underside, its light
 * below: the stretch is shorter than the margin), which it leaves instead of crossing. */
static bool floor_blocks(const gdm_shell_desc *d, crossing *c) {
    if (d->heightfield) return true;
    crossing_uvw(d->layer, c);
    if (!(meso_vec3_length(meso_vec3_sub(c->t_out, c->t_in)) > d->shadow_bias * d->voxel.z))
        return false;
    return inside(d, (meso_vec3){c->t_out.x, c->t_out.y, 1.0f - 1e-3f});
}

/* The next prism face the ray origin + x light (x > 0) enters, not one of prism `current`'s:
 * its prism, slot and point. false: the ray leaves the shell. */
static bool next_entry(const gdm_shell *shell, size_t current, meso_vec3 origin, meso_vec3 light,
                       size_t *out_prism, int *out_slot, meso_vec3 *out_point, float *out_t) {
    walk_context walk;
    rtcInitIntersectContext(&walk.base);
    walk.layer = shell->desc.layer;
    walk.current = current;
    walk.direction = light;
    meso_vec3 start = meso_vec3_madd(origin, light, -shell->step);
    struct RTCRayHit rh;
    memset(&rh, 0, sizeof rh);
    rh.ray.org_x = start.x, rh.ray.org_y = start.y, rh.ray.org_z = start.z;
    rh.ray.dir_x = light.x, rh.ray.dir_y = light.y, rh.ray.dir_z = light.z;
    rh.ray.tnear = 0.0f;
    rh.ray.tfar = INFINITY;
    rh.ray.mask = UINT32_MAX;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(shell->scene, &walk.base, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    *out_prism = meso_prism_layer_face_prism(shell->desc.layer, rh.hit.primID, out_slot);
    *out_point = meso_vec3_madd(start, light, rh.ray.tfar);
    *out_t = rh.ray.tfar;
    return true;
}

bool gdm_shell_face_is_seam(const gdm_shell *shell, size_t face) {
    return shell && shell->fin_twin && shell->fin_twin[face] != NO_TWIN;
}

bool gdm_shell_top_clear(const gdm_shell *shell, size_t prism) {
    return shell && shell->top_clear && shell->top_clear[prism];
}

size_t gdm_shell_prism_index(const gdm_shell *shell, const meso_prism *prism) {
    return (size_t)(prism - shell->desc.layer->prisms);
}

/* gdm_shell_light_visible; `at` NULL, or what the caller knows of the point
 * (gdm_shell_light_visible_at). */
static bool light_visible(const gdm_shell *shell, size_t prism, meso_vec3 uvw, meso_vec3 light,
                          bool slab_clear, bool thorough, const gdm_shell_point *at) {
    const gdm_shell_desc *d = &shell->desc;
    const meso_prism_layer *layer = d->layer;
    const meso_prism *first = &layer->prisms[prism];
    if (!first->valid) return true;
    meso_vec3 t0 = uvw;
    if (!slab_clear) {
        /* off the surface as gdm's local test starts (its table is blended with the solid's
         * zeros at the surface): up for a height field, along the solid's normal */
        meso_vec3 n = {0.0f, 0.0f, -1.0f};
        if (d->solid) {
            meso_vec3 g = at && at->has_gradient
                              ? at->gradient
                              : meso_solid_gradient(d->solid, gdm_tile_point(uvw));
            float len = meso_vec3_length(g);
            n = len > 0.0f && isfinite(len) ? meso_vec3_scale(g, 1.0f / len) : n;
        }
        t0 = meso_vec3_add(uvw, meso_vec3_mul(n, meso_vec3_scale(d->voxel, d->shadow_bias)));
        t0.z = fminf(fmaxf(t0.z, 0.0f), 1.0f);
    }
    meso_vec3 origin =
        at && slab_clear ? at->position : meso_prism_map(first, d->mesh, layer->depth, t0, -1);
    /* tested: the prisms of this stretch are tested (after the ray left the slab the caller's
     * test covered). That test ran in one flat slab along the point's own frame: it covered
     * the ray up to where a flat shell's top would be, w depth / (N . L) away (and a little
     * more for rounding). Where the surface curves over the point (under a vase's flared rim) the
     * ray stays in the shell longer, crossing other prisms through their fins: from there on they
     * are tested. */
    bool tested = !slab_clear;
    float reach = INFINITY;
    if (slab_clear) {
        meso_vec3 n;
        if (at) {
            n = at->normal;
        } else {
            float b[3];
            meso_prism_weights(first, (meso_vec2){uvw.x, uvw.y}, b);
            const uint32_t *v = first->vertices;
            n = meso_vec3_normalize(
                meso_vec3_barycentric(d->mesh->normals[v[0]], d->mesh->normals[v[1]],
                                      d->mesh->normals[v[2]], b[0], b[1], b[2]));
        }
        reach = 1.05f * uvw.z * layer->depth / fmaxf(meso_vec3_dot(n, light), 1e-3f) +
                2.0f * shell->step;
    }
    crossing c;
    size_t current = prism;
    if (!cross_prism(layer, prism, origin, t0, light, -1, &c)) return true;
    for (int n = 0; n < WALK_MAX_PRISMS; n++) {
        if (tested && crossing_blocked(d, &c, thorough)) return false;
        if (meso_vec3_length(meso_vec3_sub(c.p_out, origin)) > reach) tested = true;
        if (c.exit_slot == MESO_PRISM_BOTTOM) {
            if (floor_blocks(d, &c)) return false;
            tested = true; /* out of the slab into the object's open inside */
        } else if (c.exit_slot == MESO_PRISM_TOP) {
            if (shell->top_clear && shell->top_clear[current]) return true; /* nothing ahead */
            tested = true;
        }
        size_t next;
        int slot;
        meso_vec3 point;
        float t;
        uint32_t twin = c.exit_slot >= MESO_PRISM_FIN && shell->fin_twin
                            ? shell->fin_twin[meso_prism_layer_face(layer, current, c.exit_slot)]
                            : NO_TWIN;
        if (twin != NO_TWIN) {
            /* sideways through a fin: into its twin's prism at the same point (Embree would
             * find that face `step` ahead of its start, `step` back from here) */
            next = meso_prism_layer_face_prism(layer, twin, &slot);
            point = c.p_out;
            t = shell->step;
        } else if (!next_entry(shell, current, c.p_out, light, &next, &slot, &point, &t)) {
            return true;
        }
        /* through a fin into a prism that is not its neighbour (the ray left the shell at an
         * open border and met it again farther on): out of the slab */
        if (t > 3.0f * shell->step) tested = true;
        /* a height field's body fills every prism below its floor */
        if (tested && slot == MESO_PRISM_BOTTOM && d->heightfield) return false;
        size_t entry_face = meso_prism_layer_face(layer, next, slot);
        current = next;
        if (cross_prism(layer, next, point, (meso_vec3){0.0f, 0.0f, 0.0f}, light, slot, &c)) {
            c.entry_face = entry_face;
        } else {
            /* a degenerate prism: step past it */
            c.t_in = c.t_out = meso_prism_layer_face_uvw(layer, entry_face, point);
            c.uvw = true;
            c.p_out = point;
            c.exit_slot = MESO_PRISM_FIN;
        }
    }
    return true;
}

bool gdm_shell_light_visible(const gdm_shell *shell, size_t prism, meso_vec3 uvw, meso_vec3 light,
                             bool slab_clear, bool thorough) {
    return light_visible(shell, prism, uvw, light, slab_clear, thorough, NULL);
}

bool gdm_shell_light_visible_at(const gdm_shell *shell, size_t prism, meso_vec3 uvw,
                                const gdm_shell_point *point, meso_vec3 light, bool slab_clear,
                                bool thorough) {
    return light_visible(shell, prism, uvw, light, slab_clear, thorough, point);
}
