/* gdm under global illumination (GDM paper §3.2 "Global Illumination", §4.2;
 * docs/techniques/gdm-gi.md): at the GDM hit, the environment's light reflected by the
 * mesostructure is the dot product of the radiance transfer volume's vector at (uvw, view)
 * (bake_rtv.h) with the incident radiance vector interpolated from the base triangle's
 * vertices (render_gi.h, meso_gi_vertex_radiance), times the albedo. The scene's lights are
 * added by the shared shading model with GDM's own shadows.
 *
 * Ambient: the shading model's ambient with an environment is the scene's constant `ambient`
 * plus the environment's unshadowed SH irradiance E(n) / pi (render_environment.h). Here the
 * direct part is shaded with the environment removed from the scene (constant ambient, lights,
 * specular), and the RTV term takes the place of E(n) / pi: the sky is counted once, shadowed
 * and interreflected by the RTV. The path-traced reference splits a pixel the same way
 * (reference_path.c: its direct part leaves the SH term out).
 *
 * Threads: gdm_gi_create uses the context's workers (the RTV bake, the per-vertex transfer);
 * gdm_gi_begin_frame runs single-threaded once a frame (the technique's geometry hook);
 * gdm_gi_shade is called from many threads at once and reads the state only. */
#ifndef MESO_GDM_GI_H
#define MESO_GDM_GI_H

#include "gdm_shell_shadow.h"
#include "meso/prism.h"
#include "render_internal.h"

typedef struct gdm_gi gdm_gi;

/* The RTV's bake resolution (zero fields: bake_rtv.h's defaults). */
typedef struct gdm_gi_desc {
    int resolution, layers, eigen;
    /* eigenfunctions used at render time, the first ones of the bake's `eigen` (an SVD's
     * truncation: the same as a bake of that many); 0 or more than eigen: all */
    int used_eigen;
    /* gdm's shadows through the shell, borrowed (outliving the gi); set: a hit seen from
     * inside the base mesh takes the sky through the shell (gi_inside_sky); NULL: the light
     * from below the tangent plane (a solid's open shell) or else the unshadowed SH ambient */
    const gdm_shell *shell;
} gdm_gi_desc;

/* Where a fragment's ray met the mesostructure: texture space (u, v, w) and its prism. */
typedef struct gdm_gi_hit {
    meso_vec3 uvw;
    const meso_prism *prism;
} gdm_gi_hit;

/* Bake (through the cache) the object's RTV with its shell's aspect, and the per-vertex
 * incident radiance of scene->environment (which must be set). *out_gi NULL on failure. */
meso_result gdm_gi_create(meso_context *ctx, const meso_scene *scene, const meso_object *object,
                          const gdm_gi_desc *desc, gdm_gi **out_gi);
void gdm_gi_destroy(gdm_gi *gi);
size_t gdm_gi_memory(const gdm_gi *gi);

/* Take the frame's lights and camera (the scene may change between frames: the viewer moves
 * its camera and light). Called before any gdm_gi_shade of the frame. */
void gdm_gi_begin_frame(gdm_gi *gi, const meso_frame *frame);

/* Colour `count` fragments (position, normal, uv set as for meso_shade_fragments) whose hits
 * are hits[i]: the direct light (visibility as meso_shade_fragments takes it) plus
 * albedo x RTV(uvw, view) . L(hit). */
void gdm_gi_shade(const gdm_gi *gi, const meso_frame *frame, const meso_object *object,
                  meso_fragment *fragments, size_t count, const float *visibility,
                  const gdm_gi_hit *hits);

#endif
