// meso:requires meso_common.glsl meso_relief.glsl
// relief.frag: relief mapping (Policarpo, Oliveira & Comba 2005, as summarised in Policarpo &
// Oliveira 2006 §2.1 and its Appendix A): a linear search along the view ray over the
// bilinear height field, then a binary search, then one secant step; self-shadows by a
// second linear search toward each light. meso_relief.glsl does the rest.
//
// Uniforms (meso's option table for `relief`, same names, ranges and defaults):
//   int  u_linear_steps   1..1024, 16  steps of the linear search along the view ray
//   int  u_binary_steps   0..32, 6     steps of the binary search after the linear one
//   bool u_shadows        default true self-shadows (meso_relief.glsl)
//   int  u_shadow_steps   1..1024, 16  steps of the shadow search
//   bool u_silhouettes    default true silhouettes from per-vertex quadrics
// Textures: u_height (unit 1) and the colour map (unit 0), as in meso_common.glsl.

uniform int u_linear_steps;
uniform int u_binary_steps;
uniform int u_shadow_steps;

bool relief_search(relief_ray r, out float t) {
    // t = 0: a texel at full height is hit where the ray enters (h = 1: exactly the mesh).
    float h = meso_height_at(r.start);
    bool found = h >= 1.0 || r.flat_hit;
    float t_lo = 0.0, t_hi = 0.0, f_lo = -1.0, f_hi = h - 1.0;
    float t_prev = 0.0, f_prev = h - 1.0;
    float inv_n = 1.0 / float(u_linear_steps);
    for (int k = 1; k <= u_linear_steps && !found; ++k) {
        float tk = r.t_end * (float(k) * inv_n);
        float d = tk * (r.a - r.b * tk);
        float fk = d + meso_height_at(r.start + r.step * tk) - 1.0; // >= 0: at or below
        if (fk >= 0.0 || (k == u_linear_steps && r.floor_hit)) {   // d = 1 on the floor
            t_lo = t_prev;
            f_lo = f_prev;
            t_hi = tk;
            f_hi = max(fk, 0.0);
            found = true;
        }
        t_prev = tk;
        f_prev = fk;
    }
    for (int k = 0; k < u_binary_steps; ++k) {
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

bool relief_shadow(relief_light_ray s) {
    float inv = 1.0 / float(u_shadow_steps);
    // Sample k = steps is on the mesh (d = 0): nothing is above it.
    for (int k = 1; k < u_shadow_steps; ++k) {
        float frac = float(k) * inv;
        float h = meso_height_at(s.start + s.step * frac);
        if ((s.d + s.bulge * frac) * (1.0 - frac) + h - 1.0 > RELIEF_SHADOW_BIAS) return true;
    }
    return false;
}

void main() { relief_main(); }
