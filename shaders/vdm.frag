// meso:requires meso_common.glsl
// vdm.frag: view-dependent displacement mapping (Wang et al. 2003, §3.2, §3.3 and Fig. 6):
// per fragment the view direction in the local frame (theta, phi) and the curvature along it
// select the baked distance d(x, y, theta, phi, c) to the mesostructure, reconstructed from
// its SVD as d = sum_i W^i(x, y, phi) E^i(theta, c) (§3.3); theta beyond the maximal view
// polar angle theta_MVM = sum_i W^i E^i_MVM(c) -> discard (silhouette); the real texture
// coordinate T' = T - d V_xy; shadows by a second lookup along the light (flat-surface
// approximation, §3.2); shading at T' with the height field's normal. Beyond the paper, as
// meso's CPU technique: the hit refined on the height field where the 8 (x, y, phi) corner
// samples disagree (u_refine_steps; 0: the paper's interpolated d), the same probe for
// shadows there, and the normal of the curved mesh at the hit.
//
// The bake's space is texture space: u, v in tiles and depth in tiles (u_depth_tiles = the
// shell depth / the mesh's average world length of a tile, u_tile_world); d is in shell depths.
//
// Textures (texelFetch only, GL_NEAREST):
//   unit 2  u_vdm_weights  RGBA16F: W as half floats, `lanes` = 4 u_vdm_chunks numbers per
//           (x, y, phi): texel ((x * u_num_phi + phi) * u_vdm_chunks + j, u_vdm_level_row[l] + y)
//           holds W^{4j..4j+3} of mip level l (levels stacked in rows; §4: W box-filtered)
//   unit 3  u_vdm_eigen    RGBA32F: E_VDM, texel (c * u_num_theta + theta, j) holds
//           E^{4j..4j+3}(theta, c), zero past u_eigenfunctions
//   unit 4  u_mvm_eigen    RGBA32F: E_MVM, texel (c, j), zero past u_mvm_eigenfunctions
//   unit 1  u_height (meso_common.glsl): the height field, for T', the normal and refinement
// Uniforms (meso's option table for `vdm`, same names; the bake's sizes are the table's):
//   int  u_resolution, u_num_theta, u_num_phi, u_num_curvatures   the table's sizes
//   int  u_eigenfunctions (8), u_mvm_eigenfunctions (4)            used at bake-time layout
//   bool u_shadows (true), u_silhouettes (true), u_curvature (true)
//   bool u_silhouette_filter (false: theta_MVM of the nearest texel, as the paper)
//   bool u_mipmap (true): W's mip level from the pixel's footprint in texels
//   int  u_refine_steps (3), u_shadow_steps (16); float u_shadow_bias (-1: 0.05, or 0.2 with
//        u_refine_steps 0)
//   bool u_compressed (must be true: the GL reads the SVD only)
// and: int u_vdm_chunks, u_vdm_levels, ivec2 u_vdm_level_size[12], int u_vdm_level_row[12],
//   vec2 u_curvature_range (the bake's c_min, c_max), float u_tile_world, u_depth_tiles,
//   u_pixel_size (world width of a pixel at view depth 1), bool u_has_curvature (the mesh has
//   principal curvatures)

uniform int u_resolution;
uniform int u_num_theta;
uniform int u_num_phi;
uniform int u_num_curvatures;
uniform int u_eigenfunctions;
uniform int u_mvm_eigenfunctions;
uniform bool u_compressed;
uniform bool u_shadows;
uniform bool u_silhouettes;
uniform bool u_curvature;
uniform bool u_silhouette_filter;
uniform bool u_mipmap;
uniform int u_refine_steps;
uniform int u_shadow_steps;
uniform float u_shadow_bias;

uniform sampler2D u_vdm_weights;
uniform sampler2D u_vdm_eigen;
uniform sampler2D u_mvm_eigen;
uniform int u_vdm_chunks;
uniform int u_vdm_levels;
uniform ivec2 u_vdm_level_size[12];
uniform int u_vdm_level_row[12];
uniform vec2 u_curvature_range;
uniform float u_tile_world;
uniform float u_depth_tiles;
uniform float u_pixel_size;
uniform bool u_has_curvature;

in float v_curvature_view;

const float HALF_PI = 1.57079632679;
const float TWO_PI = 6.28318530718;
const int VDM_MAX_CHUNKS = 16; // 64 eigenfunctions

// ---- Lookups (multilinear over x, y, phi, theta, c; §4: "interpolated") --------------------

struct vdm_axis {
    int i0, i1;
    float w;
};

vdm_axis axis_clamp(float x, int n) {
    if (n <= 1 || x <= 0.0) return vdm_axis(0, 0, 0.0);
    if (x >= float(n - 1)) return vdm_axis(n - 1, n - 1, 0.0);
    int i = int(x);
    return vdm_axis(i, i + 1, x - float(i));
}

vdm_axis axis_wrap(float x, int n) {
    float f = floor(x);
    int i = int(mod(f, float(n))); // f is whole: exact
    return vdm_axis(i, i + 1 == n ? 0 : i + 1, x - f);
}

vec4 vdm_w(int level, int x, int y, int phi, int j) {
    return texelFetch(u_vdm_weights,
                      ivec2((x * u_num_phi + phi) * u_vdm_chunks + j, u_vdm_level_row[level] + y),
                      0);
}

// d in shell depths at (uv, theta, phi, c) (§3.3: sum_i W^i(x, y, phi) E^i(theta, c)),
// trilinear over (x, y, phi), bilinear over (theta, c); corners: d at the 8 (x, y, phi)
// corners; max_theta: theta_MVM from the nearest texel (§3.2) or interpolated.
float vdm_lookup(vec2 uv, float theta, float phi, float c, int level, out float max_theta,
                 out float corners[8]) {
    ivec2 size = u_vdm_level_size[level];
    float x = uv.x * float(size.x) - 0.5, y = (1.0 - uv.y) * float(size.y) - 0.5;
    vdm_axis ax = u_height_clamp ? axis_clamp(x, size.x) : axis_wrap(x, size.x);
    vdm_axis ay = u_height_clamp ? axis_clamp(y, size.y) : axis_wrap(y, size.y);
    vdm_axis ap = axis_wrap(phi * float(u_num_phi) / TWO_PI, u_num_phi);
    vdm_axis at = axis_clamp(theta * float(u_num_theta) / HALF_PI - 0.5, u_num_theta);
    float cn = u_num_curvatures > 1 ? (c - u_curvature_range.x) /
                                          (u_curvature_range.y - u_curvature_range.x) *
                                          float(u_num_curvatures - 1)
                                    : 0.0;
    vdm_axis ac = axis_clamp(cn, u_num_curvatures);
    int col0 = ac.i0 * u_num_theta + at.i0, col1 = ac.i0 * u_num_theta + at.i1;
    int col2 = ac.i1 * u_num_theta + at.i0, col3 = ac.i1 * u_num_theta + at.i1;
    float w0 = (1.0 - ac.w) * (1.0 - at.w), w1 = (1.0 - ac.w) * at.w;
    float w2 = ac.w * (1.0 - at.w), w3 = ac.w * at.w;
    vec4 e[VDM_MAX_CHUNKS], w[VDM_MAX_CHUNKS];
    for (int j = 0; j < u_vdm_chunks; j++) {
        e[j] = w0 * texelFetch(u_vdm_eigen, ivec2(col0, j), 0) +
               w1 * texelFetch(u_vdm_eigen, ivec2(col1, j), 0) +
               w2 * texelFetch(u_vdm_eigen, ivec2(col2, j), 0) +
               w3 * texelFetch(u_vdm_eigen, ivec2(col3, j), 0);
        w[j] = vec4(0.0);
    }
    float wx[2] = float[2](1.0 - ax.w, ax.w), wy[2] = float[2](1.0 - ay.w, ay.w);
    float wp[2] = float[2](1.0 - ap.w, ap.w);
    int ix[2] = int[2](ax.i0, ax.i1), iy[2] = int[2](ay.i0, ay.i1), ip[2] = int[2](ap.i0, ap.i1);
    float d = 0.0;
    for (int corner = 0; corner < 8; corner++) {
        float cw = wx[corner & 1] * wy[(corner >> 1) & 1] * wp[corner >> 2];
        float corner_d = 0.0;
        for (int j = 0; j < u_vdm_chunks; j++) {
            vec4 wj = vdm_w(level, ix[corner & 1], iy[(corner >> 1) & 1], ip[corner >> 2], j);
            corner_d += dot(wj, e[j]);
            w[j] += cw * wj;
        }
        corners[corner] = corner_d;
        d += cw * corner_d;
    }
    // theta_MVM = sum_i W^i E^i_MVM(c), with W interpolated or of the nearest texel
    int nearest_x = ax.w < 0.5 ? ax.i0 : ax.i1, nearest_y = ay.w < 0.5 ? ay.i0 : ay.i1;
    max_theta = 0.0;
    for (int j = 0; j < u_vdm_chunks; j++) {
        vec4 wj = u_silhouette_filter ? w[j]
                                      : wp[0] * vdm_w(level, nearest_x, nearest_y, ap.i0, j) +
                                            wp[1] * vdm_w(level, nearest_x, nearest_y, ap.i1, j);
        vec4 m = (1.0 - ac.w) * texelFetch(u_mvm_eigen, ivec2(ac.i0, j), 0) +
                 ac.w * texelFetch(u_mvm_eigen, ivec2(ac.i1, j), 0);
        max_theta += dot(wj, m);
    }
    return d;
}

// ---- The hit on the height field (beyond the paper; meso's vdm.c refine_hit) ----------------

// The 8 corner values clamped to >= 0 and sorted; false when they agree within 1/50 shell
// depth (the table is smooth there: its interpolated d is used as the paper does).
bool sorted_corners(float corners[8], out float sorted[8]) {
    float lo = corners[0], hi = corners[0];
    for (int i = 1; i < 8; i++) {
        lo = min(lo, corners[i]);
        hi = max(hi, corners[i]);
    }
    for (int i = 0; i < 8; i++) sorted[i] = 0.0;
    if (max(hi, 0.0) - max(lo, 0.0) < 0.02) return false;
    for (int i = 0; i < 8; i++) { // insertion sort
        float x = max(corners[i], 0.0);
        int j = i;
        for (; j > 0 && sorted[j - 1] > x; j--) sorted[j] = sorted[j - 1];
        sorted[j] = x;
    }
    return sorted[7] - sorted[0] >= 0.02;
}

// >= 0 where the point t shell depths along the bake-space ray vb is below the surface.
float residual(vec2 uv, vec3 vb, float t) {
    vec2 at = uv - t * u_depth_tiles * vb.xy;
    return t * vb.z - (1.0 - meso_height_at(meso_height_texel(at)));
}

// The first corner at which the pixel's own ray is below the height field brackets the first
// crossing; Illinois regula falsi steps close in. Where the corners agree: d as the paper.
float refine_hit(vec2 uv, vec3 vb, float corners_in[8], float d, int steps) {
    float corners[8];
    if (!sorted_corners(corners_in, corners)) return d;
    float lo = 0.0, r_lo = residual(uv, vb, 0.0);
    if (r_lo >= 0.0) return 0.0;
    float hi = -1.0, r_hi = 0.0;
    for (int i = 0; i < 8 && hi < 0.0; i++) {
        if (corners[i] <= lo) continue;
        // half-way first where the gap is wide: a thin tip between two corners
        float start = lo, gap = corners[i] - lo;
        int inner = gap > 0.3 ? 3 : (gap > 0.2 ? 2 : (gap > 0.1 ? 1 : 0));
        for (int k = 1; k <= inner + 1; k++) {
            float x = start + gap * float(k) / float(inner + 1), r = residual(uv, vb, x);
            if (r >= 0.0) {
                hi = x;
                r_hi = r;
                break;
            }
            lo = x;
            r_lo = r;
        }
    }
    if (hi < 0.0) { // above the surface at every candidate: a few steps further on
        float stride = max(corners[7] - corners[0], 0.125);
        for (int k = 1; k <= 4 && hi < 0.0; k++) {
            float x = corners[7] + stride * float(k), r = residual(uv, vb, x);
            if (r >= 0.0) {
                hi = x;
                r_hi = r;
            } else {
                lo = x;
                r_lo = r;
            }
        }
        if (hi < 0.0) return corners[7];
    }
    int side = 0;
    for (int k = 0; k < steps; k++) {
        float x = lo + (hi - lo) * r_lo / (r_lo - r_hi);
        float r = residual(uv, vb, x);
        if (r >= 0.0) {
            hi = x;
            r_hi = r;
            if (side > 0) r_lo *= 0.5; // Illinois: the stale end keeps moving
            side = 1;
        } else {
            lo = x;
            r_lo = r;
            if (side < 0) r_hi *= 0.5;
            side = -1;
        }
    }
    return lo + (hi - lo) * r_lo / (r_lo - r_hi);
}

// The shadow counterpart: where the corners agree the table decides (§3.2: d_L < limit);
// where they disagree the light ray grazes an occluder's edge and uniform probes decide.
bool blocked_before(vec2 uv, vec3 vb, float corners_in[8], float d, float limit, int steps) {
    float corners[8];
    if (!sorted_corners(corners_in, corners)) return d < limit;
    for (int k = 1; k <= steps; k++)
        if (residual(uv, vb, limit * float(k) / float(steps)) > 0.0) return true;
    return false;
}

// A world direction in the bake's space (u, v, depth), unit.
vec3 to_bake_space(vec3 dir, vec3 t, vec3 b, vec3 n, float scale_u, float scale_v) {
    return normalize(vec3(dot(dir, t) / scale_u, dot(dir, b) / scale_v, dot(dir, n) / u_tile_world));
}

void main() {
    meso_frame f = meso_frame_get();
    vec3 n = f.normal;
    // the local frame of §3.2: the normal and the texture directions
    vec3 t = normalize(f.tangent - n * dot(n, f.tangent));
    vec3 b = f.bitangent - n * dot(n, f.bitangent);
    b = normalize(b - t * dot(t, b));
    vec3 view = normalize(u_eye - f.position);
    if (dot(view, n) <= 1e-4) discard; // grazing or from behind the base surface
    float scale_u = length(f.tangent), scale_v = length(f.bitangent);
    if (!(scale_u > 0.0 && scale_v > 0.0)) discard;
    vec3 vb = to_bake_space(view, t, b, n, scale_u, scale_v);
    float theta = acos(min(vb.z, 1.0)), phi = atan(vb.y, vb.x);
    float c = 0.0, c_world = 0.0;
    if (u_curvature && u_has_curvature) {
        c = v_curvature_view;
        c_world = c;
        // world 1/length -> bake space: c s_h^2 / s, s_h the world length of one bake unit
        // along V_xy
        float hx = dot(view, t), hy = dot(view, b);
        float world_per_unit = u_tile_world;
        if (hx * hx + hy * hy > 1e-12) {
            float x = hx / scale_u, y = hy / scale_v;
            world_per_unit = sqrt((hx * hx + hy * hy) / (x * x + y * y));
        }
        c *= world_per_unit * world_per_unit / u_tile_world;
    }
    int level = 0;
    if (u_vdm_levels > 1) { // texels under the pixel: its world size here over the texel's
        float footprint = u_pixel_size * dot(f.view, u_forward);
        float rho = footprint * sqrt(float(u_vdm_level_size[0].x) * float(u_vdm_level_size[0].y) /
                                     (scale_u * scale_v));
        while (rho >= 2.0 && level + 1 < u_vdm_levels) {
            rho *= 0.5;
            level++;
        }
    }
    float theta_step = HALF_PI / float(u_num_theta);
    float max_theta, corners[8];
    float d = vdm_lookup(v_uv, theta, phi, c, level, max_theta, corners);
    // §3.2 silhouettes: theta beyond theta_MVM (the half step puts the boundary between the
    // last valid sample and the first invalid)
    if (u_silhouettes && theta > max_theta + 0.5 * theta_step) discard;
    if (u_refine_steps > 0) d = refine_hit(v_uv, vb, corners, d, u_refine_steps);
    d = max(d, 0.0);
    // the real texture coordinate (§3.2): T' = T - d V_xy, in tiles
    float offset = d * u_depth_tiles;
    vec2 uv = v_uv - offset * vb.xy;
    vec2 p = meso_height_texel(uv);
    float h = meso_height_at(p);
    float below = (1.0 - h) * u_depth;
    vec3 position = f.position - t * (offset * vb.x * scale_u) - b * (offset * vb.y * scale_v) -
                    n * below;
    // the normal of the curved mesh at the hit: the displaced normal turned by c_V per world
    // unit along V_xy (as vdm.c)
    vec3 along = position + n * below - f.position;
    vec3 normal =
        normalize(meso_displaced_normal(f, u_depth, meso_height_gradient(p)) + along * c_world);
    float visibility[MESO_MAX_LIGHTS];
    meso_all_visible(visibility);
    float bias = u_shadow_bias >= 0.0 ? u_shadow_bias : (u_refine_steps > 0 ? 0.05 : 0.2);
    for (int i = 0; u_shadows && i < u_num_lights; i++) {
        // §3.2, Fig. 5: P'' = T' + h tan(theta_L) L; lit when d_L reaches P' (h sec theta_L)
        vec3 l = meso_light_direction(i, position);
        if (dot(l, n) <= 1e-4) {
            visibility[i] = 0.0; // below the reference surface's horizon
            continue;
        }
        if (dot(l, normal) <= 0.0) continue; // unlit anyway
        vec3 lb = to_bake_space(l, t, b, n, scale_u, scale_v);
        float depth_below = 1.0 - h;
        if (depth_below <= 0.0) continue;
        float reach = depth_below * u_depth_tiles / lb.z;
        vec2 uv_light = uv + reach * lb.xy;
        float theta_l = acos(min(lb.z, 1.0)), phi_l = atan(lb.y, lb.x);
        float max_theta_l, light_corners[8];
        float d_l = vdm_lookup(uv_light, theta_l, phi_l, 0.0, level, max_theta_l, light_corners);
        if (theta_l > max_theta_l + 0.5 * theta_step) continue; // the ray meets nothing
        float expected = depth_below / lb.z;
        float limit = expected - bias * (1.0 + expected);
        bool blocked = u_refine_steps > 0
                           ? blocked_before(uv_light, lb, light_corners, d_l, limit, u_shadow_steps)
                           : d_l < limit;
        if (blocked) visibility[i] = 0.0;
    }
    float view_depth = max(dot(position - u_eye, u_forward), dot(f.view, u_forward));
    meso_write(meso_shade(position, normal, uv, visibility), view_depth);
}
