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
    return relief_linear_search(r, u_linear_steps, u_binary_steps, t);
}

bool relief_shadow(relief_light_ray s) { return relief_linear_shadow(s, u_shadow_steps); }

vec3 relief_hit_normal(meso_frame f, relief_ray r, float t, vec2 hit, float hd) {
    return relief_gradient_normal(f, hit);
}

void main() { relief_main(); }
