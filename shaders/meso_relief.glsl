// meso_relief.glsl: the relief family's fragment (GLSL 3.30 core), after meso_common.glsl:
// the view ray in the height field's texture space, the depth correction, the displaced
// normal at the hit, self-shadows toward each light and silhouettes from per-vertex quadrics
// (Policarpo, Oliveira & Comba 2005; Oliveira & Policarpo 2005; summarised in Policarpo &
// Oliveira 2006 §2.1). A technique's file supplies the two searches, declared below:
//   bool relief_search(relief_ray r, out float t)   t of the first hit along the view ray
//   bool relief_shadow(relief_light_ray s)          true where the light is blocked
// and calls relief_main() from its main().
//
// Texture space of a fragment. With T = dP/du, B = dP/dv and N unit at the fragment, the view
// vector V = P - eye (unnormalised) is written V = du T + dv B + dn N. Along the ray P + t V
// (t >= 0 from the base mesh) the texture coordinates are uv + t (du, dv) and the depth below
// the base surface in shell units is
//     d(t) = t (a - b t),   a = -dn / depth,   b = (qa x^2 + qb y^2) / depth
// with (x, y) = (V.normalize(T), V.normalize(B)) and (qa, qb) the interpolated quadric: on a
// curved mesh the surface falls away below the tangent plane, so d counts from the curved
// surface and a ray whose d returns to 0 leaves the shell (a silhouette; b = 0 without
// silhouettes). The ray hits the height field at the first t with d(t) >= 1 - h(uv(t)).
// Lookups are in texel-centre coordinates (meso_common.glsl).
//
// Uniforms (besides meso_common.glsl's):
//   bool u_shadows       self-shadows: a second search toward each light
//   bool u_silhouettes   silhouettes from the per-vertex quadrics (a_quadric)
//   bool u_shell         the CPU's search along the prism shell (relief_shell.h); the GL back
//                        end refuses 1 (gl_renderer.c), so it is always false here

uniform bool u_shadows;
uniform bool u_silhouettes;
uniform bool u_shell;
// The texture domain's open sides (meso_mesh_uv_domain): bits 1 u_min, 2 u_max, 4 v_min,
// 8 v_max of u_domain = (u_min, u_max, v_min, v_max); a hit past one is a miss.
uniform int u_domain_sides;
uniform vec4 u_domain;

bool relief_domain_inside(vec2 uv) {
    return !((u_domain_sides & 1) != 0 && uv.x < u_domain.x) &&
           !((u_domain_sides & 2) != 0 && uv.x > u_domain.y) &&
           !((u_domain_sides & 4) != 0 && uv.y < u_domain.z) &&
           !((u_domain_sides & 8) != 0 && uv.y > u_domain.w);
}

// One view ray in texel-centre coordinates: (x0 + xd t, y0 + yd t) at depth d(t) = t (a - b t),
// searched over [0, t_end]; t_end is where it reaches the shell's bottom (floor_hit) or leaves
// a convex shell.
struct relief_ray {
    vec2 start, step;
    float a, b, t_end;
    // curved_uv only (else 0): at depth d the texture coordinates advance 1 / (1 - lateral d)
    // times faster than on the mesh (relief_lateral_scale)
    float lateral;
    bool floor_hit; // the search ends on the floor: d = 1 at t_end
    bool flat_hit;  // no search: the ray does not enter the shell (hit at t = 0)
};

// A light ray from a hit at texel-centre position `start`, depth d, to `start + step` at
// s = 1, where it leaves the shell; its depth is d (1 - s) + bulge s (1 - s) (bulge >= 0 on
// a convex mesh, where the surface falls away from a rising light ray).
struct relief_light_ray {
    vec2 start, step;
    float d, bulge;
};

// Depth bias of the shadow test, shell units: the hit lies on the surface up to the
// search's error and a light ray leaving it must not find it again.
const float RELIEF_SHADOW_BIAS = 0.004;

bool relief_search(relief_ray r, out float t);
bool relief_shadow(relief_light_ray s);
vec3 relief_hit_normal(meso_frame f, relief_ray r, float t, vec2 hit, float hd);

// The height field's own normal at the hit (texel-centre coordinates `hit`).
vec3 relief_gradient_normal(meso_frame f, vec2 hit) {
    return meso_relief_normal(f, u_depth, meso_height_gradient(hit));
}

// Beyond the papers (relief_layers' `curved`): on a curved mesh the shell at depth w is a
// smaller (convex) or larger copy of the surface, so a ray's texture coordinates advance
// faster there: by 1 / (1 - kappa w depth), averaged from 0 to the ray's depth d as
// 1 / (1 - kappa d depth / 2), kappa the curvature along the ray (twice the quadric).
float relief_lateral_scale(relief_ray r, float d) { return 1.0 / (1.0 - r.lateral * max(d, 0.0)); }

// Relief mapping's search (Policarpo et al. 2005; Policarpo & Oliveira 2006 App. A):
// `linear_steps` uniform steps along the ray to the first sample below the surface, then
// `binary_steps` halvings of that bracket, then one secant step between its ends (exact where
// the surface is planar). t of the hit; false where the ray leaves the shell (silhouette).
bool relief_linear_search(relief_ray r, int linear_steps, int binary_steps, out float t) {
    // t = 0: a texel at full height is hit where the ray enters (h = 1: exactly the mesh).
    float h = meso_height_at(r.start);
    bool found = h >= 1.0 || r.flat_hit;
    float t_lo = 0.0, t_hi = 0.0, f_lo = -1.0, f_hi = h - 1.0;
    float t_prev = 0.0, f_prev = h - 1.0;
    float inv_n = 1.0 / float(linear_steps);
    for (int k = 1; k <= linear_steps && !found; ++k) {
        float tk = r.t_end * (float(k) * inv_n);
        float d = tk * (r.a - r.b * tk);
        float fk = d + meso_height_at(r.start + r.step * tk) - 1.0; // >= 0: at or below
        if (fk >= 0.0 || (k == linear_steps && r.floor_hit)) {   // d = 1 on the floor
            t_lo = t_prev;
            f_lo = f_prev;
            t_hi = tk;
            f_hi = max(fk, 0.0);
            found = true;
        }
        t_prev = tk;
        f_prev = fk;
    }
    for (int k = 0; k < binary_steps; ++k) {
        float tk = (t_lo + t_hi) * 0.5;
        float fk = tk * (r.a - r.b * tk) + meso_height_at(r.start + r.step * tk) - 1.0;
        if (fk >= 0.0) {
            t_hi = tk;
            f_hi = fk;
        } else {
            t_lo = tk;
            f_lo = fk;
        }
    }
    // Secant between the bracket's ends, f_lo < 0 <= f_hi: exact where the surface is planar.
    float span = f_hi - f_lo;
    float w = span > 1e-12 ? -f_lo / max(span, 1e-12) : 1.0;
    t = t_hi <= t_lo ? t_hi : t_lo + (t_hi - t_lo) * w;
    return found;
}

// Self-shadowing by a second linear search toward the light (Policarpo & Oliveira 2006
// §2.1): blocked where a sample lies below the surface.
bool relief_linear_shadow(relief_light_ray s, int steps) {
    float inv = 1.0 / float(steps);
    // Sample k = steps is on the mesh (d = 0): nothing is above it.
    for (int k = 1; k < steps; ++k) {
        float frac = float(k) * inv;
        float h = meso_height_at(s.start + s.step * frac);
        if ((s.d + s.bulge * frac) * (1.0 - frac) + h - 1.0 > RELIEF_SHADOW_BIAS) return true;
    }
    return false;
}

// The surface at `entry` turned to the hit t V away on the curved mesh: the quadric surface
// -(qa x^2 + qb y^2) has the normal N + 2 qa x T^ + 2 qb y B^ there, so n is turned by the
// rotation taking N to it (small angle).
vec3 relief_curve_normal(meso_frame f, vec2 q, float t, vec3 n) {
    float tl = length(f.tangent), bl = length(f.bitangent);
    float it = tl > 0.0 ? 1.0 / tl : 0.0, ib = bl > 0.0 ? 1.0 / bl : 0.0;
    float sx = 2.0 * q.x * t * dot(f.view, f.tangent) * it * it;
    float sy = 2.0 * q.y * t * dot(f.view, f.bitangent) * ib * ib;
    vec3 turned = n + f.tangent * sx + f.bitangent * sy;
    return turned * (1.0 / sqrt(max(dot(turned, turned), 1e-30)));
}

// (x, y) of world direction D along T^ and B^.
vec2 relief_along_frame(meso_frame f, vec3 d) {
    float tl = length(f.tangent), bl = length(f.bitangent);
    return vec2(tl > 0.0 ? dot(d, f.tangent) / tl : 0.0, bl > 0.0 ? dot(d, f.bitangent) / bl : 0.0);
}

// Shade the fragment of frame f at texture coordinates uv (the relief family's fragment):
// the view ray, the search, depth correction, the normal at the hit, self-shadows.
void relief_shade(meso_frame f, vec2 uv, vec2 quadric, bool silhouettes, bool shadows,
                  bool curved_uv) {
    float depth = u_depth;
    vec2 size = vec2(u_height_size);
    // ---- the view ray
    float cu = dot(f.view, f.bn), cv = dot(f.view, f.nt), cn = dot(f.view, f.tb);
    bool enter = depth > 0.0 && cn < 0.0 && f.ok;
    if (!enter) cu = cv = 0.0;
    relief_ray r;
    r.start = meso_height_texel(uv);
    r.step = vec2(cu * size.x, -cv * size.y);
    r.a = enter ? -cn / depth : 0.0;
    r.b = 0.0;
    r.lateral = 0.0;
    vec2 q = vec2(0.0);
    if (silhouettes) {
        q = quadric;
        vec2 xy = relief_along_frame(f, f.view);
        r.b = enter ? (q.x * xy.x * xy.x + q.y * xy.y * xy.y) / depth : 0.0;
        float r2 = dot(xy, xy);
        if (curved_uv && enter && r2 > 0.0) // kappa depth / 2 along the ray, within +-0.9
            r.lateral = clamp((q.x * xy.x * xy.x + q.y * xy.y * xy.y) * depth / max(r2, 1e-30),
                              -0.9, 0.9);
    }
    // d(t) = 1 at the smaller root of b t^2 - a t + 1 = 0 (stable for b -> 0); without a
    // real root the convex shell is left at t = a / b.
    float disc = r.a * r.a - 4.0 * r.b;
    bool reaches_floor = disc >= 0.0;
    r.t_end = !enter ? 0.0 : reaches_floor ? 2.0 / (r.a + sqrt(max(disc, 0.0))) : r.a / r.b;
    r.floor_hit = reaches_floor && enter;
    r.flat_hit = !enter;
    float t;
    if (!relief_search(r, t)) discard; // the ray left the curved shell: silhouette
    // ---- the hit: depth, position, texture coordinates, normal
    float hd = max(t * (r.a - r.b * t), 0.0);
    float tt = curved_uv ? t * relief_lateral_scale(r, hd) : t;
    vec2 hit = r.start + r.step * tt;
    vec3 hit_position = f.position + f.view * t;
    vec2 hit_uv = uv + vec2(cu, cv) * tt;
    if (!relief_domain_inside(hit_uv)) discard; // past an open border: the ray left the shell
    float view_depth = dot(f.view, u_forward) * (1.0 + t);
    vec3 n = relief_hit_normal(f, r, t, hit, hd);
    if (silhouettes) n = relief_curve_normal(f, q, t, n);
    // ---- self-shadows, one light ray per light
    float visibility[MESO_MAX_LIGHTS];
    meso_all_visible(visibility);
    for (int i = 0; shadows && i < u_num_lights; ++i) {
        vec3 l = meso_light_direction(i, hit_position);
        float lu = dot(l, f.bn), lv = dot(l, f.nt), ln = dot(l, f.tb);
        // The light ray leaves the shell where d(s) = hd - (ln s + ql s^2) / depth reaches 0
        // (ql: the quadric along L): s_out = 2 hd depth / (ln + sqrt(ln^2 + 4 ql hd depth)).
        // The light's elevation is taken over the tangent plane at the hit, which has turned
        // by 2 q from the entry's. Without a real positive root the surface blocks the light.
        vec2 xl = relief_along_frame(f, l), xv = relief_along_frame(f, f.view);
        float ql = q.x * xl.x * xl.x + q.y * xl.y * xl.y;
        ln += 2.0 * t * (q.x * xv.x * xl.x + q.y * xv.y * xl.y);
        float reach = hd * depth;
        float ldisc = ln * ln + 4.0 * ql * reach;
        float denominator = ln + sqrt(max(ldisc, 0.0));
        bool leaves = hd <= 0.0 ? ln > 0.0 : (ldisc >= 0.0 && denominator > 0.0);
        bool dark = !(leaves && f.ok);
        if (!dark && hd > 0.0) {
            float s = 2.0 * reach / denominator;
            relief_light_ray lr;
            lr.start = hit;
            lr.d = hd;
            lr.bulge = ql * s * s / depth;
            lr.step = vec2(lu * s * size.x, -lv * s * size.y);
            dark = relief_shadow(lr);
        }
        if (dark) visibility[i] = 0.0;
    }
    meso_write(meso_shade(hit_position, n, hit_uv, visibility), view_depth);
}

// The fragment as drawn, with the technique's uniforms.
void relief_main() {
    relief_shade(meso_frame_get(), v_uv, v_quadric, u_silhouettes, u_shadows, false);
}
