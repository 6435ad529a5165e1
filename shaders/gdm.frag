// meso:requires meso_common.glsl meso_solid.glsl
// gdm.frag: generalized displacement maps (Wang et al. 2004, §3.2, Fig. 5; §4.1). The mesh is
// extruded into a shell of prisms (meso_prism_layer_create: 8 triangles a prism, top, bottom,
// 3 fins x 2), and these faces are drawn, culled to the ones facing the camera. Per fragment,
// as meso's CPU technique (src/render/techniques/gdm.c): the ray's entry T_in on the drawn
// face, its exit from the prism (the nearest leaving plane, a fin's two planes taken as one:
// the nearer where the fin is convex, the farther where concave, Fig. 5), V_t = the unit
// texture-space segment T_in -> T_out, d = d_GDM(T_in, V_t) = sum_i W_i(x, y, phi) E_i(z,
// theta) (§4.1), a hit where d < |T_out - T_in| (§3.2), mapped back to world space for its
// depth (gl_FragDepth, so prisms and objects occlude each other correctly) and shading;
// shadows where d_GDM(T, L_t) ends before the slab's boundary (§3.2). Beyond the paper, as
// the CPU's default (u_refine_steps 6): the table's hit checked on the mesostructure itself
// (the height field's heights, a solid's signed distance, meso_solid.glsl) and bisected, and
// the shadow's blocker looked for there too.
//
// Texture space (meso/bake_gdm.h): u, v in tiles, w = 0 on the mesh (top) to 1 at the shell's
// bottom; theta from up (-w) over the whole sphere, phi from +u. A height field is the solid
// w >= 1 - h(u, v). Lookups are multilinear between samples: x = u W - 1/2, y = (1 - v) H - 1/2
// (repeating), z = w (L - 1) (clamped), t = theta T / pi - 1/2 (clamped), p = phi P / (2 pi)
// (repeating), as gdm_lookup.h and meso_axis of meso/math.h.
//
// Textures (buffer textures, texelFetch):
//   unit 2  u_gdm_weights  RGBA16F: W as half floats (the CPU's bits), u_gdm_chunks texels per
//           (x, y, phi): texel ((y W + x) P + phi) u_gdm_chunks + j holds W_{4j..4j+3}
//   unit 3  u_gdm_eigen    RGBA32F: E transposed, texel (z T + theta) u_gdm_chunks + j holds
//           E_{4j..4j+3}(z, theta); W and E are zero past u_eigenmaps
//   unit 4  u_gdm_normals  RGBA32F: the bake's unit (u, v, w) normals, texel (z H + y) W + x
//           (read with u_normals 1, or 0 on a solid)
//   unit 5  u_gdm_prisms   RGBA32F, 24 texels a prism: 0-7 its face planes (normal, offset)
//           in the slots' order (top, bottom, fin e's two triangles), 8 the fins' convexity,
//           9 (uv[0], uv_inverse[0..1]), 10 (uv_inverse[2..3], valid), 11-13 the base
//           vertices' P, 14-16 their N, 17-19 their T = dP/du, 20-22 B = dP/dv
//   unit 6  u_gdm_faces    RGBA32F, 5 texels a face (face = gl_PrimitiveID: the layer's faces
//           are drawn in order: every prism's top, then their fins, then their bottoms):
//           (P_c, u_c) for c = 0..2, then (v_0, w_0, v_1, w_1), (v_2, w_2, 0, 0)
//   unit 7  u_solid_grid   (meso_solid.glsl)
//   unit 1  u_height (meso_common.glsl): the height field
// Uniforms: ivec3 u_gdm_size (W, H, L), ivec2 u_gdm_directions (T, P), int u_gdm_chunks,
//   int u_num_prisms, bool u_gdm_heightfield; meso's option table for `gdm`, same names:
//   int u_eigenmaps (7), u_resolution, u_layers, u_num_theta, u_num_phi (the bake's: W, L, T,
//   P), bool u_shadows (true), float u_shadow_bias (-1: 0.25, or 1.5 with u_refine_steps 0),
//   int u_shadow_steps (24), float u_hit_margin (0), int u_normals (0), int u_refine_steps
//   (6), bool u_compressed (must be true: the GL reads the SVD only), bool u_gi and
//   u_gi_resolution, u_gi_layers, u_gi_eigen (GDM-GI: drawn on the CPU only; the GL refuses
//   gi 1 in a scene with an environment, where it would apply), bool u_macro_shadows and
//   u_gi_inside_sky (the CPU's shadows through the whole shell, gdm_shell_shadow.c: not read
//   here; the GL's shadows are the slab-local ones, the CPU's with macro_shadows 0), bool
//   u_clear_top_walk (of that walk: not read; it changes no image), bool u_refine_secant
//   (true: the refinement ends with a secant step, as the CPU's) and bool u_walk
//   (the CPU's view-ray shell walk, gdm_walk.h: not read here; every prism's faces are drawn,
//   the CPU's walk 0, docs/gpu.md).

uniform bool u_compressed;
uniform int u_eigenmaps;
uniform int u_resolution;
uniform int u_layers;
uniform int u_num_theta;
uniform int u_num_phi;
uniform bool u_shadows;
uniform float u_shadow_bias;
uniform int u_shadow_steps;
uniform float u_hit_margin;
uniform int u_normals;
uniform int u_refine_steps;
uniform bool u_gi;
uniform int u_gi_resolution;
uniform int u_gi_layers;
uniform int u_gi_eigen;
uniform bool u_macro_shadows;
uniform bool u_gi_inside_sky;
uniform bool u_clear_top_walk;
uniform bool u_refine_secant;
uniform bool u_walk;

uniform samplerBuffer u_gdm_weights;
uniform samplerBuffer u_gdm_eigen;
uniform samplerBuffer u_gdm_normals;
uniform samplerBuffer u_gdm_prisms;
uniform samplerBuffer u_gdm_faces;
uniform ivec3 u_gdm_size;
uniform ivec2 u_gdm_directions;
uniform int u_gdm_chunks;
uniform int u_num_prisms;
uniform bool u_gdm_heightfield;

const float GDM_PI = 3.14159265358979323846, GDM_TWO_PI = 6.28318530717958647692;
const float GDM_MAX_RAY_LENGTH = 16.0; // MESO_GDM_MAX_RAY_LENGTH
const float GDM_NONE = 3.0e38;         // "infinity": no plane bounds the ray
const int GDM_TOP = 0, GDM_BOTTOM = 1, GDM_FIN = 2;

bool gdm_finite(float x) { return !isnan(x) && !isinf(x); }

// ---- The table -----------------------------------------------------------------------------

struct gdm_axis {
    int i0, i1;
    float w;
};

// meso_axis_clamp: sample position x in [0, n - 1], clamped at both ends.
gdm_axis gdm_axis_clamp(float x, int n) {
    if (n <= 1 || x <= 0.0) return gdm_axis(0, 0, 0.0);
    if (x >= float(n - 1)) return gdm_axis(n - 1, n - 1, 0.0);
    int i = int(x);
    return gdm_axis(i, i + 1, x - float(i));
}

// meso_axis_wrap for the positions met here (x >= -1, x <= n): one period either way.
gdm_axis gdm_axis_wrap(float x, int n) {
    float f = floor(x);
    int i = int(f);
    i += i < 0 ? n : 0;
    i -= i >= n ? n : 0;
    return gdm_axis(i, i + 1 == n ? 0 : i + 1, x - f);
}

float gdm_tile_fraction(float x) {
    if (!gdm_finite(x)) return 0.0;
    float f = x - floor(x);
    return f < 1.0 ? f : 0.0;
}

vec4 gdm_w(int x, int y, int p, int j) {
    return texelFetch(u_gdm_weights,
                      ((y * u_gdm_size.x + x) * u_gdm_directions.y + p) * u_gdm_chunks + j);
}

vec4 gdm_e(int z, int t, int j) {
    return texelFetch(u_gdm_eigen, (z * u_gdm_directions.x + t) * u_gdm_chunks + j);
}

// d at uvw along the (u, v, w) direction (gdm_lookup8): the 8 (x, y, phi) corners of W
// blended, dotted with the 4 (z, theta) corners of E blended.
float gdm_lookup(vec3 uvw, vec3 direction) {
    float u = gdm_tile_fraction(uvw.x), v = gdm_tile_fraction(uvw.y);
    float w = gdm_finite(uvw.z) ? min(max(uvw.z, 0.0), 1.0) : 0.0;
    gdm_axis ax = gdm_axis_wrap(u * float(u_gdm_size.x) - 0.5, u_gdm_size.x);
    gdm_axis ay = gdm_axis_wrap((1.0 - v) * float(u_gdm_size.y) - 0.5, u_gdm_size.y);
    gdm_axis az = gdm_axis_clamp(w * float(u_gdm_size.z - 1), u_gdm_size.z);
    float len = length(direction);
    bool valid = len > 0.0 && gdm_finite(len);
    float cos_theta = valid ? -direction.z / len : 1.0;
    cos_theta = min(max(cos_theta, -1.0), 1.0);
    float theta = acos(cos_theta);
    float phi = valid ? atan(direction.y, direction.x) : 0.0;
    if (phi < 0.0) phi += GDM_TWO_PI;
    gdm_axis at = gdm_axis_clamp(theta * float(u_gdm_directions.x) / GDM_PI - 0.5,
                                 u_gdm_directions.x);
    gdm_axis ap = gdm_axis_wrap(phi * float(u_gdm_directions.y) / GDM_TWO_PI, u_gdm_directions.y);
    float c00 = (1.0 - az.w) * (1.0 - at.w), c01 = (1.0 - az.w) * at.w;
    float c10 = az.w * (1.0 - at.w), c11 = az.w * at.w;
    int ix[2] = int[2](ax.i0, ax.i1), iy[2] = int[2](ay.i0, ay.i1), ip[2] = int[2](ap.i0, ap.i1);
    float wx[2] = float[2](1.0 - ax.w, ax.w), wy[2] = float[2](1.0 - ay.w, ay.w);
    float wp[2] = float[2](1.0 - ap.w, ap.w);
    float d = 0.0;
    for (int j = 0; j < u_gdm_chunks; ++j) {
        vec4 e = c00 * gdm_e(az.i0, at.i0, j) + c01 * gdm_e(az.i0, at.i1, j) +
                 c10 * gdm_e(az.i1, at.i0, j) + c11 * gdm_e(az.i1, at.i1, j);
        vec4 wsum = vec4(0.0);
        for (int corner = 0; corner < 8; ++corner) {
            float cw = wx[corner & 1] * wy[(corner >> 1) & 1] * wp[corner >> 2];
            wsum += cw * gdm_w(ix[corner & 1], iy[(corner >> 1) & 1], ip[corner >> 2], j);
        }
        vec4 p = wsum * e;
        d += (p.x + p.y) + (p.z + p.w);
    }
    return d;
}

// meso_gdm_normal: the bake's normals, trilinear over x, y (repeating) and z (clamped).
vec3 gdm_baked_normal(vec3 uvw) {
    float u = gdm_tile_fraction(uvw.x), v = gdm_tile_fraction(uvw.y);
    float w = gdm_finite(uvw.z) ? min(max(uvw.z, 0.0), 1.0) : 0.0;
    gdm_axis ax = gdm_axis_wrap(u * float(u_gdm_size.x) - 0.5, u_gdm_size.x);
    gdm_axis ay = gdm_axis_wrap((1.0 - v) * float(u_gdm_size.y) - 0.5, u_gdm_size.y);
    gdm_axis az = gdm_axis_clamp(w * float(u_gdm_size.z - 1), u_gdm_size.z);
    vec3 n = vec3(0.0);
    for (int corner = 0; corner < 8; ++corner) {
        int x = (corner & 1) != 0 ? ax.i1 : ax.i0, y = (corner & 2) != 0 ? ay.i1 : ay.i0;
        int z = (corner & 4) != 0 ? az.i1 : az.i0;
        float cw = ((corner & 1) != 0 ? ax.w : 1.0 - ax.w) *
                   ((corner & 2) != 0 ? ay.w : 1.0 - ay.w) *
                   ((corner & 4) != 0 ? az.w : 1.0 - az.w);
        if (cw == 0.0) continue;
        n += cw * texelFetch(u_gdm_normals, (z * u_gdm_size.y + y) * u_gdm_size.x + x).xyz;
    }
    float len = length(n);
    return len > 1e-12 ? n * (1.0 / len) : vec3(0.0, 0.0, -1.0);
}

// ---- The prism -----------------------------------------------------------------------------

vec4 gdm_prism(int prism, int k) { return texelFetch(u_gdm_prisms, prism * 24 + k); }

// meso_prism_layer_face: the face index of a prism's face slot.
int gdm_face_of(int prism, int slot) {
    if (slot == GDM_TOP) return prism;
    if (slot == GDM_BOTTOM) return 7 * u_num_prisms + prism;
    return u_num_prisms + 6 * prism + (slot - GDM_FIN);
}

// meso_prism_layer_face_uvw: the (u, v, w) of a point of the face's plane, the face's
// attributes interpolated linearly.
vec3 gdm_face_uvw(int face, vec3 x) {
    int base = face * 5;
    vec4 t0 = texelFetch(u_gdm_faces, base), t1 = texelFetch(u_gdm_faces, base + 1);
    vec4 t2 = texelFetch(u_gdm_faces, base + 2), t3 = texelFetch(u_gdm_faces, base + 3);
    vec4 t4 = texelFetch(u_gdm_faces, base + 4);
    vec3 e1 = t1.xyz - t0.xyz, e2 = t2.xyz - t0.xyz, d = x - t0.xyz;
    float d00 = dot(e1, e1), d01 = dot(e1, e2), d11 = dot(e2, e2);
    float d20 = dot(d, e1), d21 = dot(d, e2);
    float det = d00 * d11 - d01 * d01;
    float b1 = 0.0, b2 = 0.0;
    if (det > 0.0) {
        b1 = (d11 * d20 - d01 * d21) / det;
        b2 = (d00 * d21 - d01 * d20) / det;
    }
    vec3 a = vec3(t0.w, t3.x, t3.y), b = vec3(t1.w, t3.z, t3.w), c = vec3(t2.w, t4.x, t4.y);
    return a * (1.0 - b1 - b2) + b * b1 + c * b2;
}

// geom_prism.c leave_time: from where the ray stays outside the plane's half-space.
float gdm_leave_time(vec4 plane, vec3 o, vec3 d, float tolerance, bool partner) {
    float dn = dot(plane.xyz, d);
    float s0 = dot(plane.xyz, o) - plane.w;
    if (dn > 0.0) return s0 >= 0.0 ? 0.0 : -s0 / dn;
    return s0 > tolerance && !partner ? 0.0 : GDM_NONE;
}

// meso_prism_layer_exit (§3.2 Fig. 5): the ray entering through entry_slot leaves at t, through
// exit_slot; false when no face bounds it.
bool gdm_prism_exit(int prism, vec3 origin, vec3 direction, int entry_slot, out float t_out,
                    out int exit_slot) {
    float tolerance = 1e-5 * (abs(origin.x) + abs(origin.y) + abs(origin.z) + u_depth);
    float best = GDM_NONE;
    int best_slot = -1;
    vec4 convex = gdm_prism(prism, 8);
    for (int slot = 0; slot < 8; slot += slot < GDM_FIN ? 1 : 2) {
        float t;
        int which = slot;
        if (slot < GDM_FIN) {
            t = slot == entry_slot
                    ? GDM_NONE
                    : gdm_leave_time(gdm_prism(prism, slot), origin, direction, tolerance, false);
        } else {
            float t1 = slot == entry_slot ? GDM_NONE
                                          : gdm_leave_time(gdm_prism(prism, slot), origin,
                                                           direction, tolerance,
                                                           slot + 1 == entry_slot);
            float t2 = slot + 1 == entry_slot ? GDM_NONE
                                              : gdm_leave_time(gdm_prism(prism, slot + 1), origin,
                                                               direction, tolerance,
                                                               slot == entry_slot);
            int fin = (slot - GDM_FIN) / 2;
            bool is_convex = (fin == 0 ? convex.x : (fin == 1 ? convex.y : convex.z)) > 0.5;
            bool first = is_convex ? t1 <= t2 : t1 >= t2;
            t = first ? t1 : t2;
            which = first ? slot : slot + 1;
        }
        if (t < best) {
            best = t;
            best_slot = which;
        }
    }
    t_out = best;
    exit_slot = best_slot;
    return best_slot >= 0 && best < GDM_NONE;
}

// meso_prism_map: the world point of texture point uvw of the prism (extrapolated linearly
// outside its UV triangle).
vec3 gdm_prism_map(int prism, vec3 uvw) {
    vec4 a = gdm_prism(prism, 9), b = gdm_prism(prism, 10);
    float dx = uvw.x - a.x, dy = uvw.y - a.y;
    float b1 = a.z * dx + a.w * dy;
    float b2 = b.x * dx + b.y * dy;
    float s = -uvw.z * u_depth;
    vec3 p0 = gdm_prism(prism, 11).xyz + gdm_prism(prism, 14).xyz * s;
    vec3 p1 = gdm_prism(prism, 12).xyz + gdm_prism(prism, 15).xyz * s;
    vec3 p2 = gdm_prism(prism, 13).xyz + gdm_prism(prism, 16).xyz * s;
    return p0 * (1.0 - b1 - b2) + p1 * b1 + p2 * b2;
}

// meso_prism_unmap (meso/prism.h): the texture point whose prism map is x, Newton's method from
// `guess` with gdm.c's GDM_UNMAP_ITERATIONS (4) and GDM_UNMAP_TOLERANCE (5e-3).
vec3 gdm_prism_unmap(int prism, vec3 x, vec3 guess) {
    vec4 a = gdm_prism(prism, 9), b = gdm_prism(prism, 10);
    vec3 p0 = gdm_prism(prism, 11).xyz, n0 = gdm_prism(prism, 14).xyz;
    vec3 dp1 = gdm_prism(prism, 12).xyz - p0, dp2 = gdm_prism(prism, 13).xyz - p0;
    vec3 dn1 = gdm_prism(prism, 15).xyz - n0, dn2 = gdm_prism(prism, 16).xyz - n0;
    vec3 uvw = guess;
    for (int k = 0; k < 4; k++) {
        float du = uvw.x - a.x, dv = uvw.y - a.y;
        float b1 = a.z * du + a.w * dv, b2 = b.x * du + b.y * dv;
        float s = -uvw.z * u_depth;
        vec3 e1 = dp1 + dn1 * s, e2 = dp2 + dn2 * s;
        vec3 n = n0 + dn1 * b1 + dn2 * b2;
        vec3 residual = p0 + n0 * s + e1 * b1 + e2 * b2 - x;
        vec3 ju = e1 * a.z + e2 * b.x, jv = e1 * a.w + e2 * b.y, jw = n * -u_depth;
        vec3 cu = cross(jv, jw), cv = cross(jw, ju), cw = cross(ju, jv);
        float det = dot(ju, cu);
        if (!(det != 0.0) || !gdm_finite(det)) return uvw;
        vec3 step = vec3(dot(cu, residual), dot(cv, residual), dot(cw, residual)) * (1.0 / det);
        uvw -= step;
        if (all(lessThan(abs(step), vec3(5e-3)))) break;
    }
    return uvw;
}

// gdm.c frame_at: the Jacobian of the prism map at a texture point with the interpolated
// tangent frame (T, B, -depth N), and its cofactor columns (J^-T = (cu cv cw) / det).
struct gdm_frame {
    vec3 normal, tangent, bitangent, cu, cv, cw;
    float det;
};

gdm_frame gdm_frame_at(int prism, vec2 uv) {
    vec4 a = gdm_prism(prism, 9), b = gdm_prism(prism, 10);
    float dx = uv.x - a.x, dy = uv.y - a.y;
    float w1 = a.z * dx + a.w * dy, w2 = b.x * dx + b.y * dy, w0 = 1.0 - w1 - w2;
    gdm_frame f;
    f.normal = normalize(gdm_prism(prism, 14).xyz * w0 + gdm_prism(prism, 15).xyz * w1 +
                         gdm_prism(prism, 16).xyz * w2);
    f.tangent = gdm_prism(prism, 17).xyz * w0 + gdm_prism(prism, 18).xyz * w1 +
                gdm_prism(prism, 19).xyz * w2;
    f.bitangent = gdm_prism(prism, 20).xyz * w0 + gdm_prism(prism, 21).xyz * w1 +
                  gdm_prism(prism, 22).xyz * w2;
    vec3 jw = f.normal * -u_depth;
    f.cu = cross(f.bitangent, jw);
    f.cv = cross(jw, f.tangent);
    f.cw = cross(f.tangent, f.bitangent);
    f.det = dot(f.tangent, f.cu);
    return f;
}

// A texture-space normal to a world one: J^-T n, unit; the base normal if degenerate.
vec3 gdm_world_normal(gdm_frame f, vec3 n) {
    vec3 m = f.cu * n.x + f.cv * n.y + f.cw * n.z;
    if (f.det < 0.0) m = -m;
    float len2 = dot(m, m);
    return len2 > 0.0 && gdm_finite(len2) ? m * (1.0 / sqrt(len2)) : f.normal;
}

// A world direction in texture space: J^-1 x, unit (zero if degenerate).
vec3 gdm_texture_direction(gdm_frame f, vec3 x) {
    vec3 t = vec3(dot(f.cu, x), dot(f.cv, x), dot(f.cw, x));
    float len2 = dot(t, t);
    if (!(len2 > 0.0) || !gdm_finite(len2)) return vec3(0.0);
    return t * ((f.det < 0.0 ? -1.0 : 1.0) / sqrt(len2));
}

// ---- The mesostructure itself (the refinement beyond the paper) ------------------------------

vec3 gdm_tile_point(vec3 uvw) { return vec3(uvw.x - floor(uvw.x), uvw.y - floor(uvw.y), uvw.z); }

// The mesostructure's function at p: (1 - h) - w for a height field, the distance for a solid;
// inside where it is <= 0.
float gdm_function(vec3 p) {
    return u_gdm_heightfield ? (1.0 - meso_height_at(meso_height_texel(p.xy))) - p.z
                             : meso_solid_distance(gdm_tile_point(p));
}

bool gdm_inside(vec3 p) { return gdm_function(p) <= 0.0; }

// Solid where a ray leaves the slab's bottom at t (height fields: always).
bool gdm_floor_is_solid(vec3 t) {
    return u_gdm_heightfield || meso_solid_distance(gdm_tile_point(vec3(t.xy, 1.0 - 1e-3))) <= 0.0;
}

// gdm.c refine_hit: the table's hit checked on the mesostructure -- outside a window before
// it and inside just past it, then bisected; else probes from the entry. The hit's distance
// along vt, negative for none. (The CPU skips probes its earlier samples' distance bounds
// already decide, with the same answers; every probe is evaluated here.)
// The view ray's path through its prism (gdm.c shade_one): t_in + x vt + x (dt - x) bow.
vec3 gdm_path(vec3 t_in, vec3 vt, vec3 bow, float dt, float x) {
    return t_in + vt * x + bow * (x * (dt - x));
}

// `steps` halvings of the bracket [lo, hi] (lo outside, hi inside).
void gdm_bisect(vec3 t_in, vec3 vt, vec3 bow, float dt, bool solid_floor, int steps,
                inout float lo, inout float hi) {
    for (int k = 0; k < steps; ++k) {
        float mid = 0.5 * (lo + hi);
        if ((solid_floor && mid >= dt) || gdm_inside(gdm_path(t_in, vt, bow, dt, mid)))
            hi = mid;
        else
            lo = mid;
    }
}

float gdm_refine_hit(vec3 t_in, vec3 vt, vec3 bow, float d, float dt, bool solid_floor,
                     float window) {
    float guess = min(max(d, 0.0), dt);
    float before = max(guess - window, 0.0), after = min(guess + 0.5 * window, dt);
    float lo = 0.0, hi = -1.0;
    bool in_before =
        (solid_floor && before >= dt) || gdm_inside(gdm_path(t_in, vt, bow, dt, before));
    bool in_after = !in_before && ((solid_floor && after >= dt) ||
                                   gdm_inside(gdm_path(t_in, vt, bow, dt, after)));
    if (!in_before && in_after) {
        lo = before;
        hi = after;
    } else {
        if ((solid_floor && 0.0 >= dt) || gdm_inside(t_in)) return 0.0;
        // gdm.c: one every eighth of the window, 8 to GDM_PROBES (64)
        float wanted = ceil(8.0 * dt / window);
        int probes = wanted > 8.0 ? (wanted < 64.0 ? int(wanted) : 64) : 8;
        for (int k = 1; k <= probes && hi < 0.0; ++k) {
            float x = k == probes ? dt : dt * float(k) / float(probes); // exactly the exit last
            if ((solid_floor && x >= dt) || gdm_inside(gdm_path(t_in, vt, bow, dt, x)))
                hi = x;
            else
                lo = x;
        }
        if (hi < 0.0) return -1.0;
    }
    // gdm.c: the last two bisections replaced by one secant step through the bracket's ends
    // where both are samples (an end the solid floor decides is not)
    bool secant = u_refine_secant && u_refine_steps >= 2;
    gdm_bisect(t_in, vt, bow, dt, solid_floor, secant ? u_refine_steps - 2 : u_refine_steps, lo,
               hi);
    if (secant) {
        bool hi_floor = solid_floor && hi >= dt;
        float f_lo = gdm_function(gdm_path(t_in, vt, bow, dt, lo));
        float f_hi = hi_floor ? 0.0 : gdm_function(gdm_path(t_in, vt, bow, dt, hi));
        float span = f_lo - f_hi; // f_lo > 0 >= f_hi
        if (!hi_floor && f_lo > 0.0 && f_hi <= 0.0 && span > 0.0 && !isinf(span))
            return lo + (hi - lo) * (f_lo / span);
        gdm_bisect(t_in, vt, bow, dt, solid_floor, 2, lo, hi); // else the two bisections
    }
    return 0.5 * (lo + hi);
}

// gdm.c shadowed (§3.2): is the light, seen from t along the unit texture direction lt,
// blocked before the slab's boundary?
bool gdm_shadowed(vec3 t, vec3 normal_t, vec3 lt, vec3 voxel, float bias, float window) {
    if (lt.z >= 0.0) return true; // the light is below the base surface: the body is between
    vec3 offset = u_gdm_heightfield ? vec3(0.0, 0.0, -1.0) : normal_t;
    t = t + offset * (voxel * bias);
    t.z = min(max(t.z, 0.0), 1.0);
    float boundary = min(t.z / -lt.z, GDM_MAX_RAY_LENGTH);
    float margin = bias * voxel.z;
    if (boundary <= margin) return false;
    float d = gdm_lookup(t, lt);
    if (u_refine_steps > 0) {
        if (d >= boundary - margin) return false;
        if (gdm_inside(t + lt * (d + 0.5 * window))) return true;
        for (int k = 0; k < u_shadow_steps; ++k) {
            float x = boundary * (float(k) + 0.5) / float(u_shadow_steps);
            if (gdm_inside(t + lt * x)) return true;
        }
        return false;
    }
    return d < boundary - margin;
}

void main() {
    int face = gl_PrimitiveID, prism, slot;
    int n = u_num_prisms;
    if (face < n) {
        prism = face;
        slot = GDM_TOP;
    } else if (face >= 7 * n) {
        prism = face - 7 * n;
        slot = GDM_BOTTOM;
    } else {
        prism = (face - n) / 6;
        slot = GDM_FIN + (face - n) % 6;
    }
    vec3 entry = v_position;
    vec3 t_in = gdm_face_uvw(face, entry); // the CPU interpolates it: the same up to rounding
    vec3 view = normalize(entry - u_eye);
    float t;
    int exit_slot;
    if (!gdm_prism_exit(prism, entry, view, slot, t, exit_slot) || !gdm_finite(t)) discard;
    vec3 p_out = entry + view * t;
    vec3 t_out = gdm_face_uvw(gdm_face_of(prism, exit_slot), p_out);
    vec3 segment = t_out - t_in;
    float dt = length(segment);
    if (!(dt > 1e-7)) discard;
    vec3 vt = segment * (1.0 / dt);
    float d = gdm_lookup(t_in, vt);
    float window = 3.0 / float(u_layers - 1);
    bool floor_exit = exit_slot == GDM_BOTTOM && gdm_floor_is_solid(t_out);
    // the ray's curved path through the prism (gdm.c shade_one): its midpoint mapped back
    vec3 bow = vec3(0.0);
    if (u_refine_steps > 0) {
        vec3 line_mid = 0.5 * (t_in + t_out);
        vec3 sag = gdm_prism_unmap(prism, entry + view * (0.5 * t), line_mid) - line_mid;
        if (gdm_finite(dot(sag, sag))) bow = sag * (4.0 / (dt * dt));
    }
    if (u_refine_steps > 0) {
        d = gdm_refine_hit(t_in, vt, bow, d, dt, floor_exit, window);
        if (d < 0.0) discard;
    } else if (!(d < dt - u_hit_margin)) {
        // §3.2: the ray passes through the prism -- unless it leaves through the bottom into
        // solid (§4.1: the miss distance is the boundary's; the point's property decides)
        if (!floor_exit) discard;
        d = d < dt ? d : dt;
    }
    d = d > 0.0 ? d : 0.0;
    vec3 hit = gdm_path(t_in, vt, bow, dt, d);
    vec3 position = gdm_prism_map(prism, hit);
    // between the entry's depth (never nearer) and the exit's (gdm.c says why)
    float entry_depth = dot(entry - u_eye, u_forward);
    float depth = dot(position - u_eye, u_forward);
    float exit_depth = dot(p_out - u_eye, u_forward);
    depth = depth < exit_depth ? depth : exit_depth;
    depth = depth > entry_depth ? depth : entry_depth;
    gdm_frame tf = gdm_frame_at(prism, hit.xy);
    bool baked = u_normals == 1 || (u_normals == 0 && !u_gdm_heightfield);
    vec3 normal_t, normal;
    if (baked) {
        normal_t = gdm_baked_normal(hit);
    } else if (u_gdm_heightfield) {
        vec2 g = meso_height_gradient(meso_height_texel(hit.xy));
        normal_t = vec3(-g.x, -g.y, -1.0);
    } else {
        normal_t = meso_solid_gradient(gdm_tile_point(hit));
    }
    if (u_gdm_heightfield && !baked) {
        meso_frame mf = meso_frame_make(position, tf.normal, tf.tangent, tf.bitangent);
        normal = meso_displaced_normal(mf, u_depth, vec2(-normal_t.x, -normal_t.y));
    } else {
        normal = gdm_world_normal(tf, normal_t);
    }
    float length_t = length(normal_t);
    normal_t = length_t > 0.0 ? normal_t * (1.0 / length_t) : vec3(0.0, 0.0, -1.0);
    float visibility[MESO_MAX_LIGHTS];
    meso_all_visible(visibility);
    if (u_shadows) {
        float bias = u_shadow_bias >= 0.0 ? u_shadow_bias : (u_refine_steps > 0 ? 0.25 : 1.5);
        vec3 voxel = vec3(1.0 / float(u_resolution), 1.0 / float(u_resolution),
                          1.0 / float(u_layers - 1));
        for (int i = 0; i < u_num_lights; ++i) {
            vec3 l = meso_light_direction(i, position);
            if (dot(l, normal) <= 0.0) continue; // unlit anyway
            vec3 lt = gdm_texture_direction(tf, l);
            if (gdm_shadowed(hit, normal_t, lt, voxel, bias, window)) visibility[i] = 0.0;
        }
    }
    meso_write(meso_shade(position, normal, hit.xy, visibility), depth);
}
