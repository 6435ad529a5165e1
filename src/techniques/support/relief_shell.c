/* The relief family on the prism shell: the shell, its drawing, the walk of view and light rays
 * and the searches along their stretches (relief_shell.h). */
#include "relief_shell.h"

#include "gdm_walk.h"
#include "meso/prism.h"
#include "meso/runtime.h"

/* Prisms a ray may cross before the walk gives up (gdm's cap, the same reason: a ray caught in
 * a loop of fins at a shared vertex ends instead of spinning; a grazing ray over a fine plane
 * crosses a few hundred). */
#define RELIEF_SHELL_MAX_PRISMS 4096
/* Fragments shaded together (meso_shade_fragments' batch). */
#define RELIEF_SHELL_CHUNK 64

struct relief_shell {
    const meso_mesh *mesh; /* the base mesh: the frame at a hit */
    meso_prism_layer *layer;
    float depth;
    /* gdm_walk_boundary's arrays and the frame's drawing order (gdm_walk_sort_faces) */
    uint32_t *fin_twin, *boundary, *drawn_face, *drawn_indices, *sort_counts;
    uint8_t *same_uvw;
    float *sort_keys;
    size_t group_start[4];
    meso_mesh drawn; /* the layer's vertex arrays, drawn_indices */
    bool closed;     /* every fin has its twin: the base mesh has no open border */
};

void relief_shell_destroy(relief_shell *shell) {
    if (!shell) return;
    meso_prism_layer_destroy(shell->layer);
    free(shell->fin_twin);
    free(shell->boundary);
    free(shell->drawn_face);
    free(shell->drawn_indices);
    free(shell->sort_counts);
    free(shell->same_uvw);
    free(shell->sort_keys);
    free(shell);
}

meso_result relief_shell_create(meso_context *ctx, const meso_object *object, const char *technique,
                                relief_shell **out_shell) {
    *out_shell = NULL;
    relief_shell *sh = calloc(1, sizeof *sh);
    if (!sh)
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: %s: out of memory", object->name,
                              technique);
    sh->mesh = object->mesh;
    sh->depth = object->mesostructure.depth;
    meso_result r = meso_prism_layer_create(ctx, object->mesh, sh->depth, object->name, &sh->layer);
    if (r != MESO_OK) {
        relief_shell_destroy(sh);
        return r;
    }
    bool ok =
        gdm_walk_boundary(sh->layer, &sh->fin_twin, &sh->boundary, &sh->same_uvw, sh->group_start);
    size_t faces = ok && sh->group_start[3] ? sh->group_start[3] : 1;
    sh->drawn_face = malloc(faces * sizeof *sh->drawn_face);
    sh->drawn_indices = malloc(3 * faces * sizeof *sh->drawn_indices);
    sh->sort_counts = malloc((GDM_DEPTH_BUCKETS + 1) * sizeof *sh->sort_counts);
    sh->sort_keys = malloc(faces * sizeof *sh->sort_keys);
    if (!ok || !sh->drawn_face || !sh->drawn_indices || !sh->sort_counts || !sh->sort_keys) {
        relief_shell_destroy(sh);
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: %s: out of memory", object->name,
                              technique);
    }
    sh->drawn = *sh->layer->faces;
    sh->drawn.indices = sh->drawn_indices;
    sh->drawn.num_triangles = sh->group_start[3];
    size_t n = sh->layer->num_prisms;
    sh->closed = true;
    for (size_t f = n; f < 7 * n && sh->closed; f++)
        sh->closed = sh->layer->prisms[(f - n) / 6].valid ? sh->fin_twin[f] != GDM_NO_TWIN : true;
    *out_shell = sh;
    return MESO_OK;
}

size_t relief_shell_memory(const relief_shell *shell) {
    if (!shell) return 0;
    size_t faces = shell->layer->faces->num_triangles, drawn = shell->group_start[3];
    return meso_prism_layer_memory(shell->layer) + faces * (sizeof(uint32_t) + 1) +
           drawn * (5 * sizeof(uint32_t) + sizeof(float)) +
           (GDM_DEPTH_BUCKETS + 1) * sizeof(uint32_t);
}

const meso_mesh *relief_shell_geometry(relief_shell *shell, const meso_frame *frame) {
    gdm_walk_sort_faces(shell->layer->faces, shell->boundary, shell->group_start, frame->eye,
                        frame->forward, shell->sort_keys, shell->sort_counts, shell->drawn_face,
                        shell->drawn_indices);
    return &shell->drawn;
}

/* ---- Searches along a stretch ------------------------------------------------------------- */

static inline int stretch_steps(int steps, float dd) {
    float n = ceilf((float)steps * fabsf(dd));
    return n > 1.0f ? (n < (float)steps ? (int)n : steps) : 1;
}

/* The search's samples first .. first + 7 of a stretch cut into n steps: their share of the
 * stretch in *sv (past n: repeats of the end, not looked at) and their points (x, y, d). */
static inline void stretch_samples8(const relief_shell_stretch *st, int first, int n, v8f *sv,
                                    v8f *x, v8f *y, v8f *d) {
    float inv = 1.0f / (float)n;
    for (int j = 0; j < RELIEF_LANES; j++) {
        int k = first + j;
        (*sv)[j] = k >= n ? 1.0f : (float)k * inv;
    }
    *x = v8_splat(st->x0) + v8_splat(st->xd) * *sv;
    *y = v8_splat(st->y0) + v8_splat(st->yd) * *sv;
    *d = v8_splat(st->d0) + v8_splat(st->dd) * *sv;
}

/* The stretch from texture point a to b ((u, v, w)) in the search's coordinates. */
static relief_shell_stretch stretch_between(const relief_shell_search *q, meso_vec3 a,
                                            meso_vec3 b) {
    float w = (float)q->width, h = (float)q->height;
    float x0 = a.x * w - 0.5f, y0 = (1.0f - a.y) * h - 0.5f;
    return (relief_shell_stretch){
        x0, y0, a.z, b.x * w - 0.5f - x0, (1.0f - b.y) * h - 0.5f - y0, b.z - a.z};
}

/* Under a height field's surface (a ray that entered an open border's fin below it, `under`
 * in search_stretch): the first sample of the stretch that is outside, *out_s, its f in
 * *out_f; false: none (still under at the stretch's end). */
static bool leave_under(const relief_shell_search *q, const relief_shell_stretch *st, float *out_s,
                        float *out_f) {
    int n = stretch_steps(q->linear_steps, st->dd);
    for (int first = 1; first <= n; first += RELIEF_LANES) {
        int count = n - first + 1 < RELIEF_LANES ? n - first + 1 : RELIEF_LANES;
        v8f sv, fv, x, y, d;
        stretch_samples8(st, first, n, &sv, &x, &y, &d);
        int out = ~q->inside8(q->user, &x, &y, &d, &fv) & ((1 << count) - 1);
        if (!out) continue;
        int j = __builtin_ctz((unsigned)out);
        *out_s = sv[j], *out_f = fv[j];
        return true;
    }
    return false;
}

/* The view ray's first hit on a stretch (*out_s): relief mapping's linear search (Policarpo &
 * Oliveira 2006 §2.1, App. A; §3.1's Algorithm 1 for multilayer maps) with the stretch's share
 * of the steps, the binary search and a secant step in the bracket (relief_common.h), or the
 * technique's exact trace. *f_start: the inside test's f at the stretch's start, NAN when not
 * known (the first stretch: the start is tested too); the end's on a miss, the next stretch's
 * start. at_floor: the stretch ends on a solid floor, a hit there whatever rounding says.
 * *under: 1 the ray entered a height field's open border (a fin) and may start under its
 * surface, 2 it is under it -- the reference's surface is a sheet with no wall down the
 * shell's cut (docs/design.md, "Measuring against the truth"), so a ray under it meets nothing
 * until it comes out above it (into a groove, a tube's inside) and is searched on from there
 * -- 0 neither. */
static bool search_stretch(const relief_shell_search *q, const relief_shell_stretch *st,
                           bool at_floor, float *f_start, int *under, float *out_s) {
    float from = 0.0f, f_lo = *f_start, f_hi = 0.0f, f;
    if (*under == 1) {
        *under = q->inside(q->user, st->x0, st->y0, st->d0, &f_lo) ? 2 : 0;
        if (!*under) *f_start = f_lo;
    }
    if (*under == 2) {
        if (!leave_under(q, st, &from, &f_lo)) return false;
        *under = 0;
        *f_start = f_lo;
    }
    /* the stretch from `from` on (all of it unless the ray came out from under the surface) */
    relief_shell_stretch rest = {st->x0 + st->xd * from, st->y0 + st->yd * from,
                                 st->d0 + st->dd * from, st->xd * (1.0f - from),
                                 st->yd * (1.0f - from), st->dd * (1.0f - from)};
    if (from > 0.0f) st = &rest;
    if (q->trace) {
        if (q->trace(q->user, st, 0.0f, out_s)) {
            *out_s = from + (1.0f - from) * *out_s;
            return true;
        }
        *out_s = 1.0f;
        return at_floor;
    }
    f_lo = *f_start;
    if (isnan(f_lo) && q->inside(q->user, st->x0, st->y0, st->d0, &f_lo)) {
        *out_s = from;
        return true;
    }
    int n = stretch_steps(q->linear_steps, st->dd);
    float lo = 0.0f, hi = -1.0f;
    for (int first = 1; first <= n && hi < 0.0f; first += RELIEF_LANES) {
        int count = n - first + 1 < RELIEF_LANES ? n - first + 1 : RELIEF_LANES;
        v8f sv, fv, x, y, d;
        stretch_samples8(st, first, n, &sv, &x, &y, &d);
        int in = q->inside8(q->user, &x, &y, &d, &fv);
        if (at_floor && first + count - 1 == n) in |= 1 << (count - 1);
        in &= (1 << count) - 1;
        if (!in) {
            lo = sv[count - 1], f_lo = fv[count - 1];
            continue;
        }
        int j = __builtin_ctz((unsigned)in);
        if (j > 0) lo = sv[j - 1], f_lo = fv[j - 1];
        hi = sv[j], f_hi = fv[j] > 0.0f ? fv[j] : 0.0f;
    }
    if (hi < 0.0f) {
        *f_start = f_lo;
        return false;
    }
    for (int k = 0; k < q->binary_steps; k++) {
        float s = 0.5f * (lo + hi);
        if (q->inside(q->user, st->x0 + st->xd * s, st->y0 + st->yd * s, st->d0 + st->dd * s, &f))
            hi = s, f_hi = f;
        else
            lo = s, f_lo = f;
    }
    /* secant between the bracket's ends, f_lo < 0 <= f_hi (exact where the surface is planar) */
    float span = f_hi - f_lo;
    float w = span > 1e-12f ? -f_lo / span : 1.0f;
    w = fminf(fmaxf(w, 0.0f), 1.0f);
    *out_s = lo + (hi - lo) * w;
    if (from > 0.0f) *out_s = from + (1.0f - from) * *out_s;
    return true;
}

/* Does a stretch of a light ray pass through the mesostructure (a sample more than the bias
 * inside: relief's second linear search with its share of the steps, or the exact trace)? The
 * stretch's start (the hit, or the last stretch's end) is not sampled, nor are samples nearer
 * the hit than `skip` (world units; `from`: the stretch's start's distance from the hit,
 * `length`: its length). Off the shell the first sample lies 1 / shadow_steps of the way from
 * the hit to the top; the search's hit lies on the inside end of its bracket, up to a
 * bracket's width inside, and samples much nearer than that found the hit's own surface more
 * than the bias inside (dark specks over weave-torus where a hit lay near a fin). */
static bool shadow_stretch(const relief_shell_search *q, const relief_shell_stretch *st, float from,
                           float length, float skip) {
    float s;
    if (q->trace) return q->trace(q->user, st, q->shadow_bias, &s);
    int n = stretch_steps(q->shadow_steps, st->dd);
    for (int first = 1; first <= n; first += RELIEF_LANES) {
        int count = n - first + 1 < RELIEF_LANES ? n - first + 1 : RELIEF_LANES, near = 0;
        int lanes = (1 << count) - 1;
        v8f sv, fv, x, y, d;
        stretch_samples8(st, first, n, &sv, &x, &y, &d);
        for (int j = 0; j < RELIEF_LANES; j++) near |= (from + sv[j] * length < skip) << j;
        if ((near & lanes) == lanes) continue;
        q->inside8(q->user, &x, &y, &d, &fv);
        if (v8_mask_bits(fv > q->shadow_bias) & ~near & lanes) return true;
    }
    return false;
}

/* ---- The walk ----------------------------------------------------------------------------- */

typedef struct shell_hit {
    meso_vec3 position, uvw;
    size_t prism;
    bool upward; /* the view ray's w decreasing there */
} shell_hit;

/* The view ray of a fragment of boundary face `face` walked front to back through the prisms
 * it crosses (gdm_walk.h) to its first hit; false when it leaves the shell first (where it
 * enters again farther on, that boundary face's own fragment walks on). */
static bool walk_view(const relief_shell *sh, const relief_shell_search *q, const meso_frame *frame,
                      const meso_fragment *f, shell_hit *out) {
    const meso_prism_layer *layer = sh->layer;
    size_t face = sh->drawn_face[f->triangle];
    int slot;
    size_t prism = meso_prism_layer_face_prism(layer, face, &slot);
    /* a face turned away (a both_faces technique draws it): the ray leaves the shell there */
    meso_vec3 outward = layer->planes[prism * MESO_PRISM_NUM_FACES + (size_t)slot].normal;
    if (meso_vec3_dot(outward, meso_vec3_sub(f->position, frame->eye)) > 0.0f) return false;
    gdm_walk_crossing c;
    meso_vec3 t_in, view;
    if (!gdm_walk_enter(layer, NULL, face, f->b0, f->b1, f->b2, f->position, frame->eye, true, &c,
                        &t_in, &view))
        return false;
    float f_start = NAN;
    /* a height field's ray entering an open border may run under the surface (search_stretch;
     * a solid's cut is capped, as the reference's) */
    int under = q->floor_solid && c.entry_slot >= MESO_PRISM_FIN ? 1 : 0;
    for (int n = 0; n < RELIEF_SHELL_MAX_PRISMS; n++) {
        size_t exit_face = meso_prism_layer_face(layer, c.prism, c.exit_slot);
        meso_vec3 t_out = meso_prism_layer_face_uvw(layer, exit_face, c.p_out);
        /* a stretch of no length holds nothing (gdm's walk: a fold's planes crossed at the
         * entry point) -- but a floor there is the floor */
        if (c.t_exit > 0.0f || c.exit_slot == MESO_PRISM_BOTTOM) {
            relief_shell_stretch st = stretch_between(q, t_in, t_out);
            float s;
            if (search_stretch(q, &st, c.exit_slot == MESO_PRISM_BOTTOM && q->floor_solid, &f_start,
                               &under, &s)) {
                out->uvw = meso_vec3_add(t_in, meso_vec3_scale(meso_vec3_sub(t_out, t_in), s));
                /* on the ray itself (its depth and the light rays' start), the (u, v, w) path's
                 * point at s mapped there */
                out->position = meso_vec3_madd(c.p_in, view, s * c.t_exit);
                out->prism = c.prism;
                out->upward = st.dd < 0.0f;
                return true;
            }
        }
        if (!gdm_walk_next(layer, sh->fin_twin, &c)) return false;
        /* the exit's (u, v, w) is the neighbour's entry unless a UV seam lies between */
        if (!sh->same_uvw[exit_face]) {
            t_out = meso_prism_layer_face_uvw(layer, c.entry_face, c.p_in);
            f_start = NAN;
        }
        t_in = t_out;
        if (!gdm_walk_exit(layer, &c, view)) return false;
    }
    return false;
}

/* The light ray from a hit toward unit direction l walked through the shell: blocked where a
 * stretch passes through the mesostructure, or where it leaves through the bottom into a
 * height field's body, a solid's filled floor (as gdm's walk takes it) or a closed mesh's
 * inside (light reaches it only through the shell's other side, which the walk does not
 * follow: taken as blocked, relief_layers' rule for a closed mesh's far wall); lit where it
 * leaves through a top or an open border's fin. `skip`: see shadow_stretch. */
static bool light_blocked(const relief_shell *sh, const relief_shell_search *q, const shell_hit *h,
                          meso_vec3 l, float skip) {
    const meso_prism_layer *layer = sh->layer;
    gdm_walk_crossing c = {.prism = h->prism,
                           .entry_face = meso_prism_layer_face(layer, h->prism, MESO_PRISM_TOP),
                           .entry_slot = -1,
                           .p_in = h->position};
    meso_vec3 t_in = h->uvw;
    float from = 0.0f;
    if (!gdm_walk_exit(layer, &c, l)) return false;
    for (int n = 0; n < RELIEF_SHELL_MAX_PRISMS; n++) {
        size_t exit_face = meso_prism_layer_face(layer, c.prism, c.exit_slot);
        meso_vec3 t_out = meso_prism_layer_face_uvw(layer, exit_face, c.p_out);
        if (c.t_exit > 0.0f) {
            relief_shell_stretch st = stretch_between(q, t_in, t_out);
            if (shadow_stretch(q, &st, from, c.t_exit, skip)) return true;
            from += c.t_exit;
        }
        int exit_slot = c.exit_slot;
        if (!gdm_walk_next(layer, sh->fin_twin, &c)) {
            if (exit_slot != MESO_PRISM_BOTTOM) return false;
            if (q->floor_solid || sh->closed) return true;
            float f, x = t_out.x * (float)q->width - 0.5f;
            float y = (1.0f - t_out.y) * (float)q->height - 0.5f;
            return q->inside(q->user, x, y, 1.0f - 1e-3f, &f);
        }
        t_in = sh->same_uvw[exit_face] ? t_out
                                       : meso_prism_layer_face_uvw(layer, c.entry_face, c.p_in);
        if (!gdm_walk_exit(layer, &c, l)) return false;
    }
    return false;
}

/* The base frame at (u, v) of a prism (relief_shell_frame, gdm_walk_base_frame) with its dual
 * basis. */
static relief_shell_frame frame_at(const relief_shell *sh, const meso_prism *prism, float u,
                                   float v) {
    relief_shell_frame f;
    f.depth = sh->depth;
    gdm_walk_base_frame(sh->mesh, prism, (meso_vec2){u, v}, &f.normal, &f.tangent, &f.bitangent);
    meso_vec3 bn = meso_vec3_cross(f.bitangent, f.normal),
              nt = meso_vec3_cross(f.normal, f.tangent);
    meso_vec3 tb = meso_vec3_cross(f.tangent, f.bitangent);
    float det = meso_vec3_dot(f.tangent, bn);
    float inv = det > 1e-20f || det < -1e-20f ? 1.0f / det : 0.0f;
    f.bn = meso_vec3_scale(bn, inv), f.nt = meso_vec3_scale(nt, inv),
    f.tb = meso_vec3_scale(tb, inv);
    return f;
}

meso_vec3 relief_shell_heights_normal(const relief_heights *m, float x, float y,
                                      const relief_shell_frame *f) {
    /* relief_gradient8's samples and arithmetic, one lane */
    float gu = (relief_shell_sample(m, x + 1.0f, y) - relief_shell_sample(m, x - 1.0f, y)) *
               (0.5f * (float)m->width);
    float gv = (relief_shell_sample(m, x, y - 1.0f) - relief_shell_sample(m, x, y + 1.0f)) *
               (0.5f * (float)m->height);
    if (gu == 0.0f && gv == 0.0f) return f->normal; /* as relief_normal8 */
    return meso_displaced_normal(f->normal, f->tangent, f->bitangent, f->depth,
                                 (meso_vec2){gu, gv});
}

/* The fragment's ray walked and its hit shaded up to the shading model's inputs: the
 * fragment's position, normal, frame, uv and out_depth, and the lights' visibility. false: a
 * miss. */
static bool shade_fragment(const relief_shell *sh, const relief_shell_search *q,
                           const meso_frame *frame, meso_fragment *f, float *visibility) {
    shell_hit h;
    if (!walk_view(sh, q, frame, f, &h)) return false;
    const meso_prism *prism = &sh->layer->prisms[h.prism];
    relief_shell_frame base = frame_at(sh, prism, h.uvw.x, h.uvw.y);
    float x = h.uvw.x * (float)q->width - 0.5f, y = (1.0f - h.uvw.y) * (float)q->height - 0.5f;
    meso_vec3 normal = q->normal(q->user, x, y, h.uvw.z, h.upward, &base);
    float depth = meso_vec3_dot(meso_vec3_sub(h.position, frame->eye), frame->forward);
    f->out_depth = depth > f->depth ? depth : f->depth; /* never nearer than the entry */
    f->position = h.position;
    f->normal = normal;
    f->tangent = base.tangent;
    f->bitangent = base.bitangent;
    f->uv = (meso_vec2){h.uvw.x, h.uvw.y};
    const meso_scene *scene = frame->scene;
    for (int li = 0; li < scene->num_lights; li++) {
        visibility[li] = 1.0f;
        if (!q->shadows) continue;
        meso_vec3 l = meso_light_direction(&scene->lights[li], h.position);
        if (meso_vec3_dot(l, normal) <= 0.0f) continue; /* unlit anyway */
        /* off the shell's first sample: 1 / shadow_steps of the way up to the top */
        float up = fmaxf(meso_vec3_dot(l, base.normal), 0.05f);
        float skip = h.uvw.z * sh->depth / (up * (float)q->shadow_steps);
        if (light_blocked(sh, q, &h, l, skip)) visibility[li] = 0.0f;
    }
    return true;
}

/* Fragments of an array (inputs and outputs), RELIEF_SHELL_CHUNK at a time: the hits shaded
 * together, misses discarded. */
static void shade_array(const relief_shell *sh, const relief_shell_search *q,
                        const meso_frame *frame, const meso_object *object,
                        meso_fragment *fragments, size_t count) {
    int num_lights = frame->scene->num_lights;
    float visibility[RELIEF_SHELL_CHUNK * MESO_SCENE_MAX_LIGHTS];
    meso_fragment hits[RELIEF_SHELL_CHUNK];
    size_t lanes[RELIEF_SHELL_CHUNK];
    for (size_t start = 0; start < count; start += RELIEF_SHELL_CHUNK) {
        size_t end = start + RELIEF_SHELL_CHUNK < count ? start + RELIEF_SHELL_CHUNK : count, n = 0;
        for (size_t i = start; i < end; i++) {
            hits[n] = fragments[i];
            if (shade_fragment(sh, q, frame, &hits[n], visibility + n * (size_t)num_lights))
                lanes[n++] = i;
            else
                fragments[i].discard = true;
        }
        if (!n) continue;
        meso_shade_fragments(frame, object, hits, n, visibility);
        for (size_t k = 0; k < n; k++) {
            meso_fragment *f = &fragments[lanes[k]];
            f->color = hits[k].color;
            f->out_depth = hits[k].out_depth;
        }
    }
}

void relief_shell_shade(const relief_shell *shell, const relief_shell_search *search,
                        const meso_frame *frame, const meso_object *object,
                        meso_fragment *fragments, size_t count) {
    shade_array(shell, search, frame, object, fragments, count);
}

void relief_shell_shade_block(const relief_shell *shell, const relief_shell_search *search,
                              const meso_frame *frame, const meso_object *object,
                              meso_fragment_block *block) {
    meso_fragment fragments[RELIEF_SHELL_CHUNK];
    for (size_t start = 0; start < block->count; start += RELIEF_SHELL_CHUNK) {
        size_t n =
            block->count - start < RELIEF_SHELL_CHUNK ? block->count - start : RELIEF_SHELL_CHUNK;
        for (size_t k = 0; k < n; k++) meso_fragment_block_get(block, start + k, &fragments[k]);
        shade_array(shell, search, frame, object, fragments, n);
        for (size_t k = 0; k < n; k++) {
            size_t i = start + k;
            block->discard[i] = fragments[k].discard;
            if (fragments[k].discard) continue;
            block->r[i] = fragments[k].color.x;
            block->g[i] = fragments[k].color.y;
            block->b[i] = fragments[k].color.z;
            block->out_depth[i] = fragments[k].out_depth;
        }
    }
}
