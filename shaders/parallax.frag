// meso:requires meso_common.glsl
// parallax.frag: parallax mapping (Kaneko et al. 2001, "Detailed shape representation with
// parallax mapping", §3): the texture coordinates are shifted along the view direction by
// u' = u + tan(theta_u) depth(u, v), v' = v + tan(theta_v) depth(u, v) (§3.1), the depth read
// at the unshifted coordinates (§3.2). With u_offset_limiting (Welsh 2004) the division by
// cos(theta) is dropped so the shift never exceeds the depth. No self-shadow, no silhouette,
// no depth correction: that is the method.
//
// Uniforms (meso's option table for `parallax`):
//   bool u_offset_limiting   default false
// Textures: u_height (unit 1) and the colour map (unit 0), as in meso_common.glsl.

uniform bool u_offset_limiting;

void main() {
    meso_frame f = meso_frame_get();
    vec2 p = meso_height_texel(v_uv);
    float cu = dot(f.view, f.bn), cv = dot(f.view, f.nt), cn = dot(f.view, f.tb);
    // §3.1: tan(theta_u) = (view along u) / (view along -N), in uv per world depth; with
    // offset limiting, per unit length of the view ray instead.
    float along = u_offset_limiting ? length(f.view) : -cn;
    bool on = u_depth > 0.0 && cn < 0.0 && f.ok;
    float scale = on ? u_depth / along : 0.0;
    // §3.2: the depth read at the unshifted coordinates stands for the shifted point's.
    float d = 1.0 - meso_height_at(p);
    vec2 offset = vec2(cu, cv) * (scale * d);
    vec2 g = meso_height_gradient(p + vec2(offset.x * float(u_height_size.x),
                                           -offset.y * float(u_height_size.y)));
    vec3 n = meso_relief_normal(f, u_depth, g);
    float visibility[MESO_MAX_LIGHTS];
    meso_all_visible(visibility);
    meso_write(meso_shade(f.position, n, v_uv + offset, visibility), dot(f.view, u_forward));
}
