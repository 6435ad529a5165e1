/* Generalized displacement maps (Wang et al. 2004): the bake (§3.1), SVD compression (§4.1),
 * lookups and bake files. Conventions in include/meso/bake_gdm.h; docs/techniques/gdm.md
 * ("Bake and compression") has the measurements behind the choices below.
 *
 * Rays are traced with Embree against a watertight triangle surface of the solid (the dual
 * contouring of meso_isosurface_bake for solids, the texel-centre grid for height fields), inside
 * the tile's column 0 <= u, v <= 1 and wrapped across its sides (GDM §3.1: the volume surrounded by
 * identical tiles). Whether a voxel is inside is decided on the source itself (the solid's
 * distance, w >= 1 - h), and a ray that starts outside it takes the first hit where it enters
 * the surface: a surface that bulges a little past the source cannot turn a free voxel's ray
 * into a hit at distance 0. */
#include <embree3/rtcore.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake_internal.h"
#include "meso/bake_cache.h"
#include "meso/bake_isosurface.h"
#include "meso/runtime.h"

#define TWO_PI (2.0 * MESO_PI_D)

/* The solid's surface is extracted this many times finer than the voxels in every direction,
 * and at least SURFACE_MIN_CELLS_UV x SURFACE_MIN_CELLS_UV x SURFACE_MIN_CELLS_W cells a tile:
 * the extraction's error is a fraction of one of its cells (docs/techniques/gdm.md), and a
 * coarse table should not have a coarse surface too. */
#define SURFACE_REFINE 2
#define SURFACE_MIN_CELLS_UV 128
#define SURFACE_MIN_CELLS_W 64
/* A height field finer than this is resampled to this many texels a side for its surface. */
#define SURFACE_MAX_TEXELS 1024
/* The tile and its 8 neighbours: every triangle of a copy that reaches into the column. */
#define COPIES 9
/* Voxels classified (inside flag, normal) by one job. */
#define VOXELS_PER_JOB 4096

struct meso_gdm {
    meso_gdm_desc desc; /* heightfield and solid NULL */
    uint64_t source_hash;
    bool from_heightfield;
    int num_sv;             /* singular values kept: min(rows, columns) */
    float *weights;         /* [rows][eigenmaps] */
    uint16_t *weights_half; /* the values of `weights` as halves unless float_weights */
    float *eigen;           /* [eigenmaps][columns] */
    float *singular;        /* [num_sv] */
    float *raw;             /* [rows][columns] or NULL */
    float *normals;         /* [layers][height][width][3] */
    meso_gdm_compression compression;
};

meso_gdm_desc meso_gdm_desc_defaults(const meso_gdm_desc *desc) {
    meso_gdm_desc d = desc ? *desc : (meso_gdm_desc){0};
    if (d.width == 0) d.width = 64;
    if (d.height == 0) d.height = d.width;
    if (d.layers == 0) d.layers = 32;
    if (d.num_theta == 0) d.num_theta = 16;
    if (d.num_phi == 0) d.num_phi = 32;
    if (d.eigenmaps == 0) d.eigenmaps = 7;
    return d;
}

static size_t rows_of(const meso_gdm_desc *d) {
    return (size_t)d->width * (size_t)d->height * (size_t)d->num_phi;
}
static int columns_of(const meso_gdm_desc *d) { return d->layers * d->num_theta; }
static size_t voxels_of(const meso_gdm_desc *d) {
    return (size_t)d->width * (size_t)d->height * (size_t)d->layers;
}

/* Validate a filled-in desc (sources aside); `name` starts the messages. */
static meso_result check_desc(meso_context *ctx, const char *name, const meso_gdm_desc *d) {
#define CHECK(cond, code, ...)                                                                     \
    if (!(cond)) return meso_log_error(ctx, code, __VA_ARGS__)
    CHECK(d->width >= 1 && d->width <= MESO_GDM_MAX_SIDE, MESO_ERROR_LIMIT,
          "%s: width: %d is outside 1-%d", name, d->width, MESO_GDM_MAX_SIDE);
    CHECK(d->height >= 1 && d->height <= MESO_GDM_MAX_SIDE, MESO_ERROR_LIMIT,
          "%s: height: %d is outside 1-%d", name, d->height, MESO_GDM_MAX_SIDE);
    CHECK(d->layers >= 2 && d->layers <= MESO_GDM_MAX_LAYERS, MESO_ERROR_LIMIT,
          "%s: layers: %d is outside 2-%d", name, d->layers, MESO_GDM_MAX_LAYERS);
    CHECK(d->num_theta >= 2 && d->num_theta <= MESO_GDM_MAX_THETA, MESO_ERROR_LIMIT,
          "%s: num_theta: %d is outside 2-%d", name, d->num_theta, MESO_GDM_MAX_THETA);
    CHECK(d->num_phi >= 1 && d->num_phi <= MESO_GDM_MAX_PHI, MESO_ERROR_LIMIT,
          "%s: num_phi: %d is outside 1-%d", name, d->num_phi, MESO_GDM_MAX_PHI);
    size_t rows = rows_of(d);
    int columns = columns_of(d);
    int rank = (size_t)columns < rows ? columns : (int)rows;
    int max_eigen = rank < MESO_GDM_MAX_EIGEN ? rank : MESO_GDM_MAX_EIGEN;
    CHECK(d->eigenmaps >= 1 && d->eigenmaps <= max_eigen, MESO_ERROR_INVALID_ARGUMENT,
          "%s: eigenmaps: %d is outside 1-%d", name, d->eigenmaps, max_eigen);
    CHECK((uint64_t)rows * (uint64_t)columns <= MESO_GDM_MAX_TABLE_ENTRIES, MESO_ERROR_LIMIT,
          "%s: the table of %zu x %d values exceeds the limit %llu", name, rows, columns,
          (unsigned long long)MESO_GDM_MAX_TABLE_ENTRIES);
    CHECK(!d->keep_raw || (uint64_t)rows * (uint64_t)columns <= MESO_GDM_MAX_RAW_FLOATS,
          MESO_ERROR_LIMIT, "%s: keeping the raw table of %zu x %d values exceeds the limit %llu",
          name, rows, columns, (unsigned long long)MESO_GDM_MAX_RAW_FLOATS);
#undef CHECK
    return MESO_OK;
}

/* The hash of the source: the height field's or the solid's, tagged so that the two kinds of
 * source never share a key. */
static uint64_t source_hash_of(const meso_gdm_desc *d) {
    uint64_t tag = d->heightfield ? 1u : d->solid ? 2u : 0u;
    uint64_t source = d->heightfield ? d->heightfield->hash
                      : d->solid     ? meso_solid_hash(d->solid)
                                     : 0u;
    return meso_hash64(&source, sizeof(source), meso_hash64(&tag, sizeof(tag), MESO_HASH_SEED));
}

uint64_t meso_gdm_cache_key(const meso_gdm_desc *desc) {
    meso_gdm_desc d = meso_gdm_desc_defaults(desc);
    uint64_t h = source_hash_of(&d);
    int32_t ints[] = {d.width,
                      d.height,
                      d.layers,
                      d.num_theta,
                      d.num_phi,
                      d.eigenmaps,
                      d.keep_raw ? 1 : 0,
                      d.float_weights ? 1 : 0,
                      SURFACE_REFINE,
                      SURFACE_MIN_CELLS_UV,
                      SURFACE_MIN_CELLS_W,
                      SURFACE_MAX_TEXELS,
                      (int32_t)MESO_GDM_KIND_VERSION};
    float ray_length = MESO_GDM_MAX_RAY_LENGTH;
    h = meso_hash64(ints, sizeof(ints), h);
    return meso_hash64(&ray_length, sizeof(ray_length), h);
}

/* Voxel positions and sampled directions (bake_gdm.h, "Conventions"). */
static meso_vec3 voxel_position(const meso_gdm_desc *d, int i, int j, int l) {
    return (meso_vec3){((float)i + 0.5f) / (float)d->width,
                       1.0f - ((float)j + 0.5f) / (float)d->height,
                       (float)l / (float)(d->layers - 1)};
}
static double theta_of(const meso_gdm_desc *d, int t) {
    return ((double)t + 0.5) * MESO_PI_D / (double)d->num_theta;
}
static double phi_of(const meso_gdm_desc *d, int p) { return (double)p * TWO_PI / d->num_phi; }
static meso_vec3 direction_of(double theta, double phi) {
    return (meso_vec3){(float)(sin(theta) * cos(phi)), (float)(sin(theta) * sin(phi)),
                       (float)-cos(theta)};
}

/* ---- The surface the rays are traced against ---------------------------------------------- */

/* Triangles in (u, v, w), each facing out of the solid: (p1 - p0) x (p2 - p0) points outward. */
typedef struct gdm_surface {
    RTCDevice device;
    RTCScene scene;
    size_t num_triangles;
} gdm_surface;

static void surface_release(gdm_surface *s) {
    if (s->scene) rtcReleaseScene(s->scene);
    if (s->device) rtcReleaseDevice(s->device);
    *s = (gdm_surface){0};
}

/* A new triangle geometry with room for num_vertices and num_triangles; the caller fills its
 * buffers, then attaches it with finish_part. */
static RTCGeometry new_part(gdm_surface *s, size_t num_vertices, size_t num_triangles,
                            float **out_vertices, uint32_t **out_indices) {
    RTCGeometry g = rtcNewGeometry(s->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    if (!g) return NULL;
    *out_vertices = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                            3 * sizeof(float), num_vertices);
    *out_indices = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                           3 * sizeof(uint32_t), num_triangles);
    if (!*out_vertices || !*out_indices) {
        rtcReleaseGeometry(g);
        return NULL;
    }
    return g;
}

/* Commit a filled part and attach it to the scene as geometry `id`. */
static void finish_part(gdm_surface *s, RTCGeometry g, unsigned id, size_t num_triangles) {
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(s->scene, g, id);
    rtcReleaseGeometry(g); /* the scene holds it */
    s->num_triangles += num_triangles;
}

/* The isosurface's copies shifted by (dx, dy) in {-1, 0, 1}^2, each keeping only the
 * triangles that reach into the column [0, 1]^2 (with their vertices renumbered): the rays
 * are traced inside the column only, and the copies make its surface whole at its sides. */
static bool add_isosurface(gdm_surface *s, const meso_isosurface *iso) {
    const float margin = 1e-4f;
    uint32_t *remap = malloc(sizeof(uint32_t) * (iso->num_vertices ? iso->num_vertices : 1));
    uint8_t *keep = malloc(iso->num_triangles ? iso->num_triangles : 1);
    bool ok = remap && keep;
    for (unsigned copy = 0; copy < COPIES && ok; copy++) {
        float dx = (float)(copy % 3) - 1.0f, dy = (float)(copy / 3) - 1.0f;
        size_t nt = 0, nv = 0;
        memset(remap, 0xff, sizeof(uint32_t) * iso->num_vertices);
        for (size_t t = 0; t < iso->num_triangles; t++) {
            const uint32_t *tri = iso->indices + 3 * t;
            float lo_u = INFINITY, hi_u = -INFINITY, lo_v = INFINITY, hi_v = -INFINITY;
            for (int c = 0; c < 3; c++) {
                meso_vec3 p = iso->positions[tri[c]];
                lo_u = fminf(lo_u, p.x + dx), hi_u = fmaxf(hi_u, p.x + dx);
                lo_v = fminf(lo_v, p.y + dy), hi_v = fmaxf(hi_v, p.y + dy);
            }
            keep[t] =
                !(hi_u < -margin || lo_u > 1.0f + margin || hi_v < -margin || lo_v > 1.0f + margin);
            if (!keep[t]) continue;
            nt++;
            for (int c = 0; c < 3; c++)
                if (remap[tri[c]] == UINT32_MAX) remap[tri[c]] = (uint32_t)nv++;
        }
        if (nt == 0) continue;
        float *vertices = NULL;
        uint32_t *indices = NULL;
        RTCGeometry g = new_part(s, nv, nt, &vertices, &indices);
        if (!g) {
            ok = false;
            break;
        }
        for (size_t v = 0; v < iso->num_vertices; v++) {
            if (remap[v] == UINT32_MAX) continue;
            float *out = vertices + 3 * (size_t)remap[v];
            out[0] = iso->positions[v].x + dx;
            out[1] = iso->positions[v].y + dy;
            out[2] = iso->positions[v].z;
        }
        size_t k = 0;
        for (size_t t = 0; t < iso->num_triangles; t++)
            if (keep[t]) {
                for (int c = 0; c < 3; c++)
                    indices[3 * k + (size_t)c] = remap[iso->indices[3 * t + (size_t)c]];
                k++;
            }
        finish_part(s, g, copy, nt);
    }
    free(keep);
    free(remap);
    return ok;
}

/* The texels a side of a height field's surface grid. */
static int surface_texels(int texels) {
    return texels < SURFACE_MAX_TEXELS ? texels : SURFACE_MAX_TEXELS;
}
static uint64_t heightfield_triangles(const meso_heightfield *hf) {
    return 2u * (uint64_t)(surface_texels(hf->width) + 1) *
           (uint64_t)(surface_texels(hf->height) + 1);
}

/* The height field's surface w = 1 - h through its texel centres, from the texel left of
 * u = 0 to the one right of u = 1 (and the same in v), so it covers the column. A field
 * finer than SURFACE_MAX_TEXELS is sampled bilinearly on a coarser grid. */
static bool add_heightfield(gdm_surface *s, const meso_heightfield *hf) {
    int gw = surface_texels(hf->width), gh = surface_texels(hf->height);
    bool native = gw == hf->width && gh == hf->height;
    size_t cw = (size_t)gw + 2, ch = (size_t)gh + 2; /* grid points: i = -1 .. gw */
    float *vertices = NULL;
    uint32_t *indices = NULL;
    size_t num_triangles = 2 * (cw - 1) * (ch - 1);
    RTCGeometry g = new_part(s, cw * ch, num_triangles, &vertices, &indices);
    if (!g) return false;
    for (size_t b = 0; b < ch; b++)
        for (size_t a = 0; a < cw; a++) {
            int i = (int)a - 1, j = (int)b - 1;
            float u = ((float)i + 0.5f) / (float)gw, v = 1.0f - ((float)j + 0.5f) / (float)gh;
            float h = native ? meso_heightfield_texel(hf, i, j) : meso_heightfield_sample(hf, u, v);
            float *out = vertices + 3 * (b * cw + a);
            out[0] = u, out[1] = v, out[2] = 1.0f - h;
        }
    /* (i, j), (i+1, j), (i, j+1): u grows along i, v falls along j, so (p1 - p0) x (p2 - p0)
     * has a negative w: it points up, out of the solid below the surface. */
    size_t k = 0;
    for (size_t b = 0; b + 1 < ch; b++)
        for (size_t a = 0; a + 1 < cw; a++) {
            uint32_t p00 = (uint32_t)(b * cw + a), p10 = p00 + 1, p01 = (uint32_t)(p00 + cw),
                     p11 = p01 + 1;
            uint32_t *t = indices + 6 * k++;
            t[0] = p00, t[1] = p10, t[2] = p01;
            t[3] = p10, t[4] = p11, t[5] = p01;
        }
    finish_part(s, g, 0, num_triangles);
    return true;
}

static int at_least(int value, int minimum) { return value > minimum ? value : minimum; }

/* The cells of the solid's surface grid. */
static meso_isosurface_desc surface_cells_of(const meso_gdm_desc *d) {
    return (meso_isosurface_desc){
        .resolution_u = at_least(SURFACE_REFINE * d->width, SURFACE_MIN_CELLS_UV),
        .resolution_v = at_least(SURFACE_REFINE * d->height, SURFACE_MIN_CELLS_UV),
        .resolution_w = at_least(SURFACE_REFINE * (d->layers - 1), SURFACE_MIN_CELLS_W)};
}

/* Bytes of the traced surface per triangle: Embree's BVH and the vertex and index buffers,
 * measured (peak resident size: 130 bytes a triangle for the weave's 172 k). */
#define SURFACE_BYTES_PER_TRIANGLE 130u

/* The source's surface and Embree's BVH over it, built on one thread: the same tree, hence the
 * same hits, for any number of the context's threads (rays are traced from the context's own
 * pool). `needed`: the bake's other memory, for the budget check once the triangles are
 * counted. */
static meso_result surface_build(meso_context *ctx, const meso_gdm_desc *d, uint64_t needed,
                                 gdm_surface *s) {
    *s = (gdm_surface){0};
    s->device = rtcNewDevice("threads=1");
    if (!s->device) return meso_log_error(ctx, MESO_ERROR_INTERNAL, "gdm: Embree could not start");
    s->scene = rtcNewScene(s->device);
    rtcSetSceneFlags(s->scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(s->scene, RTC_BUILD_QUALITY_MEDIUM);
    bool ok;
    if (d->solid) {
        meso_isosurface_desc iso_desc = surface_cells_of(d);
        meso_isosurface *iso = NULL;
        meso_result result = meso_isosurface_bake(ctx, d->solid, &iso_desc, &iso);
        if (result != MESO_OK) {
            surface_release(s);
            return result;
        }
        /* the copies add the triangles along the tile's sides: a few per cent */
        result = meso_memory_check(
            ctx, "gdm bake", needed + iso->num_triangles * 9u / 8u * SURFACE_BYTES_PER_TRIANGLE);
        ok = result == MESO_OK && add_isosurface(s, iso);
        meso_isosurface_destroy(iso);
        if (result != MESO_OK) {
            surface_release(s);
            return result;
        }
    } else {
        ok = add_heightfield(s, d->heightfield);
    }
    if (ok) rtcCommitScene(s->scene);
    enum RTCError error = rtcGetDeviceError(s->device);
    if (!ok || error != RTC_ERROR_NONE) {
        surface_release(s);
        return meso_log_error(
            ctx,
            ok && error != RTC_ERROR_OUT_OF_MEMORY ? MESO_ERROR_INTERNAL : MESO_ERROR_OUT_OF_MEMORY,
            "gdm: the ray-tracing structure could not be built (Embree error %d)", (int)error);
    }
    return MESO_OK;
}

/* ---- The bake: one ray per voxel and direction (§3.1) ------------------------------------- */

typedef struct bake_job {
    meso_gdm_desc desc;
    const gdm_surface *surface;
    const uint8_t *inside; /* [layers][height][width]: the voxel lies in the solid */
    meso_vec3 *directions; /* [num_phi][num_theta] */
    float *normals;        /* [layers][height][width][3] */
} bake_job;

/* The source's own inside test and outward normal. */
static bool source_inside(const meso_gdm_desc *d, meso_vec3 p) {
    if (d->solid) return meso_solid_distance(d->solid, p) <= 0.0f;
    return p.z >= 1.0f - meso_heightfield_sample(d->heightfield, p.x, p.y);
}
static meso_vec3 source_normal(const meso_gdm_desc *d, meso_vec3 p) {
    meso_vec3 n;
    if (d->solid) {
        n = meso_solid_gradient(d->solid, p);
    } else { /* the gradient of 1 - h(u, v) - w, positive above the surface */
        meso_vec2 g = meso_heightfield_gradient(d->heightfield, p.x, p.y);
        n = (meso_vec3){-g.x, -g.y, -1.0f};
    }
    float length = meso_vec3_length(n);
    if (!(length > 1e-12f) || !isfinite(length)) return (meso_vec3){0.0f, 0.0f, -1.0f};
    return meso_vec3_scale(n, 1.0f / length);
}

static void classify_voxels(void *user, size_t job_index, int thread_index) {
    (void)thread_index;
    bake_job *job = user;
    const meso_gdm_desc *d = &job->desc;
    size_t first = job_index * VOXELS_PER_JOB, end = first + VOXELS_PER_JOB;
    if (end > voxels_of(d)) end = voxels_of(d);
    uint8_t *inside = (uint8_t *)job->inside;
    for (size_t voxel = first; voxel < end; voxel++) {
        int i = (int)(voxel % (size_t)d->width);
        int j = (int)(voxel / (size_t)d->width % (size_t)d->height);
        int l = (int)(voxel / ((size_t)d->width * (size_t)d->height));
        meso_vec3 p = voxel_position(d, i, j, l);
        inside[voxel] = source_inside(d, p);
        meso_vec3 n = source_normal(d, p);
        job->normals[3 * voxel + 0] = n.x;
        job->normals[3 * voxel + 1] = n.y;
        job->normals[3 * voxel + 2] = n.z;
    }
}

/* d from a voxel outside the solid at `origin` (u, v in [0, 1)) along the unit `direction`:
 * the distance to where the ray first enters the surface, the ray wrapped across the column's
 * sides; where it enters none before leaving the slab 0 <= w <= 1, the distance to that face
 * (§4.1's replacement of d_max), at most MESO_GDM_MAX_RAY_LENGTH. */
static float trace(const gdm_surface *s, meso_vec3 origin, meso_vec3 direction) {
    float limit = direction.z < 0.0f   ? -origin.z / direction.z
                  : direction.z > 0.0f ? (1.0f - origin.z) / direction.z
                                       : INFINITY;
    limit = fminf(limit, MESO_GDM_MAX_RAY_LENGTH);
    float travelled = 0.0f;
    meso_vec3 q = origin;
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (;;) {
        /* the segment inside the column, up to its side or the end of the ray */
        int side_axis = -1;
        float side = INFINITY;
        if (direction.x != 0.0f) {
            side = (direction.x > 0.0f ? 1.0f - q.x : -q.x) / direction.x;
            side_axis = 0;
        }
        if (direction.y != 0.0f) {
            float t = (direction.y > 0.0f ? 1.0f - q.y : -q.y) / direction.y;
            if (t < side) side = t, side_axis = 1;
        }
        side = fmaxf(side, 0.0f);
        bool last = side >= limit - travelled;
        float segment = last ? limit - travelled : side;
        float tnear = 0.0f;
        while (tnear <= segment) {
            struct RTCRayHit rh;
            rh.ray.org_x = q.x, rh.ray.org_y = q.y, rh.ray.org_z = q.z;
            rh.ray.dir_x = direction.x, rh.ray.dir_y = direction.y, rh.ray.dir_z = direction.z;
            rh.ray.tnear = tnear, rh.ray.tfar = segment, rh.ray.time = 0.0f;
            rh.ray.mask = UINT32_MAX, rh.ray.id = 0, rh.ray.flags = 0;
            rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
            rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
            rtcIntersect1(s->scene, &context, &rh);
            if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) break;
            /* Embree's Ng is (p1 - p0) x (p2 - p0), the outward side of both surfaces */
            float facing =
                rh.hit.Ng_x * direction.x + rh.hit.Ng_y * direction.y + rh.hit.Ng_z * direction.z;
            if (facing < 0.0f) return fminf(travelled + rh.ray.tfar, limit);
            /* leaving a surface the ray never entered (it bulges past the source here) */
            tnear = rh.ray.tfar + 1e-6f * (1.0f + rh.ray.tfar);
        }
        if (last) return limit;
        travelled += segment;
        q = meso_vec3_madd(q, direction, segment);
        /* across the side into the next tile: the same column, entered from the other side */
        q.x = fminf(fmaxf(q.x, 0.0f), 1.0f);
        q.y = fminf(fmaxf(q.y, 0.0f), 1.0f);
        if (side_axis == 0) q.x = direction.x > 0.0f ? 0.0f : 1.0f;
        if (side_axis == 1) q.y = direction.y > 0.0f ? 0.0f : 1.0f;
    }
}

/* Rows [first, first + count) of A (rows (y, x, phi), columns (z, theta), row-major). The
 * streamed SVD calls this from its workers, twice per row unless the table is held. */
static void fill_rows(void *user, size_t first, size_t count, float *out) {
    const bake_job *job = user;
    const meso_gdm_desc *d = &job->desc;
    int columns = columns_of(d);
    size_t plane = (size_t)d->width * (size_t)d->height;
    for (size_t r = 0; r < count; r++) {
        size_t row = first + r;
        int p = (int)(row % (size_t)d->num_phi);
        size_t column = row / (size_t)d->num_phi; /* j * width + i */
        int i = (int)(column % (size_t)d->width), j = (int)(column / (size_t)d->width);
        const meso_vec3 *directions = job->directions + (size_t)p * (size_t)d->num_theta;
        float *a = out + r * (size_t)columns;
        for (int l = 0; l < d->layers; l++) {
            float *entries = a + (size_t)l * (size_t)d->num_theta;
            if (job->inside[(size_t)l * plane + column]) { /* §3.1: 0 inside the solid */
                for (int t = 0; t < d->num_theta; t++) entries[t] = 0.0f;
                continue;
            }
            meso_vec3 origin = voxel_position(d, i, j, l);
            for (int t = 0; t < d->num_theta; t++)
                entries[t] = trace(job->surface, origin, directions[t]);
        }
    }
}

/* The RMSE of the stored map (weights as kept, k terms) against the held table, over every
 * entry: per-block sums in a fixed order, so the same for any thread count. */
typedef struct stored_error_job {
    const meso_gdm *gdm;
    const float *table;
    double *block_sums;
} stored_error_job;

#define ERROR_ROWS_PER_JOB 256

static void stored_error_block(void *user, size_t job_index, int thread_index) {
    (void)thread_index;
    stored_error_job *job = user;
    const meso_gdm *g = job->gdm;
    const meso_gdm_desc *d = &g->desc;
    size_t rows = rows_of(d), columns = (size_t)columns_of(d);
    size_t first = job_index * ERROR_ROWS_PER_JOB, end = first + ERROR_ROWS_PER_JOB;
    if (end > rows) end = rows;
    int k = d->eigenmaps;
    double sum = 0.0;
    for (size_t row = first; row < end; row++) {
        const float *w = g->weights + row * (size_t)k;
        const float *a = job->table + row * columns;
        for (size_t c = 0; c < columns; c++) {
            float value = 0.0f;
            for (int e = 0; e < k; e++) value += w[e] * g->eigen[(size_t)e * columns + c];
            double diff = (double)value - a[c];
            sum += diff * diff;
        }
    }
    job->block_sums[job_index] = sum;
}

static float stored_rmse(meso_context *ctx, const meso_gdm *gdm, const float *table) {
    size_t rows = rows_of(&gdm->desc), jobs = (rows + ERROR_ROWS_PER_JOB - 1) / ERROR_ROWS_PER_JOB;
    double *sums = calloc(jobs, sizeof(double));
    if (!sums) return -1.0f;
    stored_error_job job = {gdm, table, sums};
    meso_parallel_for(ctx, jobs, stored_error_block, &job);
    double total = 0.0;
    for (size_t b = 0; b < jobs; b++) total += sums[b];
    free(sums);
    return (float)sqrt(total / ((double)rows * (double)columns_of(&gdm->desc)));
}

void meso_gdm_destroy(meso_gdm *gdm) {
    if (!gdm) return;
    free(gdm->weights);
    free(gdm->weights_half);
    free(gdm->eigen);
    free(gdm->singular);
    free(gdm->raw);
    free(gdm->normals);
    free(gdm);
}

/* Sizes and the RMSE of k = 1..16 terms from the singular values (§4.1): with A = U S E^T the
 * squared error of keeping k terms is the sum of the dropped s_i^2. */
static void fill_compression(meso_gdm *gdm) {
    const meso_gdm_desc *d = &gdm->desc;
    size_t rows = rows_of(d);
    int columns = columns_of(d);
    meso_gdm_compression *c = &gdm->compression;
    c->raw_bytes = (uint64_t)rows * (uint64_t)columns * 4u;
    c->compressed_bytes = (uint64_t)rows * (uint64_t)d->eigenmaps * (d->float_weights ? 4u : 2u) +
                          (uint64_t)d->eigenmaps * (uint64_t)columns * 4u;
    c->num_rmse = MESO_GDM_RMSE_COUNT;
    double energy = 0.0;
    for (int i = 0; i < gdm->num_sv; i++) energy += (double)gdm->singular[i] * gdm->singular[i];
    c->rms = (float)sqrt(energy / ((double)rows * (double)columns));
    for (int k = 1; k <= MESO_GDM_RMSE_COUNT; k++) {
        double sum = 0.0;
        for (int i = k; i < gdm->num_sv; i++) sum += (double)gdm->singular[i] * gdm->singular[i];
        c->rmse[k - 1] =
            k >= gdm->num_sv ? 0.0f : (float)sqrt(sum / ((double)rows * (double)columns));
    }
}

static meso_result check_source(meso_context *ctx, const meso_gdm_desc *d) {
    if ((d->heightfield != NULL) == (d->solid != NULL))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "gdm: exactly one of heightfield and solid must be given");
    if (d->heightfield &&
        (!d->heightfield->heights || d->heightfield->width < 1 || d->heightfield->height < 1))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "gdm: heightfield: empty");
    if (d->solid && !meso_solid_is_periodic(d->solid))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "gdm: solid: a model's solid is not a tile (GDM needs tiles that "
                              "repeat in u and v)");
    return MESO_OK;
}

/* The arguments of a bake checked, the desc with its defaults into out_desc. */
static meso_result begin_bake(meso_context *ctx, const meso_gdm_desc *desc, meso_gdm **out_gdm,
                              meso_gdm_desc *out_desc) {
    if (out_gdm) *out_gdm = NULL;
    if (!out_gdm || !desc)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "gdm: NULL desc or out_gdm");
    *out_desc = meso_gdm_desc_defaults(desc);
    meso_result result = check_source(ctx, out_desc);
    return result == MESO_OK ? check_desc(ctx, "gdm", out_desc) : result;
}

meso_result meso_gdm_bake(meso_context *ctx, const meso_gdm_desc *desc, meso_gdm **out_gdm) {
    meso_gdm_desc d;
    meso_result result = begin_bake(ctx, desc, out_gdm, &d);
    if (result != MESO_OK) return result;

    double start = meso_time_seconds();
    size_t rows = rows_of(&d), voxels = voxels_of(&d);
    int columns = columns_of(&d), k = d.eigenmaps;
    int rank = (size_t)columns < rows ? columns : (int)rows;
    /* The memory budget, before allocating: W (float, then halves), normals and inside flags,
     * the SVD's blocks and Gram matrix (bake_svd.c: 8192 rows as float and double), the
     * surface, the raw table when kept. Holding A between the passes is extra, taken only if
     * it fits. */
    uint64_t table_bytes = (uint64_t)rows * (uint64_t)columns * sizeof(float);
    /* The surface: a height field's triangles are known now; a solid's extraction needs
     * their node grid (a float and a vertex index a node), and their triangles are checked
     * once counted (surface_build). */
    meso_isosurface_desc cells = surface_cells_of(&d);
    uint64_t surface_bytes =
        d.solid ? 8u * (uint64_t)(cells.resolution_u + 1) * (uint64_t)(cells.resolution_v + 1) *
                      (uint64_t)(cells.resolution_w + 3)
                : heightfield_triangles(d.heightfield) * SURFACE_BYTES_PER_TRIANGLE;
    uint64_t needed = (uint64_t)rows * (uint64_t)k * (sizeof(float) + sizeof(uint16_t)) +
                      (uint64_t)voxels * (3u * sizeof(float) + 1u) +
                      UINT64_C(8192) * (uint64_t)columns * (sizeof(float) + sizeof(double)) +
                      3u * (uint64_t)columns * (uint64_t)columns * sizeof(double) + surface_bytes +
                      (d.keep_raw ? table_bytes : 0);
    if ((result = meso_memory_check(ctx, "gdm bake", needed)) != MESO_OK) return result;
    bool hold_table = !d.keep_raw && table_bytes <= (UINT64_C(1) << 31) &&
                      needed + table_bytes <= meso_context_memory_limit(ctx);

    gdm_surface surface = {0};
    float *vectors = NULL, *held_table = NULL;
    uint8_t *inside = NULL;
    meso_vec3 *directions = NULL;
    meso_gdm *gdm = calloc(1, sizeof(*gdm));
    if (!gdm) goto out_of_memory;
    gdm->desc = d;
    gdm->desc.heightfield = NULL;
    gdm->desc.solid = NULL;
    gdm->source_hash = source_hash_of(&d);
    gdm->from_heightfield = d.heightfield != NULL;
    gdm->num_sv = rank;
    vectors = malloc(sizeof(float) * (size_t)columns * (size_t)columns);
    inside = malloc(voxels);
    directions = malloc(sizeof(meso_vec3) * (size_t)d.num_phi * (size_t)d.num_theta);
    gdm->singular = malloc(sizeof(float) * (size_t)columns);
    gdm->weights = malloc(sizeof(float) * rows * (size_t)k);
    gdm->eigen = malloc(sizeof(float) * (size_t)k * (size_t)columns);
    gdm->normals = malloc(sizeof(float) * 3u * voxels);
    if (d.keep_raw) gdm->raw = malloc(table_bytes);
    if (!vectors || !inside || !directions || !gdm->singular || !gdm->weights || !gdm->eigen ||
        !gdm->normals || (d.keep_raw && !gdm->raw))
        goto out_of_memory;

    if ((result = surface_build(ctx, &d, needed - surface_bytes, &surface)) != MESO_OK) goto done;
    double surface_seconds = meso_time_seconds() - start;
    for (int p = 0; p < d.num_phi; p++)
        for (int t = 0; t < d.num_theta; t++)
            directions[(size_t)p * d.num_theta + t] = direction_of(theta_of(&d, t), phi_of(&d, p));
    bake_job job = {.desc = d,
                    .surface = &surface,
                    .inside = inside,
                    .directions = directions,
                    .normals = gdm->normals};
    meso_parallel_for(ctx, (voxels + VOXELS_PER_JOB - 1) / VOXELS_PER_JOB, classify_voxels, &job);

    /* A table within 2 GiB and the budget (the defaults: 256 MiB) is held between the passes
     * instead of traced again: half the bake, and the stored map's error can be measured. */
    held_table = hold_table ? malloc(table_bytes) : NULL;
    float *table = held_table ? held_table : gdm->raw;
    meso_bake_rows source = {
        .rows = rows,
        .columns = columns,
        .fill = fill_rows,
        .user = &job,
        .progress = meso_progress_begin_bake(ctx, "gdm", (table ? 1u : 2u) * (uint64_t)rows)};
    /* §4.1: A = U S E^T, W = U S: weight maps W_i(x, y, phi), eigen-maps E_i(z, theta) */
    result =
        meso_bake_svd_streamed(ctx, "gdm", &source, k, gdm->singular, vectors, gdm->weights, table);
    meso_progress_end(source.progress);
    if (result != MESO_OK) goto done;
    if (!d.float_weights) {
        gdm->weights_half = malloc(sizeof(uint16_t) * rows * (size_t)k);
        if (!gdm->weights_half) goto out_of_memory;
        meso_bake_round_to_halves(gdm->weights, gdm->weights_half, rows * (size_t)k);
    }
    for (int e = 0; e < k; e++)
        for (int c = 0; c < columns; c++)
            gdm->eigen[(size_t)e * columns + c] = vectors[(size_t)c * columns + e];
    fill_compression(gdm);
    gdm->compression.rmse_stored = table ? stored_rmse(ctx, gdm, table) : -1.0f;
    gdm->compression.bake_seconds = meso_time_seconds() - start;
    meso_log_info(ctx, "gdm: %zu triangles traced, surface and BVH %.2f s, bake %.2f s",
                  surface.num_triangles, surface_seconds, gdm->compression.bake_seconds);
    *out_gdm = gdm;
    gdm = NULL;
    goto done;
out_of_memory:
    result = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "gdm: out of memory for %zu x %d table",
                            rows, columns);
done:
    free(held_table);
    surface_release(&surface);
    free(directions);
    free(inside);
    free(vectors);
    meso_gdm_destroy(gdm);
    return result;
}

/* ---- Accessors and lookups ---------------------------------------------------------------- */

meso_gdm_desc meso_gdm_get_desc(const meso_gdm *gdm) { return gdm->desc; }
meso_gdm_compression meso_gdm_get_compression(const meso_gdm *gdm) { return gdm->compression; }

meso_gdm_view meso_gdm_get_view(const meso_gdm *gdm) {
    const meso_gdm_desc *d = &gdm->desc;
    return (meso_gdm_view){.width = d->width,
                           .height = d->height,
                           .layers = d->layers,
                           .num_theta = d->num_theta,
                           .num_phi = d->num_phi,
                           .num_eigen = d->eigenmaps,
                           .weights = gdm->weights,
                           .eigen = gdm->eigen,
                           .raw = gdm->raw,
                           .normals = gdm->normals};
}

/* A coordinate made finite and reduced to [0, 1) (u and v repeat). */
static float tile_fraction(float x) {
    if (!isfinite(x)) return 0.0f;
    float f = x - floorf(x);
    return f < 1.0f ? f : 0.0f;
}

typedef struct lookup_axes {
    meso_axis x, y, z, theta, phi;
} lookup_axes;

/* The sample positions of uvw and direction on the five axes (bake_gdm.h, "Conventions"):
 * x, y between voxel centres, repeating; z between layers, clamped to [0, 1]; theta between
 * its sample centres, clamped at the two half intervals next to the poles; phi repeating. */
static lookup_axes axes_of(const meso_gdm_desc *d, meso_vec3 uvw, meso_vec3 direction) {
    lookup_axes a;
    float u = tile_fraction(uvw.x), v = tile_fraction(uvw.y);
    float w = isfinite(uvw.z) ? fminf(fmaxf(uvw.z, 0.0f), 1.0f) : 0.0f;
    a.x = meso_axis_wrap(u * (float)d->width - 0.5f, d->width);
    a.y = meso_axis_wrap((1.0f - v) * (float)d->height - 0.5f, d->height);
    a.z = meso_axis_clamp(w * (float)(d->layers - 1), d->layers);
    float length = meso_vec3_length(direction);
    float cos_theta = length > 0.0f && isfinite(length) ? -direction.z / length : 1.0f;
    cos_theta = fminf(fmaxf(cos_theta, -1.0f), 1.0f);
    float theta = acosf(cos_theta);
    float phi = length > 0.0f && isfinite(length) ? atan2f(direction.y, direction.x) : 0.0f;
    if (phi < 0.0f) phi += (float)TWO_PI;
    a.theta = meso_axis_clamp(theta * (float)d->num_theta / MESO_PI - 0.5f, d->num_theta);
    a.phi = meso_axis_wrap(phi * (float)d->num_phi / (float)TWO_PI, d->num_phi);
    return a;
}

/* Weight of corner bit `bit` set or not along one axis. */
static float corner_weight(meso_axis axis, int set) { return set ? axis.w : 1.0f - axis.w; }

/* Corner `corner` (bits: a, b, c) of a trilinear interpolation over three axes: its indices
 * and its weight. */
static float trilinear_corner(int corner, meso_axis a, meso_axis b, meso_axis c, int *out_a,
                              int *out_b, int *out_c) {
    *out_a = corner & 1 ? a.i1 : a.i0;
    *out_b = corner & 2 ? b.i1 : b.i0;
    *out_c = corner & 4 ? c.i1 : c.i0;
    return corner_weight(a, corner & 1) * corner_weight(b, corner & 2) *
           corner_weight(c, corner & 4);
}

float meso_gdm_lookup(const meso_gdm *gdm, meso_vec3 uvw, meso_vec3 direction, int num_eigen,
                      bool raw) {
    const meso_gdm_desc *d = &gdm->desc;
    lookup_axes a = axes_of(d, uvw, direction);
    int columns = columns_of(d);
    /* the four (z, theta) columns and their bilinear weights */
    int cols[4];
    float col_weight[4];
    for (int c = 0; c < 4; c++) {
        int z = c & 1 ? a.z.i1 : a.z.i0, t = c & 2 ? a.theta.i1 : a.theta.i0;
        cols[c] = z * d->num_theta + t;
        col_weight[c] = corner_weight(a.z, c & 1) * corner_weight(a.theta, c & 2);
    }
    bool use_raw = raw && gdm->raw;
    int k = num_eigen <= 0 || num_eigen > d->eigenmaps ? d->eigenmaps : num_eigen;
    float sum = 0.0f;
    /* trilinear over the eight (x, y, phi) rows */
    for (int corner = 0; corner < 8; corner++) {
        int ix, iy, ip;
        float w = trilinear_corner(corner, a.x, a.y, a.phi, &ix, &iy, &ip);
        if (w == 0.0f) continue;
        size_t row = ((size_t)iy * (size_t)d->width + (size_t)ix) * (size_t)d->num_phi + (size_t)ip;
        float value = 0.0f;
        if (use_raw) {
            const float *entries = gdm->raw + row * (size_t)columns;
            for (int c = 0; c < 4; c++) value += col_weight[c] * entries[cols[c]];
        } else { /* §4.1: d = sum_i W_i(x, y, phi) E_i(z, theta) */
            const float *weights = gdm->weights + row * (size_t)d->eigenmaps;
            for (int e = 0; e < k; e++) {
                const float *eigen = gdm->eigen + (size_t)e * (size_t)columns;
                float ei = col_weight[0] * eigen[cols[0]] + col_weight[1] * eigen[cols[1]] +
                           col_weight[2] * eigen[cols[2]] + col_weight[3] * eigen[cols[3]];
                value += weights[e] * ei;
            }
        }
        sum += w * value;
    }
    return sum;
}

meso_vec3 meso_gdm_normal(const meso_gdm *gdm, meso_vec3 uvw) {
    const meso_gdm_desc *d = &gdm->desc;
    lookup_axes a = axes_of(d, uvw, (meso_vec3){0.0f, 0.0f, -1.0f});
    meso_vec3 n = {0.0f, 0.0f, 0.0f};
    for (int corner = 0; corner < 8; corner++) {
        int ix, iy, iz;
        float w = trilinear_corner(corner, a.x, a.y, a.z, &ix, &iy, &iz);
        if (w == 0.0f) continue;
        const float *v =
            gdm->normals +
            3u * (((size_t)iz * (size_t)d->height + (size_t)iy) * (size_t)d->width + (size_t)ix);
        n = meso_vec3_add(n, (meso_vec3){w * v[0], w * v[1], w * v[2]});
    }
    float length = meso_vec3_length(n);
    return length > 1e-12f ? meso_vec3_scale(n, 1.0f / length) : (meso_vec3){0.0f, 0.0f, -1.0f};
}

/* ---- Bake files --------------------------------------------------------------------------- */

/* report: rmse[16], num_rmse, rmse_stored, bake_seconds, rms */
#define REPORT_FLOATS (MESO_GDM_RMSE_COUNT + 4)

static int write_params(const meso_gdm *gdm, char *buffer, size_t size) {
    const meso_gdm_desc *d = &gdm->desc;
    const meso_gdm_compression *c = &gdm->compression;
    return snprintf(buffer, size,
                    "{\"width\": %d, \"height\": %d, \"layers\": %d, \"num_theta\": %d, "
                    "\"num_phi\": %d, \"eigenmaps\": %d, \"float_weights\": %d, "
                    "\"heightfield\": %d, \"max_ray_length\": %.9g, \"raw_bytes\": %llu, "
                    "\"compressed_bytes\": %llu, \"bake_seconds\": %.3f, "
                    "\"units\": \"d and normals in texture space (u, v, w): a tile and the "
                    "shell's depth are 1\"}",
                    d->width, d->height, d->layers, d->num_theta, d->num_phi, d->eigenmaps,
                    d->float_weights ? 1 : 0, gdm->from_heightfield ? 1 : 0,
                    (double)MESO_GDM_MAX_RAY_LENGTH, (unsigned long long)c->raw_bytes,
                    (unsigned long long)c->compressed_bytes, c->bake_seconds);
}

static meso_bake_file to_bake_file(const meso_gdm *gdm, char *params, size_t params_size,
                                   float *report) {
    const meso_gdm_desc *d = &gdm->desc;
    write_params(gdm, params, params_size);
    const meso_gdm_compression *c = &gdm->compression;
    for (int i = 0; i < MESO_GDM_RMSE_COUNT; i++) report[i] = c->rmse[i];
    report[MESO_GDM_RMSE_COUNT] = (float)c->num_rmse;
    report[MESO_GDM_RMSE_COUNT + 1] = c->rmse_stored;
    report[MESO_GDM_RMSE_COUNT + 2] = (float)c->bake_seconds;
    report[MESO_GDM_RMSE_COUNT + 3] = c->rms;
    meso_bake_file bake = {.kind = MESO_GDM_KIND,
                           .kind_version = MESO_GDM_KIND_VERSION,
                           .source_hash = gdm->source_hash,
                           .params_json = params,
                           .num_arrays = 5};
    uint64_t h = (uint64_t)d->height, w = (uint64_t)d->width, p = (uint64_t)d->num_phi;
    uint64_t l = (uint64_t)d->layers, t = (uint64_t)d->num_theta;
    bake.arrays[0] = (meso_bake_array){.name = "weights",
                                       .type = gdm->weights_half ? MESO_BAKE_F16 : MESO_BAKE_F32,
                                       .num_dims = 4,
                                       .dims = {h, w, p, (uint64_t)d->eigenmaps},
                                       .data = gdm->weights_half ? (void *)gdm->weights_half
                                                                 : (void *)gdm->weights};
    bake.arrays[1] = (meso_bake_array){.name = "eigen",
                                       .type = MESO_BAKE_F32,
                                       .num_dims = 3,
                                       .dims = {(uint64_t)d->eigenmaps, l, t},
                                       .data = gdm->eigen};
    bake.arrays[2] = (meso_bake_array){.name = "singular_values",
                                       .type = MESO_BAKE_F32,
                                       .num_dims = 1,
                                       .dims = {(uint64_t)gdm->num_sv},
                                       .data = gdm->singular};
    bake.arrays[3] = (meso_bake_array){.name = "normals",
                                       .type = MESO_BAKE_F32,
                                       .num_dims = 4,
                                       .dims = {l, h, w, 3},
                                       .data = gdm->normals};
    bake.arrays[4] = (meso_bake_array){.name = "report",
                                       .type = MESO_BAKE_F32,
                                       .num_dims = 1,
                                       .dims = {REPORT_FLOATS},
                                       .data = report};
    if (gdm->raw) {
        bake.arrays[5] = (meso_bake_array){.name = "raw",
                                           .type = MESO_BAKE_F32,
                                           .num_dims = 5,
                                           .dims = {h, w, p, l, t},
                                           .data = gdm->raw};
        bake.num_arrays = 6;
    }
    return bake;
}

meso_result meso_gdm_save(meso_context *ctx, const meso_gdm *gdm, const char *path) {
    if (!gdm || !path)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "gdm: NULL map or path");
    char params[1024];
    float report[REPORT_FLOATS];
    meso_bake_file bake = to_bake_file(gdm, params, sizeof(params), report);
    return meso_bake_file_save(ctx, &bake, path);
}

static float *copy_floats(const float *source, size_t count) {
    float *copy = malloc(sizeof(float) * (count ? count : 1));
    if (copy) memcpy(copy, source, sizeof(float) * count);
    return copy;
}

/* The params every loader and `meso info` read. */
static const char *const param_keys[] = {"width",   "height",    "layers",        "num_theta",
                                         "num_phi", "eigenmaps", "float_weights", "heightfield"};
#define NUM_PARAM_KEYS (int)(sizeof(param_keys) / sizeof(param_keys[0]))

meso_result meso_gdm_from_bake_file(meso_context *ctx, const meso_bake_file *bake, const char *name,
                                    meso_gdm **out_gdm) {
    if (out_gdm) *out_gdm = NULL;
    if (!bake || !out_gdm)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "gdm: NULL argument");
    name = name ? name : "gdm";
    if (strcmp(bake->kind, MESO_GDM_KIND) != 0 || bake->kind_version != MESO_GDM_KIND_VERSION)
        return meso_log_error(ctx, MESO_ERROR_FORMAT,
                              "%s: kind %s version %u is not gdm version %u", name, bake->kind,
                              bake->kind_version, MESO_GDM_KIND_VERSION);
    double v[NUM_PARAM_KEYS];
    for (int i = 0; i < NUM_PARAM_KEYS; i++)
        if (!meso_bake_params_number(bake->params_json, param_keys[i], &v[i]) || fabs(v[i]) > 1e6 ||
            v[i] != floor(v[i]))
            return meso_log_error(ctx, MESO_ERROR_FORMAT,
                                  "%s: params: %s: missing, not an integer or out of range", name,
                                  param_keys[i]);
    meso_gdm_desc d = {.width = (int)v[0],
                       .height = (int)v[1],
                       .layers = (int)v[2],
                       .num_theta = (int)v[3],
                       .num_phi = (int)v[4],
                       .eigenmaps = (int)v[5],
                       .float_weights = v[6] != 0.0};
    /* the limits first, so nothing below allocates for a file that claims a huge table */
    meso_result result = check_desc(ctx, name, &d);
    if (result != MESO_OK) return result == MESO_ERROR_LIMIT ? result : MESO_ERROR_FORMAT;
    size_t rows = rows_of(&d), voxels = voxels_of(&d);
    int columns = columns_of(&d), k = d.eigenmaps;
    int rank = (size_t)columns < rows ? columns : (int)rows;
    uint64_t h = (uint64_t)d.height, w = (uint64_t)d.width, p = (uint64_t)d.num_phi;
    uint64_t l = (uint64_t)d.layers, t = (uint64_t)d.num_theta;
    uint64_t weights_dims[4] = {h, w, p, (uint64_t)k}, eigen_dims[3] = {(uint64_t)k, l, t};
    uint64_t singular_dims[1] = {(uint64_t)rank}, normals_dims[4] = {l, h, w, 3};
    uint64_t report_dims[1] = {REPORT_FLOATS}, raw_dims[5] = {h, w, p, l, t};
    const void *weights = meso_bake_file_expect(
        bake, "weights", d.float_weights ? MESO_BAKE_F32 : MESO_BAKE_F16, 4, weights_dims);
    const float *eigen = meso_bake_file_expect(bake, "eigen", MESO_BAKE_F32, 3, eigen_dims);
    const float *singular =
        meso_bake_file_expect(bake, "singular_values", MESO_BAKE_F32, 1, singular_dims);
    const float *normals = meso_bake_file_expect(bake, "normals", MESO_BAKE_F32, 4, normals_dims);
    const float *report = meso_bake_file_expect(bake, "report", MESO_BAKE_F32, 1, report_dims);
    const float *raw = meso_bake_file_expect(bake, "raw", MESO_BAKE_F32, 5, raw_dims);
    if (!weights || !eigen || !singular || !normals || !report)
        return meso_log_error(ctx, MESO_ERROR_FORMAT,
                              "%s: arrays weights (%s), eigen, singular_values, normals, report "
                              "missing or of the wrong type or shape for the params",
                              name, d.float_weights ? "f32" : "f16");
    if (meso_bake_file_find(bake, "raw") && !raw)
        return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: array \"raw\": wrong type or shape",
                              name);
    /* Values, not only shapes: a valid checksum does not make Inf or NaN usable. Eigen-maps
     * and normals are unit vectors (|x| <= 1); weights within half precision's range; d
     * within [0, the longest ray]; the report's RMSEs >= 0 (rmse_stored -1: not measured). */
    static const struct {
        const char *array;
        double min, max;
    } ranges[] = {{"weights", -65504.0, 65504.0},   {"eigen", -1.001, 1.001},
                  {"singular_values", 0.0, 3.4e38}, {"normals", -1.001, 1.001},
                  {"report", -1.0, 3.4e38},         {"raw", 0.0, (double)MESO_GDM_MAX_RAY_LENGTH}};
    for (size_t i = 0; i < sizeof(ranges) / sizeof(ranges[0]); i++) {
        const meso_bake_array *a = meso_bake_file_find(bake, ranges[i].array);
        if (a && (result = meso_bake_array_check_values(ctx, name, a, ranges[i].min,
                                                        ranges[i].max)) != MESO_OK)
            return result;
    }
    meso_gdm *gdm = calloc(1, sizeof(*gdm));
    if (!gdm) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", name);
    gdm->desc = d;
    gdm->desc.keep_raw = raw != NULL;
    gdm->source_hash = bake->source_hash;
    gdm->from_heightfield = v[7] != 0.0;
    gdm->num_sv = rank;
    size_t num_weights = rows * (size_t)k;
    if (d.float_weights) {
        gdm->weights = copy_floats(weights, num_weights);
    } else {
        gdm->weights = malloc(sizeof(float) * num_weights);
        gdm->weights_half = malloc(sizeof(uint16_t) * num_weights);
        if (gdm->weights && gdm->weights_half) {
            memcpy(gdm->weights_half, weights, sizeof(uint16_t) * num_weights);
            meso_bake_halves_to_floats(gdm->weights_half, gdm->weights, num_weights);
        }
    }
    gdm->eigen = copy_floats(eigen, (size_t)k * (size_t)columns);
    gdm->singular = copy_floats(singular, (size_t)rank);
    gdm->normals = copy_floats(normals, 3u * voxels);
    gdm->raw = raw ? copy_floats(raw, rows * (size_t)columns) : NULL;
    if (!gdm->weights || (!d.float_weights && !gdm->weights_half) || !gdm->eigen ||
        !gdm->singular || !gdm->normals || (raw && !gdm->raw)) {
        meso_gdm_destroy(gdm);
        return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", name);
    }
    fill_compression(gdm);
    gdm->compression.rmse_stored = report[MESO_GDM_RMSE_COUNT + 1];
    gdm->compression.bake_seconds = 0.0;
    *out_gdm = gdm;
    return MESO_OK;
}

/* The steps of meso_bake_cache_run for a gdm; desc: the completed meso_gdm_desc. */
static meso_result gdm_from_file(meso_context *ctx, const meso_bake_file *bake, const char *where,
                                 const void *desc, void *out) {
    (void)desc;
    return meso_gdm_from_bake_file(ctx, bake, where, out);
}

static meso_result gdm_bake(meso_context *ctx, const void *desc, void *out) {
    return meso_gdm_bake(ctx, desc, out);
}

static meso_result gdm_store(meso_context *ctx, const meso_cached_bake *entry, const void *out) {
    char params[1024];
    float report[REPORT_FLOATS];
    meso_bake_file bake = to_bake_file(*(meso_gdm *const *)out, params, sizeof(params), report);
    return meso_bake_cache_save(ctx, &bake, entry->key);
}

meso_result meso_gdm_load(meso_context *ctx, const char *path, meso_gdm **out_gdm) {
    if (out_gdm) *out_gdm = NULL;
    return meso_bake_load_with(ctx, path, gdm_from_file, NULL, out_gdm);
}

meso_result meso_gdm_bake_cached(meso_context *ctx, const meso_gdm_desc *desc, meso_gdm **out_gdm) {
    meso_gdm_desc d;
    meso_result result = begin_bake(ctx, desc, out_gdm, &d);
    if (result != MESO_OK) return result;
    meso_cached_bake entry = {MESO_GDM_KIND,
                              MESO_GDM_KIND_VERSION,
                              "gdm",
                              meso_gdm_cache_key(&d),
                              source_hash_of(&d),
                              &d,
                              gdm_from_file,
                              gdm_bake,
                              gdm_store};
    return meso_bake_cache_run(ctx, &entry, out_gdm);
}

size_t meso_gdm_describe(const meso_bake_file *bake, char *buffer, size_t size) {
    if (!bake || strcmp(bake->kind, MESO_GDM_KIND) != 0 || !bake->params_json) return 0;
    uint64_t report_dims[1] = {REPORT_FLOATS};
    const float *r = meso_bake_file_expect(bake, "report", MESO_BAKE_F32, 1, report_dims);
    if (!r) return 0;
    double v[NUM_PARAM_KEYS], raw_bytes = 0.0, compressed_bytes = 0.0, seconds = 0.0;
    for (int i = 0; i < NUM_PARAM_KEYS; i++)
        if (!meso_bake_params_number(bake->params_json, param_keys[i], &v[i])) return 0;
    if (!meso_bake_params_number(bake->params_json, "raw_bytes", &raw_bytes) ||
        !meso_bake_params_number(bake->params_json, "compressed_bytes", &compressed_bytes) ||
        !meso_bake_params_number(bake->params_json, "bake_seconds", &seconds))
        return 0;
    char text[4096];
    int n = snprintf(text, sizeof(text),
                     "gdm: %.0f x %.0f x %.0f voxels, %.0f x %.0f directions, from a %s\n"
                     "raw %.2f MiB, compressed (k=%.0f, weights %s) %.3f MiB, ratio %.1f:1, "
                     "baked in %.1f s\n"
                     "reconstruction RMSE of d (texture units; the shell's depth is 1; RMS of d "
                     "itself %.4f):\n",
                     v[0], v[1], v[2], v[3], v[4], v[7] != 0.0 ? "height field" : "solid",
                     raw_bytes / 1048576.0, v[5], v[6] != 0.0 ? "float32" : "IEEE halves",
                     compressed_bytes / 1048576.0,
                     compressed_bytes > 0.0 ? raw_bytes / compressed_bytes : 0.0, seconds,
                     (double)r[MESO_GDM_RMSE_COUNT + 3]);
    for (int k = 1; k <= MESO_GDM_RMSE_COUNT && n > 0 && (size_t)n < sizeof(text); k++)
        n += snprintf(text + n, sizeof(text) - (size_t)n, "  k=%2d  %.5f%s\n", k, r[k - 1],
                      k == (int)v[5] ? "  (kept)" : "");
    if (n > 0 && (size_t)n < sizeof(text) && r[MESO_GDM_RMSE_COUNT + 1] >= 0.0f)
        n += snprintf(text + n, sizeof(text) - (size_t)n,
                      "as stored (k=%.0f, weights %s), measured over every entry: %.5f\n", v[5],
                      v[6] != 0.0 ? "float32" : "IEEE halves", r[MESO_GDM_RMSE_COUNT + 1]);
    if (n < 0) return 0;
    if (buffer && size) snprintf(buffer, size, "%s", text);
    return (size_t)n;
}
